//! Small painted plots: overlaid histograms (Fig. 14), the energy per iteration, key–value tables.

use egui::{Color32, Pos2, Rect, RichText, Sense, Vec2};

use crate::pipeline::fields::Energy;
use crate::stats::Histogram;

/// Overlaid bar histograms (Fig. 14) over their common range.
pub fn histogram(ui: &mut egui::Ui, series: &[(&Histogram, Color32)], unit: &str) {
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(260.0), 70.0), Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, Color32::from_gray(30));
    let lo = series.iter().map(|(h, _)| h.lo).fold(f64::INFINITY, f64::min);
    let hi = series.iter().map(|(h, _)| h.hi).fold(f64::NEG_INFINITY, f64::max);
    if !(hi > lo) {
        return;
    }
    let peak = series.iter().flat_map(|(h, _)| h.counts.iter().copied()).max().unwrap_or(1).max(1) as f32;
    for (h, color) in series {
        let n = h.counts.len().max(1) as f64;
        let w = (h.hi - h.lo) / n;
        for (i, &c) in h.counts.iter().enumerate() {
            let x0 = (h.lo + w * i as f64 - lo) / (hi - lo);
            let x1 = (h.lo + w * (i + 1) as f64 - lo) / (hi - lo);
            let top = rect.bottom() - (c as f32 / peak) * (rect.height() - 14.0);
            let bar = Rect::from_min_max(
                Pos2::new(rect.left() + x0 as f32 * rect.width(), top),
                Pos2::new(rect.left() + (x1 as f32 * rect.width()).max(x0 as f32 * rect.width() + 1.0), rect.bottom()),
            );
            p.rect_filled(bar, 0.0, color.gamma_multiply(0.75));
        }
    }
    let font = egui::FontId::proportional(10.0);
    p.text(rect.left_top() + Vec2::new(2.0, 1.0), egui::Align2::LEFT_TOP, format!("{lo:.3}{unit}"), font.clone(), Color32::LIGHT_GRAY);
    p.text(rect.right_top() + Vec2::new(-2.0, 1.0), egui::Align2::RIGHT_TOP, format!("{hi:.3}{unit}"), font, Color32::LIGHT_GRAY);
}

/// Total energy against iteration on a log scale, one colour per optimizer stage.
pub fn energy_plot(ui: &mut egui::Ui, series: &[(u32, String, f64)]) {
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(260.0), 110.0), Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, Color32::from_gray(30));
    let logs: Vec<f64> = series.iter().map(|(_, _, e)| e.max(1e-300).log10()).collect();
    let (lo, hi) = logs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    let (lo, hi) = if hi - lo < 1e-9 { (lo - 0.5, hi + 0.5) } else { (lo, hi) };
    let last = series.last().map_or(1, |s| s.0).max(1) as f32;
    let inner = rect.shrink2(Vec2::new(4.0, 14.0));
    let at =
        |it: u32, y: f64| Pos2::new(inner.left() + inner.width() * it as f32 / last, inner.bottom() - inner.height() * ((y - lo) / (hi - lo)) as f32);
    let palette = [Color32::from_rgb(110, 150, 230), Color32::from_rgb(90, 190, 90), Color32::from_rgb(230, 170, 60), Color32::from_rgb(220, 80, 70)];
    let mut stage_index = 0;
    for k in 1..series.len() {
        if series[k].1 != series[k - 1].1 {
            stage_index += 1;
            let x = at(series[k].0, lo).x;
            p.line_segment([Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())], egui::Stroke::new(1.0, Color32::from_gray(60)));
            continue;
        }
        let color = palette[stage_index % palette.len()];
        p.line_segment([at(series[k - 1].0, logs[k - 1]), at(series[k].0, logs[k])], egui::Stroke::new(1.5, color));
    }
    let font = egui::FontId::proportional(10.0);
    let (it, stage, e) = series.last().map(|(i, s, e)| (*i, s.as_str(), *e)).unwrap_or((0, "", 0.0));
    p.text(rect.left_top() + Vec2::new(2.0, 1.0), egui::Align2::LEFT_TOP, format!("1e{hi:.1}"), font.clone(), Color32::LIGHT_GRAY);
    p.text(rect.left_bottom() + Vec2::new(2.0, -1.0), egui::Align2::LEFT_BOTTOM, format!("1e{lo:.1}"), font.clone(), Color32::LIGHT_GRAY);
    p.text(rect.right_top() + Vec2::new(-2.0, 1.0), egui::Align2::RIGHT_TOP, format!("{stage} · it {it} · E {e:.3e}"), font, Color32::LIGHT_GRAY);
}

