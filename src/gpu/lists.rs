//! Blending in f32 without a blendable 32-bit target (beside the pipeline: GPU backend): per-pixel
//! fragment lists, resolved in draw and primitive order (the GL path; see [`super::Blending`]).
//!
//! wgpu's GL backend offers no 32-bit float target it can blend (nor render to: see
//! `target_choice`), and a half-float target rounds the blended colour at every layer. So on
//! GL the frame is held as f32 in a storage buffer and every blend is done by a shader, in the
//! order the blend unit would do it:
//! 1. The skin (opaque, depth tested and written) draws into an `Rgba32Uint` target holding the
//!    bits of its f32 colour (cleared to the background's bits); `start` copies it into the
//!    frame buffer of f32.
//! 2. Each fur draw (the fins, then each shell root to tip) runs `fs_fur` unchanged, with the
//!    fixed-function depth test forced before the shader (`@early_depth_test(force)`: a fragment
//!    behind the skin never runs), and instead of returning its colour appends it with its
//!    primitive index to its pixel's list (`fs_fur_listed`).
//! 3. `resolve` then blends each pixel's fragments of that draw over the frame in ascending
//!    primitive index, the order in which the API blends the fragments of one draw, with the
//!    oracle's formula (`rgb = src.rgb·a + dst.rgb·(1 − a)`, `alpha = a + dst.a·(1 − a)`), and
//!    the lists are emptied for the next draw.
//!
//! This is exact in order, not only on average: fragments of one draw do overlap (two fins at a
//! silhouette, a shell seen through its own rim), and a per-draw ping-pong of targets would blend
//! them against the same destination. One primitive covers a pixel at most once (one sample per
//! pixel), so a pixel's fragments of one draw have distinct primitive indices.
//!
//! Each draw's lists hold at most [`Lists::capacity`] fragments (four per pixel, less where the
//! device's storage buffers are smaller, or `GpuOptions::list_capacity`); a draw that lists more is reported by
//! [`super::GpuFrame::read_back`] as an error naming the count, never drawn wrong.

/// The entry points and bindings added to `fur.wgsl` for the lists (group 2).
const LISTED_ENTRY_POINTS: &str = r"
// ---- blending in f32 through per-pixel fragment lists (gpu/lists.rs) ----------------------

struct ListedFragment {
    colour: vec4<f32>,
    primitive: u32,
    next: u32,
}

// heads[0]: the fragments listed in this draw; heads[1]: the most a draw wanted beyond the
// capacity (0: none); heads[2 + pixel]: 1 + the index of the pixel's latest fragment, 0: none.
@group(2) @binding(0) var<storage, read_write> heads: array<atomic<u32>>;
@group(2) @binding(1) var<storage, read_write> listed: array<ListedFragment>;
// width, height, capacity, 0.
@group(2) @binding(2) var<uniform> list_size: vec4<u32>;

@fragment
@early_depth_test(force)
fn fs_fur_listed(v: FurVaryings, @builtin(primitive_index) primitive: u32) {
    let colour = fur_fragment(v);
    let i = atomicAdd(&heads[0], 1u);
    if (i >= list_size.z) {
        atomicMax(&heads[1], i + 1u);
        return;
    }
    listed[i].colour = colour;
    listed[i].primitive = primitive;
    let pixel = u32(v.clip.y) * list_size.x + u32(v.clip.x);
    listed[i].next = atomicExchange(&heads[2u + pixel], i + 1u);
}

// The skin's colour as the bits of its floats (an Rgba32Uint target needs no blending).
@fragment
fn fs_skin_bits(v: SkinVaryings) -> @location(0) vec4<u32> {
    return bitcast<vec4<u32>>(skin_fragment(v));
}
";

/// The compute shader that starts the frame from the skin and resolves each draw's lists.
pub const RESOLVE_SOURCE: &str = r"
struct ListedFragment {
    colour: vec4<f32>,
    primitive: u32,
    next: u32,
}

@group(0) @binding(0) var<storage, read> heads: array<u32>;
@group(0) @binding(1) var<storage, read> listed: array<ListedFragment>;
@group(0) @binding(2) var<storage, read_write> frame_colour: array<vec4<f32>>;
@group(0) @binding(3) var<uniform> list_size: vec4<u32>;
@group(0) @binding(4) var skin: texture_2d<u32>;

