// pelage's fur shaders in WGSL: the vertex closures of src/render/mod.rs and the fragment closure
// of src/render/fragment.rs (`shade_fur`), term by term. Every function carries the name of the
// Rust function it mirrors (src/shading/*.rs) and the thesis equation it implements, so a
// difference between the backends can be traced to one term. Differences that remain by design:
// GPU `exp`, `log2`, `sin` and lod_alpha's `pow` instead of libm (the lobes' powers are pelage's
// own pow01, as in the oracle); the sampler's trilinear filter instead of the oracle's f32 one
// for the fur textures (the surface maps are read with the oracle's weights,
// `sample_map`); non-finite inputs are not sanitised (valid scenes never produce them).

// ---- uniforms ---------------------------------------------------------------------------

struct FrameUniforms {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,            // xyz: camera position, object space
    light: vec4<f32>,          // xyz: unit direction towards the light
    light_colour: vec4<f32>,   // xyz
    skin_colour: vec4<f32>,    // xyz: fur colour · 0.35
    wind: vec4<f32>,           // xyz: unit wind direction, w: wind_force(time) (3.3)
    fur: vec4<f32>,            // x, y: texture_repeat; z: model_difference; w: 1 when wind is on
    shading: vec4<f32>,        // ambient, banks_exponent, specular_exponent, the exponent of the
                               // uncoloured term's lobe (dampened_exponent; eq. 3.5: specular_exponent)
    shading2: vec4<f32>,       // tangent_shift, wind_tangent_fraction, burn exponent, 1 when burning
    weights: vec4<f32>,        // eq. 3.7 weights: ambient, diffuse, specular, dampened
    weights2: vec4<f32>,       // x: shadow weight; y, z, w: 1 for SpecularLobes::Sum,
                               // AmbientTerm::Constant, ShadowTexel::Opaque (else 0)
    counts: vec4<u32>,         // specular tangents (1 or 3), debug view, spots, matches
    offset: vec4<f32>,         // xyz: the object's offset on its path at this instant (0 at rest)
    lean: vec4<f32>,           // xyz: the shared lean (gravity + spring lag, world), w: 1 with a lean
    maps: vec4<u32>,           // x: maps present (1 length, 2 density, 4 direction, 8 colour);
                               // y, z: address along u, v (0 clamp, 1 wrap); w: 1 when the
                               // layers are not pulled back (wind.keep_length = false)
    lighting: vec4<f32>,       // x: 1 for eq. 3.5 (LightingModel::Eq35), 0 for eq. 3.6/3.7;
                               // y: n of (ψ_specularity1)^n; z, w: 0
}

struct LayerUniforms {
    index: u32,                // shell index (fins: the top shell)
    max_shell: u32,            // number_of_shells − 1
    lookups: u32,              // shadow lookups, m = (N − i)/n (3.2.2)
    height_fraction: f32,      // i / N
    offset: f32,               // distance above the skin
    clamp_v: u32,              // 1: clamp v (fins), 0: wrap
    lod_span: f32,             // baked layers this one stands for under level of detail (1 without)
    shell: u32,                // 1: a shell layer, 0: the fins (or the skin)
}

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
// Spots in application order, four vec4 each:
// [kind (0 ellipsoid, 1 light, 2 stripe, 3 light stripe), 0, 0, 0],
// [centre | direction | axis | direction (xyz), exponent | period | exponent (w)],
// [radii | 0 | 0 | (period, 0, 0) (xyz), inner | inner_threshold | width | width (w)],
// [colour (xyz), outer_threshold | softness | softness (w)].
@group(0) @binding(1) var<storage, read> spots: array<vec4<f32>>;
// The matches (3.4): a unit direction with w = 0, or a position with w = its reach (> 0).
@group(0) @binding(2) var<storage, read> matches: array<vec4<f32>>;
// The surface maps in mesh uv (render/maps.rs), 1×1 placeholders where the scene has none
// (frame.maps.x says which are real); read with textureLoad by `sample_map`.
@group(0) @binding(3) var length_map: texture_2d<f32>;
@group(0) @binding(4) var density_map: texture_2d<f32>;
@group(0) @binding(5) var direction_map: texture_2d<f32>;
@group(0) @binding(6) var tint_map: texture_2d<f32>;
// A skinned glTF model's joint palette (render::Skinning, mesh::skin), read by the vertex stages
// of `vs_skin_skinned` and `vs_shell_skinned` only (bound for glTF scenes): element 0 is
// (skin inset, joint count, 0, 0); joint j's column-major 4×4 matrix (mesh.scale included) is
// elements 1 + 4j … 4 + 4j, its columns.
@group(0) @binding(7) var<storage, read> palette: array<vec4<f32>>;

@group(1) @binding(0) var<uniform> layer: LayerUniforms;
@group(1) @binding(1) var colour_map: texture_2d<f32>;
@group(1) @binding(2) var tangent_map: texture_2d<f32>;
@group(1) @binding(3) var fur_sampler: sampler;
// Density bands of a shell layer (fur/bake.rs: R, G, B, A = alpha of the strands in bands
// ≤ 0..≤ 3); a placeholder on layers without them.
@group(1) @binding(4) var density_bands: texture_2d<f32>;

// ---- numeric helpers (src/shading/numeric.rs, glam) ------------------------------------

// glam's normalize_or_zero: v · (1/|v|) when that reciprocal is finite and positive.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let r = 1.0 / length(v);
    if (r > 0.0 && r < 3.0e38) {
        return v * r;
    }
    return vec3<f32>(0.0);
}

fn normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let r = 1.0 / length(v);
    if (r > 0.0 && r < 3.0e38) {
        return v * r;
    }
    return fallback;
}

fn saturate01(x: f32) -> f32 {
    if (x > 0.0) {
        return min(x, 1.0);
    }
    return 0.0;
}

// log2_pelage (numeric.rs log2_lane): pelage's own log2 of a positive x, subnormal included,
// for the powers and the level of detail: x = 2^e·m, m in [√½, √2),
// log2 m = c·s + (s·z)·Q(z), s = (m − 1)/(m + 1), z = s², c = 2/ln 2 rounded to f32.
fn log2_pelage(x: f32) -> f32 {
    var xs = x;
    var bias = 0.0;
    if (x < 0x1p-126f) {
        xs = x * 0x1p23f;
        bias = -23.0;
    }
    let bits = bitcast<i32>(xs);
    let k = (bits - 0x3f3504f3) >> 23u;
    let m = bitcast<f32>(bits - (k << 23u));
    let e = f32(k) + bias;
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let q = 0.96179825 + z * (0.57675403 + z * 0.43095794);
    let r = 2.88539 * s + (s * z) * q;
    return e + r;
}

