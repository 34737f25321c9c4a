//! Replays the fuzz corpus and every reproducer the fuzzers found (`fuzz/corpus/<target>/`,
//! `fuzz/artifacts/<target>/`) through the same oracles the fuzz targets run (`fuzz/oracles.rs`),
//! so a fixed bug stays fixed without libFuzzer. `bash www/dev.sh fuzz` runs the fuzzers.
//!
//! `cargo test --test fuzz_replay -- --ignored write_seeds` rewrites the seeds that are encoder
//! output (protocol envelopes, design links); `fuzz/make_seeds.py` writes the others.
#![cfg(not(target_arch = "wasm32"))] // native: reads the corpus from disk

#[path = "../fuzz/oracles.rs"]
mod oracles;

use std::path::{Path, PathBuf};

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz")
}

/// The files of `fuzz/{corpus,artifacts}/<target>/`, sorted (hidden files left out).
fn inputs(target: &str) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for kind in ["corpus", "artifacts"] {
        let dir = fuzz_dir().join(kind).join(target);
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        let mut here: Vec<PathBuf> = entries
            .map(|e| e.expect("read_dir entry").path())
            .filter(|p| p.is_file() && !p.file_name().unwrap().to_string_lossy().starts_with('.'))
            .collect();
        here.sort();
        files.extend(here);
    }
    files
}

/// Says which file was being replayed when an oracle panics (the panic itself fails the test).
struct Replaying<'a>(&'a Path);

impl Drop for Replaying<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("fuzz replay: the oracle failed on {}", self.0.display());
        }
    }
}

fn replay(target: &str) {
    let files = inputs(target);
    assert!(!files.is_empty(), "no seed inputs in fuzz/corpus/{target}/");
    for path in &files {
        let data = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let _guard = Replaying(path);
        oracles::run(target, &data);
    }
    eprintln!("fuzz replay {target}: {} files", files.len());
}

#[test]
fn replay_obj() {
    replay("obj");
}

#[test]
fn replay_gltf() {
    replay("gltf");
}

#[test]
fn replay_bspline() {
    replay("bspline");
}

#[test]
fn replay_design_link() {
    replay("design_link");
}

#[test]
fn replay_protocol() {
    replay("protocol");
}

#[test]
fn every_target_is_replayed() {
    assert_eq!(oracles::TARGETS, ["obj", "gltf", "bspline", "design_link", "protocol"]);
}

// --- seeds that are encoder output ---------------------------------------------------------

mod seeds {
    use super::{fuzz_dir, oracles};
    use spherical_faces::design_link::{CameraState, ColorBy, Design, DesignSurface, Method, Shading};
    use spherical_faces::pipeline::fields::{Field, FieldData};
    use spherical_faces::pipeline::protocol::*;
    use spherical_faces::pipeline::stages::{sq::SqStage, st_adapted::StAdaptedStage, st_support::StSupportStage};
    use spherical_faces::pipeline::{Outbox, Session};
    use spherical_faces::remeshing::Sizing;
    use spherical_faces::samples::Sample;
    use spherical_faces::sq::params::{SqParams, Until};
    use spherical_faces::st_adapted::params::StAdaptedParams;
    use spherical_faces::st_support::StSupportParams;
    use std::collections::BTreeSet;

    /// Keeps one message of each kind per stage, its fields cut to a few elements.
    #[derive(Default)]
    struct Keep {
        seen: BTreeSet<String>,
        out: Vec<(String, Envelope)>,
    }

    fn shrink(f: &Field) -> Field {
        let data = match &f.data {
            FieldData::F32(v) => FieldData::F32(v.iter().copied().take(3 * f.dim as usize).collect()),
            FieldData::U32(v) => FieldData::U32(v.iter().copied().take(3 * f.dim as usize).collect()),
            FieldData::Bytes(v) => FieldData::Bytes(v.iter().copied().take(48).collect()),
        };
        Field { name: f.name.clone(), dim: f.dim, data }
    }

    impl Outbox for Keep {
        fn send(&mut self, mut msg: FromWorker, fields: Vec<Field>) {
            let fields: Vec<Field> = fields.iter().take(4).map(shrink).collect();
            let (kind, stage) = match &mut msg {
                FromWorker::Ready => ("ready", String::new()),
                FromWorker::Loaded(_) => ("loaded", String::new()),
                FromWorker::Progress(p) => (if p.energies.is_empty() { "progress" } else { "energies" }, p.stage.to_string()),
                FromWorker::Snapshot { stage, fields: headers, .. } => {
                    *headers = fields.iter().map(Field::header).collect();
                    ("snapshot", stage.to_string())
                }
                FromWorker::Files { stage, fields: headers, mime } => {
                    *headers = fields.iter().map(Field::header).collect();
                    mime.truncate(headers.len());
                    ("files", stage.to_string())
                }
                FromWorker::Finished { stage, .. } => ("finished", stage.to_string()),
                FromWorker::Cancelled { stage } => ("cancelled", stage.to_string()),
                FromWorker::Error { .. } => ("error", String::new()),
            };
            let name = format!("from_{kind}{}{}", if stage.is_empty() { "" } else { "_" }, stage.replace(['-', '.'], "_"));
            if self.seen.insert(name.clone()) {
                self.out.push((name, encode_from_worker(&msg, &fields)));
            }
        }
        fn cancel_requested(&mut self) -> bool {
            false
        }
        fn now_ms(&self) -> f64 {
            12.5
        }
    }

