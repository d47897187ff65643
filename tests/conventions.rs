//! The four places where pelage's default departs from the thesis, or follows it, each chosen
//! by a scene key (README, "Where pelage departs from the thesis"): the other choice changes the
//! image, and with every choice the quad fragment stage and its scalar twin give the same bytes;
//! so does the lighting equation of thesis 3.2.3 (`lighting = "eq-3.5"` and its exponent).

mod common;
use common::scene;

use pelage::scene::{
    AmbientTermSetting, LightingSetting, Scene, ShadowTexelSetting, SpecularLobesSetting,
    StripeKind, StripeSettings,
};

/// The image, after checking that the scalar twin of the fragment stage gives the same bytes.
fn render(scene: &Scene) -> Vec<u8> {
    common::render_checking_twin(scene, 64, "convention")
}

/// A small torus with three specular tangents and one stripe of `kind`.
fn base(kind: StripeKind) -> Scene {
    let mut s = scene("torus", 128, 96);
    s.shading.specular_tangents = 3;
    s.stripes = vec![StripeSettings {
        kind,
        ..StripeSettings::default()
    }];
    s
}

#[test]
fn each_convention_key_changes_the_image_and_both_stages_agree() {
    let defaults = base(StripeKind::default());
    let reference = render(&defaults);
    let mut variants: Vec<(&str, Scene)> = Vec::new();
    let mut s = defaults.clone();
    s.shading.specular_lobes = SpecularLobesSetting::Sum;
    variants.push(("specular_lobes = sum", s));
    let mut s = defaults.clone();
    s.shading.ambient_term = AmbientTermSetting::Constant;
    variants.push(("ambient_term = constant", s));
    let mut s = defaults.clone();
    s.shading.shadow_texel = ShadowTexelSetting::Opaque;
    variants.push(("shadow_texel = opaque", s));
    variants.push(("stripes kind = axis", base(StripeKind::Axis)));
    // Eq. 3.5 (the lighting model, not a departure): its last term in place of the dampened
    // specular, at the default n = 1 and at another n.
    let mut s = defaults.clone();
    s.shading.lighting = LightingSetting::Eq35;
    variants.push(("lighting = eq-3.5", s.clone()));
    let eq35 = render(&s);
    s.shading.specular1_exponent = 4.0;
    assert!(render(&s) != eq35, "specular1_exponent changed nothing");
    for (what, s) in &variants {
        assert!(render(s) != reference, "{what} changed nothing");
    }
}

#[test]
fn the_defaults_are_the_documented_ones() {
    let s = Scene::parse("", "empty.toml", std::path::Path::new(".")).expect("parses");
    assert_eq!(s.shading.specular_lobes, SpecularLobesSetting::Average);
    assert_eq!(s.shading.ambient_term, AmbientTermSetting::Strand);
    assert_eq!(s.shading.shadow_texel, ShadowTexelSetting::Alpha);
    assert_eq!(s.shading.lighting, LightingSetting::Eq36);
    assert_eq!(s.shading.specular1_exponent, 1.0);
    assert_eq!(StripeSettings::default().kind, StripeKind::Light);
}

#[test]
fn thesis_choices_brighten_and_darken_as_they_should() {
    // The sum of three lobes is at least their mean; a count of opaque lookups at least the sum
    // of their alphas. Compare the mean brightness of the whole frame.
    let mean = |s: &Scene| {
        let image = render(s);
        image.iter().map(|&b| f64::from(b)).sum::<f64>() / image.len() as f64
    };
    let defaults = base(StripeKind::Light);
    let m = mean(&defaults);
    let mut sum = defaults.clone();
    sum.shading.specular_lobes = SpecularLobesSetting::Sum;
    assert!(mean(&sum) > m);
    let mut opaque = defaults.clone();
    opaque.shading.shadow_texel = ShadowTexelSetting::Opaque;
    assert!(mean(&opaque) < m);
}
