//! The mechanism check made substructure by substructure (docs/method.md, "The mechanism check
//! by substructures"): whether K with every cable taut is singular, without factorizing K
//! whole. On a 1024 × 1024 grid K's factor would take about 24 GB; a substructure's takes a
//! few MB and lives only while it is checked.
//!
//! `K u = 0` exactly when no link is stretched, that is when u restricted to every substructure
//! E is in the kernel of E's own stiffness `K⁰_E = B_Eᵀ k B_E` (its links, every cable taut,
//! no interface term). Two steps:
//! 1. Per E: the r rigid motions of E that vanish on its held components (orthonormal columns
//!    Q_E) are in ker K⁰_E, since a rigid motion stretches no member. Pin r dofs of E where
//!    Q_E's rows are independent. When `K⁰_E + p Σ_pins e eᵀ` is positive definite, no kernel
//!    vector vanishes on the pins, so the kernel has dimension at most r: `ker K⁰_E = span Q_E`.
//!    Otherwise E has a mechanism of its own and this check cannot decide.
//! 2. The coarse problem: `u_E = Q_E c_E` on every E, equal wherever substructures share a
//!    free dof: `G c = 0`, one row per shared dof and holder after its first. The kernel of K
//!    is `{u(c) : G c = 0}`, of the dimension of ker G, counted on `GᵀG` (one r × r block per
//!    pair of substructures sharing a node) as K's own zero modes are counted.

use crate::decomposition::{
    add_to_gram, null_amplitudes, orthonormal_columns, Partition, RigidFrame, SubstructureTopology,
    WeakInterfaces,
};
use crate::linalg::{
    dot, factorize_counting_zero_modes, factorize_or_find_singular, zero_modes, SparseCholesky,
    SparseRow, StiffnessPattern, ZERO_MODES_COUNTED,
};
use crate::structure::{Structure, CLAMPED};
use faer::Par;
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Modules per side of the substructures a grid is checked in: about 2 300 dofs each, so that
/// a substructure's factor takes a few MB and the coarse problem 6 unknowns per 256 modules.
pub const CHECK_MODULES: usize = 16;

/// The most kernel vectors a substructure may have (rigid motions and mechanisms of its own):
/// the coarse problem keeps each substructure's values at its shared dofs in rows of this
/// length.
pub const KERNEL_COLUMNS: usize = 12;

/// What the check by substructures finds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SubstructuredVerdict {
    /// K with every cable taut is positive definite.
    Regular,
    /// K is singular, with this many zero-stiffness modes (counted as K's own are).
    Mechanism(usize),
    /// Substructure E (its index in the partition) has more than `KERNEL_COLUMNS` kernel
    /// vectors, or more mechanisms of its own than are counted: the check does not decide,
    /// and K must be factorized whole.
    Undecided(usize),
}

/// The partition a grid of `nx × ny` modules is checked in: blocks of at most
/// [`CHECK_MODULES`] modules per side.
pub fn check_shape(nx: usize, ny: usize) -> [usize; 2] {
    [nx.div_ceil(CHECK_MODULES), ny.div_ceil(CHECK_MODULES)]
}

/// The mechanism check of `structure` (linear model: K is `Bᵀ k B`) on an `shape` partition.
pub fn mechanism_by_substructures(
    structure: &Structure,
    shape: [usize; 2],
) -> SubstructuredVerdict {
    let partition = Partition::new(structure, shape, WeakInterfaces::Macro);
    // Substructures holding each node: its free dofs are shared when more than one does.
    let mut holders = vec![0u32; structure.n_nodes()];
    for sub in &partition.substructures {
        sub.nodes.iter().for_each(|&v| holders[v] += 1);
    }
    // 1. Per E: ker K⁰_E = span Q_E, and Q_E's rows at shared dofs.
    let traces: Vec<Option<RigidTrace>> = partition
        .substructures
        .par_iter()
        .map(|sub| rigid_trace(structure, sub, &holders))
        .collect();
    if let Some(e) = traces.iter().position(Option::is_none) {
        return SubstructuredVerdict::Undecided(e);
    }
    let traces: Vec<RigidTrace> = traces.into_iter().flatten().collect();
    // 2. GᵀG, and its zero modes.
    match coarse_zero_modes(&traces) {
        0 => SubstructuredVerdict::Regular,
        modes => SubstructuredVerdict::Mechanism(modes),
    }
}

