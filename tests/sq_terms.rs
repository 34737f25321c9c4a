//! Every residual term of the congruence optimization (Sec. 5.1) against central finite
//! differences, in both inequality forms, at random points around a real configuration of
//! `tunnel_arch` (some hinges active, some not), and the regularizer E_reg.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared

mod common;

use spherical_faces::geometry::bspline::{BSplineBasis, BSplineFunction};
use spherical_faces::import::{import_file, ImportedFile};
use spherical_faces::rng::Rng;
use spherical_faces::solver::{check_jacobian_report, residuals, Hinge, Proximal, Term};
use spherical_faces::sq::optimization::CongruenceProblem;
use spherical_faces::sq::params::Inequality;
use spherical_faces::sq::radius::SamplingGrid;
use spherical_faces::sq::terms::{line_fairness, LineCongruence, LineNormalAngle, TorsalAngle, TorsalDirection};

const FD_H: f64 = 1e-6;
const FD_TOL: f64 = 1e-6;

fn assert_fd(term: &dyn Term, x: &[f64]) {
    let rep = check_jacobian_report(term, x, FD_H);
    assert!(rep.max_error < FD_TOL, "term '{}': Jacobian mismatch {rep:?}", term.name());
}

/// A 5 × 5 grid on the tunnel (in the unit frame), a degree-3 radius basis, and a point: the
/// central-ish radius, jittered lines, and random torsal unknowns.
fn setup(inequality: Inequality) -> (CongruenceProblem, Vec<f64>) {
    let bytes = common::shared_bytes("data/bsplines/tunnel_arch.json");
    let Ok(ImportedFile::BSpline(b)) = import_file(&bytes, "tunnel_arch.json") else { panic!() };
    let s = b.surface.in_frame(glam::DVec3::new(0.0, 6.0, 2.0), 16.75);
    let ((u0, u1), (v0, v1)) = s.domain();
    let radius = BSplineFunction {
        u: BSplineBasis::clamped_uniform(3, 4, (u0, u1)).unwrap(),
        v: BSplineBasis::clamped_uniform(3, 4, (v0, v1)).unwrap(),
        coefficients: vec![-0.5; 16],
    };
    let grid = SamplingGrid::new(&s, 5).unwrap();
    let problem = CongruenceProblem::new(grid, &radius, inequality);
    let mut rng = Rng(7);
    let mut x: Vec<f64> = (0..problem.layout.all_variables()).map(|_| rng.uniform() - 0.5).collect();
    for (k, c) in problem.layout.radius.clone().enumerate() {
        x[c] = -0.5 + 0.05 * (k as f64).sin();
    }
    for (p, f) in problem.grid.frames.iter().enumerate() {
        let o = problem.layout.line(p);
        let l = (f.normal + 0.6 * glam::DVec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5)).to_array();
        x[o..o + 3].copy_from_slice(&l);
    }
    (problem, x)
}

#[test]
fn line_congruence_terms_match_finite_differences() {
    for inequality in [Inequality::Hinge, Inequality::Slack] {
        let (p, x) = setup(inequality);
        assert_fd(&LineCongruence { frames: &p.grid.frames, rows: &p.rows, layout: &p.layout }, &x);
        let normals: Vec<_> = p.grid.frames.iter().map(|f| f.normal).collect();
        let angle = LineNormalAngle { normals, cos2: 20f64.to_radians().cos().powi(2), layout: &p.layout };
        match inequality {
            Inequality::Hinge => {
                let r = residuals(&Hinge::new(angle.clone()), &x);
                let active = r.iter().filter(|v| **v > 0.0).count();
                assert!(active > 0 && active < r.len(), "some hinges active, some not: {active} of {}", r.len());
                assert_fd(&Hinge::new(angle.clone()), &x);
            }
            Inequality::Slack => assert_fd(&angle, &x),
        }
        assert_fd(&line_fairness(p.grid.n, &p.layout), &x);
    }
}

#[test]
fn torsal_terms_match_finite_differences() {
    for inequality in [Inequality::Hinge, Inequality::Slack] {
        let (p, x) = setup(inequality);
        let plane = TorsalDirection { quads: p.quads.clone(), diagonals: p.diagonals.clone(), layout: &p.layout };
        assert_fd(&plane, &x);
        let angle = TorsalAngle { cos2: 75f64.to_radians().cos().powi(2), layout: &p.layout };
        match inequality {
            Inequality::Hinge => {
                let r = residuals(&Hinge::new(angle.clone()), &x);
                assert!(r.iter().any(|v| *v > 0.0) && r.contains(&0.0), "{r:?}");
                assert_fd(&Hinge::new(angle.clone()), &x);
            }
            Inequality::Slack => assert_fd(&angle, &x),
        }
    }
}

/// E_reg: zero residuals at the point it was prepared at, identity Jacobian rows.
#[test]
fn the_regularizer_damps_without_energy() {
    let x = vec![0.3, -1.2, 4.0, 2.5];
    let mut reg = Proximal::new(vec![1, 3]);
    reg.prepare(&x);
    assert_eq!(residuals(&reg, &x), vec![0.0, 0.0]);
    let moved = vec![0.3, -1.0, 4.0, 2.0];
    assert_eq!(residuals(&reg, &moved), vec![-1.0 + 1.2, 2.0 - 2.5]);
    assert_fd(&reg, &x);
}

