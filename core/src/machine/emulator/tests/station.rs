//! The sorting station on the components emulator: geometry and timing against the
//! paper, hazards, faults, determinism. These were the first emulator's own tests; the
//! station's layout file (kept as a fixture) is read as components, as a legacy
//! `layout.ron` folder is.

use crate::bits::Bits;
use crate::diag::Problem;
use crate::emulator::{
    ArrivalPlan, BoxSize, BoxState, FaultKind, FaultSpec, Hazard, HazardKind, Layout, Position,
    Side, SizeMix, Trigger,
};
use crate::machine::{Description, Physical};
use crate::plant::Plant;
use crate::time::Millis;
use std::path::{Path, PathBuf};

/// The station's emulator, with what the tests do by hand: place a box, turn the table.
#[derive(Clone)]
struct Station(Physical);

impl std::ops::Deref for Station {
    type Target = Physical;
    fn deref(&self) -> &Physical {
        &self.0
    }
}

impl std::ops::DerefMut for Station {
    fn deref_mut(&mut self) -> &mut Physical {
        &mut self.0
    }
}

impl Station {
    /// The components `layout` describes, at time 0.
    fn try_new(layout: &Layout, plant: &Plant, seed: u64) -> Result<Self, Problem> {
        let c = layout.to_components().map_err(|mut p| p.remove(0))?;
        Physical::new(&Description::Components(c), plant, seed).map(Self)
    }

    fn new(layout: &Layout, plant: &Plant, seed: u64) -> Self {
        Self::try_new(layout, plant, seed).expect("emulator")
    }

    fn plant(&mut self) -> &mut crate::machine::ComponentPlant {
        let Physical::Components(c) = &mut self.0;
        c
    }

    /// A box with its centre `centre` mm along `part` (the table: from its middle).
    fn place_box(&mut self, part: &str, centre: i64, size: BoxSize) {
        let along = if part == "table" {
            centre + 250
        } else {
            centre
        };
        #[allow(clippy::cast_precision_loss)]
        let along = along as f64;
        self.plant()
            .place_item(part, along, usize::from(size == BoxSize::Large))
            .expect("placed");
    }

    fn set_table_angle_mdeg(&mut self, mdeg: i32) {
        assert!(self.plant().set_position("table", f64::from(mdeg) / 1000.0));
    }

    fn disable_quiet_steps(&mut self) {
        self.plant().disable_quiet_steps();
    }
}

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

/// The station's plant. `plant.ron` opens with `Plant(` while its struct is `PlantFile`,
/// which `ron` 0.12 refuses (reported to the lead): drop the name before parsing.
fn plant() -> Plant {
    static PLANT: std::sync::OnceLock<Plant> = std::sync::OnceLock::new();
    PLANT.get_or_init(load_plant).clone()
}

fn load_plant() -> Plant {
    let path = dir().join("plant.ron");
    let text = std::fs::read_to_string(&path).expect("plant.ron");
    Plant::from_ron(&text.replacen("\nPlant(", "\n(", 1), &path).expect("plant")
}

fn layout() -> Layout {
    Layout::load(&crate::test_support::station_layout_file()).expect("layout")
}

/// An emulator with no arrivals.
fn emu(seed: u64) -> Station {
    let mut e = Station::new(&layout(), &plant(), seed);
    e.set_arrivals(ArrivalPlan::Off);
    e
}

/// These outputs ON, and the safety contactors the safety function holds ON.
fn outs(on: &[&str]) -> Bits {
    let p = plant();
    let mut b = Bits::zeros(p.outputs.len());
    for k in (0..p.outputs.len()).filter(|&k| p.outputs[k].held_on) {
        b.set(k, true);
    }
    for a in on {
        b.set(p.output(a).expect("actuator"), true);
    }
    b
}

fn sensor(e: &Station, id: &str) -> bool {
    e.sensors().get(plant().input(id).expect("sensor"))
}

/// Steps 1 ms at a time until `pred` holds; the time it held, if within `max_ms`.
fn until(e: &mut Station, o: &Bits, max_ms: u64, pred: impl Fn(&Station) -> bool) -> Option<u64> {
    for _ in 0..max_ms {
        e.step(Millis(1), o);
        if pred(e) {
            return Some(e.now().0);
        }
    }
    None
}

