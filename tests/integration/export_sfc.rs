//! `vigie export-sfc`: the region monitor as IEC 61131-3 SFC (PLCopen XML) and as an ST
//! function block (seed 000, ch. 6.3).
//!
//! - The workshop of the thesis (12 locations): the steps, the offsets, and each
//!   edge's P0/P1 actions against the translation's rules; two small automata for the
//!   thesis's Exception 1 (Fig. 6.7, the reset moved to the source) and Exception 2
//!   (Fig. 6.8, the destination duplicated).
//! - The function block run scan by scan by the ST interpreter
//!   (`core/src/export/interp.rs`) against the region monitor on the thesis's
//!   scenarios and on random runs: its alarm falls in the PLC scan of the monitor's
//!   alarm instant (the first scan at or after it).
//! - blark (pinned in `requirements-test.txt`, from `$VIGIE_VENV` or `<repo>/.venv`)
//!   parses the function block and every ST body of the XML; the XML, read back with
//!   the XML parser, has the expected steps and transitions.

use crate::export_st::blark_parse;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use vigie_core::Millis;
use vigie_core::export::interp::{Machine, Val, parse};
use vigie_core::swa::regions::{Options, Region, RegionMonitor};
use vigie_core::swa::sfc::{self, Chart};
use vigie_core::swa::{Limits, Q, Swa, SwaFile, synthesize};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn workshop() -> (Swa, Vec<Region>) {
    let (swa, regions, _) =
        sfc::load_monitor(&repo().join("layouts/workshop/workshop.swa.ron")).unwrap();
    (swa, regions)
}

fn small(text: &str) -> (Swa, Vec<Region>) {
    let file: SwaFile = ron::from_str(text).unwrap();
    let swa = file.compile(Path::new("test.swa.ron"), text).unwrap();
    let s = synthesize(&swa, Limits::default()).unwrap();
    let regions = s.monitor_regions(&swa);
    (swa, regions)
}

/// The clocks `E*` of location `l` holds at 0.
fn zero(chart: &Chart, l: usize) -> BTreeSet<usize> {
    let dim = chart.clocks.len();
    (0..dim)
        .filter(|&k| {
            let r = &chart.regions[l];
            !r.is_empty() && r.iter().all(|p| {
                let mut up = vec![Q::zero(); dim];
                up[k] = Q::one();
                let mut down = vec![Q::zero(); dim];
                down[k] = -Q::one();
                let z =
                    |s: Option<Option<(Q, bool)>>| matches!(s, Some(Some((v, _))) if v.is_zero());
                z(p.sup(&up)) && z(p.sup(&down))
            })
        })
        .collect()
}

/// The rules of ch. 6.3 on every transition: P0 of the source adds its time to the
/// clocks running there (and only those); each clock the edge resets is reset by P1
/// of the destination or P0 of the source, or is at 0 in the source already; a P1
/// reset is right for every edge entering the step, a P0 reset for every edge leaving.
fn check_rules(swa: &Swa, chart: &Chart) {
    for s in &chart.steps {
        let running: Vec<usize> = (0..chart.clocks.len())
            .filter(|&k| swa.locations[s.location].rates[k].is_positive())
            .collect();
        assert_eq!(s.running, running, "{}: P0 adds the running clocks", s.name);
    }
    for t in &chart.transitions {
        let e = &swa.edges[t.edge];
        let (from, to) = (&chart.steps[t.from], &chart.steps[t.to]);
        assert_eq!((e.from, e.to), (from.location, to.location), "{}", t.name);
        let z = zero(chart, from.location);
        for &k in &e.resets {
            assert!(
                to.p1_resets.contains(&k) || from.p0_resets.contains(&k) || z.contains(&k),
                "{}: reset of {} not realised",
                t.name,
                chart.clocks[k]
            );
        }
        for &k in &to.p1_resets {
            assert!(
                e.resets.contains(&k) || z.contains(&k),
                "{}: P1 of {} resets {} which the edge keeps",
                t.name,
                to.name,
                chart.clocks[k]
            );
        }
        for &k in &from.p0_resets {
            assert!(
                e.resets.contains(&k) || z.contains(&k),
                "{}: P0 of {} resets {} which the edge keeps",
                t.name,
                from.name,
                chart.clocks[k]
            );
        }
    }
}

