//! Import tests: OBJ triangulation and index forms, glTF/GLB buffers and node transforms,
//! robustness against corrupt input, welding, and the shared reference meshes.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns processes

mod common;

use glam::DVec3;
use spherical_faces::geometry::mesh::weld::{weld, WeldReport};
use spherical_faces::geometry::mesh::TriMesh;
use spherical_faces::import::*;

// ---------------------------------------------------------------------------------------------
// Helpers

fn import_ok(text: &str, name: &str) -> Imported {
    match import_mesh(text.as_bytes(), name) {
        Ok(m) => m,
        Err(e) => panic!("{name}: unexpected error: {e}"),
    }
}

fn import_err(bytes: &[u8], name: &str) -> ImportError {
    match import_mesh(bytes, name) {
        Ok(m) => panic!("{name}: expected an error, got {} faces", m.mesh.face_count()),
        Err(e) => e,
    }
}

fn area_vector(m: &TriMesh) -> DVec3 {
    (0..m.face_count()).map(|f| m.face_area_vector(f)).sum()
}

fn total_area(m: &TriMesh) -> f64 {
    (0..m.face_count()).map(|f| m.face_area_vector(f).length()).sum()
}

/// Half the Newell vector: the area vector of a planar polygon.
fn polygon_area_vector(p: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for i in 0..p.len() {
        n += p[i].cross(p[(i + 1) % p.len()]);
    }
    0.5 * n
}

fn obj_polygon(points: &[DVec3]) -> String {
    let mut s = String::new();
    for p in points {
        s += &format!("v {:?} {:?} {:?}\n", p.x, p.y, p.z);
    }
    s += "f";
    for i in 1..=points.len() {
        s += &format!(" {i}");
    }
    s + "\n"
}

/// Embeds 2D points in a tilted plane through an offset origin.
fn tilted(points2: &[(f64, f64)]) -> Vec<DVec3> {
    let u = DVec3::new(1.0, 2.0, 2.0) / 3.0;
    let w = DVec3::new(2.0, 1.0, -2.0) / 3.0;
    let o = DVec3::new(0.5, -1.25, 3.0);
    points2.iter().map(|&(x, y)| o + x * u + y * w).collect()
}

/// Triangulates one polygon through the OBJ importer and checks area, orientation and count.
fn check_polygon(name: &str, points2: &[(f64, f64)]) -> Imported {
    let pts = tilted(points2);
    let m = import_ok(&obj_polygon(&pts), name);
    let expected = polygon_area_vector(&pts);
    let n = expected.normalize();
    assert_eq!(m.mesh.face_count(), pts.len() - 2, "{name}: triangle count");
    assert_eq!(m.source_polygons, 1);
    let got = area_vector(&m.mesh);
    assert!((got - expected).length() < 1e-12 * expected.length(), "{name}: area vector {got} vs {expected}");
    // No flipped or overlapping triangles: unsigned areas add up to the polygon area.
    assert!((total_area(&m.mesh) - expected.length()).abs() < 1e-12 * expected.length(), "{name}: overlap");
    for f in 0..m.mesh.face_count() {
        assert!(m.mesh.face_area_vector(f).dot(n) > 0.0, "{name}: face {f} is flipped");
    }
    m
}

fn b64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (u32::from(c[0]) << 16) | (u32::from(*c.get(1).unwrap_or(&0)) << 8) | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
        out.extend_from_slice(&b);
    }
    out
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn u16_bytes(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Simple deterministic LCG (Numerical Recipes constants).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> u32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 33) as u32
    }
}

fn shared_mesh(name: &str) -> Vec<u8> {
    common::shared_bytes(&format!("data/meshes/{name}"))
}

// ---------------------------------------------------------------------------------------------
// OBJ

#[test]
fn obj_triangle_passes_through() {
    let m = import_ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj");
    assert_eq!(m.format, Format::Obj);
    assert_eq!(m.mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(m.mesh.positions[1], DVec3::X);
    assert_eq!(m.stats.faces, 1);
    assert_eq!(m.stats.boundary_loops, 1);
    assert!(m.notes.is_empty(), "{:?}", m.notes);
}

#[test]
fn obj_convex_polygons_keep_area_and_orientation() {
    check_polygon("square.obj", &[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
    let hexagon: Vec<(f64, f64)> = (0..6)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 6.0;
            (a.cos(), a.sin())
        })
        .collect();
    check_polygon("hexagon.obj", &hexagon);
    let circle: Vec<(f64, f64)> = (0..40)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 40.0;
            (3.0 * a.cos(), 2.0 * a.sin())
        })
        .collect();
    check_polygon("ellipse40.obj", &circle);
    // Clockwise input stays clockwise (orientation follows the file).
    let cw: Vec<(f64, f64)> = hexagon.iter().rev().copied().collect();
    check_polygon("hexagon_cw.obj", &cw);
}

#[test]
fn obj_non_convex_polygons_are_ear_clipped() {
    // L shape (one reflex corner).
    check_polygon("l.obj", &[(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)]);
    // Five-pointed star starting at a reflex corner: a fan from vertex 0 would flip triangles.
    let star: Vec<(f64, f64)> = (0..10)
        .map(|k| {
            let a = (k as f64 + 0.5) * std::f64::consts::TAU / 10.0;
            let r = if k % 2 == 0 { 0.4 } else { 1.0 };
            (r * a.cos(), r * a.sin())
        })
        .collect();
    check_polygon("star.obj", &star);
    // Comb with collinear corners along the bottom edge.
    check_polygon("comb.obj", &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (3.0, 0.0), (3.0, 2.0), (2.5, 0.5), (2.0, 2.0), (1.0, 0.5), (0.0, 2.0)]);
}

#[test]
fn obj_quads_split_along_shorter_valid_diagonal() {
    // Rhombus: diagonal 1-3 (length 2) is shorter than 0-2 (length 4).
    let m = check_polygon("rhombus.obj", &[(0.0, 0.0), (2.0, -1.0), (4.0, 0.0), (2.0, 1.0)]);
    for t in &m.mesh.triangles {
        assert!(t.contains(&1) && t.contains(&3), "{t:?} does not use diagonal 1-3");
    }
    let m = check_polygon("rhombus2.obj", &[(0.0, 0.0), (1.0, -2.0), (2.0, 0.0), (1.0, 2.0)]);
    for t in &m.mesh.triangles {
        assert!(t.contains(&0) && t.contains(&2), "{t:?} does not use diagonal 0-2");
    }
    // Dart: the shorter diagonal 0-2 lies outside; the split must go through reflex corner 3.
    let m = check_polygon("dart.obj", &[(0.0, 0.0), (10.0, 1.0), (0.0, 2.0), (1.0, 1.0)]);
    for t in &m.mesh.triangles {
        assert!(t.contains(&1) && t.contains(&3), "{t:?}");
    }
}

