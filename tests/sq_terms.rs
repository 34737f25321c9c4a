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
use spherical_faces::sq::terms::{line_fairness, LineCongruence, LineNormalAngle, TorsalAngle, TorsalPlane};

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
        let plane = TorsalPlane { quads: p.quads.clone(), diagonals: p.diagonals.clone(), layout: &p.layout };
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
