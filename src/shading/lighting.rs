//! The lighting combination of thesis 3.2.3 (shading stage): the uncoloured last term (the
//! dampened specular of eq. 3.6/3.7, or `(ψ_specularity1)^n` of eq. 3.5) and the final colour,
//! eq. 3.7, with one user weight per term.

use super::lanes::Vec3xN;
use super::numeric::{pow01, pow01_lanes, saturate_select, saturate_x4};
use glam::Vec3;
use wide::f32x4;

/// Specular values strictly above this become [`DAMPENED_SPECULAR_MAX`] (thesis 3.2.3).
pub const DAMPENING_THRESHOLD: f32 = 0.6;

/// The largest dampened specular, 0.3 (thesis 3.2.3: "fixing the values over 0.6 to 0.3").
pub const DAMPENED_SPECULAR_MAX: f32 = 0.3;

/// Dampened specular (thesis 3.2.3, the `ψ_dampenedspecularity` of eq. 3.6 and 3.7): values
/// over 0.6 become 0.3; from 0 to 0.6 a linear gradient from 0 to 0.3, i.e. `0.5·s`.
///
/// The two branches meet exactly: `0.5 · 0.6_f32 == 0.3_f32` (halving is exact), so the
/// function is continuous and monotone. Negative and NaN inputs give 0; `+inf` gives 0.3.
#[inline]
pub fn dampened_specular(s: f32) -> f32 {
    if s > DAMPENING_THRESHOLD {
        DAMPENED_SPECULAR_MAX
    } else if s > 0.0 {
        0.5 * s
    } else {
        0.0
    }
}

/// [`dampened_specular`] of `N` lanes, the same bits (the branches as selects; NaN compares
/// false and gives 0).
#[inline(always)]
pub fn dampened_specular_lanes<const N: usize>(s: [f32; N]) -> [f32; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        let ramp = if s[i] > 0.0 { 0.5 * s[i] } else { 0.0 };
        out[i] = if s[i] > DAMPENING_THRESHOLD {
            DAMPENED_SPECULAR_MAX
        } else {
            ramp
        };
    }
    out
}

/// The last, uncoloured term of thesis eq. 3.5, `(ψ_specularity1)^n`:
///
/// `ψ_final = ψ_ambient + strandColor·(ψ_diffuse + ψ_specularitynew) + (ψ_specularity1)^n`.
///
/// `specularity1` is `ψ_specularity1`, the Kajiya–Kay specular of the strand's own tangent
/// alone (eq. 2.7 with the specular exponent: the centre lobe of the three-tangent
/// `ψ_specularitynew`, before any strand colour); the result is it raised to the power `n`, in
/// `[0, 1]`. The base is saturated first and `n` follows the lobe exponent convention (NaN acts
/// as 1, negative as 0), as every lobe's power: pelage's own `pow01`, `2^(n·log2 s)`, so at
/// `n = 1` the result is `specularity1` within a few ulps, not bit for bit.
#[inline]
pub fn specularity1_power(specularity1: f32, n: f32) -> f32 {
    pow01(specularity1, n)
}

/// [`specularity1_power`] of `N` lanes with one exponent, each lane the same bits.
#[inline(always)]
pub fn specularity1_power_lanes<const N: usize>(specularity1: [f32; N], n: f32) -> [f32; N] {
    pow01_lanes(specularity1, [n; N])
}

/// Which equation of thesis 3.2.3 lights the fur: what the uncoloured last term is
/// ([`uncoloured_specular`]) and the exponent of the lobe it is made of ([`Self::lobe_exponent`]).
/// Everything else is shared: `ψ_ambient + strandColor·(ψ_diffuse + ψ_specular)` with one or
/// three tangents (`ψ_specularitynew` of eq. 3.5 is the three-tangent specular), and the shadow
/// subtracted as eq. 3.7 adds it to eq. 3.6. Scene key `shading.lighting`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum LightingModel {
    /// Eq. 3.6 (with the shadow, eq. 3.7): the last term is the dampened specular
    /// ([`dampened_specular`]) of the lobe with the dampened exponent; the default (what the
    /// thesis's system renders).
    #[default]
    Eq36,
    /// Eq. 3.5: the last term is `(ψ_specularity1)^n` ([`specularity1_power`]) of the lobe
    /// with the specular exponent, its own tangent alone: a highlight in the light's colour
    /// over the strand-coloured one (thesis figure 3.13).
    Eq35 {
        /// The power `n` of `(ψ_specularity1)^n`.
        n: f32,
    },
}