#[test]
fn loads_the_station_layout() {
    let l = layout();
    assert_eq!(l.sensors.len(), 11);
    let e = emu(1);
    assert!(sensor(&e, "C4") && !sensor(&e, "C5"));
    assert_eq!(e.table_angle_mdeg(), 0);
}

#[test]
fn turntable_timings_match_the_learned_intervals() {
    for seed in 0..20 {
        let mut e = emu(seed);
        let on = outs(&["A4"]);
        let c4_fall = until(&mut e, &on, 500, |e| !sensor(e, "C4")).expect("C4 falls");
        let c5_rise = until(&mut e, &on, 4000, |e| sensor(e, "C5")).expect("C5 rises");
        assert!((100..130).contains(&c4_fall), "C4 fell at {c4_fall}");
        assert!((2900..2950).contains(&c5_rise), "C5 rose at {c5_rise}");
        until(&mut e, &on, 200, |e| e.table_angle_mdeg() == 90_000).expect("reaches 90");
        let t0 = e.now().0;
        let off = outs(&[]);
        let c5_fall = until(&mut e, &off, 500, |e| !sensor(e, "C5")).expect("C5 falls") - t0;
        let c4_rise = until(&mut e, &off, 4000, |e| sensor(e, "C4")).expect("C4 rises") - t0;
        assert!(c5_fall < 150, "C5 fell after {c5_fall}");
        assert!((2880..2970).contains(&c4_rise), "C4 rose after {c4_rise}");
        if seed == 0 {
            eprintln!(
                "timings: C4 fall {c4_fall}, C5 rise {c5_rise}, C5 fall {c5_fall}, C4 rise {c4_rise}"
            );
        }
    }
}

/// A correct open-loop-by-phases controller sending one box to `side`.
fn drive_one(e: &mut Station, side: Side, max_ms: u64) -> Vec<String> {
    let p = plant();
    let mut rises = Vec::new();
    let mut prev = e.sensors().clone();
    let mut phase = 0;
    let mut released = false;
    for _ in 0..max_ms {
        let s = |id: &str| e.sensors().get(p.input(id).expect("id"));
        let (exit_sensor, rollers) = match side {
            Side::Left => ("C8", "A2"),
            Side::Right => ("C7", "A3"),
        };
        let mut on = vec!["A5", "A6"];
        match phase {
            0 => {
                on.extend(["A0", "A1", "A2"]);
                if s("C6") {
                    phase = 1;
                    on.clear();
                    on.extend(["A5", "A6", "A4"]);
                }
            }
            1 => {
                on.push("A4");
                if s("C5") {
                    phase = 2;
                    on.push(rollers);
                }
            }
            2 => {
                on.push(rollers);
                if s(exit_sensor) {
                    released = true;
                }
                if !released || s(exit_sensor) {
                    on.push("A4");
                } else {
                    phase = 3;
                }
            }
            _ => {}
        }
        e.step(Millis(1), &outs(&on));
        let now = e.sensors().clone();
        for (i, sig) in p.inputs.iter().enumerate() {
            if now.get(i) && !prev.get(i) {
                rises.push(sig.id.clone());
            }
        }
        prev = now;
        if e.stats().delivered_total() > 0 {
            break;
        }
    }
    rises
}

fn order_of(rises: &[String], ids: &[&str]) -> Vec<String> {
    rises
        .iter()
        .filter(|r| ids.contains(&r.as_str()))
        .cloned()
        .collect()
}

#[test]
fn a_box_goes_right_without_hazard() {
    for size in [BoxSize::Small, BoxSize::Large] {
        let mut e = emu(3);
        e.place_box("entry", 200, size);
        let rises = drive_one(&mut e, Side::Right, 30_000);
        let ids = ["C0", "C1", "C3", "C6", "C5", "C7", "C9"];
        assert_eq!(order_of(&rises, &ids), ids, "{rises:?}");
        assert_eq!(rises.contains(&"C2".to_string()), size == BoxSize::Large);
        assert!(e.hazards().is_empty(), "{:?}", e.hazards());
        assert_eq!(e.stats().delivered_at("right_exit"), 1);
    }
}

