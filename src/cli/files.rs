//! Reading the input and writing the files: a bad `--out` is found before any work.

use std::io::Read;
use std::path::Path;

use spherical_faces::export::rhino::RHINO_MODEL_FILE;
use spherical_faces::export::{ExportFile, Report};
use spherical_faces::import::MAX_BYTES;
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::samples::Sample;
use spherical_faces::text::printable;

use super::args::{Input, Output};
use super::outcome::Failure;
use super::rhino;

/// Loads a file or a sample the way the app does; the error names the file.
pub fn load(input: &Input) -> Result<Loaded, Failure> {
    let path = input.surface.as_str();
    if let Some(key) = path.strip_prefix("sample:") {
        let sample = Sample::from_key(key).ok_or_else(|| {
            let names: Vec<&str> = Sample::ALL.iter().map(|s| s.key()).collect();
            Failure::input(format!("sample:{key}: no such sample (samples: {})", names.join(", ")))
        })?;
        return Ok(Loaded::from_sample(sample));
    }
    let name = Path::new(path).file_name().map_or(path.into(), |n| n.to_string_lossy().into_owned());
    if rhino::is_3dm(path) {
        let (text, object_name, units) = rhino::convert(path, input.object)?;
        let name = format!("{name} ({object_name})");
        let mut loaded = Loaded::from_file(text.as_bytes(), &name).map_err(Failure::from)?;
        loaded.info.units = units;
        return Ok(loaded);
    }
    if input.object.is_some() {
        return Err(Failure::input("--object applies to .3dm files only"));
    }
    let bytes = read_input(path)?;
    Loaded::from_file(&bytes, &name).map_err(Failure::from)
}

/// The bytes of `path`, refused before reading when over [`MAX_BYTES`].
fn read_input(path: &str) -> Result<Vec<u8>, Failure> {
    let file = std::fs::File::open(path).map_err(|e| Failure::input(format!("{path}: {e}")))?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let too_large = |n: u64| Failure::input(format!("{path}: {n} bytes exceed the limit of {MAX_BYTES} ({} MiB)", MAX_BYTES >> 20));
    if len > MAX_BYTES as u64 {
        return Err(too_large(len));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(MAX_BYTES as u64 + 1).read_to_end(&mut bytes).map_err(|e| Failure::input(format!("{path}: {e}")))?;
    if bytes.len() > MAX_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// Creates `dir` and proves it writable before any work, so a bad `--out` loses nothing.
pub fn check_output(output: &Output) -> Result<(), Failure> {
    let dir = &output.out;
    let bad = |e: std::io::Error| Failure::output(format!("{}: cannot write there: {e}", dir.display()));
    std::fs::create_dir_all(dir).map_err(bad)?;
    let probe = dir.join(".spherical-faces-write-test");
    std::fs::write(&probe, b"").map_err(bad)?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Writes `files` into `dir` and prints the report's warnings.
pub fn write_files(output: &Output, files: &[ExportFile], report: &Report) -> Result<(), Failure> {
    for f in files.iter().filter(|f| output.wants(&f.name) && f.name != RHINO_MODEL_FILE) {
        let path = output.out.join(&f.name);
        std::fs::write(&path, &f.bytes).map_err(|e| Failure::output(format!("{}: {e}", path.display())))?;
    }
    if let Some(model) = files.iter().find(|f| f.name == RHINO_MODEL_FILE && output.wants(&f.name)) {
        rhino::write(&output.out, &model.bytes)?;
    }
    for w in &report.warnings {
        eprintln!("warning: {}", printable(w));
    }
    Ok(())
}
