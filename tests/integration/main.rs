//! Integration tests: one binary.

mod fuzz_loaders;