impl LightingModel {
    /// The exponent of the single-tangent lobe the uncoloured last term is made of: under
    /// eq. 3.6/3.7 the dampened specular's own low exponent, under eq. 3.5 the specular
    /// exponent (the lobe is then `ψ_specularity1`, eq. 2.7 of the strand's own tangent).
    #[inline]
    pub fn lobe_exponent(self, specular_exponent: f32, dampened_exponent: f32) -> f32 {
        match self {
            LightingModel::Eq36 => dampened_exponent,
            LightingModel::Eq35 { .. } => specular_exponent,
        }
    }
}

/// The uncoloured last term of the lighting, from the lobe of the strand's own tangent with
/// [`LightingModel::lobe_exponent`]: [`dampened_specular`] of it (`ψ_dampenedspecularity`,
/// eq. 3.6/3.7) or [`specularity1_power`] (`(ψ_specularity1)^n`, eq. 3.5). It enters
/// [`final_colour`] as its `dampened` argument, with the same weight and light colour.
#[inline]
pub fn uncoloured_specular(lobe: f32, model: LightingModel) -> f32 {
    match model {
        LightingModel::Eq36 => dampened_specular(lobe),
        LightingModel::Eq35 { n } => specularity1_power(lobe, n),
    }
}

/// [`uncoloured_specular`] of `N` lanes, each lane the same bits.
#[inline(always)]
pub fn uncoloured_specular_lanes<const N: usize>(lobe: [f32; N], model: LightingModel) -> [f32; N] {
    match model {
        LightingModel::Eq36 => dampened_specular_lanes(lobe),
        LightingModel::Eq35 { n } => specularity1_power_lanes(lobe, n),
    }
}

/// The user weights of eq. 3.7 (thesis 3.2.3: "we multiply each of these by a user defined
/// value").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingWeights {
    /// Weight of `ψ_ambient`.
    pub ambient: f32,
    /// Weight of `ψ_diffuse` (inside the strand-colour product).
    pub diffuse: f32,
    /// Weight of `ψ_specularity` (inside the strand-colour product).
    pub specular: f32,
    /// Weight of the uncoloured last term: `ψ_dampenedspecularity` (eq. 3.6/3.7), or
    /// `(ψ_specularity1)^n` under eq. 3.5 ([`uncoloured_specular`]).
    pub dampened: f32,
    /// Weight of `ψ_shadow`, subtracted.
    pub shadow: f32,
}

/// Default weight of the shadow term, 0.08.
///
/// The raw shadow of [`crate::shading::shell_shadow`] is a count of opaque lookups: up to
/// `m = (N − i)/n` (6 at the bottom layer of the thesis's 30 shells with `height/5`; the thesis
/// gives its shadow range as `[0, −5]`). With weight 1 a single opaque lookup would already
/// black out a fully lit strand. 0.08 maps 6 opaque lookups to a darkening of 0.48: the
/// root is about half as bright as the tip, dark but never black, and one lookup costs 0.08.
pub const DEFAULT_SHADOW_WEIGHT: f32 = 0.08;

impl Default for ShadingWeights {
    /// All weights 1, except `shadow` = [`DEFAULT_SHADOW_WEIGHT`].
    fn default() -> Self {
        ShadingWeights {
            ambient: 1.0,
            diffuse: 1.0,
            specular: 1.0,
            dampened: 1.0,
            shadow: DEFAULT_SHADOW_WEIGHT,
        }
    }
}

