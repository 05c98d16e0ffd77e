//! `homogenised/substructure_{E}.csv`: the paper's "second-hand product" (its conclusion), one
//! file per substructure with macro dofs: row i describes macro dof i (the interface it lives
//! on, the substructure across it, its macro field and the interface's centroid) and holds row
//! i of the homogenised flexibility `L_E = K⁺_E − I/d_m` (m/N) in columns `L_0 … L_{m−1}`.

use super::write_atomic;
use crate::decomposition::Homogenised;
use std::io;
use std::path::{Path, PathBuf};

/// The path of substructure `index`'s file under `dir`.
pub fn homogenised_path(dir: &Path, index: usize) -> PathBuf {
    dir.join("homogenised")
        .join(format!("substructure_{index}.csv"))
}

/// Write one file per substructure that has macro dofs; returns their paths.
pub fn write_homogenised(dir: &Path, substructures: &[Homogenised]) -> io::Result<Vec<PathBuf>> {
    substructures
        .iter()
        .filter(|h| !h.dofs.is_empty())
        .map(|h| {
            let path = homogenised_path(dir, h.substructure);
            if let Some(bad) = h.flexibility.iter().find(|v| !v.is_finite()) {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("L_E of substructure {} has {bad}", h.substructure),
                ));
            }
            write_atomic(&path, |w| {
                let mut out = csv::Writer::from_writer(w);
                let m = h.dofs.len();
                let mut header: Vec<String> = [
                    "macro_dof",
                    "interface",
                    "neighbour",
                    "field",
                    "centroid_x",
                    "centroid_y",
                    "centroid_z",
                ]
                .iter()
                .map(|s| s.to_string())
                .collect();
                header.extend((0..m).map(|j| format!("L_{j}")));
                out.write_record(&header).map_err(io::Error::other)?;
                for (i, dof) in h.dofs.iter().enumerate() {
                    let mut row = vec![
                        i.to_string(),
                        dof.interface.to_string(),
                        dof.neighbour.to_string(),
                        dof.field.clone(),
                    ];
                    row.extend(dof.centroid.iter().map(|c| c.to_string()));
                    row.extend((0..m).map(|j| format!("{:e}", h.flexibility[(i, j)])));
                    out.write_record(&row).map_err(io::Error::other)?;
                }
                out.flush()
            })?;
            Ok(path)
        })
        .collect()
}
