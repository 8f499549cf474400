//! `vigie filter --trace` on a trace recorded mid-production.

#![allow(clippy::unwrap_used)] // test helpers: a failure is a test failure

use crate::live::{TempDir, repo};
use std::process::Command;

fn filter(trace: &str, extra: &[&str]) -> (bool, String) {
    let dir = TempDir::new("filter-trace");
    let path = dir.0.join("t.csv");
    std::fs::write(&path, trace).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_vigie"))
        .arg("filter")
        .arg(repo().join("layouts/sorting-station"))
        .arg("--trace")
        .arg(&path)
        .args(extra)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr),
    )
}

/// The (empty) table already at its unloading position with A4 held when the recording
/// starts: attaching (the default) reads no edge on the first row; `--cold-start` reads
/// a rising edge of A4 away from C4 and trips on CSs14. A real edge later trips both.
#[test]
fn a_trace_recorded_mid_production_does_not_trip_on_its_first_row() {
    let header = "time_ms,C0,C1,C2,C3,C4,C5,C6,C7,C8,C9,C10,A0,A1,A2,A3,A4,A5,A6\n";
    let held = "0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,1,0,0\n10,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,1,0,0\n";
    let (ok, out) = filter(&format!("{header}{held}"), &[]);
    assert!(ok, "{out}");
    assert!(
        out.trim().is_empty(),
        "no trip expected when attaching: {out}"
    );
    let (ok, out) = filter(&format!("{header}{held}"), &["--cold-start"]);
    assert!(ok, "{out}");
    assert!(
        out.contains("CSs14"),
        "a cold start sees RE(A4) away from C4: {out}"
    );
    // Released at C5 (allowed), then pressed again on the way back, away from C4: a
    // real edge, a trip either way.
    let later = "20,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0\n30,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1,0,0\n";
    let (ok, out) = filter(&format!("{header}{held}{later}"), &[]);
    assert!(ok, "{out}");
    assert!(out.contains("CSs14"), "{out}");
}
