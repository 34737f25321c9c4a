//! Tests of the sparse nonlinear least-squares solver (`spherical_faces::solver`).

use glam::DVec3;
use spherical_faces::progress::Cancelled;
use spherical_faces::solver::*;

/// Small deterministic generator (splitmix64).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(self.uniform(-1.0, 1.0), self.uniform(-1.0, 1.0), self.uniform(-1.0, 1.0));
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

fn random_x(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng(seed);
    (0..n).map(|_| rng.uniform(-1.5, 1.5)).collect()
}

fn normalized_sphere(center: DVec3, r: f64) -> [f64; 5] {
    // a = 1/(2r), b = centre/r, c = (|centre|² − r²)/(2r): bᵀb − 4ac = 1.
    [1.0 / (2.0 * r), center.x / r, center.y / r, center.z / r, (center.length_squared() - r * r) / (2.0 * r)]
}

const FD_H: f64 = 1e-6;
const FD_TOL: f64 = 1e-6;

fn assert_fd(term: &dyn Term, x: &[f64]) {
    let rep = check_jacobian_report(term, x, FD_H);
    assert!(rep.max_error < FD_TOL, "term '{}': Jacobian mismatch {:?}", term.name(), rep);
    assert_eq!(check_jacobian(term, x, FD_H), rep.max_error);
}

// ------------------------------------------------------------------------------------------
// Finite-difference Jacobians of every provided term.

#[test]
fn fd_jacobian_unit_length_vectors() {
    let x = random_x(12, 1);
    assert_fd(&UnitLength::vectors(vec![0, 3, 9]), &x);
    assert_fd(&UnitLength::vectors_dim(vec![1, 6], 4), &x);
}

#[test]
fn fd_jacobian_unit_length_spheres() {
    let x = random_x(15, 2);
    assert_fd(&UnitLength::spheres(vec![0, 5, 10]), &x);
}

#[test]
fn fd_jacobian_anchor() {
    let x = random_x(8, 3);
    assert_fd(&Anchor::new(vec![0, 5, 7], vec![0.5, -1.0, 2.0]), &x);
    assert_fd(&Anchor::block(2, &[1.0, 2.0, 3.0]), &x);
    let a = Anchor::at_current(vec![1, 4], &x);
    assert_fd(&a, &x);
}

#[test]
fn fd_jacobian_linear() {
    let x = random_x(6, 4);
    let lin = Linear::new()
        .row(&[(0, 1.5), (3, -2.0), (5, 0.25)], 0.7)
        .row(&[(2, 1.0), (2, 3.0)], -1.0) // duplicated column: summed
        .row(&[], 4.0);
    assert_fd(&lin, &x);
}

#[test]
fn fd_jacobian_hinge() {
    // x = (0.2, 2.0, -0.5, 1.3): inner residuals 1 − x_i are 0.8, −1, 1.5, −0.3: two active.
    let x = vec![0.2, 2.0, -0.5, 1.3];
    let mut lin = Linear::new();
    for i in 0..4 {
        lin.push_row(&[(i, -1.0)], 1.0);
    }
    let h = Hinge::new(lin);
    assert_fd(&h, &x);
    // The hinge of a nonlinear term.
    let xs = random_x(10, 5);
    assert_fd(&Hinge::new(UnitLength::spheres(vec![0, 5])), &xs);
    let stats = {
        let mut p = Problem::new(4);
        p.add_term(Hinge::new(Linear::new().row(&[(0, -1.0)], 1.0).row(&[(1, -1.0)], 1.0)), 1.0);
        p.term_stats(&x)
    };
    assert_eq!(stats[0].active, 1);
    assert!((stats[0].max_abs - 0.8).abs() < 1e-15);
    assert!((stats[0].energy - 0.64).abs() < 1e-12);
}

