//! Output files. Every file is written whole to a temporary name and then renamed, so a file
//! that exists under its final name is complete. [`sinks`] decides what is written when along
//! a sweep; the other modules write one kind of file each.

mod atomic;
mod history;
mod homogenised;
pub mod plots;
pub mod sinks;
mod tables;
mod vtk;

pub use atomic::{ensure_writable, write_atomic};
pub use history::{HistoryWriter, HISTORY_HEADER};
pub use homogenised::{homogenised_path, write_homogenised};
pub use plots::{FigureData, FigureSettings};
pub use sinks::{Sink, Sinks, SolveEnd, SolveKey, WriteError};
pub use tables::{
    alpha_label, result_path, write_displacements, write_stability, write_summary, write_tensions,
    StabilityRow, SummaryRow, STABILITY_HEADER, SUMMARY_HEADER,
};
pub use vtk::{kind_code, vtu_path, write_vtu, VTK_LINE};
