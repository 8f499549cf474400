//! Level 4 beyond the paper: when the control program and its state are known (emulator
//! mode, or a program loaded beside a live PLC), the hypothesis names the chart
//! elements that set or reset the offending actuator in the cycles before the trip.
//!
//! For every actuator of a fired constraint whose commanded value is the forbidden one,
//! from the runtime before the tripping scan and after it (its evolution ring and its
//! drivers):
//! - `X407`: a transition fired and deactivated the step whose action held the actuator
//!   at the required value (in the stopping cycle, or the last such evolution before);
//! - `X408`: a transition fired and activated a step whose action drives the actuator to
//!   the forbidden value;
//! - `X409`: a step action whose qualifier makes the difference (a pulse or time-limited
//!   action that ended while its step is still active, a delayed action that began, a
//!   stored `S` value not reset, an `R` action);
//! - `X410`: an output equation commands the forbidden value (true, or became false);
//! - `X411`: nothing in the program commands the required value: the steps and the
//!   equation that could command it are listed;
//! - `X412`: a step that has been active for a while drives the forbidden value and the
//!   transitions leaving it have not fired: their receptivity is suspect;
//! - `X413` (combined constraints): a step activated in the stopping cycle drives one
//!   actuator of the constraint ON while another, required ON with it, is commanded by
//!   nothing: the new step's actions or what commands the other actuator miss it;
//! - `X417`: a step's action drives the forbidden value ON and the step's place in its
//!   chart puts it in the situation the constraint forbids (the fired term's sensor
//!   literals): the transition that activated it in the stopping cycle waited for a
//!   receptivity that requires that situation, or the step, just entered, is left only
//!   by transitions that wait for its end, or it is an initial step that drove the
//!   actuator from the first scan. The action is then in the wrong step (written one
//!   step early, in the other branch, …): it comes before the X408 (or X409) of the same
//!   action, which stays as the alternative.
//! - `X420`: after each of them, for a program imported from PLCopen XML, where the
//!   steps, transitions and equations it suspects are in that file (POU, kind, line,
//!   column), so that the fix is made in the PLC's own tool.
//!
//! Every item has the fields `output`, `chart`, and as they apply `transition`,
//! `receptivity`, `step`, `activated`, `qualifier`, `equation`, `expression`, `steps`,
//! `transitions`, `signals` (names the receptivity or equation reads, comma-separated)
//! and `ms_before` (0 = the stopping cycle); X417 has `constraint`, `condition`,
//! `evidence`, `activated_by`, `exits` instead of `transition`. Items are ordered:
//! elements that changed in the stopping cycle first, then by kind (`X413`, `X417`,
//! `X407`-`X409`, `X412`, `X410`, `X411`).

use super::{Explanation, Highlight, Item, Mark};
use crate::control::SourcePlace;
use crate::control::{Driver, ProgramRuntime, Qualifier};
use crate::diag::codes::{self, Code};
use crate::engine::{FiredConstraint, Trip};
use crate::expr::Dnf;
use crate::symbols::{Literal, Space, Var};

/// One program suspect with its ordering key.
struct Suspect {
    item: Item,
    highlights: Vec<Highlight>,
    /// (0 when it happened in the stopping cycle, kind rank).
    rank: (u8, u8),
}

/// Where a fired constraint forbids its actuators: the literals of its fired term on the
/// sensors the program reads (at t, the actuators and observers left out).
struct Situation {
    /// Constraint id.
    constraint: String,
    /// The sensor literals, in the program's variables.
    literals: Vec<Literal>,
    /// The same in the file notation (`C4 . /C6`).
    notation: String,
}

impl Situation {
    fn of(c: &FiredConstraint, v: &View<'_>) -> Self {
        let mut literals = Vec::new();
        let mut notation = Vec::new();
        for l in c
            .literals
            .iter()
            .filter(|l| l.space == Space::Input && !l.previous)
        {
            if let Some((Space::Input, index)) = v.p().symbols.lookup(&l.name) {
                literals.push(Literal {
                    var: Var {
                        space: Space::Input,
                        index,
                        prev: false,
                    },
                    positive: l.value,
                });
                notation.push(l.literal.clone());
            }
        }
        Self {
            constraint: c.id.clone(),
            literals,
            notation: notation.join(" . "),
        }
    }

    /// True when the product holds every literal of the situation: it is true only in
    /// the situation.
    fn required_by(&self, product: &[Literal]) -> bool {
        !self.literals.is_empty() && self.literals.iter().all(|l| product.contains(l))
    }

    /// True when the product holds the negation of a literal of the situation: it is
    /// false as long as the situation lasts.
    fn excluded_by(&self, product: &[Literal]) -> bool {
        self.literals.iter().any(|l| {
            product.contains(&Literal {
                var: l.var,
                positive: !l.positive,
            })
        })
    }
}

/// Why the action of a step, rather than a transition, is held to be in the wrong place:
/// the step's own place in its chart puts it in the situation where its action is
/// forbidden.
#[derive(Default)]
struct Misplaced {
    /// The transition that activated the step in the stopping cycle, if it did.
    activated_by: Option<String>,
    /// Its receptivity (the product that fired) requires the situation, and it waited
    /// for it: the step is entered there.
    entry: bool,
    /// The transitions leaving the step, which all wait for the end of the situation:
    /// the step lasts through it.
    exits: Vec<String>,
    /// The step is initial and drove the actuator from the first scan: no transition
    /// brought it there.
    initial: bool,
}

