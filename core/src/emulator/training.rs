//! The training library of a plant folder, as data a trainer edits: the faults the
//! trainer injects live (`faults.ron`) and the plant-fault exercises (`exercises.ron`),
//! where the trainee meets a stopped plant, names the faulty component, and repairs it.

use super::FaultSpec;
use crate::diag::{Location, Problem, codes, read_text_optional, ron_problem};
use crate::plant::Plant;
use serde::Deserialize;
use std::collections::BTreeSet;
use std::path::Path;

/// One fault of the trainer's library: its name and what it does.
pub type NamedFault = (String, FaultSpec);

/// A plant-fault exercise: the reference program runs, the fault starts at its trigger
/// and stays hidden; the trainee names the faulty component.
#[derive(Clone, Debug, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlantExercise {
    /// `P01`.
    pub id: String,
    /// What happened, in the trainer's words: shown in the debrief only.
    pub description: String,
    /// The components whose naming counts as the right answer (signal ids of the
    /// plant: the sensor itself, or the actuator and its feedback).
    pub answer: Vec<String>,
    /// The hidden fault.
    pub fault: FaultSpec,
}

impl PlantExercise {
    /// True when naming `component` answers the exercise.
    pub fn is_answer(&self, component: &str) -> bool {
        self.answer.iter().any(|a| a == component)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExercisesFile {
    exercises: Vec<PlantExercise>,
}

/// Reads `faults.ron`: the trainer's fault library (none without the file). With an
/// emulator, each fault is also scheduled on a copy of it, so that a fault the emulator
/// refuses (a sensor it does not place, a condition that does not parse) is a load
/// problem with its line, not a refusal when the trainer injects it.
pub fn load_faults(
    path: &Path,
    plant: &Plant,
    emulator: Option<&crate::machine::Physical>,
) -> Result<Vec<NamedFault>, Vec<Problem>> {
    let Some((text, faults)) = read::<Vec<NamedFault>>(path)? else {
        return Ok(Vec::new());
    };
    let problems: Vec<Problem> = faults
        .iter()
        .filter_map(|(name, spec)| {
            let at = Some(locate(path, &text, name, 0));
            if let Some(s) = unknown_signal(plant, spec) {
                return Some(Problem::error(
                    codes::FAULT_UNKNOWN_SIGNAL.id,
                    format!("fault `{name}` names `{s}`, which the plant does not declare"),
                    at,
                ));
            }
            refused(emulator, spec).map(|p| Problem {
                message: format!("fault `{name}`: {}", p.message),
                location: at,
                ..p
            })
        })
        .collect();
    if problems.is_empty() {
        Ok(faults)
    } else {
        Err(problems)
    }
}

/// Reads `exercises.ron`: the plant-fault exercises (none without the file). Every id
/// is unique, every answer names a plant signal, the fault's signal exists and, with an
/// emulator, the fault can be scheduled on it (see [`load_faults`]).
pub fn load_exercises(
    path: &Path,
    plant: &Plant,
    emulator: Option<&crate::machine::Physical>,
) -> Result<Vec<PlantExercise>, Vec<Problem>> {
    let Some((text, file)) = read::<ExercisesFile>(path)? else {
        return Ok(Vec::new());
    };
    let mut ids = BTreeSet::new();
    let mut problems = Vec::new();
    for (i, e) in file.exercises.iter().enumerate() {
        // The nth exercise of that id is at the nth occurrence of the id.
        let nth = file.exercises[..i].iter().filter(|o| o.id == e.id).count();
        let at = || Some(locate(path, &text, &e.id, nth));
        if !ids.insert(e.id.as_str()) {
            problems.push(Problem::error(
                codes::EXERCISE_DUPLICATE.id,
                format!("exercise `{}` is declared twice", e.id),
                at(),
            ));
        }
        if e.answer.is_empty() {
            problems.push(Problem::error(
                codes::EXERCISE_ANSWER.id,
                format!("exercise `{}` has no answer", e.id),
                at(),
            ));
        }
        for a in e.answer.iter().filter(|a| !is_signal(plant, a)) {
            problems.push(Problem::error(
                codes::EXERCISE_ANSWER.id,
                format!(
                    "exercise `{}`: the answer `{a}` is not a signal of the plant",
                    e.id
                ),
                at(),
            ));
        }
        if let Some(s) = unknown_signal(plant, &e.fault) {
            problems.push(Problem::error(
                codes::FAULT_UNKNOWN_SIGNAL.id,
                format!(
                    "exercise `{}`: the fault names `{s}`, which the plant does not declare",
                    e.id
                ),
                at(),
            ));
        } else if let Some(p) = refused(emulator, &e.fault) {
            problems.push(Problem {
                message: format!("exercise `{}`: {}", e.id, p.message),
                location: at(),
                ..p
            });
        }
    }
    if problems.is_empty() {
        Ok(file.exercises)
    } else {
        Err(problems)
    }
}

/// The text of an optional file of the library and what it parses to (`None`: no file).
fn read<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Option<(String, T)>, Vec<Problem>> {
    let Some(text) = read_text_optional(path).map_err(|p| vec![p])? else {
        return Ok(None);
    };
    let parsed = ron::from_str(&text).map_err(|e| vec![ron_problem(path, &e)])?;
    Ok(Some((text, parsed)))
}

/// Why `emulator` refuses to schedule `spec` (on a copy), if it does.
fn refused(emulator: Option<&crate::machine::Physical>, spec: &FaultSpec) -> Option<Problem> {
    emulator?.clone().try_schedule_fault(spec.clone()).err()
}

fn is_signal(plant: &Plant, id: &str) -> bool {
    plant
        .inputs
        .iter()
        .chain(&plant.outputs)
        .any(|s| s.id == id)
}

/// The signal `spec` names when the plant does not declare it.
fn unknown_signal(plant: &Plant, spec: &FaultSpec) -> Option<String> {
    spec.fault
        .fields()
        .remove("signal")
        .filter(|s| !is_signal(plant, s))
}

/// The position of the `nth` occurrence of `"key"` in `text`, else the file's start.
fn locate(path: &Path, text: &str, key: &str, nth: usize) -> Location {
    Location::of_nth(path, text, &format!("\"{key}\""), nth)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::station_dir;

    fn plant() -> Plant {
        crate::test_support::station().plant
    }

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("vigie-exercises-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn the_stations_library_loads() {
        let plant = plant();
        let faults = load_faults(&station_dir().join("faults.ron"), &plant, None).unwrap();
        assert!(faults.len() >= 8);
        let ex = load_exercises(&station_dir().join("exercises.ron"), &plant, None).unwrap();
        assert!(ex.len() >= 3);
        assert!(ex.iter().all(|e| !e.answer.is_empty()));
    }

    #[test]
    fn no_file_is_an_empty_library() {
        let plant = plant();
        let none = std::env::temp_dir().join("vigie-no-such-dir/exercises.ron");
        assert_eq!(load_exercises(&none, &plant, None).unwrap(), Vec::new());
        assert_eq!(load_faults(&none, &plant, None).unwrap(), Vec::new());
    }

    #[test]
    fn bad_exercises_are_refused_with_their_line() {
        let plant = plant();
        let path = write(
            "bad-exercises.ron",
            r#"(exercises: [
    (id: "P1", description: "", answer: ["C7"], fault: (trigger: At(0), fault: SensorStuckAt0("C7"))),
    (id: "P1", description: "", answer: [], fault: (trigger: At(0), fault: SensorStuckAt0("C77"))),
    (id: "P2", description: "", answer: ["Z9"], fault: (trigger: At(0), fault: ActuatorStuckOn("A1"))),
])"#,
        );
        let err = load_exercises(&path, &plant, None).unwrap_err();
        let text = crate::diag::render(&err);
        assert!(text.contains("V0706"), "{text}");
        assert!(text.contains("`P1` is declared twice"), "{text}");
        assert!(text.contains("`P1` has no answer"), "{text}");
        assert!(text.contains("`C77`"), "{text}");
        assert!(text.contains("the answer `Z9`"), "{text}");
        assert!(text.contains("bad-exercises.ron:4:10"), "{text}");
        assert!(text.contains("bad-exercises.ron:3:10"), "{text}");
        let syntax = write("syntax.ron", "(exercises: [(id: 1)])");
        let err = load_exercises(&syntax, &plant, None).unwrap_err();
        assert!(
            crate::diag::render(&err).contains("syntax.ron:1:"),
            "{err:?}"
        );
    }

