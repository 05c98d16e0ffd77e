//! `tensolve bench`: how fast each solver of a case gets close to the exact answer.
//!
//! For every α of the case a reference is solved once with `newton` at its own tight defaults
//! (not timed). Then every solver of the case (`solver.methods`, with the case's tolerance and
//! iteration cap) solves the same load, and each of its iterates is recorded as (wall time, e):
//!
//! * **e** is the energy error of SPEC §4 and the paper §5.3,
//!   `e² = Σ_links l (B U − B U_ref)² / Σ_links l (B U_ref)²`, l the link stiffness.
//! * **wall time** is the solver's set-up (building the structure, plus the factorization of the
//!   taut stiffness for `newton` and `pcg-lcp`, plus the solver's own set-up: the same split as
//!   `summary.csv`'s `setup_seconds`) plus the time the solve had taken when the iterate was
//!   reached, read from the solver's own clock ([`IterationRecord::elapsed_seconds`]). The last
//!   iterate is timed at the end of the solve, answer assembled.
//!
//! The LATIN solvers measure e themselves after every linear stage when given the reference
//! ([`IterationRecord::error`], weighted by their search direction l, which is the stiffness
//! unless the case sets `solver.l` to a number). `newton` and `pcg-lcp` do not: their
//! observers see no displacements. Their iterate k is obtained instead by running the solver
//! again from scratch with `max_iterations = k` (k = 1, 2, … up to the iteration the full
//! solve stopped at). A capped solve does exactly what the full solve did up to iteration k, so
//! its answer is iterate k and e is computed from its displacements; the re-runs are not timed
//! (their time is that of the full solve at iteration k, already recorded). This costs O(n²)
//! iterations for n iterations, which is cheap for the iteration counts these solvers need.

use crate::case::{Case, CaseError, Method};
use crate::configure::{ConfiguredSolver, Limits, Prepared};
use crate::output::{alpha_label, write_atomic};
use crate::solvers::{IterationRecord, Observer, SetupError, Silent, Status};
use crate::structure::Structure;
use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;

/// Header of `bench.csv`.
pub const CSV_HEADER: &str = "solver,alpha,iteration,seconds,error_e";

/// The error levels of the table.
pub const THRESHOLDS: [f64; 4] = [1e-2, 1e-4, 1e-6, 1e-8];

#[derive(Debug, Error)]
pub enum BenchError {
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error(transparent)]
    Setup(#[from] SetupError),
    #[error(
        "output directory `{dir}` is not writable ({reason}): pass `--out DIR` with a directory \
         you can write to"
    )]
    OutputDir { dir: String, reason: String },
    #[error("could not write `{path}`: {reason}")]
    Write { path: String, reason: String },
    #[error(
        "the reference (newton at its default settings) did not converge at alpha = {alpha} \
         ({status:?}, residual {residual:e}), so e cannot be measured"
    )]
    Reference {
        alpha: String,
        status: Status,
        residual: f64,
    },
    #[error(
        "{count} solve(s) stopped before their stopping criterion: {list}; bench.csv and the \
         table show how far they got"
    )]
    NotConverged { count: usize, list: String },
}

impl BenchError {
    /// As for `run`: 2 for bad input (the case, the structure, the output directory); 1 when
    /// the bench could not produce what was asked.
    pub fn exit_code(&self) -> i32 {
        match self {
            BenchError::Case(_) | BenchError::Setup(_) | BenchError::OutputDir { .. } => 2,
            BenchError::Write { .. }
            | BenchError::Reference { .. }
            | BenchError::NotConverged { .. } => 1,
        }
    }
}

/// One iterate of one solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub iteration: usize,
    /// Wall time since the start of the solver's set-up, s.
    pub seconds: f64,
    /// Energy error e against the reference.
    pub error: f64,
}

/// Every iterate of one solver at one α.
#[derive(Debug, Clone)]
pub struct Series {
    pub method: Method,
    pub alpha: f64,
    pub setup_seconds: f64,
    pub status: Status,
    /// In increasing iteration and time.
    pub samples: Vec<Sample>,
}

impl Series {
    /// Wall time (set-up included) of the first iterate with e ≤ `threshold`.
    pub fn seconds_to_reach(&self, threshold: f64) -> Option<f64> {
        self.samples
            .iter()
            .find(|s| s.error <= threshold)
            .map(|s| s.seconds)
    }

    pub fn final_error(&self) -> Option<f64> {
        self.samples.last().map(|s| s.error)
    }
}

