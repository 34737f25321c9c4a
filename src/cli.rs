//! The native command line over the same pipeline as the browser app (see `main.rs`), on clap.
//!
//! Conventions: `--help` per command, `--version`; results on stdout, warnings and a live
//! progress line on stderr (on a terminal a live line, elsewhere JSON lines once a second after
//! the first second; never with `--quiet`); an error
//! is one line on stderr (one JSON object with `--json`). Exit codes: see [`EXIT_CODES`].

use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use spherical_faces::congruence::central_spheres::JetParams;
use spherical_faces::export::rhino::RHINO_MODEL_FILE;
use spherical_faces::export::{ExportFile, Report};
use spherical_faces::import::MAX_BYTES;
use spherical_faces::panels::edge_arcs::EdgeArcs;
use spherical_faces::panels::moulds::{Fabrication, MouldOutcome, MouldTarget, DEFAULT_MOULD_TOLERANCE};
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::pipeline::stages;
use spherical_faces::progress::{Clock, Progress};
use spherical_faces::remeshing::{Sizing, DEFAULT_EPSILON, MAX_FACES, MIN_FACES};
use spherical_faces::samples::Sample;
use spherical_faces::sq::params::{ParamRange, RadiusStart, SqParams, Until, ALPHA_RANGE, FACES_RANGE, GRID_RANGE, RECOMPUTE_RANGE, THETA_RANGE};
use spherical_faces::sq::report::SqSection;
use spherical_faces::sq::SqEvent;
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_adapted::StAdaptedEvent;
use spherical_faces::st_support::StSupportParams;
use spherical_faces::text::printable;
use spherical_faces::units::{format_length, Length, Units};

const EXIT_CODES: &str = "Exit codes: 0 done; 1 the output could not be written; 2 bad arguments, bad input, or a \
refusal (the surface does not suit the method); 3 the files are written but the result misses a guarantee of its method \
(report.json: meets_guarantees false, with each guarantee's figure). Errors are one line on stderr, or one JSON object \
{\"error\": ..., \"exit_code\": ...} with --json.";

const SURFACE_HELP: &str = "A mesh (.obj, .gltf, .glb), a B-spline surface (.json, the paper authors' format), a \
Rhino file (.3dm, read with the rhino3dm package through Node) or sample:NAME, a built-in sample (dome, torus, \
sphere-cap, wave-roof, vault)";

