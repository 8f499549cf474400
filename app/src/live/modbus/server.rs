//! The Modbus TCP server Vigie is to a PLC (gateway mode) or to a soft-PLC (emulator
//! mode): it answers from a [`Shared`] image that the service loop keeps up to date.
//!
//! Security and robustness:
//! - the listener binds where the configuration says (loopback by default); clients
//!   outside the allow-list are disconnected at once;
//! - only a connection from the configured PLC endpoint (address, and source port when
//!   pinned) may write, one such connection at a time (a second one is read-only until
//!   the first closes or the PLC is lost); anyone else's write gets exception 01
//!   (illegal function) and is logged;
//! - the PLC's liveness is its own acknowledged writes: a client that only reads keeps
//!   nothing alive;
//! - requests for any unit id but the configured one (0 and 255 included) get
//!   exception 0B; illegal addresses and quantities get exceptions 02 and 03, unknown
//!   functions 01;
//! - at most `max_connections` clients are served at once (more are closed at once, the
//!   refusals counted); a connection silent for `idle_timeout_ms` is closed; an accept
//!   error (descriptor exhaustion) is logged and the listener retried with backoff, so
//!   the server recovers when descriptors are free again.
//!
//! Nothing a client sends can stop the server.

use std::future::Future as _;
use std::io;
use std::net::{IpAddr, SocketAddr};
use std::pin::Pin;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};
use std::time::{Duration, Instant};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::TcpStream;
use tokio_modbus::prelude::{ExceptionCode, Request, Response, SlaveRequest};
use tokio_modbus::server::tcp::Server;
use vigie_core::Bits;
use vigie_core::live::config::{PlcEndpoint, ServerConfig};
use vigie_core::live::image::{ImageError, ServerImage};
use vigie_core::live::iomap::Area;

/// The image a server shares with the loop that drives it.
#[derive(Debug, Default)]
pub(crate) struct Shared {
    /// Sensors served to readers.
    pub(crate) inputs: Bits,
    /// Actuators as last written by the PLC.
    pub(crate) outputs: Bits,
    /// When the PLC last wrote outputs that were accepted (its liveness).
    pub(crate) plc_heard: Option<Instant>,
    /// Requests answered with an exception.
    pub(crate) exceptions: u64,
    /// The connection that holds the writer role, while one does.
    pub(crate) writer: Option<SocketAddr>,
}

/// A handle on the shared image.
pub(crate) type SharedImage = Arc<Mutex<Shared>>;

use super::super::cycle::lock;

/// Counters of what the server refused (for the link-state panel and the tests).
#[derive(Debug, Default)]
pub(crate) struct Refusals {
    /// Connections closed because `max_connections` were served.
    pub(crate) over_cap: AtomicU64,
    /// Connections closed after `idle_timeout_ms` of silence.
    pub(crate) idle: AtomicU64,
    /// Failed accepts (descriptor exhaustion and the like).
    pub(crate) accept_errors: AtomicU64,
}

/// A running server; stopped when dropped.
pub(crate) struct ServerHandle {
    /// The address it listens on (the real port when the configuration says 0).
    pub(crate) local: SocketAddr,
    task: tokio::task::JoinHandle<()>,
}

impl Drop for ServerHandle {
    fn drop(&mut self) {
        self.task.abort();
    }
}

/// One client connection.
struct Session {
    peer: SocketAddr,
    /// The connection comes from the PLC's endpoint (it may claim the writer role).
    plc: bool,
    unit: u8,
    /// A writer silent for this long may be replaced by another PLC connection.
    takeover_after: Duration,
    image: Arc<ServerImage>,
    shared: SharedImage,
    /// Refused requests of this connection (logged 1st, 2nd, 4th…).
    refused: AtomicU64,
}

impl Drop for Session {
    fn drop(&mut self) {
        let mut s = lock(&self.shared);
        if s.writer == Some(self.peer) {
            s.writer = None;
            tracing::info!(peer = %self.peer, "the PLC's connection closed");
        }
    }
}

impl tokio_modbus::server::Service for Session {
    type Request = SlaveRequest<'static>;
    type Response = Response;
    type Exception = ExceptionCode;
    type Future = std::future::Ready<Result<Response, ExceptionCode>>;

    fn call(&self, req: Self::Request) -> Self::Future {
        let result = self.handle(req);
        if let Err(code) = &result {
            tracing::debug!(peer = %self.peer, "modbus exception {code:?}");
        }
        std::future::ready(result)
    }
}

