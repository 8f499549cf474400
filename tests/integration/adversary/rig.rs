//! The rig: a fake plant, `vigie gateway` between it and the PLC (pymodbus, from
//! 127.0.0.2), the gateway's events stamped with the instant the test received them,
//! and a raw Modbus client for requests no well-behaved client would send.

use super::fake_plant::{self, FakePlant, Write};
use crate::live::{Plc, TempDir};
use std::collections::VecDeque;
use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStderr, ChildStdout, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The longest wait for anything that must happen.
pub(crate) const WAIT: Duration = Duration::from_secs(10);

/// How `vigie gateway` is started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Spawn {
    /// Events read from stdout, the log (stderr) kept for messages.
    Normal,
    /// Stdout and stderr are pipes nobody ever reads; the log at this level.
    Unread(&'static str),
    /// Under `ulimit -n` of this many descriptors.
    FdLimit(u32),
}

/// What a rig runs.
#[derive(Clone, Debug)]
pub(crate) struct Cfg {
    pub(crate) auto_reset: bool,
    /// The configuration's `server.plc`.
    pub(crate) plc: String,
    pub(crate) max_connections: usize,
    pub(crate) idle_timeout_ms: u64,
    pub(crate) spawn: Spawn,
    /// Sensors at 1 in the plant from the start.
    pub(crate) sensors: Vec<usize>,
    /// What the pymodbus PLC commands once started; `None`: no PLC.
    pub(crate) command: Option<&'static str>,
    /// Seed of the fake plant's garbage.
    pub(crate) seed: u64,
}

impl Default for Cfg {
    fn default() -> Self {
        Self {
            auto_reset: false,
            plc: "127.0.0.2".into(),
            max_connections: 8,
            idle_timeout_ms: 2000,
            spawn: Spawn::Normal,
            sensors: Vec::new(),
            command: Some("0000000"),
            seed: 1,
        }
    }
}

/// The configuration body of the contract.
/// The gateway runs the paper's station (eleven sensors, seven coils: the fake plant's
/// image), copied into `station`.
fn config_text(plant: SocketAddr, cfg: &Cfg, state: &Path, station: &Path) -> String {
    let station = crate::paper_station_in(station).canonicalize().unwrap();
    format!(
        "Gateway(plant: {station:?}, mode: Gateway, cycle_ms: 10, link_timeout_cycles: 10, \
         auto_reset: {auto_reset}, \
         client: Modbus(address: \"{plant}\", timeout_ms: 50, backoff_initial_ms: 20, backoff_max_ms: 200), \
         server: Modbus(bind: \"127.0.0.1:0\", allow: [\"127.0.0.1\", \"127.0.0.2\"], plc: {plc:?}, unit: 1, \
         max_connections: {max}, idle_timeout_ms: {idle}), \
         state_dir: {state:?}, diagnosers: false)",
        auto_reset = cfg.auto_reset,
        plc = cfg.plc,
        max = cfg.max_connections,
        idle = cfg.idle_timeout_ms,
    )
}

/// A running `vigie gateway`.
pub(crate) struct GatewayProc {
    child: Child,
    lines: Option<Receiver<(Instant, String)>>,
    /// Every event received so far, with the instant it was received.
    pub(crate) events: Vec<(Instant, serde_json::Value)>,
    log: Arc<Mutex<VecDeque<String>>>,
    /// The pipes of [`Spawn::Unread`], held open and never read.
    _unread: Option<(ChildStdout, ChildStderr)>,
}

/// Reads lines on a thread of its own, each with the instant it came.
fn pump<R: std::io::Read + Send + 'static>(
    name: &str,
    from: R,
    mut each: impl FnMut(Instant, String) -> bool + Send + 'static,
) {
    std::thread::Builder::new()
        .name(name.into())
        .spawn(move || {
            for line in BufReader::new(from).lines().map_while(Result::ok) {
                if !each(Instant::now(), line) {
                    break;
                }
            }
        })
        .unwrap();
}

impl GatewayProc {
    pub(crate) fn spawn(config: &Path, how: Spawn) -> Self {
        let vigie = env!("CARGO_BIN_EXE_vigie");
        let mut cmd = match how {
            Spawn::FdLimit(n) => {
                let mut c = Command::new("bash");
                c.arg("-c")
                    .arg(format!("ulimit -n {n}; exec \"$0\" \"$@\""))
                    .arg(vigie);
                c
            }
            _ => Command::new(vigie),
        };
        let level = match how {
            Spawn::Unread(level) => level,
            _ => "warn",
        };
        cmd.args(["gateway", "--log", level])
            .arg(config)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().expect("cannot start vigie gateway");
        let stdout = child.stdout.take().unwrap();
        let stderr = child.stderr.take().unwrap();
        let log = Arc::new(Mutex::new(VecDeque::new()));
        if let Spawn::Unread(_) = how {
            return Self {
                child,
                lines: None,
                events: Vec::new(),
                log,
                _unread: Some((stdout, stderr)),
            };
        }
        let (tx, rx) = channel();
        pump("gateway-stdout", stdout, move |t, line| {
            tx.send((t, line)).is_ok()
        });
        let l = Arc::clone(&log);
        pump("gateway-stderr", stderr, move |_, line| {
            let mut l = l.lock().unwrap();
            if l.len() >= 30 {
                l.pop_front();
            }
            l.push_back(line);
            true
        });
        Self {
            child,
            lines: Some(rx),
            events: Vec::new(),
            log,
            _unread: None,
        }
    }

