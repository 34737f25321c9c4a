//! Benchmark workloads, shared by the native divan benches (`benches/pipeline.rs`, `cargo bench`)
//! and the wasm runner in the browser (`tests/wasm_bench.rs`), so that both time exactly the same
//! work. Everything is generated in code and deterministic.
//!
//! - `jet_fit`: [`jet_fit`] with default [`JetParams`] on the free-form dome sampled with about
//!   100 000 vertices;
//! - `remesh_round_uniform` / `remesh_round_adaptive`: one pliant remeshing round
//!   ([`Remesher::round`], after [`Remesher::new`], which is not timed) of the dome with about
//!   100 000 triangles, for the uniform field g = mean edge length of the reference and for the
//!   adaptive field of the central spheres' influence zones ([`SizingField::from_curvature`]);
//! - `angle_iteration_600` / `angle_iteration_6000`: single Levenberg–Marquardt iterations of the
//!   angle-minimizing ST problem (`st_adapted::terms::build_problem`, set up as
//!   `st_adapted::compute` does) on the dome remeshed uniformly to about 600 and 6000 faces. Each sample restarts from the
//!   same initial point and runs [`ANGLE_ITERATIONS_PER_SAMPLE`] iterations; the solver's own
//!   per-iteration times (`SolverOptions::clock`) are the measurement.
//!
//! - `sq_lc_iteration` / `sq_torsal_iteration` / `sq_final_iteration` / `sq_pipeline`: the SQ
//!   method ([`crate::sq::compute`] with default parameters: θ 20°, α 75°, a 20×20 grid, about
//!   237 quads) on `tunnel_arch`; one sample is one whole run. The solver's per-iteration times
//!   of the two congruence steps (Sec. 5.1) and of the full final optimization (Eq. 10) are
//!   measured, and the whole run from the B-spline to the panels and support structure.
//! - `sq_pipeline_roof_rough` / `sq_pipeline_tunnel_bulged`: one whole SQ run with default
//!   parameters on two surfaces with real roofs' dimensionless curvature ([`SQ_HARD`]: a degree-10
//!   rough roof, a tunnel with K of both signs).
//!
//! - `mould_fits_10k` / `mould_assign_10k`: the fit data of about 10 000 panels (the dome
//!   remeshed uniformly, each face's sphere the pencil member nearest its central sphere,
//!   tessellated) and the fewest moulds within 2e-4 of the diagonal on them
//!   ([`crate::panels::moulds`]); the panels are built once, untimed.
//!
//! No `std::time` here (it panics on wasm32): timing takes a clock, in milliseconds.

use crate::congruence::central_spheres::{jet_fit, CurvatureField, JetParams};
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::import::{import_file, ImportedFile};
use crate::panels::build_panels;
use crate::panels::moulds::{Fabrication, MouldFits};
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::pipeline::method::export;
use crate::pipeline::stages::st_adapted::StAdaptedStage;
use crate::progress::ignore;
use crate::progress::Clock;
use crate::reference::Reference;
use crate::remeshing::pliant::Remesher;
use crate::remeshing::{mean_edge_length, pliant_remesh, RemeshParams, RoundStats, SizingField};
use crate::samples;
use crate::solver::{PhaseTimes, Problem, Solver, SolverOptions};
use crate::sq;
use crate::sq::params::SqParams;
use crate::st_adapted::initialization::initial_spheres;
use crate::st_adapted::optimization::OptimizationFrame;
use crate::st_adapted::params::StAdaptedParams;
use crate::stats;

/// Workload size: `Full` for benchmarking, `Tiny` to exercise the code quickly (`cargo test`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    Full,
    Tiny,
}

