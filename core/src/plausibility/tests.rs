use super::*;
use crate::bundle::PlantBundle;
use crate::engine::{Commanded, Engine, FilterMode};

fn station() -> PlantBundle {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    PlantBundle::load(&dir).unwrap().0
}

/// Runs one 10 ms cycle at `t` with the sensors `on` and the outputs `out` commanded;
/// returns what the rest of the cycle read for `sensor` and its `sus_` flag.
struct Rig {
    engine: Engine,
    plant: crate::plant::Plant,
    control: Commanded,
}

impl Rig {
    fn new(bundle: &PlantBundle) -> Self {
        Self {
            engine: Engine::new(bundle, FilterMode::Off, 16),
            plant: bundle.plant.clone(),
            control: Commanded(Bits::zeros(bundle.plant.outputs.len())),
        }
    }

    fn cycle(&mut self, t: u64, on: &[&str], out: &[&str]) {
        let mut inputs = Bits::zeros(self.plant.inputs.len());
        for s in on {
            inputs.set(self.plant.input(s).unwrap(), true);
        }
        self.control.0 = Bits::zeros(self.plant.outputs.len());
        for a in out {
            self.control.0.set(self.plant.output(a).unwrap(), true);
        }
        self.engine.cycle(Millis(t), &inputs, &mut self.control);
    }

    fn read(&self, sensor: &str) -> (bool, bool) {
        let f = self.engine.frame();
        let (_, sus) = self.engine.symbols.lookup(&suspect_name(sensor)).unwrap();
        (
            f.now(Space::Input).get(self.plant.input(sensor).unwrap()),
            f.now(Space::Aux).get(sus as usize),
        )
    }
}

#[test]
fn a_dropout_shorter_than_a_crossing_is_held_and_the_real_fall_is_taken() {
    let b = station();
    let mut r = Rig::new(&b);
    let drives = ["A1"];
    r.cycle(0, &[], &drives);
    r.cycle(10, &["C3"], &drives);
    assert_eq!(r.read("C3"), (true, false), "the box arrives");
    // 300 ms later the beam drops out for 50 ms: no box crosses C7 that fast.
    r.cycle(310, &[], &drives);
    assert_eq!(r.read("C3"), (true, true), "held at 1, suspect");
    r.cycle(320, &[], &drives);
    assert_eq!(r.read("C3"), (true, true));
    r.cycle(360, &["C3"], &drives);
    assert_eq!(r.read("C3"), (true, false), "the reading agrees again");
    assert_eq!(b.plausibility.held_edges, 0);
    assert_eq!(r.engine.plausibility.held_edges, 1);
    // The box leaves 1.2 s after it came: plausible, taken at once.
    r.cycle(1210, &[], &drives);
    assert_eq!(r.read("C3"), (false, false));
    let notices = r.engine.plausibility.take_notices();
    assert_eq!(notices.len(), 2, "{notices:?}");
    assert!(notices[0].suspect && notices[0].text.contains("C3 suspect"));
    assert!(!notices[1].suspect);
}

#[test]
fn a_long_dropout_is_taken_once_the_shortest_crossing_has_passed() {
    let b = station();
    let mut r = Rig::new(&b);
    // C1: a window without `hold_until_back` (C3 holds a too-early fall until the
    // reading comes back, see the test of that option).
    let drives = ["A1"];
    r.cycle(0, &[], &drives);
    r.cycle(10, &["C1"], &drives);
    for t in (300..900).step_by(10) {
        r.cycle(t, &[], &drives);
        assert_eq!(r.read("C1"), (true, true), "at {t} ms");
    }
    r.cycle(910, &[], &drives);
    assert_eq!(
        r.read("C1"),
        (false, false),
        "900 ms after the rise a fall is plausible"
    );
}

#[test]
fn a_pulse_while_nothing_under_the_beam_moves_is_held_at_0() {
    let b = station();
    let mut r = Rig::new(&b);
    r.cycle(0, &[], &[]);
    r.cycle(10, &[], &[]);
    r.cycle(20, &["C3"], &[]);
    assert_eq!(r.read("C3"), (false, true));
    r.cycle(30, &[], &[]);
    assert_eq!(r.read("C3"), (false, false));
    // With the belt running (applied in the previous cycle) the same rise is real.
    r.cycle(40, &[], &["A1"]);
    r.cycle(50, &["C3"], &["A1"]);
    assert_eq!(r.read("C3"), (true, false));
}

