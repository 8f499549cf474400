//! What a live run publishes for the console (`vigie --link CONFIG`): every cycle as a
//! [`ObservedCycle`], the link state, the link alarms; and the operator's reset request
//! back to the run. The cycle thread never waits for the console: the queue is bounded
//! and the oldest cycles are dropped (and counted) when the console does not keep up.

pub use super::link::ClientStatus;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use vigie_core::Millis;
use vigie_core::live::config::Mode;
use vigie_core::sim::ObservedCycle;

/// The state of a live run, as the link-state panel shows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkState {
    /// Monitor or gateway.
    pub mode: Mode,
    /// The polled peer (monitor: the PLC or plant; gateway: the plant).
    pub peer: Option<String>,
    /// Where the server towards the PLC listens (gateway).
    pub listening: Option<String>,
    /// The client's protocol and security ("OPC UA, Basic256Sha256 SignAndEncrypt,
    /// user vigie", "Modbus TCP").
    pub protocol: Option<String>,
    /// The server's protocol and security (gateway).
    pub plc_protocol: Option<String>,
    /// The client's connection state and counters.
    pub client: ClientStatus,
    /// Gateway: the PLC was heard within the link timeout (`None` in monitor mode).
    pub plc_connected: Option<bool>,
    /// Time of the last cycle since the start of the run.
    pub now: Millis,
    /// Cycles run.
    pub cycles: u64,
    /// Inputs older than their bound, by name.
    pub stale_inputs: Vec<String>,
    /// Why the outputs are held at the safe fallback, while they are (gateway).
    pub safe_outputs: Option<String>,
    /// Requests of the PLC answered with an exception (gateway).
    pub server_exceptions: u64,
    /// True while the run goes on.
    pub running: bool,
    /// Why the run stopped, when it failed.
    pub error: Option<String>,
    /// The run stopped on SIGINT or SIGTERM (the console then closes).
    pub signalled: bool,
}

impl LinkState {
    /// The state before the first cycle.
    pub fn new(mode: Mode) -> Self {
        Self {
            mode,
            peer: None,
            listening: None,
            protocol: None,
            plc_protocol: None,
            client: ClientStatus::default(),
            plc_connected: None,
            now: Millis::ZERO,
            cycles: 0,
            stale_inputs: Vec::new(),
            safe_outputs: None,
            server_exceptions: 0,
            running: true,
            error: None,
            signalled: false,
        }
    }
}

/// A link alarm raised or cleared by the run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LinkAlarm {
    /// Raised.
    Raised {
        /// Stable key (`link:plant`, `link:plc`, `link:peer`, `safe:outputs`).
        key: String,
        /// Message.
        message: String,
        /// When.
        time: Millis,
    },
    /// Cleared.
    Cleared {
        /// Key.
        key: String,
        /// When.
        time: Millis,
    },
}

/// What the console takes from the run at each frame.
#[derive(Clone, Debug, Default)]
pub struct Taken {
    /// Cycles since the last take, oldest first.
    pub cycles: Vec<ObservedCycle>,
    /// Link alarms since the last take, in order.
    pub alarms: Vec<LinkAlarm>,
    /// Notable events of the run (time, kind, text) since the last take, for the journal.
    pub events: Vec<(Millis, String, String)>,
    /// Cycles dropped because the console did not keep up (total).
    pub dropped: u64,
}

#[derive(Debug)]
struct Inner {
    state: LinkState,
    cycles: VecDeque<ObservedCycle>,
    alarms: Vec<LinkAlarm>,
    events: Vec<(Millis, String, String)>,
    dropped: u64,
    reset_requested: bool,
    diagnosers_reset_requested: bool,
}

/// The shared mailbox between a live run and the console.
#[derive(Clone, Debug)]
pub struct Tap(Arc<Mutex<Inner>>);

impl Tap {
    /// Cycles kept for the console (100 s at 10 ms).
    const CAP: usize = 10_000;

    /// A mailbox for a run in `mode`.
    pub fn new(mode: Mode) -> Self {
        Self(Arc::new(Mutex::new(Inner {
            state: LinkState::new(mode),
            cycles: VecDeque::new(),
            alarms: Vec::new(),
            events: Vec::new(),
            dropped: 0,
            reset_requested: false,
            diagnosers_reset_requested: false,
        })))
    }

    fn with<T>(&self, f: impl FnOnce(&mut Inner) -> T) -> T {
        // A poisoned lock (a panic elsewhere) still holds usable data.
        let mut g = match self.0.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        };
        f(&mut g)
    }

    /// The link state now.
    pub fn state(&self) -> LinkState {
        self.with(|i| i.state.clone())
    }

    /// Takes the cycles and alarms published since the last call.
    pub fn take(&self) -> Taken {
        self.with(|i| Taken {
            cycles: i.cycles.drain(..).collect(),
            alarms: std::mem::take(&mut i.alarms),
            events: std::mem::take(&mut i.events),
            dropped: i.dropped,
        })
    }

    /// Asks the run to reset its latched trip (gateway), as the operator's reset.
    pub fn request_reset(&self) {
        self.with(|i| i.reset_requested = true);
    }

    pub(crate) fn take_reset(&self) -> bool {
        self.with(|i| std::mem::take(&mut i.reset_requested))
    }

    /// Asks the run to clear its diagnosers' fault flags (the operator's reset after a
    /// repair).
    pub fn request_diagnosers_reset(&self) {
        self.with(|i| i.diagnosers_reset_requested = true);
    }

    pub(crate) fn take_diagnosers_reset(&self) -> bool {
        self.with(|i| std::mem::take(&mut i.diagnosers_reset_requested))
    }

    pub(crate) fn push_cycle(&self, cycle: ObservedCycle, update: impl FnOnce(&mut LinkState)) {
        self.with(|i| {
            if i.cycles.len() >= Self::CAP {
                i.cycles.pop_front();
                i.dropped += 1;
            }
            i.cycles.push_back(cycle);
            update(&mut i.state);
        });
    }

    pub(crate) fn update(&self, update: impl FnOnce(&mut LinkState)) {
        self.with(|i| update(&mut i.state));
    }

    /// Records a notable event of the run for the console's journal (at most
    /// `Tap::CAP` kept between two takes).
    pub fn event(&self, time: Millis, kind: &str, text: String) {
        self.with(|i| {
            if i.events.len() < Self::CAP {
                i.events.push((time, kind.to_string(), text));
            }
        });
    }

    /// Records a link alarm for the console (at most `Tap::CAP` kept between two
    /// takes; the rest counted as dropped, as cycles are).
    pub(crate) fn alarm(&self, alarm: LinkAlarm) {
        self.with(|i| {
            if i.alarms.len() < Self::CAP {
                i.alarms.push(alarm);
            } else {
                i.dropped += 1;
            }
        });
    }
}
