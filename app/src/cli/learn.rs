//! `vigie learn` (interval learning from traces), `vigie diagnose --report`,
//! `vigie campaign diag` and `vigie bench-diag`: the diagnosers' commands.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use vigie_core::emulator::FaultKind;
use vigie_core::pop;

/// Learns the intervals of `diagnosers.ron` from normal-run traces and rewrites it.
pub(crate) fn learn(dir: &Path, traces: &[PathBuf], alpha: Option<f64>, dry_run: bool) -> anyhow::Result<ExitCode> {
    let (db, _) = pop::load(dir).map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let mut rows = Vec::new();
    for t in traces {
        let text = std::fs::read_to_string(t).map_err(|e| anyhow::anyhow!("cannot read {}: {e}", t.display()))?;
        rows.push(vigie_core::trace::parse(&text, t, &db.bundle.plant).map_err(|p| anyhow::anyhow!("{p}"))?);
    }
    let measures = pop::learn::measure(&db.compiled, db.bundle.symbols.sizes(), &rows);
    let mut file = db.file.clone();
    if let Some(a) = alpha {
        file.alpha = a;
    }
    let done = pop::learn::apply(&mut file, &measures);
    let mut out = std::io::stdout().lock();
    for (id, m) in &measures {
        writeln!(out, "{id}: n={} min={} max={} mean={:.1} sigma={:.2} dT={:.2} (alpha {})", m.n, m.min, m.max, m.mean, m.sigma(), file.alpha * m.sigma(), file.alpha)?;
    }
    if !dry_run {
        std::fs::write(dir.join("diagnosers.ron"), file.to_ron())?;
        writeln!(out, "wrote {} intervals into {}", done.len(), dir.join("diagnosers.ron").display())?;
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints the diagnosability report (JSON).
pub(crate) fn report(dir: &Path) -> anyhow::Result<ExitCode> {
    let (db, _) = pop::load(dir).map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let r = pop::report(&db.compiled);
    writeln!(std::io::stdout().lock(), "{}", serde_json::to_string_pretty(&r)?)?;
    Ok(ExitCode::SUCCESS)
}

/// The fault injection library used by the campaign, with the partition expected.
pub(crate) fn library() -> Vec<(FaultKind, &'static str)> {
    let mut v = vec![
        (FaultKind::SensorStuckAt0("C4".into()), "C4"),
        (FaultKind::SensorStuckAt1("C4".into()), "C4"),
        (FaultKind::SensorStuckAt0("C5".into()), "C5"),
        (FaultKind::SensorStuckAt1("C5".into()), "C5"),
        (FaultKind::SpuriousRise { sensor: "C4".into(), pulse_ms: 300 }, "C4"),
        (FaultKind::SpuriousFall { sensor: "C4".into(), pulse_ms: 300 }, "C4"),
        (FaultKind::SpuriousRise { sensor: "C5".into(), pulse_ms: 300 }, "C5"),
        (FaultKind::SpuriousFall { sensor: "C5".into(), pulse_ms: 300 }, "C5"),
        (FaultKind::TableBlockedAtC4, "P"),
        (FaultKind::TableBlockedAtC5, "P"),
        (FaultKind::TableBlockedBetween, "P"),
        (FaultKind::ActuatorStuckOff("A4".into()), "P"),
        (FaultKind::ActuatorStuckOn("A4".into()), "P"),
    ];
    for s in ["C0", "C1", "C2", "C3", "C6", "C7", "C8", "C9", "C10"] {
        let p: &'static str = Box::leak(s.to_string().into_boxed_str());
        v.push((FaultKind::SensorStuckAt0(s.into()), p));
        v.push((FaultKind::SensorStuckAt1(s.into()), p));
        v.push((FaultKind::SpuriousRise { sensor: s.into(), pulse_ms: 300 }, p));
        v.push((FaultKind::SpuriousFall { sensor: s.into(), pulse_ms: 300 }, p));
    }
    for a in ["A0", "A1", "A2", "A3", "A5", "A6"] {
        v.push((FaultKind::ActuatorStuckOff(a.into()), "drive"));
        v.push((FaultKind::ActuatorStuckOn(a.into()), "drive"));
    }
    v.push((FaultKind::ConveyorSlowed { actuator: "A1".into(), percent: 50 }, "drive"));
    v
}

/// `vigie campaign diag`: every fault of the library at random times over `seeds` seeds,
/// and `fault_free_hours` of fault-free runs.
pub(crate) fn campaign(dir: &Path, seeds: u64, fault_free_hours: u64, only: Option<&str>) -> anyhow::Result<ExitCode> {
    let mut out = std::io::stdout().lock();
    let err = |p: Vec<vigie_core::diag::Problem>| anyhow::anyhow!("{}", vigie_core::diag::render(&p));
    writeln!(out, "fault | expected partition | right certain | wrong certain | none | delay ms p50/p90/max")?;
    for (kind, part) in library() {
        let name = format!("{kind:?}");
        if only.is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let (mut right, mut wrong, mut none) = (0, 0, 0);
        let mut delays = Vec::new();
        for seed in 0..seeds {
            let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
            x ^= x >> 31;
            let at = 60_000 + (x % 120_000);
            let (o, _) = pop::closed_loop(dir, seed + 1, at + 60_000, Some((kind.clone(), at))).map_err(err)?;
            let first = o.diagnoses.iter().find(|d| d.time_ms >= at);
            let early = o.diagnoses.iter().any(|d| d.time_ms < at);
            match first {
                Some(d) if !early && (d.partition == part || (part == "drive" && d.partition.ends_with("_drive")) ) => {
                    right += 1;
                    delays.push(d.time_ms - at);
                }
                Some(_) => wrong += 1,
                None if early => wrong += 1,
                None => none += 1,
            }
        }
        delays.sort_unstable();
        let q = |p: usize| delays.get(delays.len().saturating_sub(1) * p / 100).copied().unwrap_or(0);
        writeln!(out, "{name} | {part} | {right} | {wrong} | {none} | {}/{}/{}", q(50), q(90), q(100))?;
    }
    let mut false_certain = 0;
    for h in 0..fault_free_hours {
        let (o, _) = pop::closed_loop(dir, 1000 + h, 3_600_000, None).map_err(err)?;
        false_certain += o.diagnoses.len();
    }
    writeln!(out, "fault-free: {fault_free_hours} simulated hours, {false_certain} certain diagnoses (false)")?;
    Ok(ExitCode::SUCCESS)
}

/// `vigie bench-diag`: diagnoser cost per cycle (station, 1000 synthetic turntables),
/// build times, and libFAUDES' centralized diagnoser for 3, 4, 5 turntables.
pub(crate) fn bench(dir: &Path) -> anyhow::Result<ExitCode> {
    let mut out = std::io::stdout().lock();
    let err = |p: Vec<vigie_core::diag::Problem>| anyhow::anyhow!("{}", vigie_core::diag::render(&p));
    let (_, sim) = pop::closed_loop(dir, 1, 1000, None).map_err(err)?;
    // Station: replay a production minute through the diagnosers alone.
    let (mut o, mut sim2) = pop::closed_loop(dir, 2, 10, None).map_err(err)?;
    let _ = &mut o;
    let mut frames = Vec::new();
    for _ in 0..6000 {
        sim2.cycle();
        frames.push((sim2.now(), sim2.engine.frame().clone()));
    }
    let diag = sim.diagnosers.clone().ok_or_else(|| anyhow::anyhow!("no diagnosers"))?;
    let mut d = diag.clone();
    let start = Instant::now();
    for (t, f) in &mut frames {
        d.update(*t, f);
    }
    let per = start.elapsed().as_secs_f64() * 1e6 / frames.len() as f64;
    writeln!(out, "station: {} components, {per:.3} us per cycle (mean over {} cycles of production)", diag.compiled.components.len(), frames.len())?;
    // Synthetic 1000 turntables.
    let text = std::fs::read_to_string(dir.join("diagnosers.ron"))?;
    let file = pop::model::DiagnoserFile::from_ron(&text, &dir.join("diagnosers.ron")).map_err(|p| anyhow::anyhow!("{p}"))?;
    let table = file.components.iter().find(|c| c.id == "table").ok_or_else(|| anyhow::anyhow!("no table"))?;
    let n = 1000;
    let (plant, syn) = pop::synthetic(n, table);
    let mut symbols = plant.symbols();
    for a in pop::build::aux_names(&syn) {
        let _ = symbols.declare(&a, vigie_core::symbols::Space::Aux);
    }
    let syn_text = syn.to_ron();
    let start = Instant::now();
    let compiled = pop::build::compile(&syn, &syn_text, Path::new("<synthetic>"), &symbols, None).map_err(err)?;
    let build = start.elapsed();
    let mut d = pop::Diagnosers::new(compiled, &symbols);
    let mut frame = vigie_core::frame::Frame::new(symbols.sizes());
    for i in 0..n {
        frame.now[1].set(i, false);
        frame.now[0].set(2 * i, true);
    }
    let cycles = 4000u64;
    let start = Instant::now();
    for k in 0..cycles {
        frame.shift();
        // One turntable in ten rotates at a time: A4 toggles every 4 s per component.
        let t = k * 10;
        for i in (0..n).filter(|i| (t / 10 + *i as u64 * 37) % 400 == 0) {
            let v = frame.now[1].get(i);
            frame.now[1].set(i, !v);
        }
        d.update(vigie_core::Millis(t), &mut frame);
    }
    let per = start.elapsed().as_secs_f64() * 1e6 / cycles as f64;
    writeln!(out, "synthetic: {n} turntables, build {:.1} ms, {per:.2} us per cycle", build.as_secs_f64() * 1e3)?;
    // Construction time vs libFAUDES for k identical turntables.
    let tmp = std::env::temp_dir().join("vigie-bench-diag");
    std::fs::create_dir_all(&tmp)?;
    let c = &pop::load(dir).map_err(err)?.0.compiled;
    let tc = c.components.iter().find(|c| c.id == "table").ok_or_else(|| anyhow::anyhow!("no table"))?;
    let (g, m) = pop::faudes_export(tc);
    std::fs::write(tmp.join("table.gen"), g)?;
    std::fs::write(tmp.join("table.ftm"), m)?;
    for k in [3usize, 4, 5] {
        let (plant, syn) = pop::synthetic(k, table);
        let mut symbols = plant.symbols();
        for a in pop::build::aux_names(&syn) {
            let _ = symbols.declare(&a, vigie_core::symbols::Space::Aux);
        }
        let t = syn.to_ron();
        let start = Instant::now();
        let _ = pop::build::compile(&syn, &t, Path::new("<synthetic>"), &symbols, None).map_err(err)?;
        writeln!(out, "vigie decentralized build, {k} turntables: {:.3} ms", start.elapsed().as_secs_f64() * 1e3)?;
    }
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| PathBuf::from(".venv"), PathBuf::from);
    let script = PathBuf::from("tests/peers/faudes_diag.py");
    match std::process::Command::new(venv.join("bin/python")).arg(&script).arg("bench").arg(tmp.join("table.gen")).arg(tmp.join("table.ftm")).output() {
        Ok(o) => out.write_all(&o.stdout)?,
        Err(e) => writeln!(out, "libFAUDES: not run ({e}); create the venv: python3 -m venv .venv && .venv/bin/pip install -r requirements-test.txt")?,
    }
    Ok(ExitCode::SUCCESS)
}
