//! Strand generation (thesis 3.1.1; fur bake): cubic Bézier strands planted in the periodic unit
//! tile with MT19937 (`rand_mt::Mt`, 32-bit) seeded by the caller's seed.
//!
//! Invariant: strand `k` depends only on the seed and the parameters, never on how many strands
//! follow it. Each strand takes exactly [`DRAWS_PER_STRAND`] consecutive draws from the
//! generator, in the order listed at [`generate_strands`].

use glam::{Vec2, Vec3};
use rand_mt::Mt;

use super::params::{FurError, FurParams};

/// Number of `next_u32` draws each strand consumes, whatever its parameters.
pub const DRAWS_PER_STRAND: usize = 16;

/// Offset added (wrapping) to the seed for the fin strip's generator, so fin strands are
/// independent of the shell strands drawn from the same user seed.
pub const FIN_SEED_OFFSET: u32 = 0x9E37_79B9;

/// Converts one generator output to a float in `[0, 1)`: the top 24 bits, `(x >> 8) / 2^24`.
/// Exact in f32, so identical on every platform.
pub fn unit_f32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A fur strand: a cubic Bézier curve wrapped in a tapered cone.
#[derive(Debug, Clone, PartialEq)]
pub struct Strand {
    /// Root position: `x, y` in the tile (`[0, 1)` for shell strands), `z = 0`.
    pub root: Vec3,
    /// Bézier control points: `[root, control near the middle, control near the tip, tip]`
    /// (thesis 3.1.1: "the first Bézier point close to the tip, the second around the middle").
    /// Coordinates are not wrapped: a leaning strand may leave the unit tile; bakers wrap it.
    pub control: [Vec3; 4],
    /// Cone radius at the root (Bézier parameter 0), tile units.
    pub base_radius: f32,
    /// Cone radius at the tip (Bézier parameter 1), tile units.
    pub tip_radius: f32,
    /// Strand colour, linear RGB in 0..1.
    pub colour: Vec3,
    /// Unit horizontal direction the strand leans towards (its azimuth).
    pub lean: Vec2,
}

impl Strand {
    /// Cone radius at Bézier parameter `t`: linear from `base_radius` to `tip_radius`.
    pub fn radius_at(&self, t: f32) -> f32 {
        self.base_radius + (self.tip_radius - self.base_radius) * t
    }
}

/// Point of the strand's cubic Bézier at parameter `t ∈ [0, 1]`, by de Casteljau's algorithm.
pub fn bezier_point(strand: &Strand, t: f32) -> Vec3 {
    let [p0, p1, p2, p3] = strand.control;
    let a = p0.lerp(p1, t);
    let b = p1.lerp(p2, t);
    let c = p2.lerp(p3, t);
    let d = a.lerp(b, t);
    let e = b.lerp(c, t);
    d.lerp(e, t)
}

/// Derivative `dP/dt` of the strand's Bézier at `t`:
/// `3[(1−t)²(P1−P0) + 2(1−t)t(P2−P1) + t²(P3−P2)]`, evaluated by de Casteljau on the hodograph.
pub fn bezier_derivative(strand: &Strand, t: f32) -> Vec3 {
    let [p0, p1, p2, p3] = strand.control;
    let q0 = p1 - p0;
    let q1 = p2 - p1;
    let q2 = p3 - p2;
    let a = q0.lerp(q1, t);
    let b = q1.lerp(q2, t);
    3.0 * a.lerp(b, t)
}

/// Unit tangent of the strand at `t` (root → tip direction); `+z` where the derivative vanishes.
pub fn bezier_tangent(strand: &Strand, t: f32) -> Vec3 {
    bezier_derivative(strand, t).normalize_or(Vec3::Z)
}

/// Where strands are planted and how tall they are: the shell tile or the fin strip.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Planting {
    /// Extent of root `y` (1 for the shell tile, `fin_width` for fins).
    pub y_extent: f32,
    /// Multiplier on the height range (1 for shells, `fin_height_scale` for fins).
    pub height_scale: f32,
}

