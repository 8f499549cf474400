//! `vigie gateway-bench`: the gateway against a pymodbus plant on loopback.
//!
//! Measures the sustained cycle rate and period jitter of the gateway loop, and the
//! latency from a sensor change at the plant to the filtered output at the plant: with
//! the PLC commanding the intermediate conveyor (A1), C3 rises at the plant
//! (CSs2 = C3 . /C4 . A1), the filter trips and the plant's A1 falls; C3 falls, the
//! trip resets (auto reset) and A1 returns. Both edges are timed from the moment the
//! plant peer is asked to change C3 until a probe client reads the new coil.
//!
//! With `load`, that many busy processes (`sh -c 'while :; do :; done'`) run beside
//! it for the whole run, a fixed background load; every link alarm raised once the
//! PLC's first command has reached the plant is false (nothing is lost in the bench)
//! and is counted. With `seconds`, edges are timed until that much time has passed.

use super::runtime::{self, CycleStats, Setup};
use anyhow::Context as _;
use std::io::{BufRead as _, BufReader, Write as _};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tokio_modbus::client::{Reader as _, Writer as _};
use vigie_core::live::config::GatewayConfig;

/// Figures of one run.
#[derive(Debug, serde::Serialize)]
pub struct Figures {
    /// Cycles run.
    pub cycles: usize,
    /// Cycles per second over the run.
    pub rate_hz: f64,
    /// Period jitter |period − cycle| percentiles in ms: p50, p99, max.
    pub jitter_ms: [f64; 3],
    /// Work per cycle (poll, engine, write) percentiles in ms: p50, p99, max.
    pub busy_ms: [f64; 3],
    /// Sensor change → filtered output at the plant, percentiles in ms: p50, p99, max.
    pub latency_ms: [f64; 3],
    /// Edges timed.
    pub edges: usize,
    /// Busy background processes.
    pub load: usize,
    /// Seconds measured.
    pub seconds: f64,
    /// Link alarms (`link:plant`, `link:plc`) raised while measuring: all false,
    /// nothing is lost in the bench.
    pub false_alarms: Vec<String>,
    /// Safe outputs applied because inputs were older than their bound (a late plant,
    /// not a lost one: the data-age guard, not a link alarm).
    pub stale_holds: usize,
    /// The cycle thread's real-time priority, when one was asked for.
    pub rt_priority: Option<u8>,
    /// The peers' priority.
    pub peers: String,
}

/// What a run does.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Edges to time (at least).
    pub edges: usize,
    /// Run at least this long.
    pub seconds: u64,
    /// Real-time priority of the cycle thread; `None`: normal priority.
    pub rt_priority: Option<u8>,
    /// Busy background processes.
    pub load: usize,
    /// Run the peers (the pymodbus plant, the PLC and the probe) at real-time priority
    /// 40 when the process may: they stand for devices of their own that the
    /// background load must not starve, so that what is measured is the gateway (the
    /// probe then sleeps 0.5 ms between its reads instead of polling in a busy loop).
    pub rt_peers: bool,
}

/// Gives every thread of process `pid` real-time priority 40 through `chrt`
/// (util-linux); returns why not when refused.
fn raise_peer_priority(pid: u32) -> Option<String> {
    match Command::new("chrt")
        .args(["-a", "-f", "-p", "40", &pid.to_string()])
        .output()
    {
        Ok(o) if o.status.success() => None,
        Ok(o) => Some(String::from_utf8_lossy(&o.stderr).trim().to_string()),
        Err(e) => Some(format!("chrt: {e}")),
    }
}

/// Busy processes, killed when dropped.
struct Load(Vec<std::process::Child>);

