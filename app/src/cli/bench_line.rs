//! `vigie bench-line`: the cost of the closed loop against the size of the plant
//! (issue 16: lines of 1, 10 and 100 stations, cost linear in the number of
//! components).
//!
//! The lines are plant folders written as data into a temporary folder, as a user
//! would write them, then loaded and run by the same code as any plant in `layouts/`:
//! no engine knows it is being measured. A station is a belt with an entry and an end
//! beam and a monostable stamp above the belt's end with its two end sensors; the
//! belts are chained (`To`), the first is fed by the line's feeder, the last ends in a
//! sink. Each station's chart waits for a workpiece, carries it under the stamp, stamps
//! it and hands it on; its constraint forbids stamping on a moving belt. The signal
//! names are generated (`s001_belt`); they are no plant's.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Arguments of `vigie bench-line`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// Line sizes measured, in stations (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 10, 100])]
    pub(crate) stations: Vec<usize>,
    /// Simulated seconds per line.
    #[arg(long, default_value_t = 600)]
    pub(crate) seconds: u64,
    /// Keep the generated plant folders in this folder (default: a temporary folder,
    /// deleted at the end).
    #[arg(long)]
    pub(crate) keep: Option<PathBuf>,
}

/// A station's id: `s001`.
fn sid(k: usize) -> String {
    format!("s{k:03}")
}

/// The texts of a line's files, as they grow station by station.
#[derive(Default)]
struct Texts {
    signals: String,
    components: String,
    constraints: String,
    charts: String,
    inputs: usize,
    coils: usize,
}

impl Texts {
    fn sensor(&mut self, id: &str, what: &str, element: &str) {
        let _ = writeln!(
            self.signals,
            "    (id: \"{id}\", kind: Sensor, description: \"{what}\", element: \"{element}\", address: Some(DiscreteInput({}))),",
            self.inputs
        );
        self.inputs += 1;
    }

    fn actuator(&mut self, id: &str, what: &str, element: &str) {
        let _ = writeln!(
            self.signals,
            "    (id: \"{id}\", kind: Actuator, description: \"{what}\", element: \"{element}\", address: Some(Coil({})), safe: Zero),",
            self.coils
        );
        self.coils += 1;
    }

    /// Station `k` of `n`: its signals, its belt and stamp, its constraint, its chart.
    fn station(&mut self, k: usize, n: usize) {
        let s = sid(k);
        let element = format!("Station {k}");
        self.sensor(
            &format!("{s}_in"),
            "Workpiece at the belt's entry",
            &element,
        );
        self.sensor(&format!("{s}_at"), "Workpiece under the stamp", &element);
        self.sensor(&format!("{s}_up"), "Stamp up", &element);
        self.sensor(&format!("{s}_down"), "Stamp down", &element);
        self.actuator(&format!("{s}_belt"), "Belt motor", &element);
        self.actuator(&format!("{s}_stamp"), "Stamp valve (monostable)", &element);
        let feed = if k == 1 {
            "feed: Some((when: \"line_feed\", items: [(class: \"part\", length: 40.0, tags: [])])),"
        } else {
            ""
        };
        let exit = if k == n {
            "Sink".to_string()
        } else {
            format!("To(\"{}_belt\")", sid(k + 1))
        };
        let _ = writeln!(
            self.components,
            "    (id: \"{s}_belt\", name: \"Belt {k}\", kind: Conveyor((length: 400.0, drives: [(when: \"{s}_belt\", speed: 400.0)], sensors: [(signal: \"{s}_in\", at: 20.0), (signal: \"{s}_at\", at: 385.0)], {feed} exit: {exit}))),"
        );
        let _ = writeln!(
            self.components,
            "    (id: \"{s}_stamp\", name: \"Stamp {k}\", kind: Axis((min: 0.0, max: 20.0, start: 0.0, variation_ppm: 10000, tolerance_ms: 40, drives: [(when: \"{s}_stamp\", speed: 100.0), (when: \"/{s}_stamp\", speed: -100.0)], sensors: [(signal: \"{s}_up\", from: 0.0, to: 1.0), (signal: \"{s}_down\", from: 19.0, to: 20.0)]))),"
        );
        let _ = writeln!(
            self.constraints,
            "CS{s} = {s}_stamp . {s}_belt    # no stamping on a moving belt"
        );
        // Wait; carry to the stamp; stamp; lift; hand on when the next station waits.
        let next_waits = if k == n {
            String::new()
        } else {
            format!(" . {}_w", sid(k + 1))
        };
        let _ = writeln!(
            self.charts,
            r#"        Chart(name: "{s}", steps: [
            Step(id: "{s}_w", initial: true),
            Step(id: "{s}_c", actions: [Action(qualifier: N, target: "{s}_belt")]),
            Step(id: "{s}_s", actions: [Action(qualifier: N, target: "{s}_stamp")]),
            Step(id: "{s}_l"),
            Step(id: "{s}_h", actions: [Action(qualifier: N, target: "{s}_belt")]),
        ], transitions: [
            Transition(id: "{s}_t1", from: ["{s}_w"], to: ["{s}_c"], condition: "{s}_in"),
            Transition(id: "{s}_t2", from: ["{s}_c"], to: ["{s}_s"], condition: "{s}_at"),
            Transition(id: "{s}_t3", from: ["{s}_s"], to: ["{s}_l"], condition: "{s}_down"),
            Transition(id: "{s}_t4", from: ["{s}_l"], to: ["{s}_h"], condition: "{s}_up{next_waits}"),
            Transition(id: "{s}_t5", from: ["{s}_h"], to: ["{s}_w"], condition: "FE({s}_at)"),
        ]),"#
        );
    }
}

