//! Export to the PLC: IEC 61131-3 Structured Text ([`st`]) and an interpreter of the
//! generated subset ([`interp`]) used to check the export against the native engine.

pub mod interp;
pub mod st;

#[cfg(test)]
mod tests;
