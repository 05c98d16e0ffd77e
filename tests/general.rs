//! General structures (docs/method.md §7): node/member tables, supports and loads anywhere, prescribed
//! displacements, and the self-stress / mechanism counts.

mod common;

use common::{manifest_path, solve_both, tensolve, Temp};
use nalgebra::DMatrix;
use proptest::prelude::*;
use tensolve::app::check::equilibrium_counts;
use tensolve::case::{self, read_geometry};
use tensolve::model::Model;
use tensolve::solvers::latin::{Latin, LatinSettings};
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use tensolve::solvers::{AnySolver, Silent, Solution, TautStiffness};
use tensolve::structure::{Geometry, Loading, NodeFix, Structure, CLAMPED};

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0, |m: f64, (x, y)| m.max((x - y).abs()))
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m: f64, x| m.max(x.abs()))
}

#[test]
fn paper_grid_as_tables_reproduces_the_grid() {
    let grid = case::load(&manifest_path("cases/paper.toml"))
        .unwrap()
        .model();
    let tables = case::load(&manifest_path("cases/paper-csv.toml"))
        .unwrap()
        .model();
    assert!(tables.structure.layout.is_none());
    assert_eq!(tables.structure.n_free, grid.structure.n_free);
    for (alpha, slack) in [(1.0, 408), (0.5, 36)] {
        let (gn, gp) = solve_both(&grid, alpha);
        let (tn, tp) = solve_both(&tables, alpha);
        for sol in [&gn, &gp, &tn, &tp] {
            assert_eq!(sol.equilibrium.slack.iter().filter(|&&s| s).count(), slack);
        }
        let scale = max_abs(&gn.equilibrium.displacements);
        assert!(
            max_abs_diff(&gn.equilibrium.displacements, &tn.equilibrium.displacements)
                <= 1e-12 * scale
        );
        assert!(
            max_abs_diff(&gp.equilibrium.displacements, &tp.equilibrium.displacements)
                <= 1e-12 * scale
        );
    }
}

/// A tripod: apex 3 at (0, 0, h) on three bars from supports on the unit circle.
fn tripod(h: f64, kinds: [&str; 3], unilateral: bool) -> Geometry {
    let mut nodes = String::from("node,x,y,z\n");
    for k in 0..3 {
        let a = 2.0 * std::f64::consts::PI * k as f64 / 3.0;
        nodes += &format!("{},{},{},0\n", 10 + k, a.cos(), a.sin());
    }
    nodes += &format!("3,0,0,{h}\n");
    let mut members = String::from("member,a,b,kind,young,section,prestress,density\n");
    for (k, kind) in kinds.iter().enumerate() {
        members += &format!("{},{},3,{kind},2e11,1e-4,0,7850\n", 100 + k, 10 + k);
    }
    read_geometry("nodes.csv", &nodes, "members.csv", &members, unilateral).unwrap()
}

fn held(nodes: &[usize], displacement: [f64; 3]) -> Vec<NodeFix> {
    nodes
        .iter()
        .map(|&node| NodeFix {
            node,
            dofs: [true; 3],
            displacement,
        })
        .collect()
}

/// newton on `s` under the linear model.
fn newton(s: &Structure, f: &[f64]) -> Solution {
    let model = Model::linear(s.clone());
    let taut = TautStiffness::new(&model).unwrap();
    let sol = Newton::new(&model, &taut, NewtonSettings::default())
        .unwrap()
        .solve(f, None, &mut Silent);
    assert!(sol.info.status.converged(), "{:?}", sol.info);
    sol
}

/// pcg-lcp on `s` under the linear model.
fn pcg(s: &Structure, f: &[f64]) -> Solution {
    let model = Model::linear(s.clone());
    let taut = TautStiffness::new(&model).unwrap();
    let sol = PcgLcp::new(&model, &taut, PcgLcpSettings::default()).solve(f, None, &mut Silent);
    assert!(sol.info.status.converged(), "{:?}", sol.info);
    sol
}

