//! Design links: everything that defines a design, in a versioned URL fragment `#v=1&...`.
//! Parsing never fails: unknown or invalid fields are dropped and reported as notices. Values are
//! only ever used as data (enums, numbers, a file name shown as text).

use crate::curvature::JetParams;
use crate::remesh::DEFAULT_EPSILON;
use crate::samples::Sample;
use crate::st_angle::{StSizing, StVariant};

pub const VERSION: u32 = 1;

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
    pub const ALL: [ColorBy; 6] =
        [ColorBy::MeanCurvature, ColorBy::K1, ColorBy::K2, ColorBy::K1MinusK2, ColorBy::Sizing, ColorBy::None];

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

/// The methods of the pipeline. Later methods add variants and their parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Jet-fitted curvature and central spheres only (Sec. 2.6).
    Curvature,
    /// ST mesh with support structure (Sec. 4).
    StSupport,
    /// Angle-minimizing ST mesh with face size adapted to the surface (Sec. 3).
    St,
}

impl Method {
    pub const ALL: [Method; 3] = [Method::Curvature, Method::St, Method::StSupport];

    pub fn key(self) -> &'static str {
        match self {
            Method::Curvature => "curvature",
            Method::StSupport => "st-support",
            Method::St => "st",
        }
    }

    pub fn title(self) -> &'static str {
        match self {
            Method::Curvature => "Curvature (Sec. 2.6)",
            Method::StSupport => "ST with support structure (Sec. 4)",
            Method::St => "ST, adapted face size (Sec. 3)",
        }
    }

    pub fn from_key(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.key() == s)
    }
}

/// How the reference is remeshed before a method runs (Sec. 3): kept as is, with the sizing
/// field of tolerance ε (relative to the bbox diagonal), or uniformly to about N faces. Both
/// values are kept when switching, so a link can carry them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SizingDesign {
    pub kind: SizingKind,
    pub epsilon: f64,
    pub faces: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SizingKind {
    None,
    Adaptive,
    Faces,
}

impl SizingKind {
    pub const ALL: [SizingKind; 3] = [SizingKind::Adaptive, SizingKind::Faces, SizingKind::None];

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
}

impl SizingDesign {
    pub const DEFAULT_FACES: usize = 600;

    pub fn with_kind(kind: SizingKind) -> Self {
        Self { kind, epsilon: DEFAULT_EPSILON, faces: Self::DEFAULT_FACES }
    }

    /// The remeshing the pipeline runs.
    pub fn to_sizing(self) -> StSizing {
        match self.kind {
            SizingKind::None => StSizing::None,
            SizingKind::Adaptive => StSizing::Adaptive { epsilon: self.epsilon },
            SizingKind::Faces => StSizing::UniformFaces(self.faces),
        }
    }

    fn to_fragment(self, key: &str) -> String {
        format!("&{key}={}&eps={}&faces={}", self.kind.key(), fmt_num_sig(self.epsilon), self.faces)
    }
}

/// Parameters of the "ST, adapted face size" method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StDesign {
    pub sizing: SizingDesign,
    pub variant: StVariant,
}

impl Default for StDesign {
    fn default() -> Self {
        Self { sizing: SizingDesign::with_kind(SizingKind::Adaptive), variant: StVariant::A }
    }
}

/// Parameters of the ST-with-support-structure method; lengths relative to the bbox diagonal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StSupportDesign {
    /// Choose R² to minimize the intersection angles (Fig. 16, right).
    pub optimize_radius: bool,
    pub support_depth: f64,
    pub axis_length: f64,
    /// Radii closer than this count as one in the panel schedule.
    pub radius_tolerance: f64,
    /// Remeshing before the method (Fig. 16, bottom): none by default.
    pub remesh: SizingDesign,
}

impl Default for StSupportDesign {
    fn default() -> Self {
        Self {
            optimize_radius: false,
            support_depth: 0.02,
            axis_length: 0.1,
            radius_tolerance: 1e-3,
            remesh: SizingDesign::with_kind(SizingKind::None),
        }
    }
}

/// The reference surface of a design.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
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
    pub reference: Reference,
    pub method: Method,
    pub jet: JetParams,
    pub st: StSupportDesign,
    pub st_angle: StDesign,
    pub color: ColorBy,
    pub shading: Shading,
    pub edges: bool,
    /// `None` frames the mesh.
    pub camera: Option<CameraState>,
}

