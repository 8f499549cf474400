//! The filter's conservative treatment of stale inputs.
//!
//! ## Rule
//! A stale input may have any value. A literal on it (at t or t-1, either polarity) must
//! be assumed to be whichever value makes its constraint true: the constraint is
//! *potentially violated* when some value of the stale inputs makes it true. For a
//! constraint in sum-of-products form this is exact and cheap: existential
//! quantification of a variable in a DNF drops its literals from every term
//! (`∃x. x·T1 + /x·T2 + T3 = T1 + T2 + T3`). So the guard evaluates the constraint set
//! with every literal on a stale variable removed.
//!
//! Observers are rebuilt from inputs, so an observer is stale when any input its rule
//! names is (transitively through other observers); its literals are dropped too.
//! Outputs are never stale: outputs at t are what the filter decides, outputs at t-1
//! are what it applied. Auxiliary variables are left as computed.
//!
//! The fallback of the quantified set (the filter's minimum-ones vector) makes every
//! original constraint false *for every value of the stale inputs*; when no such
//! vector exists the result is the specification error, and the caller drives every
//! output to 0 as the engine does.

use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::constraints::ConstraintSet;
use crate::filter::{Filter, SpecError};
use crate::frame::Frame;
use crate::observers::Observers;
use crate::symbols::{Space, Symbols};

