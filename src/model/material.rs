//! The member law (docs/method.md §1): the trial tension `t0 + k e`, the tension (clipped at 0
//! for unilateral cables), the tangent weight, and the slack classification with its two
//! rules. A property of each member alone, whatever the kinematics: every solver and
//! `results` ask here; nothing else writes the law.

use crate::structure::{Link, Structure};

/// Relative tolerance of the one slack classification ([`SlackRule::Gap`]): a unilateral cable
/// is slack when its gap is open, `λ = −(e + t0/k) > 0`, by more than this fraction of the
/// cables' force scale, i.e. when its trial tension
/// `t0 + k e < −SLACK_GAP_TOLERANCE · max_cables(|t0|, |t0 + k e|)`. A cable at zero tension
/// with a closed gap (an unprestressed cable at rest) is taut. 1e-6 lies well above the
/// round-off of an exact solution (1e-12 of the scale) and well below the trial tension of any
/// cable that is slack on the paper's grids (> 1e-3 of the scale).
pub const SLACK_GAP_TOLERANCE: f64 = 1e-6;

/// The trial tension `t0 + k e` of a member at elongation e (before a cable's clipping).
#[inline]
pub fn trial_tension(link: &Link, elongation: f64) -> f64 {
    link.prestress + link.stiffness * elongation
}

/// τ: the trial tension, clipped at 0 for a unilateral cable (`τ = max(0, t0 + k e)`).
#[inline]
pub fn tension(link: &Link, trial: f64) -> f64 {
    if link.unilateral {
        trial.max(0.0)
    } else {
        trial
    }
}

/// Whether the member carries its axial stiffness at this trial tension: bars and bilateral
/// cables always, unilateral cables when `t0 + k e ≥ 0`.
#[inline]
pub fn is_taut(link: &Link, trial: f64) -> bool {
    !link.unilateral || trial >= 0.0
}

/// The axial tangent weight: k when taut, 0 when slack.
#[inline]
pub fn tangent_weight(link: &Link, trial: f64) -> f64 {
    if is_taut(link, trial) {
        link.stiffness
    } else {
        0.0
    }
}

/// Which unilateral cables count as slack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlackRule {
    /// The energy's own clipping: the tension is exactly 0 (`t0 + k e ≤ 0`). What newton
    /// follows along its steps.
    Clipped,
    /// The one classification every reported answer shares: the gap is open by more than
    /// [`SLACK_GAP_TOLERANCE`] of the cables' force scale.
    Gap,
}

/// Whether `link` with trial tension `trial` is slack by [`SlackRule::Gap`] against the cables'
/// force `scale`: a unilateral cable whose `t0 + k e` lies below −[`SLACK_GAP_TOLERANCE`] of it.
pub fn gap_slack(link: &Link, trial: f64, scale: f64) -> bool {
    link.unilateral && trial < -SLACK_GAP_TOLERANCE * scale
}

/// Whether `link` carries force at trial tension `trial` by the gap rule's zero against the
/// cables' force `scale`: bars and bilateral cables always; a unilateral cable when
/// `t0 + k e > SLACK_GAP_TOLERANCE · scale`. A cable within that zero either way has its gap
/// closed and no force: [`gap_slack`] does not call it slack, yet it resists only elongation
/// (what the uniqueness check, `crate::results::uniqueness`, treats it as, whichever solver
/// found it).
pub fn carries_force(link: &Link, trial: f64, scale: f64) -> bool {
    !link.unilateral || trial > SLACK_GAP_TOLERANCE * scale
}

/// The cables' force scale of [`SlackRule::Gap`] over `links` with their trial tensions:
/// `max(|t0|, |t0 + k e|)` over the unilateral cables (0 without any). A maximum, so the scale
/// of several groups of links is the largest of theirs.
pub fn gap_scale<'a>(links: impl Iterator<Item = (&'a Link, f64)>) -> f64 {
    links
        .filter(|(l, _)| l.unilateral)
        .fold(0.0f64, |m, (l, t)| m.max(l.prestress.abs()).max(t.abs()))
}

/// Per link: a unilateral cable that is slack by `rule`, from the trial tensions.
pub fn slack_flags(s: &Structure, trial: &[f64], rule: SlackRule) -> Vec<bool> {
    match rule {
        SlackRule::Clipped => s
            .links
            .iter()
            .zip(trial)
            .map(|(l, &t)| l.unilateral && tension(l, t) == 0.0)
            .collect(),
        SlackRule::Gap => {
            let scale = gap_scale(s.links.iter().zip(trial.iter().copied()));
            s.links
                .iter()
                .zip(trial)
                .map(|(l, &t)| gap_slack(l, t, scale))
                .collect()
        }
    }
}
