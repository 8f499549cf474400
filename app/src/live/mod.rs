//! The networked half of the live link (Modbus TCP over tokio-modbus): the pure parts
//! (I/O map, register image, data age, stale inputs) are in `vigie_core::live`.
//!
//! - `client`: polls the plant (or the monitored PLC), reconnects with backoff.
//! - `server`: serves an image to a PLC, with allow-list and writer checks.
//! - `backend`: what a server can serve (the emulator, a memory image).
//! - [`runtime`]: loads a configuration and runs its mode (the emulator loop is here).
//! - `cycle`: the monitor and gateway cycles on their own thread at absolute
//!   deadlines.
//! - `io`: the client on a tokio task (outputs first after a reconnection,
//!   `plant_write` events) and the runtime's heartbeat.
//! - `latch`: the latched trip on disk, saved before it is reported.
//! - [`sink`]: the headless run's events to the journal and to stdout, off the cycle.
//! - [`tap`]: what a run publishes for the console (cycles, link state, link alarms).
//! - [`bench`](mod@bench): cycle rate, jitter and sensor-to-output latency against pymodbus.
//!
//! The only wall clock of Vigie is read here (`std::time::Instant`), turned into
//! [`vigie_core::Millis`] since the start of the run.

pub(crate) mod backend;
pub mod bench;
pub(crate) mod client;
pub(crate) mod cycle;
pub(crate) mod io;
pub(crate) mod latch;
pub mod runtime;
pub(crate) mod server;
pub mod sink;
pub mod tap;

#[cfg(test)]
mod tests;

/// Resolves on SIGINT or SIGTERM (on other systems: Ctrl-C), for the headless gateway
/// and the console on a link. Call it inside a Tokio runtime: the handlers are installed
/// by the call, not when the future is first polled, so a signal that comes while the
/// run starts waits for it instead of ending the process by the default action (before
/// the outputs are driven to the safe state).
#[cfg(unix)]
pub fn stop_signal() -> impl std::future::Future<Output = ()> {
    use tokio::signal::unix::{SignalKind, signal};
    let term = signal(SignalKind::terminate());
    let int = signal(SignalKind::interrupt());
    async move {
        match (term, int) {
            (Ok(mut term), Ok(mut int)) => {
                tokio::select! {
                    _ = term.recv() => {}
                    _ = int.recv() => {}
                }
            }
            (term, int) => {
                for e in [term.err(), int.err()].into_iter().flatten() {
                    tracing::warn!("cannot watch a stop signal: {e}");
                }
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
}

/// Resolves on Ctrl-C (see the Unix version).
#[cfg(not(unix))]
pub fn stop_signal() -> impl std::future::Future<Output = ()> {
    async {
        let _ = tokio::signal::ctrl_c().await;
    }
}
