//! Alarm management after ISA-18.2: each alarm is unacknowledged while new, acknowledged
//! by the operator (with an optional note), and cleared when its condition returns to
//! normal; an alarm cleared before it is acknowledged stays in the list as
//! *cleared-unacknowledged* until it is.
//!
//! - **Priority** follows from the alarm's kind ([`AlarmKind::priority`]): a trip of the
//!   safety filter and a hazard are urgent; the list is ordered by priority, then
//!   unacknowledged first, then newest first.
//! - **Shelving** needs a reason and a duration of at most [`MAX_SHELVING`]; a safety
//!   alarm (trip, hazard, specification error, live link) is never shelvable. It is
//!   for the source: the alarm raised again while the shelving lasts stays shelved.
//! - **First-out** marks the first alarm of the event that stops the plant: the first
//!   alarm of a kind that can stop it ([`AlarmKind::can_stop`]) raised while no other
//!   such alarm is active or unacknowledged. A task monitor's prediction never stops
//!   the plant and is never first-out.
//! - Each alarm has an operator text (the plant's own names and descriptions) and an
//!   engineer's detail (formulas, codes), shown one click away.

pub mod texts;

use crate::time::Millis;
use serde::Serialize;
use std::collections::BTreeMap;

/// An alarm's operator text and the engineer's detail.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AlarmText {
    /// In the operator's words.
    pub message: String,
    /// Formula, codes, internal names; may be empty.
    pub detail: String,
    /// What the message says, as data, for a console that shows it in another language:
    /// a code (`plausibility-suspect`, `diagnosis-estimated`…; empty when none) and its
    /// fields (`sensor`, `fault`…).
    pub code: &'static str,
    /// See `code`.
    pub fields: BTreeMap<String, String>,
}

impl AlarmText {
    /// The same text with its code and fields.
    #[must_use]
    pub fn with(mut self, code: &'static str, fields: BTreeMap<String, String>) -> Self {
        self.code = code;
        self.fields = fields;
        self
    }
}

impl From<&str> for AlarmText {
    fn from(message: &str) -> Self {
        message.to_string().into()
    }
}

impl From<String> for AlarmText {
    fn from(message: String) -> Self {
        Self {
            message,
            ..Self::default()
        }
    }
}

/// The longest shelving: one shift.
pub const MAX_SHELVING: Millis = Millis(8 * 3_600_000);

/// ISA-18.2 priority; the order is the urgency (`Urgent` first).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AlarmPriority {
    /// Act now: the plant is stopped or damaged.
    Urgent,
    /// Act soon: the plant runs unprotected, degraded or blind.
    High,
    /// Look at it: a prediction or a suspect reading that did not stop the plant.
    Medium,
}

impl AlarmPriority {
    /// `1`, `2`, `3`: the number shown beside the alarm.
    pub fn rank(self) -> u8 {
        match self {
            Self::Urgent => 1,
            Self::High => 2,
            Self::Medium => 3,
        }
    }
}

/// Where an alarm comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AlarmKind {
    /// The safety filter tripped.
    FilterTrip,
    /// A diagnoser decided a fault with certainty.
    Diagnosis,
    /// A task monitor predicts an unacceptable duration.
    Task,
    /// The live link is lost or stale.
    Link,
    /// The constraint set has no fallback (specification error).
    Specification,
    /// A dangerous state of the plant (emulator hazard).
    Hazard,
    /// A sensor's edge the plant's physics does not allow was held (a suspect sensor).
    Plausibility,
    /// The live PLC's outputs left every run of the program it should be running.
    Program,
}

impl AlarmKind {
    /// Every kind, in declaration order.
    pub const ALL: [AlarmKind; 8] = [
        Self::FilterTrip,
        Self::Diagnosis,
        Self::Task,
        Self::Link,
        Self::Specification,
        Self::Hazard,
        Self::Plausibility,
        Self::Program,
    ];

