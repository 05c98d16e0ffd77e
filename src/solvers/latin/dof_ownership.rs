//! Which substructure owns each free dof, and which dofs several substructures share: what
//! r(U) sums across substructures and what neighbouring ranks send each other.

use super::Substructure;

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

    pub(super) fn of(subs: &[Substructure], n_free: usize) -> DofOwnership {
        let mut owner = vec![u32::MAX; n_free];
        let mut holders = vec![0u8; n_free];
        for (e, sub) in subs.iter().enumerate() {
            for &d in &sub.dof_global {
                if owner[d] == u32::MAX {
                    owner[d] = e as u32;
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
        DofOwnership {
            owner,
            shared_slot,
            n_shared,
            shared_local,
        }
    }
}
