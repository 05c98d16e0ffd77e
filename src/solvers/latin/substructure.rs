//! One substructure E and its linear-stage operators (docs/method.md §4 "Linear stage"):
//! `K_E = B_Eᵀ l B_E + d_m C_Eᵀ C_E` (sparse, factorized once), `Z_E = K_E⁻¹ C_Eᵀ R_E`,
//! `K*_E = d_m I − d_m² R_Eᵀ C_E Z_E`, its kernel Q_E, `K⁺_E = (K*_E + Q Qᵀ)⁻¹ − Q Qᵀ` and the
//! homogenised flexibility `L_E = K⁺_E − I/d_m`.

use super::Interface;
use crate::decomposition::kernel::{substructure_kernel, InterfaceTrace};
use crate::decomposition::partition::SubstructureTopology;
use crate::decomposition::substructure::{LocalDofs, Shapes};
use crate::linalg::{gemv_transposed, SpdSolver, StiffnessPattern};
use crate::model::Model;
use crate::structure::{transverse_pair, LinkDofs, Structure};
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

mod assembly;
mod kernel;
use assembly::{geometric_rows, interface_sides, stiffness};
use kernel::{complete_kernel, invert, rigid_kernel};

/// E's view of one of its interfaces.
#[derive(Debug, Clone)]
pub struct Side {
    /// Index of the interface in the solver's interface list.
    pub interface: usize,
    /// 0 if E is the interface's first substructure (macro forces counted +), 1 otherwise (−).
    pub which: usize,
    /// First row of this interface in E's stacked interface vector U_EΓ.
    pub gamma_offset: usize,
    /// First column of this interface in E's macro vector u_E.
    pub macro_offset: usize,
    /// Rows of this interface in U_EΓ: its nodes' free components (rows of R).
    pub rows: usize,
    /// Its macro dofs in u_E (columns of R).
    pub cols: usize,
    /// The interface's macro basis R (rows × cols), a copy kept with E.
    pub basis: DMatrix<f64>,
}

impl Side {
    /// The sign of `c_E` on this interface: +1 on its first substructure, −1 on its second.
    pub fn sign(&self) -> f64 {
        if self.which == 0 {
            1.0
        } else {
            -1.0
        }
    }
}

/// How a substructure's operators are kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OperatorStorage {
    /// K_E⁻¹ kept dense (see [`SpdSolver::new`]).
    pub dense: bool,
    /// Z_E kept (`solver.keep_z`); otherwise every linear stage computes `Z_E w` by one more
    /// solve with K_E's factor.
    pub keep_z: bool,
}

/// Why a substructure operator could not be built.
#[derive(Debug, Clone, Copy)]
pub struct SingularSubstructure;

/// One substructure E and its linear-stage operators, built once (docs/method.md §4 "Linear stage").
pub struct Substructure {
    /// Global link indices, in the order of every per-link array of E.
    pub links: Vec<usize>,
    /// Local dof → global free dof.
    pub dof_global: Vec<usize>,
    /// Per local dof: the share of a nodal load E carries (1 / substructures holding the node).
    pub load_share: Vec<f64>,
    /// Per link of E: its row of B_E on E's local dofs (`e = n·(U_b − U_a)`).
    pub link_dofs: Vec<LinkDofs>,
    /// E's interfaces, by increasing interface index: their rows stacked in this order in U_EΓ
    /// and their macro columns in u_E.
    pub sides: Vec<Side>,
    /// Local dof of each row of U_EΓ (C_E as an index map).
    pub gamma_dofs: Vec<usize>,
    /// E's macro dofs: Σ over its sides of the columns of R (columns of R_E).
    pub n_macro: usize,
    /// E's operators on its own dofs: on the rank that holds E (every substructure on one
    /// process); `None` on the others, which know E's indexing, L_E and Q_E only.
    pub ops: Option<LocalOperators>,
    /// `L_E = K⁺_E − I/d_m`, the homogenised flexibility.
    pub flexibility: DMatrix<f64>,
    /// `Q_E`: orthonormal columns spanning the kernel of K*_E (`n_macro` rows).
    pub kernel: DMatrix<f64>,
}

