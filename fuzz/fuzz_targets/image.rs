//! Image bytes → `compare`'s decoding (PNG 8/16-bit, OpenEXR, …), compared with themselves (`pelage::robust::image_bytes`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    pelage::robust::image_bytes(data);
});
