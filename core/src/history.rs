//! The recorder: a bounded ring of cycle records, kept continuously so that any trip can
//! be explained from what happened before it.

use crate::bits::Bits;
use crate::time::Millis;
use std::collections::VecDeque;

/// What one cycle looked like.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CycleRecord {
    /// End of the cycle.
    pub time: Millis,
    /// Inputs read at the start of the cycle.
    pub inputs: Bits,
    /// Outputs computed by the control program.
    pub commanded: Bits,
    /// Outputs sent to the plant after the filter.
    pub applied: Bits,
    /// Observers after their update.
    pub observers: Bits,
    /// Auxiliary variables (diagnoser flags, estimates, task outputs).
    pub aux: Bits,
    /// True while the filter's trip is latched.
    pub tripped: bool,
}

/// A bounded history of cycles, oldest first.
#[derive(Clone, Debug)]
pub struct History {
    capacity: usize,
    records: VecDeque<CycleRecord>,
    recycled: Option<CycleRecord>,
}

impl History {
    /// A history of at most `capacity` cycles.
    pub fn new(capacity: usize) -> Self {
        Self {
            capacity: capacity.max(1),
            records: VecDeque::with_capacity(capacity.clamp(1, 1 << 16)),
            recycled: None,
        }
    }

    /// Largest number of records kept.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Appends a record built by `fill`, dropping the oldest one when full. The record
    /// handed to `fill` may hold stale values from a recycled slot: `fill` sets every
    /// field.
    pub fn push_with(&mut self, fill: impl FnOnce(&mut CycleRecord)) {
        let mut rec = if self.records.len() >= self.capacity {
            self.records.pop_front()
        } else {
            self.recycled.take()
        }
        .unwrap_or_else(|| CycleRecord {
            time: Millis::ZERO,
            inputs: Bits::default(),
            commanded: Bits::default(),
            applied: Bits::default(),
            observers: Bits::default(),
            aux: Bits::default(),
            tripped: false,
        });
        fill(&mut rec);
        self.records.push_back(rec);
    }

    /// Number of records held.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Records, oldest first.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = &CycleRecord> + ExactSizeIterator {
        self.records.iter()
    }

    /// The most recent record.
    pub fn last(&self) -> Option<&CycleRecord> {
        self.records.back()
    }

    /// The most recent record, to amend (a live link records what it really applied).
    pub fn last_mut(&mut self) -> Option<&mut CycleRecord> {
        self.records.back_mut()
    }

    /// The record `back` cycles before the most recent one (0 = most recent).
    pub fn back(&self, back: usize) -> Option<&CycleRecord> {
        self.records
            .len()
            .checked_sub(back + 1)
            .and_then(|i| self.records.get(i))
    }

    /// The latest record at or before `time`.
    pub fn at(&self, time: Millis) -> Option<&CycleRecord> {
        let idx = self.records.partition_point(|r| r.time <= time);
        idx.checked_sub(1).and_then(|i| self.records.get(i))
    }

    /// Forgets everything.
    pub fn clear(&mut self) {
        self.records.clear();
    }
}
