//! STEP (ISO 10303-21, AP214) of the exact surfaces ([`crate::panels::exact_surface`]): every
//! panel and support element one `ADVANCED_FACE` on a rational `B_SPLINE_SURFACE_WITH_KNOTS`
//! (one Bézier span), bounded by its sides as rational B-spline edge curves, each face its own
//! `OPEN_SHELL` of one `SHELL_BASED_SURFACE_MODEL`, in the design's unit.

use std::fmt::Write as _;

use glam::DVec3;

use crate::geometry::rational_bezier::{RationalPatch, Side};
use crate::panels::exact_surface::ExactSurfaces;
use crate::panels::panel::Panel;
use crate::units::Units;

/// One face to write: its name (shown in CAD as the shell's) and its patch; `triangle`: its
/// side v = 1 is one point, left out of the loop.
pub struct StepFace<'a> {
    pub name: String,
    pub patch: &'a RationalPatch,
    pub triangle: bool,
}

/// A STEP real: the shortest text that reads back to `x`, with the point STEP requires.
fn real(x: f64) -> String {
    let s = format!("{x:?}");
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => format!("{m}E{e}"),
        Some((m, e)) => format!("{m}.E{e}"),
        None if s.contains('.') => s,
        None => format!("{s}."),
    }
}

/// Text with quotes doubled and only printable ASCII (STEP strings are ISO 8859-1 without
/// escapes here).
fn string(s: &str) -> String {
    s.chars().filter(|c| c.is_ascii() && !c.is_ascii_control()).collect::<String>().replace('\'', "''")
}

struct Writer {
    data: String,
    next: usize,
}

impl Writer {
    fn add(&mut self, entity: &str) -> usize {
        let id = self.next;
        self.next += 1;
        let _ = writeln!(self.data, "#{id}={entity};");
        id
    }

    fn point(&mut self, p: DVec3) -> usize {
        self.add(&format!("CARTESIAN_POINT('',({},{},{}))", real(p.x), real(p.y), real(p.z)))
    }

    fn refs(ids: &[usize]) -> String {
        ids.iter().map(|i| format!("#{i}")).collect::<Vec<_>>().join(",")
    }

    fn reals(xs: &[f64]) -> String {
        xs.iter().map(|&x| real(x)).collect::<Vec<_>>().join(",")
    }

    /// A rational B-spline curve on the control points `ids` with `weights`.
    fn curve(&mut self, ids: &[usize], weights: &[f64]) -> usize {
        let p = ids.len() - 1;
        self.add(&format!(
            "(BOUNDED_CURVE() B_SPLINE_CURVE({p},({}),.UNSPECIFIED.,.F.,.F.) B_SPLINE_CURVE_WITH_KNOTS(({m},{m}),(0.,1.),.UNSPECIFIED.) \
             CURVE() GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_CURVE(({})) REPRESENTATION_ITEM(''))",
            Self::refs(ids),
            Self::reals(weights),
            m = p + 1
        ))
    }

    /// A rational B-spline surface on the control points `ids[i][j]` (i along u).
    fn surface(&mut self, s: &RationalPatch, ids: &[Vec<usize>]) -> usize {
        let [p, q] = s.degree;
        let rows: Vec<String> = ids.iter().map(|row| format!("({})", Self::refs(row))).collect();
        let weights: Vec<String> = (0..=p).map(|i| format!("({})", Self::reals(&(0..=q).map(|j| s.weight(i, j)).collect::<Vec<_>>()))).collect();
        self.add(&format!(
            "(BOUNDED_SURFACE() B_SPLINE_SURFACE({p},{q},({}),.UNSPECIFIED.,.F.,.F.,.F.) B_SPLINE_SURFACE_WITH_KNOTS(({mp},{mp}),({mq},{mq}),\
             (0.,1.),(0.,1.),.UNSPECIFIED.) GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_SURFACE(({})) REPRESENTATION_ITEM('') SURFACE())",
            rows.join(","),
            weights.join(","),
            mp = p + 1,
            mq = q + 1
        ))
    }

