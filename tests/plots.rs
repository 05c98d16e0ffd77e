//! `[output] plots = true`: the SVG figures of a small sweep (4 × 4 modules, three α with
//! slack cables, newton + mono-latin + micro-macro) exist, are well-formed XML, carry their
//! labels as text and draw one series per α or per solver; without the key nothing is drawn.

mod common;

use common::temp_path;
use std::path::{Path, PathBuf};
use tensolve::app::sweep::{run, RunOptions};
use tensolve::output::plots::SERIES_STROKE_WIDTH;

/// Stroke colours of Figure 8's bars, slack cables and load arrows.
const BAR: &str = "#191919";
const SLACK: &str = "#787878";
const LOAD: &str = "#008C46";
/// Bars and cables of the 4 × 4 standard grid.
const BARS: usize = 4 * 16;
const CABLES: usize = 12 * 16;

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
        Run::of_case(tag, &case_text(output))
    }

    fn of_case(tag: &str, text: &str) -> Run {
        let dir = temp_path(tag);
        let case = tensolve::case::parse(text).expect("valid case");
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
    /// Every polyline.
    polylines: Vec<Polyline>,
}

/// A polyline: (stroke colour in upper case, stroke width, points).
type Polyline = (String, String, Vec<(f64, f64)>);

impl Svg {
    /// The points of every series polyline (stroke width [`SERIES_STROKE_WIDTH`]).
    fn series_points(&self) -> Vec<&[(f64, f64)]> {
        let width = SERIES_STROKE_WIDTH.to_string();
        self.polylines
            .iter()
            .filter(|(_, w, _)| *w == width)
            .map(|(_, _, points)| points.as_slice())
            .collect()
    }
}

fn parse_points(list: &str) -> Vec<(f64, f64)> {
    list.split_whitespace()
        .map(|pair| {
            let (x, y) = pair.split_once(',').expect("x,y");
            (x.parse().expect("x"), y.parse().expect("y"))
        })
        .collect()
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
        polylines: polylines
            .iter()
            .map(|n| {
                (
                    n.attribute("stroke").unwrap_or("").to_uppercase(),
                    n.attribute("stroke-width").unwrap_or("").to_string(),
                    parse_points(n.attribute("points").unwrap_or("")),
                )
            })
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
    // One series per α, and α = 0 (the prestress) although the case does not solve it.
    assert_eq!(
        tensions.series,
        ALPHAS.len() + 1,
        "tensions: one series per α and α = 0"
    );
    assert_texts(&tensions, "tensions", &alpha_labels);
    assert_texts(&tensions, "tensions", &["α = 0"]);
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
            "cable τ (N)",
            "strut (bar)",
            "slack cable (40)",
        ],
    );
    assert!(
        deformed
            .texts
            .iter()
            .any(|t| t.starts_with("Deformed structure at α = 30 (newton), displacements × ")),
        "{:?}",
        deformed.texts
    );
    // 40 of the 192 cables are slack at α = 30: their dashes are drawn in the slack colour,
    // in each of the three views.
    let slack_dashes = deformed
        .polylines_by_stroke
        .iter()
        .filter(|s| s.eq_ignore_ascii_case(SLACK))
        .count();
    assert!(slack_dashes >= 3 * 40, "{slack_dashes} slack dashes");
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
        "plots = true\nhistory = false\nsummary = false\ntensions = false\ndisplacements = false\n\
         forces = false\nreactions = false",
    );
    assert_eq!(file_names(&only_plots.0), ["plots"]);
    let eta = read_svg(&only_plots.0.join("plots/eta_micro-macro.svg"));
    assert_eq!(eta.series, ALPHAS.len());
}

/// The case of [`case_text`] with one α and only the solvers named.
fn small_case(alpha: f64, methods: &str, output: &str) -> String {
    format!(
        "[model]\ngeometry = \"linear\"\n[grid]\nmodules = [4, 4]\n[load]\nalpha = [{alpha:?}]\n\
         [solver]\nmethods = [{methods}]\nsubdomains = [2, 2]\n\
         [output]\nplots = true\nhistory = false\nsummary = false\ntensions = false\n\
         displacements = false\n{output}\n"
    )
}

