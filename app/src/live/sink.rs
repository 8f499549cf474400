//! Where the events of a headless run go (`vigie gateway`), off the runtime and off the
//! cycle: a bounded queue drained by the `vigie-events` thread, which appends each
//! event to the journal on disk (`journal.jsonl`, the console's format: `wall_ms`,
//! `sim_ms`, `kind`, `text`) and then hands it to stdout through a non-blocking, lossy
//! writer (tracing-appender's). A reader of stdout that stalls loses stdout lines,
//! never a journal entry and never a cycle; a queue that overflows loses events. Both
//! losses are counted and reported as an `events_lost` event once there is room.

use crate::console::journal::Journal;
use serde_json::json;
use std::io::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};

/// Events queued before the sink drops them.
const QUEUE: usize = 16_384;

/// The sink's handle: cheap to clone, never blocks.
#[derive(Clone)]
pub struct EventSink {
    tx: SyncSender<serde_json::Value>,
    lost: Arc<AtomicU64>,
}

/// The running sink; [`SinkThread::finish`] drains it.
pub struct SinkThread {
    thread: std::thread::JoinHandle<()>,
    _stdout: tracing_appender::non_blocking::WorkerGuard,
}

impl EventSink {
    /// Starts the sink: the journal in `journal_dir` (created if needed), then stdout.
    pub fn start(journal_dir: Option<&Path>) -> anyhow::Result<(Self, SinkThread)> {
        let journal = match journal_dir {
            Some(dir) => Some(Journal::append_only(dir).map_err(|e| {
                anyhow::anyhow!("cannot open the journal in {}: {e}", dir.display())
            })?),
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
            .spawn(move || drain(&rx, journal, stdout, &l))?;
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
        match self.tx.try_send(event) {
            Ok(()) => {}
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.lost.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

impl SinkThread {
    /// Waits until every queued event is written (call after the last
    /// [`EventSink`] clone is dropped).
    pub fn finish(self) {
        let _ = self.thread.join();
    }
}

fn drain(
    rx: &Receiver<serde_json::Value>,
    mut journal: Option<Journal>,
    mut stdout: tracing_appender::non_blocking::NonBlocking,
    lost: &AtomicU64,
) {
    let stdout_lost = stdout.error_counter();
    let mut reported_stdout = 0;
    let mut write = |event: &serde_json::Value, journal: &mut Option<Journal>| {
        if let Some(j) = journal.as_mut() {
            let kind = event["event"].as_str().unwrap_or("event");
            let time = event["time_ms"].as_u64().unwrap_or(0);
            j.push(time, kind, &event.to_string());
            if let Some(e) = j.error.take() {
                tracing::error!("{e}");
            }
        }
        let _ = stdout.write_all(format!("{event}\n").as_bytes());
    };
    while let Ok(event) = rx.recv() {
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
            write(&e, &mut journal);
        }
        write(&event, &mut journal);
    }
}
