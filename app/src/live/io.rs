//! The I/O task of the monitor and gateway: the Modbus client on a tokio task, beside
//! the cycle thread, and the runtime's heartbeat.
//!
//! The task polls the peer `lead` before each tick and writes the outputs the cycle
//! hands it as soon as it gets them. Towards a plant (gateway) the outputs come first:
//! after every (re)connection the last outputs handed by the cycle are written before
//! anything is read, a failed read never prevents the next write (each write connects
//! when the backoff allows), and every change of what was written, or of whether the
//! plant acknowledged it, is a `plant_write` event: the journal says what the plant
//! really received.
//!
//! The heartbeat is a tick of the runtime every half cycle: while the runtime itself is
//! late (a loaded machine), a peer's silence is not held against it (see
//! [`vigie_core::live::age::Watchdog::check_seen`]).

use super::link::{ClientStatus, Reader, Writer};
use super::runtime::{Clock, bits_text};
use serde_json::json;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{mpsc, oneshot, watch};
use vigie_core::live::age::AgedBits;
use vigie_core::{Bits, Millis};

use super::cycle::{lock, next_tick, poll_lead, tick_at};

/// What the I/O task publishes for the cycle.
pub(crate) struct PeerSide {
    pub(crate) inputs: AgedBits,
    pub(crate) outputs: AgedBits,
    /// When every due block was last read.
    pub(crate) heard: Option<Millis>,
    /// A request failed (or the link is down) since the peer was last heard.
    pub(crate) failed: bool,
    pub(crate) status: ClientStatus,
}

/// The client: read-only (monitor) or reading and writing (gateway).
pub(crate) enum PeerClient {
    Monitor(Reader),
    Plant(Writer),
}

impl PeerClient {
    async fn poll(&mut self, now: Millis, inputs: &mut AgedBits, outputs: &mut AgedBits) -> bool {
        match self {
            Self::Monitor(r) => r.poll(now, inputs, outputs).await,
            Self::Plant(w) => w.poll(now, inputs).await,
        }
    }

    fn status(&self) -> &ClientStatus {
        match self {
            Self::Monitor(r) => r.status(),
            Self::Plant(w) => w.status(),
        }
    }

    pub(crate) fn is_connected(&self) -> bool {
        self.status().connected
    }
}

/// The outputs to write to the plant and what became of them.
#[derive(Default)]
struct Outputs {
    /// The last outputs handed by the cycle.
    latest: Option<Bits>,
    /// The connection on which `latest` was acknowledged.
    acked_on: Option<u64>,
    /// What the last `plant_write` event said.
    reported: Option<(Bits, bool)>,
}

impl Outputs {
    /// Writes `latest` (connecting when the backoff allows) and reports a change.
    async fn write(
        &mut self,
        w: &mut Writer,
        clock: &Clock,
        events: &mpsc::Sender<serde_json::Value>,
    ) {
        let Some(values) = self.latest.clone() else {
            return;
        };
        let now = clock.now();
        let result = w.write(now, &values).await;
        let acknowledged = result.is_ok();
        self.acked_on = acknowledged.then(|| w.connection());
        let report = (values, acknowledged);
        if self.reported.as_ref() != Some(&report) {
            let mut e = json!({
                "event": "plant_write", "outputs": bits_text(&report.0),
                "acknowledged": acknowledged, "time_ms": now.0,
            });
            if let Err(why) = result {
                e["error"] = json!(why);
            }
            if events.try_send(e).is_err() {
                tracing::warn!("plant_write event dropped: the event queue is full");
            }
            self.reported = Some(report);
        }
    }

    /// True when `latest` has not been acknowledged on the current connection.
    fn due(&self, w: &Writer) -> bool {
        self.latest.is_some() && (!w.is_connected() || self.acked_on != Some(w.connection()))
    }
}

async fn changed(rx: &mut Option<watch::Receiver<Option<Bits>>>) -> bool {
    match rx {
        Some(r) => r.changed().await.is_ok(),
        None => std::future::pending().await,
    }
}

/// Where the I/O task reports.
pub(crate) struct IoLinks {
    pub(crate) side: Arc<Mutex<PeerSide>>,
    /// Outputs handed by the cycle (gateway).
    pub(crate) out: Option<watch::Receiver<Option<Bits>>>,
    /// Events (`plant_write`).
    pub(crate) events: mpsc::Sender<serde_json::Value>,
}

