//! The console on a live link (`vigie --link CONFIG`): a monitor or gateway run of
//! `layouts/…/gateway-*.ron` goes on in the background (thread `vigie-link`, the same
//! service as `vigie gateway`), and the console follows it instead of the emulator.
//!
//! Every frame, `Console::pump_link` takes the cycles the run published (through a
//! [`Tap`]) and feeds them to the simulation's engine (`Simulation::observe`, a mirror
//! of the run's engine), so the synoptic, the filter, the explanations, the chronogram,
//! the replay and the diagnosers (when the run steps them) show the live plant; link
//! alarms join the alarm list, notable events the journal. The link-state panel
//! (`panel_ui`) and the status bar (`status_ui`) show the connection: connected or
//! reconnecting (attempt, backoff), peer, age of the last poll, stale inputs, cycles,
//! exceptions.
//!
//! Vigie never commands a live plant from the console: the plant buttons and the
//! simulation controls are refused; the operator's reset goes to the run (gateway).

use super::{Command, Console, ConsoleOptions};
use crate::i18n::I18n;
use crate::live::runtime::{self, CycleStats};
use crate::live::tap::{LinkAlarm, LinkState, Tap};
use egui::{Color32, RichText};
use std::path::{Path, PathBuf};
use vigie_core::alarms::AlarmKind;
use vigie_core::engine::FilterMode;
use vigie_core::live::config::{GatewayConfig, Mode};
use vigie_core::sim::OperatorAction;

/// A live run followed by the console.
pub struct LinkSession {
    /// The configuration file.
    pub config: PathBuf,
    /// Monitor or gateway.
    pub mode: Mode,
    tap: Tap,
    /// The link state at the last frame.
    pub state: LinkState,
    /// Cycles the console could not take in time (dropped by the run's queue).
    pub dropped: u64,
    /// The program the PLC should run, followed by the run (`--program`); the
    /// console's mirror follows it too.
    pub program: Option<std::sync::Arc<vigie_core::control::CompiledProgram>>,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

/// The plant folder of a link configuration (the console loads its simulation there).
pub(crate) fn plant_dir(config: &Path) -> Result<PathBuf, String> {
    let c = GatewayConfig::load(config).map_err(|p| vigie_core::diag::render(&p))?;
    match c.mode {
        Mode::Monitor | Mode::Gateway => Ok(c.plant),
        Mode::Emulator => Err(format!(
            "{}: emulator mode serves the emulator to a PLC; open the console on a monitor or gateway configuration",
            config.display()
        )),
    }
}

/// Whether the run of a link configuration steps the diagnosers (its mirror then runs
/// them too).
pub(crate) fn runs_diagnosers(config: &Path) -> Result<bool, String> {
    let c = GatewayConfig::load(config).map_err(|p| vigie_core::diag::render(&p))?;
    Ok(c.runs_diagnosers())
}

/// Whether the run of a link configuration runs the plausibility stage (its mirror then
/// runs it too).
pub(crate) fn runs_plausibility(config: &Path) -> Result<bool, String> {
    let c = GatewayConfig::load(config).map_err(|p| vigie_core::diag::render(&p))?;
    Ok(c.plausibility)
}

impl LinkSession {
    /// Loads `config` and starts its run on a thread of its own.
    pub fn start(config: &Path, program: Option<&Path>) -> Result<Self, String> {
        let mut setup = runtime::load(config).map_err(|e| format!("{e:#}"))?;
        if let Some(p) = program {
            setup.follow_program(p).map_err(|e| format!("{e:#}"))?;
        }
        let mode = setup.config.mode;
        let program = setup.program.clone();
        let tap = Tap::new(mode);
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let run_tap = tap.clone();
        let watch_signals = WATCH_SIGNALS.load(std::sync::atomic::Ordering::Relaxed);
        let thread = std::thread::Builder::new()
            .name("vigie-link".into())
            .spawn(move || {
                let result = tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                    .map_err(anyhow::Error::from)
                    .and_then(|rt| {
                        let events = run_tap.clone();
                        let mut emit = move |e: serde_json::Value| journal_event(&events, &e);
                        let mut stats = CycleStats::default();
                        let signal_tap = run_tap.clone();
                        // The signal handlers are installed now, and only when asked
                        // (a console that does not watch them leaves SIGTERM alone).
                        let signals = watch_signals.then(|| {
                            let _inside = rt.enter();
                            crate::live::stop_signal()
                        });
                        rt.block_on(runtime::run(
                            setup,
                            async move {
                                match signals {
                                    Some(signals) => tokio::select! {
                                        _ = stop_rx => {}
                                        () = signals => {
                                            signal_tap.update(|s| s.signalled = true);
                                        }
                                    },
                                    None => {
                                        let _ = stop_rx.await;
                                    }
                                }
                            },
                            &mut emit,
                            &mut stats,
                            Some(run_tap.clone()),
                        ))
                    });
                if let Err(e) = result {
                    tracing::error!("live link: {e:#}");
                    run_tap.update(|s| {
                        s.running = false;
                        s.error = Some(format!("{e:#}"));
                    });
                }
            })
            .map_err(|e| format!("cannot start the link thread: {e}"))?;
        Ok(Self {
            config: config.to_path_buf(),
            mode,
            state: tap.state(),
            tap,
            dropped: 0,
            program,
            stop: Some(stop_tx),
            thread: Some(thread),
        })
    }

