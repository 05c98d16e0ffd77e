//! The macro problem (docs/method.md §4), assembled and factorised once per set of substructure
//! operators: `[Σ c_Eᵀ L_E c_E, N; Nᵀ, 0] [f_Γ; a] = −[Σ c_Eᵀ K⁺_E g_E; (Q_Eᵀ g_E)_E]`,
//! `N = [c_Eᵀ Q_E]_E`. Unknowns: the macro forces of every interface, then the kernel amplitudes
//! of every substructure.
//!
//! `L_E = K⁺_E − I/d_m` is −1/d_m on the kernel of K*_E, so the force block is indefinite and
//! the matrix needs a pivoting LU (COLAMD), which cost 0.45 s per factorisation on a 64 × 64
//! grid (6902 unknowns). The second equation `Nᵀ f_Γ = b_a` makes the force block definite
//! without changing the solution: adding `γ N (Nᵀ f_Γ − b_a) = 0` to the first gives
//! `Ã = Σ c_Eᵀ (L_E + γ Q_E Q_Eᵀ) c_E`, which is 1/d_m on each kernel and `K⁺_E − I/d_m > 0`
//! on its range for γ = 2/d_m. The matrix `[Ã, N; Nᵀ, 0]` is then factorised as a symmetric
//! quasi-definite one, `L D Lᵀ`, with the kernel pivots held negative by a tiny
//! regularisation that a few steps of iterative refinement against the exact matrix undo.
//! From 1024 substructures on it is factored and solved in subtrees of substructures side by
//! side (`tree`: a bisection of the substructures whose separators hold forces only), below
//! that whole after AMD (`factor`).
//! It is factorised equilibrated, `S M S` with `S_ii = 1/√M_ii` on the forces: substructures
//! whose slack cables make them soft have flexibilities far above the others', and unscaled
//! their spread cost the macro answer two decades of accuracy on 256 substructures (noise
//! that the LATIN iterates then carry: r(U) stalled at 9e-7 on 256 × 256 modules).

mod factor;
mod tree;

use super::substructure::Substructure;
use super::Interface;
use crate::linalg::{gemv, gemv_transposed};
pub(super) use factor::{Factor, MacroPattern};
use faer::sparse::Pair;
use std::sync::Arc;

/// γ d_m of the augmentation `Ã = A + γ N Nᵀ`: the force block is then 1/d_m on every kernel.
const AUGMENTATION: f64 = 2.0;

/// The macro problem `[Σ c_Eᵀ L_E c_E, N; Nᵀ, 0] [f_Γ; a] = −[Σ c_Eᵀ K⁺_E g_E; (Q_Eᵀ g_E)_E]`,
/// factorised once.
pub struct MacroProblem {
    /// Number of macro force unknowns (Σ over interfaces of their macro dofs).
    pub n_forces: usize,
    /// First kernel amplitude of each substructure, after the forces.
    pub kernel_offset: Vec<usize>,
    /// Size of the macro system: `n_forces` + Σ kernel columns.
    pub n: usize,
    /// `d_m`, for the augmentation and the scaling.
    dm: f64,
    factor: Option<Factor>,
}

/// The macro matrix is singular (an interface or kernel mode is left undetermined).
#[derive(Debug, Clone, Copy)]
pub struct SingularMacroProblem;

impl MacroProblem {
    /// Entries of its `L D Lᵀ` factor (every rank holds one: it is solved on every rank).
    pub fn factor_entries(&self) -> usize {
        self.factor.as_ref().map_or(0, Factor::entries)
    }

    /// Assemble and factorise the macro matrix; `Err` if it is singular.
    pub fn new(
        subs: &[Substructure],
        interfaces: &[Interface],
        dm: f64,
    ) -> Result<MacroProblem, SingularMacroProblem> {
        Self::assemble(subs, interfaces, dm, None, Some(tree::LEAF_SUBSTRUCTURES))
    }

    /// This problem anew, split into leaves of at least `leaf_substructures` substructures
    /// (`None`: factored whole), for tests.
    #[cfg(test)]
    pub(super) fn with_leaves(
        &self,
        subs: &[Substructure],
        interfaces: &[Interface],
        leaf_substructures: Option<usize>,
    ) -> Result<MacroProblem, SingularMacroProblem> {
        Self::assemble(subs, interfaces, self.dm, None, leaf_substructures)
    }