    /// The face of `f` in its own shell: its loop runs (0,0) → (1,0) → (1,1) → (0,1), the sides
    /// v = 1 and u = 0 against their curves, which share the surface's control points.
    fn face(&mut self, f: &StepFace) -> usize {
        let s = f.patch;
        let [p, q] = s.degree;
        let ids: Vec<Vec<usize>> = (0..=p).map(|i| (0..=q).map(|j| self.point(s.point(i, j))).collect()).collect();
        let corner_ids = [ids[0][0], ids[p][0], ids[p][q], ids[0][q]];
        let n = if f.triangle { 3 } else { 4 };
        let vertices: Vec<usize> = corner_ids[..n].iter().map(|&c| self.add(&format!("VERTEX_POINT('',#{c})"))).collect();
        let vertex = |k: usize| vertices[k.min(n - 1)];
        let mut edges = Vec::new();
        for (side, start, end, forward) in [(Side::V0, 0, 1, true), (Side::U1, 1, 2, true), (Side::V1, 3, 2, false), (Side::U0, 0, 3, false)] {
            if f.triangle && side == Side::V1 {
                continue;
            }
            let (points, weights): (Vec<usize>, Vec<f64>) = match side {
                Side::V0 => (0..=p).map(|i| (ids[i][0], s.weight(i, 0))).unzip(),
                Side::V1 => (0..=p).map(|i| (ids[i][q], s.weight(i, q))).unzip(),
                Side::U0 => (0..=q).map(|j| (ids[0][j], s.weight(0, j))).unzip(),
                Side::U1 => (0..=q).map(|j| (ids[p][j], s.weight(p, j))).unzip(),
            };
            let curve = self.curve(&points, &weights);
            let edge = self.add(&format!("EDGE_CURVE('',#{},#{},#{curve},.T.)", vertex(start), vertex(end)));
            edges.push(self.add(&format!("ORIENTED_EDGE('',*,*,#{edge},{})", if forward { ".T." } else { ".F." })));
        }
        let surface = self.surface(s, &ids);
        let lp = self.add(&format!("EDGE_LOOP('',({}))", Self::refs(&edges)));
        let bound = self.add(&format!("FACE_OUTER_BOUND('',#{lp},.T.)"));
        let face = self.add(&format!("ADVANCED_FACE('{}',(#{bound}),#{surface},.T.)", string(&f.name)));
        self.add(&format!("OPEN_SHELL('{}',(#{face}))", string(&f.name)))
    }

    /// The length unit entity of `units` (SI, or converted from the millimetre).
    fn length_unit(&mut self, units: Units) -> usize {
        let si = |prefix: &str| format!("(LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT({prefix},.METRE.))");
        match units {
            Units::M => self.add(&si("$")),
            Units::Cm => self.add(&si(".CENTI.")),
            Units::Mm => self.add(&si(".MILLI.")),
            Units::Ft | Units::In => {
                let mm = self.add(&si(".MILLI."));
                let (name, factor) = if units == Units::Ft { ("FOOT", 304.8) } else { ("INCH", 25.4) };
                let measure = self.add(&format!("LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE({}),#{mm})", real(factor)));
                let dims = self.add("DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.)");
                self.add(&format!("(CONVERSION_BASED_UNIT('{name}',#{measure}) LENGTH_UNIT() NAMED_UNIT(#{dims}))"))
            }
        }
    }
}

