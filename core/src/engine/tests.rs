use super::*;
use crate::constraints::ConstraintSet;
use crate::test_support::station;
use std::path::Path;

/// Drives an engine on the sorting station, cycle by cycle, every 10 ms. The mirror
/// contacts read the outputs applied in the previous cycle (healthy contactors) unless a
/// cycle is run `raw`.
struct Run {
    engine: Engine,
    plant: crate::plant::Plant,
    t: u64,
    applied: Bits,
}

impl Run {
    fn new(mode: FilterMode) -> Self {
        Self::with_bundle(station(), mode)
    }

    fn with_bundle(bundle: PlantBundle, mode: FilterMode) -> Self {
        Self {
            // Scripted inputs, not a plant: every edge taken as read.
            engine: {
                let mut e = Engine::new(&bundle, mode, 100);
                e.set_plausibility(false);
                e
            },
            // Before the first cycle, the outputs' initial values (a cold start).
            applied: {
                let mut b = Bits::zeros(bundle.plant.outputs.len());
                for (k, o) in bundle.plant.outputs.iter().enumerate() {
                    b.set(k, o.initial);
                }
                b
            },
            plant: bundle.plant,
            t: 0,
        }
    }

    /// One cycle with these sensors at 1 and these outputs commanded; returns the
    /// outputs applied, by name, less the safety contactors held ON (`held_on`), which
    /// are named only when released.
    fn cycle(&mut self, sensors: &[&str], commanded: &[&str]) -> Vec<String> {
        self.cycle_with(sensors, commanded, true)
    }

    /// [`Run::cycle`] with every mirror contact as the sensors say (a welded or dead
    /// contactor, or a link's first cycle).
    fn cycle_raw(&mut self, sensors: &[&str], commanded: &[&str]) -> Vec<String> {
        self.cycle_with(sensors, commanded, false)
    }

    fn cycle_with(&mut self, sensors: &[&str], commanded: &[&str], mirrors: bool) -> Vec<String> {
        self.t += 10;
        let mut inputs = Bits::zeros(self.plant.inputs.len());
        for s in sensors {
            inputs.set(self.plant.input(s).unwrap(), true);
        }
        if mirrors {
            for (i, o) in self.plant.mirrors() {
                inputs.set(i, self.applied.get(o));
            }
        }
        let mut outputs = Bits::zeros(self.plant.outputs.len());
        for a in commanded {
            outputs.set(self.plant.output(a).unwrap(), true);
        }
        let applied = self
            .engine
            .cycle(Millis(self.t), &inputs, &mut Commanded(outputs))
            .clone();
        self.applied = applied.clone();
        applied
            .ones()
            .filter(|&k| !self.plant.outputs[k].held_on)
            .map(|k| self.plant.outputs[k].id.clone())
            .collect()
    }
}