    /// The filter mode of the run's engine, which the console's engine mirrors.
    pub fn filter_mode(&self) -> FilterMode {
        match self.mode {
            Mode::Gateway => FilterMode::Enforce,
            Mode::Monitor | Mode::Emulator => FilterMode::ReportOnly,
        }
    }

    /// Stops the run (gateway: the plant receives the safe outputs first) and waits
    /// for its thread.
    pub fn stop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for LinkSession {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Whether a link run also stops on SIGINT and SIGTERM (see [`watch_signals`]).
static WATCH_SIGNALS: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Makes the links started from now on stop on SIGINT or SIGTERM (safe outputs first in
/// gateway mode), after which the console closes. The `vigie` binary turns it on;
/// tests and embedders leave the process's signals alone.
pub fn watch_signals(on: bool) {
    WATCH_SIGNALS.store(on, std::sync::atomic::Ordering::Relaxed);
}

/// Closes the window once the run stopped on a signal (called from `logic`).
pub(crate) fn close_on_signal(c: &Console, ctx: &egui::Context) {
    if c.link
        .as_ref()
        .is_some_and(|l| l.state.signalled && !l.state.running)
    {
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}

/// The run's JSON events worth a journal line.
fn journal_event(tap: &Tap, e: &serde_json::Value) {
    let kind = e["event"].as_str().unwrap_or_default();
    let time = vigie_core::Millis(e["time_ms"].as_u64().unwrap_or(0));
    let text = match kind {
        "potential_violation" => format!(
            "potentially violated with stale inputs {}: {}",
            join(&e["stale_inputs"]),
            join(&e["constraints"])
        ),
        "safe_outputs" => format!(
            "safe outputs {}: {}",
            e["outputs"].as_str().unwrap_or_default(),
            e["reason"].as_str().unwrap_or_default()
        ),
        "safe_outputs_released" => "safe outputs released".to_string(),
        "reset_refused" => format!(
            "reset refused: {}",
            e["reason"].as_str().unwrap_or_default()
        ),
        "specification_error" => e["message"].as_str().unwrap_or_default().to_string(),
        "diagnosers" => match e["state"].as_str().unwrap_or_default() {
            "started" => "diagnosers started: the plant in its initial state".to_string(),
            "suspended" => "diagnosers suspended while the peer is lost".to_string(),
            "resumed" => "diagnosers resumed, their flags and estimates kept".to_string(),
            "restarted" => "diagnosers restarted: the plant in its initial state".to_string(),
            other => format!("diagnosers {other}"),
        },
        "listening" => format!(
            "serving the PLC on {}",
            e["address"].as_str().unwrap_or_default()
        ),
        "monitoring" => format!(
            "monitoring {} (read-only)",
            e["peer"].as_str().unwrap_or_default()
        ),
        _ => return,
    };
    tap.event(time, kind, text);
}

fn join(v: &serde_json::Value) -> String {
    v.as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x.as_str())
                .collect::<Vec<_>>()
                .join(" ")
        })
        .unwrap_or_default()
}

/// With a link, the options the console opens with: the configuration's plant
/// folder, no scenario, no variant, nothing run before the first frame.
pub(crate) fn options(opts: &ConsoleOptions) -> Result<Option<ConsoleOptions>, String> {
    let Some(config) = &opts.link else {
        return Ok(None);
    };
    Ok(Some(ConsoleOptions {
        plant_dir: plant_dir(config)?,
        scenario: None,
        variant: None,
        start: false,
        run_until_ms: None,
        paused: false,
        mode: super::Mode::Production,
        ..opts.clone()
    }))
}

impl Console {
    /// Starts the link of `opts` (if any) and turns the simulation into its mirror.
    pub(crate) fn attach_link(&mut self, opts: &ConsoleOptions) -> Result<(), String> {
        let Some(config) = &opts.link else {
            return Ok(());
        };
        let session = LinkSession::start(config, opts.program.as_deref())?;
        self.sim.follow_link(session.filter_mode());
        if let Some(p) = &session.program {
            self.sim.follow_program(std::sync::Arc::clone(p));
        }
        self.journal.push(
            0,
            "session",
            &format!("live link {} ({:?})", config.display(), session.mode),
        );
        self.link = Some(session);
        self.running = true;
        self.drain_journal();
        Ok(())
    }