#[test]
fn obj_mixed_grid_counts_and_topology() {
    // 3x3 grid of quads plus a pentagon and a hexagon glued to its right and top edges.
    let mut s = String::from("# grid\no grid\n");
    for j in 0..4 {
        for i in 0..4 {
            s += &format!("v {i} {j} 0\n");
        }
    }
    let id = |i: usize, j: usize| j * 4 + i + 1;
    for j in 0..3 {
        for i in 0..3 {
            s += &format!("f {} {} {} {}\n", id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
        }
    }
    // Pentagon on the right edge x = 3, from (3,0) to (3,3).
    s += "v 4 0 0\nv 4.5 1.5 0\nv 4 3 0\n"; // 17 18 19
    s += &format!("f {} 17 18 19 {} {} {}\n", id(3, 0), id(3, 3), id(3, 2), id(3, 1));
    // Hexagon on top: (0,3) (1,3) (2,3) (3,3) (2,4) (1,4), three corners collinear.
    s += "v 2 4 0\nv 1 4 0\n"; // 20 21
    s += &format!("f {} {} {} {} 20 21\n", id(0, 3), id(1, 3), id(2, 3), id(3, 3));
    let m = import_ok(&s, "grid.obj");
    assert_eq!(m.source_polygons, 11);
    // 9 quads -> 18, "pentagon" with 7 corners (three collinear) -> 5, hexagon -> 4.
    assert_eq!(m.mesh.face_count(), 18 + 5 + 4);
    assert_eq!(m.stats.vertices, 21);
    assert_eq!(m.stats.boundary_loops, 1);
    assert_eq!(m.stats.non_manifold_edges, 0);
    assert!(area_vector(&m.mesh).z > 0.0);
    let expected_area = 9.0 + (3.0 + 0.5 * 3.0 * 0.5) + 0.5 * (3.0 + 1.0) * 1.0;
    assert!((total_area(&m.mesh) - expected_area).abs() < 1e-12, "{}", total_area(&m.mesh));
    for f in 0..m.mesh.face_count() {
        assert!(m.mesh.face_area_vector(f).z > 0.0);
    }
}

#[test]
fn obj_negative_and_slash_index_forms() {
    let base = import_ok("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "a.obj");
    let forms = [
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n",
        "v 0 0 0\nv 1 0 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 4/4\n",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\n",
        // Missing normals / texture coordinates are not an error: only positions are used.
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1//7 2//8 3//9 4//10\n",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4/-1 -3/-1/-1 -2//-1 -1\n",
        // Optional w is ignored; extra vertex colour columns too.
        "v 0 0 0 1\nv 1 0 0 1\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\nf 1 2 3 4\n",
    ];
    for (k, text) in forms.iter().enumerate() {
        let m = import_ok(text, "forms.obj");
        assert_eq!(m.mesh, base.mesh, "form {k}");
    }
    // Relative indices count back from the face's own position in the file.
    let m = import_ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf -3 -2 -1\n", "rel.obj");
    assert_eq!(m.mesh.triangles, vec![[0, 1, 2], [1, 2, 3]]);
    // Forward references (vertex defined after the face) are accepted.
    let m = import_ok("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "fwd.obj");
    assert_eq!(m.mesh.face_count(), 1);
}

#[test]
fn obj_crlf_tabs_comments_continuation_and_binary_junk() {
    let mut bytes: Vec<u8> = Vec::new();
    bytes.extend_from_slice(b"# comment with junk \xff\xfe\r\n");
    bytes.extend_from_slice(b"mtllib x.mtl\r\nusemtl \xc3\x28bad\r\ng g1\r\ns 1\r\n");
    bytes.extend_from_slice(b"v\t0 0 0 # trailing comment\r\n");
    bytes.extend_from_slice(b"v 1 \\\r\n 0 0\r\n"); // continuation
    bytes.extend_from_slice(b"  v 1 1 0\r\nv 0 1 0\r\n\r\n");
    bytes.extend_from_slice(b"f 1 2 \\\n 3 4\r\n");
    bytes.extend_from_slice(b"l 1 2\r\ncurv 0 1 1 2\r\n");
    let m = import_mesh(&bytes, "crlf.obj").unwrap();
    assert_eq!(m.mesh.face_count(), 2);
    assert_eq!(m.mesh.positions[1], DVec3::X);
    assert!(m.notes.iter().any(|n| n.contains("line/point")), "{:?}", m.notes);
    assert!(m.notes.iter().any(|n| n.contains("curv")), "{:?}", m.notes);
}

#[test]
fn obj_errors_name_file_and_line() {
    let e = import_err(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 99\n", "dir/tri_dome.obj");
    assert_eq!(e.to_string(), "tri_dome.obj: line 5: face refers to vertex 99, but only 3 vertices are defined");
    assert!(matches!(e, ImportError::Malformed { line: Some(5), .. }));
    assert_eq!(e.line(), Some(5));
    assert_eq!(e.file(), "tri_dome.obj");

    let e = import_err(b"v 0 0 0\nv 1 0 0\nf -3 -2 -1\n", "x.obj");
    assert!(e.to_string().starts_with("x.obj: line 3: face refers to vertex -3"), "{e}");
    let e = import_err(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "x.obj");
    assert!(e.to_string().contains("line 4") && e.to_string().contains("start at 1"), "{e}");
    let e = import_err(b"v 0 0 0\nv 1 zero 0\n", "x.obj");
    assert_eq!(e.to_string(), "x.obj: line 2: invalid number 'zero' in vertex");
    let e = import_err(b"v 0 0 0\nv 1 nan 0\n", "x.obj");
    assert!(e.to_string().contains("line 2") && e.to_string().contains("not a finite"), "{e}");
    let e = import_err(b"v 0 0 0\nv 1 1e999 0\n", "x.obj");
    assert!(e.to_string().contains("line 2"), "{e}");
    let e = import_err(b"v 0 0\n", "x.obj");
    assert!(e.to_string().contains("line 1: vertex needs 3 coordinates"), "{e}");
    let e = import_err(b"v 0 0 0\nv 1 \xff 0\n", "x.obj");
    assert!(matches!(e, ImportError::Malformed { line: Some(2), .. }), "{e}");
    let e = import_err(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x3\n", "x.obj");
    assert!(e.to_string().starts_with("x.obj: line 4: invalid vertex index 'x3'"), "{e}");

    let e = import_err(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "x.obj");
    assert_eq!(e.to_string(), "x.obj: no faces found");
    assert!(matches!(e, ImportError::Empty { .. }));
    let e = import_err(b"", "x.obj");
    assert!(matches!(e, ImportError::Empty { .. }));
    let e = import_err(b" \n\t\r\n", "x.obj");
    assert!(matches!(e, ImportError::Empty { .. }));
    // Only degenerate faces.
    let e = import_err(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n", "x.obj");
    assert!(matches!(e, ImportError::Empty { .. }), "{e}");
    assert!(e.to_string().contains("degenerate"), "{e}");
}

#[test]
fn obj_over_limit_is_rejected_before_parsing() {
    let mut s = String::with_capacity(8 * (MAX_TRIANGLES + 1) + 32);
    s += "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    s += &"f 1 2 3\n".repeat(MAX_TRIANGLES + 1);
    let e = import_err(s.as_bytes(), "big.obj");
    assert_eq!(e.to_string(), "big.obj: 2000001 triangles exceed the limit of 2000000");
    assert_eq!(e, ImportError::TooLarge { file: "big.obj".into(), what: "triangles".into(), count: 2_000_001, limit: 2_000_000 });
    // One huge polygon counts as its triangulation.
    let mut s = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nf");
    s += &" -1".repeat(MAX_TRIANGLES + 3);
    let e = import_err(s.as_bytes(), "poly.obj");
    assert!(matches!(e, ImportError::TooLarge { count: 2_000_001, .. }), "{e}");
}

// ---------------------------------------------------------------------------------------------
// glTF / GLB

/// A unit square (two triangles) as positions + u16 indices, and the matching JSON pieces.
fn square_buffer() -> Vec<u8> {
    let mut bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend(u16_bytes(&[0, 1, 2, 0, 2, 3]));
    bin
}

fn square_json(buffer: &str, extra_nodes: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},
  "buffers":[{buffer}],
  "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
               {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}]{extra_nodes}}}"#
    )
}

#[test]
fn gltf_with_embedded_data_uri() {
    let bin = square_buffer();
    let buffer = format!(r#"{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}"#, bin.len(), b64(&bin));
    let json = square_json(&buffer, r#","nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0"#);
    let m = import_ok(&json, "model.gltf");
    assert_eq!(m.format, Format::Gltf);
    assert_eq!(m.mesh.face_count(), 2);
    assert_eq!(m.source_polygons, 2);
    assert_eq!(m.mesh.positions[2], DVec3::new(1.0, 1.0, 0.0));
    assert_eq!(m.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.stats.boundary_loops, 1);

    // No scenes: every mesh once, untransformed. Detected by content despite the extension,
    // with a UTF-8 BOM and leading whitespace.
    let json = square_json(&buffer, "");
    let mut bytes = b"\xEF\xBB\xBF \n".to_vec();
    bytes.extend_from_slice(json.as_bytes());
    let m = import_mesh(&bytes, "model.txt").unwrap();
    assert_eq!(m.format, Format::Gltf);
    assert_eq!(m.mesh.face_count(), 2);

    // External buffers are refused with an actionable message.
    let json = square_json(r#"{"byteLength":60,"uri":"a.bin"}"#, "");
    let e = import_err(json.as_bytes(), "model.gltf");
    assert_eq!(e.to_string(), "model.gltf: buffer 0 uses external file 'a.bin'; embed it as a data: URI or export as .glb");
    assert!(matches!(e, ImportError::Unsupported { .. }));
}

#[test]
fn gltf_strip_fan_and_skipped_primitives() {
    // Six points of a 2x3 grid; strip 0,3,1,4,2,5 and a fan 0,1,4,3.
    let pos = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 2.0, 1.0, 0.0]);
    let mut bin = pos.clone();
    bin.extend(u16_bytes(&[0, 3, 1, 4, 2, 5])); // strip, offset 72
    bin.extend(u16_bytes(&[0, 1, 4, 3])); // fan, offset 84
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{}}}],
  "bufferViews":[{{"buffer":0,"byteLength":72}},{{"buffer":0,"byteOffset":72,"byteLength":12}},{{"buffer":0,"byteOffset":84,"byteLength":8}}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":6,"type":"VEC3","min":[0,0,0],"max":[2,1,0]}},
               {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}},
               {{"bufferView":2,"componentType":5123,"count":4,"type":"SCALAR"}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":5}},
                          {{"attributes":{{"POSITION":0}},"indices":2,"mode":6}},
                          {{"attributes":{{"POSITION":0}},"mode":1}},
                          {{"attributes":{{"POSITION":0}},"mode":0}}]}}],
  "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}]}}"#,
        bin.len()
    );
    let m = import_mesh(&glb(&json, &bin), "strip.glb").unwrap();
    assert_eq!(m.format, Format::Glb);
    assert_eq!(m.source_polygons, 4 + 2);
    // The fan repeats two strip triangles' area: the fan covers [0,1]x[0,1] with triangles
    // (1,4,0) and (4,3,0); the strip has (0,3,1),(3,4,1): different diagonals, so all survive.
    assert_eq!(m.mesh.face_count(), 6);
    for f in 0..m.mesh.face_count() {
        assert!(m.mesh.face_area_vector(f).z < 0.0 || m.mesh.face_area_vector(f).z > 0.0);
    }
    // Strip orientation is consistent: all strip triangles face the same way.
    let strip_z: Vec<f64> = (0..4).map(|f| m.mesh.face_area_vector(f).z).collect();
    assert!(strip_z.iter().all(|z| *z < 0.0), "{strip_z:?}");
    assert!(m.notes.iter().any(|n| n == "skipped 1 line primitive"), "{:?}", m.notes);
    assert!(m.notes.iter().any(|n| n == "skipped 1 point primitive"), "{:?}", m.notes);
}

