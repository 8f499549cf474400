//! Bad input end to end (issue 17): what `vigie check`, `filter`, `run`, `learn` and the
//! console do with an unprotected plant, a trace whose time goes backwards, a scenario
//! with absurd times, a conflicting constraint set, a duplicate signal, a 50 MiB file,
//! and what `vigie learn` keeps of `diagnosers.ron`. Fixtures: `tests/fixtures/bad-input/`.

#![allow(clippy::unwrap_used)] // test helpers: a failure is a test failure

use crate::vigie;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};
use vigie_app::{Console, ConsoleOptions};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn station() -> PathBuf {
    repo().join("layouts/sorting-station")
}

fn fixture(name: &str) -> PathBuf {
    repo().join("tests/fixtures/bad-input").join(name)
}

/// A copy of the sorting station in a fresh temporary folder.
pub(crate) fn station_copy(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vigie-bad-input-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    crate::paper::copy_dir(&station(), &dir);
    dir
}

fn text(out: &[u8]) -> String {
    String::from_utf8_lossy(out).into_owned()
}

fn json(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&out.stdout)))
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn check_warns_loudly_when_no_constraint_protects_the_plant() {
    let dir = station_copy("unprotected");
    let constraints = dir.join("constraints.txt");
    let d = path_str(&dir);
    for (setup, why) in [
        (
            Some("# CSs1 = 2P . A0 (commented out)\n\n"),
            "holds no constraint",
        ),
        (None, "does not exist"),
    ] {
        match setup {
            Some(t) => std::fs::write(&constraints, t).unwrap(),
            None => std::fs::remove_file(&constraints).unwrap(),
        }
        let warning = format!(
            "{}:1:1: warning[V0110]: the plant is unprotected: {} {why}, so the filter lets every command through",
            constraints.display(),
            constraints.display()
        );
        // Text: said first, in capitals, and again with the problems; accepted.
        let out = vigie(&["check", d]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let stdout = text(&out.stdout);
        assert_eq!(
            stdout.lines().next(),
            Some(
                format!(
                    "WARNING[V0110]: THE PLANT IS UNPROTECTED: {} {why}, so the filter lets every command through",
                    constraints.display()
                )
                .as_str()
            )
        );
        assert!(stdout.lines().any(|l| l == warning), "{stdout}");
        assert!(!stdout.contains("static checks passed"), "{stdout}");
        // JSON: a flag and the problem with its location.
        let out = vigie(&["check", d, "--json"]);
        assert!(out.status.success());
        let v = json(&out);
        assert_eq!(v["unprotected"], true);
        let problems = v["problems"].as_array().unwrap();
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert_eq!(problems[0]["code"], "V0110");
        assert_eq!(problems[0]["severity"], "warning");
        assert_eq!(problems[0]["location"]["file"], path_str(&constraints));
        assert_eq!(problems[0]["location"]["line"], 1);
    }
    // The station itself is protected.
    let out = vigie(&["check", path_str(&station()), "--json"]);
    assert_eq!(json(&out)["unprotected"], false);
    let out = vigie(&["check", path_str(&station())]);
    assert!(!text(&out.stdout).contains("UNPROTECTED"));
    let _ = std::fs::remove_dir_all(&dir);
}

fn console(plant: &Path) -> Harness<'static, Console> {
    let mut opts = ConsoleOptions::new(plant);
    opts.lang = vigie_app::i18n::Lang::En;
    opts.data_dir = None;
    Harness::builder()
        .with_size(egui::vec2(1600.0, 1000.0))
        .with_step_dt(1.0 / 60.0)
        .build_eframe(move |cc| {
            let mut c = Console::new(&opts).expect("console opens");
            c.setup(&cc.egui_ctx);
            c
        })
}

const BANNER: &str = "UNPROTECTED: no safety constraint, the filter lets every command through";

