//! `vigie export-st PLANT`: the observers, the filter with its fallback and the task
//! monitors as IEC 61131-3 Structured Text, to run at the end of the PLC cycle.

use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;

pub(crate) fn run(dir: &Path, out: Option<&Path>) -> anyhow::Result<ExitCode> {
    let bundle = super::load_valid_bundle(dir)?;
    let st = vigie_core::export::st::generate(&bundle, bundle.tasks.as_ref())
        .map_err(|e| anyhow::anyhow!("cannot export {}: {e}", dir.display()))?;
    match out {
        Some(path) => std::fs::write(path, st)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?,
        None => std::io::stdout().lock().write_all(st.as_bytes())?,
    }
    Ok(ExitCode::SUCCESS)
}
