//! Why a case cannot be used: every message names the key (or the line and column), the value
//! and the fix.

use thiserror::Error;

/// Why a case cannot be used. Displayed messages are meant for the user as they are.
#[derive(Debug, Error)]
pub enum CaseError {
    /// The file cannot be read.
    #[error("cannot read {what} `{path}`: {reason}")]
    Io {
        /// What the file is: `case file`, `nodes table`, `members table`.
        what: &'static str,
        /// The path as given.
        path: String,
        /// The operating system's reason.
        reason: String,
    },
    /// Not TOML, an unknown key, or a value of the wrong type (toml's message, with line and
    /// column).
    #[error("case file is not valid: {0}")]
    Syntax(String),
    /// A row of a `[structure]` table that cannot be used.
    #[error("{file}, line {line}, column `{column}`: `{value}` is not valid: {fix}")]
    Table {
        /// The table's path, as resolved from the case file.
        file: String,
        /// The line (1-based; the header is line 1).
        line: u64,
        /// The column's name (or `header`, `row`).
        column: String,
        /// The value as written.
        value: String,
        /// What is wrong and how to fix it.
        fix: String,
    },
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
        key: String,
        /// The value, as a user would write it.
        value: String,
        /// What is allowed.
        fix: String,
    },
    /// The case needs more memory than this process may use (estimated before allocating).
    #[error(
        "the case is too large for the memory available: `{command}` needs {estimate}; \
         {available} is available. Use fewer modules (`grid.modules`), fewer solvers \
         (`solver.methods` or `--solver`) or fewer outputs (`output.stability`, \
         `output.compare_modules`; with LATIN solvers alone and `solver.reference = \"none\"`, \
         `output.geometric_term = false` frees K's factor), or run where more memory is available"
    )]
    TooLarge {
        /// What would need the memory (`run`, `check`, `bench`, or loading the case).
        command: String,
        /// The estimate, by part.
        estimate: String,
        /// What is available, and which limit says so.
        available: String,
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

    /// The value of `key` is refused: `fix` says what is allowed.
    pub(crate) fn invalid(
        key: impl Into<String>,
        value: impl ToString,
        fix: impl Into<String>,
    ) -> Self {
        CaseError::Invalid {
            key: key.into(),
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
