//! Three clip-space vertices (12 f32, any bits: NaN, infinities, 1e30), a viewport size and a
//! cull mode → clipping, triangle setup, binning and rasterization (`pelage::robust::triangle`).
#![no_main]
use glam::Vec4;
use libfuzzer_sys::fuzz_target;
use pelage::raster::CullMode;

fuzz_target!(|data: &[u8]| {
    if data.len() < 53 {
        return;
    }
    let f = |i: usize| {
        f32::from_le_bytes([
            data[4 * i],
            data[4 * i + 1],
            data[4 * i + 2],
            data[4 * i + 3],
        ])
    };
    let v = |k: usize| Vec4::new(f(4 * k), f(4 * k + 1), f(4 * k + 2), f(4 * k + 3));
    let width = u32::from(u16::from_le_bytes([data[48], data[49]]));
    let height = u32::from(u16::from_le_bytes([data[50], data[51]]));
    let cull = match data[52] % 3 {
        0 => CullMode::None,
        1 => CullMode::Back,
        _ => CullMode::Front,
    };
    pelage::robust::triangle([v(0), v(1), v(2)], width, height, cull);
});
