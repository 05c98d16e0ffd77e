//! Where the case loader's files come from. Normally the disk; on MPI ranks other than 0 the
//! bytes rank 0 read, so that every rank parses the same case and tables whatever its file
//! system holds (issue 25: ranks can never disagree on the case). The loader reads through
//! `read_text` only, which consults the source of the calling thread.

use super::{Case, CaseError};
use std::cell::RefCell;
use std::path::{Path, PathBuf};

/// One read of the loader: the path and what came of it (the text, or why it was refused).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadRecord {
    /// The path as the loader asked for it.
    pub path: PathBuf,
    /// The text read, or the reason the read was refused (as the error would say it).
    pub outcome: Result<String, String>,
}

/// The source of the calling thread's reads.
enum Source {
    Disk,
    Recording(Vec<ReadRecord>),
    Replaying(std::vec::IntoIter<ReadRecord>),
}

thread_local! {
    static SOURCE: RefCell<Source> = const { RefCell::new(Source::Disk) };
}

/// `read` from the disk, or the next record when replaying; recorded when recording.
pub(super) fn read_through(
    path: &Path,
    read: impl FnOnce() -> Result<String, String>,
) -> Result<String, String> {
    let replayed = SOURCE.with_borrow_mut(|source| match source {
        Source::Replaying(records) => Some(match records.next() {
            Some(record) if record.path == path => record.outcome,
            _ => Err("rank 0 did not read this file (the ranks' case loading differs)".into()),
        }),
        _ => None,
    });
    if let Some(outcome) = replayed {
        return outcome;
    }
    let outcome = read();
    SOURCE.with_borrow_mut(|source| {
        if let Source::Recording(records) = source {
            records.push(ReadRecord {
                path: path.to_path_buf(),
                outcome: outcome.clone(),
            });
        }
    });
    outcome
}

/// Run `load` with `source` as the thread's source, then restore the disk.
fn with_source<T>(source: Source, load: impl FnOnce() -> T) -> (T, Source) {
    SOURCE.with_borrow_mut(|s| *s = source);
    let out = load();
    let used = SOURCE.with_borrow_mut(|s| std::mem::replace(s, Source::Disk));
    (out, used)
}

/// [`super::load_with`] from the disk, with every file it read recorded.
pub fn load_recording(
    path: &Path,
    overrides: &[String],
) -> (Result<Case, CaseError>, Vec<ReadRecord>) {
    let (case, used) = with_source(Source::Recording(Vec::new()), || {
        super::load_with(path, overrides)
    });
    let records = match used {
        Source::Recording(records) => records,
        _ => Vec::new(),
    };
    (case, records)
}

/// [`super::load_with`] reading nothing from the disk: each file's text (or refusal) comes from
/// `records`, in the order [`load_recording`] read them.
pub fn load_replaying(
    path: &Path,
    overrides: &[String],
    records: Vec<ReadRecord>,
) -> Result<Case, CaseError> {
    with_source(Source::Replaying(records.into_iter()), || {
        super::load_with(path, overrides)
    })
    .0
}

/// The records as bytes (to send them to other ranks): per record the path, an ok/refused
/// flag and the text or reason, each length-prefixed.
pub fn encode(records: &[ReadRecord]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut put = |bytes: &[u8]| {
        out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        out.extend_from_slice(bytes);
    };
    for r in records {
        put(r.path.as_os_str().as_encoded_bytes());
        match &r.outcome {
            Ok(text) => {
                put(b"ok");
                put(text.as_bytes());
            }
            Err(reason) => {
                put(b"refused");
                put(reason.as_bytes());
            }
        }
    }
    out
}

/// The records [`encode`] wrote; `None` for bytes it cannot have written.
pub fn decode(mut bytes: &[u8]) -> Option<Vec<ReadRecord>> {
    let mut take = || -> Option<Vec<u8>> {
        let (len, rest) = bytes.split_at_checked(8)?;
        let len = usize::try_from(u64::from_le_bytes(len.try_into().ok()?)).ok()?;
        let (field, rest) = rest.split_at_checked(len)?;
        bytes = rest;
        Some(field.to_vec())
    };
    let mut records = Vec::new();
    while let Some(path) = take() {
        let path = PathBuf::from(String::from_utf8(path).ok()?);
        let flag = take()?;
        let text = String::from_utf8(take()?).ok()?;
        let outcome = match flag.as_slice() {
            b"ok" => Ok(text),
            b"refused" => Err(text),
            _ => return None,
        };
        records.push(ReadRecord { path, outcome });
    }
    Some(records)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A case with a members table, loaded by replay in a directory where nothing exists,
    /// is the case loaded from the disk; a refusal replays as the same message.
    #[test]
    fn replay_gives_the_disk_case_and_the_disk_refusal() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let path = root.join("cases/prism4.toml");
        let (disk, records) = load_recording(&path, &[]);
        let disk = disk.expect("the shipped case loads");
        assert!(
            records.len() >= 2,
            "the case file and its tables: {records:?}"
        );
        let decoded = decode(&encode(&records)).expect("round trip");
        assert_eq!(decoded, records);
        let replayed = load_replaying(&path, &[], decoded).expect("replayed");
        assert_eq!(format!("{:?}", replayed), format!("{:?}", disk));

        let missing = root.join("cases/no-such-case.toml");
        let (refused, records) = load_recording(&missing, &[]);
        let refused = refused.expect_err("no such file").to_string();
        let replayed = load_replaying(&missing, &[], records).expect_err("replayed refusal");
        assert_eq!(replayed.to_string(), refused);
        // Nothing recorded: a replay finds no record and says so.
        let empty = load_replaying(&path, &[], Vec::new()).expect_err("no records");
        assert!(
            empty.to_string().contains("rank 0 did not read this file"),
            "{empty}"
        );
    }
}
