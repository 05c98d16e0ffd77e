//! Re-balancing a nearly balanced members-table prestress (issue 46; `tensolve design
//! --rebalance` only, never `run`): coordinates rounded to 1 mm leave a valid design's prestress
//! slightly out of equilibrium; its least-squares projection on the self-stress states is the
//! nearest balanced one, and the largest change is reported.

use super::design::{groups, Design, GroupForce};
use super::CaseError;
use crate::structure::{
    equilibrium_counts, project_on_self_stress, Fit, Geometry, NodeFix, Structure,
};

/// Replace `geometry`'s prestress by its projection on the self-stress states; the report
/// says the largest change and the member it is on.
pub(super) fn apply(geometry: &mut Geometry, fixes: &[NodeFix]) -> Result<Design, CaseError> {
    let structure = Structure::new(geometry, &NodeFix::unsettled(fixes), &Default::default());
    let t0: Vec<f64> = geometry.members.iter().map(|m| m.prestress).collect();
    let Some(t) = project_on_self_stress(&structure, &t0) else {
        return Err(CaseError::invalid(
            "--rebalance",
            "given",
            "re-balancing a structure with mechanisms takes at most 1500 free dofs (a dense pseudo-inverse): hold more components, or balance the table's prestress elsewhere",
        ));
    };
    // The largest change, and where.
    let (j, change) =
        t.iter()
            .zip(&t0)
            .map(|(a, b)| a - b)
            .enumerate()
            .fold((0, 0.0f64), |best, (j, d)| {
                if d.abs() > best.1.abs() {
                    (j, d)
                } else {
                    best
                }
            });
    for (m, &tj) in geometry.members.iter_mut().zip(&t) {
        m.prestress = tj;
    }
    let groups = groups(geometry)?;
    Ok(Design {
        flat: None,
        counts: equilibrium_counts(&structure),
        grouped_states: 0,
        gap: (None, None),
        fit: Fit::Rebalanced,
        groups: groups
            .into_iter()
            .map(|(name, members, kind)| GroupForce {
                // The force of the member of largest |t|.
                force: members
                    .iter()
                    .map(|&i| geometry.members[i].prestress)
                    .fold(0.0f64, |m, x| if x.abs() > m.abs() { x } else { m }),
                name,
                members,
                kind,
                given: None,
            })
            .collect(),
        min_cable: 0.0,
        rebalanced: Some((change, geometry.members[j].id)),
    })
}
