//! One substructure's own dofs, stiffness and solves, for any substructure method (LATIN's
//! linear stage, a two-level preconditioner): nothing here knows of LATIN's search directions,
//! interfaces' macro bases or its macro problem.
//!
//! | file | what |
//! |---|---|
//! | `local_dofs` | E's free dofs, their global numbers, a load's share, B_E, restriction and prolongation |
//! | `shapes` | substructures of one shape share K_E's pattern and symbolic analysis |
//! | `solves` | every substructure's factor, solved batched (the seam for a GPU) |

mod local_dofs;
mod shapes;
mod solves;

pub use local_dofs::{holders, LocalDofs};
pub use shapes::Shapes;
pub use solves::{SubstructureFactors, SubstructureSolves};
