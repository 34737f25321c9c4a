//! Design links: everything that defines a design, in a versioned URL fragment `#v=1&...`.
//! Parsing never fails: unknown or invalid fields are dropped and reported as notices. Values are
//! only ever used as data (enums, numbers, a file name shown as text).

use crate::congruence::central_spheres::JetParams;
use crate::panels::buildability::{DEFAULT_MAX_DISTANCE, MAX_DISTANCE_RANGE};
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::moulds::{Fabrication, MouldTarget, DEFAULT_MOULD_TOLERANCE};
use crate::pipeline::protocol::StageRequest;
use crate::remeshing::{Sizing, DEFAULT_EPSILON, DEFAULT_FACES, MAX_FACES, MIN_FACES};
use crate::samples::Sample;
use crate::sq::params::{RadiusStart, SqParams, Until, ALPHA_RANGE, FACES_RANGE, GRID_RANGE, RECOMPUTE_RANGE, THETA_RANGE};
use crate::st_adapted::params::StAdaptedParams;
use crate::st_support::StSupportParams;
use crate::units::{Length, Units};

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

/// The methods of the pipeline: one entry per method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Jet-fitted curvature and central spheres only (Sec. 2.6).
    Curvature,
    /// Angle-minimizing ST mesh with face size adapted to the surface (Sec. 3).
    StAdapted,
    /// ST mesh with support structure (Sec. 4).
    StSupport,
    /// SQ mesh with support structure (Sec. 5): a B-spline reference; the congruence (5.1) and
    /// the quad mesh with its spheres, panels and support structure (5.2).
    Sq,
}

impl Method {
    pub const ALL: [Method; 4] = [Method::Curvature, Method::StAdapted, Method::StSupport, Method::Sq];

    /// The link key (`method=…`).
    pub fn key(self) -> &'static str {
        match self {
            Method::Curvature => "curvature",
            Method::StAdapted => "st",
            Method::StSupport => "st-support",
            Method::Sq => "sq",
        }
    }

    pub fn title(self) -> &'static str {
        match self {
            Method::Curvature => "Curvature (Sec. 2.6)",
            Method::StAdapted => "ST, adapted face size (Sec. 3)",
            Method::StSupport => "ST with support structure (Sec. 4)",
            Method::Sq => "SQ with support structure (Sec. 5)",
        }
    }

    pub fn from_key(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.key() == s)
    }
}

/// The kind of a [`Sizing`], as links name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SizingKind {
    None,
    Adaptive,
    Faces,
}

impl SizingKind {
    pub const ALL: [SizingKind; 3] = [SizingKind::Adaptive, SizingKind::Faces, SizingKind::None];

    pub fn of(sizing: Sizing) -> Self {
        match sizing {
            Sizing::None => SizingKind::None,
            Sizing::Adaptive { .. } => SizingKind::Adaptive,
            Sizing::UniformFaces(_) => SizingKind::Faces,
        }
    }

    pub fn key(self) -> &'static str {
        match self {
            SizingKind::None => "none",
            SizingKind::Adaptive => "adaptive",
            SizingKind::Faces => "faces",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            SizingKind::None => "keep the reference triangulation",
            SizingKind::Adaptive => "adaptive (influence zones, ε)",
            SizingKind::Faces => "uniform, about N faces",
        }
    }

    pub fn from_key(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.key() == s)
    }

    /// The sizing of this kind with ε and N (the one the kind uses).
    pub fn sizing(self, epsilon: f64, faces: usize) -> Sizing {
        match self {
            SizingKind::None => Sizing::None,
            SizingKind::Adaptive => Sizing::Adaptive { epsilon },
            SizingKind::Faces => Sizing::UniformFaces(faces),
        }
    }
}

/// `&{key}=kind` and the value the kind uses (`&eps=…` or `&faces=…`).
fn sizing_fragment(key: &str, sizing: Sizing) -> String {
    let kind = SizingKind::of(sizing).key();
    match sizing {
        Sizing::None => format!("&{key}={kind}"),
        Sizing::Adaptive { epsilon } => format!("&{key}={kind}&eps={}", fmt_num(epsilon)),
        Sizing::UniformFaces(n) => format!("&{key}={kind}&faces={n}"),
    }
}

