//! Output files. Every file is written whole to a temporary name and then renamed, so a file
//! that exists under its final name is complete.

mod atomic;
mod history;
mod observers;
pub mod plots;
mod tables;
mod vtk;

pub use atomic::{ensure_writable, write_atomic};
pub use history::{HistoryWriter, HISTORY_HEADER};
pub use observers::{Recorder, Tee};
pub use plots::FigureData;
pub use tables::{
    alpha_label, result_path, write_displacements, write_stability, write_summary, write_tensions,
    StabilityRow, SummaryRow, STABILITY_HEADER, SUMMARY_HEADER,
};
pub use vtk::{kind_code, vtu_path, write_vtu, VTK_LINE};
