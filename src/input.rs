//! Opening user input (beside the pipeline). Every file a user names (a scene, an OBJ or MTL, a
//! surface map, an image to compare, a sweep's CSV or point PNG) is opened here, after two checks
//! made before it is opened: it is a regular file (a FIFO would block the open, a device such as
//! `/dev/zero` never end, a folder is no file), and it is no larger than a stated bound. The read
//! itself stops at the bound too, so a file that grows meanwhile cannot make it spend more.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The largest image [`read_image`] decodes, bytes of file: 1 GiB.
pub const MAX_IMAGE_FILE_BYTES: u64 = 1 << 30;

/// The largest text table (a sweep's `results.csv`) read, bytes: 64 MiB.
pub const MAX_TABLE_BYTES: u64 = 64 << 20;

/// An input that cannot be used, naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct InputError {
    /// The file named by the user.
    pub path: PathBuf,
    /// What is wrong with it.
    pub message: String,
}

fn error(path: &Path, message: impl std::fmt::Display) -> InputError {
    InputError {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// Checks that `path` is a regular file of at most `max_bytes` (`what` names it in the
/// message, e.g. "scene"), and returns its size. Nothing is opened.
pub fn check_regular_file(path: &Path, max_bytes: u64, what: &str) -> Result<u64, InputError> {
    let meta =
        std::fs::metadata(path).map_err(|e| error(path, format!("cannot read the {what}: {e}")))?;
    if meta.is_dir() {
        return Err(error(
            path,
            format!("is a folder: not a regular file, so not a {what}"),
        ));
    }
    if !meta.is_file() {
        return Err(error(
            path,
            format!("is not a regular file (a pipe or a device), so it cannot be read as a {what}"),
        ));
    }
    if meta.len() > max_bytes {
        return Err(error(
            path,
            format!(
                "the {what} is {} bytes, more than the limit of {max_bytes}",
                meta.len()
            ),
        ));
    }
    Ok(meta.len())
}

/// Opens `path` for reading after [`check_regular_file`].
pub fn open(path: &Path, max_bytes: u64, what: &str) -> Result<File, InputError> {
    check_regular_file(path, max_bytes, what)?;
    File::open(path).map_err(|e| error(path, format!("cannot read the {what}: {e}")))
}

/// Reads all of `path` after [`check_regular_file`], at most `max_bytes` of it.
pub fn read(path: &Path, max_bytes: u64, what: &str) -> Result<Vec<u8>, InputError> {
    let file = open(path, max_bytes, what)?;
    let mut bytes = Vec::new();
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| error(path, format!("cannot read the {what}: {e}")))?;
    if bytes.len() as u64 > max_bytes {
        return Err(error(
            path,
            format!("the {what} grew past the limit of {max_bytes} bytes while it was read"),
        ));
    }
    Ok(bytes)
}

/// Reads `path` as UTF-8 text, as [`read`] does.
pub fn read_text(path: &Path, max_bytes: u64, what: &str) -> Result<String, InputError> {
    String::from_utf8(read(path, max_bytes, what)?)
        .map_err(|_| error(path, format!("the {what} is not UTF-8 text")))
}

/// Reads an image file (any format the `image` crate reads here) as RGBA8, refusing it from
/// its header, before it is decoded, when a side is 0 or the image is larger than the renderer
/// itself may draw ([`crate::raster::framebuffer::check_size`]).
pub fn read_image(path: &Path, what: &str) -> Result<image::RgbaImage, InputError> {
    decode_image(&read(path, MAX_IMAGE_FILE_BYTES, what)?, path, what)
}

/// [`read_image`] on the file's bytes (`path` names it in errors): the one decoding path of
/// `compare`, the sweep's contact sheet and the fuzz target `image`.
pub fn decode_image(bytes: &[u8], path: &Path, what: &str) -> Result<image::RgbaImage, InputError> {
    let reader = |pixels: (u32, u32)| {
        let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| error(path, format!("cannot read the {what}: {e}")))?;
        reader.limits(decoder_limits(pixels));
        Ok::<_, InputError>(reader)
    };
    let (width, height) = reader((0, 0))?
        .into_dimensions()
        .map_err(|e| error(path, format!("cannot read the {what}: {e}")))?;
    crate::raster::framebuffer::check_size(width, height)
        .map_err(|e| error(path, format!("the {what} is {width}×{height}: {e}")))?;
    let decoded = reader((width, height))?
        .decode()
        .map_err(|e| error(path, format!("cannot read the {what}: {e}")))?;
    // A NaN is never a match: rounded to 0 it would pass as black, so an image holding one is
    // refused rather than compared.
    let nan = match &decoded {
        image::DynamicImage::ImageRgba32F(f) => f.as_raw().iter().filter(|c| c.is_nan()).count(),
        image::DynamicImage::ImageRgb32F(f) => f.as_raw().iter().filter(|c| c.is_nan()).count(),
        _ => 0,
    };
    if nan > 0 {
        return Err(error(
            path,
            format!(
                "the {what} holds {nan} NaN channel values; a NaN is never a match, so it is \
                 not compared"
            ),
        ));
    }
    Ok(to_rgba8(decoded))
}

