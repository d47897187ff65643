//! The fur fragment stage the renderer runs (`shade_fur_quad` and its `FurBatch`, 32 lanes at
//! AVX2, 16 at AVX-512, 8 on the baseline) against
//! its scalar twin (`shade_fur`, one fragment at a time) where the golden scenes do not look:
//! every debug view (each ends the batch at another step: the tangents and the alpha after the
//! alpha test, the shadow after the shadow's lookups) on the scenes that take the batch's
//! lane-by-lane paths (the burn, the density and length maps, spots, wind, mip levels changing
//! from quad to quad), and odd image sizes, whose edge quads are partly outside the image.

mod common;
use common::{render_checking_twin, scene};

use pelage::scene::{DebugView, Scene};

/// Renders `scene` with both stages and fails where a byte differs.
fn assert_stages_agree(scene: &Scene, what: &str) {
    let image = render_checking_twin(scene, 16, what);
    // A view that draws nothing would agree trivially.
    assert!(
        image.chunks(4).any(|p| p != &image[..4]),
        "{what}: a uniform image"
    );
}

#[test]
fn every_debug_view_gives_the_same_bytes_with_both_stages() {
    let scenes = [
        "burn",
        "density",
        "painted-length",
        "spots",
        "wind",
        "distance",
    ];
    for name in scenes {
        for view in [
            DebugView::None,
            DebugView::Tangents,
            DebugView::Alpha,
            DebugView::Shadow,
        ] {
            let mut s = scene(name, 150, 91);
            s.shading.debug_view = view;
            assert_stages_agree(&s, &format!("{name} in the {view:?} view"));
        }
    }
}