// ---------------------------------------------------------------------------------------------
// The final sphere-congruence optimization (Sec. 5.2, Eq. 10).

use spherical_faces::pipeline::session::Loaded;
use spherical_faces::samples::Sample;
use spherical_faces::sq::sphere_terms::{
    AxisNormalAngle, CentrePlanarity, CentreProximity, CentreQuadAngle, CentreSeparation, FanAxisAngle, NodeAxis, PanelProximity, TorsalPlane,
    VertexNormals,
};

/// Six spheres (5 blocks with a in ±[0.2, 0.5]), four vertices and four unit-ish normals.
fn sphere_point(seed: u64) -> Vec<f64> {
    let mut rng = Rng(seed);
    let mut x = Vec::new();
    for k in 0..6 {
        let a = (0.2 + 0.3 * rng.uniform()) * if k % 2 == 0 { 1.0 } else { -1.0 };
        x.extend([a, rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5]);
    }
    for _ in 0..8 {
        x.extend([rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() + 0.2]);
    }
    x
}

#[test]
fn final_optimization_terms_match_finite_differences() {
    let loaded = Loaded::from_sample(Sample::from_key("vault").unwrap());
    for seed in [3, 11, 29] {
        let x = sphere_point(seed);
        let s = |k: usize| 5 * k;
        let v = |k: usize| 30 + 3 * k;
        // Stars of four faces, and of three and five at singular vertices (Sec. 5.2).
        let stars = vec![
            (vec![s(0), s(1), s(2), s(3)], v(4)),
            (vec![s(2), s(3), s(4), s(5)], v(5)),
            (vec![s(0), s(2), s(4)], v(6)),
            (vec![s(1), s(2), s(3), s(4), s(5)], v(7)),
        ];
        assert_fd(&CentrePlanarity { stars }, &x);
        let edges = vec![
            (v(0), v(1), NodeAxis::Variable(v(4)), NodeAxis::Variable(v(5)), v(6)),
            (v(1), v(2), NodeAxis::Fixed(glam::DVec3::new(0.1, 0.2, 0.97)), NodeAxis::Variable(v(5)), v(7)),
        ];
        assert_fd(&TorsalPlane { edges }, &x);
        let n = glam::DVec3::new(0.3, -0.2, 0.9).normalize();
        assert_fd(&CentreProximity { faces: vec![(s(0), glam::DVec3::new(0.5, 0.1, -0.3), n), (s(5), glam::DVec3::ZERO, n)], epsilon: 0.01 }, &x);
        // Hinges active and inactive: wide and narrow angles.
        for cos2 in [0.0, 0.3, 0.95] {
            let stars = vec![
                (vec![s(0), s(1), s(2), s(3)], cos2),
                (vec![s(5), s(4), s(3), s(2)], cos2),
                (vec![s(0), s(3), s(5)], 0.5 * cos2),
                (vec![s(0), s(1), s(2), s(4), s(5)], cos2),
            ];
            assert_fd(&CentreQuadAngle { stars: stars.clone() }, &x);
            assert_fd(&Hinge::new(CentreQuadAngle { stars }), &x);
            let normals = VertexNormals::new(&loaded.surface, vec![v(0), v(1)], vec![n, glam::DVec3::Z], &x);
            assert_fd(&AxisNormalAngle { axes: vec![(v(4), 0), (v(5), 1)], normals: normals.clone(), cos2 }, &x);
            assert_fd(&FanAxisAngle { fans: vec![([s(0), s(1), s(2)], 0), ([s(3), s(4), s(5)], 1)], normals, cos2 }, &x);
        }
        // The boundary vertices' distance to the patch's boundary curve, the targets looked up
        // at x (fixed within an iteration), and none of its residuals zero there.
        let boundary = spherical_faces::reference::proximity::BoundaryProximity::new(&loaded.surface, vec![v(0), v(1), v(2)], &x);
        assert_fd(&boundary, &x);
        assert!(residuals(&boundary, &x).chunks(3).all(|d| d.iter().any(|r| r.abs() > 1e-6)));
        // Each panel's value at the reference point closest to its face's centroid (looked up at x).
        let groups = vec![vec![v(0), v(1), v(2)], vec![v(1), v(2), v(3)]];
        let targets = spherical_faces::reference::proximity::CentroidTargets::new(&loaded.surface, groups, &x);
        let (t0, t1) = (targets.target(0), targets.target(1));
        let panel = PanelProximity { spheres: vec![s(0), s(3)], targets };
        assert_fd(&panel, &x);
        let psi = |o: usize, p: glam::DVec3| x[o] * p.length_squared() - glam::DVec3::new(x[o + 1], x[o + 2], x[o + 3]).dot(p) + x[o + 4];
        for (r, want) in residuals(&panel, &x).into_iter().zip([psi(s(0), t0), psi(s(3), t1)]) {
            assert!((r - want).abs() <= 1e-12 * want.abs().max(1.0), "{r} {want}");
        }
        let sep = CentreSeparation { pairs: vec![(s(0), s(1), 0.3), (s(2), s(5), 2.0)], share: 0.25 };
        assert_fd(&sep, &x);
        assert!(residuals(&sep, &x).iter().all(|r| r.is_finite()));
    }
}
