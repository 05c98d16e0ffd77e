//! The discrete model of docs/method.md §1–2 on the paper's grid: counts, prestress, supports.

mod common;

use common::{paper_structure, P};
use tensolve::structure::{GridRole, Structure};

fn braced() -> Structure {
    paper_structure(&[("grid", "module", "braced".into())])
}

fn count(s: &Structure, role: GridRole) -> usize {
    (0..s.links.len())
        .filter(|&i| s.grid_role(i) == Some(role))
        .count()
}

#[test]
fn paper_grid_counts() {
    let s = paper_structure(&[]);
    assert_eq!(s.n_nodes(), 833);
    assert_eq!(3 * s.n_nodes(), 2499);
    assert_eq!(s.dof_of.len(), 2499);
    assert_eq!(s.n_free, 2397);
    assert_eq!(s.unit_load.len(), 2397);
    assert_eq!(s.n_cables(), 3072);
    assert_eq!(s.n_bars(), 1024);
}

#[test]
fn braced_grid_counts() {
    let s = braced();
    assert_eq!(s.n_nodes(), 833);
    assert_eq!(s.n_free, 2397);
    assert_eq!(s.n_cables(), 4096);
    assert_eq!(s.n_bars(), 1024);
}

#[test]
fn links_per_kind() {
    let s = paper_structure(&[]);
    for kind in [
        GridRole::LowerCable,
        GridRole::UpperCable,
        GridRole::BracingCable,
        GridRole::Bar,
    ] {
        assert_eq!(count(&s, kind), 1024, "{kind:?}");
    }
    assert_eq!(count(&s, GridRole::DiagonalCable), 0);
    let b = braced();
    for kind in [
        GridRole::LowerCable,
        GridRole::UpperCable,
        GridRole::BracingCable,
        GridRole::DiagonalCable,
        GridRole::Bar,
    ] {
        assert_eq!(count(&b, kind), 1024, "braced {kind:?}");
    }
}

#[test]
fn prestress_is_self_balanced() {
    for (name, s) in [("standard", paper_structure(&[])), ("braced", braced())] {
        let imbalance = s.prestress_imbalance();
        assert!(
            imbalance < 1e-9 * P,
            "{name}: max |B^T t0| = {imbalance:e} N"
        );
    }
}

/// docs/method.md §2's table: t0 per link kind, for module side `l` and height `h`.
fn expected_prestress(role: GridRole, l: f64, h: f64) -> f64 {
    let r = 4.0 * h * h / (l * l);
    match role {
        GridRole::LowerCable => P,
        GridRole::UpperCable => 2f64.sqrt() * P,
        GridRole::BracingCable => (1.0 + r).sqrt() * P,
        GridRole::Bar => -(5.0 + r).sqrt() * P,
        GridRole::DiagonalCable => 0.0,
    }
}

fn assert_prestress_table(s: &Structure, l: f64, h: f64) {
    for (i, link) in s.links.iter().enumerate() {
        let role = s.grid_role(i).expect("a grid's links have a role");
        let want = expected_prestress(role, l, h);
        assert!(
            (link.prestress - want).abs() <= 1e-12 * P,
            "link {i} ({role:?}): t0 = {} N, docs/method.md §2 says {want} N",
            link.prestress
        );
    }
}

#[test]
fn prestress_matches_spec_table() {
    assert_prestress_table(&paper_structure(&[]), 1.0, 0.5);
    assert_prestress_table(&braced(), 1.0, 0.5);
}

/// H/L ≠ 1/2 separates the bracing cables' √(1 + 4H²/L²) p from the upper cables' √2 p.
#[test]
fn prestress_matches_spec_table_other_geometry() {
    let s = paper_structure(&[
        ("grid", "length", 1.5.into()),
        ("grid", "height", 0.3.into()),
        ("grid", "module", "braced".into()),
    ]);
    assert_prestress_table(&s, 1.5, 0.3);
    assert!(s.prestress_imbalance() < 1e-9 * P);
}

#[test]
fn clamped_nodes_per_support_option() {
    for (clamp, expected) in [
        ("lower-x-edges", 34),
        ("lower-y-edges", 34),
        ("lower-all-edges", 64),
        ("lower-corners", 4),
        ("none", 0),
    ] {
        let s = paper_structure(&[("supports", "clamp", clamp.into())]);
        let clamped: Vec<usize> = (0..s.n_nodes()).filter(|&n| s.clamped[n]).collect();
        assert_eq!(clamped.len(), expected, "clamp = {clamp}");
        assert_eq!(s.n_free, 3 * (833 - expected), "clamp = {clamp}");
        for &n in &clamped {
            assert_eq!(
                s.nodes[n][2], 0.0,
                "clamp = {clamp}: node {n} is not a lower node"
            );
        }
    }
}

#[test]
fn paper_supports_are_the_x_edges() {
    let s = paper_structure(&[]);
    for (n, x) in s.nodes.iter().enumerate() {
        let on_edge = x[2] == 0.0 && (x[0] == 0.0 || x[0] == 16.0);
        assert_eq!(s.clamped[n], on_edge, "node {n} at {x:?}");
    }
}
