//! Where the events of a headless run go (`vigie gateway`), off the runtime and off the
//! cycle: a bounded queue drained by the `vigie-events` thread, which commits each batch
//! of events to the historian (`vigie.sqlite` in the state folder: the journal, the
//! alarm history, and the process history the cycle hands over through
//! [`LiveHistory`]) and only then hands them to stdout through a non-blocking, lossy
//! writer (tracing-appender's). A line on stdout is therefore always in the journal: a
//! kill -9 loses no event anyone saw. A reader of stdout that stalls loses stdout
//! lines, never a journal entry and never a cycle; a queue that overflows loses events.
//! Both losses are counted and reported as an `events_lost` event once there is room.

use crate::historian::writer::{Change, ProcessRecorder, cycle_values};
use crate::historian::{AlarmRow, JournalRow, Retention, Sample, Store, wall_ms};
use serde_json::json;
use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use vigie_core::history::CycleRecord;

/// What the sink is handed.
enum Msg {
    Event(serde_json::Value),
    Samples(Vec<Change>),
}

/// Events queued before the sink drops them.
const QUEUE: usize = 16_384;

/// The sink's handle: cheap to clone, never blocks.
#[derive(Clone)]
pub struct EventSink {
    tx: SyncSender<Msg>,
    lost: Arc<AtomicU64>,
}

/// The running sink; [`SinkThread::finish`] drains it.
pub struct SinkThread {
    thread: std::thread::JoinHandle<()>,
    _stdout: tracing_appender::non_blocking::WorkerGuard,
}

/// The historian of a run: where, which plant, which signals (the process history's
/// names), how long rows are kept.
pub struct SinkHistorian<'a> {
    /// The state folder (`vigie.sqlite` in it).
    pub dir: &'a Path,
    /// The plant's folder, named in the session.
    pub plant: &'a str,
    /// The process history's signals ([`crate::historian::writer::signal_names`]).
    pub signals: &'a [String],
    /// The retention.
    pub retention: Retention,
}

impl EventSink {
    /// Starts the sink: the historian when given (created if needed), then stdout.
    pub fn start(historian: Option<SinkHistorian<'_>>) -> anyhow::Result<(Self, SinkThread)> {
        let history = match historian {
            Some(h) => {
                let open = || -> Result<_, crate::historian::HistorianError> {
                    let mut store = Store::open_in(h.dir)?;
                    store.purge(wall_ms(), &h.retention)?;
                    let session = store.begin_session("gateway", h.plant, wall_ms())?;
                    let ids = store.signal_ids(h.signals)?;
                    Ok(History {
                        store,
                        session,
                        ids,
                        retention: h.retention,
                        open_alarms: BTreeMap::new(),
                        next_alarm: 1,
                        purged_at: std::time::Instant::now(),
                    })
                };
                Some(open().map_err(|e| {
                    anyhow::anyhow!("cannot open the journal in {}: {e}", h.dir.display())
                })?)
            }
            None => None,
        };
        let (stdout, guard) = tracing_appender::non_blocking::NonBlockingBuilder::default()
            .lossy(true)
            .thread_name("vigie-stdout")
            .finish(std::io::stdout());
        let (tx, rx) = sync_channel(QUEUE);
        let lost = Arc::new(AtomicU64::new(0));
        let l = Arc::clone(&lost);
        let thread = std::thread::Builder::new()
            .name("vigie-events".into())
            .spawn(move || drain(&rx, history, stdout, &l))?;
        Ok((
            Self { tx, lost },
            SinkThread {
                thread,
                _stdout: guard,
            },
        ))
    }

    /// Queues one event; when the queue is full the event is counted as lost.
    pub fn emit(&self, event: serde_json::Value) {
        self.send(Msg::Event(event));
    }

