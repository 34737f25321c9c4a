//! Whether a result can be built as delivered: every panel cut from its sphere and bounded by
//! its arcs, which do not cross (its exact patch, [`super::exact_surface`]), every support element
//! a planar piece that does not fold, every panel close to the reference. One measurement: the
//! verdicts of all three methods, the CAD files' refusals and the app's warnings read it.

use crate::guarantees::Guarantee;
use crate::params::{LinkWriter, ParamRange};
use crate::units::{format_length, Units};

use super::exact_surface::{ExactSurfaceError, ExactSurfaces};
use super::panel::Panel;
use crate::congruence::support_structure::SupportElement;

/// The name of the guarantee on the panels' distance to the reference.
pub const MAX_DISTANCE: &str = "max_distance_to_reference";

/// The default bound on the panels' distance to the reference of the methods with support
/// structure, relative to the bounding-box diagonal.
pub const DEFAULT_MAX_DISTANCE: f64 = 0.01;
/// The range a distance bound may take (relative to the diagonal).
pub const MAX_DISTANCE_RANGE: ParamRange<f64> = ParamRange::new("the distance bound", 1e-6, 1.0);

/// `&max_dist=…` when the distance bound is not its default, so older links stay as they were.
pub fn write_max_distance(link: &mut LinkWriter, max_distance: f64) {
    if max_distance != DEFAULT_MAX_DISTANCE {
        link.number("max_dist", max_distance);
    }
}

/// What stops a result from being built, measured on the delivered panels.
#[derive(Clone, Debug, PartialEq)]
pub struct Buildability {
    /// Panels whose boundary crosses itself ([`ExactSurfaceError::ArcsCross`]), by panel index.
    pub panels_with_crossing_arcs: Vec<usize>,
    /// Panels without an exact patch for another reason (a side wider than half a circle, a
    /// patch that folds, no finite sphere), by panel index.
    pub panels_without_surface: Vec<usize>,
    /// Support elements whose planar patch folds or has no side, by element index; None for a
    /// method without support structure.
    pub support_elements_that_fold: Option<Vec<usize>>,
    /// Each panel's largest distance to the reference (model units).
    pub panel_distances: Vec<f64>,
    /// The reference's bounding-box diagonal (model units).
    pub diagonal: f64,
    pub units: Units,
}

impl Buildability {
    /// Measures the `exact` surfaces of a result (the ones its CAD files hold) and its panels'
    /// `distances` to the reference (model units); `with_support`: the method delivers a support
    /// structure, whose elements count.
    pub fn measure(exact: &ExactSurfaces, distances: &[f64], with_support: bool, diagonal: f64, units: Units) -> Self {
        let mut crossing = Vec::new();
        let mut without = Vec::new();
        for (i, e) in exact.refused_panels() {
            match e {
                ExactSurfaceError::ArcsCross => crossing.push(i),
                _ => without.push(i),
            }
        }
        let support = with_support.then(|| exact.support.iter().enumerate().filter(|(_, s)| s.is_err()).map(|(i, _)| i).collect());
        Self {
            panels_with_crossing_arcs: crossing,
            panels_without_surface: without,
            support_elements_that_fold: support,
            panel_distances: distances.to_vec(),
            diagonal,
            units,
        }
    }

    /// [`Self::measure`] on the exact surfaces of `panels` and `support` (None: a method without
    /// support structure).
    pub fn of_panels(panels: &[Panel], support: Option<&[SupportElement]>, distances: &[f64], diagonal: f64, units: Units) -> Self {
        let exact = ExactSurfaces::of(panels, support.unwrap_or(&[]));
        Self::measure(&exact, distances, support.is_some(), diagonal, units)
    }

    /// The largest distance of a panel to the reference (model units), or the first panel whose
    /// distance could not be measured.
    pub fn max_distance(&self) -> Result<f64, usize> {
        let mut max = 0.0f64;
        for (i, &d) in self.panel_distances.iter().enumerate() {
            if !d.is_finite() {
                return Err(i);
            }
            max = max.max(d);
        }
        Ok(max)
    }

