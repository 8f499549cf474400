use super::*;
use crate::emulator::Trigger;
use crate::plant::{Signal, SignalKind};
use std::path::Path;

/// The drilling head of seed 003 on its own: h, b1, b2, b3 and three drives.
const HEAD: &str = r#"Components(
    name: "drill",
    components: [
        (id: "head", name: "Drill head", kind: Axis((
            min: 0.0, max: 210.0, start: 0.0, end_stops: (max: Crash), variation_ppm: 10000,
            drives: [
                (when: "DGV", speed: 100.0),
                (when: "DPV", speed: 10.0),
                (when: "MGV", speed: -100.0),
            ],
            sensors: [
                (signal: "h", from: 0.0, to: 2.0),
                (signal: "b1", from: 98.0, to: 102.0),
                (signal: "b2", from: 148.0, to: 152.0),
                (signal: "b3", from: 198.0, to: 202.0),
            ],
        ))),
    ],
    dangers: [
        (id: "fast_in_part", text: "the bit enters the part at full speed",
         component: "head", from: 105.0, to: 210.0, when: "DGV"),
    ],
)"#;

fn plant() -> Plant {
    let s = |id: &str| Signal::new(id, SignalKind::Sensor, id);
    let a = |id: &str| Signal::new(id, SignalKind::Actuator, id);
    Plant {
        name: "drill".into(),
        description: String::new(),
        inputs: vec![s("h"), s("b1"), s("b2"), s("b3")],
        outputs: vec![a("DGV"), a("DPV"), a("MGV")],
    }
}

fn emulator(seed: u64) -> ComponentPlant {
    let c = Components::from_ron(HEAD, Path::new("components.ron")).unwrap();
    ComponentPlant::new(&c, &plant(), seed).unwrap()
}

fn out(dgv: bool, dpv: bool, mgv: bool) -> Bits {
    let mut b = Bits::zeros(3);
    b.set(0, dgv);
    b.set(1, dpv);
    b.set(2, mgv);
    b
}

/// Runs 10 ms cycles with `o` until sensor `i` is on (at most `max_ms`); the time.
fn until(e: &mut ComponentPlant, o: &Bits, i: usize, max_ms: u64) -> Option<u64> {
    let end = e.now().0 + max_ms;
    while e.now().0 < end {
        e.step(Millis(10), o);
        if e.sensors().get(i) {
            return Some(e.now().0);
        }
    }
    None
}

#[test]
fn the_fault_free_drilling_cycle_reaches_each_position_in_time() {
    let mut e = emulator(1);
    assert!(e.sensors().get(0), "starts at h");
    let t0 = e.now().0;
    let t = until(&mut e, &out(true, false, false), 1, 2000).unwrap();
    assert!((950..=1000).contains(&(t - t0)), "h -> b1 in {} ms", t - t0);
    let t0 = t;
    let t = until(&mut e, &out(false, true, false), 2, 8000).unwrap();
    assert!(
        (4400..=5200).contains(&(t - t0)),
        "b1 -> b2 in {} ms",
        t - t0
    );
    let t = until(&mut e, &out(false, false, true), 1, 2000).unwrap();
    let t = until(&mut e, &out(false, true, false), 3, 12_000).unwrap() - t;
    assert!(t > 9000, "b1 -> b3 slowly: {t} ms");
    until(&mut e, &out(false, false, true), 0, 4000).unwrap();
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
}

#[test]
fn a_drive_into_the_fixture_and_both_ways_at_once_are_hazards() {
    let mut e = emulator(2);
    until(&mut e, &out(false, false, true), 3, 300)
        .ok_or(())
        .unwrap_err();
    assert!(e.hazards().is_empty(), "resting at the top end is no crash");
    e.step(Millis(10), &out(true, false, true));
    assert_eq!(e.hazards().len(), 1);
    assert_eq!(e.hazards()[0].kind, HazardKind::OpposedDrives);
    assert_eq!(e.hazards()[0].elements, ["DGV", "MGV"]);
    // Held both ways it does not move, and the hazard is reported once.
    let p = e.position("head").unwrap();
    e.step(Millis(100), &out(true, false, true));
    assert_eq!(e.position("head").unwrap(), p);
    assert_eq!(e.hazards().len(), 1);
    // Slow descent to the fixture: the full depth, then the crash.
    e.step(Millis(25_000), &out(false, true, false));
    let kinds: Vec<_> = e.hazards().iter().map(|h| h.kind).collect();
    assert_eq!(kinds, [HazardKind::OpposedDrives, HazardKind::EndStop]);
    assert_eq!(e.position("head"), Some(210.0));
}

#[test]
fn a_declared_danger_is_reported_once_per_onset() {
    let mut e = emulator(3);
    e.step(Millis(1500), &out(true, false, false));
    assert_eq!(e.hazards().len(), 1, "{:?}", e.hazards());
    let h = &e.hazards()[0];
    assert_eq!(h.kind, HazardKind::Declared);
    assert_eq!(
        h.at,
        Place::Danger {
            part: "head".into(),
            danger: "fast_in_part".into()
        }
    );
    e.step(Millis(100), &out(true, false, false));
    assert_eq!(e.hazards().len(), 1);
}

