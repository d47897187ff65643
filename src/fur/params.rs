//! Fur modelling parameters (thesis 4.1) and their validation (fur bake).
//!
//! Lengths are in *tile units*: the shell texture tile is the periodic unit square
//! `x, y ∈ [0, 1)`, and heights and radii are measured in the same unit (fractions of the tile
//! width). Every parameter is range-checked by [`FurParams::validate`], whose error names it.

use glam::Vec3;
use thiserror::Error;

/// Largest accepted `number_of_strands` and `fin_strands`.
pub const MAX_STRANDS: u32 = 1_000_000;
/// Largest accepted `strand_resolution`, `circle_resolution`, `number_of_shells` and
/// `texture_resolution`.
pub const MAX_RESOLUTION: u32 = 4096;
/// Largest accepted `supersample` factor.
pub const MAX_SUPERSAMPLE: u32 = 8;
/// Largest accepted baking grid side, `texture_resolution · supersample`.
pub const MAX_BAKE_RESOLUTION: u32 = 8192;
/// Largest accepted strand height and thickness, in tile units.
pub const MAX_LENGTH: f32 = 64.0;
/// Largest accepted `slope_deg`.
pub const MAX_SLOPE_DEG: f32 = 85.0;

/// Why a fur parameter was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FurError {
    /// A parameter is out of range or not finite.
    #[error("invalid fur parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter's field name in [`FurParams`] (as in scene files).
        name: &'static str,
        /// What is wrong with its value.
        reason: String,
    },
}

/// The fur modelling parameters. Names follow the thesis (chapter 4.1); `Default` gives its base
/// values where the thesis states them (1000 strands, strand resolution 20, circle resolution 10,
/// 10 shells, 128² texels) and documented choices elsewhere.
#[derive(Debug, Clone, PartialEq)]
pub struct FurParams {
    /// Strands planted in one shell tile (thesis `numberOfStrands`, base 1000).
    pub number_of_strands: u32,
    /// Segments sampling each Bézier strand (thesis `strandResolution`, base 20).
    pub strand_resolution: u32,
    /// Facets around each cone, the "lighting resolution" (thesis `circleResolution`, base 10).
    /// At least 3.
    pub circle_resolution: u32,
    /// Shell layers (thesis `numberOfShells`, base 10).
    pub number_of_shells: u32,
    /// Side of each shell and fin texture in texels (thesis `textureResolution`, base 128).
    pub texture_resolution: u32,
    /// Anti-aliasing factor (thesis 3.1.3): bake at `texture_resolution · supersample` per side,
    /// then box-downsample. 1 disables it.
    pub supersample: u32,
    /// Smallest strand height, tile units.
    pub min_height: f32,
    /// Largest strand height, tile units (before jitter of the tip).
    pub max_height: f32,
    /// How far strands lean from the vertical, degrees (jittered per strand by `jitter`).
    pub slope_deg: f32,
    /// Bend of the near-tip control point along the lean direction, in strand heights
    /// (0: no extra bend; negative bends backwards).
    pub curl: f32,
    /// Relative randomness, 0..1, on the slope and on the tip and both control points
    /// (each coordinate moves by up to `jitter · height`).
    pub jitter: f32,
    /// Cone radius at the root, tile units.
    pub base_thickness: f32,
    /// Cone radius at the tip, tile units.
    pub tip_thickness: f32,
    /// Relative randomness, 0..1, of both radii of a strand (one factor per strand).
    pub thickness_jitter: f32,
    /// Base strand colour, linear RGB in 0..1.
    pub colour: Vec3,
    /// Relative brightness variation, 0..1, per strand.
    pub colour_variation: f32,
    /// σ of the Gaussian layer alpha weight `exp(−(h/H)² / (2σ²))` (Lengyel), `h/H` the
    /// relative height of the layer's middle.
    pub gaussian_sigma: f32,
    /// Strands planted in the fin strip.
    pub fin_strands: u32,
    /// Fin strands are this many times taller than shell strands (thesis 3.1.2.2: at least 1).
    pub fin_height_scale: f32,
    /// Depth of the fin strip (its extent across the view direction), tile units, in (0, 1].
    pub fin_width: f32,
}

