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
