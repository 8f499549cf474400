//! The protocol-neutral link: what the monitor and gateway cycles (and the I/O task)
//! see of a peer, whatever the protocol. A protocol is an adapter with four calls
//! (poll the inputs, write the outputs, the status, connected or not) for the client,
//! and a server over the [`Shared`] image; adding one (S7 with a kept crate) adds a
//! variant here and a module beside `modbus` and `opcua`, not a copy of the cycle.
//!
//! [`Reader`] can only read; [`Writer`] can also write outputs. Monitor mode gets a
//! [`Reader`], so it cannot write by construction.

use super::modbus;
use super::modbus::server::{Shared, SharedImage};
use super::opcua;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use vigie_core::live::LinkMap;
use vigie_core::live::age::AgedBits;
use vigie_core::live::config::{ClientLink, GatewayConfig, ServerLink};
use vigie_core::live::image::ServerImage;
use vigie_core::{Bits, Millis};

/// What the link-state panel shows of a client.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ClientStatus {
    /// True while connected.
    pub connected: bool,
    /// Failed connection attempts since the last success (or since the link dropped).
    pub failed_attempts: u32,
    /// The delay before the next attempt (the current backoff) while disconnected.
    pub backoff: Millis,
    /// When the next connection attempt is due while disconnected.
    pub next_attempt: Millis,
    /// When every due value was last read successfully.
    pub last_read: Option<Millis>,
    /// Requests answered with an exception (Modbus) or values with a bad status (OPC UA).
    pub exceptions: u64,
    /// Transport errors, timeouts and malformed answers (each drops the connection).
    pub errors: u64,
    /// Successful (re)connections.
    pub connections: u64,
}

/// The connection bookkeeping every protocol's client shares: the backoff, when the
/// next attempt is due, the status the panel shows, and logging a lost peer once.
pub(crate) struct Reconnect {
    backoff: vigie_core::live::age::Backoff,
    /// When the next connection attempt is due.
    pub(crate) next_attempt: Millis,
    /// Whether the peer's loss was logged (to log transitions only).
    down_logged: bool,
    /// What the link-state panel shows.
    pub(crate) status: ClientStatus,
}

impl Reconnect {
    /// Retries from `initial_ms`, doubled after each failure up to `max_ms`.
    pub(crate) fn new(initial_ms: u64, max_ms: u64) -> Self {
        Self {
            backoff: vigie_core::live::age::Backoff::new(Millis(initial_ms), Millis(max_ms)),
            next_attempt: Millis::ZERO,
            down_logged: false,
            status: ClientStatus::default(),
        }
    }

    /// True when a connection attempt is allowed at `now`.
    pub(crate) fn may_try(&self, now: Millis) -> bool {
        now >= self.next_attempt
    }

    /// A connection opened. The backoff is reset by the first answered request, not
    /// here: a peer that accepts and then fails at once is retried ever more slowly.
    pub(crate) fn connected(&mut self) {
        self.down_logged = false;
        self.status.connected = true;
        self.status.failed_attempts = 0;
        self.status.backoff = Millis::ZERO;
        self.status.connections += 1;
    }

    /// A connection attempt failed at `now`: the next one after the backoff.
    pub(crate) fn retry_later(&mut self, peer: &dyn std::fmt::Display, now: Millis, why: &str) {
        let delay = self.backoff.failed();
        self.next_attempt = now + delay;
        self.status.failed_attempts = self.status.failed_attempts.saturating_add(1);
        self.status.backoff = delay;
        self.status.next_attempt = self.next_attempt;
        if !self.down_logged {
            tracing::warn!(peer = %peer, "{why}; retrying with backoff (next in {delay})");
            self.down_logged = true;
        } else {
            tracing::debug!(peer = %peer, "{why}; next attempt in {delay}");
        }
    }

    /// An open connection failed at `now` (the caller drops it).
    pub(crate) fn dropped(&mut self, now: Millis) {
        self.down_logged = true;
        let delay = self.backoff.failed();
        self.next_attempt = now + delay;
        self.status.connected = false;
        self.status.errors += 1;
        self.status.backoff = delay;
        self.status.next_attempt = self.next_attempt;
    }

    /// Everything due was read at `now`.
    pub(crate) fn answered(&mut self, now: Millis) {
        self.status.last_read = Some(now);
        self.backoff.reset();
    }
}

/// A client of one protocol.
enum Transport {
    Modbus(modbus::client::Link),
    OpcUa(opcua::client::Link),
}

impl Transport {
    /// The client of `link` over `map` (the map must be of the same protocol).
    fn new(
        link: ClientLink,
        map: LinkMap,
        with_outputs: bool,
        pki: &Path,
        clock: std::time::Instant,
    ) -> anyhow::Result<Self> {
        Ok(match (link, map) {
            (ClientLink::Modbus(c), LinkMap::Modbus(m)) => {
                Self::Modbus(modbus::client::Link::new(c, m, with_outputs))
            }
            (ClientLink::OpcUa(c), LinkMap::OpcUa(m)) => Self::OpcUa(opcua::client::Link::new(
                c,
                m,
                with_outputs,
                pki.to_path_buf(),
                clock,
            )),
            (link, _) => anyhow::bail!(
                "the {} client was given another protocol's map",
                link.protocol()
            ),
        })
    }

    async fn poll(&mut self, now: Millis, inputs: &mut AgedBits, outputs: &mut AgedBits) -> bool {
        match self {
            Self::Modbus(l) => l.poll(now, inputs, outputs).await,
            Self::OpcUa(l) => l.poll(now, inputs, outputs).await,
        }
    }

    async fn write(&mut self, now: Millis, outputs: &Bits) -> Result<(), String> {
        match self {
            Self::Modbus(l) => l.write(now, outputs).await,
            Self::OpcUa(l) => l.write(now, outputs).await,
        }
    }

