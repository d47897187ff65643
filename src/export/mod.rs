//! Export (beside the pipeline: export): everything a GPU implementation needs to draw the same
//! frame as the oracle, written to one folder by [`export`]:
//!
//! ```text
//! DIR/scene.json                       every parameter and uniform (see below)
//! DIR/oracle.png                       the oracle's render of this frame
//! DIR/meshes/fur.gltf, fur.bin         skin, every shell layer, this frame's fins (glTF 2.0)
//! DIR/meshes/character.gltf, .bin      a glTF model's bind mesh, skin and clip, and
//! DIR/meshes/joints.json               this frame's joint matrices ([`character`])
//! DIR/textures/shell_NN_colour.png     shell layer NN (root = 00), mip level 0
//! DIR/textures/shell_NN_tangent.png
//! DIR/textures/shell_NN_density.png    shell NN's density bands (scenes with a density map)
//! DIR/textures/fin_colour.png, fin_tangent.png
//! DIR/textures/mips/<name>_L.png       mip level L ≥ 1 of each texture above
//! DIR/textures/maps/<map>.png          the surface maps (length, density, direction, colour)
//! DIR/shaders/                         with feature `gpu`: fur.wgsl, and in glsl-450/,
//!                                      glsl-es-300/, hlsl/, msl/, spirv/ its translation with
//!                                      bindings.md and bindings.json ([`crate::gpu::translate`])
//! ```
//!
//! **Textures.** RGBA8 PNG, no colour space (linear values), row 0 at `v = 0`: upload as is.
//! Colour maps hold the strand colour and a straight (not premultiplied) alpha. Tangent maps
//! hold `unorm8(t·0.5 + 0.5)` of the unit strand tangent in tangent space (x = texture u,
//! y = texture v, z = away from the skin), alpha equal to the colour map's; decode with
//! `normalize(texel.rgb·2 − 1)`. The mip chain is pelage's own (each colour texel the
//! alpha-weighted mean `(Σ αᵢ·cᵢ + ⌊Σαᵢ/2⌋) / Σαᵢ` of the 2×2 block below it, alpha the rounded
//! mean `(a + b + c + d + 2) >> 2`; density bands the rounded mean on every channel); use the
//! exported levels rather than the GPU's mip generation to sample the same values.
//!
//! **Beyond the thesis.** Density band textures (`shell_NN_density.png`, with mips, sampled
//! like the colour map): R, G, B, A = the alpha of the strands in density bands ≤ 0, ≤ 1, ≤ 2,
//! ≤ 3 (A equals the colour map's alpha); the fragment's alpha is `density_alpha(bands,
//! density)` ([`crate::shading::density_alpha`]). Surface maps (`textures/maps/`): the maps as
//! pelage reads them (RGBA8, level 0 only), sampled in mesh uv (`TEXCOORD_0`) bilinearly at
//! level 0 with texel centres at `(i + ½)/size` and the `[maps] address` per axis
//! ([`crate::render::maps`]). `scene.json` gives each layer's `lod_span` at the instant (0: the
//! layer is not drawn), the level of detail (`frame.level_of_detail`), the shared lean
//! (`frame.lean`) and the object's path offset (`frame.object_offset`).
//!
//! **Meshes.** `fur.gltf` holds one mesh per pass; they are drawn skin, fins, then shells root to
//! tip (`scene.json`'s `pipeline.pass_order`):
//! - `skin`: `POSITION`, `NORMAL`, `TANGENT` (xyz = frame T along +u, w = ±1 with
//!   `B = w·(N × T)`), `TEXCOORD_0` (mesh uv; the fur uv is `uv × texture_repeat`), and the
//!   application-specific `_BINORMAL` (frame B), `_DPDU`, `_DPDV` (∂p/∂u, ∂p/∂v, unnormalised:
//!   the shadow and wind projections need them);
//! - `shell_NN`: the skin pushed out along `NORMAL` by `layers[NN].offset` (its own
//!   `POSITION`; every other attribute and the indices shared with `skin`); per frame, the
//!   vertex stage scales the offset by the length map, adds the part along the normal of the
//!   wind's (thesis 3.3) or the lean's displacement (the sideways part is the texture lookup
//!   `uv − wind_uv`) and the object's path offset, see `scene.json`'s `frame`;
//! - `fins`: this frame's silhouette fins (view dependent, chosen on the CPU), with `POSITION`,
//!   `NORMAL` (the root's vertex normal), `TEXCOORD_0` (fin uv, v = 0 at the root) and the fur
//!   varyings of the oracle's fragment stage at each corner: `_LIGHT`, `_EYE` (tangent space of
//!   the fin), `_SHADOW` (the self-shadow's lookup offset in fin uv), `_FADE` (level of
//!   detail's fin fade included), `_OBJECT` (the root point, object
//!   space), `_MESH_UV` (the root's mesh uv, where the maps are read), `_LENGTH` (the length
//!   map at the root; 1 at the bottom corners). Fin positions include the object's offset.
//!
//! Triangles are counter-clockwise seen from outside; indices are u32. The skin and shells
//! also carry `TEXCOORD_1`, the fur uv (`uv × texture_repeat`). Materials (written with the
//! typed `gltf-json` crate): `skin` opaque (fur colour × 0.35); `shell_NN` its colour texture
//! in `TEXCOORD_1`, `alphaMode` `BLEND`; `fins` the fin colour texture, clamp v, double-sided;
//! each fur material's `extras` name the tangent texture, density bands and mip files. The
//! default scene's nodes are in draw order (`extras.draw_order`).
//!
//! **scene.json.** `scene` repeats the scene file with every default filled in (the names of
//! the TOML keys); `camera` has the column-major `view`, `projection` and `view_projection`
//! matrices; `frame` the values resolved at the exported instant (unit light direction, wind
//! force, burn exponent, spots in application order, lean, object offset, level of detail);
//! `layers` the per-shell uniforms (offset, shadow lookups, height fraction, LOD span, texture
//! files); `maps` the surface map files; `fin`, `pipeline` (depth, blend, cull, samplers) and
//! `conventions` say the rest.

