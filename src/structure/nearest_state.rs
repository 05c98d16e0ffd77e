//! The grouped self-stress state nearest to a design intent (docs/method.md §7, "Designing a
//! prestress"): `x = N y` (N an orthonormal basis of the grouped states, one force per group)
//! with the targeted groups `x_T` at their targets `τ`, cables at least their least tension and
//! bars not in tension. With as many independent targets as states it is one small solve;
//! otherwise a quadratic programme (clarabel): minimise `‖N_T y − τ‖² + ε‖y‖²` subject to the
//! signs, then polished so that the targets and the active bounds hold to round-off.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};
use nalgebra::{DMatrix, DVector};

/// A weight ε (relative to unit targets) on `‖y‖²` that keeps the fit's matrix positive
/// definite; the least-norm tie-break itself is the programme's second stage.
const TIE_BREAK: f64 = 1e-10;

/// A bound or a target within this fraction of the design's scale counts as met (the
/// interior-point solver's accuracy is about 1e-8).
pub const MET_RELATIVE: f64 = 1e-6;

/// How the state was fixed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fit {
    /// As many independent targets as states: one solve.
    Direct,
    /// The quadratic programme (fewer or more targets, or dependent ones).
    QuadraticProgramme,
    /// No fit: the form found by force densities (`prestress.from = "force-density"`).
    ForceDensity,
    /// No fit: the table's prestress projected on the self-stress states (`--rebalance`).
    Rebalanced,
}

impl Fit {
    /// Said in the report.
    pub fn name(self) -> &'static str {
        match self {
            Fit::Direct => "direct (as many independent targets as states)",
            Fit::QuadraticProgramme => "nearest state under the signs (quadratic programme)",
            Fit::ForceDensity => "form found by force densities (one sparse solve)",
            Fit::Rebalanced => {
                "the members table's, projected on the self-stress states (least squares)"
            }
        }
    }
}

/// What each group must satisfy: at least `lower`, at most `upper` (either optional).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bounds {
    /// The least force, N (a cable's least tension).
    pub lower: Option<f64>,
    /// The largest force, N (0 for a bar).
    pub upper: Option<f64>,
}

/// The state nearest to `targets` (group, force) in the span of `basis` (s₂ vectors of one
/// force per group) within `bounds` (one per group); `None` when the programme has no
/// solution (the bounds alone cannot hold). The caller checks what is met.
pub fn nearest_state(
    basis: &[Vec<f64>],
    targets: &[(usize, f64)],
    bounds: &[Bounds],
) -> Option<(Vec<f64>, Fit)> {
    let s2 = basis.len();
    let groups = bounds.len();
    // Unit scale: the largest target or bound.
    let scale = targets
        .iter()
        .map(|t| t.1.abs())
        .chain(
            bounds
                .iter()
                .flat_map(|b| [b.lower, b.upper])
                .flatten()
                .map(f64::abs),
        )
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let n_t = DMatrix::from_fn(targets.len(), s2, |r, c| basis[c][targets[r].0]);
    let tau = DVector::from_iterator(targets.len(), targets.iter().map(|t| t.1 / scale));
    let state_of = |y: &DVector<f64>| -> Vec<f64> {
        (0..groups)
            .map(|k| scale * (0..s2).map(|c| basis[c][k] * y[c]).sum::<f64>())
            .collect()
    };
    if targets.len() == s2 && s2 > 0 {
        let svd = n_t.clone().svd(true, true);
        let largest = svd.singular_values.max();
        if svd.singular_values.min() > 1e-8 * largest {
            let y = svd.solve(&tau, 0.0).ok()?;
            return Some((state_of(&y), Fit::Direct));
        }
    }
    let y = programme(basis, &n_t, &tau, bounds, scale)?;
    let y = polish(basis, &n_t, &tau, bounds, scale, y);
    Some((state_of(&y), Fit::QuadraticProgramme))
}

/// The programme in two stages, in unit scale: first the best fit `z* = N_T y₁` of
/// `min ‖N_T y − τ‖²` under the bounds; then, among the states fitting as well (`N_T y = z*`,
/// the bounds), the one of least norm `‖y‖ = ‖x‖` — the tie-break a single weighted objective
/// leaves to the solver's tolerance. Stage 2 not solved: stage 1's answer.
fn programme(
    basis: &[Vec<f64>],
    n_t: &DMatrix<f64>,
    tau: &DVector<f64>,
    bounds: &[Bounds],
    scale: f64,
) -> Option<DVector<f64>> {
    let s2 = basis.len();
    let p = n_t.transpose() * n_t + DMatrix::identity(s2, s2) * TIE_BREAK;
    let q = -(n_t.transpose() * tau);
    let fit = solve_qp(basis, &p, &q, None, bounds, scale)?;
    let z = n_t * &fit;
    let least = solve_qp(
        basis,
        &DMatrix::identity(s2, s2),
        &DVector::zeros(s2),
        Some((n_t, &z)),
        bounds,
        scale,
    );
    Some(least.unwrap_or(fit))
}