    fn status(&self) -> &ClientStatus {
        match self {
            Self::Modbus(l) => l.status(),
            Self::OpcUa(l) => l.status(),
        }
    }

    fn is_connected(&self) -> bool {
        match self {
            Self::Modbus(l) => l.is_connected(),
            Self::OpcUa(l) => l.is_connected(),
        }
    }
}

/// A read-only client (monitor mode): it has no way to write.
pub(crate) struct Reader(Transport);

impl Reader {
    /// A client reading the inputs and, with `with_outputs`, the outputs of `map`.
    pub(crate) fn new(
        link: ClientLink,
        map: LinkMap,
        with_outputs: bool,
        pki: &Path,
        clock: std::time::Instant,
    ) -> anyhow::Result<Self> {
        Transport::new(link, map, with_outputs, pki, clock).map(Self)
    }

    /// Reads what is due at `now`; true when every due value was read.
    pub(crate) async fn poll(
        &mut self,
        now: Millis,
        inputs: &mut AgedBits,
        outputs: &mut AgedBits,
    ) -> bool {
        self.0.poll(now, inputs, outputs).await
    }

    /// The link state.
    pub(crate) fn status(&self) -> &ClientStatus {
        self.0.status()
    }
}

/// A client that reads the inputs and writes the outputs (gateway mode).
pub(crate) struct Writer(Transport);

impl Writer {
    /// A client for `map`: reads its inputs, writes its outputs.
    pub(crate) fn new(
        link: ClientLink,
        map: LinkMap,
        pki: &Path,
        clock: std::time::Instant,
    ) -> anyhow::Result<Self> {
        Transport::new(link, map, false, pki, clock).map(Self)
    }

    /// Reads what is due at `now`; true when every due value was read.
    pub(crate) async fn poll(&mut self, now: Millis, inputs: &mut AgedBits) -> bool {
        let mut none = AgedBits::new(0);
        self.0.poll(now, inputs, &mut none).await
    }

    /// Writes every output, connecting first when the backoff allows; `Ok` when every
    /// write was acknowledged, else why not.
    pub(crate) async fn write(&mut self, now: Millis, outputs: &Bits) -> Result<(), String> {
        self.0.write(now, outputs).await
    }

    /// Successful connections so far (a new connection needs the outputs again).
    pub(crate) fn connection(&self) -> u64 {
        self.0.status().connections
    }

    /// True while connected.
    pub(crate) fn is_connected(&self) -> bool {
        self.0.is_connected()
    }

    /// The link state.
    pub(crate) fn status(&self) -> &ClientStatus {
        self.0.status()
    }
}

/// A running server of either protocol; stopped when dropped.
pub(crate) enum ServerHandle {
    Modbus(modbus::server::ServerHandle),
    OpcUa(opcua::server::ServerHandle),
}

impl ServerHandle {
    /// The address it listens on.
    pub(crate) fn local(&self) -> std::net::SocketAddr {
        match self {
            Self::Modbus(h) => h.local,
            Self::OpcUa(h) => h.local,
        }
    }

    /// Where a client reaches it: an address (Modbus) or an endpoint URL (OPC UA).
    pub(crate) fn address(&self) -> String {
        match self {
            Self::Modbus(h) => h.local.to_string(),
            Self::OpcUa(h) => h.endpoint.clone(),
        }
    }
}

/// What a server to the PLC serves and how.
pub(crate) struct Serve<'a> {
    /// The run's configuration (the link timeout, the plant folder).
    pub(crate) config: &'a GatewayConfig,
    /// The server section.
    pub(crate) server: &'a ServerLink,
    /// The I/O map (Modbus); `None` for OPC UA.
    pub(crate) map: Option<&'a LinkMap>,
    /// The plant.
    pub(crate) plant: &'a vigie_core::plant::Plant,
    /// The OPC UA PKI folder.
    pub(crate) pki: &'a Path,
}

/// Starts the server the PLC talks to, over a fresh shared image whose inputs are
/// `inputs` and whose outputs are zeros (one per output of the plant): Modbus on the
/// I/O map, or OPC UA on the plant's own address space.
pub(crate) async fn serve_plc(
    serve: &Serve<'_>,
    inputs: Bits,
) -> anyhow::Result<(SharedImage, ServerHandle)> {
    use anyhow::Context as _;
    let Serve {
        config,
        server,
        map,
        plant,
        pki,
    } = *serve;
    let shared: SharedImage = Arc::new(Mutex::new(Shared {
        inputs,
        outputs: Bits::zeros(plant.outputs.len()),
        ..Shared::default()
    }));
    let handle = match server {
        ServerLink::Modbus(s) => {
            let Some(LinkMap::Modbus(map)) = map else {
                anyhow::bail!("the Modbus server needs the I/O map");
            };
            ServerHandle::Modbus(
                modbus::server::start(
                    s,
                    ServerImage::new(map, s.unit),
                    Arc::clone(&shared),
                    Duration::from_millis(config.link_timeout().0),
                )
                .await
                .with_context(|| format!("cannot listen on {}", s.bind))?,
            )
        }
        ServerLink::OpcUa(s) => {
            let namespace = s
                .namespace
                .clone()
                .unwrap_or_else(|| vigie_core::live::nodemap::plant_namespace(&config.plant));
            let space = opcua::server::AddressSpace {
                plant: &plant.name,
                namespace: &namespace,
                inputs: plant.inputs.iter().map(|x| x.id.clone()).collect(),
                outputs: plant.outputs.iter().map(|x| x.id.clone()).collect(),
            };
            ServerHandle::OpcUa(opcua::server::start(s, &space, Arc::clone(&shared), pki).await?)
        }
    };
    Ok((shared, handle))
}