impl Load {
    fn start(n: usize) -> anyhow::Result<Self> {
        let mut v = Vec::with_capacity(n);
        for _ in 0..n {
            v.push(
                Command::new("sh")
                    .args(["-c", "while :; do :; done"])
                    .stdin(Stdio::null())
                    .spawn()
                    .context("cannot start a background load process")?,
            );
        }
        Ok(Self(v))
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn percentiles(mut v: Vec<f64>) -> [f64; 3] {
    if v.is_empty() {
        return [f64::NAN; 3];
    }
    v.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let i = ((v.len() - 1) as f64 * q).round() as usize;
        v.get(i).copied().unwrap_or(f64::NAN)
    };
    [at(0.5), at(0.99), at(1.0)]
}

fn repo_root() -> PathBuf {
    let here = PathBuf::from(".");
    if here.join("tests/peers/plant.py").is_file() {
        return here;
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Runs the benchmark: `edges` timed sensor edges, then the cycle figures.
pub fn run(plant_dir: &std::path::Path, opts: Options) -> anyhow::Result<Figures> {
    let Options {
        edges,
        seconds,
        rt_priority: cycle_priority,
        load,
        rt_peers,
    } = opts;
    let _load = Load::start(load)?;
    let (mut plant, mut plant_in, plant_addr, peers) = start_plant(rt_peers)?;

    let (setup, state) = gateway_setup(plant_dir, plant_addr, cycle_priority)?;
    let measuring = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let alarms = std::sync::Arc::new(std::sync::Mutex::new(Vec::<String>::new()));
    let stale = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let (m, a, s) = (
        std::sync::Arc::clone(&measuring),
        std::sync::Arc::clone(&alarms),
        std::sync::Arc::clone(&stale),
    );

    // The gateway on its own thread and runtime.
    let (addr_tx, addr_rx) = std::sync::mpsc::channel::<SocketAddr>();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let gateway = spawn_gateway(setup, (m, a, s), addr_tx, stop_rx)?;
    let server = addr_rx
        .recv_timeout(Duration::from_secs(10))
        .context("the gateway did not start")?;

    // The PLC (A1 ON, every 5 ms) and the probe on a second runtime (this thread).
    if rt_peers {
        let p = super::cycle::Priority {
            value: 40,
            explicit: true,
        };
        super::cycle::raise_priority(p, "bench PLC and probe");
    }
    let probe_pause = if rt_peers {
        Duration::from_micros(500)
    } else {
        Duration::ZERO
    };
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let result = rt.block_on(measure(
        server,
        plant_addr,
        &mut plant_in,
        &measuring,
        (edges, seconds),
        probe_pause,
    ));
    let _ = stop_tx.send(());
    let stats = gateway
        .join()
        .map_err(|_| anyhow::anyhow!("gateway thread panicked"))??;
    let _ = writeln!(plant_in, "quit");
    let _ = plant.kill();
    let _ = plant.wait();
    let (latencies, measured) = result?;
    let _ = std::fs::remove_dir_all(&state);
    let false_alarms = std::mem::take(
        &mut *alarms
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner),
    );

    let periods: Vec<f64> = stats
        .starts
        .windows(2)
        .map(|w| (w[1] - w[0]).as_secs_f64() * 1e3)
        .collect();
    let total = stats
        .starts
        .last()
        .zip(stats.starts.first())
        .map_or(0.0, |(l, f)| (*l - *f).as_secs_f64());
    Ok(Figures {
        cycles: stats.starts.len(),
        rate_hz: if total > 0.0 {
            (stats.starts.len() - 1) as f64 / total
        } else {
            0.0
        },
        jitter_ms: percentiles(periods.iter().map(|p| (p - 10.0).abs()).collect()),
        busy_ms: percentiles(stats.busy.iter().map(|d| d.as_secs_f64() * 1e3).collect()),
        latency_ms: percentiles(latencies.clone()),
        edges: latencies.len(),
        load,
        seconds: measured,
        false_alarms,
        stale_holds: stale.load(std::sync::atomic::Ordering::Relaxed),
        rt_priority: cycle_priority,
        peers,
    })
}

/// Starts the pymodbus plant of the venv (its peers at real-time priority if asked)
/// and drains its answers; returns it, its stdin, its address and the peers' priority.
fn start_plant(
    rt_peers: bool,
) -> anyhow::Result<(
    std::process::Child,
    std::process::ChildStdin,
    SocketAddr,
    String,
)> {
    let root = repo_root();
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| root.join(".venv"), PathBuf::from);
    let python = venv.join("bin/python");
    anyhow::ensure!(
        python.is_file(),
        "{} not found: create the venv with `scripts/test.sh` (or python3 -m venv .venv && .venv/bin/pip install -r requirements-test.txt)",
        python.display()
    );
    let mut plant = Command::new(&python)
        .arg(root.join("tests/peers/plant.py"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .context("cannot start the pymodbus plant")?;
    let peers = if rt_peers {
        raise_peer_priority(plant.id()).map_or_else(
            || "real-time 40".to_string(),
            |why| format!("normal (real-time refused: {why})"),
        )
    } else {
        "normal".to_string()
    };
    let plant_in = plant.stdin.take().context("plant stdin")?;
    let mut plant_out = BufReader::new(plant.stdout.take().context("plant stdout")?);
    let mut line = String::new();
    plant_out.read_line(&mut line)?;
    let port: u16 = line
        .trim()
        .strip_prefix("listening ")
        .and_then(|p| p.parse().ok())
        .with_context(|| format!("unexpected plant output {line:?}"))?;
    let plant_addr: SocketAddr = ([127, 0, 0, 1], port).into();
    // The plant answers every command with a line: drain them, or its stdout fills
    // after some 20,000 edges and the plant stops answering Modbus too.
    std::thread::Builder::new()
        .name("bench-plant-stdout".into())
        .spawn(move || {
            let mut sink = String::new();
            while plant_out.read_line(&mut sink).is_ok_and(|n| n > 0) {
                sink.clear();
            }
        })?;
    Ok((plant, plant_in, plant_addr, peers))
}

/// The gateway's setup for the bench (plant, its diagnosers, 10 ms cycle, a fresh
/// state folder, returned too).
fn gateway_setup(
    plant_dir: &std::path::Path,
    plant_addr: SocketAddr,
    cycle_priority: Option<u8>,
) -> anyhow::Result<(Setup, PathBuf)> {
    let state = std::env::temp_dir().join(format!("vigie-gateway-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&state);
    let text = format!(
        "Gateway(mode: Gateway, plant: {:?}, cycle_ms: 10, auto_reset: true, \
         client: Modbus(address: \"{plant_addr}\"), server: Modbus(bind: \"127.0.0.1:0\", plc: \"127.0.0.1\"), \
         cycle_priority: {}, realtime: {}, state_dir: {:?})",
        plant_dir.display().to_string(),
        cycle_priority.map_or_else(|| "None".to_string(), |p| format!("Some({p})")),
        cycle_priority.is_some(),
        state.display().to_string(),
    );
    let config = GatewayConfig::from_ron(&text, std::path::Path::new("bench.ron"))
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    // The gateway as configured by default: with the plant's diagnosers.
    let (bundle, diagnosers) = runtime::load_plant(&config)?;
    let (client_map, server_map) = runtime::load_maps(&config, &bundle.plant)?;
    let setup = Setup {
        config,
        bundle,
        client_map,
        server_map,
        diagnosers,
        state_dir: state.clone(),
        history: None,
        program: None,
    };
    Ok((setup, state))
}

/// Runs the gateway on its own thread and runtime: its address is sent on `addr_tx`,
/// link alarms while measuring go to `alarms`, stale-input holds are counted.
fn spawn_gateway(
    setup: Setup,
    (m, a, s): (
        std::sync::Arc<std::sync::atomic::AtomicBool>,
        std::sync::Arc<std::sync::Mutex<Vec<String>>>,
        std::sync::Arc<std::sync::atomic::AtomicUsize>,
    ),
    addr_tx: std::sync::mpsc::Sender<SocketAddr>,
    stop_rx: tokio::sync::oneshot::Receiver<()>,
) -> std::io::Result<std::thread::JoinHandle<anyhow::Result<CycleStats>>> {
    std::thread::Builder::new()
        .name("gateway".into())
        .spawn(move || {
            let mut stats = CycleStats::default();
            let mut emit = move |e: serde_json::Value| {
                if e["event"] == "listening"
                    && let Some(addr) = e["address"].as_str().and_then(|a| a.parse().ok())
                {
                    let _ = addr_tx.send(addr);
                }
                let key = e["key"].as_str().unwrap_or_default();
                if e["event"] == "alarm" && m.load(std::sync::atomic::Ordering::Acquire) {
                    let text = format!("{key} at {} ms: {}", e["time_ms"], e["message"]);
                    if key.starts_with("link:") {
                        a.lock()
                            .unwrap_or_else(std::sync::PoisonError::into_inner)
                            .push(text);
                    } else if key == "safe:outputs"
                        && e["message"]
                            .as_str()
                            .is_some_and(|t| t.starts_with("stale inputs"))
                    {
                        s.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    }
                }
            };
            let rt = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()?;
            rt.block_on(runtime::run(
                setup,
                async {
                    let _ = stop_rx.await;
                },
                &mut emit,
                &mut stats,
                None,
            ))?;
            anyhow::Ok(stats)
        })
}

/// Drives A1 on through the PLC, then times `edges` sensor edges (and at least
/// `seconds`) from the plant to the filtered output; returns the latencies (ms) and
/// the time measured (s).
async fn measure(
    server: SocketAddr,
    plant_addr: SocketAddr,
    plant_in: &mut std::process::ChildStdin,
    measuring: &std::sync::atomic::AtomicBool,
    (edges, seconds): (usize, u64),
    probe_pause: Duration,
) -> anyhow::Result<(Vec<f64>, f64)> {
    let mut plc = tokio_modbus::client::tcp::connect_slave(server, tokio_modbus::Slave(1)).await?;
    let plc_task = tokio::spawn(async move {
        loop {
            let _ = plc.read_discrete_inputs(0, 11).await;
            let _ = plc
                .write_multiple_coils(0, &[false, true, false, false, false, false, false])
                .await;
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    });
    let mut probe =
        tokio_modbus::client::tcp::connect_slave(plant_addr, tokio_modbus::Slave(1)).await?;
    // Every probe read is bounded: a plant that stops answering ends the bench
    // with an error instead of hanging it.
    let mut read_a1 = async move || -> anyhow::Result<bool> {
        Ok(
            tokio::time::timeout(Duration::from_secs(5), probe.read_coils(1, 1))
                .await
                .map_err(|_| anyhow::anyhow!("the plant did not answer the probe within 5 s"))???
                .first()
                .copied()
                .unwrap_or(false),
        )
    };
    // Wait for A1 at the plant.
    let deadline = Instant::now() + Duration::from_secs(10);
    while !read_a1().await? {
        anyhow::ensure!(Instant::now() < deadline, "A1 never reached the plant");
        if !probe_pause.is_zero() {
            tokio::time::sleep(probe_pause).await;
        }
    }
    measuring.store(true, std::sync::atomic::Ordering::Release);
    let started = Instant::now();
    let mut latencies = Vec::with_capacity(edges);
    let mut k = 0;
    while k < edges || started.elapsed() < Duration::from_secs(seconds) {
        // Spread the phase of the change over the cycle.
        tokio::time::sleep(Duration::from_micros(3000 + (k as u64 * 7919) % 10_000)).await;
        let rising = k % 2 == 0;
        let t0 = Instant::now();
        writeln!(plant_in, "di 3 {}", u8::from(rising))?;
        plant_in.flush()?;
        let deadline = t0 + Duration::from_secs(5);
        loop {
            if read_a1().await? != rising {
                break;
            }
            if !probe_pause.is_zero() {
                tokio::time::sleep(probe_pause).await;
            }
            anyhow::ensure!(
                Instant::now() < deadline,
                "edge {k}: no filtered output within 5 s"
            );
        }
        latencies.push(t0.elapsed().as_secs_f64() * 1e3);
        k += 1;
    }
    measuring.store(false, std::sync::atomic::Ordering::Release);
    plc_task.abort();
    anyhow::Ok((latencies, started.elapsed().as_secs_f64()))
}
