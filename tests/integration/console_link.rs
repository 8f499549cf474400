//! The console on a live link (`vigie --link CONFIG`), driven through accessibility
//! queries: a monitor run against the pymodbus plant peer (`tests/peers/plant.py`) on
//! an OS-chosen loopback port; the link state, a violation with its explanation read
//! from the plant, then the peer killed (reconnecting, alarm, stale inputs) and back.
//! No fixed sleeps: every wait polls the console with a deadline.

#![allow(clippy::unwrap_used)] // a failure is a test failure

use crate::live::{Plant, TempDir, repo};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use std::time::{Duration, Instant};
use vigie_app::{Console, ConsoleOptions};

const WAIT: Duration = Duration::from_secs(15);

fn harness(opts: ConsoleOptions) -> Harness<'static, Console> {
    Harness::builder()
        .with_size(egui::vec2(1600.0, 1000.0))
        .with_step_dt(1.0 / 60.0)
        .build_eframe(move |cc| {
            let mut c = Console::new(&opts).expect("console opens on the link");
            c.setup(&cc.egui_ctx);
            c
        })
}

/// Runs frames until a label containing `text` shows (at most `WAIT`).
#[track_caller]
fn wait_for_label(h: &mut Harness<'static, Console>, text: &str) {
    let deadline = Instant::now() + WAIT;
    while Instant::now() < deadline {
        h.step();
        if h.query_all_by_label_contains(text).next().is_some() {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let state = h.state().link.as_ref().map(|l| format!("{:#?}", l.state));
    panic!("no label containing {text:?} within {WAIT:?}; link state: {state:?}");
}

fn monitor_config(dir: &TempDir, port: u16) -> std::path::PathBuf {
    let station = repo()
        .join("layouts/sorting-station")
        .canonicalize()
        .unwrap();
    let text = format!(
        "Gateway(mode: Monitor, plant: {:?}, cycle_ms: 10, link_timeout_cycles: 5, \
         client: (address: \"127.0.0.1:{port}\", timeout_ms: 200, backoff_initial_ms: 50, backoff_max_ms: 400))",
        station.display().to_string()
    );
    let path = dir.0.join("monitor.ron");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn console_follows_a_monitor_link_to_pymodbus() {
    let mut plant = Plant::start(None);
    let port = plant.port;
    let dir = TempDir::new("console-link");
    let mut opts = ConsoleOptions::new(&repo().join("layouts/sorting-station"));
    opts.link = Some(monitor_config(&dir, port));
    opts.data_dir = None;
    let mut h = harness(opts);

    // Connected: the link-state panel and the status bar say so.
    h.get_by_label("Live link");
    h.get_by_label("Mode: monitor (read-only, filter reports)");
    wait_for_label(&mut h, &format!("Link: connected to 127.0.0.1:{port}"));
    wait_for_label(&mut h, "Stale inputs: none");
    wait_for_label(&mut h, "Last poll: ");
    wait_for_label(&mut h, "Exceptions: 0");
    let cycles = h.state().sim.engine.cycles();
    assert!(cycles > 0, "the console's engine follows the link's cycles");

    // A box at C7 with the turntable's A4 off (CSs10 = C7 · /A4): the monitored plant
    // violates the constraint; the console explains it from the observed cycles.
    plant.set_inputs(&[(7, true)]);
    wait_for_label(&mut h, "Trip at");
    h.get_by_label("CSs10 = C7 · A\u{305}4\u{305}");
    h.get_by_label("2 Before stop").click();
    wait_for_label(
        &mut h,
        "CSs10 = C7 · A\u{305}4\u{305} became true: C7=1, A4=0.",
    );
    let trip = h.state().latest_trip().unwrap();
    assert!(
        !h.state().sim.engine.trips[trip].enforced,
        "monitor mode reports, never enforces"
    );

    // The peer killed: reconnecting with backoff, the link alarm, stale inputs.
    plant.stop();
    wait_for_label(
        &mut h,
        &format!("Link: reconnecting to 127.0.0.1:{port} (attempt"),
    );
    wait_for_label(&mut h, &format!("monitored peer 127.0.0.1:{port} lost"));
    wait_for_label(&mut h, "Stale inputs: C0");
    assert!(
        h.state()
            .sim
            .alarms
            .all()
            .iter()
            .any(|a| a.key == "link:peer" && a.cleared.is_none()),
        "the link alarm is in the console's alarm list"
    );

    // The peer back on the same port: connected again, the alarm cleared.
    let mut plant = Plant::start(Some(port));
    wait_for_label(&mut h, &format!("Link: connected to 127.0.0.1:{port}"));
    let deadline = Instant::now() + WAIT;
    while h
        .state()
        .sim
        .alarms
        .all()
        .iter()
        .any(|a| a.key == "link:peer" && a.cleared.is_none())
    {
        assert!(Instant::now() < deadline, "the link alarm never cleared");
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    let link = h.state().link.as_ref().unwrap();
    assert!(link.state.client.connections >= 2, "{:#?}", link.state);
    plant.set_inputs(&[(7, false)]);
}