/// What the coarse problem needs of E: the dimension of ker K⁰_E, and its orthonormal basis's
/// rows (padded to [`KERNEL_COLUMNS`]) at E's shared free dofs.
struct RigidTrace {
    columns: usize,
    shared: Vec<(usize, [f64; KERNEL_COLUMNS])>,
}

/// Step 1 for substructure `sub`: `None` when E has more mechanisms of its own than are
/// counted, or more than [`KERNEL_COLUMNS`] kernel vectors in all.
fn rigid_trace(
    structure: &Structure,
    sub: &SubstructureTopology,
    holders: &[u32],
) -> Option<RigidTrace> {
    // E's free dofs, node by node: (global free dof, node, component).
    let dofs: Vec<(usize, usize, usize)> = sub
        .nodes
        .iter()
        .flat_map(|&v| (0..3).map(move |c| (v, c)))
        .filter_map(|(v, c)| {
            let d = structure.dof_of[3 * v + c];
            (d != CLAMPED).then_some((d, v, c))
        })
        .collect();
    let n = dofs.len();
    if n == 0 {
        return Some(RigidTrace {
            columns: 0,
            shared: Vec::new(),
        });
    }
    let mut by_dof: Vec<(usize, usize)> = dofs.iter().enumerate().map(|(i, d)| (d.0, i)).collect();
    by_dof.sort_unstable();
    let local = |d: usize| by_dof[by_dof.binary_search_by_key(&d, |p| p.0).unwrap()].1;
    // The rigid motions that vanish on E's held components, orthonormal over E's free dofs.
    let positions: Vec<[f64; 3]> = sub
        .nodes
        .iter()
        .chain(&sub.clamped_nodes)
        .map(|&v| structure.nodes[v])
        .collect();
    let frame = RigidFrame::new(&positions);
    let mut gram = DMatrix::<f64>::zeros(6, 6);
    for &v in sub.nodes.iter().chain(&sub.clamped_nodes) {
        let held = structure.held_components(v);
        let block = frame.block(&structure.nodes[v]);
        let rows: Vec<[f64; 6]> = (0..3).filter(|&c| held[c]).map(|c| block[c]).collect();
        add_to_gram(&mut gram, &rows);
    }
    let fields: Vec<Vec<f64>> = null_amplitudes(gram)
        .iter()
        .map(|a| {
            dofs.iter()
                .map(|&(_, v, c)| {
                    let b = frame.block(&structure.nodes[v])[c];
                    (0..6).map(|j| b[j] * a[j]).sum()
                })
                .collect()
        })
        .collect();
    let q = orthonormal_columns(&fields, n);
    // K⁰_E = Σ k b bᵀ over E's links, plus p at each pin, p = K⁰_E's mean diagonal (the
    // pattern holds every diagonal entry).
    let rows: Vec<SparseRow> = sub
        .links
        .iter()
        .map(|&i| {
            SparseRow::new(
                structure.link_dofs[i]
                    .iter()
                    .map(|(d, c)| (Some(local(d)), c)),
            )
        })
        .collect();
    let pattern = StiffnessPattern::new(n, &rows);
    let mut values = vec![0.0; pattern.nnz()];
    pattern.assemble(
        &rows,
        |j| structure.links[sub.links[j]].stiffness,
        &mut values,
    );
    let pin = pattern.mean_diagonal(&values);
    for d in independent_rows(&q) {
        values[pattern.diag_slot[d]] += pin;
    }
    let mut factor = SparseCholesky::analyse(&pattern, Par::Seq);
    let q = match factorize_or_find_singular(&pattern, &values, &mut factor) {
        false => q,
        true => {
            // E's own mechanisms: ker K⁰_E = span Q_E ⊕ ker(K⁰_E + p Σ_pins e eᵀ), since a
            // kernel vector minus the rigid motion with its values at the pins is zero there.
            let (count, modes) = zero_modes(&pattern, &values, &mut factor);
            if count >= ZERO_MODES_COUNTED || modes.ncols() < count {
                return None;
            }
            let mut fields: Vec<Vec<f64>> = q
                .column_iter()
                .map(|c| c.iter().copied().collect())
                .collect();
            fields.extend((0..count).map(|j| modes.col(j).iter().copied().collect()));
            orthonormal_columns(&fields, n)
        }
    };
    if q.ncols() > KERNEL_COLUMNS {
        return None;
    }
    let shared = dofs
        .iter()
        .enumerate()
        .filter(|(_, &(_, v, _))| holders[v] > 1)
        .map(|(i, &(d, _, _))| {
            (
                d,
                std::array::from_fn(|j| if j < q.ncols() { q[(i, j)] } else { 0.0 }),
            )
        })
        .collect();
    Some(RigidTrace {
        columns: q.ncols(),
        shared,
    })
}

