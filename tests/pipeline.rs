//! The worker protocol and session, natively: the same code the Web Worker runs.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns processes

use spherical_faces::congruence::central_spheres::JetParams;
use spherical_faces::pipeline::fields::{field, find, Field, Part};
use spherical_faces::pipeline::protocol::*;
use spherical_faces::pipeline::stages::{sq::SqStage, st_adapted::StAdaptedStage, st_support::StSupportStage};
use spherical_faces::pipeline::{Outbox, Session};
use spherical_faces::samples::Sample;
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_support::StSupportParams;

/// Records messages, round-tripping each through the wire encoding; cancels after `cancel_after`
/// progress messages.
#[derive(Default)]
struct Recorder {
    messages: Vec<(FromWorker, Vec<Field>)>,
    cancel_after: Option<usize>,
    progress_seen: usize,
}

impl Outbox for Recorder {
    fn send(&mut self, msg: FromWorker, fields: Vec<Field>) {
        if matches!(msg, FromWorker::Progress(_)) {
            self.progress_seen += 1;
        }
        let env = encode_from_worker(&msg, &fields);
        let decoded = decode_from_worker(&env).expect("decodes");
        assert_eq!(decoded.0, msg);
        assert!(decoded.1 == if matches!(msg, FromWorker::Snapshot { .. } | FromWorker::Files { .. }) { fields } else { vec![] });
        self.messages.push(decoded);
    }
    fn cancel_requested(&mut self) -> bool {
        self.cancel_after.is_some_and(|n| self.progress_seen >= n)
    }
    fn now_ms(&self) -> f64 {
        0.0
    }
}

fn run(stage: StageRequest) -> ToWorker {
    ToWorker::Run(Box::new(stage))
}

fn send(session: &mut Session, sink: &mut Recorder, msg: ToWorker, bytes: Option<Vec<u8>>) {
    // Through the wire encoding, as the worker receives it.
    let env = encode_to_worker(&msg, bytes);
    let (decoded, body) = decode_to_worker(&env).unwrap();
    assert_eq!(decoded, msg);
    session.handle(decoded, body, sink);
}

#[test]
fn load_sample_then_curvature_streams_snapshots() {
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Dome), None);
    let FromWorker::Loaded(info) = r.messages[0].0.clone() else { panic!("{:?}", r.messages[0].0) };
    assert_eq!(info.source, Source::Sample(Sample::Dome));
    let (FromWorker::Snapshot { stage, .. }, fields) = &r.messages[1] else { panic!() };
    assert_eq!(stage, "reference");
    let pos = find(fields, field::POSITIONS).unwrap().as_f32().unwrap();
    let tri = find(fields, field::TRIANGLES).unwrap().as_u32().unwrap();
    assert_eq!(pos.len(), 3 * info.stats.vertices);
    assert_eq!(tri.len(), 3 * info.stats.faces);
    assert!(tri.iter().all(|&i| (i as usize) < info.stats.vertices));

    r.messages.clear();
    send(&mut s, &mut r, run(StageRequest::Curvature(JetParams::default())), None);
    assert!(matches!(r.messages[0].0, FromWorker::Progress(_)));
    let snap = r.messages.iter().find(|m| matches!(&m.0, FromWorker::Snapshot { stage, .. } if stage == "curvature")).unwrap();
    let h = find(&snap.1, field::MEAN_CURVATURE).unwrap().as_f32().unwrap();
    assert_eq!(h.len(), info.stats.vertices);
    assert!(h.iter().all(|x| x.is_finite()));
    let spheres = find(&snap.1, field::CENTRAL_SPHERES).unwrap();
    assert_eq!(spheres.dim, 5);
    let Some((FromWorker::Finished { result: StageResult::Curvature(summary), .. }, _)) = r.messages.last() else { panic!() };
    assert!(!summary.h_changes_sign, "the default dome keeps one sign of H");
}

