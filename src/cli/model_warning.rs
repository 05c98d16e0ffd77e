//! The warning of a run whose model on the initial geometry is off by more than
//! `model.tolerance`: the distance measured (`geometric_term`) and, where `large` was solved at
//! the worst row's α, what it gives there.

use tensolve::app::auto::against_large::ModelOffBy;

/// The warning of a run whose rows leave out more than `tolerance` of the geometry (`off.count`
/// of them, `off.worst` the largest), with what `large` gives at the worst row's α when
/// `off.measured`.
pub fn off_by_warning(off: &ModelOffBy, tolerance: f64) -> String {
    let (count, worst, measured) = (off.count, &off.worst, off.measured);
    let at = format!(
        "{}, alpha {}",
        worst.solver,
        tensolve::output::alpha_label(worst.alpha)
    );
    let largest = match worst.geometric_term() {
        Some(d) => format!("measured up to {:.1} %", 100.0 * d),
        None => format!(
            "or by an amount not measured: large's Newton steps from the answer did not settle \
             in {} steps",
            tensolve::results::DISTANCE_STEPS
        ),
    };
    let change = |model: f64, large: f64| match large.abs() > 0.0 {
        true => format!("{:+.1} %", 100.0 * (large - model) / large.abs()),
        false => "–".to_string(),
    };
    let measured = match measured {
        Some(large) => format!(
            "; measured there, `large` gives a largest deflection of {:.4e} m against {:.4e} m \
             ({}), a largest cable tension of {:.4e} N against {:.4e} N ({}) and {} slack \
             cables against {}",
            large.max_deflection,
            worst.max_deflection,
            change(worst.max_deflection, large.max_deflection),
            large.max_tension,
            worst.max_tension,
            change(worst.max_tension, large.max_tension),
            large.slack_cables,
            worst.slack_cables
        ),
        None => String::new(),
    };
    format!(
        "warning: {count} row(s) leave out a geometric term (the members' rotation under their \
         tension) that changes the answer by more than model.tolerance = {} % ({largest}: \
         {at}{measured}): `model.geometry = \"large\"` computes the large-displacement answer \
         (summary.csv: geometric_term, small_displacement_ok = false)",
        (100.0 * tolerance * 1e6).round() / 1e6,
    )
}
