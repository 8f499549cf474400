//! `vigie bench`: the figures the issues ask for, measured on this machine.
//!
//! Each figure is the median over batches of the mean time per iteration in a batch.

use std::hint::black_box;
use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;
use vigie_core::filter::Filter;
use vigie_core::frame::Frame;
use vigie_core::symbols::Space;

/// Median of per-iteration nanoseconds over `batches` batches of `per_batch` calls.
pub(crate) fn median_ns(batches: u32, per_batch: u32, mut f: impl FnMut()) -> f64 {
    let mut samples: Vec<f64> = (0..batches.max(1))
        .map(|_| {
            let start = Instant::now();
            for _ in 0..per_batch.max(1) {
                f();
            }
            start.elapsed().as_secs_f64() * 1e9 / f64::from(per_batch.max(1))
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

/// `bench.ron` in the plant folder: the scenarios the plant's own figures run (paths
/// relative to the plant folder). Without the file those figures are skipped, said.
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct BenchFile {
    /// Production without a trip, timed as a closed loop (simulated / wall time).
    #[serde(default)]
    pub(crate) production: Option<std::path::PathBuf>,
    /// A scenario that trips the filter: the filter cycle is timed on its last frame
    /// before the trip and on the tripping frame, and the explanation of the trip.
    #[serde(default)]
    trip: Option<std::path::PathBuf>,
}

pub(crate) fn bench_file(plant_dir: &Path) -> anyhow::Result<BenchFile> {
    let path = plant_dir.join("bench.ron");
    if !path.exists() {
        return Ok(BenchFile::default());
    }
    let text = std::fs::read_to_string(&path)?;
    ron::Options::default().from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{}:{}:{}: {}",
            path.display(),
            e.span.start.line,
            e.span.start.col,
            e.code
        )
    })
}

fn load_scenario(path: &Path) -> anyhow::Result<vigie_core::sim::Scenario> {
    vigie_core::sim::Scenario::load(path)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))
}

/// The frames of the trip scenario: the last one before the first trip (the outputs
/// as commanded and applied) and the tripping one (the outputs as commanded, which
/// violate), with the violated constraints and the outputs the engine applied.
struct TripFrames {
    before: Frame,
    trip: Frame,
    violated: Vec<String>,
    applied: vigie_core::bits::Bits,
}

fn trip_frames(path: &Path) -> anyhow::Result<TripFrames> {
    use vigie_core::sim::{Options, Simulation};
    let scenario = load_scenario(path)?;
    let mut sim = Simulation::from_scenario(&scenario, path, Options::default())
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let end = vigie_core::Millis(scenario.duration_ms);
    let mut before = sim.engine.frame().clone();
    while sim.now() < end && sim.engine.trips.is_empty() {
        before = sim.engine.frame().clone();
        sim.cycle();
    }
    let Some(t) = sim.engine.trips.first() else {
        anyhow::bail!("{}: the filter never trips", path.display());
    };
    let violated = t.constraints.iter().map(|c| c.id.clone()).collect();
    let mut trip = sim.engine.frame().clone();
    let commanded = sim.engine.commanded().clone();
    trip.now_mut(Space::Output).copy_from(&commanded);
    Ok(TripFrames {
        before,
        trip,
        violated,
        applied: sim.engine.applied().clone(),
    })
}

pub(crate) fn run(plant_dir: &Path, iterations: u32) -> anyhow::Result<ExitCode> {
    let mut out = std::io::stdout().lock();
    let (bundle, _) = super::load_bundle(plant_dir)?;
    // As the engine compiles it: with the plant's safe values (a safety contactor's
    // `safe: One` is part of the fallback).
    let filter = Filter::for_plant(&bundle.constraints, &bundle.plant);
    let batches = 101;
    let per_batch = (iterations / batches).max(1);
    let files = bench_file(plant_dir)?;

    writeln!(
        out,
        "{} ({} sensors, {} actuators, {} observers, {} constraints)",
        bundle.plant.name,
        bundle.plant.inputs.len(),
        bundle.plant.outputs.len(),
        bundle.observers.defs.len(),
        bundle.constraints.constraints.len()
    )?;
    match &files.trip {
        None => writeln!(
            out,
            "  filter cycle: no `trip` scenario in {}/bench.ron, not measured",
            plant_dir.display()
        )?,
        Some(trip_path) => bench_trip(
            &mut out,
            &bundle,
            &filter,
            &plant_dir.join(trip_path),
            (batches, per_batch),
        )?,
    }

    bench_synthetic(&mut out, iterations)?;
    match &files.production {
        Some(p) => closed_loop(&mut out, &plant_dir.join(p))?,
        None => writeln!(
            out,
            "closed loop: no `production` scenario in {}/bench.ron, not measured",
            plant_dir.display()
        )?,
    }
    if let Some(p) = &files.production {
        plcopen_scan(&mut out, &plant_dir.join(p))?;
    }
    task_monitors(&mut out)?;
    if let Some(trip) = &files.trip
        && let Some((ms, worst)) = explanations_ms(&plant_dir.join(trip), 21)?
    {
        writeln!(
            out,
            "explanations: five levels with 10 s projection:   {ms:>10.2} ms   goal <= 20 ms (the trip of {})",
            trip.display()
        )?;
        writeln!(
            out,
            "  (projection running the whole 10 s, no hazard:  {worst:>10.2} ms)"
        )?;
    }
    writeln!(
        out,
        "live link (10 ms cycle, jitter, sensor -> filtered output): `vigie gateway-bench` (needs the pymodbus venv)"
    )?;
    Ok(ExitCode::SUCCESS)
}

