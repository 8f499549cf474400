//! The conveyor kind inside the emulator: items fed, carried, queued, seen by beams,
//! taken, handed over to the next conveyor, dropped; faults on the belt.

use super::*;
use crate::emulator::Trigger;
use crate::plant::{Signal, SignalKind};
use std::path::Path;

/// A pusher feeds pallets (P) onto belt 1 (C1), which hands them to belt 2 (C2); belt 2
/// ends on an end stop where a robot takes them (R). Beams: b1 at the middle of belt 1,
/// tall at its end (tall items only), b2 at the end of belt 2; m1, belt 1 moving.
const LINE: &str = r#"Components(
    name: "line",
    components: [
        (id: "belt1", name: "Belt 1", kind: Conveyor((
            length: 1000.0,
            drives: [(when: "C1", speed: 250.0), (when: "B1", speed: -250.0)],
            sensors: [(signal: "b1", at: 500.0), (signal: "tall", at: 990.0, sees: Some("tall"))],
            motion: Some("m1"),
            feed: Some((when: "P", items: [
                (class: "low", length: 100.0),
                (class: "high", length: 100.0, tags: ["tall"]),
            ])),
            exit: To("belt2"),
        ))),
        (id: "belt2", name: "Belt 2", kind: Conveyor((
            length: 600.0,
            drives: [(when: "C2", speed: 300.0)],
            sensors: [(signal: "b2", at: 590.0)],
            take: Some("R"),
        ))),
    ],
)"#;

const OUT: [&str; 5] = ["P", "C1", "B1", "C2", "R"];
const IN: [&str; 5] = ["b1", "tall", "m1", "b2", "spare"];

fn plant() -> Plant {
    Plant {
        name: "line".into(),
        description: String::new(),
        inputs: IN
            .iter()
            .map(|s| Signal::new(*s, SignalKind::Sensor, *s))
            .collect(),
        outputs: OUT
            .iter()
            .map(|s| Signal::new(*s, SignalKind::Actuator, *s))
            .collect(),
    }
}

fn line(text: &str) -> ComponentPlant {
    let c = Components::from_ron(text, Path::new("components.ron")).unwrap();
    ComponentPlant::new(&c, &plant(), 1).unwrap()
}

fn out(on: &[&str]) -> Bits {
    let mut b = Bits::zeros(OUT.len());
    for o in on {
        b.set(OUT.iter().position(|x| x == o).unwrap(), true);
    }
    b
}

fn sensor(e: &ComponentPlant, s: &str) -> bool {
    e.sensors().get(IN.iter().position(|x| *x == s).unwrap())
}

/// 10 ms cycles with `o` for `ms`.
fn run(e: &mut ComponentPlant, o: &Bits, ms: u64) {
    for _ in 0..ms / 10 {
        e.step(Millis(10), o);
    }
}

/// 10 ms cycles with `o` until sensor `s` reads `v` (at most `max_ms`); the time.
fn until(e: &mut ComponentPlant, o: &Bits, s: &str, v: bool, max_ms: u64) -> Option<u64> {
    let end = e.now().0 + max_ms;
    while e.now().0 < end {
        e.step(Millis(10), o);
        if sensor(e, s) == v {
            return Some(e.now().0);
        }
    }
    None
}

/// An item on a belt as the tests see it: lengths in millionths.
#[derive(Debug)]
struct Seen {
    rear: i64,
    length: i64,
}

/// The items whose centre is on component `k`'s belt, entry first.
fn belt(e: &ComponentPlant, k: usize) -> Vec<Seen> {
    let s = e.surface_of[k].expect("a conveyor");
    e.items
        .on(s)
        .into_iter()
        .map(|b| Seen {
            rear: b.c - b.half,
            length: 2 * b.half,
        })
        .collect()
}

