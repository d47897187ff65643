//! Parameter sweeps (beside the pipeline: sweeps): the thesis's chapter 4 experiments (tables
//! 4.1–4.6) as data.
//!
//! A sweep is a scene plus one or more `NAME=V1,V2,...` parameters; its points are the
//! cartesian product of the values, the last parameter varying fastest, numbered from 0 in that
//! order. Every point is a scene of its own: the parameter values are written into the scene's
//! TOML before it is parsed and validated, so a sweep can change anything a scene file can, and
//! a bad value is refused with the same checks as a bad scene.
//!
//! Point numbers do not depend on sharding: shard `I/N` runs the points whose number is
//! `I − 1` modulo `N`, and the shards' `results.csv` files merge back into the whole sweep
//! ([`merge_results`]). `--shard auto` reads `I/N` from the job scheduler's array task
//! ([`ShardChoice`], [`shard_from_scheduler`]).

mod csv;
mod manifest;
mod plot;
mod scheduler;
mod sheet;

pub use csv::{ResultRow, Results, merge_results, parse_results, write_results};
pub use manifest::{MANIFEST_FILE, Manifest, check_shards, sweep_id};
pub use plot::{Metric, fps_plot, metric_plot};
pub use scheduler::{FromScheduler, Scheduler, ShardChoice, shard_from_scheduler};
pub use sheet::{SheetLayout, contact_sheet};

use crate::scene::Scene;
use std::path::Path;

/// A sweep that cannot be set up: names the parameter or value at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct SweepError(pub String);

/// One `--param NAME=V1,V2,...`.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepParameter {
    /// The name as given (a thesis name, a special name, or a dotted scene key).
    pub name: String,
    /// The values, as written (TOML values: `30`, `0.5`, `[1, 0, 0]`, `"obj"`).
    pub values: Vec<String>,
}

/// Thesis parameter names (chapter 4) and the scene keys they stand for.
pub const THESIS_NAMES: &[(&str, &str)] = &[
    ("model_resolution", "mesh.model_resolution"),
    ("model_difference", "fur.model_difference"),
    ("number_of_strands", "fur.number_of_strands"),
    ("strand_resolution", "fur.strand_resolution"),
    ("circle_resolution", "fur.circle_resolution"),
    ("number_of_shells", "fur.number_of_shells"),
    ("texture_resolution", "fur.texture_resolution"),
    ("specular_tangents", "shading.specular_tangents"),
    ("shadow_divisor", "shading.shadow_divisor"),
    ("width", "image.width"),
    ("height", "image.height"),
    ("seed", "seed"),
    ("time", "time"),
    ("burn_time", "time"),
];

/// Parameters that are not a single scene key:
/// - `camera_distance`: the eye moved along its line of sight to this distance from the target
///   (thesis table 4.5; [`crate::scene::CameraSettings::at_distance`]);
/// - `number_of_spots`: the first N `[[spots]]` of the scene are kept (table 4.4; asking for
///   more than the scene has is an error);
/// - `lod`: `on` gives the scene a `[lod]` table (its own, or the defaults), `off` removes it
///   (level of detail against every shell, at each distance).
pub const SPECIAL_NAMES: &[&str] = &["camera_distance", "number_of_spots", "lod"];

/// The deepest dotted scene key a parameter may name (the scene's deepest key is
/// `shading.weights.diffuse`-like, three levels; spots and paths add an index).
pub const MAX_KEY_DEPTH: usize = 8;

/// The most arrays or inline tables a parameter's values may open, all together.
pub const MAX_VALUE_NESTING: usize = 64;

impl SweepParameter {
    /// Parses `NAME=V1,V2,...`. Commas inside brackets belong to array values.
    pub fn parse(arg: &str) -> Result<Self, SweepError> {
        let bad = |why: &str| SweepError(format!("--param {arg:?}: {why}"));
        let (name, list) = arg
            .split_once('=')
            .ok_or_else(|| bad("expected NAME=V1,V2,..."))?;
        let name = name.trim();
        if name.is_empty() {
            return Err(bad("the parameter name is empty"));
        }
        // One line: a value with a line break would be a second TOML line, another key.
        if arg.contains(['\n', '\r']) {
            return Err(bad("a line break in a parameter is not allowed"));
        }
        // Scene keys are at most a few tables deep; a long dotted name is a mistake, and a
        // 20,000-level one would exhaust the stack of the TOML reader.
        let depth = name.split('.').count();
        if depth > MAX_KEY_DEPTH {
            return Err(bad(&format!(
                "the name is {depth} keys deep; scene keys are at most {MAX_KEY_DEPTH}"
            )));
        }
        if list.chars().filter(|&c| c == '[' || c == '{').count() > MAX_VALUE_NESTING {
            return Err(bad(&format!(
                "the value nests more than {MAX_VALUE_NESTING} arrays or tables"
            )));
        }
        let mut values = Vec::new();
        let (mut depth, mut start) = (0i32, 0usize);
        for (i, c) in list.char_indices() {
            match c {
                '[' => depth += 1,
                ']' => depth -= 1,
                ',' if depth == 0 => {
                    values.push(list[start..i].trim().to_string());
                    start = i + 1;
                }
                _ => {}
            }
        }
        values.push(list[start..].trim().to_string());
        if values.iter().any(String::is_empty) {
            return Err(bad("a value is empty"));
        }
        if !SPECIAL_NAMES.contains(&name) {
            let key = scene_key(name);
            if key.split('.').any(str::is_empty) {
                return Err(bad("not a parameter name or dotted scene key"));
            }
        }
        Ok(SweepParameter {
            name: name.to_string(),
            values,
        })
    }
}

