//! Unit tests of the items on surfaces: the sorting station described as components
//! gives the figures its first emulator gave (frozen in `first-emulator.ron`), and
//! tables, sources and pulses of other shapes.

use crate::emulator::{Hazard, HazardKind};
use crate::engine::FilterMode;
use crate::machine::physical::Physical;
use crate::machine::{ComponentPlant, Components};
use crate::sim::{Options, Scenario, Simulation};
use crate::time::Millis;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

fn station() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

/// The station's first emulator's figures, frozen before it was deleted.
const FROZEN: &str = include_str!("first-emulator.ron");

/// What the identity tests compare of one run: a digest (FNV-1a, 64 bits) of the
/// sensors at every PLC cycle, taken at the end of each simulated minute and at the
/// end (so that a difference is located to its minute), the hazards and the counts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Figures {
    case: String,
    cycles: u64,
    sensors_by_minute: Vec<String>,
    hazards: Vec<String>,
    stats: String,
}

/// One case: a name, the scenario, the file its `plant` is read from, how long.
struct Case {
    name: String,
    scenario: Scenario,
    path: PathBuf,
    until_ms: u64,
}

/// The station's scenario files, sorted by name.
fn scenario_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(station().join("scenarios"))
        .expect("scenarios")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".ron"))
        .collect();
    names.sort();
    assert!(names.len() >= 8, "{names:?}");
    names
}

/// Every scenario of the station, whole.
fn scenario_cases() -> Vec<Case> {
    scenario_names()
        .into_iter()
        .map(|n| {
            let path = station().join("scenarios").join(&n);
            let scenario = Scenario::load(&path).expect("scenario");
            Case {
                name: n,
                until_ms: scenario.duration_ms,
                scenario,
                path,
            }
        })
        .collect()
}

/// Every variant of the control-error library, with the filter and without (where the
/// plant is damaged), on a busy minute.
fn error_cases() -> Vec<Case> {
    use crate::control::ErrorLibrary;
    use crate::emulator::{ArrivalPlan, BoxSize};
    use crate::sim::{OperatorAction, ProgramChoice, TimedAction};
    let plant = crate::plant::Plant::load(&station().join("plant.ron")).expect("plant");
    let lib = ErrorLibrary::load(&station().join("programs/errors.ron"), &plant).expect("library");
    assert!(lib.variants.len() >= 10);
    let busy = ArrivalPlan::List(
        (0..6)
            .map(|k| {
                let size = if k % 2 == 0 {
                    BoxSize::Small
                } else {
                    BoxSize::Large
                };
                (k * 4_000, size)
            })
            .collect(),
    );
    let mut cases = Vec::new();
    for v in &lib.variants {
        for filter in [FilterMode::Off, FilterMode::Enforce] {
            let scenario = Scenario {
                name: format!("{} ({filter:?})", v.def.id),
                description: String::new(),
                plant: ".".into(),
                program: ProgramChoice::Error(v.def.id.clone()),
                seed: 7,
                arrivals: Some(busy.clone()),
                faults: Vec::new(),
                actions: vec![TimedAction {
                    at_ms: 0,
                    action: OperatorAction::Start,
                }],
                duration_ms: 60_000,
                filter,
                cycle_ms: 10,
                projection_ms: 10_000,
                diagnosers: false,
                plausibility: true,
            };
            cases.push(Case {
                name: scenario.name.clone(),
                scenario,
                path: station().join("scenario.ron"),
                until_ms: 60_000,
            });
        }
    }
    cases
}

/// The station's layout fixture (a legacy folder's `layout.ron`) read as components,
/// set up as the scenario sets up the folder's emulator.
fn converted_emulator(s: &Scenario, plant: &crate::plant::Plant) -> Physical {
    let layout = crate::emulator::Layout::load(&crate::test_support::station_layout_file())
        .expect("the station's layout fixture loads");
    let c = layout.to_components().expect("converts");
    let mut e =
        Physical::new(&crate::machine::Description::Components(c), plant, s.seed).expect("builds");
    if let Some(plan) = &s.arrivals {
        e.set_arrivals(plan.clone());
    }
    for f in &s.faults {
        e.try_schedule_fault(f.clone()).expect("the fault applies");
    }
    e
}

