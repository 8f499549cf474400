use super::*;

fn station_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

fn scenario(
    program: ProgramChoice,
    filter: FilterMode,
    arrivals: ArrivalPlan,
    duration_ms: u64,
) -> Scenario {
    Scenario {
        name: "test".into(),
        description: String::new(),
        plant: ".".into(),
        program,
        seed: 7,
        arrivals: Some(arrivals),
        faults: Vec::new(),
        actions: vec![TimedAction {
            at_ms: 0,
            action: OperatorAction::Start,
        }],
        duration_ms,
        filter,
        cycle_ms: 10,
        projection_ms: 10_000,
        diagnosers: false,
        plausibility: true,
    }
}

fn run(s: &Scenario) -> Simulation {
    // The scenario path only anchors `plant` (".") on the station folder.
    let path = station_dir().join("scenario.ron");
    let mut sim = Simulation::from_scenario(s, &path, Options::default()).expect("scenario");
    sim.run_until(Millis(s.duration_ms));
    sim
}

/// Three boxes, both sides: small (right), large (left), small (right).
fn three_boxes() -> ArrivalPlan {
    use crate::emulator::BoxSize::{Large, Small};
    ArrivalPlan::List(vec![(0, Small), (12_000, Large), (24_000, Small)])
}

/// Six boxes arriving faster than the table can sort them: they queue at the source and
/// follow each other closely, as in a busy shift.
fn busy_shift() -> ArrivalPlan {
    use crate::emulator::BoxSize::{Large, Small};
    ArrivalPlan::List(
        (0..6)
            .map(|k| (k * 4_000, if k % 2 == 0 { Small } else { Large }))
            .collect(),
    )
}

#[test]
fn reference_program_runs_an_hour_without_trip_or_hazard() {
    let path = station_dir().join("scenarios/reference-hour.ron");
    let s = Scenario::load(&path).expect("scenario loads");
    let mut sim = Simulation::from_scenario(
        &s,
        &path,
        Options {
            history_cycles: 100,
            explain: true,
        },
    )
    .expect("starts");
    sim.run_until(Millis(s.duration_ms));
    let stats = sim.emulator.stats();
    assert!(
        sim.engine.trips.is_empty(),
        "{:?}",
        sim.engine.trips.first()
    );
    assert!(
        sim.emulator.hazards().is_empty(),
        "{:?}",
        sim.emulator.hazards().first()
    );
    assert!(stats.created >= 200, "{stats:?}");
    assert_eq!(stats.delivered_total(), stats.created, "{stats:?}");
    assert_eq!(stats.damaged, 0);
    assert!(
        stats.delivered_at("left_exit") > 0 && stats.delivered_at("right_exit") > 0,
        "{stats:?}"
    );
}

