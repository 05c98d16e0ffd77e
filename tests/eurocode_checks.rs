//! EN 1993's member checks (issue 60 item 3): a strut's flexural buckling by EN 1993-1-1
//! §6.3.1 on each buckling curve and a cable's resistance by EN 1993-1-11 §6.3, against hand
//! calculations written here and against EN 1993-1-1's tabulated reduction factors; the
//! `checks.csv` of the members above 1; the grid's keys; and the refusals of bad input.

mod common;

use common::{code, column_case_with, csv_rows, stderr, summary_rows, tensolve, Temp};
use std::f64::consts::PI;

/// The column of `common::column_case` under `linear`: the bar (member 0, ℓ = 1 m, A = 1e-4
/// m², E = 2e11 Pa) carries 130 kN of compression, the cable (member 1) 30 kN of tension.
const N_ED: f64 = 1.3e5;
const T_ED: f64 = 3e4;
const AREA: f64 = 1e-4;
const YOUNG: f64 = 2e11;

/// f_y of the bar, Pa.
const F_Y: f64 = 355e6;

/// The bar's I for λ̄ = 1 on a 1 m length: N_cr = π² E I = A f_y.
fn inertia_at_unit_slenderness() -> f64 {
    AREA * F_Y / (PI * PI * YOUNG)
}

/// The members table: the bar with f_y, I and `curve`; the cable with its breaking load.
fn members(inertia: f64, curve: &str, breaking_load: &str) -> String {
    format!(
        "member,a,b,kind,young,section,prestress,density,strength,inertia,buckling_curve,breaking_load\n\
         0,0,1,bar,{YOUNG},{AREA},-5e4,,{F_Y},{inertia},{curve},\n\
         1,1,2,cable,1e11,1e-4,5e4,,,,,{breaking_load}\n"
    )
}

fn close(value: &str, expected: f64, relative: f64, what: &str) {
    let v: f64 = value
        .parse()
        .unwrap_or_else(|_| panic!("{what}: `{value}` is not a number"));
    assert!(
        (v - expected).abs() <= relative * expected.abs().max(1e-300),
        "{what}: {v}, by hand {expected}"
    );
}

/// Run the column with `members` and `extra` TOML; the bar's and the cable's `forces/` rows.
fn solve(
    tag: &str,
    members: &str,
    extra: &str,
) -> (Temp, Vec<std::collections::HashMap<String, String>>) {
    let dir = Temp::dir(tag);
    let case = column_case_with(&dir.0, members, "linear", extra);
    let out = Temp::dir(&format!("{tag}-out"));
    let o = tensolve(&["run", case.arg(), "--out", out.arg()]);
    assert_eq!(code(&o), 0, "{tag}: {}", stderr(&o));
    let rows = csv_rows(&out.0.join("forces/newton_alpha1.csv"));
    (out, rows)
}

