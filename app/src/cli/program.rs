//! `vigie program export|import`: the PLC's own program in PLCopen TC6 XML (CODESYS,
//! TwinCAT, Beremiz, OpenPLC Editor), written from and read into Vigie's program model.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use vigie_core::control::{ErrorLibrary, Program};
use vigie_core::diag::render;
use vigie_core::plant::Plant;

/// What `vigie program` does.
#[derive(clap::Subcommand, Debug)]
pub(crate) enum ProgramCmd {
    /// Write a control program as PLCopen XML, for the PLC's own tool: the plant's
    /// reference, a program file, or a variant of its error library.
    Export {
        #[command(flatten)]
        plant: super::PlantArg,
        /// The program (RON or PLCopen XML); default: `programs/reference.ron`.
        #[arg(long, conflicts_with = "variant")]
        file: Option<PathBuf>,
        /// A variant of `programs/errors.ron`.
        #[arg(long)]
        variant: Option<String>,
        /// Write to this file instead of the standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Read a PLCopen XML program against the plant, check it, and print the program
    /// Vigie runs (RON), or write it with `--out`.
    Import {
        #[command(flatten)]
        plant: super::PlantArg,
        /// The PLCopen XML file.
        #[arg(long)]
        file: PathBuf,
        /// Write the RON program to this file instead of the standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
}

fn load_program(path: &Path, plant: &Plant) -> anyhow::Result<Program> {
    let compiled = vigie_core::control::CompiledProgram::load(path, plant)
        .map_err(|p| anyhow::anyhow!("{} cannot be run:\n{}", path.display(), render(&p)))?;
    Ok(compiled.program)
}

fn emit(text: &str, out: Option<&Path>) -> anyhow::Result<()> {
    match out {
        Some(path) => std::fs::write(path, text)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?,
        None => std::io::stdout().lock().write_all(text.as_bytes())?,
    }
    Ok(())
}

pub(crate) fn run(cmd: ProgramCmd) -> anyhow::Result<ExitCode> {
    match cmd {
        ProgramCmd::Export {
            plant,
            file,
            variant,
            out,
        } => {
            let dir = &plant.plant;
            let plant = Plant::load(&dir.join("plant.ron"))
                .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
            let (program, source) = match (file, variant) {
                (_, Some(id)) => {
                    let lib = ErrorLibrary::load(&dir.join("programs/errors.ron"), &plant)
                        .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
                    let Some(v) = lib.variants.into_iter().find(|v| v.def.id == id) else {
                        anyhow::bail!(
                            "no variant `{id}` in {}",
                            dir.join("programs/errors.ron").display()
                        );
                    };
                    (v.program, dir.join("programs/errors.ron"))
                }
                (Some(f), None) => (load_program(&f, &plant)?, f),
                (None, None) => {
                    let f = dir.join("programs/reference.ron");
                    (load_program(&f, &plant)?, f)
                }
            };
            let xml = vigie_core::plcopen::export(&program, &plant, &source)
                .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
            emit(&xml, out.as_deref())?;
            if let Some(o) = out {
                eprintln!(
                    "{} (version {}) written to {}",
                    program.name,
                    program.version(),
                    o.display()
                );
            }
            Ok(ExitCode::SUCCESS)
        }
        ProgramCmd::Import { plant, file, out } => {
            let dir = &plant.plant;
            let plant = Plant::load(&dir.join("plant.ron"))
                .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
            let program = load_program(&file, &plant)?;
            let pretty = ron::ser::PrettyConfig::new().struct_names(true);
            let text = ron::ser::to_string_pretty(&program, pretty)?;
            emit(&format!("{text}\n"), out.as_deref())?;
            eprintln!(
                "{}: {} charts, {} steps, {} transitions, {} equations; version {}",
                file.display(),
                program.charts.len(),
                program.steps().count(),
                program.transitions().count(),
                program.equations.len(),
                program.version()
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}
