//! The fur fragment stage the renderer runs (`shade_fur_quad` and its 8-lane `FurBatch`) against
//! its scalar twin (`shade_fur`, one fragment at a time) where the golden scenes do not look:
//! every debug view (each ends the batch at another step: the tangents and the alpha after the
//! alpha test, the shadow after the shadow's lookups) on the scenes that take the batch's
//! lane-by-lane paths (the burn, the density and length maps, spots, wind, mip levels changing
//! from quad to quad), and odd image sizes, whose edge quads are partly outside the image.

mod common;
use common::scene;

use pelage::render::PreparedScene;
use pelage::scene::{DebugView, Scene};

/// Renders `scene` with both stages and fails where a byte differs.
fn assert_stages_agree(scene: &Scene, what: &str) {
    let prepared = PreparedScene::new(scene).expect("prepares");
    let image = prepared.render(16).expect("renders").rgba8;
    let twin = prepared
        .render_scalar_twin_at(scene.time, 16)
        .expect("renders")
        .rgba8;
    let differing = image
        .chunks(4)
        .zip(twin.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differing, 0, "{what}: {differing} pixels differ");
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
