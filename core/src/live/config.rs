//! The gateway configuration (`vigie gateway CONFIG`), a RON file such as
//! `layouts/sorting-station/gateway-monitor.ron`. Relative paths are relative to the
//! file's folder.

use crate::diag::codes;
use crate::diag::{Problem, ron_problem};
use crate::time::Millis;
use serde::{Deserialize, Serialize};
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::{Path, PathBuf};

/// What the service does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Mode {
    /// Read-only: poll a PLC or plant exposing the sensors and the commanded outputs,
    /// run observers and the filter in report-only mode; never write.
    Monitor,
    /// Serve the PLC (it reads sensors, writes commanded coils), poll the plant (read
    /// sensors, write the filtered coils), enforce the filter in between.
    Gateway,
    /// Serve the built-in emulator to an external PLC.
    Emulator,
}

fn default_cycle_ms() -> u64 {
    10
}
fn default_timeout_cycles() -> u32 {
    2
}
fn default_request_timeout_ms() -> u64 {
    50
}
pub(super) fn default_backoff_initial_ms() -> u64 {
    100
}
pub(super) fn default_backoff_max_ms() -> u64 {
    5000
}
fn default_bind() -> SocketAddr {
    SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 1502)
}
fn default_allow() -> Vec<IpAddr> {
    vec![IpAddr::V4(Ipv4Addr::LOCALHOST)]
}
fn default_unit() -> u8 {
    1
}
fn default_max_connections() -> usize {
    8
}
fn default_idle_timeout_ms() -> u64 {
    10_000
}

/// The PLC's endpoint: its address, and optionally the source port it connects from
/// (`"127.0.0.2"` or `"127.0.0.2:5020"`). Only a connection from this endpoint may
/// write, and only its own writes of outputs keep the PLC alive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct PlcEndpoint {
    /// The PLC's address.
    pub ip: IpAddr,
    /// The source port it connects from, when pinned.
    pub port: Option<u16>,
}

impl PlcEndpoint {
    /// True when a connection from `peer` is the PLC's.
    pub fn matches(&self, peer: SocketAddr) -> bool {
        peer.ip() == self.ip && self.port.is_none_or(|p| p == peer.port())
    }
}

impl std::fmt::Display for PlcEndpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.port {
            Some(p) => write!(f, "{}", SocketAddr::new(self.ip, p)),
            None => write!(f, "{}", self.ip),
        }
    }
}

impl TryFrom<String> for PlcEndpoint {
    type Error = String;

    fn try_from(s: String) -> Result<Self, String> {
        if let Ok(ip) = s.parse::<IpAddr>() {
            return Ok(Self { ip, port: None });
        }
        match s.parse::<SocketAddr>() {
            Ok(a) => Ok(Self {
                ip: a.ip(),
                port: (a.port() != 0).then_some(a.port()),
            }),
            Err(_) => Err(format!(
                "`{s}` is not a PLC endpoint: write an address (\"127.0.0.2\") or an address and source port (\"127.0.0.2:5020\")"
            )),
        }
    }
}

impl From<PlcEndpoint> for String {
    fn from(e: PlcEndpoint) -> Self {
        e.to_string()
    }
}

/// The Modbus TCP server Vigie is to a PLC.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServerConfig {
    /// Address to listen on; `127.0.0.1:1502` by default (loopback only). Port 0 lets
    /// the OS choose.
    #[serde(default = "default_bind")]
    pub bind: SocketAddr,
    /// Client addresses allowed to connect (others are disconnected at once);
    /// `[127.0.0.1]` by default.
    #[serde(default = "default_allow")]
    pub allow: Vec<IpAddr>,
    /// The PLC's endpoint (`"IP"` or `"IP:SOURCE_PORT"`), the only client allowed to
    /// write coils or registers, one connection at a time; `None` makes the server
    /// read-only. Every other client is read-only (exception 01 on writes).
    #[serde(default)]
    pub plc: Option<PlcEndpoint>,
    /// The unit id served, 1 to 247; requests to any other unit id (0 and 255
    /// included) get exception 0B.
    #[serde(default = "default_unit")]
    pub unit: u8,
    /// Client connections served at once; more are closed at once (8 by default).
    #[serde(default = "default_max_connections")]
    pub max_connections: usize,
    /// A connection that sends nothing for this long is closed (10 s by default).
    #[serde(default = "default_idle_timeout_ms")]
    pub idle_timeout_ms: u64,
}

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            bind: default_bind(),
            allow: default_allow(),
            plc: None,
            unit: default_unit(),
            max_connections: default_max_connections(),
            idle_timeout_ms: default_idle_timeout_ms(),
        }
    }
}