/// Where `ψ_ambient` of eq. 3.7 stands.
///
/// Eq. 3.7 as printed, `ψ_ambient + strandColor·(ψ_diffuse + ψ_specularity) + …`, leaves the
/// ambient outside the strand-colour product ([`AmbientTerm::Constant`]); pelage's earlier
/// convention reflects it off the strand ([`AmbientTerm::Strand`]). Scene key
/// `shading.ambient_term`; the default is [`AmbientTerm::Strand`]: a constant ambient adds the
/// same grey to every channel of every strand, which washes the fur colour out (a brown torus
/// turns beige under the default `ambient = 0.25`) and lifts the shadowed roots towards grey
/// instead of a dark fur colour (README, "Where pelage departs from the thesis").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AmbientTerm {
    /// `ψ_ambient = ambient`, the same in every channel ([`ambient_constant`]).
    Constant,
    /// `ψ_ambient = ambient · strandColor` ([`ambient_of_strand`]).
    #[default]
    Strand,
}

/// `ψ_ambient` of eq. 3.7 as printed (thesis 3.2.3): the ambient level alone, the same in
/// every channel, added outside the strand colour.
#[inline(always)]
pub fn ambient_constant(ambient: f32) -> Vec3 {
    Vec3::splat(ambient)
}

/// `ψ_ambient = ambient · strandColor`: an ambient light of level `ambient` reflected by the
/// strand, channel by channel `strand_colour[c] · ambient`.
#[inline(always)]
pub fn ambient_of_strand(ambient: f32, strand_colour: Vec3) -> Vec3 {
    strand_colour * ambient
}

/// `ψ_ambient` as `term` says: [`ambient_constant`] or [`ambient_of_strand`].
#[inline(always)]
pub fn ambient_term(ambient: f32, strand_colour: Vec3, term: AmbientTerm) -> Vec3 {
    match term {
        AmbientTerm::Constant => ambient_constant(ambient),
        AmbientTerm::Strand => ambient_of_strand(ambient, strand_colour),
    }
}

/// Final colour, thesis eq. 3.7:
/// `ψ_final = ψ_ambient + strandColor·(ψ_diffuse + ψ_specularity) + ψ_dampenedspecularity − ψ_shadow`,
/// each term scaled by its weight, per channel:
///
/// `A + strand·light·(w_d·diffuse + w_s·specular) + light·w_p·dampened − w_sh·shadow`,
/// with `A = ambient_term(w_a·ambient, strand, term)` ([`ambient_term`]: `w_a·ambient` alone,
/// or times the strand colour), then each channel clamped to `[0, 1]`.
///
/// Eq. 3.5 is the same sum: `specular` is then `ψ_specularitynew` and `dampened` the
/// uncoloured `(ψ_specularity1)^n` ([`uncoloured_specular`] gives either last term), with the
/// shadow of eq. 3.7 subtracted too.
///
/// Choices where the thesis is open: the light colour multiplies the lit terms and the
/// dampened specular (a white highlight under a white light), not the ambient or the shadow.
/// The sum is evaluated left to right in the order written above; a NaN channel becomes 0.
#[allow(clippy::too_many_arguments)] // one argument per term of eq. 3.7, in its order
#[inline]
pub fn final_colour(
    strand_colour: Vec3,
    light_colour: Vec3,
    ambient: f32,
    diffuse: f32,
    specular: f32,
    dampened: f32,
    shadow: f32,
    weights: &ShadingWeights,
    term: AmbientTerm,
) -> Vec3 {
    let lit = weights.diffuse * diffuse + weights.specular * specular;
    let highlight = weights.dampened * dampened;
    let dark = weights.shadow * shadow;
    // The three channels (and an unused fourth) as packed lanes: each lane is the scalar
    // formula's own operations in its order.
    let lanes = |v: Vec3| f32x4::new([v.x, v.y, v.z, 0.0]);
    let (s, l) = (lanes(strand_colour), lanes(light_colour));
    let a = lanes(ambient_term(weights.ambient * ambient, strand_colour, term));
    let splat = f32x4::splat;
    let sum = a + s * l * splat(lit) + l * splat(highlight) - splat(dark);
    let [x, y, z, _] = saturate_x4(sum).to_array();
    Vec3::new(x, y, z)
}

