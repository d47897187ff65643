//! `pelage bench --against OTHER`: this build and another pelage binary on the same scene and
//! arguments, round after round, and how many times the other's CPU time a frame is this
//! build's.
//!
//! Both builds run as child processes (`bench … --json`), so that each pays its own start-up,
//! bake and allocator alike and neither measures the other. On a shared machine whose load
//! moves a build's time by ±10 % between minutes, one build timed after the other says little;
//! a ratio per round, each round timing both builds within seconds of each other, does. Two
//! ways of taking a round:
//! - **in turn** (default): one build, then the other, the order reversed every other round,
//!   with the threads asked for;
//! - **together** (`--together`): both at the same time, each pinned to a core of its own
//!   (the cores swapped every round) and one thread each, so that both see the same
//!   neighbours; the fastest frame of each is the steadier figure then.
//!
//! The figure is CPU time (every thread of a child, from its own `bench` report), and the
//! machine's CPU model is printed with it.

use super::bench::BenchArgs;
use super::{Failure, progress};
use serde::Serialize;
use std::ffi::OsString;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};

/// Runs `pelage bench --against`: `args` as parsed, `raw` the process's arguments after
/// `bench` (passed on to both builds, less this comparison's own).
pub fn run(args: &BenchArgs, other: &Path, raw: &[OsString]) -> Result<String, Failure> {
    if !other.is_file() {
        return Err(Failure::bad_input(format!(
            "--against {}: no such file (give the path of another pelage binary)",
            other.display()
        )));
    }
    if args.together && args.common.threads.is_some_and(|t| t != 1) {
        return Err(Failure::bad_input(
            "--together runs each build on one core with one thread: leave out --threads or give 1",
        ));
    }
    let this = std::env::current_exe()
        .map_err(|e| Failure::other(format!("cannot find this program's own path: {e}")))?;
    let mut passed = child_arguments(raw);
    if args.together && args.common.threads.is_none() {
        passed.extend(["--threads".into(), "1".into()]);
    }
    let cores = if args.together {
        Some(pinning::two_cores()?)
    } else {
        None
    };
    let builds = [this.as_path(), other];
    let bar = progress(u64::from(args.rounds) * 2);
    let mut rounds = Vec::new();
    for round in 0..args.rounds {
        // Every other round the other build goes first (in turn) or the cores swap (together).
        let swap = round % 2 == 1;
        let [this_report, other_report] = match cores {
            Some(cores) => {
                let (a, b) = if swap {
                    (cores[1], cores[0])
                } else {
                    (cores[0], cores[1])
                };
                let mut first = pinning::spawn_on(a, bench_command(builds[0], &passed))
                    .map_err(|e| spawn_failure(builds[0], e))?;
                let second = match pinning::spawn_on(b, bench_command(builds[1], &passed)) {
                    Ok(child) => child,
                    Err(e) => {
                        // Not left running behind the error.
                        let _ = first.kill();
                        let _ = first.wait();
                        return Err(spawn_failure(builds[1], e));
                    }
                };
                // Both waited for before either report is read, so that a failure leaves
                // no build running.
                let (first, second) = (wait(builds[0], first), wait(builds[1], second));
                bar.inc(2);
                [
                    BuildReport::from_output(builds[0], &first?)?,
                    BuildReport::from_output(builds[1], &second?)?,
                ]
            }
            None => {
                let order = if swap { [1, 0] } else { [0, 1] };
                let mut reports = [None, None];
                for i in order {
                    let child = bench_command(builds[i], &passed)
                        .spawn()
                        .map_err(|e| spawn_failure(builds[i], e))?;
                    reports[i] = Some(finish(builds[i], child)?);
                    bar.inc(1);
                }
                let [Some(a), Some(b)] = reports else {
                    return Err(Failure::other("a round lost one of its builds' reports"));
                };
                [a, b]
            }
        };
        rounds.push(Round::new(this_report, other_report));
    }
    bar.finish_and_clear();
    let comparison = Comparison {
        this: this.display().to_string(),
        against: other.display().to_string(),
        cpu: cpu_model(),
        mode: if args.together { "together" } else { "in turn" },
        median_cpu_ratio: RatioSpread::of(rounds.iter().map(|r| r.median_cpu_ratio)),
        min_cpu_ratio: RatioSpread::of(rounds.iter().map(|r| r.min_cpu_ratio)),
        rounds,
    };
    if args.json {
        serde_json::to_string(&comparison)
            .map_err(|e| Failure::other(format!("cannot write JSON: {e}")))
    } else {
        Ok(comparison.text())
    }
}

