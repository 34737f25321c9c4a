//! Rhino .3dm import: `tests/data/3dm/*.3dm` (written by its `make_3dm.py` from the shared B-spline
//! surfaces) read through the rhino3dm package under Node, as the CLI reads them, equal the JSON
//! surfaces to 1e-12; the CLI opens them, lists and picks objects, and SQ runs on one. Needs Node
//! and `npm ci` in `www/rhino3dm` (done by `bash www/dev.sh test`).
#![cfg(not(target_arch = "wasm32"))]

mod common;

use std::process::Command;

use spherical_faces::geometry::bspline::BSplineSurface;
use spherical_faces::import::{import_file, ImportedFile};

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_spherical-faces")).args(args).output().expect("runs")
}

fn converted(file: &str, object: Option<usize>) -> String {
    let mut cmd = Command::new("node");
    cmd.arg("www/rhino3dm/cli.mjs").arg(file);
    if let Some(k) = object {
        cmd.args(["--object", &k.to_string()]);
    }
    let out = cmd.output().expect("node runs (the .3dm import needs Node.js)");
    assert!(out.status.success(), "{file}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

fn spline(bytes: &[u8], name: &str) -> BSplineSurface {
    match import_file(bytes, name).unwrap() {
        ImportedFile::BSpline(b) => b.surface,
        ImportedFile::Mesh(_) => panic!("{name}: a mesh"),
    }
}

/// max over a 21 × 21 grid of the domain of |f − g| (points and first derivatives), relative to
/// the control polygon's size.
fn assert_same_surface(f: &BSplineSurface, g: &BSplineSurface, what: &str) {
    assert_eq!(f.domain(), g.domain(), "{what}");
    let ((u0, u1), (v0, v1)) = f.domain();
    let (lo, hi) = g.control_points().iter().fold((glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let size = (hi - lo).length();
    let mut worst: f64 = 0.0;
    for i in 0..=20 {
        for j in 0..=20 {
            let (u, v) = (u0 + (u1 - u0) * i as f64 / 20.0, v0 + (v1 - v0) * j as f64 / 20.0);
            let (a, b) = (f.derivatives(u, v), g.derivatives(u, v));
            worst = worst.max((a.s - b.s).length()).max((a.su - b.su).length() * (u1 - u0)).max((a.sv - b.sv).length() * (v1 - v0));
        }
    }
    assert!(worst <= 1e-12 * size, "{what}: differs by {worst:e} (size {size})");
}

#[test]
fn rhino_surfaces_equal_the_json_ones() {
    for name in ["tunnel_arch", "paraboloid_dome", "torus_patch", "cylinder_patch"] {
        let json = std::fs::read(format!("../shared/data/bsplines/{name}.json")).unwrap();
        let want = spline(&json, &format!("{name}.json"));
        let text = converted(&format!("tests/data/3dm/{name}.3dm"), None);
        let got = spline(text.as_bytes(), &format!("{name}.3dm"));
        assert_same_surface(&got, &want, name);
    }
    // The file with several objects: pick the torus by index.
    let text = converted("tests/data/3dm/mixed.3dm", Some(2));
    let want = spline(&std::fs::read("../shared/data/bsplines/torus_patch.json").unwrap(), "torus_patch.json");
    assert_same_surface(&spline(text.as_bytes(), "mixed.3dm"), &want, "mixed.3dm object 2");
}

#[test]
fn the_cli_opens_3dm_lists_its_objects_and_runs_sq() {
    let out = cli(&["info", "tests/data/3dm/mixed.3dm", "--list-objects"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let objects: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let kinds: Vec<&str> = objects.iter().map(|o| o["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds, ["mesh", "surface", "surface"]);
    // The mesh, picked.
    let out = cli(&["info", "tests/data/3dm/mixed.3dm", "--object", "0"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["faces"], 8, "4 quads, triangulated");
    // Not a .3dm: refused with the reason.
    let garbage = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("sf-garbage.3dm");
    std::fs::write(&garbage, b"not a rhino file at all, just text").unwrap();
    let out = cli(&["info", garbage.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a readable Rhino .3dm file"));
    // SQ on the arch from Rhino, up to the quad mesh.
    let dir = common::temp_dir("sf-3dm-sq");
    let out = cli(&["sq", "tests/data/3dm/tunnel_arch.3dm", "--until", "remesh", "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    assert!(report["output"]["faces"].as_u64().unwrap() > 100, "{}", report["output"]);
}

/// A .3dm file brings its model unit: the moulds' tolerance (2 mm by default) is read in it, and
/// `--units` overrides it.
#[test]
fn a_3dm_file_brings_its_model_units() {
    let dir = common::temp_dir("sf-3dm-units");
    let d = dir.to_str().unwrap();
    let report = |extra: &[&str]| {
        let mut args = vec!["st-support", "tests/data/3dm/mixed.3dm", "--object", "1", "--out", d, "-q"];
        args.extend_from_slice(extra);
        let out = cli(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice::<serde_json::Value>(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
    };
    let r = report(&[]);
    assert_eq!(r["moulds"]["units"], "mm", "the file is in millimetres");
    assert_eq!(r["moulds"]["tolerance"], 2.0);
    let r = report(&["--units", "m"]);
    assert_eq!(r["moulds"]["units"], "m");
    assert_eq!(r["moulds"]["tolerance"], 0.002);
    let _ = std::fs::remove_dir_all(&dir);
}