/// An image of any depth as RGBA8: float images (OpenEXR) are rounded by the framebuffer's own
/// rule ([`crate::raster::framebuffer::quantise_unorm8`]: NaN → 0), so that `pelage render`'s
/// `.exr` reads back as the bytes of its `.png`; 16-bit and 8-bit ones by the `image` crate
/// (`round(v·255 / 65535)`).
pub fn to_rgba8(image: image::DynamicImage) -> image::RgbaImage {
    use crate::raster::framebuffer::quantise_unorm8;
    match image {
        image::DynamicImage::ImageRgba32F(_) | image::DynamicImage::ImageRgb32F(_) => {
            let float = image.into_rgba32f();
            let (w, h) = float.dimensions();
            let bytes = float.as_raw().iter().map(|&c| quantise_unorm8(c)).collect();
            image::RgbaImage::from_raw(w, h, bytes).expect("same size")
        }
        other => other.into_rgba8(),
    }
}

/// What an image decoder may allocate besides the pixels: the ancillary data it keeps (an ICC
/// profile, text chunks). A PNG's compressed `iCCP` chunk can inflate a megabyte into a gigabyte;
/// past this bound the image is refused.
pub const MAX_DECODER_EXTRA_BYTES: u64 = 16 << 20;

/// Decoder limits for an image of `pixels` (width, height; `(0, 0)` while only the header is
/// read): its RGBA f32 pixels, the widest any decoder gives, plus [`MAX_DECODER_EXTRA_BYTES`].
pub fn decoder_limits(pixels: (u32, u32)) -> image::Limits {
    let mut limits = image::Limits::default();
    let pixel_bytes = u64::from(pixels.0) * u64::from(pixels.1) * 16;
    limits.max_alloc = Some(pixel_bytes.saturating_add(MAX_DECODER_EXTRA_BYTES));
    limits
}

/// The width and height of an image file, read from its header without decoding it, and the
/// file's size in bytes; the file is checked as [`read_image`] checks it.
pub fn image_size(path: &Path, what: &str) -> Result<((u32, u32), u64), InputError> {
    let bytes = check_regular_file(path, MAX_IMAGE_FILE_BYTES, what)?;
    let file = open(path, MAX_IMAGE_FILE_BYTES, what)?;
    let mut reader =
        image::ImageReader::new(std::io::BufReader::new(file.take(MAX_IMAGE_FILE_BYTES)))
            .with_guessed_format()
            .map_err(|e| error(path, format!("cannot read the {what}: {e}")))?;
    reader.limits(decoder_limits((0, 0)));
    let size = reader
        .into_dimensions()
        .map_err(|e| error(path, format!("cannot read the {what}: {e}")))?;
    Ok((size, bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_devices_and_oversized_files_are_refused_before_reading() {
        let dir = std::env::temp_dir().join(format!("pelage-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let folder = read(&dir, 10, "scene").unwrap_err();
        assert!(
            folder.message.contains("is a folder: not a regular file"),
            "{folder}"
        );
        let device = read(Path::new("/dev/zero"), 10, "scene").unwrap_err();
        assert!(device.message.contains("not a regular file"), "{device}");
        let file = dir.join("big.txt");
        std::fs::write(&file, "0123456789abc").expect("write");
        let big = read(&file, 10, "table").unwrap_err();
        assert!(big.message.contains("13 bytes"), "{big}");
        assert_eq!(read(&file, 13, "table").expect("fits"), b"0123456789abc");
        assert!(read_text(&file, 13, "table").is_ok());
        let png = dir.join("wide.png");
        image::RgbaImage::new(7, 3).save(&png).expect("write png");
        let ((w, h), bytes) = image_size(&png, "image").expect("header");
        assert_eq!((w, h), (7, 3));
        assert_eq!(bytes, std::fs::metadata(&png).expect("size").len());
        assert!(image_size(&file, "image").is_err());
        let missing = read(&dir.join("none"), 10, "map").unwrap_err();
        assert!(missing.to_string().contains("none"), "{missing}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