    /// Its name in texts.
    pub fn name(self) -> &'static str {
        match self {
            Self::FilterTrip => "safety filter trip",
            Self::Diagnosis => "diagnosis",
            Self::Task => "task monitor",
            Self::Link => "live link",
            Self::Specification => "specification error",
            Self::Hazard => "hazard",
            Self::Plausibility => "implausible sensor",
            Self::Program => "program divergence",
        }
    }

    /// The priority of every alarm of this kind.
    pub fn priority(self) -> AlarmPriority {
        match self {
            Self::FilterTrip | Self::Hazard => AlarmPriority::Urgent,
            Self::Specification | Self::Link | Self::Diagnosis | Self::Program => {
                AlarmPriority::High
            }
            Self::Task | Self::Plausibility => AlarmPriority::Medium,
        }
    }

    /// A safety alarm (trip, hazard, a constraint set without fallback, the live link)
    /// is never shelved.
    pub fn shelvable(self) -> bool {
        matches!(self, Self::Diagnosis | Self::Task | Self::Plausibility)
    }

    /// Alarms of this kind may start the event that stops the plant (candidates for
    /// first-out); a task monitor's prediction never stops it.
    pub fn can_stop(self) -> bool {
        !matches!(self, Self::Task)
    }

    /// An alarm of this kind says the plant stopped (the filter's trip, a diagnoser's
    /// stop through its `DSTOP_` constraint, a constraint set without fallback): its
    /// event gets a first-out.
    pub fn stops(self) -> bool {
        matches!(self, Self::FilterTrip | Self::Specification)
    }
}

/// A shelving: when, until when, and why.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Shelving {
    /// When it was shelved.
    pub at: Millis,
    /// Hidden until this time.
    pub until: Millis,
    /// The operator's reason.
    pub reason: String,
}

/// ISA-18.2 alarm state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AlarmState {
    /// Active, not acknowledged.
    Unacknowledged,
    /// Active, acknowledged.
    Acknowledged,
    /// Returned to normal before being acknowledged.
    ClearedUnacknowledged,
    /// Returned to normal and acknowledged: no longer shown.
    Normal,
}

/// One alarm.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Alarm {
    /// Unique number, in order of raising.
    pub id: u64,
    /// Identity of the condition (`trip:CSs10`, `link:plant`); one active alarm per key.
    pub key: String,
    /// Origin.
    pub kind: AlarmKind,
    /// Text shown to the operator, from the plant's own names and descriptions.
    pub message: String,
    /// The engineer's detail (formula, codes), shown on demand; may be empty.
    pub detail: String,
    /// The message as data ([`AlarmText::code`]); empty when none.
    pub code: &'static str,
    /// Its fields ([`AlarmText::fields`]).
    pub fields: BTreeMap<String, String>,
    /// When it was raised.
    pub raised: Millis,
    /// Acknowledgement time and note.
    pub acknowledged: Option<(Millis, String)>,
    /// When the condition returned to normal.
    pub cleared: Option<Millis>,
    /// The current or last shelving.
    pub shelving: Option<Shelving>,
    /// First alarm of the event that stops the plant.
    pub first_out: bool,
}

impl Alarm {
    /// The ISA-18.2 state.
    pub fn state(&self) -> AlarmState {
        match (self.cleared.is_some(), self.acknowledged.is_some()) {
            (false, false) => AlarmState::Unacknowledged,
            (false, true) => AlarmState::Acknowledged,
            (true, false) => AlarmState::ClearedUnacknowledged,
            (true, true) => AlarmState::Normal,
        }
    }

    /// True while shelved at `now`.
    pub fn is_shelved(&self, now: Millis) -> bool {
        self.shelving.as_ref().is_some_and(|s| now < s.until)
    }

    /// Its priority.
    pub fn priority(&self) -> AlarmPriority {
        self.kind.priority()
    }

    /// Active or unacknowledged.
    fn is_open(&self) -> bool {
        self.state() != AlarmState::Normal
    }
}

/// Why an operator action on an alarm was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum AlarmError {
    /// No such alarm.
    #[error("no alarm #{0}")]
    Unknown(u64),
    /// Already acknowledged.
    #[error("alarm #{0} is already acknowledged")]
    AlreadyAcknowledged(u64),
    /// Shelving needs a positive duration.
    #[error("shelving needs a duration of at least 1 ms")]
    EmptyShelving,
    /// Shelving is limited to [`MAX_SHELVING`].
    #[error("shelving is limited to {} h (one shift)", MAX_SHELVING.0 / 3_600_000)]
    ShelvingTooLong,
    /// Shelving needs the operator's reason.
    #[error("shelving needs a reason")]
    NoReason,
    /// A safety alarm is never shelved.
    #[error("alarm #{0} is a safety alarm ({1}): it cannot be shelved")]
    NotShelvable(u64, &'static str),
}

