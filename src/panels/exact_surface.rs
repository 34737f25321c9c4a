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
//! largest; the first one above 0.2 is taken), or, beside a side sweeping over 120°, the point of
//! its circle opposite its middle. The projection keeps the panel's orientation about the outward
//! radius, so a pole inside the panel shows as a patch running the wrong way and is not taken.
//! Where the Coons patch folds (strongly curved arcs at a sharp corner), its one interior control
//! point is moved to where it folds least; the sides stay. A panel whose arcs cross (its boundary,
//! sampled, crosses itself) is refused at once, since any surface they bound folds; a patch that
//! folds anyway is refused too (a corner sharper or wider than the patch can turn).
//!
//! **Planar panel, support element.** The Coons patch of the arcs themselves, (2, 2), planar,
//! refused where it folds.
//!
//! A triangle is a quad with one side collapsed to a corner, the corner that folds it least.

use glam::{DVec2, DVec3};

use super::arc::Arc;
use super::panel::Panel;
use crate::congruence::support_structure::SupportElement;
use crate::geometry::rational_bezier::{ArcError, BernsteinPoly, RationalCurve, RationalPatch};
use crate::geometry::sphere::Sphere;

/// Jacobian samples per direction of the fold check.
const FOLD_SAMPLES: usize = 9;
/// A planar patch folds when its Jacobian somewhere is below this share of its largest.
pub const FOLD_RATIO: f64 = 1e-6;
/// A patch this far from folding is taken without trying other poles or corners.
const GOOD_RATIO: f64 = 0.2;
/// A side sweeping more than this (120°) adds a pole on its circle.
const WIDE_SWEEP: f64 = 2.0 * std::f64::consts::FRAC_PI_3;

/// Why a panel has no exact patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExactSurfaceError {
    /// A side is no rational quadratic (wider than half a circle, or degenerate).
    Side { side: usize, error: ArcError },
    /// Its boundary crosses itself: no patch bounded by it keeps from folding.
    ArcsCross,
    /// Every planar patch tried folds (Jacobian ratio below [`FOLD_RATIO`]).
    Folds { jacobian_ratio: f64 },
    /// Not 3 or 4 corners, or no finite sphere.
    Degenerate,
}