#[derive(Parser)]
#[command(name = "spherical-faces", version, about = "Approximates a free-form surface by a mesh of spherical panels \
(Approximation by Meshes with Spherical Faces).", after_help = EXIT_CODES)]
struct Cli {
    /// No progress on stderr (a live line on a terminal, otherwise one JSON object a second).
    #[arg(long, short, global = true)]
    quiet: bool,
    /// Errors as one JSON object on stderr, for scripts.
    #[arg(long, global = true)]
    json: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Counts after welding, mean curvature (jet-fitted on a mesh, exact on a B-spline) and, for a
    /// B-spline, its degrees, control grid, domain and curvature ranges: one JSON object. With
    /// --list-objects, the objects of a .3dm file instead.
    #[command(after_help = EXIT_CODES)]
    Info {
        #[command(flatten)]
        input: Input,
        /// List the objects of a .3dm file (one JSON object per line) and stop.
        #[arg(long)]
        list_objects: bool,
    },
    /// ST mesh with adapted face size (paper Sec. 3): remesh with the sizing field of tolerance E,
    /// or uniformly to about N faces, then optimize the face spheres.
    #[command(after_help = EXIT_CODES)]
    St {
        #[command(flatten)]
        input: Input,
        /// Sizing-field tolerance ε, relative to the bounding-box diagonal (default 0.0004).
        #[arg(long, value_name = "E", value_parser = open_fraction, conflicts_with = "faces")]
        epsilon: Option<f64>,
        /// Remesh uniformly to about N faces instead.
        #[arg(long, value_name = "N", value_parser = face_count)]
        faces: Option<usize>,
        /// Panel edges: (a) intersection circles of adjacent spheres (the bisecting plane where
        /// one would cross a panel's other arcs), (b) spheres cut by the bisecting face planes.
        #[arg(long, value_name = "a|b", default_value = "a", value_parser = variant)]
        variant: EdgeArcs,
        /// After optimizing, move the panels onto fewer moulds (keeping the largest kink within
        /// 1.2× and the panels within 2ε of the reference), then give every panel its mould's
        /// radius exactly (the schedule's `mould_snapped`).
        #[arg(long)]
        optimize_moulds: bool,
        #[command(flatten)]
        fabrication: FabricationArgs,
        #[command(flatten)]
        output: Output,
    },
    /// ST mesh with support structure (paper Sec. 4): Ω, face spheres orthogonal to it, node axes,
    /// support elements and panels.
    #[command(name = "st-support", after_help = EXIT_CODES)]
    StSupport {
        #[command(flatten)]
        input: Input,
        /// Optimize R² (or d) of Ω for the smallest kinks (Fig. 16).
        #[arg(long)]
        optimize_radius: bool,
        /// Depth of the support elements, relative to the diagonal.
        #[arg(long, value_name = "D", default_value_t = StSupportParams::default().support_depth, value_parser = fraction_in::<0, 1>)]
        depth: f64,
        /// Length of the drawn node axes, relative to the diagonal.
        #[arg(long, value_name = "L", default_value_t = StSupportParams::default().axis_length, value_parser = fraction_in::<0, 10>)]
        axis_length: f64,
        /// Radii closer than T × the diagonal count as one in the schedule.
        #[arg(long, value_name = "T", default_value_t = StSupportParams::default().radius_tolerance, value_parser = radius_tolerance)]
        radius_tolerance: f64,
        /// Remesh first with the sizing field of the local spheres orthogonal to Ω (Fig. 16,
        /// bottom).
        #[arg(long, conflicts_with = "faces")]
        adaptive: bool,
        /// The adaptive sizing's tolerance, relative to the diagonal (default 0.0004).
        #[arg(long, value_name = "E", value_parser = open_fraction, requires = "adaptive")]
        epsilon: Option<f64>,
        /// Remesh first uniformly to about N faces.
        #[arg(long, value_name = "N", value_parser = face_count)]
        faces: Option<usize>,
        /// Move the vertices so that every panel has the radius of one of fewer moulds exactly,
        /// every face sphere still orthogonal to Ω (the schedule's `mould_snapped`).
        #[arg(long)]
        optimize_moulds: bool,
        /// The panels' promised largest distance to the reference, relative to the diagonal (a
        /// miss exits with 3).
        #[arg(long, value_name = "D", default_value_t = spherical_faces::panels::buildability::DEFAULT_MAX_DISTANCE, value_parser = max_distance)]
        max_distance: f64,
        #[command(flatten)]
        fabrication: FabricationArgs,
        #[command(flatten)]
        output: Output,
    },
    /// SQ mesh with support structure (paper Sec. 5) on a B-spline surface: radius function, line
    /// congruence and torsal optimization (5.1); quad mesh along the torsal cross field, Q′, the
    /// final sphere optimization, panels, support structure and node axes (5.2).
    #[command(after_help = EXIT_CODES)]
    Sq {
        #[command(flatten)]
        input: Input,
        /// Largest angle between the lines and the normals (degrees).
        #[arg(long, value_name = "DEG", default_value_t = SqParams::default().theta_deg, value_parser = in_range_f64(THETA_RANGE))]
        theta: f64,
        /// Smallest angle between the torsal planes (degrees).
        #[arg(long, value_name = "DEG", default_value_t = SqParams::default().alpha_deg, value_parser = in_range_f64(ALPHA_RANGE))]
        alpha: f64,
        /// Points per direction of the sampling grid G.
        #[arg(long, value_name = "N", default_value_t = SqParams::default().grid, value_parser = in_range_usize(GRID_RANGE))]
        grid: usize,
        /// Recompute the exact torsal directions every K iterations.
        #[arg(long, value_name = "K", default_value_t = SqParams::default().recompute_every, value_parser = in_range_usize(RECOMPUTE_RANGE))]
        rs: usize,
        /// About this many quads.
        #[arg(long, value_name = "N", default_value_t = SqParams::default().faces, value_parser = in_range_usize(FACES_RANGE))]
        faces: usize,
        /// Stop after this stage.
        #[arg(long, value_name = "STAGE", default_value = "final", value_parser = until)]
        until: Until,
        /// The starting sphere congruence: auto (constant radii, then the central congruence
        /// when that SQ mesh misses a guarantee, keeping the result that misses fewer; constant
        /// radii alone where H changes sign), central (r = 1/H) or constant (the normal
        /// congruence, whose torsal directions are the principal directions).
        #[arg(long, value_name = "START", default_value = "auto", value_parser = radius_start)]
        start: RadiusStart,
        /// Depth of the support elements, relative to the diagonal.
        #[arg(long, value_name = "D", default_value_t = SqParams::default().support_depth, value_parser = fraction_in::<0, 1>)]
        depth: f64,
        /// Move the exact SQ mesh so that every panel has the radius of one of fewer moulds
        /// exactly, keeping exactness, θ and α (the schedule's `mould_snapped`).
        #[arg(long)]
        optimize_moulds: bool,
        /// The panels' promised largest distance to the reference, relative to the diagonal (a
        /// miss exits with 3).
        #[arg(long, value_name = "D", default_value_t = spherical_faces::panels::buildability::DEFAULT_MAX_DISTANCE, value_parser = max_distance)]
        max_distance: f64,
        #[command(flatten)]
        fabrication: FabricationArgs,
        #[command(flatten)]
        output: Output,
    },
}

