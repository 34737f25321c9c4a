//! Cross fields with singular points (Sec. 5.2): their indices, the seamless parametrization
//! with integer jumps across the cuts, and quad meshes with valence 3 and 5 exactly there.

use std::f64::consts::FRAC_PI_2;

use glam::{DVec2, DVec3};
use spherical_faces::geometry::bspline::{BSplineBasis, BSplineSurface};
use spherical_faces::remeshing::cross_field::{singular_points, split_singularities, Cross, CrossField, FineGrid};
use spherical_faces::remeshing::quad_remeshing::{integrate, quad_remesh, FieldGrid, QuadRemeshParams};
use spherical_faces::remeshing::seamless::turn;
use spherical_faces::rng::Rng;
use spherical_faces::sq::sphere_terms::support_plane_bound_deg;

/// The plane z = 0 over [−2, 2]², parametrized by (x, y).
fn plane() -> BSplineSurface {
    let basis = || BSplineBasis::clamped_uniform(1, 2, (-2.0, 2.0)).unwrap();
    let control = vec![DVec3::new(-2.0, -2.0, 0.0), DVec3::new(2.0, -2.0, 0.0), DVec3::new(-2.0, 2.0, 0.0), DVec3::new(2.0, 2.0, 0.0)];
    BSplineSurface::new(basis(), basis(), control, vec![1.0; 4]).unwrap()
}

fn grid() -> FineGrid {
    FineGrid { nu: 41, nv: 41, origin: [-2.0, -2.0], step: [0.1, 0.1] }
}

/// One cross per triangle: angle `quarters`/4 · arg(x − centre).
fn turning(grid: &FineGrid, centre: DVec2, quarters: f64) -> Vec<Cross> {
    (0..grid.triangle_count())
        .map(|t| {
            let d = grid.centroid(t) - centre;
            Cross { angle: 0.25 * quarters * d.y.atan2(d.x), skew: 0.0 }
        })
        .collect()
}

/// The same field on the cells of an n × n grid of the plane, for the remesh.
fn turning_field(surface: &BSplineSurface, centre: DVec2, quarters: f64) -> CrossField {
    let n = 41;
    let cells = n - 1;
    let crosses = (0..cells * cells)
        .map(|k| {
            let (i, j) = (k % cells, k / cells);
            let p = DVec2::new(-2.0 + 4.0 * (i as f64 + 0.5) / cells as f64, -2.0 + 4.0 * (j as f64 + 0.5) / cells as f64) - centre;
            Cross { angle: 0.25 * quarters * p.y.atan2(p.x), skew: 0.0 }
        })
        .collect();
    CrossField { n, domain: surface.domain(), crosses, filled: 0 }
}

#[test]
fn a_cross_keeps_its_lines_through_labels_and_skew() {
    let (d0, d1) = (DVec2::new(1.0, 0.2), DVec2::new(-0.3, 1.0));
    let c = Cross::from_lines(d0, d1);
    for q in -2..=3 {
        let [a, b] = c.turned(q).directions();
        // The same two lines, whatever the labels.
        let on = |x: DVec2, d: DVec2| x.perp_dot(d.normalize()).abs() < 1e-12;
        assert!((on(a, d0) && on(b, d1)) || (on(a, d1) && on(b, d0)), "labels turned by {q}");
        assert!((c.turned(q).z() - c.z()).length() < 1e-12);
    }
}

#[test]
fn a_radial_field_turns_once_about_its_centre_and_a_quarter_field_a_quarter() {
    let g = grid();
    let centre = DVec2::new(0.03, 0.07);
    let radial = singular_points(&g, &turning(&g, centre, 4.0));
    assert_eq!(radial.iter().map(|s| s.quarters).sum::<i32>(), 4, "{radial:?}");
    for s in &radial {
        assert!(g.uv(s.node).distance(centre) < 0.3, "{s:?} far from the centre");
    }
    for q in [1, -1] {
        let found = singular_points(&g, &turning(&g, centre, q as f64));
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].quarters, q);
        // At a corner of the triangle holding the centre.
        assert!(g.uv(found[0].node).distance(centre) < 0.15);
    }
    // A field without singular points has none.
    let parallel: Vec<Cross> = (0..g.triangle_count()).map(|_| Cross { angle: 0.3, skew: 0.1 }).collect();
    assert!(singular_points(&g, &parallel).is_empty());
}

