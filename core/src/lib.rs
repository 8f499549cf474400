//! Vigie's core: everything that keeps a PLC-controlled machine safe and understandable,
//! with no user interface and no wall clock.
//!
//! - [`plant`]: the I/O model (sensors C0..C10, actuators A0..A6 for the sorting station).
//! - [`expr`], [`symbols`]: the logic notation of the paper and its name table.
//! - [`constraints`]: safety constraints, classification and static checks.
//! - [`plausibility`]: timed plausibility of the sensors' edges (the first stage).
//! - [`observers`]: sequential rebuilders of unobservable state (P36, P67, 2P).
//! - [`filter`]: constraint evaluation and the fallback with priority to zero.
//! - [`engine`]: one PLC cycle, one function; [`history`]: the recorder.
//! - [`trace`]: the per-cycle CSV trace format.
//! - [`emulator`]: the deterministic plant emulator of the sorting station.
//! - [`live`]: the pure half of the Modbus live link (I/O map, data age, stale inputs).
//!
//! See `ARCHITECTURE.md` at the repository root for the data flow and the invariants.

pub mod access;
pub mod alarms;
pub mod bits;
pub mod bundle;
pub mod campaign;
pub mod constraints;
pub mod control;
pub mod diag;
pub mod dtree;
pub mod emulator;
pub mod engine;
pub mod explain;
pub mod export;
pub mod expr;
pub mod fieldbus;
pub mod filter;
pub mod frame;
pub mod history;
pub mod live;
pub mod machine;
pub mod observers;
pub mod plant;
pub mod plausibility;
pub mod plcopen;
pub mod pop;
pub mod sim;
pub mod stpn;
pub mod swa;
pub mod symbols;
pub mod synthetic;
pub mod tasks;
pub mod time;
pub mod trace;
pub mod verify;

#[cfg(test)]
mod test_support;

pub use bits::Bits;
pub use time::Millis;