/// One row of the table: a solver at one α.
#[derive(Debug, Clone)]
pub struct TableRow {
    pub solver: &'static str,
    pub alpha: f64,
    /// Per [`THRESHOLDS`] entry: the wall time to reach it, set-up included.
    pub seconds_to_reach: [Option<f64>; THRESHOLDS.len()],
    pub final_error: Option<f64>,
    pub converged: bool,
}

/// Time to reach each error level, per solver and α.
#[derive(Debug, Clone)]
pub struct Table {
    pub rows: Vec<TableRow>,
}

impl Table {
    pub fn new(series: &[Series]) -> Table {
        let rows = series
            .iter()
            .map(|s| TableRow {
                solver: s.method.name(),
                alpha: s.alpha,
                seconds_to_reach: THRESHOLDS.map(|t| s.seconds_to_reach(t)),
                final_error: s.final_error(),
                converged: s.status.converged(),
            })
            .collect();
        Table { rows }
    }
}

/// `12.3 ms`, `1.23 s`.
fn format_seconds(seconds: f64) -> String {
    let ms = 1e3 * seconds;
    if ms < 10.0 {
        format!("{ms:.2} ms")
    } else if ms < 1e3 {
        format!("{ms:.1} ms")
    } else {
        format!("{seconds:.2} s")
    }
}

impl fmt::Display for Table {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "wall time to reach e <= threshold, set-up included (— never reached)"
        )?;
        write!(f, "{:<12} {:>6}", "solver", "alpha")?;
        for t in THRESHOLDS {
            write!(f, " {:>10}", format!("e<={t:e}"))?;
        }
        writeln!(f, " {:>9}", "final e")?;
        for row in &self.rows {
            write!(f, "{:<12} {:>6}", row.solver, alpha_label(row.alpha))?;
            for seconds in row.seconds_to_reach {
                let cell = seconds.map(format_seconds).unwrap_or_else(|| "—".into());
                write!(f, " {cell:>10}")?;
            }
            let last = row.final_error.map(|e| format!("{e:.1e}"));
            write!(f, " {:>9}", last.unwrap_or_else(|| "—".into()))?;
            writeln!(
                f,
                "{}",
                if row.converged {
                    ""
                } else {
                    "  (not converged)"
                }
            )?;
        }
        Ok(())
    }
}

/// What `bench` measured.
#[derive(Debug, Clone)]
pub struct Bench {
    /// Per α, per solver in the case's order.
    pub series: Vec<Series>,
    pub table: Table,
}

impl Bench {
    /// `Err(NotConverged)` when a solver stopped before its criterion.
    pub fn check_converged(&self) -> Result<(), BenchError> {
        let failures: Vec<String> = self
            .series
            .iter()
            .filter(|s| !s.status.converged())
            .map(|s| {
                format!(
                    "{} at alpha = {} ({:?})",
                    s.method.name(),
                    alpha_label(s.alpha),
                    s.status
                )
            })
            .collect();
        if failures.is_empty() {
            Ok(())
        } else {
            Err(BenchError::NotConverged {
                count: failures.len(),
                list: failures.join(", "),
            })
        }
    }
}

/// What `measure` is doing, for progress displays.
#[derive(Debug, Clone, Copy)]
pub enum Progress<'a> {
    /// Solving the reference at α.
    Reference { alpha: f64 },
    /// Set-up and timed solve of a solver at α.
    Solve { method: Method, alpha: f64 },
    /// Capped re-run `cap` of `of` (newton, pcg-lcp).
    Rerun {
        method: Method,
        alpha: f64,
        cap: usize,
        of: usize,
    },
    /// A solver at α is measured.
    Done(&'a Series),
}

/// The reference answer at one α and what e needs of it.
struct Reference {
    displacements: Vec<f64>,
    elongations: Vec<f64>,
    /// `Σ k (B U_ref)²`.
    energy: f64,
}

impl Reference {
    /// `newton` at its default (tight) settings; refused unless it converged.
    fn solve(
        case: &Case,
        prepared: &Prepared,
        load: &[f64],
        alpha: f64,
    ) -> Result<Reference, BenchError> {
        let mut newton = ConfiguredSolver::new(
            Method::Newton,
            case,
            &prepared.structure,
            &prepared.taut,
            Limits::default(),
        )?;
        let solution = newton.solve(load, None, &mut Silent);
        if !solution.info.status.converged() {
            return Err(BenchError::Reference {
                alpha: alpha_label(alpha),
                status: solution.info.status,
                residual: solution.info.residual,
            });
        }
        let s = &prepared.structure;
        let displacements = solution.equilibrium.displacements;
        let mut elongations = vec![0.0; s.links.len()];
        s.elongations(&displacements, &mut elongations);
        let energy = stiffness_weighted_norm2(s, &elongations);
        Ok(Reference {
            displacements,
            elongations,
            energy,
        })
    }

