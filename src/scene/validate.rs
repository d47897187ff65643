//! Range checks for every scene value. Limits are checked here, before anything is allocated,
//! so an absurd scene is refused in microseconds rather than after gigabytes.

use super::Scene;
use glam::Vec3;

/// The largest values a scene may ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Image side, pixels.
    pub max_image_side: u32,
    /// Shell layers.
    pub max_shells: u32,
    /// Shell texture side, texels.
    pub max_texture_resolution: u32,
    /// Strands per tile.
    pub max_strands: u32,
    /// Procedural mesh triangles.
    pub max_model_resolution: u32,
    /// Spots, stripes, burn matches: each list at most this long (each entry is evaluated per
    /// fragment; `crate::limits::draw_work` bounds their cost with the image and the shells).
    pub max_effects: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_image_side: crate::raster::setup::MAX_DIMENSION,
            max_shells: 256,
            max_texture_resolution: 2048,
            max_strands: 1_000_000,
            max_model_resolution: 4_000_000,
            max_effects: 1024,
        }
    }
}

/// Smallest mesh size, scale and fur length accepted, world units.
const MIN_SIZE: f32 = 1.0e-6;
/// Largest mesh size, scale and fur length accepted, world units (f32 positions stay far from
/// overflow, and squared lengths stay finite).
const MAX_SIZE: f32 = 1.0e6;

/// A failed check: the dotted key and the message.
pub(super) type Failure = (String, String);

fn range_u32(key: &str, value: u32, min: u32, max: u32) -> Result<(), Failure> {
    if value < min || value > max {
        return Err((
            key.into(),
            format!("{key} = {value} is outside {min}..={max}"),
        ));
    }
    Ok(())
}

fn range_f32(key: &str, value: f32, min: f32, max: f32) -> Result<(), Failure> {
    if !value.is_finite() || value < min || value > max {
        return Err((
            key.into(),
            format!("{key} = {value} is outside {min}..={max}"),
        ));
    }
    Ok(())
}

fn positive(key: &str, value: f32) -> Result<(), Failure> {
    if !value.is_finite() || value <= 0.0 {
        return Err((
            key.into(),
            format!("{key} = {value} must be a positive number"),
        ));
    }
    Ok(())
}

fn finite_vec(key: &str, v: Vec3) -> Result<(), Failure> {
    if !v.is_finite() {
        return Err((key.into(), format!("{key} = {v} must be finite")));
    }
    Ok(())
}

fn colour(key: &str, v: Vec3) -> Result<(), Failure> {
    if !v.is_finite() || v.min_element() < 0.0 || v.max_element() > 1.0 {
        return Err((
            key.into(),
            format!("{key} = {v} must have components in 0..=1"),
        ));
    }
    Ok(())
}

/// A direction: finite, and normalisable in f32 (its squared length neither overflows nor
/// underflows to 0), since every user of it normalises it first and would silently get zero.
/// The largest coordinate of a light's position and the largest reach: their squares and the
/// squared distances of the fragment stage stay far inside f32.
const MAX_LIGHT_COORDINATE: f32 = 1.0e6;

/// A spot light or match at a point: a finite position within [`MAX_LIGHT_COORDINATE`] and a
/// positive reach.
/// Errors are reported at `line_key`'s line (a `[[spots]]` key, or the `matches` line for a
/// match given inline).
fn point_light(
    line_key: &str,
    position_key: &str,
    position: Vec3,
    reach_key: &str,
    reach: f32,
) -> Result<(), Failure> {
    if !position.is_finite() {
        return Err((
            line_key.into(),
            format!("{position_key} = {position} must be finite"),
        ));
    }
    if position.abs().max_element() > MAX_LIGHT_COORDINATE {
        return Err((
            line_key.into(),
            format!("{position_key} = {position} is outside ±{MAX_LIGHT_COORDINATE:e}"),
        ));
    }
    if !(reach.is_finite() && reach > 0.0 && reach <= MAX_LIGHT_COORDINATE) {
        return Err((
            line_key.into(),
            format!("{reach_key} = {reach} must be positive and at most {MAX_LIGHT_COORDINATE:e}"),
        ));
    }
    Ok(())
}

fn nonzero(key: &str, v: Vec3) -> Result<(), Failure> {
    finite_vec(key, v)?;
    if v.length_squared() == 0.0 {
        return Err((key.into(), format!("{key} must not be the zero vector")));
    }
    if v.try_normalize().is_none() {
        return Err((
            key.into(),
            format!("{key} = {v} cannot be normalised in f32 (its length overflows or vanishes)"),
        ));
    }
    Ok(())
}

