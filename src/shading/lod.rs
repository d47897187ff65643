//! Level of detail (shading stage): fewer shells as the fur gets smaller on screen, with a
//! continuous transition.
//!
//! How it works:
//! 1. [`lod_fur_pixels`]: the fur's on-screen height at the object's distance.
//! 2. [`lod_shell_level`]: a *continuous* number of shells `M ∈ [min, N]`, one per
//!    `pixels_per_shell` of that height.
//! 3. [`lod_layer_order`]: the layers in the order they are added (root, top, then halving the
//!    gaps), so the layers drawn at level `M` are always the first `⌈M⌉` of one fixed list:
//!    raising the level only adds layers, never moves one.
//! 4. [`lod_layer_spans`]: each drawn layer stands for the baked layers from it up to the next
//!    drawn one (its *span*); the newest layer fades in with the fractional part of `M`, taking
//!    its share of the span from the layer below it continuously.
//! 5. [`lod_alpha`]: a layer standing for `s` layers gets the alpha `s` layers of its own alpha
//!    would have together, `1 − (1 − α)^s`, so the fur's opacity holds with fewer layers.
//!
//! Every step is continuous in the distance, so two frames of a moving camera differ little;
//! at the level where every layer is drawn, spans are exactly 1 and the image is byte-identical
//! to one without level of detail.

use super::numeric::finite_or_zero;

/// Height of the fur on screen, pixels: `model_difference · (H/2) / (distance · tan(fov/2))` for
/// an image `image_height` pixels high with vertical field of view `fov_y_deg`. A distance at or
/// below 0 (camera inside the object) gives `+inf` (the most detail).
#[inline]
pub fn lod_fur_pixels(
    model_difference: f32,
    distance: f32,
    fov_y_deg: f32,
    image_height: u32,
) -> f32 {
    if distance.is_nan() || distance <= 0.0 {
        return f32::INFINITY;
    }
    let half_fov = 0.5 * fov_y_deg.to_radians();
    model_difference * (0.5 * image_height as f32) / (distance * libm::tanf(half_fov))
}

/// The continuous shell level: `fur_pixels / pixels_per_shell` clamped to
/// `[min(min_shells, shells), shells]`; never below 1. NaN gives `shells` (full detail).
#[inline]
pub fn lod_shell_level(
    fur_pixels: f32,
    pixels_per_shell: f32,
    min_shells: u32,
    shells: u32,
) -> f32 {
    let shells = shells.max(1) as f32;
    let lowest = (min_shells.max(1) as f32).min(shells);
    let level = fur_pixels / pixels_per_shell;
    if level.is_nan() {
        return shells;
    }
    level.clamp(lowest, shells)
}

/// The order in which layers `0..shells` are added as the level rises: the root, the top, then
/// the layers `⌊x·shells⌋` for `x` the base-2 radical inverse of 1, 2, 3, … (½, ¼, ¾, ⅛, …),
/// each layer once. Every prefix spreads its layers over the fur's height.
pub fn lod_layer_order(shells: u32) -> Vec<u32> {
    let n = shells.max(1);
    let mut order = vec![0];
    let mut taken = vec![false; n as usize];
    taken[0] = true;
    let mut push = |i: u32, order: &mut Vec<u32>| {
        if !taken[i as usize] {
            taken[i as usize] = true;
            order.push(i);
        }
    };
    push(n - 1, &mut order);
    // 2^bits ≥ n: the radical inverses of 0..2^bits are the multiples of 1/2^bits, whose
    // ⌊x·n⌋ cover every layer.
    let bits = 32 - (n - 1).leading_zeros().min(31);
    for j in 1u32..(1u32 << bits) {
        let x = f64::from(j.reverse_bits() >> (32 - bits)) / f64::from(1u32 << bits);
        push(((x * f64::from(n)) as u32).min(n - 1), &mut order);
    }
    order
}