    /// The guarantees: no panel with crossing arcs, none without its exact surface, no support
    /// element that folds, and every panel within `max_distance` (relative to the diagonal) of
    /// the reference.
    pub fn guarantees(&self, max_distance: f64) -> Vec<Guarantee> {
        let mut all = vec![
            Guarantee::count_at_most("panels_with_crossing_arcs", self.panels_with_crossing_arcs.len(), 0),
            Guarantee::count_at_most("panels_without_exact_surface", self.panels_without_surface.len(), 0),
        ];
        if let Some(support) = &self.support_elements_that_fold {
            all.push(Guarantee::count_at_most("support_elements_that_fold", support.len(), 0));
        }
        all.push(self.distance_guarantee(max_distance));
        all
    }

    /// Every panel within `max_distance` × the diagonal of the reference, in model units beside.
    pub fn distance_guarantee(&self, max_distance: f64) -> Guarantee {
        let diag = self.diagonal.max(f64::MIN_POSITIVE);
        let name = MAX_DISTANCE;
        let limit = format_length(max_distance * diag, self.units);
        match self.max_distance() {
            _ if self.panel_distances.is_empty() => {
                Guarantee::at_most(name, f64::NAN, max_distance, "of the diagonal").unmeasured("there are no panels")
            }
            Ok(d) => Guarantee::at_most(name, d / diag, max_distance, "of the diagonal")
                .with_model_units(format!("{}, limit {limit}", format_length(d, self.units))),
            Err(panel) => Guarantee::at_most(name, f64::NAN, max_distance, "of the diagonal")
                .unmeasured(format!("panel {panel} has a point with no closest point on the reference")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rational_bezier::RationalPatch;

    fn patch() -> RationalPatch {
        use crate::geometry::rational_bezier::RationalCurve;
        use glam::DVec3;
        let (a, b, c, d) = (DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y);
        RationalPatch::coons(
            &RationalCurve::segment(a, b),
            &RationalCurve::segment(b, c),
            &RationalCurve::segment(d, c),
            &RationalCurve::segment(a, d),
        )
    }

    #[test]
    fn counts_what_cannot_be_made_and_the_distance() {
        let exact = ExactSurfaces {
            panels: vec![Ok(patch()), Err(ExactSurfaceError::ArcsCross), Err(ExactSurfaceError::Degenerate)],
            support: vec![Ok(patch()), Err(ExactSurfaceError::Folds { jacobian_ratio: 0.0 })],
        };
        let b = Buildability::measure(&exact, &[0.1, 0.3, 0.2], true, 10.0, Units::M);
        assert_eq!(b.panels_with_crossing_arcs, vec![1]);
        assert_eq!(b.panels_without_surface, vec![2]);
        assert_eq!(b.support_elements_that_fold, Some(vec![1]));
        let g = b.guarantees(0.02);
        let names: Vec<(&str, bool)> = g.iter().map(|g| (g.name.as_str(), g.holds)).collect();
        assert_eq!(
            names,
            [
                ("panels_with_crossing_arcs", false),
                ("panels_without_exact_surface", false),
                ("support_elements_that_fold", false),
                ("max_distance_to_reference", false)
            ]
        );
        assert!((g[3].measured - 0.03).abs() < 1e-15);
        assert!(b.distance_guarantee(0.05).holds);
        let unmeasured = Buildability::measure(&exact, &[0.1, f64::INFINITY, 0.2], false, 10.0, Units::M);
        let d = unmeasured.distance_guarantee(0.5);
        assert!(!d.holds && d.unmeasured.as_deref().is_some_and(|r| r.contains("panel 1")), "{d}");
        assert_eq!(unmeasured.guarantees(0.5).len(), 3, "no support structure, no support guarantee");
    }
}
