//! The pure half of the live link (Modbus TCP): what the networking code in the app
//! needs that can be written and tested without sockets or clocks.
//!
//! - [`iomap`]: the I/O map (area, address, unit, poll period, staleness bound per
//!   signal) and its loader.
//! - [`image`]: the register image ↔ [`crate::Bits`] mapping for clients (read and write
//!   plans) and servers ([`image::ServerImage`]).
//! - [`age`]: data age (refreshment and promptness), the link watchdog, the backoff.
//! - [`stale`]: how the filter treats stale inputs (existential quantification).
//! - [`config`]: the gateway configuration file; [`opcua`]: its OPC UA sections.
//! - [`nodemap`]: the OPC UA node map (node id or browse path per signal).
//! - [`follow`]: the program the PLC should run, followed beside it (`--program`).
//!
//! Time enters only as [`crate::Millis`] parameters.

pub mod age;
pub mod config;
pub mod follow;
pub mod image;
pub mod iomap;
pub mod nodemap;
pub mod opcua;
pub mod stale;

/// RON options of the live files: `Some(…)` may be left out around optional values.
pub(crate) fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(
        ron::extensions::Extensions::IMPLICIT_SOME
            | ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES,
    )
}

/// Reads a RON file with [`ron_options`]: the value and its text (to place problems).
pub(crate) fn load_ron<T: serde::de::DeserializeOwned>(
    path: &std::path::Path,
) -> Result<(T, String), Vec<crate::diag::Problem>> {
    let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
    let value = ron_options()
        .from_str(&text)
        .map_err(|e| vec![crate::diag::ron_problem(path, &e)])?;
    Ok((value, text))
}

#[cfg(test)]
mod tests;

/// Where one side of the link finds the plant's signals: the Modbus I/O map or the OPC
/// UA node map. The cycle only reads the staleness bounds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LinkMap {
    /// Modbus TCP addresses.
    Modbus(iomap::IoMap),
    /// OPC UA nodes.
    OpcUa(nodemap::NodeMap),
}

impl LinkMap {
    /// Staleness bounds of the inputs, in input order.
    pub fn input_bounds(&self) -> Vec<crate::Millis> {
        match self {
            Self::Modbus(m) => m.input_bounds(),
            Self::OpcUa(m) => m.input_bounds(),
        }
    }

    /// The smallest poll period.
    pub fn fastest_poll(&self) -> crate::Millis {
        match self {
            Self::Modbus(m) => m.fastest_poll(),
            Self::OpcUa(m) => m.fastest_poll(),
        }
    }

    /// The number of outputs mapped (every output of the plant).
    pub fn outputs(&self) -> usize {
        match self {
            Self::Modbus(m) => m.outputs.len(),
            Self::OpcUa(m) => m.outputs.len(),
        }
    }
}
