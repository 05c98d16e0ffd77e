//! `[output] plots = true`: the SVG figures of a small sweep (4 × 4 modules, three α with
//! slack cables, newton + mono-latin + micro-macro) exist, are well-formed XML, carry their
//! labels as text and draw one series per α or per solver; without the key nothing is drawn.

mod common;

use common::temp_path;
use std::path::{Path, PathBuf};
use tensolve::app::sweep::{run, RunOptions};
use tensolve::output::plots::SERIES_STROKE_WIDTH;

/// Stroke colours of Figure 8's bars and slack cables.
const BAR: &str = "#191919";
const SLACK: &str = "#787878";
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
            "bar",
            "slack cable (40)",
            "Deformed structure at α = 30 (newton), displacements × 10",
        ],
    );
    // 40 of the 192 cables are slack at α = 30: their dashes are drawn in the slack colour,
    // in each of the two views.
    let slack_dashes = deformed
        .polylines_by_stroke
        .iter()
        .filter(|s| s.eq_ignore_ascii_case(SLACK))
        .count();
    assert!(slack_dashes >= 2 * 40, "{slack_dashes} slack dashes");
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
        "[grid]\nmodules = [4, 4]\n[load]\nalpha = [{alpha:?}]\n\
         [solver]\nmethods = [{methods}]\nsubdomains = [2, 2]\n\
         [output]\nplots = true\nhistory = false\nsummary = false\ntensions = false\n\
         displacements = false\n{output}\n"
    )
}

/// Bar polylines of Figure 8 (both views), in drawing order.
fn bar_lines(svg: &Svg) -> Vec<&[(f64, f64)]> {
    svg.polylines
        .iter()
        .filter(|(stroke, _, _)| stroke == BAR)
        .map(|(_, _, points)| points.as_slice())
        .collect()
}

#[test]
fn figure_8_draws_every_bar_and_cable_in_both_views_and_amplifies_the_displacements() {
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
    // Every bar in each of the two views, as a straight segment.
    let bars = bar_lines(&ten);
    assert_eq!(bars.len(), 2 * BARS, "bar segments");
    assert!(bars.iter().all(|points| points.len() == 2));
    // Every taut cable in each view, in colour (stroke width 2); the 40 slack ones dashed.
    let taut = ten
        .polylines
        .iter()
        .filter(|(stroke, width, _)| width == "2" && stroke != BAR && stroke != SLACK)
        .count();
    assert_eq!(taut, 2 * (CABLES - 40), "taut cable segments");
    assert_texts(&ten, "deformed ×10", &["cable τ (N)", "x (m)", "y (m)"]);

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
        &["■ support (held node)", "undeformed"],
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
                .any(|t| t.starts_with("top view (undeformed structure")),
        "{:?}",
        svg.texts
    );
    let undeformed: Vec<usize> = (0..svg.polylines.len())
        .filter(|&i| svg.polylines[i].0 == "#AAAAAA" && svg.polylines[i].1 == "2")
        .collect();
    assert_eq!(
        undeformed.len(),
        2 * members,
        "one undeformed segment per member and view"
    );
    // Under the deformed structure: each view's undeformed members come before its bars.
    let bars: Vec<usize> = (0..svg.polylines.len())
        .filter(|&i| svg.polylines[i].0 == BAR)
        .collect();
    assert_eq!(bars.len(), 2 * 3, "the simplex's three struts in each view");
    assert!(
        undeformed[members - 1] < bars[0],
        "oblique view: outline under the bars"
    );
    assert!(
        undeformed[2 * members - 1] < bars[3],
        "top view: outline under the bars"
    );
    assert!(bars[2] < undeformed[members], "one view after the other");
}

/// D7 (issue 42): α = 0's curve is drawn when the supports take part of the prestress. On the
/// saddle net (`cases/saddle-net.toml`) the cables to the held boundary load the supports, so
/// `Bᵀτ₀` is not zero over all dofs, but it is at the free ones: u = 0 with τ = τ₀ is the
/// answer at zero load, and the figure draws it beside the three solved α.
#[test]
fn d7_tensions_draw_alpha_zero_when_supports_take_part_of_the_prestress() {
    let out = temp_path("tensions-supports");
    let case = common::manifest_path("cases/saddle-net.toml");
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
    let svg = read_svg(&out.join("plots/tensions.svg"));
    let structure = tensolve::case::load(&case).unwrap().structure();
    let _ = std::fs::remove_dir_all(&out);
    // The supports do take part of the prestress: over all dofs Bᵀτ₀ is far from zero.
    assert!(structure.prestress_imbalance() > 1e-3 * structure.prestress_scale);
    assert_eq!(svg.series, 4, "α = 0, 0.25, 0.5, 1: {:?}", svg.texts);
    assert_texts(&svg, "tensions", &["α = 0", "α = 0.25", "α = 0.5", "α = 1"]);
    // α = 0's curve is τ₀ sorted: one point per cable.
    let cables = structure.links.iter().filter(|l| l.kind.is_cable()).count();
    assert!(svg.series_points().iter().all(|p| p.len() == cables));
}
