//! Why a case cannot be used: every message names the key (or the line and column), the value
//! and the fix.

use thiserror::Error;

/// Why a case cannot be used. Displayed messages are meant for the user as they are.
#[derive(Debug, Error)]
pub enum CaseError {
    /// The file cannot be read.
    #[error("cannot read case file `{path}`: {reason}")]
    Io {
        /// The path as given.
        path: String,
        /// The operating system's reason.
        reason: String,
    },
    /// Not TOML, an unknown key, or a value of the wrong type (toml's message, with line and
    /// column).
    #[error("case file is not valid: {0}")]
    Syntax(String),
    /// A command-line override (`--set key=value`) that cannot be applied or is not valid.
    #[error("--set {set}: {reason}")]
    Override {
        /// The override as given.
        set: String,
        /// What is wrong with it, and the fix.
        reason: String,
    },
    /// A value out of its range.
    #[error("`{key}` = {value} is not valid: {fix}")]
    Invalid {
        /// The key, as written in the file.
        key: &'static str,
        /// The value, as a user would write it.
        value: String,
        /// What is allowed.
        fix: String,
    },
}

impl CaseError {
    pub(crate) fn from_toml(e: toml::de::Error) -> Self {
        // toml's message already has the line, the column, the offending text and, for
        // unknown keys or variants, the allowed names; keep it on one line per fact.
        let text = e.to_string();
        let lines: Vec<String> = text.trim_end().lines().map(shorten).collect();
        CaseError::Syntax(lines.join("\n"))
    }

    pub(super) fn invalid(key: &'static str, value: impl ToString, fix: impl Into<String>) -> Self {
        CaseError::Invalid {
            key,
            value: shorten(&value.to_string()),
            fix: fix.into(),
        }
    }
}

/// Longest text of a value (or of a line of toml's message) echoed in a message.
const ECHO_MAX_CHARS: usize = 120;

/// `text`, cut to [`ECHO_MAX_CHARS`] characters with a note of its length.
fn shorten(text: &str) -> String {
    let count = text.chars().count();
    if count <= ECHO_MAX_CHARS {
        return text.to_string();
    }
    let head: String = text.chars().take(ECHO_MAX_CHARS).collect();
    format!("{head}… ({count} characters)")
}
