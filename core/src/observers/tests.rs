use super::*;
use crate::bits::Bits;
use crate::plant::Plant;
use crate::test_support::{station, station_dir};

/// Runs the station's observers over cycles of sensors at 1 and returns, per cycle,
/// the observers at 1 (`P36 P67 2P` order) and the internal states.
fn run(cycles: &[&[&str]]) -> Vec<(String, Vec<u32>)> {
    let b = station();
    let mut obs = b.observers.clone();
    let mut frame = Frame::new(b.symbols.sizes());
    cycles
        .iter()
        .map(|ones| {
            frame.shift();
            let mut inputs = Bits::zeros(b.plant.inputs.len());
            for id in *ones {
                inputs.set(b.plant.input(id).unwrap(), true);
            }
            frame.now_mut(Space::Input).copy_from(&inputs);
            obs.update(&mut frame);
            let on: Vec<&str> = frame
                .now(Space::Observer)
                .ones()
                .map(|i| b.symbols.name(Space::Observer, i as u32))
                .collect();
            (on.join(" "), obs.counts().to_vec())
        })
        .collect()
}

#[track_caller]
fn check(cycles: &[&[&str]], observers: &[&str]) {
    let got: Vec<String> = run(cycles).into_iter().map(|(on, _)| on).collect();
    assert_eq!(got, observers, "cycles {cycles:?}");
}

#[test]
fn station_observers_load_in_order() {
    let b = station();
    let ids: Vec<&str> = b.observers.defs.iter().map(|d| d.id.as_str()).collect();
    assert_eq!(ids, ["P36", "P67", "2P"]);
    assert_eq!(b.symbols.lookup("2P"), Some((Space::Observer, 2)));
}

#[test]
fn memories_set_on_falling_edge_reset_on_rising_edge() {
    // P36: set by FE(C3), reset by RE(C6).
    check(
        &[&["C3"], &[], &[], &["C6"], &["C6"]],
        &["", "P36", "P36", "", ""],
    );
    // A rising edge of C3 does nothing; a falling edge of C6 sets P67 only.
    check(&[&["C3"], &["C3"]], &["", ""]);
    check(&[&["C6"], &[]], &["", "P67"]);
    // Both in the same cycle: set wins (a box is believed to be there).
    check(
        &[&["C3"], &["C6"], &["C6"], &[]],
        &["", "P36", "P36", "P36 P67"],
    );
    // P67: set by FE(C6), reset by RE(C7).
    check(&[&["C6"], &[], &["C7"]], &["", "P67", ""]);
    check(&[&["C6"], &["C7"]], &["", "P67"]);
    // Both memories at once.
    check(&[&["C3", "C6"], &[], &["C6"]], &["", "P36 P67", "P67"]);
}

#[test]
fn two_boxes_counter() {
    // One box straddling C0 and C1: never two boxes.
    let one: &[&[&str]] = &[&["C0"], &["C0", "C1"], &["C1"], &[]];
    check(one, &["", "", "", ""]);
    assert_eq!(
        run(one).iter().map(|(_, c)| c[2]).collect::<Vec<_>>(),
        [1, 1, 1, 0]
    );
    // A second box reaches C0 while the first is still at C1: two boxes.
    let two: &[&[&str]] = &[&["C0"], &["C0", "C1"], &["C1"], &["C0", "C1"], &["C0"], &[]];
    check(two, &["", "", "", "2P", "", ""]);
    assert_eq!(
        run(two).iter().map(|(_, c)| c[2]).collect::<Vec<_>>(),
        [1, 1, 1, 2, 1, 0]
    );
    // Clear on /C0 . /C1 wins over everything, even with two boxes counted.
    check(&[&["C0"], &["C1"], &["C0", "C1"], &[]], &["", "", "2P", ""]);
    // Three boxes, then one leaves: still two.
    let three: &[&[&str]] = &[
        &["C0"],
        &["C1"],
        &["C0", "C1"],
        &["C1"],
        &["C0", "C1"],
        &["C0"],
    ];
    assert_eq!(
        run(three).iter().map(|(_, c)| c[2]).collect::<Vec<_>>(),
        [1, 1, 2, 2, 3, 2]
    );
}

#[test]
fn counter_down_saturates_at_zero() {
    // C0 and C1 rise together (count 1), C1 falls twice without a new box on C0:
    // the count stays at 0 and never wraps.
    let cycles: &[&[&str]] = &[
        &["C0", "C1"],
        &["C0"],
        &["C0", "C1"],
        &["C0"],
        &["C0", "C1"],
        &["C0"],
    ];
    let counts: Vec<u32> = run(cycles).iter().map(|(_, c)| c[2]).collect();
    assert_eq!(counts, [1, 0, 0, 0, 0, 0]);
    check(cycles, &["", "", "", "", "", ""]);
}

