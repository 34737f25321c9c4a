//! A seamless parametrization of a cross field with singular points (Sec. 5.2; the route of
//! QuadCover and MIQ, Kälberer et al. 2007, Bommes et al. 2009).
//!
//! 1. **Cuts** ([`Cuts::new`]): from every singular point a path of grid edges to the grid's
//!    border, no two sharing a node. The cut grid is a disk without singular points.
//! 2. **Combing**: a breadth-first walk over the triangles that never crosses a cut labels every
//!    cross like its neighbour's. Across a cut the labels then differ by r quarter turns, the same
//!    all along it (its period jump).
//! 3. **Transitions**: the nodes on a cut have two copies, one per side. The right copy is
//!    φ′ = Mʳ φ + t with M the quarter turn (φ0, φ1) ↦ (φ1, −φ0) and t = (I − Mʳ) φ(s), s the cut's
//!    singular point: the two sides agree at s. With φ(s) on the integer lattice (times the
//!    spacing), t is a lattice translation, so the lattice lines close up across every cut
//!    (seamless), and every singular point is a lattice point, hence a mesh vertex of valence
//!    4 − index.
//! 4. **Integer step**: the least-squares solve of the gradient rows (as for a field without
//!    singular points), then the singular points are rounded to the nearest free lattice points
//!    and fixed, and the solve is repeated (direct rounding, as MIQ's greedy rounding does in one
//!    pass when the points are few).

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, VecDeque};

use glam::DVec2;

use super::cross_field::{Cross, FineGrid, SingularPoint};

/// A cut: the path from a singular point (first node) to the grid's border (last node), its
/// period jump and the side of every triangle at its nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct Cut {
    pub path: Vec<usize>,
    /// Quarter turns from the left side's labels to the right side's.
    pub quarters: i32,
}

/// The cuts of a grid, the combed crosses and which corners use a right copy.
#[derive(Clone, Debug)]
pub struct Cuts {
    pub cuts: Vec<Cut>,
    /// Per triangle: its cross, labelled consistently across every edge that is not cut.
    pub combed: Vec<Cross>,
    /// (triangle, node) → the cut whose right copy that corner uses.
    pub right: HashMap<(usize, usize), usize>,
    /// Per triangle: its neighbours across edges, with the edge (lo, hi).
    pub adjacency: Vec<Vec<(usize, (usize, usize))>>,
    /// (from, to) across a cut edge → (the cut, σ): coordinates in `from` are
    /// M^σ (x − φ(s)) + φ(s) of coordinates x in `to`.
    pub crossings: HashMap<(usize, usize), (usize, i32)>,
}

/// M^r as a 2 × 2 matrix (rows).
pub(crate) fn quarter_turn(r: i32) -> [[f64; 2]; 2] {
    match r.rem_euclid(4) {
        0 => [[1.0, 0.0], [0.0, 1.0]],
        1 => [[0.0, 1.0], [-1.0, 0.0]],
        2 => [[-1.0, 0.0], [0.0, -1.0]],
        _ => [[0.0, -1.0], [1.0, 0.0]],
    }
}

/// M^r applied to p.
pub fn turn(r: i32, p: DVec2) -> DVec2 {
    let m = quarter_turn(r);
    DVec2::new(m[0][0] * p.x + m[0][1] * p.y, m[1][0] * p.x + m[1][1] * p.y)
}

