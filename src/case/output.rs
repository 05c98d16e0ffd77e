//! `[output]`: which files to write, and where, checked.

use super::numbers::positive;
use super::raw::RawOutput;
use super::{CaseError, OutputChoice};

/// `[output]`, each key defaulting to [`OutputChoice::default`].
pub(super) fn output_choice(o: RawOutput) -> Result<OutputChoice, CaseError> {
    let defaults = OutputChoice::default();
    if o.dir.as_ref().is_some_and(|d| d.as_os_str().is_empty()) {
        return Err(CaseError::invalid(
            "output.dir",
            "\"\"",
            "give a directory (\".\" for the current one), or remove the key for out/<case file name>",
        ));
    }
    let output = OutputChoice {
        dir: o.dir,
        summary: o.summary.unwrap_or(defaults.summary),
        tensions: o.tensions.unwrap_or(defaults.tensions),
        displacements: o.displacements.unwrap_or(defaults.displacements),
        forces: o.forces.unwrap_or(defaults.forces),
        reactions: o.reactions.unwrap_or(defaults.reactions),
        history: o.history.unwrap_or(defaults.history),
        plots: o.plots.unwrap_or(defaults.plots),
        vtk: o.vtk.unwrap_or(defaults.vtk),
        stability: o.stability.unwrap_or(defaults.stability),
        geometric_term: o.geometric_term.unwrap_or(defaults.geometric_term),
        homogenised: o.homogenised.unwrap_or(defaults.homogenised),
        amplification: o.amplification.unwrap_or(defaults.amplification),
        max_plot_iterations: o
            .max_plot_iterations
            .unwrap_or(defaults.max_plot_iterations),
        compare_modules: o.compare_modules.unwrap_or(defaults.compare_modules),
    };
    positive(
        "output.amplification",
        output.amplification,
        "the factor the displacements are drawn multiplied by (the paper's is 10)",
    )?;
    let kinds = &output.compare_modules;
    if let Some(twice) = kinds
        .iter()
        .enumerate()
        .find(|(i, k)| kinds[..*i].contains(k))
    {
        return Err(CaseError::invalid(
            "output.compare_modules",
            format!("{:?}", kinds.iter().map(|k| k.name()).collect::<Vec<_>>()),
            format!(
                "list each module kind once (`{}` is listed twice), e.g. [\"standard\", \"braced\"]",
                twice.1.name()
            ),
        ));
    }
    if !kinds.is_empty() && !output.plots {
        return Err(CaseError::invalid(
            "output.compare_modules",
            format!("{:?}", kinds.iter().map(|k| k.name()).collect::<Vec<_>>()),
            "it draws Figure 12 under plots/, which is written only with `output.plots = true`: \
             set `plots = true` in [output], or remove `compare_modules`",
        ));
    }
    if output.max_plot_iterations == 0 {
        return Err(CaseError::invalid(
            "output.max_plot_iterations",
            "0",
            "give the last iteration the convergence figures show as an integer ≥ 1 (the paper's is 100)",
        ));
    }
    Ok(output)
}
