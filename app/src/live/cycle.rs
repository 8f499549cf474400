//! The monitor and gateway cycles, and how they are timed.
//!
//! The cycle runs on a thread of its own (`vigie-cycle`) at the absolute deadlines
//! `epoch + k·cycle` (missed deadlines are skipped, never run in a burst), slept with
//! the OS's high-resolution timer: tokio's timer wheel has a granularity of one
//! millisecond, too coarse for a period jitter under 1 ms. The cycle never waits for
//! the network: the Modbus client lives on a tokio task (`peer_io`) that polls the
//! peer `lead` before each tick (so the cycle finds values a few milliseconds old,
//! stamped with their read time) and writes the outputs the cycle hands it as soon as
//! it gets them. Events go back to the async side through a bounded channel.

use super::io::{Heartbeat, PeerClient, PeerIo, PeerSide};
use super::latch::LatchStore;
use super::link::{Reader, ServerHandle, Writer, serve_plc};
use super::modbus::server::SharedImage;
use super::runtime::{
    AlarmBoard, Clock, CycleStats, Emit, Explainer, Setup, bits_text, emit_engine_events, names,
};
use super::sink::LiveHistory;
use super::tap::Tap;
use anyhow::Context as _;
use serde_json::json;
use std::future::Future;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};
use tokio::sync::{mpsc, oneshot, watch};
use vigie_core::alarms::{AlarmKind, AlarmList};
use vigie_core::bundle::PlantBundle;
use vigie_core::engine::{Commanded, Engine, FilterMode};
use vigie_core::live::age::{AgedBits, Watchdog};
use vigie_core::live::follow::{self, Follower};
use vigie_core::live::stale::StaleGuard;
use vigie_core::pop::Diagnosers;
use vigie_core::pop::build::Compiled;
use vigie_core::sim::ObservedCycle;
use vigie_core::sim::diagnosis::{
    Cooperation, LinkGate, LinkStep, estimated_frame, estimated_inputs, run_link_step, substitute,
    take_notices,
};
use vigie_core::symbols::Space;
use vigie_core::{Bits, Millis};

/// Events the cycle thread may queue for the async side before it drops them.
const EVENT_QUEUE: usize = 4096;

pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A poisoned lock (a panic elsewhere) still holds usable data.
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// How long before a tick the peer is polled: a third of the cycle, at most 3 ms.
pub(crate) fn poll_lead(period: Duration) -> Duration {
    (period / 3).min(Duration::from_millis(3))
}

/// One cycle's work, run on the cycle thread.
trait Cycle: Send + 'static {
    /// What the thread hands back when it stops.
    type Done: Send + 'static;
    /// One cycle started at `start`.
    fn step(&mut self, start: Instant);
    /// The last work after the stop request.
    fn finish(self) -> Self::Done;
}

/// Sleeps until `deadline` with the OS timer (nanosleep: microsecond resolution).
fn sleep_until(deadline: Instant) {
    let now = Instant::now();
    if deadline > now {
        std::thread::sleep(deadline - now);
    }
}

/// The index of the first tick strictly after `elapsed` (ticks at multiples of `period`).
pub(crate) fn next_tick(elapsed: Duration, period: Duration) -> u64 {
    let p = period.as_nanos().max(1);
    u64::try_from(elapsed.as_nanos() / p + 1).unwrap_or(u64::MAX)
}

pub(crate) fn tick_at(epoch: Instant, period: Duration, k: u64) -> Instant {
    let nanos = u64::try_from(period.as_nanos())
        .unwrap_or(u64::MAX)
        .saturating_mul(k);
    epoch + Duration::from_nanos(nanos)
}

/// The real-time priority a run asks for: the configured one, or by default 50 for the
/// cycle thread (49 for the I/O runtime), taken when the process may have it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Priority {
    pub(crate) value: u8,
    /// Configured explicitly: a refusal is a warning, not a note.
    pub(crate) explicit: bool,
}

impl Priority {
    /// From the configuration: `cycle_priority`, else the default unless `realtime:
    /// false`.
    pub(crate) fn of(config: &vigie_core::live::config::GatewayConfig) -> Option<Self> {
        match (config.cycle_priority, config.realtime) {
            (Some(value), _) => Some(Self {
                value,
                explicit: true,
            }),
            (None, true) => Some(Self {
                value: 50,
                explicit: false,
            }),
            (None, false) => None,
        }
    }

    /// The cycle thread's priority of `config`, the I/O runtime's thread (the
    /// caller's) raised one step below it.
    pub(crate) fn raise_io(config: &vigie_core::live::config::GatewayConfig) -> Option<Self> {
        let priority = Self::of(config);
        if let Some(p) = priority {
            raise_priority(p.below(), "I/O runtime thread");
        }
        priority
    }

    /// One step below, for the I/O runtime's thread.
    pub(crate) fn below(self) -> Self {
        Self {
            value: self.value.saturating_sub(1).max(1),
            ..self
        }
    }
}

/// Gives the calling thread (named `what` in the log) the real-time priority
/// (SCHED_FIFO); a refusal (no right to raise priorities) is logged, and the thread
/// keeps its priority.
pub(crate) fn raise_priority(priority: Priority, what: &str) {
    use thread_priority::{
        RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue, ThreadSchedulePolicy,
    };
    let p = priority.value;
    let result = ThreadPriorityValue::try_from(p)
        .map_err(|e| e.to_string())
        .and_then(|value| {
            thread_priority::set_thread_priority_and_policy(
                thread_priority::thread_native_id(),
                ThreadPriority::Crossplatform(value),
                ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
            )
            .map_err(|e| format!("{e:?}"))
        });
    match result {
        Ok(()) => tracing::info!("{what} at real-time priority {p} (SCHED_FIFO)"),
        Err(e) if priority.explicit => {
            tracing::warn!("{what} left at normal priority: real-time priority {p} refused ({e})")
        }
        Err(e) => tracing::info!(
            "{what} at normal priority (real-time priority {p} not granted: {e}; grant CAP_SYS_NICE for a jitter under 1 ms on a loaded machine)"
        ),
    }
}

