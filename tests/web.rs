//! In the browser (wasm-pack test --headless --chrome): the worker protocol across a real
//! MessageChannel with transferred buffers, the importers, and the session.
#![cfg(target_arch = "wasm32")]

use js_sys::{Promise, Reflect};
use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::JsFuture;
use wasm_bindgen_test::*;

use spherical_faces::congruence::central_spheres::JetParams;
use spherical_faces::import::{import_mesh, Format};
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::pipeline::fields::{field, Field};
use spherical_faces::pipeline::protocol::*;
use spherical_faces::pipeline::{Outbox, Session};
use spherical_faces::samples::Sample;
use spherical_faces::web::transport;

// In a dedicated worker, as the app runs its pipeline: a long run then never holds the page that
// chromedriver talks to (it drops a page that does not answer for 30 s).
wasm_bindgen_test_configure!(run_in_dedicated_worker);

/// Posts `value` through a MessageChannel (structured clone + transfer) and awaits it.
async fn through_channel(value: &JsValue, transfer: &JsValue) -> JsValue {
    let channel = web_sys::MessageChannel::new().unwrap();
    let port2 = channel.port2();
    let promise = Promise::new(&mut |resolve, _reject| {
        let cb = Closure::once_into_js(move |ev: web_sys::MessageEvent| {
            resolve.call1(&JsValue::NULL, &ev.data()).unwrap();
        });
        port2.set_onmessage(Some(cb.unchecked_ref()));
    });
    channel.port1().post_message_with_transferable(value, transfer).unwrap();
    JsFuture::from(promise).await.unwrap()
}

/// Gives the worker back to its event loop for one task. The runner runs synchronous tests back
/// to back in one task: each long test awaits this before every run, so the worker hands on its
/// output between runs and no task holds it for more than one run.
async fn next_page_task() {
    through_channel(&JsValue::NULL, &js_sys::Array::new()).await;
}

/// Runs `work` in a task of its own and logs how long it took.
async fn in_own_task<T>(what: &str, work: impl FnOnce() -> T) -> T {
    next_page_task().await;
    let start = js_sys::Date::now();
    let out = work();
    console_log!("{what}: {:.1} s in the worker", (js_sys::Date::now() - start) / 1e3);
    out
}

/// The tests run in a dedicated worker (no document), so no run holds the page.
#[wasm_bindgen_test]
fn the_tests_run_in_a_dedicated_worker() {
    let global = js_sys::global();
    assert!(!Reflect::has(&global, &"document".into()).unwrap());
    assert!(Reflect::has(&global, &"importScripts".into()).unwrap());
}

#[wasm_bindgen_test]
async fn protocol_round_trip_across_a_message_channel() {
    let fields = vec![
        Field::f32(field::POSITIONS, 3, vec![0.0, 1.0, 2.0, -3.5, 4.25, 1e-7]),
        Field::u32(field::TRIANGLES, 3, vec![0, 1, 1]),
        Field::f32(field::MEAN_CURVATURE, 1, vec![0.5, -0.25]),
    ];
    let msg = FromWorker::Snapshot { stage: StageId::Curvature, iteration: 7, fields: fields.iter().map(Field::header).collect() };
    let (obj, transfer) = transport::to_js(&encode_from_worker(&msg, &fields));
    let first_body = Reflect::get(&obj, &"bodies".into()).unwrap();
    let first_body: js_sys::ArrayBuffer = js_sys::Array::from(&first_body).get(0).unchecked_into();
    assert_eq!(first_body.byte_length(), 24);
    let received = through_channel(&obj, &transfer).await;
    // Transferred, not copied: the sender's buffer is detached.
    assert_eq!(first_body.byte_length(), 0);
    let (back, back_fields) = decode_from_worker(&transport::from_js(&received).unwrap()).unwrap();
    assert_eq!(back, msg);
    assert_eq!(back_fields, fields);

    let to = ToWorker::LoadFile { name: "roof.obj".into() };
    let (obj, transfer) = transport::to_js(&encode_to_worker(&to, Some(b"v 0 0 0".to_vec())));
    let received = through_channel(&obj, &transfer).await;
    let env = transport::from_js(&received).unwrap();
    let (back, body) = decode_to_worker(&env).unwrap();
    assert_eq!(back, to);
    assert_eq!(body, Some(&b"v 0 0 0"[..]));

    assert!(transport::from_js(&JsValue::from_str("nonsense")).is_err());
}