/// `&max_dist=…` when the distance bound is not its default, so older links stay as they were.
fn max_distance_fragment(max_distance: f64) -> String {
    if max_distance == DEFAULT_MAX_DISTANCE {
        String::new()
    } else {
        format!("&max_dist={}", fmt_num(max_distance))
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
    /// The jet fit of every method, held here once: the methods' own `jet` in `st_adapted` and
    /// `st_support` is never set or read in a design; [`Self::stage_requests`] fills it in.
    pub jet: JetParams,
    pub st_adapted: StAdaptedParams,
    pub st_support: StSupportParams,
    pub sq: SqParams,
    /// The model unit and the moulds, held here once for every panel method (filled into their
    /// params by [`Self::stage_requests`], like the jet).
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
            st_adapted: StAdaptedParams::default(),
            st_support: StSupportParams::default(),
            sq: SqParams::default(),
            fabrication: Fabrication::default(),
            color: ColorBy::MeanCurvature,
            shading: Shading::Smooth,
            edges: false,
            camera: None,
        }
    }
}

impl Design {
    /// The fragment, starting with '#'.
    pub fn to_fragment(&self) -> String {
        let mut s = format!("#v={VERSION}");
        match &self.reference {
            DesignSurface::Sample(x) => s += &format!("&sample={}", x.key()),
            DesignSurface::OwnFile(name) if name.is_empty() => s += "&sample=file",
            DesignSurface::OwnFile(name) => s += &format!("&sample=file&file={}", percent_encode(name)),
        }
        s += &format!("&method={}", self.method.key());
        s += &format!("&jet_degree={}&jet_rings={}", self.jet.degree, self.jet.max_rings);
        match self.method {
            Method::Curvature => {}
            Method::StAdapted => {
                s += &sizing_fragment("sizing", self.st_adapted.sizing);
                s += &format!("&variant={}", self.st_adapted.variant.key());
                if self.st_adapted.optimize_moulds {
                    s += "&opt_moulds=1";
                }
            }
            Method::StSupport => {
                let st = &self.st_support;
                s += &format!(
                    "&opt_r={}&depth={}&axis={}&rtol={}",
                    st.optimize_radius as u8,
                    fmt_num(st.support_depth),
                    fmt_num(st.axis_length),
                    fmt_num(st.radius_tolerance)
                );
                s += &sizing_fragment("remesh", st.remesh);
                if st.optimize_moulds {
                    s += "&opt_moulds=1";
                }
                s += &max_distance_fragment(st.max_distance);
            }
            Method::Sq => {
                let sq = &self.sq;
                s += &format!(
                    "&theta={}&alpha={}&grid={}&rs={}&faces={}&until={}",
                    fmt_num(sq.theta_deg),
                    fmt_num(sq.alpha_deg),
                    sq.grid,
                    sq.recompute_every,
                    sq.faces,
                    sq.until.key()
                );
                // The starting congruence only when not the default, so older links stay as they were.
                if sq.start != RadiusStart::Auto {
                    s += &format!("&start={}", sq.start.key());
                }
                if sq.optimize_moulds {
                    s += "&opt_moulds=1";
                }
                s += &max_distance_fragment(sq.max_distance);
            }
        }
        // Units and moulds only when not the defaults, so older links stay as they were.
        let f = &self.fabrication;
        if f.units != Units::default() {
            s += &format!("&units={}", f.units);
        }
        match f.moulds {
            MouldTarget::Tolerance(t) if t == DEFAULT_MOULD_TOLERANCE => {}
            MouldTarget::Tolerance(t) => s += &format!("&mould_tol={}", percent_encode(&t.to_string())),
            MouldTarget::Count(k) => s += &format!("&moulds={k}"),
        }
        s += &format!("&color={}&shading={}&edges={}", self.color.key(), self.shading.key(), self.edges as u8);
        if let Some(c) = self.camera {
            s += &format!(
                "&cam={},{},{},{},{},{}",
                fmt_cam(c.yaw),
                fmt_cam(c.pitch),
                fmt_cam(c.distance),
                fmt_cam(c.target[0]),
                fmt_cam(c.target[1]),
                fmt_cam(c.target[2])
            );
        }
        s
    }

    /// The stages that compute the design: the curvature (its colour maps and central spheres;
    /// the methods reuse it), then the method's stage.
    pub fn stage_requests(&self) -> Vec<StageRequest> {
        let mut stages = vec![StageRequest::Curvature(self.jet.clone())];
        match self.method {
            Method::Curvature => {}
            Method::StAdapted => stages.push(StageRequest::StAdapted(StAdaptedParams {
                jet: self.jet.clone(),
                fabrication: self.fabrication,
                ..self.st_adapted.clone()
            })),
            Method::StSupport => stages.push(StageRequest::StSupport(StSupportParams {
                jet: self.jet.clone(),
                fabrication: self.fabrication,
                ..self.st_support.clone()
            })),
            Method::Sq => stages.push(StageRequest::Sq(SqParams { fabrication: self.fabrication, ..self.sq.clone() })),
        }
        stages
    }

