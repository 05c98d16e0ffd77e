//! Setting the LATIN solver up (docs/method.md §4): the partition's interfaces at the
//! macro degree it takes, every substructure's operators, the macro problem, the soft
//! interface modes and the ranks' exchange plan, as a page of named steps.

use super::link_share::{self, WorldFacts};
use super::macro_problem::MacroProblem;
use super::{dof_ownership, enrichment, neighbours, operators, LinkShare, OperatorStorage};
use super::{Distribution, InterfaceSet, Operators, SearchDirections};
use super::{Latin, LatinSettings, Substructure, PARALLEL_MIN_DOFS};
use crate::decomposition::substructure::holders;
use crate::decomposition::{block, Exchange, Interfaces, OneProcess, Partition, WeakInterfaces};
use crate::model::Model;
use crate::solvers::SetupError;
use crate::structure::Structure;

/// What to change when the macro problem of `settings` is singular with macro bases of
/// `degree`; `takes`: the largest lower degree with which it sets up, if any.
fn singular_macro_advice(settings: &LatinSettings, degree: usize, takes: Option<usize>) -> String {
    let asked = match settings.macro_degree {
        Some(_) => format!("`solver.macro_degree` = {degree}"),
        None => format!("the default macro degree here, {degree}"),
    };
    if let Some(largest) = takes {
        return format!(
            "{asked} is more than this partition's interfaces take (degrees 1 to 16 are valid, \
             but on small substructures a high degree leaves the macro problem singular); the \
             largest degree this partition takes is {largest}: set `solver.macro_degree` to at \
             most {largest}"
        );
    }
    let mut advice =
        vec!["try another `solver.subdomains` (fewer, larger substructures)".to_string()];
    if settings.weak != WeakInterfaces::Macro {
        advice.push("`solver.weak_interfaces = \"macro\"`".to_string());
    }
    let advice = advice.join("; or ");
    match degree > 1 {
        true => format!("{advice} (degree 1 is singular too: {asked} is not the cause)"),
        false => advice,
    }
}

/// Memory all dense substructure inverses together may take (see
/// [`crate::linalg::SpdSolver::new`]).
const DENSE_BUDGET_BYTES: usize = 16 << 20;

impl<'s> Latin<'s> {
    /// Set up: partition, interfaces, substructure operators (in parallel) and the macro
    /// problem; settings the structure cannot take are refused first
    /// ([`LatinSettings::validate`]).
    pub fn new(model: &'s Model, settings: LatinSettings) -> Result<Self, SetupError> {
        Self::on_ranks(model, settings, &OneProcess)
    }

    /// Set up on the processes of `exchange` (every one calls it alike): each builds the
    /// operators of its block of substructures ([`block`]), L_E and Q_E of the others are
    /// gathered, the macro problem is factorised on every rank (see [`Exchange`]). Every rank
    /// holds `model` whole.
    pub fn on_ranks(
        model: &'s Model,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        let structure = &model.structure;
        settings.validate(structure)?;
        let partition = Partition::new(structure, settings.subdomains, settings.weak);
        Self::on_partition(model, &partition, settings, exchange)
    }

    /// [`Latin::on_ranks`] on a partition made before, of the same links: a `large` solve's
    /// linearised problems keep the partition of the initial geometry, whichever way the
    /// members' midpoints move.
    pub(crate) fn on_partition(
        model: &'s Model,
        partition: &Partition,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        settings.validate(&model.structure)?;
        let world = WorldFacts::of(&model.structure, &settings, partition.substructures.len());
        Self::set_up(model, partition, world, None, settings, exchange)
    }

