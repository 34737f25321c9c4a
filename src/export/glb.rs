//! Binary glTF 2.0 (GLB) writer, by hand: a JSON chunk (serde_json) and one BIN chunk, both
//! padded to 4 bytes (JSON with spaces, BIN with zeros).
//!
//! Layout:
//! - scene 0 with the nodes `panels`, `support` and `node_axes` (the last two only when given);
//! - mesh `panels`: **one primitive per panel**, in panel order (POSITION, NORMAL = the sphere's
//!   outward normal −∇ψ/|∇ψ|, u32 indices, mode TRIANGLES); each primitive's `extras` is
//!   `{"panel": id}` (and `"mould": j` with moulds). The `panels` node's `extras` hold
//!   `panel_count`, `primitive_per_panel` and per panel its sphere: `{id, face, corners, a, b, c,
//!   center, radius, signed_radius, plane, normal, area, triangles}` (center/radius null and
//!   normal set for planes; with moulds also `mould` and `mould_deviation`), and with moulds the
//!   table `moulds: [{id, radius, curvature, panels, max_deviation}]`. With moulds, each mould
//!   has its own material, named `mould j`, in [`mould_colour`];
//! - mesh `support`: one indexed triangle primitive (double-sided material);
//! - mesh `node_axes`: one non-indexed LINES primitive (two points per segment);
//! - `asset.extras`: the caller's `extras` (e.g. Ω from [`absolute_sphere_extras`]).
//!
//! Positions and normals are f32 in the buffer; every POSITION accessor has `min`/`max` computed
//! from the f32 values. Vertex-attribute buffer views have `byteStride` 12 (several accessors
//! share them); each panel's vertices are its own (duplicated along shared arcs, bit-identical).

use glam::DVec3;
use serde_json::{json, Map, Value};

use crate::congruence::support_structure::SupportGeometry;
use crate::export::schedule::MouldRecord;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::TriMesh;
use crate::panels::moulds::{mould_colour, MouldAssignment};
use crate::panels::panel::Panel;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const MODE_LINES: u32 = 1;
const MODE_TRIANGLES: u32 = 4;

/// `asset.extras`-ready description of Ω: `{"absolute_sphere": {"center", "r2", "at_infinity",
/// "axis", "d"}}` (center/r2 null at infinity; axis/d null otherwise).
pub fn absolute_sphere_extras(omega: &AbsoluteSphere) -> Value {
    let inner = match *omega {
        AbsoluteSphere::Sphere { center, r2 } => json!({
            "center": center.to_array(), "r2": r2, "at_infinity": false, "axis": null, "d": null
        }),
        AbsoluteSphere::Plane { axis, d } => json!({
            "center": null, "r2": null, "at_infinity": true, "axis": axis.to_array(), "d": d
        }),
    };
    json!({ "absolute_sphere": inner })
}

/// A section of the BIN chunk: one buffer view, filled by several accessors.
struct View {
    bytes: Vec<u8>,
    stride: Option<u32>,
    target: u32,
}

#[derive(Default)]
struct Builder {
    views: Vec<View>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
}

impl Builder {
    fn view(&mut self, stride: Option<u32>, target: u32) -> usize {
        self.views.push(View { bytes: Vec::new(), stride, target });
        self.views.len() - 1
    }