#[test]
fn a_bad_file_reports_an_error_and_keeps_the_design() {
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::TorusPatch), None);
    r.messages.clear();
    send(&mut s, &mut r, ToWorker::LoadFile { name: "broken.obj".into() }, Some(b"v 1 2\nf 1 2 9\n".to_vec()));
    assert_eq!(r.messages.len(), 1);
    let FromWorker::Error { message, .. } = &r.messages[0].0 else { panic!() };
    assert!(message.starts_with("broken.obj"), "{message}");
    assert_eq!(s.reference.as_ref().unwrap().info.source, Source::Sample(Sample::TorusPatch));
    // The previous reference still computes.
    r.messages.clear();
    send(&mut s, &mut r, run(StageRequest::Curvature(JetParams::default())), None);
    assert!(matches!(r.messages.last().unwrap().0, FromWorker::Finished { .. }));
}

#[test]
fn a_file_loads_through_the_session() {
    let bytes = std::fs::read("../shared/data/meshes/tri_dome.obj").unwrap();
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadFile { name: "tri_dome.obj".into() }, Some(bytes));
    let FromWorker::Loaded(info) = &r.messages[0].0 else { panic!("{:?}", r.messages[0].0) };
    assert_eq!(info.stats.vertices, 91);
    assert_eq!(info.source, Source::File("tri_dome.obj".into()));
}

#[test]
fn running_without_a_reference_is_an_error() {
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, run(StageRequest::Curvature(JetParams::default())), None);
    assert!(matches!(&r.messages[0].0, FromWorker::Error { .. }));
}

#[test]
fn cancel_takes_effect_within_one_iteration() {
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Dome), None);
    r.messages.clear();
    r.cancel_after = Some(1);
    r.progress_seen = 0;
    send(&mut s, &mut r, run(StageRequest::Curvature(JetParams::default())), None);
    let kinds: Vec<_> = r.messages.iter().map(|m| std::mem::discriminant(&m.0)).collect();
    assert_eq!(r.progress_seen, 1, "stopped at the first iteration boundary");
    assert!(matches!(r.messages.last().unwrap().0, FromWorker::Cancelled { .. }), "{kinds:?}");
    assert!(!r.messages.iter().any(|m| matches!(m.0, FromWorker::Finished { .. })));
}

#[test]
fn st_support_streams_panels_files_and_a_report() {
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Dome), None);
    r.messages.clear();
    send(&mut s, &mut r, run(StageRequest::method::<StSupportStage>(StSupportParams::default())), None);
    let snap = r.messages.iter().find(|m| matches!(&m.0, FromWorker::Snapshot { stage, .. } if stage == "st-support")).unwrap();
    let tri = find(&snap.1, field::PANEL_TRIANGLES).unwrap().as_u32().unwrap();
    let pos = find(&snap.1, field::PANEL_POSITIONS).unwrap().as_f32().unwrap();
    assert!(!tri.is_empty() && tri.iter().all(|&i| (i as usize) < pos.len() / 3));
    assert!(!find(&snap.1, field::AXES_LINES).unwrap().as_u32().unwrap().is_empty());
    let (FromWorker::Files { fields, mime, .. }, bodies) = r.messages.iter().find(|m| matches!(m.0, FromWorker::Files { .. })).unwrap() else {
        panic!()
    };
    let names: Vec<_> = fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        ["panels.glb", "panels.obj", "panels.csv", "panels.json", "moulds.csv", "panels.step", "panels.3dm.json", "support.csv", "report.json"]
    );
    assert_eq!(mime.len(), 9);
    assert_eq!(&bodies[0].as_bytes().unwrap()[..4], b"glTF");
    let Some((FromWorker::Finished { result: StageResult::Method(MethodSummary::StSupport(summary)), .. }, _)) = r.messages.last() else { panic!() };
    let m = &summary.section().expect("the report's section");
    assert!(m.max_vertex_sphere_residual <= 1e-9);
    assert!(m.max_orthogonality_residual <= 1e-9);
    assert!(m.max_node_axis_offset <= 1e-9);
    assert_eq!(summary.report.output.panels, summary.report.input.faces);
    let report: serde_json::Value = serde_json::from_slice(bodies[8].as_bytes().unwrap()).unwrap();
    assert_eq!(report["method"], "st-support");
}

