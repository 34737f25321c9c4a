//! A fourth method through the recipe of ARCHITECTURE.md, in the test tree only: a copy of the
//! crate under `target/fourth-method/` gets a dummy method (its folder, its stage file, its view,
//! and one line each in the protocol's `methods!`, `views::views` and the CLI's subcommands, the
//! module lines and its name on the methods row), is built, runs through the session, the design
//! link and the command line, and passes the architecture test. Nothing else of the tree is
//! edited: a method that needs more than the recipe fails here.
#![cfg(not(target_arch = "wasm32"))] // native: builds a copy of the crate

use std::path::{Path, PathBuf};
use std::process::Command;

const DUMMY_MOD: &str = r#"//! A dummy method, the test tree's fourth (tests/fourth_method.rs): it counts the reference's
//! faces, `copies` times.

pub mod guarantees;
pub mod params;
pub mod report;

use std::fmt;

use crate::progress::{Cancelled, Progress};
use crate::reference::Reference;
use params::DummyParams;

/// What the method makes.
#[derive(Clone, Debug)]
pub struct DummyResult {
    pub faces: usize,
    pub reference_faces: usize,
    pub copies: usize,
}

/// Why the method gave no result.
#[derive(Clone, Debug, PartialEq)]
pub enum DummyError {
    Cancelled,
    Parameter(crate::params::ParamError),
}

impl fmt::Display for DummyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DummyError::Cancelled => f.write_str("cancelled"),
            DummyError::Parameter(e) => e.fmt(f),
        }
    }
}

impl From<Cancelled> for DummyError {
    fn from(_: Cancelled) -> Self {
        DummyError::Cancelled
    }
}

pub fn compute(reference: &Reference, params: &DummyParams, progress: &mut dyn FnMut(Progress) -> Result<(), Cancelled>) -> Result<DummyResult, DummyError> {
    params.check().map_err(DummyError::Parameter)?;
    progress(Progress::new("count", 0, 1))?;
    let reference_faces = reference.mesh().face_count();
    progress(Progress::new("count", 1, 1))?;
    Ok(DummyResult { faces: reference_faces * params.copies, reference_faces, copies: params.copies })
}
"#;

const DUMMY_PARAMS: &str = r#"//! The dummy method's parameters, their ranges and defaults, and its link fields.

use serde::{Deserialize, Serialize};

use crate::params::{LinkFields, LinkReader, LinkWriter, ParamError, ParamRange};

pub const COPIES_RANGE: ParamRange<usize> = ParamRange::new("copies", 1, 10);

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DummyParams {
    pub copies: usize,
}

impl Default for DummyParams {
    fn default() -> Self {
        Self { copies: 1 }
    }
}

impl DummyParams {
    pub fn check(&self) -> Result<(), ParamError> {
        COPIES_RANGE.check(self.copies).map(|_| ())
    }
}

impl LinkFields for DummyParams {
    fn write_link(&self, link: &mut LinkWriter) {
        link.count("copies", self.copies);
    }

    fn read_link(&mut self, link: &mut LinkReader) {
        if let Some(n) = link.count("copies", COPIES_RANGE) {
            self.copies = n;
        }
    }
}
"#;

const DUMMY_GUARANTEES: &str = r#"//! What the dummy method promises: every face counted, `copies` times.

use super::DummyResult;
use crate::guarantees::{Guarantee, Verdict};

pub fn measure(result: &DummyResult) -> Verdict {
    let expected = (result.reference_faces * result.copies) as f64;
    Verdict::new(vec![Guarantee::at_least("faces", result.faces as f64, expected, "")])
}
"#;

const DUMMY_REPORT: &str = r#"//! The section "dummy" of report.json.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DummySection {
    pub faces: usize,
}
"#;

const DUMMY_STAGE: &str = r#"//! The dummy method's stage.

use serde::{Deserialize, Serialize};

use super::StageError;
use crate::dummy::params::DummyParams;
use crate::dummy::report::DummySection;
use crate::dummy::{compute, guarantees, DummyError, DummyResult};
use crate::export::{report_file, Report};
use crate::panels::moulds::MouldAssignment;
use crate::pipeline::fields::Field;
use crate::pipeline::method::{Computed, Exported, Method, Request};
use crate::pipeline::sink::{report, Sink};
use crate::progress::Clock;
use crate::reference::Reference;

pub struct DummyStage;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DummySummary {
    pub report: Report,
}

