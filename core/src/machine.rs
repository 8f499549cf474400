//! The physical plant as data: components of a library of kinds, the plant emulator
//! built from them, and the elementary actions (seed 003, part II) derived from them
//! with their per-action monitor.
//!
//! - [`actions`]: elementary actions N = (initial state, command, final state, T, ΔT):
//!   the `actions.ron` file and its checks, the decomposition rules R1-R3, the timing
//!   feasibility check (T_D < ΔT_min, (II.4)) and the learning of T and ΔT (annex B).
//! - [`monitor`]: the per-action monitor (checks a-d of seed 003, III.1), with the
//!   localisation messages of its detections.
//! - [`diagnosers`]: the decentralized diagnosers' component models derived from the
//!   axes (`vigie diagnose derive`).
//! - [`safe_state`]: whether the outputs' safe values move a component into a hazard.

pub mod actions;
pub mod derive;
pub mod description;
pub mod diagnosers;
pub mod emulator;
pub mod items;
pub mod kinds;
pub mod monitor;
pub mod safe_state;
pub mod scene;
mod topview;

pub use crate::emulator::{Hazard, HazardKind, Place};
pub use description::{ComponentDef, Components, DangerDef, Placement};
pub use emulator::ComponentPlant;
pub use scene::{Scene, SceneElement, Shape};
pub mod physical;
pub use physical::{Description, Physical};
