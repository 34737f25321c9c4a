//! The sphere toolkit (Sec. 2.4, Sec. 4) against explicit geometry: the pencil through three points, the
//! member orthogonal to Ω (R² > 0, < 0, = 0, plane), orientation, kink angles vs explicit
//! normals, inversion and power, the second common point of a vertex star. Tolerances ≈ 1e-12.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns processes

use glam::DVec3;
use spherical_faces::congruence::support_structure::{second_common_point, star_axis, STAR_AXIS_MIN_CONDITION};
use spherical_faces::geometry::absolute_sphere::AbsoluteSphere;
use spherical_faces::geometry::circle::Circle;
use spherical_faces::geometry::linalg::Svd;
use spherical_faces::geometry::sphere::Sphere;
use spherical_faces::rng::Rng;

fn assert_normalized(s: &Sphere) {
    assert!((s.discriminant() - 1.0).abs() < 1e-12, "not normalized: {s:?} ({})", s.discriminant());
}

/// Residual of "x on s" as a Euclidean distance, relative to `scale`.
fn on(s: &Sphere, x: DVec3, scale: f64) -> f64 {
    s.distance(x) / scale
}

fn triangle(rng: &mut Rng, s: f64) -> [DVec3; 3] {
    let o = rng.vec(2.0 * s);
    [o + rng.vec(s), o + rng.vec(s), o + rng.vec(s)]
}

fn tri_normal(p: &[DVec3; 3]) -> DVec3 {
    (p[1] - p[0]).cross(p[2] - p[0]).normalize()
}

#[test]
fn svd_gives_orthonormal_right_vectors_and_null_space() {
    let mut rng = Rng(7);
    for m in [3usize, 4, 6] {
        let rows: Vec<[f64; 5]> =
            (0..m).map(|_| [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)]).collect();
        let svd = Svd::new(&rows);
        for i in 0..5 {
            for j in 0..5 {
                let d: f64 = (0..5).map(|k| svd.v[i][k] * svd.v[j][k]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
            // ‖A v_i‖ = σ_i.
            let n: f64 = rows.iter().map(|r| (0..5).map(|k| r[k] * svd.v[i][k]).sum::<f64>().powi(2)).sum::<f64>().sqrt();
            assert!((n - svd.sigma[i]).abs() < 1e-14, "{n} vs {}", svd.sigma[i]);
        }
        assert!(svd.sigma.windows(2).all(|w| w[0] >= w[1]));
        for i in m.min(5)..5 {
            assert!(svd.sigma[i] < 1e-14);
        }
    }
}

#[test]
fn frame_round_trip_and_distance() {
    let mut rng = Rng(11);
    for _ in 0..50 {
        let s = Sphere::from_center_radius(rng.vec(5.0), rng.range(0.3, 4.0) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 });
        let (t, sigma) = (rng.vec(3.0), rng.range(0.1, 10.0));
        let local = s.in_frame(t, sigma);
        // Same set, same orientation.
        let y = rng.vec(2.0);
        let x = t + sigma * y;
        assert!((local.eval(y) - s.eval(x)).abs() < 1e-10 * (1.0 + s.eval(x).abs()));
        assert!((local.discriminant() - sigma * sigma * s.discriminant()).abs() < 1e-10 * sigma * sigma);
        let back = local.from_frame(t, sigma);
        for (p, q) in back.to_array().iter().zip(s.to_array()) {
            assert!((p - q).abs() < 1e-11 * (1.0 + q.abs()), "{back:?} vs {s:?}");
        }
        // Unsigned distance.
        let c = s.center().unwrap();
        let r = s.signed_radius().unwrap();
        let p = rng.vec(6.0);
        assert!((s.distance(p) - ((p - c).length() - r.abs()).abs()).abs() < 1e-12 * (1.0 + p.length()));
    }
    // Huge radius: the distance stays exact where | |x − c| − r | would cancel.
    let f = DVec3::new(1.0, 2.0, 3.0);
    let n = DVec3::new(2.0, -1.0, 2.0) / 3.0;
    let s = Sphere::from_point_normal_curvature(f, n, 1e-12);
    let x = f + 0.25 * n + DVec3::new(1.0, 2.0, 0.0).cross(n) * 0.1;
    assert!((s.distance(x) - 0.25).abs() < 1e-10, "{}", s.distance(x));
    assert!((Sphere::plane(f, n).distance(x) - 0.25).abs() < 1e-15);
}

