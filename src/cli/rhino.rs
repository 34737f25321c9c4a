//! Rhino .3dm files, read by the rhino3dm package (OpenNURBS in wasm) under Node: the same
//! converter the app loads in the browser (`www/rhino3dm/convert.mjs`).

use super::outcome::Failure;
use spherical_faces::units::Units;
use std::process::Command;

/// The converter script: `SF_RHINO3DM_CLI`, else the one in this source tree.
fn script() -> String {
    std::env::var("SF_RHINO3DM_CLI").unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/www/rhino3dm/cli.mjs").into())
}

pub fn is_3dm(path: &str) -> bool {
    path.to_ascii_lowercase().ends_with(".3dm")
}

fn how_to() -> String {
    format!(
        "reading .3dm needs Node.js ≥ 20 and the rhino3dm package: run `npm ci` in {}; or convert by hand with \
         `node {} FILE.3dm --out FILE.json` (a NURBS surface) and open the .json",
        std::path::Path::new(&script()).parent().map_or(".".into(), |p| p.display().to_string()),
        script()
    )
}

fn node(args: &[&str]) -> Result<Vec<u8>, Failure> {
    let out = Command::new("node").arg(script()).args(args).output().map_err(|e| Failure::input(format!("node: {e}; {}", how_to())))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let first = err.lines().find(|l| !l.trim().is_empty()).unwrap_or("the converter failed");
        let hint = if first.contains("npm ci") || first.contains("Cannot find") { format!(" ({})", how_to()) } else { String::new() };
        return Err(Failure::input(format!("{first}{hint}")));
    }
    Ok(out.stdout)
}

/// Writes `panels.3dm` into `dir` from its model (`www/rhino3dm/write-cli.mjs`).
pub fn write(dir: &std::path::Path, model: &[u8]) -> Result<(), Failure> {
    let writer = std::path::Path::new(&script()).with_file_name("write-cli.mjs");
    let (json, out) = (dir.join(".panels.3dm.json"), dir.join("panels.3dm"));
    std::fs::write(&json, model).map_err(|e| Failure::output(format!("{}: {e}", json.display())))?;
    let done = Command::new("node").arg(&writer).arg(&json).arg(&out).output();
    let _ = std::fs::remove_file(&json);
    let why = match done {
        Ok(o) if o.status.success() => return Ok(()),
        Ok(o) => String::from_utf8_lossy(&o.stderr).lines().find(|l| !l.trim().is_empty()).unwrap_or("the writer failed").to_string(),
        Err(e) => format!("node: {e}"),
    };
    Err(Failure::output(format!(
        "{}: {why}; the other files are written (writing .3dm needs Node.js ≥ 20 and `npm ci` in {}; or leave it out with --formats)",
        out.display(),
        writer.parent().map_or(".".into(), |p| p.display().to_string())
    )))
}

/// `info --list-objects`: the converter's object list, one JSON object per line.
pub fn list(path: &str) -> Result<String, Failure> {
    let out = node(&[path, "--list"])?;
    Ok(String::from_utf8_lossy(&out).trim_end().to_string())
}

/// The chosen object as our B-spline JSON or OBJ text, its description, and the file's
/// model unit when it names one of ours.
pub fn convert(path: &str, object: Option<usize>) -> Result<(String, String, Option<Units>), Failure> {
    let listing = list(path)?;
    let objects: Vec<serde_json::Value> = listing.lines().filter_map(|l| serde_json::from_str(l).ok()).collect();
    let pick = match object {
        Some(k) => objects
            .iter()
            .find(|o| o["index"].as_u64() == Some(k as u64))
            .ok_or_else(|| Failure::input(format!("{path}: no object {k} (objects: {})", summary(&objects))))?,
        None => objects
            .iter()
            .find(|o| o["kind"] == "surface")
            .or_else(|| objects.iter().find(|o| o["kind"] == "mesh"))
            .ok_or_else(|| Failure::input(format!("{path}: no NURBS surface or mesh")))?,
    };
    let index = pick["index"].as_u64().unwrap_or(0).to_string();
    if object.is_none() && objects.len() > 1 {
        eprintln!("note: {path} holds {} objects ({}); using object {index}, pick another with --object K", objects.len(), summary(&objects));
    }
    let text = String::from_utf8(node(&[path, "--object", &index])?).map_err(|e| Failure::input(format!("{path}: {e}")))?;
    let name = pick["name"].as_str().filter(|n| !n.is_empty()).map_or(format!("object {index}"), str::to_string);
    let units = pick["units"].as_str().and_then(Units::from_name);
    Ok((text, name, units))
}

fn summary(objects: &[serde_json::Value]) -> String {
    objects
        .iter()
        .map(|o| format!("{}: {} {}", o["index"], o["kind"].as_str().unwrap_or("?"), o["name"].as_str().unwrap_or("")).trim_end().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}