impl Cuts {
    /// Cuts `grid` at `singular` and combs `crosses` (one per triangle).
    pub fn new(grid: &FineGrid, crosses: &[Cross], singular: &[SingularPoint]) -> Self {
        let paths = cut_paths(grid, singular);
        let nt = grid.triangle_count();
        let cut_edge: HashMap<(usize, usize), usize> =
            paths.iter().enumerate().flat_map(|(c, p)| p.windows(2).map(move |w| ((w[0].min(w[1]), w[0].max(w[1])), c))).collect();
        let adjacency = triangle_adjacency(grid);
        // Combing: breadth first from the middle, never across a cut.
        let mut combed: Vec<Option<Cross>> = vec![None; nt];
        let start = 2 * ((grid.nu - 1) / 2 + (grid.nu - 1) * ((grid.nv - 1) / 2));
        combed[start] = Some(crosses[start]);
        let mut queue = VecDeque::from([start]);
        while let Some(t) = queue.pop_front() {
            let c = combed[t].unwrap();
            for &(s, edge) in &adjacency[t] {
                if combed[s].is_some() || cut_edge.contains_key(&edge) {
                    continue;
                }
                combed[s] = Some(crosses[s].aligned_to(c.angle));
                queue.push_back(s);
            }
        }
        let combed: Vec<Cross> = combed.into_iter().enumerate().map(|(t, c)| c.unwrap_or(crosses[t])).collect();
        // Sides: at every node of a cut, the triangles around it on the left of the path.
        let mut right = HashMap::new();
        let mut cuts = Vec::new();
        let mut edges: Vec<(usize, usize, usize)> = Vec::new();
        for (c, path) in paths.iter().enumerate() {
            let mut jumps = Vec::new();
            for (k, &node) in path.iter().enumerate().skip(1) {
                let around = triangles_at(grid, node);
                // The left triangle of the edge into this node, and the components of the fan
                // with the cut edges removed.
                let (a, b) = (path[k - 1], node);
                let left = around.iter().copied().find(|&t| directed(grid, t, a, b)).expect("an inner cut edge has a left triangle");
                let side = fan_sides(&around, &adjacency, &cut_edge, left);
                for (&t, &is_right) in around.iter().zip(&side) {
                    if is_right {
                        right.insert((t, node), c);
                    }
                }
                // The period jump across the edge (a, b): left and right triangle.
                if let Some(r) = around.iter().copied().find(|&t| directed(grid, t, b, a)) {
                    jumps.push(((combed[r].angle - combed[left].angle) / std::f64::consts::FRAC_PI_2).round() as i32);
                    edges.push((c, left, r));
                }
            }
            let quarters = majority(&jumps);
            cuts.push(Cut { path: path.clone(), quarters });
        }
        let mut crossings = HashMap::new();
        for (c, left, r) in edges {
            let q = cuts[c].quarters;
            crossings.insert((left, r), (c, -q));
            crossings.insert((r, left), (c, q));
        }
        Self { cuts, combed, right, adjacency, crossings }
    }

    /// The corner value of node `node` in triangle `t`: φ there, with the right copy's transition
    /// where the corner is on the right of a cut.
    pub(crate) fn corner_value(&self, t: usize, node: usize, phi: impl Fn(usize) -> DVec2) -> DVec2 {
        match self.right.get(&(t, node)) {
            None => phi(node),
            Some(&c) => {
                let cut = &self.cuts[c];
                let s = phi(cut.path[0]);
                turn(cut.quarters, phi(node)) + s - turn(cut.quarters, s)
            }
        }
    }

    /// The corner value as a linear combination: per function k, (node, function, coefficient).
    pub(crate) fn corner_terms(&self, t: usize, node: usize, k: usize) -> Vec<(usize, usize, f64)> {
        match self.right.get(&(t, node)) {
            None => vec![(node, k, 1.0)],
            Some(&c) => {
                let cut = &self.cuts[c];
                let m = quarter_turn(cut.quarters);
                let s = cut.path[0];
                let mut out = Vec::with_capacity(4);
                for j in 0..2 {
                    if m[k][j] != 0.0 {
                        out.push((node, j, m[k][j]));
                    }
                    let identity = if j == k { 1.0 } else { 0.0 };
                    if identity - m[k][j] != 0.0 {
                        out.push((s, j, identity - m[k][j]));
                    }
                }
                out
            }
        }
    }
}

/// Whether triangle t has the directed edge a → b (counter-clockwise).
fn directed(grid: &FineGrid, t: usize, a: usize, b: usize) -> bool {
    let c = grid.triangle(t);
    (0..3).any(|k| c[k] == a && c[(k + 1) % 3] == b)
}

