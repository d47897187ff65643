//! Choosing the GPU backend's device from the command line: `pelage gpu-info` lists the
//! adapters, `render --backend gpu --api vulkan|gl --adapter NAME|INDEX` picks one, and an
//! unknown API, an adapter that does not exist or the flags without `--backend gpu` give one
//! clear line and exit 2, never a panic. Without the `gpu` feature, `gpu-info` says so (exit 2).

mod common;

use common::pelage;

/// stderr's lines (pelage quiets Mesa's `XDG_RUNTIME_DIR` complaint itself: see
/// `a_headless_run_without_a_runtime_folder_prints_no_driver_noise`).
fn own_errors(out: &std::process::Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .map(str::to_string)
        .collect()
}

fn refused(args: &[&str], says: &str) {
    let out = pelage(args);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {out:?}");
    let lines = own_errors(&out);
    assert_eq!(lines.len(), 1, "{args:?}: one line, got {lines:?}");
    assert!(
        lines[0].contains(says),
        "{args:?}: {lines:?} lacks {says:?}"
    );
}

#[test]
fn api_and_adapter_need_the_gpu_backend() {
    refused(&["render", "--api", "gl", "-o", "x.png"], "--backend gpu");
    refused(
        &["render", "--adapter", "0", "-o", "x.png"],
        "--backend gpu",
    );
}

#[cfg(not(feature = "gpu"))]
#[test]
fn gpu_info_says_the_feature_is_missing() {
    refused(&["gpu-info"], "`gpu` feature");
}

#[cfg(feature = "gpu")]
mod gpu {
    use super::*;

    const SMALL: [&str; 4] = ["--width", "32", "--height", "24"];

    #[test]
    fn gpu_info_lists_the_software_adapters() {
        let out = pelage(&["gpu-info"]);
        assert_eq!(out.status.code(), Some(0), "{out:?}");
        let text = String::from_utf8_lossy(&out.stdout);
        // lavapipe (Vulkan) is installed wherever the GPU tests run (listed first, unless
        // `VK_ICD_FILENAMES` names SwiftShader before it).
        assert!(
            text.lines()
                .any(|l| l.starts_with("vulkan ") && l.contains("llvmpipe")),
            "{text}"
        );
        let out = pelage(&["gpu-info", "--api", "vulkan"]);
        assert_eq!(out.status.code(), Some(0));
        assert!(!String::from_utf8_lossy(&out.stdout).contains("gl "));
        refused(&["gpu-info", "--api", "metal"], "--api \"metal\"");
    }

    #[test]
    fn unknown_api_or_adapter_is_refused_in_one_line() {
        let dir = common::scratch("refused");
        let png = dir.join("x.png");
        let png = png.to_str().expect("path");
        let render = |extra: &[&str]| {
            let mut args = vec!["render", "--backend", "gpu", "-o", png];
            args.extend(SMALL);
            args.extend(extra);
            args.into_iter().map(str::to_string).collect::<Vec<_>>()
        };
        let call = |extra: &[&str], says: &str| {
            let args = render(extra);
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            refused(&args, says);
            assert!(!std::path::Path::new(png).exists(), "nothing written");
        };
        call(&["--api", "metal"], "unknown API");
        call(&["--adapter", "99"], "--adapter 99: no such Vulkan adapter");
        call(
            &["--adapter", "no-such-gpu"],
            "no Vulkan adapter has this name",
        );
    }

    /// Mesa's Vulkan drivers complain on stderr when `XDG_RUNTIME_DIR` is unset (CI,
    /// containers); pelage gives them a private folder, so a successful run prints its own line
    /// alone.
    #[test]
    fn a_headless_run_without_a_runtime_folder_prints_no_driver_noise() {
        let dir = common::scratch("headless");
        let png = dir.join("x.png");
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_pelage"))
            .args(["render", "--backend", "gpu", "-o"])
            .arg(&png)
            .args(SMALL)
            .env_remove("XDG_RUNTIME_DIR")
            .output()
            .expect("runs");
        assert_eq!(out.status.code(), Some(0), "{out:?}");
        let lines = own_errors(&out);
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(lines[0].starts_with("gpu: "), "{lines:?}");
    }

