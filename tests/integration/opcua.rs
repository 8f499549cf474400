//! The live link over OPC UA against independent real peers on 127.0.0.1, as
//! `live.rs` tests it over Modbus (OS-chosen ports, no fixed sleeps: every wait polls a
//! condition with a deadline):
//! - asyncua (pinned in `requirements-test.txt`) as the plant server and as the PLC
//!   client (`tests/peers/opcua_plant.py`, `tests/peers/opcua_plc.py`);
//! - pymodbus as the plant of a mixed gateway (OPC UA to the PLC, Modbus to the plant).
//!
//! Each scenario runs twice (`NAME::none`, `NAME::sign_and_encrypt`): security None
//! with anonymous sessions, and Basic256Sha256 SignAndEncrypt with user names and
//! passwords and every certificate trusted explicitly (Vigie's, made by `vigie opcua
//! cert`, in the peer's trust list; the peer's in Vigie's configuration); the round
//! trip runs with Sign too. The venv python is `$VIGIE_VENV/bin/python` or
//! `<repo>/.venv/bin/python`; without it (or without asyncua in it) these tests fail.

use crate::live::{Gateway, Peer, Plant as ModbusPlant, TempDir, python, repo, wait_until};
use std::io::{BufRead as _, BufReader, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc::channel;
use std::sync::{Arc, Mutex};

/// The namespace of the address space Vigie serves for the sorting station (and
/// expects of a plant when no node map says otherwise).
pub(crate) const NAMESPACE: &str = "urn:vigie:sorting-station";

/// The security of a run: every OPC UA link of the test uses it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sec {
    /// Security None, anonymous sessions (loopback only).
    None,
    /// Basic256Sha256 SignAndEncrypt, user names and passwords.
    Encrypt,
    /// Basic256Sha256 Sign, user names and passwords (Vigie's server offers Sign and
    /// SignAndEncrypt, the PLC takes Sign).
    Sign,
}

impl Sec {
    /// The peers' `--security` and Vigie's client `security`.
    fn names(self) -> (&'static str, &'static str) {
        match self {
            Self::None => ("none", "None"),
            Self::Encrypt => ("encrypt", "SignAndEncrypt"),
            Self::Sign => ("sign", "Sign"),
        }
    }
}

/// Runs a scenario once per security: `opcua::NAME::none` and
/// `opcua::NAME::sign_and_encrypt`.
macro_rules! both {
    ($scenario:ident) => {
        mod $scenario {
            #[test]
            fn none() {
                super::$scenario(super::Sec::None);
            }

            #[test]
            fn sign_and_encrypt() {
                super::$scenario(super::Sec::Encrypt);
            }
        }
    };
}

/// The user Vigie's client is at the plant, and its password.
const PLANT_USER: &str = "vigie";
const PLANT_PASSWORD: &str = "plant-secret";
/// The PLC's user at Vigie's server, and its password.
const PLC_USER: &str = "plc";
const PLC_PASSWORD: &str = "plc-secret";
/// Another user of Vigie's server (same password): it may read, not write.
const OPERATOR: &str = "operator";

/// The station's signals as `plant.ron` lists them.
struct Signals {
    /// Every input (sensors, then mirror contacts).
    inputs: Vec<String>,
    /// Every output.
    outputs: Vec<String>,
    /// The sensors a PLC reads (the inputs that are not mirror contacts): C0..C10.
    sensors: Vec<String>,
    /// The outputs a PLC commands (not the safety devices Vigie holds on): A0..A6.
    commands: Vec<String>,
    /// The mirror contacts as the plant peer's `--mirror` (`A0:A0_fb,...`).
    mirrors: String,
}

fn station() -> Signals {
    let plant = vigie_core::plant::Plant::load(&repo().join("layouts/sorting-station/plant.ron"))
        .unwrap_or_else(|p| panic!("{p:?}"));
    let ids = |s: &[vigie_core::plant::Signal]| s.iter().map(|s| s.id.clone()).collect();
    Signals {
        inputs: ids(&plant.inputs),
        outputs: ids(&plant.outputs),
        sensors: plant
            .inputs
            .iter()
            .filter(|s| s.feedback_of.is_none())
            .map(|s| s.id.clone())
            .collect(),
        commands: plant
            .outputs
            .iter()
            .filter(|s| !s.held_on)
            .map(|s| s.id.clone())
            .collect(),
        mirrors: plant
            .mirrors()
            .into_iter()
            .map(|(i, o)| format!("{}:{}", plant.outputs[o].id, plant.inputs[i].id))
            .collect::<Vec<_>>()
            .join(","),
    }
}

/// Vigie's own certificate in the PKI of the state folder `state`.
fn own_certificate(state: &Path) -> PathBuf {
    state.join("pki/own/cert.der")
}

/// One test's OPC UA setting: its folder (configurations, certificates, passwords,
/// Vigie's state), its security and the PLC's password hash.
pub(crate) struct Ua {
    sec: Sec,
    dir: TempDir,
    plc_hash: String,
    configs: std::cell::Cell<u32>,
}

impl Ua {
    pub(crate) fn new(sec: Sec, tag: &str) -> Self {
        let dir = TempDir::new(tag);
        std::fs::create_dir_all(dir.0.join("plant-trust")).unwrap();
        std::fs::write(
            dir.0.join("plant-password.txt"),
            format!("{PLANT_PASSWORD}\n"),
        )
        .unwrap();
        let plc_hash = if sec != Sec::None {
            hash_password(PLC_PASSWORD)
        } else {
            String::new()
        };
        Self {
            sec,
            dir,
            plc_hash,
            configs: std::cell::Cell::new(0),
        }
    }

    /// Vigie's state folder (its PKI under `pki/`).
    fn state(&self) -> PathBuf {
        self.dir.0.join("state")
    }

    /// The PLC's certificate folder (`client_cert.der`).
    fn plc_certs(&self) -> PathBuf {
        self.dir.0.join("plc")
    }

