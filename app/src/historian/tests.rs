use super::writer::{Msg, ProcessRecorder, Writer};
use super::*;
use std::time::Duration;

struct Dir(PathBuf);

impl Dir {
    fn new(tag: &str) -> Self {
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let d = std::env::temp_dir().join(format!("vigie-hist-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        Self(d)
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn row(wall_ms: u64, kind: &str, text: &str) -> JournalRow {
    JournalRow {
        wall_ms,
        sim_ms: wall_ms,
        kind: kind.into(),
        text: text.into(),
        ..JournalRow::default()
    }
}

#[test]
fn journal_is_durable_and_shared_by_two_connections() {
    let d = Dir::new("journal");
    let mut a = Store::open_in(&d.0).unwrap();
    let mut b = Store::open_in(&d.0).unwrap();
    let sa = a.begin_session("console", "station", 1).unwrap();
    let sb = b.begin_session("gateway", "station", 2).unwrap();
    assert_ne!(sa, sb);
    a.append_journal(
        sa,
        &[row(10, "trip", "CSs10 \"held\""), row(11, "ack", "ok")],
    )
    .unwrap();
    b.append_journal(sb, &[row(12, "alarm", "link lost")])
        .unwrap();
    // Each sees the other's committed rows at once (WAL, one file).
    let all = b.journal(0, "", 100).unwrap();
    assert_eq!(all.len(), 3);
    assert_eq!(all[0].text, "CSs10 \"held\"");
    assert_eq!(a.journal(0, "LINK", 100).unwrap().len(), 1);
    assert_eq!(a.journal(11, "", 100).unwrap().len(), 2);
    assert_eq!(a.integrity().unwrap(), "ok");
    let mode: String = a
        .conn
        .query_row("PRAGMA journal_mode", [], |r| r.get(0))
        .unwrap();
    assert_eq!(mode, "wal");
    let sync: i64 = a
        .conn
        .query_row("PRAGMA synchronous", [], |r| r.get(0))
        .unwrap();
    assert_eq!(sync, 2, "synchronous = FULL");
}

/// A reader beside the writer neither creates the file nor its schema, sees the
/// writer's committed rows, and cannot write.
#[test]
fn a_read_only_reader_waits_for_the_writers_schema_and_never_writes() {
    let d = Dir::new("read-only");
    assert!(Store::open_read_only(&d.0).unwrap().is_none());
    assert!(!d.0.join(FILE).exists(), "the reader created the file");
    std::fs::create_dir_all(&d.0).unwrap();
    std::fs::write(d.0.join(FILE), b"").unwrap();
    // An empty file, as the writer's open leaves it for a moment: no schema yet.
    assert!(Store::open_read_only(&d.0).unwrap().is_none());
    std::fs::remove_file(d.0.join(FILE)).unwrap();
    let mut w = Store::open_in(&d.0).unwrap();
    let s = w.begin_session("gateway", "station", 1).unwrap();
    let mut r = Store::open_read_only(&d.0)
        .unwrap()
        .expect("the schema is there");
    w.append_journal(s, &[row(10, "listening", "x")]).unwrap();
    assert_eq!(r.journal(0, "", 10).unwrap().len(), 1);
    assert!(r.begin_session("console", "station", 2).is_err());
}

/// A file of schema version 1 (journal rows without message code nor fields) opens:
/// its rows keep their text, and new rows keep their code and fields.
#[test]
fn a_version_1_file_is_migrated_and_keeps_its_rows() {
    let d = Dir::new("v1");
    std::fs::create_dir_all(&d.0).unwrap();
    {
        let c = rusqlite::Connection::open(d.0.join("vigie.sqlite")).unwrap();
        c.execute_batch(
            "CREATE TABLE sessions(id INTEGER PRIMARY KEY, source TEXT NOT NULL, \
             plant TEXT NOT NULL, started_ms INTEGER NOT NULL); \
             CREATE TABLE journal(id INTEGER PRIMARY KEY, session INTEGER NOT NULL, \
             wall_ms INTEGER NOT NULL, sim_ms INTEGER NOT NULL, kind TEXT NOT NULL, \
             text TEXT NOT NULL); \
             CREATE TABLE alarms(session INTEGER NOT NULL, alarm INTEGER NOT NULL, \
             key TEXT NOT NULL, kind TEXT NOT NULL, priority TEXT NOT NULL, \
             message TEXT NOT NULL, detail TEXT NOT NULL, raised_ms INTEGER NOT NULL, \
             acked_ms INTEGER, ack_note TEXT, cleared_ms INTEGER, shelved_until_ms INTEGER, \
             shelve_reason TEXT, first_out INTEGER NOT NULL, PRIMARY KEY(session, alarm)); \
             CREATE TABLE signals(id INTEGER PRIMARY KEY, name TEXT NOT NULL UNIQUE); \
             CREATE TABLE samples(signal INTEGER NOT NULL, t_ms INTEGER NOT NULL, \
             value INTEGER NOT NULL, PRIMARY KEY(signal, t_ms)) WITHOUT ROWID; \
             INSERT INTO sessions VALUES (1, 'console', 'station', 5); \
             INSERT INTO alarms VALUES (1, 1, 'trip:CSs10', 'trip', 'urgent', 'Safety stop', \
             '', 5, NULL, NULL, NULL, NULL, NULL, 1); \
             INSERT INTO journal VALUES (1, 1, 5, 0, 'trip', 'filter tripped on CSs10'); \
             PRAGMA user_version = 1;",
        )
        .unwrap();
    }
    let mut s = Store::open_in(&d.0).unwrap();
    let version: i64 = s
        .conn
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .unwrap();
    assert_eq!(version, SCHEMA_VERSION);
    let old = s.journal(0, "", 10).unwrap();
    assert_eq!(old.len(), 1);
    assert_eq!(old[0].text, "filter tripped on CSs10");
    assert!(old[0].code.is_empty() && old[0].fields.is_empty());
    let alarms = s.alarms(0, 10).unwrap();
    assert_eq!(alarms.len(), 1);
    assert_eq!(alarms[0].message, "Safety stop");
    assert!(alarms[0].code.is_empty() && alarms[0].first_out);
    let mut coded = row(6, "trip", "filter tripped on CSs4");
    coded.code = "journal-trip".into();
    coded.fields = [("constraints".to_string(), "CSs4".to_string())].into();
    s.append_journal(1, &[coded.clone()]).unwrap();
    drop(s);
    // Opened again (now at the current version): nothing migrates twice.
    let s = Store::open_in(&d.0).unwrap();
    let all = s.journal(0, "", 10).unwrap();
    assert_eq!(all.len(), 2);
    assert_eq!(all[1], coded);
    assert_eq!(s.integrity().unwrap(), "ok");
}

#[test]
fn a_newer_schema_is_refused_and_left_alone() {
    let d = Dir::new("newer");
    let s = Store::open_in(&d.0).unwrap();
    s.conn.execute_batch("PRAGMA user_version = 99").unwrap();
    drop(s);
    let e = Store::open_in(&d.0).unwrap_err();
    assert!(e.to_string().contains("schema version 99"), "{e}");
    assert!(e.to_string().contains("vigie.sqlite"), "{e}");
}

#[test]
fn a_file_that_is_not_a_database_is_an_error_naming_it() {
    let d = Dir::new("garbage");
    std::fs::create_dir_all(&d.0).unwrap();
    std::fs::write(d.0.join(FILE), b"not a database, just text ".repeat(100)).unwrap();
    let e = Store::open_in(&d.0).unwrap_err();
    assert!(e.to_string().contains("vigie.sqlite"), "{e}");
    // Nothing was overwritten.
    assert!(
        std::fs::read(d.0.join(FILE))
            .unwrap()
            .starts_with(b"not a database")
    );
}

#[test]
fn alarms_keep_their_latest_state() {
    let d = Dir::new("alarms");
    let mut s = Store::open_in(&d.0).unwrap();
    let session = s.begin_session("console", "station", 0).unwrap();
    let mut a = AlarmRow {
        alarm: 1,
        key: "trip:CSs10".into(),
        kind: "trip".into(),
        priority: "urgent".into(),
        message: "Safety stop".into(),
        detail: "A4 & C7".into(),
        raised_ms: 100,
        acked: None,
        cleared_ms: None,
        shelved: None,
        first_out: true,
        code: "trip".into(),
        fields: [("constraints".to_string(), "CSs10".to_string())].into(),
    };
    s.upsert_alarms(session, std::slice::from_ref(&a)).unwrap();
    a.acked = Some((150, "checked the box".into()));
    a.cleared_ms = Some(200);
    s.upsert_alarms(session, std::slice::from_ref(&a)).unwrap();
    let rows = s.alarms(0, 10).unwrap();
    assert_eq!(rows, vec![a]);
}

#[test]
fn trend_steps_and_buckets() {
    let d = Dir::new("trend");
    let mut s = Store::open_in(&d.0).unwrap();
    let ids = s.signal_ids(&["C4".into(), "A4".into()]).unwrap();
    assert_eq!(s.signal_ids(&["A4".into()]).unwrap(), vec![ids[1]]);
    // C4: 1 at 50, 0 at 1000, 1 at 1010, 0 at 1020, 1 at 5000.
    let c4 = ids[0];
    let samples: Vec<Sample> = [(50, 1), (1000, 0), (1010, 1), (1020, 0), (5000, 1)]
        .iter()
        .map(|&(t_ms, value)| Sample {
            signal: c4,
            t_ms,
            value,
        })
        .collect();
    s.append_samples(&samples).unwrap();
    // Fine buckets: every change is its own bucket.
    let t = s.trend("C4", 0, 6000, 6000).unwrap();
    assert_eq!(t.before, None);
    assert_eq!(t.buckets.len(), 5);
    assert_eq!(
        t.buckets.iter().map(|b| b.last).collect::<Vec<_>>(),
        vec![1, 0, 1, 0, 1]
    );
    // Coarse: 1000..2000 holds three changes, both values, ends at 0.
    let t = s.trend("C4", 100, 6100, 6).unwrap();
    assert_eq!(t.before, Some(1));
    assert_eq!(t.buckets.len(), 2);
    let b = t.buckets[0];
    assert_eq!(
        (b.first_ms, b.last_ms, b.changes, b.min, b.max, b.last),
        (1000, 1020, 3, 0, 1, 0)
    );
    let steps = t.steps(100, 6100);
    assert_eq!(steps.first(), Some(&(100, 1)));
    assert_eq!(steps.last(), Some(&(6100, 1)));
    assert_eq!(s.latest_ms().unwrap(), 5000);
    // An unknown signal has no history, not an error.
    assert_eq!(s.trend("nope", 0, 10, 10).unwrap(), Trend::default());
    // The range end is exclusive; nothing in an empty range.
    let t = s.trend("C4", 5000, 5000, 10).unwrap();
    assert!(t.buckets.is_empty());
    assert_eq!(t.before, Some(0));
}

#[test]
fn purge_keeps_the_retention() {
    let d = Dir::new("purge");
    let mut s = Store::open_in(&d.0).unwrap();
    let now = 100 * DAY_MS;
    let session = s.begin_session("gateway", "station", 0).unwrap();
    s.append_journal(session, &[row(1, "old", "x"), row(now - 1, "new", "y")])
        .unwrap();
    let id = s.signal_ids(&["C4".into()]).unwrap()[0];
    let at = |t_ms| Sample {
        signal: id,
        t_ms,
        value: 1,
    };
    s.append_samples(&[at(1), at(now - 40 * DAY_MS), at(now - DAY_MS)])
        .unwrap();
    let r = Retention {
        process_days: 31,
        journal_days: 50,
    };
    let p = s.purge(now, &r).unwrap();
    assert_eq!(p.samples, 2);
    assert_eq!(p.journal, 1);
    assert_eq!(s.journal(0, "", 10).unwrap().len(), 1);
    assert_eq!(s.trend("C4", 0, now, 10).unwrap().buckets.len(), 1);
}

#[test]
fn an_old_jsonl_journal_is_imported_once() {
    let d = Dir::new("import");
    std::fs::create_dir_all(&d.0).unwrap();
    let old = d.0.join("journal.jsonl");
    std::fs::write(
        &old,
        "{\"wall_ms\":5,\"sim_ms\":1,\"kind\":\"trip\",\"text\":\"CSs10\"}\n\n{\"wall_ms\":6,\"sim_ms\":2,\"kind\":\"reset\",\"text\":\"r\"}\n",
    )
    .unwrap();
    let mut s = Store::open_in(&d.0).unwrap();
    assert_eq!(s.import_jsonl(&old, "console").unwrap(), 2);
    assert!(!old.exists());
    assert!(d.0.join("journal.jsonl.imported").exists());
    assert_eq!(s.journal(0, "", 10).unwrap().len(), 2);
    // A damaged line: an error with its line and column, nothing imported.
    std::fs::write(
        &old,
        "{\"wall_ms\":5,\"sim_ms\":1,\"kind\":\"trip\",\"text\":\"a\"}\n{\"wall_ms\":oops}\n",
    )
    .unwrap();
    let e = s.import_jsonl(&old, "console").unwrap_err().to_string();
    assert!(
        e.contains("journal.jsonl") && e.contains("line 2, column"),
        "{e}"
    );
    assert!(old.exists());
    assert_eq!(s.journal(0, "", 10).unwrap().len(), 2);
}

#[test]
fn the_recorder_stores_changes_only() {
    let mut r = ProcessRecorder::new(3);
    r.record(0, [0, 1, 0].into_iter());
    r.record(10, [0, 1, 0].into_iter());
    r.record(20, [1, 1, 0].into_iter());
    assert_eq!(
        r.take_due(20, 1000),
        Some(vec![(0, 0, 0), (1, 0, 1), (2, 0, 0), (0, 20, 1)])
    );
    r.record(30, [0, 1, 0].into_iter());
    assert_eq!(r.take_due(40, 1000), None, "not due yet");
    assert_eq!(r.take_due(1020, 1000), Some(vec![(0, 30, 0)]));
    r.restart();
    r.record(2000, [0, 1, 0].into_iter());
    assert_eq!(r.take_due(2000, 0).map(|v| v.len()), Some(3));
}

#[test]
fn the_writer_commits_batches_and_flushes() {
    let d = Dir::new("writer");
    let mut store = Store::open_in(&d.0).unwrap();
    let session = store.begin_session("console", "station", 0).unwrap();
    let names = vec!["C4".to_string(), "A4".to_string()];
    let w = Writer::start(store, session, &names, Retention::default()).unwrap();
    let now = wall_ms();
    for k in 0..100u64 {
        w.send(Msg::Samples(vec![(0, now + k * 10, i64::from(k % 2 == 0))]));
    }
    assert!(w.flush(Duration::from_secs(30)));
    let reader = Store::open_in(&d.0).unwrap();
    let t = reader.trend("C4", now, now + 1000, 1000).unwrap();
    assert_eq!(t.buckets.iter().map(|b| b.changes).sum::<u64>(), 100);
    assert_eq!(w.lost(), 0);
    assert_eq!(w.take_error(), None);
}