#[test]
fn pencil_through_three_points() {
    let mut rng = Rng(3);
    for k in 0..200 {
        let scale = [1e-3, 1.0, 50.0][k % 3];
        let p = triangle(&mut rng, scale);
        let [plane, sph] = Sphere::through_points_family(p);
        assert_normalized(&plane);
        assert_normalized(&sph);
        assert_eq!(plane.a, 0.0);
        assert!((plane.b - tri_normal(&p)).length() < 1e-11, "{:?} vs {:?}", plane.b, tri_normal(&p));
        assert!(plane.inversive_product(&sph).abs() < 1e-12);
        assert!(sph.signed_radius().unwrap() > 0.0);
        let c = sph.center().unwrap();
        let diam = (p[1] - p[0]).length().max((p[2] - p[0]).length());
        // Centre in the plane of the points: the circumcentre.
        assert!(plane.distance(c) < 1e-11 * (diam + c.length()), "{}", plane.distance(c) / diam);
        for theta in [0.0, 0.3, 1.2, 2.0, 3.0, -0.7] {
            let s = Sphere::combine(&plane, f64::cos(theta), &sph, f64::sin(theta));
            assert!((s.discriminant() - 1.0).abs() < 1e-11);
            for q in p {
                assert!(on(&s, q, diam) < 1e-11, "theta {theta}: {}", on(&s, q, diam));
                // Oriented like the triangle for cos θ > 0: the normal on the points is
                // cos θ n + sin θ (in-plane).
                assert!((s.normal_at(q).dot(tri_normal(&p)) - theta.cos()).abs() < 1e-10);
            }
        }
    }
    // Collinear points: two planes through the line.
    let p = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 1.0), DVec3::new(3.0, 3.0, 3.0)];
    for s in Sphere::through_points_family(p) {
        assert!(s.a.abs() < 1e-14);
        for q in p {
            assert!(s.distance(q) < 1e-13);
        }
    }
}

/// The member of the pencil with a given curvature: through the points, exactly that radius,
/// the orientation of the sphere it starts from, the nearer of the two (small cap before big
/// cap), and none below the circumradius.
#[test]
fn pencil_member_of_a_given_radius() {
    let mut rng = Rng(11);
    for k in 0..200 {
        let scale = [1e-3, 1.0, 50.0][k % 3];
        let p = triangle(&mut rng, scale);
        let [plane, sph] = Sphere::through_points_family(p);
        let rho = sph.signed_radius().unwrap();
        let diam = (p[1] - p[0]).length().max((p[2] - p[0]).length());
        // A small cap of either orientation, and its curvature moved by up to 30 %.
        let theta = [0.2, -0.4, 0.6, 2.9][k % 4];
        let near = Sphere::combine(&plane, f64::cos(theta), &sph, f64::sin(theta));
        let own = 2.0 * near.a;
        let target = own * (0.7 + 0.6 * (k as f64 / 200.0));
        let s = Sphere::through_points_with_curvature(p, target, &near).expect("above the circumradius");
        assert_normalized(&s);
        for q in p {
            assert!(on(&s, q, diam) < 1e-11, "{}", on(&s, q, diam));
            // Orientation kept: the normals on the points agree in sign.
            assert!(s.normal_at(q).dot(near.normal_at(q)) > 0.0);
        }
        let r = s.signed_radius().unwrap();
        assert!((r - 1.0 / target).abs() <= 1e-12 * r.abs().max(diam), "radius {r} vs {}", 1.0 / target);
        // The nearer member: its angle to `near` is below that of the other solution.
        let phi = (target * rho).asin();
        let other = |phi: f64| Sphere::combine(&plane, phi.cos(), &sph, phi.sin());
        let far = if s.inversive_product(&other(phi)) > 1.0 - 1e-9 { other(std::f64::consts::PI - phi) } else { other(phi) };
        assert!(s.inversive_product(&near) >= far.inversive_product(&near) - 1e-12);
        // Below the circumradius there is none.
        assert!(Sphere::through_points_with_curvature(p, 1.01 / rho, &near).is_none());
    }
}

