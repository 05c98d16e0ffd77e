//! The compatibility operator B, link by link (SPEC §1): row i of B is `e_i = n·(U_b − U_a)`.
//! B is never formed as a matrix: each link keeps its (at most six) free dofs and the matching
//! coefficients, which serve for `B U`, `Bᵀ t` and the stiffness `Bᵀ k B` alike.

use super::{Link, CLAMPED};

/// Free dofs of one link and their coefficients in row i of B. Clamped components are left
/// out, so `len ≤ 6`.
#[derive(Debug, Clone, Copy)]
pub struct LinkDofs {
    pub len: u8,
    pub dofs: [u32; 6],
    pub coef: [f64; 6],
}

impl LinkDofs {
    pub fn new(link: &Link, dof_of: &[usize]) -> LinkDofs {
        let mut out = LinkDofs {
            len: 0,
            dofs: [0; 6],
            coef: [0.0; 6],
        };
        for (node, sign) in [(link.a, -1.0), (link.b, 1.0)] {
            for k in 0..3 {
                let d = dof_of[3 * node + k];
                if d != CLAMPED {
                    let i = out.len as usize;
                    out.dofs[i] = d as u32;
                    out.coef[i] = sign * link.direction[k];
                    out.len += 1;
                }
            }
        }
        out
    }

    #[inline]
    pub fn iter(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.dofs[..self.len as usize]
            .iter()
            .zip(&self.coef[..self.len as usize])
            .map(|(&d, &c)| (d as usize, c))
    }

    /// `e = n·(U_b − U_a)`.
    #[inline]
    pub fn elongation(&self, u: &[f64]) -> f64 {
        self.iter().map(|(d, c)| c * u[d]).sum()
    }

    /// `f += Bᵢᵀ t`.
    #[inline]
    pub fn scatter(&self, t: f64, f: &mut [f64]) {
        for (d, c) in self.iter() {
            f[d] += c * t;
        }
    }
}
