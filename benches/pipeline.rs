//! Native benchmarks (divan) of the workloads in `spherical_faces::bench_workloads`, the same ones
//! `tests/wasm_bench.rs` times in the browser:
//!
//!     cargo bench --bench pipeline
//!
//! After divan's table, one line per benchmark in the format the wasm runner prints,
//! `bench <name>: <ms> ms/iter (n=<samples>)`, the median of the samples timed here (for the
//! angle benchmarks: of the solver's per-iteration times); `bash www/dev.sh bench` compares those.
//!
//! Under `cargo test --all-targets` (no `--bench` argument) divan runs every benchmark once, and
//! the workloads are tiny ([`Scale::Tiny`]), so that this only checks that they run.

use std::sync::{Mutex, OnceLock};

use divan::Bencher;
use spherical_faces::bench_workloads::{
    exact_rhino_model, exact_step, exact_surfaces, phase_line, result_line, AngleWorkload, JetWorkload, MouldWorkload, RemeshWorkload, RoundSizing,
    Scale, SqWorkload, ANGLE_FACES, ANGLE_SAMPLES, EXACT_PANELS, JET_SAMPLES, MOULD_SAMPLES, REMESH_SAMPLES, SQ_HARD, SQ_HARD_SAMPLES, SQ_SAMPLES,
};
use spherical_faces::panels::moulds::MouldFits;
use spherical_faces::progress::{native_clock_ms, Clock};
use spherical_faces::solver::PhaseTimes;

static SCALE: OnceLock<Scale> = OnceLock::new();
/// (benchmark, milliseconds) of every timed sample, in order.
static RESULTS: Mutex<Vec<(String, f64)>> = Mutex::new(Vec::new());
/// Informational lines (`# ...`, as the wasm runner prints them), one per benchmark.
static INFO: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());

fn info(name: &str, line: String) {
    let mut i = INFO.lock().unwrap();
    match i.iter_mut().find(|(n, _)| n == name) {
        Some(e) => e.1 = line,
        None => i.push((name.to_string(), line)),
    }
}

fn scale() -> Scale {
    *SCALE.get().unwrap_or(&Scale::Tiny)
}

fn record(name: &str, ms: impl IntoIterator<Item = f64>) {
    let mut r = RESULTS.lock().unwrap();
    r.extend(ms.into_iter().map(|ms| (name.to_string(), ms)));
}

fn timed<T>(name: &str, f: impl FnOnce() -> T) -> T {
    let t = native_clock_ms();
    let out = f();
    record(name, [native_clock_ms() - t]);
    out
}

fn remesh_workload() -> &'static RemeshWorkload {
    static W: OnceLock<RemeshWorkload> = OnceLock::new();
    W.get_or_init(|| RemeshWorkload::new(scale()))
}

fn main() {
    let bench_mode = std::env::args().any(|a| a == "--bench");
    SCALE.set(if bench_mode { Scale::Full } else { Scale::Tiny }).unwrap();
    native_clock_ms();
    divan::main();
    if bench_mode {
        let results = RESULTS.lock().unwrap();
        let mut names: Vec<&str> = Vec::new();
        for (n, _) in results.iter() {
            if !names.contains(&n.as_str()) {
                names.push(n);
            }
        }
        println!();
        for (_, line) in INFO.lock().unwrap().iter() {
            println!("{line}");
        }
        for name in names {
            let ms: Vec<f64> = results.iter().filter(|(n, _)| n == name).map(|&(_, ms)| ms).collect();
            println!("{}", result_line(name, &ms));
        }
    }
}

/// `jet_fit` on the ~100k-vertex dome.
#[divan::bench(sample_count = JET_SAMPLES as u32, sample_size = 1)]
fn jet_fit(bencher: Bencher) {
    let w = JetWorkload::new(scale());
    info("jet_fit", format!("# jet_fit: {} vertices", w.mesh.vertex_count()));
    bencher.bench_local(|| timed("jet_fit", || w.run()));
}

/// One pliant remeshing round of the ~100k-triangle dome (fresh remesher per sample, not timed).
#[divan::bench(args = [RoundSizing::Uniform, RoundSizing::Adaptive], sample_count = REMESH_SAMPLES as u32, sample_size = 1)]
fn remesh_round(bencher: Bencher, sizing: RoundSizing) {
    let w = remesh_workload();
    let name = match sizing {
        RoundSizing::Uniform => "remesh_round_uniform",
        RoundSizing::Adaptive => "remesh_round_adaptive",
    };
    bencher.with_inputs(|| w.remesher(sizing)).bench_local_values(|mut r| {
        let st = timed(name, || RemeshWorkload::round(&mut r));
        info(name, format!("# {name}: {} faces, {st:?}", w.reference.face_count()));
        r // dropped outside the timing
    });
}

