//! Surface maps (length, density, direction, colour; render stage): PNG images in mesh uv space,
//! loaded once and sampled by the vertex and fragment stages.
//!
//! Sampling convention (a GPU port must match it): the map's 8-bit texels `c` read as `c/255`;
//! texel `(i, j)` has its centre at `u = (i + ½)/width`, `v = (j + ½)/height` (row 0 at
//! `v = 0`, the image's first row); a sample is bilinear between the four nearest texel centres
//! with the rasterizer's own bilinear filter ([`Sampler`], level 0, no mips), addressed per axis
//! by `[maps] address` (clamp: coordinates stop at the edge texels; wrap: the map repeats).
//! At a texel centre the sample is that texel exactly.

use crate::raster::{AddressMode, Filter, Sampler, Texture};
use crate::scene::{MapAddressSetting, MapSettings};
use glam::{Vec2, Vec4};
use std::path::{Path, PathBuf};

/// Largest map side accepted, texels (a map is sampled per vertex and per fragment; finer
/// than the screen buys nothing).
pub const MAX_MAP_SIDE: u32 = 4096;

/// A map that could not be loaded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key} = {path}: {message}")]
pub struct MapError {
    /// The scene key (`maps.length`).
    pub key: String,
    /// The file, as resolved.
    pub path: String,
    /// What is wrong.
    pub message: String,
}

/// The scene's maps, loaded.
#[derive(Clone, Debug)]
pub struct SurfaceMaps {
    /// Fur length, red channel.
    pub length: Option<Texture>,
    /// Fraction of strands kept, red channel.
    pub density: Option<Texture>,
    /// Combing direction, red and green.
    pub direction: Option<Texture>,
    /// Strand colour multiplier, RGB.
    pub colour: Option<Texture>,
    sampler: Sampler,
}

fn address(setting: MapAddressSetting) -> AddressMode {
    match setting {
        MapAddressSetting::Clamp => AddressMode::Clamp,
        MapAddressSetting::Wrap => AddressMode::Wrap,
    }
}

/// The most texels [`SurfaceMaps::red_is_zero_over`] reads for one triangle (64×64).
const BARE_CHECK_TEXELS: usize = 4096;

/// Reads a PNG map, checking its size from the header before decoding.
fn load_png(key: &str, path: &Path) -> Result<Texture, MapError> {
    // A regular file of bounded size (a FIFO or device would hang or never end the read).
    let bytes =
        crate::input::read(path, crate::input::MAX_IMAGE_FILE_BYTES, "map").map_err(|e| {
            MapError {
                key: key.to_string(),
                path: path.display().to_string(),
                message: e.message,
            }
        })?;
    decode_png_map(key, path, &bytes)
}

/// A PNG map's bytes (read from `path`, the scene key `key`) as a texture: the format and the
/// size are checked from the header before anything is decoded. (The fuzz target `map`.)
pub fn decode_png_map(key: &str, path: &Path, bytes: &[u8]) -> Result<Texture, MapError> {
    let fail = |message: String| MapError {
        key: key.to_string(),
        path: path.display().to_string(),
        message,
    };
    let reader = |pixels: (u32, u32)| {
        let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| fail(format!("cannot read the map: {e}")))?;
        reader.limits(crate::input::decoder_limits(pixels));
        Ok::<_, MapError>(reader)
    };
    let checked = reader((0, 0))?;
    if checked.format() != Some(image::ImageFormat::Png) {
        return Err(fail("not a PNG file".into()));
    }
    let (width, height) = checked
        .into_dimensions()
        .map_err(|e| fail(format!("not a readable PNG: {e}")))?;
    if width == 0 || height == 0 || width > MAX_MAP_SIDE || height > MAX_MAP_SIDE {
        return Err(fail(format!(
            "the map is {width}×{height}; each side must be 1..={MAX_MAP_SIDE}"
        )));
    }
    let image = reader((width, height))?
        .decode()
        .map_err(|e| fail(format!("not a readable PNG: {e}")))?
        .to_rgba8();
    let texels = image.pixels().map(|p| p.0).collect();
    Texture::from_rgba8(width, height, texels).map_err(|e| fail(e.to_string()))
}

