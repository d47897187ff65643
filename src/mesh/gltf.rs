//! glTF 2.0 characters in (mesh stage): meshes, their node hierarchy, skins and animation
//! clips, read with the `gltf` crate and checked before use, so that a malformed file is one
//! clear error naming the file and the JSON location (`Fox.gltf: /accessors/3: count 1000000
//! exceeds its buffer view`), never a panic or a silently wrong mesh.
//!
//! What is read:
//! - **Meshes**: every triangle primitive (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`) of every
//!   node with a mesh in the default scene (the first scene when none is marked, every root
//!   node when there are no scenes), or of the subtree of the node named by `node`. Points and
//!   lines are skipped with a warning; a model without a triangle is refused.
//! - **Positions** as the file stores them: a skinned primitive's vertices follow its joints
//!   (the node's own transform is ignored, glTF 2.0 §3.7.3.3), any other primitive its node's
//!   global transform. Nothing is re-centred or turned; `mesh.scale` multiplies the result.
//! - **Normals**: the file's `NORMAL` where given (normalised), otherwise computed from the faces
//!   and welded by position as for every pelage mesh ([`super::frame`]).
//! - **TEXCOORD_0** (floats, or normalised bytes and shorts). Without it a box projection is
//!   generated with a warning, as for OBJ files.
//! - **Skins**: `JOINTS_0`/`WEIGHTS_0` (four influences), inverse bind matrices (identity when
//!   absent); the weights normalised ([`super::skin`]).
//! - **Animations**: translation, rotation and scale channels with LINEAR, STEP and
//!   CUBICSPLINE samplers ([`super::animation`]). A clip that animates morph-target weights is
//!   refused when chosen; morph targets themselves are ignored with a warning when the mesh's
//!   default weights are all zero, refused otherwise.
//! - **Base colour**: the first material's `baseColorTexture` (PNG or JPEG) and
//!   `baseColorFactor`, for `[fur] colour_from_mesh`.
//!
//! Buffers and images come from the GLB's binary chunk, data URIs (base64), or files in the
//! glTF file's folder or below it; a URI that leaves that folder (`..`, an absolute path,
//! `file://` or any other scheme, a link pointing outside) is refused. Every size is checked
//! before memory is spent: the file and every external buffer against
//! [`MAX_GLTF_BYTES`], every accessor against its buffer view, the vertex count against
//! [`MAX_GLTF_VERTICES`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{Quat, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::animation::{Channel, Clip, Interpolation, Property};
use super::skin::{Affine, Influences, LocalTransform, PaletteEntry, Rig, Skeleton};
use super::{Mesh, TangentFrame};

/// Largest glTF, GLB or external buffer file accepted, bytes (checked before reading).
pub const MAX_GLTF_BYTES: u64 = 1 << 30;
/// Most vertices a model may have, all primitives together.
pub const MAX_GLTF_VERTICES: u64 = 16_000_000;
/// Most triangles a model may have.
pub const MAX_GLTF_TRIANGLES: u64 = 32_000_000;
/// Largest side of the base-colour image.
pub const MAX_IMAGE_SIDE: u32 = 8192;

/// A glTF file that cannot be used: the file, the JSON location when there is one, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: {}{message}", file.display(), pointer.as_ref().map(|p| format!("{p}: ")).unwrap_or_default())]
pub struct GltfError {
    /// The file.
    pub file: PathBuf,
    /// JSON pointer of the offending object (`/accessors/3`), when there is one.
    pub pointer: Option<String>,
    /// What is wrong.
    pub message: String,
}

/// The base-colour texture and factor of the model's material.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseColour {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// RGBA8 texels, row 0 at `v = 0` (glTF's top-left origin, as pelage's maps).
    pub texels: Vec<[u8; 4]>,
    /// `baseColorFactor`.
    pub factor: [f32; 4],
}

/// A loaded model: the mesh at its bind (file) positions, the rig that poses it, its clips.
#[derive(Clone, Debug, PartialEq)]
pub struct Character {
    /// Vertices as stored (skinned primitives) or in their node's space (rigid ones), with
    /// frames; posed by [`Rig::palette`] and [`super::skin::pose`].
    pub bind: Mesh,
    /// Hierarchy, palette and influences.
    pub rig: Rig,
    /// Animation clips, in the file's order.
    pub clips: Vec<Clip>,
    /// Which clips animate morph-target weights (refused when chosen).
    pub morph_clips: Vec<bool>,
    /// The base colour, when the material has a texture.
    pub base_colour: Option<BaseColour>,
    /// Non-fatal problems, in the order they arose.
    pub warnings: Vec<String>,
}

/// Which clip a scene asks for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ClipChoice {
    /// By name.
    Name(String),
    /// By index, from 0.
    Index(usize),
}

impl Character {
    /// The index of the clip `choice` names, or an error naming it and listing the clips.
    pub fn clip_index(&self, choice: &ClipChoice, file: &Path) -> Result<usize, GltfError> {
        let names = || {
            let list: Vec<String> = self
                .clips
                .iter()
                .enumerate()
                .map(|(i, c)| format!("{i}: \"{}\"", c.name))
                .collect();
            if list.is_empty() {
                "the file has no animations".to_string()
            } else {
                format!("clips: {}", list.join(", "))
            }
        };
        let index = match choice {
            ClipChoice::Index(i) if *i < self.clips.len() => *i,
            ClipChoice::Index(i) => {
                return Err(error(
                    file,
                    None,
                    format!("no animation clip {i} ({})", names()),
                ));
            }
            ClipChoice::Name(name) => match self.clips.iter().position(|c| &c.name == name) {
                Some(i) => i,
                None => {
                    return Err(error(
                        file,
                        None,
                        format!("no animation clip named \"{name}\" ({})", names()),
                    ));
                }
            },
        };
        if self.morph_clips[index] {
            return Err(error(
                file,
                Some(format!("/animations/{index}")),
                "the clip animates morph-target weights; morph targets are not supported".into(),
            ));
        }
        Ok(index)
    }
}

