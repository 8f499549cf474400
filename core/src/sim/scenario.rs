//! Checks of a scenario file beyond its syntax: the run's duration, the PLC cycle, the
//! projection horizon, the arrival periods, the fault lengths and the times of the
//! actions, faults and listed arrivals must be within sane bounds, each problem at the
//! value as written in the file.
//!
//! Codes: `V0401` PLC cycle, `V0403` duration of the run or projection horizon, `V0404`
//! a time not before the end of the run (it would never happen), `V0405` arrival
//! period or jitter, `V0406` length of a fault or of a spurious pulse.

use super::Scenario;
use crate::diag::codes;
use crate::diag::{Location, Problem, RonField, ron_field, ron_fields};
use crate::emulator::{ArrivalPlan, FaultKind, Trigger};
use std::path::Path;

/// Longest run a scenario may ask for, ms (a week: 60 million cycles of 10 ms).
pub const MAX_RUN_MS: u64 = 7 * 24 * 3_600_000;
/// Longest PLC cycle, ms.
pub const MAX_CYCLE_MS: u64 = 1_000;
/// Longest projection horizon of the explanations, ms (it is simulated at each trip).
pub const MAX_PROJECTION_MS: u64 = 3_600_000;

/// The problems of a parsed scenario; `text` is the file it was parsed from.
pub(crate) fn check(s: &Scenario, text: &str, path: &Path) -> Vec<Problem> {
    let fields = ron_fields(text);
    let at = |f: Option<&RonField>| field_location(path, f);
    let top = |name: &str| at(ron_field(&fields, &[], name, 0));
    let mut out = Vec::new();
    if !(1..=MAX_CYCLE_MS).contains(&s.cycle_ms) {
        out.push(Problem::error(
            codes::SCENARIO_CYCLE.id,
            format!(
                "cycle_ms is {} ms: a PLC cycle must be from 1 to {MAX_CYCLE_MS} ms",
                s.cycle_ms
            ),
            top("cycle_ms"),
        ));
    }
    if !(1..=MAX_RUN_MS).contains(&s.duration_ms) {
        out.push(Problem::error(
            codes::SCENARIO_DURATION.id,
            format!(
                "duration_ms is {} ms: a run lasts from 1 ms to {MAX_RUN_MS} ms (7 days)",
                s.duration_ms
            ),
            top("duration_ms"),
        ));
    }
    if s.projection_ms > MAX_PROJECTION_MS {
        out.push(Problem::error(
            codes::SCENARIO_DURATION.id,
            format!(
                "projection_ms is {} ms: the projection horizon is at most {MAX_PROJECTION_MS} ms (1 h)",
                s.projection_ms
            ),
            top("projection_ms"),
        ));
    }
    let end = s.duration_ms;
    let after_end =
        |what: String, t: u64, location: Option<Location>| not_before_end(end, what, t, location);
    for (k, a) in s.actions.iter().enumerate() {
        if a.at_ms >= end {
            out.push(after_end(
                format!("action {:?}", a.action),
                a.at_ms,
                at(ron_field(&fields, &["actions"], "at_ms", k)),
            ));
        }
    }
    match &s.arrivals {
        Some(ArrivalPlan::Periodic {
            period_ms,
            jitter_ms,
            ..
        }) => {
            if !(1..=MAX_RUN_MS).contains(period_ms) {
                out.push(Problem::error(
                    codes::SCENARIO_ARRIVALS.id,
                    format!(
                        "period_ms is {period_ms} ms: an arrival period is from 1 ms to {MAX_RUN_MS} ms"
                    ),
                    at(ron_field(&fields, &["arrivals"], "period_ms", 0)),
                ));
            }
            if *jitter_ms > MAX_RUN_MS {
                out.push(Problem::error(
                    codes::SCENARIO_ARRIVALS.id,
                    format!("jitter_ms is {jitter_ms} ms: at most {MAX_RUN_MS} ms"),
                    at(ron_field(&fields, &["arrivals"], "jitter_ms", 0)),
                ));
            }
        }
        Some(ArrivalPlan::List(list)) => {
            for &(t, _) in list.iter().filter(|(t, _)| *t >= end) {
                out.push(after_end("box arrival".into(), t, top("arrivals")));
            }
        }
        Some(ArrivalPlan::Off) | None => {}
    }
    check_faults(s, &fields, path, &mut out);
    out
}

#[cfg(test)]
mod tests;

/// Where a field's value is written (the file's start when the field is absent).
fn field_location(path: &Path, f: Option<&RonField>) -> Option<Location> {
    Some(f.map_or_else(|| Location::new(path, 1, 1), |f| f.location(path)))
}

/// The problem of `what` at `t` ms, not before the end of the run at `end` ms.
fn not_before_end(end: u64, what: String, t: u64, location: Option<Location>) -> Problem {
    Problem::error(
        codes::SCENARIO_AFTER_END.id,
        format!(
            "{what} at {t} ms is not before the end of the run (duration_ms {end}): it would never happen"
        ),
        location,
    )
}

/// The problems of the scenario's faults: trigger time, duration and pulse length.
fn check_faults(s: &Scenario, fields: &[RonField], path: &Path, out: &mut Vec<Problem>) {
    let at = |f: Option<&RonField>| field_location(path, f);
    let end = s.duration_ms;
    let after_end =
        |what: String, t: u64, location: Option<Location>| not_before_end(end, what, t, location);
    for (k, f) in s.faults.iter().enumerate() {
        // The fields of fault `k` share the container of its (required) trigger.
        let trigger = ron_field(fields, &["faults"], "trigger", k);
        let own = |name: &str| {
            trigger.and_then(|t| {
                fields
                    .iter()
                    .find(|x| x.container == t.container && x.name == name && x.is_at(&["faults"]))
            })
        };
        let pulse = own("fault").and_then(|kind| {
            fields.iter().find(|x| {
                x.name == "pulse_ms"
                    && x.is_at(&["faults", "fault"])
                    && kind.value.contains(&x.value.start)
            })
        });
        if let Trigger::At(t) = f.trigger
            && t >= end
        {
            out.push(after_end(format!("fault {:?}", f.fault), t, at(trigger)));
        }
        if let Some(d) = f.duration_ms
            && !(1..=MAX_RUN_MS).contains(&d)
        {
            out.push(Problem::error(
                codes::SCENARIO_FAULT_DURATION.id,
                format!(
                    "fault {:?} lasts {d} ms: a fault lasts from 1 ms to {MAX_RUN_MS} ms (leave duration_ms out for ever)",
                    f.fault
                ),
                at(own("duration_ms")),
            ));
        }
        if let FaultKind::SpuriousRise { pulse_ms, .. } | FaultKind::SpuriousFall { pulse_ms, .. } =
            &f.fault
            && !(1..=MAX_RUN_MS).contains(pulse_ms)
        {
            out.push(Problem::error(
                codes::SCENARIO_FAULT_DURATION.id,
                format!(
                    "pulse_ms is {pulse_ms} ms: a spurious pulse lasts from 1 ms to {MAX_RUN_MS} ms"
                ),
                at(pulse),
            ));
        }
    }
}
