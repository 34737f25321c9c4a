//! Step 2 of Sec. 4: each face sphere passes through its triangle's three vertices and is
//! orthogonal to Ω ([`Sphere::through_points_orthogonal`]: the null vector of the 4 × 5 system, a
//! plane where it must), oriented like the (working) face normal.

use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::{Cancelled, OnProgress, Progress};
use crate::reference::assumptions::is_sliver;

/// The face spheres of `mesh` orthogonal to `omega`, and how many faces are degenerate: slivers,
/// and faces whose sphere could not be made orthogonal to Ω (they keep their triangle's plane).
pub fn face_spheres(mesh: &TriMesh, omega: &AbsoluteSphere, progress: &mut OnProgress) -> Result<(Vec<Sphere>, usize), Cancelled> {
    let nf = mesh.face_count();
    let omega_coefficients = omega.coefficients();
    let mut face_spheres = Vec::with_capacity(nf);
    let mut degenerate_faces = 0;
    for f in 0..nf {
        if f % 1024 == 0 {
            progress(Progress::new("face_spheres", f, nf))?;
        }
        let p = mesh.face_points(f);
        if is_sliver(p) {
            degenerate_faces += 1;
        }
        let s = match Sphere::through_points_orthogonal(p, &omega_coefficients) {
            Some(s) if s.is_finite() => s,
            _ => {
                degenerate_faces += !is_sliver(p) as usize;
                Sphere::through_points_family(p)[0]
            }
        };
        face_spheres.push(s);
    }
    progress(Progress::new("face_spheres", nf, nf))?;
    Ok((face_spheres, degenerate_faces))
}