/// The program view shared by the helpers.
struct View<'a> {
    before: &'a ProgramRuntime,
    after: &'a ProgramRuntime,
    trip_ms: u64,
}

fn join(v: &[String]) -> String {
    v.join(",")
}

impl View<'_> {
    fn p(&self) -> &crate::control::CompiledProgram {
        self.after.program()
    }

    fn chart_of_step(&self, step: &str) -> String {
        let p = self.p();
        p.steps
            .iter()
            .find(|s| s.id == step)
            .and_then(|s| p.program.charts.get(s.chart))
            .map(|c| c.name.clone())
            .unwrap_or_default()
    }

    fn receptivity(&self, transition: &str) -> String {
        self.p()
            .program
            .transitions()
            .find(|(_, t)| t.id == transition)
            .map(|(_, t)| t.condition.clone())
            .unwrap_or_default()
    }

    fn chart_of_transition(&self, transition: &str) -> String {
        self.p()
            .program
            .transitions()
            .find(|(_, t)| t.id == transition)
            .map(|(c, _)| c.to_string())
            .unwrap_or_default()
    }

    /// Distinct names a sum of products reads, in order of appearance.
    fn dnf_names(&self, dnf: &Dnf) -> Vec<String> {
        let sym = &self.p().symbols;
        let mut out: Vec<String> = Vec::new();
        for l in dnf.iter().flatten() {
            let n = sym.name(l.var.space, l.var.index).to_string();
            if !out.contains(&n) {
                out.push(n);
            }
        }
        out
    }

    fn transition_signals(&self, transition: &str) -> Vec<String> {
        self.p()
            .transitions
            .iter()
            .find(|t| t.id == transition)
            .map(|t| self.dnf_names(&t.condition))
            .unwrap_or_default()
    }

    /// The plant signals among `names` (steps, memories and panel inputs left out):
    /// what can be marked on the synoptic.
    fn plant(&self, names: &[String]) -> Vec<String> {
        names
            .iter()
            .filter(|n| {
                matches!(
                    self.p().symbols.lookup(n),
                    Some((Space::Input | Space::Output, _))
                )
            })
            .cloned()
            .collect()
    }

    fn steps_of(&self, idx: &[u16]) -> Vec<String> {
        let p = self.p();
        idx.iter()
            .filter_map(|&s| p.steps.get(s as usize))
            .map(|s| s.id.clone())
            .collect()
    }

    /// Output slot of an actuator.
    fn slot(&self, output: &str) -> Option<usize> {
        match self.p().symbols.lookup(output) {
            Some((Space::Output, i)) => Some(i as usize),
            _ => None,
        }
    }

    /// Steps carrying a non-reset action on the slot, with the qualifier.
    fn commanding_steps(&self, slot: usize) -> Vec<(String, Qualifier)> {
        let p = self.p();
        p.actions
            .iter()
            .filter(|a| a.slot == slot && a.qualifier != Qualifier::R)
            .filter_map(|a| {
                p.steps
                    .get(a.step as usize)
                    .map(|s| (s.id.clone(), a.qualifier))
            })
            .collect()
    }

    /// The equation of the slot: (index, text).
    fn equation(&self, slot: usize) -> Option<(usize, String)> {
        let p = self.p();
        let k = p.equations.iter().position(|e| e.slot == slot)?;
        Some((
            k,
            p.program
                .equations
                .get(p.equations[k].index)
                .map(|e| e.1.clone())
                .unwrap_or_default(),
        ))
    }

    /// The last evolution (newest first) in which a transition with `step` in its
    /// downstream (`to`) or upstream (`!to`) steps fired: (transition id, time).
    fn last_firing(&self, step: &str, to: bool) -> Option<(String, u64)> {
        let p = self.p();
        let si = p.steps.iter().position(|s| s.id == step)?;
        let si = u16::try_from(si).ok()?;
        for ev in self.after.evolutions().iter().rev() {
            for t in &ev.fired {
                let Some(info) = p.transitions.iter().find(|x| &x.id == t) else {
                    continue;
                };
                let ends = if to { &info.to } else { &info.from };
                if ends.contains(&si) {
                    return Some((t.clone(), ev.time.0));
                }
            }
        }
        None
    }

    fn ms_before(&self, time: u64) -> u64 {
        self.trip_ms.saturating_sub(time)
    }

    fn when(&self, time: u64) -> String {
        match self.ms_before(time) {
            0 => "in the stopping cycle".to_string(),
            ms => format!("{ms} ms before the stop"),
        }
    }

    /// Transitions leaving `step` (id, receptivity).
    fn exits(&self, step: &str) -> Vec<String> {
        let p = self.p();
        let Some(si) = p.steps.iter().position(|s| s.id == step) else {
            return Vec::new();
        };
        p.transitions
            .iter()
            .filter(|t| t.from.iter().any(|&f| f as usize == si))
            .map(|t| t.id.clone())
            .collect()
    }
}

