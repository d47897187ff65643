// pelage's fur shaders in WGSL: the vertex closures of src/render/mod.rs and the fragment closure
// of src/render/fragment.rs (`shade_fur`), term by term. Every function carries the name of the
// Rust function it mirrors (src/shading/*.rs) and the thesis equation it implements, so a
// difference between the backends can be traced to one term. Differences that remain by design:
// GPU `pow`, `exp`, `log2`, `sin` instead of libm; the sampler's trilinear filter instead of the
// oracle's f32 one; non-finite inputs are not sanitised (valid scenes never produce them).

// ---- uniforms ---------------------------------------------------------------------------

struct FrameUniforms {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,            // xyz: camera position, object space
    light: vec4<f32>,          // xyz: unit direction towards the light
    light_colour: vec4<f32>,   // xyz
    skin_colour: vec4<f32>,    // xyz: fur colour · 0.35
    wind: vec4<f32>,           // xyz: unit wind direction, w: wind_force(time) (3.3)
    fur: vec4<f32>,            // x, y: texture_repeat; z: model_difference; w: 1 when wind is on
    shading: vec4<f32>,        // ambient, banks_exponent, specular_exponent, dampened_exponent
    shading2: vec4<f32>,       // tangent_shift, wind_tangent_fraction, burn exponent, 1 when burning
    weights: vec4<f32>,        // eq. 3.7 weights: ambient, diffuse, specular, dampened
    weights2: vec4<f32>,       // x: shadow weight
    counts: vec4<u32>,         // specular tangents (1 or 3), debug view, spots, matches
}

