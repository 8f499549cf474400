//! Timed plausibility of the sensors: the first stage of a cycle, between the inputs
//! read and the observers.
//!
//! A sensor with a rule in `plant.ron` (`plausible: Some((min_on_ms: 900, fall_when:
//! Some("A3* + A6*")))`) changes, as the plant's physics allows, only
//! - a fall no sooner than `min_on_ms` after the last accepted rise (a beam cannot fall
//!   sooner than the shortest item takes to cross it), a rise no sooner than
//!   `min_off_ms` after the last accepted fall;
//! - while its `rise_when` / `fall_when` condition holds (an item moves only while a
//!   drive under it runs; an axis leaves a position only once its motion is ordered).
//!
//! A condition may also have to hold for a time (`rise_when_for_ms`): a travel time
//! after the order (the turntable cannot reach C5 sooner than the rotation takes). Or
//! for a time in all since the last accepted edge, across its breaks
//! (`fall_when_total_ms`): a distance (a box that waited at a beam leaves it only once
//! the drives under it have run long enough to move it its length, however often they
//! stopped on the way). Before the first accepted edge the time is unknown and the
//! rule holds nothing. A
//! rise may be implausible for a time after an event (`rise_not_after`: a box reaches
//! the middle of the table no sooner than 100 ms after it left the belt's end sensor);
//! an upstream sensor stuck at 1 never gives the event, so the rule then holds nothing.
//!
//! A plausible edge may also wait for a confirmation (`rise_confirm_ms`,
//! `fall_confirm_ms`): it is taken once the reading has kept its new value that long
//! since the edge became plausible, and a shorter transient is filtered (a beam whose
//! fall releases a motion waits out a dropout).
//!
//! An edge outside these windows is **not taken**: the observers, the control program
//! and the constraints read the last plausible value (what the physics says is still
//! there: the item, the position), and the sensor is *suspect* (`sus_<sensor>` = 1,
//! an auxiliary the constraints may read) while the reading disagrees with it. Once
//! the reading agrees again, or becomes plausible (the window has passed, the motion
//! is ordered), the suspicion ends. The diagnosers read the raw values: they diagnose
//! the sensor.
//!
//! With `both_values: true` a rule asks more: the constraints are rewritten (by
//! [`suspect_constraints`]) so that a literal on the suspect sensor counts as possibly
//! true whichever its polarity, and the filter protects both the value held and the
//! value read. On the sorting station C3 says it (a held arrival at the end of the belt
//! must still stop the belt); for C4 to C8 it would leave the turntable without a safe
//! command in some contexts (CSs13 forbids rotating an "empty" table that CSs10 must
//! hold), so their rules keep the held value, as the paper's cooperation keeps one
//! estimate.
//!
//! Deterministic: time enters as the cycle's `now` only.

use crate::bits::Bits;
use crate::diag::Problem;
use crate::diag::codes;
use crate::expr::{Dnf, Expr, LeafKind, eval_dnf, parse_str, simplify};
use crate::frame::Frame;
use crate::plant::Plant;
use crate::symbols::{Space, Symbols};
use crate::time::Millis;
use serde::Serialize;

/// The auxiliary variable that says a sensor is suspect: `sus_C7`.
pub fn suspect_name(sensor: &str) -> String {
    format!("sus_{sensor}")
}

/// The sensor a suspect flag is about: `sus_C7` → `C7`.
pub fn suspect_sensor(flag: &str) -> Option<&str> {
    flag.strip_prefix("sus_")
}

/// The names of the suspect flags of the plant's rules, in input order.
pub fn suspect_names(plant: &Plant) -> Vec<String> {
    plant
        .inputs
        .iter()
        .filter(|s| s.plausible.is_some())
        .map(|s| suspect_name(&s.id))
        .collect()
}

#[derive(Clone, Debug)]
struct Rule {
    input: usize,
    aux: usize,
    min_on: u64,
    min_off: u64,
    rise: Option<Dnf>,
    fall: Option<Dnf>,
    rise_confirm: u64,
    fall_confirm: u64,
    rise_for: u64,
    fall_for: u64,
    rise_total: u64,
    fall_total: u64,
    hold_until_back: bool,
    /// `rise_not_after`: the event and the time after it.
    rise_after: Option<(Dnf, u64)>,
    /// `rise_expected_when` / `fall_expected_when`: the condition and its text.
    rise_expected: Option<(Dnf, String)>,
    fall_expected: Option<(Dnf, String)>,
}

