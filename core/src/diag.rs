//! Problems found while loading user data: each one says where (file, line, column) and what.

pub mod codes;

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

    /// The location of byte `offset` of `text` (the file's end past it), in `file`.
    pub fn at_offset(file: &Path, text: &str, offset: usize) -> Self {
        let (line, column) = line_col(text, offset);
        Self::new(file, line, column)
    }

    /// The location of the `nth` occurrence (from 0) of `needle` in `text`, else the
    /// file's start.
    pub fn of_nth(file: &Path, text: &str, needle: &str, nth: usize) -> Self {
        text.match_indices(needle).nth(nth).map_or_else(
            || Self::new(file, 1, 1),
            |(off, _)| Self::at_offset(file, text, off),
        )
    }
}

/// 1-based line and column (in characters) of a byte offset of `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or("");
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |p| p + 1);
    let column = before.get(line_start..).unwrap_or("").chars().count() + 1;
    (line, column)
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
    /// A stable code of the registry [`codes`], e.g. `V0103` (page `docs/codes/V0103.md`).
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

/// Largest file a plant loader reads (RON files, `constraints.txt`, `invariants.txt`,
/// scenarios), bytes: the committed files are a few tens of KiB, so the limit only
/// stops a wrong file (a trace, a dump, `/dev/zero`) before it fills the memory.
pub const MAX_FILE_BYTES: u64 = 8 * 1024 * 1024;

/// A `V0003` problem: `path` holds `size` bytes, more than [`MAX_FILE_BYTES`] (`None`:
/// a file whose size is not known, read up to the limit).
fn too_large(path: &Path, size: Option<u64>) -> Problem {
    let limit = format!(
        "the limit of {MAX_FILE_BYTES} bytes ({} MiB)",
        MAX_FILE_BYTES / 1_048_576
    );
    let message = match size {
        Some(size) => format!(
            "{} is {size} bytes ({:.1} MiB), more than {limit}: not read",
            path.display(),
            size as f64 / 1_048_576.0,
        ),
        None => format!("{} holds more than {limit}: not read", path.display()),
    };
    Problem::error(codes::FILE_TOO_LARGE.id, message, None)
}

fn cannot_read(path: &Path, e: &dyn std::fmt::Display) -> Problem {
    Problem::error(
        codes::FILE_UNREADABLE.id,
        format!("cannot read {}: {e}", path.display()),
        None,
    )
}

/// Checks the size of `path` before it is read: more than [`MAX_FILE_BYTES`] is a
/// `V0003` problem naming the file, its size and the limit; a device, a pipe or a
/// socket (which may never end, or block the open) is a `V0002` problem. A file that
/// cannot be looked at passes (its reader reports why).
pub fn check_size(path: &Path) -> Result<(), Problem> {
    match std::fs::metadata(path) {
        Ok(m) if m.len() > MAX_FILE_BYTES => Err(too_large(path, Some(m.len()))),
        Ok(m) if !m.is_file() && !m.is_dir() => Err(cannot_read(
            path,
            &"not a regular file (a device, a pipe or a socket)",
        )),
        _ => Ok(()),
    }
}

/// Reads a text file in bounded memory: its size is checked first ([`check_size`],
/// `V0003`), and the read stops after [`MAX_FILE_BYTES`] whatever the file says (a
/// device or a file that grows). Any other failure, invalid UTF-8 included, is a
/// `V0002` problem naming the file.
pub fn read_text(path: &Path) -> Result<String, Problem> {
    use std::io::Read as _;
    check_size(path)?;
    let file = std::fs::File::open(path).map_err(|e| cannot_read(path, &e))?;
    let mut bytes = Vec::new();
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| cannot_read(path, &e))?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large(path, None));
    }
    String::from_utf8(bytes).map_err(|e| cannot_read(path, &e))
}

/// As [`read_text`], `None` when the file does not exist.
pub fn read_text_optional(path: &Path) -> Result<Option<String>, Problem> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        _ => read_text(path).map(Some),
    }
}

