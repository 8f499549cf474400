//! The Modbus TCP server Vigie is to a PLC (gateway mode) or to a soft-PLC (emulator
//! mode): it answers from a [`Shared`] image that the service loop keeps up to date.
//!
//! Security: the listener binds where the configuration says (loopback by default),
//! clients outside the allow-list are disconnected at once, and only the configured PLC
//! address may write; anyone else's write is refused with exception 01 (illegal
//! function). Illegal addresses and quantities get exceptions 02 and 03, unknown
//! functions 01, another unit id 0B; nothing a client sends can stop the server.

use std::net::{IpAddr, SocketAddr};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use tokio_modbus::prelude::{ExceptionCode, Request, Response, SlaveRequest};
use tokio_modbus::server::tcp::{Server, accept_tcp_connection};
use vigie_core::Bits;
use vigie_core::live::config::ServerConfig;
use vigie_core::live::image::{ImageError, ServerImage};
use vigie_core::live::iomap::Area;

/// The image a server shares with the loop that drives it.
#[derive(Debug, Default)]
pub(crate) struct Shared {
    /// Sensors served to readers.
    pub(crate) inputs: Bits,
    /// Actuators as last written by the PLC.
    pub(crate) outputs: Bits,
    /// When the PLC was last heard (any request).
    pub(crate) plc_heard: Option<Instant>,
    /// Requests answered with an exception.
    pub(crate) exceptions: u64,
}

/// A handle on the shared image.
pub(crate) type SharedImage = Arc<Mutex<Shared>>;

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
    writer: bool,
    unit: u8,
    image: Arc<ServerImage>,
    shared: SharedImage,
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

impl Session {
    fn handle(&self, req: SlaveRequest<'static>) -> Result<Response, ExceptionCode> {
        let SlaveRequest { slave, request } = req;
        let Ok(mut shared) = self.shared.lock() else {
            return Err(ExceptionCode::ServerDeviceFailure);
        };
        let shared = &mut *shared;
        if self.writer {
            shared.plc_heard = Some(Instant::now());
        }
        let result = self.answer(slave, request, shared);
        if result.is_err() {
            shared.exceptions += 1;
        }
        result
    }

    fn answer(
        &self,
        slave: u8,
        request: Request<'static>,
        s: &mut Shared,
    ) -> Result<Response, ExceptionCode> {
        if slave != self.unit && slave != 0 && slave != 255 {
            return Err(ExceptionCode::GatewayTargetDevice);
        }
        let img = &self.image;
        let is_write = matches!(
            request,
            Request::WriteSingleCoil(..)
                | Request::WriteMultipleCoils(..)
                | Request::WriteSingleRegister(..)
                | Request::WriteMultipleRegisters(..)
                | Request::MaskWriteRegister(..)
                | Request::ReadWriteMultipleRegisters(..)
        );
        if is_write && !self.writer {
            tracing::warn!(peer = %self.peer, "write refused: only the configured PLC address may write");
            return Err(ExceptionCode::IllegalFunction);
        }
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

/// Binds and starts a server over `image` and `shared`.
pub(crate) async fn start(
    config: &ServerConfig,
    image: ServerImage,
    shared: SharedImage,
) -> std::io::Result<ServerHandle> {
    let listener = tokio::net::TcpListener::bind(config.bind).await?;
    let local = listener.local_addr()?;
    let image = Arc::new(image);
    let allow: Vec<IpAddr> = config.allow.clone();
    let plc = config.plc;
    let unit = config.unit;
    let task = tokio::spawn(async move {
        let server = Server::new(listener);
        let on_connected = |stream, peer: SocketAddr| {
            let allowed = allow.contains(&peer.ip());
            let session = Session {
                peer,
                writer: plc == Some(peer.ip()),
                unit,
                image: Arc::clone(&image),
                shared: Arc::clone(&shared),
            };
            async move {
                if !allowed {
                    tracing::warn!(%peer, "connection refused: not in the allow-list");
                    return Ok(None);
                }
                tracing::info!(%peer, writer = session.writer, "client connected");
                let session = std::sync::Mutex::new(Some(session));
                accept_tcp_connection(stream, peer, move |_| {
                    Ok(session.lock().ok().and_then(|mut s| s.take()))
                })
            }
        };
        let on_error = |err: std::io::Error| tracing::debug!("connection closed: {err}");
        if let Err(err) = server.serve(&on_connected, on_error).await {
            tracing::error!("server on {local} stopped: {err}");
        }
    });
    Ok(ServerHandle { local, task })
}
