//! Soft interface modes in the macro basis (docs/method.md, "Soft interface modes"): the
//! motions of an interface that a substructure resists much less than the search direction
//! d_m does. On such a mode the micro part of the iteration converges at about
//! `1 − 2 S / d_m` an iteration (S the substructure's stiffness on it), so where slack cables
//! soften a substructure these modes decide the count, and more of them the more
//! substructures there are. Added to the interface's macro basis, the macro problem solves
//! them exactly. They are taken at set-up and again at each operator rebuild, for the
//! substructures whose operators changed, so that the coarse space follows the status.

use super::macro_problem::MacroProblem;
use super::operators::share_homogenised;
use super::{Latin, Substructure};
use crate::decomposition::{number_macro_dofs, Exchange, Interface, Partition};
use crate::solvers::SetupError;
use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

/// At most this many soft modes per side of an interface (the softest first).
pub const SOFT_MODES_PER_SIDE: usize = 24;

/// A substructure's soft modes are taken anew at a rebuild once the search direction has
/// changed on at least this fraction of its links since they were taken (the first status
/// step changes many; the later ones a few cables, which move the modes little).
const STALE_FRACTION: f64 = 0.01;

/// Modes below this fraction of d_m are left out: a substructure's own mechanism at the
/// interface (S = 0) in the macro basis makes K*_E singular beyond its rigid kernel.
const SOFT_MODE_FLOOR: f64 = 1e-2;

/// One side's soft modes: its interface, which side (0 or 1), the modes.
type SideModes = (usize, usize, Vec<Vec<f64>>);

/// Per side of `sub` (its interface and the modes, one row per free component of the
/// interface's nodes): the eigenvectors of `T = d_m I − d_m² (K_E⁻¹)_ΓΓ` on the side's rows
/// outside the span of the interface's polynomial basis, whose eigenvalue lies between
/// `SOFT_MODE_FLOOR · d_m` and `theta · d_m`, softest first, at most [`SOFT_MODES_PER_SIDE`].
fn soft_modes(
    sub: &Substructure,
    polynomial: &[DMatrix<f64>],
    dm: f64,
    theta: f64,
) -> Vec<SideModes> {
    let ops = sub.ops();
    sub.sides
        .iter()
        .map(|side| {
            let rows = side.rows;
            let dof = |r: usize| sub.gamma_dofs[side.gamma_offset + r];
            let mut columns = DMatrix::<f64>::zeros(sub.n_dofs(), rows);
            for r in 0..rows {
                columns[(dof(r), r)] = 1.0;
            }
            ops.factor.solve_columns(&mut columns);
            // T = d_m I − d_m² (K_E⁻¹)_ΓΓ: the side's stiffness in series with the spring d_m.
            let mut t = DMatrix::<f64>::identity(rows, rows) * dm;
            for c in 0..rows {
                for r in 0..rows {
                    t[(r, c)] -= dm * dm * columns[(dof(r), c)];
                }
            }
            drop(columns);
            let t = (&t + t.transpose()) * 0.5;
            // P T P + d_m R Rᵀ, P = I − R Rᵀ: the polynomial fields moved to the top.
            let r = &polynomial[side.interface];
            let rrt = r * r.transpose();
            let p = DMatrix::<f64>::identity(rows, rows) - &rrt;
            let eigen = SymmetricEigen::new(&p * t * &p + rrt * dm);
            let mut soft: Vec<usize> = (0..rows)
                .filter(|&k| {
                    let value = eigen.eigenvalues[k];
                    value < theta * dm && value > SOFT_MODE_FLOOR * dm
                })
                .collect();
            soft.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
            soft.truncate(SOFT_MODES_PER_SIDE);
            let modes = soft
                .iter()
                .map(|&k| eigen.eigenvectors.column(k).iter().copied().collect())
                .collect();
            (side.interface, side.which, modes)
        })
        .collect()
}

