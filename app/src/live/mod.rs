//! The networked half of the live link (Modbus TCP over tokio-modbus, OPC UA over
//! async-opcua): the pure parts (I/O and node maps, register image, data age, stale
//! inputs) are in `vigie_core::live`.
//!
//! - `link`: the protocol-neutral client (`Reader`, `Writer`) and server start the
//!   cycles use; one adapter per protocol:
//! - `modbus`: the client (polls the plant or the monitored PLC, reconnects with
//!   backoff) and the server (serves an image to a PLC, allow-list, writer checks);
//! - `opcua`: the same over OPC UA, with the certificates (`opcua::pki`).
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
pub(crate) mod cycle;
pub(crate) mod io;
pub(crate) mod latch;
pub(crate) mod link;
pub(crate) mod modbus;
pub(crate) mod opcua;
pub mod runtime;
pub mod sink;
pub mod tap;

#[cfg(test)]
mod tests;

/// The OPC UA PKI folder of a run whose state folder is `state_dir`.
pub fn opcua_pki(state_dir: &std::path::Path) -> std::path::PathBuf {
    opcua::pki::folder(state_dir)
}

/// Vigie's OPC UA certificate in `pki`, created when absent: its path and thumbprint.
pub fn opcua_certificate(pki: &std::path::Path) -> anyhow::Result<(std::path::PathBuf, String)> {
    opcua::pki::own_certificate(pki)
}

/// Trusts a peer's certificate in `pki`; the path of the trusted copy.
pub fn opcua_trust(
    pki: &std::path::Path,
    cert: &std::path::Path,
) -> anyhow::Result<std::path::PathBuf> {
    opcua::pki::trust(pki, cert)
}

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
