//! Writing results: every file is written to a temporary sibling and renamed into place, so an
//! error or an interrupt never leaves a truncated PNG that looks complete.

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

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| error(path, "not a file name"))?;
    let tmp = dir.join(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
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
}