/// Runs `c` on the cycle thread at `epoch + k·period` for k = 1, 2, … until `stop`,
/// at the real-time `priority` when one is given.
fn spawn_cycles<C: Cycle>(
    epoch: Instant,
    period: Duration,
    priority: Option<Priority>,
    stop: Arc<AtomicBool>,
    mut c: C,
) -> anyhow::Result<oneshot::Receiver<(C::Done, CycleStats)>> {
    let (tx, rx) = oneshot::channel();
    std::thread::Builder::new()
        .name("vigie-cycle".into())
        .spawn(move || {
            if let Some(p) = priority {
                raise_priority(p, "cycle thread");
            }
            let mut stats = CycleStats::default();
            let mut k = 1;
            loop {
                sleep_until(tick_at(epoch, period, k));
                if stop.load(Ordering::Acquire) {
                    break;
                }
                let start = Instant::now();
                c.step(start);
                stats.record(start);
                let due = next_tick(Instant::now().saturating_duration_since(epoch), period);
                k = (k + 1).max(due);
            }
            let _ = tx.send((c.finish(), stats));
        })
        .context("cannot start the cycle thread")?;
    Ok(rx)
}

/// Forwards the cycle thread's events to `emit` until `shutdown`, then stops the thread
/// and returns what it handed back (the remaining events are forwarded too).
async fn supervise<D>(
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    events: &mut mpsc::Receiver<serde_json::Value>,
    stop: &AtomicBool,
    done: oneshot::Receiver<(D, CycleStats)>,
) -> anyhow::Result<(D, CycleStats)> {
    tokio::pin!(shutdown);
    tokio::pin!(done);
    let result = loop {
        tokio::select! {
            biased;
            () = &mut shutdown => {
                stop.store(true, Ordering::Release);
                break (&mut done).await;
            }
            r = &mut done => break r,
            Some(e) = events.recv() => emit(e),
        }
    };
    while let Ok(e) = events.try_recv() {
        emit(e);
    }
    result.map_err(|_| anyhow::anyhow!("the cycle thread stopped unexpectedly"))
}

fn event_sender(tx: mpsc::Sender<serde_json::Value>) -> Box<dyn FnMut(serde_json::Value) + Send> {
    let mut dropped = 0_u64;
    Box::new(move |e| {
        if tx.try_send(e).is_err() {
            dropped += 1;
            if dropped.is_power_of_two() {
                tracing::warn!("{dropped} events dropped: the event queue is full");
            }
        }
    })
}

/// The plant's task monitors (seed 000), stepped after the filter every cycle from the
/// second one on, their outputs published for the constraints of the next cycle, as
/// the console's `Simulation` does.
struct LiveTasks {
    set: vigie_core::tasks::TaskSet,
    monitor: vigie_core::tasks::Monitor,
    events: vigie_core::tasks::FrameTasks,
    seen: usize,
}

impl LiveTasks {
    fn new(bundle: &PlantBundle) -> Option<Self> {
        let set = bundle.tasks.as_ref()?;
        match vigie_core::tasks::FrameTasks::compile(set, &bundle.symbols) {
            Ok(events) => Some(Self {
                set: set.clone(),
                monitor: vigie_core::tasks::Monitor::new(set, Millis::ZERO),
                events,
                seen: 0,
            }),
            Err(p) => {
                tracing::warn!("task monitors off: {}", vigie_core::diag::render(&p));
                None
            }
        }
    }

    /// One cycle of the task monitors; in degraded mode they read the sensors the
    /// diagnosers estimate from their estimates, as the program does.
    fn step(
        &mut self,
        engine: &mut Engine,
        now: Millis,
        diagnosers: Option<&LiveDiagnosers>,
        board: &mut AlarmBoard,
        emit: Emit<'_>,
    ) {
        if engine.cycles() <= 1 {
            return;
        }
        let estimated = diagnosers.map_or(&[][..], |d| &d.estimated[..]);
        match estimated_frame(estimated, engine.frame()) {
            None => self.events.step(&mut self.monitor, now, engine.frame()),
            Some(f) => self.events.step(&mut self.monitor, now, &f),
        }
        self.events.publish(&self.monitor, engine.frame_mut());
        let new = self.monitor.alarms.get(self.seen..).unwrap_or_default();
        for a in new {
            if a.severity == vigie_core::tasks::Severity::Warning {
                emit(json!({"event": "task_warning", "text": a.text, "time_ms": a.time.0}));
            } else {
                let key = format!("task:{}:{:?}", a.subject, a.code);
                let text = vigie_core::alarms::texts::task(Some(&self.set), a);
                board.raise(emit, a.time, &key, AlarmKind::Task, text);
            }
        }
        self.seen = self.monitor.alarms.len();
    }
}

/// The plant's diagnosers in a live cycle, stepped after the filter (and the gateway's
/// safe outputs) on the outputs really applied, from the first cycle that shows the
/// plant in its initial state and not while the peer is lost (`LinkGate`), as the
/// simulation steps them (`vigie_core::sim::diagnosis`): their flags, intervals and
/// estimates are read by the rewritten constraints from the next cycle on; each
/// certain diagnosis is a `diagnosis` event and a `diag:` alarm, each start, suspension
/// or restart a `diagnosers` event.
struct LiveDiagnosers {
    diagnosers: Diagnosers,
    gate: LinkGate,
    seen: usize,
    acts: Cooperation,
    /// Sensors read from their estimates: (input, auxiliary of the estimate).
    estimated: Vec<(usize, usize)>,
    /// The operator asked to clear the fault flags; done at the next stepped cycle.
    reset_pending: bool,
}

