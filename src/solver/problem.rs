//! The problem: variables, their hard-fixed mask and ordering groups, and weighted residual
//! [`Term`]s with their Jacobians.

use std::ops::Range;

/// One group of residuals with their Jacobian.
///
/// `eval` writes `residual_count()` residuals into `r` (already zeroed) and the Jacobian entries
/// `∂r_row/∂x_col` into `jac` as `(row, col, value)` triplets, `row` local to the term
/// (`0..residual_count()`), `col` global (index into `x`). Duplicated `(row, col)` pairs are
/// summed. The sequence of `(row, col)` pairs must not depend on `x` (emit zeros instead of
/// skipping entries); values may.
///
/// A residual can be switched off at the current point with [`JacobianSink::deactivate`]: it then
/// counts as 0 and its Jacobian row is ignored (one-sided terms).
pub trait Term {
    /// Name used in reports (several terms may share a name).
    fn name(&self) -> &str;
    /// Number of residuals; must be constant.
    fn residual_count(&self) -> usize;
    /// Residuals and Jacobian at `x`.
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink);
    /// Called by the solver with the point about to be evaluated, before `eval` (e.g. to update
    /// closest points on a reference surface). Default: nothing.
    fn prepare(&mut self, _x: &[f64]) {}
}

/// Receives the Jacobian triplets of one term (see [`Term::eval`]).
pub struct JacobianSink<'s> {
    rows: &'s mut Vec<u32>,
    cols: &'s mut Vec<u32>,
    vals: &'s mut Vec<f64>,
    active: &'s mut [bool],
    row_offset: u32,
}

impl<'s> JacobianSink<'s> {
    pub(crate) fn new(rows: &'s mut Vec<u32>, cols: &'s mut Vec<u32>, vals: &'s mut Vec<f64>, active: &'s mut [bool], row_offset: usize) -> Self {
        Self { rows, cols, vals, active, row_offset: row_offset as u32 }
    }

    /// Adds `∂r_row/∂x_col = value` (summed with earlier entries at the same position).
    #[inline]
    pub fn add(&mut self, row: usize, col: usize, value: f64) {
        debug_assert!(row < self.active.len(), "Jacobian row {row} out of range");
        self.rows.push(self.row_offset + row as u32);
        self.cols.push(col as u32);
        self.vals.push(value);
    }

    /// Adds `values[k]` at `(row, col0 + k)`.
    #[inline]
    pub(crate) fn add_block(&mut self, row: usize, col0: usize, values: &[f64]) {
        for (k, &v) in values.iter().enumerate() {
            self.add(row, col0 + k, v);
        }
    }

    /// The number of entries added so far (for [`Self::scale_rows_since`]).
    #[inline]
    pub fn mark(&self) -> usize {
        self.vals.len()
    }

    /// Multiplies the entries added since `mark` by `scale(row)` (rows of the term).
    pub fn scale_rows_since(&mut self, mark: usize, scale: impl Fn(usize) -> f64) {
        for k in mark..self.vals.len() {
            self.vals[k] *= scale((self.rows[k] - self.row_offset) as usize);
        }
    }

    /// Switches residual `row` off at this point: it counts as 0 and its Jacobian row is ignored.
    #[inline]
    pub fn deactivate(&mut self, row: usize) {
        self.active[row] = false;
    }

    /// The term's residual count.
    #[inline]
    pub fn residual_count(&self) -> usize {
        self.active.len()
    }
}

/// Handle of a term in a [`Problem`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TermId(pub usize);

pub(crate) struct TermSlot<'a> {
    pub(crate) term: Box<dyn Term + 'a>,
    pub(crate) weight: f64,
}

/// Variables (count and hard-fixed mask) and weighted terms.
///
/// The lifetime lets terms borrow reference data (e.g. a BVH of the reference surface).
/// A hard constraint on the iterates: true where a point is admissible.
type Admissible<'a> = Box<dyn Fn(&[f64]) -> bool + 'a>;

pub struct Problem<'a> {
    n_vars: usize,
    fixed: Vec<bool>,
    /// Ordering group key per variable (see [`Problem::group_variables`]).
    groups: Vec<u32>,
    pub(crate) terms: Vec<TermSlot<'a>>,
    /// A hard constraint on the iterates: a step to a point it rejects is not taken.
    admissible: Option<Admissible<'a>>,
}