    /// The plant's certificate.
    fn plant_certificate(&self) -> PathBuf {
        self.dir.0.join("plant/server_cert.der")
    }

    /// The arguments of the python plant for this security.
    fn plant_args(&self) -> Vec<String> {
        match self.sec {
            Sec::None => vec!["--security".into(), "none".into()],
            Sec::Encrypt | Sec::Sign => vec![
                "--security".into(),
                self.sec.names().0.into(),
                "--cert-dir".into(),
                path_text(&self.dir.0.join("plant")),
                "--trust".into(),
                path_text(&self.dir.0.join("plant-trust")),
                "--user".into(),
                format!("{PLANT_USER}:{PLANT_PASSWORD}"),
            ],
        }
    }

    /// The arguments of the python PLC (its certificates in `certs`, its user name
    /// and password).
    fn plc_args(&self, certs: &Path, user: &str, password: &str) -> Vec<String> {
        match self.sec {
            Sec::None => vec!["--security".into(), "none".into()],
            Sec::Encrypt | Sec::Sign => vec![
                "--security".into(),
                self.sec.names().0.into(),
                "--cert-dir".into(),
                path_text(certs),
                "--server-cert".into(),
                path_text(&own_certificate(&self.state())),
                "--user".into(),
                user.into(),
                "--password".into(),
                password.into(),
            ],
        }
    }

    /// Vigie's OPC UA client section towards `endpoint`; `extra` inside it (a node map).
    pub(crate) fn client(&self, endpoint: &str, extra: &str) -> String {
        let security = match self.sec {
            Sec::None => "security: None".to_string(),
            Sec::Encrypt | Sec::Sign => format!(
                "security: {}, server_certificate: {:?}, user: {PLANT_USER:?}, password_file: {:?}",
                self.sec.names().1,
                path_text(&self.plant_certificate()),
                path_text(&self.dir.0.join("plant-password.txt"))
            ),
        };
        format!(
            "client: OpcUa(endpoint: {endpoint:?}, {security}, timeout_ms: 500, \
             backoff_initial_ms: 20, backoff_max_ms: 200, {extra})"
        )
    }

    /// Vigie's OPC UA server section (port chosen by the OS).
    fn server(&self) -> String {
        match self.sec {
            Sec::None => "server: OpcUa(bind: \"127.0.0.1:0\", security: [None], anonymous: true, \
                          plc_user: \"anonymous\")"
                .to_string(),
            Sec::Encrypt | Sec::Sign => {
                // The PLC's certificate must be there when the server starts.
                plc_certificate(&self.plc_certs());
                let hash = &self.plc_hash;
                let offered = if self.sec == Sec::Sign {
                    "Sign, SignAndEncrypt"
                } else {
                    "SignAndEncrypt"
                };
                format!(
                    "server: OpcUa(bind: \"127.0.0.1:0\", security: [{offered}], \
                     users: [(name: {PLC_USER:?}, password_hash: {hash:?}), \
                     (name: {OPERATOR:?}, password_hash: {hash:?})], anonymous: false, \
                     plc_user: {PLC_USER:?}, trusted_clients: [{:?}])",
                    path_text(&self.plc_certs().join("client_cert.der"))
                )
            }
        }
    }

    /// Writes a configuration of the station with `body` (mode, client, server,
    /// options) in the test's folder: Vigie's state in [`Self::state`], the station's
    /// I/O map with a staleness bound of 200 ms as `live.rs` uses it (for a Modbus
    /// side). With security, Vigie's certificate is made (`vigie opcua cert`) and
    /// given to the plant's trust list.
    pub(crate) fn config(&self, body: &str) -> PathBuf {
        self.config_in(&repo().join("layouts/sorting-station"), body)
    }

