//! Anderson acceleration (type II, Walker & Ni 2011) of the LATIN fixed point. One LATIN
//! iteration is a map `x ↦ G(x)` on the linear stage's input x (per link `(t̂ − l ê)/√l`, per
//! interface row `(F̂^m + d_m Û^m)/√d_m`: the only parts of ŝ a linear stage reads, scaled to
//! the energy norm); the local stage on the new s gives G(x). With `f = G(x) − x` and the
//! differences `ΔX`, `ΔF` of the last m iterates,
//! `x⁺ = x + β f − (ΔX + β ΔF) γ`, `γ = argmin ‖f − ΔF γ‖`.
//! With m = 0 this is `x⁺ = β G(x) + (1 − β) x`: the linear stage is affine in x, so it is
//! exactly the relaxation of s with μ = β.

use crate::decomposition::Exchange;
#[cfg(test)]
use crate::decomposition::OneProcess;
use crate::linalg::{par_update, par_zip_map, CHUNK};
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::collections::VecDeque;

/// Directions of ΔF whose singular value is below this fraction of the largest are dropped
/// from the least-squares problem (nearly dependent differences). It is applied to the
/// eigenvalues of the column-scaled Gram matrix `ΔFᵀΔF`, squared: below 1e-7 the Gram
/// matrix's eigenvalues (≈ 1e-14 of the largest) are round-off.
const RCOND: f64 = 1e-7;

/// Of the last m iterates, oldest first: `(ΔX_i + β ΔF_i, ΔF_i)`.
type Differences = VecDeque<(Vec<f64>, Vec<f64>)>;

/// The history of an Anderson-accelerated fixed-point iteration.
#[derive(Debug, Clone, Default)]
pub struct Anderson {
    /// m: how many differences are kept.
    depth: usize,
    /// β: the damping of the step.
    damping: f64,
    /// The last iterate x and its residual f.
    last: Option<(Vec<f64>, Vec<f64>)>,
    /// Of the last m iterates, oldest first: `(ΔX_i + β ΔF_i, ΔF_i)`, the step's column
    /// (formed once, when the difference is taken) and the least-squares column.
    differences: Differences,
    /// `ΔF_iᵀ ΔF_j`, updated as differences come and go (O(m n) an iteration instead of the
    /// O(m² n) of a factorisation of ΔF).
    gram: VecDeque<VecDeque<f64>>,
    /// Vectors of the iterate's length no longer in use (dropped differences, the caller's
    /// old inputs), written over by the next step instead of allocated again: a fresh vector
    /// of tens of megabytes is mapped by the allocator and every page of it faults on first
    /// touch, serially (1.7 % of micro-macro's run on 512 × 512 modules on one thread).
    spare: Vec<Vec<f64>>,
}

impl Anderson {
    /// An empty history of depth m with damping β.
    pub fn new(depth: usize, damping: f64) -> Anderson {
        Anderson {
            depth,
            damping,
            ..Anderson::default()
        }
    }

    /// Forget the history: the map changed (new search directions).
    pub fn restart(&mut self) {
        if let Some((x, f)) = self.last.take() {
            self.spare.extend([x, f]);
        }
        for (step, df) in self.differences.drain(..) {
            self.spare.extend([step, df]);
        }
        self.gram.clear();
    }

    /// A vector no longer used by the caller (its last input), kept for the next steps.
    pub fn recycle(&mut self, v: Vec<f64>) {
        self.spare.push(v);
    }

    /// A vector of `n` entries to be written over entirely: a spare one, else a new one.
    fn buffer(&mut self, n: usize) -> Vec<f64> {
        match self.spare.pop() {
            Some(mut v) => {
                v.resize(n, 0.0);
                v
            }
            None => vec![0.0; n],
        }
    }