    /// Parses a fragment (with or without '#'). Returns the design and notices for the user.
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
        match pairs.iter().find(|(k, _)| k == "v").map(|(_, v)| v.as_str()) {
            Some("1") => {}
            Some(other) => notices.push(format!("design link version '{}' is not supported; read as version 1", clip(other))),
            None => notices.push("design link has no version (v=1); read as version 1".into()),
        }
        let mut file_name = None;
        let mut wants_file = false;
        let (mut eps, mut faces, mut opt_moulds, mut max_distance) = (None, None, None, None);
        let (mut adapted_sizing, mut support_remesh) = (None, None);
        for (k, v) in &pairs {
            let ok = match k.as_str() {
                "v" => true,
                "sample" if v == "file" => {
                    wants_file = true;
                    true
                }
                "sample" => match Sample::from_key(v) {
                    Some(s) => {
                        d.reference = DesignSurface::Sample(s);
                        true
                    }
                    None => {
                        let names: Vec<&str> = Sample::ALL.iter().map(|s| s.key()).collect();
                        notices.push(format!("ignored unknown sample '{}' (samples: {})", clip(v), names.join(", ")));
                        continue;
                    }
                },
                // An empty name is no name: the design then asks for "your file".
                "file" => {
                    !v.is_empty() && {
                        file_name = Some(clip(v));
                        true
                    }
                }
                "method" => Method::from_key(v).map(|m| d.method = m).is_some(),
                "jet_degree" => parse_in(v, 2, 4).map(|x| d.jet.degree = x as u8).is_some(),
                "jet_rings" => parse_in(v, 1, 8).map(|x| d.jet.max_rings = x as usize).is_some(),
                "opt_r" => parse_flag(v).map(|x| d.st_support.optimize_radius = x).is_some(),
                // The switch belongs to the method the link names (applied below).
                "opt_moulds" => parse_flag(v).map(|x| opt_moulds = Some(x)).is_some(),
                "max_dist" => parse_f64_in(v, *MAX_DISTANCE_RANGE.start(), *MAX_DISTANCE_RANGE.end()).map(|x| max_distance = Some(x)).is_some(),
                "depth" => parse_f64_in(v, 0.0, 1.0).map(|x| d.st_support.support_depth = x).is_some(),
                "axis" => parse_f64_in(v, 0.0, 10.0).map(|x| d.st_support.axis_length = x).is_some(),
                "rtol" => parse_f64_in(v, 1e-9, 1.0).map(|x| d.st_support.radius_tolerance = x).is_some(),
                "remesh" => SizingKind::from_key(v).map(|k| support_remesh = Some(k)).is_some(),
                "sizing" => SizingKind::from_key(v).map(|k| adapted_sizing = Some(k)).is_some(),
                // ε and N belong to the method the link names (applied below).
                "eps" => parse_f64_in(v, 1e-7, 0.1).map(|x| eps = Some(x)).is_some(),
                "faces" => parse_in(v, MIN_FACES as i64, MAX_FACES as i64).map(|x| faces = Some(x as usize)).is_some(),
                "theta" => parse_f64_in(v, THETA_RANGE.lo, THETA_RANGE.hi).map(|x| d.sq.theta_deg = x).is_some(),
                "alpha" => parse_f64_in(v, ALPHA_RANGE.lo, ALPHA_RANGE.hi).map(|x| d.sq.alpha_deg = x).is_some(),
                "grid" => parse_in(v, GRID_RANGE.lo as i64, GRID_RANGE.hi as i64).map(|x| d.sq.grid = x as usize).is_some(),
                "rs" => parse_in(v, RECOMPUTE_RANGE.lo as i64, RECOMPUTE_RANGE.hi as i64).map(|x| d.sq.recompute_every = x as usize).is_some(),
                "until" => Until::from_key(v).map(|u| d.sq.until = u).is_some(),
                "start" => RadiusStart::from_key(v).map(|r| d.sq.start = r).is_some(),
                "variant" => EdgeArcs::from_key(v).map(|x| d.st_adapted.variant = x).is_some(),
                "color" => ColorBy::from_key(v).map(|c| d.color = c).is_some(),
                "shading" => Shading::from_key(v).map(|s| d.shading = s).is_some(),
                "edges" => parse_flag(v).map(|x| d.edges = x).is_some(),
                "cam" => parse_camera(v).map(|c| d.camera = Some(c)).is_some(),
                "units" => v.parse::<Units>().map(|u| d.fabrication.units = u).is_ok(),
                "mould_tol" => v.parse::<Length>().map(|t| d.fabrication.moulds = MouldTarget::Tolerance(t)).is_ok(),
                "moulds" => parse_in(v, 1, 1_000_000).map(|k| d.fabrication.moulds = MouldTarget::Count(k as usize)).is_some(),
                _ => {
                    notices.push(format!("ignored unknown design-link field '{}'", clip(k)));
                    continue;
                }
            };
            if !ok {
                notices.push(format!("ignored invalid value for '{}': '{}'", clip(k), clip(v)));
            }
        }
        // A sizing kind takes ε and N from the link when it names the method they belong to.
        let applies = |m: Method| d.method == m;
        let sizing_of = |kind: SizingKind, current: Sizing, mine: bool| {
            let eps = if mine { eps } else { None }.unwrap_or(match current {
                Sizing::Adaptive { epsilon } => epsilon,
                _ => DEFAULT_EPSILON,
            });
            let n = if mine { faces } else { None }.unwrap_or(match current {
                Sizing::UniformFaces(n) => n,
                _ => DEFAULT_FACES,
            });
            kind.sizing(eps, n)
        };
        let mine = applies(Method::StAdapted);
        if let Some(kind) = adapted_sizing.or(mine.then(|| SizingKind::of(d.st_adapted.sizing))) {
            d.st_adapted.sizing = sizing_of(kind, d.st_adapted.sizing, mine);
        }
        let mine = applies(Method::StSupport);
        if let Some(kind) = support_remesh.or(mine.then(|| SizingKind::of(d.st_support.remesh))) {
            d.st_support.remesh = sizing_of(kind, d.st_support.remesh, mine);
        }
        if let Some(x) = max_distance {
            match d.method {
                Method::StSupport => d.st_support.max_distance = x,
                Method::Sq => d.sq.max_distance = x,
                Method::Curvature | Method::StAdapted => {}
            }
        }
        if let Some(x) = opt_moulds {
            match d.method {
                Method::StAdapted => d.st_adapted.optimize_moulds = x,
                Method::StSupport => d.st_support.optimize_moulds = x,
                Method::Sq => d.sq.optimize_moulds = x,
                Method::Curvature => {}
            }
        }
        // For SQ, N is the remesh's face count.
        if let Some(n) = faces.filter(|_| applies(Method::Sq)) {
            if FACES_RANGE.contains(n) {
                d.sq.faces = n;
            } else {
                notices.push(format!("ignored invalid value for 'faces': '{n}' (SQ takes {} to {})", FACES_RANGE.lo, FACES_RANGE.hi));
            }
        }
        if wants_file {
            let name = file_name.unwrap_or_else(|| "your file".into());
            notices.push(format!("this design uses the file '{name}': drop it on the viewport to continue"));
            d.reference = DesignSurface::OwnFile(name);
        }
        (d, notices)
    }
}