impl SurfaceMaps {
    /// Loads the maps named in `settings`, paths relative to `base_dir`.
    pub fn load(settings: &MapSettings, base_dir: &Path) -> Result<SurfaceMaps, MapError> {
        let load = |key: &str, path: &Option<PathBuf>| -> Result<Option<Texture>, MapError> {
            path.as_ref()
                .map(|p| load_png(key, &base_dir.join(p)))
                .transpose()
        };
        Ok(SurfaceMaps {
            length: load("maps.length", &settings.length)?,
            density: load("maps.density", &settings.density)?,
            direction: load("maps.direction", &settings.direction)?,
            colour: load("maps.colour", &settings.colour)?,
            sampler: Sampler {
                address_u: address(settings.address[0]),
                address_v: address(settings.address[1]),
                filter: Filter::Bilinear,
            },
        })
    }

    /// No maps at all (the thesis's uniform fur).
    pub fn none() -> SurfaceMaps {
        SurfaceMaps {
            length: None,
            density: None,
            direction: None,
            colour: None,
            sampler: Sampler {
                address_u: AddressMode::Clamp,
                address_v: AddressMode::Clamp,
                filter: Filter::Bilinear,
            },
        }
    }

    /// Whether [`SurfaceMaps::sample`] of `map` reads red 0 everywhere on a triangle with mesh
    /// uvs `uvs`: every texel of level 0 within two texels (and the uvs' rounding) of the uvs'
    /// bounding box, through this sampler's addressing, has red 0. A bilinear sample is a
    /// weighted sum of four such texels, so it is then exactly 0, and so are the samples of
    /// every point interpolated inside the triangle. `false` for uvs that are not finite or
    /// not small enough for the bound to hold, and for a reach of more than 64×64 texels.
    pub fn red_is_zero_over(&self, map: &Texture, uvs: [Vec2; 3]) -> bool {
        let Some(level) = map.level(0) else {
            return false;
        };
        let (lo, hi) = (
            uvs[0].min(uvs[1]).min(uvs[2]),
            uvs[0].max(uvs[1]).max(uvs[2]),
        );
        // Texel columns (rows) a sample at u reads: ⌊u·W − ½⌋ and the next (bilinear), ⌊u·W⌋
        // (nearest). Two texels of margin, more where the uvs are large enough that their
        // interpolation's rounding (a few ulps) reaches a texel.
        let range = |lo: f32, hi: f32, size: u32| -> Option<(i64, i64)> {
            let size_f = size as f32;
            let (a, b) = (lo * size_f, hi * size_f);
            if !(a.is_finite() && b.is_finite()) || a.abs().max(b.abs()) > (1u32 << 24) as f32 {
                return None;
            }
            let margin = 2.0 + (a.abs().max(b.abs()) * 1.0e-5).floor();
            Some(((a - margin).floor() as i64, (b + margin).floor() as i64))
        };
        let (Some((x0, x1)), Some((y0, y1))) = (
            range(lo.x, hi.x, level.width()),
            range(lo.y, hi.y, level.height()),
        ) else {
            return false;
        };
        let (width, height) = (i64::from(level.width()), i64::from(level.height()));
        let columns = |from: i64, to: i64, size: i64, mode: AddressMode| -> Vec<usize> {
            match mode {
                AddressMode::Clamp => (from.clamp(0, size - 1)..=to.clamp(0, size - 1))
                    .map(|i| i as usize)
                    .collect(),
                AddressMode::Wrap if to - from + 1 >= size => (0..size as usize).collect(),
                AddressMode::Wrap => (from..=to)
                    .map(|i| crate::raster::texture::address(i, size as u32, mode) as usize)
                    .collect(),
            }
        };
        let xs = columns(x0, x1, width, self.sampler.address_u);
        let ys = columns(y0, y1, height, self.sampler.address_v);
        // A bounded cost a triangle (a model of many large triangles over a map that is 0
        // almost everywhere would read the whole map for each): larger reaches are not
        // checked, and their triangles are drawn.
        if xs.len() * ys.len() > BARE_CHECK_TEXELS {
            return false;
        }
        let texels = level.texels();
        ys.iter().all(|&y| {
            xs.iter().all(|&x| {
                texels
                    .get(y * width as usize + x)
                    .is_some_and(|t| t[0] == 0)
            })
        })
    }

