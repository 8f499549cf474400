//! The generated Structured Text is checked by an independent IEC 61131-3 parser:
//! `blark` (PyPI, version pinned in `requirements-test.txt`), run from the Python venv
//! at `$VIGIE_VENV` or `<repo>/.venv`. A missing venv fails the test with the command
//! to create it: this check is never skipped.

use std::path::PathBuf;
use std::process::Command;
use vigie_core::bundle::PlantBundle;
use vigie_core::plant::Plant;
use vigie_core::tasks::TaskSet;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn blark() -> PathBuf {
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| repo().join(".venv"), PathBuf::from);
    let exe = venv.join("bin").join("blark");
    assert!(
        exe.is_file(),
        "\n\nblark is missing: {} does not exist.\nThe ST export test needs the pinned Python test tools. Create them with:\n\n    python3 -m venv {venv}\n    {venv}/bin/pip install -r {req}\n\n(or point VIGIE_VENV at a venv that has them).\n",
        exe.display(),
        venv = venv.display(),
        req = repo().join("requirements-test.txt").display()
    );
    exe
}

fn station_st() -> String {
    let dir = repo().join("layouts/sorting-station");
    let tasks = TaskSet::load(&dir.join("tasks.ron")).unwrap();
    let plant = Plant::load(&dir.join("plant.ron")).unwrap();
    let (bundle, _) = PlantBundle::from_plant(&dir, plant, &tasks.aux_names());
    vigie_core::export::st::generate(&bundle, Some(&tasks)).unwrap()
}

/// Parses `text` (saved as `name`) with blark: whether it parsed, and what blark said.
pub(crate) fn blark_parse(name: &str, text: &str) -> (bool, String) {
    let dir = std::env::temp_dir().join(format!("vigie-export-st-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join(name);
    std::fs::write(&file, text).unwrap();
    let out = Command::new(blark())
        .arg("parse")
        .arg("--summary")
        .arg(&file)
        .output()
        .unwrap_or_else(|e| panic!("cannot run blark: {e}"));
    let _ = std::fs::remove_file(&file);
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), log)
}

#[test]
fn generated_st_is_accepted_by_blark() {
    let text = station_st();
    let (ok, log) = blark_parse("sorting_station.st", &text);
    assert!(
        ok,
        "blark rejected the generated ST:\n{}",
        &log[log.len().saturating_sub(4000)..]
    );
    for pou in ["FB_Observers", "FB_Filter", "FB_Tasks", "Vigie_Safety"] {
        assert!(log.contains(pou), "blark's summary does not list {pou}");
    }
}

#[test]
fn blark_rejects_broken_st() {
    // Control: the check has teeth.
    let (ok, _) = blark_parse(
        "broken.st",
        "PROGRAM X\nVAR a : BOOL; END_VAR\na := := ;\nEND_PROGRAM\n",
    );
    assert!(!ok, "blark accepted invalid ST");
}
