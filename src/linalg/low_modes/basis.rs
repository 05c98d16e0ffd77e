//! The Krylov basis of [`super::modes_below`]: B-orthonormal, with A V, B V and `H = Vᵀ A V`.

use super::*;

/// The Krylov basis V, B-orthonormal, with A V and B V (column-major `n × len`), and the
/// projection `H = Vᵀ A V`.
pub(super) struct Basis {
    pub(super) n: usize,
    pub(super) v: Vec<f64>,
    pub(super) av: Vec<f64>,
    pub(super) bv: Vec<f64>,
    pub(super) h: Mat<f64>,
}

impl Basis {
    pub(super) fn new(n: usize) -> Basis {
        Basis {
            n,
            v: Vec::new(),
            av: Vec::new(),
            bv: Vec::new(),
            h: Mat::zeros(0, 0),
        }
    }

    /// Vectors in the basis.
    pub(super) fn len(&self) -> usize {
        self.v.len() / self.n
    }

    pub(super) fn v(&self) -> MatRef<'_, f64> {
        view(&self.v, self.n)
    }

    /// B times the basis vectors from column `from` on, a copy.
    pub(super) fn bv_from(&self, from: usize) -> Vec<f64> {
        self.bv[from * self.n..].to_vec()
    }

    /// `X ← X − V (B V)ᵀ X`: X B-orthogonal to the basis (once).
    pub(super) fn project_out(&self, x: &mut [f64]) {
        let n = self.n;
        if self.v.is_empty() || x.is_empty() {
            return;
        }
        let c = product(view(&self.bv, n), true, view(x, n));
        let cols = x.len() / n;
        matmul(
            MatMut::from_column_major_slice_mut(x, n, cols),
            Accum::Add,
            self.v(),
            c.as_ref(),
            -1.0,
            Par::Seq,
        );
    }

    /// The columns of `x` B-orthonormalised against the basis and each other, and B times
    /// them: twice, a projection on the basis, then the columns scaled to unit B-norm and
    /// combined by the eigenvectors of their Gram matrix (`X ← X U D^{-1/2}`). A column that
    /// the projection leaves at [`DEPENDENT`] of its norm or less, or not finite, and a
    /// direction of the Gram matrix at [`GRAM_DEPENDENT`] of its largest or less, are
    /// dropped: the block returned may have fewer columns, or none.
    pub(super) fn orthonormalize(
        &self,
        pattern: &StiffnessPattern,
        b: &[f64],
        mut x: Vec<f64>,
    ) -> (Vec<f64>, Vec<f64>) {
        let n = self.n;
        let mut before: Vec<f64> = b_norms(&x, &apply(pattern, b, &x, n), n);
        let mut bx = Vec::new();
        for _ in 0..2 {
            self.project_out(&mut x);
            let full = apply(pattern, b, &x, n);
            let norms = b_norms(&x, &full, n);
            let (mut kept, mut b_kept) = (Vec::new(), Vec::new());
            for (j, (&after, &size)) in norms.iter().zip(&before).enumerate() {
                // A NaN norm fails the test too.
                if !(after > DEPENDENT * size && after.is_finite()) {
                    continue;
                }
                let column = &x[j * n..(j + 1) * n];
                let b_column = &full[j * n..(j + 1) * n];
                kept.extend(column.iter().map(|v| v / after));
                b_kept.extend(b_column.iter().map(|v| v / after));
            }
            let Some((new_x, new_bx, cols)) = combine_by_gram(&kept, &b_kept, n) else {
                return (Vec::new(), Vec::new());
            };
            x = new_x;
            bx = new_bx;
            before = vec![1.0; cols];
        }
        (x, bx)
    }

    /// Appends the B-orthonormal block `x` (B-orthogonal to the basis), `bx` B times it, and
    /// grows H by `[V X]ᵀ A X`.
    pub(super) fn append(
        &mut self,
        pattern: &StiffnessPattern,
        a: &[f64],
        x: Vec<f64>,
        bx: Vec<f64>,
    ) {
        let n = self.n;
        let cols = x.len() / n;
        if cols == 0 {
            return;
        }
        let old = self.len();
        let ax = apply(pattern, a, &x, n);
        self.v.extend_from_slice(&x);
        self.bv.extend_from_slice(&bx);
        self.av.extend_from_slice(&ax);
        let cross = product(self.v(), true, view(&ax, n));
        let size = old + cols;
        let mut h = Mat::<f64>::zeros(size, size);
        h.as_mut()
            .submatrix_mut(0, 0, old, old)
            .copy_from(self.h.as_ref());
        for j in 0..cols {
            for i in 0..old {
                h[(i, old + j)] = cross[(i, j)];
                h[(old + j, i)] = cross[(i, j)];
            }
            for i in 0..cols {
                h[(old + i, old + j)] = 0.5 * (cross[(old + i, j)] + cross[(old + j, i)]);
            }
        }
        self.h = h;
    }

    /// The first Ritz pair in `from..to` (values `theta`, coefficient vectors the columns of
    /// `u`) whose residual `‖A x − λ B x‖` exceeds `TOLERANCE (|λ| + floor) ‖B x‖`; `to` if
    /// none does. By blocks of [`BLOCK`] pairs, stopping at the first block with a failure.
    pub(super) fn first_unconverged(
        &self,
        theta: &[f64],
        u: MatRef<'_, f64>,
        from: usize,
        to: usize,
        floor: f64,
    ) -> usize {
        let n = self.n;
        let mut start = from;
        while start < to {
            let end = to.min(start + BLOCK);
            let y = u.subcols(start, end - start);
            let ax = product(view(&self.av, n), false, y);
            let bx = product(view(&self.bv, n), false, y);
            for j in 0..end - start {
                let lambda = theta[start + j];
                let (ac, bc) = (ax.col_as_slice(j), bx.col_as_slice(j));
                let residual = ac
                    .iter()
                    .zip(bc)
                    .map(|(p, q)| (p - lambda * q).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let size = bc.iter().map(|q| q * q).sum::<f64>().sqrt();
                // A NaN residual fails.
                let holds = residual <= TOLERANCE * (lambda.abs() + floor) * size;
                if !holds {
                    return start + j;
                }
            }
            start = end;
        }
        to
    }
}

