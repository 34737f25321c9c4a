//! Forward-mode differentiation: a number carried with its derivatives by N variables, for the
//! Jacobians of closed-form geometry (the pencil through three points, the edge circles of two
//! spheres) that terms hand to the solver. Checked against finite differences where it is used.

// The product and quotient rules use the other operators on purpose.

use std::ops::{Add, Div, Mul, Neg, Sub};

use glam::DVec3;

/// A value and its N partial derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Dual<const N: usize> {
    pub v: f64,
    pub d: [f64; N],
}

impl<const N: usize> Dual<N> {
    pub fn constant(v: f64) -> Self {
        Self { v, d: [0.0; N] }
    }

    /// The variable k.
    pub fn variable(v: f64, k: usize) -> Self {
        let mut d = [0.0; N];
        d[k] = 1.0;
        Self { v, d }
    }

    /// f(self) with f(v) = `v` and f′(v) = `slope`.
    fn chain(self, v: f64, slope: f64) -> Self {
        Self { v, d: self.d.map(|x| x * slope) }
    }

    pub fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        self.chain(r, 0.5 / r)
    }

    /// The angle of the point (x, y) = (`x`, self), as f64::atan2.
    pub fn atan2(self, x: Self) -> Self {
        let (y, r2) = (self, x.v * x.v + self.v * self.v);
        Self { v: y.v.atan2(x.v), d: std::array::from_fn(|k| (x.v * y.d[k] - y.v * x.d[k]) / r2) }
    }

    pub(crate) fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r)
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self { v: self.v + o.v, d: std::array::from_fn(|k| self.d[k] + o.d[k]) }
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self { v: self.v - o.v, d: std::array::from_fn(|k| self.d[k] - o.d[k]) }
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    fn neg(self) -> Self {
        self.chain(-self.v, -1.0)
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self { v: self.v * o.v, d: std::array::from_fn(|k| self.d[k] * o.v + self.v * o.d[k]) }
    }
}

impl<const N: usize> Mul<f64> for Dual<N> {
    type Output = Self;
    fn mul(self, s: f64) -> Self {
        self.chain(self.v * s, s)
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        self * o.recip()
    }
}

/// A point (or vector) of [`Dual`] coordinates.
#[derive(Clone, Copy, Debug)]
pub struct D3<const N: usize> {
    pub x: Dual<N>,
    pub y: Dual<N>,
    pub z: Dual<N>,
}

impl<const N: usize> D3<N> {
    /// `p` whose coordinates are the variables k, k + 1, k + 2.
    pub fn variable(p: DVec3, k: usize) -> Self {
        Self { x: Dual::variable(p.x, k), y: Dual::variable(p.y, k + 1), z: Dual::variable(p.z, k + 2) }
    }

    /// `p` with zero derivatives.
    pub fn constant(p: DVec3) -> Self {
        Self { x: Dual::constant(p.x), y: Dual::constant(p.y), z: Dual::constant(p.z) }
    }

    pub fn dot(self, o: Self) -> Dual<N> {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    pub fn cross(self, o: Self) -> Self {
        Self { x: self.y * o.z - self.z * o.y, y: self.z * o.x - self.x * o.z, z: self.x * o.y - self.y * o.x }
    }
}

impl<const N: usize> Add for D3<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
}

impl<const N: usize> Sub for D3<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
}

impl<const N: usize> Mul<Dual<N>> for D3<N> {
    type Output = Self;
    fn mul(self, s: Dual<N>) -> Self {
        Self { x: self.x * s, y: self.y * s, z: self.z * s }
    }
}
