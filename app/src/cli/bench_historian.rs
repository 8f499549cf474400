//! `vigie bench-historian`: the historian's figures (issue 19): the cost of a durable
//! journal insert, the cost of recording the process history at a 10 ms cycle, and
//! the time of a trend query over a week of that history.
//!
//! The week is real: the plant's `production` scenario of `bench.ron` runs an hour
//! at its own cycle, its changes are recorded as the console records them, and the
//! hour is written 168 times one after the other (a week of production, every signal's
//! changes at their real rate) into a fresh database in a temporary folder.

use super::bench::median_ns;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;
use vigie_app::historian::writer::{Change, ProcessRecorder, cycle_values, signal_names};
use vigie_app::historian::{JournalRow, Sample, Store, wall_ms};

const HOUR_MS: u64 = 3_600_000;

/// Arguments of `vigie bench-historian`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// Hours of history written (168: a week).
    #[arg(long, default_value_t = 168)]
    pub(crate) hours: u64,
    /// Folder of the temporary database (default: the system's temporary folder); it
    /// is deleted at the end.
    #[arg(long)]
    pub(crate) dir: Option<std::path::PathBuf>,
}

fn production_hour(plant_dir: &Path) -> anyhow::Result<(Vec<String>, Vec<Change>, u64)> {
    use vigie_core::sim::{Options, Scenario, Simulation};
    let file = plant_dir.join("bench.ron");
    let path = plant_dir.join(
        super::bench::bench_file(plant_dir)?
            .production
            .ok_or_else(|| anyhow::anyhow!("{}: no `production` scenario", file.display()))?,
    );
    let scenario =
        Scenario::load(&path).map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let mut sim = Simulation::from_scenario(&scenario, &path, Options::default())
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let names = signal_names(&sim.bundle.symbols);
    let mut rec = ProcessRecorder::new(names.len());
    let mut changes = Vec::new();
    let mut cycles = 0;
    while sim.now().0 < HOUR_MS {
        sim.cycle();
        cycles += 1;
        if let Some(r) = sim.engine.history.last() {
            rec.record(r.time.0, cycle_values(r));
        }
        if let Some(b) = rec.take_due(sim.now().0, 1000) {
            changes.extend(b);
        }
    }
    changes.extend(rec.take_due(u64::MAX, 0).unwrap_or_default());
    Ok((names, changes, cycles))
}

