//! The native command line over the same pipeline as the browser app (see `main.rs`).

use std::process::ExitCode;

use spherical_faces::curvature::{jet_fit, JetParams};
use spherical_faces::import::import_mesh;
use spherical_faces::mesh::Topology;
use spherical_faces::pipeline::st_support::{self, StSupportRequest};
use spherical_faces::remesh::DEFAULT_EPSILON;
use spherical_faces::st_angle::StSizing;
use spherical_faces::st_support::{native_clock_ms, Clock};

const USAGE: &str = "usage:
  spherical-faces info <mesh.obj|.gltf|.glb>
      <mesh> is a file or sample:NAME, a built-in sample (dome, torus, sphere-cap, wave-roof).
  spherical-faces st-support <mesh> [--optimize-radius] [--depth D] [--axis-length L]
                             [--radius-tolerance T] [--adaptive --epsilon E | --faces N] --out DIR
      ST mesh with support structure (paper Sec. 4). Writes DIR/panels.glb, panels.obj,
      panels.csv, panels.json and report.json. D, L and T are relative to the bbox diagonal
      (defaults 0.02, 0.1, 0.001). --adaptive --epsilon E remeshes first with the sizing field
      of the local spheres orthogonal to Ω (Sec. 3, Fig. 16 bottom; E relative to the diagonal,
      default 0.0004); --faces N remeshes first uniformly to about N faces.
  spherical-faces st <mesh> [--epsilon E | --faces N] [--variant a|b] --out DIR
      Angle-minimizing ST mesh with face size adapted to the surface (paper Sec. 3): remesh
      with the sizing field of tolerance E (relative to the bbox diagonal) or uniformly to
      about N faces, then optimize the face spheres. Same files and report.json schema.";

pub fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("info") if args.len() == 2 => finish(info(&args[1])),
        Some("st-support") => finish(st_support_command(&args[1..])),
        Some("st") => finish(st_command(&args[1..])),
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        _ => {
            eprintln!("{USAGE}");
            ExitCode::from(2)
        }
    }
}

