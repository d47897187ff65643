//! The GPU backend (feature `gpu`; beside the pipeline: GPU backend): the same frame as
//! [`PreparedScene::render_at`], drawn by wgpu from the same baked data, headless (no window, no
//! surface).
//!
//! What is shared with the oracle and what is the GPU's own:
//! - **Shared data**: the mesh and its tangent frames, the shell and fin textures *with the
//!   oracle's mip chains* (uploaded level by level, not regenerated), the shell offsets, the
//!   shading parameters resolved at the instant ([`PreparedScene::shade_params_at`]), and the
//!   fin quads of the frame ([`PreparedScene::fin_quads_at`]: silhouette edges are found on the
//!   CPU, as in the thesis). Beyond the thesis: the surface maps ([`PreparedScene::maps`]) and
//!   each shell's density bands ([`PreparedScene::shell_density`]); the level of detail of the
//!   instant ([`PreparedScene::level_of_detail_at`]: layers of span 0 are not drawn, the others
//!   get their span as a uniform); the shared lean and the object's path offset
//!   ([`PreparedScene::shared_lean_at`], [`PreparedScene::object_offset_at`]).
//! - **Mirrored code**: `fur.wgsl` holds the vertex closures of the shell pass and the fragment
//!   closure `shade_fur` term by term, each WGSL function named after the Rust function it
//!   mirrors, with the thesis equation numbers in comments.
//! - **The GPU's own**: rasterization, clipping and perspective-correct interpolation; the
//!   sampler's trilinear filter (at the level of detail the shader computes from coarse
//!   derivatives, as the oracle does; the surface maps are read with the oracle's own f32
//!   bilinear weights instead, see `sample_map`); `pow`, `log2`, `sqrt`; blending. The frame is
//!   blended in f32 ([`Blending`]): by the blend unit into an `Rgba32Float` target where the
//!   adapter can blend one (lavapipe can), else by a shader through per-pixel fragment lists
//!   resolved in draw and primitive order (`lists.rs`; wgpu's GL backend on Mesa), else, as a
//!   last resort, by the blend unit into `Rgba16Float`. It is read back and rounded to 8 bits on
//!   the CPU with the oracle's rule `⌊255·clamp(c) + 0.5⌋`.
//!
//! Adapters: Vulkan, or OpenGL through EGL ([`Api::Gl`]). By default the CPU adapter (Mesa's
//! lavapipe, llvmpipe on GL) is preferred, so the comparison is the same on every machine; with
//! [`AdapterChoice::Any`] the first adapter wgpu's default choice gives (a hardware GPU where
//! there is one), with [`AdapterChoice::Index`] or [`AdapterChoice::Name`] one of [`adapters`].
//! Google's SwiftShader, a CPU Vulkan driver that shares no code with Mesa's, is the third
//! implementation the tests hold to the oracle (`--adapter swiftshader`, where
//! `VK_ICD_FILENAMES` names its ICD file; `.ci/swiftshader` installs it).

use crate::render::PreparedScene;
use crate::render::fragment::Spot;
use crate::scene::DebugView;
use glam::{Mat4, Vec3, Vec4};
use image::RgbaImage;
use wgpu::util::DeviceExt;

mod lists;
pub mod translate;

/// The WGSL source of the fur shaders (entry points `vs_skin`, `fs_skin`, `vs_shell`, `vs_fin`,
/// `fs_fur`).
pub const SHADER_SOURCE: &str = include_str!("fur.wgsl");

/// What can go wrong on the GPU.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter was found (on Debian: `apt-get install mesa-vulkan-drivers` gives lavapipe).
    #[error(
        "no Vulkan adapter found ({0}); install Mesa's software Vulkan driver (Debian: apt-get install mesa-vulkan-drivers) or a GPU driver"
    )]
    NoAdapter(String),
    /// No OpenGL adapter (EGL) was found.
    #[error(
        "no OpenGL adapter found ({0}); install Mesa's EGL and software GL driver (Debian: apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri)"
    )]
    NoGlAdapter(String),
    /// An `--api` or `--adapter` that does not exist here.
    #[error("{0}")]
    Choice(String),
    /// The device could not be created.
    #[error("cannot create the GPU device: {0}")]
    Device(String),
    /// A shader, pipeline or draw was refused (validation error).
    #[error("GPU validation: {0}")]
    Validation(String),
    /// The frame could not be read back.
    #[error("GPU readback: {0}")]
    Readback(String),
    /// The scene has no mesh to draw or a size the GPU cannot take.
    #[error("GPU: {0}")]
    Scene(String),
}

/// Which adapter to use.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum AdapterChoice {
    /// The CPU (fallback) adapter, lavapipe (llvmpipe on GL): the same results on every machine.
    /// Where the loader lists SwiftShader too, still lavapipe.
    #[default]
    Software,
    /// wgpu's default adapter (a hardware GPU where there is one).
    Any,
    /// The adapter at this index in [`adapters`]' list.
    Index(usize),
    /// The adapter whose name contains this text (case-insensitive); refused when several do.
    Name(String),
}

impl AdapterChoice {
    /// `--adapter`'s value: a number is an index in [`adapters`]' list, `software` and `any`
    /// the two defaults, anything else part of a name (`swiftshader`: Google's CPU Vulkan
    /// driver, "SwiftShader Device (Subzero)", where `VK_ICD_FILENAMES` names its ICD file).
    pub fn parse(text: &str) -> AdapterChoice {
        match text.trim() {
            t if t.eq_ignore_ascii_case("software") => AdapterChoice::Software,
            t if t.eq_ignore_ascii_case("any") => AdapterChoice::Any,
            t => match t.parse::<usize>() {
                Ok(i) => AdapterChoice::Index(i),
                Err(_) => AdapterChoice::Name(t.to_string()),
            },
        }
    }
}

/// The graphics API wgpu draws through.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Api {
    /// Vulkan (Mesa's lavapipe by default).
    #[default]
    Vulkan,
    /// OpenGL through EGL (Mesa's llvmpipe headless by default; wgpu opens a desktop OpenGL
    /// 3.3+ core context where EGL offers one, as Mesa does, else OpenGL ES 3). The shader is
    /// the same WGSL with the mip level count computed instead of queried
    /// ([`translate::without_level_query`]: GLSL ES has no level query) and the shadow lookups'
    /// levels loaded one at a time ([`translate::with_uniform_level_loads`]); the frame is
    /// blended through fragment lists where `Rgba32Float` cannot be blended ([`Blending`]).
    Gl,
}

impl Api {
    /// `--api`'s value: `vulkan` or `gl`.
    pub fn parse(text: &str) -> Result<Api, GpuError> {
        match text.trim().to_ascii_lowercase().as_str() {
            "vulkan" | "vk" => Ok(Api::Vulkan),
            "gl" | "gles" | "opengl" => Ok(Api::Gl),
            other => Err(GpuError::Choice(format!(
                "--api {other:?}: unknown API (vulkan or gl)"
            ))),
        }
    }

