//! The effects over time: burning only ever removes fur, animations are time-addressable.

mod common;
use common::scene;

use pelage::render::PreparedScene;
use std::path::PathBuf;
use std::process::Command;

#[test]
fn a_burn_only_ever_removes_fur() {
    let scene = scene("burn", 160, 120);
    let burn = scene.burn.clone().expect("the burn scene burns");
    let prepared = PreparedScene::new(&scene).expect("prepares");
    let written = |t: f32| {
        prepared
            .render_at(t, 64)
            .expect("renders")
            .stats
            .fragments_written
    };
    // Before the matches light nothing burns: the count is that of the unburnt fur.
    let unburnt = written(burn.start - 0.25);
    assert_eq!(written(0.0), unburnt);
    // While the burnt area spreads, every frame draws strictly fewer fur texels than the one
    // before; afterwards the count stays put.
    let mut previous = unburnt;
    let steps = 8;
    for k in 1..=steps {
        let t = burn.start + burn.spread_duration * k as f32 / steps as f32;
        let now = written(t);
        assert!(
            now < previous,
            "t = {t}: {now} texels drawn, {previous} before"
        );
        previous = now;
    }
    assert_eq!(written(burn.start + 2.0 * burn.spread_duration), previous);
    // The roots remain: a fully spread burn still draws the skin and the burnt stubs.
    assert!(previous > unburnt / 10, "{previous} of {unburnt}");
}

#[test]
fn wind_moves_the_fur_and_lets_it_return() {
    let scene = scene("wind", 160, 120);
    let prepared = PreparedScene::new(&scene).expect("prepares");
    let at = |t: f32| prepared.render_at(t, 64).expect("renders").rgba8;
    let (start, gust, back) = (at(0.0), at(0.5), at(1.5));
    assert_ne!(start, gust, "the fur moves in a gust");
    assert_ne!(gust, back, "and swings back");
    // The wind repeats every 1/frequency = 2 s: a whole period later the phase is exactly 0
    // again and so is every pixel.
    assert_eq!(start, at(2.0));
    let mut still = scene.clone();
    still.wind = None;
    let calm = PreparedScene::new(&still)
        .expect("prepares")
        .render_at(0.5, 64)
        .expect("renders")
        .rgba8;
    assert_ne!(calm, gust);
}

#[test]
fn frame_k_of_a_sequence_is_a_render_at_k_over_fps() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("effects-frames");
    let _ = std::fs::remove_dir_all(&dir);
    let scene_path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/burn.toml");
    let gif = dir.join("burn.gif");
    let status = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args([
            "render",
            scene_path.to_str().expect("path"),
            "--width",
            "96",
            "--height",
            "72",
        ])
        .args([
            "--frames",
            "4",
            "--fps",
            "0.5",
            "-o",
            dir.to_str().expect("path"),
        ])
        .args(["--animation", gif.to_str().expect("path")])
        .status()
        .expect("pelage runs");
    assert!(status.success());
    let single = dir.join("single.png");
    let status = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args([
            "render",
            scene_path.to_str().expect("path"),
            "--width",
            "96",
            "--height",
            "72",
        ])
        .args(["--time", "6", "-o", single.to_str().expect("path")])
        .status()
        .expect("pelage runs");
    assert!(status.success());
    // Frame 3 at 0.5 fps is the instant 3 / 0.5 = 6 s.
    let frame = std::fs::read(dir.join("frame_0003.png")).expect("frame 3");
    assert_eq!(frame, std::fs::read(&single).expect("single"));
    assert_ne!(
        frame,
        std::fs::read(dir.join("frame_0000.png")).expect("frame 0")
    );
    assert!(!dir.join("frame_0004.png").exists());
    // The animated GIF holds the four frames.
    let file = std::fs::File::open(&gif).expect("gif");
    let decoder =
        image::codecs::gif::GifDecoder::new(std::io::BufReader::new(file)).expect("decodes");
    let frames = image::AnimationDecoder::into_frames(decoder)
        .collect_frames()
        .expect("frames");
    assert_eq!(frames.len(), 4);
}

