//! The GPU backend against the oracle (feature `gpu`): every scene in `scenes/` drawn by both
//! at a reduced size, a table of the comparison metrics, and a failure when a scene exceeds the
//! tolerance documented in the README ("Checking a GPU renderer"). Then the proof that the
//! comparison catches real bugs: one shader term changed on purpose must fail it.
//!
//! The adapter is the CPU one (Mesa's lavapipe; `.ci/run` installs it). Without any Vulkan
//! adapter these tests fail with a message saying what to install. The `_on_gl` tests do the
//! same through OpenGL ES (wgpu's GL backend, EGL on Mesa's llvmpipe). The `_on_swiftshader`
//! tests do it on Google's SwiftShader, a CPU Vulkan driver that shares no code with Mesa's
//! two, where the Vulkan loader lists it (`VK_ICD_FILENAMES` naming its ICD file beside
//! lavapipe's; `.ci/swiftshader` installs it); without it they are skipped, unless
//! `PELAGE_REQUIRE_SWIFTSHADER=1` (CI) makes them fail.
#![cfg(feature = "gpu")]

mod common;

use pelage::compare::{Comparison, Tolerance, compare_images};
use pelage::gpu::{AdapterChoice, Api, Blending, GpuContext, GpuOptions, SHADER_SOURCE};
use pelage::render::PreparedScene;
use pelage::scene::Scene;
use std::path::{Path, PathBuf};

/// The tolerance every scene must meet (README, "Tolerances"): at most 0.5% of pixels more
/// than 8 steps off in some channel, FLIP mean at most 0.015 and its 99th percentile at most
/// 0.15, PSNR at least 40 dB.
const TOLERANCE: &str = pelage::compare::GPU_TOLERANCE;

/// Longest image side in these tests (the oracle renders the same reduced size).
const SIDE: u32 = 240;

/// The Vulkan adapter these tests draw on: the software one (lavapipe), unless
/// `PELAGE_GPU_ADAPTER` names another as `--adapter` does (`any` for a hardware GPU, an index
/// or part of a name), so the same tests measure a hardware GPU where one is lent.
fn context() -> GpuContext {
    let choice = std::env::var("PELAGE_GPU_ADAPTER")
        .map(|v| AdapterChoice::parse(&v))
        .unwrap_or_default();
    GpuContext::new(choice).unwrap_or_else(|e| panic!("{e}"))
}

/// The second API: OpenGL ES through EGL on Mesa's llvmpipe (`.ci/run` installs it).
/// wgpu's GL backend cannot blend `Rgba32Float` there, so the frame is blended in f32 by the
/// fragment lists (`src/gpu/lists.rs`), never in half floats.
fn gl_context() -> GpuContext {
    let context =
        GpuContext::open(Api::Gl, &AdapterChoice::Software).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        context.blending(),
        Blending::FragmentLists,
        "GL on llvmpipe blends through the fragment lists"
    );
    context
}

/// The third implementation: SwiftShader on Vulkan, `None` (skipped, with a line saying why)
/// where the loader does not list it, unless `PELAGE_REQUIRE_SWIFTSHADER=1`.
fn swiftshader_context() -> Option<GpuContext> {
    match GpuContext::open(Api::Vulkan, &AdapterChoice::Name("swiftshader".into())) {
        Ok(context) => Some(context),
        Err(e) if std::env::var_os("PELAGE_REQUIRE_SWIFTSHADER").is_some_and(|v| v == "1") => {
            panic!("PELAGE_REQUIRE_SWIFTSHADER=1: {e}")
        }
        Err(e) => {
            eprintln!(
                "SKIPPED: {} needs SwiftShader, its ICD file in VK_ICD_FILENAMES (run .ci/setup): {e}",
                std::thread::current().name().unwrap_or("a test")
            );
            None
        }
    }
}

/// The prefix of the images one context writes: none for lavapipe, `gl-`, `swiftshader-`,
/// `hw-` for a hardware GPU.
fn prefix(context: &GpuContext) -> &'static str {
    match context.api() {
        Api::Gl => "gl-",
        Api::Vulkan if context.adapter_info().device_type != wgpu::DeviceType::Cpu => "hw-",
        Api::Vulkan
            if context
                .adapter_info()
                .name
                .to_lowercase()
                .contains("swiftshader") =>
        {
            "swiftshader-"
        }
        Api::Vulkan => "",
    }
}

fn scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

