//! Sweeps on schedulers: `pelage sweep --shard auto` under each scheduler's variables, and the
//! recipes of docs/cluster/ run for real: the Python `concurrent.futures` example, and the
//! Slurm job array on a one-node Slurm started here (Debian's slurm-wlm and munge), each merged
//! and compared with the same sweep run in one process.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Every variable `--shard auto` reads: removed from the commands' environments, so a test run
/// inside a job array sees only what the test sets.
const SCHEDULER_VARIABLES: &[&str] = &[
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_MAX",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_STEP",
    "SLURM_JOB_ID",
    "JOB_COMPLETION_INDEX",
    "AWS_BATCH_JOB_ARRAY_INDEX",
    "AWS_BATCH_JOB_ARRAY_SIZE",
];

/// A command with no scheduler variables in its environment.
fn clean(program: impl AsRef<std::ffi::OsStr>) -> Command {
    let mut command = Command::new(program);
    for name in SCHEDULER_VARIABLES {
        command.env_remove(name);
    }
    command
}

/// The `pelage sweep` arguments of a small, quick sweep (2 × 2 points of the embedded torus at
/// 96×72), without `-o`.
const SWEEP: &[&str] = &[
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
];

/// `pelage ARGS` with the variables `env` (`NAME=value`) set.
fn pelage_with(env: &[&str], args: &[&str]) -> Output {
    let mut command = clean(env!("CARGO_BIN_EXE_pelage"));
    for pair in env {
        let (name, value) = pair.split_once('=').expect("NAME=value");
        command.env(name, value);
    }
    command.args(args).output().expect("pelage runs")
}