    /// [`Self::config`] of the plant folder `plant` (a copy of the station's).
    fn config_in(&self, plant: &Path, body: &str) -> PathBuf {
        let n = self.configs.get();
        self.configs.set(n + 1);
        let station = plant.canonicalize().unwrap();
        let map = std::fs::read_to_string(station.join("io-map.ron"))
            .unwrap()
            .replace("max_age_ms: 30,", "max_age_ms: 200,");
        assert!(
            map.contains("max_age_ms: 200,"),
            "the station's io-map.ron changed"
        );
        let map_path = self.dir.0.join("io-map.ron");
        std::fs::write(&map_path, map).unwrap();
        let text = format!(
            "Gateway(plant: {:?}, io_map: Some({:?}), state_dir: {:?}, cycle_ms: 10, \
             link_timeout_cycles: 50, auto_reset: true, {body})",
            path_text(&station),
            path_text(&map_path),
            path_text(&self.state())
        );
        let path = self.dir.0.join(format!("gateway-{n}.ron"));
        std::fs::write(&path, text).unwrap();
        if self.sec != Sec::None {
            let out = crate::vigie(&["opcua", "cert", path.to_str().unwrap()]);
            let said = String::from_utf8_lossy(&out.stdout);
            assert!(
                out.status.success(),
                "vigie opcua cert: {said}{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let cert = own_certificate(&self.state());
            assert!(
                said.contains(&format!("certificate {}", cert.display())),
                "vigie opcua cert printed {said}"
            );
            std::fs::copy(&cert, self.dir.0.join("plant-trust/vigie.der")).unwrap();
        }
        path
    }

    /// `vigie gateway --log warn CONFIG`, its stderr kept (and echoed).
    fn start(&self, config: &Path) -> Vigie {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_vigie"));
        cmd.args(["gateway", "--log", "warn"]).arg(config);
        let (peer, stderr) = spawn_keeping_stderr("vigie gateway", cmd);
        Vigie {
            gw: Gateway {
                peer,
                events: Vec::new(),
                state: self.state(),
                _dir: TempDir::new("ua-gw"),
            },
            stderr,
        }
    }

    /// [`Self::config`] then [`Self::start`].
    fn gateway(&self, body: &str) -> Vigie {
        let config = self.config(body);
        self.start(&config)
    }

    /// A gateway between the python plant at `plant` (node map `map`, if any) and the
    /// PLC; `extra` added to the configuration.
    fn gateway_to(&self, plant: &UaPlant, map: Option<&Path>, extra: &str) -> Vigie {
        let map = map.map_or(String::new(), |m| format!("node_map: {:?}", path_text(m)));
        self.gateway(&format!(
            "mode: Gateway, {}, {}, {extra}",
            self.client(&plant.endpoint(), &map),
            self.server()
        ))
    }

    /// A node map of the station in `namespace`: `node(signal)` is each entry's place
    /// (`node: "s=C0"` or `path: "Plant/C0"`), read every 10 ms and stale after 300 ms
    /// (the python plant can miss a few reads on a loaded 2-core machine; the default,
    /// three cycles, would let the stale guard step in mid-sequence, see `live.rs`).
    fn node_map(&self, name: &str, namespace: &str, node: impl Fn(&str) -> String) -> PathBuf {
        let s = station();
        let entries: Vec<String> = s
            .inputs
            .iter()
            .chain(&s.outputs)
            .map(|id| format!("        (signal: {id:?}, {}),", node(id)))
            .collect();
        let text = format!(
            "NodeMap(\n    namespace: {namespace:?},\n    poll_ms: 10,\n    max_age_ms: 300,\n    signals: [\n{}\n    ],\n)\n",
            entries.join("\n")
        );
        let folder = self.dir.0.join(name);
        std::fs::create_dir_all(&folder).unwrap();
        let path = folder.join("node-map.ron");
        std::fs::write(&path, text).unwrap();
        path
    }

    /// The station's own address space (`s=<signal>` in [`NAMESPACE`]) as a node map
    /// with the staleness bound of [`Self::node_map`].
    pub(crate) fn relaxed_map(&self) -> PathBuf {
        self.node_map("map", NAMESPACE, |id| format!("node: \"s={id}\""))
    }
}

fn path_text(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

/// `vigie opcua hash-password` of `password`.
fn hash_password(password: &str) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vigie"))
        .args(["opcua", "hash-password"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    writeln!(child.stdin.take().unwrap(), "{password}").unwrap();
    let out = child.wait_with_output().unwrap();
    let hash = String::from_utf8_lossy(&out.stdout).trim().to_string();
    assert!(
        out.status.success() && hash.starts_with("$argon2"),
        "vigie opcua hash-password: {hash} {}",
        String::from_utf8_lossy(&out.stderr)
    );
    hash
}

/// Makes the python PLC's certificate in `certs` (it makes it at start, before it
/// connects anywhere): Vigie's server reads the certificates it trusts when it starts.
fn plc_certificate(certs: &Path) {
    if certs.join("client_cert.der").is_file() {
        return;
    }
    let mut cmd = Command::new(python());
    cmd.arg(repo().join("tests/peers/opcua_plc.py")).args([
        "--endpoint",
        "opc.tcp://127.0.0.1:1/",
        "--namespace",
        NAMESPACE,
        "--security",
        "encrypt",
        "--cert-dir",
        certs.to_str().unwrap(),
    ]);
    let mut peer = Peer::spawn("plc (certificate)", cmd);
    assert_eq!(first_line(&peer), "running");
    peer.kill();
    assert!(certs.join("client_cert.der").is_file());
}

/// The first line of a python peer; a peer that exits first (asyncua missing from the
/// venv, a bad argument: its stderr says) fails the test with what to do.
fn first_line(peer: &Peer) -> String {
    match peer.lines.recv_timeout(std::time::Duration::from_secs(10)) {
        Ok(line) => line,
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => panic!(
            "{} exited before its first line (its error is above): is asyncua installed in the \
             test venv {}? `pip install -r requirements-test.txt`",
            peer.name,
            python().display()
        ),
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            panic!("{}: no first line within 10 s", peer.name)
        }
    }
}

/// A process like [`Peer::spawn`] whose stderr is kept, line by line (and echoed to
/// the test's stderr).
fn spawn_keeping_stderr(name: &str, mut cmd: Command) -> (Peer, Arc<Mutex<Vec<String>>>) {
    let mut child = cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {name}: {e}"));
    let stdin = child.stdin.take().unwrap();
    let stdout = child.stdout.take().unwrap();
    let stderr = child.stderr.take().unwrap();
    let kept = Arc::new(Mutex::new(Vec::new()));
    let log = Arc::clone(&kept);
    let tag = name.to_string();
    std::thread::Builder::new()
        .name(format!("{name}-stderr"))
        .spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                eprintln!("[{tag}] {line}");
                log.lock().unwrap().push(line);
            }
        })
        .unwrap();
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
    let peer = Peer {
        name: name.to_string(),
        child,
        stdin,
        lines,
    };
    (peer, kept)
}

/// `vigie gateway` with its events and its stderr.
struct Vigie {
    gw: Gateway,
    stderr: Arc<Mutex<Vec<String>>>,
}

impl std::ops::Deref for Vigie {
    type Target = Gateway;
    fn deref(&self) -> &Gateway {
        &self.gw
    }
}

impl std::ops::DerefMut for Vigie {
    fn deref_mut(&mut self) -> &mut Gateway {
        &mut self.gw
    }
}

impl Vigie {
    /// The endpoint URL it serves the PLC on.
    fn endpoint(&mut self) -> String {
        let e = self.event("listening", Gateway::kind("listening"));
        let endpoint = e["endpoint"].as_str().unwrap().to_string();
        let address = e["address"].as_str().unwrap();
        assert_eq!(endpoint, format!("opc.tcp://{address}/"), "{e}");
        assert!(address.starts_with("127.0.0.1:"), "{e}");
        endpoint
    }

