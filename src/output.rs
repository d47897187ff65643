//! Writing results (output stage): every file is written to a temporary sibling and renamed into
//! place, so an error or an interrupt never leaves a truncated PNG that looks complete.

use std::io::Write;
use std::path::{Path, PathBuf};

/// A failed write, naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct OutputError {
    /// The file that could not be written.
    pub path: PathBuf,
    /// Why.
    pub message: String,
}

fn error(path: &Path, message: impl std::fmt::Display) -> OutputError {
    OutputError {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// The longest file name (bytes) an output may have: `NAME_MAX` of the common file systems.
pub const MAX_FILE_NAME_BYTES: usize = 255;

/// How many symbolic links [`write_atomic`] follows before it gives up (Linux's `MAXSYMLINKS`).
const MAX_SYMLINKS: usize = 40;

/// Whether `path` names standard output (`-o -`).
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// The file a write to `path` lands in: symbolic links followed (a relative link from the folder
/// holding it), so that a link is kept and its target replaced. The last target need not exist.
pub fn resolve_output(path: &Path) -> Result<PathBuf, OutputError> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_SYMLINKS {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&current).map_err(|e| error(path, e))?;
                current = if target.is_absolute() {
                    target
                } else {
                    current
                        .parent()
                        .map_or_else(|| target.clone(), |dir| dir.join(&target))
                };
            }
            _ => return Ok(current),
        }
    }
    Err(error(path, "too many levels of symbolic links"))
}

/// Writes `bytes` to `path` so that nothing is left half written and nothing is destroyed:
/// - `-` writes to standard output (a reader that has gone away is not an error);
/// - a symbolic link is followed and its target replaced, the link kept;
/// - an existing path that is not a regular file (a FIFO, `/dev/null`, a terminal) is written
///   through, never replaced; a folder is refused;
/// - otherwise the bytes go to a short-named temporary file in the same folder
///   (`.pelage-PID-N.tmp`, whatever the length of the final name), which is then renamed over
///   the path: an error or an interrupt never leaves a truncated file that looks complete.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    if is_stdout(path) {
        let mut out = std::io::stdout().lock();
        return match out.write_all(bytes).and_then(|()| out.flush()) {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(error(path, e)),
            _ => Ok(()),
        };
    }
    let target = resolve_output(path)?;
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => return Err(error(path, "is a folder")),
        Ok(m) if !m.is_file() => {
            // A device or FIFO: the bytes go through it; renaming over it would replace it.
            let mut file = std::fs::OpenOptions::new()
                .write(true)
                .open(&target)
                .map_err(|e| error(path, e))?;
            return file.write_all(bytes).map_err(|e| error(path, e));
        }
        _ => {}
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if target.file_name().is_none() {
        return Err(error(path, "not a file name"));
    }
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = dir.join(format!(".pelage-{}-{n}.tmp", std::process::id()));
    let result = (|| {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, &target)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        error(path, e)
    })
}

/// Encodes row-major RGBA8 pixels as PNG bytes.
pub fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut bytes);
    image::ImageEncoder::write_image(
        encoder,
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Writes an RGBA8 image as a PNG, atomically.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), OutputError> {
    let bytes = encode_png(width, height, rgba).map_err(|e| error(path, e))?;
    write_atomic(path, &bytes)
}

/// The image files `pelage render -o` writes, chosen by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit RGBA PNG (`.png`, no extension, or `-` for standard output): the reference bytes.
    Png8,
    /// 16-bit RGBA PNG (`.png` with `--depth 16`): the float values rounded to 16 bits.
    Png16,
    /// OpenEXR (`.exr`), 32-bit float RGBA: the framebuffer's values before any rounding.
    Exr,
}

/// Refuses a file name whose extension names another format than the `format` (`"png"`,
/// `"gif"`) a command writes there, so the bytes are always what the name says. A name without
/// an extension, and `-` (standard output), are accepted.
pub fn check_extension(path: &Path, format: &str) -> Result<(), String> {
    match path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
    {
        Some(e) if e != format => Err(format!(
            "{}: this is written as a .{format} file; the name says .{e}",
            path.display()
        )),
        _ => Ok(()),
    }
}

