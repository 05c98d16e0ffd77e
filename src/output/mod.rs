//! Output files. Every file is written whole to a temporary name and then renamed, so a file
//! that exists under its final name is complete.

mod atomic;
mod history;
mod tables;

pub use atomic::write_atomic;
pub use history::{HistoryWriter, HISTORY_HEADER};
pub use tables::{
    alpha_label, result_path, write_displacements, write_summary, write_tensions, SummaryRow,
    SUMMARY_HEADER,
};