/// Checks every value of `scene` against its range and `limits`.
pub(super) fn validate(scene: &Scene, limits: &Limits) -> Result<(), Failure> {
    let i = &scene.image;
    range_u32("image.width", i.width, 1, limits.max_image_side)?;
    range_u32("image.height", i.height, 1, limits.max_image_side)?;
    let pixels = u64::from(i.width) * u64::from(i.height);
    if pixels > crate::raster::framebuffer::MAX_PIXELS {
        return Err((
            "image.width".into(),
            format!(
                "image.width × image.height = {pixels} pixels exceeds the limit of {}",
                crate::raster::framebuffer::MAX_PIXELS
            ),
        ));
    }
    colour("image.background", i.background)?;

    let c = &scene.camera;
    finite_vec("camera.eye", c.eye)?;
    finite_vec("camera.target", c.target)?;
    nonzero("camera.up", c.up)?;
    if (c.target - c.eye).length_squared() == 0.0 {
        return Err((
            "camera.target".into(),
            "camera.target must differ from camera.eye".into(),
        ));
    }
    if (c.target - c.eye).try_normalize().is_none() {
        return Err((
            "camera.eye".into(),
            "camera.eye is so far from camera.target that the view direction overflows f32".into(),
        ));
    }
    let view = (c.target - c.eye).normalize_or_zero();
    if view
        .cross(c.up.normalize_or_zero())
        .try_normalize()
        .is_none()
    {
        return Err((
            "camera.up".into(),
            "camera.up must not be parallel to the view direction".into(),
        ));
    }
    range_f32("camera.fov_y_deg", c.fov_y_deg, 1.0, 170.0)?;
    positive("camera.near", c.near)?;
    if !(c.far.is_finite() && c.far > c.near) {
        return Err((
            "camera.far".into(),
            format!("camera.far = {} must be greater than camera.near", c.far),
        ));
    }

    let m = &scene.mesh;
    for (key, value) in [
        ("mesh.major_radius", m.major_radius),
        ("mesh.minor_radius", m.minor_radius),
        ("mesh.radius", m.radius),
        ("mesh.height", m.height),
        ("mesh.scale", m.scale),
    ] {
        positive(key, value)?;
        range_f32(key, value, MIN_SIZE, MAX_SIZE)?;
    }
    range_u32(
        "mesh.model_resolution",
        m.model_resolution,
        8,
        limits.max_model_resolution,
    )?;
    if m.kind == super::MeshKind::Obj && m.path.is_none() {
        return Err((
            "mesh.kind".into(),
            "mesh.kind = \"obj\" needs mesh.path".into(),
        ));
    }
    if m.kind == super::MeshKind::Gltf && m.path.is_none() {
        return Err((
            "mesh.kind".into(),
            "mesh.kind = \"gltf\" needs mesh.path".into(),
        ));
    }
    if let Some(a) = &scene.animation {
        if m.kind != super::MeshKind::Gltf {
            return Err((
                "animation".into(),
                "[animation] plays a clip of a glTF model; it needs mesh.kind = \"gltf\"".into(),
            ));
        }
        range_f32("animation.speed", a.speed, -1000.0, 1000.0)?;
        if let super::ClipSetting::Name(name) = &a.clip
            && name.is_empty()
        {
            return Err((
                "animation.clip".into(),
                "animation.clip must name a clip or give its index".into(),
            ));
        }
    }
    if scene.fur.colour_from_mesh {
        if m.kind != super::MeshKind::Gltf {
            return Err((
                "fur.colour_from_mesh".into(),
                "fur.colour_from_mesh takes the colour of a glTF model's material; it needs mesh.kind = \"gltf\"".into(),
            ));
        }
        if scene.maps.colour.is_some() {
            return Err((
                "fur.colour_from_mesh".into(),
                "fur.colour_from_mesh and maps.colour both tint the fur; keep one".into(),
            ));
        }
    }

    let f = &scene.fur;
    range_u32(
        "fur.number_of_strands",
        f.number_of_strands,
        1,
        limits.max_strands,
    )?;
    range_u32("fur.strand_resolution", f.strand_resolution, 1, 1000)?;
    range_u32("fur.circle_resolution", f.circle_resolution, 3, 1000)?;
    range_u32(
        "fur.number_of_shells",
        f.number_of_shells,
        1,
        limits.max_shells,
    )?;
    range_u32(
        "fur.texture_resolution",
        f.texture_resolution,
        4,
        limits.max_texture_resolution,
    )?;
    range_u32("fur.supersample", f.supersample, 1, 8)?;
    let baked = u64::from(f.texture_resolution) * u64::from(f.supersample);
    if baked > 8192 {
        return Err((
            "fur.supersample".into(),
            format!("fur.texture_resolution × fur.supersample = {baked} exceeds 8192"),
        ));
    }
    // Negative thins the object (thesis figure 3.10): the fur lies inside the surface.
    range_f32(
        "fur.model_difference",
        f.model_difference.abs(),
        MIN_SIZE,
        MAX_SIZE,
    )
    .map_err(|_| {
        (
            "fur.model_difference".to_string(),
            format!(
                "fur.model_difference = {} must be a number whose size is within {MIN_SIZE}..={MAX_SIZE} \
                 (negative thins the object)",
                f.model_difference
            ),
        )
    })?;
    for (k, v) in f.texture_repeat.iter().enumerate() {
        range_f32(&format!("fur.texture_repeat[{k}]"), *v, 0.001, 10_000.0)?;
    }
    colour("fur.colour", f.colour)?;
    range_f32("fur.colour_variation", f.colour_variation, 0.0, 1.0)?;
    range_f32("fur.slope_deg", f.slope_deg, 0.0, crate::fur::MAX_SLOPE_DEG)?;
    range_f32("fur.curl", f.curl, 0.0, 1.0)?;
    range_f32("fur.jitter", f.jitter, 0.0, 1.0)?;
    range_f32("fur.min_height", f.min_height, 0.01, 1.0)?;
    range_f32("fur.base_thickness", f.base_thickness, 0.0001, 0.25)?;
    range_f32("fur.tip_thickness", f.tip_thickness, 0.0, 0.25)?;
    range_f32("fur.gaussian_sigma", f.gaussian_sigma, 0.001, 1000.0)?;
    range_f32("fur.fin_height_scale", f.fin_height_scale, 0.1, 10.0)?;
    for (k, w) in f.fin_windows.iter().enumerate() {
        let key = format!("fur.fin_windows[{k}]");
        range_f32(&key, w[0], 0.0, 360.0)?;
        range_f32(&key, w[1], 0.0, 360.0)?;
        if w[0] > w[1] {
            return Err((
                key.clone(),
                format!("{key} = {w:?}: the first angle must not exceed the second"),
            ));
        }
    }

    let s = &scene.shading;
    range_f32("shading.ambient", s.ambient, 0.0, 1.0)?;
    range_f32("shading.banks_exponent", s.banks_exponent, 0.0, 256.0)?;
    range_f32(
        "shading.specular_exponent",
        s.specular_exponent,
        0.0,
        4096.0,
    )?;
    range_f32(
        "shading.dampened_exponent",
        s.dampened_exponent,
        0.0,
        4096.0,
    )?;
    range_f32(
        "shading.specular1_exponent",
        s.specular1_exponent,
        0.0,
        4096.0,
    )?;
    if !matches!(s.specular_tangents, 1 | 3) {
        return Err((
            "shading.specular_tangents".into(),
            format!(
                "shading.specular_tangents = {} must be 1 or 3",
                s.specular_tangents
            ),
        ));
    }
    range_f32("shading.tangent_shift", s.tangent_shift, 0.0, 2.0)?;
    range_u32("shading.shadow_divisor", s.shadow_divisor, 1, 256)?;
    let w = &s.weights;
    for (key, v) in [
        ("shading.weights.ambient", w.ambient),
        ("shading.weights.diffuse", w.diffuse),
        ("shading.weights.specular", w.specular),
        ("shading.weights.dampened", w.dampened),
        ("shading.weights.shadow", w.shadow),
    ] {
        range_f32(key, v, 0.0, 100.0)?;
    }

    range_f32("time", scene.time, -super::MAX_TIME, super::MAX_TIME)?;
    let matches = scene.burn.as_ref().map_or(0, |b| b.matches.len());
    for (key, count) in [
        ("spots", scene.spots.len()),
        ("stripes", scene.stripes.len()),
        ("burn.matches", matches),
    ] {
        if count > limits.max_effects {
            return Err((
                key.into(),
                format!(
                    "{key} lists {count} entries, more than the limit of {} (each is evaluated \
                     for every fragment)",
                    limits.max_effects
                ),
            ));
        }
    }
    for (k, spot) in scene.spots.iter().enumerate() {
        let key = |name: &str| format!("spots[{k}].{name}");
        colour(&key("colour"), spot.colour)?;
        match spot.kind {
            super::SpotKind::Ellipsoid => {
                finite_vec(&key("centre"), spot.centre)?;
                if !spot.radii.is_finite() || spot.radii.min_element() <= 0.0 {
                    return Err((
                        key("radii"),
                        format!("{} = {} must be positive", key("radii"), spot.radii),
                    ));
                }
                range_f32(&key("inner"), spot.inner, 0.0, 1.0)?;
            }
            super::SpotKind::Light => {
                nonzero(&key("direction"), spot.direction)?;
                match (spot.position, spot.reach) {
                    (Some(position), Some(reach)) => {
                        let (position_key, reach_key) = (key("position"), key("reach"));
                        let line_key = match position.is_finite()
                            && position.abs().max_element() <= MAX_LIGHT_COORDINATE
                        {
                            true => &reach_key,
                            false => &position_key,
                        };
                        point_light(line_key, &position_key, position, &reach_key, reach)?
                    }
                    (Some(_), None) => {
                        return Err((
                            key("position"),
                            format!(
                                "{} is set, so {} must be too: the distance at which the spot fades out",
                                key("position"),
                                key("reach")
                            ),
                        ));
                    }
                    (None, Some(_)) => {
                        return Err((
                            key("reach"),
                            format!(
                                "{} needs {}: a reach bounds a spot light at a point",
                                key("reach"),
                                key("position")
                            ),
                        ));
                    }
                    (None, None) => {}
                }
                range_f32(&key("exponent"), spot.exponent, 0.0, 10_000.0)?;
                range_f32(&key("inner_threshold"), spot.inner_threshold, 0.0, 1.0)?;
                range_f32(&key("outer_threshold"), spot.outer_threshold, 0.0, 1.0)?;
                if spot.outer_threshold > spot.inner_threshold {
                    return Err((
                        key("outer_threshold"),
                        format!(
                            "{} must not exceed {}",
                            key("outer_threshold"),
                            key("inner_threshold")
                        ),
                    ));
                }
            }
        }
    }
    for (k, stripe) in scene.stripes.iter().enumerate() {
        let key = |name: &str| format!("stripes[{k}].{name}");
        colour(&key("colour"), stripe.colour)?;
        // The keys of the other kind are refused: a file from before light stripes (the
        // default kind) has an `axis` and no `kind`, and must not draw something else quietly.
        let foreign = |name: &str, own: &str, other: &str| {
            Err((
                key(name),
                format!(
                    "{} is a key of kind = \"{other}\" stripes; this stripe is kind = \"{own}\"{}",
                    key(name),
                    if own == "light" {
                        " (the default: write kind = \"axis\" for bands across an axis)"
                    } else {
                        ""
                    }
                ),
            ))
        };
        match stripe.kind {
            super::StripeKind::Axis => {
                if stripe.direction.is_some() {
                    return foreign("direction", "axis", "light");
                }
                if stripe.exponent.is_some() {
                    return foreign("exponent", "axis", "light");
                }
                nonzero(&key("axis"), stripe.axis())?;
                positive(&key("period"), stripe.period())?;
            }
            super::StripeKind::Light => {
                if stripe.axis.is_some() {
                    return foreign("axis", "light", "axis");
                }
                nonzero(&key("direction"), stripe.direction())?;
                range_f32(&key("exponent"), stripe.exponent(), 0.0, 10_000.0)?;
                // Bands sit at lobe values (k + ½)·period within 0..=1: above 2, none.
                positive(&key("period"), stripe.period())?;
                range_f32(&key("period"), stripe.period(), 0.0, 2.0)?;
            }
        }
        range_f32(&key("width"), stripe.width(), 0.0, stripe.period())?;
        range_f32(&key("softness"), stripe.softness(), 0.0, stripe.period())?;
    }
    if let Some(w) = &scene.wind {
        nonzero("wind.direction", w.direction)?;
        range_f32("wind.strength", w.strength, 0.0, 10.0)?;
        range_f32("wind.frequency", w.frequency, 0.0, 100.0)?;
        range_f32("wind.elasticity", w.elasticity, 0.0, 1000.0)?;
        range_f32("wind.max_bend", w.max_bend, 0.0, 1.0)?;
        range_f32("wind.tangent_fraction", w.tangent_fraction, 0.0, 10.0)?;
    }
    let maps = &scene.maps;
    for (key, path) in [
        ("maps.length", &maps.length),
        ("maps.density", &maps.density),
        ("maps.direction", &maps.direction),
        ("maps.colour", &maps.colour),
    ] {
        if path.as_ref().is_some_and(|p| p.as_os_str().is_empty()) {
            return Err((key.into(), format!("{key} must name a PNG file")));
        }
    }
    if let Some(l) = &scene.lod {
        range_f32("lod.pixels_per_shell", l.pixels_per_shell, 0.01, 1000.0)?;
        range_u32("lod.min_shells", l.min_shells, 1, limits.max_shells)?;
        range_f32(
            "lod.fin_fade_pixels[0]",
            l.fin_fade_pixels[0],
            0.0,
            10_000.0,
        )?;
        range_f32(
            "lod.fin_fade_pixels[1]",
            l.fin_fade_pixels[1],
            0.0,
            10_000.0,
        )?;
        if l.fin_fade_pixels[0] > l.fin_fade_pixels[1] {
            return Err((
                "lod.fin_fade_pixels".into(),
                "lod.fin_fade_pixels: the first value must not exceed the second".into(),
            ));
        }
    }
    if let Some(g) = &scene.gravity {
        nonzero("gravity.direction", g.direction)?;
        range_f32("gravity.strength", g.strength, 0.0, 1.0)?;
    }
    if let Some(m) = &scene.motion {
        if m.path.is_empty() || m.path.len() > 10_000 {
            return Err((
                "motion.path".into(),
                format!(
                    "motion.path has {} keyframes; it needs 1 to 10000 of [t, x, y, z]",
                    m.path.len()
                ),
            ));
        }
        for (k, key) in m.path.iter().enumerate() {
            let name = format!("motion.path[{k}]");
            for value in key {
                range_f32(&name, *value, -1.0e6, 1.0e6)?;
            }
            if k > 0 && key[0] <= m.path[k - 1][0] {
                return Err((
                    name.clone(),
                    format!(
                        "{name}: keyframe times must increase ({} after {})",
                        key[0],
                        m.path[k - 1][0]
                    ),
                ));
            }
        }
        range_f32("motion.frequency", m.frequency, 0.01, 100.0)?;
        range_f32("motion.damping", m.damping, 0.01, 0.99)?;
        range_f32("motion.response", m.response, 0.0, 1000.0)?;
    }
    if let Some(b) = &scene.burn {
        if b.matches.is_empty() {
            return Err((
                "burn.matches".into(),
                "burn.matches must list at least one match".into(),
            ));
        }
        for (k, m) in b.matches.iter().enumerate() {
            let key = format!("burn.matches[{k}]");
            match m {
                super::MatchSetting::Direction(direction) => nonzero(&key, *direction)?,
                super::MatchSetting::Point(point) => point_light(
                    &key,
                    &format!("{key}.position"),
                    point.position,
                    &format!("{key}.reach"),
                    point.reach,
                )?,
            }
        }
        range_f32("burn.start", b.start, -1.0e6, 1.0e6)?;
        range_f32("burn.high_exponent", b.high_exponent, 0.0, 100_000.0)?;
        range_f32("burn.low_exponent", b.low_exponent, 0.0, 100_000.0)?;
        if b.low_exponent > b.high_exponent {
            return Err((
                "burn.low_exponent".into(),
                format!(
                    "burn.low_exponent = {} must not exceed burn.high_exponent = {}: the schedule falls from high to low",
                    b.low_exponent, b.high_exponent
                ),
            ));
        }
        range_f32("burn.spread_duration", b.spread_duration, 0.0, 1.0e6)?;
    }

    nonzero("light.direction", scene.light.direction)?;
    finite_vec("light.colour", scene.light.colour)?;
    range_f32("light.colour", scene.light.colour.max_element(), 0.0, 100.0)?;
    if scene.light.colour.min_element() < 0.0 {
        return Err((
            "light.colour".into(),
            "light.colour must not be negative".into(),
        ));
    }
    Ok(())
}

