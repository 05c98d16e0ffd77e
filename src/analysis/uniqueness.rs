//! Whether a converged answer is the only equilibrium (issue 42, D1). The energy is convex, so
//! its minimisers form a convex set: a second one exists exactly when, from the answer, a motion
//! v keeps the energy constant. Such a v leaves every member that carries force unstretched
//! (`K_c v = 0`, `K_c` the tangent over those members alone), the load does no work on it
//! (`F·v = 0`), and it stretches no cable at zero tension with its gap closed (`B_z v ≤ 0`: that
//! cable resists elongation only); slack cables, with their gaps open, let it pass. The answer is
//! flagged not unique when such a v is found: one factorization of `K_c` per converged row, and
//! the search for v only where `K_c` is singular.

use super::Equilibrium;
use crate::linalg::{
    dot, factorize_or_find_singular_below, norm, smallest_eigenvalues, SparseCholesky, SparseRow,
    StiffnessPattern, ZERO_MODES_COUNTED,
};
use crate::model::material::{carries_force, gap_scale, gap_slack};
use crate::model::{largest_moving_nodes, Model};
use crate::structure::Structure;
use nalgebra::{DMatrix, SymmetricEigen};

/// Up to this many free dofs every converged row is checked on K's analysis, where the run
/// keeps it; beyond, only where the run factorizes a tangent per row anyway
/// (`min_tangent_eigenvalue`). The check's factor is another of K's size, which the memory
/// estimate does not count beside the solvers': up to here it stays within the estimate's
/// margin (newton on 46 × 46 modules, 19 047 free dofs: peak 71 → 93 MB, estimate 119 MB;
/// on 56 × 56 the margin, 29 MB, is below a factor, 47 MB).
pub const CHECKED_UP_TO_DOFS: usize = 20_000;

/// Where the run does not keep K's analysis (LATIN solvers alone), up to this many free dofs
/// the check makes its own (pattern, ordering and factor: 6.6 MB more at the peak of
/// micro-macro on 23 × 23 modules, 4 764 free dofs; 35 MB on 40 × 40, above its 82 MB
/// estimate); beyond, the rows are not checked.
pub const OWN_ANALYSIS_UP_TO_DOFS: usize = 5_000;

/// A motion of unit norm may stretch a cable at zero tension, or the load work on it, by this
/// much (a fraction of its size) and still count as free: the zero modes of `K_c` carry
/// round-off far below it, a cable that truly holds the motion far above it.
const FREE_TOLERANCE: f64 = 1e-6;

/// Iterations of the projected gradient for the shortest point of the cables' convex hull
/// (one candidate motion; every candidate is verified before it counts).
const HULL_ITERATIONS: usize = 500;

/// The most nodes a warning names.
const NAMED_NODES: usize = 3;

/// What the check found of an answer.
#[derive(Debug, Clone, PartialEq)]
pub enum Uniqueness {
    /// No motion keeps the energy constant: the answer is the only equilibrium.
    Unique,
    /// Other equilibria of the same energy exist along a free motion.
    NotUnique {
        /// The nodes the motion moves most (by id) with their motion, the motion of unit norm,
        /// largest first.
        nodes: Vec<(u64, [f64; 3])>,
    },
    /// `prestress`: the load works on a motion that the tangent of the answer's own tensions,
    /// `K_c + K_G(τ)`, does not resist and that stretches no cable at zero tension: no
    /// equilibrium of that tangent holds there (the solve's `K_G(t0)` keeps the slack cables'
    /// share, which the answer's tensions do not have). The row is not converged.
    LoadedFreeMotion {
        /// The nodes the motion moves most, as for [`Uniqueness::NotUnique`].
        nodes: Vec<(u64, [f64; 3])>,
    },
}

impl Uniqueness {
    /// Whether the answer is the only equilibrium (`summary.csv`'s `unique`).
    pub fn is_unique(&self) -> bool {
        matches!(self, Uniqueness::Unique)
    }

    /// `summary.csv`'s `unique`: `true`, `false`, or empty where the row is no equilibrium
    /// ([`Uniqueness::LoadedFreeMotion`]).
    pub fn column(&self) -> &'static str {
        match self {
            Uniqueness::Unique => "true",
            Uniqueness::NotUnique { .. } => "false",
            Uniqueness::LoadedFreeMotion { .. } => "",
        }
    }

    /// `1 (0.00, 1.00, 0.00), 4 (…)`: the nodes of a free motion; empty when unique.
    pub fn motion_nodes(&self) -> String {
        match self {
            Uniqueness::Unique => String::new(),
            Uniqueness::NotUnique { nodes } | Uniqueness::LoadedFreeMotion { nodes } => nodes
                .iter()
                .map(|(id, u)| {
                    // Rounded first, so that round-off reads 0.00, not -0.00.
                    let [x, y, z] = u.map(|c| (100.0 * c).round() / 100.0 + 0.0);
                    format!("{id} ({x:.2}, {y:.2}, {z:.2})")
                })
                .collect::<Vec<_>>()
                .join(", "),
        }
    }
}