// The frame starts as the skin over the background (their f32 bits).
@compute @workgroup_size(8, 8)
fn start(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= list_size.x || id.y >= list_size.y) {
        return;
    }
    let bits = textureLoad(skin, vec2<u32>(id.x, id.y), 0);
    frame_colour[id.y * list_size.x + id.x] = bitcast<vec4<f32>>(bits);
}

// One draw's fragments of this pixel blended over the frame in ascending primitive index
// (distinct within a pixel), with the oracle's blend (raster/tile.rs, blend).
@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= list_size.x || id.y >= list_size.y) {
        return;
    }
    let pixel = id.y * list_size.x + id.x;
    let head = heads[2u + pixel];
    if (head == 0u) {
        return;
    }
    var dst = frame_colour[pixel];
    var blended_any = false;
    var last = 0u;
    loop {
        // The fragment of the smallest primitive index after the last one blended.
        var best = 0u;
        var best_primitive = 0u;
        var n = head;
        loop {
            if (n == 0u) {
                break;
            }
            let f = listed[n - 1u];
            if ((!blended_any || f.primitive > last)
                && (best == 0u || f.primitive < best_primitive)) {
                best = n;
                best_primitive = f.primitive;
            }
            n = f.next;
        }
        if (best == 0u) {
            break;
        }
        let src = listed[best - 1u].colour;
        let a = src.w;
        dst = src * vec4<f32>(a, a, a, 1.0) + dst * (1.0 - a);
        blended_any = true;
        last = best_primitive;
    }
    frame_colour[pixel] = dst;
}
";

/// `source` (the GL variant of `fur.wgsl`) with the fragment-list entry points: `fs_skin` and
/// `fs_fur` become the functions `skin_fragment` and `fur_fragment` (bodies unchanged, so a
/// changed shading term reaches the lists too), called by `fs_skin_bits` and `fs_fur_listed`.
pub fn with_fragment_lists(source: &str) -> Result<String, super::GpuError> {
    let swaps = [
        (
            "@fragment\nfn fs_skin(v: SkinVaryings) -> @location(0) vec4<f32> {",
            "fn skin_fragment(v: SkinVaryings) -> vec4<f32> {",
        ),
        (
            "@fragment\nfn fs_fur(v: FurVaryings) -> @location(0) vec4<f32> {",
            "fn fur_fragment(v: FurVaryings) -> vec4<f32> {",
        ),
    ];
    let mut out = String::from("enable primitive_index;\n");
    out.push_str(source);
    for (from, to) in swaps {
        if out.matches(from).count() != 1 {
            return Err(super::GpuError::Validation(format!(
                "the fragment-list variant of the shader: `{from}` not found once"
            )));
        }
        out = out.replace(from, to);
    }
    out.push_str(LISTED_ENTRY_POINTS);
    Ok(out)
}

/// Bytes of one `ListedFragment` (a vec4 and two u32, padded to the vec4's alignment).
const FRAGMENT_BYTES: u64 = 32;

/// Fragments per pixel one draw's lists hold, at most.
const FRAGMENTS_PER_PIXEL: u64 = 4;

/// The buffers and pipelines of the fragment lists of one frame.
pub struct Lists {
    /// `heads` of the shaders: counter, overflow, one list head per pixel.
    pub heads: wgpu::Buffer,
    /// The frame as f32 (`vec4` per pixel, row 0 at the top), read back at the end.
    pub frame_colour: wgpu::Buffer,
    /// Fragments one draw may list.
    pub capacity: u32,
    /// Group 2 of the fur pipelines.
    pub fur_group: wgpu::BindGroup,
    resolve_group: wgpu::BindGroup,
    start_pipeline: wgpu::ComputePipeline,
    resolve_pipeline: wgpu::ComputePipeline,
    /// The skin's colour bits (`Rgba32Uint`), the start of the frame.
    pub skin_view: wgpu::TextureView,
    width: u32,
    height: u32,
}

/// The format of the skin's target on the list path.
pub const SKIN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

