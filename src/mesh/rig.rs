//! A generated test rig (mesh stage): a bending tail, an open cylinder skinned to a chain of
//! joints, written as a self-contained glTF 2.0 file (its buffer a data URI), for the skinning
//! tests and `scenes/tail.toml`.
//!
//! The tail is `length` long along +y with `radius`, `rings` rings of `sides + 1` vertices (the
//! seam duplicated, u around, v along). Joint `k` of `joints` sits at `y = k·length/(joints − 1)`,
//! each the child of the one before; a vertex at height `y` is weighted between its two nearest
//! joints linearly. Three clips drive the chain, one per interpolation: `"Wag"` (LINEAR
//! rotations about z, and a LINEAR translation of the root), `"Curl"` (CUBICSPLINE rotations
//! about x with non-zero tangents), `"Pulse"` (STEP non-uniform scales of the middle joint).

use serde_json::json;

use super::gltf::decode_base64;

/// The rig's shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TailRig {
    /// Length along +y.
    pub length: f32,
    /// Radius.
    pub radius: f32,
    /// Rings along the length (at least 2).
    pub rings: u32,
    /// Vertices around (at least 3; one more is the seam).
    pub sides: u32,
    /// Joints in the chain (at least 2).
    pub joints: u32,
}

impl Default for TailRig {
    fn default() -> Self {
        TailRig {
            length: 4.0,
            radius: 0.35,
            rings: 17,
            sides: 16,
            joints: 4,
        }
    }
}

fn push_f32(bytes: &mut Vec<u8>, values: &[f32]) {
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
}

/// Standard base64 with padding.
pub fn encode_base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    debug_assert_eq!(decode_base64(&out).as_deref(), Some(bytes));
    out
}

