//! How close spherical panels of about N faces can come to a surface at best: per point of a
//! 60×60 grid, the best sphere through a square panel of side h = sqrt(area / N) centred there
//! deviates by about |κ1 − κ2| h² / 16 (the mean-curvature sphere, shifted half-way):
//! `cargo run --release --example sq_feasibility -- FILE.json ...`.
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::sq::radius::SamplingGrid;

fn main() {
    let faces: f64 = std::env::var("N").ok().and_then(|s| s.parse().ok()).unwrap_or(237.0);
    for a in std::env::args().skip(1) {
        let loaded = Loaded::from_file(&std::fs::read(&a).expect("readable"), &a).expect("loads");
        let s = loaded.surface.spline().expect("a B-spline");
        let grid = SamplingGrid::new(s, 60).expect("grid");
        let f = &grid.frames;
        let (mut lo, mut hi) = (glam::DVec3::splat(f64::MAX), glam::DVec3::splat(f64::MIN));
        for p in f {
            lo = lo.min(p.point);
            hi = hi.max(p.point);
        }
        let diag = (hi - lo).length();
        let area: f64 = (0..(grid.n - 1) * (grid.n - 1))
            .map(|q| {
                let c = grid.quad(q).map(|p| f[p].point);
                0.5 * ((c[1] - c[0]).cross(c[3] - c[0]).length() + (c[1] - c[2]).cross(c[3] - c[2]).length())
            })
            .sum();
        let h2 = area / faces;
        let mut dev: Vec<f64> = f.iter().map(|p| (p.k1 - p.k2).abs() * h2 / 16.0 / diag).collect();
        dev.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let over = dev.iter().filter(|&&d| d > 1e-2).count() as f64 / dev.len() as f64;
        let n_needed = faces * (dev[dev.len() - 1] / 1e-2).max(dev[(dev.len() as f64 * 0.99) as usize] / 1e-2);
        println!(
            "{:<40} max {:.2e} p99 {:.2e} p50 {:.2e} over 1e-2 on {:.1}% ; N for max {:.0}",
            a.rsplit('/').next().unwrap(),
            dev[dev.len() - 1],
            dev[(dev.len() as f64 * 0.99) as usize],
            dev[dev.len() / 2],
            100.0 * over,
            n_needed
        );
    }
}
