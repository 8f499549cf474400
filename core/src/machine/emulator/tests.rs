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
    let err = e
        .try_schedule_fault(spec(FaultKind::TableBlockedAtC4))
        .unwrap_err();
    assert_eq!(err.code, codes::FAULT_UNKNOWN_COMPONENT.id);
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
    let n1 = a.iter().find(|x| x.id == "head.h.DGV.b1").unwrap();
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