/// E's operators on its own dofs, built by the rank that holds E.
pub struct LocalOperators {
    /// The pattern of K_E (fixed by E's links), shared by the substructures of E's shape.
    pub(super) pattern: Arc<StiffnessPattern>,
    /// With the prestress's geometric stiffness (`model.geometry = "prestress"`): per link of
    /// E (its index j in E) its two transverse rows on E's dofs and `t0 / L`, the share of
    /// `K_G(t0)` that K_E holds (docs/method.md §8: part of the admissibility, not of the law).
    geometric: Vec<(usize, LinkDofs, f64)>,
    /// Solves with K_E.
    pub factor: SpdSolver,
    /// `Z_E = K_E⁻¹ C_Eᵀ R_E` (E's dofs × `n_macro`), unless it is recomputed
    /// ([`OperatorStorage::keep_z`]).
    pub z: Option<DMatrix<f64>>,
    /// `K*_E = d_m I − d_m² R_Eᵀ C_E Z_E`, symmetrised (kept for the invariant tests of its
    /// kernel).
    #[cfg_attr(not(test), allow(dead_code))]
    pub k_star: DMatrix<f64>,
    /// `K⁺_E = (K*_E + Q_E Q_Eᵀ)⁻¹ − Q_E Q_Eᵀ`, the pseudo-inverse of K*_E.
    pub k_plus: DMatrix<f64>,
}

