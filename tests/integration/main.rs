//! Integration tests: one binary.

mod live;