/// The tolerance band |g| ≤ τ: inside, nothing; outside, sign(g) τ ln(|g|/τ), on both sides.
#[test]
fn fd_jacobian_band() {
    // Inner residuals 1 − x_i: 0.8, −1, 1.5, −0.3; with τ = 0.5 the first three are outside.
    let x = vec![0.2, 2.0, -0.5, 1.3];
    let mut lin = Linear::new();
    for i in 0..4 {
        lin.push_row(&[(i, -1.0)], 1.0);
    }
    let band = Band::new(lin, 0.5);
    assert_fd(&band, &x);
    let xs = random_x(10, 5);
    assert_fd(&Band::new(UnitLength::spheres(vec![0, 5]), 0.1), &xs);
    let mut p = Problem::new(4);
    p.add_term(band, 1.0);
    let stats = p.term_stats(&x);
    let wall = |g: f64| 0.5 * (1.0 + (g - 0.5) / 0.5f64).ln();
    assert_eq!(stats[0].active, 3);
    assert!((stats[0].max_abs - wall(1.5)).abs() < 1e-15);
    let energy = wall(0.8).powi(2) + wall(1.0).powi(2) + wall(1.5).powi(2);
    assert!((stats[0].energy - energy).abs() < 1e-12, "{} vs {energy}", stats[0].energy);
    // Near the band the wall is g − τ; far out it grows like τ ln(g/τ): 0.5 ln 100 at g = 50.
    let single = |g: f64| {
        let mut p = Problem::new(1);
        p.add_term(Band::new(Linear::new().row(&[(0, 1.0)], 0.0), 0.5), 1.0);
        p.term_stats(&[g])[0].max_abs
    };
    assert!((single(0.5 + 1e-6) - 1e-6).abs() < 1e-11, "{}", single(0.5 + 1e-6));
    assert!((single(-50.0) - 0.5 * 100f64.ln()).abs() < 1e-12, "{}", single(-50.0));
}

#[test]
fn fd_jacobian_point_on_sphere() {
    let x = random_x(16, 6);
    // points at 0 and 13, spheres at 3 and 8
    assert_fd(&PointOnSphere::new(vec![(0, 3), (13, 3), (0, 8)]), &x);
}

#[test]
fn fd_jacobian_sphere_fit() {
    let x = random_x(7, 7);
    let pts = vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(-0.5, 0.1, 0.3), DVec3::ZERO];
    assert_fd(&SphereFit::new(2, pts), &x);
}

#[test]
fn fd_jacobian_inversive_product() {
    let x = random_x(15, 8);
    assert_fd(&InversiveProduct::new(vec![(0, 5), (5, 10), (10, 10)], 1.0), &x);
    assert_fd(&InversiveProductFixed::new(vec![0, 10], [0.3, 1.0, -0.5, 0.25, 2.0], 0.0), &x);
}

#[test]
fn fd_jacobian_point_on_plane() {
    let x = random_x(11, 9);
    assert_fd(&PointOnPlane::new(vec![(0, 3, 6), (7, 3, 10), (3, 0, 6)]), &x);
}

#[test]
fn fd_jacobian_fn_term() {
    let x = random_x(3, 10);
    let t = FnTerm::new("product", 2, |x: &[f64], r: &mut [f64], jac: &mut JacobianSink| {
        r[0] = x[0] * x[1] - x[2];
        jac.add(0, 0, x[1]);
        jac.add(0, 1, x[0]);
        jac.add(0, 2, -1.0);
        r[1] = x[2].sin();
        jac.add(1, 2, x[2].cos());
    });
    assert_fd(&t, &x);
}

#[test]
fn fd_check_catches_wrong_jacobians() {
    let x = random_x(3, 11);
    let wrong = FnTerm::new("wrong", 1, |x: &[f64], r: &mut [f64], jac: &mut JacobianSink| {
        r[0] = x[0] * x[0] + x[1];
        jac.add(0, 0, x[0]); // should be 2 x0; and ∂/∂x1 is missing
    });
    assert!(check_jacobian(&wrong, &x, FD_H) > 0.1);
}

// ------------------------------------------------------------------------------------------
// Convergence on known problems.

