//! The console's journal, alarm history and process history, kept in the historian
//! (`vigie.sqlite` in the data folder, shared with the gateway: see
//! [`crate::historian`]).
//!
//! Entries are collected during a frame and committed together, durably, by
//! [`Journal::commit`], which the console calls at the end of every command, every
//! batch of cycles and every frame, before anything is drawn. The process history
//! (every change of every signal) and the alarms' states go through the historian's
//! writer thread, so a frame never waits on them.

use crate::historian::writer::{Msg, ProcessRecorder, Writer, cycle_values, signal_names};
use crate::historian::{AlarmRow, HistorianError, Retention, Store, wall_ms};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use vigie_core::alarms::{Alarm, AlarmList};
use vigie_core::history::CycleRecord;
use vigie_core::symbols::Symbols;

pub use crate::historian::JournalRow as Entry;

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

/// The historian side of the journal.
struct Persist {
    store: Store,
    session: i64,
    writer: Writer,
    recorder: ProcessRecorder,
    /// Wall-clock time of simulated time 0 of the current run, ms.
    base_ms: u64,
    /// The last time stamped, ms (a restart of the emulator starts after it).
    last_ms: u64,
    /// What was last written of each alarm: acknowledged, cleared, shelved until.
    alarms: BTreeMap<u64, (bool, bool, Option<u64>)>,
}

/// The journal: shown in the console, committed to the historian.
pub struct Journal {
    entries: Vec<Entry>,
    /// Index of the first entry not yet committed.
    committed: usize,
    persist: Option<Persist>,
    /// The last error of the historian, shown in the status bar.
    pub error: Option<String>,
}

impl Journal {
    /// A journal in memory only (tests, or no data folder).
    pub fn memory() -> Self {
        Self {
            entries: Vec::new(),
            committed: 0,
            persist: None,
            error: None,
        }
    }

    /// A journal committed to `dir/vigie.sqlite` as a new console session of `plant`,
    /// with the process history of `symbols`' signals. An earlier `journal.jsonl` in
    /// `dir` is imported first. When the historian cannot be opened the journal stays
    /// in memory and says why in [`Journal::error`].
    pub fn open(dir: Option<&Path>, plant: &str, symbols: &Symbols) -> Self {
        let mut j = Self::memory();
        if let Some(dir) = dir {
            match Self::persist(dir, plant, symbols) {
                Ok(p) => j.persist = Some(p),
                Err(e) => j.error = Some(format!("journal in memory only: {e}")),
            }
        }
        j
    }

    fn persist(dir: &Path, plant: &str, symbols: &Symbols) -> Result<Persist, HistorianError> {
        let mut store = Store::open_in(dir)?;
        let old = dir.join("journal.jsonl");
        if old.exists() {
            store.import_jsonl(&old, "console")?;
        }
        // Simulated time runs ahead of the clock at a high speed: the run starts after
        // whatever an earlier session stamped.
        let base_ms = wall_ms().max(store.latest_ms()? + 1);
        let session = store.begin_session("console", plant, base_ms)?;
        let names = signal_names(symbols);
        let writer = Writer::start(Store::open_in(dir)?, session, &names, Retention::default())?;
        Ok(Persist {
            store,
            session,
            writer,
            recorder: ProcessRecorder::new(names.len()),
            base_ms,
            last_ms: base_ms,
            alarms: BTreeMap::new(),
        })
    }

    /// The database written, if any.
    pub fn path(&self) -> Option<&Path> {
        self.persist.as_ref().map(|p| p.store.path())
    }

    /// The historian, to read trends and past entries.
    pub fn store(&self) -> Option<&Store> {
        self.persist.as_ref().map(|p| &p.store)
    }

    /// The time stamped on simulated time `sim_ms` of the current run, ms: the run's
    /// start (the clock, or after an earlier session's last stamp) plus `sim_ms`.
    pub fn wall_of(&self, sim_ms: u64) -> u64 {
        self.persist
            .as_ref()
            .map_or_else(wall_ms, |p| p.base_ms + sim_ms)
    }

    /// Adds one entry; it is committed by the next [`Journal::commit`].
    pub fn push(&mut self, sim_ms: u64, kind: &str, text: &str) {
        self.push_coded(sim_ms, kind, text, "", BTreeMap::new());
    }

    /// Adds one entry with the message that tells it in another language (`code`, a
    /// message id) and its fields.
    pub fn push_coded(
        &mut self,
        sim_ms: u64,
        kind: &str,
        text: &str,
        code: &str,
        fields: BTreeMap<String, String>,
    ) {
        let wall_ms = self.wall_of(sim_ms);
        self.entries.push(Entry {
            wall_ms,
            sim_ms,
            kind: kind.to_string(),
            text: text.to_string(),
            code: code.to_string(),
            fields,
        });
    }