/// How many baked layers each layer stands for at `level` (0: not drawn), indexed by layer.
///
/// The first `⌈level⌉` layers of `order` are drawn. Sorted by height, a drawn layer `i` whose
/// next drawn layer above is `j` (or `shells` for the highest) spans `j − i`. The newest layer
/// `p` (the last of the drawn prefix) fades in with `φ = level − (⌈level⌉ − 1)`: it spans
/// `φ·(j_p − p)` and the drawn layer below it spans `(p − i) + (1 − φ)·(j_p − p)`. Spans always
/// add up to `shells`, and are continuous in `level`.
pub fn lod_layer_spans(order: &[u32], level: f32) -> Vec<f32> {
    let shells = order.len();
    let mut spans = vec![0.0f32; shells];
    if shells == 0 {
        return spans;
    }
    let level = if level.is_nan() {
        shells as f32
    } else {
        level.clamp(1.0, shells as f32)
    };
    let drawn_count = (libm::ceilf(level) as usize).clamp(1, shells);
    let fade = level - (drawn_count - 1) as f32;
    let mut drawn: Vec<u32> = order[..drawn_count].to_vec();
    drawn.sort_unstable();
    let newest = order[drawn_count - 1];
    for (k, &i) in drawn.iter().enumerate() {
        let next = drawn.get(k + 1).map_or(shells as u32, |&j| j);
        spans[i as usize] = (next - i) as f32;
    }
    if fade < 1.0 {
        let k = drawn.iter().position(|&i| i == newest).unwrap_or(0);
        let own = spans[newest as usize];
        if k > 0 {
            let below = drawn[k - 1] as usize;
            spans[below] += (1.0 - fade) * own;
            spans[newest as usize] = fade * own;
        }
    }
    spans
}

/// `x^n` for a whole `n` by square-and-multiply, lowest bit first: `result *= base` when the
/// bit is set, then `base *= base`. A fixed order of f32 products, cheaper than `powf`.
#[inline]
pub fn pow_whole(x: f32, n: u32) -> f32 {
    let (mut result, mut base, mut n) = (1.0f32, x, n);
    while n > 0 {
        if n & 1 == 1 {
            result *= base;
        }
        base *= base;
        n >>= 1;
    }
    result
}

/// The alpha of a layer standing for `span` layers of alpha `alpha`: `1 − (1 − α)^span`.
/// `span == 1` returns `alpha` itself, `span ≤ 0` gives 0; a whole `span` (every drawn layer
/// but the one fading in and the one below it) raises with [`pow_whole`], a fractional one
/// with `libm::powf`. `alpha` is saturated.
#[inline]
pub fn lod_alpha(alpha: f32, span: f32) -> f32 {
    if span == 1.0 {
        return alpha;
    }
    let a = if alpha > 0.0 { alpha.min(1.0) } else { 0.0 };
    let span = finite_or_zero(span);
    if span <= 0.0 {
        return 0.0;
    }
    let whole = span as u32;
    if whole as f32 == span {
        1.0 - pow_whole(1.0 - a, whole)
    } else {
        1.0 - libm::powf(1.0 - a, span)
    }
}

