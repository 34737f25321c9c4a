//! Picking: the mesh vertex under the pointer (for the central-sphere overlay).

use glam::Vec3;

/// The vertex of the triangles (flat positions and indices) nearest to where the ray `o + s d`
/// first hits them, if it hits them.
pub fn pick_vertex(positions: &[f32], triangles: &[u32], o: Vec3, d: Vec3) -> Option<usize> {
    let vtx = |i: u32| Vec3::from_slice(&positions[3 * i as usize..3 * i as usize + 3]);
    let mut best: Option<(f32, [u32; 3], Vec3)> = None;
    for t in triangles.chunks_exact(3) {
        let (a, b, c) = (vtx(t[0]), vtx(t[1]), vtx(t[2]));
        if let Some(s) = ray_triangle(o, d, a, b, c) {
            if best.is_none_or(|(bs, ..)| s < bs) {
                best = Some((s, [t[0], t[1], t[2]], o + d * s));
            }
        }
    }
    let (_, tri, hit) = best?;
    tri.into_iter().min_by(|&a, &b| (vtx(a) - hit).length().total_cmp(&(vtx(b) - hit).length())).map(|v| v as usize)
}

/// Möller–Trumbore: the ray parameter of the hit, if any.
pub fn ray_triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let t = o - a;
    let u = t.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = t.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let s = e2.dot(q) * inv;
    (s > 0.0).then_some(s)
}