#[derive(Clone, Copy, Debug, Default)]
struct State {
    /// The value the rest of the cycle reads.
    accepted: bool,
    /// When the last accepted edge happened (None: never, or before the first cycle).
    since: Option<u64>,
    /// The reading disagrees with `accepted` since then (an implausible edge held).
    suspect_since: Option<u64>,
    /// A plausible edge waits for its confirmation since then.
    pending_since: Option<u64>,
    /// The rise / fall condition has held without a break since then.
    rise_cond_since: Option<u64>,
    fall_cond_since: Option<u64>,
    /// An edge came too soon after the accepted one (`hold_until_back`): held until the
    /// reading agrees again.
    latched: bool,
    /// The last cycle where the `rise_not_after` event held.
    event_at: Option<u64>,
    /// How long the rise / fall condition has held in all since the last accepted edge
    /// (None: no edge accepted yet, the time is unknown).
    rise_total: Option<u64>,
    fall_total: Option<u64>,
}

/// A change of a sensor's suspicion, for the journal and the alarms.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Notice {
    /// When, ms.
    pub time_ms: u64,
    /// The sensor.
    pub sensor: String,
    /// True: an implausible edge was held; false: the reading agrees again or became
    /// plausible.
    pub suspect: bool,
    /// In words.
    pub text: String,
    /// The alarm code of the text, with its fields: `plausibility-filtered` (`edge`,
    /// `ms`, `confirm_ms`), `plausibility-suspect` (`edge`, `held`, `latched`),
    /// `plausibility-again` (`ms`).
    pub code: &'static str,
    /// See `code`.
    pub fields: std::collections::BTreeMap<String, String>,
}

/// One compiled rule, for the ST export (see [`Plausibility::export_rules`]).
#[derive(Clone, Copy, Debug)]
pub struct ExportRule<'a> {
    /// Input index.
    pub input: usize,
    /// Index of the `sus_` auxiliary.
    pub aux: usize,
    /// See [`crate::plant::PlausibleRule`].
    pub min_on_ms: u64,
    /// See [`crate::plant::PlausibleRule`].
    pub min_off_ms: u64,
    /// The rise condition, if any.
    pub rise_when: Option<&'a Dnf>,
    /// The fall condition, if any.
    pub fall_when: Option<&'a Dnf>,
    /// See [`crate::plant::PlausibleRule`].
    pub rise_confirm_ms: u64,
    /// See [`crate::plant::PlausibleRule`].
    pub fall_confirm_ms: u64,
    /// See [`crate::plant::PlausibleRule`].
    pub rise_when_for_ms: u64,
    /// See [`crate::plant::PlausibleRule`].
    pub fall_when_for_ms: u64,
    /// See [`crate::plant::PlausibleRule`].
    pub rise_when_total_ms: u64,
    /// See [`crate::plant::PlausibleRule`].
    pub fall_when_total_ms: u64,
    /// See [`crate::plant::PlausibleRule`].
    pub hold_until_back: bool,
    /// See [`crate::plant::PlausibleRule`]: the event and the time after it.
    pub rise_not_after: Option<(&'a Dnf, u64)>,
}

/// The compiled rules of a plant and their state.
#[derive(Clone, Debug, Default)]
pub struct Plausibility {
    rules: Vec<Rule>,
    states: Vec<State>,
    names: Vec<String>,
    /// The readings of the cycle, before the stage (the diagnosers read them).
    raw: Bits,
    raw_prev: Bits,
    notices: Vec<Notice>,
    decided: Vec<(bool, bool)>,
    /// The time of the last cycle (the `_total_ms` conditions add the time since).
    last_t: u64,
    /// Edges held so far.
    pub held_edges: u64,
}

