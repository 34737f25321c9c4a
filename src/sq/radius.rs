//! The sampling grid G, the mean-curvature check of Sec. 6.3, and the radius function of Eq. 8.
//!
//! - **G**: n × n parameters, uniform over the domain with both ends; point (i, j) (i along U) at
//!   i + n j; quad (i, j) has corners (i, j), (i+1, j), (i+1, j+1), (i, j+1).
//! - **Sign of H** (Sec. 6.3: the method is limited to shapes without a sign change of the mean
//!   curvature, since it starts from the central spheres, whose radius 1/H is unbounded where
//!   H = 0). H is sampled on a fine grid of cell midpoints (area-weighted shares of each sign) and
//!   on G. A wrong sign or |H| · diag < [`MIN_MEAN_CURVATURE`] inside the strip between the
//!   boundary and G's second row is a warning (CAD surfaces often curl at their edges), and those
//!   grid points are left out of the fit. So is a *speck* of the other sign inside: at most
//!   [`MAX_SPECK_SHARE`] of the area, bending a panel the wrong way by at most
//!   [`SPECK_TOLERANCE`] of the diagonal, so that spheres of the dominant sign still approximate
//!   it. Anything more refuses the central start and says where; the method then starts from
//!   constant radii alone ([`crate::sq::start`]), which exist whatever the sign of H.
//! - **Radius**: r_ij = 1/H at the points of G, fitted by least squares with a clamped uniform
//!   B-spline basis ([`crate::sq::params::RadiusBasis`]; Eq. 8 puts r on f's basis, which would
//!   have as many coefficients as G has points; the authors' code fits 36).

// Negated float comparisons are deliberate: they also reject NaN.

use crate::geometry::bspline::{BSplineBasis, BSplineFunction, BSplineSurface, FitError, SurfaceFrame};
use crate::reference::assumptions::Warning;
use crate::sq::params::RadiusBasis;

use super::error::SqError;

/// Smallest |H| · diag accepted at a point of G.
pub const MIN_MEAN_CURVATURE: f64 = 1e-2;
/// Cells per direction of the fine grid that measures the sign of H.
pub(crate) const SIGN_GRID: usize = 200;

/// The corners of quad q = i + (n − 1) j of an n × n grid: (i, j), (i+1, j), (i+1, j+1), (i, j+1).
pub(crate) fn grid_quad(n: usize, q: usize) -> [usize; 4] {
    let (i, j) = (q % (n - 1), q / (n - 1));
    [i + n * j, i + 1 + n * j, i + 1 + n * (j + 1), i + n * (j + 1)]
}

/// The sampling grid G with the surface's frames.
#[derive(Clone, Debug)]
pub struct SamplingGrid {
    pub n: usize,
    pub uv: Vec<[f64; 2]>,
    pub frames: Vec<SurfaceFrame>,
}

impl SamplingGrid {
    pub fn new(surface: &BSplineSurface, n: usize) -> Result<Self, SqError> {
        let ((u0, u1), (v0, v1)) = surface.domain();
        let at = |a: f64, b: f64, k: usize| {
            if k + 1 == n {
                b
            } else {
                a + (b - a) * k as f64 / (n - 1) as f64
            }
        };
        let uv: Vec<[f64; 2]> = (0..n).flat_map(|j| (0..n).map(move |i| [at(u0, u1, i), at(v0, v1, j)])).collect();
        let frames = uv.iter().map(|p| surface.frame(p[0], p[1]).ok_or(SqError::Singular { uv: *p })).collect::<Result<Vec<_>, _>>()?;
        Ok(Self { n, uv, frames })
    }

    pub(crate) fn point_count(&self) -> usize {
        self.n * self.n
    }

    pub(crate) fn quad_count(&self) -> usize {
        (self.n - 1) * (self.n - 1)
    }

    /// The corners of quad q = i + (n − 1) j.
    pub fn quad(&self, q: usize) -> [usize; 4] {
        grid_quad(self.n, q)
    }

    /// Whether point p lies on G's outer ring.
    pub fn on_boundary(&self, p: usize) -> bool {
        let (i, j) = (p % self.n, p / self.n);
        i == 0 || j == 0 || i + 1 == self.n || j + 1 == self.n
    }
}