    fn backends(self) -> wgpu::Backends {
        match self {
            Api::Vulkan => wgpu::Backends::VULKAN,
            Api::Gl => wgpu::Backends::GL,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Api::Vulkan => "Vulkan",
            Api::Gl => "OpenGL (EGL)",
        }
    }
}

fn instance(api: Api) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = api.backends();
    wgpu::Instance::new(desc)
}

/// The adapters `api` offers on this machine, in wgpu's order (the indices of `--adapter N`).
pub fn adapters(api: Api) -> Vec<wgpu::AdapterInfo> {
    let instance = instance(api);
    pollster::block_on(instance.enumerate_adapters(api.backends()))
        .iter()
        .map(|a| a.get_info())
        .collect()
}

fn describe(list: &[wgpu::AdapterInfo]) -> String {
    if list.is_empty() {
        return "none found".into();
    }
    list.iter()
        .enumerate()
        .map(|(i, a)| format!("{i}: {}", a.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// What `--adapter swiftshader` adds when no adapter has that name.
const SWIFTSHADER_HINT: &str = "; SwiftShader is found through the Vulkan loader: point \
     VK_ICD_FILENAMES at its vk_swiftshader_icd.json (.ci/swiftshader installs it under \
     target/swiftshader/)";

/// Mesa's CPU adapter (lavapipe, "llvmpipe" in its name) where `api` lists several CPU
/// adapters (lavapipe and SwiftShader, `VK_ICD_FILENAMES` naming both): the default stays the
/// one whose figures the book gives, where wgpu's own fallback choice would take the first one
/// listed. `None` where there is one CPU adapter or none.
fn mesa_among_cpu_adapters(instance: &wgpu::Instance, api: Api) -> Option<wgpu::Adapter> {
    let mut cpu: Vec<wgpu::Adapter> =
        pollster::block_on(instance.enumerate_adapters(api.backends()))
            .into_iter()
            .filter(|a| a.get_info().device_type == wgpu::DeviceType::Cpu)
            .collect();
    if cpu.len() < 2 {
        return None;
    }
    let index = cpu
        .iter()
        .position(|a| a.get_info().name.to_lowercase().contains("llvmpipe"))
        .unwrap_or(0);
    Some(cpu.swap_remove(index))
}

/// Options of a GPU render.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// WGSL source replacing [`SHADER_SOURCE`] (tests change one term on purpose with it).
    pub shader: Option<String>,
    /// With [`Blending::FragmentLists`], the most fur fragments one draw may list; `None`: four
    /// per pixel, within the device's storage buffer limit. A draw that lists more makes
    /// [`GpuFrame::read_back`] fail, saying how many it had.
    pub list_capacity: Option<u32>,
    /// For a glTF model, upload the mesh posed on the CPU ([`PreparedScene::mesh_at`]) instead
    /// of skinning it in the vertex stage from the joint palette (the default; tests compare the
    /// two).
    pub pose_on_cpu: bool,
}

/// A wgpu device and queue, made once and reused for many frames.
pub struct GpuContext {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    target_format: wgpu::TextureFormat,
    blending: Blending,
    api: Api,
    /// Whether the vertex stage can read storage buffers (skinning from the palette).
    vertex_storage: bool,
}

/// How the fur's layers are blended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blending {
    /// By the blend unit, into an `Rgba32Float` target (lavapipe on Vulkan).
    Float32,
    /// By a shader, in f32, through per-pixel fragment lists resolved in draw and primitive
    /// order: where the adapter cannot blend `Rgba32Float` but can list fragments (wgpu's GL
    /// backend on Mesa's llvmpipe; `lists.rs` says how).
    FragmentLists,
    /// By the blend unit, into an `Rgba16Float` target: the last resort (half floats round the
    /// blended colour at every layer).
    Float16,
}

const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Floats per fin vertex: position and the `FinVertex` varyings of `fur.wgsl`.
const FIN_FLOATS: usize = 31;

/// Floats per posed mesh vertex: the `MeshVertex` of `fur.wgsl`.
const MESH_FLOATS: usize = 32;

/// 4-byte words per bind vertex of a skinned model: the `SkinnedVertex` of `fur.wgsl`.
const SKINNED_WORDS: usize = 31;

impl GpuContext {
    /// Opens a Vulkan adapter (see [`AdapterChoice`]) and creates a device on it.
    pub fn new(choice: AdapterChoice) -> Result<Self, GpuError> {
        Self::open(Api::Vulkan, &choice)
    }

    /// Opens an adapter of `api` (see [`AdapterChoice`]) and creates a device on it.
    pub fn open(api: Api, choice: &AdapterChoice) -> Result<Self, GpuError> {
        let instance = instance(api);
        let missing = |e: String| match api {
            Api::Vulkan => GpuError::NoAdapter(e),
            Api::Gl => GpuError::NoGlAdapter(e),
        };
        let adapter = match choice {
            AdapterChoice::Software | AdapterChoice::Any => {
                let mesa = match choice {
                    AdapterChoice::Software => mesa_among_cpu_adapters(&instance, api),
                    _ => None,
                };
                match mesa {
                    Some(adapter) => adapter,
                    None => {
                        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                            power_preference: wgpu::PowerPreference::HighPerformance,
                            force_fallback_adapter: *choice == AdapterChoice::Software,
                            compatible_surface: None,
                            ..Default::default()
                        }))
                        .map_err(|e| missing(e.to_string()))?
                    }
                }
            }
            AdapterChoice::Index(_) | AdapterChoice::Name(_) => {
                let mut all = pollster::block_on(instance.enumerate_adapters(api.backends()));
                let infos: Vec<wgpu::AdapterInfo> = all.iter().map(|a| a.get_info()).collect();
                if all.is_empty() {
                    return Err(missing("enumerating adapters found none".into()));
                }
                let index = match choice {
                    AdapterChoice::Index(i) if *i < all.len() => *i,
                    AdapterChoice::Index(i) => {
                        return Err(GpuError::Choice(format!(
                            "--adapter {i}: no such {} adapter (have {})",
                            api.name(),
                            describe(&infos)
                        )));
                    }
                    AdapterChoice::Name(name) => {
                        let wanted = name.to_lowercase();
                        let hits: Vec<usize> = (0..infos.len())
                            .filter(|&i| infos[i].name.to_lowercase().contains(&wanted))
                            .collect();
                        match hits[..] {
                            [i] => i,
                            [] => {
                                return Err(GpuError::Choice(format!(
                                    "--adapter {name:?}: no {} adapter has this name (have {}){}",
                                    api.name(),
                                    describe(&infos),
                                    if wanted == "swiftshader" && api == Api::Vulkan {
                                        SWIFTSHADER_HINT
                                    } else {
                                        ""
                                    }
                                )));
                            }
                            _ => {
                                return Err(GpuError::Choice(format!(
                                    "--adapter {name:?}: several {} adapters match (have {}); give the index",
                                    api.name(),
                                    describe(&infos)
                                )));
                            }
                        }
                    }
                    _ => 0,
                };
                all.swap_remove(index)
            }
        };
        let info = adapter.get_info();
        let (mut features, mut target_format) = target_choice(&adapter);
        let mut limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
        // A skinned model's palette is one more storage buffer, read by the vertex stage: where
        // the adapter cannot, its mesh is posed on the CPU.
        limits.max_storage_buffers_per_shader_stage = limits
            .max_storage_buffers_per_shader_stage
            .max(adapter.limits().max_storage_buffers_per_shader_stage);
        let vertex_storage = adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::VERTEX_STORAGE);
        let list_features =
            wgpu::Features::PRIMITIVE_INDEX | wgpu::Features::SHADER_EARLY_DEPTH_TEST;
        let list_flags =
            wgpu::DownlevelFlags::COMPUTE_SHADERS | wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE;
        let blending = if target_format == wgpu::TextureFormat::Rgba32Float {
            Blending::Float32
        } else if adapter.features().contains(list_features)
            && adapter
                .get_downlevel_capabilities()
                .flags
                .contains(list_flags)
        {
            features |= list_features;
            target_format = wgpu::TextureFormat::Rgba32Float;
            let offered = adapter.limits();
            limits.max_storage_buffer_binding_size = offered.max_storage_buffer_binding_size;
            limits.max_buffer_size = offered.max_buffer_size;
            Blending::FragmentLists
        } else {
            Blending::Float16
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("pelage"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(GpuContext {
            device,
            queue,
            info,
            target_format,
            blending,
            api,
            vertex_storage,
        })
    }

    /// Whether a glTF model is skinned in the vertex stage from its joint palette (the vertex
    /// stage can read storage buffers); otherwise its mesh is uploaded posed by the CPU.
    pub fn skins_in_vertex_stage(&self) -> bool {
        self.vertex_storage
    }

    /// The API drawn through.
    pub fn api(&self) -> Api {
        self.api
    }

    /// The adapter in use (name, driver, device type).
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The format the frame is blended in: `Rgba32Float` (by the blend unit, or by a shader
    /// through fragment lists), else `Rgba16Float`.
    pub fn target_format(&self) -> wgpu::TextureFormat {
        self.target_format
    }

    /// How the layers are blended.
    pub fn blending(&self) -> Blending {
        self.blending
    }

    /// Draws `prepared` at `time` (seconds): the skin, the shells root to tip, the fins.
    /// One call sets the frame up ([`GpuContext::prepare_frame`]), draws it once and reads it
    /// back; to draw the same frame many times, prepare it once.
    pub fn render(
        &self,
        prepared: &PreparedScene,
        time: f32,
        options: &GpuOptions,
    ) -> Result<RgbaImage, GpuError> {
        let frame = self.prepare_frame(prepared, time, options)?;
        frame.draw()?;
        frame.read_back()
    }

    /// Sets up the frame of `prepared` at `time` on the device: the textures, the mesh and the
    /// fin quads of that instant uploaded, the pipelines built, the render pass ready to be
    /// submitted by [`GpuFrame::draw`] as often as wanted (the same view each time: the fins
    /// are view dependent, so a frame at another instant or camera needs a new set-up).
    pub fn prepare_frame(
        &self,
        prepared: &PreparedScene,
        time: f32,
        options: &GpuOptions,
    ) -> Result<GpuFrame<'_>, GpuError> {
        let guard = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = self.prepare_inner(prepared, time, options);
        let scope = pollster::block_on(guard.pop());
        if let Some(e) = scope {
            return Err(GpuError::Validation(e.to_string()));
        }
        result
    }

    fn prepare_inner(
        &self,
        prepared: &PreparedScene,
        time: f32,
        options: &GpuOptions,
    ) -> Result<GpuFrame<'_>, GpuError> {
        let device = &self.device;
        let s = prepared.scene();
        let (width, height) = (s.image.width, s.image.height);
        // A glTF model is skinned in the vertex stage from the frame's palette (unless the
        // options ask for the CPU's pose); every other mesh is uploaded as it is drawn.
        let skinning = if options.pose_on_cpu || !self.vertex_storage {
            None
        } else {
            prepared.skinning_at(time)
        };
        let mesh = match &skinning {
            // The posed mesh only for its lags (a character with [motion]).
            Some(_) if !(prepared.poses() && s.motion.is_some()) => {
                std::borrow::Cow::Borrowed(prepared.mesh())
            }
            _ => prepared.mesh_at(time),
        };
        if mesh.vertices.is_empty() || mesh.indices.is_empty() {
            return Err(GpuError::Scene("the mesh has no triangles".into()));
        }
        // `motion.response` times each vertex's lag, as the oracle's lean adds it.
        let response = s.motion.as_ref().map_or(1.0, |m| m.response);
        let source = options.shader.as_deref().unwrap_or(SHADER_SOURCE);
        let source = match self.api {
            Api::Vulkan => source.to_string(),
            Api::Gl => {
                translate::with_uniform_level_loads(&translate::without_level_query(source)?)?
            }
        };
        let listed = self.blending == Blending::FragmentLists;
        let source = if listed {
            lists::with_fragment_lists(&source)?
        } else {
            source
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("fur.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });

        // Group 0: frame uniforms, spots, matches.
        let frame_bytes = frame_uniforms(prepared, time);
        let frame_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame"),
            contents: &frame_bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let shade = prepared.shade_params_at(time);
        let spots = storage_floats(shade.spots.iter().flat_map(spot_vec4s));
        // A match as one vec4: a unit direction with w = 0, or a position with w = its reach.
        let matches = storage_floats(shade.burn.iter().flat_map(|b| {
            let directions = b.directions.iter().map(|m| m.extend(0.0).to_array());
            let points = b
                .points
                .iter()
                .map(|m| m.position.extend(m.reach).to_array());
            directions.chain(points)
        }));
        let spot_buffer = self.storage(&spots, "spots");
        let match_buffer = self.storage(&matches, "matches");
        // The surface maps (read at level 0); a 1×1 placeholder for each absent one.
        let placeholder = self.placeholder();
        let surface = prepared.maps();
        let map_view = |map: &Option<crate::raster::Texture>| {
            map.as_ref()
                .map_or_else(|| placeholder.clone(), |m| self.upload(m))
        };
        let map_views = [
            map_view(&surface.length),
            map_view(&surface.density),
            map_view(&surface.direction),
            map_view(&surface.colour),
        ];
        // The joint palette of a skinned model (binding 7, the vertex stage only): a header
        // (skin inset, joint count) and each column-major matrix's four columns.
        let palette_buffer = skinning.as_ref().map(|k| {
            let mut floats = vec![s.fur.skin_inset(), k.palette.len() as f32, 0.0, 0.0];
            floats.extend(k.palette.iter().flatten());
            self.storage(&floats, "palette")
        });
        let mut frame_entries = vec![
            layout_entry(0, buffer_binding(wgpu::BufferBindingType::Uniform)),
            layout_entry(
                1,
                buffer_binding(wgpu::BufferBindingType::Storage { read_only: true }),
            ),
            layout_entry(
                2,
                buffer_binding(wgpu::BufferBindingType::Storage { read_only: true }),
            ),
            layout_entry(3, texture_binding()),
            layout_entry(4, texture_binding()),
            layout_entry(5, texture_binding()),
            layout_entry(6, texture_binding()),
        ];
        let mut frame_bindings = vec![
            bind(0, &frame_buffer),
            bind(1, &spot_buffer),
            bind(2, &match_buffer),
            bind_view(3, &map_views[0]),
            bind_view(4, &map_views[1]),
            bind_view(5, &map_views[2]),
            bind_view(6, &map_views[3]),
        ];
        if let Some(buffer) = &palette_buffer {
            frame_entries.push(wgpu::BindGroupLayoutEntry {
                visibility: wgpu::ShaderStages::VERTEX,
                ..layout_entry(
                    7,
                    buffer_binding(wgpu::BufferBindingType::Storage { read_only: true }),
                )
            });
            frame_bindings.push(bind(7, buffer));
        }
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &frame_entries,
        });
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &frame_layout,
            entries: &frame_bindings,
        });

        // Group 1: layer uniforms, colour map, tangent map, sampler, density bands.
        let layer_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("layer"),
            entries: &[
                layout_entry(0, buffer_binding(wgpu::BufferBindingType::Uniform)),
                layout_entry(1, texture_binding()),
                layout_entry(2, texture_binding()),
                layout_entry(
                    3,
                    wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                ),
                layout_entry(4, texture_binding()),
            ],
        });
        let sampler = |clamp_v: bool| {
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("fur"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: if clamp_v {
                    wgpu::AddressMode::ClampToEdge
                } else {
                    wgpu::AddressMode::Repeat
                },
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                ..Default::default()
            })
        };
        let shell_sampler = sampler(false);
        let fin_sampler = sampler(true);
        // `layer`: the `LayerUniforms` of fur.wgsl, [index, max_shell, lookups,
        // height_fraction, offset, clamp_v, lod_span, shell] (floats as their bits).
        let layer_group = |layer: [u32; 8],
                           colour: &wgpu::TextureView,
                           tangent: &wgpu::TextureView,
                           sampler: &wgpu::Sampler,
                           bands: &wgpu::TextureView| {
            let bytes: Vec<u8> = layer.iter().flat_map(|v| v.to_le_bytes()).collect();
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("layer"),
                contents: &bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("layer"),
                layout: &layer_layout,
                entries: &[
                    bind(0, &buffer),
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(colour),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(tangent),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::Sampler(sampler),
                    },
                    bind_view(4, bands),
                ],
            })
        };

        // Shells: under level of detail only the layers with a span > 0 are drawn, their
        // alpha compensated for the layers they stand for.
        let n = prepared.shell_count();
        let lod = prepared.level_of_detail_at(time);
        let spans: Vec<f32> = (0..n)
            .map(|i| lod.as_ref().map_or(1.0, |l| l.spans[i]))
            .collect();
        let mut shell_views = Vec::with_capacity(n);
        for i in 0..n {
            let (colour, tangent) = prepared.shell_textures(i).expect("layer in range");
            shell_views.push((self.upload(colour), self.upload(tangent)));
        }
        let max_shell = s.fur.number_of_shells - 1;
        let skin_group = layer_group(
            [0, max_shell, 0, 0, 0, 0, 0, 0],
            &shell_views[0].0,
            &shell_views[0].1,
            &shell_sampler,
            &placeholder,
        );
        let shell_groups: Vec<wgpu::BindGroup> = (0..n)
            .filter(|&i| spans[i] > 0.0)
            .map(|i| {
                let bands = prepared
                    .shell_density(i)
                    .map_or_else(|| placeholder.clone(), |b| self.upload(b));
                let p = prepared.shell_layer_params(i as u32);
                layer_group(
                    [
                        p.index,
                        p.max_shell,
                        p.lookups,
                        p.height_fraction.to_bits(),
                        prepared.shell_offsets()[i].to_bits(),
                        0,
                        spans[i].to_bits(),
                        1,
                    ],
                    &shell_views[i].0,
                    &shell_views[i].1,
                    &shell_sampler,
                    &bands,
                )
            })
            .collect();

        // Vertex data: the mesh (skin and shells), the fin quads of this frame. A skinned
        // model's bind vertices with their influences (joint indices as u32 bits), the rest
        // pose's fields and the frame's lag; any other mesh as drawn.
        let mesh_floats: Vec<f32> = match &skinning {
            Some(k) => k
                .bind
                .vertices
                .iter()
                .zip(&k.influences)
                .zip(&mesh.vertices)
                .flat_map(|((b, i), v)| {
                    let mut out = Vec::with_capacity(SKINNED_WORDS);
                    out.extend(b.position.to_array());
                    out.extend(b.normal.to_array());
                    out.extend(b.uv.to_array());
                    out.extend(b.dpdu.to_array());
                    out.extend(b.dpdv.to_array());
                    out.extend(i.joints.map(f32::from_bits));
                    out.extend(i.weights);
                    out.extend(v.rest_position.to_array());
                    out.extend(v.rest_normal.to_array());
                    out.extend((v.lag * response).to_array());
                    out
                })
                .collect(),
            None => mesh
                .vertices
                .iter()
                .flat_map(|v| {
                    let mut out = Vec::with_capacity(MESH_FLOATS);
                    out.extend(v.position.to_array());
                    out.extend(v.normal.to_array());
                    out.extend(v.uv.to_array());
                    out.extend(v.frame.tangent.to_array());
                    out.extend(v.frame.binormal.to_array());
                    out.extend(v.frame.normal.to_array());
                    out.extend(v.dpdu.to_array());
                    out.extend(v.dpdv.to_array());
                    out.extend(v.rest_position.to_array());
                    out.extend(v.rest_normal.to_array());
                    out.extend((v.lag * response).to_array());
                    out
                })
                .collect(),
        };
        let mesh_buffer = self.vertex_buffer(&mesh_floats, "mesh");
        let index_buffer = self.index_buffer(&mesh.indices, "mesh indices");
        let mesh_index_count = (mesh.indices.len() * 3) as u32;
        // Fins; level of detail fades them (in the quads' fade) and leaves them out at 0.
        let fins_drawn = lod.as_ref().is_none_or(|l| l.fin_fade != 0.0);
        let fin = match prepared.fin_textures().filter(|_| fins_drawn) {
            Some((colour, tangent)) => {
                let (quads, triangles) = prepared.fin_quads_at(time);
                if triangles.is_empty() {
                    None
                } else {
                    let floats: Vec<f32> = quads
                        .iter()
                        .flat_map(|(p, f)| {
                            let mut out = Vec::with_capacity(FIN_FLOATS);
                            out.extend(p.to_array());
                            out.extend(f.surface.uv.to_array());
                            out.extend(f.lit.light.to_array());
                            out.extend(f.lit.eye.to_array());
                            out.extend(f.surface.shadow.to_array());
                            out.push(f.surface.fade);
                            out.extend(f.surface.object.to_array());
                            out.extend(f.surface.normal.to_array());
                            out.extend(f.surface.wind_uv.to_array());
                            out.extend(f.lit.wind.to_array());
                            out.extend(f.surface.mesh_uv.to_array());
                            out.push(f.surface.length);
                            out.extend(f.lit.lean.to_array());
                            out
                        })
                        .collect();
                    let (colour, tangent) = (self.upload(colour), self.upload(tangent));
                    let fin_layer = prepared.fin_layer_params();
                    let group = layer_group(
                        [
                            fin_layer.index,
                            fin_layer.max_shell,
                            fin_layer.lookups,
                            fin_layer.height_fraction.to_bits(),
                            0,
                            1,
                            1.0f32.to_bits(),
                            0,
                        ],
                        &colour,
                        &tangent,
                        &fin_sampler,
                        &placeholder,
                    );
                    Some((
                        self.vertex_buffer(&floats, "fins"),
                        self.index_buffer(&triangles, "fin indices"),
                        (triangles.len() * 3) as u32,
                        group,
                    ))
                }
            }
            None => None,
        };

        // Pipelines (with the fragment lists, group 2 holds them).
        let list_layout = listed.then(|| lists::Lists::fur_layout(device));
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("fur"),
            bind_group_layouts: &[
                Some(&frame_layout),
                Some(&layer_layout),
                list_layout.as_ref(),
            ][..if listed { 3 } else { 2 }],
            immediate_size: 0,
        });
        let mesh_attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x3,
            4 => Float32x3, 5 => Float32x3, 6 => Float32x3, 7 => Float32x3,
            8 => Float32x3, 9 => Float32x3, 10 => Float32x3
        ];
        let skinned_attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x3,
            4 => Float32x3, 5 => Uint32x4, 6 => Float32x4, 7 => Float32x3,
            8 => Float32x3, 9 => Float32x3
        ];
        let fin_attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x2, 2 => Float32x3, 3 => Float32x3, 4 => Float32x2,
            5 => Float32, 6 => Float32x3, 7 => Float32x3, 8 => Float32x2, 9 => Float32x3,
            10 => Float32x2, 11 => Float32, 12 => Float32x3
        ];
        let mesh_vertex = match &skinning {
            Some(_) => wgpu::VertexBufferLayout {
                array_stride: (SKINNED_WORDS * 4) as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &skinned_attributes,
            },
            None => wgpu::VertexBufferLayout {
                array_stride: (MESH_FLOATS * 4) as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &mesh_attributes,
            },
        };
        let (vs_skin, vs_shell) = match &skinning {
            Some(_) => ("vs_skin_skinned", "vs_shell_skinned"),
            None => ("vs_skin", "vs_shell"),
        };
        let fin_vertex = wgpu::VertexBufferLayout {
            array_stride: (FIN_FLOATS * 4) as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &fin_attributes,
        };
        let alpha_blend = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::SrcAlpha,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
        };
        // `target`: the colour target's format and blend; `None` for a fur draw into the
        // fragment lists (no colour target).
        let pipeline = |vs: &str,
                        fs: &str,
                        vertex: &wgpu::VertexBufferLayout,
                        target: Option<(wgpu::TextureFormat, Option<wgpu::BlendState>)>,
                        depth_compare: wgpu::CompareFunction,
                        depth_write: bool,
                        cull: Option<wgpu::Face>| {
            let targets: Vec<Option<wgpu::ColorTargetState>> = target
                .map(|(format, blend)| wgpu::ColorTargetState {
                    format,
                    blend,
                    write_mask: wgpu::ColorWrites::ALL,
                })
                .into_iter()
                .map(Some)
                .collect();
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(vs),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: &[Some(vertex.clone())],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: cull,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(depth_compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let (skin_fs, skin_target, fur_fs, fur_target) = if listed {
            (
                "fs_skin_bits",
                (lists::SKIN_FORMAT, None),
                "fs_fur_listed",
                None,
            )
        } else {
            (
                "fs_skin",
                (self.target_format, None),
                "fs_fur",
                Some((self.target_format, Some(alpha_blend))),
            )
        };
        let skin_pipeline = pipeline(
            vs_skin,
            skin_fs,
            &mesh_vertex,
            Some(skin_target),
            wgpu::CompareFunction::Less,
            true,
            Some(wgpu::Face::Back),
        );
        let shell_pipeline = pipeline(
            vs_shell,
            fur_fs,
            &mesh_vertex,
            fur_target,
            wgpu::CompareFunction::LessEqual,
            false,
            Some(wgpu::Face::Back),
        );
        let fin_pipeline = pipeline(
            "vs_fin",
            fur_fs,
            &fin_vertex,
            fur_target,
            wgpu::CompareFunction::LessEqual,
            false,
            None,
        );

        // Targets.
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let target = match &list_layout {
            Some(layout) => FrameTarget::Lists(lists::Lists::new(
                device,
                layout,
                width,
                height,
                options.list_capacity,
            )),
            None => {
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("colour"),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: self.target_format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                });
                let view = texture.create_view(&Default::default());
                FrameTarget::Blended(texture, view)
            }
        };
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let depth_view = depth.create_view(&Default::default());
        let bg = s.image.background;
        Ok(GpuFrame {
            context: self,
            width,
            height,
            background: wgpu::Color {
                r: f64::from(bg.x),
                g: f64::from(bg.y),
                b: f64::from(bg.z),
                a: 1.0,
            },
            target,
            depth_view,
            frame_group,
            mesh_buffer,
            index_buffer,
            mesh_index_count,
            skin_pipeline,
            skin_group,
            fin_pipeline,
            fin,
            shell_pipeline,
            shell_groups,
        })
    }

    fn storage(&self, floats: &[f32], label: &str) -> wgpu::Buffer {
        let bytes: Vec<u8> = floats.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
    }

    fn vertex_buffer(&self, floats: &[f32], label: &str) -> wgpu::Buffer {
        let bytes: Vec<u8> = floats.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: wgpu::BufferUsages::VERTEX,
            })
    }

    fn index_buffer(&self, triangles: &[[u32; 3]], label: &str) -> wgpu::Buffer {
        let bytes: Vec<u8> = triangles
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: wgpu::BufferUsages::INDEX,
            })
    }

    /// A 1×1 transparent texture bound where a layer or frame has no map.
    fn placeholder(&self) -> wgpu::TextureView {
        let texel =
            crate::raster::Texture::from_rgba8(1, 1, vec![[0; 4]]).expect("a 1×1 texture is valid");
        self.upload(&texel)
    }

    /// Uploads a texture with the oracle's own mip chain.
    fn upload(&self, texture: &crate::raster::Texture) -> wgpu::TextureView {
        let levels = texture.level_count() as u32;
        let gpu = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("fur texture"),
            size: wgpu::Extent3d {
                width: texture.width(),
                height: texture.height(),
                depth_or_array_layers: 1,
            },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for k in 0..levels {
            let level = texture.level(k as usize).expect("level in range");
            let bytes: Vec<u8> = level.texels().iter().flatten().copied().collect();
            self.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &gpu,
                    mip_level: k,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                &bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(level.width() * 4),
                    rows_per_image: Some(level.height()),
                },
                wgpu::Extent3d {
                    width: level.width(),
                    height: level.height(),
                    depth_or_array_layers: 1,
                },
            );
        }
        gpu.create_view(&Default::default())
    }
}