/// The plausibility stage's notices of this cycle as events and alarms: an alarm
/// `plausibility:<sensor>` while a sensor is suspect (an edge its physics does not allow
/// held), cleared when its reading is plausible again.
fn plausibility_events(
    engine: &mut Engine,
    plant: &vigie_core::plant::Plant,
    board: &mut AlarmBoard,
    emit: Emit<'_>,
) {
    for n in engine.plausibility.take_notices() {
        let key = format!("plausibility:{}", n.sensor);
        let now = Millis(n.time_ms);
        if n.suspect {
            let text = vigie_core::alarms::texts::plausibility(plant, &n);
            board.raise(emit, now, &key, AlarmKind::Plausibility, text);
        } else {
            emit(
                json!({"event": "plausibility", "sensor": n.sensor, "text": n.text, "time_ms": n.time_ms}),
            );
            if board
                .alarms
                .active_keys(AlarmKind::Plausibility)
                .contains(&key)
            {
                board.clear(emit, now, &key);
            }
        }
    }
}

/// The engine with the sensors the diagnosers estimate (a flagged sensor is read from
/// its estimate by the observers and the constraints) and the plausibility stage on or
/// off as configured.
fn with_estimates(
    mut engine: Engine,
    compiled: Option<&vigie_core::pop::build::Compiled>,
    bundle: &PlantBundle,
    plausibility: bool,
) -> Engine {
    engine.set_plausibility(plausibility);
    if let Some(c) = compiled {
        engine.set_estimates(vigie_core::sim::diagnosis::estimate_map(
            c,
            &bundle.plant,
            &bundle.symbols,
        ));
    }
    engine
}

impl LiveDiagnosers {
    fn new(compiled: Option<Compiled>, bundle: &PlantBundle, acts: Cooperation) -> Option<Self> {
        Some(Self {
            diagnosers: Diagnosers::new(compiled?, &bundle.symbols),
            gate: LinkGate::default(),
            seen: 0,
            acts,
            estimated: Vec::new(),
            reset_pending: false,
        })
    }

    /// Steps the diagnosers (when `usable`; first clearing their flags when the
    /// operator asked, `reset_asked`) and reports their new certain diagnoses; returns
    /// what was done, for the console's mirror.
    fn step(
        &mut self,
        engine: &mut Engine,
        usable: bool,
        reset_asked: bool,
        bundle: &PlantBundle,
        board: &mut AlarmBoard,
        emit: Emit<'_>,
    ) -> LinkStep {
        let now = engine.now();
        self.reset_pending |= reset_asked;
        let (mut step, change) = self.gate.step(usable, &self.diagnosers, engine.frame());
        if let Some(change) = change {
            tracing::info!("diagnosers {change:?} at {now}");
            emit(json!({"event": "diagnosers", "state": change, "time_ms": now.0}));
        }
        // The operator's reset after a repair: the flags are cleared and the models
        // restart from the observed values (the mirror does the same on `Restarted`).
        if self.reset_pending && step == LinkStep::Stepped {
            self.reset_pending = false;
            step = LinkStep::Restarted;
            self.estimated.clear();
            for key in board.alarms.active_keys(AlarmKind::Diagnosis) {
                board.clear(emit, now, &key);
            }
            tracing::info!("diagnosers reset by the operator at {now}");
            emit(json!({"event": "diagnosers_reset", "time_ms": now.0}));
        }
        let d = &mut self.diagnosers;
        engine.after_filter(&mut |t, f, held| run_link_step(d, step, t, f, held));
        let notices = take_notices(&self.diagnosers, &mut self.seen, self.acts);
        if notices.is_empty() {
            return step;
        }
        self.estimated = estimated_inputs(&self.diagnosers, &bundle.plant, &bundle.symbols);
        for n in notices {
            let mut line = serde_json::to_value(&n.diagnosis).unwrap_or_default();
            line["event"] = json!("diagnosis");
            line["stop"] = json!(n.stop);
            line["estimated"] = json!(n.estimated);
            line["text"] = json!(n.text);
            emit(line);
            let text = vigie_core::alarms::texts::diagnosis(&bundle.plant, &n, self.acts);
            board.raise(emit, now, &n.key, AlarmKind::Diagnosis, text);
        }
        step
    }

    /// The certain diagnoses so far.
    fn diagnoses(this: Option<&Self>) -> Vec<vigie_core::pop::Diagnosis> {
        this.map(|d| d.diagnosers.diagnoses.clone())
            .unwrap_or_default()
    }
}

/// How the cycles tell a late peer from a lost one (see
/// [`Watchdog::check_seen`]): the request timeout as the grace of a request in flight,
/// and a hard bound of four times the link timeout plus the request timeout.
#[derive(Clone, Copy, Debug)]
struct Liveness {
    grace: Millis,
    link: Millis,
    hard: Millis,
}

impl Liveness {
    fn of(config: &vigie_core::live::config::GatewayConfig, request_timeout_ms: u64) -> Self {
        let grace = Millis(request_timeout_ms);
        Self {
            grace,
            link: config.link_timeout(),
            hard: Millis((config.link_timeout() + grace).0.saturating_mul(4)),
        }
    }

    /// A polled peer: a request in flight gets the grace.
    fn check(
        self,
        dog: &mut Watchdog,
        now: Millis,
        beat: &Heartbeat,
        failed: bool,
    ) -> Option<vigie_core::live::age::Transition> {
        dog.check_seen(now, beat.seen(), failed, self.grace, self.hard)
    }