impl Method for DummyStage {
    const KEY: &'static str = "dummy";
    const LABEL: &'static str = "Dummy (the test tree's fourth method)";
    type Params = DummyParams;
    type Result = DummyResult;
    type Summary = DummySummary;

    fn optimizes_moulds(_params: &DummyParams) -> bool {
        false
    }

    fn compute(reference: &Reference, request: &Request<DummyParams>, _clock: Clock, sink: &mut dyn Sink) -> Result<Computed<DummyResult>, StageError> {
        let start = sink.now_ms();
        let result = compute(reference, &request.params, &mut |p| report(sink, p, Vec::new(), start))?;
        Ok(Computed { result, iteration: 1 })
    }

    fn export(_reference: &Reference, result: &DummyResult, _request: &Request<DummyParams>, _clock: Clock) -> Exported {
        let mut report = Report::new(Self::KEY);
        report.set_section(&DummySection { faces: result.faces });
        report.set_verdict(&guarantees::measure(result));
        let files = vec![report_file(&report)];
        Exported { report, files, moulds: None }
    }

    fn display(_result: &DummyResult, _moulds: Option<&MouldAssignment>) -> Vec<Field> {
        Vec::new()
    }

    fn summary(_result: &DummyResult, report: Report) -> DummySummary {
        DummySummary { report }
    }

    fn report(summary: &DummySummary) -> &Report {
        &summary.report
    }

    fn report_mut(summary: &mut DummySummary) -> &mut Report {
        &mut summary.report
    }

    fn describe(result: &DummyResult, _report: &Report, _request: &Request<DummyParams>, out: &str) -> String {
        format!("counted {} faces into {out}", result.faces)
    }
}

impl From<DummyError> for StageError {
    fn from(e: DummyError) -> Self {
        match e {
            DummyError::Cancelled => StageError::Cancelled,
            e => StageError::refused(&e, None),
        }
    }
}
"#;

/// The view (wasm only: the architecture test reads it, the native build does not compile it).
const DUMMY_VIEW: &str = r#"//! The dummy method's view.

use super::method_view::{Drawn, Frame, MethodView};
use crate::design_link::{Design, Method};
use crate::export::Report;
use crate::pipeline::fields::Field;
use crate::pipeline::protocol::{MethodId, MethodSummary, StageId, StageResult};
use crate::pipeline::stages::dummy::DummyStage;

#[derive(Default)]
pub struct DummyMethod {
    report: Option<Report>,
}

impl MethodView for DummyMethod {
    fn method(&self) -> Method {
        Method::Of(MethodId::Dummy)
    }
    fn name(&self) -> &'static str {
        "dummy"
    }
    fn owns(&self, stage: StageId) -> bool {
        stage.method() == Some(MethodId::Dummy)
    }
    fn start(&mut self) {
        self.report = None;
    }
    fn clear(&mut self) {
        self.report = None;
    }
    fn controls(&mut self, ui: &mut egui::Ui, design: &mut Design) -> bool {
        let params = design.params_mut::<DummyStage>();
        let range = crate::dummy::params::COPIES_RANGE;
        ui.add(egui::Slider::new(&mut params.copies, range.lo..=range.hi).text("copies")).changed()
    }
    fn results(&self, ui: &mut egui::Ui, _design: &Design) {
        if let Some(r) = &self.report {
            crate::web::app::panels::verdict(ui, r);
        }
    }
    fn snapshot(&mut self, _stage: StageId, _iteration: u32, _fields: &[Field], _generation: &mut u64) -> bool {
        false
    }
    fn finished(&mut self, result: StageResult) -> Option<Report> {
        let StageResult::Method(MethodSummary::Dummy(summary)) = result else { return None };
        self.report = Some(summary.report.clone());
        self.report.clone()
    }
    fn draw(&self, _frame: &Frame) -> Drawn {
        Drawn::reference_only()
    }
    fn automation(&self) -> serde_json::Value {
        serde_json::json!({ "ready": self.report.is_some() })
    }
}
"#;

const DUMMY_CLI_FLAGS: &str = r#"
/// `dummy`'s flags.
#[derive(Args)]
pub struct DummyFlags {
    /// How many times to count the faces.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = in_range_usize(spherical_faces::dummy::params::COPIES_RANGE))]
    copies: usize,
}

impl MethodFlags for DummyFlags {
    type Method = spherical_faces::pipeline::stages::dummy::DummyStage;

    fn params(&self) -> spherical_faces::dummy::params::DummyParams {
        spherical_faces::dummy::params::DummyParams { copies: self.copies }
    }
}
"#;