/// What the enrichment keeps between rebuilds.
pub(super) struct SoftModes {
    /// θ: modes below `θ d_m` are soft.
    theta: f64,
    /// The partition (the substructures' nodes, for their rigid kernels).
    partition: Partition,
    /// Per interface, its polynomial basis.
    polynomial: Vec<DMatrix<f64>>,
    /// Per interface, per side, its soft modes.
    modes: Vec<[Vec<Vec<f64>>; 2]>,
    /// Per link, the search direction l its substructure's modes were taken with (NaN: not
    /// yet taken).
    taken_with: Vec<f64>,
}

impl SoftModes {
    /// No modes yet, on interfaces with their polynomial bases.
    pub(super) fn new(
        theta: f64,
        partition: Partition,
        interfaces: &[Interface],
        links: usize,
    ) -> Self {
        SoftModes {
            theta,
            partition,
            polynomial: interfaces.iter().map(|i| i.basis.clone()).collect(),
            modes: vec![[Vec::new(), Vec::new()]; interfaces.len()],
            taken_with: vec![f64::NAN; links],
        }
    }

    /// Of the substructures `which`, those whose modes are stale under the search directions
    /// `search`: l changed on at least [`STALE_FRACTION`] of their links since the modes
    /// were taken (every one the first time). Each process counts the links it keeps, which
    /// are the links of the substructures it holds; the verdicts are gathered.
    fn stale(
        &mut self,
        substructures: &[Substructure],
        which: &[usize],
        held: &std::ops::Range<usize>,
        search: &[f64],
        exchange: &dyn Exchange,
    ) -> Vec<usize> {
        let mine: Vec<f64> = which
            .iter()
            .filter(|e| held.contains(e))
            .filter(|&&e| {
                let links = &substructures[e].links;
                let changed = links
                    .iter()
                    .filter(|&&i| search[i] != self.taken_with[i])
                    .count();
                changed as f64 >= STALE_FRACTION * links.len() as f64
            })
            .map(|&e| e as f64)
            .collect();
        let mut stale: Vec<usize> = match exchange.size() {
            1 => mine,
            _ => exchange.all_gather(&mine),
        }
        .into_iter()
        .map(|e| e as usize)
        .collect();
        stale.sort_unstable();
        for &e in stale.iter().filter(|e| held.contains(e)) {
            for &i in &substructures[e].links {
                self.taken_with[i] = search[i];
            }
        }
        stale
    }

    /// The soft modes of the sides of the substructures `which` (increasing), recomputed on
    /// this process for those it holds and gathered from the others: per side, its
    /// interface, which side, the modes' count and rows, then the modes.
    fn update(
        &mut self,
        substructures: &[Substructure],
        which: &[usize],
        held: &std::ops::Range<usize>,
        dm: f64,
        exchange: &dyn Exchange,
    ) {
        let found: Vec<Vec<SideModes>> = which
            .par_iter()
            .filter(|e| held.contains(e))
            .map(|&e| soft_modes(&substructures[e], &self.polynomial, dm, self.theta))
            .collect();
        let mut mine = Vec::new();
        for (interface, side, modes) in found.into_iter().flatten() {
            let rows = modes.first().map_or(0, Vec::len);
            mine.extend([interface, side, modes.len(), rows].map(|x| x as f64));
            mine.extend(modes.into_iter().flatten());
        }
        let all = match exchange.size() {
            1 => mine,
            _ => exchange.all_gather(&mine),
        };
        let mut rest = all.as_slice();
        while let [interface, side, count, rows, tail @ ..] = rest {
            let (count, rows) = (*count as usize, *rows as usize);
            let (values, tail) = tail.split_at(count * rows);
            self.modes[*interface as usize][*side as usize] =
                values.chunks(rows.max(1)).map(<[f64]>::to_vec).collect();
            rest = tail;
        }
    }
}

/// What an enrichment does ([`Latin::plan_enrichment`]): the substructures whose soft modes
/// are retaken, the interfaces they lie on (whose bases change) and every substructure on
/// those interfaces (condensed anew on the new bases); all increasing.
pub(super) struct Enrichment {
    stale: Vec<usize>,
    touched: Vec<usize>,
    /// The substructures [`Latin::enrich`] condenses anew: a rebuild only refactorizes these.
    pub affected: Vec<usize>,
}

