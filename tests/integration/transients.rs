//! The robust filter under transient sensor faults (issue 17): the findings of the
//! issue replayed on the sorting station, and a reduced `vigie campaign transients`.
//!
//! - A beam that drops out for a few tens of milliseconds while a box crosses it made
//!   the program and the observers believe the box had gone: the table was released and
//!   the box sheared, with the filter and the diagnosers on. The plausibility stage
//!   (`plausible` in `plant.ron`) holds such a fall: no box crosses a beam that fast.
//! - The campaign's dropouts of C6 and C7 (the beams of the table and of the right
//!   exit), of every length, at random moments of the crossing: no hazard, and
//!   production restored by the reset in most runs.
//! - A dropout of C8 late in a large box's crossing (after the 900 ms of the shortest
//!   box) released the table under the box: C8 now falls no sooner than 350 ms after
//!   the box has cleared C6 (its rear passes C8 400 ms later, whatever its length).
//! - A pulse of C4 while the table came back made the program load a box onto a table
//!   still turning: C4 rises no sooner than 2.89 s after A4 was released, and the
//!   diagnosers' estimate of C4 waits for the end of the table's arrival window.
//! - A pulse of C7 or C8 with no box leaving the table tripped the filter and stopped
//!   production: a box reaches an exit only from the table at C5 with its rollers on.
//! - A pulse of C3 while a box is on its way to it became a box for the program, and
//!   the real box's arrival, soon after that one "left", was held as implausible: the
//!   belt pushed it onto the turning table. C3 is read as possibly on by the
//!   constraints while it is suspect (`both_values`): a held arrival still stops A1.

#![allow(clippy::unwrap_used)] // test helpers: a failure is a test failure

use std::path::{Path, PathBuf};
use vigie_core::Millis;
use vigie_core::emulator::{ArrivalPlan, FaultKind, FaultSpec, SizeMix, Trigger};
use vigie_core::pop::transients::{Config, run};
use vigie_core::sim::{OperatorAction, Options, Simulation};

fn station() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

/// `vigie campaign transients --only ONLY` on the station over `seeds`, with
/// `fault_free_hours` of production after it (two threads).
fn campaign(
    only: &str,
    seeds: std::ops::Range<u64>,
    fault_free_hours: u64,
) -> (Config, vigie_core::pop::transients::Report) {
    campaign_in(&station(), only, seeds, fault_free_hours)
}

/// [`campaign`] on the plant folder `dir`.
fn campaign_in(
    dir: &std::path::Path,
    only: &str,
    seeds: std::ops::Range<u64>,
    fault_free_hours: u64,
) -> (Config, vigie_core::pop::transients::Report) {
    let config = Config {
        first_seed: seeds.start,
        seeds: seeds.end - seeds.start,
        only: Some(only.into()),
        threads: 2,
        fault_free_hours,
        ..Config::default()
    };
    let report = run(dir, &config).unwrap();
    (config, report)
}

/// Every case of `report` struck, with no hazard (and, with `no_wrong`, no wrong certain
/// diagnosis).
fn assert_struck_without_hazard(report: &vigie_core::pop::transients::Report, no_wrong: bool) {
    for r in &report.rows {
        assert!(r.injected > 0, "{}", r.name);
        assert_eq!(r.hazards, 0, "{}: {:?}", r.name, r.failures);
        if no_wrong {
            assert_eq!(r.wrong, 0, "{}: {:?}", r.name, r.failures);
        }
    }
}

fn production(seed: u64) -> Simulation {
    let dir = station();
    let (bundle, _) = vigie_core::bundle::PlantBundle::load(&dir).unwrap();
    let program = vigie_core::control::CompiledProgram::load(
        &dir.join("programs/reference.ron"),
        &bundle.plant,
    )
    .unwrap();
    let mut sim = Simulation::new(
        bundle,
        program,
        seed,
        Options {
            history_cycles: 16,
            explain: false,
        },
    )
    .unwrap();
    sim.enable_diagnosers().unwrap();
    sim.emulator.set_arrivals(ArrivalPlan::Periodic {
        period_ms: 8_000,
        jitter_ms: 1_000,
        mix: SizeMix::Alternate,
        count: None,
    });
    sim.act(&OperatorAction::Start).unwrap();
    sim
}

