//! Bad input through the real binary: every scene in `tests/malformed/` (some pointing at the
//! broken meshes and material libraries in `tests/malformed/meshes/`) and a list of bad command
//! lines must exit with status 2 and one line on stderr naming the file (and line and key, or
//! the argument), quickly, without a panic and without writing an output.
//!
//! Each scene's first line says what its message must contain: `# expect: TEXT`. Add a case by
//! adding a file; nothing here needs to change.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A refused input must be refused well within this (the huge ones before allocating).
const QUICK: Duration = Duration::from_secs(5);

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed")
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("malformed-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn pelage(args: &[&str]) -> (Output, Duration) {
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args(args)
        .output()
        .expect("pelage runs");
    (out, start.elapsed())
}

/// The contract for refused input; returns a description of the first breach.
fn check_refusal(what: &str, out: &Output, took: Duration, expect: &str) -> Result<(), String> {
    let err = String::from_utf8_lossy(&out.stderr);
    let problem = if out.status.code() != Some(2) {
        Some(format!("exit status {:?}, expected 2", out.status.code()))
    } else if err.contains("panicked") || err.contains("internal error") {
        Some("a panic".into())
    } else if err.trim_end().lines().count() != 1 {
        Some("more than one line".into())
    } else if !err.starts_with("error: ") {
        Some("no `error: ` prefix".into())
    } else if !err.contains(expect) {
        Some(format!("no {expect:?}"))
    } else if took > QUICK {
        Some(format!("took {took:?}"))
    } else {
        None
    };
    match problem {
        Some(p) => Err(format!("{what}: {p}\n    stderr: {}", err.trim_end())),
        None => Ok(()),
    }
}

#[test]
fn every_malformed_scene_is_refused_with_a_one_line_message() {
    let out_dir = scratch("scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(corpus())
        .expect("corpus")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 50, "corpus has {} scenes", scenes.len());
    let mut failures = Vec::new();
    for scene in &scenes {
        let bytes = std::fs::read(scene).expect("read scene");
        let first = String::from_utf8_lossy(bytes.split(|&b| b == b'\n').next().unwrap_or(&[]))
            .into_owned();
        let expect = first
            .strip_prefix("# expect: ")
            .unwrap_or_else(|| panic!("{}: first line must be `# expect: TEXT`", scene.display()))
            .trim()
            .to_string();
        let output = out_dir.join("out.png");
        let (out, took) = pelage(&[
            "render",
            scene.to_str().expect("utf-8 path"),
            "-o",
            output.to_str().expect("utf-8 path"),
            "--threads",
            "2",
        ]);
        let name = scene.file_name().expect("name").to_string_lossy();
        if let Err(e) = check_refusal(&name, &out, took, &expect) {
            failures.push(e);
        }
        if output.exists() {
            failures.push(format!("{name}: wrote {}", output.display()));
            let _ = std::fs::remove_file(&output);
        }
    }
    let leftovers: Vec<_> = std::fs::read_dir(&out_dir)
        .expect("list")
        .filter_map(Result::ok)
        .map(|e| e.file_name())
        .collect();
    assert!(leftovers.is_empty(), "files left behind: {leftovers:?}");
    assert!(
        failures.is_empty(),
        "{} of {} malformed scenes broke the contract:\n{}",
        failures.len(),
        scenes.len(),
        failures.join("\n")
    );
}