// pow01 (numeric.rs pow01, its scalar twin): saturate(base)^max(exponent, 0), 0^0 = 1, as
// 2^(y·log2 x) with pelage's own polynomials, not the GPU's pow: the same operations in the
// same order, so the same bits where the GPU's arithmetic is IEEE and it does not contract
// a·b + c into a fused multiply-add (GPUs may, and may flush subnormals: within the GPU
// tolerance). round() is the oracle's (t + 1.5·2^23) − 1.5·2^23: nearest, ties to even.
fn pow01(base: f32, exponent: f32) -> f32 {
    let x = saturate01(base);
    let y = max(exponent, 0.0);
    if (y == 0.0) {
        return 1.0;
    }
    if (x <= 0.0) {
        return 0.0;
    }
    if (x >= 1.0) {
        return 1.0;
    }
    let t = y * log2_pelage(x);
    if (!(t >= -151.0)) {
        return 0.0;
    }
    // 2^t = 2^n·(1 + f·P(f)).
    let clamped = max(t, -152.0);
    let n = round(clamped);
    var whole = i32(n);
    let f = clamped - n;
    var p = 0.00015353342;
    p = 0.0013398901 + f * p;
    p = 0.009618438 + f * p;
    p = 0.055503324 + f * p;
    p = 0.24022648 + f * p;
    p = 0.6931472 + f * p;
    let fraction = 1.0 + f * p;
    var scale = 1.0;
    if (whole < -125) {
        whole = whole + 64;
        scale = 0x1p-64f;
    }
    return bitcast<f32>(bitcast<i32>(fraction) + (whole << 23u)) * scale;
}

fn smoothstep01(t0: f32) -> f32 {
    let t = saturate01(t0);
    return t * t * (3.0 - 2.0 * t);
}

// ramp: 0 at or below lo, 1 at or above hi (checked first), smoothstep between.
fn ramp(x: f32, lo: f32, hi: f32) -> f32 {
    if (x >= hi) {
        return 1.0;
    } else if (x <= lo) {
        return 0.0;
    }
    return smoothstep01((x - lo) / (hi - lo));
}

// ---- tangent space (3.2.1, tangent_space.rs) --------------------------------------------

struct TangentFrame {
    tangent: vec3<f32>,
    binormal: vec3<f32>,
    normal: vec3<f32>,
}

fn to_tangent_space(v: vec3<f32>, f: TangentFrame) -> vec3<f32> {
    return vec3<f32>(dot(v, f.tangent), dot(v, f.binormal), dot(v, f.normal));
}

// cos_sin_unit: cosine and sqrt(max(0, 1 − cos²)) of two unit-or-zero vectors.
fn cos_sin_unit(a: vec3<f32>, b: vec3<f32>) -> vec2<f32> {
    if (all(a == vec3<f32>(0.0)) || all(b == vec3<f32>(0.0))) {
        return vec2<f32>(0.0);
    }
    let c = clamp(dot(a, b), -1.0, 1.0);
    return vec2<f32>(c, sqrt(max(1.0 - c * c, 0.0)));
}

// ---- Kajiya–Kay (eq. 2.5, 2.7, 3.5; kajiya_kay.rs) ---------------------------------------

// Eq. 2.5 raised to Banks's exponent (3.2.3): sin(t, l)^p.
fn kajiya_kay_diffuse(tangent: vec3<f32>, light: vec3<f32>, banks_exponent: f32) -> f32 {
    let cs = cos_sin_unit(normalize_or_zero(tangent), normalize_or_zero(light));
    return pow01(cs.y, banks_exponent);
}

// Eq. 2.7 on unit vectors: ((t·l)(t·e) + sin(t, l) sin(t, e))^p.
fn specular_unit(t: vec3<f32>, l: vec3<f32>, e: vec3<f32>, exponent: f32) -> f32 {
    let a = cos_sin_unit(t, l);
    let b = cos_sin_unit(t, e);
    return pow01(a.x * b.x + a.y * b.y, exponent);
}

fn kajiya_kay_specular(tangent: vec3<f32>, light: vec3<f32>, eye: vec3<f32>, exponent: f32) -> f32 {
    return specular_unit(normalize_or_zero(tangent), normalize_or_zero(light), normalize_or_zero(eye), exponent);
}

// Scheuermann's shifted tangent (eq. 3.5): normalize(t + shift·n).
fn shift_tangent(tangent: vec3<f32>, normal: vec3<f32>, shift: f32) -> vec3<f32> {
    return normalize_or_zero(tangent + shift * normal);
}

// three_lobe_specular: the thesis's sum of the three lobes, or their mean (eq. 3.5).
fn three_lobe_specular(centre: f32, up: f32, down: f32) -> f32 {
    let sum = centre + up + down;
    if (frame.weights2.y != 0.0) {
        return sum;
    }
    return sum / 3.0;
}

// One tangent, or three (t, shifted up, shifted down) combined by three_lobe_specular, eq. 3.5.
fn specular_with_tangents(tangent: vec3<f32>, normal: vec3<f32>, light: vec3<f32>, eye: vec3<f32>,
                          exponent: f32, tangents: u32, shift: f32) -> f32 {
    let t = normalize_or_zero(tangent);
    let l = normalize_or_zero(light);
    let e = normalize_or_zero(eye);
    let centre = specular_unit(t, l, e, exponent);
    if (tangents != 3u) {
        return centre;
    }
    let n = normalize_or_zero(normal);
    let up = specular_unit(shift_tangent(t, n, shift), l, e, exponent);
    let down = specular_unit(shift_tangent(t, n, -shift), l, e, exponent);
    return three_lobe_specular(centre, up, down);
}

// ---- lighting (3.2.3, eq. 3.7; lighting.rs) ---------------------------------------------

const DAMPENING_THRESHOLD: f32 = 0.6;
const DAMPENED_SPECULAR_MAX: f32 = 0.3;

fn dampened_specular(s: f32) -> f32 {
    if (s > DAMPENING_THRESHOLD) {
        return DAMPENED_SPECULAR_MAX;
    } else if (s > 0.0) {
        return 0.5 * s;
    }
    return 0.0;
}

// specularity1_power: eq. 3.5's last term, (ψ_specularity1)^n.
fn specularity1_power(specularity1: f32, n: f32) -> f32 {
    return pow01(specularity1, n);
}

// uncoloured_specular: the last term, from the lobe of the strand's own tangent: the dampened
// specular (eq. 3.6/3.7), or (ψ_specularity1)^n under eq. 3.5.
fn uncoloured_specular(lobe: f32) -> f32 {
    if (frame.lighting.x != 0.0) {
        return specularity1_power(lobe, frame.lighting.y);
    }
    return dampened_specular(lobe);
}