fn succeeded(o: Output, what: &str) -> Output {
    assert!(
        o.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The sweep in one process, into `dir/whole`.
fn whole_sweep(dir: &Path) -> PathBuf {
    let whole = dir.join("whole");
    let mut args = vec!["sweep"];
    args.extend(SWEEP);
    args.extend(["-o", whole.to_str().unwrap()]);
    succeeded(pelage_with(&[], &args), "the whole sweep");
    whole
}

/// results.csv's points and values (the timings differ from run to run).
fn points_and_values(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("results.csv"))
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .lines()
        .map(|l| l.split(',').take(3).collect::<Vec<_>>().join(","))
        .collect()
}

/// `merged` is the sweep `whole`: the same points and values, and every point image the same
/// bytes.
fn assert_same_sweep(merged: &Path, whole: &Path) {
    assert_eq!(points_and_values(merged), points_and_values(whole));
    for k in 0..4 {
        let file = format!("point_{k:04}.png");
        assert!(
            std::fs::read(merged.join(&file)).expect("merged point")
                == std::fs::read(whole.join(&file)).expect("whole point"),
            "{file} differs from the one-process sweep"
        );
    }
    assert!(merged.join("fps.png").is_file() && merged.join("contact_sheet.png").is_file());
}

/// Merges the shard folders into `out`.
fn merge(out: &Path, shards: &[PathBuf]) {
    let mut args = vec!["sweep-merge", "-o", out.to_str().unwrap()];
    args.extend(shards.iter().map(|s| s.to_str().unwrap()));
    succeeded(pelage_with(&[], &args), "sweep-merge");
}

/// The variables a scheduler sets in task `k` (0-based) of an array.
type TaskVariables = fn(usize) -> Vec<String>;

#[test]
fn shard_auto_reads_each_schedulers_task() {
    let dir = common::scratch("auto");
    let whole = whole_sweep(&dir);
    // Three tasks under each scheduler, numbered its way: a Slurm array --array=5-7, a
    // Kubernetes Indexed Job of 3 completions, an AWS Batch array of size 3.
    let schedulers: [(&str, &str, TaskVariables); 3] = [
        ("slurm", "auto", |k| {
            vec![
                format!("SLURM_ARRAY_TASK_ID={}", 5 + k),
                "SLURM_ARRAY_TASK_MIN=5".into(),
                "SLURM_ARRAY_TASK_MAX=7".into(),
                "SLURM_ARRAY_TASK_COUNT=3".into(),
                "SLURM_ARRAY_TASK_STEP=1".into(),
                "SLURM_JOB_ID=99".into(),
            ]
        }),
        ("kubernetes", "auto/3", |k| {
            vec![format!("JOB_COMPLETION_INDEX={k}")]
        }),
        ("aws", "auto", |k| {
            vec![
                format!("AWS_BATCH_JOB_ARRAY_INDEX={k}"),
                "AWS_BATCH_JOB_ARRAY_SIZE=3".into(),
            ]
        }),
    ];
    for (name, flag, variables) in schedulers {
        let mut shards = Vec::new();
        for k in 0..3 {
            let out = dir.join(format!("{name}-{k}"));
            let env = variables(k);
            let env: Vec<&str> = env.iter().map(String::as_str).collect();
            let mut args = vec!["sweep"];
            args.extend(SWEEP);
            args.extend(["--shard", flag, "-o", out.to_str().unwrap()]);
            let o = succeeded(pelage_with(&env, &args), name);
            let said = String::from_utf8_lossy(&o.stderr);
            assert!(
                said.contains(&format!("is shard {}/3", k + 1)),
                "{name}: {said}"
            );
            shards.push(out);
        }
        let merged = dir.join(format!("{name}-merged"));
        merge(&merged, &shards);
        assert_same_sweep(&merged, &whole);
    }
    // Refusals: exit 2, one line naming the variable, nothing written.
    let slurm = |id: &str, count: &str| {
        vec![
            format!("SLURM_ARRAY_TASK_ID={id}"),
            "SLURM_ARRAY_TASK_MIN=1".to_string(),
            format!("SLURM_ARRAY_TASK_COUNT={count}"),
        ]
    };
    let with = |mut v: Vec<String>, more: &[&str]| {
        v.extend(more.iter().map(|s| s.to_string()));
        v
    };
    let cases: Vec<(Vec<String>, &str, &str)> = vec![
        (vec![], "auto", "no scheduler's task index is set"),
        (
            vec!["SLURM_JOB_ID=7".into()],
            "auto",
            "submit the job as an array",
        ),
        (slurm("x", "3"), "auto", "SLURM_ARRAY_TASK_ID=\"x\""),
        (slurm("4", "3"), "auto", "SLURM_ARRAY_TASK_ID gives task 3"),
        (slurm("1", "3"), "auto/4", "has 3 tasks"),
        (
            vec!["JOB_COMPLETION_INDEX=0".into()],
            "auto",
            "--shard auto/N",
        ),
        (
            vec!["JOB_COMPLETION_INDEX=3".into()],
            "auto/3",
            "JOB_COMPLETION_INDEX gives task 3",
        ),
        (
            vec!["AWS_BATCH_JOB_ARRAY_INDEX=0".into()],
            "auto",
            "AWS_BATCH_JOB_ARRAY_SIZE is not",
        ),
        (
            with(
                slurm("1", "3"),
                &["AWS_BATCH_JOB_ARRAY_INDEX=1", "AWS_BATCH_JOB_ARRAY_SIZE=3"],
            ),
            "auto",
            "two schedulers disagree",
        ),
        (vec![], "auto/0", "expected auto, auto/N"),
    ];
    for (env, flag, needle) in cases {
        let out = dir.join("never");
        let env: Vec<&str> = env.iter().map(String::as_str).collect();
        let mut args = vec!["sweep"];
        args.extend(SWEEP);
        args.extend(["--shard", flag, "-o", out.to_str().unwrap()]);
        let o = pelage_with(&env, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{env:?} {flag}: {err}");
        assert!(
            err.contains(needle),
            "{env:?} {flag}: {needle:?} not in {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{env:?}: {err}");
        assert!(!out.exists(), "{env:?}: nothing is written");
    }
}

/// A program on the PATH, or in the system folders (`/usr/sbin`, where Debian puts the daemons).
fn find_program(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/sbin", "/usr/bin"].map(PathBuf::from))
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
}

/// Skips (returns true) when something the test needs is missing (`needs` says what), unless
/// the environment variable `require` is 1, where it fails instead.
fn skip_without(needs: Option<String>, require: &str) -> bool {
    let Some(needs) = needs else {
        return false;
    };
    assert!(
        std::env::var(require).as_deref() != Ok("1"),
        "{require}=1 but this test needs {needs} (run .ci/setup)"
    );
    eprintln!(
        "SKIPPED: {} needs {needs} (run .ci/setup)",
        std::thread::current().name().unwrap_or("a test")
    );
    true
}

#[test]
fn the_futures_example_gives_the_whole_sweep() {
    // docs/cluster/sweep_futures.py: 3 shards as subprocesses on a ThreadPoolExecutor, merged.
    let python = find_program("python3");
    if skip_without(
        python.is_none().then(|| "python3".into()),
        "PELAGE_REQUIRE_PYTHON",
    ) {
        return;
    }
    let dir = common::scratch("futures");
    let whole = whole_sweep(&dir);
    let merged = dir.join("merged");
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cluster/sweep_futures.py");
    let o = clean(python.expect("python3"))
        .arg(example)
        .arg("3")
        .arg(&merged)
        .args(SWEEP)
        .env("PELAGE", env!("CARGO_BIN_EXE_pelage"))
        .env("JOBS", "3")
        .output()
        .expect("python3 runs");
    succeeded(o, "sweep_futures.py");
    assert_same_sweep(&merged, &whole);
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("list")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().contains(".shards."))
        .collect();
    assert!(left.is_empty(), "the shards are removed once merged");
    // A shard that fails stops the example with pelage's message.
    let o = clean(find_program("python3").expect("python3"))
        .arg(example)
        .args(["2", dir.join("bad").to_str().unwrap()])
        .args(["--param", "number_of_shells=0"])
        .env("PELAGE", env!("CARGO_BIN_EXE_pelage"))
        .output()
        .expect("python3 runs");
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("number_of_shells"));
}

