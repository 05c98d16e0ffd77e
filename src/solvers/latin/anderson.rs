//! Anderson acceleration (type II, Walker & Ni 2011) of the LATIN fixed point. One LATIN
//! iteration is a map `x ↦ G(x)` on the linear stage's input x (per link `(t̂ − l ê)/√l`, per
//! interface row `(F̂^m + d_m Û^m)/√d_m`: the only parts of ŝ a linear stage reads, scaled to
//! the energy norm); the local stage on the new s gives G(x). With `f = G(x) − x` and the
//! differences `ΔX`, `ΔF` of the last m iterates,
//! `x⁺ = x + β f − (ΔX + β ΔF) γ`, `γ = argmin ‖f − ΔF γ‖`.
//! With m = 0 this is `x⁺ = β G(x) + (1 − β) x`: the linear stage is affine in x, so it is
//! exactly the relaxation of s with μ = β.

use nalgebra::{DMatrix, DVector};
use std::collections::VecDeque;

/// Singular values of ΔF below this fraction of the largest are dropped from the least-squares
/// problem (nearly dependent differences).
const RCOND: f64 = 1e-10;

/// The history of an Anderson-accelerated fixed-point iteration.
#[derive(Debug, Clone, Default)]
pub struct Anderson {
    /// m: how many differences are kept.
    depth: usize,
    /// β: the damping of the step.
    damping: f64,
    /// The last iterates x_i and their residuals f_i, oldest first (at most m).
    history: VecDeque<(Vec<f64>, Vec<f64>)>,
}

impl Anderson {
    /// An empty history of depth m with damping β.
    pub fn new(depth: usize, damping: f64) -> Anderson {
        Anderson {
            depth,
            damping,
            history: VecDeque::new(),
        }
    }

    /// Forget the history: the map changed (new search directions).
    pub fn restart(&mut self) {
        self.history.clear();
    }

    /// The next input from `x` and `g = G(x)`. Right after a restart it is `G(x)` itself (the
    /// old x belongs to another map: neither damped nor kept).
    pub fn step(&mut self, x: &[f64], g: &[f64], restarted: bool) -> Vec<f64> {
        if restarted {
            self.restart();
            return g.to_vec();
        }
        let beta = self.damping;
        let f: Vec<f64> = g.iter().zip(x).map(|(g, x)| g - x).collect();
        // x⁺ = x + β f.
        let mut next: Vec<f64> = x.iter().zip(&f).map(|(x, f)| x + beta * f).collect();
        let k = self.history.len();
        if k > 0 && self.depth > 0 {
            // ΔX_i = x_{i+1} − x_i, ΔF_i = f_{i+1} − f_i over the history and the current x, f.
            let n = f.len();
            let xs: Vec<&[f64]> = self.history.iter().map(|h| &h.0[..]).chain([x]).collect();
            let fs: Vec<&[f64]> = self
                .history
                .iter()
                .map(|h| &h.1[..])
                .chain([&f[..]])
                .collect();
            let dx = DMatrix::<f64>::from_fn(n, k, |r, i| xs[i + 1][r] - xs[i][r]);
            let df = DMatrix::<f64>::from_fn(n, k, |r, i| fs[i + 1][r] - fs[i][r]);
            // γ = argmin ‖f − ΔF γ‖, by SVD with small singular values dropped.
            let svd = df.clone().svd(true, true);
            let cutoff = RCOND * svd.singular_values.max();
            if let Ok(gamma) = svd.solve(&DVector::from_column_slice(&f), cutoff) {
                // x⁺ −= (ΔX + β ΔF) γ.
                let correction = (dx + df * beta) * gamma;
                next.iter_mut()
                    .zip(correction.iter())
                    .for_each(|(x, c)| *x -= c);
            }
        }
        if self.depth > 0 {
            self.history.push_back((x.to_vec(), f));
            while self.history.len() > self.depth {
                self.history.pop_front();
            }
        }
        next
    }
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
            x = aa.step(&x, &g, false);
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

    #[test]
    fn restart_returns_the_map_value_and_forgets() {
        let mut aa = Anderson::new(3, 0.5);
        let x = vec![1.0, 2.0];
        let _ = aa.step(&x, &[0.0, 0.0], false);
        assert_eq!(aa.history.len(), 1);
        let next = aa.step(&x, &[3.0, 4.0], true);
        assert_eq!(next, vec![3.0, 4.0]);
        assert!(aa.history.is_empty());
    }
}
