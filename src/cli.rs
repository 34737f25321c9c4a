//! The native command line over the same pipeline as the browser app (see `main.rs`).

use std::process::ExitCode;

use spherical_faces::congruence::central_spheres::JetParams;
use spherical_faces::export::ExportFile;
use spherical_faces::panels::edge_arcs::EdgeArcs;
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::pipeline::stages;
use spherical_faces::progress::{ignore, Clock};
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::{Sizing, DEFAULT_EPSILON};
use spherical_faces::samples::Sample;
use spherical_faces::sq::params::{SqParams, Until, ALPHA_RANGE, FACES_RANGE, GRID_RANGE, RECOMPUTE_RANGE, THETA_RANGE};
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_support::StSupportParams;

const USAGE: &str = "usage:
  spherical-faces info <surface>
      <surface> is a mesh (.obj, .gltf, .glb), a B-spline surface (.json, the paper authors'
      format) or sample:NAME, a built-in sample (dome, torus, sphere-cap, wave-roof, vault).
  spherical-faces st-support <surface> [--optimize-radius] [--depth D] [--axis-length L]
                             [--radius-tolerance T] [--adaptive --epsilon E | --faces N] --out DIR
      ST mesh with support structure (paper Sec. 4). Writes DIR/panels.glb, panels.obj,
      panels.csv, panels.json and report.json. D, L and T are relative to the bbox diagonal
      (defaults 0.02, 0.1, 0.001). --adaptive --epsilon E remeshes first with the sizing field
      of the local spheres orthogonal to Ω (Sec. 3, Fig. 16 bottom; E relative to the diagonal,
      default 0.0004); --faces N remeshes first uniformly to about N faces.
  spherical-faces st <surface> [--epsilon E | --faces N] [--variant a|b] --out DIR
      Angle-minimizing ST mesh with face size adapted to the surface (paper Sec. 3): remesh
      with the sizing field of tolerance E (relative to the bbox diagonal) or uniformly to
      about N faces, then optimize the face spheres. Same files and report.json schema.
  spherical-faces sq <bspline.json> [--theta DEG] [--alpha DEG] [--grid N] [--rs K]
                     [--faces N] [--until congruence|remesh|final] [--depth D] --out DIR
      SQ mesh with support structure (paper Sec. 5): fit the radius function on an N × N
      grid (default 20), optimize the line congruence to within θ of the normals (default
      20°) and its torsal planes to meet at ≥ α (default 75°), recomputing the torsal
      directions every K iterations (default 10) (Sec. 5.1); remesh along the torsal cross
      field to about N quads (default 237) and fair it into Q′; optimize the face spheres
      (Eq. 10) and project to an exact SQ mesh; panels, support structure of depth D
      (relative to the diagonal, default 0.02) and node axes (Sec. 5.2). Writes
      congruence.json and congruence.glb; with --until remesh also mesh.obj (Q′); by default
      also panels.glb, panels.obj, panels.csv, panels.json, support.csv, mesh.obj (the SQ
      mesh's vertices and quads) and report.json.";

pub fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("info") if args.len() == 2 => finish(info(&args[1])),
        Some("st-support") => finish(st_support_command(&args[1..])),
        Some("st") => finish(st_command(&args[1..])),
        Some("sq") => finish(sq_command(&args[1..])),
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

/// Loads a file or a sample the way the app does; the error names the file. `sample:NAME` is a
/// built-in sample (the app's sample menu).
fn load(path: &str) -> Result<Loaded, String> {
    if let Some(key) = path.strip_prefix("sample:") {
        let sample = Sample::from_key(key).ok_or_else(|| {
            let names: Vec<&str> = Sample::ALL.iter().map(|s| s.key()).collect();
            format!("sample:{key}: no such sample (samples: {})", names.join(", "))
        })?;
        return Ok(Loaded::from_sample(sample));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    let name = std::path::Path::new(path).file_name().map_or(path.into(), |n| n.to_string_lossy().into_owned());
    Loaded::from_file(&bytes, &name).map_err(|e| e.to_string())
}

/// `st-support <mesh> [options] --out DIR`: writes the panel files and report.json.
fn st_support_command(args: &[String]) -> Result<String, String> {
    let mut params = StSupportParams::default();
    let (mut mesh_path, mut out) = (None, None);
    let (mut adaptive, mut epsilon, mut faces) = (false, None, None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--optimize-radius" => params.optimize_radius = true,
            "--depth" => params.support_depth = number(a, it.next(), (0.0, 1.0))?,
            "--axis-length" => params.axis_length = number(a, it.next(), (0.0, 10.0))?,
            "--radius-tolerance" => params.radius_tolerance = number(a, it.next(), (1e-9, 1.0))?,
            "--adaptive" => adaptive = true,
            "--epsilon" => epsilon = Some(positive_fraction(a, it.next())?),
            "--faces" => faces = Some(face_count(a, it.next())?),
            "--out" => out = Some(it.next().ok_or("--out needs a folder")?.clone()),
            s => positional(s, &mut mesh_path)?,
        }
    }
    params.remesh = match (adaptive, epsilon, faces) {
        (_, _, Some(_)) if adaptive || epsilon.is_some() => return Err("use either --adaptive --epsilon E or --faces N".into()),
        (false, Some(_), None) => return Err("--epsilon needs --adaptive (remesh with the sizing field)".into()),
        (true, e, None) => Sizing::Adaptive { epsilon: e.unwrap_or(DEFAULT_EPSILON) },
        (false, None, Some(n)) => Sizing::UniformFaces(n),
        _ => Sizing::None,
    };
    let mesh_path = mesh_path.ok_or("st-support needs a mesh file")?;
    let out = std::path::PathBuf::from(out.ok_or("st-support needs --out DIR")?);
    let clock = Clock::native();
    let t0 = clock.now();
    let reference = read_reference(&mesh_path)?;
    let import_ms = clock.now() - t0;
    let t1 = clock.now();
    reference.curvature(&params.jet, &mut ignore).map_err(|e| e.to_string())?;
    let curvature_ms = clock.now() - t1;
    let mut result = spherical_faces::st_support::compute(&reference, &params, clock, &mut ignore)
        .map_err(|e| format!("{mesh_path}: {e}"))?;
    // The report's timings include reading and curvature, which the CLI did itself.
    result.timings_ms.insert(0, ("curvature".into(), curvature_ms));
    result.timings_ms.insert(0, ("import".into(), import_ms));
    let (report, files) = stages::st_support::export(&reference, &result, &params, clock);
    write_files(&out, &files)?;
    Ok(format!(
        "wrote {} panels to {} (max kink {:.3}°, max distance to reference {:.2e} of the diagonal)",
        result.panels.len(),
        out.display(),
        result.metrics.max_kink_angle_deg,
        report.metrics.max_distance_to_reference.unwrap_or(f64::NAN)
    ))
}

/// `st <mesh> [--epsilon E | --faces N] [--variant a|b] --out DIR`.
fn st_command(args: &[String]) -> Result<String, String> {
    let mut params = StAdaptedParams::default();
    let (mut mesh_path, mut out) = (None, None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--epsilon" => params.sizing = Sizing::Adaptive { epsilon: positive_fraction(a, Some(value()?))? },
            "--faces" => params.sizing = Sizing::UniformFaces(face_count(a, Some(value()?))?),
            "--variant" => {
                let v = value()?;
                params.variant = EdgeArcs::from_key(v).ok_or(format!("--variant {v}: expected a or b"))?;
            }
            "--out" => out = Some(value()?.clone()),
            s => positional(s, &mut mesh_path)?,
        }
    }
    let mesh_path = mesh_path.ok_or("st needs a mesh file")?;
    let out = std::path::PathBuf::from(out.ok_or("st needs --out DIR")?);
    let reference = read_reference(&mesh_path)?;
    let clock = Clock::native();
    let result = spherical_faces::st_adapted::compute(&reference, &params, clock, &mut |_| Ok(()))
        .map_err(|e| format!("{mesh_path}: {e}"))?;
    let (report, files) = stages::st_adapted::export(&reference, &result, &params, clock);
    write_files(&out, &files)?;
    Ok(format!(
        "wrote {} panels to {} (kink mean {:.3}°, max {:.3}°; max distance to reference {:.2e} of the diagonal)",
        report.output.panels,
        out.display(),
        result.metrics.mean_kink_angle_deg,
        result.metrics.max_kink_angle_deg,
        result.metrics.max_distance_to_reference
    ))
}

