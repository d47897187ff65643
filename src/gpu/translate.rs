//! `fur.wgsl` in every GPU language (feature `gpu`; beside the pipeline: GPU backend): translated
//! by naga, the shader compiler wgpu itself uses, to GLSL 4.50 core, GLSL ES 3.00, HLSL (shader
//! model 5.1), MSL 2.1 and SPIR-V 1.0, with the bindings written down beside each
//! ([`translate_all`]).
//!
//! One resource table ([`resources`]) fixes every slot; each language's binding map is built
//! from it, so `bindings.md` / `bindings.json` and the translated code cannot disagree:
//! - **GLSL**: uniform blocks, storage blocks and textures each numbered from 0 in
//!   (group, binding) order; textures and their sampler are combined (`sampler2D`); the sampler
//!   has no slot of its own (set its state on the texture units of the textures it samples).
//!   GLSL ES 3.00 has no storage buffers, no level query and no explicit binding numbers: its
//!   variant of the shader ([`es300_source`]) holds the spots, matches and joint palette in
//!   uniform arrays of fixed capacity ([`ES300_MAX_SPOTS`], [`ES300_MAX_MATCHES`],
//!   [`ES300_MAX_JOINTS`]), computes the mip level count
//!   from the texture size ([`without_level_query`]), and its resources are bound by name.
//! - **HLSL**: `b` registers for uniform buffers, `t` for textures and read-only storage
//!   buffers (`ByteAddressBuffer`), all in space 0; samplers go through naga's sampler heap
//!   (see `bindings.md`).
//! - **MSL**: `buffer(n)` for uniform and storage buffers, `texture(n)`, `sampler(n)`, and a
//!   sizes buffer for the three runtime-sized arrays; vertex attributes are `[[attribute(L)]]`
//!   with L the WGSL location.
//! - **SPIR-V**: descriptor set = WGSL group, binding = WGSL binding; one module with every
//!   entry point.
//!
//! Clip space in every output is wgpu's (`0 ≤ z ≤ w`); GLSL keeps it as is (see the README,
//! "Porting the shader to an engine"), SPIR-V negates clip y as wgpu's Vulkan backend does
//! (use a viewport of positive height), HLSL and MSL need nothing.

use super::{GpuError, SHADER_SOURCE};
use naga::back::{glsl, hlsl, msl, spv};
use naga::common::wgsl::TypeContext;
use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use naga::{AddressSpace, Module, ResourceBinding, ShaderStage, TypeInner};
use serde::Serialize;
use std::collections::BTreeMap;

/// Spots the GLSL ES 3.00 variant holds (uniform array of 4 × this many `vec4`).
pub const ES300_MAX_SPOTS: usize = 64;
/// Burning matches the GLSL ES 3.00 variant holds.
pub const ES300_MAX_MATCHES: usize = 64;
/// Joints of a skinned model the GLSL ES 3.00 variant holds (its palette is a uniform array of
/// 1 + 4 × this many `vec4`).
pub const ES300_MAX_JOINTS: usize = 64;

/// The entry points of `fur.wgsl`, in the order they are written down.
pub const ENTRY_POINTS: [&str; 7] = [
    "vs_skin",
    "fs_skin",
    "vs_skin_skinned",
    "vs_shell",
    "vs_shell_skinned",
    "vs_fin",
    "fs_fur",
];

/// The folders [`translate_all`] fills, under `shaders/`.
pub const LANGUAGES: [&str; 5] = ["glsl-450", "glsl-es-300", "hlsl", "msl", "spirv"];

/// What kind of resource a binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ResourceKind {
    /// A uniform buffer (a struct).
    Uniform,
    /// A read-only storage buffer (an array of `vec4<f32>`).
    Storage,
    /// A sampled 2D texture of floats.
    Texture,
    /// A filtering sampler.
    Sampler,
}

/// One resource of the shader, with its slot in every language.
#[derive(Clone, Debug, Serialize)]
pub struct Resource {
    /// WGSL `@group`.
    pub group: u32,
    /// WGSL `@binding`.
    pub binding: u32,
    /// The WGSL variable.
    pub name: String,
    /// What it holds.
    pub kind: ResourceKind,
    /// Its WGSL type.
    pub wgsl_type: String,
    /// GLSL 4.50 `layout(binding = n)`: the uniform block binding, storage block binding or
    /// texture unit (`None` for the sampler, which GLSL combines with the textures).
    pub glsl_binding: Option<u32>,
    /// HLSL register, space 0 (`b0`, `t3`…; `None` for the sampler, which is in the heap).
    pub hlsl_register: Option<String>,
    /// MSL attribute (`buffer(0)`, `texture(2)`, `sampler(0)`).
    pub msl_slot: String,
}