/// The figures of a case on the station folder's components (`converted` false) or
/// on the layout fixture read as components, and the hazards the first emulator did
/// not know (both directions of the rollers' drive at once), set apart.
fn figures(case: &Case, converted: bool) -> (Figures, Vec<Hazard>) {
    let options = Options {
        history_cycles: 10,
        explain: false,
    };
    let mut sim = Simulation::from_scenario(&case.scenario, &case.path, options).expect("starts");
    assert!(sim.emulator.as_components().is_some(), "on components");
    if converted {
        let plant = sim.bundle.plant.clone();
        sim.emulator = converted_emulator(&case.scenario, &plant);
    }
    let n = sim.bundle.plant.inputs.len();
    let (mut h, mut cycles, mut minute) = (0xcbf2_9ce4_8422_2325_u64, 0, 60_000);
    let mut sensors_by_minute = Vec::new();
    while sim.now() < Millis(case.until_ms) {
        sim.cycle();
        cycles += 1;
        let b = sim.emulator.sensors();
        for i in 0..n {
            h = (h ^ u64::from(b.get(i))).wrapping_mul(0x0100_0000_01b3);
        }
        if sim.now().0 >= minute {
            sensors_by_minute.push(format!("{h:016x}"));
            minute += 60_000;
        }
    }
    sensors_by_minute.push(format!("{h:016x}"));
    let (opposed, others): (Vec<Hazard>, Vec<Hazard>) = sim
        .emulator
        .hazards()
        .iter()
        .cloned()
        .partition(|h| h.kind == HazardKind::OpposedDrives);
    let json = |v: &dyn erased::Json| v.json();
    let figures = Figures {
        case: case.name.clone(),
        cycles,
        sensors_by_minute,
        hazards: others.iter().map(|h| json(h)).collect(),
        stats: json(&sim.emulator.stats()),
    };
    (figures, opposed)
}

/// JSON of what the figures keep.
mod erased {
    pub(super) trait Json {
        fn json(&self) -> String;
    }
    impl<T: serde::Serialize> Json for T {
        fn json(&self) -> String {
            serde_json::to_string(self).expect("serialises")
        }
    }
}

fn frozen() -> Vec<Figures> {
    ron::from_str(FROZEN).expect("first-emulator.ron parses")
}

/// The first difference of `got` from the frozen figures of the same case.
fn compare(got: &Figures, frozen: &[Figures]) {
    let want = frozen
        .iter()
        .find(|f| f.case == got.case)
        .unwrap_or_else(|| panic!("no frozen figures for {}", got.case));
    if let Some(m) = (0..want.sensors_by_minute.len())
        .find(|&m| got.sensors_by_minute.get(m) != Some(&want.sensors_by_minute[m]))
    {
        panic!(
            "{}: the sensors differ from the first emulator's in minute {m} ({} cycles run, {} then)",
            got.case, got.cycles, want.cycles
        );
    }
    assert_eq!(got, want, "{}", got.case);
}

#[test]
fn the_station_as_components_runs_the_reference_hour_as_its_first_emulator_did() {
    let frozen = frozen();
    let case = scenario_cases()
        .into_iter()
        .find(|c| c.name == "reference-hour.ron")
        .expect("the reference hour");
    let (got, opposed) = figures(&case, false);
    assert!(got.cycles > 360_000);
    assert!(opposed.is_empty(), "{opposed:?}");
    compare(&got, &frozen);
}

#[test]
fn the_station_as_components_runs_every_scenario_of_the_station_as_its_first_emulator_did() {
    let frozen = frozen();
    for case in scenario_cases()
        .iter()
        .filter(|c| c.name != "reference-hour.ron")
    {
        let (got, opposed) = figures(case, false);
        assert!(opposed.is_empty(), "{}: {opposed:?}", case.name);
        compare(&got, &frozen);
    }
}

/// A legacy `layout.ron` folder runs on the components emulator, read through
/// `Layout::to_components`: the station's layout file, so read, runs every scenario of
/// the station as the first emulator did, sensors every cycle, hazards and counts.
#[test]
fn the_station_layout_read_as_components_runs_every_scenario_as_its_emulator_did() {
    let frozen = frozen();
    for case in &scenario_cases() {
        let (got, opposed) = figures(case, true);
        assert!(opposed.is_empty(), "{}: {opposed:?}", case.name);
        compare(&got, &frozen);
    }
}

/// Every variant of the control-error library, with the filter and without (where
/// the plant is damaged: the hazards are compared one by one), on a busy minute. The
/// components find one hazard the first emulator did not know, the rollers driven
/// both ways at once, and only without the filter (with it, CSs* keep A2 and A3 apart).
#[test]
fn the_station_as_components_runs_the_error_library_as_its_first_emulator_did() {
    let frozen = frozen();
    let mut opposed = Vec::new();
    for case in &error_cases() {
        let (got, o) = figures(case, false);
        if !o.is_empty() {
            opposed.push((case.name.clone(), case.scenario.filter));
        }
        compare(&got, &frozen);
    }
    assert!(
        !opposed.is_empty() && opposed.iter().all(|(_, f)| *f == FilterMode::Off),
        "{opposed:?}"
    );
}