#[test]
fn workshop_steps_offsets_and_actions_follow_the_rules() {
    let (swa, regions) = workshop();
    let chart = sfc::translate(&swa, &regions).unwrap();
    assert_eq!(chart.steps.len(), 12, "one step per location");
    assert_eq!(chart.offsets.len(), 5, "δx1, δx2, δy2, δx4, δy4");
    assert_eq!(chart.transitions.len(), swa.edges.len(), "one per edge");
    assert!(chart.forbidden.is_empty() && chart.duplicated.is_empty());
    check_rules(&swa, &chart);
    let step = |loc: &str| {
        let l = swa.location(loc).unwrap();
        chart.steps.iter().find(|s| s.location == l).unwrap()
    };
    let names =
        |ks: &[usize]| -> Vec<&str> { ks.iter().map(|&k| chart.clocks[k].as_str()).collect() };
    // `d` from "A1:wait_d A2:idle" starts the conveyor: P0 adds the step's time to x1
    // (the window's clock runs there). x2 and y2 are already 0 there (E* holds them
    // at 0: `b` reset them), so no action resets them. "A1:run A2:idle" is entered by
    // `d` and by `R` from "A1:run A2:run", which resets x4 and y4 (and `d` finds them
    // at 0): its P1 resets x4 and y4.
    let s0 = step("A1:wait_d A2:idle");
    assert!(s0.initial);
    assert_eq!(names(&s0.running), ["A1.x1"]);
    assert!(s0.p0_resets.is_empty());
    assert_eq!(names(&step("A1:run A2:idle").p1_resets), ["A2.x4", "A2.y4"]);
    // `e` from "A1:at_b A2:idle" reopens the window (x1) and starts the robot (x4, y4,
    // at 0 already). "A1:wait_d A2:run" is also entered by `r_R`, which keeps x1: the
    // reset of x1 is a P0 of "A1:at_b A2:idle", which `e` alone leaves (Fig. 6.7).
    assert_eq!(names(&step("A1:at_b A2:idle").p0_resets), ["A1.x1"]);
    assert!(step("A1:wait_d A2:run").p1_resets.is_empty());
    // An interruption resets nothing and stops y2; "A1:int A2:idle" is also entered
    // by `R` from "A1:int A2:run", so its P1 resets x4 and y4 (which `s_c` finds at 0).
    let int = step("A1:int A2:idle");
    assert_eq!(names(&int.p1_resets), ["A2.x4", "A2.y4"]);
    assert_eq!(names(&int.running), ["A1.x2"]);
}

/// Fig. 6.7: two edges enter `c` resetting different clocks (`x` from `a`, `y` from
/// `b`); each source leaves only by that edge, so the reset moves to its P0.
const EXCEPTION_1: &str = r#"(components: [(name: "k", clocks: ["x", "y"], initial: "i", progress: ["a", "b", "c"],
  locations: [(name: "i"),
    (name: "a", running: ["x", "y"], invariant: "x <= 5000 && y <= 5000"),
    (name: "b", running: ["x", "y"], invariant: "x <= 5000 && y <= 5000"),
    (name: "c", running: ["x", "y"], invariant: "x <= 5000 && y <= 5000")],
  edges: [(from: "i", to: "a", event: "p", reset: ["x", "y"]),
    (from: "i", to: "b", event: "q", reset: ["x", "y"]),
    (from: "a", to: "c", event: "e1", guard: "x >= 1000", reset: ["x"]),
    (from: "b", to: "c", event: "e2", guard: "y >= 1000", reset: ["y"]),
    (from: "c", to: "i", event: "f", guard: "x >= 1000 && y >= 1000", reset: ["x", "y"], goal: true)])])"#;

