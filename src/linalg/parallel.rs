//! Vector kernels split over threads in fixed chunks, so that every sum is taken in the same
//! order whatever the number of threads (results identical on 1 and on 2 threads).

use rayon::prelude::*;

/// Entries per parallel task: below this a vector is one task.
pub const CHUNK: usize = 16_384;

/// `Σ a_k b_k`, partial sums per fixed chunk added in order.
pub fn par_dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let partial: Vec<f64> = a[..n]
        .par_chunks(CHUNK)
        .zip(b[..n].par_chunks(CHUNK))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>())
        .collect();
    partial.iter().sum()
}

/// `out_k = f(k, a_k, b_k)` over fixed chunks.
pub fn par_zip_map(out: &mut [f64], a: &[f64], b: &[f64], f: impl Fn(f64, f64) -> f64 + Sync) {
    out.par_chunks_mut(CHUNK)
        .zip(a.par_chunks(CHUNK).zip(b.par_chunks(CHUNK)))
        .for_each(|(o, (x, y))| {
            o.iter_mut()
                .zip(x.iter().zip(y))
                .for_each(|(o, (p, q))| *o = f(*p, *q));
        });
}

/// `out_k = f(out_k, a_k)` over fixed chunks.
pub fn par_update(out: &mut [f64], a: &[f64], f: impl Fn(f64, f64) -> f64 + Sync) {
    out.par_chunks_mut(CHUNK)
        .zip(a.par_chunks(CHUNK))
        .for_each(|(o, x)| o.iter_mut().zip(x).for_each(|(o, p)| *o = f(*o, *p)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn par_dot_is_the_same_on_one_and_on_two_threads() {
        let a: Vec<f64> = (0..100_003)
            .map(|k| ((k * 7919) % 1013) as f64 / 17.0)
            .collect();
        let b: Vec<f64> = (0..100_003).map(|k| 1.0 / (1.0 + k as f64)).collect();
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| par_dot(&a, &b))
        };
        assert_eq!(on(1).to_bits(), on(2).to_bits());
        let serial: f64 = a.iter().zip(&b).map(|(p, q)| p * q).sum();
        assert!((on(2) - serial).abs() <= 1e-12 * serial.abs());
        let mut out = vec![0.0; a.len()];
        par_zip_map(&mut out, &a, &b, |p, q| p - 2.0 * q);
        assert!(out
            .iter()
            .zip(a.iter().zip(&b))
            .all(|(o, (p, q))| *o == p - 2.0 * q));
    }
}
