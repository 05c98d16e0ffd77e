//! Local stage (docs/method.md §4): given s, find ŝ on the constitutive set Γ along the search
//! direction, independently per link and per interface.

use super::{Latin, SideState, SubState};
use crate::linalg::{gemv, gemv_transposed};
use crate::structure::Link;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// The law a local stage projects s on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum LocalLaw<'a> {
    /// The exact unilateral law of the cables.
    Exact,
    /// The law linearised at a slack status, per link (docs/method.md §9): cables taut in it
    /// elastic both ways, cables slack in it without tension.
    Frozen(&'a [bool]),
}

impl Latin<'_> {
    /// Local stage (docs/method.md §4): given s in `state`, find ŝ on `law`, on the links of
    /// the substructures this process holds and on the interfaces they touch (all of them on
    /// one process): what its linear stages, η and slack count read.
    pub(super) fn local_stage(&self, state: &mut [SubState], law: LocalLaw) {
        self.local_stage_on(state, law, self.ranks.held());
    }

    /// The local stage on the links of `subs` and on the interfaces they touch.
    pub(super) fn local_stage_on(
        &self,
        state: &mut [SubState],
        law: LocalLaw,
        subs: std::ops::Range<usize>,
    ) {
        let s = self.structure;
        let search = &self.search.now;
        let status = match law {
            LocalLaw::Exact => None,
            LocalLaw::Frozen(status) => Some(status),
        };
        self.operators.substructures[subs.clone()]
            .par_iter()
            .zip(state[subs.clone()].par_iter_mut())
            .with_min_len(self.ranks.chunk())
            .for_each(|(sub, st)| {
                for (j, &i) in sub.links.iter().enumerate() {
                    let (link, l, e, t) = (&s.links[i], search[i], st.e[j], st.t[j]);
                    let (e_hat, t_hat, slack) = match status {
                        Some(status) => frozen_link_local_stage(link, l, e, t, status[i]),
                        None => link_local_stage(link, l, e, t),
                    };
                    st.e_hat[j] = e_hat;
                    st.t_hat[j] = t_hat;
                    st.slack_hat[j] = slack;
                }
            });
        // The interfaces with a side in `subs`: their two sides computed in parallel on
        // copies, then written back (an interface between two ranks is computed alike on
        // both, from the two sides' s every rank holds).
        let touched: Vec<usize> = (0..self.interfaces.list.len())
            .filter(|&k| {
                let [a, b] = self.interfaces.list[k].topology.sides;
                subs.contains(&a) || subs.contains(&b)
            })
            .collect();
        let sides: Vec<(SideState, SideState)> = touched
            .par_iter()
            .with_min_len(self.ranks.chunk())
            .map(|&k| {
                let (iface, [ia, ib]) = (&self.interfaces.list[k], self.interfaces.side_slots[k]);
                let [a, b] = iface.topology.sides;
                let (mut side_a, mut side_b) =
                    (state[a].sides[ia].clone(), state[b].sides[ib].clone());
                interface_local_stage(&iface.basis, self.world.dm, &mut side_a, &mut side_b);
                (side_a, side_b)
            })
            .collect();
        for (&k, (side_a, side_b)) in touched.iter().zip(sides) {
            let [a, b] = self.interfaces.list[k].topology.sides;
            let [ia, ib] = self.interfaces.side_slots[k];
            state[a].sides[ia] = side_a;
            state[b].sides[ib] = side_b;
        }
    }
}

/// `(ê, t̂, slack)` of one link from its `(e, t)` (additional tension t), search direction l.
pub fn link_local_stage(link: &Link, l: f64, e: f64, t: f64) -> (f64, f64, bool) {
    let k = link.stiffness;
    if !link.unilateral {
        // ê = (l e + t)/(k + l), t̂ = k ê.
        let e_hat = (l * e + t) / (k + l);
        return (e_hat, k * e_hat, false);
    }
    // λ̃ = −(τ/l + e + t0/k), τ = t + t0; slack if λ̃ ≥ 0, else τ̂ = −λ̃ / (1/k + 1/l).
    let t0 = link.prestress;
    let tau = t + t0;
    let lambda = -(tau / l + e + t0 / k);
    let (tau_hat, slack) = if lambda >= 0.0 {
        (0.0, true)
    } else {
        (-lambda / (1.0 / k + 1.0 / l), false)
    };
    let t_hat = tau_hat - t0;
    let e_hat = e - (t_hat - t) / l;
    (e_hat, t_hat, slack)
}