#[test]
fn st_support_on_a_minimal_surface_is_refused() {
    let bytes = std::fs::read("../shared/data/meshes/enneper2.obj").unwrap();
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadFile { name: "enneper2.obj".into() }, Some(bytes));
    r.messages.clear();
    send(&mut s, &mut r, run(StageRequest::method::<StSupportStage>(StSupportParams::default())), None);
    let Some((FromWorker::Error { message, .. }, _)) = r.messages.last() else { panic!("{:?}", r.messages.last()) };
    assert!(message.contains("no usable central spheres"), "{message}");
    assert!(!r.messages.iter().any(|m| matches!(m.0, FromWorker::Files { .. })));
}

/// The "ST, adapted face size" stage streams the sizing field, the remeshed triangulation,
/// panels, per-iteration energies, the files and its summary, in that order.
#[test]
fn st_stage_streams_sizing_remesh_panels_and_energies() {
    let (sizing_stage, remeshed_stage, panels_stage) =
        (StageId::Method(MethodId::StAdapted, Part::Sizing), StageId::Method(MethodId::StAdapted, Part::Remeshed), StageId::of(MethodId::StAdapted));
    let (stf, pf) = (field::SIZING, field::PANEL_TRIANGLES);
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Dome), None);
    let FromWorker::Loaded(info) = r.messages[0].0.clone() else { panic!() };
    r.messages.clear();
    send(&mut s, &mut r, run(StageRequest::method::<StAdaptedStage>(StAdaptedParams::default())), None);
    let pos = |stage: StageId| r.messages.iter().position(|m| matches!(&m.0, FromWorker::Snapshot { stage: s, .. } if *s == stage));
    let (i_sizing, i_remesh, i_panels) = (pos(sizing_stage).unwrap(), pos(remeshed_stage).unwrap(), pos(panels_stage).unwrap());
    assert!(i_sizing < i_remesh && i_remesh < i_panels);
    let g = find(&r.messages[i_sizing].1, stf).unwrap().as_f32().unwrap();
    assert_eq!(g.len(), info.stats.vertices);
    assert!(g.iter().all(|x| x.is_finite() && *x > 0.0));
    let remeshed = &r.messages[i_remesh].1;
    let rt = find(remeshed, field::TRIANGLES).unwrap().as_u32().unwrap();
    let rp = find(remeshed, field::POSITIONS).unwrap().as_f32().unwrap();
    assert!(rt.len() / 3 > 100 && rt.len() / 3 < 1000, "{} faces", rt.len() / 3);
    assert!(rt.iter().all(|&i| (i as usize) < rp.len() / 3));
    // Every iteration reports its energies; the total is the sum of the term energies.
    let energies: Vec<&StageProgress> = r
        .messages
        .iter()
        .filter_map(|m| match &m.0 {
            FromWorker::Progress(p) if !p.energies.is_empty() => Some(p),
            _ => None,
        })
        .collect();
    assert_eq!(energies.len(), 45);
    for (k, p) in energies.iter().enumerate() {
        assert_eq!(p.iteration as usize, k + 1);
        assert_eq!(p.total, 45);
        let total = p.energies[0].value;
        let sum: f64 = p.energies[1..].iter().map(|e| e.value).sum();
        assert!((total - sum).abs() <= 1e-9 * total.abs().max(1e-30), "{total} vs {sum}");
    }
    // Panels: the first (iteration 0) and the last (all iterations) snapshot.
    let panel_snaps: Vec<u32> = r
        .messages
        .iter()
        .filter_map(|m| match &m.0 {
            FromWorker::Snapshot { stage, iteration, .. } if *stage == panels_stage => Some(*iteration),
            _ => None,
        })
        .collect();
    assert_eq!(panel_snaps.first(), Some(&0));
    assert_eq!(panel_snaps.last(), Some(&45));
    let last = r.messages.iter().rev().find(|m| matches!(&m.0, FromWorker::Snapshot { stage, .. } if *stage == panels_stage)).unwrap();
    let tri = find(&last.1, pf).unwrap().as_u32().unwrap();
    assert!(tri.len() / 3 >= rt.len() / 3);
    let files = r.messages.iter().find(|m| matches!(m.0, FromWorker::Files { .. })).unwrap();
    let names: Vec<&str> = files.1.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["panels.glb", "panels.obj", "panels.csv", "panels.json", "moulds.csv", "panels.step", "panels.3dm.json", "report.json"]);
    let Some((FromWorker::Finished { result: StageResult::Method(MethodSummary::StAdapted(summary)), .. }, _)) = r.messages.last() else { panic!() };
    assert_eq!(summary.report.method, "st");
    assert_eq!(summary.iterations, 45);
    assert_eq!(summary.remeshed_faces, rt.len() / 3);
    assert!(summary.metrics.max_vertex_sphere_residual <= 1e-8);
    // Variant (a) trades a little kink for edge circles that stay over their edges (Sec. 6.1; the
    // panel distances are tested in tests/st_adapted.rs).
    let (i, f) = (&summary.initial, &summary.metrics);
    assert!(f.mean_kink_angle_deg < 1.05 * i.mean_kink_angle_deg, "mean kink {} → {}", i.mean_kink_angle_deg, f.mean_kink_angle_deg);
    let (lo, hi) = summary.sizing_range.unwrap();
    assert!(lo > 0.0 && lo <= hi);
}

