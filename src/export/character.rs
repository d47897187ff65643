//! Export of a glTF character (export stage): the model written back out with its skin and
//! the clip the scene plays, so that an engine can play it, plus the frame's joint matrices.
//!
//! ```text
//! DIR/meshes/character.gltf, character.bin   the bind mesh, its skin, the node hierarchy and
//!                                            the clip (glTF 2.0)
//! DIR/meshes/joints.json                     the joint matrices at the exported instant
//! ```
//!
//! **What an engine must match.** The mesh is pelage's bind mesh (one primitive, vertices as the
//! file binds them, `JOINTS_0`/`WEIGHTS_0` as pelage reads them: weights already normalised
//! `w_k / (((w0 + w1) + w2) + w3)`, a slot of weight zero written as joint 0). The skin's joint
//! list is pelage's palette in its order, so `JOINTS_0` indexes it and `joints.json` alike: the
//! joints of each skin in the order the drawn mesh nodes are composed, a rigid (unskinned) mesh
//! node as a joint of identity inverse bind matrix. A node that is a joint twice (two skins
//! sharing it, or a rigid mesh node that is also a joint) gets an extra child of identity
//! transform for each further use, since a skin lists a node once. Every root of the file's
//! hierarchy hangs under `pelage_scale`, whose scale is the scene's `mesh.scale`. Node indices
//! below the helper nodes are the file's own, with their rest transforms.
//!
//! The clip is the one `[animation]` names, its keys and interpolation as the file gives them;
//! its `extras` give `speed` and `loop`: the clip time of scene time `t` is `t·speed`, wrapped
//! into `[0, end]` when looping, clamped otherwise (`joints.json` gives it for the instant).
//! After skinning, pelage moves the skin along its skinned normal by `skin_inset` and grows
//! the shells from there along the same normal (`joints.json`).

use super::{GltfBuilder, checked, extras, primitive};
use crate::mesh::animation::{Interpolation, Property};
use crate::mesh::skin::{Affine, LocalTransform, PaletteEntry};
use crate::render::PreparedScene;
use gltf_json as gj;
use serde_json::{Value, json};

/// The glTF document, its buffer and `joints.json` of a character.
pub(super) struct CharacterFiles {
    pub gltf: gj::Root,
    pub bin: Vec<u8>,
    pub joints: Value,
}

/// The largest palette `JOINTS_0` can index (unsigned short).
const MAX_JOINTS: usize = 1 << 16;

