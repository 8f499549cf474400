//! Integration tests: one binary.

mod adversary;
mod bad_input;
mod console;
mod console_link;
mod diagnoser;
mod export_st;
mod filter_trace;
mod fuzz_loaders;
mod live;
mod transients;
