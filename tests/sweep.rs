//! `pelage sweep` and `pelage sweep-merge` as a user runs them: the folder's files, the CSV's
//! points, shards that merge into the whole sweep, and bad parameters refused with exit 2.

mod common;
use common::{pelage, scratch};

use std::process::Output;

/// A small, quick sweep: 2 × 2 points of the embedded torus at 96×72.
fn sweep_args(out: &str) -> Vec<String> {
    [
        "sweep",
        "--param",
        "number_of_shells=4,8",
        "--param",
        "shading.specular_tangents=1,3",
        "--width",
        "96",
        "--height",
        "72",
        "--frames",
        "1",
        "-o",
        out,
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

fn run(args: &[String]) -> Output {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = pelage(&args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The rows of results.csv without the timings: point and parameter values.
fn points_and_values(csv: &str) -> Vec<String> {
    csv.lines()
        .map(|l| l.split(',').take(3).collect::<Vec<_>>().join(","))
        .collect()
}

#[test]
fn a_sweep_writes_csv_renders_sheet_and_plot() {
    let dir = scratch("whole");
    let out = dir.join("all");
    run(&sweep_args(out.to_str().unwrap()));
    let csv = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
    assert_eq!(
        points_and_values(&csv),
        [
            "point,number_of_shells,shading.specular_tangents",
            "0,4,1",
            "1,4,3",
            "2,8,1",
            "3,8,3"
        ]
    );
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("bake_ms,median_frame_ms")
    );
    for file in [
        "contact_sheet.png",
        "fps.png",
        "frame_time.png",
        "fragments.png",
        "point_0000.png",
        "point_0003.png",
    ] {
        let image = common::open_rgba8(out.join(file));
        assert!(image.width() > 0);
    }
    // A point's render is the render of the scene with that value.
    let single = dir.join("single.png");
    run(&[
        "render",
        "--width",
        "96",
        "--height",
        "72",
        "-o",
        single.to_str().unwrap(),
    ]
    .map(String::from));
    let with_value = dir.join("with-value.png");
    let scene = dir.join("eight.toml");
    let text =
        pelage::scene::DEFAULT_SCENE.replace("number_of_shells = 40", "number_of_shells = 8");
    assert_ne!(
        text,
        pelage::scene::DEFAULT_SCENE,
        "the default scene sets number_of_shells"
    );
    std::fs::write(&scene, text).expect("scene");
    // Relative paths in the default scene (none today) would resolve from its folder.
    run(&[
        "render",
        scene.to_str().unwrap(),
        "--width",
        "96",
        "--height",
        "72",
        "-o",
        with_value.to_str().unwrap(),
    ]
    .map(String::from));
    assert_eq!(
        std::fs::read(out.join("point_0002.png")).unwrap(),
        std::fs::read(&with_value).unwrap(),
        "point 2 (number_of_shells=8, one tangent) equals a render with that value"
    );
}

#[test]
fn shards_merge_into_the_whole_sweep() {
    let dir = scratch("shards");
    let mut shard_dirs = Vec::new();
    for i in 1..=3 {
        let out = dir.join(format!("shard{i}"));
        let mut args = sweep_args(out.to_str().unwrap());
        args.extend(["--shard".to_string(), format!("{i}/3")]);
        run(&args);
        shard_dirs.push(out);
    }
    let merged = dir.join("merged");
    let mut args = vec![
        "sweep-merge".to_string(),
        "-o".into(),
        merged.to_str().unwrap().into(),
    ];
    args.extend(shard_dirs.iter().map(|d| d.to_str().unwrap().to_string()));
    run(&args);
    let csv = std::fs::read_to_string(merged.join("results.csv")).expect("merged csv");
    assert_eq!(
        points_and_values(&csv)[1..],
        ["0,4,1", "1,4,3", "2,8,1", "3,8,3"]
    );
    for k in 0..4 {
        assert!(merged.join(format!("point_{k:04}.png")).is_file());
    }
    assert!(merged.join("contact_sheet.png").is_file());
    // The same shard twice is refused: its points would count twice.
    let twice = pelage(&[
        "sweep-merge",
        "-o",
        dir.join("twice").to_str().unwrap(),
        shard_dirs[0].to_str().unwrap(),
        shard_dirs[0].to_str().unwrap(),
    ]);
    assert_eq!(twice.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&twice.stderr).contains("their points overlap"));
    // A shard left out is refused, naming it.
    let refused = |shards: &[&std::path::Path], needle: &str| {
        let out = dir.join("refused");
        let mut args = vec!["sweep-merge", "-o", out.to_str().unwrap()];
        args.extend(shards.iter().map(|d| d.to_str().unwrap()));
        let o = pelage(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{needle}: {err}");
        assert!(!out.exists(), "nothing is written for refused shards");
    };
    refused(&[&shard_dirs[0], &shard_dirs[2]], "shard 2/3 is missing");
    // A shard of another sweep (other values) is refused, though its columns match.
    let other = dir.join("other2");
    let mut args = sweep_args(other.to_str().unwrap());
    args[2] = "number_of_shells=5,9".into();
    args.extend(["--shard".to_string(), "2/3".to_string()]);
    run(&args);
    refused(
        &[&shard_dirs[0], &other, &shard_dirs[2]],
        "are from different sweeps",
    );
    // A shard whose rows were tampered with (a point of another shard) is refused.
    let tampered = dir.join("tampered");
    std::fs::create_dir_all(&tampered).expect("dir");
    for file in ["sweep.txt", "results.csv"] {
        std::fs::copy(shard_dirs[1].join(file), tampered.join(file)).expect("copy");
    }
    let csv = std::fs::read_to_string(tampered.join("results.csv")).expect("csv");
    let first_row = csv.lines().nth(1).expect("a row").to_string();
    let moved = first_row.replacen("1,", "2,", 1);
    std::fs::write(
        tampered.join("results.csv"),
        csv.replace(&first_row, &moved),
    )
    .expect("write");
    refused(
        &[&shard_dirs[0], &tampered, &shard_dirs[2]],
        "does not belong to shard 2/3",
    );
    // A shard's point images must be there, be images, and lie inside the shard.
    let copy_of_second = |name: &str| {
        let copy = dir.join(name);
        std::fs::create_dir_all(&copy).expect("dir");
        for entry in std::fs::read_dir(&shard_dirs[1]).expect("list") {
            let entry = entry.expect("entry");
            std::fs::copy(entry.path(), copy.join(entry.file_name())).expect("copy");
        }
        let csv = std::fs::read_to_string(copy.join("results.csv")).expect("csv");
        let point: usize = csv.lines().nth(1).expect("a row")[..1]
            .parse()
            .expect("point");
        (copy.clone(), copy.join(format!("point_{point:04}.png")))
    };
    let (missing, image) = copy_of_second("missing");
    std::fs::remove_file(&image).expect("remove");
    refused(&[&shard_dirs[0], &missing, &shard_dirs[2]], "is missing");
    let (not_image, image) = copy_of_second("not_image");
    std::fs::write(&image, "not a PNG").expect("write");
    refused(
        &[&shard_dirs[0], &not_image, &shard_dirs[2]],
        "is not an image",
    );
    #[cfg(unix)]
    {
        let (linked, image) = copy_of_second("linked");
        let outside = dir.join("outside.png");
        std::fs::copy(&image, &outside).expect("copy");
        std::fs::remove_file(&image).expect("remove");
        std::os::unix::fs::symlink(&outside, &image).expect("link");
        refused(
            &[&shard_dirs[0], &linked, &shard_dirs[2]],
            "outside the shard",
        );
    }
}

#[test]
fn a_sweep_replaces_an_earlier_sweep_whole_and_never_mixes() {
    let dir = scratch("replace");
    let out = dir.join("sweep");
    run(&sweep_args(out.to_str().unwrap()));
    assert!(out.join("point_0003.png").is_file());
    // Two points into the same folder: the four of the earlier sweep are all gone.
    let mut args = sweep_args(out.to_str().unwrap());
    args.drain(3..5);
    run(&args);
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "contact_sheet.png",
            "fps.png",
            "fragments.png",
            "frame_time.png",
            "point_0000.png",
            "point_0001.png",
            "results.csv",
            "sweep.txt"
        ]
    );
    // A folder holding anything else is refused before work.
    std::fs::write(out.join("notes.txt"), "mine").expect("write");
    let o = pelage(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("notes.txt"), "{err}");
    assert!(out.join("notes.txt").is_file() && out.join("point_0001.png").is_file());
}

#[test]
fn bad_parameters_are_refused_before_rendering() {
    let dir = scratch("bad");
    for (param, needle) in [
        ("number_of_shells=10,0", "number_of_shells"),
        ("fur.not_a_key=3", "not_a_key"),
        ("number_of_spots=13", "number_of_spots"),
        ("no_equals_sign", "NAME=V1"),
        ("camera_distance=-3", "camera_distance"),
    ] {
        let out = dir.join("never");
        let o = pelage(&["sweep", "--param", param, "-o", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{param}: {err}");
        assert!(err.contains(needle), "{param}: {err}");
        assert!(!err.contains("panicked"), "{param}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{param}: {err}");
        assert!(!out.exists(), "{param}: nothing is written for a bad sweep");
    }
    let o = pelage(&[
        "sweep",
        "--param",
        "number_of_shells=4",
        "--against-oracle",
        "-o",
        dir.join("y").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--backend gpu"));
    if !cfg!(feature = "gpu") {
        let o = pelage(&[
            "sweep",
            "--param",
            "number_of_shells=4",
            "--backend",
            "gpu",
            "-o",
            dir.join("z").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&o.stderr).contains("feature"));
    }
    let o = pelage(&[
        "sweep",
        "--param",
        "number_of_shells=4",
        "--shard",
        "4/3",
        "-o",
        dir.join("x").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn the_gnu_parallel_recipe_gives_the_whole_sweep() {
    // docs/cluster/sweep-parallel.sh: 3 shards at once with GNU parallel, merged; the same
    // points, values and images as one sweep. Skipped without `parallel` unless
    // PELAGE_REQUIRE_PARALLEL=1 (CI installs it).
    let has_parallel = std::process::Command::new("parallel")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_parallel {
        assert!(
            std::env::var("PELAGE_REQUIRE_PARALLEL").as_deref() != Ok("1"),
            "PELAGE_REQUIRE_PARALLEL=1 but GNU parallel is missing: apt-get install parallel"
        );
        eprintln!(
            "SKIPPED: {} needs GNU parallel (run .ci/setup)",
            std::thread::current().name().unwrap_or("a test")
        );
        return;
    }
    let dir = scratch("parallel");
    let whole = dir.join("whole");
    run(&sweep_args(whole.to_str().unwrap()));
    let merged = dir.join("merged");
    let recipe = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/cluster/sweep-parallel.sh"
    );
    let args = sweep_args("unused");
    let o = std::process::Command::new("bash")
        .arg(recipe)
        .arg("3")
        .arg(&merged)
        .args(&args[1..args.len() - 2])
        .env("PELAGE", env!("CARGO_BIN_EXE_pelage"))
        .env("JOBS", "3")
        .output()
        .expect("bash runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = |d: &std::path::Path| {
        points_and_values(&std::fs::read_to_string(d.join("results.csv")).expect("csv"))
    };
    assert_eq!(csv(&merged), csv(&whole));
    for k in 0..4 {
        let file = format!("point_{k:04}.png");
        assert_eq!(
            std::fs::read(merged.join(&file)).expect("merged point"),
            std::fs::read(whole.join(&file)).expect("whole point"),
            "{file}"
        );
    }
    assert!(merged.join("fps.png").is_file() && merged.join("contact_sheet.png").is_file());
    // The shards' folder is removed afterwards.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("list")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().contains(".shards."))
        .collect();
    assert!(left.is_empty());
}