/// A struct's layout as the uniform buffer holds it.
#[derive(Clone, Debug, Serialize)]
pub struct StructLayout {
    /// The WGSL struct name.
    pub name: String,
    /// Size in bytes (the buffer's size).
    pub size: u32,
    /// Members in order.
    pub members: Vec<MemberLayout>,
}

/// One member of a [`StructLayout`].
#[derive(Clone, Debug, Serialize)]
pub struct MemberLayout {
    /// The WGSL member name.
    pub name: String,
    /// WGSL type.
    pub wgsl_type: String,
    /// Offset in bytes from the start of the struct.
    pub offset: u32,
    /// Size in bytes.
    pub size: u32,
}

/// An entry point: its stage, the resources it uses, its vertex inputs or outputs.
#[derive(Clone, Debug, Serialize)]
pub struct EntryPoint {
    /// The WGSL name.
    pub name: String,
    /// `vertex` or `fragment`.
    pub stage: String,
    /// The resources it reads (WGSL names).
    pub resources: Vec<String>,
    /// Vertex inputs (vertex stages) or colour outputs (fragment stages): location, name, type.
    pub locations: Vec<Location>,
}

/// One `@location` of an entry point's inputs (vertex) or outputs (fragment).
#[derive(Clone, Debug, Serialize)]
pub struct Location {
    /// `@location(n)`.
    pub location: u32,
    /// The member name (`out` for a fragment output).
    pub name: String,
    /// WGSL type.
    pub wgsl_type: String,
}

/// The bindings of one language's folder: what `bindings.json` holds and `bindings.md` shows.
#[derive(Clone, Debug, Serialize)]
pub struct Bindings {
    /// The folder (one of [`LANGUAGES`]).
    pub language: String,
    /// The files of the folder's code, and for each the entry points it holds.
    pub files: BTreeMap<String, Vec<String>>,
    /// Every resource, in (group, binding) order.
    pub resources: Vec<Resource>,
    /// The uniform structs.
    pub structs: Vec<StructLayout>,
    /// The entry points.
    pub entry_points: Vec<EntryPoint>,
    /// GLSL ES 3.00 only: per file, the GLSL name of each resource (bound by name there) and of
    /// each vertex input.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub glsl_names: BTreeMap<String, BTreeMap<String, String>>,
    /// What else the language needs (clip space, samplers, sizes buffer).
    pub notes: Vec<String>,
}

/// A translated file: its path under `shaders/` and its bytes.
pub struct ShaderFile {
    /// Path relative to the export's `shaders/` folder (`hlsl/fur.hlsl`).
    pub path: String,
    /// The bytes.
    pub bytes: Vec<u8>,
}

fn fail(stage: &str, e: impl std::fmt::Display) -> GpuError {
    GpuError::Validation(format!("translating fur.wgsl ({stage}): {e}"))
}

/// Parses and validates WGSL with naga (every check on, the capabilities wgpu asks for).
pub fn parse(source: &str) -> Result<(Module, ModuleInfo), GpuError> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| fail("parse", e.emit_to_string(source)))?;
    let info = Validator::new(ValidationFlags::all(), Capabilities::empty())
        .validate(&module)
        .map_err(|e| fail("validate", e.emit_to_string(source)))?;
    Ok((module, info))
}

/// The mip level count of a full chain (down to 1×1, each level half the one above, rounded
/// down): what `textureNumLevels` answers for pelage's textures, without the query ES 3.00 lacks.
const ES300_LEVELS: &str = "
// GLSL ES 3.00 has no texture level query: the count of a full mip chain (pelage uploads
// every level down to 1x1), from the size of level 0.
fn es300_levels(t: texture_2d<f32>) -> u32 {
    let size = textureDimensions(t, 0u);
    var side = max(size.x, size.y);
    var levels = 1u;
    while side > 1u {
        side = side >> 1u;
        levels = levels + 1u;
    }
    return levels;
}
";

