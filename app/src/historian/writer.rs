//! The historian's writer thread and the process recorder that feeds it.
//!
//! The cycle never waits for the disk: [`ProcessRecorder`] keeps the last value of
//! every signal and hands over only the changes, in batches; [`Writer`] queues them
//! on a bounded channel (a full queue loses the batch, counted and reported) and a
//! thread of its own commits them, one transaction per batch, and purges what is older
//! than the retention every hour.

use super::{AlarmRow, HistorianError, Retention, Sample, Store, wall_ms};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use vigie_core::history::CycleRecord;
use vigie_core::symbols::{Space, Symbols};

/// Batches queued before the writer drops them.
const QUEUE: usize = 1024;
/// How often the writer purges.
const PURGE_EVERY: Duration = Duration::from_secs(3600);

/// One change: the signal's index in the recorder's names, time (ms), value.
pub type Change = (u32, u64, i64);

/// What the writer is asked to do.
pub enum Msg {
    /// Changes of the recorder's signals.
    Samples(Vec<Change>),
    /// The latest state of these alarms.
    Alarms(Vec<AlarmRow>),
    /// Answers once everything queued before is committed.
    Flush(SyncSender<()>),
}

/// The names the process history gives a cycle's signals: the inputs and the applied
/// outputs by their names, the commanded outputs as `NAME.cmd`, then the observers.
pub fn signal_names(symbols: &Symbols) -> Vec<String> {
    let mut names: Vec<String> = symbols.names(Space::Input).to_vec();
    names.extend(symbols.names(Space::Output).iter().cloned());
    names.extend(
        symbols
            .names(Space::Output)
            .iter()
            .map(|n| format!("{n}.cmd")),
    );
    names.extend(symbols.names(Space::Observer).iter().cloned());
    names
}

/// The values of a cycle in the order of [`signal_names`].
pub fn cycle_values(rec: &CycleRecord) -> impl Iterator<Item = i64> + '_ {
    fn bits(b: &vigie_core::Bits) -> impl Iterator<Item = i64> + '_ {
        (0..b.len()).map(move |i| i64::from(b.get(i)))
    }
    bits(&rec.inputs)
        .chain(bits(&rec.applied))
        .chain(bits(&rec.commanded))
        .chain(bits(&rec.observers))
}

/// Keeps the last value of each signal and collects the changes.
#[derive(Debug)]
pub struct ProcessRecorder {
    last: Vec<Option<i64>>,
    pending: Vec<Change>,
    sent_ms: Option<u64>,
}

impl ProcessRecorder {
    /// A recorder of `n` signals (the first cycle records every value).
    pub fn new(n: usize) -> Self {
        Self {
            last: vec![None; n],
            pending: Vec::new(),
            sent_ms: None,
        }
    }

    /// Records the values at `t_ms` (in the order of the names; extra values are
    /// ignored, missing ones keep their last value).
    pub fn record(&mut self, t_ms: u64, values: impl Iterator<Item = i64>) {
        for (i, (last, v)) in self.last.iter_mut().zip(values).enumerate() {
            if *last != Some(v) {
                *last = Some(v);
                self.pending
                    .push((u32::try_from(i).unwrap_or(u32::MAX), t_ms, v));
            }
        }
    }

    /// The changes collected, when `every_ms` has passed since the last batch (or
    /// at once with `every_ms` 0).
    pub fn take_due(&mut self, t_ms: u64, every_ms: u64) -> Option<Vec<Change>> {
        let due = self
            .sent_ms
            .is_none_or(|s| t_ms.saturating_sub(s) >= every_ms);
        if !due || self.pending.is_empty() {
            return None;
        }
        self.sent_ms = Some(t_ms);
        Some(std::mem::take(&mut self.pending))
    }

    /// Forgets the last values: the next record stores every value again (a new
    /// session, a restart of the emulator).
    pub fn restart(&mut self) {
        self.last.iter_mut().for_each(|v| *v = None);
    }
}

/// The writer's handle: never blocks the caller.
pub struct Writer {
    tx: Option<SyncSender<Msg>>,
    lost: Arc<AtomicU64>,
    error: Arc<Mutex<Option<String>>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl std::fmt::Debug for Writer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Writer").finish_non_exhaustive()
    }
}