/// As many rows of `q` as it has columns, chosen greedily so that they are independent: each
/// the row of largest norm once the rows chosen before are projected out.
fn independent_rows(q: &DMatrix<f64>) -> Vec<usize> {
    let mut rows: Vec<Vec<f64>> = q.row_iter().map(|r| r.iter().copied().collect()).collect();
    let mut chosen = Vec::with_capacity(q.ncols());
    for _ in 0..q.ncols() {
        let (best, norm2) = rows
            .iter()
            .enumerate()
            .map(|(i, r)| (i, dot(r, r)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("a kernel column has rows");
        if norm2 <= 0.0 {
            break;
        }
        let unit: Vec<f64> = rows[best].iter().map(|x| x / norm2.sqrt()).collect();
        for r in rows.iter_mut() {
            let a = dot(r, &unit);
            r.iter_mut().zip(&unit).for_each(|(x, u)| *x -= a * u);
        }
        chosen.push(best);
    }
    chosen
}

/// Step 2: the zero modes of `GᵀG`, whose unknowns are every E's rigid-motion amplitudes c_E.
fn coarse_zero_modes(traces: &[RigidTrace]) -> usize {
    let mut offset = Vec::with_capacity(traces.len() + 1);
    offset.push(0);
    for t in traces {
        offset.push(offset.last().unwrap() + t.columns);
    }
    let n = *offset.last().unwrap();
    if n == 0 {
        return 0;
    }
    // The values at each shared dof, by dof then substructure.
    let mut at_dof: Vec<(usize, usize, [f64; KERNEL_COLUMNS])> = traces
        .iter()
        .enumerate()
        .flat_map(|(e, t)| t.shared.iter().map(move |&(d, row)| (d, e, row)))
        .collect();
    at_dof.sort_unstable_by_key(|&(d, e, _)| (d, e));
    // GᵀG by blocks (E, F), E ≥ F: row g = (a on E1, −b on Ej) adds a aᵀ, b bᵀ and −b aᵀ.
    let mut blocks: BTreeMap<(usize, usize), [f64; KERNEL_COLUMNS * KERNEL_COLUMNS]> =
        BTreeMap::new();
    let mut add =
        |e: usize, f: usize, x: &[f64; KERNEL_COLUMNS], y: &[f64; KERNEL_COLUMNS], sign: f64| {
            let block = blocks
                .entry((e, f))
                .or_insert([0.0; KERNEL_COLUMNS * KERNEL_COLUMNS]);
            for i in 0..KERNEL_COLUMNS {
                for j in 0..KERNEL_COLUMNS {
                    block[KERNEL_COLUMNS * i + j] += sign * x[i] * y[j];
                }
            }
        };
    for group in at_dof.chunk_by(|a, b| a.0 == b.0) {
        let (_, first, a) = &group[0];
        for (_, other, b) in &group[1..] {
            add(*first, *first, a, a, 1.0);
            add(*other, *other, b, b, 1.0);
            add(*other, *first, b, a, -1.0);
        }
    }
    // The entries of block (E, F) of the lower triangle: (row, column, index in the block).
    let entry = |e: usize, f: usize| {
        let (re, rf, oe, of) = (traces[e].columns, traces[f].columns, offset[e], offset[f]);
        (0..re)
            .flat_map(move |i| (0..rf).map(move |j| (i, j)))
            .filter(move |&(i, j)| e != f || i >= j)
            .map(move |(i, j)| (oe + i, of + j, KERNEL_COLUMNS * i + j))
    };
    let entries: Vec<(usize, usize)> = blocks
        .keys()
        .flat_map(|&(e, f)| entry(e, f).map(|(r, c, _)| (r, c)))
        .collect();
    let pattern = StiffnessPattern::from_lower_entries(n, &entries);
    let mut values = vec![0.0; pattern.nnz()];
    for (&(e, f), block) in &blocks {
        for (r, c, k) in entry(e, f) {
            values[pattern.slot(r, c).expect("an entry of the pattern")] += block[k];
        }
    }
    if pattern.mean_diagonal(&values) == 0.0 {
        // No substructure shares a dof: every amplitude is free.
        return n.min(ZERO_MODES_COUNTED);
    }
    let mut factor = SparseCholesky::analyse(&pattern, Par::Seq);
    factorize_counting_zero_modes(&pattern, &values, &mut factor)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{SetupError, TautStiffness};
    use crate::structure::{Clamp, GridSpec, LoadPattern, Loading, ModuleKind, NodeFix};

    fn grid(modules: [usize; 2], module: ModuleKind, clamp: Clamp) -> Structure {
        let spec = GridSpec {
            modules,
            module,
            clamp,
            ..GridSpec::default()
        };
        Structure::grid(&spec, &LoadPattern::default())
    }

    /// K's zero modes as the whole factorization counts them.
    fn whole(structure: &Structure) -> usize {
        match TautStiffness::new(&crate::model::Model::linear(structure.clone())) {
            Ok(_) => 0,
            Err(SetupError::Mechanism { zero_modes, .. }) => zero_modes,
            Err(other) => panic!("{other}"),
        }
    }

    fn count(verdict: SubstructuredVerdict) -> usize {
        match verdict {
            SubstructuredVerdict::Regular => 0,
            SubstructuredVerdict::Mechanism(modes) => modes,
            SubstructuredVerdict::Undecided(e) => panic!("substructure {e} undecided"),
        }
    }

    /// On every support preset and both modules, every partition from one substructure to one
    /// per module finds the zero modes the whole factorization counts: none when supported, the
    /// rigid motions (and the standard grid's own mechanism) when nothing is held.
    #[test]
    fn the_check_by_substructures_counts_what_the_whole_factor_counts() {
        let presets = [
            Clamp::LowerXEdges,
            Clamp::LowerAllEdges,
            Clamp::LowerCorners,
            Clamp::None,
        ];
        let mut seen = std::collections::BTreeSet::new();
        for clamp in presets {
            for module in [ModuleKind::Standard, ModuleKind::Braced] {
                let s = grid([9, 6], module, clamp);
                let expected = whole(&s);
                seen.insert(expected);
                for shape in [[1, 1], [2, 2], [3, 2], [4, 5], [9, 6]] {
                    let found = count(mechanism_by_substructures(&s, shape));
                    assert_eq!(found, expected, "{clamp:?} {module:?} {shape:?}");
                }
            }
        }
        // Regular grids, the braced grid's six rigid motions, and the standard one's seven.
        assert_eq!(seen.into_iter().collect::<Vec<_>>(), vec![0, 6, 7]);
    }

    /// Supports that leave a grid a mechanism within a substructure's reach: two lower corners
    /// clamped (a rotation about the line through them), then the components of the other two
    /// held one at a time. Each count equals the whole factorization's, and it falls to zero.
    #[test]
    fn partly_held_nodes_are_counted_as_the_whole_factor_counts() {
        let spec = GridSpec {
            modules: [6, 4],
            module: ModuleKind::Braced,
            clamp: Clamp::LowerCorners,
            ..GridSpec::default()
        };
        let (geometry, layout, corners) = Structure::grid_parts(&spec);
        let held = |fixes: &[NodeFix]| {
            let mut s = Structure::new(&geometry, fixes, &Loading::default());
            s.layout = Some(layout);
            s
        };
        let mut counts = Vec::new();
        for components in [[false; 3], [false, false, true], [true, false, true]] {
            let mut fixes = corners[..2].to_vec();
            fixes.extend(corners[2..].iter().map(|f| NodeFix {
                dofs: components,
                ..*f
            }));
            let s = held(&fixes);
            let expected = whole(&s);
            for shape in [[1, 1], [2, 2], [3, 4], [6, 4]] {
                assert_eq!(
                    count(mechanism_by_substructures(&s, shape)),
                    expected,
                    "{components:?} {shape:?}"
                );
            }
            counts.push(expected);
        }
        assert!(counts[0] > 0 && counts[2] == 0, "{counts:?}");
    }
}
