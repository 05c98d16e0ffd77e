//! What a sparse Cholesky factor of a stiffness takes, estimated before anything is allocated
//! (the memory estimate of `tensolve check` and the refusal before a run).

/// Entries of a sparse Cholesky factor per dof and per `log2(dofs)` under nested dissection:
/// 124 M entries on 256 × 256 modules (592 899 dofs, log2 = 19.2) is 10.9.
pub const FACTOR_ENTRIES_PER_DOF_LOG2: f64 = 11.0;

/// Bytes per factor entry: the value (8) and the supernodal structure's indices and workspace
/// (peak RSS of `newton` minus that of `pcg-lcp`, one factor apart, is 9.5 bytes per entry on
/// 64 × 64 to 256 × 256 grids; rounded up).
pub const BYTES_PER_FACTOR_ENTRY: f64 = 10.0;

/// Fill of the minimum-degree ordering against nested dissection (194 M against 124 M
/// entries on 256 × 256 modules), for `check`'s rank factorization. The solvers' factors use
/// minimum degree only below 512 free nodes (it was 10 000 when the formula was calibrated,
/// and it still bounded what was measured there, up to 56 × 56 modules), so they are all
/// counted as nested dissection.
pub const AMD_FILL_RATIO: f64 = 1.6;

/// Bytes of one sparse Cholesky factor of a stiffness on `dofs` dofs: `11 · d · log2(d)`
/// entries of 10 bytes (nested dissection), [`AMD_FILL_RATIO`] times that with `amd`.
pub fn factor_bytes(dofs: usize, amd: bool) -> u64 {
    let d = dofs.max(2) as f64;
    let entries = FACTOR_ENTRIES_PER_DOF_LOG2 * d * d.log2();
    let fill = if amd { AMD_FILL_RATIO } else { 1.0 };
    (fill * entries * BYTES_PER_FACTOR_ENTRY) as u64
}