impl Plausibility {
    /// Compiles the rules of `plant`; the `sus_` auxiliaries must be declared in
    /// `symbols`. Problems name the sensor and the condition's column.
    pub fn new(plant: &Plant, symbols: &Symbols) -> Result<Self, Vec<Problem>> {
        let mut rules = Vec::new();
        let mut names = Vec::new();
        let mut problems = Vec::new();
        for (input, s) in plant.inputs.iter().enumerate() {
            let Some(r) = &s.plausible else { continue };
            let mut cond = |what: &str, text: &Option<String>| -> Option<Dnf> {
                let text = text.as_ref()?;
                match parse_str(text).and_then(|e| e.to_dnf(symbols)) {
                    Ok(d) => Some(simplify(&d)),
                    Err(e) => {
                        problems.push(Problem::error(
                            codes::PLAUSIBILITY_INVALID.id,
                            format!(
                                "plausibility of `{}`: `{what}: \"{text}\"`, column {}: {}",
                                s.id, e.span.column, e.message
                            ),
                            None,
                        ));
                        None
                    }
                }
            };
            let rise = cond("rise_when", &r.rise_when);
            let fall = cond("fall_when", &r.fall_when);
            let rise_expected =
                cond("rise_expected_when", &r.rise_expected_when).zip(r.rise_expected_when.clone());
            let fall_expected =
                cond("fall_expected_when", &r.fall_expected_when).zip(r.fall_expected_when.clone());
            let rise_after = r
                .rise_not_after
                .as_ref()
                .and_then(|a| cond("rise_not_after", &Some(a.event.clone())).map(|d| (d, a.ms)));
            let Some((Space::Aux, aux)) = symbols.lookup(&suspect_name(&s.id)) else {
                problems.push(Problem::error(
                    codes::PLAUSIBILITY_INVALID.id,
                    format!(
                        "plausibility of `{}`: `{}` is not declared",
                        s.id,
                        suspect_name(&s.id)
                    ),
                    None,
                ));
                continue;
            };
            rules.push(Rule {
                input,
                aux: aux as usize,
                min_on: r.min_on_ms,
                min_off: r.min_off_ms,
                rise,
                fall,
                rise_confirm: r.rise_confirm_ms,
                fall_confirm: r.fall_confirm_ms,
                rise_for: r.rise_when_for_ms,
                fall_for: r.fall_when_for_ms,
                rise_total: r.rise_when_total_ms,
                fall_total: r.fall_when_total_ms,
                hold_until_back: r.hold_until_back,
                rise_after,
                rise_expected,
                fall_expected,
            });
            names.push(s.id.clone());
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        let states = vec![State::default(); rules.len()];
        Ok(Self {
            rules,
            states,
            names,
            raw: Bits::zeros(plant.inputs.len()),
            raw_prev: Bits::zeros(plant.inputs.len()),
            notices: Vec::new(),
            decided: Vec::new(),
            last_t: 0,
            held_edges: 0,
        })
    }

    /// The expectation (`rise_expected_when` / `fall_expected_when`, as written) that an
    /// edge of input `input` broke, read over `frame` (the cycle of the edge: its values
    /// at t and t-1); `None` when the edge was expected or the sensor has no
    /// expectation.
    pub fn unexpected_edge(&self, input: usize, rose: bool, frame: &Frame) -> Option<&str> {
        let r = self.rules.iter().find(|r| r.input == input)?;
        let (dnf, text) = if rose {
            r.rise_expected.as_ref()?
        } else {
            r.fall_expected.as_ref()?
        };
        (!eval_dnf(dnf, frame)).then_some(text.as_str())
    }

    /// True when the plant has no rule (the stage changes nothing).
    pub fn is_empty(&self) -> bool {
        self.rules.is_empty()
    }

    /// Starts from `frame`'s inputs at t as accepted values (a cold start or an attach):
    /// no edge before them is known.
    fn restart(&mut self, frame: &Frame) {
        for (r, st) in self.rules.iter().zip(&mut self.states) {
            *st = State {
                accepted: frame.now(Space::Input).get(r.input),
                since: None,
                suspect_since: None,
                pending_since: None,
                rise_cond_since: None,
                fall_cond_since: None,
                latched: false,
                event_at: None,
                rise_total: None,
                fall_total: None,
            };
        }
    }

    /// The stage: `frame` holds the readings at t (and every value at t-1); the
    /// accepted values replace them and the `sus_` flags are written.
    pub fn step(&mut self, now: Millis, frame: &mut Frame, first: bool) {
        if self.rules.is_empty() {
            return;
        }
        std::mem::swap(&mut self.raw, &mut self.raw_prev);
        self.raw.copy_from(frame.now(Space::Input));
        let t = now.0;
        if first {
            self.raw_prev.copy_from(frame.prev(Space::Input));
            self.restart(frame);
            self.last_t = t;
        }
        let dt = t.saturating_sub(self.last_t);
        self.last_t = t;
        // Every rule decides on the readings (its condition sees the raw values at t),
        // then the accepted values are written.
        let mut decided = std::mem::take(&mut self.decided);
        decided.clear();
        for (k, r) in self.rules.iter().enumerate() {
            let st = &mut self.states[k];
            let holds = |d: &Option<Dnf>| d.as_ref().is_none_or(|d| eval_dnf(d, frame));
            // A condition held for a time is tracked every cycle (Some: it has held that
            // long, so it holds now); an untimed one is read only for an edge (None).
            let timed = |d: &Option<Dnf>, ms: u64, since: &mut Option<u64>| {
                (ms > 0).then(|| {
                    if holds(d) {
                        t.saturating_sub(*since.get_or_insert(t)) >= ms
                    } else {
                        *since = None;
                        false
                    }
                })
            };
            let rise_ok = timed(&r.rise, r.rise_for, &mut st.rise_cond_since);
            let fall_ok = timed(&r.fall, r.fall_for, &mut st.fall_cond_since);
            // A condition held for a time in all: the time of every cycle where it held
            // (it reads the outputs applied over that cycle) is added.
            let rise_total_ok = total_ok(|| holds(&r.rise), r.rise_total, &mut st.rise_total, dt);
            let fall_total_ok = total_ok(|| holds(&r.fall), r.fall_total, &mut st.fall_total, dt);
            // The event is tracked every cycle; a rise is plausible only `ms` after it.
            let after_event = r.rise_after.as_ref().is_none_or(|(event, ms)| {
                if eval_dnf(event, frame) {
                    st.event_at = Some(t);
                }
                st.event_at.is_none_or(|at| t.saturating_sub(at) >= *ms)
            });
            let read = frame.now(Space::Input).get(r.input);
            let mut suspect = false;
            if read != st.accepted {
                let since = st.since.map_or(u64::MAX, |s| t.saturating_sub(s));
                let (window, cond, timed, total_ok) = if read {
                    (r.min_off, &r.rise, rise_ok, rise_total_ok)
                } else {
                    (r.min_on, &r.fall, fall_ok, fall_total_ok)
                };
                let in_window = since < window;
                let plausible = !st.latched
                    && !in_window
                    && total_ok
                    && (!read || after_event)
                    && timed.unwrap_or_else(|| holds(cond));
                let confirm = if read { r.rise_confirm } else { r.fall_confirm };
                if !plausible {
                    suspect = true;
                    st.pending_since = None;
                    st.latched |= r.hold_until_back && in_window;
                } else if t.saturating_sub(*st.pending_since.get_or_insert(t)) >= confirm {
                    st.accepted = read;
                    st.since = Some(t);
                    st.pending_since = None;
                    st.rise_total = Some(0);
                    st.fall_total = Some(0);
                }
            } else {
                st.latched = false;
                if let Some(from) = st.pending_since.take() {
                    filtered_notice(
                        &mut self.notices,
                        &mut self.held_edges,
                        &self.names[k],
                        t,
                        from,
                        r,
                        read,
                    );
                }
            }
            suspect_notices(
                &mut self.notices,
                &mut self.held_edges,
                &self.names[k],
                t,
                st,
                suspect,
                read,
            );
            decided.push((st.accepted, suspect));
        }
        for (r, &(accepted, suspect)) in self.rules.iter().zip(&decided) {
            frame.now_mut(Space::Input).set(r.input, accepted);
            frame.now_mut(Space::Aux).set(r.aux, suspect);
        }
        self.decided = decided;
    }

    /// The rules as the ST export generates them: (input, `sus_` auxiliary, min on,
    /// min off, rise condition, fall condition, rise confirmation, fall confirmation).
    pub fn export_rules(&self) -> Vec<ExportRule<'_>> {
        self.rules
            .iter()
            .map(|r| ExportRule {
                input: r.input,
                aux: r.aux,
                min_on_ms: r.min_on,
                min_off_ms: r.min_off,
                rise_when: r.rise.as_ref(),
                fall_when: r.fall.as_ref(),
                rise_confirm_ms: r.rise_confirm,
                fall_confirm_ms: r.fall_confirm,
                rise_when_for_ms: r.rise_for,
                fall_when_for_ms: r.fall_for,
                rise_when_total_ms: r.rise_total,
                fall_when_total_ms: r.fall_total,
                hold_until_back: r.hold_until_back,
                rise_not_after: r.rise_after.as_ref().map(|(d, ms)| (d, *ms)),
            })
            .collect()
    }

