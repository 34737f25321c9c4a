//! The arguments every method shares: the input, the fabrication settings and the output.

use std::path::PathBuf;

use clap::Args;

use spherical_faces::export::rhino::RHINO_MODEL_FILE;
use spherical_faces::panels::moulds::{Fabrication, MouldTarget, DEFAULT_MOULD_TOLERANCE, MOULD_COUNT_RANGE};
use spherical_faces::params::ParamRange;
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::units::{Length, Units};

const SURFACE_HELP: &str = "A mesh (.obj, .gltf, .glb), a B-spline surface (.json, the paper authors' format), a \
Rhino file (.3dm, read with the rhino3dm package through Node) or sample:NAME, a built-in sample (dome, torus, \
sphere-cap, wave-roof, vault)";

#[derive(Args)]
pub struct Input {
    #[arg(help = SURFACE_HELP, value_name = "SURFACE")]
    pub surface: String,
    /// In a .3dm file with several objects, the one to take (its index in `info --list-objects`);
    /// default: the first NURBS surface, else the first mesh.
    #[arg(long, value_name = "K")]
    pub object: Option<usize>,
}

/// The model unit and the moulds the panels are fitted to.
#[derive(Args)]
pub struct FabricationArgs {
    /// What one model unit is: m, cm, mm, ft or in (default: the .3dm file's unit system, else m).
    #[arg(long, value_name = "UNIT", value_parser = units)]
    pub units: Option<Units>,
    /// The fewest moulds (radii the panels share) within this fit tolerance δ, e.g. 2mm or
    /// 0.1in (a bare number is in model units). Default 2mm.
    #[arg(long, value_name = "LENGTH", value_parser = length, conflicts_with = "moulds")]
    pub mould_tolerance: Option<Length>,
    /// Exactly this many moulds at most, at the smallest fit tolerance that allows it.
    #[arg(long, value_name = "K", value_parser = in_range_usize(MOULD_COUNT_RANGE))]
    pub moulds: Option<usize>,
}

impl FabricationArgs {
    fn fabrication(&self) -> Fabrication {
        let moulds = match (self.moulds, self.mould_tolerance) {
            (Some(k), _) => MouldTarget::Count(k),
            (None, Some(t)) => MouldTarget::Tolerance(t),
            (None, None) => MouldTarget::Tolerance(DEFAULT_MOULD_TOLERANCE),
        };
        Fabrication { units: self.units.unwrap_or_default(), moulds }
    }

    /// [`Self::fabrication`] in the file's unit when `--units` is not given.
    pub fn fabrication_for(&self, loaded: &Loaded) -> Fabrication {
        let f = self.fabrication();
        match (self.units, loaded.info.units) {
            (None, Some(units)) => Fabrication { units, ..f },
            _ => f,
        }
    }
}

#[derive(Args)]
pub struct Output {
    /// The folder to write into (created if missing; checked before any work).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The files to write, comma-separated: glb (panels.glb), obj (panels.obj), schedule
    /// (panels.csv, panels.json, moulds.csv, support.csv), step (panels.step) and 3dm
    /// (panels.3dm, written by the rhino3dm package through Node), both with every panel and
    /// support element an exact rational NURBS surface, or all; report.json is always written
    #[arg(long, value_name = "LIST", value_enum, value_delimiter = ',', default_value = "all")]
    pub formats: Vec<FileFormat>,
}

/// A kind of file the panel methods write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FileFormat {
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
    pub fn wants(&self, name: &str) -> bool {
        FileFormat::of(name).is_none_or(|f| self.formats.iter().any(|&w| w == f || w == FileFormat::All))
    }
}

/// A number checked against its range (the parameter's one check, [`ParamRange::check`]).
pub fn in_range_f64(range: ParamRange<f64>) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |s| range.parse(s)
}

/// A count checked against its range.
pub fn in_range_usize(range: ParamRange<usize>) -> impl Fn(&str) -> Result<usize, String> + Clone {
    move |s| range.parse(s)
}

pub fn units(s: &str) -> Result<Units, String> {
    s.parse().map_err(|e: spherical_faces::units::UnitsError| e.to_string())
}

pub fn length(s: &str) -> Result<Length, String> {
    s.parse().map_err(|e: spherical_faces::units::UnitsError| e.to_string())
}