#[test]
fn the_table_leaves_c4_only_once_a4_is_ordered() {
    let b = station();
    let mut r = Rig::new(&b);
    r.cycle(0, &["C4"], &[]);
    r.cycle(10, &[], &[]);
    assert_eq!(
        r.read("C4"),
        (true, true),
        "C4 falls with A4 off: held at 1"
    );
    r.cycle(20, &["C4"], &["A4"]);
    assert_eq!(r.read("C4"), (true, false));
    r.cycle(100, &[], &["A4"]);
    assert_eq!(r.read("C4"), (false, false), "A4 applied: the table leaves");
}

#[test]
fn the_first_cycle_takes_what_it_reads() {
    let b = station();
    let mut r = Rig::new(&b);
    r.cycle(0, &["C7", "C4"], &[]);
    assert_eq!(r.read("C7"), (true, false));
    assert_eq!(r.read("C4"), (true, false));
}

#[test]
fn the_diagnosers_read_the_raw_sensors() {
    let b = station();
    let mut r = Rig::new(&b);
    r.cycle(0, &["C4"], &[]);
    let mut seen = None;
    let mut inputs = Bits::zeros(b.plant.inputs.len());
    let mut control = Commanded(Bits::zeros(b.plant.outputs.len()));
    r.engine
        .cycle_with(Millis(10), &inputs, &mut control, &mut |_, f, _| {
            seen = Some((f.now(Space::Input).get(4), f.prev(Space::Input).get(4)));
        });
    assert_eq!(seen, Some((false, true)), "the diagnosers see C4 fall");
    assert!(
        r.engine.frame().now(Space::Input).get(4),
        "the rest reads it held"
    );
    inputs.set(4, true);
    r.engine.cycle(Millis(20), &inputs, &mut control);
}

#[test]
fn a_rule_with_a_bad_condition_names_the_sensor_and_the_column() {
    let mut plant = station().plant;
    plant.inputs[7].plausible = Some(crate::plant::PlausibleRule {
        rise_when: Some("A3* + Nope".into()),
        ..Default::default()
    });
    let mut symbols = plant.symbols();
    // The station's rules read its observers (`P36*` for C6, `P67*` for C7).
    for o in ["P36", "P67", "2P"] {
        symbols.declare(o, Space::Observer).unwrap();
    }
    for n in suspect_names(&plant) {
        symbols.declare(&n, Space::Aux).unwrap();
    }
    let err = Plausibility::new(&plant, &symbols).unwrap_err();
    assert_eq!(err.len(), 1, "{err:?}");
    assert_eq!(err[0].code, "V0013");
    assert!(err[0].message.contains("`C7`"), "{}", err[0].message);
    assert!(err[0].message.contains("column 7"), "{}", err[0].message);
}

#[test]
fn both_values_makes_a_literal_possibly_true_whatever_its_polarity() {
    let e = crate::expr::parse_str("C3 . /C4 . A1 + RE(C4) . A2").unwrap();
    let s = suspect_expr(&e, &["C4".to_string()]);
    let mut symbols = crate::symbols::Symbols::new();
    for (n, sp) in [
        ("C3", Space::Input),
        ("C4", Space::Input),
        ("A1", Space::Output),
        ("A2", Space::Output),
        ("sus_C4", Space::Aux),
    ] {
        symbols.declare(n, sp).unwrap();
    }
    let dnf = simplify(&s.to_dnf(&symbols).unwrap());
    let text = crate::expr::render_dnf(&dnf, &symbols);
    for term in [
        "C3 . /C4 . A1",
        "C3 . A1 . sus_C4",
        "C4 . /C4* . A2",
        "C4 . A2 . sus_C4*",
        "/C4* . A2 . sus_C4",
        "A2 . sus_C4 . sus_C4*",
    ] {
        assert!(text.contains(term), "{term} missing in {text}");
    }
}

