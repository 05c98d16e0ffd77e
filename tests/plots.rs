//! `[output] plots = true`: the SVG figures of a small sweep (4 × 4 modules, three α with
//! slack cables, newton + mono-latin + micro-macro) exist, are well-formed XML, carry their
//! labels as text and draw one series per α or per solver; without the key nothing is drawn.

mod common;

use common::temp_path;
use std::path::{Path, PathBuf};
use tensolve::app::sweep::{run, RunOptions};
use tensolve::output::plots::SERIES_STROKE_WIDTH;

const SOLVERS: [&str; 3] = ["newton", "mono-latin", "micro-macro"];
const ALPHAS: [&str; 3] = ["1", "10", "30"];

fn case_text(output: &str) -> String {
    format!(
        "[grid]\nmodules = [4, 4]\n[load]\nalpha = [1.0, 10.0, 30.0]\n\
         [solver]\nmethods = [\"newton\", \"mono-latin\", \"micro-macro\"]\nsubdomains = [2, 2]\n\
         [output]\n{output}\n"
    )
}

/// Runs the case into a fresh directory, removed when dropped.
struct Run(PathBuf);

impl Run {
    fn new(tag: &str, output: &str) -> Run {
        let dir = temp_path(tag);
        let case = tensolve::case::parse(&case_text(output)).expect("valid case");
        let options = RunOptions {
            out_dir: Some(dir.clone()),
            methods: None,
        };
        run(&case, &options, &mut |_| {}).expect("every solve converges");
        Run(dir)
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        // The run's lock and manifest (issue 13) are bookkeeping, not results.
        .filter(|n| !n.starts_with(".tensolve"))
        .collect();
    names.sort();
    names
}

/// A parsed SVG: its series polylines and its texts.
struct Svg {
    series: usize,
    texts: Vec<String>,
    polylines_by_stroke: Vec<String>,
}

fn read_svg(path: &Path) -> Svg {
    let text = std::fs::read_to_string(path).unwrap();
    for bad in ["NaN", "inf"] {
        assert!(!text.contains(bad), "{}: contains {bad}", path.display());
    }
    let doc = roxmltree::Document::parse(&text)
        .unwrap_or_else(|e| panic!("{} is not well-formed XML: {e}", path.display()));
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let width = SERIES_STROKE_WIDTH.to_string();
    let polylines: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("polyline"))
        .collect();
    Svg {
        series: polylines
            .iter()
            .filter(|n| n.attribute("stroke-width") == Some(width.as_str()))
            .count(),
        texts: doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text())
            .map(|t| t.trim().to_string())
            .collect(),
        polylines_by_stroke: polylines
            .iter()
            .filter_map(|n| n.attribute("stroke"))
            .map(str::to_string)
            .collect(),
    }
}

fn assert_texts(svg: &Svg, name: &str, wanted: &[&str]) {
    for w in wanted {
        assert!(
            svg.texts.iter().any(|t| t == w),
            "{name}: no text `{w}` among {:?}",
            svg.texts
        );
    }
}

/// `10⁻³`, `10⁰`, `10²`: how a log axis labels its decades.
fn is_power_of_ten_label(text: &str) -> bool {
    text.strip_prefix("10")
        .is_some_and(|e| !e.is_empty() && e.chars().all(|c| "⁻⁰¹²³⁴⁵⁶⁷⁸⁹".contains(c)))
}

#[test]
fn every_figure_is_well_formed_with_one_series_per_alpha_or_solver() {
    let out = Run::new("plots", "plots = true");
    let plots = out.0.join("plots");
    assert_eq!(
        file_names(&plots),
        [
            "deformed_alpha30.svg",
            "error_all.svg",
            "error_micro-macro.svg",
            "error_mono-latin.svg",
            "eta_micro-macro.svg",
            "eta_mono-latin.svg",
            "slack_fraction.svg",
            "tensions.svg",
        ]
    );
    let alpha_labels: Vec<String> = ALPHAS.iter().map(|a| format!("α = {a}")).collect();
    let alpha_labels: Vec<&str> = alpha_labels.iter().map(String::as_str).collect();

    let tensions = read_svg(&plots.join("tensions.svg"));
    assert_eq!(tensions.series, ALPHAS.len(), "tensions: one series per α");
    assert_texts(&tensions, "tensions", &alpha_labels);
    assert_texts(
        &tensions,
        "tensions",
        &["cable tension τ (N)", "cable rank (–)"],
    );

    let slack = read_svg(&plots.join("slack_fraction.svg"));
    assert_eq!(
        slack.series,
        SOLVERS.len(),
        "slack_fraction: one series per solver"
    );
    assert_texts(&slack, "slack_fraction", &SOLVERS);
    assert_texts(&slack, "slack_fraction", &["load factor α (–)"]);

    for solver in ["mono-latin", "micro-macro"] {
        for measure in ["error", "eta"] {
            let name = format!("{measure}_{solver}.svg");
            let svg = read_svg(&plots.join(&name));
            assert_eq!(svg.series, ALPHAS.len(), "{name}: one series per α");
            assert_texts(&svg, &name, &alpha_labels);
            assert_texts(&svg, &name, &["iteration (–)"]);
            let decades = svg
                .texts
                .iter()
                .filter(|t| is_power_of_ten_label(t))
                .count();
            assert!(
                decades >= 3,
                "{name}: a log y axis labels decades: {:?}",
                svg.texts
            );
        }
    }

    let all = read_svg(&plots.join("error_all.svg"));
    assert_eq!(all.series, 2, "error_all: one series per LATIN solver");
    assert_texts(&all, "error_all", &["mono-latin", "micro-macro"]);
    assert_texts(
        &all,
        "error_all",
        &["Energy error e per iteration at α = 30"],
    );

    let deformed = read_svg(&plots.join("deformed_alpha30.svg"));
    assert_texts(
        &deformed,
        "deformed",
        &[
            "x (m)",
            "y (m)",
            "nodes: uz (m)",
            "taut cables: τ (N)",
            "slack cable (τ = 0)",
        ],
    );
    // 40 of the 192 cables are slack at α = 30: their dashes are drawn in the slack colour.
    let slack_dashes = deformed
        .polylines_by_stroke
        .iter()
        .filter(|s| s.eq_ignore_ascii_case("#E41A1C"))
        .count();
    assert!(slack_dashes >= 40, "{slack_dashes} slack dashes");
}

#[test]
fn figures_need_no_history_file_and_nothing_is_drawn_unless_asked() {
    let without = Run::new("no-plots", "");
    let names = file_names(&without.0);
    assert!(!names.contains(&"plots".to_string()), "{names:?}");
    assert!(!names.contains(&"vtk".to_string()), "{names:?}");

    // The convergence figures come from the solve's own records, not from the history files.
    let only_plots = Run::new(
        "plots-only",
        "plots = true\nhistory = false\nsummary = false\ntensions = false\ndisplacements = false",
    );
    assert_eq!(file_names(&only_plots.0), ["plots"]);
    let eta = read_svg(&only_plots.0.join("plots/eta_micro-macro.svg"));
    assert_eq!(eta.series, ALPHAS.len());
}