/// Draws one strand: exactly [`DRAWS_PER_STRAND`] values `u0..u15` (see [`generate_strands`]).
fn draw_strand(rng: &mut Mt, params: &FurParams, planting: Planting) -> Strand {
    let mut u = [0.0f32; DRAWS_PER_STRAND];
    for v in &mut u {
        *v = unit_f32(rng.next_u32());
    }
    // Signed jitter in [−1, 1).
    let s = |x: f32| 2.0 * x - 1.0;

    let root = Vec3::new(u[0], u[1] * planting.y_extent, 0.0);
    let h = (params.min_height + (params.max_height - params.min_height) * u[2])
        * planting.height_scale;
    let slope_deg = (params.slope_deg * (1.0 + params.jitter * s(u[3]))).clamp(0.0, 89.0);
    let slope = slope_deg.to_radians();
    let azimuth = u[4] * core::f32::consts::TAU;
    let lean = Vec2::new(libm::cosf(azimuth), libm::sinf(azimuth));
    let lean3 = Vec3::new(lean.x, lean.y, 0.0);
    // Horizontal run of the straight strand from root to tip.
    let run = h * libm::tanf(slope);
    let amp = params.jitter * h;
    let jit = |a: f32, b: f32, c: f32| Vec3::new(s(a), s(b), s(c)) * amp;

    // Around the middle: half the height, a quarter of the run (the strand rises steeply first).
    let mid = root + lean3 * (0.25 * run) + Vec3::Z * (0.5 * h) + jit(u[5], u[6], u[7]);
    // Near the tip: 85 % of the height, three quarters of the run plus the curl.
    let near_tip = root
        + lean3 * (0.75 * run + params.curl * h)
        + Vec3::Z * (0.85 * h)
        + jit(u[8], u[9], u[10]);
    let tip = root + lean3 * run + Vec3::Z * h + jit(u[11], u[12], u[13]);

    let thickness = (1.0 + params.thickness_jitter * s(u[14])).max(0.0);
    let brightness = 1.0 + params.colour_variation * s(u[15]);
    Strand {
        root,
        control: [root, mid, near_tip, tip],
        base_radius: params.base_thickness * thickness,
        tip_radius: params.tip_thickness * thickness,
        colour: (params.colour * brightness).clamp(Vec3::ZERO, Vec3::ONE),
        lean,
    }
}

pub(crate) fn generate_planted(
    params: &FurParams,
    seed: u32,
    count: u32,
    planting: Planting,
) -> Vec<Strand> {
    let mut rng = Mt::new(seed);
    (0..count)
        .map(|_| draw_strand(&mut rng, params, planting))
        .collect()
}

/// Generates `number_of_strands` strands in the unit tile from MT19937 seeded with `seed`.
///
/// Each strand draws 16 values `u_i = unit_f32(next_u32())` in this order:
/// `u0, u1` root `x`, `y` (uniform in `[0, 1)`); `u2` height `lerp(min_height, max_height, u2)`;
/// `u3` slope `slope_deg·(1 + jitter·(2u3−1))`; `u4` lean azimuth `2π·u4`;
/// `u5..u7` middle control jitter; `u8..u10` near-tip control jitter; `u11..u13` tip jitter
/// (each `jitter·height·(2u−1)` on x, y, z); `u14` thickness factor
/// `1 + thickness_jitter·(2u14−1)`; `u15` brightness `1 + colour_variation·(2u15−1)`.
///
/// Shape (before jitter), with `run = height·tan(slope)` along the lean direction `d`:
/// middle control `root + 0.25·run·d + 0.5·height·z`; near-tip control
/// `root + (0.75·run + curl·height)·d + 0.85·height·z`; tip `root + run·d + height·z`.
/// The root itself is not jittered: it is already uniform.
pub fn generate_strands(params: &FurParams, seed: u32) -> Result<Vec<Strand>, FurError> {
    params.validate()?;
    Ok(generate_planted(
        params,
        seed,
        params.number_of_strands,
        Planting {
            y_extent: 1.0,
            height_scale: 1.0,
        },
    ))
}

/// Generates the fin strip's strands (thesis 3.1.2.2): the same generator and draw order as
/// [`generate_strands`], seeded with `seed.wrapping_add(FIN_SEED_OFFSET)`, `fin_strands`
/// strands with roots `x ∈ [0, 1)`, `y ∈ [0, fin_width)` and heights × `fin_height_scale`.
pub fn generate_fin_strands(params: &FurParams, seed: u32) -> Result<Vec<Strand>, FurError> {
    params.validate()?;
    Ok(generate_planted(
        params,
        seed.wrapping_add(FIN_SEED_OFFSET),
        params.fin_strands,
        Planting {
            y_extent: params.fin_width,
            height_scale: params.fin_height_scale,
        },
    ))
}

