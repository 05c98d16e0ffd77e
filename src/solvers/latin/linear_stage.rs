//! Linear stage (docs/method.md §4): given ŝ, find s: per substructure a solve with K_E, one macro
//! solve gluing the substructures by exact macro continuity, then per substructure its
//! displacements, its links' (e, t) and its interface sides' (U, F).

use super::substructure::Substructure;
use super::{Latin, SubState};
use crate::linalg::gemv;
use crate::structure::Structure;
use rayon::prelude::*;

/// What a substructure hands to the macro problem: `y_E = K_E⁻¹ F̂d_E` (kept for its
/// recovery) and `g_E = d_m R_Eᵀ C_E y_E` (its part of the macro right-hand side).
pub(crate) struct Condensed {
    /// `y_E`, on E's dofs.
    pub y: Vec<f64>,
    /// `g_E`, on E's macro dofs.
    pub g: Vec<f64>,
}

/// The linear-stage inputs every substructure reads alike.
pub(crate) struct StageInputs<'a> {
    pub structure: &'a Structure,
    /// The load on the free dofs.
    pub load: &'a [f64],
    /// l of every link.
    pub search: &'a [f64],
    pub dm: f64,
}

impl Substructure {
    /// The first half of E's linear stage (docs/method.md §4): `F̂d_E` from the load share,
    /// the links' `t̂ − l ê + t0` and the interfaces' `F̂^m + d_m Û^m` of ŝ; then
    /// `y_E = K_E⁻¹ F̂d_E` and `g_E = d_m R_Eᵀ C_E y_E`.
    pub(crate) fn condense(&self, inputs: &StageInputs<'_>, st: &SubState) -> Condensed {
        let mut f: Vec<f64> = self
            .dof_global
            .iter()
            .zip(&self.load_share)
            .map(|(&d, &share)| inputs.load[d] * share)
            .collect();
        let links = &inputs.structure.links;
        for (j, &i) in self.links.iter().enumerate() {
            let w = st.t_hat[j] - inputs.search[i] * st.e_hat[j] + links[i].prestress;
            self.link_dofs[j].scatter(-w, &mut f);
        }
        for (side, ss) in self.sides.iter().zip(&st.sides) {
            for (r, &v) in ss.hat_load.iter().enumerate() {
                f[self.gamma_dofs[side.gamma_offset + r]] += v;
            }
        }
        self.ops().factor.solve_in_place(&mut f);
        let mut g = self.project(&f);
        g.iter_mut().for_each(|x| *x *= inputs.dm);
        Condensed { y: f, g }
    }

    /// The second half (docs/method.md §4): from E's macro forces `f_E = c_E f_Γ` and kernel
    /// amplitudes `a_E`, `u_E = L_E f_E + K⁺_E g_E + Q_E a_E`, `U_E = y_E + d_m Z_E (u_E +
    /// f_E/d_m)`, then s: the links' `e = B_E U_E`, `t = t̂ + l (e − ê)`, and the interfaces'
    /// `U = C_E U_E`, `F = R f + F̂^m + d_m Û^m − d_m (U − R u)`.
    pub(crate) fn recover(
        &self,
        inputs: &StageInputs<'_>,
        f_e: &[f64],
        a_e: &[f64],
        condensed: Condensed,
        st: &mut SubState,
    ) {
        let dm = inputs.dm;
        let mut u_e = vec![0.0; self.n_macro];
        gemv(&mut u_e, &self.flexibility, f_e, false);
        gemv(&mut u_e, &self.ops().k_plus, &condensed.g, true);
        gemv(&mut u_e, &self.kernel, a_e, true);
        // U_E = y_E + d_m Z_E (u_E + f_E/d_m).
        let star: Vec<f64> = u_e.iter().zip(f_e).map(|(u, f)| dm * u + f).collect();
        st.u.copy_from_slice(&condensed.y);
        match &self.ops().z {
            Some(z) => gemv(&mut st.u, z, &star, true),
            None => {
                // Z_E star = K_E⁻¹ C_Eᵀ R_E star, by one more solve.
                let mut v = vec![0.0; self.n_dofs()];
                self.scatter_macro(&star, &mut v);
                self.ops().factor.solve_in_place(&mut v);
                st.u.iter_mut().zip(&v).for_each(|(u, z)| *u += z);
            }
        }
        // e_E = B_E U_E, t_E = t̂_E + l(e_E − ê_E).
        for (j, &i) in self.links.iter().enumerate() {
            st.e[j] = self.link_dofs[j].elongation(&st.u);
            st.t[j] = st.t_hat[j] + inputs.search[i] * (st.e[j] - st.e_hat[j]);
        }
        // Interfaces: U = C_E U_E, U^M = R u, F^M = R f, F^m = F̂^m + d_m Û^m − d_m(U − U^M).
        for (side, ss) in self.sides.iter().zip(st.sides.iter_mut()) {
            let block = side.macro_offset..side.macro_offset + side.cols;
            let mut u_macro = vec![0.0; side.rows];
            let mut f_macro = vec![0.0; side.rows];
            gemv(&mut u_macro, &side.basis, &u_e[block.clone()], false);
            gemv(&mut f_macro, &side.basis, &f_e[block], false);
            for r in 0..side.rows {
                let u = st.u[self.gamma_dofs[side.gamma_offset + r]];
                ss.u[r] = u;
                ss.f[r] = f_macro[r] + ss.hat_load[r] - dm * (u - u_macro[r]);
            }
        }
    }
}