fn suspect(
    code: Code,
    rank: (u8, u8),
    text: String,
    fields: &[(&str, String)],
    plant: &[String],
) -> Suspect {
    Suspect {
        item: Item::new(code, text, fields),
        highlights: plant
            .iter()
            .map(|s| Highlight {
                element: s.clone(),
                mark: Mark::Suspect,
            })
            .collect(),
        rank,
    }
}

fn on_off(v: bool) -> &'static str {
    if v { "ON" } else { "OFF" }
}

/// The program suspects for `trip`, most specific first, from the runtime before the
/// tripping scan (`before`) and after it (`after`).
pub fn program_suspects(
    trip: &Trip,
    before: &ProgramRuntime,
    after: &ProgramRuntime,
) -> Vec<(Item, Vec<Highlight>)> {
    let view = View {
        before,
        after,
        trip_ms: trip.time_ms,
    };
    let mut out: Vec<Suspect> = Vec::new();
    let mut seen: Vec<String> = Vec::new();
    for c in &trip.constraints {
        let first = out.len();
        let situation = Situation::of(c, &view);
        for l in c
            .literals
            .iter()
            .filter(|l| l.space == Space::Output && !l.previous)
        {
            if seen.contains(&l.name) {
                continue;
            }
            seen.push(l.name.clone());
            let Some(slot) = view.slot(&l.name) else {
                continue;
            };
            let was = before.value(&l.name).unwrap_or(false);
            if l.value {
                forbidden_on(&view, &l.name, slot, (was, &situation), &mut out);
            } else {
                forbidden_off(&view, &l.name, slot, was, &mut out);
            }
        }
        if let Some(s) = coordination(&view, &c.id, &out[first..]) {
            out.insert(first, s);
        }
    }
    // Stable: suspects of the same rank keep the order of the constraint's literals.
    out.sort_by_key(|s| s.rank);
    out.into_iter().map(|s| (s.item, s.highlights)).collect()
}

/// Inserts the program suspects at the head of the hypothesis level of `ex` (after a
/// suspect sensor, X414, before the paper's (a)/(b)/(d) suspects): the first suspect is
/// then the most specific one. A stop by the diagnosers alone has none.
pub fn add_program_hypothesis(
    ex: &mut Explanation,
    trip: &Trip,
    before: &ProgramRuntime,
    after: &ProgramRuntime,
) {
    // A stop by the diagnosers alone is no program error: no program suspects.
    if trip
        .constraints
        .iter()
        .all(|c| crate::pop::coop::is_diagnoser_stop(&c.id))
    {
        return;
    }
    let suspects = program_suspects(trip, before, after);
    let level = &mut ex.hypothesis;
    let mut items = Vec::with_capacity(suspects.len() + level.items.len());
    // A suspect sensor (X414) and an unexpected edge (X418) stay first: the program
    // read what the stage held, or what the plant could not have shown.
    let sensors = level
        .items
        .iter()
        .take_while(|i| {
            i.code == codes::X_SUSPECT_SENSOR.id || i.code == codes::X_UNEXPECTED_EDGE.id
        })
        .count();
    items.extend(level.items.drain(..sensors));
    let places = &after.program().program.places;
    for (item, highlights) in suspects {
        highlights.into_iter().for_each(|h| level.highlight(h));
        let placed = place_items(&item, places);
        items.push(item);
        items.extend(placed);
    }
    items.append(&mut level.items);
    super::merge_identical(&mut items);
    level.items = items;
}

/// The fields of a suspect that name the elements it suspects (not those it cites as
/// context, such as the steps an equation reads).
const SUSPECTED: [&str; 5] = ["step", "transition", "activated_by", "exits", "equation"];

/// X420: where the elements `item` suspects are in the PLCopen file the program was
/// imported from (none for a program written in Vigie's own format).
fn place_items(
    item: &Item,
    places: &std::collections::BTreeMap<String, Vec<SourcePlace>>,
) -> Vec<Item> {
    let mut out: Vec<Item> = Vec::new();
    for key in SUSPECTED {
        let Some(names) = item.fields.get(key) else {
            continue;
        };
        for name in names.split(',').map(str::trim) {
            for p in places.get(name).into_iter().flatten() {
                let what = match p.kind.as_str() {
                    "step" => format!("Step {name} is"),
                    "transition" => format!("Transition {name} is"),
                    lang => format!("{name} is written ({lang})"),
                };
                let placed = Item::new(
                    codes::X_SOURCE_PLACE,
                    format!(
                        "{what} in POU {} of {}, line {}, column {}.",
                        p.pou, p.file, p.line, p.column
                    ),
                    &[
                        ("element", name.to_string()),
                        ("file", p.file.clone()),
                        ("pou", p.pou.clone()),
                        ("kind", p.kind.clone()),
                        ("line", p.line.to_string()),
                        ("column", p.column.to_string()),
                    ],
                );
                if !out.contains(&placed) {
                    out.push(placed);
                }
            }
        }
    }
    out
}