/// A cancel during the optimization stops the stage within the iteration: no iteration, panels or
/// files after the cancel request, Cancelled, and the loaded design is intact (it computes again).
#[test]
fn st_stage_cancels_within_one_iteration() {
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Dome), None);
    let FromWorker::Loaded(info) = r.messages[0].0.clone() else { panic!() };
    r.messages.clear();
    r.cancel_after = Some(25);
    r.progress_seen = 0;
    send(&mut s, &mut r, run(StageRequest::method::<StAdaptedStage>(StAdaptedParams::default())), None);
    assert!(matches!(&r.messages.last().unwrap().0, FromWorker::Cancelled { stage } if stage == "st"), "{:?}", r.messages.last().unwrap().0);
    // The cancel was requested once 25 progress messages had been sent: the 25th is the last.
    let progress: Vec<usize> = r.messages.iter().enumerate().filter(|(_, m)| matches!(m.0, FromWorker::Progress(_))).map(|(i, _)| i).collect();
    assert_eq!(progress.len(), 25, "progress after the cancel request");
    let after = &r.messages[progress[24] + 1..];
    assert_eq!(after.len(), 1, "only Cancelled follows: {:?}", after.iter().map(|m| &m.0).collect::<Vec<_>>());
    assert!(!r.messages.iter().any(|m| matches!(m.0, FromWorker::Files { .. } | FromWorker::Finished { .. })));
    // The design is what was loaded, and runs again to the end.
    let loaded = s.reference.as_ref().expect("the reference is kept");
    assert_eq!(loaded.info, info);
    assert_eq!(loaded.surface.mesh().face_count(), info.stats.faces);
    r.messages.clear();
    r.cancel_after = None;
    send(&mut s, &mut r, run(StageRequest::Curvature(JetParams::default())), None);
    assert!(matches!(r.messages.last().unwrap().0, FromWorker::Finished { .. }));
}