// Eq. 3.7: A + strand·light·(w_d·diffuse + w_s·specular) + light·w_p·dampened − w_sh·shadow,
// each channel clamped to [0, 1]; A = ambient_term: w_a·ambient alone (eq. 3.7 as printed) or
// times the strand colour.
fn final_colour(strand_colour: vec3<f32>, light_colour: vec3<f32>, ambient: f32, diffuse: f32,
                specular: f32, dampened: f32, shadow: f32) -> vec3<f32> {
    let w = frame.weights;
    let lit = w.y * diffuse + w.z * specular;
    let highlight = w.w * dampened;
    let dark = frame.weights2.x * shadow;
    var out: vec3<f32>;
    for (var c = 0; c < 3; c++) {
        let s = strand_colour[c];
        let l = light_colour[c];
        var a = w.x * ambient;
        if (frame.weights2.z == 0.0) {
            a = a * s;
        }
        out[c] = saturate01(a + s * l * lit + l * highlight - dark);
    }
    return out;
}

// ---- projection (3.2.2; projection.rs) ---------------------------------------------------

const SINGULAR_RELATIVE_DET: f32 = 1e-3;

// Axis::least / Axis::greatest: ties to the lowest index.
fn axis_least(v: vec3<f32>) -> u32 {
    let a = abs(v);
    var best = 0u;
    if (a[1] < a[best]) { best = 1u; }
    if (a[2] < a[best]) { best = 2u; }
    return best;
}

fn axis_greatest(v: vec3<f32>) -> u32 {
    let a = abs(v);
    var best = 0u;
    if (a[1] > a[best]) { best = 1u; }
    if (a[2] > a[best]) { best = 2u; }
    return best;
}

fn kept_axes(dropped: u32) -> vec2<u32> {
    if (dropped == 0u) { return vec2<u32>(1u, 2u); }
    if (dropped == 1u) { return vec2<u32>(0u, 2u); }
    return vec2<u32>(0u, 1u);
}

fn abs_det(u: vec3<f32>, v: vec3<f32>, axis: u32) -> f32 {
    let k = kept_axes(axis);
    return abs(u[k.x] * v[k.y] - v[k.x] * u[k.y]);
}

// Cramer's rule on the kept axes; xy: the solution, z: 1 when solvable.
fn solve_dropping(c: vec3<f32>, u: vec3<f32>, v: vec3<f32>, dropped: u32) -> vec3<f32> {
    let k = kept_axes(dropped);
    let i = k.x;
    let j = k.y;
    let det = u[i] * v[j] - v[i] * u[j];
    let scale = length(u) * length(v);
    if (abs(det) <= SINGULAR_RELATIVE_DET * scale) {
        return vec3<f32>(0.0);
    }
    let a = (c[i] * v[j] - v[i] * c[j]) / det;
    let b = (u[i] * c[j] - c[i] * u[j]) / det;
    return vec3<f32>(a, b, 1.0);
}

fn project_to_uv_dropping(change: vec3<f32>, dpdu: vec3<f32>, dpdv: vec3<f32>, dropped: u32) -> vec2<f32> {
    let first = solve_dropping(change, dpdu, dpdv, dropped);
    if (first.z != 0.0) {
        return first.xy;
    }
    var best = 0u;
    for (var axis = 1u; axis < 3u; axis++) {
        if (abs_det(dpdu, dpdv, axis) > abs_det(dpdu, dpdv, best)) {
            best = axis;
        }
    }
    return solve_dropping(change, dpdu, dpdv, best).xy;
}

fn project_to_uv(change: vec3<f32>, dpdu: vec3<f32>, dpdv: vec3<f32>) -> vec2<f32> {
    return project_to_uv_dropping(change, dpdu, dpdv, axis_least(change));
}

// ---- shadow (3.2.2; shadow.rs) -----------------------------------------------------------

const SHADOW_MIN_COS: f32 = 0.25;

// shadowChange: l̂ · height_above / max(l̂·n̂, 0.25).
fn shadow_change(light_dir_world: vec3<f32>, normal: vec3<f32>, height_above: f32) -> vec3<f32> {
    let l = normalize_or_zero(light_dir_world);
    let n = normalize_or_zero(normal);
    let h = max(height_above, 0.0);
    let cos = max(dot(l, n), SHADOW_MIN_COS);
    return l * (h / cos);
}

// Sampler::sample_nearest_level: texel ⌊uv·size⌋ of mip level ⌊λ + 0.5⌋ of `t`. The level's
// size is level 0's halved `level` times (at least 1, as the oracle's chain is built), not
// textureDimensions(t, level): lavapipe answers that query for a level that differs between
// the lanes of one SIMD group with one lane's level, and the other lanes then read outside
// their level (robust access returns 0: shadow-free specks where λ crosses k + ½).
fn sample_nearest_level(t: texture_2d<f32>, uv: vec2<f32>, lod: f32) -> vec4<f32> {
    let max_level = f32(textureNumLevels(t) - 1u);
    let level = u32(clamp(lod, 0.0, max_level) + 0.5);
    let size = max(vec2<i32>(textureDimensions(t, 0u)) >> vec2<u32>(level), vec2<i32>(1));
    var x = i32(floor(uv.x * f32(size.x)));
    var y = i32(floor(uv.y * f32(size.y)));
    x = ((x % size.x) + size.x) % size.x;
    if (layer.clamp_v != 0u) {
        y = clamp(y, 0, size.y - 1);
    } else {
        y = ((y % size.y) + size.y) % size.y;
    }
    return textureLoad(t, vec2<i32>(x, y), i32(level));
}

// shade_fur's `covered_at`: the alpha of one texel, through the density bands on a shell with
// a density map, else the colour map's.
fn covered_at(uv: vec2<f32>, lod: f32, density: f32) -> f32 {
    if (has_bands()) {
        return density_alpha(sample_nearest_level(density_bands, uv, lod), density);
    }
    return sample_nearest_level(colour_map, uv, lod).a;
}

// SHADOW_OPAQUE_ALPHA: a texel is transparent below half the smallest non-zero 8-bit alpha.
const SHADOW_OPAQUE_ALPHA: f32 = 0.5 / 255.0;

// shadow_texel: 1 for a texel that is not transparent (the thesis's count, shadow_of_opaque),
// or the alpha saturated (shadow_of_alpha).
fn shadow_texel(alpha: f32) -> f32 {
    if (frame.weights2.w != 0.0) {
        return select(0.0, 1.0, alpha >= SHADOW_OPAQUE_ALPHA);
    }
    return saturate01(alpha);
}

// shell_shadow: Σ_{k=1..m} shadow_texel(covered(uv + step·(k/m))).
fn shell_shadow(uv: vec2<f32>, shadow_lookup: vec2<f32>, lookups: u32, lod: f32, density: f32) -> f32 {
    let m = f32(lookups);
    var shadow = 0.0;
    for (var k = 1u; k <= lookups; k++) {
        shadow += shadow_texel(covered_at(uv + shadow_lookup * (f32(k) / m), lod, density));
    }
    return shadow;
}

// ---- spots and stripes (3.2.4; spots.rs) -------------------------------------------------

fn ellipsoid_spot_intensity(p: vec3<f32>, centre: vec3<f32>, radii: vec3<f32>, inner: f32) -> f32 {
    let r = abs(radii);
    if (!(r.x > 0.0 && r.y > 0.0 && r.z > 0.0)) {
        return 0.0;
    }
    let d = length((p - centre) / r);
    return ramp(-d, -1.0, -saturate01(inner));
}