/// The I/O task: polls the peer `lead` before each tick, writes the outputs handed
/// through `out` at once (gateway), publishes into `side`, until `stop`. Returns the
/// client (for the last write of the safe outputs).
async fn peer_io(
    mut client: PeerClient,
    links: IoLinks,
    mut stop: oneshot::Receiver<()>,
    clock: Clock,
    period: Duration,
) -> PeerClient {
    let IoLinks {
        side,
        mut out,
        events,
    } = links;
    let lead = poll_lead(period);
    let (mut inputs, mut outputs) = {
        let s = lock(&side);
        (s.inputs.clone(), s.outputs.clone())
    };
    let mut pending = Outputs::default();
    let mut k: u64 = 1;
    enum Wake {
        Stop,
        Write,
        OutputsGone,
        Poll,
    }
    loop {
        let target = tick_at(clock.0, period, k)
            .checked_sub(lead)
            .unwrap_or(clock.0);
        let wake = tokio::select! {
            biased;
            _ = &mut stop => Wake::Stop,
            ok = changed(&mut out) => if ok { Wake::Write } else { Wake::OutputsGone },
            () = tokio::time::sleep_until(target.into()) => Wake::Poll,
        };
        match wake {
            Wake::Stop => break,
            Wake::OutputsGone => out = None,
            Wake::Write => {
                pending.latest = out.as_mut().and_then(|r| r.borrow_and_update().clone());
                if let PeerClient::Plant(w) = &mut client {
                    pending.write(w, &clock, &events).await;
                }
                lock(&side).status.clone_from(client.status());
            }
            Wake::Poll => {
                // Outputs first: a new connection gets the last outputs before any read,
                // and only the write connects (the poll below must not open a
                // connection when the backoff ends between the two and read first).
                if let PeerClient::Plant(w) = &mut client
                    && pending.due(w)
                {
                    pending.write(w, &clock, &events).await;
                    if !w.is_connected() {
                        let mut s = lock(&side);
                        s.failed = true;
                        s.status.clone_from(w.status());
                        drop(s);
                        k = next_poll(&clock, period, lead, k);
                        continue;
                    }
                }
                let now = clock.now();
                let ok = client.poll(now, &mut inputs, &mut outputs).await;
                {
                    let mut s = lock(&side);
                    s.inputs.clone_from(&inputs);
                    s.outputs.clone_from(&outputs);
                    if ok {
                        s.heard = Some(now);
                        s.failed = false;
                    } else {
                        s.failed = true;
                    }
                    s.status.clone_from(client.status());
                }
                k = next_poll(&clock, period, lead, k);
            }
        }
    }
    client
}

/// The tick after poll `k`: the next one, or the first not yet past when polls ran late.
fn next_poll(clock: &Clock, period: Duration, lead: Duration, k: u64) -> u64 {
    let due = next_tick(
        Instant::now().saturating_duration_since(clock.0) + lead,
        period,
    );
    (k + 1).max(due)
}

/// The runtime's heartbeat: the time (ms since the start of the run) at which the
/// runtime last ran a tick, every half cycle.
#[derive(Clone, Debug, Default)]
pub(crate) struct Heartbeat(Arc<AtomicU64>);

impl Heartbeat {
    /// When the runtime last ran.
    pub(crate) fn seen(&self) -> Millis {
        Millis(self.0.load(Ordering::Acquire))
    }

    /// Starts the heartbeat task on the current runtime, until `stop` is dropped.
    pub(crate) fn start(clock: Clock, period: Duration) -> (Self, oneshot::Sender<()>) {
        let beat = Self::default();
        let (tx, mut rx) = oneshot::channel::<()>();
        let b = beat.clone();
        tokio::spawn(async move {
            let mut interval = tokio::time::interval((period / 2).max(Duration::from_millis(1)));
            interval.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
            loop {
                tokio::select! {
                    biased;
                    _ = &mut rx => break,
                    _ = interval.tick() => b.0.store(clock.now().0, Ordering::Release),
                }
            }
        });
        (beat, tx)
    }
}

/// The running I/O task.
pub(crate) struct PeerIo {
    pub(crate) side: Arc<Mutex<PeerSide>>,
    pub(crate) heartbeat: Heartbeat,
    stop: oneshot::Sender<()>,
    stop_beat: oneshot::Sender<()>,
    task: tokio::task::JoinHandle<PeerClient>,
}

impl PeerIo {
    /// Starts the I/O task and the heartbeat.
    pub(crate) fn start(
        client: PeerClient,
        (n_in, n_out): (usize, usize),
        out: Option<watch::Receiver<Option<Bits>>>,
        events: mpsc::Sender<serde_json::Value>,
        clock: Clock,
        period: Duration,
    ) -> Self {
        let side = Arc::new(Mutex::new(PeerSide {
            inputs: AgedBits::new(n_in),
            outputs: AgedBits::new(n_out),
            heard: None,
            failed: false,
            status: ClientStatus::default(),
        }));
        let (heartbeat, stop_beat) = Heartbeat::start(clock, period);
        let (stop, stop_rx) = oneshot::channel();
        let links = IoLinks {
            side: Arc::clone(&side),
            out,
            events,
        };
        let task = tokio::spawn(peer_io(client, links, stop_rx, clock, period));
        Self {
            side,
            heartbeat,
            stop,
            stop_beat,
            task,
        }
    }

    /// Stops the task and returns the client.
    pub(crate) async fn stop(self) -> anyhow::Result<PeerClient> {
        let _ = self.stop.send(());
        let _ = self.stop_beat.send(());
        self.task
            .await
            .map_err(|e| anyhow::anyhow!("the I/O task failed: {e}"))
    }
}
