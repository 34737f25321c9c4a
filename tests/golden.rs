//! Golden runs: the ST methods (Sec. 3 and 4) on the shared meshes and the built-in samples,
//! recorded through the CLI and reproduced: counts equal, report metrics and panel geometry
//! (face spheres and corner positions) within 1e-9 of the bounding-box diagonal.
//!
//! `SF_GOLDEN=write cargo test --test golden` records `tests/golden/*.json` anew; without it the
//! runs are compared with the recording. Timings are not compared.
#![cfg(not(target_arch = "wasm32"))] // native: spawns the CLI, reads ../shared

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{json, Value};

/// Panels stored per run: every k-th, k = ⌈n / SAMPLED_PANELS⌉, plus sums over all panels.
const SAMPLED_PANELS: usize = 80;
/// Allowed difference, relative to the bounding-box diagonal (lengths) or to max(1, |x|).
const TOLERANCE: f64 = 1e-9;

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

fn input_path(input: &str) -> String {
    match input {
        "tri_mesh" | "botanic-garden-bubble-0" => format!("../shared/data/meshes/{input}.obj"),
        sample => format!("sample:{sample}"),
    }
}

/// The frame-free form of a normalized sphere (a, b, c) near the point t: its coefficients in the
/// frame y = (x − t)/σ, normalized again (a σ, b − 2 a t, ψ(t)/σ).
fn sphere_in_frame(s: [f64; 5], t: [f64; 3], sigma: f64) -> [f64; 5] {
    let (a, b, c) = (s[0], [s[1], s[2], s[3]], s[4]);
    let tt = t[0] * t[0] + t[1] * t[1] + t[2] * t[2];
    let psi = a * tt - (b[0] * t[0] + b[1] * t[1] + b[2] * t[2]) + c;
    [a * sigma, b[0] - 2.0 * a * t[0], b[1] - 2.0 * a * t[1], b[2] - 2.0 * a * t[2], psi / sigma]
}

/// What one run gives: its error, or the report (without timings) and the panel geometry.
fn record(input: &str, args: &[&str]) -> Value {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("sf-golden-{}-{}", input, args.join("_")));
    let _ = std::fs::remove_dir_all(&dir);
    let path = input_path(input);
    let mut cmd_args: Vec<&str> = vec![args[0], &path];
    cmd_args.extend_from_slice(&args[1..]);
    let dir_s = dir.to_str().unwrap().to_string();
    cmd_args.extend_from_slice(&["--out", &dir_s]);
    let out = Command::new(env!("CARGO_BIN_EXE_spherical-faces")).args(&cmd_args).output().expect("runs");
    // Exit 3: the result was written but misses a guarantee; its report says which, and is
    // recorded like any other (with `meets_guarantees: false`).
    if !out.status.success() && out.status.code() != Some(3) {
        let err = String::from_utf8_lossy(&out.stderr).trim().to_string();
        assert_eq!(out.status.code(), Some(2), "{err}");
        return json!({ "error": err });
    }
    let read = |name: &str| -> Value { serde_json::from_slice(&std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))).unwrap() };
    let mut report = read("report.json");
    report.as_object_mut().unwrap().remove("timings_ms");
    let schedule = read("panels.json");
    let _ = std::fs::remove_dir_all(&dir);
    let diag = schedule["reference_diagonal"].as_f64().unwrap();
    let panels = schedule["panels"].as_array().unwrap();
    let stride = panels.len().div_ceil(SAMPLED_PANELS).max(1);
    let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    let geometry = |p: &Value| -> (Vec<Vec<f64>>, [f64; 5]) {
        let vertices: Vec<Vec<f64>> = p["vertices"].as_array().unwrap().iter().map(|v| v.as_array().unwrap().iter().map(f).collect()).collect();
        let n = vertices.len() as f64;
        let t = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).sum::<f64>() / n);
        let s = &p["sphere"];
        let b: Vec<f64> = s["b"].as_array().unwrap().iter().map(f).collect();
        (vertices, sphere_in_frame([f(&s["a"]), b[0], b[1], b[2], f(&s["c"])], t, diag))
    };
    let mut sums = vec![0.0; 8];
    let mut sampled = Vec::new();
    for (i, p) in panels.iter().enumerate() {
        let (vertices, sphere) = geometry(p);
        for (k, x) in sphere.iter().enumerate() {
            sums[k] += x;
        }
        for v in &vertices {
            for k in 0..3 {
                sums[5 + k] += v[k] / diag;
            }
        }
        if i % stride == 0 {
            sampled.push(json!({ "id": p["id"], "vertex_ids": p["vertex_ids"], "vertices": vertices, "sphere": sphere }));
        }
    }
    json!({
        "report": report,
        "panels": { "count": panels.len(), "diagonal": diag, "stride": stride, "sampled": sampled, "sums": sums },
    })
}

