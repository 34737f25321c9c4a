//! B-spline surfaces in the JSON format of the paper's authors (exported from Rhino):
//! `{"degreeU", "degreeV", "knotsU", "knotsV", "controlPoints"}`.
//!
//! - `controlPoints` is a flat list x, y, z, w, …; control point (i, j), i along U, starts at
//!   float 4·(j·n_U + i) (U runs fastest, as the authors' reader, splipy, reads it).
//! - Knots follow openNURBS: len = n + degree − 1, the end knots repeated `degree` times; one copy
//!   of the first and last knot is added to get the textbook vector (exact also for unclamped and
//!   periodic vectors). The textbook form, len = n + degree + 1, is accepted too; the two are told
//!   apart by which makes n_U · n_V equal the number of control points.
//! - (x, y, z) is the Euclidean point and w its weight: S = Σ N_i M_j w P / Σ N_i M_j w.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;
use serde_json::Value;

use super::raw::{check_scale, Ctx, ImportError, MAX_COORDINATE};
use crate::geometry::bspline::{BSplineBasis, BSplineSurface, MAX_DEGREE};

/// Most control points accepted.
pub(crate) const MAX_CONTROL_POINTS: usize = 1_000_000;

/// The five keys of the format.
pub(crate) const KEYS: [&str; 5] = ["degreeU", "degreeV", "knotsU", "knotsV", "controlPoints"];

/// Whether JSON text looks like this format: it names one of its keys (no glTF key is one).
pub(crate) fn looks_like_bspline(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(1 << 20)];
    let has = |key: &str| head.windows(key.len() + 2).any(|w| w[0] == b'"' && &w[1..=key.len()] == key.as_bytes() && w[key.len() + 1] == b'"');
    KEYS.iter().any(|k| has(k))
}