/// `fur.wgsl` with the spots, matches and joint palette in uniform arrays of fixed capacity instead of storage
/// buffers, and the mip level count computed from the texture size instead of queried (GLSL ES
/// 3.00 and WebGL 2 have neither). Same bindings, same code otherwise.
pub fn es300_source() -> Result<String, GpuError> {
    let swaps = [
        (
            "var<storage, read> spots: array<vec4<f32>>;",
            format!(
                "var<uniform> spots: array<vec4<f32>, {}>;",
                4 * ES300_MAX_SPOTS
            ),
        ),
        (
            "var<storage, read> matches: array<vec4<f32>>;",
            format!("var<uniform> matches: array<vec4<f32>, {ES300_MAX_MATCHES}>;"),
        ),
        (
            "var<storage, read> palette: array<vec4<f32>>;",
            format!(
                "var<uniform> palette: array<vec4<f32>, {}>;",
                1 + 4 * ES300_MAX_JOINTS
            ),
        ),
    ];
    let mut source = SHADER_SOURCE.to_string();
    for (from, to) in swaps {
        if source.matches(from).count() != 1 {
            return Err(fail(
                "GLSL ES 3.00 variant",
                format!("`{from}` not found once"),
            ));
        }
        source = source.replace(from, &to);
    }
    without_level_query(&source)
}

/// `source` with every `textureNumLevels(t)` replaced by the level count of a full mip chain
/// computed from the size of level 0 (`es300_levels`): GLSL ES (any version) has no level
/// query, so the ES 3.00 output and wgpu's GL backend draw this. The same count for pelage's
/// textures, which are uploaded with every level down to 1×1.
pub fn without_level_query(source: &str) -> Result<String, GpuError> {
    if !source.contains("textureNumLevels(") {
        return Err(fail("GLSL ES variant", "no textureNumLevels to replace"));
    }
    let mut source = source.replace("textureNumLevels(", "es300_levels(");
    source.push_str(ES300_LEVELS);
    Ok(source)
}

/// `source` with the per-lane mip level of `sample_nearest_level`'s `textureLoad` made uniform
/// across the lanes: each level of the chain is loaded in turn by the lanes whose level it is.
/// wgpu's GL backend has naga guard every `texelFetch` with `textureSize(t, level)`, and
/// llvmpipe answers that query, for a level that differs between the lanes of one SIMD group,
/// with one lane's level (the bug `sample_nearest_level` already works round for its own size):
/// the guard then fails for the other lanes and their load reads 0, leaving shadow-free specks
/// along the lines where the level changes. The texel loaded is the same.
pub fn with_uniform_level_loads(source: &str) -> Result<String, GpuError> {
    let from = "    return textureLoad(t, vec2<i32>(x, y), i32(level));\n";
    let to = "    var texel = vec4<f32>(0.0);
    for (var l = 0u; l <= u32(max_level); l++) {
        if (l == level) {
            texel = textureLoad(t, vec2<i32>(x, y), i32(l));
        }
    }
    return texel;
";
    if source.matches(from).count() != 1 {
        return Err(fail(
            "GL variant",
            format!("`{}` not found once", from.trim()),
        ));
    }
    Ok(source.replace(from, to))
}

fn type_name(module: &Module, ty: naga::Handle<naga::Type>) -> String {
    module.to_ctx().type_to_string(ty)
}