/// The character files of `prepared` at `time`, or `None` when its mesh is not a glTF model.
/// `colour_texture`: the exported colour map (relative to the export folder), used as the base
/// colour when the fur takes its colour from the model.
pub(super) fn character(
    prepared: &PreparedScene,
    time: f32,
    colour_texture: Option<&str>,
) -> Result<Option<CharacterFiles>, String> {
    let Some(model) = prepared.character() else {
        return Ok(None);
    };
    let rig = model.rig;
    let skeleton = &rig.skeleton;
    if rig.palette.len() > MAX_JOINTS {
        return Err(format!(
            "the model has {} palette entries; JOINTS_0 indexes at most {MAX_JOINTS}",
            rig.palette.len()
        ));
    }
    let mut b = GltfBuilder::default();
    b.root.asset = gj::Asset {
        generator: Some("pelage export".into()),
        ..Default::default()
    };

    // The file's nodes, same indices, rest transforms.
    let count = skeleton.parents.len();
    let mut children: Vec<Vec<gj::Index<gj::Node>>> = vec![Vec::new(); count];
    for (node, parent) in skeleton.parents.iter().enumerate() {
        if let Some(p) = parent {
            children[*p].push(gj::Index::new(node as u32));
        }
    }
    for node in 0..count {
        let mut n = gj::Node {
            name: Some(skeleton.names[node].clone()).filter(|s| !s.is_empty()),
            ..Default::default()
        };
        match skeleton.rest[node] {
            LocalTransform::Trs {
                translation,
                rotation,
                scale,
            } => {
                n.translation = Some(translation.to_array());
                n.rotation = Some(gj::scene::UnitQuaternion(rotation.to_array()));
                n.scale = Some(scale.to_array());
            }
            LocalTransform::Matrix(m) => n.matrix = Some(m.to_cols_4x4()),
        }
        b.root.push(n);
    }

    // The palette as the skin's joints; a node used twice gets a helper child per further use.
    let mut used = vec![false; count];
    let mut joints = Vec::with_capacity(rig.palette.len());
    let mut inverse_binds: Vec<f32> = Vec::with_capacity(16 * rig.palette.len());
    for (k, entry) in rig.palette.iter().enumerate() {
        let (node, inverse_bind) = match *entry {
            PaletteEntry::Joint { node, inverse_bind } => (node, inverse_bind),
            PaletteEntry::Node { node } => (node, Affine::IDENTITY),
        };
        let joint = if std::mem::replace(&mut used[node], true) {
            let helper = b.root.push(gj::Node {
                name: Some(format!("pelage_palette_{k}")),
                extras: extras(&json!({
                    "pelage": format!("palette entry {k}: node {node} again (identity transform)")
                })),
                ..Default::default()
            });
            children[node].push(helper);
            helper
        } else {
            gj::Index::new(node as u32)
        };
        joints.push(joint);
        inverse_binds.extend(inverse_bind.to_cols_4x4());
    }
    for (node, list) in children.into_iter().enumerate() {
        if !list.is_empty() {
            b.root.nodes[node].children = Some(list);
        }
    }
    let roots: Vec<gj::Index<gj::Node>> = (0..count)
        .filter(|&n| skeleton.parents[n].is_none())
        .map(|n| gj::Index::new(n as u32))
        .collect();
    let scale_root = b.root.push(gj::Node {
        name: Some("pelage_scale".into()),
        scale: Some([rig.scale; 3]),
        children: Some(roots),
        extras: extras(&json!({ "pelage": "mesh.scale of the scene" })),
        ..Default::default()
    });

    // The bind mesh with its influences.
    let bind = model.bind;
    let position = b.vec3s(bind.vertices.iter().map(|v| v.position), true);
    let normal = b.vec3s(bind.vertices.iter().map(|v| v.normal), false);
    let uv = b.vec2s(bind.vertices.iter().map(|v| v.uv));
    let weights: Vec<f32> = rig.influences.iter().flat_map(|i| i.weights).collect();
    let weights = b.floats(&weights, 4, false);
    let joint_indices = joints_accessor(
        &mut b,
        rig.influences.iter().map(|i| {
            // Indices fit: the palette's length was checked above.
            std::array::from_fn(|k| {
                if i.weights[k] != 0.0 {
                    i.joints[k] as u16
                } else {
                    0
                }
            })
        }),
    );
    let indices = b.indices(&bind.indices);
    let colour = prepared.scene().fur.colour;
    let base_color_texture = colour_texture.map(|file| {
        let sampler = b.root.push(gj::texture::Sampler {
            mag_filter: Some(checked(gj::texture::MagFilter::Linear)),
            min_filter: Some(checked(gj::texture::MinFilter::Linear)),
            name: None,
            wrap_s: checked(gj::texture::WrappingMode::Repeat),
            wrap_t: checked(gj::texture::WrappingMode::Repeat),
            extensions: None,
            extras: None,
        });
        gj::texture::Info {
            index: b.texture(file, sampler),
            tex_coord: 0,
            extensions: None,
            extras: None,
        }
    });
    let material = b.root.push(gj::Material {
        name: Some("character".into()),
        pbr_metallic_roughness: gj::material::PbrMetallicRoughness {
            base_color_factor: gj::material::PbrBaseColorFactor(match base_color_texture {
                Some(_) => [1.0; 4],
                None => colour.extend(1.0).to_array(),
            }),
            base_color_texture,
            metallic_factor: gj::material::StrengthFactor(0.0),
            roughness_factor: gj::material::StrengthFactor(1.0),
            ..Default::default()
        },
        extras: extras(&json!({
            "pelage": "the skin the fur grows on; draw the fur from meshes/fur.gltf and scene.json"
        })),
        ..Default::default()
    });
    use gj::mesh::Semantic;
    let mesh = b.root.push(gj::Mesh {
        name: Some("character".into()),
        primitives: vec![primitive(
            &[
                (Semantic::Positions, position),
                (Semantic::Normals, normal),
                (Semantic::TexCoords(0), uv),
                (Semantic::Joints(0), joint_indices),
                (Semantic::Weights(0), weights),
            ],
            indices,
            material,
        )],
        weights: None,
        extensions: None,
        extras: None,
    });
    let inverse_binds = b.floats_in(&inverse_binds, 16, false, None);
    let skin = b.root.push(gj::Skin {
        extensions: None,
        extras: None,
        inverse_bind_matrices: Some(inverse_binds),
        joints: joints.clone(),
        name: Some("pelage_palette".into()),
        skeleton: Some(scale_root),
    });
    let mesh_node = b.root.push(gj::Node {
        name: Some("character".into()),
        mesh: Some(mesh),
        skin: Some(skin),
        ..Default::default()
    });

    // The clip the scene plays.
    let mut clip_json = Value::Null;
    if let Some((clip, speed, looping)) = model.clip {
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        for channel in &clip.channels {
            let input = b.floats_in(&channel.times, 1, true, None);
            let width = match channel.property {
                Property::Rotation => 4,
                Property::Translation | Property::Scale => 3,
            };
            let values: Vec<f32> = channel
                .values
                .iter()
                .flat_map(|v| v.to_array().into_iter().take(width))
                .collect();
            let output = b.floats_in(&values, width, false, None);
            let sampler = gj::Index::new(samplers.len() as u32);
            samplers.push(gj::animation::Sampler {
                extensions: None,
                extras: None,
                input,
                interpolation: checked(match channel.interpolation {
                    Interpolation::Linear => gj::animation::Interpolation::Linear,
                    Interpolation::Step => gj::animation::Interpolation::Step,
                    Interpolation::CubicSpline => gj::animation::Interpolation::CubicSpline,
                }),
                output,
            });
            channels.push(gj::animation::Channel {
                sampler,
                target: gj::animation::Target {
                    extensions: None,
                    extras: None,
                    node: gj::Index::new(channel.node as u32),
                    path: checked(match channel.property {
                        Property::Translation => gj::animation::Property::Translation,
                        Property::Rotation => gj::animation::Property::Rotation,
                        Property::Scale => gj::animation::Property::Scale,
                    }),
                },
                extensions: None,
                extras: None,
            });
        }
        let clip_time = clip.clip_time(time, speed, looping);
        clip_json = json!({
            "name": clip.name,
            "speed": speed,
            "loop": looping,
            "end": clip.end(),
            "clip_time": clip_time,
        });
        if !channels.is_empty() {
            b.root.push(gj::Animation {
                extensions: None,
                extras: extras(&json!({
                    "speed": speed,
                    "loop": looping,
                    "pelage": "clip time = scene time × speed, wrapped into [0, end] when loop is true, clamped otherwise",
                })),
                channels,
                name: Some(clip.name.clone()).filter(|s| !s.is_empty()),
                samplers,
            });
        }
    }

    let scene = b.root.push(gj::Scene {
        nodes: vec![scale_root, mesh_node],
        name: Some("pelage character".into()),
        extensions: None,
        extras: None,
    });
    b.root.scene = Some(scene);

    let palette = prepared
        .skinning_at(time)
        .map(|s| s.palette)
        .unwrap_or_default();
    let joints_json = json!({
        "format": "pelage joints 1",
        "time": time,
        "gltf": "character.gltf",
        "clip": clip_json,
        "scale": rig.scale,
        "skin_inset": model.skin_inset,
        "joints": palette.iter().zip(&joints).enumerate().map(|(k, (m, node))| json!({
            "index": k,
            "node": node.value(),
            "name": b.root.nodes[node.value()].name,
            "matrix": m,
        })).collect::<Vec<_>>(),
        "conventions": {
            "matrix": "column-major 4×4, mesh.scale included: global(joint)·inverse_bind scaled by mesh.scale; the palette entry JOINTS_0 indexes (the skin's joint list in character.gltf, in the same order)",
            "blend": "M = ((w0·P[j0] + w1·P[j1]) + w2·P[j2]) + w3·P[j3], entry by entry, f32, no fused multiply-add; weights as WEIGHTS_0 (already normalised)",
            "position": "M·p of the bind POSITION, then moved by skin_inset along the skinned normal",
            "normal": "the cofactor matrix of M's 3×3 times the bind NORMAL, negated where det < 0, normalised (the inverse transpose up to a positive factor)",
            "shells": "pushed out from the inset skin along the skinned normal; fins chosen on the posed silhouette (meshes/fur.gltf holds this frame's)",
            "tangent_frame": "rebuilt on the posed surface from the skinned dp/du, dp/dv and normal (eq. 3.1–3.3), not skinned from the bind frame",
        },
    });
    let (gltf, bin) = b.finish("character.bin");
    Ok(Some(CharacterFiles {
        gltf,
        bin,
        joints: joints_json,
    }))
}

/// `JOINTS_0` as unsigned shorts.
fn joints_accessor(
    b: &mut GltfBuilder,
    joints: impl Iterator<Item = [u16; 4]>,
) -> gj::Index<gj::Accessor> {
    b.align();
    let offset = b.bin.len();
    let mut count = 0usize;
    for j in joints {
        for v in j {
            b.bin.extend_from_slice(&v.to_le_bytes());
        }
        count += 1;
    }
    let view = b.view(offset, Some(gj::buffer::Target::ArrayBuffer));
    b.accessor(
        view,
        count,
        gj::accessor::ComponentType::U16,
        gj::accessor::Type::Vec4,
        (None, None),
    )
}