/// The arguments both builds get: those after `bench`, less `--against`, `--rounds`,
/// `--together` and `--json` (with their values), then `--json`.
pub fn child_arguments(raw: &[OsString]) -> Vec<OsString> {
    let mut out = Vec::new();
    let mut args = raw.iter();
    while let Some(arg) = args.next() {
        let text = arg.to_string_lossy();
        match text.as_ref() {
            "--against" | "--rounds" => {
                args.next();
            }
            "--together" | "--json" => {}
            _ if text.starts_with("--against=") || text.starts_with("--rounds=") => {}
            _ => out.push(arg.clone()),
        }
    }
    out.push("--json".into());
    out
}

/// `BUILD bench ARGS`, its output captured.
fn bench_command(build: &Path, args: &[OsString]) -> Command {
    let mut command = Command::new(build);
    command
        .arg("bench")
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    command
}

fn spawn_failure(build: &Path, error: std::io::Error) -> Failure {
    Failure::bad_input(format!("cannot run {}: {error}", build.display()))
}

/// Waits for a build's `bench` and takes its output.
fn wait(build: &Path, child: Child) -> Result<Output, Failure> {
    child
        .wait_with_output()
        .map_err(|e| Failure::other(format!("waiting for {}: {e}", build.display())))
}

/// Waits for a build's `bench` and reads its report.
fn finish(build: &Path, child: Child) -> Result<BuildReport, Failure> {
    BuildReport::from_output(build, &wait(build, child)?)
}

/// What the comparison reads of one build's `bench --json`.
#[derive(Serialize, Clone, Copy)]
struct BuildReport {
    median_cpu_ms: f64,
    min_cpu_ms: f64,
    median_frame_ms: f64,
    fragments_per_frame: Option<u64>,
}

impl BuildReport {
    fn from_output(build: &Path, output: &Output) -> Result<BuildReport, Failure> {
        if !output.status.success() {
            let stderr = String::from_utf8_lossy(&output.stderr);
            let last = stderr.lines().rev().find(|l| !l.trim().is_empty());
            return Err(Failure::other(format!(
                "{} bench failed ({}): {}",
                build.display(),
                output.status,
                last.unwrap_or("no message")
            )));
        }
        let not_a_report = |why: &str| {
            Failure::other(format!(
                "{}: its `bench --json` output {why}: is it a pelage build?",
                build.display()
            ))
        };
        let text = String::from_utf8_lossy(&output.stdout);
        let json: serde_json::Value =
            serde_json::from_str(text.trim()).map_err(|_| not_a_report("is not JSON"))?;
        let number = |key: &str| {
            json.get(key)
                .and_then(serde_json::Value::as_f64)
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| {
                    not_a_report(&format!(
                        "has no positive {key} (CPU time is measured on Linux only)"
                    ))
                })
        };
        Ok(BuildReport {
            median_cpu_ms: number("median_cpu_ms")?,
            min_cpu_ms: number("min_cpu_ms")?,
            median_frame_ms: number("median_frame_ms")?,
            fragments_per_frame: json
                .get("fragments_per_frame")
                .and_then(serde_json::Value::as_u64),
        })
    }
}

/// One round: both builds' reports and the other's CPU over this build's.
#[derive(Serialize)]
struct Round {
    this: BuildReport,
    against: BuildReport,
    /// The other build's median CPU a frame over this build's: above 1 this build is cheaper.
    median_cpu_ratio: f64,
    /// The same of the fastest frames.
    min_cpu_ratio: f64,
}

impl Round {
    fn new(this: BuildReport, against: BuildReport) -> Round {
        Round {
            this,
            against,
            median_cpu_ratio: against.median_cpu_ms / this.median_cpu_ms,
            min_cpu_ratio: against.min_cpu_ms / this.min_cpu_ms,
        }
    }
}

/// The median and range of the rounds' ratios.
#[derive(Serialize)]
struct RatioSpread {
    median: f64,
    min: f64,
    max: f64,
}

