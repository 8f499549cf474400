//! The historian: one SQLite database per data folder (`vigie.sqlite`) holding the
//! journal, the alarm history and the process history of every signal, shared by the
//! console and the headless gateway (each run is a session with its source).
//!
//! - **Durable commits**: WAL with `synchronous = FULL`; a journal entry is shown on
//!   screen or printed on stdout only after the transaction that holds it committed, so
//!   a kill -9 loses no entry anyone saw.
//! - **Process history**: one row per change of a signal (`samples`, keyed by signal and
//!   time), written in batches by a thread of its own ([`writer`]); a trend query over
//!   any range returns at most a given number of buckets ([`Store::trend`]).
//! - **Retention**: rows older than the [`Retention`] are deleted when the store opens
//!   and every hour of a run.
//!
//! Times are wall-clock milliseconds since the Unix epoch; the emulator's rows are
//! stamped with the session's start plus simulated time.

pub mod writer;

use rusqlite::{Connection, OptionalExtension as _, params};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The database file in a data folder.
pub const FILE: &str = "vigie.sqlite";

/// The schema version this build writes (`PRAGMA user_version`).
const SCHEMA_VERSION: i64 = 2;

const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS sessions(
    id INTEGER PRIMARY KEY,
    source TEXT NOT NULL,
    plant TEXT NOT NULL,
    started_ms INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS journal(
    id INTEGER PRIMARY KEY,
    session INTEGER NOT NULL,
    wall_ms INTEGER NOT NULL,
    sim_ms INTEGER NOT NULL,
    kind TEXT NOT NULL,
    text TEXT NOT NULL,
    code TEXT NOT NULL DEFAULT '',
    fields TEXT NOT NULL DEFAULT ''
);
CREATE INDEX IF NOT EXISTS journal_time ON journal(wall_ms);
CREATE TABLE IF NOT EXISTS alarms(
    session INTEGER NOT NULL,
    alarm INTEGER NOT NULL,
    key TEXT NOT NULL,
    kind TEXT NOT NULL,
    priority TEXT NOT NULL,
    message TEXT NOT NULL,
    detail TEXT NOT NULL,
    raised_ms INTEGER NOT NULL,
    acked_ms INTEGER,
    ack_note TEXT,
    cleared_ms INTEGER,
    shelved_until_ms INTEGER,
    shelve_reason TEXT,
    first_out INTEGER NOT NULL,
    code TEXT NOT NULL DEFAULT '',
    fields TEXT NOT NULL DEFAULT '',
    PRIMARY KEY(session, alarm)
);
CREATE INDEX IF NOT EXISTS alarms_time ON alarms(raised_ms);
CREATE TABLE IF NOT EXISTS signals(
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE
);
CREATE TABLE IF NOT EXISTS samples(
    signal INTEGER NOT NULL,
    t_ms INTEGER NOT NULL,
    value INTEGER NOT NULL,
    PRIMARY KEY(signal, t_ms)
) WITHOUT ROWID;
";

/// What can go wrong with the historian.
#[derive(Debug, thiserror::Error)]
pub enum HistorianError {
    /// The folder or the file cannot be opened or created.
    #[error("historian {}: {source}", path.display())]
    Open {
        /// The database file.
        path: PathBuf,
        /// Why.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A statement failed.
    #[error("historian {}: {source}", path.display())]
    Sql {
        /// The database file.
        path: PathBuf,
        /// SQLite's error.
        source: rusqlite::Error,
    },
    /// The file was written by a newer Vigie.
    #[error(
        "historian {}: schema version {found}, this Vigie knows up to {SCHEMA_VERSION} (a newer Vigie wrote it; nothing was changed)",
        path.display()
    )]
    Newer {
        /// The database file.
        path: PathBuf,
        /// Its version.
        found: i64,
    },
}

pub use vigie_core::live::config::Retention;

/// A journal entry's fields as stored: JSON, empty for none.
fn encode_fields(fields: &BTreeMap<String, String>) -> String {
    if fields.is_empty() {
        String::new()
    } else {
        serde_json::to_string(fields).unwrap_or_default()
    }
}