#[test]
fn sphere_fit_to_noisy_points() {
    let mut rng = Rng(42);
    let center = DVec3::new(0.3, -1.2, 2.0);
    let radius = 1.7;
    let noise = 1e-3;
    let pts: Vec<DVec3> = (0..400).map(|_| center + rng.unit_vector() * (radius + rng.uniform(-noise, noise))).collect();
    let mut problem = Problem::new(5);
    problem.add_term(SphereFit::new(0, pts.clone()), 1.0);
    problem.add_term(UnitLength::spheres(vec![0]), 100.0);
    // Rough start: centroid, unit radius.
    let centroid = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
    let mut x = normalized_sphere(centroid + DVec3::new(0.2, 0.1, -0.3), 1.0).to_vec();
    let mut solver = Solver::default();
    let rep = solver.solve(&mut problem, &mut x, |_| Ok(()));
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    let (a, b, c) = (x[0], DVec3::new(x[1], x[2], x[3]), x[4]);
    let fit_center = b / (2.0 * a);
    let fit_radius = (b.length_squared() - 4.0 * a * c).sqrt() / (2.0 * a);
    println!(
        "sphere fit: {} iterations, centre error {:.2e}, radius error {:.2e}, energy {:.3e}",
        rep.iterations,
        (fit_center - center).length(),
        fit_radius - radius,
        rep.energy
    );
    assert!((fit_center - center).length() < noise);
    assert!((fit_radius - radius).abs() < noise);
    assert!((b.length_squared() - 4.0 * a * c - 1.0).abs() < 1e-6);
    // Every point within the noise band of the fitted sphere.
    for p in &pts {
        assert!(((*p - fit_center).length() - fit_radius).abs() < 2.0 * noise);
    }
}

/// A quad grid over a saddle, with noise; returns (vertices, faces as 4 vertex indices).
fn quad_mesh(n: usize, seed: u64) -> (Vec<DVec3>, Vec<[usize; 4]>) {
    let mut rng = Rng(seed);
    let mut verts = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let u = -1.0 + 2.0 * i as f64 / n as f64;
            let v = -1.0 + 2.0 * j as f64 / n as f64;
            verts.push(DVec3::new(u + rng.uniform(-0.02, 0.02), v + rng.uniform(-0.02, 0.02), 0.3 * (u * u - v * v) + rng.uniform(-0.02, 0.02)));
        }
    }
    let mut faces = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let k = j * (n + 1) + i;
            faces.push([k, k + 1, k + n + 2, k + n + 1]);
        }
    }
    (verts, faces)
}

struct Planarization<'a> {
    problem: Problem<'a>,
    x: Vec<f64>,
    closeness: TermId,
    n_verts: usize,
    faces: Vec<[usize; 4]>,
}

/// Variables: vertices (3 each), then per face a unit normal (3) and an offset (1).
fn planarization(n: usize) -> Planarization<'static> {
    let (verts, faces) = quad_mesh(n, 7);
    let nv = verts.len();
    let nf = faces.len();
    let n_vars = 3 * nv + 4 * nf;
    let mut x = vec![0.0; n_vars];
    for (i, v) in verts.iter().enumerate() {
        x[3 * i..3 * i + 3].copy_from_slice(&v.to_array());
    }
    let normal = |f: usize| 3 * nv + 3 * f;
    let offset = |f: usize| 3 * nv + 3 * nf + f;
    let mut items = Vec::new();
    for (f, q) in faces.iter().enumerate() {
        let n = (verts[q[2]] - verts[q[0]]).cross(verts[q[3]] - verts[q[1]]).normalize();
        let d = q.iter().map(|&k| n.dot(verts[k])).sum::<f64>() / 4.0;
        x[normal(f)..normal(f) + 3].copy_from_slice(&n.to_array());
        x[offset(f)] = d;
        for &k in q {
            items.push((3 * k, normal(f), offset(f)));
        }
    }
    let mut problem = Problem::new(n_vars);
    problem.add_term(PointOnPlane::new(items).with_name("planarity"), 1.0);
    problem.add_term(UnitLength::vectors((0..nf).map(normal).collect()), 1.0);
    let closeness = problem.add_term(Anchor::at_current((0..3 * nv).collect(), &x).with_name("closeness"), 1e-2);
    Planarization { problem, x, closeness, n_verts: nv, faces }
}

