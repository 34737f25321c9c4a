//! Panels as exact surfaces (`panels::exact_surface`): on the results of all three methods, every
//! panel's patch, sampled on a 20 × 20 grid, lies on the panel's sphere within 1e-9 of the
//! diagonal, its sides lie on the panel's arcs within 1e-9 and run between its corners, its
//! weights are positive and its planar image does not fold; every support element's patch lies
//! in its plane, bounded by its arcs and node-axis segments.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared

mod common;

use common::load_reference;
use glam::DVec3;
use spherical_faces::congruence::support_structure::SupportElement;
use spherical_faces::geometry::circle::Circle;
use spherical_faces::geometry::rational_bezier::{RationalCurve, RationalPatch, Side};
use spherical_faces::import::{import_file, ImportedFile};
use spherical_faces::panels::arc::Arc;
use spherical_faces::panels::exact_surface::{panel_patch, support_patch, ExactSurfaceError};
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::panels::panel::Panel;
use spherical_faces::progress::Clock;
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::Sizing;
use spherical_faces::samples::Sample;
use spherical_faces::sq::params::SqParams;
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_support::StSupportParams;

const GRID: usize = 20;
const EXACT: f64 = 1e-9;

/// Distance from x to the circle (or, straight, the line) of `arc`.
fn off_circle(arc: &Arc, x: DVec3) -> f64 {
    let c: &Circle = &arc.circle;
    if arc.is_straight() {
        let e = (arc.to - arc.from).normalize();
        let d = x - arc.from;
        return (d - d.dot(e) * e).length();
    }
    let d = x - c.center;
    let h = d.dot(c.normal);
    let rho = (d - h * c.normal).length();
    ((rho - c.radius).powi(2) + h * h).sqrt()
}

/// Distance from x to the arc itself (dense samples, refined to the circle).
fn off_arc(arc: &Arc, x: DVec3) -> f64 {
    let n = 2000;
    (0..=n).map(|k| arc.point(k as f64 / n as f64).distance(x)).fold(f64::INFINITY, f64::min)
}

/// The sides of a patch in the panel's order: corner k → k + 1.
fn sides(patch: &RationalPatch, corners: usize) -> Vec<RationalCurve> {
    let mut s = vec![patch.side(Side::V0), patch.side(Side::U1), patch.side(Side::V1).reversed(), patch.side(Side::U0).reversed()];
    if corners == 3 {
        s.remove(2);
    }
    s
}

/// Every guarantee of the exact patches of `panels` (diagonal `diag`); returns the worst
/// sphere and arc distances, relative.
fn check_panels(name: &str, panels: &[Panel], diag: f64) -> (f64, f64) {
    let (mut on_sphere, mut on_arcs) = (0.0f64, 0.0f64);
    for p in panels {
        let patch = panel_patch(p).unwrap_or_else(|e| panic!("{name}: panel {}: {e}", p.face));
        assert!(patch.weights.iter().all(|&w| w > 0.0 && w.is_finite()), "{name}: panel {}: weights {:?}", p.face, patch.weights);
        assert_eq!(patch.degree, if p.is_planar() { [2, 2] } else { [4, 4] });
        for i in 0..=GRID {
            for j in 0..=GRID {
                let x = patch.evaluate(i as f64 / GRID as f64, j as f64 / GRID as f64);
                on_sphere = on_sphere.max(p.sphere.distance(x) / diag);
            }
        }
        let n = p.arcs.len();
        // A triangle's sides start at one of its corners.
        let first = (0..n)
            .min_by(|&a, &b| p.arcs[a].from.distance(patch.evaluate(0.0, 0.0)).total_cmp(&p.arcs[b].from.distance(patch.evaluate(0.0, 0.0))))
            .unwrap();
        assert!(n == 3 || first == 0, "{name}: a quad's sides start at corner 0");
        for (s, side) in sides(&patch, n).iter().enumerate() {
            let k = (s + first) % n;
            let arc = &p.arcs[k];
            assert!(side.evaluate(0.0).distance(arc.from) <= EXACT * diag, "{name}: panel {} side {k} starts off its corner", p.face);
            assert!(side.evaluate(1.0).distance(p.arcs[(k + 1) % n].from) <= EXACT * diag, "{name}: panel {} side {k}", p.face);
            for t in 0..=GRID {
                on_arcs = on_arcs.max(off_circle(arc, side.evaluate(t as f64 / GRID as f64)) / diag);
            }
            // On the arc, not on the rest of its circle: its middle is near the arc's.
            let mid = side.evaluate(0.5);
            assert!(off_arc(arc, mid) <= 2e-3 * arc.length() + EXACT * diag, "{name}: panel {} side {k} leaves its arc", p.face);
        }
    }
    eprintln!("{name}: {} panels, patches within {on_sphere:.1e} of their spheres, sides within {on_arcs:.1e} of their arcs", panels.len());
    assert!(on_sphere <= EXACT, "{name}: {on_sphere:e}");
    assert!(on_arcs <= EXACT, "{name}: {on_arcs:e}");
    (on_sphere, on_arcs)
}

