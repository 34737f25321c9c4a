//! The fuzz oracles: one function per fuzz target, each taking the raw input bytes and panicking
//! (with a message saying which property broke) when the library misbehaves.
//!
//! Shared verbatim by the fuzz targets (`fuzz/fuzz_targets/*.rs`) and by the replay test
//! (`tests/fuzz_replay.rs`), both through `#[path = ".../oracles.rs"] mod oracles;`, so this file
//! depends only on `spherical_faces` and `std`.
#![allow(dead_code)]

use spherical_faces::design_link::{Design, DesignSurface};
use spherical_faces::import::{import_file, Imported, ImportedBSpline, ImportedFile};
use spherical_faces::pipeline::fields::Field;
use spherical_faces::pipeline::protocol::{decode_from_worker, decode_to_worker, encode_from_worker, encode_to_worker, Envelope};

/// The fuzz targets, by name (the binaries in fuzz/Cargo.toml, the folders in fuzz/corpus/).
pub const TARGETS: [&str; 5] = ["obj", "gltf", "bspline", "design_link", "protocol"];

/// Runs the oracle of `target` on `data`.
pub fn run(target: &str, data: &[u8]) {
    match target {
        "obj" => obj(data),
        "gltf" => gltf(data),
        "bspline" => bspline(data),
        "design_link" => design_link(data),
        "protocol" => protocol(data),
        other => panic!("unknown fuzz target '{other}'"),
    }
}

// --- importers ---------------------------------------------------------------------------------

/// OBJ: the importer never panics; what it returns is a valid mesh.
pub fn obj(data: &[u8]) {
    check_import(data, "fuzz.obj");
}

/// glTF and GLB (the GLB magic picks the name; content detection comes first anyway).
pub fn gltf(data: &[u8]) {
    let name = if data.starts_with(b"glTF") { "fuzz.glb" } else { "fuzz.gltf" };
    check_import(data, name);
}

/// The authors' B-spline JSON.
pub fn bspline(data: &[u8]) {
    check_import(data, "fuzz.json");
}

fn check_import(data: &[u8], name: &str) {
    match import_file(data, name) {
        Ok(ImportedFile::Mesh(m)) => check_mesh(&m),
        Ok(ImportedFile::BSpline(b)) => check_bspline(&b),
        Err(e) => {
            // Documented: every failure's message starts with the file name.
            assert_eq!(e.file(), name, "error names another file: {e}");
            let msg = e.to_string();
            assert!(msg.starts_with(name), "error message does not start with the file name: {msg}");
        }
    }
}

fn check_mesh(m: &Imported) {
    let n = m.mesh.positions.len();
    if let Some(i) = m.mesh.positions.iter().position(|p| !p.is_finite()) {
        panic!("imported vertex {i} is not finite: {:?}", m.mesh.positions[i]);
    }
    assert!(!m.mesh.triangles.is_empty(), "import succeeded with no triangles");
    let mut referenced = vec![false; n];
    for (f, t) in m.mesh.triangles.iter().enumerate() {
        for &v in t {
            assert!((v as usize) < n, "triangle {f} {t:?} refers to vertex {v}; the mesh has {n}");
            referenced[v as usize] = true;
        }
        assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "triangle {f} {t:?} repeats a vertex");
    }
    if let Some(v) = referenced.iter().position(|r| !r) {
        panic!("vertex {v} of {n} is referenced by no triangle (the importer removes unused vertices)");
    }
    // `faces`: 3 or 4 corners in range, and triangulating them gives `mesh.triangles` in order.
    let mut tris = Vec::with_capacity(m.mesh.triangles.len());
    for (f, face) in m.faces.iter().enumerate() {
        assert!(matches!(face.len(), 3 | 4), "face {f} has {} corners", face.len());
        for &v in face.corners() {
            assert!((v as usize) < n, "face {f} {:?} refers to vertex {v}; the mesh has {n}", face.corners());
        }
        tris.extend(face.triangles());
    }
    assert!(tris == m.mesh.triangles, "the faces do not triangulate to the mesh's triangles");
}

fn check_bspline(b: &ImportedBSpline) {
    let s = &b.surface;
    if let Some(i) = s.control_points().iter().position(|p| !p.is_finite()) {
        panic!("control point {i} is not finite: {:?}", s.control_points()[i]);
    }
    if let Some(i) = s.weights().iter().position(|w| !(w.is_finite() && *w > 0.0)) {
        panic!("weight {i} is {} (must be finite and positive)", s.weights()[i]);
    }
    assert_eq!(s.control_points().len(), s.basis_u().count() * s.basis_v().count(), "control grid size");
    // The surface's points are finite wherever its data is of sane magnitude (beyond that,
    // 1e308-sized coordinates may overflow honestly: the importer accepts finite numbers).
    let sane = |x: f64| x.abs() <= 1e100;
    let sane_data = s.control_points().iter().all(|p| sane(p.x) && sane(p.y) && sane(p.z))
        && s.weights().iter().all(|&w| (1e-100..=1e100).contains(&w))
        && s.basis_u().knots().iter().chain(s.basis_v().knots()).all(|&t| sane(t));
    if sane_data {
        let (grid, _) = s.tessellate([4, 4]);
        if let Some(i) = grid.positions.iter().position(|p| !p.is_finite()) {
            panic!("surface point {i} of a 4×4 grid is not finite: {:?}", grid.positions[i]);
        }
    }
}