#[test]
fn faults_act_on_signals_and_on_the_component() {
    let mut e = emulator(4);
    let spec = |fault| FaultSpec {
        trigger: Trigger::At(0),
        fault,
        duration_ms: None,
    };
    e.try_schedule_fault(spec(FaultKind::Blocked("head".into())))
        .unwrap();
    e.step(Millis(2000), &out(true, false, false));
    assert_eq!(e.position("head"), Some(0.0), "blocked");
    assert_eq!(e.repair_faults(), 1);
    e.try_schedule_fault(spec(FaultKind::SensorStuckAt0("b1".into())))
        .unwrap();
    assert!(until(&mut e, &out(true, false, false), 1, 1500).is_none());
    e.try_schedule_fault(spec(FaultKind::ActuatorStuckOff("MGV".into())))
        .unwrap();
    let p = e.position("head").unwrap();
    e.step(Millis(500), &out(false, false, true));
    assert_eq!(e.position("head").unwrap(), p, "MGV dead");
    let err = e
        .try_schedule_fault(spec(FaultKind::Blocked("lift".into())))
        .unwrap_err();
    assert_eq!(err.code, codes::FAULT_UNKNOWN_COMPONENT.id);
    // Only a component with positions can be stuck at one: the head can.
    let err = e
        .try_schedule_fault(spec(FaultKind::StuckAt {
            component: "lift".into(),
            position: crate::emulator::Position(0.0),
        }))
        .unwrap_err();
    assert_eq!(err.code, codes::FAULT_UNKNOWN_COMPONENT.id);
    assert!(err.message.contains("cannot stop at 0"), "{err:?}");
    e.try_schedule_fault(spec(FaultKind::StuckAt {
        component: "head".into(),
        position: crate::emulator::Position(p),
    }))
    .unwrap();
    e.step(Millis(500), &out(true, false, false));
    assert_eq!(e.position("head").unwrap(), p, "stuck where it is");
}

#[test]
fn a_slowed_head_takes_longer_and_a_seed_fixes_every_run() {
    let run = |seed: u64, slowed: bool| {
        let mut e = emulator(seed);
        if slowed {
            e.try_schedule_fault(FaultSpec {
                trigger: Trigger::At(0),
                fault: FaultKind::Slowed {
                    component: "head".into(),
                    percent: 50,
                },
                duration_ms: None,
            })
            .unwrap();
        }
        until(&mut e, &out(true, false, false), 1, 5000).unwrap()
    };
    assert_eq!(run(7, false), run(7, false));
    assert!(run(7, true) > 1900, "{}", run(7, true));
    let times: std::collections::BTreeSet<_> = (0..20).map(|s| run(s, false)).collect();
    assert!(times.len() > 1, "the speed varies with the seed: {times:?}");
}

#[test]
fn the_derived_actions_are_the_papers_and_the_emulator_meets_them() {
    let e = emulator(0);
    let a = e.derived_actions();
    let n1 = a.iter().find(|x| x.id == "head_h_DGV_b1").unwrap();
    // Over many seeds, each h -> b1 lies in [T - ΔT, T + ΔT] (10 ms cycles).
    for seed in 0..50 {
        let mut e = emulator(seed);
        let t = until(&mut e, &out(true, false, false), 1, 5000).unwrap();
        assert!(
            t + 10 >= n1.t_ms - n1.dt_ms && t <= n1.t_ms + n1.dt_ms + 10,
            "seed {seed}: {t} ms against {} ± {}",
            n1.t_ms,
            n1.dt_ms
        );
    }
}

/// A tank with a filling pump and valve, a draining pump, level and flow sensors.
const TANK: &str = r#"Components(
    name: "tank",
    components: [
        (id: "tank1", name: "Tank 1", kind: Tank((
            capacity: 100.0, start: 5.0, overflow: Crash, dry_run: Crash,
            flows: [
                (when: "M1 . V1", rate: 25.0, sensor: Some("C1")),
                (when: "M2", rate: -20.0, sensor: Some("C2")),
            ],
            sensors: [(signal: "b1", from: 0.0, to: 8.0), (signal: "h1", from: 92.0, to: 100.0)],
        ))),
    ],
)"#;

fn tank_plant() -> Plant {
    let s = |id: &str| Signal::new(id, SignalKind::Sensor, id);
    let a = |id: &str| Signal::new(id, SignalKind::Actuator, id);
    Plant {
        name: "tank".into(),
        description: String::new(),
        inputs: vec![s("b1"), s("h1"), s("C1"), s("C2")],
        outputs: vec![a("M1"), a("V1"), a("M2")],
    }
}

fn tank() -> ComponentPlant {
    let c = Components::from_ron(TANK, Path::new("components.ron")).unwrap();
    ComponentPlant::new(&c, &tank_plant(), 1).unwrap()
}