/// A straight vertical strand of constant radius `r` rooted at (x, y), `h` tall: the simplest
/// strand whose bake can be predicted by hand (test helper).
#[cfg(test)]
pub(crate) fn vertical_strand(x: f32, y: f32, h: f32, r: f32, colour: Vec3) -> Strand {
    let root = Vec3::new(x, y, 0.0);
    let tip = root + Vec3::Z * h;
    Strand {
        root,
        control: [
            root,
            root.lerp(tip, 1.0 / 3.0),
            root.lerp(tip, 2.0 / 3.0),
            tip,
        ],
        base_radius: r,
        tip_radius: r,
        colour,
        lean: glam::Vec2::X,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn casteljau_f64(p: [Vec3; 4], t: f64) -> [f64; 3] {
        let mut pts: Vec<[f64; 3]> = p
            .iter()
            .map(|v| [v.x as f64, v.y as f64, v.z as f64])
            .collect();
        while pts.len() > 1 {
            pts = pts
                .windows(2)
                .map(|w| {
                    [
                        w[0][0] + (w[1][0] - w[0][0]) * t,
                        w[0][1] + (w[1][1] - w[0][1]) * t,
                        w[0][2] + (w[1][2] - w[0][2]) * t,
                    ]
                })
                .collect();
        }
        pts[0]
    }

    fn derivative_f64(p: [Vec3; 4], t: f64) -> [f64; 3] {
        let h = [p[1] - p[0], p[2] - p[1], p[3] - p[2]];
        let mut out = [0.0; 3];
        for (i, o) in out.iter_mut().enumerate() {
            let c = |v: Vec3| v.to_array()[i] as f64;
            *o = 3.0
                * ((1.0 - t) * (1.0 - t) * c(h[0])
                    + 2.0 * (1.0 - t) * t * c(h[1])
                    + t * t * c(h[2]));
        }
        out
    }

    #[test]
    fn bezier_matches_f64_de_casteljau() {
        let params = FurParams {
            jitter: 0.5,
            curl: 0.8,
            ..FurParams::default()
        };
        let strands = generate_strands(&params, 7).expect("valid");
        for s in strands.iter().take(50) {
            for k in 0..=64 {
                let t = k as f32 / 64.0;
                let p = bezier_point(s, t);
                let e = casteljau_f64(s.control, t as f64);
                let d = bezier_derivative(s, t);
                let ed = derivative_f64(s.control, t as f64);
                for i in 0..3 {
                    let got = p.to_array()[i] as f64;
                    assert!(
                        (got - e[i]).abs() <= 4e-6 * (1.0 + e[i].abs()),
                        "{got} vs {}",
                        e[i]
                    );
                    let gd = d.to_array()[i] as f64;
                    assert!(
                        (gd - ed[i]).abs() <= 1e-5 * (1.0 + ed[i].abs()),
                        "{gd} vs {}",
                        ed[i]
                    );
                }
            }
            assert_eq!(bezier_point(s, 0.0), s.control[0]);
            assert_eq!(bezier_point(s, 1.0), s.control[3]);
            let tan = bezier_tangent(s, 0.3);
            assert!((tan.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn unit_f32_range() {
        assert_eq!(unit_f32(0), 0.0);
        assert!(unit_f32(u32::MAX) < 1.0);
        assert_eq!(unit_f32(1 << 31), 0.5);
    }

    #[test]
    fn strand_k_does_not_depend_on_count() {
        let few = FurParams {
            number_of_strands: 10,
            ..FurParams::default()
        };
        let many = FurParams {
            number_of_strands: 300,
            ..FurParams::default()
        };
        let a = generate_strands(&few, 42).expect("valid");
        let b = generate_strands(&many, 42).expect("valid");
        assert_eq!(a.len(), 10);
        assert_eq!(b.len(), 300);
        assert_eq!(a[..], b[..10]);
    }

    #[test]
    fn seeds_and_ranges() {
        let p = FurParams::default();
        let a = generate_strands(&p, 1).expect("valid");
        let b = generate_strands(&p, 1).expect("valid");
        let c = generate_strands(&p, 2).expect("valid");
        assert_eq!(a, b);
        assert_ne!(a, c);
        for s in &a {
            assert!((0.0..1.0).contains(&s.root.x) && (0.0..1.0).contains(&s.root.y));
            assert_eq!(s.root.z, 0.0);
            assert_eq!(s.control[0], s.root);
            let h = s.control[3].z;
            assert!(h > p.min_height * 0.8 && h < p.max_height * 1.2, "{h}");
            // Leans along its lean direction.
            let run = (s.control[3] - s.root).truncate();
            assert!(run.dot(s.lean) > 0.0);
            assert!(s.base_radius >= s.tip_radius && s.tip_radius > 0.0);
            assert!(s.colour.cmple(Vec3::ONE).all() && s.colour.cmpge(Vec3::ZERO).all());
        }
    }

    #[test]
    fn fin_strands_in_strip_and_taller() {
        let p = FurParams::default();
        let fins = generate_fin_strands(&p, 3).expect("valid");
        assert_eq!(fins.len(), p.fin_strands as usize);
        let mean_h: f32 = fins.iter().map(|s| s.control[3].z).sum::<f32>() / fins.len() as f32;
        assert!(mean_h > p.max_height);
        for s in &fins {
            assert!(s.root.y >= 0.0 && s.root.y < p.fin_width);
        }
    }

    #[test]
    fn invalid_params_are_rejected() {
        let p = FurParams {
            jitter: f32::NAN,
            ..FurParams::default()
        };
        assert!(generate_strands(&p, 1).is_err());
        assert!(generate_fin_strands(&p, 1).is_err());
    }
}
