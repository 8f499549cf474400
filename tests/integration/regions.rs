//! The plant's task monitor running the synthesised regions (`regions.ron` beside
//! `tasks.ron`, `vigie synthesize`; seed 000's `A*`): every committed regions file is
//! what its tasks give, a stale one is refused by the layout loader (V1503), and the
//! emulator's task alarms come from the regions.

use crate::live::{TempDir, repo};
use crate::vigie;
use std::path::Path;
use vigie_core::diag::codes;
use vigie_core::sim::{Options, Scenario, Simulation};
use vigie_core::tasks::{Alarm, AlarmCode};

/// A copy of a layout folder (files and sub-folders) in `to`.
fn copy_layout(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_layout(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}

/// Runs `scenario` of the plant folder `dir` in the emulator.
fn run(dir: &Path, scenario: &str) -> Simulation {
    let path = dir.join("scenarios").join(scenario);
    let s = Scenario::load(&path).unwrap();
    let mut sim = Simulation::from_scenario(&s, &path, Options::default()).unwrap();
    sim.run_until(vigie_core::time::Millis(s.duration_ms));
    sim
}

fn alarms(sim: &Simulation) -> Vec<Alarm> {
    sim.tasks.as_ref().unwrap().monitor.alarms.clone()
}

/// Every `regions.ron` committed beside a layout's `tasks.ron` is what `vigie
/// synthesize` gives today (a changed task makes CI fail here, as the loader would
/// refuse it).
#[test]
fn every_committed_regions_file_is_up_to_date() {
    let mut checked = Vec::new();
    let mut layouts: Vec<_> = std::fs::read_dir(repo().join("layouts"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("regions.ron").is_file())
        .collect();
    layouts.sort();
    for dir in layouts {
        let name = dir.file_name().unwrap().to_str().unwrap().to_string();
        let tasks = format!("layouts/{name}/tasks.ron");
        let out = vigie(&["synthesize", &tasks, "--check"]);
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success() && said.contains("is up to date"),
            "{name}: {said}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        checked.push(name);
    }
    assert_eq!(
        checked,
        [
            "liquid-supply",
            "production-line",
            "single-conveyor",
            "workshop"
        ]
    );
}

/// A task bound changed since the regions were synthesised: the layout loader refuses
/// them (V1503, naming the regions file and the command that makes them again), the
/// tasks are not run on the closed form instead, and the emulator does not start.
#[test]
fn a_stale_regions_file_is_refused_by_the_layout_loader() {
    let tmp = TempDir::new("stale-regions");
    let dir = tmp.0.join("workshop");
    copy_layout(&repo().join("layouts/workshop"), &dir);
    let tasks = std::fs::read_to_string(dir.join("tasks.ron")).unwrap();
    let changed = tasks.replace("gamma_ms: 5000", "gamma_ms: 6000");
    assert_ne!(changed, tasks);
    std::fs::write(dir.join("tasks.ron"), changed).unwrap();
    let (bundle, problems) = vigie_core::bundle::PlantBundle::load(&dir).unwrap();
    assert!(bundle.tasks.is_none());
    let stale: Vec<_> = problems
        .iter()
        .filter(|p| p.code == codes::REGIONS_STALE.id)
        .collect();
    assert_eq!(stale.len(), 1, "{problems:?}");
    let text = stale[0].to_string();
    let regions = dir.join("regions.ron");
    let command = format!("vigie synthesize {}", dir.join("tasks.ron").display());
    assert!(
        stale[0].is_error()
            && text.starts_with(&format!("{}:3:", regions.display()))
            && text.contains(&command),
        "{text}"
    );
    let path = dir.join("scenarios/thesis-scenario-1.ron");
    let s = Scenario::load(&path).unwrap();
    let Err(refused) = Simulation::from_scenario(&s, &path, Options::default()) else {
        panic!("the emulator started with stale regions");
    };
    assert!(
        refused.iter().any(|p| p.code == codes::REGIONS_STALE.id),
        "{refused:?}"
    );
    // `vigie check` says it too, and fails.
    let out = vigie(&["check", dir.to_str().unwrap()]);
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!out.status.success() && said.contains(&command), "{said}");
}

/// The emulator (the console's `Simulation`) runs the workshop's committed regions:
/// scenario 1 (the conveyor jammed as the second pallet is pushed at 4 s) alarms for
/// the conveyor at 6 s, as the thesis says. The instant is the regions': with the
/// conveyor's interruption tolerance made 1.5 s in a copy of `regions.ron` (its
/// `tasks.ron` unchanged, so its fingerprint holds), the same run alarms at 5.5 s, T009
/// (the regions left before the task's own bounds, 6 s).
#[test]
fn the_emulators_task_alarm_comes_from_the_regions() {
    let sim = run(&repo().join("layouts/workshop"), "thesis-scenario-1.ron");
    let monitor = &sim.tasks.as_ref().unwrap().monitor;
    assert!(monitor.regions().is_some(), "the workshop runs its regions");
    let a = alarms(&sim);
    assert_eq!(a.len(), 1, "{a:?}");
    assert_eq!(
        (a[0].code, a[0].subject.as_str()),
        (AlarmCode::T001, "conveyor")
    );
    assert!((6_000..=6_020).contains(&a[0].time.0), "{:?}", a[0]);

    let tmp = TempDir::new("tight-regions");
    let dir = tmp.0.join("workshop");
    copy_layout(&repo().join("layouts/workshop"), &dir);
    let regions = std::fs::read_to_string(dir.join("regions.ron")).unwrap();
    let tight = regions.replace(
        "0 <= conveyor.x - conveyor.y < 2000",
        "0 <= conveyor.x - conveyor.y < 1500",
    );
    assert_ne!(tight, regions);
    std::fs::write(dir.join("regions.ron"), tight).unwrap();
    let sim = run(&dir, "thesis-scenario-1.ron");
    let b = alarms(&sim);
    assert_eq!(b.len(), 1, "{b:?}");
    assert_eq!(
        (b[0].code, b[0].subject.as_str()),
        (AlarmCode::T009, "conveyor")
    );
    assert_eq!(a[0].time.0 - b[0].time.0, 500, "{:?} then {:?}", a[0], b[0]);
    // One 10 ms scan of motion before the jam: x − y reached the tightened 1.5 s.
    let (x, y) = (b[0].x_ms.unwrap(), b[0].y_ms.unwrap());
    assert_eq!(x - y, 1500, "{:?}", b[0]);
}
