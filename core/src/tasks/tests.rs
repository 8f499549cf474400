// The fixtures mirror fixtures.ron's tuples field for field.
#![allow(clippy::type_complexity)]

use super::monitor::crossing;
use super::spec::TaskFile;
use super::*;
use crate::time::Millis;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Fixtures {
    specs: BTreeMap<String, TaskFile>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Case {
    name: String,
    spec: String,
    events: Vec<(u64, String)>,
    until_ms: u64,
    /// (time, code, subject, x, y, watchdog)
    alarms: Vec<AlarmRow>,
    #[serde(default)]
    texts: Vec<(usize, String)>,
    /// (at, task, state, x, y, interruptions, slack, predicted alarm)
    #[serde(default)]
    status: Vec<(u64, String, TaskState, u64, u64, u32, i64, Option<u64>)>,
}

fn load_fixtures() -> Fixtures {
    ron::from_str(include_str!("fixtures.ron")).unwrap()
}

fn spec_of(f: &Fixtures, name: &str) -> TaskSet {
    let file = f
        .specs
        .get(name)
        .unwrap_or_else(|| panic!("no spec {name}"));
    TaskSet::from_file(file.clone(), Path::new(name), None).unwrap()
}

/// An alarm as the fixtures write it: (time, code, subject, x, y, watchdog).
type AlarmRow = (
    u64,
    AlarmCode,
    String,
    Option<u64>,
    Option<u64>,
    Option<u64>,
);

fn row(a: &Alarm) -> AlarmRow {
    (
        a.time.0,
        a.code,
        a.subject.clone(),
        a.x_ms,
        a.y_ms,
        a.watchdog.map(|w| w.0),
    )
}

/// Replays `case` through the plant's monitor of `set` (the closed form, or the
/// synthesised regions when `set` has them); checks the live panel at the case's
/// times and returns the monitor.
fn replay(case: &Case, set: &TaskSet) -> Monitor {
    let mut m = Monitor::new(set, Millis::ZERO);
    let mut statuses = Vec::new();
    let mut checks = case.status.iter().peekable();
    for (t, e) in &case.events {
        while let Some(c) = checks.next_if(|c| c.0 < *t) {
            m.advance(Millis(c.0));
            statuses.push((c, m.status(Millis(c.0))));
        }
        m.on_event(Millis(*t), e);
    }
    for c in checks {
        m.advance(Millis(c.0));
        statuses.push((c, m.status(Millis(c.0))));
    }
    m.advance(Millis(case.until_ms));
    for (c, st) in statuses {
        let s = st.iter().find(|s| s.id == c.1).unwrap();
        let got = (
            s.state,
            s.x_ms,
            s.y_ms,
            s.interruptions,
            s.slack_ms,
            s.predicted_alarm.map(|p| p.0),
        );
        assert_eq!(
            got,
            (c.2, c.3, c.4, c.5, c.6, c.7),
            "case `{}` status at {}",
            case.name,
            c.0
        );
    }
    m
}

#[test]
fn thesis_fixtures() {
    let f = load_fixtures();
    assert!(f.cases.len() >= 20);
    for case in &f.cases {
        let set = spec_of(&f, &case.spec);
        let m = replay(case, &set);
        let got: Vec<AlarmRow> = m.alarms.iter().map(row).collect();
        assert_eq!(got, case.alarms, "case `{}`: {:#?}", case.name, m.alarms);
        for (i, text) in &case.texts {
            assert_eq!(&m.alarms[*i].text, text, "case `{}`", case.name);
        }
    }
}

#[test]
fn watchdog_gains() {
    let f = load_fixtures();
    let gain = |name: &str| {
        let case = f.cases.iter().find(|c| c.name == name).unwrap();
        let set = spec_of(&f, &case.spec);
        let mut m = Monitor::new(&set, Millis::ZERO);
        for (t, e) in &case.events {
            m.on_event(Millis(*t), e);
        }
        m.advance(Millis(case.until_ms));
        m.alarms[0].earlier_by_ms
    };
    assert_eq!(gain("workshop scenario 1"), Some(3000));
    assert_eq!(gain("workshop scenario 3"), Some(500));
    assert_eq!(gain("liquid, d at 0"), Some(2000));
    assert_eq!(gain("conveyor: permanent block at 4"), Some(6000));
}

#[test]
fn next_deadline_predicts_the_alarm() {
    let f = load_fixtures();
    let set = spec_of(&f, "workshop");
    let mut m = Monitor::new(&set, Millis::ZERO);
    for (t, e) in [
        (0, "d"),
        (3000, "b"),
        (3000, "e"),
        (3500, "d"),
        (4000, "s_R"),
        (4500, "r_R"),
        (5000, "s_R"),
    ] {
        m.on_event(Millis(t), e);
    }
    // Robot interrupted at 5 with x - y = 0.5: tolerance 2 used up at 6.5.
    assert_eq!(
        m.next_deadline(),
        Some(Deadline {
            at: Millis(6500),
            after: false
        })
    );
    assert!(m.advance(Millis(6499)).is_empty());
    assert_eq!(m.advance(Millis(6500)).len(), 1);
}

#[test]
fn invalid_specs_are_rejected_with_a_location() {
    let text = "(tasks: [\n  (id: \"a\", start: \"s\", end: \"e\", alpha_ms: 5, beta_ms: 4, gamma_ms: 9),\n  (id: \"b\", start: \"s\", end: \"e\", alpha_ms: 1, beta_ms: 4, gamma_ms: 4),\n  (id: \"c\", start: \"s\", end: \"e\", interrupt: Some(\"i\"), alpha_ms: 1, beta_ms: 2, gamma_ms: 4),\n])";
    let err = TaskSet::from_ron(text, Path::new("tasks.ron")).unwrap_err();
    let msgs: Vec<String> = err.iter().map(ToString::to_string).collect();
    assert_eq!(msgs.len(), 3, "{msgs:#?}");
    assert!(
        msgs[0].starts_with(
            "tasks.ron:2:8: error[V0803]: task `a`: α = 5 ms is greater than β = 4 ms"
        ),
        "{}",
        msgs[0]
    );
    assert!(
        msgs[1].starts_with(
            "tasks.ron:3:8: error[V0804]: task `b`: β = 4 ms must be less than γ = 4 ms"
        ),
        "{}",
        msgs[1]
    );
    assert!(msgs[2].contains("V0805"), "{}", msgs[2]);
    let bad =
        TaskSet::from_ron("(tasks: [(id: \"a\", bogus: 1)])", Path::new("t.ron")).unwrap_err();
    assert!(bad[0].to_string().starts_with("t.ron:1:"), "{}", bad[0]);
    // Without interrupt events the task is non-interruptible.
    let ok = TaskSet::from_ron(
        "(tasks: [(id: \"a\", start: \"s\", end: \"e\", alpha_ms: 1, beta_ms: 2, gamma_ms: 3)])",
        Path::new("t.ron"),
    )
    .unwrap();
    assert!(!ok.tasks[0].interruptible());
}

#[test]
fn crossing_is_exact_for_every_slope() {
    // v(t) = v0 + s·t against a bound: brute force over integer instants.
    for v0 in -5i64..6 {
        for s in 0i64..4 {
            for bound in -3i64..8 {
                for strict in [true, false] {
                    let d = crossing(v0, s, bound, strict, Millis(0));
                    let first = (0u64..50).find(|&t| {
                        let v = v0 + s * i64::try_from(t).unwrap();
                        if strict { v >= bound } else { v > bound }
                    });
                    assert_eq!(
                        d.map(|d| d.first_violating_ms().0),
                        first,
                        "{v0} {s} {bound} {strict}"
                    );
                }
            }
        }
    }
}

mod props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The event-driven monitor and a brute-force millisecond simulation of the closed
        /// form agree on the first alarm of a single interruptible task.
        #[test]
        fn matches_brute_force(alpha in 1u64..20, extra_b in 0u64..10, extra_g in 1u64..10,
                               gaps in proptest::collection::vec(1u64..8, 0..8)) {
            let (a, b, g) = (alpha, alpha + extra_b, alpha + extra_b + extra_g);
            let file = TaskFile {
                tasks: vec![spec::TaskDef { id: "t".into(), description: String::new(), start: "d".into(), end: "b".into(),
                    interrupt: Some("s".into()), resume: Some("r".into()), alpha_ms: a, beta_ms: b, gamma_ms: g,
                    slowdown: spec::Slowdown::Strict }],
                windows: vec![], cross: vec![], unexpected: spec::Unexpected::Ignore, latch: spec::Latch::PerTask,
                repair: None, check_end: true,
            };
            let set = TaskSet::from_file(file, Path::new("p"), None).unwrap();
            let mut m = Monitor::new(&set, Millis(0));
            m.on_event(Millis(0), "d");
            let mut t = 0;
            let mut times = Vec::new();
            for (k, gap) in gaps.iter().enumerate() {
                t += gap;
                times.push((t, if k % 2 == 0 { "s" } else { "r" }));
                m.on_event(Millis(t), if k % 2 == 0 { "s" } else { "r" });
            }
            m.advance(Millis(200));
            // Brute force: step 1 ms; events first at each instant, then the check.
            let (mut x, mut y, mut running) = (0u64, 0u64, true);
            let mut first = None;
            for now in 0..=200u64 {
                if now > 0 { x += 1; if running { y += 1; } }
                for (et, e) in &times { if *et == now { running = *e == "r"; } }
                let violated = x - y >= g - a || x >= g || y > b;
                if violated { first = Some(now); break; }
            }
            let got = m.alarms.first().map(|a| a.deadline_ms());
            prop_assert_eq!(got, first);
        }
    }
}