// --- design link -------------------------------------------------------------------------------

/// A link the app writes reads back to itself, silently: for any input, `d.to_fragment()` is a
/// fixed point of parse-then-write and parsing it yields no notice (except the one that asks for
/// the user's own file again, which every link naming a file gets by design).
pub fn design_link(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let (d, _) = Design::from_fragment(&text);
    let first = d.to_fragment();
    let (d2, notices) = Design::from_fragment(&first);
    let own_file = matches!(d2.reference, DesignSurface::OwnFile(_));
    let notices: Vec<&String> = notices.iter().filter(|n| !(own_file && n.starts_with("this design uses the file"))).collect();
    assert!(notices.is_empty(), "the app-written link {first:?} reads back with notices {notices:?}");
    let second = d2.to_fragment();
    assert_eq!(second, first, "the app-written link is not a fixed point of read-then-write");
}

// --- worker protocol ---------------------------------------------------------------------------

/// The envelope of fuzz input: the JSON header up to the first 0 byte; after it, the binary
/// bodies, each as a u32 little-endian length and that many bytes (the last one takes what
/// remains when the length runs past the end). No 0 byte: no bodies.
pub fn protocol_envelope(data: &[u8]) -> Envelope {
    let (json, rest) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    };
    let mut bodies = Vec::new();
    if let Some(mut rest) = rest {
        while !rest.is_empty() {
            let (len, tail) = match rest.split_first_chunk::<4>() {
                Some((len, tail)) => (u32::from_le_bytes(*len) as usize, tail),
                None => (rest.len(), rest),
            };
            let len = len.min(tail.len());
            bodies.push(tail[..len].to_vec());
            rest = &tail[len..];
        }
    }
    Envelope { json: String::from_utf8_lossy(json).into_owned(), bodies }
}

/// The inverse of [`protocol_envelope`] (for writing seeds).
pub fn protocol_bytes(env: &Envelope) -> Vec<u8> {
    let mut out = env.json.as_bytes().to_vec();
    if !env.bodies.is_empty() {
        out.push(0);
        for b in &env.bodies {
            out.extend_from_slice(&(b.len() as u32).to_le_bytes());
            out.extend_from_slice(b);
        }
    }
    out
}

/// Both directions: whatever decodes re-encodes to something that decodes to the same message
/// and fields, and encoding that again gives the same envelope.
pub fn protocol(data: &[u8]) {
    let env = protocol_envelope(data);

    if let Ok((msg, body)) = decode_to_worker(&env) {
        let env2 = encode_to_worker(&msg, body.map(<[u8]>::to_vec));
        let (msg2, body2) = decode_to_worker(&env2).unwrap_or_else(|e| panic!("re-encoded ToWorker {:?} does not decode: {e}", env2.json));
        assert_eq!(format!("{msg2:?}"), format!("{msg:?}"), "ToWorker changed in a round trip through {:?}", env2.json);
        assert_eq!(body2, body, "the ToWorker body changed in a round trip");
        let env3 = encode_to_worker(&msg2, body2.map(<[u8]>::to_vec));
        assert_eq!(env3, env2, "encoding a ToWorker is not stable");
    }

    if let Ok((msg, fields)) = decode_from_worker(&env) {
        let env2 = encode_from_worker(&msg, &fields);
        let (msg2, fields2) = decode_from_worker(&env2).unwrap_or_else(|e| panic!("re-encoded FromWorker {:?} does not decode: {e}", env2.json));
        assert_eq!(format!("{msg2:?}"), format!("{msg:?}"), "FromWorker changed in a round trip through {:?}", env2.json);
        assert_eq!(format!("{fields2:?}"), format!("{fields:?}"), "fields changed in a round trip");
        let env3 = encode_from_worker(&msg2, &fields2);
        assert_eq!(env3, env2, "encoding a FromWorker is not stable");
        // Fields rebuilt from bytes give the same bytes back.
        for (f, b) in fields.iter().zip(&env.bodies) {
            assert_eq!(&Field::to_bytes(f), b, "field '{}' does not give back its bytes", f.name);
        }
    }
}