/// How the mean curvature's sign looks over the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct MeanCurvatureSigns {
    /// Area shares of H > 0 and H < 0 (fine grid).
    pub positive_share: f64,
    pub negative_share: f64,
    /// +1 or −1: the sign over most of the area.
    pub sign: f64,
    /// Points of G with the other sign or |H| · diag < [`MIN_MEAN_CURVATURE`] (left out of the
    /// fit): in the boundary strip or in a speck, else the check refuses.
    pub excluded: Vec<usize>,
    /// When H turns in the boundary strip, and when a speck of the other sign is run through.
    pub warnings: Vec<Warning>,
}

/// Largest share of the area a speck of the other sign of H may cover inside the patch.
pub const MAX_SPECK_SHARE: f64 = 0.05;
/// A speck of the other sign is run through when, over one panel of the mesh asked for (edge
/// h = √(area / faces)), the surface bends the wrong way by at most this much of the diagonal:
/// max |H| · h² / 8 over the speck, the sagitta a panel of the dominant sign (at most a plane)
/// cannot follow.
pub const SPECK_TOLERANCE: f64 = 1e-3;

/// At most this share of G's points inside the patch may be left out of the radius fit.
pub(crate) const MAX_EXCLUDED_SHARE: f64 = 0.25;

/// A cell of the fine grid: (u, v, H, area element).
type SignCell = (f64, f64, f64, f64);

/// The cells of the fine grid as (u, v, H, area element), the area shares of H > 0 and H < 0,
/// and the total of the area elements with a sign.
fn sign_cells(surface: &BSplineSurface) -> (Vec<SignCell>, [f64; 2], f64) {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let (mut pos, mut neg) = (0.0, 0.0);
    let mut cells = Vec::with_capacity(SIGN_GRID * SIGN_GRID);
    for j in 0..SIGN_GRID {
        for i in 0..SIGN_GRID {
            let (u, v) = (u0 + (u1 - u0) * (i as f64 + 0.5) / SIGN_GRID as f64, v0 + (v1 - v0) * (j as f64 + 0.5) / SIGN_GRID as f64);
            let d = surface.derivatives(u, v);
            let area = d.su.cross(d.sv).length();
            let h = d.frame().map_or(0.0, |f| f.mean);
            if h > 0.0 {
                pos += area;
            } else if h < 0.0 {
                neg += area;
            }
            cells.push((u, v, h, area));
        }
    }
    let total = (pos + neg).max(f64::MIN_POSITIVE);
    (cells, [pos / total, neg / total], total)
}

/// The area shares of H > 0 and H < 0 over the patch (fine grid).
pub fn mean_curvature_shares(surface: &BSplineSurface) -> [f64; 2] {
    sign_cells(surface).1
}