    /// Appends VEC3 f32 data to view `v`; returns the accessor index. `bounds` adds min/max.
    fn vec3(&mut self, v: usize, pts: impl Iterator<Item = DVec3>, bounds: bool) -> usize {
        let offset = self.views[v].bytes.len();
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut count = 0usize;
        for p in pts {
            let f = [p.x as f32, p.y as f32, p.z as f32];
            for c in 0..3 {
                lo[c] = lo[c].min(f[c]);
                hi[c] = hi[c].max(f[c]);
                self.views[v].bytes.extend_from_slice(&f[c].to_le_bytes());
            }
            count += 1;
        }
        let mut acc = json!({
            "bufferView": v, "byteOffset": offset, "componentType": FLOAT, "count": count, "type": "VEC3"
        });
        if bounds {
            acc["min"] = json!(lo.map(f64::from));
            acc["max"] = json!(hi.map(f64::from));
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Appends u32 indices to view `v`; returns the accessor index.
    fn indices(&mut self, v: usize, tris: &[[u32; 3]]) -> usize {
        let offset = self.views[v].bytes.len();
        for &i in tris.iter().flatten() {
            self.views[v].bytes.extend_from_slice(&i.to_le_bytes());
        }
        self.accessors.push(json!({
            "bufferView": v, "byteOffset": offset, "componentType": UNSIGNED_INT,
            "count": tris.len() * 3, "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }

    /// A node of one indexed triangle primitive (with vertex normals when given) with its own
    /// mesh and double-sided material of `pbr` (pbrMetallicRoughness).
    fn triangles_node(&mut self, name: &str, pbr: Value, positions: &[DVec3], normals: Option<&[DVec3]>, triangles: &[[u32; 3]]) -> Value {
        let vp = self.view(Some(12), ARRAY_BUFFER);
        let vn = normals.map(|_| self.view(Some(12), ARRAY_BUFFER));
        let vi = self.view(None, ELEMENT_ARRAY_BUFFER);
        let pos = self.vec3(vp, positions.iter().copied(), true);
        let mut attributes = json!({ "POSITION": pos });
        if let (Some(v), Some(n)) = (vn, normals) {
            attributes["NORMAL"] = json!(self.vec3(v, n.iter().copied(), false));
        }
        let idx = self.indices(vi, triangles);
        self.materials.push(json!({ "name": name, "pbrMetallicRoughness": pbr, "doubleSided": true }));
        self.meshes.push(json!({ "name": name, "primitives": [{
            "attributes": attributes, "indices": idx, "mode": MODE_TRIANGLES, "material": self.materials.len() - 1
        }]}));
        json!({ "name": name, "mesh": self.meshes.len() - 1 })
    }

    /// A node of LINES (two points per segment) with its own mesh and unlit material.
    fn lines_node(&mut self, set: &LineSet) -> Value {
        let vp = self.view(Some(12), ARRAY_BUFFER);
        let pos = self.vec3(vp, set.segments.iter().flat_map(|&(s, e)| [s, e]), true);
        self.materials.push(json!({
            "name": set.name,
            "pbrMetallicRoughness": { "baseColorFactor": set.color, "metallicFactor": 0.0, "roughnessFactor": 1.0 }
        }));
        self.meshes.push(json!({ "name": set.name, "primitives": [{
            "attributes": { "POSITION": pos }, "mode": MODE_LINES, "material": self.materials.len() - 1
        }]}));
        json!({ "name": set.name, "mesh": self.meshes.len() - 1 })
    }

    /// The GLB bytes: JSON chunk and BIN chunk.
    fn finish(self, nodes: Vec<Value>, extras: Value) -> Vec<u8> {
        let (meshes, materials) = (self.meshes, self.materials);
        // Buffer: views back to back, each 4-byte aligned (all data is 4-byte elements anyway).
        let mut bin: Vec<u8> = Vec::new();
        let mut buffer_views: Vec<Value> = Vec::new();
        for v in &self.views {
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            let mut view = json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": v.bytes.len(), "target": v.target });
            if let Some(s) = v.stride {
                view["byteStride"] = json!(s);
            }
            buffer_views.push(view);
            bin.extend_from_slice(&v.bytes);
        }

        let mut asset = json!({
            "version": "2.0",
            "generator": concat!("spherical-faces ", env!("CARGO_PKG_VERSION")),
        });
        if !extras.is_null() {
            asset["extras"] = extras;
        }
        let mut root = Map::new();
        root.insert("asset".into(), asset);
        root.insert("scene".into(), json!(0));
        root.insert("scenes".into(), json!([{ "name": "spherical-faces", "nodes": (0..nodes.len()).collect::<Vec<_>>() }]));
        root.insert("nodes".into(), Value::Array(nodes));
        if !meshes.is_empty() {
            root.insert("meshes".into(), Value::Array(meshes));
            root.insert("materials".into(), Value::Array(materials));
            root.insert("accessors".into(), Value::Array(self.accessors));
            root.insert("bufferViews".into(), Value::Array(buffer_views));
            root.insert("buffers".into(), json!([{ "byteLength": bin.len() }]));
        }
        let mut json_bytes = serde_json::to_vec(&Value::Object(root)).expect("JSON values serialize");
        while !json_bytes.len().is_multiple_of(4) {
            json_bytes.push(b' ');
        }
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }

        let has_bin = !bin.is_empty();
        let total = 12 + 8 + json_bytes.len() + if has_bin { 8 + bin.len() } else { 0 };
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json_bytes);
        if has_bin {
            out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
            out.extend_from_slice(b"BIN\0");
            out.extend_from_slice(&bin);
        }
        out
    }
}

/// Per-panel sphere data for the `panels` node's extras.
fn panel_extras(p: &Panel) -> Value {
    let s = p.sphere;
    let planar = p.is_planar();
    let center = s.center().filter(|_| !planar).map(|c| c.to_array());
    let signed = s.signed_radius().filter(|_| !planar);
    json!({
        "id": p.face,
        "face": p.face,
        "corners": p.corners,
        "a": s.a,
        "b": s.b.to_array(),
        "c": s.c,
        "center": center,
        "radius": signed.map(f64::abs),
        "signed_radius": signed,
        "plane": planar,
        "normal": if planar { json!(s.b.normalize_or_zero().to_array()) } else { Value::Null },
        "area": p.area,
        "triangles": p.triangles.len(),
    })
}

/// Named line segments of a GLB (a LINES primitive in one colour).
pub struct LineSet<'a> {
    pub name: &'a str,
    pub color: [f32; 4],
    pub segments: &'a [(DVec3, DVec3)],
}

/// Writes a GLB of a surface (node `surface`: triangles with vertex normals) and line sets (one
/// node each, named by the set; empty sets are left out); `extras` goes to `asset.extras`.
pub(crate) fn write_lines_glb(surface: &TriMesh, line_sets: &[LineSet], extras: Value) -> Vec<u8> {
    let mut b = Builder::default();
    let mut nodes = Vec::new();
    if !surface.triangles.is_empty() {
        let material = json!({ "baseColorFactor": [0.80, 0.82, 0.86, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6 });
        let normals = surface.vertex_normals();
        nodes.push(b.triangles_node("surface", material, &surface.positions, Some(&normals), &surface.triangles));
    }
    for set in line_sets.iter().filter(|s| !s.segments.is_empty()) {
        nodes.push(b.lines_node(set));
    }
    b.finish(nodes, extras)
}

/// Writes a GLB. `node_axes` are line segments (start, end), e.g. from
/// `SupportStructure::axis_segments`; `extras` goes to `asset.extras` (omitted when null).
/// Empty parts are left out (an empty `panels` node is still written).
pub fn write_glb(
    panels: &[Panel],
    support: Option<&SupportGeometry>,
    node_axes: Option<&[(DVec3, DVec3)]>,
    moulds: Option<&MouldAssignment>,
    extras: Value,
) -> Vec<u8> {
    let mut b = Builder::default();
    let mut nodes: Vec<Value> = Vec::new();
    let moulds = moulds.filter(|m| m.panel_mould.len() == panels.len());

    // Panels.
    let mut panels_node = json!({ "name": "panels" });
    let mut records: Vec<Value> = panels.iter().map(panel_extras).collect();
    if let Some(m) = moulds {
        for (r, (&j, &d)) in records.iter_mut().zip(m.panel_mould.iter().zip(&m.panel_deviation)) {
            r["mould"] = json!(j);
            r["mould_deviation"] = json!(d);
        }
    }
    panels_node["extras"] = json!({
        "panel_count": panels.len(),
        "primitive_per_panel": true,
        "panels": records,
    });
    if let Some(m) = moulds {
        panels_node["extras"]["moulds"] = json!(MouldRecord::of(m));
    }
    if !panels.is_empty() {
        let (vp, vn, vi) = (b.view(Some(12), ARRAY_BUFFER), b.view(Some(12), ARRAY_BUFFER), b.view(None, ELEMENT_ARRAY_BUFFER));
        let material = |name: String, [r, g, bl]: [f32; 3]| {
            json!({
                "name": name,
                "pbrMetallicRoughness": { "baseColorFactor": [r, g, bl, 1.0], "metallicFactor": 0.9, "roughnessFactor": 0.25 },
                "doubleSided": true
            })
        };
        let first = b.materials.len();
        match moulds {
            Some(m) => b.materials.extend((0..m.moulds.len()).map(|j| material(format!("mould {j}"), mould_colour(j)))),
            None => b.materials.push(material("panels".into(), [0.80, 0.82, 0.86])),
        }
        let primitives: Vec<Value> = panels
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let pos = b.vec3(vp, p.positions.iter().copied(), true);
                let nrm = b.vec3(vn, p.positions.iter().map(|&x| p.normal_at(x)), false);
                let idx = b.indices(vi, &p.triangles);
                let mould = moulds.map(|m| m.panel_mould[i]);
                let mut extras = json!({ "panel": p.face });
                if let Some(j) = mould {
                    extras["mould"] = json!(j);
                }
                json!({
                    "attributes": { "POSITION": pos, "NORMAL": nrm },
                    "indices": idx, "mode": MODE_TRIANGLES, "material": first + mould.unwrap_or(0) as usize,
                    "extras": extras
                })
            })
            .collect();
        b.meshes.push(json!({ "name": "panels", "primitives": primitives }));
        panels_node["mesh"] = json!(b.meshes.len() - 1);
    }
    nodes.push(panels_node);

    // Support structure.
    if let Some(s) = support.filter(|s| !s.triangles.is_empty() && !s.positions.is_empty()) {
        let material = json!({ "baseColorFactor": [0.55, 0.42, 0.28, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7 });
        nodes.push(b.triangles_node("support", material, &s.positions, None, &s.triangles));
    }

    // Node axes.
    if let Some(axes) = node_axes.filter(|a| !a.is_empty()) {
        let set = LineSet { name: "node_axes", color: [0.85, 0.15, 0.1, 1.0], segments: axes };
        nodes.push(b.lines_node(&set));
    }

    b.finish(nodes, extras)
}

/// The JSON chunk of a GLB (for tests and tools); None if `glb` is not a GLB.
pub fn glb_json(glb: &[u8]) -> Option<Value> {
    if glb.len() < 20 || &glb[0..4] != b"glTF" || &glb[16..20] != b"JSON" {
        return None;
    }
    let len = u32::from_le_bytes(glb[12..16].try_into().ok()?) as usize;
    serde_json::from_slice(glb.get(20..20 + len)?).ok()
}