impl TailRig {
    /// The glTF JSON text of the rig (see the module docs).
    pub fn to_gltf(&self) -> String {
        let (rings, sides, joints) = (self.rings.max(2), self.sides.max(3), self.joints.max(2));
        let spacing = self.length / (joints - 1) as f32;
        let mut bin = Vec::new();
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        // Appends a buffer view and an accessor over it; returns the accessor's index.
        let mut add = |bin: &mut Vec<u8>,
                       data: Vec<u8>,
                       count: usize,
                       ty: &str,
                       component: u32,
                       extra: serde_json::Value| {
            let offset = bin.len();
            bin.extend_from_slice(&data);
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len()}));
            let mut accessor = json!({
                "bufferView": views.len() - 1,
                "componentType": component,
                "count": count,
                "type": ty,
            });
            if let (Some(a), Some(e)) = (accessor.as_object_mut(), extra.as_object()) {
                a.extend(e.clone());
            }
            accessors.push(accessor);
            accessors.len() - 1
        };
        const FLOAT: u32 = 5126;
        let (mut positions, mut uvs, mut joint_ids, mut weights) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for r in 0..rings {
            let v = r as f32 / (rings - 1) as f32;
            let y = v * self.length;
            let below = ((y / spacing) as u32).min(joints - 2);
            let t = (y - below as f32 * spacing) / spacing;
            for s in 0..=sides {
                let u = s as f32 / sides as f32;
                let angle = std::f32::consts::TAU * (s % sides) as f32 / sides as f32;
                // Counter-clockwise seen from outside: around −y·… so (p1 − p0) × (p2 − p0) is outward.
                positions.extend_from_slice(&[
                    self.radius * libm::sinf(angle),
                    y,
                    self.radius * libm::cosf(angle),
                ]);
                uvs.extend_from_slice(&[u, 1.0 - v]);
                joint_ids.extend_from_slice(&[below as u16, below as u16 + 1, 0, 0]);
                weights.extend_from_slice(&[1.0 - t, t, 0.0, 0.0]);
            }
        }
        let count = positions.len() / 3;
        let mut indices: Vec<u16> = Vec::new();
        let row = sides + 1;
        for r in 0..rings - 1 {
            for s in 0..sides {
                let a = (r * row + s) as u16;
                let b = a + 1;
                let c = a + row as u16;
                let d = c + 1;
                indices.extend_from_slice(&[a, b, d, a, d, c]);
            }
        }
        let (lo, hi) = (
            [-self.radius, 0.0, -self.radius],
            [self.radius, self.length, self.radius],
        );
        let mut data = Vec::new();
        push_f32(&mut data, &positions);
        let position = add(
            &mut bin,
            data,
            count,
            "VEC3",
            FLOAT,
            json!({"min": lo, "max": hi}),
        );
        let mut data = Vec::new();
        push_f32(&mut data, &uvs);
        let uv = add(&mut bin, data, count, "VEC2", FLOAT, json!({}));
        let data = joint_ids.iter().flat_map(|j| j.to_le_bytes()).collect();
        let joint = add(&mut bin, data, count, "VEC4", 5123, json!({}));
        let mut data = Vec::new();
        push_f32(&mut data, &weights);
        let weight = add(&mut bin, data, count, "VEC4", FLOAT, json!({}));
        let data = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let index = add(&mut bin, data, indices.len(), "SCALAR", 5123, json!({}));
        let mut data = Vec::new();
        for k in 0..joints {
            let y = -(k as f32) * spacing;
            push_f32(
                &mut data,
                &[
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, y, 0.0, 1.0,
                ],
            );
        }
        let inverse_binds = add(&mut bin, data, joints as usize, "MAT4", FLOAT, json!({}));

        // Clips. Keys at 0, 0.5, 1, 1.5, 2 s.
        let times = [0.0f32, 0.5, 1.0, 1.5, 2.0];
        let mut data = Vec::new();
        push_f32(&mut data, &times);
        let input = add(
            &mut bin,
            data,
            times.len(),
            "SCALAR",
            FLOAT,
            json!({"min": [0.0], "max": [2.0]}),
        );
        let quat = |axis: usize, angle: f32| {
            let mut q = [0.0f32, 0.0, 0.0, libm::cosf(angle / 2.0)];
            q[axis] = libm::sinf(angle / 2.0);
            q
        };
        let wag = [0.0f32, 0.5, 0.0, -0.5, 0.0];
        let node_of = |k: u32| 1 + k as usize;
        let mut wag_channels = Vec::new();
        let mut wag_samplers = Vec::new();
        for k in 1..joints {
            let mut data = Vec::new();
            for a in wag {
                push_f32(&mut data, &quat(2, a * (1.0 + 0.2 * k as f32)));
            }
            let out = add(&mut bin, data, times.len(), "VEC4", FLOAT, json!({}));
            wag_samplers.push(json!({"input": input, "output": out, "interpolation": "LINEAR"}));
            wag_channels.push(json!({"sampler": wag_samplers.len() - 1, "target": {"node": node_of(k), "path": "rotation"}}));
        }
        let mut data = Vec::new();
        for x in [0.0f32, 0.2, 0.0, -0.2, 0.0] {
            push_f32(&mut data, &[x, 0.0, 0.1 * x]);
        }
        let out = add(&mut bin, data, times.len(), "VEC3", FLOAT, json!({}));
        wag_samplers.push(json!({"input": input, "output": out, "interpolation": "LINEAR"}));
        wag_channels.push(json!({"sampler": wag_samplers.len() - 1, "target": {"node": node_of(0), "path": "translation"}}));

        let mut curl_channels = Vec::new();
        let mut curl_samplers = Vec::new();
        for k in 1..joints {
            let mut data = Vec::new();
            for (i, _) in times.iter().enumerate() {
                let angle = 0.6 * libm::sinf(std::f32::consts::PI * i as f32 / 2.0);
                let tangent = 0.3 * libm::cosf(std::f32::consts::PI * i as f32 / 2.0);
                let mut t = [0.0f32; 4];
                t[0] = tangent;
                push_f32(&mut data, &t);
                push_f32(&mut data, &quat(0, angle));
                push_f32(&mut data, &t);
            }
            let out = add(&mut bin, data, times.len() * 3, "VEC4", FLOAT, json!({}));
            curl_samplers
                .push(json!({"input": input, "output": out, "interpolation": "CUBICSPLINE"}));
            curl_channels.push(json!({"sampler": curl_samplers.len() - 1, "target": {"node": node_of(k), "path": "rotation"}}));
        }

        let mut data = Vec::new();
        for s in [1.0f32, 1.4, 0.8, 1.2, 1.0] {
            push_f32(&mut data, &[s, 1.0, 2.0 - s]);
        }
        let out = add(&mut bin, data, times.len(), "VEC3", FLOAT, json!({}));
        let pulse = json!({
            "name": "Pulse",
            "samplers": [{"input": input, "output": out, "interpolation": "STEP"}],
            "channels": [{"sampler": 0, "target": {"node": node_of(joints / 2), "path": "scale"}}],
        });

        let mut nodes = vec![json!({"name": "tail", "mesh": 0, "skin": 0})];
        for k in 0..joints {
            let mut node = json!({"name": format!("joint{k}")});
            if k > 0 {
                node["translation"] = json!([0.0, spacing, 0.0]);
            }
            if k + 1 < joints {
                node["children"] = json!([node_of(k + 1)]);
            }
            nodes.push(node);
        }
        let root = json!({
            "asset": {"version": "2.0", "generator": "pelage mesh::rig::TailRig"},
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": nodes,
            "meshes": [{"name": "tail", "primitives": [{
                "attributes": {"POSITION": position, "TEXCOORD_0": uv, "JOINTS_0": joint, "WEIGHTS_0": weight},
                "indices": index,
            }]}],
            "skins": [{"joints": (0..joints).map(node_of).collect::<Vec<_>>(), "inverseBindMatrices": inverse_binds}],
            "animations": [
                {"name": "Wag", "samplers": wag_samplers, "channels": wag_channels},
                {"name": "Curl", "samplers": curl_samplers, "channels": curl_channels},
                pulse,
            ],
            "accessors": accessors,
            "bufferViews": views,
            "buffers": [{
                "byteLength": bin.len(),
                "uri": format!("data:application/octet-stream;base64,{}", encode_base64(&bin)),
            }],
        });
        let mut text = serde_json::to_string_pretty(&root).unwrap_or_default();
        text.push('\n');
        text
    }
}
