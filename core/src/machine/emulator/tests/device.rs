//! Detectors and fieldbus links inside the emulator.

use super::*;
use crate::emulator::{FaultKind, FaultSpec, Trigger};
use crate::plant::{Signal, SignalKind};
use std::path::Path;

/// A detector on `p . k` with a 100 ms on-delay and 20 ms off-delay; a link copying it
/// every 50 ms from 10 ms.
const DEVICES: &str = r#"Components(
    name: "devices",
    components: [
        (id: "relay", name: "Relay", kind: Detector((signal: "d", when: "p . K", on_delay_ms: 100, off_delay_ms: 20))),
        (id: "bus", name: "Bus", kind: Link((from: "d", to: "img", period_ms: 50, phase_ms: 10))),
    ],
)"#;

fn emulator() -> ComponentPlant {
    let plant = Plant {
        name: "devices".into(),
        description: String::new(),
        inputs: ["p", "d", "img"]
            .iter()
            .map(|s| Signal::new(*s, SignalKind::Sensor, *s))
            .collect(),
        outputs: vec![Signal::new("K", SignalKind::Actuator, "K")],
    };
    let c = Components::from_ron(DEVICES, Path::new("components.ron")).unwrap();
    ComponentPlant::new(&c, &plant, 1).unwrap()
}

/// Runs 1 ms steps with K = `k` until `until_ms`; the times `input` changed.
fn trace(e: &mut ComponentPlant, k: bool, input: usize, until_ms: u64) -> Vec<(u64, bool)> {
    let mut o = Bits::zeros(1);
    o.set(0, k);
    let mut last = e.sensors().get(input);
    let mut out = Vec::new();
    while e.now().0 < until_ms {
        e.step(Millis(1), &o);
        let v = e.sensors().get(input);
        if v != last {
            out.push((e.now().0, v));
            last = v;
        }
    }
    out
}

fn perturb(e: &mut ComponentPlant, at: u64, ms: u64) {
    e.try_schedule_fault(FaultSpec {
        trigger: Trigger::At(at),
        fault: FaultKind::SensorStuckAt1("p".into()),
        duration_ms: Some(ms),
    })
    .unwrap();
}

#[test]
fn a_detector_confirms_after_its_delay_and_an_environment_input_returns_to_zero() {
    let mut e = emulator();
    perturb(&mut e, 40, 300);
    let p = trace(&mut e.clone(), true, 0, 500);
    assert_eq!(p, vec![(40, true), (340, false)], "the perturbation ends");
    let d = trace(&mut e, true, 1, 500);
    // On 100 ms after p rose, off 20 ms after it fell.
    assert_eq!(d, vec![(140, true), (360, false)]);
}

#[test]
fn a_detector_waits_for_its_whole_condition() {
    let mut e = emulator();
    perturb(&mut e, 40, 300);
    assert!(
        trace(&mut e, false, 1, 500).is_empty(),
        "K off: no fault current"
    );
}

#[test]
fn a_link_delivers_at_poll_instants_and_an_unconfirmed_perturbation_carries_nothing() {
    let mut e = emulator();
    perturb(&mut e, 40, 300);
    // d on [140, 360): polls at 10, 60, 110, 160, ...: img on at 160; the poll at 360
    // reads d as the step before left it (still on): off at 410.
    assert_eq!(trace(&mut e, true, 2, 600), vec![(160, true), (410, false)]);
    // A perturbation shorter than the relay's on-delay never confirms: nothing to carry.
    let mut e = emulator();
    perturb(&mut e, 40, 30);
    assert!(trace(&mut e, true, 2, 600).is_empty());
}

#[test]
fn a_slowed_link_polls_at_half_the_rate_and_a_blocked_one_freezes() {
    let mut e = emulator();
    e.try_schedule_fault(FaultSpec {
        trigger: Trigger::At(0),
        fault: FaultKind::Slowed {
            component: "bus".into(),
            percent: 50,
        },
        duration_ms: None,
    })
    .unwrap();
    perturb(&mut e, 40, 300);
    // Polls at 10, 110, 210, ...: d on at 140 is delivered at 210, off at 360 at 410.
    assert_eq!(trace(&mut e, true, 2, 600), vec![(210, true), (410, false)]);
    let mut e = emulator();
    e.try_schedule_fault(FaultSpec {
        trigger: Trigger::At(200),
        fault: FaultKind::Blocked("bus".into()),
        duration_ms: None,
    })
    .unwrap();
    perturb(&mut e, 40, 300);
    assert_eq!(trace(&mut e, true, 2, 600), vec![(160, true)], "frozen on");
}
