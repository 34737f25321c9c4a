//! Helpers shared by the native tests: the shared data, the reference meshes, the Khronos glTF
//! validator. A missing `../shared` fails loudly: CI always has it beside the repo.
#![allow(dead_code)] // each test file uses some of these

use std::path::{Path, PathBuf};

use serde_json::Value;
use spherical_faces::geometry::mesh::TriMesh;
use spherical_faces::import::import_mesh;
use spherical_faces::reference::Reference;

/// A file of `../shared`, e.g. `data/meshes/tri_mesh.obj`.
pub fn shared_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared").join(relative)
}

/// The bytes of a file of `../shared` (panics, naming it, when it is missing).
pub fn shared_bytes(relative: &str) -> Vec<u8> {
    let path = shared_path(relative);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e} (../shared must be beside the repo)", path.display()))
}

/// A mesh of `../shared/data/meshes` (name without `.obj`), through the crate's importer.
pub fn load(name: &str) -> TriMesh {
    let bytes = shared_bytes(&format!("data/meshes/{name}.obj"));
    import_mesh(&bytes, &format!("{name}.obj")).expect("imports").mesh
}

/// [`load`] as a reference surface.
pub fn load_reference(name: &str) -> Reference {
    Reference::from_triangles(load(name))
}

/// Runs tests/e2e/validate-gltf.mjs (the Khronos glTF validator) on `file`; returns whether it
/// passed and its JSON summary. Panics (test failure) when the validator is not installed.
pub fn khronos_validate(file: &Path) -> (bool, Value) {
    let e2e = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/e2e");
    assert!(
        e2e.join("node_modules").join("gltf-validator").is_dir(),
        "the Khronos glTF validator is not installed: run `npm ci` in tests/e2e (it is a devDependency there)"
    );
    let out = std::process::Command::new("node")
        .arg(e2e.join("validate-gltf.mjs"))
        .arg(file)
        .current_dir(&e2e)
        .output()
        .unwrap_or_else(|e| panic!("cannot run `node` ({e}); install Node.js and run `npm ci` in tests/e2e"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let json: Value = serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("validate-gltf.mjs printed no JSON ({e}); stdout: {stdout}; stderr: {}", String::from_utf8_lossy(&out.stderr)));
    (out.status.success(), json)
}

/// A fresh temporary folder for one test, under cargo's target/tmp (reused by the next run, so
/// runs leave nothing behind in the system's temporary folder).
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("sf-test-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
