//! PNG bytes → a scene's surface map, decoded and sampled (`pelage::robust::map_bytes`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    pelage::robust::map_bytes(data);
});
