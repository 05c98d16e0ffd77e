//! How numbers read in file names, tables and messages, where more than one layer writes them:
//! the case names its load factors as the output files will, so that two α with one label are
//! refused before anything is solved.

/// Longest α label written out in full; a longer one (1e-250 is 252 characters in full, too
/// long for a file name) is written in exponent form.
const ALPHA_LABEL_MAX: usize = 24;

/// α as it appears in file names: Rust's `{}` for f64 (1 → `1`, 0.05 → `0.05`), or its
/// exponent form (`1e-250`) when that would be longer than 24 characters.
pub fn alpha_label(alpha: f64) -> String {
    let full = format!("{alpha}");
    if full.len() > ALPHA_LABEL_MAX {
        format!("{alpha:e}")
    } else {
        full
    }
}