#[test]
fn a_trip_latches_and_records_what_happened() {
    let mut run = Run::new(FilterMode::Enforce);
    // Box on the table in loading position, rotation starts; table in unloading position.
    assert_eq!(run.cycle(&["C4", "C6"], &["A4"]), ["A4"]);
    assert_eq!(run.cycle(&["C5", "C6"], &["A4"]), ["A4"]);
    // The box leaves C6 (P67 set) ...
    assert_eq!(run.cycle(&["C5"], &["A4"]), ["A4"]);
    assert!(run.engine.drain_events().is_empty());
    // ... reaches C7 and the program releases A4 (the paper's CSs10) to start A3.
    assert_eq!(run.cycle(&["C5", "C7"], &["A3"]), ["A4"]);
    assert!(run.engine.is_tripped());
    assert_eq!(run.engine.drain_events(), [Event::Trip { index: 0 }]);
    let trip = &run.engine.trips[0];
    assert_eq!(
        (
            trip.time_ms,
            trip.cycle,
            trip.enforced,
            trip.spec_error.clone()
        ),
        (40, 4, true, None)
    );
    let lit = |literal: &str, name: &str, space, value| LiteralValue {
        literal: literal.into(),
        name: name.into(),
        space,
        previous: false,
        value,
    };
    assert_eq!(
        trip.constraints,
        [FiredConstraint {
            id: "CSs10".into(),
            class: Class::Simple,
            notation: "C7 . /A4".into(),
            literals: vec![
                lit("C7", "C7", Space::Input, true),
                lit("/A4", "A4", Space::Output, false)
            ],
        }]
    );
    let actions: Vec<(&str, bool, bool, Action)> = trip
        .actions
        .iter()
        .map(|a| (a.output.as_str(), a.commanded, a.applied, a.action))
        .collect();
    assert_eq!(
        actions,
        [
            ("A0", false, false, Action::Unchanged),
            ("A1", false, false, Action::Unchanged),
            ("A2", false, false, Action::Unchanged),
            ("A3", true, false, Action::ForcedOff),
            ("A4", false, true, Action::ForcedOn),
            ("A5", false, false, Action::Unchanged),
            ("A6", false, false, Action::Unchanged),
            ("KM0", true, true, Action::Unchanged),
            ("YV0", true, true, Action::Unchanged),
        ]
    );
    let fallback: Vec<(&str, bool)> = trip
        .fallback
        .iter()
        .map(|(n, v)| (n.as_str(), *v))
        .collect();
    assert_eq!(
        fallback,
        [
            ("A0", false),
            ("A1", false),
            ("A2", false),
            ("A3", false),
            ("A4", true),
            ("A5", false),
            ("A6", false),
            ("KM0", true),
            ("YV0", true)
        ]
    );
    let rec = run.engine.history.last().unwrap();
    assert_eq!((rec.time, rec.tripped), (Millis(40), true));
    assert_eq!(
        (rec.commanded.to_string(), rec.applied.to_string()),
        ("000100011".into(), "000010011".into())
    );

    // Latched: compliant commands are not applied, the fallback is.
    assert_eq!(run.cycle(&["C5", "C7"], &["A3", "A4"]), ["A4"]);
    assert_eq!(run.cycle(&["C5", "C7"], &["A3", "A4", "A5", "A6"]), ["A4"]);
    assert!(run.engine.drain_events().is_empty());
    assert_eq!(run.engine.trips.len(), 1);
    // The fallback follows the context: at C4 with an empty table A4 must drop.
    assert_eq!(run.cycle(&["C4"], &["A4"]), Vec::<String>::new());
}

#[test]
fn reset_is_refused_while_the_commands_still_violate() {
    let mut run = Run::new(FilterMode::Enforce);
    assert_eq!(run.engine.reset(), Err(ResetRefused::NotTripped));
    run.cycle(&["C4", "C6"], &["A4"]);
    run.cycle(&["C5", "C6"], &["A4"]);
    run.cycle(&["C5"], &["A4"]);
    run.cycle(&["C5", "C7"], &["A3", "A2"]);
    let trip_constraints: Vec<&str> = run.engine.trips[0]
        .constraints
        .iter()
        .map(|c| c.id.as_str())
        .collect();
    assert_eq!(trip_constraints, ["CSs10", "CSs12"]);
    let refused = run.engine.reset().unwrap_err();
    assert_eq!(
        refused.to_string(),
        "reset refused: CSs10, CSs12 still violated by the commanded outputs"
    );
    assert!(run.engine.is_tripped());
    // The outputs applied are untouched by the refused reset.
    assert_eq!(run.engine.applied().to_string(), "000010011");
    run.cycle(&["C5", "C7"], &["A3"]);
    assert_eq!(
        run.engine.reset(),
        Err(ResetRefused::StillViolated {
            constraints: vec!["CSs10".into()],
            observers: vec![],
        })
    );
    run.drain();
    // Commands corrected: the reset is accepted and the commands pass again.
    assert_eq!(run.cycle(&["C5", "C7"], &["A3", "A4"]), ["A4"]);
    assert_eq!(run.engine.reset(), Ok(()));
    assert!(!run.engine.is_tripped());
    assert_eq!(run.engine.drain_events(), [Event::Reset]);
    assert_eq!(run.cycle(&["C5", "C7"], &["A3", "A4"]), ["A3", "A4"]);
    // The filter keeps checking: a new violation trips again.
    assert_eq!(run.cycle(&["C5", "C7"], &["A3"]), ["A4"]);
    assert_eq!(run.engine.drain_events(), [Event::Trip { index: 1 }]);
    assert_eq!(
        run.engine.reset(),
        Err(ResetRefused::StillViolated {
            constraints: vec!["CSs10".into()],
            observers: vec![],
        })
    );
}