/// The scene at a reduced size (aspect kept), and the instants to check.
fn load(path: &Path) -> (Scene, Vec<f32>) {
    let mut scene = Scene::load(path).expect("scene");
    let (w, h) = (scene.image.width as f32, scene.image.height as f32);
    let scale = SIDE as f32 / w.max(h);
    scene.image.width = ((w * scale).round() as u32).max(2);
    scene.image.height = ((h * scale).round() as u32).max(2);
    let name = path.file_stem().expect("name").to_string_lossy();
    // The animated scenes at instants of the golden tests (wind swaying, fur burning, the
    // torus flying away with fewer shells, the characters posed).
    let times = match name.as_ref() {
        "wind" => vec![0.5, 1.5],
        "burn" => vec![3.0, 6.0],
        "lod-flyaway" => vec![0.0, 0.8, 2.0, 4.0],
        // The characters, skinned in the vertex stage, walking and wagging.
        "fox" => vec![0.4],
        "tail" => vec![0.5],
        _ => vec![scene.time],
    };
    (scene, times)
}

fn out_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("gpu");
    std::fs::create_dir_all(&dir).expect("out dir");
    dir
}

fn compare(
    context: &GpuContext,
    prepared: &PreparedScene,
    time: f32,
    options: &GpuOptions,
    tolerance: &Tolerance,
    name: &str,
) -> Comparison {
    let oracle = prepared.render_at(time, 64).expect("oracle render");
    let oracle = image::RgbaImage::from_raw(oracle.width, oracle.height, oracle.rgba8)
        .expect("oracle image");
    let gpu = context
        .render(prepared, time, options)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let c = compare_images(&oracle, &gpu, tolerance).expect("same size");
    let dir = out_dir();
    oracle
        .save(dir.join(format!("{name}-oracle.png")))
        .expect("write");
    gpu.save(dir.join(format!("{name}-gpu.png")))
        .expect("write");
    pelage::compare::heat_map(&oracle, &gpu)
        .expect("same size")
        .save(dir.join(format!("{name}-heat.png")))
        .expect("write");
    c
}

fn row(name: &str, c: &Comparison) -> String {
    format!(
        "{name:<18} {:>9.3}% {:>4} {:>4} {:>4} {:>8.4} {:>10} {:>8.4}% {:>8.5} {:>8.5} {:>8.5}  {}",
        100.0 * c.exact_pixels as f64 / c.pixels as f64,
        c.max_abs_error[0],
        c.max_abs_error[1],
        c.max_abs_error[2],
        (c.mean_abs_error[0] + c.mean_abs_error[1] + c.mean_abs_error[2]) / 3.0,
        c.psnr.to_string(),
        100.0 * c.over_fraction(),
        c.flip.mean,
        c.flip.p99,
        c.flip.max,
        if c.passed() { "ok" } else { "FAIL" }
    )
}

/// A glTF model skinned in the vertex stage from the joint palette draws the frame the CPU's
/// pose draws when uploaded, and both meet the oracle's tolerance, at the golden instants.
#[test]
fn vertex_stage_skinning_matches_the_cpu_pose() {
    let context = context();
    let tolerance = Tolerance::parse(TOLERANCE).expect("tolerance");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let on_cpu = GpuOptions {
        pose_on_cpu: true,
        ..GpuOptions::default()
    };
    for (name, times) in [("tail", [0.0, 0.5, 1.25]), ("fox", [0.0, 0.4, 0.8])] {
        let (scene, _) = load(&dir.join(format!("{name}.toml")));
        let prepared = PreparedScene::new(&scene).expect("prepare");
        for t in times {
            let label = format!("{name}@{t}");
            let skinned = compare(
                &context,
                &prepared,
                t,
                &GpuOptions::default(),
                &tolerance,
                &format!("skinned-{label}"),
            );
            let posed = compare(
                &context,
                &prepared,
                t,
                &on_cpu,
                &tolerance,
                &format!("posed-{label}"),
            );
            println!("{}", row(&format!("skinned {label}"), &skinned));
            println!("{}", row(&format!("cpu-posed {label}"), &posed));
            let a = context
                .render(&prepared, t, &GpuOptions::default())
                .expect("skinned");
            let b = context.render(&prepared, t, &on_cpu).expect("posed");
            let between = compare_images(&b, &a, &tolerance).expect("same size");
            println!("{}", row(&format!("skinned/posed {label}"), &between));
            assert!(skinned.passed(), "{label}: skinned on the GPU");
            assert!(posed.passed(), "{label}: posed on the CPU");
            assert!(between.passed(), "{label}: skinned against posed");
        }
    }
}