    /// Feeds the cycles, alarms and events the run published since the last frame.
    pub(crate) fn pump_link(&mut self) {
        let Some(link) = &mut self.link else {
            return;
        };
        let taken = link.tap.take();
        link.state = link.tap.state();
        link.dropped = taken.dropped;
        for c in &taken.cycles {
            self.sim.observe(c);
            if let Some(rec) = self.sim.engine.history.last() {
                self.journal.record_cycle(rec);
            }
        }
        for (time, kind, text) in &taken.events {
            self.journal.push(time.0, kind, text);
        }
        // Task and diagnosis alarms are the mirror's own (its task monitors and its
        // diagnosers follow the same cycles).
        let link_alarms = taken.alarms.into_iter().filter(|a| {
            let (LinkAlarm::Raised { key, .. } | LinkAlarm::Cleared { key, .. }) = a;
            !key.starts_with("task:") && !key.starts_with("diag:")
        });
        for a in link_alarms {
            match a {
                LinkAlarm::Raised { key, message, time } => {
                    self.journal.push(time.0, "link_alarm", &message);
                    self.sim.alarms.raise(time, &key, AlarmKind::Link, message);
                }
                LinkAlarm::Cleared { key, time } => {
                    self.journal
                        .push(time.0, "link_alarm_cleared", &format!("{key} cleared"));
                    self.sim.alarms.clear(time, &key);
                }
            }
        }
        self.drain_journal();
        self.follow_trip();
        self.journal.sync_alarms(&self.sim.alarms);
        self.journal.commit();
    }

