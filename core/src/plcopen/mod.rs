//! PLCopen TC6 XML (v2.01) control programs: the PLC's own program, read into Vigie's
//! program model ([`Program`](crate::control::Program)) so that the emulator, the campaigns, training,
//! verification and the explanations run it as they run a `programs/*.ron` file, and
//! written back after an edit so that it returns to the PLC's tool (CODESYS, TwinCAT,
//! Beremiz, OpenPLC Editor).
//!
//! # What is read
//! - The POUs of type `program` that the configuration's tasks call, in task order (all
//!   of them in file order when the file has no configuration), with their interface
//!   and the configuration's global variables.
//! - `BOOL` variables, bound to the plant: by located address (`%IXa.b` is the plant
//!   input at discrete input 8a+b, `%QXa.b` the output at coil 8a+b, as OpenPLC maps
//!   them; `%MX` a memory), else by name (a plant signal's id, case-insensitive as IEC
//!   names are); an unbound input variable is an operator panel button, any other a
//!   memory. `R_TRIG` and `F_TRIG` instances.
//! - SFC bodies (steps, initial steps, transitions with ST, referenced or LD
//!   conditions, selection and simultaneous divergences and convergences, jumps, action
//!   blocks on Boolean variables with the qualifiers N, S, R, P, L, D, SD, DS, SL and the step time
//!   `S.T`), ST bodies (assignments, IF, function-block calls) and LD bodies (contacts,
//!   negated and edge contacts, coils, negated, set and reset coils).
//!
//! Everything else is refused with a problem naming the element and its line and
//! column in the file ([`crate::diag::codes::PLCOPEN_UNSUPPORTED`]); nothing is skipped.
//!
//! # Semantics
//! The runtime runs a [`Program`](crate::control::Program) one scan per cycle: SFC evolution, then the actions,
//! then the equations top-down (see [`crate::control::ProgramRuntime`]). The import
//! executes the ST and LD bodies symbolically, in task order, into one equation per
//! assigned variable, so that each variable ends every scan with the value the PLC would
//! give it: a variable read before it is written in the scan reads its previous value
//! (`x*`), an `IF` becomes the choice between the new and the old value, an `R_TRIG`
//! called on `x` reads `RE(x)` after its call. A variable written both by an SFC action
//! and by ST or LD must be written `x := x OR …` (a coil in parallel with the action), as
//! Vigie's equations OR their value with the actions'.

mod export;
mod ld;
mod read;
mod sfc;
mod st;

#[cfg(test)]
mod tests;

pub use export::export;
pub use read::import;

use std::path::Path;

/// True for a program file in PLCopen XML (by its extension, `.xml`).
pub fn is_plcopen(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// The namespace of PLCopen TC6 v2.01.
pub const NAMESPACE: &str = "http://www.plcopen.org/xml/tc6_0201";

/// The name of Vigie's own `addData` block (start and stop buttons, chart names):
/// other tools keep it (`handleUnknown="preserve"`) and ignore it.
pub const ADD_DATA: &str = "urn:vigie:program";
