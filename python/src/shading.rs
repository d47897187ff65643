//! `pelage._pelage`'s shading terms: each calls the `pelage::shading` function the renderer's
//! fragment stage calls (whose SIMD lanes the library's tests hold to the same bits), once per
//! item of flat `float32` arrays. Vectors are `3` (or `2`) consecutive values per item; the
//! Python side (`pelage.shading`) broadcasts and flattens.

use super::{floats, slice_of};
use numpy::{PyArray1, PyReadonlyArray1};
use pelage::glam::{Vec2, Vec3};
use pelage::shading as terms;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

type Floats<'py> = PyReadonlyArray1<'py, f32>;
type Out<'py> = PyResult<Bound<'py, PyArray1<f32>>>;

/// The most shadow lookups a call may ask for (the renderer's count is at most the number of
/// shells, itself at most a few thousand).
const MAX_LOOKUPS: u32 = 1 << 16;

/// The `i`th vector of a flat array of 3-vectors.
fn vec3(values: &[f32], i: usize) -> Vec3 {
    Vec3::new(values[3 * i], values[3 * i + 1], values[3 * i + 2])
}

/// The `i`th vector of a flat array of 2-vectors.
fn vec2(values: &[f32], i: usize) -> Vec2 {
    Vec2::new(values[2 * i], values[2 * i + 1])
}

fn shadow_texel_kind(name: &str) -> PyResult<terms::ShadowTexel> {
    match name {
        "alpha" => Ok(terms::ShadowTexel::Alpha),
        "opaque" => Ok(terms::ShadowTexel::Opaque),
        _ => Err(PyValueError::new_err(format!(
            "texel = {name:?}: \"alpha\" or \"opaque\" is expected"
        ))),
    }
}

fn ambient_kind(name: &str) -> PyResult<terms::AmbientTerm> {
    match name {
        "strand" => Ok(terms::AmbientTerm::Strand),
        "constant" => Ok(terms::AmbientTerm::Constant),
        _ => Err(PyValueError::new_err(format!(
            "ambient_term = {name:?}: \"strand\" or \"constant\" is expected"
        ))),
    }
}

/// Kajiya–Kay diffuse, eq. 2.5 with Banks's exponent.
#[pyfunction]
fn kajiya_kay_diffuse<'py>(
    py: Python<'py>,
    n: usize,
    tangent: Floats<'py>,
    light: Floats<'py>,
    exponent: Floats<'py>,
) -> Out<'py> {
    let (t, l, p) = (
        slice_of(&tangent, "tangent", n, 3)?,
        slice_of(&light, "light", n, 3)?,
        slice_of(&exponent, "exponent", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::kajiya_kay_diffuse(vec3(t, i), vec3(l, i), p[i]))
            .collect(),
    ))
}

/// Kajiya–Kay specular, eq. 2.7.
#[pyfunction]
fn kajiya_kay_specular<'py>(
    py: Python<'py>,
    n: usize,
    tangent: Floats<'py>,
    light: Floats<'py>,
    eye: Floats<'py>,
    exponent: Floats<'py>,
) -> Out<'py> {
    let (t, l, e, p) = (
        slice_of(&tangent, "tangent", n, 3)?,
        slice_of(&light, "light", n, 3)?,
        slice_of(&eye, "eye", n, 3)?,
        slice_of(&exponent, "exponent", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::kajiya_kay_specular(vec3(t, i), vec3(l, i), vec3(e, i), p[i]))
            .collect(),
    ))
}

/// The sine of the angle between two vectors, as a shader computes it.
#[pyfunction]
fn sin_between<'py>(py: Python<'py>, n: usize, a: Floats<'py>, b: Floats<'py>) -> Out<'py> {
    let (a, b) = (slice_of(&a, "a", n, 3)?, slice_of(&b, "b", n, 3)?);
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::sin_between(vec3(a, i), vec3(b, i)))
            .collect(),
    ))
}

/// The dampened specular of thesis 3.2.3.
#[pyfunction]
fn dampened_specular<'py>(py: Python<'py>, n: usize, specular: Floats<'py>) -> Out<'py> {
    let s = slice_of(&specular, "specular", n, 1)?;
    Ok(floats(
        py,
        s.iter().map(|&s| terms::dampened_specular(s)).collect(),
    ))
}