fn check_support(name: &str, elements: &[SupportElement], diag: f64) {
    for (e, el) in elements.iter().enumerate() {
        let patch = support_patch(el).unwrap_or_else(|err| panic!("{name}: element {e}: {err}"));
        let n = el.circle.normal;
        for i in 0..=GRID {
            for j in 0..=GRID {
                let x = patch.evaluate(i as f64 / GRID as f64, j as f64 / GRID as f64);
                assert!((x - el.corners[0]).dot(n).abs() <= EXACT * diag, "{name}: element {e} leaves its plane");
            }
        }
        let on = |c: &Circle, x: DVec3| {
            let d = x - c.center;
            ((d - d.dot(c.normal) * c.normal).length() - c.radius).abs()
        };
        for t in 0..=GRID {
            let t = t as f64 / GRID as f64;
            assert!(on(&el.circle, patch.side(Side::V0).evaluate(t)) <= EXACT * diag, "{name}: element {e}: edge arc");
            if el.inner_circle.radius.is_finite() {
                assert!(on(&el.inner_circle, patch.side(Side::V1).evaluate(t)) <= EXACT * diag, "{name}: element {e}: inner arc");
            }
        }
        assert!(patch.evaluate(1.0, 1.0).distance(el.corners[2]) <= EXACT * diag && patch.evaluate(0.0, 1.0).distance(el.corners[3]) <= EXACT * diag);
    }
}

#[test]
fn st_adapted_panels_are_exact_patches() {
    let reference = load_reference("tri_mesh");
    let params = StAdaptedParams { sizing: Sizing::Adaptive { epsilon: 2e-3 }, ..Default::default() };
    let result = spherical_faces::st_adapted::compute(&reference, &params, &Fabrication::default(), Clock::default(), &mut |_| Ok(())).unwrap();
    check_panels("st tri_mesh", &result.panels, reference.diagonal());
}

#[test]
fn st_support_panels_and_elements_are_exact_patches() {
    let reference = load_reference("cmc1");
    let result =
        spherical_faces::st_support::compute(&reference, &StSupportParams::default(), &Fabrication::default(), Clock::default(), &mut |_| Ok(()))
            .unwrap();
    check_panels("st-support cmc1", &result.panels, reference.diagonal());
    check_support("st-support cmc1", &result.support.elements, reference.diagonal());
}

#[test]
fn sq_panels_and_elements_are_exact_patches() {
    let tunnel = match import_file(&common::shared_bytes("data/bsplines/tunnel_arch.json"), "tunnel_arch.json") {
        Ok(ImportedFile::BSpline(b)) => b.surface,
        other => panic!("{other:?}"),
    };
    for (name, surface) in [("sq vault", Sample::Vault.bspline().unwrap()), ("sq tunnel_arch", tunnel)] {
        let reference = Reference::from_bspline(surface).unwrap();
        let result =
            spherical_faces::sq::compute(&reference, &SqParams::default(), &Fabrication::default(), Clock::default(), &mut |_| Ok(())).unwrap();
        let mesh = &result.sq_mesh.as_ref().expect("an SQ mesh").mesh;
        assert!(mesh.panels.iter().all(|p| p.arcs.len() == 4));
        check_panels(name, &mesh.panels, reference.diagonal());
        check_support(name, &mesh.support.elements, reference.diagonal());
    }
}