/// Every resource of `module` in (group, binding) order, with its slot in each language.
pub fn resources(module: &Module) -> Vec<Resource> {
    let mut globals: Vec<(ResourceBinding, &naga::GlobalVariable)> = module
        .global_variables
        .iter()
        .filter_map(|(_, g)| g.binding.map(|b| (b, g)))
        .collect();
    globals.sort_by_key(|(b, _)| (b.group, b.binding));
    let (mut gl_uniform, mut gl_storage, mut gl_texture) = (0, 0, 0);
    let (mut hlsl_b, mut hlsl_t) = (0, 0);
    let (mut msl_buffer, mut msl_texture, mut msl_sampler) = (0, 0, 0);
    let mut out = Vec::new();
    for (b, g) in globals {
        let kind = match (g.space, &module.types[g.ty].inner) {
            (AddressSpace::Uniform, _) => ResourceKind::Uniform,
            (AddressSpace::Storage { .. }, _) => ResourceKind::Storage,
            (_, TypeInner::Sampler { .. }) => ResourceKind::Sampler,
            _ => ResourceKind::Texture,
        };
        let next = |n: &mut u32| {
            *n += 1;
            *n - 1
        };
        let (glsl_binding, hlsl_register, msl_slot) = match kind {
            ResourceKind::Uniform => (
                Some(next(&mut gl_uniform)),
                Some(format!("b{}", next(&mut hlsl_b))),
                format!("buffer({})", next(&mut msl_buffer)),
            ),
            ResourceKind::Storage => (
                Some(next(&mut gl_storage)),
                Some(format!("t{}", next(&mut hlsl_t))),
                format!("buffer({})", next(&mut msl_buffer)),
            ),
            ResourceKind::Texture => (
                Some(next(&mut gl_texture)),
                Some(format!("t{}", next(&mut hlsl_t))),
                format!("texture({})", next(&mut msl_texture)),
            ),
            ResourceKind::Sampler => (None, None, format!("sampler({})", next(&mut msl_sampler))),
        };
        out.push(Resource {
            group: b.group,
            binding: b.binding,
            name: g.name.clone().unwrap_or_default(),
            kind,
            wgsl_type: type_name(module, g.ty),
            glsl_binding,
            hlsl_register,
            msl_slot,
        });
    }
    out
}

fn binding_of(r: &Resource) -> ResourceBinding {
    ResourceBinding {
        group: r.group,
        binding: r.binding,
    }
}

/// The layouts of the uniform structs (sizes and offsets as the GPU reads the buffers).
pub fn struct_layouts(module: &Module) -> Vec<StructLayout> {
    let ctx = module.to_ctx();
    let mut out = Vec::new();
    for (_, g) in module.global_variables.iter() {
        if g.space != AddressSpace::Uniform {
            continue;
        }
        if let TypeInner::Struct { members, span } = &module.types[g.ty].inner {
            out.push(StructLayout {
                name: type_name(module, g.ty),
                size: *span,
                members: members
                    .iter()
                    .map(|m| MemberLayout {
                        name: m.name.clone().unwrap_or_default(),
                        wgsl_type: type_name(module, m.ty),
                        offset: m.offset,
                        size: module.types[m.ty].inner.size(ctx),
                    })
                    .collect(),
            });
        }
    }
    out
}

fn stage_name(stage: ShaderStage) -> &'static str {
    match stage {
        ShaderStage::Vertex => "vertex",
        ShaderStage::Fragment => "fragment",
        _ => "compute",
    }
}

fn locations_of(
    module: &Module,
    binding: Option<&naga::Binding>,
    ty: naga::Handle<naga::Type>,
    name: &str,
    out: &mut Vec<Location>,
) {
    match (binding, &module.types[ty].inner) {
        (Some(naga::Binding::Location { location, .. }), _) => out.push(Location {
            location: *location,
            name: name.to_string(),
            wgsl_type: type_name(module, ty),
        }),
        (None, TypeInner::Struct { members, .. }) => {
            for m in members {
                let member = m.name.clone().unwrap_or_default();
                locations_of(module, m.binding.as_ref(), m.ty, &member, out);
            }
        }
        _ => {}
    }
}

/// The entry points of `module`: stage, resources used, vertex inputs or fragment outputs.
pub fn entry_points(module: &Module, info: &ModuleInfo) -> Vec<EntryPoint> {
    let mut out = Vec::new();
    for (i, ep) in module.entry_points.iter().enumerate() {
        let usage = info.get_entry_point(i);
        let mut used: Vec<(ResourceBinding, String)> = module
            .global_variables
            .iter()
            .filter(|(h, g)| g.binding.is_some() && !usage[*h].is_empty())
            .filter_map(|(_, g)| g.binding.map(|b| (b, g.name.clone().unwrap_or_default())))
            .collect();
        used.sort_by_key(|(b, _)| (b.group, b.binding));
        let mut locations = Vec::new();
        match ep.stage {
            ShaderStage::Vertex => {
                for arg in &ep.function.arguments {
                    let name = arg.name.clone().unwrap_or_default();
                    locations_of(module, arg.binding.as_ref(), arg.ty, &name, &mut locations);
                }
            }
            _ => {
                if let Some(result) = &ep.function.result {
                    locations_of(
                        module,
                        result.binding.as_ref(),
                        result.ty,
                        "out",
                        &mut locations,
                    );
                }
            }
        }
        locations.sort_by_key(|l| l.location);
        out.push(EntryPoint {
            name: ep.name.clone(),
            stage: stage_name(ep.stage).to_string(),
            resources: used.into_iter().map(|(_, n)| n).collect(),
            locations,
        });
    }
    out
}