#[test]
fn a_box_goes_left_without_hazard() {
    let mut e = emu(4);
    e.place_box("entry", 200, BoxSize::Large);
    let rises = drive_one(&mut e, Side::Left, 30_000);
    let ids = ["C0", "C1", "C3", "C6", "C5", "C8", "C10"];
    assert_eq!(order_of(&rises, &ids), ids, "{rises:?}");
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
    assert_eq!(e.stats().delivered_at("left_exit"), 1);
}

fn kinds(e: &Station) -> Vec<HazardKind> {
    e.hazards().iter().map(|h| h.kind).collect()
}

#[test]
fn a1_onto_a_rotated_table_drops_the_box() {
    let mut e = emu(1);
    e.set_table_angle_mdeg(90_000);
    e.place_box("intermediate", 1000, BoxSize::Small);
    // A4 held: the table stays at 90 degrees, nothing continues A1.
    until(&mut e, &outs(&["A1", "A4"]), 3000, |e| {
        !e.hazards().is_empty()
    })
    .expect("hazard");
    let h = &e.hazards()[0];
    assert_eq!(h.kind, HazardKind::Dropped);
    assert!(h.elements.contains(&"A1".to_string()));
    assert_eq!(e.boxes()[0].state, BoxState::Fallen);
    // A fallen box lies still.
    let at = e.boxes()[0].x_mm;
    e.step(Millis(1000), &outs(&["A1", "A4"]));
    assert_eq!(e.boxes()[0].x_mm, at);
    assert_eq!(e.stats().damaged, 1);
}

#[test]
fn rollers_at_loading_push_the_box_off_the_far_end() {
    let mut e = emu(1);
    e.place_box("table", 100, BoxSize::Small);
    until(&mut e, &outs(&["A2"]), 3000, |e| !e.hazards().is_empty()).expect("hazard");
    assert_eq!(kinds(&e), vec![HazardKind::Dropped]);
}

#[test]
fn a0_onto_stopped_a1_pushes_the_box() {
    let mut e = emu(1);
    e.place_box("entry", 1000, BoxSize::Small);
    until(&mut e, &outs(&["A0"]), 3000, |e| !e.hazards().is_empty()).expect("hazard");
    let h = &e.hazards()[0];
    assert_eq!(h.kind, HazardKind::PushedAgainstStopped);
    assert_eq!(h.elements, vec!["A0".to_string(), "A1".to_string()]);
    // The same box does not report the same kind twice.
    e.step(Millis(2000), &outs(&["A0"]));
    assert_eq!(kinds(&e), vec![HazardKind::PushedAgainstStopped]);
}

#[test]
fn a1_onto_stopped_rollers_pushes_the_box() {
    let mut e = emu(1);
    e.place_box("intermediate", 1000, BoxSize::Large);
    until(&mut e, &outs(&["A1"]), 3000, |e| !e.hazards().is_empty()).expect("hazard");
    assert_eq!(kinds(&e), vec![HazardKind::PushedAgainstStopped]);
}

#[test]
fn releasing_a4_while_a_box_straddles_c7_shears_it() {
    let mut e = emu(1);
    e.set_table_angle_mdeg(90_000);
    e.place_box("table", 0, BoxSize::Small);
    until(&mut e, &outs(&["A4", "A3", "A6"]), 3000, |e| {
        sensor(e, "C7")
    })
    .expect("C7");
    assert!(e.hazards().is_empty());
    until(&mut e, &outs(&["A3", "A6"]), 100, |e| {
        !e.hazards().is_empty()
    })
    .expect("hazard");
    assert_eq!(kinds(&e), vec![HazardKind::Sheared]);
}

#[test]
fn rollers_on_with_a_stopped_exit_push_the_box() {
    let mut e = emu(1);
    e.set_table_angle_mdeg(90_000);
    e.place_box("table", 0, BoxSize::Small);
    until(&mut e, &outs(&["A4", "A2"]), 3000, |e| {
        !e.hazards().is_empty()
    })
    .expect("hazard");
    assert_eq!(kinds(&e), vec![HazardKind::PushedAgainstStopped]);
}

