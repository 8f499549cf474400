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
    // The mirror contacts follow the outputs one cycle late; the safety contactor and
    // valve are closed.
    let header = "time_ms,C0,C1,C2,C3,C4,C5,C6,C7,C8,C9,C10,A0,A1,A2,A3,A4,A5,A6,\
                  A0_fb,A1_fb,A2_fb,A3_fb,A4_fb,A5_fb,A6_fb,KM0_fb,YV0_fb,KM0,YV0\n";
    let held = "0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,1,0,0,0,0,0,0,1,0,0,1,1,1,1\n\
                10,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,1,0,0,0,0,0,0,1,0,0,1,1,1,1\n";
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
    let later = "20,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1,0,0,1,1,1,1\n\
                 30,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,1,1,1,1\n";
    let (ok, out) = filter(&format!("{header}{held}{later}"), &[]);
    assert!(ok, "{out}");
    assert!(out.contains("CSs14"), "{out}");
}

/// A plant whose constraints read 36 variables: `vigie check` proves the fallback per
/// output component, names the component whose own support is too large (26
/// variables) as not proved, and never claims more, in text and JSON.
#[test]
fn check_states_what_it_proved_and_what_it_could_not_on_a_large_plant() {
    let dir = TempDir::new("check-large");
    let mut signals = String::new();
    for i in 0..36 {
        signals.push_str(&format!(
            "(id: \"S{i}\", kind: Sensor, description: \"sensor {i}\"),\n"
        ));
    }
    for k in 0..6 {
        signals.push_str(&format!(
            "(id: \"Q{k}\", kind: Actuator, description: \"actuator {k}\"),\n"
        ));
    }
    std::fs::write(
        dir.0.join("plant.ron"),
        format!("Plant(name: \"large\", signals: [\n{signals}])\n"),
    )
    .unwrap();
    std::fs::write(dir.0.join("observers.ron"), "(observers: [])\n").unwrap();
    // Q0 and Q1 are linked by combined constraints reading S0..S25; Q2..Q5 each by
    // simple constraints on the other sensors.
    let mut text = String::new();
    for i in 0..13 {
        text.push_str(&format!(
            "CSc{i} = S{} . S{} . Q0 . /Q1\n",
            2 * i,
            2 * i + 1
        ));
    }
    for (n, i) in (26..36).enumerate() {
        text.push_str(&format!("CSs{n} = S{i} . Q{}\n", 2 + n % 4));
    }
    std::fs::write(dir.0.join("constraints.txt"), text).unwrap();
    let run = |json: bool| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_vigie"));
        cmd.arg("check").arg(&dir.0);
        if json {
            cmd.arg("--json");
        }
        let out = cmd.output().unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr)
    };
    let text = run(false);
    assert!(text.contains("the constraints read 36 variables"), "{text}");
    assert!(
        text.contains("Q0,Q1") && text.contains("support  26  NOT PROVED"),
        "{text}"
    );
    assert!(
        text.contains("Q2") && text.contains("proved: a fallback in every reachable context"),
        "{text}"
    );
    assert!(text.contains("NOT PROVED for every context"), "{text}");
    assert!(
        !text.contains("a fallback exists in every reachable context, every name"),
        "never claims what it did not prove: {text}"
    );
    let json: serde_json::Value = serde_json::from_str(&run(true)).unwrap();
    assert_eq!(json["fallback"]["method"], "not_proved");
    assert_eq!(json["fallback"]["support"], 36);
    let comps = json["fallback"]["components"].as_array().unwrap();
    let q01 = comps.iter().find(|c| c["outputs"][0] == "Q0").unwrap();
    assert_eq!(
        (q01["support"].as_u64(), q01["proved"].as_bool()),
        (Some(26), Some(false))
    );
    assert!(comps.iter().filter(|c| c["proved"] == true).count() >= 4);
}
