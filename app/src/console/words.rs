//! The texts the console builds from the plant's data and the engine's records (a
//! trip's alarm, where to look, why a reset is refused) in the language shown. In
//! English they are the core's own texts (`vigie_core::alarms::texts`), the records of
//! the journal; in another language they are built from the same data with the
//! console's messages and the plant folder's translations (`constraint-<id>`,
//! `element-<name>` with the name in lower case and its spaces as dashes).

use crate::i18n::{I18n, Lang};
use vigie_core::alarms::Alarm;
use vigie_core::alarms::texts;
use vigie_core::bundle::PlantBundle;
use vigie_core::emulator::FaultSpec;
use vigie_core::engine::{ResetRefused, Trip};

/// The plant's name of an element in the language shown.
pub(crate) fn element(i18n: &I18n, element: &str) -> String {
    let key = format!("element-{}", element.to_lowercase().replace(' ', "-"));
    i18n.plant(&key).unwrap_or_else(|| element.to_string())
}

/// `A4 (Table tournante)`: a signal with its element.
fn signal_phrase(i18n: &I18n, bundle: &PlantBundle, id: &str) -> String {
    match bundle.plant.signal(id).map(|s| s.element.as_str()) {
        Some(e) if !e.is_empty() => format!("{id} ({})", element(i18n, e)),
        _ => id.to_string(),
    }
}

/// What a constraint protects, and its id.
fn constraint_phrase(i18n: &I18n, bundle: &PlantBundle, id: &str) -> String {
    constraint_phrase_with(i18n, bundle, id, "")
}

/// What a constraint protects, its id and `with` (`, avec C4 = 1`).
fn constraint_phrase_with(i18n: &I18n, bundle: &PlantBundle, id: &str, with: &str) -> String {
    use vigie_core::pop::coop::{STOP_PREFIX, is_diagnoser_stop};
    let generated = is_diagnoser_stop(id).then(|| {
        let partition = id.trim_start_matches(STOP_PREFIX);
        i18n.ta("words-diagnoser-stop", &[("partition", partition.into())])
    });
    let description = i18n
        .plant(&format!("constraint-{id}"))
        .or(generated)
        .or_else(|| {
            bundle
                .constraints
                .get(id)
                .map(|c| c.description.clone())
                .filter(|d| !d.is_empty())
        });
    match description {
        Some(d) => format!("{d} ({id}{with})"),
        None => i18n.ta("words-constraint-violated", &[("id", id.into())]) + with,
    }
}

/// A manual request the constraints refuse, in the language shown: `refused` is
/// [`vigie_core::engine::Engine::check_request`]'s answer for it; `core_text` what the
/// core said (the record, and the English text).
pub(crate) fn refused_request(
    i18n: &I18n,
    bundle: &PlantBundle,
    id: &str,
    on: bool,
    refused: &[vigie_core::engine::FiredConstraint],
    core_text: &str,
) -> String {
    if i18n.lang() == Lang::En || refused.is_empty() {
        return core_text.to_string();
    }
    let why: Vec<(String, String)> = refused
        .iter()
        .map(|fc| (fc.id.clone(), texts::request_context(fc).join(", ")))
        .collect();
    refusal(i18n, bundle, id, on, &why)
}

/// A refused manual request from its journal fields (`output`, `on`, `constraints` and
/// `with-<constraint>`), in the language shown.
fn refusal_from_fields(
    i18n: &I18n,
    bundle: &PlantBundle,
    fields: &std::collections::BTreeMap<String, String>,
) -> Option<String> {
    let output = fields.get("output")?;
    let on = fields.get("on")? == "true";
    let why: Vec<(String, String)> = fields
        .get("constraints")?
        .split(',')
        .filter(|c| !c.is_empty())
        .map(|c| {
            let with = fields
                .get(&format!("with-{c}"))
                .cloned()
                .unwrap_or_default();
            (c.to_string(), with)
        })
        .collect();
    Some(refusal(i18n, bundle, output, on, &why))
}

/// `id` ON (or OFF, with what that does) refused, and why: each constraint with the
/// values that make it refuse (`C4 = 1, C6 = 0`).
fn refusal(
    i18n: &I18n,
    bundle: &PlantBundle,
    id: &str,
    on: bool,
    why: &[(String, String)],
) -> String {
    let what = if on {
        i18n.ta("words-request-on", &[("id", id.into())])
    } else {
        match i18n.plant(&format!("off-{id}")) {
            Some(m) => i18n.ta(
                "words-request-off-meaning",
                &[("id", id.into()), ("meaning", (&m).into())],
            ),
            None => i18n.ta("words-request-off", &[("id", id.into())]),
        }
    };
    let why: Vec<String> = why
        .iter()
        .map(|(c, context)| {
            let with = if context.is_empty() {
                String::new()
            } else {
                i18n.ta("words-with", &[("values", context.into())])
            };
            constraint_phrase_with(i18n, bundle, c, &with)
        })
        .collect();
    i18n.ta(
        "words-request-refused",
        &[("what", (&what).into()), ("why", (&why.join(" ; ")).into())],
    )
}