/// Runs until `input` has read `value` without a break for `after_ms` (bounded), then
/// injects `fault`; returns its time.
fn strike_after(
    sim: &mut Simulation,
    input: &str,
    value: bool,
    after_ms: u64,
    fault: FaultKind,
) -> u64 {
    let i = sim.bundle.plant.input(input).unwrap();
    let limit = Millis(sim.now().0 + 120_000);
    let mut since = None;
    while sim.now() < limit {
        if sim.emulator.sensors().get(i) == value {
            let s = *since.get_or_insert(sim.now().0);
            if sim.now().0 >= s + after_ms {
                let at = sim.now().0;
                sim.inject(FaultSpec {
                    trigger: Trigger::At(at),
                    fault,
                    duration_ms: None,
                })
                .unwrap();
                return at;
            }
        } else {
            since = None;
        }
        sim.cycle();
    }
    panic!("{input} never read {value} for {after_ms} ms");
}

/// Runs until `sensor` has been on for `after_ms` (bounded), then drops it out for
/// `length_ms`; returns the time of the dropout.
fn drop_out_while_a_box_crosses(
    sim: &mut Simulation,
    sensor: &str,
    after_ms: u64,
    length_ms: u64,
) -> u64 {
    let fault = FaultKind::SpuriousFall {
        sensor: sensor.into(),
        pulse_ms: length_ms,
    };
    strike_after(sim, sensor, true, after_ms, fault)
}

/// Runs until `input` has read `value` for `after_ms` (bounded), then a pulse of
/// `sensor` of `length_ms`; returns its time.
fn pulse_after(
    sim: &mut Simulation,
    input: &str,
    value: bool,
    after_ms: u64,
    sensor: &str,
    length_ms: u64,
) -> u64 {
    let fault = FaultKind::SpuriousRise {
        sensor: sensor.into(),
        pulse_ms: length_ms,
    };
    strike_after(sim, input, value, after_ms, fault)
}

/// The transient of `sensor` was held (journaled as suspect), the filter never tripped
/// and production went on (at least `boxes` delivered).
#[track_caller]
fn held_without_trip(sim: &Simulation, seed: u64, sensor: &str, boxes: u32) {
    assert!(
        sim.engine.trips.is_empty(),
        "seed {seed}, transient of {sensor}: {} trips",
        sim.engine.trips.len()
    );
    assert!(
        sim.journal()
            .iter()
            .any(|j| j.kind == "plausibility" && j.text.contains(&format!("{sensor} suspect"))),
        "seed {seed}: the held edge of {sensor} is journaled"
    );
    let s = sim.emulator.stats();
    assert!(
        s.delivered_total() >= boxes,
        "seed {seed}: production goes on"
    );
}

#[test]
fn a_dropout_of_c7_while_a_box_leaves_to_the_right_shears_nothing() {
    for (seed, after, length) in [(1, 200, 40), (2, 300, 80), (3, 100, 20), (4, 500, 300)] {
        let mut sim = production(seed);
        sim.run_until(Millis(20_000));
        let at = drop_out_while_a_box_crosses(&mut sim, "C7", after, length);
        sim.run_until(Millis(at + 30_000));
        assert!(
            sim.emulator.hazards().is_empty(),
            "seed {seed}, dropout of {length} ms {after} ms into the crossing: {:?}",
            sim.emulator.hazards()
        );
        held_without_trip(&sim, seed, "C7", 4);
    }
}