#[test]
fn a_fast_box_catching_a_slow_one_collides() {
    let mut e = emu(1);
    e.schedule_fault(FaultSpec {
        trigger: Trigger::At(0),
        fault: FaultKind::ConveyorSlowed {
            actuator: "A1".into(),
            percent: 30,
        },
        duration_ms: None,
    });
    // Box 2 touches box 1 while its centre is still on the faster A0.
    e.place_box("intermediate", 200, BoxSize::Small);
    e.place_box("entry", 920, BoxSize::Small);
    until(&mut e, &outs(&["A0", "A1"]), 5000, |e| {
        !e.hazards().is_empty()
    })
    .expect("hazard");
    let h = &e.hazards()[0];
    assert_eq!(h.kind, HazardKind::Collision);
    assert_eq!(h.box_id, 2);
}

#[test]
fn boxes_in_a_train_do_not_collide() {
    let mut e = emu(1);
    e.place_box("entry", 400, BoxSize::Small);
    e.place_box("entry", 700, BoxSize::Small);
    e.step(Millis(3000), &outs(&["A0", "A1"]));
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
}

fn fault(trigger: Trigger, fault: FaultKind, duration_ms: Option<u64>) -> FaultSpec {
    FaultSpec {
        trigger,
        fault,
        duration_ms,
    }
}

#[test]
fn sensor_faults_change_the_sensors() {
    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::At(10),
        FaultKind::SensorStuckAt0("C4".into()),
        Some(100),
    ));
    e.schedule_fault(fault(
        Trigger::At(10),
        FaultKind::SensorStuckAt1("C5".into()),
        None,
    ));
    e.schedule_fault(fault(
        Trigger::At(300),
        FaultKind::SpuriousRise {
            sensor: "C3".into(),
            pulse_ms: 50,
        },
        None,
    ));
    e.schedule_fault(fault(
        Trigger::At(500),
        FaultKind::SpuriousFall {
            sensor: "C4".into(),
            pulse_ms: 30,
        },
        None,
    ));
    let off = outs(&[]);
    e.step(Millis(20), &off);
    assert!(!sensor(&e, "C4") && sensor(&e, "C5"));
    e.step(Millis(100), &off);
    assert!(sensor(&e, "C4"));
    e.step(Millis(200), &off);
    assert!(sensor(&e, "C3"));
    e.step(Millis(50), &off);
    assert!(!sensor(&e, "C3"));
    e.step(Millis(140), &off);
    assert!(!sensor(&e, "C4"));
    e.step(Millis(40), &off);
    assert!(sensor(&e, "C4"));
}

#[test]
fn actuator_faults_change_the_plant() {
    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::At(0),
        FaultKind::ActuatorStuckOff("A4".into()),
        Some(1000),
    ));
    e.step(Millis(500), &outs(&["A4"]));
    assert!(sensor(&e, "C4"));
    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::At(0),
        FaultKind::ActuatorStuckOn("A4".into()),
        None,
    ));
    e.step(Millis(500), &outs(&[]));
    assert!(!sensor(&e, "C4"));
}

#[test]
fn table_faults_block_the_rotation() {
    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::At(0),
        FaultKind::StuckAt {
            component: "table".into(),
            position: Position(0.0),
        },
        None,
    ));
    e.step(Millis(4000), &outs(&["A4"]));
    assert!(sensor(&e, "C4") && !sensor(&e, "C5"));

    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::At(3500),
        FaultKind::StuckAt {
            component: "table".into(),
            position: Position(90.0),
        },
        None,
    ));
    e.step(Millis(3500), &outs(&["A4"]));
    e.step(Millis(4000), &outs(&[]));
    assert!(sensor(&e, "C5") && !sensor(&e, "C4"));

    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::At(1000),
        FaultKind::Blocked("table".into()),
        Some(2000),
    ));
    e.step(Millis(2900), &outs(&["A4"]));
    assert!(!sensor(&e, "C4") && !sensor(&e, "C5"));
    assert_eq!(e.table_angle_mdeg() / 1000, 29);
    e.step(Millis(3000), &outs(&["A4"]));
    assert!(sensor(&e, "C5"));
}