/// The colour target and the device features it needs: `Rgba32Float` where the adapter can
/// blend it, else `Rgba16Float`.
///
/// Vulkan (lavapipe) offers `FLOAT32_BLENDABLE`. wgpu's GL backend never offers that feature;
/// it reports each format's abilities itself (`TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`,
/// always offered on GL), and calls `Rgba32Float` renderable and blendable only when the
/// context lists `GL_EXT_color_buffer_float` or `GL_ARB_color_buffer_float`. On EGL, wgpu
/// opens a desktop OpenGL 3.3+ core context whenever EGL offers desktop GL (Mesa does: 4.5
/// core on llvmpipe), and a core profile lists neither extension (float colour buffers are
/// core since OpenGL 3.0; Mesa lists the ARB one in compatibility profiles only), so through
/// wgpu 30 `Rgba32Float` is not even renderable on Mesa's GL. The check stays general: a
/// driver whose GL context lists the extension gets the 32-bit target here.
fn target_choice(adapter: &wgpu::Adapter) -> (wgpu::Features, wgpu::TextureFormat) {
    let float32 = wgpu::TextureFormat::Rgba32Float;
    let offered = adapter.features();
    if offered.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        return (wgpu::Features::FLOAT32_BLENDABLE, float32);
    }
    let specific = wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
    let reported = adapter.get_texture_format_features(float32);
    if offered.contains(specific)
        && reported
            .flags
            .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE)
        && reported
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC)
    {
        return (specific, float32);
    }
    (wgpu::Features::empty(), wgpu::TextureFormat::Rgba16Float)
}