/// The plant's reference program scanned on the sensors of a minute of its `production`
/// scenario, as written in RON and as read back from its PLCopen XML export (the
/// import adds memories for previous values and step flags): ns per scan, medians of
/// 11 replays each.
fn plcopen_scan(out: &mut impl std::io::Write, path: &Path) -> anyhow::Result<()> {
    use std::sync::Arc;
    use vigie_core::control::{CompiledProgram, Origin, ProgramRuntime};
    use vigie_core::engine::Control as _;
    use vigie_core::sim::{Options, Simulation};
    let render =
        |p: Vec<vigie_core::diag::Problem>| anyhow::anyhow!("{}", vigie_core::diag::render(&p));
    let scenario = load_scenario(path)?;
    let mut sim = Simulation::from_scenario(&scenario, path, Options::default()).map_err(render)?;
    let mut sensors = Vec::new();
    while sim.now() < vigie_core::Millis(60_000) {
        sim.cycle();
        sensors.push(sim.emulator.sensors().clone());
    }
    let plant = sim.bundle.plant.clone();
    let native = Arc::clone(sim.program.program());
    let xml = vigie_core::plcopen::export(&native.program, &plant, path).map_err(render)?;
    let read =
        vigie_core::plcopen::import(&xml, Path::new("reference.xml"), &plant).map_err(render)?;
    let imported =
        Arc::new(CompiledProgram::new(&read, &plant, &Origin::default()).map_err(render)?);
    let replay = |program: &Arc<CompiledProgram>| {
        let mut times = Vec::new();
        for _ in 0..11 {
            let mut rt = ProgramRuntime::new(Arc::clone(program));
            if let Some(b) = &program.program.start {
                let _ = rt.press(b);
            }
            let mut frame = Frame::new([plant.inputs.len(), plant.outputs.len(), 0, 0]);
            let mut outs = vigie_core::Bits::zeros(plant.outputs.len());
            let start = Instant::now();
            for (k, s) in sensors.iter().enumerate() {
                frame.shift();
                frame.now_mut(Space::Input).copy_from(s);
                rt.scan(vigie_core::Millis(10 * (k as u64 + 1)), &frame, &mut outs);
                black_box(&outs);
            }
            times.push(start.elapsed().as_nanos() as f64 / sensors.len() as f64);
        }
        times.sort_by(f64::total_cmp);
        times[times.len() / 2]
    };
    let (a, b) = (replay(&native), replay(&imported));
    writeln!(
        out,
        "PLCopen: the reference program's scan, {} scans of {}:",
        sensors.len(),
        path.file_name().unwrap_or_default().to_string_lossy()
    )?;
    writeln!(
        out,
        "  as written (RON):                              {a:>10.0} ns"
    )?;
    writeln!(
        out,
        "  read from its PLCopen export:                  {b:>10.0} ns   {:.2}x, goal <= 2x",
        b / a
    )?;
    Ok(())
}