/// Converts a `ron` parse error into a problem at its file position.
pub fn ron_problem(file: &Path, err: &ron::error::SpannedError) -> Problem {
    Problem::error(
        codes::RON_INVALID.id,
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

/// A field of a RON text (`name: value`) and where its value is written, so that a
/// semantic check can point at the value it rejects (serde gives no positions).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RonField {
    /// The field name.
    pub name: String,
    /// Names of the fields whose values hold this one, outermost first (`["signals"]`
    /// for the `id` of a signal in `plant.ron`).
    pub path: Vec<String>,
    /// Byte offset of the bracket that opens the struct holding the field: the fields
    /// of one struct share it.
    pub container: usize,
    /// Byte range of the value as written (`Ms(50)` in `lo: Ms(50),`).
    pub value: std::ops::Range<usize>,
    /// Line of the value's first character, from 1.
    pub line: usize,
    /// Column of the value's first character, in characters, from 1.
    pub column: usize,
}

impl RonField {
    /// Where the value is written, in `file`.
    pub fn location(&self, file: &Path) -> Location {
        Location::new(file, self.line, self.column)
    }

    /// Whether the field sits at `path` (names of the enclosing fields, outermost first).
    pub fn is_at(&self, path: &[&str]) -> bool {
        self.path.len() == path.len() && self.path.iter().zip(path).all(|(a, b)| a == b)
    }
}

/// The `nth` (from 0) field called `name` at `path` in `fields`.
pub fn ron_field<'a>(
    fields: &'a [RonField],
    path: &[&str],
    name: &str,
    nth: usize,
) -> Option<&'a RonField> {
    fields
        .iter()
        .filter(|f| f.name == name && f.is_at(path))
        .nth(nth)
}

/// The fields of a RON text in the order they are written. The scan knows strings, raw
/// strings, characters and nested comments; it does not validate (the parser does),
/// and on a text the parser would reject it returns what it could see, never panics.
pub fn ron_fields(text: &str) -> Vec<RonField> {
    let b = text.as_bytes();
    let mut out: Vec<RonField> = Vec::new();
    let mut stack = vec![Open { at: 0, field: None }];
    // The field whose value has not started yet, and the end of the last token.
    let mut awaiting: Option<usize> = None;
    let mut last_end = 0;
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        // Whitespace and comments are not tokens.
        let ws = whitespace_len(b, i);
        if ws > 0 {
            i += ws;
            continue;
        }
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            i = skip_line_comment(b, i);
            continue;
        }
        if c == b'/' && b.get(i + 1) == Some(&b'*') {
            i = skip_block_comment(b, i);
            continue;
        }
        let start = i;
        if let Some(k) = awaiting.take()
            && let Some(f) = out.get_mut(k)
        {
            f.value = start..start;
        }
        match c {
            b'"' => i = skip_string(b, i + 1),
            b'\'' => i = skip_char(b, i + 1),
            b'r' if raw_string_start(b, i).is_some() => {
                i = skip_raw_string(b, i);
            }
            b'(' | b'[' | b'{' => {
                stack.push(Open { at: i, field: None });
                i += 1;
            }
            b')' | b']' | b'}' => {
                if stack.len() > 1
                    && let Some(mut open) = stack.pop()
                {
                    finish(&mut out, &mut open, last_end);
                }
                i += 1;
            }
            b',' => {
                if let Some(open) = stack.last_mut() {
                    finish(&mut out, open, last_end);
                }
                i += 1;
                last_end = i;
                continue;
            }
            c if c.is_ascii_digit() => i = skip_number(b, i),
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let name_start;
                (name_start, i) = scan_name(b, i);
                let colon = skip_trivia(b, i);
                if b.get(colon) == Some(&b':') && b.get(colon + 1) != Some(&b':') {
                    let path = stack
                        .iter()
                        .take(stack.len() - 1)
                        .filter_map(|o| o.field.and_then(|k| out.get(k)))
                        .map(|f| f.name.clone())
                        .collect();
                    let Some(open) = stack.last_mut() else {
                        break;
                    };
                    finish(&mut out, open, last_end);
                    out.push(RonField {
                        name: text.get(name_start..i).unwrap_or("").to_string(),
                        path,
                        container: open.at,
                        value: colon + 1..colon + 1,
                        line: 0,
                        column: 0,
                    });
                    open.field = Some(out.len() - 1);
                    awaiting = Some(out.len() - 1);
                    i = colon + 1;
                    last_end = i;
                    continue;
                }
            }
            _ => {
                i += text
                    .get(i..)
                    .and_then(|s| s.chars().next())
                    .map_or(1, char::len_utf8);
            }
        }
        last_end = i.min(b.len());
    }
    while let Some(mut open) = stack.pop() {
        finish(&mut out, &mut open, last_end);
    }
    set_lines_and_columns(text, &mut out);
    out
}

/// An open bracket of the RON scan and the field whose value it holds, if any.
struct Open {
    at: usize,
    field: Option<usize>,
}

/// Ends the value of the open field, if any, at the end of the last token.
fn finish(out: &mut [RonField], open: &mut Open, last_end: usize) {
    if let Some(k) = open.field.take()
        && let Some(f) = out.get_mut(k)
    {
        f.value.end = last_end.max(f.value.start);
    }
}