/// Every variant of the control-error library: without the filter the plant is damaged
/// (or, for the variants whose consequence is functional, production stops: fewer boxes
/// delivered than by the reference program); with it the filter trips first on the
/// variant's declared constraint and nothing is damaged.
#[test]
fn every_error_variant_is_caught_by_its_constraint() {
    let lib = ErrorLibrary::load(
        &station_dir().join("programs/errors.ron"),
        &crate::plant::Plant::load(&station_dir().join("plant.ron")).expect("plant"),
    )
    .expect("library");
    let with_hazard = lib
        .variants
        .iter()
        .filter(|v| v.def.consequence == crate::control::Consequence::Hazard)
        .count();
    assert!(with_hazard >= 10, "{with_hazard} variants damage the plant");
    let reference = run(&scenario(
        ProgramChoice::Reference,
        FilterMode::Off,
        busy_shift(),
        120_000,
    ));
    let delivered = |s: &Simulation| s.emulator.stats().delivered_total();
    let mut failures = Vec::new();
    for v in &lib.variants {
        let id = &v.def.id;
        let off = run(&scenario(
            ProgramChoice::Error(id.clone()),
            FilterMode::Off,
            busy_shift(),
            120_000,
        ));
        match v.def.consequence {
            crate::control::Consequence::Hazard if off.emulator.hazards().is_empty() => {
                failures.push(format!("{id}: no hazard without the filter"));
            }
            crate::control::Consequence::Functional if delivered(&off) >= delivered(&reference) => {
                failures.push(format!("{id}: production not disrupted without the filter"));
            }
            _ => {}
        }
        let on = run(&scenario(
            ProgramChoice::Error(id.clone()),
            FilterMode::Enforce,
            busy_shift(),
            120_000,
        ));
        let first = on.engine.trips.first().map(|t| {
            t.constraints
                .iter()
                .map(|c| c.id.clone())
                .collect::<Vec<_>>()
        });
        match &first {
            Some(ids) if ids.contains(&v.def.expected_constraint) => {}
            other => failures.push(format!(
                "{id}: expected a trip on {}, got {other:?}",
                v.def.expected_constraint
            )),
        }
        if !on.emulator.hazards().is_empty() {
            failures.push(format!(
                "{id}: hazard with the filter: {:?}",
                on.emulator.hazards()[0]
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn reference_program_copes_with_a_busy_shift() {
    let sim = run(&scenario(
        ProgramChoice::Reference,
        FilterMode::Enforce,
        busy_shift(),
        120_000,
    ));
    assert!(
        sim.engine.trips.is_empty(),
        "{:?}",
        sim.engine.trips.first()
    );
    assert!(
        sim.emulator.hazards().is_empty(),
        "{:?}",
        sim.emulator.hazards().first()
    );
    let stats = sim.emulator.stats();
    assert_eq!(stats.delivered_total(), 6, "{stats:?}");
}

#[test]
fn same_scenario_and_seed_give_identical_reports() {
    let s = scenario(
        ProgramChoice::Error("E01".into()),
        FilterMode::Enforce,
        three_boxes(),
        40_000,
    );
    let a = serde_json::to_string(&run(&s).report(s.seed)).expect("json");
    let b = serde_json::to_string(&run(&s).report(s.seed)).expect("json");
    assert_eq!(a, b);
    let periodic = ArrivalPlan::Periodic {
        period_ms: 9_000,
        jitter_ms: 3_000,
        mix: crate::emulator::SizeMix::RandomLarge(50),
        count: None,
    };
    let mut s1 = scenario(
        ProgramChoice::Reference,
        FilterMode::Enforce,
        periodic,
        60_000,
    );
    let r1 = serde_json::to_string(&run(&s1).report(s1.seed)).expect("json");
    s1.seed += 1;
    let r2 = serde_json::to_string(&run(&s1).report(s1.seed)).expect("json");
    assert_ne!(r1, r2, "another seed gives other arrivals");
}

#[test]
fn the_papers_cs10_case_is_explained_with_a_projection() {
    let path = station_dir().join("scenarios/cs10-paper.ron");
    let s = Scenario::load(&path).expect("scenario");
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    sim.run_until(Millis(s.duration_ms));
    assert_eq!(sim.engine.trips.len(), 1);
    assert_eq!(sim.engine.trips[0].constraints[0].id, "CSs10");
    assert!(sim.emulator.hazards().is_empty());
    let ex = &sim.explanations[&0];
    let p = &sim.projections[&0];
    assert!(
        p.hazards
            .iter()
            .any(|h| serde_json::to_value(h.kind).ok() == Some(serde_json::json!("sheared"))),
        "{:?}",
        p.hazards
    );
    assert_eq!(ex.projection.items[0].code, "X101");
    // The held A4 is the filter's doing; operator reset refused while C7 is still on.
    assert!(sim.act(&OperatorAction::Reset).is_err());
    assert!(sim.journal().iter().any(|j| j.kind == "reset_refused"));
    // The trip's alarm, in the operator's words from the constraint's own comment; the
    // formula one click away.
    let alarm = &sim.alarms.all()[0];
    assert_eq!(
        alarm.message,
        "Safety stop: box leaving to the right: hold the rotation (CSs10). Held ON: A4 \
         (Turntable). Stopped: A0 (Entry conveyor), A5 (Left exit conveyor), A6 (Right exit \
         conveyor)"
    );
    assert_eq!(alarm.detail, "CSs10 = C7 . /A4 (true at 11680 ms)");
    assert!(alarm.first_out);
}

/// While the filter holds the plant, Start is refused with the reason and the next step
/// (it would otherwise be latched into the program and start the plant at the reset);
/// Stop always works. Both are journaled; after the reset Start is taken again.
#[test]
fn start_is_refused_while_tripped_and_stop_always_works() {
    let (s, mut sim) = load_station_scenario("cs10-paper.ron");
    sim.run_until(Millis(s.duration_ms));
    assert!(sim.engine.is_tripped());
    let e = sim.act(&OperatorAction::Start).unwrap_err();
    assert_eq!(
        e,
        "refused: the safety filter has stopped the plant (CSs10); Reset first, then Start"
    );
    assert!(
        sim.journal()
            .iter()
            .any(|j| j.kind == "operator_refused" && j.text.contains("Reset first"))
    );
    sim.act(&OperatorAction::Stop).expect("Stop always works");
    // Not tripped: Start is pressed again.
    let mut fresh = load_station_scenario("cs10-paper.ron").1;
    assert!(!fresh.engine.is_tripped());
    fresh.act(&OperatorAction::Start).expect("Start taken");
}

#[test]
fn bad_scenarios_are_reported() {
    let dir = std::env::temp_dir().join(format!("vigie-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let p = dir.join("bad.ron");
    std::fs::write(
        &p,
        "Scenario(name: \"x\", program: Reference, seed: 1, duration_ms: 10, bogus: 1)",
    )
    .expect("write");
    let err = Scenario::load(&p).expect_err("unknown field");
    assert!(
        err[0].location.as_ref().is_some_and(|l| l.line == 1),
        "{err:?}"
    );
    let s = scenario(
        ProgramChoice::Error("E99".into()),
        FilterMode::Enforce,
        three_boxes(),
        10,
    );
    let err = Simulation::from_scenario(&s, &station_dir().join("s.ron"), Options::default())
        .err()
        .expect("unknown variant");
    assert_eq!(err[0].code, "V0402");
}

fn load_station_scenario(name: &str) -> (Scenario, Simulation) {
    load_scenario_in(&station_dir(), name)
}

fn load_scenario_in(dir: &Path, name: &str) -> (Scenario, Simulation) {
    let path = dir.join("scenarios").join(name);
    let s = Scenario::load(&path).expect("scenario");
    let sim = Simulation::from_scenario(
        &s,
        &path,
        Options {
            history_cycles: 100,
            explain: true,
        },
    )
    .expect("starts");
    (s, sim)
}

/// Runs the scenario written in `text` on the station to its end (as if it were a file
/// of its `scenarios/` folder) and returns its report.
fn run_station_text(text: &str) -> RunReport {
    let s: Scenario = ron::from_str(text).expect("scenario");
    let path = station_dir().join("scenarios").join("inline.ron");
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    sim.run_until(Millis(s.duration_ms));
    sim.report(s.seed)
}

/// One hour with an operator pause every 5 minutes: the pauses interrupt the tasks in
/// progress (acceptable interruptions) and no task alarm is raised.
#[test]
fn task_monitors_accept_operator_pauses_over_an_hour() {
    let (s, mut sim) = load_station_scenario("tasks-hour.ron");
    let mut interrupted_seen = 0;
    let pauses: Vec<u64> = s
        .actions
        .iter()
        .filter(|a| a.action == OperatorAction::Pause)
        .map(|a| a.at_ms)
        .collect();
    assert!(pauses.len() >= 10);
    for p in &pauses {
        sim.run_until(Millis(p + 1_000));
        let t = sim.tasks.as_ref().expect("tasks");
        interrupted_seen += t
            .monitor
            .status(sim.now())
            .iter()
            .filter(|st| st.state == crate::tasks::TaskState::Interrupted)
            .count();
    }
    sim.run_until(Millis(s.duration_ms));
    assert!(
        interrupted_seen >= pauses.len() / 2,
        "pauses interrupted only {interrupted_seen} tasks"
    );
    let report = sim.report(s.seed);
    assert!(
        report.task_alarms.is_empty(),
        "{:?}",
        report.task_alarms.first()
    );
    assert!(report.trips.is_empty() && report.hazards.is_empty());
    assert_eq!(report.boxes.delivered_total(), report.boxes.created);
}

/// Issue 19: the task monitors raise no alarm in normal production, whatever the start
/// delay or the arrival rate the reference program sustains. At the console's arrival
/// rate (a box every 8 s) every run raised a false `entry` alarm after about 90 s: the
/// task started at the box's arrival at C0, and a box waits there for the belt for up
/// to about 10 s, which the task's total bound (4.5 s) counted. It now starts with the
/// push (C0 . A0 . A1). Seeds 1 to 4, Start at 0, 5, 13 and 20 s, boxes every 7, 8 and
/// 15 s, five minutes each.
#[test]
fn task_monitors_raise_no_alarm_in_normal_production_whatever_the_start_and_rate() {
    for (period, jitter) in [(7_000, 500), (8_000, 1_000), (15_000, 2_000)] {
        for start in [0, 5_000, 13_000, 20_000] {
            for seed in 1..=4 {
                let text = format!(
                    "Scenario(name: \"late start\", program: Reference, seed: {seed}, \
                     arrivals: Some(Periodic(period_ms: {period}, jitter_ms: {jitter}, mix: Alternate)), \
                     actions: [(at_ms: {start}, action: Start)], duration_ms: 300000, \
                     filter: Enforce, diagnosers: true)"
                );
                let report = run_station_text(&text);
                let case = format!("period {period} ms, Start at {start} ms, seed {seed}");
                assert!(
                    report.task_alarms.is_empty(),
                    "{case}: {:?}",
                    report.task_alarms.first()
                );
                assert!(
                    report.trips.is_empty() && report.hazards.is_empty(),
                    "{case}"
                );
                assert!(report.boxes.delivered_total() > 15, "{case}");
            }
        }
    }
}

/// The `entry` task, now started by the push, still alarms when the pushed box never
/// shows at C1 (C1 dead from 20 s): its effective time passes β (1.5 s), at the same
/// moment as when it started at the box's arrival.
#[test]
fn the_entry_task_alarms_when_the_pushed_box_never_shows_at_c1() {
    let text = "Scenario(name: \"C1 dead\", program: Reference, seed: 1, \
                faults: [(trigger: At(20000), fault: SensorStuckAt0(\"C1\"))], \
                actions: [(at_ms: 0, action: Start)], duration_ms: 60000, \
                filter: Enforce, diagnosers: true)";
    let report = run_station_text(text);
    let a = report.task_alarms.first().expect("an alarm");
    assert_eq!(
        (a.subject.as_str(), a.time),
        ("entry", Millis(28_490)),
        "{a:?}"
    );
    assert_eq!(a.y_ms, Some(1_500), "past beta: {a:?}");
}

/// A permanent blocking of the turntable mid-rotation: the rotation task alarms when its
/// effective time passes β, earlier than the classical watchdog at start + γ.
#[test]
fn task_monitor_alarms_before_the_watchdog_on_a_blocked_table() {
    let (s, mut sim) = load_station_scenario("table-blocked.ron");
    sim.run_until(Millis(s.duration_ms));
    let report = sim.report(s.seed);
    let a = report.task_alarms.first().expect("an alarm");
    assert_eq!(a.subject, "turn_out");
    assert!(a.earlier_by_ms.is_some_and(|d| d > 0), "{a:?}");
    assert!(a.text.contains("before the watchdog"), "{}", a.text);
    assert!(
        sim.alarms
            .all()
            .iter()
            .any(|x| x.kind == crate::alarms::AlarmKind::Task)
    );
}

fn bits(text: &str) -> crate::bits::Bits {
    let v: Vec<bool> = text.chars().map(|c| c == '1').collect();
    crate::bits::Bits::from_bools(&v)
}

fn observed(time: u64, inputs: &str, commanded: &str, applied: &str, reset: bool) -> ObservedCycle {
    ObservedCycle {
        time: Millis(time),
        inputs: bits(inputs),
        commanded: bits(commanded),
        applied: bits(applied),
        reset,
        diagnosers: diagnosis::LinkStep::Skipped,
        attach: false,
        restored: None,
        followed: false,
    }
}

/// [`observed`] for the paper's eleven sensors and seven actuators, completed for the
/// shipped station as a healthy plant shows it: the safety contactors commanded and
/// applied ON, each mirror contact reading the output applied the cycle before.
fn observed_healthy(
    sim: &Simulation,
    time: u64,
    inputs: &str,
    commanded: &str,
    applied: &str,
    reset: bool,
) -> ObservedCycle {
    let plant = &sim.bundle.plant;
    let held: String = plant.outputs[commanded.len()..]
        .iter()
        .map(|o| if o.held_on { '1' } else { '0' })
        .collect();
    let mut cycle = observed(
        time,
        &format!("{inputs:0<width$}", width = plant.inputs.len()),
        &format!("{commanded}{held}"),
        &format!("{applied}{held}"),
        reset,
    );
    for (i, o) in plant.mirrors() {
        cycle.inputs.set(i, sim.engine.applied().get(o));
    }
    cycle
}

fn following(mode: FilterMode) -> Simulation {
    let mut s = scenario(
        ProgramChoice::Reference,
        FilterMode::Enforce,
        three_boxes(),
        0,
    );
    // The observed cycles are scripted, not a plant: every edge taken as read.
    s.plausibility = false;
    let mut sim =
        Simulation::from_scenario(&s, &station_dir().join("scenario.ron"), Options::default())
            .expect("scenario");
    sim.follow_link(mode);
    sim
}

#[test]
fn a_monitored_violation_is_recorded_alarmed_and_explained() {
    let mut sim = following(FilterMode::ReportOnly);
    assert!(sim.is_live());
    // C7 with A4 off: CSs10 = C7 . /A4, reported, never enforced.
    for (k, inputs) in ["00000000000", "00000001000", "00000001000"]
        .iter()
        .enumerate()
    {
        let t = 10 * (k as u64 + 1);
        sim.observe(&observed(t, inputs, "0000000", "0000000", false));
    }
    assert_eq!(sim.now(), Millis(30));
    assert_eq!(sim.engine.trips.len(), 1);
    let trip = &sim.engine.trips[0];
    assert!(!trip.enforced);
    assert_eq!(trip.time_ms, 20);
    assert!(trip.constraints.iter().any(|c| c.id == "CSs10"));
    let ex = sim.explanations.get(&0).expect("explained");
    assert!(
        !ex.projection.items.is_empty(),
        "level 1 from the observation"
    );
    assert!(
        sim.alarms
            .all()
            .iter()
            .any(|a| a.kind == AlarmKind::FilterTrip)
    );
    // The box the sensors see at C7 is drawn there.
    assert_eq!(sim.emulator.boxes().len(), 1);
    // Time never goes back.
    sim.observe(&observed(5, "00000000000", "0000000", "0000000", false));
    assert_eq!(sim.now(), Millis(30));
}

#[test]
fn a_gateway_is_mirrored_with_its_applied_outputs_and_resets() {
    let mut sim = following(FilterMode::Enforce);
    // A loaded table rotates to the unloading position, the box leaves it to the right
    // exit (C6 falls, C7 rises): the PLC commands A4 until then.
    for (t, inputs) in [
        (10, "00001010000"),
        (20, "00000110000"),
        (30, "00000100000"),
    ] {
        sim.observe(&observed_healthy(
            &sim, t, inputs, "0000100", "0000100", false,
        ));
    }
    assert!(!sim.engine.is_tripped());
    // The PLC releases A4 with the box at C7: the gateway trips on CSs10 and holds A4;
    // the mirror trips in the same cycle and records what the plant received.
    sim.observe(&observed_healthy(
        &sim,
        40,
        "00000101000",
        "0000000",
        "0000100",
        false,
    ));
    assert!(sim.engine.is_tripped());
    assert!(
        sim.engine.trips[0]
            .constraints
            .iter()
            .any(|c| c.id == "CSs10")
    );
    assert_eq!(
        sim.engine.history.last().unwrap().applied,
        bits("000010011")
    );
    assert_eq!(sim.engine.applied(), &bits("000010011"));
    // The box has left; the gateway resets before the next cycle, the mirror follows.
    sim.observe(&observed_healthy(
        &sim,
        50,
        "00000100000",
        "0000000",
        "0000100",
        false,
    ));
    assert!(sim.engine.is_tripped());
    sim.observe(&observed_healthy(
        &sim,
        60,
        "00000100000",
        "0000000",
        "0000000",
        true,
    ));
    assert!(!sim.engine.is_tripped());
    assert!(sim.journal().iter().any(|e| e.kind == "reset"));
    assert!(
        sim.alarms
            .all()
            .iter()
            .all(|a| a.kind != AlarmKind::FilterTrip || a.cleared.is_some())
    );
}

/// A monitor takes the safety devices as the PLC commands them: a PLC that leaves KM0
/// and YV0 open (their mirrors open) is not reported as commanding dead contactors
/// (it was, every cycle, when the engine held them ON); one that closes KM0 while its
/// mirror stays open is (CSk15); a gateway holds them ON whatever the PLC commands.
#[test]
fn a_monitor_takes_the_safety_devices_as_the_plc_commands_them() {
    let mut sim = following(FilterMode::ReportOnly);
    let idle = "00001000000000000000";
    // Past the mirrors' 30 ms feedback time.
    for t in [10, 20, 30, 40, 50, 60] {
        sim.observe(&observed(t, idle, "000000000", "000000000", false));
    }
    assert!(sim.engine.trips.is_empty(), "{:?}", sim.engine.trips);
    // KM0 commanded (coil 7) and applied, its mirror (input 18) stays open past its
    // 30 ms feedback time.
    for t in [70, 80, 90, 100, 110, 120] {
        sim.observe(&observed(t, idle, "000000010", "000000010", false));
    }
    let ids: Vec<&str> = sim
        .engine
        .trips
        .iter()
        .flat_map(|t| t.constraints.iter().map(|c| c.id.as_str()))
        .collect();
    assert!(ids.contains(&"CSk15"), "{ids:?}");
    // The engine of a live monitor (what it applies is what the PLC commanded): held
    // ON, KM0 reads as commanded with its mirror open, a dead contactor after 30 ms.
    let bundle = sim.bundle.clone();
    let watch = |observe: bool| {
        let mut e = crate::engine::Engine::new(&bundle, FilterMode::ReportOnly, 100);
        if observe {
            e.observe_safety_devices();
        }
        let inputs = bits(idle);
        for t in 1..=6 {
            e.cycle(Millis(10 * t), &inputs, &mut Commanded(bits("000000000")));
        }
        e.trips.len()
    };
    assert_eq!(watch(true), 0);
    assert_eq!(
        watch(false),
        1,
        "held ON, the monitor reports KM0 and YV0 dead"
    );
    // A gateway holds them ON: the commanded vector it filters has KM0 and YV0.
    let mut gw = following(FilterMode::Enforce);
    gw.observe(&observed(10, idle, "000000000", "000000011", false));
    assert_eq!(
        gw.engine.frame().now(Space::Output).to_string(),
        "000000011"
    );
}

fn following_with_diagnosers(mode: FilterMode) -> Simulation {
    let mut s = scenario(
        ProgramChoice::Reference,
        FilterMode::Enforce,
        three_boxes(),
        0,
    );
    s.diagnosers = true;
    s.plausibility = false; // scripted cycles
    let mut sim =
        Simulation::from_scenario(&s, &station_dir().join("scenario.ron"), Options::default())
            .expect("scenario");
    sim.follow_link(mode);
    sim
}

/// Observes `inputs` / `commanded` / `applied` every 10 ms from `from` (excluded) to `to`
/// (included), with the diagnosers stepped as `step`.
fn observe_span(
    sim: &mut Simulation,
    (from, to): (u64, u64),
    (inputs, commanded, applied): (&str, &str, &str),
    step: diagnosis::LinkStep,
) {
    let mut t = from + 10;
    while t <= to {
        let mut c = observed(t, inputs, commanded, applied, false);
        c.diagnosers = step;
        sim.observe(&c);
        t += 10;
    }
}

#[test]
fn a_followed_link_diagnoses_c4_stuck_at_rest_and_the_filter_reads_the_estimate() {
    use diagnosis::LinkStep::Stepped;
    let mut sim = following_with_diagnosers(FilterMode::Enforce);
    // The empty table rests at C4 (A4 off) for a second, then C4 dies.
    observe_span(
        &mut sim,
        (0, 1000),
        ("00001000000", "0000000", "0000000"),
        Stepped,
    );
    let d = sim.diagnosers.as_ref().expect("diagnosers on");
    assert!(diagnosis::at_initial_state(d, sim.engine.frame()));
    observe_span(
        &mut sim,
        (1000, 3000),
        ("00000000000", "0000000", "0000000"),
        Stepped,
    );
    let d = sim.diagnosers.as_ref().expect("diagnosers on");
    assert!(d.diagnoses.is_empty(), "{:?}", d.diagnoses);
    assert!(!diagnosis::at_initial_state(d, sim.engine.frame()));
    // Certain once no pulse end (2 s) and no motion (C5 within I4) explains the fall.
    observe_span(
        &mut sim,
        (3000, 5000),
        ("00000000000", "0000000", "0000000"),
        Stepped,
    );
    let d = sim.diagnosers.as_ref().expect("diagnosers on");
    let diag = d.diagnoses.first().expect("a certain diagnosis");
    assert_eq!(
        (diag.component.as_str(), diag.partition.as_str()),
        ("table", "C4")
    );
    assert!(diag.fault.contains("F1"), "{diag:?}");
    assert!((4000..=4300).contains(&diag.time_ms), "{diag:?}");
    assert!(
        sim.alarms
            .all()
            .iter()
            .any(|a| a.key == "diag:table:C4" && a.kind == AlarmKind::Diagnosis)
    );
    assert!(
        sim.journal()
            .iter()
            .any(|e| e.kind == "diagnosis" && e.text.contains("C4 estimated from time intervals"))
    );
    // The filter reads Ĉ4 = 1 (at rest since long, I10): the PLC rotating the empty
    // table trips CSs13 (C4 . /C6 . A4 with the estimate), not CSs14 (/C4 . RE(A4)).
    observe_span(
        &mut sim,
        (5000, 5010),
        ("00000000000", "0000100", "0000000"),
        Stepped,
    );
    let trip = sim.engine.trips.last().expect("a trip");
    let ids: Vec<&str> = trip.constraints.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(ids, ["CSs13"], "{trip:?}");
    assert!(
        trip.constraints[0]
            .literals
            .iter()
            .any(|l| l.name == "EST(C4)" && l.value),
        "{trip:?}"
    );
    // A link lost and back: the flag is kept, the estimates go on at once (no restart,
    // whatever changed meanwhile).
    use diagnosis::GateChange::{Resumed, Started, Suspended};
    let mut gate = diagnosis::LinkGate::default();
    let d = sim.diagnosers.as_ref().expect("diagnosers on");
    let (c4, none, c5) = (
        frame_with(&sim, "00001000000"),
        frame_with(&sim, "00000000000"),
        frame_with(&sim, "00000100000"),
    );
    assert_eq!(gate.step(true, d, &c4), (Stepped, Some(Started)));
    assert_eq!(
        gate.step(false, d, &none),
        (diagnosis::LinkStep::Skipped, Some(Suspended))
    );
    assert_eq!(gate.step(true, d, &c5), (Stepped, Some(Resumed)));
}

/// A frame with `inputs` at t and every output 0.
fn frame_with(sim: &Simulation, inputs: &str) -> crate::frame::Frame {
    let mut f = crate::frame::Frame::new(sim.engine.symbols.sizes());
    f.now_mut(Space::Input).copy_from(&bits(inputs));
    f
}

#[test]
fn a_followed_link_does_not_step_the_diagnosers_the_link_skipped() {
    use diagnosis::LinkStep::{Restarted, Skipped, Stepped};
    let mut sim = following_with_diagnosers(FilterMode::ReportOnly);
    observe_span(
        &mut sim,
        (0, 1000),
        ("00001000000", "0000000", "0000000"),
        Stepped,
    );
    // The peer lost for 5 s: its held values are no observation.
    observe_span(
        &mut sim,
        (1000, 6000),
        ("00000000000", "0000000", "0000000"),
        Skipped,
    );
    let d = sim.diagnosers.as_ref().expect("diagnosers on");
    assert!(d.diagnoses.is_empty(), "{:?}", d.diagnoses);
    // Nothing flagged: after a loss, the diagnosers go on when nothing changed
    // meanwhile, and restart in the initial state otherwise; no diagnosis comes from
    // the gap.
    use diagnosis::GateChange::{Restarted as Restart, Resumed, Started, Suspended};
    let (c4, none, c5) = (
        frame_with(&sim, "00001000000"),
        frame_with(&sim, "00000000000"),
        frame_with(&sim, "00000100000"),
    );
    let mut gate = diagnosis::LinkGate::default();
    assert_eq!(gate.step(false, d, &c4), (Skipped, None), "never heard yet");
    assert_eq!(gate.step(true, d, &none), (Skipped, None), "not initial");
    assert_eq!(gate.step(true, d, &c4), (Stepped, Some(Started)));
    assert_eq!(gate.step(true, d, &none), (Stepped, None));
    assert_eq!(gate.step(false, d, &none), (Skipped, Some(Suspended)));
    assert_eq!(gate.step(false, d, &c5), (Skipped, None));
    assert_eq!(
        gate.step(true, d, &none),
        (Stepped, Some(Resumed)),
        "unchanged"
    );
    assert_eq!(gate.step(false, d, &none), (Skipped, Some(Suspended)));
    assert_eq!(
        gate.step(true, d, &c5),
        (Skipped, None),
        "changed, not initial"
    );
    assert_eq!(gate.step(true, d, &c4), (Restarted, Some(Restart)));
    assert_eq!(gate.step(true, d, &none), (Stepped, None));
    observe_span(
        &mut sim,
        (6000, 6010),
        ("00001000000", "0000000", "0000000"),
        Restarted,
    );
    observe_span(
        &mut sim,
        (6010, 8000),
        ("00001000000", "0000000", "0000000"),
        Stepped,
    );
    let d = sim.diagnosers.as_ref().expect("diagnosers on");
    assert!(d.diagnoses.is_empty(), "{:?}", d.diagnoses);
}

/// A gateway restarted with a latched trip, attaching to a running plant: the mirror
/// restores the same trip and attaches at the same cycle, so it holds the same
/// fallback and sees the same edges (none on the first values read).
#[test]
fn a_followed_link_restores_its_latched_trip_and_attaches_with_it() {
    let mut earlier = following(FilterMode::Enforce);
    // The PLC commands A0 with a box at C0 and A1 off: CSc1.
    earlier.observe(&observed(10, "10000000000", "1000000", "0000000", false));
    assert!(earlier.engine.is_tripped());
    let trip = earlier.engine.trips.last().cloned().unwrap();
    let mut sim = following(FilterMode::Enforce);
    // The first values read: the table at its unloading position with A4 held; with
    // no attach the mirror would read RE(A4) away from C4 (CSs14).
    let mut first = observed(10, "00000100000", "0000100", "0000100", false);
    first.attach = true;
    first.restored = Some(trip.clone());
    sim.observe(&first);
    assert!(sim.engine.is_tripped(), "the restored trip holds");
    assert_eq!(
        sim.engine.trips,
        vec![trip],
        "no new trip on the attached cycle"
    );
}

/// The console's Start presses the button the program names (`start`); a program that
/// names none refuses Start with a message that says where to name it, and the refusal
/// is journaled.
#[test]
fn start_presses_the_programs_start_button_or_says_it_has_none() {
    let dir = station_dir();
    let (bundle, _) = crate::bundle::PlantBundle::load(&dir).unwrap();
    let path = dir.join("programs/reference.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut program = crate::control::Program::from_ron(&text, &path).unwrap();
    let compiled = |p: &crate::control::Program| {
        crate::control::CompiledProgram::new(
            p,
            &bundle.plant,
            &crate::control::Origin::new(&path, &text),
        )
        .unwrap()
    };
    let mut sim =
        Simulation::new(bundle.clone(), compiled(&program), 1, Options::default()).unwrap();
    assert!(sim.program.is_active("X0"));
    sim.act(&OperatorAction::Start).unwrap();
    sim.cycle();
    sim.cycle();
    assert!(!sim.program.is_active("X0"), "t0 fired on START");
    program.start = None;
    let without = compiled(&program);
    let mut sim = Simulation::new(bundle.clone(), without, 1, Options::default()).unwrap();
    let e = sim.act(&OperatorAction::Start).unwrap_err();
    assert!(e.contains("names no start button"), "{e}");
    assert!(
        sim.journal()
            .iter()
            .any(|j| j.text.contains("names no start button"))
    );
}

/// The index of signal `id` among `signals`.
fn index_of(signals: &[crate::plant::Signal], id: &str) -> usize {
    signals.iter().position(|s| s.id == id).expect("signal")
}

/// The value of input `id` the emulator shows now.
fn sensor(sim: &Simulation, id: &str) -> bool {
    sim.emulator
        .sensors()
        .get(index_of(&sim.bundle.plant.inputs, id))
}

/// The value of output `id` the filter applied in the last cycle.
fn applied(sim: &Simulation, id: &str) -> bool {
    sim.engine
        .frame()
        .now(Space::Output)
        .get(index_of(&sim.bundle.plant.outputs, id))
}

/// Issue 19, manual mode (seed 004, section 7): while a box leaves the turntable to the
/// right, the operator who switches the rotation off by hand is refused in his terms,
/// from the constraint's own description and the sensor that shows the box; the table
/// stays held, cycle after cycle. Entering is bumpless (the outputs stay as they were);
/// Start is refused by hand; leaving restarts the program from its initial steps.
#[test]
fn a_manual_command_that_would_break_a_constraint_is_refused_and_never_reaches_the_plant() {
    let s = scenario(
        ProgramChoice::Reference,
        FilterMode::Enforce,
        three_boxes(),
        60_000,
    );
    let path = station_dir().join("scenario.ron");
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    let mut n = 0;
    while !sensor(&sim, "C7") {
        sim.cycle();
        n += 1;
        assert!(n < 6_000, "no box reached C7 in 60 s");
    }
    sim.cycle();
    assert!(
        applied(&sim, "A4"),
        "the table is held at C5 while the box leaves"
    );
    let before = sim.engine.frame().now(Space::Output).clone();
    sim.act(&OperatorAction::Manual(true)).expect("manual");
    assert_eq!(sim.plant_state(), PlantState::Manual);
    assert_eq!(sim.manual_outputs(), Some(&before), "bumpless");
    let e = sim
        .act(&OperatorAction::ManualSet("A4".into(), false))
        .unwrap_err();
    assert_eq!(
        e,
        "A4 OFF (the turntable returns to the loading position) refused: box leaving to the \
         right: hold the rotation (CSs10, with C7 = 1)"
    );
    assert!(
        sim.journal()
            .iter()
            .any(|j| j.kind == "manual_refused" && j.text == e)
    );
    for _ in 0..20 {
        sim.cycle();
        assert!(
            applied(&sim, "A4"),
            "the refused command never reaches the plant"
        );
    }
    assert!(!sim.engine.is_tripped());
    // An allowed command is taken: the right exit conveyor off, then on again.
    sim.act(&OperatorAction::ManualSet("A6".into(), false))
        .expect("A6 off");
    sim.cycle();
    assert!(!applied(&sim, "A6"));
    sim.act(&OperatorAction::ManualSet("A6".into(), true))
        .expect("A6 on");
    assert!(sim.act(&OperatorAction::Start).is_err(), "no Start by hand");
    assert!(
        sim.act(&OperatorAction::ManualSet("A9".into(), true))
            .unwrap_err()
            .contains("no output `A9`")
    );
    sim.act(&OperatorAction::Manual(false)).expect("automatic");
    assert!(sim.program.at_initial_situation());
    assert!(sim.manual_outputs().is_none());
    assert!(
        sim.act(&OperatorAction::ManualSet("A6".into(), true))
            .is_err(),
        "no manual request in automatic mode"
    );
}

/// Every manual request the constraints allow is taken and every other refused, at the
/// idle start (table empty at the loading position): a rotation of the empty table
/// (CSs13) and the rollers of an empty table towards nothing are checked with the plant
/// as it is; an edge constraint sees the request as the next cycle's value.
#[test]
fn each_manual_request_at_rest_is_checked_against_every_constraint() {
    let s = scenario(
        ProgramChoice::Reference,
        FilterMode::Enforce,
        ArrivalPlan::List(Vec::new()),
        10_000,
    );
    let path = station_dir().join("scenario.ron");
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    sim.run_until(Millis(200));
    sim.act(&OperatorAction::Manual(true)).expect("manual");
    let e = sim
        .act(&OperatorAction::ManualSet("A4".into(), true))
        .unwrap_err();
    assert_eq!(
        e,
        "A4 ON refused: no rotation of an empty table (CSs13, with C4 = 1, C6 = 0)"
    );
    // Exhaustively: every output ON alone from rest, taken exactly when the engine's
    // own check of that vector finds no violation, and then applied.
    for k in 0..sim.bundle.plant.outputs.len() {
        let id = sim.bundle.plant.outputs[k].id.clone();
        let mut candidate = sim.manual_outputs().cloned().expect("manual");
        candidate.set(k, true);
        let allowed = sim.engine.check_request(&candidate).is_empty();
        let r = sim.act(&OperatorAction::ManualSet(id.clone(), true));
        assert_eq!(r.is_ok(), allowed, "{id}: {r:?}");
        sim.cycle();
        assert_eq!(applied(&sim, &id), allowed, "{id}");
        if allowed {
            sim.act(&OperatorAction::ManualSet(id.clone(), false))
                .expect("off");
            sim.cycle();
        }
    }
    assert!(!sim.engine.is_tripped());
    assert!(sim.emulator.hazards().is_empty());
}

/// A manual command allowed now may lead to a violation later (the plant moves on): the
/// filter still runs every cycle and stops it. Both conveyors on by hand carry a box to
/// the end of the belt; CSc2 trips before the box is pushed onto the stopped rollers,
/// and no item is damaged.
#[test]
fn the_filter_still_stops_what_manual_commands_lead_to() {
    let s = scenario(
        ProgramChoice::Reference,
        FilterMode::Enforce,
        ArrivalPlan::List(vec![(0, crate::emulator::BoxSize::Small)]),
        30_000,
    );
    let path = station_dir().join("scenario.ron");
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    sim.run_until(Millis(100));
    sim.act(&OperatorAction::Manual(true)).expect("manual");
    sim.act(&OperatorAction::ManualSet("A1".into(), true))
        .expect("A1");
    sim.act(&OperatorAction::ManualSet("A0".into(), true))
        .expect("A0");
    sim.run_until(Millis(30_000));
    assert_eq!(sim.engine.trips.len(), 1, "{:?}", sim.engine.trips);
    assert_eq!(sim.engine.trips[0].constraints[0].id, "CSc2");
    assert!(
        sim.emulator.hazards().is_empty(),
        "{:?}",
        sim.emulator.hazards()
    );
    assert_eq!(sim.plant_state(), PlantState::Tripped);
    // Tripped: manual requests are overridden by the fallback, leaving is allowed.
    sim.act(&OperatorAction::Manual(false)).expect("leave");
}

/// A bypass of one constraint (seed 004, section 7): refused without a reason, over a
/// shift or for an unknown constraint; while active, the filter does not enforce that
/// constraint (the paper's CSs10 case no longer trips on it) and only it; it ends by
/// itself at its time and is journaled at each step.
#[test]
fn a_bypass_is_bounded_journaled_lifts_only_its_constraint_and_ends_by_itself() {
    let (_, mut sim) = load_station_scenario("cs10-paper.ron");
    let bypass = |constraint: &str, minutes: u64, reason: &str| OperatorAction::Bypass {
        constraint: constraint.into(),
        minutes,
        reason: reason.into(),
        by: "marie".into(),
    };
    assert!(
        sim.act(&bypass("CSs99", 5, "test"))
            .unwrap_err()
            .contains("no safety constraint")
    );
    assert!(
        sim.act(&bypass("CSs10", 5, " "))
            .unwrap_err()
            .contains("needs a reason")
    );
    assert!(
        sim.act(&bypass("CSs10", 481, "test"))
            .unwrap_err()
            .contains("1 to 480 min")
    );
    assert!(sim.bypasses().is_empty());
    sim.act(&bypass("CSs10", 1, "C7 being replaced"))
        .expect("bypass");
    assert_eq!(sim.engine.bypassed().iter().collect::<Vec<_>>(), ["CSs10"]);
    sim.run_until(Millis(20_000));
    assert!(
        sim.engine
            .trips
            .iter()
            .all(|t| t.constraints.iter().all(|c| c.id != "CSs10")),
        "{:?}",
        sim.engine.trips
    );
    assert!(sim.journal().iter().any(|j| {
        j.kind == "bypass"
            && j.text
                .contains("CSs10 bypassed for 1 min by marie: C7 being replaced")
    }));
    sim.run_until(Millis(60_100));
    assert!(sim.bypasses().is_empty());
    assert!(sim.engine.bypassed().is_empty());
    assert!(
        sim.journal()
            .iter()
            .any(|j| j.kind == "bypass_end" && j.text.contains("time is up"))
    );
    // The same case without the bypass trips on CSs10 (the bypass made the difference).
    let (s, mut plain) = load_station_scenario("cs10-paper.ron");
    plain.run_until(Millis(s.duration_ms));
    assert_eq!(plain.engine.trips[0].constraints[0].id, "CSs10");
    // Ended early by hand.
    plain.act(&bypass("CSs2", 30, "test")).expect("bypass");
    plain
        .act(&OperatorAction::EndBypass("CSs2".into()))
        .expect("end");
    assert!(plain.engine.bypassed().is_empty());
    assert!(
        plain
            .act(&OperatorAction::EndBypass("CSs2".into()))
            .is_err()
    );
}

/// Issue 19, "operator and diagnoser" (seed 004, section 7): the belt dies under a
/// pushed box; the feed is in doubt between a dead belt and a beam (here C0, on the
/// box held against the stopped belt) and stops the plant on the safe side. The console
/// asks the operator the question that tells them apart, in the plant's own words; the
/// answer gives the conclusion, journaled; the question is not asked again; the
/// diagnosers' reset forgets the answer. On the paper's station: the shipped one's
/// mirror contact shows the dead belt's contactor open at the next cycle (CSk4), before
/// any doubt.
#[test]
fn a_diagnoser_in_doubt_asks_the_operator_and_uses_the_answer() {
    let paper = crate::test_support::paper_station("doubt-paper");
    let (s, mut sim) = load_scenario_in(&paper, "a1-dead-belt.ron");
    sim.run_until(Millis(s.duration_ms));
    let questions = sim.doubt_questions();
    assert_eq!(questions.len(), 1, "{questions:?}");
    let q = &questions[0];
    assert_eq!(
        (q.component.as_str(), q.sensor.as_str(), q.reading),
        ("feed", "C0", true)
    );
    assert_eq!(
        q.question,
        "Look at the Entry conveyor: is there an item at C0 (Box at the end of the entry \
         conveyor)? C0 reads 1."
    );
    assert_eq!(q.sensor_faults, ["C0_stuck1", "C0_rise"]);
    assert_eq!(q.other_faults, ["M1_blocked"]);
    // Were there no box at C0, the beam would be at fault.
    let mut other = load_scenario_in(&paper, "a1-dead-belt.ron").1;
    other.run_until(Millis(s.duration_ms));
    other
        .act(&OperatorAction::AnswerDoubt {
            component: "feed".into(),
            sensor: "C0".into(),
            item: false,
        })
        .expect("answer");
    assert_eq!(
        other.doubt_answers()["feed"],
        "feed: the operator sees no item at C0, which reads 1: C0 is at fault (C0_stuck1 \
         or C0_rise); repair it, then reset the diagnosers"
    );
    // The box is there (the truth: the belt is dead, the box held against it).
    sim.act(&OperatorAction::AnswerDoubt {
        component: "feed".into(),
        sensor: "C0".into(),
        item: true,
    })
    .expect("answer");
    let conclusion = sim.doubt_answers()["feed"].clone();
    assert_eq!(
        conclusion,
        "feed: the operator sees an item at C0, as C0 reads: C0 is right, the cause is \
         M1_blocked (check that drive), then reset the diagnosers"
    );
    assert!(
        sim.journal()
            .iter()
            .any(|j| j.kind == "operator_answer" && j.text == conclusion)
    );
    assert!(sim.doubt_questions().is_empty());
    assert!(
        sim.act(&OperatorAction::AnswerDoubt {
            component: "feed".into(),
            sensor: "C0".into(),
            item: true,
        })
        .is_err(),
        "answered once"
    );
    sim.act(&OperatorAction::ResetDiagnosers).expect("reset");
    assert!(sim.doubt_answers().is_empty());
}

/// Issue 20, hardware before program: with an actuator stuck ON its mirror contact
/// (X419) or the diagnosers (X415, X416) stop the plant, and level 4 names the hardware
/// first (with the stuck actuator among what
/// to check), not the program's equation; a stop by the diagnosers alone lists no
/// program suspect.
#[test]
fn an_actuator_stuck_on_is_named_as_hardware_before_the_program() {
    let program_codes = [
        codes::X_TRANSITION_DEACTIVATED_STEP.id,
        codes::X_TRANSITION_ACTIVATED_STEP.id,
        codes::X_QUALIFIER.id,
        codes::X_EQUATION_FORBIDDEN_VALUE.id,
        codes::X_NOTHING_COMMANDS.id,
        codes::X_STEP_NOT_LEFT.id,
        codes::X_COMBINED_MISSING.id,
        codes::X_MISPLACED_ACTION.id,
    ];
    let hardware = [
        codes::X_HARDWARE_CERTAIN.id,
        codes::X_HARDWARE_AMBIGUOUS.id,
        codes::X_CONTACTOR_DISAGREES.id,
    ];
    let mut named = Vec::new();
    for actuator in ["A2", "A3", "A4"] {
        let text = format!(
            r#"Scenario(
                name: "{actuator} stuck ON",
                plant: ".",
                program: Reference,
                seed: 3,
                arrivals: Some(Periodic(period_ms: 8000, jitter_ms: 1000, mix: Alternate)),
                faults: [(trigger: At(20000), fault: ActuatorStuckOn("{actuator}"))],
                actions: [(at_ms: 0, action: Start)],
                duration_ms: 60000,
                filter: Enforce,
                diagnosers: true,
            )"#
        );
        let s: Scenario = ron::from_str(&text).expect("scenario");
        let sim = run(&s);
        assert!(!sim.engine.trips.is_empty(), "{actuator}: no stop");
        let ex = sim.explanations.values().next().expect("explained");
        let first = &ex.hypothesis.items[0];
        assert!(
            hardware.contains(&first.code),
            "{actuator}: level 4 starts with {} {}",
            first.code,
            first.text
        );
        assert!(
            first.fields["check"].split(", ").any(|e| e == actuator),
            "{actuator}: {}",
            first.text
        );
        assert!(first.text.starts_with("Hardware first"), "{}", first.text);
        let trip = &sim.engine.trips[0];
        if trip
            .constraints
            .iter()
            .all(|c| crate::pop::coop::is_diagnoser_stop(&c.id))
        {
            let blamed: Vec<&Item> = ex
                .hypothesis
                .items
                .iter()
                .filter(|i| program_codes.contains(&i.code))
                .collect();
            assert!(blamed.is_empty(), "{actuator}: {blamed:?}");
        }
        assert!(
            ex.hypothesis
                .highlights
                .iter()
                .any(|h| h.element == actuator && h.mark == Mark::Suspect),
            "{actuator}"
        );
        named.push(actuator);
    }
    assert_eq!(named.len(), 3);
    // A program error with the diagnosers on: no hardware item.
    let path = station_dir().join("scenarios/cs10-paper.ron");
    let mut s = Scenario::load(&path).expect("scenario");
    s.diagnosers = true;
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    sim.run_until(Millis(s.duration_ms));
    let ex = sim.explanations.values().next().expect("explained");
    assert!(
        ex.hypothesis
            .items
            .iter()
            .all(|i| !hardware.contains(&i.code)),
        "{:?}",
        ex.hypothesis.items
    );
    assert_eq!(
        ex.hypothesis.items[0].code,
        codes::X_TRANSITION_DEACTIVATED_STEP.id
    );
}

/// Issue 20: in monitor mode (the filter only reports) the explanation and the alarm
/// say what the filter would have done, never that it stopped the plant.
#[test]
fn a_report_only_violation_is_told_as_not_stopped() {
    let path = station_dir().join("scenarios/cs10-paper.ron");
    let mut s = Scenario::load(&path).expect("scenario");
    s.filter = FilterMode::ReportOnly;
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    sim.run_until(Millis(s.duration_ms));
    let trip = sim.engine.trips.first().expect("the violation is recorded");
    assert!(!trip.enforced);
    let ex = &sim.explanations[&0];
    let codes0: Vec<&str> = ex.current_state.items.iter().map(|i| i.code).collect();
    assert_eq!(
        codes0,
        [
            codes::X_FILTER_WOULD_STOP.id,
            codes::X_FILTER_WOULD_APPLY.id
        ]
    );
    let would = &ex.current_state.items[1];
    assert_eq!(would.fields["held"], "A4", "{}", would.text);
    for level in ex.levels() {
        for item in &level.items {
            assert!(
                !item.text.contains("stopped the plant at")
                    && !item.text.contains("held ON by the filter")
                    && !item.text.contains("the stop prevented"),
                "{}: {}",
                item.code,
                item.text
            );
        }
    }
    let alarm = &sim.alarms.all()[0];
    assert!(
        alarm
            .message
            .starts_with("Safety violation, plant not stopped"),
        "{}",
        alarm.message
    );
    // Enforced, the same run says it stopped the plant.
    let s = Scenario::load(&path).expect("scenario");
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
    sim.run_until(Millis(s.duration_ms));
    assert_eq!(
        sim.explanations[&0].current_state.items[0].code,
        codes::X_FILTER_STOPPED.id
    );
}

/// The table's beam stuck at 1 while a box waits at C3 (the training exercise P03):
/// the filter stops the plant in that cycle, before any diagnoser can tell. C6 rose with
/// no box between C3 and C6 (`rise_expected_when: "P36*"`), so level 4 names C6 first
/// (X418), before the program's receptivity and equation, which only read it. A box
/// that really reaches C7 (the paper's CSs10, E01) is expected there: no X418.
#[test]
fn a_beam_that_rises_where_no_item_can_come_is_named_first() {
    let text = r#"Scenario(
        name: "C6 stuck at 1",
        plant: ".",
        program: Reference,
        seed: 1,
        faults: [(trigger: At(25000), fault: SensorStuckAt1("C6"))],
        actions: [(at_ms: 0, action: Start)],
        duration_ms: 30000,
        filter: Enforce,
        diagnosers: true,
    )"#;
    let s: Scenario = ron::from_str(text).expect("scenario");
    let sim = run(&s);
    let trip = sim.engine.trips.first().expect("a stop");
    assert_eq!(trip.time_ms, 25_000, "stopped in the cycle of the fault");
    let ex = sim.explanations.values().next().expect("explained");
    let first = &ex.hypothesis.items[0];
    assert_eq!(
        first.code,
        codes::X_UNEXPECTED_EDGE.id,
        "{:?}",
        ex.hypothesis.items
    );
    assert_eq!(first.fields["sensor"], "C6");
    assert_eq!(first.fields["follows"], "P36");
    assert!(
        first.text.contains("P36 = A box between C3 and C6"),
        "{}",
        first.text
    );
    assert!(
        ex.hypothesis
            .highlights
            .iter()
            .any(|h| h.element == "C6" && h.mark == Mark::Suspect)
    );
    // The paper's trip: C7 rose with a box leaving to the right (P67 at t-1).
    let path = station_dir().join("scenarios/cs10-paper.ron");
    let paper = Scenario::load(&path).expect("cs10-paper");
    let mut sim = Simulation::from_scenario(&paper, &path, Options::default()).expect("sim");
    sim.run_until(Millis(14_000));
    let ex = sim.explanations.values().next().expect("explained");
    assert!(
        ex.hypothesis
            .items
            .iter()
            .all(|i| i.code != codes::X_UNEXPECTED_EDGE.id),
        "{:?}",
        ex.hypothesis.items
    );
}

/// Issue 17, welded actuators: no output of the paper's station can stop a welded
/// contactor, so a welded intermediate conveyor keeps pushing boxes, and damages them.
/// With a safety contactor on the drives' supply and a mirror contact on A1's
/// contactor (plant data only: `supplies`, `held_on`, `feedback_of`, monomials),
/// the weld shows one cycle after A1's release, the filter releases the contactor and
/// the belt stops: no hazard, a trip on CSk3. Fault-free, the contactor changes
/// nothing (no trip, the same deliveries).
#[test]
fn a_safety_contactor_stops_a_welded_belt_that_the_paper_station_cannot() {
    let km = crate::test_support::edm_station("km-welded");
    let text = |at: u64| {
        format!(
            r#"Scenario(
                name: "A1 welded",
                plant: ".",
                program: Reference,
                seed: 5,
                arrivals: Some(Periodic(period_ms: 8000, jitter_ms: 1000, mix: Alternate)),
                faults: [(trigger: At({at}), fault: ActuatorStuckOn("A1"))],
                actions: [(at_ms: 0, action: Start)],
                duration_ms: 90000,
                filter: Enforce,
                diagnosers: true,
            )"#
        )
    };
    let paper = crate::test_support::paper_station("paper-welded");
    let run_in = |dir: &std::path::Path, s: &Scenario| {
        let mut sim = Simulation::from_scenario(s, &dir.join("scenario.ron"), Options::default())
            .unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
        sim.run_until(Millis(s.duration_ms));
        sim
    };
    let (mut plain_hazards, mut km_hazards, mut km_trips) = (0, 0, 0);
    for k in 0..12u64 {
        let s: Scenario = ron::from_str(&text(20_000 + 1_300 * k)).expect("scenario");
        let plain = run_in(&paper, &s);
        plain_hazards += plain.emulator.hazards().len();
        let path = km.join("scenario.ron");
        let mut sim = Simulation::from_scenario(&s, &path, Options::default())
            .unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
        sim.run_until(Millis(s.duration_ms));
        km_hazards += sim.emulator.hazards().len();
        if sim
            .engine
            .trips
            .iter()
            .any(|t| t.constraints.iter().any(|c| c.id == "CSk3"))
        {
            km_trips += 1;
        }
    }
    assert!(
        plain_hazards > 0,
        "the paper's station cannot stop a welded belt"
    );
    assert_eq!(km_hazards, 0, "with the contactor");
    assert!(
        km_trips >= 10,
        "the weld shows on the mirror contact: {km_trips} of 12"
    );
    // Fault-free: the contactor stays ON, nothing trips, the same boxes are delivered.
    let free: Scenario = ron::from_str(
        r#"Scenario(
            name: "fault-free",
            plant: ".",
            program: Reference,
            seed: 5,
            arrivals: Some(Periodic(period_ms: 8000, jitter_ms: 1000, mix: Alternate)),
            actions: [(at_ms: 0, action: Start)],
            duration_ms: 120000,
            filter: Enforce,
            diagnosers: true,
        )"#,
    )
    .expect("scenario");
    let plain = run_in(&paper, &free);
    let mut sim = Simulation::from_scenario(&free, &km.join("scenario.ron"), Options::default())
        .expect("sim");
    sim.run_until(Millis(free.duration_ms));
    assert!(
        sim.engine.trips.is_empty(),
        "{:?}",
        sim.engine.trips.first()
    );
    assert_eq!(sim.emulator.stats(), plain.emulator.stats());
}

/// Issue 17's welded and dead actuators, the campaign's way: every drive and both
/// safety devices of the station with external device monitoring, welded and dead, at
/// the sustained arrival period, filter and diagnosers on: no hazard and no wrong
/// certain diagnosis (a dead drive shows on its mirror in the next cycle and its
/// supply is cut before a belt has slid 10 mm under a box; a welded table valve is
/// frozen within the docking tolerance), but for the rollers' two directions at once
/// when one welds while the other runs. The paper's station under the same faults
/// damages boxes.
#[test]
fn with_device_monitoring_no_welded_or_dead_drive_damages_a_box() {
    use crate::pop::transients::{Config, run as campaign};
    let edm = crate::test_support::edm_station("km-campaign");
    let config = |only: &str| Config {
        seeds: 2,
        first_seed: 3,
        only: Some(only.into()),
        fault_free_hours: 0,
        ..Config::default()
    };
    let mut paper_hazards = 0;
    for only in [" welded", " dead"] {
        let r =
            campaign(&edm, &config(only)).unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
        assert_eq!(r.rows.len(), 9, "{only}: seven drives, KM0 and YV0");
        for row in &r.rows {
            assert_eq!(
                (row.hazards - row.own_hazards, row.wrong),
                (0, 0),
                "{}: {:?}",
                row.name,
                row.failures
            );
            // The rollers' reversing pair: A3 welded while the program runs A2 drives
            // both directions at once before any sensor can show it (what a
            // mechanical interlock of the contactors prevents, no filter can): the
            // drive's own hazard, no box damaged.
            if row.own_hazards > 0 {
                assert!(
                    row.name.contains("A2") || row.name.contains("A3"),
                    "{}: {:?}",
                    row.name,
                    row.failures
                );
                assert!(
                    row.failures.iter().all(|f| f.contains("OpposedDrives")),
                    "{:?}",
                    row.failures
                );
            }
        }
        let paper = campaign(
            &crate::test_support::paper_station("paper-campaign"),
            &config(only),
        )
        .unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
        paper_hazards += paper.rows.iter().map(|r| r.hazards).sum::<usize>();
    }
    assert!(
        paper_hazards > 0,
        "the paper's station cannot stop a welded or dead drive"
    );
}

/// A live PLC runs each error of the station's library, monitored with that program
/// given (`--program`): the mirror's explanation of the violation has the same
/// hypothesis as the emulator's run of the program (the program's elements first);
/// without the program it has none of them. The projection runs the program on: for
/// some error it ends elsewhere than with the PLC's last outputs held.
#[test]
fn a_monitored_plc_with_its_program_given_is_explained_by_its_program() {
    let path = station_dir().join("scenarios/cs10-paper.ron");
    let lib = crate::control::ErrorLibrary::load(
        &station_dir().join("programs/errors.ron"),
        &crate::plant::Plant::load(&station_dir().join("plant.ron")).expect("plant"),
    )
    .expect("library");
    let (mut explained, mut projected_apart) = (0, 0);
    for v in lib.variants {
        let mut s = Scenario::load(&path).expect("scenario");
        s.program = ProgramChoice::Error(v.def.id.clone());
        s.filter = FilterMode::ReportOnly;
        s.plausibility = false;
        let mut plc = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
        let mut cycles = Vec::new();
        while plc.engine.trips.is_empty() && plc.now() < Millis(60_000) {
            plc.cycle();
            cycles.push((
                plc.engine.history.last().expect("recorded").time,
                plc.engine.frame().now(Space::Input).clone(),
                plc.engine.commanded().clone(),
            ));
        }
        let Some(emulated) = plc.explanations.get(&0) else {
            continue;
        };
        let program = std::sync::Arc::new(v.compiled);
        let monitor = |given: bool| {
            let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
            sim.follow_link(FilterMode::ReportOnly);
            if given {
                sim.follow_program(std::sync::Arc::clone(&program));
            }
            for (k, (time, inputs, commanded)) in cycles.iter().enumerate() {
                sim.observe(&ObservedCycle {
                    time: *time,
                    inputs: inputs.clone(),
                    commanded: commanded.clone(),
                    applied: commanded.clone(),
                    reset: false,
                    diagnosers: diagnosis::LinkStep::Skipped,
                    attach: k == 0,
                    restored: None,
                    followed: true,
                });
            }
            sim
        };
        let codes = |ex: &Explanation| -> Vec<String> {
            ex.hypothesis
                .items
                .iter()
                .map(|i| i.code.to_string())
                .collect()
        };
        let is_program = |c: &String| ("X407".."X414").contains(&c.as_str()) || c == "X417";
        let live = monitor(true);
        let id = &v.def.id;
        let followed = live.explanations.get(&0).expect("explained");
        assert_eq!(followed.hypothesis, emulated.hypothesis, "{id}");
        assert!(
            codes(followed).iter().any(is_program),
            "{id}: {:?}",
            codes(followed)
        );
        let blind = monitor(false);
        let unknown = blind.explanations.get(&0).expect("explained");
        assert!(
            !codes(unknown).iter().any(is_program),
            "{id}: {:?}",
            codes(unknown)
        );
        let at = |sim: &Simulation| sim.projections.get(&0).map(|p| p.boxes.clone());
        projected_apart += usize::from(at(&live) != at(&blind));
        explained += 1;
    }
    assert!(explained >= 10, "{explained} errors explained");
    assert!(projected_apart >= 1);
}