fn light_spot_intensity(normal: vec3<f32>, spot_light_dir: vec3<f32>, exponent: f32) -> f32 {
    return pow01(dot(normalize_or_zero(normal), normalize_or_zero(spot_light_dir)), exponent);
}

// reach_falloff: (1 − d²/R²)² inside the reach, 0 beyond.
fn reach_falloff(distance_squared: f32, reach: f32) -> f32 {
    let q = distance_squared / (reach * reach);
    if (q < 1.0 && reach > 0.0) {
        let k = 1.0 - q;
        return k * k;
    }
    return 0.0;
}

// point_light_cosine: n̂·o/√(o·o), o = light − point.
fn point_light_cosine(unit_normal: vec3<f32>, offset: vec3<f32>) -> f32 {
    let length_squared = dot(offset, offset);
    if (length_squared > 0.0) {
        return dot(unit_normal, offset) / sqrt(length_squared);
    }
    return 0.0;
}

// point_light_intensity: the lobe towards a light at a point, times its reach falloff.
fn point_light_intensity(unit_normal: vec3<f32>, point: vec3<f32>, light: vec3<f32>, reach: f32, exponent: f32) -> f32 {
    let offset = light - point;
    let falloff = reach_falloff(dot(offset, offset), reach);
    if (falloff == 0.0) {
        return 0.0;
    }
    return pow01(point_light_cosine(unit_normal, offset), exponent) * falloff;
}

fn spot_gradient(intensity: f32, inner_threshold: f32, outer_threshold: f32) -> f32 {
    return ramp(intensity, outer_threshold, inner_threshold);
}

fn apply_spot(fur_colour: vec3<f32>, spot_colour: vec3<f32>, weight: f32) -> vec3<f32> {
    let w = saturate01(weight);
    return fur_colour * (1.0 - w) + spot_colour * w;
}

// libm::roundf: half away from zero.
fn round_half_away(x: f32) -> f32 {
    return sign(x) * floor(abs(x) + 0.5);
}

fn stripe_intensity(coordinate: f32, period: f32, width: f32, softness: f32) -> f32 {
    if (!(period > 0.0)) {
        return 0.0;
    }
    let cell = coordinate / period;
    let dist = abs(cell - round_half_away(cell)) * period;
    let half = 0.5 * max(width, 0.0);
    let soft = max(softness, 0.0);
    return ramp(-dist, -(half + soft), -half);
}

// light_stripe_band: bands of the lobe value centred on (k + ½)·period.
fn light_stripe_band(lobe: f32, period: f32, width: f32, softness: f32) -> f32 {
    return stripe_intensity(lobe - 0.5 * period, period, width, softness);
}

// Spot::weight_at, applied in order (apply_spots).
fn apply_spots(fur_colour: vec3<f32>, object: vec3<f32>, normal: vec3<f32>) -> vec3<f32> {
    var strand = fur_colour;
    for (var s = 0u; s < frame.counts.z; s++) {
        let head = spots[4u * s];
        let a = spots[4u * s + 1u];
        let b = spots[4u * s + 2u];
        let c = spots[4u * s + 3u];
        var weight = 0.0;
        if (head.x == 0.0) {
            weight = ellipsoid_spot_intensity(object, a.xyz, b.xyz, b.w);
        } else if (head.x == 1.0) {
            let lobe = light_spot_intensity(normal, a.xyz, a.w);
            weight = spot_gradient(lobe, b.w, c.w);
        } else if (head.x == 2.0) {
            weight = stripe_intensity(dot(object, a.xyz), a.w, b.w, c.w);
        } else if (head.x == 4.0) {
            let lobe = point_light_intensity(normalize_or_zero(normal), object, a.xyz, b.x, a.w);
            weight = spot_gradient(lobe, b.w, c.w);
        } else {
            let lobe = light_spot_intensity(normal, a.xyz, a.w);
            weight = light_stripe_band(lobe, b.x, b.w, c.w);
        }
        strand = apply_spot(strand, c.xyz, weight);
    }
    return strand;
}

// ---- wind (3.3; wind.rs) -----------------------------------------------------------------

fn wind_displacement(wind_dir: vec3<f32>, normal: vec3<f32>, force: f32, shell_fraction: f32,
                     strand_height: f32) -> vec3<f32> {
    let w = normalize_or_zero(wind_dir);
    let n = normalize_or_zero(normal);
    let across = w - n * dot(w, n);
    let h = saturate01(shell_fraction) * max(strand_height, 0.0);
    let bend = clamp(force, -1.0, 1.0);
    let offset = across * (bend * h);
    let pull = h - sqrt(max(h * h - dot(offset, offset), 0.0));
    return offset - n * pull;
}

// vertex_pull: the vertex stage moves a layer only along the normal; the sideways part is the
// texture's (wind_uv_offset).
fn vertex_pull(displacement: vec3<f32>, normal: vec3<f32>) -> vec3<f32> {
    let n = normalize_or_zero(normal);
    return n * dot(displacement, n);
}

fn wind_uv_offset(displacement: vec3<f32>, normal: vec3<f32>, dpdu: vec3<f32>, dpdv: vec3<f32>) -> vec2<f32> {
    let n = normalize_or_zero(normal);
    let horizontal = displacement - n * dot(displacement, n);
    return project_to_uv_dropping(horizontal, dpdu, dpdv, axis_greatest(n));
}

// 3.3.1: normalize(t + fraction·w), falling back to the normalised tangent.
fn bend_tangent(tangent: vec3<f32>, wind_tangent_space: vec3<f32>, fraction: f32) -> vec3<f32> {
    return normalize_or(tangent + fraction * wind_tangent_space, normalize_or_zero(tangent));
}

// ---- surface maps (render/maps.rs; shading/maps.rs) -------------------------------------

const MAP_LENGTH: u32 = 1u;
const MAP_DENSITY: u32 = 2u;
const MAP_DIRECTION: u32 = 4u;
const MAP_COLOUR: u32 = 8u;

fn has_map(which: u32) -> bool {
    return (frame.maps.x & which) != 0u;
}

// A shell layer with density bands (LayerMaps::density is Some).
fn has_bands() -> bool {
    return has_map(MAP_DENSITY) && layer.shell != 0u;
}

// render/texture.rs `address` under `[maps] address`: wrap (Euclidean remainder) or clamp.
fn map_address(i: i32, size: i32, wrap: u32) -> i32 {
    if (wrap != 0u) {
        return ((i % size) + size) % size;
    }
    return clamp(i, 0, size - 1);
}

// A texel as its bytes (0–255): textureLoad of an RGBA8 texture gives byte/255.
fn texel_bytes(map: texture_2d<f32>, at: vec2<i32>) -> vec4<f32> {
    return round(textureLoad(map, at, 0) * 255.0);
}