/// The check of the equilibrium `eq` of `model` under `load` (free dofs). `pattern` is the
/// stiffness's pattern and `analysed` a factor analysed on it (only its symbolic part is used).
pub fn uniqueness(
    model: &Model,
    eq: &Equilibrium,
    load: &[f64],
    pattern: &StiffnessPattern,
    analysed: &SparseCholesky,
) -> Uniqueness {
    let s = &model.structure;
    if s.n_free == 0 {
        return Uniqueness::Unique;
    }
    let u = &eq.displacements;
    let trial = model.trial_tensions(u);
    let scale = gap_scale(s.links.iter().zip(trial.iter().copied()));
    let carrying: Vec<bool> = s
        .links
        .iter()
        .zip(&trial)
        .map(|(l, &t)| carries_force(l, t, scale))
        .collect();
    // With every member carrying force, K_c on the initial geometry without geometric
    // stiffness is K with every cable taut, regular by the set-up's mechanism check: nothing
    // to factorize.
    if !model.has_geometric_stiffness() && carrying.iter().all(|&c| c) {
        return Uniqueness::Unique;
    }
    // K_c: the tangent over the members that carry force (with `prestress`, plus the
    // geometric stiffness of the answer's own tensions K_G(τ), as the stability check,
    // `smallest_tangent_eigenvalue`, judges it: a slack cable none).
    let mut values = vec![0.0; pattern.nnz()];
    model.assemble_answer_tangent(u, &eq.tensions, |i| carrying[i], pattern, &mut values);
    let mut factor = analysed.share_symbolic();
    // Singular as `min_tangent_eigenvalue` calls it (below TANGENT_ZERO_RELATIVE of the mean
    // diagonal): under `prestress` and `large` a free motion's stiffness is round-off, not an
    // exact zero pivot, and a stricter test flipped `unique` from row to row.
    let relative = super::TANGENT_ZERO_RELATIVE;
    if !factorize_or_find_singular_below(pattern, &values, &mut factor, relative) {
        return Uniqueness::Unique;
    }
    let threshold = relative * pattern.mean_diagonal(&values);
    let null = null_basis(pattern, &values, &mut factor, threshold);
    // Per cable at zero tension with its gap closed: its elongation rate along a motion (the
    // rows of ∇ℓ with `large`).
    let rows = model.member_rows(u);
    let row = |i: usize| -> &SparseRow { &rows[i] };
    let at_zero_cables: Vec<usize> = (0..s.links.len())
        .filter(|&i| !carrying[i] && !gap_slack(&s.links[i], trial[i], scale))
        .collect();
    if model.prestress_stiffness().is_some() {
        if let Some(v) = loaded_motion(&null, load, &eq.tensions) {
            let held = at_zero_cables
                .iter()
                .any(|&i| row(i).elongation(&v).abs() > FREE_TOLERANCE);
            if !held {
                return Uniqueness::LoadedFreeMotion {
                    nodes: named_nodes(s, &v),
                };
            }
        }
    }
    let null = without_load_work(null, load, &eq.tensions);
    if null.is_empty() {
        return Uniqueness::Unique;
    }
    let at_zero: Vec<Vec<f64>> = at_zero_cables
        .iter()
        .map(|&i| {
            null.iter()
                .map(|v| row(i).elongation(v))
                .collect::<Vec<f64>>()
        })
        .filter(|g| norm(g) > FREE_TOLERANCE)
        .collect();
    match free_combination(&at_zero, null.len()) {
        None => Uniqueness::Unique,
        Some(c) => {
            let mut v = vec![0.0; s.n_free];
            for (basis, &w) in null.iter().zip(&c) {
                v.iter_mut().zip(basis).for_each(|(x, b)| *x += w * b);
            }
            Uniqueness::NotUnique {
                nodes: named_nodes(s, &v),
            }
        }
    }
}

/// The nodes the motion `v` moves most, with their motion, largest first.
fn named_nodes(s: &Structure, v: &[f64]) -> Vec<(u64, [f64; 3])> {
    let nodes = largest_moving_nodes(s, v, NAMED_NODES);
    let largest = nodes.first().map_or(0.0, |(_, m)| size(m));
    nodes
        .into_iter()
        // Round-off on the nodes the motion leaves in place is no motion.
        .filter(|(_, m)| size(m) >= FREE_TOLERANCE * largest)
        .collect()
}