fn exception(e: &ImageError) -> ExceptionCode {
    match e {
        ImageError::IllegalAddress { .. } => ExceptionCode::IllegalDataAddress,
        ImageError::IllegalQuantity { .. } => ExceptionCode::IllegalDataValue,
    }
}

fn is_write(request: &Request<'_>) -> bool {
    matches!(
        request,
        Request::WriteSingleCoil(..)
            | Request::WriteMultipleCoils(..)
            | Request::WriteSingleRegister(..)
            | Request::WriteMultipleRegisters(..)
            | Request::MaskWriteRegister(..)
            | Request::ReadWriteMultipleRegisters(..)
    )
}

impl Session {
    fn handle(&self, req: SlaveRequest<'static>) -> Result<Response, ExceptionCode> {
        let SlaveRequest { slave, request } = req;
        let mut shared = lock(&self.shared);
        let shared = &mut *shared;
        let write = is_write(&request);
        let result = if slave != self.unit {
            log_power_of_two(&self.refused, |n| {
                tracing::warn!(peer = %self.peer, "request to unit {slave} refused (exception 0B): this server is unit {} ({n} refused on this connection)", self.unit);
            });
            Err(ExceptionCode::GatewayTargetDevice)
        } else if write && !self.claim_writer(shared) {
            Err(ExceptionCode::IllegalFunction)
        } else {
            self.answer(request, shared)
        };
        match &result {
            Err(_) => shared.exceptions += 1,
            Ok(_) if write => shared.plc_heard = Some(Instant::now()),
            Ok(_) => {}
        }
        result
    }

    /// True when this connection may write: it comes from the PLC's endpoint and holds
    /// the writer role (taken when free, or from a writer silent for longer than the
    /// link timeout).
    fn claim_writer(&self, s: &mut Shared) -> bool {
        if !self.plc {
            log_power_of_two(&self.refused, |n| {
                tracing::warn!(peer = %self.peer, "write refused (exception 01): only the configured PLC endpoint may write ({n} refused on this connection)");
            });
            return false;
        }
        match s.writer {
            Some(w) if w == self.peer => true,
            Some(w)
                if s.plc_heard
                    .is_some_and(|h| h.elapsed() <= self.takeover_after) =>
            {
                log_power_of_two(&self.refused, |n| {
                    tracing::warn!(peer = %self.peer, writer = %w, "write refused (exception 01): the PLC already writes on another connection ({n} refused on this one)");
                });
                false
            }
            previous => {
                if let Some(w) = previous {
                    tracing::warn!(peer = %self.peer, "the PLC writes on a new connection; the silent one ({w}) is read-only now");
                }
                s.writer = Some(self.peer);
                true
            }
        }
    }

    fn answer(&self, request: Request<'static>, s: &mut Shared) -> Result<Response, ExceptionCode> {
        let img = &self.image;
        let r = match request {
            Request::ReadCoils(a, n) => img
                .read_bits(Area::Coil, a, n, &s.inputs, &s.outputs)
                .map(Response::ReadCoils),
            Request::ReadDiscreteInputs(a, n) => img
                .read_bits(Area::DiscreteInput, a, n, &s.inputs, &s.outputs)
                .map(Response::ReadDiscreteInputs),
            Request::ReadInputRegisters(a, n) => img
                .read_registers(Area::InputRegister, a, n, &s.inputs, &s.outputs)
                .map(Response::ReadInputRegisters),
            Request::ReadHoldingRegisters(a, n) => img
                .read_registers(Area::HoldingRegister, a, n, &s.inputs, &s.outputs)
                .map(Response::ReadHoldingRegisters),
            Request::WriteSingleCoil(a, v) => img
                .write_coils(a, &[v], &mut s.outputs)
                .map(|()| Response::WriteSingleCoil(a, v)),
            Request::WriteMultipleCoils(a, values) => {
                let n = u16::try_from(values.len()).unwrap_or(u16::MAX);
                img.write_coils(a, &values, &mut s.outputs)
                    .map(|()| Response::WriteMultipleCoils(a, n))
            }
            Request::WriteSingleRegister(a, w) => img
                .write_registers(a, &[(0, w)], &mut s.outputs)
                .map(|()| Response::WriteSingleRegister(a, w)),
            Request::WriteMultipleRegisters(a, words) => {
                let n = u16::try_from(words.len()).unwrap_or(u16::MAX);
                let pairs: Vec<(u16, u16)> = words.iter().map(|&w| (0, w)).collect();
                img.write_registers(a, &pairs, &mut s.outputs)
                    .map(|()| Response::WriteMultipleRegisters(a, n))
            }
            Request::MaskWriteRegister(a, and, or) => img
                .write_registers(a, &[(and, or)], &mut s.outputs)
                .map(|()| Response::MaskWriteRegister(a, and, or)),
            _ => return Err(ExceptionCode::IllegalFunction),
        };
        r.map_err(|e| exception(&e))
    }
}

