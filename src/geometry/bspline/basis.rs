//! A univariate B-spline basis: degree p, the textbook knot vector t_0 ≤ … ≤ t_{n+p} (n + p + 1
//! knots for n basis functions), the domain [t_p, t_n], and the p + 1 basis functions that do not
//! vanish on a knot span with their derivatives (Piegl & Tiller, *The NURBS Book*, A2.1, A2.3).

// Negated float comparisons are deliberate: they also reject NaN.
// The loops index as Piegl & Tiller's algorithms do.

use std::fmt;

/// The largest degree accepted (p + 1 ≤ 16 functions per span).
pub const MAX_DEGREE: usize = 15;
/// Derivatives computed by [`BSplineBasis::evaluate`]: values, first and second.
pub(crate) const DERIVATIVES: usize = 2;

/// Why a knot vector cannot define a basis.
#[derive(Clone, Debug, PartialEq)]
pub enum BasisError {
    /// Degree 0 or above [`MAX_DEGREE`].
    Degree(usize),
    /// Fewer basis functions than degree + 1.
    TooFewFunctions { functions: usize, degree: usize },
    /// The knot vector has the wrong length for the number of functions.
    KnotCount { knots: usize, expected: usize },
    /// A knot is NaN or infinite.
    NonFiniteKnot { index: usize },
    /// t_{index} < t_{index − 1}.
    Decreasing { index: usize },
    /// An interior knot repeated more than `degree` times (the basis would be discontinuous).
    Multiplicity { index: usize, multiplicity: usize },
    /// t_p = t_n: the domain is a point.
    EmptyDomain,
}

impl fmt::Display for BasisError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BasisError::Degree(p) => write!(f, "degree {p} is outside 1..={MAX_DEGREE}"),
            BasisError::TooFewFunctions { functions, degree } => {
                write!(f, "{functions} control points are too few for degree {degree} (at least {})", degree + 1)
            }
            BasisError::KnotCount { knots, expected } => write!(f, "{knots} knots, expected {expected}"),
            BasisError::NonFiniteKnot { index } => write!(f, "knot {index} is not a finite number"),
            BasisError::Decreasing { index } => write!(f, "knot {index} is smaller than knot {}", index - 1),
            BasisError::Multiplicity { index, multiplicity } => {
                write!(f, "interior knot {index} is repeated {multiplicity} times, more than the degree")
            }
            BasisError::EmptyDomain => f.write_str("the knot vector's domain is empty"),
        }
    }
}

impl std::error::Error for BasisError {}

/// The non-vanishing basis functions at a parameter: N_{first + j} for j = 0..=p, and their
/// first and second derivatives (`values[k][j]` = k-th derivative of N_{first + j}).
#[derive(Clone, Copy, Debug)]
pub struct BasisValues {
    pub first: usize,
    pub count: usize,
    pub values: [[f64; MAX_DEGREE + 1]; DERIVATIVES + 1],
}

/// A B-spline basis.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineBasis {
    degree: usize,
    knots: Vec<f64>,
}