/// Rotates `v` by the (normalized) quaternion (x, y, z, w), written out by hand.
fn rotate(q: [f32; 4], v: DVec3) -> DVec3 {
    let q = [q[0] as f64, q[1] as f64, q[2] as f64, q[3] as f64];
    let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (x, y, z, w) = (q[0] / len, q[1] / len, q[2] / len, q[3] / len);
    let r = [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ];
    DVec3::new(
        r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z,
        r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z,
        r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z,
    )
}

#[test]
fn glb_node_transforms_accumulate_in_f64() {
    let bin = square_buffer();
    // Node 0 (TRS) -> node 1 (matrix) -> node 2 (TRS, mesh); node 3 (mesh, mirrored) under node 0.
    let t0 = [10.0f32, -2.0, 0.5];
    let r0 = [0.0f32, 0.38268343, 0.0, 0.9238795]; // 45 degrees about y (f32-rounded)
    let s0 = [2.0f32, 3.0, 0.5];
    // Column-major: rotate 90 degrees about z, then translate (1, 2, 3).
    let m1 = [0.0f32, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 2.0, 3.0, 1.0];
    let t2 = [0.25f32, 0.125, -4.0];
    let r2 = [0.1f32, 0.2, 0.3, 0.9]; // not unit: normalized by the importer
    let s2 = [1.5f32, 1.5, 1.5];
    let s3 = [-1.0f32, 1.0, 1.0];
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":60}}],
  "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
               {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
  "nodes":[{{"children":[1,3],"translation":{t0:?},"rotation":{r0:?},"scale":{s0:?}}},
           {{"children":[2],"matrix":{m1:?}}},
           {{"mesh":0,"translation":{t2:?},"rotation":{r2:?},"scale":{s2:?}}},
           {{"mesh":0,"scale":{s3:?}}},
           {{"mesh":0,"translation":[100,0,0]}}],
  "scenes":[{{"nodes":[4]}},{{"nodes":[0]}}],"scene":1}}"#
    );
    let m = import_mesh(&glb(&json, &bin), "nodes.glb").unwrap();
    let to = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let node0 = |p: DVec3| to(t0) + rotate(r0, to(s0) * p);
    let node1 = |p: DVec3| DVec3::new(-p.y, p.x, p.z) + DVec3::new(1.0, 2.0, 3.0);
    let node2 = |p: DVec3| to(t2) + rotate(r2, to(s2) * p);
    let node3 = |p: DVec3| to(s3) * p;
    let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    let mut expected: Vec<DVec3> = square.iter().map(|&p| node0(node1(node2(p)))).collect();
    expected.extend(square.iter().map(|&p| node0(node3(p))));
    assert_eq!(m.mesh.positions.len(), 8, "scene 1 only: node 4 (scene 0) must not be imported");
    for (got, want) in m.mesh.positions.iter().zip(&expected) {
        assert!((*got - *want).length() <= 1e-12 * want.length().max(1.0), "{got} vs {want}");
    }
    // The mirrored instance keeps its outward orientation: the winding is flipped so that the
    // face normal is the transformed normal (node 0 applied to +z as a normal).
    let n_world = |n: DVec3| rotate(r0, n / to(s0)); // inverse-transpose of R*S
    let expected_normal = n_world(DVec3::Z).normalize();
    for f in 2..4 {
        let n = m.mesh.face_area_vector(f).normalize();
        assert!(n.dot(expected_normal) > 0.999, "face {f}: {n} vs {expected_normal}");
    }
    for f in 0..2 {
        let n = m.mesh.face_area_vector(f);
        assert!(n.length() > 0.0);
    }
}