impl Default for Design {
    fn default() -> Self {
        Self {
            reference: Reference::Sample(Sample::Dome),
            method: Method::Curvature,
            jet: JetParams::default(),
            st: StSupportDesign::default(),
            st_angle: StDesign::default(),
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
            Reference::Sample(x) => s += &format!("&sample={}", x.key()),
            Reference::OwnFile(name) => s += &format!("&sample=file&file={}", percent_encode(name)),
        }
        s += &format!("&method={}", self.method.key());
        s += &format!("&jet_degree={}&jet_rings={}", self.jet.degree, self.jet.max_rings);
        if self.method == Method::StSupport {
            let st = &self.st;
            s += &format!(
                "&opt_r={}&depth={}&axis={}&rtol={}",
                st.optimize_radius as u8,
                fmt_num(st.support_depth),
                fmt_num(st.axis_length),
                fmt_num(st.radius_tolerance)
            );
            s += &st.remesh.to_fragment("remesh");
        }
        if self.method == Method::St {
            s += &self.st_angle.sizing.to_fragment("sizing");
            s += &format!("&variant={}", if self.st_angle.variant == StVariant::B { "b" } else { "a" });
        }
        s += &format!("&color={}&shading={}&edges={}", self.color.key(), self.shading.key(), self.edges as u8);
        if let Some(c) = self.camera {
            s += &format!(
                "&cam={},{},{},{},{},{}",
                fmt_num(c.yaw),
                fmt_num(c.pitch),
                fmt_num(c.distance),
                fmt_num(c.target[0]),
                fmt_num(c.target[1]),
                fmt_num(c.target[2])
            );
        }
        s
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
        let (mut eps, mut faces) = (None, None);
        for (k, v) in &pairs {
            let ok = match k.as_str() {
                "v" => true,
                "sample" if v == "file" => {
                    wants_file = true;
                    true
                }
                "sample" => Sample::from_key(v).map(|s| d.reference = Reference::Sample(s)).is_some(),
                "file" => {
                    file_name = Some(clip(v));
                    !v.is_empty()
                }
                "method" => Method::from_key(v).map(|m| d.method = m).is_some(),
                "jet_degree" => parse_in(v, 2, 4).map(|x| d.jet.degree = x as u8).is_some(),
                "jet_rings" => parse_in(v, 1, 8).map(|x| d.jet.max_rings = x as usize).is_some(),
                "opt_r" => match v.as_str() {
                    "0" | "1" => {
                        d.st.optimize_radius = v == "1";
                        true
                    }
                    _ => false,
                },
                "depth" => parse_f64_in(v, 0.0, 1.0).map(|x| d.st.support_depth = x).is_some(),
                "axis" => parse_f64_in(v, 0.0, 10.0).map(|x| d.st.axis_length = x).is_some(),
                "rtol" => parse_f64_in(v, 1e-9, 1.0).map(|x| d.st.radius_tolerance = x).is_some(),
                "remesh" => SizingKind::from_key(v).map(|k| d.st.remesh.kind = k).is_some(),
                "sizing" => SizingKind::from_key(v).map(|k| d.st_angle.sizing.kind = k).is_some(),
                // ε and N belong to the method the link names (applied below).
                "eps" => parse_f64_in(v, 1e-7, 0.1).map(|x| eps = Some(x)).is_some(),
                "faces" => parse_in(v, 8, 200_000).map(|x| faces = Some(x as usize)).is_some(),
                "variant" => match v.as_str() {
                    "a" | "b" => {
                        d.st_angle.variant = if v == "b" { StVariant::B } else { StVariant::A };
                        true
                    }
                    _ => false,
                },
                "color" => ColorBy::from_key(v).map(|c| d.color = c).is_some(),
                "shading" => Shading::from_key(v).map(|s| d.shading = s).is_some(),
                "edges" => match v.as_str() {
                    "0" | "1" => {
                        d.edges = v == "1";
                        true
                    }
                    _ => false,
                },
                "cam" => parse_camera(v).map(|c| d.camera = Some(c)).is_some(),
                _ => {
                    notices.push(format!("ignored unknown design-link field '{}'", clip(k)));
                    continue;
                }
            };
            if !ok {
                notices.push(format!("ignored invalid value for '{}': '{}'", clip(k), clip(v)));
            }
        }
        let sizing = match d.method {
            Method::StSupport => Some(&mut d.st.remesh),
            Method::St => Some(&mut d.st_angle.sizing),
            Method::Curvature => None,
        };
        if let Some(sizing) = sizing {
            sizing.epsilon = eps.unwrap_or(sizing.epsilon);
            sizing.faces = faces.unwrap_or(sizing.faces);
        }
        if wants_file {
            let name = file_name.unwrap_or_else(|| "your file".into());
            notices.push(format!("this design uses the file '{name}': drop it on the viewport to continue"));
            d.reference = Reference::OwnFile(name);
        }
        (d, notices)
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

/// Four significant digits, for small values like ε.
fn fmt_num_sig(x: f64) -> String {
    let s = format!("{x:.3e}");
    match s.split_once('e') {
        Some((m, e)) => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
        None => s,
    }
}

fn fmt_num(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// Notices quote link text; keep it short.
fn clip(s: &str) -> String {
    let mut out: String = s.chars().filter(|c| !c.is_control()).take(60).collect();
    if s.chars().count() > 60 {
        out.push('…');
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let d = Design {
            reference: Reference::Sample(Sample::TorusPatch),
            method: Method::Curvature,
            jet: JetParams { degree: 2, max_rings: 3, ..JetParams::default() },
            st: StSupportDesign::default(),
            st_angle: StDesign::default(),
            color: ColorBy::K1,
            shading: Shading::Flat,
            edges: true,
            camera: Some(CameraState { yaw: 0.5, pitch: -0.25, distance: 6.0, target: [1.0, -2.0, 0.125] }),
        };
        let (back, notices) = Design::from_fragment(&d.to_fragment());
        assert!(notices.is_empty(), "{notices:?}");
        assert_eq!(back, d);
    }

    #[test]
    fn st_support_parameters_round_trip() {
        let d = Design {
            method: Method::StSupport,
            st: StSupportDesign {
                optimize_radius: true,
                support_depth: 0.035,
                axis_length: 0.25,
                radius_tolerance: 0.002,
                remesh: SizingDesign { kind: SizingKind::Adaptive, epsilon: 2.5e-4, faces: 900 },
            },
            ..Design::default()
        };
        let (back, notices) = Design::from_fragment(&d.to_fragment());
        assert!(notices.is_empty(), "{notices:?}");
        assert_eq!(back, d);
        let (bad, notices) = Design::from_fragment("#v=1&method=st-support&depth=-1&opt_r=2&rtol=nan");
        assert_eq!(bad.st, StSupportDesign::default());
        assert_eq!(notices.len(), 3);
    }

    #[test]
    fn st_parameters_round_trip() {
        for (kind, variant) in [(SizingKind::Adaptive, StVariant::B), (SizingKind::Faces, StVariant::A), (SizingKind::None, StVariant::A)] {
            let d = Design {
                method: Method::St,
                st_angle: StDesign { sizing: SizingDesign { kind, epsilon: 1.25e-3, faces: 2000 }, variant },
                color: ColorBy::Sizing,
                ..Design::default()
            };
            let frag = d.to_fragment();
            let (back, notices) = Design::from_fragment(&frag);
            assert!(notices.is_empty(), "{notices:?}");
            assert_eq!(back, d, "{frag}");
        }
        // ε and N go to the method the link names, wherever they stand in it.
        let (d, _) = Design::from_fragment("#v=1&eps=0.002&faces=50&method=st");
        assert_eq!(d.st_angle.sizing.epsilon, 0.002);
        assert_eq!(d.st_angle.sizing.faces, 50);
        assert_eq!(d.st.remesh, StSupportDesign::default().remesh);
        let (bad, notices) = Design::from_fragment("#v=1&method=st&eps=2&faces=3&variant=c&sizing=cubic");
        assert_eq!(bad.st_angle, StDesign::default());
        assert_eq!(notices.len(), 4, "{notices:?}");
    }

    #[test]
    fn unknown_and_invalid_fields_are_reported() {
        let (d, notices) = Design::from_fragment("#v=1&sample=torus&bogus=7&color=purple&jet_degree=9&cam=1,2");
        assert_eq!(d.reference, Reference::Sample(Sample::TorusPatch));
        assert_eq!(d.color, ColorBy::MeanCurvature);
        assert_eq!(d.jet.degree, JetParams::default().degree);
        assert_eq!(d.camera, None);
        assert_eq!(notices.len(), 4, "{notices:?}");
        assert!(notices[0].contains("bogus"));
    }

    #[test]
    fn file_names_are_data() {
        let d = Design { reference: Reference::OwnFile("<img src=x onerror=alert(1)>.obj".into()), ..Design::default() };
        let frag = d.to_fragment();
        assert!(!frag.contains('<') && !frag.contains(' '));
        let (back, notices) = Design::from_fragment(&frag);
        assert_eq!(back.reference, d.reference);
        assert_eq!(notices.len(), 1);
    }

    #[test]
    fn empty_and_garbage_fragments_give_defaults() {
        assert_eq!(Design::from_fragment("").0, Design::default());
        assert_eq!(Design::from_fragment("#").0, Design::default());
        let (d, n) = Design::from_fragment("#%%%&&==&v=1&%zz=1");
        assert_eq!(d, Design::default());
        assert!(!n.is_empty());
    }
}