/// The Modbus TCP client Vigie is to the plant (or to the PLC in monitor mode).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClientConfig {
    /// The peer's address.
    pub address: SocketAddr,
    /// Time allowed for one request (and for connecting).
    #[serde(default = "default_request_timeout_ms")]
    pub timeout_ms: u64,
    /// First reconnection delay, doubled after each failure.
    #[serde(default = "default_backoff_initial_ms")]
    pub backoff_initial_ms: u64,
    /// Largest reconnection delay.
    #[serde(default = "default_backoff_max_ms")]
    pub backoff_max_ms: u64,
}

/// The client Vigie is to the plant (gateway) or to the monitored PLC (monitor):
/// `Modbus(address: …)` or `OpcUa(endpoint: …)`. The cycle is the same for both.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ClientLink {
    /// Modbus TCP, through the I/O map (`io_map`).
    Modbus(ClientConfig),
    /// OPC UA, through the node map.
    OpcUa(super::opcua::OpcUaClientConfig),
}

/// The server Vigie is to a PLC (gateway) or to a soft-PLC (emulator):
/// `Modbus(bind: …)` or `OpcUa(bind: …)`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ServerLink {
    /// Modbus TCP, serving the I/O map's addresses.
    Modbus(ServerConfig),
    /// OPC UA, serving the plant's signals as Boolean nodes.
    OpcUa(super::opcua::OpcUaServerConfig),
}

impl ClientLink {
    /// The peer, as the link-state panel names it (an address or an endpoint URL).
    pub fn peer(&self) -> String {
        match self {
            Self::Modbus(c) => c.address.to_string(),
            Self::OpcUa(c) => c.endpoint.clone(),
        }
    }

    /// The protocol's name.
    pub fn protocol(&self) -> &'static str {
        match self {
            Self::Modbus(_) => "Modbus TCP",
            Self::OpcUa(_) => "OPC UA",
        }
    }

    /// The protocol and its security, as the link-state panel shows them
    /// ("OPC UA, Basic256Sha256 SignAndEncrypt, user vigie").
    pub fn describe(&self) -> String {
        match self {
            Self::Modbus(_) => self.protocol().to_string(),
            Self::OpcUa(c) => format!(
                "OPC UA, {}, {}",
                c.security,
                c.user
                    .as_ref()
                    .map_or_else(|| "anonymous".to_string(), |u| format!("user {u}"))
            ),
        }
    }

    /// Time allowed for one request.
    pub fn timeout_ms(&self) -> u64 {
        match self {
            Self::Modbus(c) => c.timeout_ms,
            Self::OpcUa(c) => c.timeout_ms,
        }
    }
}

impl ServerLink {
    /// The protocol and its security, as the link-state panel shows them.
    pub fn describe(&self) -> String {
        match self {
            Self::Modbus(_) => "Modbus TCP".to_string(),
            Self::OpcUa(s) => format!(
                "OPC UA, {}",
                s.security
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join(" / ")
            ),
        }
    }

    /// The address it listens on.
    pub fn bind(&self) -> SocketAddr {
        match self {
            Self::Modbus(s) => s.bind,
            Self::OpcUa(s) => s.bind,
        }
    }
}