#[derive(Args)]
struct Input {
    #[arg(help = SURFACE_HELP, value_name = "SURFACE")]
    surface: String,
    /// In a .3dm file with several objects, the one to take (its index in `info --list-objects`);
    /// default: the first NURBS surface, else the first mesh.
    #[arg(long, value_name = "K")]
    object: Option<usize>,
}

/// The model unit and the moulds the panels are fitted to.
#[derive(Args)]
struct FabricationArgs {
    /// What one model unit is: m, cm, mm, ft or in (default: the .3dm file's unit system, else m).
    #[arg(long, value_name = "UNIT", value_parser = units)]
    units: Option<Units>,
    /// The fewest moulds (radii the panels share) within this fit tolerance δ, e.g. 2mm or
    /// 0.1in (a bare number is in model units). Default 2mm.
    #[arg(long, value_name = "LENGTH", value_parser = length, conflicts_with = "moulds")]
    mould_tolerance: Option<Length>,
    /// Exactly this many moulds at most, at the smallest fit tolerance that allows it.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    moulds: Option<u32>,
}

impl FabricationArgs {
    fn fabrication(&self) -> Fabrication {
        let moulds = match (self.moulds, self.mould_tolerance) {
            (Some(k), _) => MouldTarget::Count(k as usize),
            (None, Some(t)) => MouldTarget::Tolerance(t),
            (None, None) => MouldTarget::Tolerance(DEFAULT_MOULD_TOLERANCE),
        };
        Fabrication { units: self.units.unwrap_or_default(), moulds }
    }

    /// [`Self::fabrication`] in the file's unit when `--units` is not given.
    fn fabrication_for(&self, loaded: &Loaded) -> Fabrication {
        let f = self.fabrication();
        match (self.units, loaded.info.units) {
            (None, Some(units)) => Fabrication { units, ..f },
            _ => f,
        }
    }
}

#[derive(Args)]
struct Output {
    /// The folder to write into (created if missing; checked before any work).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// The files to write, comma-separated: glb (panels.glb), obj (panels.obj), schedule
    /// (panels.csv, panels.json, moulds.csv, support.csv), step (panels.step) and 3dm
    /// (panels.3dm, written by the rhino3dm package through Node), both with every panel and
    /// support element an exact rational NURBS surface, or all; report.json is always written
    #[arg(long, value_name = "LIST", value_enum, value_delimiter = ',', default_value = "all")]
    formats: Vec<FileFormat>,
}

