//! Member checks (issue 45 item 2): stress, utilisation, Euler load and slack margin against
//! hand formulas on a structure whose forces are known in closed form, the summary's largest
//! utilisation and its warning, and the refusals of a bad `strength` or `inertia`.

mod common;

use common::{code, column_case, csv_rows, stderr, summary_rows, tensolve, Temp};
use std::f64::consts::PI;

const CHECKED: &str = "member,a,b,kind,young,section,prestress,density,strength,inertia\n\
                       0,0,1,bar,2e11,1e-4,-5e4,,2.6e9,1e-8\n\
                       1,1,2,cable,1e11,1e-4,5e4,,6e8,\n";

fn close(value: &str, expected: f64, what: &str) {
    let v: f64 = value
        .parse()
        .unwrap_or_else(|_| panic!("{what}: `{value}` is not a number"));
    assert!(
        (v - expected).abs() <= 1e-8 * expected.abs().max(1.0),
        "{what}: {v}, by hand {expected}"
    );
}

/// Run `case` into `out` (progress on stderr, which is not a terminal here).
fn run(case: &Temp, out: &Temp) -> std::process::Output {
    tensolve(&["run", case.arg(), "--out", out.arg()])
}

#[test]
fn member_checks_agree_with_hand_formulas() {
    for geometry in ["linear", "large"] {
        let dir = Temp::dir("checks-column");
        let case = column_case(&dir.0, CHECKED, geometry);
        let out = Temp::dir("checks-column-out");
        let o = run(&case, &out);
        assert_eq!(code(&o), 0, "{geometry}: {}", stderr(&o));
        let rows = csv_rows(&out.0.join("forces/newton_alpha1.csv"));
        let (bar, cable) = (&rows[0], &rows[1]);
        let (tb, tc) = (-1.3e5, 3e4);
        close(&bar["force_N"], tb, "bar force");
        close(&cable["force_N"], tc, "cable force");
        // σ = τ / S; utilisation |σ| / f.
        close(&bar["stress_Pa"], tb / 1e-4, "bar stress");
        close(&cable["stress_Pa"], tc / 1e-4, "cable stress");
        close(&bar["utilisation"], 1.3e9 / 2.6e9, "bar utilisation");
        close(&cable["utilisation"], 3e8 / 6e8, "cable utilisation");
        // π² E I / ℓ²: ℓ the current length (1 − 4 mm) under `large`, the initial one (1 m)
        // under `linear`.
        let length: f64 = if geometry == "large" { 1.0 - 4e-3 } else { 1.0 };
        let euler = PI * PI * 2e11 * 1e-8 / (length * length);
        close(&bar["euler_load_N"], euler, "Euler load");
        close(
            &bar["buckling_utilisation"],
            1.3e5 / euler,
            "buckling utilisation",
        );
        assert_eq!(bar["slack_margin"], "", "a bar has no slack margin");
        // The cable: no Euler load; its tension over its prestress.
        assert_eq!(cable["euler_load_N"], "");
        assert_eq!(cable["buckling_utilisation"], "");
        close(&cable["slack_margin"], tc / 5e4, "slack margin");
        // The summary: the largest utilisation (the bar's buckling) and its member, warned of.
        let summary = &summary_rows(&out.0)[0];
        close(
            &summary["max_utilisation"],
            1.3e5 / euler,
            "max_utilisation",
        );
        assert_eq!(summary["max_utilisation_member"], "0");
        let err = stderr(&o);
        assert!(
            err.contains("warning: newton at alpha = 1: member 0 is at")
                && err.contains("of its Euler load (buckling)"),
            "{err}"
        );
    }
}

#[test]
fn without_strength_or_inertia_the_outputs_keep_their_columns() {
    // The columns present but every cell empty: nothing is checked, nothing added.
    let members = "member,a,b,kind,young,section,prestress,density,strength,inertia\n\
                   0,0,1,bar,2e11,1e-4,-5e4,,,\n1,1,2,cable,1e11,1e-4,5e4,,,\n";
    let dir = Temp::dir("checks-none");
    let case = column_case(&dir.0, members, "linear");
    let out = Temp::dir("checks-none-out");
    let o = run(&case, &out);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let forces = std::fs::read_to_string(out.0.join("forces/newton_alpha1.csv")).unwrap();
    assert_eq!(
        forces.lines().next().unwrap(),
        "member,kind,node_a,node_b,force_N,elongation_m,current_length_m"
    );
    let summary = std::fs::read_to_string(out.0.join("summary.csv")).unwrap();
    assert_eq!(
        summary.lines().next().unwrap(),
        tensolve::output::SUMMARY_HEADER
    );
    assert!(!stderr(&o).contains("utilisation"));
}