/// Fig. 6.8: as [`EXCEPTION_1`], but `a` also leaves by `g`, which keeps `x`: the
/// reset of `x` can be neither on `c`'s entry nor on `a`'s exit, so `c` is duplicated.
const EXCEPTION_2: &str = r#"(components: [(name: "k", clocks: ["x", "y"], initial: "i", progress: ["a", "b", "c", "d"],
  locations: [(name: "i"),
    (name: "a", running: ["x", "y"], invariant: "x <= 5000 && y <= 5000"),
    (name: "b", running: ["x", "y"], invariant: "x <= 5000 && y <= 5000"),
    (name: "c", running: ["x", "y"], invariant: "x <= 5000 && y <= 5000"),
    (name: "d", running: ["x"], invariant: "x <= 5000 && y <= 5000")],
  edges: [(from: "i", to: "a", event: "p", reset: ["x", "y"]),
    (from: "i", to: "b", event: "q", reset: ["x", "y"]),
    (from: "a", to: "c", event: "e1", guard: "x >= 1000", reset: ["x"]),
    (from: "a", to: "d", event: "g"),
    (from: "d", to: "a", event: "h"),
    (from: "b", to: "c", event: "e2", guard: "y >= 1000", reset: ["y"]),
    (from: "c", to: "i", event: "f", guard: "x >= 1000 && y >= 1000", reset: ["x", "y"], goal: true)])])"#;

#[test]
fn exception_1_moves_the_reset_to_the_source() {
    let (swa, regions) = small(EXCEPTION_1);
    let chart = sfc::translate(&swa, &regions).unwrap();
    check_rules(&swa, &chart);
    assert!(chart.duplicated.is_empty());
    let step = |n: &str| {
        chart
            .steps
            .iter()
            .find(|s| swa.locations[s.location].name == n)
            .unwrap()
    };
    assert_eq!(step("k:a").p0_resets, [0], "P0 of a resets x");
    assert_eq!(step("k:b").p0_resets, [1], "P0 of b resets y");
    assert!(step("k:c").p1_resets.is_empty());
    compare_random(&swa, &regions, &chart, 150, 7);
}

#[test]
fn exception_2_duplicates_the_destination() {
    let (swa, regions) = small(EXCEPTION_2);
    let chart = sfc::translate(&swa, &regions).unwrap();
    check_rules(&swa, &chart);
    let c = swa.location("k:c").unwrap();
    assert_eq!(chart.duplicated, [c]);
    let copies: Vec<_> = chart.steps.iter().filter(|s| s.location == c).collect();
    assert_eq!(copies.len(), 2);
    // The copy entered from a resets x on entry; the one from b needs no P1 (P0 of b
    // resets y, b leaving only by e2).
    let from_a = chart
        .transitions
        .iter()
        .find(|t| chart.events[t.event].0 == "e1")
        .unwrap();
    assert_eq!(chart.steps[from_a.to].p1_resets, [0]);
    let b = chart
        .steps
        .iter()
        .find(|s| swa.locations[s.location].name == "k:b")
        .unwrap();
    assert_eq!(b.p0_resets, [1]);
    assert_eq!(chart.steps.len(), 6);
    compare_random(&swa, &regions, &chart, 150, 11);
}

// ---- The function block against the region monitor ----

/// The first alarm of the region monitor: `(at, after)`.
fn monitor_alarm(
    swa: &Swa,
    regions: &[Region],
    events: &[(u64, String)],
    until: u64,
) -> Option<(u64, bool)> {
    let mut m = RegionMonitor::new(swa.clone(), regions.to_vec(), Millis(0), Options::default());
    let mut first = None;
    for (t, e) in events {
        if e == "m" {
            m.advance(Millis(*t));
            first = first.or_else(|| m.alarm().map(|a| (a.at.at.0, a.at.after)));
            m.repair(Millis(*t));
        } else {
            m.on_event(Millis(*t), e);
        }
        first = first.or_else(|| m.alarm().map(|a| (a.at.at.0, a.at.after)));
    }
    m.advance(Millis(until));
    first.or_else(|| m.alarm().map(|a| (a.at.at.0, a.at.after)))
}