/// One jet fit per reference: the curvature stage fits the reference's jets, and the methods
/// that follow (with the same jet parameters) reuse them; new parameters fit again. (The ST
/// method also fits the jets of its remeshed mesh, after its "remesh" step: another mesh.)
#[test]
fn a_reference_fits_its_jets_once() {
    // Progress of a jet fit (total > 0; a step marker has total 0) before any "remesh" step.
    let reference_fits = |r: &Recorder| {
        r.messages
            .iter()
            .filter_map(|m| match &m.0 {
                FromWorker::Progress(p) => Some(p),
                _ => None,
            })
            .take_while(|p| p.detail != "remesh")
            .filter(|p| p.detail == "jet_fit" && p.total > 0)
            .count()
    };
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::SphereCap), None);
    r.messages.clear();
    send(&mut s, &mut r, run(StageRequest::Curvature(JetParams::default())), None);
    assert!(reference_fits(&r) > 0, "the curvature stage reports its jet fit");
    for stage in [
        StageRequest::method::<StSupportStage>(StSupportParams::default()),
        StageRequest::method::<StAdaptedStage>(StAdaptedParams { stages: StAdaptedParams::default().stages[..1].to_vec(), ..Default::default() }),
    ] {
        r.messages.clear();
        send(&mut s, &mut r, run(stage.clone()), None);
        assert!(r.messages.iter().any(|m| matches!(m.0, FromWorker::Finished { .. })), "{:?}", r.messages.last().map(|m| &m.0));
        assert_eq!(reference_fits(&r), 0, "{} fitted the reference's jets again", stage.name());
    }
    r.messages.clear();
    let other = JetParams { degree: 2, ..JetParams::default() };
    send(&mut s, &mut r, run(StageRequest::Curvature(other)), None);
    assert!(reference_fits(&r) > 0, "other jet parameters fit again");
}

/// SQ in the session: live lines and one energy report per solver iteration, the cross field,
/// the quad mesh, live panels, then the panels, support structure and node axes, the files and
/// the summary; θ and α met on the vault sample, and the mesh exact.
#[test]
fn sq_streams_lines_and_energies_then_files() {
    use spherical_faces::sq::params::SqParams;
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Vault), None);
    r.messages.clear();
    let params = SqParams { grid: 12, ..SqParams::default() };
    send(&mut s, &mut r, run(StageRequest::method::<SqStage>(params)), None);
    let energies = r.messages.iter().filter(|(m, _)| matches!(m, FromWorker::Progress(p) if !p.energies.is_empty())).count();
    let Some((FromWorker::Finished { result: StageResult::Method(MethodSummary::Sq(summary)), .. }, _)) = r.messages.last() else {
        panic!("{:?}", r.messages.last())
    };
    let section = summary.section().expect("the report's section");
    assert_eq!(energies, section.iterations, "one energy report per iteration");
    let figures = &section.congruence.figures;
    assert!(figures.max_line_normal_angle_deg <= 20.0 && figures.min_torsal_plane_angle_deg >= 75.0, "{figures:?}");
    let snapshots: Vec<&Vec<Field>> = r
        .messages
        .iter()
        .filter_map(|(m, f)| matches!(m, FromWorker::Snapshot { stage, .. } if *stage == StageId::of(MethodId::Sq)).then_some(f))
        .collect();
    let first = snapshots.first().unwrap();
    assert_eq!(find(first, field::SQ_INITIAL_LINES).and_then(Field::as_f32).unwrap().len(), 144 * 6, "two points per line");
    let last = snapshots.last().unwrap();
    assert_eq!(find(last, field::SQ_CROSS_FIELD).and_then(Field::as_f32).unwrap().len(), 121 * 2 * 6, "two arms per quad");
    assert_eq!(find(last, field::SQ_CROSS_FIELD_ANGLE).and_then(Field::as_f32).unwrap().len(), 121 * 2);
    assert!(find(last, field::SQ_NO_REAL_QUADS).and_then(Field::as_f32).unwrap().is_empty());
    for name in [field::SQ_QUAD_MESH, field::PANEL_TRIANGLES, field::SUPPORT_TRIANGLES, field::AXES_LINES] {
        let len = find(last, name).map_or(0, |f| f.as_f32().map_or(0, <[f32]>::len) + f.as_u32().map_or(0, <[u32]>::len));
        assert!(len > 0, "{name} in the last snapshot");
    }
    // Live panels while the spheres optimize.
    assert!(snapshots[..snapshots.len() - 1].iter().any(|f| find(f, field::PANEL_TRIANGLES).is_some()), "live panels");
    let section = summary.section().expect("the report's section");
    let mesh = section.sq_mesh.as_ref().expect("the SQ mesh's figures").figures;
    assert!(mesh.max_vertex_sphere_residual <= 1e-8 && mesh.max_centre_face_planarity <= 1e-8, "{mesh:?}");
    assert_eq!(section.stopped_after, "final");
    let files: Vec<&str> = r
        .messages
        .iter()
        .find_map(|(m, _)| match m {
            FromWorker::Files { fields, .. } => Some(fields.iter().map(|h| h.name.as_str()).collect()),
            _ => None,
        })
        .unwrap();
    assert_eq!(
        files,
        [
            "congruence.glb",
            "congruence.json",
            "mesh.obj",
            "panels.glb",
            "panels.obj",
            "panels.csv",
            "panels.json",
            "moulds.csv",
            "panels.step",
            "panels.3dm.json",
            "support.csv",
            "report.json"
        ]
    );
}

