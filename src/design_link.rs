//! Design links: everything that defines a design, in a versioned URL fragment `#v=1&...`.
//! Parsing never fails: unknown or invalid fields are dropped and reported as notices. Values are
//! only ever used as data (enums, numbers, a file name shown as text). Each method writes and
//! reads its own fields ([`LinkFields`] in its `params.rs`); this file names no method.

use crate::congruence::central_spheres::JetParams;
use crate::panels::moulds::Fabrication;
use crate::params::{number_text, percent_decode, percent_encode, FieldStatus, LinkFields, LinkReader, LinkWriter};
use crate::pipeline::method::Request;
use crate::pipeline::protocol::{MethodId, MethodParams, OnWire, StageRequest};
use crate::samples::Sample;

pub(crate) const VERSION: u32 = 1;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorBy {
    MeanCurvature,
    K1,
    K2,
    K1MinusK2,
    /// The sizing field g of the "ST, adapted face size" method (Sec. 3).
    Sizing,
    None,
}

impl ColorBy {
    pub const ALL: [ColorBy; 6] = [ColorBy::MeanCurvature, ColorBy::K1, ColorBy::K2, ColorBy::K1MinusK2, ColorBy::Sizing, ColorBy::None];

    pub fn key(self) -> &'static str {
        match self {
            ColorBy::MeanCurvature => "H",
            ColorBy::K1 => "k1",
            ColorBy::K2 => "k2",
            ColorBy::K1MinusK2 => "k1-k2",
            ColorBy::Sizing => "sizing",
            ColorBy::None => "none",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            ColorBy::MeanCurvature => "mean curvature H",
            ColorBy::K1 => "κ1",
            ColorBy::K2 => "κ2",
            ColorBy::K1MinusK2 => "|κ1 − κ2|",
            ColorBy::Sizing => "sizing field g",
            ColorBy::None => "none",
        }
    }

    pub fn from_key(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.key() == s)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    Flat,
    Smooth,
    Reflective,
}

impl Shading {
    pub const ALL: [Shading; 3] = [Shading::Flat, Shading::Smooth, Shading::Reflective];

    pub fn key(self) -> &'static str {
        match self {
            Shading::Flat => "flat",
            Shading::Smooth => "smooth",
            Shading::Reflective => "reflective",
        }
    }

    pub fn from_key(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.key() == s)
    }
}

/// What a design computes: the curvature alone, or a method with its panels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Jet-fitted curvature and central spheres only (Sec. 2.6).
    Curvature,
    Of(MethodId),
}

impl Method {
    /// The curvature, then every method of the menu.
    pub fn all() -> impl Iterator<Item = Method> {
        std::iter::once(Method::Curvature).chain(MethodId::ALL.iter().map(|&m| Method::Of(m)))
    }

    /// The link key (`method=…`).
    pub fn key(self) -> &'static str {
        match self {
            Method::Curvature => "curvature",
            Method::Of(m) => m.key(),
        }
    }

    pub fn title(self) -> &'static str {
        match self {
            Method::Curvature => "Curvature (Sec. 2.6)",
            Method::Of(m) => m.label(),
        }
    }

    pub fn from_key(s: &str) -> Option<Self> {
        Self::all().find(|m| m.key() == s)
    }
}

/// The reference surface of a design.
#[derive(Clone, Debug, PartialEq)]
pub enum DesignSurface {
    Sample(Sample),
    /// The user's own file: a link can only name it; the user drops it again.
    OwnFile(String),
}

/// Orbit camera around `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraState {
    pub yaw: f64,
    pub pitch: f64,
    pub distance: f64,
    pub target: [f64; 3],
}

#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    pub reference: DesignSurface,
    pub method: Method,
    /// The jet fit of every method, held here once; [`Self::stage_requests`] puts it in the
    /// requests.
    pub jet: JetParams,
    /// Every method's parameters, one per method of [`MethodId::ALL`], kept while another
    /// method is shown.
    pub methods: Vec<MethodParams>,
    /// The model unit and the moulds, held here once for every panel method.
    pub fabrication: Fabrication,
    pub color: ColorBy,
    pub shading: Shading,
    pub edges: bool,
    /// `None` frames the mesh.
    pub camera: Option<CameraState>,
}

impl Default for Design {
    fn default() -> Self {
        Self {
            reference: DesignSurface::Sample(Sample::Dome),
            method: Method::Curvature,
            jet: JetParams::default(),
            methods: MethodId::ALL.iter().map(|m| m.default_params()).collect(),
            fabrication: Fabrication::default(),
            color: ColorBy::MeanCurvature,
            shading: Shading::Smooth,
            edges: false,
            camera: None,
        }
    }
}

impl Design {
    /// A design of method `M` with `params`, the rest the defaults.
    pub fn of<M: OnWire>(params: M::Params) -> Self {
        let mut d = Design { method: Method::Of(M::ID), ..Design::default() };
        *d.params_mut::<M>() = params;
        d
    }

    /// Method `M`'s parameters.
    pub fn params<M: OnWire>(&self) -> &M::Params {
        self.methods.iter().find_map(M::unwrap_params).expect("a design holds every method's parameters")
    }

    pub fn params_mut<M: OnWire>(&mut self) -> &mut M::Params {
        self.methods.iter_mut().find_map(M::unwrap_params_mut).expect("a design holds every method's parameters")
    }

    /// The parameters of `method`.
    pub fn method_params(&self, method: MethodId) -> &MethodParams {
        self.methods.iter().find(|p| p.method() == method).expect("a design holds every method's parameters")
    }

    fn method_params_mut(&mut self, method: MethodId) -> &mut MethodParams {
        self.methods.iter_mut().find(|p| p.method() == method).expect("a design holds every method's parameters")
    }