    /// The PLC, which writes to us, its silence measured up to the runtime's
    /// heartbeat: while its connection is open (a PLC late on a loaded machine) it gets
    /// one more link timeout; a closed connection (a PLC that died) none.
    fn check_plc(
        self,
        dog: &mut Watchdog,
        now: Millis,
        beat: &Heartbeat,
        connected: bool,
    ) -> Option<vigie_core::live::age::Transition> {
        dog.check_seen(now, beat.seen(), !connected, self.link, self.hard)
    }
}

/// The monitor's cycle.
struct MonitorCycle {
    clock: Clock,
    /// Attach to the running plant at the first values read (`first_cycle: Attach`).
    attach: bool,
    /// The engine attaches in this cycle (for the console's mirror).
    attached_now: bool,
    peer: String,
    side: Arc<Mutex<PeerSide>>,
    beat: Heartbeat,
    liveness: Liveness,
    bundle: PlantBundle,
    layout: Option<vigie_core::emulator::Layout>,
    engine: Engine,
    guard: StaleGuard,
    control: Commanded,
    inputs: AgedBits,
    outputs: AgedBits,
    bounds: Vec<Millis>,
    dog: Watchdog,
    heard: Option<Millis>,
    board: AlarmBoard,
    last_potential: Vec<String>,
    last_spec: Option<String>,
    tasks: Option<LiveTasks>,
    diagnosers: Option<LiveDiagnosers>,
    emit: Box<dyn FnMut(serde_json::Value) + Send>,
    tap: Option<Tap>,
    /// The process history (`vigie gateway`).
    history: Option<LiveHistory>,
    /// The program the PLC should run, followed beside it (`--program`); dropped when
    /// the peer is lost (the cycles missed would make a false divergence).
    follower: Option<Follower>,
    /// The first cycle followed was announced (`program_following`).
    following: bool,
}

impl Cycle for MonitorCycle {
    type Done = Vec<vigie_core::pop::Diagnosis>;

    fn step(&mut self, start: Instant) {
        let now = self.clock.at(start);
        let status = self.listen(now);
        self.control.0.copy_from(self.outputs.values());
        self.engine
            .cycle(now, self.inputs.values(), &mut self.control);
        // The program follows this cycle before its trips are explained: they read it.
        let usable = self.heard.is_some() && !self.dog.is_lost();
        let followed = self.follow(now, usable);
        let explainer = Explainer {
            bundle: &self.bundle,
            layout: self.layout.as_ref(),
            program: self.follower.as_ref().and_then(Follower::program),
        };
        emit_engine_events(
            &mut self.engine,
            &mut *self.emit,
            Some(&explainer),
            &mut self.last_spec,
        );
        let reset_asked = self.tap.as_ref().is_some_and(Tap::take_diagnosers_reset);
        let diagnosers = match &mut self.diagnosers {
            Some(d) => d.step(
                &mut self.engine,
                usable,
                reset_asked,
                &self.bundle,
                &mut self.board,
                &mut *self.emit,
            ),
            None => LinkStep::Skipped,
        };
        plausibility_events(
            &mut self.engine,
            &self.bundle.plant,
            &mut self.board,
            &mut *self.emit,
        );
        if let Some(t) = &mut self.tasks {
            let d = self.diagnosers.as_ref();
            t.step(&mut self.engine, now, d, &mut self.board, &mut *self.emit);
        }
        let stale = self.inputs.stale(now, &self.bounds);
        let verdict = self.guard.check(self.engine.frame(), &stale);
        if verdict.potentially_violated != self.last_potential {
            if !verdict.potentially_violated.is_empty() {
                tracing::warn!(
                    "potentially violated with stale inputs: {}",
                    verdict.potentially_violated.join(", ")
                );
                (self.emit)(json!({
                    "event": "potential_violation",
                    "constraints": verdict.potentially_violated,
                    "stale_inputs": names(&self.bundle, Space::Input, &stale),
                    "time_ms": now.0,
                }));
            }
            self.last_potential = verdict.potentially_violated;
        }
        if let Some(h) = &mut self.history
            && let Some(rec) = self.engine.history.last()
        {
            h.record(rec);
        }
        if let Some(tap) = &self.tap {
            let stale_names = names(&self.bundle, Space::Input, &stale);
            let cycles = self.engine.cycles();
            tap.push_cycle(
                ObservedCycle {
                    time: now,
                    inputs: self.inputs.values().clone(),
                    commanded: self.outputs.values().clone(),
                    applied: self.outputs.values().clone(),
                    reset: false,
                    diagnosers,
                    attach: std::mem::take(&mut self.attached_now),
                    restored: None,
                    followed,
                },
                |st| {
                    st.client = status;
                    st.now = now;
                    st.cycles = cycles;
                    st.stale_inputs = stale_names;
                },
            );
        }
    }

    fn finish(mut self) -> Self::Done {
        if let Some(h) = &mut self.history {
            h.finish();
        }
        LiveDiagnosers::diagnoses(self.diagnosers.as_ref())
    }
}

impl MonitorCycle {
    /// One cycle of the program's follower: a divergence is a `program_divergence`
    /// event and the `program:divergence` alarm; a lost peer ends the following.
    /// True when the follower stepped (the console's mirror steps its own then).
    fn follow(&mut self, now: Millis, usable: bool) -> bool {
        let Some(f) = &mut self.follower else {
            return false;
        };
        if !usable {
            if self.heard.is_some() {
                (self.emit)(json!({
                    "event": "program_follow_stopped",
                    "reason": "the peer was lost: the cycles missed cannot be followed",
                    "time_ms": now.0,
                }));
                self.follower = None;
            }
            return false;
        }
        if !self.following {
            // From this cycle on, the PLC's program should be in its initial situation.
            (self.emit)(json!({"event": "program_following", "time_ms": now.0}));
            self.following = true;
        }
        if let Some(d) = f.step(now, self.inputs.values(), self.outputs.values()) {
            tracing::error!("{}", d.message());
            (self.emit)(json!({
                "event": "program_divergence",
                "output": d.output,
                "plc": d.plc,
                "program": d.program,
                "program_name": d.program_name,
                "version": d.version,
                "time_ms": now.0,
            }));
            self.board.raise(
                &mut *self.emit,
                now,
                "program:divergence",
                AlarmKind::Program,
                d.alarm_text(),
            );
        }
        true
    }

