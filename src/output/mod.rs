//! Output files. Every file is written whole into a private staging directory and published by
//! a rename ([`publish`]), so a file that exists under its final name is complete, and a solve's
//! files appear together, before its `summary.csv` row. [`sinks`] decides what is written when along
//! a sweep; the other modules write one kind of file each.

mod atomic;
mod envelope;
mod groups;
mod history;
mod homogenised;
mod member_checks;
pub mod modes;
mod modes_vtk;
pub mod plots;
pub mod publish;
pub mod sinks;
mod tables;
mod vtk;

pub use crate::labels::alpha_label;
pub use atomic::{ensure_writable, write_atomic};
pub use envelope::{
    write_combined_summary, write_envelopes, Combined, ENVELOPE_MEMBERS_HEADER,
    ENVELOPE_NODES_HEADER,
};
pub use history::{history_column, history_header, HistoryWriter};
pub use homogenised::{homogenised_path, write_homogenised};
pub use member_checks::{ChecksSink, CHECKS_HEADER, CHECK_COLUMNS, EUROCODE_COLUMNS};
pub use modes::ModesSink;
pub use plots::{FigureData, FigureSettings};
pub use publish::{lock_directory, OpenError, OutputDir};
pub use sinks::{Sink, Sinks, SolveEnd, SolveKey, WriteError};
pub use tables::{
    reaction_totals, reaction_totals_line, result_path, stability_line, summary_check_cells,
    summary_line, write_displacements, write_forces, write_mechanisms, write_reactions,
    write_tensions, StabilityRow, SummaryRow, REACTION_TOTALS_HEADER, STABILITY_HEADER,
    SUMMARY_CHECK_COLUMNS, SUMMARY_HEADER,
};
pub use vtk::{kind_code, link_code, vtu_path, write_vtu, VTK_LINE};