/// Bar polylines of Figure 8 (all three views), in drawing order.
fn bar_lines(svg: &Svg) -> Vec<&[(f64, f64)]> {
    svg.polylines
        .iter()
        .filter(|(stroke, _, _)| stroke == BAR)
        .map(|(_, _, points)| points.as_slice())
        .collect()
}

#[test]
fn figure_8_draws_every_bar_and_cable_in_every_view_and_amplifies_the_displacements() {
    let at = |amplification: f64| {
        let output = format!("amplification = {amplification:?}");
        let run = Run::of_case(
            &format!("deformed-{amplification}"),
            &small_case(30.0, "\"newton\"", &output),
        );
        let svg = read_svg(&run.0.join("plots/deformed_alpha30.svg"));
        (run, svg)
    };
    let (_ten, ten) = at(10.0);
    // Every bar in each of the three views, as a straight segment heavier than the cables
    // (3 px in a grid).
    let bars = bar_lines(&ten);
    assert_eq!(bars.len(), 3 * BARS, "bar segments");
    assert!(bars.iter().all(|points| points.len() == 2));
    assert!(ten
        .polylines
        .iter()
        .filter(|(stroke, _, _)| stroke == BAR)
        .all(|(_, width, _)| width == "3"));
    // Every taut cable in each view, in colour (stroke width 2); the 40 slack ones dashed.
    let taut = ten
        .polylines
        .iter()
        .filter(|(stroke, width, _)| width == "2" && stroke != BAR && stroke != SLACK)
        .count();
    assert_eq!(taut, 3 * (CABLES - 40), "taut cable segments");
    assert_texts(
        &ten,
        "deformed ×10",
        &[
            "cable τ (N)",
            "x (m)",
            "y (m)",
            "z (m)",
            "Deformed structure at α = 30 (newton), displacements × 10",
        ],
    );
    // 256 members: no node or member label.
    let labels: Vec<&String> = ten.texts.iter().filter(|t| is_label(t)).collect();
    assert!(labels.is_empty(), "labels on 256 members: {labels:?}");

    // Another amplification draws other geometry: the same bars, elsewhere.
    let (_forty, forty) = at(40.0);
    assert_texts(
        &forty,
        "deformed ×40",
        &["Deformed structure at α = 30 (newton), displacements × 40"],
    );
    let moved = bar_lines(&forty);
    assert_eq!(moved.len(), bars.len());
    let changed = bars.iter().zip(&moved).filter(|(a, b)| a != b).count();
    assert!(
        changed > BARS,
        "{changed} of {} bar segments moved with the amplification",
        bars.len()
    );
}

#[test]
fn compressed_cables_of_a_bilateral_case_are_drawn_in_the_compression_colours() {
    let case = small_case(30.0, "\"newton\"", "")
        .replace("[solver]", "[cables]\nunilateral = false\n[solver]");
    let run = Run::of_case("deformed-linear", &case);
    let svg = read_svg(&run.0.join("plots/deformed_alpha30.svg"));
    assert_texts(
        &svg,
        "deformed linear",
        &["blue: compressed cable", "slack cable (0)"],
    );
    // Blue cables: blue the largest channel, well above red.
    let blue = svg
        .polylines
        .iter()
        .filter(|(stroke, width, _)| {
            let channel = |k: usize| u8::from_str_radix(&stroke[1 + 2 * k..3 + 2 * k], 16).ok();
            width == "2"
                && stroke.len() == 7
                && matches!((channel(0), channel(2)), (Some(r), Some(b)) if b as i32 > r as i32 + 60)
        })
        .count();
    assert!(blue >= 2, "{blue} compressed cable segments");
}

#[test]
fn convergence_axes_stop_at_max_plot_iterations() {
    let run = Run::of_case(
        "max-iterations",
        &small_case(30.0, "\"micro-macro\"", "max_plot_iterations = 5"),
    );
    for name in ["error_micro-macro.svg", "eta_micro-macro.svg"] {
        let svg = read_svg(&run.0.join("plots").join(name));
        let series = svg.series_points();
        assert_eq!(series.len(), 1, "{name}");
        // Iterations 0 to 5 (micro-macro takes more than 5 iterations at α = 30).
        assert_eq!(series[0].len(), 6, "{name}: {:?}", series[0]);
        // The x axis is labelled up to 5, no further.
        let ticks: Vec<f64> = svg
            .texts
            .iter()
            .filter_map(|t| t.parse::<f64>().ok())
            .collect();
        assert!(ticks.contains(&5.0), "{name}: {ticks:?}");
        assert!(ticks.iter().all(|&t| t <= 5.0), "{name}: {ticks:?}");
    }
}

