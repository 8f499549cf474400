//! The pure half of the live link (Modbus TCP): what the networking code in the app
//! needs that can be written and tested without sockets or clocks.
//!
//! - [`iomap`]: the I/O map (area, address, unit, poll period, staleness bound per
//!   signal) and its loader.
//! - [`image`]: the register image ↔ [`crate::Bits`] mapping for clients (read and write
//!   plans) and servers ([`image::ServerImage`]).
//! - [`age`]: data age (refreshment and promptness), the link watchdog, the backoff.
//! - [`stale`]: how the filter treats stale inputs (existential quantification).
//! - [`config`]: the gateway configuration file.
//! - [`follow`]: the program the PLC should run, followed beside it (`--program`).
//!
//! Time enters only as [`crate::Millis`] parameters.

pub mod age;
pub mod config;
pub mod follow;
pub mod image;
pub mod iomap;
pub mod stale;

/// RON options of the live files: `Some(…)` may be left out around optional values.
pub(crate) fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
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