pub mod character;

use crate::camera::Camera;
use crate::raster::Texture;
use crate::render::fragment::{ALPHA_DISCARD, Spot};
use crate::render::{PreparedScene, RenderError};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use gltf_json as gj;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// What can go wrong exporting.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The oracle render failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A file could not be written.
    #[error("{path}: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// What [`export`] wrote.
#[derive(Clone, Debug, Default)]
pub struct ExportSummary {
    /// Every file written, relative to the export folder.
    pub files: Vec<PathBuf>,
}

/// The files of one exported texture, relative to the export folder.
#[derive(Clone, Debug, Default)]
struct TextureFiles {
    /// `textures/NAME.png`.
    level0: String,
    /// `textures/mips/NAME_L.png`, L = 1, 2, …
    mips: Vec<String>,
}

/// The textures of a shell layer or of the fins, for the glTF's materials.
#[derive(Clone, Debug, Default)]
struct LayerTextures {
    colour: TextureFiles,
    tangent: TextureFiles,
    density: Option<TextureFiles>,
}

struct Writer<'a> {
    dir: &'a Path,
    files: Vec<PathBuf>,
}

impl Writer<'_> {
    fn write(&mut self, relative: &str, bytes: &[u8]) -> Result<(), ExportError> {
        let path = self.dir.join(relative);
        let fail = |e: String| ExportError::Write {
            path: path.clone(),
            message: e,
        };
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| fail(e.to_string()))?;
        }
        crate::output::write_atomic(&path, bytes).map_err(|e| fail(e.message))?;
        self.files.push(PathBuf::from(relative));
        Ok(())
    }

    fn png(
        &mut self,
        relative: &str,
        width: u32,
        height: u32,
        rgba: &[u8],
    ) -> Result<(), ExportError> {
        let bytes =
            crate::output::encode_png(width, height, rgba).map_err(|e| ExportError::Write {
                path: self.dir.join(relative),
                message: e,
            })?;
        self.write(relative, &bytes)
    }

    /// Level 0 as `textures/NAME.png`, levels ≥ 1 as `textures/mips/NAME_L.png`.
    fn texture(&mut self, name: &str, texture: &Texture) -> Result<TextureFiles, ExportError> {
        let mut mips = Vec::new();
        for k in 0..texture.level_count() {
            let level = texture.level(k).expect("level in range");
            let rgba: Vec<u8> = level.texels().iter().flatten().copied().collect();
            let relative = if k == 0 {
                format!("textures/{name}.png")
            } else {
                format!("textures/mips/{name}_{k}.png")
            };
            self.png(&relative, level.width(), level.height(), &rgba)?;
            if k > 0 {
                mips.push(relative);
            }
        }
        Ok(TextureFiles {
            level0: format!("textures/{name}.png"),
            mips,
        })
    }
}