/// Levenshtein distance between two keys (insertions, deletions, substitutions of chars).
pub(super) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

/// For serde's "unknown field `X`, expected one of `a`, `b`, …" (or "unknown variant"), the
/// known name nearest to `X` when it is near enough to be a misspelling (at most a third of
/// its letters differ, 1 to 3 edits): "did you mean `number_of_shells`?".
pub(super) fn suggestion(message: &str) -> Option<String> {
    if !(message.starts_with("unknown field `") || message.starts_with("unknown variant `")) {
        return None;
    }
    // Backticked words: the unknown one, then the expected ones.
    let mut words = message.split('`').skip(1).step_by(2);
    let unknown = words.next()?;
    let limit = (unknown.chars().count() / 3).clamp(1, 3);
    let (distance, best) = words
        .map(|known| (edit_distance(unknown, known), known))
        .min_by_key(|&(d, _)| d)?;
    (distance <= limit).then(|| format!("did you mean `{best}`?"))
}

/// Finds the 1-based line of a dotted key (`fur.number_of_shells`) by following table
/// headers; `None` when the key is not written in the file (a default failed, or an inline
/// table hides it).
pub(super) fn line_of_key(text: &str, dotted: &str) -> Option<usize> {
    // `spots[2].radii`: the key inside the third `[[spots]]` table.
    if let Some((array, rest)) = dotted.split_once('[')
        && let Some((index, key)) = rest.split_once("].")
        && let Ok(index) = index.parse::<usize>()
    {
        return line_in_array_table(text, array, index, key);
    }
    let dotted = dotted.split('[').next().unwrap_or(dotted);
    let (table, key) = match dotted.rsplit_once('.') {
        Some((t, k)) => (t, k),
        None => ("", dotted),
    };
    let mut current = String::new();
    let mut table_line = None;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if let Some(header) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            current = header.trim().to_string();
            if current == table {
                table_line = Some(n + 1);
            }
            continue;
        }
        let name = line.split('=').next().unwrap_or("").trim();
        if current == table && name == key {
            return Some(n + 1);
        }
        // `weights = { ... }` style inline tables: point at the inline table's line.
        if let Some((parent, last)) = table.rsplit_once('.')
            && current == parent
            && name == last
        {
            return Some(n + 1);
        }
    }
    // A whole array of tables (`spots`): its first `[[spots]]` header.
    table_line.or_else(|| {
        text.lines()
            .position(|raw| {
                let line = raw.split('#').next().unwrap_or("").trim();
                line.strip_prefix("[[")
                    .and_then(|l| l.strip_suffix("]]"))
                    .is_some_and(|h| h.trim() == dotted)
            })
            .map(|n| n + 1)
    })
}