/// A planar panel is a planar (2, 2) patch; a triangle's third side runs back to its first
/// corner, its collapsed side is one point.
#[test]
fn planar_and_triangular_panels() {
    let reference = Reference::from_triangles(Sample::SphereCap.mesh());
    let result =
        spherical_faces::st_support::compute(&reference, &StSupportParams::default(), &Fabrication::default(), Clock::default(), &mut |_| Ok(()))
            .unwrap();
    let p = &result.panels[0];
    let patch = panel_patch(p).unwrap();
    let collapsed = patch.side(Side::V1);
    assert!(collapsed.points.iter().all(|x| x.distance(collapsed.points[0]) <= 1e-12 * reference.diagonal()));
    let mut flat = p.clone();
    // The corners run counter-clockwise about the outward normal (b of a plane).
    let n = (p.arcs[1].from - p.arcs[0].from).cross(p.arcs[2].from - p.arcs[0].from).normalize();
    flat.sphere = spherical_faces::geometry::sphere::Sphere::plane(p.arcs[0].from, n);
    flat.arcs = (0..3).map(|k| Arc::straight(p.arcs[k].from, p.arcs[(k + 1) % 3].from, n)).collect();
    let patch = panel_patch(&flat).unwrap();
    assert_eq!(patch.degree, [2, 2]);
    check_panels("a flat triangle", &[flat.clone()], reference.diagonal());
    // Turned inside out (its sphere's orientation negated), the panel is the rest of its sphere
    // (or plane) beyond its arcs: no bounded patch has those sides running that way.
    for mut outside in [p.clone(), flat] {
        let s = outside.sphere;
        outside.sphere = spherical_faces::geometry::sphere::Sphere { a: -s.a, b: -s.b, c: -s.c };
        assert!(matches!(panel_patch(&outside), Err(ExactSurfaceError::Folds { .. })), "{:?}", panel_patch(&outside));
    }
}

/// A flat triangle whose first side leaves its corners outside the triangle and bulges back in:
/// its arcs cross near both corners, so it is refused as such, not as a fold.
#[test]
fn a_panel_whose_arcs_cross_is_refused() {
    let corners = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 1.0, 0.0)];
    // The circle through (0, 0), (1, 0) and (0.5, h), run over its top: clockwise about +z. Its
    // tangent at (0, 0) is steeper than the side to (0.5, 1).
    let h = 0.45;
    let k = (h * h - 0.25) / (2.0 * h);
    let bulge = Arc { circle: Circle { center: DVec3::new(0.5, k, 0.0), normal: -DVec3::Z, radius: h - k }, from: corners[0], to: corners[1] };
    assert!((bulge.point(0.5) - DVec3::new(0.5, h, 0.0)).length() < 1e-12);
    assert!(bulge.point(0.05).x < 0.5 * bulge.point(0.05).y, "it leaves (0, 0) outside the triangle");
    let mut arcs = vec![bulge];
    arcs.extend((1..3).map(|i| Arc::straight(corners[i], corners[(i + 1) % 3], DVec3::Z)));
    let panel = Panel {
        face: 0,
        sphere: spherical_faces::geometry::sphere::Sphere::plane(DVec3::ZERO, DVec3::Z),
        corners: vec![0, 1, 2],
        arcs,
        positions: corners.to_vec(),
        triangles: Vec::new(),
        area: 0.0,
        arc_vertices: Vec::new(),
    };
    assert_eq!(panel_patch(&panel), Err(ExactSurfaceError::ArcsCross));
    // The same lifted onto the unit sphere near its north pole.
    let mut on_sphere = panel.clone();
    let lift = |p: DVec3| DVec3::new(0.3 * (p.x - 0.5), 0.3 * (p.y - 0.4), 1.0).normalize();
    let pts = corners.map(lift);
    let circle_through = |a: DVec3, b: DVec3, c: DVec3| {
        let n = (b - a).cross(c - a).normalize();
        let center = n * n.dot(a); // the plane's foot from the sphere's centre
        Circle { center, normal: n, radius: (a - center).length() }
    };
    // Side 0 on the circle through its ends and the lifted middle of the bulge: its normal (M − A) × (B − A) points into the sphere: A → M → B runs counter-clockwise about it.
    let c0 = circle_through(pts[0], lift(DVec3::new(0.5, h, 0.0)), pts[1]);
    let mut arcs = vec![Arc { circle: c0, from: pts[0], to: pts[1] }];
    for i in 1..3 {
        // Great circle arcs, the short way.
        let (a, b) = (pts[i], pts[(i + 1) % 3]);
        arcs.push(Arc { circle: Circle { center: DVec3::ZERO, normal: a.cross(b).normalize(), radius: 1.0 }, from: a, to: b });
    }
    on_sphere.arcs = arcs;
    on_sphere.positions = pts.to_vec();
    on_sphere.sphere = spherical_faces::geometry::sphere::Sphere { a: -0.5, b: DVec3::ZERO, c: 0.5 }; // outward: away from the centre
    assert!(on_sphere.arcs.iter().all(|a| (a.point(0.5).length() - 1.0).abs() < 1e-12), "the arcs lie on the unit sphere");
    assert!((on_sphere.arcs[0].point(0.5) - lift(DVec3::new(0.5, h, 0.0))).length() < 1e-12, "side 0 through its lifted middle");
    assert_eq!(panel_patch(&on_sphere), Err(ExactSurfaceError::ArcsCross));
}