impl std::fmt::Display for ExactSurfaceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ExactSurfaceError::Side { side, error } => write!(f, "side {side}: {error}"),
            ExactSurfaceError::ArcsCross => f.write_str("its arcs cross, so any surface they bound folds"),
            ExactSurfaceError::Folds { jacobian_ratio } => {
                write!(f, "every patch tried folds (smallest Jacobian {jacobian_ratio:.1e} of its largest)")
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
    if arcs_cross(&panel.sphere, &panel.arcs) {
        return Err(ExactSurfaceError::ArcsCross);
    }
    if panel.is_planar() {
        // The corners run counter-clockwise about the outward normal −∇ψ = b/|b|.
        let normal = panel.sphere.b.try_normalize().ok_or(ExactSurfaceError::Degenerate)?;
        let sides: Vec<RationalCurve> = (0..n).map(|k| side_curve(&panel.arcs[k], panel.arcs[(k + 1) % n].from, k)).collect::<Result<_, _>>()?;
        let (ratio, patch) = coons_of(&sides, normal, true);
        return if ratio > FOLD_RATIO { Ok(patch) } else { Err(ExactSurfaceError::Folds { jacobian_ratio: ratio }) };
    }
    let (Some(c), Some(r)) = (panel.sphere.center(), panel.sphere.signed_radius()) else {
        return Err(ExactSurfaceError::Degenerate);
    };
    let r = r.abs();
    if !(r.is_finite() && r > 0.0 && c.is_finite()) {
        return Err(ExactSurfaceError::Degenerate);
    }
    // The outward normal −∇ψ = −sign(a)·(x − C)/r: the corners run counter-clockwise about it.
    let outward = -panel.sphere.a.signum();
    // Candidate poles: the antipodes of the panel's middle and of the points halfway to each
    // corner; then, for a side sweeping over 120°, the point of its circle opposite its middle
    // (the side projects to a segment, the others to narrower arcs).
    let middle = middle_of(&panel.arcs);
    let on_sphere = |x: DVec3| (x - c).try_normalize().map(|d| c + r * d);
    let antipode = |x: DVec3| on_sphere(x).map(|x| 2.0 * c - x);
    let mut poles: Vec<DVec3> = antipode(middle).into_iter().collect();
    poles.extend(panel.arcs.iter().filter_map(|a| antipode(0.5 * (middle + a.from))));
    for arc in &panel.arcs {
        if !arc.is_straight() && arc.sweep() > WIDE_SWEEP {
            poles.extend(on_sphere(2.0 * arc.circle.center - arc.point(0.5)));
        }
    }
    // The plain Coons patches first, (ratio, patch, pole) of the best; only if every one folds,
    // the unfolded one ([`unfolded`]) of the pole that folds least.
    let mut best: Option<(f64, RationalPatch, DVec3)> = None;
    let mut first_error = None;
    for &pole in &poles {
        match spherical_patch(panel, c, r, outward, pole, false) {
            Ok((ratio, patch)) if best.as_ref().is_none_or(|(b, ..)| ratio > *b) => best = Some((ratio, patch, pole)),
            Ok(_) => {}
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
        if best.as_ref().is_some_and(|(b, ..)| *b >= GOOD_RATIO) {
            break;
        }
    }
    if let Some((ratio, _, pole)) = best.as_ref().filter(|(ratio, ..)| *ratio <= FOLD_RATIO) {
        if let Some((moved, patch)) = spherical_patch(panel, c, r, outward, *pole, true).ok().filter(|(moved, _)| moved > ratio) {
            best = Some((moved, patch, *pole));
        }
    }
    match best {
        Some((ratio, patch, _)) if ratio > FOLD_RATIO => Ok(patch),
        Some((ratio, ..)) => Err(ExactSurfaceError::Folds { jacobian_ratio: ratio }),
        None => Err(first_error.unwrap_or(ExactSurfaceError::Degenerate)),
    }
}

/// The mean of the arcs' middles.
fn middle_of(arcs: &[Arc]) -> DVec3 {
    arcs.iter().map(|a| a.point(0.5)).sum::<DVec3>() / arcs.len() as f64
}

/// Whether the arcs of a panel on `sphere` cross one another, so that any surface they bound
/// folds: its boundary, mapped into a plane that keeps crossings (a plane's own frame; on a
/// sphere, the stereographic projection from the antipode of the arcs' middle), crosses itself
/// ([`boundary_crosses`]). A sphere with no finite centre, or fewer than three arcs: false (no
/// patch is made of it anyway). The verdicts of every method count these panels
/// ([`super::buildability`]); the ST method steers away from them while it optimizes.
pub fn arcs_cross(sphere: &Sphere, arcs: &[Arc]) -> bool {
    if arcs.len() < 3 {
        return false;
    }
    if sphere.a == 0.0 {
        let Some(normal) = sphere.b.try_normalize() else {
            return false;
        };
        let e1 = normal.any_orthonormal_vector();
        let e2 = normal.cross(e1);
        return boundary_crosses(arcs, |x| DVec2::new(x.dot(e1), x.dot(e2)));
    }
    let (Some(c), Some(r)) = (sphere.center(), sphere.signed_radius()) else {
        return false;
    };
    let r = r.abs();
    let Some(d) = (middle_of(arcs) - c).try_normalize() else {
        return false;
    };
    if !(r.is_finite() && r > 0.0 && c.is_finite()) {
        return false;
    }
    // Stereographic projection keeps crossings (from any pole off the boundary).
    let projection = Stereographic::new(c, r, c - r * d);
    boundary_crosses(arcs, |x| projection.project(x))
}

/// Stereographic projection from `pole` on the sphere (c, r) onto the plane through c normal to
/// a = (c − pole)/r, scaled by 1/r: σ(x)/r in the frame (e1, e2), with e1 × e2 = a.
struct Stereographic {
    pole: DVec3,
    a: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl Stereographic {
    fn new(c: DVec3, r: f64, pole: DVec3) -> Self {
        let a = ((c - pole) / r).normalize();
        let e1 = a.any_orthonormal_vector();
        Self { pole, a, e1, e2: a.cross(e1) }
    }

    fn project(&self, x: DVec3) -> DVec2 {
        let d = x - self.pole;
        DVec2::new(d.dot(self.e1), d.dot(self.e2)) / d.dot(self.a)
    }
}

/// The (4, 4) patch of a spherical panel (centre c, radius r) projected from `pole`, with the
/// Jacobian ratio of its planar patch about `outward`·a, a = (c − pole)/r (`unfold`: where it
/// folds, unfolded). The projection keeps the orientation about the outward radius, so a pole
/// inside the panel, which turns it inside out, folds.
fn spherical_patch(panel: &Panel, c: DVec3, r: f64, outward: f64, pole: DVec3, unfold: bool) -> Result<(f64, RationalPatch), ExactSurfaceError> {
    let projection = Stereographic::new(c, r, pole);
    let Stereographic { a, e1, e2, .. } = projection;
    // As a point of the plane z = 0.
    let project = |x: DVec3| projection.project(x).extend(0.0);
    let n = panel.arcs.len();
    let mut sides = Vec::with_capacity(n);
    for (k, arc) in panel.arcs.iter().enumerate() {
        let (from, to) = (project(arc.from), project(panel.arcs[(k + 1) % n].from));
        let curve = RationalCurve::circular_arc(from, project(arc.point(0.5)), to).map_err(|error| ExactSurfaceError::Side { side: k, error })?;
        sides.push(curve);
    }
    let (ratio, planar) = coons_of(&sides, outward * DVec3::Z, unfold);
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

/// Samples per arc of the crossing test, and per sample interval when a crossing is confirmed.
const CROSSING_SAMPLES: usize = 24;
const CROSSING_REFINE: usize = 32;

/// Whether the boundary of `arcs`, mapped into a plane by `project`, crosses itself: two segments
/// of its polygon (each arc sampled at [`CROSSING_SAMPLES`] points) that share no point cross
/// strictly, and the arcs near them, sampled [`CROSSING_REFINE`] times finer, cross too (chords
/// of two arcs leaving a sharp corner can cross where the arcs do not).
fn boundary_crosses(arcs: &[Arc], project: impl Fn(DVec3) -> DVec2) -> bool {
    let n = CROSSING_SAMPLES;
    let at = |k: usize, t: f64| project(arcs[k].point(t));
    let polygon: Vec<DVec2> = (0..arcs.len()).flat_map(|k| (0..n).map(move |i| (k, i as f64 / n as f64))).map(|(k, t)| at(k, t)).collect();
    let m = polygon.len();
    // Segment i of the polygon, and the piece of its arc around it (one segment more each side),
    // sampled finer: (arc, t from, t to).
    let segment = |i: usize| (polygon[i], polygon[(i + 1) % m]);
    let around = |i: usize| {
        let h = 1.0 / n as f64;
        let t = (i % n) as f64 * h;
        let (t0, t1) = ((t - h).max(0.0), (t + 2.0 * h).min(1.0));
        (0..=CROSSING_REFINE).map(|s| at(i / n, t0 + (t1 - t0) * s as f64 / CROSSING_REFINE as f64)).collect::<Vec<DVec2>>()
    };
    (0..m).any(|i| {
        (i + 2..m).filter(|&j| (j + 1) % m != i).any(|j| {
            let ((a, b), (c, d)) = (segment(i), segment(j));
            segments_cross(a, b, c, d) && polylines_cross(&around(i), &around(j))
        })
    })
}

/// Whether two polylines cross, at segments that share no point.
fn polylines_cross(p: &[DVec2], q: &[DVec2]) -> bool {
    p.windows(2).any(|x| q.windows(2).any(|y| !(x.contains(&y[0]) || x.contains(&y[1])) && segments_cross(x[0], x[1], y[0], y[1])))
}

/// Whether the segments ab and cd cross at a point inside both.
fn segments_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let side = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
    side(a, b, c) * side(a, b, d) < 0.0 && side(c, d, a) * side(c, d, b) < 0.0
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
/// triangle's sides from the corner that folds it least, its last corner at both (1,1) and (0,1);
/// with `unfold`, a patch that folds with its interior point moved ([`unfolded`]).
fn coons_of(sides: &[RationalCurve], normal: DVec3, unfold: bool) -> (f64, RationalPatch) {
    if sides.len() == 4 {
        let patch = RationalPatch::coons(&sides[0], &sides[1], &sides[2].reversed(), &sides[3].reversed());
        let plain = (jacobian_ratio(&patch, normal, false), patch);
        return if unfold { unfolded(plain, normal, false) } else { plain };
    }
    let mut rotations: Vec<(f64, RationalPatch)> = Vec::with_capacity(3);
    for r in 0..3 {
        let [a, b, c] = [0, 1, 2].map(|k| &sides[(k + r) % 3]);
        let patch = RationalPatch::coons(a, b, &RationalCurve::point(b.points[2]), &c.reversed());
        let ratio = jacobian_ratio(&patch, normal, true);
        if ratio >= GOOD_RATIO {
            return (ratio, patch);
        }
        rotations.push((ratio, patch));
    }
    rotations.sort_by(|a, b| b.0.total_cmp(&a.0));
    if !unfold || rotations[0].0 > FOLD_RATIO {
        return rotations.swap_remove(0);
    }
    // A corner near a cusp, or wider than 180°, folds a patch that has it as a regular corner; as
    // the collapsed corner, the interior point can turn the patch's sides around it the long way.
    let mut best: Option<(f64, RationalPatch)> = None;
    for rotation in rotations {
        let moved = unfolded(rotation, normal, true);
        if best.as_ref().is_none_or(|(b, _)| moved.0 > *b) {
            best = Some(moved);
        }
        if best.as_ref().is_some_and(|(b, _)| *b >= GOOD_RATIO) {
            break;
        }
    }
    best.expect("three rotations")
}

/// A Coons patch that folds (ratio below [`FOLD_RATIO`]) with its one interior control point moved
/// in its plane to where it folds least: a pattern search from the Coons point, its step doubled
/// on success (up to 4 sizes of the patch) and halved on failure, down to 1e-3 of the size. Its sides stay exactly what they are.
fn unfolded(start: (f64, RationalPatch), normal: DVec3, collapsed: bool) -> (f64, RationalPatch) {
    let mut best = start;
    if best.0 > FOLD_RATIO || best.1.degree != [2, 2] {
        return best;
    }
    const CENTRE: usize = 4; // (1, 1) of the 3 × 3 net
    let e1 = normal.any_orthonormal_vector();
    let e2 = normal.cross(e1);
    let corners = [0, 2, 6, 8].map(|k| best.1.points[k]);
    let size = corners.iter().flat_map(|a| corners.iter().map(move |b| a.distance(*b))).fold(0.0, f64::max);
    let mut step = 0.25 * size;
    for _ in 0..40 {
        if step <= 1e-3 * size || best.0 >= GOOD_RATIO {
            break;
        }
        let moved = [e1, -e1, e2, -e2, e1 + e2, e1 - e2, e2 - e1, -e1 - e2].into_iter().find_map(|d| {
            let mut trial = best.1.clone();
            trial.points[CENTRE] += step * d;
            let ratio = jacobian_ratio(&trial, normal, collapsed);
            (ratio > best.0).then_some((ratio, trial))
        });
        match moved {
            Some(better) => {
                best = better;
                step = (2.0 * step).min(4.0 * size);
            }
            None => step *= 0.5,
        }
    }
    best
}

/// The smallest Jacobian of a planar patch along `normal` (the side its boundary must run
/// counter-clockwise about) over its largest, sampled inside: ≤ 0 where it folds or runs the
/// other way. `collapsed`: the side v = 1 is a point, where the Jacobian vanishes like 1 − v; it
/// is divided by that.
pub fn jacobian_ratio(patch: &RationalPatch, normal: DVec3, collapsed: bool) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for i in 0..FOLD_SAMPLES {
        for j in 0..FOLD_SAMPLES {
            let (u, v) = ((i as f64 + 0.5) / FOLD_SAMPLES as f64, (j as f64 + 0.5) / FOLD_SAMPLES as f64);
            let (_, du, dv) = patch.derivatives(u, v);
            let jacobian = du.cross(dv).dot(normal) / if collapsed { 1.0 - v } else { 1.0 };
            (lo, hi) = (lo.min(jacobian), hi.max(jacobian.abs()));
        }
    }
    if hi > 0.0 {
        lo / hi
    } else {
        0.0
    }
}

/// `normal` or −`normal`: the one its boundary (0,0) → (1,0) → (1,1) → (0,1) runs
/// counter-clockwise about, by the signed area it encloses.
fn boundary_normal(patch: &RationalPatch, normal: DVec3) -> DVec3 {
    const PER_SIDE: usize = 8;
    let boundary: Vec<DVec3> = (0..4 * PER_SIDE)
        .map(|k| {
            let t = (k % PER_SIDE) as f64 / PER_SIDE as f64;
            let (u, v) = [(t, 0.0), (1.0, t), (1.0 - t, 1.0), (0.0, 1.0 - t)][k / PER_SIDE];
            patch.evaluate(u, v)
        })
        .collect();
    let area: f64 = (0..boundary.len()).map(|k| boundary[k].cross(boundary[(k + 1) % boundary.len()]).dot(normal)).sum();
    if area < 0.0 {
        -normal
    } else {
        normal
    }
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
    let patch = RationalPatch::coons(&outer, &RationalCurve::segment(c1, c2), &inner, &RationalCurve::segment(c0, c3));
    let ratio = jacobian_ratio(&patch, boundary_normal(&patch, element.circle.normal), false);
    if ratio > FOLD_RATIO {
        Ok(patch)
    } else {
        Err(ExactSurfaceError::Folds { jacobian_ratio: ratio })
    }
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
