//! Writing a cloud as a GLB: one POINTS primitive with float attributes (tightly packed,
//! one buffer view each), a `COLOR_0` for viewers without the extension, and our label
//! attribute when the cloud has labels.

use glam::{Quat, Vec3};
use serde_json::{json, Map, Value};

use super::accessor::{FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT};
use super::container::assemble_glb;
use super::{half_turn, sh_attribute, Axis, EXTENSION, LABEL_ATTRIBUTE, OPACITY, ROTATION, SCALE};
use crate::splat::codec::{Format, SplatError, SH_C0};
use crate::splat::sh::ShRotator;
use crate::splat::{sh_coeff_count, GaussianCloud};

/// Which way the axes of the cloud to write lie; glTF's are +y up, +z forward.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceFrame {
    /// A capture's frame as PLY, SPZ and `.splat` hold it (y down for COLMAP-based
    /// trainers): turned half a turn about z, as splat-transform does, so that reading the
    /// GLB back gives the cloud as it was.
    Capture,
    /// The simulation's world, z up: turned a quarter turn about x (+z becomes glTF's +y),
    /// so that the scene stands upright in glTF viewers.
    ZUp,
}

/// `ARRAY_BUFFER`, the buffer view target of vertex attributes.
const ARRAY_BUFFER: u64 = 34962;