/// The scene key (or table) a parameter changes: its [`scene_key`], or for a special name the
/// key it rewrites (`camera_distance` the eye, `number_of_spots` the spots, `lod` the table).
fn touched_key(name: &str) -> &str {
    match name {
        "camera_distance" => "camera.eye",
        "number_of_spots" => "spots",
        "lod" => "lod",
        _ => scene_key(name),
    }
}

/// Whether two parameter names change one scene value: the same key under two names
/// (`time` and `burn_time`, `model_resolution` and `mesh.model_resolution`), or a table and a key
/// inside it (`lod` and `lod.min_shells`).
fn same_key(a: &str, b: &str) -> bool {
    let (a, b) = (touched_key(a), touched_key(b));
    let inside = |outer: &str, inner: &str| {
        inner
            .strip_prefix(outer)
            .is_some_and(|rest| rest.is_empty() || rest.starts_with('.') || rest.starts_with('['))
    };
    inside(a, b) || inside(b, a)
}

/// The scene key a parameter name stands for (thesis names are translated, dotted keys kept).
pub fn scene_key(name: &str) -> &str {
    THESIS_NAMES
        .iter()
        .find(|(thesis, _)| *thesis == name)
        .map_or(name, |(_, key)| key)
}

/// One point of a sweep: its number and a value for each parameter, in parameter order.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    /// Position in the whole sweep (independent of sharding).
    pub index: usize,
    /// `(name, value)` for each parameter.
    pub values: Vec<(String, String)>,
}

