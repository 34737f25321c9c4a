//! Cross fields in the parameter plane of a patch, and their singular points (Sec. 5.2: the
//! torsal directions as a cross field).
//!
//! A cross is two lines, not necessarily orthogonal. It is stored as the orthogonal cross nearest
//! to it (angle c, defined modulo π/2) and a skew s: the lines are at c − s and c + π/2 + s. Turning
//! the labels by a quarter (family 1 becomes family 0) takes (c, s) to (c + π/2, −s). The
//! orthogonal part is the 4-direction field z = e^{4ic}, which needs no combing: averages and
//! interpolation are taken on z, as in Knöppel et al. 2013.
//!
//! **Singular points.** On a triangulated grid with one cross per triangle, the index of a vertex
//! is the turning of c around it, a multiple of a quarter turn (Ray et al. 2008). An umbilic of a
//! dome turns the field by a full turn, a generic umbilic by a half; a quad mesh has only quarter
//! turns (valence 3 at +1/4, 5 at −1/4), so [`split_singularities`] replaces each cluster of
//! singular points by quarter-turn points around it, changing the field only near the cluster.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use glam::{DVec2, DVec3};

use crate::geometry::bspline::BSplineSurface;

/// A cross of two lines in the parameter plane (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cross {
    /// The angle c of the nearest orthogonal cross (radians, modulo π/2 with the skew's sign).
    pub angle: f64,
    /// The skew s ∈ [−π/4, π/4]: family 0 at c − s, family 1 at c + π/2 + s.
    pub skew: f64,
}

impl Cross {
    /// The cross of the lines along `d0` and `d1` (any length, any sign).
    pub fn from_lines(d0: DVec2, d1: DVec2) -> Self {
        let a = d0.y.atan2(d0.x);
        let opening = (d1.y.atan2(d1.x) - a).rem_euclid(PI);
        let skew = 0.5 * (opening - FRAC_PI_2);
        Self { angle: a + skew, skew }
    }

    /// Unit directions of family 0 and family 1.
    pub fn directions(self) -> [DVec2; 2] {
        let dir = |t: f64| DVec2::new(t.cos(), t.sin());
        [dir(self.angle - self.skew), dir(self.angle + FRAC_PI_2 + self.skew)]
    }

    /// The 4-direction representative e^{4ic}.
    pub fn z(self) -> DVec2 {
        DVec2::new((4.0 * self.angle).cos(), (4.0 * self.angle).sin())
    }

    /// The same cross with its labels turned by `quarters` quarter turns.
    pub fn turned(self, quarters: i32) -> Self {
        Self { angle: self.angle + quarters as f64 * FRAC_PI_2, skew: if quarters.rem_euclid(2) == 0 { self.skew } else { -self.skew } }
    }

    /// The quarter turns that bring this cross's labels nearest to angle `reference`.
    pub(crate) fn quarters_to(self, reference: f64) -> i32 {
        ((reference - self.angle) / FRAC_PI_2).round() as i32
    }

    /// Labelled like the cross at angle `reference` (the nearest of its four labellings).
    pub(crate) fn aligned_to(self, reference: f64) -> Self {
        self.turned(self.quarters_to(reference))
    }
}

/// The weighted mean of crosses: the angle from the mean of z, the skew from the crosses labelled
/// like it. None when z averages to (nearly) zero.
pub(crate) fn mean_cross(crosses: impl IntoIterator<Item = (f64, Cross)>) -> Option<Cross> {
    let items: Vec<(f64, Cross)> = crosses.into_iter().collect();
    let z = items.iter().fold(DVec2::ZERO, |s, (w, c)| s + *w * c.z());
    let total: f64 = items.iter().map(|(w, _)| w).sum();
    if !(z.length() > 1e-12 * total.max(1e-300)) {
        return None;
    }
    let angle = 0.25 * z.y.atan2(z.x);
    let skew = items.iter().map(|(w, c)| w * c.aligned_to(angle).skew).sum::<f64>() / total;
    Some(Cross { angle, skew })
}

/// The difference b − a of two cross angles, modulo a quarter turn, in (−π/4, π/4].
pub(crate) fn angle_step(a: f64, b: f64) -> f64 {
    let d = (b - a).rem_euclid(FRAC_PI_2);
    if d > 0.5 * FRAC_PI_2 {
        d - FRAC_PI_2
    } else {
        d
    }
}