/// Per GLSL file, the GLSL name of each WGSL resource and vertex input.
type GlslNames = BTreeMap<String, BTreeMap<String, String>>;

fn glsl_extension(stage: ShaderStage) -> &'static str {
    match stage {
        ShaderStage::Vertex => "vert",
        _ => "frag",
    }
}

/// GLSL of every entry point, one file each (`NAME.vert` / `NAME.frag`), and for each file the
/// names naga gave the resources and vertex inputs.
fn glsl_files(
    module: &Module,
    info: &ModuleInfo,
    version: glsl::Version,
    table: &[Resource],
) -> Result<(Vec<(String, String)>, GlslNames), GpuError> {
    let mut binding_map = glsl::BindingMap::default();
    if version.supports_explicit_locations() {
        for r in table {
            if let Some(slot) = r.glsl_binding {
                let slot = u8::try_from(slot).map_err(|e| fail("GLSL", e))?;
                binding_map.insert(binding_of(r), slot);
            }
        }
    }
    let options = glsl::Options {
        version,
        writer_flags: glsl::WriterFlags::empty(),
        binding_map,
        zero_initialize_workgroup_memory: true,
    };
    let mut files = Vec::new();
    let mut names = BTreeMap::new();
    for ep in &module.entry_points {
        let ext = glsl_extension(ep.stage);
        let pipeline = glsl::PipelineOptions {
            shader_stage: ep.stage,
            entry_point: ep.name.clone(),
            multiview: None,
        };
        let mut text = String::new();
        let reflection = glsl::Writer::new(
            &mut text,
            module,
            info,
            &options,
            &pipeline,
            naga::proc::BoundsCheckPolicies::default(),
        )
        .and_then(|mut w| w.write())
        .map_err(|e| fail(&format!("GLSL {version} {}", ep.name), e))?;
        let file = format!("{}.{ext}", ep.name);
        let mut map = BTreeMap::new();
        for (glsl_name, mapping) in &reflection.texture_mapping {
            let var = &module.global_variables[mapping.texture];
            map.insert(var.name.clone().unwrap_or_default(), glsl_name.clone());
        }
        for (handle, glsl_name) in &reflection.uniforms {
            let var = &module.global_variables[*handle];
            map.insert(var.name.clone().unwrap_or_default(), glsl_name.clone());
        }
        if ep.stage == ShaderStage::Vertex {
            for (glsl_name, location) in &reflection.varying {
                map.insert(
                    format!("@location({})", location.location),
                    glsl_name.clone(),
                );
            }
        }
        names.insert(file.clone(), map);
        files.push((file, text));
    }
    Ok((files, names))
}

fn hlsl_file(module: &Module, info: &ModuleInfo, table: &[Resource]) -> Result<String, GpuError> {
    let target = |register: u32| hlsl::BindTarget {
        space: 0,
        register,
        binding_array_size: None,
        dynamic_storage_buffer_offsets_index: None,
        restrict_indexing: false,
    };
    let mut options = hlsl::Options {
        shader_model: hlsl::ShaderModel::V5_1,
        fake_missing_bindings: false,
        ..Default::default()
    };
    let mut next_t = 0;
    for r in table {
        if let Some(register) = &r.hlsl_register {
            let n: u32 = register[1..].parse().map_err(|e| fail("HLSL", e))?;
            options.binding_map.insert(binding_of(r), target(n));
            if register.starts_with('t') {
                next_t = next_t.max(n + 1);
            }
        } else {
            // The sampler: a slot in the heap (register s0), its index in the group's index array.
            options.binding_map.insert(binding_of(r), target(0));
        }
    }
    // Each group with a sampler gets an index array on the next t register.
    for r in table.iter().filter(|r| r.kind == ResourceKind::Sampler) {
        let key = hlsl::SamplerIndexBufferKey { group: r.group };
        if let std::collections::btree_map::Entry::Vacant(e) =
            options.sampler_buffer_binding_map.entry(key)
        {
            e.insert(target(next_t));
            next_t += 1;
        }
    }
    let mut text = String::new();
    hlsl::Writer::new(&mut text, &options, &hlsl::PipelineOptions::default())
        .write(module, info, None)
        .map_err(|e| fail("HLSL", e))?;
    Ok(text)
}

