//! Dense matrix–vector products on nalgebra storage through faer's SIMD kernels (nalgebra's
//! generic `Mul` on dynamic matrices is several times slower, and these products sit in the
//! LATIN iteration loop).

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use nalgebra::DMatrix;

/// `y ← A x` (or `y += A x` with `accumulate`).
pub fn gemv(y: &mut [f64], a: &DMatrix<f64>, x: &[f64], accumulate: bool) {
    product(y, a, false, x, accumulate);
}

/// `y ← Aᵀ x` (or `y += Aᵀ x` with `accumulate`).
pub fn gemv_transposed(y: &mut [f64], a: &DMatrix<f64>, x: &[f64], accumulate: bool) {
    product(y, a, true, x, accumulate);
}

fn product(y: &mut [f64], a: &DMatrix<f64>, transposed: bool, x: &[f64], accumulate: bool) {
    let view = MatRef::from_column_major_slice(a.as_slice(), a.nrows(), a.ncols());
    let op = if transposed { view.transpose() } else { view };
    debug_assert_eq!((y.len(), x.len()), (op.nrows(), op.ncols()));
    if y.is_empty() {
        return;
    }
    if x.is_empty() {
        if !accumulate {
            y.iter_mut().for_each(|v| *v = 0.0);
        }
        return;
    }
    let (n, k) = (y.len(), x.len());
    matmul(
        MatMut::from_column_major_slice_mut(y, n, 1),
        if accumulate {
            Accum::Add
        } else {
            Accum::Replace
        },
        op,
        MatRef::from_column_major_slice(x, k, 1),
        1.0,
        Par::Seq,
    );
}
