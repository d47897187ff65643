//! Scene text → parser, validation, resource estimates (`pelage::robust::scene_text`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        pelage::robust::scene_text(text);
    }
});