    /// The readings of the last cycle before the stage, at t and at t-1.
    pub fn raw(&self) -> (&Bits, &Bits) {
        (&self.raw, &self.raw_prev)
    }

    /// The notices since the last call.
    pub fn take_notices(&mut self) -> Vec<Notice> {
        std::mem::take(&mut self.notices)
    }
}

/// Notices kept until taken; a caller that never takes them (a benchmark, a replay)
/// keeps the first ones only.
const MAX_NOTICES: usize = 1024;

type Said = (
    String,
    &'static str,
    std::collections::BTreeMap<String, String>,
);

/// A condition held for a time in all: `dt` is added to `acc` when it holds; true once
/// `acc` reaches `ms` (or while the total is unknown, or with no such condition).
fn total_ok(holds: impl Fn() -> bool, ms: u64, acc: &mut Option<u64>, dt: u64) -> bool {
    ms == 0 || {
        if let Some(a) = acc.as_mut()
            && holds()
        {
            *a = a.saturating_add(dt);
        }
        acc.is_none_or(|a| a >= ms)
    }
}

/// Notices of a sensor becoming suspect or plausible again.
fn suspect_notices(
    notices: &mut Vec<Notice>,
    held_edges: &mut u64,
    name: &str,
    t: u64,
    st: &mut State,
    suspect: bool,
    read: bool,
) {
    match (suspect, st.suspect_since) {
        (true, None) => {
            st.suspect_since = Some(t);
            *held_edges += 1;
            let edge = if read { "rise" } else { "fall" };
            let held = u8::from(st.accepted);
            let until = if st.latched {
                format!(
                    " until it reads {held} again (so soon after the last edge, the last one was a transient)"
                )
            } else {
                String::new()
            };
            let text = format!(
                "{name} suspect: implausible {edge} (the plant's physics does not allow it now); {name} held at {held}{until}"
            );
            let fields = fields(&[
                ("edge", edge.into()),
                ("held", held.to_string()),
                ("latched", st.latched.to_string()),
            ]);
            notice(
                notices,
                t,
                name,
                true,
                (text, "plausibility-suspect", fields),
            );
        }
        (false, Some(from)) => {
            st.suspect_since = None;
            let ms = t.saturating_sub(from);
            let text = format!("{name} plausible again after {ms} ms");
            let fields = fields(&[("ms", ms.to_string())]);
            notice(
                notices,
                t,
                name,
                false,
                (text, "plausibility-again", fields),
            );
        }
        _ => {}
    }
}

