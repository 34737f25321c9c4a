//! The parameters of the SQ method (Sec. 5) with their defaults, written once: Tables 1 and 2 for
//! the weights, the authors' radius basis for Eq. 8.

use serde::{Deserialize, Serialize};

use crate::congruence::support_structure::{AXIS_LENGTH_RANGE, SUPPORT_DEPTH_RANGE};
use crate::panels::buildability::{write_max_distance, DEFAULT_MAX_DISTANCE, MAX_DISTANCE_RANGE};
use crate::panels::RADIUS_TOLERANCE_RANGE;
use crate::params::{LinkFields, LinkReader, LinkWriter, ParamRange};

/// How an inequality (∠(l, n) ≤ θ, torsal planes meeting at ≥ α) enters the energy. Measured on
/// `tunnel_arch` and the vault (θ 20°, α 75°): with slacks, step 1 stalls at E_LC ≈ 4e-5 per term
/// (the slacks stick at 0, as the authors found); with hinges it reaches 1e-30.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Inequality {
    /// One-sided residual max(0, g), as the authors' later code does.
    #[default]
    Hinge,
    /// The paper's dummy variable: g + μ² (a residual, μ a variable).
    Slack,
}

/// Where the congruence optimization starts (Sec. 5.1, Sec. 6.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RadiusStart {
    /// Constant radii first; when the SQ mesh from them misses a guarantee, the central
    /// congruence r = 1/H (Sec. 5.1), whose spheres fit the surface best (Sec. 2.6), and the
    /// result that misses fewer guarantees. Where H changes sign or vanishes, constant radii
    /// alone. Run only as far as the congruence or the quad mesh, the start whose congruence
    /// misses θ and α on fewer points of G.
    #[default]
    Auto,
    /// The central congruence only.
    Central,
    /// Constant radii: the normal congruence of f, whose torsal directions are the principal
    /// directions and whose torsal planes are orthogonal (Sec. 2.5, θ = 0), the start Sec. 6.3
    /// names for the other curvature restriction.
    Constant,
}

impl RadiusStart {
    pub const ALL: [RadiusStart; 3] = [RadiusStart::Auto, RadiusStart::Central, RadiusStart::Constant];

    /// The starts tried, in order.
    pub fn starts(self) -> &'static [RadiusStart] {
        match self {
            RadiusStart::Auto => &[RadiusStart::Constant, RadiusStart::Central],
            RadiusStart::Central => &[RadiusStart::Central],
            RadiusStart::Constant => &[RadiusStart::Constant],
        }
    }

    pub fn key(self) -> &'static str {
        match self {
            RadiusStart::Auto => "auto",
            RadiusStart::Central => "central",
            RadiusStart::Constant => "constant",
        }
    }

    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.key() == key)
    }
}

/// The radius function's basis (Eq. 8): clamped, uniform, `controls` × `controls` coefficients.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RadiusBasis {
    pub degree: usize,
    pub controls: usize,
}

impl Default for RadiusBasis {
    /// The authors' code: degree 5, 6 × 6 coefficients.
    fn default() -> Self {
        Self { degree: 5, controls: 6 }
    }
}

/// Weights of the line-congruence step (Sec. 5.1, Table 1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LineCongruenceWeights {
    pub lc: f64,
    pub lc_orth: f64,
    /// |l| = 1.
    pub unit: f64,
}

impl Default for LineCongruenceWeights {
    fn default() -> Self {
        Self { lc: 1.0, lc_orth: 2.0, unit: 1.0 }
    }
}

/// Weights of the torsal step (Sec. 5.1, Table 2, except w_LC_orth: with Table 2's 0.01 the
/// lines of `tunnel_arch` leave the θ cone by 0.6°–1.6° during the torsal step; 1 keeps them in).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TorsalWeights {
    pub lc: f64,
    pub lc_orth: f64,
    pub torsal: f64,
    pub angle: f64,
    pub fair: f64,
    pub reg: f64,
    /// |l| = 1, |t| = 1 and |n*| = 1.
    pub unit: f64,
}

impl Default for TorsalWeights {
    fn default() -> Self {
        Self { lc: 1.0, lc_orth: 1.0, torsal: 1.0, angle: 2.0, fair: 0.1, reg: 0.05, unit: 1.0 }
    }
}