/// ISA-18.2's alarm flood: more than this many alarms in 10 minutes.
pub const FLOOD_PER_10_MIN: usize = 10;

/// Ten minutes, the ISA-18.2 measurement interval.
const TEN_MIN_MS: u64 = 600_000;

/// Alarm-system performance (ISA-18.2 section 16, EEMUA 191): rates per fixed 10-minute
/// interval from the start of the run, floods, chattering and the most frequent sources.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AlarmKpis {
    /// Alarms raised in all.
    pub total: usize,
    /// Raised in the last 10 minutes (sliding, up to now).
    pub last_10_min: usize,
    /// Average per 10 minutes over the run (at least one interval).
    pub average_per_10_min: f64,
    /// The busiest fixed 10-minute interval.
    pub peak_per_10_min: usize,
    /// Fixed 10-minute intervals so far (the current one included).
    pub intervals: usize,
    /// Of those, intervals in flood (more than [`FLOOD_PER_10_MIN`]).
    pub flood_intervals: usize,
    /// The last 10 minutes are a flood.
    pub flooding: bool,
    /// Sources raised three times or more within a minute (chattering).
    pub chattering: Vec<String>,
    /// The five most frequent sources, most frequent first (ties by name).
    pub most_frequent: Vec<(String, usize)>,
}

/// An alarm's source for the statistics: its key without the item numbers
/// (`hazard:9:Collision` → `hazard:Collision`).
pub fn source_of(key: &str) -> String {
    key.split(':')
        .filter(|seg| seg.is_empty() || !seg.chars().all(|c| c.is_ascii_digit()))
        .collect::<Vec<_>>()
        .join(":")
}

/// A filter of the alarm history.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HistoryFilter {
    /// Case-insensitive text found in the message, the detail or the key.
    pub text: String,
    /// Only this kind.
    pub kind: Option<AlarmKind>,
    /// Only this priority.
    pub priority: Option<AlarmPriority>,
}

impl HistoryFilter {
    /// True when `a` passes.
    pub fn matches(&self, a: &Alarm) -> bool {
        let needle = self.text.trim().to_lowercase();
        self.kind.is_none_or(|k| a.kind == k)
            && self.priority.is_none_or(|p| a.priority() == p)
            && (needle.is_empty()
                || [&a.message, &a.detail, &a.key]
                    .iter()
                    .any(|t| t.to_lowercase().contains(&needle)))
    }
}

/// One CSV field, quoted.
fn csv_field(text: &str) -> String {
    format!("\"{}\"", text.replace('"', "\"\""))
}

/// The alarm list.
#[derive(Clone, Debug, Default, Serialize)]
pub struct AlarmList {
    alarms: Vec<Alarm>,
    next_id: u64,
}

impl AlarmList {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// Raises an alarm for `key` unless one is already active; returns its id.
    pub fn raise(
        &mut self,
        now: Millis,
        key: &str,
        kind: AlarmKind,
        text: impl Into<AlarmText>,
    ) -> u64 {
        let AlarmText {
            message,
            detail,
            code,
            fields,
        } = text.into();
        if let Some(a) = self
            .alarms
            .iter()
            .find(|a| a.key == key && a.cleared.is_none())
        {
            return a.id;
        }
        // First-out, once the plant stops: the earliest open alarm that can start a
        // stop (a suspect sensor before the trip), else this one. An event in which
        // nothing stops has none.
        let mut first_out = false;
        if kind.stops() && !self.alarms.iter().any(|a| a.first_out && a.is_open()) {
            match self
                .alarms
                .iter_mut()
                .filter(|a| a.kind.can_stop() && a.is_open())
                .min_by_key(|a| a.id)
            {
                Some(a) => a.first_out = true,
                None => first_out = true,
            }
        }
        // Shelving is for the source (a chattering alarm clears and comes back): an
        // alarm raised again while its key's shelving lasts stays shelved.
        let shelving = self
            .alarms
            .iter()
            .rev()
            .find(|a| a.key == key)
            .and_then(|a| a.shelving.clone())
            .filter(|s| now < s.until);
        self.next_id += 1;
        self.alarms.push(Alarm {
            id: self.next_id,
            key: key.to_string(),
            kind,
            message,
            detail,
            code,
            fields,
            raised: now,
            acknowledged: None,
            cleared: None,
            shelving,
            first_out,
        });
        self.next_id
    }