/// What the copy runs: the method through the session and the design link, and through the
/// command line.
const RUN_TEST: &str = r#"use spherical_faces::design_link::Design;
use spherical_faces::dummy::params::DummyParams;
use spherical_faces::pipeline::fields::Field;
use spherical_faces::pipeline::protocol::*;
use spherical_faces::pipeline::stages::dummy::DummyStage;
use spherical_faces::pipeline::{Outbox, Session};
use spherical_faces::samples::Sample;

struct Record(Vec<FromWorker>);

impl Outbox for Record {
    fn send(&mut self, msg: FromWorker, _fields: Vec<Field>) {
        self.0.push(msg);
    }
    fn cancel_requested(&mut self) -> bool {
        false
    }
    fn now_ms(&self) -> f64 {
        0.0
    }
}

#[test]
fn the_fourth_method_runs_through_the_session_and_the_link() {
    let mut s = Session::new();
    let mut r = Record(Vec::new());
    s.handle(ToWorker::LoadSample(Sample::Dome), None, &mut r);
    let FromWorker::Loaded(info) = r.0[0].clone() else { panic!("{:?}", r.0[0]) };
    s.handle(ToWorker::Run(Box::new(StageRequest::method::<DummyStage>(DummyParams { copies: 3 }))), None, &mut r);
    let Some(FromWorker::Finished { stage, result: StageResult::Method(MethodSummary::Dummy(summary)), .. }) = r.0.last() else {
        panic!("{:?}", r.0.last())
    };
    assert_eq!(stage.key(), "dummy");
    assert_eq!(summary.report.meets_guarantees, Some(true), "{:?}", summary.report.guarantees);
    assert!(r.0.iter().any(|m| matches!(m, FromWorker::Files { stage, .. } if stage.key() == "dummy")));
    let section: spherical_faces::dummy::report::DummySection = summary.report.section().unwrap();
    assert_eq!(section.faces, 3 * info.stats.faces);
    // A range the method owns is read by the session's request too.
    s.handle(ToWorker::Run(Box::new(StageRequest::method::<DummyStage>(DummyParams { copies: 11 }))), None, &mut r);
    assert!(matches!(r.0.last(), Some(FromWorker::Error { message, .. }) if message.contains("copies 11")), "{:?}", r.0.last());
    // Its parameters are in the design link.
    let d = Design::of::<DummyStage>(DummyParams { copies: 7 });
    let fragment = d.to_fragment();
    assert!(fragment.contains("&method=dummy&") && fragment.contains("&copies=7"), "{fragment}");
    let (back, notices) = Design::from_fragment(&fragment);
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(back, d);
}

#[test]
fn the_fourth_method_runs_through_the_cli() {
    let dir = std::env::temp_dir().join("sf-fourth-method");
    let _ = std::fs::remove_dir_all(&dir);
    let bin = env!("CARGO_BIN_EXE_spherical-faces-fourth");
    let out = std::process::Command::new(bin).args(["dummy", "sample:dome", "--copies", "2", "-q", "--out"]).arg(&dir).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("counted "));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["method"], "dummy");
    assert_eq!(report["meets_guarantees"], true);
    let bad = std::process::Command::new(bin).args(["dummy", "sample:dome", "--copies", "0", "--out"]).arg(&dir).output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let help = std::process::Command::new(bin).arg("--help").output().unwrap();
    assert!(String::from_utf8_lossy(&help.stdout).contains("dummy"));
}
"#;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let target = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &target);
        } else {
            std::fs::copy(&p, &target).unwrap();
        }
    }
}

/// `text` with `add` after the line that contains `anchor` (which must be there once).
fn after_line(path: &Path, anchor: &str, add: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    assert_eq!(text.matches(anchor).count(), 1, "{}: the recipe's place `{anchor}` moved", path.display());
    let at = text.find(anchor).unwrap();
    let end = at + text[at..].find('\n').map_or(text.len() - at, |i| i + 1);
    std::fs::write(path, format!("{}{add}{}", &text[..end], &text[end..])).unwrap();
}

/// `text` with `from` (there once) replaced by `to`.
fn replace_once(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    assert_eq!(text.matches(from).count(), 1, "{}: the recipe's place `{from}` moved", path.display());
    std::fs::write(path, text.replacen(from, to, 1)).unwrap();
}