#[test]
fn a_fed_pallet_crosses_the_beams_at_the_belts_speed_and_waits_at_the_end_stop() {
    let mut e = line(LINE);
    run(&mut e, &out(&["P"]), 10);
    assert_eq!(e.items_in(), 1);
    run(&mut e, &out(&[]), 10);
    // Belt 1 at 250 mm/s: its front (100 mm) reaches b1 (500 mm) after 1.6 s.
    let t0 = e.now().0;
    let t = until(&mut e, &out(&["C1", "C2"]), "b1", true, 5_000).unwrap();
    assert!((1_590..=1_610).contains(&(t - t0)), "{}", t - t0);
    assert!(sensor(&e, "m1"));
    // A low pallet: the high beam never sees it; it passes to belt 2 and stops at its end.
    let t = until(&mut e, &out(&["C1", "C2"]), "b2", true, 10_000).unwrap();
    assert!(t > 0 && !sensor(&e, "tall"));
    run(&mut e, &out(&["C1", "C2"]), 2_000);
    let items = belt(&e, 1);
    assert_eq!(items.len(), 1);
    assert_eq!(items[0].rear, 500_000_000, "against the end stop");
    assert!(sensor(&e, "b2"));
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
    // The robot takes it.
    run(&mut e, &out(&["R"]), 10);
    assert_eq!(e.items_out(), 1);
    assert!(
        !sensor(&e, "b2") || {
            run(&mut e, &out(&[]), 10);
            !sensor(&e, "b2")
        }
    );
}

#[test]
fn the_high_beam_sees_only_tall_items() {
    let mut e = line(LINE);
    // Two pallets: low then tall, 400 mm apart.
    run(&mut e, &out(&["P"]), 10);
    run(&mut e, &out(&["C1"]), 1_600);
    run(&mut e, &out(&["P", "C1"]), 10);
    let mut seen_tall = false;
    for _ in 0..600 {
        e.step(Millis(10), &out(&["C1", "C2"]));
        seen_tall |= sensor(&e, "tall");
    }
    assert!(seen_tall);
    assert_eq!(e.items_in(), 2);
}

#[test]
fn items_queue_behind_a_waiting_one_and_a_full_next_belt_holds_them() {
    let text = LINE.replace(
        "name: \"line\",",
        "name: \"line\", items: (push_tolerance: 2000.0),",
    );
    let mut e = line(&text);
    // Three pallets fed 500 ms apart while belt 1 runs and belt 2 stands: the first
    // crosses onto belt 2 until it lies on belt 1 by the straddle margin only (25 mm)
    // and stays there, belt 2 stopped; the next wait behind it, queued without
    // overlapping, on an accumulating belt without harm.
    for _ in 0..3 {
        run(&mut e, &out(&["P", "C1"]), 10);
        run(&mut e, &out(&["C1"]), 500);
    }
    run(&mut e, &out(&["C1"]), 10_000);
    let b1 = belt(&e, 0);
    let b2 = belt(&e, 1);
    assert_eq!(b2.len(), 1, "{b2:?}");
    assert_eq!(b2[0].rear, -25_000_000, "25 mm still on belt 1: {b2:?}");
    assert_eq!(b1.len(), 2, "{b1:?}");
    assert_eq!(b1[1].rear + b1[1].length, 975_000_000, "behind it");
    assert!(
        b1[0].rear + b1[0].length <= b1[1].rear,
        "no overlap: {b1:?}"
    );
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
}

#[test]
fn a_belt_pushing_an_item_onto_a_stopped_one_damages_it_past_the_push_tolerance() {
    // Without a tolerance, as soon as the item lies on both by more than the margin.
    let mut e = line(LINE);
    run(&mut e, &out(&["P", "C1"]), 10);
    run(&mut e, &out(&["C1"]), 5_000);
    let h = e.hazards();
    assert_eq!(h.len(), 1, "{h:?}");
    assert_eq!(h[0].kind, HazardKind::PushedAgainstStopped);
    assert_eq!(h[0].elements, vec!["B1", "C1", "C2"]);
    // Both belts running, none.
    let mut e = line(LINE);
    run(&mut e, &out(&["P", "C1", "C2"]), 10);
    run(&mut e, &out(&["C1", "C2"]), 5_000);
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
    assert_eq!(belt(&e, 1).len(), 1);
}

#[test]
fn a_feed_onto_an_occupied_entry_is_a_collision() {
    let mut e = line(LINE);
    run(&mut e, &out(&["P"]), 10);
    run(&mut e, &out(&[]), 10);
    run(&mut e, &out(&["P"]), 10);
    assert_eq!(e.items_in(), 1);
    assert_eq!(e.hazards().len(), 1);
    assert_eq!(e.hazards()[0].kind, HazardKind::Collision);
    assert_eq!(e.hazards()[0].elements, vec!["P".to_string()]);
}