fn pumps(m1: bool, v1: bool, m2: bool) -> Bits {
    let mut b = Bits::zeros(3);
    b.set(0, m1);
    b.set(1, v1);
    b.set(2, m2);
    b
}

#[test]
fn a_tank_fills_and_empties_at_its_flows_rates_with_its_flow_sensors() {
    let mut e = tank();
    assert!(e.sensors().get(0) && !e.sensors().get(1), "starts low");
    // A pump without its valve moves nothing, and its flow sensor stays off.
    e.step(Millis(1000), &pumps(true, false, false));
    assert_eq!(e.position("tank1"), Some(5.0));
    assert!(!e.sensors().get(2));
    // 25 l/s: from 5 l to 92 l (h1) in 3.48 s.
    let t = until(&mut e, &pumps(true, true, false), 1, 5000).unwrap();
    assert!((4470..=4490).contains(&t), "{t}");
    assert!(e.sensors().get(2) && !e.sensors().get(3));
    // Both flows: 5 l/s net.
    e.step(Millis(1000), &pumps(true, true, true));
    let l = e.position("tank1").unwrap();
    assert!((96.9..97.4).contains(&l), "{l}");
    assert!(e.sensors().get(2) && e.sensors().get(3));
    let t0 = e.now().0;
    let t = until(&mut e, &pumps(false, false, true), 0, 6000).unwrap();
    assert!((4450..=4470).contains(&(t - t0)), "{}", t - t0);
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
}

#[test]
fn a_full_tank_spills_and_an_empty_one_runs_its_pump_dry() {
    let mut e = tank();
    e.step(Millis(5000), &pumps(true, true, false));
    assert_eq!(e.position("tank1"), Some(100.0));
    assert_eq!(e.hazards().len(), 1);
    assert_eq!(e.hazards()[0].kind, HazardKind::Overflow);
    assert_eq!(e.hazards()[0].elements, ["M1", "V1"]);
    assert!(!e.sensors().get(2), "no flow into a full tank");
    e.step(Millis(6000), &pumps(false, false, true));
    assert_eq!(e.position("tank1"), Some(0.0));
    assert_eq!(e.hazards()[1].kind, HazardKind::DryRun);
    assert!(!e.sensors().get(3), "no flow out of an empty tank");
    assert_eq!(e.hazards().len(), 2, "each reported once per onset");
}

#[test]
fn a_blocked_pipe_stops_every_flow_and_its_sensors_say_so() {
    let mut e = tank();
    e.step(Millis(1000), &pumps(true, true, false));
    e.try_schedule_fault(FaultSpec {
        trigger: Trigger::At(0),
        fault: FaultKind::Blocked("tank1".into()),
        duration_ms: Some(2000),
    })
    .unwrap();
    let level = e.position("tank1").unwrap();
    e.step(Millis(1000), &pumps(true, true, false));
    assert_eq!(e.position("tank1").unwrap(), level);
    assert!(!e.sensors().get(2), "the flow sensor sees the blockage");
    e.step(Millis(1500), &pumps(true, true, false));
    assert!(
        e.position("tank1").unwrap() > level,
        "resumes when it clears"
    );
    assert!(e.sensors().get(2));
}

#[test]
fn a_tanks_elementary_actions_are_derived_from_its_levels_and_flows() {
    let a = tank().derived_actions();
    let fill = a.iter().find(|x| x.id == "tank1_b1_M1_V1_h1").unwrap();
    // From anywhere in [0, 8] l to 92 l at 25 l/s: 3.36 s to 3.68 s.
    assert_eq!((fill.t_ms, fill.dt_ms), (3520, 160));
    assert!(
        a.iter()
            .any(|x| x.initial == "h1" && x.command == "M2" && x.final_state == "b1")
    );
}

/// The emulator skips the rest of a period when every component is at rest, and
/// steps once per period what nothing reads within it: the plant is the same as when
/// it is stepped one millisecond at a time, on random commands, faults included.
#[test]
fn periods_and_single_steps_give_the_same_plant() {
    let mut rng = crate::synthetic::SplitMix64::new(9);
    for seed in 0..20 {
        let (mut a, mut b) = (emulator(seed), emulator(seed));
        let fault = FaultSpec {
            trigger: Trigger::At(3000),
            fault: FaultKind::Blocked("head".into()),
            duration_ms: Some(700),
        };
        a.try_schedule_fault(fault.clone()).unwrap();
        b.try_schedule_fault(fault).unwrap();
        for _ in 0..600 {
            let o = out(rng.chance(1, 3), rng.chance(1, 3), rng.chance(1, 4));
            a.step(Millis(10), &o);
            for _ in 0..10 {
                b.step(Millis(1), &o);
            }
            assert_eq!(a.sensors(), b.sensors(), "seed {seed}");
            assert_eq!(a.position("head"), b.position("head"), "seed {seed}");
        }
        assert_eq!(a.hazards(), b.hazards(), "seed {seed}");
    }
}
