//! The decentralized diagnosers (issue 4) end to end on the sorting station:
//! - a reduced fault campaign (every fault of the injection library, a few seeds each,
//!   one fault-free hour) with the properties of `vigie campaign diagnoser`;
//! - C4 stuck at 0 during production with the filter on: the cooperation keeps zero
//!   hazards and production goes on in degraded mode;
//! - the `diagnoses` of the `vigie run --headless` report;
//! - the libFAUDES cross-check (pinned `faudes` in the test venv; a missing venv fails).

#![allow(clippy::unwrap_used)] // test helpers: a failure is a test failure

use std::path::{Path, PathBuf};
use std::process::Command;
use vigie_core::Millis;
use vigie_core::emulator::{FaultKind, FaultSpec, Trigger};
use vigie_core::pop;
use vigie_core::pop::campaign::{Config, run};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn station() -> PathBuf {
    repo().join("layouts/sorting-station")
}

/// Faults localised in every run of the 100-seed campaign (diagnosed on their
/// partition, or an actuator's stopped on by its mirror contact), whatever the moment (the others are context-dependent: see `docs/diagnoser.md`).
const ALWAYS: &[&str] = &[
    "C4 stuck at 0, table at rest at C4",
    "table blocked at C4",
    "table blocked at C5",
    "A4 stuck off",
    "A4 stuck on",
    "C1 stuck at 0",
    "C1 stuck at 1",
    "C7 stuck at 0",
    "C8 stuck at 0",
    "C9 stuck at 1",
    "C10 stuck at 1",
    "C10 spurious rise 300 ms",
    "A2 stuck on",
    "A3 stuck off",
    "A5 stuck off",
    "A6 stuck off",
];

#[test]
fn reduced_fault_campaign_diagnoses_the_right_partition_and_never_a_false_one() {
    let config = Config {
        seeds: 4,
        fault_free_hours: 1,
        threads: 2,
        ..Config::default()
    };
    let r = run(&station(), &config).unwrap();
    assert!(r.rows.len() >= 50, "library too small: {}", r.rows.len());
    let mut text = String::new();
    for row in &r.rows {
        text.push_str(&format!("{row:?}\n"));
    }
    for row in &r.rows {
        assert_eq!(
            row.wrong + row.early,
            0,
            "{}: wrong or early certain diagnosis\n{row:#?}",
            row.name
        );
        assert_eq!(
            row.right
                + row.monitored
                + row.ambiguous.values().sum::<usize>()
                + row.no_effect.values().sum::<usize>(),
            row.runs,
            "{row:#?}"
        );
        if ALWAYS.contains(&row.name.as_str()) {
            // Diagnosed, or stopped on the faulted actuator by its mirror contact.
            assert_eq!(
                row.right + row.monitored,
                row.runs,
                "{} must always be localised\n{row:#?}",
                row.name
            );
        }
    }
    assert!(
        r.false_diagnoses.is_empty(),
        "false diagnoses: {:#?}",
        r.false_diagnoses
    );
    assert_eq!(r.fault_free_hazards, 0);
    assert!(r.fault_free_delivered > 200, "{}", r.fault_free_delivered);
}

#[test]
fn c4_stuck_at_0_at_rest_goes_on_in_degraded_mode_without_hazard() {
    let (_, mut sim) = pop::closed_loop(&station(), 11, 40_000, None).unwrap();
    let before = sim.emulator.stats();
    let delivered_before = before.delivered_total();
    // Wait until the table rests at C4 with A4 off, then C4 dies.
    let c4 = sim.bundle.plant.input("C4").unwrap();
    let a4 = sim.bundle.plant.output("A4").unwrap();
    while !sim.emulator.sensors().get(c4) || sim.engine.applied().get(a4) {
        sim.cycle();
    }
    let at = sim.now().0;
    sim.inject(FaultSpec {
        trigger: Trigger::At(at),
        fault: FaultKind::SensorStuckAt0("C4".into()),
        duration_ms: None,
    })
    .unwrap();
    sim.run_until(Millis(at + 600_000));
    let d = sim.diagnosers.as_ref().unwrap();
    assert!(
        !d.diagnoses.is_empty(),
        "C4 stuck at 0 at rest was not diagnosed"
    );
    assert!(
        d.diagnoses.iter().all(|x| x.partition == "C4"),
        "{:#?}",
        d.diagnoses
    );
    let delay = d.diagnoses[0].time_ms - at;
    assert!(delay < 5_000, "diagnosed after {delay} ms");
    // The task monitors (seed 000) read the estimate too: once C4 is estimated, no
    // task waits for the dead sensor (no "running longer than" alarm, no "unexpected
    // end event" warning). The task under way when C4 died may report once.
    let settled = d.diagnoses[0].time_ms + 20_000;
    let task_lines: Vec<_> = sim
        .journal()
        .iter()
        .filter(|e| e.time_ms > settled && e.kind.starts_with("task_"))
        .collect();
    assert!(task_lines.is_empty(), "{task_lines:#?}");
    assert!(
        d.flagged()
            .iter()
            .any(|(p, stop, s)| p == "C4" && !stop && s.as_deref() == Some("C4"))
    );
    assert!(
        sim.emulator.hazards().is_empty(),
        "{:?}",
        sim.emulator.hazards()
    );
    let after = sim.emulator.stats();
    let delivered = after.delivered_total() - delivered_before;
    // A box every 15 s for 10 minutes: production goes on (degraded).
    assert!(
        delivered >= 30,
        "only {delivered} boxes delivered in degraded mode"
    );
    assert!(
        sim.journal()
            .iter()
            .any(|j| j.text.contains("C4 estimated from time intervals")),
        "the operator is not told that C4 is estimated"
    );
}