#[test]
fn every_scene_matches_the_oracle_within_tolerance() {
    let context = context();
    every_scene(&context, prefix(&context), TOLERANCE);
}

/// The same scenes, instants and tolerance through OpenGL (wgpu's GL backend, EGL).
#[test]
fn every_scene_matches_the_oracle_within_tolerance_on_gl() {
    every_scene(&gl_context(), "gl-", TOLERANCE);
}

/// The same scenes, instants and tolerance on SwiftShader (Vulkan): the third implementation,
/// whose code generator (Subzero or LLVM, its own rasterizer and sampler) is not Mesa's gallivm.
#[test]
fn every_scene_matches_the_oracle_within_tolerance_on_swiftshader() {
    if let Some(context) = swiftshader_context() {
        every_scene(&context, "swiftshader-", TOLERANCE);
    }
}

/// Every scene against the oracle; `prefix` starts the names of the images written.
fn every_scene(context: &GpuContext, prefix: &str, tolerance: &str) {
    let info = context.adapter_info();
    let tolerance = Tolerance::parse(tolerance).expect("tolerance");
    println!(
        "adapter: {} ({:?}, {}), target {:?}, blending {:?}; tolerance {tolerance}",
        info.name,
        info.device_type,
        info.driver_info,
        context.target_format(),
        context.blending()
    );
    println!("API: {:?}", context.api());
    println!(
        "{:<18} {:>10} {:>4} {:>4} {:>4} {:>8} {:>10} {:>9} {:>8} {:>8} {:>8}",
        "scene",
        "exact",
        "maxR",
        "maxG",
        "maxB",
        "mean",
        "PSNR",
        ">thresh",
        "FLIPmean",
        "FLIPp99",
        "FLIPmax"
    );
    let mut failures = Vec::new();
    for path in scenes() {
        let (scene, times) = load(&path);
        let prepared = PreparedScene::new(&scene).expect("prepare");
        let stem = path
            .file_stem()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        for &t in &times {
            let name = if times.len() > 1 {
                format!("{stem}@t{t}")
            } else {
                stem.clone()
            };
            let c = compare(
                context,
                &prepared,
                t,
                &GpuOptions::default(),
                &tolerance,
                &format!("{prefix}{name}"),
            );
            println!("{}", row(&name, &c));
            if !c.passed() {
                failures.push(format!("{name}: {}", c.failures.join("; ")));
            }
        }
    }
    println!("images and heat maps: {}", out_dir().display());
    assert!(
        failures.is_empty(),
        "outside tolerance:\n{}",
        failures.join("\n")
    );
}

#[test]
fn the_thesis_conventions_match_the_oracle_within_tolerance() {
    // The scenes above use the defaults; here the other choice of each convention key (README,
    // "Where pelage departs from the thesis"): the three lobes summed, the ambient outside the
    // strand colour, opaque shadow lookups counted, and the stripes of both kinds.
    let context = context();
    let tolerance = Tolerance::parse(TOLERANCE).expect("tolerance");
    let (mut scene, _) = load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cow.toml"));
    scene.shading.specular_tangents = 3;
    scene.shading.specular_lobes = pelage::scene::SpecularLobesSetting::Sum;
    scene.shading.weights.specular = 0.2;
    scene.shading.ambient_term = pelage::scene::AmbientTermSetting::Constant;
    scene.shading.shadow_texel = pelage::scene::ShadowTexelSetting::Opaque;
    scene.stripes.push(pelage::scene::StripeSettings {
        kind: pelage::scene::StripeKind::Axis,
        axis: Some(glam::Vec3::new(0.2, 0.0, 1.0)),
        period: Some(7.0),
        width: Some(0.9),
        softness: Some(0.4),
        ..pelage::scene::StripeSettings::default()
    });
    let prepared = PreparedScene::new(&scene).expect("prepare");
    let c = compare(
        &context,
        &prepared,
        scene.time,
        &GpuOptions::default(),
        &tolerance,
        "thesis-conventions",
    );
    println!("{}", row("thesis choices", &c));
    assert!(c.passed(), "outside tolerance: {}", c.failures.join("; "));
}

