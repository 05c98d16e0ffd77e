//! Helpers shared by the integration tests: cases built in code, solving with both reference
//! solvers, and an independent check of the cable law.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};
use tensolve::case::{self, Case};
use tensolve::model::Model;
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use tensolve::solvers::{AnySolver, Silent, Solution, TautStiffness};
use tensolve::structure::Structure;

/// `‖a − b‖ / ‖b‖` (`‖a − b‖` where b = 0).
pub fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    let scale = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    if scale > 0.0 {
        diff / scale
    } else {
        diff
    }
}

/// Lower cable prestress p of the paper case, N.
pub const P: f64 = 2000.0;

pub fn manifest_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// Text of `cases/paper.toml`.
pub fn paper_text() -> String {
    std::fs::read_to_string(manifest_path("cases/paper.toml")).expect("cases/paper.toml")
}

/// Text of the paper case with some keys replaced: `("grid", "module", "braced".into())`.
pub fn paper_text_with(overrides: &[(&str, &str, toml::Value)]) -> String {
    let mut table: toml::Table = paper_text().parse().expect("paper.toml is TOML");
    for (section, key, value) in overrides {
        table
            .entry(section.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .expect("a section is a table")
            .insert(key.to_string(), value.clone());
    }
    toml::to_string(&table).unwrap()
}

/// The paper case with some keys replaced: `("grid", "module", "braced".into())`.
pub fn paper_with(overrides: &[(&str, &str, toml::Value)]) -> Case {
    case::parse(&paper_text_with(overrides)).expect("valid case")
}

pub fn paper_structure(overrides: &[(&str, &str, toml::Value)]) -> Structure {
    (paper_with(overrides)).structure()
}

/// The model of the paper case with some keys replaced (its structure under its geometric model).
pub fn paper_model(overrides: &[(&str, &str, toml::Value)]) -> Model {
    (paper_with(overrides)).model()
}

/// The load `alpha · unit_load` on the free dofs.
pub fn load(s: &Structure, alpha: f64) -> Vec<f64> {
    s.unit_load.iter().map(|f| alpha * f).collect()
}

/// Solve with newton (from U = 0) and pcg-lcp, default settings; both must converge.
pub fn solve_both(s: &Model, alpha: f64) -> (Solution, Solution) {
    let taut = TautStiffness::new(s).expect("taut stiffness is regular");
    let f = load(&s.structure, alpha);
    let newton = Newton::new(s, &taut, NewtonSettings::default())
        .expect("newton set-up")
        .solve(&f, None, &mut Silent);
    let pcg = PcgLcp::new(s, &taut, PcgLcpSettings::default()).solve(&f, None, &mut Silent);
    assert!(
        newton.info.status.converged(),
        "newton at alpha {alpha}: {:?}",
        newton.info
    );
    assert!(
        pcg.info.status.converged(),
        "pcg-lcp at alpha {alpha}: {:?}",
        pcg.info
    );
    (newton, pcg)
}

/// Independent check of the cable law, written from docs/method.md §1 alone: the largest violation, in N
/// relative to p, of `τ = t0 + k e` (bars, bilateral cables, taut cables) or of
/// `0 ≤ τ ⊥ λ ≥ 0` with the slack gap `kλ = τ − t0 − k e` (unilateral cables).
pub fn max_law_violation(s: &Structure, sol: &Solution) -> f64 {
    let eq = &sol.equilibrium;
    let mut worst: f64 = 0.0;
    for ((l, ld), &tau) in s.links.iter().zip(&s.link_dofs).zip(&eq.tensions) {
        let k_lambda = tau - l.prestress - l.stiffness * ld.elongation(&eq.displacements);
        let v = if l.unilateral {
            // min(a, b) = 0 ⇔ a ≥ 0, b ≥ 0, a·b = 0.
            k_lambda.min(tau).abs()
        } else {
            k_lambda.abs()
        };
        worst = worst.max(v);
    }
    worst / s.prestress_scale
}

/// A path under the temp dir that no other test (or test process) uses.
pub fn temp_path(tag: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("tensolve-test-{}-{n}-{tag}", std::process::id()))
}

/// Run the `tensolve` binary.
pub fn tensolve(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .args(args)
        .output()
        .expect("run tensolve")
}

/// A process's exit code (-1 when a signal ended it).
pub fn code(o: &Output) -> i32 {
    o.status.code().unwrap_or(-1)
}

/// `cases` proptest cases from the fixed `seed`, so that CI runs the same cases every time;
/// set `PROPTEST_RNG_SEED` to explore others.
pub fn fixed_seed_config(cases: u32, seed: u64) -> proptest::test_runner::Config {
    let mut config = proptest::test_runner::Config {
        cases,
        ..Default::default()
    };
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        config.rng_seed = proptest::test_runner::RngSeed::Fixed(seed);
    }
    config
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A temporary file or directory, removed when dropped.
pub struct Temp(pub PathBuf);

impl Temp {
    pub fn dir(tag: &str) -> Temp {
        Temp(temp_path(tag))
    }
    pub fn file(tag: &str, text: &str) -> Temp {
        let path = temp_path(&format!("{tag}.toml"));
        std::fs::write(&path, text).unwrap();
        Temp(path)
    }
    pub fn arg(&self) -> &str {
        self.0.to_str().expect("utf-8 temp path")
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
        let _ = std::fs::remove_file(&self.0);
    }
}

