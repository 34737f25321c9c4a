//! Faces of 4 corners: an exact quad sphere mesh. A surface of revolution sampled along
//! parallels and meridians has isosceles-trapezoid faces, so every face is circular; its sphere
//! is the one through that circle with its centre on the axis. All faces of a ring share that
//! sphere, and two rings' spheres meet in their common parallel. Two triangle fans close the
//! ends, each on the sphere through its pole and its end parallel. The panels must lie on their
//! spheres, share their arcs, tile the spherical zones and caps (Archimedes: area 2πRh), and
//! export: the schedule with four vertex ids, OBJ, and a GLB the Khronos validator accepts.
#![cfg(not(target_arch = "wasm32"))] // native: spawns the glTF validator

mod common;

use std::f64::consts::TAU;

use glam::DVec3;
use spherical_faces::export::glb::glb_json;
use spherical_faces::export::{build_schedule, write_glb, write_obj};
use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::geometry::mesh::{Face, PolyMesh};
use spherical_faces::geometry::sphere::Sphere;
use spherical_faces::panels::build_panels;
use spherical_faces::panels::panel::Panel;
use spherical_faces::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use spherical_faces::reference::Reference;

const RINGS: usize = 6;
const MERIDIANS: usize = 16;

/// The meridian curve: (radius, height) of parallel i.
fn parallel(i: usize) -> (f64, f64) {
    let t = i as f64 / RINGS as f64;
    (1.0 + 0.45 * (2.0 * t).sin(), 1.6 * t)
}

/// The poles' heights: below parallel 0 and above parallel RINGS.
const POLES: [f64; 2] = [-0.35, 1.6 + 0.25];

/// The sphere through the circles (r0, z0) and (r1, z1) about the z axis, centre on the axis,
/// oriented outward (away from the centre): its centre height and radius.
fn axial_sphere((r0, z0): (f64, f64), (r1, z1): (f64, f64)) -> (Sphere, f64) {
    // |(r0, z0) − (0, zc)| = |(r1, z1) − (0, zc)|.
    let zc = (r1 * r1 - r0 * r0 + z1 * z1 - z0 * z0) / (2.0 * (z1 - z0));
    let radius = (r0 * r0 + (z0 - zc) * (z0 - zc)).sqrt();
    (Sphere::from_center_radius(DVec3::new(0.0, 0.0, zc), -radius), radius)
}

/// The vase: parallels i = 0..=RINGS, meridians j = 0..MERIDIANS (closed around the z axis), its
/// quad faces counter-clockwise about the outward normal, and per face the sphere through its
/// circle with the centre on the axis; then the two pole fans (triangles, faces 6·16 and on).
fn vase() -> SphereMesh {
    let mut positions = Vec::new();
    for i in 0..=RINGS {
        let (r, z) = parallel(i);
        for j in 0..MERIDIANS {
            let phi = TAU * j as f64 / MERIDIANS as f64;
            positions.push(DVec3::new(r * phi.cos(), r * phi.sin(), z));
        }
    }
    let id = |i: usize, j: usize| (i * MERIDIANS + j % MERIDIANS) as u32;
    let mut faces = Vec::new();
    let mut spheres = Vec::new();
    for i in 0..RINGS {
        let (sphere, _) = axial_sphere(parallel(i), parallel(i + 1));
        for j in 0..MERIDIANS {
            faces.push(Face::quad([id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j)]));
            spheres.push(sphere);
        }
    }
    let (bottom, top) = (positions.len() as u32, positions.len() as u32 + 1);
    positions.extend(POLES.map(|z| DVec3::new(0.0, 0.0, z)));
    let (bottom_sphere, _) = axial_sphere((0.0, POLES[0]), parallel(0));
    let (top_sphere, _) = axial_sphere(parallel(RINGS), (0.0, POLES[1]));
    for j in 0..MERIDIANS {
        faces.push(Face::triangle([id(0, j + 1), id(0, j), bottom]));
        spheres.push(bottom_sphere);
    }
    for j in 0..MERIDIANS {
        faces.push(Face::triangle([id(RINGS, j), id(RINGS, j + 1), top]));
        spheres.push(top_sphere);
    }
    SphereMesh::new(PolyMesh::new(positions, faces), spheres, BoundaryArcRule::Parallel(DVec3::Z))
}

const QUADS: usize = RINGS * MERIDIANS;

fn diag(sm: &SphereMesh) -> f64 {
    sm.mesh.bbox_diagonal()
}

fn panels(sm: &SphereMesh) -> Vec<Panel> {
    build_panels(sm, 1e-4 * diag(sm))
}