/// Measures the plant's filter cycle on the frames of its `trip` scenario: the frame
/// before the trip, then the tripping frame with its fallback.
fn bench_trip(
    out: &mut impl std::io::Write,
    bundle: &vigie_core::bundle::PlantBundle,
    filter: &Filter,
    trip_path: &Path,
    (batches, per_batch): (u32, u32),
) -> anyhow::Result<()> {
    let frames = trip_frames(trip_path)?;
    let mut frame = frames.before;
    let mut observers = bundle.observers.clone();
    let mut violations = Vec::new();
    let mut state = filter.new_state();
    let no_trip = median_ns(batches, per_batch, || {
        observers.update(black_box(&mut frame));
        filter.sync(&mut state, black_box(&frame));
        filter.violations_synced(&state, black_box(&frame), &mut violations);
        black_box(&violations);
    });
    anyhow::ensure!(
        violations.is_empty(),
        "the frame before the trip unexpectedly violates {violations:?}"
    );
    let mut trip = frames.trip;
    let mut state = filter.new_state();
    let with_trip = median_ns(batches, per_batch, || {
        filter.sync(&mut state, black_box(&trip));
        filter.violations_synced(&state, black_box(&trip), &mut violations);
        let fb = filter.fallback_synced(&state, &trip);
        black_box(&fb);
    });
    anyhow::ensure!(
        !violations.is_empty(),
        "the tripping frame violates nothing"
    );
    observers.update(&mut trip);
    let fb = filter.fallback(&trip).map_err(|e| anyhow::anyhow!("{e}"))?;
    anyhow::ensure!(
        fb == frames.applied,
        "the fallback differs from what the engine applied at the trip: {} vs {}",
        fb,
        frames.applied
    );
    writeln!(
        out,
        "  filter cycle, no trip (observers + constraints): {no_trip:>10.1} ns   goal <= 1000 ns"
    )?;
    writeln!(
        out,
        "  filter cycle with the {} trip (+ fallback): {with_trip:>10.1} ns   goal <= 1000 ns",
        frames.violated.join(", ")
    )?;
    Ok(())
}

/// Measures the filter on the synthetic plant (10,000 signals, 10,000 constraints):
/// cycles with a few inputs changed, a trip and its fallback.
fn bench_synthetic(out: &mut impl std::io::Write, iterations: u32) -> anyhow::Result<()> {
    // Synthetic plant: 10,000 signals, 10,000 constraints.
    let mut violations = Vec::new();
    let synth = vigie_core::synthetic::generate(10_000, 10_000, 42);
    let sfilter = Filter::new(&synth.constraints, synth.plant.outputs.len());
    let mut sframe = Frame::new(synth.symbols.sizes());
    let mut rng = vigie_core::synthetic::SplitMix64::new(7);
    // Random sensors and previous outputs; the outputs at t are the control's commands
    // in normal production: compliant (the fallback of this context with every output that
    // no constraint forces kept ON, as a running plant would have them).
    for space in [Space::Input, Space::Output] {
        for i in 0..synth.symbols.len(space) {
            sframe.now[space as usize].set(i, rng.chance(1, 2));
            sframe.prev[space as usize].set(i, rng.chance(1, 2));
        }
    }
    make_compliant(&sfilter, &mut sframe)?;
    let heavy = (iterations / 1000).max(10);
    // Each measured cycle changes 10 random sensors (a PLC cycle changes few inputs) and
    // runs the incremental evaluation, as the engine does.
    let mut sstate = sfilter.new_state();
    sfilter.sync(&mut sstate, &sframe);
    let n_in = synth.plant.inputs.len();
    let s_cycle = median_ns(21, heavy.min(200), || {
        for _ in 0..10 {
            let i = usize::try_from(rng.below(n_in as u64)).unwrap_or(0);
            let v = sframe.now[Space::Input as usize].get(i);
            sframe.now[Space::Input as usize].set(i, !v);
        }
        sfilter.sync(&mut sstate, black_box(&sframe));
        sfilter.violations_synced(&sstate, black_box(&sframe), &mut violations);
        black_box(&violations);
    });
    let s_full = median_ns(21, heavy.min(200), || {
        sfilter.violations_into(black_box(&sframe), &mut violations);
        black_box(&violations);
    });
    // Back to the compliant state for the trip measurements.
    make_compliant(&sfilter, &mut sframe)?;
    let n_viol_after_changes = violations.len();
    // A trip: one forced-OFF output commanded ON.
    let tripping = first_trip(
        &sfilter,
        &sframe,
        synth.plant.outputs.len(),
        &mut violations,
    );
    let n_trip = violations.len();
    sfilter.sync(&mut sstate, &tripping);
    let s_trip_cycle = median_ns(21, heavy.min(200), || {
        sfilter.sync(&mut sstate, black_box(&tripping));
        sfilter.violations_synced(&sstate, black_box(&tripping), &mut violations);
        black_box(&violations);
    });
    let s_fallback = median_ns(21, heavy.min(200), || {
        let fb = sfilter.fallback_synced(black_box(&sstate), &tripping);
        black_box(&fb);
    });
    let s_fallback_full = median_ns(21, heavy.min(200), || {
        let fb = sfilter.fallback(black_box(&tripping));
        black_box(&fb);
    });
    let ok = sfilter.fallback_synced(&sstate, &tripping).is_ok();
    writeln!(
        out,
        "synthetic plant (seed 42: {} signals, {} constraints)",
        synth.plant.inputs.len() + synth.plant.outputs.len(),
        synth.constraints.constraints.len(),
    )?;
    writeln!(
        out,
        "  filter cycle, 10 inputs changed per cycle:       {:>10.1} µs   goal <= 100 µs ({n_viol_after_changes} constraints true at the end)",
        s_cycle / 1000.0
    )?;
    writeln!(
        out,
        "  filter cycle, {n_trip} constraint(s) true:             {:>10.1} µs   goal <= 100 µs",
        s_trip_cycle / 1000.0
    )?;
    writeln!(
        out,
        "  (full re-evaluation of every term, no state:     {:>10.1} µs)",
        s_full / 1000.0
    )?;
    writeln!(
        out,
        "  fallback ({}):                              {:>10.1} µs   goal <= 50 µs",
        if ok { "found" } else { "spec error" },
        s_fallback / 1000.0
    )?;
    writeln!(
        out,
        "  (fallback re-evaluating every term:              {:>10.1} µs)",
        s_fallback_full / 1000.0
    )?;
    Ok(())
}