/// Writes the export of `prepared` at `time` (seconds) into `dir` (created if missing): the
/// oracle's render, textures, meshes and `scene.json`; see the [module docs](self).
pub fn export(
    prepared: &PreparedScene,
    time: f32,
    dir: &Path,
) -> Result<ExportSummary, ExportError> {
    let mut w = Writer {
        dir,
        files: Vec::new(),
    };
    let image = prepared.render_at(time, crate::raster::DEFAULT_TILE_SIZE)?;
    w.png("oracle.png", image.width, image.height, &image.rgba8)?;

    let lod = prepared.level_of_detail_at(time);
    let mut layers = Vec::new();
    let mut shell_textures = Vec::new();
    for i in 0..prepared.shell_count() {
        let (colour, tangent) = prepared.shell_textures(i).expect("layer in range");
        let colour_file = w.texture(&format!("shell_{i:02}_colour"), colour)?;
        let tangent_file = w.texture(&format!("shell_{i:02}_tangent"), tangent)?;
        let density_file = prepared
            .shell_density(i)
            .map(|bands| w.texture(&format!("shell_{i:02}_density"), bands))
            .transpose()?;
        let p = prepared.shell_layer_params(i as u32);
        layers.push(json!({
            "index": p.index,
            "offset": prepared.shell_offsets()[i],
            "shadow_lookups": p.lookups,
            "height_fraction": p.height_fraction,
            "max_shell": p.max_shell,
            "lod_span": lod.as_ref().map_or(1.0, |l| l.spans[i]),
            "colour_texture": colour_file.level0,
            "tangent_texture": tangent_file.level0,
            "density_texture": density_file.as_ref().map(|d| &d.level0),
            "mip_levels": colour.level_count(),
        }));
        shell_textures.push(LayerTextures {
            colour: colour_file,
            tangent: tangent_file,
            density: density_file,
        });
    }
    let surface = prepared.maps();
    let mut maps = serde_json::Map::new();
    for (name, map) in [
        ("length", &surface.length),
        ("density", &surface.density),
        ("direction", &surface.direction),
        ("colour", &surface.colour),
    ] {
        if let Some(map) = map {
            let level = map.level(0).expect("level 0");
            let rgba: Vec<u8> = level.texels().iter().flatten().copied().collect();
            let relative = format!("textures/maps/{name}.png");
            w.png(&relative, level.width(), level.height(), &rgba)?;
            maps.insert(name.to_string(), json!(relative));
        }
    }
    let mut fin_textures = None;
    let fin = match prepared.fin_textures() {
        Some((colour, tangent)) => {
            let colour_files = w.texture("fin_colour", colour)?;
            let tangent_files = w.texture("fin_tangent", tangent)?;
            let (colour_file, tangent_file) =
                (colour_files.level0.clone(), tangent_files.level0.clone());
            fin_textures = Some(LayerTextures {
                colour: colour_files,
                tangent: tangent_files,
                density: None,
            });
            json!({
                "height": prepared.fin_height(),
                "colour_texture": colour_file,
                "tangent_texture": tangent_file,
                "mip_levels": colour.level_count(),
                "layer": {
                    "index": prepared.fin_layer_params().index,
                    "shadow_lookups": prepared.fin_layer_params().lookups,
                    "height_fraction": prepared.fin_layer_params().height_fraction,
                },
                "sampler": { "address_u": "wrap", "address_v": "clamp", "filter": "trilinear" },
            })
        }
        None => Value::Null,
    };

    let (gltf, bin) = gltf(prepared, time, &shell_textures, fin_textures.as_ref());
    w.write("meshes/fur.bin", &bin)?;
    let text = serde_json::to_string_pretty(&gltf).expect("JSON of plain values");
    w.write("meshes/fur.gltf", text.as_bytes())?;

    // A glTF model: written back with its skin and clip, and the frame's joint matrices.
    let colour_texture = maps
        .get("colour")
        .and_then(Value::as_str)
        .filter(|_| prepared.scene().fur.colour_from_mesh)
        .map(str::to_string);
    let model =
        character::character(prepared, time, colour_texture.as_deref()).map_err(|message| {
            ExportError::Write {
                path: dir.join("meshes/character.gltf"),
                message,
            }
        })?;
    let has_character = model.is_some();
    if let Some(model) = model {
        w.write("meshes/character.bin", &model.bin)?;
        let text = serde_json::to_string_pretty(&model.gltf).expect("JSON of plain values");
        w.write("meshes/character.gltf", text.as_bytes())?;
        let text = serde_json::to_string_pretty(&model.joints).expect("JSON of plain values");
        w.write("meshes/joints.json", text.as_bytes())?;
    }

    // The shader in every GPU language, with its bindings (feature `gpu`).
    #[cfg(feature = "gpu")]
    for file in crate::gpu::translate::translate_all().map_err(|e| ExportError::Write {
        path: dir.join("shaders"),
        message: e.to_string(),
    })? {
        w.write(&format!("shaders/{}", file.path), &file.bytes)?;
    }

    let mut json = scene_json(prepared, time, layers, fin, Value::Object(maps));
    if has_character {
        json["files"]["character"] = json!("meshes/character.gltf");
        json["files"]["joints"] = json!("meshes/joints.json");
    }
    let text = serde_json::to_string_pretty(&json).expect("JSON of plain values");
    w.write("scene.json", text.as_bytes())?;
    Ok(ExportSummary { files: w.files })
}

/// The camera of a scene, as the renderer builds it.
pub fn camera(scene: &Scene) -> Camera {
    Camera {
        eye: scene.camera.eye,
        target: scene.camera.target,
        up: scene.camera.up,
        fov_y_deg: scene.camera.fov_y_deg,
        near: scene.camera.near,
        far: scene.camera.far,
    }
}