/// Dome rings for the jet-fit mesh: 1 + 3·182·183 = 99 919 vertices.
pub(crate) const JET_RINGS: usize = 182;
/// Dome rings for the remeshing reference: 6·129² = 99 846 triangles.
pub(crate) const REMESH_RINGS: usize = 129;
/// Relative tolerance ε of the adaptive sizing field. Not the app's default (4e-4, which asks
/// for about 500 faces, so a round would mostly collapse): 2e-6 gives a field of about the
/// reference's density (median g ≈ its mean edge length), so the round splits, collapses, flips
/// and smooths at about 100k triangles.
pub const ADAPTIVE_EPSILON: f64 = 2e-6;
/// Target face counts of the angle-optimization benchmarks.
pub const ANGLE_FACES: [usize; 2] = [600, 6000];
/// LM iterations per angle-optimization sample (each sample restarts from the initial point).
pub const ANGLE_ITERATIONS_PER_SAMPLE: usize = 5;

/// The free-form dome with `rings` rings ([`samples::dome`]), `Tiny` → 8 rings.
pub fn dome(rings: usize, scale: Scale) -> TriMesh {
    samples::dome(match scale {
        Scale::Full => rings,
        Scale::Tiny => 8,
    })
}

/// The one-line result both runners print: `bench <name>: <ms> ms/iter (n=<samples>)`, the
/// median over the samples.
pub fn result_line(name: &str, samples_ms: &[f64]) -> String {
    let median = stats::median(samples_ms).unwrap_or(f64::NAN);
    format!("bench {name}: {median:.3} ms/iter (n={})", samples_ms.len())
}

/// Times `f` `n` times with `clock`, in milliseconds.
pub(crate) fn time_n(clock: Clock, n: usize, mut f: impl FnMut()) -> Vec<f64> {
    (0..n)
        .map(|_| {
            let t = clock.now();
            f();
            clock.now() - t
        })
        .collect()
}

// --- 1. jet fitting ------------------------------------------------------------------------------

/// The jet-fit workload: mesh, topology, default parameters.
pub struct JetWorkload {
    pub mesh: TriMesh,
    pub topo: Topology,
    pub params: JetParams,
}

impl JetWorkload {
    pub fn new(scale: Scale) -> Self {
        let mesh = dome(JET_RINGS, scale);
        let topo = Topology::new(&mesh);
        Self { mesh, topo, params: JetParams::default() }
    }

    /// The timed work: one jet fit of every vertex.
    pub fn run(&self) -> CurvatureField {
        jet_fit(&self.mesh, &self.topo, &self.params, &mut ignore).expect("jet fit")
    }
}

// --- 2. one pliant remeshing round ---------------------------------------------------------------

/// Which sizing field the remeshing round uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoundSizing {
    /// g = the reference's mean edge length.
    Uniform,
    /// Influence zones of the reference's central spheres, ε = [`ADAPTIVE_EPSILON`].
    Adaptive,
}

/// The remeshing workload: reference, sizing fields, default parameters.
pub struct RemeshWorkload {
    pub reference: TriMesh,
    pub uniform: SizingField,
    pub adaptive: SizingField,
    pub params: RemeshParams,
}

impl RemeshWorkload {
    /// Builds the reference and both sizing fields (the adaptive one needs a jet fit and the
    /// influence zones: a few seconds at full scale).
    pub fn new(scale: Scale) -> Self {
        let reference = dome(REMESH_RINGS, scale);
        let topo = Topology::new(&reference);
        let uniform = SizingField::uniform(&reference, mean_edge_length(&reference, &topo));
        let field = jet_fit(&reference, &topo, &JetParams::default(), &mut ignore).expect("jet fit");
        let adaptive = SizingField::from_curvature(&reference, &topo, &field, ADAPTIVE_EPSILON);
        Self { reference, uniform, adaptive, params: RemeshParams::default() }
    }

    pub fn sizing(&self, sizing: RoundSizing) -> &SizingField {
        match sizing {
            RoundSizing::Uniform => &self.uniform,
            RoundSizing::Adaptive => &self.adaptive,
        }
    }