/// "0" or "1".
fn parse_flag(v: &str) -> Option<bool> {
    match v {
        "0" => Some(false),
        "1" => Some(true),
        _ => None,
    }
}

fn parse_in(v: &str, lo: i64, hi: i64) -> Option<i64> {
    v.parse::<i64>().ok().filter(|x| (lo..=hi).contains(x))
}

fn parse_f64_in(v: &str, lo: f64, hi: f64) -> Option<f64> {
    v.parse::<f64>().ok().filter(|x| x.is_finite() && (lo..=hi).contains(x))
}

fn parse_camera(v: &str) -> Option<CameraState> {
    let n: Vec<f64> = v.split(',').map(|x| x.parse::<f64>()).collect::<Result<_, _>>().ok()?;
    if n.len() != 6 || n.iter().any(|x| !x.is_finite()) || n[2] <= 0.0 {
        return None;
    }
    Some(CameraState { yaw: n[0], pitch: n[1].clamp(-1.55, 1.55), distance: n[2], target: [n[3], n[4], n[5]] })
}

/// A parameter exactly: the shorter of the plain and the exponent form of the shortest
/// round-trip digits (so `rtol=1e-5` reads back as 1e-5, never as 0).
fn fmt_num(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let (plain, exp) = (format!("{x}"), format!("{x:e}"));
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

/// A camera coordinate to six significant digits: short, and a fixed point of reading and
/// writing (a distance of 1e-5 stays 1e-5).
fn fmt_cam(x: f64) -> String {
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    fmt_num(rounded)
}

/// Notices quote link text; keep it short.
fn clip(s: &str) -> String {
    crate::text::clip(s, 60)
}

fn percent_encode(s: &str) -> String {
    let mut out = String::new();
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || b"-_.~".contains(&b) {
            out.push(b as char);
        } else {
            out += &format!("%{b:02X}");
        }
    }
    out
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(if b[i] == b'+' { b' ' } else { b[i] });
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