#[test]
fn the_fixture_is_a_quad_sphere_mesh() {
    let sm = vase();
    let d = diag(&sm);
    assert!(sm.mesh.faces[..QUADS].iter().all(|f| f.len() == 4));
    assert!(sm.mesh.faces[QUADS..].iter().all(|f| f.len() == 3));
    for f in 0..sm.mesh.face_count() {
        let s = sm.face_spheres[f];
        assert!((s.discriminant() - 1.0).abs() < 1e-12);
        for p in sm.mesh.face_points(f) {
            assert!(s.distance(p) < 1e-12 * d, "face {f}: a corner is off its sphere");
        }
        // Oriented like the face: the sphere's normal at a corner agrees with the face normal.
        let p = sm.mesh.face_points(f);
        assert!(s.normal_at(p[0]).dot(sm.mesh.face_area_vector(f)) > 0.0, "face {f} misoriented");
    }
    assert!(sm.max_vertex_sphere_residual() < 1e-12 * d);
    // Closed: every edge has two faces (parallels, meridians, spokes).
    let topo = sm.topology();
    assert_eq!(topo.edges().len(), (2 * RINGS + 3) * MERIDIANS);
    assert_eq!(topo.interior_edges().count(), topo.edges().len());
    assert_eq!(topo.stats(&sm.mesh).boundary_loops, 0);
    // Its triangulation splits every quad along the diagonal from corner 0.
    let tri = sm.mesh.triangulated();
    assert_eq!(tri.face_count(), 2 * QUADS + 2 * MERIDIANS);
    assert_eq!(tri.triangles[0], [0, 1, MERIDIANS as u32 + 1]);
    // Kinks: zero within a ring or a fan (one sphere), positive across the parallels.
    let kinks = sm.kink_angles_deg();
    assert_eq!(kinks.iter().filter(|&&k| k < 1e-9).count(), (RINGS + 2) * MERIDIANS);
    assert_eq!(kinks.iter().filter(|&&k| k > 1e-3).count(), (RINGS + 1) * MERIDIANS);
}

#[test]
fn quad_panels_lie_on_their_spheres_and_share_their_arcs() {
    let sm = vase();
    let d = diag(&sm);
    let panels = panels(&sm);
    assert_eq!(panels.len(), sm.mesh.face_count());
    for (f, p) in panels.iter().enumerate() {
        let n = sm.mesh.faces[f].len();
        assert_eq!(p.corners, sm.mesh.faces[f].corners());
        assert_eq!(p.arcs.len(), n);
        assert_eq!(p.arc_vertices.len(), n);
        assert_eq!(p.positions[..n].to_vec(), sm.mesh.face_points(f));
        for x in &p.positions {
            assert!(p.sphere.distance(*x) < 1e-9 * d, "panel {f}: a point is off its sphere");
        }
        assert!(p.chord_error() <= 1e-4 * d * (1.0 + 1e-9), "panel {f}: chord error {}", p.chord_error());
        assert_eq!(p.folded_triangles(), 0, "panel {f}");
        for k in 0..n {
            // Arc k runs from corner k to corner k + 1, on the sphere.
            let pts = p.arc_points(k);
            assert_eq!(pts[0], sm.mesh.positions[p.corners[k] as usize]);
            assert_eq!(*pts.last().unwrap(), sm.mesh.positions[p.corners[(k + 1) % n] as usize]);
        }
    }
    // Every interior edge: the two panels carry the same arc points, in opposite directions.
    let topo = sm.topology();
    for (e, f, g) in topo.interior_edges() {
        let side = |face: u32| topo.edge_faces(e).iter().find(|&&(h, _)| h == face).unwrap().1 as usize;
        let a = panels[f as usize].arc_points(side(f));
        let mut b = panels[g as usize].arc_points(side(g));
        b.reverse();
        assert_eq!(a, b, "edge {:?}: the panels' arcs differ", topo.edges()[e]);
    }
    // Parallel arcs are circles about the axis; meridian arcs and spokes lie in their meridian
    // plane.
    for p in &panels {
        for k in 0..p.arcs.len() {
            let arc = p.arcs[k];
            let (a, b) = (arc.from, arc.to);
            if (a.z - b.z).abs() < 1e-12 {
                assert!(arc.circle.normal.cross(DVec3::Z).length() < 1e-9);
                assert!(arc.circle.center.truncate().length() < 1e-9 * d);
            } else {
                let off_axis = if a.truncate().length() > b.truncate().length() { a } else { b };
                let n = DVec3::Z.cross(off_axis).normalize();
                assert!(arc.circle.normal.cross(n).length() < 1e-9, "meridian arc off its plane");
            }
        }
    }
}