#[test]
fn figure_12_draws_both_module_kinds_on_one_chart() {
    let run = Run::of_case(
        "modules",
        &small_case(
            30.0,
            "\"newton\", \"micro-macro\"",
            "compare_modules = [\"standard\", \"braced\"]",
        ),
    );
    let svg = read_svg(&run.0.join("plots/error_modules.svg"));
    assert_eq!(svg.series, 2, "one series per module kind and LATIN solver");
    assert_texts(
        &svg,
        "error_modules",
        &[
            "standard, micro-macro",
            "braced, micro-macro",
            "Energy error e per iteration by module kind at α = 30",
        ],
    );
    // Two different structures converge differently: the braced grid is not the standard
    // one drawn twice.
    let series = svg.series_points();
    assert_eq!(series.len(), 2);
    assert_ne!(series[0], series[1], "both series are the same curve");
    let names = file_names(&run.0.join("plots"));
    assert!(
        names.contains(&"error_modules.svg".to_string()),
        "{names:?}"
    );
}

#[test]
fn bad_figure_keys_are_rejected_by_name() {
    for (output, key) in [
        ("amplification = 0.0", "output.amplification"),
        ("amplification = -10.0", "output.amplification"),
        ("max_plot_iterations = 0", "output.max_plot_iterations"),
        (
            "compare_modules = [\"braced\", \"braced\"]",
            "output.compare_modules",
        ),
    ] {
        let error = tensolve::case::parse(&small_case(1.0, "\"newton\"", output))
            .expect_err(output)
            .to_string();
        assert!(error.contains(key), "{output}: {error}");
    }
    // Figure 12 asked for without plots would silently draw nothing.
    let without_plots = small_case(1.0, "\"newton\"", "compare_modules = [\"braced\"]")
        .replace("plots = true", "plots = false");
    let error = tensolve::case::parse(&without_plots)
        .expect_err("compare_modules without plots")
        .to_string();
    assert!(
        error.contains("output.compare_modules") && error.contains("plots = true"),
        "{error}"
    );
}

/// Figure 8 of a general structure (`cases/simplex.toml`, no modules): its captions and legend
/// speak of supports, not of modules or clamped nodes, and both views draw every member
/// undeformed in light grey (#AAAAAA, 2 px) before, so under, the deformed structure.
#[test]
fn figure_8_of_a_general_structure_says_supports_and_draws_the_undeformed_structure_under() {
    let out = temp_path("deformed-general");
    let case = common::manifest_path("cases/simplex.toml");
    let run = common::tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "output.plots=true",
    ]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let svg = read_svg(&out.join("plots/deformed_alpha1.svg"));
    let members = tensolve::case::load(&case).unwrap().structure().links.len();
    let _ = std::fs::remove_dir_all(&out);

    assert_texts(
        &svg,
        "general Figure 8",
        &["▲ support (held node)", "undeformed"],
    );
    for text in &svg.texts {
        let lower = text.to_lowercase();
        assert!(
            !lower.contains("module") && !lower.contains("clamped"),
            "a general structure's Figure 8 says `{text}`"
        );
    }
    assert!(
        svg.texts
            .iter()
            .any(|t| t.starts_with("oblique view (undeformed structure"))
            && svg
                .texts
                .iter()
                .any(|t| t.starts_with("plan, top view (undeformed"))
            && svg
                .texts
                .iter()
                .any(|t| t.starts_with("elevation, front view (undeformed")),
        "{:?}",
        svg.texts
    );
    let undeformed: Vec<usize> = (0..svg.polylines.len())
        .filter(|&i| svg.polylines[i].0 == "#AAAAAA" && svg.polylines[i].1 == "2")
        .collect();
    assert_eq!(
        undeformed.len(),
        3 * members,
        "one undeformed segment per member and view"
    );
    // Under the deformed structure: each view's undeformed members come before its bars.
    let bars: Vec<usize> = (0..svg.polylines.len())
        .filter(|&i| svg.polylines[i].0 == BAR)
        .collect();
    assert_eq!(bars.len(), 3 * 3, "the simplex's three struts in each view");
    assert!(
        bars.iter().all(|&i| svg.polylines[i].1 == "4"),
        "struts 4 px"
    );
    for view in 0..3 {
        assert!(
            undeformed[(view + 1) * members - 1] < bars[3 * view],
            "view {view}: outline under the bars"
        );
    }
    assert!(bars[2] < undeformed[members], "one view after the other");
    assert!(
        bars[5] < undeformed[2 * members],
        "one view after the other"
    );
}