/// Eq. 3.5's last term, `(ψ_specularity1)^n`.
#[pyfunction]
fn specularity1_power<'py>(
    py: Python<'py>,
    n: usize,
    specularity1: Floats<'py>,
    exponent: Floats<'py>,
) -> Out<'py> {
    let (s, p) = (
        slice_of(&specularity1, "specularity1", n, 1)?,
        slice_of(&exponent, "exponent", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::specularity1_power(s[i], p[i]))
            .collect(),
    ))
}

/// Eq. 3.7, the final colour.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // one argument per term of eq. 3.7, in its order
fn final_colour<'py>(
    py: Python<'py>,
    n: usize,
    strand_colour: Floats<'py>,
    light_colour: Floats<'py>,
    ambient: Floats<'py>,
    diffuse: Floats<'py>,
    specular: Floats<'py>,
    dampened: Floats<'py>,
    shadow: Floats<'py>,
    weights: [f32; 5],
    ambient_term: &str,
) -> Out<'py> {
    let term = ambient_kind(ambient_term)?;
    let [w_ambient, w_diffuse, w_specular, w_dampened, w_shadow] = weights;
    let weights = terms::ShadingWeights {
        ambient: w_ambient,
        diffuse: w_diffuse,
        specular: w_specular,
        dampened: w_dampened,
        shadow: w_shadow,
    };
    let (s, l) = (
        slice_of(&strand_colour, "strand_colour", n, 3)?,
        slice_of(&light_colour, "light_colour", n, 3)?,
    );
    let (a, d, sp, dm, sh) = (
        slice_of(&ambient, "ambient", n, 1)?,
        slice_of(&diffuse, "diffuse", n, 1)?,
        slice_of(&specular, "specular", n, 1)?,
        slice_of(&dampened, "dampened", n, 1)?,
        slice_of(&shadow, "shadow", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .flat_map(|i| {
                terms::final_colour(
                    vec3(s, i),
                    vec3(l, i),
                    a[i],
                    d[i],
                    sp[i],
                    dm[i],
                    sh[i],
                    &weights,
                    term,
                )
                .to_array()
            })
            .collect(),
    ))
}

/// The shell shadow's change vector towards the light (thesis 3.2.2).
#[pyfunction]
fn shadow_change<'py>(
    py: Python<'py>,
    n: usize,
    light: Floats<'py>,
    normal: Floats<'py>,
    height_above: Floats<'py>,
) -> Out<'py> {
    let (l, nm, h) = (
        slice_of(&light, "light", n, 3)?,
        slice_of(&normal, "normal", n, 3)?,
        slice_of(&height_above, "height_above", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .flat_map(|i| terms::shadow_change(vec3(l, i), vec3(nm, i), h[i]).to_array())
            .collect(),
    ))
}

/// A change vector projected to (u, v), dropping the axis with the least change (3.2.2).
#[pyfunction]
fn project_to_uv<'py>(
    py: Python<'py>,
    n: usize,
    change: Floats<'py>,
    dpdu: Floats<'py>,
    dpdv: Floats<'py>,
) -> Out<'py> {
    let (c, u, v) = (
        slice_of(&change, "change", n, 3)?,
        slice_of(&dpdu, "dpdu", n, 3)?,
        slice_of(&dpdv, "dpdv", n, 3)?,
    );
    Ok(floats(
        py,
        (0..n)
            .flat_map(|i| terms::project_to_uv(vec3(c, i), vec3(u, i), vec3(v, i)).to_array())
            .collect(),
    ))
}

/// `m = (N − i)/n` of table 4.4: the number of shadow lookups of a shell.
#[pyfunction]
fn shadow_lookup_count(number_of_shells: u32, shell_index: u32, divisor: u32) -> u32 {
    terms::shadow_lookup_count(number_of_shells, shell_index, divisor)
}

/// What one shadow lookup adds for a texel's alpha.
#[pyfunction]
fn shadow_texel<'py>(py: Python<'py>, n: usize, alpha: Floats<'py>, texel: &str) -> Out<'py> {
    let kind = shadow_texel_kind(texel)?;
    let a = slice_of(&alpha, "alpha", n, 1)?;
    Ok(floats(
        py,
        a.iter().map(|&a| terms::shadow_texel(a, kind)).collect(),
    ))
}