    fn stderr(&self) -> Vec<String> {
        self.stderr.lock().unwrap().clone()
    }
}

/// A predicate of an event: `event` with `key`.
fn keyed(event: &'static str, key: &'static str) -> impl Fn(&serde_json::Value) -> bool {
    move |e| e["event"] == event && e["key"] == key
}

/// A trip or violation naming `id`.
fn naming(event: &'static str, id: &'static str) -> impl Fn(&serde_json::Value) -> bool {
    move |e| {
        e["event"] == event
            && e["record"]["constraints"]
                .as_array()
                .is_some_and(|c| c.iter().any(|c| c["id"] == id))
    }
}

/// The asyncua plant (`tests/peers/opcua_plant.py`): every signal of the station, the
/// mirror contacts wired.
pub(crate) struct UaPlant {
    peer: Peer,
    port: u16,
}

impl UaPlant {
    pub(crate) fn start(ua: &Ua, namespace: &str, port: Option<u16>) -> Self {
        let s = station();
        let mut cmd = Command::new(python());
        cmd.arg(repo().join("tests/peers/opcua_plant.py")).args([
            "--namespace",
            namespace,
            "--inputs",
            &s.inputs.join(","),
            "--outputs",
            &s.outputs.join(","),
            "--mirror",
            &s.mirrors,
        ]);
        cmd.args(ua.plant_args());
        if let Some(p) = port {
            cmd.args(["--port", &p.to_string()]);
        }
        let peer = Peer::spawn("opcua plant", cmd);
        let first = first_line(&peer);
        let port = first
            .strip_prefix("listening ")
            .and_then(|p| p.parse().ok())
            .unwrap_or_else(|| panic!("opcua plant: unexpected first line {first:?}"));
        Self { peer, port }
    }

    pub(crate) fn endpoint(&self) -> String {
        format!("opc.tcp://127.0.0.1:{}/", self.port)
    }

    /// Kills the plant process (the link loses its peer).
    pub(crate) fn kill(&mut self) {
        self.peer.kill();
    }

    /// Sets signals, all in one step of the peer.
    pub(crate) fn set(&mut self, values: &[(&str, bool)]) {
        let mut line = String::from("set");
        for &(n, v) in values {
            line.push_str(&format!(" {n} {}", u8::from(v)));
        }
        assert_eq!(self.peer.ask(&line), "ok");
    }

    /// The outputs A0..A6 KM0 YV0 as the plant holds them.
    fn outputs(&mut self) -> String {
        let line = self.peer.ask("outputs");
        line.strip_prefix("outputs ")
            .unwrap_or_else(|| panic!("opcua plant: {line}"))
            .to_string()
    }
}

/// The asyncua PLC (`tests/peers/opcua_plc.py`).
struct UaPlc(Peer);

impl UaPlc {
    /// The PLC of `ua` at `endpoint`, reading `inputs` and writing `outputs` every 5 ms.
    fn start(ua: &Ua, endpoint: &str, inputs: &[String], outputs: &[String]) -> Self {
        let certs = ua.plc_certs();
        Self::start_as(
            ua,
            endpoint,
            inputs,
            outputs,
            (&certs, PLC_USER, PLC_PASSWORD),
        )
    }

    /// The same with the certificate of `certs`, `user` and `password`.
    fn start_as(
        ua: &Ua,
        endpoint: &str,
        inputs: &[String],
        outputs: &[String],
        (certs, user, password): (&Path, &str, &str),
    ) -> Self {
        let mut cmd = Command::new(python());
        cmd.arg(repo().join("tests/peers/opcua_plc.py")).args([
            "--endpoint",
            endpoint,
            "--namespace",
            NAMESPACE,
            "--inputs",
            &inputs.join(","),
            "--outputs",
            &outputs.join(","),
            "--period-ms",
            "5",
        ]);
        cmd.args(ua.plc_args(certs, user, password));
        let peer = Peer::spawn("opcua plc", cmd);
        assert_eq!(first_line(&peer), "running");
        Self(peer)
    }

    /// What the scan writes from now on.
    fn command(&mut self, outputs: &str) {
        assert_eq!(self.0.ask(&format!("outputs {outputs}")), "ok");
    }

    /// The inputs last read.
    fn sensors(&mut self) -> String {
        let line = self.0.ask("inputs");
        line.strip_prefix("inputs ")
            .unwrap_or_else(|| panic!("opcua plc: {line}"))
            .to_string()
    }

    /// Scans, errors, last error.
    fn status(&mut self) -> (u64, u64, String) {
        let line = self.0.ask("status");
        let w: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(w.len(), 4, "opcua plc: {line}");
        (
            w[1].parse().unwrap(),
            w[2].parse().unwrap(),
            w[3].to_string(),
        )
    }

    /// One write outside the scan: `ok` or `error STATUS`.
    fn write(&mut self, name: &str, value: bool) -> String {
        self.0.ask(&format!("write {name} {}", u8::from(value)))
    }

    /// One read outside the scan: `value 0|1` or `error STATUS`.
    fn read(&mut self, name: &str) -> String {
        self.0.ask(&format!("read {name}"))
    }

    /// Waits for its first session to be refused: no scan, errors, the last one
    /// returned.
    #[track_caller]
    fn refused(&mut self, what: &str) -> String {
        let mut last = String::new();
        wait_until(what, || {
            let (scans, errors, l) = self.status();
            assert_eq!(scans, 0, "{what}: the PLC got a session ({l})");
            last = l;
            errors >= 2
        });
        last
    }
}

/// Tests that move the turntable from C4 to C5 in a few milliseconds run without the
/// diagnosers and the plausibility stage (see `live.rs`).
const NO_DIAGNOSERS: &str = "diagnosers: false, plausibility: false";

// 1. Round trip: plant → Vigie → PLC, PLC → Vigie → plant, through the station's own
// address space (no node map: the plant serves `s=<signal>` in urn:vigie:sorting-station).
both!(gateway_round_trip);