fn max_planarity(p: &Planarization) -> f64 {
    let nv = p.n_verts;
    let nf = p.faces.len();
    let x = &p.x;
    let mut worst = 0.0f64;
    for (f, q) in p.faces.iter().enumerate() {
        let n = DVec3::from_slice(&x[3 * nv + 3 * f..]).normalize();
        let d = x[3 * nv + 3 * nf + f] / DVec3::from_slice(&x[3 * nv + 3 * f..]).length();
        for &k in q {
            worst = worst.max((n.dot(DVec3::from_slice(&x[3 * k..])) - d).abs());
        }
    }
    worst
}

#[test]
fn planarize_quad_mesh() {
    let mut p = planarization(12);
    let x0 = p.x.clone();
    let diag = 2.0 * 3f64.sqrt();
    let initial = max_planarity(&p);
    let mut solver = Solver::default();
    let mut energies = Vec::new();
    for w in [1e-2, 1e-4, 1e-6, 0.0] {
        p.problem.set_weight(p.closeness, w);
        energies.clear();
        let rep = solver.solve(&mut p.problem, &mut p.x, |it| {
            energies.push(it.energy);
            Ok(())
        });
        println!(
            "closeness {w:e}: {} iterations ({} accepted), energy {:.3e} → {:.3e}, {:?}, terms {:?}",
            rep.iterations,
            rep.accepted_steps,
            rep.initial_energy,
            rep.energy,
            rep.termination,
            rep.terms.iter().map(|t| (t.name.as_str(), t.max_abs)).collect::<Vec<_>>()
        );
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        // Monotone: the energy never increases within a stage.
        assert!(energies.windows(2).all(|w| w[1] <= w[0]));
    }
    let fin = max_planarity(&p);
    let moved = (0..3 * p.n_verts).map(|i| (p.x[i] - x0[i]).abs()).fold(0.0, f64::max);
    println!("planarity {initial:.3e} → {fin:.3e} (diag {diag:.3}); max vertex move {moved:.3e}");
    assert!(initial > 1e-3);
    assert!(fin < 1e-8 * diag, "max planarity residual {fin:e}");
    // Unit normals, and the reported statistics agree.
    let stats = p.problem.term_stats(&p.x);
    assert!(stats[0].max_abs < 1e-8 * diag);
    assert!(stats[1].max_abs < 1e-8);
    assert!(moved < 0.1, "vertices moved {moved}");
    assert_eq!(solver.symbolic_analyses(), 1);
}

#[test]
fn hinge_one_sided() {
    // x ≥ 1 and y ≥ 1 as hinges g = 1 − v ≤ 0 (weight 1e6), anchors pull x to 0 and y to 3.
    let mut problem = Problem::new(2);
    problem.add_term(Anchor::new(vec![0, 1], vec![0.0, 3.0]), 1.0);
    let ge1 = Linear::new().row(&[(0, -1.0)], 1.0).row(&[(1, -1.0)], 1.0);
    problem.add_term(Hinge::new(ge1).with_name("x>=1"), 1e6);
    let mut x = vec![3.0, 5.0];
    let mut solver = Solver::default();
    let rep = solver.solve(&mut problem, &mut x, |_| Ok(()));
    println!("hinge: x = {:?}, {:?}, {} iterations", x, rep.termination, rep.iterations);
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    // Penalty optimum of x² + 1e6 (1 − x)²: x = 1e6 / (1e6 + 1).
    assert!((x[0] - 1e6 / (1e6 + 1.0)).abs() < 1e-9, "x = {}", x[0]);
    // The inactive hinge does not act on y (converged to the relative-decrease tolerance).
    assert!((x[1] - 3.0).abs() < 1e-9, "y = {}", x[1]);
    assert_eq!(rep.terms[1].name, "x>=1");
    assert_eq!(rep.terms[1].active, 1);
    assert!(rep.terms[1].max_abs > 0.0 && rep.terms[1].max_abs < 1e-5);
}

