//! The turntable cell's geometry and what the emulators share: the layout of a cell
//! (derived from placed components, or a legacy `layout.ron` read as components), the
//! fault injection, the public views of items and hazards, and the training library.
//!
//! The station's first emulator lived here, a deterministic engine of its one layout
//! (conveyors and a roller turntable as 1-D axes joined at their ends). Every plant now
//! runs on the components emulator (`machine::emulator`), which gives the figures the
//! first one gave, frozen in `machine/items/first-emulator.ron`.
//!
//! # Geometry of the sorting station, and why (seed 004, section 6)
//!
//! Boxes are 300 mm (small, 200 mm high) and 380 mm (large, 320 mm high) square; the
//! high beam is at 250 mm. All surfaces run at 300 mm/s (0.3 mm/ms).
//!
//! - Entry conveyor A0, x 0→1200 at y = 0; C0 at 1180 mm: a box front reaches C0 67 ms
//!   (more than two 10 ms PLC cycles) before the joint, so CSc1 stops A0 in time.
//! - Intermediate conveyor A1, x 1200→2400; C1 (low) and C2 (high) at 100 mm,
//!   so C0–C1 = 120 mm < 300 mm (observer 2P); C3 at 1180 mm (CSs2, CSc2 act 67 ms
//!   before the joint).
//! - Turntable centred at (2650, 0), u ∈ [−250, 250]; at 0° its −u end meets A1's end
//!   and +u points at nothing; at 90° +u meets the left exit A5 (y 250→1600) and −u the
//!   right exit A6 (y −250→−1600). C6 is on the table at u = +150: a box stops with its
//!   front there, fully on the table (large: rear at u = −230).
//! - C7 (right) and C8 (left) at 20 mm along their exits; C9 and C10 at 1330 mm.
//!   [C3, C6] = 420 mm and [C6, C7] = 420 mm exceed the largest box (observers P36, P67);
//!   [C6, C8] = 120 mm is shorter than the smallest box. When C7/C8 falls the box rear
//!   is 20 mm past the table edge.
//! - Rotation: 30 mdeg/ms out, 29.7 mdeg/ms back (±0.3 % per rotation); C4 = angle ≤ 3.6°,
//!   C5 = angle ≥ 87.75°. After A4 rises, C4 falls at ~120 ms and C5 rises at ~2925 ms;
//!   after A4 falls, C5 falls at ~76 ms and C4 rises at ~2909 ms (intervals I2, I4, I7, I9).
//! - Hazard margins: a box is pushed against a stopped surface when it lies more than
//!   25 mm on each (so a box whose rear just left C0 or C3 is not), and is sheared when
//!   it passes the table edge by more than 2 mm while the table turns.

pub(crate) mod faults;
mod layout;
mod model;
mod training;

pub use faults::{FaultKind, FaultSpec, Position, Trigger};
pub(crate) use layout::quoted_positions;
pub use layout::{
    ArrivalPlan, Beam, BoxDims, BoxSize, Conveyor, Elevator, Layout, Point, SensorDef, SensorKind,
    Side, SizeMix, Source, Turntable,
};
pub use model::{BoxState, BoxStats, BoxView, Hazard, HazardKind, Place};
pub use training::{NamedFault, PlantExercise, load_exercises, load_faults};