/// The STEP file of `faces`, in `units`, with a distance uncertainty of `precision` (model
/// units). `name` names the product.
pub fn write_step(name: &str, faces: &[StepFace], units: Units, precision: f64) -> String {
    let mut w = Writer { data: String::new(), next: 1 };
    let app = w.add("APPLICATION_CONTEXT('core data for automotive mechanical design processes')");
    w.add(&format!("APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{app})"));
    let pc = w.add(&format!("PRODUCT_CONTEXT('',#{app},'mechanical')"));
    let product = w.add(&format!("PRODUCT('{0}','{0}','',(#{pc}))", string(name)));
    let formation = w.add(&format!("PRODUCT_DEFINITION_FORMATION('','',#{product})"));
    let pdc = w.add(&format!("PRODUCT_DEFINITION_CONTEXT('part definition',#{app},'design')"));
    let definition = w.add(&format!("PRODUCT_DEFINITION('design','',#{formation},#{pdc})"));
    let shape = w.add(&format!("PRODUCT_DEFINITION_SHAPE('','',#{definition})"));
    let length = w.length_unit(units);
    let angle = w.add("(NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.))");
    let solid = w.add("(NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT())");
    let uncertainty = w
        .add(&format!("UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE({}),#{length},'distance_accuracy_value','confusion accuracy')", real(precision)));
    let context = w.add(&format!(
        "(GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{uncertainty})) \
         GLOBAL_UNIT_ASSIGNED_CONTEXT((#{length},#{angle},#{solid})) REPRESENTATION_CONTEXT('',''))"
    ));
    let origin = w.point(DVec3::ZERO);
    let z = w.add("DIRECTION('',(0.,0.,1.))");
    let x = w.add("DIRECTION('',(1.,0.,0.))");
    let placement = w.add(&format!("AXIS2_PLACEMENT_3D('',#{origin},#{z},#{x})"));
    let shells: Vec<usize> = faces.iter().map(|f| w.face(f)).collect();
    let model = w.add(&format!("SHELL_BASED_SURFACE_MODEL('',({}))", Writer::refs(&shells)));
    let representation = w.add(&format!("MANIFOLD_SURFACE_SHAPE_REPRESENTATION('{}',(#{placement},#{model}),#{context})", string(name)));
    w.add(&format!("SHAPE_DEFINITION_REPRESENTATION(#{shape},#{representation})"));
    format!(
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('Spherical Faces: exact panels and support elements'),'2;1');\n\
         FILE_NAME('{0}.step','',(''),(''),'spherical-faces','spherical-faces','');\n\
         FILE_SCHEMA(('AUTOMOTIVE_DESIGN {{ 1 0 10303 214 1 1 1 1 }}'));\nENDSEC;\nDATA;\n{1}ENDSEC;\nEND-ISO-10303-21;\n",
        string(name),
        w.data
    )
}

/// `panels.step`: every panel with an exact patch ("panel i") and every support element ("support
/// element e"), in `units`, with an uncertainty of 1e-9 of the diagonal `diag`.
pub fn write_exact_step(name: &str, panels: &[Panel], exact: &ExactSurfaces, units: Units, diag: f64) -> String {
    let mut faces = Vec::with_capacity(exact.panels.len() + exact.support.len());
    for (i, patch) in exact.panels.iter().enumerate() {
        if let Ok(patch) = patch {
            faces.push(StepFace { name: format!("panel {i}"), patch, triangle: panels[i].arcs.len() == 3 });
        }
    }
    for (e, patch) in exact.support.iter().enumerate() {
        if let Ok(patch) = patch {
            faces.push(StepFace { name: format!("support element {e}"), patch, triangle: false });
        }
    }
    write_step(name, &faces, units, 1e-9 * diag.max(f64::MIN_POSITIVE))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reals_read_back_exactly_and_carry_a_point() {
        for x in [0.0, 1.0, -2.5, 1e-7, 1.5e20, 0.1, -3.0e-300, 123456789.0] {
            let s = real(x);
            assert!(s.contains('.'), "{s}");
            assert_eq!(s.replace("E", "e").parse::<f64>().unwrap(), x, "{s}");
        }
        assert_eq!(real(1e-7), "1.E-7");
        assert_eq!(string("it's é"), "it''s ");
    }
}
