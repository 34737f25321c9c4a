//! The parameters of the angle-minimizing ST method, with their defaults (the one place they
//! are written).

use serde::{Deserialize, Serialize};

use crate::congruence::central_spheres::JetParams;
use crate::panels::buildability::DEFAULT_MAX_DISTANCE;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::RADIUS_TOLERANCE_RANGE;
use crate::params::{LinkFields, LinkReader, LinkWriter, ParamError};
use crate::remeshing::{RemeshParams, Sizing, DEFAULT_EPSILON};

/// Term weights (frame scaled to diagonal 1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StAdaptedWeights {
    pub angle: f64,
    pub tangent_distance: f64,
    pub point_distance: f64,
    /// Face sphere through the reference point closest to the face centroid (limits bulging).
    pub face_distance: f64,
    pub fairness: f64,
    /// Variant (a): the sideways bulge of the edge circles' arcs (`terms::EdgeCircle`); not
    /// used by variant (b), whose arcs are cut by bisecting planes.
    pub edge_circle: f64,
    /// Variant (a): adjacent panels whose sagittas over their common edge differ by more than
    /// the tolerance band's τ (`terms::SagittaMatch` in a `solver::Band`); not used by variant
    /// (b), nor without a tolerance ε.
    pub sagitta_match: f64,
    /// Barrier against folded faces (`FaceOrientation` under a hinge).
    pub orientation: f64,
    /// The tolerance band: vertices and face centroids farther from the reference than
    /// [`StAdaptedParams::tolerance_band`] (`solver::Band`), so the tolerance ε holds for the
    /// panels, not only on average.
    pub tolerance: f64,
}

impl Default for StAdaptedWeights {
    fn default() -> Self {
        Self {
            angle: 1.0,
            tangent_distance: 100.0,
            point_distance: 10.0,
            face_distance: 100.0,
            fairness: 1.0,
            edge_circle: 10.0,
            sagitta_match: 1e4,
            orientation: 1000.0,
            tolerance: 1e4,
        }
    }
}

/// One optimization stage: proximity weights × `proximity_scale`, at most `iterations` solver
/// iterations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OptimizationStage {
    pub name: String,
    pub proximity_scale: f64,
    pub iterations: usize,
}

/// Parameters of the method ([`super::compute`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StAdaptedParams {
    pub sizing: Sizing,
    /// Edge variant (Fig. 12): intersection circles (a) or bisecting planes (b).
    pub variant: EdgeArcs,
    pub remesh: RemeshParams,
    pub jet: JetParams,
    pub weights: StAdaptedWeights,
    pub stages: Vec<OptimizationStage>,
    /// Refuse when fewer than this fraction of reference vertices have a usable central sphere.
    pub min_usable_fraction: f64,
    /// A vertex is usable when |H| ≥ this × (|k₁| + |k₂|)/2 (and not planar).
    pub min_curvature_ratio: f64,
    /// Initial LM regularization ε of the first stage; later stages continue from the last ε.
    pub initial_epsilon: f64,
    /// Hard-fix the boundary vertices of the remeshed mesh (they lie on the reference boundary).
    pub fix_boundary: bool,
    /// Hard-fix the vertices of remeshed edges whose faces meet at more than
    /// `remesh.feature_angle_deg` (feature curves kept by the remesher).
    pub fix_features: bool,
    /// Radii closer than this (× the bbox diagonal) count as one in the panel schedule.
    pub radius_tolerance: f64,
    /// Move the panels onto fewer moulds after optimizing ([`super::moulds::fewer_moulds`]).
    pub optimize_moulds: bool,
}

impl StAdaptedParams {
    /// Default stages with the given iteration counts per stage (proximity, angle, relax).
    pub fn stages_with(iterations: [usize; 3]) -> Vec<OptimizationStage> {
        let mk = |name: &str, p: f64, it: usize| OptimizationStage { name: name.into(), proximity_scale: p, iterations: it };
        vec![mk("proximity", 10.0, iterations[0]), mk("angle", 1.0, iterations[1]), mk("relax", 0.5, iterations[2])]
    }