/// `y` of `min ½ yᵀ P y + qᵀ y` subject to `E y = e` (when given), `N_k y ≥ lower_k / scale`
/// and `N_k y ≤ upper_k / scale` (clarabel); `None` when it is not solved.
fn solve_qp(
    basis: &[Vec<f64>],
    p: &DMatrix<f64>,
    q: &DVector<f64>,
    equality: Option<(&DMatrix<f64>, &DVector<f64>)>,
    bounds: &[Bounds],
    scale: f64,
) -> Option<DVector<f64>> {
    let s2 = basis.len();
    // P's upper triangle, as clarabel takes it.
    let (mut pi, mut pj, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..s2 {
        for i in 0..=j {
            pi.push(i);
            pj.push(j);
            pv.push(p[(i, j)]);
        }
    }
    let p = CscMatrix::new_from_triplets(s2, s2, pi, pj, pv);
    // A y + s = b: s = 0 on the equalities, then s ≥ 0: −N_k y ≤ −lower_k, N_k y ≤ upper_k.
    let (mut ai, mut aj, mut av, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut cones = Vec::new();
    if let Some((e, values)) = equality {
        for r in 0..e.nrows() {
            for c in 0..s2 {
                ai.push(b.len());
                aj.push(c);
                av.push(e[(r, c)]);
            }
            b.push(values[r]);
        }
        cones.push(ZeroConeT(e.nrows()));
    }
    let inequalities = b.len();
    for (k, bound) in bounds.iter().enumerate() {
        for (limit, sign) in [(bound.lower, -1.0), (bound.upper, 1.0)] {
            if let Some(limit) = limit {
                let row = b.len();
                for (c, v) in basis.iter().enumerate() {
                    ai.push(row);
                    aj.push(c);
                    av.push(sign * v[k]);
                }
                b.push(sign * limit / scale);
            }
        }
    }
    cones.push(NonnegativeConeT(b.len() - inequalities));
    let a = CscMatrix::new_from_triplets(b.len(), s2, ai, aj, av);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .ok()?;
    let q: Vec<f64> = q.iter().copied().collect();
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
    solver.solve();
    matches!(
        solver.solution.status,
        SolverStatus::Solved | SolverStatus::AlmostSolved
    )
    .then(|| DVector::from_vec(solver.solution.x.clone()))
}

/// `y` moved least so that the targets and the bounds `y` nearly meets (within
/// [`MET_RELATIVE`]) hold exactly: `y + M⁺(r − M y)`, M those rows, r their values.
fn polish(
    basis: &[Vec<f64>],
    n_t: &DMatrix<f64>,
    tau: &DVector<f64>,
    bounds: &[Bounds],
    scale: f64,
    y: DVector<f64>,
) -> DVector<f64> {
    let s2 = basis.len();
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut values: Vec<f64> = Vec::new();
    let near = |a: f64, b: f64| (a - b).abs() <= MET_RELATIVE;
    for r in 0..n_t.nrows() {
        let row: Vec<f64> = n_t.row(r).iter().copied().collect();
        let at = row.iter().zip(y.iter()).map(|(a, b)| a * b).sum::<f64>();
        if near(at, tau[r]) {
            rows.push(row);
            values.push(tau[r]);
        }
    }
    for (k, bound) in bounds.iter().enumerate() {
        let row: Vec<f64> = basis.iter().map(|v| v[k]).collect();
        let at = row.iter().zip(y.iter()).map(|(a, b)| a * b).sum::<f64>();
        for limit in [bound.lower, bound.upper].into_iter().flatten() {
            if near(at, limit / scale) {
                rows.push(row.clone());
                values.push(limit / scale);
            }
        }
    }
    if rows.is_empty() {
        return y;
    }
    let m = DMatrix::from_fn(rows.len(), s2, |r, c| rows[r][c]);
    let r = DVector::from_vec(values) - &m * &y;
    let svd = m.svd(true, true);
    // Singular values below 1e-10 of the largest: dependent rows (a target on a bound).
    let eps = 1e-10 * svd.singular_values.max();
    match svd.solve(&r, eps) {
        Ok(step) => y + step,
        Err(_) => y,
    }
}