/// A cross field on an n × n grid of a rectangle: per cell (i + (n − 1) j) its cross.
#[derive(Clone, Debug, PartialEq)]
pub struct CrossField {
    /// Points per direction of the grid.
    pub n: usize,
    pub domain: ((f64, f64), (f64, f64)),
    /// Per cell: its cross.
    pub crosses: Vec<Cross>,
    /// Cells that had no directions of their own (filled from their neighbours).
    pub filled: usize,
}

impl CrossField {
    /// The field of per-cell direction pairs (unordered, unsigned; None where a cell has none):
    /// cells without directions take the mean of their neighbours'. None when no cell has
    /// directions.
    pub fn new(surface: &BSplineSurface, n: usize, raw: &[Option<[[f64; 2]; 2]>]) -> Option<Self> {
        let cells = n - 1;
        assert_eq!(raw.len(), cells * cells, "one entry per grid cell");
        let mut out: Vec<Option<Cross>> = raw.iter().map(|d| d.map(|[a, b]| Cross::from_lines(DVec2::from(a), DVec2::from(b)))).collect();
        if out.iter().all(Option::is_none) {
            return None;
        }
        let neighbours = |q: usize| {
            let (i, j) = (q % cells, q / cells);
            let mut v = Vec::with_capacity(4);
            if i > 0 {
                v.push(q - 1);
            }
            if i + 1 < cells {
                v.push(q + 1);
            }
            if j > 0 {
                v.push(q - cells);
            }
            if j + 1 < cells {
                v.push(q + cells);
            }
            v
        };
        let mut filled = 0;
        loop {
            let missing: Vec<usize> = (0..out.len()).filter(|&q| out[q].is_none()).collect();
            if missing.is_empty() {
                break;
            }
            let mut progress = false;
            for q in missing {
                let known = neighbours(q).into_iter().filter_map(|r| out[r]).map(|c| (1.0, c));
                if let Some(c) = mean_cross(known) {
                    out[q] = Some(c);
                    filled += 1;
                    progress = true;
                }
            }
            if !progress {
                break;
            }
        }
        let crosses = out.into_iter().map(|c| c.unwrap_or(Cross { angle: 0.0, skew: 0.0 })).collect();
        Some(Self { n, domain: surface.domain(), crosses, filled })
    }

    /// The cross at (u, v), bilinear (on z) between cell centres, clamped to the domain.
    pub(crate) fn cross_at(&self, u: f64, v: f64) -> Cross {
        let cells = self.n - 1;
        if cells == 1 {
            return self.crosses[0];
        }
        let ((u0, u1), (v0, v1)) = self.domain;
        let s = ((u - u0) / (u1 - u0) * cells as f64 - 0.5).clamp(0.0, (cells - 1) as f64);
        let t = ((v - v0) / (v1 - v0) * cells as f64 - 0.5).clamp(0.0, (cells - 1) as f64);
        let (i, j) = ((s.floor() as usize).min(cells - 2), (t.floor() as usize).min(cells - 2));
        let (fs, ft) = (s - i as f64, t - j as f64);
        let c = |a: usize, b: usize| self.crosses[(i + a) + cells * (j + b)];
        let weights = [((1.0 - fs) * (1.0 - ft), c(0, 0)), (fs * (1.0 - ft), c(1, 0)), ((1.0 - fs) * ft, c(0, 1)), (fs * ft, c(1, 1))];
        // Where z cancels (a singular point), the nearest cell's cross.
        mean_cross(weights).unwrap_or_else(|| weights.iter().max_by(|a, b| a.0.total_cmp(&b.0)).unwrap().1)
    }

    /// The two directions at (u, v).
    pub fn at(&self, u: f64, v: f64) -> [DVec2; 2] {
        self.cross_at(u, v).directions()
    }

    /// The two directions at (u, v) as unit 3D tangent vectors of `surface`.
    pub(crate) fn at_3d(&self, surface: &BSplineSurface, u: f64, v: f64) -> [DVec3; 2] {
        let d = surface.derivatives(u, v);
        self.at(u, v).map(|t| (d.su * t.x + d.sv * t.y).normalize_or_zero())
    }
}

/// A regular grid of the parameter plane, each cell cut into two triangles: (i, j), (i + 1, j),
/// (i, j + 1) and (i + 1, j + 1), (i, j + 1), (i + 1, j), both counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FineGrid {
    /// Nodes per direction; node (i, j) at i + nu j.
    pub nu: usize,
    pub nv: usize,
    /// Parameters of node (0, 0) and the spacing.
    pub origin: [f64; 2],
    pub step: [f64; 2],
}