impl RatioSpread {
    fn of(ratios: impl Iterator<Item = f64>) -> RatioSpread {
        let mut sorted: Vec<f64> = ratios.collect();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        // The middle value, or the mean of the two middle ones.
        let median = match n {
            0 => f64::NAN,
            _ if n % 2 == 1 => sorted[n / 2],
            _ => (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0,
        };
        RatioSpread {
            median,
            min: sorted.first().copied().unwrap_or(f64::NAN),
            max: sorted.last().copied().unwrap_or(f64::NAN),
        }
    }
}

/// The whole comparison; `--json` prints it as it is.
#[derive(Serialize)]
struct Comparison {
    this: String,
    against: String,
    /// `/proc/cpuinfo`'s model name, family and model.
    cpu: String,
    /// `in turn` or `together`.
    mode: &'static str,
    rounds: Vec<Round>,
    median_cpu_ratio: RatioSpread,
    min_cpu_ratio: RatioSpread,
}

impl Comparison {
    fn text(&self) -> String {
        let how = match self.mode {
            "together" => {
                "both builds at the same time, a core each (swapped every round), one thread each"
            }
            _ => "one build after the other, the order reversed every other round",
        };
        let mut lines = vec![
            format!("this build: {}", self.this),
            format!("against:    {}", self.against),
            format!("CPU: {}", self.cpu),
            format!("{} rounds, {how}", self.rounds.len()),
            "round  CPU a frame, this build (median / fastest)  the other build  other/this (median / fastest)".to_string(),
        ];
        for (i, r) in self.rounds.iter().enumerate() {
            lines.push(format!(
                "{:>5}  {:>10.1} / {:<10.1} ms                   {:>8.1} / {:<8.1} ms  {:.3} / {:.3}",
                i + 1,
                r.this.median_cpu_ms,
                r.this.min_cpu_ms,
                r.against.median_cpu_ms,
                r.against.min_cpu_ms,
                r.median_cpu_ratio,
                r.min_cpu_ratio
            ));
        }
        let spread = |s: &RatioSpread| format!("{:.3}× ({:.3}–{:.3})", s.median, s.min, s.max);
        lines.push(format!(
            "the other build's CPU a frame over this build's, per round: median frames {}, fastest frames {}",
            spread(&self.median_cpu_ratio),
            spread(&self.min_cpu_ratio)
        ));
        let differs = self
            .rounds
            .iter()
            .any(|r| r.this.fragments_per_frame != r.against.fragments_per_frame);
        if differs {
            lines.push(
                "note: the two builds shade different numbers of fragments: not the same work"
                    .to_string(),
            );
        }
        lines.join("\n")
    }
}

/// The CPU model as `/proc/cpuinfo` names it (its first processor), with family and model.
fn cpu_model() -> String {
    let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") else {
        return "unknown (no /proc/cpuinfo)".to_string();
    };
    let field = |key: &str| {
        info.lines()
            .find(|l| l.split(':').next().is_some_and(|k| k.trim() == key))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    };
    let name = field("model name").unwrap_or_else(|| "unknown".to_string());
    let cpus = info.lines().filter(|l| l.starts_with("processor")).count();
    match (field("cpu family"), field("model")) {
        (Some(family), Some(model)) => {
            format!("{name} (family {family}, model {model}), {cpus} CPUs")
        }
        _ => format!("{name}, {cpus} CPUs"),
    }
}

/// Where a child runs: Linux pins the calling thread to one core while it starts a child,
/// which inherits the mask, then restores it (no `unsafe`, no external tool).
#[cfg(target_os = "linux")]
mod pinning {
    use super::Failure;
    use rustix::thread::{CpuSet, sched_getaffinity, sched_setaffinity};
    use std::process::{Child, Command};

    /// The first two cores this process may run on.
    pub fn two_cores() -> Result<[usize; 2], Failure> {
        let mask = sched_getaffinity(None)
            .map_err(|e| Failure::other(format!("cannot read this process's cores: {e}")))?;
        let cores: Vec<usize> = (0..CpuSet::MAX_CPU).filter(|&c| mask.is_set(c)).collect();
        match cores[..] {
            [a, b, ..] => Ok([a, b]),
            _ => Err(Failure::bad_input(format!(
                "--together needs two cores; this process may run on {}",
                cores.len()
            ))),
        }
    }

    /// Starts `command` pinned to `core`.
    pub fn spawn_on(core: usize, mut command: Command) -> std::io::Result<Child> {
        let saved = sched_getaffinity(None)?;
        let mut one = CpuSet::new();
        one.set(core);
        sched_setaffinity(None, &one)?;
        let child = command.spawn();
        sched_setaffinity(None, &saved)?;
        child
    }
}

#[cfg(not(target_os = "linux"))]
mod pinning {
    use super::Failure;
    use std::process::{Child, Command};

    pub fn two_cores() -> Result<[usize; 2], Failure> {
        Err(Failure::bad_input(
            "--together pins each build to a core, which pelage does on Linux only",
        ))
    }

