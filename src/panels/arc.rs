//! Circular arcs in space: sampling, sweep, sagitta and the point above a chord.

use glam::DVec3;

use crate::geometry::circle::Circle;

/// Most segments of one arc.
pub const MAX_ARC_SEGMENTS: usize = 4096;

/// A circular arc from `from` to `to`, counter-clockwise about `circle.normal`. A straight edge
/// has `circle.radius = +∞`, `circle.center` at the chord midpoint and `circle.normal` normal to
/// a plane containing the edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    pub circle: Circle,
    pub from: DVec3,
    pub to: DVec3,
}

impl Arc {
    /// A straight edge from `from` to `to`; `plane_normal` is the normal of a plane containing it
    /// (made orthogonal to the edge).
    pub fn straight(from: DVec3, to: DVec3, plane_normal: DVec3) -> Arc {
        let e = (to - from).normalize_or_zero();
        let n = (plane_normal - plane_normal.dot(e) * e).try_normalize().unwrap_or_else(|| e.any_orthonormal_vector());
        Arc { circle: Circle { center: 0.5 * (from + to), normal: n, radius: f64::INFINITY }, from, to }
    }

    pub fn is_straight(&self) -> bool {
        !self.circle.radius.is_finite()
    }

    /// The same edge traversed from `to` to `from` (normal flipped, so still counter-clockwise).
    pub fn reversed(&self) -> Arc {
        Arc { circle: Circle { normal: -self.circle.normal, ..self.circle }, from: self.to, to: self.from }
    }

    pub(crate) fn chord_length(&self) -> f64 {
        self.from.distance(self.to)
    }

    /// Orthonormal basis of the circle's plane: u from the centre toward `from`, v = n × u (the
    /// arc's tangent direction at `from`).
    fn basis(&self) -> (DVec3, DVec3) {
        let n = self.circle.normal;
        let d = self.from - self.circle.center;
        let u = (d - d.dot(n) * n).try_normalize().unwrap_or_else(|| n.any_orthonormal_vector());
        (u, n.cross(u))
    }

    /// The angle swept from `from` to `to`, in (0, 2π); 0 for a straight or degenerate arc.
    /// Computed from the chord (cos θ = 1 − L²/2r², sin θ = ⟨to − from, v⟩/r), which stays
    /// accurate when the centre is far away.
    pub fn sweep(&self) -> f64 {
        let r = self.circle.radius;
        if !r.is_finite() || r <= 0.0 {
            return 0.0;
        }
        let (_, v) = self.basis();
        let chord = self.to - self.from;
        let l = chord.length();
        if l == 0.0 {
            return 0.0;
        }
        let half = (l / (2.0 * r)).min(1.0).asin();
        if chord.dot(v) >= 0.0 {
            2.0 * half
        } else {
            2.0 * std::f64::consts::PI - 2.0 * half
        }
    }

    /// Arc length (chord length when straight).
    pub fn length(&self) -> f64 {
        if self.is_straight() {
            self.chord_length()
        } else {
            self.circle.radius * self.sweep()
        }
    }

    /// The point at parameter t ∈ [0, 1] (uniform in angle); exactly `from` at 0 and `to` at 1.
    pub fn point(&self, t: f64) -> DVec3 {
        if t <= 0.0 {
            return self.from;
        }
        if t >= 1.0 {
            return self.to;
        }
        if self.is_straight() {
            return self.from + t * (self.to - self.from);
        }
        let r = self.circle.radius;
        let (u, v) = self.basis();
        let phi = t * self.sweep();
        let s = (0.5 * phi).sin();
        // c + r(cos φ u + sin φ v), written relative to `from` = c + r u.
        self.from + (r * phi.sin()) * v - (2.0 * r * s * s) * u
    }

    /// Largest distance between the arc and its chord (0 when straight).
    pub fn sagitta(&self) -> f64 {
        segment_sagitta(self.circle.radius, self.sweep())
    }

    /// Number of equal-angle segments whose sagitta is at most `tol` (1 for straight arcs), at
    /// most [`MAX_ARC_SEGMENTS`], and at most 90° each.
    pub(crate) fn segments_for(&self, tol: f64) -> usize {
        let r = self.circle.radius;
        let theta = self.sweep();
        if !r.is_finite() || theta <= 0.0 {
            return 1;
        }
        // Sagitta of a segment of angle Δ: 2r sin²(Δ/4) ≤ tol.
        let x = tol / (2.0 * r);
        let dmax = if x >= 1.0 || !x.is_finite() { std::f64::consts::PI } else { 4.0 * x.sqrt().asin() };
        let dmax = dmax.clamp(1e-12, 0.5 * std::f64::consts::PI);
        let n = (theta / dmax).ceil();
        if n.is_finite() {
            (n as usize).clamp(1, MAX_ARC_SEGMENTS)
        } else {
            MAX_ARC_SEGMENTS
        }
    }

    /// `segments + 1` points along the arc, equal in angle, with exact endpoints.
    pub fn sample(&self, segments: usize) -> Vec<DVec3> {
        let n = segments.max(1);
        (0..=n).map(|j| self.point(j as f64 / n as f64)).collect()
    }

    /// The arc point above the chord point `from + t (to − from)`, t ∈ [0, 1]: the arc's
    /// intersection with the line through that chord point orthogonal to the chord in the arc's
    /// plane (the chord point itself for a straight arc). Of the circle's two points on that line
    /// the one on this arc is taken: with w = normal × (to − from)/|to − from| the arc lies on the
    /// −w side of the centre, so the offset is s = h − √(h² + l²/4 − u²), h = ⟨centre − chord
    /// midpoint, w⟩, u the signed distance from the chord midpoint (rationalized when h ≥ 0, the
    /// minor arc, to keep precision for huge radii).
    pub fn point_over_chord(&self, t: f64) -> DVec3 {
        let e = self.to - self.from;
        let x0 = self.from + t * e;
        let l = e.length();
        if self.is_straight() || l == 0.0 {
            return x0;
        }
        let eh = e / l;
        let w = self.circle.normal.cross(eh).normalize_or_zero();
        let h = (self.circle.center - 0.5 * (self.from + self.to)).dot(w);
        let u = (t - 0.5) * l;
        let rest = ((0.5 * l - u.abs()) * (0.5 * l + u.abs())).max(0.0); // l²/4 − u²
        let root = (h * h + rest).sqrt();
        let s = if h >= 0.0 { -rest / (root + h) } else { h - root };
        x0 + s * w
    }

    /// Sagitta of one of `segments` equal segments.
    #[cfg(test)]
    pub(crate) fn segment_sagitta(&self, segments: usize) -> f64 {
        segment_sagitta(self.circle.radius, self.sweep() / segments.max(1) as f64)
    }
}

/// Sagitta of a circular segment of radius r and angle θ: 2r sin²(θ/4) (0 for r = ∞).
pub(crate) fn segment_sagitta(r: f64, theta: f64) -> f64 {
    if !r.is_finite() {
        return 0.0;
    }
    let s = (0.25 * theta).sin();
    2.0 * r * s * s
}