/// The actuator is commanded ON and must not be (`was`: commanded ON in the cycle
/// before; `situation`: where the constraint forbids it).
fn forbidden_on(
    v: &View<'_>,
    output: &str,
    slot: usize,
    (was, situation): (bool, &Situation),
    out: &mut Vec<Suspect>,
) {
    let rose = !was;
    let drivers = v.after.drivers(output).unwrap_or_default();
    for d in &drivers {
        match d {
            Driver::Action { step, qualifier } => {
                action_forbidden_on(v, output, (step, *qualifier), rose, situation, out);
            }
            Driver::Stored { set_by } => {
                let left: Vec<String> = set_by
                    .iter()
                    .filter(|s| !v.after.is_active(s))
                    .cloned()
                    .collect();
                let chart = set_by
                    .first()
                    .map(|s| v.chart_of_step(s))
                    .unwrap_or_default();
                let recent = rose
                    || set_by
                        .iter()
                        .any(|s| v.before.is_active(s) && !v.after.is_active(s));
                out.push(suspect(
                    codes::X_QUALIFIER,
                    (u8::from(!recent), 0),
                    format!(
                        "{output} is stored ON by the S action of step {} and no R action reset it{}: the qualifier S of this action is suspect.",
                        set_by.join(", "),
                        if left.is_empty() { String::new() } else { format!(" after {} was left", left.join(", ")) }
                    ),
                    &[
                        ("output", output.to_string()),
                        ("chart", chart),
                        ("step", join(set_by)),
                        ("qualifier", "S".into()),
                        ("ms_before", "0".into()),
                    ],
                    &[],
                ));
            }
            Driver::Equation { expression } => {
                equation_suspect(v, output, slot, true, expression, rose, out);
            }
        }
    }
}

/// The suspect for an action of a step that drives the forbidden ON: the transition that
/// activated the step (X408), the action's qualifier (X409) or the step's exits (X412);
/// before them, the action itself (X417) when the step's place in its chart puts it in
/// the situation where the constraint forbids the actuator ([`misplacement`]).
fn action_forbidden_on(
    v: &View<'_>,
    output: &str,
    (step, qualifier): (&str, Qualifier),
    rose: bool,
    situation: &Situation,
    out: &mut Vec<Suspect>,
) {
    let chart = v.chart_of_step(step);
    let newly = !v.before.is_active(step);
    let activation = v.last_firing(step, true);
    let action_started = rose && !newly;
    let entered_now = newly
        || (rose
            && activation
                .as_ref()
                .is_some_and(|(_, t)| v.ms_before(*t) == 0));
    let entry = activation.as_ref().filter(|_| entered_now);
    if let Some(m) = misplacement(v, step, qualifier, situation, (entry, action_started)) {
        let rank = u8::from(entry.is_some_and(|(_, t)| v.ms_before(*t) > 0));
        let since = activation.as_ref().map_or(0, |(_, t)| v.ms_before(*t));
        out.push(misplaced_suspect(
            v,
            (output, step, qualifier),
            situation,
            &m,
            (rank, since),
        ));
    }
    if entered_now {
        // X408: the transition that activated the step.
        if let Some((t, time)) = activation {
            let rec = v.receptivity(&t);
            let signals = v.transition_signals(&t);
            out.push(suspect(
                codes::X_TRANSITION_ACTIVATED_STEP,
                (u8::from(v.ms_before(time) > 0), 0),
                format!(
                    "Transition {t} (receptivity `{rec}`) fired {} and activated step {step}, whose action {qualifier} {output} drives {output} ON: the receptivity of {t} is suspect (it reads {}).",
                    v.when(time),
                    signals.join(", ")
                ),
                &[
                    ("output", output.to_string()),
                    ("chart", chart),
                    ("transition", t.clone()),
                    ("receptivity", rec),
                    ("signals", join(&signals)),
                    ("step", step.to_string()),
                    ("qualifier", qualifier.to_string()),
                    ("ms_before", v.ms_before(time).to_string()),
                ],
                &v.plant(&signals),
            ));
            return;
        }
    }
    if action_started {
        // X409: a delayed action that began while the step was active.
        out.push(suspect(
            codes::X_QUALIFIER,
            (0, 0),
            format!(
                "Step {step} was already active; its action {qualifier} {output} began to drive {output} ON in the stopping cycle: the qualifier of this action is suspect."
            ),
            &[
                ("output", output.to_string()),
                ("chart", chart),
                ("step", step.to_string()),
                ("qualifier", qualifier.to_string()),
                ("ms_before", "0".into()),
            ],
            &[],
        ));
        return;
    }
    // X412: the step stays active for too long.
    out.push(step_not_left(
        v,
        output,
        (step, qualifier),
        chart,
        activation,
    ));
}