    /// The keys of the alarms of `kind` whose condition is still present, in raising
    /// order.
    pub fn active_keys(&self, kind: AlarmKind) -> Vec<String> {
        self.alarms
            .iter()
            .filter(|a| a.kind == kind && a.cleared.is_none())
            .map(|a| a.key.clone())
            .collect()
    }

    /// The condition behind `key` returned to normal.
    pub fn clear(&mut self, now: Millis, key: &str) {
        for a in self
            .alarms
            .iter_mut()
            .filter(|a| a.key == key && a.cleared.is_none())
        {
            a.cleared = Some(now);
        }
    }

    /// Operator acknowledgement, with an optional note (empty for none).
    pub fn acknowledge(&mut self, now: Millis, id: u64, note: &str) -> Result<(), AlarmError> {
        let a = self
            .alarms
            .iter_mut()
            .find(|a| a.id == id)
            .ok_or(AlarmError::Unknown(id))?;
        if a.acknowledged.is_some() {
            return Err(AlarmError::AlreadyAcknowledged(id));
        }
        a.acknowledged = Some((now, note.to_string()));
        Ok(())
    }

    /// Acknowledges every unacknowledged alarm among `ids` (all of them for `None`),
    /// shelved ones included; returns the ids acknowledged, in raising order.
    pub fn acknowledge_all(&mut self, now: Millis, ids: Option<&[u64]>, note: &str) -> Vec<u64> {
        let mut done = Vec::new();
        for a in self
            .alarms
            .iter_mut()
            .filter(|a| a.acknowledged.is_none() && ids.is_none_or(|ids| ids.contains(&a.id)))
        {
            a.acknowledged = Some((now, note.to_string()));
            done.push(a.id);
        }
        done
    }

    /// Hides an alarm for `duration` (at most [`MAX_SHELVING`]), with the operator's
    /// `reason`; refused for a safety alarm.
    pub fn shelve(
        &mut self,
        now: Millis,
        id: u64,
        duration: Millis,
        reason: &str,
    ) -> Result<(), AlarmError> {
        let a = self
            .alarms
            .iter_mut()
            .find(|a| a.id == id)
            .ok_or(AlarmError::Unknown(id))?;
        if !a.kind.shelvable() {
            return Err(AlarmError::NotShelvable(id, a.kind.name()));
        }
        if duration.0 == 0 {
            return Err(AlarmError::EmptyShelving);
        }
        if duration > MAX_SHELVING {
            return Err(AlarmError::ShelvingTooLong);
        }
        if reason.trim().is_empty() {
            return Err(AlarmError::NoReason);
        }
        a.shelving = Some(Shelving {
            at: now,
            until: now + duration,
            reason: reason.trim().to_string(),
        });
        Ok(())
    }

    /// Shows a shelved alarm again (its shelving ends now).
    pub fn unshelve(&mut self, now: Millis, id: u64) -> Result<(), AlarmError> {
        let a = self
            .alarms
            .iter_mut()
            .find(|a| a.id == id)
            .ok_or(AlarmError::Unknown(id))?;
        if let Some(s) = a.shelving.as_mut() {
            s.until = s.until.min(now);
        }
        Ok(())
    }

    /// Alarms to show at `now`, not back to normal and not shelved: by priority, then
    /// unacknowledged first, then newest first.
    pub fn visible(&self, now: Millis) -> Vec<&Alarm> {
        let mut v: Vec<&Alarm> = self
            .alarms
            .iter()
            .filter(|a| a.is_open() && !a.is_shelved(now))
            .collect();
        v.sort_by_key(|a| {
            (
                a.priority(),
                a.acknowledged.is_some(),
                std::cmp::Reverse(a.id),
            )
        });
        v
    }

