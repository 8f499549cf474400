//! Integration tests: one binary.

// Test code: a failed unwrap is the test's failure (helpers included, which
// `allow-unwrap-in-tests` does not cover).
#![allow(clippy::unwrap_used)]

mod adversary;
mod bad_input;
mod cli;
mod console;
mod console_link;
mod diagnoser;
mod export_sfc;
mod export_st;
mod filter_trace;
mod fuzz_loaders;
mod live;
mod opcua;
mod plants;
mod polyhedra;
mod regions;
mod stpn;
mod transients;

#[path = "../../core/src/test_support/paper.rs"]
mod paper;

/// Runs the `vigie` binary from the repository root and waits for it.
pub(crate) fn vigie(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_vigie"))
        .args(args)
        .current_dir(live::repo())
        .output()
        .expect("vigie runs")
}

/// The paper's sorting station (no device monitoring), copied to `dir` (created): for
/// the tests that count its eleven sensors and seven coils, such as the link's
/// hardening against misbehaving peers.
pub(crate) fn paper_station_in(dir: &std::path::Path) -> std::path::PathBuf {
    paper::copy_dir(&live::repo().join("layouts/sorting-station"), dir);
    paper::strip_device_monitoring(dir);
    dir.to_path_buf()
}

/// The journal of the historian in `dir` (`vigie.sqlite`), one JSON object per line
/// (`wall_ms`, `sim_ms`, `kind`, `text`), oldest first; empty when there is none.
pub(crate) fn historian_journal(dir: &std::path::Path) -> String {
    // Read only: a reader that opened it read-write could race the writer's own start.
    let Some(store) = vigie_app::historian::Store::open_read_only(dir).expect("historian opens")
    else {
        return String::new();
    };
    store
        .journal(0, "", usize::MAX >> 1)
        .expect("journal reads")
        .iter()
        .map(|r| serde_json::to_string(r).expect("row as JSON") + "\n")
        .collect()
}