/// The sign check of the module docs; `diag` is the bounding-box diagonal and `faces` the
/// number of panels asked for (the panel size of the speck test).
pub fn check_mean_curvature(surface: &BSplineSurface, grid: &SamplingGrid, diag: f64, faces: usize) -> Result<MeanCurvatureSigns, SqError> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let n = grid.n;
    // The strip between the boundary and G's second row, in parameters.
    let (su, sv) = ((u1 - u0) / (n - 1) as f64, (v1 - v0) / (n - 1) as f64);
    let in_strip = |u: f64, v: f64| u < u0 + su || u > u1 - su || v < v0 + sv || v > v1 - sv;
    let (cells, [positive_share, negative_share], total) = sign_cells(surface);
    let sign = if positive_share >= negative_share { 1.0 } else { -1.0 };
    let wrong = |h: f64| !(h * sign * diag >= MIN_MEAN_CURVATURE);
    // The speck: cells of the other sign inside the patch.
    let (mut speck_area, mut worst, mut worst_uv) = (0.0, 0.0f64, [u0, v0]);
    for &(u, v, h, area) in &cells {
        if h * sign < 0.0 && !in_strip(u, v) {
            speck_area += area;
            if h.abs() > worst {
                (worst, worst_uv) = (h.abs(), [u, v]);
            }
        }
    }
    let speck_share = speck_area / total;
    let area = total * (u1 - u0) * (v1 - v0) / (SIGN_GRID * SIGN_GRID) as f64;
    // The sagitta |H| h² / 8 over a panel of edge h = √(area / faces).
    let bend = |h: f64| h.abs() * area / faces.max(1) as f64 / 8.0;
    let sagitta = bend(worst);
    let refusal = SqError::MeanCurvatureSignChange { positive_share, negative_share, at: Some(worst_uv) };
    if speck_area > 0.0 && !(speck_share <= MAX_SPECK_SHARE && sagitta <= SPECK_TOLERANCE * diag) {
        return Err(refusal);
    }
    let mut excluded = Vec::new();
    let mut in_speck = 0;
    for (p, f) in grid.frames.iter().enumerate() {
        if wrong(f.mean) {
            let uv = grid.uv[p];
            if !in_strip(uv[0], uv[1]) {
                // Inside: a point of the speck, or where H nearly vanishes, bending the wrong way
                // by at most the speck's tolerance over a panel.
                if !(bend(f.mean) <= SPECK_TOLERANCE * diag) || (f.mean * sign < 0.0 && speck_area == 0.0) {
                    return Err(if f.mean * sign < 0.0 { refusal } else { SqError::MeanCurvatureNearZero { uv, h_diag: f.mean * diag } });
                }
                in_speck += 1;
            }
            excluded.push(p);
        }
    }
    if excluded.len() == grid.point_count() || in_speck as f64 > MAX_EXCLUDED_SHARE * grid.point_count() as f64 {
        return Err(match excluded.iter().find(|&&p| grid.frames[p].mean * sign >= 0.0) {
            Some(&p) if speck_area == 0.0 => SqError::MeanCurvatureNearZero { uv: grid.uv[p], h_diag: grid.frames[p].mean * diag },
            _ => refusal,
        });
    }
    let mut warnings = Vec::new();
    let strip_flips = cells.iter().any(|&(u, v, h, _)| h * sign < 0.0 && in_strip(u, v)) || excluded.len() > in_speck;
    let other_positive = sign < 0.0;
    if strip_flips {
        warnings.push(Warning::MeanCurvatureTurnsNearBoundary {
            other_positive,
            share_percent: 100.0 * if sign > 0.0 { negative_share } else { positive_share } - 100.0 * speck_share,
            left_out: excluded.len() - in_speck,
            grid_points: grid.point_count(),
        });
    }
    if speck_area > 0.0 || in_speck > 0 {
        warnings.push(Warning::MeanCurvatureSpeck {
            other_positive,
            share_percent: 100.0 * speck_share,
            uv: worst_uv,
            max_abs_mean: worst,
            sagitta: sagitta / diag,
            left_out: in_speck,
            grid_points: grid.point_count(),
        });
    }
    Ok(MeanCurvatureSigns { positive_share, negative_share, sign, excluded, warnings })
}

/// The fitted radius function and how well it matches r = 1/H on G.
#[derive(Clone, Debug)]
pub struct RadiusFit {
    pub function: BSplineFunction,
    pub error: FitError,
    /// `error.max` divided by the mean |r| of the samples.
    pub relative_error: f64,
    /// Samples used (G's points minus the excluded ones).
    pub samples: usize,
}

/// The radius basis `basis` on the surface's domain, in U and V.
fn radius_bases(surface: &BSplineSurface, basis: RadiusBasis) -> Result<(BSplineBasis, BSplineBasis), SqError> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let make =
        |lo: f64, hi: f64| BSplineBasis::clamped_uniform(basis.degree, basis.controls, (lo, hi)).map_err(|e| SqError::RadiusBasis(e.to_string()));
    Ok((make(u0, u1)?, make(v0, v1)?))
}

/// r ≡ `r` on the basis `basis` (where the central radii 1/H do not exist: no fit, no error).
pub fn constant_radius_fit(surface: &BSplineSurface, basis: RadiusBasis, r: f64) -> Result<RadiusFit, SqError> {
    let (u, v) = radius_bases(surface, basis)?;
    let coefficients = vec![r; u.count() * v.count()];
    let error = FitError { rms: 0.0, max: 0.0 };
    Ok(RadiusFit { function: BSplineFunction { u, v, coefficients }, error, relative_error: 0.0, samples: 0 })
}

/// Fits r = 1/H over G (minus `excluded`) with the basis `basis` on the surface's domain.
pub fn fit_radius(surface: &BSplineSurface, grid: &SamplingGrid, basis: RadiusBasis, excluded: &[usize]) -> Result<RadiusFit, SqError> {
    let (bu, bv) = radius_bases(surface, basis)?;
    let samples: Vec<([f64; 2], f64)> =
        (0..grid.point_count()).filter(|p| !excluded.contains(p)).map(|p| (grid.uv[p], 1.0 / grid.frames[p].mean)).collect();
    let (function, error) =
        BSplineFunction::fit(bu, bv, &samples).ok_or(SqError::RadiusFit { samples: samples.len(), coefficients: basis.controls * basis.controls })?;
    let mean = samples.iter().map(|s| s.1.abs()).sum::<f64>() / samples.len() as f64;
    Ok(RadiusFit { function, error, relative_error: error.max / mean, samples: samples.len() })
}
