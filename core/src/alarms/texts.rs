//! Operator texts of the alarms, built from the plant's own names and descriptions (the
//! constraints' comments, the signals' descriptions and elements, the tasks'
//! descriptions), with the engineer's detail (formulas, codes, internal names) kept
//! apart, one click away in the console.

use super::AlarmText;
use crate::bundle::PlantBundle;
use crate::emulator::{Hazard, HazardKind};
use crate::engine::{FiredConstraint, Trip};
use crate::plant::Plant;
use crate::sim::diagnosis::{Cooperation, Notice};
use crate::symbols::Space;
use crate::tasks::{self, TaskSet};

/// A trip of the safety filter: what each violated constraint protects, and what the
/// filter did to the outputs. The detail is each constraint as written.
pub fn trip(bundle: &PlantBundle, trip: &Trip) -> AlarmText {
    let why: Vec<String> = trip
        .constraints
        .iter()
        .map(|fc| violated(bundle, fc, ""))
        .collect();
    let changed = |on: bool| -> Vec<String> {
        trip.actions
            .iter()
            .filter(|a| a.commanded != a.applied && a.applied == on)
            .map(|a| output_phrase(&bundle.plant, &a.output))
            .collect()
    };
    let mut message = if trip.enforced {
        format!("Safety stop: {}", why.join("; "))
    } else {
        format!(
            "Safety violation, plant not stopped (monitor mode: the filter only reports): {}",
            why.join("; ")
        )
    };
    for (list, what) in [(changed(true), "Held ON"), (changed(false), "Stopped")] {
        if !list.is_empty() {
            message.push_str(&format!(". {what}: {}", list.join(", ")));
        }
    }
    let detail = trip
        .constraints
        .iter()
        .map(|fc| format!("{} = {}", fc.id, fc.notation))
        .collect::<Vec<_>>()
        .join("; ");
    let ids = |v: Vec<&str>| v.join(",");
    let outputs = |on: bool| {
        ids(trip
            .actions
            .iter()
            .filter(|a| a.commanded != a.applied && a.applied == on)
            .map(|a| a.output.as_str())
            .collect())
    };
    AlarmText {
        message,
        detail: format!("{detail} (true at {} ms)", trip.time_ms),
        ..AlarmText::default()
    }
    .with(
        "trip",
        [
            (
                "constraints".to_string(),
                ids(trip.constraints.iter().map(|c| c.id.as_str()).collect()),
            ),
            ("held".to_string(), outputs(true)),
            ("stopped".to_string(), outputs(false)),
            ("enforced".to_string(), trip.enforced.to_string()),
        ]
        .into_iter()
        .collect(),
    )
}

/// A violated constraint in the operator's words: what it protects and its id, then
/// `with` (`, with C7 = 1`); `constraint X violated` when it has no description.
fn violated(bundle: &PlantBundle, fc: &FiredConstraint, with: &str) -> String {
    match bundle
        .constraints
        .get(&fc.id)
        .map(|c| c.description.as_str())
    {
        Some(d) if !d.is_empty() => format!("{d} ({}{with})", fc.id),
        _ => format!("constraint {} violated{with}", fc.id),
    }
}

/// A manual request the constraints refuse (`what`: `A4 OFF (…)`): each violated
/// constraint in the operator's words with the plant signals and observers that make it
/// true.
pub fn refused_request(bundle: &PlantBundle, what: &str, refused: &[FiredConstraint]) -> String {
    let why: Vec<String> = refused
        .iter()
        .map(|fc| {
            let context = request_context(fc);
            let with = if context.is_empty() {
                String::new()
            } else {
                format!(", with {}", context.join(", "))
            };
            violated(bundle, fc, &with)
        })
        .collect();
    format!("{what} refused: {}", why.join("; "))
}

