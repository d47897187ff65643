//! Writes the README's crops of the fins (`docs/fins/*.png`): a region of a scene rendered with
//! the thesis's angle-window fins, with the outline fins (the default) and with no fins, side by
//! side (enlarged by a whole factor, nearest), 4 white pixels apart.
//!
//! `cargo run --release --example fin_crops [OUT_DIR]` (default `docs/fins`).

use std::path::{Path, PathBuf};

use pelage::render::PreparedScene;
use pelage::scene::{FinSelectionSetting, Scene};

/// A crop: the scene, the file written, the region `(x, y, width, height)` in pixels of the
/// scene's image, and its enlargement.
const CROPS: [(&str, &str, [u32; 4], u32); 2] = [
    ("torus", "torus-top-edge.png", [60, 40, 260, 110], 2),
    ("gravity", "gravity-sphere.png", [140, 40, 360, 400], 1),
];
const GAP: u32 = 4;

fn render(scene: &Scene) -> Result<image::RgbaImage, String> {
    let image = PreparedScene::new(scene)
        .and_then(|p| p.render(64))
        .map_err(|e| e.to_string())?;
    image::RgbaImage::from_raw(image.width, image.height, image.rgba8)
        .ok_or_else(|| "the image's size does not match its pixels".to_string())
}

fn crops(out: &Path) -> Result<(), String> {
    let scenes = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    for (name, file, [x, y, w, h], scale) in CROPS {
        let base = Scene::load(&scenes.join(format!("{name}.toml"))).map_err(|e| e.to_string())?;
        let mut windows = base.clone();
        windows.fur.fin_selection = FinSelectionSetting::AngleWindows;
        let mut outline = base.clone();
        outline.fur.fin_selection = FinSelectionSetting::Outline;
        let mut none = base.clone();
        none.fur.fins = false;
        let panels = [windows, outline, none];
        let (pw, ph) = (w * scale, h * scale);
        let width = panels.len() as u32 * pw + (panels.len() as u32 - 1) * GAP;
        let mut sheet = image::RgbaImage::from_pixel(width, ph, image::Rgba([255; 4]));
        for (k, scene) in panels.iter().enumerate() {
            let full = render(scene)?;
            let left = k as u32 * (pw + GAP);
            for py in 0..ph {
                for px in 0..pw {
                    let p = *full.get_pixel(x + px / scale, y + py / scale);
                    sheet.put_pixel(left + px, py, p);
                }
            }
        }
        let rgb = image::DynamicImage::ImageRgba8(sheet).to_rgb8();
        let path = out.join(file);
        rgb.save(&path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

fn main() {
    let out = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("docs/fins"), PathBuf::from);
    if let Err(e) = crops(&out) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
