//! A short sparse row: at most six (index, coefficient) pairs. It is the row of an operator that
//! couples two 3-vectors, such as the compatibility operator B of a two-node member
//! (`e = n·(U_b − U_a)`); one row serves for `B U`, `Bᵀ t` and the stiffness `Bᵀ k B` alike.

/// At most six (index, coefficient) pairs.
#[derive(Debug, Clone, Copy)]
pub struct SparseRow {
    /// Number of pairs in use.
    pub len: u8,
    /// Column indices of the pairs in use (the first `len`).
    pub dofs: [u32; 6],
    /// Coefficients of the pairs in use (the first `len`).
    pub coef: [f64; 6],
}

impl SparseRow {
    /// The row `Σ coefficient · x[index]` over the pairs given; pairs whose index is `None` are
    /// left out.
    pub fn new(pairs: impl IntoIterator<Item = (Option<usize>, f64)>) -> SparseRow {
        let mut row = SparseRow {
            len: 0,
            dofs: [0; 6],
            coef: [0.0; 6],
        };
        for (index, coefficient) in pairs {
            if let Some(d) = index {
                let i = row.len as usize;
                row.dofs[i] = d as u32;
                row.coef[i] = coefficient;
                row.len += 1;
            }
        }
        row
    }

    /// The (index, coefficient) pairs in use.
    #[inline]
    pub fn iter(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.dofs[..self.len as usize]
            .iter()
            .zip(&self.coef[..self.len as usize])
            .map(|(&d, &c)| (d as usize, c))
    }

    /// The row applied to `u`: for a member, its elongation `e = n·(U_b − U_a)`.
    #[inline]
    pub fn elongation(&self, u: &[f64]) -> f64 {
        self.iter().map(|(d, c)| c * u[d]).sum()
    }

    /// `f += rowᵀ t`: for a member, the nodal forces of its tension t.
    #[inline]
    pub fn scatter(&self, t: f64, f: &mut [f64]) {
        for (d, c) in self.iter() {
            f[d] += c * t;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn left_out_indices_and_transpose() {
        let row = SparseRow::new([(Some(2), 1.0), (None, 5.0), (Some(0), -2.0)]);
        assert_eq!(row.len, 2);
        let u = [1.0, 10.0, 3.0];
        assert_eq!(row.elongation(&u), 3.0 - 2.0);
        // ⟨row, u⟩ = ⟨rowᵀ 1, u⟩.
        let mut f = vec![0.0; 3];
        row.scatter(1.0, &mut f);
        assert_eq!(f, [-2.0, 0.0, 1.0]);
    }
}