// unorm8_exact: a filtered byte value scaled once, x·257/2^16 then y + y·(2^-16 + 2^-32).
fn unorm8_scale(x: vec4<f32>) -> vec4<f32> {
    let y = x * (257.0 / 65536.0);
    return y + y * (1.0 / 65536.0 + 1.0 / 4294967296.0);
}

// SurfaceMaps::sample: bilinear at level 0 between the texel centres (i + ½)/size, with the
// oracle's f32 weights (Sampler::bilinear_footprint and BilinearFootprint::filter) on the
// texels' bytes, scaled once, not the GPU sampler's fixed-point ones: a map decides cuts
// (length) and which strands show (density), so it is read as the oracle reads it.
fn sample_map(map: texture_2d<f32>, uv: vec2<f32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(map, 0u));
    let x = uv.x * f32(size.x) - 0.5;
    let y = uv.y * f32(size.y) - 0.5;
    let xf = floor(x);
    let yf = floor(y);
    let fx = x - xf;
    let fy = y - yf;
    let xa = map_address(i32(xf), size.x, frame.maps.y);
    let xb = map_address(i32(xf) + 1, size.x, frame.maps.y);
    let ya = map_address(i32(yf), size.y, frame.maps.z);
    let yb = map_address(i32(yf) + 1, size.y, frame.maps.z);
    let t00 = texel_bytes(map, vec2<i32>(xa, ya));
    let t10 = texel_bytes(map, vec2<i32>(xb, ya));
    let t01 = texel_bytes(map, vec2<i32>(xa, yb));
    let t11 = texel_bytes(map, vec2<i32>(xb, yb));
    let top = t00 + (t10 - t00) * fx;
    let bottom = t01 + (t11 - t01) * fx;
    return unorm8_scale(top + (bottom - top) * fy);
}

// SurfaceMaps::length_at: the length map's red channel, 1 without one.
fn length_at(uv: vec2<f32>) -> f32 {
    if (has_map(MAP_LENGTH)) {
        return sample_map(length_map, uv).x;
    }
    return 1.0;
}

// layer_within_length: the root layer always shows; layer i/N while i/N · vertex length is
// below the length sampled here.
fn layer_within_length(height_fraction: f32, vertex_length: f32, local_length: f32) -> bool {
    return height_fraction <= 0.0 || height_fraction * vertex_length < local_length;
}

// density_alpha: x = 4·saturate(density); linear between band ⌊x⌋ − 1 (0 below the first) and
// band ⌊x⌋; band 3 from x = 4 on.
fn density_band_alpha(bands: vec4<f32>, i: i32) -> f32 {
    if (i < 0) {
        return 0.0;
    }
    return bands[min(i, 3)];
}

fn density_alpha(bands: vec4<f32>, density: f32) -> f32 {
    let x = saturate01(density) * 4.0;
    let kf = floor(x);
    let f = x - kf;
    let k = i32(kf);
    if (k >= 4) {
        return bands.w;
    }
    let below = density_band_alpha(bands, k - 1);
    return below + (density_band_alpha(bands, k) - below) * f;
}

// comb_lean: (r·2 − 1, g·2 − 1, 0), shortened to length 1 when longer.
fn comb_lean(sample: vec4<f32>) -> vec3<f32> {
    var v = vec2<f32>(sample.x * 2.0 - 1.0, sample.y * 2.0 - 1.0);
    let l = length(v);
    if (l > 1.0) {
        v = v / l;
    }
    return vec3<f32>(v, 0.0);
}

// tint_strand: strand · saturate(tint), per channel.
fn tint_strand(strand: vec3<f32>, tint: vec3<f32>) -> vec3<f32> {
    return strand * vec3<f32>(saturate01(tint.x), saturate01(tint.y), saturate01(tint.z));
}

// ---- lean and level of detail (shading/motion.rs, shading/lod.rs) ------------------------

// lean_displacement: the lean's part tangent to the surface (at most 1 long) times
// h = fraction·height, pulled back along −n̂ by h − sqrt(h² − |o|²).
fn lean_displacement(lean: vec3<f32>, normal: vec3<f32>, shell_fraction: f32,
                     strand_height: f32) -> vec3<f32> {
    let n = normalize_or_zero(normal);
    var across = lean - n * dot(lean, n);
    let l = length(across);
    if (l > 1.0) {
        across = across / l;
    }
    let h = saturate01(shell_fraction) * max(strand_height, 0.0);
    let offset = across * h;
    let pull = h - sqrt(max(h * h - dot(offset, offset), 0.0));
    return offset - n * pull;
}

// Bending::lean_at: the shared lean plus the combing of the direction map at this vertex,
// world space (the frame's tangent and binormal carry its u and v).
fn lean_at(uv: vec2<f32>, tf: TangentFrame) -> vec3<f32> {
    var comb = vec3<f32>(0.0);
    if (has_map(MAP_DIRECTION)) {
        let c = comb_lean(sample_map(direction_map, uv));
        comb = tf.tangent * c.x + tf.binormal * c.y;
    }
    return frame.lean.xyz + comb;
}

// pow_whole: x^n for a whole n by square-and-multiply, lowest bit first (lod.rs pow_whole).
fn pow_whole(x: f32, n: u32) -> f32 {
    var result = 1.0;
    var base = x;
    var k = n;
    loop {
        if (k == 0u) {
            break;
        }
        if ((k & 1u) == 1u) {
            result = result * base;
        }
        base = base * base;
        k = k >> 1u;
    }
    return result;
}

// lod_alpha: a layer standing for `span` layers, 1 − (1 − α)^span; span 1 keeps α as it is; a
// whole span raises by pow_whole, a fractional one by pow.
fn lod_alpha(alpha: f32, span: f32) -> f32 {
    if (span == 1.0) {
        return alpha;
    }
    let a = saturate01(alpha);
    if (span <= 0.0) {
        return 0.0;
    }
    // pow(0, s) is outside WGSL's domain of pow (log2 of 0): an opaque texel stays opaque.
    if (a >= 1.0) {
        return 1.0;
    }
    let whole = u32(span);
    if (f32(whole) == span) {
        return 1.0 - pow_whole(1.0 - a, whole);
    }
    return 1.0 - pow(1.0 - a, span);
}

// ---- burning (3.4; burn.rs, fragment.rs BurnState) ---------------------------------------

const BURN_THRESHOLD: f32 = 0.1;
const UNBURNT: u32 = 0u;
const CHARRED: u32 = 1u;
const BURNT: u32 = 2u;

struct BurnOutcome {
    kind: u32,
    colour_factor: f32,
}

fn burn_rule(intensity: f32, shell_index: u32, max_shell: u32) -> BurnOutcome {
    if (!(intensity > BURN_THRESHOLD)) {
        return BurnOutcome(UNBURNT, 1.0);
    }
    let i = min(intensity, 1.0);
    let t = (1.0 - i) * f32(max_shell);
    if (shell_index > 0u && f32(shell_index) > t) {
        return BurnOutcome(BURNT, 1.0);
    }
    return BurnOutcome(CHARRED, 1.0 - i);
}