/// The combination of `basis` (orthonormal) the load works on, of unit norm, where `F·v` is
/// beyond [`FREE_TOLERANCE`] of the forces at play; `None` where the load does no work on it.
fn loaded_motion(basis: &[Vec<f64>], load: &[f64], tensions: &[f64]) -> Option<Vec<f64>> {
    let work = load_work(basis, load, tensions)?;
    let size = norm(&work);
    let mut v = vec![0.0; basis[0].len()];
    for (b, w) in basis.iter().zip(&work) {
        v.iter_mut().zip(b).for_each(|(x, y)| *x += w / size * y);
    }
    Some(v)
}

fn size(m: &[f64; 3]) -> f64 {
    m[0].hypot(m[1]).hypot(m[2])
}

/// An orthonormal basis of the null space of the (singular) matrix `values`: the Ritz vectors of
/// eigenvalue within `threshold` (the tangent's zero) either way (at most
/// [`ZERO_MODES_COUNTED`]).
fn null_basis(
    pattern: &StiffnessPattern,
    values: &[f64],
    factor: &mut SparseCholesky,
    threshold: f64,
) -> Vec<Vec<f64>> {
    let n = pattern.n;
    let mut block = 8.min(n);
    loop {
        let eig = smallest_eigenvalues(pattern, values, factor, block, 30, 1e-3);
        let all_zero = eig.values.iter().all(|v| v.abs() <= threshold);
        if !all_zero || block >= n.min(ZERO_MODES_COUNTED) {
            return (0..eig.vectors.ncols())
                .filter(|&j| eig.values.get(j).is_some_and(|v| v.abs() <= threshold))
                .map(|j| eig.vectors.col(j).iter().copied().collect())
                .collect();
        }
        block = (2 * block).min(n).min(ZERO_MODES_COUNTED);
    }
}

/// `F·v` for each v of `basis`, where it is beyond [`FREE_TOLERANCE`] of the forces at play
/// (`‖F‖`, the largest tension); `None` where the load does no work on the span.
fn load_work(basis: &[Vec<f64>], load: &[f64], tensions: &[f64]) -> Option<Vec<f64>> {
    let forces = norm(load).max(tensions.iter().fold(0.0f64, |m, t| m.max(t.abs())));
    let work: Vec<f64> = basis.iter().map(|v| dot(load, v)).collect();
    (!basis.is_empty() && norm(&work) > FREE_TOLERANCE * forces).then_some(work)
}

/// The part of the span of `basis` (orthonormal) the load does no work on: all of it when
/// `F·v` is within [`FREE_TOLERANCE`] of the forces at play (`‖F‖`, the largest tension) for
/// every v, else the complement of the one combination it works on.
fn without_load_work(basis: Vec<Vec<f64>>, load: &[f64], tensions: &[f64]) -> Vec<Vec<f64>> {
    let Some(work) = load_work(basis.as_slice(), load, tensions) else {
        return basis;
    };
    // The coefficient vectors orthogonal to `work`, orthonormalised (Gram–Schmidt).
    let m = basis.len();
    let mut kept: Vec<Vec<f64>> = vec![normalised(work)];
    for j in 0..m {
        let mut c: Vec<f64> = (0..m).map(|k| if k == j { 1.0 } else { 0.0 }).collect();
        for q in &kept {
            let p = dot(&c, q);
            c.iter_mut().zip(q).for_each(|(x, y)| *x -= p * y);
        }
        if norm(&c) > 1e-8 {
            kept.push(normalised(c));
        }
    }
    kept.iter()
        .skip(1)
        .map(|c| {
            let mut v = vec![0.0; basis[0].len()];
            for (b, &w) in basis.iter().zip(c) {
                v.iter_mut().zip(b).for_each(|(x, y)| *x += w * y);
            }
            v
        })
        .collect()
}

fn normalised(mut v: Vec<f64>) -> Vec<f64> {
    let n = norm(&v);
    v.iter_mut().for_each(|x| *x /= n);
    v
}

