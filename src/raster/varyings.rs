//! Varyings: the per-vertex values the vertex stage hands to the fragment stage.
//!
//! Invariant: every interpolation the rasterizer performs is a [`Varyings::weighted_sum`] of
//! exactly three values, evaluated as `(a·wa + b·wb) + c·wc` per component, so the same inputs
//! give the same bits whatever the thread count or tile size.

use glam::{Vec2, Vec3, Vec4};

/// Values interpolated across a triangle. Implemented for `()`, `f32`, glam vectors, arrays
/// of `f32` and tuples of up to four varyings; implement it for your own struct by weighting
/// each field.
pub trait Varyings: Copy + Send + Sync {
    /// `a·wa + b·wb + c·wc`, evaluated per component as `(a·wa + b·wb) + c·wc`.
    fn weighted_sum(a: &Self, wa: f32, b: &Self, wb: f32, c: &Self, wc: f32) -> Self;

    /// `a·(1 − t) + b·t`, used by clipping.
    #[inline]
    fn lerp(a: &Self, b: &Self, t: f32) -> Self {
        Self::weighted_sum(a, 1.0 - t, b, t, b, 0.0)
    }

    /// `a − b`, used for screen-space derivatives.
    #[inline]
    fn difference(a: &Self, b: &Self) -> Self {
        Self::weighted_sum(a, 1.0, b, -1.0, b, 0.0)
    }
}

impl Varyings for () {
    #[inline]
    fn weighted_sum(_: &(), _: f32, _: &(), _: f32, _: &(), _: f32) {}
}

impl Varyings for f32 {
    #[inline]
    fn weighted_sum(a: &f32, wa: f32, b: &f32, wb: f32, c: &f32, wc: f32) -> f32 {
        (a * wa + b * wb) + c * wc
    }
}

macro_rules! glam_varyings {
    ($($t:ty),*) => {$(
        impl Varyings for $t {
            #[inline]
            fn weighted_sum(a: &$t, wa: f32, b: &$t, wb: f32, c: &$t, wc: f32) -> $t {
                (*a * wa + *b * wb) + *c * wc
            }
        }
    )*};
}
glam_varyings!(Vec2, Vec3, Vec4);

impl<const N: usize> Varyings for [f32; N] {
    /// A plain loop, which the compiler runs on packed registers (structs of `f32` fields are
    /// interpolated through it).
    #[inline(always)]
    fn weighted_sum(a: &Self, wa: f32, b: &Self, wb: f32, c: &Self, wc: f32) -> Self {
        let mut out = [0.0f32; N];
        for i in 0..N {
            out[i] = (a[i] * wa + b[i] * wb) + c[i] * wc;
        }
        out
    }
}

macro_rules! tuple_varyings {
    ($($name:ident $idx:tt),+) => {
        impl<$($name: Varyings),+> Varyings for ($($name,)+) {
            #[inline]
            fn weighted_sum(a: &Self, wa: f32, b: &Self, wb: f32, c: &Self, wc: f32) -> Self {
                ($($name::weighted_sum(&a.$idx, wa, &b.$idx, wb, &c.$idx, wc),)+)
            }
        }
    };
}
tuple_varyings!(A 0);
tuple_varyings!(A 0, B 1);
tuple_varyings!(A 0, B 1, C 2);
tuple_varyings!(A 0, B 1, C 2, D 3);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_sum_order_is_left_to_right() {
        let (a, b, c) = (1.0e8_f32, -1.0e8_f32, 1.0_f32);
        assert_eq!(f32::weighted_sum(&a, 1.0, &b, 1.0, &c, 1.0), 1.0);
    }

    #[test]
    fn tuples_and_arrays_weight_each_component() {
        let a = (1.0_f32, Vec2::new(2.0, 3.0), [4.0_f32, 5.0]);
        let b = (10.0_f32, Vec2::new(20.0, 30.0), [40.0_f32, 50.0]);
        let m = Varyings::lerp(&a, &b, 0.5);
        assert_eq!(m.0, 5.5);
        assert_eq!(m.1, Vec2::new(11.0, 16.5));
        assert_eq!(m.2, [22.0, 27.5]);
        let d = Varyings::difference(&b, &a);
        assert_eq!(d.1, Vec2::new(18.0, 27.0));
    }
}