/// `n3`, `m12`: a node or member label of Figure 8.
fn is_label(text: &str) -> bool {
    text.strip_prefix('n')
        .or_else(|| text.strip_prefix('m'))
        .is_some_and(|id| !id.is_empty() && id.chars().all(|c| c.is_ascii_digit()))
}

/// Runs a shipped case (`cases/{name}.toml`) with plots and the extra `--set`s; its output
/// directory, removed when dropped.
fn run_shipped(name: &str, sets: &[&str]) -> Run {
    let out = temp_path(&format!("report-{name}"));
    let case = common::manifest_path(&format!("cases/{name}.toml"));
    let mut args = vec![
        "run",
        case.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "output.plots=true",
    ];
    for set in sets {
        args.extend(["--set", set]);
    }
    let run = common::tensolve(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    Run(out)
}

/// Rows of a CSV file as numbers by column name (non-numeric cells left out).
fn numeric_rows(path: &Path) -> Vec<std::collections::HashMap<String, f64>> {
    common::csv_rows(path)
        .into_iter()
        .map(|row| {
            row.into_iter()
                .filter_map(|(k, v)| v.parse().ok().map(|v| (k, v)))
                .collect()
        })
        .collect()
}

/// Issue 45: the automatic amplification draws the largest displacement as 10 % of the
/// structure's size, rounded to two digits: recomputed here from the run's own displacement
/// table (the diagonal of the nodes' bounding box, the largest |u| of a node), and stated in
/// the title; `output.amplification` still overrides it.
#[test]
fn automatic_amplification_is_a_tenth_of_the_size_over_the_largest_displacement() {
    let run = run_shipped("prism4", &[]);
    let rows = numeric_rows(&run.0.join("displacements/newton_alpha1.csv"));
    assert_eq!(rows.len(), 8, "the prism's 8 nodes");
    let span = |k: &str| {
        let values = rows.iter().map(|r| r[k]);
        values.clone().fold(f64::NEG_INFINITY, f64::max) - values.fold(f64::INFINITY, f64::min)
    };
    let size = (span("x").powi(2) + span("y").powi(2) + span("z").powi(2)).sqrt();
    let largest = rows
        .iter()
        .map(|r| (r["ux"].powi(2) + r["uy"].powi(2) + r["uz"].powi(2)).sqrt())
        .fold(0.0, f64::max);
    // The case's comment: the top moves 41.7 mm at α = 1.
    assert!(
        (largest - 0.0417).abs() < 5e-4,
        "largest displacement {largest}"
    );
    let exact = 0.1 * size / largest;
    let unit = 10f64.powf(exact.log10().floor() - 1.0);
    let expected = (exact / unit).round() * unit;
    let svg = read_svg(&run.0.join("plots/deformed_alpha1.svg"));
    let title = svg
        .texts
        .iter()
        .find_map(|t| t.strip_prefix("Deformed structure at α = 1 (newton), displacements × "))
        .unwrap_or_else(|| panic!("no title among {:?}", svg.texts));
    let stated: f64 = title.parse().expect("a number");
    assert!(
        (stated - expected).abs() < 1e-9 * expected,
        "stated × {stated}, 10 % of {size} m over {largest} m is × {exact}"
    );
    assert!(
        svg.texts
            .iter()
            .any(|t| t.contains("drawn as 10 % of the structure's size") && t.contains("41.7 mm")),
        "{:?}",
        svg.texts
    );
    // The override.
    let given = run_shipped("prism4", &["output.amplification=25.0"]);
    let svg = read_svg(&given.0.join("plots/deformed_alpha1.svg"));
    assert_texts(
        &svg,
        "prism × 25",
        &["Deformed structure at α = 1 (newton), displacements × 25"],
    );
}

/// Issue 45: the simplex's Figure 8 has an elevation beside the plan and the oblique view;
/// each view marks the 3 supports with a triangle and the 3 loads with an arrow (a shaft and a
/// head each, in the load colour), labels the 6 nodes, and the oblique view the 9 members.
#[test]
fn figure_8_of_a_small_structure_has_an_elevation_supports_loads_and_labels() {
    let run = run_shipped("simplex", &[]);
    let path = run.0.join("plots/deformed_alpha1.svg");
    let svg = read_svg(&path);
    assert_texts(
        &svg,
        "simplex",
        &["x (m)", "y (m)", "z (m)", "load (max 1.04 kN)"],
    );
    assert!(svg
        .texts
        .iter()
        .any(|t| t.starts_with("elevation, front view")));
    for node in 0..6 {
        let label = format!("n{node}");
        let count = svg.texts.iter().filter(|t| **t == label).count();
        assert_eq!(count, 3, "{label} in each view");
    }
    for member in 0..9 {
        let label = format!("m{member}");
        let count = svg.texts.iter().filter(|t| **t == label).count();
        assert_eq!(count, 1, "{label} in the oblique view");
    }
    let text = std::fs::read_to_string(&path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let supports = doc
        .descendants()
        .filter(|n| n.has_tag_name("polygon") && n.attribute("fill") == Some("#000000"))
        .count();
    assert_eq!(supports, 3 * 3, "3 supports in 3 views");
    let arrows = svg.polylines.iter().filter(|(s, _, _)| s == LOAD).count();
    assert_eq!(
        arrows,
        3 * 3 * 2,
        "3 loads in 3 views, a shaft and a head each"
    );
}

/// Issue 45: `output.figure_alpha` picks the α of Figure 8 and of the member-force chart; one
/// not solved exits 2 naming the key, the value and the α available.
#[test]
fn figure_alpha_picks_the_load_factor_drawn() {
    let run = run_shipped("simplex", &["output.figure_alpha=0.5"]);
    let names = file_names(&run.0.join("plots"));
    assert!(
        names.contains(&"deformed_alpha0.5.svg".to_string()),
        "{names:?}"
    );
    assert!(
        !names.contains(&"deformed_alpha1.svg".to_string()),
        "{names:?}"
    );
    let forces = read_svg(&run.0.join("plots/member_forces.svg"));
    assert_texts(
        &forces,
        "member forces",
        &["Member forces at α = 0.5 (newton)"],
    );

    let case = common::manifest_path("cases/simplex.toml");
    let out = temp_path("figure-alpha-bad");
    let bad = common::tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "output.figure_alpha=0.3",
    ]);
    let _ = std::fs::remove_dir_all(&out);
    assert_eq!(common::code(&bad), 2);
    let message = common::stderr(&bad);
    for wanted in ["output.figure_alpha", "0.3", "0.25, 0.5, 1"] {
        assert!(message.contains(wanted), "no `{wanted}` in: {message}");
    }
}