impl Writer {
    /// Starts the writer thread over `store`, for the signals `names` of `session`.
    pub fn start(
        mut store: Store,
        session: i64,
        names: &[String],
        retention: Retention,
    ) -> Result<Self, HistorianError> {
        let ids = store.signal_ids(names)?;
        let (tx, rx) = sync_channel(QUEUE);
        let lost = Arc::new(AtomicU64::new(0));
        let error = Arc::new(Mutex::new(None));
        let e = Arc::clone(&error);
        let thread = std::thread::Builder::new()
            .name("vigie-historian".into())
            .spawn(move || run(&rx, &mut store, session, &ids, retention, &e))
            .map_err(|err| HistorianError::Open {
                path: std::path::PathBuf::from(super::FILE),
                source: Box::new(err),
            })?;
        Ok(Self {
            tx: Some(tx),
            lost,
            error,
            thread: Some(thread),
        })
    }

    /// Queues `msg`; a full queue drops it and counts it.
    pub fn send(&self, msg: Msg) {
        let Some(tx) = &self.tx else { return };
        match tx.try_send(msg) {
            Ok(()) => {}
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.lost.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// Waits (at most `timeout`) until everything queued is committed; false on
    /// timeout or when the thread is gone.
    pub fn flush(&self, timeout: Duration) -> bool {
        let Some(tx) = &self.tx else { return false };
        let (ack, done) = sync_channel(1);
        if tx.send(Msg::Flush(ack)).is_err() {
            return false;
        }
        done.recv_timeout(timeout).is_ok()
    }

    /// Batches dropped so far (queue full).
    pub fn lost(&self) -> u64 {
        self.lost.load(Ordering::Relaxed)
    }

    /// The last error of the thread (a full disk, a locked file), taken.
    pub fn take_error(&self) -> Option<String> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }
}

impl Drop for Writer {
    fn drop(&mut self) {
        // Closing the channel ends the thread once the queue is written.
        self.tx = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn run(
    rx: &Receiver<Msg>,
    store: &mut Store,
    session: i64,
    ids: &[i64],
    retention: Retention,
    error: &Mutex<Option<String>>,
) {
    let report = |e: HistorianError| {
        tracing::error!("{e}");
        if let Ok(mut slot) = error.lock() {
            *slot = Some(e.to_string());
        }
    };
    let mut purged_at = std::time::Instant::now();
    if let Err(e) = store.purge(wall_ms(), &retention) {
        report(e);
    }
    loop {
        let first = match rx.recv_timeout(Duration::from_secs(60)) {
            Ok(m) => m,
            Err(RecvTimeoutError::Timeout) => {
                if purged_at.elapsed() >= PURGE_EVERY {
                    purged_at = std::time::Instant::now();
                    if let Err(e) = store.purge(wall_ms(), &retention) {
                        report(e);
                    }
                }
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => break,
        };
        // Everything already queued goes into the same transactions.
        let mut samples = Vec::new();
        let mut alarms = Vec::new();
        let mut acks = Vec::new();
        let mut next = Some(first);
        while let Some(msg) = next {
            match msg {
                Msg::Samples(changes) => {
                    samples.extend(changes.into_iter().filter_map(|(i, t_ms, value)| {
                        ids.get(i as usize).map(|&signal| Sample {
                            signal,
                            t_ms,
                            value,
                        })
                    }))
                }
                Msg::Alarms(rows) => alarms.extend(rows),
                Msg::Flush(ack) => acks.push(ack),
            }
            next = if samples.len() < 100_000 {
                rx.try_recv().ok()
            } else {
                None
            };
        }
        if let Err(e) = store.append_samples(&samples) {
            report(e);
        }
        if let Err(e) = store.upsert_alarms(session, &alarms) {
            report(e);
        }
        for a in acks {
            let _ = a.send(());
        }
        if purged_at.elapsed() >= PURGE_EVERY {
            purged_at = std::time::Instant::now();
            if let Err(e) = store.purge(wall_ms(), &retention) {
                report(e);
            }
        }
    }
}