/// Runs the function block: a scan every `tc` ms and one at each event's instant
/// (`CycleMs` the time since the last scan; events at one instant in successive
/// scans), `EqTolMs` one cycle. Returns the scan times and the first alarm's.
fn fb_alarm(
    chart: &Chart,
    events: &[(u64, String)],
    until: u64,
    tc: u64,
) -> (Vec<u64>, Option<u64>) {
    let unit = parse(&chart.function_block()).unwrap();
    let mut fb = Machine::new(unit, "FB_RegionMonitor").unwrap();
    fb.set("EqTolMs", Val::Int(tc as i64)).unwrap();
    let input = |e: &str| -> Option<String> {
        if e == "m" {
            return Some("Repair".into());
        }
        chart
            .events
            .iter()
            .find(|(n, _)| n == e)
            .map(|(_, id)| id.clone())
    };
    // (time, event)
    let mut scans: Vec<(u64, Option<String>)> = (0..=until / tc).map(|k| (k * tc, None)).collect();
    scans.extend(events.iter().map(|(t, e)| (*t, Some(e.clone()))));
    scans.sort_by_key(|(t, e)| (*t, e.is_some()));
    let (mut last, mut first, mut times) = (0u64, None, Vec::new());
    for (t, e) in &scans {
        fb.set("CycleMs", Val::Int((*t - last) as i64)).unwrap();
        let var = e.as_deref().and_then(input);
        if let Some(v) = &var {
            fb.set(v, Val::Bool(true)).unwrap();
        }
        fb.scan().unwrap();
        if let Some(v) = &var {
            fb.set(v, Val::Bool(false)).unwrap();
        }
        last = *t;
        times.push(*t);
        if first.is_none() && fb.get("Alarm").unwrap() == Val::Bool(true) {
            first = Some(*t);
        }
    }
    (times, first)
}

/// The function block alarms in the first scan at (or, for a non-strict bound, after)
/// the region monitor's alarm instant, and never without it.
fn compare(
    swa: &Swa,
    regions: &[Region],
    chart: &Chart,
    events: &[(u64, String)],
    until: u64,
    tc: u64,
) -> Option<u64> {
    let want = monitor_alarm(swa, regions, events, until);
    let (times, got) = fb_alarm(chart, events, until, tc);
    let expected = want.and_then(|(at, after)| {
        times
            .iter()
            .copied()
            .find(|&s| if after { s > at } else { s >= at })
    });
    assert_eq!(
        got, expected,
        "events {events:?}: the region monitor alarms at {want:?}, the function block at {got:?}"
    );
    got
}

/// A small deterministic generator (the tests need no seed file).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 33) % n.max(1)
    }
}

/// Random runs: from the current location, mostly an event it accepts, sometimes any
/// event or the repair, after a random delay.
fn compare_random(swa: &Swa, regions: &[Region], chart: &Chart, runs: usize, seed: u64) {
    let mut rng = Lcg(seed);
    let all: Vec<String> = swa.events().into_iter().map(str::to_string).collect();
    let (mut alarms, mut quiet) = (0, 0);
    for _ in 0..runs {
        let mut events = Vec::new();
        let mut t = 0;
        let mut loc = 0;
        for _ in 0..rng.next(10) + 2 {
            t += rng.next(2500);
            let out: Vec<&vigie_core::swa::automaton::Edge> =
                swa.edges.iter().filter(|e| e.from == loc).collect();
            let r = rng.next(20);
            let e = if r == 0 {
                loc = 0;
                "m".to_string()
            } else if r == 1 || out.is_empty() {
                all[rng.next(all.len() as u64) as usize].clone()
            } else {
                let e = out[rng.next(out.len() as u64) as usize];
                loc = e.to;
                e.event.clone()
            };
            events.push((t, e));
        }
        match compare(swa, regions, chart, &events, t + 6000, 10) {
            Some(_) => alarms += 1,
            None => quiet += 1,
        }
    }
    assert!(
        alarms > 0 && quiet > 0,
        "the runs cover both: {alarms} alarms, {quiet} without"
    );
}

fn ev(list: &[(u64, &str)]) -> Vec<(u64, String)> {
    list.iter().map(|(t, e)| (*t, (*e).to_string())).collect()
}

