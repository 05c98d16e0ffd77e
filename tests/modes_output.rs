//! `output.modes` through the command line (issue 45 item 1): the shipped simplex, its members
//! given a density in a copy of its directory, writes `modes/{solver}_alpha{α}.csv` and the
//! shapes at every α; its mechanism's mode is flagged prestress-governed at the prestressed
//! state; without any density the key is refused, exit 2, by name. Under `large`, the
//! frequencies of the shipped tensegrity cases (steel members) agree with OpenSees `eigen` on
//! corotTruss at the same states (`scripts/peers/corot_compare.py --modes`).

mod common;

use common::{manifest_path, require_python};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `tensolve run` of `case` into `out` with `sets` (`--set` each).
fn run(case: &Path, out: &Path, sets: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_tensolve"));
    command.arg("run").arg(case).arg("--out").arg(out);
    for set in sets {
        command.arg("--set").arg(set);
    }
    command.output().unwrap()
}

/// A copy of the shipped simplex under `dir`, its members of steel; the case file's path.
fn steel_simplex(dir: &Path) -> PathBuf {
    steel_copy(dir, "simplex", |text| text.to_string())
}

/// A copy of the shipped case `name` (its directory and its case file, `edit`ed) under `dir`,
/// its members of steel (a `density` column of 7850 kg/m³); the case file's path.
fn steel_copy(dir: &Path, name: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    std::fs::create_dir(dir.join(name)).unwrap();
    std::fs::copy(
        manifest_path(&format!("cases/{name}/nodes.csv")),
        dir.join(format!("{name}/nodes.csv")),
    )
    .unwrap();
    let members =
        std::fs::read_to_string(manifest_path(&format!("cases/{name}/members.csv"))).unwrap();
    let mut lines = members.lines();
    let header = lines.next().unwrap();
    let mut table = format!("{header},density\n");
    for line in lines.filter(|l| !l.trim().is_empty()) {
        table.push_str(&format!("{line},7850\n"));
    }
    std::fs::write(dir.join(format!("{name}/members.csv")), table).unwrap();
    let case = dir.join(format!("{name}.toml"));
    let text = std::fs::read_to_string(manifest_path(&format!("cases/{name}.toml"))).unwrap();
    std::fs::write(&case, edit(&text)).unwrap();
    case
}