/// Columns of unit B-norm (`bx` B times them) combined by the eigenvectors of their Gram
/// matrix, `X ← X U D^{-1/2}`, a direction at [`GRAM_DEPENDENT`] of the largest or less
/// dropped: the B-orthonormal block, B times it, and its columns; `None` when none is left.
pub(super) fn combine_by_gram(
    x: &[f64],
    bx: &[f64],
    n: usize,
) -> Option<(Vec<f64>, Vec<f64>, usize)> {
    let cols = x.len() / n;
    if cols == 0 {
        return None;
    }
    let mut gram = product(view(x, n), true, view(bx, n));
    for j in 0..cols {
        for i in j + 1..cols {
            let mean = 0.5 * (gram[(i, j)] + gram[(j, i)]);
            gram[(i, j)] = mean;
            gram[(j, i)] = mean;
        }
    }
    let (d, u) = symmetric_eigen(gram.as_ref())?;
    let largest = d.last().copied().unwrap_or(0.0);
    let directions: Vec<usize> = (0..cols)
        .filter(|&k| d[k] > GRAM_DEPENDENT * largest && d[k] > 0.0)
        .collect();
    if directions.is_empty() {
        return None;
    }
    let combine = Mat::<f64>::from_fn(cols, directions.len(), |i, c| {
        u[(i, directions[c])] / d[directions[c]].sqrt()
    });
    let new_x = product(view(x, n), false, combine.as_ref());
    let new_bx = product(view(bx, n), false, combine.as_ref());
    Some((columns(&new_x), columns(&new_bx), directions.len()))
}

/// B-norms `√(xᵀ B x)` of the columns of a block and B times it.
pub(super) fn b_norms(x: &[f64], bx: &[f64], n: usize) -> Vec<f64> {
    x.chunks(n)
        .zip(bx.chunks(n))
        .map(|(c, bc)| {
            c.iter()
                .zip(bc)
                .map(|(p, q)| p * q)
                .sum::<f64>()
                .max(0.0)
                .sqrt()
        })
        .collect()
}

/// The columns of `m`, one after another (column-major, no padding).
pub(super) fn columns(m: &Mat<f64>) -> Vec<f64> {
    (0..m.ncols())
        .flat_map(|j| m.col_as_slice(j).iter().copied())
        .collect()
}