/// [`final_colour`] (eq. 3.7) of `N` fragments (the lit lanes of a batch): per lane and
/// channel the same operations in the same order, so the same bits, with each channel of the
/// lanes as one packed run instead of the three channels of one fragment.
#[allow(clippy::too_many_arguments)] // one argument per term of eq. 3.7, in its order
#[inline(always)]
pub fn final_colour_lanes<const N: usize>(
    strand_colour: &Vec3xN<N>,
    light_colour: Vec3,
    ambient: f32,
    diffuse: [f32; N],
    specular: [f32; N],
    dampened: [f32; N],
    shadow: [f32; N],
    weights: &ShadingWeights,
    term: AmbientTerm,
) -> Vec3xN<N> {
    let (mut lit, mut highlight, mut dark) = ([0.0; N], [0.0; N], [0.0; N]);
    for i in 0..N {
        lit[i] = weights.diffuse * diffuse[i] + weights.specular * specular[i];
        highlight[i] = weights.dampened * dampened[i];
        dark[i] = weights.shadow * shadow[i];
    }
    let level = weights.ambient * ambient;
    let terms = ChannelTerms {
        level,
        term,
        lit,
        highlight,
        dark,
    };
    Vec3xN {
        x: terms.channel(strand_colour.x, light_colour.x),
        y: terms.channel(strand_colour.y, light_colour.y),
        z: terms.channel(strand_colour.z, light_colour.z),
    }
}

/// What eq. 3.7 adds to every channel of `N` lanes, for [`final_colour_lanes`].
struct ChannelTerms<const N: usize> {
    level: f32,
    term: AmbientTerm,
    lit: [f32; N],
    highlight: [f32; N],
    dark: [f32; N],
}

