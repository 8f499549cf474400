//! The console on a live link (`vigie --link CONFIG`), driven through accessibility
//! queries, against the pymodbus peers (`tests/peers/`) on OS-chosen loopback ports:
//! - a monitor run: the link state, a violation with its explanation read from the
//!   plant, then the peer killed (reconnecting, alarm, stale inputs) and back;
//! - a gateway run: the PLC commands a forbidden combination, the plant receives the
//!   filter's output, the console shows the trip; the operator's reset is refused while
//!   the constraint holds and goes through the gateway once it does not;
//! - a monitor run with the plant's diagnosers: C4 dies at rest, the diagnoser panel
//!   shows the certain diagnosis the mirror makes from the run's cycles;
//! - a monitor run with the PLC's program given as PLCopen XML (`--program`): the
//!   program shown is that one, and the hypothesis names its equation, placed in the
//!   file;
//! - a monitor run over OPC UA (the asyncua plant, Basic256Sha256 SignAndEncrypt, user
//!   name): the panel names the protocol, a violation is explained, the peer killed and
//!   back.
//!
//! No fixed sleeps: every wait polls the console with a deadline.

#![allow(clippy::unwrap_used)] // a failure is a test failure

use crate::live::{Plant, Plc, StandIn, TempDir, repo, wait_until};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use std::time::{Duration, Instant};
use vigie_app::{Console, ConsoleOptions};

const WAIT: Duration = Duration::from_secs(15);

fn harness(mut opts: ConsoleOptions) -> Harness<'static, Console> {
    opts.lang = vigie_app::i18n::Lang::En;
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

