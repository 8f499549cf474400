//! Modbus TCP (tokio-modbus): the client and the server of the live link. The cycle
//! does not see them (`super::link`).

pub(crate) mod client;
pub(crate) mod server;
