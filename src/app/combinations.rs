//! `tensolve run` on a case with load combinations (`[[load.combinations]]`, or one per
//! `[[load.cases]]` entry): each combination is its own load, solved on its own as a whole
//! run into `DIR/combinations/<name>/` (cables go slack: the response is not linear in the
//! load, so nothing is superposed); then `DIR/summary.csv` gathers their rows with a
//! `combination` column, and `DIR/envelope/` the largest and smallest member forces,
//! utilisations and displacements over them ([`crate::output::write_envelopes`]).

use super::sweep::{output_dir, run_on, RunError, RunEvent, RunOptions};
use crate::case::Case;
use crate::decomposition::Exchange;
use crate::output::{write_combined_summary, write_envelopes, Combined, SummaryRow, WriteError};

/// Every combination of `case` run, in order, into its directory under the run's; a
/// combination whose run fails to converge does not stop the others (the first such error is
/// returned at the end, the envelope written over them all the same, each envelope row saying
/// how many combinations it covers); any other error stops the run. Returns every row, with
/// its combination's name.
pub fn run_combinations(
    case: &Case,
    options: &RunOptions,
    exchange: &dyn Exchange,
    events: &mut dyn FnMut(RunEvent<'_>),
) -> Result<Vec<(String, SummaryRow)>, RunError> {
    let dir = output_dir(case, options);
    let mut combined: Vec<Combined> = Vec::new();
    let mut rows = Vec::new();
    let mut failed = None;
    for (k, combination) in case.load.combinations.iter().enumerate() {
        let sub = dir.join("combinations").join(&combination.name);
        let sub_options = RunOptions {
            out_dir: Some(sub.clone()),
            methods: options.methods.clone(),
        };
        events(RunEvent::Combination(&combination.name));
        match run_on(case.combination(k), &sub_options, exchange, events) {
            Ok(r) => rows.extend(r.into_iter().map(|r| (combination.name.clone(), r))),
            Err(e @ RunError::NotConverged { .. }) => {
                failed.get_or_insert(e);
            }
            Err(e) => return Err(e),
        }
        combined.push((combination.name.clone(), sub));
    }
    if exchange.rank() == 0 {
        let mut keys: Vec<(String, f64)> = Vec::new();
        for (_, r) in &rows {
            if !keys.iter().any(|(s, a)| s == &r.solver && *a == r.alpha) {
                keys.push((r.solver.clone(), r.alpha));
            }
        }
        let at = |path: &str| {
            let path = dir.join(path);
            move |source| WriteError { path, source }
        };
        write_combined_summary(&dir, &combined, "combination").map_err(at("summary.csv"))?;
        write_envelopes(&dir, &combined, &keys).map_err(at("envelope"))?;
    }
    match failed {
        Some(e) => Err(e),
        None => Ok(rows),
    }
}