#[test]
fn a_late_dropout_of_an_exit_beam_releases_no_table_under_a_box() {
    // Alternate sizes and sides: the boxes leaving left are large (1.27 s at C8), those
    // leaving right small (1 s at C7).
    for (seed, sensor, after, length) in [
        (1, "C8", 950, 300),
        (2, "C8", 1_050, 100),
        (3, "C8", 1_100, 500),
        (4, "C8", 1_000, 20),
        (5, "C7", 950, 200),
        (6, "C7", 920, 50),
    ] {
        let mut sim = production(seed);
        sim.run_until(Millis(20_000));
        let at = drop_out_while_a_box_crosses(&mut sim, sensor, after, length);
        sim.run_until(Millis(at + 30_000));
        assert!(
            sim.emulator.hazards().is_empty(),
            "seed {seed}, {sensor} out {length} ms {after} ms into the crossing: {:?}",
            sim.emulator.hazards()
        );
        assert!(sim.engine.trips.is_empty(), "seed {seed}: a trip");
        let s = sim.emulator.stats();
        assert!(s.delivered_total() >= 4, "seed {seed}: production goes on");
    }
}

#[test]
fn a_pulse_of_c4_while_the_table_comes_back_loads_no_box_onto_it() {
    // C5 off and C4 off: the table is on its way back (or out); the pulse comes late
    // in the return, when a box waits at C3 for the table.
    for (seed, after, length) in [
        (1, 2_400, 20),
        (2, 2_600, 100),
        (3, 1_500, 500),
        (4, 2_550, 10),
    ] {
        let mut sim = production(seed);
        sim.run_until(Millis(20_000));
        // Wait for the table to leave C5 (its return), then `after` ms of C4 off.
        let c5 = sim.bundle.plant.input("C5").unwrap();
        let limit = Millis(sim.now().0 + 60_000);
        while !sim.emulator.sensors().get(c5) && sim.now() < limit {
            sim.cycle();
        }
        while sim.emulator.sensors().get(c5) && sim.now() < limit {
            sim.cycle();
        }
        assert!(sim.now() < limit, "seed {seed}: the table never came back");
        let left = sim.now().0;
        let at = pulse_after(&mut sim, "C4", false, after, "C4", length);
        assert!(
            at - left < 2_900,
            "seed {seed}: the pulse came after the table"
        );
        sim.run_until(Millis(at + 30_000));
        assert!(
            sim.emulator.hazards().is_empty(),
            "seed {seed}, pulse of {length} ms {} ms into the return: {:?}",
            at - left,
            sim.emulator.hazards()
        );
        let s = sim.emulator.stats();
        assert!(s.delivered_total() >= 4, "seed {seed}");
    }
}

/// A pulse of C3 while a box is on its way (10 seeds of every length: 5 hazards
/// before C3 was read as possibly on while suspect), its dropouts and its flicker.
#[test]
fn the_campaigns_c3_transients_push_no_box_onto_the_table() {
    let (config, report) = campaign("C3 ", 0..10, 0);
    assert_eq!(report.rows.len(), 2 * config.lengths_ms.len() + 1);
    assert_struck_without_hazard(&report, true);
}

/// A pulse of C4 accepted 2.85 s after A4's release came 50 ms before the table, which
/// docks 45 ms after C4 rises: the box was loaded onto a table still turning (5 hazards
/// of 500 ms pulses in seeds 40 to 99). C4 rises no sooner than 2.89 s after it (the
/// table's return takes 2.90 s at the fastest on the rule's clock).
#[test]
fn a_pulse_of_c4_just_before_the_table_docks_loads_no_box_onto_it() {
    let (config, report) = campaign("C4 pulse", 40..100, 0);
    assert_eq!(report.rows.len(), config.lengths_ms.len());
    assert_struck_without_hazard(&report, false);
}

/// A dropout of C0 while a box waits there and A1 runs for the box ahead was taken as
/// the box leaving (the fall was plausible with A1 on): the program ran A0, and once
/// C3's fall stopped A1 the box was pushed against the stopped belt, with CSc1 blind
/// (11 hazards of 200 and 500 ms dropouts in seeds 7 to 31). A box leaves C0 only with
/// its front already at C1: C0 falls only while C1 is on.
#[test]
fn a_dropout_of_c0_while_the_box_waits_pushes_it_against_no_stopped_belt() {
    let (config, report) = campaign("C0 dropout", 0..32, 0);
    assert_eq!(report.rows.len(), config.lengths_ms.len());
    assert_struck_without_hazard(&report, true);
}