/// Compares `got` with `want` recursively: numbers within the tolerance (`scale` for lengths
/// relative to nothing else), everything else equal.
fn compare(path: &str, want: &Value, got: &Value, scale: f64, errors: &mut Vec<String>) {
    match (want, got) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            let tol = TOLERANCE * scale.max(a.abs()).max(1.0);
            if (a - b).abs() > tol || (a - b).is_nan() {
                errors.push(format!("{path}: {a:e} recorded, {b:e} now (tolerance {tol:e})"));
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            for k in keys {
                match (a.get(k), b.get(k)) {
                    (Some(x), Some(y)) => compare(&format!("{path}.{k}"), x, y, scale, errors),
                    (x, y) => errors.push(format!("{path}.{k}: {x:?} recorded, {y:?} now")),
                }
            }
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                compare(&format!("{path}[{i}]"), x, y, scale, errors);
            }
        }
        (a, b) if a == b => {}
        (a, b) => errors.push(format!("{path}: {a} recorded, {b} now")),
    }
}

fn check(name: &str, input: &str, args: &[&str]) {
    let got = record(input, args);
    let file = golden_dir().join(format!("{name}.json"));
    if std::env::var("SF_GOLDEN").as_deref() == Ok("write") {
        std::fs::create_dir_all(golden_dir()).unwrap();
        let recorded = json!({ "input": input, "args": args, "run": got });
        std::fs::write(&file, serde_json::to_string_pretty(&recorded).unwrap() + "\n").unwrap();
        return;
    }
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let want: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(want["args"], json!(args), "{name}: recorded with other arguments");
    let mut errors = Vec::new();
    // Panel sums add up n panels: allow n times the tolerance there.
    let n = want["run"]["panels"]["count"].as_f64().unwrap_or(1.0);
    if let (Some(w), Some(g)) = (want["run"]["panels"]["sums"].as_array(), got["panels"]["sums"].as_array()) {
        for (k, (a, b)) in w.iter().zip(g).enumerate() {
            compare(&format!("panels.sums[{k}]"), a, b, n, &mut errors);
        }
    }
    let strip = |v: &Value| {
        let mut v = v.clone();
        if let Some(p) = v.get_mut("panels").and_then(Value::as_object_mut) {
            p.remove("sums");
        }
        v
    };
    compare(name, &strip(&want["run"]), &strip(&got), 1.0, &mut errors);
    assert!(errors.is_empty(), "{name}: {} differences:\n{}", errors.len(), errors.iter().take(20).cloned().collect::<Vec<_>>().join("\n"));
}

macro_rules! golden {
    ($($name:ident: $input:literal, [$($arg:literal),*];)*) => {
        $(
            #[test]
            fn $name() {
                check(stringify!($name), $input, &[$($arg),*]);
            }
        )*
    };
}

golden! {
    tri_mesh_st_a: "tri_mesh", ["st", "--epsilon", "0.002", "--variant", "a"];
    tri_mesh_st_b: "tri_mesh", ["st", "--epsilon", "0.002", "--variant", "b"];
    tri_mesh_st_support: "tri_mesh", ["st-support"];
    tri_mesh_st_support_adaptive: "tri_mesh", ["st-support", "--adaptive"];
    tri_mesh_st_support_faces_300: "tri_mesh", ["st-support", "--faces", "300"];
    bubble_st_a: "botanic-garden-bubble-0", ["st", "--epsilon", "0.002", "--variant", "a"];
    bubble_st_b: "botanic-garden-bubble-0", ["st", "--epsilon", "0.002", "--variant", "b"];
    bubble_st_support: "botanic-garden-bubble-0", ["st-support"];
    bubble_st_support_adaptive: "botanic-garden-bubble-0", ["st-support", "--adaptive"];
    bubble_st_support_faces_300: "botanic-garden-bubble-0", ["st-support", "--faces", "300"];
    dome_st_a: "dome", ["st", "--epsilon", "0.002", "--variant", "a"];
    dome_st_b: "dome", ["st", "--epsilon", "0.002", "--variant", "b"];
    dome_st_support: "dome", ["st-support"];
    dome_st_support_adaptive: "dome", ["st-support", "--adaptive"];
    dome_st_support_faces_300: "dome", ["st-support", "--faces", "300"];
    torus_st_a: "torus", ["st", "--epsilon", "0.002", "--variant", "a"];
    torus_st_b: "torus", ["st", "--epsilon", "0.002", "--variant", "b"];
    torus_st_support: "torus", ["st-support"];
    torus_st_support_adaptive: "torus", ["st-support", "--adaptive"];
    torus_st_support_faces_300: "torus", ["st-support", "--faces", "300"];
    sphere_cap_st_a: "sphere-cap", ["st", "--epsilon", "0.002", "--variant", "a"];
    sphere_cap_st_b: "sphere-cap", ["st", "--epsilon", "0.002", "--variant", "b"];
    sphere_cap_st_support: "sphere-cap", ["st-support"];
    sphere_cap_st_support_adaptive: "sphere-cap", ["st-support", "--adaptive"];
    sphere_cap_st_support_faces_300: "sphere-cap", ["st-support", "--faces", "300"];
    wave_roof_st_a: "wave-roof", ["st", "--epsilon", "0.002", "--variant", "a"];
    wave_roof_st_b: "wave-roof", ["st", "--epsilon", "0.002", "--variant", "b"];
    wave_roof_st_support: "wave-roof", ["st-support"];
    wave_roof_st_support_adaptive: "wave-roof", ["st-support", "--adaptive"];
    wave_roof_st_support_faces_300: "wave-roof", ["st-support", "--faces", "300"];
}