/// Notice of a transient filtered: the reading came back before the confirmation.
fn filtered_notice(
    notices: &mut Vec<Notice>,
    held_edges: &mut u64,
    name: &str,
    t: u64,
    from: u64,
    r: &Rule,
    read: bool,
) {
    // The reading came back before the confirmation: a transient filtered.
    *held_edges += 1;
    let edge = if read { "fall" } else { "rise" };
    let confirm = if read { r.fall_confirm } else { r.rise_confirm };
    let ms = t.saturating_sub(from);
    let text = format!(
        "{name}: a {edge} of {ms} ms filtered (shorter than its {confirm} ms confirmation)"
    );
    let fields = fields(&[
        ("edge", edge.into()),
        ("ms", ms.to_string()),
        ("confirm_ms", confirm.to_string()),
    ]);
    notice(
        notices,
        t,
        name,
        false,
        (text, "plausibility-filtered", fields),
    );
}

fn notice(notices: &mut Vec<Notice>, time_ms: u64, sensor: &str, suspect: bool, said: Said) {
    let (text, code, fields) = said;
    if notices.len() < MAX_NOTICES {
        notices.push(Notice {
            time_ms,
            sensor: sensor.to_string(),
            suspect,
            text,
            code,
            fields,
        });
    }
}

fn fields(pairs: &[(&str, String)]) -> std::collections::BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| ((*k).to_string(), v.clone()))
        .collect()
}