/// The inputs each observer reads, directly or through other observers.
pub fn observer_inputs(observers: &Observers, symbols: &Symbols) -> Vec<Bits> {
    let n_in = symbols.len(Space::Input);
    let n_obs = observers.defs.len();
    let mut inputs = vec![Bits::zeros(n_in); n_obs];
    let mut uses = vec![Vec::new(); n_obs];
    for (o, def) in observers.defs.iter().enumerate() {
        for text in def.rule.expressions() {
            for name in identifiers(text) {
                match symbols.lookup(name) {
                    Some((Space::Input, i)) => {
                        if let Some(bits) = inputs.get_mut(o) {
                            bits.set(i as usize, true);
                        }
                    }
                    Some((Space::Observer, j)) => {
                        if let Some(u) = uses.get_mut(o) {
                            u.push(j as usize);
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    // Transitive closure: at most n_obs rounds.
    for _ in 0..n_obs {
        let mut changed = false;
        for o in 0..n_obs {
            let mut merged = inputs.get(o).cloned().unwrap_or_default();
            for &j in uses.get(o).map_or(&[][..], Vec::as_slice) {
                for i in inputs
                    .get(j)
                    .map(|b| b.ones().collect::<Vec<_>>())
                    .unwrap_or_default()
                {
                    if !merged.get(i) {
                        merged.set(i, true);
                        changed = true;
                    }
                }
            }
            if let Some(slot) = inputs.get_mut(o) {
                *slot = merged;
            }
        }
        if !changed {
            break;
        }
    }
    inputs
}

/// Names in an expression: runs of letters, digits and `_` starting with a letter.
fn identifiers(text: &str) -> impl Iterator<Item = &str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| w.starts_with(|c: char| c.is_ascii_alphabetic()))
}

/// The stale variables of one cycle.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Stale {
    /// Stale inputs.
    pub inputs: Bits,
    /// Observers that read a stale input.
    pub observers: Bits,
}

impl Stale {
    /// True when nothing is stale.
    pub fn is_empty(&self) -> bool {
        self.inputs.count_ones() == 0 && self.observers.count_ones() == 0
    }
}

/// `set` with every literal on a stale variable removed (existential quantification).
pub fn quantify(set: &ConstraintSet, stale: &Stale) -> ConstraintSet {
    let mut out = set.clone();
    for c in &mut out.constraints {
        for term in &mut c.dnf {
            term.retain(|l| {
                let i = l.var.index as usize;
                match l.var.space {
                    Space::Input => !stale.inputs.get(i),
                    Space::Observer => !stale.observers.get(i),
                    Space::Output | Space::Aux => true,
                }
            });
        }
    }
    out
}

/// What the guard found in one cycle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Verdict {
    /// Ids of the constraints some value of the stale inputs makes true with the
    /// outputs of the frame, in file order.
    pub potentially_violated: Vec<String>,
    /// The outputs safe for every value of the stale inputs (only computed when some
    /// constraint is potentially violated).
    pub fallback: Option<Result<Bits, SpecError>>,
}

/// Evaluates the constraints with stale inputs quantified, caching the compiled filter
/// for the last set of stale variables (it changes rarely).
#[derive(Clone, Debug)]
pub struct StaleGuard {
    set: ConstraintSet,
    n_outputs: usize,
    deps: Vec<Bits>,
    safe: Vec<crate::plant::SafeValue>,
    cached: Option<(Stale, Filter)>,
}

impl StaleGuard {
    /// A guard for a loaded plant.
    pub fn new(bundle: &PlantBundle) -> Self {
        Self {
            set: bundle.constraints.clone(),
            n_outputs: bundle.plant.outputs.len(),
            safe: bundle.plant.outputs.iter().map(|s| s.safe).collect(),
            deps: observer_inputs(&bundle.observers, &bundle.symbols),
            cached: None,
        }
    }

    /// The stale variables for these stale inputs.
    pub fn stale(&self, stale_inputs: &Bits) -> Stale {
        let mut observers = Bits::zeros(self.deps.len());
        for (o, reads) in self.deps.iter().enumerate() {
            if reads.ones_fast().any(|i| stale_inputs.get(i)) {
                observers.set(o, true);
            }
        }
        Stale {
            inputs: stale_inputs.clone(),
            observers,
        }
    }

    fn filter_for(&mut self, stale_inputs: &Bits) -> Option<&Filter> {
        let stale = self.stale(stale_inputs);
        if self.cached.as_ref().is_none_or(|(s, _)| *s != stale) {
            let filter = Filter::new(&quantify(&self.set, &stale), self.n_outputs)
                .with_safe_values(self.safe.clone());
            self.cached = Some((stale, filter));
        }
        self.cached.as_ref().map(|(_, f)| f)
    }

    /// The safe outputs for the frame's context whatever the PLC commands (the outputs at
    /// t are ignored) and whatever the stale inputs are: the fallback of the quantified
    /// set. Used when the PLC is lost. On a specification error the caller applies
    /// [`StaleGuard::safe_vector`].
    pub fn safe_outputs(&mut self, frame: &Frame, stale_inputs: &Bits) -> Result<Bits, SpecError> {
        match self.filter_for(stale_inputs) {
            Some(f) => f.fallback(frame),
            None => Ok(Bits::zeros(self.n_outputs)),
        }
    }

    /// Every output at its safe value in the frame's context (`Hold` keeps the previous
    /// output): the outputs when no fallback exists.
    pub fn safe_vector(&self, frame: &Frame) -> Bits {
        crate::filter::safe_vector(&self.safe, frame)
    }

    /// Checks the frame's outputs at t against the quantified constraints. With no stale
    /// input the verdict is empty (the engine's own filter is exact then).
    pub fn check(&mut self, frame: &Frame, stale_inputs: &Bits) -> Verdict {
        if stale_inputs.count_ones() == 0 {
            return Verdict {
                potentially_violated: Vec::new(),
                fallback: None,
            };
        }
        let Some(filter) = self.filter_for(stale_inputs) else {
            return Verdict {
                potentially_violated: Vec::new(),
                fallback: None,
            };
        };
        let violated = filter.violations(frame);
        if violated.is_empty() {
            return Verdict {
                potentially_violated: Vec::new(),
                fallback: None,
            };
        }
        Verdict {
            potentially_violated: violated.iter().map(|&i| filter.id(i).to_string()).collect(),
            fallback: Some(filter.fallback(frame)),
        }
    }
}
