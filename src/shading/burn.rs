//! Burning fur (thesis 3.4; shading stage): a match is a spot light fixed to the object; its lobe
//! intensity decides, per shell, whether the layer is intact, charred, or burnt away, and its
//! exponent follows a schedule so the burnt area starts small and spreads.

use super::lanes::lane_mask;
use glam::Vec3;

/// Spot intensities strictly above this burn (thesis 3.4: "if the intensity is greater than
/// 0.1"); 0.1 itself is unburnt.
pub const BURN_THRESHOLD: f32 = 0.1;

/// What the burn rule does to one shell texel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BurnOutcome {
    /// Ordinary shading with eq. 3.7.
    Unburnt,
    /// Still there, charred: multiply the strand colour by `colour_factor = 1 − I`.
    Charred {
        /// The factor on the strand colour, in `[0, 0.9)`.
        colour_factor: f32,
    },
    /// Burnt away: alpha 0.
    Burnt,
}

impl BurnOutcome {
    /// The strand colour after the burn: unchanged when unburnt, scaled when charred, and
    /// unchanged when burnt (the texel is then drawn with alpha 0, see [`BurnOutcome::alpha`]).
    #[inline]
    pub fn strand_colour(self, strand_colour: Vec3) -> Vec3 {
        match self {
            BurnOutcome::Charred { colour_factor } => strand_colour * colour_factor,
            BurnOutcome::Unburnt | BurnOutcome::Burnt => strand_colour,
        }
    }

    /// The texel's alpha after the burn: 0 when burnt, else `alpha` unchanged.
    #[inline]
    pub fn alpha(self, alpha: f32) -> f32 {
        match self {
            BurnOutcome::Burnt => 0.0,
            BurnOutcome::Unburnt | BurnOutcome::Charred { .. } => alpha,
        }
    }
}

/// The burn rule of thesis 3.4 for spot intensity `I` at shell `shell_index`:
///
/// - `I > 0.1` (strictly; NaN and `I ≤ 0.1` are [`BurnOutcome::Unburnt`]): with `I` capped at
///   1 and `t = (1 − I)·max_shell`,
///   - a shell with `shell_index > t` is [`BurnOutcome::Burnt`] ("if it is smaller than the
///     current shell value then we set the alpha to 0");
///   - a shell with `shell_index ≤ t` is [`BurnOutcome::Charred`] with factor `1 − I`; equality
///     (`shell_index == t`) counts as not yet burnt, the thesis's "smaller than" being strict.
/// - The bottom layer (`shell_index == 0`) is never burnt: burnt stubs remain at the root
///   (with `I = 1` it is charred with factor 0, black).
///
/// `max_shell` is the index of the top shell (`number_of_shells − 1`). The shell index is
/// compared as an f32 (exact below 2²⁴ shells).
#[inline]
pub fn burn_rule(intensity: f32, shell_index: u32, max_shell: u32) -> BurnOutcome {
    if intensity.is_nan() || intensity <= BURN_THRESHOLD {
        return BurnOutcome::Unburnt;
    }
    let i = intensity.min(1.0);
    let t = (1.0 - i) * max_shell as f32;
    if shell_index > 0 && shell_index as f32 > t {
        BurnOutcome::Burnt
    } else {
        BurnOutcome::Charred {
            colour_factor: 1.0 - i,
        }
    }
}

/// [`burn_rule`] of `N` lanes as lane masks (bit `l` for lane `l`, `N` at most 32): which are
/// burnt away, which charred and by what factor. Lane by lane the same outcome as the scalar
/// rule ([`BurnLanes::outcome`] reads one lane back).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BurnLanes<const N: usize> {
    /// Lanes burnt away ([`BurnOutcome::Burnt`]).
    pub burnt: u32,
    /// Lanes charred ([`BurnOutcome::Charred`]); never a burnt lane.
    pub charred: u32,
    /// Each charred lane's factor on the strand colour (meaningless in the other lanes).
    pub colour_factor: [f32; N],
}

impl<const N: usize> BurnLanes<N> {
    /// The outcome of lane `lane` (`0..N`; a lane past the last reads the last).
    pub fn outcome(&self, lane: usize) -> BurnOutcome {
        let lane = lane.min(N.saturating_sub(1));
        let bit = 1u32.checked_shl(lane as u32).unwrap_or(0);
        if self.burnt & bit != 0 {
            BurnOutcome::Burnt
        } else if self.charred & bit != 0 {
            BurnOutcome::Charred {
                colour_factor: self.colour_factor[lane],
            }
        } else {
            BurnOutcome::Unburnt
        }
    }
}