fn leaf(name: &str, kind: LeafKind, span: crate::expr::Span) -> Expr {
    Expr::Leaf {
        name: name.to_string(),
        kind,
        span,
    }
}

/// `e` with every reading of a ruled sensor made possibly true while it is suspect:
/// under an even number of negations `x` becomes `x + sus_x`, under an odd number
/// `x . /sus_x` (so that `/x` reads `/x + sus_x`); `x*` likewise with `sus_x*`, and the
/// edges are expanded first (`RE(x)` = `x . /x*`).
pub fn suspect_expr(e: &Expr, sensors: &[String]) -> Expr {
    fn go(e: &Expr, sensors: &[String], positive: bool) -> Expr {
        match e {
            Expr::Leaf { name, kind, span } if sensors.contains(name) => {
                let sus = suspect_name(name);
                let now = |k: LeafKind| leaf(name, k, *span);
                let wrap = |x: Expr, s: Expr, pos: bool| {
                    if pos {
                        Expr::Or(vec![x, s])
                    } else {
                        Expr::And(vec![x, Expr::Not(Box::new(s))])
                    }
                };
                match kind {
                    LeafKind::Now => wrap(
                        now(LeafKind::Now),
                        leaf(&sus, LeafKind::Now, *span),
                        positive,
                    ),
                    LeafKind::Prev => wrap(
                        now(LeafKind::Prev),
                        leaf(&sus, LeafKind::Prev, *span),
                        positive,
                    ),
                    LeafKind::Rise => go(
                        &Expr::And(vec![
                            now(LeafKind::Now),
                            Expr::Not(Box::new(now(LeafKind::Prev))),
                        ]),
                        sensors,
                        positive,
                    ),
                    LeafKind::Fall => go(
                        &Expr::And(vec![
                            Expr::Not(Box::new(now(LeafKind::Now))),
                            now(LeafKind::Prev),
                        ]),
                        sensors,
                        positive,
                    ),
                    LeafKind::Estimate => e.clone(),
                }
            }
            Expr::Not(x) => Expr::Not(Box::new(go(x, sensors, !positive))),
            Expr::And(v) => Expr::And(v.iter().map(|x| go(x, sensors, positive)).collect()),
            Expr::Or(v) => Expr::Or(v.iter().map(|x| go(x, sensors, positive)).collect()),
            _ => e.clone(),
        }
    }
    go(e, sensors, true)
}

/// Rewrites every constraint of `set` with [`suspect_expr`] for the sensors of `plant`
/// whose rule says `both_values` (expression and sum of products; ids, text and lines kept).
pub fn suspect_constraints(
    set: &mut crate::constraints::ConstraintSet,
    plant: &Plant,
    symbols: &Symbols,
) -> Vec<Problem> {
    let sensors: Vec<String> = plant
        .inputs
        .iter()
        .filter(|s| s.plausible.as_ref().is_some_and(|r| r.both_values))
        .map(|s| s.id.clone())
        .collect();
    if sensors.is_empty() {
        return Vec::new();
    }
    let mut problems = Vec::new();
    for c in &mut set.constraints {
        let e = suspect_expr(&c.expr, &sensors);
        match e.to_dnf(symbols) {
            Ok(d) => {
                c.expr = e;
                c.dnf = simplify(&d);
            }
            Err(err) => problems.push(Problem::error(
                codes::PLAUSIBILITY_INVALID.id,
                format!("{}: with the suspect sensors, {}", c.id, err.message),
                Some(c.location.clone()),
            )),
        }
    }
    problems
}

#[cfg(test)]
mod tests;