impl Default for FurParams {
    fn default() -> Self {
        Self {
            number_of_strands: 1000,
            strand_resolution: 20,
            circle_resolution: 10,
            number_of_shells: 10,
            texture_resolution: 128,
            supersample: 2,
            min_height: 0.6,
            max_height: 1.0,
            slope_deg: 20.0,
            curl: 0.15,
            jitter: 0.1,
            base_thickness: 0.012,
            tip_thickness: 0.003,
            thickness_jitter: 0.25,
            colour: Vec3::new(0.42, 0.26, 0.14),
            colour_variation: 0.15,
            gaussian_sigma: 0.5,
            fin_strands: 60,
            fin_height_scale: 1.5,
            fin_width: 0.05,
        }
    }
}

fn invalid(name: &'static str, reason: impl Into<String>) -> FurError {
    FurError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

fn check_count(name: &'static str, value: u32, min: u32, max: u32) -> Result<(), FurError> {
    if value < min || value > max {
        return Err(invalid(name, format!("{value} is outside {min}..={max}")));
    }
    Ok(())
}

fn check_range(name: &'static str, value: f32, min: f32, max: f32) -> Result<(), FurError> {
    if !value.is_finite() {
        return Err(invalid(name, format!("{value} is not a finite number")));
    }
    if value < min || value > max {
        return Err(invalid(name, format!("{value} is outside {min}..={max}")));
    }
    Ok(())
}

impl FurParams {
    /// Checks every parameter; the error names the first bad one (in field order).
    pub fn validate(&self) -> Result<(), FurError> {
        check_count("number_of_strands", self.number_of_strands, 0, MAX_STRANDS)?;
        check_count(
            "strand_resolution",
            self.strand_resolution,
            1,
            MAX_RESOLUTION,
        )?;
        check_count(
            "circle_resolution",
            self.circle_resolution,
            3,
            MAX_RESOLUTION,
        )?;
        check_count("number_of_shells", self.number_of_shells, 1, MAX_RESOLUTION)?;
        check_count(
            "texture_resolution",
            self.texture_resolution,
            1,
            MAX_RESOLUTION,
        )?;
        check_count("supersample", self.supersample, 1, MAX_SUPERSAMPLE)?;
        if self.texture_resolution * self.supersample > MAX_BAKE_RESOLUTION {
            return Err(invalid(
                "supersample",
                format!(
                    "texture_resolution · supersample = {} exceeds {MAX_BAKE_RESOLUTION}",
                    self.texture_resolution * self.supersample
                ),
            ));
        }
        check_range("min_height", self.min_height, f32::MIN_POSITIVE, MAX_LENGTH)?;
        check_range("max_height", self.max_height, f32::MIN_POSITIVE, MAX_LENGTH)?;
        if self.max_height < self.min_height {
            return Err(invalid(
                "max_height",
                format!(
                    "{} is below min_height {}",
                    self.max_height, self.min_height
                ),
            ));
        }
        check_range("slope_deg", self.slope_deg, 0.0, MAX_SLOPE_DEG)?;
        check_range("curl", self.curl, -4.0, 4.0)?;
        check_range("jitter", self.jitter, 0.0, 1.0)?;
        check_range("base_thickness", self.base_thickness, 0.0, MAX_LENGTH)?;
        check_range("tip_thickness", self.tip_thickness, 0.0, MAX_LENGTH)?;
        check_range("thickness_jitter", self.thickness_jitter, 0.0, 1.0)?;
        for c in self.colour.to_array() {
            check_range("colour", c, 0.0, 1.0)?;
        }
        check_range("colour_variation", self.colour_variation, 0.0, 1.0)?;
        check_range("gaussian_sigma", self.gaussian_sigma, 1e-3, 1e3)?;
        check_count("fin_strands", self.fin_strands, 0, MAX_STRANDS)?;
        check_range("fin_height_scale", self.fin_height_scale, 1e-3, MAX_LENGTH)?;
        check_range("fin_width", self.fin_width, f32::MIN_POSITIVE, 1.0)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name_of(p: &FurParams) -> &'static str {
        match p.validate() {
            Err(FurError::InvalidParameter { name, .. }) => name,
            Ok(()) => "ok",
        }
    }

    #[test]
    fn defaults_are_thesis_base_values_and_valid() {
        let p = FurParams::default();
        assert_eq!(p.validate(), Ok(()));
        assert_eq!(p.number_of_strands, 1000);
        assert_eq!(p.strand_resolution, 20);
        assert_eq!(p.circle_resolution, 10);
        assert_eq!(p.number_of_shells, 10);
        assert_eq!(p.texture_resolution, 128);
    }

    #[test]
    fn errors_name_the_parameter() {
        let d = FurParams::default();
        let cases: Vec<(FurParams, &str)> = vec![
            (
                FurParams {
                    number_of_shells: 0,
                    ..d.clone()
                },
                "number_of_shells",
            ),
            (
                FurParams {
                    texture_resolution: 0,
                    ..d.clone()
                },
                "texture_resolution",
            ),
            (
                FurParams {
                    texture_resolution: 4097,
                    ..d.clone()
                },
                "texture_resolution",
            ),
            (
                FurParams {
                    strand_resolution: 0,
                    ..d.clone()
                },
                "strand_resolution",
            ),
            (
                FurParams {
                    circle_resolution: 2,
                    ..d.clone()
                },
                "circle_resolution",
            ),
            (
                FurParams {
                    number_of_strands: MAX_STRANDS + 1,
                    ..d.clone()
                },
                "number_of_strands",
            ),
            (
                FurParams {
                    supersample: 0,
                    ..d.clone()
                },
                "supersample",
            ),
            (
                FurParams {
                    texture_resolution: 4096,
                    supersample: 4,
                    ..d.clone()
                },
                "supersample",
            ),
            (
                FurParams {
                    min_height: -0.1,
                    ..d.clone()
                },
                "min_height",
            ),
            (
                FurParams {
                    max_height: f32::NAN,
                    ..d.clone()
                },
                "max_height",
            ),
            (
                FurParams {
                    max_height: 0.5,
                    min_height: 0.6,
                    ..d.clone()
                },
                "max_height",
            ),
            (
                FurParams {
                    slope_deg: 90.0,
                    ..d.clone()
                },
                "slope_deg",
            ),
            (
                FurParams {
                    curl: f32::INFINITY,
                    ..d.clone()
                },
                "curl",
            ),
            (
                FurParams {
                    jitter: -0.5,
                    ..d.clone()
                },
                "jitter",
            ),
            (
                FurParams {
                    base_thickness: -0.01,
                    ..d.clone()
                },
                "base_thickness",
            ),
            (
                FurParams {
                    tip_thickness: f32::NAN,
                    ..d.clone()
                },
                "tip_thickness",
            ),
            (
                FurParams {
                    thickness_jitter: 2.0,
                    ..d.clone()
                },
                "thickness_jitter",
            ),
            (
                FurParams {
                    colour: Vec3::new(0.5, f32::NAN, 0.1),
                    ..d.clone()
                },
                "colour",
            ),
            (
                FurParams {
                    colour_variation: 1.5,
                    ..d.clone()
                },
                "colour_variation",
            ),
            (
                FurParams {
                    gaussian_sigma: 0.0,
                    ..d.clone()
                },
                "gaussian_sigma",
            ),
            (
                FurParams {
                    fin_strands: u32::MAX,
                    ..d.clone()
                },
                "fin_strands",
            ),
            (
                FurParams {
                    fin_height_scale: 0.0,
                    ..d.clone()
                },
                "fin_height_scale",
            ),
            (
                FurParams {
                    fin_width: 0.0,
                    ..d.clone()
                },
                "fin_width",
            ),
        ];
        for (p, name) in cases {
            assert_eq!(name_of(&p), name);
            let msg = p
                .validate()
                .map_err(|e| e.to_string())
                .err()
                .unwrap_or_default();
            assert!(msg.contains(name), "message {msg:?} lacks {name}");
        }
    }
}
