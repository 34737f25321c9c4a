//! The CAD model of `panels.3dm` ([`RHINO_MODEL_FILE`]): the exact surfaces
//! ([`crate::panels::exact_surface`]) and curves as JSON, which the front end writes as a Rhino
//! .3dm file with rhino3dm (`www/rhino3dm/write.mjs`: the worker for the app, Node for the CLI).
//!
//! Layers: `panels` with one sub-layer `mould j` per mould (in its colour in the app), `support`,
//! `node axes`, `edges`, `reference` (m and Ω: a sphere, or a plane as a patch). Every panel surface carries user text: its id, mould, sphere
//! centre and radius (or "plane"), fit deviation and unit.

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::congruence::support_structure::SupportStructure;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::rational_bezier::{RationalCurve, RationalPatch};
use crate::panels::exact_surface::{arc_curve, ExactSurfaces};
use crate::panels::moulds::{mould_colour, MouldAssignment};
use crate::panels::panel::Panel;
use crate::units::Units;

/// The export file holding the model; the front end replaces it by `panels.3dm`.
pub const RHINO_MODEL_FILE: &str = "panels.3dm.json";
/// Its MIME type.
pub const RHINO_MODEL_MIME: &str = "application/vnd.spherical-faces.3dm-model+json";

#[derive(Clone, Debug, Serialize)]
pub struct Layer {
    pub name: String,
    pub parent: Option<usize>,
    pub color: [u8; 3],
}

#[derive(Clone, Debug, Serialize)]
pub struct Surface {
    pub layer: usize,
    pub name: String,
    pub degree: [usize; 2],
    pub points: Vec<[f64; 3]>,
    pub weights: Vec<f64>,
    pub user_text: serde_json::Map<String, serde_json::Value>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Curve {
    pub layer: usize,
    pub name: String,
    pub points: Vec<[f64; 3]>,
    pub weights: Vec<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Line {
    pub layer: usize,
    pub name: String,
    pub from: [f64; 3],
    pub to: [f64; 3],
}

#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub layer: usize,
    pub name: String,
    pub at: [f64; 3],
}

#[derive(Clone, Debug, Serialize)]
pub struct SphereObject {
    pub layer: usize,
    pub name: String,
    pub center: [f64; 3],
    pub radius: f64,
}

/// The model, as `write.mjs` reads it.
#[derive(Clone, Debug, Serialize)]
pub struct RhinoModel {
    pub units: Units,
    pub layers: Vec<Layer>,
    pub surfaces: Vec<Surface>,
    pub curves: Vec<Curve>,
    pub lines: Vec<Line>,
    pub points: Vec<Point>,
    pub spheres: Vec<SphereObject>,
}

const PANELS: usize = 0;
const SUPPORT: usize = 1;
const NODE_AXES: usize = 2;
const EDGES: usize = 3;
const REFERENCE: usize = 4;

fn surface(layer: usize, name: String, patch: &RationalPatch) -> Surface {
    Surface {
        layer,
        name,
        degree: patch.degree,
        points: patch.points.iter().map(|p| p.to_array()).collect(),
        weights: patch.weights.clone(),
        user_text: serde_json::Map::new(),
    }
}

fn curve(layer: usize, name: String, c: &RationalCurve) -> Curve {
    Curve { layer, name, points: c.points.iter().map(|p| p.to_array()).collect(), weights: c.weights.clone() }
}

/// The plane ⟨x, axis⟩ = d of a plane Ω (Sec. 4, where m is at infinity) as a bilinear patch
/// over the points projected into it, a tenth wider on every side.
fn plane_patch(axis: DVec3, d: f64, points: impl Iterator<Item = DVec3>) -> Option<RationalPatch> {
    let length = axis.length();
    let n = axis.try_normalize()?;
    let origin = n * (d / length);
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for x in points {
        let q = DVec2::new((x - origin).dot(e1), (x - origin).dot(e2));
        (lo, hi) = (lo.min(q), hi.max(q));
    }
    let pad = 0.1 * (hi - lo).max_element();
    let (lo, hi) = (lo - DVec2::splat(pad), hi + DVec2::splat(pad));
    if !(lo.is_finite() && hi.is_finite() && origin.is_finite()) {
        return None;
    }
    let at = |u: f64, v: f64| origin + u * e1 + v * e2;
    Some(RationalPatch { degree: [1, 1], points: vec![at(lo.x, lo.y), at(lo.x, hi.y), at(hi.x, lo.y), at(hi.x, hi.y)], weights: vec![1.0; 4] })
}

/// What goes into `panels.3dm`.
pub struct RhinoInput<'a> {
    pub panels: &'a [Panel],
    pub exact: &'a ExactSurfaces,
    pub moulds: &'a MouldAssignment,
    pub support: Option<&'a SupportStructure>,
    pub omega: Option<&'a AbsoluteSphere>,
    pub units: Units,
}