/// Replaces `from` (which must occur exactly once) in the shader.
fn perturbed(from: &str, to: &str) -> GpuOptions {
    assert_eq!(
        SHADER_SOURCE.matches(from).count(),
        1,
        "the perturbation must change exactly one place: {from}"
    );
    GpuOptions {
        shader: Some(SHADER_SOURCE.replace(from, to)),
        ..GpuOptions::default()
    }
}

fn check_caught(scene_file: &str, time: f32, options: GpuOptions, what: &str) {
    check_caught_on(&context(), scene_file, time, options, what);
}

fn check_caught_on(
    context: &GpuContext,
    scene_file: &str,
    time: f32,
    options: GpuOptions,
    what: &str,
) {
    let prefix = prefix(context);
    let tolerance = Tolerance::parse(TOLERANCE).expect("tolerance");
    let (scene, _) = load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(scene_file));
    let prepared = PreparedScene::new(&scene).expect("prepare");
    let honest = compare(
        context,
        &prepared,
        time,
        &GpuOptions::default(),
        &tolerance,
        &format!("{prefix}honest"),
    );
    let bad = compare(
        context,
        &prepared,
        time,
        &options,
        &tolerance,
        &format!("{prefix}{what}"),
    );
    println!("{}\n{}", row("unchanged shader", &honest), row(what, &bad));
    assert!(
        honest.passed(),
        "the unchanged shader must pass: {:?}",
        honest.failures
    );
    assert!(
        !bad.passed(),
        "{what}: the comparison did not catch the change"
    );
}

#[test]
fn a_changed_banks_exponent_is_caught() {
    // Banks's exponent 4.8 → 4.6 in the diffuse term (eq. 2.5, thesis 3.2.3).
    check_caught(
        "scenes/torus.toml",
        0.0,
        perturbed(
            "kajiya_kay_diffuse(tangent, light, s.y)",
            "kajiya_kay_diffuse(tangent, light, s.y - 0.2)",
        ),
        "banks 4.6",
    );
}

#[test]
fn a_changed_burn_threshold_is_caught() {
    // The burn threshold 0.1 → 0.15 (thesis 3.4).
    check_caught(
        "scenes/burn.toml",
        6.0,
        perturbed(
            "const BURN_THRESHOLD: f32 = 0.1;",
            "const BURN_THRESHOLD: f32 = 0.15;",
        ),
        "burn threshold 0.15",
    );
}

#[test]
fn an_ignored_level_of_detail_span_is_caught() {
    // Level of detail without the alpha compensation: the few layers drawn far away keep the
    // alpha of one layer each (lod_alpha, shading/lod.rs).
    check_caught(
        "scenes/lod-flyaway.toml",
        2.0,
        perturbed(
            "lod_alpha(coverage * v.fade, layer.lod_span)",
            "lod_alpha(coverage * v.fade, 1.0)",
        ),
        "lod span ignored",
    );
}

#[test]
fn a_lowered_density_is_caught() {
    // density_alpha at 0.05 less density than the map says (shading/maps.rs).
    check_caught(
        "scenes/density.toml",
        0.0,
        perturbed(
            "density_alpha(bands, density)",
            "density_alpha(bands, density - 0.05)",
        ),
        "density − 0.05",
    );
}

#[test]
fn a_tangent_not_bent_by_the_lean_is_caught() {
    // Gravity moves the layers but the strands' tangents stay upright (the lean's bend_tangent
    // left out of the fragment stage).
    check_caught(
        "scenes/gravity.toml",
        0.0,
        perturbed(
            "tangent = bend_tangent(tangent, v.lean, layer.height_fraction);",
            "",
        ),
        "lean tangent left out",
    );
}

/// The five changes above are caught through OpenGL too, at the same tier.
#[test]
fn the_five_changes_are_caught_on_gl() {
    the_five_changes_are_caught_on(&gl_context());
}

/// The five changes above are caught on SwiftShader too, at the same tier.
#[test]
fn the_five_changes_are_caught_on_swiftshader() {
    if let Some(context) = swiftshader_context() {
        the_five_changes_are_caught_on(&context);
    }
}