/// The energy of every term against iteration on a log scale, one colour per term, with a key;
/// a vertical rule where the step changes.
pub fn term_plot(ui: &mut egui::Ui, series: &[(u32, String, Vec<Energy>)]) {
    let names: Vec<&str> = series.last().map(|(_, _, e)| e.iter().map(|e| e.name.as_str()).collect()).unwrap_or_default();
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(260.0), 120.0), Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, Color32::from_gray(30));
    let log = |e: f64| e.max(1e-30).log10();
    let (lo, hi) = series
        .iter()
        .flat_map(|(_, _, e)| e.iter().map(|e| log(e.value)))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
    if !(hi >= lo) {
        return;
    }
    let (lo, hi) = if hi - lo < 1e-9 { (lo - 0.5, hi + 0.5) } else { (lo, hi) };
    let last = series.iter().map(|s| s.0).max().unwrap_or(1).max(1) as f32;
    let inner = rect.shrink2(Vec2::new(4.0, 14.0));
    let at =
        |it: u32, y: f64| Pos2::new(inner.left() + inner.width() * it as f32 / last, inner.bottom() - inner.height() * ((y - lo) / (hi - lo)) as f32);
    let palette = [
        Color32::WHITE,
        Color32::from_rgb(110, 150, 230),
        Color32::from_rgb(90, 190, 90),
        Color32::from_rgb(230, 170, 60),
        Color32::from_rgb(220, 80, 70),
        Color32::from_rgb(180, 110, 220),
        Color32::from_rgb(80, 200, 200),
        Color32::from_rgb(200, 200, 90),
        Color32::from_rgb(160, 160, 160),
    ];
    let color = |name: &str| {
        let k = names.iter().position(|n| *n == name).unwrap_or(names.len());
        palette[k % palette.len()]
    };
    for k in 1..series.len() {
        let (a, b) = (&series[k - 1], &series[k]);
        if a.1 != b.1 {
            let x = at(b.0, lo).x;
            p.line_segment([Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())], egui::Stroke::new(1.0, Color32::from_gray(70)));
            continue;
        }
        for e in &b.2 {
            if let Some(prev) = a.2.iter().find(|x| x.name == e.name) {
                p.line_segment([at(a.0, log(prev.value)), at(b.0, log(e.value))], egui::Stroke::new(1.2, color(&e.name)));
            }
        }
    }
    let font = egui::FontId::proportional(10.0);
    p.text(rect.left_top() + Vec2::new(2.0, 1.0), egui::Align2::LEFT_TOP, format!("1e{hi:.1}"), font.clone(), Color32::LIGHT_GRAY);
    p.text(rect.left_bottom() + Vec2::new(2.0, -1.0), egui::Align2::LEFT_BOTTOM, format!("1e{lo:.1}"), font.clone(), Color32::LIGHT_GRAY);
    ui.horizontal_wrapped(|ui| {
        for n in &names {
            ui.label(RichText::new(format!("■ {n}")).small().color(color(n)));
        }
    });
}

/// A two-column table of labels and values.
pub fn key_values(ui: &mut egui::Ui, id: &str, rows: &[(&str, String)]) {
    egui::Grid::new(id).num_columns(2).show(ui, |ui| {
        for (k, v) in rows {
            ui.label(*k);
            ui.label(no_nan(v));
            ui.end_row();
        }
    });
}

/// A figure as shown: a number that could not be measured reads so, never "NaN" or "inf".
pub fn no_nan(text: &str) -> std::borrow::Cow<'_, str> {
    let unbounded = |w: &str| w.parse::<f64>().is_ok_and(f64::is_infinite);
    if !text.contains("NaN") && !text.split_whitespace().any(unbounded) {
        return text.into();
    }
    let words: Vec<String> = text.split(' ').map(|w| if unbounded(w) { "unbounded".into() } else { w.replace("NaN", "not measured") }).collect();
    words.join(" ").into()
}