    /// Takes in the events that came.
    fn take_in(&mut self, wait: Duration) {
        let Some(rx) = &self.lines else {
            std::thread::sleep(wait);
            return;
        };
        if let Ok((t, line)) = rx.recv_timeout(wait) {
            let mut push = |t, line: String| match serde_json::from_str(&line) {
                Ok(v) => self.events.push((t, v)),
                Err(e) => panic!("vigie gateway wrote a line that is not JSON ({e}): {line}"),
            };
            push(t, line);
            while let Ok((t, line)) = rx.try_recv() {
                push(t, line);
            }
        }
    }

    /// The first event received at or after `after` matching `pred`, waiting until
    /// `deadline`.
    pub(crate) fn wait_event(
        &mut self,
        after: Instant,
        deadline: Instant,
        pred: &dyn Fn(&serde_json::Value) -> bool,
    ) -> Option<(Instant, serde_json::Value)> {
        loop {
            let found = self
                .events
                .iter()
                .find(|(t, e)| *t >= after && pred(e))
                .cloned();
            let now = Instant::now();
            if found.is_some() || now >= deadline || self.lines.is_none() {
                return found;
            }
            self.take_in((deadline - now).min(Duration::from_millis(20)));
        }
    }

    /// The events received at or after `after` whose kind is `kind`.
    pub(crate) fn events_of(
        &mut self,
        kind: &str,
        after: Instant,
    ) -> Vec<(Instant, serde_json::Value)> {
        self.take_in(Duration::ZERO);
        self.events
            .iter()
            .filter(|(t, e)| *t >= after && e["event"] == kind)
            .cloned()
            .collect()
    }

    /// SIGKILL, and the exit collected.
    pub(crate) fn kill9(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    pub(crate) fn is_running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    pub(crate) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The last events (times relative to `origin`) and log lines, for messages.
    pub(crate) fn describe(&mut self, origin: Instant) -> String {
        self.take_in(Duration::ZERO);
        let skip = self.events.len().saturating_sub(40);
        let mut out = format!("events ({} in all, the last ones):\n", self.events.len());
        for (t, e) in &self.events[skip..] {
            let ms = t.saturating_duration_since(origin).as_millis();
            let text = e.to_string();
            let cut: String = text.chars().take(300).collect();
            out.push_str(&format!("  +{ms} ms {cut}\n"));
        }
        out.push_str("gateway log (the last lines):\n");
        for l in self.log.lock().unwrap().iter() {
            out.push_str(&format!("  {l}\n"));
        }
        // When nobody reads its output, its status is all there is to say.
        match self.child.try_wait() {
            Ok(None) => out.push_str("the gateway is running\n"),
            Ok(Some(status)) => out.push_str(&format!("the gateway has exited: {status}\n")),
            Err(e) => out.push_str(&format!("the gateway's status is unknown: {e}\n")),
        }
        out
    }
}

impl Drop for GatewayProc {
    fn drop(&mut self) {
        self.kill9();
    }
}

/// A fake plant, a gateway in front of it, and (unless told otherwise) the PLC.
pub(crate) struct Rig {
    // Dropped in this order: the PLC, the gateway, the plant.
    pub(crate) plc: Option<Plc>,
    pub(crate) gw: GatewayProc,
    pub(crate) plant: FakePlant,
    /// The gateway's server.
    pub(crate) server: SocketAddr,
    /// Where the test started: the origin of the times in messages.
    pub(crate) t0: Instant,
    /// Said first in failure messages (the run of a series, its seed).
    pub(crate) note: String,
    pub(crate) cfg: Cfg,
    config: PathBuf,
    dir: TempDir,
}

impl Rig {
    /// Starts the plant (its sensors set), the gateway, and the PLC with its command,
    /// then waits until the plant receives that command.
    pub(crate) fn start(cfg: Cfg) -> Self {
        let t0 = Instant::now();
        let plant = FakePlant::start(cfg.seed);
        for &s in &cfg.sensors {
            plant.set_sensor(s, true);
        }
        let dir = TempDir::new("adversary");
        let config = dir.0.join("gateway.ron");
        std::fs::write(
            &config,
            config_text(
                plant.addr(),
                &cfg,
                &dir.0.join("state"),
                &dir.0.join("station"),
            ),
        )
        .unwrap();
        let gw = GatewayProc::spawn(&config, cfg.spawn);
        let mut rig = Self {
            plc: None,
            gw,
            plant,
            server: SocketAddr::from(([127, 0, 0, 1], 0)),
            t0,
            note: String::new(),
            cfg,
            config,
            dir,
        };
        rig.server = rig.listening(t0);
        if let Some(command) = rig.start_plc() {
            let since = Instant::now();
            rig.expect_write(&format!("the PLC's {command}"), since, since + WAIT, |w| {
                w.coils == command
            });
        }
        rig
    }