/// Weights of the final sphere-congruence optimization (Eq. 10, Table 3's first row and defaults).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SphereWeights {
    pub sphere: f64,
    pub unit: f64,
    pub supp: f64,
    /// E_supp during the warm-up ("a small value for the support structure").
    pub warm_up_supp: f64,
    pub torsal_plane: f64,
    pub prox_f: f64,
    pub prox_c: f64,
    /// Each panel through the reference at its face's centre
    /// ([`crate::sq::sphere_terms::PanelProximity`]; not in Eq. 10).
    pub prox_panel: f64,
    /// The boundary vertices' distance to the patch's boundary curve, so that the panels keep
    /// covering the patch ([`crate::reference::proximity::BoundaryProximity`]; not in Eq. 10).
    pub prox_boundary: f64,
    /// ε of the point-distance part of E_prox.
    pub epsilon: f64,
    pub fair: f64,
    pub reg_sphere: f64,
    pub reg_normal: f64,
    /// The support planes at a node meeting at ≥ α, and the node axes within θ of the normals
    /// (hinges; not in Eq. 10, see [`super::sphere_terms`]).
    pub support_angle: f64,
    pub axis_angle: f64,
}

impl Default for SphereWeights {
    fn default() -> Self {
        Self {
            sphere: 2.0,
            unit: 10.0,
            supp: 0.5,
            warm_up_supp: 0.05,
            torsal_plane: 0.01,
            prox_f: 1.0,
            prox_c: 0.1,
            prox_panel: 1.0,
            prox_boundary: 10.0,
            epsilon: 0.01,
            fair: 0.2,
            reg_sphere: 0.04,
            reg_normal: 0.05,
            support_angle: 1.0,
            axis_angle: 1.0,
        }
    }
}

/// How far the method runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Until {
    /// Sec. 5.1: the optimized congruence and its torsal cross field.
    Congruence,
    /// Sec. 5.2, first part: the quad mesh along the cross field and Q′.
    Remesh,
    /// The whole method: the SQ mesh with panels, support structure and node axes.
    #[default]
    Final,
}

impl Until {
    pub const ALL: [Until; 3] = [Until::Congruence, Until::Remesh, Until::Final];

    pub fn key(self) -> &'static str {
        match self {
            Until::Congruence => "congruence",
            Until::Remesh => "remesh",
            Until::Final => "final",
        }
    }

    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|u| u.key() == key)
    }
}

/// The SQ method's parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SqParams {
    /// Grid points per parameter direction of the sampling grid G.
    pub grid: usize,
    /// Largest angle between a line of the congruence and the surface normal (degrees).
    pub theta_deg: f64,
    /// Smallest angle between the two torsal planes (degrees).
    pub alpha_deg: f64,
    /// The optimization aims at θ − margins[0] and α + margins[1] (degrees): the soft terms
    /// (w_angle = 0 in the final iterations) let the result drift back by about that much, and θ
    /// and α are to be met.
    pub margins_deg: [f64; 2],
    pub radius_basis: RadiusBasis,
    /// The starting sphere congruence.
    pub start: RadiusStart,
    pub inequality: Inequality,
    /// Iterations of the line-congruence step (at most; it stops when converged).
    pub lc_iterations: usize,
    pub lc_weights: LineCongruenceWeights,
    /// Iterations of the torsal step.
    pub torsal_iterations: usize,
    /// RS: the torsal directions and plane normals are recomputed every this many iterations.
    pub recompute_every: usize,
    /// The last iterations run with w_angle = w_fair = 0.
    pub final_iterations: usize,
    pub torsal_weights: TorsalWeights,
    /// How far to run.
    pub until: Until,
    /// Quads to aim at in the remesh (Sec. 5.2).
    pub faces: usize,
    /// Iterations of the glide fairing that turns the remesh into Q′.
    pub fairing_iterations: usize,
    /// Weight of the polyline fairness against the glide terms in Q′.
    pub fairing_weight: f64,
    /// Iterations of the final optimization: warm-up, full (Eq. 10), projection to exactness.
    pub sphere_iterations: [usize; 3],
    /// The full optimization stops when [`Self::sphere_decrease_window`] iterations together
    /// lower its energy by at most this fraction. Its descent is slow and steady (at 100
    /// iterations a step still lowers it by 0.05 %, and moves vertices by 6e-5 of the diagonal
    /// that the projection after it then moves by 1e-3), so a window sees where it flattens:
    /// on the corpora it ends after 30–60 iterations with the same verdicts, exactness on the
    /// same runs and distances within a few percent either way. Where the descent hovers at
    /// the tolerance the stop moves with rounding (the vault: 20, 34 or 64 iterations as its
    /// control points move by 1e-15), and the figures with it.
    pub sphere_decrease_tolerance: f64,
    /// Iterations over which [`Self::sphere_decrease_tolerance`] is measured.
    pub sphere_decrease_window: usize,
    pub sphere_weights: SphereWeights,
    /// Depth of the support elements, relative to the bounding-box diagonal.
    pub support_depth: f64,
    /// Length of the displayed node axes, relative to the diagonal.
    pub axis_length: f64,
    /// Radii closer than this (relative to the diagonal) count as one in the schedule.
    pub radius_tolerance: f64,
    /// Move the exact mesh onto fewer moulds, its panels snapped to their radii
    /// ([`super::moulds`]).
    pub optimize_moulds: bool,
    /// The panels' promised distance to the reference, relative to the diagonal
    /// ([`crate::panels::buildability::DEFAULT_MAX_DISTANCE`]).
    pub max_distance: f64,
}

