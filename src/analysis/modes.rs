//! Natural frequencies and modes at an answer (issue 45 item 1): the lowest pairs of
//! `K_T φ = ω² M φ` on the free dofs, `K_T` the model's tangent there (the carrying members'
//! `k BᵀB`, plus `K_G(t0)` with `prestress`, or the exact Hessian on the current geometry with
//! `large`) and M the members' mass. A mode is prestress-governed when the members' elastic
//! stiffness alone, `K_E = Σ_carrying k BᵢᵀBᵢ` (on the current geometry under `large`: `Bᵢ` the
//! current `∇ℓᵢ`), holds less than [`PRESTRESS_GOVERNED`] of its
//! stiffness: the prestress's geometric stiffness is what makes it vibrate at all.

use crate::linalg::{
    lowest_generalized_modes, NoShiftFactorizes, SparseCholesky, StiffnessPattern,
};
use crate::model::{MassKind, Model};

/// A mode is prestress-governed when `φᵀ K_E φ < PRESTRESS_GOVERNED · φᵀ K_T φ`.
pub const PRESTRESS_GOVERNED: f64 = 0.01;

/// Residual tolerance of the eigenpairs (relative to the shift and the eigenvalue).
const MODE_TOLERANCE: f64 = 1e-10;

/// One natural mode.
#[derive(Debug, Clone, PartialEq)]
pub struct NaturalMode {
    /// ω / 2π, Hz (0 for a zero or negative eigenvalue).
    pub frequency_hz: f64,
    /// ω² = φᵀ K_T φ / φᵀ M φ, (rad/s)².
    pub eigenvalue: f64,
    /// `φᵀ K_E φ / φᵀ K_T φ`: the share of the mode's stiffness from the members' elasticity.
    pub elastic_share: f64,
    /// The shape on the free dofs, M-normalised (`φᵀ M φ = 1`).
    pub shape: Vec<f64>,
    /// Whether the eigensolver's residual criterion held for the modes it returned (they
    /// come from one solve: all or none); an unconverged mode is written, and says so.
    pub converged: bool,
}

impl NaturalMode {
    /// 1 / f, s (infinite for a zero frequency).
    pub fn period_s(&self) -> f64 {
        1.0 / self.frequency_hz
    }

    /// Whether the mode's stiffness comes from the prestress ([`PRESTRESS_GOVERNED`]).
    pub fn prestress_governed(&self) -> bool {
        self.elastic_share < PRESTRESS_GOVERNED
    }
}

/// The `count` lowest natural modes of `model` at displacements `u` and tensions `tensions`,
/// the members `carrying` force stiff, under `mass`; `analysed` is analysed on `pattern` (the
/// stiffness's pattern; only its symbolic part is used).
pub fn natural_modes(
    model: &Model,
    (u, tensions, carrying): (&[f64], &[f64], &[bool]),
    pattern: &StiffnessPattern,
    analysed: &SparseCholesky,
    count: usize,
    mass: MassKind,
) -> Result<Vec<NaturalMode>, NoShiftFactorizes> {
    let s = &model.structure;
    let mut tangent = vec![0.0; pattern.nnz()];
    model.assemble_modal_tangent(u, tensions, |i| carrying[i], pattern, &mut tangent);
    // K_E on the geometry the tangent is taken on: the current one under `large`.
    let rows = model.member_rows(u);
    let mut elastic = vec![0.0; pattern.nnz()];
    pattern.assemble(
        &rows,
        |i| match carrying[i] {
            true => s.links[i].stiffness,
            false => 0.0,
        },
        &mut elastic,
    );
    let mut m = vec![0.0; pattern.nnz()];
    model.assemble_mass(pattern, mass, &mut m);
    let mut factor = analysed.share_symbolic();
    let modes =
        lowest_generalized_modes(pattern, &tangent, &m, &mut factor, count, MODE_TOLERANCE)?;
    let quadratic = |a: &[f64], x: &[f64]| {
        let mut ax = vec![0.0; x.len()];
        pattern.sym_matvec(a, x, &mut ax);
        crate::linalg::dot(x, &ax)
    };
    let converged = modes.converged;
    Ok(modes
        .values
        .iter()
        .zip(modes.vectors)
        .map(|(&eigenvalue, shape)| {
            let total = quadratic(&tangent, &shape);
            let elastic_share = match total > 0.0 {
                true => quadratic(&elastic, &shape) / total,
                false => 1.0,
            };
            NaturalMode {
                frequency_hz: eigenvalue.max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
                eigenvalue,
                elastic_share,
                shape,
                converged,
            }
        })
        .collect())
}

/// The natural modes of the answers along a sweep (`output.modes`): `count` of them under
/// `mass`, on the stiffness's pattern and symbolic analysis made at the first answer and kept.
pub struct ModalAnalysis {
    count: usize,
    mass: MassKind,
    analysed: Option<(StiffnessPattern, SparseCholesky)>,
}

impl ModalAnalysis {
    /// `count` modes of each answer under `mass`.
    pub fn new(count: usize, mass: MassKind) -> Self {
        ModalAnalysis {
            count,
            mass,
            analysed: None,
        }
    }

    /// The modes at `eq` under `model`: none when `K_T − σM` factorizes for no shift tried.
    pub fn of(&mut self, model: &Model, eq: &super::Equilibrium) -> Vec<NaturalMode> {
        let (pattern, analysed) = self
            .analysed
            .get_or_insert_with(|| super::TautStiffness::analyse(&model.structure));
        let carrying: Vec<bool> = eq.slack.iter().map(|&s| !s).collect();
        let at = (&eq.displacements[..], &eq.tensions[..], &carrying[..]);
        natural_modes(model, at, pattern, analysed, self.count, self.mass).unwrap_or_default()
    }
}
