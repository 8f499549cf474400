//! Integration tests: one binary.

mod console;
mod diagnoser;
mod export_st;
mod fuzz_loaders;
mod live;