/// A pulse of C6 just after C3 falls (the real box's front still 130 ms from C6) was
/// taken for the box: the program stopped the rollers and turned the table with the box
/// on its edge (4 hazards in 100 seeds, 2 in seeds 60 to 89). C6 rises no sooner than
/// 100 ms after C3 falls (`rise_not_after`). A pulse taken for a box sends a phantom to
/// an exit, whose model then blamed C7 with certainty (5 wrong in seeds 60 to 89): its
/// beam partitions wait while the c6 model suspects C6 (`assumes_item`).
#[test]
fn a_pulse_of_c6_just_after_c3_falls_turns_no_table_under_a_box() {
    let (config, report) = campaign("C6 pulse", 60..90, 0);
    assert_eq!(report.rows.len(), config.lengths_ms.len());
    assert_struck_without_hazard(&report, true);
}

/// A dropout of C5 while the table has just reached it (its arrival window I4 still
/// open) was diagnosed, rightly, as a fault of C5, but C5's estimate from the windows
/// (pessimistic: reached once I4 has closed) read the table as gone: CSs5 tripped with
/// the box half out, and after the restart the right exit blamed C7 with certainty (17
/// wrong, 27 trips in 700 runs; 14 wrong in seeds 40 to 99). The model saw the table
/// arrive and explains the dropout by C5: the estimate is the plant state's value.
#[test]
fn a_dropout_of_c5_at_the_tables_arrival_neither_trips_nor_blames_c7() {
    let (config, report) = campaign("C5 dropout", 40..100, 0);
    assert_eq!(report.rows.len(), config.lengths_ms.len());
    assert_struck_without_hazard(&report, true);
    for r in &report.rows {
        assert_eq!(r.trips, 0, "{}: {:?}", r.name, r.failures);
    }
}

