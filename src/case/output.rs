//! `[output]`: which files to write, and where, checked.

use super::numbers::{number, positive};
use super::{CaseError, OutputChoice};

/// `[output]` as read (each key absent taking [`OutputChoice::default`]'s value), checked.
pub(super) fn output_choice(output: OutputChoice) -> Result<OutputChoice, CaseError> {
    if output
        .dir
        .as_ref()
        .is_some_and(|d| d.as_os_str().is_empty())
    {
        return Err(CaseError::invalid(
            "output.dir",
            "\"\"",
            "give a directory (\".\" for the current one), or remove the key for out/<case file name>",
        ));
    }
    if let Some(amplification) = output.amplification {
        positive(
            "output.amplification",
            amplification,
            "the factor the displacements are drawn multiplied by (the paper's is 10), or remove \
             the key for an automatic one",
        )?;
    }
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

/// `output.modes > 0` needs mass: some member of `geometry` with a `density`, or a point mass.
pub(super) fn check_modes_have_mass(
    output: &OutputChoice,
    geometry: &crate::structure::Geometry,
    point_masses: &[(usize, f64)],
) -> Result<(), CaseError> {
    let massless = geometry.members.iter().all(|m| m.density <= 0.0) && point_masses.is_empty();
    if output.modes > 0 && massless {
        return Err(CaseError::invalid(
            "output.modes",
            output.modes.to_string(),
            "the natural modes need the members' mass, and no member has a density: give the \
             members table a `density` column (kg/m³, after `prestress`; a grid: `bars.density` \
             and `cables.density`) or `[[modal.point_mass]]`, or set `modes = 0`",
        ));
    }
    Ok(())
}

/// `output.figure_alpha`, when given, is one of the load factors solved (`alphas`), to 1e-9
/// relative (0.1 matches a range's 0.09999999999999999), and is set to that α exactly.
pub(super) fn match_figure_alpha(
    output: &mut OutputChoice,
    alphas: &[f64],
) -> Result<(), CaseError> {
    let Some(wanted) = output.figure_alpha else {
        return Ok(());
    };
    let same = |a: f64| a == wanted || (a - wanted).abs() <= 1e-9 * a.abs().max(wanted.abs());
    if let Some(&alpha) = alphas.iter().find(|&&a| same(a)) {
        output.figure_alpha = Some(alpha);
        return Ok(());
    }
    let available: Vec<String> = alphas.iter().map(|&a| number(a)).collect();
    Err(CaseError::invalid(
        "output.figure_alpha",
        number(wanted),
        format!(
            "give one of the load factors solved (load.alpha): {}; or remove the key for the \
             largest",
            available.join(", ")
        ),
    ))
}