#[test]
fn bad_command_lines_are_refused_naming_the_argument() {
    let dir = scratch("arguments");
    let png = dir.join("x.png");
    let png = png.to_str().expect("utf-8 path");
    let frames = dir.join("frames");
    let frames = frames.to_str().expect("utf-8 path");
    let cluttered = dir.join("cluttered");
    std::fs::create_dir_all(&cluttered).expect("dir");
    std::fs::write(cluttered.join("notes.txt"), "keep me").expect("write");
    let cluttered = cluttered.to_str().expect("utf-8 path");
    let missing_dir = dir.join("no/such/folder/x.png");
    let missing_dir = missing_dir.to_str().expect("utf-8 path");
    let d = dir.to_str().expect("utf-8 path");
    let shell_textures = corpus().join("memory-shell-textures.toml");
    let shell_textures = shell_textures.to_str().expect("utf-8 path").to_string();
    let bake_work = corpus().join("bake-work.toml");
    let bake_work = bake_work.to_str().expect("utf-8 path").to_string();
    let thousand_seeds = format!(
        "seed={}",
        (1..=1000)
            .map(|s| s.to_string())
            .collect::<Vec<_>>()
            .join(",")
    );
    // Two 1024² images: a comparison needs over 100 MiB, known from their headers.
    let [big_a, big_b] = ["a", "b"].map(|name| {
        let path = dir.join(format!("{name}.png"));
        image::RgbaImage::new(1024, 1024)
            .save(&path)
            .expect("write png");
        path.to_str().expect("utf-8 path").to_string()
    });
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["render", "--width", "abc", "-o", png], "--width"),
        (vec!["render", "--width", "-5", "-o", png], "--width"),
        (vec!["render", "--width", "0", "-o", png], "image.width = 0"),
        (vec!["render", "--threads", "0", "-o", png], "--threads"),
        (vec!["render", "--tile", "7", "-o", png], "--tile"),
        (vec!["render", "--time", "nan", "-o", png], "time"),
        (vec!["render", "--frobnicate", "-o", png], "--frobnicate"),
        (vec!["frobnicate"], "frobnicate"),
        (
            vec!["render", "--max-memory", "8X", "-o", png],
            "--max-memory",
        ),
        (
            vec!["render", "--max-memory", "1K", "-o", png],
            "--max-memory",
        ),
        (vec!["render", "--max-work", "-3", "-o", png], "--max-work"),
        (vec!["render", "--max-work", "10", "-o", png], "--max-work"),
        (vec!["render", "--frames", "0", "-o", frames], "--frames"),
        (
            vec!["render", "--frames", "200000", "-o", frames],
            "--frames",
        ),
        (
            vec!["render", "--frames", "2", "--fps", "nan", "-o", frames],
            "--fps",
        ),
        (
            vec!["render", "--frames", "2", "--fps", "0", "-o", frames],
            "--fps",
        ),
        (
            vec!["render", "--animation", "a.gif", "-o", png],
            "--frames",
        ),
        (vec!["render", "-o", d], "is a folder"),
        (vec!["render", d, "-o", png], "not a regular file"),
        (vec!["render", "/dev/null", "-o", png], "/dev/null"),
        (vec!["render", "-o", missing_dir], "does not exist"),
        (
            vec!["render", "--frames", "2", "-o", cluttered],
            "notes.txt",
        ),
        (
            vec![
                "render",
                "--frames",
                "2",
                "--animation",
                missing_dir,
                "-o",
                frames,
            ],
            "--animation",
        ),
        (vec!["bench", "--frames", "0"], "--frames"),
        (vec!["bench", "--max-memory", "1M"], "--max-memory"),
        // Every command that renders applies render's estimates, before any work.
        (
            vec!["export", &shell_textures, "-o", frames],
            "the export needs about",
        ),
        (
            vec!["export", &bake_work, "-o", frames],
            "baking the fur needs about",
        ),
        (
            vec!["view", &shell_textures, "--frames", "1"],
            "the render needs about",
        ),
        (
            vec![
                "sweep",
                "--param",
                "fur.number_of_shells=4,256",
                "--param",
                "fur.texture_resolution=2048",
                "-o",
                frames,
            ],
            "point 1 (fur.number_of_shells=256 fur.texture_resolution=2048)",
        ),
        (
            vec![
                "sweep",
                "--param",
                &thousand_seeds,
                "--max-memory",
                "300M",
                "-o",
                frames,
            ],
            "the contact sheet needs about",
        ),
        (
            vec!["compare", &big_a, &big_b, "--max-memory", "64M"],
            "the comparison needs about",
        ),
    ];
    let mut failures = Vec::new();
    for (args, expect) in &cases {
        let (out, took) = pelage(args);
        if let Err(e) = check_refusal(&format!("{args:?}"), &out, took, expect) {
            failures.push(e);
        }
    }
    assert!(
        !Path::new(png).exists(),
        "nothing is written for refused input"
    );
    assert!(
        !Path::new(frames).exists(),
        "no frame folder for refused input"
    );
    assert!(
        failures.is_empty(),
        "{} bad command lines broke the contract:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn help_and_version_still_succeed() {
    for args in [["--help"], ["--version"]] {
        let (out, _) = pelage(&args);
        assert!(out.status.success(), "{args:?}");
        assert!(!out.stdout.is_empty(), "{args:?}");
    }
}

