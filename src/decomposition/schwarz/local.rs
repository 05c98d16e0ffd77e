//! One overlapping subdomain Ω_j of the two-level Schwarz preconditioner: its Dirichlet matrix
//! `A_j = R_j H R_jᵀ` (every link with a free dof in Ω_j, its row cut to Ω_j's dofs), factorised;
//! its Neumann matrix `A_j^Neu` (the links with every free dof in Ω_j); and its GenEO vectors,
//! `A_j^Neu v = λ D_j A_j D_j v` with λ < τ, kept as `Z_j = D_j V_j` (docs/method.md,
//! "Newton–Krylov on the substructures"). The pattern and its symbolic analysis are made once;
//! a new set of link weights refactorises.

use super::GeneoSolve;
use crate::linalg::{
    modes_below, modes_below_by_subspace, NotPositiveDefinite, SparseCholesky, SparseRow,
    StiffnessPattern,
};
use crate::structure::Structure;
use faer::Par;
use nalgebra::DMatrix;

/// A subdomain's operators.
pub(super) struct LocalProblem {
    /// The pattern of A_j, on the cut rows of its links.
    pattern: StiffnessPattern,
    /// Per link of Ω_j (the overlap's order): its row cut to Ω_j's local dofs.
    rows: Vec<SparseRow>,
    /// Per link of Ω_j: its global index, and whether it is in the Neumann matrix.
    links: Vec<(usize, bool)>,
    /// A_j's factor (on the symbolic analysis made once).
    dirichlet: SparseCholesky,
    /// The link weights A_j was last factorised with (`None`: never).
    weights: Option<Vec<f64>>,
    /// The link weights of the pencil its GenEO vectors solve (`None`: none yet).
    geneo_weights: Option<Vec<f64>>,
    /// `Z_j = D_j V_j` (Ω_j's dofs × its coarse vectors).
    pub coarse: DMatrix<f64>,
    /// GenEO's eigenvalues of the kept vectors, ascending, and whether every one below τ was
    /// found.
    pub values: Vec<f64>,
    pub complete: bool,
}

impl LocalProblem {
    /// Ω_j with free dofs `dofs` (global, increasing) and links `links` (the overlap's).
    pub(super) fn new(structure: &Structure, dofs: &[usize], links: &[(usize, bool)]) -> Self {
        let local = |d: usize| dofs.binary_search(&d).ok();
        let rows: Vec<SparseRow> = links
            .iter()
            .map(|&(i, _)| {
                SparseRow::new(structure.link_dofs[i].iter().map(|(d, c)| (local(d), c)))
            })
            .collect();
        let pattern = StiffnessPattern::new(dofs.len(), &rows);
        let dirichlet = SparseCholesky::analyse(&pattern, Par::Seq);
        LocalProblem {
            pattern,
            rows,
            links: links.to_vec(),
            dirichlet,
            weights: None,
            geneo_weights: None,
            coarse: DMatrix::zeros(dofs.len(), 0),
            values: Vec::new(),
            complete: true,
        }
    }

    /// Whether the link weights `weights` (global, per link) differ from those A_j was last
    /// factorised with, on Ω_j's links.
    pub(super) fn changed(&self, weights: &[f64]) -> bool {
        match &self.weights {
            None => true,
            Some(old) => self
                .links
                .iter()
                .zip(old)
                .any(|(&(i, _), &w)| weights[i] != w),
        }
    }

    /// A_j for `weights` and `mu` (`H = Σ w_i b_i b_iᵀ + μ I`), factorised, and its GenEO
    /// vectors below `settings.tau` (at most `settings.max_modes`), kept where at most
    /// `settings.keep_vectors` of Ω_j's links changed weight since they were found (a
    /// preconditioner's coarse space need not be exact; E is made anew on the current H);
    /// `unity` is D_j. `true` when the vectors were found anew.
    pub(super) fn refresh(
        &mut self,
        weights: &[f64],
        mu: f64,
        unity: &[f64],
        settings: &super::SchwarzSettings,
    ) -> Result<bool, NotPositiveDefinite> {
        let (tau, max_modes) = (settings.tau, settings.max_modes);
        let local_weights: Vec<f64> = self.links.iter().map(|&(i, _)| weights[i]).collect();
        let pattern = &self.pattern;
        // A_j = Σ_{links of Ω_j} w (R_j b)(R_j b)ᵀ + μ I.
        let mut dirichlet = vec![0.0; pattern.nnz()];
        pattern.assemble(&self.rows, |k| local_weights[k], &mut dirichlet);
        // A_j^Neu = Σ_{inner links} w b bᵀ + μ I.
        let mut neumann = vec![0.0; pattern.nnz()];
        let links = &self.links;
        pattern.assemble(
            &self.rows,
            |k| if links[k].1 { local_weights[k] } else { 0.0 },
            &mut neumann,
        );
        for &s in &pattern.diag_slot {
            dirichlet[s] += mu;
            neumann[s] += mu;
        }
        self.weights = None;
        self.dirichlet.factorize(pattern, &dirichlet)?;
        let kept = self.geneo_weights.as_ref().is_some_and(|old| {
            let changed = old
                .iter()
                .zip(&local_weights)
                .filter(|(a, b)| a != b)
                .count();
            changed as f64 <= settings.keep_vectors * old.len() as f64
        });
        if kept {
            self.weights = Some(local_weights);
            return Ok(false);
        }
        // B = D_j A_j D_j.
        let mut scaled = dirichlet;
        for (r, c, s) in pattern.entries() {
            scaled[s] *= unity[r] * unity[c];
        }
        let mut shifted = self.dirichlet.share_symbolic();
        let modes = match settings.geneo {
            GeneoSolve::Exact => {
                modes_below(pattern, &neumann, &scaled, &mut shifted, tau, max_modes)?
            }
            GeneoSolve::Subspace {
                width,
                sweeps,
                warm_sweeps,
            } => {
                // Warm: the last vectors Z_j start the block (D_j V_j: near enough to V_j to
                // start from, where D_j is not zero).
                let warm = self.coarse.ncols() > 0;
                let sweeps = if warm { warm_sweeps } else { sweeps };
                let start = warm.then_some(&self.coarse);
                let pencil = (tau, max_modes);
                modes_below_by_subspace(
                    pattern,
                    &neumann,
                    &scaled,
                    &mut shifted,
                    pencil,
                    (width, sweeps),
                    start,
                )?
            }
        };
        // Z_j = D_j V_j.
        let mut coarse = modes.vectors;
        for (r, mut row) in coarse.row_iter_mut().enumerate() {
            row *= unity[r];
        }
        self.coarse = coarse;
        self.values = modes.values;
        self.complete = modes.complete;
        self.geneo_weights = Some(local_weights.clone());
        self.weights = Some(local_weights);
        Ok(true)
    }

    /// Refactorised, its GenEO vectors found anew, at the next refresh, whatever the weights.
    pub(super) fn forget(&mut self) {
        self.weights = None;
        self.geneo_weights = None;
    }

    /// `x ← A_j⁻¹ x` on Ω_j's dofs.
    pub(super) fn solve(&self, x: &mut [f64]) {
        self.dirichlet.solve_in_place(x);
    }
}
