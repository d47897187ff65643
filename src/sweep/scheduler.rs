//! `--shard auto`: the shard a job scheduler's array task stands for, read from the variables
//! the scheduler sets. Pure: the environment comes in as a lookup, so every convention is
//! tested without touching the process's environment.
//!
//! Each scheduler numbers its tasks its own way; each maps to pelage's 1-based `I/N`:
//! - Slurm job arrays: `SLURM_ARRAY_TASK_ID` is whatever `--array` says (`0-3`, `1-4`,
//!   `0-15:4`), so the shard is `(ID − SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP + 1` of
//!   `SLURM_ARRAY_TASK_COUNT`; an array with gaps (`--array=1,3,7`) has no such numbering and is
//!   refused.
//! - Kubernetes Indexed Jobs: `JOB_COMPLETION_INDEX` is 0-based, and the Job's `completions`
//!   is not in the pod's environment: it is given as `--shard auto/N`.
//! - AWS Batch array jobs: `AWS_BATCH_JOB_ARRAY_INDEX` is 0-based, of `AWS_BATCH_JOB_ARRAY_SIZE`.
//!
//! Invariant: a shard is returned only when every scheduler whose index is set agrees on it
//! (and with the `N` of `auto/N`, if given); anything else is an error naming the variable.

use super::{MAX_POINTS, Shard, SweepError};

/// A job scheduler whose array tasks `--shard auto` understands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheduler {
    /// A Slurm job array (`sbatch --array`).
    Slurm,
    /// A Kubernetes Indexed Job (`completionMode: Indexed`).
    Kubernetes,
    /// An AWS Batch array job (`arrayProperties.size`).
    AwsBatch,
}

impl Scheduler {
    /// Every scheduler, in the order they are looked up.
    pub const ALL: [Scheduler; 3] = [Scheduler::Slurm, Scheduler::Kubernetes, Scheduler::AwsBatch];

    /// The scheduler's name, for messages.
    pub fn name(self) -> &'static str {
        match self {
            Scheduler::Slurm => "Slurm job array",
            Scheduler::Kubernetes => "Kubernetes Indexed Job",
            Scheduler::AwsBatch => "AWS Batch array job",
        }
    }

    /// The variable whose presence says the task runs under this scheduler.
    pub fn index_variable(self) -> &'static str {
        match self {
            Scheduler::Slurm => "SLURM_ARRAY_TASK_ID",
            Scheduler::Kubernetes => "JOB_COMPLETION_INDEX",
            Scheduler::AwsBatch => "AWS_BATCH_JOB_ARRAY_INDEX",
        }
    }
}

/// What `--shard` says: a shard given outright, or one to read from the scheduler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardChoice {
    /// `I/N`.
    Given(Shard),
    /// `auto` (`count: None`) or `auto/N`.
    Auto {
        /// The `N` of `auto/N`: the shard count where the scheduler does not say it
        /// (Kubernetes), or a check on the count where it does.
        count: Option<usize>,
    },
}

impl ShardChoice {
    /// Parses `--shard`: `I/N`, `auto` or `auto/N`.
    pub fn parse(text: &str) -> Result<Self, SweepError> {
        let Some(rest) = text.trim().strip_prefix("auto") else {
            return Shard::parse(text).map(ShardChoice::Given);
        };
        if rest.is_empty() {
            return Ok(ShardChoice::Auto { count: None });
        }
        let bad = || {
            SweepError(format!(
                "--shard {text:?}: expected auto, auto/N (N from 1 to {MAX_POINTS}) or I/N"
            ))
        };
        let count: usize = rest
            .strip_prefix('/')
            .ok_or_else(bad)?
            .trim()
            .parse()
            .map_err(|_| bad())?;
        if count == 0 || count > MAX_POINTS {
            return Err(bad());
        }
        Ok(ShardChoice::Auto { count: Some(count) })
    }