/// The configuration file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Gateway")]
pub struct GatewayConfig {
    /// Monitor (default), gateway or emulator.
    #[serde(default = "default_mode")]
    pub mode: Mode,
    /// The plant folder.
    pub plant: PathBuf,
    /// The I/O map; the plant folder's `io-map.ron` when absent.
    #[serde(default)]
    pub io_map: Option<PathBuf>,
    /// The cycle period.
    #[serde(default = "default_cycle_ms")]
    pub cycle_ms: u64,
    /// A link silent (plant) or a PLC silent for more than this many cycles is lost:
    /// outputs go to the safe fallback and an alarm is raised (2 by default).
    #[serde(default = "default_timeout_cycles")]
    pub link_timeout_cycles: u32,
    /// The plant (gateway) or the polled PLC or plant (monitor).
    #[serde(default)]
    pub client: Option<ClientLink>,
    /// The server towards the PLC (gateway, emulator).
    #[serde(default)]
    pub server: Option<ServerLink>,
    /// Reset a latched trip as soon as the PLC's commands comply again (headless
    /// service with no operator); by default a trip latches until restart.
    #[serde(default)]
    pub auto_reset: bool,
    /// Emulator seed.
    #[serde(default)]
    pub seed: u64,
    /// Real-time priority (SCHED_FIFO, 1 to 99) of the monitor or gateway cycle thread
    /// (the I/O runtime's thread gets one less), for a period jitter under 1 ms on a
    /// loaded machine; it needs the right to raise priorities (root or CAP_SYS_NICE,
    /// e.g. systemd's `AmbientCapabilities`). When refused, the cycle runs at normal
    /// priority with a warning. By default 50 when `realtime` is on.
    #[serde(default)]
    pub cycle_priority: Option<u8>,
    /// The first cycle's previous values: `Attach` (the default) takes the first
    /// values read from the plant (or the monitored PLC) as the values at t-1, so
    /// that attaching to a running plant shows no edge; `Cold` starts from the
    /// signals' initial values, as a PLC's first scan.
    #[serde(default = "default_first_cycle")]
    pub first_cycle: crate::engine::FirstCycle,
    /// Take a real-time priority when the process may have one (true by default);
    /// false runs every thread at normal priority.
    #[serde(default = "default_realtime")]
    pub realtime: bool,
    /// Where the gateway keeps its historian (`vigie.sqlite`: the journal, the alarm
    /// history and the process history, as the console's) and its latched trip (`latch.json`, so that a trip survives a crash or a restart);
    /// relative to the configuration's folder. By default the data folder
    /// (`VIGIE_DATA_DIR`, else `$XDG_DATA_HOME/vigie`, else `~/.local/share/vigie`)
    /// under `gateway/<configuration file stem>`.
    #[serde(default)]
    pub state_dir: Option<PathBuf>,
    /// Run the plant's diagnosers (`diagnosers.ron`, when the plant folder has one) in
    /// the monitor and gateway cycles, after the filter, with the constraints rewritten
    /// for the cooperation; true by default. Ignored in emulator mode.
    #[serde(default = "default_diagnosers")]
    pub diagnosers: bool,
    /// Run the sensors' plausibility stage (`plausible` in `plant.ron`) in the monitor
    /// and gateway cycles; true by default. `false` takes every edge as read (a test
    /// peer that moves the plant faster than its physics).
    #[serde(default = "default_diagnosers")]
    pub plausibility: bool,
    /// How long the historian keeps its rows: `retention: (process_days: 31,
    /// journal_days: 366)` by default.
    #[serde(default)]
    pub retention: Retention,
    /// The warnings found at load (security None on loopback), for the log.
    #[serde(skip)]
    pub warnings: Vec<Problem>,
}

/// How long the historian keeps its rows (the console's and the gateway's).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Retention {
    /// Process history (every change of every signal), days.
    #[serde(default = "Retention::default_process_days")]
    pub process_days: u32,
    /// Journal and alarm history, days.
    #[serde(default = "Retention::default_journal_days")]
    pub journal_days: u32,
}

impl Retention {
    fn default_process_days() -> u32 {
        31
    }
    fn default_journal_days() -> u32 {
        366
    }
}

impl Default for Retention {
    fn default() -> Self {
        Self {
            process_days: Self::default_process_days(),
            journal_days: Self::default_journal_days(),
        }
    }
}

fn default_diagnosers() -> bool {
    true
}

fn default_realtime() -> bool {
    true
}

fn default_first_cycle() -> crate::engine::FirstCycle {
    crate::engine::FirstCycle::Attach
}

fn default_mode() -> Mode {
    Mode::Monitor
}

impl GatewayConfig {
    /// Parses a configuration; `file` is used in messages and to resolve relative paths.
    pub fn from_ron(text: &str, file: &Path) -> Result<Self, Vec<Problem>> {
        let mut config: Self = super::config_ron_options()
            .from_str(text)
            .map_err(|e| vec![ron_problem(file, &e)])?;
        let base = file.parent().unwrap_or(Path::new("."));
        if config.plant.is_relative() {
            config.plant = base.join(&config.plant);
        }
        if let Some(m) = config.io_map.as_mut().filter(|m| m.is_relative()) {
            *m = base.join(&*m);
        }
        if let Some(d) = config.state_dir.as_mut().filter(|d| d.is_relative()) {
            *d = base.join(&*d);
        }
        let mut problems = Vec::new();
        if let Some(ClientLink::OpcUa(c)) = config.client.as_mut() {
            c.resolve(base);
            c.check(file, text, &mut problems);
        }
        if let Some(ServerLink::OpcUa(s)) = config.server.as_mut() {
            s.resolve(base);
            s.check(file, text, &mut problems);
        }
        let at = |n: &str| Some(crate::diag::Location::of_nth(file, text, n, 0));
        if config.cycle_ms == 0 {
            problems.push(Problem::error(
                codes::GATEWAY_CYCLE.id,
                "cycle_ms must be at least 1",
                at("cycle_ms"),
            ));
        }
        if config
            .cycle_priority
            .is_some_and(|p| !(1..=99).contains(&p))
        {
            problems.push(Problem::error(
                codes::GATEWAY_PRIORITY.id,
                "cycle_priority must be between 1 and 99",
                at("cycle_priority"),
            ));
        }
        if config.link_timeout_cycles == 0 {
            problems.push(Problem::error(
                codes::GATEWAY_LINK_TIMEOUT.id,
                "link_timeout_cycles must be at least 1",
                at("link_timeout_cycles"),
            ));
        }
        match config.mode {
            Mode::Monitor | Mode::Gateway if config.client.is_none() => {
                problems.push(Problem::error(
                    codes::GATEWAY_NO_CLIENT.id,
                    format!(
                        "{:?} mode needs `client: Modbus(address: …)` or `client: OpcUa(endpoint: …)`",
                        config.mode
                    ),
                    at("mode"),
                ))
            }
            Mode::Gateway | Mode::Emulator if config.server.is_none() => {
                problems.push(Problem::error(
                    codes::GATEWAY_NO_SERVER.id,
                    format!(
                        "{:?} mode needs `server: Modbus(…)` or `server: OpcUa(…)`",
                        config.mode
                    ),
                    at("mode"),
                ))
            }
            _ => {}
        }
        if let Some((s, plc)) = config.modbus_server().and_then(|s| s.plc.map(|p| (s, p)))
            && !s.allow.contains(&plc.ip)
        {
            {
                problems.push(Problem::error(
                    codes::GATEWAY_PLC_NOT_ALLOWED.id,
                    format!("the PLC address {} is not in the allow-list", plc.ip),
                    at("plc"),
                ));
            }
        }
        config.check_server(&mut problems, text, file);
        let (warnings, errors): (Vec<Problem>, Vec<Problem>) = problems
            .into_iter()
            .partition(|p| p.severity == crate::diag::Severity::Warning);
        config.warnings = warnings;
        if errors.is_empty() {
            Ok(config)
        } else {
            Err(errors)
        }
    }