#[test]
fn tripod_tensions_follow_from_statics() {
    // A vertical load P on the apex: each bar carries t = −P ℓ / (3 h) by symmetry.
    let h = 2.0;
    let g = tripod(h, ["bar"; 3], false);
    let p = 3000.0;
    let loading = Loading {
        points: vec![(3, [0.0, 0.0, -p])],
        ..Loading::default()
    };
    let s = Structure::new(&g, &held(&[0, 1, 2], [0.0; 3]), &loading);
    assert_eq!(s.n_free, 3);
    let want = -p * (1.0 + h * h).sqrt() / (3.0 * h);
    for sol in [newton(&s, &s.unit_load), pcg(&s, &s.unit_load)] {
        for t in &sol.equilibrium.tensions {
            assert!((t - want).abs() <= 1e-9 * want.abs(), "{t} vs {want}");
        }
    }
}

/// The structure's full stiffness `Σ k nnᵀ` on all 3·nodes dofs, from the geometry alone.
fn full_stiffness(s: &Structure) -> DMatrix<f64> {
    let n = 3 * s.n_nodes();
    let mut k = DMatrix::zeros(n, n);
    for l in &s.links {
        for (p, sp) in [(l.a, -1.0), (l.b, 1.0)] {
            for (q, sq) in [(l.a, -1.0), (l.b, 1.0)] {
                for i in 0..3 {
                    for j in 0..3 {
                        k[(3 * p + i, 3 * q + j)] +=
                            sp * sq * l.stiffness * l.direction[i] * l.direction[j];
                    }
                }
            }
        }
    }
    k
}

#[test]
fn settlement_matches_the_condensed_linear_system() {
    // Bilateral tripod, one support settled by (0.001, −0.002, −0.01), a point load too:
    // independently, K_ff U_f = F_f − K_fp U_d.
    let g = tripod(1.5, ["bar", "cable", "cable"], false);
    let ud = [0.001, -0.002, -0.01];
    let mut fixes = held(&[0, 1], [0.0; 3]);
    fixes.extend(held(&[2], ud));
    let loading = Loading {
        points: vec![(3, [100.0, 50.0, -400.0])],
        ..Loading::default()
    };
    let s = Structure::new(&g, &fixes, &loading);
    let k = full_stiffness(&s);
    let n = 3 * s.n_nodes();
    let free: Vec<usize> = (0..n).filter(|&d| s.dof_of[d] != CLAMPED).collect();
    let fixed: Vec<usize> = (0..n).filter(|&d| s.dof_of[d] == CLAMPED).collect();
    let kff = DMatrix::from_fn(free.len(), free.len(), |i, j| k[(free[i], free[j])]);
    let rhs = DMatrix::from_fn(free.len(), 1, |i, _| {
        s.unit_load[i]
            - fixed
                .iter()
                .map(|&p| k[(free[i], p)] * s.prescribed[p])
                .sum::<f64>()
    });
    let u = kff.lu().solve(&rhs).unwrap();
    for sol in [newton(&s, &s.unit_load), pcg(&s, &s.unit_load)] {
        let got = &sol.equilibrium.displacements;
        let err = (0..free.len()).fold(0.0, |m: f64, i| m.max((got[i] - u[i]).abs()));
        assert!(err <= 1e-9 * u.amax(), "{err} vs {}", u.amax());
        // Reactions balance the load: Σ over all dofs of Bᵀτ, with the applied force, is 0.
        let full = s.full_displacements(got);
        assert_eq!(&full[6..9], &ud);
    }
}

#[test]
fn self_weight_is_carried_by_the_reactions_and_superposes_with_point_loads() {
    let g = tripod(1.0, ["bar"; 3], false);
    let fixes = held(&[0, 1, 2], [0.0; 3]);
    let gravity = [0.0, 0.0, -9.81];
    let weight = Loading {
        gravity: Some(gravity),
        ..Loading::default()
    };
    let s = Structure::new(&g, &fixes, &weight);
    let sol = newton(&s, &s.unit_load);
    // Total weight Σ ρ S ℓ g; the reactions at the held nodes are Σ τ n there, plus the half
    // weights of the members that fall on those nodes directly.
    let total: f64 = s
        .links
        .iter()
        .map(|l| 7850.0 * 1e-4 * l.length * 9.81)
        .sum();
    let mut reaction_z = 0.0;
    for (l, t) in s.links.iter().zip(&sol.equilibrium.tensions) {
        // node a is the support: the member pulls it by τ n (towards b).
        reaction_z += -t * l.direction[2] + 0.5 * 7850.0 * 1e-4 * l.length * 9.81;
    }
    assert!(
        (reaction_z - total).abs() <= 1e-9 * total,
        "{reaction_z} vs {total}"
    );
    // Superposition, linear regime: U(weight + point) = U(weight) + U(point).
    let point = Loading {
        points: vec![(3, [20.0, -10.0, -50.0])],
        ..Loading::default()
    };
    let both = Loading {
        gravity: Some(gravity),
        points: point.points.clone(),
        ..Loading::default()
    };
    let sp = Structure::new(&g, &fixes, &point);
    let sb = Structure::new(&g, &fixes, &both);
    let (uw, up, ub) = (
        sol.equilibrium.displacements,
        newton(&sp, &sp.unit_load).equilibrium.displacements,
        newton(&sb, &sb.unit_load).equilibrium.displacements,
    );
    let sum: Vec<f64> = uw.iter().zip(&up).map(|(a, b)| a + b).collect();
    assert!(max_abs_diff(&sum, &ub) <= 1e-10 * max_abs(&ub));
}