/// The rows of a modes file: (frequency, period, prestress-governed).
fn modes(path: &Path) -> Vec<(f64, f64, bool)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("mode,frequency_Hz,period_s,prestress_governed,converged")
    );
    lines
        .enumerate()
        .map(|(i, line)| {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells.len(), 5, "{line}");
            assert_eq!(cells[0], (i + 1).to_string());
            // The eigensolver's residual criterion held.
            assert_eq!(cells[4], "true", "{line}");
            (
                cells[1].parse().unwrap(),
                cells[2].parse().unwrap(),
                cells[3].parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn the_simplex_writes_its_lowest_modes_at_every_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let case = steel_simplex(dir.path());
    let out = dir.path().join("out");
    // The shipped α, and 0: the prestressed state, where the mechanism is held by the prestress
    // alone (under load the case's `large` model stiffens it by the geometry as it opens).
    let o = run(
        &case,
        &out,
        &["output.modes=3", "load.alpha=[0.0, 0.25, 0.5, 1.0]"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for alpha in ["0", "0.25", "0.5", "1"] {
        let rows = modes(&out.join(format!("modes/newton_alpha{alpha}.csv")));
        assert_eq!(rows.len(), 3, "α = {alpha}");
        assert!(rows[0].0 > 0.0, "α = {alpha}: {rows:?}");
        assert!(
            rows.windows(2).all(|w| w[0].0 <= w[1].0),
            "α = {alpha}: {rows:?}"
        );
        for (f, period, _) in &rows {
            assert!((f * period - 1.0).abs() < 1e-12, "α = {alpha}: {rows:?}");
        }
        // Every node of every mode, held ones at 0.
        let shapes =
            std::fs::read_to_string(out.join(format!("modes/newton_alpha{alpha}_shapes.csv")))
                .unwrap();
        assert!(shapes.starts_with("mode,node,ux,uy,uz\n"));
        assert_eq!(shapes.lines().count(), 1 + 3 * 6);
        assert!(shapes.contains("\n1,0,0,0,0\n"), "{shapes}");
    }
    let at_rest = modes(&out.join("modes/newton_alpha0.csv"));
    assert!(at_rest[0].2, "{at_rest:?}");
    assert!(!at_rest[1].2 && !at_rest[2].2, "{at_rest:?}");
}

#[test]
fn modes_without_a_density_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = run(
        &manifest_path("cases/simplex.toml"),
        &out,
        &["output.modes=2"],
    );
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("output.modes"), "{stderr}");
    assert!(stderr.contains("density"), "{stderr}");
    assert!(!out.join("modes").exists());
}

/// The 6 lowest frequencies of newton's `large` answers on the shipped tensegrity cases, their
/// members of steel, at the prestressed state (α = 0) and the shipped α, against OpenSees
/// `eigen` on corotTruss at the same states (the tangent there, and the mass `ρ S L` per
/// member), consistent and lumped: to 1e-6 of each frequency (`scripts/peers/corot_compare.py
/// --modes`, which also compares the answers); and the simplex with point masses on nodes. A peer check: ignored by a plain `cargo test`,
/// failed where openseespy or numpy is missing; CI runs it (`.ci/run` installs them).
#[test]
#[ignore = "peer check: needs python3 with openseespy and numpy (python3 -m pip install openseespy numpy); run with -- --include-ignored"]
fn frequencies_agree_with_opensees_eigen_on_corot_truss() {
    require_python(&["openseespy.opensees", "numpy"]);
    // The simplex with point masses too: 20 kg on each top node, 5 kg on a held one.
    let point_masses = "[[modal.point_mass]]\nnodes = [3, 4, 5]\nmass = 20.0\n\n\
                        [[modal.point_mass]]\nnodes = [0, 5]\nmass = 5.0\n";
    let cases = ["simplex", "prism4", "tower", "saddle-net"]
        .into_iter()
        .map(|name| (name, ""))
        .chain([("simplex", point_masses)]);
    for (name, extra) in cases {
        for mass in ["consistent", "lumped"] {
            let dir = tempfile::tempdir().unwrap();
            let shipped = "alpha = [0.25, 0.5, 1.0]";
            let case = steel_copy(dir.path(), name, |text| {
                assert!(text.contains(shipped), "{name}: the shipped α changed");
                let at_rest = text.replace(shipped, "alpha = [0.0, 0.25, 0.5, 1.0]");
                format!("{at_rest}\n[modal]\nmass = \"{mass}\"\n\n{extra}")
            });
            let out = dir.path().join("out");
            let o = run(&case, &out, &["output.modes=6"]);
            assert!(
                o.status.success(),
                "{name} {mass}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let compare = Command::new("python3")
                .arg(manifest_path("scripts/peers/corot_compare.py"))
                .arg(&case)
                .arg(&out)
                .args(["--rtol", "1e-6", "--modes"])
                .output()
                .unwrap();
            let stdout = String::from_utf8_lossy(&compare.stdout);
            assert!(
                compare.status.success(),
                "{name} {mass}: {stdout}{}",
                String::from_utf8_lossy(&compare.stderr)
            );
            // Every α compared its 6 frequencies.
            assert_eq!(
                stdout.matches(", 6 modes ").count(),
                4,
                "{name} {mass}: {stdout}"
            );
            eprint!("{name} {mass}:\n{stdout}");
        }
    }
}

/// A grid's members get their mass from `bars.density` and `cables.density`: the paper's grid
/// so given has the frequencies of the same grid written as tables (`cases/paper-csv.toml`)
/// with those densities in a `density` column, at the prestressed state and under load;
/// a negative density exits 2 naming the key, and a `[structure]` refuses the keys.
#[test]
fn grid_densities_give_the_tables_frequencies() {
    let dir = tempfile::tempdir().unwrap();
    let (bars, cables) = (7850.0, 8000.0);
    let settings = [
        "output.modes=5",
        "load.alpha=[0.0, 1.0]",
        "solver.methods=[\"newton\"]",
        "output.plots=false",
        "output.history=false",
    ];
    let grid_out = dir.path().join("grid");
    let mut sets = settings.to_vec();
    let (bar_key, cable_key) = (
        format!("bars.density={bars}"),
        format!("cables.density={cables}"),
    );
    sets.extend([bar_key.as_str(), cable_key.as_str()]);
    let o = run(&manifest_path("cases/paper.toml"), &grid_out, &sets);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The tables, a density per member by kind.
    std::fs::create_dir(dir.path().join("paper-grid")).unwrap();
    std::fs::copy(
        manifest_path("cases/paper-grid/nodes.csv"),
        dir.path().join("paper-grid/nodes.csv"),
    )
    .unwrap();
    let members = std::fs::read_to_string(manifest_path("cases/paper-grid/members.csv")).unwrap();
    let mut lines = members.lines();
    let mut table = format!("{},density\n", lines.next().unwrap());
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let density = if line.contains(",bar,") { bars } else { cables };
        table.push_str(&format!("{line},{density}\n"));
    }
    std::fs::write(dir.path().join("paper-grid/members.csv"), table).unwrap();
    let case = dir.path().join("paper-csv.toml");
    std::fs::copy(manifest_path("cases/paper-csv.toml"), &case).unwrap();
    let tables_out = dir.path().join("tables");
    let o = run(&case, &tables_out, &settings[..3]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for alpha in ["0", "1"] {
        let file = format!("modes/newton_alpha{alpha}.csv");
        let (grid, tables) = (modes(&grid_out.join(&file)), modes(&tables_out.join(&file)));
        assert_eq!(grid.len(), 5);
        assert_eq!(tables.len(), 5);
        for (g, t) in grid.iter().zip(&tables) {
            assert!(g.0 > 0.0, "α = {alpha}: {grid:?}");
            assert!(
                (g.0 - t.0).abs() <= 1e-9 * t.0,
                "α = {alpha}: {grid:?} against {tables:?}"
            );
        }
    }
    let o = run(
        &manifest_path("cases/paper.toml"),
        &dir.path().join("negative"),
        &["bars.density=-1.0"],
    );
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("bars.density") && stderr.contains("≥ 0"),
        "{stderr}"
    );
    let o = run(
        &manifest_path("cases/simplex.toml"),
        &dir.path().join("structure"),
        &["cables.density=7850.0"],
    );
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("cables.density"), "{stderr}");
}