#[test]
fn a_full_turn_splits_into_four_quarter_turns_and_a_dipole_vanishes() {
    let g = grid();
    let mut radial = turning(&g, DVec2::new(0.03, 0.07), 4.0);
    let placed = split_singularities(&g, &mut radial, 1.0, 0.3, DVec2::ONE);
    assert_eq!(placed.len(), 4, "{placed:?}");
    assert!(placed.iter().all(|s| s.quarters == 1));
    // Far from the cluster the field is the radial one still.
    let reference = turning(&g, DVec2::new(0.03, 0.07), 4.0);
    for t in 0..g.triangle_count() {
        if g.centroid(t).length() > 1.8 {
            let d = (radial[t].angle - reference[t].angle).rem_euclid(FRAC_PI_2);
            assert!(d.min(FRAC_PI_2 - d) < 3f64.to_radians(), "triangle {t}: {}°", d.to_degrees());
        }
    }
    // +1 and −1 a little apart: nothing is left.
    let mut dipole: Vec<Cross> = (0..g.triangle_count())
        .map(|t| {
            let x = g.centroid(t);
            let (a, b) = (x - DVec2::new(-0.21, 0.04), x - DVec2::new(0.19, 0.04));
            Cross { angle: 0.25 * (a.y.atan2(a.x) - b.y.atan2(b.x)), skew: 0.0 }
        })
        .collect();
    assert_eq!(singular_points(&g, &dipole).len(), 2);
    assert!(split_singularities(&g, &mut dipole, 1.0, 0.8, DVec2::ONE).is_empty());
}

#[test]
fn the_parametrization_jumps_by_lattice_translations_across_its_cuts() {
    let surface = plane();
    for q in [1.0, -1.0] {
        let field = turning_field(&surface, DVec2::new(0.23, 0.11), q);
        let h = 0.27;
        let g = integrate(&FieldGrid::new(&surface, &field, 60, 12, h, 4.0 * h), 10.0, h).unwrap();
        assert_eq!(g.singular.len(), 1);
        assert_eq!(g.cuts.cuts.len(), 1);
        let cut = &g.cuts.cuts[0];
        assert_eq!(cut.quarters.rem_euclid(4), (q as i32).rem_euclid(4), "period jump of a {q} quarter point");
        // The singular point sits on the lattice.
        let s = cut.path[0];
        let phi = |node: usize| DVec2::new(g.phi[0][node], g.phi[1][node]);
        let key = phi(s) / h;
        assert!((key - key.round()).length() < 1e-9, "φ(s)/h = {key}");
        assert_eq!([key.x.round() as i32, key.y.round() as i32], g.cone_keys[0]);
        // Across the cut: right = M^r (left − φ(s)) + φ(s), a rotation about a lattice point, so
        // the difference of the two sides is a lattice translation wherever the cut is.
        let mut checked = 0;
        for t in 0..g.grid.triangle_count() {
            for (k, &node) in g.grid.triangle(t).iter().enumerate() {
                if let Some(&c) = g.cuts.right.get(&(t, node)) {
                    let right = g.corners[t][k];
                    let expected = turn(g.cuts.cuts[c].quarters, phi(node) - phi(s)) + phi(s);
                    assert!((right - expected).length() < 1e-12);
                    let jump = (right - turn(g.cuts.cuts[c].quarters, phi(node))) / h;
                    assert!((jump - jump.round()).length() < 1e-9, "jump {jump} not on the lattice");
                    checked += 1;
                }
            }
        }
        assert!(checked > 20);
    }
}

