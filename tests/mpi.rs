//! Under MPI (`cargo test --release --features mpi --test mpi`, with Debian's OpenMPI): the
//! binary started by `mpirun` on several ranks. Rank 0 reads the case and the others load its
//! bytes; rank 0 alone prints; every rank exits with the same status; `check` prints the rank
//! layout; `run` shares micro-macro's substructures among the ranks and gives the threaded
//! run's numbers bit for bit (issue 25).
#![cfg(feature = "mpi")]

mod common;

use common::{code, manifest_path, tensolve, Temp};
use std::process::{Command, Output};

/// `tensolve args` on `ranks` MPI ranks (oversubscribed: this machine may have fewer cores),
/// killed after 5 minutes (exit 124), so that ranks left waiting on each other fail a test
/// instead of hanging it.
fn mpirun(ranks: usize, args: &[&str]) -> Output {
    Command::new("timeout")
        .args([
            "300",
            "mpirun",
            "--oversubscribe",
            "--allow-run-as-root",
            "-n",
        ])
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

/// A CSV file with the columns whose name ends in `_seconds` (times) left out, row by row.
fn without_times(path: &std::path::Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let keep: Vec<bool> = header.iter().map(|h| !h.ends_with("_seconds")).collect();
    std::iter::once(header.join(","))
        .chain(lines.map(str::to_string))
        .map(|line| {
            line.split(',')
                .zip(&keep)
                .filter(|(_, &k)| k)
                .map(|(v, _)| v.to_string())
                .collect()
        })
        .collect()
}

/// The CSV files `got` and `want` hold the same results ([`without_times`]) bit for bit, but
/// for the summary's `equilibrium_residual` where the ranks each keep a share of the links: they
/// add r(U)'s nodal forces share by share, so it may differ by round-off (1e-9 of itself); and
/// `unique`, which ranks keeping shares leave empty (not checked: docs/guide.md, summary.csv).
fn assert_same_results(got: &std::path::Path, want: &std::path::Path, what: &str) {
    let (got, want) = (without_times(got), without_times(want));
    assert_eq!(got.len(), want.len(), "{what}: rows");
    let header = &want[0];
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.len(), w.len(), "{what}: columns");
        for ((a, b), name) in g.iter().zip(w).zip(header) {
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * y.abs();
            let same = match (name.as_str(), a.parse::<f64>(), b.parse::<f64>()) {
                ("equilibrium_residual", Ok(x), Ok(y)) => close(x, y),
                ("unique", ..) if a.is_empty() => true,
                _ => a == b,
            };
            assert!(same, "{what}: {name} {a} against {b}");
        }
    }
}

