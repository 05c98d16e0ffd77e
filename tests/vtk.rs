//! `[output] vtk = true`: one VTK XML unstructured grid per solver and α whose points, cells
//! and data are the structure's and the solve's (checked against the CSV files of the same
//! run); a non-finite value is an error and leaves no file.

mod common;

use common::temp_path;
use std::path::{Path, PathBuf};
use tensolve::app::sweep::{run, RunOptions};
use tensolve::case::Case;
use tensolve::output::{kind_code, link_code, write_vtu, VTK_LINE};
use tensolve::solvers::Equilibrium;
use tensolve::structure::LinkKind;

const CASE: &str = "[grid]\nmodules = [4, 4]\n[load]\nalpha = [1.0, 30.0]\n\
                    [solver]\nmethods = [\"newton\", \"mono-latin\", \"micro-macro\"]\n\
                    subdomains = [2, 2]\n[output]\nvtk = true\n";

struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn case() -> Case {
    tensolve::case::parse(CASE).expect("valid case")
}

fn numbers<T: std::str::FromStr>(node: roxmltree::Node) -> Vec<T>
where
    T::Err: std::fmt::Debug,
{
    node.text()
        .unwrap_or("")
        .split_whitespace()
        .map(|w| w.parse().expect("a number"))
        .collect()
}

fn data_array<'a>(doc: &'a roxmltree::Document, name: &str) -> roxmltree::Node<'a, 'a> {
    doc.descendants()
        .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
        .unwrap_or_else(|| panic!("no DataArray {name}"))
}

/// Column `name` of a CSV file, as numbers.
fn csv_column(path: &Path, name: &str) -> Vec<f64> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let index = reader
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == name)
        .unwrap();
    reader
        .records()
        .map(|r| r.unwrap()[index].parse().unwrap())
        .collect()
}

fn relative_close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-300)
}

#[test]
fn vtu_files_hold_the_structure_and_the_solved_tensions() {
    let case = case();
    let structure = case.structure();
    let out = TempDir(temp_path("vtk"));
    let options = RunOptions {
        out_dir: Some(out.0.clone()),
        methods: None,
    };
    run(&case, &options, &mut |_| {}).expect("every solve converges");

    for solver in ["newton", "mono-latin", "micro-macro"] {
        for alpha in ["1", "30"] {
            let path = out.0.join(format!("vtk/{solver}_alpha{alpha}.vtu"));
            let text = std::fs::read_to_string(&path).unwrap();
            let doc = roxmltree::Document::parse(&text).expect("well-formed XML");
            let root = doc.root_element();
            assert_eq!(root.attribute("type"), Some("UnstructuredGrid"));
            let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
            assert_eq!(piece.attribute("NumberOfPoints"), Some("65"));
            assert_eq!(piece.attribute("NumberOfCells"), Some("256"));
            assert_eq!(structure.n_nodes(), 65);
            assert_eq!(structure.links.len(), 256);

            let points: Vec<f64> = numbers(data_array(&doc, "position"));
            let expected: Vec<f64> = structure.nodes.iter().flatten().copied().collect();
            assert_eq!(points, expected);
            let connectivity: Vec<usize> = numbers(data_array(&doc, "connectivity"));
            let links: Vec<usize> = structure.links.iter().flat_map(|l| [l.a, l.b]).collect();
            assert_eq!(connectivity, links);
            let offsets: Vec<usize> = numbers(data_array(&doc, "offsets"));
            assert_eq!(offsets, (1..=256).map(|i| 2 * i).collect::<Vec<_>>());
            let types: Vec<u8> = numbers(data_array(&doc, "types"));
            assert!(types.iter().all(|&t| t == VTK_LINE));
            // Vectors state their 3 components; scalars leave NumberOfComponents to its
            // default of 1, which meshio reads as shape (n,), not (n, 1).
            for (name, components) in [
                ("position", Some("3")),
                ("displacement", Some("3")),
                ("tension", None),
                ("slack", None),
                ("kind", None),
            ] {
                assert_eq!(
                    data_array(&doc, name).attribute("NumberOfComponents"),
                    components,
                    "{name}"
                );
            }
            let kinds: Vec<i32> = numbers(data_array(&doc, "kind"));
            let expected: Vec<i32> = (0..structure.links.len())
                .map(|i| link_code(&structure, i))
                .collect();
            assert_eq!(kinds, expected);

            // The cables' tensions are those of the tensions CSV of the same solve.
            let tensions: Vec<f64> = numbers(data_array(&doc, "tension"));
            let slack: Vec<u8> = numbers(data_array(&doc, "slack"));
            let cable_tensions: Vec<f64> = tensions
                .iter()
                .zip(&kinds)
                .filter(|(_, &k)| k != kind_code(LinkKind::Bar))
                .map(|(&t, _)| t)
                .collect();
            let csv = csv_column(
                &out.0.join(format!("tensions/{solver}_alpha{alpha}.csv")),
                "tension",
            );
            assert_eq!(cable_tensions.len(), csv.len());
            for (i, (v, c)) in cable_tensions.iter().zip(&csv).enumerate() {
                assert!(
                    relative_close(*v, *c),
                    "{solver} α {alpha} cable {i}: {v} vs {c}"
                );
            }
            let slack_in_csv = csv.iter().filter(|&&t| t == 0.0).count();
            assert_eq!(slack.iter().filter(|&&s| s == 1).count(), slack_in_csv);
            if alpha == "30" {
                assert!(slack_in_csv > 0, "α = 30 has slack cables");
            }

            // Displacements are the displacements CSV's, node by node.
            let u: Vec<f64> = numbers(data_array(&doc, "displacement"));
            let uz = csv_column(
                &out.0
                    .join(format!("displacements/{solver}_alpha{alpha}.csv")),
                "uz",
            );
            for (node, z) in uz.iter().enumerate() {
                assert!(relative_close(u[3 * node + 2], *z), "node {node}");
            }
        }
    }
}

#[test]
fn a_non_finite_value_is_an_error_and_leaves_no_file() {
    let structure = (case()).structure();
    let mut tensions: Vec<f64> = structure.links.iter().map(|l| l.prestress).collect();
    tensions[7] = f64::NAN;
    let eq = Equilibrium {
        displacements: vec![0.0; structure.n_free],
        tensions,
        slack: vec![false; structure.links.len()],
    };
    let out = TempDir(temp_path("vtk-nan"));
    let e = write_vtu(&out.0, "newton", 1.0, &structure, &eq).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
    assert!(e.to_string().contains("tension 7"), "{e}");
    assert!(!out.0.join("vtk/newton_alpha1.vtu").exists());

    let mut eq = eq;
    eq.tensions[7] = 0.0;
    eq.displacements[3] = f64::INFINITY;
    assert!(write_vtu(&out.0, "newton", 1.0, &structure, &eq).is_err());
    assert!(!out.0.join("vtk/newton_alpha1.vtu").exists());
}