fn check_orthogonal(s: &Sphere, omega: &AbsoluteSphere, scale: f64) {
    let defect = omega.orthogonality_defect(s);
    match omega {
        AbsoluteSphere::Sphere { .. } => assert!(defect <= 1e-11 * scale * scale, "defect {defect} scale {scale}"),
        AbsoluteSphere::Plane { .. } => assert!(defect <= 1e-11 * scale, "defect {defect}"),
    }
    // The coefficient row of the notes vanishes too.
    let row = omega.row();
    let dot: f64 = row.iter().zip(s.to_array()).map(|(r, x)| r * x).sum();
    let norm: f64 = row.iter().map(|r| r * r).sum::<f64>().sqrt();
    assert!(dot.abs() <= 1e-12 * norm, "row residual {dot} (norm {norm})");
}

#[test]
fn member_orthogonal_to_omega_recovers_a_known_sphere() {
    let mut rng = Rng(5);
    for k in 0..300 {
        // A known sphere S (centre C, signed radius r) and a centre m; R² := |C − m|² − r² makes
        // S orthogonal to Ω, whatever its sign.
        let c = rng.vec(3.0);
        let r = rng.range(0.5, 5.0) * if k % 2 == 0 { 1.0 } else { -1.0 };
        let m = match k % 4 {
            0 => c + rng.unit() * (r.abs() * rng.range(1.05, 3.0)), // R² > 0
            1 => c + rng.unit() * (r.abs() * rng.range(0.0, 0.95)), // R² < 0
            _ => rng.vec(6.0),
        };
        let mut r2 = (c - m).length_squared() - r * r;
        if k % 10 == 7 {
            // R² = 0: Ω is the point m on S.
            let m0 = c + rng.unit() * r.abs();
            r2 = 0.0;
            let omega = AbsoluteSphere::Sphere { center: m0, r2 };
            let p = [c + rng.unit() * r.abs(), c + rng.unit() * r.abs(), c + rng.unit() * r.abs()];
            let s = Sphere::through_points_orthogonal(p, &omega.coefficients()).unwrap();
            assert!(s.distance(m0) < 1e-11 * r.abs(), "passes through m: {}", s.distance(m0));
            continue;
        }
        let omega = AbsoluteSphere::Sphere { center: m, r2 };
        let p = [c + rng.unit() * r.abs(), c + rng.unit() * r.abs(), c + rng.unit() * r.abs()];
        let s = Sphere::through_points_orthogonal(p, &omega.coefficients()).unwrap();
        assert_normalized(&s);
        check_orthogonal(&s, &omega, r.abs() + (c - m).length());
        for q in p {
            assert!(on(&s, q, r.abs()) < 1e-12);
        }
        let got_c = s.center().unwrap();
        assert!((got_c - c).length() < 1e-10 * (r.abs() + c.length()), "k={k}: {got_c} vs {c}");
        assert!((s.signed_radius().unwrap().abs() - r.abs()).abs() < 1e-10 * r.abs());
        // Oriented like the triangle.
        assert!(s.normal_at(p[0]).dot(tri_normal(&p)) > 0.0);
        // The null vector of the 4 × 5 matrix.
        let arr = s.to_array();
        for q in p {
            let row = Sphere::point_row(q);
            let v: f64 = row.iter().zip(arr).map(|(x, y)| x * y).sum();
            assert!(v.abs() < 1e-11 * (1.0 + q.length_squared()));
        }
    }
}

