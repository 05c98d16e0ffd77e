//! Dense matrix–vector products on nalgebra storage through faer's SIMD kernels (nalgebra's
//! generic `Mul` on dynamic matrices is several times slower, and these products sit in the
//! LATIN iteration loop).

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use nalgebra::DMatrix;

fn view(a: &DMatrix<f64>) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(a.as_slice(), a.nrows(), a.ncols())
}

/// `y ← A x` (or `y += A x` with `accumulate`).
pub fn gemv(y: &mut [f64], a: &DMatrix<f64>, x: &[f64], accumulate: bool) {
    debug_assert_eq!((y.len(), x.len()), a.shape());
    let (n, k) = a.shape();
    if n == 0 {
        return;
    }
    if k == 0 {
        if !accumulate {
            y.iter_mut().for_each(|v| *v = 0.0);
        }
        return;
    }
    matmul(
        MatMut::from_column_major_slice_mut(y, n, 1),
        if accumulate {
            Accum::Add
        } else {
            Accum::Replace
        },
        view(a),
        MatRef::from_column_major_slice(x, k, 1),
        1.0,
        Par::Seq,
    );
}

/// `y ← Aᵀ x` (or `y += Aᵀ x` with `accumulate`).
pub fn gemv_transposed(y: &mut [f64], a: &DMatrix<f64>, x: &[f64], accumulate: bool) {
    let (k, n) = a.shape();
    debug_assert_eq!((y.len(), x.len()), (n, k));
    if n == 0 {
        return;
    }
    if k == 0 {
        if !accumulate {
            y.iter_mut().for_each(|v| *v = 0.0);
        }
        return;
    }
    matmul(
        MatMut::from_column_major_slice_mut(y, n, 1),
        if accumulate {
            Accum::Add
        } else {
            Accum::Replace
        },
        view(a).transpose(),
        MatRef::from_column_major_slice(x, k, 1),
        1.0,
        Par::Seq,
    );
}
