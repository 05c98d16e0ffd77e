//! Output files. Every file is written whole to a temporary name and then renamed, so a file
//! that exists under its final name is complete.

mod atomic;
mod tables;

pub use atomic::write_atomic;
pub use tables::{alpha_label, write_displacements, write_summary, write_tensions, SummaryRow};