fn msl_file(module: &Module, info: &ModuleInfo, table: &[Resource]) -> Result<String, GpuError> {
    let slot = |s: &str| -> Result<u8, GpuError> {
        let inner = s
            .split_once('(')
            .and_then(|(_, rest)| rest.strip_suffix(')'))
            .ok_or_else(|| fail("MSL", format!("slot {s}")))?;
        inner.parse().map_err(|e| fail("MSL", e))
    };
    let mut resources = msl::BindingMap::default();
    let mut buffers = 0u8;
    for r in table {
        let n = slot(&r.msl_slot)?;
        let mut target = msl::BindTarget::default();
        match r.kind {
            ResourceKind::Uniform | ResourceKind::Storage => {
                target.buffer = Some(n);
                buffers = buffers.max(n + 1);
            }
            ResourceKind::Texture => target.texture = Some(n),
            ResourceKind::Sampler => target.sampler = Some(msl::BindSamplerTarget::Resource(n)),
        }
        resources.insert(binding_of(r), target);
    }
    let per_entry = msl::EntryPointResources {
        resources,
        sizes_buffer: Some(buffers),
        ..Default::default()
    };
    let options = msl::Options {
        lang_version: (2, 1),
        per_entry_point_map: ENTRY_POINTS
            .iter()
            .map(|e| (e.to_string(), per_entry.clone()))
            .collect(),
        fake_missing_bindings: false,
        ..Default::default()
    };
    let (text, _) = msl::write_string(module, info, &options, &msl::PipelineOptions::default())
        .map_err(|e| fail("MSL", e))?;
    Ok(text)
}

fn spirv_file(module: &Module, info: &ModuleInfo) -> Result<Vec<u8>, GpuError> {
    let options = spv::Options {
        flags: spv::WriterFlags::ADJUST_COORDINATE_SPACE | spv::WriterFlags::LABEL_VARYINGS,
        ..Default::default()
    };
    let words = spv::write_vec(module, info, &options, None).map_err(|e| fail("SPIR-V", e))?;
    Ok(words.iter().flat_map(|w| w.to_le_bytes()).collect())
}

fn notes(language: &str, table: &[Resource]) -> Vec<String> {
    let sizes = table
        .iter()
        .filter(|r| matches!(r.kind, ResourceKind::Uniform | ResourceKind::Storage))
        .count();
    let clip = "Clip space is wgpu's: 0 ≤ z ≤ w, y up in NDC";
    match language {
        "glsl-450" => vec![
            format!("{clip}, kept as is: call glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE) (GL 4.5) so depth matches the oracle's, and clear depth to 1."),
            "Textures and the sampler are combined: each texture is a sampler2D on the texture unit given; set the fur sampler's state (repeat u, repeat v on shells / clamp v on fins, trilinear) on the units of colour_map, tangent_map and density_bands, nearest and level 0 on the maps (read with texelFetch).".into(),
            "Uniform blocks and storage blocks have separate binding numbers (glBindBufferBase(GL_UNIFORM_BUFFER, n) / GL_SHADER_STORAGE_BUFFER).".into(),
            "Window row 0 is the bottom row in GL: flip rows when reading back to compare with the oracle's PNG (row 0 at the top).".into(),
        ],
        "glsl-es-300" => vec![
            format!("{clip}, kept as is: without clip control ES maps z ∈ [0, 1] to depth [0.5, 1]; the depth test still orders fragments the same way."),
            format!("This folder's fur.wgsl is the variant translated: spots, matches and the joint palette are uniform arrays (at most {ES300_MAX_SPOTS} spots, 4 vec4 each, {ES300_MAX_MATCHES} matches and {ES300_MAX_JOINTS} joints, 1 + 4 vec4 each; upload them as uniform blocks padded to the full size), and the mip level count is computed from the size of level 0 (upload every level down to 1×1, as exported)."),
            "No explicit bindings in ES 3.00: bind by the GLSL names listed per file (glGetUniformBlockIndex + glUniformBlockBinding, glUniform1i on each sampler2D, glBindAttribLocation for vertex inputs).".into(),
            "Window row 0 is the bottom row in GL: flip rows when reading back.".into(),
        ],
        "hlsl" => vec![
            format!("{clip}, as D3D's: no change."),
            "Registers are in space 0. Read-only storage buffers are ByteAddressBuffers on t registers (vec4 i at byte 16·i).".into(),
            "The sampler goes through naga's sampler heap: a SamplerState array at s0 (space 0) holding the fur sampler, and a StructuredBuffer<uint> of heap indices for group 1 (nagaGroup1SamplerIndexArray, its t register declared in fur.hlsl, after the textures'); put the fur sampler at heap index 0 and one 0 in the index array. The comparison heap (s0, space 1) is declared but unused.".into(),
            "Entry points keep their WGSL names; compile with vs_5_1 / ps_5_1 (fxc) or vs_6_0 / ps_6_0 (dxc).".into(),
        ],
        "msl" => vec![
            format!("{clip}, as Metal's: no change."),
            format!("buffer({sizes}) is the sizes buffer: uint byte sizes of spots, matches then palette (the runtime-sized arrays, in declaration order)."),
            "Vertex attributes are [[attribute(L)]] with L the WGSL location; give the vertex buffers buffer indices above the sizes buffer in the MTLVertexDescriptor.".into(),
        ],
        "spirv" => vec![
            format!("{clip}; clip y is already negated for Vulkan (as wgpu does): use a viewport of positive height."),
            "Descriptor set = WGSL group, binding = WGSL binding; one module holds every entry point.".into(),
        ],
        _ => Vec::new(),
    }
}

