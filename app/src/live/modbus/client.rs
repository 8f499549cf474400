//! The Modbus TCP client Vigie is to the plant (gateway) or to the monitored PLC
//! (monitor): polls the map's read blocks when due, stamps every value with the time it
//! was read, reconnects with backoff, and never fails the caller: exceptions, timeouts
//! and refused connections are logged with the peer address and the values age.
//!
//! The cycle reaches it through the protocol-neutral `Reader` and `Writer` of
//! `super::super::link`.

use super::super::link::{ClientStatus, Reconnect};
use std::time::Duration;
use tokio_modbus::Slave;
use tokio_modbus::client::{Context, Reader as _, Writer as _};
use tokio_modbus::prelude::{SlaveContext as _, tcp};
use vigie_core::live::age::AgedBits;
use vigie_core::live::config::ClientConfig;
use vigie_core::live::image::{Raw, ReadBlock, WriteOp, plan_reads, plan_writes};
use vigie_core::live::iomap::{Area, IoMap};
use vigie_core::{Bits, Millis};

/// Why a request failed.
#[derive(Debug, thiserror::Error)]
pub(crate) enum LinkError {
    /// The peer answered with a Modbus exception.
    #[error("{peer} answered {what} with exception {code:?}")]
    Exception {
        /// Peer.
        peer: std::net::SocketAddr,
        /// The request.
        what: String,
        /// The exception.
        code: tokio_modbus::ExceptionCode,
    },
    /// Transport or framing error: the connection is dropped.
    #[error("{peer}: {what} failed: {error}")]
    Transport {
        /// Peer.
        peer: std::net::SocketAddr,
        /// The request.
        what: String,
        /// The error.
        error: String,
    },
    /// No answer in time: the connection is dropped.
    #[error("{peer}: {what} timed out after {timeout_ms} ms")]
    Timeout {
        /// Peer.
        peer: std::net::SocketAddr,
        /// The request.
        what: String,
        /// The limit.
        timeout_ms: u64,
    },
    /// Not connected.
    #[error("{peer}: not connected")]
    Disconnected {
        /// Peer.
        peer: std::net::SocketAddr,
    },
}

/// The connection and the poll schedule.
pub(crate) struct Link {
    config: ClientConfig,
    map: IoMap,
    blocks: Vec<ReadBlock>,
    last_poll: Vec<Option<Millis>>,
    ctx: Option<Context>,
    failing_blocks: Vec<bool>,
    link: Reconnect,
}

impl Link {
    pub(crate) fn new(config: ClientConfig, map: IoMap, with_outputs: bool) -> Self {
        let blocks = plan_reads(&map, with_outputs, 8);
        let n = blocks.len();
        Self {
            link: Reconnect::new(config.backoff_initial_ms, config.backoff_max_ms),
            config,
            map,
            blocks,
            last_poll: vec![None; n],
            ctx: None,
            failing_blocks: vec![false; n],
        }
    }

    pub(crate) fn peer(&self) -> std::net::SocketAddr {
        self.config.address
    }

    fn timeout(&self) -> Duration {
        Duration::from_millis(self.config.timeout_ms)
    }

    pub(crate) fn is_connected(&self) -> bool {
        self.ctx.is_some()
    }

    async fn ensure_connected(&mut self, now: Millis) -> bool {
        if self.ctx.is_some() {
            return true;
        }
        if !self.link.may_try(now) {
            return false;
        }
        let peer = self.peer();
        match tokio::time::timeout(self.timeout(), tcp::connect(peer)).await {
            Ok(Ok(ctx)) => {
                tracing::info!(%peer, "connected");
                self.ctx = Some(ctx);
                self.last_poll.iter_mut().for_each(|t| *t = None);
                self.link.connected();
                true
            }
            Ok(Err(e)) => {
                self.retry_later(now, &format!("cannot connect: {}", describe_io(&e)));
                false
            }
            Err(_) => {
                self.retry_later(
                    now,
                    &format!("cannot connect: no answer in {} ms", self.config.timeout_ms),
                );
                false
            }
        }
    }

    fn retry_later(&mut self, now: Millis, why: &str) {
        let peer = self.peer();
        self.link.retry_later(&peer, now, why);
    }

    fn drop_connection(&mut self, now: Millis, err: &LinkError) {
        tracing::warn!("{err}; connection dropped");
        self.ctx = None;
        self.link.dropped(now);
    }

