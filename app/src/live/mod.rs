//! The networked half of the live link (Modbus TCP over tokio-modbus): the pure parts
//! (I/O map, register image, data age, stale inputs) are in `vigie_core::live`.
//!
//! - [`client`]: polls the plant (or the monitored PLC), reconnects with backoff.
//! - [`server`]: serves an image to a PLC, with allow-list and writer checks.
//! - [`backend`]: what a server can serve (the emulator, a memory image).
//! - [`runtime`]: the monitor, gateway and emulator service loops.
//! - [`bench`]: cycle rate, jitter and sensor-to-output latency against pymodbus.
//!
//! The only wall clock of Vigie is read here (`std::time::Instant`), turned into
//! [`vigie_core::Millis`] since the start of the run.

pub(crate) mod backend;
pub(crate) mod bench;
pub(crate) mod client;
pub(crate) mod runtime;
pub(crate) mod server;

#[cfg(test)]
mod tests;
