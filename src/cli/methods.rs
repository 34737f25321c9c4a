//! One subcommand per method, each with its own flags (read into the method's parameters, each
//! checked against the range its `params.rs` gives), and one driver for them all: load, run the
//! method through the pipeline's seam, write the files, say what was written, exit 3 on a miss.

use clap::{Args, Subcommand};

use spherical_faces::congruence::central_spheres::JetParams;
use spherical_faces::congruence::support_structure::{AXIS_LENGTH_RANGE, SUPPORT_DEPTH_RANGE};
use spherical_faces::export::ExportFile;
use spherical_faces::panels::buildability::{DEFAULT_MAX_DISTANCE, MAX_DISTANCE_RANGE};
use spherical_faces::panels::edge_arcs::EdgeArcs;
use spherical_faces::panels::RADIUS_TOLERANCE_RANGE;
use spherical_faces::pipeline::fields::{Field, Part, StepProgress};
use spherical_faces::pipeline::method::{run, Method, Request};
use spherical_faces::pipeline::sink::Sink;
use spherical_faces::pipeline::stages::sq::SqStage;
use spherical_faces::pipeline::stages::st_adapted::StAdaptedStage;
use spherical_faces::pipeline::stages::st_support::StSupportStage;
use spherical_faces::pipeline::stages::StageError;
use spherical_faces::progress::Clock;
use spherical_faces::remeshing::{Sizing, DEFAULT_EPSILON, EPSILON_RANGE, FACES_RANGE};
use spherical_faces::sq::params::{self as sq, RadiusStart, SqParams, Until};
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_support::StSupportParams;

use super::args::{in_range_f64, in_range_usize, FabricationArgs, Input, Output};
use super::files::{check_output, load, write_files};
use super::outcome::{verdict, Failure, EXIT_CODES};
use super::progress::ProgressLine;

/// A method's own flags, read into its parameters.
pub trait MethodFlags: Args {
    type Method: Method;
    fn params(&self) -> <Self::Method as Method>::Params;
}

/// A method's subcommand: the input, the method's flags, the fabrication settings, the output.
#[derive(Args)]
pub struct MethodArgs<F: MethodFlags> {
    #[command(flatten)]
    input: Input,
    #[command(flatten)]
    flags: F,
    #[command(flatten)]
    fabrication: FabricationArgs,
    #[command(flatten)]
    output: Output,
}

/// The methods' subcommands, one line each.
#[derive(Subcommand)]
pub enum MethodCommand {
    /// ST mesh with adapted face size (paper Sec. 3): remesh with the sizing field of tolerance E,
    /// or uniformly to about N faces, then optimize the face spheres.
    #[command(name = StAdaptedStage::KEY, after_help = EXIT_CODES)]
    St(MethodArgs<StAdaptedFlags>),
    /// ST mesh with support structure (paper Sec. 4): Ω, face spheres orthogonal to it, node axes,
    /// support elements and panels.
    #[command(name = StSupportStage::KEY, after_help = EXIT_CODES)]
    StSupport(MethodArgs<StSupportFlags>),
    /// SQ mesh with support structure (paper Sec. 5) on a B-spline surface: radius function, line
    /// congruence and torsal optimization (5.1); quad mesh along the torsal cross field, Q′, the
    /// final sphere optimization, panels, support structure and node axes (5.2).
    #[command(name = SqStage::KEY, after_help = EXIT_CODES)]
    Sq(MethodArgs<SqFlags>),
}

impl MethodCommand {
    pub fn run(self, progress: &mut ProgressLine) -> Result<String, Failure> {
        match self {
            MethodCommand::St(a) => drive(a, progress),
            MethodCommand::StSupport(a) => drive(a, progress),
            MethodCommand::Sq(a) => drive(a, progress),
        }
    }
}

/// Where a method streams on the command line: progress to the progress line, files kept to be
/// written; no live snapshots.
struct Collect<'a> {
    progress: &'a mut ProgressLine,
    files: Vec<ExportFile>,
    clock: Clock,
}

