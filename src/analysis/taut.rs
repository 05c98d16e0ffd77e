//! The stiffness with every cable taut, `K = Bᵀ k B` on the free dofs (docs/method.md §2–3), factorized
//! once per structure and shared by the solvers; building it is where a mechanism is refused.

use super::SetupError;
use crate::linalg::{
    factorize_counting_zero_modes, NodeOrdering, SparseCholesky, StiffnessPattern,
};
use crate::model::{prestress_stability, Model, PrestressStability};
use crate::structure::Structure;
use faer::Par;

/// From this many free nodes on, the factor's ordering is nested dissection on the nodes'
/// coordinates rather than AMD (smaller structures keep AMD, which needs no geometry); the
/// measurements behind 512: docs/method.md, "Tuning log".
const NESTED_DISSECTION_MIN_NODES: usize = 512;

/// `K = Bᵀ k B` with every cable taut, its pattern (shared by every stiffness of the structure)
/// and its factor.
#[derive(Debug, Clone)]
pub struct TautStiffness {
    /// The pattern of K, which is also that of every tangent stiffness.
    pub pattern: StiffnessPattern,
    /// Lower triangle of K on `pattern`.
    pub values: Vec<f64>,
    /// Cholesky factor of K.
    pub factor: SparseCholesky,
}

impl TautStiffness {
    /// K's pattern and its symbolic analysis (the fill-reducing ordering chosen by size: AMD,
    /// or nested dissection from the free nodes' coordinates), before any numeric work.
    pub fn analyse(structure: &Structure) -> (StiffnessPattern, SparseCholesky) {
        let pattern = StiffnessPattern::new(structure.n_free, &structure.link_dofs);
        // Coordinates of the free nodes, in free-dof order (three dofs per free node).
        let free_nodes: Vec<[f64; 3]> = (0..structure.nodes.len())
            .filter(|&v| !structure.clamped[v])
            .map(|v| structure.nodes[v])
            .collect();
        let ordering = if free_nodes.len() >= NESTED_DISSECTION_MIN_NODES {
            NodeOrdering::NestedDissection(&free_nodes)
        } else {
            NodeOrdering::Amd
        };
        let factor = SparseCholesky::analyse_ordered(&pattern, Par::Seq, ordering);
        (pattern, factor)
    }

    /// Assemble and factorize K (with the prestress's geometric stiffness when the model has
    /// it: `K + K_G(t0)`, docs/method.md §8); refuse a structure whose K is singular, saying
    /// where its modes are and whether its prestress would stiffen them.
    pub fn new(model: &Model) -> Result<TautStiffness, SetupError> {
        let (pattern, mut factor) = Self::analyse(&model.structure);
        let mut values = vec![0.0; pattern.nnz()];
        model.assemble_tangent(&pattern, |_| true, &mut values);
        let zero_modes = factorize_counting_zero_modes(&pattern, &values, &mut factor);
        if zero_modes > 0 {
            return Err(refusal(model, zero_modes));
        }
        Ok(TautStiffness {
            pattern,
            values,
            factor,
        })
    }
}

impl TautStiffness {
    /// K's pattern, values and symbolic analysis, never factorised (`factor` holds the analysis
    /// alone): for newton's substructured solve in a run whose mechanism check was made
    /// substructure by substructure, which never factorises K whole.
    pub fn unfactorised(model: &Model) -> TautStiffness {
        let (pattern, factor) = Self::analyse(&model.structure);
        let mut values = vec![0.0; pattern.nnz()];
        model.assemble_tangent(&pattern, |_| true, &mut values);
        TautStiffness {
            pattern,
            values,
            factor,
        }
    }

    /// The refusal of `model`, whose K has `zero_modes` zero-stiffness modes, as
    /// [`TautStiffness::new`] gives it: for a check that found them without K's factor.
    pub fn refusal(model: &Model, zero_modes: usize) -> SetupError {
        refusal(model, zero_modes)
    }
}