/// A journal entry's fields as stored; what is not a JSON object of strings reads as
/// none (the entry keeps its text).
fn decode_fields(text: &str) -> BTreeMap<String, String> {
    serde_json::from_str(text).unwrap_or_default()
}

/// One journal entry.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct JournalRow {
    /// Wall-clock time, ms since the Unix epoch.
    pub wall_ms: u64,
    /// Time of the run (simulated or since the link started), ms.
    pub sim_ms: u64,
    /// `trip`, `reset`, `hazard`, `operator`, `ack`, `shelve`, `fault`…
    pub kind: String,
    /// Text (English, the record).
    pub text: String,
    /// The id of the message that tells the text in another language (`journal-trip`,
    /// `alarm-hazard`…; empty when none), with its fields.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub code: String,
    /// See `code`.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub fields: BTreeMap<String, String>,
}

/// One alarm as the history keeps it (its latest state).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AlarmRow {
    /// The alarm's number in its session.
    pub alarm: u64,
    /// Its condition (`trip:CSs10`, `link:peer`).
    pub key: String,
    /// Its kind (`trip`, `task`…).
    pub kind: String,
    /// `urgent`, `high` or `medium`.
    pub priority: String,
    /// The operator's text.
    pub message: String,
    /// The engineer's detail.
    pub detail: String,
    /// Wall-clock times, ms.
    pub raised_ms: u64,
    /// Acknowledged when, with what note.
    pub acked: Option<(u64, String)>,
    /// Cleared when.
    pub cleared_ms: Option<u64>,
    /// Shelved until when, why.
    pub shelved: Option<(u64, String)>,
    /// First alarm of the event that stopped the plant.
    pub first_out: bool,
    /// What the message says as data (the alarm's code, `trip`, `hazard`…; empty when
    /// none), to show it in another language.
    pub code: String,
    /// See `code`.
    pub fields: BTreeMap<String, String>,
}

/// One change of a signal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// The signal's id in [`Store::signal_ids`].
    pub signal: i64,
    /// Wall-clock time, ms.
    pub t_ms: u64,
    /// The new value.
    pub value: i64,
}

/// One bucket of a trend.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TrendBucket {
    /// Time of the bucket's first change, ms.
    pub first_ms: u64,
    /// Time of its last change, ms.
    pub last_ms: u64,
    /// Changes in the bucket.
    pub changes: u64,
    /// Smallest and largest value taken in the bucket.
    pub min: i64,
    /// See `min`.
    pub max: i64,
    /// The value after the bucket's last change.
    pub last: i64,
}

/// A signal's history over a range, in at most the buckets asked for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Trend {
    /// The value at the start of the range (the last change before it), if any.
    pub before: Option<i64>,
    /// The changes in the range, bucketed, in time order.
    pub buckets: Vec<TrendBucket>,
}

impl Trend {
    /// Points of a step line from `from_ms` to `to_ms` (ms, value): each change is a
    /// vertical step, and a bucket whose value went both ways is drawn as a bar
    /// from its smallest to its largest value.
    pub fn steps(&self, from_ms: u64, to_ms: u64) -> Vec<(u64, i64)> {
        let mut pts = Vec::with_capacity(self.buckets.len() * 4 + 2);
        let mut v = self.before;
        if let Some(v) = v {
            pts.push((from_ms, v));
        }
        for b in &self.buckets {
            if let Some(prev) = v {
                pts.push((b.first_ms, prev));
            }
            if b.min != b.max {
                pts.push((b.first_ms, b.min));
                pts.push((b.first_ms, b.max));
                pts.push((b.last_ms, b.min));
                pts.push((b.last_ms, b.max));
            }
            pts.push((b.last_ms, b.last));
            v = Some(b.last);
        }
        if let Some(v) = v {
            pts.push((to_ms, v));
        }
        pts
    }
}

/// Rows deleted by [`Store::purge`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Purged {
    /// Samples.
    pub samples: u64,
    /// Journal entries.
    pub journal: u64,
    /// Alarms.
    pub alarms: u64,
}

/// The current wall-clock time, ms since the Unix epoch.
pub fn wall_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_millis()).unwrap_or(u64::MAX))
}

const DAY_MS: u64 = 86_400_000;

