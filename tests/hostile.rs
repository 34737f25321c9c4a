//! Hostile inputs: every file of the corpus (`tests/data/hostile/`, written by its
//! `make_corpus.py`, and `../shared/data/hostile/`) through import, `info` and each method, and one
//! test per known defect. Asserted: no panic; success or a clear error naming the cause; no NaN or
//! null where a number belongs; bounded work, by counts (neighbourhood sizes, remesh operations,
//! tessellation triangles per panel), never by wall time.
#![cfg(not(target_arch = "wasm32"))] // native: reads files, spawns the CLI

use spherical_faces::pipeline::method::export;
use spherical_faces::pipeline::stages::st_adapted::StAdaptedStage;
use spherical_faces::pipeline::stages::st_support::StSupportStage;
use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;
use spherical_faces::congruence::central_spheres::{JetParams, MAX_NEIGHBOURHOOD};
use spherical_faces::design_link::Design;
use spherical_faces::export::Report;
use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::geometry::mesh::TriMesh;
use spherical_faces::import::import_mesh;
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::panels::panel::Panel;
use spherical_faces::panels::tessellate::MAX_PANEL_TRIANGLES;
use spherical_faces::panels::{level_cap, PANEL_TRIANGLE_BUDGET};
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::pipeline::stages;
use spherical_faces::progress::{ignore, Clock};
use spherical_faces::reference::assumptions::Warning;
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::{face_cap, pliant_remesh_with_stats, RemeshParams, Sizing, SizingField, MAX_METHOD_FACES};
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_adapted::StAdaptedError;
use spherical_faces::st_support::{StSupportError, StSupportParams};

const SHARED: &str = "../shared/data/hostile";
const OWN: &str = "tests/data/hostile";

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_spherical-faces")).args(args).output().expect("runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("sf-hostile-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn load(path: &Path) -> Result<Loaded, String> {
    let bytes = std::fs::read(path).unwrap();
    Loaded::from_file(&bytes, &path.file_name().unwrap().to_string_lossy()).map_err(|e| e.to_string())
}

/// A message a user can read: one line, no control characters, names the file.
fn assert_clear(message: &str, file: &str) {
    assert!(!message.is_empty() && !message.contains('\n'), "{file}: {message:?}");
    assert!(!message.chars().any(char::is_control), "{file}: control characters in {message:?}");
}

/// No null and no non-finite number anywhere in a report, except Ω's documented nulls (its centre
/// and R² at infinity, its axis and offset when finite).
fn assert_numbers(v: &serde_json::Value, at: &str) {
    match v {
        serde_json::Value::Null => {
            let allowed = ["absolute_sphere.center", "absolute_sphere.r2", "absolute_sphere.axis", "absolute_sphere.d"];
            assert!(allowed.iter().any(|a| at.ends_with(a)), "null at {at}");
        }
        serde_json::Value::Number(n) => {
            assert!(n.as_f64().is_some_and(f64::is_finite), "{at} = {n}")
        }
        serde_json::Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| assert_numbers(x, &format!("{at}[{i}]"))),
        serde_json::Value::Object(o) => o.iter().for_each(|(k, x)| assert_numbers(x, &format!("{at}.{k}"))),
        _ => {}
    }
}

fn assert_report(report: &Report, file: &str) {
    assert_numbers(&serde_json::to_value(report).unwrap(), file);
}

fn assert_bounded_panels(panels: &[Panel], file: &str) {
    let most = panels.iter().map(|p| p.triangles.len()).max().unwrap_or(0);
    assert!(most <= MAX_PANEL_TRIANGLES, "{file}: a panel of {most} triangles");
}

fn corpus() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in [OWN, SHARED] {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ["obj", "gltf", "glb", "json"].contains(&ext) {
                files.push(p);
            }
        }
    }
    files.sort();
    assert!(files.len() >= 14, "{files:?}");
    files
}

