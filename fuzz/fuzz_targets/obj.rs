//! OBJ bytes → line scan, tobj, merge, tangent frames, shell extrusion and fin edges
//! (`pelage::robust::obj_bytes`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    pelage::robust::obj_bytes(data);
});