    /// Takes the peer's latest values and watches its liveness (attaching the engine
    /// when it is first heard); returns the client's status.
    fn listen(&mut self, now: Millis) -> super::link::ClientStatus {
        let (heard, failed, status) = {
            let s = lock(&self.side);
            self.inputs.clone_from(&s.inputs);
            self.outputs.clone_from(&s.outputs);
            (s.heard, s.failed, s.status.clone())
        };
        let what = format!("monitored peer {}", self.peer);
        if heard != self.heard {
            if self.heard.is_none() && self.attach {
                self.engine.attach_next_cycle();
                self.attached_now = true;
            }
            self.heard = heard;
            if let Some(h) = heard {
                let t = self.dog.heard(h);
                self.board
                    .watch(&mut *self.emit, now, "link:peer", &what, t);
            }
        }
        let t = self.liveness.check(&mut self.dog, now, &self.beat, failed);
        self.board
            .watch(&mut *self.emit, now, "link:peer", &what, t);
        status
    }
}

pub(crate) async fn monitor(
    setup: Setup,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
    tap: Option<Tap>,
) -> anyhow::Result<()> {
    let Setup {
        config,
        bundle,
        client_map,
        server_map: _,
        diagnosers,
        state_dir,
        history,
        program,
    } = setup;
    let (client, map) = config
        .client
        .clone()
        .zip(client_map)
        .context("monitor mode needs a client section")?;
    let clock = Clock(Instant::now());
    let period = Duration::from_millis(config.cycle_ms.max(1));
    let priority = Priority::raise_io(&config);
    let (peer, protocol) = (client.peer(), client.describe());
    let liveness = Liveness::of(&config, client.timeout_ms());
    let (n_in, n_out) = (bundle.plant.inputs.len(), bundle.plant.outputs.len());
    let (tx, mut events) = mpsc::channel(EVENT_QUEUE);
    let pki = super::opcua::pki::folder(&state_dir);
    let reader = PeerClient::Monitor(Reader::new(client, map.clone(), true, &pki, clock.0)?);
    let io = PeerIo::start(reader, (n_in, n_out), None, tx.clone(), clock, period);
    if let Some(t) = &tap {
        t.update(|s| {
            s.peer = Some(peer.clone());
            s.protocol = Some(protocol);
        });
    }
    emit(json!({
        "event": "monitoring", "peer": peer.clone(), "diagnosers": diagnosers.is_some(),
        "program": program.as_ref().map(|p| format!("{} (version {})", p.program.name, p.program.version())),
    }));
    let stop = Arc::new(AtomicBool::new(false));
    let cycle = MonitorCycle {
        clock,
        attach: config.first_cycle == vigie_core::engine::FirstCycle::Attach,
        attached_now: false,
        peer,
        side: Arc::clone(&io.side),
        beat: io.heartbeat.clone(),
        liveness,
        layout: vigie_core::machine::Description::load(&bundle.dir)
            .ok()
            .and_then(|d| d.layout()),
        engine: with_estimates(
            {
                // The PLC drives the safety devices; the monitor writes nothing.
                let mut e = Engine::new(&bundle, FilterMode::ReportOnly, 6000);
                e.observe_safety_devices();
                e
            },
            diagnosers.as_ref(),
            &bundle,
            config.plausibility,
        ),
        guard: StaleGuard::new(&bundle),
        control: Commanded(Bits::zeros(n_out)),
        inputs: AgedBits::new(n_in),
        outputs: AgedBits::new(n_out),
        bounds: map.input_bounds(),
        dog: Watchdog::new(config.link_timeout(), Millis::ZERO),
        heard: None,
        board: AlarmBoard {
            alarms: AlarmList::new(),
            tap: tap.clone(),
        },
        last_potential: Vec::new(),
        last_spec: None,
        tasks: LiveTasks::new(&bundle),
        // Report-only: the stop is reported, the PLC reads its own sensors.
        diagnosers: LiveDiagnosers::new(
            diagnosers,
            &bundle,
            Cooperation {
                stop: false,
                estimate: false,
            },
        ),
        emit: event_sender(tx),
        tap: tap.clone(),
        history,
        follower: program.map(|p| Follower::new(p, &bundle.plant, follow::TOLERANCE)),
        following: false,
        bundle,
    };
    let done = spawn_cycles(clock.0, period, priority, Arc::clone(&stop), cycle)?;
    let result = supervise(shutdown, emit, &mut events, &stop, done).await;
    let client = io.stop().await?;
    let (diagnoses, cycle_stats) = result?;
    *stats = cycle_stats;
    if let Some(t) = &tap {
        t.update(|s| s.running = false);
    }
    emit(json!({
        "event": "stopped", "connected": client.is_connected(), "diagnoses": diagnoses,
    }));
    Ok(())
}