    /// The next input from `x` and `g = G(x)` (this process's part of them, in `pieces`).
    /// Right after a restart it is `G(x)` itself (the old x belongs to another map: neither
    /// damped nor kept).
    pub fn step(&mut self, x: &[f64], g: &[f64], restarted: bool, pieces: &Pieces<'_>) -> Vec<f64> {
        if restarted {
            self.restart();
            let mut next = self.buffer(g.len());
            par_update(&mut next, g, |_, g| g);
            return next;
        }
        let beta = self.damping;
        let n = x.len();
        let mut f = self.buffer(n);
        par_zip_map(&mut f, g, x, |g, x| g - x);
        // x⁺ = x + β f.
        let mut next = self.buffer(n);
        par_zip_map(&mut next, x, &f, |x, f| x + beta * f);
        if self.depth == 0 {
            self.spare.push(f);
            return next;
        }
        // A new difference, and with it ΔFᵀΔF_new and ΔFᵀf (the least-squares right-hand
        // side) in one pass over the kept ΔF.
        let mut rhs = Vec::new();
        if let Some((x_prev, f_prev)) = self.last.take() {
            // ΔX = x − x_prev, ΔF = f − f_prev; the step's column ΔX + β ΔF.
            let (mut step, mut df) = (x_prev, f_prev);
            par_update(&mut step, x, |previous, x| x - previous);
            par_update(&mut df, &f, |previous, f| f - previous);
            par_update(&mut step, &df, |dx, df| dx + beta * df);
            if self.differences.len() == self.depth {
                if let Some((step, df)) = self.differences.pop_front() {
                    self.spare.extend([step, df]);
                }
                self.gram.pop_front();
                self.gram.iter_mut().for_each(|row| {
                    row.pop_front();
                });
            }
            let (products, with_f) = products_with(&self.differences, &df, &f, pieces);
            for (row, &p) in self.gram.iter_mut().zip(&products) {
                row.push_back(p);
            }
            self.gram.push_back(products.into_iter().collect());
            self.differences.push_back((step, df));
            rhs = with_f;
        }
        if let Some(gamma) = self.coefficients(&rhs) {
            // x⁺ −= (ΔX + β ΔF) γ, chunk by chunk over all the columns.
            let differences = &self.differences;
            next.par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(chunk, out)| {
                    let start = chunk * CHUNK;
                    for ((step, _), &c) in differences.iter().zip(&gamma) {
                        let step = &step[start..start + out.len()];
                        out.iter_mut().zip(step).for_each(|(x, s)| *x -= c * s);
                    }
                });
        }
        let mut x_kept = self.buffer(n);
        par_update(&mut x_kept, x, |_, x| x);
        self.last = Some((x_kept, f));
        next
    }

    /// `γ = argmin ‖f − ΔF γ‖` from the normal equations `ΔFᵀΔF γ = ΔFᵀ f` (`with_f` = ΔFᵀf),
    /// scaled to a unit diagonal and solved on the eigenvectors whose eigenvalue is above
    /// `RCOND²` of the largest. `None` without history.
    fn coefficients(&self, with_f: &[f64]) -> Option<Vec<f64>> {
        let k = self.differences.len();
        if k == 0 {
            return None;
        }
        let scale: Vec<f64> = (0..k)
            .map(|i| {
                let d = self.gram[i][i];
                if d > 0.0 {
                    1.0 / d.sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let gram = DMatrix::from_fn(k, k, |i, j| scale[i] * self.gram[i][j] * scale[j]);
        let rhs: Vec<f64> = with_f.iter().zip(&scale).map(|(p, s)| s * p).collect();
        let eigen = gram.symmetric_eigen();
        let largest = eigen.eigenvalues.max();
        if !(largest > 0.0 && largest.is_finite()) {
            return None;
        }
        let mut gamma = vec![0.0; k];
        for (m, &lambda) in eigen.eigenvalues.iter().enumerate() {
            if lambda <= RCOND * RCOND * largest {
                continue;
            }
            let v = eigen.eigenvectors.column(m);
            let c = v.iter().zip(&rhs).map(|(a, b)| a * b).sum::<f64>() / lambda;
            gamma
                .iter_mut()
                .zip(v.iter())
                .for_each(|(g, a)| *g += c * a);
        }
        gamma.iter_mut().zip(&scale).for_each(|(g, s)| *g *= s);
        Some(gamma)
    }
}

/// How Anderson's vectors are split among processes and summed: this process holds the
/// consecutive `pieces` (the linear stage's input of its substructures), each summed in fixed
/// chunks from its own start; every rank gathers the chunks' partial sums and adds them in the
/// substructures' order. The same sums on any number of threads and of ranks.
pub(crate) struct Pieces<'a> {
    /// The lengths of this process's pieces, in order.
    pub lengths: Vec<usize>,
    /// The processes that hold the other pieces.
    pub exchange: &'a dyn Exchange,
}

impl Pieces<'_> {
    /// One piece of `n` entries on one process.
    #[cfg(test)]
    pub fn whole(n: usize) -> Pieces<'static> {
        Pieces {
            lengths: vec![n],
            exchange: &OneProcess,
        }
    }

    /// The chunks of this process's entries: each piece cut every [`CHUNK`] entries.
    fn chunks(&self) -> Vec<std::ops::Range<usize>> {
        let mut chunks = Vec::new();
        let mut start = 0;
        for &len in &self.lengths {
            let end = start + len;
            let mut at = start;
            while at < end {
                let next = (at + CHUNK).min(end);
                chunks.push(at..next);
                at = next;
            }
            start = end;
        }
        chunks
    }
}