// BurnState::intensity: the strongest match. The matches by direction take the lobe of their
// largest cosine (one power); each match at a point its lobe times its reach falloff.
fn burn_intensity(normal: vec3<f32>, point: vec3<f32>) -> f32 {
    let unit_normal = normalize_or_zero(normal);
    let exponent = frame.shading2.z;
    var strongest = 0.0;
    var cosine = -2.0;
    var directions = false;
    for (var m = 0u; m < frame.counts.w; m++) {
        let light = matches[m];
        if (light.w == 0.0) {
            cosine = max(cosine, dot(unit_normal, normalize_or_zero(light.xyz)));
            directions = true;
        } else {
            strongest = max(strongest, point_light_intensity(unit_normal, point, light.xyz, light.w, exponent));
        }
    }
    if (directions) {
        strongest = max(strongest, pow01(cosine, exponent));
    }
    return strongest;
}

// ShadeParams::burn_outcome, at a surface point (object space, rest pose).
fn burn_outcome(normal: vec3<f32>, point: vec3<f32>, index: u32, max_shell: u32) -> BurnOutcome {
    if (frame.shading2.w == 0.0) {
        return BurnOutcome(UNBURNT, 1.0);
    }
    return burn_rule(burn_intensity(normal, point), index, max_shell);
}

fn strand_colour_after_burn(b: BurnOutcome, strand_colour: vec3<f32>) -> vec3<f32> {
    if (b.kind == CHARRED) {
        return strand_colour * b.colour_factor;
    }
    return strand_colour;
}

// ---- texture level of detail (raster/texture.rs) -----------------------------------------

// level_of_detail: log2 of the larger texel footprint of the coarse uv derivatives, as
// ½·log2 of the larger squared footprint with pelage's log2 (no square root). A zero footprint
// gives a value far below 0, which the caller clamps to level 0 as the oracle's −∞.
fn level_of_detail(ddx: vec2<f32>, ddy: vec2<f32>, size: vec2<f32>) -> f32 {
    let a = ddx * size;
    let b = ddy * size;
    let squared = max(a.x * a.x + a.y * a.y, b.x * b.x + b.y * b.y);
    if (squared <= 0.0) {
        return -1.0e30;
    }
    return 0.5 * log2_pelage(squared);
}

// ---- the skin (render/mod.rs, first draw) -------------------------------------------------

// A vertex as drawn (posed on the CPU, or by `skinned` below): mesh::Vertex. `rest_position` and
// `rest_normal` are the rest pose's (what spots, stripes and matches are fixed to; equal to
// position and normal for a mesh that is not posed), `lag` the vertex's own motion lag times
// motion.response (zero but for a posed character with [motion]).
struct MeshVertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) frame_tangent: vec3<f32>,
    @location(4) frame_binormal: vec3<f32>,
    @location(5) frame_normal: vec3<f32>,
    @location(6) dpdu: vec3<f32>,
    @location(7) dpdv: vec3<f32>,
    @location(8) rest_position: vec3<f32>,
    @location(9) rest_normal: vec3<f32>,
    @location(10) lag: vec3<f32>,
}

struct SkinVaryings {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) rest_normal: vec3<f32>,
    @location(2) rest_position: vec3<f32>,
}

// The skin's vertex closure: the posed normal lights it, the rest normal meets the matches.
fn skin_vertex(v: MeshVertex) -> SkinVaryings {
    var out: SkinVaryings;
    out.clip = frame.view_proj * vec4<f32>(v.position + frame.offset.xyz, 1.0);
    out.normal = v.normal;
    out.rest_normal = v.rest_normal;
    out.rest_position = v.rest_position;
    return out;
}

@vertex
fn vs_skin(v: MeshVertex) -> SkinVaryings {
    return skin_vertex(v);
}

// ---- skinning (mesh/skin.rs, mesh/frame.rs) ------------------------------------------------

// A bind-pose vertex of a skinned glTF model with its four palette influences (weights
// normalised at load) and the rest pose's fields (see MeshVertex).
struct SkinnedVertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) dpdu: vec3<f32>,
    @location(4) dpdv: vec3<f32>,
    @location(5) joints: vec4<u32>,
    @location(6) weights: vec4<f32>,
    @location(7) rest_position: vec3<f32>,
    @location(8) rest_normal: vec3<f32>,
    @location(9) lag: vec3<f32>,
}

// Column c of joint j's palette matrix; a joint past the palette counts as the identity (as
// Influences::blend).
fn palette_column(j: u32, c: u32) -> vec4<f32> {
    if (f32(j) >= palette[0].y) {
        var identity = vec4<f32>(0.0);
        identity[c] = 1.0;
        return identity;
    }
    return palette[1u + 4u * j + c];
}

// Influences::blend, column c: ((w0·P[j0] + w1·P[j1]) + w2·P[j2]) + w3·P[j3].
fn blend_column(joints: vec4<u32>, weights: vec4<f32>, c: u32) -> vec3<f32> {
    let a = weights.x * palette_column(joints.x, c).xyz;
    let b = weights.y * palette_column(joints.y, c).xyz;
    let d = weights.z * palette_column(joints.z, c).xyz;
    let e = weights.w * palette_column(joints.w, c).xyz;
    return ((a + b) + d) + e;
}

// u × v as Affine::transform_normal writes it.
fn cross_pelage(u: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x);
}

fn dot_pelage(u: vec3<f32>, v: vec3<f32>) -> f32 {
    return (u.x * v.x + u.y * v.y) + u.z * v.z;
}

// frame.rs orthogonal_part: v without its part along unit n, normalised twice; w = 0 when that is
// (almost) zero or v is zero or not finite.
fn orthogonal_part(v: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    let len = length(v);
    if (!(len <= 3.4028235e38) || len <= 1.17549435e-38) {
        return vec4<f32>(0.0);
    }
    let u = v / len;
    let t = u - n * dot(n, u);
    if (dot(t, t) < 1.0e-8) {
        return vec4<f32>(0.0);
    }
    let t1 = normalize(t);
    return vec4<f32>(normalize(t1 - n * dot(n, t1)), 1.0);
}

// frame.rs arbitrary_tangent: the axis least aligned with n (ties x, y, z), orthogonalised.
fn arbitrary_tangent(n: vec3<f32>) -> vec3<f32> {
    let a = abs(n);
    var axis = vec3<f32>(0.0, 0.0, 1.0);
    if (a.x <= a.y && a.x <= a.z) {
        axis = vec3<f32>(1.0, 0.0, 0.0);
    } else if (a.y <= a.z) {
        axis = vec3<f32>(0.0, 1.0, 0.0);
    }
    return normalize(axis - n * dot(n, axis));
}

