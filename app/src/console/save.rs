//! The save dialog of the exports: the desktop's own (rfd: the XDG portal, else
//! zenity), on a thread of its own so that the console keeps running while it is
//! open. The chosen path comes back as a typed [`Command`]; a dialog that cannot open
//! (no portal, no zenity) or that is cancelled is said in the status line, and the
//! path field beside the button still exports under the data folder.

use super::Command;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, TryRecvError, channel};

/// What is exported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Export {
    /// The journal (CSV).
    Journal,
    /// The alarm history as filtered (CSV).
    Alarms,
    /// The changes of the trends' signals over their range (CSV).
    Trend,
    /// The alarm history as filtered, laid out for paper (HTML), then opened to print.
    AlarmsPrint,
    /// The incident report: a folder (report.md, one PNG per level, the chronogram).
    Report,
    /// The program on screen as PLCopen XML, for the PLC's own tool.
    Program,
}

impl Export {
    /// The file name offered.
    pub fn default_name(self) -> &'static str {
        match self {
            Self::Journal => "vigie-journal.csv",
            Self::Alarms => "vigie-alarms.csv",
            Self::Trend => "vigie-trend.csv",
            Self::AlarmsPrint => "vigie-alarms.html",
            Self::Report => "incident-report",
            Self::Program => "program.xml",
        }
    }

    /// The file type offered: its name and extension.
    fn filter(self) -> (&'static str, &'static str) {
        match self {
            Self::AlarmsPrint => ("HTML", "html"),
            Self::Program => ("PLCopen XML", "xml"),
            _ => ("CSV", "csv"),
        }
    }

    /// The command that writes the export to `path`.
    pub fn command(self, path: PathBuf) -> Command {
        match self {
            Self::Journal => Command::ExportCsv(path),
            Self::Alarms => Command::ExportAlarms(path),
            Self::Trend => Command::ExportTrend(path),
            Self::AlarmsPrint => Command::PrintAlarms(path),
            Self::Report => Command::ExportReport(path),
            Self::Program => Command::ExportProgram(path),
        }
    }
}

/// The dialog open, if any.
#[derive(Default)]
pub struct SaveDialog {
    open: Option<(Export, Receiver<Option<PathBuf>>)>,
}

impl std::fmt::Debug for SaveDialog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SaveDialog")
            .field("open", &self.open.as_ref().map(|(e, _)| e))
            .finish()
    }
}

impl SaveDialog {
    /// True while a dialog is open.
    pub fn is_open(&self) -> bool {
        self.open.is_some()
    }

    /// Opens the dialog for `what` in `dir`; false when one is already open or the
    /// thread cannot start.
    pub fn ask(&mut self, what: Export, dir: &Path) -> bool {
        if self.open.is_some() {
            return false;
        }
        let (tx, rx) = channel();
        let dir = dir.to_path_buf();
        let spawned = std::thread::Builder::new()
            .name("vigie-save-dialog".into())
            .spawn(move || {
                let _ = std::fs::create_dir_all(&dir);
                let dialog = rfd::FileDialog::new()
                    .set_title("Vigie: export")
                    .set_directory(&dir)
                    .set_file_name(what.default_name());
                // A report is a folder of its own: named like a file, no type.
                let path = if what == Export::Report {
                    dialog.save_file()
                } else {
                    dialog
                        .add_filter(what.filter().0, &[what.filter().1])
                        .save_file()
                };
                let _ = tx.send(path);
            });
        if spawned.is_err() {
            return false;
        }
        self.open = Some((what, rx));
        true
    }

    /// The dialog's answer once it closed: `Some(Ok(command))` for a chosen path,
    /// `Some(Err(()))` for a cancel or a dialog that could not open.
    pub fn poll(&mut self) -> Option<Result<Command, ()>> {
        let (what, rx) = self.open.as_ref()?;
        let answer = match rx.try_recv() {
            Ok(Some(path)) => Some(Ok(what.command(path))),
            Ok(None) | Err(TryRecvError::Disconnected) => Some(Err(())),
            Err(TryRecvError::Empty) => None,
        };
        if answer.is_some() {
            self.open = None;
        }
        answer
    }
}