#[test]
fn a_slowed_conveyor_takes_longer() {
    let time_to_c0 = |percent: Option<u8>| {
        let mut e = emu(1);
        if let Some(p) = percent {
            e.schedule_fault(fault(
                Trigger::At(0),
                FaultKind::ConveyorSlowed {
                    actuator: "A0".into(),
                    percent: p,
                },
                None,
            ));
        }
        e.place_box("entry", 500, BoxSize::Small);
        until(&mut e, &outs(&["A0", "A1"]), 10_000, |e| sensor(e, "C0")).expect("C0")
    };
    let (normal, slow) = (time_to_c0(None), time_to_c0(Some(50)));
    assert!(slow > normal * 19 / 10, "{normal} vs {slow}");
}

#[test]
fn condition_triggered_fault_starts_when_the_condition_holds() {
    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::When("RE(C0) . A0".into()),
        FaultKind::SensorStuckAt1("C9".into()),
        None,
    ));
    e.place_box("entry", 800, BoxSize::Small);
    let on = outs(&["A0", "A1"]);
    let c0 = until(&mut e, &on, 5000, |e| sensor(e, "C0")).expect("C0");
    assert!(!sensor(&e, "C9"));
    let c9 = until(&mut e, &on, 10, |e| sensor(e, "C9")).expect("C9");
    assert!(c9 - c0 <= 2, "{c0} {c9}");
}

#[test]
fn bad_faults_are_reported_not_panicked() {
    let mut e = emu(1);
    e.schedule_fault(fault(
        Trigger::At(0),
        FaultKind::SensorStuckAt0("C99".into()),
        None,
    ));
    e.schedule_fault(fault(
        Trigger::When("C3 . ".into()),
        FaultKind::Blocked("table".into()),
        None,
    ));
    e.schedule_fault(fault(
        Trigger::When("C3 . X7".into()),
        FaultKind::Blocked("table".into()),
        None,
    ));
    assert_eq!(e.fault_problems().len(), 3);
    assert!(e.fault_problems()[0].message.contains("C99"));
    assert!(e.fault_problems()[2].message.contains("X7"));
}

#[test]
fn faults_read_from_ron() {
    let text = r#"[
        (trigger: At(1200), fault: SensorStuckAt0("C4"), duration_ms: Some(500)),
        (trigger: When("C3 . /C4"), fault: ConveyorSlowed(actuator: "A1", percent: 50)),
        (trigger: At(0), fault: SpuriousRise(sensor: "C7", pulse_ms: 20)),
    ]"#;
    let faults: Vec<FaultSpec> = ron::from_str(text).expect("faults");
    assert_eq!(faults.len(), 3);
    assert_eq!(faults[1].duration_ms, None);
}

/// Runs `ms` with periodic arrivals and a crude controller; returns the sensor trace.
fn closed_loop(seed: u64, ms: u64) -> (Vec<String>, Vec<Hazard>, Vec<u64>) {
    let mut e = Station::new(&layout(), &plant(), seed);
    e.set_arrivals(ArrivalPlan::Periodic {
        period_ms: 3000,
        jitter_ms: 1500,
        mix: SizeMix::RandomLarge(50),
        count: None,
    });
    let mut trace = Vec::new();
    let mut created = Vec::new();
    let mut last = String::new();
    for t in 0..ms {
        // Conveyors always on, table toggling every 4 s: hazards are expected.
        let on = if (t / 4000) % 2 == 0 {
            outs(&["A0", "A1", "A5", "A6"])
        } else {
            outs(&["A0", "A1", "A4", "A3", "A6"])
        };
        let before = e.stats().created;
        e.step(Millis(1), &on);
        if e.stats().created > before {
            created.push(e.now().0);
        }
        let s = e.sensors().to_string();
        if s != last {
            trace.push(format!("{} {s}", e.now().0));
            last = s;
        }
    }
    (trace, e.hazards().to_vec(), created)
}

#[test]
fn same_seed_same_run_other_seed_other_arrivals() {
    let a = closed_loop(7, 30_000);
    let b = closed_loop(7, 30_000);
    assert_eq!(a, b);
    assert!(!a.1.is_empty());
    let c = closed_loop(8, 30_000);
    assert_ne!(a.2, c.2);
}

