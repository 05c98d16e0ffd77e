//! Domain decomposition as shared infrastructure (docs/method.md §4): how a structure is cut
//! into substructures and what passes between them, independent of the solver that iterates
//! on it. The LATIN solvers, the mechanism check by substructures and the MPI ranks all use it.
//!
//! | file | what |
//! |---|---|
//! | `partition` | substructures and interfaces of an `sx × sy` partition, weak interfaces |
//! | `macro_basis` | the macro fields of an interface, orthonormalised |
//! | `interfaces` | interfaces with their macro bases, redundant constraints left out |
//! | `kernel` | rigid frames and the kernel of a substructure's condensed operator |
//! | `exchange` | the collective operations of the processes that share a solve |
//! | `homogenised` | a substructure's homogenised flexibility on its macro dofs |
//! | `schwarz` | a two-level overlapping Schwarz preconditioner with a GenEO coarse space |
//! | `substructure` | one substructure's own dofs, factor and solves, for any substructure method |

mod exchange;
mod homogenised;
pub(crate) mod interfaces;
pub(crate) mod kernel;
pub(crate) mod macro_basis;
pub(crate) mod partition;
pub mod schwarz;
pub mod substructure;

pub use exchange::{block, Exchange, OneProcess};
pub use homogenised::{Homogenised, MacroDof};
pub(crate) use interfaces::{number_macro_dofs, Interface, Interfaces};
pub(crate) use kernel::{add_to_gram, null_amplitudes, RigidFrame};
pub(crate) use macro_basis::orthonormal_columns;
pub use partition::WeakInterfaces;
pub(crate) use partition::{Partition, SubstructureTopology};
