//! OPC UA (async-opcua): the client and the server of the live link, and the
//! certificates. The same contract as the Modbus adapter (`super::modbus`); the cycle
//! sees neither (`super::link`).

pub(crate) mod client;
pub(crate) mod pki;
pub(crate) mod server;