fn load(text: &str) -> Vec<String> {
    let plant_text = std::fs::read_to_string(station_dir().join("plant.ron")).unwrap();
    let plant = Plant::from_ron(&plant_text, Path::new("plant.ron")).unwrap();
    let mut symbols = plant.symbols();
    let (_, problems) = Observers::from_ron(text, Path::new("observers.ron"), &mut symbols);
    problems.iter().map(ToString::to_string).collect()
}

fn memory(id: &str, set: &str, reset: &str) -> String {
    format!(r#"(observers: [(id: "{id}", rule: Memory(set: "{set}", reset: "{reset}"))])"#)
}

#[track_caller]
fn check_load(text: &str, expected: &[&str]) {
    assert_eq!(load(text), expected, "{text}");
}

#[test]
fn observer_file_errors_name_the_observer() {
    check_load(&memory("P", "FE(C3) . C4*", "RE(C6)"), &[]);
    check_load(
        &memory("P36", "FE(C3", "RE(C6)"),
        &[
            "observers.ron:1:1: error[V0202]: observer `P36`: `set`: expected `)`, found end of expression (column 6)",
        ],
    );
    check_load(
        &memory("P36", "FE(C3)", "RE(X)"),
        &[
            "observers.ron:1:1: error[V0202]: observer `P36`: `reset`: unknown signal `X` (column 4)",
        ],
    );
    check_load(
        &memory("Q", "C0 . A0", "C1"),
        &[
            "observers.ron:1:1: error[V0201]: observer `Q`: `set` may read inputs, previous outputs and auxiliaries only",
        ],
    );
    // Previous outputs are allowed, outputs at t and edges of outputs are not.
    check_load(&memory("Q", "A0*", "C1"), &[]);
    check_load(
        &memory("Q", "C0", "RE(A1)"),
        &[
            "observers.ron:1:1: error[V0201]: observer `Q`: `reset` may read inputs, previous outputs and auxiliaries only",
        ],
    );
    check_load(
        r#"(observers: [(id: "N", rule: Counter(up: "C0", down: "C1 +", clear: Some("A2"), at_least: 2))])"#,
        &[
            "observers.ron:1:1: error[V0201]: observer `N`: `clear` may read inputs, previous outputs and auxiliaries only",
            "observers.ron:1:1: error[V0202]: observer `N`: `down`: expected a name, `/` or `(`, found end of expression (column 5)",
        ],
    );
    check_load(
        &memory("P-1", "C0", "C1"),
        &["observers.ron:1:1: error[V0203]: observer id `P-1` must be letters, digits and `_`"],
    );
    check_load(
        &memory("C0", "C0", "C1"),
        &["observers.ron:1:1: error[V0204]: observer `C0` has the name of another signal"],
    );
    // `empty_when` (read at the re-initialisation) is checked like the rule.
    check_load(
        r#"(observers: [(id: "P", rule: Memory(set: "C0", reset: "C1"), empty_when: Some("C3 + C6"))])"#,
        &[],
    );
    check_load(
        r#"(observers: [(id: "P", rule: Memory(set: "C0", reset: "C1"), empty_when: Some("C3 + X"))])"#,
        &[
            "observers.ron:1:1: error[V0202]: observer `P`: `empty_when`: unknown signal `X` (column 6)",
        ],
    );
    check_load(
        r#"(observers: [(id: "P", rule: Memory(set: "C0", reset: "C1"), empty_when: Some("A4"))])"#,
        &[
            "observers.ron:1:1: error[V0201]: observer `P`: `empty_when` may read inputs, previous outputs and auxiliaries only",
        ],
    );
    // Observers read inputs, not each other.
    check_load(
        r#"(observers: [(id: "P", rule: Memory(set: "C0", reset: "C1")), (id: "Q", rule: Memory(set: "P", reset: "C1"))])"#,
        &["observers.ron:1:1: error[V0202]: observer `Q`: `set`: unknown signal `P` (column 1)"],
    );
    check_load(
        "(observers: [(id: \"P\",\n  rule: Toggle)])",
        &[
            "observers.ron:2:9: error[V0001]: invalid RON: Unexpected variant named `Toggle` in enum `Rule`, expected either `Memory` or `Counter` instead",
        ],
    );
}

#[test]
fn bad_observers_are_skipped_and_the_rest_kept() {
    let plant_text = std::fs::read_to_string(station_dir().join("plant.ron")).unwrap();
    let plant = Plant::from_ron(&plant_text, Path::new("plant.ron")).unwrap();
    let mut symbols = plant.symbols();
    let text = r#"(observers: [(id: "A", rule: Memory(set: "X", reset: "C1")), (id: "B", rule: Memory(set: "C0", reset: "C1"))])"#;
    let (obs, problems) = Observers::from_ron(text, Path::new("o.ron"), &mut symbols);
    assert_eq!(problems.len(), 1);
    assert_eq!(obs.len(), 1);
    assert_eq!(symbols.lookup("B"), Some((Space::Observer, 0)));
    assert_eq!(symbols.lookup("A"), None);
}
