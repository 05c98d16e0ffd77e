//! The LATIN solver's internal invariants on the paper case (issue 29: tested beside the code,
//! the internals `pub(crate)`): the partition report and the kernels of K*_E against a
//! first-principles computation from B_E, the linear stage's macro continuity, macro force
//! balance and equilibrium per substructure, and the local stage's law on both search
//! directions.
//!
//! Figures measured when these tests were written are quoted next to each bound; run with
//! `--nocapture` to see the current ones.

use super::{macro_basis, Latin, LatinSettings, LatinState, Partition, PAPER_DM};
use crate::decomposition::WeakInterfaces;
use crate::solvers::Solver;
use crate::structure::{GridSpec, LoadPattern, Structure};
use nalgebra::DMatrix;

/// Interface search direction of the paper, N/m (set explicitly by `settings`).
const DM: f64 = PAPER_DM;

/// The paper's case (`cases/paper.toml`): the 16 × 16 grid of §5, whose keys are the
/// defaults of [`GridSpec`] and [`LoadPattern`] (built here without the case file: solvers
/// sit below `case`).
fn paper_structure() -> Structure {
    Structure::grid(&GridSpec::default(), &LoadPattern::default())
}

/// The paper's grid with n × n modules.
fn grid_structure(n: usize) -> Structure {
    let spec = GridSpec {
        modules: [n, n],
        ..GridSpec::default()
    };
    Structure::grid(&spec, &LoadPattern::default())
}

/// Every k-th link slack where it is a cable (a status pattern for the operators' tests).
fn slack_every(s: &Structure, k: usize) -> Vec<bool> {
    s.links
        .iter()
        .enumerate()
        .map(|(i, l)| l.unilateral && i % k == 0)
        .collect()
}

/// The load `alpha · unit_load` on the free dofs.
fn load(s: &Structure, alpha: f64) -> Vec<f64> {
    s.unit_load.iter().map(|f| alpha * f).collect()
}

fn settings(subdomains: [usize; 2], weak: WeakInterfaces) -> LatinSettings {
    LatinSettings {
        subdomains,
        weak,
        dm: Some(DM),
        ..LatinSettings::default()
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

mod kernels;
mod linear_stage;
mod local_stage;
mod operators;
