//! Meshes: procedural torus, sphere and cylinder, OBJ loading, tangent frames (thesis
//! eq. 3.1–3.3), shell extrusion and fin edges.

pub mod frame;