/// s and m from a dense SVD of A = Bᵀ (free dofs × members).
fn dense_counts(s: &Structure) -> (usize, usize) {
    let mut a = DMatrix::<f64>::zeros(s.n_free, s.links.len());
    for (j, row) in s.link_dofs.iter().enumerate() {
        for (d, v) in row.iter() {
            a[(d, j)] += v;
        }
    }
    let sv = a.singular_values();
    let top = sv.max();
    let rank = sv.iter().filter(|&&x| x > 1e-10 * top).count();
    (s.links.len() - rank, s.n_free - rank)
}

fn grid_case(modules: [usize; 2], module: &str, clamp: &str) -> Structure {
    case::parse(&format!(
        "[grid]\nmodules = {modules:?}\nmodule = \"{module}\"\n[supports]\nclamp = \"{clamp}\"\n[load]\nalpha = [1.0]\n"
    ))
    .unwrap()
    .structure()
}

#[test]
fn self_stress_and_mechanism_counts_agree_with_a_dense_svd() {
    let cases = [
        (
            "paper module alone",
            grid_case([1, 1], "standard", "none"),
            Some(9),
        ),
        (
            "braced module alone",
            grid_case([1, 1], "braced", "none"),
            None,
        ),
        (
            "2 x 2 clamped on x edges",
            grid_case([2, 2], "standard", "lower-x-edges"),
            Some(0),
        ),
        (
            "3 x 2 braced on corners",
            grid_case([3, 2], "braced", "lower-corners"),
            None,
        ),
        (
            "tripod",
            Structure::new(
                &tripod(1.0, ["bar"; 3], false),
                &held(&[0, 1, 2], [0.0; 3]),
                &Loading::default(),
            ),
            Some(0),
        ),
        (
            "free tripod",
            Structure::new(&tripod(1.0, ["bar"; 3], false), &[], &Loading::default()),
            None,
        ),
    ];
    for (name, s, m_known) in cases {
        let c = equilibrium_counts(&s);
        let (s_dense, m_dense) = dense_counts(&s);
        assert_eq!(
            (c.self_stress_states, c.mechanisms),
            (s_dense, m_dense),
            "{name}"
        );
        assert_eq!(c.rank + c.mechanisms, s.n_free, "{name}");
        if let Some(m) = m_known {
            assert_eq!(c.mechanisms, m, "{name}");
        }
    }
}

/// The bad tables: (nodes, members, line, column).
const BAD: &[(&str, &str, u64, &str)] = &[
    (
        "node,x,y,z\n0,0,0,0\n0,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,0\n",
        3,
        "node",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,zz\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,0\n",
        3,
        "z",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,inf\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,0\n",
        3,
        "z",
    ),
    (
        "node,x,y,z\n0,0,0,0\n-1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,0\n",
        3,
        "node",
    ),
    (
        "node,x,y\n0,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,0\n",
        1,
        "header",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,7,bar,1,1,0\n",
        2,
        "b",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,0,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,0\n",
        2,
        "b",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,rope,1,1,0\n",
        2,
        "kind",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,-1,1,0\n",
        2,
        "young",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,0,0\n",
        2,
        "section",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,NaN\n",
        2,
        "prestress",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1,0\n0,1,0,bar,1,1,0\n",
        3,
        "member",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress,density\n0,0,1,bar,1,1,0,-3\n",
        2,
        "density",
    ),
    (
        "node,x,y,z\n0,0,0,0\n1,1,0,0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,1,1\n",
        2,
        "prestress",
    ),
];

