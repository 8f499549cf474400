//! Integration tests: one binary.

mod export_st;
