//! Reference scenes rendered by the `pelage` binary while busy threads of another process (this
//! test) load every core give the reference PNG byte for byte, for several thread counts and
//! tile sizes: scheduling, preemption and contention never change the image.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Threads that spin on floating-point work until dropped.
struct Load {
    stop: Arc<AtomicBool>,
    threads: Vec<std::thread::JoinHandle<f64>>,
}

impl Load {
    fn start(count: usize) -> Load {
        let stop = Arc::new(AtomicBool::new(false));
        let threads = (0..count)
            .map(|k| {
                let stop = Arc::clone(&stop);
                std::thread::spawn(move || {
                    let mut x = k as f64 + 0.5;
                    while !stop.load(Ordering::Relaxed) {
                        for _ in 0..10_000 {
                            x = (x * 1.000_001 + 0.37).sin().abs() + 0.5;
                        }
                    }
                    x
                })
            })
            .collect();
        Load { stop, threads }
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

#[test]
fn reference_scenes_are_identical_while_the_cores_are_busy() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("under-load");
    std::fs::create_dir_all(&out).expect("scratch dir");
    let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
    let _load = Load::start(2 * cores);
    for (scene, threads, tile) in [
        ("leg", "1", "64"),
        ("leg", "3", "16"),
        ("leg", "8", "32"),
        ("torus", "2", "64"),
    ] {
        let png = out.join(format!("{scene}-{threads}-{tile}.png"));
        let o = Command::new(env!("CARGO_BIN_EXE_pelage"))
            .arg("render")
            .arg(root.join("scenes").join(format!("{scene}.toml")))
            .args(["--threads", threads, "--tile", tile, "-o"])
            .arg(&png)
            .output()
            .expect("pelage runs");
        assert!(
            o.status.success(),
            "{scene}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let expected = std::fs::read(root.join("reference_images").join(format!("{scene}.png")))
            .expect("reference");
        let actual = std::fs::read(&png).expect("output");
        assert!(
            actual == expected,
            "{scene} with --threads {threads} --tile {tile} under load differs from its reference"
        );
    }
}
