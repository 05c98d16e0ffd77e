//! The member checks (issue 45): per member its stress, its utilisation against its design
//! strength, for a bar its Euler load and the utilisation of that (or, with a buckling curve,
//! of its buckling resistance by EN 1993-1-1 §6.3.1) by its compression, for a cable its slack
//! margin and, with a breaking load, its utilisation by EN 1993-1-11 §6.3; and the largest
//! utilisation of a solve with its member and the clause it comes from.

use super::eurocode::{cable_resistance, flexural_buckling, FlexuralBuckling};
use crate::model::Model;
use crate::solvers::Equilibrium;
use crate::structure::{LinkKind, MemberChecks, Structure};

/// Where a utilisation comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clause {
    /// `|σ| / f`, the design strength.
    Stress,
    /// A bar's compression over its Euler load `π² E I / ℓ²` (no buckling curve).
    Euler,
    /// A bar's compression over `N_b,Rd = χ A f_y / γ_M1` (EN 1993-1-1 §6.3.1).
    FlexuralBuckling,
    /// A cable's tension over `F_Rd = F_uk / (1.5 γ_R)` (EN 1993-1-11 §6.3).
    CableResistance,
}

impl Clause {
    /// Its name in `forces/`' `clause` column and `checks.csv`.
    pub fn name(self) -> &'static str {
        match self {
            Clause::Stress => "stress",
            Clause::Euler => "Euler",
            Clause::FlexuralBuckling => "EN 1993-1-1 6.3.1",
            Clause::CableResistance => "EN 1993-1-11 6.3",
        }
    }

    /// What the utilisation is of, in a sentence.
    pub fn resistance(self) -> &'static str {
        match self {
            Clause::Stress => "design strength",
            Clause::Euler => "Euler load (buckling)",
            Clause::FlexuralBuckling => "buckling resistance N_b,Rd (EN 1993-1-1 §6.3.1)",
            Clause::CableResistance => "design resistance F_Rd (EN 1993-1-11 §6.3)",
        }
    }
}

/// One member's checks at an answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemberCheck {
    /// Axial stress σ = τ / S, Pa (tension > 0).
    pub stress: f64,
    /// `|σ| / f` with the member's design strength f; `None` without one.
    pub utilisation: Option<f64>,
    /// A bar's Euler load `π² E I / ℓ²`, N, on the current length ℓ under `large` and the
    /// initial length otherwise; `None` for cables and bars without an inertia.
    pub euler_load: Option<f64>,
    /// A bar's compression (0 in tension) over its buckling resistance N_b,Rd with a buckling
    /// curve, over its Euler load without; `None` with no Euler load.
    pub buckling_utilisation: Option<f64>,
    /// A bar's flexural buckling by EN 1993-1-1 §6.3.1 (λ̄, χ, N_b,Rd), with a buckling curve.
    pub flexural: Option<FlexuralBuckling>,
    /// A cable's design resistance F_Rd (EN 1993-1-11 §6.3), N, with a breaking load.
    pub cable_resistance: Option<f64>,
    /// A cable's tension over F_Rd (0 slack), with a breaking load.
    pub cable_utilisation: Option<f64>,
    /// A cable's tension over its given prestress t0 (1 at the prestressed state, 0 slack);
    /// `None` for bars and cables without prestress.
    pub slack_margin: Option<f64>,
}

impl MemberCheck {
    /// The member's largest utilisation (strength, buckling, cable resistance), when it has
    /// one, and its clause (the first of these on a tie).
    pub fn governing(&self) -> Option<(f64, Clause)> {
        let buckling = match self.flexural {
            Some(_) => Clause::FlexuralBuckling,
            None => Clause::Euler,
        };
        [
            (self.utilisation, Clause::Stress),
            (self.buckling_utilisation, buckling),
            (self.cable_utilisation, Clause::CableResistance),
        ]
        .into_iter()
        .filter_map(|(u, clause)| u.map(|u| (u, clause)))
        .fold(
            None,
            |worst: Option<(f64, Clause)>, (u, clause)| match worst {
                Some((w, _)) if w >= u => worst,
                _ => Some((u, clause)),
            },
        )
    }
}

/// The checks of link `i` of `s` (data `checks`) carrying `tension` at length `length`.
pub fn member_check(
    s: &Structure,
    checks: &MemberChecks,
    i: usize,
    tension: f64,
    length: f64,
) -> MemberCheck {
    let l = &s.links[i];
    let data = checks.of(i, l.kind);
    let stress = tension / data.section;
    let euler_load = match l.kind {
        LinkKind::Bar => data
            .inertia
            .map(|inertia| std::f64::consts::PI.powi(2) * data.young * inertia / (length * length)),
        LinkKind::Cable => None,
    };
    let prestress = s.self_stress(l);
    // EN 1993-1-1 §6.3.1 on a bar with a buckling curve (its strength f_y, its Euler load N_cr).
    let flexural = match (data.buckling, data.strength, euler_load) {
        (Some(b), Some(f_y), Some(n_cr)) if l.kind == LinkKind::Bar => Some(flexural_buckling(
            data.section,
            f_y,
            n_cr,
            b.curve,
            b.gamma_m1,
        )),
        _ => None,
    };
    let buckling_resistance = flexural.map(|f| f.resistance).or(euler_load);
    let cable_resistance = data
        .breaking
        .filter(|_| l.kind.is_cable())
        .map(|c| cable_resistance(c.load, c.gamma_r));
    MemberCheck {
        stress,
        utilisation: data.strength.map(|f| stress.abs() / f),
        euler_load,
        buckling_utilisation: buckling_resistance.map(|p| (-tension).max(0.0) / p),
        flexural,
        cable_resistance,
        cable_utilisation: cable_resistance.map(|r| tension.max(0.0) / r),
        slack_margin: (l.kind.is_cable() && prestress > 0.0).then(|| tension / prestress),
    }
}

/// Every member's checks at the answer `eq` of `model`, in link order; `None` when the case
/// gives no strength and no inertia. The Euler load is on the current length under `large`
/// (the deformed geometry), on the initial length under `linear` and `prestress`.
pub fn member_checks(model: &Model, eq: &Equilibrium) -> Option<Vec<MemberCheck>> {
    let s = &model.structure;
    let checks = s.checks.as_ref()?;
    let current = model.current_lengths(&eq.displacements);
    Some(
        (0..s.links.len())
            .map(|i| {
                let length = current.as_ref().map_or(s.links[i].length, |c| c[i]);
                member_check(s, checks, i, eq.tensions[i], length)
            })
            .collect(),
    )
}

/// The largest utilisation of a solve and its member.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Governing {
    /// The largest of the members' utilisations (strength, buckling, cable resistance).
    pub utilisation: f64,
    /// The member it belongs to (its id).
    pub member: u64,
    /// The check it comes from.
    pub clause: Clause,
    /// How many members have a utilisation above 1.
    pub over: usize,
}

/// The largest utilisation at the answer `eq` of `model`; `None` when no member is checked.
pub fn governing(model: &Model, eq: &Equilibrium) -> Option<Governing> {
    let checks = member_checks(model, eq)?;
    let mut worst: Option<Governing> = None;
    let mut over = 0;
    for (i, check) in checks.iter().enumerate() {
        let Some((utilisation, clause)) = check.governing() else {
            continue;
        };
        over += usize::from(utilisation > 1.0);
        if worst.is_none_or(|w| utilisation > w.utilisation) {
            worst = Some(Governing {
                utilisation,
                member: model.structure.links[i].id,
                clause,
                over: 0,
            });
        }
    }
    worst.map(|w| Governing { over, ..w })
}