/// Coefficients c (unit norm) of a motion `Σ c_j v_j` that stretches none of the cables whose
/// rates along the basis are `rows` (`g·c ≤ FREE_TOLERANCE` for every g), or `None` when none of
/// the candidates does: the rates' null space and principal directions (either sign), each basis
/// motion (either sign), and the direction opposite the shortest point of the rows' convex hull
/// (which shortens every cable when that point is not 0). A candidate counts only once verified,
/// so a motion is never called free that is not.
fn free_combination(rows: &[Vec<f64>], m: usize) -> Option<Vec<f64>> {
    let unit = |j: usize| -> Vec<f64> { (0..m).map(|k| if k == j { 1.0 } else { 0.0 }).collect() };
    if rows.is_empty() {
        return Some(unit(0));
    }
    let frees = |c: &[f64]| rows.iter().all(|g| dot(g, c) <= FREE_TOLERANCE);
    // GᵀG: its eigenvectors are the rates' principal directions, ascending (null space first).
    let gram = DMatrix::from_fn(m, m, |i, j| rows.iter().map(|g| g[i] * g[j]).sum::<f64>());
    let eig = SymmetricEigen::new(gram);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let mut candidates: Vec<Vec<f64>> = order
        .iter()
        .map(|&j| eig.eigenvectors.column(j).iter().copied().collect())
        .chain((0..m).map(unit))
        .collect();
    let largest = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    if let Some(w) = shortest_hull_point(rows, m, largest) {
        candidates.push(w.iter().map(|x| -x).collect());
    }
    for c in candidates {
        if norm(&c) == 0.0 {
            continue;
        }
        let c = normalised(c);
        if frees(&c) {
            return Some(c);
        }
        let opposite: Vec<f64> = c.iter().map(|x| -x).collect();
        if frees(&opposite) {
            return Some(opposite);
        }
    }
    None
}

/// `w = Gᵀ y` for the y on the simplex that makes it shortest (projected gradient, step 1/L with
/// `L = λ_max(GᵀG)`): the point of the rows' convex hull nearest 0. `None` when it is 0 (to
/// round-off), where no motion shortens every cable.
fn shortest_hull_point(rows: &[Vec<f64>], m: usize, lipschitz: f64) -> Option<Vec<f64>> {
    if lipschitz <= 0.0 {
        return None;
    }
    let p = rows.len();
    let mut y = vec![1.0 / p as f64; p];
    let hull_point = |y: &[f64]| -> Vec<f64> {
        let mut w = vec![0.0; m];
        for (g, &yi) in rows.iter().zip(y) {
            w.iter_mut().zip(g).for_each(|(x, gi)| *x += yi * gi);
        }
        w
    };
    for _ in 0..HULL_ITERATIONS {
        let w = hull_point(&y);
        // ∇ ½‖Gᵀy‖² = G Gᵀ y.
        let step: Vec<f64> = rows
            .iter()
            .zip(&y)
            .map(|(g, &yi)| yi - dot(g, &w) / lipschitz)
            .collect();
        y = onto_simplex(step);
    }
    let w = hull_point(&y);
    (norm(&w) > FREE_TOLERANCE).then_some(w)
}

/// The Euclidean projection of `v` onto the simplex `{y ≥ 0, Σ y = 1}` (sort and threshold).
fn onto_simplex(v: Vec<f64>) -> Vec<f64> {
    let mut sorted = v.clone();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let mut sum = 0.0;
    let mut shift = 0.0;
    for (k, &x) in sorted.iter().enumerate() {
        sum += x;
        let t = (sum - 1.0) / (k + 1) as f64;
        if x - t > 0.0 {
            shift = t;
        }
    }
    v.into_iter().map(|x| (x - shift).max(0.0)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_motion_is_free_when_no_cable_at_zero_is_stretched_by_it() {
        // One cable in a plane of motions: the one across it leaves it alone.
        let c = free_combination(&[vec![1.0, 1.0]], 2).unwrap();
        assert!(
            (c[0] + c[1]).abs() < 1e-12 && (norm(&c) - 1.0).abs() < 1e-12,
            "{c:?}"
        );
        // One cable along the only motion: the sign that shortens it.
        assert_eq!(free_combination(&[vec![0.5]], 1), Some(vec![-1.0]));
        // Two cables opposite each other along e0: e1 is free (it touches neither).
        let c = free_combination(&[vec![1.0, 0.0], vec![-1.0, 0.0]], 2).unwrap();
        assert!(
            c[0].abs() < 1e-12 && (c[1].abs() - 1.0).abs() < 1e-12,
            "{c:?}"
        );
        // Three cables around the plane hold every motion of it.
        let around = [vec![1.0, 0.0], vec![0.0, 1.0], vec![-1.0, -1.0]];
        assert_eq!(free_combination(&around, 2), None);
        // Three cables that no basis motion nor principal direction leaves unstretched (GᵀG is
        // 2.25 I): the hull's shortest point, (0.25, 0.25), gives −(1, 1)/√2, which shortens all.
        let rows = [vec![1.0, -0.5], vec![-0.5, 1.0], vec![1.0, 1.0]];
        let c = free_combination(&rows, 2).unwrap();
        assert!((c[0] - c[1]).abs() < 1e-6 && c[0] < 0.0, "{c:?}");
    }

    #[test]
    fn projection_onto_the_simplex() {
        let y = onto_simplex(vec![0.5, 0.5, 0.5]);
        assert!(y.iter().all(|&x| (x - 1.0 / 3.0).abs() < 1e-15), "{y:?}");
        let y = onto_simplex(vec![2.0, 0.0]);
        assert_eq!(y, vec![1.0, 0.0]);
    }
}