    /// Untimed setup of one sample: a fresh remesher on the reference.
    pub fn remesher(&self, sizing: RoundSizing) -> Remesher<'_> {
        Remesher::new(&self.reference, self.sizing(sizing), &self.params)
    }

    /// The timed work: one round.
    pub fn round(remesher: &mut Remesher<'_>) -> RoundStats {
        remesher.round()
    }

    /// Times `n` rounds, each on a fresh remesher (built and dropped outside the timing).
    pub(crate) fn time_rounds(&self, sizing: RoundSizing, clock: Clock, n: usize) -> (Vec<f64>, RoundStats) {
        let mut stats = RoundStats::default();
        let ms = (0..n)
            .map(|_| {
                let mut r = self.remesher(sizing);
                let t = clock.now();
                stats = Self::round(&mut r);
                let ms = clock.now() - t;
                drop(r);
                ms
            })
            .collect();
        (ms, stats)
    }
}

// --- 3. angle-optimization iterations -----------------------------------------------------------

/// The angle-minimizing ST problem in the normalized frame, set up as `st_adapted::compute` does
/// (uniform remeshing to about `target_faces` faces, initial spheres from the central spheres of
/// the remeshed mesh, boundary and feature vertices fixed), "angle" stage weights.
pub struct AngleWorkload {
    /// The reference (the default dome) and the remeshed mesh in the optimization's frame, the
    /// initial point and the fixed vertices.
    pub frame: OptimizationFrame,
    pub params: StAdaptedParams,
}

impl AngleWorkload {
    pub fn new(target_faces: usize, scale: Scale) -> Self {
        let target_faces = match scale {
            Scale::Full => target_faces,
            Scale::Tiny => 60,
        };
        let params = StAdaptedParams::default();
        let reference = Reference::from_triangles(samples::Sample::Dome.mesh());
        let sizing = SizingField::uniform_for_face_count(reference.mesh(), target_faces);
        let remeshed = pliant_remesh(reference.mesh(), &sizing, &params.remesh, &mut ignore).expect("remesh");
        let rtopo = Topology::new(&remeshed);
        let rfield = jet_fit(&remeshed, &rtopo, &params.jet, &mut ignore).expect("jet fit");
        let init = initial_spheres(&remeshed, &rfield.central_spheres);
        let frame = OptimizationFrame::new(&reference, &remeshed, &init, &params);
        Self { frame, params }
    }

    pub fn faces(&self) -> usize {
        self.frame.mesh.face_count()
    }

    /// The problem at the initial point with the fixed vertices fixed.
    pub fn problem(&self) -> Problem<'_> {
        self.frame.problem(&self.params.variant_weights()).0
    }

    /// A solver for [`ANGLE_ITERATIONS_PER_SAMPLE`] iterations, timing each one with `clock`.
    pub fn solver(&self, clock: Clock) -> Solver {
        Solver::new(SolverOptions {
            max_iterations: ANGLE_ITERATIONS_PER_SAMPLE,
            initial_epsilon: self.params.initial_epsilon,
            clock,
            ..SolverOptions::default()
        })
    }

    /// The timed work of one sample: [`ANGLE_ITERATIONS_PER_SAMPLE`] iterations from the initial
    /// point; returns the per-iteration times (empty without a clock).
    pub fn sample(&self, problem: &mut Problem<'_>, solver: &mut Solver) -> Vec<f64> {
        self.sample_with_phases(problem, solver).0
    }

    /// [`Self::sample`] with the solver's phase times (evaluate, assemble, factorize + solve).
    pub fn sample_with_phases(&self, problem: &mut Problem<'_>, solver: &mut Solver) -> (Vec<f64>, PhaseTimes) {
        let mut x = self.frame.x0.clone();
        let report = solver.solve(problem, &mut x, |_| Ok(()));
        (report.iteration_ms, report.phase_ms)
    }
}

/// The phase times per iteration of `phases` summed over `iterations`, as an informational line:
/// where an iteration's time goes, natively and in wasm.
pub fn phase_line(name: &str, phases: &PhaseTimes, iterations: usize) -> String {
    let n = iterations.max(1) as f64;
    format!(
        "# {name} per iteration: evaluate {:.3} ms, assemble {:.3} ms, factorize+solve {:.3} ms",
        phases.evaluate / n,
        phases.assemble / n,
        phases.factorize_solve / n
    )
}