/// `(ΔF_iᵀ ΔF_new, ΔF_iᵀ f)` for every kept ΔF_i and then ΔF_new itself, in one pass over
/// them: each chunk's partial sums, gathered from every rank and added in chunk order.
fn products_with(
    kept: &Differences,
    df_new: &[f64],
    f: &[f64],
    pieces: &Pieces<'_>,
) -> (Vec<f64>, Vec<f64>) {
    let columns: Vec<&[f64]> = kept
        .iter()
        .map(|(_, df)| df.as_slice())
        .chain([df_new])
        .collect();
    let width = 2 * columns.len();
    let partial: Vec<f64> = pieces
        .chunks()
        .into_par_iter()
        .flat_map_iter(|range| {
            let (new, f) = (&df_new[range.clone()], &f[range.clone()]);
            columns
                .iter()
                .flat_map(|column| {
                    let column = &column[range.clone()];
                    let with_new = column.iter().zip(new).map(|(p, q)| p * q).sum::<f64>();
                    let with_f = column.iter().zip(f).map(|(p, q)| p * q).sum::<f64>();
                    [with_new, with_f]
                })
                .collect::<Vec<f64>>()
        })
        .collect();
    let all = pieces.exchange.all_gather(&partial);
    let mut sums = vec![0.0; width];
    for chunk in all.chunks(width) {
        sums.iter_mut().zip(chunk).for_each(|(s, p)| *s += p);
    }
    sums.chunks(2).map(|pair| (pair[0], pair[1])).unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// G(x) = A x + b, a contraction: the iteration must reach its fixed point x* = (I − A)⁻¹ b.
    fn affine(x: &[f64]) -> Vec<f64> {
        let a = [[0.9, 0.05, 0.0], [0.02, -0.85, 0.1], [0.0, 0.1, 0.95]];
        let b = [1.0, -2.0, 0.5];
        (0..3)
            .map(|i| (0..3).map(|j| a[i][j] * x[j]).sum::<f64>() + b[i])
            .collect()
    }

    fn iterations(depth: usize, damping: f64) -> usize {
        let mut aa = Anderson::new(depth, damping);
        let mut x = vec![0.0; 3];
        for k in 0..10_000 {
            let g = affine(&x);
            let res: f64 = g.iter().zip(&x).map(|(g, x)| (g - x).powi(2)).sum();
            if res.sqrt() < 1e-10 {
                return k;
            }
            x = aa.step(&x, &g, false, &Pieces::whole(3));
        }
        usize::MAX
    }

    #[test]
    fn depth_zero_is_damped_picard_and_acceleration_reaches_the_same_point() {
        // Plain damped iteration: slow (spectral radius of 0.8 A + 0.2 I ≈ 0.96).
        let plain = iterations(0, 0.8);
        // Anderson on a 3-dimensional affine map is exact after at most 3 + 1 differences.
        let accelerated = iterations(5, 0.8);
        assert!(plain > 100 && plain < 10_000, "plain {plain}");
        assert!(accelerated <= 8, "accelerated {accelerated}");
    }

    /// A column of `n` entries in [−5, 5), different for each `seed`.
    fn column(n: usize, seed: usize) -> Vec<f64> {
        (0..n)
            .map(|k| (((k + 1) * (seed + 3) * 7919) % 1013) as f64 / 101.0 - 5.0)
            .collect()
    }

    /// `count` kept differences (ΔF only), the new ΔF and f, of `n` entries.
    fn history(n: usize, count: usize) -> (Differences, Vec<f64>, Vec<f64>) {
        let kept = (0..count).map(|i| (Vec::new(), column(n, i))).collect();
        (kept, column(n, 11), column(n, 12))
    }

    /// `work` on a pool of `threads` threads.
    fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> T {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(work)
    }

    /// The fused pass gives the products `par_dot` gives, to the bit, on one and on two
    /// threads (what makes the Anderson step's results independent of the threads).
    #[test]
    fn the_fused_products_are_par_dots() {
        let n = 3 * CHUNK + 17;
        let (kept, new, f) = history(n, 4);
        for threads in [1, 2] {
            let (with_new, with_f) = on_threads(threads, || {
                products_with(&kept, &new, &f, &Pieces::whole(n))
            });
            let columns: Vec<&Vec<f64>> = kept.iter().map(|(_, c)| c).chain([&new]).collect();
            for (i, c) in columns.iter().enumerate() {
                assert_eq!(
                    with_new[i].to_bits(),
                    crate::linalg::par_dot(c, &new).to_bits()
                );
                assert_eq!(with_f[i].to_bits(), crate::linalg::par_dot(c, &f).to_bits());
            }
        }
    }

    /// Pieces (a substructure's part each, one longer than a chunk) are cut into chunks from
    /// their own starts: the chunks tile the entries in order, and the products are the same on
    /// one and on two threads and equal the plain sums to round-off.
    #[test]
    fn products_over_pieces_do_not_depend_on_the_threads() {
        let pieces = Pieces {
            lengths: vec![7, CHUNK + 5, 0, 300],
            exchange: &OneProcess,
        };
        let chunks = pieces.chunks();
        let n: usize = pieces.lengths.iter().sum();
        assert_eq!(chunks.len(), 4);
        assert!(chunks.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!((chunks[0].start, chunks[3].end), (0, n));
        let (kept, new, f) = history(n, 3);
        let on = |threads: usize| on_threads(threads, || products_with(&kept, &new, &f, &pieces));
        let (one, two) = (on(1), on(2));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!((bits(&one.0), bits(&one.1)), (bits(&two.0), bits(&two.1)));
        let plain = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
        let columns: Vec<&Vec<f64>> = kept.iter().map(|(_, c)| c).chain([&new]).collect();
        for (i, c) in columns.iter().enumerate() {
            let (a, b) = (plain(c, &new), plain(c, &f));
            assert!((one.0[i] - a).abs() <= 1e-12 * a.abs(), "{} {a}", one.0[i]);
            assert!(
                (one.1[i] - b).abs() <= 1e-12 * b.abs().max(1.0),
                "{} {b}",
                one.1[i]
            );
        }
    }

    #[test]
    fn restart_returns_the_map_value_and_forgets() {
        let mut aa = Anderson::new(3, 0.5);
        let x = vec![1.0, 2.0];
        let _ = aa.step(&x, &[0.0, 0.0], false, &Pieces::whole(2));
        assert!(aa.last.is_some());
        let next = aa.step(&x, &[3.0, 4.0], true, &Pieces::whole(2));
        assert_eq!(next, vec![3.0, 4.0]);
        assert!(aa.last.is_none() && aa.differences.is_empty() && aa.gram.is_empty());
    }

    /// Reused vectors change no iterate: the caller's old inputs recycled, a restart midway,
    /// the iterates are bit for bit those of a history that never reuses one, and the spare
    /// vectors stay bounded by the history (a leak would grow them every step).
    #[test]
    fn recycled_vectors_change_no_iterate_and_stay_bounded() {
        let (mut reusing, mut fresh) = (Anderson::new(2, 0.8), Anderson::new(2, 0.8));
        let (mut x, mut y) = (vec![0.0; 3], vec![0.0; 3]);
        for k in 0..40 {
            let restart = k == 17;
            let next = reusing.step(&x, &affine(&x), restart, &Pieces::whole(3));
            reusing.recycle(std::mem::replace(&mut x, next));
            y = fresh.step(&y, &affine(&y), restart, &Pieces::whole(3));
            fresh.spare.clear();
            assert_eq!(x, y, "iterate {k}");
            // At most every vector the history ever held: 2 per difference, the last
            // iterate's 2, the caller's recycled input and the restart's copy of G(x).
            assert!(
                reusing.spare.len() <= 2 * 2 + 4,
                "{} spare",
                reusing.spare.len()
            );
        }
    }
}