#[test]
fn headless_report_lists_the_diagnoses() {
    let scenario = station().join("scenarios/c4-stuck-degraded.ron");
    let out = Command::new(env!("CARGO_BIN_EXE_vigie"))
        .arg("run")
        .arg(&scenario)
        .arg("--headless")
        .arg("--no-timing")
        .current_dir(repo())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let diagnoses = v["diagnoses"].as_array().unwrap();
    assert!(!diagnoses.is_empty(), "{v:#}");
    let first = &diagnoses[0];
    assert_eq!(first["partition"], "C4", "{first}");
    assert_eq!(first["certainty"], "certain", "{first}");
    assert!(first["time_ms"].as_u64().is_some() && first["fault"].as_str().is_some());
    assert_eq!(v["hazards"].as_array().unwrap().len(), 0, "{v:#}");
}

fn python() -> PathBuf {
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| repo().join(".venv"), PathBuf::from);
    let py = venv.join("bin/python");
    assert!(
        py.is_file(),
        "the test venv is missing ({} not found): the libFAUDES cross-check needs the pinned `faudes`. \
         Run `scripts/test.sh` once, or create it with \
         `python3 -m venv .venv && .venv/bin/pip install -r requirements-test.txt` at the repository root \
         (or point VIGIE_VENV at an existing one)",
        py.display()
    );
    py
}

/// Event sequences over a component's symbols: every sequence of up to `depth` events
/// that our untimed replay does not reject before its end, plus the first rejected
/// extension of each.
fn sequences(c: &pop::build::Component, depth: usize) -> Vec<Vec<String>> {
    let names: Vec<&str> = c.symbols.iter().map(|s| s.name.as_str()).collect();
    let mut out = Vec::new();
    let mut frontier: Vec<Vec<&str>> = vec![Vec::new()];
    for _ in 0..depth {
        let mut next = Vec::new();
        for seq in &frontier {
            for n in &names {
                let mut s = seq.clone();
                s.push(n);
                let r = pop::runtime::replay_untimed(c, &s).unwrap();
                if r.last().is_some_and(|x| !x.is_empty()) {
                    next.push(s.clone());
                }
                out.push(s.iter().map(|x| (*x).to_string()).collect());
            }
        }
        frontier = next;
        if out.len() > 20_000 {
            break;
        }
    }
    out
}