/// `(ê, t̂, slack)` of one link on the law linearised at its status (docs/method.md §9): a bar
/// or a cable taut in the status is elastic both ways (`t̂ = k ê`), a cable slack in it
/// carries no tension (`τ̂ = t0 + t̂ = 0`, any ê); along the search direction l.
pub fn frozen_link_local_stage(
    link: &Link,
    l: f64,
    e: f64,
    t: f64,
    slack: bool,
) -> (f64, f64, bool) {
    if !slack {
        // ê = (l e + t)/(k + l), t̂ = k ê.
        let e_hat = (l * e + t) / (link.stiffness + l);
        return (e_hat, link.stiffness * e_hat, false);
    }
    // τ̂ = 0, and (t̂ − t) + l (ê − e) = 0.
    let t_hat = -link.prestress;
    (e - (t_hat - t) / l, t_hat, true)
}

/// The interface's two sides: micro parts by the explicit formulas, macro parts pass through.
pub(super) fn interface_local_stage(
    basis: &DMatrix<f64>,
    dm: f64,
    a: &mut SideState,
    b: &mut SideState,
) {
    // R Rᵀ v, the macro part of an interface field.
    let mut coefficients = vec![0.0; basis.ncols()];
    let mut project = |v: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; v.len()];
        gemv_transposed(&mut coefficients, basis, v, false);
        gemv(&mut out, basis, &coefficients, false);
        out
    };
    let (ua_macro, fa_macro) = (project(&a.u), project(&a.f));
    let (ub_macro, fb_macro) = (project(&b.u), project(&b.f));
    for r in 0..a.u.len() {
        let (ua, fa) = (a.u[r] - ua_macro[r], a.f[r] - fa_macro[r]);
        let (ub, fb) = (b.u[r] - ub_macro[r], b.f[r] - fb_macro[r]);
        // Û^m = ½[(U^m_a + U^m_b) − (F^m_a + F^m_b)/d_m] on both sides;
        // F̂^m_a = ½[(F^m_a − F^m_b) − d_m(U^m_a − U^m_b)] = −F̂^m_b.
        let u_hat = 0.5 * ((ua + ub) - (fa + fb) / dm);
        let f_hat_a = 0.5 * ((fa - fb) - dm * (ua - ub));
        a.u_hat[r] = ua_macro[r] + u_hat;
        b.u_hat[r] = ub_macro[r] + u_hat;
        a.f_hat[r] = fa_macro[r] + f_hat_a;
        b.f_hat[r] = fb_macro[r] - f_hat_a;
        a.hat_load[r] = f_hat_a + dm * u_hat;
        b.hat_load[r] = -f_hat_a + dm * u_hat;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::macro_basis::orthonormal_columns;
    use crate::structure::LinkKind;

    /// A link 0 → 1 along x of stiffness `k` and prestress `t0`.
    fn link(kind: LinkKind, k: f64, t0: f64, unilateral: bool) -> Link {
        Link {
            id: 0,
            a: 0,
            b: 1,
            kind,
            module: 0,
            direction: [1.0, 0.0, 0.0],
            length: 1.0,
            stiffness: k,
            prestress: t0,
            unilateral,
            rest_change: 0.0,
            mass: 0.0,
        }
    }

    /// Deterministic pseudo-random numbers in [−1, 1) (xorshift64*).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
            2.0 * (bits as f64 / (1u64 << 53) as f64) - 1.0
        }

        fn vec(&mut self, n: usize, scale: f64) -> Vec<f64> {
            (0..n).map(|_| scale * self.next()).collect()
        }
    }

    fn close(a: f64, b: f64, scale: f64) -> bool {
        (a - b).abs() <= 1e-12 * scale.max(1.0)
    }

    #[test]
    fn bar_local_stage_is_on_the_law_and_the_search_direction() {
        let (k, t0) = (3.0e6, -4500.0);
        let bar = link(LinkKind::Bar, k, t0, false);
        for (l, e, t) in [
            (k, 1e-3, 250.0),
            (0.3 * k, -2e-4, 4000.0),
            (7.0 * k, 0.0, -900.0),
        ] {
            let (e_hat, t_hat, slack) = link_local_stage(&bar, l, e, t);
            assert!(!slack, "a bar is never slack");
            // Law of a bar on the additional tension: t̂ = k ê (the prestress plays no part).
            assert!(
                close(t_hat, k * e_hat, t_hat.abs()),
                "t̂ = {t_hat}, k ê = {}",
                k * e_hat
            );
            // Search direction: (t̂ − t) + l (ê − e) = 0.
            let d = (t_hat - t) + l * (e_hat - e);
            assert!(
                d.abs() <= 1e-12 * (t.abs() + l * e.abs()),
                "off the search direction: {d}"
            );
        }
        // A bilateral cable (the linear case) behaves as a bar, even in compression.
        let cable = link(LinkKind::Cable, k, 2000.0, false);
        let (e_hat, t_hat, slack) = link_local_stage(&cable, k, -0.01, -5000.0);
        assert!(!slack);
        assert!(close(t_hat, k * e_hat, t_hat.abs()));
        assert!(
            t_hat + 2000.0 < 0.0,
            "a bilateral cable may carry compression"
        );
    }

    /// Checks the unilateral law and the search direction on one local-stage result, and
    /// returns whether it is slack.
    fn check_cable(k: f64, t0: f64, l: f64, e: f64, t: f64) -> bool {
        let cable = link(LinkKind::Cable, k, t0, true);
        let (e_hat, t_hat, slack) = link_local_stage(&cable, l, e, t);
        let scale = t.abs() + t0.abs() + l * e.abs();
        // Search direction: (t̂ − t) + l (ê − e) = 0.
        let d = (t_hat - t) + l * (e_hat - e);
        assert!(d.abs() <= 1e-12 * scale, "off the search direction: {d}");
        // Total tension τ̂ = t0 + t̂ and gap λ̂ = −ê + t̂/k (docs/method.md §1): 0 ≤ τ̂ ⊥ λ̂ ≥ 0.
        let tau_hat = t0 + t_hat;
        let gap = -e_hat + t_hat / k;
        if slack {
            assert_eq!(tau_hat, 0.0, "slack: τ̂ = 0 exactly");
            // λ̂ = −ê − t0/k ≥ 0, i.e. ê ≤ −t0/k: the cable is shorter than its rest length.
            assert!(gap >= 0.0, "slack with a negative gap λ̂ = {gap}");
            assert!(e_hat <= -t0 / k);
        } else {
            // Taut: τ̂ = t0 + k ê ≥ 0 and λ̂ = 0.
            assert!(tau_hat >= 0.0, "taut in compression: τ̂ = {tau_hat}");
            assert!(close(tau_hat, t0 + k * e_hat, scale), "τ̂ ≠ t0 + k ê");
            assert!(
                gap.abs() <= 1e-12 * (scale / k),
                "taut with a gap λ̂ = {gap}"
            );
        }
        slack
    }

    #[test]
    fn cable_local_stage_taut_and_slack() {
        let (k, t0, l) = (1.0e5, 2000.0, 2.0e5);
        // Taut: a small extension of a prestressed cable.
        assert!(!check_cable(k, t0, l, 0.01, 500.0));
        // Taut although s is in compression (τ = −500 N) but ê is long enough.
        assert!(!check_cable(k, t0, l, 0.0, -2500.0));
        // Slack: shortened by more than t0/k = 0.02 m, with some tension left in s.
        assert!(check_cable(k, t0, l, -0.05, -1500.0));
        // Slack: an unprestressed cable (t0 = 0) in compression.
        assert!(check_cable(k, 0.0, k, -1e-3, -50.0));
        // Many inputs on both sides of the switch, with l ≠ k.
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let (mut taut, mut slack) = (0, 0);
        for _ in 0..2000 {
            let l = k * 10f64.powf(2.0 * rng.next());
            let e = 0.05 * rng.next();
            let t = 4000.0 * rng.next();
            if check_cable(k, t0, l, e, t) {
                slack += 1;
            } else {
                taut += 1;
            }
        }
        assert!(
            taut > 100 && slack > 100,
            "both regimes: {taut} taut, {slack} slack"
        );
    }

    #[test]
    fn cable_local_stage_switches_at_zero_tension() {
        // With l = k the taut candidate is τ̂ = ½ (τ + t0 + k e): slack iff τ + t0 + k e ≤ 0.
        let (k, t0) = (1.0e5, 2000.0);
        let cable = link(LinkKind::Cable, k, t0, true);
        let (_, t_hat, slack) = link_local_stage(&cable, k, -0.03, 999.0);
        assert!(!slack);
        assert!(close(t0 + t_hat, 0.5 * (2999.0 + 2000.0 - 3000.0), 1e4));
        let (_, t_hat, slack) = link_local_stage(&cable, k, -0.03, 1000.0 - 2000.0 - 1.0);
        assert!(slack);
        assert_eq!(t_hat, -t0);
    }

    #[test]
    fn frozen_local_stage_is_on_the_linearised_law_and_the_search_direction() {
        let (k, t0) = (1.0e5, 2000.0);
        let cable = link(LinkKind::Cable, k, t0, true);
        let mut rng = Rng(11);
        for _ in 0..500 {
            let l = k * 10f64.powf(2.0 * rng.next());
            let (e, t) = (0.05 * rng.next(), 4000.0 * rng.next());
            let scale = t.abs() + t0.abs() + l * e.abs();
            for slack in [false, true] {
                let (e_hat, t_hat, flagged) = frozen_link_local_stage(&cable, l, e, t, slack);
                assert_eq!(flagged, slack);
                let d = (t_hat - t) + l * (e_hat - e);
                assert!(d.abs() <= 1e-12 * scale, "off the search direction: {d}");
                if slack {
                    assert_eq!(t0 + t_hat, 0.0, "slack in the status: no tension");
                } else {
                    // Taut in the status: t̂ = k ê even in compression (τ̂ < 0 allowed).
                    assert!(close(t_hat, k * e_hat, scale));
                }
            }
            // Where the exact law is taut, the taut linearisation agrees with it.
            let exact = link_local_stage(&cable, l, e, t);
            if !exact.2 {
                let frozen = frozen_link_local_stage(&cable, l, e, t, false);
                assert!(close(exact.0, frozen.0, 1e-6) && close(exact.1, frozen.1, scale));
            }
        }
    }

    fn side(rng: &mut Rng, n: usize) -> SideState {
        SideState {
            u: rng.vec(n, 1e-3),
            f: rng.vec(n, 1e3),
            u_hat: rng.vec(n, 1.0),
            f_hat: rng.vec(n, 1.0),
            hat_load: rng.vec(n, 1.0),
        }
    }

    fn apply(m: &DMatrix<f64>, v: &[f64]) -> Vec<f64> {
        (m * nalgebra::DVector::from_column_slice(v))
            .iter()
            .copied()
            .collect()
    }

    #[test]
    fn interface_local_stage_micro_continuity_macro_pass_through() {
        let (n, dm) = (6, 3.92e6);
        let mut rng = Rng(42);
        let basis = orthonormal_columns(&[rng.vec(n, 1.0), rng.vec(n, 1.0)], n);
        assert_eq!(basis.ncols(), 2);
        let macro_part = &basis * basis.transpose();
        let micro_part = DMatrix::<f64>::identity(n, n) - &macro_part;
        for _ in 0..20 {
            let (mut a, mut b) = (side(&mut rng, n), side(&mut rng, n));
            let (a0, b0) = (a.clone(), b.clone());
            interface_local_stage(&basis, dm, &mut a, &mut b);
            let (u_tol, f_tol) = (1e-15, 1e-9);
            let near =
                |x: &[f64], y: &[f64], tol: f64| x.iter().zip(y).all(|(p, q)| (p - q).abs() <= tol);
            // Micro parts: Û^m equal on both sides, F̂^m opposite.
            let (ua_m, ub_m) = (apply(&micro_part, &a.u_hat), apply(&micro_part, &b.u_hat));
            assert!(near(&ua_m, &ub_m, u_tol), "Û^m differs: {ua_m:?} {ub_m:?}");
            let (fa_m, fb_m) = (apply(&micro_part, &a.f_hat), apply(&micro_part, &b.f_hat));
            let minus_fb: Vec<f64> = fb_m.iter().map(|x| -x).collect();
            assert!(near(&fa_m, &minus_fb, f_tol), "F̂^m not opposite");
            for (s, s0, u_m, f_m) in [(&a, &a0, &ua_m, &fa_m), (&b, &b0, &ub_m, &fb_m)] {
                // Macro parts pass through: R Rᵀ Û = R Rᵀ U, R Rᵀ F̂ = R Rᵀ F.
                let (uh_mac, u_mac) = (apply(&macro_part, &s.u_hat), apply(&macro_part, &s0.u));
                assert!(near(&uh_mac, &u_mac, u_tol), "macro Û ≠ macro U");
                let (fh_mac, f_mac) = (apply(&macro_part, &s.f_hat), apply(&macro_part, &s0.f));
                assert!(near(&fh_mac, &f_mac, f_tol), "macro F̂ ≠ macro F");
                // s is untouched.
                assert_eq!((&s.u, &s.f), (&s0.u, &s0.f));
                // The load on the substructure: F̂^m + d_m Û^m.
                let load: Vec<f64> = f_m.iter().zip(u_m).map(|(f, u)| f + dm * u).collect();
                assert!(near(&s.hat_load, &load, f_tol), "hat_load ≠ F̂^m + d_m Û^m");
                // Ascent search direction on the micro parts: F̂^m − F^m = d_m (Û^m − U^m).
                let u0_m = apply(&micro_part, &s0.u);
                let f0_m = apply(&micro_part, &s0.f);
                for r in 0..n {
                    let d = (f_m[r] - f0_m[r]) - dm * (u_m[r] - u0_m[r]);
                    assert!(d.abs() <= f_tol, "off the interface search direction: {d}");
                }
            }
        }
    }

    #[test]
    fn interface_local_stage_all_macro_and_all_micro() {
        let (n, dm) = (3, 3.92e6);
        let mut rng = Rng(7);
        // All-macro (R = I): ŝ = s on each side, no micro load.
        let (mut a, mut b) = (side(&mut rng, n), side(&mut rng, n));
        interface_local_stage(&DMatrix::identity(n, n), dm, &mut a, &mut b);
        for s in [&a, &b] {
            for r in 0..n {
                assert!((s.u_hat[r] - s.u[r]).abs() <= 1e-18);
                assert!((s.f_hat[r] - s.f[r]).abs() <= 1e-12);
                assert!(s.hat_load[r].abs() <= 1e-12);
            }
        }
        // All-micro (no columns): Û equal, F̂ opposite, and the explicit formulas.
        let (mut a, mut b) = (side(&mut rng, n), side(&mut rng, n));
        interface_local_stage(&DMatrix::zeros(n, 0), dm, &mut a, &mut b);
        for r in 0..n {
            let u = 0.5 * ((a.u[r] + b.u[r]) - (a.f[r] + b.f[r]) / dm);
            let f = 0.5 * ((a.f[r] - b.f[r]) - dm * (a.u[r] - b.u[r]));
            assert!((a.u_hat[r] - u).abs() <= 1e-18 && (b.u_hat[r] - u).abs() <= 1e-18);
            assert!((a.f_hat[r] - f).abs() <= 1e-9 && (b.f_hat[r] + f).abs() <= 1e-9);
        }
    }
}
