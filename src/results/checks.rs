//! The member checks (issue 45): per member its stress, its utilisation against its design
//! strength, for a bar its Euler load and the utilisation of that by its compression, for a
//! cable its slack margin; and the largest utilisation of a solve with its member.

use crate::model::Model;
use crate::solvers::Equilibrium;
use crate::structure::{LinkKind, MemberChecks, Structure};

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
    /// A bar's compression over its Euler load (0 in tension); `None` with no Euler load.
    pub buckling_utilisation: Option<f64>,
    /// A cable's tension over its given prestress t0 (1 at the prestressed state, 0 slack);
    /// `None` for bars and cables without prestress.
    pub slack_margin: Option<f64>,
}

impl MemberCheck {
    /// The member's larger utilisation (strength or buckling), when it has one, and whether
    /// it is the buckling one.
    pub fn governing(&self) -> Option<(f64, bool)> {
        match (self.utilisation, self.buckling_utilisation) {
            (Some(u), Some(b)) if b > u => Some((b, true)),
            (Some(u), _) => Some((u, false)),
            (None, Some(b)) => Some((b, true)),
            (None, None) => None,
        }
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
    let prestress = s.given_prestress(l);
    MemberCheck {
        stress,
        utilisation: data.strength.map(|f| stress.abs() / f),
        euler_load,
        buckling_utilisation: euler_load.map(|p| (-tension).max(0.0) / p),
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
    /// The largest of the members' utilisations (strength and buckling).
    pub utilisation: f64,
    /// The member it belongs to (its id).
    pub member: u64,
    /// It is the buckling utilisation (else the strength one).
    pub buckling: bool,
    /// How many members have a utilisation above 1.
    pub over: usize,
}

/// The largest utilisation at the answer `eq` of `model`; `None` when no member is checked.
pub fn governing(model: &Model, eq: &Equilibrium) -> Option<Governing> {
    let checks = member_checks(model, eq)?;
    let mut worst: Option<Governing> = None;
    let mut over = 0;
    for (i, check) in checks.iter().enumerate() {
        let Some((utilisation, buckling)) = check.governing() else {
            continue;
        };
        over += usize::from(utilisation > 1.0);
        if worst.is_none_or(|w| utilisation > w.utilisation) {
            worst = Some(Governing {
                utilisation,
                member: model.structure.links[i].id,
                buckling,
                over: 0,
            });
        }
    }
    worst.map(|w| Governing { over, ..w })
}