/// `sq <bspline.json> [--theta DEG] [--alpha DEG] [--grid N] [--rs K] [--faces N]
/// [--until congruence|remesh|final] [--depth D] --out DIR`.
fn sq_command(args: &[String]) -> Result<String, String> {
    let mut params = SqParams::default();
    let (mut path, mut out) = (None, None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--theta" => params.theta_deg = number(a, it.next(), THETA_RANGE)?,
            "--alpha" => params.alpha_deg = number(a, it.next(), ALPHA_RANGE)?,
            "--grid" => params.grid = whole(a, it.next(), GRID_RANGE)?,
            "--rs" => params.recompute_every = whole(a, it.next(), RECOMPUTE_RANGE)?,
            "--faces" => params.faces = whole(a, it.next(), FACES_RANGE)?,
            "--depth" => params.support_depth = number(a, it.next(), (1e-6, 0.5))?,
            "--until" => {
                let v = it.next().ok_or("--until needs a stage: congruence, remesh or final")?;
                params.until = Until::from_key(v).ok_or(format!("--until {v}: expected congruence, remesh or final"))?;
            }
            "--out" => out = Some(it.next().ok_or("--out needs a folder")?.clone()),
            s => positional(s, &mut path)?,
        }
    }
    let path = path.ok_or("sq needs a B-spline surface (.json) or sample:vault")?;
    let out = std::path::PathBuf::from(out.ok_or("sq needs --out DIR")?);
    let reference = read_reference(&path)?;
    let clock = Clock::native();
    let result = spherical_faces::sq::compute(&reference, &params, clock, &mut |_| Ok(())).map_err(|e| format!("{path}: {e}"))?;
    let segments = spherical_faces::export::congruence::CongruenceSegments::of(&result.congruence);
    let (report, files) = stages::sq::export(&reference, &result, &params, &segments, clock);
    write_files(&out, &files)?;
    let m = &report.metrics;
    let g = |x: Option<f64>| x.unwrap_or(f64::NAN);
    let mut text = match params.until {
        Until::Final => format!(
            "wrote an SQ mesh of {} spherical quad panels with support structure to {}: vertex–sphere residual {:.1e}, centre-face \
             planarity {:.1e}, torsal-plane residual {:.1e}; node axes within {:.2}° of the normals (θ = {}°); support planes meet at \
             ≥ {:.2}° (α = {}°); max distance to the reference {:.2e} of the diagonal; edges off the torsal directions by {:.2}° on \
             average; {} distinct radii; {:.0} ms.",
            report.output.panels,
            out.display(),
            g(m.max_vertex_sphere_residual),
            g(m.max_centre_face_planarity),
            g(m.max_torsal_plane_residual),
            g(m.max_axis_normal_angle_deg),
            params.theta_deg,
            g(m.min_torsal_plane_angle_deg),
            params.alpha_deg,
            g(m.max_distance_to_reference),
            g(m.mean_edge_torsal_angle_deg),
            m.distinct_radii.unwrap_or(0),
            report.timings_ms.get("total").copied().unwrap_or(0.0),
        ),
        Until::Remesh => format!(
            "wrote the quad mesh Q′ ({} quads, {:.1} % of the patch, edges off the torsal directions by {:.2}° on average, at most {:.2}°) \
             and the congruence to {}.",
            report.output.faces,
            100.0 * g(m.coverage),
            g(m.mean_edge_torsal_angle_deg),
            g(m.max_edge_torsal_angle_deg),
            out.display()
        ),
        Until::Congruence => format!(
            "wrote the congruence of a {n}×{n} grid to {} (lines within {:.2}° of the normals, θ = {}°; torsal planes meet at ≥ {:.2}°, \
             α = {}°; {} quads without real torsal directions; E_LC per term {:.2e}).",
            out.display(),
            g(m.max_line_normal_angle_deg),
            params.theta_deg,
            g(m.min_torsal_plane_angle_deg),
            params.alpha_deg,
            m.quads_without_real_torsal_directions.unwrap_or(0),
            g(m.lc_residual),
            n = params.grid,
        ),
    };
    for w in &report.warnings {
        text += &format!("\nwarning: {w}");
    }
    Ok(text)
}