impl Alarm {
    /// First integer ms at which the alarm's condition holds (the crossing instant, or one
    /// ms later for a bound that is exceeded rather than reached).
    fn deadline_ms(&self) -> u64 {
        if self.code == AlarmCode::T002 {
            self.time.0 + 1
        } else {
            self.time.0
        }
    }
}

#[test]
fn synthetic_scales() {
    let set = synthetic(1000);
    let mut m = Monitor::new(&set, Millis(0));
    for i in 0..1000 {
        m.on_event(Millis(i), &format!("s{i}"));
    }
    assert_eq!(
        m.next_deadline(),
        Some(Deadline {
            at: Millis(4000),
            after: true
        })
    );
    m.on_event(Millis(1000), "i0");
    assert_eq!(
        m.next_deadline(),
        Some(Deadline {
            at: Millis(3000),
            after: false
        })
    );
    assert_eq!(m.advance(Millis(3000)).len(), 1);
}

/// Every fixture of the conveyor and the workshop again, now through the monitor of
/// the synthesised regions (`E*` of the product of the tasks' and windows' stopwatch
/// automata, no hand-written bound): its first alarm falls at the fixture's first
/// alarm instant, on the same task. The liquid supply's four tasks are left out: their
/// product (81 locations, 8 clocks) takes minutes to synthesise today.
#[test]
fn thesis_fixtures_from_synthesised_regions() {
    use crate::swa::regions::{Options, RegionMonitor};
    use crate::swa::{Limits, from_tasks, synthesize};
    let f = load_fixtures();
    let mut cache = BTreeMap::new();
    let mut replayed = 0;
    for case in f.cases.iter().filter(|c| !c.spec.starts_with("liquid")) {
        replayed += 1;
        let set = spec_of(&f, &case.spec);
        let (swa, regions) = cache
            .entry(case.spec.clone())
            .or_insert_with(|| {
                let swa = from_tasks::automata(&set)
                    .compile(Path::new(&case.spec), "")
                    .unwrap();
                let s = synthesize(&swa, Limits::default()).unwrap();
                let regions = s.monitor_regions(&swa);
                (swa, regions)
            })
            .clone();
        let options = Options {
            check_guards: set.check_end,
            unexpected: set.unexpected == spec::Unexpected::Alarm,
        };
        let mut m = RegionMonitor::new(swa, regions, Millis::ZERO, options);
        let mut raised = None;
        for (t, e) in &case.events {
            if set.repair.as_deref() == Some(e.as_str()) {
                m.advance(Millis(*t));
                raised = raised.or_else(|| m.alarm().cloned());
                m.repair(Millis(*t));
            } else {
                m.on_event(Millis(*t), e);
            }
            raised = raised.or_else(|| m.alarm().cloned());
        }
        m.advance(Millis(case.until_ms));
        raised = raised.or_else(|| m.alarm().cloned());
        let first = case.alarms.first();
        match (first, raised.as_ref()) {
            (None, None) => {}
            (Some(want), Some(got)) => {
                assert_eq!(got.at.at.0, want.0, "{}: {got:?}", case.name);
                assert!(
                    got.components.contains(&want.2),
                    "{}: {got:?} is not about {}",
                    case.name,
                    want.2
                );
            }
            (want, got) => panic!("{}: fixture {want:?}, regions {got:?}", case.name),
        }
    }
    assert_eq!(replayed, 20, "the conveyor and workshop cases");
}

