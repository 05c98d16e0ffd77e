//! Under MPI (`cargo test --release --features mpi --test mpi`, with Debian's OpenMPI): the
//! binary started by `mpirun` on several ranks. Rank 0 reads the case and the others load its
//! bytes; rank 0 alone prints; every rank exits with the same status; `check` prints the rank
//! layout; `run` is refused on several ranks until the solve is distributed (issue 25).
#![cfg(feature = "mpi")]

mod common;

use common::{code, manifest_path, tensolve, Temp};
use std::process::{Command, Output};

/// `tensolve args` on `ranks` MPI ranks (oversubscribed: this machine may have fewer cores).
fn mpirun(ranks: usize, args: &[&str]) -> Output {
    Command::new("mpirun")
        .args(["--oversubscribe", "--allow-run-as-root", "-n"])
        .arg(ranks.to_string())
        .arg(env!("CARGO_BIN_EXE_tensolve"))
        .args(args)
        .output()
        .expect("mpirun (Debian's openmpi-bin) on the PATH")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `t` without its `available` line (the memory available, read at each run).
fn without_available(t: String) -> String {
    t.lines()
        .filter(|l| !l.starts_with("  available"))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// The number after `key` on the line of `text` that starts with it.
fn number_after(text: &str, key: &str) -> usize {
    let line = text
        .lines()
        .find(|l| l.starts_with(key))
        .unwrap_or_else(|| panic!("`{key}` in\n{text}"));
    line[key.len()..]
        .split_whitespace()
        .next()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("a number after `{key}`: {line}"))
}

/// On 2 and 4 ranks `check` prints its report once, then one line per rank: contiguous
/// blocks of the 16 substructures holding every link of the grid once.
#[test]
fn check_prints_the_rank_layout_once() {
    let case = manifest_path("cases/scale-16-latin.toml");
    let alone = tensolve(&["check", case.to_str().unwrap()]);
    assert_eq!(code(&alone), 0, "{}", text(&alone.stderr));
    let alone = without_available(text(&alone.stdout));
    assert!(
        !alone.contains("ranks:"),
        "one process prints no layout:\n{alone}"
    );
    let links = number_after(&alone, "bars") + number_after(&alone, "cables");
    for ranks in [2, 4] {
        let o = mpirun(ranks, &["check", case.to_str().unwrap()]);
        let out = without_available(text(&o.stdout));
        assert_eq!(code(&o), 0, "{out}{}", text(&o.stderr));
        assert!(
            out.starts_with(&alone),
            "the report once, as one process prints it:\n{out}"
        );
        let layout = &out[alone.len()..];
        assert!(
            layout.starts_with(&format!("ranks: {ranks} (micro-macro")),
            "{layout}"
        );
        let mut held = 0;
        for r in 0..ranks {
            let line = layout
                .lines()
                .find(|l| l.starts_with(&format!("  rank {r}:")))
                .unwrap_or_else(|| panic!("rank {r} in {layout}"));
            let first = r * 16 / ranks;
            let last = (r + 1) * 16 / ranks;
            assert!(
                line.contains(&format!("substructures {first}..{last} ({})", last - first)),
                "{line}"
            );
            held += line
                .split(", ")
                .find_map(|p| p.strip_suffix(" links"))
                .and_then(|n| n.parse::<usize>().ok())
                .unwrap_or_else(|| panic!("links in {line}"));
        }
        assert_eq!(held, links, "every link on one rank:\n{layout}");
        assert_eq!(layout.matches("  rank ").count(), ranks, "{layout}");
        // The digest rank 0 prints is this process's digest of the case read from the disk,
        // and every rank had it (or check would have failed).
        let digest = tensolve::app::ranks::case_digest(&tensolve::case::load(&case).unwrap());
        assert!(
            layout.contains(&format!("digest {digest:016x} on all {ranks} ranks")),
            "{digest:016x} in {layout}"
        );
    }
}

/// A case with tables beside it (`prism4`), loaded through rank 0's broadcast (the replay
/// itself is tested in `case::sources`): check's report is the one a single process prints
/// (but for the memory available, read at each run).
#[test]
fn a_case_with_tables_checks_alike_on_three_ranks() {
    let case = manifest_path("cases/prism4.toml");
    let alone = tensolve(&["check", case.to_str().unwrap()]);
    assert_eq!(code(&alone), 0, "{}", text(&alone.stderr));
    let o = mpirun(3, &["check", case.to_str().unwrap()]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    assert_eq!(
        without_available(text(&o.stdout)),
        format!(
            "{}ranks: 3 (no micro-macro solver in the case: nothing to distribute)\n",
            without_available(text(&alone.stdout))
        )
    );
}

/// A bad case fails on every rank with rank 0's message, said once; a missing file too.
#[test]
fn a_bad_case_fails_everywhere_with_one_message() {
    let case = manifest_path("cases/scale-16-latin.toml");
    let o = mpirun(
        2,
        &[
            "check",
            case.to_str().unwrap(),
            "--set",
            "solver.tolerance=-1",
        ],
    );
    let err = text(&o.stderr);
    assert_eq!(code(&o), 2, "{err}");
    assert_eq!(err.matches("error: ").count(), 1, "{err}");
    assert!(err.contains("solver.tolerance"), "{err}");
    let o = mpirun(2, &["check", "/nonexistent/case.toml"]);
    let err = text(&o.stderr);
    assert_eq!(code(&o), 2, "{err}");
    assert_eq!(err.matches("error: ").count(), 1, "{err}");
    assert!(err.contains("/nonexistent/case.toml"), "{err}");
}

/// `run` on two ranks is refused before anything is written (the solve is not distributed
/// yet); on one rank under mpirun it runs as without MPI.
#[test]
fn run_is_refused_on_several_ranks_and_runs_on_one() {
    let case = manifest_path("cases/scale-16-latin.toml");
    let out = Temp::dir("mpi-run");
    let o = mpirun(
        2,
        &["run", case.to_str().unwrap(), "--out", out.arg(), "--quiet"],
    );
    let err = text(&o.stderr);
    assert_eq!(code(&o), 2, "{err}");
    assert_eq!(err.matches("error: ").count(), 1, "{err}");
    assert!(
        err.contains("on 2 MPI ranks") && err.contains("mpirun -n 1"),
        "{err}"
    );
    assert!(!out.0.exists(), "nothing written");

    let o = mpirun(
        1,
        &["run", case.to_str().unwrap(), "--out", out.arg(), "--quiet"],
    );
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let summary = std::fs::read_to_string(out.0.join("summary.csv")).expect("summary");
    let rows: Vec<&str> = summary.lines().skip(1).collect();
    assert_eq!(rows.len(), 2, "{summary}");
    assert!(
        rows.iter().all(|r| r.split(',').nth(2) == Some("true")),
        "{summary}"
    );
}