/// `[[modal.point_mass]]` alone gives the simplex a mass: the massless members' structure with
/// a mass m on each top node has frequencies ∝ 1/√m (the same shapes, 4 m: half the
/// frequencies); a mass ≤ 0 exits 2 naming the entry's key.
#[test]
fn point_masses_alone_give_modes_scaling_as_one_over_root_mass() {
    let dir = tempfile::tempdir().unwrap();
    let frequencies = |mass: f64, tag: &str| {
        let case = dir.path().join(format!("{tag}.toml"));
        let text = std::fs::read_to_string(manifest_path("cases/simplex.toml")).unwrap();
        let text = text.replace(
            "simplex/",
            &format!("{}/", manifest_path("cases/simplex").display()),
        );
        std::fs::write(
            &case,
            format!("{text}\n[[modal.point_mass]]\nnodes = [3, 4, 5]\nmass = {mass:?}\n"),
        )
        .unwrap();
        let out = dir.path().join(tag);
        let o = run(&case, &out, &["output.modes=6", "load.alpha=[0.0, 1.0]"]);
        (o, out)
    };
    let (o, light) = frequencies(10.0, "light");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (o, heavy) = frequencies(40.0, "heavy");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for alpha in ["0", "1"] {
        let file = format!("modes/newton_alpha{alpha}.csv");
        let (light, heavy) = (modes(&light.join(&file)), modes(&heavy.join(&file)));
        assert_eq!(light.len(), 6);
        for (l, h) in light.iter().zip(&heavy) {
            assert!(l.0 > 0.0, "α = {alpha}: {light:?}");
            assert!(
                (h.0 - l.0 / 2.0).abs() <= 1e-9 * l.0,
                "α = {alpha}: {light:?} {heavy:?}"
            );
        }
    }
    let (o, _) = frequencies(0.0, "zero");
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("modal.point_mass[0].mass"), "{stderr}");
}

