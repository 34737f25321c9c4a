//! Evaluation buffers, the cached sparsity pattern of JᵀJ, allocation-free assembly and the
//! faer sparse Cholesky (symbolic once per pattern, numeric every iteration).
//!
//! Pattern (built when the triplet structure or the fixed mask changes):
//! - every Jacobian triplet `t` maps to an *entry* `trip_entry[t]`: a unique (row, free column)
//!   pair (duplicates are summed; triplets on hard-fixed columns map to `NONE`);
//! - entries are grouped by row, sorted by column: `entry_row_ptr`, `entry_col`;
//! - for every row with k entries, the k(k+1)/2 products `J_ra J_rb` (a ≤ b) are accumulated into
//!   the upper-triangular CSC value array of JᵀWJ at precomputed positions `pair_dest`.
//!
//! An iteration then costs: one scatter of triplet values into entries, one pass over the pairs,
//! a copy with ε² added on the diagonal, faer's numeric LLᵀ and a solve. No hashing, no
//! allocation.

use super::ordering::{BlockGraph, Ordering};
use super::problem::{JacobianSink, Problem};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

pub(crate) const NONE: u32 = u32::MAX;

/// Residuals, activity and Jacobian triplets of all terms at one point.
#[derive(Default)]
pub(crate) struct EvalBuffers {
    /// Unweighted residuals; 0 where inactive.
    pub r: Vec<f64>,
    pub active: Vec<bool>,
    /// Triplets, rows global.
    pub rows: Vec<u32>,
    pub cols: Vec<u32>,
    pub vals: Vec<f64>,
    /// Row range of term t: `term_rows[t]..term_rows[t + 1]`.
    pub term_rows: Vec<usize>,
    /// Triplet range of term t.
    pub term_trips: Vec<usize>,
}

