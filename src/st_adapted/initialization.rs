//! Initialization of the face spheres (Sec. 3 end): the member of the pencil of spheres through a
//! face's three vertices closest to its central sphere.

use glam::DVec3;

use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;

/// The member of the pencil through `p` closest to `target` (max ⟨s, target⟩), oriented like the
/// triangle (component along the plane member ≥ 0).
pub fn closest_family_member(p: [DVec3; 3], target: &Sphere) -> Sphere {
    let [s0, s1] = Sphere::through_points_family(p);
    let theta = s1.inversive_product(target).atan2(s0.inversive_product(target));
    let (sn, cs) = theta.sin_cos();
    let s = Sphere::combine(&s0, cs, &s1, sn);
    if cs < 0.0 {
        s.flipped()
    } else {
        s
    }
}

/// Initial face spheres: closest pencil members to the mean of the vertices' central spheres.
pub fn initial_spheres(mesh: &TriMesh, vertex_spheres: &[Sphere]) -> Vec<Sphere> {
    (0..mesh.face_count())
        .map(|f| {
            let c = Sphere::blend(mesh.triangles[f].map(|v| vertex_spheres[v as usize].to_array().map(|a| a / 3.0)));
            closest_family_member(mesh.face_points(f), &c)
        })
        .collect()
}