    /// The weights the variant uses: variant (b) cuts its arcs by bisecting planes and has no
    /// edge-circle or sagitta-match term.
    pub(crate) fn variant_weights(&self) -> StAdaptedWeights {
        match self.variant {
            EdgeArcs::Intersection => self.weights.clone(),
            EdgeArcs::BisectingPlanes => StAdaptedWeights { edge_circle: 0.0, sagitta_match: 0.0, ..self.weights.clone() },
        }
    }

    /// The tolerance band's half-width, relative to the diagonal: ε/2 of an adaptive sizing, so
    /// that vertices and face centroids stay within ε/2 and the panels, which bulge by about ε
    /// between them, within 2ε. None for a face-count target, which has no ε. The optimization
    /// widens it to the reference's facet sagitta where that is larger (a reference coarser than
    /// ε/2; coarser than ε it is also warned about).
    pub fn tolerance_band(&self) -> Option<f64> {
        self.epsilon().map(|epsilon| 0.5 * epsilon)
    }

    /// How far the panels may lie from the reference, relative to the diagonal (Sec. 3): 2ε, the
    /// band [`Self::tolerance_band`] allows between vertices and centroids and the bulge between
    /// them; 4× the reference's `facet_sagitta` where that is larger, since the optimization's
    /// band widens to it (no smooth panel comes closer to coarse facets). A face-count target,
    /// which has no ε: [`DEFAULT_MAX_DISTANCE`].
    pub fn distance_bound(&self, facet_sagitta: f64) -> f64 {
        self.tolerance_band().map_or(DEFAULT_MAX_DISTANCE, |band| 4.0 * band.max(facet_sagitta))
    }

    /// The tolerance ε of an adaptive sizing, relative to the diagonal (None for a face-count
    /// target or no remeshing).
    pub fn epsilon(&self) -> Option<f64> {
        match self.sizing {
            Sizing::Adaptive { epsilon } => Some(epsilon),
            _ => None,
        }
    }

    /// Solver iterations over all stages.
    pub(crate) fn total_iterations(&self) -> usize {
        self.stages.iter().map(|s| s.iterations).sum()
    }
}

impl Default for StAdaptedParams {
    fn default() -> Self {
        Self {
            sizing: Sizing::Adaptive { epsilon: DEFAULT_EPSILON },
            variant: EdgeArcs::Intersection,
            remesh: RemeshParams::default(),
            jet: JetParams::default(),
            weights: StAdaptedWeights::default(),
            stages: Self::stages_with([5, 15, 25]),
            min_usable_fraction: 0.5,
            min_curvature_ratio: 0.1,
            initial_epsilon: 0.1,
            fix_boundary: true,
            fix_features: true,
            radius_tolerance: 1e-3,
            optimize_moulds: false,
        }
    }
}

impl StAdaptedParams {
    /// Every parameter a design sets, against its range.
    pub fn check(&self) -> Result<(), ParamError> {
        self.sizing.check()?;
        RADIUS_TOLERANCE_RANGE.check(self.radius_tolerance)?;
        Ok(())
    }
}

impl LinkFields for StAdaptedParams {
    fn write_link(&self, link: &mut LinkWriter) {
        self.sizing.write_link("sizing", link);
        link.text("variant", self.variant.key());
        if self.optimize_moulds {
            link.flag("opt_moulds", true);
        }
        if self.radius_tolerance != Self::default().radius_tolerance {
            link.number("rtol", self.radius_tolerance);
        }
    }

    fn read_link(&mut self, link: &mut LinkReader) {
        self.sizing.read_link("sizing", link);
        link.set_parsed("variant", EdgeArcs::from_key, &mut self.variant);
        link.set_flag("opt_moulds", &mut self.optimize_moulds);
        link.set_number("rtol", RADIUS_TOLERANCE_RANGE, &mut self.radius_tolerance);
    }
}
