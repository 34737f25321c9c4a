//! The congruence on G as line segments, for the viewer and the exports: the lines over the
//! surface (Fig. 21), the torsal cross field (Fig. 23) and the outlines of the quads without real
//! torsal directions. Lengths follow the mean spacing of G.

use glam::DVec3;

use crate::congruence::torsal::TorsalPair;

use super::radius::grid_quad;

/// Line segments drawn per line of the congruence: this many grid spacings long.
pub(crate) const LINE_LENGTH: f64 = 1.5;
/// Each arm of the cross field: this share of the grid spacing, centred at the quad's centre.
pub(crate) const CROSS_LENGTH: f64 = 0.7;

/// Mean distance between neighbouring points of G (n × n points, i + n j).
pub(crate) fn grid_spacing(n: usize, points: &[DVec3]) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for j in 0..n {
        for i in 0..n {
            let p = points[i + n * j];
            if i + 1 < n {
                sum += (points[i + 1 + n * j] - p).length();
                count += 1;
            }
            if j + 1 < n {
                sum += (points[i + n * (j + 1)] - p).length();
                count += 1;
            }
        }
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

/// From every point of G along its unit line, `length` long.
pub(crate) fn line_segments(points: &[DVec3], lines: &[DVec3], length: f64) -> Vec<(DVec3, DVec3)> {
    points.iter().zip(lines).map(|(&p, &l)| (p, p + length * l)).collect()
}

/// Two arms per quad with real torsal directions, centred at the quad's centre, each with the
/// quad's torsal-plane angle (degrees).
pub fn cross_field(n: usize, points: &[DVec3], torsal: &[Option<TorsalPair>], length: f64) -> (Vec<(DVec3, DVec3)>, Vec<f64>) {
    let (mut segments, mut angles) = (Vec::new(), Vec::new());
    for (q, pair) in torsal.iter().enumerate() {
        let Some(pair) = pair else { continue };
        let centre = grid_quad(n, q).iter().map(|&p| points[p]).sum::<DVec3>() * 0.25;
        for t in pair.t {
            segments.push((centre - 0.5 * length * t, centre + 0.5 * length * t));
            angles.push(pair.angle_deg);
        }
    }
    (segments, angles)
}

/// The four edges of every quad of G without real torsal directions.
pub(crate) fn quad_outlines(n: usize, points: &[DVec3], torsal: &[Option<TorsalPair>]) -> Vec<(DVec3, DVec3)> {
    torsal
        .iter()
        .enumerate()
        .filter(|(_, pair)| pair.is_none())
        .flat_map(|(q, _)| {
            let c = grid_quad(n, q).map(|p| points[p]);
            (0..4).map(move |k| (c[k], c[(k + 1) % 4]))
        })
        .collect()
}