impl FineGrid {
    pub fn node(&self, i: usize, j: usize) -> usize {
        i + self.nu * j
    }
    pub(crate) fn node_count(&self) -> usize {
        self.nu * self.nv
    }
    pub fn triangle_count(&self) -> usize {
        2 * (self.nu - 1) * (self.nv - 1)
    }
    pub fn uv(&self, node: usize) -> DVec2 {
        let (i, j) = (node % self.nu, node / self.nu);
        DVec2::new(self.origin[0] + i as f64 * self.step[0], self.origin[1] + j as f64 * self.step[1])
    }
    /// The corners of triangle t (counter-clockwise).
    pub fn triangle(&self, t: usize) -> [usize; 3] {
        let cell = t / 2;
        let (i, j) = (cell % (self.nu - 1), cell / (self.nu - 1));
        if t.is_multiple_of(2) {
            [self.node(i, j), self.node(i + 1, j), self.node(i, j + 1)]
        } else {
            [self.node(i + 1, j + 1), self.node(i, j + 1), self.node(i + 1, j)]
        }
    }
    pub fn centroid(&self, t: usize) -> DVec2 {
        self.triangle(t).iter().map(|&n| self.uv(n)).sum::<DVec2>() / 3.0
    }
    /// The triangle holding parameter point p (clamped to the grid).
    pub(crate) fn triangle_at(&self, p: DVec2) -> usize {
        let s = ((p.x - self.origin[0]) / self.step[0]).clamp(0.0, (self.nu - 1) as f64);
        let t = ((p.y - self.origin[1]) / self.step[1]).clamp(0.0, (self.nv - 1) as f64);
        let (i, j) = ((s.floor() as usize).min(self.nu - 2), (t.floor() as usize).min(self.nv - 2));
        let cell = 2 * (i + (self.nu - 1) * j);
        if (s - i as f64) + (t - j as f64) <= 1.0 {
            cell
        } else {
            cell + 1
        }
    }
    /// Whether `node` is on the grid's outer boundary.
    pub(crate) fn on_border(&self, node: usize) -> bool {
        let (i, j) = (node % self.nu, node / self.nu);
        i == 0 || j == 0 || i + 1 == self.nu || j + 1 == self.nv
    }
    /// The triangles around an inner node, counter-clockwise (six on this grid).
    pub fn ring(&self, node: usize) -> Vec<usize> {
        let (i, j) = (node % self.nu, node / self.nu);
        let cell = |a: usize, b: usize| 2 * (a + (self.nu - 1) * b);
        // Counter-clockwise from the cell to the upper right.
        vec![cell(i, j), cell(i - 1, j) + 1, cell(i - 1, j), cell(i - 1, j - 1) + 1, cell(i, j - 1), cell(i, j - 1) + 1]
    }
    /// The grid's edges at a node: the neighbours it shares a triangle edge with.
    pub fn neighbours(&self, node: usize) -> Vec<usize> {
        let (i, j) = ((node % self.nu) as i64, (node / self.nu) as i64);
        [(1, 0), (0, 1), (-1, 1), (-1, 0), (0, -1), (1, -1)]
            .into_iter()
            .map(|(a, b)| (i + a, j + b))
            .filter(|&(a, b)| a >= 0 && b >= 0 && a < self.nu as i64 && b < self.nv as i64)
            .map(|(a, b)| self.node(a as usize, b as usize))
            .collect()
    }
}

/// A singular point of a cross field on a [`FineGrid`]: its node and its index in quarter turns
/// (+1: valence 3, −1: valence 5, +4: the full turn of a dome's umbilic).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SingularPoint {
    pub node: usize,
    pub quarters: i32,
}

/// The singular points of a field with one cross per triangle (inner nodes only).
pub fn singular_points(grid: &FineGrid, crosses: &[Cross]) -> Vec<SingularPoint> {
    let mut out = Vec::new();
    for j in 1..grid.nv - 1 {
        for i in 1..grid.nu - 1 {
            let node = grid.node(i, j);
            let ring = grid.ring(node);
            let turn: f64 = (0..ring.len()).map(|k| angle_step(crosses[ring[k]].angle, crosses[ring[(k + 1) % ring.len()]].angle)).sum();
            let quarters = (turn / FRAC_PI_2).round() as i32;
            if quarters != 0 {
                out.push(SingularPoint { node, quarters });
            }
        }
    }
    out
}

/// How far apart (in lattice spacings) the quarter-turn points of a cluster are placed. Two
/// singular vertices on one quad leave its other corners too little room: three edges at each of
/// two corners leave 60° for the other two, five 108° each, so the support planes there cannot
/// meet at 75°. Two spacings would keep them off a common quad on an even lattice; the
/// integration stretches the lattice about them and rounds them to lattice points, and at 2.5 a
/// pair still shared a quad (`tests/singular_fields.rs`).
const SINGULAR_SPREAD: f64 = 4.0;

