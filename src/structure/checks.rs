//! What the member checks (issue 45) read of each member: its Young's modulus and section,
//! and the design strength and second moment of area the case may give. Held apart from the
//! members, so that a case without checks keeps no more per link than before.

use super::LinkKind;

/// One member's data for the checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckedMember {
    /// Young's modulus E, Pa.
    pub young: f64,
    /// Cross-section S, m².
    pub section: f64,
    /// Design strength f, Pa (`strength`): the stress utilisation `|σ| / f`; `None`: not
    /// checked.
    pub strength: Option<f64>,
    /// Second moment of area I, m⁴ (`inertia`, bars): the Euler load `π² E I / ℓ²`; `None`:
    /// not checked.
    pub inertia: Option<f64>,
    /// A bar's flexural buckling by EN 1993-1-1 §6.3.1 (`buckling_curve`), its strength read
    /// as f_y; `None`: against the Euler load alone.
    pub buckling: Option<Buckling>,
    /// A cable's resistance by EN 1993-1-11 §6.3 (`breaking_load`); `None`: not checked.
    pub breaking: Option<CableBreaking>,
}

impl CheckedMember {
    /// The data of a member of modulus `young` and section `section` with no check.
    pub fn unchecked(young: f64, section: f64) -> CheckedMember {
        CheckedMember {
            young,
            section,
            strength: None,
            inertia: None,
            buckling: None,
            breaking: None,
        }
    }

    /// Whether any check is asked of it.
    pub fn is_checked(&self) -> bool {
        self.strength.is_some()
            || self.inertia.is_some()
            || self.buckling.is_some()
            || self.breaking.is_some()
    }

    /// Whether a check of EN 1993 is asked of it (a buckling curve or a breaking load).
    pub fn is_eurocode(&self) -> bool {
        self.buckling.is_some() || self.breaking.is_some()
    }
}

/// EN 1993-1-1 Table 6.1's buckling curves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BucklingCurve {
    /// Curve a0: imperfection factor 0.13.
    A0,
    /// Curve a: 0.21.
    A,
    /// Curve b: 0.34.
    B,
    /// Curve c: 0.49.
    C,
    /// Curve d: 0.76.
    D,
}

impl BucklingCurve {
    /// Every curve, in the table's order.
    pub const ALL: [BucklingCurve; 5] = [
        BucklingCurve::A0,
        BucklingCurve::A,
        BucklingCurve::B,
        BucklingCurve::C,
        BucklingCurve::D,
    ];

    /// The imperfection factor α of EN 1993-1-1 Table 6.1.
    pub fn imperfection(self) -> f64 {
        match self {
            BucklingCurve::A0 => 0.13,
            BucklingCurve::A => 0.21,
            BucklingCurve::B => 0.34,
            BucklingCurve::C => 0.49,
            BucklingCurve::D => 0.76,
        }
    }

    /// Its name in a case and a table: `a0`, `a`, `b`, `c`, `d`.
    pub fn name(self) -> &'static str {
        match self {
            BucklingCurve::A0 => "a0",
            BucklingCurve::A => "a",
            BucklingCurve::B => "b",
            BucklingCurve::C => "c",
            BucklingCurve::D => "d",
        }
    }

    /// The curve named `name`, if any.
    pub fn from_name(name: &str) -> Option<BucklingCurve> {
        BucklingCurve::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// A bar's flexural buckling check (EN 1993-1-1 §6.3.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Buckling {
    /// Its buckling curve.
    pub curve: BucklingCurve,
    /// The partial factor γ_M1 (`checks.gamma_m1`).
    pub gamma_m1: f64,
}

/// A cable's resistance check (EN 1993-1-11 §6.3): `F_Rd = F_uk / (1.5 γ_R)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableBreaking {
    /// The characteristic breaking load F_uk, N.
    pub load: f64,
    /// The partial factor γ_R (`checks.gamma_r`).
    pub gamma_r: f64,
}

/// The members' data for the checks: per member kind (a grid's `bars.*`, `cables.*`), or per
/// member in link order (a members table's `strength` and `inertia` columns).
#[derive(Debug, Clone, PartialEq)]
pub enum MemberChecks {
    /// Every bar alike, every cable alike.
    Kinds {
        /// The bars' data.
        bars: CheckedMember,
        /// The cables' data.
        cables: CheckedMember,
    },
    /// One entry per member, in link order.
    Each(Vec<CheckedMember>),
}

impl MemberChecks {
    /// The data of link `i`, of kind `kind`.
    pub fn of(&self, i: usize, kind: LinkKind) -> CheckedMember {
        match self {
            MemberChecks::Kinds { bars, cables } => match kind {
                LinkKind::Bar => *bars,
                LinkKind::Cable => *cables,
            },
            MemberChecks::Each(each) => each[i],
        }
    }

    /// Whether any member asks for a check of EN 1993 (a buckling curve, a breaking load).
    pub fn any_eurocode(&self) -> bool {
        match self {
            MemberChecks::Kinds { bars, cables } => bars.is_eurocode() || cables.is_eurocode(),
            MemberChecks::Each(each) => each.iter().any(CheckedMember::is_eurocode),
        }
    }

    /// The checks of the links `links` (indices into this one's), in that order.
    pub fn keeping(&self, links: &[usize]) -> MemberChecks {
        match self {
            MemberChecks::Kinds { .. } => self.clone(),
            MemberChecks::Each(each) => {
                MemberChecks::Each(links.iter().map(|&i| each[i]).collect())
            }
        }
    }
}