    pub fn spawn_on(_core: usize, mut command: Command) -> std::io::Result<Child> {
        command.spawn()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(args: &[&str]) -> Vec<OsString> {
        args.iter().map(OsString::from).collect()
    }

    #[test]
    fn both_builds_get_the_arguments_less_the_comparisons_own() {
        let raw = strings(&[
            "scenes/thesis-4-2.toml",
            "--against",
            "/tmp/old",
            "--frames",
            "4",
            "--rounds=3",
            "--together",
            "--json",
            "--against=/x",
            "--rounds",
            "5",
            "--tile",
            "32",
        ]);
        assert_eq!(
            child_arguments(&raw),
            strings(&[
                "scenes/thesis-4-2.toml",
                "--frames",
                "4",
                "--tile",
                "32",
                "--json"
            ])
        );
    }

    #[test]
    fn ratio_spread_takes_the_middle_of_the_rounds() {
        let s = RatioSpread::of([1.2, 0.9, 1.1].into_iter());
        assert_eq!((s.median, s.min, s.max), (1.1, 0.9, 1.2));
        let s = RatioSpread::of([1.0, 2.0, 4.0, 3.0].into_iter());
        assert_eq!((s.median, s.min, s.max), (2.5, 1.0, 4.0));
    }

    fn output(status: i32, stdout: &str, stderr: &str) -> Output {
        use std::os::unix::process::ExitStatusExt;
        Output {
            status: std::process::ExitStatus::from_raw(status << 8),
            stdout: stdout.as_bytes().to_vec(),
            stderr: stderr.as_bytes().to_vec(),
        }
    }

    #[test]
    #[cfg(unix)]
    fn a_build_that_fails_or_is_not_pelage_is_named() {
        let build = Path::new("/opt/old/pelage");
        let failed = BuildReport::from_output(build, &output(2, "", "error: scene.toml line 3\n"))
            .err()
            .map(|f| f.message);
        assert!(
            failed
                .as_deref()
                .is_some_and(|m| m.contains("/opt/old/pelage") && m.contains("line 3")),
            "{failed:?}"
        );
        let not_json = BuildReport::from_output(build, &output(0, "hello", ""))
            .err()
            .map(|f| f.message);
        assert!(
            not_json.as_deref().is_some_and(|m| m.contains("not JSON")),
            "{not_json:?}"
        );
        let no_cpu = BuildReport::from_output(
            build,
            &output(
                0,
                r#"{"median_cpu_ms":null,"min_cpu_ms":1,"median_frame_ms":2}"#,
                "",
            ),
        )
        .err()
        .map(|f| f.message);
        assert!(
            no_cpu
                .as_deref()
                .is_some_and(|m| m.contains("median_cpu_ms")),
            "{no_cpu:?}"
        );
        let good = BuildReport::from_output(
            build,
            &output(
                0,
                r#"{"median_cpu_ms":10.5,"min_cpu_ms":9,"median_frame_ms":6,"fragments_per_frame":7}"#,
                "",
            ),
        );
        assert!(good.is_ok_and(|r| r.median_cpu_ms == 10.5 && r.fragments_per_frame == Some(7)));
    }

    #[test]
    fn a_round_divides_the_other_by_this() {
        let report = |median, min| BuildReport {
            median_cpu_ms: median,
            min_cpu_ms: min,
            median_frame_ms: median,
            fragments_per_frame: None,
        };
        let round = Round::new(report(100.0, 80.0), report(150.0, 100.0));
        assert_eq!((round.median_cpu_ratio, round.min_cpu_ratio), (1.5, 1.25));
    }

    #[test]
    #[cfg(unix)]
    fn reports_read_back_every_bit_of_what_they_wrote() {
        // A ratio printed by one build is read by the next (and by tests) as the same f64:
        // serde_json's default parser is off by one unit in the last place for about one
        // shortest-form number in six near 1 (measured on 2 M), e.g. this one.
        let ratio = f64::from_bits(0x3ff0_0001_091f_1668);
        let text = serde_json::to_string(&ratio).expect("a finite number");
        assert_eq!(text, "1.0000009876543121");
        let read: f64 = serde_json::from_str(&text).expect("a number");
        assert_eq!(read.to_bits(), ratio.to_bits());
        // And through the path that reads another build's report.
        let report =
            format!(r#"{{"median_cpu_ms":{text},"min_cpu_ms":{text},"median_frame_ms":{text}}}"#);
        let read = BuildReport::from_output(Path::new("/opt/old/pelage"), &output(0, &report, ""))
            .ok()
            .map(|r| [r.median_cpu_ms, r.min_cpu_ms, r.median_frame_ms].map(f64::to_bits));
        assert_eq!(read, Some([ratio.to_bits(); 3]));
    }
}
