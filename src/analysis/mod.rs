//! The analyses between the model and the solvers (issue 58): what is computed of a structure,
//! a model or an answer whatever solver found it. The taut stiffness and the mechanism check
//! every solver sets up on ([`taut`], [`mod@mechanism_by_substructures`]), why a solver cannot be
//! set up ([`setup_error`]), the equilibrium state every solver answers with ([`equilibrium`]),
//! and of an answer: the no-equilibrium certificate ([`mod@no_equilibrium`]), the energy error
//! against a reference ([`energy_error`]), its stability ([`stability`]), uniqueness
//! ([`uniqueness`]), natural modes ([`modes`]) and its distance to `large` ([`geometric_term`]).
//! Solvers, results, outputs and the application read them; nothing here solves for a load.

pub mod energy_error;
pub mod equilibrium;
pub mod geometric_term;
pub mod mechanism_by_substructures;
pub mod modes;
pub mod motion;
pub mod no_equilibrium;
pub mod setup_error;
pub mod stability;
pub mod taut;
pub mod uniqueness;

pub use energy_error::Reference;
pub use equilibrium::Equilibrium;
pub use geometric_term::{
    distance_to_large, LargeDistance, DISTANCE_FAR, DISTANCE_ROUND_OFF, DISTANCE_SETTLED,
    DISTANCE_STEPS,
};
pub use mechanism_by_substructures::{
    check_shape, mechanism_by_substructures, SubstructuredVerdict, CHECK_MODULES,
};
pub use motion::{largest_motion, largest_node_norm};
pub use no_equilibrium::{
    no_equilibrium, no_equilibrium_along, no_equilibrium_of_answer, no_equilibrium_of_slack_set,
    unit_direction, LinksAlong, NoEquilibrium, UnitDirection,
};
pub use setup_error::{ModeRow, SetupError};
pub use stability::{
    smallest_assembled_eigenvalue, smallest_tangent_eigenvalue, EIGENVALUE_FULL_DOFS,
    TANGENT_ZERO_RELATIVE,
};
pub use taut::TautStiffness;