fn the_five_changes_are_caught_on(context: &GpuContext) {
    let cases = [
        (
            "scenes/torus.toml",
            0.0,
            "kajiya_kay_diffuse(tangent, light, s.y)",
            "kajiya_kay_diffuse(tangent, light, s.y - 0.2)",
            "banks 4.6",
        ),
        (
            "scenes/burn.toml",
            6.0,
            "const BURN_THRESHOLD: f32 = 0.1;",
            "const BURN_THRESHOLD: f32 = 0.15;",
            "burn threshold 0.15",
        ),
        (
            "scenes/lod-flyaway.toml",
            2.0,
            "lod_alpha(coverage * v.fade, layer.lod_span)",
            "lod_alpha(coverage * v.fade, 1.0)",
            "lod span ignored",
        ),
        (
            "scenes/density.toml",
            0.0,
            "density_alpha(bands, density)",
            "density_alpha(bands, density - 0.05)",
            "density − 0.05",
        ),
        (
            "scenes/gravity.toml",
            0.0,
            "tangent = bend_tangent(tangent, v.lean, layer.height_fraction);",
            "",
            "lean tangent left out",
        ),
    ];
    for (scene, time, from, to, what) in cases {
        check_caught_on(context, scene, time, perturbed(from, to), what);
    }
}

/// The shader with every vertex's clip position snapped to 1/16 pixel (4 sub-pixel bits,
/// rounding to nearest) on a `width`×`height` frame, before the rasterizer snaps it again.
fn snapped_to_sixteenths(width: u32, height: u32) -> GpuOptions {
    let mut source = SHADER_SOURCE.to_string();
    for clip in [
        "frame.view_proj * vec4<f32>(v.position + frame.offset.xyz, 1.0)",
        "frame.view_proj * vec4<f32>(p, 1.0)",
        "frame.view_proj * vec4<f32>(v.position, 1.0)",
    ] {
        let from = format!("out.clip = {clip};");
        assert_eq!(source.matches(&from).count(), 1, "{from}");
        source = source.replace(&from, &format!("out.clip = snap_sixteenths({clip});"));
    }
    source.push_str(&format!(
        "
fn snap_sixteenths(c: vec4<f32>) -> vec4<f32> {{
    let size = vec2<f32>({width}.0, {height}.0);
    let s = round((c.xy / c.w * 0.5 + 0.5) * size * 16.0) / 16.0;
    return vec4<f32>((s / size * 2.0 - 1.0) * c.w, c.z, c.w);
}}
"
    ));
    GpuOptions {
        shader: Some(source),
        ..GpuOptions::default()
    }
}

