//! Robustness of the loaders: random bytes and random mutations of the sorting station's
//! files end in a clear error or a valid result, never a panic.
//!
//! `VIGIE_FUZZ_CASES` sets the number of cases per loader (default 2000);
//! `VIGIE_FUZZ_CASES=1000000 cargo test -p vigie --test integration fuzz` is the long run.

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::path::{Path, PathBuf};
use vigie_core::constraints::ConstraintSet;
use vigie_core::diag::Problem;
use vigie_core::observers::Observers;
use vigie_core::plant::Plant;

fn station_file(name: &str) -> String {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    std::fs::read_to_string(dir.join(name)).expect("the sorting station files are readable")
}

fn cases() -> u32 {
    std::env::var("VIGIE_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000)
}

fn runner() -> TestRunner {
    TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    })
}

/// One edit of a text.
#[derive(Clone, Debug)]
enum Edit {
    Insert(usize, char),
    Delete(usize),
    Replace(usize, char),
    SwapLines(usize, usize),
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for e in edits {
        match *e {
            Edit::Insert(i, c) => chars.insert(i % (chars.len() + 1), c),
            Edit::Delete(i) if !chars.is_empty() => {
                chars.remove(i % chars.len());
            }
            Edit::Replace(i, c) if !chars.is_empty() => {
                let n = chars.len();
                chars[i % n] = c;
            }
            Edit::SwapLines(a, b) => {
                let s: String = chars.iter().collect();
                let mut lines: Vec<&str> = s.lines().collect();
                if !lines.is_empty() {
                    let n = lines.len();
                    lines.swap(a % n, b % n);
                }
                chars = lines.join("\n").chars().collect();
            }
            _ => {}
        }
    }
    chars.into_iter().collect()
}

/// Characters that matter to the three formats, plus some that do not.
fn interesting_char() -> impl Strategy<Value = char> {
    prop_oneof![
        prop::sample::select(vec![
            '(', ')', '[', ']', '{', '}', ',', ':', '"', '=', '.', '+', '/', '!', '*', '#', ' ',
            '\n', '\t', '0', '1', '2', 'A', 'C', 'P', 'R', 'E', 'F', 'S', '_', '\\', '\'', 'é',
            '·', '¬', '\u{0}', '\u{feff}',
        ]),
        any::<char>(),
    ]
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), interesting_char()).prop_map(|(i, c)| Edit::Insert(i, c)),
        any::<usize>().prop_map(Edit::Delete),
        (any::<usize>(), interesting_char()).prop_map(|(i, c)| Edit::Replace(i, c)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::SwapLines(a, b)),
    ]
}

/// A mutated copy of `base`, or random text (bytes decoded lossily).
fn input(base: String) -> impl Strategy<Value = String> {
    prop_oneof![
        4 => prop::collection::vec(edit(), 1..8).prop_map(move |e| apply(&base, &e)),
        1 => prop::collection::vec(any::<u8>(), 0..300).prop_map(|b| String::from_utf8_lossy(&b).into_owned()),
    ]
}

/// Every problem is clear: a message, and a location in the file when it has one.
fn check_problems(
    problems: &[Problem],
    file: &Path,
    need_location: bool,
) -> Result<(), TestCaseError> {
    for p in problems {
        prop_assert!(!p.message.trim().is_empty(), "empty message: {:?}", p);
        if need_location {
            let Some(loc) = p.location.as_ref() else {
                return Err(TestCaseError::fail(format!("no location: {p}")));
            };
            prop_assert_eq!(&loc.file, file);
            prop_assert!(loc.line >= 1 && loc.column >= 1, "{}", p);
        }
    }
    Ok(())
}

fn station_plant() -> Plant {
    Plant::from_ron(&station_file("plant.ron"), Path::new("plant.ron"))
        .expect("the station's plant.ron loads")
}