    /// Reads every block that is due; true when all of them were read.
    pub(crate) async fn poll(
        &mut self,
        now: Millis,
        inputs: &mut AgedBits,
        outputs: &mut AgedBits,
    ) -> bool {
        if !self.ensure_connected(now).await {
            return false;
        }
        let mut all_ok = true;
        for b in 0..self.blocks.len() {
            let due = match (self.last_poll.get(b).copied().flatten(), self.blocks.get(b)) {
                (None, Some(_)) => true,
                // One millisecond of tolerance: times are whole milliseconds.
                (Some(t), Some(block)) => {
                    now.saturating_sub(t) >= block.poll.saturating_sub(Millis(1))
                }
                _ => false,
            };
            if !due {
                continue;
            }
            match self.read_block(b).await {
                Ok(raw) => {
                    if let Some(slot) = self.last_poll.get_mut(b) {
                        *slot = Some(now);
                    }
                    let Some(block) = self.blocks.get(b) else {
                        continue;
                    };
                    let decoded = match &raw {
                        RawOwned::Bits(v) => block.decode(Raw::Bits(v), now, inputs, outputs),
                        RawOwned::Words(v) => block.decode(Raw::Words(v), now, inputs, outputs),
                    };
                    if let Err(e) = decoded {
                        tracing::warn!(peer = %self.peer(), "{e}");
                        self.link.status.errors += 1;
                        all_ok = false;
                    } else if self.failing_blocks.get(b).copied().unwrap_or(false) {
                        tracing::info!(peer = %self.peer(), "{} {} read again", block.area, block.start);
                        if let Some(f) = self.failing_blocks.get_mut(b) {
                            *f = false;
                        }
                    }
                }
                Err(e @ LinkError::Exception { .. }) => {
                    self.link.status.exceptions += 1;
                    // The device answered: keep the connection, let the values age.
                    if let Some(f) = self.failing_blocks.get_mut(b)
                        && !*f
                    {
                        tracing::warn!("{e}");
                        *f = true;
                    }
                    all_ok = false;
                }
                Err(e) => {
                    self.drop_connection(now, &e);
                    return false;
                }
            }
        }
        if all_ok {
            self.link.answered(now);
        }
        all_ok
    }

    async fn read_block(&mut self, b: usize) -> Result<RawOwned, LinkError> {
        let peer = self.peer();
        let timeout = self.timeout();
        let timeout_ms = self.config.timeout_ms;
        let Some(block) = self.blocks.get(b) else {
            return Err(LinkError::Disconnected { peer });
        };
        let (area, start, count, unit) = (block.area, block.start, block.count, block.unit);
        let Some(ctx) = self.ctx.as_mut() else {
            return Err(LinkError::Disconnected { peer });
        };
        ctx.set_slave(Slave(unit));
        let what = format!("read {count} {area} at {start} (unit {unit})");
        let outcome = match area {
            Area::DiscreteInput => {
                tokio::time::timeout(timeout, ctx.read_discrete_inputs(start, count))
                    .await
                    .map(|r| r.map(|r| r.map(RawOwned::Bits)))
            }
            Area::Coil => tokio::time::timeout(timeout, ctx.read_coils(start, count))
                .await
                .map(|r| r.map(|r| r.map(RawOwned::Bits))),
            Area::InputRegister => {
                tokio::time::timeout(timeout, ctx.read_input_registers(start, count))
                    .await
                    .map(|r| r.map(|r| r.map(RawOwned::Words)))
            }
            Area::HoldingRegister => {
                tokio::time::timeout(timeout, ctx.read_holding_registers(start, count))
                    .await
                    .map(|r| r.map(|r| r.map(RawOwned::Words)))
            }
        };
        settle(peer, what, timeout_ms, outcome)
    }

