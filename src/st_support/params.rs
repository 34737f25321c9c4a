//! The parameters of ST meshes with support structure (Sec. 4), their defaults written once
//! here: the CLI, the app and the design link read them.

use serde::{Deserialize, Serialize};

use super::absolute_sphere::AbsoluteSphereParams;
use crate::congruence::central_spheres::JetParams;
use crate::congruence::support_structure::{AXIS_LENGTH_RANGE, SUPPORT_DEPTH_RANGE};
use crate::panels::buildability::{write_max_distance, DEFAULT_MAX_DISTANCE, MAX_DISTANCE_RANGE};
use crate::panels::RADIUS_TOLERANCE_RANGE;
use crate::params::{LinkFields, LinkReader, LinkWriter, ParamError};
use crate::remeshing::Sizing;

/// Neighbours of a local sphere orthogonal to Ω (remeshing with `Sizing::Adaptive`).
pub const LOCAL_SPHERE_POINTS: usize = 16;

/// Parameters of the method ([`compute`]); lengths relative to the bbox diagonal. The defaults
/// are written here only.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StSupportParams {
    /// Choose R² (or d) minimizing the mean kink angle instead of the mean of the R_i².
    pub optimize_radius: bool,
    /// Depth of the support elements. Default 0.02.
    pub support_depth: f64,
    /// Length of the displayed node-axis segments. Default 0.1.
    pub axis_length: f64,
    /// Radii closer than this count as one in the panel schedule. Default 1e-3.
    pub radius_tolerance: f64,
    /// Remesh first: adaptively with the sizing field of the local spheres orthogonal to Ω
    /// (Fig. 16, bottom; ε × diag), uniformly to about N faces, or not at all (the default).
    pub remesh: Sizing,
    pub jet: JetParams,
    pub absolute: AbsoluteSphereParams,
    /// Move the vertices so that the panels have the radii of fewer moulds exactly, every face
    /// sphere still orthogonal to Ω ([`super::moulds`]).
    pub optimize_moulds: bool,
    /// The panels' promised distance to the reference, relative to the diagonal
    /// ([`crate::panels::buildability::DEFAULT_MAX_DISTANCE`]).
    pub max_distance: f64,
}

impl Default for StSupportParams {
    fn default() -> Self {
        Self {
            optimize_radius: false,
            support_depth: 0.02,
            axis_length: 0.1,
            radius_tolerance: 1e-3,
            remesh: Sizing::None,
            jet: JetParams::default(),
            absolute: AbsoluteSphereParams::default(),
            optimize_moulds: false,
            max_distance: DEFAULT_MAX_DISTANCE,
        }
    }
}

impl StSupportParams {
    /// Every parameter a design sets, against its range.
    pub fn check(&self) -> Result<(), ParamError> {
        self.remesh.check()?;
        SUPPORT_DEPTH_RANGE.check(self.support_depth)?;
        AXIS_LENGTH_RANGE.check(self.axis_length)?;
        RADIUS_TOLERANCE_RANGE.check(self.radius_tolerance)?;
        MAX_DISTANCE_RANGE.check(self.max_distance)?;
        Ok(())
    }
}

impl LinkFields for StSupportParams {
    fn write_link(&self, link: &mut LinkWriter) {
        link.flag("opt_r", self.optimize_radius);
        link.number("depth", self.support_depth);
        link.number("axis", self.axis_length);
        link.number("rtol", self.radius_tolerance);
        self.remesh.write_link("remesh", link);
        if self.optimize_moulds {
            link.flag("opt_moulds", true);
        }
        write_max_distance(link, self.max_distance);
    }

    fn read_link(&mut self, link: &mut LinkReader) {
        link.set_flag("opt_r", &mut self.optimize_radius);
        link.set_number("depth", SUPPORT_DEPTH_RANGE, &mut self.support_depth);
        link.set_number("axis", AXIS_LENGTH_RANGE, &mut self.axis_length);
        link.set_number("rtol", RADIUS_TOLERANCE_RANGE, &mut self.radius_tolerance);
        self.remesh.read_link("remesh", link);
        link.set_flag("opt_moulds", &mut self.optimize_moulds);
        link.set_number("max_dist", MAX_DISTANCE_RANGE, &mut self.max_distance);
    }
}