/// A monitor configuration; `extra` adds fields (the diagnosers are on by default).
fn monitor_config(dir: &TempDir, port: u16, extra: &str) -> std::path::PathBuf {
    let station = repo()
        .join("layouts/sorting-station")
        .canonicalize()
        .unwrap();
    let text = format!(
        "Gateway(mode: Monitor, plant: {:?}, cycle_ms: 10, link_timeout_cycles: 5, \
         client: Modbus(address: \"127.0.0.1:{port}\", timeout_ms: 200, backoff_initial_ms: 50, backoff_max_ms: 400), {extra})",
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
    // The paper's constraints as written: with the diagnosers they are shown rewritten
    // for the cooperation (CSs10 = C7 . /A4 . /def_P).
    opts.link = Some(monitor_config(
        &dir,
        port,
        "diagnosers: false, plausibility: false",
    ));
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
    // A violation, not a stop: the monitored PLC keeps its outputs (issue 20).
    wait_for_label(&mut h, "Violation at");
    h.get_by_label("CSs10 = C7 · A\u{305}4\u{305}");
    // The live link moves the layout between frames: the button is pressed through
    // its accessibility action, as a screen reader does.
    h.get_by_label("2 Before stop").click_accesskit();
    wait_for_label(
        &mut h,
        "CSs10 = C7 · A\u{305}4\u{305} became true: C7=1, A4=0.",
    );
    let trip = h.state().latest_trip().unwrap();
    assert!(
        !h.state().sim.engine.trips[trip].enforced,
        "monitor mode reports, never enforces"
    );
    let level0 = &h.state().sim.explanations[&trip].current_state.items;
    assert_eq!(level0[0].code, "X006", "{:?}", level0[0].text);

    // The peer killed: reconnecting with backoff, the link alarm (active, in the
    // console's alarm list), stale inputs. (On a loaded machine the slow peer may have
    // raised and cleared the alarm before: wait for an active one.)
    plant.stop();
    wait_for_label(
        &mut h,
        &format!("Link: reconnecting to 127.0.0.1:{port} (attempt"),
    );
    wait_state(&mut h, "the active link alarm", |c| {
        c.sim
            .alarms
            .all()
            .iter()
            .any(|a| a.key == "link:peer" && a.cleared.is_none())
    });
    wait_for_label(&mut h, &format!("monitored peer 127.0.0.1:{port} lost"));
    wait_for_label(&mut h, "Stale inputs: C0");

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

fn gateway_config(dir: &TempDir, port: u16) -> std::path::PathBuf {
    let station = repo()
        .join("layouts/sorting-station")
        .canonicalize()
        .unwrap();
    let text = format!(
        "Gateway(mode: Gateway, plant: {:?}, cycle_ms: 10, link_timeout_cycles: 50, \
         client: Modbus(address: \"127.0.0.1:{port}\", timeout_ms: 200, backoff_initial_ms: 20, backoff_max_ms: 200), \
         server: Modbus(bind: \"127.0.0.1:0\", allow: [\"127.0.0.1\", \"127.0.0.2\"], plc: \"127.0.0.2\"), \
         diagnosers: false, plausibility: false, state_dir: {:?})", // the table moves in milliseconds: a fault for its diagnoser, edges the physics does not allow
        station.display().to_string(),
        dir.0.join("state").display().to_string()
    );
    let path = dir.0.join("gateway.ron");
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs frames until `cond` holds on the console (at most `WAIT`).
#[track_caller]
fn wait_state(h: &mut Harness<'static, Console>, what: &str, cond: impl Fn(&Console) -> bool) {
    let deadline = Instant::now() + WAIT;
    while !cond(h.state()) {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn console_follows_a_gateway_link_and_resets_through_it() {
    let mut plant = Plant::start(None);
    let port = plant.port;
    let dir = TempDir::new("console-gateway");
    let mut opts = ConsoleOptions::new(&repo().join("layouts/sorting-station"));
    opts.link = Some(gateway_config(&dir, port));
    opts.data_dir = None;
    let mut h = harness(opts);
    h.get_by_label("Mode: gateway (filter enforced between PLC and plant)");
    wait_for_label(&mut h, &format!("Link: connected to 127.0.0.1:{port}"));
    wait_for_label(&mut h, "PLC: silent");
    let server = h
        .state()
        .link
        .as_ref()
        .unwrap()
        .state
        .listening
        .clone()
        .unwrap();
    wait_for_label(&mut h, &format!("PLC server: {server}"));
    let mut plc = Plc::start(server.parse().unwrap(), Some("127.0.0.2"));
    plc.command("0000000");
    wait_for_label(&mut h, "PLC: heard");

    // The sequence of the gateway test (live.rs): a loaded table rotates to the
    // unloading position, the box leaves it to the right exit (C6 falls, C7 rises, one
    // edge per cycle), and the PLC releases A4 too early (CSs10 = C7 · /A4): the
    // gateway trips and holds A4 at the plant.
    plant.set_inputs(&[(4, true), (6, true)]);
    wait_until("the PLC to see C4 C6", || plc.sensors() == "di 00001010000");
    plc.command("0000100");
    wait_until("the plant to rotate", || plant.coils() == "0000100");
    plant.set_inputs(&[(4, false), (5, true)]);
    wait_until("the PLC to see C5 C6", || plc.sensors() == "di 00000110000");
    plant.set_inputs(&[(6, false)]);
    wait_until("the PLC to see C5", || plc.sensors() == "di 00000100000");
    plant.set_inputs(&[(7, true)]);
    wait_until("the PLC to see C5 C7", || plc.sensors() == "di 00000101000");
    plc.command("0000000");
    wait_for_label(&mut h, "TRIPPED");
    wait_for_label(&mut h, "Trip at");
    h.get_by_label("CSs10 = C7 · A\u{305}4\u{305}");
    let trip = h.state().latest_trip().unwrap();
    let record = &h.state().sim.engine.trips[trip];
    assert!(record.enforced);
    assert!(
        record.constraints.iter().any(|c| c.id == "CSs10"),
        "{record:?}"
    );
    assert_eq!(plant.coils(), "0000100", "the plant holds A4");

    // Reset while the box is still at C7: the gateway refuses it, the journal says why.
    h.get_by_label("Reset").click();
    wait_for_label(&mut h, "reset refused: ");
    assert!(h.state().sim.engine.is_tripped());
    assert_eq!(plant.coils(), "0000100");

    // The box has left: the reset goes through the gateway, the mirror follows, the
    // plant gets the PLC's outputs again.
    plant.set_inputs(&[(7, false)]);
    wait_until("the PLC to see C5 alone", || {
        plc.sensors() == "di 00000100000"
    });
    h.get_by_label("Reset").click();
    wait_state(&mut h, "the console's engine to reset", |c| {
        !c.sim.engine.is_tripped()
    });
    wait_until("the plant to follow the PLC again", || {
        plant.coils() == "0000000"
    });
    assert!(h.query_all_by_label_contains("TRIPPED").next().is_none());
}

#[test]
fn console_shows_the_diagnosers_of_a_monitor_link() {
    let mut plant = Plant::start(None);
    // The empty table at rest at C4: the initial state, where the diagnosers start.
    plant.set_inputs(&[(4, true)]);
    let dir = TempDir::new("console-diag");
    let mut opts = ConsoleOptions::new(&repo().join("layouts/sorting-station"));
    opts.link = Some(monitor_config(&dir, plant.port, ""));
    opts.data_dir = None;
    let mut h = harness(opts);
    // The diagnoser panel, fed by the mirror of the run's cycles.
    wait_for_label(&mut h, "Diagnosers (0 certain diagnoses)");
    wait_state(&mut h, "the mirror's diagnosers to start", |c| {
        c.sim
            .diagnosers
            .as_ref()
            .is_some_and(|d| d.estimate("table").iter().any(|s| s == "x0"))
    });
    // C4 dies at rest: certain on partition C4 after about 3.1 s.
    plant.set_inputs(&[(4, false)]);
    wait_for_label(&mut h, "Diagnosers (1 certain diagnoses)");
    wait_for_label(&mut h, "C4 at fault: the filter reads C\u{302}4");
    let c = h.state();
    let d = &c.sim.diagnosers.as_ref().unwrap().diagnoses[0];
    assert_eq!(
        (d.component.as_str(), d.partition.as_str()),
        ("table", "C4")
    );
    // One alarm, the mirror's (the run's own `diag:` alarm is not added twice).
    let alarms: Vec<_> = c
        .sim
        .alarms
        .all()
        .iter()
        .filter(|a| a.key == "diag:table:C4")
        .collect();
    assert_eq!(alarms.len(), 1, "{alarms:#?}");

    // The technician changes the sensor (C4 shows the table at rest again) and resets
    // the diagnosers: the run clears its flags, the mirror follows, the banner and the
    // alarm go.
    plant.set_inputs(&[(4, true)]);
    h.get_by_label("Reset diagnosers (after repair)").click();
    wait_state(&mut h, "the mirror's flags to clear", |c| {
        c.sim
            .diagnosers
            .as_ref()
            .is_some_and(|d| d.flagged().is_empty())
    });
    h.run_steps(3);
    assert!(
        h.query_all_by_label_contains("at fault").next().is_none(),
        "the degraded-mode banner is still shown"
    );
    assert!(
        h.state()
            .sim
            .alarms
            .all()
            .iter()
            .filter(|a| a.key == "diag:table:C4")
            .all(|a| a.cleared.is_some())
    );
}

/// `vigie --link CONFIG --program e11.xml`: a PLC stand-in runs the station's error E11
/// (A0 not stopped at C0), and the technician gives that program. The console shows the
/// program followed, and the violation's hypothesis names A0's equation and where it is
/// written in the file.
#[test]
fn console_explains_a_monitored_violation_with_the_program_given() {
    let station = repo().join("layouts/sorting-station");
    let plant_ron = vigie_core::plant::Plant::load(&station.join("plant.ron")).unwrap();
    let lib =
        vigie_core::control::ErrorLibrary::load(&station.join("programs/errors.ron"), &plant_ron)
            .unwrap();
    let e11 = lib
        .variants
        .into_iter()
        .find(|v| v.def.id == "E11")
        .unwrap()
        .program;
    let dir = TempDir::new("console-follow");
    let xml = dir.0.join("e11.xml");
    std::fs::write(
        &xml,
        vigie_core::plcopen::export(&e11, &plant_ron, std::path::Path::new("e11.ron")).unwrap(),
    )
    .unwrap();
    let given = vigie_core::control::CompiledProgram::load(&xml, &plant_ron).unwrap();
    let plant = Plant::start(None);
    let port = plant.port;
    let plc = StandIn::start(plant, e11);
    let mut opts = ConsoleOptions::new(&station);
    opts.link = Some(monitor_config(
        &dir,
        port,
        "diagnosers: false, plausibility: false",
    ));
    opts.program = Some(xml.clone());
    opts.data_dir = None;
    let mut h = harness(opts);
    wait_for_label(&mut h, &format!("Link: connected to 127.0.0.1:{port}"));
    // The program on screen is the one given.
    assert_eq!(
        h.state().sim.program.program().program.version(),
        given.program.version()
    );
    plc.press_start();
    plc.set(&[(4, true)]);
    wait_until("the feed conveyor A0 to run after START", || {
        plc.coils().starts_with('1')
    });
    plc.set(&[(0, true)]);
    wait_for_label(&mut h, "Violation at");
    h.get_by_label("4 Hypothesis").click_accesskit();
    wait_for_label(&mut h, "A0 is written (ST) in POU");
    wait_for_label(&mut h, "of e11.xml, line");
    let trip = h.state().latest_trip().unwrap();
    let items = &h.state().sim.explanations[&trip].hypothesis.items;
    assert!(items.iter().any(|i| i.code == "X410"), "{items:#?}");
}

#[test]
fn console_follows_an_opcua_monitor_link_with_encryption() {
    use crate::opcua::{NAMESPACE, Sec, Ua, UaPlant};
    let ua = Ua::new(Sec::Encrypt, "console-opcua");
    let mut plant = UaPlant::start(&ua, NAMESPACE, None);
    let map = ua.relaxed_map();
    let config = ua.config(&format!(
        "mode: Monitor, diagnosers: false, plausibility: false, {}",
        ua.client(
            &plant.endpoint(),
            &format!("node_map: {:?}", map.display().to_string())
        )
    ));
    let mut opts = ConsoleOptions::new(&repo().join("layouts/sorting-station"));
    opts.link = Some(config);
    opts.data_dir = None;
    let mut h = harness(opts);
    h.get_by_label("Mode: monitor (read-only, filter reports)");
    wait_for_label(&mut h, &format!("Link: connected to {}", plant.endpoint()));
    h.get_by_label("Protocol: OPC UA, Basic256Sha256 SignAndEncrypt, user vigie");
    wait_for_label(&mut h, "Stale inputs: none");

    // A box at C7 with A4 off: CSs10 violated, explained from the observed cycles.
    plant.set(&[("C7", true)]);
    wait_for_label(&mut h, "Violation at");
    h.get_by_label("2 Before stop").click_accesskit();
    wait_for_label(
        &mut h,
        "CSs10 = C7 · A\u{305}4\u{305} became true: C7=1, A4=0.",
    );

    // The peer killed: reconnecting, stale inputs; back on its port: connected again.
    let endpoint = plant.endpoint();
    let port: u16 = endpoint
        .trim_start_matches("opc.tcp://127.0.0.1:")
        .trim_end_matches('/')
        .parse()
        .unwrap();
    plant.kill();
    wait_for_label(&mut h, &format!("Link: reconnecting to {endpoint}"));
    wait_for_label(&mut h, "Stale inputs: C0");
    let _plant = UaPlant::start(&ua, NAMESPACE, Some(port));
    wait_for_label(&mut h, &format!("Link: connected to {endpoint}"));
    assert!(h.state().link.as_ref().unwrap().state.client.connections >= 2);
}
