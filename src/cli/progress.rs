//! The progress display of the command line (the library reports events and never prints):
//! a bar on a terminal, plain lines when stderr is not a terminal, nothing with `--quiet`; and
//! the one-line forms of an iterate, a summary row and a bench series.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};
use tensolve::app::auto::against_large::ModelOffBy;
use tensolve::app::bench::Progress;
use tensolve::app::sweep::RunEvent;
use tensolve::output::{alpha_label, SummaryRow};
use tensolve::results::uniqueness::Uniqueness;
use tensolve::solvers::{IterationRecord, Measure};

/// Progress on stderr: a bar on a terminal (lines printed above it, a spinner and what is
/// running beside it), plain lines when stderr is not a terminal, nothing with `--quiet`.
pub enum Display {
    Quiet,
    Lines,
    Bar(ProgressBar),
}

/// The bar's message is redrawn at most this often.
const BAR_REFRESH: Duration = Duration::from_millis(100);
/// Without a terminal, a running solve prints its iterate at most this often.
const LINE_REFRESH: Duration = Duration::from_secs(10);
/// Without a terminal, a set-up step longer than this prints what it did and how long it took.
const LONG_STAGE: Duration = Duration::from_secs(1);

/// What the progress display knows of the run: the set-up step or solve in progress.
pub struct Reporter {
    display: Display,
    /// The set-up step in progress and when it began.
    stage: Option<(String, Instant)>,
    /// When the display last showed an iterate.
    shown: Instant,
    /// The last e reported in the solve in progress (LATIN against its reference).
    last_error: Option<f64>,
    /// What the run's rows left out of the geometry, when the run said
    /// ([`RunEvent::ModelOffBy`]).
    pub model_off_by: Option<ModelOffBy>,
    /// The links this process kept of the structure's, when set-up said
    /// ([`RunEvent::LinksKept`]).
    pub links_kept: Option<(usize, usize)>,
    /// A row with slack cables gets a warning (`checks.forbid_slack`).
    pub forbid_slack: bool,
}

impl Reporter {
    pub fn new(quiet: bool, ticks: usize) -> Reporter {
        let display = if quiet {
            Display::Quiet
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(ticks as u64);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner:.green} {bar:30.cyan/blue} {pos}/{len} solves [{elapsed}] {msg}",
                )
                .expect("valid template"),
            );
            // Redrawn on a timer too: a long set-up or solve sends nothing for seconds.
            bar.enable_steady_tick(Duration::from_millis(120));
            Display::Bar(bar)
        } else {
            Display::Lines
        };
        Reporter {
            display,
            stage: None,
            shown: Instant::now(),
            last_error: None,
            model_off_by: None,
            links_kept: None,
            forbid_slack: false,
        }
    }

    pub fn line(&self, text: &str) {
        match &self.display {
            Display::Quiet => {}
            Display::Lines => eprintln!("{text}"),
            Display::Bar(bar) => bar.println(text),
        }
    }

    /// What is running now (shown on the bar only).
    pub fn status(&self, text: String) {
        if let Display::Bar(bar) = &self.display {
            bar.set_message(text);
        }
    }

    pub fn tick(&self) {
        if let Display::Bar(bar) = &self.display {
            bar.inc(1);
        }
    }

    pub fn finish(&mut self) {
        self.end_stage();
        if let Display::Bar(bar) = &self.display {
            bar.finish_and_clear();
        }
    }

    /// A set-up step began.
    pub fn begin_stage(&mut self, text: &str) {
        self.end_stage();
        self.status(format!("{text} ..."));
        self.stage = Some((text.to_string(), Instant::now()));
    }

    /// The step in progress ended: without a terminal, a long one is reported with its time.
    pub fn end_stage(&mut self) {
        if let Some((text, start)) = self.stage.take() {
            let took = start.elapsed();
            if matches!(self.display, Display::Lines) && took > LONG_STAGE {
                self.line(&format!("{text}: {:.1} s", took.as_secs_f64()));
            }
        }
    }

    /// One event of `tensolve run`.
    pub fn run_event(&mut self, event: RunEvent<'_>) {
        match event {
            RunEvent::Stage(text) => self.begin_stage(text),
            RunEvent::SolveStart { solver, alpha } => {
                self.end_stage();
                self.last_error = None;
                self.shown = Instant::now();
                self.status(format!("{solver} alpha = {}: starting", alpha_label(alpha)));
            }
            RunEvent::Iteration {
                solver,
                alpha,
                measure,
                record,
            } => {
                self.last_error = record.error.or(self.last_error);
                let refresh = match self.display {
                    Display::Quiet => return,
                    Display::Lines => LINE_REFRESH,
                    Display::Bar(_) => BAR_REFRESH,
                };
                if self.shown.elapsed() < refresh {
                    return;
                }
                self.shown = Instant::now();
                let text = iterate_message(solver, alpha, measure, record);
                match self.display {
                    Display::Lines => self.line(&format!("  {text}")),
                    _ => self.status(text),
                }
            }
            RunEvent::Combination(name) => {
                self.end_stage();
                self.line(&format!("combination {name}"));
            }
            RunEvent::Construction(name) => {
                self.end_stage();
                self.line(&format!("stage {name}"));
            }
            RunEvent::LinksKept { kept, whole } => self.links_kept = Some((kept, whole)),
            RunEvent::ModelOffBy(off) => self.model_off_by = Some(off.clone()),
            RunEvent::Row(row) => {
                let mut text = format_row(row);
                if self.forbid_slack && row.slack_cables > 0 && !row.status.no_answer() {
                    text.push_str(&format!(
                        "\n  warning: {} at alpha = {}: {} cable(s) slack where \
                         `checks.forbid_slack` forbids it (checks.csv names them)",
                        row.solver,
                        alpha_label(row.alpha),
                        row.slack_cables
                    ));
                }
                if let Some(e) = self.last_error.take() {
                    // Beside the row's numbers, before the warnings under it.
                    let end = text.find('\n').unwrap_or(text.len());
                    text.insert_str(end, &format!(", e = {e:.1e}"));
                }
                self.line(&text);
                self.tick();
            }
        }
    }
}