/// Parses a B-spline surface file.
pub(crate) fn parse(bytes: &[u8], ctx: &Ctx) -> Result<(BSplineSurface, Vec<String>), ImportError> {
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let json: Value = serde_json::from_slice(text).map_err(|e| ctx.malformed(Some(e.line()), format!("invalid JSON: {e}")))?;
    let obj = json
        .as_object()
        .ok_or_else(|| ctx.malformed(None, "expected a JSON object with the keys degreeU, degreeV, knotsU, knotsV, controlPoints"))?;
    let mut notes = Vec::new();
    let unknown: Vec<&str> = obj.keys().map(String::as_str).filter(|k| !KEYS.contains(k)).collect();
    if !unknown.is_empty() {
        notes.push(format!("ignored unknown keys: {}", unknown.join(", ")));
    }
    let degree = |key: &str| -> Result<usize, ImportError> {
        let v = obj.get(key).ok_or_else(|| ctx.malformed(None, format!("missing key '{key}'")))?;
        match v.as_u64() {
            Some(p) if (1..=MAX_DEGREE as u64).contains(&p) => Ok(p as usize),
            _ => Err(ctx.malformed(None, format!("'{key}' must be an integer from 1 to {MAX_DEGREE}, found {v}"))),
        }
    };
    let numbers = |key: &str| -> Result<Vec<f64>, ImportError> {
        let v = obj.get(key).ok_or_else(|| ctx.malformed(None, format!("missing key '{key}'")))?;
        let list = v.as_array().ok_or_else(|| ctx.malformed(None, format!("'{key}' must be a list of numbers")))?;
        list.iter()
            .enumerate()
            .map(|(i, x)| match x.as_f64() {
                Some(f) if f.is_finite() => Ok(f),
                _ => Err(ctx.malformed(None, format!("'{key}'[{i}] is not a finite number: {x}"))),
            })
            .collect()
    };
    let (pu, pv) = (degree("degreeU")?, degree("degreeV")?);
    let (ku, kv) = (numbers("knotsU")?, numbers("knotsV")?);
    for (key, knots) in [("knotsU", &ku), ("knotsV", &kv)] {
        if let Some(k) = knots.iter().find(|k| k.abs() > MAX_COORDINATE) {
            return Err(ctx.unsupported(format!("'{key}': the knot {k:e} is beyond ±{:e}: rescale the parameter domain", MAX_COORDINATE)));
        }
    }
    let cp = numbers("controlPoints")?;
    if cp.len() % 4 != 0 {
        return Err(ctx.malformed(None, format!("'controlPoints' has {} numbers, not a multiple of 4 (x, y, z, w per point)", cp.len())));
    }
    let points = cp.len() / 4;
    if points > MAX_CONTROL_POINTS {
        return Err(ctx.too_large("control points", points as u64, MAX_CONTROL_POINTS));
    }
    let (form_u, form_v) = knot_forms(ku.len(), pu, kv.len(), pv, points).ok_or_else(|| {
        let count = |len: usize, p: usize, d: isize| (len as isize - p as isize + d).max(0);
        ctx.malformed(
            None,
            format!(
                "'controlPoints' holds {points} points, but the knot vectors give n_U × n_V = {} × {} (openNURBS form: \
                 len(knots) = n + degree − 1) or {} × {} (textbook form: n + degree + 1); \
                 knotsU has {} knots for degreeU {pu}, knotsV {} for degreeV {pv}",
                count(ku.len(), pu, 1),
                count(kv.len(), pv, 1),
                count(ku.len(), pu, -1),
                count(kv.len(), pv, -1),
                ku.len(),
                kv.len()
            ),
        )
    })?;
    let basis = |key: &str, p: usize, knots: Vec<f64>, form: KnotForm| -> Result<BSplineBasis, ImportError> {
        let knots = match form {
            KnotForm::OpenNurbs => {
                let (first, last) = (knots[0], knots[knots.len() - 1]);
                std::iter::once(first).chain(knots).chain(std::iter::once(last)).collect()
            }
            KnotForm::Textbook => knots,
        };
        BSplineBasis::new(p, knots).map_err(|e| ctx.malformed(None, format!("'{key}': {e}")))
    };
    let bu = basis("knotsU", pu, ku, form_u)?;
    let bv = basis("knotsV", pv, kv, form_v)?;
    let control: Vec<DVec3> = cp.chunks_exact(4).map(|c| DVec3::new(c[0], c[1], c[2])).collect();
    let weights: Vec<f64> = cp.chunks_exact(4).map(|c| c[3]).collect();
    check_scale(&control, ctx)?;
    if let Some(i) = weights.iter().position(|&w| !(w > 0.0)) {
        return Err(ctx.malformed(None, format!("'controlPoints': the weight of point {i} is {} (weights must be positive)", weights[i])));
    }
    // Products of basis functions and weights must stay normal numbers (a subnormal weight, or
    // knots spanning 1e308, give NaN points).
    let range = 1.0 / MAX_COORDINATE..=MAX_COORDINATE;
    if let Some(i) = weights.iter().position(|w| !range.contains(w)) {
        return Err(ctx.unsupported(format!(
            "'controlPoints': the weight of point {i} is {:e}, outside [{:e}, {:e}]: rescale the weights",
            weights[i],
            range.start(),
            range.end()
        )));
    }
    let surface = BSplineSurface::new(bu, bv, control, weights).map_err(|e| ctx.malformed(None, format!("'controlPoints': {e}")))?;
    if matches!((form_u, form_v), (KnotForm::Textbook, _) | (_, KnotForm::Textbook)) {
        notes.push("knot vectors in the textbook form (n + degree + 1 knots)".into());
    }
    Ok((surface, notes))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum KnotForm {
    /// len = n + p − 1.
    OpenNurbs,
    /// len = n + p + 1.
    Textbook,
}

/// The knot forms that make n_U · n_V = `points`: both openNURBS first, then both textbook,
/// then mixed.
fn knot_forms(lu: usize, pu: usize, lv: usize, pv: usize, points: usize) -> Option<(KnotForm, KnotForm)> {
    let count = |len: usize, p: usize, form: KnotForm| match form {
        KnotForm::OpenNurbs => (len + 1).checked_sub(p),
        KnotForm::Textbook => len.checked_sub(p + 1),
    };
    use KnotForm::*;
    [(OpenNurbs, OpenNurbs), (Textbook, Textbook), (OpenNurbs, Textbook), (Textbook, OpenNurbs)].into_iter().find(|&(fu, fv)| {
        match (count(lu, pu, fu), count(lv, pv, fv)) {
            (Some(nu), Some(nv)) => nu > 0 && nv > 0 && nu.checked_mul(nv) == Some(points),
            _ => false,
        }
    })
}