/// An indexing corner with three positions: the table at 0 deg takes an item from
/// `feed`, turns to 180 deg and passes it to `out` (its rollers' end there); turning
/// with the item over its edge shears it; its arrivals wait for a free entry.
const CORNER: &str = r#"Components(
    name: "corner",
    items: (straddle_margin: 25.0, shear_margin: 2.0, push_tolerance: 20.0),
    components: [
        (id: "feed", name: "Feed", kind: Conveyor((
            length: 600.0,
            drives: [(when: "F", speed: 300.0)],
            sensors: [(signal: "s_in", at: 580.0)],
            source: Some((
                items: [(class: "a", length: 200.0), (class: "b", length: 300.0, tags: ["tall"])],
                arrivals: (period_ms: 1000, count: Some(3)),
            )),
            exit: To("table"),
            accumulating: false,
        ))),
        (id: "table", name: "Table", kind: Turntable((
            start: 0.0,
            positions: [
                (at: 0.0, when: "/T1 . /T2", joins: [(end: Start, to: "feed", at: End)]),
                (at: 90.0, when: "T1", joins: []),
                (at: 180.0, when: "T2", joins: [(end: Start, to: "out", at: Start)]),
            ],
            speed: 90.0,
            dock_tolerance: 1.0,
            sensors: [(signal: "p0", from: -0.5, to: 0.5), (signal: "p180", from: 179.5, to: 180.5)],
            length: 400.0,
            rollers: [(when: "R", speed: 300.0), (when: "Rb", speed: -300.0)],
            beams: [(signal: "s_mid", at: 200.0)],
        ))),
        (id: "out", name: "Out", kind: Conveyor((
            length: 800.0,
            drives: [(when: "O", speed: 300.0)],
            exit: Sink,
            accumulating: false,
        ))),
    ],
)"#;

const C_OUT: [&str; 6] = ["F", "T1", "T2", "R", "Rb", "O"];
const C_IN: [&str; 4] = ["s_in", "p0", "p180", "s_mid"];

fn corner() -> ComponentPlant {
    use crate::plant::{Plant, Signal, SignalKind};
    let plant = Plant {
        name: "corner".into(),
        description: String::new(),
        inputs: C_IN
            .iter()
            .map(|s| Signal::new(*s, SignalKind::Sensor, *s))
            .collect(),
        outputs: C_OUT
            .iter()
            .map(|s| Signal::new(*s, SignalKind::Actuator, *s))
            .collect(),
    };
    let c = Components::from_ron(CORNER, Path::new("components.ron")).expect("parses");
    ComponentPlant::new(&c, &plant, 3).expect("builds")
}

fn drive(e: &mut ComponentPlant, on: &[&str], ms: u64) {
    let mut b = crate::bits::Bits::zeros(C_OUT.len());
    for o in on {
        b.set(C_OUT.iter().position(|x| x == o).expect("output"), true);
    }
    for _ in 0..ms / 10 {
        e.step(Millis(10), &b);
    }
}

fn lit(e: &ComponentPlant, s: &str) -> bool {
    e.sensors()
        .get(C_IN.iter().position(|x| *x == s).expect("input"))
}

#[test]
fn a_table_with_three_positions_takes_an_item_and_hands_it_over_at_the_third() {
    let mut e = corner();
    assert!(lit(&e, "p0"));
    // The first arrival (class a, 200 mm) runs onto the table and stops in its middle.
    drive(&mut e, &["F", "R"], 2_000);
    drive(&mut e, &["R"], 20);
    let mut k = 0;
    while !lit(&e, "s_mid") && k < 100 {
        drive(&mut e, &["F", "R"], 10);
        k += 1;
    }
    assert!(lit(&e, "s_mid"), "the item reaches the table's beam");
    drive(&mut e, &["R"], 100);
    drive(&mut e, &[], 10);
    // Turn to 180 deg (2 s at 90 deg/s), through 90 deg where nothing is joined.
    drive(&mut e, &["T2"], 2_100);
    assert!(lit(&e, "p180") && !lit(&e, "p0"));
    // Rollers backwards (towards their start, which meets `out` there) and `out` on.
    drive(&mut e, &["T2", "Rb", "O"], 5_000);
    assert_eq!(e.items_out_by_exit(), vec![("out".to_string(), 1)]);
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
}