impl ImageFormat {
    /// The format for `path` at `depth` bits per PNG channel (8 or 16): `.png` (any case),
    /// no extension and `-` are PNG, `.exr` is OpenEXR; any other extension is refused, naming
    /// it, as is `depth` 16 for anything but PNG.
    pub fn for_path(path: &Path, depth: u8) -> Result<Self, String> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        let format = match extension.as_deref() {
            None | Some("png") => {
                if depth == 16 {
                    ImageFormat::Png16
                } else {
                    ImageFormat::Png8
                }
            }
            Some("exr") => ImageFormat::Exr,
            Some(other) => {
                return Err(format!(
                    "{}: pelage cannot write .{other} files; it writes .png (8-bit, or 16-bit \
                     with --depth 16) and .exr (32-bit float)",
                    path.display()
                ));
            }
        };
        if depth == 16 && format == ImageFormat::Exr {
            return Err(format!(
                "{}: --depth 16 is for PNG; an .exr file holds 32-bit floats",
                path.display()
            ));
        }
        if depth != 8 && depth != 16 {
            return Err(format!("--depth {depth}: 8 or 16 bits per channel"));
        }
        Ok(format)
    }
}

/// `⌊65535·clamp(c, 0, 1) + 0.5⌋`, NaN → 0: the 16-bit twin of the framebuffer's 8-bit rounding
/// (`quantise_unorm8`).
#[inline]
pub fn quantise_unorm16(c: f32) -> u16 {
    if c.is_nan() {
        return 0;
    }
    (c.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
}

/// Encodes row-major float RGBA (4 values a pixel) as a 16-bit RGBA PNG.
pub fn encode_png16(width: u32, height: u32, rgba: &[f32]) -> Result<Vec<u8>, String> {
    let samples: Vec<u16> = rgba.iter().map(|&c| quantise_unorm16(c)).collect();
    let mut bytes = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut bytes);
    image::ImageEncoder::write_image(
        encoder,
        bytemuck::cast_slice(&samples),
        width,
        height,
        image::ExtendedColorType::Rgba16,
    )
    .map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Encodes row-major float RGBA (4 values a pixel) as OpenEXR, 32-bit float, unchanged.
pub fn encode_exr(width: u32, height: u32, rgba: &[f32]) -> Result<Vec<u8>, String> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    let encoder = image::codecs::openexr::OpenExrEncoder::new(&mut bytes);
    image::ImageEncoder::write_image(
        encoder,
        bytemuck::cast_slice(rgba),
        width,
        height,
        image::ExtendedColorType::Rgba32F,
    )
    .map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}

/// Writes float RGBA as a 16-bit PNG or an OpenEXR file (`format`), atomically. For
/// [`ImageFormat::Png8`] the caller writes the 8-bit bytes with [`write_png`].
pub fn write_float_image(
    path: &Path,
    format: ImageFormat,
    width: u32,
    height: u32,
    rgba: &[f32],
) -> Result<(), OutputError> {
    let bytes = match format {
        ImageFormat::Png16 => encode_png16(width, height, rgba),
        ImageFormat::Exr => encode_exr(width, height, rgba),
        ImageFormat::Png8 => Err("8-bit PNG is written from the 8-bit image".to_string()),
    }
    .map_err(|e| error(path, e))?;
    write_atomic(path, &bytes)
}