    /// Checks the server section's unit id, connection limit and idle timeout.
    fn check_server(&self, problems: &mut Vec<Problem>, text: &str, file: &Path) {
        let at = |n: &str| Some(crate::diag::Location::of_nth(file, text, n, 0));
        let Some(s) = self.modbus_server() else {
            return;
        };
        if !(1..=247).contains(&s.unit) {
            problems.push(Problem::error(
                codes::GATEWAY_UNIT_ID.id,
                format!(
                    "unit {} cannot be served: a Modbus unit id is 1 to 247 (0 is broadcast, 248 to 255 are reserved)",
                    s.unit
                ),
                at("unit"),
            ));
        }
        if s.max_connections == 0 {
            problems.push(Problem::error(
                codes::GATEWAY_MAX_CONNECTIONS.id,
                "max_connections must be at least 1 (the PLC's connection)",
                at("max_connections"),
            ));
        }
        if s.idle_timeout_ms <= self.link_timeout().0 {
            problems.push(Problem::error(
                codes::GATEWAY_IDLE_TIMEOUT.id,
                format!(
                    "idle_timeout_ms ({}) must be longer than the link timeout ({} ms): a PLC would be disconnected before it is declared lost",
                    s.idle_timeout_ms,
                    self.link_timeout().0
                ),
                at("idle_timeout_ms"),
            ));
        }
    }

    /// Loads a configuration file.
    pub fn load(path: &Path) -> Result<Self, Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| {
            vec![Problem::error(
                codes::GATEWAY_CONFIG_UNREADABLE.id,
                p.message,
                None,
            )]
        })?;
        Self::from_ron(&text, path)
    }

    /// The Modbus server section, when the server is a Modbus one.
    pub fn modbus_server(&self) -> Option<&ServerConfig> {
        match &self.server {
            Some(ServerLink::Modbus(s)) => Some(s),
            _ => None,
        }
    }

    /// The node map path given to the OPC UA client, else the plant folder's
    /// `node-map.ron` when it has one; `None`: the address space Vigie serves.
    pub fn node_map_path(&self) -> Option<PathBuf> {
        match &self.client {
            Some(ClientLink::OpcUa(c)) if c.node_map.is_some() => c.node_map.clone(),
            _ => Some(self.plant.join("node-map.ron")).filter(|p| p.is_file()),
        }
    }

    /// The I/O map path.
    pub fn io_map_path(&self) -> PathBuf {
        self.io_map
            .clone()
            .unwrap_or_else(|| self.plant.join("io-map.ron"))
    }

    /// True when the monitor or gateway cycles run the diagnosers: switched on (the
    /// default) and the plant folder has a `diagnosers.ron`.
    pub fn runs_diagnosers(&self) -> bool {
        self.diagnosers
            && matches!(self.mode, Mode::Monitor | Mode::Gateway)
            && self.plant.join("diagnosers.ron").is_file()
    }

    /// The cycle period.
    pub fn cycle(&self) -> Millis {
        Millis(self.cycle_ms)
    }

    /// How long a silent peer may stay silent: `link_timeout_cycles` cycles.
    pub fn link_timeout(&self) -> Millis {
        Millis(
            self.cycle_ms
                .saturating_mul(u64::from(self.link_timeout_cycles)),
        )
    }
}