/// Runs tests/e2e/read-step.mjs (OpenCascade through occt-import-js) on `file`: the vertices of
/// each face's triangulation, in file order. Panics when the reader is not installed.
fn read_step(file: &std::path::Path, unit: &str) -> Vec<Vec<DVec3>> {
    let e2e = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/e2e");
    assert!(e2e.join("node_modules/occt-import-js").is_dir(), "occt-import-js is not installed: run `npm ci` in tests/e2e");
    let out = std::process::Command::new("node").arg(e2e.join("read-step.mjs")).arg(file).args(["--unit", unit]).output().expect("runs node");
    assert!(out.status.success(), "read-step.mjs: {}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    json["faces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            f.as_array().unwrap().chunks(3).map(|c| DVec3::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap(), c[2].as_f64().unwrap())).collect()
        })
        .collect()
}

fn vec3(v: &serde_json::Value) -> DVec3 {
    DVec3::new(v[0].as_f64().unwrap(), v[1].as_f64().unwrap(), v[2].as_f64().unwrap())
}

/// `panels.step` of every method, read by OpenCascade: one face per panel and support element,
/// each triangulated with its vertices on the panel's scheduled sphere (or the element's
/// plane) within 1e-6 of the diagonal; and `panels.3dm`, read by rhino3dm ([`check_3dm`]).
#[test]
fn cad_files_read_back_on_their_spheres() {
    let shared = |p: &str| common::shared_path(p).to_str().unwrap().to_string();
    // Every method on every one of the four inputs it takes (SQ needs a B-spline); ST with
    // support structure on a B-spline remeshed to about 600 faces (its default, the tessellation,
    // gives some 12,000 faces, whose files take a minute to read back).
    let (vault, tunnel) = ("sample:vault".to_string(), shared("data/bsplines/tunnel_arch.json"));
    let cases = [
        ("sq", vault.clone(), vec![]),
        ("sq", tunnel.clone(), vec![]),
        ("st", vault.clone(), vec!["--units", "cm"]),
        ("st", tunnel.clone(), vec![]),
        ("st", shared("data/meshes/tri_mesh.obj"), vec!["--epsilon", "2e-3"]),
        ("st", shared("data/meshes/cmc1.obj"), vec![]),
        ("st-support", vault, vec!["--faces", "600"]),
        ("st-support", tunnel, vec!["--faces", "600", "--units", "ft"]),
        ("st-support", shared("data/meshes/tri_mesh.obj"), vec![]),
        ("st-support", shared("data/meshes/cmc1.obj"), vec!["--units", "mm"]),
    ];
    for (k, (method, input, extra)) in cases.iter().enumerate() {
        let dir = common::temp_dir(&format!("sf-step-{k}"));
        let mut args = vec![*method, input.as_str(), "-q", "--out", dir.to_str().unwrap()];
        args.extend(extra.iter().copied());
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_spherical-faces")).args(&args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        let schedule: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("panels.json")).unwrap()).unwrap();
        let report: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
        let unit = schedule["units"].as_str().unwrap();
        let diag = schedule["reference_diagonal"].as_f64().unwrap();
        let exact = &report["exact_surfaces"];
        assert!(exact["refused"].as_array().is_none_or(|r| r.is_empty()), "{method} {input}: {exact}");
        let faces = read_step(&dir.join("panels.step"), unit);
        let panels = schedule["panels"].as_array().unwrap();
        let elements = schedule["support_elements"].as_array().map_or(&[][..], |e| &e[..]);
        assert_eq!(faces.len(), panels.len() + elements.len(), "{method} {input}: faces read back");
        let mut worst: f64 = 0.0;
        for (face, p) in faces.iter().zip(panels) {
            let s = &p["sphere"];
            assert!(face.len() >= 3);
            for &x in face {
                let d = if s["plane"].as_bool().unwrap() {
                    (x - vec3(&p["vertices"][0])).dot(vec3(&s["normal"])).abs()
                } else {
                    ((x - vec3(&s["center"])).length() - s["radius"].as_f64().unwrap()).abs()
                };
                worst = worst.max(d / diag);
            }
        }
        for (face, el) in faces[panels.len()..].iter().zip(elements) {
            for &x in face {
                worst = worst.max((x - vec3(&el["plane_point"])).dot(vec3(&el["plane_normal"])).abs() / diag);
            }
        }
        let bytes = std::fs::metadata(dir.join("panels.step")).unwrap().len();
        eprintln!("{method} {input}: {} faces read back by OpenCascade, within {worst:.1e} of the diagonal; panels.step {bytes} bytes", faces.len());
        assert!(worst <= 1e-6, "{method} {input}: {worst:e}");
        check_3dm(&format!("{method} {input}"), &dir, &schedule, &report);
    }
}