impl RhinoModel {
    pub fn of(input: &RhinoInput) -> Self {
        let colour = |c: [f32; 3]| c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8);
        let grey = [190, 190, 190];
        let mut layers: Vec<Layer> = ["panels", "support", "node axes", "edges", "reference"]
            .iter()
            .map(|name| Layer { name: (*name).into(), parent: None, color: grey })
            .collect();
        let first_mould = layers.len();
        for j in 0..input.moulds.moulds.len() {
            layers.push(Layer { name: format!("mould {j}"), parent: Some(PANELS), color: colour(mould_colour(j)) });
        }
        let mut model = RhinoModel {
            units: input.units,
            layers,
            surfaces: Vec::new(),
            curves: Vec::new(),
            lines: Vec::new(),
            points: Vec::new(),
            spheres: Vec::new(),
        };
        let unit = input.units.symbol();
        for (i, (p, exact)) in input.panels.iter().zip(&input.exact.panels).enumerate() {
            let Ok(patch) = exact else { continue };
            let j = input.moulds.panel_mould.get(i).copied().unwrap_or(0) as usize;
            let mut s = surface(first_mould + j, format!("panel {i}"), patch);
            let text = &mut s.user_text;
            text.insert("id".into(), i.into());
            text.insert("mould".into(), j.into());
            match (p.sphere.center(), p.sphere.signed_radius()) {
                (Some(c), Some(r)) if !p.is_planar() => {
                    text.insert("sphere_center".into(), format!("{} {} {}", c.x, c.y, c.z).into());
                    text.insert("sphere_radius".into(), r.abs().into());
                }
                _ => {
                    text.insert("sphere_radius".into(), "plane".into());
                }
            }
            text.insert("fit_deviation".into(), input.moulds.panel_deviation.get(i).copied().unwrap_or(f64::NAN).into());
            text.insert("units".into(), unit.into());
            model.surfaces.push(s);
        }
        for (e, exact) in input.exact.support.iter().enumerate() {
            if let Ok(patch) = exact {
                model.surfaces.push(surface(SUPPORT, format!("support element {e}"), patch));
            }
        }
        // One curve per mesh edge: the first panel's arc along it.
        let mut seen = std::collections::HashSet::new();
        for p in input.panels {
            let n = p.corners.len();
            for (k, arc) in p.arcs.iter().enumerate() {
                let (a, b) = (p.corners[k], p.corners[(k + 1) % n]);
                if seen.insert((a.min(b), a.max(b))) {
                    if let Ok(c) = arc_curve(arc) {
                        model.curves.push(curve(EDGES, format!("edge {}-{}", a.min(b), a.max(b)), &c));
                    }
                }
            }
        }
        if let Some(s) = input.support {
            for (v, (from, to)) in s.axis_segments().into_iter().enumerate() {
                model.lines.push(Line { layer: NODE_AXES, name: format!("node axis {v}"), from: from.to_array(), to: to.to_array() });
            }
        }
        match input.omega {
            Some(&AbsoluteSphere::Sphere { center, r2 }) => {
                model.points.push(Point { layer: REFERENCE, name: "m".into(), at: center.to_array() });
                if r2 > 0.0 {
                    model.spheres.push(SphereObject { layer: REFERENCE, name: "Ω".into(), center: center.to_array(), radius: r2.sqrt() });
                }
            }
            Some(&AbsoluteSphere::Plane { axis, d }) => {
                if let Some(patch) = plane_patch(axis, d, input.panels.iter().flat_map(|p| p.arcs.iter().map(|a| a.from))) {
                    model.surfaces.push(surface(REFERENCE, "Ω".into(), &patch));
                }
            }
            None => {}
        }
        model
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("the model serializes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_omega_is_a_patch_in_its_plane_over_the_points() {
        let (axis, d) = (DVec3::new(0.0, 0.0, 2.0), 6.0); // z = 3
        let points = [DVec3::new(-1.0, 0.0, 1.0), DVec3::new(2.0, 4.0, 5.0), DVec3::new(0.5, -3.0, 3.0)];
        let patch = plane_patch(axis, d, points.into_iter()).unwrap();
        for i in 0..=10 {
            for j in 0..=10 {
                let x = patch.evaluate(i as f64 / 10.0, j as f64 / 10.0);
                assert!((x.z - 3.0).abs() <= 1e-12, "{x}");
            }
        }
        // Every point's foot in the plane lies inside the patch (a parallelogram, here a rectangle).
        let (p00, p01, p10) = (patch.point(0, 0), patch.point(0, 1), patch.point(1, 0));
        let (du, dv) = (p10 - p00, p01 - p00);
        assert!(du.dot(dv).abs() <= 1e-12);
        for x in points {
            let foot = DVec3::new(x.x, x.y, 3.0) - p00;
            let (u, v) = (foot.dot(du) / du.length_squared(), foot.dot(dv) / dv.length_squared());
            assert!((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v), "{u} {v}");
        }
        assert!(plane_patch(DVec3::ZERO, 1.0, points.into_iter()).is_none());
    }
}