/// K = Bᵀ k B (every cable taut) on the free dofs, dense: for independent checks on small grids.
pub fn dense_stiffness(s: &Structure) -> nalgebra::DMatrix<f64> {
    let n = s.n_free;
    let mut k = nalgebra::DMatrix::<f64>::zeros(n, n);
    for (l, ld) in s.links.iter().zip(&s.link_dofs) {
        for (p, cp) in ld.iter() {
            for (q, cq) in ld.iter() {
                k[(p, q)] += l.stiffness * cp * cq;
            }
        }
    }
    k
}

/// Fails the test, saying what to install, unless python3 imports every module of `modules`:
/// a peer check that cannot run is a failure, never a pass (it is ignored unless asked for).
pub fn require_python(modules: &[&str]) {
    for module in modules {
        let imports = Command::new("python3")
            .args(["-c", &format!("import {module}")])
            .output()
            .is_ok_and(|o| o.status.success());
        let package = module.split('.').next().unwrap_or(module);
        assert!(
            imports,
            "this peer check needs python3's `{module}`, which does not import here: install \
             it with `python3 -m pip install {package}` (.ci/run installs every peer), or run \
             `cargo test --release` without --include-ignored / --ignored to leave the peer \
             checks out"
        );
    }
}

/// The rows of a CSV file as maps from its header's names to the values.
pub fn csv_rows(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            header
                .iter()
                .cloned()
                .zip(rec.unwrap().iter().map(String::from))
                .collect()
        })
        .collect()
}

/// The rows of `dir`'s summary.csv ([`csv_rows`]).
pub fn summary_rows(dir: &Path) -> Vec<std::collections::HashMap<String, String>> {
    csv_rows(&dir.join("summary.csv"))
}

/// The difference of two runs' answers by `solver` at `alpha` (`displacements/` and `forces/`
/// written): the larger of `max_node |U − U_large| / max_node |U_large|` and
/// `max_i |τᵢ − τᵢ_large| / max_i |τᵢ_large|`, `large` the second run.
pub fn difference_of_runs(model: &Path, large: &Path, solver: &str, alpha: &str) -> f64 {
    use std::collections::HashMap;
    let number = |r: &HashMap<String, String>, key: &str| -> f64 {
        r[key]
            .parse()
            .unwrap_or_else(|_| panic!("{key} = {:?}", r[key]))
    };
    let read =
        |dir: &Path, what: &str| csv_rows(&dir.join(format!("{what}/{solver}_alpha{alpha}.csv")));
    let motion = |r: &HashMap<String, String>| [number(r, "ux"), number(r, "uy"), number(r, "uz")];
    let size = |u: [f64; 3]| u.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (u, u_large) = (read(model, "displacements"), read(large, "displacements"));
    let deflection = u_large.iter().map(|r| size(motion(r))).fold(0.0, f64::max);
    let displacement = u
        .iter()
        .zip(&u_large)
        .map(|(a, b)| {
            let (a, b) = (motion(a), motion(b));
            size([a[0] - b[0], a[1] - b[1], a[2] - b[2]])
        })
        .fold(0.0, f64::max);
    let (f, f_large) = (read(model, "forces"), read(large, "forces"));
    let largest = f_large
        .iter()
        .map(|r| number(r, "force_N").abs())
        .fold(0.0, f64::max);
    let force = f
        .iter()
        .zip(&f_large)
        .map(|(a, b)| (number(a, "force_N") - number(b, "force_N")).abs())
        .fold(0.0, f64::max);
    (displacement / deflection).max(force / largest)
}

/// A bar from node 0 (0, 0, 0) up to node 1 (0, 0, 1) and a cable from node 1 down to node 2
/// (0, 0, −1), nodes 0 and 2 held, node 1 free along z alone, carrying 100 kN down at α = 1.
/// Bar: E = 2e11 Pa, S = 1e-4 m², k_b = 2e7 N/m, t0 = −50 kN; cable: E = 1e11, S = 1e-4, ℓ = 2
/// m, k_c = 5e6 N/m, t0 = 50 kN. The members stay on the z axis, so `linear` and `large`
/// agree: u_z = −F / (k_b + k_c) = −4 mm, τ_b = −50 kN − 80 kN = −130 kN, τ_c = 50 kN − 20 kN
/// = 30 kN.
pub fn column_case(dir: &Path, members: &str, geometry: &str) -> Temp {
    column_case_with(dir, members, geometry, "")
}

/// [`column_case`] with `extra` TOML appended (e.g. a `[checks]` table).
pub fn column_case_with(dir: &Path, members: &str, geometry: &str, extra: &str) -> Temp {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(
        dir.join("nodes.csv"),
        "node,x,y,z\n0,0,0,0\n1,0,0,1\n2,0,0,-1\n",
    )
    .unwrap();
    std::fs::write(dir.join("members.csv"), members).unwrap();
    let case = dir.join("case.toml");
    std::fs::write(
        &case,
        format!(
            "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n\
             [[supports.fix]]\nnodes = [0, 2]\n\
             [[supports.fix]]\nnodes = [1]\ndofs = [\"x\", \"y\"]\n\
             [[load.point]]\nnodes = [1]\nforce = [0.0, 0.0, -1e5]\n\
             [load]\nalpha = [1.0]\n[model]\ngeometry = \"{geometry}\"\n\
             [solver]\nmethods = [\"newton\"]\n{extra}"
        ),
    )
    .unwrap();
    Temp(case)
}