    /// Shelved alarms at `now`.
    pub fn shelved(&self, now: Millis) -> Vec<&Alarm> {
        self.alarms.iter().filter(|a| a.is_shelved(now)).collect()
    }

    /// Every alarm ever raised, oldest first.
    pub fn all(&self) -> &[Alarm] {
        &self.alarms
    }

    /// An alarm by id.
    pub fn get(&self, id: u64) -> Option<&Alarm> {
        self.alarms.iter().find(|a| a.id == id)
    }

    /// Every alarm `filter` passes, newest first (the history: cleared and
    /// acknowledged ones included).
    pub fn history(&self, filter: &HistoryFilter) -> Vec<&Alarm> {
        self.alarms
            .iter()
            .rev()
            .filter(|a| filter.matches(a))
            .collect()
    }

    /// `alarms` as CSV, one line each with every field quoted; times in ms of plant
    /// time, empty when not applicable.
    pub fn history_csv(alarms: &[&Alarm]) -> String {
        let mut s = String::from(
            "id,raised_ms,priority,kind,state,first_out,message,detail,cleared_ms,\
             acknowledged_ms,note,shelved_until_ms,shelving_reason\n",
        );
        let ms = |t: Option<Millis>| t.map(|t| t.0.to_string()).unwrap_or_default();
        for a in alarms {
            let state = serde_json::to_value(a.state())
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            let fields = [
                a.id.to_string(),
                a.raised.0.to_string(),
                format!("P{}", a.priority().rank()),
                a.kind.name().to_string(),
                state,
                a.first_out.to_string(),
                a.message.clone(),
                a.detail.clone(),
                ms(a.cleared),
                ms(a.acknowledged.as_ref().map(|x| x.0)),
                a.acknowledged
                    .as_ref()
                    .map(|x| x.1.clone())
                    .unwrap_or_default(),
                ms(a.shelving.as_ref().map(|x| x.until)),
                a.shelving
                    .as_ref()
                    .map(|x| x.reason.clone())
                    .unwrap_or_default(),
            ];
            let line: Vec<String> = fields.iter().map(|f| csv_field(f)).collect();
            s.push_str(&line.join(","));
            s.push('\n');
        }
        s
    }

    /// The alarm-system figures at `now`.
    pub fn kpis(&self, now: Millis) -> AlarmKpis {
        let intervals = usize::try_from(now.0 / TEN_MIN_MS + 1).unwrap_or(usize::MAX);
        let mut per: std::collections::BTreeMap<u64, usize> = std::collections::BTreeMap::new();
        let mut by_source: std::collections::BTreeMap<String, Vec<u64>> =
            std::collections::BTreeMap::new();
        for a in &self.alarms {
            *per.entry(a.raised.0 / TEN_MIN_MS).or_default() += 1;
            by_source
                .entry(source_of(&a.key))
                .or_default()
                .push(a.raised.0);
        }
        let last_10_min = self
            .alarms
            .iter()
            .filter(|a| a.raised.0 + TEN_MIN_MS > now.0 && a.raised <= now)
            .count();
        let chattering = by_source
            .iter()
            .filter(|(_, times)| times.windows(3).any(|w| w[2] - w[0] <= 60_000))
            .map(|(k, _)| k.clone())
            .collect();
        let mut most_frequent: Vec<(String, usize)> = by_source
            .iter()
            .map(|(k, t)| (k.clone(), t.len()))
            .collect();
        most_frequent.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
        most_frequent.truncate(5);
        let elapsed = (now.0 as f64 / TEN_MIN_MS as f64).max(1.0);
        AlarmKpis {
            total: self.alarms.len(),
            last_10_min,
            average_per_10_min: self.alarms.len() as f64 / elapsed,
            peak_per_10_min: per.values().copied().max().unwrap_or(0),
            intervals,
            flood_intervals: per.values().filter(|&&n| n > FLOOD_PER_10_MIN).count(),
            flooding: last_10_min > FLOOD_PER_10_MIN,
            chattering,
            most_frequent,
        }
    }