/// The dotted key written on 1-based `line` (`fur.number_of_shells`, `spots[1].radii`), or the
/// table when the line is a header; `None` outside any key.
pub(super) fn key_at_line(text: &str, line: usize) -> Option<String> {
    let mut table = String::new();
    let mut counts: std::collections::BTreeMap<String, usize> = Default::default();
    for (n, raw) in text.lines().enumerate() {
        let l = raw.split('#').next().unwrap_or("").trim();
        let header = if let Some(h) = l.strip_prefix("[[").and_then(|h| h.split_once("]]")) {
            let name = h.0.trim().to_string();
            let count = counts.entry(name.clone()).or_insert(0);
            *count += 1;
            Some(format!("{name}[{}]", *count - 1))
        } else {
            l.strip_prefix('[')
                .and_then(|h| h.split_once(']'))
                .map(|h| h.0.trim().to_string())
        };
        if let Some(h) = header {
            table = h;
            if n + 1 == line {
                return Some(table).filter(|t| !t.is_empty());
            }
            continue;
        }
        if n + 1 == line {
            let name = l.split_once('=').map(|(k, _)| k.trim())?;
            if name.is_empty() || name.contains(char::is_whitespace) {
                return None;
            }
            return Some(if table.is_empty() {
                name.to_string()
            } else {
                format!("{table}.{name}")
            });
        }
    }
    None
}

