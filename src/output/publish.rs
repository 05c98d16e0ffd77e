//! The commit protocol of an output directory. One run at a time writes into a directory (a
//! lock); a solve's files are written into a private staging directory and published together
//! at one commit point, before its `summary.csv` row; a manifest lists what the run wrote, so
//! the next run removes exactly that, when it opens the directory, and leaves every other file
//! alone. Removal never follows a link: an entry is removed only through real directories, and
//! a link is removed itself, never its target.
//!
//! | file | what |
//! |---|---|
//! | `.tensolve.lock` | locked (`flock`) while a run writes; released when the process ends, even killed |
//! | `.tensolve-manifest` | one relative path per line: the files the last run published |
//! | `.tensolve-staging-*` | the current solve's files until they are published; removed after |

use std::collections::BTreeSet;
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{self, Read, Write};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Component, Path, PathBuf};

use super::sinks::WriteError;

/// The lock file's name.
pub const LOCK_FILE: &str = ".tensolve.lock";
/// The manifest's name.
pub const MANIFEST_FILE: &str = ".tensolve-manifest";
/// The prefix of the staging directories' names.
const STAGING_PREFIX: &str = ".tensolve-staging-";
/// The largest manifest read back (a longer one is not ours, and is left alone).
const MANIFEST_MAX_BYTES: u64 = 64 << 20;

/// Why an output directory cannot be opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// Another run holds the directory's lock.
    #[error(
        "output directory `{}` is in use by another tensolve run (it holds `{LOCK_FILE}`): wait \
         for that run to end, or pass `--out` with another directory",
        dir.display()
    )]
    Busy {
        /// The directory.
        dir: PathBuf,
    },
    /// The lock's name is taken by a link (not followed).
    #[error(
        "`{}` is a link, not tensolve's lock file: it is not followed; remove it (`rm {}`) and \
         run again",
        lock.display(),
        lock.display()
    )]
    LockIsLink {
        /// The lock's path.
        lock: PathBuf,
    },
    /// The directory cannot be created, locked or written.
    #[error("output directory `{}` is not writable ({source})", dir.display())]
    Io {
        /// The directory.
        dir: PathBuf,
        /// Why.
        source: io::Error,
    },
}

/// A line-per-solve file (`summary.csv`, `stability.csv`): created whole at its first row,
/// then appended to through the handle it was created with (never reopened by name).
struct Ledger {
    file: File,
    /// Its length after the last whole row: a failed append is cut back to it.
    len: u64,
}

/// What the current solve has made visible, so that it can be withdrawn whole.
#[derive(Default)]
struct SolveRecord {
    /// The files its commit published, under their final names.
    files: Vec<PathBuf>,
    /// The ledgers it appended a row to, with each one's length before that row (`None`: the
    /// row created the ledger).
    rows: Vec<(PathBuf, Option<u64>)>,
}

/// An output directory opened for one run: locked, with a private staging directory.
pub struct OutputDir {
    root: PathBuf,
    /// Held for the run's life; the OS releases it when the process ends.
    _lock: File,
    staging: Option<tempfile::TempDir>,
    manifest: File,
    ledgers: std::collections::BTreeMap<PathBuf, Ledger>,
    published: BTreeSet<PathBuf>,
    /// The current solve's published files and rows (since its commit).
    solve: SolveRecord,
}

/// Create `root` if needed and lock it for this process (`.tensolve.lock`, released when the
/// process ends, even killed): refused as [`OpenError::Busy`] while another `run` or `bench`
/// holds it. The lock is held as long as the returned file.
pub fn lock_directory(root: &Path) -> Result<File, OpenError> {
    let io_err = |source| OpenError::Io {
        dir: root.to_path_buf(),
        source,
    };
    std::fs::create_dir_all(root).map_err(io_err)?;
    // O_NOFOLLOW: a link planted under the lock's name is refused, never followed (opening
    // through it would create a file at its target).
    let lock = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .custom_flags(libc::O_NOFOLLOW)
        .open(root.join(LOCK_FILE))
        .map_err(|e| match e.raw_os_error() {
            Some(libc::ELOOP) => OpenError::LockIsLink {
                lock: root.join(LOCK_FILE),
            },
            _ => io_err(e),
        })?;
    match lock.try_lock() {
        Ok(()) => Ok(lock),
        Err(TryLockError::WouldBlock) => Err(OpenError::Busy {
            dir: root.to_path_buf(),
        }),
        Err(TryLockError::Error(e)) => Err(io_err(e)),
    }
}