impl Latin<'_> {
    /// Linear stage (docs/method.md §4): given ŝ in `state`, find s: every substructure
    /// condensed, the macro problem solved on their `g_E`, every substructure recovered.
    /// With `relaxation = Some(μ)`, s is then relaxed against the previous one on every field
    /// (e, t, U, interface U and F): `s ← μ s_new + (1 − μ) s_old`. The macro solve is refined
    /// to `accuracy` of its right-hand side (0: to the end).
    pub(super) fn linear_stage(
        &self,
        load: &[f64],
        state: &mut [SubState],
        relaxation: Option<f64>,
        accuracy: f64,
    ) {
        let inputs = StageInputs {
            structure: self.structure,
            load,
            search: &self.search.now,
            dm: self.world.dm,
        };
        // 1. The substructures this process holds, condensed: y_E, g_E and E's part of the
        //    macro right-hand side.
        let held = self.ranks.held();
        let macro_problem = &self.operators.macro_problem;
        let (condensed, pieces): (Vec<Condensed>, Vec<Vec<f64>>) = self.operators.substructures
            [held.clone()]
        .par_iter()
        .zip(state[held.clone()].par_iter())
        .with_min_len(self.ranks.chunk())
        .map(|(sub, st)| {
            let c = sub.condense(&inputs, st);
            let piece = macro_problem.rhs_piece(sub, &c.g);
            (c, piece)
        })
        .unzip();
        // 2. Every substructure's part (gathered from the ranks), summed in their order.
        let pieces = self.gather_pieces(pieces);
        let mut rhs = self.operators.macro_problem.zero_rhs();
        for (e, (sub, piece)) in self.operators.substructures.iter().zip(&pieces).enumerate() {
            self.operators
                .macro_problem
                .add_rhs(e, sub, &self.interfaces.list, piece, &mut rhs);
        }
        // 3. The macro problem, solved on every rank.
        let solution = self.operators.macro_problem.solve_rhs(rhs, accuracy);
        // 4. The held substructures recovered, relaxed when asked.
        let interfaces = &self.interfaces.list;
        self.operators.substructures[held.clone()]
            .par_iter()
            .zip(state[held.clone()].par_iter_mut())
            .zip(condensed.into_par_iter())
            .with_min_len(self.ranks.chunk())
            .enumerate()
            .for_each(|(k, ((sub, st), condensed))| {
                let e = held.start + k;
                let previous = relaxation.map(|mu| (mu, Relaxed::of(st)));
                let (f_e, a_e) = macro_problem.answer(e, sub, interfaces, &solution);
                sub.recover(&inputs, &f_e, a_e, condensed, st);
                if let Some((mu, previous)) = previous {
                    previous.blend_into(st, mu);
                }
            });
        // 5. What the linear stage wrote of the others' substructures.
        self.share_linear_stage(state);
    }

    /// Every substructure's part of the macro right-hand side, from the `held` ones' parts on
    /// each rank (on one process: `held` itself).
    fn gather_pieces(&self, held: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        if self.ranks.size() == 1 {
            return held;
        }
        let all = self.ranks.gather(&held.concat());
        let mut rest = all.as_slice();
        self.operators
            .substructures
            .iter()
            .map(|sub| {
                let (piece, tail) = rest.split_at(sub.n_macro + sub.kernel.ncols());
                rest = tail;
                piece.to_vec()
            })
            .collect()
    }

    /// What the next stages read of the other ranks' substructures after a linear stage:
    /// point to point from the neighbouring ranks (`NeighbourPlan::share_s`), or s whole
    /// when every iteration reads it.
    fn share_linear_stage(&self, state: &mut [SubState]) {
        match self.ranks.neighbours() {
            _ if self.ranks.size() == 1 => {}
            Some(plan) => plan.share_s(self.ranks.exchange(), state),
            None => self.share_whole_state(state),
        }
    }

    /// For the answer, which reads U on every dof: U_E of every substructure, from the rank
    /// that holds it onto every rank, when the iterations exchange s point to point (the
    /// answer's per-link values are gathered by themselves: `Latin::per_link`).
    pub(super) fn complete_state(&self, state: &mut [SubState]) {
        if self.ranks.neighbours().is_none() || self.ranks.size() == 1 {
            return;
        }
        let mine: Vec<f64> = state[self.ranks.held()]
            .iter()
            .flat_map(|st| st.u.iter().copied())
            .collect();
        let all = self.ranks.gather(&mine);
        let mut rest = all.as_slice();
        for (e, st) in state.iter_mut().enumerate() {
            let (values, tail) = rest.split_at(st.u.len());
            if !self.ranks.holds(e) {
                st.u.copy_from_slice(values);
            }
            rest = tail;
        }
    }

    /// The fields of s a linear stage writes (e, t, U_E, the sides' U and F) of every
    /// substructure, from the rank that holds it onto every rank.
    pub(super) fn share_whole_state(&self, state: &mut [SubState]) {
        if self.ranks.size() == 1 {
            return;
        }
        let mut mine = Vec::new();
        for st in &state[self.ranks.held()] {
            mine.extend_from_slice(&st.e);
            mine.extend_from_slice(&st.t);
            mine.extend_from_slice(&st.u);
            for side in &st.sides {
                mine.extend_from_slice(&side.u);
                mine.extend_from_slice(&side.f);
            }
        }
        let all = self.ranks.gather(&mine);
        let mut rest = all.as_slice();
        let mut take = |into: &mut [f64], write: bool| {
            let (values, tail) = rest.split_at(into.len());
            if write {
                into.copy_from_slice(values);
            }
            rest = tail;
        };
        for ((e, st), sub) in state
            .iter_mut()
            .enumerate()
            .zip(&self.operators.substructures)
        {
            let write = !self.ranks.holds(e);
            st.widen(sub);
            take(&mut st.e, write);
            take(&mut st.t, write);
            take(&mut st.u, write);
            for side in &mut st.sides {
                take(&mut side.u, write);
                take(&mut side.f, write);
            }
        }
    }
}

/// The fields of s that relaxation blends, as they were before a linear stage.
struct Relaxed {
    e: Vec<f64>,
    t: Vec<f64>,
    u: Vec<f64>,
    sides: Vec<(Vec<f64>, Vec<f64>)>,
}

impl Relaxed {
    fn of(st: &SubState) -> Relaxed {
        Relaxed {
            e: st.e.clone(),
            t: st.t.clone(),
            u: st.u.clone(),
            sides: st
                .sides
                .iter()
                .map(|s| (s.u.clone(), s.f.clone()))
                .collect(),
        }
    }

    /// `new ← μ new + (1 − μ) old`, field by field.
    fn blend_into(self, st: &mut SubState, mu: f64) {
        let blend = |new: &mut [f64], old: &[f64]| {
            new.iter_mut()
                .zip(old)
                .for_each(|(n, o)| *n = mu * *n + (1.0 - mu) * o);
        };
        blend(&mut st.e, &self.e);
        blend(&mut st.t, &self.t);
        blend(&mut st.u, &self.u);
        for (side, (u, f)) in st.sides.iter_mut().zip(&self.sides) {
            blend(&mut side.u, u);
            blend(&mut side.f, f);
        }
    }
}