/// SQ's central start refuses a sign change of H and sends H at the vertices first; on a mesh it
/// needs a B-spline.
#[test]
fn sq_refusals_reach_the_app() {
    use spherical_faces::sq::params::{RadiusStart, SqParams};
    let bytes = std::fs::read("../shared/data/bsplines/saddle_sign_change.json").unwrap();
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadFile { name: "saddle_sign_change.json".into() }, Some(bytes));
    let FromWorker::Loaded(info) = &r.messages[0].0 else { panic!() };
    let vertices = info.stats.vertices;
    r.messages.clear();
    send(&mut s, &mut r, run(StageRequest::method::<SqStage>(SqParams { start: RadiusStart::Central, ..SqParams::default() })), None);
    let n = r.messages.len();
    let (FromWorker::Snapshot { stage, .. }, fields) = &r.messages[n - 2] else { panic!("{:?}", r.messages[n - 2].0) };
    assert_eq!(*stage, StageId::Method(MethodId::Sq, Part::Refused));
    let h = find(fields, field::MEAN_CURVATURE).and_then(Field::as_f32).unwrap();
    assert_eq!(h.len(), vertices);
    assert!(h.iter().any(|&x| x > 0.0) && h.iter().any(|&x| x < 0.0));
    let FromWorker::Error { message, .. } = &r.messages[n - 1].0 else { panic!() };
    assert!(message.contains("central start needs a mean curvature of one sign") && message.contains("constant radii"), "{message}");

    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Dome), None);
    send(&mut s, &mut r, run(StageRequest::method::<SqStage>(SqParams::default())), None);
    let FromWorker::Error { message, .. } = &r.messages.last().unwrap().0 else { panic!() };
    assert!(message.contains("B-spline reference"), "{message}");
}

/// A cancel during the torsal step stops SQ within the iteration: Cancelled, no files after it,
/// and the design computes again.
#[test]
fn sq_stage_cancels_within_one_iteration() {
    use spherical_faces::sq::params::SqParams;
    let mut s = Session::new();
    let mut r = Recorder::default();
    send(&mut s, &mut r, ToWorker::LoadSample(Sample::Vault), None);
    r.messages.clear();
    let params = SqParams { grid: 10, ..SqParams::default() };
    r.cancel_after = Some(60);
    r.progress_seen = 0;
    send(&mut s, &mut r, run(StageRequest::method::<SqStage>(params.clone())), None);
    assert!(matches!(&r.messages.last().unwrap().0, FromWorker::Cancelled { stage } if stage == "sq"), "{:?}", r.messages.last().unwrap().0);
    let progress = r.messages.iter().filter(|m| matches!(m.0, FromWorker::Progress(_))).count();
    assert_eq!(progress, 60, "no progress after the cancel request");
    assert!(!r.messages.iter().any(|m| matches!(m.0, FromWorker::Files { .. } | FromWorker::Finished { .. })));
    r.messages.clear();
    r.cancel_after = None;
    send(&mut s, &mut r, run(StageRequest::method::<SqStage>(params)), None);
    assert!(matches!(&r.messages.last().unwrap().0, FromWorker::Finished { result: StageResult::Method(MethodSummary::Sq(_)), .. }));
}

/// Progress messages of the method's stage among `messages`.
fn method_progress(messages: &[(FromWorker, Vec<Field>)], stage: StageId) -> usize {
    messages.iter().filter(|m| matches!(&m.0, FromWorker::Progress(p) if p.stage == stage)).count()
}