/// Replaying one run gives its changes of signals, so that a technician can read what
/// the program, the observers and the stage did around the failure.
#[test]
fn a_replayed_run_gives_its_changes_of_signals() {
    let config = Config {
        first_seed: 7,
        seeds: 1,
        only: Some("C0 dropout 500 ms".into()),
        threads: 1,
        fault_free_hours: 0,
        changes: true,
        ..Config::default()
    };
    // The station as it was before C0's fall waited for C1, where seed 7 fails (a
    // failed run's changes are reported).
    let dir = crate::bad_input::station_copy("transients-c0-old-rule");
    let plant = dir.join("plant.ron");
    let text = std::fs::read_to_string(&plant).unwrap();
    let old = text.replace(
        r#"fall_when: Some("C1* . (A0* + A1*)")"#,
        r#"fall_when: Some("A0* + A1*")"#,
    );
    assert_ne!(old, text, "C0's fall rule is in plant.ron");
    std::fs::write(&plant, old).unwrap();
    let report = run(&dir, &config).unwrap();
    let row = &report.rows[0];
    assert_eq!(row.hazards, 1, "{:?}", row.failures);
    let changes = &row.first_failure_changes;
    assert!(
        changes
            .iter()
            .any(|l| l.contains("C0=0") && l.contains("A0=1")),
        "the dropout and the program's A0 in one cycle: {changes:?}"
    );
    assert!(changes.iter().all(|l| l.contains(" ms: ")));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_pulse_of_an_exit_beam_with_the_table_empty_neither_trips_nor_stops_production() {
    for (seed, sensor, length) in [(1, "C7", 50), (2, "C8", 200), (3, "C7", 500), (4, "C8", 10)] {
        let mut sim = production(seed);
        sim.run_until(Millis(20_000));
        // The table at C4 and empty (C6 off) for a while.
        let c6 = sim.bundle.plant.input("C6").unwrap();
        let limit = Millis(sim.now().0 + 60_000);
        while sim.now() < limit
            && (sim.emulator.sensors().get(c6)
                || !sim
                    .emulator
                    .sensors()
                    .get(sim.bundle.plant.input("C4").unwrap()))
        {
            sim.cycle();
        }
        let at = pulse_after(&mut sim, "C6", false, 300, sensor, length);
        sim.run_until(Millis(at + 40_000));
        assert!(
            sim.emulator.hazards().is_empty(),
            "seed {seed}: {:?}",
            sim.emulator.hazards()
        );
        held_without_trip(&sim, seed, sensor, 5);
    }
}

#[test]
fn the_campaigns_table_and_exit_pulses_give_no_hazard_and_production_comes_back() {
    let (config, report) = campaign("pulse", 0..4, 0);
    let rows: Vec<_> = report
        .rows
        .iter()
        .filter(|r| {
            ["C4 ", "C5 ", "C7 ", "C8 "]
                .iter()
                .any(|s| r.name.starts_with(s))
        })
        .collect();
    assert_eq!(rows.len(), 4 * config.lengths_ms.len());
    for r in &rows {
        assert!(r.injected > 0, "{}", r.name);
        assert_eq!(r.hazards, 0, "{}: {:?}", r.name, r.failures);
        assert_eq!(r.not_restored, 0, "{}: {:?}", r.name, r.failures);
        assert_eq!(r.wrong, 0, "{}: {:?}", r.name, r.failures);
    }
}

#[test]
fn the_campaigns_beam_dropouts_give_no_hazard_and_production_comes_back() {
    let (config, report) = campaign("dropout", 0..6, 1);
    let rows: Vec<_> = report
        .rows
        .iter()
        .filter(|r| ["C6 ", "C7 ", "C8 "].iter().any(|s| r.name.starts_with(s)))
        .collect();
    assert_eq!(rows.len(), 3 * config.lengths_ms.len());
    for r in &rows {
        assert!(r.injected > 0, "{}", r.name);
        assert_eq!(r.hazards, 0, "{}: {:?}", r.name, r.failures);
    }
    let restored: usize = rows.iter().map(|r| r.restored).sum();
    let injected: usize = rows.iter().map(|r| r.injected).sum();
    assert!(
        restored * 4 >= injected * 3,
        "{restored} of {injected} restored"
    );
    let ff = &report.fault_free;
    assert_eq!(ff.hours, 1);
    assert_eq!(
        ff.held_edges, 0,
        "a plausibility rule holds a real edge: {:?}",
        ff.examples
    );
    assert_eq!(ff.trips + ff.hazards + ff.diagnoses, 0, "{:?}", ff.examples);
    assert!(ff.delivered > 300, "{}", ff.delivered);
}

/// A rule that holds a rise on what an upstream sensor said (a box reaches C6 only after
/// it left C3, C7 only after it cleared C6: tried) blinds the constraints when that
/// sensor sticks: stuck at 1, C3 never falls, the box on the table went unseen (held at
/// 0) and was pushed off it (18 hazards on 20 seeds, 0 without the rules); C6 stuck at
/// 1 hid every box at C7 and the table was released under it (12, 0 without). A sensor
/// stuck at 1 must never give more hazards with the rules than read as it is.
/// (Stuck at 0, C0, C3 and C6 give hazards with or without the rules: a dead beam
/// blinds the constraints that read it, and which box meets it depends on when the
/// production stops.)
#[test]
fn a_sensor_stuck_at_1_gives_no_more_hazards_with_the_plausibility_rules_than_without() {
    let sensors = [
        "C0", "C1", "C2", "C3", "C4", "C5", "C6", "C7", "C8", "C9", "C10",
    ];
    for sensor in sensors {
        for one in [true] {
            let mut hazards = [0usize; 2];
            for (k, rules) in [false, true].into_iter().enumerate() {
                for seed in 0..6u64 {
                    let mut sim = production(seed);
                    sim.engine.set_plausibility(rules);
                    let at = 20_000 + (seed * 7_919) % 40_000;
                    sim.run_until(Millis(at));
                    let fault = if one {
                        FaultKind::SensorStuckAt1(sensor.into())
                    } else {
                        FaultKind::SensorStuckAt0(sensor.into())
                    };
                    sim.inject(FaultSpec {
                        trigger: Trigger::At(at),
                        fault,
                        duration_ms: None,
                    })
                    .unwrap();
                    sim.run_until(Millis(at + 60_000));
                    hazards[k] += sim.emulator.hazards().len();
                }
            }
            assert!(
                hazards[1] <= hazards[0],
                "{sensor} stuck at {}: {} hazards with the rules, {} without",
                u8::from(one),
                hazards[1],
                hazards[0]
            );
        }
    }
}

/// Issue 17: a dead intermediate belt under a box pushed from C0 reads, for a while,
/// like a C1 stuck at 0 (the feed model cannot tell them apart), and the entry conveyor
/// went on bringing boxes that collided with the stuck one (48 hazards of other
/// elements than A1 in 100 seeds; seed 2: boxes 5, 6 and 7). The feed model, certainly
/// faulty with a stopping fault among its candidates, now stops the plant on the safe
/// side: only the pushed box itself is damaged (the push that meets a dead belt, which
/// no sensor shows before it happens), and the stop says it is ambiguous.
#[test]
fn a_dead_belt_under_a_pushed_box_stops_the_plant_before_the_next_box_collides() {
    // The paper's station: the shipped one's mirror contact shows the dead belt's
    // contactor open the next cycle and stops the plant before the diagnosers.
    let tmp = crate::live::TempDir::new("dead-belt");
    let paper = crate::paper_station_in(&tmp.0);
    let (_, report) = campaign_in(&paper, "A1 dead", 0..12, 0);
    let row = &report.rows[0];
    assert!(row.runs == 12 && row.injected == 12, "{row:?}");
    assert_eq!(row.hazards, row.own_hazards, "{:?}", row.failures);
    assert!(
        row.hazards <= row.runs,
        "one damaged box per run at most: {:?}",
        row.failures
    );
    assert_eq!(row.wrong, 0, "{:?}", row.failures);
    assert!(
        row.first_failure_journal
            .iter()
            .any(|l| l.contains("ambiguous between") && l.contains("safe side")),
        "{:#?}",
        row.first_failure_journal
    );
}

/// Issue 17 (a welded actuator is not blamed on a sensor with certainty): a welded
/// entry conveyor pushes the box waiting at C0 onto the belt behind the belt's own box.
/// The feed follows one box: C1 rising there read as `C1_stuck1|C1_rise`, certain at
/// once (84 of 100 runs blamed C1 or C3; seeds 1, 4 and 6 blamed C1). Its beams'
/// decisions now wait `confirm_ms` (4 s): the pushed box clears C0 unordered, which no
/// fault of a beam explains, and the feed loses track and claims nothing.
#[test]
fn a_welded_entry_conveyor_is_not_blamed_on_c1() {
    for (seed, row) in welded_runs_not_blamed_on_a_sensor("A0 welded", &[1, 4, 6]) {
        assert!(
            row.first_failure_journal
                .iter()
                .any(|l| l.contains("unexplained") && l.contains("(feed)")),
            "seed {seed}: the feed loses track: {:#?}",
            row.first_failure_journal
        );
    }
}

/// Issue 17 (a welded actuator is not blamed on a sensor with certainty): a welded
/// intermediate belt pushes the box at C3 onto the table while the rollers load it, and
/// its front reaches C6 sooner than the rollers alone bring it (1.25 s after their
/// order, against 1.38 s at the soonest). The table's model had only C6's own faults
/// for that, and said `C6_stuck1|C6_rise|C6_fall` with certainty (seeds 5, 89, 98).
/// `C6_pushed` (the loading's window, untimed) now explains it too: the sensor is not
/// blamed, and the welded belt's damage stays its own.
#[test]
fn a_welded_belt_that_pushes_the_box_onto_the_table_is_not_blamed_on_c6() {
    welded_runs_not_blamed_on_a_sensor("A1 welded", &[5, 89, 98]);
}

/// One run of the actuator fault `only` per seed on the paper's station (no mirror
/// contact: the diagnosers alone see the weld), each struck, with no wrong certain
/// diagnosis and no hazard but the faulted actuator's own; the rows, by seed.
fn welded_runs_not_blamed_on_a_sensor(
    only: &str,
    seeds: &[u64],
) -> Vec<(u64, vigie_core::pop::transients::Row)> {
    let tmp = crate::live::TempDir::new("welded");
    let paper = crate::paper_station_in(&tmp.0);
    seeds
        .iter()
        .map(|&seed| {
            let (_, mut report) = campaign_in(&paper, only, seed..seed + 1, 0);
            let row = report.rows.remove(0);
            assert_eq!(row.injected, 1, "{row:?}");
            assert_eq!(row.wrong, 0, "seed {seed}: {:?}", row.failures);
            assert_eq!(
                row.hazards, row.own_hazards,
                "seed {seed}: {:?}",
                row.failures
            );
            (seed, row)
        })
        .collect()
}

/// Every struck run of `report` without hazard or wrong certain diagnosis, and with
/// production restored by the reset.
fn assert_restored(report: &vigie_core::pop::transients::Report) {
    assert_struck_without_hazard(report, true);
    for r in &report.rows {
        assert_eq!(r.not_restored, 0, "{}: {:?}", r.name, r.failures);
    }
}

/// Issue 17 (recovery): a pulse of C3 became a box for the program and P36, which then
/// waited for a box that never reached C6 and refused every reset (210 of 700 C3 pulses
/// not restored; seeds 3 to 9 had 13). C3 is now held at 1 until the
/// reading comes back (`hold_until_back`): the program's phantom box and the real one
/// become one. The c6 model, which ordered the loading on that lie, waits while the
/// stage holds C3 and restarts when it ends (it claimed C6 faults 6 to 8 s later).
#[test]
fn a_pulse_of_c3_leaves_no_phantom_box_and_production_comes_back() {
    let (_, report) = campaign("C3 pulse", 3..10, 0);
    assert_restored(&report);
}

/// Issue 17 (recovery): a dropout of C3 in the first scans of the table pulling the
/// box that waited there was taken for the box leaving: P36 and the program waited for
/// a box at C6 that the table had already brought, the filter tripped and refused every
/// reset. The box now leaves C3 only once the drives under it (the belt, or the rollers
/// with the table at C4) have run the shortest box's length in all since it came
/// (`fall_when_total_ms`): the dropout is held, nothing trips.
#[test]
fn a_dropout_of_c3_as_the_table_pulls_the_box_is_held_and_production_goes_on() {
    for (seed, length) in [
        (0u64, 20u64),
        (1, 50),
        (2, 100),
        (3, 200),
        (4, 500),
        (5, 300),
    ] {
        let mut sim = production(seed);
        sim.run_until(Millis(20_000));
        let plant = &sim.bundle.plant;
        let c3 = plant.input("C3").unwrap();
        let rollers = [plant.output("A2").unwrap(), plant.output("A3").unwrap()];
        let limit = Millis(sim.now().0 + 60_000);
        // The box at C3 and the rollers pulling it for 40 ms.
        let mut since = None;
        while sim.now() < limit {
            let pulling = sim.emulator.sensors().get(c3)
                && rollers.iter().any(|&a| sim.engine.applied().get(a));
            if !pulling {
                since = None;
            } else if sim.now().0 >= *since.get_or_insert(sim.now().0) + 40 {
                break;
            }
            sim.cycle();
        }
        assert!(
            sim.now() < limit,
            "seed {seed}: the table never pulled a box"
        );
        let at = sim.now().0;
        sim.inject(FaultSpec {
            trigger: Trigger::At(at),
            fault: FaultKind::SpuriousFall {
                sensor: "C3".into(),
                pulse_ms: length,
            },
            duration_ms: None,
        })
        .unwrap();
        sim.run_until(Millis(at + 40_000));
        assert!(
            sim.emulator.hazards().is_empty(),
            "seed {seed}: {:?}",
            sim.emulator.hazards()
        );
        held_without_trip(&sim, seed, "C3", 4);
    }
}

/// Issue 17 (recovery): the campaign's C3 dropouts that ended with production stopped
/// for good (seed 6 of 20 ms, seeds 0 and 10 of 500 ms: the box taken for gone, or a
/// stop half-way through its pull that lost the distance already driven), now
/// restored, with no hazard and no wrong diagnosis.
#[test]
fn the_campaigns_c3_dropouts_that_stopped_production_for_good_are_restored() {
    let (_, report) = campaign("C3 dropout", 0..12, 0);
    assert_restored(&report);
}

/// Issue 17 (recovery): a pulse of C6 while the table pulls a box off C3 is a box on
/// the table for the program and the stage (a box leaves the table only at C5: C6 is
/// held at 1), the filter trips and every reset is refused, for good (about 105 of the
/// campaign's 700 C6 pulses). The operator checks the plant and re-initialises: the
/// program restarts from its initial steps, the observers with no room left between
/// their sensors are cleared, the sensors are taken as read; production comes back.
#[test]
fn a_phantom_box_at_c6_refuses_the_reset_and_the_reinitialisation_restores_production() {
    let path = station().join("scenarios/c6-phantom.ron");
    let scenario = vigie_core::sim::Scenario::load(&path).unwrap();
    let mut sim = Simulation::from_scenario(&scenario, &path, Options::default()).unwrap();
    sim.run_until(Millis(29_500));
    assert_eq!(sim.engine.trips.len(), 1, "the phantom trips the filter");
    assert!(
        sim.engine.is_tripped(),
        "the reset at 29 s is refused: {:?}",
        sim.journal().iter().rev().take(6).collect::<Vec<_>>()
    );
    let before = sim.emulator.stats();
    sim.run_until(Millis(scenario.duration_ms));
    assert!(!sim.engine.is_tripped(), "re-initialised at 30 s");
    assert!(
        sim.journal().iter().any(|j| j.kind == "reinitialise"),
        "the re-initialisation is journaled"
    );
    assert_eq!(sim.engine.trips.len(), 1);
    assert!(
        sim.emulator.hazards().is_empty(),
        "{:?}",
        sim.emulator.hazards()
    );
    // The operator took the boxes off, and production came back with the next ones
    // (every 8 s or so, for 60 s).
    let s = sim.emulator.stats();
    assert!(s.removed > 0, "{s:?}");
    let delivered = |s: &vigie_core::emulator::BoxStats| s.delivered_total();
    assert!(
        delivered(&s) >= delivered(&before) + 5,
        "production came back: {before:?} then {s:?}"
    );
}

/// Issue 17 (recovery): the campaign's C6 pulses of 500 ms, restored (seeds 1 and 9
/// were not before the operator's re-initialisation: the campaign's operator resets,
/// resets the diagnosers, then, the plant checked, re-initialises).
#[test]
fn the_campaigns_c6_phantoms_are_restored_by_the_reinitialisation() {
    let (_, report) = campaign("C6 pulse 500 ms", 0..12, 0);
    assert_restored(&report);
}

/// Issue 17 (no wrong certain diagnosis): a C5 flicker made the table's model restart
/// on the estimate, CSs5 tripped mid-evacuation, and after the operator's resets the
/// right exit's model, restarted with the box half-way at an unknown clock, blamed C7
/// (or C8) with certainty (seeds 25, 56, 69, 82 and 83 of 100). Every component now
/// decides nothing with certainty after a reset until it is back in its initial state
/// with the normal mode only.
#[test]
fn after_a_c5_flicker_and_the_resets_no_exit_beam_is_blamed() {
    for seeds in [20..30, 50..60, 65..70, 80..85] {
        let (_, report) = campaign("C5 flicker", seeds, 0);
        assert_restored(&report);
    }
}