/// Waits for `submission` (all work when `None`). wgpu's GL backend turns "no timeout" into
/// `glClientWaitSync`'s largest, about 2.1 s, which a large frame on llvmpipe can pass: a wait
/// that times out is repeated (up to ten minutes in all) instead of failing.
fn wait(device: &wgpu::Device, submission: Option<wgpu::SubmissionIndex>) -> Result<(), GpuError> {
    for _ in 0..300 {
        match device.poll(wgpu::PollType::Wait {
            submission_index: submission.clone(),
            timeout: None,
        }) {
            Ok(_) => return Ok(()),
            Err(wgpu::PollError::Timeout) => continue,
            Err(e) => return Err(GpuError::Readback(e.to_string())),
        }
    }
    Err(GpuError::Readback(
        "the GPU did not finish the frame in ten minutes".into(),
    ))
}

/// Where a frame is blended: a colour target (and its view) blended by the blend unit, or the
/// fragment lists.
enum FrameTarget {
    Blended(wgpu::Texture, wgpu::TextureView),
    Lists(lists::Lists),
}

/// A fin pass of a frame: vertices, indices, index count, layer bind group.
type FinDraw = (wgpu::Buffer, wgpu::Buffer, u32, wgpu::BindGroup);

/// One frame set up on the device by [`GpuContext::prepare_frame`]: everything uploaded once,
/// the render pass submitted again by each [`GpuFrame::draw`]. Its targets are cleared at the
/// start of every pass, so every draw gives the same image.
pub struct GpuFrame<'a> {
    context: &'a GpuContext,
    width: u32,
    height: u32,
    background: wgpu::Color,
    target: FrameTarget,
    depth_view: wgpu::TextureView,
    frame_group: wgpu::BindGroup,
    mesh_buffer: wgpu::Buffer,
    index_buffer: wgpu::Buffer,
    mesh_index_count: u32,
    skin_pipeline: wgpu::RenderPipeline,
    skin_group: wgpu::BindGroup,
    fin_pipeline: wgpu::RenderPipeline,
    fin: Option<FinDraw>,
    shell_pipeline: wgpu::RenderPipeline,
    shell_groups: Vec<wgpu::BindGroup>,
}