fn gateway_round_trip(sec: Sec) {
    let ua = Ua::new(sec, "ua-round-trip");
    let s = station();
    let mut plant = UaPlant::start(&ua, NAMESPACE, None);
    let mut gw = ua.gateway_to(&plant, None, "");
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    // Sensors: plant → Vigie → PLC.
    plant.set(&[("C0", true), ("C7", true), ("C10", true)]);
    wait_until("the PLC to read C0, C7 and C10", || {
        plc.sensors() == "10000001001"
    });
    plant.set(&[("C0", false), ("C7", false), ("C10", false)]);
    wait_until("the PLC to read all sensors 0", || {
        plc.sensors() == "00000000000"
    });
    // Outputs: PLC → Vigie (allowed by the filter) → plant; the safety devices KM0 and
    // YV0 held on by Vigie.
    plc.command("1100011");
    wait_until("the plant to receive A0 A1 A5 A6", || {
        plant.outputs() == "110001111"
    });
    plc.command("0000000");
    wait_until("the plant to receive A0..A6 at 0", || {
        plant.outputs() == "000000011"
    });
    let ack = gw.event("an acknowledged plant write", |e| {
        e["event"] == "plant_write" && e["acknowledged"] == true
    });
    assert!(ack["error"].is_null(), "{ack}");
    let (scans, errors, last) = plc.status();
    assert!(
        scans > 0 && errors == 0,
        "PLC scans {scans}, errors {errors} ({last})"
    );
    let stopped = gw.stop();
    assert_eq!(stopped["written"], true, "{stopped}");
}

/// The round trip with Basic256Sha256 Sign, Vigie's server offering Sign and
/// SignAndEncrypt.
#[test]
fn gateway_round_trip_signed() {
    gateway_round_trip(Sec::Sign);
}

// 2. The hold of A4 (CSs10 = C7 . /A4): the turntable stays rotated while a box is at C7.
both!(gateway_enforces_the_hold_of_a4);

fn gateway_enforces_the_hold_of_a4(sec: Sec) {
    let ua = Ua::new(sec, "ua-hold");
    let s = station();
    let mut plant = UaPlant::start(&ua, NAMESPACE, None);
    let map = ua.relaxed_map();
    let mut gw = ua.gateway_to(&plant, Some(&map), NO_DIAGNOSERS);
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    // A loaded table in the loading position starts rotating.
    plant.set(&[("C4", true), ("C6", true)]);
    wait_until("the PLC to see C4 C6", || plc.sensors() == "00001010000");
    plc.command("0000100");
    wait_until("the plant to rotate", || plant.outputs() == "000010011");
    // It reaches the unloading position; the box leaves the table (C6, then C7 on the
    // right exit), and the PLC releases A4 too early.
    plant.set(&[("C4", false), ("C5", true)]);
    wait_until("the PLC to see C5 C6", || plc.sensors() == "00000110000");
    plant.set(&[("C6", false)]);
    wait_until("the PLC to see C5", || plc.sensors() == "00000100000");
    plant.set(&[("C7", true)]);
    wait_until("the PLC to see C5 C7", || plc.sensors() == "00000101000");
    plc.command("0000000");
    let trip = gw.event("trip on CSs10", naming("trip", "CSs10"));
    assert_eq!(trip["record"]["enforced"], true, "{trip}");
    // The plant keeps A4 ON for as long as C7 is there.
    for _ in 0..20 {
        assert_eq!(plant.outputs(), "000010011", "A4 must stay ON while C7 = 1");
    }
    // The box has left: the PLC's release is allowed again, the trip resets.
    plant.set(&[("C7", false)]);
    wait_until("the plant to release A4", || plant.outputs() == "000000011");
    gw.event("reset", Gateway::kind("reset"));
    gw.stop();
}

// 3. The plant dies and comes back on the same port.
both!(plant_killed_raises_the_alarm_and_reconnects);

fn plant_killed_raises_the_alarm_and_reconnects(sec: Sec) {
    let ua = Ua::new(sec, "ua-plant-killed");
    let s = station();
    let mut plant = UaPlant::start(&ua, NAMESPACE, None);
    let port = plant.port;
    let map = ua.relaxed_map();
    let mut gw = ua.gateway_to(&plant, Some(&map), "");
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    plc.command("1100000");
    wait_until("the plant to receive A0 A1", || {
        plant.outputs() == "110000011"
    });
    // Vigie has read the mirror contacts since (the PLC reads what Vigie read): killed
    // sooner, the plant would leave Vigie with contacts read before the command, which
    // the contactor monitoring rightly takes for dead contactors (CSk2, CSk4).
    wait_until("Vigie to read A0_fb and A1_fb", || {
        plc.read("A0_fb") == "value 1" && plc.read("A1_fb") == "value 1"
    });
    gw.forget();
    plant.peer.kill();
    let alarm = gw.event("plant lost alarm", keyed("alarm", "link:plant"));
    let safe = gw.event("safe outputs", Gateway::kind("safe_outputs"));
    assert!(safe["reason"].as_str().unwrap().contains("stale"), "{safe}");
    assert!(
        safe["time_ms"].as_u64().unwrap() <= alarm["time_ms"].as_u64().unwrap(),
        "safe outputs {safe} after the alarm {alarm}"
    );
    // The fallback the plant is to get once it is declared lost (the one written first
    // after the reconnection): stale inputs may have had a fallback of their own before.
    let lost = gw.event("the safe outputs of the plant lost", |e| {
        e["event"] == "safe_outputs" && e["reason"].as_str().is_some_and(|r| r.contains("lost"))
    });
    let fallback = lost["outputs"].as_str().unwrap().to_string();
    assert_ne!(fallback, "110000011", "{lost}");
    // The plant returns on the same port (a fresh process, every output 0).
    gw.forget();
    let mut plant = UaPlant::start(&ua, NAMESPACE, Some(port));
    gw.event("plant alarm cleared", keyed("alarm_cleared", "link:plant"));
    gw.event(
        "safe outputs released",
        Gateway::kind("safe_outputs_released"),
    );
    wait_until("the plant to receive A0 A1 again", || {
        plant.outputs() == "110000011"
    });
    // The first write the new plant acknowledged: the outputs current at the
    // reconnection, the safe fallback (not the PLC's commands of before the loss).
    let first = gw
        .events
        .iter()
        .find(|e| e["event"] == "plant_write" && e["acknowledged"] == true)
        .cloned()
        .unwrap_or_else(|| panic!("no acknowledged plant_write: {:#?}", gw.events));
    assert_eq!(first["outputs"], fallback.as_str(), "{:#?}", gw.events);
    gw.stop();
}