#[test]
fn every_bad_row_exits_2_naming_file_line_and_column() {
    for (i, &(nodes, members, line, column)) in BAD.iter().enumerate() {
        let dir = Temp::dir(&format!("bad-table-{i}"));
        std::fs::create_dir_all(&dir.0).unwrap();
        std::fs::write(dir.0.join("nodes.csv"), nodes).unwrap();
        std::fs::write(dir.0.join("members.csv"), members).unwrap();
        let case = dir.0.join("case.toml");
        std::fs::write(
            &case,
            "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n[load]\nalpha = [1.0]\n",
        )
        .unwrap();
        let out = tensolve(&["check", case.to_str().unwrap()]);
        let err = common::stderr(&out);
        assert_eq!(out.status.code(), Some(2), "case {i}: {err}");
        let file = if i < 5 { "nodes.csv" } else { "members.csv" };
        assert!(err.contains(file), "case {i}: {err}");
        assert!(err.contains(&format!("line {line}")), "case {i}: {err}");
        assert!(
            err.contains(&format!("column `{column}`")),
            "case {i}: {err}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn mutated_tables_never_panic(
        cut in 0usize..200,
        byte in any::<u8>(),
        at in 0usize..200,
        which in 0usize..2,
    ) {
        let mut texts = [
            b"node,x,y,z\n0,0,0,0\n1,1,0,0\n2,0,1,0\n3,0.3,0.3,1\n".to_vec(),
            b"member,a,b,kind,young,section,prestress,density\n0,0,3,bar,2e11,1e-4,0,7850\n1,1,3,cable,1e11,1e-4,0,\n2,2,3,bar,2e11,1e-4,0,1\n".to_vec(),
        ];
        let t = &mut texts[which];
        let at = at % t.len();
        t[at] = byte;
        let cut = cut.min(t.len());
        t.truncate(t.len() - cut / 4);
        let nodes = String::from_utf8_lossy(&texts[0]).into_owned();
        let members = String::from_utf8_lossy(&texts[1]).into_owned();
        if let Err(e) = read_geometry("n.csv", &nodes, "m.csv", &members, true) {
            prop_assert!(e.to_string().contains("line"));
        }
    }
}

/// A 3 × 3 grid of the paper's modules with every node moved off the grid by up to 3 % of
/// the module, the prestress projected onto the self-stress states at the free dofs
/// (`t0 − Aᵀ (A Aᵀ)⁻¹ A t0`), clamped on the lower x-edges.
fn perturbed() -> Structure {
    perturbed_held(false)
}

/// [`perturbed`]; with `partial`, the lower edge x = 3 is held in z only and its corner
/// (3, 3) settles by 3 mm (the prestress projected on the free dofs of these supports).
fn perturbed_held(partial: bool) -> Structure {
    let grid = grid_case([3, 3], "standard", "lower-x-edges");
    let mut nodes = String::from("node,x,y,z\n");
    for (n, p) in grid.nodes.iter().enumerate() {
        let wobble = |k: usize| 0.03 * (((n * 7 + k * 13) % 11) as f64 / 10.0 - 0.5);
        let moved = if grid.clamped[n] {
            *p
        } else {
            [p[0] + wobble(0), p[1] + wobble(1), p[2] + wobble(2)]
        };
        nodes += &format!("{n},{},{},{}\n", moved[0], moved[1], moved[2]);
    }
    let write = |t0: &[f64]| {
        let mut members = String::from("member,a,b,kind,young,section,prestress\n");
        for (i, l) in grid.links.iter().enumerate() {
            let (kind, young, section) = if l.kind.is_cable() {
                ("cable", 1e11, 0.5e-4)
            } else {
                ("bar", 2e11, 2.8e-4)
            };
            members += &format!("{i},{},{},{kind},{young},{section},{}\n", l.a, l.b, t0[i]);
        }
        members
    };
    let x_max = grid.nodes.iter().fold(0.0, |m: f64, p| m.max(p[0]));
    let y_max = grid.nodes.iter().fold(0.0, |m: f64, p| m.max(p[1]));
    let fixes: Vec<NodeFix> = (0..grid.n_nodes())
        .filter(|&n| grid.clamped[n])
        .map(|n| {
            let p = grid.nodes[n];
            if partial && p[0] == x_max {
                let settles = p[1] == y_max;
                NodeFix {
                    node: n,
                    dofs: [false, false, true],
                    displacement: [0.0, 0.0, if settles { -0.003 } else { 0.0 }],
                }
            } else {
                held(&[n], [0.0; 3])[0]
            }
        })
        .collect();
    let t0: Vec<f64> = grid.links.iter().map(|l| l.prestress).collect();
    let raw = read_geometry("n", &nodes, "m", &write(&t0), true).unwrap();
    let s = Structure::new(&raw, &fixes, &Loading::default());
    let mut a = DMatrix::<f64>::zeros(s.n_free, s.links.len());
    for (j, row) in s.link_dofs.iter().enumerate() {
        for (d, v) in row.iter() {
            a[(d, j)] += v;
        }
    }
    let t = nalgebra::DVector::from_vec(t0);
    let y = (&a * a.transpose()).cholesky().unwrap().solve(&(&a * &t));
    let balanced = &t - a.transpose() * y;
    let g = read_geometry("n", &nodes, "m", &write(balanced.as_slice()), true).unwrap();
    let loading = Loading {
        nodal: [0.0, 0.0, -40.0],
        ..Loading::default()
    };
    Structure::new(&g, &fixes, &loading)
}

/// The load and newton's solution at the smallest of α = 4, 8, 16, 32 at which at least 5 %
/// of the cables of `s` are slack.
fn five_percent_slack(s: &Structure) -> (Vec<f64>, Solution) {
    [4.0, 8.0, 16.0, 32.0]
        .iter()
        .map(|alpha| {
            let f: Vec<f64> = s.unit_load.iter().map(|x| alpha * x).collect();
            let sol = newton(s, &f);
            (f, sol)
        })
        .find(|(_, sol)| sol.equilibrium.slack.iter().filter(|&&x| x).count() * 20 >= s.n_cables())
        .expect("some load factor slackens 5 % of the cables")
}

#[test]
fn four_solvers_agree_on_a_perturbed_general_structure() {
    let s = perturbed();
    assert!(s.layout.is_none());
    let (f, reference) = five_percent_slack(&s);
    println!(
        "slack: {} of {}",
        reference.equilibrium.slack.iter().filter(|&&x| x).count(),
        s.n_cables()
    );
    let p = pcg(&s, &f);
    let model = Model::linear(s.clone());
    let scale = max_abs(&reference.equilibrium.displacements);
    assert!(
        max_abs_diff(
            &p.equilibrium.displacements,
            &reference.equilibrium.displacements
        ) <= 1e-8 * scale
    );
    for subdomains in [[1, 1], [2, 2]] {
        let settings = LatinSettings {
            subdomains,
            ..LatinSettings::default()
        };
        let mut latin = Latin::new(&model, settings).unwrap();
        let sol = latin.solve(&f, None, &mut Silent);
        assert_latin_agrees(&sol, &reference, subdomains, 1e-5 * scale);
    }
}

/// `cases/skew-grid.toml`: a 6 × 4 general grid held on one lower edge in x, y, z, on the
/// other in z only, with a 5 mm settlement at a corner (docs/method.md §7).
fn skew_grid() -> Structure {
    case::load(&manifest_path("cases/skew-grid.toml"))
        .unwrap()
        .structure()
}

#[test]
fn latin_solvers_agree_with_newton_on_partial_supports_and_a_settlement() {
    let s = skew_grid();
    // The case really has both: nodes held on z only, and a non-zero prescribed displacement.
    let partial = (0..s.n_nodes())
        .filter(|&n| {
            let held = (0..3).filter(|&k| s.dof_of[3 * n + k] == CLAMPED).count();
            held == 1
        })
        .count();
    assert_eq!(partial, 5);
    assert!(s.prescribed.iter().any(|&u| u == -0.005));
    let alpha = 2.0;
    let f: Vec<f64> = s.unit_load.iter().map(|x| alpha * x).collect();
    let reference = newton(&s, &f);
    let slack = reference.equilibrium.slack.iter().filter(|&&x| x).count();
    assert!(
        slack * 20 >= s.n_cables(),
        "{slack} slack of {}",
        s.n_cables()
    );
    let scale = max_abs(&reference.equilibrium.displacements);
    let model = Model::linear(s.clone());
    for subdomains in [[1, 1], [2, 2], [3, 2]] {
        let settings = LatinSettings {
            subdomains,
            tolerance: 1e-9,
            ..LatinSettings::default()
        };
        let mut latin = Latin::new(&model, settings).unwrap();
        if subdomains != [1, 1] {
            // The partition does cut through the partly held edge (held in z only): some
            // interface has a node with only its x and y rows.
            let partly_held = latin.partly_held_interface_nodes();
            assert!(partly_held >= 1, "LATIN {subdomains:?}");
            println!(
                "LATIN {subdomains:?}: {partly_held} partly held interface node(s), kernel columns {:?}",
                latin.kernel_columns()
            );
        }
        let sol = latin.solve(&f, None, &mut Silent);
        assert_latin_agrees(&sol, &reference, subdomains, 1e-6 * scale);
        // The held components sit at their prescribed values, the settlement included.
        let full = s.full_displacements(&sol.equilibrium.displacements);
        for (d, &ud) in s.prescribed.iter().enumerate() {
            if s.dof_of[d] == CLAMPED {
                assert_eq!(full[d], ud);
            }
        }
    }
}

#[test]
fn the_settled_skew_grid_case_runs_all_four_solvers() {
    let case = case::load(&manifest_path("cases/skew-grid.toml")).unwrap();
    let names: Vec<&str> = case.solver.methods.iter().map(|m| m.name()).collect();
    assert_eq!(names, ["newton", "pcg-lcp", "mono-latin", "micro-macro"]);
    let out_dir = Temp::dir("skew-grid-four");
    let out = tensolve(&[
        "run",
        manifest_path("cases/skew-grid.toml").to_str().unwrap(),
        "--out",
        out_dir.arg(),
        "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", common::stderr(&out));
    let summary = std::fs::read_to_string(out_dir.0.join("summary.csv")).unwrap();
    let mut lines = summary.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|&h| h == name).unwrap();
    let (solver, alpha, converged, slack) = (
        column("solver"),
        column("alpha"),
        column("converged"),
        column("slack_cables"),
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // Three load factors, four solvers, every one converged with newton's slack count.
    assert_eq!(rows.len(), 12, "{summary}");
    for name in names {
        assert_eq!(rows.iter().filter(|r| r[solver] == name).count(), 3);
    }
    for row in &rows {
        assert_eq!(row[converged], "true", "{row:?}");
        let newton = rows
            .iter()
            .find(|r| r[solver] == "newton" && r[alpha] == row[alpha])
            .unwrap();
        assert_eq!(row[slack], newton[slack], "{row:?}");
    }
}

/// A node D at the origin held by three cables (members 10, 11, 12, to clamped nodes at
/// (2, 0, 0), (0, 3, 0), (0, 0, 1)) and a bar (13, to a clamped node at (1, 2, 2)); a node E
/// at (0, 0, −1) held determinately by members 20, 21 (cables) and 22 (bar), plus `extra`
/// member rows. s = 7 − 6 = 1, m = 0. Equilibrium of D, `Σ t n = 0` with n = (1, 0, 0),
/// (0, 1, 0), (0, 0, 1), (1, 2, 2)/3: `t10 = −t13/3`, `t11 = t12 = −2 t13/3`; E carries none.
fn self_stress_tables(extra: &str, prestress_11: f64) -> (String, String) {
    let nodes = "node,x,y,z\n0,0,0,0\n1,2,0,0\n2,0,3,0\n3,0,0,1\n4,1,2,2\n5,0,0,-1\n6,-1,0,0\n";
    let members = format!(
        "member,a,b,kind,young,section,prestress\n\
         10,0,1,cable,1e11,1e-4,0\n11,0,2,cable,1e11,1e-4,{prestress_11}\n\
         12,0,3,cable,1e11,1e-4,0\n13,0,4,bar,2e11,3e-4,0\n\
         20,5,1,cable,1e11,1e-4,0\n21,5,2,cable,1e11,1e-4,0\n22,5,4,bar,2e11,3e-4,0\n{extra}"
    );
    (nodes.to_string(), members)
}

/// A case on [`self_stress_tables`]: nodes 1, 2, 3, 4 and 6 clamped, `prestress` as the
/// `[prestress]` section's body, 10 N down on D.
fn self_stress_case(tag: &str, extra: &str, prestress_11: f64, prestress: &str) -> Temp {
    let dir = Temp::dir(tag);
    std::fs::create_dir_all(&dir.0).unwrap();
    let (nodes, members) = self_stress_tables(extra, prestress_11);
    std::fs::write(dir.0.join("nodes.csv"), nodes).unwrap();
    std::fs::write(dir.0.join("members.csv"), members).unwrap();
    std::fs::write(
        dir.0.join("case.toml"),
        format!(
            "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n\
             [[supports.fix]]\nnodes = [1, 2, 3, 4, 6]\n\
             [prestress]\n{prestress}\n\
             [[load.point]]\nnodes = [0]\nforce = [0.0, 0.0, -10.0]\n\
             [load]\nalpha = [1.0]\n"
        ),
    )
    .unwrap();
    dir
}

#[test]
fn prestress_from_the_self_stress_state_matches_statics() {
    let dir = self_stress_case(
        "self-stress-ok",
        "",
        0.0,
        "from = \"self-stress\"\nmember = 10\nforce = 1000.0",
    );
    let s = case::load(&dir.0.join("case.toml")).unwrap().structure();
    assert_eq!(equilibrium_counts(&s).self_stress_states, 1);
    assert_eq!(equilibrium_counts(&s).mechanisms, 0);
    let t0: Vec<f64> = s.links.iter().map(|l| l.prestress).collect();
    let want = [1000.0, 2000.0, 2000.0, -3000.0, 0.0, 0.0, 0.0];
    for ((l, t), w) in s.links.iter().zip(&t0).zip(want) {
        assert!(
            (t - w).abs() <= 1e-9 * 3000.0,
            "member {}: {t} vs {w}",
            l.id
        );
    }
    // In equilibrium at the free dofs: |B_fᵀ t0| ≤ 1e-10 ‖t0‖.
    let mut f = vec![0.0; s.n_free];
    s.nodal_forces(&t0, &mut f);
    let size = t0.iter().map(|t| t * t).sum::<f64>().sqrt();
    assert!(max_abs(&f) <= 1e-10 * size, "{f:?}");
    // Compression sign: the same state through the bar at −3000 N.
    let dir = self_stress_case(
        "self-stress-bar",
        "",
        0.0,
        "from = \"self-stress\"\nmember = 13\nforce = -3000.0",
    );
    let s = case::load(&dir.0.join("case.toml")).unwrap().structure();
    for (l, w) in s.links.iter().zip(want) {
        assert!((l.prestress - w).abs() <= 1e-9 * 3000.0, "member {}", l.id);
    }
    // And it solves: newton under 10 N down on D, every cable of D taut.
    let sol = newton(&s, &s.unit_load);
    assert!(sol.equilibrium.slack[..3].iter().all(|&x| !x));
}

#[test]
fn self_stress_prestress_refusals_exit_2_naming_the_key() {
    let from = |member: &str, force: &str| {
        format!("from = \"self-stress\"\nmember = {member}\nforce = {force}")
    };
    // (extra members, member 11's prestress in the table, [prestress] body, key, also said)
    let cases: [(&str, f64, String, &str, &str); 7] = [
        // A second self-stress state: a cable from D to node 6.
        (
            "30,0,6,cable,1e11,1e-4,0\n",
            0.0,
            from("10", "1000.0"),
            "prestress.from",
            "s = 2",
        ),
        ("", 0.0, from("99", "1000.0"), "prestress.member", "99"),
        // E is determinate: the state is zero on its members.
        ("", 0.0, from("20", "1000.0"), "prestress.member", "zero"),
        ("", 5.0, from("10", "1000.0"), "prestress.from", "member 11"),
        // Tension in the bar compresses the three cables.
        (
            "",
            0.0,
            from("13", "3000.0"),
            "prestress.force",
            "member 10 (-1000 N)",
        ),
        (
            "",
            0.0,
            "member = 10".to_string(),
            "prestress.member",
            "from = \"self-stress\"",
        ),
        ("", 0.0, from("10", "0.0"), "prestress.force", "non-zero"),
    ];
    for (i, (extra, p11, prestress, key, said)) in cases.iter().enumerate() {
        let dir = self_stress_case(&format!("self-stress-bad-{i}"), extra, *p11, prestress);
        let out = tensolve(&["check", dir.0.join("case.toml").to_str().unwrap()]);
        let err = common::stderr(&out);
        assert_eq!(out.status.code(), Some(2), "case {i}: {err}");
        assert!(err.contains(key), "case {i}: {err}");
        assert!(err.contains(said), "case {i}: {err}");
    }
    // A grid's prestress is `lower_cable`; and `[prestress]` still refuses unknown keys.
    for (body, key) in [
        (
            "from = \"self-stress\"\nmember = 0\nforce = 1.0",
            "prestress.from",
        ),
        ("form = \"self-stress\"", "form"),
    ] {
        let text =
            format!("[grid]\nmodules = [2, 2]\n[prestress]\n{body}\n[load]\nalpha = [1.0]\n");
        let err = case::parse(&text).expect_err(body).to_string();
        assert!(err.contains(key), "{err}");
    }
    // A mechanism (E held by two members only): refused with m.
    let dir = Temp::dir("self-stress-mechanism");
    std::fs::create_dir_all(&dir.0).unwrap();
    let (nodes, members) = self_stress_tables("", 0.0);
    let members: String = members
        .lines()
        .filter(|l| !l.starts_with("22,"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.0.join("nodes.csv"), nodes).unwrap();
    std::fs::write(dir.0.join("members.csv"), members).unwrap();
    std::fs::write(
        dir.0.join("case.toml"),
        "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n\
         [[supports.fix]]\nnodes = [1, 2, 3, 4, 6]\n\
         [prestress]\nfrom = \"self-stress\"\nmember = 10\nforce = 1000.0\n\
         [load]\nalpha = [1.0]\n[model]\ngeometry = \"linear\"\n",
    )
    .unwrap();
    let out = tensolve(&["check", dir.0.join("case.toml").to_str().unwrap()]);
    let err = common::stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("prestress.from") && err.contains("m = 1"),
        "{err}"
    );
}

#[test]
fn latin_partitions_down_to_one_module_agree_on_partial_supports_and_a_settlement() {
    let s = perturbed_held(true);
    assert!(s.prescribed.iter().any(|&u| u == -0.003));
    let (f, reference) = five_percent_slack(&s);
    let scale = max_abs(&reference.equilibrium.displacements);
    let model = Model::linear(s.clone());
    for subdomains in [[1, 1], [2, 2], [3, 3]] {
        let settings = LatinSettings {
            subdomains,
            tolerance: 1e-9,
            // micro-macro's r(U) floors near 2.5e-8 on one-module substructures, with or
            // without partial supports (2.4e-8 on this grid clamped on both edges).
            residual_tolerance: Some(1e-7),
            ..LatinSettings::default()
        };
        let mut latin = Latin::new(&model, settings).unwrap();
        let sol = latin.solve(&f, None, &mut Silent);
        assert_latin_agrees(&sol, &reference, subdomains, 1e-6 * scale);
    }
}

/// A LATIN solve on `subdomains` converged to `reference`'s slack set and displacements, to
/// `tolerance` (m) in every component.
fn assert_latin_agrees(
    sol: &Solution,
    reference: &Solution,
    subdomains: [usize; 2],
    tolerance: f64,
) {
    assert!(
        sol.info.status.converged(),
        "LATIN {subdomains:?}: {:?}",
        sol.info
    );
    assert_eq!(
        sol.equilibrium.slack, reference.equilibrium.slack,
        "LATIN {subdomains:?}"
    );
    let d = max_abs_diff(
        &sol.equilibrium.displacements,
        &reference.equilibrium.displacements,
    );
    println!(
        "LATIN {subdomains:?}: {} iterations, max |ΔU| = {d:e} (tolerance {tolerance:e})",
        sol.info.iterations
    );
    assert!(d <= tolerance, "LATIN {subdomains:?}: {d} vs {tolerance}");
}

#[test]
fn check_counts_partly_held_nodes_and_settlements() {
    // skew-grid: 5 nodes held on all three components, 5 vertically only (one of which
    // settles by 5 mm).
    let case = common::manifest_path("cases/skew-grid.toml");
    let o = common::tensolve(&["check", case.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.lines().any(|l| l.starts_with("held nodes")
            && l.contains(" 5 (all three components), 5 on some components; 1 prescribed")),
        "{text}"
    );
    assert!(text
        .lines()
        .any(|l| l.starts_with("free dofs") && l.ends_with(" 259")));
}