    fn send(&self, msg: Msg) {
        match self.tx.try_send(msg) {
            Ok(()) => {}
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.lost.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

/// The process history of a live run: the changes of every signal, cycle by cycle,
/// handed to the sink once a second (and at the end).
pub struct LiveHistory {
    recorder: ProcessRecorder,
    sink: EventSink,
    /// Wall-clock time of the run's time 0, ms.
    base_ms: u64,
}

impl LiveHistory {
    /// The history of `n` signals ([`crate::historian::writer::signal_names`]) into
    /// `sink`, from now.
    pub fn new(n: usize, sink: EventSink) -> Self {
        Self {
            recorder: ProcessRecorder::new(n),
            sink,
            base_ms: wall_ms(),
        }
    }

    /// Records the cycle (the engine's last record).
    pub fn record(&mut self, rec: &CycleRecord) {
        let t = self.base_ms + rec.time.0;
        self.recorder.record(t, cycle_values(rec));
        if let Some(batch) = self.recorder.take_due(t, 1000) {
            self.sink.send(Msg::Samples(batch));
        }
    }

    /// Hands over what is left.
    pub fn finish(&mut self) {
        if let Some(batch) = self.recorder.take_due(u64::MAX, 0) {
            self.sink.send(Msg::Samples(batch));
        }
    }
}

impl std::fmt::Debug for LiveHistory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveHistory").finish_non_exhaustive()
    }
}

impl SinkThread {
    /// Waits until every queued event is written (call after the last
    /// [`EventSink`] clone is dropped).
    pub fn finish(self) {
        let _ = self.thread.join();
    }
}

/// The historian as the sink thread keeps it.
struct History {
    store: Store,
    session: i64,
    ids: Vec<i64>,
    retention: Retention,
    /// The alarms raised and not cleared, by key.
    open_alarms: BTreeMap<String, AlarmRow>,
    next_alarm: u64,
    purged_at: std::time::Instant,
}

impl History {
    /// Commits one batch: the journal rows, the alarms they raise or clear, the
    /// samples. Errors are logged; the events still go to stdout (the log says the
    /// journal missed them).
    fn commit(&mut self, events: &[serde_json::Value], samples: &[Change]) {
        let now = wall_ms();
        let rows: Vec<JournalRow> = events
            .iter()
            .map(|e| JournalRow {
                wall_ms: now,
                sim_ms: e["time_ms"].as_u64().unwrap_or(0),
                kind: e["event"].as_str().unwrap_or("event").to_string(),
                text: e.to_string(),
                ..JournalRow::default()
            })
            .collect();
        let mut alarms = Vec::new();
        for e in events {
            let Some(key) = e["key"].as_str() else {
                continue;
            };
            match e["event"].as_str() {
                Some("alarm") => {
                    let row = AlarmRow {
                        alarm: self.next_alarm,
                        key: key.to_string(),
                        kind: key.split(':').next().unwrap_or("alarm").to_string(),
                        priority: e["priority"].as_str().unwrap_or("").to_lowercase(),
                        message: e["message"].as_str().unwrap_or("").to_string(),
                        detail: e["detail"].as_str().unwrap_or("").to_string(),
                        raised_ms: now,
                        acked: None,
                        cleared_ms: None,
                        shelved: None,
                        first_out: false,
                        code: String::new(),
                        fields: BTreeMap::new(),
                    };
                    self.next_alarm += 1;
                    alarms.push(row.clone());
                    self.open_alarms.insert(key.to_string(), row);
                }
                Some("alarm_cleared") => {
                    if let Some(mut row) = self.open_alarms.remove(key) {
                        row.cleared_ms = Some(now);
                        alarms.push(row);
                    }
                }
                _ => {}
            }
        }
        let samples: Vec<Sample> = samples
            .iter()
            .filter_map(|&(i, t_ms, value)| {
                self.ids.get(i as usize).map(|&signal| Sample {
                    signal,
                    t_ms,
                    value,
                })
            })
            .collect();
        let results = [
            self.store.append_journal(self.session, &rows),
            self.store.upsert_alarms(self.session, &alarms),
            self.store.append_samples(&samples),
        ];
        for r in results {
            if let Err(e) = r {
                tracing::error!("{e}");
            }
        }
        if self.purged_at.elapsed() >= std::time::Duration::from_secs(3600) {
            self.purged_at = std::time::Instant::now();
            if let Err(e) = self.store.purge(now, &self.retention) {
                tracing::error!("{e}");
            }
        }
    }
}

/// Events committed per transaction at most.
const BATCH: usize = 512;

fn drain(
    rx: &Receiver<Msg>,
    mut history: Option<History>,
    mut stdout: tracing_appender::non_blocking::NonBlocking,
    lost: &AtomicU64,
) {
    let stdout_lost = stdout.error_counter();
    let mut reported_stdout = 0;
    while let Ok(first) = rx.recv() {
        // Everything already queued (up to a batch) in one transaction.
        let mut events = Vec::new();
        let mut samples = Vec::new();
        let mut next = Some(first);
        while let Some(msg) = next {
            match msg {
                Msg::Event(e) => events.push(e),
                Msg::Samples(s) => samples.extend(s),
            }
            next = if events.len() < BATCH {
                rx.try_recv().ok()
            } else {
                None
            };
        }
        let queue = lost.swap(0, Ordering::Relaxed);
        let out = stdout_lost.dropped_lines();
        if queue > 0 || out > reported_stdout {
            let e = json!({
                "event": "events_lost", "queue": queue,
                "stdout_lines": out - reported_stdout,
                "text": format!("{queue} events lost (queue full), {} stdout lines lost (nobody read them; the journal has them)", out - reported_stdout),
            });
            reported_stdout = out;
            tracing::warn!("{}", e["text"].as_str().unwrap_or_default());
            events.insert(0, e);
        }
        if let Some(h) = history.as_mut() {
            h.commit(&events, &samples);
        }
        // Only now, committed, do they reach stdout.
        for e in &events {
            let _ = stdout.write_all(format!("{e}\n").as_bytes());
        }
    }
}
