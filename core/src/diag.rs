//! Problems found while loading user data: each one says where (file, line, column) and what.

use serde::Serialize;
use std::path::{Path, PathBuf};

/// A position in a text file, 1-based.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub struct Location {
    /// The file, as given to the loader.
    pub file: PathBuf,
    /// Line, starting at 1.
    pub line: usize,
    /// Column in characters, starting at 1.
    pub column: usize,
}

impl Location {
    /// A location in `file`.
    pub fn new(file: &Path, line: usize, column: usize) -> Self {
        Self {
            file: file.to_path_buf(),
            line,
            column,
        }
    }
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.column)
    }
}

/// How bad a problem is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// The data cannot be used as it is.
    Error,
    /// The data can be used but something looks wrong.
    Warning,
}

/// One problem found by a loader or a static check.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Problem {
    /// Error or warning.
    pub severity: Severity,
    /// A stable code, e.g. `V0103`, documented in `ARCHITECTURE.md`.
    pub code: &'static str,
    /// Human-readable message, lowercase, no trailing period.
    pub message: String,
    /// Where, when the problem is tied to a place in a file.
    pub location: Option<Location>,
}

impl Problem {
    /// An error at `location`.
    pub fn error(
        code: &'static str,
        message: impl Into<String>,
        location: Option<Location>,
    ) -> Self {
        Self {
            severity: Severity::Error,
            code,
            message: message.into(),
            location,
        }
    }

    /// A warning at `location`.
    pub fn warning(
        code: &'static str,
        message: impl Into<String>,
        location: Option<Location>,
    ) -> Self {
        Self {
            severity: Severity::Warning,
            code,
            message: message.into(),
            location,
        }
    }

    /// True for errors.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let sev = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        match &self.location {
            Some(loc) => write!(f, "{loc}: {sev}[{}]: {}", self.code, self.message),
            None => write!(f, "{sev}[{}]: {}", self.code, self.message),
        }
    }
}

/// Reads a text file; a failure is a `V0002` problem naming the file.
pub fn read_text(path: &Path) -> Result<String, Problem> {
    std::fs::read_to_string(path).map_err(|e| {
        Problem::error(
            "V0002",
            format!("cannot read {}: {e}", path.display()),
            None,
        )
    })
}

/// Converts a `ron` parse error into a problem at its file position.
pub fn ron_problem(file: &Path, err: &ron::error::SpannedError) -> Problem {
    Problem::error(
        "V0001",
        format!("invalid RON: {}", err.code),
        Some(Location::new(file, err.span.start.line, err.span.start.col)),
    )
}

/// Renders a list of problems, one per line.
pub fn render(problems: &[Problem]) -> String {
    problems
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("\n")
}
