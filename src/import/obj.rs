//! Wavefront OBJ: `v` and `f` statements; everything else is ignored (noted if unusual).
//!
//! Two passes over the bytes: the first counts vertices and triangles so that over-limit files
//! are rejected before anything large is allocated; the second parses. Faces are triangulated
//! after all vertices are read (so forward references work): triangles as-is, quads along the
//! shorter valid diagonal, larger polygons by ear clipping in their best-fit (Newell) plane,
//! with a fan as the fallback. Quads are remembered as quads (faces of 4 corners), starting at
//! the corner their diagonal leaves from.

use super::raw::{excerpt, Ctx, ImportError, RawMesh};
use glam::{DVec2, DVec3};
use std::borrow::Cow;
use std::collections::BTreeMap;

/// Polygons with more corners than this are strip-triangulated (ear clipping is quadratic).
const EAR_CLIP_MAX: usize = 256;

/// Logical lines: `\n`-separated, a trailing `\` joins the next line. Yields 1-based line numbers
/// of the first physical line.
struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0, line: 0 }
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, Cow<'a, [u8]>);

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let first_line = self.line + 1;
        let mut joined: Option<Vec<u8>> = None;
        loop {
            let rest = self.data.get(self.pos..).unwrap_or(&[]);
            let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            let phys = &rest[..end];
            self.pos += end + 1;
            self.line += 1;
            let trimmed = phys.trim_ascii_end();
            let continued = trimmed.last() == Some(&b'\\') && self.pos < self.data.len();
            let part = if continued { &trimmed[..trimmed.len() - 1] } else { phys };
            match (&mut joined, continued) {
                (None, false) => return Some((first_line, Cow::Borrowed(part))),
                (None, true) => {
                    let mut buf = part.to_vec();
                    buf.push(b' ');
                    joined = Some(buf);
                }
                (Some(buf), _) => {
                    buf.extend_from_slice(part);
                    if !continued {
                        return joined.map(|b| (first_line, Cow::Owned(b)));
                    }
                    buf.push(b' ');
                }
            }
        }
    }
}

fn strip_comment(line: &[u8]) -> &[u8] {
    match line.iter().position(|&b| b == b'#') {
        Some(i) => &line[..i],
        None => line,
    }
}

fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace() || *b == 0x0b).filter(|t| !t.is_empty())
}

fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