    /// The levels of subtrees its factor is split into (0: whole).
    pub(super) fn split_levels(&self) -> usize {
        self.factor.as_ref().map_or(0, |f| f.pattern.split_levels())
    }

    /// The macro problem of new substructure operators on the same partition, reusing this
    /// one's symbolic analysis when the pattern is the same (the search directions changed,
    /// the kernels did not).
    pub fn refactor(
        &self,
        subs: &[Substructure],
        interfaces: &[Interface],
    ) -> Result<MacroProblem, SingularMacroProblem> {
        Self::assemble(
            subs,
            interfaces,
            self.dm,
            self.factor.as_ref(),
            Some(tree::LEAF_SUBSTRUCTURES),
        )
    }

    /// Assemble the macro matrix in an order fixed by the partition, reuse `previous`'s
    /// symbolic analysis when the pattern is the same, factorise, and check the factor.
    fn assemble(
        subs: &[Substructure],
        interfaces: &[Interface],
        dm: f64,
        previous: Option<&Factor>,
        leaf_substructures: Option<usize>,
    ) -> Result<MacroProblem, SingularMacroProblem> {
        let n_forces: usize = interfaces.iter().map(|i| i.basis.ncols()).sum();
        let mut kernel_offset = Vec::with_capacity(subs.len());
        let mut n = n_forces;
        for sub in subs {
            kernel_offset.push(n);
            n += sub.kernel.ncols();
        }
        let problem = |factor| MacroProblem {
            n_forces,
            kernel_offset: kernel_offset.clone(),
            n,
            dm,
            factor,
        };
        if n == 0 {
            return Ok(problem(None));
        }
        let (entries, values) = Self::entries(subs, interfaces, dm, &kernel_offset, n);
        let pattern = match previous {
            Some(old) if old.pattern.argsort_len == values.len() => Arc::clone(&old.pattern),
            _ => Arc::new(MacroPattern::new(n, &entries, n_forces, |lower| {
                leaf_substructures.and_then(|leaf| {
                    tree::macro_tree(subs, interfaces, &kernel_offset, lower, leaf)
                })
            })?),
        };
        drop(entries);
        let factor = Factor::new(pattern, &values, n_forces)?;
        drop(values);
        // Checked at set-up only: a re-set-up changes l > 0 alone, which keeps every
        // K*_E + Q_E Q_Eᵀ definite (its Cholesky succeeded) and so Ã definite.
        if previous.is_none() {
            factor.check_regular(n)?;
        }
        Ok(problem(Some(factor)))
    }

    /// Lower triangle of D [Ã, N; Nᵀ, 0] D, entry by entry in an order fixed by the partition
    /// (zeros included, so the pattern never changes); duplicates are summed on assembly.
    fn entries(
        subs: &[Substructure],
        interfaces: &[Interface],
        dm: f64,
        kernel_offset: &[usize],
        n: usize,
    ) -> (Vec<Pair<usize, usize>>, Vec<f64>) {
        let gamma = AUGMENTATION / dm;
        let mut entries: Vec<Pair<usize, usize>> = Vec::new();
        let mut values: Vec<f64> = Vec::new();
        let mut add = |r: usize, c: usize, v: f64| {
            if r >= c {
                entries.push(Pair::new(r, c));
                values.push(v);
            }
        };
        for (e, sub) in subs.iter().enumerate() {
            // L_E + γ Q_E Q_Eᵀ, scaled by d_m.
            let q = &sub.kernel;
            let block = (&sub.flexibility + q * q.transpose() * gamma) * dm;
            for s1 in &sub.sides {
                let row0 = interfaces[s1.interface].macro_offset;
                for s2 in &sub.sides {
                    let col0 = interfaces[s2.interface].macro_offset;
                    let sign = s1.sign() * s2.sign();
                    for i in 0..s1.cols {
                        for j in 0..s2.cols {
                            let v = block[(s1.macro_offset + i, s2.macro_offset + j)];
                            add(row0 + i, col0 + j, sign * v);
                        }
                    }
                }
                for i in 0..s1.cols {
                    for k in 0..q.ncols() {
                        let v = s1.sign() * q[(s1.macro_offset + i, k)];
                        add(kernel_offset[e] + k, row0 + i, v);
                    }
                }
            }
        }
        // Every pivot is in the pattern.
        for i in 0..n {
            add(i, i, 0.0);
        }
        (entries, values)
    }