#[test]
fn switching_to_the_estimate_and_back_is_not_an_edge() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    let (db, _) = crate::pop::load(&dir).unwrap();
    let mut e = Engine::new(&db.bundle, FilterMode::Off, 16);
    e.set_estimates(crate::sim::diagnosis::estimate_map(
        &db.compiled,
        &db.bundle.plant,
        &db.bundle.symbols,
    ));
    let sym = &db.bundle.symbols;
    let (_, def) = sym.lookup("def_C4").unwrap();
    let (_, est) = sym.lookup("EST(C4)").unwrap();
    let c4 = db.bundle.plant.input("C4").unwrap();
    let mut inputs = Bits::zeros(db.bundle.plant.inputs.len());
    inputs.set(c4, true);
    let mut control = Commanded(Bits::zeros(db.bundle.plant.outputs.len()));
    e.cycle(Millis(0), &inputs, &mut control);
    // The diagnosers flag C4 and estimate it at 0 (written at the end of a cycle).
    e.frame_mut().now_mut(Space::Aux).set(def as usize, true);
    e.frame_mut().now_mut(Space::Aux).set(est as usize, false);
    e.cycle(Millis(10), &inputs, &mut control);
    let f = e.frame();
    assert!(!f.now(Space::Input).get(c4), "C4 read from its estimate");
    assert!(
        !f.prev(Space::Input).get(c4),
        "no falling edge made up by the switch"
    );
    e.cycle(Millis(20), &inputs, &mut control);
    assert!(!e.frame().now(Space::Input).get(c4));
    e.frame_mut().now_mut(Space::Aux).set(def as usize, false);
    e.cycle(Millis(30), &inputs, &mut control);
    let f = e.frame();
    assert!(f.now(Space::Input).get(c4) && f.prev(Space::Input).get(c4));
}

/// Cycles every 10 ms from `from` to `to` (excluded) with the same readings and orders.
fn hold(r: &mut Rig, from: u64, to: u64, on: &[&str], out: &[&str]) {
    for t in (from..to).step_by(10) {
        r.cycle(t, on, out);
    }
}

#[test]
fn the_table_reaches_c5_no_sooner_than_the_rotation_takes() {
    // C5: `rise_when: "A4*"` held for 2890 ms (the rotation takes 2.9 s at the least).
    let b = station();
    let mut r = Rig::new(&b);
    hold(&mut r, 0, 100, &["C4"], &["A4"]);
    hold(&mut r, 100, 1_000, &[], &["A4"]);
    // A pulse of C5 half-way: the table cannot be there yet.
    r.cycle(1_000, &["C5"], &["A4"]);
    assert_eq!(r.read("C5"), (false, true), "held at 0, suspect");
    hold(&mut r, 1_010, 2_890, &[], &["A4"]);
    assert_eq!(r.read("C5"), (false, false));
    // A4* has held since the cycle at 10 ms: at 2890 ms it has held 2880 ms.
    r.cycle(2_890, &["C5"], &["A4"]);
    assert_eq!(r.read("C5"), (false, true), "2880 ms of rotation: too soon");
    r.cycle(2_900, &["C5"], &["A4"]);
    assert_eq!(
        r.read("C5"),
        (true, false),
        "2890 ms of rotation: the table is there"
    );
}

#[test]
fn releasing_a4_restarts_the_rotation_time() {
    // The table released half-way comes back: the rise of C5 must wait a whole
    // rotation again once A4 is applied anew.
    let b = station();
    let mut r = Rig::new(&b);
    hold(&mut r, 0, 2_000, &[], &["A4"]);
    hold(&mut r, 2_000, 2_100, &[], &[]);
    hold(&mut r, 2_100, 3_000, &[], &["A4"]);
    r.cycle(3_000, &["C5"], &["A4"]);
    assert_eq!(r.read("C5"), (false, true), "890 ms since A4 again");
}

/// The box on the table at C5, leaving to the left (A2): C8 rises while C6 is still on.
fn box_leaving_left(r: &mut Rig) {
    hold(r, 0, 100, &["C5", "C6"], &["A2", "A4", "A5"]);
    r.cycle(100, &["C5", "C6", "C8"], &["A2", "A4", "A5"]);
    assert_eq!(r.read("C8"), (true, false), "the box reaches C8");
}