/// `micro-macro alpha = 0.5: iteration 37, eta = 3.2e-4, e = 1.1e-3, 12 slack, 0.84 s`: a
/// solve in progress, e when the solve is measured against a reference.
fn iterate_message(solver: &str, alpha: f64, measure: Measure, record: &IterationRecord) -> String {
    let mut text = format!(
        "{solver} alpha = {}: iteration {}, {} = {:.1e}",
        alpha_label(alpha),
        record.iteration,
        measure.short_name(),
        record.stopping_value
    );
    if let Some(e) = record.error {
        text.push_str(&format!(", e = {e:.1e}"));
    }
    text.push_str(&format!(
        ", {} slack, {:.2} s",
        record.slack_cables, record.elapsed_seconds
    ));
    text
}

fn format_row(r: &SummaryRow) -> String {
    let mut line = format!(
        "{:>11} alpha = {:<6} {} in {} it, {} / {} slack, {}r(U) {:.1e}, {:.1} ms",
        r.solver,
        alpha_label(r.alpha),
        match (r.converged, r.at_roundoff) {
            // A LATIN stop on Δη at round-off of the prestress: η is then a ratio of round-off
            // to round-off (no load), not a measure of anything.
            (true, true) if r.alpha == 0.0 && r.measure == Measure::Indicator => {
                "converged (no load: Δη at round-off of the prestress)".to_string()
            }
            // Every solver (issue 57, E2, R5-5, R5-6): r(U) at round-off, the load too small
            // beside the prestress for r_F to reach the tolerance.
            (true, true) => "converged at round-off (r(U) is at the round-off of the \
                             prestress's balance, where the load is too small beside the \
                             prestress for its own residual r_F to reach the tolerance)"
                .to_string(),
            (true, false) => "converged".to_string(),
            (false, _) => format!("NOT converged ({})", r.status),
        },
        r.iterations,
        r.slack_cables,
        r.cables,
        // The stopping measure beside r(U), when it is another measure (and means something).
        match r.measure {
            _ if r.converged && r.at_roundoff => String::new(),
            Measure::EquilibriumResidual => String::new(),
            Measure::ComplementarityResidual =>
            // `+ 0.0`: a −0 reads 0.
                format!("complementarity {:.1e}, ", r.stopping_value + 0.0),
            Measure::Indicator => format!("eta {:.1e}, ", r.stopping_value),
        },
        r.equilibrium_residual,
        1e3 * r.solve_seconds
    );
    // The load path (`large`): where a limit point stopped it, and a row solved from an
    // equilibrium before the previous row's (that one did not reach its α).
    if let (Some(from), Some(reached)) = (r.path_from, r.path_reached) {
        if r.status == tensolve::solvers::Status::LimitPoint {
            line.push_str(&format!(
                ", path from alpha = {} stopped at alpha = {}",
                alpha_label(from),
                alpha_label(reached)
            ));
        } else if r.path_restarted {
            line.push_str(&format!(
                ", path from alpha = {} (the last equilibrium before the rows that did not \
                 reach their alpha)",
                alpha_label(from)
            ));
        }
    }
    // The model of the row, and why that one.
    line.push_str(&format!(", {} ({})", r.model.name(), r.model_reason));
    if !r.status.no_answer()
        && !r.updates_geometry
        && r.max_member_rotation > tensolve::results::SMALL_DISPLACEMENT_LIMIT
    {
        line.push_str(&format!(
            "\n  warning: {} at alpha = {}: a member's ends moved apart by {:.0} % of its length \
             (max deflection {:.3} m); the small-perturbation model (geometry not updated) is \
             not valid beyond {:.0} %: read this row with care (summary.csv: \
             small_displacement_ok = false)",
            r.solver,
            alpha_label(r.alpha),
            100.0 * r.max_member_rotation,
            r.max_deflection,
            100.0 * tensolve::results::SMALL_DISPLACEMENT_LIMIT
        ));
    }
    if let Some(g) = r.governing.filter(|g| g.utilisation > 1.0) {
        let others = match g.over {
            0 | 1 => String::new(),
            n => format!(" ({} other member(s) above 1 too)", n - 1),
        };
        line.push_str(&format!(
            "\n  warning: {} at alpha = {}: member {} is at {:.3} of its {}{others}: a \
             utilisation above 1 (summary.csv: max_utilisation; forces/: every member's). A \
             larger section, a stronger member or less load",
            r.solver,
            alpha_label(r.alpha),
            g.member,
            g.utilisation,
            g.clause.resistance(),
        ));
    }
    if let Some(not_unique) = r
        .uniqueness
        .as_ref()
        .filter(|u| matches!(u, Uniqueness::NotUnique { .. }))
    {
        line.push_str(&format!(
            "\n  warning: {} at alpha = {}: the answer is not unique: the members that carry \
             force leave a motion free that the load does no work on and that stretches no \
             cable (it moves nodes {}); along it lie other equilibria of the same energy, and another \
             solver may return one of them (summary.csv: unique = false). Members or supports \
             that hold that motion, or prestress that keeps its cables taut, make it unique",
            r.solver,
            alpha_label(r.alpha),
            not_unique.motion_nodes()
        ));
    }
    line
}

