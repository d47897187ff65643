//! `sweep.txt` (beside the pipeline: sweeps): what sweep a folder's results belong to, so that
//! `sweep-merge` joins only the shards of one sweep, all of them, each once.
//!
//! ```text
//! pelage sweep
//! id = 9f0c2d4e5a6b7c81
//! points = 12
//! shard = 2/3
//! ```
//!
//! `id` is a 64-bit FNV-1a hash of everything that decides the sweep's points and their
//! images (the scene text, the parameters and their values, the size and time overrides, the
//! frames timed, the backend); `points` is the whole sweep's count, `shard` the part this
//! folder holds (`all` for an unsharded or merged sweep).

use super::{Shard, SweepError};

/// The manifest of one sweep folder.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Manifest {
    /// The sweep's identity ([`sweep_id`]).
    pub id: u64,
    /// Points in the whole sweep.
    pub points: usize,
    /// The shard this folder holds; `None` for the whole sweep.
    pub shard: Option<Shard>,
}

/// The file name of the manifest in a sweep folder.
pub const MANIFEST_FILE: &str = "sweep.txt";

/// FNV-1a, 64 bits, over `parts`, each followed by a 0 byte so that boundaries count.
pub fn sweep_id<'a>(parts: impl IntoIterator<Item = &'a str>) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        for &byte in part.as_bytes().iter().chain(&[0u8]) {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    hash
}

impl Manifest {
    /// The manifest's text.
    pub fn to_text(&self) -> String {
        let shard = match self.shard {
            Some(s) => format!("{}/{}", s.index, s.count),
            None => "all".to_string(),
        };
        format!(
            "pelage sweep\nid = {:016x}\npoints = {}\nshard = {shard}\n",
            self.id, self.points
        )
    }

    /// Parses a manifest read from `file`.
    pub fn parse(text: &str, file: &str) -> Result<Manifest, SweepError> {
        let bad = |why: &str| SweepError(format!("{file}: {why}"));
        let mut lines = text.lines();
        if lines.next() != Some("pelage sweep") {
            return Err(bad(
                "not a sweep manifest (its first line is not `pelage sweep`)",
            ));
        }
        let (mut id, mut points, mut shard) = (None, None, None);
        for (n, line) in lines.enumerate() {
            let at = |why: String| SweepError(format!("{file}:{}: {why}", n + 2));
            let (key, value) = line
                .split_once(" = ")
                .ok_or_else(|| at(format!("expected `key = value`, found {line:?}")))?;
            match key {
                "id" => {
                    id = Some(
                        u64::from_str_radix(value, 16)
                            .map_err(|_| at(format!("id {value:?} is not 16 hex digits")))?,
                    );
                }
                "points" => {
                    let count = value
                        .parse::<usize>()
                        .map_err(|_| at(format!("points {value:?} is not a count")))?;
                    // Used as a loop bound and an allocation size: bounded before use.
                    if count > super::MAX_POINTS {
                        return Err(at(format!(
                            "points {count}: a sweep has at most {} points",
                            super::MAX_POINTS
                        )));
                    }
                    points = Some(count);
                }
                "shard" => {
                    shard = Some(if value == "all" {
                        None
                    } else {
                        Some(Shard::parse(value).map_err(|e| at(e.0))?)
                    });
                }
                other => return Err(at(format!("unknown key {other:?}"))),
            }
        }
        match (id, points, shard) {
            (Some(id), Some(points), Some(shard)) => Ok(Manifest { id, points, shard }),
            _ => Err(bad("needs id, points and shard")),
        }
    }
}