/// `panels.3dm` read back by rhino3dm: every object valid, one surface per panel on its mould's
/// layer with its user text, on its sphere (20 × 20 grid) within 1e-9 of the diagonal, its sides
/// on its arcs' circles within 1e-9; the support elements and edges as surfaces and curves.
fn check_3dm(name: &str, dir: &std::path::Path, schedule: &serde_json::Value, report: &serde_json::Value) {
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/e2e/read-3dm.mjs");
    let out = std::process::Command::new("node").arg(script).arg(dir.join("panels.3dm")).output().expect("runs node");
    assert!(out.status.success(), "read-3dm.mjs: {}", String::from_utf8_lossy(&out.stderr));
    let model: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let unit = schedule["units"].as_str().unwrap();
    let rhino_unit = match unit {
        "m" => "Meters",
        "cm" => "Centimeters",
        "mm" => "Millimeters",
        "ft" => "Feet",
        _ => "Inches",
    };
    assert_eq!(model["units"], rhino_unit, "{name}");
    let diag = schedule["reference_diagonal"].as_f64().unwrap();
    let objects = model["objects"].as_array().unwrap();
    assert!(objects.iter().all(|o| o["valid"] == true), "{name}: an invalid object");
    let panels = schedule["panels"].as_array().unwrap();
    let surfaces: Vec<&serde_json::Value> = objects.iter().filter(|o| o["name"].as_str().unwrap_or("").starts_with("panel ")).collect();
    assert_eq!(surfaces.len(), panels.len(), "{name}: one surface per panel");
    let (mut on_sphere, mut on_arcs) = (0.0f64, 0.0f64);
    for (s, p) in surfaces.iter().zip(panels) {
        assert_eq!(s["kind"], "NurbsSurface");
        let id = p["id"].as_u64().unwrap();
        assert_eq!(s["user_text"]["id"], id.to_string(), "{name}");
        assert_eq!(s["user_text"]["mould"], p["mould"].as_u64().unwrap().to_string(), "{name}");
        assert_eq!(s["layer"], format!("panels::mould {}", p["mould"]), "{name}");
        let sphere = &p["sphere"];
        let off = |x: DVec3| {
            if sphere["plane"].as_bool().unwrap() {
                (x - vec3(&p["vertices"][0])).dot(vec3(&sphere["normal"])).abs()
            } else {
                ((x - vec3(&sphere["center"])).length() - sphere["radius"].as_f64().unwrap()).abs()
            }
        };
        for x in s["grid"].as_array().unwrap() {
            on_sphere = on_sphere.max(off(vec3(x)) / diag);
        }
        let edges = p["edges"].as_array().unwrap();
        let off_edge = |e: &serde_json::Value, x: DVec3| {
            if e["straight"].as_bool().unwrap() {
                return 0.0;
            }
            let (c, n) = (vec3(&e["center"]), vec3(&e["normal"]));
            let d = x - c;
            let h = d.dot(n);
            (((d - h * n).length() - e["radius"].as_f64().unwrap()).powi(2) + h * h).sqrt()
        };
        for side in s["sides"].as_array().unwrap() {
            let pts: Vec<DVec3> = side.as_array().unwrap().iter().map(vec3).collect();
            if pts.iter().all(|x| x.distance(pts[0]) <= 1e-12 * diag) {
                continue; // a triangle's collapsed side
            }
            let best = edges.iter().map(|e| pts.iter().map(|&x| off_edge(e, x)).fold(0.0, f64::max)).fold(f64::INFINITY, f64::min);
            on_arcs = on_arcs.max(best / diag);
        }
    }
    let support = objects.iter().filter(|o| o["layer"] == "support").count();
    assert_eq!(support as u64, report["exact_surfaces"]["support_elements"].as_u64().unwrap(), "{name}");
    assert!(objects.iter().any(|o| o["layer"] == "edges" && o["kind"] == "NurbsCurve"), "{name}: edge arcs");
    let bytes = std::fs::metadata(dir.join("panels.3dm")).unwrap().len();
    eprintln!("{name}: panels.3dm read back by rhino3dm, {} objects, panels within {on_sphere:.1e} of their spheres, sides within {on_arcs:.1e} of their arcs; {bytes} bytes", objects.len());
    assert!(on_sphere <= EXACT && on_arcs <= EXACT, "{name}: {on_sphere:e}, {on_arcs:e}");
}