impl Sink for Collect<'_> {
    fn progress(&mut self, p: StepProgress) {
        self.progress.show(&p.detail, p.iteration, p.total);
    }

    fn snapshot(&mut self, _part: Part, _iteration: u32, _fields: Vec<Field>) {}

    fn files(&mut self, files: Vec<ExportFile>) {
        self.files.extend(files);
    }

    fn cancel_requested(&mut self) -> bool {
        false
    }

    fn now_ms(&self) -> f64 {
        self.clock.now()
    }

    fn wants_snapshots(&self) -> bool {
        false
    }
}

/// `METHOD SURFACE [flags] --out DIR`: every method's one driver.
fn drive<F: MethodFlags>(a: MethodArgs<F>, progress: &mut ProgressLine) -> Result<String, Failure> {
    check_output(&a.output)?;
    let loaded = load(&a.input)?;
    let request = Request { params: a.flags.params(), fabrication: a.fabrication.fabrication_for(&loaded), jet: JetParams::default() };
    let reference = loaded.surface;
    let clock = Clock::native();
    let mut sink = Collect { progress, files: Vec::new(), clock };
    let (summary, computed) = run::<F::Method>(&reference, &request, clock, &mut sink).map_err(|e| match e {
        StageError::Cancelled => Failure::input("cancelled"),
        e => Failure::input(format!("{}: {e}", a.input.surface)),
    })?;
    let files = std::mem::take(&mut sink.files);
    progress.clear();
    let report = F::Method::report(&summary);
    write_files(&a.output, &files, report)?;
    verdict(F::Method::describe(&computed.result, report, &request, &a.output.out.display().to_string()), report)
}

/// The panels' promised distance to the reference, of the methods with support structure.
#[derive(Args)]
pub struct MaxDistance {
    /// The panels' promised largest distance to the reference, relative to the diagonal (a
    /// miss exits with 3).
    #[arg(long, value_name = "D", default_value_t = DEFAULT_MAX_DISTANCE, value_parser = in_range_f64(MAX_DISTANCE_RANGE))]
    max_distance: f64,
}

/// `st`'s flags.
#[derive(Args)]
pub struct StAdaptedFlags {
    /// Sizing-field tolerance ε, relative to the bounding-box diagonal (default 0.0004).
    #[arg(long, value_name = "E", value_parser = in_range_f64(EPSILON_RANGE), conflicts_with = "faces")]
    epsilon: Option<f64>,
    /// Remesh uniformly to about N faces instead.
    #[arg(long, value_name = "N", value_parser = in_range_usize(FACES_RANGE))]
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
}

impl MethodFlags for StAdaptedFlags {
    type Method = StAdaptedStage;

    fn params(&self) -> StAdaptedParams {
        let sizing = match self.faces {
            Some(n) => Sizing::UniformFaces(n),
            None => Sizing::Adaptive { epsilon: self.epsilon.unwrap_or(DEFAULT_EPSILON) },
        };
        StAdaptedParams { sizing, variant: self.variant, optimize_moulds: self.optimize_moulds, ..StAdaptedParams::default() }
    }
}