/// Writes the plant folder of a line of `n` stations into `dir`.
pub(crate) fn write_line(dir: &Path, n: usize, duration_ms: u64) -> std::io::Result<()> {
    std::fs::create_dir_all(dir.join("programs"))?;
    std::fs::create_dir_all(dir.join("scenarios"))?;
    let mut t = Texts::default();
    t.sensor("line_start", "Line start button", "Panel");
    t.actuator(
        "line_feed",
        "Feeder: places a workpiece on the first belt",
        "Panel",
    );
    let _ = writeln!(
        t.components,
        "    (id: \"start_button\", name: \"Line start\", kind: Button((signal: \"line_start\", pulse_ms: 300))),"
    );
    for k in 1..=n {
        t.station(k, n);
    }
    let Texts {
        signals,
        components,
        constraints,
        charts,
        ..
    } = t;
    let first = sid(1);
    std::fs::write(
        dir.join("plant.ron"),
        format!(
            "// Generated by `vigie bench-line`: a line of {n} stations.\nPlant(\n  name: \"Line of {n} stations\",\n  description: \"Belts with a stamp each, chained (vigie bench-line).\",\n  signals: [\n{signals}  ],\n)\n"
        ),
    )?;
    std::fs::write(
        dir.join("components.ron"),
        format!(
            "Components(\n  name: \"Line of {n} stations\",\n  components: [\n{components}  ],\n)\n"
        ),
    )?;
    std::fs::write(dir.join("constraints.txt"), constraints)?;
    std::fs::write(
        dir.join("programs/reference.ron"),
        format!(
            r#"Program(
    name: "Line of {n} stations: reference",
    description: "Start: the feeder places a workpiece whenever the first station waits; each station stamps it and hands it on.",
    panel: [],
    start: Some("line_start"),
    stop: None,
    memories: [],
    timers: [],
    charts: [
        Chart(name: "line", steps: [Step(id: "run0", initial: true), Step(id: "run1")], transitions: [
            Transition(id: "trun", from: ["run0"], to: ["run1"], condition: "RE(line_start)"),
        ]),
        Chart(name: "feeder", steps: [
            Step(id: "f0", initial: true),
            Step(id: "f1", actions: [Action(qualifier: N, target: "line_feed")]),
        ], transitions: [
            Transition(id: "tf1", from: ["f0"], to: ["f1"], condition: "run1 . {first}_w . /{first}_in"),
            Transition(id: "tf2", from: ["f1"], to: ["f0"], condition: "{first}_in"),
        ]),
{charts}    ],
    equations: [],
)
"#
        ),
    )?;
    std::fs::write(
        dir.join("scenarios/production.ron"),
        format!(
            "Scenario(\n  name: \"Line of {n} stations: production\",\n  description: \"Start, then production.\",\n  program: Reference,\n  seed: 1,\n  actions: [(at_ms: 500, action: Start)],\n  duration_ms: {duration_ms},\n)\n"
        ),
    )?;
    Ok(())
}

