//! tensolve: static equilibrium of large tensegrity grids whose cables can go slack.
//!
//! Data flow: [`case`] (TOML) → [`structure`] (nodes, links, supports) → [`solvers`] →
//! [`results`] (checks and derived quantities) → [`output`] (CSV files); [`run`] drives a case,
//! [`bench`] times the solvers of a case against a reference.

pub mod bench;
pub mod case;
pub mod configure;
pub mod linalg;
pub mod output;
pub mod results;
pub mod run;
pub mod solvers;
pub mod structure;