/// A kind of file the panel methods write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum FileFormat {
    All,
    Glb,
    Obj,
    Schedule,
    Step,
    #[value(name = "3dm")]
    Rhino,
}

impl FileFormat {
    /// The kind of an export file; None for those always written (report.json, the congruence).
    fn of(name: &str) -> Option<FileFormat> {
        match name {
            "panels.glb" => Some(FileFormat::Glb),
            "panels.obj" => Some(FileFormat::Obj),
            "panels.step" => Some(FileFormat::Step),
            RHINO_MODEL_FILE => Some(FileFormat::Rhino),
            "panels.csv" | "panels.json" | "moulds.csv" | "support.csv" => Some(FileFormat::Schedule),
            _ => None,
        }
    }
}

impl Output {
    fn wants(&self, name: &str) -> bool {
        FileFormat::of(name).is_none_or(|f| self.formats.iter().any(|&w| w == f || w == FileFormat::All))
    }
}

/// Why a command failed: the message and the exit code.
struct Failure {
    message: String,
    code: u8,
}

impl Failure {
    fn input(message: impl Into<String>) -> Self {
        Self { message: message.into(), code: 2 }
    }

    fn output(message: impl Into<String>) -> Self {
        Self { message: message.into(), code: 1 }
    }

    /// The files are written, but the result misses a guarantee of its method: the misses, for
    /// stderr.
    fn missed(report: &Report) -> Self {
        Self {
            message: format!("the result misses its guarantees: {}", report.failure_text()),
            code: spherical_faces::guarantees::MISSED_GUARANTEES_EXIT_CODE,
        }
    }
}

impl<E: std::fmt::Display> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure::input(e.to_string())
    }
}

pub fn main() -> ExitCode {
    let json = std::env::args().any(|a| a == "--json");
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                print!("{}", e.render());
                return ExitCode::SUCCESS;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                eprint!("{}", e.render());
                return ExitCode::from(2);
            }
            // One line: clap's message up to its usage, without its prefix, and where to look.
            let text = e.render().to_string();
            let message: Vec<&str> = text
                .lines()
                .map(str::trim)
                .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
                .filter(|l| !l.is_empty() && !l.starts_with("tip:"))
                .collect();
            let message = message.join(" ");
            return fail(json, &Failure::input(format!("{} (see --help)", message.trim_start_matches("error: "))));
        }
    };
    let mode = match (cli.quiet, std::io::stderr().is_terminal()) {
        (true, _) => ProgressMode::Off,
        (false, true) => ProgressMode::Line,
        (false, false) => ProgressMode::JsonLines,
    };
    let mut progress = ProgressLine::new(mode);
    let result = match cli.command {
        Command::Info { input, list_objects } => info(&input, list_objects),
        Command::St { input, epsilon, faces, variant, optimize_moulds, fabrication, output } => {
            let sizing = match faces {
                Some(n) => Sizing::UniformFaces(n),
                None => Sizing::Adaptive { epsilon: epsilon.unwrap_or(DEFAULT_EPSILON) },
            };
            st(&input, StAdaptedParams { sizing, variant, optimize_moulds, ..StAdaptedParams::default() }, &fabrication, &output, &mut progress)
        }
        Command::StSupport {
            input,
            optimize_radius,
            depth,
            axis_length,
            radius_tolerance,
            adaptive,
            epsilon,
            faces,
            optimize_moulds,
            max_distance,
            fabrication,
            output,
        } => {
            let remesh = match (adaptive, faces) {
                (true, _) => Sizing::Adaptive { epsilon: epsilon.unwrap_or(DEFAULT_EPSILON) },
                (false, Some(n)) => Sizing::UniformFaces(n),
                (false, None) => Sizing::None,
            };
            let params = StSupportParams {
                optimize_radius,
                support_depth: depth,
                axis_length,
                radius_tolerance,
                remesh,
                optimize_moulds,
                max_distance,
                ..StSupportParams::default()
            };
            st_support(&input, params, &fabrication, &output, &mut progress)
        }
        Command::Sq { input, theta, alpha, grid, rs, faces, until, start, depth, optimize_moulds, max_distance, fabrication, output } => {
            let params = SqParams {
                theta_deg: theta,
                alpha_deg: alpha,
                grid,
                recompute_every: rs,
                faces,
                until,
                start,
                support_depth: depth,
                optimize_moulds,
                max_distance,
                ..SqParams::default()
            };
            sq(&input, params, &fabrication, &output, &mut progress)
        }
    };
    progress.clear();
    match result {
        Ok(out) => {
            println!("{out}");
            ExitCode::SUCCESS
        }
        Err(f) => fail(json, &f),
    }
}

