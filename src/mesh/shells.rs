//! Shell geometry (thesis 3.1.4; mesh stage): each shell layer is the mesh pushed out along its
//! vertex normals; the invariant is that offsets start at 0 on the surface and never decrease from
//! one layer to the next.
//!
//! Layer `i` of `N` shells sits at `model_difference · f(i / N)`: layer 0 on the surface, layer
//! `N − 1` at `model_difference · f((N − 1) / N)`, just below `model_difference`. This matches
//! the shell textures, where layer `i` holds the strand slice between heights `i·h/N` and
//! `(i+1)·h/N`: each shell is drawn at the *bottom* of its slab, and the top of the last slab
//! (`i = N`, the fur tips) is at exactly `model_difference`, "the total length of shell
//! textures" (thesis 4.1).

use glam::Vec3;

use super::Mesh;

/// How shells are spaced between the surface and `model_difference`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShellSpacing {
    /// Evenly: `f(x) = x`.
    #[default]
    Uniform,
    /// Denser near the tip, sparser near the root: `f(x) = 1 − (1 − x)²`. Thesis 3.1.4: "if we
    /// are using less amount of textures, we intensify the placing on the top, and increase the
    /// spacing in the bottom". The gap between consecutive shells shrinks linearly towards the
    /// tip (`f'(x) = 2(1 − x)`).
    DenserNearTip,
}

impl ShellSpacing {
    /// The spacing function `f` on `[0, 1]` (input clamped), with `f(0) = 0`, `f(1) = 1`,
    /// non-decreasing.
    pub fn apply(self, x: f32) -> f32 {
        let x = x.clamp(0.0, 1.0);
        match self {
            ShellSpacing::Uniform => x,
            ShellSpacing::DenserNearTip => 1.0 - (1.0 - x) * (1.0 - x),
        }
    }
}

/// Distance layer `layer` of `number_of_shells` is pushed out along the vertex normal:
/// `model_difference · f(layer / number_of_shells)` (see the module docs). `layer` is clamped to
/// `number_of_shells` (which gives the fur tips, `model_difference`); with no shells the offset
/// is 0.
pub fn shell_offset(
    layer: u32,
    number_of_shells: u32,
    model_difference: f32,
    spacing: ShellSpacing,
) -> f32 {
    if number_of_shells == 0 {
        return 0.0;
    }
    let x = layer.min(number_of_shells) as f32 / number_of_shells as f32;
    model_difference * spacing.apply(x)
}

/// Every vertex position pushed `offset` along its vertex normal (one whole shell). Normals are
/// welded by position, so vertices duplicated at seams move together and the shell stays
/// closed.
pub fn extrude(mesh: &Mesh, offset: f32) -> Vec<Vec3> {
    mesh.vertices
        .iter()
        .map(|v| v.position + v.normal * offset)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::procedural::torus;

    #[test]
    fn offsets_monotonic_and_bounded() {
        for spacing in [ShellSpacing::Uniform, ShellSpacing::DenserNearTip] {
            for n in [1, 2, 3, 10, 50, 100] {
                assert_eq!(shell_offset(0, n, 1.5, spacing), 0.0);
                let mut last = -1.0;
                let mut gaps = Vec::new();
                for i in 0..n {
                    let o = shell_offset(i, n, 1.5, spacing);
                    assert!(o > last && o < 1.5, "{spacing:?} {i}/{n}: {o}");
                    gaps.push(o - last.max(0.0));
                    last = o;
                }
                assert_eq!(shell_offset(n, n, 1.5, spacing), 1.5);
                assert_eq!(shell_offset(n + 7, n, 1.5, spacing), 1.5);
                if spacing == ShellSpacing::DenserNearTip && n > 2 {
                    // Gaps shrink towards the tip.
                    assert!(gaps[1..].windows(2).all(|w| w[1] < w[0]), "{gaps:?}");
                }
            }
        }
        assert_eq!(shell_offset(3, 0, 1.0, ShellSpacing::Uniform), 0.0);
        assert_eq!(shell_offset(5, 10, 1.0, ShellSpacing::Uniform), 0.5);
        assert_eq!(shell_offset(5, 10, 1.0, ShellSpacing::DenserNearTip), 0.75);
    }

    #[test]
    fn extrude_torus_keeps_seams_closed() {
        let mesh = torus(1.0, 0.4, 500);
        let shell = extrude(&mesh, 0.1);
        for (v, q) in mesh.vertices.iter().zip(&shell) {
            let core = Vec3::new(v.position.x, 0.0, v.position.z).normalize();
            assert!(((*q - core).length() - 0.5).abs() < 2e-3);
        }
        for (i, a) in mesh.vertices.iter().enumerate() {
            for (j, b) in mesh.vertices.iter().enumerate().skip(i + 1) {
                if a.position == b.position {
                    assert_eq!(shell[i], shell[j]);
                }
            }
        }
    }
}