fn parse_i64(tok: &[u8]) -> Option<i64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses an OBJ file into raw (unwelded) triangles.
pub(super) fn parse(bytes: &[u8], ctx: &Ctx) -> Result<RawMesh, ImportError> {
    // Pass 1: counts only.
    let (mut n_vertices, mut n_triangles, mut n_corners) = (0u64, 0u64, 0u64);
    for (_, line) in Lines::new(bytes) {
        let mut it = tokens(strip_comment(&line));
        match it.next() {
            Some(b"v") => n_vertices += 1,
            Some(b"f") | Some(b"fo") => {
                let k = it.count() as u64;
                n_triangles += k.saturating_sub(2);
                n_corners += k;
            }
            _ => {}
        }
    }
    ctx.check_limits(n_triangles, n_vertices)?;
    let n_vertices = n_vertices as usize;

    // Pass 2: parse vertices and collect polygons (corners flattened).
    let mut positions: Vec<DVec3> = Vec::with_capacity(n_vertices);
    let mut corners: Vec<u32> = Vec::with_capacity(n_corners.min(3 * n_triangles) as usize);
    let mut short = 0usize;
    let mut poly_ends: Vec<usize> = Vec::new();
    let mut lines_points = 0usize;
    let mut ignored: BTreeMap<String, usize> = BTreeMap::new();
    for (ln, line) in Lines::new(bytes) {
        let mut it = tokens(strip_comment(&line));
        let Some(keyword) = it.next() else { continue };
        match keyword {
            b"v" => {
                let mut c = [0.0f64; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    let tok = it.next().ok_or_else(|| ctx.malformed(Some(ln), format!("vertex needs 3 coordinates (x y z), found {k}")))?;
                    let x = parse_f64(tok).ok_or_else(|| ctx.malformed(Some(ln), format!("invalid number '{}' in vertex", excerpt(tok))))?;
                    if !x.is_finite() {
                        return Err(ctx.malformed(Some(ln), format!("vertex coordinate '{}' is not a finite number", excerpt(tok))));
                    }
                    *slot = x;
                }
                positions.push(DVec3::from_array(c));
            }
            b"f" | b"fo" => {
                let first = corners.len();
                for tok in it {
                    let v = tok.split(|&b| b == b'/').next().unwrap_or(tok);
                    let i = parse_i64(v).ok_or_else(|| ctx.malformed(Some(ln), format!("invalid vertex index '{}' in face", excerpt(tok))))?;
                    let idx = match i {
                        0 => return Err(ctx.malformed(Some(ln), "face refers to vertex 0, but OBJ vertex numbers start at 1")),
                        i if i > 0 => {
                            if i as u64 > n_vertices as u64 {
                                return Err(ctx.malformed(Some(ln), format!("face refers to vertex {i}, but only {n_vertices} vertices are defined")));
                            }
                            i - 1
                        }
                        i => {
                            let defined = positions.len() as i64;
                            if i.checked_neg().is_none_or(|m| m > defined) {
                                return Err(ctx.malformed(
                                    Some(ln),
                                    format!("face refers to vertex {i} (counting back), but only {defined} vertices are defined before this line"),
                                ));
                            }
                            defined + i
                        }
                    };
                    corners.push(idx as u32);
                }
                // Faces with fewer than three corners are not stored: storage stays bounded by
                // the (checked) triangle count.
                if corners.len() - first < 3 {
                    corners.truncate(first);
                    short += 1;
                } else {
                    poly_ends.push(corners.len());
                }
            }
            b"l" | b"p" => lines_points += 1,
            b"vt" | b"vn" | b"vp" | b"g" | b"o" | b"s" | b"usemtl" | b"mtllib" | b"usemap" | b"maplib" | b"lod" | b"shadow_obj" | b"trace_obj"
            | b"bevel" | b"c_interp" | b"d_interp" => {}
            other => {
                let key = excerpt(other);
                if ignored.len() < 8 || ignored.contains_key(&key) {
                    *ignored.entry(key).or_insert(0) += 1;
                }
            }
        }
    }

    // Triangulation.
    let mut raw = RawMesh { source_polygons: poly_ends.len() + short, ..RawMesh::default() };
    raw.triangles.reserve(n_triangles as usize);
    let mut tri = Triangulator::default();
    let (mut fans, mut big) = (0usize, 0usize);
    let mut start = 0;
    let mut poly: Vec<u32> = Vec::new();
    for &end in &poly_ends {
        poly.clear();
        for &v in corners.get(start..end).unwrap_or(&[]) {
            if poly.last() != Some(&v) {
                poly.push(v);
            }
        }
        start = end;
        while poly.len() > 1 && poly.first() == poly.last() {
            poly.pop();
        }
        if poly.len() < 3 {
            short += 1;
            continue;
        }
        let first = raw.triangles.len();
        if poly.len() > EAR_CLIP_MAX {
            big += 1;
            strip(&poly, &mut raw.triangles);
        } else if !tri.triangulate(&positions, &poly, &mut raw.triangles) {
            fans += 1;
        }
        if poly.len() == 4 {
            // A quad stays a quad: its two triangles share its corner 0 (see `RawMesh::quads`).
            raw.quads.push(first);
        }
    }
    raw.dropped_faces = short;
    if short > 0 {
        raw.notes.push(format!("skipped {short} faces with fewer than 3 distinct vertices"));
    }
    if fans > 0 {
        raw.notes.push(format!("{fans} polygons could not be ear-clipped (self-intersecting or strongly non-planar); fan-triangulated"));
    }
    if big > 0 {
        raw.notes
            .push(format!("{big} polygons with more than {EAR_CLIP_MAX} corners were triangulated as a zigzag strip (exact for convex polygons)"));
    }
    if lines_points > 0 {
        raw.notes.push(format!("skipped {lines_points} line/point elements (l, p)"));
    }
    if !ignored.is_empty() {
        let total: usize = ignored.values().sum();
        let names: Vec<&str> = ignored.keys().map(|s| s.as_str()).collect();
        raw.notes.push(format!("ignored {total} unsupported statements ({})", names.join(", ")));
    }
    raw.positions = positions;
    Ok(raw)
}

/// A zigzag strip between the polygon's two halves: every corner is on at most four triangles
/// (a fan would make one corner a hub of valence n, and curvature estimation there quadratic).
/// Same orientation as the polygon; exact for convex polygons, like a fan.
fn strip(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    let (mut lo, mut hi) = (0usize, poly.len() - 1);
    let mut advance_lo = true;
    while hi - lo >= 2 {
        if advance_lo {
            out.push([poly[lo], poly[lo + 1], poly[hi]]);
            lo += 1;
        } else {
            out.push([poly[lo], poly[hi - 1], poly[hi]]);
            hi -= 1;
        }
        advance_lo = !advance_lo;
    }
}

fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    for i in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[i], poly[i + 1]]);
    }
}

/// Reusable scratch space for polygon triangulation.
#[derive(Default)]
struct Triangulator {
    pts: Vec<DVec2>,
    prev: Vec<usize>,
    next: Vec<usize>,
}

/// Twice the area vector of a polygon (Newell's method, relative to its centroid).
fn newell_normal(pts: &[DVec3]) -> DVec3 {
    let c = pts.iter().copied().sum::<DVec3>() / pts.len().max(1) as f64;
    let mut n = DVec3::ZERO;
    for (i, p) in pts.iter().enumerate() {
        let q = pts[(i + 1) % pts.len()];
        n += (*p - c).cross(q - c);
    }
    n
}