impl OutputDir {
    /// Create `root` if needed, lock it (refused when another run holds it), remove the
    /// staging directories of a killed run, create this run's staging directory, and remove
    /// what the previous run published (before anything of this run is written: a run that
    /// fails, or is killed, leaves nothing of another that would look like its own), then
    /// start a new, empty manifest.
    pub fn open(root: &Path) -> Result<OutputDir, OpenError> {
        let io_err = |source| OpenError::Io {
            dir: root.to_path_buf(),
            source,
        };
        let lock = lock_directory(root)?;
        remove_stale_staging(root).map_err(io_err)?;
        let staging = tempfile::Builder::new()
            .prefix(STAGING_PREFIX)
            .tempdir_in(root)
            .map_err(io_err)?;
        remove_previous(root, read_manifest(&root.join(MANIFEST_FILE))).map_err(io_err)?;
        // Created exclusively in the staging directory and renamed into place: a planted
        // link of the manifest's name is replaced, never written through. The old manifest
        // stays until every file it lists is gone, so a kill above loses none of them.
        let manifest = staging.path().join(MANIFEST_FILE);
        let file = OpenOptions::new()
            .append(true)
            .create_new(true)
            .open(&manifest)
            .map_err(io_err)?;
        std::fs::rename(&manifest, root.join(MANIFEST_FILE)).map_err(io_err)?;
        Ok(OutputDir {
            root: root.to_path_buf(),
            _lock: lock,
            staging: Some(staging),
            manifest: file,
            ledgers: Default::default(),
            published: BTreeSet::new(),
            solve: SolveRecord::default(),
        })
    }

    /// The directory the results go to.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Where the current solve's files are written (same relative paths as under
    /// [`root`](Self::root)); nothing there is visible until [`commit`](Self::commit).
    pub fn staging(&self) -> &Path {
        self.staging.as_ref().expect("staging until finish").path()
    }

    /// Publish every staged file under its final name. On error, the files this commit had
    /// already published are removed again: a solve is published whole or not at all.
    pub fn commit(&mut self) -> Result<(), WriteError> {
        self.solve = SolveRecord::default();
        let staging = self.staging().to_path_buf();
        let staged = staged_files(&staging).map_err(WriteError::at(&staging))?;
        if staged.is_empty() {
            return Ok(());
        }
        let manifest = self.root.join(MANIFEST_FILE);
        self.record(&staged).map_err(WriteError::at(&manifest))?;
        let mut done: Vec<PathBuf> = Vec::new();
        // A failure names the file under its final name (issue 13, M3), not the directory.
        let result = staged.iter().try_for_each(|rel| {
            let to = self.root.join(rel);
            ensure_real_dir(&self.root, rel).map_err(WriteError::at(&to))?;
            std::fs::rename(staging.join(rel), &to).map_err(WriteError::at(&to))?;
            done.push(to);
            Ok(())
        });
        if result.is_err() {
            for path in &done {
                let _ = std::fs::remove_file(path);
            }
            let _ = self.discard();
        } else {
            self.solve.files = done;
        }
        result
    }

    /// Take back what the current solve made visible: the files its commit published and the
    /// ledger rows it appended (a ledger its row created is removed). Called when one of its
    /// rows cannot be written (a full disk, a file-size limit): its files would have no
    /// `summary.csv` row. Best effort: removing needs no space.
    pub fn withdraw(&mut self) {
        let solve = std::mem::take(&mut self.solve);
        for path in &solve.files {
            let _ = std::fs::remove_file(path);
        }
        for (rel, before) in solve.rows.into_iter().rev() {
            match before {
                Some(len) => {
                    if let Some(ledger) = self.ledgers.get_mut(&rel) {
                        if ledger.file.set_len(len).is_ok() {
                            ledger.len = len;
                        }
                    }
                }
                None => {
                    self.ledgers.remove(&rel);
                    let _ = std::fs::remove_file(self.root.join(&rel));
                }
            }
        }
    }