impl SweepPoint {
    /// `name=value name=value`, for labels and messages.
    pub fn label(&self) -> String {
        self.values
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// Largest number of points a sweep may have.
pub const MAX_POINTS: usize = 100_000;

/// Every point of the sweep, the last parameter varying fastest.
pub fn sweep_points(parameters: &[SweepParameter]) -> Result<Vec<SweepPoint>, SweepError> {
    if parameters.is_empty() {
        return Err(SweepError("a sweep needs at least one --param".into()));
    }
    for (i, p) in parameters.iter().enumerate() {
        if let Some(q) = parameters[..i].iter().find(|q| q.name == p.name) {
            return Err(SweepError(format!(
                "--param {} is given twice; list all its values in one --param",
                q.name
            )));
        }
        if let Some(q) = parameters[..i].iter().find(|q| same_key(&q.name, &p.name)) {
            return Err(SweepError(format!(
                "--param {} and --param {} set the same scene value ({}), so one would silently \
                 win; give one of them",
                q.name,
                p.name,
                touched_key(&p.name)
            )));
        }
    }
    let count = parameters
        .iter()
        .try_fold(1usize, |n, p| n.checked_mul(p.values.len()))
        .filter(|&n| n <= MAX_POINTS)
        .ok_or_else(|| SweepError(format!("the sweep has more than {MAX_POINTS} points")))?;
    Ok((0..count)
        .map(|index| {
            let mut rest = index;
            let mut values = vec![(String::new(), String::new()); parameters.len()];
            for (slot, p) in values.iter_mut().zip(parameters).rev() {
                let v = rest % p.values.len();
                rest /= p.values.len();
                *slot = (p.name.clone(), p.values[v].clone());
            }
            SweepPoint { index, values }
        })
        .collect())
}

/// `--shard I/N`: 1-based shard `I` of `N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, 1..=count.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// Parses `I/N` with `1 ≤ I ≤ N ≤` [`MAX_POINTS`] (more shards than a sweep may have
    /// points would only be empty ones; the bound also keeps `N` a safe allocation size when
    /// `sweep-merge` reads it back from a `sweep.txt`).
    pub fn parse(text: &str) -> Result<Self, SweepError> {
        let bad = || SweepError(format!("--shard {text:?}: expected I/N with 1 <= I <= N"));
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        if count > MAX_POINTS {
            return Err(SweepError(format!(
                "--shard {text:?}: at most {MAX_POINTS} shards (a sweep has at most as many points)"
            )));
        }
        Ok(Shard { index, count })
    }

    /// Whether this shard runs the point with this number.
    pub fn runs(&self, point: usize) -> bool {
        point % self.count == self.index - 1
    }
}

/// The scene of one sweep point: the parameter values written into the scene's TOML (`text`,
/// read from `file`), then parsed and validated like any scene. Errors name the file and the
/// parameter.
pub fn scene_at(
    text: &str,
    file: &str,
    base_dir: &Path,
    point: &SweepPoint,
) -> Result<Scene, SweepError> {
    let context = |why: String| SweepError(format!("{file} with {}: {why}", point.label()));
    let mut table: toml::Table = toml::from_str(text).map_err(|e| {
        SweepError(format!(
            "{file}: {}",
            e.message().trim() // the scene itself is bad: no parameter to blame
        ))
    })?;
    let mut distance = None;
    for (name, value) in &point.values {
        match name.as_str() {
            "camera_distance" => {
                let d: f32 = value
                    .parse()
                    .map_err(|_| context(format!("camera_distance {value:?} is not a number")))?;
                if !(d.is_finite() && d >= 0.0) {
                    return Err(context(format!(
                        "camera_distance {value} must be finite and not negative"
                    )));
                }
                distance = Some(d);
            }
            "number_of_spots" => {
                let n: usize = value.parse().map_err(|_| {
                    context(format!("number_of_spots {value:?} is not a whole number"))
                })?;
                let spots = table.get_mut("spots").and_then(toml::Value::as_array_mut);
                let have = spots.as_ref().map_or(0, |s| s.len());
                if n > have {
                    return Err(context(format!(
                        "number_of_spots {n}, but the scene has only {have} [[spots]]"
                    )));
                }
                if let Some(spots) = spots {
                    spots.truncate(n);
                }
            }
            "lod" => match value.as_str() {
                "on" | "true" => {
                    table
                        .entry("lod")
                        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
                }
                "off" | "false" => {
                    table.remove("lod");
                }
                _ => return Err(context(format!("lod {value:?} must be on or off"))),
            },
            _ => set_key(&mut table, scene_key(name), parse_value(value)).map_err(&context)?,
        }
    }
    let edited = toml::to_string(&table).map_err(|e| context(e.to_string()))?;
    let mut scene = Scene::parse(&edited, file, base_dir).map_err(|e| context(e.message))?;
    if let Some(d) = distance {
        scene.camera = scene.camera.at_distance(d);
        scene.revalidate(file).map_err(|e| context(e.message))?;
    }
    Ok(scene)
}

/// A value as TOML (`30`, `0.5`, `true`, `[1, 2]`, `"text"`); anything that is not valid TOML
/// is taken as a bare string (so `kind=obj` works without quotes).
fn parse_value(text: &str) -> toml::Value {
    toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.to_string()))
}