// 4. The PLC dies: the plant gets the safe fallback; a PLC comes back.
both!(plc_killed_gives_safe_outputs_then_recovers);

fn plc_killed_gives_safe_outputs_then_recovers(sec: Sec) {
    let ua = Ua::new(sec, "ua-plc-killed");
    let s = station();
    let mut plant = UaPlant::start(&ua, NAMESPACE, None);
    let map = ua.relaxed_map();
    let mut gw = ua.gateway_to(&plant, Some(&map), NO_DIAGNOSERS);
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    // A loaded table rotates to the unloading position (hold A4 there), the
    // intermediate conveyor on.
    plant.set(&[("C4", true), ("C6", true)]);
    wait_until("the PLC to see C4 C6", || plc.sensors() == "00001010000");
    plc.command("0100100");
    wait_until("the plant to receive A1 A4", || {
        plant.outputs() == "010010011"
    });
    plant.set(&[("C4", false), ("C5", true)]);
    wait_until("the PLC to see C5 C6", || plc.sensors() == "00000110000");
    gw.forget();
    plc.0.kill();
    let alarm = gw.event("PLC lost alarm", keyed("alarm", "link:plc"));
    let safe = gw.event("safe outputs", Gateway::kind("safe_outputs"));
    // Every output at its safe value but what a constraint forces: A4 held, KM0 and
    // YV0 (safe ON) left closed.
    assert_eq!(safe["outputs"], "000010011", "{safe}");
    assert!(safe["time_ms"].as_u64() >= alarm["time_ms"].as_u64());
    wait_until("the plant to hold the fallback", || {
        plant.outputs() == "000010011"
    });
    // A PLC comes back.
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    plc.command("0100100");
    gw.event("PLC alarm cleared", keyed("alarm_cleared", "link:plc"));
    wait_until("the plant to follow the PLC again", || {
        plant.outputs() == "010010011"
    });
    // Shutdown with the PLC still commanding A1: the plant gets the safe state.
    let stopped = gw.stop();
    assert_eq!(stopped["outputs"], "000010011", "{stopped}");
    assert_eq!(stopped["written"], true, "{stopped}");
    assert_eq!(plant.outputs(), "000010011");
}

// 5. Monitor mode against the python plant standing for a PLC that exposes its
// sensors and its commanded outputs.
both!(monitor_reports_with_explanations_and_never_writes);

fn monitor_reports_with_explanations_and_never_writes(sec: Sec) {
    let ua = Ua::new(sec, "ua-monitor");
    let mut plant = UaPlant::start(&ua, NAMESPACE, None);
    let port = plant.port;
    // The PLC lets A4 go while C7 = 1, before the monitor's first read (see `live.rs`).
    plant.set(&[("C5", true), ("C7", true), ("A4", false)]);
    let map = ua.relaxed_map();
    let map = format!("node_map: {:?}", path_text(&map));
    let mut gw = ua.gateway(&format!(
        "mode: Monitor, {}",
        ua.client(&plant.endpoint(), &map)
    ));
    gw.event("monitoring", Gateway::kind("monitoring"));
    let v = gw.event("violation of CSs10", naming("violation", "CSs10"));
    assert_eq!(v["record"]["enforced"], false, "{v}");
    assert!(v["explanation"].is_object(), "{v}");
    let projection = &v["explanation"]["projection"]["items"];
    assert!(
        projection.as_array().is_some_and(|items| !items.is_empty()),
        "{projection}"
    );
    // Nothing was written: A4 is still OFF at the peer.
    for _ in 0..10 {
        assert_eq!(plant.outputs(), "000000000");
    }
    assert!(
        !gw.events.iter().any(|e| e["event"] == "plant_write"),
        "{:#?}",
        gw.events
    );
    // The peer dies: link alarm, and it comes back.
    gw.forget();
    plant.peer.kill();
    gw.event("link alarm", keyed("alarm", "link:peer"));
    let mut plant = UaPlant::start(&ua, NAMESPACE, Some(port));
    gw.event("link alarm cleared", keyed("alarm_cleared", "link:peer"));
    let stopped = gw.stop();
    assert_eq!(stopped["connected"], true, "{stopped}");
    assert_eq!(plant.outputs(), "000000000");
    assert!(
        !gw.events.iter().any(|e| e["event"] == "plant_write"),
        "{:#?}",
        gw.events
    );
}

// 6. The emulator served over OPC UA to the python PLC.
both!(emulator_served_to_an_opcua_plc);

