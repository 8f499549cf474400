//! A fieldbus variable: a consumer's copy of a signal, refreshed at the bus's poll
//! instants (seed 002: FIP's producer/consumer buffers, overwritten by each write and
//! not consumed by reads, so the consumer sees the value as it was at the last poll).
//! The copy is a plant input (the other cell's image: `DefDep(D1)` as D2 reads it);
//! the source may be any plant signal. Polls are at `phase_ms + k · period_ms`; a change
//! that comes and goes between two polls (a zero-length spike) is never transmitted.
//! `Slowed(link, percent)` stretches the period (a bus configured with half the rate at
//! 50 %), `Blocked(link)` freezes the copy (a lost producer).

use super::{ComponentFaults, StepCtx};
use crate::diag::{Problem, codes};
use crate::machine::scene::{SceneElement, Shape};
use crate::symbols::{Space, Symbols, Var};
use serde::{Deserialize, Serialize};

/// A link's parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkDef {
    /// The signal produced (any plant signal).
    pub from: String,
    /// The plant input the consumer reads.
    pub to: String,
    /// The bus period for this variable, ms.
    pub period_ms: u64,
    /// The first poll, ms.
    #[serde(default)]
    pub phase_ms: u64,
}

impl LinkDef {
    pub(super) fn check(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(1..=3_600_000).contains(&self.period_ms) {
            out.push(format!(
                "link `{}` -> `{}`: period_ms {} is not from 1 ms to one hour",
                self.from, self.to, self.period_ms
            ));
        }
        if self.phase_ms >= self.period_ms.max(1) {
            out.push(format!(
                "link `{}` -> `{}`: phase_ms {} must be under the period",
                self.from, self.to, self.phase_ms
            ));
        }
        out
    }

    pub(super) fn signals(&self) -> Vec<(&str, Space)> {
        vec![(self.to.as_str(), Space::Input)]
    }

    pub(super) fn expressions(&self) -> Vec<&str> {
        vec![self.from.as_str()]
    }
}

/// A link's live state.
#[derive(Clone, Debug)]
pub struct Link {
    from: String,
    to: String,
    source: Var,
    input: usize,
    period: u64,
    /// Time of the next poll, ms.
    next: u64,
    value: bool,
    /// The source as the last step saw it.
    last: bool,
}

impl Link {
    pub(super) fn new(id: &str, def: &LinkDef, symbols: &Symbols) -> Result<Self, Problem> {
        let unknown = |what: &str, s: &str| {
            Problem::error(
                codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                format!("`{id}`: link {what} `{s}` is not a plant signal of the right kind"),
                None,
            )
        };
        let source = match symbols.lookup(&def.from) {
            Some((space @ (Space::Input | Space::Output), i)) => Var {
                space,
                index: i,
                prev: false,
            },
            _ => return Err(unknown("source", &def.from)),
        };
        let Some((Space::Input, input)) = symbols.lookup(&def.to) else {
            return Err(unknown("copy", &def.to));
        };
        Ok(Self {
            from: def.from.clone(),
            to: def.to.clone(),
            source,
            input: input as usize,
            period: def.period_ms.max(1),
            next: def.phase_ms,
            value: false,
            last: false,
        })
    }

    pub(super) fn step(&mut self, ctx: &StepCtx<'_>, faults: ComponentFaults) {
        self.last = ctx.frame.get(self.source);
        if faults.blocked {
            return;
        }
        let period = self.period * 100 / u64::from(faults.speed_percent.max(1));
        while ctx.now >= self.next {
            self.value = self.last;
            self.next += period.max(1);
        }
    }

    /// Settled: the copy says what the source says (a poll would change nothing).
    pub(super) fn idle(&self) -> bool {
        self.value == self.last
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        sensors.set(self.input, self.value);
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Device {
                signals: vec![self.from.clone(), self.to.clone()],
            },
        }
    }
}