impl GpuFrame<'_> {
    /// The frame's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Submits the frame's render pass (the skin, the fins, the shells root to tip) and waits
    /// until the device has finished it. Nothing is uploaded or read back: this is the frame
    /// time of a renderer whose data already lives on the device.
    pub fn draw(&self) -> Result<(), GpuError> {
        let device = &self.context.device;
        let guard = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = device.create_command_encoder(&Default::default());
        self.encode_pass(&mut encoder);
        let index = self.context.queue.submit([encoder.finish()]);
        let waited = wait(device, Some(index));
        if let Some(e) = pollster::block_on(guard.pop()) {
            return Err(GpuError::Validation(e.to_string()));
        }
        waited.map(|_| ())
    }

    /// Copies the last drawn frame to the CPU and rounds it to 8 bits with the oracle's rule.
    pub fn read_back(&self) -> Result<RgbaImage, GpuError> {
        let device = &self.context.device;
        let guard = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = self.read_back_inner();
        if let Some(e) = pollster::block_on(guard.pop()) {
            return Err(GpuError::Validation(e.to_string()));
        }
        result
    }

    fn encode_pass(&self, encoder: &mut wgpu::CommandEncoder) {
        let target_view = match &self.target {
            FrameTarget::Blended(_, view) => view,
            FrameTarget::Lists(lists) => return self.encode_lists(encoder, lists),
        };
        let mut pass = self.begin_with_skin(encoder, "fur", target_view, self.background, None);
        // Fins at the silhouette, before the shells (as the oracle draws them).
        if let Some((vertices, indices, count, group)) = &self.fin {
            pass.set_pipeline(&self.fin_pipeline);
            pass.set_bind_group(1, group, &[]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..*count, 0, 0..1);
            pass.set_vertex_buffer(0, self.mesh_buffer.slice(..));
            pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        }
        // Shells, root to tip (thesis 3.1.4).
        pass.set_pipeline(&self.shell_pipeline);
        for group in &self.shell_groups {
            pass.set_bind_group(1, group, &[]);
            pass.draw_indexed(0..self.mesh_index_count, 0, 0..1);
        }
    }

    /// Begins a render pass that clears `view` to `clear` and the depth to 1, and draws the
    /// opaque skin in it (writing depth); `lists_group` is the fragment lists' bind group 2,
    /// where the pipelines have one.
    fn begin_with_skin<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        view: &wgpu::TextureView,
        clear: wgpu::Color,
        lists_group: Option<&wgpu::BindGroup>,
    ) -> wgpu::RenderPass<'e> {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.frame_group, &[]);
        if let Some(group) = lists_group {
            pass.set_bind_group(2, group, &[]);
        }
        pass.set_vertex_buffer(0, self.mesh_buffer.slice(..));
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        // The skin: opaque, writes depth.
        pass.set_pipeline(&self.skin_pipeline);
        pass.set_bind_group(1, &self.skin_group, &[]);
        pass.draw_indexed(0..self.mesh_index_count, 0, 0..1);
        pass
    }

    /// The frame through the fragment lists (`lists.rs`): the skin into its target of bits,
    /// then each fur draw in its own pass, its lists resolved after it.
    fn encode_lists(&self, encoder: &mut wgpu::CommandEncoder, lists: &lists::Lists) {
        // The background's f32 bits as the integer clear value of the Rgba32Uint target
        // (exact: a u32 fits an f64).
        let bits = |c: f64| f64::from((c as f32).to_bits());
        let bg = self.background;
        let clear = wgpu::Color {
            r: bits(bg.r),
            g: bits(bg.g),
            b: bits(bg.b),
            a: bits(bg.a),
        };
        drop(self.begin_with_skin(
            encoder,
            "skin",
            &lists.skin_view,
            clear,
            Some(&lists.fur_group),
        ));
        lists.start(encoder);
        lists.clear_all(encoder);
        // A fur draw: depth tested against the skin (not written), no colour target.
        let fur_pass = |encoder: &mut wgpu::CommandEncoder,
                        pipeline: &wgpu::RenderPipeline,
                        group: &wgpu::BindGroup,
                        vertices: &wgpu::Buffer,
                        indices: &wgpu::Buffer,
                        count: u32| {
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("fur"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &self.depth_view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &self.frame_group, &[]);
                pass.set_bind_group(1, group, &[]);
                pass.set_bind_group(2, &lists.fur_group, &[]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..count, 0, 0..1);
            }
            lists.resolve(encoder);
        };
        // Fins at the silhouette, before the shells (as the oracle draws them).
        if let Some((vertices, indices, count, group)) = &self.fin {
            fur_pass(
                encoder,
                &self.fin_pipeline,
                group,
                vertices,
                indices,
                *count,
            );
        }
        // Shells, root to tip (thesis 3.1.4).
        for group in &self.shell_groups {
            fur_pass(
                encoder,
                &self.shell_pipeline,
                group,
                &self.mesh_buffer,
                &self.index_buffer,
                self.mesh_index_count,
            );
        }
    }

    /// Maps `buffer` (`COPY_DST | MAP_READ`) after the copies in `encoder` and returns its bytes.
    fn map_read(
        &self,
        encoder: wgpu::CommandEncoder,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<u8>, GpuError> {
        let device = &self.context.device;
        self.context.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        wait(device, None)?;
        receiver
            .recv()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let bytes = slice
            .get_mapped_range()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .to_vec();
        buffer.unmap();
        Ok(bytes)
    }

    /// The frame of the fragment lists: its f32 colours, and the check that no draw listed
    /// more fragments than the lists hold.
    fn read_back_lists(&self, lists: &lists::Lists) -> Result<RgbaImage, GpuError> {
        let device = &self.context.device;
        let colour_bytes = u64::from(self.width) * u64::from(self.height) * 16;
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: colour_bytes + 8,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&lists.frame_colour, 0, &readback, 0, colour_bytes);
        encoder.copy_buffer_to_buffer(&lists.heads, 0, &readback, colour_bytes, 8);
        let data = self.map_read(encoder, &readback)?;
        let word =
            |at: usize| u32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]);
        let wanted = word(colour_bytes as usize + 4);
        if wanted > 0 {
            return Err(GpuError::Scene(format!(
                "one draw has {wanted} fur fragments, more than the {} the fragment lists hold at {}×{} (the device's storage buffer limit); render smaller",
                lists.capacity, self.width, self.height
            )));
        }
        let rgba: Vec<u8> = data[..colour_bytes as usize]
            .chunks_exact(4)
            .map(|c| to_unorm8(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
            .collect();
        RgbaImage::from_raw(self.width, self.height, rgba)
            .ok_or_else(|| GpuError::Readback("short image".into()))
    }

    fn read_back_inner(&self) -> Result<RgbaImage, GpuError> {
        let target = match &self.target {
            FrameTarget::Blended(texture, _) => texture,
            FrameTarget::Lists(lists) => return self.read_back_lists(lists),
        };
        let device = &self.context.device;
        let (width, height) = (self.width, self.height);
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        let texel_bytes = if self.context.target_format == wgpu::TextureFormat::Rgba32Float {
            16
        } else {
            8
        };
        let row = (width * texel_bytes).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(row) * u64::from(height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: target,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(height),
                },
            },
            size,
        );
        let data = self.map_read(encoder, &readback)?;
        let mut rgba = Vec::with_capacity(width as usize * height as usize * 4);
        for y in 0..height as usize {
            let line = &data[y * row as usize..][..(width * texel_bytes) as usize];
            if texel_bytes == 16 {
                for c in line.chunks_exact(4) {
                    rgba.push(to_unorm8(f32::from_le_bytes([c[0], c[1], c[2], c[3]])));
                }
            } else {
                for c in line.chunks_exact(2) {
                    rgba.push(to_unorm8(half_to_f32(u16::from_le_bytes([c[0], c[1]]))));
                }
            }
        }
        RgbaImage::from_raw(width, height, rgba)
            .ok_or_else(|| GpuError::Readback("short image".into()))
    }
}