/// With `output.vtk`, `modes/{solver}_alpha{α}.vtu` holds the modes for ParaView: its
/// `frequency_Hz` the CSV's, its `mode_k` arrays the shapes CSV's node by node, its points the
/// answer's deformed nodes under `large` (the `vtk/` file's positions plus displacements).
#[test]
fn the_modes_vtu_holds_the_csv_modes_on_the_deformed_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let case = steel_simplex(dir.path());
    let out = dir.path().join("out");
    let o = run(&case, &out, &["output.modes=3", "output.vtk=true"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let numbers = |text: &str| -> Vec<f64> {
        text.split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    let arrays = |path: &Path| -> Vec<(String, Vec<f64>)> {
        let text = std::fs::read_to_string(path).unwrap();
        let doc = roxmltree::Document::parse(&text).unwrap();
        doc.descendants()
            .filter(|n| n.has_tag_name("DataArray"))
            .map(|n| {
                (
                    n.attribute("Name").unwrap().to_string(),
                    numbers(n.text().unwrap_or("")),
                )
            })
            .collect()
    };
    let get = |arrays: &[(String, Vec<f64>)], name: &str| -> Vec<f64> {
        arrays.iter().find(|(n, _)| n == name).unwrap().1.clone()
    };
    let modes_vtu = arrays(&out.join("modes/newton_alpha1.vtu"));
    let solve_vtu = arrays(&out.join("vtk/newton_alpha1.vtu"));
    let frequencies: Vec<f64> = modes(&out.join("modes/newton_alpha1.csv"))
        .iter()
        .map(|r| r.0)
        .collect();
    assert_eq!(get(&modes_vtu, "frequency_Hz"), frequencies);
    let shapes = std::fs::read_to_string(out.join("modes/newton_alpha1_shapes.csv")).unwrap();
    for k in 1..=3 {
        let expected: Vec<f64> = shapes
            .lines()
            .skip(1)
            .filter(|l| l.starts_with(&format!("{k},")))
            .flat_map(|l| numbers(&l.split(',').skip(2).collect::<Vec<_>>().join(" ")))
            .collect();
        assert_eq!(expected.len(), 18);
        assert_eq!(get(&modes_vtu, &format!("mode_{k}")), expected, "mode {k}");
    }
    let (x, u) = (get(&solve_vtu, "position"), get(&solve_vtu, "displacement"));
    let moved: Vec<f64> = x.iter().zip(&u).map(|(a, b)| a + b).collect();
    let points = get(&modes_vtu, "position");
    assert!(u.iter().any(|v| v.abs() > 1e-3));
    assert!(points
        .iter()
        .zip(&moved)
        .all(|(p, q)| (p - q).abs() <= 1e-12 * (1.0 + q.abs())));
}

/// With `output.plots`, `modes/{solver}_alpha{α}.svg` draws the lowest 4 modes: a title with
/// each one's frequency as in the CSV (the mechanism's "prestress-governed" at α = 0), and every
/// member twice per panel (the structure and the shape); none without `output.plots`.
#[test]
fn the_modes_figure_draws_the_lowest_four() {
    let dir = tempfile::tempdir().unwrap();
    let case = steel_simplex(dir.path());
    let out = dir.path().join("out");
    let o = run(
        &case,
        &out,
        &["output.modes=5", "output.plots=true", "load.alpha=[0.0]"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let svg = std::fs::read_to_string(out.join("modes/newton_alpha0.svg")).unwrap();
    let rows = modes(&out.join("modes/newton_alpha0.csv"));
    for (k, row) in rows.iter().enumerate().take(4) {
        assert!(
            svg.contains(&format!("mode {}: {:.4} Hz", k + 1, row.0)),
            "{svg}"
        );
    }
    assert!(!svg.contains("mode 5:"));
    assert!(svg.contains("mode 1: ") && svg.contains("Hz, prestress-governed\n</text>"));
    // The simplex's 9 members (3 bars, 3 side cables, the top ring).
    assert_eq!(svg.matches("<polyline ").count(), 4 * 2 * 9);
    let plain = dir.path().join("plain");
    let o = run(
        &case,
        &plain,
        &["output.modes=5", "output.plots=false", "load.alpha=[0.0]"],
    );
    assert!(o.status.success());
    assert!(!plain.join("modes/newton_alpha0.svg").exists());
}