/// The task set of a fixture with its regions synthesised (what `vigie synthesize`
/// writes and the layout loader reads), so that [`Monitor::new`] runs them.
fn with_regions(set: &TaskSet) -> TaskSet {
    use crate::swa::regions::{TaskRegions, fingerprint};
    use crate::swa::{Limits, from_tasks, synthesize};
    let file = from_tasks::automata(set);
    let swa = file.compile(&set.file, "").unwrap();
    let s = synthesize(&swa, Limits::default()).unwrap();
    let regions = s.monitor_regions(&swa);
    TaskSet {
        regions: Some(TaskRegions {
            path: set.file.with_file_name("regions.ron"),
            fingerprint: fingerprint(&file),
            swa: std::sync::Arc::new(swa),
            regions: std::sync::Arc::new(regions),
        }),
        ..set.clone()
    }
}

/// The conveyor and workshop fixtures through the PLANT's monitor running the
/// synthesised regions (as the emulator and the live link run it when `regions.ron`
/// is beside `tasks.ron`): the alarms are the fixture's, code, subject, clocks and
/// watchdog included, and so is the live panel; the one difference is the
/// coordinator's hand-written cross-task constraint, which is not run beside regions
/// (its case's first alarm, the window's, is the same). The liquid supply's four
/// dependent tasks take minutes to synthesise: left out.
#[test]
fn thesis_fixtures_through_the_plant_monitor_with_regions() {
    let f = load_fixtures();
    let mut cache: BTreeMap<String, TaskSet> = BTreeMap::new();
    let mut replayed = 0;
    for case in f.cases.iter().filter(|c| !c.spec.starts_with("liquid")) {
        replayed += 1;
        let set = cache
            .entry(case.spec.clone())
            .or_insert_with(|| with_regions(&spec_of(&f, &case.spec)))
            .clone();
        let m = replay(case, &set);
        assert!(m.regions().is_some(), "{}: the regions run", case.name);
        let got: Vec<AlarmRow> = m.alarms.iter().map(row).collect();
        if set.cross.is_empty() {
            assert_eq!(got, case.alarms, "case `{}`: {:#?}", case.name, m.alarms);
            for (i, text) in &case.texts {
                assert_eq!(&m.alarms[*i].text, text, "case `{}`", case.name);
            }
        } else {
            assert_eq!(got.first(), case.alarms.first(), "case `{}`", case.name);
        }
    }
    assert_eq!(replayed, 20, "the conveyor and workshop cases");
}

