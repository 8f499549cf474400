//! The Vigie operator console (egui): a thin shell over the core's state.