    /// The fragment, starting with '#'.
    pub fn to_fragment(&self) -> String {
        let mut link = LinkWriter { text: format!("#v={VERSION}") };
        match &self.reference {
            DesignSurface::Sample(x) => link.text("sample", x.key()),
            DesignSurface::OwnFile(name) if name.is_empty() => link.text("sample", "file"),
            DesignSurface::OwnFile(name) => {
                link.text("sample", "file");
                link.text("file", &percent_encode(name));
            }
        }
        link.text("method", self.method.key());
        self.jet.write_link(&mut link);
        if let Method::Of(m) = self.method {
            self.method_params(m).write_link(&mut link);
        }
        self.fabrication.write_link(&mut link);
        link.text("color", self.color.key());
        link.text("shading", self.shading.key());
        link.flag("edges", self.edges);
        if let Some(c) = self.camera {
            let cam = [c.yaw, c.pitch, c.distance, c.target[0], c.target[1], c.target[2]].map(fmt_cam);
            link.text("cam", &cam.join(","));
        }
        link.text
    }

    /// The stages that compute the design: the curvature (its colour maps and central spheres;
    /// the methods reuse it), then the method's stage.
    pub fn stage_requests(&self) -> Vec<StageRequest> {
        let mut stages = vec![StageRequest::Curvature(self.jet.clone())];
        if let Method::Of(m) = self.method {
            let request = Request { params: self.method_params(m).clone(), fabrication: self.fabrication, jet: self.jet.clone() };
            stages.push(StageRequest::Method(Box::new(request)));
        }
        stages
    }

    /// Parses a fragment (with or without '#'). Returns the design and notices for the user, in
    /// the order of the link's fields.
    pub fn from_fragment(fragment: &str) -> (Design, Vec<String>) {
        let mut d = Design::default();
        let mut notices = Vec::new();
        let body = fragment.strip_prefix('#').unwrap_or(fragment);
        if body.is_empty() {
            return (d, notices);
        }
        let pairs: Vec<(String, String)> = body
            .split('&')
            .filter(|p| !p.is_empty())
            .map(|p| {
                let (k, v) = p.split_once('=').unwrap_or((p, ""));
                (percent_decode(k), percent_decode(v))
            })
            .collect();
        let mut link = LinkReader::new(pairs);
        match link.get("v").as_deref() {
            Some("1") => {}
            Some(other) => notices.push(format!("design link version '{}' is not supported; read as version 1", clip(other))),
            None => notices.push("design link has no version (v=1); read as version 1".into()),
        }
        let wants_file = d.read_surface(&mut link, &mut notices);
        // An empty name is no name: the design then asks for "your file".
        let file_name = link.get("file").filter(|v| !v.is_empty()).map(|v| clip(&v));
        d.read_fields(&mut link);
        for (k, v, status) in link.fields() {
            match status {
                FieldStatus::Read => {}
                FieldStatus::Invalid => notices.push(format!("ignored invalid value for '{}': '{}'", clip(k), clip(v))),
                FieldStatus::Unread => notices.push(format!("ignored unknown design-link field '{}'", clip(k))),
            }
        }
        // The app asks for the file by name in its view, and keeps the link until it comes.
        if wants_file {
            d.reference = DesignSurface::OwnFile(file_name.unwrap_or_default());
        }
        (d, notices)
    }

    /// The sample a link names; true when it names the user's own file.
    fn read_surface(&mut self, link: &mut LinkReader, notices: &mut Vec<String>) -> bool {
        match link.get("sample").as_deref() {
            Some("file") => true,
            Some(v) => {
                match Sample::from_key(v) {
                    Some(s) => self.reference = DesignSurface::Sample(s),
                    None => {
                        let names: Vec<&str> = Sample::ALL.iter().map(|s| s.key()).collect();
                        notices.push(format!("ignored unknown sample '{}' (samples: {})", clip(v), names.join(", ")));
                    }
                }
                false
            }
            None => false,
        }
    }

    /// The method, its fields, and the fields every design has. Another method's fields are not
    /// this design's: they are known, and left.
    fn read_fields(&mut self, link: &mut LinkReader) {
        link.set_parsed("method", Method::from_key, &mut self.method);
        self.jet.read_link(link);
        self.fabrication.read_link(link);
        link.set_parsed("color", ColorBy::from_key, &mut self.color);
        link.set_parsed("shading", Shading::from_key, &mut self.shading);
        link.set_flag("edges", &mut self.edges);
        if let Some(c) = link.parsed("cam", parse_camera) {
            self.camera = Some(c);
        }
        if let Method::Of(m) = self.method {
            self.method_params_mut(m).read_link(link);
        }
        for &other in MethodId::ALL.iter().filter(|&&o| self.method != Method::Of(o)) {
            let mut theirs = link.fresh();
            other.default_params().read_link(&mut theirs);
            link.mark_known(&theirs);
        }
    }
}

fn parse_camera(v: &str) -> Option<CameraState> {
    let n: Vec<f64> = v.split(',').map(|x| x.parse::<f64>()).collect::<Result<_, _>>().ok()?;
    if n.len() != 6 || n.iter().any(|x| !x.is_finite()) || n[2] <= 0.0 {
        return None;
    }
    Some(CameraState { yaw: n[0], pitch: n[1].clamp(-1.55, 1.55), distance: n[2], target: [n[3], n[4], n[5]] })
}

/// A camera coordinate to six significant digits: short, and a fixed point of reading and
/// writing (a distance of 1e-5 stays 1e-5).
fn fmt_cam(x: f64) -> String {
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    number_text(rounded)
}

/// Notices quote link text; keep it short.
fn clip(s: &str) -> String {
    crate::text::clip(s, 60)
}