impl<const N: usize> ChannelTerms<N> {
    /// One channel of eq. 3.7 on the lanes, as [`final_colour`] computes it.
    #[inline(always)]
    fn channel(&self, strand: [f32; N], light: f32) -> [f32; N] {
        let mut out = [0.0; N];
        for i in 0..N {
            let s = strand[i];
            // `ambient_term`: the level alone, or the strand times it.
            let a = match self.term {
                AmbientTerm::Constant => self.level,
                AmbientTerm::Strand => s * self.level,
            };
            out[i] = saturate_select(
                a + s * light * self.lit[i] + light * self.highlight[i] - self.dark[i],
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};

    #[test]
    fn dampening_matches_definition_and_boundary() {
        let below = f32::from_bits(DAMPENING_THRESHOLD.to_bits() - 1);
        let above = f32::from_bits(DAMPENING_THRESHOLD.to_bits() + 1);
        assert_eq!(dampened_specular(DAMPENING_THRESHOLD), 0.3);
        assert_eq!(dampened_specular(above), 0.3);
        assert!(dampened_specular(below) < 0.3);
        assert_close(
            dampened_specular(below),
            0.5 * f64::from(below),
            1e-9,
            "0.6−",
        );
        assert_eq!(dampened_specular(0.0), 0.0);
        assert_eq!(dampened_specular(-0.5), 0.0);
        assert_eq!(dampened_specular(f32::NAN), 0.0);
        assert_eq!(dampened_specular(f32::INFINITY), 0.3);
        assert_eq!(dampened_specular(1.0), 0.3);
        let mut rng = Lcg::new(20);
        for _ in 0..1000 {
            let s = rng.range(-0.2, 1.2);
            let s64 = f64::from(s);
            let expected = if s64 > 0.6f32 as f64 {
                0.3f32 as f64
            } else {
                (0.5 * s64).max(0.0)
            };
            // Halving is exact: the bound is 0.
            assert_close(dampened_specular(s), expected, 0.0, "dampened");
        }
    }

    #[test]
    fn specularity1_power_matches_f64() {
        // Bound: pow01's, 3·(1 + |n·log2 s|) ulp of the result (documented and measured in
        // numeric.rs), taken as 4·(1 + |t|)·2^−23 relative, plus 1e-38 for subnormal results.
        let mut rng = Lcg::new(25);
        for k in 0..5000 {
            let s = match k % 50 {
                0 => 0.0,
                1 => 1.0,
                2 => 1e-30,
                _ => rng.unit(),
            };
            let n = [1.0, 2.0, 0.5][k % 3] * rng.range(0.25, 16.0);
            let exact = f64::from(s).powf(f64::from(n));
            let t = f64::from(n) * f64::from(s).log2();
            let tol = if s > 0.0 {
                4.0 * (1.0 + t.abs()) * exact * f64::from(f32::EPSILON) + 1e-38
            } else {
                0.0
            };
            assert_close(specularity1_power(s, n), exact, tol, "(ψ_specularity1)^n");
        }
        // n = 1: the actual specularity, within an ulp or two.
        for s in [0.1f32, 0.37, 0.9, 1.0] {
            assert_close(specularity1_power(s, 1.0), f64::from(s), 3e-7, "n = 1");
        }
        // The range and the exponent convention of every lobe.
        assert_eq!(specularity1_power(0.0, 4.0), 0.0);
        assert_eq!(specularity1_power(1.0, 4.0), 1.0);
        assert_eq!(specularity1_power(2.0, 4.0), 1.0);
        assert_eq!(specularity1_power(-0.5, 4.0), 0.0);
        assert_eq!(specularity1_power(f32::NAN, 4.0), 0.0);
        assert_eq!(specularity1_power(0.3, 0.0), 1.0);
        assert_eq!(specularity1_power(0.3, -2.0), 1.0);
        assert_close(
            specularity1_power(0.3, f32::NAN),
            0.3,
            3e-7,
            "NaN n acts as 1",
        );
        // A larger n narrows the highlight: the power falls below the lobe everywhere in (0, 1).
        assert!(specularity1_power(0.5, 4.0) < specularity1_power(0.5, 1.0));
    }

    #[test]
    fn uncoloured_specular_is_the_model_s_last_term() {
        let mut rng = Lcg::new(26);
        for _ in 0..2000 {
            let lobe = rng.range(-0.2, 1.2);
            let n = rng.range(0.5, 8.0);
            let eq36 = uncoloured_specular(lobe, LightingModel::Eq36);
            let eq35 = uncoloured_specular(lobe, LightingModel::Eq35 { n });
            assert_eq!(eq36.to_bits(), dampened_specular(lobe).to_bits());
            assert_eq!(eq35.to_bits(), specularity1_power(lobe, n).to_bits());
        }
        assert_eq!(LightingModel::default(), LightingModel::Eq36);
        assert_eq!(LightingModel::Eq36.lobe_exponent(24.0, 4.0), 4.0);
        assert_eq!(
            LightingModel::Eq35 { n: 2.0 }.lobe_exponent(24.0, 4.0),
            24.0
        );
    }

    #[test]
    fn default_weights() {
        let w = ShadingWeights::default();
        assert_eq!(
            (w.ambient, w.diffuse, w.specular, w.dampened),
            (1.0, 1.0, 1.0, 1.0)
        );
        assert_eq!(w.shadow, 0.08);
        // Six opaque lookups over a fully lit white strand leave it visible.
        let c = final_colour(
            Vec3::ONE,
            Vec3::ONE,
            0.0,
            1.0,
            0.0,
            0.0,
            6.0,
            &w,
            AmbientTerm::Strand,
        );
        assert!(c.x > 0.5);
    }

    #[test]
    fn packed_channels_give_the_scalar_formula_bit_for_bit() {
        // The formula as written in the doc, one channel at a time in scalar f32.
        #[allow(clippy::too_many_arguments)]
        fn scalar(
            s: Vec3,
            l: Vec3,
            a: f32,
            d: f32,
            sp: f32,
            p: f32,
            sh: f32,
            w: &ShadingWeights,
            term: AmbientTerm,
        ) -> Vec3 {
            let lit = w.diffuse * d + w.specular * sp;
            let (highlight, dark) = (w.dampened * p, w.shadow * sh);
            let channel = |s: f32, l: f32| {
                let ambient = match term {
                    AmbientTerm::Strand => w.ambient * a * s,
                    AmbientTerm::Constant => w.ambient * a,
                };
                crate::shading::numeric::saturate(ambient + s * l * lit + l * highlight - dark)
            };
            Vec3::new(channel(s.x, l.x), channel(s.y, l.y), channel(s.z, l.z))
        }
        let mut rng = Lcg::new(22);
        let specials = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            1e-40,
            3e38,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let pick = |rng: &mut Lcg, k: usize| {
            if k.is_multiple_of(5) {
                specials[(k / 5 + rng.unit().to_bits() as usize) % specials.len()]
            } else {
                rng.range(-2.0, 3.0)
            }
        };
        for k in 0..20_000 {
            let mut v = [0.0f32; 16];
            for (i, x) in v.iter_mut().enumerate() {
                *x = pick(&mut rng, k * 16 + i);
            }
            let w = ShadingWeights {
                ambient: v[11],
                diffuse: v[12],
                specular: v[13],
                dampened: v[14],
                shadow: v[15],
            };
            let (s, l) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
            let term = [AmbientTerm::Strand, AmbientTerm::Constant][k % 2];
            let got = final_colour(s, l, v[6], v[7], v[8], v[9], v[10], &w, term);
            let expected = scalar(s, l, v[6], v[7], v[8], v[9], v[10], &w, term);
            assert_eq!(
                got.to_array().map(f32::to_bits),
                expected.to_array().map(f32::to_bits),
                "{v:?}"
            );
        }
    }

    #[test]
    fn lanes_are_the_scalar_eq_3_7_bit_for_bit() {
        lanes_bit_for_bit::<4>();
        lanes_bit_for_bit::<8>();
    }

    fn lanes_bit_for_bit<const N: usize>() {
        let mut rng = Lcg::new(23);
        let specials = [0.0, -0.0, 0.6, 1.0, -1.0, 3e38, f32::NAN, f32::INFINITY];
        let mut pick = |k: usize| {
            if k.is_multiple_of(7) {
                specials[(k / 7) % specials.len()]
            } else {
                rng.range(-0.5, 1.5)
            }
        };
        for k in 0..5000usize {
            let lanes: [f32; N] = std::array::from_fn(|i| pick(k * 40 + i));
            let got = dampened_specular_lanes(lanes);
            for i in 0..N {
                assert_eq!(got[i].to_bits(), dampened_specular(lanes[i]).to_bits());
            }
            let n = [1.0, 3.5, 0.0, f32::NAN, 40.0][k % 5];
            for model in [LightingModel::Eq36, LightingModel::Eq35 { n }] {
                let got = uncoloured_specular_lanes(lanes, model);
                for i in 0..N {
                    assert_eq!(
                        got[i].to_bits(),
                        uncoloured_specular(lanes[i], model).to_bits(),
                        "{model:?} of {}",
                        lanes[i]
                    );
                }
            }
            let strand: [Vec3; N] = std::array::from_fn(|i| {
                Vec3::new(
                    pick(k * 40 + 4 + i),
                    pick(k * 40 + 8 + i),
                    pick(k * 40 + 12 + i),
                )
            });
            let term: [[f32; N]; 4] =
                std::array::from_fn(|t| std::array::from_fn(|i| pick(k * 40 + 16 + 4 * t + i)));
            let light = Vec3::new(pick(k * 40 + 32), pick(k * 40 + 33), pick(k * 40 + 34));
            let ambient = pick(k * 40 + 35);
            let w = ShadingWeights {
                ambient: pick(k * 40 + 36),
                diffuse: pick(k * 40 + 37),
                specular: pick(k * 40 + 38),
                dampened: pick(k * 40 + 39),
                shadow: [0.08, 1.0, -0.5][k % 3],
            };
            let ambient_term = [AmbientTerm::Strand, AmbientTerm::Constant][k % 2];
            let got = final_colour_lanes(
                &Vec3xN::from_lanes(strand),
                light,
                ambient,
                term[0],
                term[1],
                term[2],
                term[3],
                &w,
                ambient_term,
            );
            for i in 0..N {
                let expected = final_colour(
                    strand[i],
                    light,
                    ambient,
                    term[0][i],
                    term[1][i],
                    term[2][i],
                    term[3][i],
                    &w,
                    ambient_term,
                );
                assert_eq!(
                    got.lane(i).to_array().map(f32::to_bits),
                    expected.to_array().map(f32::to_bits),
                    "lane {i}: {:?}",
                    strand[i]
                );
            }
        }
    }

    #[test]
    fn final_colour_matches_f64() {
        // Bound: 1e-6 absolute (a handful of products of values ≤ 2).
        let mut rng = Lcg::new(21);
        for n in 0..2000 {
            let strand = Vec3::new(rng.unit(), rng.unit(), rng.unit());
            let light = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 1.5;
            let (a, d, s, p, sh) = (
                rng.unit(),
                rng.unit(),
                rng.unit(),
                rng.range(0.0, 0.3),
                rng.range(0.0, 6.0),
            );
            let w = ShadingWeights {
                ambient: rng.unit(),
                diffuse: rng.unit(),
                specular: rng.unit(),
                dampened: rng.unit(),
                shadow: rng.range(0.0, 0.2),
            };
            let term = [AmbientTerm::Strand, AmbientTerm::Constant][n % 2];
            let got = final_colour(strand, light, a, d, s, p, sh, &w, term);
            for k in 0..3 {
                let (sc, lc) = (f64::from(strand[k]), f64::from(light[k]));
                let f = |x: f32| f64::from(x);
                // ψ_ambient: times the strand colour, or the level alone (eq. 3.7 as printed).
                let reflected = if term == AmbientTerm::Strand { sc } else { 1.0 };
                let expected = (f(w.ambient) * f(a) * reflected
                    + sc * lc * (f(w.diffuse) * f(d) + f(w.specular) * f(s))
                    + lc * f(w.dampened) * f(p)
                    - f(w.shadow) * f(sh))
                .clamp(0.0, 1.0);
                assert_close(got[k], expected, 1e-6, "final colour");
            }
        }
    }

    #[test]
    fn final_colour_clamps_and_survives_nan() {
        let w = ShadingWeights::default();
        let strand = AmbientTerm::Strand;
        let bright = final_colour(Vec3::ONE, Vec3::ONE, 1.0, 1.0, 1.0, 0.3, 0.0, &w, strand);
        assert_eq!(bright, Vec3::ONE);
        let black = final_colour(Vec3::ONE, Vec3::ONE, 0.0, 0.0, 0.0, 0.0, 100.0, &w, strand);
        assert_eq!(black, Vec3::ZERO);
        let nan = final_colour(
            Vec3::splat(f32::NAN),
            Vec3::ONE,
            1.0,
            1.0,
            1.0,
            0.3,
            0.0,
            &w,
            strand,
        );
        assert_eq!(nan, Vec3::ZERO);
        let inf = final_colour(
            Vec3::ONE,
            Vec3::ONE,
            f32::INFINITY,
            0.0,
            0.0,
            0.0,
            0.0,
            &w,
            strand,
        );
        assert_eq!(inf, Vec3::ONE);
        // Ambient alone: ambient × strand colour.
        let amb = final_colour(
            Vec3::new(0.5, 0.2, 0.1),
            Vec3::ONE,
            0.4,
            0.0,
            0.0,
            0.0,
            0.0,
            &w,
            strand,
        );
        assert_close(amb.x, 0.2, 1e-7, "ambient r");
        assert_close(amb.y, 0.08, 1e-7, "ambient g");
        // Eq. 3.7 as printed: the ambient level alone, in every channel.
        let amb = final_colour(
            Vec3::new(0.5, 0.2, 0.1),
            Vec3::ONE,
            0.4,
            0.0,
            0.0,
            0.0,
            0.0,
            &w,
            AmbientTerm::Constant,
        );
        assert_eq!(amb, Vec3::splat(0.4));
    }

    #[test]
    fn ambient_terms_match_f64() {
        // Bound: one f32 product, half an ulp of a value ≤ 4: 3e-7.
        let mut rng = Lcg::new(24);
        for _ in 0..2000 {
            let a = rng.range(0.0, 2.0);
            let strand = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0;
            let constant = ambient_term(a, strand, AmbientTerm::Constant);
            let reflected = ambient_term(a, strand, AmbientTerm::Strand);
            assert_eq!(constant, ambient_constant(a));
            assert_eq!(reflected, ambient_of_strand(a, strand));
            for k in 0..3 {
                assert_close(constant[k], f64::from(a), 0.0, "constant ambient");
                let expected = f64::from(a) * f64::from(strand[k]);
                assert_close(reflected[k], expected, 3e-7, "ambient of the strand");
            }
        }
        assert_eq!(AmbientTerm::default(), AmbientTerm::Strand);
    }
}