#[test]
// One operator's session, step by step: split, the steps would lose their order.
#[allow(clippy::too_many_lines)]
fn libfaudes_gives_the_same_certain_faults_on_the_same_sequences() {
    let py = python();
    let (db, _) = pop::load(&station()).unwrap();
    let tmp = std::env::temp_dir().join(format!("vigie-faudes-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut compared = 0;
    let mut empty: Vec<String> = Vec::new();
    let mut too_big: Vec<String> = Vec::new();
    for c in &db.compiled.components {
        // libFAUDES' diagnoser (an observer of the fault-labelled automaton) grows
        // fast with the automaton: the table (202 states) takes 5 s, the right exit
        // (235) 18 s, the left exit (361) did not finish in 12 minutes, the feed
        // (about 1,450) in 10. Above 300 states the model is left out, and said so.
        if c.g.len() > 300 {
            too_big.push(format!("{} ({} states)", c.id, c.g.len()));
            continue;
        }
        let started = std::time::Instant::now();
        let (g, m) = pop::faudes_export(c);
        let gen_path = tmp.join(format!("{}.gen", c.id));
        let ftm_path = tmp.join(format!("{}.ftm", c.id));
        std::fs::write(&gen_path, g).unwrap();
        std::fs::write(&ftm_path, m).unwrap();
        let depth = if c.id == "table" { 5 } else { 6 };
        let seqs = sequences(c, depth);
        let seq_path = tmp.join(format!("{}.json", c.id));
        let theirs_names: Vec<Vec<String>> = seqs
            .iter()
            .map(|s| s.iter().map(|e| pop::faudes_name(e)).collect())
            .collect();
        std::fs::write(&seq_path, serde_json::to_string(&theirs_names).unwrap()).unwrap();
        let out = Command::new(&py)
            .arg(repo().join("tests/peers/faudes_diag.py"))
            .arg("check")
            .arg(&gen_path)
            .arg(&ftm_path)
            .arg(&seq_path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "faudes_diag.py failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        // The faudes module prints notices on import: the JSON is the last line.
        let text = String::from_utf8_lossy(&out.stdout);
        let last = text
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        if last.contains("\"empty\"") {
            // libFAUDES 2.34.5 builds an empty diagnoser for the one-sensor conveyor
            // models (not understood yet): they are listed, the turntable must compare.
            empty.push(c.id.clone());
            continue;
        }
        eprintln!(
            "libFAUDES on {} ({} states, {} sequences): {:.1} s",
            c.id,
            c.g.len(),
            seqs.len(),
            started.elapsed().as_secs_f64()
        );
        let theirs: Vec<Vec<Option<Vec<String>>>> = serde_json::from_str(last).unwrap();
        assert_eq!(theirs.len(), seqs.len());
        for (seq, row) in seqs.iter().zip(&theirs) {
            let names: Vec<&str> = seq.iter().map(String::as_str).collect();
            let ours = pop::runtime::replay_untimed(c, &names).unwrap();
            for (k, t) in row.iter().enumerate() {
                let o = &ours[k];
                match t {
                    // libFAUDES: the sequence left the language.
                    None => assert!(
                        o.is_empty(),
                        "{}: {names:?} at {k}: libFAUDES rejects, we keep {o:?}",
                        c.id
                    ),
                    Some(labels) => {
                        assert!(
                            !o.is_empty(),
                            "{}: {names:?} at {k}: we reject, libFAUDES has {labels:?}",
                            c.id
                        );
                        // Same certain verdict per partition: a partition is certain when
                        // every hypothesis is a fault of it.
                        for p in &c.partitions {
                            let in_p = |f: &str| p.faults.iter().any(|&i| c.faults[i] == f);
                            let ours_certain = o.iter().all(|h| h.as_deref().is_some_and(in_p));
                            let theirs_certain = labels.iter().all(|l| l != "N" && in_p(l));
                            assert_eq!(
                                ours_certain, theirs_certain,
                                "{}: {names:?} at {k}, partition {}: ours {o:?}, libFAUDES {labels:?}",
                                c.id, p.id
                            );
                        }
                    }
                }
                compared += 1;
            }
        }
    }
    for must in ["table", "right", "c6"] {
        assert!(
            !empty.iter().any(|t| t == must) && !too_big.iter().any(|t| t.starts_with(must)),
            "{must} must be cross-checked: no diagnoser for {empty:?}, too large: {too_big:?}"
        );
    }
    eprintln!(
        "libFAUDES cross-check: {compared} verdicts compared; no libFAUDES diagnoser for {empty:?}; too large for it: {too_big:?}"
    );
    assert!(compared > 1000, "only {compared} verdicts compared");
}

#[test]
fn the_committed_feed_model_is_what_its_generator_writes() {
    // `scripts/gen-feed-model.py` writes the 41-state feed model; an edit by hand (or a
    // generator change not run) would make them drift.
    let out = Command::new("python3")
        .arg(repo().join("scripts/gen-feed-model.py"))
        .arg("--print")
        .output()
        .expect("python3 must be installed (scripts/test.sh installs it)");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let generated = String::from_utf8(out.stdout).unwrap();
    let file = std::fs::read_to_string(station().join("diagnosers.ron")).unwrap();
    assert!(
        file.contains(&generated),
        "diagnosers.ron's feed differs from `python3 scripts/gen-feed-model.py --print`: run `python3 scripts/gen-feed-model.py`"
    );
}