#[test]
fn fixed_variables_stay_bit_identical() {
    let mut p = planarization(6);
    let nv = p.n_verts;
    // Fix the boundary row j = 0 of vertices, and one face's offset.
    let fixed: Vec<usize> = (0..7 * 3).chain([3 * nv + 4 * p.faces.len() - 1]).collect();
    for &i in &fixed {
        p.x[i] += 0.1 + 0.2; // non-representable sums: any rounding would show
        p.problem.fix(i);
    }
    let before: Vec<u64> = fixed.iter().map(|&i| p.x[i].to_bits()).collect();
    let x0 = p.x.clone();
    let mut solver = Solver::default();
    p.problem.set_weight(p.closeness, 1e-4);
    let rep = solver.solve(&mut p.problem, &mut p.x, |_| Ok(()));
    assert!(rep.accepted_steps > 0);
    assert_eq!(rep.free_variables, p.x.len() - fixed.len());
    let after: Vec<u64> = fixed.iter().map(|&i| p.x[i].to_bits()).collect();
    assert_eq!(before, after);
    assert!((0..p.x.len()).any(|i| p.x[i] != x0[i]), "free variables must move");
    assert!(rep.energy < 1e-3 * rep.initial_energy);
}

/// With a decrease window of k iterations the solver stops at the first iteration where the
/// last k together lowered the energy by at most the tolerance's fraction, and not before.
#[test]
fn a_decrease_window_stops_where_k_iterations_together_barely_descend() {
    let (k, tolerance) = (4, 0.5);
    let mut p = planarization(8);
    p.problem.set_weight(p.closeness, 1e-3);
    let mut solver =
        Solver::new(SolverOptions { relative_decrease_tolerance: tolerance, decrease_window: k, step_tolerance: 0.0, ..Default::default() });
    let mut energies = vec![];
    let rep = solver.solve(&mut p.problem, &mut p.x, |it| {
        energies.push(it.energy);
        Ok(())
    });
    energies.insert(0, rep.initial_energy);
    assert_eq!(rep.termination, Termination::RelativeDecrease, "{energies:?}");
    let flat = |i: usize| i >= k && energies[i - k] - energies[i] <= tolerance * energies[i - k];
    let n = rep.iterations;
    assert!(flat(n), "{energies:?}");
    assert!((1..n).all(|i| !flat(i)), "stopped late: {energies:?}");
    assert!(n > k, "{energies:?}");
}

#[test]
fn symbolic_factorization_is_reused() {
    let mut p = planarization(8);
    let mut solver = Solver::new(SolverOptions { max_iterations: 20, step_tolerance: 0.0, relative_decrease_tolerance: 0.0, ..Default::default() });
    for w in [1e-1, 1e-2, 1e-3, 1e-4] {
        p.problem.set_weight(p.closeness, w);
        solver.solve(&mut p.problem, &mut p.x, |_| Ok(()));
    }
    assert!(solver.numeric_factorizations() >= 20, "{}", solver.numeric_factorizations());
    assert_eq!(solver.symbolic_analyses(), 1);

    // A new term changes the pattern: one more analysis, then reuse again.
    let n = p.problem.num_variables();
    p.problem.add_term(Anchor::new(vec![0], vec![p.x[0]]), 1.0);
    let rep = solver.solve(&mut p.problem, &mut p.x, |_| Ok(()));
    assert_eq!(rep.symbolic_analyses, 1);
    assert_eq!(solver.symbolic_analyses(), 2);
    let rep = solver.solve(&mut p.problem, &mut p.x, |_| Ok(()));
    assert_eq!(rep.symbolic_analyses, 0);
    // Fixing a variable changes the pattern too.
    p.problem.fix(n - 1);
    solver.solve(&mut p.problem, &mut p.x, |_| Ok(()));
    assert_eq!(solver.symbolic_analyses(), 3);
}

#[test]
fn structure_change_during_a_run_is_detected() {
    // A term that emits an extra Jacobian entry once x0 < 0.5: the pattern changes mid-run.
    let t = FnTerm::new("switching", 2, |x: &[f64], r: &mut [f64], jac: &mut JacobianSink| {
        r[0] = x[0] - 0.25;
        jac.add(0, 0, 1.0);
        if x[0] < 0.5 {
            r[1] = x[1] - x[0];
            jac.add(1, 0, -1.0);
        } else {
            r[1] = x[1] - 0.5;
        }
        jac.add(1, 1, 1.0);
    });
    let mut problem = Problem::new(2);
    problem.add_term(t, 1.0);
    let mut x = vec![1.0, 3.0];
    let mut solver = Solver::default();
    let rep = solver.solve(&mut problem, &mut x, |_| Ok(()));
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    assert_eq!(rep.symbolic_analyses, 2);
    assert!((x[0] - 0.25).abs() < 1e-10 && (x[1] - 0.25).abs() < 1e-10, "{x:?}");
}

