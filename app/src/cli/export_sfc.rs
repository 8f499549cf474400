//! `vigie export-sfc FILE`: the region monitor of a `*.swa.ron`, a `*.swpn.ron` or a `tasks.ron` (its
//! committed regions, checked against the automata) as an IEC 61131-3 program: SFC in
//! PLCopen XML and one Structured Text function block (`core/src/swa/sfc.rs`).

use anyhow::{Context, anyhow};
use std::path::Path;
use std::process::ExitCode;
use vigie_core::swa::sfc;

pub(crate) fn run(file: &Path, out: Option<&Path>) -> anyhow::Result<ExitCode> {
    let render = |p: &[vigie_core::diag::Problem]| vigie_core::diag::render(p);
    let (swa, regions, regions_path) =
        sfc::load_monitor(file).map_err(|p| anyhow!("{}", render(&p)))?;
    let chart = sfc::translate(&swa, &regions).map_err(|e| {
        let text = std::fs::read_to_string(&regions_path).unwrap_or_default();
        anyhow!("{}", render(&[e.problem(&regions_path, &text)]))
    })?;
    let name = file
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("monitor");
    let stem = name
        .strip_suffix(".swa.ron")
        .or_else(|| name.strip_suffix(".swpn.ron"))
        .or_else(|| name.strip_suffix(".ron"))
        .unwrap_or(name);
    let dir = out.map_or_else(
        || file.parent().unwrap_or(Path::new(".")).to_path_buf(),
        Path::to_path_buf,
    );
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let xml = dir.join(format!("{stem}.sfc.xml"));
    let st = dir.join(format!("{stem}.monitor.st"));
    std::fs::write(&xml, chart.plcopen(stem))
        .with_context(|| format!("cannot write {}", xml.display()))?;
    std::fs::write(&st, chart.function_block())
        .with_context(|| format!("cannot write {}", st.display()))?;
    println!(
        "SFC1: {} steps ({} locations unreachable under acceptable behaviour, {} duplicated), {} transitions, {} offset variables; {} forbidden events; SFC2: 2 steps",
        chart.steps.len(),
        chart.regions.iter().filter(|r| r.is_empty()).count(),
        chart.duplicated.len(),
        chart.transitions.len(),
        chart.offsets.len(),
        chart.forbidden.len()
    );
    println!("wrote {}", xml.display());
    println!("wrote {}", st.display());
    Ok(ExitCode::SUCCESS)
}