/// Whether two index arrays are equal. Every accepted step compares the whole triplet structure;
/// `==` on integer slices becomes a memcmp, which wasm runs a byte at a time, while this OR of
/// XORs vectorizes.
fn same_indices(a: &[u32], b: &[u32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// Counting sort: the values of `items` (bucket, value) grouped by bucket, in input order within
/// a bucket; returns the bucket starts (`n_buckets + 1` of them) and the grouped values.
fn group_by_bucket<T: Copy + Default>(n_buckets: usize, items: impl Iterator<Item = (usize, T)> + Clone) -> (Vec<u32>, Vec<T>) {
    let mut start = vec![0u32; n_buckets + 1];
    for (k, _) in items.clone() {
        start[k + 1] += 1;
    }
    for k in 0..n_buckets {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut out = vec![T::default(); start[n_buckets] as usize];
    for (k, v) in items {
        out[fill[k] as usize] = v;
        fill[k] += 1;
    }
    (start, out)
}

/// Evaluates one term into (cleared) buffers; used by `evaluate` and the Jacobian check.
pub(crate) fn eval_term(
    term: &dyn super::problem::Term,
    x: &[f64],
    r: &mut [f64],
    active: &mut [bool],
    rows: &mut Vec<u32>,
    cols: &mut Vec<u32>,
    vals: &mut Vec<f64>,
    row_offset: usize,
) {
    r.fill(0.0);
    active.fill(true);
    let mut sink = JacobianSink::new(rows, cols, vals, active, row_offset);
    term.eval(x, r, &mut sink);
    for (ri, &a) in r.iter_mut().zip(active.iter()) {
        if !a {
            *ri = 0.0;
        }
    }
}

/// Evaluates every term at `x` (no `prepare`). Reuses the buffers' capacity.
pub(crate) fn evaluate(problem: &Problem, x: &[f64], buf: &mut EvalBuffers) {
    assert_eq!(x.len(), problem.num_variables(), "variable vector has the wrong length");
    let nt = problem.terms.len();
    buf.term_rows.clear();
    buf.term_rows.push(0);
    for t in &problem.terms {
        let last = *buf.term_rows.last().unwrap();
        buf.term_rows.push(last + t.term.residual_count());
    }
    let m = buf.term_rows[nt];
    buf.r.clear();
    buf.r.resize(m, 0.0);
    buf.active.clear();
    buf.active.resize(m, true);
    buf.rows.clear();
    buf.cols.clear();
    buf.vals.clear();
    buf.term_trips.clear();
    buf.term_trips.push(0);
    for (ti, t) in problem.terms.iter().enumerate() {
        let (r0, r1) = (buf.term_rows[ti], buf.term_rows[ti + 1]);
        eval_term(&*t.term, x, &mut buf.r[r0..r1], &mut buf.active[r0..r1], &mut buf.rows, &mut buf.cols, &mut buf.vals, r0);
        buf.term_trips.push(buf.rows.len());
    }
}

/// Σ_t w_t Σ r² (inactive residuals are already 0).
pub(crate) fn weighted_energy(problem: &Problem, buf: &EvalBuffers) -> f64 {
    let mut e = 0.0;
    for (ti, t) in problem.terms.iter().enumerate() {
        let s: f64 = buf.r[buf.term_rows[ti]..buf.term_rows[ti + 1]].iter().map(|r| r * r).sum();
        e += t.weight * s;
    }
    e
}

/// The cached normal-equation system for one sparsity pattern.
pub(crate) struct System {
    /// The ordering used (never `Auto`).
    pub ordering: Ordering,
    // ---- identity of the pattern
    n_vars: usize,
    fixed: Vec<bool>,
    rows: Vec<u32>,
    cols: Vec<u32>,
    term_rows: Vec<usize>,
    term_trips: Vec<usize>,
    // ---- maps
    /// Free index → variable index.
    pub free_to_var: Vec<u32>,
    trip_entry: Vec<u32>,
    entry_row_ptr: Vec<u32>,
    entry_col: Vec<u32>,
    pair_dest: Vec<u32>,
    diag_pos: Vec<u32>,
    // ---- matrices and work
    a_sym: SymbolicSparseColMat<u32>,
    chol: Option<SymbolicCholesky<u32>>,
    /// JᵀWJ, upper CSC values.
    h: Vec<f64>,
    /// h + μ I.
    a: Vec<f64>,
    l: Vec<f64>,
    /// JᵀW r over the free variables.
    pub g: Vec<f64>,
    /// Weighted entry values √w J.
    ev: Vec<f64>,
    /// Weighted residuals √w r.
    rw: Vec<f64>,
    sqrt_w: Vec<f64>,
    mem: MemBuffer,
}

impl System {
    pub fn n_free(&self) -> usize {
        self.free_to_var.len()
    }

    /// Number of stored entries of the upper triangle of JᵀJ (including the diagonal).
    pub fn nnz(&self) -> usize {
        self.h.len()
    }

    /// Stored values of the Cholesky factor.
    pub fn factor_nnz(&self) -> usize {
        self.l.len()
    }

    /// Σ_j c_j² over the columns of L (c_j = stored entries of column j): about the flop count of
    /// one numeric factorization.
    pub fn factor_flops(&self) -> f64 {
        self.chol.as_ref().map_or(0.0, factor_flops)
    }

    pub(crate) fn is_supernodal(&self) -> bool {
        matches!(self.chol.as_ref().map(|c| c.raw()), Some(faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(_)))
    }

    /// Whether `buf`'s structure (and the problem's variables) are those of this pattern.
    pub fn matches(&self, problem: &Problem, buf: &EvalBuffers) -> bool {
        self.n_vars == problem.num_variables() && self.fixed.as_slice() == problem.fixed_mask() && self.matches_structure(buf)
    }

    pub(crate) fn matches_structure(&self, buf: &EvalBuffers) -> bool {
        self.term_rows == buf.term_rows
            && self.term_trips == buf.term_trips
            && same_indices(&self.rows, &buf.rows)
            && same_indices(&self.cols, &buf.cols)
    }

    /// Builds the pattern, the maps and the symbolic factorization from an evaluation.
    pub fn build(problem: &Problem, buf: &EvalBuffers, ordering: Ordering, supernodal: bool) -> Self {
        let n_vars = problem.num_variables();
        let fixed = problem.fixed_mask().to_vec();
        let m = buf.r.len();
        let n_trip = buf.rows.len();
        assert!(n_vars < NONE as usize && m < NONE as usize && n_trip < NONE as usize);
        for ti in 0..problem.terms.len() {
            let (r0, r1) = (buf.term_rows[ti], buf.term_rows[ti + 1]);
            for t in buf.term_trips[ti]..buf.term_trips[ti + 1] {
                let (r, c) = (buf.rows[t] as usize, buf.cols[t] as usize);
                assert!(
                    r >= r0 && r < r1 && c < n_vars,
                    "term '{}' emitted a Jacobian entry out of range: global row {} (term rows {}..{}), column {} of {}",
                    problem.terms[ti].term.name(),
                    r,
                    r0,
                    r1,
                    c,
                    n_vars
                );
            }
        }

        let mut free_index = vec![NONE; n_vars];
        let mut free_to_var = Vec::new();
        for v in 0..n_vars {
            if !fixed[v] {
                free_index[v] = free_to_var.len() as u32;
                free_to_var.push(v as u32);
            }
        }
        let nf = free_to_var.len();

        // Group triplets with free columns by row.
        let (row_start, mut order) =
            group_by_bucket(m, (0..n_trip).filter(|&t| free_index[buf.cols[t] as usize] != NONE).map(|t| (buf.rows[t] as usize, t as u32)));

        // Unique (row, free col) entries, sorted by column within each row.
        let mut trip_entry = vec![NONE; n_trip];
        let mut entry_row_ptr = Vec::with_capacity(m + 1);
        let mut entry_col: Vec<u32> = Vec::with_capacity(order.len());
        entry_row_ptr.push(0u32);
        for r in 0..m {
            let slice = &mut order[row_start[r] as usize..row_start[r + 1] as usize];
            slice.sort_unstable_by_key(|&t| free_index[buf.cols[t as usize] as usize]);
            let row_first = entry_col.len();
            for &t in slice.iter() {
                let fc = free_index[buf.cols[t as usize] as usize];
                if entry_col.len() == row_first || *entry_col.last().unwrap() != fc {
                    entry_col.push(fc);
                }
                trip_entry[t as usize] = (entry_col.len() - 1) as u32;
            }
            entry_row_ptr.push(entry_col.len() as u32);
        }
        drop(order);

        // Upper-triangular pattern of JᵀJ + diagonal, column by column: column j holds j and
        // every i < j that shares a row with it. `pair_dest` lists, row by row and for a ≤ b over
        // the row's sorted entries, the position of (cols[a], cols[b]), as `assemble` reads it.
        let mut n_pairs = 0usize;
        let mut pair_base = Vec::with_capacity(m);
        for r in 0..m {
            let k = (entry_row_ptr[r + 1] - entry_row_ptr[r]) as usize;
            pair_base.push(n_pairs);
            n_pairs += k * (k + 1) / 2;
        }
        assert!(n_pairs < NONE as usize, "too many Jacobian products");
        // The rows of each free column, with the column's index within the row (Jᵀ in CSR).
        let (col_rows_ptr, col_rows) = group_by_bucket(
            nf,
            (0..m).flat_map(|r| {
                let (e0, e1) = (entry_row_ptr[r] as usize, entry_row_ptr[r + 1] as usize);
                entry_col[e0..e1].iter().enumerate().map(move |(b, &c)| (c as usize, (r as u32, b as u32)))
            }),
        );
        let mut col_ptr = Vec::with_capacity(nf + 1);
        col_ptr.push(0u32);
        let mut row_idx: Vec<u32> = Vec::new();
        let mut pos = vec![NONE; nf];
        let mut pair_dest = vec![NONE; n_pairs];
        let mut diag_pos = Vec::with_capacity(nf);
        for j in 0..nf {
            let start = row_idx.len();
            let rows = &col_rows[col_rows_ptr[j] as usize..col_rows_ptr[j + 1] as usize];
            row_idx.push(j as u32);
            pos[j] = 0;
            for &(r, b) in rows {
                let e0 = entry_row_ptr[r as usize] as usize;
                for &i in &entry_col[e0..e0 + b as usize] {
                    if pos[i as usize] == NONE {
                        pos[i as usize] = 0;
                        row_idx.push(i);
                    }
                }
            }
            row_idx[start..].sort_unstable();
            for (p, &i) in row_idx[start..].iter().enumerate() {
                pos[i as usize] = (start + p) as u32;
            }
            diag_pos.push(pos[j]);
            // Entry (a, b) of a row with k entries sits at a k − a(a − 1)/2 + (b − a) in its block.
            for &(r, b) in rows {
                let (e0, e1) = (entry_row_ptr[r as usize] as usize, entry_row_ptr[r as usize + 1] as usize);
                let (k, b) = (e1 - e0, b as usize);
                for (a, &i) in entry_col[e0..e0 + b + 1].iter().enumerate() {
                    pair_dest[pair_base[r as usize] + a * k - a * a.saturating_sub(1) / 2 + (b - a)] = pos[i as usize];
                }
            }
            for &i in &row_idx[start..] {
                pos[i as usize] = NONE;
            }
            col_ptr.push(row_idx.len() as u32);
        }
        let nnz = row_idx.len();
        assert!(nnz < NONE as usize);
        debug_assert!(pair_dest.iter().all(|&d| d != NONE));

        let groups = problem.variable_groups();
        let group: Vec<u32> = free_to_var.iter().map(|&v| groups[v as usize]).collect();
        let a_sym = SymbolicSparseColMat::<u32>::new_checked(nf, nf, col_ptr, None, row_idx);
        let (chol, l_len, mem, chosen) = if nf > 0 {
            let (chol, chosen) = symbolic_with_ordering(a_sym.as_ref(), &group, ordering, supernodal);
            let req = StackReq::or(
                chol.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
                chol.solve_in_place_scratch::<f64>(1, Par::Seq),
            );
            let l_len = chol.len_val();
            (Some(chol), l_len, MemBuffer::new(req), chosen)
        } else {
            (None, 0, MemBuffer::new(StackReq::EMPTY), ordering)
        };

        Self {
            ordering: chosen,
            n_vars,
            fixed,
            rows: buf.rows.clone(),
            cols: buf.cols.clone(),
            term_rows: buf.term_rows.clone(),
            term_trips: buf.term_trips.clone(),
            free_to_var,
            trip_entry,
            ev: vec![0.0; entry_col.len()],
            entry_row_ptr,
            entry_col,
            pair_dest,
            diag_pos,
            a_sym,
            chol,
            h: vec![0.0; nnz],
            a: vec![0.0; nnz],
            l: vec![0.0; l_len],
            g: vec![0.0; nf],
            rw: vec![0.0; m],
            sqrt_w: Vec::with_capacity(problem.terms.len()),
            mem,
        }
    }

    /// Fills JᵀWJ and JᵀWr from an evaluation with this pattern's structure.
    pub fn assemble(&mut self, problem: &Problem, buf: &EvalBuffers) {
        self.sqrt_w.clear();
        self.sqrt_w.extend(problem.terms.iter().map(|t| t.weight.sqrt()));
        for ti in 0..problem.terms.len() {
            let s = self.sqrt_w[ti];
            let (r0, r1) = (buf.term_rows[ti], buf.term_rows[ti + 1]);
            for (rw, &r) in self.rw[r0..r1].iter_mut().zip(&buf.r[r0..r1]) {
                *rw = s * r;
            }
        }
        self.ev.fill(0.0);
        for ti in 0..problem.terms.len() {
            let s = self.sqrt_w[ti];
            let (t0, t1) = (buf.term_trips[ti], buf.term_trips[ti + 1]);
            for (&e, &v) in self.trip_entry[t0..t1].iter().zip(&buf.vals[t0..t1]) {
                if e != NONE {
                    self.ev[e as usize] += s * v;
                }
            }
        }
        self.h.fill(0.0);
        self.g.fill(0.0);
        let h = &mut self.h[..];
        let g = &mut self.g[..];
        let mut dests = &self.pair_dest[..];
        let m = self.rw.len();
        for row in 0..m {
            let e0 = self.entry_row_ptr[row] as usize;
            let e1 = self.entry_row_ptr[row + 1] as usize;
            let k = e1 - e0;
            let np = k * (k + 1) / 2;
            let (row_dests, rest) = dests.split_at(np);
            dests = rest;
            let rr = self.rw[row];
            if !buf.active[row] || (rr == 0.0 && self.ev[e0..e1].iter().all(|&v| v == 0.0)) {
                continue;
            }
            let vals = &self.ev[e0..e1];
            let cols = &self.entry_col[e0..e1];
            let mut d = row_dests;
            for a in 0..k {
                let va = vals[a];
                g[cols[a] as usize] += va * rr;
                let (da, rest) = d.split_at(k - a);
                d = rest;
                for (&dst, &vb) in da.iter().zip(&vals[a..]) {
                    h[dst as usize] += va * vb;
                }
            }
        }
    }

    /// |JᵀWr|∞.
    pub(crate) fn gradient_inf_norm(&self) -> f64 {
        self.g.iter().fold(0.0, |m, g| m.max(g.abs()))
    }

    /// Solves (JᵀWJ + μI) Δ = −JᵀWr into `delta` (length n_free). False if the numeric
    /// factorization failed (not positive definite).
    pub(crate) fn factor_solve(&mut self, mu: f64, delta: &mut [f64]) -> bool {
        let nf = self.n_free();
        assert_eq!(delta.len(), nf);
        let Some(chol) = self.chol.as_ref() else {
            return true;
        };
        self.a.copy_from_slice(&self.h);
        for &p in &self.diag_pos {
            self.a[p as usize] += mu;
        }
        let mat = SparseColMatRef::new(self.a_sym.as_ref(), &self.a);
        let stack = MemStack::new(&mut self.mem);
        let llt = match chol.factorize_numeric_llt(&mut self.l, mat, Side::Upper, LltRegularization::default(), Par::Seq, stack, Default::default()) {
            Ok(llt) => llt,
            Err(_) => return false,
        };
        for (d, g) in delta.iter_mut().zip(&self.g) {
            *d = -g;
        }
        llt.solve_in_place_with_conj(Conj::No, MatMut::from_column_major_slice_mut(delta, nf, 1), Par::Seq, stack);
        delta.iter().all(|d| d.is_finite())
    }
}

/// The symbolic Cholesky factorization of the upper pattern `a` with the requested ordering;
/// `Auto` tries block AMD and nested dissection and keeps the one with fewer flops; `supernodal`
/// forces the supernodal factorization.
fn symbolic_with_ordering(
    a: SymbolicSparseColMatRef<'_, u32>,
    group: &[u32],
    ordering: Ordering,
    supernodal: bool,
) -> (SymbolicCholesky<u32>, Ordering) {
    let threshold = if supernodal { SupernodalThreshold::FORCE_SUPERNODAL } else { SupernodalThreshold::AUTO };
    let analyze = |ord: SymmetricOrdering<'_, u32>| {
        factorize_symbolic_cholesky(a, Side::Upper, ord, CholeskySymbolicParams { supernodal_flop_ratio_threshold: threshold, ..Default::default() })
            .expect("symbolic Cholesky analysis")
    };
    if ordering == Ordering::Amd {
        return (analyze(SymmetricOrdering::Amd), Ordering::Amd);
    }
    let graph = BlockGraph::new(group, a.col_ptr(), a.row_idx());
    let with_nodes = |nodes: Vec<u32>| {
        let (fwd, inv) = graph.expand(&nodes);
        analyze(SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, fwd.len())))
    };
    match ordering {
        Ordering::BlockAmd => (with_nodes(graph.amd_order()), Ordering::BlockAmd),
        Ordering::NestedDissection => (with_nodes(graph.nested_dissection_order()), Ordering::NestedDissection),
        _ => {
            let amd = with_nodes(graph.amd_order());
            let nd = with_nodes(graph.nested_dissection_order());
            if factor_flops(&nd) < factor_flops(&amd) {
                (nd, Ordering::NestedDissection)
            } else {
                (amd, Ordering::BlockAmd)
            }
        }
    }
}

