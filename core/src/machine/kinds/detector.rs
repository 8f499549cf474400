//! A detector: a plant input that turns on when a condition over the plant's signals has
//! held for `on_delay_ms`, and off when it has not held for `off_delay_ms`. It covers a
//! device with its own small logic and no geometry: a protection relay or a smart
//! sensor with pre-confirmation (seed 002's feeder sensor: a fault current present,
//! breaker closed, for 100 ms), a current transformer (no delay), a debounced contact,
//! a thermal overload relay.
//!
//! The condition may read any plant signal: outputs as applied, inputs as last read
//! (including an environment input no component drives, that a scenario's fault sets:
//! the perturbation on a line).

use super::StepCtx;
use crate::diag::{Problem, codes};
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::machine::scene::{SceneElement, Shape};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};

/// A detector's parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorDef {
    /// The plant input it writes.
    pub signal: String,
    /// The condition, over any plant signal.
    pub when: String,
    /// How long the condition must hold before the input turns on, ms.
    #[serde(default)]
    pub on_delay_ms: u64,
    /// How long the condition must be gone before it turns off, ms.
    #[serde(default)]
    pub off_delay_ms: u64,
}

impl DetectorDef {
    pub(super) fn check(&self) -> Vec<String> {
        if self.on_delay_ms > 3_600_000 || self.off_delay_ms > 3_600_000 {
            vec![format!(
                "detector `{}`: delays of at most one hour",
                self.signal
            )]
        } else {
            Vec::new()
        }
    }

    pub(super) fn signals(&self) -> Vec<(&str, Space)> {
        vec![(self.signal.as_str(), Space::Input)]
    }

    pub(super) fn expressions(&self) -> Vec<&str> {
        vec![self.when.as_str()]
    }
}

/// A detector's live state.
#[derive(Clone, Debug)]
pub struct Detector {
    signal: String,
    input: usize,
    when: Dnf,
    on_delay: u64,
    off_delay: u64,
    /// How long the condition has held, or been gone, ms.
    held: u64,
    gone: u64,
    cond: bool,
    on: bool,
}

impl Detector {
    pub(super) fn new(id: &str, def: &DetectorDef, symbols: &Symbols) -> Result<Self, Problem> {
        let Some((Space::Input, i)) = symbols.lookup(&def.signal) else {
            return Err(Problem::error(
                codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                format!("`{id}` names detector `{}`, not a plant input", def.signal),
                None,
            ));
        };
        let when = parse_str(&def.when)
            .and_then(|e| e.to_dnf(symbols))
            .map_err(|e| {
                Problem::error(
                    codes::COMPONENTS_EXPRESSION.id,
                    format!("`{id}`: detector `{}`: {}", def.when, e.message),
                    None,
                )
            })?;
        Ok(Self {
            signal: def.signal.clone(),
            input: i as usize,
            when: simplify(&when),
            on_delay: def.on_delay_ms,
            off_delay: def.off_delay_ms,
            held: 0,
            gone: 0,
            cond: false,
            on: false,
        })
    }

    pub(super) fn step(&mut self, ctx: &StepCtx<'_>) {
        self.cond = eval_dnf(&self.when, ctx.frame);
        if self.cond {
            self.gone = 0;
            self.held = self.held.saturating_add(ctx.dt);
            if self.held >= self.on_delay {
                self.on = true;
            }
        } else {
            self.held = 0;
            self.gone = self.gone.saturating_add(ctx.dt);
            if self.gone >= self.off_delay {
                self.on = false;
            }
        }
    }

    /// Settled: the input says what the condition says.
    pub(super) fn idle(&self) -> bool {
        self.cond == self.on
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        sensors.set(self.input, self.on);
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Device {
                signals: vec![self.signal.clone()],
            },
        }
    }
}
