//! A push button of the operator's panel wired to a plant input: the operator's press
//! holds the input ON for `pulse_ms` (a human press lasts a few hundred ms), then it
//! springs back. The console's Start, and a scenario's `Press`, press it when the
//! program names it as its start or stop.

use super::StepCtx;
use crate::diag::{Problem, codes};
use crate::machine::scene::{SceneElement, Shape};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};

/// A button's parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ButtonDef {
    /// The plant input it closes.
    pub signal: String,
    /// How long a press holds it, ms.
    #[serde(default = "press_ms")]
    pub pulse_ms: u64,
}

fn press_ms() -> u64 {
    300
}

impl ButtonDef {
    pub(super) fn check(&self) -> Vec<String> {
        if (1..=60_000).contains(&self.pulse_ms) {
            Vec::new()
        } else {
            vec![format!(
                "button `{}` has pulse_ms {}: from 1 to 60000",
                self.signal, self.pulse_ms
            )]
        }
    }

    pub(super) fn signals(&self) -> Vec<(&str, Space)> {
        vec![(self.signal.as_str(), Space::Input)]
    }
}

/// A button's live state.
#[derive(Clone, Debug)]
pub struct Button {
    signal: String,
    input: usize,
    pulse_ms: u64,
    remaining_ms: u64,
}

impl Button {
    pub(super) fn new(id: &str, def: &ButtonDef, symbols: &Symbols) -> Result<Self, Problem> {
        let Some((Space::Input, i)) = symbols.lookup(&def.signal) else {
            return Err(Problem::error(
                codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                format!("`{id}` names button `{}`, not a plant input", def.signal),
                None,
            ));
        };
        Ok(Self {
            signal: def.signal.clone(),
            input: i as usize,
            pulse_ms: def.pulse_ms,
            remaining_ms: 0,
        })
    }

    pub(super) fn step(&mut self, ctx: &StepCtx<'_>) {
        self.remaining_ms = self.remaining_ms.saturating_sub(ctx.dt);
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        sensors.set(self.input, self.remaining_ms > 0);
    }

    pub(super) fn pressed(&self) -> bool {
        self.remaining_ms > 0
    }

    /// Presses it when it closes `signal`; false otherwise.
    pub(super) fn press(&mut self, signal: &str) -> bool {
        if signal == self.signal {
            self.remaining_ms = self.pulse_ms;
            true
        } else {
            false
        }
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Button {
                signal: self.signal.clone(),
                pressed: self.pressed(),
            },
        }
    }
}
