//! How good a line congruence is for a support structure (Sec. 2.5 (b), (c)): the angles between
//! its lines and the surface normals, and per grid quad whether it has real torsal directions
//! and at which angle their planes meet.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::congruence::torsal::{torsal_pair, TorsalPair};
use crate::stats::{mean, percentile};

use super::radius::SamplingGrid;

/// The figures of a congruence on G.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CongruenceFigures {
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_line_normal_angle_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub mean_line_normal_angle_deg: f64,
    pub quads_without_real_torsal_directions: usize,
    /// Over the quads with real torsal directions (0 when there are none).
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub min_torsal_plane_angle_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub p10_torsal_plane_angle_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub mean_torsal_plane_angle_deg: f64,
}

/// The torsal pair of every quad of G for `lines` (unit, one per point of G).
pub fn torsal_pairs(grid: &SamplingGrid, lines: &[DVec3]) -> Vec<Option<TorsalPair>> {
    (0..grid.quad_count())
        .map(|q| {
            let c = grid.quad(q);
            torsal_pair(c.map(|p| grid.frames[p].point), c.map(|p| lines[p]))
        })
        .collect()
}

/// ∠(l, n) in degrees at every point.
pub(crate) fn line_normal_angles(grid: &SamplingGrid, lines: &[DVec3]) -> Vec<f64> {
    grid.frames.iter().zip(lines).map(|(f, l)| l.normalize_or_zero().dot(f.normal).clamp(-1.0, 1.0).acos().to_degrees()).collect()
}

impl CongruenceFigures {
    pub fn of(grid: &SamplingGrid, lines: &[DVec3], pairs: &[Option<TorsalPair>]) -> Self {
        let angles = line_normal_angles(grid, lines);
        let planes: Vec<f64> = pairs.iter().flatten().map(|p| p.angle_deg).collect();
        Self {
            max_line_normal_angle_deg: angles.iter().copied().fold(0.0, f64::max),
            mean_line_normal_angle_deg: mean(&angles),
            quads_without_real_torsal_directions: pairs.iter().filter(|p| p.is_none()).count(),
            min_torsal_plane_angle_deg: if planes.is_empty() { 0.0 } else { planes.iter().copied().fold(f64::INFINITY, f64::min) },
            p10_torsal_plane_angle_deg: if planes.is_empty() { 0.0 } else { percentile(planes.iter().copied(), 0.1) },
            mean_torsal_plane_angle_deg: mean(&planes),
        }
    }
}

/// Grid points whose line is beyond θ, quads without real torsal directions and quads whose
/// torsal planes meet below α (degrees).
pub fn misses(grid: &SamplingGrid, lines: &[DVec3], pairs: &[Option<TorsalPair>], theta_deg: f64, alpha_deg: f64) -> usize {
    let beyond = line_normal_angles(grid, lines).iter().filter(|&&a| !(a <= theta_deg)).count();
    beyond + pairs.iter().filter(|p| p.is_none_or(|p| !(p.angle_deg >= alpha_deg))).count()
}