#[test]
fn a_fourth_method_added_by_the_recipe_builds_runs_and_passes_the_architecture_test() {
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or(root().join("target"), PathBuf::from);
    let copy = target.join("fourth-method");
    let _ = std::fs::remove_dir_all(copy.join("src"));
    let _ = std::fs::remove_dir_all(copy.join("tests"));
    for dir in ["src", "benches"] {
        copy_dir(&root().join(dir), &copy.join(dir));
    }
    std::fs::create_dir_all(copy.join("tests")).unwrap();
    for file in ["Cargo.lock", "rustfmt.toml", "ARCHITECTURE.md", "tests/architecture.rs"] {
        std::fs::copy(root().join(file), copy.join(file)).unwrap();
    }
    // The manifest: its own binary name (the copy shares the target directory, and so its
    // dependencies' builds) and the vendored crate where it is.
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let manifest = manifest
        .replace("default-run = \"spherical-faces\"", "default-run = \"spherical-faces-fourth\"")
        .replace("name = \"spherical-faces\"\npath = \"src/main.rs\"", "name = \"spherical-faces-fourth\"\npath = \"src/main.rs\"")
        .replace("path = \"vendor/", &format!("path = \"{}/vendor/", root().display()));
    assert!(manifest.contains("spherical-faces-fourth\"\npath"), "the manifest's [[bin]] moved");
    std::fs::write(copy.join("Cargo.toml"), manifest).unwrap();

    // 1. The folder, and its module line.
    let src = copy.join("src");
    std::fs::create_dir_all(src.join("dummy")).unwrap();
    for (file, text) in [("mod.rs", DUMMY_MOD), ("params.rs", DUMMY_PARAMS), ("guarantees.rs", DUMMY_GUARANTEES), ("report.rs", DUMMY_REPORT)] {
        std::fs::write(src.join("dummy").join(file), text).unwrap();
    }
    after_line(&src.join("lib.rs"), "pub mod design_link;", "/// The test tree's fourth method.\npub mod dummy;\n");
    // 2. The stage file, and its module line.
    std::fs::write(src.join("pipeline/stages/dummy.rs"), DUMMY_STAGE).unwrap();
    after_line(&src.join("pipeline/stages/mod.rs"), "pub mod curvature;", "pub mod dummy;\n");
    // 3. The protocol's line.
    after_line(&src.join("pipeline/protocol.rs"), "    Sq => stages::sq::SqStage,", "    Dummy => stages::dummy::DummyStage,\n");
    // 4. The view and its line in views::views.
    std::fs::write(src.join("web/app/views/dummy.rs"), DUMMY_VIEW).unwrap();
    after_line(&src.join("web/app/views/mod.rs"), "pub mod curvature;", "pub mod dummy;\n");
    after_line(&src.join("web/app/views/mod.rs"), "Box::new(sq::SqMethod::default()),", "        Box::new(dummy::DummyMethod::default()),\n");
    // 5. The CLI's subcommand: its variant, its arm and its flags.
    let cli = src.join("cli/methods.rs");
    after_line(
        &cli,
        "    Sq(MethodArgs<SqFlags>),",
        "    /// The test tree's fourth method.\n    #[command(name = \"dummy\", after_help = EXIT_CODES)]\n    Dummy(MethodArgs<DummyFlags>),\n",
    );
    after_line(&cli, "            MethodCommand::Sq(a) => drive(a, progress),", "            MethodCommand::Dummy(a) => drive(a, progress),\n");
    std::fs::write(&cli, std::fs::read_to_string(&cli).unwrap() + DUMMY_CLI_FLAGS).unwrap();
    // 6. Its name on the methods row.
    replace_once(
        &copy.join("ARCHITECTURE.md"),
        "| methods | `st_adapted`, `st_support`, `sq` |",
        "| methods | `st_adapted`, `st_support`, `sq`, `dummy` |",
    );
    std::fs::write(copy.join("tests/fourth_method_run.rs"), RUN_TEST).unwrap();

    let out = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["test", "--manifest-path"])
        .arg(copy.join("Cargo.toml"))
        .args(["--test", "architecture", "--test", "fourth_method_run"])
        .env("CARGO_TARGET_DIR", &target)
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "the copy with a fourth method failed:\n{stdout}\n{stderr}");
    for test in [
        "the_fourth_method_runs_through_the_session_and_the_link ... ok",
        "the_fourth_method_runs_through_the_cli ... ok",
        "every_method_follows_the_recipe ... ok",
        "no_file_outside_the_recipe_names_a_method ... ok",
        "imports_follow_the_documented_layers_without_cycles ... ok",
    ] {
        assert!(stdout.contains(test), "{test} did not run:\n{stdout}");
    }
}