/// The fins' opacity factor: the Hermite smoothstep of the fur's on-screen height between
/// `fade[0]` (0: fins gone) and `fade[1]` (1: fins whole). Equal ends give a step at them.
#[inline]
pub fn lod_fin_fade(fur_pixels: f32, fade: [f32; 2]) -> f32 {
    let [lo, hi] = fade;
    if fur_pixels.is_nan() {
        return 1.0;
    }
    if hi <= lo {
        return if fur_pixels >= hi { 1.0 } else { 0.0 };
    }
    let x = ((fur_pixels - lo) / (hi - lo)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};

    #[test]
    fn fur_pixels_matches_f64() {
        let mut rng = Lcg::new(5);
        for _ in 0..1000 {
            let (d, dist, fov, h) = (
                rng.range(0.01, 3.0),
                rng.range(0.5, 100.0),
                rng.range(5.0, 120.0),
                1 + (rng.unit() * 2000.0) as u32,
            );
            let expected = f64::from(d) * 0.5 * f64::from(h)
                / (f64::from(dist) * (f64::from(fov).to_radians() * 0.5).tan());
            assert_close(
                lod_fur_pixels(d, dist, fov, h),
                expected,
                2e-6 * expected,
                "fur px",
            );
        }
        assert_eq!(lod_fur_pixels(0.6, 0.0, 45.0, 480), f32::INFINITY);
    }

    #[test]
    fn shell_level_is_clamped_and_continuous() {
        assert_eq!(lod_shell_level(100.0, 1.0, 4, 30), 30.0);
        assert_eq!(lod_shell_level(1.0, 1.0, 4, 30), 4.0);
        assert_eq!(lod_shell_level(15.0, 2.0, 4, 30), 7.5);
        assert_eq!(lod_shell_level(1.0, 1.0, 40, 30), 30.0);
        assert_eq!(lod_shell_level(f32::NAN, 1.0, 4, 30), 30.0);
        assert_eq!(lod_shell_level(f32::INFINITY, 1.0, 4, 30), 30.0);
    }

    #[test]
    fn layer_order_is_a_permutation_whose_prefixes_spread() {
        for n in 1..=64 {
            let order = lod_layer_order(n);
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..n).collect::<Vec<_>>(), "n = {n}");
            assert_eq!(order[0], 0);
            if n > 1 {
                assert_eq!(order[1], n - 1);
            }
            // Every prefix of m ≥ 3 layers leaves no gap wider than about 2·n/(m−1).
            for m in 3..=n as usize {
                let mut p = order[..m].to_vec();
                p.sort_unstable();
                let widest = p.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
                assert!(
                    widest as f32 <= 2.0 * n as f32 / (m - 1) as f32 + 1.0,
                    "n {n} m {m}: gap {widest} in {p:?}"
                );
            }
        }
        assert_eq!(&lod_layer_order(30)[..6], &[0, 29, 15, 7, 22, 3]);
    }

    #[test]
    fn spans_add_up_are_one_at_full_detail_and_continuous() {
        let order = lod_layer_order(30);
        assert!(lod_layer_spans(&order, 30.0).iter().all(|&s| s == 1.0));
        for k in 0..=2900 {
            let level = 1.0 + k as f32 * 0.01;
            let spans = lod_layer_spans(&order, level);
            let total: f32 = spans.iter().sum();
            assert!((total - 30.0).abs() < 1e-3, "level {level}: {total}");
            // Nested: a layer drawn at this level is drawn at every higher level.
            let higher = lod_layer_spans(&order, (level + 0.5).min(30.0));
            for (a, b) in spans.iter().zip(&higher) {
                assert!(*a == 0.0 || *b > 0.0);
            }
            // Continuous: a small step of the level moves every span by at most the step
            // times the widest gap.
            let next = lod_layer_spans(&order, level + 0.001);
            for (a, b) in spans.iter().zip(&next) {
                assert!(
                    (a - b).abs() <= 0.001 * 30.0 + 1e-4,
                    "level {level}: {a} → {b}"
                );
            }
        }
        // Level 2: the root spans everything below the top, the top spans 1.
        let spans = lod_layer_spans(&order, 2.0);
        assert_eq!((spans[0], spans[29]), (29.0, 1.0));
        // Level 2.25: layer 15 fades in with a quarter of its span (29 − 15 = 14).
        let spans = lod_layer_spans(&order, 2.25);
        assert_eq!(
            (spans[0], spans[15], spans[29]),
            (15.0 + 0.75 * 14.0, 0.25 * 14.0, 1.0)
        );
    }

    #[test]
    fn lod_alpha_matches_f64() {
        let mut rng = Lcg::new(8);
        for _ in 0..2000 {
            let (a, s) = (rng.unit(), rng.range(0.0, 30.0));
            let expected = 1.0 - (1.0 - f64::from(a)).powf(f64::from(s));
            // Bound: 1 − a is exact to 6e-8; powf's slope s·(1−a)^(s−1) carries it.
            let slope = f64::from(s) * (1.0 - f64::from(a)).powf(f64::from(s) - 1.0).min(1e3);
            assert_close(
                lod_alpha(a, s),
                expected,
                1e-6 + 1.2e-7 * slope,
                "lod alpha",
            );
        }
        for _ in 0..2000 {
            let (a, n) = (rng.unit(), 1 + (rng.unit() * 40.0) as u32);
            let expected = 1.0 - (1.0 - f64::from(a)).powi(n as i32);
            // Bound: n products, each rounding by 2^-24 relative: n·6e-8 of (1 − a)^n ≤ 1.
            assert_close(
                lod_alpha(a, n as f32),
                expected,
                1e-7 + 1.2e-7 * f64::from(n),
                "whole",
            );
        }
        assert_eq!(pow_whole(0.5, 0), 1.0);
        assert_eq!(pow_whole(0.5, 5), 0.03125);
        assert_eq!(lod_alpha(0.3, 1.0), 0.3);
        assert_eq!(lod_alpha(0.3, 0.0), 0.0);
        assert_eq!(lod_alpha(1.0, 3.0), 1.0);
        assert_eq!(lod_alpha(0.0, 3.0), 0.0);
    }

    #[test]
    fn fin_fade_is_a_smoothstep() {
        assert_eq!(lod_fin_fade(0.5, [1.0, 3.0]), 0.0);
        assert_eq!(lod_fin_fade(3.5, [1.0, 3.0]), 1.0);
        assert_eq!(lod_fin_fade(2.0, [1.0, 3.0]), 0.5);
        assert_close(lod_fin_fade(1.5, [1.0, 3.0]), 0.15625, 1e-7, "quarter");
        assert_eq!(lod_fin_fade(2.0, [2.0, 2.0]), 1.0);
        assert_eq!(lod_fin_fade(1.9, [2.0, 2.0]), 0.0);
    }
}