/// Σ_j c_j² over the columns of L (c_j = stored entries of column j, diagonal included).
pub(crate) fn factor_flops(chol: &SymbolicCholesky<u32>) -> f64 {
    use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
    match chol.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr().windows(2).map(|w| ((w[1] - w[0]) as f64).powi(2)).sum(),
        SymbolicCholeskyRaw::Supernodal(s) => {
            let (b, e, rp) = (s.supernode_begin(), s.supernode_end(), s.col_ptr_for_row_idx());
            let mut f = 0.0;
            for k in 0..s.n_supernodes() {
                let w = (e[k] - b[k]) as usize;
                let p = (rp[k + 1] - rp[k]) as f64;
                // column i of the supernode stores w − i + p entries
                for i in 0..w {
                    f += ((w - i) as f64 + p).powi(2);
                }
            }
            f
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::solver::Linear;

    /// The pattern holds exactly the upper triangle of JᵀJ's structure plus the diagonal, and
    /// `assemble` gives the dense JᵀWJ and JᵀWr over the free variables: rows with repeated and
    /// unsorted columns, two weights, fixed variables, a free variable in no row.
    #[test]
    fn assembly_matches_the_dense_normal_equations() {
        let n = 23;
        let mut rng = Rng(7);
        let mut problem = Problem::new(n);
        let mut dense_rows: Vec<(f64, Vec<f64>, f64)> = Vec::new();
        for (weight, rows) in [(1.0, 31), (2.5, 17)] {
            let mut term = Linear::new();
            for _ in 0..rows {
                let k = 1 + (rng.uniform() * 7.0) as usize;
                let coeffs: Vec<(usize, f64)> =
                    (0..k).map(|_| (((rng.uniform() * (n - 1) as f64) as usize).min(n - 2), rng.range(-1.0, 1.0))).collect();
                let constant = rng.range(-1.0, 1.0);
                term.push_row(&coeffs, constant);
                let mut row = vec![0.0; n];
                for &(c, v) in &coeffs {
                    row[c] += v;
                }
                dense_rows.push((weight, row, constant));
            }
            problem.add_term(term, weight);
        }
        for v in [0, 5, 6, 13] {
            problem.fix(v);
        }
        let x: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let mut buf = EvalBuffers::default();
        evaluate(&problem, &x, &mut buf);
        let mut sys = System::build(&problem, &buf, Ordering::BlockAmd, false);
        sys.assemble(&problem, &buf);
        let free: Vec<usize> = sys.free_to_var.iter().map(|&v| v as usize).collect();
        assert_eq!(free.len(), n - 4);
        let (col_ptr, row_idx) = (sys.a_sym.col_ptr(), sys.a_sym.row_idx());
        for (j, &vj) in free.iter().enumerate() {
            let rows = &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize];
            assert!(rows.windows(2).all(|w| w[0] < w[1]), "column {j}: rows sorted and unique");
            for (i, &vi) in free.iter().enumerate().take(j + 1) {
                let coupled = i == j || dense_rows.iter().any(|(_, row, _)| row[vi] != 0.0 && row[vj] != 0.0);
                let at = rows.iter().position(|&r| r as usize == i);
                assert_eq!(at.is_some(), coupled, "pattern entry ({i}, {j})");
                let (mut h, mut g) = (0.0, 0.0);
                for (w, row, c) in &dense_rows {
                    h += w * row[vi] * row[vj];
                    if i == j {
                        let r: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>() + c;
                        g += w * row[vj] * r;
                    }
                }
                if let Some(p) = at {
                    let got = sys.h[col_ptr[j] as usize + p];
                    assert!((got - h).abs() <= 1e-12 * (1.0 + h.abs()), "JᵀWJ ({i}, {j}): {got} vs {h}");
                }
                if i == j {
                    assert!((sys.g[j] - g).abs() <= 1e-12 * (1.0 + g.abs()), "JᵀWr {j}: {} vs {g}", sys.g[j]);
                }
            }
        }
    }
}