/// Panels whose plain Coons patch folds, from ST on conical1 and flower_cmc1 (tests/data/exact):
/// those whose arcs cross (sampled densely here, 2048 points an arc) are refused as such; the
/// others, with the collapsed corner and the interior point chosen, have exact patches.
#[test]
fn panels_with_a_sharp_corner_are_exact_patches_or_cross() {
    let mut crossing = 0;
    let text = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/exact/sharp_corner_panels.json")).unwrap();
    let fixture: serde_json::Value = serde_json::from_str(&text).unwrap();
    for p in fixture["panels"].as_array().unwrap() {
        let corners: Vec<DVec3> = p["corners"].as_array().unwrap().iter().map(vec3).collect();
        let n = corners.len();
        let arcs: Vec<Arc> = p["arcs"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
            .map(|(k, a)| Arc {
                circle: Circle { center: vec3(&a["center"]), normal: vec3(&a["normal"]), radius: a["radius"].as_f64().unwrap() },
                from: corners[k],
                to: corners[(k + 1) % n],
            })
            .collect();
        for (arc, a) in arcs.iter().zip(p["arcs"].as_array().unwrap()) {
            assert!((arc.sweep().to_degrees() - a["sweep_deg"].as_f64().unwrap()).abs() <= 1e-6, "the fixture's arcs as scheduled");
        }
        let s = &p["sphere"];
        let panel = Panel {
            face: p["id"].as_u64().unwrap() as usize,
            sphere: spherical_faces::geometry::sphere::Sphere { a: s["a"].as_f64().unwrap(), b: vec3(&s["b"]), c: s["c"].as_f64().unwrap() },
            corners: (0..n as u32).collect(),
            arcs,
            positions: corners.clone(),
            triangles: Vec::new(),
            area: 0.0,
            arc_vertices: Vec::new(),
        };
        if arcs_cross_densely(&panel) {
            crossing += 1;
            assert_eq!(panel_patch(&panel), Err(ExactSurfaceError::ArcsCross), "{} panel {}", p["source"], p["id"]);
            continue;
        }
        check_panels(&format!("{} panel {}", p["source"], p["id"]), &[panel], p["diagonal"].as_f64().unwrap());
    }
    assert!(crossing < fixture["panels"].as_array().unwrap().len(), "one panel at least has an exact patch");
}

/// Whether two arcs of `panel` cross, by their polygons of 2048 points an arc in the tangent
/// plane at the corners' mean (segments sharing a point left out).
fn arcs_cross_densely(panel: &Panel) -> bool {
    const N: usize = 2048;
    let m = panel.positions.iter().sum::<DVec3>() / panel.positions.len() as f64;
    let normal = panel.normal_at(m);
    let (e1, e2) = (normal.any_orthonormal_vector(), normal.cross(normal.any_orthonormal_vector()));
    let poly: Vec<glam::DVec2> = panel
        .arcs
        .iter()
        .flat_map(|a| (0..N).map(move |k| a.point(k as f64 / N as f64)))
        .map(|x| glam::DVec2::new((x - m).dot(e1), (x - m).dot(e2)))
        .collect();
    let n = poly.len();
    let side = |a: glam::DVec2, b: glam::DVec2, p: glam::DVec2| (b - a).perp_dot(p - a);
    (0..n).any(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        (i + 2..n).filter(|&j| (j + 1) % n != i).any(|j| {
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            side(a, b, c) * side(a, b, d) < 0.0 && side(c, d, a) * side(c, d, b) < 0.0
        })
    })
}