impl BSplineBasis {
    /// A basis of degree `degree` on the textbook knot vector (n + p + 1 knots for n functions).
    pub fn new(degree: usize, knots: Vec<f64>) -> Result<Self, BasisError> {
        if degree == 0 || degree > MAX_DEGREE {
            return Err(BasisError::Degree(degree));
        }
        let functions = knots.len().saturating_sub(degree + 1);
        if functions < degree + 1 {
            return Err(BasisError::TooFewFunctions { functions, degree });
        }
        if let Some(index) = knots.iter().position(|t| !t.is_finite()) {
            return Err(BasisError::NonFiniteKnot { index });
        }
        if let Some(index) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
            return Err(BasisError::Decreasing { index });
        }
        // Interior knots (strictly inside the domain) of multiplicity > p.
        let (lo, hi) = (knots[degree], knots[functions]);
        if !(lo < hi) {
            return Err(BasisError::EmptyDomain);
        }
        let mut i = 0;
        while i < knots.len() {
            let j = (i..knots.len()).take_while(|&j| knots[j] == knots[i]).last().unwrap_or(i);
            let multiplicity = j - i + 1;
            if knots[i] > lo && knots[i] < hi && multiplicity > degree {
                return Err(BasisError::Multiplicity { index: i, multiplicity });
            }
            i = j + 1;
        }
        Ok(Self { degree, knots })
    }

    /// A clamped basis with `functions` functions of degree `degree` and uniform interior knots
    /// on `[lo, hi]`.
    pub fn clamped_uniform(degree: usize, functions: usize, (lo, hi): (f64, f64)) -> Result<Self, BasisError> {
        let interior = functions.saturating_sub(degree + 1);
        let mut knots = vec![lo; degree + 1];
        knots.extend((1..=interior).map(|k| lo + (hi - lo) * k as f64 / (interior + 1) as f64));
        knots.extend(std::iter::repeat_n(hi, degree + 1));
        Self::new(degree, knots)
    }

    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The textbook knot vector.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// Number of basis functions n.
    pub fn count(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    /// The domain [t_p, t_n].
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.count()])
    }

    /// The knot span k (t_k ≤ t < t_{k+1}, p ≤ k < n) holding `t`, clamped to the domain; at its
    /// right end, the last non-empty span (A2.1).
    pub fn span(&self, t: f64) -> usize {
        let (p, n) = (self.degree, self.count());
        let (lo, hi) = self.domain();
        let t = if t.is_nan() { lo } else { t.clamp(lo, hi) };
        if t >= hi {
            return (p..n).rev().find(|&k| self.knots[k] < self.knots[k + 1]).unwrap_or(n - 1);
        }
        // The largest k in p..n with t_k ≤ t (then t < t_{k+1}).
        let (mut a, mut b) = (p, n);
        while b - a > 1 {
            let m = (a + b) / 2;
            if self.knots[m] <= t {
                a = m;
            } else {
                b = m;
            }
        }
        a
    }

    /// The non-vanishing basis functions at `t` (clamped to the domain) with their first and
    /// second derivatives (A2.3).
    pub fn evaluate(&self, t: f64) -> BasisValues {
        // Tables sized p + 1 at compile time: nothing larger to clear, loops of known length.
        macro_rules! sized {
            ($($n:literal)*) => {
                match self.degree + 1 {
                    $($n => self.evaluate_sized::<$n>(t),)*
                    _ => unreachable!("degree checked in BSplineBasis::new"),
                }
            };
        }
        sized!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
    }

    /// [`Self::evaluate`] with N = p + 1. The table holds A2.3's `ndu`, with the knot differences
    /// below its diagonal stored as their reciprocals (each one divides several times).
    fn evaluate_sized<const N: usize>(&self, t: f64) -> BasisValues {
        let p = N - 1;
        let (lo, hi) = self.domain();
        let t = if t.is_nan() { lo } else { t.clamp(lo, hi) };
        let span = self.span(t);
        let u = &self.knots;
        let mut ndu = [[0.0; N]; N];
        let (mut left, mut right) = ([0.0; N], [0.0; N]);
        ndu[0][0] = 1.0;
        for j in 1..=p {
            left[j] = t - u[span + 1 - j];
            right[j] = u[span + j] - t;
            let mut saved = 0.0;
            for r in 0..j {
                let inverse = 1.0 / (right[r + 1] + left[j - r]);
                ndu[j][r] = inverse;
                let temp = ndu[r][j - 1] * inverse;
                ndu[r][j] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            ndu[j][j] = saved;
        }
        const M: usize = MAX_DEGREE + 1;
        let mut out = BasisValues { first: span - p, count: N, values: [[0.0; M]; DERIVATIVES + 1] };
        for j in 0..=p {
            out.values[0][j] = ndu[j][p];
        }
        let n = DERIVATIVES.min(p);
        let mut a = [[0.0; N]; 2];
        for r in 0..=p {
            let (mut s1, mut s2) = (0, 1);
            a[0][0] = 1.0;
            for k in 1..=n {
                let mut d = 0.0;
                let rk = r as isize - k as isize;
                let pk = p - k;
                if rk >= 0 {
                    a[s2][0] = a[s1][0] * ndu[pk + 1][rk as usize];
                    d = a[s2][0] * ndu[rk as usize][pk];
                }
                let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
                let j2 = if r as isize - 1 <= pk as isize { k - 1 } else { p - r };
                for j in j1..=j2 {
                    let idx = (rk + j as isize) as usize;
                    a[s2][j] = (a[s1][j] - a[s1][j - 1]) * ndu[pk + 1][idx];
                    d += a[s2][j] * ndu[idx][pk];
                }
                if r <= pk {
                    a[s2][k] = -a[s1][k - 1] * ndu[pk + 1][r];
                    d += a[s2][k] * ndu[r][pk];
                }
                out.values[k][r] = d;
                std::mem::swap(&mut s1, &mut s2);
            }
        }
        let mut factor = p as f64;
        for k in 1..=n {
            for j in 0..=p {
                out.values[k][j] *= factor;
            }
            factor *= (p - k) as f64;
        }
        out
    }

    /// The Greville abscissae (t_{i+1} + … + t_{i+p})/p: where each function peaks, roughly.
    pub fn greville(&self) -> Vec<f64> {
        let p = self.degree;
        (0..self.count()).map(|i| self.knots[i + 1..=i + p].iter().sum::<f64>() / p as f64).collect()
    }
}