/// A coupling the per-task closed form cannot see, with numbers. The thesis's
/// workshop: the window `d_window` (opened by `e`, the robot's start) must be closed by
/// `d` within 2 s, and `d` is the conveyor's start, so the conveyor must end first
/// (or the robot end and a new `e` open the window again). `d` at 0 starts the
/// conveyor (α = 3 s) and closes the window; `e` at 1.5 s starts the robot (α = 2 s)
/// and opens the window: the conveyor has 1.5 s to go, the window 2 s. At 2 s the
/// cell stops (`s_c`, `s_R`): the conveyor has 1 s to go, the window 1.5 s left, so
/// after 0.5 s stopped the conveyor cannot end, and `d` come, within the window, and
/// the robot, stopped too, cannot end and open it again in time. The regions alarm
/// just after 2.5 s, for the window (T009); the closed form waits for the window's
/// own bound (just after 3.5 s) and the tasks' tolerances (x − y = 2 s at 4 s).
#[test]
fn regions_detect_a_coupling_before_the_closed_form() {
    let f = load_fixtures();
    let set = spec_of(&f, "workshop");
    let events = [(0, "d"), (1500, "e"), (2000, "s_c"), (2000, "s_R")];
    let run = |set: &TaskSet| {
        let mut m = Monitor::new(set, Millis::ZERO);
        for (t, e) in events {
            m.on_event(Millis(t), e);
        }
        m.advance(Millis(4000));
        m.alarms.iter().map(row).collect::<Vec<_>>()
    };
    let conveyor = (
        4000,
        AlarmCode::T001,
        "conveyor".to_string(),
        Some(4000),
        Some(2000),
        Some(5000),
    );
    let robot = (
        4000,
        AlarmCode::T001,
        "robot".to_string(),
        Some(2500),
        Some(500),
        Some(5500),
    );
    assert_eq!(
        run(&set),
        vec![
            (3500, AlarmCode::T006, "d_window".into(), None, None, None),
            conveyor.clone(),
            robot.clone(),
        ]
    );
    let regions = with_regions(&set);
    let mut m = Monitor::new(&regions, Millis::ZERO);
    for (t, e) in events {
        m.on_event(Millis(t), e);
    }
    // Known at 2 s already: just after 2.5 s.
    assert_eq!(
        m.next_deadline(),
        Some(Deadline {
            at: Millis(2500),
            after: true
        })
    );
    assert!(m.advance(Millis(2500)).is_empty());
    let raised = m.advance(Millis(2501)).to_vec();
    assert_eq!(
        raised.iter().map(row).collect::<Vec<_>>(),
        vec![(2500, AlarmCode::T009, "d_window".into(), None, None, None)]
    );
    assert!(
        raised[0]
            .text
            .starts_with("Controller window d_window can no longer close in time"),
        "{}",
        raised[0].text
    );
    assert!(
        raised[0]
            .text
            .ends_with("its own bound alone would alarm at 3.5 s, 1 s later."),
        "{}",
        raised[0].text
    );
    // The tasks keep their own bounds after the regions' alarm (per-task latch).
    assert_eq!(
        run(&regions),
        vec![
            (2500, AlarmCode::T009, "d_window".into(), None, None, None),
            conveyor,
            robot,
        ]
    );
}
