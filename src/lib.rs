//! tensolve: static equilibrium of large tensegrity grids whose cables can go slack.
//!
//! Data flows one way, and each module only uses those before it:
//!
//! ```text
//! host, linalg, labels → structure → model → decomposition → analysis → solvers → results → output
//!                                         ↘                       ↓                  ↓
//!                                           case ────────────────────────────────→  app (sweep, bench, check)
//! ```
//!
//! [`host`] reads what the machine lets this process use (its memory); [`linalg`] is sparse
//! linear algebra knowing nothing of the domain; [`labels`] how numbers read where several
//! layers write them (α in file names and messages); [`structure`] builds nodes, links,
//! supports and loads from a plain [`structure::GridSpec`]; [`model`] is a structure with the
//! kinematics its members move by (the member law, `K_G`, the current geometry);
//! [`decomposition`] cuts it into substructures and interfaces (and says what processes
//! sharing them exchange); [`analysis`] computes what a structure, a model or an answer is
//! whatever solver found it (the taut stiffness, mechanisms, no-equilibrium certificates,
//! stability, uniqueness, modes, energy error); [`solvers`] holds the four solvers behind one [`solvers::Solver`]
//! trait and one [`solvers::drive`]r; [`results`] checks and derives quantities from an
//! answer; [`output`] writes files through one sink per file family; [`case`] turns a TOML file
//! into those specs and settings; [`app`] runs a case.

#![warn(missing_docs)]

pub mod analysis;
pub mod app;
pub mod case;
pub mod decomposition;
pub mod host;
pub mod labels;
pub mod linalg;
pub mod model;
pub mod output;
pub mod results;
pub mod solvers;
pub mod structure;