    /// e of displacements `u`: relative when the reference strains anything, absolute else
    /// (as the LATIN solvers measure it).
    fn error(&self, s: &Structure, u: &[f64]) -> f64 {
        let mut difference = vec![0.0; s.links.len()];
        s.elongations(u, &mut difference);
        difference
            .iter_mut()
            .zip(&self.elongations)
            .for_each(|(d, r)| *d -= r);
        let distance = stiffness_weighted_norm2(s, &difference);
        if self.energy > 0.0 {
            (distance / self.energy).sqrt()
        } else {
            distance.sqrt()
        }
    }
}

/// `Σ_links k e²`.
fn stiffness_weighted_norm2(s: &Structure, elongations: &[f64]) -> f64 {
    s.links
        .iter()
        .zip(elongations)
        .map(|(l, e)| l.stiffness * e * e)
        .sum()
}

/// Turns the solver's iteration records into samples (e as reported, when reported).
struct SampleRecorder {
    setup_seconds: f64,
    samples: Vec<Sample>,
}

impl Observer for SampleRecorder {
    fn iteration(&mut self, record: &IterationRecord) {
        self.samples.push(Sample {
            iteration: record.iteration,
            seconds: self.setup_seconds + record.elapsed_seconds,
            error: record.error.unwrap_or(f64::NAN),
        });
    }
}

/// Run every solver of the case at every α of it against a `newton` reference.
pub fn measure(
    case: &Case,
    prepared: &Prepared,
    on_progress: &mut dyn FnMut(Progress),
) -> Result<Bench, BenchError> {
    let mut series = Vec::new();
    for &alpha in &case.load.alphas {
        let load: Vec<f64> = prepared
            .structure
            .unit_load
            .iter()
            .map(|f| alpha * f)
            .collect();
        on_progress(Progress::Reference { alpha });
        let reference = Reference::solve(case, prepared, &load, alpha)?;
        for &method in &case.solver.methods {
            on_progress(Progress::Solve { method, alpha });
            let measured = measure_series(
                case,
                prepared,
                method,
                alpha,
                &load,
                &reference,
                on_progress,
            )?;
            on_progress(Progress::Done(&measured));
            series.push(measured);
        }
    }
    let table = Table::new(&series);
    Ok(Bench { series, table })
}

/// Set up and solve once, recording every iterate; fill in e where the solver did not.
fn measure_series(
    case: &Case,
    prepared: &Prepared,
    method: Method,
    alpha: f64,
    load: &[f64],
    reference: &Reference,
    on_progress: &mut dyn FnMut(Progress),
) -> Result<Series, SetupError> {
    let clock = Instant::now();
    let mut solver = ConfiguredSolver::new(
        method,
        case,
        &prepared.structure,
        &prepared.taut,
        Limits::of_case(case),
    )?;
    let setup_seconds = prepared.shared_setup_seconds(method) + clock.elapsed().as_secs_f64();
    let mut recorder = SampleRecorder {
        setup_seconds,
        samples: Vec::new(),
    };
    let solution = solver.solve(load, Some(&reference.displacements), &mut recorder);
    let mut samples = recorder.samples;
    let final_error = if method.is_latin() {
        samples.last().map_or(f64::NAN, |s| s.error)
    } else {
        reference.error(&prepared.structure, &solution.equilibrium.displacements)
    };
    // The last iterate is the answer: timed when the solve returned it.
    let last = solution.info.iterations;
    samples.retain(|s| s.iteration < last);
    samples.push(Sample {
        iteration: last,
        seconds: setup_seconds + solution.info.solve_seconds,
        error: final_error,
    });
    if !method.is_latin() {
        let of = last.saturating_sub(1);
        for sample in samples.iter_mut().filter(|s| s.iteration < last) {
            let cap = sample.iteration;
            on_progress(Progress::Rerun {
                method,
                alpha,
                cap,
                of,
            });
            sample.error = capped_error(case, prepared, method, cap, load, reference)?;
        }
    }
    Ok(Series {
        method,
        alpha,
        setup_seconds,
        status: solution.info.status,
        samples,
    })
}

/// e of iterate `cap` of newton or pcg-lcp: the answer of a solve capped at `cap` iterations.
fn capped_error(
    case: &Case,
    prepared: &Prepared,
    method: Method,
    cap: usize,
    load: &[f64],
    reference: &Reference,
) -> Result<f64, SetupError> {
    let limits = Limits {
        max_iterations: Some(cap),
        ..Limits::of_case(case)
    };
    let mut solver =
        ConfiguredSolver::new(method, case, &prepared.structure, &prepared.taut, limits)?;
    let solution = solver.solve(load, None, &mut Silent);
    Ok(reference.error(&prepared.structure, &solution.equilibrium.displacements))
}