/// The GLB of `cloud` (`name` names it in the error of a cloud past the format's 4 GiB).
pub fn write(cloud: &GaussianCloud, frame: SourceFrame, name: &str) -> Result<Vec<u8>, SplatError> {
    let mut c = cloud.clone();
    match frame {
        SourceFrame::Capture => half_turn(&mut c, Axis::Z),
        SourceFrame::ZUp => stand_z_up(&mut c),
    }
    let mut out = Layout::default();
    let primitive = (!c.is_empty()).then(|| primitive(&c, &mut out));
    let mut gltf = json!({
        "asset": {"version": "2.0", "generator": concat!("splatter ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": [EXTENSION],
        "scene": 0,
    });
    if let Some(primitive) = primitive {
        gltf["scenes"] = json!([{"nodes": [0]}]);
        gltf["nodes"] = json!([{"mesh": 0}]);
        gltf["meshes"] = json!([{"primitives": [primitive]}]);
        gltf["buffers"] = json!([{"byteLength": out.bin.len()}]);
        gltf["bufferViews"] = Value::Array(out.views);
        gltf["accessors"] = Value::Array(out.accessors);
    } else {
        gltf["scenes"] = json!([{"nodes": []}]);
    }
    let text = serde_json::to_vec(&gltf).unwrap_or_default();
    assemble_glb(&text, &out.bin).ok_or_else(|| SplatError::Unsupported {
        file: name.to_string(),
        format: Format::Gltf,
        what: format!(
            "a cloud of {} Gaussians ({} bytes of attributes)",
            c.len(),
            out.bin.len()
        ),
        expected: "a GLB under 4 GiB",
    })
}

/// z up → y up: (x, y, z) → (x, z, −y), a quarter turn about x.
fn stand_z_up(c: &mut GaussianCloud) {
    let turn = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    for p in c.positions.iter_mut().chain(c.normals.iter_mut()) {
        *p = Vec3::new(p.x, p.z, -p.y);
    }
    for q in &mut c.rotations {
        *q = (turn * *q).normalize();
    }
    if c.sh_degree > 0 {
        let rotator = ShRotator::new();
        let (degree, stride) = (c.sh_degree, c.sh_stride());
        for coeffs in c.sh.chunks_exact_mut(stride) {
            let turned = rotator.to_world(degree, coeffs, turn.as_dquat());
            coeffs.copy_from_slice(&turned);
        }
    }
}

/// The binary chunk, its buffer views and accessors as they are laid out.
#[derive(Default)]
struct Layout {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Layout {
    /// Append one attribute's bytes as a buffer view and an accessor; returns its index.
    fn add(
        &mut self,
        bytes: &[u8],
        count: usize,
        component: u64,
        kind: &str,
        extra: Value,
    ) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let mut view = json!({
            "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": ARRAY_BUFFER,
        });
        // An element narrower than 4 bytes is padded to 4: glTF aligns vertex attributes so.
        let size = match component {
            UNSIGNED_BYTE => 1,
            UNSIGNED_SHORT => 2,
            _ => 4,
        };
        let components = match kind {
            "VEC4" => 4,
            "VEC3" => 3,
            _ => 1,
        };
        if size * components < 4 {
            view["byteStride"] = json!(4);
        }
        self.views.push(view);
        let mut accessor = json!({
            "bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": kind,
        });
        if let (Some(a), Value::Object(more)) = (accessor.as_object_mut(), extra) {
            a.extend(more);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn floats(&mut self, values: impl IntoIterator<Item = f32>, count: usize, kind: &str) -> usize {
        let bytes: Vec<u8> = values.into_iter().flat_map(f32::to_le_bytes).collect();
        self.add(&bytes, count, FLOAT, kind, Value::Null)
    }
}

/// The splat primitive of `c` (already in glTF's frame), its data added to `out`.
// Over 80 lines on purpose: each attribute of the primitive in the extension's order.
fn primitive(c: &GaussianCloud, out: &mut Layout) -> Value {
    let n = c.len();
    let (lo, hi) = c.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let mut attributes = Map::new();
    let mut put = |name: &str, index: usize| {
        attributes.insert(name.to_string(), json!(index));
    };
    let bytes: Vec<u8> = c
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    put(
        "POSITION",
        out.add(
            &bytes,
            n,
            FLOAT,
            "VEC3",
            json!({"min": lo.to_array(), "max": hi.to_array()}),
        ),
    );
    put(
        "COLOR_0",
        out.add(
            &fallback_colours(c),
            n,
            UNSIGNED_BYTE,
            "VEC4",
            json!({"normalized": true}),
        ),
    );
    put(
        ROTATION,
        out.floats(
            c.rotations.iter().flat_map(|q| [q.x, q.y, q.z, q.w]),
            n,
            "VEC4",
        ),
    );
    put(
        SCALE,
        out.floats(c.scales.iter().flat_map(|s| s.to_array()), n, "VEC3"),
    );
    put(
        OPACITY,
        out.floats(c.opacities.iter().copied(), n, "SCALAR"),
    );
    let stride = c.sh_stride();
    for k in 0..sh_coeff_count(c.sh_degree) {
        let l = (k as f32).sqrt() as u32;
        let values = (0..n).flat_map(|i| {
            let at = i * stride + k * 3;
            [c.sh[at], c.sh[at + 1], c.sh[at + 2]]
        });
        put(
            &sh_attribute(l, k as u32 - l * l),
            out.floats(values, n, "VEC3"),
        );
    }
    let mut primitive = json!({
        "mode": 0,
        "extensions": {EXTENSION: {
            "kernel": "ellipse",
            "colorSpace": "srgb_rec709_display",
            "projection": "perspective",
            "sortingMethod": "cameraDistance",
        }},
    });
    if !c.labels.is_empty() {
        let bytes: Vec<u8> = c
            .labels
            .iter()
            .flat_map(|l| [l.to_le_bytes(), [0, 0]])
            .flatten()
            .collect();
        put(
            LABEL_ATTRIBUTE,
            out.add(&bytes, n, UNSIGNED_SHORT, "SCALAR", Value::Null),
        );
        primitive["extras"] = json!({LABEL_ATTRIBUTE: c.label_names});
    }
    primitive["attributes"] = Value::Object(attributes);
    primitive
}

/// `COLOR_0` for viewers that draw the primitive as points: the diffuse colour (0.5 + C0 ·
/// DC, clamped, then decoded from sRGB since glTF vertex colours are linear) and the
/// opacity, as normalized bytes.
fn fallback_colours(c: &GaussianCloud) -> Vec<u8> {
    let stride = c.sh_stride();
    let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let linear = |s: f32| {
        let s = s.clamp(0.0, 1.0);
        if s <= 0.04045 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    };
    (0..c.len())
        .flat_map(|i| {
            let dc = &c.sh[i * stride..i * stride + 3];
            let rgb = [0, 1, 2].map(|ch| byte(linear(0.5 + SH_C0 * dc[ch])));
            [rgb[0], rgb[1], rgb[2], byte(c.opacities[i])]
        })
        .collect()
}