/// Every corpus file: import, the curvature `info` shows, ST with support structure and ST
/// (uniform, small) end in a result or a clear error; results have finite reports and bounded
/// panels and neighbourhoods.
#[test]
fn every_hostile_file_gets_a_bounded_clear_answer() {
    for path in corpus() {
        let file = path.display().to_string();
        let loaded = match load(&path) {
            Ok(l) => l,
            Err(message) => {
                assert_clear(&message, &file);
                continue;
            }
        };
        let reference = &loaded.surface;
        let field = reference.curvature(&JetParams::default(), &mut ignore).unwrap();
        assert!(field.summary.largest_neighbourhood <= MAX_NEIGHBOURHOOD, "{file}");
        assert!(field.vertices.iter().all(|c| c.mean.is_finite()), "{file}");
        let clock = Clock(None);
        // The raw input when small; a remesh of a large one (the ST-support run on 5000 raw
        // faces is bounded too, but takes minutes in a test build).
        let remesh = if reference.mesh().face_count() <= 2000 { Sizing::None } else { Sizing::UniformFaces(300) };
        let params = StSupportParams { remesh, ..StSupportParams::default() };
        match spherical_faces::st_support::compute(reference, &params, &Fabrication::default(), clock, &mut ignore) {
            Ok(result) => {
                assert_bounded_panels(&result.panels, &file);
                let (report, _) = export::<StSupportStage>(reference, &result, &params, &Fabrication::default(), clock);
                assert_report(&report, &file);
            }
            Err(e) => assert_clear(&e.to_string(), &file),
        }
        let params = StAdaptedParams { sizing: Sizing::UniformFaces(60), ..StAdaptedParams::default() };
        match spherical_faces::st_adapted::compute(reference, &params, &Fabrication::default(), clock, &mut |_| Ok(())) {
            Ok(result) => {
                assert_bounded_panels(&result.panels, &file);
                assert!(result.remeshed.face_count() <= 180, "{file}: {} faces for 60", result.remeshed.face_count());
                let (report, _) = export::<StAdaptedStage>(reference, &result, &params, &Fabrication::default(), clock);
                assert_report(&report, &file);
            }
            Err(e) => assert_clear(&e.to_string(), &file),
        }
    }
}

// --- 0. Pliant remeshing is bounded by construction ------------------------------------------------

/// The 4-face reproducer: a uniform remesh to N either reaches about N or is refused, and its
/// splits never outgrow the cap (4 × the faces the field asks for + 2 × the input's).
#[test]
fn remeshing_a_tiny_mesh_reaches_its_target_or_refuses() {
    let reference = load(&Path::new(SHARED).join("remesh_runaway_4faces.obj")).unwrap().surface;
    let mesh = reference.mesh();
    for n in [12, 100, 1000] {
        let sizing = SizingField::uniform_for_face_count(mesh, n);
        let cap = face_cap(mesh, &sizing);
        assert!(cap <= 8 * n + 2 * mesh.face_count() + 64, "cap {cap} for {n}");
        let out = pliant_remesh_with_stats(mesh, &sizing, &RemeshParams::default(), &mut ignore).unwrap();
        let splits: usize = out.rounds.iter().map(|r| r.splits).sum();
        assert!(out.mesh.face_count() <= cap, "{} faces over the cap {cap}", out.mesh.face_count());
        assert!(splits <= out.rounds.len() * cap, "{splits} splits");
        let st = StAdaptedParams { sizing: Sizing::UniformFaces(n), ..StAdaptedParams::default() };
        match spherical_faces::st_adapted::compute(&reference, &st, &Fabrication::default(), Clock(None), &mut |_| Ok(())) {
            Ok(r) => assert!((n / 3..=3 * n).contains(&r.remeshed.face_count()), "{} faces for {n}", r.remeshed.face_count()),
            Err(e) => assert!(matches!(e, StAdaptedError::Remesh(..)) && e.to_string().contains("remesh"), "{e}"),
        }
    }
}

// --- 1. Every count the user types is capped, the same everywhere ---------------------------------