/// Prints the command's output, or its error as one line on stderr with exit code 2.
fn finish(result: Result<String, String>) -> ExitCode {
    match result {
        Ok(out) => {
            println!("{out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// Reads a mesh the way the app does; the error names the file. `sample:NAME` is a built-in
/// sample (the app's sample menu: dome, torus, sphere-cap, wave-roof).
fn read_mesh(path: &str) -> Result<spherical_faces::import::Imported, String> {
    if let Some(key) = path.strip_prefix("sample:") {
        return sample_mesh(key);
    }
    let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    let name = std::path::Path::new(path).file_name().map_or(path.into(), |n| n.to_string_lossy().into_owned());
    import_mesh(&bytes, &name).map_err(|e| e.to_string())
}

/// A built-in sample as if imported.
fn sample_mesh(key: &str) -> Result<spherical_faces::import::Imported, String> {
    use spherical_faces::samples::Sample;
    let sample = Sample::from_key(key).ok_or_else(|| {
        let names: Vec<&str> = Sample::ALL.iter().map(|s| s.key()).collect();
        format!("sample:{key}: no such sample (samples: {})", names.join(", "))
    })?;
    let mesh = sample.mesh();
    let stats = Topology::new(&mesh).stats(&mesh);
    Ok(spherical_faces::import::Imported {
        source_polygons: mesh.face_count(),
        mesh,
        stats,
        format: spherical_faces::import::Format::Obj,
        merged_vertices: 0,
        dropped_faces: 0,
        notes: Vec::new(),
    })
}

/// `st-support <mesh> [options] --out DIR`: writes the panel files and report.json.
fn st_support_command(args: &[String]) -> Result<String, String> {
    let mut req = StSupportRequest::default();
    let (mut mesh_path, mut out) = (None, None);
    let (mut adaptive, mut epsilon, mut faces) = (false, None, None);
    let mut it = args.iter();
    let number = |flag: &str, v: Option<&String>, lo: f64, hi: f64| -> Result<f64, String> {
        let v = v.ok_or(format!("{flag} needs a value"))?;
        v.parse::<f64>().ok().filter(|x| (lo..=hi).contains(x)).ok_or(format!("{flag} {v}: expected a number in [{lo}, {hi}]"))
    };
    while let Some(a) = it.next() {
        match a.as_str() {
            "--optimize-radius" => req.optimize_radius = true,
            "--depth" => req.support_depth = number(a, it.next(), 0.0, 1.0)?,
            "--axis-length" => req.axis_length = number(a, it.next(), 0.0, 10.0)?,
            "--radius-tolerance" => req.radius_tolerance = number(a, it.next(), 1e-9, 1.0)?,
            "--adaptive" => adaptive = true,
            "--epsilon" => epsilon = Some(positive_fraction(a, it.next())?),
            "--faces" => faces = Some(face_count(a, it.next())?),
            "--out" => out = Some(it.next().ok_or("--out needs a folder")?.clone()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s if mesh_path.is_none() => mesh_path = Some(s.to_string()),
            s => return Err(format!("unexpected argument {s}")),
        }
    }
    req.remesh = match (adaptive, epsilon, faces) {
        (_, _, Some(_)) if adaptive || epsilon.is_some() => return Err("use either --adaptive --epsilon E or --faces N".into()),
        (false, Some(_), None) => return Err("--epsilon needs --adaptive (remesh with the sizing field)".into()),
        (true, e, None) => StSizing::Adaptive { epsilon: e.unwrap_or(DEFAULT_EPSILON) },
        (false, None, Some(n)) => StSizing::UniformFaces(n),
        _ => StSizing::None,
    };
    let mesh_path = mesh_path.ok_or("st-support needs a mesh file")?;
    let out = std::path::PathBuf::from(out.ok_or("st-support needs --out DIR")?);
    let t0 = native_clock_ms();
    let imported = read_mesh(&mesh_path)?;
    let import_ms = native_clock_ms() - t0;
    let topology = Topology::new(&imported.mesh);
    let t1 = native_clock_ms();
    let field = jet_fit(&imported.mesh, &topology, &req.jet, &mut |_, _| true).ok_or("cancelled")?;
    let curvature_ms = native_clock_ms() - t1;
    let mut output = st_support::run(&imported.mesh, &topology, &field, &req, Clock(Some(native_clock_ms)), &mut |_, _, _| true)
        .map_err(|e| format!("{mesh_path}: {e}"))?;
    // The report's timings include reading and curvature, which the CLI did itself.
    output.summary.report.add_timing("import", import_ms);
    output.summary.report.add_timing("curvature", curvature_ms);
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    for f in &output.files {
        let bytes = if f.name == "report.json" { output.summary.report.to_json().into_bytes() } else { f.bytes.clone() };
        std::fs::write(out.join(&f.name), bytes).map_err(|e| format!("{}: {e}", out.join(&f.name).display()))?;
    }
    Ok(format!(
        "wrote {} panels to {} (max kink {:.3}°, max distance to reference {:.2e} of the diagonal)",
        output.panels.len(),
        out.display(),
        output.result.metrics.max_kink_angle_deg,
        output.summary.report.metrics.max_distance_to_reference.unwrap_or(f64::NAN)
    ))
}

/// `st <mesh> [--epsilon E | --faces N] [--variant a|b] --out DIR`.
fn st_command(args: &[String]) -> Result<String, String> {
    use spherical_faces::pipeline::st_angle::report_and_files;
    use spherical_faces::st_angle::{st_angle, StAngleParams, StVariant};
    let mut params = StAngleParams::default();
    let (mut mesh_path, mut out) = (None, None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--epsilon" => params.sizing = StSizing::Adaptive { epsilon: positive_fraction(a, Some(value()?))? },
            "--faces" => params.sizing = StSizing::UniformFaces(face_count(a, Some(value()?))?),
            "--variant" => {
                params.variant = match value()?.as_str() {
                    "a" => StVariant::A,
                    "b" => StVariant::B,
                    v => return Err(format!("--variant {v}: expected a or b")),
                }
            }
            "--out" => out = Some(value()?.clone()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s if mesh_path.is_none() => mesh_path = Some(s.to_string()),
            s => return Err(format!("unexpected argument {s}")),
        }
    }
    let mesh_path = mesh_path.ok_or("st needs a mesh file")?;
    let out = std::path::PathBuf::from(out.ok_or("st needs --out DIR")?);
    let imported = read_mesh(&mesh_path)?;
    let result = st_angle(&imported.mesh, &params, Some(native_clock_ms), &mut |_| true).map_err(|e| format!("{mesh_path}: {e}"))?;
    let (report, files) = report_and_files(&imported.mesh, &result, 1e-3);
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    for f in &files {
        std::fs::write(out.join(&f.name), &f.bytes).map_err(|e| format!("{}: {e}", out.join(&f.name).display()))?;
    }
    Ok(format!(
        "wrote {} panels to {} (kink mean {:.3}°, max {:.3}°; max distance to reference {:.2e} of the diagonal)",
        report.output.panels,
        out.display(),
        result.metrics.mean_kink_angle_deg,
        result.metrics.max_kink_angle_deg,
        result.metrics.max_distance_to_reference
    ))
}

/// ε of a sizing field: a number in (0, 1), relative to the bbox diagonal.
fn positive_fraction(flag: &str, v: Option<&String>) -> Result<f64, String> {
    let v = v.ok_or(format!("{flag} needs a value"))?;
    v.parse::<f64>().ok().filter(|x| *x > 0.0 && *x < 1.0).ok_or(format!("{flag} {v}: expected a number in (0, 1)"))
}

/// A target face count of a uniform remesh.
fn face_count(flag: &str, v: Option<&String>) -> Result<usize, String> {
    let v = v.ok_or(format!("{flag} needs a value"))?;
    v.parse::<usize>().ok().filter(|n| *n >= 4).ok_or(format!("{flag} {v}: expected a whole number ≥ 4"))
}

/// One JSON object: counts after triangulation and welding, and the jet-fitted mean curvature.
fn info(path: &str) -> Result<String, String> {
    let imported = read_mesh(path)?;
    let topology = Topology::new(&imported.mesh);
    let field = jet_fit(&imported.mesh, &topology, &JetParams::default(), &mut |_, _| true)
        .ok_or("curvature computation was cancelled")?;
    let s = &imported.stats;
    let c = &field.summary;
    let json = serde_json::json!({
        "vertices": s.vertices,
        "faces": s.faces,
        "boundary_loops": s.boundary_loops,
        "non_manifold_edges": s.non_manifold_edges,
        "bbox_diagonal": imported.mesh.bbox_diagonal(),
        "mean_curvature": {"min": c.min_h, "max": c.max_h, "mean": c.mean_h},
        "h_changes_sign": c.h_changes_sign,
    });
    Ok(json.to_string())
}