/// Why a singular (or, with geometric stiffness, indefinite) taut stiffness is refused: the
/// prestress-stability test of docs/method.md §8 tells whether geometric stiffness would make it
/// solvable, and names the nodes of the modes that stay unstiffened.
fn refusal(model: &Model, zero_modes: usize) -> SetupError {
    let s = &model.structure;
    // Grids are refused without the dense test (their mechanisms are too few supports).
    let stability = (s.layout.is_none() || model.has_geometric_stiffness())
        .then(|| prestress_stability(s))
        .flatten();
    if model.has_geometric_stiffness() {
        return not_prestress_stable(model, stability.as_ref());
    }
    let unstiffened = |st: &PrestressStability| unstiffened_modes(s, st);
    let rows = |st: &PrestressStability, all: bool| mode_rows(s, st, all);
    let grid = s.layout.is_some();
    // Mᵀ K_G M positive definite does not make K + K_G(t0) so (a prestress too small to
    // resolve, or one that buckles the bars): "solvable" only when it is.
    let geometric_regular =
        |st: &PrestressStability| match TautStiffness::new(&Model::prestress(s.clone())) {
            Ok(_) => Ok(()),
            Err(_) => Err(crate::model::indefinite_reason(s, Some(st))),
        };
    match stability {
        Some(st) if st.mechanisms > 0 && st.stable() => match geometric_regular(&st) {
            Err(reason) => SetupError::Mechanism {
                zero_modes,
                where_: " (every node's motion in mechanisms.csv of the output directory, \
                         written by `run`)"
                    .to_string(),
                modes: rows(&st, true),
                advice: format!(
                    "its prestress stiffens all {} mechanism(s) (the smallest by {:.3e} N/m), but \
                     K + K_G(t0) is not positive definite, so no model solves it: {reason}",
                    st.mechanisms,
                    st.smallest().unwrap_or(0.0)
                ),
            },
            Ok(()) => SetupError::Mechanism {
                zero_modes,
                where_: " (every node's motion in mechanisms.csv of the output directory, written \
                     by `run`)"
                    .to_string(),
                modes: rows(&st, true),
                advice: format!(
                    "it is prestress-stable (its prestress stiffens all {} mechanism(s), the \
                 smallest by {:.3e} N/m): solvable with `model.geometry = \"prestress\"` or \
                 `\"large\"`",
                    st.mechanisms,
                    st.smallest().unwrap_or(0.0)
                ),
            },
        },
        stability => SetupError::Mechanism {
            zero_modes,
            modes: stability
                .as_ref()
                .map(|st| rows(st, true))
                .unwrap_or_default(),
            where_: stability
                .filter(|st| st.mechanisms > 0)
                .map(|st| {
                    format!(
                        " ({}; every node's motion in mechanisms.csv of the output directory, \
                         written by `run`)",
                        unstiffened(&st)
                    )
                })
                .unwrap_or_default(),
            advice: if grid {
                "hold more nodes (`supports.clamp`, `supports.fix`) or use a stiffer module \
                 (`grid.module = \"braced\"`)"
                    .to_string()
            } else {
                "hold more nodes (`supports.fix`) or add members; its prestress does not \
                 stiffen it either"
                    .to_string()
            },
        },
    }
}

/// With geometric stiffness, `K + K_G(t0)` not positive definite: the modes the prestress does
/// not stiffen (with their nodes), or why it is indefinite though it stiffens them all.
fn not_prestress_stable(model: &Model, stability: Option<&PrestressStability>) -> SetupError {
    let s = &model.structure;
    let modes = stability
        .map(|st| mode_rows(s, st, false))
        .unwrap_or_default();
    let slip = crate::model::unit_slip_strain(s)
        .map(|(id, strain)| format!("{}; ", crate::model::unit_slip_sentence(id, strain)))
        .unwrap_or_default();
    let detail = match stability {
        Some(st) if !st.stable() => format!(
            "{slip}{} of its {} mechanism(s) not stiffened: {} (every node's motion in \
             mechanisms.csv of the output directory, written by `run`); add members or \
             supports, or change the prestress",
            st.unstiffened().count(),
            st.mechanisms,
            unstiffened_modes(s, st)
        ),
        _ => format!(
            "`K + K_G(t0)` is not positive definite: {}",
            crate::model::indefinite_reason(s, stability)
        ),
    };
    // Rest-length changes act in full on the initial geometry (never ramped by α): there the
    // members carry t0 − k Δℓ0, and a change larger than the prestress can take shows here.
    let actions = if s.links.iter().any(|l| l.rest_change != 0.0) {
        "; the members' rest-length changes (`load.rest_length_change`, `load.temperature`) act \
         in full on the initial geometry, where the members then carry t0 − k Δℓ0: a change \
         that slackens cables or overloads bars there is refused with it (smaller changes, or \
         a larger prestress)"
    } else {
        ""
    };
    SetupError::NotPrestressStable {
        model: model.geometry().name(),
        detail: format!("{detail}{actions}"),
        modes,
    }
}

/// The first three modes the prestress does not stiffen, each with the nodes it moves most.
fn unstiffened_modes(s: &Structure, st: &PrestressStability) -> String {
    let modes: Vec<String> = st
        .unstiffened()
        .take(3)
        .enumerate()
        .map(|(k, m)| m.describe(s, k + 1))
        .collect();
    modes.join("; ")
}

/// The modes behind a refusal, node by node, for mechanisms.csv: those the prestress does not
/// stiffen, or (`all`) every mechanism.
fn mode_rows(s: &Structure, st: &PrestressStability, all: bool) -> Vec<super::ModeRow> {
    st.modes
        .iter()
        .filter(|m| all || m.stiffness <= st.threshold)
        .enumerate()
        .flat_map(|(k, m)| {
            let full = s.full_displacements(&m.displacement);
            (0..s.nodes.len())
                .map(move |v| {
                    (
                        s.node_ids[v],
                        k + 1,
                        [full[3 * v], full[3 * v + 1], full[3 * v + 2]],
                    )
                })
                .collect::<Vec<_>>()
        })
        .collect()
}
