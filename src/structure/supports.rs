//! Supports: which nodes are clamped (U = 0 on all three components).

use super::{Clamp, GridLayout, NodeFix};

/// The nodes a clamp preset holds, each on all three components at zero.
pub(super) fn clamp_fixes(layout: &GridLayout, clamp: Clamp) -> Vec<NodeFix> {
    let mut clamped = vec![false; layout.n_nodes()];
    let (nx, ny) = (layout.nx, layout.ny);
    let mut set = |i: usize, j: usize| clamped[layout.corner(i, j)] = true;
    match clamp {
        Clamp::LowerXEdges | Clamp::LowerAllEdges | Clamp::LowerYEdges => {
            if clamp != Clamp::LowerYEdges {
                for j in 0..=ny {
                    set(0, j);
                    set(nx, j);
                }
            }
            if clamp != Clamp::LowerXEdges {
                for i in 0..=nx {
                    set(i, 0);
                    set(i, ny);
                }
            }
        }
        Clamp::LowerCorners => {
            for (i, j) in [(0, 0), (nx, 0), (nx, ny), (0, ny)] {
                set(i, j);
            }
        }
        Clamp::None => {}
    }
    (0..clamped.len())
        .filter(|&n| clamped[n])
        .map(|node| NodeFix {
            node,
            dofs: [true; 3],
            displacement: [0.0; 3],
        })
        .collect()
}