/// At λ̄ = 1 each curve's χ is EN 1993-1-1's (Figure 6.4; tabulated to 4 digits in the
/// design tables: a0 0.7253, a 0.6656, b 0.5970, c 0.5399, d 0.4671), and N_b,Rd = χ A f_y /
/// γ_M1 with γ_M1 = 1.1 given; the hand calculation below, written out, agrees to 1e-12.
#[test]
fn each_buckling_curve_gives_the_codes_reduction_factor() {
    let tabulated: [(&str, f64, f64); 5] = [
        ("a0", 0.13, 0.7253),
        ("a", 0.21, 0.6656),
        ("b", 0.34, 0.5970),
        ("c", 0.49, 0.5399),
        ("d", 0.76, 0.4671),
    ];
    let gamma_m1 = 1.1;
    for (curve, alpha, table_chi) in tabulated {
        let (_out, rows) = solve(
            &format!("en-curve-{curve}"),
            &members(inertia_at_unit_slenderness(), curve, ""),
            "[checks]\ngamma_m1 = 1.1\n",
        );
        let bar = &rows[0];
        // By hand: λ̄ = √(A f_y / N_cr) = 1, Φ = 0.5 (1 + α (1 − 0.2) + 1) = 1 + 0.4 α,
        // χ = 1 / (Φ + √(Φ² − 1)).
        let phi = 1.0 + 0.4 * alpha;
        let chi = 1.0 / (phi + (phi * phi - 1.0).sqrt());
        assert!(
            (chi - table_chi).abs() <= 5e-5,
            "{curve}: χ {chi} against the table's {table_chi}"
        );
        let resistance = chi * AREA * F_Y / gamma_m1;
        assert_eq!(bar["buckling_curve"], curve);
        close(&bar["slenderness"], 1.0, 1e-12, "λ̄");
        close(&bar["chi"], chi, 1e-12, "χ");
        close(&bar["buckling_resistance_N"], resistance, 1e-12, "N_b,Rd");
        close(
            &bar["buckling_utilisation"],
            N_ED / resistance,
            1e-8,
            "N_Ed / N_b,Rd",
        );
        // The Euler load stays reported: N_cr = A f_y here.
        close(&bar["euler_load_N"], AREA * F_Y, 1e-12, "N_cr");
        // Governing: buckling (N_Ed / N_b,Rd ≥ 3.7) over the stress (1.3e9 / 355e6 = 3.66).
        close(
            &bar["governing_utilisation"],
            N_ED / resistance,
            1e-8,
            "governing",
        );
        assert_eq!(bar["clause"], "EN 1993-1-1 6.3.1");
        // The cable has no breaking load here: its EN cells are empty, and no clause governs
        // it (it has no strength either).
        assert_eq!(rows[1]["cable_resistance_N"], "");
        assert_eq!(rows[1]["clause"], "");
    }
}

/// A stocky strut (λ̄ = 0.2 and below) has χ = 1: buckling ignored (§6.3.1.2 (4)); with γ_M1
/// at its default 1.0, N_b,Rd = A f_y, so the buckling utilisation equals the stress one.
#[test]
fn a_stocky_strut_has_no_reduction() {
    // N_cr = 25 A f_y → λ̄ = 0.2; and 100 A f_y → λ̄ = 0.1.
    for (factor, slenderness) in [(25.0, 0.2), (100.0, 0.1)] {
        let inertia = factor * inertia_at_unit_slenderness();
        let (_out, rows) = solve(
            &format!("en-stocky-{slenderness}"),
            &members(inertia, "c", ""),
            "",
        );
        let bar = &rows[0];
        close(&bar["slenderness"], slenderness, 1e-12, "λ̄");
        close(&bar["chi"], 1.0, 1e-12, "χ");
        close(&bar["buckling_resistance_N"], AREA * F_Y, 1e-12, "N_b,Rd");
        // Stress 1.3e9 / 355e6 = 3.662 = buckling N_Ed / (A f_y): a tie (to round-off).
        close(&bar["utilisation"], N_ED / (AREA * F_Y), 1e-12, "|σ| / f_y");
        close(
            &bar["buckling_utilisation"],
            N_ED / (AREA * F_Y),
            1e-12,
            "N_Ed / N_b,Rd",
        );
        assert!(
            ["stress", "EN 1993-1-1 6.3.1"].contains(&bar["clause"].as_str()),
            "{}",
            bar["clause"]
        );
    }
}

/// EN 1993-1-11: F_Rd = F_uk / (1.5 γ_R); with F_uk = 40 kN and γ_R = 0.9, F_Rd = 29 629.6 N
/// and the cable's 30 kN is at 1.0125: over 1, with the bar, in `checks.csv`, and the
/// summary's largest utilisation is the bar's.
#[test]
fn a_cable_is_checked_against_its_breaking_load_and_checks_csv_lists_the_members_over_one() {
    let (out, rows) = solve(
        "en-cable",
        &members(inertia_at_unit_slenderness(), "b", "4e4"),
        "[checks]\ngamma_r = 0.9\n",
    );
    let cable = &rows[1];
    // By hand: F_Rd = 40 000 / (1.5 × 0.9).
    let f_rd = 40_000.0 / 1.35;
    close(&cable["cable_resistance_N"], f_rd, 1e-12, "F_Rd");
    close(
        &cable["cable_utilisation"],
        T_ED / f_rd,
        1e-8,
        "F_Ed / F_Rd",
    );
    assert_eq!(cable["clause"], "EN 1993-1-11 6.3");
    assert_eq!(cable["buckling_curve"], "");
    let checks = csv_rows(&out.0.join("checks.csv"));
    let listed: Vec<(&str, &str)> = checks
        .iter()
        .map(|r| (r["member"].as_str(), r["clause"].as_str()))
        .collect();
    assert_eq!(
        listed,
        [("0", "EN 1993-1-1 6.3.1"), ("1", "EN 1993-1-11 6.3")]
    );
    close(&checks[1]["utilisation"], T_ED / f_rd, 1e-8, "checks.csv");
    assert_eq!(checks[0]["solver"], "newton");
    let summary = &summary_rows(&out.0)[0];
    assert_eq!(summary["max_utilisation_member"], "0");
}