// --- 4. SQ congruence iterations ----------------------------------------------------------------

/// `tunnel_arch.json` (benches/data, a copy of ../shared/data/bsplines).
pub(crate) const TUNNEL_ARCH: &str = include_str!("../benches/data/tunnel_arch.json");

/// The SQ method on `tunnel_arch` or another surface ([`Self::on`]): default parameters (on
/// `tunnel_arch` a 20 × 20 grid and about 237 quads), or an 8 × 8 grid and 16 quads when tiny.
pub struct SqWorkload {
    pub reference: Reference,
    pub params: SqParams,
}

/// The hard surfaces whole SQ runs are timed on (benches/data, copies of
/// ../shared/data/bsplines/hard): (benchmark name, file).
pub const SQ_HARD: [(&str, &str); 2] = [
    ("sq_pipeline_roof_rough", include_str!("../benches/data/roof_rough.json")),
    ("sq_pipeline_tunnel_bulged", include_str!("../benches/data/tunnel_bulged.json")),
];

/// Whole SQ runs per hard surface.
pub const SQ_HARD_SAMPLES: usize = 3;

impl SqWorkload {
    /// On `tunnel_arch`.
    pub fn new(scale: Scale) -> Self {
        Self::on(TUNNEL_ARCH, scale)
    }

    /// On the surface of a B-spline JSON file.
    pub fn on(json: &str, scale: Scale) -> Self {
        let ImportedFile::BSpline(b) = import_file(json.as_bytes(), "surface.json").expect("the surface imports") else {
            unreachable!("a B-spline JSON file")
        };
        let reference = Reference::from_bspline(b.surface).expect("the surface is regular");
        let params = match scale {
            Scale::Full => SqParams::default(),
            Scale::Tiny => SqParams {
                grid: 8,
                lc_iterations: 3,
                torsal_iterations: 3,
                final_iterations: 1,
                faces: 16,
                fairing_iterations: 2,
                sphere_iterations: [1, 3, 3],
                ..SqParams::default()
            },
        };
        Self { reference, params }
    }

    /// The timed work: one whole run; the per-iteration times (ms) of step 1, step 2 and the
    /// final optimization, and the run's total (ms).
    pub fn sample(&self, clock: Clock) -> SqSample {
        let t0 = clock.now();
        let r = sq::compute(&self.reference, &self.params, &Fabrication::default(), clock, &mut |_| Ok(())).expect("SQ runs");
        let total_ms = clock.now() - t0;
        let faces = r.sq_mesh.as_ref().map_or(0, |f| f.mesh.panels.len());
        let c = r.congruence;
        SqSample {
            lc_ms: c.lc_iteration_ms,
            torsal_ms: c.torsal_iteration_ms,
            final_ms: r.sq_mesh.map(|f| f.outcome.iteration_ms).unwrap_or_default(),
            total_ms,
            faces,
        }
    }

    pub fn describe(&self) -> String {
        let n = self.params.grid;
        format!(
            "# sq: tunnel_arch, {n}×{n} grid ({} lines, {} quads), θ {}°, α {}°, about {} quads",
            n * n,
            (n - 1) * (n - 1),
            self.params.theta_deg,
            self.params.alpha_deg,
            self.params.faces
        )
    }
}

/// What one SQ run measured.
#[derive(Clone, Debug, Default)]
pub struct SqSample {
    pub lc_ms: Vec<f64>,
    pub torsal_ms: Vec<f64>,
    pub final_ms: Vec<f64>,
    pub total_ms: f64,
    /// Panels of the SQ mesh.
    pub faces: usize,
}

