//! Synthetic plants generated from a seed, for benchmarks at scale.
//!
//! The shape follows the sorting station: mostly simple constraints (one output at t
//! and two or three context literals), a few combined ones (two outputs), some with a
//! previous-output literal (edges).

use crate::constraints::ConstraintSet;
use crate::plant::{Plant, Signal, SignalKind};
use crate::symbols::Symbols;
use std::fmt::Write as _;
use std::path::Path;

/// A small deterministic generator (SplitMix64), so that the core needs no RNG crate.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Seeds the generator.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (n > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }

    /// True with probability `num/den`.
    pub fn chance(&mut self, num: u64, den: u64) -> bool {
        self.below(den) < num
    }
}

/// A generated plant and its constraint text.
pub struct Synthetic {
    /// The plant.
    pub plant: Plant,
    /// Its symbols.
    pub symbols: Symbols,
    /// The constraints.
    pub constraints: ConstraintSet,
    /// The constraint file text.
    pub text: String,
}

/// Generates a plant with `signals` signals (half sensors, half actuators) and
/// `constraints` constraints from `seed`. The constraint set satisfies property (6) and
/// always has a fallback, by construction: one output in ten is *monostable* (like A4)
/// and is constrained only with edges, `RE(A)` forcing it to stay 0 and `FE(A)` forcing
/// it to stay 1 (the paper's sufficient condition); the others are only ever forced to 0;
/// combined constraints `A_k . /A_m` take a non-monostable `A_k`, so `A_k = 0` always
/// satisfies them.
pub fn generate(signals: usize, constraints: usize, seed: u64) -> Synthetic {
    let mut rng = SplitMix64::new(seed);
    let n_in = signals / 2;
    let n_out = signals - n_in;
    let inputs = (0..n_in)
        .map(|i| Signal::new(format!("C{i}"), SignalKind::Sensor, String::new()))
        .collect();
    let outputs = (0..n_out)
        .map(|k| Signal::new(format!("A{k}"), SignalKind::Actuator, String::new()))
        .collect();
    let plant = Plant::new("synthetic", inputs, outputs);
    let symbols = plant.symbols();
    let mut text = String::new();
    for c in 0..constraints {
        let n_ctx = 2 + rng.below(2);
        let mut lits: Vec<String> = (0..n_ctx)
            .map(|_| {
                let i = rng.below(n_in as u64);
                if rng.chance(1, 2) {
                    format!("C{i}")
                } else {
                    format!("/C{i}")
                }
            })
            .collect();
        let k = rng.below(n_out as u64);
        let monostable = |k: u64| k.is_multiple_of(10);
        if monostable(k) {
            lits.push(if rng.chance(1, 2) {
                format!("RE(A{k})")
            } else {
                format!("FE(A{k})")
            });
            let _ = writeln!(text, "CSs{c} = {}", lits.join(" . "));
        } else if rng.chance(1, 10) {
            // Combined: A_k . /A_m (pushing a box onto a stopped conveyor).
            let m = (k + 1 + rng.below(n_out as u64 - 1)) % n_out as u64;
            lits.push(format!("A{k}"));
            lits.push(format!("/A{m}"));
            let _ = writeln!(text, "CSc{c} = {}", lits.join(" . "));
        } else {
            lits.push(format!("A{k}"));
            let _ = writeln!(text, "CSs{c} = {}", lits.join(" . "));
        }
    }
    let (set, _problems) = ConstraintSet::parse(&text, Path::new("synthetic.txt"), &symbols);
    Synthetic {
        plant,
        symbols,
        constraints: set,
        text,
    }
}