    /// A bilinear sample of `map` at mesh uv `uv` (see the module's convention).
    #[inline]
    pub fn sample(&self, map: &Texture, uv: Vec2) -> Vec4 {
        self.sampler.sample_level(map, uv, 0.0)
    }

    /// The fur length at `uv` (red channel, 0..1); 1 without a length map.
    #[inline]
    pub fn length_at(&self, uv: Vec2) -> f32 {
        self.length.as_ref().map_or(1.0, |m| self.sample(m, uv).x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: u32, height: u32, texels: &[u8], address: MapAddressSetting) -> SurfaceMaps {
        let texture = Texture::from_rgba8(
            width,
            height,
            texels.iter().map(|&r| [r, 0, 0, 255]).collect(),
        )
        .expect("texture");
        SurfaceMaps {
            length: Some(texture),
            sampler: Sampler {
                address_u: super::address(address),
                address_v: super::address(address),
                filter: Filter::Bilinear,
            },
            ..SurfaceMaps::none()
        }
    }

    #[test]
    fn texel_centres_give_the_texel_and_midpoints_the_mean() {
        let m = map(
            4,
            2,
            &[0, 51, 102, 255, 10, 20, 30, 40],
            MapAddressSetting::Clamp,
        );
        for (i, expected) in [0u8, 51, 102, 255].iter().enumerate() {
            let uv = Vec2::new((i as f32 + 0.5) / 4.0, 0.25);
            assert_eq!(m.length_at(uv), f32::from(*expected) / 255.0, "texel {i}");
        }
        assert_eq!(m.length_at(Vec2::new(0.625, 0.75)), 30.0 / 255.0);
        // Halfway between texel centres 1 and 2 of row 0 (u = 0.5): their mean, to f32
        // rounding; halfway between the rows too: the mean of four.
        let mid = m.length_at(Vec2::new(0.5, 0.25));
        assert!((f64::from(mid) - (51.0 + 102.0) / 2.0 / 255.0).abs() < 1e-6);
        let four = m.length_at(Vec2::new(0.5, 0.5));
        assert!((f64::from(four) - (51.0 + 102.0 + 20.0 + 30.0) / 4.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn edges_clamp_or_wrap() {
        let clamp = map(4, 1, &[0, 51, 102, 255], MapAddressSetting::Clamp);
        // Outside the first and last texel centres a clamped map holds the edge texel.
        assert_eq!(clamp.length_at(Vec2::new(0.0, 0.5)), 0.0);
        assert_eq!(clamp.length_at(Vec2::new(-3.0, 0.5)), 0.0);
        assert_eq!(clamp.length_at(Vec2::new(1.0, 0.5)), 1.0);
        assert_eq!(clamp.length_at(Vec2::new(7.0, 0.5)), 1.0);
        let wrap = map(4, 1, &[0, 51, 102, 255], MapAddressSetting::Wrap);
        // A wrapped map blends the last and first texels across u = 0 (and u = 1).
        let seam = f64::from(wrap.length_at(Vec2::new(0.0, 0.5)));
        assert!((seam - 255.0 / 2.0 / 255.0).abs() < 1e-6, "{seam}");
        assert_eq!(
            wrap.length_at(Vec2::new(1.0, 0.5)),
            wrap.length_at(Vec2::new(0.0, 0.5))
        );
        assert_eq!(wrap.length_at(Vec2::new(2.125, 0.5)), 0.0);
    }

    #[test]
    fn missing_and_foreign_files_are_named() {
        let dir = std::env::temp_dir().join(format!("pelage-maps-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(dir.join("text.png"), "not a png").expect("write");
        let settings = MapSettings {
            density: Some(PathBuf::from("text.png")),
            ..MapSettings::default()
        };
        let e = SurfaceMaps::load(&settings, &dir).expect_err("not a PNG");
        assert_eq!(e.key, "maps.density");
        assert!(e.path.ends_with("text.png"), "{e}");
        let settings = MapSettings {
            colour: Some(PathBuf::from("absent.png")),
            ..MapSettings::default()
        };
        let e = SurfaceMaps::load(&settings, &dir).expect_err("missing");
        assert!(e.to_string().starts_with("maps.colour = "), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
