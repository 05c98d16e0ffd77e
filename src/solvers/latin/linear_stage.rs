//! Linear stage (docs/method.md §4): given ŝ, find s: per substructure a solve with K_E, one macro
//! solve gluing the substructures by exact macro continuity, then per substructure its
//! displacements, its links' (e, t) and its interface sides' (U, F).

use super::{Latin, SubState};
use crate::linalg::gemv;
use rayon::prelude::*;

impl Latin<'_> {
    /// Linear stage (docs/method.md §4): given ŝ in `state`, find s.
    /// With `relaxation = Some(μ)`, s is then relaxed against the previous one on every field
    /// (e, t, U, interface U and F): `s ← μ s_new + (1 − μ) s_old`.
    pub(super) fn linear_stage(
        &self,
        load: &[f64],
        state: &mut [SubState],
        relaxation: Option<f64>,
    ) {
        let s = self.structure;
        let dm = self.dm;
        let search = &self.search;
        // Per substructure: F̂d_E, y_E = K_E⁻¹ F̂d_E, g_E = d_m R_Eᵀ C_E y_E.
        let condensed: Vec<(Vec<f64>, Vec<f64>)> = self
            .substructures
            .par_iter()
            .zip(state.par_iter())
            .with_min_len(self.chunk)
            .map(|(sub, st)| {
                let mut f: Vec<f64> = sub
                    .dof_global
                    .iter()
                    .zip(&sub.load_share)
                    .map(|(&d, &share)| load[d] * share)
                    .collect();
                for (j, &i) in sub.links.iter().enumerate() {
                    let w = st.t_hat[j] - search[i] * st.e_hat[j] + s.links[i].prestress;
                    sub.link_dofs[j].scatter(-w, &mut f);
                }
                for (side, ss) in sub.sides.iter().zip(&st.sides) {
                    for (r, &v) in ss.hat_load.iter().enumerate() {
                        f[sub.gamma_dofs[side.gamma_offset + r]] += v;
                    }
                }
                sub.factor.solve_in_place(&mut f);
                let mut g = sub.project(&f);
                g.iter_mut().for_each(|x| *x *= dm);
                (f, g)
            })
            .collect();
        let (y, g): (Vec<Vec<f64>>, Vec<Vec<f64>>) = condensed.into_iter().unzip();
        let solution = self
            .macro_problem
            .solve(&self.substructures, &self.interfaces, &g);
        let interfaces = &self.interfaces;
        let kernel_offset = &self.macro_problem.kernel_offset;
        self.substructures
            .par_iter()
            .zip(state.par_iter_mut())
            .zip(y.into_par_iter().zip(g.into_par_iter()))
            .with_min_len(self.chunk)
            .enumerate()
            .for_each(|(e, ((sub, st), (y, g)))| {
                let previous = relaxation.map(|mu| (mu, Relaxed::of(st)));
                // f_E = c_E f_Γ, a_E; u_E = L_E f_E + K⁺_E g_E + Q_E a_E.
                let mut f_e = vec![0.0; sub.n_macro];
                for side in &sub.sides {
                    let off = interfaces[side.interface].macro_offset;
                    for i in 0..side.cols {
                        f_e[side.macro_offset + i] = side.sign() * solution[off + i];
                    }
                }
                let a_e = &solution[kernel_offset[e]..kernel_offset[e] + sub.kernel.ncols()];
                let mut u_e = vec![0.0; sub.n_macro];
                gemv(&mut u_e, &sub.flexibility, &f_e, false);
                gemv(&mut u_e, &sub.k_plus, &g, true);
                gemv(&mut u_e, &sub.kernel, a_e, true);
                // U_E = y_E + d_m Z_E (u_E + f_E/d_m).
                let star: Vec<f64> = u_e.iter().zip(&f_e).map(|(u, f)| dm * u + f).collect();
                st.u.copy_from_slice(&y);
                gemv(&mut st.u, &sub.z, &star, true);
                // e_E = B_E U_E, t_E = t̂_E + l(e_E − ê_E).
                for (j, &i) in sub.links.iter().enumerate() {
                    st.e[j] = sub.link_dofs[j].elongation(&st.u);
                    st.t[j] = st.t_hat[j] + search[i] * (st.e[j] - st.e_hat[j]);
                }
                // Interfaces: U = C_E U_E, U^M = R u, F^M = R f, F^m = F̂^m + d_m Û^m − d_m(U − U^M).
                for (side, ss) in sub.sides.iter().zip(st.sides.iter_mut()) {
                    let block = side.macro_offset..side.macro_offset + side.cols;
                    let mut u_macro = vec![0.0; side.rows];
                    let mut f_macro = vec![0.0; side.rows];
                    gemv(&mut u_macro, &side.basis, &u_e[block.clone()], false);
                    gemv(&mut f_macro, &side.basis, &f_e[block], false);
                    for r in 0..side.rows {
                        let u = st.u[sub.gamma_dofs[side.gamma_offset + r]];
                        ss.u[r] = u;
                        ss.f[r] = f_macro[r] + ss.hat_load[r] - dm * (u - u_macro[r]);
                    }
                }
                if let Some((mu, previous)) = previous {
                    previous.blend_into(st, mu);
                }
            });
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