#[test]
fn cancel_via_hook_stops_immediately() {
    let mut p = planarization(8);
    let mut solver = Solver::default();
    let mut calls = 0;
    let mut last_x = Vec::new();
    let rep = solver.solve(&mut p.problem, &mut p.x, |it| {
        calls += 1;
        assert_eq!(it.iteration, calls);
        assert_eq!(it.terms.len(), 3);
        last_x = it.x.to_vec();
        if it.iteration < 3 {
            Ok(())
        } else {
            Err(Cancelled)
        }
    });
    assert_eq!(calls, 3);
    assert_eq!(rep.iterations, 3);
    assert_eq!(rep.termination, Termination::Cancelled);
    assert_eq!(rep.numeric_factorizations, 3);
    assert_eq!(last_x, p.x);
}

#[test]
fn reports_per_term_statistics() {
    let mut problem = Problem::new(3);
    let a = problem.add_term(Anchor::new(vec![0, 1], vec![1.0, -2.0]).with_name("a"), 2.0);
    problem.add_term(Linear::new().row(&[(2, 1.0)], 0.0).with_name("b"), 0.5);
    let x = vec![0.0, 0.0, 3.0];
    let s = problem.term_stats(&x);
    assert_eq!(s[0].name, "a");
    assert_eq!(s[0].residuals, 2);
    assert!((s[0].mean_abs - 1.5).abs() < 1e-15);
    assert!((s[0].max_abs - 2.0).abs() < 1e-15);
    assert!((s[0].energy - 2.0 * 5.0).abs() < 1e-12);
    assert!((s[1].energy - 0.5 * 9.0).abs() < 1e-12);
    assert!((problem.energy(&x) - 14.5).abs() < 1e-12);
    problem.set_weight(a, 0.0);
    assert_eq!(problem.weight(a), 0.0);
    assert!((problem.energy(&x) - 4.5).abs() < 1e-12);
    // The report serializes (for the worker protocol / report.json).
    let mut solver = Solver::default();
    let mut xs = x.clone();
    let rep = solver.solve(&mut problem, &mut xs, |it| {
        serde_json::to_string(it).unwrap();
        Ok(())
    });
    let json = serde_json::to_string(&rep).unwrap();
    let back: SolveReport = serde_json::from_str(&json).unwrap();
    assert_eq!(back.terms, rep.terms);
    assert!(xs[2].abs() < 1e-10);
    assert_eq!(xs[0], 0.0); // weight 0: untouched by the solve (regularization only)
}

#[test]
fn auxiliary_variables() {
    // Minimize Σ (p_i − s)² with an auxiliary s appended after the "real" variables p: s = mean.
    let mut problem = Problem::new(4);
    let aux = problem.add_variables(1);
    assert_eq!(aux, 4..5);
    let mut lin = Linear::new();
    for i in 0..4 {
        lin.push_row(&[(i, 1.0), (aux.start, -1.0)], 0.0);
    }
    problem.add_term(lin, 1.0);
    for i in 0..4 {
        problem.fix(i);
    }
    let mut x = vec![1.0, 2.0, 4.0, 9.0, 0.0];
    let rep = Solver::default().solve(&mut problem, &mut x, |_| Ok(()));
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    assert!((x[4] - 4.0).abs() < 1e-10, "{x:?}");
}