#[test]
fn workshop_function_block_alarms_in_the_scan_of_the_region_monitor() {
    let (swa, regions) = workshop();
    let chart = sfc::translate(&swa, &regions).unwrap();
    // Scenario 1: the conveyor blocked at 4 s, the alarm at 6 s (T001).
    let s1 = ev(&[
        (0, "d"),
        (3000, "b"),
        (3000, "e"),
        (4000, "d"),
        (4000, "s_c"),
        (5000, "R"),
    ]);
    assert_eq!(compare(&swa, &regions, &chart, &s1, 20_000, 10), Some(6000));
    // The same with the repair at 7 s: back to the start, no second alarm.
    let mut s1m = s1.clone();
    s1m.push((7000, "m".into()));
    s1m.extend(ev(&[(7500, "d"), (11_000, "b")]));
    assert_eq!(
        compare(&swa, &regions, &chart, &s1m, 14_000, 10),
        Some(6000)
    );
    // Scenario 2 (reconstructed): 1.5 s of interruptions, no alarm.
    let s2 = ev(&[
        (1000, "d"),
        (2000, "s_c"),
        (2500, "r_c"),
        (3000, "s_c"),
        (4000, "r_c"),
        (5500, "b"),
    ]);
    assert_eq!(compare(&swa, &regions, &chart, &s2, 5900, 10), None);
    // Scenario 3: the robot stopped at 5 s, the alarm at 6.5 s with b.
    let s3 = ev(&[
        (0, "d"),
        (3000, "b"),
        (3000, "e"),
        (3500, "d"),
        (4000, "s_R"),
        (4500, "r_R"),
        (5000, "s_R"),
        (6500, "b"),
    ]);
    assert_eq!(compare(&swa, &regions, &chart, &s3, 20_000, 10), Some(6500));
    // No d within 2 s of e: just after 5 s, in the next scan.
    let w = ev(&[(0, "d"), (3000, "b"), (3000, "e")]);
    assert_eq!(compare(&swa, &regions, &chart, &w, 4900, 10), None);
    assert_eq!(compare(&swa, &regions, &chart, &w, 6000, 10), Some(5010));
    // With a 7 ms cycle the instants fall between scans.
    assert_eq!(compare(&swa, &regions, &chart, &s1, 20_000, 7), Some(6006));
    compare_random(&swa, &regions, &chart, 300, 1);
}

#[test]
fn plant_task_monitors_export_and_agree_with_their_regions() {
    for layout in ["single-conveyor", "workshop"] {
        let (swa, regions, _) =
            sfc::load_monitor(&repo().join("layouts").join(layout).join("tasks.ron")).unwrap();
        let chart = sfc::translate(&swa, &regions).unwrap();
        check_rules(&swa, &chart);
        compare_random(&swa, &regions, &chart, 60, 3);
    }
}

// ---- blark and the XML ----

#[test]
fn blark_parses_the_function_block_and_every_body_of_the_xml() {
    let (swa, regions) = workshop();
    let chart = sfc::translate(&swa, &regions).unwrap();
    let fb = chart.function_block();
    let (ok, log) = blark_parse("workshop_monitor.st", &fb);
    assert!(
        ok,
        "blark rejected the function block:\n{}",
        &log[log.len().saturating_sub(3000)..]
    );
    assert!(log.contains("FB_RegionMonitor"));

    let xml = chart.plcopen("workshop");
    let o = sfc::outline(&xml).expect("well-formed XML");
    let names: Vec<&str> = o.pous.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["SFC1", "SFC2"]);
    let (sfc1, sfc2) = (&o.pous[0].1, &o.pous[1].1);
    assert_eq!(sfc1.steps.len(), 12);
    assert_eq!(sfc1.steps.iter().filter(|s| s.1).count(), 1);
    // One transition per edge, and each step's restart (the repair).
    assert_eq!(sfc1.conditions.len(), swa.edges.len() + 12);
    // P1, N and P0 on every step.
    assert_eq!(sfc1.blocks.len(), 3 * 12);
    assert!(
        sfc1.blocks
            .iter()
            .all(|(s, _, a)| a.starts_with(&format!("{s}_")))
    );
    assert_eq!(
        sfc2.steps,
        [
            ("ACCEPTABLE".to_string(), true),
            ("FAULT".to_string(), false)
        ]
    );
    assert_eq!(sfc2.conditions.len(), 2);
    assert!(
        sfc2.blocks
            .contains(&("FAULT".into(), "N".into(), "Alarm".into()))
    );
    assert!(sfc2.conditions[0].1.contains("X_S5 AND"));

    let bodies = sfc::bodies_as_st(&o);
    let (ok, log) = blark_parse("workshop_sfc_bodies.st", &bodies);
    assert!(
        ok,
        "blark rejected the XML's ST bodies:\n{}",
        &log[log.len().saturating_sub(3000)..]
    );
    // Control: a broken body is rejected.
    let (ok, _) = blark_parse("broken.st", &bodies.replacen(":= 0;", ":= := 0;", 1));
    assert!(!ok, "blark accepted a broken body");
}

