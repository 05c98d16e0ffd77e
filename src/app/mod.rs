//! The application on top of the pipeline: set solvers up for a case ([`setup`]), run a sweep
//! of load factors into files (`sweep`), measure what accuracy costs in time (`bench`) and
//! report what a case describes ([`check`]), each after estimating the memory it needs
//! ([`memory`]).

pub mod allocator;
pub mod auto;
pub mod bench;
pub mod check;
pub mod combinations;
pub mod compare;
pub mod design;
pub mod memory;
pub mod ranks;
pub mod reference;
pub mod setup;
pub mod stages;
pub mod sweep;
