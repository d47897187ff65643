//! pelage: a deterministic, pure-software CPU renderer for shell-and-fin fur.
//!
//! The output is an oracle for GPU ports: the same scene gives the same bytes for any thread
//! count, any tile size and any [`simd`] level (the instruction set chosen at run time), on every
//! run.
//!
//! # The pipeline
//!
//! The modules follow the path the data takes, and lower stages never import higher ones:
//!
//! ```text
//! scene ──▶ mesh ────────▶ fur bake ────▶ raster ─────▶ shading ──────▶ render ─────▶ output
//! TOML →    torus, OBJ,    strands →      clip, setup,  Kajiya–Kay,     one frame:    PNG, EXR,
//! typed     glTF; frames,  shell and fin  bin, tiles,   shadow, spots,  base mesh,    GIF
//! Scene     shells         textures       depth, blend  wind, burn      shells, fins
//! ```
//!
//! - [`scene`]: TOML text → a typed, range-checked [`scene::Scene`] (the input of everything).
//! - [`mesh`]: the base surface (procedural, OBJ, glTF), its tangent frames and shell offsets;
//!   [`camera`] gives the view and projection.
//! - [`fur`]: strands and cones, baked into the shell and fin textures (thesis 3.1).
//! - [`raster`]: clip, fixed-point setup, binning and tile rasterization; it knows nothing about
//!   fur.
//! - [`shading`]: the thesis's shading terms as small pure functions (thesis 3.2–3.4).
//! - [`render`]: [`render::PreparedScene`] assembles one frame: the base mesh, the shells layer
//!   by layer, the fins.
//! - [`output`]: writing PNG, EXR and GIF files atomically.
//!
//! Beside the pipeline: [`limits`] refuses scenes too large before anything is allocated,
//! [`export`] writes what a GPU port needs to draw the same frame, [`compare`] measures a GPU
//! frame against the oracle's, [`sweep`] runs the thesis's parameter experiments, [`input`],
//! [`font`] and [`robust`] serve them, and `gpu` (feature `gpu`) draws the same
//! frame with wgpu.
//!
//! # A whole frame
//!
//! ```
//! use pelage::glam::Vec3;
//! use pelage::render::PreparedScene;
//! use pelage::scene::Scene;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // A scene from TOML text: every key left out takes its default (`Scene::load(path)` reads a
//! // file, `Scene::embedded_default()` is the furred torus of thesis figure 3.1).
//! let text = r#"
//!     [image]
//!     width = 64
//!     height = 48
//!
//!     [mesh]
//!     kind = "sphere"
//!
//!     [fur]
//!     number_of_strands = 200
//!     number_of_shells = 8
//!     texture_resolution = 32
//! "#;
//! let mut scene = Scene::parse(text, "<example>", std::path::Path::new("."))?;
//! scene.camera.eye = Vec3::new(0.0, 1.0, 4.0); // glam, re-exported as `pelage::glam`
//!
//! let prepared = PreparedScene::new(&scene)?; // builds the mesh, bakes the fur
//! let frame = prepared.render_at(0.0, 64)?; // time 0 s, 64-pixel tiles
//! assert_eq!((frame.width, frame.height), (64, 48));
//! assert_eq!(frame.rgba8.len(), 64 * 48 * 4); // RGBA8, row 0 at the top
//!
//! // The same bytes with another tile size: the tile size is a speed choice, never an image one.
//! assert_eq!(prepared.render_at(0.0, 16)?.rgba8, frame.rgba8);
//!
//! let path = std::env::temp_dir().join("pelage-doc-example.png");
//! pelage::output::write_png(&path, frame.width, frame.height, &frame.rgba8)?;
//! # std::fs::remove_file(&path)?;
//! # Ok(())
//! # }
//! ```
#![warn(missing_docs)]

pub mod camera;
pub mod compare;
pub mod export;
pub mod font;
pub mod fur;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod input;
pub mod limits;
pub mod mesh;
pub mod output;
pub mod raster;
pub mod render;
pub mod robust;
pub mod scene;
pub mod shading;
pub mod simd;
pub mod sweep;

// The foreign crates whose types the public API takes or returns, so that callers use the
// versions pelage was built with (a different glam gives type mismatches).
/// glam, the vector and matrix types of every public signature (`Vec3`, `Vec4`, `Mat4`, …).
pub use glam;
/// image, whose `RgbaImage` the comparison, diagram and text functions take and return.
pub use image;
/// wgpu, whose adapter and texture types the GPU backend's API names (feature `gpu`).
#[cfg(feature = "gpu")]
pub use wgpu;