fn emulator_served_to_an_opcua_plc(sec: Sec) {
    let ua = Ua::new(sec, "ua-emulator");
    let s = station();
    let config = ua.config(&format!("mode: Emulator, seed: 1, {}", ua.server()));
    let mut gw = ua.start(&config);
    let endpoint = gw.endpoint();
    if sec == Sec::Encrypt {
        // A wrong password: no session, so nothing written.
        let certs = ua.plc_certs();
        let who = (certs.as_path(), PLC_USER, "wrong");
        let mut wrong = UaPlc::start_as(&ua, &endpoint, &s.sensors, &s.outputs, who);
        wrong.command("111111111");
        let last = wrong.refused("the wrong password to be refused");
        eprintln!("the wrong password: {last}");
        assert!(
            ["BadUserAccessDenied", "BadIdentityTokenRejected"].contains(&last.as_str()),
            "the PLC with a wrong password failed with {last}"
        );
    }
    // A PLC that only reads: the table starts at C4, no output was written.
    let mut reader = UaPlc::start(&ua, &endpoint, &s.sensors, &[]);
    wait_until("the PLC to read C4", || reader.sensors() == "00001000000");
    for out in &s.outputs {
        assert_eq!(reader.read(out), "value 0", "{out} was written");
    }
    // The inputs are read-only, even for the PLC's identity.
    let refused = reader.write("C0", true);
    assert_eq!(refused, "error BadUserAccessDenied", "write C0 1");
    assert_eq!(reader.read("C0"), "value 0");
    // The PLC closes the safety contactor KM0 and runs the entry conveyor A0: the
    // emulated plant moves, a box reaches C0.
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.outputs);
    plc.command("100000010");
    wait_until("the PLC's A0 and KM0 to be served", || {
        reader.read("A0") == "value 1" && reader.read("KM0") == "value 1"
    });
    wait_until("the emulator to raise C0", || {
        plc.sensors().starts_with('1')
    });
    let (scans, errors, last) = plc.status();
    assert!(
        scans > 0 && errors == 0,
        "PLC scans {scans}, errors {errors} ({last})"
    );
    if sec == Sec::Encrypt {
        // Another user reads, but the outputs are the PLC's alone.
        let certs = ua.plc_certs();
        let who = (certs.as_path(), OPERATOR, PLC_PASSWORD);
        let mut operator = UaPlc::start_as(&ua, &endpoint, &s.sensors, &[], who);
        wait_until("the operator to read C4", || {
            operator.sensors().as_bytes()[4] == b'1'
        });
        assert_eq!(operator.write("A0", false), "error BadUserAccessDenied");
        assert_eq!(operator.read("A0"), "value 1");
    }
    gw.stop();
    if sec == Sec::Encrypt {
        drop((reader, plc));
        untrusted_client_then_trusted(&ua, &config);
    }
}