/// A number in [lo, hi] after `flag`.
fn number(flag: &str, v: Option<&String>, (lo, hi): (f64, f64)) -> Result<f64, String> {
    let v = v.ok_or(format!("{flag} needs a value"))?;
    v.parse::<f64>().ok().filter(|x| (lo..=hi).contains(x)).ok_or(format!("{flag} {v}: expected a number in [{lo}, {hi}]"))
}

/// A whole number in [lo, hi] after `flag`.
fn whole(flag: &str, v: Option<&String>, (lo, hi): (usize, usize)) -> Result<usize, String> {
    let v = v.ok_or(format!("{flag} needs a value"))?;
    v.parse::<usize>().ok().filter(|x| (lo..=hi).contains(x)).ok_or(format!("{flag} {v}: expected a whole number in [{lo}, {hi}]"))
}

/// An argument that is not a known option: the input path the first time, an error otherwise.
fn positional(arg: &str, path: &mut Option<String>) -> Result<(), String> {
    if arg.starts_with("--") {
        return Err(format!("unknown option {arg}"));
    }
    if path.is_some() {
        return Err(format!("unexpected argument {arg}"));
    }
    *path = Some(arg.to_string());
    Ok(())
}

/// Writes `files` into `dir` (created if missing).
fn write_files(dir: &std::path::Path, files: &[ExportFile]) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for f in files {
        let path = dir.join(&f.name);
        std::fs::write(&path, &f.bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
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

/// The reference surface in a file (or a sample).
fn read_reference(path: &str) -> Result<Reference, String> {
    Ok(load(path)?.surface)
}

/// One JSON object: counts after triangulation and welding (of a B-spline: its tessellation),
/// and the mean curvature (jet-fitted on a mesh, exact on a B-spline, at the vertices); for a
/// B-spline also its degrees, control grid, domain and the ranges of H and K.
fn info(path: &str) -> Result<String, String> {
    let loaded = load(path)?;
    let field = loaded.surface.curvature(&JetParams::default(), &mut ignore).map_err(|_| "curvature computation was cancelled".to_string())?;
    let s = &loaded.info.stats;
    let c = &field.summary;
    let mut json = serde_json::json!({
        "vertices": s.vertices,
        "faces": s.faces,
        "boundary_loops": s.boundary_loops,
        "non_manifold_edges": s.non_manifold_edges,
        "bbox_diagonal": loaded.info.bbox_diagonal,
        "mean_curvature": {"min": c.min_h, "max": c.max_h, "mean": c.mean_h},
        "h_changes_sign": c.h_changes_sign,
    });
    if let Some(b) = &loaded.info.bspline {
        json["bspline"] = serde_json::json!({
            "degree": b.degree,
            "control_points": b.control,
            "domain": b.domain,
            "rational": b.rational,
            "tessellation": b.tessellation,
            "mean_curvature": {"min": b.mean_curvature[0], "max": b.mean_curvature[1]},
            "gauss_curvature": {"min": b.gauss_curvature[0], "max": b.gauss_curvature[1]},
        });
    }
    Ok(json.to_string())
}