/// faer's dense products above 16³ run gemm, whose simd128 kernels are off by default: the
/// `wasm-simd128-enable` feature (Cargo.toml) must reach it, or the Cholesky runs scalar kernels.
#[wasm_bindgen_test]
fn dense_products_run_wasm_simd_kernels() {
    assert!(gemm::get_wasm_simd128(), "gemm's wasm simd128 kernels are off");
}

/// Small dense products (at most 16³ multiply-adds) go to nano-gemm, whose wasm fallback kernel is
/// patched (vendor/nano-gemm/PATCH.md): column-major, transposed, accumulating and replacing
/// products agree with a triple loop.
#[wasm_bindgen_test]
fn small_dense_products_match_a_triple_loop() {
    use faer::linalg::matmul::matmul;
    use faer::{Accum, Mat, Par};
    let value = |i: usize, j: usize, s: f64| ((i * 7 + j * 3) as f64 * 0.37 + s).sin();
    for (m, n, k) in [(1, 1, 1), (3, 4, 5), (7, 5, 6), (16, 16, 16), (9, 2, 13), (2, 11, 3)] {
        let lhs = Mat::from_fn(m, k, |i, j| value(i, j, 0.1));
        let lhs_t = Mat::from_fn(k, m, |i, j| value(j, i, 0.1));
        let rhs = Mat::from_fn(k, n, |i, j| value(i, j, 0.7));
        let start = Mat::from_fn(m, n, |i, j| value(i, j, 1.3));
        for (accum, transposed) in [(Accum::Replace, false), (Accum::Add, false), (Accum::Add, true)] {
            let mut dst = start.clone();
            let left = if transposed { lhs_t.transpose() } else { lhs.as_ref() };
            matmul(dst.as_mut(), accum, left, rhs.as_ref(), -0.5, Par::Seq);
            for i in 0..m {
                for j in 0..n {
                    let dot: f64 = (0..k).map(|p| lhs[(i, p)] * rhs[(p, j)]).sum();
                    let base = if accum == Accum::Add { start[(i, j)] } else { 0.0 };
                    let want = base - 0.5 * dot;
                    assert!(
                        (dst[(i, j)] - want).abs() <= 1e-12,
                        "{m}×{k}·{k}×{n} ({accum:?}, transposed {transposed}) at ({i}, {j}): {} vs {want}",
                        dst[(i, j)]
                    );
                }
            }
        }
    }
}

#[wasm_bindgen_test]
fn obj_importer_in_the_browser() {
    let bytes = include_bytes!("../../shared/data/meshes/tri_dome.obj");
    let imported = import_mesh(bytes, "tri_dome.obj").unwrap();
    assert_eq!(imported.stats.vertices, 91);
    assert_eq!(imported.stats.faces, 160);
    assert_eq!(imported.format, Format::Obj);
    let quads = import_mesh(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "q.obj").unwrap();
    assert_eq!(quads.stats.faces, 2);
    assert!(import_mesh(b"v 1 2\nf 1 2 9\n", "broken.obj").is_err());
    // The first third of the file holds only vertices: refused, saying so.
    let cut = import_mesh(&bytes[..bytes.len() / 3], "tri_dome.obj").unwrap_err();
    assert!(cut.to_string().contains("no faces"), "{cut}");
}

#[wasm_bindgen_test]
fn gltf_importers_in_the_browser() {
    // One triangle with an embedded data: URI buffer: 3 × vec3 f32 positions.
    let mut bin = Vec::new();
    for x in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bin.extend_from_slice(&x.to_le_bytes());
    }
    const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut b64 = String::new();
    for c in bin.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                b64.push(B64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                b64.push('=');
            }
        }
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0,"translation":[10,0,0]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
    );
    let m = import_mesh(json.as_bytes(), "tri.gltf").unwrap();
    assert_eq!(m.format, Format::Gltf);
    assert_eq!(m.stats.faces, 1);
    assert!(m.mesh.positions.iter().all(|p| p.x >= 10.0));
    assert!(import_mesh(&json.as_bytes()[..json.len() / 2], "tri.gltf").is_err());
    assert!(import_mesh(b"glTF\x02\x00\x00\x00\xff\xff\x00\x00", "t.glb").is_err());
}