#[test]
fn a_belt_with_nothing_after_its_end_drops_the_item() {
    let text = LINE.replace("exit: To(\"belt2\")", "exit: Drop");
    let mut e = line(&text);
    run(&mut e, &out(&["P"]), 10);
    run(&mut e, &out(&["C1"]), 5_000);
    assert_eq!(e.hazards().len(), 1, "{:?}", e.hazards());
    assert_eq!(e.hazards()[0].kind, HazardKind::Dropped);
    assert!(belt(&e, 0).is_empty());
}

#[test]
fn a_sink_delivers_and_both_directions_at_once_are_a_hazard() {
    let text = LINE.replace("exit: To(\"belt2\")", "exit: Sink");
    let mut e = line(&text);
    run(&mut e, &out(&["P"]), 10);
    run(&mut e, &out(&["C1"]), 5_000);
    assert_eq!(e.items_out(), 1);
    assert!(e.hazards().is_empty());
    run(&mut e, &out(&["C1", "B1"]), 100);
    assert_eq!(e.hazards().len(), 1);
    assert_eq!(e.hazards()[0].kind, HazardKind::OpposedDrives);
    assert!(!sensor(&e, "m1"), "held: not moving");
}

#[test]
fn a_blocked_belt_stops_its_items_and_its_motion_sensor_falls() {
    let mut e = line(LINE);
    e.try_schedule_fault(crate::emulator::FaultSpec {
        trigger: Trigger::At(500),
        fault: crate::emulator::FaultKind::Blocked("belt1".into()),
        duration_ms: Some(1_000),
    })
    .unwrap();
    run(&mut e, &out(&["P"]), 10);
    run(&mut e, &out(&["C1"]), 480);
    assert!(sensor(&e, "m1"));
    run(&mut e, &out(&["C1"]), 100);
    assert!(!sensor(&e, "m1"), "blocked");
    let before = belt(&e, 0)[0].rear;
    run(&mut e, &out(&["C1"]), 500);
    assert_eq!(belt(&e, 0)[0].rear, before);
    run(&mut e, &out(&["C1"]), 1_000);
    assert!(sensor(&e, "m1"), "moves again after the fault");
    assert!(belt(&e, 0)[0].rear > before);
}

#[test]
fn backwards_items_stop_at_the_entry() {
    let mut e = line(LINE);
    run(&mut e, &out(&["P"]), 10);
    run(&mut e, &out(&["C1"]), 1_000);
    run(&mut e, &out(&["B1"]), 3_000);
    assert_eq!(belt(&e, 0)[0].rear, 0);
    assert!(e.hazards().is_empty());
}

#[test]
fn an_exit_to_a_missing_or_non_conveyor_component_is_an_error_with_its_place() {
    let text = LINE.replace("exit: To(\"belt2\")", "exit: To(\"belt9\")");
    let p = Components::from_ron(&text, Path::new("components.ron")).unwrap_err();
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].message.contains("belt9"), "{p:?}");
    assert!(p[0].location.as_ref().is_some_and(|l| l.line > 1), "{p:?}");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Whatever the commands (feeds, both directions, robot grips at any time, in
    /// bursts of any length): on every belt the items stay in order, never overlap,
    /// their centre stays on the belt (an item may overhang the joint between the
    /// belts), and none is lost or made (fed = on the belts + taken).
    #[test]
    fn items_never_overlap_and_none_is_lost(
        commands in proptest::collection::vec((0u8..32, 1u64..40), 1..120),
        seed in 0u64..1000,
    ) {
        let c = Components::from_ron(LINE, Path::new("components.ron")).unwrap();
        let mut e = ComponentPlant::new(&c, &plant(), seed).unwrap();
        for (mask, cycles) in commands {
            let mut o = Bits::zeros(OUT.len());
            for (k, _) in OUT.iter().enumerate() {
                o.set(k, mask >> k & 1 == 1);
            }
            for _ in 0..cycles {
                e.step(Millis(10), &o);
                let mut on_belts = 0;
                for k in 0..2 {
                    let b = belt(&e, k);
                    let items = &b;
                    on_belts += items.len() as u32;
                    let len = if k == 0 { 1_000_000_000 } else { 600_000_000 };
                    for w in items.windows(2) {
                        proptest::prop_assert!(w[0].rear + w[0].length <= w[1].rear, "{:?}", items);
                    }
                    for i in items {
                        let c = i.rear + i.length / 2;
                        proptest::prop_assert!((0..=len).contains(&c), "{:?}", i);
                        if k == 0 {
                            proptest::prop_assert!(i.rear >= 0, "the entry is a stop: {:?}", i);
                        } else {
                            proptest::prop_assert!(i.rear + i.length <= len, "an end stop: {:?}", i);
                        }
                    }
                }
                proptest::prop_assert_eq!(e.items_in(), on_belts + e.items_out());
            }
        }
    }
}

