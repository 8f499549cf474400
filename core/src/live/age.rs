//! Data age (seed 002's refreshment and promptness, asynchronous variant): every value
//! carries the time it was read, and a value older than its bound is stale. Also the
//! link watchdog and the reconnection backoff, as pure functions of [`Millis`].

use crate::bits::Bits;
use crate::time::Millis;

/// True when a value read at `read_at` (never, for `None`) is older than `max_age` at
/// `now`. A value exactly `max_age` old is still fresh.
pub fn is_stale(read_at: Option<Millis>, now: Millis, max_age: Millis) -> bool {
    match read_at {
        None => true,
        Some(t) => now.saturating_sub(t) > max_age,
    }
}

/// Values with the time each was last read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AgedBits {
    values: Bits,
    read_at: Vec<Option<Millis>>,
}

impl AgedBits {
    /// `len` values, all 0 and never read (stale).
    pub fn new(len: usize) -> Self {
        Self {
            values: Bits::zeros(len),
            read_at: vec![None; len],
        }
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        self.read_at.len()
    }

    /// True when there is no value.
    pub fn is_empty(&self) -> bool {
        self.read_at.is_empty()
    }

    /// Records value `i` read at `at`.
    pub fn set(&mut self, i: usize, value: bool, at: Millis) {
        if let Some(slot) = self.read_at.get_mut(i) {
            *slot = Some(at);
            self.values.set(i, value);
        }
    }

    /// The last values read (held values for the stale ones).
    pub fn values(&self) -> &Bits {
        &self.values
    }

    /// When value `i` was last read.
    pub fn read_at(&self, i: usize) -> Option<Millis> {
        self.read_at.get(i).copied().flatten()
    }

    /// Age of value `i` at `now`, `None` if never read.
    pub fn age(&self, i: usize, now: Millis) -> Option<Millis> {
        self.read_at(i).map(|t| now.saturating_sub(t))
    }

    /// The stale values at `now`, bit `i` set when value `i` is older than `bounds[i]`
    /// (a missing bound counts as zero).
    pub fn stale(&self, now: Millis, bounds: &[Millis]) -> Bits {
        let mut out = Bits::zeros(self.len());
        for (i, &t) in self.read_at.iter().enumerate() {
            let bound = bounds.get(i).copied().unwrap_or(Millis::ZERO);
            out.set(i, is_stale(t, now, bound));
        }
        out
    }

    /// Forgets every read time (everything stale, values held).
    pub fn invalidate(&mut self) {
        self.read_at.iter_mut().for_each(|t| *t = None);
    }
}

/// A change of a [`Watchdog`]'s state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transition {
    /// Nothing was heard for longer than the timeout.
    Lost {
        /// When the peer was last heard, `None` if never.
        last_heard: Option<Millis>,
    },
    /// The peer is heard again.
    Restored,
}

/// Declares a peer lost when nothing was heard from it for longer than `timeout`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Watchdog {
    timeout: Millis,
    last_heard: Option<Millis>,
    started: Millis,
    lost: bool,
}

impl Watchdog {
    /// A watchdog started at `now`: a peer never heard is lost `timeout` after it.
    pub fn new(timeout: Millis, now: Millis) -> Self {
        Self {
            timeout,
            last_heard: None,
            started: now,
            lost: false,
        }
    }

    /// The peer was heard at `now`; returns [`Transition::Restored`] if it was lost.
    pub fn heard(&mut self, now: Millis) -> Option<Transition> {
        self.last_heard = Some(now);
        if self.lost {
            self.lost = false;
            Some(Transition::Restored)
        } else {
            None
        }
    }

    /// Checks at `now`; returns [`Transition::Lost`] once when the timeout passes.
    pub fn check(&mut self, now: Millis) -> Option<Transition> {
        let since = self.last_heard.unwrap_or(self.started);
        if !self.lost && now.saturating_sub(since) > self.timeout {
            self.lost = true;
            return Some(Transition::Lost {
                last_heard: self.last_heard,
            });
        }
        None
    }

    /// Checks at `now`, telling a late peer from a lost one. `seen` is when the I/O
    /// side last ran (the runtime's heartbeat): a silence is measured up to there, so a
    /// runtime delayed by a loaded machine does not blame the peer for it. `failed`
    /// says whether a request failed (or the link is down) since the peer was last
    /// heard; while none did, an answer may still come and the peer gets `grace` more.
    /// Whatever the I/O side, a silence longer than `hard` on the cycle's own clock is
    /// a loss. Returns [`Transition::Lost`] once, as [`Watchdog::check`].
    pub fn check_seen(
        &mut self,
        now: Millis,
        seen: Millis,
        failed: bool,
        grace: Millis,
        hard: Millis,
    ) -> Option<Transition> {
        let since = self.last_heard.unwrap_or(self.started);
        let allowed = if failed {
            self.timeout
        } else {
            self.timeout + grace
        };
        let silent =
            seen.saturating_sub(since) > allowed || now.saturating_sub(since) > hard.max(allowed);
        if !self.lost && silent {
            self.lost = true;
            return Some(Transition::Lost {
                last_heard: self.last_heard,
            });
        }
        None
    }

    /// True while the peer is lost.
    pub fn is_lost(&self) -> bool {
        self.lost
    }

    /// When the peer was last heard.
    pub fn last_heard(&self) -> Option<Millis> {
        self.last_heard
    }
}

/// Exponential reconnection backoff: `initial`, doubled after each failure up to `max`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Backoff {
    initial: Millis,
    max: Millis,
    next: Millis,
}

impl Backoff {
    /// A backoff from `initial` to `max`.
    pub fn new(initial: Millis, max: Millis) -> Self {
        Self {
            initial,
            max: max.max(initial),
            next: initial,
        }
    }

    /// The delay before the next attempt; doubles the one after.
    pub fn failed(&mut self) -> Millis {
        let delay = self.next;
        self.next = Millis(self.next.0.saturating_mul(2)).min(self.max);
        delay
    }

    /// After a success: the next failure waits `initial` again.
    pub fn reset(&mut self) {
        self.next = self.initial;
    }
}
