//! Which substructure owns each free dof, and which dofs several substructures share: what
//! r(U) sums across substructures and what neighbouring ranks send each other.

use super::Substructure;
use crate::linalg::buckets;

/// Which substructure owns each free dof (the first of those holding it) and, per
/// substructure, its dofs held by others too (in its local order): what r(U) sums across
/// substructures, and across ranks.
pub(super) struct DofOwnership {
    /// Per free dof, its owner.
    pub(super) owner: Vec<u32>,
    /// Per free dof held by more than one substructure, its slot among those dofs
    /// ([`NOT_SHARED`] for the others).
    pub(super) shared_slot: Vec<u32>,
    /// How many free dofs are shared.
    pub(super) n_shared: usize,
    /// Per substructure, the local indices of its shared dofs.
    pub(super) shared_local: Vec<Vec<u32>>,
    /// Per free dof, its local index in its owner.
    owner_local: Vec<u32>,
    /// Per shared dof (by slot), where its holders other than the owner start in
    /// `other_holders` (one more entry than slots).
    other_start: Vec<usize>,
    /// The holders of shared dofs other than their owners, `(substructure, local index)`, in
    /// the substructures' order.
    other_holders: Vec<(u32, u32)>,
}

/// [`DofOwnership::shared_slot`] of a dof only one substructure holds.
pub(super) const NOT_SHARED: u32 = u32::MAX;

impl DofOwnership {
    /// Whether substructure `e` owns free dof `d` (the first of those holding it).
    pub(super) fn owns(&self, e: usize, d: usize) -> bool {
        self.owner[d] as usize == e
    }

    /// The slot of a shared free dof `d` among the shared dofs.
    pub(super) fn slot(&self, d: usize) -> usize {
        self.shared_slot[d] as usize
    }

    /// The mean of a free dof's values in the substructures holding it,
    /// `(0 + v_1 + v_2 + …) / count` in the substructures' order (0 where none holds it);
    /// `value(e, local)` reads substructure e's value.
    pub(super) fn mean(&self, d: usize, value: impl Fn(usize, usize) -> f64) -> f64 {
        let e = self.owner[d];
        if e == u32::MAX {
            return 0.0;
        }
        let mut sum = 0.0 + value(e as usize, self.owner_local[d] as usize);
        let slot = self.shared_slot[d];
        if slot == NOT_SHARED {
            return sum;
        }
        let range = self.other_start[slot as usize]..self.other_start[slot as usize + 1];
        for &(e, local) in &self.other_holders[range.clone()] {
            sum += value(e as usize, local as usize);
        }
        sum / (1 + range.len()) as f64
    }

    pub(super) fn of(subs: &[Substructure], n_free: usize) -> DofOwnership {
        let mut owner = vec![u32::MAX; n_free];
        let mut owner_local = vec![0u32; n_free];
        let mut holders = vec![0u8; n_free];
        for (e, sub) in subs.iter().enumerate() {
            for (local, &d) in sub.dof_global.iter().enumerate() {
                if owner[d] == u32::MAX {
                    owner[d] = e as u32;
                    owner_local[d] = local as u32;
                }
                holders[d] = holders[d].saturating_add(1);
            }
        }
        let mut n_shared = 0;
        let shared_slot: Vec<u32> = holders
            .iter()
            .map(|&h| match h > 1 {
                true => {
                    n_shared += 1;
                    (n_shared - 1) as u32
                }
                false => NOT_SHARED,
            })
            .collect();
        let shared_local = subs
            .iter()
            .map(|sub| {
                (0..sub.dof_global.len() as u32)
                    .filter(|&k| shared_slot[sub.dof_global[k as usize]] != NOT_SHARED)
                    .collect()
            })
            .collect();
        let (other_start, other_holders) = other_holders(subs, &owner, &shared_slot, n_shared);
        DofOwnership {
            owner,
            shared_slot,
            n_shared,
            shared_local,
            owner_local,
            other_start,
            other_holders,
        }
    }
}

/// Per shared slot, the holders of that dof other than its owner, in the substructures' order.
fn other_holders(
    subs: &[Substructure],
    owner: &[u32],
    shared_slot: &[u32],
    n_shared: usize,
) -> (Vec<usize>, Vec<(u32, u32)>) {
    buckets(n_shared, |emit| {
        for (e, sub) in subs.iter().enumerate() {
            for (local, &d) in sub.dof_global.iter().enumerate() {
                if shared_slot[d] != NOT_SHARED && owner[d] as usize != e {
                    emit(shared_slot[d] as usize, (e as u32, local as u32));
                }
            }
        }
    })
}