    /// Commits the entries added since the last commit in one durable transaction.
    /// On failure they stay pending (retried at the next commit) and the error is
    /// shown; nothing is dropped.
    pub fn commit(&mut self) {
        let Some(p) = &mut self.persist else {
            self.committed = self.entries.len();
            return;
        };
        if let Some(e) = p.writer.take_error() {
            self.error = Some(e);
        }
        if self.committed == self.entries.len() {
            return;
        }
        match p
            .store
            .append_journal(p.session, &self.entries[self.committed..])
        {
            Ok(()) => self.committed = self.entries.len(),
            Err(e) => self.error = Some(format!("journal not saved yet: {e}")),
        }
    }

    /// Records one cycle of the process history.
    pub fn record_cycle(&mut self, rec: &CycleRecord) {
        let Some(p) = &mut self.persist else { return };
        let t = p.base_ms + rec.time.0;
        p.last_ms = p.last_ms.max(t);
        p.recorder.record(t, cycle_values(rec));
        if let Some(batch) = p.recorder.take_due(t, 1000) {
            p.writer.send(Msg::Samples(batch));
        }
    }

    /// The emulator restarts at simulated time 0: the run goes on after the last time
    /// stamped, and every value is recorded again.
    pub fn restart_run(&mut self) {
        let Some(p) = &mut self.persist else { return };
        if let Some(batch) = p.recorder.take_due(u64::MAX, 0) {
            p.writer.send(Msg::Samples(batch));
        }
        p.base_ms = wall_ms().max(p.last_ms + 1);
        p.recorder.restart();
    }

    /// Writes the alarms that changed since the last call to the alarm history.
    pub fn sync_alarms(&mut self, alarms: &AlarmList) {
        let Some(p) = &mut self.persist else { return };
        let mut rows = Vec::new();
        for a in alarms.all() {
            let print = (
                a.acknowledged.is_some(),
                a.cleared.is_some(),
                a.shelving.as_ref().map(|s| s.until.0),
            );
            if p.alarms.get(&a.id) != Some(&print) {
                p.alarms.insert(a.id, print);
                rows.push(alarm_row(a, p.base_ms));
            }
        }
        if !rows.is_empty() {
            p.writer.send(Msg::Alarms(rows));
        }
    }

    /// Hands the pending process history to the writer and waits (at most 10 s) for
    /// it to be committed; false if it was not.
    pub fn flush_history(&mut self) -> bool {
        self.commit();
        let Some(p) = &mut self.persist else {
            return true;
        };
        if let Some(batch) = p.recorder.take_due(u64::MAX, 0) {
            p.writer.send(Msg::Samples(batch));
        }
        p.writer.flush(std::time::Duration::from_secs(10))
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
        write_export(path, &self.to_csv())
    }
}

/// Writes an export to `path`, creating its folder.
pub fn write_export(path: &Path, text: &str) -> std::io::Result<()> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)?;
    }
    std::fs::write(path, text)
}

impl Drop for Journal {
    fn drop(&mut self) {
        self.flush_history();
    }
}

fn alarm_row(a: &Alarm, base_ms: u64) -> AlarmRow {
    AlarmRow {
        alarm: a.id,
        key: a.key.clone(),
        kind: a.kind.name().to_string(),
        priority: format!("{:?}", a.priority()).to_lowercase(),
        message: a.message.clone(),
        detail: a.detail.clone(),
        raised_ms: base_ms + a.raised.0,
        acked: a
            .acknowledged
            .as_ref()
            .map(|(t, n)| (base_ms + t.0, n.clone())),
        cleared_ms: a.cleared.map(|t| base_ms + t.0),
        shelved: a
            .shelving
            .as_ref()
            .map(|s| (base_ms + s.until.0, s.reason.clone())),
        first_out: a.first_out,
        code: a.code.to_string(),
        fields: a.fields.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_are_committed_together_and_survive_a_reopen() {
        let dir = std::env::temp_dir().join(format!("vigie-journal-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let symbols = Symbols::new();
        let mut j = Journal::open(Some(&dir), "station", &symbols);
        assert_eq!(j.error, None);
        j.push(10, "ack", "alarm 1 acknowledged: \"checked\"");
        j.push(11, "trip", "CSs10");
        assert!(
            Store::open_in(&dir)
                .unwrap()
                .journal(0, "", 10)
                .unwrap()
                .is_empty(),
            "nothing before the commit"
        );
        j.commit();
        let rows = Store::open_in(&dir).unwrap().journal(0, "", 10).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].kind, "ack");
        assert!(j.to_csv().contains("\"\"checked\"\""));
        drop(j);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
