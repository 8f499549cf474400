//! The control part ("partie commande"): GRAFCET/SFC charts and Ladder-like output
//! equations as data, run scan by scan like a PLC.
//!
//! - [`program`]: the program format (`layouts/<plant>/programs/*.ron`) and its
//!   compilation against a plant (names resolved in a program-local
//!   [`crate::symbols::Symbols`]: plant inputs and outputs, then steps, memories, timers
//!   and panel inputs in the Aux space).
//! - [`runtime`]: [`ProgramRuntime`], the scan-cycle runtime implementing
//!   [`crate::engine::Control`]; its doc states the scan semantics.
//! - [`library`]: single-place edits ([`Patch`]) and the library of erroneous variants
//!   of a reference program ([`ErrorLibrary`]).
//! - [`mutation`]: enumeration of single mutations for localisation campaigns.
//!
//! Problem codes: V0901–V0915 program compilation, V0920–V0921 error library (`diag::codes`).

pub mod library;
pub mod mutation;
mod packed;
pub mod program;
pub mod runtime;

pub use library::{Consequence, ErrorLibrary, Patch, Variant, differences};
pub use mutation::{Mutation, mutations};
pub use program::{
    Action, Chart, CompiledProgram, Counter, CounterKind, Delay, DelayKind, Origin, Program,
    Qualifier, SourcePlace, Step, Transition,
};
pub use runtime::{Driver, Evolution, ProgramRuntime, UnknownPanel};

#[cfg(test)]
mod tests;