#[test]
fn c8_falls_no_sooner_than_400_ms_after_the_box_has_cleared_c6() {
    // C8: `fall_when: "/C6* . (…)"` held for 350 ms: the rear of a box passes C8 400 ms
    // after it passes C6, whatever the box's length. A dropout of C8 late in a large
    // box's crossing (after the 900 ms of the shortest box) is held until then.
    let b = station();
    let mut r = Rig::new(&b);
    box_leaving_left(&mut r);
    hold(&mut r, 110, 1_000, &["C5", "C6", "C8"], &["A2", "A4", "A5"]);
    hold(&mut r, 1_000, 1_100, &["C5", "C8"], &["A2", "A4", "A5"]);
    assert_eq!(r.read("C6"), (false, false), "the rear clears C6");
    // 100 ms later C8 drops out: the rear cannot have reached C8 yet.
    hold(&mut r, 1_100, 1_200, &["C5"], &["A2", "A4", "A5"]);
    assert_eq!(r.read("C8"), (true, true), "held at 1: the table stays");
    hold(&mut r, 1_200, 1_350, &["C5"], &["A2", "A4", "A5"]);
    assert_eq!(r.read("C8"), (true, true));
    hold(&mut r, 1_350, 1_420, &["C5"], &["A2", "A4", "A5"]);
    assert_eq!(
        r.read("C8"),
        (false, false),
        "350 ms after C6: the box is off the table"
    );
}

#[test]
fn a_pulse_of_c7_or_c8_with_no_box_leaving_the_table_is_held() {
    // The table at C4: nothing can reach the exits (C7 needs the table at C5 and A3, C8
    // the table at C5 and A2).
    let b = station();
    let mut r = Rig::new(&b);
    hold(&mut r, 0, 100, &["C4"], &["A5", "A6"]);
    r.cycle(100, &["C4", "C7", "C8"], &["A5", "A6"]);
    assert_eq!(r.read("C7"), (false, true));
    assert_eq!(r.read("C8"), (false, true));
    r.cycle(110, &["C4"], &["A5", "A6"]);
    assert_eq!(r.read("C7"), (false, false));
    assert_eq!(r.read("C8"), (false, false));
}

#[test]
fn a_box_reaches_c6_only_at_the_loading_position() {
    // C6: `rise_when: "C4* . (A1* + A2*)"`: a box comes onto the table at C4, pushed by
    // A1 or drawn by the rollers. (Not "after it left C3", `P36*`: with C3 stuck at 1
    // that hid every box on the table.)
    let b = station();
    let mut r = Rig::new(&b);
    hold(&mut r, 0, 100, &["C5"], &["A2", "A4"]);
    r.cycle(100, &["C5", "C6"], &["A2", "A4"]);
    assert_eq!(
        r.read("C6"),
        (false, true),
        "at C5 nothing comes on: held at 0"
    );
    hold(&mut r, 110, 200, &["C5"], &["A2", "A4"]);
    let mut r = Rig::new(&b);
    hold(&mut r, 0, 100, &["C4"], &["A1"]);
    r.cycle(100, &["C4", "C6"], &["A1"]);
    assert_eq!(
        r.read("C6"),
        (true, false),
        "at C4 with A1 on: the box arrives"
    );
}

/// `hold_until_back`: a C3 pulse of 500 ms while the belt runs (shorter than any box)
/// is held at 1 until the reading comes back, not taken as a box leaving 900 ms after
/// it came; without the option the fall is taken once the window has passed.
#[test]
fn an_edge_inside_its_window_is_held_until_the_reading_comes_back_with_hold_until_back() {
    for hold in [false, true] {
        let mut b = station();
        let c3 = b.plant.input("C3").unwrap();
        b.plant.inputs[c3]
            .plausible
            .as_mut()
            .unwrap()
            .hold_until_back = hold;
        b.plausibility = Plausibility::new(&b.plant, &b.symbols).unwrap();
        let mut r = Rig::new(&b);
        let drives = ["A1"];
        r.cycle(0, &[], &drives);
        r.cycle(10, &["C3"], &drives);
        assert_eq!(r.read("C3"), (true, false), "the rise is plausible (A1 on)");
        r.cycle(510, &[], &drives);
        assert_eq!(r.read("C3"), (true, true), "a fall 500 ms after: held");
        r.cycle(1000, &[], &drives);
        if hold {
            assert_eq!(r.read("C3"), (true, true), "still held past the window");
            r.cycle(5000, &[], &drives);
            assert_eq!(r.read("C3"), (true, true), "until the reading comes back");
            let n = r.engine.plausibility.take_notices();
            assert!(n[0].text.contains("until it reads 1 again"), "{n:?}");
            // The real box: the reading agrees again, and its fall is taken.
            r.cycle(5010, &["C3"], &drives);
            assert_eq!(r.read("C3"), (true, false));
            r.cycle(6300, &[], &drives);
            assert_eq!(r.read("C3"), (false, false), "the real box leaves");
        } else {
            assert_eq!(r.read("C3"), (false, false), "taken once the window passed");
        }
    }
}