/// The gateway's cycle.
struct GatewayCycle {
    clock: Clock,
    /// Attach to the running plant at the first values read (`first_cycle: Attach`).
    attach: bool,
    /// The engine attaches in this cycle (for the console's mirror).
    attached_now: bool,
    plant_peer: String,
    side: Arc<Mutex<PeerSide>>,
    beat: Heartbeat,
    liveness: Liveness,
    /// Saves the latch before its events are released.
    latch: LatchStore,
    /// The latch state last handed to `latch`.
    latched: bool,
    /// A trip restored at start, for the console's mirror (sent with the first cycle).
    restored: Option<vigie_core::engine::Trip>,
    shared: SharedImage,
    out: watch::Sender<Option<Bits>>,
    bundle: PlantBundle,
    engine: Engine,
    guard: StaleGuard,
    control: Commanded,
    inputs: AgedBits,
    bounds: Vec<Millis>,
    plant_dog: Watchdog,
    plant_heard: Option<Millis>,
    plc_dog: Watchdog,
    plc_last: Option<Instant>,
    board: AlarmBoard,
    safe_reason: Option<String>,
    last_spec: Option<String>,
    tasks: Option<LiveTasks>,
    diagnosers: Option<LiveDiagnosers>,
    auto_reset: bool,
    emit: Box<dyn FnMut(serde_json::Value) + Send>,
    tap: Option<Tap>,
    /// The process history (`vigie gateway`).
    history: Option<LiveHistory>,
}

impl GatewayCycle {
    /// The outputs safe whatever the stale inputs are and whatever the PLC commands.
    fn safe_now(&mut self, now: Millis) -> Bits {
        let stale = self.inputs.stale(now, &self.bounds);
        let frame = self.engine.frame();
        self.guard
            .safe_outputs(frame, &stale)
            .unwrap_or_else(|_| self.guard.safe_vector(frame))
    }

    /// Resets a latched trip when asked (automatic reset or the console's operator).
    fn reset_if_asked(&mut self, now: Millis) -> bool {
        let asked = self.tap.as_ref().is_some_and(Tap::take_reset);
        if !(self.auto_reset || asked) || !self.engine.is_tripped() {
            return false;
        }
        match self.engine.reset() {
            Ok(()) => true,
            Err(e) => {
                if asked {
                    tracing::warn!("reset refused: {e}");
                    (self.emit)(
                        json!({"event": "reset_refused", "reason": e.to_string(), "time_ms": now.0}),
                    );
                }
                false
            }
        }
    }

    /// Step 1: the plant's inputs as last polled, its liveness watched (attaching the
    /// engine when it is first heard); returns the client's status.
    fn listen_plant(&mut self, now: Millis) -> super::link::ClientStatus {
        let (heard, failed, status) = {
            let s = lock(&self.side);
            self.inputs.clone_from(&s.inputs);
            (s.heard, s.failed, s.status.clone())
        };
        let what = format!("plant {}", self.plant_peer);
        if heard != self.plant_heard {
            if self.plant_heard.is_none() && self.attach {
                self.engine.attach_next_cycle();
                self.attached_now = true;
            }
            self.plant_heard = heard;
            if let Some(h) = heard {
                let t = self.plant_dog.heard(h);
                self.board
                    .watch(&mut *self.emit, now, "link:plant", &what, t);
            }
        }
        let t = self
            .liveness
            .check(&mut self.plant_dog, now, &self.beat, failed);
        self.board
            .watch(&mut *self.emit, now, "link:plant", &what, t);
        status
    }

    /// Step 2: the PLC's outputs, its liveness watched (heard when it writes); returns
    /// the server's exception count.
    fn listen_plc(&mut self, now: Millis) -> u64 {
        let (heard, server_exceptions, plc_connected) = {
            let s = lock(&self.shared);
            self.control.0.copy_from(&s.outputs);
            (s.plc_heard, s.exceptions, s.writer.is_some())
        };
        if heard.is_some() && heard != self.plc_last {
            self.plc_last = heard;
            let t = self.plc_dog.heard(heard.map_or(now, |h| self.clock.at(h)));
            self.board.watch(&mut *self.emit, now, "link:plc", "PLC", t);
        }
        let t = self
            .liveness
            .check_plc(&mut self.plc_dog, now, &self.beat, plc_connected);
        self.board.watch(&mut *self.emit, now, "link:plc", "PLC", t);
        server_exceptions
    }

    /// Step 4: the outputs sent to the plant, the safe fallback when the PLC or the plant
    /// is lost or stale inputs may violate a constraint (announced and alarmed on a
    /// change); returns the stale inputs, the outputs applied and the reason, if any.
    fn safe_outputs(&mut self, now: Millis) -> (Bits, Bits, Option<String>) {
        let n_out = self.control.0.len();
        let stale = self.inputs.stale(now, &self.bounds);
        let mut applied = self.engine.applied().clone();
        let reason = if self.plc_dog.is_lost() {
            applied = self.safe_now(now);
            Some("PLC lost: the safe fallback is sent to the plant".to_string())
        } else if self.plant_dog.is_lost() {
            // Written as soon as the plant answers again (or now, when it is connected
            // but its values cannot be read).
            applied = self.safe_now(now);
            Some(format!(
                "plant {} lost, its inputs stale: the safe fallback is sent to the plant (written first after a reconnection; `plant_write` says what it acknowledged)",
                self.plant_peer
            ))
        } else if stale.count_ones() > 0 {
            let v = self.guard.check(self.engine.frame(), &stale);
            if v.potentially_violated.is_empty() {
                None
            } else {
                applied = v
                    .fallback
                    .and_then(Result::ok)
                    .unwrap_or_else(|| Bits::zeros(n_out));
                Some(format!(
                    "stale inputs {}: {} potentially violated, safe fallback applied",
                    names(&self.bundle, Space::Input, &stale).join(" "),
                    v.potentially_violated.join(", ")
                ))
            }
        } else {
            None
        };
        if reason != self.safe_reason {
            match &reason {
                Some(r) => {
                    (self.emit)(json!({
                        "event": "safe_outputs", "reason": r,
                        "outputs": bits_text(&applied), "time_ms": now.0,
                    }));
                    if self.safe_reason.is_some() {
                        self.board.clear(&mut *self.emit, now, "safe:outputs");
                    }
                    self.board.raise(
                        &mut *self.emit,
                        now,
                        "safe:outputs",
                        AlarmKind::Link,
                        r.clone(),
                    );
                }
                None => {
                    (self.emit)(json!({"event": "safe_outputs_released", "time_ms": now.0}));
                    self.board.clear(&mut *self.emit, now, "safe:outputs");
                }
            }
            self.safe_reason.clone_from(&reason);
        }
        self.engine.set_applied(&applied);
        (stale, applied, reason)
    }
}