/// X412: `step`, active since `activation`, drives `output` ON and the transitions
/// leaving it did not fire.
fn step_not_left(
    v: &View<'_>,
    output: &str,
    (step, qualifier): (&str, Qualifier),
    chart: String,
    activation: Option<(String, u64)>,
) -> Suspect {
    let exits = v.exits(step);
    let recs: Vec<String> = exits
        .iter()
        .map(|t| format!("{t} `{}`", v.receptivity(t)))
        .collect();
    let mut signals: Vec<String> = Vec::new();
    for t in &exits {
        for s in v.transition_signals(t) {
            if !signals.contains(&s) {
                signals.push(s);
            }
        }
    }
    let since = activation
        .as_ref()
        .map(|(t, time)| format!(" since {t} fired {}", v.when(*time)))
        .unwrap_or_default();
    suspect(
        codes::X_STEP_NOT_LEFT,
        (1, 1),
        format!(
            "Step {step} has been active{since} and its action {qualifier} {output} drives {output} ON; the transition(s) leaving it, {}, did not fire: their receptivity is suspect.",
            recs.join(", ")
        ),
        &[
            ("output", output.to_string()),
            ("chart", chart),
            ("step", step.to_string()),
            ("qualifier", qualifier.to_string()),
            ("transition", join(&exits)),
            (
                "receptivity",
                exits
                    .iter()
                    .map(|t| v.receptivity(t))
                    .collect::<Vec<_>>()
                    .join(" | "),
            ),
            ("signals", join(&signals)),
            (
                "ms_before",
                activation
                    .map(|(_, t)| v.ms_before(t))
                    .unwrap_or(0)
                    .to_string(),
            ),
        ],
        &v.plant(&signals),
    )
}

/// Whether the action of `step` on the actuator is in the wrong step rather than its
/// step entered too early (X408) or at the first scan for a qualifier's reason (X409),
/// from the program and its recorded evolution. The evidence never comes from the
/// element the alternative suspect blames:
/// - entry: the transition that activated the step in the stopping cycle (`entry`)
///   waited in its upstream steps (they were not entered in the scan just before, see
///   [`waited`]) and every product of its receptivity that was true when it fired holds
///   the whole situation where the constraint forbids the actuator: the chart entered
///   the step where it was written to, and the step commands what is forbidden there;
/// - exits: the step was entered in the stopping cycle and every transition leaving it
///   waits for the end of that situation (each product holds the negation of one of its
///   literals): the step is the one that lasts through it. Not for a step active for a
///   while, whose alternative suspect is its exits (X412);
/// - initial: the step is initial, never moved by a recorded evolution, and its action
///   (not delayed) began while it was active (`started`): the first scan.
fn misplacement(
    v: &View<'_>,
    step: &str,
    qualifier: Qualifier,
    situation: &Situation,
    (entry, started): (Option<&(String, u64)>, bool),
) -> Option<Misplaced> {
    if situation.literals.is_empty() {
        return None;
    }
    let p = v.p();
    let frame = v.after.frame();
    let product_holds = |c: &&Vec<Literal>| {
        c.iter()
            .filter(|l| l.var.space == Space::Input)
            .all(|l| frame.literal(*l))
    };
    let mut m = Misplaced {
        activated_by: entry.map(|(t, _)| t.clone()),
        ..Misplaced::default()
    };
    if let Some((t, _)) = entry
        && let Some(info) = p.transitions.iter().find(|x| &x.id == t)
        && waited(v, info)
    {
        // The products of the receptivity that were true when it fired all require the
        // situation: the transition waited for it.
        let fired: Vec<&Vec<Literal>> = info.condition.iter().filter(product_holds).collect();
        if !fired.is_empty() && fired.iter().all(|c| situation.required_by(c)) {
            m.entry = true;
        }
    }
    // The exits are evidence only when the step was entered in the stopping cycle: the
    // alternative is then its entry, not its exits (a step active for a while whose
    // exits wait for the end of the situation may be one whose exits are wrong, X412).
    let exits = v.exits(step);
    let waits = |t: &String| {
        p.transitions
            .iter()
            .find(|x| &x.id == t)
            .is_some_and(|x| x.condition.iter().all(|c| situation.excluded_by(c)))
    };
    if entry.is_some() && !exits.is_empty() && exits.iter().all(waits) {
        m.exits = exits;
    }
    m.initial = started
        && !matches!(qualifier, Qualifier::D(_))
        && p.steps.iter().any(|s| s.id == step && s.initial)
        && v.last_firing(step, true).is_none()
        && v.last_firing(step, false).is_none();
    (m.entry || !m.exits.is_empty() || m.initial).then_some(m)
}

/// True when transition `info`, fired in the stopping cycle, had waited in its upstream
/// steps: none of them had been activated in the scan just before (a receptivity already
/// true when its upstream step is entered lets the chart cross that step without
/// waiting, and is then suspect itself). An upstream step activated before the
/// evolutions recorded (or initial) has waited.
fn waited(v: &View<'_>, info: &crate::control::program::TransitionInfo) -> bool {
    let evolutions = v.after.evolutions();
    let Some(now) = evolutions
        .iter()
        .rev()
        .find(|e| e.fired.contains(&info.id))
        .map(|e| e.scan)
    else {
        return true;
    };
    let p = v.p();
    info.from.iter().all(|&f| {
        // A step that commands nothing (no action, no equation reads it) has nothing to
        // let act: crossing it in one scan is no sign.
        let Some(aux) = p.steps.get(f as usize).map(|s| s.aux) else {
            return true;
        };
        let read = p
            .equations
            .iter()
            .flat_map(|e| e.dnf.iter().flatten())
            .any(|l| l.var.space == Space::Aux && l.var.index == aux);
        if !read && !p.actions.iter().any(|a| a.step == f) {
            return true;
        }
        let entered = evolutions.iter().rev().filter(|e| e.scan < now).find(|e| {
            e.fired.iter().any(|t| {
                p.transitions
                    .iter()
                    .find(|x| &x.id == t)
                    .is_some_and(|x| x.to.contains(&f))
            })
        });
        entered.is_none_or(|e| e.scan + 1 < now)
    })
}