    /// In link mode, handles the commands that would drive the plant or the emulator;
    /// true when `cmd` was handled here.
    pub(crate) fn link_command(&mut self, cmd: &Command) -> bool {
        let Some(link) = &self.link else {
            return false;
        };
        let refused = "live link: the PLC drives the plant, Vigie only watches and filters";
        self.status = match cmd {
            Command::Plant(OperatorAction::Reset) => match link.mode {
                Mode::Gateway => {
                    link.tap.request_reset();
                    "reset requested from the gateway".to_string()
                }
                _ => "monitor mode: the filter only reports, there is nothing to reset".into(),
            },
            Command::Plant(OperatorAction::ResetDiagnosers) => {
                link.tap.request_diagnosers_reset();
                "diagnosers reset requested from the run".to_string()
            }
            Command::Plant(_)
            | Command::Restart
            | Command::RestartWithEdit
            | Command::LoadVariant(_)
            | Command::InjectFault(_)
            | Command::VerifyFix => refused.to_string(),
            Command::Run | Command::Pause | Command::Step | Command::SetSpeed(_) => {
                "live link: the plant runs in real time".to_string()
            }
            _ => return false,
        };
        true
    }
}

/// One line of text for the connection, in the language shown.
pub fn connection_text(i18n: &I18n, s: &LinkState) -> String {
    let peer = s.peer.clone().unwrap_or_default();
    if let Some(e) = &s.error {
        return i18n.ta("linkp-stopped-error", &[("error", e.into())]);
    }
    if !s.running {
        return i18n.t("linkp-stopped");
    }
    if s.client.connected {
        i18n.ta("linkp-connected", &[("peer", (&peer).into())])
    } else if s.client.failed_attempts == 0 && s.client.connections == 0 {
        i18n.ta("linkp-connecting", &[("peer", (&peer).into())])
    } else {
        i18n.ta(
            "linkp-reconnecting",
            &[
                ("peer", (&peer).into()),
                ("attempt", (s.client.failed_attempts + 1).into()),
                ("ms", s.client.next_attempt.saturating_sub(s.now).0.into()),
            ],
        )
    }
}

fn poll_text(i18n: &I18n, s: &LinkState) -> String {
    match s.client.last_read {
        Some(t) => i18n.ta(
            "linkp-last-poll",
            &[("ms", s.now.saturating_sub(t).0.into())],
        ),
        None => i18n.t("linkp-never-polled"),
    }
}

fn stale_text(i18n: &I18n, s: &LinkState) -> String {
    if s.stale_inputs.is_empty() {
        i18n.t("linkp-no-stale")
    } else {
        i18n.ta(
            "linkp-stale",
            &[("inputs", (&s.stale_inputs.join(" ")).into())],
        )
    }
}

fn state_color(c: &Console, s: &LinkState) -> Color32 {
    if s.client.connected && s.running && s.stale_inputs.is_empty() {
        c.palette.running
    } else if s.client.connected && s.running {
        c.palette.alarm
    } else {
        c.palette.trip
    }
}

/// The link-state panel (top of the side panel in link mode).
pub(crate) fn panel_ui(c: &Console, ui: &mut egui::Ui) {
    let Some(link) = &c.link else {
        return;
    };
    let s = &link.state;
    let i = &c.i18n;
    ui.heading(i.t("linkp-title"));
    ui.label(i.t(match link.mode {
        Mode::Gateway => "linkp-mode-gateway",
        _ => "linkp-mode-monitor",
    }));
    ui.label(
        RichText::new(connection_text(i, s))
            .strong()
            .color(Color32::WHITE)
            .background_color(state_color(c, s)),
    );
    if let Some(p) = &s.protocol {
        ui.label(i.ta("linkp-protocol", &[("protocol", p.into())]));
    }
    ui.label(poll_text(i, s));
    let stale = RichText::new(stale_text(i, s));
    ui.label(if s.stale_inputs.is_empty() {
        stale
    } else {
        stale.color(c.palette.alarm)
    });
    ui.label(i.ta("linkp-cycles", &[("n", s.cycles.into())]));
    ui.label(i.ta(
        "linkp-exceptions",
        &[
            ("n", s.client.exceptions.into()),
            ("errors", s.client.errors.into()),
            ("connections", s.client.connections.into()),
        ],
    ));
    if let Some(addr) = &s.listening {
        ui.label(i.ta(
            "linkp-plc-server",
            &[("address", (&addr.to_string()).into())],
        ));
        if let Some(p) = &s.plc_protocol {
            ui.label(i.ta("linkp-plc-protocol", &[("protocol", p.into())]));
        }
        ui.label(i.t(match s.plc_connected {
            Some(true) => "linkp-plc-heard",
            _ => "linkp-plc-silent",
        }));
        ui.label(i.ta("linkp-plc-refused", &[("n", s.server_exceptions.into())]));
    }
    if let Some(r) = &s.safe_outputs {
        ui.label(
            RichText::new(i.ta("linkp-safe-outputs", &[("reason", r.into())]))
                .color(c.palette.trip),
        );
    }
    if link.dropped > 0 {
        ui.label(
            RichText::new(i.ta("linkp-dropped", &[("n", link.dropped.into())]))
                .color(c.palette.text_dim),
        );
    }
    ui.label(RichText::new(link.config.display().to_string()).color(c.palette.text_dim));
    ui.separator();
}

/// The toolbar in link mode (no simulation controls, no plant buttons: the PLC drives
/// the plant): true when shown.
pub(crate) fn toolbar_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) -> bool {
    let Some(link) = &c.link else {
        return false;
    };
    ui.label(RichText::new("VIGIE").strong().size(18.0));
    ui.separator();
    let what = match link.mode {
        Mode::Gateway => "link-gateway",
        _ => "link-monitor",
    };
    ui.label(
        RichText::new(c.i18n.t(what))
            .strong()
            .color(Color32::WHITE)
            .background_color(state_color(c, &link.state)),
    );
    ui.separator();
    ui.label(format!("t = {}", super::views::fmt_ms(c.sim.now().0)));
    ui.separator();
    let tripped = c.sim.engine.is_tripped();
    if link.mode == Mode::Gateway {
        super::views::reset_button_ui(c, ui, "link-reset-hover", out);
        ui.separator();
    }
    let unack = c.sim.alarms.unacknowledged();
    let (txt, col) = if tripped {
        (c.i18n.t("state-tripped"), c.palette.trip)
    } else if unack > 0 {
        (
            c.i18n.ta("state-unacknowledged", &[("n", unack.into())]),
            c.palette.alarm,
        )
    } else {
        (c.i18n.t("link-normal"), c.palette.equipment_edge)
    };
    ui.label(
        RichText::new(txt)
            .strong()
            .color(Color32::WHITE)
            .background_color(col),
    );
    true
}

/// The link's element of the status bar: true when shown (link mode).
pub(crate) fn status_ui(c: &Console, ui: &mut egui::Ui) -> bool {
    let Some(link) = &c.link else {
        return false;
    };
    let s = &link.state;
    ui.label(
        RichText::new(connection_text(&c.i18n, s))
            .strong()
            .color(Color32::WHITE)
            .background_color(state_color(c, s)),
    );
    ui.label(c.i18n.ta(
        "linkp-status",
        &[
            ("poll", (&poll_text(&c.i18n, s)).into()),
            ("stale", (&stale_text(&c.i18n, s)).into()),
            ("cycles", s.cycles.into()),
            (
                "exceptions",
                (s.client.exceptions + s.server_exceptions).into(),
            ),
        ],
    ));
    if !c.status.is_empty() {
        ui.separator();
        ui.label(RichText::new(&c.status).strong());
    }
    true
}
