//! B-spline surfaces: the authors' JSON format, exact evaluation against the closed forms and the
//! independent reference samples of `../shared/data/bsplines`, finite-difference checks of every
//! derivative, both knot forms, rational weights and clear refusals.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared

mod common;

use glam::DVec3;
use serde_json::{json, Value};
use spherical_faces::geometry::bspline::{BSplineBasis, BSplineFunction, BSplineSurface};
use spherical_faces::import::{import_file, ImportedFile};

const FILES: [&str; 7] =
    ["paraboloid_dome", "paraboloid_dome_deg5", "torus_patch", "sphere_patch", "cylinder_patch", "tunnel_arch", "saddle_sign_change"];

fn surface_from(bytes: &[u8], name: &str) -> BSplineSurface {
    match import_file(bytes, name) {
        Ok(ImportedFile::BSpline(b)) => b.surface,
        Ok(ImportedFile::Mesh(_)) => panic!("{name}: imported as a mesh"),
        Err(e) => panic!("{name}: {e}"),
    }
}

fn load(name: &str) -> BSplineSurface {
    surface_from(&common::shared_bytes(&format!("data/bsplines/{name}.json")), &format!("{name}.json"))
}

fn raw(name: &str) -> Value {
    serde_json::from_slice(&common::shared_bytes(&format!("data/bsplines/{name}.json"))).unwrap()
}

/// n × n parameters, uniform with both ends, U outer (the order of reference_samples.json).
fn grid(s: &BSplineSurface, n: usize) -> Vec<[f64; 2]> {
    let ((u0, u1), (v0, v1)) = s.domain();
    let at = |a: f64, b: f64, k: usize| a + (b - a) * k as f64 / (n - 1) as f64;
    (0..n).flat_map(|i| (0..n).map(move |j| [at(u0, u1, i), at(v0, v1, j)])).collect()
}

#[test]
fn the_reference_samples_are_reproduced() {
    let samples = raw_samples();
    for name in FILES {
        let s = load(name);
        let rows = samples[format!("{name}.json")]["rows"].as_array().unwrap_or_else(|| panic!("{name} in reference_samples.json"));
        let mut worst = [0.0f64; 4];
        for row in rows {
            let r: Vec<f64> = row.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            let f = s.frame(r[0], r[1]).unwrap();
            let scale = 1.0 + f.point.length();
            worst[0] = worst[0].max((f.point - DVec3::new(r[2], r[3], r[4])).length() / scale);
            worst[1] = worst[1].max((f.normal - DVec3::new(r[5], r[6], r[7])).length());
            worst[2] = worst[2].max((f.mean - r[8]).abs() / (1.0 + r[8].abs()));
            worst[3] = worst[3].max((f.gauss - r[9]).abs() / (1.0 + r[9].abs()));
        }
        assert_eq!(rows.len(), 25, "{name}");
        assert!(worst.iter().all(|w| *w < 1e-11), "{name}: point, normal, H, K differ by {worst:?}");
    }
}

fn raw_samples() -> Value {
    serde_json::from_slice(&common::shared_bytes("data/bsplines/reference_samples.json")).unwrap()
}

#[test]
fn both_paraboloids_are_the_analytic_paraboloid() {
    // z = (x² + y²)/(2R), R = 4, x = u, y = v.
    let r = 4.0;
    let (a, b) = (load("paraboloid_dome"), load("paraboloid_dome_deg5"));
    for uv in grid(&a, 41) {
        let (x, y) = (uv[0], uv[1]);
        let q: f64 = 1.0 + (x * x + y * y) / (r * r);
        let point = DVec3::new(x, y, (x * x + y * y) / (2.0 * r));
        let normal = DVec3::new(-x / r, -y / r, 1.0) / q.sqrt();
        let h = (2.0 + (x * x + y * y) / (r * r)) / (2.0 * r * q.powf(1.5));
        let k = 1.0 / (r * r * q * q);
        for s in [&a, &b] {
            let f = s.frame(x, y).unwrap();
            assert!((f.point - point).length() < 1e-12, "{uv:?}: {} vs {point}", f.point);
            assert!((f.normal - normal).length() < 1e-12);
            assert!((f.mean - h).abs() < 1e-12 && (f.gauss - k).abs() < 1e-12, "{uv:?}: H {} vs {h}, K {} vs {k}", f.mean, f.gauss);
        }
        // The same parametrization: every derivative agrees.
        let (da, db) = (a.derivatives(x, y), b.derivatives(x, y));
        for (p, q) in [(da.su, db.su), (da.sv, db.sv), (da.suu, db.suu), (da.suv, db.suv), (da.svv, db.svv)] {
            assert!((p - q).length() < 1e-12, "{uv:?}: {p} vs {q}");
        }
    }
}