    /// Drop every staged file unpublished (a solve with no finite answer).
    pub fn discard(&mut self) -> io::Result<()> {
        for rel in staged_files(self.staging())? {
            std::fs::remove_file(self.staging().join(rel))?;
        }
        Ok(())
    }

    /// Append `line` to the ledger `rel` (created with `header` at its first row). The row is
    /// one write; a failed write is cut back, so the file always ends with a whole row.
    pub fn append(&mut self, rel: &str, header: &str, line: &str) -> io::Result<()> {
        let rel = PathBuf::from(rel);
        if !self.ledgers.contains_key(&rel) {
            let staged = self.staging().join(&rel);
            let mut file = OpenOptions::new()
                .read(true)
                .append(true)
                .create_new(true)
                .open(&staged)?;
            let text = format!("{header}\n{line}\n");
            file.write_all(text.as_bytes())?;
            file.sync_data()?;
            self.record(std::slice::from_ref(&rel))?;
            std::fs::rename(&staged, self.root.join(&rel))?;
            let len = text.len() as u64;
            self.solve.rows.push((rel.clone(), None));
            self.ledgers.insert(rel, Ledger { file, len });
            return Ok(());
        }
        let ledger = self.ledgers.get_mut(&rel).expect("checked");
        let text = format!("{line}\n");
        match ledger.file.write_all(text.as_bytes()) {
            Ok(()) => {
                self.solve.rows.push((rel, Some(ledger.len)));
                ledger.len += text.len() as u64;
                Ok(())
            }
            Err(e) => {
                let _ = ledger.file.set_len(ledger.len);
                Err(e)
            }
        }
    }

    /// The run ended: sync the ledgers, remove the staging directory. The lock is released
    /// when `self` is dropped.
    pub fn finish(mut self) -> io::Result<()> {
        for ledger in self.ledgers.values() {
            ledger.file.sync_data()?;
        }
        if let Some(staging) = self.staging.take() {
            staging.close()?;
        }
        Ok(())
    }

    /// Write ahead: the manifest names a file before it is published.
    fn record(&mut self, rels: &[PathBuf]) -> io::Result<()> {
        let mut text = String::new();
        for rel in rels {
            if self.published.insert(rel.clone()) {
                text.push_str(&rel.to_string_lossy());
                text.push('\n');
            }
        }
        if text.is_empty() {
            return Ok(());
        }
        let manifest = &mut self.manifest;
        manifest.write_all(text.as_bytes())?;
        manifest.sync_data()
    }
}

/// The relative paths of the files under `dir`.
fn staged_files(dir: &Path) -> io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for entry in std::fs::read_dir(dir.join(&rel))? {
            let entry = entry?;
            let path = rel.join(entry.file_name());
            if entry.file_type()?.is_dir() {
                stack.push(path);
            } else {
                files.push(path);
            }
        }
    }
    files.sort();
    Ok(files)
}