impl SqSample {
    /// Appends another sample's times.
    pub fn extend(&mut self, other: SqSample) -> &mut Self {
        self.lc_ms.extend(other.lc_ms);
        self.torsal_ms.extend(other.torsal_ms);
        self.final_ms.extend(other.final_ms);
        self.faces = other.faces;
        self
    }
}

// --- the whole suite, as the wasm runner runs it -------------------------------------------------

// --- 5. moulds -----------------------------------------------------------------------------------

/// About 10 000 panels of the dome and their mould fit data.
pub struct MouldWorkload {
    pub panels: Vec<crate::panels::panel::Panel>,
    pub fits: crate::panels::moulds::MouldFits,
    pub tolerance: f64,
}

impl MouldWorkload {
    pub fn new(scale: Scale) -> Self {
        let faces = match scale {
            Scale::Full => 10_000,
            Scale::Tiny => 60,
        };
        let params = StAdaptedParams::default();
        let reference = Reference::from_triangles(samples::Sample::Dome.mesh());
        let sizing = SizingField::uniform_for_face_count(reference.mesh(), faces);
        let remeshed = pliant_remesh(reference.mesh(), &sizing, &params.remesh, &mut ignore).expect("remesh");
        let field = jet_fit(&remeshed, &Topology::new(&remeshed), &params.jet, &mut ignore).expect("jet fit");
        let spheres = initial_spheres(&remeshed, &field.central_spheres);
        let diag = remeshed.bbox_diagonal();
        let sphere_mesh = SphereMesh::new(remeshed, spheres, BoundaryArcRule::Parallel(glam::DVec3::ZERO));
        let panels = build_panels(&sphere_mesh, crate::panels::DEFAULT_CHORD_TOLERANCE * diag);
        let fits = MouldFits::of(&panels);
        Self { panels, fits, tolerance: 2e-4 * diag }
    }
}

/// Samples per benchmark for [`run_suite`] (the divan bench uses the same workloads).
pub const JET_SAMPLES: usize = 5;
pub const REMESH_SAMPLES: usize = 5;
pub const ANGLE_SAMPLES: usize = 6;
pub const SQ_SAMPLES: usize = 5;
pub const MOULD_SAMPLES: usize = 10;