/// Memory reserved is memory counted: a render runs within an address-space limit
/// (`ulimit -v`) of twice its memory estimate. The scene is a dense torus (10⁶ triangles, most
/// covering no pixel) under 8 shells: the pipeline once reserved room for every submitted
/// triangle of every pending draw, ten times the estimate, and aborted here.
#[test]
fn a_render_runs_within_twice_its_memory_estimate_of_address_space() {
    use pelage::limits;
    let dir = scratch("address-space");
    let text = "[image]\nwidth = 320\nheight = 240\n\
                [mesh]\nkind = \"torus\"\nmodel_resolution = 1000000\n\
                [fur]\nnumber_of_strands = 200\nnumber_of_shells = 8\ntexture_resolution = 32\n";
    let scene_path = dir.join("dense.toml");
    std::fs::write(&scene_path, text).expect("write scene");
    let scene = pelage::scene::Scene::parse(text, "dense.toml", &dir).expect("valid scene");
    let work = limits::Workload {
        threads: 2,
        ..limits::Workload::default()
    };
    let estimate = limits::estimate_memory(&scene, limits::mesh_size(&scene).expect("size"), &work);
    let set_up = estimate
        .parts
        .iter()
        .find(|(name, _)| name.starts_with("set-up triangles"))
        .expect("set-up part")
        .1;
    assert!(
        set_up > estimate.total() / 2,
        "the set-up triangles dominate the estimate: {estimate:?}"
    );
    let limit_kib = 2 * estimate.total() / 1024;
    let output = dir.join("dense.png");
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v {limit_kib} && exec \"$0\" render \"$1\" -o \"$2\" --threads 2",
        ))
        .arg(env!("CARGO_BIN_EXE_pelage"))
        .arg(&scene_path)
        .arg(&output)
        .output()
        .expect("bash runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "render under ulimit -v {limit_kib} KiB (estimate {}): status {:?}\n{err}",
        limits::format_bytes(estimate.total()),
        out.status
    );
    assert!(output.is_file(), "no image written");

    // The comparison of two 1024² images with both maps, within twice its estimate.
    let [a, b] = ["a", "b"].map(|name| {
        let path = dir.join(format!("{name}.png"));
        image::RgbaImage::from_fn(1024, 1024, |x, y| {
            image::Rgba([x as u8, y as u8, (x ^ y) as u8, 255])
        })
        .save(&path)
        .expect("write png");
        path
    });
    let files = std::fs::metadata(&a).expect("a").len() + std::fs::metadata(&b).expect("b").len();
    let estimate = limits::compare_memory((1024, 1024), (1024, 1024), files).total();
    let limit_kib = 2 * estimate / 1024;
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v {limit_kib} && exec \"$0\" compare \"$1\" \"$2\" --heatmap \"$3\" \
             --flip-map \"$4\"",
        ))
        .arg(env!("CARGO_BIN_EXE_pelage"))
        .args([&a, &b, &dir.join("heat.png"), &dir.join("flip.png")])
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .expect("bash runs");
    assert!(
        out.status.success(),
        "compare under ulimit -v {limit_kib} KiB: status {:?}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );

    // A 1024² PNG whose 260 KB compressed iCCP chunk inflates to 256 MiB
    // (tests/malformed/images/iccp-bomb.png): the decoders keep at most
    // pelage::input::MAX_DECODER_EXTRA_BYTES of ancillary data, so it is compared within the
    // same budget (it took the whole 256 MiB before).
    let bomb = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/images/iccp-bomb.png");
    let files = 2 * std::fs::metadata(&bomb).expect("bomb").len();
    let estimate = limits::compare_memory((1024, 1024), (1024, 1024), files).total();
    let limit_kib = 2 * estimate / 1024;
    assert!(
        limit_kib < 256 * 1024,
        "the budget must be smaller than the inflated profile"
    );
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v {limit_kib} && exec \"$0\" compare \"$1\" \"$1\""
        ))
        .arg(env!("CARGO_BIN_EXE_pelage"))
        .arg(&bomb)
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .expect("bash runs");
    assert!(
        out.status.success(),
        "the iCCP bomb under ulimit -v {limit_kib} KiB: status {:?}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The limits refuse what is absurd, never a shipped scene: every scene in `scenes/` fits the
/// default budgets (memory, bake work, drawing work) with room to spare.
#[test]
fn every_shipped_scene_fits_the_default_budgets_with_room_to_spare() {
    use pelage::limits;
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&scenes)
        .expect("scenes")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 10, "{} scenes", paths.len());
    let work = limits::Workload {
        threads: 2,
        ..limits::Workload::default()
    };
    let spare = limits::Budgets {
        memory: limits::DEFAULT_MAX_MEMORY / 4,
        bake_work: limits::DEFAULT_MAX_BAKE_WORK / 4,
        draw_work: limits::DEFAULT_MAX_DRAW_WORK / 10,
    };
    for path in &paths {
        let scene = pelage::scene::Scene::load(path).expect("shipped scenes load");
        let mesh = limits::mesh_size(&scene).expect("mesh size");
        if let Err(e) = limits::check(&scene, mesh, &work, &spare) {
            panic!("{}: {e}", path.display());
        }
    }
}