#[test]
fn the_kubernetes_manifest_counts_its_shards_once() {
    // docs/cluster/indexed-job.yaml: the N of `--shard auto/N` is the Job's completions (a Job
    // does not tell its pods), and its pods write to shards/$JOB_COMPLETION_INDEX.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/cluster/indexed-job.yaml"
    ))
    .expect("manifest");
    // The YAML without its comments.
    let text: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    let value = |key: &str| -> Vec<String> {
        text.lines()
            .filter_map(|l| l.trim().strip_prefix(key))
            .map(|rest| rest.split_whitespace().next().unwrap_or("").to_string())
            .collect()
    };
    let completions = value("completions:");
    let auto: Vec<String> = text
        .split("--shard auto/")
        .skip(1)
        .map(|rest| rest.split_whitespace().next().unwrap_or("").to_string())
        .collect();
    assert_eq!(completions.len(), 1, "one Indexed Job");
    assert!(
        auto.len() == 1 && auto == completions,
        "{auto:?} {completions:?}"
    );
    assert_eq!(value("completionMode:"), ["Indexed"]);
    assert!(text.contains("-o /sweep/shards/$JOB_COMPLETION_INDEX"));
    assert!(text.contains("sweep-merge -o /sweep/merged /sweep/shards/*"));
}

/// A one-node Slurm cluster (munged, slurmctld, slurmd) whose files all lie in one temporary
/// folder; dropping it cancels its jobs and stops its daemons, in reverse order.
#[cfg(unix)]
struct Slurm {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

#[cfg(unix)]
impl Slurm {
    /// Starts the daemons and waits until the node takes jobs.
    fn start(programs: &SlurmPrograms) -> Slurm {
        // Under /tmp: a Unix socket's path must stay under 108 bytes.
        let dir = std::env::temp_dir().join(format!("pelage-slurm-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        // munged refuses folders that others may write to, whatever the umask.
        use std::os::unix::fs::PermissionsExt;
        for sub in ["state", "spool", "log", "run"] {
            std::fs::create_dir_all(dir.join(sub)).expect("slurm folders");
            std::fs::set_permissions(dir.join(sub), std::fs::Permissions::from_mode(0o755))
                .expect("chmod");
        }
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).expect("chmod");
        let mut slurm = Slurm {
            conf: dir.join("slurm.conf"),
            dir: dir.clone(),
            daemons: Vec::new(),
        };
        // munge: a key owned by us (root), mode 0400.
        let key = dir.join("munge.key");
        let mut bytes = vec![0u8; 1024];
        use std::io::Read;
        std::fs::File::open("/dev/urandom")
            .and_then(|mut f| f.read_exact(&mut bytes))
            .expect("random key");
        std::fs::write(&key, &bytes).expect("munge key");
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400)).expect("chmod");
        let socket = dir.join("run/munge.socket");
        let run = |name: &str| dir.join("run").join(name);
        let log = |name: &str| dir.join("log").join(name);
        let mut munged = Command::new(&programs.munged);
        munged
            .arg("--foreground")
            .arg("--force")
            .arg(format!("--key-file={}", key.display()))
            .arg(format!("--socket={}", socket.display()))
            .arg(format!("--pid-file={}", run("munged.pid").display()))
            .arg(format!("--seed-file={}", run("munged.seed").display()))
            .arg(format!("--log-file={}", log("munged.log").display()));
        slurm.spawn("munged", munged);
        slurm.wait_for("munged's socket", || socket.exists());
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let conf = format!(
            "ClusterName=pelagetest\n\
             SlurmctldHost=localhost(127.0.0.1)\n\
             SlurmctldPort={ctld_port}\n\
             SlurmdPort={d_port}\n\
             SlurmUser=root\n\
             SlurmdUser=root\n\
             AuthType=auth/munge\n\
             CredType=cred/munge\n\
             AuthInfo=socket={socket}\n\
             StateSaveLocation={state}\n\
             SlurmdSpoolDir={spool}\n\
             SlurmctldPidFile={ctld_pid}\n\
             SlurmdPidFile={d_pid}\n\
             SlurmctldLogFile={ctld_log}\n\
             SlurmdLogFile={d_log}\n\
             ProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\n\
             SelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\n\
             ReturnToService=2\n\
             MpiDefault=none\n\
             NodeName=localhost NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n",
            ctld_port = free_port(),
            d_port = free_port(),
            socket = socket.display(),
            state = dir.join("state").display(),
            spool = dir.join("spool").display(),
            ctld_pid = run("slurmctld.pid").display(),
            d_pid = run("slurmd.pid").display(),
            ctld_log = log("slurmctld.log").display(),
            d_log = log("slurmd.log").display(),
        );
        std::fs::write(&slurm.conf, conf).expect("slurm.conf");
        let mut slurmctld = Command::new(&programs.slurmctld);
        slurmctld.args(["-D", "-i", "-f"]).arg(&slurm.conf);
        slurm.spawn("slurmctld", slurmctld);
        let mut slurmd = Command::new(&programs.slurmd);
        slurmd
            .args(["-D", "-N", "localhost", "-f"])
            .arg(&slurm.conf);
        slurm.spawn("slurmd", slurmd);
        let sinfo = programs.sinfo.clone();
        let conf = slurm.conf.clone();
        slurm.wait_for("the node to be idle", || {
            Command::new(&sinfo)
                .args(["-h", "-N", "-o", "%T"])
                .env("SLURM_CONF", &conf)
                .output()
                .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        });
        slurm
    }