/// Prints the failure (one line, or one JSON object) and gives its exit code.
fn fail(json: bool, f: &Failure) -> ExitCode {
    let message = printable(&f.message);
    if json {
        eprintln!("{}", serde_json::json!({ "error": message, "exit_code": f.code }));
    } else {
        eprintln!("error: {message}");
    }
    ExitCode::from(f.code)
}

/// How progress goes to stderr.
#[derive(Clone, Copy, PartialEq, Eq)]
enum ProgressMode {
    Off,
    /// A live line "step done/total" on a terminal, redrawn at most every 100 ms.
    Line,
    /// Not a terminal: one JSON object a line, `{"progress": {"step", "done", "total"}}`, at most
    /// one a second, the first after a second (a quick run or refusal prints none).
    JsonLines,
}

/// The progress on stderr.
struct ProgressLine {
    mode: ProgressMode,
    started: std::time::Instant,
    last: Option<std::time::Instant>,
    drawn: bool,
}

impl ProgressLine {
    fn new(mode: ProgressMode) -> Self {
        Self { mode, started: std::time::Instant::now(), last: None, drawn: false }
    }

    fn show(&mut self, p: &Progress) {
        let since = |t: Option<std::time::Instant>| t.map_or(u128::MAX, |t| t.elapsed().as_millis());
        match self.mode {
            ProgressMode::Off => return,
            ProgressMode::JsonLines => {
                if self.started.elapsed().as_millis() >= 1000 && since(self.last) >= 1000 {
                    self.last = Some(std::time::Instant::now());
                    eprintln!("{}", serde_json::json!({ "progress": { "step": p.step, "done": p.done, "total": p.total } }));
                }
                return;
            }
            ProgressMode::Line if since(self.last) < 100 => return,
            ProgressMode::Line => {}
        }
        self.last = Some(std::time::Instant::now());
        let text = if p.total > 0 { format!("{} {}/{}", p.step, p.done, p.total) } else { p.step.to_string() };
        eprint!("\r{text:<60}");
        let _ = std::io::stderr().flush();
        self.drawn = true;
    }

    fn clear(&mut self) {
        if self.drawn {
            eprint!("\r{:<60}\r", "");
            self.drawn = false;
        }
    }
}

