//! Exact line search on the energy (docs/method.md §3): `φ(s) = Π(U + sΔU)` is a piecewise quadratic in
//! s, its derivative piecewise linear and non-decreasing, with a breakpoint wherever a
//! unilateral cable changes state; the minimiser is found by walking the breakpoints in order.

use crate::structure::Link;
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

/// A breakpoint of φ': at `position`, the curvature changes by `change`.
#[derive(Debug, Clone, Copy)]
struct Breakpoint {
    position: f64,
    change: f64,
}

// Ordered by position alone (`total_cmp`): breakpoints at the same position may come in any
// order, which does not change the minimiser (φ' is the same there whatever the order).
impl PartialEq for Breakpoint {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Breakpoint {}
impl PartialOrd for Breakpoint {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Breakpoint {
    fn cmp(&self, other: &Self) -> Ordering {
        self.position.total_cmp(&other.position)
    }
}

/// Exact minimiser `s > 0` of `φ(s) = Π(U + s ΔU)`, from each link's trial tension at U
/// (`t0 + k e`, before clipping) and its elongation along the step (`B ΔU`), and the work of
/// the load along the step `Fᵀ ΔU`, and a quadratic term of the model (docs/method.md §8:
/// `geometric = (ΔUᵀK_G U, ΔUᵀK_G ΔU)`, zero without geometric stiffness). `None` when ΔU is not a descent direction (φ'(0) ≥ 0) or
/// φ has no minimiser along it.
pub(crate) fn exact_line_search(
    links: &[Link],
    trial: &[f64],
    step_elongation: &[f64],
    load_work: f64,
    geometric: (f64, f64),
) -> Option<f64> {
    // φ'(s) = Σ_taut τ_i(s) Δe_i + ΔUᵀK_G(U + sΔU) − Fᵀ ΔU, τ_i(s) = a_i + s b_i.
    let mut slope_value = geometric.0 - load_work;
    let mut curvature = geometric.1;
    let mut events: Vec<Reverse<Breakpoint>> = Vec::new();
    let mut event = |position: f64, change: f64| {
        events.push(Reverse(Breakpoint { position, change }));
    };
    for ((l, &a), &de) in links.iter().zip(trial).zip(step_elongation) {
        let b = l.stiffness * de;
        let c = l.stiffness * de * de;
        if !l.unilateral {
            slope_value += a * de;
            curvature += c;
            continue;
        }
        let active = a > 0.0 || (a == 0.0 && b > 0.0);
        if active {
            slope_value += a * de;
            curvature += c;
            if b < 0.0 {
                // Goes slack at s = −a/b: its curvature leaves.
                event(-a / b, -c);
            }
        } else if b > 0.0 {
            // Becomes taut at s = −a/b.
            event(-a / b, c);
        }
    }
    walk(slope_value, curvature, events)
}

/// Where the energy along a step has its minimiser (docs/method.md §3), substructure by
/// substructure: each gives its links' part of φ'(0), of the curvature and its breakpoints up
/// to `s = 1` ([`EnergyAlongStep::of_links`]); the parts are added in the substructures'
/// order ([`EnergyAlongStep::add`]), on any number of processes alike. For callers that take
/// `min(s, 1)`: a breakpoint beyond 1 cannot move a minimiser below 1.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct EnergyAlongStep {
    /// φ'(0) of these links.
    pub slope: f64,
    /// φ''(0⁺) of these links.
    pub curvature: f64,
    /// (position, change of curvature) of each breakpoint at a position ≤ 1.
    pub breakpoints: Vec<(f64, f64)>,
}

impl EnergyAlongStep {
    /// The part of the links `(link, trial tension at U, elongation along ΔU)`.
    pub(crate) fn of_links<'a>(links: impl Iterator<Item = (&'a Link, f64, f64)>) -> Self {
        let mut part = EnergyAlongStep::default();
        for (l, a, de) in links {
            let b = l.stiffness * de;
            let c = l.stiffness * de * de;
            let active = !l.unilateral || a > 0.0 || (a == 0.0 && b > 0.0);
            if active {
                part.slope += a * de;
                part.curvature += c;
            }
            // A taut cable going slack (its curvature leaves) or a slack one becoming taut.
            let turns = l.unilateral && if active { b < 0.0 } else { b > 0.0 };
            if turns && -a / b <= 1.0 {
                part.breakpoints.push((-a / b, if active { -c } else { c }));
            }
        }
        part
    }

    /// `self` then `other`, in that order.
    pub(crate) fn add(&mut self, other: &EnergyAlongStep) {
        self.slope += other.slope;
        self.curvature += other.curvature;
        self.breakpoints.extend_from_slice(&other.breakpoints);
    }

    /// The minimiser `s > 0` of `φ(s)` with the load's work `Fᵀ ΔU` along the step, beyond
    /// which `min(s, 1)` is taken; `None` when the step is not a descent or φ has no
    /// minimiser below 1.
    pub(crate) fn minimiser(&self, load_work: f64) -> Option<f64> {
        let events = self.breakpoints.iter();
        let events = events.map(|&(position, change)| Reverse(Breakpoint { position, change }));
        walk(self.slope - load_work, self.curvature, events.collect())
    }
}