impl Default for SqParams {
    fn default() -> Self {
        Self {
            grid: 20,
            theta_deg: 20.0,
            alpha_deg: 75.0,
            margins_deg: [1.0, 3.0],
            radius_basis: RadiusBasis::default(),
            start: RadiusStart::default(),
            inequality: Inequality::default(),
            lc_iterations: 100,
            lc_weights: LineCongruenceWeights::default(),
            torsal_iterations: 100,
            recompute_every: 10,
            final_iterations: 10,
            torsal_weights: TorsalWeights::default(),
            until: Until::default(),
            faces: 237,
            fairing_iterations: 10,
            fairing_weight: 0.002,
            sphere_iterations: [5, 100, 60],
            sphere_decrease_tolerance: 1e-2,
            sphere_decrease_window: 10,
            sphere_weights: SphereWeights::default(),
            support_depth: 0.02,
            axis_length: 0.06,
            radius_tolerance: 1e-3,
            optimize_moulds: false,
            max_distance: DEFAULT_MAX_DISTANCE,
        }
    }
}

impl SqParams {
    /// Every parameter against its range, checked once here.
    pub fn check(&self) -> Result<(), ParamError> {
        GRID_RANGE.check(self.grid)?;
        THETA_RANGE.check(self.theta_deg)?;
        ALPHA_RANGE.check(self.alpha_deg)?;
        FACES_RANGE.check(self.faces)?;
        SUPPORT_DEPTH_RANGE.check(self.support_depth)?;
        AXIS_LENGTH_RANGE.check(self.axis_length)?;
        RADIUS_TOLERANCE_RANGE.check(self.radius_tolerance)?;
        RECOMPUTE_RANGE.check(self.recompute_every)?;
        MAX_DISTANCE_RANGE.check(self.max_distance)?;
        let b = self.radius_basis;
        if !RADIUS_DEGREE_RANGE.contains(b.degree) || b.controls <= b.degree || !RADIUS_CONTROLS_RANGE.contains(b.controls) {
            return Err(ParamError::RadiusBasis { degree: b.degree, controls: b.controls });
        }
        let mut p = self.clone();
        for (key, field, range) in LINK_NUMBERS {
            range.check(*field(&mut p)).map_err(|e| ParamError::OutOfRange(crate::params::ParamError { name: key, ..e }))?;
        }
        for (key, field, range) in LINK_COUNTS {
            range.check(*field(&mut p)).map_err(|e| ParamError::OutOfRange(crate::params::ParamError { name: key, ..e }))?;
        }
        Ok(())
    }