#[test]
fn glb_and_gltf_errors() {
    let bin = square_buffer();
    let json = square_json(r#"{"byteLength":60}"#, "");
    let good = glb(&json, &bin);
    assert!(import_mesh(&good, "ok.glb").is_ok());

    let e = import_err(&good[..1200.min(good.len() - 1)], "x.glb");
    assert_eq!(e.to_string(), format!("x.glb: truncated GLB (header says {} bytes, file has {})", good.len(), good.len() - 1));
    let e = import_err(&good[..7], "x.glb");
    assert!(e.to_string().contains("truncated GLB"), "{e}");
    let e = import_err(b"not a glb at all", "x.glb");
    assert!(e.to_string().starts_with("x.glb: not a GLB file"), "{e}");
    let mut v1 = good.clone();
    v1[4] = 1;
    assert!(matches!(import_err(&v1, "x.glb"), ImportError::Unsupported { .. }));

    let e = import_err(br#"{"asset":{"version":"1.0"},"meshes":{"m":{}}}"#, "old.gltf");
    assert!(matches!(e, ImportError::Unsupported { .. }), "{e}");
    let e = import_err(b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"meshes\": [1,]\n}", "x.gltf");
    assert!(matches!(e, ImportError::Malformed { line: Some(3), .. }), "{e}");
    let e = import_err(br#"{"asset":{"version":"2.0"}}"#, "x.gltf");
    assert_eq!(e.to_string(), "x.gltf: no faces found");
    let e = import_err(br#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"]}"#, "x.gltf");
    assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");

    // Index out of range, accessor outside its view, view outside the buffer.
    let bad_index = {
        let mut b = bin.clone();
        b[48..50].copy_from_slice(&9u16.to_le_bytes());
        b
    };
    let e = import_err(&glb(&json, &bad_index), "x.glb");
    assert!(e.to_string().contains("index 9 is out of range"), "{e}");
    let j = json.replace(r#""count":4"#, r#""count":5"#);
    assert!(import_err(&glb(&j, &bin), "x.glb").to_string().contains("does not fit"));
    let j = json.replace(r#""byteLength":48}"#, r#""byteLength":480}"#);
    assert!(import_err(&glb(&j, &bin), "x.glb").to_string().contains("outside buffer"));
    // Dangling references.
    let j = json.replace(r#""POSITION":0"#, r#""POSITION":7"#);
    assert!(import_err(&glb(&j, &bin), "x.glb").to_string().contains("accessor 7 does not exist"));
    let j = json.replace(r#""buffer":0,"byteOffset":48"#, r#""buffer":3,"byteOffset":48"#);
    assert!(import_mesh(&glb(&j, &bin), "x.glb").is_err());
    let j = square_json(r#"{"byteLength":60}"#, r#","nodes":[{"mesh":0,"children":[0]}],"scenes":[{"nodes":[0,5]}]"#);
    assert!(import_err(&glb(&j, &bin), "x.glb").to_string().contains("node 5 does not exist"));
    // A cycle in the node graph is not followed forever.
    let j = square_json(r#"{"byteLength":60}"#, r#","nodes":[{"mesh":0,"children":[1]},{"children":[0]}],"scenes":[{"nodes":[0]}]"#);
    let m = import_mesh(&glb(&j, &bin), "x.glb").unwrap();
    assert_eq!(m.mesh.face_count(), 2);
    assert!(m.notes.iter().any(|n| n.contains("repeated node")), "{:?}", m.notes);
}

#[test]
fn gltf_huge_declared_counts_are_rejected_cheaply() {
    let bin = square_buffer();
    let json = square_json(r#"{"byteLength":60}"#, "");
    // 6,000,003 indices -> 2,000,001 triangles: rejected before any buffer is read.
    let j = json.replace(r#""count":6"#, r#""count":6000003"#);
    let e = import_err(&glb(&j, &bin), "big.glb");
    assert_eq!(e.to_string(), "big.glb: 2000001 triangles exceed the limit of 2000000");
    let j = json.replace(r#""count":4"#, r#""count":18446744073709551615"#);
    assert!(matches!(import_err(&glb(&j, &bin), "big.glb"), ImportError::TooLarge { .. }));
    let j = json.replace(r#""count":4"#, r#""count":3000000"#);
    assert!(matches!(import_err(&glb(&j, &bin), "big.glb"), ImportError::Malformed { .. }));
    // Many instances of one mesh through the node hierarchy also count (declared counts only:
    // 1000 triangles per instance, 2001 instances).
    let nodes: Vec<String> = (0..2001).map(|_| r#"{"mesh":0}"#.to_string()).collect();
    let roots: Vec<String> = (0..2001).map(|i| i.to_string()).collect();
    let j = square_json(r#"{"byteLength":60}"#, &format!(r#","nodes":[{}],"scenes":[{{"nodes":[{}]}}]"#, nodes.join(","), roots.join(",")))
        .replace(r#""count":6"#, r#""count":3000"#);
    let e = import_err(&glb(&j, &bin), "inst.glb");
    assert!(matches!(e, ImportError::TooLarge { count: 2_001_000, .. }), "{e}");
    // Zero-count accessors with absurd offsets, and absurd strides, are handled without overflow.
    let j = json.replace(r#""count":6,"type":"SCALAR""#, r#""count":0,"byteOffset":18446744073709551615,"type":"SCALAR""#);
    assert!(matches!(import_err(&glb(&j, &bin), "x.glb"), ImportError::Empty { .. }));
    let j = json.replace(r#""byteLength":48}"#, r#""byteLength":48,"byteStride":4000000000}"#);
    assert!(matches!(import_err(&glb(&j, &bin), "x.glb"), ImportError::Malformed { .. }));
    // GLB header declaring a huge length.
    let mut g = glb(&json, &bin);
    g[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(import_err(&g, "x.glb").to_string().contains("truncated GLB"));
    // Chunk declaring a huge length.
    let mut g = glb(&json, &bin);
    g[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(import_err(&g, "x.glb").to_string().contains("truncated GLB"));
}

// ---------------------------------------------------------------------------------------------
// Robustness: truncation and corruption never panic

#[test]
fn truncated_inputs_fail_cleanly() {
    let bin = square_buffer();
    let glb_bytes = glb(&square_json(r#"{"byteLength":60}"#, ""), &bin);
    for cut in 0..glb_bytes.len() {
        assert!(import_mesh(&glb_bytes[..cut], "t.glb").is_err(), "GLB cut at {cut}");
    }
    let buffer = format!(r#"{{"byteLength":60,"uri":"data:application/gltf-buffer;base64,{}"}}"#, b64(&bin));
    let gltf_text = square_json(&buffer, r#","nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]"#);
    assert!(import_mesh(gltf_text.as_bytes(), "t.gltf").is_ok());
    for cut in 0..gltf_text.len() {
        assert!(import_mesh(&gltf_text.as_bytes()[..cut], "t.gltf").is_err(), "glTF cut at {cut}");
    }
    // OBJ prefixes may be valid smaller meshes; they must never panic, and cuts inside the
    // last face's index list must not invent faces.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 3\n";
    for cut in 0..obj.len() {
        if let Ok(m) = import_mesh(&obj.as_bytes()[..cut], "t.obj") {
            assert!(m.mesh.face_count() <= 3);
        }
    }
    let dome = shared_mesh("tri_dome.obj");
    for cut in (0..dome.len()).step_by(97) {
        let _ = import_mesh(&dome[..cut], "tri_dome.obj");
    }
}

#[test]
fn corrupt_inputs_never_panic() {
    let bin = square_buffer();
    let glb_bytes = glb(&square_json(r#"{"byteLength":60}"#, ""), &bin);
    // Every single-byte corruption of a valid GLB.
    for i in 0..glb_bytes.len() {
        for x in [0x00u8, 0xff, 0x7f, b'9', b'"'] {
            let mut g = glb_bytes.clone();
            g[i] = x;
            let _ = import_mesh(&g, "c.glb");
        }
    }
    // Random bytes behind plausible prefixes.
    let mut rng = Lcg(0x5eed);
    let prefixes: [&[u8]; 6] = [b"", b"glTF\x02\x00\x00\x00", b"{", b"v 1 2 3\nf ", b"f 1 2 3\nv ", b"{\"asset\":{\"version\":\"2.0\"},"];
    for round in 0..600 {
        let len = (rng.next() % 200) as usize;
        let mut data = prefixes[round % prefixes.len()].to_vec();
        data.extend((0..len).map(|_| (rng.next() & 0xff) as u8));
        if round % 2 == 0 && data.starts_with(b"glTF") && data.len() >= 12 {
            let n = data.len() as u32;
            data[8..12].copy_from_slice(&n.to_le_bytes());
        }
        for name in ["r.obj", "r.gltf", "r.glb", "r.bin"] {
            let _ = import_mesh(&data, name);
        }
    }
    // Random text made of OBJ tokens.
    let words = ["v", "f", "-1", "1", "2", "3", "0", "1/2/3", "//", "\n", " ", "1e308", "-0", "\\", "#", "vt", "1.5"];
    for _ in 0..300 {
        let n = rng.next() % 60;
        let s: String = (0..n).map(|_| words[(rng.next() as usize) % words.len()]).collect::<Vec<_>>().join(" ");
        let _ = import_mesh(s.as_bytes(), "w.obj");
    }
    // Random JSON-ish glTF fragments.
    let parts = [
        r#"{"asset":{"version":"2.0"},"#,
        r#""accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}],"#,
        r#""accessors":[{"componentType":5125,"count":3,"type":"SCALAR","sparse":{"count":2,"indices":{"bufferView":0,"componentType":5125},"values":{"bufferView":0}}}],"#,
        r#""bufferViews":[{"buffer":0,"byteLength":48,"byteStride":4}],"#,
        r#""buffers":[{"byteLength":48,"uri":"data:;base64,AAAA"}],"#,
        r#""meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":0,"mode":4}]}],"#,
        r#""nodes":[{"mesh":0,"matrix":[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0]}],"#,
        r#""scenes":[{"nodes":[0,0,1]}],"#,
        r#""scene":3,"#,
    ];
    for _ in 0..300 {
        let mut s = String::new();
        for _ in 0..(rng.next() % 8) {
            s += parts[(rng.next() as usize) % parts.len()];
        }
        s += r#""x":0}"#;
        let _ = import_mesh(s.as_bytes(), "j.gltf");
    }
}

// ---------------------------------------------------------------------------------------------
// Welding

#[test]
fn weld_merges_within_tolerance_and_cleans_faces() {
    let positions = vec![
        DVec3::new(0.0, 0.0, 0.0),  // 0
        DVec3::new(1.0, 0.0, 0.0),  // 1
        DVec3::new(0.0, 1.0, 0.0),  // 2
        DVec3::new(1e-9, 0.0, 0.0), // 3: within 1e-7 of 0 -> merged
        DVec3::new(1.0, 1.0, 0.0),  // 4
        DVec3::new(0.0, 1.0, 1e-6), // 5: beyond tolerance of 2 -> stays
        DVec3::new(5.0, 5.0, 5.0),  // 6: unreferenced
        DVec3::new(0.5, 0.0, 0.0),  // 7: collinear with 0 and 1
    ];
    let triangles = vec![
        [0, 1, 2],
        [3, 4, 1], // same as (0,4,1) after merging
        [1, 4, 5],
        [0, 3, 2], // repeated index after merging -> dropped
        [0, 1, 7], // zero area -> dropped
        [2, 1, 0], // duplicate vertex set of face 0 (reversed) -> dropped
        [1, 4, 3], // duplicate of face 1 -> dropped
        [0, 1, 9], // out of range -> dropped
    ];
    let mesh = TriMesh::new(positions, triangles);
    let (out, report) = weld(&mesh, 1e-7);
    assert_eq!(report, WeldReport { merged_vertices: 1, dropped_faces: 5, removed_unreferenced: 2 });
    assert_eq!(out.positions, vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.0, 1.0, 1e-6)]);
    assert_eq!(out.triangles, vec![[0, 1, 2], [0, 3, 1], [1, 3, 4]]);

    // Zero tolerance: only exact duplicates merge (-0.0 == 0.0).
    let m = TriMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(-0.0, 0.0, 0.0), DVec3::new(1e-300, 0.0, 0.0)],
        vec![[0, 1, 2], [3, 1, 2], [4, 1, 2]],
    );
    let (out, report) = weld(&m, 0.0);
    assert_eq!(report.merged_vertices, 1);
    assert_eq!(out.face_count(), 2);
}

#[test]
fn weld_handles_cell_boundaries_and_chains() {
    // Points straddling grid cells at many offsets merge with their partner within tolerance.
    let tol = 1e-3;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut rng = Lcg(7);
    for k in 0..500 {
        let p = DVec3::new(
            (rng.next() % 1000) as f64 * 0.0117 + 20.0 * k as f64,
            (rng.next() % 1000) as f64 * 0.0031,
            -((rng.next() % 1000) as f64) * 0.0053,
        );
        let d = DVec3::new(0.6, -0.5, 0.55).normalize() * tol * 0.999;
        let base = positions.len() as u32;
        positions.extend([p, p + DVec3::new(0.3, 0.0, 0.0), p + DVec3::new(0.0, 0.3, 0.0), p + d]);
        triangles.push([base, base + 1, base + 2]);
        triangles.push([base + 3, base + 2, base + 1]); // duplicate after merging
    }
    let (out, report) = weld(&TriMesh::new(positions, triangles), tol);
    assert_eq!(report.merged_vertices, 500);
    assert_eq!(out.face_count(), 500);
    assert_eq!(out.vertex_count(), 1500);

    // Greedy representatives do not chain: a, a+0.9t, a+1.8t -> the third stays separate.
    let a = DVec3::new(0.1, 0.2, 0.3);
    let m = TriMesh::new(vec![a, a + DVec3::X * 0.9 * tol, a + DVec3::X * 1.8 * tol, DVec3::ONE, DVec3::Y], vec![[0, 3, 4], [1, 3, 4], [2, 4, 3]]);
    let (out, report) = weld(&m, tol);
    assert_eq!(report.merged_vertices, 1);
    assert_eq!(out.face_count(), 2);
}

#[test]
fn import_welds_relative_to_diagonal() {
    // Diagonal ~ 1000: tolerance 1e-4. A duplicate 1e-5 away merges, one 1e-3 away stays.
    let text = "v 0 0 0\nv 1000 0 0\nv 0 1000 0\nv 0.00001 0 0\nv 0 1000.001 0\nv 1000 1000 0\n\
                f 1 2 3\nf 4 6 2\nf 5 2 6\n";
    let m = import_ok(text, "w.obj");
    assert_eq!(m.merged_vertices, 1);
    assert_eq!(m.mesh.vertex_count(), 5);
    assert_eq!(m.stats.boundary_loops, 1);
    assert_eq!(m.dropped_faces, 0);
    assert!(m.notes.iter().any(|n| n.contains("merged 1 coincident")), "{:?}", m.notes);
}

// ---------------------------------------------------------------------------------------------
// Shared reference meshes

#[test]
fn tri_dome_stats() {
    let m = import_mesh(&shared_mesh("tri_dome.obj"), "tri_dome.obj").unwrap();
    assert_eq!(m.stats.vertices, 91);
    assert_eq!(m.stats.faces, 160);
    assert_eq!(m.stats.boundary_loops, 1);
    assert_eq!(m.stats.non_manifold_edges, 0);
    assert_eq!(m.source_polygons, 160);
    assert_eq!(m.merged_vertices, 0);
    assert_eq!(m.dropped_faces, 0);
}

#[test]
fn shared_meshes_import() {
    // (file, source polygons, vertices, triangles, boundary loops, non-manifold edges)
    let expected: [(&str, usize, usize, usize, usize, usize); 8] = [
        ("botanic-garden-bubble-0.obj", 1076, 1121, 2152, 1, 0),
        ("chebyshev_sphere.obj", 400, 441, 800, 1, 0),
        ("cmc1.obj", 240, 272, 480, 2, 0),
        ("conical1.obj", 1080, 1147, 2160, 1, 0),
        ("enneper2.obj", 900, 961, 1800, 1, 0),
        ("flower_cmc1.obj", 1296, 1369, 2592, 1, 0),
        ("tri_dome.obj", 160, 91, 160, 1, 0),
        ("tri_mesh.obj", 2592, 1344, 2592, 2, 0),
    ];
    println!(
        "{:<28} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}",
        "file", "polys", "verts", "tris", "loops", "nm", "bverts", "merged", "dropped"
    );
    for (name, polys, verts, tris, loops, nm) in expected {
        let m = import_mesh(&shared_mesh(name), name).unwrap_or_else(|e| panic!("{e}"));
        let s = m.stats;
        println!(
            "{:<28} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}  {:?}",
            name,
            m.source_polygons,
            s.vertices,
            s.faces,
            s.boundary_loops,
            s.non_manifold_edges,
            s.boundary_vertices,
            m.merged_vertices,
            m.dropped_faces,
            m.notes
        );
        assert_eq!(m.source_polygons, polys, "{name}");
        assert_eq!((s.vertices, s.faces, s.boundary_loops, s.non_manifold_edges), (verts, tris, loops, nm), "{name}");
        assert_eq!((m.merged_vertices, m.dropped_faces), (0, 0), "{name}");
        // The sources are consistently oriented; triangulation must keep that: no directed
        // edge occurs twice.
        let mut directed: Vec<(u32, u32)> = m.mesh.triangles.iter().flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]).collect();
        directed.sort_unstable();
        assert!(directed.windows(2).all(|w| w[0] != w[1]), "{name}: inconsistent orientation");
    }
}

#[test]
fn gltf_interleaved_quantized_and_sparse_accessors() {
    // Interleaved view (stride 16): u16 normalized position xyz + 2 bytes padding + 2 f32 junk.
    let raw: [[u16; 3]; 4] = [[0, 0, 0], [65535, 0, 0], [65535, 65535, 0], [0, 65535, 0]];
    let mut bin = Vec::new();
    for p in raw {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
        bin.extend([0u8; 2]);
        bin.extend(7.5f32.to_le_bytes());
        bin.extend(7.5f32.to_le_bytes());
    }
    bin.extend([0u8, 1, 2, 0, 2, 3]); // u8 indices at 64
    bin.extend([0u8, 0]); // pad to 72
    bin.extend([1u32, 2].iter().flat_map(|i| i.to_le_bytes())); // sparse indices at 72
    bin.extend(f32_bytes(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0])); // sparse values at 80
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsRequired":["KHR_mesh_quantization"],
  "buffers":[{{"byteLength":{}}}],
  "bufferViews":[{{"buffer":0,"byteLength":64,"byteStride":16}},{{"buffer":0,"byteOffset":64,"byteLength":6}},
                 {{"buffer":0,"byteOffset":72,"byteLength":8}},{{"buffer":0,"byteOffset":80,"byteLength":24}}],
  "accessors":[{{"bufferView":0,"componentType":5123,"normalized":true,"count":4,"type":"VEC3"}},
               {{"bufferView":1,"componentType":5121,"count":6,"type":"SCALAR"}},
               {{"componentType":5126,"count":3,"type":"VEC3",
                 "sparse":{{"count":2,"indices":{{"bufferView":2,"componentType":5125}},"values":{{"bufferView":3}}}}}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}},
            {{"primitives":[{{"attributes":{{"POSITION":2}}}}]}}],
  "nodes":[{{"mesh":0}},{{"mesh":1,"translation":[0,0,1]}}],"scenes":[{{"nodes":[0,1]}}]}}"#,
        bin.len()
    );
    let m = import_mesh(&glb(&json, &bin), "q.glb").unwrap();
    assert_eq!(
        m.mesh.positions,
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y, DVec3::Z, DVec3::new(1.0, 0.0, 1.0), DVec3::new(0.0, 1.0, 1.0)]
    );
    assert_eq!(m.mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]]);
    assert!(m.notes.is_empty(), "{:?}", m.notes);
    // A sparse index beyond the accessor count is an error, not a panic.
    let mut bad = bin.clone();
    bad[72..76].copy_from_slice(&3u32.to_le_bytes());
    let e = import_err(&glb(&json, &bad), "q.glb");
    assert!(e.to_string().contains("sparse index 3 is out of range"), "{e}");
}

#[test]
fn format_detection() {
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    assert_eq!(detect_format(obj, "a.OBJ"), Some(Format::Obj));
    assert_eq!(detect_format(obj, "a.txt"), None);
    assert_eq!(import_mesh(obj, "a.txt").unwrap().format, Format::Obj);
    assert_eq!(detect_format(b"glTF....", "a.obj"), Some(Format::Glb));
    assert_eq!(detect_format(b"  {", "a.glb"), Some(Format::Gltf));
    assert_eq!(detect_format(b"solid x", "a.gltf"), Some(Format::Gltf));
    let e = import_err(b"solid cube\nfacet normal 0 0 1\n", "cube.stl");
    assert!(matches!(e, ImportError::Unsupported { .. }), "{e}");
    assert!(e.to_string().starts_with("cube.stl: cannot import '.stl' files"), "{e}");
}

/// Large-input timing (run with `cargo test --release --test import -- --ignored --nocapture`).
#[test]
#[ignore]
fn large_mesh_timing() {
    let n = 1000; // n x n quads -> 2,000,000 triangles
    let mut s = String::with_capacity(40 * (n + 1) * (n + 1) + 30 * n * n);
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            s += &format!("v {x} {y} {}\n", (x * 3.0).sin() * (y * 2.0).cos());
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            s += &format!("f {} {} {} {}\n", id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
        }
    }
    let t = std::time::Instant::now();
    let m = import_mesh(s.as_bytes(), "big.obj").unwrap();
    println!("OBJ {} MB: {:?}, {:?}", s.len() >> 20, t.elapsed(), m.stats);
    assert_eq!(m.stats.faces, 2 * n * n);
    assert_eq!(m.stats.boundary_loops, 1);

    // The same as an unindexed triangle soup in a GLB: 6M vertices to weld.
    let mut pos: Vec<f32> = Vec::with_capacity(9 * m.mesh.face_count());
    for t in &m.mesh.triangles {
        for &v in t {
            let p = m.mesh.positions[v as usize];
            pos.extend([p.x as f32, p.y as f32, p.z as f32]);
        }
    }
    let bin = f32_bytes(&pos);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{}}}],"bufferViews":[{{"buffer":0,"byteLength":{}}}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3"}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}]}}"#,
        bin.len(),
        bin.len(),
        pos.len() / 3
    );
    let g = glb(&json, &bin);
    let t = std::time::Instant::now();
    let m2 = import_mesh(&g, "big.glb").unwrap();
    println!("GLB {} MB: {:?}, {:?}, merged {}", g.len() >> 20, t.elapsed(), m2.stats, m2.merged_vertices);
    assert_eq!(m2.stats.faces, 2 * n * n);
    assert_eq!(m2.stats.vertices, (n + 1) * (n + 1));
}

/// Mutation fuzzing of valid seeds (run with `-- --ignored`; in debug mode to catch overflow).
#[test]
#[ignore]
fn fuzz_mutations_long() {
    let bin = square_buffer();
    let buffer = format!(r#"{{"byteLength":60,"uri":"data:application/gltf-buffer;base64,{}"}}"#, b64(&bin));
    let seeds: Vec<(Vec<u8>, &str)> = vec![
        (
            glb(
                &square_json(
                    r#"{"byteLength":60}"#,
                    r#","nodes":[{"mesh":0,"children":[1]},{"mesh":0,"rotation":[0,0,1,0]}],"scenes":[{"nodes":[0]}]"#,
                ),
                &bin,
            ),
            "f.glb",
        ),
        (square_json(&buffer, r#","nodes":[{"mesh":0,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}],"scenes":[{"nodes":[0]}]"#).into_bytes(), "f.gltf"),
        (b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 3 3 0\nf 1 2 3 4\nf 2 5 6 3\nf -1 -2 -3 -4 -5 -6\n".to_vec(), "f.obj"),
    ];
    let mut rng = Lcg(12345);
    let digits =
        [b"0".as_slice(), b"4294967295", b"-1", b"1e308", b"99999999999", b"65535", b"2147483648", b"3", b"5125", b"5126", b"\"a\"", b"null"];
    let mut oks = 0;
    for iter in 0..300_000 {
        let (seed, name) = &seeds[iter % seeds.len()];
        let mut d = seed.clone();
        let k = 1 + rng.next() % 4;
        for _ in 0..k {
            if d.is_empty() {
                break;
            }
            let at = rng.next() as usize % d.len();
            match rng.next() % 5 {
                0 => d[at] = rng.next() as u8,
                1 => {
                    d.remove(at);
                }
                2 => d.insert(at, rng.next() as u8),
                3 => {
                    // replace a digit run with an extreme number
                    let mut e = at;
                    while e < d.len() && d[e].is_ascii_digit() {
                        e += 1;
                    }
                    let rep = digits[rng.next() as usize % digits.len()];
                    d.splice(at..e, rep.iter().copied());
                }
                _ => d.truncate(at),
            }
        }
        if name.ends_with(".glb") && d.len() >= 12 && rng.next().is_multiple_of(2) {
            let n = d.len() as u32;
            d[8..12].copy_from_slice(&n.to_le_bytes());
        }
        if import_mesh(&d, name).is_ok() {
            oks += 1;
        }
    }
    println!("ok results: {oks}");
}

/// OBJ quads stay quads (faces of 4 corners) beside the triangulation the algorithms use, and
/// triangulating them gives that triangulation back, triangle for triangle.
#[test]
fn quads_stay_quads() {
    use spherical_faces::geometry::mesh::topology::Topology;
    let q = import_mesh(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 3\n", "q.obj").unwrap();
    assert_eq!(q.faces.iter().map(|f| f.len()).collect::<Vec<_>>(), [4, 3]);
    assert_eq!(q.mesh.face_count(), 3);
    assert_eq!(q.surface().triangulated(), q.mesh);
    // The quad's drawn edges: 4 of its own and the triangle's 2 others, no diagonal.
    assert_eq!(Topology::new(&q.surface()).edges().len(), 6);
    // A quad whose other diagonal is the valid one is stored from that diagonal's corner.
    let concave = import_mesh(b"v 0 0 0\nv 2 0 0\nv 0.5 0.5 0\nv 0 2 0\nf 1 2 3 4\n", "c.obj").unwrap();
    assert_eq!(concave.faces.len(), 1);
    assert_eq!(concave.surface().triangulated(), concave.mesh);
    // A quad that welds into a triangle is a triangle.
    let welded = import_mesh(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 1 1 0\nf 1 2 3 4\n", "w.obj").unwrap();
    assert_eq!(welded.faces.iter().map(|f| f.len()).collect::<Vec<_>>(), [3]);
    // The bubble is made of quads.
    let bubble = import_mesh(&shared_mesh("botanic-garden-bubble-0.obj"), "bubble.obj").unwrap();
    assert_eq!(bubble.faces.len(), 1076);
    assert!(bubble.faces.iter().all(|f| f.len() == 4));
    assert_eq!(bubble.surface().triangulated(), bubble.mesh);
    let dome = import_mesh(&shared_mesh("tri_dome.obj"), "tri_dome.obj").unwrap();
    assert!(dome.faces.iter().all(|f| f.len() == 3));
    assert_eq!(dome.surface().triangulated(), dome.mesh);
}
