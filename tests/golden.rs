//! Golden images: every scene in `scenes/` is rendered and compared pixel-exact with its
//! reference in `reference_images/`.
//!
//! On a mismatch the test writes `target/golden-diff/<scene>.png` (expected | differing pixels
//! in red | actual) and fails. To regenerate references on purpose, run
//! `PELAGE_BLESS=1 cargo test --release --test golden`: it writes every reference, then fails
//! so that a blessing run is never mistaken for a passing one.

mod common;

use pelage::render::PreparedScene;
use pelage::scene::Scene;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The scene's image, after checking that the fragment stage's scalar twin gives the same bytes,
/// unless `PELAGE_GOLDEN_SKIP_TWIN=1`: CI's rerun at a third SIMD level sets it, since the twin is
/// scalar code whose bytes the level cannot change, and the runs at the best level and at the
/// baseline have compared it already.
fn render(scene: &Scene, tile: u32) -> Vec<u8> {
    if std::env::var("PELAGE_GOLDEN_SKIP_TWIN").as_deref() == Ok("1") {
        let prepared = PreparedScene::new(scene).expect("scene prepares");
        return prepared.render(tile).expect("scene renders").rgba8;
    }
    common::render_checking_twin(scene, tile, "golden")
}

fn write_diff(name: &str, width: u32, height: u32, expected: &[u8], actual: &[u8]) -> PathBuf {
    let dir = root().join("target/golden-diff");
    std::fs::create_dir_all(&dir).expect("diff folder");
    let (w, h) = (width as usize, height as usize);
    let mut out = vec![0u8; 3 * w * h * 4];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) * 4;
            let row = y * 3 * w;
            let differs = expected[i..i + 4] != actual[i..i + 4];
            out[(row + x) * 4..(row + x) * 4 + 4].copy_from_slice(&expected[i..i + 4]);
            let mask = if differs {
                [255, 0, 0, 255]
            } else {
                [0, 0, 0, 255]
            };
            out[(row + w + x) * 4..(row + w + x) * 4 + 4].copy_from_slice(&mask);
            out[(row + 2 * w + x) * 4..(row + 2 * w + x) * 4 + 4]
                .copy_from_slice(&actual[i..i + 4]);
        }
    }
    let path = dir.join(format!("{name}.png"));
    pelage::output::write_png(&path, width * 3, height, &out).expect("diff image");
    path
}

/// Loads a scene for golden testing. Goldens are at most 640×480 to keep the suite fast: a
/// larger scene (the thesis's 1366×768 configuration) is checked at 640 pixels wide, same aspect.
fn load_scene(name: &str) -> Scene {
    let path = root().join("scenes").join(format!("{name}.toml"));
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    if scene.image.width > 640 || scene.image.height > 480 {
        let scale = (640.0 / scene.image.width as f32).min(480.0 / scene.image.height as f32);
        scene.image.width = ((scene.image.width as f32 * scale) as u32).max(1);
        scene.image.height = ((scene.image.height as f32 * scale) as u32).max(1);
    }
    scene
}

fn blessing() -> bool {
    std::env::var_os("PELAGE_BLESS").is_some()
}

/// Which picture of a scene a reference holds.
#[derive(Clone, Copy, Debug)]
enum Variant {
    /// The scene as written.
    AsWritten,
    /// The scene at another instant, seconds.
    Time(f32),
    /// The camera moved along its line of sight to this distance from its target.
    Distance(f32),
}

impl Variant {
    fn apply(self, scene: &mut Scene) {
        match self {
            Variant::AsWritten => {}
            Variant::Time(t) => scene.time = t,
            Variant::Distance(d) => scene.camera = scene.camera.at_distance(d),
        }
    }

    fn file_name(self, name: &str) -> String {
        match self {
            Variant::AsWritten => format!("{name}.png"),
            Variant::Time(t) => format!("{name}@t{t}.png"),
            Variant::Distance(d) => format!("{name}@d{d}.png"),
        }
    }
}