#[test]
fn fuzz_constraints_file() {
    let plant = station_plant();
    let mut symbols = plant.symbols();
    let (_, p) = Observers::from_ron(
        &station_file("observers.ron"),
        Path::new("observers.ron"),
        &mut symbols,
    );
    assert!(p.is_empty());
    let file = Path::new("constraints.txt");
    runner()
        .run(&input(station_file("constraints.txt")), |text| {
            let (set, problems) = ConstraintSet::parse(&text, file, &symbols);
            check_problems(&problems, file, true)?;
            let lines = text.lines().count().max(1);
            for p in &problems {
                let loc = p.location.as_ref().unwrap();
                prop_assert!(loc.line <= lines, "{} beyond {} lines", p, lines);
            }
            for c in &set.constraints {
                prop_assert!(!c.id.is_empty());
                prop_assert!(c.dnf.iter().all(|t| !t.is_empty()));
            }
            check_problems(
                &set.check_property_6(&symbols, &Default::default()).0,
                file,
                true,
            )?;
            Ok(())
        })
        .unwrap();
}

#[test]
fn fuzz_plant_file() {
    let file = Path::new("plant.ron");
    runner()
        .run(&input(station_file("plant.ron")), |text| {
            match Plant::from_ron(&text, file) {
                Ok(plant) => {
                    let symbols = plant.symbols();
                    prop_assert_eq!(
                        symbols.len(vigie_core::symbols::Space::Input),
                        plant.inputs.len()
                    );
                }
                Err(problems) => {
                    prop_assert!(!problems.is_empty());
                    check_problems(&problems, file, true)?;
                }
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn fuzz_observers_file() {
    let plant = station_plant();
    let file = Path::new("observers.ron");
    runner()
        .run(&input(station_file("observers.ron")), |text| {
            let mut symbols = plant.symbols();
            let (obs, problems) = Observers::from_ron(&text, file, &mut symbols);
            check_problems(&problems, file, true)?;
            // Whatever loaded runs.
            let mut obs = obs;
            let mut frame = vigie_core::frame::Frame::new(symbols.sizes());
            for i in 0..4 {
                frame.shift();
                frame
                    .now_mut(vigie_core::symbols::Space::Input)
                    .set(i, true);
                obs.update(&mut frame);
            }
            Ok(())
        })
        .unwrap();
}

/// The station's header and `rows` rows, 10 ms apart, with a few sensors on.
fn station_trace(rows: usize) -> String {
    let plant = station_plant();
    let mut text = vigie_core::trace::header(&plant);
    text.push('\n');
    for i in 0..rows {
        let inputs = vigie_core::bits::Bits::from_bools(
            &(0..plant.inputs.len())
                .map(|k| (i + k) % 3 == 0)
                .collect::<Vec<_>>(),
        );
        let outputs = vigie_core::bits::Bits::from_bools(
            &(0..plant.outputs.len())
                .map(|k| (i * k) % 2 == 1)
                .collect::<Vec<_>>(),
        );
        vigie_core::trace::write_row(
            &mut text,
            vigie_core::Millis(10 * i as u64 + 10),
            &inputs,
            &outputs,
        );
    }
    text
}

#[test]
fn fuzz_trace_file() {
    let plant = station_plant();
    let file = Path::new("trace.csv");
    runner()
        .run(&input(station_trace(6)), |text| {
            match vigie_core::trace::parse(&text, file, &plant) {
                Ok(rows) => {
                    // What loads has strictly increasing times.
                    prop_assert!(rows.windows(2).all(|w| w[0].time < w[1].time));
                }
                Err(p) => {
                    check_problems(std::slice::from_ref(&p), file, true)?;
                    let lines = text.lines().count().max(1);
                    let loc = p.location.as_ref().unwrap();
                    prop_assert!(loc.line <= lines, "{} beyond {} lines", p, lines);
                }
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn fuzz_scenario_file() {
    use vigie_core::sim::Scenario;
    use vigie_core::sim::scenario::{MAX_CYCLE_MS, MAX_RUN_MS};
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    let base = std::fs::read_to_string(dir.join("scenarios/c4-stuck-degraded.ron")).unwrap();
    let file = Path::new("s.ron");
    runner()
        .run(&input(base), |text| {
            match Scenario::from_ron(&text, file) {
                Ok(s) => {
                    prop_assert!((1..=MAX_CYCLE_MS).contains(&s.cycle_ms));
                    prop_assert!((1..=MAX_RUN_MS).contains(&s.duration_ms));
                    prop_assert!(s.actions.iter().all(|a| a.at_ms < s.duration_ms));
                }
                Err(problems) => {
                    prop_assert!(!problems.is_empty());
                    check_problems(&problems, file, true)?;
                    let lines = text.lines().count().max(1);
                    for p in &problems {
                        let loc = p.location.as_ref().unwrap();
                        prop_assert!(loc.line <= lines, "{} beyond {} lines", p, lines);
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn fuzz_layout_file() {
    // A legacy `layout.ron` (the station's first one, kept as a fixture).
    let file = Path::new("layout.ron");
    let fixture = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../core/src/emulator/layout/sorting-station.ron");
    runner()
        .run(&input(std::fs::read_to_string(fixture).unwrap()), |text| {
            if let Err(problems) = vigie_core::emulator::Layout::from_ron(&text, file) {
                prop_assert!(!problems.is_empty());
                check_problems(&problems, file, true)?;
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn fuzz_components_file() {
    let file = Path::new("components.ron");
    runner()
        .run(&input(station_file("components.ron")), |text| {
            if let Err(problems) = vigie_core::machine::Components::from_ron(&text, file) {
                prop_assert!(!problems.is_empty());
                check_problems(&problems, file, true)?;
            }
            Ok(())
        })
        .unwrap();
}

/// Whatever the diagnoser file looks like, as long as it parses, `vigie learn` writes
/// new window bounds in place: the result reads back with exactly those bounds (the
/// rewrite checks it) and the text outside the bounds is unchanged.
#[test]
fn fuzz_learn_rewrite() {
    use vigie_core::pop::model::{Bound, DiagnoserFile};
    let file = Path::new("diagnosers.ron");
    let parsed = std::cell::Cell::new(0u32);
    runner()
        .run(&input(station_file("diagnosers.ron")), |text| {
            let Ok(before) = DiagnoserFile::from_ron(&text, file) else {
                return Ok(());
            };
            parsed.set(parsed.get() + 1);
            let mut learned = before.clone();
            for iv in learned.components.iter_mut().flat_map(|c| &mut c.intervals) {
                if let (Bound::Ms(lo), Bound::Ms(hi)) = (&iv.lo, &iv.hi) {
                    let (lo, hi) = (lo.saturating_add(1), hi.saturating_add(1000));
                    iv.lo = Bound::Ms(lo);
                    iv.hi = Bound::Ms(hi);
                }
            }
            let out = match vigie_core::pop::learn::rewrite(&text, file, &learned) {
                Ok(out) => out,
                Err(p) => return Err(TestCaseError::fail(format!("{p}\n{text}"))),
            };
            // Same text once the values of the bounds are cut out.
            let blank = |t: &str| {
                let mut s = String::new();
                let mut done = 0;
                for f in vigie_core::diag::ron_fields(t) {
                    if (f.name == "lo" || f.name == "hi") && f.is_at(&["components", "intervals"]) {
                        s.push_str(&t[done..f.value.start]);
                        done = f.value.end;
                    }
                }
                s.push_str(&t[done..]);
                s
            };
            let (a, b) = (blank(&text), blank(&out));
            if a != b {
                let k = a.bytes().zip(b.bytes()).take_while(|(x, y)| x == y).count();
                let from = k.saturating_sub(80);
                return Err(TestCaseError::fail(format!(
                    "differs at byte {k}: {:?} / {:?}",
                    a.get(from..(k + 80).min(a.len())),
                    b.get(from..(k + 80).min(b.len()))
                )));
            }
            Ok(())
        })
        .unwrap();
    assert!(parsed.get() > 0, "no mutation parsed");
}