/// `rise_not_after` (C6: `(event: "FE(C3)", ms: 100)`): a box that leaves C3 reaches
/// the middle of the table 130 ms later at the soonest, so a C6 rise 50 ms after C3
/// falls is held; the real one, 150 ms after, is taken. With C3 stuck at 1 the event
/// never comes and C6's rises are taken as before (the rule hides no box).
#[test]
fn a_rise_soon_after_its_event_is_held_and_a_stuck_upstream_sensor_holds_nothing() {
    let b = station();
    let mut r = Rig::new(&b);
    let drives = ["A1", "A2"];
    hold(&mut r, 0, 1500, &["C3", "C4"], &drives);
    r.cycle(1500, &["C4"], &drives);
    r.cycle(1550, &["C4", "C6"], &drives);
    assert_eq!(
        r.read("C6"),
        (false, true),
        "50 ms after C3 fell: held at 0"
    );
    r.cycle(1560, &["C4"], &drives);
    assert_eq!(r.read("C6"), (false, false), "the pulse is over");
    r.cycle(1650, &["C4", "C6"], &drives);
    assert_eq!(r.read("C6"), (true, false), "150 ms after: the box arrives");

    // C3 stuck at 1: no fall of C3, and the box's C6 rise is taken.
    let mut r = Rig::new(&b);
    hold(&mut r, 0, 1500, &["C3", "C4"], &drives);
    r.cycle(1500, &["C3", "C4", "C6"], &drives);
    assert_eq!(r.read("C6"), (true, false));
}

/// `fall_when_total_ms` (C3): a box that waited at the end of the belt leaves the beam
/// only once the drives under it have run long enough in all to move it its length,
/// however often they stopped on the way. A dropout in the first scans of the pull is
/// held (the window since the rise passed long ago, and the drives run); a stop
/// half-way and a restart do not lose the time already driven, so the real fall is
/// taken when the total is reached, not a whole crossing after the restart.
#[test]
fn a_fall_waits_for_the_drive_time_in_all_since_the_rise_across_a_stop() {
    for total in [0, 900] {
        let mut b = station();
        let c3 = b.plant.input("C3").unwrap();
        let rule = b.plant.inputs[c3].plausible.as_mut().unwrap();
        rule.fall_when_total_ms = total;
        rule.hold_until_back = false;
        b.plausibility = Plausibility::new(&b.plant, &b.symbols).unwrap();
        let mut r = Rig::new(&b);
        // The box arrives with A1 on, which stops at once: it waits at C3 for 5 s.
        r.cycle(0, &[], &["A1"]);
        r.cycle(10, &["C3"], &["A1"]);
        assert_eq!(r.read("C3"), (true, false), "the box arrives");
        hold(&mut r, 20, 5_000, &["C3"], &[]);
        // The table pulls it (A1 and the rollers); 100 ms later the beam drops out.
        hold(&mut r, 5_000, 5_100, &["C3"], &["A1", "A2"]);
        r.cycle(5_100, &[], &["A1", "A2"]);
        if total == 0 {
            assert_eq!(r.read("C3"), (false, false), "taken: the window has passed");
            continue;
        }
        assert_eq!(r.read("C3"), (true, true), "100 ms of drive: held");
        hold(&mut r, 5_110, 5_400, &["C3"], &["A1", "A2"]);
        assert_eq!(r.read("C3"), (true, false), "the reading is back");
        // A trip stops the drives half-way for 2.6 s; the restart goes on.
        hold(&mut r, 5_400, 8_000, &["C3"], &[]);
        hold(&mut r, 8_000, 8_300, &["C3"], &["A1", "A2"]);
        // 20 + 400 + 300 ms driven: a fall now is still too soon.
        r.cycle(8_300, &[], &["A1", "A2"]);
        assert_eq!(r.read("C3"), (true, true), "720 ms of drive in all: held");
        hold(&mut r, 8_310, 8_500, &["C3"], &["A1", "A2"]);
        // 910 ms driven in all: the box's rear leaves the beam.
        r.cycle(8_500, &[], &["A1", "A2"]);
        assert_eq!(r.read("C3"), (false, false), "the real fall is taken");
    }
}
