//! Panels as exact surfaces, for CAD: every panel one untrimmed rational Bézier patch on its
//! sphere whose sides are its circular arcs, every support element a planar patch.
//!
//! **Spherical panel.** Project the panel stereographically from a pole P on its sphere outside
//! it, onto the plane through the centre C normal to a = (C − P)/r: circles become circles (or
//! lines, through P), so the arcs become planar rational quadratics. Their Coons patch, taken in
//! homogeneous form, is a rational (2, 2) patch S/W of the plane (coordinates σ(x)/r) with
//! exactly those sides. The inverse projection of s = S/W,
//!   X = C + r (2s + (1 − |s|²) a) / (1 + |s|²) = C + r (2SW + (W² − |S|²) a) / (W² + |S|²),
//! is quadratic, so X is a rational patch of bidegree (4, 4), with weights W² + |S|² > 0,
//! exactly on the sphere, whose sides are exactly the arcs (the
//! images of the planar sides). The pole is the antipode of a point of the panel, the one of a few
//! whose planar patch is farthest from folding (the smallest ratio of its Jacobian over its
//! largest; the first one above 0.2 is taken); a patch that folds anyway is refused.
//!
//! **Planar panel, support element.** The Coons patch of the arcs themselves, (2, 2), planar.
//!
//! A triangle is a quad with one side collapsed to a corner, the corner that folds it least.

use glam::DVec3;

use super::arc::Arc;
use super::panel::Panel;
use crate::congruence::support_structure::SupportElement;
use crate::geometry::rational_bezier::{ArcError, BernsteinPoly, RationalCurve, RationalPatch};

/// Jacobian samples per direction of the fold check.
const FOLD_SAMPLES: usize = 9;
/// A planar patch folds when its Jacobian somewhere is below this share of its largest.
pub const FOLD_RATIO: f64 = 1e-6;
/// A patch this far from folding is taken without trying other poles or corners.
const GOOD_RATIO: f64 = 0.2;

/// Why a panel has no exact patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExactSurfaceError {
    /// A side is no rational quadratic (wider than half a circle, or degenerate).
    Side { side: usize, error: ArcError },
    /// Every planar patch tried folds (Jacobian ratio below [`FOLD_RATIO`]).
    Folds { jacobian_ratio: f64 },
    /// Not 3 or 4 corners, or no finite sphere.
    Degenerate,
}

impl std::fmt::Display for ExactSurfaceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ExactSurfaceError::Side { side, error } => write!(f, "side {side}: {error}"),
            ExactSurfaceError::Folds { jacobian_ratio } => {
                write!(f, "its patch folds (smallest Jacobian {jacobian_ratio:.1e} of its largest): its arcs cross")
            }
            ExactSurfaceError::Degenerate => f.write_str("it has no finite sphere or not 3 or 4 corners"),
        }
    }
}

impl std::error::Error for ExactSurfaceError {}