/// The finished report of the last run.
fn finished_report(messages: &[(FromWorker, Vec<Field>)]) -> spherical_faces::export::Report {
    let Some((FromWorker::Finished { result, .. }, _)) = messages.last().cloned() else { panic!("{:?}", messages.last()) };
    result.report().expect("a method's report").clone()
}

/// A new δ or K for the finished result exports it again without running the method: no
/// progress, the same panels, the moulds the new tolerance asks for. Anything else, a method that
/// optimizes for its moulds, or a new reference runs the method again.
#[test]
fn new_moulds_export_the_last_result_again() {
    use spherical_faces::panels::moulds::{Fabrication, MouldTarget};
    use spherical_faces::sq::params::SqParams;
    use spherical_faces::units::{Length, Units};
    let by_count = |k| Fabrication { units: Units::M, moulds: MouldTarget::Count(k) };
    let tolerance = |t| Fabrication { units: Units::M, moulds: MouldTarget::Tolerance(Length { value: t, unit: None }) };
    let panels = |m: &[(FromWorker, Vec<Field>)], stage: StageId| {
        let snap = m.iter().rev().find(|m| matches!(&m.0, FromWorker::Snapshot { stage: s, .. } if *s == stage)).expect("a snapshot");
        find(&snap.1, field::PANEL_POSITIONS).unwrap().as_f32().unwrap().to_vec()
    };
    type Request = fn(Fabrication, bool) -> StageRequest;
    let cases: [(Sample, Request); 2] = [
        (Sample::Dome, |f, o| {
            StageRequest::method::<StSupportStage>(StSupportParams { optimize_moulds: o, ..Default::default() }).with_fabrication(f)
        }),
        (Sample::Vault, |f, o| StageRequest::method::<SqStage>(SqParams { optimize_moulds: o, ..Default::default() }).with_fabrication(f)),
    ];
    for (sample, request) in cases {
        let mut s = Session::new();
        let mut r = Recorder::default();
        send(&mut s, &mut r, ToWorker::LoadSample(sample), None);
        let stage = request(by_count(1), false).name();
        let ran = |s: &mut Session, req: StageRequest| {
            let mut r = Recorder::default();
            send(s, &mut r, run(req), None);
            r.messages
        };
        let first = ran(&mut s, request(by_count(1), false));
        assert!(method_progress(&first, stage) > 0, "{sample:?}: the method ran");
        let one = finished_report(&first).moulds.unwrap();
        assert_eq!(one.count, 1, "{sample:?}");
        let again = ran(&mut s, request(by_count(3), false));
        assert_eq!(method_progress(&again, stage), 0, "{sample:?}: exported again, not run");
        assert_eq!(panels(&again, stage), panels(&first, stage), "{sample:?}: the same panels");
        assert!(again.iter().any(|m| matches!(m.0, FromWorker::Files { .. })), "{sample:?}: new files");
        let three = finished_report(&again);
        assert_eq!(three.moulds.as_ref().unwrap().count, 3, "{sample:?}");
        assert!(three.moulds.as_ref().unwrap().tolerance < one.tolerance, "{sample:?}");
        assert_eq!(three.metrics, finished_report(&first).metrics, "{sample:?}: the same result");
        // A tolerance is a new δ too.
        let by_tolerance = ran(&mut s, request(tolerance(one.tolerance), false));
        assert_eq!(method_progress(&by_tolerance, stage), 0, "{sample:?}");
        assert_eq!(finished_report(&by_tolerance).moulds.unwrap().count, 1, "{sample:?}");
        // Optimizing for the moulds depends on them: the method runs.
        assert!(method_progress(&ran(&mut s, request(by_count(3), true)), stage) > 0, "{sample:?}");
        // A new reference forgets the result.
        send(&mut s, &mut r, ToWorker::LoadSample(sample), None);
        assert!(method_progress(&ran(&mut s, request(by_count(1), false)), stage) > 0, "{sample:?}");
    }
}