/// Sets the frame's outputs to the fallback of its context (the commands of a plant in
/// normal production).
fn make_compliant(sfilter: &Filter, sframe: &mut Frame) -> anyhow::Result<()> {
    let compliant = sfilter
        .fallback(sframe)
        .map_err(|e| anyhow::anyhow!("synthetic plant has no fallback: {e}"))?;
    sframe.now[Space::Output as usize].copy_from(&compliant);
    Ok(())
}

/// The frame with the first output (of `n_out`) whose flip violates a constraint
/// flipped; `violations` are then that trip's.
fn first_trip(
    sfilter: &Filter,
    sframe: &Frame,
    n_out: usize,
    violations: &mut Vec<usize>,
) -> Frame {
    let mut tripping = sframe.clone();
    sfilter.violations_into(&tripping, violations);
    for k in 0..n_out {
        let before = tripping.now[Space::Output as usize].get(k);
        tripping.now[Space::Output as usize].set(k, !before);
        sfilter.violations_into(&tripping, violations);
        if !violations.is_empty() {
            break;
        }
        tripping.now[Space::Output as usize].set(k, before);
    }
    tripping
}

/// Task monitor cost per event and per cycle against the number of tasks.
fn task_monitors(out: &mut impl std::io::Write) -> anyhow::Result<()> {
    use vigie_core::Millis;
    use vigie_core::tasks::{Monitor, synthetic};
    writeln!(
        out,
        "task monitors (stopwatches, seed 000), synthetic task sets:"
    )?;
    writeln!(
        out,
        "  {:>6} {:>14} {:>14}",
        "tasks", "per event", "per cycle"
    )?;
    for n in [1usize, 10, 100, 1_000, 10_000] {
        let set = synthetic(n);
        let starts: Vec<String> = set.tasks.iter().map(|t| t.start.clone()).collect();
        let mut monitor = Monitor::new(&set, Millis::ZERO);
        let mut t = 0u64;
        let mut k = 0usize;
        let per_event = median_ns(21, 200, || {
            t += 1;
            k = (k + 1) % starts.len();
            black_box(monitor.on_event(Millis(t), &starts[k]));
        });
        let per_cycle = median_ns(21, 2_000, || {
            t += 10;
            black_box(monitor.advance(Millis(t)));
            black_box(monitor.next_deadline());
        });
        writeln!(
            out,
            "  {n:>6} {:>11.0} ns {:>11.0} ns",
            per_event, per_cycle
        )?;
    }
    Ok(())
}

/// CPU time consumed by this thread, from `/proc/thread-self/schedstat` (Linux); `None`
/// elsewhere.
pub(crate) fn thread_cpu() -> Option<std::time::Duration> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = text.split_whitespace().next()?.parse().ok()?;
    Some(std::time::Duration::from_nanos(ns))
}

/// Simulated time / wall time of the closed loop: the emulator at its step, the
/// program scanned every cycle, observers, filter and recorder, over the `production`
/// scenario of `bench.ron` (the station: an hour, `scenarios/reference-hour.ron`).
/// The shortest closed-loop run measured, simulated ms.
const MIN_CLOSED_LOOP_MS: u64 = 600_000;