/// Scans an identifier at `i` (a raw `r#name` included): its name's start and its end.
fn scan_name(b: &[u8], i: usize) -> (usize, usize) {
    let c = b[i];
    let mut name_start = i;
    if c == b'r'
        && b.get(i + 1) == Some(&b'#')
        && b.get(i + 2)
            .is_some_and(|&d| d.is_ascii_alphabetic() || d == b'_')
    {
        name_start = i + 2;
    }
    let mut i = name_start;
    while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
        i += 1;
    }
    (name_start, i)
}

/// Lines and columns of the values.
fn set_lines_and_columns(text: &str, out: &mut [RonField]) {
    let line_starts: Vec<usize> = std::iter::once(0)
        .chain(text.match_indices('\n').map(|(k, _)| k + 1))
        .collect();
    for f in out {
        let line = line_starts.partition_point(|&s| s <= f.value.start);
        let from = line_starts.get(line.wrapping_sub(1)).copied().unwrap_or(0);
        f.line = line.max(1);
        f.column = text
            .get(from..f.value.start)
            .map_or(0, |s| s.chars().count())
            + 1;
    }
}

fn skip_line_comment(b: &[u8], i: usize) -> usize {
    b[i..]
        .iter()
        .position(|&c| c == b'\n')
        .map_or(b.len(), |k| i + k + 1)
}

/// Past a block comment (RON nests them).
fn skip_block_comment(b: &[u8], mut i: usize) -> usize {
    let mut depth = 0usize;
    while i < b.len() {
        if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
            depth += 1;
            i += 2;
        } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            i += 1;
        }
    }
    b.len()
}

/// Past the closing quote of a string whose content starts at `i`.
fn skip_string(b: &[u8], mut i: usize) -> usize {
    while i < b.len() {
        match b[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    b.len()
}

/// Past the closing quote of a character whose content starts at `i`.
fn skip_char(b: &[u8], mut i: usize) -> usize {
    if b.get(i) == Some(&b'\\') {
        i += 2;
    } else {
        i += 1;
    }
    match b
        .get(i..)
        .and_then(|r| r.iter().position(|&c| c == b'\'' || c == b'\n'))
    {
        Some(k) if b[i + k] == b'\'' => i + k + 1,
        Some(k) => i + k,
        None => b.len(),
    }
}

/// The number of `#` of a raw string `r#"…"#` starting at `i`.
fn raw_string_start(b: &[u8], i: usize) -> Option<usize> {
    if i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_') {
        return None;
    }
    let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
    (b.get(i + 1 + hashes) == Some(&b'"')).then_some(hashes)
}

fn skip_raw_string(b: &[u8], i: usize) -> usize {
    let hashes = raw_string_start(b, i).unwrap_or(0);
    let mut k = i + hashes + 2;
    while k < b.len() {
        if b[k] == b'"'
            && b[k + 1..]
                .iter()
                .take(hashes)
                .filter(|&&c| c == b'#')
                .count()
                == hashes
        {
            return k + 1 + hashes;
        }
        k += 1;
    }
    b.len()
}

fn skip_number(b: &[u8], mut i: usize) -> usize {
    while i < b.len() {
        let c = b[i];
        let exponent_sign = (c == b'+' || c == b'-') && matches!(b[i - 1], b'e' | b'E');
        if c.is_ascii_alphanumeric() || c == b'_' || c == b'.' || exponent_sign {
            i += 1;
        } else {
            break;
        }
    }
    i
}

/// The length in bytes of the whitespace character at `i`, 0 if there is none: RON's
/// whitespace (`ron::parse::is_whitespace_char`), vertical tab, form feed, U+0085,
/// U+200E, U+200F, U+2028 and U+2029 included.
fn whitespace_len(b: &[u8], i: usize) -> usize {
    match b.get(i..).unwrap_or(&[]) {
        [b' ' | b'\t' | b'\n' | b'\r' | 0x0B | 0x0C, ..] => 1,
        [0xC2, 0x85, ..] => 2,
        [0xE2, 0x80, 0x8E | 0x8F | 0xA8 | 0xA9, ..] => 3,
        _ => 0,
    }
}

/// Past whitespace and comments.
fn skip_trivia(b: &[u8], mut i: usize) -> usize {
    loop {
        let ws = whitespace_len(b, i);
        if ws > 0 {
            i += ws;
        } else if b.get(i) == Some(&b'/') && b.get(i + 1) == Some(&b'/') {
            i = skip_line_comment(b, i);
        } else if b.get(i) == Some(&b'/') && b.get(i + 1) == Some(&b'*') {
            i = skip_block_comment(b, i);
        } else {
            return i;
        }
    }
}

#[cfg(test)]
mod tests;