#[test]
fn member_orthogonal_to_plane_omega_and_plane_members() {
    let mut rng = Rng(9);
    for _ in 0..100 {
        let axis = rng.unit();
        let d = rng.range(-3.0, 3.0);
        let omega = AbsoluteSphere::Plane { axis, d };
        let p = triangle(&mut rng, 1.0);
        let s = Sphere::through_points_orthogonal(p, &omega.coefficients()).unwrap();
        assert_normalized(&s);
        let c = s.center().unwrap();
        assert!((c.dot(axis) - d).abs() < 1e-10 * (1.0 + c.length()), "centre off the plane: {}", c.dot(axis) - d);
        check_orthogonal(&s, &omega, 1.0);
        for q in p {
            assert!(s.distance(q) < 1e-12 * (1.0 + q.length()));
        }
    }
    // A triangle whose plane contains m: the member orthogonal to Ω is that plane (a = 0), found
    // without a special case, for R² of either sign.
    for r2 in [4.0, -4.0, 0.0] {
        let m = DVec3::new(0.3, -0.2, 0.0);
        let omega = AbsoluteSphere::Sphere { center: m, r2 };
        let p = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0), DVec3::new(-1.0, -1.0, 0.0)];
        let s = Sphere::through_points_orthogonal(p, &omega.coefficients()).unwrap();
        assert!(s.a.abs() < 1e-14, "{s:?}");
        assert!((s.b - DVec3::Z).length() < 1e-14);
        assert!(s.c.abs() < 1e-14);
        // Nearly so: a huge sphere, continuously.
        let q = [p[0], p[1], DVec3::new(-1.0, -1.0, 1e-9)];
        let s = Sphere::through_points_orthogonal(q, &omega.coefficients()).unwrap();
        assert!(s.a.abs() < 1e-8 && s.a != 0.0, "{s:?}");
        check_orthogonal(&s, &omega, 1.0 / s.a.abs());
    }
    // Degenerate: R² = 0 with m on the points' circle: every member passes through m.
    let p = [DVec3::X, DVec3::Y, -DVec3::X];
    let omega = AbsoluteSphere::Sphere { center: -DVec3::Y, r2: 0.0 };
    assert!(Sphere::through_points_orthogonal(p, &omega.coefficients()).is_none());
}

