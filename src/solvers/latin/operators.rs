//! Every substructure's operators at set-up, shared among the processes of an [`Exchange`]:
//! each builds those of its block, L_E and Q_E of the others are gathered; then the macro
//! problem they make.

use super::macro_problem::MacroProblem;
use super::substructure::OperatorStorage;
use super::{Interface, Partition, Substructure};
use crate::decomposition::substructure::Shapes;
use crate::decomposition::Exchange;
use crate::model::Model;
use crate::solvers::SetupError;
use crate::structure::CLAMPED;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// The substructures of the partition for the search direction `search`: those of the block
/// `held` this process holds with their operators (in parallel), the others with L_E and Q_E
/// gathered from the processes of `exchange` that hold them; and the macro problem they make.
#[allow(clippy::too_many_arguments)]
pub(super) fn build(
    model: &Model,
    partition: &Partition,
    interfaces: &[Interface],
    holders: &[u8],
    search: &[f64],
    dm: f64,
    storage: OperatorStorage,
    (exchange, held): (&dyn Exchange, std::ops::Range<usize>),
) -> Result<(Vec<Substructure>, MacroProblem), SetupError> {
    // Every substructure, in parallel (a scratch dof map per task); those of one shape share
    // its pattern and analysis.
    let shapes = Shapes::default();
    let built: Vec<Result<Substructure, usize>> = (0..partition.substructures.len())
        .into_par_iter()
        .map_init(
            || vec![CLAMPED; 3 * model.structure.n_nodes()],
            |scratch, e| {
                let topo = &partition.substructures[e];
                if !held.contains(&e) {
                    return Ok(Substructure::remote(
                        e, topo, model, interfaces, holders, scratch,
                    ));
                }
                Substructure::new(
                    e, topo, model, interfaces, holders, search, dm, storage, &shapes, scratch,
                )
                .map_err(|_| e)
            },
        )
        .collect();
    // The first substructure left without stiffness on any rank.
    let failed = built.iter().find_map(|b| b.as_ref().err().copied());
    if !exchange.all(failed.is_none()) {
        let mine = [failed.map_or(f64::INFINITY, |e| e as f64)];
        let first = exchange
            .all_gather(&mine)
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        return Err(SetupError::SingularSubstructure {
            index: first as usize,
            prestress: model.prestress_stiffness().is_some(),
        });
    }
    let mut substructures: Vec<Substructure> = built.into_iter().flatten().collect();
    let all: Vec<usize> = (0..substructures.len()).collect();
    share_homogenised(&mut substructures, &all, exchange, &held);
    let macro_problem = MacroProblem::new(&substructures, interfaces, dm).map_err(|_| {
        SetupError::SingularMacroProblem {
            advice: String::new(),
        }
    })?;
    Ok((substructures, macro_problem))
}

/// L_E and Q_E of the substructures `which` (increasing) from the ranks that hold them onto
/// every rank: per substructure the kernel's columns, L_E, then Q_E (column-major).
pub(super) fn share_homogenised(
    substructures: &mut [Substructure],
    which: &[usize],
    exchange: &dyn Exchange,
    held: &std::ops::Range<usize>,
) {
    if exchange.size() == 1 {
        return;
    }
    let mut mine = Vec::new();
    for &e in which.iter().filter(|e| held.contains(e)) {
        let sub = &substructures[e];
        mine.push(sub.kernel.ncols() as f64);
        mine.extend_from_slice(sub.flexibility.as_slice());
        mine.extend_from_slice(sub.kernel.as_slice());
    }
    let all = exchange.all_gather(&mine);
    let mut rest = all.as_slice();
    for &e in which {
        let m = substructures[e].n_macro;
        let columns = rest[0] as usize;
        let (flexibility, tail) = rest[1..].split_at(m * m);
        let (kernel, tail) = tail.split_at(m * columns);
        rest = tail;
        if !held.contains(&e) {
            let sub = &mut substructures[e];
            sub.flexibility = DMatrix::from_column_slice(m, m, flexibility);
            sub.kernel = DMatrix::from_column_slice(m, columns, kernel);
        }
    }
}