pub fn report_bench(reporter: &Reporter, progress: Progress) {
    match progress {
        Progress::Reference { method, alpha } => reporter.status(format!(
            "reference ({}) at alpha = {}",
            method.name(),
            alpha_label(alpha)
        )),
        Progress::Solve { method, alpha } => reporter.status(format!(
            "{} at alpha = {}",
            method.name(),
            alpha_label(alpha)
        )),
        Progress::ReferenceNotUnique { alpha, nodes } => reporter.line(&format!(
            "  warning: the reference at alpha = {}: the answer is not unique (a motion free \
             of the load moves nodes {nodes}): other equilibria of the same energy lie along \
             it, so a solver's e against this one may stay large although it converged to \
             another (run's summary.csv: unique = false)",
            alpha_label(alpha)
        )),
        Progress::Done(series) => {
            let last = series.samples.last();
            reporter.line(&format!(
                "{:>11} alpha = {:<6} {:?} after {} it, e = {:.1e}, {:.1} ms (set-up {:.1} ms)",
                series.method.name(),
                alpha_label(series.alpha),
                series.status,
                last.map_or(0, |s| s.iteration),
                last.map_or(f64::NAN, |s| s.error),
                1e3 * last.map_or(0.0, |s| s.seconds),
                1e3 * series.setup_seconds
            ));
            reporter.tick();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_iterate_shows_solver_alpha_iteration_measure_error_and_time() {
        let record = IterationRecord {
            iteration: 37,
            stopping_value: 3.2e-4,
            equilibrium_residual: Some(1e-6),
            rebuilds: 0,
            error: Some(1.1e-3),
            slack_cables: 12,
            elapsed_seconds: 0.84,
        };
        assert_eq!(
            iterate_message("micro-macro", 0.5, Measure::Indicator, &record),
            "micro-macro alpha = 0.5: iteration 37, eta = 3.2e-4, e = 1.1e-3, 12 slack, 0.84 s"
        );
        let record = IterationRecord {
            error: None,
            ..record
        };
        assert_eq!(
            iterate_message("pcg-lcp", 1.0, Measure::ComplementarityResidual, &record),
            "pcg-lcp alpha = 1: iteration 37, residual = 3.2e-4, 12 slack, 0.84 s"
        );
    }
}
