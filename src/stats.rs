//! Small statistics of samples: mean, median, percentiles and histograms (Fig. 14).

use serde::{Deserialize, Serialize};

/// Arithmetic mean; 0 for no values.
pub fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        0.0
    } else {
        values.iter().sum::<f64>() / values.len() as f64
    }
}

/// Median (mean of the middle two for an even count); None for no values.
pub fn median(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut s = values.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    Some(if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) })
}

/// The q-quantile by nearest rank (q in [0, 1]); 0 for no values.
pub fn percentile(values: impl IntoIterator<Item = f64>, q: f64) -> f64 {
    let mut v: Vec<f64> = values.into_iter().collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
}

/// Mean, median and max of the finite values (0s when there are none).
pub fn summary_stats(values: &[f64]) -> (f64, f64, f64) {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    match median(&v) {
        None => (0.0, 0.0, 0.0),
        Some(m) => (mean(&v), m, v.iter().copied().fold(f64::NEG_INFINITY, f64::max)),
    }
}

/// A histogram of values with `bins` equal bins over [lo, hi] (min and max of the finite
/// values).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    pub lo: f64,
    pub hi: f64,
    pub counts: Vec<u32>,
}

impl Histogram {
    pub fn new(values: &[f64], bins: usize) -> Self {
        let bins = bins.max(1);
        let finite = values.iter().copied().filter(|v| v.is_finite());
        let (lo, hi) = finite.clone().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
        let mut counts = vec![0u32; bins];
        if lo > hi {
            return Self { lo: 0.0, hi: 0.0, counts };
        }
        let w = (hi - lo).max(f64::MIN_POSITIVE);
        for v in finite {
            let k = (((v - lo) / w) * bins as f64) as usize;
            counts[k.min(bins - 1)] += 1;
        }
        Self { lo, hi, counts }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_and_percentiles() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(percentile([5.0, 1.0, 3.0, 2.0, 4.0], 0.5), 3.0);
        assert_eq!(percentile([5.0, 1.0, 3.0, 2.0, 4.0], 0.95), 5.0);
        assert_eq!(summary_stats(&[1.0, f64::NAN, 3.0]), (2.0, 2.0, 3.0));
        let h = Histogram::new(&[0.0, 0.5, 1.0, f64::INFINITY], 2);
        assert_eq!((h.lo, h.hi, h.counts), (0.0, 1.0, vec![1, 2]));
    }
}
