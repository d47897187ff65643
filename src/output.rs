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