/// A gripper carries the item it takes off belt 2's end to belt 3's entry (`feed.from`):
/// the very item, class and number kept, is put down; a carried item is not counted out;
/// placing with nothing held places nothing.
#[test]
fn a_carried_item_keeps_its_class_and_is_counted_once() {
    let text = LINE.replace(
        "            take: Some(\"R\"),\n        ))),",
        "            take: Some(\"R\"),\n        ))),\n        (id: \"belt3\", name: \"Belt 3\", kind: Conveyor((\n            length: 600.0,\n            drives: [(when: \"C2\", speed: 300.0)],\n            feed: Some((when: \"B1\", from: Some(\"belt2\"))),\n            exit: Sink,\n        ))),",
    );
    assert_ne!(text, LINE);
    let mut e = line(&text);
    let items = |e: &ComponentPlant, id: &str| -> Vec<(u32, String)> {
        e.scene()
            .elements
            .iter()
            .filter(|x| x.id == id)
            .flat_map(|x| match &x.shape {
                crate::machine::Shape::Conveyor { items, .. } => {
                    items.iter().map(|i| (i.id, i.class.clone())).collect()
                }
                _ => Vec::new(),
            })
            .collect()
    };
    // Two items: "low" then "high".
    for _ in 0..2 {
        run(&mut e, &out(&["P"]), 20);
        run(&mut e, &out(&["C1"]), 600);
    }
    assert!(until(&mut e, &out(&["C1", "C2"]), "b2", true, 20_000).is_some());
    run(&mut e, &out(&["R"]), 20);
    assert_eq!(e.items_out(), 0, "carried, not out");
    assert!(items(&e, "belt3").is_empty());
    // The second item reaches the end; closing the gripper again while it holds the
    // first takes nothing (a gripper holds one).
    assert!(until(&mut e, &out(&["C1", "C2"]), "b2", true, 20_000).is_some());
    run(&mut e, &out(&[]), 20);
    run(&mut e, &out(&["R"]), 20);
    assert_eq!(
        items(&e, "belt2").len(),
        1,
        "the second item stays on belt 2"
    );
    run(&mut e, &out(&[]), 20);
    run(&mut e, &out(&["B1"]), 20);
    assert_eq!(items(&e, "belt3"), vec![(1, "low".to_string())]);
    // Nothing held: a second place puts nothing down, and nothing is hurt (belt 2's
    // item stays there: the taker did not rise since).
    run(&mut e, &out(&[]), 20);
    run(&mut e, &out(&["B1"]), 20);
    assert_eq!(items(&e, "belt3").len(), 1);
    assert!(e.hazards().is_empty(), "{:?}", e.hazards());
    // Belt 3 delivers it into its sink: counted once.
    run(&mut e, &out(&["C2"]), 4_000);
    assert_eq!(e.items_out(), 1);
}

/// A feeder carrying from a conveyor that takes nothing is refused with its location.
#[test]
fn a_feeder_carrying_from_a_conveyor_without_a_taker_is_refused() {
    let text = LINE.replace(
        "            feed: Some((when: \"P\", items: [",
        "            feed: Some((when: \"P\", from: Some(\"belt1\"), items: [",
    );
    let p = Components::from_ron(&text, Path::new("components.ron")).unwrap_err();
    assert!(p.iter().all(|p| p.location.is_some()), "{p:?}");
    assert!(
        p.iter().any(|p| p.message.contains("carries from `belt1`")),
        "{p:?}"
    );
}
