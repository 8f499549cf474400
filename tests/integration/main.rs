//! Integration tests: one binary.

mod console;
mod console_link;
mod diagnoser;
mod export_st;
mod fuzz_loaders;
mod live;