/// The exact patch of `panel`: bidegree (4, 4) on its sphere, (2, 2) for a plane; its sides
/// v = 0, u = 1, v = 1 (reversed), u = 0 (reversed) follow the panel's arcs, a quad's from
/// corner 0, a triangle's from the corner that folds its patch least, its side v = 1 collapsed
/// to a point ([`coons_of`]).
pub fn panel_patch(panel: &Panel) -> Result<RationalPatch, ExactSurfaceError> {
    let n = panel.arcs.len();
    if !(n == 3 || n == 4) {
        return Err(ExactSurfaceError::Degenerate);
    }
    if panel.is_planar() {
        let sides: Vec<RationalCurve> =
            (0..n).map(|k| side_curve(&panel.arcs[k], panel.arcs[(k + 1) % n].from, k)).collect::<Result<_, _>>()?;
        let normal = panel.sphere.b.try_normalize().ok_or(ExactSurfaceError::Degenerate)?;
        let (ratio, patch) = coons_of(&sides, normal);
        return if ratio > FOLD_RATIO { Ok(patch) } else { Err(ExactSurfaceError::Folds { jacobian_ratio: ratio }) };
    }
    let (Some(c), Some(r)) = (panel.sphere.center(), panel.sphere.signed_radius()) else {
        return Err(ExactSurfaceError::Degenerate);
    };
    let r = r.abs();
    if !(r.is_finite() && r > 0.0 && c.is_finite()) {
        return Err(ExactSurfaceError::Degenerate);
    }
    // Candidate points of the panel whose antipodes are the poles: its middle, and halfway to
    // each corner.
    let middle = panel.arcs.iter().map(|a| a.point(0.5)).sum::<DVec3>() / n as f64;
    let on_sphere = |x: DVec3| (x - c).try_normalize().map(|d| c + r * d);
    let mut candidates: Vec<DVec3> = on_sphere(middle).into_iter().collect();
    candidates.extend(panel.arcs.iter().filter_map(|a| on_sphere(0.5 * (middle + a.from))));
    let mut best: Option<(f64, RationalPatch)> = None;
    let mut first_error = None;
    for point in candidates {
        let a = (point - c) / r;
        match spherical_patch(panel, c, r, a) {
            Ok((ratio, patch)) if best.as_ref().is_none_or(|(b, _)| ratio > *b) => best = Some((ratio, patch)),
            Ok(_) => {}
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
        if best.as_ref().is_some_and(|(b, _)| *b >= GOOD_RATIO) {
            break;
        }
    }
    match best {
        Some((ratio, patch)) if ratio > FOLD_RATIO => Ok(patch),
        Some((ratio, _)) => Err(ExactSurfaceError::Folds { jacobian_ratio: ratio }),
        None => Err(first_error.unwrap_or(ExactSurfaceError::Degenerate)),
    }
}

/// The (4, 4) patch of a spherical panel projected from the pole c − r·a, with the Jacobian ratio
/// of its planar patch.
fn spherical_patch(panel: &Panel, c: DVec3, r: f64, a: DVec3) -> Result<(f64, RationalPatch), ExactSurfaceError> {
    let e1 = a.any_orthonormal_vector();
    let e2 = a.cross(e1);
    let pole = c - r * a;
    // σ(x)/r in the frame (e1, e2), as a point of the plane z = 0.
    let project = |x: DVec3| {
        let d = x - pole;
        let h = d.dot(a);
        DVec3::new(d.dot(e1) / h, d.dot(e2) / h, 0.0)
    };
    let n = panel.arcs.len();
    let mut sides = Vec::with_capacity(n);
    for (k, arc) in panel.arcs.iter().enumerate() {
        let (from, to) = (project(arc.from), project(panel.arcs[(k + 1) % n].from));
        let curve = RationalCurve::circular_arc(from, project(arc.point(0.5)), to).map_err(|error| ExactSurfaceError::Side { side: k, error })?;
        sides.push(curve);
    }
    let (ratio, planar) = coons_of(&sides, DVec3::Z);
    let coefficients = |f: &dyn Fn(&DVec3, f64) -> f64| BernsteinPoly {
        degree: planar.degree,
        coefficients: planar.points.iter().zip(&planar.weights).map(|(p, &w)| f(p, w)).collect(),
    };
    let (sx, sy, w) = (coefficients(&|p, w| w * p.x), coefficients(&|p, w| w * p.y), coefficients(&|_, w| w));
    let ww = w.mul(&w);
    let ss = sx.mul(&sx).combine(1.0, &sy.mul(&sy), 1.0);
    let d = ww.combine(1.0, &ss, 1.0);
    let nx = sx.mul(&w);
    let ny = sy.mul(&w);
    let na = ww.combine(1.0, &ss, -1.0);
    if d.coefficients.iter().any(|&x| !(x > 0.0)) {
        return Err(ExactSurfaceError::Folds { jacobian_ratio: 0.0 });
    }
    let points = (0..d.coefficients.len())
        .map(|k| {
            let dk = d.coefficients[k];
            c + r * ((2.0 * nx.coefficients[k] / dk) * e1 + (2.0 * ny.coefficients[k] / dk) * e2 + (na.coefficients[k] / dk) * a)
        })
        .collect();
    Ok((ratio, RationalPatch { degree: d.degree, points, weights: d.coefficients }))
}

/// Side k of a planar panel: its arc from corner k to `to`, the next side's first corner (a
/// straight edge: a segment).
fn side_curve(arc: &Arc, to: DVec3, k: usize) -> Result<RationalCurve, ExactSurfaceError> {
    if arc.is_straight() {
        return Ok(RationalCurve::segment(arc.from, to));
    }
    RationalCurve::circular_arc(arc.from, arc.point(0.5), to).map_err(|error| ExactSurfaceError::Side { side: k, error })
}

/// The Coons patch of 3 or 4 sides running corner k → k + 1, and its Jacobian ratio along
/// `normal` ([`jacobian_ratio`]): a quad's corners 0, 1, 2, 3 at (0,0), (1,0), (1,1), (0,1); a
/// triangle's sides from the corner that folds it least, its last corner at both (1,1) and (0,1).
fn coons_of(sides: &[RationalCurve], normal: DVec3) -> (f64, RationalPatch) {
    if sides.len() == 4 {
        let patch = RationalPatch::coons(&sides[0], &sides[1], &sides[2].reversed(), &sides[3].reversed());
        return (jacobian_ratio(&patch, normal, false), patch);
    }
    let mut best: Option<(f64, RationalPatch)> = None;
    for r in 0..3 {
        let [a, b, c] = [0, 1, 2].map(|k| &sides[(k + r) % 3]);
        let patch = RationalPatch::coons(a, b, &RationalCurve::point(b.points[2]), &c.reversed());
        let ratio = jacobian_ratio(&patch, normal, true);
        if best.as_ref().is_none_or(|(b, _)| ratio > *b) {
            best = Some((ratio, patch));
        }
        if ratio >= GOOD_RATIO {
            break;
        }
    }
    best.expect("three rotations")
}

/// The smallest Jacobian of a planar patch (along `normal`, signed like the patch's own
/// orientation) over its largest, sampled inside: ≤ 0 where it folds. `collapsed`: the side v = 1
/// is a point, where the Jacobian vanishes like 1 − v; it is divided by that.
pub fn jacobian_ratio(patch: &RationalPatch, normal: DVec3, collapsed: bool) -> f64 {
    let jacobian = |u: f64, v: f64| {
        let (_, du, dv) = patch.derivatives(u, v);
        let j = du.cross(dv).dot(normal);
        if collapsed { j / (1.0 - v) } else { j }
    };
    let mut values = [0.0; FOLD_SAMPLES * FOLD_SAMPLES];
    for i in 0..FOLD_SAMPLES {
        for j in 0..FOLD_SAMPLES {
            let (u, v) = ((i as f64 + 0.5) / FOLD_SAMPLES as f64, (j as f64 + 0.5) / FOLD_SAMPLES as f64);
            values[i * FOLD_SAMPLES + j] = jacobian(u, v);
        }
    }
    let sign = jacobian(0.5, 0.4).signum();
    let lo = values.iter().map(|j| sign * j).fold(f64::INFINITY, f64::min);
    let hi = values.iter().map(|j| j.abs()).fold(0.0, f64::max);
    if hi > 0.0 && sign != 0.0 { lo / hi } else { 0.0 }
}

/// The planar patch of a support element: its edge arc (corners 0 → 1, the shorter way), the
/// node-axis segment at corner 1 (→ 2), its inner arc (corners 3 → 2) and the segment at corner
/// 0 (→ 3).
pub fn support_patch(element: &SupportElement) -> Result<RationalPatch, ExactSurfaceError> {
    let [c0, c1, c2, c3] = element.corners;
    let through = |circle: &crate::geometry::circle::Circle, a: DVec3, b: DVec3| {
        let d = 0.5 * (a + b) - circle.center;
        let d = d - d.dot(circle.normal) * circle.normal;
        d.try_normalize().map_or(0.5 * (a + b), |d| circle.center + circle.radius * d)
    };
    let arc = |circle, a, b, side| {
        if !circle_is_finite(circle) {
            return Ok(RationalCurve::segment(a, b));
        }
        RationalCurve::circular_arc(a, through(circle, a, b), b).map_err(|error| ExactSurfaceError::Side { side, error })
    };
    let outer = arc(&element.circle, c0, c1, 0)?;
    let inner = arc(&element.inner_circle, c3, c2, 2)?;
    Ok(RationalPatch::coons(&outer, &RationalCurve::segment(c1, c2), &inner, &RationalCurve::segment(c0, c3)))
}

fn circle_is_finite(c: &crate::geometry::circle::Circle) -> bool {
    c.radius.is_finite() && c.radius > 0.0 && c.center.is_finite()
}

/// An arc as a rational quadratic (a straight edge: a segment).
pub fn arc_curve(arc: &Arc) -> Result<RationalCurve, ArcError> {
    if arc.is_straight() {
        return Ok(RationalCurve::segment(arc.from, arc.to));
    }
    RationalCurve::circular_arc(arc.from, arc.point(0.5), arc.to)
}

/// The exact surfaces of a result: each panel's patch (or why it has none) and each support
/// element's.
#[derive(Clone, Debug, Default)]
pub struct ExactSurfaces {
    pub panels: Vec<Result<RationalPatch, ExactSurfaceError>>,
    pub support: Vec<Result<RationalPatch, ExactSurfaceError>>,
}

impl ExactSurfaces {
    pub fn of(panels: &[Panel], support: &[SupportElement]) -> Self {
        Self { panels: panels.iter().map(panel_patch).collect(), support: support.iter().map(support_patch).collect() }
    }

    /// The panels without an exact patch, with the reason, by panel id.
    pub fn refused_panels(&self) -> impl Iterator<Item = (usize, &ExactSurfaceError)> {
        self.panels.iter().enumerate().filter_map(|(i, p)| p.as_ref().err().map(|e| (i, e)))
    }
}