    /// A zero right-hand side `[b_f; b_a]`.
    pub fn zero_rhs(&self) -> Vec<f64> {
        vec![0.0; self.n]
    }

    /// Substructure E's part of the right-hand side in E's own macro dofs, computed where E
    /// is held: `K⁺_E g_E + γ Q_E Q_Eᵀ g_E` on its macro dofs, then `Q_Eᵀ g_E`.
    pub fn rhs_piece(&self, sub: &Substructure, g: &[f64]) -> Vec<f64> {
        let gamma = AUGMENTATION / self.dm;
        let mut kg = vec![0.0; sub.n_macro];
        gemv(&mut kg, &sub.ops().k_plus, g, false);
        let mut qg = vec![0.0; sub.kernel.ncols()];
        gemv_transposed(&mut qg, &sub.kernel, g, false);
        let mut nb = vec![0.0; sub.n_macro];
        gemv(&mut nb, &sub.kernel, &qg, false);
        let mut piece: Vec<f64> = kg.iter().zip(&nb).map(|(k, n)| k + gamma * n).collect();
        piece.extend_from_slice(&qg);
        piece
    }

    /// Substructure E's `piece` ([`Self::rhs_piece`]) added to `rhs` (a sum over the
    /// substructures, in their order on every rank): `b_f −= c_Eᵀ (K⁺_E g_E + γ Q_E Q_Eᵀ g_E)`,
    /// `b_a,E = −Q_Eᵀ g_E`.
    pub fn add_rhs(
        &self,
        e: usize,
        sub: &Substructure,
        interfaces: &[Interface],
        piece: &[f64],
        rhs: &mut [f64],
    ) {
        let (forces, kernel) = piece.split_at(sub.n_macro);
        for side in &sub.sides {
            let row0 = interfaces[side.interface].macro_offset;
            for i in 0..side.cols {
                rhs[row0 + i] -= side.sign() * forces[side.macro_offset + i];
            }
        }
        let kernel_rows = self.kernel_offset[e]..self.kernel_offset[e] + sub.kernel.ncols();
        rhs[kernel_rows]
            .iter_mut()
            .zip(kernel)
            .for_each(|(r, q)| *r -= q);
    }

    /// The error the set-up's regularity check measures (invariant tests: the equilibration).
    #[cfg(test)]
    pub(super) fn forward_error(&self) -> f64 {
        self.factor
            .as_ref()
            .map_or(0.0, |f| f.forward_error(self.n))
    }

    /// `[f_Γ; a]` from the assembled right-hand side, refined until the residual is below
    /// `accuracy` times the right-hand side's largest entry (scaled).
    pub fn solve_rhs(&self, mut rhs: Vec<f64>, accuracy: f64) -> Vec<f64> {
        if let Some(factor) = &self.factor {
            // x = D y with (D M̃ D) y = D b.
            let scale = |i: usize| {
                if i < self.n_forces {
                    self.dm.sqrt()
                } else {
                    1.0 / self.dm.sqrt()
                }
            };
            rhs.iter_mut().enumerate().for_each(|(i, b)| *b *= scale(i));
            factor.solve(&mut rhs, accuracy);
            rhs.iter_mut().enumerate().for_each(|(i, y)| *y *= scale(i));
        }
        rhs
    }

    /// Substructure E's share of the answer: its macro forces `f_E = c_E f_Γ` (signed per
    /// side) and its kernel amplitudes `a_E`.
    pub fn answer<'a>(
        &self,
        e: usize,
        sub: &Substructure,
        interfaces: &[Interface],
        solution: &'a [f64],
    ) -> (Vec<f64>, &'a [f64]) {
        let mut f_e = vec![0.0; sub.n_macro];
        for side in &sub.sides {
            let off = interfaces[side.interface].macro_offset;
            for i in 0..side.cols {
                f_e[side.macro_offset + i] = side.sign() * solution[off + i];
            }
        }
        let a_e = &solution[self.kernel_offset[e]..self.kernel_offset[e] + sub.kernel.ncols()];
        (f_e, a_e)
    }
}