/// Create the directories of `rel` under `root`, refusing a link in their place (a planted
/// link would send the results elsewhere).
fn ensure_real_dir(root: &Path, rel: &Path) -> io::Result<()> {
    let mut dir = root.to_path_buf();
    let Some(parent) = rel.parent() else {
        return Ok(());
    };
    for part in parent.components() {
        dir.push(part);
        match std::fs::symlink_metadata(&dir) {
            Ok(m) if m.is_dir() => {}
            Ok(_) => {
                return Err(io::Error::new(
                    io::ErrorKind::AlreadyExists,
                    format!(
                        "`{}` is not a directory (a link or a file): remove it",
                        dir.display()
                    ),
                ))
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => std::fs::create_dir(&dir)?,
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// The relative paths a manifest lists; a path that could leave the directory (absolute,
/// `..`) or names tensolve's own bookkeeping (`.tensolve*`) is ignored, as is a manifest too
/// large or unreadable.
fn read_manifest(path: &Path) -> Vec<PathBuf> {
    let Ok(file) = File::open(path) else {
        return Vec::new();
    };
    let mut text = String::new();
    if file
        .take(MANIFEST_MAX_BYTES)
        .read_to_string(&mut text)
        .is_err()
    {
        return Vec::new();
    }
    text.lines()
        .map(PathBuf::from)
        .filter(|p| {
            !p.as_os_str().is_empty()
                && p.components().all(|c| matches!(c, Component::Normal(_)))
                && !p.to_string_lossy().starts_with(".tensolve")
        })
        .collect()
}

/// Remove the files the previous run published, `summary.csv` last: at every moment each
/// result file still there has its row (a kill in between leaves rows whose files are gone,
/// never a file without its row).
fn remove_previous(root: &Path, mut previous: Vec<PathBuf>) -> io::Result<()> {
    previous.sort_by_key(|rel| rel == Path::new("summary.csv"));
    let root_dir = File::open(root)?;
    for rel in previous {
        remove_below(&root_dir, &rel)?;
    }
    Ok(())
}

/// Remove `rel` (normal components only) below the directory `root`, without following a
/// link: each directory on the way is opened with `O_NOFOLLOW` relative to the one before
/// (`openat`), so a link or a file in a directory's place ends the walk and the entry is left
/// alone; the entry itself is removed only when it is a regular file or a link (`unlinkat`
/// removes the link, never its target). Race-free: no path is resolved twice.
fn remove_below(root: &File, rel: &Path) -> io::Result<()> {
    use rustix::fs::{openat, statat, unlinkat, AtFlags, FileType, Mode, OFlags};
    use rustix::io::Errno;
    use std::os::fd::AsFd;
    let parts: Vec<&std::ffi::OsStr> = rel.iter().collect();
    let Some((last, dirs)) = parts.split_last() else {
        return Ok(());
    };
    let mut dir: Option<std::os::fd::OwnedFd> = None;
    for part in dirs {
        let flags = OFlags::RDONLY | OFlags::DIRECTORY | OFlags::NOFOLLOW | OFlags::CLOEXEC;
        let opened = match &dir {
            Some(d) => openat(d, *part, flags, Mode::empty()),
            None => openat(root, *part, flags, Mode::empty()),
        };
        match opened {
            Ok(fd) => dir = Some(fd),
            // Gone, a link (ELOOP) or not a directory: nothing of ours below it.
            Err(Errno::NOENT | Errno::LOOP | Errno::NOTDIR) => return Ok(()),
            Err(e) => return Err(e.into()),
        }
    }
    let d = match &dir {
        Some(d) => d.as_fd(),
        None => root.as_fd(),
    };
    // The entry itself, not what a link points to.
    let stat = match statat(d, *last, AtFlags::SYMLINK_NOFOLLOW) {
        Ok(stat) => stat,
        Err(Errno::NOENT) => return Ok(()),
        Err(e) => return Err(e.into()),
    };
    let kind = FileType::from_raw_mode(stat.st_mode);
    if kind != FileType::RegularFile && kind != FileType::Symlink {
        return Ok(());
    }
    // Flags empty: never removes a directory, never follows a link (it removes the link).
    match unlinkat(d, *last, AtFlags::empty()) {
        Ok(()) | Err(Errno::NOENT) => Ok(()),
        Err(e) => Err(e.into()),
    }
}

/// Remove the staging directories a killed run left (only directories: a link of that name is
/// left alone).
fn remove_stale_staging(root: &Path) -> io::Result<()> {
    for entry in std::fs::read_dir(root)? {
        let entry = entry?;
        let stale = entry
            .file_name()
            .to_string_lossy()
            .starts_with(STAGING_PREFIX);
        if stale && entry.file_type()?.is_dir() {
            std::fs::remove_dir_all(entry.path())?;
        }
    }
    Ok(())
}