/// Where SwiftShader differs from the oracle by far more than 8 steps (a few pixels on
/// silhouettes, up to 79 steps on `lod-flyaway` at 2 s), the cause is its 4 sub-pixel bits
/// (`subPixelPrecisionBits = 4`; the oracle and lavapipe snap to 8): lavapipe drawing the
/// vertices snapped to 1/16 pixel in the vertex stage gives SwiftShader's frame to within
/// 8 steps on every pixel, and SwiftShader's own frame does not change with that snapping.
#[test]
fn swiftshader_differs_on_silhouettes_by_its_four_sub_pixel_bits() {
    let Some(swiftshader) = swiftshader_context() else {
        return;
    };
    let (scene, _) = load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/lod-flyaway.toml"));
    let prepared = PreparedScene::new(&scene).expect("prepare");
    let t = 2.0;
    let snapped = snapped_to_sixteenths(scene.image.width, scene.image.height);
    let oracle = prepared.render_at(t, 64).expect("oracle render");
    let oracle = image::RgbaImage::from_raw(oracle.width, oracle.height, oracle.rgba8)
        .expect("oracle image");
    let draw = |context: &GpuContext, options: &GpuOptions| {
        context
            .render(&prepared, t, options)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let on_swiftshader = draw(&swiftshader, &GpuOptions::default());
    let lavapipe_snapped = draw(&context(), &snapped);
    let swiftshader_snapped = draw(&swiftshader, &snapped);
    let within = |a: &image::RgbaImage, b: &image::RgbaImage, steps: u32, what: &str| {
        let tolerance = Tolerance::parse(&format!("threshold={steps},over=0")).expect("tolerance");
        let c = compare_images(a, b, &tolerance).expect("same size");
        println!("{}", row(what, &c));
        c.passed()
    };
    assert!(
        !within(&oracle, &on_swiftshader, 8, "oracle/swiftshader"),
        "SwiftShader no longer differs from the oracle on silhouettes: the book's note is stale"
    );
    assert!(within(
        &lavapipe_snapped,
        &on_swiftshader,
        8,
        "lavapipe 4 bits/swiftshader"
    ));
    assert!(within(
        &swiftshader_snapped,
        &on_swiftshader,
        1,
        "swiftshader 4 bits/itself"
    ));
}

/// Through OpenGL the frame is blended by the fragment lists, in draw and primitive order:
/// drawn through GL and through Vulkan (whose blend unit blends `Rgba32Float`), the images
/// agree to within one 8-bit step on every pixel and are equal on nearly all, on a scene with
/// fins, spots and forty shells (a torus, whose shells are seen through their own rims).
#[test]
fn gl_and_vulkan_agree_to_one_step() {
    let (scene, _) = load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/torus.toml"));
    let prepared = PreparedScene::new(&scene).expect("prepare");
    assert!(prepared.fin_textures().is_some(), "the scene has fins");
    let options = GpuOptions::default();
    let vulkan = context()
        .render(&prepared, scene.time, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    let gl = gl_context()
        .render(&prepared, scene.time, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    let c = compare_images(
        &vulkan,
        &gl,
        &Tolerance::parse("threshold=1,over=0").expect("tolerance"),
    )
    .expect("same size");
    println!("{}", row("GL against Vulkan", &c));
    assert!(c.passed(), "GL and Vulkan differ: {:?}", c.failures);
    assert!(
        c.exact_pixels as f64 >= 0.99 * c.pixels as f64,
        "only {} of {} pixels equal",
        c.exact_pixels,
        c.pixels
    );
}

/// `pelage bench --backend gpu` draws one frame set up once again and again: every draw gives
/// the image of a fresh `render`, fins included.
#[test]
fn a_frame_set_up_once_draws_the_same_image_every_time() {
    draws_the_same_image_every_time(&context());
}

/// The same through GL: the fragment lists fill in whatever order the fragments arrive, and
/// every draw still gives the same bytes (each list is blended in primitive order).
#[test]
fn a_frame_set_up_once_draws_the_same_image_every_time_on_gl() {
    draws_the_same_image_every_time(&gl_context());
}

/// A draw that lists more fragments than the lists hold is an error naming the count, never a
/// wrong image; with room for them the same frame draws.
#[test]
fn fragment_lists_that_overflow_are_an_error() {
    let context = gl_context();
    let (scene, _) = load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/torus.toml"));
    let prepared = PreparedScene::new(&scene).expect("prepare");
    let small = GpuOptions {
        list_capacity: Some(1000),
        ..GpuOptions::default()
    };
    let e = context
        .render(&prepared, scene.time, &small)
        .expect_err("a shell covers more than 1000 pixels");
    let message = e.to_string();
    assert!(
        message.contains("more than the 1000 the fragment lists hold"),
        "{message}"
    );
    let roomy = GpuOptions {
        list_capacity: Some(scene.image.width * scene.image.height * 4),
        ..GpuOptions::default()
    };
    let default = context
        .render(&prepared, scene.time, &GpuOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let with_room = context
        .render(&prepared, scene.time, &roomy)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(with_room == default);
}

fn draws_the_same_image_every_time(context: &GpuContext) {
    let (scene, _) = load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/thesis-4-2.toml"
    )));
    let prepared = PreparedScene::new(&scene).expect("prepare");
    assert!(prepared.fin_textures().is_some(), "the scene has fins");
    let options = GpuOptions::default();
    let fresh = context
        .render(&prepared, scene.time, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    let frame = context
        .prepare_frame(&prepared, scene.time, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(frame.size(), (scene.image.width, scene.image.height));
    for draw in 0..3 {
        frame.draw().unwrap_or_else(|e| panic!("{e}"));
        let image = frame.read_back().unwrap_or_else(|e| panic!("{e}"));
        assert!(image == fresh, "draw {draw} differs from a fresh render");
    }
}

#[test]
fn a_gpu_sweep_against_the_oracle_adds_the_metrics() {
    let dir = out_dir().join("sweep");
    let _ = std::fs::remove_dir_all(&dir);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args([
            "sweep",
            "--backend",
            "gpu",
            "--against-oracle",
            "--param",
            "number_of_shells=8,16",
            "--width",
            "120",
            "--height",
            "90",
            "--frames",
            "1",
            "-o",
        ])
        .arg(&dir)
        .output()
        .expect("pelage runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.join("results.csv")).expect("results.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let verdict = header
        .iter()
        .position(|h| *h == "oracle_within_tolerance")
        .expect("the comparison's columns");
    assert!(header.contains(&"oracle_flip_mean") && header.contains(&"oracle_psnr_db"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2);
    for row in rows {
        assert_eq!(row[verdict], "true", "{row:?}");
    }
    assert!(dir.join("point_0001_diff.png").is_file());
}
