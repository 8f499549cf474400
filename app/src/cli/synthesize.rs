//! `vigie synthesize FILE`: the monitoring regions `E*` of a task set (`tasks.ron`) or
//! of stopwatch automata (`*.swa.ron`), written beside it (`core/src/swa/`).

use anyhow::{Context, anyhow};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use vigie_core::diag::codes;
use vigie_core::swa::regions::RegionsFile;
use vigie_core::swa::swpn::SwpnFile;
use vigie_core::swa::{Limits, SwaFile, from_tasks, synthesize};
use vigie_core::tasks::TaskSet;

/// The automata of `file` and where their regions go.
fn automata(file: &Path) -> anyhow::Result<(SwaFile, String, PathBuf)> {
    let render = |p: &[vigie_core::diag::Problem]| vigie_core::diag::render(p);
    let name = file.file_name().and_then(|n| n.to_str()).unwrap_or("");
    if let Some(stem) = name.strip_suffix(".swpn.ron") {
        let (net, text) = SwpnFile::load(file).map_err(|p| anyhow!("{}", render(&p)))?;
        let t = net
            .translate(file, &text)
            .map_err(|p| anyhow!("{}", render(&p)))?;
        return Ok((
            t.automaton,
            String::new(),
            file.with_file_name(format!("{stem}.regions.ron")),
        ));
    }
    if let Some(stem) = name.strip_suffix(".swa.ron") {
        let text = std::fs::read_to_string(file)
            .with_context(|| format!("cannot read {}", file.display()))?;
        let parsed: SwaFile = ron::from_str(&text)
            .map_err(|e| anyhow!("{}", render(&[vigie_core::diag::ron_problem(file, &e)])))?;
        Ok((
            parsed,
            text,
            file.with_file_name(format!("{stem}.regions.ron")),
        ))
    } else {
        let set = TaskSet::load(file).map_err(|p| anyhow!("{}", render(&p)))?;
        Ok((
            from_tasks::automata(&set),
            String::new(),
            file.with_file_name("regions.ron"),
        ))
    }
}

pub(crate) fn run(
    file: &Path,
    out: Option<&Path>,
    check: bool,
    limit: usize,
    members: usize,
) -> anyhow::Result<ExitCode> {
    let render = |p: &[vigie_core::diag::Problem]| vigie_core::diag::render(p);
    let (parsed, text, default_out) = automata(file)?;
    let swa = parsed
        .compile(file, &text)
        .map_err(|p| anyhow!("{}", render(&[p])))?;
    let t0 = Instant::now();
    let limits = Limits {
        iterations: limit,
        members,
    };
    let s = synthesize(&swa, limits)
        .map_err(|e| anyhow!("{}: error[{}]: {e}", file.display(), codes::SWA_LIMIT.id))?;
    let elapsed = t0.elapsed();
    let source = file.display().to_string();
    let regions = RegionsFile::new(&source, &parsed, &swa, &s);
    let out = out.map_or(default_out, Path::to_path_buf);
    println!(
        "{} components, {} clocks, {} locations ({} unreachable under acceptable behaviour), synthesised in {:.3} s",
        swa.components.len(),
        swa.clocks.len(),
        swa.locations.len(),
        s.unreachable().len(),
        elapsed.as_secs_f64()
    );
    if !s.approximate.is_empty() {
        println!(
            "conservative: {} locations over-approximated (may detect later, never falsely)",
            s.approximate.len()
        );
    }
    for l in &regions.locations {
        if l.region.is_empty() {
            println!("  {}: unreachable", l.location);
        } else {
            println!("  {}: {}", l.location, l.region.join("  ||  "));
        }
    }
    let text = regions.to_ron();
    if check {
        let old = std::fs::read_to_string(&out).unwrap_or_default();
        if old == text {
            println!("{} is up to date", out.display());
            return Ok(ExitCode::SUCCESS);
        }
        eprintln!(
            "{}: error[{}]: not the regions these automata give; run `vigie synthesize {}` (with the `--members` it was written with, if not the default)",
            out.display(),
            codes::REGIONS_STALE.id,
            file.display()
        );
        return Ok(ExitCode::FAILURE);
    }
    std::fs::write(&out, text).with_context(|| format!("cannot write {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

/// `vigie bench-synthesis`: synthesis time against the number of tasks.
pub(crate) fn bench(max_tasks: usize, budget: f64) {
    println!("tasks  locations  clocks  polyhedra  approximated  time (s)");
    let mut last = 0.0;
    let mut last_n = 0;
    for n in 1..=max_tasks {
        if last > budget {
            println!("{n:>5}  not run: {last_n} tasks took {last:.1} s > budget {budget} s");
            continue;
        }
        last_n = n;
        let set = vigie_core::tasks::synthetic(n);
        let file = from_tasks::automata(&set);
        let Ok(swa) = file.compile(Path::new("<synthetic>"), "") else {
            println!("{n:>5}  the product is too large");
            break;
        };
        let t0 = Instant::now();
        match synthesize(&swa, Limits::default()) {
            Ok(s) => {
                last = t0.elapsed().as_secs_f64();
                let members: usize = s.regions.iter().map(Vec::len).sum();
                println!(
                    "{n:>5}  {:>9}  {:>6}  {members:>9}  {:>12}  {last:>8.3}",
                    swa.locations.len(),
                    swa.clocks.len(),
                    s.approximate.len()
                );
            }
            Err(e) => {
                last = t0.elapsed().as_secs_f64();
                println!("{n:>5}  {e} after {last:.1} s");
            }
        }
    }
}