#[test]
fn ron_errors_carry_line_and_column() {
    let text = std::fs::read_to_string(crate::test_support::station_layout_file()).expect("read");
    let broken = text.replacen("step_ms: 1,", "step_ms: 1,\n    bogus: 3,", 1);
    let err = Layout::from_ron(&broken, Path::new("layout.ron")).expect_err("unknown field");
    let loc = err[0].location.clone().expect("location");
    assert_eq!((loc.line, loc.column > 1), (7, true), "{}", err[0]);
    let broken = text.replacen("width_mm: 450,", "width_mm: 450 450,", 1);
    let err = Layout::from_ron(&broken, Path::new("layout.ron")).expect_err("syntax");
    assert!(
        err[0].location.as_ref().is_some_and(|l| l.line > 5),
        "{}",
        err[0]
    );
}

#[test]
fn unknown_signal_or_part_is_a_clear_problem() {
    let text = std::fs::read_to_string(crate::test_support::station_layout_file()).expect("read");
    let broken = text.replace("actuator: \"A1\"", "actuator: \"A9\"");
    let l = Layout::from_ron(&broken, Path::new("layout.ron")).expect("parses");
    let p = Station::try_new(&l, &plant(), 1).err().expect("unknown A9");
    assert!(p.message.contains("`A9`"), "{p}");
    assert!(p.location.is_some_and(|l| l.line > 1));
    let broken = text.replace("part: \"table\"", "part: \"tabel\"");
    let err = Layout::from_ron(&broken, Path::new("layout.ron")).expect_err("unknown part");
    assert!(err[0].message.contains("tabel"), "{}", err[0]);
}

#[test]
fn hazards_serialise_with_snake_case_kinds() {
    let mut e = emu(1);
    e.place_box("entry", 1000, BoxSize::Small);
    e.step(Millis(1000), &outs(&["A0"]));
    let json = serde_json::to_string(e.hazards()).expect("json");
    assert!(json.contains("\"pushed_against_stopped\""), "{json}");
    assert!(
        serde_json::to_string(&e.stats())
            .expect("json")
            .contains("\"damaged\":1")
    );
}

#[test]
fn clones_project_forward_independently() {
    let mut e = emu(1);
    e.place_box("entry", 100, BoxSize::Large);
    let mut f = e.clone();
    f.step(Millis(1000), &outs(&["A0"]));
    assert_eq!(e.now(), Millis(0));
    assert!(f.boxes()[0].x_mm > e.boxes()[0].x_mm + 250.0);
}

/// Taking quiet steps at once gives exactly the plant that single steps give: same
/// sensors every PLC period, same boxes, same hazards, over a run with the reference
/// program's kind of traffic (random commands held for many periods).
#[test]
fn quiet_steps_change_nothing() {
    let (layout, plant) = (layout(), plant());
    let mut fast = Station::new(&layout, &plant, 5);
    let mut slow = Station::new(&layout, &plant, 5);
    slow.disable_quiet_steps();
    let mut rng = crate::synthetic::SplitMix64::new(9);
    let mut out = Bits::zeros(plant.outputs.len());
    for k in 0..30_000u64 {
        if rng.chance(1, 40) {
            let i = rng.below(plant.outputs.len() as u64) as usize;
            let v = out.get(i);
            out.set(i, !v);
        }
        fast.step(Millis(10), &out);
        slow.step(Millis(10), &out);
        assert_eq!(fast.sensors(), slow.sensors(), "period {k}");
        assert_eq!(fast.boxes(), slow.boxes(), "period {k}");
    }
    assert_eq!(fast.hazards(), slow.hazards());
    assert_eq!(fast.stats(), slow.stats());
    assert!(fast.stats().created > 10);
}