struct LayerUniforms {
    index: u32,                // shell index (fins: the top shell)
    max_shell: u32,            // number_of_shells − 1
    lookups: u32,              // shadow lookups, m = (N − i)/n (3.2.2)
    height_fraction: f32,      // i / N
    offset: f32,               // distance above the skin
    clamp_v: u32,              // 1: clamp v (fins), 0: wrap
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
// Spots in application order, four vec4 each:
// [kind (0 ellipsoid, 1 light, 2 stripe), 0, 0, 0],
// [centre | direction | axis (xyz), exponent | period (w)],
// [radii (xyz), inner | inner_threshold | width (w)],
// [colour (xyz), outer_threshold | softness (w)].
@group(0) @binding(1) var<storage, read> spots: array<vec4<f32>>;
// Unit match directions (3.4), xyz.
@group(0) @binding(2) var<storage, read> matches: array<vec4<f32>>;

@group(1) @binding(0) var<uniform> layer: LayerUniforms;
@group(1) @binding(1) var colour_map: texture_2d<f32>;
@group(1) @binding(2) var tangent_map: texture_2d<f32>;
@group(1) @binding(3) var fur_sampler: sampler;

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

// pow01: saturate(base)^max(exponent, 0), 0^0 = 1.
fn pow01(base: f32, exponent: f32) -> f32 {
    let b = saturate01(base);
    let p = max(exponent, 0.0);
    if (p == 0.0) {
        return 1.0;
    }
    if (b <= 0.0) {
        return 0.0;
    }
    return pow(b, p);
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

// One tangent, or the mean of three (t, shifted up, shifted down), eq. 3.5.
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
    return (centre + up + down) / 3.0;
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

// Eq. 3.7: w_a·ambient·strand + strand·light·(w_d·diffuse + w_s·specular) + light·w_p·dampened
// − w_sh·shadow, each channel clamped to [0, 1].
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
        out[c] = saturate01(w.x * ambient * s + s * l * lit + l * highlight - dark);
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

// Sampler::sample_nearest_level: the alpha of texel ⌊uv·size⌋ of mip level ⌊λ + 0.5⌋. The
// level's size is level 0's halved `level` times (at least 1, as the oracle's chain is built),
// not textureDimensions(colour_map, level): lavapipe answers that query for a level that
// differs between the lanes of one SIMD group with one lane's level, and the other lanes then
// read outside their level (robust access returns 0: shadow-free specks where λ crosses k + ½).
fn sample_nearest_level_alpha(uv: vec2<f32>, lod: f32) -> f32 {
    let max_level = f32(textureNumLevels(colour_map) - 1u);
    let level = u32(clamp(lod, 0.0, max_level) + 0.5);
    let size = max(vec2<i32>(textureDimensions(colour_map, 0u)) >> vec2<u32>(level), vec2<i32>(1));
    var x = i32(floor(uv.x * f32(size.x)));
    var y = i32(floor(uv.y * f32(size.y)));
    x = ((x % size.x) + size.x) % size.x;
    if (layer.clamp_v != 0u) {
        y = clamp(y, 0, size.y - 1);
    } else {
        y = ((y % size.y) + size.y) % size.y;
    }
    return textureLoad(colour_map, vec2<i32>(x, y), i32(level)).a;
}

// shell_shadow: Σ_{k=1..m} saturate(alpha(uv + step·(k/m))).
fn shell_shadow(uv: vec2<f32>, shadow_lookup: vec2<f32>, lookups: u32, lod: f32) -> f32 {
    let m = f32(lookups);
    var shadow = 0.0;
    for (var k = 1u; k <= lookups; k++) {
        shadow += saturate01(sample_nearest_level_alpha(uv + shadow_lookup * (f32(k) / m), lod));
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
        } else {
            weight = stripe_intensity(dot(object, a.xyz), a.w, b.w, c.w);
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

fn wind_uv_offset(displacement: vec3<f32>, normal: vec3<f32>, dpdu: vec3<f32>, dpdv: vec3<f32>) -> vec2<f32> {
    let n = normalize_or_zero(normal);
    let horizontal = displacement - n * dot(displacement, n);
    return project_to_uv_dropping(horizontal, dpdu, dpdv, axis_greatest(n));
}

// 3.3.1: normalize(t + fraction·w), falling back to the normalised tangent.
fn bend_tangent(tangent: vec3<f32>, wind_tangent_space: vec3<f32>, fraction: f32) -> vec3<f32> {
    return normalize_or(tangent + fraction * wind_tangent_space, normalize_or_zero(tangent));
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

// BurnState::intensity: the strongest match lobe.
fn burn_intensity(normal: vec3<f32>) -> f32 {
    var strongest = 0.0;
    for (var m = 0u; m < frame.counts.w; m++) {
        strongest = max(strongest, light_spot_intensity(normal, matches[m].xyz, frame.shading2.z));
    }
    return strongest;
}

// ShadeParams::burn_outcome.
fn burn_outcome(normal: vec3<f32>, index: u32, max_shell: u32) -> BurnOutcome {
    if (frame.shading2.w == 0.0) {
        return BurnOutcome(UNBURNT, 1.0);
    }
    return burn_rule(burn_intensity(normal), index, max_shell);
}

fn strand_colour_after_burn(b: BurnOutcome, strand_colour: vec3<f32>) -> vec3<f32> {
    if (b.kind == CHARRED) {
        return strand_colour * b.colour_factor;
    }
    return strand_colour;
}

// ---- texture level of detail (raster/texture.rs) -----------------------------------------

// level_of_detail: log2 of the larger texel footprint of the coarse uv derivatives.
fn level_of_detail(ddx: vec2<f32>, ddy: vec2<f32>, size: vec2<f32>) -> f32 {
    let along_x = length(ddx * size);
    let along_y = length(ddy * size);
    return log2(max(along_x, along_y));
}

// ---- the skin (render/mod.rs, first draw) -------------------------------------------------

struct MeshVertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) frame_tangent: vec3<f32>,
    @location(4) frame_binormal: vec3<f32>,
    @location(5) frame_normal: vec3<f32>,
    @location(6) dpdu: vec3<f32>,
    @location(7) dpdv: vec3<f32>,
}

struct SkinVaryings {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
}

@vertex
fn vs_skin(v: MeshVertex) -> SkinVaryings {
    var out: SkinVaryings;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.normal = v.normal;
    return out;
}

// The skin: the fur colour darkened, charred where the fur burns: colour·(0.5 + 0.5·max(0, n·l)).
@fragment
fn fs_skin(v: SkinVaryings) -> @location(0) vec4<f32> {
    if (frame.counts.y != 0u) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let n = normalize_or_zero(v.normal);
    let colour = strand_colour_after_burn(burn_outcome(n, 0u, layer.max_shell), frame.skin_colour.xyz);
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
}

// The shell vertex closure: the layer pushed out along the normal, moved by the wind (3.3),
// eye and light into tangent space (3.2.1), the shadow step projected to uv (3.2.2).
@vertex
fn vs_shell(v: MeshVertex) -> FurVaryings {
    let tf = TangentFrame(v.frame_tangent, v.frame_binormal, v.frame_normal);
    let repeat = frame.fur.xy;
    let difference = frame.fur.z;
    let light = frame.light.xyz;
    let eye = frame.eye.xyz;
    var displacement = vec3<f32>(0.0);
    var wind_uv = vec2<f32>(0.0);
    var wind_ts = vec3<f32>(0.0);
    if (frame.fur.w != 0.0) {
        let direction = frame.wind.xyz;
        let force = frame.wind.w;
        displacement = wind_displacement(direction, v.normal, force, layer.height_fraction, difference);
        wind_uv = wind_uv_offset(displacement, v.normal, v.dpdu / repeat.x, v.dpdv / repeat.y);
        wind_ts = to_tangent_space(direction * force, tf);
    }
    let p = v.position + v.normal * layer.offset + displacement;
    let change = shadow_change(light, v.frame_normal, difference - layer.offset);
    var out: FurVaryings;
    out.clip = frame.view_proj * vec4<f32>(p, 1.0);
    out.uv = v.uv * repeat;
    out.light = to_tangent_space(light, tf);
    out.eye = to_tangent_space(eye - p, tf);
    out.shadow = project_to_uv(change, v.dpdu / repeat.x, v.dpdv / repeat.y);
    out.fade = 1.0;
    out.object = v.position;
    out.normal = v.normal;
    out.wind_uv = wind_uv;
    out.wind = wind_ts;
    return out;
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
}

// The fin vertex closure: the quads and their varyings come from the CPU (silhouette edges).
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
    return out;
}

const ALPHA_DISCARD: f32 = 0.5 / 255.0;

// shade_fur (render/fragment.rs): steps 1–7 of its module docs, in order.
@fragment
fn fs_fur(v: FurVaryings) -> @location(0) vec4<f32> {
    // Coarse derivatives of the fur uv, taken first (uniform control flow).
    let ddx = dpdxCoarse(v.uv);
    let ddy = dpdyCoarse(v.uv);
    // 1. Burning (3.4): a burnt texel is discarded before any texture read.
    let burn = burn_outcome(v.normal, layer.index, layer.max_shell);
    if (burn.kind == BURNT) {
        discard;
    }
    // 2. The reverse wind lookup (3.3).
    let uv = v.uv - v.wind_uv;
    // 3. Colour and tangent maps, trilinear at the level of detail of the fur uv.
    let lod = level_of_detail(ddx, ddy, vec2<f32>(textureDimensions(colour_map, 0u)));
    let max_level = f32(textureNumLevels(colour_map) - 1u);
    let level = clamp(lod, 0.0, max_level);
    let texel = textureSampleLevel(colour_map, fur_sampler, uv, level);
    let alpha = texel.a * v.fade;
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
    // 4. Spots and stripes (3.2.4), then charring.
    let spotted = apply_spots(texel.rgb, v.object, v.normal);
    let strand = strand_colour_after_burn(burn, spotted);
    // 5. The tangent, bent by the wind (3.3.1).
    var tangent = normalize_or(encoded.rgb * 2.0 - vec3<f32>(1.0), vec3<f32>(0.0, 0.0, 1.0));
    let wind_fraction = frame.shading2.y;
    if (wind_fraction > 0.0) {
        tangent = bend_tangent(tangent, v.wind, layer.height_fraction * wind_fraction);
    }
    let light = normalize_or_zero(v.light);
    let eye = normalize_or_zero(v.eye);
    // 6. The shell self-shadow (3.2.2), displaced by the wind too.
    let shadow = shell_shadow(uv, v.shadow + v.wind_uv, layer.lookups, lod);
    if (debug == 3u) {
        let g = clamp(1.0 - frame.weights2.x * shadow, 0.0, 1.0);
        return vec4<f32>(g, g, g, alpha);
    }
    // 7. Kajiya–Kay (eq. 2.5, 2.7), the dampened specular (3.2.3), eq. 3.7.
    let s = frame.shading;
    let diffuse = kajiya_kay_diffuse(tangent, light, s.y);
    let specular = specular_with_tangents(tangent, vec3<f32>(0.0, 0.0, 1.0), light, eye, s.z,
                                          frame.counts.x, frame.shading2.x);
    let dampened = dampened_specular(kajiya_kay_specular(tangent, light, eye, s.w));
    let colour = final_colour(strand, frame.light_colour.xyz, s.x, diffuse, specular, dampened, shadow);
    return vec4<f32>(colour, alpha);
}
