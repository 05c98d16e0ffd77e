//! A structure as an engineer describes it (docs/method.md §7): nodes with ids, members between them,
//! supports per node and direction, and loads per node. The module grid is one generator of
//! this description ([`super::grid`]); a case's `[structure]` tables are another.

use super::{GridRole, LinkKind};

/// One bar or cable as described.
#[derive(Debug, Clone, PartialEq)]
pub struct Member {
    /// The member's id as the user knows it (the CSV's `member`; the link index for grids).
    pub id: u64,
    /// Start node (index into [`Geometry::nodes`]).
    pub a: usize,
    /// End node.
    pub b: usize,
    /// Bar or cable.
    pub kind: LinkKind,
    /// Young's modulus E, Pa.
    pub young: f64,
    /// Cross-section S, m².
    pub section: f64,
    /// Prestress t0, N (tension positive).
    pub prestress: f64,
    /// Density ρ, kg/m³ (for self-weight; 0 when not given).
    pub density: f64,
    /// The module the member belongs to on a grid; 0 for general structures.
    pub module: usize,
}

/// Nodes and members.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// The node ids as the user knows them (the CSV's `node`; the index for grids).
    pub node_ids: Vec<u64>,
    /// Initial positions, m.
    pub nodes: Vec<[f64; 3]>,
    /// Bars and cables.
    pub members: Vec<Member>,
    /// Whether cables carry tension only.
    pub unilateral: bool,
    /// Per member, its role in its module when the geometry is a generated module grid
    /// ([`super::Structure::grid_parts`]); `None` for tables.
    pub grid_roles: Option<Vec<GridRole>>,
    /// The members' data for the member checks, when the case gives a strength or an inertia
    /// (kept after [`Geometry::release_members`]: a grid's is two entries).
    pub checks: Option<super::MemberChecks>,
    /// Per member, its group label (the members table's `group` column); `None` without it.
    pub groups: Option<Vec<String>>,
}

/// A member whose section's equivalent diameter reaches this fraction of its length is named
/// by `check` ([`Geometry::thickest_member`]): a third (a strut of length/diameter 3; cm²
/// for m² makes a 2.8e-4 m² strut 1.9 m across).
pub const STOCKIEST: f64 = 1.0 / 3.0;

impl Geometry {
    /// The member whose section is widest against its length, when its equivalent diameter
    /// `√(4S/π)` reaches `STOCKIEST` (a third) of its length: its id, section (m²), diameter and length
    /// (m). No member of a tension structure is that stocky: such a section is a unit slip (mm²
    /// or cm² for m²: issue 57, N-D7, sections of 523 and 100 passed `check` silently).
    pub fn thickest_member(&self) -> Option<(u64, f64, f64, f64)> {
        self.members
            .iter()
            .map(|m| {
                let (length, _) = super::length_and_direction(self.nodes[m.a], self.nodes[m.b]);
                let diameter = (4.0 * m.section / std::f64::consts::PI).sqrt();
                (m.id, m.section, diameter, length)
            })
            .filter(|&(_, _, d, l)| d >= STOCKIEST * l)
            .max_by(|a, b| (a.2 / a.3).total_cmp(&(b.2 / b.3)))
    }

    /// Drop the members (and their grid roles), once a structure has been built of them: a
    /// run keeps its structure, not the description it was built from.
    pub fn release_members(&mut self) {
        self.members = Vec::new();
        self.grid_roles = None;
        self.groups = None;
    }

    /// Member `j`'s initial length, m.
    pub fn member_length(&self, j: usize) -> f64 {
        let m = &self.members[j];
        length_and_direction(self.nodes[m.a], self.nodes[m.b]).0
    }

    /// Per member, its group (issue 46): the `group` column's label, a grid member's kind
    /// (its role in its module), else the member's own id, each member its own group.
    pub fn member_groups(&self) -> Vec<String> {
        match (&self.groups, &self.grid_roles) {
            (Some(groups), _) => groups.clone(),
            (None, Some(roles)) => roles.iter().map(|r| r.name().to_string()).collect(),
            (None, None) => self.members.iter().map(|m| m.id.to_string()).collect(),
        }
    }
}

/// Displacement components of one node held at prescribed values (`U|Γu = Ud`, docs/method.md §7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeFix {
    /// The node (index into [`Geometry::nodes`]).
    pub node: usize,
    /// Which of x, y, z are prescribed.
    pub dofs: [bool; 3],
    /// The prescribed displacement of those components, m (never scaled by α).
    pub displacement: [f64; 3],
}

impl NodeFix {
    /// `fixes` holding the same components at zero: the same free dofs, without the tensions
    /// settlements impose (for the given prestress t0 alone).
    pub fn unsettled(fixes: &[NodeFix]) -> Vec<NodeFix> {
        fixes
            .iter()
            .map(|f| NodeFix {
                displacement: [0.0; 3],
                ..*f
            })
            .collect()
    }
}

/// What loads the structure at α = 1.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Loading {
    /// The same force on every node's free components, N (`load.nodal`).
    pub nodal: [f64; 3],
    /// Forces on given nodes, N (`load.point`), summed.
    pub points: Vec<(usize, [f64; 3])>,
    /// Gravity acceleration, m/s², for self-weight (`load.self_weight`): a member of mass
    /// `ρ S ℓ` puts `ρ S ℓ g / 2` on each end (docs/method.md §7).
    pub gravity: Option<[f64; 3]>,
    /// Changes Δℓ0 of members' rest lengths, m (member index, change; actuation and
    /// temperature, `load.rest_length_change`, `load.temperature`): the member's law becomes
    /// `τ = t0 − k Δℓ0 + k e` in every model, never scaled by α.
    pub rest_length_changes: Vec<(usize, f64)>,
}

impl Loading {
    /// Δℓ0 of each of `members` members, m (0 where none is given; entries add up).
    pub fn rest_length_change_of(&self, members: usize) -> Vec<f64> {
        let mut change = vec![0.0; members];
        for &(j, c) in &self.rest_length_changes {
            change[j] += c;
        }
        change
    }
}

/// Length ℓ of the segment from `xa` to `xb` and its unit direction.
pub fn length_and_direction(xa: [f64; 3], xb: [f64; 3]) -> (f64, [f64; 3]) {
    let d = [xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]];
    let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    (length, [d[0] / length, d[1] / length, d[2] / length])
}

/// Two unit vectors orthogonal to the unit vector n and to each other: `I − n nᵀ = p pᵀ + q qᵀ`.
pub fn transverse_pair(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    // Cross with the axis n is least aligned with.
    let axis = (0..3)
        .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[axis] = 1.0;
    let p = normalised(cross(n, e));
    (p, cross(n, p))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalised(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transverse_pair_completes_an_orthonormal_basis() {
        for n in [
            [1.0, 0.0, 0.0],
            [0.0, 0.6, 0.8],
            normalised([1.0, -2.0, 0.5]),
        ] {
            let (p, q) = transverse_pair(n);
            let d = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            for (a, b, want) in [
                (p, p, 1.0),
                (q, q, 1.0),
                (p, q, 0.0),
                (p, n, 0.0),
                (q, n, 0.0),
            ] {
                assert!((d(a, b) - want).abs() < 1e-14, "{a:?}·{b:?}");
            }
        }
    }
}