/// The minimiser of a piecewise quadratic from φ'(0), φ''(0⁺) and its breakpoints (`None`
/// when φ'(0) ≥ 0, or when φ decreases without end).
fn walk(mut slope_value: f64, mut curvature: f64, events: Vec<Reverse<Breakpoint>>) -> Option<f64> {
    if slope_value >= 0.0 {
        return None;
    }
    // Breakpoints in increasing order, taken from a min-heap only as far as the minimiser:
    // most lie far beyond it, and heapifying is linear where sorting them all is not.
    let mut events = BinaryHeap::from(events);
    let mut at = 0.0;
    while let Some(Reverse(Breakpoint { position, change })) = events.pop() {
        let reached = slope_value + curvature * (position - at);
        if curvature > 0.0 && reached >= 0.0 {
            return Some(at - slope_value / curvature);
        }
        slope_value = reached;
        at = position;
        curvature += change;
    }
    if curvature > 0.0 {
        Some(at - slope_value / curvature)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::LinkKind;

    fn link(stiffness: f64, unilateral: bool) -> Link {
        Link {
            id: 0,
            a: 0,
            b: 1,
            kind: if unilateral {
                LinkKind::Cable
            } else {
                LinkKind::Bar
            },
            module: 0,
            direction: [1.0, 0.0, 0.0],
            length: 1.0,
            stiffness,
            prestress: 0.0,
            unilateral,
            rest_change: 0.0,
            mass: 0.0,
        }
    }

    /// φ(s) evaluated directly: Σ_bars (a s b-form) + Σ_cables ½ k ⟨·⟩₊², minus the work.
    fn phi(links: &[Link], trial: &[f64], de: &[f64], work: f64, s: f64) -> f64 {
        let mut value = -work * s;
        for ((l, &a), &d) in links.iter().zip(trial).zip(de) {
            let tau = a + s * l.stiffness * d;
            let energy = |t: f64| 0.5 * t * t / l.stiffness;
            value += if l.unilateral {
                energy(tau.max(0.0)) - energy(a.max(0.0))
            } else {
                energy(tau) - energy(a)
            };
        }
        value
    }

    #[test]
    fn minimiser_matches_a_dense_scan_across_breakpoints() {
        // A bar and three cables: one taut going slack, one slack becoming taut, one taut.
        let links = [
            link(10.0, false),
            link(4.0, true),
            link(6.0, true),
            link(2.0, true),
        ];
        let trial = [1.0, 3.0, -2.0, 1.0];
        let de = [-0.2, -1.0, 1.5, 0.5];
        let work = 5.0;
        let s =
            exact_line_search(&links, &trial, &de, work, (0.0, 0.0)).expect("a descent direction");
        // Compare with a fine scan of φ (convex in s).
        let best = (0..=40_000)
            .map(|i| i as f64 * 1e-4)
            .min_by(|&x, &y| {
                phi(&links, &trial, &de, work, x).total_cmp(&phi(&links, &trial, &de, work, y))
            })
            .unwrap();
        assert!((s - best).abs() < 2e-4, "line search {s}, scan {best}");
        // φ'(s) = 0 there: a small step either way does not decrease φ.
        let at = phi(&links, &trial, &de, work, s);
        assert!(phi(&links, &trial, &de, work, s + 1e-6) >= at - 1e-12);
        assert!(phi(&links, &trial, &de, work, s - 1e-6) >= at - 1e-12);
    }

    #[test]
    fn no_step_along_an_ascent_direction() {
        let links = [link(1.0, false)];
        // φ'(0) = a·Δe − work = 1·1 − 0 > 0.
        assert_eq!(
            exact_line_search(&links, &[1.0], &[1.0], 0.0, (0.0, 0.0)),
            None
        );
    }
}