#[test]
fn the_torus_patch_has_the_torus_curvature() {
    let (big_r, r) = (3.0, 1.0);
    let s = load("torus_patch");
    for uv in grid(&s, 31) {
        let f = s.frame(uv[0], uv[1]).unwrap();
        let p = f.point;
        // cos φ from the point (the parametrization is rational, not angle-proportional).
        let cos_phi = ((p.x * p.x + p.y * p.y).sqrt() - big_r) / r;
        let h = -(big_r + 2.0 * r * cos_phi) / (2.0 * r * (big_r + r * cos_phi));
        let k = cos_phi / (r * (big_r + r * cos_phi));
        assert!((f.mean - h).abs() < 1e-10 && (f.gauss - k).abs() < 1e-10, "{uv:?}: H {} vs {h}, K {} vs {k}", f.mean, f.gauss);
        // On the torus: distance r from the core circle.
        let core = DVec3::new(p.x, p.y, 0.0).normalize() * big_r;
        assert!(((p - core).length() - r).abs() < 1e-12);
        // Principal directions: the parallel (horizontal) and the meridian.
        let horizontal = DVec3::Z.cross(p).normalize();
        let along = f.dir1.dot(horizontal).abs().max(f.dir2.dot(horizontal).abs());
        assert!((along - 1.0).abs() < 1e-10, "{uv:?}: no principal direction along the parallel");
    }
}

#[test]
fn rational_patches_lie_on_their_sphere_and_cylinder() {
    let sphere = load("sphere_patch");
    for uv in grid(&sphere, 21) {
        let f = sphere.frame(uv[0], uv[1]).unwrap();
        assert!((f.point.length() - 2.0).abs() < 1e-13);
        assert!((f.normal + f.point / 2.0).length() < 1e-12, "the normal points to the centre");
        assert!((f.mean - 0.5).abs() < 1e-12 && (f.gauss - 0.25).abs() < 1e-12);
    }
    let cylinder = load("cylinder_patch");
    for uv in grid(&cylinder, 21) {
        let f = cylinder.frame(uv[0], uv[1]).unwrap();
        assert!(((f.point.x.powi(2) + f.point.z.powi(2)).sqrt() - 2.5).abs() < 1e-13);
        assert!((f.mean - 0.2).abs() < 1e-12 && f.gauss.abs() < 1e-12);
        // The rulings (0, 1, 0) are principal with κ = 0.
        let ruling = if f.k2.abs() < 1e-12 { f.dir2 } else { f.dir1 };
        assert!((ruling.dot(DVec3::Y).abs() - 1.0).abs() < 1e-10);
    }
}

/// Central differences of S, S_u, S_v and n against the analytic derivatives, away from knots.
#[test]
fn derivatives_match_finite_differences() {
    for name in FILES {
        let s = load(name);
        let ((u0, u1), (v0, v1)) = s.domain();
        let (hu, hv) = (1e-5 * (u1 - u0), 1e-5 * (v1 - v0));
        let size = s.control_points().iter().map(|p| p.length()).fold(1.0, f64::max);
        let mut worst = 0.0f64;
        for k in 0..37 {
            // Irrational fractions keep the samples off the knots.
            let (a, b) = (((k as f64) * 0.618_033_988 + 0.13) % 1.0, ((k as f64) * 0.414_213_562 + 0.07) % 1.0);
            let (u, v) = (u0 + (u1 - u0) * (0.02 + 0.96 * a), v0 + (v1 - v0) * (0.02 + 0.96 * b));
            let d = s.derivatives(u, v);
            let (pu, mu, pv, mv) = (s.derivatives(u + hu, v), s.derivatives(u - hu, v), s.derivatives(u, v + hv), s.derivatives(u, v - hv));
            let checks = [
                (d.su, (pu.s - mu.s) / (2.0 * hu), hu),
                (d.sv, (pv.s - mv.s) / (2.0 * hv), hv),
                (d.suu, (pu.su - mu.su) / (2.0 * hu), hu),
                (d.suv, (pv.su - mv.su) / (2.0 * hv), hv),
                (d.suv, (pu.sv - mu.sv) / (2.0 * hu), hu),
                (d.svv, (pv.sv - mv.sv) / (2.0 * hv), hv),
            ];
            for (analytic, numeric, h) in checks {
                let err = (analytic - numeric).length() * h / size;
                worst = worst.max(err);
            }
            let f = s.frame(u, v).unwrap();
            let (fu, fv) = (
                s.frame(u + hu, v).unwrap().normal - s.frame(u - hu, v).unwrap().normal,
                s.frame(u, v + hv).unwrap().normal - s.frame(u, v - hv).unwrap().normal,
            );
            assert!((f.nu - fu / (2.0 * hu)).length() * hu < 1e-9, "{name}: ∂n/∂u");
            assert!((f.nv - fv / (2.0 * hv)).length() * hv < 1e-9, "{name}: ∂n/∂v");
        }
        // Relative to the step: central differences are O(h²) accurate, rounding O(ε/h).
        assert!(worst < 1e-9, "{name}: derivative vs finite difference {worst:e}");
    }
}