fn check_lookups(lookups: u32, n: usize) -> PyResult<usize> {
    if lookups > MAX_LOOKUPS {
        return Err(PyValueError::new_err(format!(
            "lookups = {lookups}: at most {MAX_LOOKUPS}"
        )));
    }
    n.checked_mul(lookups as usize)
        .filter(|&total| total <= 1 << 28)
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "{n} points × {lookups} lookups is too many (at most 2^28)"
            ))
        })
}

/// Where the `m` lookups of [`terms::shell_shadow`] land, per point: `(n, m, 2)` flat. The
/// points are those the renderer samples, recorded from the function itself.
#[pyfunction]
fn shadow_lookup_points<'py>(
    py: Python<'py>,
    n: usize,
    uv: Floats<'py>,
    shadow_lookup: Floats<'py>,
    lookups: u32,
) -> Out<'py> {
    let total = check_lookups(lookups, n)?;
    let (uv, step) = (
        slice_of(&uv, "uv", n, 2)?,
        slice_of(&shadow_lookup, "shadow_lookup", n, 2)?,
    );
    let mut points = Vec::with_capacity(total * 2);
    for i in 0..n {
        terms::shell_shadow(
            |p| {
                points.extend(p.to_array());
                0.0
            },
            vec2(uv, i),
            vec2(step, i),
            lookups,
            terms::ShadowTexel::Alpha,
        );
    }
    Ok(floats(py, points))
}

/// The shell shadow of each point from the alphas sampled at its `m` lookups, summed in the
/// renderer's order (`(n, m)` flat alphas in, `n` values out).
#[pyfunction]
fn shell_shadow<'py>(
    py: Python<'py>,
    n: usize,
    alphas: Floats<'py>,
    lookups: u32,
    texel: &str,
) -> Out<'py> {
    let kind = shadow_texel_kind(texel)?;
    check_lookups(lookups, n)?;
    let a = slice_of(&alphas, "alphas", n, lookups as usize)?;
    let m = lookups as usize;
    Ok(floats(
        py,
        (0..n)
            .map(|i| {
                let mut sampled = a[i * m..(i + 1) * m].iter();
                terms::shell_shadow(
                    |_| sampled.next().copied().unwrap_or(0.0),
                    Vec2::ZERO,
                    Vec2::ZERO,
                    lookups,
                    kind,
                )
            })
            .collect(),
    ))
}

/// A geometric spot: the intensity inside an ellipsoid (3.2.4).
#[pyfunction]
fn ellipsoid_spot_intensity<'py>(
    py: Python<'py>,
    n: usize,
    point: Floats<'py>,
    centre: Floats<'py>,
    radii: Floats<'py>,
    inner: Floats<'py>,
) -> Out<'py> {
    let (p, c, r, k) = (
        slice_of(&point, "point", n, 3)?,
        slice_of(&centre, "centre", n, 3)?,
        slice_of(&radii, "radii", n, 3)?,
        slice_of(&inner, "inner", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::ellipsoid_spot_intensity(vec3(p, i), vec3(c, i), vec3(r, i), k[i]))
            .collect(),
    ))
}

/// A light-based spot: the lobe of a light fixed to the object (3.2.4).
#[pyfunction]
fn light_spot_intensity<'py>(
    py: Python<'py>,
    n: usize,
    normal: Floats<'py>,
    direction: Floats<'py>,
    exponent: Floats<'py>,
) -> Out<'py> {
    let (nm, d, p) = (
        slice_of(&normal, "normal", n, 3)?,
        slice_of(&direction, "direction", n, 3)?,
        slice_of(&exponent, "exponent", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::light_spot_intensity(vec3(nm, i), vec3(d, i), p[i]))
            .collect(),
    ))
}

/// A spot's weight from its intensity: full inside, a gradient in the outer ring.
#[pyfunction]
fn spot_gradient<'py>(
    py: Python<'py>,
    n: usize,
    intensity: Floats<'py>,
    inner_threshold: Floats<'py>,
    outer_threshold: Floats<'py>,
) -> Out<'py> {
    let (s, a, b) = (
        slice_of(&intensity, "intensity", n, 1)?,
        slice_of(&inner_threshold, "inner_threshold", n, 1)?,
        slice_of(&outer_threshold, "outer_threshold", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::spot_gradient(s[i], a[i], b[i]))
            .collect(),
    ))
}