/// Replaces the singular points of `crosses` (one per triangle of `grid`) by quarter-turn points
/// (see the module docs): singular points closer than `reach` (parameter units, through chains)
/// form a cluster; a cluster of total index K becomes |K| points of index sign(K), neighbours
/// [`SINGULAR_SPREAD`] spacings apart, on a circle (K ≥ 3) or on a line along the field (K = 2),
/// centred where the cluster's index is; a lone quarter-turn point stays. `scale` turns
/// parameters into lengths (|f_u|, |f_v|). The field changes by the turning of
/// Π (x − p_j)^{±1} / Π (x − s_i)^{k_i}, which tends to 1 away from the cluster. Inside a disk
/// about each cluster (its points plus 1.5 spacings), where the directions are the noise of an
/// umbilic, the field is the one of the disk's rim with the cluster's turning taken out, carried
/// in along the rays, times the placed points' turning. The skew fades out within 2.5 spacings of
/// the disk (a quarter-turn point needs orthogonal lines). Returns the singular points found after.
pub fn split_singularities(grid: &FineGrid, crosses: &mut [Cross], reach: f64, spacing: f64, scale: DVec2) -> Vec<SingularPoint> {
    let found = singular_points(grid, crosses);
    let metric = |p: DVec2| p * scale;
    // First the dipoles: a point and a nearest one of opposite index within a spacing cancel
    // (each its own cluster of total index 0); then single-linkage clusters of the rest.
    let at = |i: usize| metric(grid.uv(found[i].node));
    let mut pairs: Vec<(f64, usize, usize)> = (0..found.len())
        .flat_map(|a| (a + 1..found.len()).map(move |b| (a, b)))
        .filter(|&(a, b)| found[a].quarters == -found[b].quarters)
        .map(|(a, b)| (at(a).distance(at(b)), a, b))
        .filter(|(d, _, _)| *d <= spacing)
        .collect();
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut dipole = vec![false; found.len()];
    let mut cluster: Vec<usize> = (0..found.len()).collect();
    for (_, a, b) in pairs {
        if !dipole[a] && !dipole[b] {
            dipole[a] = true;
            dipole[b] = true;
            cluster[a] = b;
        }
    }
    fn root(c: &mut [usize], i: usize) -> usize {
        let mut r = i;
        while c[r] != r {
            r = c[r];
        }
        c[i] = r;
        r
    }
    for a in (0..found.len()).filter(|&a| !dipole[a]) {
        for b in (a + 1..found.len()).filter(|&b| !dipole[b]) {
            if at(a).distance(at(b)) <= reach {
                let (ra, rb) = (root(&mut cluster, a), root(&mut cluster, b));
                cluster[ra] = rb;
            }
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<SingularPoint>> = Default::default();
    for i in 0..found.len() {
        let r = root(&mut cluster, i);
        groups.entry(r).or_default().push(found[i]);
    }
    // Per cluster: the points removed (with their index) and the points placed.
    let mut removed: Vec<(DVec2, i32)> = Vec::new();
    let mut placed: Vec<(DVec2, i32)> = Vec::new();
    let mut centres: Vec<DVec2> = Vec::new();
    let mut radii: Vec<f64> = Vec::new();
    for members in groups.values() {
        if let [single] = members.as_slice() {
            if single.quarters.abs() == 1 {
                continue;
            }
        }
        let total: i32 = members.iter().map(|s| s.quarters).sum();
        let weight: f64 = members.iter().map(|s| s.quarters.abs() as f64).sum();
        let centre = members.iter().map(|s| metric(grid.uv(s.node)) * s.quarters.abs() as f64).sum::<DVec2>() / weight;
        for s in members {
            removed.push((metric(grid.uv(s.node)), s.quarters));
        }
        centres.push(centre);
        radii.push(members.iter().map(|s| metric(grid.uv(s.node)).distance(centre)).fold(0.0, f64::max) + 1.5 * spacing);
        let count = total.unsigned_abs() as usize;
        let sign = total.signum();
        // Laid out along the field's mean direction near the cluster (after the removal below).
        let along = nearby_angle(grid, crosses, centre, metric, &removed, 2.0 * spacing);
        let dir = |t: f64| DVec2::new(t.cos(), t.sin());
        let apart = SINGULAR_SPREAD * spacing;
        for k in 0..count {
            let p = if count >= 3 {
                centre + apart / (2.0 * (PI / count as f64).sin()) * dir(along + PI / 4.0 + 2.0 * PI * k as f64 / count as f64)
            } else {
                // Two points on a line through the centre at φ add 0.25 (2φ + π) to the field
                // between them (index +1 each; −0.25 (2φ + π) at −1): the line follows the field,
                // so that the two vertices are steps apart along one family, when
                // φ ≡ along + that (mod π/2).
                let axis = if sign > 0 { 2.0 * along + FRAC_PI_2 } else { 2.0 / 3.0 * (along - FRAC_PI_4) };
                centre + apart * (k as f64 - 0.5 * (count as f64 - 1.0)) * dir(axis)
            };
            placed.push((p, sign));
        }
    }
    if removed.is_empty() {
        return found;
    }
    // Snap the placed points to distinct inner nodes.
    let mut snapped: Vec<(DVec2, i32)> = Vec::new();
    let mut taken = std::collections::HashSet::new();
    for (p, sign) in placed {
        let uv = p / scale;
        let i = (((uv.x - grid.origin[0]) / grid.step[0]).round() as i64).clamp(1, grid.nu as i64 - 2) as usize;
        let j = (((uv.y - grid.origin[1]) / grid.step[1]).round() as i64).clamp(1, grid.nv as i64 - 2) as usize;
        let mut node = grid.node(i, j);
        while !taken.insert(node) {
            node = grid.neighbours(node).into_iter().find(|n| !taken.contains(n) && !grid.on_border(*n)).unwrap_or(node);
        }
        snapped.push((metric(grid.uv(node)), sign));
    }
    let arg = |w: DVec2| w.y.atan2(w.x);
    let mul = |a: DVec2, b: DVec2| DVec2::new(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
    // Π (x − p_j)^{σ_j} and Π (x − s_i)^{−k_i}, as unit complex numbers.
    let placed_turn = |x: DVec2| {
        snapped.iter().fold(DVec2::X, |w, &(p, sign)| {
            let d = (x - p).normalize_or_zero();
            mul(w, if sign > 0 { d } else { DVec2::new(d.x, -d.y) })
        })
    };
    let removed_turn = |x: DVec2| {
        removed.iter().fold(DVec2::X, |mut w, &(s, k)| {
            let d = (x - s).normalize_or_zero();
            let d = if k > 0 { DVec2::new(d.x, -d.y) } else { d };
            for _ in 0..k.unsigned_abs() {
                w = mul(w, d);
            }
            w
        })
    };
    let original: Vec<f64> = crosses.iter().map(|c| c.angle).collect();
    // The field with the removed points' turning taken out, at a point (lengths).
    let unwound = |x: DVec2| original[grid.triangle_at(x / scale)] + 0.25 * arg(removed_turn(x));
    for (t, cross) in crosses.iter_mut().enumerate() {
        let x = metric(grid.centroid(t));
        // Inside a cluster's disk the unwound field of its rim, carried in along the rays: the
        // field there is noise about an umbilic.
        let inside = centres.iter().zip(&radii).find(|(c, r)| x.distance(**c) < **r);
        let base = match inside {
            Some((c, r)) => {
                let ray = (x - *c).normalize_or(DVec2::X);
                unwound(*c + *r * ray)
            }
            None => cross.angle + 0.25 * arg(removed_turn(x)),
        };
        cross.angle = base + 0.25 * arg(placed_turn(x));
        let near = centres.iter().zip(&radii).map(|(c, r)| (x.distance(*c) - r).max(0.0)).fold(f64::INFINITY, f64::min) / spacing;
        cross.skew *= (near / 2.5).clamp(0.0, 1.0);
    }
    singular_points(grid, crosses)
}

/// The field's mean cross angle on a ring about `centre` (lengths), with the turning of the
/// `removed` points taken out, so it does not depend on where on the ring one looks.
fn nearby_angle(grid: &FineGrid, crosses: &[Cross], centre: DVec2, metric: impl Fn(DVec2) -> DVec2, removed: &[(DVec2, i32)], radius: f64) -> f64 {
    let mut z = DVec2::ZERO;
    for (t, cross) in crosses.iter().enumerate() {
        let x = metric(grid.centroid(t));
        let d = x.distance(centre);
        if d > radius || d < 0.5 * radius {
            continue;
        }
        let turn: f64 = removed.iter().map(|(s, k)| *k as f64 * (x - *s).y.atan2((x - *s).x)).sum();
        let a = cross.angle - 0.25 * turn;
        z += DVec2::new((4.0 * a).cos(), (4.0 * a).sin());
    }
    0.25 * z.y.atan2(z.x)
}