/// Every file under `dir` (relative paths, sorted), figures left out.
fn files_under(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_none_or(|x| x != "svg") {
                files.push(path.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    files.sort();
    files
}

/// micro-macro on 1, 2 and 4 ranks against the threaded run of the same binary without
/// mpirun: the same files, and in them the same numbers bit for bit (times aside): summary
/// (iterations, slack sets' counts, e, η, r(U)), histories and displacements. Each rank
/// computes its substructures' halves of the linear stage, and the macro right-hand side is
/// summed in the substructures' order on every rank, as on one process.
fn ranks_agree_with_threads(case: &str, sets: &[&str], rank_counts: &[usize]) {
    let case = manifest_path(case);
    let args = |out: &Temp| {
        vec![
            "run".to_string(),
            case.to_str().unwrap().to_string(),
            "--out".into(),
            out.arg().to_string(),
            "--quiet".into(),
            "--solver".into(),
            "micro-macro".into(),
            "--set".into(),
            "output.displacements=true".into(),
            "--set".into(),
            "output.plots=false".into(),
        ]
        .into_iter()
        .chain(
            sets.iter()
                .flat_map(|set| ["--set".to_string(), set.to_string()]),
        )
        .collect::<Vec<String>>()
    };
    let threads = Temp::dir("mpi-threads");
    let a = args(&threads);
    let o = tensolve(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let expected = files_under(&threads.0);
    assert!(expected.len() >= 3, "{expected:?}");
    for &ranks in rank_counts {
        let out = Temp::dir("mpi-ranks");
        let a = args(&out);
        let o = mpirun(ranks, &a.iter().map(String::as_str).collect::<Vec<_>>());
        assert_eq!(code(&o), 0, "{ranks} ranks: {}", text(&o.stderr));
        assert_eq!(
            files_under(&out.0),
            expected,
            "{ranks} ranks: the same files"
        );
        for file in &expected {
            let (got, want) = (&out.0.join(file), &threads.0.join(file));
            assert_same_results(got, want, &format!("{ranks} ranks: {}", file.display()));
        }
    }
}

#[test]
fn the_paper_case_on_ranks_is_the_threaded_run() {
    ranks_agree_with_threads("cases/paper.toml", &["load.alpha=[0.5, 1.0]"], &[1, 2, 4]);
}

/// micro-macro under large displacements (issue 44): each Newton step's linearised problem is
/// solved on the ranks' substructures, and 2 and 4 ranks give the threaded run's iterates and
/// answer (500 slack cables at α = 1) bit for bit.
#[test]
fn large_on_ranks_is_the_threaded_run() {
    ranks_agree_with_threads(
        "cases/paper.toml",
        &[
            "load.alpha=[0.5, 1.0]",
            "model.geometry=\"large\"",
            "solver.reference=\"none\"",
        ],
        &[2, 4],
    );
}

/// `model.geometry = "auto"` on ranks (issue 44): every rank measures newton's linear answer
/// alike, so all move to `large` at the same α (0.1 on the paper's grid) and give the
/// threaded run's rows, `model` column included.
#[test]
fn auto_on_ranks_is_the_threaded_run() {
    ranks_agree_with_threads(
        "cases/paper.toml",
        &[
            "load.alpha=[0.05, 0.1, 0.5]",
            "model.geometry=\"auto\"",
            "solver.reference=\"none\"",
        ],
        &[2],
    );
}

#[test]
fn scale_16_on_ranks_is_the_threaded_run() {
    ranks_agree_with_threads(
        "cases/scale-16-latin.toml",
        &["load.alpha=[2.4]"],
        &[1, 2, 4],
    );
}

#[test]
fn scale_64_on_ranks_is_the_threaded_run() {
    ranks_agree_with_threads(
        "cases/scale-64-latin.toml",
        &["load.alpha=[0.15]"],
        &[1, 2, 4],
    );
}

/// A macro basis of degree 2 (4 substructures of 8 × 8 modules): its extra columns are
/// reduced and solved alike on every rank.
#[test]
fn a_higher_macro_degree_on_ranks_is_the_threaded_run() {
    ranks_agree_with_threads(
        "cases/scale-16-latin.toml",
        &["load.alpha=[2.4]", "solver.subdomains=[2, 2]"],
        &[2, 4],
    );
}

/// A run of micro-macro alone with no reference solve has the ranks keep only their
/// substructures' links: every rank when the files asked for read no link (summary, history,
/// displacements: the ranks measure each answer together), the ranks other than 0 otherwise
/// (rank 0 keeps the whole structure for the files that read every link). The paper's case and
/// a 64 × 64 grid on 2 and 4 ranks still give the threaded run's files, bit for bit but for
/// r(U) of the summary, which the shares add in another order; the run says what the ranks
/// kept, and with a reference solve that every rank kept the whole structure.
#[test]
fn ranks_keeping_their_links_alone_are_the_threaded_run() {
    let alone = ["solver.reference=\"none\"", "output.geometric_term=false"];
    let no_link_files = [
        "output.tensions=false",
        "output.forces=false",
        "output.reactions=false",
        "output.vtk=false",
        "output.stability=false",
        "output.homogenised=false",
    ];
    for (case, alpha) in [
        ("cases/paper.toml", "load.alpha=[0.5, 1.0]"),
        ("cases/scale-64-latin.toml", "load.alpha=[0.15]"),
    ] {
        let sets: Vec<&str> = [alpha]
            .iter()
            .chain(&alone)
            .chain(&no_link_files)
            .copied()
            .collect();
        ranks_agree_with_threads(case, &sets, &[2, 4]);
    }
    ranks_agree_with_threads(
        "cases/paper.toml",
        &[
            "load.alpha=[1.0]",
            alone[0],
            alone[1],
            "output.tensions=true",
        ],
        &[3],
    );
    let case = manifest_path("cases/paper.toml");
    let said = |sets: &[&str]| {
        let out = Temp::dir("mpi-kept");
        let mut args = vec!["run", case.to_str().unwrap(), "--out", out.arg()];
        args.extend(["--solver", "micro-macro", "--set", "load.alpha=[1.0]"]);
        for set in sets {
            args.extend(["--set", set]);
        }
        let o = mpirun(4, &args);
        assert_eq!(code(&o), 0, "{}", text(&o.stderr));
        text(&o.stderr)
    };
    // 16 substructures of 256 links each, 4 per rank.
    let mut sets = alone.to_vec();
    sets.extend(no_link_files);
    sets.push("output.plots=false");
    let err = said(&sets);
    let every = "MPI: every rank kept only its substructures' links, at most 1024 of 4096";
    assert!(err.contains(every), "{err}");
    assert!(err.contains("408 / 3072 slack"), "{err}");
    let err = said(&alone);
    let others = "MPI: ranks 1 to 3 kept only their substructures' links, at most 1024 of 4096";
    assert!(err.contains(others), "{err}");
    assert!(err.contains("408 / 3072 slack"), "{err}");
    let err = said(&[]);
    assert!(
        err.contains("MPI: every rank kept the whole structure"),
        "{err}"
    );
}

/// A run that never solves with K's factor (LATIN alone, reference none, no geometric-term
/// check) has rank 0 alone make the mechanism check: the others' results are the same, and a
/// mechanism is refused on every rank, with rank 0's message once and nothing written.
#[test]
fn rank_0_alone_checks_for_a_mechanism_when_no_solve_needs_k() {
    let released = [
        "load.alpha=[2.4]",
        "solver.reference=\"none\"",
        "output.geometric_term=false",
    ];
    ranks_agree_with_threads("cases/scale-16-latin.toml", &released, &[2]);
    let case = manifest_path("cases/scale-16-latin.toml");
    let out = Temp::dir("mpi-mechanism");
    let mut args = vec!["run", case.to_str().unwrap(), "--out", out.arg(), "--quiet"];
    for set in released.iter().chain(&["supports.clamp=\"none\""]) {
        args.extend(["--set", set]);
    }
    let o = mpirun(2, &args);
    let err = text(&o.stderr);
    assert_ne!(code(&o), 0, "{err}");
    assert_eq!(err.matches("error").count(), 1, "{err}");
    assert!(err.contains("mechanism"), "{err}");
    assert!(!out.0.exists(), "nothing written");
}

/// The paper's plain method (the relaxed order, l fixed) on 3 ranks, whose blocks are uneven
/// (5, 5 and 6 of the 16 substructures), once as the paper runs it (μ = 1) and once relaxed
/// (μ = 0.8: each rank blends its own substructures' s before sharing it).
#[test]
fn the_plain_method_on_three_ranks_is_the_threaded_run() {
    let case = "cases/paper-plain.toml";
    ranks_agree_with_threads(case, &["load.alpha=[0.5, 1.0]"], &[3]);
    let relaxed = ["load.alpha=[1.0]", "solver.relaxation=0.8"];
    ranks_agree_with_threads(case, &relaxed, &[3]);
}

/// A solve that cannot be set up fails on every rank, with one message and nothing written;
/// `bench` is refused on several ranks.
#[test]
fn a_refused_set_up_fails_everywhere_and_bench_is_refused() {
    let case = manifest_path("cases/scale-16-latin.toml");
    let out = Temp::dir("mpi-refused");
    let o = mpirun(
        2,
        &[
            "run",
            case.to_str().unwrap(),
            "--out",
            out.arg(),
            "--quiet",
            "--set",
            "solver.subdomains=[40, 4]",
        ],
    );
    let err = text(&o.stderr);
    assert_ne!(code(&o), 0, "{err}");
    assert_eq!(err.matches("error").count(), 1, "{err}");
    assert!(err.contains("solver.subdomains"), "{err}");
    assert!(!out.0.exists(), "nothing written");

    let o = mpirun(2, &["bench", case.to_str().unwrap(), "--quiet"]);
    let err = text(&o.stderr);
    assert_eq!(code(&o), 2, "{err}");
    assert!(err.contains("on 2 MPI ranks"), "{err}");
}

/// Rank 0 alone writes: when it cannot open the output directory, every rank stops there (none
/// waits in the solve's collectives) and exits non-zero, with rank 0's message once.
#[test]
fn an_output_directory_rank_0_cannot_write_stops_every_rank() {
    let case = manifest_path("cases/scale-16-latin.toml");
    let o = mpirun(
        2,
        &[
            "run",
            case.to_str().unwrap(),
            "--out",
            "/proc/tensolve-cannot-write-here",
            "--quiet",
            "--solver",
            "micro-macro",
        ],
    );
    let err = text(&o.stderr);
    assert_eq!(code(&o), 2, "{err}");
    assert_eq!(err.matches("error: ").count(), 1, "{err}");
    assert!(err.contains("not writable"), "{err}");
}