/// openNURBS knots (n + p − 1) and textbook knots (n + p + 1) give the same surface.
#[test]
fn both_knot_forms_give_the_same_surface() {
    for name in ["tunnel_arch", "torus_patch", "cylinder_patch"] {
        let mut j = raw(name);
        let a = load(name);
        for key in ["knotsU", "knotsV"] {
            let k: Vec<f64> = j[key].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            let padded: Vec<f64> = std::iter::once(k[0]).chain(k.iter().copied()).chain(std::iter::once(k[k.len() - 1])).collect();
            j[key] = json!(padded);
        }
        let b = surface_from(serde_json::to_string(&j).unwrap().as_bytes(), "textbook.json");
        assert_eq!(a, b, "{name}");
    }
}

/// The ordering is U fastest: the non-square files read the other way round are other surfaces
/// (their control grids do not even have the shape).
#[test]
fn control_points_run_u_fastest() {
    let s = load("torus_patch");
    assert_eq!((s.basis_u().count(), s.basis_v().count()), (5, 3));
    // Corner (u0, v0) is control point 0, (u1, v0) is control point n_u − 1.
    let ((u0, u1), (v0, _)) = s.domain();
    assert!((s.point(u0, v0) - s.control_points()[0]).length() < 1e-14);
    assert!((s.point(u1, v0) - s.control_points()[4]).length() < 1e-14);
}

