//! Which MPI ranks of a run keep only their own substructures' links, and which the whole
//! structure.

use crate::app::memory::Workload;
use crate::case::{Case, ReferenceChoice};
use crate::solvers::latin::LinkShare;
use crate::solvers::Method;

/// Which MPI ranks of a run keep only their micro-macro substructures' links
/// ([`crate::app::setup::Prepared::keep_links_of`]), the others keeping the whole structure. A rank keeps a share
/// only when micro-macro is the run's one solver, with no reference solve and without K's
/// factor, and when the solve can run on shares ([`LinkShare::possible`]: not with
/// status-following l nor with the prestress's geometric stiffness).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sharing {
    /// Every rank keeps the whole structure (one process, or another solver, a reference
    /// solve or K's factor needs it).
    Whole,
    /// Ranks 1 … P − 1 keep their links alone; rank 0 keeps the whole structure for the
    /// files that read every link (tensions, forces, reactions, VTK, figures, stability,
    /// homogenised operators; the member checks read every link too) and judges every answer
    /// alone.
    AllButRank0,
    /// Every rank keeps its links alone (the files asked for read no link: summary, history,
    /// displacements); the ranks judge and measure every answer together.
    EveryRank,
}

impl Sharing {
    /// Which runs share out their links, as `check` and `run` say it.
    pub const WHEN_SHARED: &'static str = "only a run of micro-macro alone with reference = \
         \"none\", output.geometric_term = false and the default search policy shares out its \
         links";

    /// The sharing of a run of `case` by `methods` on `ranks` ranks that keeps K's factor or
    /// not (`keeps_taut`).
    pub fn of(case: &Case, methods: &[Method], keeps_taut: bool, ranks: usize) -> Sharing {
        let possible = case
            .solver
            .latin_settings(Method::MicroMacro)
            .is_some_and(|settings| LinkShare::possible(case.model, &settings));
        let shares = ranks > 1
            && methods == [Method::MicroMacro]
            && case.solver.reference == ReferenceChoice::None
            && !keeps_taut
            && possible;
        let o = &case.output;
        let reads_links = o.tensions
            || o.forces
            || o.reactions
            || o.vtk
            || o.plots
            || o.stability
            || o.homogenised
            || case.geometry.checks.is_some();
        match (shares, reads_links) {
            (false, _) => Sharing::Whole,
            (true, true) => Sharing::AllButRank0,
            (true, false) => Sharing::EveryRank,
        }
    }

    /// The sharing of `tensolve run` on `case` (its own solvers) on `ranks` ranks.
    pub fn of_run(case: &Case, ranks: usize) -> Sharing {
        let methods = &case.solver.methods;
        Sharing::of(
            case,
            methods,
            Workload::run(case, methods).keeps_taut,
            ranks,
        )
    }

    /// What `check` says of it.
    pub fn describe(self) -> String {
        match self {
            Sharing::Whole => {
                format!(
                    "every rank keeps the whole structure ({})",
                    Self::WHEN_SHARED
                )
            }
            Sharing::AllButRank0 => {
                "ranks 1 and up keep only their substructures' links; rank 0 keeps the whole \
                 structure for the files that read every link (tensions, forces, reactions, vtk, \
                 plots, stability, homogenised: turn them off and every rank keeps its share)"
                    .to_string()
            }
            Sharing::EveryRank => {
                "every rank keeps only its substructures' links (nodes, supports and loads \
                 whole); the ranks judge and measure each answer together"
                    .to_string()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::latin::SearchPolicy;

    /// The ranks keep shares of the links only for micro-macro alone with no reference and
    /// without K's factor, on several ranks, every rank when no file reads a link.
    #[test]
    fn links_are_shared_only_where_nothing_needs_the_whole_structure() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/paper.toml");
        let alone = [
            "solver.reference=\"none\"".to_string(),
            "output.geometric_term=false".to_string(),
        ];
        let mut case = crate::case::load_with(&path, &alone).unwrap();
        let mm = [Method::MicroMacro];
        assert_eq!(Sharing::of(&case, &mm, false, 2), Sharing::AllButRank0);
        assert_eq!(Sharing::of(&case, &mm, false, 1), Sharing::Whole);
        assert_eq!(Sharing::of(&case, &mm, true, 4), Sharing::Whole);
        let both = [Method::MicroMacro, Method::MonoLatin];
        assert_eq!(Sharing::of(&case, &both, false, 4), Sharing::Whole);
        let o = &mut case.output;
        (o.tensions, o.forces, o.reactions, o.plots) = (false, false, false, false);
        assert_eq!(Sharing::of(&case, &mm, false, 2), Sharing::EveryRank);
        case.output.vtk = true;
        assert_eq!(Sharing::of(&case, &mm, false, 2), Sharing::AllButRank0);
        case.solver.latin.policy = SearchPolicy::Status;
        assert_eq!(Sharing::of(&case, &mm, false, 2), Sharing::Whole);
        let with_reference = crate::case::load_with(&path, &alone[1..]).unwrap();
        assert_eq!(Sharing::of(&with_reference, &mm, false, 2), Sharing::Whole);
        // The run's own solvers (the paper's four) keep the whole structure.
        assert_eq!(Sharing::of_run(&case, 2), Sharing::Whole);
    }
}