// TangentFrame::from_derivatives: T = dpdu orthogonalised against N (else from dpdv, else an
// arbitrary tangent), B = N × T flipped against dpdv.
fn frame_from_derivatives(n: vec3<f32>, dpdu: vec3<f32>, dpdv: vec3<f32>) -> TangentFrame {
    var t = arbitrary_tangent(n);
    let from_u = orthogonal_part(dpdu, n);
    let from_v = orthogonal_part(dpdv, n);
    if (from_u.w != 0.0) {
        t = from_u.xyz;
    } else if (from_v.w != 0.0) {
        t = normalize(cross(from_v.xyz, n));
    }
    var b = cross(n, t);
    if (dot(b, dpdv) < 0.0) {
        b = -b;
    }
    return TangentFrame(t, b, n);
}

// skin::pose_vertex and render's inset: the vertex through its blended matrix M (position M·p,
// derivatives M₃·d, normal the cofactor of M₃ times n, negated where det M₃ < 0, normalised),
// moved by the skin inset along the posed normal, its frame rebuilt.
fn skinned(v: SkinnedVertex) -> MeshVertex {
    let c0 = blend_column(v.joints, v.weights, 0u);
    let c1 = blend_column(v.joints, v.weights, 1u);
    let c2 = blend_column(v.joints, v.weights, 2u);
    let c3 = blend_column(v.joints, v.weights, 3u);
    let p = v.position;
    let position = ((c0 * p.x + c1 * p.y) + c2 * p.z) + c3;
    let dpdu = (c0 * v.dpdu.x + c1 * v.dpdu.y) + c2 * v.dpdu.z;
    let dpdv = (c0 * v.dpdv.x + c1 * v.dpdv.y) + c2 * v.dpdv.z;
    // The rows of M₃ and their cofactors.
    let a0 = vec3<f32>(c0.x, c1.x, c2.x);
    let a1 = vec3<f32>(c0.y, c1.y, c2.y);
    let a2 = vec3<f32>(c0.z, c1.z, c2.z);
    let k0 = cross_pelage(a1, a2);
    let k1 = cross_pelage(a2, a0);
    let k2 = cross_pelage(a0, a1);
    var m = vec3<f32>(dot_pelage(k0, v.normal), dot_pelage(k1, v.normal),
                      dot_pelage(k2, v.normal));
    if (dot_pelage(a0, k0) < 0.0) {
        m = -m;
    }
    // glam's try_normalize: the bind normal where the length is zero or not finite.
    var normal = v.normal;
    let inv = 1.0 / length(m);
    if (inv > 0.0 && inv <= 3.4028235e38) {
        normal = m * inv;
    }
    let f = frame_from_derivatives(normal, dpdu, dpdv);
    var out: MeshVertex;
    out.position = position + normal * palette[0].x;
    out.normal = normal;
    out.uv = v.uv;
    out.frame_tangent = f.tangent;
    out.frame_binormal = f.binormal;
    out.frame_normal = f.normal;
    out.dpdu = dpdu;
    out.dpdv = dpdv;
    out.rest_position = v.rest_position;
    out.rest_normal = v.rest_normal;
    out.lag = v.lag;
    return out;
}

@vertex
fn vs_skin_skinned(v: SkinnedVertex) -> SkinVaryings {
    return skin_vertex(skinned(v));
}

// The skin: the fur colour darkened, charred where the fur burns: colour·(0.5 + 0.5·max(0, n·l)).
@fragment
fn fs_skin(v: SkinVaryings) -> @location(0) vec4<f32> {
    if (frame.counts.y != 0u) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let n = normalize_or_zero(v.normal);
    let rest = normalize_or_zero(v.rest_normal);
    let colour = strand_colour_after_burn(burn_outcome(rest, v.rest_position, 0u, layer.max_shell), frame.skin_colour.xyz);
    return vec4<f32>(colour * (0.5 + 0.5 * max(dot(n, frame.light.xyz), 0.0)), 1.0);
}

// ---- shells and fins ---------------------------------------------------------------------

// FurVaryings (render/fragment.rs).
struct FurVaryings {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) light: vec3<f32>,
    @location(2) eye: vec3<f32>,
    @location(3) shadow: vec2<f32>,
    @location(4) fade: f32,
    @location(5) object: vec3<f32>,
    @location(6) normal: vec3<f32>,
    @location(7) wind_uv: vec2<f32>,
    @location(8) wind: vec3<f32>,
    @location(9) mesh_uv: vec2<f32>,
    @location(10) length: f32,
    @location(11) lean: vec3<f32>,
}

// The shell vertex closure: the layer pushed out along the normal (its height scaled by the
// length map), moved by the wind (3.3) or, with a lean, by the wind's bend plus the lean, and by
// the object's path offset; eye and light into tangent space (3.2.1), the shadow step projected
// to uv (3.2.2).
// Spots, stripes and matches read the rest pose's position and normal; a posed character's own
// lag joins the lean.
fn shell_vertex(v: MeshVertex) -> FurVaryings {
    let tf = TangentFrame(v.frame_tangent, v.frame_binormal, v.frame_normal);
    let repeat = frame.fur.xy;
    let light = frame.light.xyz;
    let eye = frame.eye.xyz;
    // A length map scales the layer's height above the skin (1 without one).
    let fur_length = length_at(v.uv);
    let strand_height = frame.fur.z * fur_length;
    let offset = layer.offset * fur_length;
    let has_wind = frame.fur.w != 0.0;
    let has_lean = frame.lean.w != 0.0;
    let direction = frame.wind.xyz;
    let force = frame.wind.w;
    // Bending::displacement.
    var displacement = vec3<f32>(0.0);
    var lean_ts = vec3<f32>(0.0);
    if (has_lean) {
        var wind_bend = vec3<f32>(0.0);
        if (has_wind) {
            wind_bend = direction * clamp(force, -1.0, 1.0);
        }
        let lean = lean_at(v.uv, tf) + v.lag;
        displacement = lean_displacement(wind_bend + lean, v.normal, layer.height_fraction,
                                         strand_height);
        lean_ts = to_tangent_space(lean, tf);
    } else if (has_wind) {
        displacement = wind_displacement(direction, v.normal, force, layer.height_fraction,
                                         strand_height);
    }
    var wind_uv = vec2<f32>(0.0);
    if (has_wind || has_lean) {
        wind_uv = wind_uv_offset(displacement, v.normal, v.dpdu / repeat.x, v.dpdv / repeat.y);
    }
    var wind_ts = vec3<f32>(0.0);
    if (has_wind) {
        wind_ts = to_tangent_space(direction * force, tf);
    }
    // maps.w = 1: the layers are not pulled back (wind.keep_length = false, figure 3.16).
    var pull = vertex_pull(displacement, v.normal);
    if (frame.maps.w == 1u) {
        pull = vec3<f32>(0.0);
    }
    let p = v.position + v.normal * offset + pull + frame.offset.xyz;
    let change = shadow_change(light, v.frame_normal, strand_height - offset);
    var out: FurVaryings;
    out.clip = frame.view_proj * vec4<f32>(p, 1.0);
    out.uv = v.uv * repeat;
    out.light = to_tangent_space(light, tf);
    out.eye = to_tangent_space(eye - p, tf);
    out.shadow = project_to_uv(change, v.dpdu / repeat.x, v.dpdv / repeat.y);
    out.fade = 1.0;
    out.object = v.rest_position;
    out.normal = v.rest_normal;
    out.wind_uv = wind_uv;
    out.wind = wind_ts;
    out.mesh_uv = v.uv;
    out.length = fur_length;
    out.lean = lean_ts;
    return out;
}