    #[test]
    fn a_fault_on_an_unknown_signal_is_refused() {
        let plant = plant();
        let path = write(
            "bad-faults.ron",
            "[\n (\"ok\", (trigger: At(0), fault: SensorStuckAt0(\"C7\"))),\n (\"ghost\", (trigger: At(0), fault: SensorStuckAt1(\"C99\"))),\n]",
        );
        let err = load_faults(&path, &plant, None).unwrap_err();
        let text = crate::diag::render(&err);
        assert!(
            text.contains("V0703") && text.contains("bad-faults.ron:3:3"),
            "{text}"
        );
    }

    /// What the emulator refuses is refused at load, with the line: an actuator named
    /// as a sensor, a condition that does not parse.
    #[test]
    fn a_fault_the_emulator_refuses_is_a_load_problem() {
        let bundle = crate::test_support::station();
        let layout = crate::test_support::station_layout();
        let emu = crate::machine::Physical::of_cell(&layout, &bundle.plant, 1).unwrap();
        let path = write(
            "refused-exercises.ron",
            r#"(exercises: [
    (id: "P1", description: "", answer: ["A1"], fault: (trigger: At(0), fault: SensorStuckAt0("A1"))),
    (id: "P2", description: "", answer: ["C3"], fault: (trigger: When("C3 . "), fault: SensorStuckAt1("C3"))),
])"#,
        );
        // The plant declares A1: only the emulator can tell it is no sensor.
        assert!(load_exercises(&path, &bundle.plant, None).is_ok());
        let text =
            crate::diag::render(&load_exercises(&path, &bundle.plant, Some(&emu)).unwrap_err());
        assert!(
            text.contains("refused-exercises.ron:2:10") && text.contains("V0703"),
            "{text}"
        );
        assert!(
            text.contains("refused-exercises.ron:3:10") && text.contains("V0704"),
            "{text}"
        );
        let faults = load_faults(&station_dir().join("faults.ron"), &bundle.plant, Some(&emu));
        assert!(faults.is_ok(), "{faults:?}");
        let ex = load_exercises(
            &station_dir().join("exercises.ron"),
            &bundle.plant,
            Some(&emu),
        );
        assert!(ex.is_ok(), "{ex:?}");
    }
}