#[test]
fn face_counts_are_capped_in_the_cli_and_the_link() {
    let dome = format!("{SHARED}/dome20.obj");
    for cmd in ["st", "st-support"] {
        let out = cli(&[cmd, &dome, "--faces", "18446744073709551615", "--out", scratch("faces").to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{cmd}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("200000") && err.lines().count() == 1, "{err}");
    }
    let (d, notices) = Design::from_fragment("#v=1&method=st&sizing=faces&faces=200001");
    assert_eq!(notices.len(), 1, "{notices:?}");
    assert_ne!(d.params::<spherical_faces::pipeline::stages::st_adapted::StAdaptedStage>().sizing, Sizing::UniformFaces(200_001));
}

// --- 2. Curvature is linear in the input ------------------------------------------------------------

#[test]
fn a_vertex_of_huge_valence_keeps_fits_bounded_and_big_polygons_have_no_hub() {
    let fan = load(&Path::new(OWN).join("fan_5000.obj")).unwrap().surface;
    let field = fan.curvature(&JetParams::default(), &mut ignore).unwrap();
    assert!(field.summary.largest_neighbourhood <= MAX_NEIGHBOURHOOD);
    let ngon = import_mesh(&std::fs::read(Path::new(OWN).join("ngon_1500.obj")).unwrap(), "ngon_1500.obj").unwrap();
    let mesh = ngon.surface().triangulated();
    let topo = Topology::new(&mesh);
    let valence = (0..topo.vertex_count()).map(|v| topo.vertex_neighbors(v).len()).max().unwrap();
    assert_eq!(mesh.face_count(), 1498);
    assert!(valence <= 4, "a hub of valence {valence}");
}

// --- 3. The output folder is checked before any work ------------------------------------------------

#[test]
fn an_unwritable_output_folder_is_refused_first() {
    // The input does not exist either: the folder is what the user hears about.
    let out = cli(&["st", "/nonexistent/in.obj", "--out", "/proc/sf-no-such-dir/out"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/proc/sf-no-such-dir/out") && err.contains("cannot write"), "{err}");
}

// --- 4. Messages never carry control characters -------------------------------------------------------

#[test]
fn messages_escape_control_characters() {
    for name in ["control_chars.obj", "control_chars.json"] {
        let path = format!("{OWN}/{name}");
        let err = load(Path::new(&path)).err().expect("refused");
        assert_clear(&err, name);
        let out = cli(&["info", &path]);
        assert_eq!(out.status.code(), Some(2));
        assert!(!out.stderr.iter().any(|&b| b == 0x1b || b == 0x07), "{:?}", String::from_utf8_lossy(&out.stderr));
    }
    let err = load(Path::new(&format!("{OWN}/control_chars.obj"))).err().unwrap();
    assert!(err.contains("\\x1B[2J"), "the escape is shown, escaped: {err}");
}

// --- 5. Out-of-range scales are named as such -----------------------------------------------------------

#[test]
fn out_of_range_scales_are_refused_as_such() {
    for name in ["huge_scale.obj", "tiny_scale.obj"] {
        let err = load(&Path::new(OWN).join(name)).err().expect("refused");
        assert!(err.contains("rescale") && !err.contains("degenerate"), "{name}: {err}");
    }
}

// --- 6. Sizes are checked before anything large is read or allocated ---------------------------------

#[test]
fn oversized_files_and_lying_accessors_are_refused_before_reading() {
    // A sparse 20 GB file: refused from its length, never read.
    let dir = scratch("big");
    std::fs::create_dir_all(&dir).unwrap();
    let big = dir.join("huge.obj");
    std::fs::File::create(&big).unwrap().set_len(20 << 30).unwrap();
    let out = cli(&["info", big.to_str().unwrap()]);
    let _ = std::fs::remove_file(&big);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("exceed the limit"));
    let err = load(&Path::new(OWN).join("lying_accessor.gltf")).err().unwrap();
    assert!(err.contains("no bufferView"), "{err}");
}

// --- 7. App-written design links read back to the same design -----------------------------------------

#[test]
fn design_links_round_trip_without_notices() {
    for name in ["design_link_roundtrip_rtol.frag", "design_link_roundtrip_cam.frag"] {
        let text = std::fs::read_to_string(Path::new(SHARED).join(name)).unwrap();
        let (first, notices) = Design::from_fragment(text.trim());
        assert!(notices.is_empty(), "{name}: {notices:?}");
        let written = first.to_fragment();
        let (again, notices) = Design::from_fragment(&written);
        assert!(notices.is_empty(), "{name}: {written}: {notices:?}");
        assert_eq!(again, first, "{name}: {written}");
        assert_eq!(again.to_fragment(), written);
    }
    let (d, _) = Design::from_fragment("#v=1&method=st-support&rtol=0.00001");
    assert_eq!(d.params::<spherical_faces::pipeline::stages::st_support::StSupportStage>().radius_tolerance, 1e-5);
    let (d, _) = Design::from_fragment("#v=1&cam=0,0,0.00001,0,0,0");
    assert_eq!(d.camera.map(|c| c.distance), Some(1e-5));
}

// --- 8. A sign change of H is warned about in the CLI and the report -------------------------------------

#[test]
fn st_support_warns_where_h_changes_sign() {
    let dir = scratch("saddle");
    let out = cli(&["st-support", &format!("{SHARED}/tessellation_blowup_saddle18.obj"), "--out", dir.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("warning: H changes sign"), "{err}");
    // Its panels kink by up to 169°: several have no surface that does not fold, nor do their
    // support elements, and they stand far off the saddle. The files are written, and the run
    // exits with 3 naming what cannot be built.
    assert_eq!(out.status.code(), Some(3), "{err}");
    let line = err.lines().last().unwrap();
    assert!(
        line.contains("misses its guarantees") && line.contains("support_elements_that_fold") && line.contains("max_distance_to_reference"),
        "{line}"
    );
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    let warnings = report["warnings"].as_array().unwrap();
    assert!(warnings.iter().any(|w| w.as_str().unwrap().contains("H changes sign")), "{warnings:?}");
    assert!(warnings.iter().any(|w| w.as_str().unwrap().contains("kinks")), "{warnings:?}");
    assert_numbers(&report, "saddle18 report");
}

// --- 9. Slivers are degenerate faces, and tessellation is bounded per panel -------------------------------

#[test]
fn slivers_are_counted_and_tessellation_is_bounded() {
    let reference = load(&Path::new(OWN).join("sliver_dome.obj")).unwrap().surface;
    let result =
        spherical_faces::st_support::compute(&reference, &StSupportParams::default(), &Fabrication::default(), Clock(None), &mut ignore).unwrap();
    assert!(result.metrics.degenerate_faces >= 1);
    assert!(result.warnings.iter().any(|w| matches!(w, Warning::Slivers { faces } if *faces >= 1)), "{:?}", result.warnings);
    assert_bounded_panels(&result.panels, "sliver_dome");

    let saddle = load(&Path::new(SHARED).join("tessellation_blowup_saddle18.obj")).unwrap().surface;
    let result =
        spherical_faces::st_support::compute(&saddle, &StSupportParams::default(), &Fabrication::default(), Clock(None), &mut ignore).unwrap();
    assert_bounded_panels(&result.panels, "saddle18");
    let ngon = load(&Path::new(OWN).join("ngon_1500.obj")).unwrap().surface;
    let result = spherical_faces::st_support::compute(&ngon, &StSupportParams::default(), &Fabrication::default(), Clock(None), &mut ignore).unwrap();
    let triangles: usize = result.panels.iter().map(|p| p.triangles.len()).sum();
    let zippers = result.panels.len() * 4 * (4 * level_cap(result.panels.len(), PANEL_TRIANGLE_BUDGET, 32) + 2);
    assert!(triangles <= PANEL_TRIANGLE_BUDGET + zippers, "{triangles} triangles for {} panels", result.panels.len());
}

// --- 10. A fold-over flap: bounded remeshing and a warning -------------------------------------------------

#[test]
fn a_folded_flap_is_warned_about_and_remeshes_within_bounds() {
    let reference = load(&Path::new(OWN).join("flap_dome.obj")).unwrap().surface;
    let mesh = reference.mesh();
    let sizing = SizingField::uniform_for_face_count(mesh, 200);
    let cap = face_cap(mesh, &sizing);
    let out = pliant_remesh_with_stats(mesh, &sizing, &RemeshParams::default(), &mut ignore).unwrap();
    let operations: usize = out.rounds.iter().map(|r| r.splits + r.collapses + r.flips).sum();
    assert!(out.mesh.face_count() <= cap);
    assert!(operations <= 40 * cap, "{operations} operations, cap {cap}");
    // The flap cannot be cut into 200 even faces: refused, and the refusal names the fold.
    let params = StAdaptedParams { sizing: Sizing::UniformFaces(200), ..StAdaptedParams::default() };
    let err = spherical_faces::st_adapted::compute(&reference, &params, &Fabrication::default(), Clock(None), &mut |_| Ok(())).unwrap_err();
    let StAdaptedError::Remesh(refused) = &err else { panic!("{err}") };
    assert!(refused.warnings.iter().any(|w| matches!(w, Warning::Folds { .. })), "{err}");
    assert!(err.to_string().contains("folds back"), "{err}");
}

// --- 11. Each method guards its size and asks for a remesh ----------------------------------------------

fn grid(n: usize) -> TriMesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            positions.push(DVec3::new(x, y, 0.5 - (x - 0.5).powi(2) - (y - 0.5).powi(2)));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * (n as u32 + 1) + i;
            let (b, c, d) = (a + 1, a + n as u32 + 1, a + n as u32 + 2);
            triangles.extend([[a, b, d], [a, d, c]]);
        }
    }
    TriMesh::new(positions, triangles)
}

#[test]
fn methods_refuse_more_faces_than_they_handle_and_name_the_remesh() {
    let reference = Reference::from_triangles(grid(145)); // 42,050 faces
    assert!(reference.mesh().face_count() > MAX_METHOD_FACES);
    let err =
        spherical_faces::st_support::compute(&reference, &StSupportParams::default(), &Fabrication::default(), Clock(None), &mut ignore).unwrap_err();
    let StSupportError::TooManyFaces(e) = &err else { panic!("{err}") };
    assert_eq!(e.suggested(), MAX_METHOD_FACES / 2);
    assert!(err.to_string().contains(&format!("remesh to about {} faces first", MAX_METHOD_FACES / 2)), "{err}");
    let stage = stages::StageError::from(err);
    assert_eq!(stage.remesh_to(), Some(MAX_METHOD_FACES / 2));
    let params = StAdaptedParams { sizing: Sizing::UniformFaces(MAX_METHOD_FACES + 1), ..StAdaptedParams::default() };
    let err = spherical_faces::st_adapted::compute(&reference, &params, &Fabrication::default(), Clock(None), &mut |_| Ok(())).unwrap_err();
    assert!(matches!(err, StAdaptedError::TooManyFaces(_)), "{err}");
}