/// [`burn_rule`] of `N` intensities (`N` at most 32) on one shell, with the same comparisons
/// and roundings per lane, as loops over the lanes that the level's copy of the fur stage runs
/// packed (step 1 of the fur stage runs it on every lane of a burning frame).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
pub fn burn_rule_lanes<const N: usize>(
    intensity: [f32; N],
    shell_index: u32,
    max_shell: u32,
) -> BurnLanes<N> {
    let (max_shell_f, shell_f) = (max_shell as f32, shell_index as f32);
    let (mut above, mut below_shell) = (0u32, 0u32);
    let mut colour_factor = [0.0f32; N];
    for k in 0..N {
        let intensity = intensity[k];
        // `min(I, 1)` where `I` is a number above the threshold.
        let i = if intensity < 1.0 { intensity } else { 1.0 };
        let factor = 1.0 - i;
        colour_factor[k] = factor;
        // `I > 0.1`, false for NaN: the lanes the rule touches.
        above |= lane_mask(intensity > BURN_THRESHOLD) & (1 << k);
        below_shell |= lane_mask(factor * max_shell_f < shell_f) & (1 << k);
    }
    let burnt = if shell_index > 0 {
        above & below_shell
    } else {
        0
    };
    BurnLanes {
        burnt,
        charred: above & !burnt,
        colour_factor,
    }
}

/// An intensity from which [`burn_rule`] surely burns shell `shell_index` of `max_shell` away:
/// every `I ≥ level` (NaN aside) is [`BurnOutcome::Burnt`]. A shader that knows a lane's
/// intensity is at least this skips its exact value (`light_spot_cosine_above` turns it into
/// a cosine).
///
/// `level = max(0.1, 1 − shell_index/max_shell) + 10⁻³`: above the strict threshold, and with
/// `I ≥ level` the rule's `(1 − min(I, 1))·max_shell` is at most `shell_index − 10⁻³·max_shell`
/// before rounding, which f32's rounding (below `2⁻²³·max_shell`) cannot bring up to
/// `shell_index`. +∞ for the root shell (never burnt) and for `max_shell = 0`.
#[inline]
pub fn burnt_away_above(shell_index: u32, max_shell: u32) -> f32 {
    if shell_index == 0 || max_shell == 0 {
        return f32::INFINITY;
    }
    BURN_THRESHOLD.max(1.0 - shell_index as f32 / max_shell as f32) + 1.0e-3
}

/// The schedule of a match's spot exponent over time (thesis 3.4: "in the beginning of the
/// simulation it is inactive, then we change it to a higher value to only affect the region
/// closest to the fire, later we decrease the exponent to increase the area").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BurnSchedule {
    /// Time (seconds) when the match lights; inactive before.
    pub start: f32,
    /// Exponent at `start`: a narrow lobe, only the nearest area burns.
    pub high_exponent: f32,
    /// Exponent at the end of the spread, kept afterwards: a wide lobe.
    pub low_exponent: f32,
    /// Seconds over which the exponent falls from high to low.
    pub spread_duration: f32,
}