#[test]
fn all_fixed_or_empty_problems() {
    let mut problem = Problem::new(2);
    problem.add_term(Anchor::new(vec![0], vec![1.0]), 1.0);
    problem.fix_range(0..2);
    let mut x = vec![0.0, 0.0];
    let rep = Solver::default().solve(&mut problem, &mut x, |_| panic!("no iteration expected"));
    assert_eq!(rep.termination, Termination::NoFreeVariables);
    assert_eq!(x, vec![0.0, 0.0]);
    let mut empty = Problem::new(3);
    let rep = Solver::default().solve(&mut empty, &mut [1.0, 2.0, 3.0], |_| Ok(()));
    assert_eq!(rep.termination, Termination::EnergyTolerance);
}

// ------------------------------------------------------------------------------------------
// Timing (ignored): cargo test --release --test solver -- --ignored --nocapture

/// ST-like synthetic problem: a triangulated height field with `n × n` vertices, one normalized
/// generalized sphere per face; terms: vertices on their faces' spheres, normalization,
/// inversive product of neighbouring faces → 1, closeness of vertices and optionally a Laplacian
/// fairness (which couples 2-ring neighbours and about doubles the Cholesky fill).
fn st_like(n: usize, fairness: bool) -> (Problem<'static>, Vec<f64>) {
    let mut rng = Rng(99);
    let vid = |i: usize, j: usize| j * n + i;
    let mut verts = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let u = i as f64 / (n - 1) as f64 * 2.0 - 1.0;
            let v = j as f64 / (n - 1) as f64 * 2.0 - 1.0;
            verts.push(DVec3::new(u, v, 0.3 * (1.5 * u).sin() * (1.2 * v).cos() + rng.uniform(-0.01, 0.01)));
        }
    }
    let mut faces = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            faces.push([vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)]);
            faces.push([vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)]);
        }
    }
    let nv = verts.len();
    let nf = faces.len();
    let sph = |f: usize| 3 * nv + 5 * f;
    let mut x = vec![0.0; 3 * nv + 5 * nf];
    for (i, v) in verts.iter().enumerate() {
        x[3 * i..3 * i + 3].copy_from_slice(&v.to_array());
    }
    for (f, t) in faces.iter().enumerate() {
        // A large sphere through the centroid with the face normal (nearly the face plane).
        let (a, b, c) = (verts[t[0]], verts[t[1]], verts[t[2]]);
        let nrm = (b - a).cross(c - a).normalize();
        let m = (a + b + c) / 3.0;
        let s = normalized_sphere(m - 4.0 * nrm, 4.0);
        x[sph(f)..sph(f) + 5].copy_from_slice(&s);
    }
    let mut on_sphere = Vec::new();
    for (f, t) in faces.iter().enumerate() {
        for &v in t {
            on_sphere.push((3 * v, sph(f)));
        }
    }
    // Edge adjacency.
    let mut edges = std::collections::HashMap::new();
    let mut pairs = Vec::new();
    for (f, t) in faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if let Some(g) = edges.insert(key, f) {
                pairs.push((sph(g), sph(f)));
            }
        }
    }
    let mut fair = Linear::new().with_name("fairness");
    for j in 1..n - 1 {
        for i in 1..n - 1 {
            let nb = [vid(i - 1, j), vid(i + 1, j), vid(i, j - 1), vid(i, j + 1), vid(i + 1, j + 1), vid(i - 1, j - 1)];
            for k in 0..3 {
                let mut row = vec![(3 * vid(i, j) + k, 1.0)];
                row.extend(nb.iter().map(|&q| (3 * q + k, -1.0 / 6.0)));
                fair.push_row(&row, 0.0);
            }
        }
    }
    let mut problem = Problem::new(x.len());
    problem.add_term(PointOnSphere::new(on_sphere).with_name("E_sphere"), 1.0);
    problem.add_term(UnitLength::spheres((0..nf).map(sph).collect()), 1.0);
    problem.add_term(InversiveProduct::new(pairs, 1.0).with_name("angle"), 0.1);
    problem.add_term(Anchor::at_current((0..3 * nv).collect(), &x).with_name("closeness"), 0.01);
    if fairness {
        problem.add_term(fair, 0.001);
    }
    (problem, x)
}