    /// [`Latin::on_ranks`] on a rank that keeps only its substructures' links: `model`
    /// and `share` as [`LinkShare::new`] made them, with these settings and as many ranks as
    /// `exchange` has.
    pub fn on_share(
        model: &'s Model,
        share: &'s LinkShare,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        assert!(
            share.settings == settings && share.ranks == exchange.size(),
            "a share of the links is used with the settings and ranks it was made for"
        );
        Self::set_up(
            model,
            &share.partition,
            share.world,
            Some(&share.world_links),
            settings,
            exchange,
        )
    }

    /// Set up for `partition` of `model` (whole, or with the held substructures' links
    /// alone and `world_links` saying where they lie in the whole).
    fn set_up(
        model: &'s Model,
        partition: &Partition,
        mut world: WorldFacts,
        world_links: Option<&'s [Vec<usize>]>,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        let structure = &model.structure;
        // 1. The links' search directions l as set up.
        let base_search: Vec<f64> = structure
            .links
            .iter()
            .map(|l| link_share::base_search(&settings, l.stiffness))
            .collect();
        // 2. How the operators are kept, and the substructures this process holds.
        let storage = OperatorStorage {
            dense: dense_bytes(partition, structure) <= DENSE_BUDGET_BYTES,
            keep_z: settings.keep_z,
        };
        let held = block(
            exchange.rank(),
            exchange.size(),
            partition.substructures.len(),
        );
        // 3. Interfaces, substructures and the macro problem, at the degree asked for or at
        //    the largest the partition takes.
        let built = Built {
            model,
            partition,
            settings: &settings,
            search: &base_search,
            storage,
            exchange,
            held: held.clone(),
            holders: holders(partition, structure.n_nodes()),
        };
        let (interfaces, (substructures, macro_problem)) = built.at_a_degree(&mut world)?;
        let dof_ownership = dof_ownership::DofOwnership::of(&substructures, structure.n_free);
        let mut latin = Latin {
            model,
            structure,
            settings,
            world,
            interfaces: InterfaceSet {
                list: interfaces.list,
                side_slots: Vec::new(),
                dropped: interfaces.dropped,
                redundant_nodes: interfaces.redundant_nodes,
            },
            operators: Operators {
                substructures,
                macro_problem,
                storage,
                soft_modes: None,
                lost: false,
            },
            search: SearchDirections {
                now: base_search.clone(),
                slack: vec![false; structure.links.len()],
                base: base_search,
            },
            ranks: Distribution::new(
                exchange,
                held,
                dof_ownership,
                world_links,
                if structure.n_free < PARALLEL_MIN_DOFS {
                    usize::MAX
                } else {
                    1
                },
            ),
        };
        // 4. Per interface, its place among each side's sides.
        let mut side_slots = vec![[0usize; 2]; latin.interfaces.list.len()];
        for sub in &latin.operators.substructures {
            for (slot, side) in sub.sides.iter().enumerate() {
                side_slots[side.interface][side.which] = slot;
            }
        }
        latin.interfaces.side_slots = side_slots;
        // 5. Soft interface modes in the macro bases (`solver.soft_modes`).
        if let (Some(theta), false) = (latin.settings.soft_modes, latin.interfaces.list.is_empty())
        {
            latin.operators.soft_modes = Some(enrichment::SoftModes::new(
                theta,
                partition.clone(),
                &latin.interfaces.list,
                latin.structure.links.len(),
            ));
            let all: Vec<usize> = (0..latin.operators.substructures.len()).collect();
            let search = latin.search.now.clone();
            if let Some(plan) = latin.plan_enrichment(&all, &search) {
                latin.enrich(plan)?;
            }
        }
        // 6. On several ranks, what passes point to point after each linear stage.
        if exchange.size() > 1 && !latin.reads_whole_state() {
            latin.ranks.set_neighbours(neighbours::NeighbourPlan::new(
                &latin.operators.substructures,
                &latin.interfaces.list,
                latin.ranks.dof_ownership(),
                exchange.rank(),
                exchange.size(),
            ));
        }
        Ok(latin)
    }
}

/// Bytes of every substructure's K_E⁻¹ kept dense. Dense inverses are kept while all of them
/// fit in a cache-sized budget (every iteration reads them whole): 16 × 195² doubles on the
/// paper's case (4.9 MB), not 256 of them (78 MB).
fn dense_bytes(partition: &Partition, structure: &Structure) -> usize {
    partition
        .substructures
        .iter()
        .map(|t| 8 * t.free_dofs(structure).pow(2))
        .sum()
}

/// What building the substructures' operators and the macro problem takes, whatever the
/// interfaces' degree.
struct Built<'a> {
    model: &'a Model,
    partition: &'a Partition,
    settings: &'a LatinSettings,
    search: &'a [f64],
    storage: OperatorStorage,
    exchange: &'a dyn Exchange,
    held: std::ops::Range<usize>,
    /// Per node, how many substructures hold it.
    holders: Vec<u8>,
}

impl Built<'_> {
    /// The substructures and the macro problem on `interfaces` with the search direction d_m.
    fn on(
        &self,
        interfaces: &Interfaces,
        dm: f64,
    ) -> Result<(Vec<Substructure>, MacroProblem), SetupError> {
        operators::build(
            self.model,
            self.partition,
            &interfaces.list,
            &self.holders,
            self.search,
            dm,
            self.storage,
            (self.exchange, self.held.clone()),
        )
    }

    /// The interfaces at `world.macro_degree` and what they build. Where that leaves the
    /// macro problem singular and the degree is the default's guess from the substructures'
    /// size, the largest degree the partition takes, tried downwards, and d_m with it
    /// (`world` then says which; `check` prints both; issue 42, T4).
    fn at_a_degree(
        &self,
        world: &mut WorldFacts,
    ) -> Result<(Interfaces, (Vec<Substructure>, MacroProblem)), SetupError> {
        let (structure, settings) = (&self.model.structure, self.settings);
        let interfaces_at =
            |degree: usize| Interfaces::new(structure, self.partition, settings.weak, degree);
        // d_m at the degree p: the default `c p k̄ / √H` is linear in p (`auto_dm`).
        let dm_at = |degree: usize| match settings.dm {
            Some(dm) => dm,
            None => world.dm * degree.max(1) as f64 / world.macro_degree.max(1) as f64,
        };
        let interfaces = interfaces_at(world.macro_degree);
        match self.on(&interfaces, world.dm) {
            Err(SetupError::SingularMacroProblem { .. }) => {}
            built => return Ok((interfaces, built?)),
        }
        let takes = (1..world.macro_degree).rev().find_map(|degree| {
            let lower = interfaces_at(degree);
            self.on(&lower, dm_at(degree))
                .ok()
                .map(|built| (degree, lower, built))
        });
        match (settings.macro_degree, takes) {
            (None, Some((degree, lower, built))) => {
                world.dm = dm_at(degree);
                world.macro_degree = degree;
                Ok((lower, built))
            }
            (_, takes) => Err(SetupError::SingularMacroProblem {
                advice: singular_macro_advice(settings, world.macro_degree, takes.map(|t| t.0)),
            }),
        }
    }
}