/// Below 1 everywhere, `checks.csv` is not written.
#[test]
fn no_member_over_one_writes_no_checks_file() {
    // A breaking load of 1 MN and a strut with I 100× larger, f_y 10× larger.
    let members = format!(
        "member,a,b,kind,young,section,prestress,density,strength,inertia,buckling_curve,breaking_load\n\
         0,0,1,bar,{YOUNG},{AREA},-5e4,,3.55e9,{},a,\n\
         1,1,2,cable,1e11,1e-4,5e4,,,,,1e6\n",
        100.0 * inertia_at_unit_slenderness()
    );
    let (out, rows) = solve("en-below", &members, "[checks]\ngamma_r = 1.0\n");
    assert!(!out.0.join("checks.csv").exists());
    let governing: f64 = rows[0]["governing_utilisation"].parse().unwrap();
    assert!(governing < 1.0, "{governing}");
}

/// A grid's `bars.buckling_curve` and `cables.breaking_load`: every bar's χ is the hand
/// formula's at its own length and the grid's section, every cable's F_Rd the same.
#[test]
fn a_grid_takes_the_keys_per_member_kind() {
    let dir = Temp::dir("en-grid");
    std::fs::create_dir_all(&dir.0).unwrap();
    let case = dir.0.join("case.toml");
    std::fs::write(
        &case,
        "[grid]\nmodules = [4, 4]\n[load]\nalpha = [0.5]\n[solver]\nmethods = [\"newton\"]\n\
         [bars]\nstrength = 355e6\ninertia = 1e-7\nbuckling_curve = \"c\"\n\
         [cables]\nbreaking_load = 2e5\n[checks]\ngamma_r = 0.9\ngamma_m1 = 1.05\n",
    )
    .unwrap();
    let out = Temp::dir("en-grid-out");
    let o = tensolve(&["run", case.to_str().unwrap(), "--out", out.arg()]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let rows = csv_rows(&out.0.join("forces/newton_alpha0.5.csv"));
    let (mut bars, mut cables) = (0, 0);
    for r in &rows {
        let number = |k: &str| r[k].parse::<f64>().unwrap();
        if r["kind"] == "bar" {
            bars += 1;
            assert_eq!(r["buckling_curve"], "c");
            // λ̄ = √(A f_y / N_cr), N_cr the row's Euler load; A f_y from N_b,Rd / χ · γ_M1.
            let area_fy = number("buckling_resistance_N") / number("chi") * 1.05;
            let slenderness = (area_fy / number("euler_load_N")).sqrt();
            close(&r["slenderness"], slenderness, 1e-12, "λ̄");
            let phi = 0.5 * (1.0 + 0.49 * (slenderness - 0.2) + slenderness * slenderness);
            let chi = (1.0 / (phi + (phi * phi - slenderness * slenderness).sqrt())).min(1.0);
            close(&r["chi"], chi, 1e-12, "χ");
        } else {
            cables += 1;
            close(&r["cable_resistance_N"], 2e5 / 1.35, 1e-12, "F_Rd");
            assert_eq!(r["buckling_curve"], "");
        }
    }
    assert!(bars > 0 && cables > 0);
}

/// Bad input: exit 2, the key (or file, line and column), the value and the fix named.
#[test]
fn bad_code_check_input_is_refused_with_its_key() {
    let inertia = inertia_at_unit_slenderness();
    let header = "member,a,b,kind,young,section,prestress,density,strength,inertia,buckling_curve,breaking_load\n";
    let cable = "1,1,2,cable,1e11,1e-4,5e4,,,,,\n";
    let cases: Vec<(String, &str, &[&str])> = vec![
        // A curve that is not one.
        (
            format!("{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,{F_Y},{inertia},e,\n{cable}"),
            "",
            &[
                "members.csv",
                "line 2",
                "buckling_curve",
                "`a0`, `a`, `b`, `c`, `d`",
            ],
        ),
        // A curve on a cable.
        (
            format!(
                "{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,,,,\n1,1,2,cable,1e11,1e-4,5e4,,6e8,,b,\n"
            ),
            "",
            &["line 3", "buckling_curve", "is a cable"],
        ),
        // A curve without an inertia.
        (
            format!("{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,{F_Y},,b,\n{cable}"),
            "",
            &["line 2", "buckling_curve", "`strength` (f_y) and `inertia`"],
        ),
        // A breaking load on a bar, and one that is not positive.
        (
            format!("{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,,,,1e5\n{cable}"),
            "[checks]\ngamma_r = 1.0\n",
            &["line 2", "breaking_load", "this member is a bar"],
        ),
        (
            format!(
                "{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,,,,\n1,1,2,cable,1e11,1e-4,5e4,,,,,-3\n"
            ),
            "[checks]\ngamma_r = 1.0\n",
            &["line 3", "breaking_load", "must be > 0"],
        ),
        // A breaking load without γ_R.
        (
            format!(
                "{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,,,,\n1,1,2,cable,1e11,1e-4,5e4,,,,,1e5\n"
            ),
            "",
            &["checks.gamma_r", "missing", "F_uk / (1.5 γ_R)"],
        ),
        // A factor that divides nothing, and one out of range.
        (
            format!("{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,{F_Y},{inertia},,\n{cable}"),
            "[checks]\ngamma_r = 1.1\n",
            &["checks.gamma_r", "1.1", "no cable has a breaking load"],
        ),
        (
            format!("{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,{F_Y},{inertia},b,\n{cable}"),
            "[checks]\ngamma_m1 = nan\n",
            &["checks.gamma_m1", "between 0.5 and 5"],
        ),
        // An unknown key of [checks].
        (
            format!("{header}0,0,1,bar,{YOUNG},{AREA},-5e4,,{F_Y},{inertia},b,\n{cable}"),
            "[checks]\ngamma_m0 = 1.0\n",
            &["gamma_m0"],
        ),
    ];
    for (k, (members, extra, expected)) in cases.iter().enumerate() {
        let dir = Temp::dir(&format!("en-bad-{k}"));
        let case = column_case_with(&dir.0, members, "linear", extra);
        let out = Temp::dir(&format!("en-bad-{k}-out"));
        let o = tensolve(&["run", case.arg(), "--out", out.arg()]);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "case {k}: {err}");
        for piece in *expected {
            assert!(err.contains(piece), "case {k}: `{piece}` not in: {err}");
        }
        assert!(
            !out.0.join("summary.csv").exists(),
            "case {k} wrote results"
        );
    }
    // The grid's keys: an unknown curve, and a curve without the bars' strength.
    for (k, (bars, expected)) in [
        (
            "strength = 3e8\ninertia = 1e-7\nbuckling_curve = \"z\"\n",
            "bars.buckling_curve",
        ),
        ("inertia = 1e-7\nbuckling_curve = \"a\"\n", "bars.strength"),
    ]
    .into_iter()
    .enumerate()
    {
        let dir = Temp::dir(&format!("en-bad-grid-{k}"));
        std::fs::create_dir_all(&dir.0).unwrap();
        let case = dir.0.join("case.toml");
        std::fs::write(
            &case,
            format!("[grid]\nmodules = [2, 2]\n[load]\nalpha = [0.5]\n[bars]\n{bars}"),
        )
        .unwrap();
        let o = tensolve(&["check", case.to_str().unwrap()]);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "grid {k}: {err}");
        assert!(err.contains(expected), "grid {k}: {err}");
    }
}
