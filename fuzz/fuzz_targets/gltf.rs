//! glTF and GLB bytes → the checked loader (accessors, skins, clips, images), then the model
//! posed at rest and at a few instants of every clip (`pelage::robust::gltf_bytes`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    pelage::robust::gltf_bytes(data);
});
