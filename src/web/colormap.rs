//! Colour maps for per-vertex scalars: the same maps as shaders/mesh.wgsl, for the legend.

use egui::{Color32, Painter, Pos2, Rect, Vec2};

/// A robust display range (2nd to 98th percentile of finite values) and whether the data
/// straddles zero, in which case the range is symmetric and the map diverging.
pub fn robust_range(values: &[f32]) -> ((f32, f32), bool) {
    let mut v: Vec<f32> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return ((0.0, 1.0), false);
    }
    v.sort_by(f32::total_cmp);
    let at = |q: f32| v[((v.len() - 1) as f32 * q).round() as usize];
    let (lo, hi) = (at(0.02), at(0.98));
    if lo < 0.0 && hi > 0.0 {
        let m = lo.abs().max(hi.abs());
        ((-m, m), true)
    } else if hi - lo <= f32::EPSILON * hi.abs().max(1e-30) {
        ((lo - 0.5 * lo.abs().max(1e-6), hi + 0.5 * hi.abs().max(1e-6)), false)
    } else {
        ((lo, hi), false)
    }
}

/// A symmetric range (−m, m) for a diverging map of values whose sign matters: m is the 80th
/// percentile of |value| (finite values), so that a few peaks do not wash out where the sign
/// changes.
pub fn symmetric_range(values: &[f32]) -> (f32, f32) {
    let mut v: Vec<f32> = values.iter().map(|x| x.abs()).filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (-1.0, 1.0);
    }
    v.sort_by(f32::total_cmp);
    let m = v[((v.len() - 1) as f32 * 0.8).round() as usize].max(1e-12);
    (-m, m)
}

pub fn viridis(t: f32) -> [f32; 3] {
    const C: [[f32; 3]; 7] = [
        [0.2777, 0.0054, 0.3340],
        [0.1050, 1.4046, 1.3845],
        [-0.3309, 0.2148, 0.0951],
        [-4.6342, -5.7991, -19.3324],
        [6.2283, 14.1799, 56.6906],
        [4.7764, -13.7451, -65.3530],
        [-5.4355, 4.6459, 26.3124],
    ];
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut acc = C[6][k];
        for j in (0..6).rev() {
            acc = C[j][k] + t * acc;
        }
        *o = acc.clamp(0.0, 1.0);
    }
    out
}

pub fn diverging(t: f32) -> [f32; 3] {
    let mix = |a: [f32; 3], b: [f32; 3], s: f32| [a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s, a[2] + (b[2] - a[2]) * s];
    let (blue, white, red) = ([0.23, 0.30, 0.75], [0.87, 0.87, 0.87], [0.71, 0.02, 0.15]);
    if t < 0.5 {
        mix(blue, white, t * 2.0)
    } else {
        mix(white, red, (t - 0.5) * 2.0)
    }
}

/// The shader writes linear values into an sRGB target; match that for the legend.
fn to_color(c: [f32; 3]) -> Color32 {
    Color32::from(egui::Rgba::from_rgb(c[0], c[1], c[2]))
}

/// A vertical colour bar with its range, in the viewport's top-right corner.
pub fn legend(painter: &Painter, viewport: Rect, label: &str, range: (f32, f32), diverging_map: bool) {
    let size = Vec2::new(18.0, 160.0);
    let min = Pos2::new(viewport.max.x - 90.0, viewport.min.y + 36.0);
    let bar = Rect::from_min_size(min, size);
    let steps = 32;
    for i in 0..steps {
        let t0 = i as f32 / steps as f32;
        let t1 = (i + 1) as f32 / steps as f32;
        let c = if diverging_map { diverging(1.0 - t0) } else { viridis(1.0 - t0) };
        let r = Rect::from_min_max(Pos2::new(bar.min.x, bar.min.y + t0 * size.y), Pos2::new(bar.max.x, bar.min.y + t1 * size.y + 0.5));
        painter.rect_filled(r, 0.0, to_color(c));
    }
    let font = egui::FontId::proportional(12.0);
    let text = Color32::from_gray(220);
    painter.text(bar.right_top() + Vec2::new(4.0, 0.0), egui::Align2::LEFT_TOP, format!("{:.3}", range.1), font.clone(), text);
    painter.text(bar.right_bottom() + Vec2::new(4.0, 0.0), egui::Align2::LEFT_BOTTOM, format!("{:.3}", range.0), font.clone(), text);
    if diverging_map {
        painter.text(Pos2::new(bar.max.x + 4.0, bar.center().y), egui::Align2::LEFT_CENTER, "0", font.clone(), text);
    }
    painter.text(bar.center_top() - Vec2::new(0.0, 6.0), egui::Align2::CENTER_BOTTOM, label, font, text);
}

/// The colour of bin `k` of `bins` (viridis at the bin's centre), as the viewer draws it.
pub fn bin_color(k: usize, bins: usize) -> [f32; 4] {
    let c = viridis((k as f32 + 0.5) / bins as f32);
    [c[0], c[1], c[2], 1.0]
}

/// A legend of `bins` colour bins over `range` (lowest at the bottom), in the viewport's
/// top-right corner.
pub fn binned_legend(painter: &Painter, viewport: Rect, label: &str, range: (f32, f32), bins: usize) {
    let size = Vec2::new(18.0, 160.0);
    let min = Pos2::new(viewport.max.x - 90.0, viewport.min.y + 36.0);
    let bar = Rect::from_min_size(min, size);
    let font = egui::FontId::proportional(12.0);
    let text = Color32::from_gray(220);
    let h = size.y / bins as f32;
    for k in 0..bins {
        let top = bar.max.y - (k + 1) as f32 * h;
        let c = bin_color(k, bins);
        painter.rect_filled(Rect::from_min_size(Pos2::new(bar.min.x, top), Vec2::new(size.x, h - 1.0)), 0.0, to_color([c[0], c[1], c[2]]));
        let value = range.0 + (range.1 - range.0) * k as f32 / bins as f32;
        painter.text(Pos2::new(bar.max.x + 4.0, top + h), egui::Align2::LEFT_BOTTOM, format!("{value:.1}"), font.clone(), text);
    }
    painter.text(bar.right_top() + Vec2::new(4.0, 0.0), egui::Align2::LEFT_TOP, format!("{:.1}", range.1), font.clone(), text);
    painter.text(bar.center_top() - Vec2::new(0.0, 6.0), egui::Align2::CENTER_BOTTOM, label, font, text);
}