#[test]
fn quads_only_with_valence_three_or_five_exactly_at_the_singular_points() {
    let surface = plane();
    for q in [1i32, -1] {
        let field = turning_field(&surface, DVec2::new(0.23, 0.11), q as f64);
        let m = quad_remesh(&surface, &field, &QuadRemeshParams::default()).unwrap();
        assert!(m.mesh.faces.iter().all(|f| f.corners().len() == 4));
        assert_eq!(m.folded_triangles, 0);
        assert_eq!(m.singular.len(), 1, "{:?}", m.singular);
        let (cone, index) = m.singular[0];
        assert_eq!(index, q);
        assert!(DVec2::from(m.uv[cone as usize]).distance(DVec2::new(0.23, 0.11)) < 0.2);
        let mut valence = vec![0; m.mesh.vertex_count()];
        for f in &m.mesh.faces {
            for &v in f.corners() {
                valence[v as usize] += 1;
            }
        }
        assert_eq!(valence[cone as usize], 4 - q, "the singular vertex");
        // Every other vertex away from the boundary has four quads.
        for (v, &n) in valence.iter().enumerate() {
            let p = DVec2::from(m.uv[v]);
            if v != cone as usize && p.x.abs() < 1.4 && p.y.abs() < 1.4 {
                assert_eq!(n, 4, "vertex {v} at {p}");
            }
        }
    }
}

/// A half turn (an umbilic of a generic surface, a lemon) becomes two valence-3 vertices that
/// share no quad: on one quad they would leave its other two corners 60° together, so no support
/// planes there could meet at α.
#[test]
fn the_two_vertices_of_a_half_turn_share_no_quad() {
    let surface = plane();
    for (centre, q) in [(DVec2::new(0.13, -0.08), 2.0), (DVec2::new(-0.21, 0.17), -2.0)] {
        let field = turning_field(&surface, centre, q);
        let m = quad_remesh(&surface, &field, &QuadRemeshParams { target_faces: 150, ..QuadRemeshParams::default() }).unwrap();
        let cones: Vec<u32> = m.singular.iter().map(|&(v, _)| v).collect();
        assert_eq!(cones.len(), 2, "{:?}", m.singular);
        assert!(m.singular.iter().all(|&(_, k)| k as f64 == q / 2.0), "{:?}", m.singular);
        let shared: Vec<usize> = (0..m.mesh.face_count()).filter(|&f| cones.iter().all(|c| m.mesh.faces[f].corners().contains(c))).collect();
        let h = (16.0 / m.mesh.face_count() as f64).sqrt();
        let apart = DVec2::from(m.uv[cones[0] as usize]).distance(DVec2::from(m.uv[cones[1] as usize]));
        assert!(shared.is_empty(), "quads {shared:?} hold both singular vertices ({apart:.2} apart, h ≈ {h:.2})");
        assert!(apart >= 1.8 * h, "{apart:.2} apart, h ≈ {h:.2}");
    }
}

/// m planes through one axis: however they turn, two neighbours meet at no more than the bound
/// (60° for three, 90° for four, 72° for five), and evenly spread ones reach it.
#[test]
fn support_planes_about_one_axis_meet_at_most_at_the_bound() {
    assert_eq!(support_plane_bound_deg(3), 60.0);
    assert_eq!(support_plane_bound_deg(4), 90.0);
    assert!((support_plane_bound_deg(5) - 72.0).abs() < 1e-12);
    let plane_angle = |a: f64, b: f64| {
        let d = (b - a).rem_euclid(180.0);
        d.min(180.0 - d)
    };
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for m in 3..=5usize {
        let bound = support_plane_bound_deg(m);
        let even: Vec<f64> = (0..m).map(|k| 360.0 * k as f64 / m as f64).collect();
        let widest = (0..m).map(|k| plane_angle(even[k], even[(k + 1) % m])).fold(f64::INFINITY, f64::min);
        assert!((widest - bound).abs() < 1e-9, "{m} evenly spread: {widest}");
        for _ in 0..2000 {
            // Half-planes in cyclic order about the axis.
            let mut at: Vec<f64> = (0..m).map(|_| 360.0 * rng.uniform()).collect();
            at.sort_by(f64::total_cmp);
            let worst = (0..m).map(|k| plane_angle(at[k], at[(k + 1) % m])).fold(f64::INFINITY, f64::min);
            assert!(worst <= bound + 1e-9, "{m} planes at {at:?} all meet at ≥ {worst}°");
        }
    }
}