    /// The angle the line-normal term aims at: θ − margins[0] (at least half of θ).
    pub(crate) fn target_theta_deg(&self) -> f64 {
        (self.theta_deg - self.margins_deg[0]).max(0.5 * self.theta_deg)
    }

    /// The angle the torsal-angle term aims at: α + margins[1] (at most 90°).
    pub(crate) fn target_alpha_deg(&self) -> f64 {
        (self.alpha_deg + self.margins_deg[1]).min(90.0)
    }
}

/// Why [`SqParams::check`] refuses the parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamError {
    OutOfRange(crate::params::ParamError),
    RadiusBasis { degree: usize, controls: usize },
}

impl From<crate::params::ParamError> for ParamError {
    fn from(e: crate::params::ParamError) -> Self {
        ParamError::OutOfRange(e)
    }
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamError::OutOfRange(e) => e.fmt(f),
            ParamError::RadiusBasis { degree, controls } => write!(
                f,
                "radius basis: degree {degree} with {controls} coefficients per direction (degree {}..={}, more coefficients than the degree, at most {})",
                RADIUS_DEGREE_RANGE.lo, RADIUS_DEGREE_RANGE.hi, RADIUS_CONTROLS_RANGE.hi
            ),
        }
    }
}

impl std::error::Error for ParamError {}

/// The accepted ranges.
pub const GRID_RANGE: ParamRange<usize> = ParamRange::new("grid", 4, 100);
pub const THETA_RANGE: ParamRange<f64> = ParamRange::new("θ", 1.0, 89.0);
pub const ALPHA_RANGE: ParamRange<f64> = ParamRange::new("α", 1.0, 90.0);
pub const RECOMPUTE_RANGE: ParamRange<usize> = ParamRange::new("RS", 1, 1000);
/// Quads: about what finishes within a minute and 1 GB natively on 2 cores. Measured at 3000
/// on the degree-10 `hard/roof_rough`: 2964 quads, exact, 61 s and 0.55 GB (the sparse
/// factorization of the final optimization is 80 % of it and grows as N^1.8); with --faces 5000
/// `tunnel_arch` took 23 s and 0.52 GB, `paraboloid_dome` 77 s and 0.72 GB.
pub const FACES_RANGE: ParamRange<usize> =
    ParamRange::new("faces", 4, 3_000).bounded_by("more quads than SQ finishes within a minute and 1 GB natively");
/// The radius function's degree and coefficients per direction (Eq. 8).
pub const RADIUS_DEGREE_RANGE: ParamRange<usize> = ParamRange::new("radius degree", 1, 15);
pub const RADIUS_CONTROLS_RANGE: ParamRange<usize> = ParamRange::new("radius coefficients", 2, 40);
/// Iterations of a step, and a term's weight.
pub const ITERATIONS_RANGE: ParamRange<usize> = ParamRange::new("iterations", 0, 10_000);
pub const WEIGHT_RANGE: ParamRange<f64> = ParamRange::new("weight", 0.0, 1e6);