#[test]
fn export_sfc_command_writes_both_files() {
    let out = std::env::temp_dir().join(format!("vigie-export-sfc-cli-{}", std::process::id()));
    let status = Command::new(env!("CARGO_BIN_EXE_vigie"))
        .arg("export-sfc")
        .arg(repo().join("layouts/workshop/workshop.swa.ron"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&status.stdout);
    assert!(
        status.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&status.stderr)
    );
    assert!(stdout.contains("SFC1: 12 steps"), "{stdout}");
    let xml = std::fs::read_to_string(out.join("workshop.sfc.xml")).unwrap();
    let st = std::fs::read_to_string(out.join("workshop.monitor.st")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    assert!(sfc::outline(&xml).is_ok());
    assert!(st.starts_with("(* The region monitor"));
}

/// The liquid supply of seed 000 ch. 6.4 from its stopwatch Petri net
/// (`layouts/liquid-supply/liquid.swpn.ron`, regions synthesised exactly with
/// `--members 64`): the committed regions are what the net gives, SFC1 has the thesis's
/// 22 steps and 9 offset variables, the function block raises the thesis's alarm in the
/// scan of τ = 9 s (d at 0, h1 3, h2 5, s_b1 6, s_b2 6.1: empty tank 1 can no longer end),
/// agrees with the region monitor on random runs, and blark parses it.
#[test]
fn liquid_supply_from_its_petri_net_exports_22_steps_and_9_offsets() {
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_vigie"))
            .args(args)
            .current_dir(repo())
            .output()
            .unwrap()
    };
    let net = "layouts/liquid-supply/liquid.swpn.ron";
    let out = run(&["synthesize", net, "--members", "64", "--check"]);
    let said = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{said}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(said.contains("26 locations (4 unreachable"), "{said}");
    assert!(said.contains("is up to date"), "{said}");
    let (swa, regions, _) = sfc::load_monitor(&repo().join(net)).unwrap();
    let chart = sfc::translate(&swa, &regions).unwrap();
    let fb = chart.function_block();
    let outline = sfc::outline(&chart.plcopen("liquid")).unwrap();
    let steps: Vec<usize> = outline.pous.iter().map(|(_, c)| c.steps.len()).collect();
    assert_eq!(steps, [22, 2], "SFC1 and SFC2");
    assert_eq!(chart.offsets.len(), 9, "{:?}", chart.offsets);
    let scenario = ev(&[
        (0, "d"),
        (3000, "h1"),
        (5000, "h2"),
        (6000, "s_b1"),
        (6100, "s_b2"),
    ]);
    assert_eq!(
        compare(&swa, &regions, &chart, &scenario, 12_000, 10),
        Some(9000)
    );
    let nominal = ev(&[
        (0, "d"),
        (3000, "h1"),
        (4000, "h2"),
        (7000, "b2"),
        (8000, "b1"),
    ]);
    assert_eq!(compare(&swa, &regions, &chart, &nominal, 20_000, 10), None);
    // An interruption within tolerance, and one beyond it (fill tank 2 stopped at 1 s:
    // x4 − y4 reaches γ − α = 3 at 4 s).
    let tolerated = ev(&[
        (0, "d"),
        (1000, "s_h1"),
        (2000, "r_h1"),
        (4000, "h1"),
        (4500, "h2"),
        (8000, "b2"),
        (9500, "b1"),
    ]);
    assert_eq!(
        compare(&swa, &regions, &chart, &tolerated, 20_000, 10),
        None
    );
    let stopped = ev(&[(0, "d"), (1000, "s_h2")]);
    assert_eq!(
        compare(&swa, &regions, &chart, &stopped, 10_000, 10),
        Some(4000)
    );
    let (ok, log) = blark_parse("liquid_monitor.st", &fb);
    assert!(ok, "{log}");
}
