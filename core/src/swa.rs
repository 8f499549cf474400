//! Stopwatch automata and the offline synthesis of monitoring regions (seed 000,
//! Allahham 2008, chapters 2 and 4).
//!
//! - [`poly`]: convex polyhedra with general linear constraints in exact rationals.
//! - [`linear`]: constraints as text (`0 <= x - y < 2000 && y <= 10000`).
//! - [`automaton`]: stopwatch automata as data and their synchronous product.
//! - [`synth`]: the region operators and `E* = E ∩ ⋂ Pre*(D_c)`.
//! - [`from_tasks`]: the automata of a `tasks.ron`.
//! - [`swpn`]: stopwatch Petri nets (chapter 5), translated into an automaton.
//! - [`regions`]: the synthesised regions as a file (`vigie synthesize`) and the monitor
//!   that runs them.
//! - [`sfc`]: the region monitor as an IEC 61131-3 program (SFC in PLCopen XML, and an
//!   ST function block).

pub mod automaton;
pub mod from_tasks;
pub mod linear;
pub mod lp;
pub mod poly;
pub mod rat;
pub mod regions;
pub mod sfc;
pub mod swpn;
pub mod synth;

pub use automaton::{Swa, SwaFile};
pub use poly::{Poly, Q};
pub use synth::{Limits, Synthesis, synthesize};

#[cfg(test)]
mod tests;
