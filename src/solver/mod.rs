//! Sparse nonlinear least squares: Levenberg–Marquardt in the regularized guided-projection form
//! of Tang et al. 2014, with a sparse Cholesky factorization from faer.
//!
//! A [`Problem`] is a set of weighted [`Term`]s over one flat vector of variables `x: Vec<f64>`.
//! The caller lays out the blocks (vertices, generalized spheres (a, b₁, b₂, b₃, c), plane normals,
//! auxiliary variables, …): a term only knows the offsets of the blocks it reads. The solver
//! minimizes
//!
//! ```text
//! E(x) = Σ_t w_t Σ_{i active in t} r_{t,i}(x)²
//! ```
//!
//! over the free variables; hard-fixed variables ([`Problem::fix`]) keep their values bit for bit
//! (their Jacobian columns are dropped from the normal equations).
//!
//! Each iteration solves `(JᵀWJ + ε²I) Δ = −JᵀW r` (see [`Solver`] for the damping control).
//!
//! - **Auxiliary variables**: just more variables ([`Problem::add_variables`]).
//! - **Unit length**: [`UnitLength`] (|v|² − 1 for 3-blocks, bᵀb − 4ac − 1 for 5-blocks).
//! - **One-sided terms**: any residual can be switched off for the current point with
//!   [`JacobianSink::deactivate`]; [`Hinge`] wraps any term into `max(0, g)`, [`Band`] into the dead zone |g| ≤ τ.
//! - **Fixed variables**: soft with [`Anchor`], hard with [`Problem::fix`].
//! - **Stages**: [`Problem::set_weight`] between calls to [`Solver::solve`]; the solver keeps its
//!   symbolic factorization across calls as long as the sparsity pattern is the same.
//!
//! Terms must emit the same Jacobian *structure* (sequence of `(row, col)` pairs) at every point;
//! only values change. A changed structure is detected and triggers a new symbolic analysis.
//!
//! This module tree depends only on `faer`, `glam` and `serde` (no other crate modules).

mod assembly;
mod check;
mod lm;
pub mod ordering;
pub mod problem;
pub mod terms;

pub use check::{check_jacobian, check_jacobian_report, jacobians, residuals, JacobianCheck};
pub use lm::{IterationReport, PhaseTimes, SolveReport, Solver, SolverOptions, TermStats, Termination};
pub use ordering::Ordering;
pub use problem::{JacobianSink, Problem, Term, TermId};
pub use terms::{
    Anchor, Band, FnTerm, Hinge, InversiveProduct, InversiveProductFixed, Linear, PointOnPlane, PointOnSphere, Proximal, SphereFit, UnitLength,
};
