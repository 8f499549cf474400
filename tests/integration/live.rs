//! The live link against independent real peers on 127.0.0.1 (OS-chosen ports, no fixed
//! sleeps: every wait polls a condition with a deadline):
//! - pymodbus (pinned in `requirements-test.txt`) as the plant server and as the PLC
//!   client (`tests/peers/plant.py`, `tests/peers/plc.py`);
//! - mbpoll (Debian package) as a second client of the emulator served over Modbus.
//!
//! The venv python is `$VIGIE_VENV/bin/python` or `<repo>/.venv/bin/python`; without it
//! these tests fail with the command that creates it.

#![allow(clippy::unwrap_used)] // test helpers: a failure is a test failure

use std::io::{BufRead as _, BufReader, Write as _};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

pub(crate) fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub(crate) fn python() -> PathBuf {
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| repo().join(".venv"), PathBuf::from);
    let py = venv.join("bin/python");
    assert!(
        py.is_file(),
        "the test venv is missing ({} not found): run `scripts/test.sh` once, or create it with \
         `python3 -m venv .venv && .venv/bin/pip install -r requirements-test.txt` at the repository root \
         (or point VIGIE_VENV at an existing one)",
        py.display()
    );
    py
}

fn mbpoll() -> PathBuf {
    let path = PathBuf::from("/usr/bin/mbpoll");
    assert!(
        path.is_file(),
        "mbpoll is missing: run `scripts/test.sh` once (it installs the Debian package), or `apt-get install mbpoll`"
    );
    path
}

const WAIT: Duration = Duration::from_secs(10);

/// Polls `cond` until it holds or `WAIT` passes.
#[track_caller]
pub(crate) fn wait_until(what: &str, mut cond: impl FnMut() -> bool) {
    let deadline = Instant::now() + WAIT;
    while Instant::now() < deadline {
        if cond() {
            return;
        }
        std::thread::yield_now();
        std::thread::sleep(Duration::from_millis(2));
    }
    panic!("timed out waiting for {what}");
}

/// A child process driven by lines on stdin, answering lines on stdout.
pub(crate) struct Peer {
    pub(crate) name: String,
    pub(crate) child: Child,
    pub(crate) stdin: ChildStdin,
    pub(crate) lines: Receiver<String>,
}

impl Peer {
    pub(crate) fn spawn(name: &str, mut cmd: Command) -> Self {
        let mut child = cmd
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {name}: {e}"));
        let stdin = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, lines) = channel();
        std::thread::Builder::new()
            .name(format!("{name}-stdout"))
            .spawn(move || {
                for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                    if tx.send(line).is_err() {
                        break;
                    }
                }
            })
            .unwrap();
        Self {
            name: name.to_string(),
            child,
            stdin,
            lines,
        }
    }

    pub(crate) fn line(&self) -> String {
        self.lines
            .recv_timeout(WAIT)
            .unwrap_or_else(|_| panic!("{}: no output within {WAIT:?}", self.name))
    }

    pub(crate) fn ask(&mut self, command: &str) -> String {
        writeln!(self.stdin, "{command}").unwrap();
        self.stdin.flush().unwrap();
        self.line()
    }

    pub(crate) fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        self.kill();
    }
}

/// The pymodbus plant.
pub(crate) struct Plant {
    pub(crate) peer: Peer,
    pub(crate) port: u16,
}

impl Plant {
    pub(crate) fn start(port: Option<u16>) -> Self {
        let mut cmd = Command::new(python());
        cmd.arg(repo().join("tests/peers/plant.py"))
            .args(["--mirror", &station_mirrors()]);
        if let Some(p) = port {
            cmd.args(["--port", &p.to_string()]);
        }
        let peer = Peer::spawn("plant", cmd);
        let first = peer.line();
        let port = first
            .strip_prefix("listening ")
            .and_then(|p| p.parse().ok())
            .unwrap_or_else(|| panic!("plant: unexpected first line {first:?}"));
        Self { peer, port }
    }

    /// Sets the inputs, all in the same step of the peer (a reader sees them change in
    /// the same scan).
    pub(crate) fn set_inputs(&mut self, bits: &[(u16, bool)]) {
        let mut line = String::from("di");
        for &(a, v) in bits {
            line.push_str(&format!(" {a} {}", u8::from(v)));
        }
        assert_eq!(self.peer.ask(&line), "ok");
    }

    /// Kills the plant process (the link loses its peer).
    pub(crate) fn stop(&mut self) {
        self.peer.kill();
    }

    pub(crate) fn coils(&mut self) -> String {
        let line = self.peer.ask("coils");
        line.strip_prefix("coils ")
            .unwrap_or_else(|| panic!("plant: {line}"))[..7]
            .to_string()
    }
}

/// The sorting station's mirror contacts as the plant peer's `--mirror` wiring
/// (`coil:input,...`), read from `plant.ron`: each contactor's auxiliary contact follows
/// its coil, as the real plant's wiring does.
pub(crate) fn station_mirrors() -> String {
    use vigie_core::plant::{Address, Plant};
    let plant = Plant::load(&repo().join("layouts/sorting-station/plant.ron"))
        .unwrap_or_else(|p| panic!("{p:?}"));
    plant
        .mirrors()
        .into_iter()
        .filter_map(
            |(i, o)| match (plant.inputs[i].address, plant.outputs[o].address) {
                (Some(Address::DiscreteInput(d)), Some(Address::Coil(c))) => {
                    Some(format!("{c}:{d}"))
                }
                _ => None,
            },
        )
        .collect::<Vec<_>>()
        .join(",")
}

/// The pymodbus PLC.
pub(crate) struct Plc(Peer);

impl Plc {
    pub(crate) fn start(server: SocketAddr, source: Option<&str>) -> Self {
        let mut cmd = Command::new(python());
        cmd.arg(repo().join("tests/peers/plc.py")).args([
            "--port",
            &server.port().to_string(),
            "--period-ms",
            "5",
        ]);
        if let Some(s) = source {
            cmd.args(["--source", s]);
        }
        let peer = Peer::spawn("plc", cmd);
        assert_eq!(peer.line(), "running");
        Self(peer)
    }

    pub(crate) fn command(&mut self, coils: &str) {
        assert_eq!(self.0.ask(&format!("coils {coils}")), "ok");
    }

    pub(crate) fn sensors(&mut self) -> String {
        self.0.ask("di")
    }

    pub(crate) fn status(&mut self) -> (u64, u64, String) {
        let line = self.0.ask("status");
        let w: Vec<&str> = line.split_whitespace().collect();
        (
            w[1].parse().unwrap(),
            w[2].parse().unwrap(),
            w[3].to_string(),
        )
    }
}

/// `vigie gateway CONFIG` with its JSON events.
pub(crate) struct Gateway {
    pub(crate) peer: Peer,
    pub(crate) events: Vec<serde_json::Value>,
    /// Its state folder (the historian, the latch), unless the test named one.
    pub(crate) state: PathBuf,
    pub(crate) _dir: TempDir,
}

pub(crate) struct TempDir(pub(crate) PathBuf);