/// The line of `key` in the `index`-th `[[array]]` table (or the table's header line).
fn line_in_array_table(text: &str, array: &str, index: usize, key: &str) -> Option<usize> {
    let header = format!("[[{array}]]");
    let mut seen = 0usize;
    let mut inside = false;
    let mut header_line = None;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.starts_with('[') {
            inside = line == header && {
                seen += 1;
                seen == index + 1
            };
            if inside {
                header_line = Some(n + 1);
            }
            continue;
        }
        if inside && line.split('=').next().unwrap_or("").trim() == key {
            return Some(n + 1);
        }
    }
    header_line
}

#[cfg(test)]
mod suggestion_tests {
    use super::*;

    #[test]
    fn misspelt_keys_get_the_nearest_known_key_and_others_none() {
        assert_eq!(edit_distance("number_of_shell", "number_of_shells"), 1);
        assert_eq!(edit_distance("speculr", "specular"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        let fur = "unknown field `number_of_shell`, expected one of `number_of_strands`, \
                   `number_of_shells`, `texture_resolution`";
        assert_eq!(
            suggestion(fur).as_deref(),
            Some("did you mean `number_of_shells`?")
        );
        let kind = "unknown variant `toru`, expected one of `torus`, `sphere`";
        assert_eq!(suggestion(kind).as_deref(), Some("did you mean `torus`?"));
        // Too far from anything: no guess.
        let far = "unknown field `weights`, expected one of `fins`, `curl`";
        assert_eq!(suggestion(far), None);
        assert_eq!(suggestion("invalid type: string \"a\", expected u32"), None);
    }

    #[test]
    fn an_array_of_tables_is_found_by_its_first_header() {
        let text = "seed = 1\n[image]\nwidth = 8\n[[spots]]\n[[spots]]\n";
        assert_eq!(line_of_key(text, "spots"), Some(4));
    }
}

#[cfg(test)]
mod tests {
    use super::super::Scene;
    use std::path::Path;

    fn parse(text: &str) -> Result<Scene, super::super::SceneError> {
        Scene::parse(text, "test.toml", Path::new("."))
    }

    #[test]
    fn empty_scene_takes_the_thesis_base_values() {
        let s = parse("").expect("defaults are valid");
        assert_eq!(s.fur.number_of_strands, 1000);
        assert_eq!(s.fur.strand_resolution, 20);
        assert_eq!(s.fur.circle_resolution, 10);
        assert_eq!(s.fur.number_of_shells, 10);
        assert_eq!(s.fur.texture_resolution, 128);
        assert_eq!(s.mesh.model_resolution, 500);
        assert_eq!(s.shading.banks_exponent, 4.8);
    }

    #[test]
    fn out_of_range_values_name_file_line_and_key() {
        let err =
            parse("seed = 1\n[fur]\nnumber_of_strands = 10\nnumber_of_shells = 0\n").unwrap_err();
        assert_eq!(err.line, Some(4));
        assert!(
            err.to_string()
                .starts_with("test.toml:4: fur.number_of_shells = 0"),
            "{err}"
        );
        assert!(
            parse("[fur]\nmodel_difference = -1.0\n").is_ok(),
            "negative thins"
        );
        let err = parse("[fur]\nmodel_difference = 0.0\n").unwrap_err();
        assert!(err.to_string().contains("fur.model_difference"), "{err}");
        let err = parse("[image]\nwidth = 100000\n").unwrap_err();
        assert_eq!(err.line, Some(2));
        let err = parse("[shading]\nweights = { shadow = -1.0 }\n").unwrap_err();
        assert_eq!(err.line, Some(2), "{err}");
        assert!(err.message.contains("shading.weights.shadow"), "{err}");
        let err =
            parse("[shading]\nlighting = \"eq-3.5\"\nspecular1_exponent = -2.0\n").unwrap_err();
        assert_eq!(err.line, Some(3), "{err}");
        assert!(err.message.contains("shading.specular1_exponent"), "{err}");
    }

    #[test]
    fn unknown_keys_and_bad_types_are_errors_with_lines() {
        let err = parse("[fur]\nnumber_of_strands = 10\nnumber_of_hairs = 3\n").unwrap_err();
        assert_eq!(err.line, Some(3), "{err}");
        assert!(err.message.contains("number_of_hairs"), "{err}");
        let err = parse("[camera]\neye = [1, 2]\n").unwrap_err();
        assert_eq!(err.line, Some(2), "{err}");
        let err = parse("[mesh]\nkind = \"teapot\"\n").unwrap_err();
        assert!(err.message.contains("teapot"), "{err}");
        let err = parse("[light]\ndirection = [0, 0, 0]\n").unwrap_err();
        assert!(err.message.contains("light.direction"), "{err}");
        let err = parse("[fur]\nmodel_difference = nan\n").unwrap_err();
        assert!(err.message.contains("fur.model_difference"), "{err}");
    }

    #[test]
    fn type_errors_name_the_key() {
        let err = parse("seed = 1\n[image]\nwidth = \"big\"\n").unwrap_err();
        assert_eq!(err.line, Some(3), "{err}");
        assert!(err.message.starts_with("image.width: "), "{err}");
        let err = parse("[[spots]]\n[[spots]]\nradii = [1, 2]\n").unwrap_err();
        assert!(err.message.starts_with("spots[1].radii: "), "{err}");
        let err = parse("time = \"noon\"\n").unwrap_err();
        assert!(err.message.starts_with("time: "), "{err}");
        assert_eq!(super::key_at_line("[a]\n\n", 2), None);
        assert_eq!(super::key_at_line("[a.b]\n", 1), Some("a.b".into()));
    }

    #[test]
    fn effects_are_checked_with_their_keys() {
        let two_spots =
            "[[spots]]\nradii = [1, 1, 1]\n\n[[spots]]\ncolour = [1, 1, 1]\nradii = [1, -2, 1]\n";
        let err = parse(two_spots).unwrap_err();
        assert!(err.message.contains("spots[1].radii"), "{err}");
        assert_eq!(err.line, Some(6), "{err}");
        let err = parse("[burn]\nhigh_exponent = 4.0\nlow_exponent = 50.0\n").unwrap_err();
        assert!(err.message.contains("burn.low_exponent"), "{err}");
        assert_eq!(err.line, Some(3));
        let err = parse("[wind]\nstrength = nan\n").unwrap_err();
        assert!(err.message.contains("wind.strength"), "{err}");
        let err = parse("[wind]\ndirection = [0, 0, 0]\n").unwrap_err();
        assert!(err.message.contains("wind.direction"), "{err}");
        let err = parse("[[stripes]]\nkind = \"axis\"\nperiod = -1.0\n").unwrap_err();
        assert!(err.message.contains("stripes[0].period"), "{err}");
        let err =
            parse("[[spots]]\nkind = \"light\"\ninner_threshold = 0.2\nouter_threshold = 0.5\n")
                .unwrap_err();
        assert!(err.message.contains("outer_threshold"), "{err}");
        assert!(parse("time = 2.5\n[wind]\n[burn]\nmatches = [[0, 1, 0], [1, 0, 0]]\n").is_ok());
        let err = parse("[[stripes]]\nkind = \"light\"\ndirection = [0, 0, 0]\n").unwrap_err();
        assert!(err.message.contains("stripes[0].direction"), "{err}");
        assert_eq!(err.line, Some(3), "{err}");
        let err = parse("[[stripes]]\nkind = \"light\"\nexponent = -1\n").unwrap_err();
        assert!(err.message.contains("stripes[0].exponent"), "{err}");
        // A light stripe needs no axis, an axis stripe no light.
        // A light stripe (the default kind) refuses an axis, an axis stripe a light.
        let err = parse("[[stripes]]\ncolour = [1, 1, 1]\naxis = [1, 0, 0]\n").unwrap_err();
        assert!(err.message.contains("stripes[0].axis"), "{err}");
        assert!(err.message.contains("kind = \"axis\""), "{err}");
        assert_eq!(err.line, Some(3), "{err}");
        let err = parse("[[stripes]]\nkind = \"axis\"\nexponent = 2\n").unwrap_err();
        assert!(err.message.contains("stripes[0].exponent"), "{err}");
        let err = parse("[[stripes]]\nperiod = 5\n").unwrap_err();
        assert!(err.message.contains("stripes[0].period"), "{err}");
        assert!(parse("[[stripes]]\nkind = \"axis\"\nperiod = 5\nwidth = 2\n").is_ok());
        assert!(parse("[[stripes]]\nkind = \"axis\"\naxis = [0, 0, 0]\n").is_err());
    }

    #[test]
    fn convention_keys_take_named_values_only() {
        for (table, key, good, bad) in [
            ("[shading]", "specular_lobes", ["sum", "average"], "mean"),
            (
                "[shading]",
                "ambient_term",
                ["constant", "strand"],
                "outside",
            ),
            ("[shading]", "shadow_texel", ["opaque", "alpha"], "count"),
            ("[shading]", "lighting", ["eq-3.6", "eq-3.5"], "eq-3.4"),
            ("[[stripes]]", "kind", ["axis", "light"], "band"),
        ] {
            for value in good {
                let text = format!("{table}\n{key} = \"{value}\"\n");
                assert!(parse(&text).is_ok(), "{text}");
            }
            let text = format!("seed = 1\n{table}\n{key} = \"{bad}\"\n");
            let err = parse(&text).unwrap_err();
            assert_eq!(err.file, "test.toml");
            assert_eq!(err.line, Some(3), "{err}");
            assert!(
                err.message.contains(key) && err.message.contains(bad),
                "{err}"
            );
        }
    }

    #[test]
    fn vectors_that_vanish_or_overflow_when_normalised_are_refused() {
        for (text, key) in [
            (
                "[light]\ndirection = [1e30, 1e30, 1e30]\n",
                "light.direction",
            ),
            (
                "[light]\ndirection = [1e-30, 0.0, 0.0]\n",
                "light.direction",
            ),
            ("[wind]\ndirection = [3e38, 3e38, 0.0]\n", "wind.direction"),
            (
                "[gravity]\ndirection = [0.0, -1e-25, 0.0]\n",
                "gravity.direction",
            ),
            ("[light]\ncolour = [nan, 1.0, 1.0]\n", "light.colour"),
            (
                "[camera]\neye = [3e38, 0.0, 0.0]\ntarget = [-3e38, 0.0, 0.0]\n",
                "camera.eye",
            ),
        ] {
            let err = parse(text).unwrap_err();
            assert!(err.to_string().contains(key), "{text}: {err}");
        }
    }

    #[test]
    fn arrays_longer_than_their_value_are_refused() {
        for (text, key) in [
            (
                "[light]\ndirection = [1.0, 0.0, 0.0, 9.0]\n",
                "light.direction",
            ),
            (
                "[fur]\ntexture_repeat = [8.0, 4.0, 2.0]\n",
                "fur.texture_repeat",
            ),
            (
                "[image]\nbackground = [0.1, 0.2, 0.3, \"x\"]\n",
                "image.background",
            ),
        ] {
            let err = parse(text).unwrap_err();
            assert!(err.to_string().contains(key), "{text}: {err}");
            assert!(err.to_string().contains("takes exactly"), "{text}: {err}");
        }
        assert!(parse("[light]\ndirection = [1.0, 0.0, 0.0]\n").is_ok());
    }

    #[test]
    fn mesh_keys_without_effect_are_refused() {
        for (text, key) in [
            (
                "[mesh]\nkind = \"torus\"\npath = \"bunny.obj\"\n",
                "mesh.path",
            ),
            (
                "[mesh]\nkind = \"sphere\"\nmajor_radius = 3.0\n",
                "mesh.major_radius",
            ),
            ("[mesh]\nkind = \"leg\"\nradius = 5.0\n", "mesh.radius"),
        ] {
            let err = parse(text).unwrap_err();
            assert!(err.to_string().contains(key), "{text}: {err}");
            assert!(err.to_string().contains("no effect"), "{text}: {err}");
        }
        // The defaults a written-back scene lists are let through.
        assert!(parse("[mesh]\nkind = \"sphere\"\nmajor_radius = 6.0\nradius = 3.0\n").is_ok());
    }
}
