//! Writes `scenes/meshes/tail/tail.gltf`, the generated bending-tail rig of
//! `pelage::mesh::rig` (a skinned cylinder on a chain of four joints, three clips), which
//! `scenes/tail.toml` and the character tests use: `cargo run --example tail_rig`.
//! `tests/characters.rs` checks that the committed file is this program's output.

fn main() -> std::io::Result<()> {
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/tail");
    std::fs::create_dir_all(&folder)?;
    let path = folder.join("tail.gltf");
    std::fs::write(&path, pelage::mesh::rig::TailRig::default().to_gltf())?;
    println!("wrote {}", path.display());
    Ok(())
}
