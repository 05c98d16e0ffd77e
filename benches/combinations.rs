//! What load combinations cost (issue 60): `tensolve`'s run of a 64 × 64 grid (`linear`,
//! newton) under 20 combinations of 5 load cases, against one plain run of one combination's
//! loads, in one process; and where a combination's time goes: its set-up (the structure, K's
//! symbolic analysis and factor, the solver's set-up) against its solves. Each combination is
//! its own run (its set-up repeated); of that set-up, the symbolic analysis of K (pattern and
//! fill-reducing order, the same for every combination of one structure) is timed apart: what
//! sharing it across combinations would save.
//!
//! Run with `cargo bench --bench combinations`. Figures are medians of [`REPEATS`] runs (the
//! machine is shared and noisy).

use std::time::Instant;
use tensolve::app::combinations::run_combinations;
use tensolve::app::sweep::{run, RunEvent, RunOptions};
use tensolve::case;
use tensolve::decomposition::OneProcess;
use tensolve::solvers::TautStiffness;

const REPEATS: usize = 3;

/// The grid, and its five load cases: G (nodal) and four point loads, one per quadrant.
fn cases() -> String {
    let mut text = String::from(
        "[grid]\nmodules = [64, 64]\n[supports]\nclamp = \"lower-all-edges\"\n\
         [model]\ngeometry = \"linear\"\n[solver]\nmethods = [\"newton\"]\n\
         [output]\nplots = false\ntensions = false\nreactions = false\nvtk = false\n\
         [load]\nalpha = [1.0]\n\
         [[load.cases]]\nname = \"G\"\nnodal = [0.0, 0.0, -4.0]\n",
    );
    for (k, (x, y)) in [(0.0, 0.0), (32.0, 0.0), (0.0, 32.0), (32.0, 32.0)]
        .iter()
        .enumerate()
    {
        text.push_str(&format!(
            "[[load.cases]]\nname = \"Q{k}\"\n[[load.cases.point]]\n\
             box = {{ min = [{x}, {y}, -1.0], max = [{}, {}, 1.0] }}\nforce = [0.0, 0.0, -3.0]\n",
            x + 32.0,
            y + 32.0
        ));
    }
    text
}

/// 20 combinations: G at 1.35 or 1.0 with each pair of the four point cases at 1.5 / 0.9.
fn combinations() -> String {
    let mut text = String::new();
    let mut n = 0;
    for g in [1.35, 1.0] {
        for a in 0..4 {
            for b in 0..4 {
                if a == b || n >= 20 {
                    continue;
                }
                text.push_str(&format!(
                    "[[load.combinations]]\nname = \"C{n}\"\nfactors = {{ G = {g}, Q{a} = 1.5, Q{b} = 0.9 }}\n"
                ));
                n += 1;
            }
        }
    }
    assert_eq!(n, 20);
    text
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let text = format!("{}{}", cases(), combinations());
    let combined = case::parse(&text).expect("the bench case");
    let one = combined.combination(0);
    let dir = std::env::temp_dir().join(format!(
        "tensolve-bench-combinations-{}",
        std::process::id()
    ));
    let (mut all, mut single, mut set_up_share) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..REPEATS {
        let _ = std::fs::remove_dir_all(&dir);
        // Set-up: from each combination's start to its first solve.
        let (mut set_up, mut started) = (0.0, None::<Instant>);
        let start = Instant::now();
        let options = RunOptions {
            out_dir: Some(dir.join("all")),
            methods: None,
        };
        run_combinations(&combined, &options, &OneProcess, &mut |e| match e {
            RunEvent::Combination(_) => started = Some(Instant::now()),
            RunEvent::SolveStart { .. } => {
                if let Some(t) = started.take() {
                    set_up += t.elapsed().as_secs_f64();
                }
            }
            _ => {}
        })
        .expect("20 combinations");
        let total = start.elapsed().as_secs_f64();
        all.push(total);
        set_up_share.push(set_up / total);
        let start = Instant::now();
        let options = RunOptions {
            out_dir: Some(dir.join("one")),
            methods: None,
        };
        run(&one, &options, &mut |_| {}).expect("one combination");
        single.push(start.elapsed().as_secs_f64());
    }
    let _ = std::fs::remove_dir_all(&dir);
    // The symbolic analysis of K (its pattern and fill-reducing order), which every
    // combination of one structure redoes alike: what sharing it would save.
    let structure = one.structure();
    let symbolic = median(
        (0..REPEATS)
            .map(|_| {
                let start = Instant::now();
                std::hint::black_box(TautStiffness::analyse(&structure));
                start.elapsed().as_secs_f64()
            })
            .collect(),
    );
    let (all, single) = (median(all), median(single));
    println!("64 x 64 grid, linear, newton, alpha = 1 (medians of {REPEATS}):");
    println!(
        "  20 combinations     {all:.2} s ({:.3} s a combination)",
        all / 20.0
    );
    println!("  one plain run       {single:.3} s");
    println!(
        "  ratio               {:.2} (20 would be 20 x a plain run)",
        all / single
    );
    println!(
        "  set-up share        {:.0} % of the 20 combinations' time (the structure, K's analysis and factor, newton's set-up, redone per combination)",
        100.0 * median(set_up_share)
    );
    println!(
        "  symbolic analysis   {symbolic:.3} s a combination, {:.1} % of the 20 combinations' time (what sharing it would save)",
        100.0 * 20.0 * symbolic / all
    );
}