    /// The shard this task runs, and the scheduler it came from (`None` for `I/N`).
    pub fn resolve(
        self,
        env: &dyn Fn(&str) -> Option<String>,
    ) -> Result<(Shard, Option<FromScheduler>), SweepError> {
        match self {
            ShardChoice::Given(shard) => Ok((shard, None)),
            ShardChoice::Auto { count } => {
                let found = shard_from_scheduler(count, env)?;
                Ok((found.shard, Some(found)))
            }
        }
    }
}

/// A shard read from a scheduler's variables, with what it was read from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FromScheduler {
    /// The 1-based shard.
    pub shard: Shard,
    /// The scheduler (the first in [`Scheduler::ALL`] when several agree).
    pub scheduler: Scheduler,
    /// The variables read, as `NAME=value` separated by spaces.
    pub variables: String,
}

/// The shard of `--shard auto` (`count: None`) or `auto/N`, from the variables `env` looks up.
/// Errors: no scheduler's index set; a value that is not a whole number, or out of range; a
/// Slurm array with gaps; a count missing (Kubernetes without `auto/N`); two schedulers, or a
/// scheduler and `N`, that disagree.
pub fn shard_from_scheduler(
    count: Option<usize>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<FromScheduler, SweepError> {
    let mut found: Vec<FromScheduler> = Vec::new();
    for scheduler in Scheduler::ALL {
        if env(scheduler.index_variable()).is_none() {
            continue;
        }
        let one = from_one(scheduler, count, env)?;
        if let Some(first) = found.first()
            && first.shard != one.shard
        {
            return Err(SweepError(format!(
                "--shard auto: two schedulers disagree: {} ({}) says shard {}/{}, {} ({}) \
                 says {}/{}; unset the variables of the one not running this task",
                first.scheduler.name(),
                first.variables,
                first.shard.index,
                first.shard.count,
                one.scheduler.name(),
                one.variables,
                one.shard.index,
                one.shard.count,
            )));
        }
        found.push(one);
    }
    if let Some(first) = found.into_iter().next() {
        return Ok(first);
    }
    let hint = if env("SLURM_JOB_ID").is_some() {
        " (SLURM_JOB_ID is set: submit the job as an array, sbatch --array=1-N)"
    } else {
        ""
    };
    Err(SweepError(format!(
        "--shard auto: no scheduler's task index is set{hint}: it reads SLURM_ARRAY_TASK_ID \
         (Slurm job arrays), JOB_COMPLETION_INDEX (Kubernetes Indexed Jobs, with --shard auto/N) \
         or AWS_BATCH_JOB_ARRAY_INDEX (AWS Batch array jobs); outside a job array give --shard I/N"
    )))
}

/// The shard one scheduler's variables give (its index variable is set).
fn from_one(
    scheduler: Scheduler,
    given_count: Option<usize>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<FromScheduler, SweepError> {
    let mut read = Vec::new();
    let mut number = |name: &str, required: bool| -> Result<Option<usize>, SweepError> {
        let Some(value) = env(name) else {
            if required {
                return Err(SweepError(format!(
                    "--shard auto: {} is set but {name} is not ({})",
                    scheduler.index_variable(),
                    scheduler.name()
                )));
            }
            return Ok(None);
        };
        read.push(format!("{name}={value}"));
        value.trim().parse::<usize>().map(Some).map_err(|_| {
            SweepError(format!(
                "--shard auto: {name}={value:?} is not a whole number ({})",
                scheduler.name()
            ))
        })
    };
    // (0-based index, count, the variable that gave the count)
    let (index, count, count_variable) = match scheduler {
        Scheduler::Slurm => {
            let id = number("SLURM_ARRAY_TASK_ID", true)?.unwrap_or(0);
            let min = number("SLURM_ARRAY_TASK_MIN", true)?.unwrap_or(0);
            let count = number("SLURM_ARRAY_TASK_COUNT", true)?.unwrap_or(0);
            let step = number("SLURM_ARRAY_TASK_STEP", false)?.unwrap_or(1);
            let max = number("SLURM_ARRAY_TASK_MAX", false)?;
            let variables = read.join(" ");
            let gaps = || {
                SweepError(format!(
                    "--shard auto: the Slurm array is not an evenly spaced range ({variables}): \
                     submit it as --array=1-N (or A-B, or A-B:S)"
                ))
            };
            if id < min || step == 0 || (id - min) % step != 0 {
                return Err(gaps());
            }
            if let Some(max) = max
                && (max < min || (max - min) / step + 1 != count)
            {
                return Err(gaps());
            }
            ((id - min) / step, count, "SLURM_ARRAY_TASK_COUNT")
        }
        Scheduler::Kubernetes => {
            let index = number("JOB_COMPLETION_INDEX", true)?.unwrap_or(0);
            let Some(count) = given_count else {
                return Err(SweepError(format!(
                    "--shard auto: JOB_COMPLETION_INDEX={index} is set (Kubernetes Indexed Job) \
                     but a Job does not tell its pods their count: give --shard auto/N with N \
                     the Job's spec.completions"
                )));
            };
            (index, count, "auto/N")
        }
        Scheduler::AwsBatch => {
            let index = number("AWS_BATCH_JOB_ARRAY_INDEX", true)?.unwrap_or(0);
            let count = number("AWS_BATCH_JOB_ARRAY_SIZE", true)?.unwrap_or(0);
            (index, count, "AWS_BATCH_JOB_ARRAY_SIZE")
        }
    };
    let variables = read.join(" ");
    if count == 0 || count > MAX_POINTS {
        return Err(SweepError(format!(
            "--shard auto: {count_variable} gives {count} shards ({variables}); expected 1 to \
             {MAX_POINTS}"
        )));
    }
    if index >= count {
        return Err(SweepError(format!(
            "--shard auto: {} gives task {index}, past the last of {count} ({variables})",
            scheduler.index_variable()
        )));
    }
    if let Some(given) = given_count.filter(|&n| n != count) {
        return Err(SweepError(format!(
            "--shard auto/{given}: the {} has {count} tasks ({variables})",
            scheduler.name()
        )));
    }
    Ok(FromScheduler {
        shard: Shard {
            index: index + 1,
            count,
        },
        scheduler,
        variables,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A lookup over `NAME=value` pairs.
    fn env(pairs: &[&str]) -> impl Fn(&str) -> Option<String> {
        let pairs: Vec<(String, String)> = pairs
            .iter()
            .map(|p| {
                let (n, v) = p.split_once('=').expect("NAME=value");
                (n.to_string(), v.to_string())
            })
            .collect();
        move |name| {
            pairs
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, v)| v.clone())
        }
    }

    fn auto(count: Option<usize>, pairs: &[&str]) -> Result<(usize, usize), String> {
        shard_from_scheduler(count, &env(pairs))
            .map(|f| (f.shard.index, f.shard.count))
            .map_err(|e| e.0)
    }

    fn slurm(id: usize, min: usize, max: usize, count: usize, step: usize) -> Vec<String> {
        vec![
            format!("SLURM_ARRAY_TASK_ID={id}"),
            format!("SLURM_ARRAY_TASK_MIN={min}"),
            format!("SLURM_ARRAY_TASK_MAX={max}"),
            format!("SLURM_ARRAY_TASK_COUNT={count}"),
            format!("SLURM_ARRAY_TASK_STEP={step}"),
        ]
    }

    fn strs(v: &[String]) -> Vec<&str> {
        v.iter().map(String::as_str).collect()
    }

    #[test]
    fn the_flag_parses() {
        assert_eq!(
            ShardChoice::parse("auto"),
            Ok(ShardChoice::Auto { count: None })
        );
        assert_eq!(
            ShardChoice::parse("auto/8"),
            Ok(ShardChoice::Auto { count: Some(8) })
        );
        assert_eq!(
            ShardChoice::parse("2/8"),
            Ok(ShardChoice::Given(Shard { index: 2, count: 8 }))
        );
        for bad in ["auto/0", "auto/", "auto8", "auto/x", "autom", "auto/100001"] {
            assert!(ShardChoice::parse(bad).is_err(), "{bad}");
        }
        let given = ShardChoice::parse("3/4").expect("3/4");
        let (shard, from) = given
            .resolve(&env(&["SLURM_ARRAY_TASK_ID=1"]))
            .expect("given");
        assert_eq!((shard.index, from), (3, None));
    }

    #[test]
    fn slurm_arrays_map_to_shards_whatever_their_first_id() {
        // --array=0-3 and --array=1-4: the same four shards.
        for min in [0, 1, 7] {
            for k in 0..4 {
                let e = slurm(min + k, min, min + 3, 4, 1);
                assert_eq!(auto(None, &strs(&e)), Ok((k + 1, 4)), "{e:?}");
            }
        }
        // --array=0-15:4 is four tasks, 0, 4, 8, 12.
        assert_eq!(auto(None, &strs(&slurm(8, 0, 12, 4, 4))), Ok((3, 4)));
        // Without MAX and STEP (older Slurm): ID − MIN of COUNT.
        let e = [
            "SLURM_ARRAY_TASK_ID=5",
            "SLURM_ARRAY_TASK_MIN=3",
            "SLURM_ARRAY_TASK_COUNT=4",
        ];
        assert_eq!(auto(None, &e), Ok((3, 4)));
        // auto/N agreeing with the array is fine.
        assert_eq!(auto(Some(4), &strs(&slurm(2, 1, 4, 4, 1))), Ok((2, 4)));
        let found = shard_from_scheduler(None, &env(&strs(&slurm(2, 1, 4, 4, 1)))).expect("ok");
        assert_eq!(found.scheduler, Scheduler::Slurm);
        assert!(found.variables.contains("SLURM_ARRAY_TASK_ID=2"));
    }

    #[test]
    fn bad_slurm_arrays_are_refused_naming_the_variable() {
        // --array=1,3,7: three tasks over a range of seven.
        let e = auto(None, &strs(&slurm(3, 1, 7, 3, 1))).expect_err("gaps");
        assert!(
            e.contains("evenly spaced") && e.contains("SLURM_ARRAY_TASK_MAX=7"),
            "{e}"
        );
        assert!(
            auto(None, &strs(&slurm(5, 0, 12, 4, 4))).is_err(),
            "off the step"
        );
        assert!(
            auto(None, &strs(&slurm(0, 1, 4, 4, 1))).is_err(),
            "below MIN"
        );
        let e = auto(None, &strs(&slurm(5, 1, 4, 4, 1))).expect_err("past MAX");
        assert!(e.contains("SLURM_ARRAY_TASK_ID"), "{e}");
        let e = auto(None, &strs(&slurm(1, 1, 4, 4, 0))).expect_err("step 0");
        assert!(e.contains("SLURM_ARRAY_TASK_STEP=0"), "{e}");
        let e = auto(None, &["SLURM_ARRAY_TASK_ID=x"]).expect_err("not a number");
        assert!(
            e.contains("SLURM_ARRAY_TASK_ID=\"x\"") && e.contains("whole number"),
            "{e}"
        );
        let e = auto(None, &["SLURM_ARRAY_TASK_ID=1", "SLURM_ARRAY_TASK_MIN=1"]).expect_err("");
        assert!(e.contains("SLURM_ARRAY_TASK_COUNT is not"), "{e}");
        let none = [
            "SLURM_ARRAY_TASK_ID=0",
            "SLURM_ARRAY_TASK_MIN=0",
            "SLURM_ARRAY_TASK_COUNT=0",
        ];
        let e = auto(None, &none).expect_err("no tasks");
        assert!(e.contains("SLURM_ARRAY_TASK_COUNT gives 0"), "{e}");
        let e = auto(Some(3), &strs(&slurm(2, 1, 4, 4, 1))).expect_err("auto/3 of 4");
        assert!(e.contains("auto/3") && e.contains("has 4 tasks"), "{e}");
        let e = auto(None, &["SLURM_JOB_ID=12"]).expect_err("not an array");
        assert!(e.contains("sbatch --array"), "{e}");
    }

    #[test]
    fn kubernetes_indexed_jobs_take_the_count_from_the_flag() {
        for k in 0..5 {
            let e = format!("JOB_COMPLETION_INDEX={k}");
            assert_eq!(auto(Some(5), &[&e]), Ok((k + 1, 5)));
        }
        let e = auto(None, &["JOB_COMPLETION_INDEX=0"]).expect_err("no count");
        assert!(e.contains("auto/N") && e.contains("completions"), "{e}");
        let e = auto(Some(5), &["JOB_COMPLETION_INDEX=5"]).expect_err("index 5 of 5");
        assert!(e.contains("JOB_COMPLETION_INDEX"), "{e}");
        let e = auto(Some(5), &["JOB_COMPLETION_INDEX=-1"]).expect_err("negative");
        assert!(e.contains("JOB_COMPLETION_INDEX=\"-1\""), "{e}");
    }

    #[test]
    fn aws_batch_arrays_are_zero_based() {
        let e = ["AWS_BATCH_JOB_ARRAY_INDEX=0", "AWS_BATCH_JOB_ARRAY_SIZE=10"];
        assert_eq!(auto(None, &e), Ok((1, 10)));
        let e = ["AWS_BATCH_JOB_ARRAY_INDEX=9", "AWS_BATCH_JOB_ARRAY_SIZE=10"];
        assert_eq!(auto(Some(10), &e), Ok((10, 10)));
        let e = [
            "AWS_BATCH_JOB_ARRAY_INDEX=10",
            "AWS_BATCH_JOB_ARRAY_SIZE=10",
        ];
        assert!(auto(None, &e).unwrap_err().contains("past the last"));
        let e = auto(None, &["AWS_BATCH_JOB_ARRAY_INDEX=1"]).expect_err("no size");
        assert!(e.contains("AWS_BATCH_JOB_ARRAY_SIZE is not"), "{e}");
        let e = [
            "AWS_BATCH_JOB_ARRAY_INDEX=1",
            "AWS_BATCH_JOB_ARRAY_SIZE=1e3",
        ];
        assert!(
            auto(None, &e)
                .unwrap_err()
                .contains("AWS_BATCH_JOB_ARRAY_SIZE=\"1e3\"")
        );
        let e = [
            "AWS_BATCH_JOB_ARRAY_INDEX=1",
            "AWS_BATCH_JOB_ARRAY_SIZE=100001",
        ];
        assert!(auto(None, &e).unwrap_err().contains("expected 1 to 100000"));
    }

    #[test]
    fn schedulers_must_agree_and_one_must_be_set() {
        let mut both = slurm(2, 1, 4, 4, 1);
        both.push("AWS_BATCH_JOB_ARRAY_INDEX=1".into());
        both.push("AWS_BATCH_JOB_ARRAY_SIZE=4".into());
        assert_eq!(auto(None, &strs(&both)), Ok((2, 4)));
        both.push("JOB_COMPLETION_INDEX=2".into());
        let e = auto(Some(4), &strs(&both)).expect_err("disagree");
        assert!(
            e.contains("disagree") && e.contains("JOB_COMPLETION_INDEX=2") && e.contains("3/4"),
            "{e}"
        );
        let e = auto(None, &[]).expect_err("none");
        for name in [
            "SLURM_ARRAY_TASK_ID",
            "JOB_COMPLETION_INDEX",
            "AWS_BATCH_JOB_ARRAY_INDEX",
            "--shard I/N",
        ] {
            assert!(e.contains(name), "{name}: {e}");
        }
    }
}