#[test]
fn a_table_turning_with_an_item_over_its_edge_shears_it_and_an_unjoined_end_drops_it() {
    let mut e = corner();
    // The item half on the table when the table turns away.
    let mut k = 0;
    while !lit(&e, "s_in") && k < 500 {
        drive(&mut e, &["F", "R"], 10);
        k += 1;
    }
    drive(&mut e, &["F", "R"], 300);
    drive(&mut e, &["T1"], 500);
    let h = e.hazards();
    assert!(
        h.iter()
            .any(|h| h.kind == crate::emulator::HazardKind::Sheared
                && h.place == "edge of the Table"
                && h.elements.contains(&"T1".to_string())),
        "{h:?}"
    );
    // An item fully on the table, turned to 90 deg where nothing is joined: the
    // rollers push it off the table's end.
    let mut e = corner();
    let mut k = 0;
    while !lit(&e, "s_mid") && k < 500 {
        drive(&mut e, &["F", "R"], 10);
        k += 1;
    }
    drive(&mut e, &["R"], 100);
    drive(&mut e, &["T1"], 1_100);
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
    drive(&mut e, &["T1", "R"], 3_000);
    assert!(
        e.hazards()
            .iter()
            .any(|h| h.kind == crate::emulator::HazardKind::Dropped),
        "{:?}",
        e.hazards()
    );
}

#[test]
fn arrivals_wait_for_a_free_entry_and_stop_at_their_count() {
    let mut e = corner();
    // Nothing runs: the first arrival waits on the entry, the others behind it.
    drive(&mut e, &[], 10_000);
    assert_eq!(e.items_in(), 1, "one on the belt, two waiting");
    drive(&mut e, &["F", "R"], 1_500);
    drive(&mut e, &[], 10);
    assert_eq!(e.items_in(), 2, "the second came once the first left");
    drive(&mut e, &["F"], 20_000);
    assert!(e.items_in() <= 3, "three at most");
}

/// A transient injected between two PLC cycles (an operator's or a campaign's, not a
/// scenario's) takes effect at the next internal step, as on the first emulator: a
/// pulse of C8 as long as one cycle, with the table empty, is read by the next cycle
/// and held by the plausibility rules (the components once made it active at once and
/// over before any cycle read it).
#[test]
fn a_pulse_injected_between_two_cycles_is_read_as_the_layout_read_it() {
    use crate::emulator::{ArrivalPlan, FaultKind, FaultSpec, SizeMix, Trigger};
    use crate::sim::OperatorAction;
    let run = || {
        let path = station().join("scenarios/reference-hour.ron");
        let s = Scenario::load(&path).expect("scenario");
        let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("sim");
        sim.emulator.set_arrivals(ArrivalPlan::Periodic {
            period_ms: 8_000,
            jitter_ms: 1_000,
            mix: SizeMix::Alternate,
            count: None,
        });
        sim.act(&OperatorAction::Start).expect("start");
        sim.run_until(Millis(20_000));
        let input = |id: &str| sim.bundle.plant.input(id).expect("input");
        let (c4, c6, c8) = (input("C4"), input("C6"), input("C8"));
        let mut empty_since = None;
        for _ in 0..10_000 {
            if sim.emulator.sensors().get(c4) && !sim.emulator.sensors().get(c6) {
                let t = *empty_since.get_or_insert(sim.now().0);
                if sim.now().0 >= t + 300 {
                    break;
                }
            } else {
                empty_since = None;
            }
            sim.cycle();
        }
        assert!(empty_since.is_some(), "the table is empty at C4 for 300 ms");
        let at = sim.now().0;
        sim.inject(FaultSpec {
            trigger: Trigger::At(at),
            fault: FaultKind::SpuriousRise {
                sensor: "C8".into(),
                pulse_ms: 10,
            },
            duration_ms: None,
        })
        .expect("inject");
        let mut read = Vec::new();
        for _ in 0..4 {
            read.push(sim.emulator.sensors().get(c8));
            sim.cycle();
        }
        let held = sim
            .journal()
            .iter()
            .any(|j| j.kind == "plausibility" && j.text.contains("C8 suspect"));
        (at, read, held)
    };
    // The first emulator read [false, true, false, false] too, and held it.
    let components = run();
    assert_eq!(components.1, [false, true, false, false]);
    assert!(components.2, "the pulse is held as implausible");
}
