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