#[test]
fn quad_panels_tile_the_spherical_zones() {
    let sm = vase();
    let panels = panels(&sm);
    // Archimedes: the zone of a sphere of radius R between two planes h apart has area 2πRh.
    let heights = std::iter::once(POLES[0]).chain((0..=RINGS).map(|i| parallel(i).1)).chain([POLES[1]]);
    let heights: Vec<f64> = heights.collect();
    let exact: f64 = (0..RINGS + 2)
        .map(|k| {
            let face = if k == 0 {
                QUADS
            } else if k == RINGS + 1 {
                QUADS + MERIDIANS
            } else {
                (k - 1) * MERIDIANS
            };
            let s = sm.face_spheres[face];
            TAU * s.signed_radius().unwrap().abs() * (heights[k + 1] - heights[k])
        })
        .sum();
    let area: f64 = panels.iter().map(|p| p.area).sum();
    // The tessellation is inscribed (convex spherical pieces), its chords within the tolerance
    // t of the sphere: it falls short of the exact area, by at most about 2t/R of it.
    let t = 1e-4 * diag(&sm);
    let r_min = sm.face_spheres.iter().map(|s| s.signed_radius().unwrap().abs()).fold(f64::INFINITY, f64::min);
    assert!(area <= exact && exact - area < 2.0 * t / r_min * exact, "panels {area} vs zones {exact}");
}

#[test]
fn quad_panels_export() {
    let sm = vase();
    let panels = panels(&sm);
    let reference = Reference::new(sm.mesh.clone());
    // The reference keeps the quads; its triangulation is what distances are measured to.
    assert_eq!(reference.surface().faces, sm.mesh.faces);
    assert_eq!(reference.mesh().face_count(), 2 * QUADS + 2 * MERIDIANS);
    // The two widest rings' radii differ by 1e-4: one radius at 1e-3, two at 1e-6.
    assert_eq!(build_schedule(&panels, &reference, 1e-3).distinct_radii, RINGS + 1);
    let schedule = build_schedule(&panels, &reference, 1e-6);
    assert_eq!(schedule.panel_count, panels.len());
    assert_eq!(schedule.distinct_radii, RINGS + 2);
    for (r, p) in schedule.panels.iter().zip(&panels) {
        let n = p.corners.len();
        assert_eq!(r.vertex_ids, p.corners);
        assert_eq!(r.vertices.len(), n);
        assert_eq!(r.edges.len(), n);
        assert_eq!(r.edges[n - 1].from, p.corners[n - 1]);
        assert_eq!(r.edges[n - 1].to, p.corners[0]);
        // The panels bulge off the flat quads by at most their sagitta.
        assert!(r.max_deviation < 0.05 * sm.mesh.bbox_diagonal());
    }
    let csv = schedule.to_csv();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert!(header.contains(&"v3_id") && header.contains(&"v3_z") && header.contains(&"edge3_radius"));
    assert!(csv.lines().skip(1).all(|row| row.split(',').count() == header.len()));

    let obj = write_obj(&panels, None, None);
    assert_eq!(obj.lines().filter(|l| l.starts_with("g panel_")).count(), panels.len());
    let glb = write_glb(&panels, None, None, None, serde_json::json!({ "method": "quad test" }));
    let j = glb_json(&glb).unwrap();
    assert_eq!(j["nodes"][0]["extras"]["panels"][5]["corners"].as_array().unwrap().len(), 4);
    let dir = common::temp_dir("quad-glb");
    let path = dir.join("quads.glb");
    std::fs::write(&path, &glb).unwrap();
    let (ok, summary) = common::khronos_validate(&path);
    assert!(ok, "{summary}");
    assert_eq!(summary["numErrors"], 0, "{summary}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn topology_of_mixed_faces() {
    // A quad and a triangle sharing an edge.
    let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y, DVec3::new(2.0, 0.5, 0.0)];
    let mesh = PolyMesh::new(positions, vec![Face::quad([0, 1, 2, 3]), Face::triangle([1, 4, 2])]);
    let topo = Topology::new(&mesh);
    assert_eq!(topo.edges().len(), 6);
    let shared = topo.edge_index(1, 2).unwrap();
    assert_eq!(topo.edge_faces(shared), &[(0, 1), (1, 2)]);
    assert_eq!(topo.interior_edges().collect::<Vec<_>>(), vec![(shared, 0, 1)]);
    assert_eq!(topo.vertex_faces(2), &[0, 1]);
    assert!((mesh.face_area_vector(0) - DVec3::Z).length() < 1e-15);
    assert_eq!(mesh.triangulated().triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
}