/// One straight vertical strand on a flat plane seen from straight above, far away (so that the
/// parallax between layers is a fraction of a pixel): the right edge of its footprint is that of
/// its top layer. `bend` is the scene's `[wind]` or `[gravity]` table.
fn one_strand_scene(dir: &std::path::Path, seed: u32, bend: &str) -> pelage::scene::Scene {
    // A 4 × 4 plane at y = 0, normal +y, u along +x and v along −z (so T × B = +y, eq. 3.3).
    let obj = "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n\
               vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\n\
               f 1/1 4/4 3/3\nf 1/1 3/3 2/2\n";
    std::fs::write(dir.join("plane.obj"), obj).expect("write plane");
    // A leading `time = …` line of `bend` is a top-level key.
    let (top, bend) = match bend.strip_prefix("time") {
        Some(_) => bend.split_once('\n').unwrap_or((bend, "")),
        None => ("", bend),
    };
    let text = format!(
        r#"seed = {seed}
{top}
[image]
width = 256
height = 256
background = [0.0, 0.0, 1.0]
[camera]
eye = [0.0, 100.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y_deg = 2.8
near = 50.0
far = 200.0
[mesh]
kind = "obj"
path = "plane.obj"
[fur]
number_of_strands = 1
number_of_shells = 30
texture_resolution = 128
model_difference = 1.0
texture_repeat = [1.0, 1.0]
slope_deg = 0.0
curl = 0.0
jitter = 0.0
min_height = 1.0
base_thickness = 0.02
tip_thickness = 0.02
colour_variation = 0.0
gaussian_sigma = 4.0
fins = false
[shading]
debug_view = "alpha"
{bend}
"#
    );
    pelage::scene::Scene::parse(&text, "one-strand.toml", dir).unwrap_or_else(|e| panic!("{e}"))
}

/// The rightmost column holding fur (a pixel that is neither the black skin of the alpha view
/// nor the blue background), if any.
fn rightmost_fur_column(image: &pelage::render::RenderedImage) -> Option<u32> {
    let w = image.width as usize;
    image
        .rgba8
        .chunks(4)
        .enumerate()
        .filter(|(_, p)| p[0] > 0 && p[0] == p[2])
        .map(|(i, _)| (i % w) as u32)
        .max()
}

#[test]
fn wind_gravity_motion_and_combing_move_a_single_strand_once() {
    // Thesis 3.3: the vertices move only back along −normal, the sideways motion is the texture
    // lookup. Applied twice (vertices and texture), the top layer moved twice the model's
    // displacement.
    let dir = common::scratch("one-strand");
    let wind = "[wind]\ndirection = [1.0, 0.0, 0.0]\nstrength = 0.8\nfrequency = 0.0\n\
                elasticity = 0.0\nmax_bend = 0.6\n";
    let gravity = "[gravity]\ndirection = [1.0, 0.0, 0.0]\nstrength = 0.35\n";
    // The object moves 1 along −x and back by 1 s, then rests where it started: at 1.1 s its fur
    // still lags on the spring, with the strand's root where it was at rest.
    let motion = "time = 1.1\n[motion]\npath = [[0.0, 0.0, 0.0, 0.0], [0.5, -1.0, 0.0, 0.0], \
                  [1.0, 0.0, 0.0, 0.0]]\nfrequency = 1.5\ndamping = 0.2\nresponse = 1.0\n";
    // Combing: a uniform direction map whose red leans the fur along u (+x on the plane) and
    // whose green (128, as near the middle as 8 bits go) leans it a hair along v, which does
    // not move the footprint's right edge.
    let comb_red = 191u8;
    image::RgbaImage::from_pixel(2, 2, image::Rgba([comb_red, 128, 0, 255]))
        .save(dir.join("comb.png"))
        .expect("write the direction map");
    let comb = "[maps]\ndirection = \"comb.png\"\n";
    for bend in [wind, gravity, motion, comb] {
        // A seed whose strand lies well inside the plane, so no part of it wraps over the tile.
        let found = (1..64).find_map(|seed| {
            let still = one_strand_scene(&dir, seed, "");
            let image = PreparedScene::new(&still).ok()?.render(64).ok()?;
            let right = rightmost_fur_column(&image)?;
            (40..140).contains(&right).then_some((seed, right))
        });
        let (seed, still_right) = found.expect("a seed with the strand inside the plane");
        let scene = one_strand_scene(&dir, seed, bend);
        let prepared = PreparedScene::new(&scene).expect("prepares");
        let moved = prepared.render(64).expect("renders");
        let moved_right = rightmost_fur_column(&moved).expect("fur drawn");
        // The model: the top layer (i = N − 1) at height h = (N − 1)/N · model_difference moves
        // sideways by bend · h, the bend being the wind's force, the gravity's strength, the
        // spring's lag or the combing lean.
        let n = scene.fur.number_of_shells as f32;
        let h = (n - 1.0) / n * scene.fur.model_difference;
        let bend_sine = match (&scene.wind, &scene.gravity, &scene.motion) {
            (Some(w), _, _) => w.direction_and_force(0.0).1,
            (None, Some(g), _) => g.strength,
            (None, None, Some(m)) => {
                let lag = pelage::shading::spring_lag(&m.path, scene.time, m.frequency, m.damping)
                    * m.response;
                assert!(lag.x > 0.05 && lag.x < 1.0, "the lag leans right: {lag}");
                lag.x
            }
            // The map's red r decodes to a lean of r/255 · 2 − 1 along u (0.498 for 191).
            (None, None, None) if scene.maps.direction.is_some() => {
                f32::from(comb_red) / 255.0 * 2.0 - 1.0
            }
            _ => 0.0,
        };
        assert!(bend_sine > 0.1, "{bend}: the model leans the strand right");
        let sideways = bend_sine * h;
        // The layer sits at height √(h² − sideways²) after the pull; seen from 100 units above
        // with a 2.8° field of view over 256 pixels.
        let height = (h * h - sideways * sideways).sqrt();
        let focal = 128.0 / (1.4f32.to_radians()).tan();
        let expected = sideways * focal / (100.0 - height);
        let measured = moved_right as f32 - still_right as f32;
        eprintln!(
            "{} moved {measured} px, model {expected:.2} px",
            bend.lines().next().unwrap_or("")
        );
        assert!(
            (measured - expected).abs() <= 1.0,
            "{bend}: the top layer moved {measured} px, the model says {expected:.2} px"
        );
    }
}

#[test]
fn a_negative_model_difference_thins_the_object_inside_its_surface() {
    // Thesis figure 3.10: the same fur, grown from the surface moved inward, ends where the
    // thickened fur starts: the thinned object's outermost shell is the thickened one's skin.
    let thick = scene("gravity", 160, 120);
    let mut thin = thick.clone();
    thin.fur.model_difference = -thick.fur.model_difference;
    let thick = PreparedScene::new(&thick).expect("prepares");
    let thin = PreparedScene::new(&thin).expect("prepares");
    let d = thick.scene().fur.model_difference;
    for (a, b) in thick.mesh().vertices.iter().zip(&thin.mesh().vertices) {
        let moved = b.position - a.position;
        assert!(
            (moved + a.normal * d).length() < 1e-5,
            "skin moved inward by |d|"
        );
    }
    assert_eq!(thick.shell_offsets(), thin.shell_offsets());
    // The thinned object covers less of the image than the thickened one.
    let covered = |p: &PreparedScene| {
        let image = p.render(64).expect("renders");
        let bg = p.scene().image.background;
        let bg = [bg.x, bg.y, bg.z].map(|c| (c * 255.0).round() as u8);
        image.rgba8.chunks(4).filter(|px| px[..3] != bg).count()
    };
    assert!(covered(&thin) < covered(&thick));
}

/// Median over columns 200..440 of the first row from the top that is not background.
fn fur_top_row(image: &pelage::render::RenderedImage) -> u32 {
    let w = image.width as usize;
    let px = |x: usize, y: usize| &image.rgba8[(y * w + x) * 4..(y * w + x) * 4 + 3];
    let background = px(0, 0).to_vec();
    let mut rows: Vec<u32> = (200..440)
        .map(|x| {
            (0..image.height as usize)
                .find(|&y| {
                    px(x, y)
                        .iter()
                        .zip(&background)
                        .map(|(a, b)| (i32::from(*a) - i32::from(*b)).abs())
                        .sum::<i32>()
                        > 12
                })
                .unwrap_or(image.height as usize) as u32
        })
        .collect();
    rows.sort_unstable();
    rows[rows.len() / 2]
}

#[test]
fn without_the_pull_the_bent_fur_stands_as_tall_as_the_unbent() {
    // Thesis figure 3.16: animating "solely in the fragment shader" leaves every layer at its
    // full height while its texture moves sideways, so the strands stretch; the pull along
    // −normal (3.3) lowers the bent fur. The torus's near top seen from the side.
    let stretched = scene("excessive-bending", 640, 480);
    assert!(stretched.wind.as_ref().is_some_and(|w| !w.keep_length));
    let mut kept = stretched.clone();
    if let Some(w) = kept.wind.as_mut() {
        w.keep_length = true;
    }
    let mut still = stretched.clone();
    still.wind = None;
    let top = |s: &pelage::scene::Scene| {
        fur_top_row(
            &PreparedScene::new(s)
                .expect("prepares")
                .render(64)
                .expect("renders"),
        ) as i32
    };
    let (still, kept, stretched) = (top(&still), top(&kept), top(&stretched));
    assert!(
        (stretched - still).abs() <= 4,
        "stretched fur top at row {stretched}, unbent at {still}"
    );
    assert!(
        kept - still >= 8,
        "the pulled-back fur's top (row {kept}) is not below the unbent's ({still})"
    );
}
