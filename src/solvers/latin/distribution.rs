//! The distribution of a LATIN solve across processes: which substructures this one holds,
//! who owns each dof, what passes point to point, and the collective operations. The one value
//! a solve asks where a step runs on, gathers from or sends to other ranks; its fields are read
//! here only.

use super::dof_ownership::DofOwnership;
use super::neighbours::NeighbourPlan;
use crate::decomposition::Exchange;
use std::ops::Range;

/// The processes sharing a solve and what this one holds.
pub(super) struct Distribution<'s> {
    /// The processes sharing the solve (`OneProcess` unless set up by `Latin::on_ranks`).
    exchange: &'s dyn Exchange,
    /// The substructures this process holds (their operators, their halves of the linear
    /// stage): all of them on one process.
    held: Range<usize>,
    /// Which substructure owns each free dof, for r(U).
    dof_ownership: DofOwnership,
    /// On several ranks, what passes point to point after each linear stage; `None` when
    /// every iteration reads the whole state (`Latin::reads_whole_state`) and on one process.
    neighbours: Option<NeighbourPlan>,
    /// On a rank that keeps only its substructures' links (`LinkShare`): per substructure, its
    /// links' indices in the whole structure. `None` when the structure is whole.
    world_links: Option<&'s [Vec<usize>]>,
    /// Substructures per parallel task: all of them (one task, no threads) when the work of an
    /// iteration is too small to pay for the scheduling.
    chunk: usize,
}

impl<'s> Distribution<'s> {
    /// The distribution on `exchange`, holding `held`, with no point-to-point plan yet.
    pub(super) fn new(
        exchange: &'s dyn Exchange,
        held: Range<usize>,
        dof_ownership: DofOwnership,
        world_links: Option<&'s [Vec<usize>]>,
        chunk: usize,
    ) -> Self {
        Distribution {
            exchange,
            held,
            dof_ownership,
            neighbours: None,
            world_links,
            chunk,
        }
    }

    /// What passes point to point after each linear stage from now on.
    pub(super) fn set_neighbours(&mut self, plan: NeighbourPlan) {
        self.neighbours = Some(plan);
    }

    /// The substructures this process holds.
    pub(super) fn held(&self) -> Range<usize> {
        self.held.clone()
    }

    /// Whether this process holds substructure `e`.
    pub(super) fn holds(&self, e: usize) -> bool {
        self.held.contains(&e)
    }

    /// The processes sharing the solve.
    pub(super) fn exchange(&self) -> &'s dyn Exchange {
        self.exchange
    }

    /// How many processes share the solve.
    pub(super) fn size(&self) -> usize {
        self.exchange.size()
    }

    /// Every process's `values`, in rank order (the same on every process).
    pub(super) fn gather(&self, values: &[f64]) -> Vec<f64> {
        self.exchange.all_gather(values)
    }

    /// Whether `holds` on every process.
    pub(super) fn all(&self, holds: bool) -> bool {
        self.exchange.all(holds)
    }

    /// Which substructure owns each free dof.
    pub(super) fn dof_ownership(&self) -> &DofOwnership {
        &self.dof_ownership
    }

    /// What passes point to point, when anything does.
    pub(super) fn neighbours(&self) -> Option<&NeighbourPlan> {
        self.neighbours.as_ref()
    }

    /// Per substructure, its links' indices in the whole structure on a rank that keeps its
    /// own links only.
    pub(super) fn world_links(&self) -> Option<&'s [Vec<usize>]> {
        self.world_links
    }

    /// Substructures per parallel task.
    pub(super) fn chunk(&self) -> usize {
        self.chunk
    }
}
