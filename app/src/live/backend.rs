//! What a Modbus server can serve: anything that reads inputs and takes outputs.

use vigie_core::machine::Physical;
use vigie_core::{Bits, Millis};

/// A plant behind a server: the emulator, or an in-memory image in tests.
pub(crate) trait IoBackend: Send {
    /// Advances by `dt` with `outputs` applied.
    fn write_outputs(&mut self, dt: Millis, outputs: &Bits);
    /// The sensors now.
    fn read_inputs(&self) -> &Bits;
}

/// The built-in emulator as a backend.
pub(crate) struct EmulatorBackend(pub(crate) Physical);

impl IoBackend for EmulatorBackend {
    fn write_outputs(&mut self, dt: Millis, outputs: &Bits) {
        self.0.step(dt, outputs);
    }

    fn read_inputs(&self) -> &Bits {
        self.0.sensors()
    }
}

/// Inputs set from outside, outputs recorded (tests).
#[cfg_attr(not(test), expect(dead_code, reason = "served in the unit tests"))]
#[derive(Clone, Debug, Default)]
pub(crate) struct MemoryBackend {
    /// Sensors to serve.
    pub(crate) inputs: Bits,
    /// The last outputs written.
    pub(crate) outputs: Bits,
}

impl IoBackend for MemoryBackend {
    fn write_outputs(&mut self, _dt: Millis, outputs: &Bits) {
        self.outputs.copy_from(outputs);
    }

    fn read_inputs(&self) -> &Bits {
        &self.inputs
    }
}