/// `push_tolerance_mm`: a box pushed against a stopped surface is damaged once the
/// driving surface has slid that far under it without a break (10 mm: 33 ms at
/// 300 mm/s), not at the first millimetre; a push broken off sooner damages nothing,
/// and the next push counts from zero.
#[test]
fn a_push_is_damage_once_the_belt_has_slid_the_tolerance() {
    let at_once = {
        let mut l = layout();
        l.push_tolerance_mm = 0;
        let mut e = Station::new(&l, &plant(), 1);
        e.set_arrivals(ArrivalPlan::Off);
        e.place_box("entry", 1000, BoxSize::Small);
        until(&mut e, &outs(&["A0"]), 3000, |e| !e.hazards().is_empty()).expect("hazard")
    };
    let mut l = layout();
    l.push_tolerance_mm = 10;
    let tolerant = |e: &mut Station| {
        e.place_box("entry", 1000, BoxSize::Small);
    };
    let mut e = Station::new(&l, &plant(), 1);
    e.set_arrivals(ArrivalPlan::Off);
    tolerant(&mut e);
    let later = until(&mut e, &outs(&["A0"]), 3000, |e| !e.hazards().is_empty()).expect("hazard");
    // 10 mm at 300 µm per ms: the 34th millisecond of sliding.
    assert_eq!(later - at_once, 33, "{at_once} → {later}");
    // Pushes of 20 ms with pauses: never 10 mm in one go.
    let mut e = Station::new(&l, &plant(), 1);
    e.set_arrivals(ArrivalPlan::Off);
    tolerant(&mut e);
    until(&mut e, &outs(&["A0"]), 3000, |e| e.boxes()[0].x_mm > 1055.0).expect("straddles");
    for _ in 0..20 {
        e.step(Millis(20), &outs(&["A0"]));
        e.step(Millis(20), &outs(&[]));
    }
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
    let mut bad = l.clone();
    bad.push_tolerance_mm = -1;
    assert_eq!(bad.check().len(), 1, "a negative tolerance is refused");
}

/// A plant with a safety valve on the turntable's air and a safety contactor on the
/// drives (`supplies` in `plant.ron`): without its supply the table stays where it is
/// (it does not return as a released monostable valve would), the drives stop
/// whatever their own output, and the safety devices are actuators a fault can weld or
/// kill, mirrored by their contacts.
#[test]
fn supplies_freeze_the_table_stop_the_drives_and_can_fail() {
    let dir = crate::test_support::edm_station("edm-emulator");
    let path = dir.join("plant.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let p = Plant::from_ron(&text.replacen("\nPlant(", "\n(", 1), &path).expect("plant");
    let l = Layout::load(&crate::test_support::station_layout_file()).expect("layout");
    let on = |names: &[&str]| {
        let mut b = Bits::zeros(p.outputs.len());
        for a in names {
            b.set(p.output(a).expect("actuator"), true);
        }
        b
    };
    let mut e = Station::new(&l, &p, 1);
    e.set_arrivals(ArrivalPlan::Off);
    assert!(e.actuators().iter().any(|a| a == "KM0") && e.actuators().iter().any(|a| a == "YV0"));
    e.step(Millis(1500), &on(&["A4", "YV0", "KM0"]));
    let half = e.table_angle_mdeg();
    assert!((40_000..50_000).contains(&half), "{half}");
    for out in [on(&["A4", "KM0"]), on(&["KM0"])] {
        e.step(Millis(2000), &out);
        assert_eq!(e.table_angle_mdeg(), half, "frozen without its air");
    }
    e.step(Millis(4000), &on(&["YV0", "KM0"]));
    assert_eq!(e.table_angle_mdeg(), 0, "back with its air");
    // The drives stop without KM0, and a dead KM0 stops them although it is commanded.
    e.place_box("entry", 100, BoxSize::Small);
    let x0 = e.boxes()[0].x_mm;
    e.step(Millis(500), &on(&["A0", "YV0"]));
    assert!((e.boxes()[0].x_mm - x0).abs() < 0.5, "no supply, no motion");
    let fb = p.input("KM0_fb").unwrap();
    e.step(Millis(10), &on(&["A0", "KM0", "YV0"]));
    assert!(e.sensors().get(fb), "KM0's mirror shows it closed");
    e.schedule_fault(fault(
        Trigger::At(0),
        FaultKind::ActuatorStuckOff("KM0".into()),
        None,
    ));
    let x1 = e.boxes()[0].x_mm;
    e.step(Millis(500), &on(&["A0", "KM0", "YV0"]));
    assert!((e.boxes()[0].x_mm - x1).abs() < 0.5, "KM0 dead: no motion");
    assert!(!e.sensors().get(fb), "KM0's mirror shows it open");
}
