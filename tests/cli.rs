//! The `pelage` binary as a user runs it: identical files for any thread count and tile size,
//! bad input answered with exit status 2 and a one-line message naming what is wrong.

mod common;
use common::{pelage, scratch};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `pelage render` on bad input and checks the contract: exit 2, one line, no panic.
fn refused(args: &[&str], expect: &str) {
    let o = pelage(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains(expect),
        "{args:?}: expected {expect:?} in {err:?}"
    );
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "{args:?}: one line expected: {err}"
    );
}

#[test]
fn render_is_identical_for_threads_and_tiles() {
    let dir = scratch("identical");
    let mut files = Vec::new();
    for (threads, tile) in [("1", "64"), ("2", "64"), ("2", "16"), ("1", "16")] {
        let out = dir.join(format!("t{threads}-{tile}.png"));
        let o = pelage(&[
            "render",
            "--width",
            "200",
            "--height",
            "150",
            "--threads",
            threads,
            "--tile",
            tile,
            "-o",
            out.to_str().expect("utf-8 path"),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        files.push(std::fs::read(&out).expect("png"));
    }
    assert!(
        files.iter().all(|f| f == &files[0]),
        "renders differ across --threads/--tile"
    );
    let img = common::decode_rgba8(&files[0]);
    assert_eq!((img.width(), img.height()), (200, 150));
    // The furred torus covers the middle of the image; the corners are background.
    assert_ne!(img.get_pixel(100, 90), img.get_pixel(2, 2));
}

#[test]
fn absurd_sizes_and_arguments_are_refused() {
    let out = scratch("sizes").join("x.png");
    let o = out.to_str().expect("utf-8 path");
    refused(&["render", "--width", "0", "-o", o], "image.width = 0");
    refused(
        &["render", "--height", "100000", "-o", o],
        "image.height = 100000",
    );
    refused(
        &["render", "--width", "16000", "--height", "16000", "-o", o],
        "pixels exceeds",
    );
    refused(&["render", "--tile", "7", "-o", o], "--tile");
    assert!(!out.exists(), "nothing is written for refused input");
}

#[test]
fn bad_scenes_name_file_line_and_key() {
    let dir = scratch("scenes");
    let zero = write(
        &dir,
        "zero.toml",
        "[fur]\nnumber_of_strands = 10\nnumber_of_shells = 0\n",
    );
    refused(
        &["render", zero.to_str().expect("path")],
        "zero.toml:3: fur.number_of_shells = 0",
    );
    // Negative thins the object (figure 3.10); zero is no fur at all.
    let flat = write(&dir, "flat.toml", "[fur]\nmodel_difference = 0.0\n");
    refused(
        &["render", flat.to_str().expect("path")],
        "flat.toml:2: fur.model_difference",
    );
    let unknown = write(&dir, "unknown.toml", "[camera]\nfov = 30\n");
    refused(
        &["render", unknown.to_str().expect("path")],
        "unknown.toml:2",
    );
    let broken = write(&dir, "broken.toml", "[image\nwidth = 3\n");
    refused(&["render", broken.to_str().expect("path")], "broken.toml:1");
    refused(
        &["render", dir.join("absent.toml").to_str().expect("path")],
        "absent.toml",
    );
}

#[test]
fn bad_meshes_are_clear_errors() {
    let dir = scratch("meshes");
    let missing = write(
        &dir,
        "missing.toml",
        "[mesh]\nkind = \"obj\"\npath = \"nowhere.obj\"\n",
    );
    refused(&["render", missing.to_str().expect("path")], "nowhere.obj");
    write(&dir, "empty.obj", "# no faces\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    let empty = write(
        &dir,
        "empty.toml",
        "[mesh]\nkind = \"obj\"\npath = \"empty.obj\"\n",
    );
    refused(&["render", empty.to_str().expect("path")], "empty.obj");
    write(&dir, "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    let nan = write(
        &dir,
        "nan.toml",
        "[mesh]\nkind = \"obj\"\npath = \"nan.obj\"\n",
    );
    refused(&["render", nan.to_str().expect("path")], "nan.obj");
}

#[test]
fn an_obj_without_uvs_renders_with_a_warning() {
    let dir = scratch("obj");
    let cube = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
                f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    write(&dir, "cube.obj", cube);
    let scene = write(
        &dir,
        "cube.toml",
        "[image]\nwidth = 96\nheight = 72\n[camera]\neye = [3.0, 3.0, 4.0]\n[mesh]\nkind = \"obj\"\npath = \"cube.obj\"\n[fur]\nnumber_of_strands = 200\nmodel_difference = 0.2\n",
    );
    let out = dir.join("cube.png");
    let o = pelage(&[
        "render",
        scene.to_str().expect("path"),
        "-o",
        out.to_str().expect("path"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning"), "{}", stderr(&o));
    assert!(out.exists());
}

#[test]
fn bench_reports_json() {
    let report = bench_json(&["--frames", "2"]).expect("the oracle needs no adapter");
    let keys = json_keys(&report);
    for key in [
        "bake_ms",
        "median_frame_ms",
        "fps",
        "fragments_per_s",
        "backend",
        "adapter",
        "median_cpu_ms",
    ] {
        assert!(keys.contains(key), "{key} missing from {report}");
    }
    assert_eq!(report["frames"], 2);
}

/// The keys of a JSON object printed by `pelage bench`.
fn json_keys(value: &serde_json::Value) -> std::collections::BTreeSet<String> {
    value
        .as_object()
        .unwrap_or_else(|| panic!("a JSON object: {value}"))
        .keys()
        .cloned()
        .collect()
}

/// `pelage bench ARGS --json`, parsed; `None` (with a note) where there is no Vulkan adapter.
fn bench_json(args: &[&str]) -> Option<serde_json::Value> {
    let mut all = vec!["bench", "--width", "64", "--height", "48"];
    if !args.contains(&"--frames") {
        all.extend(["--frames", "1"]);
    }
    all.extend(args);
    all.push("--json");
    let o = pelage(&all);
    let err = stderr(&o);
    if err.contains("no Vulkan adapter") {
        assert_eq!(o.status.code(), Some(2), "{err}");
        eprintln!("skipped: no Vulkan adapter on this machine (install mesa-vulkan-drivers)");
        return None;
    }
    assert!(o.status.success(), "{all:?}: {err}");
    let text = String::from_utf8_lossy(&o.stdout);
    Some(serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}")))
}

#[cfg(feature = "gpu")]
#[test]
fn bench_on_the_gpu_reports_every_field_of_the_oracles() {
    let oracle = bench_json(&[]).expect("the oracle needs no adapter");
    let Some(gpu) = bench_json(&["--backend", "gpu", "--threads", "2"]) else {
        return;
    };
    let (oracle_keys, gpu_keys) = (json_keys(&oracle), json_keys(&gpu));
    let missing: Vec<&String> = oracle_keys.difference(&gpu_keys).collect();
    assert!(
        missing.is_empty(),
        "missing from the GPU's JSON: {missing:?}"
    );
    assert_eq!(gpu["backend"], "gpu");
    assert!(gpu["adapter"].is_string(), "{gpu}");
    assert_eq!(
        gpu["threads"], 2,
        "--threads sets lavapipe's threads: {gpu}"
    );
    assert!(gpu["median_frame_ms"].as_f64().is_some_and(|t| t > 0.0));
    assert!(gpu["readback_ms"].as_f64().is_some(), "{gpu}");
    assert_eq!(oracle["backend"], "cpu");
}

#[cfg(feature = "gpu")]
#[test]
fn bench_race_prints_both_backends_and_their_ratio() {
    let args = [
        "bench",
        "--width",
        "64",
        "--height",
        "48",
        "--frames",
        "2",
        "--threads",
        "2",
        "--race",
    ];
    let o = pelage(&args);
    let err = stderr(&o);
    if err.contains("no Vulkan adapter") {
        eprintln!("skipped: no Vulkan adapter on this machine (install mesa-vulkan-drivers)");
        return;
    }
    assert!(o.status.success(), "{err}");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("\noracle "), "{text}");
    assert!(text.contains("frame time: oracle is "), "{text}");
    assert!(
        text.contains("× faster than") || text.contains("× slower than"),
        "{text}"
    );
    let Some(race) = bench_json(&["--threads", "2", "--race"]) else {
        return;
    };
    assert_eq!(race["oracle"]["backend"], "cpu");
    assert_eq!(race["gpu"]["backend"], "gpu");
    assert_eq!(json_keys(&race["oracle"]), json_keys(&race["gpu"]));
    assert!(
        race["wall_ratio"].as_f64().is_some_and(|r| r > 0.0),
        "{race}"
    );
    assert!(
        race["summary"]
            .as_str()
            .is_some_and(|s| s.starts_with("oracle is ")),
        "{race}"
    );
}

/// `pelage bench --against BUILD ARGS --json`, parsed (this test binary against itself).
fn bench_against(args: &[&str]) -> Output {
    let mut all = vec![
        "bench",
        "--against",
        env!("CARGO_BIN_EXE_pelage"),
        "--width",
        "64",
        "--height",
        "48",
        "--frames",
        "1",
        "--rounds",
        "2",
    ];
    all.extend(args);
    all.push("--json");
    pelage(&all)
}

#[test]
fn bench_against_another_build_compares_them_round_by_round() {
    let parse = |o: &Output| -> serde_json::Value {
        assert!(o.status.success(), "{}", stderr(o));
        let text = String::from_utf8_lossy(&o.stdout);
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"))
    };
    let in_turn = parse(&bench_against(&["--threads", "1"]));
    assert_eq!(in_turn["mode"], "in turn");
    assert!(in_turn["cpu"].as_str().is_some_and(|c| !c.is_empty()));
    let rounds = in_turn["rounds"].as_array().expect("rounds");
    assert_eq!(rounds.len(), 2);
    for round in rounds {
        for key in ["median_cpu_ratio", "min_cpu_ratio"] {
            let ratio = round[key].as_f64().expect("a ratio");
            assert!(ratio.is_finite() && ratio > 0.0, "{round}");
        }
        // The same binary on the same scene: the same work.
        assert_eq!(
            round["this"]["fragments_per_frame"],
            round["against"]["fragments_per_frame"]
        );
        let ratio = round["against"]["median_cpu_ms"].as_f64().expect("ms")
            / round["this"]["median_cpu_ms"].as_f64().expect("ms");
        assert_eq!(round["median_cpu_ratio"].as_f64(), Some(ratio));
    }
    let spread = &in_turn["median_cpu_ratio"];
    let (min, median, max) = (
        spread["min"].as_f64().expect("min"),
        spread["median"].as_f64().expect("median"),
        spread["max"].as_f64().expect("max"),
    );
    assert!(min <= median && median <= max, "{spread}");
    // Together: a core each where the process may run on two, else refused by name.
    let allowed = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("Cpus_allowed_list:"))?;
            let list = line.split(':').nth(1)?.trim().to_string();
            Some(
                list.split(',')
                    .map(|r| match r.split_once('-') {
                        Some((a, b)) => {
                            b.parse::<usize>()
                                .unwrap_or(0)
                                .saturating_sub(a.parse::<usize>().unwrap_or(0))
                                + 1
                        }
                        None => 1,
                    })
                    .sum::<usize>(),
            )
        });
    let together = bench_against(&["--together"]);
    match allowed {
        Some(n) if n >= 2 => assert_eq!(parse(&together)["mode"], "together"),
        Some(_) => {
            assert_eq!(together.status.code(), Some(2), "{}", stderr(&together));
            assert!(stderr(&together).contains("two cores"));
        }
        None => {}
    }
}

#[test]
fn bench_against_refuses_what_it_cannot_compare() {
    refused(
        &["bench", "--against", "no/such/pelage"],
        "--against no/such/pelage: no such file",
    );
    refused(&["bench", "--rounds", "3"], "--against");
    refused(&["bench", "--together"], "--against");
    let me = env!("CARGO_BIN_EXE_pelage");
    refused(&["bench", "--against", me, "--race"], "--race");
    refused(
        &["bench", "--against", me, "--together", "--threads", "2"],
        "one thread",
    );
    refused(&["bench", "--against", me, "--rounds", "0"], "--rounds");
    // A build that fails is named, in turn and together (where the machine has /bin/false).
    if Path::new("/bin/false").is_file() {
        for together in [false, true] {
            let mut args = vec!["bench", "--against", "/bin/false", "--rounds", "1"];
            args.extend(["--width", "32", "--height", "32", "--frames", "1"]);
            if together {
                args.push("--together");
            }
            let o = pelage(&args);
            let err = stderr(&o);
            assert_ne!(o.status.code(), Some(0), "{args:?}: {err}");
            let named = err.contains("/bin/false bench failed");
            assert!(
                named || (together && err.contains("two cores")),
                "{args:?}: {err}"
            );
            assert!(!err.contains("panicked"), "{err}");
        }
    }
}

#[test]
fn bench_refuses_an_unknown_backend_and_a_gpu_it_lacks() {
    refused(&["bench", "--backend", "vulkan"], "--backend");
    refused(&["bench", "--backend", "gpu", "--race"], "--race");
    refused(
        &["bench", "--adapter", "any"],
        "--adapter chooses the GPU's device: add --backend gpu or --race",
    );
    if !cfg!(feature = "gpu") {
        refused(&["bench", "--backend", "gpu"], "`gpu` feature");
        refused(&["bench", "--race"], "`gpu` feature");
    }
}

#[test]
fn diagram_draws_every_figure_the_same_every_time() {
    let dir = scratch("diagram");
    let all = dir.join("all");
    let o = pelage(&["diagram", "--all", "-o", all.to_str().expect("path")]);
    assert!(o.status.success(), "{}", stderr(&o));
    for n in 2..=7 {
        let file = all.join(format!("fig-3-{n}.png"));
        let img = common::open_rgba8(&file);
        assert_eq!(
            (img.width(), img.height()),
            (960, 540),
            "{}",
            file.display()
        );
    }
    let one = dir.join("one.png");
    for _ in 0..2 {
        let o = pelage(&[
            "diagram",
            "--figure",
            "3.4",
            "-o",
            one.to_str().expect("path"),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            std::fs::read(&one).expect("png"),
            std::fs::read(all.join("fig-3-4.png")).expect("png"),
            "--figure 3.4 and --all differ, or two runs differ"
        );
    }
    // The options change the strand and its cones.
    let coarse = dir.join("coarse.png");
    let o = pelage(&[
        "diagram",
        "--figure",
        "fig-3-3",
        "--circle-resolution",
        "4",
        "--strand-resolution",
        "3",
        "--seed",
        "7",
        "-o",
        coarse.to_str().expect("path"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(
        std::fs::read(&coarse).expect("png"),
        std::fs::read(all.join("fig-3-3.png")).expect("png")
    );
}

#[test]
fn diagram_refuses_bad_figures_and_resolutions() {
    let out = scratch("diagram-bad").join("x.png");
    let o = out.to_str().expect("utf-8 path");
    refused(&["diagram", "--figure", "3.9", "-o", o], "3.9");
    refused(&["diagram", "--figure", "torus", "-o", o], "torus");
    refused(&["diagram", "-o", o], "--figure");
    refused(&["diagram", "--figure", "3.2", "--all", "-o", o], "--all");
    refused(
        &[
            "diagram",
            "--figure",
            "3.3",
            "--circle-resolution",
            "2",
            "-o",
            o,
        ],
        "--circle-resolution",
    );
    refused(
        &[
            "diagram",
            "--figure",
            "3.3",
            "--strand-resolution",
            "100000",
            "-o",
            o,
        ],
        "--strand-resolution",
    );
    assert!(!out.exists(), "nothing is written for refused input");
}

#[test]
fn outputs_write_through_devices_links_and_standard_output_and_never_clobber() {
    let dir = scratch("outputs");
    let scene = write(
        &dir,
        "small.toml",
        "[image]\nwidth = 32\nheight = 24\n[fur]\nnumber_of_strands = 50\n",
    );
    let scene = scene.to_str().expect("path");
    let reference = dir.join("reference.png");
    let o = pelage(&["render", scene, "-o", reference.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let png = std::fs::read(&reference).expect("reference");
    // It says what it wrote, on standard output.
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        format!("{}: 32×24 8-bit PNG at t = 0 s\n", reference.display())
    );
    let exr = dir.join("linear.exr");
    let o = pelage(&["render", scene, "-o", exr.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).ends_with(": 32×24 OpenEXR (32-bit float) at t = 0 s\n")
    );
    let frames = dir.join("frames");
    let o = pelage(&[
        "render",
        scene,
        "--frames",
        "2",
        "--fps",
        "4",
        "-o",
        frames.to_str().expect("path"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        format!(
            "{}: 2 frames (frame_0000.png to frame_0001.png) at 4 fps\n",
            frames.display()
        )
    );

    // `-o -`: the PNG on standard output, no file named `-`.
    let o = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .current_dir(&dir)
        .args(["render", scene, "-o", "-"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(o.stdout, png);
    assert!(!dir.join("-").exists());

    // A symbolic link: its target is replaced, the link stays a link.
    let target = dir.join("target.png");
    std::fs::write(&target, b"old").expect("target");
    let link = dir.join("link.png");
    std::os::unix::fs::symlink("target.png", &link).expect("symlink");
    let o = pelage(&["render", scene, "-o", link.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        std::fs::symlink_metadata(&link)
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert_eq!(std::fs::read(&target).expect("target"), png);

    // A device is written through, not replaced.
    let o = pelage(&["render", scene, "-o", "/dev/null"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let null = std::fs::metadata("/dev/null").expect("/dev/null");
    assert!(!null.is_file(), "/dev/null is still a device");

    // A name longer than a file system allows is refused before any work; a long valid one
    // is written (the temporary name is short).
    let long = dir.join("n".repeat(300) + ".png");
    refused(
        &["render", scene, "-o", long.to_str().expect("path")],
        "longer than the 255",
    );
    let valid = dir.join("v".repeat(246) + ".png");
    let o = pelage(&["render", scene, "-o", valid.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(std::fs::read(&valid).expect("long name"), png);
    // Nothing else was left behind.
    let hidden = std::fs::read_dir(&dir)
        .expect("dir")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .count();
    assert_eq!(hidden, 0);
}

#[test]
fn a_closed_pipe_is_not_a_bug() {
    let dir = scratch("pipe");
    let scene = write(
        &dir,
        "small.toml",
        "[image]\nwidth = 32\nheight = 24\n[fur]\nnumber_of_strands = 50\n",
    );
    let png = dir.join("a.png");
    let o = pelage(&[
        "render",
        scene.to_str().expect("path"),
        "-o",
        png.to_str().expect("path"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let png = png.to_str().expect("path");
    for _ in 0..5 {
        // The reader closes at once: whatever pelage manages to write, it exits as compare
        // does (0, the images are equal), never as a bug (101).
        let mut child = Command::new(env!("CARGO_BIN_EXE_pelage"))
            .args(["compare", png, png, "--json"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("spawns");
        drop(child.stdout.take());
        let o = child.wait_with_output().expect("waits");
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        assert!(!stderr(&o).contains("internal error"), "{}", stderr(&o));
    }
}

/// Runs pelage with `args`, killing it (and failing) if it has not finished in 30 s: a FIFO
/// opened for reading would block forever.
fn pelage_within_30s(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawns");
    let start = std::time::Instant::now();
    while child.try_wait().expect("waits").is_none() {
        if start.elapsed() > std::time::Duration::from_secs(30) {
            let _ = child.kill();
            panic!("pelage {args:?} still running after 30 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

#[test]
fn pipes_devices_and_folders_are_refused_as_inputs_before_they_are_opened() {
    let dir = scratch("inputs");
    let fifo = dir.join("fifo");
    let made = Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let fifo = fifo.to_str().expect("path");
    let folder = dir.to_str().expect("path");
    let png = dir.join("a.png");
    let o = pelage(&[
        "render",
        write(&dir, "s.toml", "[image]\nwidth = 16\nheight = 12\n")
            .to_str()
            .expect("path"),
        "-o",
        png.to_str().expect("path"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let png = png.to_str().expect("path");
    let shard = dir.join("shard");
    std::fs::create_dir_all(&shard).expect("shard");
    let made = Command::new("mkfifo")
        .arg(shard.join("results.csv"))
        .status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let merged = dir.join("merged");
    let cases: Vec<Vec<&str>> = vec![
        vec!["render", fifo, "-o", png],
        vec!["render", "/dev/zero", "-o", png],
        vec!["render", folder, "-o", png],
        vec!["compare", fifo, png],
        vec!["compare", png, "/dev/zero"],
        vec![
            "sweep",
            "/dev/zero",
            "--param",
            "number_of_shells=2",
            "-o",
            folder,
        ],
        vec!["sweep", fifo, "--param", "number_of_shells=2", "-o", folder],
        vec![
            "sweep-merge",
            "-o",
            merged.to_str().expect("path"),
            shard.to_str().expect("path"),
        ],
    ];
    for args in cases {
        let o = pelage_within_30s(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("not a regular file") || err.contains("is a folder"),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}

#[test]
fn frame_times_past_the_time_range_are_refused_before_work() {
    let dir = scratch("fps");
    let scene = write(&dir, "s.toml", "[image]\nwidth = 16\nheight = 12\n");
    let frames = dir.join("frames");
    refused(
        &[
            "render",
            scene.to_str().expect("path"),
            "--frames",
            "1000",
            "--fps",
            "0.0001",
            "-o",
            frames.to_str().expect("path"),
        ],
        "past the largest time",
    );
    assert!(!frames.exists());
}

#[test]
fn a_stripe_period_lost_to_precision_is_refused() {
    // On the torus (points up to 8.4 from the origin) a period of 1e-5 is 840,000 periods:
    // f32 cannot place the bands any more, which painted the whole object.
    let dir = scratch("stripe");
    let scene = write(
        &dir,
        "s.toml",
        "[image]\nwidth = 16\nheight = 12\n[[stripes]]\nkind = \"axis\"\nperiod = 1e-5\n\
         width = 5e-6\nsoftness = 1e-6\n",
    );
    let png = dir.join("s.png");
    refused(
        &[
            "render",
            scene.to_str().expect("path"),
            "-o",
            png.to_str().expect("path"),
        ],
        "stripes[0].period",
    );
    assert!(!png.exists());
}

#[test]
fn compare_names_a_missing_input_before_blaming_the_report_folder() {
    let dir = scratch("missing-compare");
    let there = dir.join("there");
    std::fs::create_dir_all(&there).expect("folder");
    let missing = dir.join("nowhere");
    let report = dir.join("report");
    for (a, b) in [(&missing, &there), (&there, &missing)] {
        let args = [
            "compare",
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "-o",
            report.to_str().unwrap(),
        ];
        let o = pelage(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("nowhere: no such image or folder"), "{err}");
        assert!(!err.contains("-o "), "{err}");
    }
}

#[test]
fn export_summary_puts_the_count_before_the_list() {
    let dir = scratch("export-summary");
    let out = dir.join("torus-export");
    let o = pelage(&[
        "export",
        "--width",
        "32",
        "--height",
        "24",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out
        .lines()
        .find(|l| l.contains(" files ("))
        .unwrap_or_else(|| panic!("no summary in {out:?}"));
    let count: usize = line
        .split(": ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count in {line:?}"));
    assert!(count > 10, "{line}");
    assert!(
        line.contains("textures/") && !line.contains("textures/1"),
        "{line}"
    );
}

/// Every output is written as its name says and through links: an output folder named by a
/// symbolic link (to an earlier export or frame folder) is replaced where the link leads and the
/// link stays; a GIF, diagram or heat map under another format's extension is refused before
/// any work.
#[test]
fn output_folders_are_written_through_links_and_names_say_the_format() {
    let dir = scratch("through-links");
    let scene = write(
        &dir,
        "small.toml",
        "[image]\nwidth = 32\nheight = 24\n[fur]\nnumber_of_strands = 50\nnumber_of_shells = 4\n",
    );
    let scene = scene.to_str().expect("path");
    for (what, args) in [
        ("export", vec!["export", scene]),
        ("frames", vec!["render", scene, "--frames", "2"]),
    ] {
        let real = dir.join(format!("{what}-real"));
        let link = dir.join(format!("{what}-link"));
        let mut first = args.clone();
        first.extend(["-o", real.to_str().expect("path")]);
        let o = pelage(&first);
        assert_eq!(o.status.code(), Some(0), "{what}: {}", stderr(&o));
        std::os::unix::fs::symlink(&real, &link).expect("symlink");
        let marker = real.join("scene.json");
        let before = std::fs::metadata(real.join(if what == "export" {
            "oracle.png"
        } else {
            "frame_0000.png"
        }))
        .expect("first output")
        .modified()
        .expect("mtime");
        std::thread::sleep(std::time::Duration::from_millis(20));
        let mut again = args.clone();
        again.extend(["-o", link.to_str().expect("path")]);
        let o = pelage(&again);
        assert_eq!(o.status.code(), Some(0), "{what}: {}", stderr(&o));
        let meta = std::fs::symlink_metadata(&link).expect("link");
        assert!(
            meta.file_type().is_symlink(),
            "{what}: the link was replaced by a folder"
        );
        let after = std::fs::metadata(real.join(if what == "export" {
            "oracle.png"
        } else {
            "frame_0000.png"
        }))
        .expect("second output")
        .modified()
        .expect("mtime");
        assert!(
            after > before,
            "{what}: the folder the link leads to was not rewritten"
        );
        assert_eq!(marker.exists(), what == "export");
    }

    let no_work = |args: &[&str], says: &str| {
        let o = pelage(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
    };
    let gif = dir.join("anim.png");
    let frames = dir.join("never");
    no_work(
        &[
            "render",
            scene,
            "--frames",
            "2",
            "--animation",
            gif.to_str().expect("path"),
            "-o",
            frames.to_str().expect("path"),
        ],
        "the name says .png",
    );
    assert!(!gif.exists() && !frames.exists());
    let jpg = dir.join("d.jpg");
    no_work(
        &[
            "diagram",
            "--figure",
            "3.2",
            "-o",
            jpg.to_str().expect("path"),
        ],
        "written as a .png file",
    );
    assert!(!jpg.exists());
    let png = dir.join("frames-real/frame_0000.png");
    let png = png.to_str().expect("path");
    let heat = dir.join("h.jpg");
    no_work(
        &[
            "compare",
            png,
            png,
            "--heatmap",
            heat.to_str().expect("path"),
        ],
        "--heatmap",
    );
    assert!(!heat.exists());
}

/// `compare` never destroys or misreads its inputs: a report folder that holds a compared folder
/// is refused before anything is written, and a float image holding NaN is refused (a NaN is
/// never a match; rounded to 0 it would pass as black).
#[test]
fn compare_keeps_its_inputs_and_never_matches_nan() {
    let dir = scratch("compare-inputs");
    let black = image::RgbaImage::from_pixel(8, 6, image::Rgba([0, 0, 0, 255]));
    let reference = dir.join("X/images");
    let capture = dir.join("Y");
    std::fs::create_dir_all(&reference).expect("dir");
    std::fs::create_dir_all(&capture).expect("dir");
    black.save(reference.join("a.png")).expect("png");
    black.save(capture.join("a.png")).expect("png");
    let report = dir.join("X");
    let o = pelage(&[
        "compare",
        reference.to_str().expect("path"),
        capture.to_str().expect("path"),
        "-o",
        report.to_str().expect("path"),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("holds the compared folder"),
        "{}",
        stderr(&o)
    );
    assert!(
        reference.join("a.png").is_file(),
        "the reference image is gone"
    );
    assert!(!report.join("report.html").exists());

    let nan =
        image::Rgba32FImage::from_pixel(8, 6, image::Rgba([f32::NAN, f32::NAN, f32::NAN, 1.0]));
    let exr = dir.join("nan.exr");
    image::DynamicImage::ImageRgba32F(nan)
        .save(&exr)
        .expect("exr");
    let o = pelage(&[
        "compare",
        reference.join("a.png").to_str().expect("path"),
        exr.to_str().expect("path"),
        "--tolerance",
        "exact",
    ]);
    assert_ne!(
        o.status.code(),
        Some(0),
        "a NaN capture passed: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(stderr(&o).contains("NaN"), "{}", stderr(&o));
}