    /// Number of unacknowledged alarms (active or cleared).
    pub fn unacknowledged(&self) -> usize {
        self.alarms
            .iter()
            .filter(|a| a.acknowledged.is_none())
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isa_18_2_lifecycle() {
        let mut l = AlarmList::new();
        let a = l.raise(Millis(10), "trip:CSs10", AlarmKind::FilterTrip, "CSs10");
        assert_eq!(l.get(a).map(Alarm::state), Some(AlarmState::Unacknowledged));
        assert!(l.get(a).is_some_and(|x| x.first_out));
        // Same condition again: no duplicate.
        assert_eq!(
            l.raise(Millis(20), "trip:CSs10", AlarmKind::FilterTrip, "x"),
            a
        );
        let b = l.raise(Millis(30), "link:plant", AlarmKind::Link, "link");
        assert!(
            l.get(b).is_some_and(|x| !x.first_out),
            "second of the burst"
        );
        l.clear(Millis(40), "link:plant");
        assert_eq!(
            l.get(b).map(Alarm::state),
            Some(AlarmState::ClearedUnacknowledged)
        );
        assert_eq!(l.visible(Millis(40)).len(), 2);
        l.acknowledge(Millis(50), b, "cable reseated").unwrap();
        assert_eq!(l.get(b).map(Alarm::state), Some(AlarmState::Normal));
        assert_eq!(l.visible(Millis(50)).len(), 1);
        assert_eq!(
            l.acknowledge(Millis(60), b, ""),
            Err(AlarmError::AlreadyAcknowledged(b))
        );
        l.acknowledge(Millis(60), a, "").unwrap();
        assert_eq!(l.get(a).map(Alarm::state), Some(AlarmState::Acknowledged));
        // A new event, once the last one's alarms are cleared and acknowledged, starts
        // a new first-out.
        l.clear(Millis(65), "trip:CSs10");
        let c = l.raise(Millis(70), "diag:C4", AlarmKind::Diagnosis, "C4");
        assert!(
            l.get(c).is_some_and(|x| !x.first_out),
            "nothing stopped (degraded mode): no first-out"
        );
        let d = l.raise(Millis(80), "trip:CSs2", AlarmKind::FilterTrip, "CSs2");
        assert!(
            l.get(c).is_some_and(|x| x.first_out),
            "the trip's first-out"
        );
        assert!(l.get(d).is_some_and(|x| !x.first_out));
        assert_eq!(l.all().len(), 4, "nothing is ever removed");
    }

    #[test]
    fn shelving_needs_a_reason_and_a_bounded_duration_and_never_hides_a_safety_alarm() {
        let mut l = AlarmList::new();
        let a = l.raise(Millis(0), "k", AlarmKind::Task, "m");
        assert_eq!(
            l.shelve(Millis(0), a, Millis(0), "known"),
            Err(AlarmError::EmptyShelving)
        );
        assert_eq!(
            l.shelve(Millis(0), a, Millis(1000), "  "),
            Err(AlarmError::NoReason)
        );
        assert_eq!(
            l.shelve(Millis(0), a, MAX_SHELVING + Millis(1), "known"),
            Err(AlarmError::ShelvingTooLong)
        );
        l.shelve(Millis(100), a, Millis(1000), " belt being cleaned ")
            .unwrap();
        assert_eq!(
            l.get(a)
                .and_then(|x| x.shelving.as_ref())
                .map(|s| s.reason.as_str()),
            Some("belt being cleaned")
        );
        assert!(l.visible(Millis(500)).is_empty());
        assert_eq!(l.shelved(Millis(500)).len(), 1);
        assert_eq!(l.visible(Millis(1100)).len(), 1, "shelving expired");
        l.shelve(Millis(1100), a, Millis(1000), "again").unwrap();
        l.unshelve(Millis(1200), a).unwrap();
        assert_eq!(l.visible(Millis(1200)).len(), 1);
        assert_eq!(
            l.get(a).and_then(|x| x.shelving.as_ref()).map(|s| s.until),
            Some(Millis(1200)),
            "the shelving stays on record, ended"
        );
        assert_eq!(l.unshelve(Millis(0), 99), Err(AlarmError::Unknown(99)));
        // A chattering source: shelved, it clears and comes back while the shelving
        // lasts, and stays hidden; after the shelving, it shows.
        l.shelve(Millis(2000), a, Millis(10_000), "chattering beam")
            .unwrap();
        l.clear(Millis(2100), "k");
        let again = l.raise(Millis(2200), "k", AlarmKind::Task, "m");
        assert_ne!(again, a);
        assert!(l.visible(Millis(2300)).iter().all(|x| x.id != again));
        l.clear(Millis(12_100), "k");
        let later = l.raise(Millis(12_100), "k", AlarmKind::Task, "m");
        assert!(l.visible(Millis(12_200)).iter().any(|x| x.id == later));
        // Every safety kind is refused, whatever the reason and duration.
        for kind in [
            AlarmKind::FilterTrip,
            AlarmKind::Hazard,
            AlarmKind::Specification,
            AlarmKind::Link,
        ] {
            let id = l.raise(Millis(0), &format!("{kind:?}"), kind, "m");
            assert_eq!(
                l.shelve(Millis(0), id, Millis(1000), "nuisance"),
                Err(AlarmError::NotShelvable(id, kind.name()))
            );
            assert!(l.get(id).is_some_and(|x| x.shelving.is_none()));
        }
    }

    #[test]
    fn the_list_is_ordered_by_priority_then_unacknowledged_then_newest() {
        let mut l = AlarmList::new();
        let task = l.raise(Millis(0), "task", AlarmKind::Task, "t");
        let trip = l.raise(Millis(10), "trip", AlarmKind::FilterTrip, "x");
        let diag = l.raise(Millis(20), "diag", AlarmKind::Diagnosis, "d");
        let plaus = l.raise(Millis(30), "pl", AlarmKind::Plausibility, "p");
        let ids =
            |l: &AlarmList| -> Vec<u64> { l.visible(Millis(40)).iter().map(|a| a.id).collect() };
        assert_eq!(ids(&l), vec![trip, diag, plaus, task]);
        l.acknowledge(Millis(40), plaus, "").unwrap();
        assert_eq!(ids(&l), vec![trip, diag, task, plaus]);
        let trip2 = l.raise(Millis(50), "trip2", AlarmKind::FilterTrip, "y");
        assert_eq!(ids(&l), vec![trip2, trip, diag, task, plaus]);
        assert!(AlarmPriority::Urgent < AlarmPriority::Medium);
        assert_eq!(AlarmKind::FilterTrip.priority().rank(), 1);
    }

    #[test]
    fn acknowledge_all_or_a_page() {
        let mut l = AlarmList::new();
        let a = l.raise(Millis(0), "a", AlarmKind::Task, "a");
        let b = l.raise(Millis(0), "b", AlarmKind::Diagnosis, "b");
        let c = l.raise(Millis(0), "c", AlarmKind::FilterTrip, "c");
        l.acknowledge(Millis(1), a, "").unwrap();
        assert_eq!(l.acknowledge_all(Millis(2), Some(&[a, b]), "page"), vec![b]);
        assert_eq!(l.unacknowledged(), 1);
        assert_eq!(l.acknowledge_all(Millis(3), None, ""), vec![c]);
        assert_eq!(l.unacknowledged(), 0);
        assert!(l.acknowledge_all(Millis(4), None, "").is_empty());
        assert_eq!(
            l.get(b).and_then(|x| x.acknowledged.clone()),
            Some((Millis(2), "page".to_string()))
        );
    }

    #[test]
    fn first_out_is_the_first_alarm_of_the_stopping_event_never_a_task_prediction() {
        let mut l = AlarmList::new();
        // A task alarm first (a prediction, it stops nothing), then the trip.
        let task = l.raise(Millis(0), "task", AlarmKind::Task, "t");
        let trip = l.raise(Millis(10), "trip", AlarmKind::FilterTrip, "x");
        let hazard = l.raise(Millis(20), "hz", AlarmKind::Hazard, "h");
        let first = |l: &AlarmList| -> Vec<u64> {
            l.all()
                .iter()
                .filter(|a| a.first_out)
                .map(|a| a.id)
                .collect()
        };
        assert_eq!(first(&l), vec![trip]);
        // A suspect sensor before the trip is the trip's first-out.
        let mut m = AlarmList::new();
        let sus = m.raise(Millis(0), "pl", AlarmKind::Plausibility, "p");
        assert_eq!(
            first(&m),
            Vec::<u64>::new(),
            "a suspect sensor alone stops nothing"
        );
        m.raise(Millis(5), "trip", AlarmKind::FilterTrip, "x");
        assert_eq!(first(&m), vec![sus]);
        // Once the event's alarms are cleared and acknowledged, a new event starts.
        for k in ["trip", "hz"] {
            l.clear(Millis(30), k);
        }
        l.acknowledge_all(Millis(30), Some(&[trip, hazard]), "");
        let trip2 = l.raise(Millis(40), "trip", AlarmKind::FilterTrip, "x");
        assert_eq!(first(&l), vec![trip, trip2]);
        assert!(l.get(task).is_some_and(|a| !a.first_out));
    }

    #[test]
    fn kpis_count_rates_floods_chattering_and_sources() {
        let mut l = AlarmList::new();
        assert_eq!(l.kpis(Millis(0)).total, 0);
        // 12 hazards in the first 10 minutes (a flood), each on its own item.
        for k in 0..12u64 {
            l.raise(
                Millis(k * 1000),
                &format!("hazard:{k}:Collision"),
                AlarmKind::Hazard,
                "h",
            );
        }
        // One task alarm later, three times within a minute (chattering).
        for t in [700_000, 720_000, 750_000] {
            l.raise(Millis(t), "task:entry:T002", AlarmKind::Task, "t");
            l.clear(Millis(t + 1), "task:entry:T002");
        }
        let k = l.kpis(Millis(1_290_000));
        assert_eq!(k.total, 15);
        assert_eq!(k.intervals, 3);
        assert_eq!(k.peak_per_10_min, 12);
        assert_eq!(k.flood_intervals, 1);
        assert_eq!(k.last_10_min, 3);
        assert!(!k.flooding);
        assert!((k.average_per_10_min - 15.0 / (1_290_000.0 / 600_000.0)).abs() < 1e-9);
        assert_eq!(
            k.chattering,
            vec![
                "hazard:Collision".to_string(),
                "task:entry:T002".to_string()
            ]
        );
        assert_eq!(
            k.most_frequent,
            vec![
                ("hazard:Collision".to_string(), 12),
                ("task:entry:T002".to_string(), 3)
            ]
        );
        assert!(l.kpis(Millis(11_000)).flooding);
        assert_eq!(source_of("hazard:9:Collision"), "hazard:Collision");
        assert_eq!(source_of("trip:CSs10"), "trip:CSs10");
    }

    #[test]
    fn the_history_filters_by_text_kind_and_priority_and_exports_csv() {
        let mut l = AlarmList::new();
        let a = l.raise(
            Millis(10),
            "trip:CSs10",
            AlarmKind::FilterTrip,
            AlarmText {
                message: "Safety stop: box leaving".into(),
                detail: "CSs10 = C7 . /A4".into(),
                ..AlarmText::default()
            },
        );
        l.raise(Millis(20), "task:x:T002", AlarmKind::Task, "Box \"late\"");
        l.acknowledge(Millis(30), a, "checked, ok").unwrap();
        let all = HistoryFilter::default();
        assert_eq!(l.history(&all).len(), 2);
        let by_text = HistoryFilter {
            text: " c7 ".into(),
            ..HistoryFilter::default()
        };
        assert_eq!(
            l.history(&by_text).iter().map(|x| x.id).collect::<Vec<_>>(),
            [a]
        );
        let by_kind = HistoryFilter {
            kind: Some(AlarmKind::Task),
            ..HistoryFilter::default()
        };
        assert_eq!(l.history(&by_kind).len(), 1);
        let by_priority = HistoryFilter {
            priority: Some(AlarmPriority::Urgent),
            ..HistoryFilter::default()
        };
        assert_eq!(l.history(&by_priority)[0].id, a);
        let csv = AlarmList::history_csv(&l.history(&all));
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].starts_with("id,raised_ms,priority,kind,state"));
        assert!(lines[1].contains("\"Box \"\"late\"\"\""), "{csv}");
        assert!(
            lines[2].starts_with("\"1\",\"10\",\"P1\",\"safety filter trip\",\"acknowledged\""),
            "{csv}"
        );
        assert!(lines[2].contains("\"checked, ok\""));
    }
}
