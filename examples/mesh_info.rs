//! Prints a procedural mesh's bounding box and mean tile size: a helper for writing scenes.
fn main() {
    let kind = std::env::args().nth(1).unwrap_or_else(|| "leg".into());
    let mesh = match kind.as_str() {
        "torus" => pelage::mesh::torus(6.0, 2.4, 500),
        "sphere" => pelage::mesh::sphere(2.0, 500),
        "cylinder" => pelage::mesh::cylinder(2.0, 4.0, 500),
        _ => pelage::mesh::leg(1200),
    };
    let (mut lo, mut hi) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
    let (mut du, mut dv) = (0.0f32, 0.0f32);
    for v in &mesh.vertices {
        lo = lo.min(v.position);
        hi = hi.max(v.position);
        du += v.dpdu.length();
        dv += v.dpdv.length();
    }
    let n = mesh.vertices.len() as f32;
    println!(
        "{kind}: {} triangles, bbox {lo} .. {hi}, mean |dp/du| {}, |dp/dv| {}",
        mesh.indices.len(),
        du / n,
        dv / n
    );
}
