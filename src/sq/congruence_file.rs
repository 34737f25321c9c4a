//! What the SQ congruence stage writes (Sec. 5.1): the data of `congruence.json` and the display
//! segments of `congruence.glb` (written by the stage, `crate::pipeline::stages::sq`).
//!
//! `congruence.json`, lengths in model units:
//! ```json
//! {"grid": n, "domain": [[u0, u1], [v0, v1]], "theta_deg": θ, "alpha_deg": α,
//!  "radius": {"basis": {"degree": 5, "controls": 6}, "coefficients": [...]},
//!  "points": [{"uv": [u, v], "f": [x, y, z], "n": [...], "r": r, "l": [...], "initial_l": [...]}, ...],
//!  "quads": [{"corners": [p0, p1, p2, p3], "torsal_plane_angle_deg": x,
//!             "torsal": [{"direction": [...], "uv": [du, dv], "plane_normal": [...]}, {...}]}, ...]}
//! ```
//! Point (i, j) of G (i along u) is at i + n j; quad (i, j) at i + (n − 1) j with corners (i, j),
//! (i+1, j), (i+1, j+1), (i, j+1). A quad without real torsal directions has `torsal` and
//! `torsal_plane_angle_deg` null. Torsal directions are unit in 3D and in the (u, v) domain.
//!
//! `congruence.glb`: the reference (node `surface`), the optimized lines and the lines of the
//! central congruence as segments (`lines`, `initial_lines`), the torsal cross field
//! (`cross_field`) and the outlines of the quads without real torsal directions
//! (`quads_without_real_torsal_directions`); `asset.extras` holds θ, α and the figures.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::params::RadiusBasis;
use super::radius::grid_quad;
use super::segments::{cross_field, grid_spacing, line_segments, quad_outlines, CROSS_LENGTH, LINE_LENGTH};
use super::SqCongruence;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CongruenceJson {
    pub grid: usize,
    pub domain: [[f64; 2]; 2],
    pub theta_deg: f64,
    pub alpha_deg: f64,
    pub radius: RadiusJson,
    pub points: Vec<PointJson>,
    pub quads: Vec<QuadJson>,
}

/// r(u, v) in model units on the clamped uniform basis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RadiusJson {
    pub basis: RadiusBasis,
    pub coefficients: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointJson {
    pub uv: [f64; 2],
    pub f: [f64; 3],
    pub n: [f64; 3],
    pub r: f64,
    pub l: [f64; 3],
    pub initial_l: [f64; 3],
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuadJson {
    pub corners: [usize; 4],
    pub torsal_plane_angle_deg: Option<f64>,
    pub torsal: Option<[TorsalJson; 2]>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TorsalJson {
    pub direction: [f64; 3],
    pub uv: [f64; 2],
    pub plane_normal: [f64; 3],
}

impl CongruenceJson {
    pub fn of(c: &SqCongruence, theta_deg: f64, alpha_deg: f64, domain: [[f64; 2]; 2]) -> Self {
        let points = (0..c.points.len())
            .map(|p| PointJson {
                uv: c.uv[p],
                f: c.points[p].to_array(),
                n: c.normals[p].to_array(),
                r: c.radii[p],
                l: c.lines[p].to_array(),
                initial_l: c.initial_lines[p].to_array(),
            })
            .collect();
        let quads = c
            .torsal
            .iter()
            .zip(&c.torsal_uv)
            .enumerate()
            .map(|(q, (pair, uv))| QuadJson {
                corners: grid_quad(c.grid, q),
                torsal_plane_angle_deg: pair.map(|p| p.angle_deg),
                torsal: pair.zip(*uv).map(|(p, uv)| {
                    [0, 1].map(|k| TorsalJson { direction: p.t[k].to_array(), uv: uv[k], plane_normal: p.plane_normals[k].to_array() })
                }),
            })
            .collect();
        Self {
            grid: c.grid,
            domain,
            theta_deg,
            alpha_deg,
            radius: RadiusJson { basis: c.radius_basis, coefficients: c.radius.coefficients.clone() },
            points,
            quads,
        }
    }

    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string(self).expect("the congruence serializes");
        s.push('\n');
        s
    }
}

/// The congruence as display segments (see [`crate::sq::segments`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CongruenceSegments {
    pub lines: Vec<(DVec3, DVec3)>,
    pub initial_lines: Vec<(DVec3, DVec3)>,
    pub cross_field: Vec<(DVec3, DVec3)>,
    /// The torsal-plane angle of each cross-field arm's quad (degrees).
    pub cross_field_angle_deg: Vec<f64>,
    pub no_real_quads: Vec<(DVec3, DVec3)>,
}

impl CongruenceSegments {
    pub fn of(c: &SqCongruence) -> Self {
        let spacing = grid_spacing(c.grid, &c.points);
        let (cross, angles) = cross_field(c.grid, &c.points, &c.torsal, CROSS_LENGTH * spacing);
        Self {
            lines: line_segments(&c.points, &c.lines, LINE_LENGTH * spacing),
            initial_lines: line_segments(&c.points, &c.initial_lines, LINE_LENGTH * spacing),
            cross_field: cross,
            cross_field_angle_deg: angles,
            no_real_quads: quad_outlines(c.grid, &c.points, &c.torsal),
        }
    }
}