impl TempDir {
    pub(crate) fn new(tag: &str) -> Self {
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("vigie-it-{tag}-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

impl Gateway {
    fn start(config_body: &str) -> Self {
        Self::start_with(config_body, &[])
    }

    /// `vigie gateway` with these arguments after the configuration.
    fn start_with(config_body: &str, args: &[&str]) -> Self {
        let dir = TempDir::new("gw");
        let station = repo()
            .join("layouts/sorting-station")
            .canonicalize()
            .unwrap();
        // Each gateway keeps its journal and latch in its own folder (unless the test
        // names one).
        let state = if config_body.contains("state_dir") {
            String::new()
        } else {
            format!(
                "state_dir: {:?}, ",
                dir.0.join("state").display().to_string()
            )
        };
        // The station's I/O map with a staleness bound of 200 ms in place of 30 ms:
        // the Python plant peer can miss a few polls on a loaded machine, and a stale
        // guard that steps in for one cycle changes the sequence a test follows (the
        // stale guard has its own test, which kills the plant).
        let map = std::fs::read_to_string(station.join("io-map.ron"))
            .unwrap()
            .replace("max_age_ms: 30,", "max_age_ms: 200,");
        assert!(
            map.contains("max_age_ms: 200,"),
            "the station's io-map.ron changed"
        );
        let map_path = dir.0.join("io-map.ron");
        std::fs::write(&map_path, map).unwrap();
        let text = format!(
            "Gateway(plant: {:?}, io_map: Some({:?}), {state}{config_body})",
            station.display().to_string(),
            map_path.display().to_string()
        );
        let path = dir.0.join("gateway.ron");
        std::fs::write(&path, text).unwrap();
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_vigie"));
        cmd.args(["gateway", "--log", "warn"]).arg(&path).args(args);
        Self {
            peer: Peer::spawn("vigie gateway", cmd),
            events: Vec::new(),
            state: dir.0.join("state"),
            _dir: dir,
        }
    }

    /// Forgets the events seen so far (later waits see only new ones).
    pub(crate) fn forget(&mut self) {
        while let Ok(line) = self.peer.lines.try_recv() {
            let _ = line;
        }
        self.events.clear();
    }

    /// Waits for an event matching `pred` (events seen before count too).
    #[track_caller]
    pub(crate) fn event(
        &mut self,
        what: &str,
        pred: impl Fn(&serde_json::Value) -> bool,
    ) -> serde_json::Value {
        if let Some(e) = self.events.iter().find(|e| pred(e)) {
            return e.clone();
        }
        let deadline = Instant::now() + WAIT;
        while Instant::now() < deadline {
            if let Ok(line) = self.peer.lines.recv_timeout(Duration::from_millis(50)) {
                let v: serde_json::Value = serde_json::from_str(&line)
                    .unwrap_or_else(|e| panic!("not JSON ({e}): {line}"));
                self.events.push(v.clone());
                if pred(&v) {
                    return v;
                }
            }
        }
        panic!(
            "timed out waiting for event {what}; events: {:#?}",
            self.events
        );
    }

    pub(crate) fn kind(kind: &'static str) -> impl Fn(&serde_json::Value) -> bool {
        move |e| e["event"] == kind
    }

    fn listening(&mut self) -> SocketAddr {
        let e = self.event("listening", Self::kind("listening"));
        e["address"].as_str().unwrap().parse().unwrap()
    }

    /// SIGTERM, then the final event.
    pub(crate) fn stop(&mut self) -> serde_json::Value {
        let pid = self.peer.child.id().to_string();
        let status = Command::new("kill").args(["-TERM", &pid]).status().unwrap();
        assert!(status.success());
        let e = self.event("stopped", Self::kind("stopped"));
        let code = self.peer.child.wait().unwrap();
        assert!(code.success(), "vigie gateway exited with {code}");
        e
    }
}

/// A PLC or plant silent for 50 cycles (500 ms) is lost: on a loaded 2-core machine a
/// peer can miss 100 ms, and a stale guard that takes the outputs to their fallback in
/// the middle of a test's sequence changes what the test sees (the test of the stale
/// guard itself kills the PLC and waits for it).
fn gateway_config(plant_port: u16, extra: &str) -> String {
    format!(
        "mode: Gateway, cycle_ms: 10, link_timeout_cycles: 50, auto_reset: true, \
         client: Modbus(address: \"127.0.0.1:{plant_port}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200), \
         server: Modbus(bind: \"127.0.0.1:0\", allow: [\"127.0.0.1\", \"127.0.0.2\"], plc: \"127.0.0.2\"), {extra}"
    )
}

// Sensor addresses of the sorting station (discrete inputs) and actuator positions.
const C3: u16 = 3;
const C4: u16 = 4;
const C5: u16 = 5;
const C6: u16 = 6;
const C7: u16 = 7;

#[test]
fn gateway_round_trip_with_pymodbus() {
    let mut plant = Plant::start(None);
    let mut gw = Gateway::start(&gateway_config(plant.port, ""));
    let server = gw.listening();
    let mut plc = Plc::start(server, Some("127.0.0.2"));
    // Sensors: plant → Vigie → PLC.
    plant.set_inputs(&[(0, true), (C7, true), (10, true)]);
    wait_until("the PLC to read C0, C7 and C10", || {
        plc.sensors() == "di 10000001001"
    });
    plant.set_inputs(&[(0, false), (C7, false), (10, false)]);
    wait_until("the PLC to read all sensors 0", || {
        plc.sensors() == "di 00000000000"
    });
    // Outputs: PLC → Vigie (allowed by the filter) → plant.
    plc.command("1100011");
    wait_until("the plant to receive A0 A1 A5 A6", || {
        plant.coils() == "1100011"
    });
    plc.command("0000000");
    wait_until("the plant to receive all outputs 0", || {
        plant.coils() == "0000000"
    });
    let (scans, errors, last) = plc.status();
    assert!(
        scans > 0 && errors == 0,
        "PLC scans {scans}, errors {errors} ({last})"
    );
    let stopped = gw.stop();
    assert_eq!(stopped["written"], true);
}

/// The tests of the filter move the turntable from C4 to C5 in a few milliseconds,
/// which the table's diagnoser rightly takes for a fault (and may stop the plant for)
/// and the plausibility stage for edges the physics does not allow (it holds them):
/// they run without either.
const NO_DIAGNOSERS: &str = "diagnosers: false, plausibility: false";

#[test]
fn gateway_enforces_the_hold_of_a4() {
    let mut plant = Plant::start(None);
    let mut gw = Gateway::start(&gateway_config(plant.port, NO_DIAGNOSERS));
    let server = gw.listening();
    let mut plc = Plc::start(server, Some("127.0.0.2"));
    // A loaded table in the loading position starts rotating.
    plant.set_inputs(&[(C4, true), (C6, true)]);
    wait_until("the PLC to see C4 C6", || plc.sensors() == "di 00001010000");
    plc.command("0000100");
    wait_until("the plant to rotate", || plant.coils() == "0000100");
    // It reaches the unloading position; the box leaves the table (C6, then C7 on the
    // right exit), and the PLC releases A4 too early (CSs10 = C7 . /A4).
    plant.set_inputs(&[(C4, false), (C5, true)]);
    wait_until("the PLC to see C5 C6", || plc.sensors() == "di 00000110000");
    // One edge per cycle, as on a real plant (P67 is set by FE(C6), reset by RE(C7)).
    plant.set_inputs(&[(C6, false)]);
    wait_until("the PLC to see C5", || plc.sensors() == "di 00000100000");
    plant.set_inputs(&[(C7, true)]);
    wait_until("the PLC to see C5 C7", || plc.sensors() == "di 00000101000");
    plc.command("0000000");
    let trip = gw.event("trip on CSs10", |e| {
        e["event"] == "trip"
            && e["record"]["constraints"]
                .as_array()
                .is_some_and(|c| c.iter().any(|c| c["id"] == "CSs10"))
    });
    assert_eq!(trip["record"]["enforced"], true);
    // The plant keeps A4 ON for as long as C7 is there.
    for _ in 0..20 {
        assert_eq!(plant.coils(), "0000100", "A4 must stay ON while C7 = 1");
    }
    // The box has left: the PLC's release is allowed again.
    plant.set_inputs(&[(C7, false)]);
    wait_until("the plant to release A4", || plant.coils() == "0000000");
    gw.event("reset", Gateway::kind("reset"));
    gw.stop();
}

/// A plant with the empty table at rest at C4 (A4 off) before the gateway starts, so
/// that the gateway's first cycle takes it as read, the gateway (`extra` added to its
/// configuration) and a PLC behind it.
fn gateway_with_the_table_at_c4(extra: &str) -> (Plant, Gateway, Plc) {
    let mut plant = Plant::start(None);
    plant.set_inputs(&[(C4, true)]);
    let mut gw = Gateway::start(&gateway_config(plant.port, extra));
    let server = gw.listening();
    let plc = Plc::start(server, Some("127.0.0.2"));
    (plant, gw, plc)
}

/// A box crosses C3 onto the table at C4 with A1 and the rollers A2 on (CSc2: never
/// onto stopped rollers): the beam rises and, the box's length later, falls (the
/// shortest box takes 1 s at 300 mm/s; a fall sooner than 900 ms would be a transient,
/// which the gateway holds until the beam reads 1 again: `hold_until_back` on C3). Then
/// the PLC stops the rollers again (A1 only), as the program does before the box
/// reaches C6 (CSs6).
fn cross_c3(plant: &mut Plant, plc: &mut Plc, gw: &mut Gateway) {
    plc.command("0110000");
    wait_until("the plant to run A1 A2", || plant.coils() == "0110000");
    plant.set_inputs(&[(C3, true)]);
    wait_until("the PLC to see C3", || plc.sensors().as_bytes()[6] == b'1');
    // The plant peer plays the physics: the box is under the beam for its length.
    let crossing = Instant::now();
    wait_until("the box to cross C3 (1 s)", || {
        crossing.elapsed() >= Duration::from_millis(1_000)
    });
    // The box leaves C3 and comes onto the table: this peer shows C6 in the same scan,
    // faster than the physics (130 ms at the soonest), so the gateway holds C6 until
    // 100 ms after it took the fall of C3 (`rise_not_after`) and says when it takes it.
    plant.set_inputs(&[(C3, false), (C6, true)]);
    wait_until("the PLC to see C3 clear", || {
        plc.sensors().as_bytes()[6] == b'0'
    });
    plc.command("0100000");
    wait_until("the plant to run A1 only", || plant.coils() == "0100000");
    gw.event("the rise of C6 taken", |e| {
        e["event"] == "plausibility"
            && e["sensor"] == "C6"
            && e["text"]
                .as_str()
                .is_some_and(|t| t.contains("plausible again"))
    });
}

/// Issue 17's first finding behind a gateway: the beam at the right exit drops out
/// while a box leaves the table, the PLC (which reads the plant's own inputs) takes it
/// for the box's departure and releases A4; the gateway's plausibility stage holds C7 (no
/// box crosses a beam that fast), so the trip names CSs10 = C7 . /A4 (C7 read as 1)
/// and the table stays held.
#[test]
fn gateway_holds_the_table_through_a_dropout_of_c7() {
    let (mut plant, mut gw, mut plc) = gateway_with_the_table_at_c4("diagnosers: false");
    // Edges as the physics allows them (plant.ron `plausible`): a box crosses C3 while
    // A1 runs and comes onto the table, the table leaves C4 once A4 is applied and
    // reaches C5 a rotation later, the box clears C6 while the rollers run to the right
    // and reaches C7. The gateway holds what comes sooner and says when it takes it.
    wait_until("the PLC to see C4", || plc.sensors() == "di 00001000000");
    plc.command("0100000");
    wait_until("the plant to run A1", || plant.coils() == "0100000");
    cross_c3(&mut plant, &mut plc, &mut gw);
    wait_until("the PLC to see C4 C6", || plc.sensors() == "di 00001010000");
    plc.command("0000100");
    wait_until("the plant to rotate", || plant.coils() == "0000100");
    plant.set_inputs(&[(C4, false)]);
    wait_until("the PLC to see the table leave", || {
        plc.sensors() == "di 00000010000"
    });
    plant.set_inputs(&[(C5, true)]);
    wait_until("the PLC to see C5 C6", || plc.sensors() == "di 00000110000");
    gw.event(
        "the table taken at C5 once the rotation has had its time",
        |e| e["event"] == "plausibility" && e["sensor"] == "C5",
    );
    plc.command("0001101");
    wait_until("the plant to evacuate right", || plant.coils() == "0001101");
    plant.set_inputs(&[(C6, false)]);
    wait_until("the PLC to see the box leave C6", || {
        plc.sensors() == "di 00000100000"
    });
    plant.set_inputs(&[(C7, true)]);
    wait_until("the PLC to see C5 C7", || plc.sensors() == "di 00000101000");
    // The dropout: the PLC sees C7 fall and releases A4.
    plant.set_inputs(&[(C7, false)]);
    wait_until("the PLC to see C7 drop out", || {
        plc.sensors() == "di 00000100000"
    });
    let held = gw.event("C7 suspect", |e| {
        e["event"] == "alarm" && e["key"] == "plausibility:C7"
    });
    assert!(
        held["message"].as_str().unwrap().contains("C7 held at 1"),
        "{held}"
    );
    plc.command("0001001");
    let trip = gw.event("trip on CSs10", |e| {
        e["event"] == "trip"
            && e["record"]["constraints"]
                .as_array()
                .is_some_and(|c| c.iter().any(|c| c["id"] == "CSs10"))
    });
    assert_eq!(trip["record"]["enforced"], true);
    wait_until("the plant to keep A4 on", || {
        plant.coils().as_bytes()[4] == b'1'
    });
    for _ in 0..20 {
        assert_eq!(
            plant.coils().as_bytes()[4],
            b'1',
            "A4 must stay ON under the box"
        );
    }
    // The beam sees the box again: the suspicion ends.
    plant.set_inputs(&[(C7, true)]);
    gw.event("C7 plausible again", |e| {
        e["event"] == "alarm_cleared" && e["key"] == "plausibility:C7"
    });
    let _ = gw.stop();
}

#[test]
fn plc_killed_gives_safe_outputs_then_recovers() {
    let mut plant = Plant::start(None);
    let mut gw = Gateway::start(&gateway_config(plant.port, NO_DIAGNOSERS));
    let server = gw.listening();
    let mut plc = Plc::start(server, Some("127.0.0.2"));
    // A loaded table rotates to the unloading position (CSs8: hold A4 there), the
    // intermediate conveyor on.
    plant.set_inputs(&[(C4, true), (C6, true)]);
    wait_until("the PLC to see C4 C6", || plc.sensors() == "di 00001010000");
    plc.command("0100100");
    wait_until("the plant to receive A1 A4", || plant.coils() == "0100100");
    plant.set_inputs(&[(C4, false), (C5, true)]);
    wait_until("the PLC to see C5 C6", || plc.sensors() == "di 00000110000");
    gw.forget();
    plc.0.kill();
    let alarm = gw.event("PLC lost alarm", |e| {
        e["event"] == "alarm" && e["key"] == "link:plc"
    });
    let safe = gw.event("safe outputs", |e| e["event"] == "safe_outputs");
    // The fallback: every output at its safe value but what a constraint forces: A4
    // held, the safety contactor and valve (KM0, YV0, safe ON) left closed.
    assert_eq!(safe["outputs"], "000010011");
    assert!(safe["time_ms"].as_u64() >= alarm["time_ms"].as_u64());
    wait_until("the plant to hold the fallback", || {
        plant.coils() == "0000100"
    });
    // A PLC comes back.
    let mut plc = Plc::start(server, Some("127.0.0.2"));
    plc.command("0100100");
    gw.event("PLC alarm cleared", |e| {
        e["event"] == "alarm_cleared" && e["key"] == "link:plc"
    });
    wait_until("the plant to follow the PLC again", || {
        plant.coils() == "0100100"
    });
    // Shutdown with the PLC still commanding A1: the plant gets the safe state.
    let stopped = gw.stop();
    assert_eq!(stopped["outputs"], "000010011");
    assert_eq!(plant.coils(), "0000100");
}

#[test]
fn plant_killed_raises_the_alarm_and_reconnects() {
    let mut plant = Plant::start(None);
    let port = plant.port;
    let mut gw = Gateway::start(&gateway_config(port, ""));
    let server = gw.listening();
    let mut plc = Plc::start(server, Some("127.0.0.2"));
    plc.command("1100000");
    wait_until("the plant to receive A0 A1", || plant.coils() == "1100000");
    gw.forget();
    plant.peer.kill();
    let alarm = gw.event("plant lost alarm", |e| {
        e["event"] == "alarm" && e["key"] == "link:plant"
    });
    // Every input is stale now: the outputs the PLC commands are held only if no value
    // of the sensors can make a constraint true (CSc1 = C0 . A0 . /A1 cannot with A1 ON,
    // CSs2 = C3 . /C4 . A1 can): the safe fallback is applied.
    let safe = gw.event("safe outputs", |e| e["event"] == "safe_outputs");
    assert!(safe["reason"].as_str().unwrap().contains("stale"), "{safe}");
    // Within the link timeout: at the latest in the cycle that declares the plant lost.
    assert!(
        safe["time_ms"].as_u64().unwrap() <= alarm["time_ms"].as_u64().unwrap(),
        "safe outputs {safe} after the alarm {alarm}"
    );
    // The plant returns on the same port (a fresh process, all coils 0).
    gw.forget();
    let mut plant = Plant::start(Some(port));
    gw.event("plant alarm cleared", |e| {
        e["event"] == "alarm_cleared" && e["key"] == "link:plant"
    });
    gw.event(
        "safe outputs released",
        Gateway::kind("safe_outputs_released"),
    );
    wait_until("the plant to receive A0 A1 again", || {
        plant.coils() == "1100000"
    });
    gw.stop();
}

#[test]
fn illegal_requests_get_exceptions_and_nothing_crashes() {
    let plant = Plant::start(None);
    let mut gw = Gateway::start(&gateway_config(plant.port, ""));
    let server = gw.listening();
    let mut plc = Plc::start(server, Some("127.0.0.2"));
    // Past the 20 discrete inputs and the 9 coils; no registers at all.
    assert_eq!(plc.0.ask("raw 2 17 5"), "exception 2");
    assert_eq!(plc.0.ask("raw 1 9 1"), "exception 2");
    assert_eq!(plc.0.ask("raw 3 0 1"), "exception 2");
    assert_eq!(plc.0.ask("raw 15 7 4"), "exception 2");
    assert_eq!(plc.0.ask("raw 2 0 11"), "ok 00000000000");
    // A client that is not the PLC (127.0.0.1) may read but not write.
    let mut other = Plc::start(server, None);
    wait_until("the other client's writes to be refused", || {
        let (_, errors, last) = other.status();
        errors > 0 && last == "write:1"
    });
    assert_eq!(other.0.ask("raw 2 0 3"), "ok 000");
    drop(other);
    // Garbage and a truncated frame on raw sockets: the connection is dropped, the
    // server lives on.
    for bytes in [
        &b"\x00\x01\x00\x00\x00\x06\x01\x2b\xff\xff\xff"[..],
        b"hello modbus\r\n\r\n",
        b"\x00\x01\x00\x00\xff\xff",
    ] {
        let mut s = std::net::TcpStream::connect(server).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
        let _ = s.write_all(bytes);
        let mut buf = [0u8; 64];
        let _ = std::io::Read::read(&mut s, &mut buf);
    }
    // An unknown function code gets exception 01.
    let mut s = std::net::TcpStream::connect(server).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    s.write_all(b"\x00\x07\x00\x00\x00\x02\x01\x41").unwrap();
    let mut buf = [0u8; 9];
    std::io::Read::read_exact(&mut s, &mut buf).unwrap();
    assert_eq!(&buf, b"\x00\x07\x00\x00\x00\x03\x01\xc1\x01");
    // A client outside the allow-list (127.0.0.3) is disconnected at once.
    let mut s = std::net::TcpStream::connect_timeout(&server, Duration::from_secs(2));
    if let Ok(s) = s.as_mut() {
        // Connected from 127.0.0.1: allowed. (The allow-list check from another source
        // address is below, through the PLC peer's --source.)
        let _ = s;
    }
    let mut stranger = Plc::start(server, Some("127.0.0.3"));
    wait_until("the stranger to be refused", || {
        let (_, errors, last) = stranger.status();
        errors > 0 && last != "write:1"
    });
    let (scans, _, _) = stranger.status();
    assert_eq!(scans, 0, "a client outside the allow-list got answers");
    // The PLC still works.
    assert_eq!(plc.0.ask("raw 2 0 11"), "ok 00000000000");
    gw.stop();
}

#[test]
fn monitor_reports_with_explanations_and_never_writes() {
    let mut plant = Plant::start(None);
    let body = format!(
        "mode: Monitor, cycle_ms: 10, link_timeout_cycles: 10, \
         client: Modbus(address: \"127.0.0.1:{}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200)",
        plant.port
    );
    // The PLC (here the pymodbus server exposing sensors and commanded coils) lets A4
    // go while C7 = 1. The values are there before the monitor's first read: set
    // later, they would be edges the plausibility stage holds (the table cannot reach
    // C5 sooner than a rotation after A4, a box reaches C7 only from the table at C5
    // with A3 on), or not, depending on when the monitor first read the peer.
    plant.set_inputs(&[(C5, true), (C7, true)]);
    assert_eq!(plant.peer.ask("co 4 0"), "ok");
    let mut gw = Gateway::start(&body);
    gw.event("monitoring", Gateway::kind("monitoring"));
    let v = gw.event("violation of CSs10", |e| {
        e["event"] == "violation"
            && e["record"]["constraints"]
                .as_array()
                .is_some_and(|c| c.iter().any(|c| c["id"] == "CSs10"))
    });
    assert_eq!(v["record"]["enforced"], false);
    assert!(v["explanation"].is_object(), "{v}");
    // Level 1 in live mode: an emulator initialised from the observed sensors projects
    // the released table with the box at C7.
    let projection = &v["explanation"]["projection"]["items"];
    assert!(
        projection.as_array().is_some_and(|items| !items.is_empty()),
        "{projection}"
    );
    // Nothing was written: A4 is still OFF at the peer.
    for _ in 0..10 {
        assert_eq!(plant.coils(), "0000000");
    }
    // The peer dies: link alarm, and it comes back.
    let port = plant.port;
    plant.peer.kill();
    gw.event("link alarm", |e| {
        e["event"] == "alarm" && e["key"] == "link:peer"
    });
    let _plant = Plant::start(Some(port));
    gw.event("link alarm cleared", |e| {
        e["event"] == "alarm_cleared" && e["key"] == "link:peer"
    });
    gw.stop();
}

/// A `diagnosis` event of the partition `partition`.
fn diagnosis_of(partition: &'static str) -> impl Fn(&serde_json::Value) -> bool {
    move |e| e["event"] == "diagnosis" && e["partition"] == partition
}

#[test]
fn gateway_diagnoses_c4_stuck_at_rest_and_the_plc_and_filter_read_its_estimate() {
    let (mut plant, mut gw, mut plc) = gateway_with_the_table_at_c4("");
    plc.command("0000000");
    // The diagnosers start on the plant in its initial state.
    gw.event("the diagnosers' start", |e| {
        e["event"] == "diagnosers" && e["state"] == "started"
    });
    wait_until("the PLC to see C4", || plc.sensors() == "di 00001000000");
    // C4 dies (stuck at 0) while the table stays: the table's diagnoser sees the fall
    // with A4 off; once no pulse end (2 s) and no motion (C5 within I4, 3.1 s) explains
    // it, the fault is certainly in partition C4 (docs/diagnoser.md).
    plant.set_inputs(&[(C4, false)]);
    let fell = Instant::now();
    let d = gw.event("a diagnosis of C4", diagnosis_of("C4"));
    assert!(
        fell.elapsed() >= Duration::from_secs(2),
        "diagnosed after {:?}: {d}",
        fell.elapsed()
    );
    assert_eq!(d["component"], "table", "{d}");
    assert_eq!(d["certainty"], "certain", "{d}");
    assert_eq!(d["estimated"], "C4", "{d}");
    assert_eq!(d["stop"], false, "{d}");
    assert!(d["fault"].as_str().unwrap().contains("F1"), "{d}");
    assert!(d["time_ms"].as_u64().is_some(), "{d}");
    gw.event("the diagnosis alarm", |e| {
        e["event"] == "alarm" && e["key"] == "diag:table:C4"
    });
    // Degraded mode: the PLC reads Ĉ4 (1: the table rests since long, I10) in place of
    // the dead sensor, as the simulation's program does.
    wait_until("the PLC to read the estimate of C4", || {
        plc.sensors() == "di 00001000000"
    });
    // The filter reads it too: rotating the empty table trips CSs13 (C4 . /C6 . A4,
    // with the estimate), not CSs14 (/C4 . RE(A4), with the dead sensor).
    gw.forget();
    plc.command("0000100");
    let trip = gw.event("a trip", Gateway::kind("trip"));
    let ids: Vec<&str> = trip["record"]["constraints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, ["CSs13"], "{trip}");
    assert!(
        trip["record"]["constraints"][0]["literals"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l["name"] == "EST(C4)" && l["value"] == true),
        "{trip}"
    );
    for _ in 0..10 {
        assert_eq!(plant.coils(), "0000000", "the empty table must not rotate");
    }
    plc.command("0000000");
    // The final report carries the diagnosis.
    let stopped = gw.stop();
    let diagnoses = stopped["diagnoses"].as_array().unwrap();
    assert!(
        diagnoses
            .iter()
            .any(|d| d["partition"] == "C4" && d["component"] == "table"),
        "{stopped}"
    );
}

#[test]
fn gateway_stops_the_plant_on_a_certain_fault_of_the_table_drive() {
    let (mut plant, mut gw, mut plc) = gateway_with_the_table_at_c4("");
    gw.event("the diagnosers' start", |e| {
        e["event"] == "diagnosers" && e["state"] == "started"
    });
    // A box comes onto the table with the intermediate conveyor.
    plc.command("0100000");
    wait_until("the plant to receive A1", || plant.coils() == "0100000");
    cross_c3(&mut plant, &mut plc, &mut gw);
    wait_until("the PLC to see C4 C6", || plc.sensors() == "di 00001010000");
    // The PLC orders the rotation; the table does not move (blocked at C4): no fall of
    // C4 within I2, no rise of C5 within I4. Partition P (stop) becomes certain.
    plc.command("0100100");
    wait_until("the plant to receive A1 A4", || plant.coils() == "0100100");
    let d = gw.event("a diagnosis of P", diagnosis_of("P"));
    assert_eq!(d["component"], "table", "{d}");
    assert_eq!(d["stop"], true, "{d}");
    assert!(d["fault"].as_str().unwrap().contains("F5"), "{d}");
    // From the next cycle on, DSTOP_P drives every output to its safe value (0),
    // whatever the PLC commands, as in the simulation, except what a constraint forces:
    // A4, once applied, is released only at C5 (CSs15), so it stays on; A1 stops.
    gw.event("the stop", |e| {
        e["event"] == "trip"
            && e["record"]["constraints"]
                .as_array()
                .is_some_and(|c| c.iter().any(|c| c["id"] == "DSTOP_P"))
    });
    wait_until("the plant to be stopped", || plant.coils() == "0000100");
    for _ in 0..10 {
        assert_eq!(plant.coils(), "0000100", "the PLC's A1 must not pass");
    }
    let stopped = gw.stop();
    assert_eq!(stopped["outputs"], "000010011", "A4, KM0 and YV0 ON");
    assert!(
        stopped["diagnoses"]
            .as_array()
            .unwrap()
            .iter()
            .any(|d| d["partition"] == "P"),
        "{stopped}"
    );
}

#[test]
fn monitor_reports_a_diagnosis_and_the_diagnosers_can_be_switched_off() {
    for on in [true, false] {
        let mut plant = Plant::start(None);
        // The empty table at rest at C4: the initial state. Without the diagnosers, a
        // box is already at C7 with A4 off when the monitor attaches: its first reading
        // is taken as it is (a box appearing at C7 later, with the table at C4, would be
        // an implausible rise that the plausibility stage holds; whether the test set it
        // before or after the monitor's first poll was a race under load).
        plant.set_inputs(&[(C4, true)]);
        if !on {
            plant.set_inputs(&[(C7, true)]);
        }
        let body = format!(
            "mode: Monitor, cycle_ms: 10, link_timeout_cycles: 10, diagnosers: {on}, \
             client: Modbus(address: \"127.0.0.1:{}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200)",
            plant.port
        );
        let mut gw = Gateway::start(&body);
        let m = gw.event("monitoring", Gateway::kind("monitoring"));
        assert_eq!(m["diagnosers"], on, "{m}");
        if !on {
            // The paper's constraints as written (with the diagnosers CSs10 reads
            // `C7 . /A4 . /def_P`): a box at C7 with A4 off.
            let v = gw.event("the violation of CSs10", Gateway::kind("violation"));
            let c = &v["record"]["constraints"][0];
            assert_eq!(c["id"], "CSs10", "{v}");
            assert!(!c["notation"].as_str().unwrap().contains("def_"), "{v}");
            let stopped = gw.stop();
            assert_eq!(stopped["diagnoses"], serde_json::json!([]), "{stopped}");
            continue;
        }
        // The diagnosers start on the first values read, then C4 dies.
        gw.event("the diagnosers' start", |e| {
            e["event"] == "diagnosers" && e["state"] == "started"
        });
        plant.set_inputs(&[(C4, false)]);
        let d = gw.event("a diagnosis of C4", diagnosis_of("C4"));
        // Report-only: the PLC keeps reading its own sensor.
        assert!(
            d["text"]
                .as_str()
                .unwrap()
                .contains("the control program still reads C4"),
            "{d}"
        );
        let stopped = gw.stop();
        assert!(
            stopped["diagnoses"]
                .as_array()
                .unwrap()
                .iter()
                .any(|d| d["partition"] == "C4" && d["component"] == "table"),
            "{stopped}"
        );
    }
}

fn mbpoll_run(args: &[&str]) -> String {
    let out = Command::new(mbpoll()).args(args).output().unwrap();
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn emulator_served_to_pymodbus_and_mbpoll() {
    let mut gw = Gateway::start(
        "mode: Emulator, cycle_ms: 10, seed: 1, \
         server: Modbus(bind: \"127.0.0.1:0\", allow: [\"127.0.0.1\", \"127.0.0.2\"], plc: \"127.0.0.2\")",
    );
    let server = gw.listening();
    let port = server.port().to_string();
    let base = ["-m", "tcp", "-a", "1", "-0", "-1", "-o", "2", "-p", &port];
    // mbpoll reads the 11 sensors.
    let mut args = base.to_vec();
    args.extend(["-t", "1", "-r", "0", "-c", "11", "127.0.0.1"]);
    let out = mbpoll_run(&args);
    assert!(out.contains("[10]:"), "{out}");
    // The soft-PLC (pymodbus, the configured PLC address) closes the safety contactor
    // KM0 (coil 7: served, the emulator is the plant and obeys its coils) and runs the
    // entry conveyor.
    let mut plc = Plc::start(server, Some("127.0.0.2"));
    plc.command("100000010");
    // mbpoll reads the coils back.
    let mut args = base.to_vec();
    args.extend(["-t", "0", "-r", "0", "-c", "7", "127.0.0.1"]);
    wait_until("mbpoll to read A0 = 1", || {
        let out = mbpoll_run(&args);
        out.contains("[0]: \t1") && out.contains("[1]: \t0")
    });
    // The emulated plant moves: a box reaches the end of the entry conveyor (C0).
    wait_until("the emulator to raise C0", || {
        plc.sensors().starts_with("di 1")
    });
    // mbpoll is not the PLC: its write is refused; past the image is an illegal address.
    let mut args = base.to_vec();
    args.extend(["-t", "0", "-r", "3", "127.0.0.1", "1"]);
    let out = mbpoll_run(&args);
    assert!(out.to_lowercase().contains("illegal function"), "{out}");
    let mut args = base.to_vec();
    args.extend(["-t", "1", "-r", "20", "-c", "2", "127.0.0.1"]);
    let out = mbpoll_run(&args);
    assert!(out.to_lowercase().contains("illegal data address"), "{out}");
    gw.stop();
}

/// A kill -9 of the gateway in the middle of a burst of events loses no journal entry
/// that reached stdout (a line is printed only once its transaction committed), and
/// the historian opens sound afterwards, with the process history of the run.
#[test]
fn kill_9_of_the_gateway_during_a_burst_loses_no_committed_entry() {
    let mut plant = Plant::start(None);
    let body = format!(
        "mode: Monitor, cycle_ms: 10, link_timeout_cycles: 50, {NO_DIAGNOSERS}, \
         client: Modbus(address: \"127.0.0.1:{}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200)",
        plant.port
    );
    // A box at C7 with the table at C5: every release of A4 is a violation of CSs10.
    plant.set_inputs(&[(C5, true), (C7, true)]);
    let mut gw = Gateway::start(&body);
    gw.event("monitoring", Gateway::kind("monitoring"));
    let mut printed: Vec<String> = Vec::new();
    let violations = |p: &[String]| p.iter().filter(|l| l.contains("\"violation\"")).count();
    // The burst: A4 on and off as fast as the peer answers, until 40 violations were
    // printed (bounded: at most 20,000 toggles).
    for k in 0..20_000 {
        assert_eq!(plant.peer.ask(&format!("co 4 {}", k % 2)), "ok");
        printed.extend(gw.peer.lines.try_iter());
        if violations(&printed) >= 40 {
            break;
        }
    }
    assert!(
        violations(&printed) >= 40,
        "a burst of violations: {printed:#?}"
    );
    // The process history reaches the disk during the run (a batch a second): A4's
    // changes are there before the kill.
    let a4_changes = |store: &vigie_app::historian::Store| -> u64 {
        let now = vigie_app::historian::wall_ms();
        let trend = store
            .trend("A4.cmd", now - 600_000, now + 1000, 600)
            .expect("trend");
        trend.buckets.iter().map(|b| b.changes).sum()
    };
    let reader = vigie_app::historian::Store::open_in(&gw.state).expect("historian opens");
    let mut k = 0;
    wait_until("A4's changes in the process history", || {
        k += 1;
        assert_eq!(plant.peer.ask(&format!("co 4 {}", k % 2)), "ok");
        a4_changes(&reader) >= 2
    });
    drop(reader);
    // Killed in the middle of it (the toggles go on while it dies).
    let _ = plant.peer.ask("co 4 1");
    gw.peer.kill();
    let _ = plant.peer.ask("co 4 0");
    // Whatever reached stdout before the kill (the reader thread may still hold lines).
    printed.extend(gw.peer.lines.try_iter());
    let store =
        vigie_app::historian::Store::open_in(&gw.state).expect("historian opens after kill -9");
    assert_eq!(store.integrity().expect("integrity check"), "ok");
    let journal: std::collections::BTreeSet<String> = store
        .journal(0, "", usize::MAX >> 1)
        .expect("journal")
        .into_iter()
        .map(|r| r.text)
        .collect();
    let missing: Vec<&String> = printed.iter().filter(|l| !journal.contains(*l)).collect();
    assert!(
        missing.is_empty(),
        "{} of {} printed events are not in the journal: {missing:#?}",
        missing.len(),
        printed.len()
    );
    assert!(a4_changes(&store) >= 2);
}

/// A virtual X display for a real console window (`Xvfb -displayfd`: the server picks
/// a free display number and prints it).
pub(crate) struct Xvfb {
    child: Child,
    pub(crate) display: String,
}

impl Xvfb {
    pub(crate) fn start() -> Self {
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x720x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start Xvfb (scripts/test.sh installs it): {e}"));
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::Builder::new()
            .name("xvfb-display".into())
            .spawn(move || {
                let mut line = String::new();
                let _ = BufReader::new(stdout).read_line(&mut line);
                let _ = tx.send(line);
            })
            .unwrap();
        let n = rx.recv_timeout(WAIT).expect("Xvfb printed its display");
        let n = n.trim();
        assert!(
            !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()),
            "Xvfb display {n:?}"
        );
        Self {
            child,
            display: format!(":{n}"),
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A kill -9 of the console (a real window on Xvfb, following a monitor link) during a
/// burst of journal entries: every entry committed before the kill is still there,
/// and the historian opens sound.
#[test]
fn kill_9_of_the_console_during_a_burst_loses_no_committed_entry() {
    let x = Xvfb::start();
    let mut plant = Plant::start(None);
    plant.set_inputs(&[(C5, true), (C7, true)]);
    let dir = TempDir::new("console-kill");
    let data = dir.0.join("data");
    let station = repo()
        .join("layouts/sorting-station")
        .canonicalize()
        .unwrap();
    let config = dir.0.join("monitor.ron");
    std::fs::write(
        &config,
        format!(
            "Gateway(mode: Monitor, plant: {:?}, cycle_ms: 10, link_timeout_cycles: 50, {NO_DIAGNOSERS}, \
             state_dir: {:?}, client: Modbus(address: \"127.0.0.1:{}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200))",
            station.display().to_string(),
            dir.0.join("link-state").display().to_string(),
            plant.port
        ),
    )
    .unwrap();
    let mut console = Command::new(env!("CARGO_BIN_EXE_vigie"))
        .arg("--link")
        .arg(&config)
        .env("DISPLAY", &x.display)
        .env("VIGIE_DATA_DIR", &data)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("the console starts");
    // The burst: every release of A4 while the box is at C7 is a trip entry.
    let mut seen = Vec::new();
    let mut k = 0;
    wait_until("60 trip entries committed by the console", || {
        k += 1;
        assert_eq!(plant.peer.ask(&format!("co 4 {}", k % 2)), "ok");
        if k % 20 == 0
            && data.join(vigie_app::historian::FILE).exists()
            && let Ok(store) = vigie_app::historian::Store::open_in(&data)
        {
            seen = store.journal(0, "", usize::MAX >> 1).unwrap_or_default();
        }
        assert!(console.try_wait().unwrap().is_none(), "the console exited");
        seen.iter().filter(|r| r.kind == "trip").count() >= 60
    });
    // Killed while the burst goes on.
    let _ = plant.peer.ask("co 4 1");
    console.kill().unwrap();
    let _ = console.wait();
    let store = vigie_app::historian::Store::open_in(&data).expect("historian opens after kill -9");
    assert_eq!(store.integrity().expect("integrity check"), "ok");
    let after = store.journal(0, "", usize::MAX >> 1).expect("journal");
    assert!(after.len() >= seen.len());
    assert_eq!(
        &after[..seen.len()],
        &seen[..],
        "the committed entries are intact"
    );
}

/// A PLC stand-in: a control program scanned every 5 ms on the sensors the test sets,
/// its outputs written to the pymodbus plant's coils, as a PLC drives its own bus.
pub(crate) struct StandIn {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// The operator's START, pressed at the next scan once set.
    start: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// Scans run so far.
    scans: std::sync::Arc<std::sync::atomic::AtomicU64>,
    inputs: std::sync::Arc<std::sync::Mutex<vigie_core::Bits>>,
    thread: Option<std::thread::JoinHandle<()>>,
    plant: std::sync::Arc<std::sync::Mutex<Plant>>,
}

impl StandIn {
    /// Runs `program` (the station's) against `plant`; START waits for [`Self::press_start`].
    pub(crate) fn start(plant: Plant, program: vigie_core::control::Program) -> Self {
        use std::sync::atomic::{AtomicBool, Ordering};
        use std::sync::{Arc, Mutex};
        use vigie_core::engine::Control as _;
        let station =
            vigie_core::plant::Plant::load(&repo().join("layouts/sorting-station/plant.ron"))
                .unwrap_or_else(|p| panic!("{p:?}"));
        let compiled = vigie_core::control::CompiledProgram::new(
            &program,
            &station,
            &vigie_core::control::Origin::default(),
        )
        .unwrap_or_else(|p| panic!("{}", vigie_core::diag::render(&p)));
        let stop = Arc::new(AtomicBool::new(false));
        let inputs = Arc::new(Mutex::new(vigie_core::Bits::zeros(station.inputs.len())));
        let plant = Arc::new(Mutex::new(plant));
        let start_button = Arc::new(AtomicBool::new(false));
        let (s, i, p) = (Arc::clone(&stop), Arc::clone(&inputs), Arc::clone(&plant));
        let go = Arc::clone(&start_button);
        let scans = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let counter = Arc::clone(&scans);
        let thread = std::thread::Builder::new()
            .name("plc-stand-in".into())
            .spawn(move || {
                let mut rt = vigie_core::control::ProgramRuntime::new(Arc::new(compiled));
                let n_out = station.outputs.len();
                let mut frame = vigie_core::frame::Frame::new([station.inputs.len(), n_out, 0, 0]);
                let mut out = vigie_core::Bits::zeros(n_out);
                let mut written: Option<vigie_core::Bits> = None;
                let start = Instant::now();
                // Bounded: a stand-in left running stops after two minutes.
                let mut pressed = false;
                while !s.load(Ordering::Relaxed) && start.elapsed() < Duration::from_secs(120) {
                    if !pressed && go.load(Ordering::Relaxed) {
                        rt.press("START").expect("the station's START");
                        pressed = true;
                    }
                    frame.shift();
                    frame
                        .now_mut(vigie_core::symbols::Space::Input)
                        .copy_from(&i.lock().expect("inputs"));
                    let now = u64::try_from(start.elapsed().as_millis()).unwrap_or(u64::MAX);
                    rt.scan(vigie_core::Millis(now), &frame, &mut out);
                    let mut plant = p.lock().expect("plant");
                    for k in 0..n_out {
                        if written.as_ref().is_none_or(|w| w.get(k) != out.get(k)) {
                            let reply = plant.peer.ask(&format!("co {k} {}", u8::from(out.get(k))));
                            assert_eq!(reply, "ok");
                        }
                    }
                    drop(plant);
                    written = Some(out.clone());
                    counter.fetch_add(1, Ordering::Relaxed);
                    // The PLC's own scan period.
                    std::thread::sleep(Duration::from_millis(5));
                }
            })
            .expect("the stand-in's thread starts");
        Self {
            stop,
            start: start_button,
            scans,
            inputs,
            thread: Some(thread),
            plant,
        }
    }

    /// Waits until the stand-in has scanned `n` times more: a state held that long
    /// (20 scans, 100 ms) is seen by the monitor for several of its cycles, more than
    /// the follower's tolerance.
    fn scans(&self, n: u64) {
        use std::sync::atomic::Ordering;
        let from = self.scans.load(Ordering::Relaxed);
        wait_until("scans of the PLC", || {
            self.scans.load(Ordering::Relaxed) >= from + n
        });
    }

    /// The operator presses START.
    pub(crate) fn press_start(&self) {
        self.start.store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// Sets sensors at the plant and in the stand-in's next scan.
    pub(crate) fn set(&self, bits: &[(u16, bool)]) {
        let mut i = self.inputs.lock().expect("inputs");
        for &(a, v) in bits {
            i.set(usize::from(a), v);
        }
        self.plant.lock().expect("plant").set_inputs(bits);
    }

    /// The plant's coils as the stand-in wrote them.
    pub(crate) fn coils(&self) -> String {
        self.plant.lock().expect("plant").coils()
    }
}

impl Drop for StandIn {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A box through the station's feed, as the sensors see it: it reaches C0, is pushed
/// (C0 falls), travels to C3, with the turntable at the loading position (C4).
fn feed_one_box(plc: &StandIn) {
    plc.set(&[(C4, true)]);
    wait_until("the feed conveyor A0 to run after START", || {
        plc.coils().starts_with('1')
    });
    plc.set(&[(0, true)]);
    wait_until("the push (A1 on)", || plc.coils().as_bytes()[1] == b'1');
    plc.scans(20);
    plc.set(&[(0, false)]);
    plc.scans(20);
    plc.set(&[(C3, true)]);
}

/// `vigie gateway --program FILE` in monitor mode follows the PLC with the program it
/// should run (here the station's reference, given as PLCopen XML): no alarm while the
/// PLC stand-in runs that program; with a stand-in running a mutated program (the
/// intermediate conveyor's step left on the rise of C3 instead of its fall) the
/// `program_divergence` event and alarm name the first output that differs, A1.
#[test]
fn monitor_follows_the_given_program_and_names_the_first_diverging_output() {
    let station = repo().join("layouts/sorting-station");
    let plant_ron = vigie_core::plant::Plant::load(&station.join("plant.ron"))
        .unwrap_or_else(|p| panic!("{p:?}"));
    let reference = vigie_core::control::CompiledProgram::load(
        &station.join("programs/reference.ron"),
        &plant_ron,
    )
    .unwrap_or_else(|p| panic!("{p:?}"))
    .program;
    let dir = TempDir::new("follow");
    let xml = dir.0.join("reference.xml");
    std::fs::write(
        &xml,
        vigie_core::plcopen::export(&reference, &plant_ron, Path::new("reference.ron"))
            .expect("exports"),
    )
    .expect("writes");
    let body = |port: u16| {
        format!(
            "mode: Monitor, cycle_ms: 10, link_timeout_cycles: 50, {NO_DIAGNOSERS}, \
             client: Modbus(address: \"127.0.0.1:{port}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200)"
        )
    };
    let run = |program: vigie_core::control::Program| {
        let plant = Plant::start(None);
        let port = plant.port;
        let plc = StandIn::start(plant, program);
        let mut gw = Gateway::start_with(&body(port), &["--program", xml.to_str().expect("utf-8")]);
        let m = gw.event("monitoring", Gateway::kind("monitoring"));
        assert!(
            m["program"]
                .as_str()
                .is_some_and(|p| p.contains("reference")),
            "{m}"
        );
        // The PLC's program is at rest when the following starts; then START.
        gw.event("following", Gateway::kind("program_following"));
        plc.press_start();
        feed_one_box(&plc);
        (gw, plc)
    };
    // The program given: followed without an alarm.
    let (mut gw, plc) = run(reference.clone());
    wait_until("the table to take the box (A2 on)", || {
        plc.coils().as_bytes()[2] == b'1'
    });
    let end = gw.stop();
    assert!(
        !gw.events.iter().any(|e| e["event"] == "program_divergence"),
        "{:#?}",
        gw.events
    );
    assert!(end.is_object());
    drop(plc);
    // A mutated program in the PLC.
    let mut mutant = reference;
    for c in &mut mutant.charts {
        for t in &mut c.transitions {
            if t.condition == "FE(C3)" && t.from == ["X12"] {
                t.condition = "RE(C3)".into();
            }
        }
    }
    let (mut gw, _plc) = run(mutant);
    let d = gw.event("the divergence", Gateway::kind("program_divergence"));
    assert_eq!(d["output"], "A1", "{d}");
    assert_eq!(
        (d["plc"].as_bool(), d["program"].as_bool()),
        (Some(false), Some(true)),
        "{d}"
    );
    gw.event("its alarm", |e| {
        e["event"] == "alarm" && e["key"] == "program:divergence"
    });
    gw.stop();
}

/// A PLC runs the station's error E11 (the feed conveyor A0 not stopped when a box
/// reaches C0), and `--program` is given that same program as PLCopen XML: the PLC is
/// followed without a divergence, and the violation of CSc1 is explained by the
/// program: its equation of A0 (X410) leads the hypothesis, placed in the file (X420).
#[test]
fn monitor_explains_a_violation_with_the_program_given() {
    let station = repo().join("layouts/sorting-station");
    let plant_ron = vigie_core::plant::Plant::load(&station.join("plant.ron"))
        .unwrap_or_else(|p| panic!("{p:?}"));
    let lib =
        vigie_core::control::ErrorLibrary::load(&station.join("programs/errors.ron"), &plant_ron)
            .unwrap_or_else(|p| panic!("{p:?}"));
    let e11 = lib
        .variants
        .into_iter()
        .find(|v| v.def.id == "E11")
        .expect("E11")
        .program;
    let dir = TempDir::new("follow-explain");
    let xml = dir.0.join("e11.xml");
    std::fs::write(
        &xml,
        vigie_core::plcopen::export(&e11, &plant_ron, Path::new("e11.ron")).expect("exports"),
    )
    .expect("writes");
    let plant = Plant::start(None);
    let port = plant.port;
    let plc = StandIn::start(plant, e11);
    let mut gw = Gateway::start_with(
        &format!(
            "mode: Monitor, cycle_ms: 10, link_timeout_cycles: 50, {NO_DIAGNOSERS}, \
             client: Modbus(address: \"127.0.0.1:{port}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200)"
        ),
        &["--program", xml.to_str().expect("utf-8")],
    );
    gw.event("following", Gateway::kind("program_following"));
    plc.press_start();
    plc.set(&[(C4, true)]);
    wait_until("the feed conveyor A0 to run after START", || {
        plc.coils().starts_with('1')
    });
    // A box at C0: the reference stops A0 (or pushes with A1); E11 keeps feeding.
    plc.set(&[(0, true)]);
    let v = gw.event("the violation of CSc1", |e| {
        e["event"] == "violation"
            && e["record"]["constraints"]
                .as_array()
                .is_some_and(|c| c.iter().any(|c| c["id"] == "CSc1"))
    });
    let items = v["explanation"]["hypothesis"]["items"]
        .as_array()
        .unwrap_or_else(|| panic!("no hypothesis: {v}"))
        .clone();
    let codes: Vec<&str> = items.iter().filter_map(|i| i["code"].as_str()).collect();
    let first_program = codes
        .iter()
        .position(|c| ("X407".."X418").contains(c))
        .unwrap_or_else(|| panic!("no program suspect: {codes:?}"));
    assert_eq!(
        codes.get(first_program + 1),
        Some(&"X420"),
        "the suspect placed in the file: {codes:?}"
    );
    assert!(
        items.iter().any(|i| i["code"] == "X420"
            && i["fields"]["file"] == "e11.xml"
            && i["fields"]["element"] == "A0"),
        "{items:#?}"
    );
    assert!(
        !gw.events.iter().any(|e| e["event"] == "program_divergence"),
        "{:#?}",
        gw.events
    );
    gw.stop();
}
