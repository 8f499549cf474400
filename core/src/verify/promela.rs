//! Promela export of the abstract model for the SPIN model checker.