/// `out/<case file stem>-bench`.
pub fn default_dir(case_path: &Path) -> PathBuf {
    let stem = case_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "case".into());
    Path::new("out").join(format!("{stem}-bench"))
}

/// Create `dir` and make sure a file can be written in it.
pub fn ensure_writable(dir: &Path) -> Result<(), BenchError> {
    crate::output::ensure_writable(dir).map_err(|e| BenchError::OutputDir {
        dir: dir.display().to_string(),
        reason: e.to_string(),
    })
}

/// `bench.csv` and `bench.svg` under `dir`, each written atomically.
pub fn write_files(dir: &Path, bench: &Bench, title: &str) -> Result<(), BenchError> {
    let fail = |path: &Path, reason: String| BenchError::Write {
        path: path.display().to_string(),
        reason,
    };
    let csv = dir.join("bench.csv");
    write_atomic(&csv, |w| write_csv(w, &bench.series)).map_err(|e| fail(&csv, e.to_string()))?;
    let svg_path = dir.join("bench.svg");
    let svg = render_svg(&bench.series, title).map_err(|e| fail(&svg_path, e))?;
    write_atomic(&svg_path, |w| w.write_all(svg.as_bytes()))
        .map_err(|e| fail(&svg_path, e.to_string()))
}

/// `solver,alpha,iteration,seconds,error_e`, one row per iterate.
pub fn write_csv(w: &mut dyn Write, series: &[Series]) -> std::io::Result<()> {
    writeln!(w, "{CSV_HEADER}")?;
    for s in series {
        for sample in &s.samples {
            writeln!(
                w,
                "{},{},{},{},{:e}",
                s.method.name(),
                alpha_label(s.alpha),
                sample.iteration,
                sample.seconds,
                sample.error
            )?;
        }
    }
    Ok(())
}

/// One colour per solver, in [`Method::ALL`] order: the colours of the run's figures.
const COLOURS: [plotters::style::RGBColor; 4] = [
    plotters::style::RGBColor(31, 119, 180),
    plotters::style::RGBColor(255, 127, 14),
    plotters::style::RGBColor(44, 160, 44),
    plotters::style::RGBColor(148, 103, 189),
];

/// A series with more iterates than this is drawn as a line only: its markers would merge.
const MAX_MARKED_POINTS: usize = 100;

/// Smallest e drawn: e = 0 (an iterate equal to the reference) sits on the lower edge.
const PLOT_FLOOR: f64 = 1e-16;

/// Log range `[lo, hi]` widened to whole decades around the finite positive `values`.
fn decade_range(values: impl Iterator<Item = f64>, floor: f64) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .map(|v| v.max(floor))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return 1e-3..1.0;
    }
    let lo = 10f64.powf(lo.log10().floor());
    let hi = 10f64.powf(hi.log10().ceil()).max(10.0 * lo);
    lo..hi
}

/// The solver, its α when the plot has several, and a note when an iterate has e = 0.
fn series_label(s: &Series, several_alphas: bool) -> String {
    let mut label = s.method.name().to_string();
    if several_alphas {
        label += &format!(" (α = {})", alpha_label(s.alpha));
    }
    if s.samples.iter().any(|p| p.error == 0.0) {
        label += ", e = 0 on the lower edge";
    }
    label
}

/// e against wall time, log–log, one line per solver (and α): an SVG document.
pub fn render_svg(series: &[Series], title: &str) -> Result<String, String> {
    use plotters::prelude::*;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let samples = || series.iter().flat_map(|s| s.samples.iter());
        let x_range = decade_range(samples().map(|p| p.seconds), 1e-9);
        let y_range = decade_range(samples().map(|p| p.error), PLOT_FLOOR);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 24))
            .margin(20)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(x_range.log_scale(), y_range.clone().log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("wall time, set-up included (s)")
            .y_desc("energy error e (–)")
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 18))
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        let several_alphas = series.iter().any(|s| s.alpha != series[0].alpha);
        for s in series {
            let index = Method::ALL.iter().position(|&m| m == s.method).unwrap_or(0);
            let colour = COLOURS[index % COLOURS.len()];
            let points: Vec<(f64, f64)> = s
                .samples
                .iter()
                .filter(|p| p.error.is_finite())
                .map(|p| (p.seconds, p.error.max(y_range.start)))
                .collect();
            if points.len() <= MAX_MARKED_POINTS {
                chart
                    .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| e.to_string())?;
            }
            chart
                .draw_series(LineSeries::new(points, colour.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(series_label(s, several_alphas))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .label_font(("sans-serif", 16))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}