/// Loads a file or a sample the way the app does; the error names the file.
fn load(input: &Input) -> Result<Loaded, Failure> {
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
fn check_output(output: &Output) -> Result<(), Failure> {
    let dir = &output.out;
    let bad = |e: std::io::Error| Failure::output(format!("{}: cannot write there: {e}", dir.display()));
    std::fs::create_dir_all(dir).map_err(bad)?;
    let probe = dir.join(".spherical-faces-write-test");
    std::fs::write(&probe, b"").map_err(bad)?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Writes `files` into `dir` and prints the report's warnings.
fn write_files(output: &Output, files: &[ExportFile], report: &Report) -> Result<(), Failure> {
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

/// `st-support SURFACE [options] --out DIR`.
fn st_support(
    input: &Input,
    mut params: StSupportParams,
    f: &FabricationArgs,
    output: &Output,
    progress: &mut ProgressLine,
) -> Result<String, Failure> {
    check_output(output)?;
    let clock = Clock::native();
    let t0 = clock.now();
    let loaded = load(input)?;
    params.fabrication = f.fabrication_for(&loaded);
    let reference = loaded.surface;
    let import_ms = clock.now() - t0;
    let t1 = clock.now();
    let mut on_progress = |p: Progress| {
        progress.show(&p);
        Ok(())
    };
    reference.curvature(&params.jet, &mut on_progress).map_err(|_| Failure::input("cancelled"))?;
    let curvature_ms = clock.now() - t1;
    let mut result = spherical_faces::st_support::compute(&reference, &params, clock, &mut on_progress)
        .map_err(|e| Failure::input(format!("{}: {e}", input.surface)))?;
    // The report's timings include reading and curvature, which the CLI did itself.
    result.timings_ms.insert(0, ("curvature".into(), curvature_ms));
    result.timings_ms.insert(0, ("import".into(), import_ms));
    let (report, files) = stages::st_support::export(&reference, &result, &params, clock);
    progress.clear();
    write_files(output, &files, &report)?;
    let refused = MouldOutcome::section(result.moulds.as_ref()).refused();
    let summary = format!(
        "wrote {} panels to {} (max kink {:.3}°, max distance to reference {})",
        result.panels.len(),
        output.out.display(),
        result.metrics.max_kink_angle_deg,
        report.metrics.as_ref().map_or("–".into(), |m| m.max_distance_text())
    );
    verdict(with_refusal(with_moulds(summary, &report), refused), &report)
}

/// `summary`, then why no round toward fewer moulds was kept, if so.
fn with_refusal(summary: String, refused: Option<String>) -> String {
    match refused {
        Some(why) => format!("{summary}; {why}"),
        None => summary,
    }
}

/// `summary`, then the exact surfaces of `panels.step` and `panels.3dm` and the moulds of the report: how many,
/// within what, in model units.
fn with_moulds(summary: String, report: &Report) -> String {
    let summary = match &report.exact_surfaces {
        Some(e) => format!("{summary}; CAD surfaces (panels.step, panels.3dm): {}", e.describe()),
        None => summary,
    };
    match &report.moulds {
        Some(m) => format!(
            "{summary}; {} mould{} within {} (largest fit deviation {}; moulds.csv); {}",
            m.count,
            if m.count == 1 { "" } else { "s" },
            format_length(m.tolerance, m.units),
            format_length(m.max_deviation, m.units),
            m.snap.describe(report.output.panels, m.units),
        ),
        None => summary,
    }
}

/// `st SURFACE [--epsilon E | --faces N] [--variant a|b] --out DIR`.
fn st(input: &Input, mut params: StAdaptedParams, f: &FabricationArgs, output: &Output, progress: &mut ProgressLine) -> Result<String, Failure> {
    check_output(output)?;
    let loaded = load(input)?;
    params.fabrication = f.fabrication_for(&loaded);
    let reference = loaded.surface;
    let clock = Clock::native();
    let result = spherical_faces::st_adapted::compute(&reference, &params, clock, &mut |e| {
        match e {
            StAdaptedEvent::Progress(p) | StAdaptedEvent::Iteration { progress: p, .. } => progress.show(&p),
            _ => {}
        }
        Ok(())
    })
    .map_err(|e| Failure::input(format!("{}: {e}", input.surface)))?;
    let (report, files) = stages::st_adapted::export(&reference, &result, &params, clock);
    progress.clear();
    write_files(output, &files, &report)?;
    let summary = format!(
        "wrote {} panels to {} (kink mean {:.3}°, max {:.3}°; max distance to reference {}; {} folded faces)",
        report.output.panels,
        output.out.display(),
        result.metrics.mean_kink_angle_deg,
        result.metrics.max_kink_angle_deg,
        report.metrics.as_ref().map_or("–".into(), |m| m.max_distance_text()),
        result.metrics.flipped_faces
    );
    verdict(with_moulds(summary, &report), &report)
}

/// The summary when the report meets its guarantees; else the summary (what was written) goes
/// to stdout at once and the failure, with exit code 3, to stderr.
fn verdict(summary: String, report: &Report) -> Result<String, Failure> {
    if report.meets_guarantees == Some(true) {
        return Ok(summary);
    }
    println!("{summary}");
    Err(Failure::missed(report))
}

/// `sq SURFACE [options] --out DIR`.
fn sq(input: &Input, mut params: SqParams, f: &FabricationArgs, output: &Output, progress: &mut ProgressLine) -> Result<String, Failure> {
    check_output(output)?;
    let loaded = load(input)?;
    params.fabrication = f.fabrication_for(&loaded);
    let reference = loaded.surface;
    let clock = Clock::native();
    let result = spherical_faces::sq::compute(&reference, &params, clock, &mut |e| {
        if let SqEvent::Progress(p) = e {
            progress.show(&p);
        }
        Ok(())
    })
    .map_err(|e| Failure::input(format!("{}: {e}", input.surface)))?;
    let segments = spherical_faces::sq::congruence_file::CongruenceSegments::of(&result.congruence);
    let (report, files) = stages::sq::export(&reference, &result, &params, &segments, clock);
    progress.clear();
    write_files(output, &files, &report)?;
    let sq: SqSection = report.section().expect("the SQ report has its section");
    let panels = report.metrics.clone().unwrap_or_default();
    let quads = sq.quad_mesh.as_ref();
    let summary = match (params.until, &sq.sq_mesh) {
        (Until::Final, Some(mesh)) => {
            let f = &mesh.figures;
            format!(
                "wrote an SQ mesh of {} spherical quad panels with support structure to {}: vertex–sphere residual {:.1e}, centre-face \
                 planarity {:.1e}, torsal-plane residual {:.1e}; node axes within {:.2}° of the normals (θ = {}°); support planes meet at \
                 ≥ {:.2}° (α = {}°); max distance to the reference {}; edges off the torsal directions by {:.2}° on \
                 average; {} distinct radii; {:.0} ms.",
                report.output.panels,
                output.out.display(),
                f.max_vertex_sphere_residual,
                f.max_centre_face_planarity,
                f.max_torsal_plane_residual,
                f.max_axis_normal_angle_deg,
                params.theta_deg,
                f.min_torsal_plane_angle_deg,
                params.alpha_deg,
                panels.max_distance_text(),
                quads.map_or(f64::NAN, |q| q.mean_edge_torsal_angle_deg),
                panels.distinct_radii,
                report.timings_ms.get("total").copied().unwrap_or(0.0),
            )
        }
        (Until::Final | Until::Remesh, _) => format!(
            "wrote the quad mesh Q′ ({} quads, {:.1} % of the patch, edges off the torsal directions by {:.2}° on average, at most {:.2}°) \
             and the congruence to {}.",
            report.output.faces,
            100.0 * quads.map_or(f64::NAN, |q| q.coverage),
            quads.map_or(f64::NAN, |q| q.mean_edge_torsal_angle_deg),
            quads.map_or(f64::NAN, |q| q.max_edge_torsal_angle_deg),
            output.out.display()
        ),
        (Until::Congruence, _) => {
            let c = &sq.congruence;
            format!(
                "wrote the congruence of a {n}×{n} grid to {} (lines within {:.2}° of the normals, θ = {}°; torsal planes meet at ≥ {:.2}°, \
                 α = {}°; {} quads without real torsal directions; E_LC per term {:.2e}).",
                output.out.display(),
                c.figures.max_line_normal_angle_deg,
                params.theta_deg,
                c.figures.min_torsal_plane_angle_deg,
                params.alpha_deg,
                c.figures.quads_without_real_torsal_directions,
                c.lc_residual,
                n = params.grid,
            )
        }
    };
    let refused = sq.sq_mesh.as_ref().and_then(|m| m.moulds.refused());
    verdict(with_refusal(with_moulds(summary, &report), refused), &report)
}

/// One JSON object: counts after triangulation and welding (of a B-spline: its tessellation),
/// and the mean curvature (jet-fitted on a mesh, exact on a B-spline, at the vertices); for a
/// B-spline also its degrees, control grid, domain and the ranges of H and K.
fn info(input: &Input, list_objects: bool) -> Result<String, Failure> {
    if list_objects {
        if !rhino::is_3dm(&input.surface) {
            return Err(Failure::input("--list-objects applies to .3dm files only"));
        }
        return rhino::list(&input.surface);
    }
    let loaded = load(input)?;
    let field = loaded.surface.curvature(&JetParams::default(), &mut |_| Ok(())).map_err(|_| Failure::input("cancelled"))?;
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

/// Rhino .3dm files, read by the rhino3dm package (OpenNURBS in wasm) under Node: the same
/// converter the app loads in the browser (`www/rhino3dm/convert.mjs`).
mod rhino {
    use super::Failure;
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
}

// --- value parsers: every count and number the user types is checked here ------------------------

fn number(s: &str) -> Result<f64, String> {
    s.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("'{s}' is not a number"))
}

/// A number in [LO, HI].
fn fraction_in<const LO: u32, const HI: u32>(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if (LO as f64..=HI as f64).contains(&x) {
        Ok(x)
    } else {
        Err(format!("{x} is not in [{LO}, {HI}]"))
    }
}

/// ε: a number in (0, 1).
fn open_fraction(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if x > 0.0 && x < 1.0 {
        Ok(x)
    } else {
        Err(format!("{x} is not in (0, 1)"))
    }
}

fn units(s: &str) -> Result<Units, String> {
    s.parse().map_err(|e: spherical_faces::units::UnitsError| e.to_string())
}

fn length(s: &str) -> Result<Length, String> {
    s.parse().map_err(|e: spherical_faces::units::UnitsError| e.to_string())
}

fn radius_tolerance(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if (1e-9..=1.0).contains(&x) {
        Ok(x)
    } else {
        Err(format!("{x} is not in [1e-9, 1]"))
    }
}

/// A distance bound ([`spherical_faces::panels::buildability::check_max_distance`]).
fn max_distance(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    spherical_faces::panels::buildability::check_max_distance(x).map(|_| x)
}

/// A remesh's face count: [`MIN_FACES`] to [`MAX_FACES`], as in the design link and the app.
fn face_count(s: &str) -> Result<usize, String> {
    let n: usize = s.parse().map_err(|_| format!("'{s}' is not a whole number"))?;
    if (MIN_FACES..=MAX_FACES).contains(&n) {
        Ok(n)
    } else {
        Err(format!("{n} is not in [{MIN_FACES}, {MAX_FACES}]"))
    }
}

fn variant(s: &str) -> Result<EdgeArcs, String> {
    EdgeArcs::from_key(s).ok_or_else(|| format!("'{s}': expected a or b"))
}

fn radius_start(s: &str) -> Result<RadiusStart, String> {
    RadiusStart::from_key(s).ok_or_else(|| format!("'{s}': expected auto, central or constant"))
}

fn until(s: &str) -> Result<Until, String> {
    Until::from_key(s).ok_or_else(|| format!("'{s}': expected congruence, remesh or final"))
}

/// A number checked against its range (the method's own check, [`ParamRange::check`]).
fn in_range_f64(range: ParamRange<f64>) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |s| range.check(number(s)?).map_err(|e| e.to_string())
}

fn in_range_usize(range: ParamRange<usize>) -> impl Fn(&str) -> Result<usize, String> + Clone {
    move |s| {
        let n: usize = s.parse().map_err(|_| format!("'{s}' is not a whole number"))?;
        match range.check(n) {
            Err(_) if range == FACES_RANGE && n > range.hi => {
                Err(format!("{n} is more quads than SQ finishes within a minute and 1 GB; at most {}", range.hi))
            }
            checked => checked.map_err(|e| e.to_string()),
        }
    }
}