@vertex
fn vs_shell(v: MeshVertex) -> FurVaryings {
    return shell_vertex(v);
}

// The shells of a skinned model: the bind vertex skinned by the palette, then the same closure.
@vertex
fn vs_shell_skinned(v: SkinnedVertex) -> FurVaryings {
    return shell_vertex(skinned(v));
}

struct FinVertex {
    @location(0) position: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) light: vec3<f32>,
    @location(3) eye: vec3<f32>,
    @location(4) shadow: vec2<f32>,
    @location(5) fade: f32,
    @location(6) object: vec3<f32>,
    @location(7) normal: vec3<f32>,
    @location(8) wind_uv: vec2<f32>,
    @location(9) wind: vec3<f32>,
    @location(10) mesh_uv: vec2<f32>,
    @location(11) length: f32,
    @location(12) lean: vec3<f32>,
}

// The fin vertex closure: the quads and their varyings come from the CPU (silhouette edges),
// the wind among them: none at the roots, the whole at the top edge, so `shade_fur` bends a fin's
// tangent as the shell at the same height bends its own.
@vertex
fn vs_fin(v: FinVertex) -> FurVaryings {
    var out: FurVaryings;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.uv = v.uv;
    out.light = v.light;
    out.eye = v.eye;
    out.shadow = v.shadow;
    out.fade = v.fade;
    out.object = v.object;
    out.normal = v.normal;
    out.wind_uv = v.wind_uv;
    out.wind = v.wind;
    out.mesh_uv = v.mesh_uv;
    out.length = v.length;
    out.lean = v.lean;
    return out;
}

const ALPHA_DISCARD: f32 = 0.5 / 255.0;

// shade_fur (render/fragment.rs): steps 1–7 of its module docs, in order, with the terms
// beyond the thesis where shade_fur takes them (length cut, density, level of detail, tint,
// lean).
@fragment
fn fs_fur(v: FurVaryings) -> @location(0) vec4<f32> {
    // Coarse derivatives of the fur uv, taken first (uniform control flow).
    let ddx = dpdxCoarse(v.uv);
    let ddy = dpdyCoarse(v.uv);
    // 1. Burning (3.4): a burnt texel is discarded before any texture read.
    let burn = burn_outcome(v.normal, v.object, layer.index, layer.max_shell);
    if (burn.kind == BURNT) {
        discard;
    }
    // A shell layer above the painted length is dropped (fins are not cut).
    if (layer.shell != 0u && has_map(MAP_LENGTH)
        && !layer_within_length(layer.height_fraction, v.length,
                                sample_map(length_map, v.mesh_uv).x)) {
        discard;
    }
    // 2. The reverse wind lookup (3.3), the lean's too.
    let uv = v.uv - v.wind_uv;
    // 3. Colour and tangent maps, trilinear at the level of detail of the fur uv.
    let lod = level_of_detail(ddx, ddy, vec2<f32>(textureDimensions(colour_map, 0u)));
    let max_level = f32(textureNumLevels(colour_map) - 1u);
    let level = clamp(lod, 0.0, max_level);
    let texel = textureSampleLevel(colour_map, fur_sampler, uv, level);
    // The density map selects strands through the bands (shells) or scales the alpha (fins).
    var density = 0.0;
    var coverage = texel.a;
    if (has_map(MAP_DENSITY)) {
        density = sample_map(density_map, v.mesh_uv).x;
        if (has_bands()) {
            let bands_level = clamp(lod, 0.0, f32(textureNumLevels(density_bands) - 1u));
            let bands = textureSampleLevel(density_bands, fur_sampler, uv, bands_level);
            coverage = density_alpha(bands, density);
        } else {
            coverage = texel.a * saturate01(density);
        }
    }
    // Level of detail: a layer standing for several gets their alpha together.
    let alpha = lod_alpha(coverage * v.fade, layer.lod_span);
    if (!(alpha >= ALPHA_DISCARD)) {
        discard;
    }
    let encoded = textureSampleLevel(tangent_map, fur_sampler, uv, level);
    let debug = frame.counts.y;
    if (debug == 1u) {
        return vec4<f32>(encoded.rgb, alpha);
    }
    if (debug == 2u) {
        return vec4<f32>(1.0, 1.0, 1.0, alpha);
    }
    // 4. The colour map's tint, spots and stripes (3.2.4), then charring.
    var tinted = texel.rgb;
    if (has_map(MAP_COLOUR)) {
        tinted = tint_strand(tinted, sample_map(tint_map, v.mesh_uv).rgb);
    }
    let spotted = apply_spots(tinted, v.object, v.normal);
    let strand = strand_colour_after_burn(burn, spotted);
    // 5. The tangent, bent by the wind (3.3.1), then by the lean.
    var tangent = normalize_or(encoded.rgb * 2.0 - vec3<f32>(1.0), vec3<f32>(0.0, 0.0, 1.0));
    let wind_fraction = frame.shading2.y;
    if (wind_fraction > 0.0) {
        tangent = bend_tangent(tangent, v.wind, layer.height_fraction * wind_fraction);
    }
    if (frame.lean.w != 0.0) {
        tangent = bend_tangent(tangent, v.lean, layer.height_fraction);
    }
    // The interpolated light and eye, normalised once, by the lighting terms themselves.
    let light = v.light;
    let eye = v.eye;
    // 6. The shell self-shadow (3.2.2), displaced by the wind too; through the density bands.
    let shadow = shell_shadow(uv, v.shadow + v.wind_uv, layer.lookups, lod, density);
    if (debug == 3u) {
        let g = clamp(1.0 - frame.weights2.x * shadow, 0.0, 1.0);
        return vec4<f32>(g, g, g, alpha);
    }
    // 7. Kajiya–Kay (eq. 2.5, 2.7), the uncoloured last term (the dampened specular of 3.2.3,
    // or eq. 3.5's (ψ_specularity1)^n), eq. 3.7.
    let s = frame.shading;
    let diffuse = kajiya_kay_diffuse(tangent, light, s.y);
    let specular = specular_with_tangents(tangent, vec3<f32>(0.0, 0.0, 1.0), light, eye, s.z,
                                          frame.counts.x, frame.shading2.x);
    let dampened = uncoloured_specular(kajiya_kay_specular(tangent, light, eye, s.w));
    let colour = final_colour(strand, frame.light_colour.xyz, s.x, diffuse, specular, dampened, shadow);
    return vec4<f32>(colour, alpha);
}