/// A client whose certificate is not in `trusted_clients` is refused (its certificate
/// kept in `pki/rejected`); trusted with `vigie opcua trust`, it is accepted once the
/// server restarts.
fn untrusted_client_then_trusted(ua: &Ua, config: &Path) {
    let s = station();
    let stranger = ua.dir.0.join("stranger");
    let mut gw = ua.start(config);
    let endpoint = gw.endpoint();
    let who = (stranger.as_path(), PLC_USER, PLC_PASSWORD);
    let mut plc = UaPlc::start_as(ua, &endpoint, &s.sensors, &[], who);
    let last = plc.refused("the untrusted certificate to be refused");
    eprintln!("the untrusted certificate: {last}");
    assert!(
        last.contains("Certificate") || last.contains("Security"),
        "the untrusted PLC failed with {last}"
    );
    let rejected = ua.state().join("pki/rejected");
    assert!(
        std::fs::read_dir(&rejected).is_ok_and(|mut d| d.next().is_some()),
        "the refused certificate is not kept in {}",
        rejected.display()
    );
    drop(plc);
    gw.stop();
    let cert = stranger.join("client_cert.der");
    let out = crate::vigie(&[
        "opcua",
        "trust",
        config.to_str().unwrap(),
        cert.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "vigie opcua trust: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let mut gw = ua.start(config);
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start_as(ua, &endpoint, &s.sensors, &[], who);
    wait_until("the trusted PLC to read C4", || {
        plc.sensors() == "00001000000"
    });
    let (scans, errors, last) = plc.status();
    assert!(
        scans > 0 && errors == 0,
        "PLC scans {scans}, errors {errors} ({last})"
    );
    gw.stop();
}

// 7. Mixed: OPC UA to the PLC, Modbus TCP to the pymodbus plant.
both!(mixed_gateway_opcua_plc_modbus_plant);

fn mixed_gateway_opcua_plc_modbus_plant(sec: Sec) {
    let ua = Ua::new(sec, "ua-mixed");
    let s = station();
    let mut plant = ModbusPlant::start(None);
    let mut gw = ua.gateway(&format!(
        "mode: Gateway, client: Modbus(address: \"127.0.0.1:{}\", timeout_ms: 200, \
         backoff_initial_ms: 20, backoff_max_ms: 200), {}",
        plant.port,
        ua.server()
    ));
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    plant.set_inputs(&[(0, true), (7, true), (10, true)]);
    wait_until("the PLC to read C0, C7 and C10", || {
        plc.sensors() == "10000001001"
    });
    plant.set_inputs(&[(0, false), (7, false), (10, false)]);
    wait_until("the PLC to read all sensors 0", || {
        plc.sensors() == "00000000000"
    });
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
    assert_eq!(stopped["written"], true, "{stopped}");
}

/// The line and column (1-based) of the first `needle` in `text`.
fn line_col(text: &str, needle: &str) -> (usize, usize) {
    let at = text.find(needle).unwrap();
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let col = at - before.rfind('\n').map_or(0, |n| n + 1) + 1;
    (line, col)
}

// 8. A node map that does not fit the plant's server: V1603 at every connection
// attempt with its place in the map, the plant never connected, the safe outputs; a
// map that fits (browse paths in the plant's own namespace) works.
#[test]
fn node_map_with_a_typo_is_reported_and_a_right_one_works() {
    let ua = Ua::new(Sec::None, "ua-node-map");
    let s = station();
    let namespace = "urn:test:sorting";
    let mut plant = UaPlant::start(&ua, namespace, None);
    // C7 mistyped C7x.
    let typo = ua.node_map("typo", namespace, |id| {
        let node = if id == "C7" { "C7x" } else { id };
        format!("node: \"s={node}\"")
    });
    let text = std::fs::read_to_string(&typo).unwrap();
    let (line, col) = line_col(&text, "\"C7\"");
    let mut gw = ua.gateway_to(&plant, Some(&typo), "");
    let endpoint = gw.endpoint();
    let place = format!("node-map.ron:{line}:{col}");
    wait_until("the V1603 line on stderr", || {
        gw.stderr().iter().any(|l| l.contains("error[V1603]"))
    });
    let stderr = gw.stderr();
    let v1603: Vec<&String> = stderr.iter().filter(|l| l.contains("V1603")).collect();
    assert!(
        v1603
            .iter()
            .any(|l| l.contains(&place) && l.contains(&plant.endpoint()) && l.contains("C7x")),
        "no V1603 line with {place}, {} and C7x: {stderr:#?}",
        plant.endpoint()
    );
    assert!(
        v1603.iter().all(|l| l.contains("`C7`")),
        "only C7 does not fit: {stderr:#?}"
    );
    gw.event("plant alarm", keyed("alarm", "link:plant"));
    let safe = gw.event("safe outputs", Gateway::kind("safe_outputs"));
    assert!(safe["outputs"].is_string(), "{safe}");
    // The plant's server was never written.
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    plc.command("1000000");
    wait_until("a PLC scan", || plc.status().0 > 0);
    assert_eq!(plant.outputs(), "000000000");
    assert!(
        !gw.events
            .iter()
            .any(|e| e["event"] == "plant_write" && e["acknowledged"] == true),
        "{:#?}",
        gw.events
    );
    gw.stop();
    drop(plc);
    // The right map: browse paths from the Objects folder, `Plant/<signal>`.
    let paths = ua.node_map("paths", namespace, |id| format!("path: \"Plant/{id}\""));
    let mut gw = ua.gateway_to(&plant, Some(&paths), "");
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    plant.set(&[("C7", true)]);
    wait_until("the PLC to read C7", || plc.sensors() == "00000001000");
    plc.command("1000000");
    wait_until("the plant to receive A0", || plant.outputs() == "100000011");
    assert!(
        !gw.stderr().iter().any(|l| l.contains("V1603")),
        "{:#?}",
        gw.stderr()
    );
    gw.stop();
}

/// A `node-map.ron` in the plant folder is the client's map when the configuration
/// names none: the station copied (folder `sorting-station`, so that Vigie's server
/// keeps its namespace) with a map of browse paths in the plant's own namespace.
#[test]
fn node_map_in_the_plant_folder_is_taken() {
    let ua = Ua::new(Sec::None, "ua-node-map-folder");
    let s = station();
    let namespace = "urn:test:sorting";
    let mut plant = UaPlant::start(&ua, namespace, None);
    let paths = ua.node_map("paths", namespace, |id| format!("path: \"Plant/{id}\""));
    let folder = ua.dir.0.join("copy/sorting-station");
    crate::paper::copy_dir(&repo().join("layouts/sorting-station"), &folder);
    std::fs::copy(&paths, folder.join("node-map.ron")).unwrap();
    let config = ua.config_in(
        &folder,
        &format!(
            "mode: Gateway, {}, {}",
            ua.client(&plant.endpoint(), ""),
            ua.server()
        ),
    );
    let mut gw = ua.start(&config);
    let endpoint = gw.endpoint();
    let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
    plant.set(&[("C7", true)]);
    wait_until("the PLC to read C7", || plc.sensors() == "00000001000");
    plc.command("0100000");
    wait_until("the plant to receive A1", || plant.outputs() == "010000011");
    gw.stop();
}

/// An "OPC UA plant" that is not one: every connection gets `answer` (garbage bytes,
/// or nothing at all) and stays open. The listener's thread ends with the test.
fn fake_plant(answer: &'static [u8]) -> u16 {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::Builder::new()
        .name("fake-opcua-plant".into())
        .spawn(move || {
            let mut held = Vec::new();
            for stream in listener.incoming().take(64) {
                let Ok(mut stream) = stream else { continue };
                let _ = std::io::Write::write_all(&mut stream, answer);
                held.push(stream);
            }
        })
        .unwrap();
    port
}

// 9. A plant that answers garbage, or accepts and never answers: the link is lost (the
// alarm, the safe outputs held for the PLC), the gateway keeps serving the PLC and
// stops cleanly; nothing hangs.
#[test]
fn a_plant_that_answers_garbage_or_nothing_is_lost_and_the_plc_still_served() {
    for (what, answer) in [
        (
            "garbage",
            &b"HELF\xff\xff\xff\x7f garbage that is no OPC UA message"[..],
        ),
        ("silence", &b""[..]),
    ] {
        let ua = Ua::new(Sec::None, "ua-fake-plant");
        let s = station();
        let port = fake_plant(answer);
        let mut gw = ua.gateway(&format!(
            "mode: Gateway, {}, {}",
            ua.client(&format!("opc.tcp://127.0.0.1:{port}/"), ""),
            ua.server()
        ));
        gw.event(&format!("{what}: link:plant"), keyed("alarm", "link:plant"));
        gw.event(
            &format!("{what}: safe outputs"),
            Gateway::kind("safe_outputs"),
        );
        // The PLC's side is served all the same: it reads (stale, held) sensors.
        let endpoint = gw.endpoint();
        let mut plc = UaPlc::start(&ua, &endpoint, &s.sensors, &s.commands);
        wait_until(&format!("{what}: the PLC served"), || plc.status().0 > 5);
        let stopped = gw.stop();
        assert_eq!(stopped["written"], false, "{what}: {stopped}");
        assert!(
            !gw.events
                .iter()
                .any(|e| e["event"] == "plant_write" && e["acknowledged"] == true),
            "{what}: nothing acknowledged a write: {:#?}",
            gw.events
        );
    }
}