/// A served connection: closed after `idle` without a byte received; frees its place
/// under the connection cap when dropped.
struct Connection {
    stream: TcpStream,
    idle: Duration,
    deadline: Pin<Box<tokio::time::Sleep>>,
    active: Arc<AtomicUsize>,
    refusals: Arc<Refusals>,
    peer: SocketAddr,
}

impl Drop for Connection {
    fn drop(&mut self) {
        self.active.fetch_sub(1, Ordering::AcqRel);
    }
}

impl AsyncRead for Connection {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        let before = buf.filled().len();
        match Pin::new(&mut this.stream).poll_read(cx, buf) {
            Poll::Ready(r) => {
                if buf.filled().len() > before {
                    let next = tokio::time::Instant::now() + this.idle;
                    this.deadline.as_mut().reset(next);
                }
                Poll::Ready(r)
            }
            Poll::Pending => match this.deadline.as_mut().poll(cx) {
                Poll::Ready(()) => {
                    this.refusals.idle.fetch_add(1, Ordering::Relaxed);
                    tracing::info!(peer = %this.peer, "connection closed: silent for {} ms", this.idle.as_millis());
                    Poll::Ready(Err(io::Error::new(
                        io::ErrorKind::TimedOut,
                        "idle connection closed",
                    )))
                }
                Poll::Pending => Poll::Pending,
            },
        }
    }
}

impl AsyncWrite for Connection {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.get_mut().stream).poll_write(cx, buf)
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_flush(cx)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_shutdown(cx)
    }
}

/// Logs the 1st, 2nd, 4th, 8th… occurrence of a repeated event.
fn log_power_of_two(counter: &AtomicU64, what: impl FnOnce(u64)) {
    let n = counter.fetch_add(1, Ordering::Relaxed) + 1;
    if n.is_power_of_two() {
        what(n);
    }
}

/// What a server needs to accept a connection.
struct Acceptor {
    allow: Vec<IpAddr>,
    plc: Option<PlcEndpoint>,
    unit: u8,
    max: usize,
    idle: Duration,
    takeover_after: Duration,
    image: Arc<ServerImage>,
    shared: SharedImage,
    active: Arc<AtomicUsize>,
    refusals: Arc<Refusals>,
}

impl Acceptor {
    fn accept(&self, stream: TcpStream, peer: SocketAddr) -> Option<(Session, Connection)> {
        if !self.allow.contains(&peer.ip()) {
            tracing::warn!(%peer, "connection refused: not in the allow-list");
            return None;
        }
        let served = self.active.fetch_add(1, Ordering::AcqRel);
        if served >= self.max {
            self.active.fetch_sub(1, Ordering::AcqRel);
            log_power_of_two(&self.refusals.over_cap, |n| {
                tracing::warn!(%peer, "connection refused: {} clients already served (max_connections); {n} refused so far", self.max);
            });
            return None;
        }
        let _ = stream.set_nodelay(true);
        let plc = self.plc.is_some_and(|p| p.matches(peer));
        tracing::info!(%peer, plc, "client connected");
        let session = Session {
            peer,
            plc,
            unit: self.unit,
            takeover_after: self.takeover_after,
            image: Arc::clone(&self.image),
            shared: Arc::clone(&self.shared),
            refused: AtomicU64::new(0),
        };
        let conn = Connection {
            stream,
            idle: self.idle,
            deadline: Box::pin(tokio::time::sleep(self.idle)),
            active: Arc::clone(&self.active),
            refusals: Arc::clone(&self.refusals),
            peer,
        };
        Some((session, conn))
    }
}