impl Lists {
    /// The layout of group 2 of the fur pipelines.
    pub fn fur_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fragment lists"),
            entries: &[
                entry(0, wgpu::ShaderStages::FRAGMENT, storage(false)),
                entry(1, wgpu::ShaderStages::FRAGMENT, storage(false)),
                entry(2, wgpu::ShaderStages::FRAGMENT, uniform()),
            ],
        })
    }

    /// The buffers for a `width` × `height` frame, bound to `fur_layout`'s group and to the
    /// resolve pipelines; `capacity` (fragments per draw) lowers the default.
    pub fn new(
        device: &wgpu::Device,
        fur_layout: &wgpu::BindGroupLayout,
        width: u32,
        height: u32,
        capacity: Option<u32>,
    ) -> Lists {
        use wgpu::util::DeviceExt;
        let pixels = u64::from(width) * u64::from(height);
        let limit = device
            .limits()
            .max_storage_buffer_binding_size
            .min(device.limits().max_buffer_size);
        let capacity = (pixels * FRAGMENTS_PER_PIXEL)
            .min(limit / FRAGMENT_BYTES)
            .min(u64::from(capacity.unwrap_or(u32::MAX - 1))) as u32;
        let heads = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("list heads"),
            size: (2 + pixels) * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let listed = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("listed fragments"),
            size: u64::from(capacity.max(1)) * FRAGMENT_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let frame_colour = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame colour"),
            size: pixels * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let size_bytes: Vec<u8> = [width, height, capacity, 0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let size = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("list size"),
            contents: &size_bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let fur_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fragment lists"),
            layout: fur_layout,
            entries: &[whole(0, &heads), whole(1, &listed), whole(2, &size)],
        });
        let skin = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("skin bits"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SKIN_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let skin_view = skin.create_view(&Default::default());
        let compute = wgpu::ShaderStages::COMPUTE;
        let resolve_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resolve"),
            entries: &[
                entry(0, compute, storage(true)),
                entry(1, compute, storage(true)),
                entry(2, compute, storage(false)),
                entry(3, compute, uniform()),
                entry(
                    4,
                    compute,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
            ],
        });
        let resolve_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resolve"),
            layout: &resolve_layout,
            entries: &[
                whole(0, &heads),
                whole(1, &listed),
                whole(2, &frame_colour),
                whole(3, &size),
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&skin_view),
                },
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("resolve"),
            source: wgpu::ShaderSource::Wgsl(RESOLVE_SOURCE.into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("resolve"),
            bind_group_layouts: &[Some(&resolve_layout)],
            immediate_size: 0,
        });
        let pipeline = |entry_point: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry_point),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry_point),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Lists {
            heads,
            frame_colour,
            capacity,
            fur_group,
            resolve_group,
            start_pipeline: pipeline("start"),
            resolve_pipeline: pipeline("resolve"),
            skin_view,
            width,
            height,
        }
    }

    /// Empties the lists and the overflow count: before the first fur draw.
    pub fn clear_all(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.heads, 0, None);
    }

    /// Starts the frame from the skin's target (after the skin's pass).
    pub fn start(&self, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(encoder, &self.start_pipeline);
    }

    /// Blends the lists of the draw just made over the frame and empties them (keeping the
    /// overflow count).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(encoder, &self.resolve_pipeline);
        encoder.clear_buffer(&self.heads, 0, Some(4));
        encoder.clear_buffer(&self.heads, 8, None);
    }

    fn dispatch(&self, encoder: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("fragment lists"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.resolve_group, &[]);
        pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
    }
}

fn entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty,
        count: None,
    }
}

fn storage(read_only: bool) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

fn uniform() -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

fn whole(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naga::valid::{Capabilities, ValidationFlags, Validator};

    fn validate(source: &str) -> naga::Module {
        let module = naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{e}"));
        Validator::new(ValidationFlags::all(), Capabilities::all())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{e:?}"));
        module
    }

    #[test]
    fn the_list_variant_of_the_gl_shader_is_valid_with_its_entry_points() {
        let gl = crate::gpu::translate::without_level_query(crate::gpu::SHADER_SOURCE)
            .and_then(|s| crate::gpu::translate::with_uniform_level_loads(&s))
            .and_then(|s| with_fragment_lists(&s))
            .unwrap_or_else(|e| panic!("{e}"));
        let module = validate(&gl);
        let names: Vec<&str> = module
            .entry_points
            .iter()
            .map(|e| e.name.as_str())
            .collect();
        for name in [
            "vs_skin",
            "vs_shell",
            "vs_fin",
            "fs_skin_bits",
            "fs_fur_listed",
        ] {
            assert!(names.contains(&name), "{name} missing from {names:?}");
        }
        assert!(!names.contains(&"fs_fur") && !names.contains(&"fs_skin"));
        let resolve = validate(RESOLVE_SOURCE);
        assert_eq!(resolve.entry_points.len(), 2);
    }

    #[test]
    fn a_shader_without_the_fragment_entry_points_is_refused() {
        let e = with_fragment_lists("fn main() {}").expect_err("nothing to turn into lists");
        assert!(e.to_string().contains("fs_skin"), "{e}");
    }
}