/// X417: the action of `step` drives `output` ON where the step's place in its chart
/// puts it in the situation where the constraint forbids `output` (`rank`: the first
/// component of the ordering key; `since`: ms between the step's activation and the
/// stop).
fn misplaced_suspect(
    v: &View<'_>,
    (output, step, qualifier): (&str, &str, Qualifier),
    situation: &Situation,
    m: &Misplaced,
    (rank, since): (u8, u64),
) -> Suspect {
    let cond = &situation.notation;
    let constraint = &situation.constraint;
    let recs = |ts: &[String]| {
        ts.iter()
            .map(|t| v.receptivity(t))
            .collect::<Vec<_>>()
            .join(" | ")
    };
    let mut reasons = Vec::new();
    match &m.activated_by {
        Some(t) if m.entry => reasons.push(format!(
            "it was activated by {t} in the stopping cycle, whose receptivity `{}` waited for {cond}",
            v.receptivity(t)
        )),
        Some(t) => reasons.push(format!("it was activated by {t} in the stopping cycle")),
        None => {}
    }
    if !m.exits.is_empty() {
        reasons.push(format!(
            "it is left only by {} (`{}`), which {} for the end of {cond}",
            m.exits.join(", "),
            recs(&m.exits),
            if m.exits.len() == 1 { "waits" } else { "wait" }
        ));
    }
    if m.initial {
        reasons.push(
            "it is an initial step, active from the first scan: no transition activated it"
                .to_string(),
        );
    }
    let (evidence, receptivity) = match (&m.activated_by, m.exits.is_empty()) {
        (Some(t), _) if m.entry => ("entry", v.receptivity(t)),
        (_, false) => ("exits", recs(&m.exits)),
        _ => ("initial", String::new()),
    };
    let condition: Vec<String> = situation
        .literals
        .iter()
        .map(|l| v.p().symbols.name(l.var.space, l.var.index).to_string())
        .collect();
    suspect(
        codes::X_MISPLACED_ACTION,
        (rank, 0),
        format!(
            "The action {qualifier} {output} of step {step} drives {output} ON in the situation where {constraint} forbids it ({cond}): {}. The action of {step} on {output} is suspect: it belongs to another step.",
            reasons.join("; ")
        ),
        &[
            ("output", output.to_string()),
            ("chart", v.chart_of_step(step)),
            ("step", step.to_string()),
            ("qualifier", qualifier.to_string()),
            ("constraint", constraint.clone()),
            ("condition", cond.clone()),
            ("evidence", evidence.to_string()),
            ("activated_by", m.activated_by.clone().unwrap_or_default()),
            ("receptivity", receptivity),
            ("exits", join(&m.exits)),
            ("ms_before", since.to_string()),
        ],
        &v.plant(&condition),
    )
}

/// An equation commands the forbidden value (`on`: true and the actuator must be OFF;
/// else false and it must be ON).
fn equation_suspect(
    v: &View<'_>,
    output: &str,
    slot: usize,
    on: bool,
    expression: &str,
    changed: bool,
    out: &mut Vec<Suspect>,
) {
    let p = v.p();
    let Some(eq) = p.equations.iter().find(|e| e.slot == slot) else {
        return;
    };
    let frame = v.after.frame();
    // The terms that are true (for ON), or every term (for OFF).
    let terms: Vec<&Vec<crate::symbols::Literal>> = eq
        .dnf
        .iter()
        .filter(|t| !on || t.iter().all(|l| frame.literal(*l)))
        .collect();
    let mut signals: Vec<String> = Vec::new();
    for l in terms.iter().copied().flatten() {
        let n = p.symbols.name(l.var.space, l.var.index).to_string();
        if !signals.contains(&n) {
            signals.push(n);
        }
    }
    // Steps the terms read, and what changed them last.
    let mut steps = Vec::new();
    let mut transitions = Vec::new();
    let mut recent = changed;
    for s in &signals {
        if !p.steps.iter().any(|st| &st.id == s) {
            continue;
        }
        steps.push(s.clone());
        let active = v.after.is_active(s);
        if let Some((t, time)) = v.last_firing(s, active) {
            if v.ms_before(time) == 0 {
                recent = true;
            }
            if !transitions.contains(&t) {
                transitions.push(t);
            }
        }
    }
    let how = if on {
        format!("is true through {}", signals.join(", "))
    } else {
        format!("is false (it reads {})", signals.join(", "))
    };
    let via = if transitions.is_empty() {
        String::new()
    } else {
        format!(
            "; the steps it reads last changed when {} fired",
            transitions.join(", ")
        )
    };
    out.push(suspect(
        codes::X_EQUATION_FORBIDDEN_VALUE,
        (u8::from(!recent), 2),
        format!(
            "The equation of {output}, `{expression}`, {how}, so {output} is commanded {}{via}: the equation of {output} is suspect.",
            on_off(on)
        ),
        &[
            ("output", output.to_string()),
            ("chart", String::new()),
            ("equation", output.to_string()),
            ("expression", expression.to_string()),
            ("signals", join(&signals)),
            ("steps", join(&steps)),
            ("transitions", join(&transitions)),
            ("ms_before", "0".into()),
        ],
        &v.plant(&signals),
    ));
}