fn to_i64(v: u64) -> i64 {
    i64::try_from(v).unwrap_or(i64::MAX)
}

fn to_u64(v: i64) -> u64 {
    u64::try_from(v).unwrap_or(0)
}

/// A connection to the historian.
pub struct Store {
    conn: Connection,
    path: PathBuf,
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Store").field("path", &self.path).finish()
    }
}

impl Store {
    /// Opens (creating it if needed) `dir/vigie.sqlite`.
    pub fn open_in(dir: &Path) -> Result<Self, HistorianError> {
        std::fs::create_dir_all(dir).map_err(|e| HistorianError::Open {
            path: dir.join(FILE),
            source: Box::new(e),
        })?;
        Self::open(&dir.join(FILE))
    }

    /// Opens (creating it if needed) the database at `path`: WAL, durable commits, a
    /// busy timeout for the other process sharing it.
    pub fn open(path: &Path) -> Result<Self, HistorianError> {
        let conn = Connection::open(path).map_err(|e| HistorianError::Open {
            path: path.to_path_buf(),
            source: Box::new(e),
        })?;
        let store = Self {
            conn,
            path: path.to_path_buf(),
        };
        store.setup()?;
        Ok(store)
    }

    /// Opens `dir/vigie.sqlite` to read it beside the process that writes it: read
    /// only, so it never creates, migrates or switches the file's journal mode under
    /// the writer (a reader that did raced the gateway's own start). `None` while the
    /// file does not exist or its writer has not created the schema yet.
    pub fn open_read_only(dir: &Path) -> Result<Option<Self>, HistorianError> {
        let path = dir.join(FILE);
        if !path.exists() {
            return Ok(None);
        }
        let flags = rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY
            | rusqlite::OpenFlags::SQLITE_OPEN_NO_MUTEX
            | rusqlite::OpenFlags::SQLITE_OPEN_URI;
        let conn = Connection::open_with_flags(&path, flags).map_err(|e| HistorianError::Open {
            path: path.clone(),
            source: Box::new(e),
        })?;
        let store = Self { conn, path };
        store
            .conn
            .busy_timeout(std::time::Duration::from_secs(10))
            .map_err(|e| store.sql(e))?;
        let version: i64 = store
            .conn
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .map_err(|e| store.sql(e))?;
        match version {
            0 => Ok(None),
            SCHEMA_VERSION => Ok(Some(store)),
            v if v > SCHEMA_VERSION => Err(HistorianError::Newer {
                path: store.path.clone(),
                found: v,
            }),
            v => Err(HistorianError::Open {
                path: store.path.clone(),
                source: format!("schema version {v}: open it once read-write to migrate it").into(),
            }),
        }
    }

    fn sql(&self, source: rusqlite::Error) -> HistorianError {
        HistorianError::Sql {
            path: self.path.clone(),
            source,
        }
    }