/// Runs every benchmark with `clock` and passes one [`result_line`] per benchmark to `out`, plus
/// informational lines starting with `#`. Awaits `pause()` between benchmarks (the browser runner
/// yields to the event loop there, so that the page stays responsive and the output streams).
pub async fn run_suite<P, F>(clock: Clock, scale: Scale, out: &mut dyn FnMut(&str), pause: P)
where
    P: Fn() -> F,
    F: std::future::Future<Output = ()>,
{
    let jet = JetWorkload::new(scale);
    out(&format!("# jet_fit: {} vertices", jet.mesh.vertex_count()));
    jet.run(); // warm-up
    pause().await;
    let mut ms = Vec::new();
    for _ in 0..JET_SAMPLES {
        ms.extend(time_n(clock, 1, || drop(jet.run())));
        pause().await;
    }
    out(&result_line("jet_fit", &ms));
    drop(jet);

    let remesh = RemeshWorkload::new(scale);
    pause().await;
    for (name, sizing) in [("remesh_round_uniform", RoundSizing::Uniform), ("remesh_round_adaptive", RoundSizing::Adaptive)] {
        let (mut ms, mut st) = (Vec::new(), RoundStats::default());
        for _ in 0..REMESH_SAMPLES {
            let (m, s) = remesh.time_rounds(sizing, clock, 1);
            ms.extend(m);
            st = s;
            pause().await;
        }
        out(&format!("# {name}: {} faces, {st:?}", remesh.reference.face_count()));
        out(&result_line(name, &ms));
    }
    drop(remesh);

    for faces in ANGLE_FACES {
        let w = AngleWorkload::new(faces, scale);
        out(&format!("# angle_iteration_{faces}: {} faces, {} vertices", w.faces(), w.frame.mesh.vertex_count()));
        pause().await;
        let mut problem = w.problem();
        let mut solver = w.solver(clock);
        w.sample(&mut problem, &mut solver); // symbolic analysis, reused afterwards
        pause().await;
        let (mut ms, mut phases) = (Vec::new(), PhaseTimes::default());
        for _ in 0..ANGLE_SAMPLES {
            let (m, p) = w.sample_with_phases(&mut problem, &mut solver);
            ms.extend(m);
            phases.add(&p);
            pause().await;
        }
        out(&phase_line(&format!("angle_iteration_{faces}"), &phases, ms.len()));
        out(&result_line(&format!("angle_iteration_{faces}"), &ms));
    }

    let sq = SqWorkload::new(scale);
    out(&sq.describe());
    sq.sample(clock);
    pause().await;
    let (mut all, mut totals) = (SqSample::default(), Vec::new());
    for _ in 0..SQ_SAMPLES {
        let s = sq.sample(clock);
        totals.push(s.total_ms);
        all.extend(s);
        pause().await;
    }
    out(&format!("# sq_final_iteration: {} panels", all.faces));
    out(&result_line("sq_lc_iteration", &all.lc_ms));
    out(&result_line("sq_torsal_iteration", &all.torsal_ms));
    out(&result_line("sq_final_iteration", &all.final_ms));
    out(&result_line("sq_pipeline", &totals));
    drop(sq);
    for (name, json) in SQ_HARD {
        let w = SqWorkload::on(json, scale);
        w.sample(clock); // warm-up
        pause().await;
        let mut totals = Vec::new();
        let mut faces = 0;
        for _ in 0..SQ_HARD_SAMPLES {
            let s = w.sample(clock);
            (faces, totals) = (s.faces, [totals, vec![s.total_ms]].concat());
            pause().await;
        }
        out(&format!("# {name}: one whole SQ run (defaults), {faces} panels"));
        out(&result_line(name, &totals));
    }

    let m = MouldWorkload::new(scale);
    pause().await;
    let fits_ms: Vec<f64> = (0..MOULD_SAMPLES).flat_map(|_| time_n(clock, 1, || drop(MouldFits::of(&m.panels)))).collect();
    let mut moulds = 0;
    let assign_ms: Vec<f64> = (0..MOULD_SAMPLES).flat_map(|_| time_n(clock, 1, || moulds = m.fits.assign(m.tolerance).moulds.len())).collect();
    out(&format!("# mould_assign_10k: {} panels, {moulds} moulds within 2e-4 of the diagonal", m.panels.len()));
    out(&result_line("mould_fits_10k", &fits_ms));
    out(&result_line("mould_assign_10k", &assign_ms));
    pause().await;
    let panels = &m.panels[..EXACT_PANELS.min(m.panels.len())];
    let exact_ms: Vec<f64> = (0..MOULD_SAMPLES).flat_map(|_| time_n(clock, 1, || drop(exact_surfaces(panels)))).collect();
    let exact = exact_surfaces(panels);
    let mut bytes = 0;
    let step_ms: Vec<f64> = (0..MOULD_SAMPLES).flat_map(|_| time_n(clock, 1, || bytes = exact_step(panels, &exact).len())).collect();
    let moulds = m.fits.assign(m.tolerance);
    let mut model_bytes = 0;
    let model_ms: Vec<f64> =
        (0..MOULD_SAMPLES).flat_map(|_| time_n(clock, 1, || model_bytes = exact_rhino_model(panels, &exact, &moulds).len())).collect();
    out(&format!("# step_2k: {} panels ({} without an exact patch), panels.step {bytes} bytes", panels.len(), exact.refused_panels().count()));
    out(&format!("# rhino_model_2k: the panels.3dm model, {model_bytes} bytes of JSON for rhino3dm"));
    out(&result_line("exact_surfaces_2k", &exact_ms));
    out(&result_line("step_2k", &step_ms));
    out(&result_line("rhino_model_2k", &model_ms));
}

/// Panels of the exact-surface benchmarks.
pub const EXACT_PANELS: usize = 2000;