/// What [`scan`] finds without reading the buffers: for the memory estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GltfSummary {
    /// Triangles of every triangle primitive (upper bound: every mesh of the file).
    pub triangles: u64,
    /// Vertices of those primitives.
    pub vertices: u64,
    /// Animation keys of every sampler (inputs and outputs).
    pub animation_keys: u64,
    /// Bytes of the file.
    pub file_bytes: u64,
}

fn error(file: &Path, pointer: Option<String>, message: String) -> GltfError {
    GltfError {
        file: file.to_path_buf(),
        pointer,
        message,
    }
}

/// Size of a GLB file's header: magic, version, total length (glTF 2.0, section 4.4.2).
const GLB_HEADER_BYTES: u32 = 12;

/// The GLB header's total length, checked before the `gltf` crate subtracts the header's size
/// from it (an arithmetic overflow there on a length under 12, found by the fuzz target).
fn check_glb_header(bytes: &[u8], file: &Path) -> Result<(), GltfError> {
    let Some(length) = bytes
        .strip_prefix(b"glTF")
        .and_then(|rest| rest.get(4..8))
        .and_then(|field| <[u8; 4]>::try_from(field).ok())
        .map(u32::from_le_bytes)
    else {
        return Ok(());
    };
    if length < GLB_HEADER_BYTES {
        return Err(error(
            file,
            None,
            format!(
                "not a readable GLB file: its header gives a total length of {length} bytes, \
                 less than the {GLB_HEADER_BYTES}-byte header itself"
            ),
        ));
    }
    Ok(())
}

/// `accessors[3].count` as a JSON pointer, `/accessors/3/count`.
fn json_pointer(path: &str) -> String {
    let mut out = String::from("/");
    for c in path.chars() {
        match c {
            '[' | '.' => out.push('/'),
            ']' => {}
            c => out.push(c),
        }
    }
    out
}

