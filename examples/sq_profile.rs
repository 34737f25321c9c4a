//! Profiles the two steps of the SQ congruence optimization on `tunnel_arch` (20 × 20 grid):
//! `cargo run --release --example sq_profile`.

use spherical_faces::import::{import_file, ImportedFile};
use spherical_faces::progress::Clock;
use spherical_faces::sq::optimization::{CongruenceProblem, StepOutcome};
use spherical_faces::sq::params::SqParams;
use spherical_faces::sq::radius::{check_mean_curvature, fit_radius, SamplingGrid};

fn main() {
    let bytes = std::fs::read("../shared/data/bsplines/tunnel_arch.json").expect("../shared");
    let Ok(ImportedFile::BSpline(b)) = import_file(&bytes, "tunnel_arch.json") else { panic!() };
    let s = b.surface.in_frame(glam::DVec3::new(0.0, 6.0, 2.2), 16.75);
    let params = SqParams::default();
    let grid = SamplingGrid::new(&s, params.grid).unwrap();
    let signs = check_mean_curvature(&s, &grid, 1.0, SqParams::default().faces).unwrap();
    let fit = fit_radius(&s, &grid, params.radius_basis, &signs.excluded).unwrap();
    let problem = CongruenceProblem::new(grid, &fit.function, params.inequality);
    let lines = problem.congruence_lines(&fit.function.coefficients).unwrap();
    let clock = Clock::native();
    for _ in 0..3 {
        let mut x = problem.initial_point(&fit.function.coefficients, &lines, &params);
        let lc = problem.line_congruence_step(&mut x, &params, clock, &mut |_, _, _, _| Ok(())).unwrap();
        let mut x = problem.extend_for_torsal(&x);
        let t = problem.torsal_step(&mut x, &params, clock, &mut |_, _, _, _| Ok(())).unwrap();
        print("lc", &lc);
        print("torsal", &t);
    }
}

/// One line per step: iterations, the median iteration and the mean time per phase.
fn print(step: &str, o: &StepOutcome) {
    let per = |total: f64| total / o.iterations.max(1) as f64;
    println!(
        "{step}: {} it, median {:.3} ms; per it: evaluate {:.3}, assemble {:.3}, factorize+solve {:.3}, symbolic {:.3} (total)",
        o.iterations,
        spherical_faces::stats::median(&o.iteration_ms).unwrap_or(0.0),
        per(o.phase_ms.evaluate),
        per(o.phase_ms.assemble),
        per(o.phase_ms.factorize_solve),
        o.phase_ms.symbolic
    );
}