    /// Starts a daemon in the foreground, its output in `log/NAME.out`.
    fn spawn(&mut self, name: &'static str, mut command: Command) {
        let out = std::fs::File::create(self.dir.join("log").join(format!("{name}.out")))
            .expect("daemon log");
        let err = out.try_clone().expect("daemon log");
        let child = command
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err)
            .spawn()
            .unwrap_or_else(|e| panic!("{name} does not start: {e}"));
        self.daemons.push((name, child));
    }

    /// Polls `ready` for up to 30 s; fails with the daemons' logs if a daemon stops or time
    /// runs out.
    fn wait_for(&mut self, what: &str, mut ready: impl FnMut() -> bool) {
        let start = Instant::now();
        while !ready() {
            let stopped = self
                .daemons
                .iter_mut()
                .find_map(|(name, child)| Some((*name, child.try_wait().ok()??)));
            if let Some((name, status)) = stopped {
                panic!("{name} stopped ({status}):\n{}", self.logs());
            }
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "no {what} after 30 s:\n{}",
                self.logs()
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Runs docs/cluster/slurm-array.sh with `N OUT ARGS` from `dir` and waits for it (up to
    /// 300 s, after which it fails with the logs); returns its status and what it printed.
    fn run_recipe(
        &self,
        dir: &Path,
        n: &str,
        out: &Path,
        args: &[&str],
    ) -> (std::process::ExitStatus, String) {
        let recipe = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cluster/slurm-array.sh");
        let log = dir.join("recipe.out");
        let file = std::fs::File::create(&log).expect("recipe log");
        let mut child = clean("bash")
            .arg(recipe)
            .arg(n)
            .arg(out)
            .args(args)
            .current_dir(dir)
            .env("PELAGE", env!("CARGO_BIN_EXE_pelage"))
            .env("WAIT", "1")
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .stdout(file.try_clone().expect("log"))
            .stderr(file)
            .spawn()
            .expect("bash runs");
        let start = Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait().expect("wait") {
                break status;
            }
            if start.elapsed() > Duration::from_secs(300) {
                let _ = child.kill();
                let _ = child.wait();
                panic!("the Slurm recipe took over 300 s:\n{}", self.logs());
            }
            std::thread::sleep(Duration::from_millis(100));
        };
        (status, std::fs::read_to_string(&log).unwrap_or_default())
    }

    /// The last lines of every log, for a failure message.
    fn logs(&self) -> String {
        let mut text = String::new();
        let Ok(entries) = std::fs::read_dir(self.dir.join("log")) else {
            return text;
        };
        let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        paths.sort();
        for path in paths {
            let body = std::fs::read_to_string(&path).unwrap_or_default();
            let lines: Vec<&str> = body.lines().collect();
            text += &format!("== {}\n", path.display());
            for line in &lines[lines.len().saturating_sub(15)..] {
                text += line;
                text.push('\n');
            }
        }
        text
    }
}

#[cfg(unix)]
impl Drop for Slurm {
    fn drop(&mut self) {
        if let Some(scancel) = find_program("scancel") {
            let _ = Command::new(scancel)
                .args(["--partition=debug", "--quiet"])
                .env("SLURM_CONF", &self.conf)
                .output();
        }
        for (_, child) in self.daemons.iter_mut().rev() {
            // SIGTERM, which each daemon handles by shutting down, then SIGKILL after 10 s.
            let _ = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .output();
            let start = Instant::now();
            while matches!(child.try_wait(), Ok(None)) && start.elapsed() < Duration::from_secs(10)
            {
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
        if std::thread::panicking() {
            eprintln!("slurm's files are kept in {}", self.dir.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

/// A TCP port free on this machine now.
#[cfg(unix)]
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// Where Debian's slurm-wlm and munge put their programs.
#[cfg(unix)]
struct SlurmPrograms {
    munged: PathBuf,
    slurmctld: PathBuf,
    slurmd: PathBuf,
    sinfo: PathBuf,
}

#[cfg(unix)]
impl SlurmPrograms {
    /// The programs, or what the test needs and lacks.
    fn find() -> Result<Self, String> {
        let find = |name: &str| {
            find_program(name).ok_or_else(|| format!("{name} (Debian's slurm-wlm and munge)"))
        };
        for client in ["sbatch", "scancel"] {
            find(client)?;
        }
        let programs = SlurmPrograms {
            munged: find("munged")?,
            slurmctld: find("slurmctld")?,
            slurmd: find("slurmd")?,
            sinfo: find("sinfo")?,
        };
        let uid = Command::new("id")
            .arg("-u")
            .output()
            .map_err(|e| e.to_string())?;
        if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
            return Err("root (slurmd starts each job as its user)".into());
        }
        Ok(programs)
    }
}

#[cfg(unix)]
#[test]
fn the_slurm_recipe_gives_the_whole_sweep() {
    // docs/cluster/slurm-array.sh on a one-node Slurm: an array of 3 tasks, each `--shard auto`,
    // and the merge as a job that depends on the array; the same points, values and point
    // images as one sweep. Skipped without Slurm unless PELAGE_REQUIRE_SLURM=1 (CI installs it).
    let programs = SlurmPrograms::find();
    if skip_without(programs.as_ref().err().cloned(), "PELAGE_REQUIRE_SLURM") {
        return;
    }
    let dir = common::scratch("slurm");
    let whole = whole_sweep(&dir);
    let slurm = Slurm::start(&programs.expect("found"));
    let merged = dir.join("merged");
    let start = Instant::now();
    let (status, said) = slurm.run_recipe(&dir, "3", &merged, SWEEP);
    let task_log = |name: &str| {
        std::fs::read_to_string(dir.join("merged.logs").join(name)).unwrap_or_default()
    };
    assert!(
        status.success(),
        "slurm-array.sh: {said}\n{}\n{}\n{}",
        task_log("task-1.out"),
        task_log("merge.out"),
        slurm.logs()
    );
    eprintln!(
        "the Slurm recipe ran in {:.1} s: {}",
        start.elapsed().as_secs_f64(),
        said.trim()
    );
    assert_same_sweep(&merged, &whole);
    // Each task resolved its own shard from the array's variables.
    for task in 1..=3 {
        let log = task_log(&format!("task-{task}.out"));
        assert!(
            log.contains(&format!("is shard {task}/3 (Slurm job array")),
            "{log}"
        );
    }
    assert!(
        !dir.join("merged.shards").exists(),
        "shards removed once merged"
    );
    // A task that fails cancels the merge, and the script says so (Slurm ends a cancelled job
    // with exit code 0, which `sbatch --wait` passes on).
    let bad = dir.join("bad");
    let args = ["--param", "number_of_shells=4,0", "--width", "32"];
    let (status, said) = slurm.run_recipe(&dir, "2", &bad, &args);
    assert!(
        !status.success() && said.contains("no merge: a task"),
        "{said}"
    );
    assert!(!bad.exists(), "nothing merged");
    drop(slurm);
}