/// The fur colour moved towards a spot colour by a weight.
#[pyfunction]
fn apply_spot<'py>(
    py: Python<'py>,
    n: usize,
    fur_colour: Floats<'py>,
    spot_colour: Floats<'py>,
    weight: Floats<'py>,
) -> Out<'py> {
    let (f, s, w) = (
        slice_of(&fur_colour, "fur_colour", n, 3)?,
        slice_of(&spot_colour, "spot_colour", n, 3)?,
        slice_of(&weight, "weight", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .flat_map(|i| terms::apply_spot(vec3(f, i), vec3(s, i), w[i]).to_array())
            .collect(),
    ))
}

/// A stripe across an axis: bands of a period along a coordinate.
#[pyfunction]
fn stripe_intensity<'py>(
    py: Python<'py>,
    n: usize,
    coordinate: Floats<'py>,
    period: Floats<'py>,
    width: Floats<'py>,
    softness: Floats<'py>,
) -> Out<'py> {
    let (c, p, w, s) = (
        slice_of(&coordinate, "coordinate", n, 1)?,
        slice_of(&period, "period", n, 1)?,
        slice_of(&width, "width", n, 1)?,
        slice_of(&softness, "softness", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::stripe_intensity(c[i], p[i], w[i], s[i]))
            .collect(),
    ))
}

/// The thesis's stripes: bands of the lobe of a light fixed to the object.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // the term's own arguments, flattened
fn light_stripe_intensity<'py>(
    py: Python<'py>,
    n: usize,
    normal: Floats<'py>,
    direction: Floats<'py>,
    exponent: Floats<'py>,
    period: Floats<'py>,
    width: Floats<'py>,
    softness: Floats<'py>,
) -> Out<'py> {
    let (nm, d) = (
        slice_of(&normal, "normal", n, 3)?,
        slice_of(&direction, "direction", n, 3)?,
    );
    let (e, p, w, s) = (
        slice_of(&exponent, "exponent", n, 1)?,
        slice_of(&period, "period", n, 1)?,
        slice_of(&width, "width", n, 1)?,
        slice_of(&softness, "softness", n, 1)?,
    );
    Ok(floats(
        py,
        (0..n)
            .map(|i| terms::light_stripe_intensity(vec3(nm, i), vec3(d, i), e[i], p[i], w[i], s[i]))
            .collect(),
    ))
}

/// Adds the shading functions to the native module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("BANKS_EXPONENT", terms::BANKS_EXPONENT)?;
    m.add("SHADOW_OPAQUE_ALPHA", terms::SHADOW_OPAQUE_ALPHA)?;
    m.add_function(wrap_pyfunction!(kajiya_kay_diffuse, m)?)?;
    m.add_function(wrap_pyfunction!(kajiya_kay_specular, m)?)?;
    m.add_function(wrap_pyfunction!(sin_between, m)?)?;
    m.add_function(wrap_pyfunction!(dampened_specular, m)?)?;
    m.add_function(wrap_pyfunction!(specularity1_power, m)?)?;
    m.add_function(wrap_pyfunction!(final_colour, m)?)?;
    m.add_function(wrap_pyfunction!(shadow_change, m)?)?;
    m.add_function(wrap_pyfunction!(project_to_uv, m)?)?;
    m.add_function(wrap_pyfunction!(shadow_lookup_count, m)?)?;
    m.add_function(wrap_pyfunction!(shadow_texel, m)?)?;
    m.add_function(wrap_pyfunction!(shadow_lookup_points, m)?)?;
    m.add_function(wrap_pyfunction!(shell_shadow, m)?)?;
    m.add_function(wrap_pyfunction!(ellipsoid_spot_intensity, m)?)?;
    m.add_function(wrap_pyfunction!(light_spot_intensity, m)?)?;
    m.add_function(wrap_pyfunction!(spot_gradient, m)?)?;
    m.add_function(wrap_pyfunction!(apply_spot, m)?)?;
    m.add_function(wrap_pyfunction!(stripe_intensity, m)?)?;
    m.add_function(wrap_pyfunction!(light_stripe_intensity, m)?)?;
    Ok(())
}