impl<'a> Problem<'a> {
    /// A problem over `n_vars` free variables and no terms.
    pub fn new(n_vars: usize) -> Self {
        Self { n_vars, fixed: vec![false; n_vars], groups: (0..n_vars as u32).collect(), terms: Vec::new(), admissible: None }
    }

    /// Only points that `admissible` accepts are taken as steps (the solver treats any other
    /// trial point as a failed step and raises the damping): a barrier that no weight can
    /// trade away, e.g. no folded face.
    pub(crate) fn set_admissible(&mut self, admissible: impl Fn(&[f64]) -> bool + 'a) {
        self.admissible = Some(Box::new(admissible));
    }

    /// Whether `x` is admissible (always, without a constraint).
    pub(crate) fn is_admissible(&self, x: &[f64]) -> bool {
        self.admissible.as_ref().is_none_or(|f| f(x))
    }

    /// Appends `count` (auxiliary) variables and returns their index range.
    pub fn add_variables(&mut self, count: usize) -> Range<usize> {
        let start = self.n_vars;
        self.n_vars += count;
        self.fixed.resize(self.n_vars, false);
        self.groups.extend(start as u32..self.n_vars as u32);
        start..self.n_vars
    }

    /// Declares the variables of `range` one block (e.g. the 5 coefficients of a sphere, the 3
    /// coordinates of a vertex): the fill-reducing ordering ([`Ordering`]) keeps them together
    /// and orders blocks instead of variables. Only a hint: it changes the ordering, hence the
    /// rounding, not the problem. Groups may not overlap (a later call wins).
    pub fn group_variables(&mut self, range: Range<usize>) {
        let key = range.start as u32;
        for g in &mut self.groups[range] {
            *g = key;
        }
    }

    /// The ordering group key of every variable (equal keys = one block).
    pub(crate) fn variable_groups(&self) -> &[u32] {
        &self.groups
    }

    pub fn num_variables(&self) -> usize {
        self.n_vars
    }

    /// Adds a term with weight `weight` (≥ 0).
    pub fn add_term(&mut self, term: impl Term + 'a, weight: f64) -> TermId {
        self.add_boxed(Box::new(term), weight)
    }

    pub(crate) fn add_boxed(&mut self, term: Box<dyn Term + 'a>, weight: f64) -> TermId {
        assert!(weight >= 0.0 && weight.is_finite(), "term weight must be finite and ≥ 0");
        self.terms.push(TermSlot { term, weight });
        TermId(self.terms.len() - 1)
    }

    /// Changes a term's weight (≥ 0; 0 switches the term off without changing the pattern).
    pub fn set_weight(&mut self, id: TermId, weight: f64) {
        assert!(weight >= 0.0 && weight.is_finite(), "term weight must be finite and ≥ 0");
        self.terms[id.0].weight = weight;
    }

    pub fn weight(&self, id: TermId) -> f64 {
        self.terms[id.0].weight
    }

    pub fn num_terms(&self) -> usize {
        self.terms.len()
    }

    pub fn term(&self, id: TermId) -> &(dyn Term + 'a) {
        &*self.terms[id.0].term
    }

    pub fn term_mut(&mut self, id: TermId) -> &mut (dyn Term + 'a) {
        &mut *self.terms[id.0].term
    }

    /// Hard-fixes variable `i`: excluded from the solve, its value never changes.
    pub fn fix(&mut self, i: usize) {
        self.fixed[i] = true;
    }

    /// Hard-fixes a range of variables.
    pub fn fix_range(&mut self, range: Range<usize>) {
        for f in &mut self.fixed[range] {
            *f = true;
        }
    }

    pub(crate) fn unfix(&mut self, i: usize) {
        self.fixed[i] = false;
    }

    pub(crate) fn fixed_mask(&self) -> &[bool] {
        &self.fixed
    }

    /// Calls [`Term::prepare`] on every term that is switched on (weight > 0): a term switched
    /// off adds nothing to the energy, and its preparation (a closest-point search per vertex
    /// for the proximity terms) would be wasted.
    pub fn prepare(&mut self, x: &[f64]) {
        for t in self.terms.iter_mut().filter(|t| t.weight > 0.0) {
            t.term.prepare(x);
        }
    }

    /// Calls [`Term::prepare`] on every term, switched off or not (before [`Self::term_stats`]
    /// reports every term's residuals).
    pub fn prepare_all(&mut self, x: &[f64]) {
        for t in &mut self.terms {
            t.term.prepare(x);
        }
    }
}