/// The exact patches of `panels` ([`crate::panels::exact_surface`]).
pub fn exact_surfaces(panels: &[crate::panels::panel::Panel]) -> crate::panels::exact_surface::ExactSurfaces {
    crate::panels::exact_surface::ExactSurfaces::of(panels, &[])
}

/// The model of `panels.3dm` ([`crate::export::rhino`]) of `panels` with their exact patches and
/// moulds, as the JSON rhino3dm writes from.
pub fn exact_rhino_model(
    panels: &[crate::panels::panel::Panel],
    exact: &crate::panels::exact_surface::ExactSurfaces,
    moulds: &crate::panels::moulds::MouldAssignment,
) -> String {
    use crate::export::rhino::{RhinoInput, RhinoModel};
    RhinoModel::of(&RhinoInput { panels, exact, moulds, support: None, omega: None, units: crate::units::Units::M }).to_json()
}

/// `panels.step` of `panels` with their exact patches.
pub fn exact_step(panels: &[crate::panels::panel::Panel], exact: &crate::panels::exact_surface::ExactSurfaces) -> String {
    crate::export::step::write_exact_step("panels", panels, exact, crate::units::Units::M, 1.0)
}

/// The verdict runs that native and wasm must agree on (`tests/verdicts.rs` records them,
/// `tests/web.rs` runs them in the browser, one page task each): ST with adapted face size on the
/// free-form dome sample remeshed to about 300 faces, and SQ on the vault sample with a 12 × 12
/// grid and about 60 quads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VerdictRun {
    StDome,
    SqVault,
}

/// How far a figure of a recorded verdict may move on another platform, relative to the larger.
pub const FIGURE_TOLERANCE: f64 = 1e-2;

impl VerdictRun {
    pub const ALL: [VerdictRun; 2] = [VerdictRun::StDome, VerdictRun::SqVault];

    /// How far the run's figures may move on another platform (its holds and counts may not).
    /// SQ on the vault follows rounding: its control points scaled by 1 + k·1e-15 (k = 0..5) gave
    /// node axes 11.4–15.2°, support planes 75–86° and distances 6.6e-3–7.6e-3 of the diagonal
    /// (the full optimization stopping after 20 to 100 iterations, with either of its stopping
    /// rules); wasm's SIMD sums in another order.
    pub fn figure_tolerance(self) -> f64 {
        match self {
            VerdictRun::StDome => FIGURE_TOLERANCE,
            VerdictRun::SqVault => 0.25,
        }
    }

    /// The run's name in the recording (`tests/data/verdicts.json`).
    pub fn name(self) -> &'static str {
        match self {
            VerdictRun::StDome => "st dome 300 faces",
            VerdictRun::SqVault => "sq vault grid 12, 60 quads",
        }
    }

    /// The run's report guarantees, measured on the delivered panels.
    pub fn run(self) -> Vec<crate::guarantees::Guarantee> {
        use crate::progress::Clock;
        use crate::remeshing::Sizing;
        match self {
            VerdictRun::StDome => {
                let dome = Reference::from_triangles(samples::Sample::Dome.mesh());
                let params = crate::st_adapted::params::StAdaptedParams { sizing: Sizing::UniformFaces(300), ..Default::default() };
                let st =
                    crate::st_adapted::compute(&dome, &params, &Fabrication::default(), Clock(None), &mut |_| Ok(())).expect("ST runs on the dome");
                export::<StAdaptedStage>(&dome, &st, &params, &Fabrication::default(), Clock(None)).0.guarantees
            }
            VerdictRun::SqVault => {
                let vault = samples::Sample::Vault.bspline().expect("the vault is a B-spline");
                let vault = Reference::from_bspline(vault).expect("a B-spline reference");
                let params = sq::params::SqParams { grid: 12, faces: 60, ..Default::default() };
                sq::compute(&vault, &params, &Fabrication::default(), Clock(None), &mut |_| Ok(())).expect("SQ runs on the vault").verdict.guarantees
            }
        }
    }
}

