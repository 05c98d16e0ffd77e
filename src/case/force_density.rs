//! `[prestress] from = "force-density"` (issue 46, docs/method.md §7 "Designing a prestress"):
//! Schek's force density method. With `q_j = t_j / ℓ_j` given per group, a free node's
//! equilibrium `Σ_j q_j (x_other − x_node) = 0` is linear in the positions: the weighted
//! Laplacian `L = Cᵀ Q C` at the free nodes solves `L_ff x_f = −L_fa x_a` once (one sparse LU,
//! three right-hand sides), the anchors `a` staying where the nodes table puts them. Then
//! `t_j = q_j ℓ_j`. With mixed signs (a tensegrity's bars) `L_ff` may be singular: the rank
//! condition is checked, and a singular one is refused.

use super::design::{groups, Design, GroupForce};
use super::numbers::{bounded, number, PHYSICAL_MAX};
use super::raw::RawPrestress;
use super::CaseError;
use crate::structure::{
    equilibrium_counts, grouped_states, length_and_direction, Fit, Geometry, LinkKind, NodeFix,
    Structure,
};
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use std::collections::BTreeMap;

/// The key of the force densities.
const KEY: &str = "prestress.force_density";

/// Residual of the Laplacian solve, relative to the right-hand side and the solution's
/// scale, above which `L_ff` counts as singular (the rank condition fails).
const SINGULAR_RESIDUAL: f64 = 1e-8;

/// Place the free nodes of `geometry` by the force densities of `raw.force_density` and set
/// the members' prestress `t = q ℓ` (see the module).
pub(super) fn apply(
    raw: &RawPrestress,
    geometry: &mut Geometry,
    fixes: &[NodeFix],
) -> Result<Design, CaseError> {
    // 1. A force density for every group, non-zero.
    let groups = groups(geometry)?;
    let q = densities(raw, &groups, geometry.members.len())?;
    // 2. Anchors: the nodes with a held component; the others are free.
    let mut anchored = vec![false; geometry.nodes.len()];
    fixes
        .iter()
        .filter(|f| f.dofs.iter().any(|&d| d))
        .for_each(|f| anchored[f.node] = true);
    let free: Vec<usize> = (0..geometry.nodes.len())
        .filter(|&i| !anchored[i])
        .collect();
    // 3. One sparse solve for the free positions.
    let positions = solve_positions(geometry, &q, &anchored, &free)?;
    for (r, &i) in free.iter().enumerate() {
        geometry.nodes[i] = positions[r];
    }
    // 4. The forces t = q ℓ, in the form found.
    for (j, m) in geometry.members.iter_mut().enumerate() {
        let (length, _) = length_and_direction(geometry.nodes[m.a], geometry.nodes[m.b]);
        if length <= 1e-12 {
            return Err(CaseError::invalid(
                KEY,
                format!("member {} of zero length in the form found", m.id),
                "its ends land on one point: change the force densities, or anchor one of its nodes",
            ));
        }
        m.prestress = q[j] * length;
    }
    Ok(report(geometry, fixes, groups, &q))
}

/// Per member, the force density of its group (N/m), each group given one.
fn densities(
    raw: &RawPrestress,
    groups: &[(String, Vec<usize>, LinkKind)],
    members: usize,
) -> Result<Vec<f64>, CaseError> {
    let given = raw.force_density.clone().unwrap_or_default();
    let mut q = vec![0.0; members];
    for (name, value) in &given {
        let key = format!("{KEY}.{name}");
        bounded(
            &key,
            *value,
            PHYSICAL_MAX,
            "the group's force density in N/m",
        )?;
        let Some(g) = groups.iter().find(|g| &g.0 == name) else {
            return Err(CaseError::invalid(
                key,
                number(*value),
                format!("there is no group \"{name}\": name a label of the members table's `group` column (a member id without it)"),
            ));
        };
        if *value == 0.0 {
            return Err(CaseError::invalid(
                key,
                "0",
                "give a non-zero force density in N/m (tension > 0, compression < 0)",
            ));
        }
        g.1.iter().for_each(|&j| q[j] = *value);
    }
    let missing: Vec<&str> = groups
        .iter()
        .filter(|g| !given.contains_key(&g.0))
        .take(10)
        .map(|g| g.0.as_str())
        .collect();
    if !missing.is_empty() {
        return Err(CaseError::invalid(
            KEY,
            format!("no force density for group(s) {}", missing.join(", ")),
            "give every group its force density q = t/ℓ in N/m: `force_density = { <group> = <q> }`",
        ));
    }
    Ok(q)
}

