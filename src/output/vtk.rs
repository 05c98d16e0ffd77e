//! `vtk/{solver}_alpha{α}.vtu`: one solve as a VTK XML unstructured grid (ASCII), ready for
//! ParaView ("Warp By Vector" on `displacement`).
//!
//! Points are the nodes at their initial positions (m), with point data `displacement` (m,
//! 3 components, zero on clamped nodes). Cells are one `VTK_LINE` (type 3) per link, bars and
//! cables, in the order of the structure's links, with cell data `tension` (total τ = t0 + t,
//! N), `kind` (Int32, see [`kind_code`]) and `slack` (UInt8: 1 for a slack cable, else 0).
//! Field data `alpha` holds the load factor. A non-finite value is an error, never a file.

use super::write_atomic;
use crate::labels::alpha_label;
use crate::solvers::Equilibrium;
use crate::structure::{GridRole, LinkKind, Structure};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// VTK's cell type of a two-node line.
pub const VTK_LINE: u8 = 3;

/// The `kind` code of link `i` of `s` in the VTU files: 0 lower cable, 1 upper cable, 2
/// bracing cable, 3 diagonal cable (braced module), 4 bar, 5 cable of a general structure. A
/// grid's link has the code of its [`GridRole`], a general structure's that of its kind.
pub fn link_code(s: &Structure, i: usize) -> i32 {
    match s.grid_role(i) {
        Some(GridRole::LowerCable) => 0,
        Some(GridRole::UpperCable) => 1,
        Some(GridRole::BracingCable) => 2,
        Some(GridRole::DiagonalCable) => 3,
        Some(GridRole::Bar) => kind_code(LinkKind::Bar),
        None => kind_code(s.links[i].kind),
    }
}

/// The `kind` code of a general structure's link in the VTU files ([`link_code`]): 4 bar, 5
/// cable.
pub fn kind_code(kind: LinkKind) -> i32 {
    match kind {
        LinkKind::Bar => 4,
        LinkKind::Cable => 5,
    }
}

/// Path `dir/vtk/{solver}_alpha{α}.vtu` of a solve's VTU file.
pub fn vtu_path(dir: &Path, solver: &str, alpha: f64) -> PathBuf {
    dir.join("vtk")
        .join(format!("{solver}_alpha{}.vtu", alpha_label(alpha)))
}

/// Write the VTU file of one solve; refuses (InvalidData) when a value is not finite.
pub fn write_vtu(
    dir: &Path,
    solver: &str,
    alpha: f64,
    s: &Structure,
    eq: &Equilibrium,
) -> io::Result<PathBuf> {
    let displacements = s.full_displacements(&eq.displacements);
    let points: Vec<f64> = s.nodes.iter().flatten().copied().collect();
    check_finite("alpha", &[alpha])?;
    check_finite("node position", &points)?;
    check_finite("displacement", &displacements)?;
    check_finite("tension", &eq.tensions)?;
    let path = vtu_path(dir, solver, alpha);
    write_atomic(&path, |w| {
        write_grid(w, alpha, s, eq, &points, &displacements)
    })?;
    Ok(path)
}

pub(super) fn check_finite(what: &str, values: &[f64]) -> io::Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "{what} {i} is {} (not finite): no VTU file written",
                values[i]
            ),
        )),
    }
}

fn write_grid(
    w: &mut dyn Write,
    alpha: f64,
    s: &Structure,
    eq: &Equilibrium,
    points: &[f64],
    displacements: &[f64],
) -> io::Result<()> {
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
    )?;
    writeln!(w, "<UnstructuredGrid>")?;
    writeln!(w, "<FieldData>")?;
    writeln!(
        w,
        r#"<DataArray type="Float64" Name="alpha" NumberOfTuples="1" format="ascii">{}</DataArray>"#,
        float(&alpha)
    )?;
    writeln!(w, "</FieldData>")?;
    piece_start(w, s)?;
    writeln!(w, r#"<PointData Vectors="displacement">"#)?;
    data_array(
        w,
        "Float64",
        "displacement",
        3,
        displacements.iter().map(float),
    )?;
    writeln!(w, "</PointData>")?;
    writeln!(w, r#"<CellData Scalars="tension">"#)?;
    data_array(w, "Float64", "tension", 1, eq.tensions.iter().map(float))?;
    let kinds = (0..s.links.len()).map(|i| link_code(s, i).to_string());
    data_array(w, "Int32", "kind", 1, kinds)?;
    let slack = eq.slack.iter().map(|&b| u8::from(b).to_string());
    data_array(w, "UInt8", "slack", 1, slack)?;
    writeln!(w, "</CellData>")?;
    writeln!(w, "<Points>")?;
    data_array(w, "Float64", "position", 3, points.iter().map(float))?;
    writeln!(w, "</Points>")?;
    write_cells(w, s)?;
    writeln!(w, "</Piece>")?;
    writeln!(w, "</UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

/// `<Piece …>` of `s`: a point per node, a cell per link.
pub(super) fn piece_start(w: &mut dyn Write, s: &Structure) -> io::Result<()> {
    writeln!(
        w,
        r#"<Piece NumberOfPoints="{}" NumberOfCells="{}">"#,
        s.n_nodes(),
        s.links.len()
    )
}

pub(super) fn write_cells(w: &mut dyn Write, s: &Structure) -> io::Result<()> {
    writeln!(w, "<Cells>")?;
    let connectivity = s
        .links
        .iter()
        .flat_map(|l| [l.a, l.b])
        .map(|n| n.to_string());
    data_array(w, "Int64", "connectivity", 1, connectivity)?;
    let offsets = (1..=s.links.len()).map(|i| (2 * i).to_string());
    data_array(w, "Int64", "offsets", 1, offsets)?;
    let types = s.links.iter().map(|_| VTK_LINE.to_string());
    data_array(w, "UInt8", "types", 1, types)?;
    writeln!(w, "</Cells>")
}

/// Shortest text that reads back to the same f64.
pub(super) fn float(x: &f64) -> String {
    format!("{x:e}")
}

/// One ASCII `DataArray`, one tuple per line. A scalar array leaves `NumberOfComponents` to
/// its default of 1: readers such as meshio turn an explicit 1 into an (n, 1) array.
pub(super) fn data_array(
    w: &mut dyn Write,
    vtk_type: &str,
    name: &str,
    components: usize,
    values: impl Iterator<Item = String>,
) -> io::Result<()> {
    let components_attribute = match components {
        1 => String::new(),
        n => format!(r#" NumberOfComponents="{n}""#),
    };
    writeln!(
        w,
        r#"<DataArray type="{vtk_type}" Name="{name}"{components_attribute} format="ascii">"#
    )?;
    for (i, v) in values.enumerate() {
        let sep = if (i + 1) % components == 0 { "\n" } else { " " };
        write!(w, "{v}{sep}")?;
    }
    writeln!(w, "</DataArray>")
}
