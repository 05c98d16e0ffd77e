//! `modes/{solver}_alpha{α}.vtu` (`output.modes` with `output.vtk`): the natural modes of one
//! answer for ParaView ("Warp By Vector" on `mode_k`). Points are the nodes where the modes
//! are taken: at `X + U` under `large` (its tangent is the current geometry's), at their
//! initial positions otherwise; point data `mode_1` … `mode_N` (3 components, M-normalised as
//! in `_shapes.csv`, held components 0); cells one line per link with cell data `kind` (as
//! in `vtk/`); field data `alpha` and `frequency_Hz` (N values). A non-finite value is an
//! error, never a file.

use super::vtk::{check_finite, data_array, float, link_code, write_cells};
use super::write_atomic;
use crate::labels::alpha_label;
use crate::model::Model;
use crate::results::modes::NaturalMode;
use crate::structure::CLAMPED;
use std::io;
use std::path::{Path, PathBuf};

/// `modes/{solver}_alpha{α}.vtu` under `dir`.
pub fn modes_vtu_path(dir: &Path, solver: &str, alpha: f64) -> PathBuf {
    dir.join("modes")
        .join(format!("{solver}_alpha{}.vtu", alpha_label(alpha)))
}

/// The nodes where the modes of the answer at displacements `u` (free dofs) are taken: at
/// `X + U` under `large`, at their initial positions otherwise.
pub(super) fn modal_positions(model: &Model, u: &[f64]) -> Vec<[f64; 3]> {
    let s = &model.structure;
    s.nodes
        .iter()
        .enumerate()
        .map(|(node, x)| {
            std::array::from_fn(|c| match s.dof_of[3 * node + c] {
                d if d != CLAMPED && model.updates_geometry() => x[c] + u[d],
                _ => x[c],
            })
        })
        .collect()
}

/// Writes the modes of the answer at displacements `u` (free dofs) into `path`.
pub fn write_modes_vtu(
    path: &Path,
    alpha: f64,
    model: &Model,
    u: &[f64],
    modes: &[NaturalMode],
) -> io::Result<()> {
    let s = &model.structure;
    let on_nodes = |v: &[f64]| -> Vec<f64> {
        s.dof_of
            .iter()
            .map(|&d| if d == CLAMPED { 0.0 } else { v[d] })
            .collect()
    };
    let points: Vec<f64> = modal_positions(model, u).into_iter().flatten().collect();
    let shapes: Vec<Vec<f64>> = modes.iter().map(|m| on_nodes(&m.shape)).collect();
    let frequencies: Vec<f64> = modes.iter().map(|m| m.frequency_hz).collect();
    check_finite("node position", &points)?;
    check_finite("frequency", &frequencies)?;
    for shape in &shapes {
        check_finite("mode shape", shape)?;
    }
    write_atomic(path, |w| {
        writeln!(w, r#"<?xml version="1.0"?>"#)?;
        writeln!(
            w,
            r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
        )?;
        writeln!(w, "<UnstructuredGrid>\n<FieldData>")?;
        writeln!(
            w,
            r#"<DataArray type="Float64" Name="alpha" NumberOfTuples="1" format="ascii">{}</DataArray>"#,
            float(&alpha)
        )?;
        let listed: Vec<String> = frequencies.iter().map(float).collect();
        writeln!(
            w,
            r#"<DataArray type="Float64" Name="frequency_Hz" NumberOfTuples="{}" format="ascii">{}</DataArray>"#,
            listed.len(),
            listed.join(" ")
        )?;
        writeln!(w, "</FieldData>")?;
        super::vtk::piece_start(w, s)?;
        writeln!(w, "<PointData>")?;
        for (i, shape) in shapes.iter().enumerate() {
            data_array(
                w,
                "Float64",
                &format!("mode_{}", i + 1),
                3,
                shape.iter().map(float),
            )?;
        }
        writeln!(w, "</PointData>\n<CellData>")?;
        let kinds = (0..s.links.len()).map(|i| link_code(s, i).to_string());
        data_array(w, "Int32", "kind", 1, kinds)?;
        writeln!(w, "</CellData>\n<Points>")?;
        data_array(w, "Float64", "position", 3, points.iter().map(float))?;
        writeln!(w, "</Points>")?;
        write_cells(w, s)?;
        writeln!(w, "</Piece>\n</UnstructuredGrid>\n</VTKFile>")
    })
}