/// Issue 45: four cables from one node to the corners of a tetrahedron, 1 kN of prestress
/// each and a load of a few newtons: tensions within 0.5 % of each other. The colour scale
/// spans their own range, so the least and the most tensioned cables take the two ends of the
/// ramp (yellow #FECC5C, dark red #800026), not four nearly equal dark reds.
#[test]
fn near_uniform_tensions_span_the_whole_colour_scale() {
    let dir = temp_path("near-uniform");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("nodes.csv"),
        "node,x,y,z\n0,0,0,0\n1,1,1,1\n2,1,-1,-1\n3,-1,1,-1\n4,-1,-1,1\n",
    )
    .unwrap();
    let members: String = (1..=4)
        .map(|b| format!("{},0,{b},cable,1e11,1e-4,1000.0\n", b - 1))
        .collect();
    std::fs::write(
        dir.join("members.csv"),
        format!("member,a,b,kind,young,section,prestress\n{members}"),
    )
    .unwrap();
    std::fs::write(
        dir.join("case.toml"),
        "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n\
         [[supports.fix]]\nnodes = [1, 2, 3, 4]\n\
         [[load.point]]\nnodes = [0]\nforce = [2.0, 3.0, 4.0]\n\
         [load]\nalpha = [1.0]\n[output]\nplots = true\n",
    )
    .unwrap();
    let case = tensolve::case::load(&dir.join("case.toml")).expect("valid case");
    let out = dir.join("out");
    let options = RunOptions {
        out_dir: Some(out.clone()),
        methods: None,
    };
    run(&case, &options, &mut |_| {}).expect("converges");
    let tensions: Vec<f64> = numeric_rows(&out.join("forces/newton_alpha1.csv"))
        .iter()
        .map(|r| r["force_N"])
        .collect();
    let svg = read_svg(&out.join("plots/deformed_alpha1.svg"));
    let _ = std::fs::remove_dir_all(&dir);
    let (lo, hi) = tensions
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &t| {
            (lo.min(t), hi.max(t))
        });
    assert!(lo > 990.0 && hi < 1010.0 && hi - lo > 1.0, "{tensions:?}");
    let cable_colours: Vec<&str> = svg
        .polylines
        .iter()
        .filter(|(stroke, width, _)| width == "2" && stroke != "#AAAAAA" && stroke != LOAD)
        .map(|(stroke, _, _)| stroke.as_str())
        .collect();
    assert_eq!(cable_colours.len(), 3 * 4, "4 cables in 3 views");
    for end in ["#FECC5C", "#800026"] {
        assert_eq!(
            cable_colours.iter().filter(|c| **c == end).count(),
            3,
            "{end} once per view: {cable_colours:?}"
        );
    }
}