/// `ANGLE_ITERATIONS_PER_SAMPLE` LM iterations from the initial point (divan times the whole
/// call; the `bench` line is the median of the solver's per-iteration times).
#[divan::bench(args = ANGLE_FACES, sample_count = ANGLE_SAMPLES as u32, sample_size = 1)]
fn angle_iterations(bencher: Bencher, faces: usize) {
    let w = AngleWorkload::new(faces, scale());
    let mut problem = w.problem();
    let mut solver = w.solver(Clock(Some(native_clock_ms)));
    w.sample(&mut problem, &mut solver); // symbolic analysis, reused afterwards
    let name = format!("angle_iteration_{faces}");
    info(&name, format!("# {name}: {} faces, {} vertices", w.faces(), w.frame.mesh.vertex_count()));
    let (mut phases, mut iterations) = (PhaseTimes::default(), 0);
    bencher.bench_local(|| {
        let (ms, p) = w.sample_with_phases(&mut problem, &mut solver);
        phases.add(&p);
        iterations += ms.len();
        record(&name, ms)
    });
    info(&format!("{name} phases"), phase_line(&name, &phases, iterations));
}

/// One whole SQ run on tunnel_arch (20×20 grid, about 237 quads) per sample; the `bench` lines
/// are the medians of the solver's per-iteration times of step 1 (`sq_lc_iteration`), step 2
/// (`sq_torsal_iteration`) and the final optimization (`sq_final_iteration`), and of the whole
/// run (`sq_pipeline`).
#[divan::bench(sample_count = SQ_SAMPLES as u32, sample_size = 1)]
fn sq_iterations(bencher: Bencher) {
    let w = SqWorkload::new(scale());
    let clock = Clock(Some(native_clock_ms));
    w.sample(clock); // warm-up
    info("sq", w.describe());
    bencher.bench_local(|| {
        let s = w.sample(clock);
        record("sq_lc_iteration", s.lc_ms);
        record("sq_torsal_iteration", s.torsal_ms);
        record("sq_final_iteration", s.final_ms);
        record("sq_pipeline", vec![s.total_ms]);
    });
}

/// One whole SQ run per sample on each hard surface of `SQ_HARD` (`sq_pipeline_<surface>`).
#[divan::bench(args = [0, 1], sample_count = SQ_HARD_SAMPLES as u32, sample_size = 1)]
fn sq_hard(bencher: Bencher, k: usize) {
    let (name, json) = SQ_HARD[k];
    let w = SqWorkload::on(json, scale());
    let clock = Clock(Some(native_clock_ms));
    let faces = w.sample(clock).faces; // warm-up
    info(name, format!("# {name}: one whole SQ run (defaults), {faces} panels"));
    bencher.bench_local(|| record(name, [w.sample(clock).total_ms]));
}

#[divan::bench(sample_count = MOULD_SAMPLES as u32, sample_size = 1)]
fn moulds(bencher: Bencher) {
    let m = MouldWorkload::new(scale());
    info("moulds", format!("# mould_assign_10k: {} panels", m.panels.len()));
    bencher.bench_local(|| {
        timed("mould_fits_10k", || MouldFits::of(&m.panels));
        timed("mould_assign_10k", || m.fits.assign(m.tolerance));
    });
}

#[divan::bench(sample_count = MOULD_SAMPLES as u32, sample_size = 1)]
fn exact_surfaces_and_step(bencher: Bencher) {
    let m = MouldWorkload::new(scale());
    let panels = &m.panels[..EXACT_PANELS.min(m.panels.len())];
    info("exact", format!("# step_2k: {} panels ({} without an exact patch)", panels.len(), exact_surfaces(panels).refused_panels().count()));
    let moulds = m.fits.assign(m.tolerance);
    // panels.3dm as the CLI writes it: the model's JSON to a file, then rhino3dm under Node
    // (www/rhino3dm/write-cli.mjs, Node's start and rhino3dm's load included).
    let writer = concat!(env!("CARGO_MANIFEST_DIR"), "/www/rhino3dm/write-cli.mjs");
    let rhino3dm = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("www/rhino3dm/node_modules/rhino3dm").is_dir();
    if !rhino3dm {
        info("exact 3dm", "# panels_3dm_2k: skipped, rhino3dm is not installed (npm ci in www/rhino3dm)".into());
    }
    let dir = std::env::temp_dir().join(format!("sf-bench-3dm-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    bencher.bench_local(|| {
        let t = native_clock_ms();
        let exact = timed("exact_surfaces_2k", || exact_surfaces(panels));
        let step = timed("step_2k", || exact_step(panels, &exact));
        std::fs::write(dir.join("panels.step"), step).unwrap();
        let model = timed("rhino_model_2k", || exact_rhino_model(panels, &exact, &moulds));
        if rhino3dm {
            std::fs::write(dir.join("model.json"), model).unwrap();
            let out = timed("panels_3dm_2k", || {
                std::process::Command::new("node").arg(writer).arg(dir.join("model.json")).arg(dir.join("panels.3dm")).output().unwrap()
            });
            assert!(out.status.success(), "write-cli.mjs: {}", String::from_utf8_lossy(&out.stderr));
            record("cad_files_2k", [native_clock_ms() - t]);
            let size = |f: &str| std::fs::metadata(dir.join(f)).map_or(0, |m| m.len());
            info("exact 3dm", format!("# cad_files_2k: panels.step {} bytes, panels.3dm {} bytes", size("panels.step"), size("panels.3dm")));
        }
    });
    let _ = std::fs::remove_dir_all(&dir);
}