pub(crate) fn run(plant_dir: &Path, args: &Args) -> anyhow::Result<ExitCode> {
    let mut out = std::io::stdout().lock();
    let base = args.dir.clone().unwrap_or_else(std::env::temp_dir);
    let dir = base.join(format!("vigie-bench-historian-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let result = measure(plant_dir, args, &dir, &mut out);
    let _ = std::fs::remove_dir_all(&dir);
    result?;
    Ok(ExitCode::SUCCESS)
}

fn measure(
    plant_dir: &Path,
    args: &Args,
    dir: &Path,
    out: &mut impl std::io::Write,
) -> anyhow::Result<()> {
    let mut store = Store::open_in(dir)?;
    writeln!(
        out,
        "historian in {} (WAL, synchronous = FULL)",
        store.path().display()
    )?;

    // 1. The journal: one entry per durable transaction (an operator's action), and a
    //    batch of 100 (a burst of events in one frame or one gateway batch).
    bench_journal(&mut store, out)?;

    // 2. The process history: an hour of production, written `hours` times.
    let t = Instant::now();
    let (names, hour, cycles) = production_hour(plant_dir)?;
    let emulate_s = t.elapsed().as_secs_f64();
    let ids = store.signal_ids(&names)?;
    let start = wall_ms().saturating_sub(args.hours * HOUR_MS);
    let mut inserted = 0u64;
    let mut batch_times = Vec::new();
    let t = Instant::now();
    for h in 0..args.hours {
        // One commit per simulated second, as the writer thread does.
        let mut second = Vec::new();
        let mut current = None;
        for &(i, t_ms, value) in &hour {
            let s = t_ms / 1000;
            if current.is_some_and(|c| c != s) {
                let b = Instant::now();
                store.append_samples(&second)?;
                batch_times.push(b.elapsed().as_secs_f64());
                inserted += second.len() as u64;
                second.clear();
            }
            current = Some(s);
            second.push(Sample {
                signal: ids[i as usize],
                t_ms: start + h * HOUR_MS + t_ms,
                value,
            });
        }
        store.append_samples(&second)?;
        inserted += second.len() as u64;
    }
    let write_s = t.elapsed().as_secs_f64();
    batch_times.sort_by(f64::total_cmp);
    let pct = |p: f64| batch_times[((batch_times.len() - 1) as f64 * p) as usize] * 1e3;
    let size = std::fs::metadata(store.path()).map_or(0, |m| m.len())
        + std::fs::metadata(dir.join(format!("{}-wal", vigie_app::historian::FILE)))
            .map_or(0, |m| m.len());
    writeln!(
        out,
        "  process history: {} signals, an hour of production = {cycles} cycles, {} changes (emulated in {emulate_s:.1} s)",
        names.len(),
        hour.len()
    )?;
    writeln!(
        out,
        "  {} h written: {inserted} changes in {write_s:.1} s ({:.0} changes/s); a second's commit: median {:.2} ms, p99 {:.2} ms, max {:.2} ms; {:.1} MB",
        args.hours,
        inserted as f64 / write_s,
        pct(0.5),
        pct(0.99),
        pct(1.0),
        size as f64 / 1e6
    )?;
    writeln!(
        out,
        "  recording cost: the writer thread is busy {:.3} % of the time at a 10 ms cycle (one commit a second)",
        pct(0.5) / 1000.0 * 100.0
    )?;

    // 3. Trend queries over the whole history, a day and an hour, for the signal that
    //    changes most, in 1,000 buckets (a plot's width).
    bench_trends(&store, out, &names, &hour, (start, args.hours))?;
    // 4. Retention: with a one-day process retention, the older half of the history
    //    is purged.
    let t = Instant::now();
    let keep_a_day = vigie_app::historian::Retention {
        process_days: 1,
        journal_days: 366,
    };
    let p = store.purge(start + args.hours * HOUR_MS / 2 + 24 * HOUR_MS, &keep_a_day)?;
    writeln!(
        out,
        "  retention: the older half ({} changes) purged in {:.2} s",
        p.samples,
        t.elapsed().as_secs_f64()
    )?;
    Ok(())
}

/// Times journal inserts: one entry per commit, and batches of 100.
fn bench_journal(store: &mut Store, out: &mut impl std::io::Write) -> anyhow::Result<()> {
    let session = store.begin_session("bench", "bench", wall_ms())?;
    let entry = |k: u64| JournalRow {
        wall_ms: wall_ms(),
        sim_ms: k,
        kind: "trip".into(),
        text: format!(
            "Safety stop {k}: a journal entry of a typical length, with the constraint's description"
        ),
        ..JournalRow::default()
    };
    let mut k = 0;
    let one = median_ns(51, 4, || {
        k += 1;
        store.append_journal(session, &[entry(k)]).expect("insert");
    });
    let batch: Vec<JournalRow> = (0..100).map(entry).collect();
    let hundred = median_ns(21, 2, || {
        store.append_journal(session, &batch).expect("insert");
    });
    writeln!(
        out,
        "  journal insert, one entry per commit: {:.2} ms (median of 51 × 4)",
        one / 1e6
    )?;
    writeln!(
        out,
        "  journal insert, 100 entries per commit: {:.2} ms per batch, {:.1} µs per entry",
        hundred / 1e6,
        hundred / 100.0 / 1e3
    )?;
    Ok(())
}

/// Times trend queries (1,000 buckets) of the busiest signal over the whole history,
/// a day and an hour.
fn bench_trends(
    store: &Store,
    out: &mut impl std::io::Write,
    names: &[String],
    hour: &[Change],
    (start, hours): (u64, u64),
) -> anyhow::Result<()> {
    let mut counts = vec![0u64; names.len()];
    for &(i, _, _) in hour {
        counts[i as usize] += 1;
    }
    let busiest = counts
        .iter()
        .enumerate()
        .max_by_key(|(_, c)| **c)
        .map_or(0, |(i, _)| i);
    let end = start + hours * HOUR_MS;
    for (label, span) in [
        ("the whole history", hours * HOUR_MS),
        ("a day", 24 * HOUR_MS),
        ("an hour", HOUR_MS),
    ] {
        let from = end.saturating_sub(span).max(start);
        let mut buckets = 0;
        let ns = median_ns(11, 1, || {
            let t = store
                .trend(&names[busiest], from, end, 1000)
                .expect("trend");
            buckets = t.buckets.len();
        });
        writeln!(
            out,
            "  trend of {} over {label}: {:.1} ms ({buckets} buckets, {} changes in the hour)",
            names[busiest],
            ns / 1e6,
            counts[busiest]
        )?;
    }
    Ok(())
}