/// Issue 45: a general structure under 100 members draws `member_forces.svg` instead of the
/// rank-sorted `tensions.svg`: on the tower (9 struts, 36 cables, 2 slack at α = 1) one label
/// per member in table order, one bar per member that is not slack, struts near black and
/// cables in colour, each as long as the member's force in the run's forces table.
#[test]
fn member_force_chart_has_one_labelled_bar_per_member() {
    let run = run_shipped("tower", &[]);
    let names = file_names(&run.0.join("plots"));
    assert!(
        names.contains(&"member_forces.svg".to_string()),
        "{names:?}"
    );
    assert!(!names.contains(&"tensions.svg".to_string()), "{names:?}");
    let forces = common::csv_rows(&run.0.join("forces/newton_alpha1.csv"));
    assert_eq!(forces.len(), 45);
    let path = run.0.join("plots/member_forces.svg");
    let svg = read_svg(&path);
    let slack: Vec<bool> = forces
        .iter()
        .map(|r| r["force_N"].parse::<f64>().unwrap() == 0.0)
        .collect();
    assert_eq!(slack.iter().filter(|&&s| s).count(), 2);
    for (row, &is_slack) in forces.iter().zip(&slack) {
        let tail = if is_slack { " (slack)" } else { "" };
        let label = format!("m{} {}{tail}", row["member"], row["kind"]);
        let count = svg.texts.iter().filter(|t| **t == label).count();
        assert_eq!(count, 1, "{label}");
    }
    // The bars: rectangles other than the white background, in member order.
    let text = std::fs::read_to_string(&path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let bars: Vec<(f64, String)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("rect") && n.attribute("fill") != Some("#FFFFFF"))
        .map(|n| {
            let width: f64 = n.attribute("width").unwrap().parse().unwrap();
            (width, n.attribute("fill").unwrap().to_uppercase())
        })
        .collect();
    let drawn: Vec<&std::collections::HashMap<String, String>> = forces
        .iter()
        .zip(&slack)
        .filter(|(_, &s)| !s)
        .map(|(r, _)| r)
        .collect();
    assert_eq!(
        bars.len(),
        drawn.len(),
        "one bar per member that is not slack"
    );
    let magnitude =
        |r: &std::collections::HashMap<String, String>| r["force_N"].parse::<f64>().unwrap().abs();
    let largest = drawn.iter().map(|r| magnitude(r)).fold(0.0, f64::max);
    let longest = bars.iter().map(|(w, _)| *w).fold(0.0, f64::max);
    for ((width, fill), row) in bars.iter().zip(&drawn) {
        let expected = longest * magnitude(row) / largest;
        assert!(
            (width - expected).abs() <= 1.5,
            "m{}: {width} px, {expected:.1} expected",
            row["member"]
        );
        assert_eq!(
            fill == BAR,
            row["kind"] == "bar",
            "m{}: {fill}",
            row["member"]
        );
    }
}