fn triangles_at(grid: &FineGrid, node: usize) -> Vec<usize> {
    let (i, j) = (node % grid.nu, node / grid.nu);
    let mut out = Vec::with_capacity(6);
    for (a, b) in [(0i64, 0i64), (-1, 0), (-1, -1), (0, -1)] {
        let (ci, cj) = (i as i64 + a, j as i64 + b);
        if ci < 0 || cj < 0 || ci as usize >= grid.nu - 1 || cj as usize >= grid.nv - 1 {
            continue;
        }
        for half in 0..2 {
            let t = 2 * (ci as usize + (grid.nu - 1) * cj as usize) + half;
            if grid.triangle(t).contains(&node) {
                out.push(t);
            }
        }
    }
    out
}

/// Per triangle: its neighbours across edges, with the edge (lo, hi).
fn triangle_adjacency(grid: &FineGrid) -> Vec<Vec<(usize, (usize, usize))>> {
    let nt = grid.triangle_count();
    let mut by_edge: HashMap<(usize, usize), Vec<usize>> = HashMap::with_capacity(2 * nt);
    for t in 0..nt {
        let c = grid.triangle(t);
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(t);
        }
    }
    let mut out = vec![Vec::with_capacity(3); nt];
    for (edge, ts) in by_edge {
        if let [a, b] = ts.as_slice() {
            out[*a].push((*b, edge));
            out[*b].push((*a, edge));
        }
    }
    for n in &mut out {
        n.sort_unstable();
    }
    out
}

/// Which of the triangles `around` a node lie on the other side of the cut edges from `left`.
fn fan_sides(around: &[usize], adjacency: &[Vec<(usize, (usize, usize))>], cut_edge: &HashMap<(usize, usize), usize>, left: usize) -> Vec<bool> {
    let mut reached = vec![false; around.len()];
    let index = |t: usize| around.iter().position(|&a| a == t);
    let mut stack = vec![left];
    reached[index(left).unwrap()] = true;
    while let Some(t) = stack.pop() {
        for &(s, edge) in &adjacency[t] {
            if cut_edge.contains_key(&edge) {
                continue;
            }
            if let Some(k) = index(s) {
                if !reached[k] {
                    reached[k] = true;
                    stack.push(s);
                }
            }
        }
    }
    reached.iter().map(|r| !r).collect()
}

fn majority(values: &[i32]) -> i32 {
    let mut counts = [0usize; 4];
    for v in values {
        counts[v.rem_euclid(4) as usize] += 1;
    }
    (0..4).max_by_key(|&k| counts[k]).unwrap_or(0) as i32
}

/// Shortest paths of grid edges (lengths in parameters) from every singular point to the border,
/// none through a node of an earlier path or another singular point.
fn cut_paths(grid: &FineGrid, singular: &[SingularPoint]) -> Vec<Vec<usize>> {
    let n = grid.node_count();
    let mut blocked = vec![false; n];
    for s in singular {
        blocked[s.node] = true;
    }
    let mut paths = Vec::new();
    for s in singular {
        let mut dist = vec![f64::INFINITY; n];
        let mut prev = vec![usize::MAX; n];
        // Smallest distance first: non-negative floats order as their bits.
        let mut heap = BinaryHeap::new();
        dist[s.node] = 0.0;
        heap.push((Reverse(0f64.to_bits()), s.node));
        let mut end = None;
        while let Some((Reverse(bits), v)) = heap.pop() {
            let d = f64::from_bits(bits);
            if d > dist[v] {
                continue;
            }
            if grid.on_border(v) {
                end = Some(v);
                break;
            }
            for w in grid.neighbours(v) {
                if blocked[w] {
                    continue;
                }
                let nd = d + grid.uv(v).distance(grid.uv(w));
                if nd < dist[w] {
                    dist[w] = nd;
                    prev[w] = v;
                    heap.push((Reverse(nd.to_bits()), w));
                }
            }
        }
        let Some(mut v) = end else { continue };
        let mut path = vec![v];
        while v != s.node {
            v = prev[v];
            path.push(v);
        }
        path.reverse();
        for &v in &path {
            blocked[v] = true;
        }
        paths.push(path);
    }
    paths
}