/// `st-support`'s flags.
#[derive(Args)]
pub struct StSupportFlags {
    /// Optimize R² (or d) of Ω for the smallest kinks (Fig. 16).
    #[arg(long)]
    optimize_radius: bool,
    /// Depth of the support elements, relative to the diagonal.
    #[arg(long, value_name = "D", default_value_t = StSupportParams::default().support_depth, value_parser = in_range_f64(SUPPORT_DEPTH_RANGE))]
    depth: f64,
    /// Length of the drawn node axes, relative to the diagonal.
    #[arg(long, value_name = "L", default_value_t = StSupportParams::default().axis_length, value_parser = in_range_f64(AXIS_LENGTH_RANGE))]
    axis_length: f64,
    /// Radii closer than T × the diagonal count as one in the schedule.
    #[arg(long, value_name = "T", default_value_t = StSupportParams::default().radius_tolerance, value_parser = in_range_f64(RADIUS_TOLERANCE_RANGE))]
    radius_tolerance: f64,
    /// Remesh first with the sizing field of the local spheres orthogonal to Ω (Fig. 16,
    /// bottom).
    #[arg(long, conflicts_with = "faces")]
    adaptive: bool,
    /// The adaptive sizing's tolerance, relative to the diagonal (default 0.0004).
    #[arg(long, value_name = "E", value_parser = in_range_f64(EPSILON_RANGE), requires = "adaptive")]
    epsilon: Option<f64>,
    /// Remesh first uniformly to about N faces.
    #[arg(long, value_name = "N", value_parser = in_range_usize(FACES_RANGE))]
    faces: Option<usize>,
    /// Move the vertices so that every panel has the radius of one of fewer moulds exactly,
    /// every face sphere still orthogonal to Ω (the schedule's `mould_snapped`).
    #[arg(long)]
    optimize_moulds: bool,
    #[command(flatten)]
    distance: MaxDistance,
}

impl MethodFlags for StSupportFlags {
    type Method = StSupportStage;

    fn params(&self) -> StSupportParams {
        let remesh = match (self.adaptive, self.faces) {
            (true, _) => Sizing::Adaptive { epsilon: self.epsilon.unwrap_or(DEFAULT_EPSILON) },
            (false, Some(n)) => Sizing::UniformFaces(n),
            (false, None) => Sizing::None,
        };
        StSupportParams {
            optimize_radius: self.optimize_radius,
            support_depth: self.depth,
            axis_length: self.axis_length,
            radius_tolerance: self.radius_tolerance,
            remesh,
            optimize_moulds: self.optimize_moulds,
            max_distance: self.distance.max_distance,
            ..StSupportParams::default()
        }
    }
}

/// `sq`'s flags.
#[derive(Args)]
pub struct SqFlags {
    /// Largest angle between the lines and the normals (degrees).
    #[arg(long, value_name = "DEG", default_value_t = SqParams::default().theta_deg, value_parser = in_range_f64(sq::THETA_RANGE))]
    theta: f64,
    /// Smallest angle between the torsal planes (degrees).
    #[arg(long, value_name = "DEG", default_value_t = SqParams::default().alpha_deg, value_parser = in_range_f64(sq::ALPHA_RANGE))]
    alpha: f64,
    /// Points per direction of the sampling grid G.
    #[arg(long, value_name = "N", default_value_t = SqParams::default().grid, value_parser = in_range_usize(sq::GRID_RANGE))]
    grid: usize,
    /// Recompute the exact torsal directions every K iterations.
    #[arg(long, value_name = "K", default_value_t = SqParams::default().recompute_every, value_parser = in_range_usize(sq::RECOMPUTE_RANGE))]
    rs: usize,
    /// About this many quads (at most what finishes within a minute and 1 GB natively).
    #[arg(long, value_name = "N", default_value_t = SqParams::default().faces, value_parser = in_range_usize(sq::FACES_RANGE))]
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
    #[arg(long, value_name = "D", default_value_t = SqParams::default().support_depth, value_parser = in_range_f64(SUPPORT_DEPTH_RANGE))]
    depth: f64,
    /// Move the exact SQ mesh so that every panel has the radius of one of fewer moulds
    /// exactly, keeping exactness, θ and α (the schedule's `mould_snapped`).
    #[arg(long)]
    optimize_moulds: bool,
    #[command(flatten)]
    distance: MaxDistance,
}

impl MethodFlags for SqFlags {
    type Method = SqStage;

    fn params(&self) -> SqParams {
        SqParams {
            theta_deg: self.theta,
            alpha_deg: self.alpha,
            grid: self.grid,
            recompute_every: self.rs,
            faces: self.faces,
            until: self.until,
            start: self.start,
            support_depth: self.depth,
            optimize_moulds: self.optimize_moulds,
            max_distance: self.distance.max_distance,
            ..SqParams::default()
        }
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