/// Every [`VerdictRun`] in turn: (name, guarantees).
pub fn verdict_runs() -> Vec<(&'static str, Vec<crate::guarantees::Guarantee>)> {
    VerdictRun::ALL.into_iter().map(|r| (r.name(), r.run())).collect()
}

/// The hard SQ verdict run that native and wasm must agree on: the B-spline file `bytes` (named
/// `name`) at the paper's Fig. 19 settings (θ 15°, α 45°) with a 16 × 16 grid and about 120 quads
/// (`tests/verdicts.rs` records it, `tests/web.rs` runs it in the browser, one page task per
/// file); the report's guarantees.
pub fn hard_verdict_run(name: &str, bytes: &[u8]) -> Vec<crate::guarantees::Guarantee> {
    use crate::import::{import_file, ImportedFile};
    use crate::progress::Clock;
    let params = sq::params::SqParams { grid: 16, faces: 120, theta_deg: 15.0, alpha_deg: 45.0, ..Default::default() };
    let Ok(ImportedFile::BSpline(b)) = import_file(bytes, name) else { panic!("{name} is a B-spline") };
    let reference = Reference::from_bspline(b.surface).expect("a B-spline reference");
    sq::compute(&reference, &params, &Fabrication::default(), Clock(None), &mut |_| Ok(()))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .verdict
        .guarantees
}

/// Whether two runs of [`verdict_runs`] reach the same verdict: the same guarantees, each holding
/// alike, counts equal and figures within `tolerance` of the larger (1e-12 absolute): the
/// optimizations sum in another order on wasm's SIMD, and after 45 iterations the ST dome's
/// panels lie 0.3 % nearer or farther; the differences, if any.
pub fn verdict_differences(a: &[crate::guarantees::Guarantee], b: &[crate::guarantees::Guarantee], tolerance: f64) -> Vec<String> {
    let mut out = Vec::new();
    if a.len() != b.len() {
        out.push(format!("{} guarantees against {}", a.len(), b.len()));
    }
    for (x, y) in a.iter().zip(b) {
        let tolerance = if x.unit.is_empty() { 0.0 } else { 1e-12 + tolerance * x.measured.abs().max(y.measured.abs()) };
        let close = (x.measured - y.measured).abs() <= tolerance;
        if x.name != y.name || x.holds != y.holds || x.limit != y.limit || !(close || (x.measured.is_nan() && y.measured.is_nan())) {
            out.push(format!("{} {} ({}) against {} {} ({})", x.name, x.measured, x.holds, y.name, y.measured, y.holds));
        }
    }
    out
}

/// The differences between `runs` and a recording of them (`tests/data/verdicts.json`: per run
/// its name and guarantees), each as [`verdict_differences`] gives them, prefixed by the run.
pub fn recorded_verdict_differences(recorded: &str, runs: &[(&str, Vec<crate::guarantees::Guarantee>)]) -> Vec<String> {
    #[derive(serde::Deserialize)]
    struct Recorded {
        run: String,
        guarantees: Vec<crate::guarantees::Guarantee>,
    }
    let recorded: Vec<Recorded> = match serde_json::from_str(recorded) {
        Ok(r) => r,
        Err(e) => return vec![format!("the recording does not read: {e}")],
    };
    if recorded.len() != runs.len() {
        return vec![format!("{} runs recorded, {} run", recorded.len(), runs.len())];
    }
    let mut out = Vec::new();
    for ((name, now), want) in runs.iter().zip(&recorded) {
        if want.run != *name {
            out.push(format!("{} recorded where {name} runs", want.run));
        }
        let tolerance = VerdictRun::ALL.into_iter().find(|r| r.name() == *name).map_or(FIGURE_TOLERANCE, VerdictRun::figure_tolerance);
        out.extend(verdict_differences(&want.guarantees, now, tolerance).into_iter().map(|d| format!("{name}: {d}")));
    }
    out
}