fn closed_loop(out: &mut impl std::io::Write, path: &Path) -> anyhow::Result<()> {
    use vigie_core::sim::{Options, Simulation};
    let scenario = load_scenario(path)?;
    let mut sim = Simulation::from_scenario(&scenario, path, Options::default())
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    // A short production (a work cycle, a batch) is repeated to ten simulated minutes at
    // least: a few milliseconds of wall time measure nothing.
    let repeats = MIN_CLOSED_LOOP_MS.div_ceil(scenario.duration_ms.max(1));
    let duration_ms = scenario.duration_ms * repeats;
    sim.repeat_pending(scenario.duration_ms, duration_ms - 1);
    let cpu0 = thread_cpu();
    let start = Instant::now();
    sim.run_until(vigie_core::Millis(duration_ms));
    let wall = start.elapsed();
    let cpu = thread_cpu().zip(cpu0).map(|(b, a)| b.saturating_sub(a));
    let sim_s = duration_ms as f64 / 1000.0;
    let unit = match sim.emulator.as_components() {
        Some(c) if c.carries_items() => "items out (delivered or taken)",
        _ => "elementary actions completed",
    };
    let what = format!(
        "{} {unit}, {} trips",
        sim.produced(),
        sim.engine.trips.len()
    );
    writeln!(
        out,
        "closed loop (emulator + reference program + filter + monitors), {sim_s:.0} simulated s ({repeats} x {}), {what}:",
        path.file_name().unwrap_or_default().to_string_lossy()
    )?;
    writeln!(
        out,
        "  simulated / wall time:                         {:>10.0}x   goal >= 10000x ({:.3} s wall)",
        sim_s / wall.as_secs_f64(),
        wall.as_secs_f64()
    )?;
    if let Some(cpu) = cpu {
        writeln!(
            out,
            "  simulated / CPU time of the thread:            {:>10.0}x   ({:.3} s CPU; wall is higher on a loaded machine)",
            sim_s / cpu.as_secs_f64(),
            cpu.as_secs_f64()
        )?;
    }
    Ok(())
}

/// The five explanation levels of the first trip of the `trip` scenario of `bench.ron`
/// (the station: the paper's CSs10 trip, `cs10-paper.ron`, variant E01) with a 10 s
/// projection: the closed loop runs to the trip, then
/// [`vigie_core::sim::Simulation::explanation`] is timed on copies of the states at the
/// start of the tripping cycle. Returns the median time in ms, `None` when the plant has
/// no such scenario or it does not trip.
/// The second figure is the worst case of the projection alone: the full 10 s horizon
/// (no hazard predicted).
pub(crate) fn explanations_ms(path: &Path, batches: u32) -> anyhow::Result<Option<(f64, f64)>> {
    use vigie_core::sim::{Options, Simulation};
    let scenario = load_scenario(path)?;
    anyhow::ensure!(
        scenario.projection_ms == 10_000,
        "the benchmark needs a 10 s projection horizon"
    );
    let options = Options {
        history_cycles: 30_000,
        explain: false,
    };
    let mut sim = Simulation::from_scenario(&scenario, path, options)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let end = vigie_core::Millis(scenario.duration_ms);
    let mut before = None;
    while sim.now() < end && sim.engine.trips.is_empty() {
        before = Some((sim.emulator.clone(), sim.program.clone()));
        sim.cycle();
    }
    let Some((emulator, program)) = before.filter(|_| !sim.engine.trips.is_empty()) else {
        return Ok(None);
    };
    let mut levels = 0;
    let ns = median_ns(batches.max(1), 1, || {
        let r = sim.explanation(0, emulator.clone(), program.clone(), &sim.program);
        levels = r.as_ref().map_or(0, |(ex, _)| {
            ex.levels().iter().filter(|l| !l.items.is_empty()).count()
        });
        black_box(&r);
    });
    anyhow::ensure!(
        levels == 5,
        "the explanation has {levels} non-empty levels, not 5"
    );
    // The projection stops at the first predicted hazard (+0.5 s shown); without any
    // hazard it runs the whole horizon: 10 s of program scans and emulator steps.
    let worst = median_ns(batches.clamp(1, 5), 1, || {
        use vigie_core::engine::Control as _;
        let (mut emu, mut prog) = (emulator.clone(), program.clone());
        let symbols = &sim.engine.symbols;
        let mut frame = vigie_core::frame::Frame::new(symbols.sizes());
        let mut outputs = vigie_core::Bits::zeros(sim.bundle.plant.outputs.len());
        let stop = emu.now() + vigie_core::Millis(10_000);
        while emu.now() < stop {
            frame.shift();
            frame.now_mut(Space::Input).copy_from(emu.sensors());
            prog.scan(emu.now(), &frame, &mut outputs);
            emu.step(sim.cycle_period(), &outputs);
        }
        black_box(&emu);
    });
    Ok(Some((ns / 1e6, worst / 1e6)))
}