fn check_scene(name: &str, variant: Variant) {
    let mut scene = load_scene(name);
    variant.apply(&mut scene);
    let file = variant.file_name(name);
    let actual = render(&scene, 64);
    let reference = root().join("reference_images").join(&file);
    if blessing() {
        pelage::output::write_png(&reference, scene.image.width, scene.image.height, &actual)
            .expect("write reference");
        eprintln!("wrote {}", reference.display());
        return;
    }
    // The library's decoder, not `image::open` (see `common::open_rgba8`).
    let expected = pelage::input::read_image(&reference, "reference image")
        .unwrap_or_else(|e| panic!("{e} (regenerate with PELAGE_BLESS=1)"));
    assert_eq!(
        (expected.width(), expected.height()),
        (scene.image.width, scene.image.height),
        "{file}: reference size differs"
    );
    if expected.as_raw() != &actual {
        let differing = common::differing_pixels(expected.as_raw(), &actual);
        let stem = file.trim_end_matches(".png");
        let diff = write_diff(
            stem,
            scene.image.width,
            scene.image.height,
            expected.as_raw(),
            &actual,
        );
        panic!(
            "{file}: {differing} pixels differ from {}; see {}",
            reference.display(),
            diff.display()
        );
    }
}

/// Every scene also renders byte-identically with other thread counts and tile sizes (at its
/// most demanding variant: the latest instant, the nearest distance). The scene is baked again
/// inside each pool (baking must not depend on the thread count either) and that bake renders at
/// both tile sizes: six renders, each one a combination no other covers.
fn check_invariance(name: &str, variant: Variant) {
    let mut scene = load_scene(name);
    variant.apply(&mut scene);
    let mut first: Option<(usize, u32, Vec<u8>)> = None;
    for threads in [1, 2, 8] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let prepared = PreparedScene::new(&scene).expect("prepares");
            for tile in [64, 16] {
                let image = prepared.render(tile).expect("renders").rgba8;
                match &first {
                    None => first = Some((threads, tile, image)),
                    Some((t0, tile0, reference)) => assert!(
                        image == *reference,
                        "{name}: threads {threads}, tile {tile} differ from threads {t0}, tile {tile0}"
                    ),
                }
            }
        });
    }
}

/// `name => "file"` checks the scene as written; `name => "file" at times [..]` or
/// `at distances [..]` checks one reference per instant or camera distance.
macro_rules! golden {
    ($($name:ident => $file:literal $(at $kind:ident [$($v:expr),+])?),* $(,)?) => {
        $(
            mod $name {
                #[allow(unused_imports)]
                use super::Variant;
                fn variants() -> Vec<Variant> {
                    golden!(@variants $($kind [$($v),+])?)
                }
                #[test]
                fn matches_reference() {
                    for v in variants() {
                        super::check_scene($file, v);
                    }
                    // A blessing run writes every reference, then fails on purpose so that it is
                    // never mistaken for a passing one.
                    assert!(!super::blessing(), "PELAGE_BLESS is set: references written; unset it and rerun");
                }
                #[test]
                fn identical_for_threads_and_tiles() {
                    let last = *variants().last().expect("a variant");
                    super::check_invariance($file, last);
                }
            }
        )*
        const LISTED: &[&str] = &[$($file),*];
    };
    (@variants) => { vec![Variant::AsWritten] };
    (@variants times [$($v:expr),+]) => { vec![$(Variant::Time($v)),+] };
    (@variants distances [$($v:expr),+]) => { vec![$(Variant::Distance($v)),+] };
}

golden! {
    torus => "torus",
    tangents => "tangents",
    specular => "specular",
    specular_eq35 => "specular-eq35",
    leg => "leg",
    bull => "bull",
    face => "face",
    face_thinned => "face-thinned",
    thesis_4_1 => "thesis-4-1",
    thesis_4_2 => "thesis-4-2",
    thesis_4_4 => "thesis-4-4",
    thesis_4_6 => "thesis-4-6" at times [2.0, 12.0],
    cow => "cow",
    spots => "spots",
    wind => "wind" at times [0.0, 0.5, 1.5],
    excessive_bending => "excessive-bending",
    burn => "burn" at times [0.0, 1.0, 3.0, 6.0, 10.0],
    distance => "distance" at distances [24.0, 17.0, 12.0, 9.0],
    painted_length => "painted-length",
    density => "density",
    combed => "combed",
    gravity => "gravity",
    lod_flyaway => "lod-flyaway" at times [0.0, 0.8, 2.0, 4.0],
    fox => "fox" at times [0.0, 0.4, 0.8],
    tail => "tail" at times [0.0, 0.5, 1.25],
}

#[test]
fn every_scene_has_a_golden_test() {
    let mut on_disk: Vec<String> = std::fs::read_dir(root().join("scenes"))
        .expect("scenes folder")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = LISTED.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(
        on_disk, listed,
        "every scene in scenes/ needs an entry in the golden! list"
    );
}