struct Recorder(Vec<FromWorker>);

impl Outbox for Recorder {
    fn send(&mut self, msg: FromWorker, _fields: Vec<Field>) {
        self.0.push(msg);
    }
    fn cancel_requested(&mut self) -> bool {
        false
    }
    fn now_ms(&self) -> f64 {
        js_sys::Date::now()
    }
}

#[wasm_bindgen_test]
async fn session_runs_curvature_in_wasm() {
    let mut s = Session::new();
    let mut r = Recorder(Vec::new());
    in_own_task("curvature of the sphere cap", || {
        s.handle(ToWorker::LoadSample(Sample::SphereCap), None, &mut r);
        s.handle(ToWorker::Run(Box::new(StageRequest::Curvature(JetParams::default()))), None, &mut r);
    })
    .await;
    let Some(FromWorker::Finished { result: StageResult::Curvature(summary), .. }) = r.0.last() else { panic!("{:?}", r.0.last()) };
    assert!(summary.min_h.is_finite() && summary.max_h.is_finite());
    assert!(!summary.h_changes_sign);
}

/// On wasm32 a field header's `len × 4` is computed in 64 bits: a length of 2³⁰ + 1 would wrap a
/// 32-bit product to 4 and accept a 4-byte body.
#[wasm_bindgen_test]
fn field_lengths_do_not_wrap_on_wasm32() {
    use spherical_faces::pipeline::fields::{FieldHeader, FieldKind};
    let header = FieldHeader { name: "positions".into(), kind: FieldKind::F32, dim: 3, len: (1 << 30) + 1 };
    assert!(Field::from_bytes(&header, &[0, 0, 0, 0]).is_err());
}

/// SQ in wasm meets every guarantee on a shared roof, as natively: the congruence holds θ on every
/// grid point and every grid quad has real torsal directions with planes at ≥ α, recomputed here
/// from the congruence's own points and lines, and the SQ mesh meets every guarantee. One test
/// per roof, each one SQ run of about 10 s.
async fn sq_meets_its_guarantees_in_wasm_on(name: &str, surface: spherical_faces::geometry::bspline::BSplineSurface, theta: f64, alpha: f64) {
    use spherical_faces::congruence::torsal::torsal_pair;
    use spherical_faces::progress::Clock;
    use spherical_faces::reference::Reference;
    use spherical_faces::sq::params::SqParams;
    let reference = Reference::from_bspline(surface).unwrap();
    let params = SqParams { theta_deg: theta, alpha_deg: alpha, ..SqParams::default() };
    let run = || spherical_faces::sq::compute(&reference, &params, &Fabrication::default(), Clock(None), &mut |_| Ok(())).unwrap();
    let result = in_own_task(&format!("SQ on {name}"), run).await;
    let c = &result.congruence;
    let n = c.grid;
    for (p, (l, normal)) in c.lines.iter().zip(&c.normals).enumerate() {
        let angle = l.dot(*normal).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(angle <= theta, "{name}: line {p} at {angle:.2}° from the normal");
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let corners = [i + n * j, i + 1 + n * j, i + 1 + n * (j + 1), i + n * (j + 1)];
            let pair = torsal_pair(corners.map(|k| c.points[k]), corners.map(|k| c.lines[k]));
            let pair = pair.unwrap_or_else(|| panic!("{name}: quad ({i}, {j}) without real torsal directions"));
            assert!(pair.angle_deg >= alpha, "{name}: quad ({i}, {j}) torsal planes at {:.2}°", pair.angle_deg);
        }
    }
    assert!(result.verdict.holds(), "{name}: {}", result.verdict.failure_text());
    if let Some(f) = result.sq_mesh.as_ref().map(|m| m.mesh.figures) {
        console_log!(
            "{name} in wasm: {} quads, vertex–sphere {:.1e}, planarity {:.1e}, axes ≤ {:.2}°, support planes ≥ {:.2}°",
            result.sq_mesh.as_ref().map_or(0, |m| m.mesh.panels.len()),
            f.max_vertex_sphere_residual,
            f.max_centre_face_planarity,
            f.max_axis_normal_angle_deg,
            f.min_torsal_plane_angle_deg
        );
    }
}