    fn setup(&self) -> Result<(), HistorianError> {
        self.conn
            .busy_timeout(std::time::Duration::from_secs(10))
            .map_err(|e| self.sql(e))?;
        let mode: String = self
            .conn
            .query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))
            .map_err(|e| self.sql(e))?;
        if !mode.eq_ignore_ascii_case("wal") {
            return Err(HistorianError::Open {
                path: self.path.clone(),
                source: format!("cannot switch to WAL (journal mode {mode})").into(),
            });
        }
        self.conn
            .execute_batch("PRAGMA synchronous = FULL; PRAGMA foreign_keys = ON;")
            .map_err(|e| self.sql(e))?;
        let version: i64 = self
            .conn
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .map_err(|e| self.sql(e))?;
        if version > SCHEMA_VERSION {
            return Err(HistorianError::Newer {
                path: self.path.clone(),
                found: version,
            });
        }
        // Version 1 had no message code nor fields on journal entries: its rows keep
        // their text and gain empty ones.
        let migrate = if version == 1 {
            "ALTER TABLE journal ADD COLUMN code TEXT NOT NULL DEFAULT ''; \
             ALTER TABLE journal ADD COLUMN fields TEXT NOT NULL DEFAULT ''; \
             ALTER TABLE alarms ADD COLUMN code TEXT NOT NULL DEFAULT ''; \
             ALTER TABLE alarms ADD COLUMN fields TEXT NOT NULL DEFAULT '';"
        } else {
            ""
        };
        if version == SCHEMA_VERSION {
            return Ok(());
        }
        // IMMEDIATE: the write lock is taken first, so a writer holding the file makes
        // this wait (busy timeout) rather than fail on a lock upgrade.
        self.conn
            .execute_batch(&format!(
                "BEGIN IMMEDIATE; {migrate} {SCHEMA} PRAGMA user_version = {SCHEMA_VERSION}; COMMIT;"
            ))
            .map_err(|e| self.sql(e))
    }

    /// The database file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Runs `f` in one durable transaction, committed when it returns `Ok`.
    fn write<T>(
        &mut self,
        f: impl FnOnce(&rusqlite::Transaction<'_>) -> rusqlite::Result<T>,
    ) -> Result<T, HistorianError> {
        let path = self.path.clone();
        let sql = |source| HistorianError::Sql { path, source };
        let run = || {
            let tx = self.conn.transaction()?;
            let value = f(&tx)?;
            tx.commit()?;
            Ok(value)
        };
        run().map_err(sql)
    }

    /// Starts a session (a console or gateway run) and returns its id.
    pub fn begin_session(
        &mut self,
        source: &str,
        plant: &str,
        started_ms: u64,
    ) -> Result<i64, HistorianError> {
        self.conn
            .execute(
                "INSERT INTO sessions(source, plant, started_ms) VALUES (?1, ?2, ?3)",
                params![source, plant, to_i64(started_ms)],
            )
            .map_err(|e| self.sql(e))?;
        Ok(self.conn.last_insert_rowid())
    }

    /// Appends journal entries in one durable transaction: when this returns `Ok`,
    /// every entry survives a kill -9 or a power cut.
    pub fn append_journal(
        &mut self,
        session: i64,
        rows: &[JournalRow],
    ) -> Result<(), HistorianError> {
        if rows.is_empty() {
            return Ok(());
        }
        self.write(|tx| {
            let mut st = tx.prepare_cached(
                "INSERT INTO journal(session, wall_ms, sim_ms, kind, text, code, fields) \
                     VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
            )?;
            for r in rows {
                st.execute(params![
                    session,
                    to_i64(r.wall_ms),
                    to_i64(r.sim_ms),
                    r.kind,
                    r.text,
                    r.code,
                    encode_fields(&r.fields)
                ])?;
            }
            Ok(())
        })
    }

    /// The journal entries from `from_ms` on (wall clock), oldest first, at most
    /// `limit`, whose kind or text contains `search` (case-insensitive; empty: all).
    pub fn journal(
        &self,
        from_ms: u64,
        search: &str,
        limit: usize,
    ) -> Result<Vec<JournalRow>, HistorianError> {
        let mut st = self
            .conn
            .prepare_cached(
                "SELECT wall_ms, sim_ms, kind, text, code, fields FROM journal WHERE wall_ms >= ?1 \
                 AND (?2 = '' OR instr(lower(kind || ' ' || text), lower(?2)) > 0) \
                 ORDER BY id LIMIT ?3",
            )
            .map_err(|e| self.sql(e))?;
        let rows = st
            .query_map(
                params![to_i64(from_ms), search, to_i64(limit as u64)],
                |r| {
                    Ok(JournalRow {
                        wall_ms: to_u64(r.get(0)?),
                        sim_ms: to_u64(r.get(1)?),
                        kind: r.get(2)?,
                        text: r.get(3)?,
                        code: r.get(4)?,
                        fields: decode_fields(&r.get::<_, String>(5)?),
                    })
                },
            )
            .map_err(|e| self.sql(e))?;
        rows.collect::<Result<_, _>>().map_err(|e| self.sql(e))
    }

    /// Writes the latest state of these alarms of `session` (insert or replace), in
    /// one durable transaction.
    pub fn upsert_alarms(&mut self, session: i64, rows: &[AlarmRow]) -> Result<(), HistorianError> {
        if rows.is_empty() {
            return Ok(());
        }
        self.write(|tx| {
            let mut st = tx
                .prepare_cached(
                    "INSERT OR REPLACE INTO alarms(session, alarm, key, kind, priority, message, detail, \
                     raised_ms, acked_ms, ack_note, cleared_ms, shelved_until_ms, shelve_reason, first_out, \
                     code, fields) \
                     VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)",
                )?;
            for a in rows {
                st.execute(params![
                    session,
                    to_i64(a.alarm),
                    a.key,
                    a.kind,
                    a.priority,
                    a.message,
                    a.detail,
                    to_i64(a.raised_ms),
                    a.acked.as_ref().map(|(t, _)| to_i64(*t)),
                    a.acked.as_ref().map(|(_, n)| n.as_str()),
                    a.cleared_ms.map(to_i64),
                    a.shelved.as_ref().map(|(t, _)| to_i64(*t)),
                    a.shelved.as_ref().map(|(_, r)| r.as_str()),
                    a.first_out,
                    a.code,
                    encode_fields(&a.fields)
                ])?;
            }
            Ok(())
        })
    }

    /// The alarms raised from `from_ms` on, every session, oldest first (at most
    /// `limit`).
    pub fn alarms(&self, from_ms: u64, limit: usize) -> Result<Vec<AlarmRow>, HistorianError> {
        let mut st = self
            .conn
            .prepare_cached(
                "SELECT alarm, key, kind, priority, message, detail, raised_ms, acked_ms, ack_note, \
                 cleared_ms, shelved_until_ms, shelve_reason, first_out, code, fields FROM alarms \
                 WHERE raised_ms >= ?1 ORDER BY raised_ms, session, alarm LIMIT ?2",
            )
            .map_err(|e| self.sql(e))?;
        let rows = st
            .query_map(params![to_i64(from_ms), to_i64(limit as u64)], |r| {
                let acked: Option<i64> = r.get(7)?;
                let shelved: Option<i64> = r.get(10)?;
                Ok(AlarmRow {
                    alarm: to_u64(r.get(0)?),
                    key: r.get(1)?,
                    kind: r.get(2)?,
                    priority: r.get(3)?,
                    message: r.get(4)?,
                    detail: r.get(5)?,
                    raised_ms: to_u64(r.get(6)?),
                    acked: acked
                        .map(|t| {
                            Ok::<_, rusqlite::Error>((
                                to_u64(t),
                                r.get::<_, Option<String>>(8)?.unwrap_or_default(),
                            ))
                        })
                        .transpose()?,
                    cleared_ms: r.get::<_, Option<i64>>(9)?.map(to_u64),
                    shelved: shelved
                        .map(|t| {
                            Ok::<_, rusqlite::Error>((
                                to_u64(t),
                                r.get::<_, Option<String>>(11)?.unwrap_or_default(),
                            ))
                        })
                        .transpose()?,
                    first_out: r.get(12)?,
                    code: r.get(13)?,
                    fields: decode_fields(&r.get::<_, String>(14)?),
                })
            })
            .map_err(|e| self.sql(e))?;
        rows.collect::<Result<_, _>>().map_err(|e| self.sql(e))
    }

    /// The ids of these signal names, created as needed.
    pub fn signal_ids(&mut self, names: &[String]) -> Result<Vec<i64>, HistorianError> {
        self.write(|tx| {
            let mut insert =
                tx.prepare_cached("INSERT OR IGNORE INTO signals(name) VALUES (?1)")?;
            let mut get = tx.prepare_cached("SELECT id FROM signals WHERE name = ?1")?;
            let mut ids = Vec::with_capacity(names.len());
            for n in names {
                insert.execute([n])?;
                ids.push(get.query_row([n], |r| r.get(0))?);
            }
            Ok(ids)
        })
    }

    /// The latest time stamped in the journal or the process history, ms (0 when
    /// empty): a session that stamps simulated time starts after it, so that two
    /// sessions never overlap.
    pub fn latest_ms(&self) -> Result<u64, HistorianError> {
        let journal: Option<i64> = self
            .conn
            .query_row("SELECT MAX(wall_ms) FROM journal", [], |r| r.get(0))
            .map_err(|e| self.sql(e))?;
        // Per signal: the last key of each range of the primary key.
        let samples: Option<i64> = self
            .conn
            .query_row(
                "SELECT MAX((SELECT MAX(t_ms) FROM samples WHERE signal = signals.id)) FROM signals",
                [],
                |r| r.get(0),
            )
            .map_err(|e| self.sql(e))?;
        Ok(to_u64(journal.unwrap_or(0).max(samples.unwrap_or(0))))
    }

    /// The signals with a history, by name.
    pub fn signals(&self) -> Result<Vec<String>, HistorianError> {
        let mut st = self
            .conn
            .prepare_cached("SELECT name FROM signals ORDER BY name")
            .map_err(|e| self.sql(e))?;
        let rows = st.query_map([], |r| r.get(0)).map_err(|e| self.sql(e))?;
        rows.collect::<Result<_, _>>().map_err(|e| self.sql(e))
    }

    /// Appends changes of signals in one transaction (a change at the same signal and
    /// millisecond as a stored one replaces it).
    pub fn append_samples(&mut self, samples: &[Sample]) -> Result<(), HistorianError> {
        if samples.is_empty() {
            return Ok(());
        }
        self.write(|tx| {
            let mut st = tx.prepare_cached(
                "INSERT OR REPLACE INTO samples(signal, t_ms, value) VALUES (?1, ?2, ?3)",
            )?;
            for s in samples {
                st.execute(params![s.signal, to_i64(s.t_ms), s.value])?;
            }
            Ok(())
        })
    }

    /// The history of `signal` over `[from_ms, to_ms)` in at most `buckets` equal
    /// buckets of time (each with its first and last change, the values taken and the
    /// last one), and its value before the range.
    pub fn trend(
        &self,
        signal: &str,
        from_ms: u64,
        to_ms: u64,
        buckets: u32,
    ) -> Result<Trend, HistorianError> {
        let Some(id) = self
            .conn
            .query_row("SELECT id FROM signals WHERE name = ?1", [signal], |r| {
                r.get::<_, i64>(0)
            })
            .optional()
            .map_err(|e| self.sql(e))?
        else {
            return Ok(Trend::default());
        };
        let before = self
            .conn
            .prepare_cached(
                "SELECT value FROM samples WHERE signal = ?1 AND t_ms < ?2 ORDER BY t_ms DESC LIMIT 1",
            )
            .and_then(|mut st| {
                st.query_row(params![id, to_i64(from_ms)], |r| r.get(0))
                    .optional()
            })
            .map_err(|e| self.sql(e))?;
        let width = (to_ms.saturating_sub(from_ms) / u64::from(buckets.max(1))).max(1);
        let mut st = self
            .conn
            .prepare_cached(
                "SELECT MIN(t_ms), MAX(t_ms), COUNT(*), MIN(value), MAX(value) FROM samples \
                 WHERE signal = ?1 AND t_ms >= ?2 AND t_ms < ?3 GROUP BY (t_ms - ?2) / ?4 ORDER BY 1",
            )
            .map_err(|e| self.sql(e))?;
        let rows = st
            .query_map(
                params![id, to_i64(from_ms), to_i64(to_ms), to_i64(width)],
                |r| {
                    Ok(TrendBucket {
                        first_ms: to_u64(r.get(0)?),
                        last_ms: to_u64(r.get(1)?),
                        changes: to_u64(r.get(2)?),
                        min: r.get(3)?,
                        max: r.get(4)?,
                        last: 0,
                    })
                },
            )
            .map_err(|e| self.sql(e))?;
        let mut buckets: Vec<TrendBucket> =
            rows.collect::<Result<_, _>>().map_err(|e| self.sql(e))?;
        // The value after each bucket's last change: one lookup of the primary key each.
        let mut last = self
            .conn
            .prepare_cached("SELECT value FROM samples WHERE signal = ?1 AND t_ms = ?2")
            .map_err(|e| self.sql(e))?;
        for b in &mut buckets {
            b.last = if b.min == b.max {
                b.min
            } else {
                last.query_row(params![id, to_i64(b.last_ms)], |r| r.get(0))
                    .map_err(|e| self.sql(e))?
            };
        }
        Ok(Trend { before, buckets })
    }

    /// The changes of `signal` in `[from_ms, to_ms)`, with the value before the range
    /// first (stamped `from_ms`), in time order.
    pub fn changes(
        &self,
        signal: &str,
        from_ms: u64,
        to_ms: u64,
    ) -> Result<Vec<(u64, i64)>, HistorianError> {
        let t = self.trend(signal, from_ms, to_ms, 1)?;
        let mut out: Vec<(u64, i64)> = t.before.map(|v| (from_ms, v)).into_iter().collect();
        let mut st = self
            .conn
            .prepare_cached(
                "SELECT t_ms, value FROM samples WHERE signal = (SELECT id FROM signals WHERE name = ?1) \
                 AND t_ms >= ?2 AND t_ms < ?3 ORDER BY t_ms",
            )
            .map_err(|e| self.sql(e))?;
        let rows = st
            .query_map(params![signal, to_i64(from_ms), to_i64(to_ms)], |r| {
                Ok((to_u64(r.get(0)?), r.get(1)?))
            })
            .map_err(|e| self.sql(e))?;
        for r in rows {
            out.push(r.map_err(|e| self.sql(e))?);
        }
        Ok(out)
    }

    /// Deletes what is older than the retention at `now_ms`.
    pub fn purge(&mut self, now_ms: u64, retention: &Retention) -> Result<Purged, HistorianError> {
        let process = to_i64(now_ms.saturating_sub(u64::from(retention.process_days) * DAY_MS));
        let journal = to_i64(now_ms.saturating_sub(u64::from(retention.journal_days) * DAY_MS));
        self.write(|tx| {
            // Per signal: a range of the primary key each, no full scan.
            let ids: Vec<i64> = tx
                .prepare("SELECT id FROM signals")?
                .query_map([], |r| r.get(0))?
                .collect::<Result<_, _>>()?;
            let mut del = tx.prepare("DELETE FROM samples WHERE signal = ?1 AND t_ms < ?2")?;
            let mut purged = Purged::default();
            for id in ids {
                purged.samples += del.execute(params![id, process])? as u64;
            }
            purged.journal =
                tx.execute("DELETE FROM journal WHERE wall_ms < ?1", [journal])? as u64;
            purged.alarms =
                tx.execute("DELETE FROM alarms WHERE raised_ms < ?1", [journal])? as u64;
            Ok(purged)
        })
    }

    /// `PRAGMA integrity_check` (`ok` when sound).
    pub fn integrity(&self) -> Result<String, HistorianError> {
        self.conn
            .query_row("PRAGMA integrity_check", [], |r| r.get(0))
            .map_err(|e| self.sql(e))
    }

    /// Imports a JSON-lines journal written by an earlier Vigie (`journal.jsonl`) as a
    /// session of its own, then renames the file `journal.jsonl.imported`; a line that
    /// is not an entry is an error naming the file and line, and nothing is imported.
    pub fn import_jsonl(&mut self, file: &Path, source: &str) -> Result<usize, HistorianError> {
        let open = |e: String| HistorianError::Open {
            path: file.to_path_buf(),
            source: e.into(),
        };
        let text = std::fs::read_to_string(file).map_err(|e| open(e.to_string()))?;
        #[derive(serde::Deserialize)]
        struct Old {
            wall_ms: u64,
            sim_ms: u64,
            kind: String,
            text: String,
        }
        let mut rows = Vec::new();
        for (n, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let e: Old = serde_json::from_str(line)
                .map_err(|e| open(format!("line {}, column {}: {e}", n + 1, e.column())))?;
            rows.push(JournalRow {
                wall_ms: e.wall_ms,
                sim_ms: e.sim_ms,
                kind: e.kind,
                text: e.text,
                ..JournalRow::default()
            });
        }
        let started = rows.first().map_or(0, |r| r.wall_ms);
        let session = self.begin_session(source, "journal.jsonl", started)?;
        self.append_journal(session, &rows)?;
        let mut done = file.as_os_str().to_owned();
        done.push(".imported");
        std::fs::rename(file, &done).map_err(|e| open(e.to_string()))?;
        Ok(rows.len())
    }
}

#[cfg(test)]
mod tests;