fn cross2(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

impl Triangulator {
    /// Appends triangles for polygon `poly` (indices into `positions`, at least 3, no repeated
    /// consecutive indices) keeping its orientation. Returns false if it fell back to a fan.
    fn triangulate(&mut self, positions: &[DVec3], poly: &[u32], out: &mut Vec<[u32; 3]>) -> bool {
        let p = |i: usize| positions.get(poly[i] as usize).copied().unwrap_or(DVec3::ZERO);
        match poly.len() {
            3 => {
                out.push([poly[0], poly[1], poly[2]]);
                true
            }
            4 => {
                let q = [p(0), p(1), p(2), p(3)];
                let n = newell_normal(&q);
                let up = |a: usize, b: usize, c: usize| (q[b] - q[a]).cross(q[c] - q[a]).dot(n) > 0.0;
                let valid_a = up(0, 1, 2) && up(0, 2, 3);
                let valid_b = up(1, 2, 3) && up(1, 3, 0);
                let shorter_a = q[0].distance_squared(q[2]) <= q[1].distance_squared(q[3]);
                let use_a = match (valid_a, valid_b) {
                    (true, false) => true,
                    (false, true) => false,
                    _ => shorter_a,
                };
                if use_a {
                    out.push([poly[0], poly[1], poly[2]]);
                    out.push([poly[0], poly[2], poly[3]]);
                } else {
                    out.push([poly[1], poly[2], poly[3]]);
                    out.push([poly[1], poly[3], poly[0]]);
                }
                true
            }
            _ => {
                let start = out.len();
                if self.ear_clip(positions, poly, out) {
                    true
                } else {
                    out.truncate(start);
                    fan(poly, out);
                    false
                }
            }
        }
    }

    /// Ear clipping in the plane orthogonal to the Newell normal.
    fn ear_clip(&mut self, positions: &[DVec3], poly: &[u32], out: &mut Vec<[u32; 3]>) -> bool {
        let n = poly.len();
        let pts3: Vec<DVec3> = poly.iter().map(|&v| positions.get(v as usize).copied().unwrap_or(DVec3::ZERO)).collect();
        let Some(normal) = newell_normal(&pts3).try_normalize() else {
            return false;
        };
        let u = normal.any_orthonormal_vector();
        let w = normal.cross(u);
        // (u, w, normal) is right-handed, so the polygon is counter-clockwise in (u, w).
        self.pts.clear();
        self.pts.extend(pts3.iter().map(|q| DVec2::new(q.dot(u), q.dot(w))));
        let (lo, hi) = self.pts.iter().fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(l, h), q| (l.min(*q), h.max(*q)));
        let scale = (hi - lo).max_element();
        if !(scale.is_finite() && scale > 0.0) {
            return false;
        }
        let eps = 1e-12 * scale * scale;
        self.prev.clear();
        self.next.clear();
        self.prev.extend((0..n).map(|i| (i + n - 1) % n));
        self.next.extend((0..n).map(|i| (i + 1) % n));
        let pts = &self.pts;
        let (prev, next) = (&mut self.prev, &mut self.next);

        let mut remaining = n;
        let mut cur = 0usize;
        while remaining > 3 {
            let mut clipped = false;
            // First pass: strictly convex ears; second: also (nearly) collinear corners.
            'passes: for min_turn in [eps, -eps] {
                let mut i = cur;
                let candidates = remaining;
                for _ in 0..candidates {
                    let (a, b, c) = (prev[i], i, next[i]);
                    let (pa, pb, pc) = (pts[a], pts[b], pts[c]);
                    let turn = cross2(pb - pa, pc - pb);
                    if turn > min_turn && Self::is_empty_ear(pts, next, a, b, c, eps) {
                        out.push([poly[a], poly[b], poly[c]]);
                        next[a] = c;
                        prev[c] = a;
                        remaining -= 1;
                        cur = c;
                        clipped = true;
                        break 'passes;
                    }
                    i = next[i];
                }
            }
            if !clipped {
                return false;
            }
        }
        let (a, b, c) = (prev[cur], cur, next[cur]);
        out.push([poly[a], poly[b], poly[c]]);
        true
    }

    /// No other remaining corner lies inside or on triangle (a, b, c).
    fn is_empty_ear(pts: &[DVec2], next: &[usize], a: usize, b: usize, c: usize, eps: f64) -> bool {
        let (pa, pb, pc) = (pts[a], pts[b], pts[c]);
        let mut j = next[c];
        while j != a {
            let q = pts[j];
            if q != pa && q != pb && q != pc {
                let inside = cross2(pb - pa, q - pa) >= -eps && cross2(pc - pb, q - pb) >= -eps && cross2(pa - pc, q - pc) >= -eps;
                if inside {
                    return false;
                }
            }
            j = next[j];
        }
        true
    }
}