/// One line's figures.
struct Figures {
    stations: usize,
    components: usize,
    signals: usize,
    sim_s: f64,
    wall_s: f64,
    produced: u64,
    trips: usize,
    hazards: usize,
}

fn measure(dir: &Path, n: usize, duration_ms: u64) -> anyhow::Result<Figures> {
    use vigie_core::sim::{Options, Scenario, Simulation};
    write_line(dir, n, duration_ms)?;
    let path = dir.join("scenarios/production.ron");
    let scenario =
        Scenario::load(&path).map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let mut sim = Simulation::from_scenario(&scenario, &path, Options::default())
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let start = Instant::now();
    sim.run_until(vigie_core::Millis(duration_ms));
    let wall_s = start.elapsed().as_secs_f64();
    let plant = &sim.bundle.plant;
    Ok(Figures {
        stations: n,
        components: 2 * n + 1,
        signals: plant.inputs.len() + plant.outputs.len(),
        #[allow(clippy::cast_precision_loss)]
        sim_s: duration_ms as f64 / 1000.0,
        wall_s,
        produced: sim.produced(),
        trips: sim.engine.trips.len(),
        hazards: sim.emulator.hazards().len(),
    })
}

pub(crate) fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let root = match &args.keep {
        Some(d) => d.clone(),
        None => std::env::temp_dir().join(format!("vigie-bench-line-{}", std::process::id())),
    };
    let duration_ms = args.seconds.max(1) * 1000;
    let mut rows = Vec::new();
    for &n in &args.stations {
        anyhow::ensure!(n >= 1, "a line has at least one station");
        let dir = root.join(format!("line-{n}"));
        rows.push(measure(&dir, n, duration_ms)?);
    }
    if args.keep.is_none() {
        let _ = std::fs::remove_dir_all(&root);
    }
    println!(
        "closed loop (emulator + reference program + filter + monitors) on generated lines, {} simulated s each:",
        args.seconds
    );
    println!(
        "  stations  components  signals   simulated/wall   wall us per simulated s per component   items out  trips  hazards"
    );
    let mut per: Vec<(usize, f64)> = Vec::new();
    for f in &rows {
        #[allow(clippy::cast_precision_loss)]
        let us = f.wall_s * 1e6 / f.sim_s / f.components as f64;
        per.push((f.stations, us));
        println!(
            "  {:>8}  {:>10}  {:>7}   {:>13.0}x   {:>37.2}   {:>9}  {:>5}  {:>7}",
            f.stations,
            f.components,
            f.signals,
            f.sim_s / f.wall_s,
            us,
            f.produced,
            f.trips,
            f.hazards
        );
    }
    if let (Some(a), Some(b)) = (per.first(), per.last())
        && b.0 > a.0
    {
        println!(
            "  cost per component, {} stations against {}: {:.2}x   goal: linear (about 1x)",
            b.0,
            a.0,
            b.1 / a.1
        );
    }
    if rows.iter().any(|f| f.trips > 0 || f.hazards > 0) {
        eprintln!("a generated line tripped or was damaged: the figures measure a broken run");
        return Ok(ExitCode::FAILURE);
    }
    if rows.iter().any(|f| f.produced == 0) {
        eprintln!(
            "a generated line delivered nothing in {} s: a workpiece takes about 1.5 s per station, give --seconds more",
            args.seconds
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The generated lines are plants like any other: they load, produce without a
    /// trip or a hazard, and every station's workpiece reaches the sink.
    #[test]
    fn a_generated_line_produces_through_every_station() {
        for n in [1, 3] {
            let dir =
                std::env::temp_dir().join(format!("vigie-line-test-{}-{n}", std::process::id()));
            let f = measure(&dir, n, 60_000).unwrap();
            let _ = std::fs::remove_dir_all(&dir);
            assert_eq!(f.trips, 0, "{n} stations");
            assert_eq!(f.hazards, 0, "{n} stations");
            assert!(f.produced >= 10, "{n} stations: {} out", f.produced);
            assert_eq!(f.signals, 2 + 6 * n);
        }
    }
}