fn refusal(mutate: impl Fn(&mut Value)) -> String {
    let mut j = raw("tunnel_arch");
    mutate(&mut j);
    match import_file(serde_json::to_string(&j).unwrap().as_bytes(), "bad.json") {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn bad_files_are_refused_with_the_field_named() {
    let m = refusal(|j| j["knotsU"][7] = json!(-100.0));
    assert!(m.starts_with("bad.json: 'knotsU'") && m.contains("smaller than knot"), "{m}");
    let m = refusal(|j| {
        let cp = j["controlPoints"].as_array_mut().unwrap();
        cp.truncate(cp.len() - 4);
    });
    assert!(m.contains("'controlPoints' holds 155 points") && m.contains("12 × 13"), "{m}");
    let m = refusal(|j| j["controlPoints"].as_array_mut().unwrap().pop().map(|_| ()).unwrap());
    assert!(m.contains("not a multiple of 4"), "{m}");
    let m = refusal(|j| j["degreeU"] = json!(0));
    assert!(m.contains("'degreeU' must be an integer from 1 to 15"), "{m}");
    let m = refusal(|j| j["degreeV"] = json!(16));
    assert!(m.contains("'degreeV' must be an integer from 1 to 15"), "{m}");
    let m = refusal(|j| j["controlPoints"][5] = json!("x"));
    assert!(m.contains("'controlPoints'[5] is not a finite number"), "{m}");
    let m = refusal(|j| j["controlPoints"][3] = json!(0.0));
    assert!(m.contains("weight of point 0 is 0"), "{m}");
    let m = refusal(|j| {
        j.as_object_mut().unwrap().remove("knotsV");
    });
    assert!(m.contains("missing key 'knotsV'"), "{m}");
    // Too few control points for the degree: 2 × 2 points of degree 3.
    let tiny = json!({"degreeU": 3, "degreeV": 3, "knotsU": [0, 1, 2, 3], "knotsV": [0, 1, 2, 3],
        "controlPoints": [0, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0, 1, 1, 1, 0, 1]});
    let m = import_file(tiny.to_string().as_bytes(), "tiny.json").unwrap_err().to_string();
    assert!(m.contains("too few for degree 3") || m.contains("holds 4 points"), "{m}");
    // NaN is not JSON; 1e999 overflows to a non-number.
    let m = import_file(b"{\"degreeU\": 2, \"degreeV\": 2, \"knotsU\": [NaN], \"knotsV\": [], \"controlPoints\": []}", "nan.json")
        .unwrap_err()
        .to_string();
    assert!(m.contains("invalid JSON"), "{m}");
}

#[test]
fn a_spline_function_reproduces_its_space_and_fits_samples() {
    // g(u, v) = u² v − 3v + 1 is in the space of a degree-5 basis: the fit is exact.
    let (bu, bv) = (BSplineBasis::clamped_uniform(5, 6, (0.0, 10.0)).unwrap(), BSplineBasis::clamped_uniform(5, 6, (0.0, 12.0)).unwrap());
    let g = |u: f64, v: f64| u * u * v - 3.0 * v + 1.0;
    let samples: Vec<([f64; 2], f64)> =
        (0..20).flat_map(|i| (0..20).map(move |j| (i as f64 * 10.0 / 19.0, j as f64 * 12.0 / 19.0))).map(|(u, v)| ([u, v], g(u, v))).collect();
    let (f, err) = BSplineFunction::fit(bu, bv, &samples).unwrap();
    assert!(err.max < 1e-9, "{err:?}");
    let (value, du, dv) = f.evaluate(3.3, 7.1);
    assert!((value - g(3.3, 7.1)).abs() < 1e-9 && (du - 2.0 * 3.3 * 7.1).abs() < 1e-8 && (dv - (3.3 * 3.3 - 3.0)).abs() < 1e-8);
    // Too few samples for 36 coefficients: no fit.
    let (bu, bv) = (BSplineBasis::clamped_uniform(5, 6, (0.0, 1.0)).unwrap(), BSplineBasis::clamped_uniform(5, 6, (0.0, 1.0)).unwrap());
    assert!(BSplineFunction::fit(bu, bv, &samples[..30]).is_none());
}

/// A rescaled domain moves only the knots: the same points at the mapped parameters (to 1e-12 of
/// the diagonal), and after the isotropic scale both parameters run at one mean speed in space.
#[test]
fn a_rescaled_domain_keeps_the_surface_and_evens_the_parameter_speeds() {
    let given = surface_from(include_bytes!("data/corpus40/corpus_40_15_dome.json"), "corpus_40_15_dome.json");
    let ((u0, u1), (v0, v1)) = given.domain();
    let scale = given.isotropic_scale(16);
    let iso = given.rescaled(scale);
    let diag = given.tessellate([8, 8]).0.bbox_diagonal();
    for [u, v] in grid(&given, 9) {
        let (p, q) = (given.point(u, v), iso.point(u0 + (u - u0) * scale[0], v0 + (v - v0) * scale[1]));
        assert!(p.distance(q) <= 1e-12 * diag, "({u}, {v}): {p} against {q}");
    }
    let ((a0, a1), (b0, b1)) = iso.domain();
    assert!((a1 - a0 - (u1 - u0) * scale[0]).abs() < 1e-12 && (b1 - b0 - (v1 - v0) * scale[1]).abs() < 1e-12);
    // This patch's knots run over [0, 13.3] × [0, 1] for sides 6.4 and 5.1 long: u is the slow one.
    assert!(scale[0] < 0.2 && scale[1] == 1.0, "{scale:?}");
    let mean_speeds = |s: &BSplineSurface| {
        let g = grid(s, 16);
        let sum = g.iter().fold([0.0, 0.0], |m, &[u, v]| {
            let d = s.derivatives(u, v);
            [m[0] + d.su.length(), m[1] + d.sv.length()]
        });
        sum[0] / sum[1]
    };
    assert!(mean_speeds(&given) < 0.2, "{}", mean_speeds(&given));
    assert!((mean_speeds(&iso) - 1.0).abs() < 0.05, "{}", mean_speeds(&iso));
}