impl Cycle for GatewayCycle {
    type Done = (Bits, Vec<vigie_core::pop::Diagnosis>);

    fn step(&mut self, start: Instant) {
        let now = self.clock.at(start);
        // 1. The plant, as last polled.
        let status = self.listen_plant(now);
        // 2. The PLC: heard when it writes its outputs.
        let server_exceptions = self.listen_plc(now);
        // 3. The engine; a change of the latch is on disk before it is reported.
        let reset = self.reset_if_asked(now);
        self.engine
            .cycle(now, self.inputs.values(), &mut self.control);
        let mut events = Vec::new();
        emit_engine_events(
            &mut self.engine,
            &mut |e| events.push(e),
            None,
            &mut self.last_spec,
        );
        if self.engine.is_tripped() == self.latched {
            events.into_iter().for_each(&mut *self.emit);
        } else {
            self.latched = self.engine.is_tripped();
            let trip = self.engine.trips.last().filter(|_| self.latched).cloned();
            self.latch.save(trip, events);
        }
        // 4. Safe outputs.
        let (stale, applied, reason) = self.safe_outputs(now);
        // 5. The diagnosers follow what the plant receives.
        let usable = self.plant_heard.is_some() && !self.plant_dog.is_lost();
        let reset_asked = self.tap.as_ref().is_some_and(Tap::take_diagnosers_reset);
        let diagnosers = match &mut self.diagnosers {
            Some(d) => d.step(
                &mut self.engine,
                usable,
                reset_asked,
                &self.bundle,
                &mut self.board,
                &mut *self.emit,
            ),
            None => LinkStep::Skipped,
        };
        plausibility_events(
            &mut self.engine,
            &self.bundle.plant,
            &mut self.board,
            &mut *self.emit,
        );
        if let Some(t) = &mut self.tasks {
            let d = self.diagnosers.as_ref();
            t.step(&mut self.engine, now, d, &mut self.board, &mut *self.emit);
        }
        // 6. Outputs to the plant (written by the I/O task at once), sensors to the PLC
        // (in degraded mode a flagged sensor as its estimate).
        self.out.send_replace(Some(applied.clone()));
        {
            let mut shared = lock(&self.shared);
            shared.inputs.copy_from(self.inputs.values());
            if let Some(d) = &self.diagnosers {
                substitute(&d.estimated, self.engine.frame(), &mut shared.inputs);
            }
        }
        if let Some(h) = &mut self.history
            && let Some(rec) = self.engine.history.last()
        {
            h.record(rec);
        }
        if let Some(tap) = &self.tap {
            let stale_names = names(&self.bundle, Space::Input, &stale);
            let cycles = self.engine.cycles();
            let plc = self.plc_last.is_some() && !self.plc_dog.is_lost();
            tap.push_cycle(
                ObservedCycle {
                    time: now,
                    inputs: self.inputs.values().clone(),
                    commanded: self.control.0.clone(),
                    applied,
                    reset,
                    diagnosers,
                    attach: std::mem::take(&mut self.attached_now),
                    restored: self.restored.take(),
                    // The follower runs in monitor mode only.
                    followed: false,
                },
                |st| {
                    st.client = status;
                    st.now = now;
                    st.cycles = cycles;
                    st.stale_inputs = stale_names;
                    st.plc_connected = Some(plc);
                    st.safe_outputs = reason;
                    st.server_exceptions = server_exceptions;
                },
            );
        }
    }

    /// Shutdown: the fallback of the current context, whatever the PLC commands; and
    /// the certain diagnoses of the run.
    fn finish(mut self) -> Self::Done {
        if let Some(h) = &mut self.history {
            h.finish();
        }
        let now = self.clock.now();
        (
            self.safe_now(now),
            LiveDiagnosers::diagnoses(self.diagnosers.as_ref()),
        )
    }
}