/// A shared B-spline file as a surface.
fn shared_bspline(name: &str, bytes: &[u8]) -> spherical_faces::geometry::bspline::BSplineSurface {
    use spherical_faces::import::{import_file, ImportedFile};
    match import_file(bytes, name) {
        Ok(ImportedFile::BSpline(b)) => b.surface,
        _ => panic!("{name}: a B-spline"),
    }
}

/// The tunnel arch at θ 20°, α 75°.
#[wasm_bindgen_test]
async fn sq_meets_its_guarantees_in_wasm_on_the_tunnel_arch() {
    let surface = shared_bspline("tunnel_arch.json", include_bytes!("../../shared/data/bsplines/tunnel_arch.json"));
    sq_meets_its_guarantees_in_wasm_on("tunnel_arch.json", surface, 20.0, 75.0).await;
}

/// The saddle roof at the paper's Fig. 19 settings, θ 15°, α 45°.
#[wasm_bindgen_test]
async fn sq_meets_its_guarantees_in_wasm_on_the_saddle_roof() {
    let surface = shared_bspline("saddle_roof.json", include_bytes!("../../shared/data/bsplines/saddle_roof.json"));
    sq_meets_its_guarantees_in_wasm_on("saddle_roof.json", surface, 15.0, 45.0).await;
}

/// The vault sample at θ 20°, α 75°.
#[wasm_bindgen_test]
async fn sq_meets_its_guarantees_in_wasm_on_the_vault_sample() {
    sq_meets_its_guarantees_in_wasm_on("sample:vault", Sample::Vault.bspline().unwrap(), 20.0, 75.0).await;
}

/// The verdicts of one ST and one SQ run in wasm equal the native ones recorded in
/// `tests/data/verdicts.json` (`tests/verdicts.rs` checks the native runs against it): the same
/// guarantees, each holding alike, counts equal and figures within the run's
/// [`VerdictRun::figure_tolerance`].
#[wasm_bindgen_test]
async fn wasm_reaches_the_native_verdicts() {
    use spherical_faces::bench_workloads::{recorded_verdict_differences, VerdictRun};
    let mut runs = Vec::new();
    for run in VerdictRun::ALL {
        runs.push((run.name(), in_own_task(run.name(), || run.run()).await));
    }
    let diff = recorded_verdict_differences(include_str!("data/verdicts.json"), &runs);
    assert!(diff.is_empty(), "{diff:?}");
    for (name, now) in &runs {
        console_log!("{name} in wasm: {} guarantees, as native", now.len());
    }
}

/// SQ on two hard surfaces in wasm (the revolved bell, whose mean curvature changes sign, and the
/// umbilic dome) reaches the native verdicts recorded in `tests/data/verdicts_hard.json`
/// (`tests/verdicts.rs`), each run a few seconds.
#[wasm_bindgen_test]
async fn wasm_reaches_the_native_hard_verdicts() {
    use spherical_faces::bench_workloads::{hard_verdict_run, recorded_verdict_differences};
    let files: [(&str, &[u8]); 2] = [
        ("revolved_bell.json", include_bytes!("../../shared/data/bsplines/hard/revolved_bell.json")),
        ("umbilic_dome.json", include_bytes!("../../shared/data/bsplines/hard/umbilic_dome.json")),
    ];
    let mut runs = Vec::new();
    for (name, bytes) in files {
        runs.push((name, in_own_task(name, || hard_verdict_run(name, bytes)).await));
    }
    let diff = recorded_verdict_differences(include_str!("data/verdicts_hard.json"), &runs);
    assert!(diff.is_empty(), "{diff:?}");
    for (name, now) in &runs {
        console_log!("{name} in wasm: {} guarantees, as native", now.len());
    }
}
