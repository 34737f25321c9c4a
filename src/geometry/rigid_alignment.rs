//! The rigid motion that brings points closest to a surface along its normals: point-to-plane
//! ICP (Chen and Medioni), linearized about the current pose and solved by least squares, a few
//! rounds. A rigid motion keeps every sphere a sphere and every plane a plane, so it moves an
//! exact sphere mesh onto its reference without costing its exactness.

use glam::{DMat3, DQuat, DVec3};

use super::linalg::lstsq_householder;

/// Weight of the rows that hold the motion, per point: a motion that moves the points along the
/// surface by d costs as much as normal distances of `HOLD` · d.
const HOLD: f64 = 1e-3;

/// The rotation R and translation t (x ↦ R x + t) after `rounds` rounds that bring `points`
/// closest to the surface in the least-squares sense of their signed normal distances;
/// `closest(i, p)` is the closest point of the surface to point `i` at `p` and its unit normal.
/// The identity when the points do not fix a motion (fewer than 6, or all on one plane's
/// normals: a plane slides along itself).
pub fn point_to_plane_motion(points: &[DVec3], rounds: usize, closest: &mut dyn FnMut(usize, DVec3) -> Option<(DVec3, DVec3)>) -> (DMat3, DVec3) {
    let (mut rotation, mut translation) = (DMat3::IDENTITY, DVec3::ZERO);
    let n = points.len();
    if n < 6 {
        return (rotation, translation);
    }
    let origin = points.iter().copied().sum::<DVec3>() / n as f64;
    for _ in 0..rounds {
        // Residual ⟨p − q, n⟩ + ⟨(p − o) × n, ω⟩ + ⟨n, τ⟩ for the small motion p ↦ p + ω × (p − o) + τ.
        // Six rows more hold the motion where the points barely fix it (a nearly flat patch
        // slides along itself): τ at the scale of the residuals, ω at that over the arms.
        let m = n + 6;
        let mut a = vec![0.0; 6 * m];
        let mut b = vec![0.0; m];
        let arms = (points.iter().map(|p| (*p - origin).length_squared()).sum::<f64>() / n as f64).sqrt().max(f64::MIN_POSITIVE);
        for j in 0..6 {
            a[j * m + n + j] = HOLD * (n as f64).sqrt() * if j < 3 { arms } else { 1.0 };
        }
        let rows: Vec<Option<(DVec3, DVec3, f64)>> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let p = rotation * *p + translation;
                let (q, normal) = closest(i, p)?;
                Some(((p - origin).cross(normal), normal, (p - q).dot(normal)))
            })
            .collect();
        for (i, row) in rows.iter().enumerate() {
            let Some((arm, normal, r)) = *row else { continue };
            for (j, v) in arm.to_array().into_iter().chain(normal.to_array()).enumerate() {
                a[j * m + i] = v;
            }
            b[i] = -r;
        }
        let mut x = [0.0; 6];
        if !lstsq_householder(&mut a, m, 6, &mut b, &mut x, 1e-12) {
            break;
        }
        let omega = DVec3::new(x[0], x[1], x[2]);
        let step = DMat3::from_quat(DQuat::from_scaled_axis(omega));
        // p ↦ R_ω (p − o) + o + τ, composed after the current motion.
        rotation = step * rotation;
        translation = step * (translation - origin) + origin + DVec3::new(x[3], x[4], x[5]);
    }
    (rotation, translation)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points of a paraboloid z = (x² + 2y²)/4, moved by a small rotation and translation: the
    /// motion found brings every point back onto the surface.
    #[test]
    fn a_moved_patch_comes_back_onto_its_surface() {
        let f = |x: f64, y: f64| (x * x + 2.0 * y * y) / 4.0;
        let on: Vec<DVec3> = (0..49)
            .map(|k| DVec3::new((k % 7) as f64 / 3.0 - 1.0, (k / 7) as f64 / 3.0 - 1.0, 0.0))
            .map(|p| DVec3::new(p.x, p.y, f(p.x, p.y)))
            .collect();
        let r = DMat3::from_quat(DQuat::from_scaled_axis(DVec3::new(0.02, -0.03, 0.01)));
        let t = DVec3::new(0.01, 0.02, 0.05);
        let moved: Vec<DVec3> = on.iter().map(|p| r * *p + t).collect();
        // The closest point by Newton steps on the graph's distance.
        let mut closest = |_: usize, p: DVec3| {
            let (mut x, mut y) = (p.x, p.y);
            for _ in 0..50 {
                let q = DVec3::new(x, y, f(x, y));
                let (fu, fv) = (DVec3::new(1.0, 0.0, x / 2.0), DVec3::new(0.0, 1.0, y));
                let d = q - p;
                let (g0, g1) = (d.dot(fu), d.dot(fv));
                let (h00, h01, h11) = (fu.dot(fu) + d.z / 2.0, fu.dot(fv), fv.dot(fv) + d.z);
                let det = h00 * h11 - h01 * h01;
                x -= (h11 * g0 - h01 * g1) / det;
                y -= (h00 * g1 - h01 * g0) / det;
            }
            let n = DVec3::new(-x / 2.0, -y, 1.0).normalize();
            Some((DVec3::new(x, y, f(x, y)), n))
        };
        let before = moved.iter().enumerate().map(|(i, p)| closest(i, *p).unwrap().0.distance(*p)).fold(0.0, f64::max);
        let (rot, tr) = point_to_plane_motion(&moved, 8, &mut closest);
        let after = moved
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let p = rot * *p + tr;
                closest(i, p).unwrap().0.distance(p)
            })
            .fold(0.0, f64::max);
        assert!(before > 1e-2 && after < 1e-9, "{before:e} → {after:e}");
        // A rotation.
        assert!((rot.determinant() - 1.0).abs() < 1e-12 && (rot.transpose() * rot).abs_diff_eq(DMat3::IDENTITY, 1e-12));
    }
}
