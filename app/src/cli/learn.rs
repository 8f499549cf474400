//! `vigie diagnose learn` (interval learning from traces), `vigie diagnose report`,
//! `vigie campaign diagnoser` and `vigie diagnose bench`: the diagnosers' commands.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use vigie_core::pop;

/// Learns the intervals of `diagnosers.ron` from normal-run traces and writes the
/// learned bounds into it in place (`pop::learn::rewrite`: comments and layout kept);
/// the statistics are printed.
pub(crate) fn learn(
    dir: &Path,
    traces: &[PathBuf],
    alpha: Option<f64>,
    dry_run: bool,
) -> anyhow::Result<ExitCode> {
    let render =
        |p: &[vigie_core::diag::Problem]| anyhow::anyhow!("{}", vigie_core::diag::render(p));
    let path = dir.join("diagnosers.ron");
    let plant = vigie_core::plant::Plant::load(&dir.join("plant.ron")).map_err(|p| render(&p))?;
    // Read once: the text learned from is the text rewritten.
    let text = vigie_core::diag::read_text(&path).map_err(|p| render(&[p]))?;
    let (db, _) = pop::from_text(dir, plant, &text, &path).map_err(|p| render(&p))?;
    let mut rows = Vec::new();
    for t in traces {
        let text = std::fs::read_to_string(t)
            .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", t.display()))?;
        rows.push(
            vigie_core::trace::parse(&text, t, &db.bundle.plant)
                .map_err(|p| anyhow::anyhow!("{p}"))?,
        );
    }
    let measures = pop::learn::measure(&db.compiled, db.bundle.symbols.sizes(), &rows);
    let mut file = db.file.clone();
    if let Some(a) = alpha {
        file.alpha = a;
    }
    let done = pop::learn::apply(&mut file, &measures);
    let mut out = std::io::stdout().lock();
    for (id, m) in &measures {
        writeln!(
            out,
            "{id}: n={} min={} max={} mean={:.1} sigma={:.2} dT={:.2} (alpha {})",
            m.n,
            m.min,
            m.max,
            m.mean,
            m.sigma(),
            file.alpha * m.sigma(),
            file.alpha
        )?;
    }
    if !dry_run {
        let rewritten = pop::learn::rewrite(&text, &path, &file).map_err(|p| render(&[p]))?;
        std::fs::write(&path, rewritten)?;
        writeln!(
            out,
            "learned {} intervals: their window bounds written into {} (comments and layout kept; the statistics above are not written)",
            done.len(),
            path.display()
        )?;
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints the diagnosability report (JSON).
/// The first line of a `diagnosers.ron` that `vigie diagnose derive` wrote (and may
/// write again).
pub(crate) const DERIVED: &str =
    "// Derived from components.ron by `vigie diagnose derive`: derive again after";

/// `vigie diagnose derive`: the diagnosers of a plant of components, from its axes.
pub(crate) fn derive(dir: &Path, stdout: bool) -> anyhow::Result<ExitCode> {
    let path = dir.join("components.ron");
    let desc = vigie_core::machine::Components::load(&path)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let (bundle, _) = vigie_core::bundle::PlantBundle::load(dir)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let d = vigie_core::machine::diagnosers::derive(&desc, &bundle.symbols);
    let text = derived_text(&d);
    if stdout {
        write!(std::io::stdout().lock(), "{text}")?;
    } else {
        let out = dir.join("diagnosers.ron");
        if let Ok(old) = std::fs::read_to_string(&out)
            && !old.starts_with(DERIVED)
        {
            anyhow::bail!(
                "{} was not written by `vigie diagnose derive`: it is left alone (print the derived models with --stdout)",
                out.display()
            );
        }
        std::fs::write(&out, &text)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", out.display()))?;
    }
    let mut err = std::io::stderr().lock();
    for c in &d.file.components {
        writeln!(
            err,
            "{}: {} states, {} expected evolutions, {} intervals, {} faults",
            c.id,
            c.states.len(),
            c.expected.len(),
            c.intervals.len(),
            c.faults.len()
        )?;
    }
    for (id, why) in &d.skipped {
        writeln!(err, "{id}: no model ({why})")?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The file `derive` writes: a header, the components without a model, the models.
pub(crate) fn derived_text(d: &vigie_core::machine::diagnosers::Derived) -> String {
    let mut text = format!(
        "{DERIVED}\n// editing components.ron, or take this file over by deleting these lines\n// (then `derive` leaves it alone). Learn the intervals with `vigie diagnose learn`.\n"
    );
    for (id, why) in &d.skipped {
        text.push_str(&format!("// {id}: no model ({why})\n"));
    }
    // One state, evolution, interval or fault per line: a model of hundreds of states
    // stays a file one reads and diffs.
    let cfg = ron::ser::PrettyConfig::new()
        .struct_names(true)
        .depth_limit(4);
    text.push_str(&ron::ser::to_string_pretty(&d.file, cfg).unwrap_or_default());
    text.push('\n');
    text
}

pub(crate) fn report(dir: &Path) -> anyhow::Result<ExitCode> {
    let (db, _) =
        pop::load(dir).map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let r = pop::report(&db.compiled);
    writeln!(
        std::io::stdout().lock(),
        "{}",
        serde_json::to_string_pretty(&r)?
    )?;
    Ok(ExitCode::SUCCESS)
}

/// `vigie campaign diagnoser`: every fault of the library at random times over `seeds`
/// seeds, and `fault_free_hours` of fault-free runs (`vigie_core::pop::campaign`).
pub(crate) fn campaign(
    dir: &Path,
    (first_seed, seeds): (u64, u64),
    fault_free_hours: u64,
    only: Option<&str>,
    threads: Option<usize>,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let config = pop::campaign::Config {
        seeds,
        first_seed,
        fault_free_hours,
        only: only.map(str::to_string),
        threads: threads
            .or_else(|| std::thread::available_parallelism().ok().map(usize::from))
            .unwrap_or(1)
            .max(1),
        ..pop::campaign::Config::default()
    };
    let start = Instant::now();
    let r = pop::campaign::run(dir, &config).map_err(|p| {
        anyhow::anyhow!("cannot run the campaign:\n{}", vigie_core::diag::render(&p))
    })?;
    let mut out = std::io::stdout().lock();
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(&r)?)?;
        return Ok(ExitCode::SUCCESS);
    }
    writeln!(
        out,
        "diagnoser fault campaign: {} seeds per fault, fault at {}..{} s, watched {} s after it ({:.0} s wall)",
        r.seeds,
        config.first_ms / 1000,
        (config.first_ms + config.spread_ms) / 1000,
        config.watch_ms / 1000,
        start.elapsed().as_secs_f64()
    )?;
    let (right, mirror, runs, bad, lost) = campaign_rows(&mut out, &r)?;
    writeln!(
        out,
        "total: {runs} runs, {right} right, {mirror} stopped on the faulted actuator by its mirror contact, {bad} wrong or early, {lost} lost track (unexplained, no fault claimed)"
    )?;
    writeln!(
        out,
        "fault-free: {} simulated hours, {} produced (items delivered, or elementary actions completed on a plant of components), {} hazards, {} certain diagnoses (all false)",
        r.fault_free_hours,
        r.fault_free_delivered,
        r.fault_free_hazards,
        r.false_diagnoses.len()
    )?;
    for d in r.false_diagnoses.iter().take(10) {
        writeln!(
            out,
            "      FALSE {} ms {}/{} {}",
            d.time_ms, d.component, d.partition, d.fault
        )?;
    }
    Ok(if bad == 0 && r.false_diagnoses.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The diagnoser campaign's table, one row per injection with its notes; the totals
/// (right, by the mirror, runs, wrong or early, lost).
fn campaign_rows(
    out: &mut impl Write,
    r: &pop::campaign::Report,
) -> anyhow::Result<(usize, usize, usize, usize, usize)> {
    writeln!(
        out,
        "{:<34} {:<22} {:>5} {:>5} {:>6} {:>5} {:>5} {:>5} {:>5} {:>5}  delay ms p50/p90/max",
        "fault",
        "expected partition",
        "runs",
        "right",
        "mirror",
        "wrong",
        "early",
        "ambig",
        "none",
        "lost"
    )?;
    let (mut right, mut mirror, mut runs, mut bad, mut lost) = (0, 0, 0, 0, 0);
    for row in &r.rows {
        let q = |p| {
            row.delay_quantile(p)
                .map_or_else(|| "-".to_string(), |d| d.to_string())
        };
        writeln!(
            out,
            "{:<34} {:<22} {:>5} {:>5} {:>6} {:>5} {:>5} {:>5} {:>5} {:>5}  {}/{}/{}",
            row.name,
            row.expected.join("|"),
            row.runs,
            row.right,
            row.monitored,
            row.wrong,
            row.early,
            row.ambiguous.values().sum::<usize>(),
            row.no_effect.values().sum::<usize>(),
            row.lost,
            q(50),
            q(90),
            q(100)
        )?;
        for (why, n) in &row.ambiguous {
            writeln!(out, "      not diagnosable ({n}): ambiguous {why}")?;
        }
        for (why, n) in &row.no_effect {
            writeln!(out, "      no observable effect ({n}): {why}")?;
        }
        for f in &row.failures {
            writeln!(out, "      FAILURE {f}")?;
        }
        for l in &row.lost_runs {
            writeln!(out, "      lost track (no fault claimed) {l}")?;
        }
        right += row.right;
        mirror += row.monitored;
        lost += row.lost;
        runs += row.runs;
        bad += row.wrong + row.early;
    }
    Ok((right, mirror, runs, bad, lost))
}

/// `vigie campaign transients`: transient sensor faults, pairs, and welded and dead
/// actuators at the highest sustained arrival rate (`vigie_core::pop::transients`).
pub(crate) fn transients(
    dir: &Path,
    (first_seed, seeds): (u64, u64),
    fault_free_hours: u64,
    only: Option<&str>,
    threads: Option<usize>,
    (json, plausibility): (bool, bool),
) -> anyhow::Result<ExitCode> {
    use vigie_core::pop::transients;
    let config = transients::Config {
        seeds,
        first_seed,
        fault_free_hours,
        plausibility,
        // Replaying one run: its changes of signals in the JSON report.
        changes: seeds == 1,
        only: only.map(str::to_string),
        threads: threads
            .or_else(|| std::thread::available_parallelism().ok().map(usize::from))
            .unwrap_or(1)
            .max(1),
        ..transients::Config::default()
    };
    let start = Instant::now();
    let r = transients::run(dir, &config).map_err(|p| {
        anyhow::anyhow!("cannot run the campaign:\n{}", vigie_core::diag::render(&p))
    })?;
    let (runs, hazards, wrong, restored, not_restored) = r.totals();
    let ff = &r.fault_free;
    let ok = hazards == 0
        && wrong == 0
        && not_restored == 0
        && ff.trips + ff.hazards + ff.diagnoses == 0
        && ff.held_edges == 0;
    let mut out = std::io::stdout().lock();
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(&r)?)?;
        return Ok(if ok {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        });
    }
    writeln!(
        out,
        "transient-fault campaign: {} seeds per case, filter Enforce, diagnosers on, plausibility stage {}; transients during production of period {} ms (+0..{} ms: an item's arrival, or the production scenario's length), actuator faults at the sustained period {} ms ({:.0} s wall)",
        r.seeds,
        if r.plausibility { "on" } else { "off" },
        r.transient_period_ms.0,
        r.transient_period_ms.1,
        r.sustained_period_ms,
        start.elapsed().as_secs_f64()
    )?;
    writeln!(
        out,
        "{:<26} {:>5} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}",
        "case", "runs", "struck", "trips", "hazard", "own", "wrong", "right", "restor", "stuck"
    )?;
    for row in &r.rows {
        writeln!(
            out,
            "{:<26} {:>5} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}",
            row.name,
            row.runs,
            row.injected,
            row.trips,
            row.hazards,
            row.own_hazards,
            row.wrong,
            row.right,
            row.restored,
            row.not_restored
        )?;
        for f in &row.failures {
            writeln!(out, "      FAILURE {f}")?;
        }
    }
    writeln!(
        out,
        "total: {runs} runs, {hazards} hazards, {wrong} wrong certain diagnoses, production restored after {restored} transients, not after {not_restored} ({again} tripped again later and were recovered again)",
        again = r.rows.iter().map(|row| row.tripped_again).sum::<usize>()
    )?;
    writeln!(
        out,
        "fault-free: {} simulated hours, {} produced (items delivered, or elementary actions completed), {} trips, {} hazards, {} certain diagnoses, {} sensor edges held as implausible",
        ff.hours, ff.delivered, ff.trips, ff.hazards, ff.diagnoses, ff.held_edges
    )?;
    for e in &ff.examples {
        writeln!(out, "      FAULT-FREE {e}")?;
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// Wall-clock limit of one libFAUDES construction in `vigie diagnose bench`, s.
const LIBFAUDES_LIMIT_S: u64 = 60;

/// `vigie diagnose bench`: diagnoser cost per cycle (station, 1000 synthetic turntables),
/// build times, and libFAUDES' centralized diagnoser for 1, 3, 4, 5 identical turntables
/// and box beams (`c6`).
pub(crate) fn bench(dir: &Path) -> anyhow::Result<ExitCode> {
    let mut out = std::io::stdout().lock();
    let err =
        |p: Vec<vigie_core::diag::Problem>| anyhow::anyhow!("{}", vigie_core::diag::render(&p));
    bench_station(dir, &mut out)?;
    // Synthetic 1000 turntables.
    let text = std::fs::read_to_string(dir.join("diagnosers.ron"))?;
    let file = pop::model::DiagnoserFile::from_ron(&text, &dir.join("diagnosers.ron"))
        .map_err(|p| anyhow::anyhow!("{p}"))?;
    let table = file
        .components
        .iter()
        .find(|c| c.id == "table")
        .ok_or_else(|| anyhow::anyhow!("no table"))?;
    let n = 1000;
    let (syn, symbols) = synthetic(n, table);
    let syn_text = syn.to_ron();
    let start = Instant::now();
    let compiled = pop::build::compile(&syn, &syn_text, Path::new("<synthetic>"), &symbols, None)
        .map_err(err)?;
    let d = pop::Diagnosers::new(compiled.clone(), &symbols);
    let build = start.elapsed();
    writeln!(
        out,
        "synthetic: {n} turntables, build {:.1} ms (compile and run-time tables; goal < 1000 ms)",
        build.as_secs_f64() * 1e3,
    )?;
    let shared = synthetic_cycles(d, &symbols, n);
    let own = synthetic_cycles(
        pop::Diagnosers::new_unshared(compiled, &symbols),
        &symbols,
        n,
    );
    for (what, r) in [
        (
            "one run-time table for the identical turntables (the default)",
            shared,
        ),
        (
            "one run-time table per turntable (as if all were different)",
            own,
        ),
    ] {
        writeln!(
            out,
            "synthetic, {what}: {:.2} us per cycle wall clock, {} goal <= 50 us ({:.1} edges per cycle over {} cycles; {} certain diagnoses in this fault-free run)",
            r.wall_us,
            r.cpu_us
                .map_or_else(String::new, |c| format!("{c:.2} us on the CPU;")),
            r.edges as f64 / r.cycles as f64,
            r.cycles,
            r.diagnosed
        )?;
    }
    // Construction time vs libFAUDES for k identical components: the turntable (202
    // automaton states) and the table's box beam `c6` (small enough for libFAUDES to
    // finish with several copies).
    let tmp = std::env::temp_dir().join("vigie-bench-diag");
    std::fs::create_dir_all(&tmp)?;
    let station = pop::load(dir).map_err(err)?.0.compiled;
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| PathBuf::from(".venv"), PathBuf::from);
    for id in ["table", "c6"] {
        let def = file
            .components
            .iter()
            .find(|c| c.id == id)
            .ok_or_else(|| anyhow::anyhow!("no component `{id}`"))?;
        let compiled = station
            .components
            .iter()
            .find(|c| c.id == id)
            .ok_or_else(|| anyhow::anyhow!("no component `{id}`"))?;
        for k in [1usize, 3, 4, 5] {
            let (syn, symbols) = synthetic(k, def);
            let t = syn.to_ron();
            let start = Instant::now();
            let _ = pop::build::compile(&syn, &t, Path::new("<synthetic>"), &symbols, None)
                .map_err(err)?;
            writeln!(
                out,
                "vigie decentralized build, {k} x {id}: {:.3} ms ({} automaton states each)",
                start.elapsed().as_secs_f64() * 1e3,
                compiled.g.len()
            )?;
        }
        let (g, m) = pop::faudes_export(compiled);
        let (gen_path, ftm_path) = (tmp.join(format!("{id}.gen")), tmp.join(format!("{id}.ftm")));
        std::fs::write(&gen_path, g)?;
        std::fs::write(&ftm_path, m)?;
        if !libfaudes_rows(&mut out, &venv, &gen_path, &ftm_path, id)? {
            break;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Times the station's diagnosers replaying ten minutes of recorded production.
fn bench_station(dir: &Path, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    let err =
        |p: Vec<vigie_core::diag::Problem>| anyhow::anyhow!("{}", vigie_core::diag::render(&p));
    // Station: ten minutes of production recorded (frames after the filter), then
    // replayed through a fresh copy of the diagnosers alone.
    let (_, mut sim) = pop::closed_loop(dir, 2, 10, None).map_err(err)?;
    let diag = sim
        .diagnosers
        .clone()
        .ok_or_else(|| anyhow::anyhow!("no diagnosers"))?;
    let mut frames = Vec::new();
    for _ in 0..60_000 {
        sim.cycle();
        frames.push((sim.now(), sim.engine.frame().clone()));
    }
    let mut best = f64::MAX;
    for _ in 0..5 {
        let mut d = diag.clone();
        let mut fr = frames.clone();
        let start = Instant::now();
        for (t, f) in &mut fr {
            d.update(*t, f);
        }
        best = best.min(start.elapsed().as_secs_f64() * 1e6 / frames.len() as f64);
    }
    writeln!(
        out,
        "station: {} components, {best:.3} us per cycle (best of 5 replays of {} cycles = 10 min of production; goal <= 50 us)",
        diag.compiled.components.len(),
        frames.len()
    )?;
    Ok(())
}

/// `n` synthetic copies of `def` and the symbols of their plant (auxiliaries declared).
fn synthetic(
    n: usize,
    def: &pop::model::ComponentDef,
) -> (pop::model::DiagnoserFile, vigie_core::symbols::Symbols) {
    let (plant, syn) = pop::synthetic(n, def);
    let mut symbols = plant.symbols();
    for a in pop::build::aux_names(&syn) {
        let _ = symbols.declare(&a, vigie_core::symbols::Space::Aux);
    }
    (syn, symbols)
}

/// libFAUDES' centralized diagnoser for 1, 3, 4 and 5 copies of the exported component
/// `id`, each construction stopped after [`LIBFAUDES_LIMIT_S`]; false when the venv is
/// missing (said in the output).
fn libfaudes_rows(
    out: &mut impl Write,
    venv: &Path,
    gen_path: &Path,
    ftm_path: &Path,
    id: &str,
) -> anyhow::Result<bool> {
    let script = PathBuf::from("tests/peers/faudes_diag.py");
    let mut unfinished: Option<usize> = None;
    for k in [1usize, 3, 4, 5] {
        if let Some(j) = unfinished {
            // More copies only make the composition larger.
            writeln!(
                out,
                "libFAUDES centralized EventDiagnoser, {k} x {id}: not run ({j} copies did not finish)"
            )?;
            continue;
        }
        let child = std::process::Command::new(venv.join("bin/python"))
            .arg(&script)
            .arg("bench")
            .arg(gen_path)
            .arg(ftm_path)
            .arg(id)
            .arg(k.to_string())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn();
        let mut child = match child {
            Ok(c) => c,
            Err(e) => {
                writeln!(
                    out,
                    "libFAUDES: not run ({e}); create the venv: python3 -m venv .venv && .venv/bin/pip install -r requirements-test.txt"
                )?;
                return Ok(false);
            }
        };
        let started = Instant::now();
        let limit = std::time::Duration::from_secs(LIBFAUDES_LIMIT_S);
        loop {
            if child.try_wait()?.is_some() {
                let o = child.wait_with_output()?;
                // The faudes module prints notices on import: keep the figures.
                for line in String::from_utf8_lossy(&o.stdout)
                    .lines()
                    .filter(|l| l.starts_with("libFAUDES"))
                {
                    writeln!(out, "{line}")?;
                }
                break;
            }
            if started.elapsed() > limit {
                let _ = child.kill();
                let _ = child.wait();
                // What it printed before (the size of the composed plant).
                let mut text = String::new();
                if let Some(mut o) = child.stdout.take() {
                    let _ = std::io::Read::read_to_string(&mut o, &mut text);
                }
                for line in text.lines().filter(|l| l.starts_with("libFAUDES")) {
                    writeln!(out, "{line}")?;
                }
                writeln!(
                    out,
                    "libFAUDES centralized EventDiagnoser, {k} x {id}: not finished after {LIBFAUDES_LIMIT_S} s (stopped)"
                )?;
                unfinished = Some(k);
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
    Ok(true)
}

/// Time the calling thread spent on a CPU, ns (Linux `schedstat`): unlike the wall
/// clock, it does not count the time other processes held the CPU.
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// What [`synthetic_cycles`] measured.
struct SyntheticRun {
    wall_us: f64,
    cpu_us: Option<f64>,
    edges: u64,
    cycles: u64,
    diagnosed: usize,
}

/// Runs `n` synthetic turntables through their normal cycle and times the diagnosers:
/// one period of warm-up, then six periods timed.
fn synthetic_cycles(
    mut d: pop::Diagnosers,
    symbols: &vigie_core::symbols::Symbols,
    n: usize,
) -> SyntheticRun {
    let mut frame = vigie_core::frame::Frame::new(symbols.sizes());
    // Every turntable runs its normal cycle (period 10 s, phases staggered): RE(A4) at 0,
    // FE(C4) at 100, RE(C5) at 2900, FE(A4) at 4000, FE(C5) at 4100, RE(C4) at 6900.
    for i in 0..n {
        frame.now[0].set(2 * i, true);
    }
    let script: [(u64, usize, bool); 6] = [
        (0, 0, true),
        (100, 1, false),
        (2900, 2, true),
        (4000, 0, false),
        (4100, 2, false),
        (6900, 1, true),
    ];
    // The edges of each cycle of the period, computed once: the loop below only writes
    // them into the frame, so that the time measured is the diagnosers'. During the
    // warm-up a turntable rests at C4 until its first order, so that every one starts
    // in its initial state.
    let period = 1000usize;
    let mut schedule: Vec<Vec<(usize, usize, bool)>> = vec![Vec::new(); period];
    let mut first: Vec<Vec<(usize, usize, bool)>> = vec![Vec::new(); period];
    let mut started = vec![false; n];
    for k in 0..period {
        let t = 10_000 + k as u64 * 10;
        for (i, started) in started.iter_mut().enumerate() {
            let phase = (t + (i as u64 * 7919) % 10_000) % 10_000;
            for &(at, sig, v) in &script {
                if phase / 10 == at / 10 {
                    *started |= at == 0;
                    schedule[k].push((sig, i, v));
                    if *started {
                        first[k].push((sig, i, v));
                    }
                }
            }
        }
    }
    let cycles = 6000u64;
    let warm = period as u64;
    let mut edges = 0u64;
    let mut start = Instant::now();
    let mut cpu0 = thread_cpu_ns();
    let mut diagnosed = 0;
    for k in 0..warm + cycles {
        if k == warm {
            start = Instant::now();
            cpu0 = thread_cpu_ns();
            edges = 0;
            diagnosed = d.diagnoses.len();
        }
        frame.shift();
        let t = 10_000 + k * 10;
        let todo = if k < warm { &first } else { &schedule };
        for &(sig, i, v) in &todo[k as usize % period] {
            edges += 1;
            match sig {
                0 => frame.now[1].set(i, v),
                1 => frame.now[0].set(2 * i, v),
                _ => frame.now[0].set(2 * i + 1, v),
            }
        }
        d.update(vigie_core::Millis(t), &mut frame);
    }
    let wall_us = start.elapsed().as_secs_f64() * 1e6 / cycles as f64;
    let cpu_us = match (cpu0, thread_cpu_ns()) {
        (Some(a), Some(b)) => Some(b.saturating_sub(a) as f64 / 1e3 / cycles as f64),
        _ => None,
    };
    SyntheticRun {
        wall_us,
        cpu_us,
        edges,
        cycles,
        diagnosed: d.diagnoses.len() - diagnosed,
    }
}
