//! Integration tests: one binary.

mod export_st;
mod fuzz_loaders;
mod live;