impl Substructure {
    /// E's operators, built in the order of docs/method.md §4 "Linear stage", kept as
    /// `storage` says. `shapes`: the patterns and analyses of the
    /// substructures built so far, shared with E when it has the shape of one. `local_dof` is
    /// a scratch map of length `3·nodes`, all [`CLAMPED`](crate::structure::CLAMPED) on entry and on exit.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        index: usize,
        topology: &SubstructureTopology,
        model: &Model,
        interfaces: &[Interface],
        holders: &[u8],
        search: &[f64],
        dm: f64,
        storage: OperatorStorage,
        shapes: &Shapes,
        local_dof: &mut [usize],
    ) -> Result<Substructure, SingularSubstructure> {
        // 1.–3. E's local dofs, B_E and its share of K_G(t0), C_E and R_E.
        let (mut sub, geometric) =
            Self::indexed(index, topology, model, interfaces, holders, local_dof);
        // 4. K_E = B_Eᵀ l B_E + K_G,E + d_m C_Eᵀ C_E, factorized.
        let pattern = StiffnessPattern::new(sub.n_dofs(), &sub.link_dofs);
        let values = stiffness(
            &pattern,
            &sub.link_dofs,
            &geometric,
            &sub.gamma_dofs,
            &sub.links,
            search,
            dm,
        );
        let (pattern, factor) = shapes
            .factor(pattern, &values, storage.dense)
            .map_err(|_| SingularSubstructure)?;
        // 5. Z_E = K_E⁻¹ C_Eᵀ R_E and K*_E = d_m I − d_m² R_Eᵀ C_E Z_E.
        let (z, k_star) = sub.condense_operators(&factor, dm);
        // 6. Q_E: the rigid motions with no micro trace, completed by the null space of K*_E.
        let rigid = rigid_kernel(&sub.sides, topology, &model.structure, interfaces);
        sub.kernel = complete_kernel(&k_star, rigid, dm).ok_or(SingularSubstructure)?;
        // 7. K⁺_E = (K*_E + Q_E Q_Eᵀ)⁻¹ − Q_E Q_Eᵀ and L_E = K⁺_E − I/d_m.
        let (k_plus, flexibility) = invert(&k_star, &sub.kernel, dm)?;
        sub.flexibility = flexibility;
        sub.ops = Some(LocalOperators {
            pattern,
            geometric,
            factor,
            z: storage.keep_z.then_some(z),
            k_star,
            k_plus,
        });
        Ok(sub)
    }

    /// E as a rank that does not hold it knows it: its indexing (steps 1–3 of [`Self::new`]),
    /// no operators; L_E and Q_E are set from the rank that holds it.
    pub fn remote(
        index: usize,
        topology: &SubstructureTopology,
        model: &Model,
        interfaces: &[Interface],
        holders: &[u8],
        local_dof: &mut [usize],
    ) -> Substructure {
        Self::indexed(index, topology, model, interfaces, holders, local_dof).0
    }

    /// Steps 1–3 of [`Self::new`]: E with its indexing and no operators, and its share of
    /// K_G(t0) on its dofs. `local_dof` is all [`CLAMPED`](crate::structure::CLAMPED) on entry and on exit.
    fn indexed(
        index: usize,
        topology: &SubstructureTopology,
        model: &Model,
        interfaces: &[Interface],
        holders: &[u8],
        local_dof: &mut [usize],
    ) -> (Substructure, Vec<(usize, LinkDofs, f64)>) {
        let structure = &model.structure;
        // 1.–2. E's local dofs (numbered in `local_dof` until step 3 is done) and B_E, one row
        //       `e = n·(U_b − U_a)` per link on them (the substructure room's); E's share of K_G(t0).
        let LocalDofs {
            dof_global,
            load_share,
            link_dofs,
        } = LocalDofs::number(topology, structure, holders, local_dof);
        let geometric = geometric_rows(topology, model, local_dof);
        // 3. C_E and R_E: E's interfaces, their rows in U_EΓ and their columns in u_E.
        let (sides, gamma_dofs, n_macro) = interface_sides(index, interfaces, local_dof);
        LocalDofs::clear(topology, local_dof);
        let sub = Substructure {
            links: topology.links.clone(),
            dof_global,
            load_share,
            link_dofs,
            sides,
            gamma_dofs,
            n_macro,
            ops: None,
            flexibility: DMatrix::zeros(0, 0),
            kernel: DMatrix::zeros(0, 0),
        };
        (sub, geometric)
    }

    /// E's operators, on the rank that holds E.
    pub fn ops(&self) -> &LocalOperators {
        self.ops
            .as_ref()
            .expect("a substructure's operators are used only on the rank that holds it")
    }

    /// E's operators for the search directions `search`, rebuilt in place: its indexing, the
    /// pattern of K_E and its symbolic analysis, and the kernel Q_E are kept (they depend on
    /// E's links and supports, not on l > 0); K_E is factorised anew into the factor's own
    /// storage and Z_E, K*_E, K⁺_E, L_E recomputed. Nothing of the previous operators is kept
    /// (a rebuild of every substructure would otherwise hold two sets at once): on failure
    /// they are lost, and the caller rebuilds them from the previous directions.
    pub fn set_search(
        &mut self,
        search: &[f64],
        dm: f64,
        storage: OperatorStorage,
    ) -> Result<(), SingularSubstructure> {
        self.rebuild_operators(search, dm, storage, true)
    }

    /// Step 4 of [`Self::set_search`] alone: K_E for the directions `search`, factorized; Z_E,
    /// K*_E, K⁺_E and L_E are left for [`Self::set_interfaces`], which a rebuild that retakes
    /// soft interface modes calls next (condensing on the old bases first would be thrown
    /// away).
    pub(super) fn refactor(
        &mut self,
        search: &[f64],
        dm: f64,
        storage: OperatorStorage,
    ) -> Result<(), SingularSubstructure> {
        self.rebuild_operators(search, dm, storage, false)
    }

    /// E's sides re-read from `interfaces`, whose macro bases changed (not their nodes), and
    /// where E is held, steps 5–7 of [`Self::new`] on its kept factor: Z_E, K*_E, Q_E, K⁺_E
    /// and L_E for the new bases.
    pub(super) fn set_interfaces(
        &mut self,
        topology: &SubstructureTopology,
        structure: &Structure,
        interfaces: &[Interface],
        dm: f64,
        storage: OperatorStorage,
    ) -> Result<(), SingularSubstructure> {
        let mut n_macro = 0;
        for side in &mut self.sides {
            side.basis = interfaces[side.interface].basis.clone();
            side.cols = side.basis.ncols();
            side.macro_offset = n_macro;
            n_macro += side.cols;
        }
        self.n_macro = n_macro;
        let Some(mut ops) = self.ops.take() else {
            // Not held here: L_E and Q_E come from the rank that holds E.
            return Ok(());
        };
        let (z, k_star) = self.condense_operators(&ops.factor, dm);
        let rigid = rigid_kernel(&self.sides, topology, structure, interfaces);
        let built = complete_kernel(&k_star, rigid, dm)
            .ok_or(SingularSubstructure)
            .and_then(|kernel| {
                let (k_plus, flexibility) = invert(&k_star, &kernel, dm)?;
                Ok((kernel, k_plus, flexibility))
            });
        if let Ok((kernel, k_plus, flexibility)) = &built {
            self.kernel = kernel.clone();
            self.flexibility = flexibility.clone();
            ops.k_plus = k_plus.clone();
        }
        (ops.z, ops.k_star) = (storage.keep_z.then_some(z), k_star);
        self.ops = Some(ops);
        built.map(|_| ())
    }

    /// Steps 4–7 of [`Self::new`] on E's kept pattern, analysis and kernel (step 4 alone
    /// without `condense`).
    fn rebuild_operators(
        &mut self,
        search: &[f64],
        dm: f64,
        storage: OperatorStorage,
        condense: bool,
    ) -> Result<(), SingularSubstructure> {
        let mut ops = self
            .ops
            .take()
            .expect("a substructure's operators are rebuilt only on the rank that holds it");
        let rebuilt = self.rebuild_taken(&mut ops, search, dm, storage, condense);
        self.ops = Some(ops);
        rebuilt
    }

    /// [`Self::rebuild_operators`] on E's operators `ops`, taken out of E meanwhile.
    fn rebuild_taken(
        &mut self,
        ops: &mut LocalOperators,
        search: &[f64],
        dm: f64,
        storage: OperatorStorage,
        condense: bool,
    ) -> Result<(), SingularSubstructure> {
        // 4. K_E = B_Eᵀ l B_E + K_G,E + d_m C_Eᵀ C_E, factorized.
        let values = stiffness(
            &ops.pattern,
            &self.link_dofs,
            &ops.geometric,
            &self.gamma_dofs,
            &self.links,
            search,
            dm,
        );
        match &mut ops.factor {
            SpdSolver::Sparse(factor) => factor
                .factorize(&ops.pattern, &values)
                .map_err(|_| SingularSubstructure)?,
            SpdSolver::Dense(_) => {
                ops.factor = SpdSolver::new(&ops.pattern, &values, storage.dense)
                    .map_err(|_| SingularSubstructure)?
            }
        }
        drop(values);
        if !condense {
            return Ok(());
        }
        // 5. Z_E and K*_E; 7. K⁺_E and L_E (Q_E of step 6 is kept).
        let (z, k_star) = self.condense_operators(&ops.factor, dm);
        let (k_plus, flexibility) = invert(&k_star, &self.kernel, dm)?;
        (ops.z, ops.k_star, ops.k_plus) = (storage.keep_z.then_some(z), k_star, k_plus);
        self.flexibility = flexibility;
        Ok(())
    }

    /// `Z_E = K_E⁻¹ C_Eᵀ R_E` and `K*_E = d_m I − d_m² R_Eᵀ C_E Z_E` (symmetrised) from the
    /// factor of K_E.
    pub(super) fn condense_operators(
        &self,
        factor: &SpdSolver,
        dm: f64,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        // Z_E column by column of the block-diagonal R_E.
        let n_macro = self.n_macro;
        let mut z = DMatrix::<f64>::zeros(self.n_dofs(), n_macro);
        for side in &self.sides {
            let basis = &side.basis;
            for j in 0..side.cols {
                let mut col = z.column_mut(side.macro_offset + j);
                for r in 0..side.rows {
                    col[self.gamma_dofs[side.gamma_offset + r]] += basis[(r, j)];
                }
            }
        }
        factor.solve_columns(&mut z);
        let mut k_star = DMatrix::<f64>::identity(n_macro, n_macro) * dm;
        for j in 0..n_macro {
            let rz = self.project(z.column(j).as_slice());
            for i in 0..n_macro {
                k_star[(i, j)] -= dm * dm * rz[i];
            }
        }
        let k_star = (&k_star + k_star.transpose()) * 0.5;
        (z, k_star)
    }

    /// Number of E's free dofs (the free components of the nodes it touches).
    pub fn n_dofs(&self) -> usize {
        self.dof_global.len()
    }

    /// `R_Eᵀ C_E v` for a vector on E's dofs.
    pub fn project(&self, v: &[f64]) -> Vec<f64> {
        self.project_gamma(&self.gather(v))
    }

    /// `C_E v`: E's interface rows.
    pub fn gather(&self, v: &[f64]) -> Vec<f64> {
        self.gamma_dofs.iter().map(|&d| v[d]).collect()
    }

    /// `v += C_Eᵀ R_E w` for w on E's macro dofs: each interface's `R w` on its rows' dofs.
    pub fn scatter_macro(&self, w: &[f64], v: &mut [f64]) {
        for side in &self.sides {
            let block = &w[side.macro_offset..side.macro_offset + side.cols];
            for r in 0..side.rows {
                let row: f64 = (0..side.cols).map(|j| side.basis[(r, j)] * block[j]).sum();
                v[self.gamma_dofs[side.gamma_offset + r]] += row;
            }
        }
    }

    /// `R_Eᵀ w` for w on E's interface rows.
    pub fn project_gamma(&self, w: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_macro];
        for side in &self.sides {
            gemv_transposed(
                &mut out[side.macro_offset..side.macro_offset + side.cols],
                &side.basis,
                &w[side.gamma_offset..side.gamma_offset + side.rows],
                false,
            );
        }
        out
    }
}