    fn write(target: &str, name: &str, bytes: &[u8]) {
        assert!(bytes.len() < 20_000, "{name}: {} bytes", bytes.len());
        let dir = fuzz_dir().join("corpus").join(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(name), bytes).unwrap();
    }

    fn run(stage: StageRequest) -> ToWorker {
        ToWorker::Run(Box::new(stage))
    }

    /// Writes fuzz/corpus/protocol/* (real envelopes, framed as `oracles::protocol_envelope`
    /// reads them) and the design links the app writes.
    #[test]
    #[ignore = "rewrites fuzz/corpus; run by hand"]
    fn write_seeds() {
        let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec();
        let spline = std::fs::read(fuzz_dir().join("corpus/bspline/paraboloid_dome.json")).unwrap();
        let requests: Vec<(&str, ToWorker, Option<Vec<u8>>)> = vec![
            ("to_load_sample", ToWorker::LoadSample(Sample::WaveRoof), None),
            ("to_load_file", ToWorker::LoadFile { name: "tri.obj".into() }, Some(obj.clone())),
            ("to_run_curvature", run(StageRequest::Curvature(Default::default())), None),
            ("to_run_st_adapted", run(StageRequest::method::<StAdaptedStage>(StAdaptedParams::default())), None),
            ("to_run_st_support", run(StageRequest::method::<StSupportStage>(StSupportParams::default())), None),
            ("to_run_sq", run(StageRequest::method::<SqStage>(SqParams::default())), None),
            ("to_cancel", ToWorker::Cancel, None),
            ("to_crash", ToWorker::Crash, None),
        ];
        for (name, msg, bytes) in &requests {
            write("protocol", name, &oracles::protocol_bytes(&encode_to_worker(msg, bytes.clone())));
        }

        // What the worker sends, from real runs (small ones).
        let mut keep = Keep::default();
        keep.send(FromWorker::Ready, vec![]);
        let mut s = Session::new();
        s.handle(ToWorker::LoadFile { name: "bad.obj".into() }, Some(b"v 0 0 0\nf 1 2 9\n"), &mut keep);
        s.handle(ToWorker::LoadSample(Sample::Dome), None, &mut keep);
        s.handle(run(StageRequest::Curvature(Default::default())), None, &mut keep);
        let st = StAdaptedParams { sizing: Sizing::UniformFaces(60), ..StAdaptedParams::default() };
        s.handle(run(StageRequest::method::<StAdaptedStage>(st)), None, &mut keep);
        let sts = StSupportParams { remesh: Sizing::UniformFaces(60), ..StSupportParams::default() };
        s.handle(run(StageRequest::method::<StSupportStage>(sts)), None, &mut keep);
        s.handle(ToWorker::LoadFile { name: "paraboloid_dome.json".into() }, Some(&spline), &mut keep);
        s.handle(run(StageRequest::method::<SqStage>(SqParams { grid: 8, until: Until::Congruence, ..SqParams::default() })), None, &mut keep);
        keep.send(FromWorker::Cancelled { stage: StageId::of(MethodId::Sq) }, vec![]);
        for (name, env) in &keep.out {
            write("protocol", name, &oracles::protocol_bytes(env));
        }

        // Design links as the app writes them.
        let designs = [
            ("app_curvature.frag", Design::default()),
            (
                "app_st.frag",
                Design {
                    method: Method::Of(MethodId::StAdapted),
                    reference: DesignSurface::Sample(Sample::SphereCap),
                    color: ColorBy::Sizing,
                    shading: Shading::Flat,
                    edges: true,
                    camera: Some(CameraState { yaw: 0.25, pitch: -0.5, distance: 4.0, target: [0.5, -0.25, 1.0] }),
                    ..Design::default()
                },
            ),
            ("app_st_support.frag", Design { method: Method::Of(MethodId::StSupport), ..Design::default() }),
            ("app_sq.frag", Design { method: Method::Of(MethodId::Sq), reference: DesignSurface::Sample(Sample::Vault), ..Design::default() }),
            ("app_file.frag", Design { reference: DesignSurface::OwnFile("my roof #2.obj".into()), ..Design::default() }),
        ];
        for (name, d) in &designs {
            write("design_link", name, d.to_fragment().as_bytes());
        }
    }
}