#[test]
fn a_refused_reset_names_the_observers_that_hold_it() {
    let mut run = Run::new(FilterMode::Enforce);
    // A box leaves the table at C5 to the right: C6 falls, P67 holds the rotation.
    assert_eq!(run.cycle(&["C4", "C6"], &["A4"]), ["A4"]);
    assert_eq!(run.cycle(&["C5", "C6"], &["A3", "A4"]), ["A3", "A4"]);
    assert_eq!(run.cycle(&["C5"], &["A3", "A4"]), ["A3", "A4"]);
    // The program releases A4 with the box between C6 and C7: CSs11 trips.
    run.cycle(&["C5"], &["A3"]);
    assert!(run.engine.is_tripped());
    let refused = run.engine.reset().unwrap_err();
    assert_eq!(
        refused,
        ResetRefused::StillViolated {
            constraints: vec!["CSs11".into()],
            observers: vec!["P67".into()],
        }
    );
    assert_eq!(
        refused.to_string(),
        "reset refused: CSs11 still violated by the commanded outputs (with P67 = 1)"
    );
}

impl Run {
    fn drain(&mut self) -> Vec<Event> {
        self.engine.drain_events()
    }
}

#[test]
fn report_only_never_changes_outputs_and_records_each_new_violated_set() {
    let mut run = Run::new(FilterMode::ReportOnly);
    // (sensors at 1, outputs commanded, constraints recorded in this cycle)
    type Step<'a> = (&'a [&'a str], &'a [&'a str], Option<&'a [&'a str]>);
    let steps: [Step<'_>; 9] = [
        (&["C4", "C6"], &["A4"], None),
        (&["C5", "C6"], &["A4"], None),
        (&["C5"], &["A4"], None),
        (&["C5", "C7"], &["A3"], Some(&["CSs10"])),
        (&["C5", "C7"], &["A3"], None),
        (&["C5", "C7"], &["A2", "A3"], Some(&["CSs10", "CSs12"])),
        (&["C5", "C7"], &["A2", "A3"], None),
        // Pressing A4 again away from C4 is a rising edge (CSs14).
        (&["C5", "C7"], &["A3", "A4"], Some(&["CSs14"])),
        (&["C5", "C7"], &[], Some(&["CSs10"])),
    ];
    for (i, (sensors, commanded, recorded)) in steps.iter().enumerate() {
        let applied = run.cycle(sensors, commanded);
        assert_eq!(
            applied,
            commanded.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
            "cycle {}",
            i + 1
        );
        assert!(!run.engine.is_tripped());
        let events = run.drain();
        match recorded {
            None => assert!(events.is_empty(), "cycle {}: {events:?}", i + 1),
            Some(ids) => {
                let index = run.engine.trips.len() - 1;
                assert_eq!(events, [Event::Violation { index }], "cycle {}", i + 1);
                let trip = &run.engine.trips[index];
                let got: Vec<&str> = trip.constraints.iter().map(|c| c.id.as_str()).collect();
                assert_eq!(&got, ids, "cycle {}", i + 1);
                assert!(!trip.enforced);
                assert!(
                    trip.actions
                        .iter()
                        .all(|a| a.action == Action::Unchanged && a.applied == a.commanded)
                );
                assert_eq!(trip.time_ms, 10 * (i as u64 + 1));
            }
        }
    }
    assert_eq!(run.engine.trips.len(), 4);
    assert_eq!(run.engine.reset(), Err(ResetRefused::NotTripped));
}

#[test]
fn off_mode_passes_everything_and_records_nothing() {
    let mut run = Run::new(FilterMode::Off);
    assert_eq!(run.cycle(&["C5", "C7"], &["A3", "A2"]), ["A2", "A3"]);
    assert_eq!(run.cycle(&["C0"], &["A0"]), ["A0"]);
    assert!(run.drain().is_empty());
    assert!(run.engine.trips.is_empty());
    assert_eq!(run.engine.history.len(), 2);
    assert!(!run.engine.history.last().unwrap().tripped);
}

#[test]
fn leaving_enforce_mode_releases_the_latch() {
    let mut run = Run::new(FilterMode::Enforce);
    run.cycle(&["C7"], &[]);
    assert!(run.engine.is_tripped());
    run.engine.set_mode(FilterMode::ReportOnly);
    assert!(!run.engine.is_tripped());
    assert_eq!(run.cycle(&["C7"], &["A0"]), ["A0"]);
}

fn conflicting_bundle(text: &str) -> PlantBundle {
    let mut b = station();
    let (set, problems) = ConstraintSet::parse(text, Path::new("c.txt"), &b.symbols);
    assert!(problems.is_empty());
    b.constraints = set;
    b
}

#[test]
fn specification_error_drives_every_output_to_zero_once_reported() {
    let mut run = Run::with_bundle(
        conflicting_bundle("X = C0 . /A0\nY = C0 . A0"),
        FilterMode::Enforce,
    );
    assert_eq!(run.cycle(&[], &["A0", "A1"]), ["A0", "A1"]);
    assert_eq!(run.cycle(&["C0"], &["A0", "A1"]), Vec::<String>::new());
    let message = "no output vector satisfies every constraint: X, Y".to_string();
    assert_eq!(
        run.drain(),
        [
            Event::Trip { index: 0 },
            Event::SpecificationError {
                message: message.clone()
            }
        ]
    );
    let trip = &run.engine.trips[0];
    assert_eq!(trip.spec_error.as_deref(), Some(message.as_str()));
    // Every output at its safe value: 0, and the safety contactors (safe: One) ON.
    assert!(
        trip.fallback
            .iter()
            .all(|(name, v)| *v == (name == "KM0" || name == "YV0"))
    );
    let forced: Vec<&str> = trip
        .actions
        .iter()
        .filter(|a| a.action == Action::ForcedOff)
        .map(|a| a.output.as_str())
        .collect();
    assert_eq!(forced, ["A0", "A1"]);
    // The error persists: outputs stay at 0 and the event is not repeated every cycle.
    assert_eq!(run.cycle(&["C0"], &["A0", "A1"]), Vec::<String>::new());
    assert_eq!(run.cycle(&["C0"], &["A1"]), Vec::<String>::new());
    assert!(run.drain().is_empty());
    // Once the conflict is gone the fallback applies again; a new conflict is reported.
    assert_eq!(run.cycle(&[], &["A1"]), Vec::<String>::new());
    run.cycle(&["C0"], &[]);
    assert_eq!(run.drain(), [Event::SpecificationError { message }]);
}

/// A trace recorded mid-production: the table already at its unloading position with
/// A4 held (C5, A4). A cold start reads it as a rising edge of A4 away from C4
/// (CSs14 = /C4 . RE(A4)) and trips on the first row; attaching takes the first row
/// as the previous values too and sees no edge. Both see a real edge after it.
#[test]
fn attaching_to_a_running_plant_shows_no_edge_on_the_first_cycle() {
    let mut cold = Run::new(FilterMode::Enforce);
    cold.cycle(&["C5", "C6"], &["A4"]);
    assert!(
        cold.engine.is_tripped(),
        "a cold start sees RE(A4) away from C4"
    );
    let mut attached = Run::new(FilterMode::Enforce);
    attached.engine.set_first_cycle(FirstCycle::Attach);
    // The running plant's contactors are closed: their mirrors say so.
    assert_eq!(
        attached.cycle_raw(&["C5", "C6", "A4_fb", "KM0_fb", "YV0_fb"], &["A4"]),
        ["A4"]
    );
    assert!(!attached.engine.is_tripped());
    attached.cycle(&["C5", "C6"], &["A4"]);
    assert!(!attached.engine.is_tripped());
    // Released at C5 and pressed again before C4: a real rising edge away from C4.
    attached.cycle(&["C6"], &[]);
    attached.cycle(&["C6"], &["A4"]);
    assert!(
        attached.engine.is_tripped(),
        "the edges after the first cycle are real"
    );
}

/// The initial values of `plant.ron` are a cold start's previous values: an output
/// that starts ON has no rising edge in the first cycle.
#[test]
fn a_cold_start_reads_the_initial_values_as_the_previous_ones() {
    let mut b = station();
    let a4 = b.plant.output("A4").unwrap();
    b.plant.outputs[a4].initial = true;
    let mut run = Run::with_bundle(b, FilterMode::Enforce);
    run.cycle(&["C5", "C6"], &["A4"]);
    assert!(!run.engine.is_tripped(), "A4 was ON before the first cycle");
}

/// A trip restored after a restart holds the fallback from the first cycle until a
/// reset whose commands comply, as if it had just happened.
#[test]
fn a_restored_trip_holds_the_fallback_until_the_reset() {
    let mut first = Run::new(FilterMode::Enforce);
    first.cycle(&["C0"], &["A0"]);
    assert!(first.engine.is_tripped(), "CSc1 = C0 . A0 . /A1");
    let trip = first.engine.trips.last().cloned().unwrap();
    let mut again = Run::new(FilterMode::Enforce);
    again.engine.restore_trip(trip.clone());
    assert!(again.engine.is_tripped());
    // The PLC commands something allowed: the latch holds anyway.
    assert_eq!(again.cycle(&[], &["A0", "A1"]), Vec::<String>::new());
    assert!(again.engine.drain_events().is_empty(), "no new trip event");
    assert_eq!(again.engine.trips, vec![trip]);
    again.engine.reset().unwrap();
    assert_eq!(again.cycle(&[], &["A0", "A1"]), ["A0", "A1"]);
    // Report-only engines do not latch.
    let mut monitor = Run::new(FilterMode::ReportOnly);
    monitor.engine.restore_trip(first.engine.trips[0].clone());
    assert!(!monitor.engine.is_tripped());
}

/// The operator's re-initialisation (issue 17, recovery). A pulse of C6 at the loading
/// position while the rollers run is a box for the stage (a rise is plausible there),
/// the filter trips on CSs6, and C6's fall at C4 is not plausible (a box leaves the
/// table only at C5): C6 stays held at 1 and every reset is refused. After a check of
/// the plant, the re-initialisation takes the sensors as read and ends the trip. The
/// outputs at t-1 stay what was applied: a release of the table away from C5 is still
/// an edge of A4 (CSs15), and the filter trips again on it.
#[test]
fn the_reinitialisation_takes_the_sensors_as_read_and_keeps_the_applied_outputs() {
    let mut run = Run::new(FilterMode::Enforce);
    run.engine.set_plausibility(true);
    assert!(!run.engine.reinitialise(false), "nothing to re-initialise");
    for _ in 0..300 {
        run.cycle(&["C4"], &["A1", "A2"]);
    }
    run.cycle(&["C4", "C6"], &["A1", "A2"]);
    assert!(run.engine.is_tripped());
    for _ in 0..100 {
        assert!(
            !run.cycle(&["C4"], &["A1", "A2"])
                .contains(&"A2".to_string())
        );
    }
    let refused = run.engine.reset().unwrap_err();
    assert!(refused.to_string().contains("CSs6"), "{refused}");
    assert!(run.engine.reinitialise(false));
    assert!(!run.engine.is_tripped());
    assert_eq!(run.cycle(&["C4"], &["A1", "A2"]), ["A1", "A2"]);
    let c6 = run.plant.input("C6").unwrap();
    assert!(
        !run.engine.frame().now(Space::Input).get(c6),
        "C6 taken as read"
    );
    assert!(!run.engine.is_tripped());

    let mut run = Run::new(FilterMode::Enforce);
    run.cycle(&["C4", "C6"], &["A4"]);
    run.cycle(&["C6"], &["A4"]);
    // Released half-way: CSs15 trips and the fallback holds A4.
    assert_eq!(run.cycle(&["C6"], &[]), ["A4"]);
    assert!(run.engine.is_tripped());
    assert!(run.engine.reinitialise(false));
    assert_eq!(run.cycle(&["C6"], &[]), ["A4"], "still held away from C5");
    assert!(run.engine.is_tripped());
}

/// At the re-initialisation an observer is cleared only where the sensors as read leave
/// no room for its item (`empty_when`, P36: `C3 + C6`); otherwise it keeps its value
/// and what it protects stays protected (a box between C3 and C6 that no sensor sees).
#[test]
fn the_reinitialisation_clears_an_observer_only_where_the_sensors_leave_no_room() {
    for (after, cleared) in [(&[][..], false), (&["C3"][..], true)] {
        let mut run = Run::new(FilterMode::Enforce);
        let (_, p36) = run.engine.symbols.lookup("P36").unwrap();
        let p36 = p36 as usize;
        run.cycle(&["C3", "C4"], &["A1"]);
        run.cycle(&["C4"], &["A1"]);
        assert!(
            run.engine.frame().now(Space::Observer).get(p36),
            "FE(C3) sets P36"
        );
        // The table leaves C4 with the belt on and a box at its end: CSs2 trips.
        run.cycle(&["C3"], &["A1"]);
        assert!(run.engine.is_tripped());
        assert!(run.engine.reinitialise(false));
        run.cycle(after, &[]);
        assert_eq!(
            !run.engine.frame().now(Space::Observer).get(p36),
            cleared,
            "sensors {after:?}"
        );
        let expected: Vec<String> = if cleared { vec!["P36".into()] } else { vec![] };
        assert_eq!(run.engine.reinit_cleared, expected);
    }
}

/// The plant emptied by the operator before the re-initialisation: every observer
/// restarts empty, whatever the sensors show (P36 set, no sensor on).
#[test]
fn the_reinitialisation_of_an_emptied_plant_clears_every_observer() {
    let mut run = Run::new(FilterMode::Enforce);
    let (_, p36) = run.engine.symbols.lookup("P36").unwrap();
    let p36 = p36 as usize;
    run.cycle(&["C3", "C4"], &["A1"]);
    run.cycle(&["C4"], &["A1"]);
    run.cycle(&["C3"], &["A1"]);
    assert!(run.engine.is_tripped());
    assert!(run.engine.frame().now(Space::Observer).get(p36));
    assert!(run.engine.reinitialise(true));
    run.cycle(&[], &[]);
    assert!(!run.engine.frame().now(Space::Observer).get(p36));
    assert_eq!(run.engine.reinit_cleared, ["P36"]);
    assert!(!run.engine.is_tripped());
}

/// The station with mirror contacts that follow within one cycle (`feedback_ms: 0`).
fn instant_mirrors(mut b: PlantBundle) -> PlantBundle {
    for s in &mut b.plant.inputs {
        s.feedback_ms = 0;
    }
    b
}

/// A mirror contact that disagrees with its output for less than its `feedback_ms`
/// (the contactor still switching, a live link's latency) is read as agreeing: no trip;
/// a disagreement that lasts trips once it has lasted that long, not before; one that
/// ends in time leaves no trace, and the count starts again at the next one.
#[test]
fn a_mirror_is_read_as_agreeing_for_its_feedback_time() {
    let dir = crate::test_support::edm_station("edm-feedback-ms");
    let (b, _) = PlantBundle::load(&dir).unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
    let a6_fb = b.plant.input("A6_fb").unwrap();
    assert_eq!(b.plant.inputs[a6_fb].feedback_ms, 30);
    let mut run = Run::with_bundle(b, FilterMode::Enforce);
    let safety = ["C4", "KM0_fb", "YV0_fb"];
    run.cycle_raw(&["C4"], &[]);
    run.cycle_raw(&safety, &[]);
    // A6 commanded at 30 ms; its mirror closes only 40 ms later (cycles 40..60 read it
    // open: 20 ms of disagreement, less than 30): no trip, and the frame read agreement.
    run.cycle_raw(&safety, &["A6"]);
    for _ in 0..3 {
        run.cycle_raw(&safety, &["A6"]);
        assert!(!run.engine.is_tripped(), "{:?}", run.engine.trips);
        assert!(
            run.engine.frame().now(Space::Input).get(a6_fb),
            "held as closed"
        );
    }
    let with_fb = ["C4", "KM0_fb", "YV0_fb", "A6_fb"];
    run.cycle_raw(&with_fb, &["A6"]);
    assert!(!run.engine.is_tripped());
    // Released at 80 ms; the mirror stays closed (welded): held open at 90, 100, 110
    // (0, 10, 20 ms of disagreement), read closed at 120 (30 ms): CSk13.
    run.cycle_raw(&with_fb, &[]);
    for t in [90, 100, 110] {
        run.cycle_raw(&with_fb, &[]);
        assert!(!run.engine.is_tripped(), "{t} ms");
    }
    run.cycle_raw(&with_fb, &[]);
    let ids: Vec<&str> = run.engine.trips[0]
        .constraints
        .iter()
        .map(|c| c.id.as_str())
        .collect();
    assert_eq!(ids, ["CSk13"]);
}

/// An attach to a running plant takes a mirrored contactor's previous value from its
/// mirror contact, not from the command: a safety contactor the link has not closed yet
/// (its mirror open, KM0 commanded ON by the safety function) is not taken for a dead
/// one (CSk15 = KM0 . KM0* . /KM0_fb). A cold start reads every previous output as 0 and
/// does not trip either; an attach where the mirror shows the contactor closed while the
/// plant's previous command is unknown keeps it closed.
#[test]
fn an_attach_reads_a_mirrored_contactor_from_its_mirror() {
    let dir = crate::test_support::edm_station("edm-attach");
    let (b, _) = PlantBundle::load(&dir).unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
    let b = instant_mirrors(b);
    let mut attached = Run::with_bundle(b.clone(), FilterMode::Enforce);
    attached.engine.set_first_cycle(FirstCycle::Attach);
    attached.cycle_raw(&[], &[]);
    assert!(
        !attached.engine.is_tripped(),
        "{:?}",
        attached.engine.trips.first().map(|t| &t.constraints)
    );
    // The contactors close with the link: their mirrors follow in the next cycle.
    attached.cycle_raw(&["KM0_fb", "YV0_fb"], &[]);
    assert!(!attached.engine.is_tripped());
    // Then KM0 drops out while the safety function holds it: a dead contactor.
    attached.cycle_raw(&["YV0_fb"], &[]);
    assert!(attached.engine.is_tripped(), "KM0 dead");
    let mut cold = Run::with_bundle(b, FilterMode::Enforce);
    cold.cycle_raw(&[], &[]);
    assert!(!cold.engine.is_tripped());
}

/// The check of a manual request on a plant with mirror contacts: in the next cycle a
/// healthy contactor's mirror follows what is applied now (a drive released in this
/// cycle is not taken for a welded one when it is requested again), and a welded one
/// stays welded (its request is refused on its monomial).
#[test]
fn a_manual_request_lets_healthy_mirrors_follow_and_refuses_a_weld() {
    let dir = crate::test_support::edm_station("edm-manual");
    let (b, _) = PlantBundle::load(&dir).unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
    let b = instant_mirrors(b);
    let mut run = Run::with_bundle(b, FilterMode::Enforce);
    let healthy = |run: &mut Run, mirrors: &[&str], commanded: &[&str]| {
        let mut s = vec!["C4"];
        s.extend_from_slice(mirrors);
        run.cycle_raw(&s, commanded);
    };
    healthy(&mut run, &[], &["A6"]);
    healthy(&mut run, &["KM0_fb", "YV0_fb", "A6_fb"], &["A6"]);
    // A6 released now: its mirror still shows it closed (it reads the cycle before).
    healthy(&mut run, &["KM0_fb", "YV0_fb", "A6_fb"], &[]);
    assert!(!run.engine.is_tripped());
    let request = |run: &Run, on: &[&str]| {
        let mut out = Bits::zeros(run.plant.outputs.len());
        for a in on.iter().chain(&["KM0", "YV0"]) {
            out.set(run.plant.output(a).unwrap(), true);
        }
        run.engine
            .check_request(&out)
            .into_iter()
            .map(|c| c.id)
            .collect::<Vec<_>>()
    };
    assert_eq!(request(&run, &["A6"]), Vec::<String>::new(), "A6 ON again");
    assert_eq!(request(&run, &[]), Vec::<String>::new(), "A6 stays OFF");
    // Welded: released two cycles ago, its mirror still shows it closed.
    healthy(&mut run, &["KM0_fb", "YV0_fb", "A6_fb"], &[]);
    assert!(run.engine.is_tripped(), "CSk13 trips on the weld");
    assert_eq!(
        request(&run, &[]),
        ["CSk13"],
        "a request does not hide the weld"
    );
}
