//! Atomic file replacement: write a temporary file of a random name, created exclusively in
//! the same directory (so it never follows a planted link), flush and sync it, then rename it
//! over `path`.

use std::io::{BufWriter, Write};
use std::path::Path;

/// Create `path` (and its directory) with what `fill` writes, atomically: on error no file
/// replaces `path` and the temporary one is removed.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir)?;
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // `tempfile` opens with O_CREAT | O_EXCL under a random name: no link is followed and no
    // other process can guess or share the name. Dropped on error, the file is removed.
    // Created with mode 0666 less the umask, as `File::create` (and `summary.csv`) would:
    // tempfile's own 0600 made every result file private whatever the umask (issue 57, R5-9).
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{file_name}."))
        .suffix(".tmp")
        .permissions(create_mode())
        .tempfile_in(dir)?;
    let mut w = BufWriter::new(tmp);
    fill(&mut w)?;
    let tmp = w.into_inner().map_err(|e| e.into_error())?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// The mode a new file is created with before the umask: 0666.
fn create_mode() -> std::fs::Permissions {
    use std::os::unix::fs::PermissionsExt;
    std::fs::Permissions::from_mode(0o666)
}

/// Create `dir` and make sure a file can be written in it (a probe file of a random name,
/// removed).
pub fn ensure_writable(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let probe = tempfile::Builder::new()
        .prefix(".tensolve-probe-")
        .tempfile_in(dir)?;
    probe.close()
}
