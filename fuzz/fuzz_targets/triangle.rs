//! Three clip-space vertices (12 f32, any bits: NaN, infinities, 1e30), a viewport size and a
//! cull mode → clipping, triangle setup, binning and rasterization (`pelage::robust::triangle`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    pelage::robust::triangle_bytes(data);
});
