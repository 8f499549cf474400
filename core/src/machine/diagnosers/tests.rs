use super::*;
use crate::pop::build;
use std::path::Path;

/// A double-acting cylinder: 0..100 mm at 200 mm/s, no speed variation.
const CYLINDER: &str = r#"Components(
    name: "t",
    components: [
        (id: "cyl", name: "Cylinder", kind: Axis((
            min: 0.0, max: 100.0, start: 0.0,
            drives: [(when: "FWD", speed: 200.0), (when: "BWD", speed: -200.0)],
            sensors: [(signal: "lo", from: 0.0, to: 2.0), (signal: "hi", from: 98.0, to: 100.0)],
        ))),
        (id: "go", name: "Start", kind: Button((signal: "B"))),
    ],
)"#;

fn symbols(inputs: &[&str], outputs: &[&str]) -> Symbols {
    let mut s = Symbols::new();
    for i in inputs {
        s.declare(i, Space::Input).unwrap();
    }
    for o in outputs {
        s.declare(o, Space::Output).unwrap();
    }
    s
}

fn derived(text: &str, inputs: &[&str], outputs: &[&str]) -> (Derived, Symbols) {
    let desc = Components::from_ron(text, Path::new("components.ron")).unwrap();
    let mut sy = symbols(inputs, outputs);
    let d = derive(&desc, &sy);
    for a in build::aux_names(&d.file) {
        sy.declare(&a, Space::Aux).unwrap();
    }
    (d, sy)
}

/// The window (lo, hi, clock) of the evolution `event` out of `from`.
fn window(c: &ComponentDef, from: &str, event: &str) -> Option<(Bound, Bound, String)> {
    let e = c
        .expected
        .iter()
        .find(|e| e.from == from && e.event == event)
        .unwrap_or_else(|| panic!("no {event} out of {from}"));
    let id = e.within.as_ref()?;
    let i = c.intervals.iter().find(|i| &i.id == id).unwrap();
    Some((i.lo.clone(), i.hi.clone(), i.after.clone()))
}

#[test]
fn a_cylinders_edges_are_timed_from_the_order_that_moved_it() {
    let (d, sy) = derived(CYLINDER, &["lo", "hi", "B"], &["FWD", "BWD"]);
    assert_eq!(
        d.skipped,
        vec![("go".to_string(), "a button (no travel)".to_string())]
    );
    let c = &d.file.components[0];
    assert_eq!(c.signals, ["FWD", "BWD", "hi", "lo"]);
    assert_eq!(c.initial, "lo|none");
    assert_eq!(c.initial_values, "/FWD . /BWD . /hi . lo");
    // Leaving its 2 mm window takes at most 10 ms at 200 mm/s, plus a cycle.
    assert_eq!(
        window(c, "lo|FWD|on RE(FWD)", "FE(lo)"),
        Some((Bound::Ms(0), Bound::Ms(20), "RE(FWD)".into()))
    );
    // From the order: at least the 96 mm gap (480 ms), at most with the 2 mm it
    // started in (490 ms); a cycle each side.
    assert_eq!(
        window(c, "lo..hi|FWD|on RE(FWD) in lo", "RE(hi)"),
        Some((Bound::Ms(470), Bound::Ms(500), "RE(FWD)".into()))
    );
    // An order in a moving state comes within the same window: the state dies when
    // neither comes (a blocked cylinder).
    assert_eq!(
        window(c, "lo..hi|FWD|on RE(FWD) in lo", "FE(FWD)"),
        Some((Bound::Ms(0), Bound::Ms(500), "RE(FWD)".into()))
    );
    // Driven both ways, it is held: at rest, no window.
    assert_eq!(window(c, "lo|FWD+BWD", "FE(BWD)"), None);
    // Beyond the last sensor the cylinder rests on its end: no edge expected.
    assert!(
        !c.expected
            .iter()
            .any(|e| e.from == "hi|FWD|on RE(FWD) in lo" && e.event.contains("(hi)")),
    );
    // Four faults per sensor, the drive's blocked and unordered motion; a stopping
    // drive partition naming both outputs; the emulator's blocked axis injected.
    let parts: Vec<(&str, bool)> = c
        .partitions
        .iter()
        .map(|p| (p.id.as_str(), p.stop))
        .collect();
    assert_eq!(parts, [("hi", false), ("lo", false), ("cyl_drive", true)]);
    assert_eq!(c.partitions[2].actuators, ["FWD", "BWD"]);
    assert_eq!(c.faults.len(), 10);
    assert_eq!(c.injections[0].expected, ["cyl_drive"]);
    // The model compiles as written, through its RON text.
    let text = d.file.to_ron();
    let back = DiagnoserFile::from_ron(&text, Path::new("diagnosers.ron")).unwrap();
    assert_eq!(back, d.file);
    let compiled = build::compile(&back, &text, Path::new("diagnosers.ron"), &sy, None);
    assert!(compiled.is_ok(), "{:?}", compiled.err());
}