/// The spot exponent of a match at `time` (thesis 3.4), or `None` while inactive.
///
/// - `time < start` (or NaN time or start): `None`.
/// - `start ≤ time < start + spread_duration`: geometric interpolation
///   `high·(low/high)^((time − start)/spread_duration)`, exactly `high` at `start`. A lobe
///   `cos^p` spreads in angle like `1/sqrt(p)`, so a geometric fall of `p` widens the burnt
///   area at a steady relative rate, where a linear fall would barely move at first.
/// - afterwards (and for a non-positive or NaN `spread_duration`): `low`.
///
/// A non-positive or non-finite exponent in the schedule is replaced by 1.
#[inline]
pub fn burn_exponent(time: f32, schedule: &BurnSchedule) -> Option<f32> {
    if time.is_nan() || schedule.start.is_nan() || time < schedule.start {
        return None;
    }
    let positive_or_one = |p: f32| if p.is_finite() && p > 0.0 { p } else { 1.0 };
    let high = positive_or_one(schedule.high_exponent);
    let low = positive_or_one(schedule.low_exponent);
    let elapsed = time - schedule.start;
    let duration = schedule.spread_duration;
    if duration.is_nan() || duration <= 0.0 || elapsed.is_nan() || elapsed >= duration {
        return Some(low);
    }
    Some(high * libm::powf(low / high, elapsed / duration))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};

    #[test]
    fn the_rule_on_lanes_is_the_scalar_rule_lane_by_lane() {
        let mut rng = Lcg::new(71);
        let mut intensities = vec![
            f32::NAN,
            f32::NEG_INFINITY,
            -1.0,
            0.0,
            BURN_THRESHOLD,
            BURN_THRESHOLD.next_up(),
            0.5,
            1.0f32.next_down(),
            1.0,
            1.5,
            f32::INFINITY,
        ];
        // Intensities a few ulps around where each shell of 30 turns from charred to burnt.
        for shell in 0..30u32 {
            let edge = 1.0 - shell as f32 / 29.0;
            let (mut below, mut above) = (edge, edge);
            for _ in 0..4 {
                (below, above) = (below.next_down(), above.next_up());
                intensities.extend([below, above]);
            }
        }
        intensities.extend((0..400).map(|_| rng.range(-0.2, 1.2)));
        for max_shell in [0u32, 1, 29, 99] {
            for shell in 0..=max_shell {
                for chunk in intensities.chunks(16) {
                    let mut lanes = [0.0f32; 16];
                    lanes[..chunk.len()].copy_from_slice(chunk);
                    let wide = burn_rule_lanes(lanes, shell, max_shell);
                    assert_eq!(wide.burnt & wide.charred, 0);
                    let mut quad = [0.0f32; 4];
                    quad.copy_from_slice(&lanes[..4]);
                    let narrow = burn_rule_lanes(quad, shell, max_shell);
                    for (i, &intensity) in lanes.iter().enumerate() {
                        let want = burn_rule(intensity, shell, max_shell);
                        let got = wide.outcome(i);
                        if i < 4 {
                            assert_eq!(narrow.outcome(i), got, "{intensity} on {shell}");
                        }
                        match (got, want) {
                            (
                                BurnOutcome::Charred { colour_factor: a },
                                BurnOutcome::Charred { colour_factor: b },
                            ) => assert_eq!(a.to_bits(), b.to_bits(), "{intensity} on {shell}"),
                            _ => assert_eq!(got, want, "{intensity} on {shell} of {max_shell}"),
                        }
                    }
                }
            }
        }
    }

    fn charred(factor: f32) -> BurnOutcome {
        BurnOutcome::Charred {
            colour_factor: factor,
        }
    }

    #[test]
    fn intensities_from_the_burnt_level_burn_the_shell_away() {
        let mut rng = Lcg::new(71);
        for max_shell in [1u32, 2, 3, 7, 29, 30, 99, 255, 1023, 4095] {
            assert_eq!(burnt_away_above(0, max_shell), f32::INFINITY);
            for shell in 1..=max_shell {
                let level = burnt_away_above(shell, max_shell);
                assert!(level > BURN_THRESHOLD, "{shell}/{max_shell}");
                let mut intensity = level;
                for _ in 0..32 {
                    assert_eq!(
                        burn_rule(intensity, shell, max_shell),
                        BurnOutcome::Burnt,
                        "{intensity} on {shell}/{max_shell}"
                    );
                    intensity = intensity.next_up();
                }
                for _ in 0..8 {
                    let above = rng.range(level.min(1.0), 1.5);
                    if above >= level {
                        assert_eq!(burn_rule(above, shell, max_shell), BurnOutcome::Burnt);
                    }
                }
                // The margin is small: well under the level, the shell is not burnt.
                let under = (1.0 - shell as f64 / max_shell as f64).max(0.1) - 2.0e-3;
                if under > 0.1 {
                    assert_ne!(
                        burn_rule(under as f32, shell, max_shell),
                        BurnOutcome::Burnt
                    );
                }
            }
        }
        assert_eq!(burnt_away_above(3, 0), f32::INFINITY);
    }

    #[test]
    fn burn_rule_branches() {
        // 30 shells: max_shell = 29.
        assert_eq!(burn_rule(0.0, 10, 29), BurnOutcome::Unburnt);
        assert_eq!(burn_rule(0.1, 29, 29), BurnOutcome::Unburnt); // exactly 0.1
        assert_eq!(burn_rule(-1.0, 29, 29), BurnOutcome::Unburnt);
        assert_eq!(burn_rule(f32::NAN, 29, 29), BurnOutcome::Unburnt);
        let just = f32::from_bits(0.1f32.to_bits() + 1);
        // Just above 0.1: t ≈ 26.1, the top layers burn, the lower ones char.
        assert_eq!(burn_rule(just, 29, 29), BurnOutcome::Burnt);
        assert_eq!(burn_rule(just, 27, 29), BurnOutcome::Burnt);
        assert_eq!(burn_rule(just, 26, 29), charred(1.0 - just));
        // I = 0.5 with max_shell 20: t = 10 exactly; equality is charred, above is burnt.
        assert_eq!(burn_rule(0.5, 10, 20), charred(0.5));
        assert_eq!(burn_rule(0.5, 11, 20), BurnOutcome::Burnt);
        assert_eq!(burn_rule(0.5, 0, 20), charred(0.5));
        // I = 1: everything above the root burns; the root remains, black.
        assert_eq!(burn_rule(1.0, 1, 29), BurnOutcome::Burnt);
        assert_eq!(burn_rule(1.0, 29, 29), BurnOutcome::Burnt);
        assert_eq!(burn_rule(1.0, 0, 29), charred(0.0));
        // Intensities above 1 are capped.
        assert_eq!(burn_rule(3.0, 0, 29), charred(0.0));
        assert_eq!(burn_rule(f32::INFINITY, 5, 29), BurnOutcome::Burnt);
        // A single shell (max_shell 0) is never burnt.
        assert_eq!(burn_rule(0.9, 0, 0), charred(1.0 - 0.9));
    }

    #[test]
    fn burn_rule_matches_f64_threshold() {
        let mut rng = Lcg::new(60);
        for _ in 0..5000 {
            let i = rng.range(0.0, 1.0);
            let max_shell = (rng.next_u64() % 64) as u32;
            let shell = (rng.next_u64() % u64::from(max_shell + 1)) as u32;
            let (id, t) = (f64::from(i), (1.0 - f64::from(i)) * f64::from(max_shell));
            let got = burn_rule(i, shell, max_shell);
            if id <= 0.1f32 as f64 {
                assert_eq!(got, BurnOutcome::Unburnt);
            } else if shell > 0 && f64::from(shell) > t + 1e-5 {
                assert_eq!(got, BurnOutcome::Burnt, "I {i} shell {shell}/{max_shell}");
            } else if shell == 0 || f64::from(shell) < t - 1e-5 {
                assert_eq!(got, charred(1.0 - i), "I {i} shell {shell}/{max_shell}");
            }
        }
    }

    #[test]
    fn outcome_applies_to_colour_and_alpha() {
        let c = Vec3::new(0.5, 0.4, 0.2);
        assert_eq!(BurnOutcome::Unburnt.strand_colour(c), c);
        assert_eq!(charred(0.5).strand_colour(c), c * 0.5);
        assert_eq!(BurnOutcome::Burnt.alpha(0.8), 0.0);
        assert_eq!(charred(0.5).alpha(0.8), 0.8);
        assert_eq!(BurnOutcome::Unburnt.alpha(0.8), 0.8);
    }

    #[test]
    fn schedule_phases_and_geometric_curve() {
        let s = BurnSchedule {
            start: 2.0,
            high_exponent: 200.0,
            low_exponent: 2.0,
            spread_duration: 10.0,
        };
        assert_eq!(burn_exponent(0.0, &s), None);
        assert_eq!(
            burn_exponent(f32::from_bits(2.0f32.to_bits() - 1), &s),
            None
        );
        assert_eq!(burn_exponent(f32::NAN, &s), None);
        assert_eq!(burn_exponent(2.0, &s), Some(200.0));
        assert_eq!(burn_exponent(12.0, &s), Some(2.0));
        assert_eq!(burn_exponent(1e9, &s), Some(2.0));
        assert_eq!(burn_exponent(f32::INFINITY, &s), Some(2.0));
        // Half way: the geometric mean, 20.
        assert_close(
            burn_exponent(7.0, &s).unwrap_or(0.0),
            20.0,
            2e-5 * 20.0,
            "midpoint",
        );
        // Against f64, relative bound 1e-5.
        let mut rng = Lcg::new(61);
        for _ in 0..1000 {
            let t = rng.range(2.0, 12.0);
            let f = (f64::from(t) - 2.0) / 10.0;
            let expected = 200.0 * (2.0f64 / 200.0).powf(f);
            let got = burn_exponent(t, &s).unwrap_or(f32::NAN);
            assert_close(got, expected, 1e-5 * expected, "schedule");
            // Monotone fall between the two exponents.
            assert!((2.0..=200.0).contains(&got));
        }
        // Degenerate schedules.
        let instant = BurnSchedule {
            spread_duration: 0.0,
            ..s
        };
        assert_eq!(burn_exponent(2.0, &instant), Some(2.0));
        let bad = BurnSchedule {
            high_exponent: f32::NAN,
            low_exponent: -3.0,
            spread_duration: f32::NAN,
            ..s
        };
        assert_eq!(burn_exponent(5.0, &bad), Some(1.0));
        let nan_start = BurnSchedule {
            start: f32::NAN,
            ..s
        };
        assert_eq!(burn_exponent(5.0, &nan_start), None);
    }
}