#[test]
fn the_console_shows_a_red_banner_when_no_constraint_protects_the_plant() {
    let dir = station_copy("console-unprotected");
    std::fs::write(dir.join("constraints.txt"), "# nothing\n").unwrap();
    // With the diagnosers (their generated stops are not safety constraints) and
    // without them.
    for diagnosers in [true, false] {
        if !diagnosers {
            std::fs::remove_file(dir.join("diagnosers.ron")).unwrap();
        }
        let mut h = console(&dir);
        h.run_steps(2);
        h.get_by_label(BANNER);
        assert_eq!(
            h.state().sim.bundle.unprotected().map(|p| p.code),
            Some("V0110")
        );
    }
    let mut h = console(&station());
    h.run_steps(2);
    assert!(h.query_by_label(BANNER).is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn check_points_a_specification_error_at_the_constraints_lines() {
    let dir = station_copy("conflict");
    std::fs::copy(
        fixture("constraints-conflict.txt"),
        dir.join("constraints.txt"),
    )
    .unwrap();
    let out = vigie(&["check", path_str(&dir), "--json"]);
    assert!(!out.status.success());
    let v = json(&out);
    let errors: Vec<&serde_json::Value> = v["problems"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["severity"] == "error")
        .collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!(errors[0]["code"], "V0107");
    assert_eq!(errors[0]["location"]["line"], 4);
    assert_eq!(errors[0]["location"]["column"], 1);
    let message = errors[0]["message"].as_str().unwrap();
    assert!(
        message.ends_with("(CSx2 on line 4, CSx1 on line 6, CSx3 on line 7)"),
        "{message}"
    );
    let out = vigie(&["check", path_str(&dir)]);
    let want = format!(
        "{}:4:1: error[V0107]: ",
        dir.join("constraints.txt").display()
    );
    assert!(text(&out.stdout).contains(&want), "{}", text(&out.stdout));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn check_reports_a_duplicate_signal_where_it_is_written() {
    let dir = station_copy("duplicate");
    std::fs::copy(fixture("plant-duplicate.ron"), dir.join("plant.ron")).unwrap();
    let out = vigie(&["check", path_str(&dir)]);
    assert!(!out.status.success());
    assert_eq!(
        text(&out.stderr).trim_end(),
        format!(
            "{}:9:17: error[V0011]: signal `C3` is declared twice (first on line 6)",
            dir.join("plant.ron").display()
        )
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn filter_refuses_a_trace_whose_time_goes_backwards_or_repeats() {
    let plant = path_str(&station()).to_string();
    for (name, want) in [
        (
            "trace-time-backwards.csv",
            "4:1: error[V0331]: time 15 ms goes backwards from 20 ms on line 3: the time of a trace must increase",
        ),
        (
            "trace-time-repeats.csv",
            "4:1: error[V0331]: time 20 ms repeats 20 ms on line 3: the time of a trace must increase",
        ),
        (
            "trace-repeated-column.csv",
            "1:64: error[V0330]: column `C4` appears twice in the trace header (first at column 21)",
        ),
    ] {
        let trace = fixture(name);
        let out = vigie(&["filter", &plant, "--trace", path_str(&trace)]);
        assert!(!out.status.success(), "{name}");
        assert!(out.stdout.is_empty(), "{name}: {}", text(&out.stdout));
        let stderr = text(&out.stderr);
        assert!(
            stderr.contains(&format!("{}:{want}", trace.display())),
            "{name}: {stderr}"
        );
    }
}

#[test]
fn run_refuses_absurd_scenario_times_at_their_values() {
    let scenario = fixture("scenario-bad-times.ron");
    let out = vigie(&["run", path_str(&scenario), "--headless"]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    let f = scenario.display();
    for want in [
        format!("{f}:10:15: error[V0401]: cycle_ms is 0 ms"),
        format!("{f}:8:50: error[V0404]: action Stop at 90000 ms is not before the end of the run"),
        format!("{f}:7:40: error[V0405]: period_ms is 0 ms"),
    ] {
        assert!(stderr.contains(&want), "{want}\n{stderr}");
    }
    // A run that would never end is refused at once.
    let scenario = fixture("scenario-endless.ron");
    let started = Instant::now();
    let out = vigie(&["run", path_str(&scenario), "--headless"]);
    assert!(started.elapsed() < Duration::from_secs(30));
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains(&format!(
            "{}:7:18: error[V0403]: duration_ms is 18446744073709551615 ms",
            scenario.display()
        )),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn a_50_mib_file_is_refused_quickly_by_check_and_learn() {
    let dir = station_copy("large");
    let d = path_str(&dir).to_string();
    for name in [
        "constraints.txt",
        "components.ron",
        "diagnosers.ron",
        "plant.ron",
    ] {
        let path = dir.join(name);
        let saved = std::fs::read(&path).unwrap();
        std::fs::File::create(&path)
            .unwrap()
            .set_len(50 * 1024 * 1024)
            .unwrap();
        let want = format!(
            "error[V0003]: {} is 52428800 bytes (50.0 MiB), more than the limit of 8388608 bytes (8 MiB): not read",
            path.display()
        );
        let started = Instant::now();
        let out = vigie(&["check", &d, "--json"]);
        assert!(started.elapsed() < Duration::from_secs(10), "{name}");
        assert!(!out.status.success(), "{name}");
        let v = json(&out);
        assert_eq!(v["problems"][0]["code"], "V0003", "{name}: {v}");
        let out = vigie(&["check", &d]);
        assert_eq!(text(&out.stderr).trim_end(), want, "{name}");
        if name == "diagnosers.ron" || name == "plant.ron" {
            let trace = fixture("trace-time-repeats.csv");
            let out = vigie(&[
                "diagnose",
                "learn",
                "--plant",
                &d,
                path_str(&trace),
                "--dry-run",
            ]);
            assert!(!out.status.success(), "{name}");
            assert!(
                text(&out.stderr).contains(&want),
                "{name}: {}",
                text(&out.stderr)
            );
        }
        std::fs::write(&path, saved).unwrap();
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `Ms(<n>)` → `Ms(_)`, so that two lines compare without their bounds.
fn without_bounds(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(k) = rest.find("Ms(") {
        out.push_str(&rest[..k + 3]);
        rest = &rest[k + 3..];
        let digits = rest.chars().take_while(char::is_ascii_digit).count();
        out.push('_');
        rest = &rest[digits..];
    }
    out.push_str(rest);
    out
}

#[test]
fn learn_rewrites_only_the_interval_bounds_of_diagnosers_ron() {
    let dir = station_copy("learn");
    let before = std::fs::read_to_string(dir.join("diagnosers.ron")).unwrap();
    // Two minutes of production recorded, then learned from.
    let scenario = dir.join("scenarios/learn-two-minutes.ron");
    std::fs::write(
        &scenario,
        "Scenario(name: \"learn\", program: Reference, seed: 3, actions: [(at_ms: 0, action: Start)], duration_ms: 120000)",
    )
    .unwrap();
    let trace = dir.join("trace.csv");
    let out = vigie(&[
        "run",
        path_str(&scenario),
        "--headless",
        "--trace",
        path_str(&trace),
        "--no-timing",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = vigie(&[
        "diagnose",
        "learn",
        "--plant",
        path_str(&dir),
        path_str(&trace),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let after = std::fs::read_to_string(dir.join("diagnosers.ron")).unwrap();
    assert_ne!(after, before, "nothing learned");
    // Same lines; a changed line differs only in its `Ms(..)` values, on an interval.
    let (b, a): (Vec<&str>, Vec<&str>) = (before.lines().collect(), after.lines().collect());
    assert_eq!(a.len(), b.len());
    for (x, y) in b.iter().zip(&a) {
        if x != y {
            assert!(x.trim_start().starts_with("(id: \"I"), "{x}");
            assert_eq!(without_bounds(x), without_bounds(y), "{x}\n{y}");
        }
    }
    assert_eq!(after.ends_with('\n'), before.ends_with('\n'));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `vigie bench` reads the scenarios of the plant's own figures from its `bench.ron`
/// (no scenario name in the code): a broken file is an error at its line and column,
/// before anything is measured; a `trip` scenario that never trips is said, not
/// measured on a frame that violates nothing.
#[test]
fn bench_reads_its_scenarios_from_the_plant_folder() {
    let dir = station_copy("bench");
    let d = path_str(&dir);
    // (bench.ron, what stderr says, nothing measured yet)
    for (bench, says, before_any_figure) in [
        (
            "(\n    production: Some(\"scenarios/reference-hour.ron\"),\n    trips: 3,\n)\n",
            "bench.ron:3:",
            true,
        ),
        (
            "(trip: Some(\"scenarios/reference-hour.ron\"))\n",
            "the filter never trips",
            false,
        ),
    ] {
        std::fs::write(dir.join("bench.ron"), bench).unwrap();
        let out = vigie(&["bench", "--plant", d, "--iterations", "101"]);
        let err = text(&out.stderr);
        assert!(!out.status.success());
        assert!(err.contains(says), "{err}");
        if before_any_figure {
            assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
        }
    }
}
