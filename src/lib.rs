//! tensolve: static equilibrium of large tensegrity grids whose cables can go slack.
//!
//! Data flow: [`case`] (TOML) → [`structure`] (nodes, links, supports) → [`solvers`] →
//! [`results`] (checks and derived quantities) → [`output`] (CSV files).

pub mod case;
pub mod linalg;
pub mod output;
pub mod results;
pub mod run;
pub mod solvers;
pub mod structure;