/// The actuator is commanded OFF and must be ON.
fn forbidden_off(v: &View<'_>, output: &str, slot: usize, was: bool, out: &mut Vec<Suspect>) {
    let before = v.before.drivers(output).unwrap_or_default();
    let fired = v.after.fired_last_scan();
    let mut found = false;
    for d in &before {
        match d {
            Driver::Action { step, qualifier } => {
                let chart = v.chart_of_step(step);
                if v.after.is_active(step) {
                    // The step is still active: the action itself ended.
                    found = true;
                    out.push(suspect(
                        codes::X_QUALIFIER,
                        (0, 0),
                        format!(
                            "Step {step} is still active but its action {qualifier} {output} no longer commands {output}{}: the qualifier of this action is suspect.",
                            match qualifier {
                                Qualifier::P => " (a pulse lasts one scan)",
                                Qualifier::L(_) => " (its time limit ran out)",
                                _ => "",
                            }
                        ),
                        &[
                            ("output", output.to_string()),
                            ("chart", chart),
                            ("step", step.clone()),
                            ("qualifier", qualifier.to_string()),
                            ("ms_before", "0".into()),
                        ],
                        &[],
                    ));
                    continue;
                }
                for t in fired.iter().filter(|t| deactivates(v, t, step)) {
                    found = true;
                    out.push(deactivation(v, t, step, *qualifier, output, v.trip_ms));
                }
            }
            Driver::Stored { set_by } => {
                // Reset by an R action of a step active now.
                let resetters: Vec<String> = {
                    let p = v.p();
                    p.actions
                        .iter()
                        .filter(|a| a.slot == slot && a.qualifier == Qualifier::R)
                        .filter_map(|a| p.steps.get(a.step as usize))
                        .filter(|s| v.after.is_active(&s.id))
                        .map(|s| s.id.clone())
                        .collect()
                };
                found = true;
                let chart = resetters
                    .first()
                    .or(set_by.first())
                    .map(|s| v.chart_of_step(s))
                    .unwrap_or_default();
                out.push(suspect(
                    codes::X_QUALIFIER,
                    (0, 0),
                    format!(
                        "{output} was stored ON (S action of {}) and was reset in the stopping cycle by the R action of {}: this reset is suspect.",
                        set_by.join(", "),
                        if resetters.is_empty() { "a step".to_string() } else { resetters.join(", ") }
                    ),
                    &[
                        ("output", output.to_string()),
                        ("chart", chart),
                        ("step", join(&resetters)),
                        ("qualifier", "R".into()),
                        ("ms_before", "0".into()),
                    ],
                    &[],
                ));
            }
            Driver::Equation { expression } => {
                found = true;
                equation_suspect(v, output, slot, false, expression, true, out);
            }
        }
    }
    if found {
        return;
    }
    let _ = was;
    // Nothing held it in the cycle before: the last evolution that left a step
    // commanding it.
    let commanding = v.commanding_steps(slot);
    for ev in v.after.evolutions().iter().rev() {
        let mut hit = false;
        for t in &ev.fired {
            for (step, q) in &commanding {
                if deactivates(v, t, step) && !matches!(q, Qualifier::S) {
                    out.push(deactivation(v, t, step, *q, output, ev.time.0));
                    hit = true;
                }
            }
        }
        if hit {
            return;
        }
    }
    nothing_commands(v, output, slot, &commanding, out);
}

/// X411: nothing commands the actuator that must be ON.
fn nothing_commands(
    v: &View<'_>,
    output: &str,
    slot: usize,
    commanding: &[(String, Qualifier)],
    out: &mut Vec<Suspect>,
) {
    let steps: Vec<String> = commanding.iter().map(|(s, _)| s.clone()).collect();
    let eq = v.equation(slot);
    let mut signals = Vec::new();
    if let Some((k, _)) = &eq
        && let Some(e) = v.p().equations.get(*k)
    {
        signals = v.dnf_names(&e.dnf);
    }
    let text = format!(
        "{output} should be ON but no element of the program commands it now: {}{}.",
        if steps.is_empty() {
            "no step acts on it".to_string()
        } else {
            format!(
                "none of the steps that act on it ({}) is active",
                steps.join(", ")
            )
        },
        eq.as_ref()
            .map(|(_, e)| format!(", and its equation `{e}` is false"))
            .unwrap_or_default()
    );
    out.push(suspect(
        codes::X_NOTHING_COMMANDS,
        (1, 3),
        text,
        &[
            ("output", output.to_string()),
            (
                "chart",
                steps
                    .first()
                    .map(|s| v.chart_of_step(s))
                    .unwrap_or_default(),
            ),
            ("steps", join(&steps)),
            (
                "equation",
                if eq.is_some() {
                    output.to_string()
                } else {
                    String::new()
                },
            ),
            ("expression", eq.map(|(_, e)| e).unwrap_or_default()),
            ("signals", join(&signals)),
        ],
        &[],
    ));
}