/// Checks that `shards` (`(folder name, manifest, points it holds)`) are the shards of one
/// sweep, every shard once, and that together they hold each of its points exactly once.
pub fn check_shards(shards: &[(String, Manifest, Vec<usize>)]) -> Result<(), SweepError> {
    let Some((first_name, first, _)) = shards.first() else {
        return Err(SweepError("nothing to merge: no shard given".into()));
    };
    let count = first.shard.map_or(1, |s| s.count);
    let mut holder: Vec<Option<&str>> = vec![None; count];
    for (name, m, points) in shards {
        if m.id != first.id || m.points != first.points {
            return Err(SweepError(format!(
                "{name} and {first_name} are from different sweeps (their sweep.txt ids or \
                 point counts differ): merge the shards of one sweep"
            )));
        }
        let shard = m.shard.unwrap_or(Shard { index: 1, count: 1 });
        if shard.count != count {
            return Err(SweepError(format!(
                "{name} is shard {}/{} but {first_name} is one of {count}: the sweep was split \
                 two ways",
                shard.index, shard.count
            )));
        }
        if let Some(other) = holder[shard.index - 1] {
            return Err(SweepError(format!(
                "{name} and {other} are both shard {}/{count}: their points overlap",
                shard.index
            )));
        }
        holder[shard.index - 1] = Some(name);
        if let Some(p) = points.iter().find(|&&p| !shard.runs(p) || p >= m.points) {
            return Err(SweepError(format!(
                "{name}: point {p} does not belong to shard {}/{count} of a sweep of {} points",
                shard.index, m.points
            )));
        }
        let expected = (0..m.points).filter(|&p| shard.runs(p)).count();
        if points.len() != expected {
            return Err(SweepError(format!(
                "{name}: shard {}/{count} holds {} of its {expected} points: it is incomplete",
                shard.index,
                points.len()
            )));
        }
    }
    if let Some(missing) = holder.iter().position(Option::is_none) {
        return Err(SweepError(format!(
            "shard {}/{count} is missing: give every shard's folder",
            missing + 1
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shard(i: usize, n: usize) -> Option<Shard> {
        Some(Shard { index: i, count: n })
    }

    fn manifest(id: u64, points: usize, s: Option<Shard>) -> Manifest {
        Manifest {
            id,
            points,
            shard: s,
        }
    }

    #[test]
    fn manifests_round_trip_and_ids_depend_on_every_part() {
        let m = manifest(sweep_id(["scene", "a=1,2"]), 4, shard(2, 3));
        assert_eq!(Manifest::parse(&m.to_text(), "s.txt").expect("parse"), m);
        let whole = manifest(7, 4, None);
        assert_eq!(
            Manifest::parse(&whole.to_text(), "s.txt").expect("parse"),
            whole
        );
        assert_ne!(sweep_id(["ab", "c"]), sweep_id(["a", "bc"]));
        assert_ne!(sweep_id(["scene", "a=1,2"]), sweep_id(["scene", "a=1,3"]));
        assert!(Manifest::parse("id = 1\n", "x.txt").is_err());
        let err = Manifest::parse("pelage sweep\nid = zz\npoints = 1\nshard = all\n", "x.txt")
            .unwrap_err();
        assert!(err.0.contains("x.txt:2"), "{}", err.0);
        // Counts are allocation sizes and loop bounds: bounded when read.
        for text in [
            "pelage sweep\nid = 1\npoints = 1000000000000000\nshard = all\n",
            "pelage sweep\nid = 1\npoints = 4\nshard = 1/1000000000000\n",
            "pelage sweep\nid = 1\npoints = 4\nshard = 1/18446744073709551615\n",
        ] {
            let err = Manifest::parse(text, "x.txt").unwrap_err();
            assert!(err.0.contains("at most"), "{}", err.0);
        }
    }

    #[test]
    fn shards_must_be_of_one_sweep_each_once_and_complete() {
        let part = |name: &str, id, i, points: &[usize]| {
            (
                name.to_string(),
                manifest(id, 5, shard(i, 2)),
                points.to_vec(),
            )
        };
        let one = part("one", 1, 1, &[0, 2, 4]);
        let two = part("two", 1, 2, &[1, 3]);
        assert!(check_shards(&[one.clone(), two.clone()]).is_ok());
        let err = |s: &[(String, Manifest, Vec<usize>)]| check_shards(s).unwrap_err().0;
        assert!(err(std::slice::from_ref(&one)).contains("shard 2/2 is missing"));
        assert!(err(&[one.clone(), part("other", 9, 2, &[1, 3])]).contains("different sweeps"));
        assert!(err(&[one.clone(), one.clone()]).contains("both shard 1/2"));
        assert!(err(&[one.clone(), part("two", 1, 2, &[1])]).contains("incomplete"));
        assert!(err(&[one.clone(), part("two", 1, 2, &[1, 2])]).contains("point 2"));
        let three = ("three".to_string(), manifest(1, 5, shard(1, 3)), vec![0, 3]);
        assert!(err(&[one, two, three]).contains("split"));
    }
}