/// The free nodes' positions from `L_ff x_f = −L_fa x_a` (sparse LU), refused when `L_ff` is
/// singular (the rank condition) or a free node is joined to nothing.
fn solve_positions(
    geometry: &Geometry,
    q: &[f64],
    anchored: &[bool],
    free: &[usize],
) -> Result<Vec<[f64; 3]>, CaseError> {
    let mut row_of = vec![usize::MAX; geometry.nodes.len()];
    free.iter().enumerate().for_each(|(r, &i)| row_of[i] = r);
    let n = free.len();
    let mut entries: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    let mut rhs = Mat::<f64>::zeros(n, 3);
    // L = Cᵀ Q C member by member: +q on both diagonals, −q off them.
    for (m, &qj) in geometry.members.iter().zip(q) {
        for (p, o) in [(m.a, m.b), (m.b, m.a)] {
            if anchored[p] {
                continue;
            }
            let r = row_of[p];
            *entries.entry((r, r)).or_insert(0.0) += qj;
            if anchored[o] {
                (0..3).for_each(|k| rhs[(r, k)] += qj * geometry.nodes[o][k]);
            } else {
                *entries.entry((r, row_of[o])).or_insert(0.0) -= qj;
            }
        }
    }
    let singular = |why: String| {
        CaseError::invalid(
            KEY,
            "{ … }",
            format!("the rank condition fails: the force-density Laplacian at the {n} free node(s) is singular ({why}), so the free nodes have no unique position: anchor more nodes ([[supports.fix]]), or change the densities (with mixed signs, the bars' q must not cancel the cables' at any node)"),
        )
    };
    if n == 0 {
        return Ok(Vec::new());
    }
    let triplets: Vec<Triplet<usize, usize, f64>> = entries
        .iter()
        .map(|(&(row, col), &val)| Triplet { row, col, val })
        .collect();
    let laplacian = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| singular(format!("{e:?}")))?;
    let lu = laplacian
        .sp_lu()
        .map_err(|e| singular(format!("the LU stopped: {e:?}")))?;
    let x = lu.solve(&rhs);
    // The rank condition, checked: a finite solution that solves the system.
    let residual = &laplacian * &x - &rhs;
    let size = (0..n)
        .flat_map(|r| (0..3).map(move |k| (r, k)))
        .fold(0.0f64, |m, (r, k)| {
            m.max(x[(r, k)].abs()).max(rhs[(r, k)].abs())
        });
    let qmax = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = (0..n)
        .flat_map(|r| (0..3).map(move |k| (r, k)))
        .fold(0.0f64, |m, (r, k)| m.max(residual[(r, k)].abs()));
    // A NaN residual fails too: `worst <= …` is false.
    let solved = worst <= SINGULAR_RESIDUAL * qmax * size.max(1.0);
    if !size.is_finite() || !solved {
        // Non-finite positions have no residual to quote (it read "a residual of 0").
        let why = match size.is_finite() {
            true => format!("the solve leaves a residual of {}", number(worst)),
            false => "the solve gives positions that are not finite".to_string(),
        };
        return Err(singular(why));
    }
    Ok((0..n).map(|r| [x[(r, 0)], x[(r, 1)], x[(r, 2)]]).collect())
}

/// The report of a form-finding: the counts of the form found and each group's largest force.
fn report(
    geometry: &Geometry,
    fixes: &[NodeFix],
    groups: Vec<(String, Vec<usize>, LinkKind)>,
    q: &[f64],
) -> Design {
    let structure = Structure::new(geometry, &NodeFix::unsettled(fixes), &Default::default());
    let mut group_of = vec![0; geometry.members.len()];
    groups
        .iter()
        .enumerate()
        .for_each(|(k, g)| g.1.iter().for_each(|&j| group_of[j] = k));
    let states = grouped_states(&structure, &group_of, groups.len()).ok();
    Design {
        counts: equilibrium_counts(&structure),
        grouped_states: states.as_ref().map_or(0, |s| s.count()),
        gap: states.map_or((None, None), |s| s.gap),
        fit: Fit::ForceDensity,
        groups: groups
            .into_iter()
            .map(|(name, members, kind)| {
                // The force of the member of largest |t| (t = qℓ varies along a group).
                let force = members
                    .iter()
                    .map(|&j| geometry.members[j].prestress)
                    .fold(0.0f64, |m, t| if t.abs() > m.abs() { t } else { m });
                let density = q[members[0]];
                GroupForce {
                    name,
                    members,
                    kind,
                    force,
                    given: Some(density),
                }
            })
            .collect(),
        min_cable: 0.0,
        rebalanced: None,
        flat: flatness(&geometry.nodes).filter(|&spread| spread <= FLAT_RELATIVE),
    }
}

/// A form whose nodes lie within this fraction of its size of one plane is flat.
const FLAT_RELATIVE: f64 = 1e-9;

/// The spread of `nodes` off their best plane, relative to their extent: the square root of
/// the smallest eigenvalue of their covariance over that of the largest. A form found by
/// force densities places each free node at a weighted mean of its neighbours, so anchors in
/// one plane give a form in that plane, whatever the densities (issue 57, N-D11: a prism and a
/// net came back flat, called stable, without a word).
fn flatness(nodes: &[[f64; 3]]) -> Option<f64> {
    if nodes.len() < 4 {
        return None;
    }
    let n = nodes.len() as f64;
    let mean: Vec<f64> = (0..3)
        .map(|k| nodes.iter().map(|p| p[k]).sum::<f64>() / n)
        .collect();
    let covariance = nalgebra::Matrix3::from_fn(|i, j| {
        nodes
            .iter()
            .map(|p| (p[i] - mean[i]) * (p[j] - mean[j]))
            .sum::<f64>()
            / n
    });
    let values = covariance.symmetric_eigenvalues();
    let largest = values.max();
    (largest > 0.0).then(|| (values.min().max(0.0) / largest).sqrt())
}