#[test]
fn orientation_helpers() {
    let s = Sphere::from_center_radius(DVec3::new(1.0, 2.0, 3.0), 2.0);
    let x = DVec3::new(1.0, 2.0, 5.0);
    // Positive radius: the normal points to the centre.
    assert!((s.normal_at(x) - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-15);
    let f = s.flipped();
    assert!((f.normal_at(x) - DVec3::Z).length() < 1e-15);
    assert_eq!(f.center(), s.center());
    assert!((f.signed_radius().unwrap() + 2.0).abs() < 1e-15);
    assert_eq!(s.orient_toward(x, DVec3::Z), f);
    assert_eq!(s.orient_toward(x, -DVec3::Z), s);
    // from_point_normal_curvature has N(f) = n.
    let n = DVec3::new(2.0, 2.0, 1.0) / 3.0;
    for h in [0.3, -0.3, 0.0] {
        let t = Sphere::from_point_normal_curvature(x, n, h);
        assert!((t.normal_at(x) - n).length() < 1e-15);
    }
}

/// A point of the intersection circle and the explicit unit normals (c − x)/r of both spheres.
fn explicit_kink(s1: &Sphere, s2: &Sphere) -> f64 {
    let circle = Circle::intersection(s1, s2).unwrap();
    let u = circle.normal.any_orthonormal_vector();
    let x = circle.center + circle.radius * u;
    let n = |s: &Sphere| match (s.center(), s.signed_radius()) {
        (Some(c), Some(r)) => (c - x) / r,
        _ => s.b,
    };
    assert!(s1.distance(x) < 1e-12 && s2.distance(x) < 1e-12);
    n(s1).dot(n(s2)).clamp(-1.0, 1.0).acos()
}

#[test]
fn kink_angle_matches_explicit_normals() {
    let mut rng = Rng(13);
    for _ in 0..200 {
        let c1 = rng.vec(2.0);
        let r1 = rng.range(0.5, 3.0);
        let r2 = rng.range(0.5, 3.0);
        let phi = rng.range(0.05, 3.0);
        // |c1 − c2|² = r1² + r2² − 2 r1 r2 cos φ.
        let d = (r1 * r1 + r2 * r2 - 2.0 * r1 * r2 * phi.cos()).sqrt();
        let c2 = c1 + rng.unit() * d;
        for (sa, sb) in [(1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
            let s1 = Sphere::from_center_radius(c1, sa * r1);
            let s2 = Sphere::from_center_radius(c2, sb * r2);
            let k = s1.kink_angle(&s2);
            assert!((k - explicit_kink(&s1, &s2)).abs() < 1e-9, "{k} vs {}", explicit_kink(&s1, &s2));
            assert!((k.cos() - s1.inversive_product(&s2)).abs() < 1e-12);
            let expected = if sa * sb > 0.0 { phi } else { std::f64::consts::PI - phi };
            assert!((k - expected).abs() < 1e-11, "{k} vs {expected}");
        }
        // A sphere and a plane through the common circle.
        let plane = Sphere::plane(c1 + DVec3::new(0.0, 0.0, 0.3 * r1), DVec3::Z);
        let s1 = Sphere::from_center_radius(c1, r1);
        assert!((s1.kink_angle(&plane) - explicit_kink(&s1, &plane)).abs() < 1e-9);
    }
    // Tiny angles between panels (nearly equal spheres through a common circle) stay accurate:
    // arccos of the inversive product would lose half the digits. Common circle of radius ρ in
    // z = 0; centres on the z-axis at heights h₁, h₂ with atan(h₂/ρ) − atan(h₁/ρ) = φ.
    for phi in [1e-4f64, 1e-7, 1e-10] {
        let rho = 0.5f64;
        let h1 = 0.8f64;
        let h2 = rho * ((h1 / rho).atan() + phi).tan();
        let s1 = Sphere::from_center_radius(DVec3::new(0.0, 0.0, h1), rho.hypot(h1));
        let s2 = Sphere::from_center_radius(DVec3::new(0.0, 0.0, h2), rho.hypot(h2));
        let k = s1.kink_angle(&s2);
        assert!((k - phi).abs() < 1e-6 * phi + 1e-15, "phi {phi}: {k}");
        let naive = s1.inversive_product(&s2).clamp(-1.0, 1.0).acos();
        if phi < 1e-7 {
            assert!((naive - phi).abs() > 1e-3 * phi, "arccos happened to be accurate");
        }
        assert_eq!(s1.kink_angle(&s1), 0.0);
    }
}

#[test]
fn inversion_and_power() {
    let mut rng = Rng(17);
    let m = DVec3::new(1.0, -2.0, 0.5);
    for r2 in [4.0, -2.25, 0.0] {
        let omega = AbsoluteSphere::Sphere { center: m, r2 };
        for _ in 0..50 {
            let x = rng.vec(5.0);
            let y = omega.invert(x).unwrap();
            assert!((omega.power(x) - ((x - m).length_squared() - r2)).abs() < 1e-12);
            if r2 == 0.0 {
                assert_eq!(y, m);
                continue;
            }
            // On the line through m, with |x − m|·|y − m| = |R²|, same side iff R² > 0.
            assert!((x - m).cross(y - m).length() < 1e-12 * (x - m).length() * (y - m).length());
            assert!(((x - m).dot(y - m) - r2).abs() < 1e-12 * r2.abs());
            // An involution.
            assert!((omega.invert(y).unwrap() - x).length() < 1e-12 * (1.0 + x.length()));
        }
        if r2 > 0.0 {
            let on_omega = m + r2.sqrt() * DVec3::new(0.6, 0.0, 0.8);
            assert!((omega.invert(on_omega).unwrap() - on_omega).length() < 1e-14);
        }
        assert!(omega.invert(m).is_none());
        // A sphere orthogonal to Ω is mapped onto itself (also for R² < 0).
        if r2 != 0.0 {
            let p = [rng.vec(3.0), rng.vec(3.0), rng.vec(3.0)];
            let s = Sphere::through_points_orthogonal(p, &omega.coefficients()).unwrap();
            for q in p {
                let y = omega.invert(q).unwrap();
                assert!(s.distance(y) < 1e-11 * (1.0 + y.length()), "{}", s.distance(y));
            }
        }
    }
    // The plane: reflection; power is the signed distance.
    let axis = DVec3::new(0.0, 0.6, 0.8);
    let omega = AbsoluteSphere::Plane { axis, d: 1.5 };
    let x = DVec3::new(1.0, 2.0, 3.0);
    let y = omega.invert(x).unwrap();
    assert!((omega.power(x) - (x.dot(axis) - 1.5)).abs() < 1e-15);
    assert!((omega.power(y) + omega.power(x)).abs() < 1e-14);
    assert!((y - x).cross(axis).length() < 1e-14);
    // Coefficients: eval = power; the row is proportional to the inversive row.
    for omega in [AbsoluteSphere::Sphere { center: m, r2: 3.0 }, AbsoluteSphere::Sphere { center: m, r2: -3.0 }, omega] {
        let k = omega.coefficients();
        assert!((k.eval(x) - omega.power(x)).abs() < 1e-12);
        let (a, b) = (omega.row(), k.inversive_row());
        let ratio = if b[0].abs() > 1e-9 { a[0] / b[0] } else { a[1] / b[1] };
        for (p, q) in a.iter().zip(b) {
            assert!((p - ratio * q).abs() < 1e-12 * (1.0 + p.abs()));
        }
    }
}

/// `count` spheres through v orthogonal to Ω, through random further points.
fn star(rng: &mut Rng, v: DVec3, omega: &AbsoluteSphere, count: usize) -> Vec<Sphere> {
    (0..count)
        .map(|_| {
            let p = [v, v + rng.vec(1.0), v + rng.vec(1.0)];
            Sphere::through_points_orthogonal(p, &omega.coefficients()).unwrap()
        })
        .collect()
}

#[test]
fn second_common_point_of_a_star() {
    let mut rng = Rng(23);
    let m = DVec3::new(0.5, 0.2, -3.0);
    for r2 in [9.0, 2.0, -4.0, 0.0] {
        let omega = AbsoluteSphere::Sphere { center: m, r2 };
        for _ in 0..50 {
            let v = rng.vec(2.0);
            let k = 3 + (rng.uniform() * 5.0) as usize;
            let spheres = star(&mut rng, v, &omega, k);
            let expected = omega.invert(v).unwrap();
            let got = second_common_point(&spheres, v).expect("determined");
            let scale = (expected - m).length().max((v - m).length());
            assert!((got - expected).length() < 1e-11 * scale, "R² {r2}: {got} vs {expected}");
            // The axis passes through m.
            let axis = star_axis(&spheres, v).unwrap();
            assert!((m - v).cross(axis.direction).length() < 1e-11 * (m - v).length());
            assert!(axis.condition >= STAR_AXIS_MIN_CONDITION);
        }
    }
    // Plane Ω: the reflection of v.
    let omega = AbsoluteSphere::Plane { axis: DVec3::new(0.0, 0.0, 1.0), d: -2.0 };
    for _ in 0..20 {
        let v = rng.vec(2.0);
        let spheres = star(&mut rng, v, &omega, 5);
        let got = second_common_point(&spheres, v).unwrap();
        assert!((got - omega.invert(v).unwrap()).length() < 1e-11);
    }
    // Undetermined: two spheres, or all spheres equal.
    let v = DVec3::new(0.0, 0.0, 1.0);
    let s = Sphere::from_center_radius(DVec3::ZERO, 1.0);
    assert!(second_common_point(&[s, s.flipped()], v).is_none());
    assert!(second_common_point(&[s, s, s, s], v).is_none());
    // All planes through a common line: the line, v̄ at infinity.
    let dir = DVec3::new(1.0, 2.0, 2.0) / 3.0;
    let planes: Vec<Sphere> = (0..4).map(|_| Sphere::plane(v, dir.cross(rng.unit()).normalize())).collect();
    let axis = star_axis(&planes, v).unwrap();
    assert!(axis.second_point.is_none());
    assert!(axis.direction.cross(dir).length() < 1e-12);
    assert!(second_common_point(&planes, v).is_none());
}
