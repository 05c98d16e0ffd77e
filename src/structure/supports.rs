//! Supports: which nodes are clamped (U = 0 on all three components).

use super::{Clamp, GridLayout};

pub(super) fn clamped_nodes(layout: &GridLayout, nodes: &[[f64; 3]], clamp: Clamp) -> Vec<bool> {
    let mut clamped = vec![false; nodes.len()];
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
    clamped
}