    /// Starts the PLC (from 127.0.0.2) with its command, if the rig has one.
    fn start_plc(&mut self) -> Option<&'static str> {
        let command = self.cfg.command?;
        let mut plc = Plc::start(self.server, Some("127.0.0.2"));
        plc.command(command);
        self.plc = Some(plc);
        Some(command)
    }

    /// The address of the `listening` event received after `after`; from the journal
    /// when nobody reads stdout.
    fn listening(&mut self, after: Instant) -> SocketAddr {
        let address = if self.gw.lines.is_some() {
            let e = self.event("the listening event", after, WAIT, |e| {
                e["event"] == "listening"
            });
            e.1["address"].as_str().map(str::to_string)
        } else {
            let mut found = None;
            self.wait("the listening entry in the journal", WAIT, |r| {
                found = r
                    .journal()
                    .into_iter()
                    .find(|e| e["event"] == "listening")
                    .and_then(|e| e["address"].as_str().map(str::to_string));
                found.is_some()
            });
            found
        };
        address
            .and_then(|a| a.parse().ok())
            .unwrap_or_else(|| self.fail("a listening address"))
    }

    /// Kills the gateway (SIGKILL) and the PLC, and starts both again on the same
    /// configuration, state folder and plant; returns when.
    pub(crate) fn kill9_and_restart(&mut self) -> Instant {
        self.gw.kill9();
        self.plc = None;
        let restarted = Instant::now();
        self.gw = GatewayProc::spawn(&self.config, self.cfg.spawn);
        self.server = self.listening(restarted);
        self.start_plc();
        restarted
    }

    pub(crate) fn plc(&mut self) -> &mut Plc {
        self.plc.as_mut().expect("this rig runs a PLC")
    }

    pub(crate) fn state_dir(&self) -> PathBuf {
        self.dir.0.join("state")
    }

    /// The journal's entries, each the event it holds (`text` parsed), with `kind`.
    pub(crate) fn journal(&self) -> Vec<serde_json::Value> {
        let text = crate::historian_journal(&self.state_dir());
        text.lines()
            .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
            .map(|entry| {
                let mut e: serde_json::Value = entry["text"]
                    .as_str()
                    .and_then(|t| serde_json::from_str(t).ok())
                    .unwrap_or_default();
                if !e.is_object() {
                    e = serde_json::json!({});
                }
                e["journal_kind"] = entry["kind"].clone();
                e
            })
            .collect()
    }

    /// Panics with `expected`, what the plant received since the start, and the events.
    #[track_caller]
    pub(crate) fn fail(&mut self, expected: &str) -> ! {
        let writes = self.plant.writes_since(self.t0);
        panic!(
            "{}expected {expected}\nthe plant received (times from the start of the test):\n{}{}",
            if self.note.is_empty() {
                String::new()
            } else {
                format!("{}: ", self.note)
            },
            fake_plant::summary(&writes, self.t0),
            self.gw.describe(self.t0)
        );
    }

    /// Milliseconds from the start of the test (for messages).
    pub(crate) fn ms(&self, t: Instant) -> u128 {
        t.saturating_duration_since(self.t0).as_millis()
    }

