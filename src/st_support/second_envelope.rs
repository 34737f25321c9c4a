//! Step 6 of Sec. 4: the second envelope, the mesh inverted in Ω (same triangles). Given for
//! R² > 0 (Fig. 10), also for R² < 0 (anti-inversion: the spheres pass through the anti-inverted
//! vertices too) and for a plane Ω (reflection); None for R² = 0 (it degenerates to m).

use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::TriMesh;

pub fn second_envelope(mesh: &TriMesh, omega: &AbsoluteSphere) -> Option<TriMesh> {
    match *omega {
        AbsoluteSphere::Sphere { r2: 0.0, .. } => None,
        _ => mesh.positions.iter().map(|p| omega.invert(*p)).collect::<Option<Vec<_>>>().map(|pos| TriMesh::new(pos, mesh.triangles.clone())),
    }
}