#[test]
fn st_like_problem_converges_small() {
    let (mut problem, mut x) = st_like(6, true);
    for t in 0..problem.num_terms() {
        let term = problem.term(TermId(t));
        assert!(check_jacobian(term, &x, FD_H) < FD_TOL, "{}", term.name());
    }
    let mut solver = Solver::default();
    let rep = solver.solve(&mut problem, &mut x, |_| Ok(()));
    assert!(rep.energy < rep.initial_energy);
    assert_eq!(rep.symbolic_analyses, 1);
}

/// Every fill-reducing ordering gives the same iterates (up to rounding) on an ST-like problem
/// whose spheres and vertices are declared blocks; the report names the ordering used.
#[test]
fn orderings_agree() {
    use spherical_faces::solver::Ordering;
    let mut results = Vec::new();
    for ordering in [Ordering::Amd, Ordering::BlockAmd, Ordering::NestedDissection, Ordering::Auto] {
        let (mut problem, mut x) = st_like(9, true);
        let nv = 81;
        for v in 0..nv {
            problem.group_variables(3 * v..3 * v + 3);
        }
        for f in 0..2 * 8 * 8 {
            problem.group_variables(3 * nv + 5 * f..3 * nv + 5 * f + 5);
        }
        let mut solver = Solver::new(SolverOptions { max_iterations: 8, ordering, ..Default::default() });
        let rep = solver.solve(&mut problem, &mut x, |_| Ok(()));
        assert_eq!(rep.symbolic_analyses, 1);
        match ordering {
            Ordering::Auto => assert!(matches!(rep.ordering, Ordering::BlockAmd | Ordering::NestedDissection)),
            o => assert_eq!(rep.ordering, o),
        }
        assert!(rep.energy < rep.initial_energy, "{ordering:?}: {} → {}", rep.initial_energy, rep.energy);
        results.push((rep.energy, x));
    }
    let (e0, x0) = &results[0];
    for (e, x) in &results[1..] {
        assert!((e - e0).abs() <= 1e-9 * e0.abs(), "energies {e} vs {e0}");
        let dx = x.iter().zip(x0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(dx < 1e-8, "iterates differ by {dx}");
    }
}

#[cfg(not(target_arch = "wasm32"))] // a native clock
#[test]
#[ignore]
fn timing_synthetic_600_faces() {
    use spherical_faces::progress::native_clock_ms as now_ms;
    for (n, fairness) in [(18usize, true), (18, false), (56, true), (56, false)] {
        let (mut problem, mut x) = st_like(n, fairness);
        let mut solver = Solver::new(SolverOptions {
            max_iterations: 30,
            step_tolerance: 0.0,
            relative_decrease_tolerance: 0.0,
            clock: spherical_faces::progress::Clock(Some(now_ms)),
            ..Default::default()
        });
        let t0 = now_ms();
        let rep = solver.solve(&mut problem, &mut x, |_| Ok(()));
        let total = now_ms() - t0;
        let mut ms = rep.iteration_ms.clone();
        ms.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let median = ms[ms.len() / 2];
        println!(
            "synthetic ST-like, {} faces{}: {} variables, {} residuals, JᵀJ nnz {}: {} iterations ({} accepted), \
             first solve incl. symbolic {:.2} ms, median {:.3} ms/iteration, min {:.3}, max {:.3}; energy {:.3e} → {:.3e}",
            2 * (n - 1) * (n - 1),
            if fairness { " with fairness" } else { "" },
            rep.free_variables,
            rep.residuals,
            rep.normal_matrix_nnz,
            rep.iterations,
            rep.accepted_steps,
            total,
            median,
            ms[0],
            ms[ms.len() - 1],
            rep.initial_energy,
            rep.energy
        );
        let it = rep.iterations as f64;
        println!(
            "  L nnz {} ({}), flops {:.2e}, per iteration: evaluate {:.3} ms, assemble {:.3} ms, factorize+solve {:.3} ms; symbolic {:.2} ms",
            rep.factor_nnz,
            if rep.supernodal { "supernodal" } else { "simplicial" },
            rep.factor_flops,
            rep.phase_ms.evaluate / it,
            rep.phase_ms.assemble / it,
            rep.phase_ms.factorize_solve / it,
            rep.phase_ms.symbolic
        );
    }
}
