//! Where a load path's next solve starts: the answer at its load predicted from the last
//! equilibria reached, extrapolated along the path.

use crate::linalg::dot;

/// The equilibria a load path reached (their loads and displacements): the last one, where the
/// next solve's path starts, and the two before it, for the predictor.
#[derive(Debug, Clone)]
pub(super) struct Reached {
    /// The last equilibrium reached: its load and displacements.
    pub last: (Vec<f64>, Vec<f64>),
    /// The equilibria reached before it (the latest last, at most two).
    before: Vec<(Vec<f64>, Vec<f64>)>,
    /// The limit point the last solve from `last` located, when it ended at one.
    pub limit: Option<LocatedLimit>,
}

/// A limit point located on the path from an equilibrium: the last equilibrium found on it,
/// and the load beyond which none was, [`super::LIMIT_TOLERANCE`] of its load apart.
#[derive(Debug, Clone)]
pub(super) struct LocatedLimit {
    /// The load of the equilibrium the path started from.
    pub from: Vec<f64>,
    /// The load of the last equilibrium found on the path, and its displacements.
    pub equilibrium: Vec<f64>,
    pub u: Vec<f64>,
    /// The load of the smallest increment that found no equilibrium.
    pub beyond: Vec<f64>,
    /// Increments rejected for an equilibrium on another branch on the way.
    pub branch_jumps: usize,
    /// The cables that went slack in the last increment tried (ids).
    pub slackened: Vec<u64>,
}

/// The parameter t of `point = from + t (through − from)` when `point` lies on that line (to
/// 1e-12 of the distances), else `None`.
pub(super) fn ray_parameter(from: &[f64], through: &[f64], point: &[f64]) -> Option<f64> {
    let step: Vec<f64> = through.iter().zip(from).map(|(a, b)| a - b).collect();
    let ahead: Vec<f64> = point.iter().zip(from).map(|(a, b)| a - b).collect();
    let squared = dot(&step, &step);
    if squared.is_nan() || squared <= 0.0 {
        return None;
    }
    let t = dot(&ahead, &step) / squared;
    let off: f64 = ahead
        .iter()
        .zip(&step)
        .map(|(a, b)| (a - t * b).powi(2))
        .sum();
    (off <= 1e-12 * dot(&ahead, &ahead).max(squared)).then_some(t)
}

impl Reached {
    /// The prestressed state, U = 0 under no load, on `n` free dofs.
    pub fn prestressed(n: usize) -> Reached {
        Reached {
            last: (vec![0.0; n], vec![0.0; n]),
            before: Vec::new(),
            limit: None,
        }
    }

    /// A new equilibrium reached: displacements `u` at `load`.
    pub fn record(&mut self, load: Vec<f64>, u: Vec<f64>) {
        self.limit = None;
        let previous = std::mem::replace(&mut self.last, (load, u));
        if self.before.len() == 2 {
            self.before.remove(0);
        }
        self.before.push(previous);
    }

    /// The prediction of the answer at `load` by extrapolating the last equilibria along the
    /// load path (Lagrange, through the last three when there are three, else the secant of
    /// the last two), when their loads and `load` are collinear and `load` lies ahead by at
    /// most four of the last steps.
    pub fn predict(&self, load: &[f64]) -> Option<Vec<f64>> {
        let (l2, u2) = &self.last;
        let (l1, u1) = self.before.last()?;
        // The path parameter of a load: 0 at the last equilibrium, −1 at the one before.
        let parameter = |l: &[f64]| ray_parameter(l2, l1, l).map(|t| -t);
        let t = parameter(load).filter(|&t| t > 0.0 && t <= 4.0)?;
        let mut points: Vec<(f64, &Vec<f64>)> = vec![(-1.0, u1), (0.0, u2)];
        if self.before.len() == 2 {
            let (l0, u0) = &self.before[0];
            if let Some(t0) = parameter(l0).filter(|&t0| t0 < -1.0) {
                points.insert(0, (t0, u0));
            }
        }
        // Lagrange weights at t: w_i = Π_{j≠i} (t − t_j) / (t_i − t_j).
        let weights: Vec<f64> = (0..points.len())
            .map(|i| {
                (0..points.len())
                    .filter(|&j| j != i)
                    .map(|j| (t - points[j].0) / (points[i].0 - points[j].0))
                    .product()
            })
            .collect();
        Some(
            (0..u2.len())
                .map(|k| {
                    points
                        .iter()
                        .zip(&weights)
                        .map(|((_, u), w)| w * u[k])
                        .sum()
                })
                .collect(),
        )
    }
}
