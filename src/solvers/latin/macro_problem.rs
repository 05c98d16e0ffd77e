//! The macro problem (SPEC §4), assembled and factorized once (sparse LU):
//! `[Σ c_Eᵀ L_E c_E, N; Nᵀ, 0] [f_Γ; a] = −[Σ c_Eᵀ K⁺_E g_E; (Q_Eᵀ g_E)_E]`,
//! `N = [c_Eᵀ Q_E]_E`. Unknowns: the macro forces of every interface, then the kernel amplitudes
//! of every substructure.

use super::substructure::Substructure;
use super::Interface;
use crate::linalg::{gemv, gemv_transposed};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, Triplet};

/// The macro problem `[Σ c_Eᵀ L_E c_E, N; Nᵀ, 0] [f_Γ; a] = −[Σ c_Eᵀ K⁺_E g_E; (Q_Eᵀ g_E)_E]`,
/// LU-factorised once.
pub struct MacroProblem {
    /// Number of macro force unknowns (Σ over interfaces of their macro dofs).
    pub n_forces: usize,
    /// First kernel amplitude of each substructure, after the forces.
    pub kernel_offset: Vec<usize>,
    /// Size of the macro system: `n_forces` + Σ kernel columns.
    pub n: usize,
    lu: Option<Lu<usize, f64>>,
    /// The LU's symbolic analysis and the pattern it was made for (column pointers, row
    /// indices).
    symbolic: Option<(SymbolicLu<usize>, Pattern)>,
}

/// A sparse pattern: column pointers and row indices.
type Pattern = (Vec<usize>, Vec<usize>);

/// The macro matrix is singular (an interface or kernel mode is left undetermined).
#[derive(Debug, Clone, Copy)]
pub struct SingularMacroProblem;

impl MacroProblem {
    /// Assemble and LU-factorise the macro matrix; `Err` if it is singular.
    pub fn new(
        subs: &[Substructure],
        interfaces: &[Interface],
    ) -> Result<MacroProblem, SingularMacroProblem> {
        Self::assemble(subs, interfaces, None)
    }

    /// The macro problem of new substructure operators on the same partition, reusing this
    /// one's symbolic LU analysis when the pattern is the same (the search directions changed,
    /// the kernels did not).
    pub fn refactor(
        &self,
        subs: &[Substructure],
        interfaces: &[Interface],
    ) -> Result<MacroProblem, SingularMacroProblem> {
        Self::assemble(subs, interfaces, Some(self))
    }

    fn assemble(
        subs: &[Substructure],
        interfaces: &[Interface],
        previous: Option<&MacroProblem>,
    ) -> Result<MacroProblem, SingularMacroProblem> {
        let n_forces: usize = interfaces.iter().map(|i| i.basis.ncols()).sum();
        let mut kernel_offset = Vec::with_capacity(subs.len());
        let mut n = n_forces;
        for sub in subs {
            kernel_offset.push(n);
            n += sub.kernel.ncols();
        }
        // Duplicates are summed by faer when the matrix is built.
        let mut triplets: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut add = |r: usize, c: usize, v: f64| {
            if v != 0.0 {
                triplets.push(Triplet::new(r, c, v));
            }
        };
        for (e, sub) in subs.iter().enumerate() {
            for s1 in &sub.sides {
                let row0 = interfaces[s1.interface].macro_offset;
                for s2 in &sub.sides {
                    let col0 = interfaces[s2.interface].macro_offset;
                    let sign = s1.sign() * s2.sign();
                    for i in 0..s1.cols {
                        for j in 0..s2.cols {
                            let v = sub.flexibility[(s1.macro_offset + i, s2.macro_offset + j)];
                            add(row0 + i, col0 + j, sign * v);
                        }
                    }
                }
                for i in 0..s1.cols {
                    for k in 0..sub.kernel.ncols() {
                        let v = s1.sign() * sub.kernel[(s1.macro_offset + i, k)];
                        add(row0 + i, kernel_offset[e] + k, v);
                        add(kernel_offset[e] + k, row0 + i, v);
                    }
                }
            }
        }
        let mut analysed = None;
        let lu = if n == 0 {
            None
        } else {
            let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
                .map_err(|_| SingularMacroProblem)?;
            let pattern = (
                matrix.symbolic().col_ptr().to_vec(),
                matrix.symbolic().row_idx().to_vec(),
            );
            let symbolic = match previous.and_then(|p| p.symbolic.as_ref()) {
                Some((symbolic, old)) if *old == pattern => symbolic.clone(),
                _ => SymbolicLu::try_new(matrix.symbolic()).map_err(|_| SingularMacroProblem)?,
            };
            let lu = Lu::try_new_with_symbolic(symbolic.clone(), matrix.as_ref())
                .map_err(|_| SingularMacroProblem)?;
            analysed = Some((symbolic, pattern));
            // LU does not report a singular matrix reliably: solve M x = M x0 for a known x0.
            let x0: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 / 7.0).collect();
            let mut x = vec![0.0; n];
            for t in &triplets {
                x[t.row] += t.val * x0[t.col];
            }
            lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 1));
            let error = x
                .iter()
                .zip(&x0)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if error.is_nan() || error > 1e-6 {
                return Err(SingularMacroProblem);
            }
            Some(lu)
        };
        Ok(MacroProblem {
            n_forces,
            kernel_offset,
            n,
            lu,
            symbolic: analysed,
        })
    }

    /// Right-hand side from every `g_E`, solve, and return `[f_Γ; a]`.
    pub fn solve(
        &self,
        subs: &[Substructure],
        interfaces: &[Interface],
        g: &[Vec<f64>],
    ) -> Vec<f64> {
        let mut rhs = vec![0.0; self.n];
        for (e, sub) in subs.iter().enumerate() {
            let mut kg = vec![0.0; sub.n_macro];
            gemv(&mut kg, &sub.k_plus, &g[e], false);
            for side in &sub.sides {
                let row0 = interfaces[side.interface].macro_offset;
                for i in 0..side.cols {
                    rhs[row0 + i] -= side.sign() * kg[side.macro_offset + i];
                }
            }
            let kernel_rows = self.kernel_offset[e]..self.kernel_offset[e] + sub.kernel.ncols();
            let mut qg = vec![0.0; sub.kernel.ncols()];
            gemv_transposed(&mut qg, &sub.kernel, &g[e], false);
            rhs[kernel_rows]
                .iter_mut()
                .zip(&qg)
                .for_each(|(r, q)| *r -= q);
        }
        if let Some(lu) = &self.lu {
            let n = rhs.len();
            lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, n, 1));
        }
        rhs
    }
}