/// The trip alarm's text.
pub(crate) fn trip_message(i18n: &I18n, bundle: &PlantBundle, trip: &Trip) -> String {
    if i18n.lang() == Lang::En {
        return texts::trip(bundle, trip).message;
    }
    trip_from_fields(i18n, bundle, &texts::trip(bundle, trip).fields)
}

/// A trip alarm's text in the language shown from its fields (`constraints`, `held`,
/// `stopped`: ids, comma-separated), as an earlier run's alarm keeps them.
fn trip_from_fields(
    i18n: &I18n,
    bundle: &PlantBundle,
    fields: &std::collections::BTreeMap<String, String>,
) -> String {
    let ids = |k: &str| -> Vec<&str> {
        fields.get(k).map_or(Vec::new(), |v| {
            v.split(',').filter(|s| !s.is_empty()).collect()
        })
    };
    let why: Vec<String> = ids("constraints")
        .iter()
        .map(|id| constraint_phrase(i18n, bundle, id))
        .collect();
    let list = |k: &str| -> String {
        ids(k)
            .iter()
            .map(|o| signal_phrase(i18n, bundle, o))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let id = if fields.get("enforced").is_some_and(|e| e == "false") {
        "words-safety-violation"
    } else {
        "words-safety-stop"
    };
    let mut text = i18n.ta(id, &[("why", (&why.join(" ; ")).into())]);
    for (list, id) in [
        (list("held"), "words-held-on"),
        (list("stopped"), "words-stopped"),
    ] {
        if !list.is_empty() {
            text.push_str(&i18n.ta(id, &[("list", (&list).into())]));
        }
    }
    text
}

/// Where to look on the machine after `trip`.
pub(crate) fn where_to_look(i18n: &I18n, bundle: &PlantBundle, trip: &Trip) -> Vec<String> {
    if i18n.lang() == Lang::En {
        return texts::where_to_look(bundle, trip);
    }
    texts::where_to_look_by_element(bundle, trip)
        .into_iter()
        .map(|(e, ids)| {
            if e.is_empty() {
                ids.join(", ")
            } else {
                format!("{} ({})", element(i18n, &e), ids.join(", "))
            }
        })
        .collect()
}

/// Why a reset is refused.
pub(crate) fn reset_refused(i18n: &I18n, e: &ResetRefused) -> String {
    if i18n.lang() == Lang::En {
        return e.to_string();
    }
    match e {
        ResetRefused::NotTripped => i18n.t("words-not-tripped"),
        ResetRefused::StillViolated {
            constraints,
            observers,
        } => {
            let mut t = i18n.ta(
                "words-still-violated",
                &[("constraints", (&constraints.join(", ")).into())],
            );
            if !observers.is_empty() {
                t.push_str(&i18n.ta(
                    "words-with-observers",
                    &[("observers", (&observers.join(" = 1, ")).into())],
                ));
            }
            t
        }
    }
}

/// An alarm's text in the language shown: a trip's from its record; the others as the
/// core wrote them.
pub(crate) fn alarm_message(i18n: &I18n, bundle: &PlantBundle, a: &Alarm) -> String {
    if i18n.lang() == Lang::En {
        return a.message.clone();
    }
    if a.code.is_empty() {
        return a.message.clone();
    }
    let id = format!("alarm-{}", a.code);
    coded(i18n, bundle, &id, &a.fields).unwrap_or_else(|| a.message.clone())
}

/// The message `id` of the language shown built from a record's `fields` (an alarm's,
/// a journal entry's), with what the plant folder translates added (a sensor's
/// description, a task's subject, a place, a fault); `None` when the language shown
/// has no such message of its own.
pub(crate) fn coded(
    i18n: &I18n,
    bundle: &PlantBundle,
    id: &str,
    fields: &std::collections::BTreeMap<String, String>,
) -> Option<String> {
    if id == "alarm-trip" && i18n.lang() != Lang::En {
        return Some(trip_from_fields(i18n, bundle, fields));
    }
    if id == "journal-manual-refused" && i18n.lang() != Lang::En {
        return refusal_from_fields(i18n, bundle, fields);
    }
    if id.is_empty() || !i18n.has_own(id) {
        return None;
    }
    let mut fields = fields.clone();
    if let Some(sensor) = fields.get("sensor").cloned() {
        let description = i18n
            .plant(&format!("signal-{sensor}"))
            .or_else(|| bundle.plant.signal(&sensor).map(|s| s.description.clone()))
            .unwrap_or_default();
        fields.insert("description".into(), description);
    }
    if let Some(place) = i18n.place(&fields) {
        fields.insert("place".into(), place);
    }
    if fields.contains_key("fault") {
        let what = fault_of(i18n, &i18n.signal_descriptions(&bundle.plant), &fields);
        fields.insert("what".into(), what);
    }
    if fields.contains_key("scenario_key") {
        let t = title(i18n, &fields, false);
        fields.insert("scenario".into(), t);
    }
    if let Some(task) = fields.get("task").cloned()
        && let Some(subject) = i18n.plant(&format!("task-{task}"))
    {
        fields.insert("subject".into(), subject);
    }
    let args: Vec<(&str, crate::i18n::Arg<'_>)> = fields
        .iter()
        .map(|(k, v)| (k.as_str(), crate::i18n::Arg::Str(v.as_str())))
        .collect();
    Some(i18n.ta(id, &args))
}

/// A journal entry's text in the language shown: its message when it has one in
/// this language, else the text recorded.
pub(crate) fn journal_text(
    i18n: &I18n,
    bundle: &PlantBundle,
    e: &crate::historian::JournalRow,
) -> String {
    if i18n.lang() == Lang::En {
        return e.text.clone();
    }
    coded(i18n, bundle, &e.code, &e.fields).unwrap_or_else(|| e.text.clone())
}

/// A journal entry's kind in the language shown.
pub(crate) fn journal_kind(i18n: &I18n, kind: &str) -> String {
    let id = format!("journal-kind-{kind}");
    if i18n.lang() != Lang::En && i18n.has_own(&id) {
        i18n.t(&id)
    } else {
        kind.to_string()
    }
}

/// A fault of the training library in the language shown: in English the name
/// `faults.ron` gives it; in another language built from its kind and the signal's
/// translated description.
pub(crate) fn fault(
    i18n: &I18n,
    descriptions: &std::collections::BTreeMap<String, String>,
    name: &str,
    spec: &FaultSpec,
) -> String {
    if i18n.lang() == Lang::En {
        return name.to_string();
    }
    fault_of(i18n, descriptions, &spec.fault.fields())
}

/// A fault told from its kind and signal in the language shown (the debrief's words,
/// whatever its name in the library).
pub(crate) fn fault_told(
    i18n: &I18n,
    descriptions: &std::collections::BTreeMap<String, String>,
    spec: &FaultSpec,
) -> String {
    fault_of(i18n, descriptions, &spec.fault.fields())
}

/// A fault told from its fields ([`FaultKind::fields`]) in the language shown.
fn fault_of(
    i18n: &I18n,
    descriptions: &std::collections::BTreeMap<String, String>,
    fields: &std::collections::BTreeMap<String, String>,
) -> String {
    let get = |k: &str| fields.get(k).map_or("", String::as_str);
    let signal = get("signal");
    let description = descriptions
        .get(signal)
        .map_or(String::new(), |d| format!(" ({d})"));
    i18n.ta(
        &format!("fault-{}", get("fault")),
        &[
            ("signal", signal.into()),
            ("description", (&description).into()),
            ("ms", get("ms").into()),
            ("percent", get("percent").into()),
            ("component", get("component").into()),
            ("position", get("position").into()),
        ],
    )
}

/// A run's title from its fields (see `Source::title_fields`), in the language shown
/// or in English (`english`, a record's text): the console's message or the plant
/// folder's text named by `scenario_key`, else the scenario file's own name
/// (`scenario`, English as the file gives it).
pub(crate) fn title(
    i18n: &I18n,
    fields: &std::collections::BTreeMap<String, String>,
    english: bool,
) -> String {
    let get = |k: &str| fields.get(k).map_or("", String::as_str);
    let key = get("scenario_key");
    if key.is_empty() {
        return get("scenario").to_string();
    }
    let args = [("id", get("id").into())];
    if i18n.has(key) {
        return if english {
            i18n.ta_en(key, &args)
        } else {
            i18n.ta(key, &args)
        };
    }
    if english || i18n.lang() == Lang::En {
        return get("scenario").to_string();
    }
    i18n.plant(key)
        .unwrap_or_else(|| get("scenario").to_string())
}