/// `bindings.md`: the tables of [`Bindings`] for a reader.
pub fn bindings_markdown(b: &Bindings) -> String {
    let mut s = format!(
        "# Bindings of fur.wgsl as {} (generated by `pelage export`)\n\n",
        b.language
    );
    s += "## Files\n\n";
    for (file, eps) in &b.files {
        s += &format!("- `{file}`: {}\n", eps.join(", "));
    }
    let slot_header = match b.language.as_str() {
        "glsl-450" => "GLSL binding",
        "glsl-es-300" => "GLSL name (per file below)",
        "hlsl" => "HLSL register (space 0)",
        "msl" => "MSL slot",
        _ => "SPIR-V (set, binding)",
    };
    s += &format!(
        "\n## Resources\n\n| group | binding | name | kind | WGSL type | {slot_header} |\n|---|---|---|---|---|---|\n"
    );
    for r in &b.resources {
        let slot = match b.language.as_str() {
            "glsl-450" => r
                .glsl_binding
                .map_or("(combined with the textures)".to_string(), |n| {
                    n.to_string()
                }),
            "glsl-es-300" => "by name".to_string(),
            "hlsl" => r
                .hlsl_register
                .clone()
                .unwrap_or_else(|| "sampler heap (see notes)".into()),
            "msl" => r.msl_slot.clone(),
            _ => format!("({}, {})", r.group, r.binding),
        };
        s += &format!(
            "| {} | {} | `{}` | {:?} | `{}` | {} |\n",
            r.group, r.binding, r.name, r.kind, r.wgsl_type, slot
        );
    }
    for st in &b.structs {
        s += &format!(
            "\n## `{}` ({} bytes, std140-compatible)\n\n| offset | size | member | WGSL type |\n|---|---|---|---|\n",
            st.name, st.size
        );
        for m in &st.members {
            s += &format!(
                "| {} | {} | `{}` | `{}` |\n",
                m.offset, m.size, m.name, m.wgsl_type
            );
        }
    }
    s += "\n## Entry points\n";
    for ep in &b.entry_points {
        s += &format!(
            "\n### `{}` ({})\n\nResources: {}.\n\n",
            ep.name,
            ep.stage,
            ep.resources
                .iter()
                .map(|r| format!("`{r}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let what = if ep.stage == "vertex" {
            "Vertex inputs"
        } else {
            "Outputs"
        };
        s += &format!("| {what}: location | name | WGSL type |\n|---|---|---|\n");
        for l in &ep.locations {
            s += &format!("| {} | `{}` | `{}` |\n", l.location, l.name, l.wgsl_type);
        }
    }
    if !b.glsl_names.is_empty() {
        s += "\n## GLSL names (bind by name)\n";
        for (file, names) in &b.glsl_names {
            s += &format!("\n### `{file}`\n\n| WGSL | GLSL |\n|---|---|\n");
            for (wgsl, glsl) in names {
                s += &format!("| `{wgsl}` | `{glsl}` |\n");
            }
        }
    }
    s += "\n## Notes\n\n";
    for n in &b.notes {
        s += &format!("- {n}\n");
    }
    s
}

fn bindings(
    language: &str,
    module: &Module,
    info: &ModuleInfo,
    files: BTreeMap<String, Vec<String>>,
    glsl_names: BTreeMap<String, BTreeMap<String, String>>,
) -> Bindings {
    let table = resources(module);
    Bindings {
        language: language.to_string(),
        files,
        notes: notes(language, &table),
        resources: table,
        structs: struct_layouts(module),
        entry_points: entry_points(module, info),
        glsl_names,
    }
}

fn push_bindings(out: &mut Vec<ShaderFile>, b: &Bindings) -> Result<(), GpuError> {
    let json = serde_json::to_string_pretty(b).map_err(|e| fail("bindings.json", e))?;
    out.push(ShaderFile {
        path: format!("{}/bindings.json", b.language),
        bytes: json.into_bytes(),
    });
    out.push(ShaderFile {
        path: format!("{}/bindings.md", b.language),
        bytes: bindings_markdown(b).into_bytes(),
    });
    Ok(())
}

/// `fur.wgsl` in every language of [`LANGUAGES`], each folder with its code, `bindings.json`
/// and `bindings.md`, plus `fur.wgsl` itself. Deterministic: the same bytes on every run.
pub fn translate_all() -> Result<Vec<ShaderFile>, GpuError> {
    let (module, info) = parse(SHADER_SOURCE)?;
    let table = resources(&module);
    let all: Vec<String> = module.entry_points.iter().map(|e| e.name.clone()).collect();
    let mut out = vec![ShaderFile {
        path: "fur.wgsl".into(),
        bytes: SHADER_SOURCE.as_bytes().to_vec(),
    }];

    for (language, version, source) in [
        ("glsl-450", glsl::Version::Desktop(450), None),
        (
            "glsl-es-300",
            glsl::Version::Embedded {
                version: 300,
                is_webgl: false,
            },
            Some(es300_source()?),
        ),
    ] {
        let parsed;
        let (m, i) = match &source {
            Some(text) => {
                parsed = parse(text)?;
                (&parsed.0, &parsed.1)
            }
            None => (&module, &info),
        };
        let (files, names) = glsl_files(m, i, version, &resources(m))?;
        let mut listing = BTreeMap::new();
        for (file, text) in files {
            let ep = file.split('.').next().unwrap_or_default().to_string();
            listing.insert(file.clone(), vec![ep]);
            out.push(ShaderFile {
                path: format!("{language}/{file}"),
                bytes: text.into_bytes(),
            });
        }
        let names = if version.supports_explicit_locations() {
            BTreeMap::new()
        } else {
            names
        };
        if let Some(text) = &source {
            out.push(ShaderFile {
                path: format!("{language}/fur.wgsl"),
                bytes: text.clone().into_bytes(),
            });
        }
        push_bindings(&mut out, &bindings(language, m, i, listing, names))?;
    }

    let hlsl = hlsl_file(&module, &info, &table)?;
    out.push(ShaderFile {
        path: "hlsl/fur.hlsl".into(),
        bytes: hlsl.into_bytes(),
    });
    let files = BTreeMap::from([("fur.hlsl".to_string(), all.clone())]);
    push_bindings(
        &mut out,
        &bindings("hlsl", &module, &info, files, BTreeMap::new()),
    )?;

    let metal = msl_file(&module, &info, &table)?;
    out.push(ShaderFile {
        path: "msl/fur.metal".into(),
        bytes: metal.into_bytes(),
    });
    let files = BTreeMap::from([("fur.metal".to_string(), all.clone())]);
    push_bindings(
        &mut out,
        &bindings("msl", &module, &info, files, BTreeMap::new()),
    )?;

    out.push(ShaderFile {
        path: "spirv/fur.spv".into(),
        bytes: spirv_file(&module, &info)?,
    });
    let files = BTreeMap::from([("fur.spv".to_string(), all)]);
    push_bindings(
        &mut out,
        &bindings("spirv", &module, &info, files, BTreeMap::new()),
    )?;
    Ok(out)
}