fn parse(bytes: &[u8], file: &Path) -> Result<gltf::Gltf, GltfError> {
    check_glb_header(bytes, file)?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| parse_error(e, file))?;
    let root = document.into_json();
    // gltf-json's own validation reads a primitive's POSITION accessor before checking that it
    // exists (a panic on an index past the accessors, found by the fuzz target): checked first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&position)
                && index.value() >= root.accessors.len()
            {
                return Err(error(
                    file,
                    Some(format!("/meshes/{m}/primitives/{p}/attributes/POSITION")),
                    format!(
                        "accessor {} does not exist (the file has {})",
                        index.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    // Nor does it check an animation channel's target (the `gltf` crate unwraps both).
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let pointer = Some(format!("/animations/{a}/channels/{c}/target"));
            if channel.target.node.value() >= root.nodes.len() {
                return Err(error(
                    file,
                    pointer,
                    format!("node {} does not exist", channel.target.node.value()),
                ));
            }
            if !matches!(
                channel.target.path,
                gltf::json::validation::Checked::Valid(_)
            ) {
                return Err(error(
                    file,
                    pointer,
                    "path is not one of translation, rotation, scale, weights".into(),
                ));
            }
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| parse_error(e, file))?;
    Ok(gltf::Gltf { document, blob })
}

fn parse_error(e: gltf::Error, file: &Path) -> GltfError {
    match e {
        gltf::Error::Validation(list) => {
            let (path, what) = list
                .first()
                .map(|(p, e)| (json_pointer(p.as_str()), e.to_string()))
                .unwrap_or_default();
            error(file, Some(path), format!("invalid glTF: {what}"))
        }
        gltf::Error::Binary(b) => error(file, None, format!("not a readable GLB file: {b}")),
        gltf::Error::Deserialize(d) => error(file, None, format!("invalid glTF JSON: {d}")),
        other => error(file, None, format!("cannot read the glTF: {other}")),
    }
}

/// Counts triangles, vertices and animation keys from the JSON alone (no buffer is read).
pub fn scan(path: &Path) -> Result<GltfSummary, GltfError> {
    let bytes = read_file(path, path)?;
    scan_bytes(&bytes, path)
}

/// [`scan`] on bytes already read.
pub fn scan_bytes(bytes: &[u8], file: &Path) -> Result<GltfSummary, GltfError> {
    let gltf = parse(bytes, file)?;
    let mut s = GltfSummary {
        file_bytes: bytes.len() as u64,
        ..GltfSummary::default()
    };
    for mesh in gltf.meshes() {
        for p in mesh.primitives() {
            let vertices = p.get(&gltf::Semantic::Positions).map_or(0, |a| a.count()) as u64;
            let corners = p.indices().map_or(vertices, |a| a.count() as u64);
            s.vertices = s.vertices.saturating_add(vertices);
            s.triangles = s.triangles.saturating_add(match p.mode() {
                Mode::Triangles => corners / 3,
                Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
                _ => 0,
            });
        }
    }
    for a in gltf.animations() {
        for sampler in a.samplers() {
            let keys = sampler.input().count() as u64 + sampler.output().count() as u64;
            s.animation_keys = s.animation_keys.saturating_add(keys);
        }
    }
    Ok(s)
}

fn read_file(path: &Path, file: &Path) -> Result<Vec<u8>, GltfError> {
    crate::input::read(path, MAX_GLTF_BYTES, "glTF file").map_err(|e| error(file, None, e.message))
}

/// Loads the model at `path` (see the module docs); `node` picks one node's subtree by name.
pub fn load(path: &Path, node: Option<&str>, scale: f32) -> Result<Character, GltfError> {
    let bytes = read_file(path, path)?;
    let folder = path.parent().unwrap_or(Path::new("."));
    load_bytes(&bytes, path, Some(folder), node, scale)
}

/// [`load`] from bytes; `folder` is where external buffers and images may be read (`None`:
/// only the GLB chunk and data URIs, as for the fuzz target).
pub fn load_bytes(
    bytes: &[u8],
    file: &Path,
    folder: Option<&Path>,
    node: Option<&str>,
    scale: f32,
) -> Result<Character, GltfError> {
    let gltf = parse(bytes, file)?;
    let buffers = load_buffers(&gltf, file, folder)?;
    let mut loader = Loader {
        gltf: &gltf,
        file,
        folder,
        buffers,
        warnings: Vec::new(),
    };
    loader.character(node, scale)
}

struct Loader<'a> {
    gltf: &'a gltf::Gltf,
    file: &'a Path,
    folder: Option<&'a Path>,
    buffers: Vec<Vec<u8>>,
    warnings: Vec<String>,
}

fn load_buffers(
    gltf: &gltf::Gltf,
    file: &Path,
    folder: Option<&Path>,
) -> Result<Vec<Vec<u8>>, GltfError> {
    let mut out = Vec::new();
    for buffer in gltf.buffers() {
        let pointer = Some(format!("/buffers/{}", buffer.index()));
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                error(
                    file,
                    pointer.clone(),
                    "refers to a GLB binary chunk the file does not have".into(),
                )
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, file, folder, &pointer)?,
        };
        if (data.len() as u64) < buffer.length() as u64 {
            return Err(error(
                file,
                pointer,
                format!(
                    "byteLength {} exceeds the {} bytes of its data",
                    buffer.length(),
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes a URI names: a base64 data URI, or a file in `folder` or below it.
fn read_uri(
    uri: &str,
    file: &Path,
    folder: Option<&Path>,
    pointer: &Option<String>,
) -> Result<Vec<u8>, GltfError> {
    let fail = |message: String| error(file, pointer.clone(), message);
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or_else(|| fail("a data URI must be base64 (\";base64,\")".into()))?;
        if data.len() as u64 / 4 * 3 > MAX_GLTF_BYTES {
            return Err(fail(format!(
                "data URI exceeds the limit of {MAX_GLTF_BYTES} bytes"
            )));
        }
        return decode_base64(data).ok_or_else(|| fail("data URI is not valid base64".into()));
    }
    let decoded = percent_decode(uri).ok_or_else(|| fail(format!("URI \"{uri}\" is malformed")))?;
    let relative = Path::new(&decoded);
    let leaves = uri.contains(':')
        || decoded.starts_with('/')
        || decoded.starts_with('\\')
        || relative.is_absolute()
        || relative.components().any(|c| {
            !matches!(
                c,
                std::path::Component::Normal(_) | std::path::Component::CurDir
            )
        });
    if leaves {
        return Err(fail(format!(
            "URI \"{uri}\" leaves the model's folder (only relative paths below it are read)"
        )));
    }
    let folder =
        folder.ok_or_else(|| fail(format!("external URI \"{uri}\" cannot be read here")))?;
    let path = folder.join(relative);
    // A link inside the folder must not lead out of it.
    let (Ok(real), Ok(root)) = (path.canonicalize(), folder.canonicalize()) else {
        return Err(fail(format!("cannot read \"{}\"", path.display())));
    };
    if !real.starts_with(&root) {
        return Err(fail(format!(
            "URI \"{uri}\" leads out of the model's folder (through a link)"
        )));
    }
    crate::input::read(&path, MAX_GLTF_BYTES, "glTF buffer").map_err(|e| fail(e.message))
}

fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Standard base64 with optional padding; `None` on any other character.
pub fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let s = s.trim_end_matches('=').as_bytes();
    if s.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 2);
    for chunk in s.chunks(4) {
        let mut acc = 0u32;
        for &c in chunk {
            acc = (acc << 6) | value(c)?;
        }
        acc <<= 6 * (4 - chunk.len() as u32);
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// Whether `node` or one of its ancestors satisfies `is` (the hierarchy has no cycles: checked
/// when the skeleton is built).
fn has_ancestor(skeleton: &Skeleton, node: usize, is: impl Fn(usize) -> bool) -> bool {
    let mut k = node;
    loop {
        if is(k) {
            return true;
        }
        match skeleton.parents[k] {
            Some(p) => k = p,
            None => return false,
        }
    }
}

/// One component read as f32 (normalised integers as the specification maps them).
fn component(data: &[u8], ty: DataType, normalized: bool) -> f32 {
    match ty {
        DataType::F32 => f32::from_le_bytes([data[0], data[1], data[2], data[3]]),
        DataType::U8 if normalized => f32::from(data[0]) / 255.0,
        DataType::U8 => f32::from(data[0]),
        DataType::I8 if normalized => (f32::from(data[0] as i8) / 127.0).max(-1.0),
        DataType::I8 => f32::from(data[0] as i8),
        DataType::U16 if normalized => f32::from(u16::from_le_bytes([data[0], data[1]])) / 65535.0,
        DataType::U16 => f32::from(u16::from_le_bytes([data[0], data[1]])),
        DataType::I16 if normalized => {
            (f32::from(i16::from_le_bytes([data[0], data[1]])) / 32767.0).max(-1.0)
        }
        DataType::I16 => f32::from(i16::from_le_bytes([data[0], data[1]])),
        DataType::U32 => u32::from_le_bytes([data[0], data[1], data[2], data[3]]) as f32,
    }
}

fn integer(data: &[u8], ty: DataType) -> Option<u32> {
    match ty {
        DataType::U8 => Some(u32::from(data[0])),
        DataType::U16 => Some(u32::from(u16::from_le_bytes([data[0], data[1]]))),
        DataType::U32 => Some(u32::from_le_bytes([data[0], data[1], data[2], data[3]])),
        _ => None,
    }
}

fn width(d: Dimensions) -> usize {
    match d {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

impl Loader<'_> {
    fn fail(&self, pointer: impl Into<Option<String>>, message: String) -> GltfError {
        error(self.file, pointer.into(), message)
    }

    /// The elements of an accessor: `count` slices of `width × component size` bytes, each
    /// checked to lie inside its buffer view and buffer.
    fn elements(
        &self,
        accessor: &gltf::Accessor,
        dims: &[Dimensions],
        types: &[DataType],
    ) -> Result<Vec<&[u8]>, GltfError> {
        let pointer = format!("/accessors/{}", accessor.index());
        if !dims.contains(&accessor.dimensions()) {
            return Err(self.fail(
                pointer,
                format!(
                    "type {:?} is not one of {dims:?} here",
                    accessor.dimensions()
                ),
            ));
        }
        if !types.contains(&accessor.data_type()) {
            return Err(self.fail(
                pointer,
                format!(
                    "componentType {:?} is not one of {types:?} here",
                    accessor.data_type()
                ),
            ));
        }
        if accessor.sparse().is_some() {
            return Err(self.fail(pointer, "sparse accessors are not supported".into()));
        }
        let count = accessor.count() as u64;
        if count > MAX_GLTF_VERTICES.max(MAX_GLTF_TRIANGLES * 3) {
            return Err(self.fail(pointer, format!("count {count} exceeds the limits")));
        }
        let Some(view) = accessor.view() else {
            return Err(self.fail(
                pointer,
                "has no buffer view (all zeros is not supported)".into(),
            ));
        };
        let element = (width(accessor.dimensions()) * accessor.data_type().size()) as u64;
        let stride = view.stride().map_or(element, |s| s as u64);
        if stride < element {
            return Err(self.fail(
                format!("/bufferViews/{}", view.index()),
                format!("byteStride {stride} is less than the element size {element}"),
            ));
        }
        let buffer = &self.buffers[view.buffer().index()];
        let view_end = (view.offset() as u64).checked_add(view.length() as u64);
        if view_end.is_none_or(|end| end > buffer.len() as u64) {
            return Err(self.fail(
                format!("/bufferViews/{}", view.index()),
                format!(
                    "byteOffset {} + byteLength {} exceeds its buffer's {} bytes",
                    view.offset(),
                    view.length(),
                    buffer.len()
                ),
            ));
        }
        let needed = if count == 0 {
            Some(0)
        } else {
            stride
                .checked_mul(count - 1)
                .and_then(|n| n.checked_add(element))
                .and_then(|n| n.checked_add(accessor.offset() as u64))
        };
        if needed.is_none_or(|n| n > view.length() as u64) {
            return Err(self.fail(pointer, format!("count {count} exceeds its buffer view")));
        }
        let start = view.offset() + accessor.offset();
        let data = &buffer[start..start + view.length() - accessor.offset()];
        Ok((0..count as usize)
            .map(|i| &data[i * stride as usize..i * stride as usize + element as usize])
            .collect())
    }

    /// Float vectors of `n` components (any allowed component type).
    fn floats(
        &self,
        accessor: &gltf::Accessor,
        dims: &[Dimensions],
        types: &[DataType],
    ) -> Result<Vec<Vec4>, GltfError> {
        let ty = accessor.data_type();
        let size = ty.size();
        let normalized = accessor.normalized();
        let n = width(accessor.dimensions()).min(4);
        let values: Vec<Vec4> = self
            .elements(accessor, dims, types)?
            .into_iter()
            .map(|e| {
                let mut v = [0.0f32; 4];
                for (k, slot) in v.iter_mut().enumerate().take(n) {
                    *slot = component(&e[k * size..], ty, normalized);
                }
                Vec4::from_array(v)
            })
            .collect();
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.fail(
                format!("/accessors/{}", accessor.index()),
                format!("element {k} is not finite ({:?})", values[k].to_array()),
            ));
        }
        Ok(values)
    }

    fn integers(
        &self,
        accessor: &gltf::Accessor,
        dims: &[Dimensions],
    ) -> Result<Vec<[u32; 4]>, GltfError> {
        let ty = accessor.data_type();
        let size = ty.size();
        let n = width(accessor.dimensions()).min(4);
        Ok(self
            .elements(
                accessor,
                dims,
                &[DataType::U8, DataType::U16, DataType::U32],
            )?
            .into_iter()
            .map(|e| {
                let mut v = [0u32; 4];
                for (k, slot) in v.iter_mut().enumerate().take(n) {
                    *slot = integer(&e[k * size..], ty).unwrap_or(0);
                }
                v
            })
            .collect())
    }

    fn skeleton(&self) -> Result<(Skeleton, Vec<usize>), GltfError> {
        let count = self.gltf.nodes().count();
        let mut parents: Vec<Option<usize>> = vec![None; count];
        for node in self.gltf.nodes() {
            for child in node.children() {
                let c = child.index();
                if let Some(p) = parents[c] {
                    return Err(self.fail(
                        format!("/nodes/{}/children", node.index()),
                        format!("node {c} is already a child of node {p} (a node has one parent)"),
                    ));
                }
                parents[c] = Some(node.index());
            }
        }
        // A cycle: following parents from some node never reaches a root.
        for start in 0..count {
            let mut node = start;
            for _ in 0..=count {
                match parents[node] {
                    Some(p) => node = p,
                    None => break,
                }
            }
            if parents[node].is_some() {
                return Err(self.fail(
                    format!("/nodes/{start}"),
                    "the node hierarchy has a cycle".into(),
                ));
            }
        }
        let rest = self
            .gltf
            .nodes()
            .map(|node| match node.transform() {
                gltf::scene::Transform::Matrix { matrix } => {
                    let flat: [f32; 16] = bytemuck::cast(matrix);
                    Affine::from_cols_4x4(&flat)
                        .map(LocalTransform::Matrix)
                        .ok_or_else(|| {
                            self.fail(
                                format!("/nodes/{}/matrix", node.index()),
                                "the matrix is not affine (last row 0 0 0 1) or not finite".into(),
                            )
                        })
                }
                gltf::scene::Transform::Decomposed {
                    translation,
                    rotation,
                    scale,
                } => {
                    let all = translation.iter().chain(&rotation).chain(&scale);
                    if all.clone().any(|v| !v.is_finite()) {
                        return Err(self.fail(
                            format!("/nodes/{}", node.index()),
                            "translation, rotation or scale is not finite".into(),
                        ));
                    }
                    Ok(LocalTransform::Trs {
                        translation: Vec3::from_array(translation),
                        rotation: Quat::from_array(rotation),
                        scale: Vec3::from_array(scale),
                    })
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let names = self
            .gltf
            .nodes()
            .map(|n| n.name().unwrap_or_default().to_string())
            .collect();
        // The scene's roots.
        let roots: Vec<usize> = match self
            .gltf
            .default_scene()
            .or_else(|| self.gltf.scenes().next())
        {
            Some(scene) => scene.nodes().map(|n| n.index()).collect(),
            None => (0..count).filter(|&n| parents[n].is_none()).collect(),
        };
        let mut order = Vec::new();
        let mut seen = vec![false; count];
        for &root in &roots {
            let mut stack = vec![root];
            while let Some(n) = stack.pop() {
                if std::mem::replace(&mut seen[n], true) {
                    continue;
                }
                order.push(n);
                let children: Vec<usize> = self.gltf.nodes().nth(n).map_or(Vec::new(), |node| {
                    node.children().map(|c| c.index()).collect()
                });
                stack.extend(children.into_iter().rev());
            }
        }
        // Joints of a skin outside the scene still need their transforms: compose every node
        // that is not in the scene after it, parents first.
        for n in 0..count {
            if !seen[n] && parents[n].is_none() {
                let mut stack = vec![n];
                while let Some(k) = stack.pop() {
                    if std::mem::replace(&mut seen[k], true) {
                        continue;
                    }
                    order.push(k);
                    let children: Vec<usize> =
                        self.gltf.nodes().nth(k).map_or(Vec::new(), |node| {
                            node.children().map(|c| c.index()).collect()
                        });
                    stack.extend(children.into_iter().rev());
                }
            }
        }
        Ok((
            Skeleton {
                parents,
                rest,
                names,
                order,
            },
            roots,
        ))
    }

    fn character(&mut self, node: Option<&str>, scale: f32) -> Result<Character, GltfError> {
        let (skeleton, roots) = self.skeleton()?;
        // The nodes whose meshes are drawn, in the composition order.
        let chosen: Vec<usize> = match node {
            None => skeleton
                .order
                .iter()
                .copied()
                .filter(|&n| has_ancestor(&skeleton, n, |k| roots.contains(&k)))
                .collect(),
            Some(name) => {
                let matches: Vec<usize> = (0..skeleton.names.len())
                    .filter(|&n| skeleton.names[n] == name)
                    .collect();
                let top = match matches.as_slice() {
                    [one] => *one,
                    [] => {
                        return Err(self.fail(None, format!("no node named \"{name}\"")));
                    }
                    many => {
                        return Err(self.fail(
                            None,
                            format!(
                                "{} nodes are named \"{name}\" ({many:?}); the name must be unique",
                                many.len()
                            ),
                        ));
                    }
                };
                skeleton
                    .order
                    .iter()
                    .copied()
                    .filter(|&n| has_ancestor(&skeleton, n, |k| k == top))
                    .collect()
            }
        };

        let mut palette: Vec<PaletteEntry> = Vec::new();
        let mut skin_offsets: BTreeMap<usize, u32> = BTreeMap::new();
        let mut positions: Vec<Vec3> = Vec::new();
        let mut normals: Vec<Option<Vec3>> = Vec::new();
        let mut uvs: Vec<Option<Vec2>> = Vec::new();
        let mut influences: Vec<Influences> = Vec::new();
        let mut indices: Vec<[u32; 3]> = Vec::new();
        let mut material = None;
        for &n in &chosen {
            let Some(gnode) = self.gltf.nodes().nth(n) else {
                continue;
            };
            let Some(mesh) = gnode.mesh() else {
                continue;
            };
            let skin = gnode.skin();
            let entry = match &skin {
                Some(skin) => match skin_offsets.get(&skin.index()) {
                    Some(&offset) => offset,
                    None => {
                        let offset = palette.len() as u32;
                        self.add_skin(skin, &mut palette)?;
                        skin_offsets.insert(skin.index(), offset);
                        offset
                    }
                },
                None => {
                    palette.push(PaletteEntry::Node { node: n });
                    palette.len() as u32 - 1
                }
            };
            let morph_weights = mesh.weights().unwrap_or(&[]);
            for primitive in mesh.primitives() {
                let pointer = format!("/meshes/{}/primitives/{}", mesh.index(), primitive.index());
                if primitive.morph_targets().next().is_some() {
                    if morph_weights.iter().any(|&w| w != 0.0) {
                        return Err(self.fail(
                            pointer,
                            "morph targets with non-zero weights are not supported".into(),
                        ));
                    }
                    self.warnings.push(format!(
                        "{}: {pointer}: morph targets ignored (their weights are zero)",
                        self.file.display()
                    ));
                }
                let mode = primitive.mode();
                if !matches!(
                    mode,
                    Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
                ) {
                    self.warnings.push(format!(
                        "{}: {pointer}: mode {mode:?} has no triangles; skipped",
                        self.file.display()
                    ));
                    continue;
                }
                let Some(pos) = primitive.get(&gltf::Semantic::Positions) else {
                    return Err(self.fail(pointer, "has no POSITION".into()));
                };
                let p = self.floats(&pos, &[Dimensions::Vec3], &[DataType::F32])?;
                let base = positions.len() as u64;
                if base + p.len() as u64 > MAX_GLTF_VERTICES {
                    return Err(self.fail(
                        pointer,
                        format!("the model has more than {MAX_GLTF_VERTICES} vertices"),
                    ));
                }
                let count = p.len();
                positions.extend(p.iter().map(|v| v.truncate()));
                match primitive.get(&gltf::Semantic::Normals) {
                    Some(a) => {
                        let nrm = self.floats(&a, &[Dimensions::Vec3], &[DataType::F32])?;
                        self.same_count(&a, count, &pointer)?;
                        normals.extend(nrm.iter().map(|v| v.truncate().try_normalize()));
                    }
                    None => normals.extend(std::iter::repeat_n(None, count)),
                }
                match primitive.get(&gltf::Semantic::TexCoords(0)) {
                    Some(a) => {
                        let t = self.floats(
                            &a,
                            &[Dimensions::Vec2],
                            &[DataType::F32, DataType::U8, DataType::U16],
                        )?;
                        self.same_count(&a, count, &pointer)?;
                        uvs.extend(t.iter().map(|v| Some(Vec2::new(v.x, v.y))));
                    }
                    None => uvs.extend(std::iter::repeat_n(None, count)),
                }
                if skin.is_some() {
                    let (Some(j), Some(w)) = (
                        primitive.get(&gltf::Semantic::Joints(0)),
                        primitive.get(&gltf::Semantic::Weights(0)),
                    ) else {
                        return Err(self.fail(
                            pointer,
                            "the node has a skin but the primitive has no JOINTS_0 and WEIGHTS_0"
                                .into(),
                        ));
                    };
                    if primitive.get(&gltf::Semantic::Joints(1)).is_some() {
                        return Err(self.fail(
                            pointer,
                            "JOINTS_1: more than four influences a vertex are not supported".into(),
                        ));
                    }
                    let joints = self.integers(&j, &[Dimensions::Vec4])?;
                    let weights = self.floats(
                        &w,
                        &[Dimensions::Vec4],
                        &[DataType::F32, DataType::U8, DataType::U16],
                    )?;
                    self.same_count(&j, count, &pointer)?;
                    self.same_count(&w, count, &pointer)?;
                    let joint_count = match &skin {
                        Some(s) => s.joints().count() as u32,
                        None => 0,
                    };
                    for (k, (jv, wv)) in joints.iter().zip(&weights).enumerate() {
                        if let Some(bad) = jv.iter().find(|&&x| x >= joint_count) {
                            return Err(self.fail(
                                format!("/accessors/{}", j.index()),
                                format!(
                                    "vertex {k}: joint {bad} is past the skin's {joint_count} joints"
                                ),
                            ));
                        }
                        let inf = Influences::normalised(jv.map(|x| x + entry), wv.to_array())
                            .ok_or_else(|| {
                                self.fail(
                                    format!("/accessors/{}", w.index()),
                                    format!(
                                        "vertex {k}: weights {:?} are negative, not finite or all zero",
                                        wv.to_array()
                                    ),
                                )
                            })?;
                        influences.push(inf);
                    }
                } else {
                    influences.extend(std::iter::repeat_n(Influences::rigid(entry), count));
                }
                let corners: Vec<u32> = match primitive.indices() {
                    Some(a) => {
                        let ix = self.integers(&a, &[Dimensions::Scalar])?;
                        if let Some((k, bad)) =
                            ix.iter().enumerate().find(|(_, v)| v[0] as usize >= count)
                        {
                            return Err(self.fail(
                                format!("/accessors/{}", a.index()),
                                format!(
                                    "index {k} is {}, past the primitive's {count} vertices",
                                    bad[0]
                                ),
                            ));
                        }
                        ix.iter().map(|v| v[0]).collect()
                    }
                    None => (0..count as u32).collect(),
                };
                let b = base as u32;
                let before = indices.len();
                match mode {
                    Mode::Triangles => indices.extend(
                        corners
                            .chunks_exact(3)
                            .map(|t| [t[0] + b, t[1] + b, t[2] + b]),
                    ),
                    Mode::TriangleStrip => {
                        for k in 0..corners.len().saturating_sub(2) {
                            let (a, c1, c2) = (corners[k], corners[k + 1], corners[k + 2]);
                            let t = if k % 2 == 0 { [a, c1, c2] } else { [c1, a, c2] };
                            indices.push(t.map(|i| i + b));
                        }
                    }
                    _ => {
                        for k in 1..corners.len().saturating_sub(1) {
                            indices.push([corners[0] + b, corners[k] + b, corners[k + 1] + b]);
                        }
                    }
                }
                if indices.len() as u64 > MAX_GLTF_TRIANGLES {
                    return Err(self.fail(
                        pointer,
                        format!("the model has more than {MAX_GLTF_TRIANGLES} triangles"),
                    ));
                }
                if indices.len() > before && material.is_none() {
                    material = Some(primitive.material());
                }
            }
        }
        if indices.is_empty() {
            return Err(self.fail(
                None,
                match node {
                    Some(name) => format!("node \"{name}\" and its children have no triangles"),
                    None => "the scene has no triangle primitives".into(),
                },
            ));
        }

        let (positions, uvs, indices, influences, normals) = if uvs.iter().all(Option::is_some) {
            let uvs = uvs
                .into_iter()
                .map(|u| u.unwrap_or_default())
                .collect::<Vec<_>>();
            (positions, uvs, indices, influences, normals)
        } else {
            self.warnings.push(format!(
                "{}: no TEXCOORD_0 (or only on some primitives); generated a box projection",
                self.file.display()
            ));
            let (p, uv, idx, origin) =
                super::obj::box_projection_with_origins(&positions, &indices);
            let inf = origin.iter().map(|&o| influences[o as usize]).collect();
            let nrm = origin.iter().map(|&o| normals[o as usize]).collect();
            (p, uv, idx, inf, nrm)
        };
        let mut bind = Mesh::from_parts(&positions, &uvs, indices)
            .map_err(|e| self.fail(None, e.to_string()))?;
        for (v, n) in bind.vertices.iter_mut().zip(&normals) {
            if let Some(n) = n {
                v.normal = *n;
                v.frame = TangentFrame::from_derivatives(*n, v.dpdu, v.dpdv);
            }
        }
        let (clips, morph_clips) = self.clips(&skeleton)?;
        let base_colour = match material {
            Some(m) => self.base_colour(&m)?,
            None => None,
        };
        Ok(Character {
            bind,
            rig: Rig {
                skeleton,
                palette,
                influences,
                scale,
            },
            clips,
            morph_clips,
            base_colour,
            warnings: std::mem::take(&mut self.warnings),
        })
    }

    fn same_count(&self, a: &gltf::Accessor, count: usize, pointer: &str) -> Result<(), GltfError> {
        if a.count() != count {
            return Err(self.fail(
                format!("/accessors/{}", a.index()),
                format!(
                    "count {} differs from POSITION's {count} in {pointer}",
                    a.count()
                ),
            ));
        }
        Ok(())
    }

    fn add_skin(
        &self,
        skin: &gltf::Skin,
        palette: &mut Vec<PaletteEntry>,
    ) -> Result<(), GltfError> {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let pointer = format!("/skins/{}", skin.index());
        if joints.is_empty() {
            return Err(self.fail(pointer, "the skin has no joints".into()));
        }
        let inverse_binds = match skin.inverse_bind_matrices() {
            Some(a) => {
                let elements = self.elements(&a, &[Dimensions::Mat4], &[DataType::F32])?;
                if elements.len() < joints.len() {
                    return Err(self.fail(
                        format!("/accessors/{}", a.index()),
                        format!(
                            "{} inverse bind matrices for {} joints",
                            elements.len(),
                            joints.len()
                        ),
                    ));
                }
                elements
                    .iter()
                    .enumerate()
                    .take(joints.len())
                    .map(|(k, e)| {
                        let mut m = [0.0f32; 16];
                        for (i, v) in m.iter_mut().enumerate() {
                            *v = component(&e[4 * i..], DataType::F32, false);
                        }
                        Affine::from_cols_4x4(&m).ok_or_else(|| {
                            self.fail(
                                format!("/accessors/{}", a.index()),
                                format!("inverse bind matrix {k} is not affine or not finite"),
                            )
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?
            }
            None => vec![Affine::IDENTITY; joints.len()],
        };
        palette.extend(
            joints
                .iter()
                .zip(inverse_binds)
                .map(|(&node, inverse_bind)| PaletteEntry::Joint { node, inverse_bind }),
        );
        Ok(())
    }

    fn clips(&self, skeleton: &Skeleton) -> Result<(Vec<Clip>, Vec<bool>), GltfError> {
        let mut clips = Vec::new();
        let mut morph = Vec::new();
        for animation in self.gltf.animations() {
            let mut channels = Vec::new();
            let mut animates_weights = false;
            for channel in animation.channels() {
                let pointer = format!(
                    "/animations/{}/channels/{}",
                    animation.index(),
                    channel.index()
                );
                let target = channel.target();
                let node = target.node().index();
                let property = match target.property() {
                    gltf::animation::Property::Translation => Property::Translation,
                    gltf::animation::Property::Rotation => Property::Rotation,
                    gltf::animation::Property::Scale => Property::Scale,
                    gltf::animation::Property::MorphTargetWeights => {
                        animates_weights = true;
                        continue;
                    }
                };
                if matches!(skeleton.rest[node], LocalTransform::Matrix(_)) {
                    return Err(self.fail(
                        pointer,
                        format!("animates node {node}, which has a matrix (only TRS nodes may be animated)"),
                    ));
                }
                let sampler = channel.sampler();
                let interpolation = match sampler.interpolation() {
                    gltf::animation::Interpolation::Linear => Interpolation::Linear,
                    gltf::animation::Interpolation::Step => Interpolation::Step,
                    gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let input = sampler.input();
                let times: Vec<f32> = self
                    .floats(&input, &[Dimensions::Scalar], &[DataType::F32])?
                    .iter()
                    .map(|v| v.x)
                    .collect();
                let input_pointer = format!("/accessors/{}", input.index());
                if times.is_empty() {
                    return Err(self.fail(input_pointer, "a sampler needs at least one key".into()));
                }
                if times[0] < 0.0 {
                    return Err(
                        self.fail(input_pointer, format!("key time {} is negative", times[0]))
                    );
                }
                if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
                    return Err(self.fail(
                        input_pointer,
                        format!(
                            "key times must increase: key {} ({}) is not after key {k} ({})",
                            k + 1,
                            times[k + 1],
                            times[k]
                        ),
                    ));
                }
                let output = sampler.output();
                let values = if property == Property::Rotation {
                    self.floats(
                        &output,
                        &[Dimensions::Vec4],
                        &[
                            DataType::F32,
                            DataType::I8,
                            DataType::U8,
                            DataType::I16,
                            DataType::U16,
                        ],
                    )?
                } else {
                    self.floats(&output, &[Dimensions::Vec3], &[DataType::F32])?
                };
                let per_key = if interpolation == Interpolation::CubicSpline {
                    3
                } else {
                    1
                };
                if values.len() != times.len() * per_key {
                    return Err(self.fail(
                        format!("/accessors/{}", output.index()),
                        format!(
                            "{} output values for {} keys ({per_key} a key)",
                            values.len(),
                            times.len()
                        ),
                    ));
                }
                channels.push(Channel {
                    node,
                    property,
                    interpolation,
                    times,
                    values,
                });
            }
            clips.push(Clip {
                name: animation.name().unwrap_or_default().to_string(),
                channels,
            });
            morph.push(animates_weights);
        }
        Ok((clips, morph))
    }

    fn base_colour(&self, material: &gltf::Material) -> Result<Option<BaseColour>, GltfError> {
        let pbr = material.pbr_metallic_roughness();
        let factor = pbr.base_color_factor();
        let Some(info) = pbr.base_color_texture() else {
            return Ok(None);
        };
        if info.tex_coord() != 0 {
            return Ok(None);
        }
        let image_index = info.texture().source().index();
        let pointer = Some(format!("/images/{image_index}"));
        let json = &self.gltf.as_json().images[image_index];
        let bytes: Vec<u8> = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                let Some(view) = self.gltf.views().nth(view.value()) else {
                    return Err(self.fail(pointer, "its buffer view does not exist".into()));
                };
                let buffer = &self.buffers[view.buffer().index()];
                let end = view.offset().checked_add(view.length());
                match end {
                    Some(end) if end <= buffer.len() => buffer[view.offset()..end].to_vec(),
                    _ => {
                        return Err(self.fail(
                            format!("/bufferViews/{}", view.index()),
                            "exceeds its buffer".into(),
                        ));
                    }
                }
            }
            (None, Some(uri)) => read_uri(uri, self.file, self.folder, &pointer)?,
            (None, None) => return Err(self.fail(pointer, "has neither uri nor bufferView".into())),
        };
        let reader = || {
            let mut reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
                .with_guessed_format()
                .map_err(|e| self.fail(pointer.clone(), format!("cannot read the image: {e}")))?;
            reader.limits(crate::input::decoder_limits((0, 0)));
            Ok::<_, GltfError>(reader)
        };
        let format = reader()?.format();
        if !matches!(
            format,
            Some(image::ImageFormat::Png | image::ImageFormat::Jpeg)
        ) {
            return Err(self.fail(pointer.clone(), "the image is neither PNG nor JPEG".into()));
        }
        let (w, h) = reader()?
            .into_dimensions()
            .map_err(|e| self.fail(pointer.clone(), format!("not a readable image: {e}")))?;
        if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
            return Err(self.fail(
                pointer.clone(),
                format!("the image is {w}×{h}; each side must be 1..={MAX_IMAGE_SIDE}"),
            ));
        }
        let mut decoder = reader()?;
        decoder.limits(crate::input::decoder_limits((w, h)));
        let rgba = decoder
            .decode()
            .map_err(|e| self.fail(pointer.clone(), format!("not a readable image: {e}")))?;
        let rgba = crate::input::to_rgba8(rgba);
        Ok(Some(BaseColour {
            width: w,
            height: h,
            texels: rgba.pixels().map(|p| p.0).collect(),
            factor,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_and_refuses_junk() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("a*==").is_none());
        assert!(decode_base64("a").is_none());
    }

    #[test]
    fn a_glb_length_shorter_than_its_header_is_refused_by_name() {
        for length in [0u32, 11] {
            let mut bytes = b"glTF".to_vec();
            bytes.extend_from_slice(&2u32.to_le_bytes());
            bytes.extend_from_slice(&length.to_le_bytes());
            bytes.extend_from_slice(&[0; 20]);
            let message = scan_bytes(&bytes, Path::new("short.glb"))
                .unwrap_err()
                .to_string();
            assert!(message.contains("short.glb"), "{message}");
            assert!(
                message.contains(&format!("total length of {length} bytes")),
                "{message}"
            );
        }
        // A header whose length is its own size is past this check (the crate then finds no
        // JSON chunk).
        let mut bytes = b"glTF".to_vec();
        bytes.extend_from_slice(&2u32.to_le_bytes());
        bytes.extend_from_slice(&12u32.to_le_bytes());
        let message = scan_bytes(&bytes, Path::new("empty.glb"))
            .unwrap_err()
            .to_string();
        assert!(!message.contains("total length"), "{message}");
    }

    #[test]
    fn json_paths_become_pointers() {
        assert_eq!(json_pointer("accessors[3].count"), "/accessors/3/count");
    }
}
