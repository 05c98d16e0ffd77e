//! A rank's share of the links (issue 25): a micro-macro solve on P ranks where each rank keeps
//! only the links of its own substructures. What the solver needs of the whole structure (its
//! counts, the default d_m, the prestress scale) is worked out once from it at set-up, with the
//! partition; the rank then keeps a model of its links alone ([`Model::keeping_links`])
//! and, per substructure, where its links' values go in the world's link order (the answer is
//! gathered whole, link by link).

use super::{auto_dm, LatinSettings, Partition, SearchDirection, SearchPolicy};
use crate::model::{GeometricModel, Model};
use crate::solvers::SetupError;
use crate::structure::Structure;

/// What the LATIN solver needs of the whole structure, whichever share of it a rank keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct WorldFacts {
    /// Links of the whole structure.
    pub links: usize,
    /// Its unilateral cables.
    pub cables: usize,
    /// d_m as used: `settings.dm`, or [`auto_dm`] of the whole structure.
    pub dm: f64,
    /// The degree of the strong interfaces' macro bases.
    pub macro_degree: usize,
    /// `(½ Σ t0² / l)^{1/2}` over every link, with l as set up: the prestress in the units
    /// of Δη.
    pub prestress_scale: f64,
}

impl WorldFacts {
    /// The facts of `structure` whole, partitioned into `substructures`, under `settings`.
    pub(super) fn of(
        structure: &Structure,
        settings: &LatinSettings,
        substructures: usize,
    ) -> Self {
        let links = structure.links.len();
        let macro_degree = settings.macro_degree_on(links, substructures);
        let dm = settings
            .dm
            .unwrap_or_else(|| auto_dm(structure, substructures, macro_degree));
        let prestress_scale = (0.5
            * structure
                .links
                .iter()
                .map(|l| l.prestress * l.prestress / base_search(settings, l.stiffness))
                .sum::<f64>())
        .sqrt();
        WorldFacts {
            links,
            cables: structure.links.iter().filter(|l| l.unilateral).count(),
            dm,
            macro_degree,
            prestress_scale,
        }
    }
}

/// The search direction l of a link of stiffness `k` as set up (`solver.l`).
pub(super) fn base_search(settings: &LatinSettings, k: f64) -> f64 {
    match settings.search {
        SearchDirection::Stiffness => k,
        SearchDirection::Uniform(v) => v,
    }
}

/// What one rank keeps, beside a structure of its own links ([`LinkShare::new`]), to run its
/// substructures (see the module's text).
pub struct LinkShare {
    /// The partition: this rank's substructures with their links numbered as in
    /// `structure`, the others with their nodes only.
    pub(super) partition: Partition,
    /// Per substructure, its links' indices in the whole structure.
    pub(super) world_links: Vec<Vec<usize>>,
    pub(super) world: WorldFacts,
    /// The settings and the number of ranks it was made for.
    pub(super) settings: LatinSettings,
    pub(super) ranks: usize,
    /// The substructures this rank holds.
    held: std::ops::Range<usize>,
    /// Cables of the whole structure, unilateral or not ([`Structure::n_cables`]).
    cables: usize,
}

impl LinkShare {
    /// Whether a solve with `settings` under `model` can run on shares of the links: not when
    /// every iteration reads the whole state (status-following l classifies every cable, and
    /// the prestress's geometric stiffness is one operator of the whole structure).
    pub fn possible(model: GeometricModel, settings: &LatinSettings) -> bool {
        settings.policy != SearchPolicy::Status && !model.has_geometric_stiffness()
    }

    /// The share rank `rank` of `ranks` keeps of the model `whole` under `settings`: the model
    /// of its substructures' links ([`super::block`]) alone, and the rest of its share; `None`
    /// when the solve cannot run on shares ([`LinkShare::possible`]). Settings `whole` cannot
    /// take are refused first.
    pub fn new(
        whole: &Model,
        settings: &LatinSettings,
        rank: usize,
        ranks: usize,
    ) -> Result<Option<(Model, LinkShare)>, SetupError> {
        settings.validate(&whole.structure)?;
        if !Self::possible(whole.geometry(), settings) {
            return Ok(None);
        }
        let mut partition = Partition::new(&whole.structure, settings.subdomains, settings.weak);
        let n_subs = partition.substructures.len();
        let world = WorldFacts::of(&whole.structure, settings, n_subs);
        let held = super::block(rank, ranks, n_subs);
        let mut kept = Vec::new();
        let mut world_links = Vec::with_capacity(n_subs);
        for (e, topo) in partition.substructures.iter_mut().enumerate() {
            let links = std::mem::take(&mut topo.links);
            if held.contains(&e) {
                topo.links = (kept.len()..kept.len() + links.len()).collect();
                kept.extend_from_slice(&links);
            }
            world_links.push(links);
        }
        let model = whole
            .keeping_links(&kept)
            .expect("a model without K_G(t0) keeps any links");
        let share = LinkShare {
            partition,
            world_links,
            world,
            settings: *settings,
            ranks,
            held,
            cables: whole.structure.n_cables(),
        };
        Ok(Some((model, share)))
    }

    /// Links of the whole structure.
    pub fn world_links(&self) -> usize {
        self.world.links
    }

    /// Cables of the whole structure ([`Structure::n_cables`]).
    pub fn world_cables(&self) -> usize {
        self.cables
    }

    /// The whole structure's index of each link the rank keeps, in the kept structure's order.
    pub fn kept_world_links(&self) -> Vec<usize> {
        self.world_links[self.held.clone()].concat()
    }
}