/// Writes frames (width, height, RGBA8) as a looping animated GIF at `fps`, atomically. GIF
/// delays are whole hundredths of a second: `round(100 / fps)`, at least 1. Colours are reduced
/// to a 256-colour palette per frame by the `gif` crate's deterministic quantiser.
pub fn write_gif(path: &Path, frames: &[(u32, u32, Vec<u8>)], fps: f32) -> Result<(), OutputError> {
    let mut bytes = Vec::new();
    {
        let mut encoder = image::codecs::gif::GifEncoder::new(&mut bytes);
        encoder
            .set_repeat(image::codecs::gif::Repeat::Infinite)
            .map_err(|e| error(path, e))?;
        let hundredths = (100.0 / fps).round().max(1.0) as u32;
        for (width, height, rgba) in frames {
            let buffer = image::RgbaImage::from_raw(*width, *height, rgba.clone())
                .ok_or_else(|| error(path, "frame size does not match its pixels"))?;
            let delay = image::Delay::from_numer_denom_ms(hundredths * 10, 1);
            encoder
                .encode_frame(image::Frame::from_parts(buffer, 0, 0, delay))
                .map_err(|e| error(path, e))?;
        }
    }
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trips_and_leaves_no_temporary_file() {
        let dir = std::env::temp_dir().join(format!("pelage-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("a.png");
        let pixels: Vec<u8> = (0..4 * 3 * 2).map(|i| i as u8 * 10).collect();
        write_png(&path, 3, 2, &pixels).expect("write");
        let back = image::open(&path).expect("read").to_rgba8();
        assert_eq!(back.as_raw(), &pixels);
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .expect("list")
            .filter_map(Result::ok)
            .collect();
        assert_eq!(leftovers.len(), 1);
        assert!(write_png(&dir.join("missing/b.png"), 3, 2, &pixels).is_err());
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn formats_follow_the_extension_and_unknown_ones_are_named() {
        let f = |p: &str, d| ImageFormat::for_path(Path::new(p), d);
        assert_eq!(f("a.png", 8), Ok(ImageFormat::Png8));
        assert_eq!(f("a.PNG", 16), Ok(ImageFormat::Png16));
        assert_eq!(f("-", 8), Ok(ImageFormat::Png8));
        assert_eq!(f("a", 8), Ok(ImageFormat::Png8));
        assert_eq!(f("a.exr", 8), Ok(ImageFormat::Exr));
        let jpg = f("out.jpg", 8).unwrap_err();
        assert!(
            jpg.contains("out.jpg") && jpg.contains(".jpg files"),
            "{jpg}"
        );
        assert!(f("a.exr", 16).unwrap_err().contains("--depth 16"));
        assert!(f("a.png", 12).is_err());
    }

    #[test]
    fn sixteen_bit_rounding_matches_f64() {
        for i in 0..=4096 {
            let c = i as f32 / 4096.0 * 1.2 - 0.1;
            // In f64, unless 65535·c lies within f32's rounding of a half step (where the
            // f32 product and sum may round up: the same rule as the 8-bit rounding).
            let scaled = f64::from(c).clamp(0.0, 1.0) * 65535.0;
            let expected = (scaled + 0.5).floor();
            let got = f64::from(quantise_unorm16(c));
            if (scaled.fract() - 0.5).abs() > 1e-2 {
                assert_eq!(got, expected, "{c}");
            } else {
                assert!((got - expected).abs() <= 1.0, "{c}");
            }
        }
        assert_eq!(quantise_unorm16(f32::NAN), 0);
        assert_eq!(quantise_unorm16(f32::INFINITY), 65535);
    }

    #[test]
    fn sixteen_bit_png_and_exr_round_trip() {
        let rgba: Vec<f32> = (0..4 * 3 * 2).map(|i| i as f32 / 23.0).collect();
        let png = encode_png16(3, 2, &rgba).expect("png16");
        let back = image::load_from_memory(&png).expect("read").to_rgba16();
        let expected: Vec<u16> = rgba.iter().map(|&c| quantise_unorm16(c)).collect();
        assert_eq!(back.as_raw(), &expected);
        let exr = encode_exr(3, 2, &rgba).expect("exr");
        let back = image::load_from_memory(&exr).expect("read").to_rgba32f();
        assert_eq!(back.as_raw(), &rgba);
    }
}