/// A parameter of the link's advanced fields, by its key.
type LinkNumber = (&'static str, fn(&mut SqParams) -> &mut f64, ParamRange<f64>);
type LinkCount = (&'static str, fn(&mut SqParams) -> &mut usize, ParamRange<usize>);

/// `[(key, accessor, range)]` of fields of [`SqParams`] of type `$ty`.
macro_rules! link_fields {
    ($ty:ty; $($key:literal => ($($path:tt)+), $range:expr;)*) => {
        [$(($key, {
            fn get(p: &mut SqParams) -> &mut $ty {
                &mut p.$($path)+
            }
            get as fn(&mut SqParams) -> &mut $ty
        }, $range)),*]
    };
}

/// The design link's numbers beyond the main ones, written when not their defaults.
const LINK_NUMBERS: [LinkNumber; 17] = link_fields!(f64;
    "depth" => (support_depth), SUPPORT_DEPTH_RANGE;
    "axis" => (axis_length), AXIS_LENGTH_RANGE;
    "rtol" => (radius_tolerance), RADIUS_TOLERANCE_RANGE;
    "w_lc1" => (lc_weights.lc), WEIGHT_RANGE;
    "w_orth1" => (lc_weights.lc_orth), WEIGHT_RANGE;
    "w_lc2" => (torsal_weights.lc), WEIGHT_RANGE;
    "w_orth2" => (torsal_weights.lc_orth), WEIGHT_RANGE;
    "w_torsal" => (torsal_weights.torsal), WEIGHT_RANGE;
    "w_angle" => (torsal_weights.angle), WEIGHT_RANGE;
    "w_fair2" => (torsal_weights.fair), WEIGHT_RANGE;
    "w_reg" => (torsal_weights.reg), WEIGHT_RANGE;
    "w_sphere" => (sphere_weights.sphere), WEIGHT_RANGE;
    "w_supp" => (sphere_weights.supp), WEIGHT_RANGE;
    "w_tplane" => (sphere_weights.torsal_plane), WEIGHT_RANGE;
    "w_prox_f" => (sphere_weights.prox_f), WEIGHT_RANGE;
    "w_prox_c" => (sphere_weights.prox_c), WEIGHT_RANGE;
    "w_fair3" => (sphere_weights.fair), WEIGHT_RANGE;
);

/// The design link's counts beyond the main ones, written when not their defaults (the radius
/// basis is read and checked whole, in [`SqParams::check`]).
const LINK_COUNTS: [LinkCount; 6] = link_fields!(usize;
    "lc_it" => (lc_iterations), ITERATIONS_RANGE;
    "tor_it" => (torsal_iterations), ITERATIONS_RANGE;
    "last_it" => (final_iterations), ITERATIONS_RANGE;
    "final_it" => (sphere_iterations[1]), ITERATIONS_RANGE;
    "r_deg" => (radius_basis.degree), RADIUS_DEGREE_RANGE;
    "r_coef" => (radius_basis.controls), RADIUS_CONTROLS_RANGE;
);

impl LinkFields for SqParams {
    fn write_link(&self, link: &mut LinkWriter) {
        link.number("theta", self.theta_deg);
        link.number("alpha", self.alpha_deg);
        link.count("grid", self.grid);
        link.count("rs", self.recompute_every);
        link.count("faces", self.faces);
        link.text("until", self.until.key());
        // The starting congruence only when not the default, so older links stay as they were.
        if self.start != RadiusStart::Auto {
            link.text("start", self.start.key());
        }
        if self.optimize_moulds {
            link.flag("opt_moulds", true);
        }
        write_max_distance(link, self.max_distance);
        let (mut p, mut d) = (self.clone(), SqParams::default());
        for (key, field, _) in LINK_NUMBERS {
            if *field(&mut p) != *field(&mut d) {
                link.number(key, *field(&mut p));
            }
        }
        for (key, field, _) in LINK_COUNTS {
            if *field(&mut p) != *field(&mut d) {
                link.count(key, *field(&mut p));
            }
        }
    }

    fn read_link(&mut self, link: &mut LinkReader) {
        link.set_number("theta", THETA_RANGE, &mut self.theta_deg);
        link.set_number("alpha", ALPHA_RANGE, &mut self.alpha_deg);
        link.set_count("grid", GRID_RANGE, &mut self.grid);
        link.set_count("rs", RECOMPUTE_RANGE, &mut self.recompute_every);
        link.set_count("faces", FACES_RANGE, &mut self.faces);
        link.set_parsed("until", Until::from_key, &mut self.until);
        link.set_parsed("start", RadiusStart::from_key, &mut self.start);
        link.set_flag("opt_moulds", &mut self.optimize_moulds);
        link.set_number("max_dist", MAX_DISTANCE_RANGE, &mut self.max_distance);
        for (key, field, range) in LINK_NUMBERS {
            link.set_number(key, range, field(self));
        }
        for (key, field, range) in LINK_COUNTS {
            link.set_count(key, range, field(self));
        }
    }
}

/// How far below the bound of a singular vertex its support planes may meet (degrees).
pub(crate) const SINGULAR_MARGIN_DEG: f64 = 1.0;

/// The projection's hinges keep θ and α by this much (degrees): its last, pure Gauss–Newton
/// steps may still move the angles by a few tenths.
pub(crate) const PROJECTION_MARGIN_DEG: f64 = 0.5;