/// Binds and starts a server over `image` and `shared`; `takeover_after` is the link
/// timeout (a PLC silent that long may write again from a new connection).
pub(crate) async fn start(
    config: &ServerConfig,
    image: ServerImage,
    shared: SharedImage,
    takeover_after: Duration,
) -> io::Result<ServerHandle> {
    let listener = tokio::net::TcpListener::bind(config.bind).await?;
    let local = listener.local_addr()?;
    let refusals = Arc::new(Refusals::default());
    let acceptor = Arc::new(Acceptor {
        allow: config.allow.clone(),
        plc: config.plc,
        unit: config.unit,
        max: config.max_connections.max(1),
        idle: Duration::from_millis(config.idle_timeout_ms.max(1)),
        takeover_after,
        image: Arc::new(image),
        shared,
        active: Arc::new(AtomicUsize::new(0)),
        refusals,
    });
    let task = tokio::spawn(async move {
        let server = Server::new(listener);
        let on_connected = |stream, peer: SocketAddr| {
            let accepted = acceptor.accept(stream, peer);
            async move { Ok(accepted) }
        };
        let on_error = |err: io::Error| {
            tracing::debug!("connection closed: {}", super::client::describe_io(&err))
        };
        let mut delay = Duration::from_millis(10);
        loop {
            let started = Instant::now();
            // `serve` returns only on an accept error (descriptors exhausted, …): the
            // connections it served are closed with it; retry once descriptors may be
            // free again.
            match server.serve(&on_connected, on_error).await {
                Ok(()) => break,
                Err(err) => {
                    if started.elapsed() > Duration::from_secs(1) {
                        delay = Duration::from_millis(10);
                    }
                    log_power_of_two(&acceptor.refusals.accept_errors, |n| {
                        tracing::error!(
                            "server on {local}: cannot accept a connection ({}); retrying in {} ms ({n} failures)",
                            super::client::describe_io(&err),
                            delay.as_millis()
                        );
                    });
                    tokio::time::sleep(delay).await;
                    delay = (delay * 2).min(Duration::from_secs(1));
                }
            }
        }
    });
    Ok(ServerHandle { local, task })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio_modbus::Slave;
    use tokio_modbus::client::{Context as Client, Reader as _, Writer as _};
    use tokio_modbus::prelude::SlaveContext as _;
    use vigie_core::live::iomap::IoMap;
    use vigie_core::plant::Plant;

    fn station() -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
    }

    /// A server for the station's map, PLC at 127.0.0.2, with `extra` server fields.
    async fn serve(extra: &str) -> (ServerHandle, SharedImage) {
        let plant = Plant::load(&station().join("plant.ron")).unwrap();
        let (map, _) = IoMap::load(&station().join("io-map.ron"), &plant).unwrap();
        let text = format!(
            "Gateway(mode: Emulator, plant: \".\", server: Modbus(bind: \"127.0.0.1:0\", allow: [\"127.0.0.1\", \"127.0.0.2\"], plc: \"127.0.0.2\"{extra}))"
        );
        let config =
            vigie_core::live::config::GatewayConfig::from_ron(&text, std::path::Path::new("t.ron"))
                .unwrap()
                .modbus_server()
                .unwrap()
                .clone();
        let shared: SharedImage = Arc::new(Mutex::new(Shared {
            inputs: Bits::zeros(11),
            outputs: Bits::zeros(7),
            ..Shared::default()
        }));
        let server = start(
            &config,
            ServerImage::new(&map, 1),
            Arc::clone(&shared),
            Duration::from_millis(200),
        )
        .await
        .unwrap();
        (server, shared)
    }

    async fn client_from(source: [u8; 4], server: SocketAddr) -> Client {
        let socket = tokio::net::TcpSocket::new_v4().unwrap();
        socket.bind((source, 0).into()).unwrap();
        let stream = socket.connect(server).await.unwrap();
        tokio_modbus::client::tcp::attach_slave(stream, Slave(1))
    }

    fn outputs(shared: &SharedImage) -> String {
        lock(shared).outputs.to_string()
    }

    fn rt() -> tokio::runtime::Runtime {
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap()
    }

    #[test]
    fn only_the_plc_endpoint_writes_one_connection_at_a_time_and_only_its_writes_keep_it_alive() {
        rt().block_on(async {
            let (server, shared) = serve("").await;
            // Another local program: it reads, its writes are refused, it keeps nothing alive.
            let mut other = client_from([127, 0, 0, 1], server.local).await;
            for _ in 0..5 {
                other.read_discrete_inputs(0, 11).await.unwrap().unwrap();
            }
            assert_eq!(lock(&shared).plc_heard, None, "reads keep nothing alive");
            assert_eq!(
                other.write_multiple_coils(0, &[true; 7]).await.unwrap(),
                Err(ExceptionCode::IllegalFunction)
            );
            assert_eq!(outputs(&shared), "0000000");
            // The PLC: its writes are served and are its liveness.
            let mut plc = client_from([127, 0, 0, 2], server.local).await;
            plc.read_discrete_inputs(0, 11).await.unwrap().unwrap();
            assert_eq!(
                lock(&shared).plc_heard,
                None,
                "a PLC that only reads is not alive"
            );
            plc.write_multiple_coils(0, &[true, false, false, false, false, false, false])
                .await
                .unwrap()
                .unwrap();
            assert!(lock(&shared).plc_heard.is_some());
            assert_eq!(outputs(&shared), "1000000");
            // A second connection from the PLC's address while the PLC writes: refused.
            let mut second = client_from([127, 0, 0, 2], server.local).await;
            assert_eq!(
                second.write_multiple_coils(0, &[true; 7]).await.unwrap(),
                Err(ExceptionCode::IllegalFunction)
            );
            assert_eq!(outputs(&shared), "1000000");
            // Units other than 1, broadcast 0 and 255 included: refused, never executed.
            for unit in [0, 2, 247, 255] {
                plc.set_slave(Slave(unit));
                assert_eq!(
                    plc.write_multiple_coils(0, &[true; 7]).await.unwrap(),
                    Err(ExceptionCode::GatewayTargetDevice),
                    "unit {unit}"
                );
                assert_eq!(
                    plc.read_coils(0, 7).await.unwrap(),
                    Err(ExceptionCode::GatewayTargetDevice),
                    "unit {unit}"
                );
            }
            assert_eq!(outputs(&shared), "1000000");
            // The first PLC connection closes: the second may write.
            drop(plc);
            let deadline = Instant::now() + Duration::from_secs(10);
            while lock(&shared).writer.is_some() {
                assert!(
                    Instant::now() < deadline,
                    "the closed writer was not released"
                );
                tokio::time::sleep(Duration::from_millis(2)).await;
            }
            second
                .write_multiple_coils(0, &[false, true, false, false, false, false, false])
                .await
                .unwrap()
                .unwrap();
            assert_eq!(outputs(&shared), "0100000");
        });
    }

    #[test]
    fn a_silent_writer_is_replaced_after_the_link_timeout() {
        rt().block_on(async {
            let (server, shared) = serve("").await;
            let mut first = client_from([127, 0, 0, 2], server.local).await;
            first.write_single_coil(0, true).await.unwrap().unwrap();
            let mut second = client_from([127, 0, 0, 2], server.local).await;
            assert_eq!(
                second.write_single_coil(1, true).await.unwrap(),
                Err(ExceptionCode::IllegalFunction)
            );
            // The first connection stays open but the PLC stops writing on it (a
            // half-open connection after a PLC restart): after the link timeout
            // (200 ms here) the new connection takes over.
            let deadline = Instant::now() + Duration::from_secs(10);
            loop {
                if second.write_single_coil(1, true).await.unwrap().is_ok() {
                    break;
                }
                assert!(Instant::now() < deadline, "never taken over");
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
            assert!(lock(&shared).plc_heard.unwrap().elapsed() < Duration::from_secs(1));
            assert_eq!(
                first.write_single_coil(2, true).await.unwrap(),
                Err(ExceptionCode::IllegalFunction),
                "the old connection is read-only now"
            );
        });
    }

    #[test]
    fn connections_over_the_cap_are_closed_and_idle_ones_time_out() {
        rt().block_on(async {
            let (server, _shared) = serve(", max_connections: 3, idle_timeout_ms: 300").await;
            let mut plc = client_from([127, 0, 0, 2], server.local).await;
            plc.read_discrete_inputs(0, 11).await.unwrap().unwrap();
            // Two more fill the cap; the rest of a flood is closed at once.
            let mut held = Vec::new();
            for _ in 0..2 {
                let mut c = client_from([127, 0, 0, 1], server.local).await;
                c.read_discrete_inputs(0, 1).await.unwrap().unwrap();
                held.push(c);
            }
            for _ in 0..50 {
                let mut c = client_from([127, 0, 0, 1], server.local).await;
                assert!(
                    c.read_discrete_inputs(0, 1).await.is_err(),
                    "a connection over the cap must be closed"
                );
            }
            // The PLC is still served through the flood.
            plc.read_discrete_inputs(0, 11).await.unwrap().unwrap();
            // Silent connections are closed after 300 ms, which frees their places.
            let deadline = Instant::now() + Duration::from_secs(10);
            loop {
                let mut c = client_from([127, 0, 0, 1], server.local).await;
                if c.read_discrete_inputs(0, 1).await.is_ok() {
                    break;
                }
                assert!(
                    Instant::now() < deadline,
                    "idle connections never timed out"
                );
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
            assert!(
                held[0].read_discrete_inputs(0, 1).await.is_err(),
                "an idle connection is closed"
            );
        });
    }
}
