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
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// RON options of the gateway configuration: also `Modbus(address: …)` for the
/// newtype variant `Modbus(ClientConfig)` (without doubled parentheses). Not for the
/// other files: it reads `Some((0, 2000))` as a tuple variant's fields.
pub(crate) fn config_ron_options() -> ron::Options {
    ron_options().with_default_extension(
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

/// A signal placed on a link: how often it is read, how old it may get.
pub(crate) trait Placed {
    /// Its read period.
    fn poll(&self) -> crate::Millis;
    /// Its staleness bound.
    fn max_age(&self) -> crate::Millis;
}

/// The smallest read period of a map's signals (10 ms for an empty map).
pub(crate) fn fastest_poll<'a, T: Placed + 'a>(
    signals: impl Iterator<Item = &'a T>,
) -> crate::Millis {
    signals.map(Placed::poll).min().unwrap_or(crate::Millis(10))
}

/// The staleness bounds of a map's inputs, in input order.
pub(crate) fn input_bounds<'a, T: Placed + 'a>(
    inputs: impl Iterator<Item = &'a T>,
) -> Vec<crate::Millis> {
    inputs.map(Placed::max_age).collect()
}

/// The plant's signals a map leaves unmapped (`inputs` and `outputs` indexed like the
/// plant's), as one problem at the top of the map's file.
pub(crate) fn unmapped<T>(
    plant: &crate::plant::Plant,
    inputs: &[Option<T>],
    outputs: &[Option<T>],
    path: &std::path::Path,
) -> Option<crate::diag::Problem> {
    let missing: Vec<&str> = plant
        .inputs
        .iter()
        .zip(inputs)
        .chain(plant.outputs.iter().zip(outputs))
        .filter(|(_, m)| m.is_none())
        .map(|(s, _)| s.id.as_str())
        .collect();
    (!missing.is_empty()).then(|| {
        crate::diag::Problem::error(
            crate::diag::codes::IO_MAP_UNMAPPED.id,
            format!("signals not mapped: {}", missing.join(", ")),
            Some(crate::diag::Location::new(path, 1, 1)),
        )
    })
}

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