/// Sets `a.b.c` in a TOML table, creating the tables on the way.
fn set_key(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts.pop().unwrap_or(key);
    let mut at = table;
    for part in parts {
        let entry = at
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        at = entry
            .as_table_mut()
            .ok_or_else(|| format!("{key}: {part} is not a table in the scene"))?;
    }
    at.insert(last.to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn param(arg: &str) -> SweepParameter {
        SweepParameter::parse(arg).expect("parameter")
    }

    #[test]
    fn parameters_split_on_top_level_commas() {
        let p = param("light.direction=[1, 0, 0],[0,1,0]");
        assert_eq!(p.name, "light.direction");
        assert_eq!(p.values, vec!["[1, 0, 0]", "[0,1,0]"]);
        assert_eq!(param(" number_of_shells = 10,20 ").values, vec!["10", "20"]);
        for bad in ["number_of_shells", "=1,2", "a=1,,2", "a..b=1", "fur.=3"] {
            assert!(SweepParameter::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn points_are_the_product_last_fastest() {
        let points = sweep_points(&[param("a=1,2"), param("b=x,y,z")]).expect("points");
        let labels: Vec<String> = points.iter().map(SweepPoint::label).collect();
        assert_eq!(
            labels,
            [
                "a=1 b=x", "a=1 b=y", "a=1 b=z", "a=2 b=x", "a=2 b=y", "a=2 b=z"
            ]
        );
        assert!(points.iter().enumerate().all(|(i, p)| p.index == i));
        assert!(sweep_points(&[]).is_err());
        assert!(sweep_points(&[param("a=1"), param("a=2")]).is_err());
        let huge = |name: &str| param(&format!("{name}={}", vec!["1"; 300].join(",")));
        assert_eq!(
            sweep_points(&[huge("a"), huge("b")]).expect("90 000").len(),
            90_000
        );
        assert!(sweep_points(&[huge("a"), huge("b"), huge("c")]).is_err());
    }

    #[test]
    fn shards_partition_the_points() {
        let shards: Vec<Shard> = (1..=3)
            .map(|i| Shard::parse(&format!("{i}/3")).expect("shard"))
            .collect();
        for point in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.runs(point)).count(), 1);
        }
        for bad in [
            "0/3",
            "4/3",
            "1",
            "a/b",
            "1/0",
            "1/18446744073709551615",
            "1/100001",
        ] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn two_names_for_one_key_are_refused() {
        for (a, b) in [
            ("time=1", "burn_time=2"),
            ("model_resolution=10", "mesh.model_resolution=20"),
            ("width=10", "image.width=20"),
            ("camera_distance=5", "camera.eye=[0, 0, 5]"),
            ("lod=on", "lod.min_shells=4"),
            ("number_of_spots=1", "spots[0].radius=0.5"),
        ] {
            let e = sweep_points(&[param(a), param(b)]).expect_err(b);
            assert!(e.0.contains("set the same scene value"), "{a} {b}: {e}");
        }
        // Neighbours that only share a prefix of letters are different keys.
        sweep_points(&[
            param("fur.number_of_shells=4"),
            param("fur.number_of_shells_x=1"),
        ])
        .expect("different keys");
        sweep_points(&[param("time=1"), param("width=10")]).expect("different keys");
    }

    #[test]
    fn values_land_in_the_scene() {
        let text = crate::scene::DEFAULT_SCENE;
        let dir = Path::new("scenes");
        let points = sweep_points(&[
            param("number_of_shells=7"),
            param("shading.specular_tangents=3"),
            param("camera_distance=10"),
            param("light.colour=[0.5, 0.25, 1.0]"),
        ])
        .expect("points");
        let scene = scene_at(text, "torus.toml", dir, &points[0]).expect("scene");
        assert_eq!(scene.fur.number_of_shells, 7);
        assert_eq!(scene.shading.specular_tangents, 3);
        let d = (scene.camera.eye - scene.camera.target).length();
        assert!((d - 10.0).abs() < 1e-4, "{d}");
        assert_eq!(scene.light.colour, glam::Vec3::new(0.5, 0.25, 1.0));
        assert_eq!(scene.lod, None);
        let points = sweep_points(&[param("lod=on,off")]).expect("points");
        let on = scene_at(text, "torus.toml", dir, &points[0]).expect("on");
        assert_eq!(on.lod, Some(crate::scene::LodSettings::default()));
        let with_lod = format!("{text}\n[lod]\nmin_shells = 6\n");
        let off = scene_at(&with_lod, "torus.toml", dir, &points[1]).expect("off");
        assert_eq!(off.lod, None);
        let kept = scene_at(&with_lod, "torus.toml", dir, &points[0]).expect("kept");
        assert_eq!(kept.lod.map(|l| l.min_shells), Some(6));
    }

    #[test]
    fn bad_values_name_the_parameter() {
        let text = crate::scene::DEFAULT_SCENE;
        let dir = Path::new("scenes");
        for (arg, needle) in [
            ("number_of_shells=0", "number_of_shells"),
            ("fur.no_such_key=1", "no_such_key"),
            ("number_of_spots=13", "number_of_spots"),
            ("camera_distance=-1", "camera_distance"),
            ("lod=maybe", "lod"),
            ("texture_resolution=abc", "texture_resolution"),
        ] {
            let points = sweep_points(&[param(arg)]).expect("points");
            let err = scene_at(text, "torus.toml", dir, &points[0]).expect_err(arg);
            assert!(
                err.0.contains("torus.toml") && err.0.contains(needle),
                "{arg}: {err}"
            );
        }
    }

    #[test]
    fn line_breaks_and_deep_names_are_refused_before_any_toml_is_read() {
        for (arg, needle) in [
            ("number_of_shells=10\n[fur]", "line break"),
            ("fur.colour=[1,0,0]\r", "line break"),
        ] {
            let err = SweepParameter::parse(arg).unwrap_err();
            assert!(err.0.contains(needle), "{arg:?}: {err}");
        }
        let deep = format!("{}=1", vec!["a"; 20_000].join("."));
        let err = SweepParameter::parse(&deep).unwrap_err();
        assert!(err.0.contains("keys deep"), "{err}");
        let nested = format!("fur.colour={}1{}", "[".repeat(20_000), "]".repeat(20_000));
        let err = SweepParameter::parse(&nested).unwrap_err();
        assert!(err.0.contains("nests"), "{err}");
    }
}