    /// Polls `cond` every 2 ms until it holds or `within` passes (then fails).
    #[track_caller]
    pub(crate) fn wait(
        &mut self,
        what: &str,
        within: Duration,
        mut cond: impl FnMut(&mut Self) -> bool,
    ) {
        let deadline = Instant::now() + within;
        loop {
            if cond(self) {
                return;
            }
            if Instant::now() >= deadline {
                self.fail(&format!("{what} within {within:?}"));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    /// The first event received at or after `after` matching `pred`, within `within`.
    #[track_caller]
    pub(crate) fn event(
        &mut self,
        what: &str,
        after: Instant,
        within: Duration,
        pred: impl Fn(&serde_json::Value) -> bool,
    ) -> (Instant, serde_json::Value) {
        let deadline = Instant::now() + within;
        match self.gw.wait_event(after, deadline, &pred) {
            Some(e) => e,
            None => self.fail(&format!(
                "the event {what} (after +{} ms) within {within:?}",
                self.ms(after)
            )),
        }
    }

    /// The first write received in `[after, deadline]` matching `pred`.
    #[track_caller]
    pub(crate) fn expect_write(
        &mut self,
        what: &str,
        after: Instant,
        deadline: Instant,
        pred: impl Fn(&Write) -> bool,
    ) -> Write {
        loop {
            let found = self
                .plant
                .writes_since(after)
                .into_iter()
                .find(|w| w.at <= deadline && pred(w));
            if let Some(w) = found {
                return w;
            }
            if Instant::now() > deadline {
                let (a, d) = (self.ms(after), self.ms(deadline));
                self.fail(&format!(
                    "the plant to receive a write of {what} between +{a} ms and +{d} ms"
                ));
            }
            self.gw.take_in(Duration::from_millis(2));
        }
    }
}

/// A Modbus TCP client that sends what it is told, from the source it is told.
pub(crate) struct RawClient {
    stream: TcpStream,
    tid: u16,
}

/// FC 15: the 7 coils from 0, "0101000"-style.
pub(crate) fn write_coils(coils: &str) -> Vec<u8> {
    let byte = coils
        .chars()
        .enumerate()
        .fold(0u8, |b, (k, c)| b | (u8::from(c == '1') << k));
    vec![15, 0, 0, 0, 7, 1, byte]
}

/// FC 5: one coil on.
pub(crate) fn write_coil_on(address: u8) -> Vec<u8> {
    vec![5, 0, address, 0xFF, 0x00]
}

/// FC 2: the 11 sensors.
pub(crate) const READ_SENSORS: [u8; 5] = [2, 0, 0, 0, 11];

impl RawClient {
    /// Connects to `server` from `source` (port 0: chosen by the OS).
    pub(crate) fn connect(server: SocketAddr, source: SocketAddr) -> std::io::Result<Self> {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()?;
        let stream = rt.block_on(async {
            let socket = tokio::net::TcpSocket::new_v4()?;
            socket.set_reuseaddr(true)?;
            socket.bind(source)?;
            let s = tokio::time::timeout(Duration::from_secs(2), socket.connect(server))
                .await
                .map_err(|_| std::io::Error::new(std::io::ErrorKind::TimedOut, "connect"))??;
            s.into_std()
        })?;
        stream.set_nonblocking(false)?;
        stream.set_read_timeout(Some(Duration::from_secs(1)))?;
        stream.set_nodelay(true)?;
        Ok(Self { stream, tid: 0 })
    }

    /// How long a request waits for its answer (1 s by default).
    pub(crate) fn answer_within(self, timeout: Duration) -> Self {
        let _ = self.stream.set_read_timeout(Some(timeout));
        self
    }

    /// Sends one request to `unit`; its answer's PDU (an exception is `[fc | 0x80, code]`).
    pub(crate) fn request(&mut self, unit: u8, pdu: &[u8]) -> std::io::Result<Vec<u8>> {
        self.tid = self.tid.wrapping_add(1);
        let len = u16::try_from(pdu.len() + 1).unwrap();
        let mut frame = self.tid.to_be_bytes().to_vec();
        frame.extend_from_slice(&[0, 0]);
        frame.extend_from_slice(&len.to_be_bytes());
        frame.push(unit);
        frame.extend_from_slice(pdu);
        self.stream.write_all(&frame)?;
        let mut head = [0u8; 7];
        self.stream.read_exact(&mut head)?;
        let n = usize::from(u16::from_be_bytes([head[4], head[5]]));
        let mut body = vec![0u8; n.saturating_sub(1)];
        self.stream.read_exact(&mut body)?;
        if head[..2] != self.tid.to_be_bytes() {
            return Err(std::io::Error::other(format!(
                "answer to transaction {} carries {:?}",
                self.tid,
                &head[..2]
            )));
        }
        Ok(body)
    }

    /// Waits for the server to close the connection (or `within` to pass); true when
    /// it closed.
    pub(crate) fn closed_within(&mut self, within: Duration) -> bool {
        let deadline = Instant::now() + within;
        let mut buf = [0u8; 64];
        while Instant::now() < deadline {
            match self.stream.read(&mut buf) {
                Ok(0) => return true,
                Ok(_) => {}
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(_) => return true,
            }
        }
        false
    }

    /// Sends bytes as they are.
    pub(crate) fn send_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.stream.write_all(bytes)
    }
}

pub(crate) fn from_ip(ip: [u8; 4]) -> SocketAddr {
    SocketAddr::from((ip, 0))
}