/// Draws `prepared` at `time` on a new [`GpuContext`] with the default (software) adapter.
/// For many frames, make one context and call [`GpuContext::render`].
pub fn render(prepared: &PreparedScene, time: f32) -> Result<RgbaImage, GpuError> {
    GpuContext::new(AdapterChoice::default())?.render(prepared, time, &GpuOptions::default())
}

/// The oracle's output rule: `⌊255·clamp(c, 0, 1) + 0.5⌋`, NaN → 0.
fn to_unorm8(c: f32) -> u8 {
    if c > 0.0 {
        (255.0 * c.min(1.0) + 0.5) as u8
    } else {
        0
    }
}

/// IEEE half to f32 (the Rgba16Float fallback target).
fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((h >> 10) & 0x1f);
    let mantissa = f32::from(h & 0x3ff);
    sign * match exponent {
        0 => mantissa * 2f32.powi(-24),
        31 => {
            if mantissa == 0.0 {
                f32::INFINITY
            } else {
                f32::NAN
            }
        }
        e => (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}

fn layout_entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty,
        count: None,
    }
}

fn buffer_binding(ty: wgpu::BufferBindingType) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

fn texture_binding() -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type: wgpu::TextureSampleType::Float { filterable: true },
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    }
}

fn bind_view(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

fn bind(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// A storage array of vec4s; never empty (a zero vec4 when there is nothing).
fn storage_floats(items: impl Iterator<Item = [f32; 4]>) -> Vec<f32> {
    let mut out: Vec<f32> = items.flatten().collect();
    if out.is_empty() {
        out.extend([0.0; 4]);
    }
    out
}

/// A spot as four vec4s (the layout in `fur.wgsl`).
fn spot_vec4s(spot: &Spot) -> [[f32; 4]; 4] {
    match *spot {
        Spot::Ellipsoid {
            centre,
            radii,
            inner,
            colour,
        } => [
            [0.0; 4],
            centre.extend(0.0).to_array(),
            radii.extend(inner).to_array(),
            colour.extend(0.0).to_array(),
        ],
        Spot::Light {
            direction,
            exponent,
            inner_threshold,
            outer_threshold,
            colour,
            ..
        } => [
            [1.0, 0.0, 0.0, 0.0],
            direction.extend(exponent).to_array(),
            Vec3::ZERO.extend(inner_threshold).to_array(),
            colour.extend(outer_threshold).to_array(),
        ],
        Spot::PointLight {
            position,
            reach,
            exponent,
            inner_threshold,
            outer_threshold,
            colour,
            ..
        } => [
            [4.0, 0.0, 0.0, 0.0],
            position.extend(exponent).to_array(),
            Vec3::new(reach, 0.0, 0.0)
                .extend(inner_threshold)
                .to_array(),
            colour.extend(outer_threshold).to_array(),
        ],
        Spot::LightStripe {
            direction,
            exponent,
            period,
            width,
            softness,
            colour,
            ..
        } => [
            [3.0, 0.0, 0.0, 0.0],
            direction.extend(exponent).to_array(),
            Vec3::new(period, 0.0, 0.0).extend(width).to_array(),
            colour.extend(softness).to_array(),
        ],
        Spot::Stripe {
            axis,
            period,
            width,
            softness,
            colour,
        } => [
            [2.0, 0.0, 0.0, 0.0],
            axis.extend(period).to_array(),
            Vec3::ZERO.extend(width).to_array(),
            colour.extend(softness).to_array(),
        ],
    }
}

/// The `FrameUniforms` of `fur.wgsl`, bytes in field order.
/// The frame uniform buffer of `prepared` at `time` as the backend uploads it: `FrameUniforms`
/// of `fur.wgsl` (its layout is written down by [`translate`] in every language).
pub fn frame_uniforms(prepared: &PreparedScene, time: f32) -> Vec<u8> {
    let s = prepared.scene();
    let camera = crate::export::camera(s);
    let view_proj: Mat4 = camera.view_projection(s.image.width as f32 / s.image.height as f32);
    let shade = prepared.shade_params_at(time);
    let wind = s.wind.as_ref().map(|w| {
        let (direction, force) = w.direction_and_force(time);
        direction.extend(force)
    });
    let w = &shade.weights;
    let (burn_exponent, burning) = match &shade.burn {
        Some(b) => (b.exponent, 1.0),
        None => (0.0, 0.0),
    };
    let floats: Vec<Vec4> = vec![
        s.camera.eye.extend(1.0),
        s.light.direction.normalize_or_zero().extend(0.0),
        shade.light_colour.extend(0.0),
        (s.fur.colour * 0.35).extend(0.0),
        wind.unwrap_or(Vec4::ZERO),
        Vec4::new(
            s.fur.texture_repeat[0],
            s.fur.texture_repeat[1],
            s.fur.fur_length(),
            if wind.is_some() { 1.0 } else { 0.0 },
        ),
        Vec4::new(
            shade.ambient,
            shade.exponents.banks,
            shade.exponents.specular,
            shade.exponents.dampened,
        ),
        Vec4::new(
            shade.tangent_shift,
            shade.wind_tangent_fraction,
            burn_exponent,
            burning,
        ),
        Vec4::new(w.ambient, w.diffuse, w.specular, w.dampened),
        Vec4::new(
            w.shadow,
            // SPECULAR_LOBES_SUM, AMBIENT_CONSTANT, SHADOW_OPAQUE flags in fur.wgsl.
            f32::from(u8::from(matches!(
                shade.tangents,
                crate::shading::SpecularTangents::Three(crate::shading::SpecularLobes::Sum)
            ))),
            f32::from(u8::from(
                shade.ambient_term == crate::shading::AmbientTerm::Constant,
            )),
            f32::from(u8::from(
                shade.shadow_texel == crate::shading::ShadowTexel::Opaque,
            )),
        ),
    ];
    let offset = prepared.object_offset_at(time).unwrap_or(Vec3::ZERO);
    let lean = prepared.shared_lean_at(time);
    let mut bytes: Vec<u8> = view_proj
        .to_cols_array()
        .iter()
        .chain(
            floats
                .iter()
                .flat_map(|v| v.to_array())
                .collect::<Vec<_>>()
                .iter(),
        )
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let tangents: u32 = match shade.tangents {
        crate::shading::SpecularTangents::One => 1,
        crate::shading::SpecularTangents::Three(_) => 3,
    };
    let debug: u32 = match shade.debug_view {
        DebugView::None => 0,
        DebugView::Tangents => 1,
        DebugView::Alpha => 2,
        DebugView::Shadow => 3,
    };
    let matches = shade
        .burn
        .as_ref()
        .map_or(0, |b| b.directions.len() + b.points.len()) as u32;
    for v in [tangents, debug, shade.spots.len() as u32, matches] {
        bytes.extend(v.to_le_bytes());
    }
    for v in [
        offset.extend(0.0),
        lean.unwrap_or(Vec3::ZERO)
            .extend(if lean.is_some() { 1.0 } else { 0.0 }),
    ] {
        bytes.extend(v.to_array().iter().flat_map(|c| c.to_le_bytes()));
    }
    let maps = prepared.maps();
    // MAP_LENGTH, MAP_DENSITY, MAP_DIRECTION, MAP_COLOUR in fur.wgsl.
    let present = u32::from(maps.length.is_some())
        | u32::from(maps.density.is_some()) << 1
        | u32::from(maps.direction.is_some()) << 2
        | u32::from(maps.colour.is_some()) << 3;
    let wrap =
        |a: crate::scene::MapAddressSetting| u32::from(a == crate::scene::MapAddressSetting::Wrap);
    let stretch = u32::from(s.wind.as_ref().is_some_and(|w| !w.keep_length));
    for v in [
        present,
        wrap(s.maps.address[0]),
        wrap(s.maps.address[1]),
        stretch,
    ] {
        bytes.extend(v.to_le_bytes());
    }
    // The lighting equation (fur.wgsl's `uncoloured_specular`): eq. 3.5 and its n, or eq. 3.6.
    let lighting = match shade.lighting {
        crate::shading::LightingModel::Eq36 => Vec4::ZERO,
        crate::shading::LightingModel::Eq35 { n } => Vec4::new(1.0, n, 0.0, 0.0),
    };
    bytes.extend(lighting.to_array().iter().flat_map(|c| c.to_le_bytes()));
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_decode() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0x3800), 0.5);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0), 0.0);
    }

    #[test]
    fn output_rounding_is_the_oracles() {
        assert_eq!(to_unorm8(1.0), 255);
        assert_eq!(to_unorm8(0.5), 128);
        assert_eq!(to_unorm8(-1.0), 0);
        assert_eq!(to_unorm8(f32::NAN), 0);
    }
}