#[test]
fn a_window_shorter_than_a_cycles_travel_may_be_crossed_unseen() {
    // A 1 mm window at 200 mm/s (2 mm per 10 ms cycle): from the gap before it, both
    // its rise and the next window's rise may come, the latter timed over the gap, the
    // window and the next gap.
    let text = CYLINDER.replace(
        "(signal: \"hi\", from: 98.0",
        "(signal: \"mid\", from: 50.0, to: 51.0), (signal: \"hi\", from: 98.0",
    );
    let (d, _) = derived(&text, &["lo", "mid", "hi", "B"], &["FWD", "BWD"]);
    let c = &d.file.components[0];
    let from = "lo..mid|FWD|on RE(FWD) in lo";
    assert_eq!(
        window(c, from, "RE(mid)"),
        Some((Bound::Ms(230), Bound::Ms(260), "RE(FWD)".into()))
    );
    assert_eq!(
        window(c, from, "RE(hi)"),
        Some((Bound::Ms(470), Bound::Ms(500), "RE(FWD)".into()))
    );
    // A 10 mm window is always seen.
    let wide = text.replace("to: 51.0", "to: 60.0");
    let (d, _) = derived(&wide, &["lo", "mid", "hi", "B"], &["FWD", "BWD"]);
    let c = &d.file.components[0];
    assert!(
        !c.expected
            .iter()
            .any(|e| e.from == from && e.event == "RE(hi)")
    );
}

#[test]
fn end_switches_on_a_point_are_segments_of_their_own() {
    let text = CYLINDER
        .replace("from: 0.0, to: 2.0", "from: 0.0, to: 0.0")
        .replace("from: 98.0, to: 100.0", "from: 100.0, to: 100.0");
    let (d, _) = derived(&text, &["lo", "hi", "B"], &["FWD", "BWD"]);
    let c = &d.file.components[0];
    assert_eq!(c.initial, "lo|none");
    assert_eq!(
        window(c, "lo|FWD|on RE(FWD)", "FE(lo)"),
        Some((Bound::Ms(0), Bound::Ms(10), "RE(FWD)".into()))
    );
    assert_eq!(
        window(c, "lo..hi|FWD|on RE(FWD) in lo", "RE(hi)"),
        Some((Bound::Ms(490), Bound::Ms(510), "RE(FWD)".into()))
    );
}

#[test]
fn what_the_model_cannot_follow_is_said_not_guessed() {
    // Two sensors that rise at the same position (windows that touch do not: the
    // point they share shows both).
    let text = CYLINDER.replace(
        "(signal: \"hi\", from: 98.0, to: 100.0)",
        "(signal: \"hi\", from: 10.0, to: 30.0), (signal: \"mid\", from: 10.0, to: 20.0)",
    );
    let (d, _) = derived(&text, &["lo", "mid", "hi", "B"], &["FWD", "BWD"]);
    assert!(d.file.components.is_empty());
    assert!(
        d.skipped[0].1.contains("hi, mid change together at 10"),
        "{:?}",
        d.skipped
    );
    let text = CYLINDER.replace("from: 98.0, to: 100.0", "from: 2.0, to: 100.0");
    let (d, _) = derived(&text, &["lo", "hi", "B"], &["FWD", "BWD"]);
    assert_eq!(d.file.components.len(), 1, "{:?}", d.skipped);
    // A drive that reads a sensor.
    let text = CYLINDER.replace("when: \"BWD\"", "when: \"BWD . /lo\"");
    let (d, _) = derived(&text, &["lo", "hi", "B"], &["FWD", "BWD"]);
    assert!(
        d.skipped[0].1.contains("reads `lo`, not an output"),
        "{:?}",
        d.skipped
    );
    // No sensor at all.
    let text = CYLINDER.replace(
        "sensors: [(signal: \"lo\", from: 0.0, to: 2.0), (signal: \"hi\", from: 98.0, to: 100.0)]",
        "sensors: []",
    );
    let (d, _) = derived(&text, &["lo", "hi", "B"], &["FWD", "BWD"]);
    assert_eq!(d.skipped[0].1, "no position sensor");
}

#[test]
fn a_welded_drive_is_a_motion_from_rest_and_a_change_of_speed_on_the_way() {
    // Two speeds forward: FAST switched on unordered during a slow move is a motion
    // of the drive partition, not an early sensor.
    let text = CYLINDER.replace(
        "(when: \"FWD\", speed: 200.0)",
        "(when: \"FWD\", speed: 200.0), (when: \"FAST\", speed: 800.0)",
    );
    let (d, _) = derived(&text, &["lo", "hi", "B"], &["FWD", "BWD", "FAST"]);
    let c = &d.file.components[0];
    let motion = &c
        .faults
        .iter()
        .find(|f| f.id == "cyl_motion")
        .unwrap()
        .behaviours;
    let has = |state: &str, edge: &str| {
        motion
            .iter()
            .any(|b| *b == Behaviour::Moves(state.into(), edge.into()))
    };
    assert!(has("lo|none", "RE(FWD)"));
    assert!(has("lo..hi|FWD|on RE(FWD) in lo", "RE(FAST)"));
    // Switching on a drive that changes nothing is no motion, nor is one that stops
    // (the blocked fault says that).
    assert!(!has("lo..hi|FAST|on RE(FAST) in lo", "RE(FWD)"));
    assert!(!has("lo..hi|FWD|on RE(FWD) in lo", "FE(FWD)"));
    // A monostable cylinder whose output dies on the way goes back: a motion.
    let text = CYLINDER.replace("when: \"BWD\"", "when: \"/FWD\"");
    let (d, _) = derived(&text, &["lo", "hi", "B"], &["FWD"]);
    let c = &d.file.components[0];
    let motion = &c
        .faults
        .iter()
        .find(|f| f.id == "cyl_motion")
        .unwrap()
        .behaviours;
    assert!(motion.contains(&Behaviour::Moves(
        "lo..hi|FWD|on RE(FWD) in lo".into(),
        "FE(FWD)".into()
    )));
}