#[test]
fn a_grid_checks_its_members_per_kind() {
    // At α = 0 the grid carries its prestress: bars −√(5 + 4H²/L²)·p = −√6 · 2 kN, of length
    // ℓ = (L/2)·√(5 + 4H²/L²), ℓ² = 1.5 m² (docs/method.md §2): their Euler load is
    // π² · 2e11 · 2e-8 / 1.5 = 26.3 kN, the largest utilisation 4.90 / 26.3 = 0.186 (the
    // bars' strength: 0.058; the upper cables': 2.83 kN / 0.5e-4 m² / 1 GPa = 0.057).
    let case = Temp::file(
        "checks-grid",
        "[grid]\nmodules = [2, 2]\n[bars]\nstrength = 3e8\ninertia = 2e-8\n\
         [cables]\nstrength = 1e9\n[load]\nalpha = [0.0]\n[solver]\nmethods = [\"newton\"]\n",
    );
    let out = Temp::dir("checks-grid-out");
    let o = tensolve(&["run", case.arg(), "--out", out.arg(), "--quiet"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let bar_force = -(6.0f64).sqrt() * 2000.0;
    let mut bars = 0;
    let mut first_bar = None;
    for row in csv_rows(&out.0.join("forces/newton_alpha0.csv")) {
        let force: f64 = row["force_N"].parse().unwrap();
        let length: f64 = row["current_length_m"].parse().unwrap();
        if row["kind"] == "bar" {
            bars += 1;
            first_bar.get_or_insert(row["member"].clone());
            close(&row["current_length_m"], 1.5f64.sqrt(), "bar length");
            close(&row["force_N"], bar_force, "bar prestress");
            close(&row["stress_Pa"], force / 2.8e-4, "bar stress");
            close(
                &row["utilisation"],
                force.abs() / 2.8e-4 / 3e8,
                "bar utilisation",
            );
            let euler = PI * PI * 2e11 * 2e-8 / (length * length);
            close(&row["euler_load_N"], euler, "Euler load");
            close(&row["buckling_utilisation"], -force / euler, "buckling");
        } else {
            close(&row["stress_Pa"], force / 0.5e-4, "cable stress");
            close(
                &row["utilisation"],
                force.abs() / 0.5e-4 / 1e9,
                "cable utilisation",
            );
            assert_eq!(row["euler_load_N"], "");
            // At the prestressed state every prestressed cable's margin is 1.
            close(&row["slack_margin"], 1.0, "slack margin at zero load");
        }
    }
    assert_eq!(bars, 16);
    let summary = &summary_rows(&out.0)[0];
    let euler = PI * PI * 2e11 * 2e-8 / 1.5;
    close(
        &summary["max_utilisation"],
        -bar_force / euler,
        "max_utilisation",
    );
    // Every bar alike: the first in link order is named.
    assert_eq!(summary["max_utilisation_member"], first_bar.unwrap());
}

/// `tensolve check` of the column with `members`: its exit code and stderr.
fn check(members: &str) -> (i32, String) {
    let dir = Temp::dir("checks-bad");
    let case = column_case(&dir.0, members, "linear");
    let o = tensolve(&["check", case.arg()]);
    (code(&o), stderr(&o))
}

#[test]
fn a_bad_strength_or_inertia_exits_2_naming_the_member_and_the_column() {
    let header = "member,a,b,kind,young,section,prestress,density,strength,inertia\n";
    let bar = "0,0,1,bar,2e11,1e-4,-5e4,,2.6e9,1e-8\n";
    for (cable, column, value) in [
        ("7,1,2,cable,1e11,1e-4,5e4,,0,\n", "strength", "0"),
        ("7,1,2,cable,1e11,1e-4,5e4,,-2e8,\n", "strength", "-2e8"),
        ("7,1,2,cable,1e11,1e-4,5e4,,NaN,\n", "strength", "NaN"),
        ("7,1,2,cable,1e11,1e-4,5e4,,6e8,-1e-8\n", "inertia", "-1e-8"),
    ] {
        let (code, err) = check(&format!("{header}{bar}{cable}"));
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("members.csv, line 3, column `")
                && err.contains(&format!("column `{column}`: `{value}` is not valid"))
                && err.contains(&format!("member 7: `{column}` must be")),
            "{column} = {value}: {err}"
        );
    }
    // A bar without bending stiffness would buckle under any compression.
    let (code, err) = check(&format!(
        "{header}0,0,1,bar,2e11,1e-4,-5e4,,,0\n1,1,2,cable,1e11,1e-4,5e4,,,\n"
    ));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("line 2, column `inertia`")
            && err.contains("member 0: `inertia` must be > 0 on a bar"),
        "{err}"
    );
}

#[test]
fn a_bad_grid_check_key_exits_2_naming_the_key() {
    for (section, key, value) in [
        ("bars", "strength", "0.0"),
        ("bars", "inertia", "-1e-8"),
        ("cables", "strength", "-5e8"),
    ] {
        let case = Temp::file(
            "checks-grid-bad",
            &format!(
                "[grid]\nmodules = [2, 2]\n[{section}]\n{key} = {value}\n[load]\nalpha = [1.0]\n"
            ),
        );
        let o = tensolve(&["check", case.arg()]);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{err}");
        assert!(err.contains(&format!("`{section}.{key}` = ")), "{err}");
    }
    // On a [structure] the members table says it, per member.
    let dir = Temp::dir("checks-structure-key");
    let case = column_case(&dir.0, CHECKED, "linear");
    let mut text = std::fs::read_to_string(&case.0).unwrap();
    text.push_str("[bars]\nstrength = 3e8\n");
    std::fs::write(&case.0, text).unwrap();
    let o = tensolve(&["check", case.arg()]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("`bars.strength`"), "{}", stderr(&o));
}