pub(crate) async fn gateway(
    setup: Setup,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
    tap: Option<Tap>,
) -> anyhow::Result<()> {
    let Setup {
        config,
        bundle,
        client_map,
        server_map,
        diagnosers,
        state_dir,
        history,
        ..
    } = setup;
    let pki = super::opcua::pki::folder(&state_dir);
    let ((client, map), server_config) = config
        .client
        .clone()
        .zip(client_map)
        .zip(config.server.clone())
        .context("gateway mode needs a client and a server section")?;
    let (n_in, n_out) = (bundle.plant.inputs.len(), bundle.plant.outputs.len());
    let clock = Clock(Instant::now());
    let period = Duration::from_millis(config.cycle_ms.max(1));
    let priority = Priority::raise_io(&config);
    // A trip latched by an earlier run (a crash, a kill) holds from the first cycle.
    let (engine, restored) = restored_engine(&bundle, diagnosers.as_ref(), &config, &state_dir)?;
    let serve = super::link::Serve {
        config: &config,
        server: &server_config,
        map: server_map.as_ref(),
        plant: &bundle.plant,
        pki: &pki,
    };
    let (shared, server) = serve_plc(&serve, Bits::zeros(n_in)).await?;
    let announced = (diagnosers.is_some(), state_dir.as_path(), restored.as_ref());
    let sides = (&client, &server_config);
    announce(emit, tap.as_ref(), &server, sides, announced);
    let (plant_peer, liveness) = (client.peer(), Liveness::of(&config, client.timeout_ms()));
    let (out_tx, out_rx) = watch::channel(None);
    let (tx, mut events) = mpsc::channel(EVENT_QUEUE);
    let writer = PeerClient::Plant(Writer::new(client, map.clone(), &pki, clock.0)?);
    let io = PeerIo::start(writer, (n_in, 0), Some(out_rx), tx.clone(), clock, period);
    let latch_tx = tx.clone();
    let latch = LatchStore::start(state_dir, move |e| {
        if latch_tx.try_send(e).is_err() {
            tracing::warn!("a latch event was dropped: the event queue is full");
        }
    })?;
    let stop = Arc::new(AtomicBool::new(false));
    let cycle = GatewayCycle {
        clock,
        attach: config.first_cycle == vigie_core::engine::FirstCycle::Attach,
        attached_now: false,
        plant_peer,
        side: Arc::clone(&io.side),
        beat: io.heartbeat.clone(),
        liveness,
        latch,
        latched: restored.is_some(),
        restored: restored.clone(),
        shared,
        out: out_tx,
        engine,
        guard: StaleGuard::new(&bundle),
        control: Commanded(Bits::zeros(n_out)),
        inputs: AgedBits::new(n_in),
        bounds: map.input_bounds(),
        plant_dog: Watchdog::new(config.link_timeout(), Millis::ZERO),
        plant_heard: None,
        plc_dog: Watchdog::new(config.link_timeout(), Millis::ZERO),
        plc_last: None,
        board: AlarmBoard {
            alarms: AlarmList::new(),
            tap: tap.clone(),
        },
        safe_reason: None,
        last_spec: None,
        tasks: LiveTasks::new(&bundle),
        // Enforced: a flagged stop partition stops the plant, the PLC reads the
        // estimate of a flagged sensor.
        diagnosers: LiveDiagnosers::new(
            diagnosers,
            &bundle,
            Cooperation {
                stop: true,
                estimate: true,
            },
        ),
        auto_reset: config.auto_reset,
        emit: event_sender(tx),
        tap: tap.clone(),
        history,
        bundle,
    };
    let done = spawn_cycles(clock.0, period, priority, Arc::clone(&stop), cycle)?;
    let result = supervise(shutdown, emit, &mut events, &stop, done).await;
    let mut client = io.stop().await?;
    let ((safe, diagnoses), cycle_stats) = result?;
    *stats = cycle_stats;
    stop_report(&mut client, clock, &safe, &diagnoses, tap.as_ref(), emit).await;
    drop(server);
    Ok(())
}

/// The gateway's engine, holding a trip latched by an earlier run (returned too).
fn restored_engine(
    bundle: &PlantBundle,
    diagnosers: Option<&vigie_core::pop::build::Compiled>,
    config: &vigie_core::live::config::GatewayConfig,
    state_dir: &std::path::Path,
) -> anyhow::Result<(Engine, Option<vigie_core::engine::Trip>)> {
    let mut engine = with_estimates(
        Engine::new(bundle, FilterMode::Enforce, 6000),
        diagnosers,
        bundle,
        config.plausibility,
    );
    let restored = super::latch::load(state_dir)?;
    if let Some(trip) = restored.clone() {
        engine.restore_trip(trip);
    }
    Ok((engine, restored))
}

/// Announces the gateway: where it serves the PLC and reaches the plant (log, tap,
/// `listening` event), and a trip restored from an earlier run.
fn announce(
    emit: Emit<'_>,
    tap: Option<&Tap>,
    server: &ServerHandle,
    (client, server_link): (
        &vigie_core::live::config::ClientLink,
        &vigie_core::live::config::ServerLink,
    ),
    (diagnosers, state_dir, restored): (bool, &std::path::Path, Option<&vigie_core::engine::Trip>),
) {
    let served = server.address();
    let plant = client.peer();
    tracing::info!(
        "serving the PLC on {served} ({}), plant at {plant} ({})",
        server_link.describe(),
        client.describe()
    );
    if let Some(t) = tap {
        t.update(|s| {
            s.peer = Some(plant.clone());
            s.listening = Some(served.clone());
            s.protocol = Some(client.describe());
            s.plc_protocol = Some(server_link.describe());
        });
    }
    emit(json!({
        "event": "listening", "address": server.local().to_string(), "endpoint": served,
        "plant": plant, "diagnosers": diagnosers,
        "state_dir": state_dir.display().to_string(),
    }));
    if let Some(trip) = restored {
        let ids: Vec<&str> = trip.constraints.iter().map(|c| c.id.as_str()).collect();
        tracing::warn!(
            "a trip latched before the restart holds ({}): the outputs stay at the fallback until the reset",
            ids.join(", ")
        );
        emit(json!({"event": "trip_restored", "record": trip}));
    }
}

/// Writes the safe outputs to the plant on stopping and reports the stop (log, tap,
/// `stopped` event with the diagnoses).
async fn stop_report(
    client: &mut PeerClient,
    clock: Clock,
    safe: &Bits,
    diagnoses: &[vigie_core::pop::Diagnosis],
    tap: Option<&Tap>,
    emit: Emit<'_>,
) {
    let written = match client {
        PeerClient::Plant(w) => w.write(clock.now(), safe).await.is_ok(),
        PeerClient::Monitor(_) => false,
    };
    tracing::info!(
        "stopped; safe outputs {safe} {}",
        if written {
            "written"
        } else {
            "not written (plant unreachable)"
        }
    );
    if let Some(t) = tap {
        t.update(|s| s.running = false);
    }
    emit(json!({
        "event": "stopped", "outputs": bits_text(safe), "written": written,
        "diagnoses": diagnoses,
    }));
}