    /// The GPU path is held to the CPU path's refusals, before any work: the output's folder,
    /// the memory and the work estimates.
    #[test]
    fn the_gpu_backend_shares_the_cpu_limits() {
        let dir = common::scratch("gpu-limits");
        let huge = dir.join("huge.toml");
        std::fs::write(
            &huge,
            "[fur]\nnumber_of_shells = 256\ntexture_resolution = 2048\n",
        )
        .expect("write");
        let png = dir.join("x.png");
        let (huge, png) = (huge.to_str().expect("path"), png.to_str().expect("path"));
        refused(
            &["render", huge, "--backend", "gpu", "-o", png],
            "of memory, more than the limit",
        );
        refused(
            &[
                "render",
                huge,
                "--backend",
                "gpu",
                "--max-memory",
                "64G",
                "--max-work",
                "1e9",
                "-o",
                png,
            ],
            "more than the limit of 1.000e9",
        );
        assert!(!std::path::Path::new(png).exists());
        let missing = dir.join("no-such-folder/x.png");
        refused(
            &[
                "render",
                "--backend",
                "gpu",
                "-o",
                missing.to_str().expect("path"),
            ],
            "does not exist",
        );
    }

    #[test]
    fn adapter_by_index_and_by_name_renders_the_same_frame() {
        let dir = common::scratch("pick");
        // lavapipe's index in the list (0 where it is the only Vulkan adapter).
        let out = pelage(&["gpu-info", "--api", "vulkan"]);
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        let index = text
            .lines()
            .find(|l| l.contains("llvmpipe"))
            .and_then(|l| l.strip_prefix("vulkan "))
            .and_then(|l| l.split(':').next())
            .expect("lavapipe listed")
            .to_string();
        let mut images = Vec::new();
        for pick in [index.as_str(), "llvmpipe", "software"] {
            let png = dir.join(format!("{pick}.png"));
            let mut args = vec!["render", "--backend", "gpu", "--adapter", pick, "-o"];
            let path = png.to_str().expect("path").to_string();
            args.push(&path);
            args.extend(SMALL);
            let out = pelage(&args);
            assert_eq!(out.status.code(), Some(0), "--adapter {pick}: {out:?}");
            images.push(std::fs::read(&png).expect("png"));
        }
        // The three choices are lavapipe: the same bytes.
        assert_eq!(images[0], images[1]);
        assert_eq!(images[0], images[2]);
    }

    /// `--adapter swiftshader` picks Google's CPU Vulkan driver where `VK_ICD_FILENAMES` names
    /// its ICD file (`.ci/swiftshader` installs it under `target/swiftshader/`); with lavapipe's
    /// named too, `software` (the default) stays lavapipe. Where the loader does not list it,
    /// the one-line refusal says how to make it. Skipped without SwiftShader unless
    /// `PELAGE_REQUIRE_SWIFTSHADER=1`.
    #[test]
    fn adapter_swiftshader_picks_swiftshader() {
        let dir = common::scratch("swiftshader");
        let png = dir.join("x.png");
        let run = |icds: Option<&str>, adapter: &str| {
            let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_pelage"));
            command
                .args(["render", "--backend", "gpu", "--adapter", adapter, "-o"])
                .arg(&png)
                .args(SMALL)
                .env_remove("VK_DRIVER_FILES")
                .env_remove("VK_ADD_DRIVER_FILES");
            match icds {
                Some(files) => command.env("VK_ICD_FILENAMES", files),
                None => command.env_remove("VK_ICD_FILENAMES"),
            };
            command.output().expect("runs")
        };
        let out = run(None, "swiftshader");
        assert_eq!(out.status.code(), Some(2), "{out:?}");
        let lines = own_errors(&out);
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(
            lines[0].contains("no Vulkan adapter has this name")
                && lines[0].contains("VK_ICD_FILENAMES"),
            "{lines:?}"
        );

        let icd = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("target/swiftshader/vk_swiftshader_icd.json");
        if !icd.is_file() {
            assert!(
                std::env::var_os("PELAGE_REQUIRE_SWIFTSHADER").is_none_or(|v| v != "1"),
                "PELAGE_REQUIRE_SWIFTSHADER=1 but no {} (run .ci/setup)",
                icd.display()
            );
            eprintln!(
                "SKIPPED: {} needs SwiftShader, {} (run .ci/setup)",
                std::thread::current().name().unwrap_or("a test"),
                icd.display()
            );
            return;
        }
        let lavapipe = std::fs::read_dir("/usr/share/vulkan/icd.d")
            .expect("the Vulkan ICD folder")
            .map(|e| e.expect("entry").path())
            .find(|p| p.to_string_lossy().contains("lvp_icd"))
            .expect("lavapipe's ICD file");
        let both = format!("{}:{}", lavapipe.display(), icd.display());
        for (adapter, name) in [
            ("swiftshader", "SwiftShader Device"),
            ("software", "llvmpipe"),
        ] {
            let out = run(Some(&both), adapter);
            assert_eq!(out.status.code(), Some(0), "--adapter {adapter}: {out:?}");
            let lines = own_errors(&out);
            assert!(
                lines.len() == 1 && lines[0].starts_with(&format!("gpu: {name}")),
                "--adapter {adapter}: {lines:?}"
            );
        }
    }
}