/// X413, for a combined constraint: a step activated in the stopping cycle drives one
/// actuator of it to the forbidden value (ON) while another one, which must then be ON,
/// is commanded by nothing (an `X411` suspect): the new situation commands the first
/// actuator without the second, so the actions of the new step or the elements that
/// command the second are suspect.
fn coordination(v: &View<'_>, constraint: &str, suspects: &[Suspect]) -> Option<Suspect> {
    let undriven = suspects
        .iter()
        .find(|s| s.item.code == codes::X_NOTHING_COMMANDS.id)?;
    let new_steps: Vec<String> = v
        .after
        .active_steps()
        .into_iter()
        .filter(|s| !v.before.is_active(s))
        .map(str::to_string)
        .collect();
    let names = |s: &Suspect, key: &str| -> Vec<String> {
        s.item
            .fields
            .get(key)
            .map(|x| {
                x.split(',')
                    .filter(|n| !n.is_empty())
                    .map(str::to_string)
                    .collect()
            })
            .unwrap_or_default()
    };
    let (driven, steps) = suspects
        .iter()
        .filter(|s| s.item.code != codes::X_NOTHING_COMMANDS.id)
        .find_map(|s| {
            let read: Vec<String> = names(s, "step")
                .into_iter()
                .chain(names(s, "steps"))
                .collect();
            let new: Vec<String> = read.into_iter().filter(|x| new_steps.contains(x)).collect();
            (!new.is_empty()).then_some((s, new))
        })?;
    let on = field(driven, "output");
    let off = field(undriven, "output");
    let fired: Vec<String> = v
        .after
        .fired_last_scan()
        .into_iter()
        .filter(|t| {
            let p = v.p();
            p.transitions
                .iter()
                .find(|x| x.id == *t)
                .is_some_and(|x| v.steps_of(&x.to).iter().any(|s| steps.contains(s)))
        })
        .map(str::to_string)
        .collect();
    let equation = field(undriven, "equation");
    let expression = field(undriven, "expression");
    let commanding = field(undriven, "steps");
    let elsewhere = match (equation.is_empty(), commanding.is_empty()) {
        (false, _) => format!("the equation of {off} (`{expression}`)"),
        (true, false) => format!("the steps acting on {off} ({commanding})"),
        (true, true) => format!("the program, which never commands {off}"),
    };
    Some(Suspect {
        item: Item::new(
            codes::X_COMBINED_MISSING,
            format!(
                "Step {} (activated by {} in the stopping cycle) drives {on} ON, but nothing commands {off}, which {constraint} requires ON with {on}: the actions of {} or {elsewhere} miss {off}.",
                steps.join(", "),
                fired.join(", "),
                steps.join(", "),
            ),
            &[
                ("output", off.clone()),
                ("constraint", constraint.to_string()),
                (
                    "chart",
                    steps
                        .first()
                        .map(|s| v.chart_of_step(s))
                        .unwrap_or_default(),
                ),
                ("step", join(&steps)),
                ("transition", join(&fired)),
                ("equation", equation),
                ("expression", expression),
                ("steps", commanding),
                ("driven", on),
                ("ms_before", "0".into()),
            ],
        ),
        highlights: vec![Highlight {
            element: off,
            mark: Mark::Suspect,
        }],
        rank: (0, 0),
    })
}

/// A suspect's field, empty when absent.
fn field(s: &Suspect, key: &str) -> String {
    s.item.fields.get(key).cloned().unwrap_or_default()
}

/// True when transition `t` has `step` upstream.
fn deactivates(v: &View<'_>, t: &str, step: &str) -> bool {
    let p = v.p();
    let Some(info) = p.transitions.iter().find(|x| x.id == t) else {
        return false;
    };
    v.steps_of(&info.from).iter().any(|s| s == step)
}

/// X407 for transition `t` that deactivated `step` at `time`.
fn deactivation(
    v: &View<'_>,
    t: &str,
    step: &str,
    q: Qualifier,
    output: &str,
    time: u64,
) -> Suspect {
    let p = v.p();
    let to = p
        .transitions
        .iter()
        .find(|x| x.id == t)
        .map(|info| v.steps_of(&info.to))
        .unwrap_or_default();
    let rec = v.receptivity(t);
    let signals = v.transition_signals(t);
    Suspect {
        item: Item::new(
            codes::X_TRANSITION_DEACTIVATED_STEP,
            format!(
                "Transition {t} (receptivity `{rec}`) fired {} and deactivated step {step}, whose action {q} {output} held {output} ON; it activated {}, which does not command {output} now: the receptivity of {t} is suspect (it reads {}).",
                v.when(time),
                to.join(", "),
                signals.join(", ")
            ),
            &[
                ("output", output.to_string()),
                ("chart", v.chart_of_transition(t)),
                ("transition", t.to_string()),
                ("receptivity", rec),
                ("signals", join(&signals)),
                ("step", step.to_string()),
                ("qualifier", q.to_string()),
                ("activated", join(&to)),
                ("ms_before", v.ms_before(time).to_string()),
            ],
        ),
        highlights: v
            .plant(&signals)
            .iter()
            .map(|s| Highlight {
                element: s.clone(),
                mark: Mark::Suspect,
            })
            .collect(),
        rank: (u8::from(v.ms_before(time) > 0), 0),
    }
}