    /// Writes every output (connecting first when the backoff allows); `Ok` when every
    /// write was acknowledged, else why not.
    pub(crate) async fn write(&mut self, now: Millis, outputs: &Bits) -> Result<(), String> {
        if !self.ensure_connected(now).await {
            return Err(format!(
                "{}: not connected (next attempt at {})",
                self.peer(),
                self.link.next_attempt
            ));
        }
        let peer = self.peer();
        let timeout = self.timeout();
        let timeout_ms = self.config.timeout_ms;
        for op in plan_writes(&self.map, outputs) {
            let Some(ctx) = self.ctx.as_mut() else {
                return Err(format!("{peer}: not connected"));
            };
            let result = match &op {
                WriteOp::Coils {
                    unit,
                    start,
                    values,
                } => {
                    ctx.set_slave(Slave(*unit));
                    let what = format!("write {} coils at {start} (unit {unit})", values.len());
                    settle(
                        peer,
                        what,
                        timeout_ms,
                        tokio::time::timeout(timeout, ctx.write_multiple_coils(*start, values))
                            .await,
                    )
                }
                WriteOp::MaskRegister {
                    unit,
                    address,
                    and_mask,
                    or_mask,
                } => {
                    ctx.set_slave(Slave(*unit));
                    let what = format!("mask write holding register {address} (unit {unit})");
                    settle(
                        peer,
                        what,
                        timeout_ms,
                        tokio::time::timeout(
                            timeout,
                            ctx.masked_write_register(*address, *and_mask, *or_mask),
                        )
                        .await,
                    )
                }
            };
            match result {
                Ok(()) => {}
                Err(e @ LinkError::Exception { .. }) => {
                    self.link.status.exceptions += 1;
                    tracing::warn!("{e}");
                    return Err(e.to_string());
                }
                Err(e) => {
                    self.drop_connection(now, &e);
                    return Err(e.to_string());
                }
            }
        }
        Ok(())
    }
}

enum RawOwned {
    Bits(Vec<bool>),
    Words(Vec<u16>),
}

type Outcome<T> = Result<tokio_modbus::Result<T>, tokio::time::error::Elapsed>;

fn settle<T>(
    peer: std::net::SocketAddr,
    what: String,
    timeout_ms: u64,
    outcome: Outcome<T>,
) -> Result<T, LinkError> {
    match outcome {
        Ok(Ok(Ok(v))) => Ok(v),
        Ok(Ok(Err(code))) => Err(LinkError::Exception { peer, what, code }),
        Ok(Err(e)) => Err(LinkError::Transport {
            peer,
            what,
            error: describe_modbus(&e),
        }),
        Err(_) => Err(LinkError::Timeout {
            peer,
            what,
            timeout_ms,
        }),
    }
}

/// A transport error in words a technician reads: what happened to the connection,
/// with the system's own text after it.
pub(crate) fn describe_io(e: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    let what = match e.kind() {
        K::UnexpectedEof | K::ConnectionReset | K::ConnectionAborted | K::BrokenPipe => {
            "the peer closed the connection"
        }
        K::ConnectionRefused => "connection refused (nothing listens at that address)",
        K::TimedOut => "no answer in time",
        K::InvalidData => "the peer sent a malformed frame",
        K::AddrNotAvailable => "the address is not available on this machine",
        K::NotConnected => "not connected",
        _ => match e.raw_os_error() {
            // EINPROGRESS, EALREADY: a connection whose handshake never completed.
            Some(115 | 114) => "the connection was not established (the peer did not complete it)",
            // EMFILE, ENFILE: no file descriptor left.
            Some(24 | 23) => "no file descriptor left (too many open connections or files)",
            Some(113) => "no route to the peer",
            _ => "",
        },
    };
    if what.is_empty() {
        e.to_string()
    } else {
        format!("{what} ({e})")
    }
}

/// A Modbus client error in words (see [`describe_io`]).
fn describe_modbus(e: &tokio_modbus::Error) -> String {
    match e {
        tokio_modbus::Error::Transport(io) => describe_io(io),
        tokio_modbus::Error::Protocol(p) => {
            format!("the peer answered out of turn or malformed ({p})")
        }
    }
}

impl Link {
    /// The link state.
    pub(crate) fn status(&self) -> &ClientStatus {
        &self.link.status
    }
}

#[cfg(test)]
mod tests {
    use super::describe_io;
    use std::io::{Error, ErrorKind};

    #[test]
    fn peer_errors_read_as_words_with_the_system_text_after() {
        let closed = describe_io(&Error::from(ErrorKind::ConnectionReset));
        assert!(
            closed.starts_with("the peer closed the connection ("),
            "{closed}"
        );
        let eof = describe_io(&Error::from(ErrorKind::UnexpectedEof));
        assert!(eof.starts_with("the peer closed the connection"), "{eof}");
        // EINPROGRESS, what a connection to a closed peer used to be logged as.
        let in_progress = describe_io(&Error::from_raw_os_error(115));
        assert!(
            in_progress.starts_with("the connection was not established")
                && in_progress.contains("115"),
            "{in_progress}"
        );
        let refused = describe_io(&Error::from(ErrorKind::ConnectionRefused));
        assert!(refused.contains("nothing listens"), "{refused}");
        let fds = describe_io(&Error::from_raw_os_error(24));
        assert!(fds.starts_with("no file descriptor left"), "{fds}");
    }
}