fn debug_name<T: std::fmt::Debug>(v: T) -> String {
    // Scene enums are written in the TOML's snake_case.
    let name = format!("{v:?}");
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

/// The scene with every default filled in, under the TOML's key names.
pub fn scene_values(s: &Scene) -> Value {
    let map_path =
        |p: &Option<PathBuf>| p.as_ref().map(|p| s.base_dir.join(p).display().to_string());
    json!({
        "seed": s.seed,
        "time": s.time,
        "image": { "width": s.image.width, "height": s.image.height, "background": s.image.background },
        "camera": {
            "eye": s.camera.eye, "target": s.camera.target, "up": s.camera.up,
            "fov_y_deg": s.camera.fov_y_deg, "near": s.camera.near, "far": s.camera.far,
        },
        "mesh": {
            "kind": debug_name(s.mesh.kind), "major_radius": s.mesh.major_radius,
            "minor_radius": s.mesh.minor_radius, "radius": s.mesh.radius, "height": s.mesh.height,
            "model_resolution": s.mesh.model_resolution,
            "path": s.mesh.path.as_ref().map(|p| s.base_dir.join(p).display().to_string()),
            "scale": s.mesh.scale,
        },
        "fur": {
            "number_of_strands": s.fur.number_of_strands,
            "strand_resolution": s.fur.strand_resolution,
            "circle_resolution": s.fur.circle_resolution,
            "number_of_shells": s.fur.number_of_shells,
            "texture_resolution": s.fur.texture_resolution,
            "model_difference": s.fur.model_difference,
            "fur_length": s.fur.fur_length(),
            "skin_inset": s.fur.skin_inset(),
            "shell_spacing": debug_name(s.fur.shell_spacing),
            "texture_repeat": s.fur.texture_repeat,
            "colour": s.fur.colour,
            "colour_variation": s.fur.colour_variation,
            "slope_deg": s.fur.slope_deg,
            "curl": s.fur.curl,
            "jitter": s.fur.jitter,
            "min_height": s.fur.min_height,
            "base_thickness": s.fur.base_thickness,
            "tip_thickness": s.fur.tip_thickness,
            "supersample": s.fur.supersample,
            "gaussian_sigma": s.fur.gaussian_sigma,
            "fins": s.fur.fins,
            "fin_windows": s.fur.fin_windows,
            "fin_height_scale": s.fur.fin_height_scale,
        },
        "shading": {
            "ambient": s.shading.ambient,
            "banks_exponent": s.shading.banks_exponent,
            "specular_exponent": s.shading.specular_exponent,
            "dampened_exponent": s.shading.dampened_exponent,
            "lighting": match s.shading.lighting {
                crate::scene::LightingSetting::Eq36 => "eq-3.6",
                crate::scene::LightingSetting::Eq35 => "eq-3.5",
            },
            "specular1_exponent": s.shading.specular1_exponent,
            "specular_tangents": s.shading.specular_tangents,
            "specular_lobes": debug_name(s.shading.specular_lobes),
            "ambient_term": debug_name(s.shading.ambient_term),
            "shadow_texel": debug_name(s.shading.shadow_texel),
            "tangent_shift": s.shading.tangent_shift,
            "shadow_divisor": s.shading.shadow_divisor,
            "weights": {
                "ambient": s.shading.weights.ambient, "diffuse": s.shading.weights.diffuse,
                "specular": s.shading.weights.specular, "dampened": s.shading.weights.dampened,
                "shadow": s.shading.weights.shadow,
            },
            "debug_view": debug_name(s.shading.debug_view),
        },
        "light": { "direction": s.light.direction, "colour": s.light.colour },
        "spots": s.spots.iter().map(|p| json!({
            "kind": debug_name(p.kind), "colour": p.colour, "centre": p.centre, "radii": p.radii,
            "inner": p.inner, "direction": p.direction, "position": p.position,
            "reach": p.reach, "exponent": p.exponent,
            "inner_threshold": p.inner_threshold, "outer_threshold": p.outer_threshold,
        })).collect::<Vec<_>>(),
        "stripes": s.stripes.iter().map(|p| json!({
            "kind": debug_name(p.kind), "colour": p.colour, "axis": p.axis(),
            "direction": p.direction(), "exponent": p.exponent(), "period": p.period(),
            "width": p.width(), "softness": p.softness(),
        })).collect::<Vec<_>>(),
        "wind": s.wind.as_ref().map(|w| json!({
            "direction": w.direction, "strength": w.strength, "frequency": w.frequency,
            "elasticity": w.elasticity, "max_bend": w.max_bend,
            "tangent_fraction": w.tangent_fraction, "keep_length": w.keep_length,
        })),
        "burn": s.burn.as_ref().map(|b| json!({
            "matches": b.matches, "start": b.start, "high_exponent": b.high_exponent,
            "low_exponent": b.low_exponent, "spread_duration": b.spread_duration,
        })),
        "maps": {
            "length": map_path(&s.maps.length), "density": map_path(&s.maps.density),
            "direction": map_path(&s.maps.direction), "colour": map_path(&s.maps.colour),
            "address": [debug_name(s.maps.address[0]), debug_name(s.maps.address[1])],
        },
        "lod": s.lod.as_ref().map(|l| json!({
            "pixels_per_shell": l.pixels_per_shell, "min_shells": l.min_shells,
            "fin_fade_pixels": l.fin_fade_pixels,
        })),
        "gravity": s.gravity.as_ref().map(|g| json!({
            "direction": g.direction, "strength": g.strength,
        })),
        "motion": s.motion.as_ref().map(|m| json!({
            "path": m.path, "frequency": m.frequency, "damping": m.damping,
            "response": m.response,
        })),
    })
}

fn spot_json(spot: &Spot) -> Value {
    match *spot {
        Spot::Ellipsoid {
            centre,
            radii,
            inner,
            colour,
        } => {
            json!({ "kind": "ellipsoid", "centre": centre, "radii": radii, "inner": inner, "colour": colour })
        }
        Spot::Light {
            direction,
            exponent,
            inner_threshold,
            outer_threshold,
            colour,
            ..
        } => json!({
            "kind": "light", "direction_unit": direction, "exponent": exponent,
            "inner_threshold": inner_threshold, "outer_threshold": outer_threshold, "colour": colour,
        }),
        Spot::PointLight {
            position,
            reach,
            exponent,
            inner_threshold,
            outer_threshold,
            colour,
            ..
        } => json!({
            "kind": "point_light", "position": position, "reach": reach, "exponent": exponent,
            "inner_threshold": inner_threshold, "outer_threshold": outer_threshold, "colour": colour,
        }),
        Spot::LightStripe {
            direction,
            exponent,
            period,
            width,
            softness,
            colour,
            ..
        } => json!({
            "kind": "light_stripe", "direction_unit": direction, "exponent": exponent,
            "period": period, "width": width, "softness": softness, "colour": colour,
        }),
        Spot::Stripe {
            axis,
            period,
            width,
            softness,
            colour,
        } => json!({
            "kind": "stripe", "axis_unit": axis, "period": period, "width": width,
            "softness": softness, "colour": colour,
        }),
    }
}

fn scene_json(
    prepared: &PreparedScene,
    time: f32,
    layers: Vec<Value>,
    fin: Value,
    maps: Value,
) -> Value {
    let s = prepared.scene();
    let cam = camera(s);
    let aspect = s.image.width as f32 / s.image.height as f32;
    let shade = prepared.shade_params_at(time);
    let wind = s.wind.as_ref().map(|w| {
        let (direction, force) = w.direction_and_force(time);
        json!({
            "direction_unit": direction,
            "force": force,
            "tangent_fraction": w.tangent_fraction,
            "keep_length": w.keep_length,
        })
    });
    let lod = prepared.level_of_detail_at(time).map(|l| {
        json!({
            "fur_pixels": l.fur_pixels,
            "level": l.level,
            "fin_fade": l.fin_fade,
        })
    });
    let map_settings = &s.maps;
    json!({
        "format": "pelage export 1",
        "time": time,
        "files": { "render": "oracle.png", "meshes": "meshes/fur.gltf" },
        "scene": scene_values(s),
        "camera": {
            "aspect": aspect,
            "view": cam.view().to_cols_array(),
            "projection": cam.projection(aspect).to_cols_array(),
            "view_projection": cam.view_projection(aspect).to_cols_array(),
        },
        "frame": {
            "light_direction_unit": s.light.direction.normalize_or_zero(),
            "light_colour": shade.light_colour,
            "eye": s.camera.eye,
            "skin_colour": s.fur.colour * 0.35,
            "texture_repeat": s.fur.texture_repeat,
            "tile_world_size": prepared.tile_world_size(),
            "wind": wind,
            "burn": shade.burn.as_ref().map(|b| json!({
                "exponent": b.exponent, "matches_unit": b.directions,
                "match_points": b.points.iter().map(|m| json!({ "position": m.position, "reach": m.reach })).collect::<Vec<_>>(),
            })),
            "spots": shade.spots.iter().map(spot_json).collect::<Vec<_>>(),
            "alpha_discard": ALPHA_DISCARD,
            "burn_threshold": crate::shading::BURN_THRESHOLD,
            "lean": prepared.shared_lean_at(time),
            "object_offset": prepared.object_offset_at(time),
            "level_of_detail": lod,
        },
        "layers": layers,
        "maps": {
            "files": maps,
            "address": [debug_name(map_settings.address[0]), debug_name(map_settings.address[1])],
            "sampler": "bilinear at level 0 in mesh uv, texel centres at (i + ½)/size, f32 weights",
        },
        "fin": fin,
        "pipeline": {
            "clear_colour": s.image.background.extend(1.0),
            "clear_depth": 1.0,
            "pass_order": ["skin", "fins", "shells"],
            "skin": { "depth_compare": "less", "depth_write": true, "blend": "replace", "cull": "back" },
            "shells": { "depth_compare": "less_equal", "depth_write": false, "blend": "alpha", "cull": "back", "order": "root to tip" },
            "fins": { "depth_compare": "less_equal", "depth_write": false, "blend": "alpha", "cull": "none" },
            "blend_alpha": "colour = src·a + dst·(1 − a); alpha = a + dst·(1 − a)",
            "front_face": "counter-clockwise in NDC (y up)",
            "shell_sampler": { "address_u": "wrap", "address_v": "wrap", "filter": "trilinear" },
            "level_of_detail": "λ = ½·log2(max(|ddx(uv)·size|², |ddy(uv)·size|²)) with pelage's log2 (log2_pelage in fur.wgsl), from coarse derivatives of the fur uv (before the wind offset), clamped to [0, levels − 1]",
            "shadow_lookups": "texel ⌊uv·size⌋ of mip level ⌊λ + 0.5⌋, alpha channel",
        },
        "conventions": {
            "v_direction": "texture row 0 (the top row of the PNG) is at v = 0, v grows down the image, as glTF, D3D, Metal, Vulkan and Godot address textures: upload the rows as they are; OpenGL also puts the first uploaded row at t = 0 (do not flip on load); Unity puts v = 0 at the bottom row of an imported texture: sample (u, 1 − v)",
            "tangent_frame": "TANGENT.xyz = T along +u, TANGENT.w = ±1 with B = w·(N × T) along +v (glTF's rule); tangent maps in the frame (x = T, y = B, z = N); pelage's own frames, not MikkTSpace: use the exported ones; where v is flipped (Unity), negate B and the tangent map's y",
            "alpha": "straight (not premultiplied) in every colour texture and in the blend",
            "blend_state": "colour = src·a + dst·(1 − a), alpha = a + dst·(1 − a): (SRC_ALPHA, ONE_MINUS_SRC_ALPHA) for colour, (ONE, ONE_MINUS_SRC_ALPHA) for alpha",
            "colour_space": "linear values everywhere: textures are read as byte/255 (UNORM, not sRGB formats), the target is written without sRGB encoding",
            "depth_range": "NDC z in [0, 1] (0 at the near plane), cleared to 1.0, LESS for the skin, LESS_EQUAL without writes for fins and shells; not reversed",
            "ndc_y": "NDC +y is the top row of the image",
            "engines": {
                "opengl": { "v": "as is", "depth": "glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)", "colour": "GL_RGBA8 textures, GL_FRAMEBUFFER_SRGB off", "readback": "glReadPixels gives the bottom row first: flip" },
                "vulkan": { "v": "as is", "depth": "native [0, 1]", "colour": "R8G8B8A8_UNORM", "clip_y": "the SPIR-V negates y: viewport of positive height" },
                "direct3d": { "v": "as is", "depth": "native [0, 1]", "colour": "DXGI_FORMAT_R8G8B8A8_UNORM" },
                "metal": { "v": "as is", "depth": "native [0, 1]", "colour": "MTLPixelFormatRGBA8Unorm" },
                "unity": { "v": "1 − v (or flip the textures)", "depth": "reversed Z on D3D/Vulkan/Metal: use Unity's own projection with the same camera", "colour": "textures with sRGB off, a linear RenderTexture for the comparison" },
                "unreal": { "v": "as is", "depth": "reversed Z: use Unreal's own projection with the same camera", "colour": "textures with sRGB off" },
                "godot": { "v": "as is", "depth": "reversed Z in Godot 4: use Godot's own projection with the same camera", "colour": "samplers without source_color; Godot encodes its output to sRGB: read back before, or decode" },
                "gltf": { "v": "as is", "colour": "glTF declares baseColorTexture sRGB: a viewer decodes the colour textures as sRGB, so its blend differs from pelage's" }
            },
            "clip_space": "0 ≤ z ≤ w (wgpu/Vulkan/D3D)",
            "output": "8-bit channel = ⌊255·clamp(c, 0, 1) + 0.5⌋, no colour-space conversion",
            "texel": "byte / 255, linear",
            "tangent_encoding": "unorm8(t·0.5 + 0.5), tangent space (x = u, y = v, z = away from skin)",
            "fragment_order": "burn (3.4), length cut (shells), wind and lean reverse lookup (3.3), colour and tangent maps, density (bands on shells, a factor on fins), lod_alpha, colour map tint, spots and stripes (3.2.4), charring, wind-bent tangent (3.3.1), lean-bent tangent, shell shadow (3.2.2; through the density bands), Kajiya–Kay (2.5, 2.7), the uncoloured last term (dampened specular, or eq. 3.5's (ψ_specularity1)^n), eq. 3.7",
            "vertex_order": "length = length map at the vertex (1 without); offset and strand height × length; displacement = wind_displacement (wind alone) or lean_displacement(wind direction·clamp(force) + lean + comb, …) with a lean; position + normal·offset + vertex_pull(displacement) (only the part along the normal: the sideways part is the texture lookup uv − wind_uv) + object offset",
        },
    })
}

/// A glTF 2.0 document (typed, `gltf-json`) and its binary buffer, built accessor by accessor.
#[derive(Default)]
struct GltfBuilder {
    root: gj::Root,
    bin: Vec<u8>,
}

/// `value` as a glTF `extras` object.
fn extras(value: &Value) -> gj::extras::Extras {
    serde_json::value::to_raw_value(value).ok()
}

fn checked<T>(value: T) -> gj::validation::Checked<T> {
    gj::validation::Checked::Valid(value)
}

impl GltfBuilder {
    /// The document with its one buffer, `uri` (beside the `.gltf`), and the buffer's bytes.
    fn finish(mut self, uri: &str) -> (gj::Root, Vec<u8>) {
        self.align();
        self.root.buffers.push(gj::Buffer {
            byte_length: self.bin.len().into(),
            name: None,
            uri: Some(uri.into()),
            extensions: None,
            extras: None,
        });
        (self.root, self.bin)
    }

    fn align(&mut self) {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
    }

    /// The bytes from `offset` to the end as a buffer view; `target` only for vertex attributes
    /// and indices (animation keys and inverse bind matrices have none).
    fn view(
        &mut self,
        offset: usize,
        target: Option<gj::buffer::Target>,
    ) -> gj::Index<gj::buffer::View> {
        self.root.push(gj::buffer::View {
            buffer: gj::Index::new(0),
            byte_length: (self.bin.len() - offset).into(),
            byte_offset: Some(offset.into()),
            byte_stride: None,
            name: None,
            target: target.map(checked),
            extensions: None,
            extras: None,
        })
    }

    /// Float vectors of `n` components (1 to 4, or 16 for a 4×4 matrix); returns the accessor. `bounds` adds min/max (required
    /// on POSITION).
    fn floats(&mut self, data: &[f32], n: usize, bounds: bool) -> gj::Index<gj::Accessor> {
        self.floats_in(data, n, bounds, Some(gj::buffer::Target::ArrayBuffer))
    }

    /// [`Self::floats`] in a buffer view with this `target`.
    fn floats_in(
        &mut self,
        data: &[f32],
        n: usize,
        bounds: bool,
        target: Option<gj::buffer::Target>,
    ) -> gj::Index<gj::Accessor> {
        self.align();
        let offset = self.bin.len();
        for v in data {
            self.bin.extend_from_slice(&v.to_le_bytes());
        }
        let view = self.view(offset, target);
        let kind = match n {
            1 => gj::accessor::Type::Scalar,
            2 => gj::accessor::Type::Vec2,
            3 => gj::accessor::Type::Vec3,
            4 => gj::accessor::Type::Vec4,
            _ => gj::accessor::Type::Mat4,
        };
        let (mut min, mut max) = (None, None);
        if bounds {
            let mut lo = vec![f32::INFINITY; n];
            let mut hi = vec![f32::NEG_INFINITY; n];
            for c in data.chunks_exact(n) {
                for k in 0..n {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
            min = Some(json!(lo));
            max = Some(json!(hi));
        }
        self.accessor(
            view,
            data.len() / n,
            gj::accessor::ComponentType::F32,
            kind,
            (min, max),
        )
    }

    /// An accessor of `count` tightly packed elements of `view`.
    fn accessor(
        &mut self,
        view: gj::Index<gj::buffer::View>,
        count: usize,
        component: gj::accessor::ComponentType,
        kind: gj::accessor::Type,
        (min, max): (Option<Value>, Option<Value>),
    ) -> gj::Index<gj::Accessor> {
        self.root.push(gj::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: count.into(),
            component_type: checked(gj::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: checked(kind),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn vec3s(&mut self, data: impl Iterator<Item = Vec3>, bounds: bool) -> gj::Index<gj::Accessor> {
        let flat: Vec<f32> = data.flat_map(|v| v.to_array()).collect();
        self.floats(&flat, 3, bounds)
    }

    fn vec2s(&mut self, data: impl Iterator<Item = Vec2>) -> gj::Index<gj::Accessor> {
        let flat: Vec<f32> = data.flat_map(|v| v.to_array()).collect();
        self.floats(&flat, 2, false)
    }

    fn indices(&mut self, triangles: &[[u32; 3]]) -> gj::Index<gj::Accessor> {
        self.align();
        let offset = self.bin.len();
        for i in triangles.iter().flatten() {
            self.bin.extend_from_slice(&i.to_le_bytes());
        }
        let view = self.view(offset, Some(gj::buffer::Target::ElementArrayBuffer));
        self.accessor(
            view,
            triangles.len() * 3,
            gj::accessor::ComponentType::U32,
            gj::accessor::Type::Scalar,
            (None, None),
        )
    }

    /// A texture of a PNG under the export folder (`file` relative to it), with `sampler`.
    fn texture(
        &mut self,
        file: &str,
        sampler: gj::Index<gj::texture::Sampler>,
    ) -> gj::Index<gj::Texture> {
        let image = self.root.push(gj::Image {
            buffer_view: None,
            mime_type: Some(gj::image::MimeType("image/png".into())),
            name: Some(file.to_string()),
            // fur.gltf lies in meshes/: the textures are one folder up.
            uri: Some(format!("../{file}")),
            extensions: None,
            extras: None,
        });
        self.root.push(gj::Texture {
            name: Some(file.to_string()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        })
    }

    fn sampler(&mut self, wrap_t: gj::texture::WrappingMode) -> gj::Index<gj::texture::Sampler> {
        self.root.push(gj::texture::Sampler {
            mag_filter: Some(checked(gj::texture::MagFilter::Linear)),
            min_filter: Some(checked(gj::texture::MinFilter::LinearMipmapLinear)),
            name: None,
            wrap_s: checked(gj::texture::WrappingMode::Repeat),
            wrap_t: checked(wrap_t),
            extensions: None,
            extras: None,
        })
    }

    /// A material of fur drawn with straight alpha blending, textured with `textures.colour`
    /// in `TEXCOORD_n`, the rest named in its extras.
    fn fur_material(
        &mut self,
        name: String,
        textures: &LayerTextures,
        tex_coord: u32,
        sampler: gj::Index<gj::texture::Sampler>,
        double_sided: bool,
        more: Value,
    ) -> gj::Index<gj::Material> {
        let colour = self.texture(&textures.colour.level0, sampler);
        let mut extra = json!({
            "pelage": "fur layer: draw with fur.wgsl (or its translation in shaders/); this material is the colour texture alone",
            "colour_mips": textures.colour.mips,
            "tangent_texture": textures.tangent.level0,
            "tangent_mips": textures.tangent.mips,
            "density_texture": textures.density.as_ref().map(|d| &d.level0),
            "density_mips": textures.density.as_ref().map(|d| &d.mips),
        });
        if let (Some(target), Value::Object(more)) = (extra.as_object_mut(), more) {
            target.extend(more);
        }
        self.root.push(gj::Material {
            alpha_mode: checked(gj::material::AlphaMode::Blend),
            double_sided,
            name: Some(name),
            pbr_metallic_roughness: gj::material::PbrMetallicRoughness {
                base_color_texture: Some(gj::texture::Info {
                    index: colour,
                    tex_coord,
                    extensions: None,
                    extras: None,
                }),
                metallic_factor: gj::material::StrengthFactor(0.0),
                roughness_factor: gj::material::StrengthFactor(1.0),
                ..Default::default()
            },
            extras: extras(&extra),
            ..Default::default()
        })
    }
}

fn primitive(
    attributes: &[(gj::mesh::Semantic, gj::Index<gj::Accessor>)],
    indices: gj::Index<gj::Accessor>,
    material: gj::Index<gj::Material>,
) -> gj::mesh::Primitive {
    gj::mesh::Primitive {
        attributes: attributes
            .iter()
            .map(|(semantic, index)| (checked(semantic.clone()), *index))
            .collect(),
        extensions: None,
        extras: None,
        indices: Some(indices),
        material: Some(material),
        mode: checked(gj::mesh::Mode::Triangles),
        targets: None,
    }
}

/// `meshes/fur.gltf`: one mesh and node per pass, in draw order (skin, fins, shells root to
/// tip), each with its material; see the [module docs](self).
fn gltf(
    prepared: &PreparedScene,
    time: f32,
    shells: &[LayerTextures],
    fin: Option<&LayerTextures>,
) -> (gj::Root, Vec<u8>) {
    use gj::mesh::Semantic;
    let mesh = prepared.mesh_at(time);
    let v = &mesh.vertices;
    let s = prepared.scene();
    let mut b = GltfBuilder::default();
    b.root.asset = gj::Asset {
        generator: Some("pelage export".into()),
        ..Default::default()
    };
    let mut skin_mesh = None;
    let mut fin_mesh = None;
    let new_mesh = |name: &str, primitive: gj::mesh::Primitive| gj::Mesh {
        name: Some(name.to_string()),
        primitives: vec![primitive],
        weights: None,
        extensions: None,
        extras: None,
    };
    let mut shell_meshes = Vec::new();
    if !v.is_empty() && !mesh.indices.is_empty() {
        let position = b.vec3s(v.iter().map(|v| v.position), true);
        let normal = b.vec3s(v.iter().map(|v| v.normal), false);
        let tangent: Vec<f32> = v
            .iter()
            .flat_map(|v| {
                let f = &v.frame;
                let w = if f.normal.cross(f.tangent).dot(f.binormal) < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                [f.tangent.x, f.tangent.y, f.tangent.z, w]
            })
            .collect();
        let tangent = b.floats(&tangent, 4, false);
        let uv = b.vec2s(v.iter().map(|v| v.uv));
        let repeat = Vec2::from(s.fur.texture_repeat);
        let fur_uv = b.vec2s(v.iter().map(|v| v.uv * repeat));
        let binormal = b.vec3s(v.iter().map(|v| v.frame.binormal), false);
        let dpdu = b.vec3s(v.iter().map(|v| v.dpdu), false);
        let dpdv = b.vec3s(v.iter().map(|v| v.dpdv), false);
        let indices = b.indices(&mesh.indices);
        let attributes = |position| {
            vec![
                (Semantic::Positions, position),
                (Semantic::Normals, normal),
                (Semantic::Tangents, tangent),
                (Semantic::TexCoords(0), uv),
                (Semantic::TexCoords(1), fur_uv),
                (Semantic::Extras("BINORMAL".into()), binormal),
                (Semantic::Extras("DPDU".into()), dpdu),
                (Semantic::Extras("DPDV".into()), dpdv),
            ]
        };
        let skin_colour = s.fur.colour * 0.35;
        let skin = b.root.push(gj::Material {
            name: Some("skin".into()),
            pbr_metallic_roughness: gj::material::PbrMetallicRoughness {
                base_color_factor: gj::material::PbrBaseColorFactor(
                    skin_colour.extend(1.0).to_array(),
                ),
                metallic_factor: gj::material::StrengthFactor(0.0),
                roughness_factor: gj::material::StrengthFactor(1.0),
                ..Default::default()
            },
            extras: extras(&json!({ "pelage": "skin: opaque, fur colour × 0.35, drawn first" })),
            ..Default::default()
        });
        skin_mesh = Some((
            "skin".to_string(),
            new_mesh("skin", primitive(&attributes(position), indices, skin)),
        ));
        let sampler = b.sampler(gj::texture::WrappingMode::Repeat);
        for (i, &offset) in prepared.shell_offsets().iter().enumerate() {
            let p = b.vec3s(v.iter().map(|v| v.position + v.normal * offset), true);
            let name = format!("shell_{i:02}");
            let material = match shells.get(i) {
                Some(textures) => b.fur_material(
                    name.clone(),
                    textures,
                    1,
                    sampler,
                    false,
                    json!({ "shell": i, "offset": offset }),
                ),
                None => skin,
            };
            shell_meshes.push((
                name.clone(),
                new_mesh(&name, primitive(&attributes(p), indices, material)),
            ));
        }
    }
    let (fin_vertices, fin_triangles) = prepared.fin_quads_at(time);
    if let Some(textures) = fin.filter(|_| !fin_triangles.is_empty()) {
        let position = b.vec3s(fin_vertices.iter().map(|(p, _)| *p), true);
        let normal = b.vec3s(fin_vertices.iter().map(|(_, f)| f.surface.normal), false);
        let uv = b.vec2s(fin_vertices.iter().map(|(_, f)| f.surface.uv));
        let light = b.vec3s(fin_vertices.iter().map(|(_, f)| f.lit.light), false);
        let eye = b.vec3s(fin_vertices.iter().map(|(_, f)| f.lit.eye), false);
        let shadow = b.vec2s(fin_vertices.iter().map(|(_, f)| f.surface.shadow));
        let fade: Vec<f32> = fin_vertices.iter().map(|(_, f)| f.surface.fade).collect();
        let fade = b.floats(&fade, 1, false);
        let object = b.vec3s(fin_vertices.iter().map(|(_, f)| f.surface.object), false);
        let mesh_uv = b.vec2s(fin_vertices.iter().map(|(_, f)| f.surface.mesh_uv));
        let length: Vec<f32> = fin_vertices.iter().map(|(_, f)| f.surface.length).collect();
        let length = b.floats(&length, 1, false);
        let indices = b.indices(&fin_triangles);
        let sampler = b.sampler(gj::texture::WrappingMode::ClampToEdge);
        let material = b.fur_material(
            "fins".into(),
            textures,
            0,
            sampler,
            true,
            json!({ "fin_height": prepared.fin_height() }),
        );
        let attributes = [
            (Semantic::Positions, position),
            (Semantic::Normals, normal),
            (Semantic::TexCoords(0), uv),
            (Semantic::Extras("LIGHT".into()), light),
            (Semantic::Extras("EYE".into()), eye),
            (Semantic::Extras("SHADOW".into()), shadow),
            (Semantic::Extras("FADE".into()), fade),
            (Semantic::Extras("OBJECT".into()), object),
            (Semantic::Extras("MESH_UV".into()), mesh_uv),
            (Semantic::Extras("LENGTH".into()), length),
        ];
        fin_mesh = Some((
            "fins".to_string(),
            new_mesh("fins", primitive(&attributes, indices, material)),
        ));
    }
    // Meshes skin, shells, fins (the order of earlier exports); nodes in draw order: skin, fins,
    // shells root to tip.
    let skin_index = skin_mesh.map(|(name, mesh)| (name, b.root.push(mesh)));
    let shell_indices: Vec<_> = shell_meshes
        .into_iter()
        .map(|(name, mesh)| (name, b.root.push(mesh)))
        .collect();
    let fin_index = fin_mesh.map(|(name, mesh)| (name, b.root.push(mesh)));
    let pushed = skin_index.into_iter().chain(fin_index).chain(shell_indices);
    let mut nodes = Vec::new();
    for (order, (name, mesh)) in pushed.enumerate() {
        nodes.push(b.root.push(gj::Node {
            mesh: Some(mesh),
            name: Some(name),
            extras: extras(&json!({ "draw_order": order })),
            ..Default::default()
        }));
    }
    let scene = b.root.push(gj::Scene {
        nodes,
        name: Some("pelage".into()),
        extensions: None,
        extras: extras(&json!({
            "pelage": "draw the nodes in their order (skin, fins, shells root to tip): depth test on, depth writes off after the skin, straight alpha blending"
        })),
    });
    b.root.scene = Some(scene);
    b.finish("fur.bin")
}