impl Latin<'_> {
    /// Of the substructures `which` (increasing), those whose soft modes are stale under the
    /// search directions `search`, and what retaking them changes; marks their modes as taken
    /// with `search`. `None` without `solver.soft_modes`.
    pub(super) fn plan_enrichment(
        &mut self,
        which: &[usize],
        search: &[f64],
    ) -> Option<Enrichment> {
        let soft = self.operators.soft_modes.as_mut()?;
        let stale = soft.stale(
            &self.operators.substructures,
            which,
            &self.ranks.held(),
            search,
            self.ranks.exchange(),
        );
        let touched: Vec<usize> = (0..self.interfaces.list.len())
            .filter(|&k| {
                self.interfaces.list[k]
                    .topology
                    .sides
                    .iter()
                    .any(|e| stale.binary_search(e).is_ok())
            })
            .collect();
        let mut affected: Vec<usize> = touched
            .iter()
            .flat_map(|&k| self.interfaces.list[k].topology.sides)
            .collect();
        affected.sort_unstable();
        affected.dedup();
        Some(Enrichment {
            stale,
            touched,
            affected,
        })
    }

    /// The enrichment `plan`: the stale substructures' soft modes taken anew from their
    /// operators, the macro bases of the touched interfaces remade (polynomial fields, then
    /// the soft modes of the first side, then of the second), the operators of the affected
    /// substructures condensed on the new bases (K_E's factor kept), and the macro problem
    /// set up anew; with nothing stale, the macro problem refactorized on the bases as they
    /// stand.
    pub(super) fn enrich(&mut self, plan: Enrichment) -> Result<(), SetupError> {
        let Some(soft) = self.operators.soft_modes.as_mut() else {
            return Ok(());
        };
        if plan.stale.is_empty() {
            // The bases stand: the changed operators were condensed on them.
            self.operators.macro_problem = self
                .operators
                .macro_problem
                .refactor(&self.operators.substructures, &self.interfaces.list)
                .map_err(|_| SetupError::SingularMacroProblem {
                    advice: String::new(),
                })?;
            return Ok(());
        }
        soft.update(
            &self.operators.substructures,
            &plan.stale,
            &self.ranks.held(),
            self.world.dm,
            self.ranks.exchange(),
        );
        for &k in &plan.touched {
            let polynomial = &soft.polynomial[k];
            let mut fields: Vec<Vec<f64>> = polynomial
                .column_iter()
                .map(|c| c.iter().copied().collect())
                .collect();
            let mut labels: Vec<String> =
                self.interfaces.list[k].fields[..polynomial.ncols()].to_vec();
            for (side, modes) in soft.modes[k].iter().enumerate() {
                for (j, mode) in modes.iter().enumerate() {
                    fields.push(mode.clone());
                    labels.push(format!("soft {} of side {side}", j + 1));
                }
            }
            self.interfaces.list[k].set_fields(&fields, &labels);
        }
        number_macro_dofs(&mut self.interfaces.list);
        let affected = &plan.affected;
        let (structure, interfaces, dm, storage) = (
            self.structure,
            &self.interfaces.list,
            self.world.dm,
            self.operators.storage,
        );
        let partition = &soft.partition;
        let failed = self
            .operators
            .substructures
            .par_iter_mut()
            .enumerate()
            .filter(|(e, _)| affected.binary_search(e).is_ok())
            .map(|(e, sub)| {
                let topology = &partition.substructures[e];
                sub.set_interfaces(topology, structure, interfaces, dm, storage)
                    .map_err(|_| e)
            })
            .collect::<Result<Vec<()>, usize>>()
            .err();
        if !self.ranks.all(failed.is_none()) {
            return Err(SetupError::SingularSubstructure {
                index: failed.unwrap_or(0),
                prestress: self.model.prestress_stiffness().is_some(),
            });
        }
        share_homogenised(
            &mut self.operators.substructures,
            affected,
            self.ranks.exchange(),
            &self.ranks.held(),
        );
        self.operators.macro_problem =
            MacroProblem::new(&self.operators.substructures, &self.interfaces.list, dm).map_err(
                |_| SetupError::SingularMacroProblem {
                    advice:
                        "lower `solver.soft_modes` (fewer soft interface modes in the macro basis)"
                            .to_string(),
                },
            )?;
        Ok(())
    }
}
