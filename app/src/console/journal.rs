//! The console journal: every event and operator action, appended to disk as it
//! happens (one JSON line per entry, flushed), and exportable to CSV.

use serde::Serialize;
use std::fs::{File, OpenOptions};
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// One journal line.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Entry {
    /// Wall-clock time, ms since the Unix epoch.
    pub wall_ms: u64,
    /// Simulated time, ms.
    pub sim_ms: u64,
    /// `trip`, `reset`, `hazard`, `operator`, `ack`, `shelve`, `fault`…
    pub kind: String,
    /// Text.
    pub text: String,
}

/// The data directory: `VIGIE_DATA_DIR`, else `$XDG_DATA_HOME/vigie`, else
/// `~/.local/share/vigie`, else `./vigie-data`.
pub fn data_dir_from_env() -> PathBuf {
    if let Some(d) = std::env::var_os("VIGIE_DATA_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_DATA_HOME").filter(|d| !d.is_empty()) {
        return PathBuf::from(d).join("vigie");
    }
    if let Some(h) = std::env::var_os("HOME").filter(|d| !d.is_empty()) {
        return PathBuf::from(h).join(".local/share/vigie");
    }
    PathBuf::from("vigie-data")
}

fn wall_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_millis()).unwrap_or(u64::MAX))
}

/// The journal: in memory for display, on disk append-only.
pub struct Journal {
    entries: Vec<Entry>,
    /// Keep the entries in memory (the console shows them; a headless run does not).
    keep: bool,
    file: Option<File>,
    path: Option<PathBuf>,
    /// The last write error, shown in the status bar.
    pub error: Option<String>,
}

impl Journal {
    /// A journal writing to `dir/journal.jsonl` (appending to an existing file), or
    /// memory only when `dir` is `None`.
    pub fn open(dir: Option<&Path>) -> Self {
        let mut j = Self {
            entries: Vec::new(),
            keep: true,
            file: None,
            path: None,
            error: None,
        };
        if let Some(dir) = dir {
            let path = dir.join("journal.jsonl");
            match std::fs::create_dir_all(dir)
                .and_then(|()| OpenOptions::new().create(true).append(true).open(&path))
            {
                Ok(f) => {
                    j.file = Some(f);
                    j.path = Some(path);
                }
                Err(e) => j.error = Some(format!("journal {}: {e}", path.display())),
            }
        }
        j
    }

    /// A journal appending to `dir/journal.jsonl` that keeps nothing in memory (a
    /// headless service running for months); fails when the file cannot be opened.
    pub fn append_only(dir: &Path) -> std::io::Result<Self> {
        let j = Self::open(Some(dir));
        match (&j.file, &j.error) {
            (Some(_), _) => Ok(Self { keep: false, ..j }),
            (None, e) => Err(std::io::Error::other(e.clone().unwrap_or_default())),
        }
    }

    /// The file written, if any.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// Appends one entry and writes it to disk at once.
    pub fn push(&mut self, sim_ms: u64, kind: &str, text: &str) {
        let e = Entry {
            wall_ms: wall_ms(),
            sim_ms,
            kind: kind.to_string(),
            text: text.to_string(),
        };
        if let Some(f) = &mut self.file {
            let line = serde_json::to_string(&e).unwrap_or_default();
            if let Err(err) = writeln!(f, "{line}").and_then(|()| f.flush()) {
                self.error = Some(format!("journal write: {err}"));
            }
        }
        if self.keep {
            self.entries.push(e);
        }
    }

    /// Entries, oldest first.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// The journal as CSV (`wall_ms,sim_ms,kind,text`).
    pub fn to_csv(&self) -> String {
        let mut s = String::from("wall_ms,sim_ms,kind,text\n");
        for e in &self.entries {
            s.push_str(&format!(
                "{},{},{},\"{}\"\n",
                e.wall_ms,
                e.sim_ms,
                e.kind,
                e.text.replace('"', "\"\"")
            ));
        }
        s
    }

    /// Writes the CSV export to `path`.
    pub fn export_csv(&self, path: &Path) -> std::io::Result<()> {
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent)?;
        }
        std::fs::write(path, self.to_csv())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_reach_the_disk_at_once() {
        let dir = std::env::temp_dir().join(format!("vigie-journal-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut j = Journal::open(Some(&dir));
        j.push(10, "ack", "alarm 1 acknowledged: \"checked\"");
        let text = std::fs::read_to_string(dir.join("journal.jsonl")).unwrap();
        assert!(text.contains("\"kind\":\"ack\""));
        assert!(j.to_csv().contains("\"\"checked\"\""));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
