//! Unit tests of the items on surfaces: the sorting station described as components
//! runs cycle for cycle as its layout's emulator did.

use crate::machine::physical::Physical;
use crate::machine::{ComponentPlant, Components};
use crate::sim::{Options, Scenario, Simulation};
use crate::time::Millis;
use std::path::{Path, PathBuf};

fn station() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

/// The station's first emulator, run from the layout file it was written for (kept as
/// a fixture): what the components must reproduce.
fn layout_emulator(s: &Scenario, plant: &crate::plant::Plant) -> Physical {
    let layout = crate::emulator::Layout::load(&crate::test_support::station_layout_file())
        .expect("the station's layout fixture loads");
    let mut e = Physical::first_emulator(&layout, plant, s.seed).expect("builds");
    if let Some(plan) = &s.arrivals {
        e.set_arrivals(plan.clone());
    }
    for f in &s.faults {
        e.try_schedule_fault(f.clone()).expect("the fault applies");
    }
    e
}

/// The layout fixture read as components ([`crate::emulator::Layout::to_components`],
/// what a legacy `layout.ron` folder runs on), set up as [`layout_emulator`] sets up
/// the first emulator.
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

/// The scenario run twice, on the layout's emulator and on the components; the
/// sensors, every cycle, and the hazards, are the same. Returns the cycles compared.
fn same_run(scenario: &str, until_ms: u64) -> u64 {
    let path = station().join("scenarios").join(scenario);
    let s = Scenario::load(&path).expect("scenario");
    let (cycles, opposed) = same(&s, &path, until_ms);
    assert!(opposed.is_empty(), "{scenario}: {opposed:?}");
    cycles
}

/// [`same_run`] of a scenario read from `path` (which anchors its `plant`). The
/// components report one hazard the layout did not know, both directions of a drive
/// at once (the rollers' A2 and A3): those are returned, the others compared.
fn same(s: &Scenario, path: &Path, until_ms: u64) -> (u64, Vec<crate::emulator::Hazard>) {
    same_as(s, path, until_ms, false)
}

/// [`same`], the components being the station folder's (`converted` false) or the
/// layout fixture read as components (true).
fn same_as(
    s: &Scenario,
    path: &Path,
    until_ms: u64,
    converted: bool,
) -> (u64, Vec<crate::emulator::Hazard>) {
    let scenario = &s.name;
    let options = || Options {
        history_cycles: 10,
        explain: false,
    };
    let mut old = Simulation::from_scenario(s, path, options()).expect("starts");
    let new = Simulation::from_scenario(s, path, options()).expect("starts");
    let mut new = new;
    let plant = new.bundle.plant.clone();
    assert!(
        new.emulator.as_components().is_some(),
        "the folder runs on components"
    );
    old.emulator = layout_emulator(s, &plant);
    if converted {
        new.emulator = converted_emulator(s, &plant);
    }
    let mut cycles = 0;
    while old.now() < Millis(until_ms) {
        old.cycle();
        new.cycle();
        cycles += 1;
        let (a, b) = (old.emulator.sensors(), new.emulator.sensors());
        if a != b {
            let differ: Vec<_> = (0..plant.inputs.len())
                .filter(|&i| a.get(i) != b.get(i))
                .map(|i| format!("{}={}", plant.inputs[i].id, u8::from(a.get(i))))
                .collect();
            panic!(
                "{scenario}: at {} ms the sensors differ (layout's values: {differ:?})",
                old.now().0
            );
        }
    }
    let (opposed, others): (Vec<_>, Vec<_>) = new
        .emulator
        .hazards()
        .iter()
        .cloned()
        .partition(|h| h.kind == crate::emulator::HazardKind::OpposedDrives);
    assert_eq!(old.emulator.hazards(), others.as_slice(), "{scenario}");
    assert_eq!(old.emulator.stats(), new.emulator.stats(), "{scenario}");
    assert!(new.emulator.as_components().is_some());
    (cycles, opposed)
}

#[test]
fn the_station_as_components_runs_the_reference_hour_as_its_layout_did() {
    let cycles = same_run("reference-hour.ron", 3_660_000);
    assert!(cycles > 360_000);
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

#[test]
fn the_station_as_components_runs_every_scenario_of_the_station_as_its_layout_did() {
    let names = scenario_names();
    for n in names.iter().filter(|n| *n != "reference-hour.ron") {
        let path = station().join("scenarios").join(n);
        let s = Scenario::load(&path).expect("scenario");
        same_run(n, s.duration_ms);
    }
}

/// A legacy `layout.ron` folder runs on the components emulator, read through
/// `Layout::to_components`: the station's layout file, so read, runs every scenario of
/// the station (the reference hour's first ten minutes) as the first emulator did,
/// sensors every cycle, hazards and counts.
#[test]
fn the_station_layout_read_as_components_runs_every_scenario_as_its_emulator_did() {
    for n in &scenario_names() {
        let path = station().join("scenarios").join(n);
        let s = Scenario::load(&path).expect("scenario");
        let (cycles, opposed) = same_as(&s, &path, s.duration_ms.min(600_000), true);
        assert!(cycles > 100, "{n}");
        assert!(opposed.is_empty(), "{n}: {opposed:?}");
    }
}

/// Every variant of the control-error library, with the filter and without (where
/// the plant is damaged: the hazards are compared one by one), on a busy shift.
#[test]
fn the_station_as_components_runs_the_error_library_as_its_layout_did() {
    use crate::control::ErrorLibrary;
    use crate::emulator::{ArrivalPlan, BoxSize};
    use crate::engine::FilterMode;
    use crate::sim::{OperatorAction, ProgramChoice, TimedAction};
    let plant = crate::plant::Plant::load(&station().join("plant.ron")).expect("plant");
    let lib = ErrorLibrary::load(&station().join("programs/errors.ron"), &plant).expect("library");
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
    let mut opposed = Vec::new();
    for v in &lib.variants {
        for filter in [FilterMode::Off, FilterMode::Enforce] {
            let s = Scenario {
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
            let (_, o) = same(&s, &station().join("scenario.ron"), 60_000);
            if !o.is_empty() {
                opposed.push((v.def.id.clone(), filter));
            }
        }
    }
    // Only without the filter: with it, CSs* keep A2 and A3 apart.
    assert!(
        opposed.iter().all(|(_, f)| *f == FilterMode::Off),
        "{opposed:?}"
    );
    assert!(lib.variants.len() >= 10);
    eprintln!("opposed drives, found by the components only: {opposed:?}");
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
/// scenario's) takes effect at the next internal step on both emulators: a pulse of
/// C8 as long as one cycle, with the table empty, is read by the next cycle and held
/// by the plausibility rules on both (the components once made it active at once and
/// over before any cycle read it).
#[test]
fn a_pulse_injected_between_two_cycles_is_read_as_the_layout_read_it() {
    use crate::emulator::{ArrivalPlan, FaultKind, FaultSpec, SizeMix, Trigger};
    use crate::sim::OperatorAction;
    let run = |first_emulator: bool| {
        let path = station().join("scenarios/reference-hour.ron");
        let s = Scenario::load(&path).expect("scenario");
        let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("sim");
        if first_emulator {
            let plant = sim.bundle.plant.clone();
            sim.emulator = layout_emulator(&s, &plant);
        }
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
    let (components, first) = (run(false), run(true));
    assert_eq!(components, first);
    assert_eq!(components.1, [false, true, false, false]);
    assert!(components.2, "the pulse is held as implausible");
}