/// What makes a refused request's constraint true in the plant: its sensors, observers
/// and outputs at t-1 with their values (`C4 = 1`), in the term's order.
pub fn request_context(fc: &FiredConstraint) -> Vec<String> {
    fc.literals
        .iter()
        .filter(|l| {
            matches!(l.space, Space::Input | Space::Observer)
                || (l.space == Space::Output && l.previous)
        })
        .map(|l| format!("{} = {}", l.name, u8::from(l.value)))
        .collect()
}

/// A certain diagnosis's alarm: the sensor it is about (the estimated one, else its
/// partition) named with its description.
pub fn diagnosis(plant: &Plant, n: &Notice, acts: Cooperation) -> AlarmText {
    let sensor = n.estimated.as_deref().unwrap_or(&n.diagnosis.partition);
    let fields = [
        ("fault", n.diagnosis.fault.replace('|', ", ")),
        ("partition", n.diagnosis.partition.clone()),
        ("component", n.diagnosis.component.clone()),
        ("sensor", n.sensor.clone().unwrap_or_default()),
        ("stop", acts.stop.to_string()),
        ("estimate", acts.estimate.to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    about_signal(plant, sensor, &n.text).with(n.code, fields)
}

/// A sensor the plausibility stage holds as suspect, with its code and fields
/// (`plausibility-suspect`: `sensor`, `edge`, `held`, `latched`).
pub fn plausibility(plant: &Plant, n: &crate::plausibility::Notice) -> AlarmText {
    let mut fields = n.fields.clone();
    fields.insert("sensor".into(), n.sensor.clone());
    about_signal(plant, &n.sensor, &n.text).with(n.code, fields)
}

/// Where to look on the machine after `trip`: the elements of the plant signals its
/// constraints read (`Right exit conveyor (C7)`, `Turntable (A4)`), in order of first
/// mention; signals without an element by their id alone.
pub fn where_to_look(bundle: &PlantBundle, trip: &Trip) -> Vec<String> {
    where_to_look_by_element(bundle, trip)
        .into_iter()
        .map(|(e, ids)| {
            if e.is_empty() {
                ids.join(", ")
            } else {
                format!("{e} ({})", ids.join(", "))
            }
        })
        .collect()
}

/// What [`where_to_look`] says, as data: each element (empty for signals without one)
/// with the ids of its signals, in order of first mention.
pub fn where_to_look_by_element(bundle: &PlantBundle, trip: &Trip) -> Vec<(String, Vec<String>)> {
    let mut by_element: Vec<(String, Vec<String>)> = Vec::new();
    for l in trip.constraints.iter().flat_map(|fc| &fc.literals) {
        let Some(signal) = bundle.plant.signal(&l.name) else {
            continue;
        };
        let element = signal.element.clone();
        match by_element.iter_mut().find(|(e, _)| *e == element) {
            Some((_, ids)) if ids.contains(&l.name) => {}
            Some((_, ids)) => ids.push(l.name.clone()),
            None => by_element.push((element, vec![l.name.clone()])),
        }
    }
    by_element
}

/// `A4 (Turntable)`: an output with its element, when the plant names one.
fn output_phrase(plant: &Plant, id: &str) -> String {
    match plant.signal(id).map(|s| s.element.as_str()) {
        Some(e) if !e.is_empty() => format!("{id} ({e})"),
        _ => id.to_string(),
    }
}

/// A hazard of the emulated plant, in words.
pub fn hazard(h: &Hazard) -> AlarmText {
    let item = |what: &str| format!("Item {} damaged: {what} {}", h.box_id, h.place);
    let message = match h.kind {
        HazardKind::Sheared => item("sheared at the"),
        HazardKind::Dropped => item("fell off the"),
        HazardKind::Collision => item("collided on the"),
        HazardKind::PushedAgainstStopped => item("pushed against a stopped surface"),
        HazardKind::EndStop => format!("{} driven into the end of its travel", h.place),
        HazardKind::OpposedDrives => format!("{} driven both ways at once", h.place),
        HazardKind::Declared => format!("Dangerous state: {}", h.place),
        HazardKind::Overflow => format!("{} overflows", h.place),
        HazardKind::DryRun => format!("{}: a pump runs dry", h.place),
    };
    AlarmText {
        message,
        detail: format!("{:?}; actuators {}", h.kind, h.elements.join(", ")),
        ..AlarmText::default()
    }
    .with(
        "hazard",
        [
            ("item", h.box_id.to_string()),
            ("kind", format!("{:?}", h.kind)),
            ("place", h.place.clone()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .chain(h.at.fields())
        .collect(),
    )
}

/// A task monitor's alarm: the task's description (its first clause) and what is
/// wrong; the detail is the monitor's own text with its bounds and times.
pub fn task(set: Option<&TaskSet>, a: &tasks::Alarm) -> AlarmText {
    let description = set.and_then(|s| {
        s.tasks
            .iter()
            .find(|t| t.id == a.subject)
            .map(|t| t.description.as_str())
            .or_else(|| {
                s.windows
                    .iter()
                    .find(|w| w.id == a.subject)
                    .map(|w| w.description.as_str())
            })
            .or_else(|| {
                s.cross
                    .iter()
                    .find(|c| c.id == a.subject)
                    .map(|c| c.description.as_str())
            })
    });
    let subject = match description.map(first_clause) {
        Some(d) if !d.is_empty() => d,
        _ => format!("Task {}", a.subject),
    };
    AlarmText {
        message: format!("{subject}: {}", a.code.meaning()),
        detail: format!("{} {}: {}", a.code.as_str(), a.subject, a.text),
        ..AlarmText::default()
    }
    .with(
        "task",
        [
            ("subject", subject.clone()),
            ("task", a.subject.clone()),
            ("code", a.code.as_str().to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
    )
}

/// The text up to the first `:`, `(` or `;`, trimmed.
fn first_clause(text: &str) -> String {
    text.split([':', '(', ';'])
        .next()
        .unwrap_or("")
        .trim()
        .to_string()
}

/// A text about a sensor (a diagnosis, a held edge) with the sensor's description after
/// its first mention: `C4 suspect…` → `C4 (Turntable in loading position) suspect…`.
/// The detail is the text as the engine wrote it.
pub fn about_signal(plant: &Plant, sensor: &str, text: &str) -> AlarmText {
    let described = plant
        .signal(sensor)
        .filter(|s| !s.description.is_empty())
        .and_then(|s| {
            let at = find_word(text, sensor)?;
            let end = at + sensor.len();
            Some(format!(
                "{} ({}){}",
                &text[..end],
                s.description,
                &text[end..]
            ))
        });
    AlarmText {
        message: described.unwrap_or_else(|| text.to_string()),
        detail: text.to_string(),
        ..AlarmText::default()
    }
}

/// The byte offset of the first occurrence of `word` in `text` not inside a longer name.
fn find_word(text: &str, word: &str) -> Option<usize> {
    let is_name = |c: char| c.is_alphanumeric() || c == '_';
    text.match_indices(word).map(|(i, _)| i).find(|&i| {
        let before = text[..i].chars().next_back();
        let after = text[i + word.len()..].chars().next();
        !before.is_some_and(is_name) && !after.is_some_and(is_name)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_word_is_found_only_as_a_whole_name() {
        assert_eq!(find_word("fault C4_stuck0 on C4 (table)", "C4"), Some(19));
        assert_eq!(find_word("C40 and XC4", "C4"), None);
        assert_eq!(find_word("C4", "C4"), Some(0));
    }

    #[test]
    fn the_first_clause_of_a_description() {
        assert_eq!(
            first_clause("Box carried from C1 to C3 (at most 4 s)"),
            "Box carried from C1 to C3"
        );
        assert_eq!(first_clause("Push: from C0"), "Push");
        assert_eq!(first_clause(""), "");
    }
}
