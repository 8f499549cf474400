//! Alarm management after ISA-18.2: each alarm is unacknowledged while new, acknowledged
//! by the operator (with an optional note), and cleared when its condition returns to
//! normal; an alarm cleared before it is acknowledged stays in the list as
//! *cleared-unacknowledged* until it is. Alarms can be shelved for a limited time. The
//! first alarm of a burst (raised while no other unacknowledged alarm is active) is
//! marked *first-out*.

use crate::time::Millis;
use serde::Serialize;

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
    /// Text shown to the operator.
    pub message: String,
    /// When it was raised.
    pub raised: Millis,
    /// Acknowledgement time and note.
    pub acknowledged: Option<(Millis, String)>,
    /// When the condition returned to normal.
    pub cleared: Option<Millis>,
    /// Hidden until this time.
    pub shelved_until: Option<Millis>,
    /// First alarm of its burst.
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
        self.shelved_until.is_some_and(|t| now < t)
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
    pub fn raise(&mut self, now: Millis, key: &str, kind: AlarmKind, message: String) -> u64 {
        if let Some(a) = self
            .alarms
            .iter()
            .find(|a| a.key == key && a.cleared.is_none())
        {
            return a.id;
        }
        let first_out = !self
            .alarms
            .iter()
            .any(|a| a.state() == AlarmState::Unacknowledged);
        self.next_id += 1;
        self.alarms.push(Alarm {
            id: self.next_id,
            key: key.to_string(),
            kind,
            message,
            raised: now,
            acknowledged: None,
            cleared: None,
            shelved_until: None,
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

    /// Hides an alarm for `duration`.
    pub fn shelve(&mut self, now: Millis, id: u64, duration: Millis) -> Result<(), AlarmError> {
        if duration.0 == 0 {
            return Err(AlarmError::EmptyShelving);
        }
        let a = self
            .alarms
            .iter_mut()
            .find(|a| a.id == id)
            .ok_or(AlarmError::Unknown(id))?;
        a.shelved_until = Some(now + duration);
        Ok(())
    }

    /// Shows a shelved alarm again.
    pub fn unshelve(&mut self, id: u64) -> Result<(), AlarmError> {
        let a = self
            .alarms
            .iter_mut()
            .find(|a| a.id == id)
            .ok_or(AlarmError::Unknown(id))?;
        a.shelved_until = None;
        Ok(())
    }

    /// Alarms to show at `now`: not back to normal, not shelved; newest first.
    pub fn visible(&self, now: Millis) -> Vec<&Alarm> {
        let mut v: Vec<&Alarm> = self
            .alarms
            .iter()
            .filter(|a| a.state() != AlarmState::Normal && !a.is_shelved(now))
            .collect();
        v.reverse();
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
        let a = l.raise(
            Millis(10),
            "trip:CSs10",
            AlarmKind::FilterTrip,
            "CSs10".into(),
        );
        assert_eq!(l.get(a).map(Alarm::state), Some(AlarmState::Unacknowledged));
        assert!(l.get(a).is_some_and(|x| x.first_out));
        // Same condition again: no duplicate.
        assert_eq!(
            l.raise(Millis(20), "trip:CSs10", AlarmKind::FilterTrip, "x".into()),
            a
        );
        let b = l.raise(Millis(30), "link:plant", AlarmKind::Link, "link".into());
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
        // A new burst after everything is acknowledged starts a new first-out.
        let c = l.raise(Millis(70), "diag:C4", AlarmKind::Diagnosis, "C4".into());
        assert!(l.get(c).is_some_and(|x| x.first_out));
        assert_eq!(l.all().len(), 3, "nothing is ever removed");
    }

    #[test]
    fn shelving_is_time_limited() {
        let mut l = AlarmList::new();
        let a = l.raise(Millis(0), "k", AlarmKind::Hazard, "m".into());
        assert_eq!(
            l.shelve(Millis(0), a, Millis(0)),
            Err(AlarmError::EmptyShelving)
        );
        l.shelve(Millis(100), a, Millis(1000)).unwrap();
        assert!(l.visible(Millis(500)).is_empty());
        assert_eq!(l.shelved(Millis(500)).len(), 1);
        assert_eq!(l.visible(Millis(1100)).len(), 1, "shelving expired");
        l.shelve(Millis(1100), a, Millis(1000)).unwrap();
        l.unshelve(a).unwrap();
        assert_eq!(l.visible(Millis(1200)).len(), 1);
        assert_eq!(l.unshelve(99), Err(AlarmError::Unknown(99)));
    }
}
