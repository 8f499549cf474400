//! The operator console: state, the closed set of [`Command`]s the views emit, and the
//! one place ([`Console::apply`]) where they change the simulation.
//!
//! `App::logic` advances the simulation by real elapsed time × speed, in whole PLC
//! cycles, capped per frame; `App::ui` only renders (see `views.rs`).

mod diagnosers;
mod grafcet;
pub mod journal;
mod ladder;
pub mod link;
mod maintenance;
mod past;
mod placement;
pub mod report;
pub mod save;
pub mod synoptic;
mod training;
pub mod trends;
pub mod users;
mod verification;
mod views;
mod words;

use crate::i18n::{I18n, Lang};
use crate::theme::Palette;
use journal::Journal;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use vigie_core::access::{Permission, Role};
use vigie_core::control::{CompiledProgram, ErrorLibrary};
use vigie_core::emulator::{NamedFault, PlantExercise};
use vigie_core::sim::{OperatorAction, Options, ProgramChoice, Scenario, Simulation};
use vigie_core::time::Millis;

pub use maintenance::{Draft, DraftEdit, FixCheck, parse_actions};
pub use training::{FixLine, FixOutcome, History, Score, ScoreRecord, correct_fix, verify_fix};

/// The console's modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Mode {
    /// Operator console.
    #[default]
    Production,
    /// Control charts: active steps, receptivities, edit and recompile.
    Maintenance,
    /// Control-error library, fault injection and score.
    Training,
}

impl Mode {
    /// Parses `production`, `maintenance` or `training`.
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "production" => Some(Self::Production),
            "maintenance" => Some(Self::Maintenance),
            "training" => Some(Self::Training),
            _ => None,
        }
    }
}

/// Names of the five explanation levels, as on their buttons.
pub const LEVEL_NAMES: [&str; 5] = [
    "0 Current state",
    "1 Projection",
    "2 Before stop",
    "3 Advanced",
    "4 Hypothesis",
];

/// Everything the operator can ask for. Views emit commands; [`Console::apply`] is the
/// only place that acts on them.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Run the simulation.
    Run,
    /// Pause it.
    Pause,
    /// Run one PLC cycle (paused).
    Step,
    /// Simulation speed, 0.1 to 100.
    SetSpeed(f64),
    /// A plant action (Start, Stop, Reset…), through the filter's rules.
    Plant(OperatorAction),
    /// Switch mode.
    SetMode(Mode),
    /// Show an explanation level (or none).
    ShowLevel(Option<usize>),
    /// Acknowledge an alarm with a note.
    Acknowledge {
        /// Alarm id.
        id: u64,
        /// Note (may be empty).
        note: String,
    },
    /// Acknowledge several alarms at once: every unacknowledged one (`None`) or those
    /// of the page shown.
    AcknowledgeAll {
        /// The alarms of the page, or `None` for all.
        ids: Option<Vec<u64>>,
        /// Note (may be empty).
        note: String,
    },
    /// Shelve an alarm for a time, with a reason (refused for a safety alarm).
    Shelve {
        /// Alarm id.
        id: u64,
        /// Duration, ms of plant time.
        ms: u64,
        /// The operator's reason.
        reason: String,
    },
    /// Unshelve an alarm.
    Unshelve(u64),
    /// Close the shelving form without shelving.
    CloseShelveForm,
    /// Replay the synoptic at a recorded time (`None`: live).
    Scrub(Option<u64>),
    /// Export the journal to CSV (a relative path is under the data folder).
    ExportCsv(PathBuf),
    /// Export the alarm history, as filtered, to CSV (a relative path is under the data
    /// folder).
    ExportAlarms(PathBuf),
    /// Export the changes of the trends' signals over their range to CSV (a relative
    /// path is under the data folder).
    ExportTrend(PathBuf),
    /// Write the alarm history, as filtered, as a document laid out for paper (HTML;
    /// a relative path is under the data folder), then open it in the desktop's
    /// browser to print it (when the console opens files, see
    /// [`ConsoleOptions::open_files`]).
    PrintAlarms(PathBuf),
    /// Open the desktop's save dialog for an export; the export follows the choice.
    SaveAs(save::Export),
    /// Show the console in this language.
    SetLanguage(Lang),
    /// Export the incident report (Markdown + one PNG per level) into a folder.
    ExportReport(PathBuf),
    /// Maintenance: write the program on screen as PLCopen XML (for the PLC's tool);
    /// an empty path writes `<program>-<version>.xml` under the data folder.
    ExportProgram(PathBuf),
    /// Maintenance: recompile the edited program.
    Recompile,
    /// Maintenance: restart the scenario with the compiled edit.
    RestartWithEdit,
    /// Maintenance: drop the edits.
    DiscardEdits,
    /// Restart the current scenario with its own program.
    Restart,
    /// Training: load a variant of the control-error library.
    LoadVariant(String),
    /// Training: load a plant-fault exercise (`exercises.ron`).
    LoadPlantExercise(String),
    /// Training, plant-fault exercise: the trainee names the faulty component.
    SubmitDiagnosis(String),
    /// Training: end the exercise without a correct fix and show the answer (the
    /// debrief; recorded in the trainee's history as given up).
    ShowAnswer,
    /// Log in with a name and a password (checked against `users.ron`).
    Login {
        /// Login name.
        name: String,
        /// Password (never stored nor journaled).
        password: String,
    },
    /// Log out: back to the operator role.
    Logout,
    /// Training: inject a fault of the fault library now.
    InjectFault(usize),
    /// Open another plant folder (the plant picker): its reference program, the
    /// console's language kept; the session starts over (logged out).
    OpenPlant(PathBuf),
    /// Training and maintenance: compile the text on screen, re-run the scenario with
    /// it, score it and keep what ran ([`FixCheck`]).
    VerifyFix,
    /// The chronogram's time window, ms (clamped to 2 s .. 1 h).
    ChronoWindow(u64),
    /// The program view scrolled to the focused element: no more scrolling to it.
    ProgramScrolled,
    /// Maintenance: show the program as a GRAFCET, as ladder rungs or as text.
    ShowProgramView(ProgramView),
    /// From the hypothesis: open the program (maintenance) on this element (a step, a
    /// transition or an equation's target), framed and scrolled into view.
    ShowInProgram(String),
    /// Maintenance: edit one element of the draft (a receptivity, a step's actions, an
    /// equation).
    EditDraft(DraftEdit),
    /// Maintenance: verify the loaded constraint set (worker thread).
    VerifyConstraints,
    /// Maintenance: replay the verification's shortest hazard trace.
    ReplayCounterexample,
}

/// How the maintenance view shows the control program.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ProgramView {
    /// The charts as GRAFCET (IEC 60848).
    #[default]
    Grafcet,
    /// The output equations as ladder rungs.
    Ladder,
    /// Every element's text in a list.
    Text,
}

/// Options for opening the console.
#[derive(Clone, Debug)]
pub struct ConsoleOptions {
    /// Plant folder.
    pub plant_dir: PathBuf,
    /// Scenario file (`None`: the reference program with the layout's arrivals).
    pub scenario: Option<PathBuf>,
    /// Initial speed.
    pub speed: f64,
    /// Initial mode.
    pub mode: Mode,
    /// Explanation level to show once a trip is explained.
    pub level: Option<usize>,
    /// Run the simulation headless up to this time before the first frame.
    pub run_until_ms: Option<u64>,
    /// Start paused.
    pub paused: bool,
    /// Journal directory (`None`: memory only).
    pub data_dir: Option<PathBuf>,
    /// Press START before the first frame.
    pub start: bool,
    /// Load this variant of the control-error library (training).
    pub variant: Option<String>,
    /// Follow the live link of this configuration instead of the emulator.
    pub link: Option<PathBuf>,
    /// With `link` in monitor mode: the program the PLC should run, followed beside it.
    pub program: Option<PathBuf>,
    /// The language shown first (default: the system's, [`Lang::from_env`]).
    pub lang: Lang,
    /// Open a printed document in the desktop's browser (off by default: tests and
    /// headless runs write it only).
    pub open_files: bool,
}

impl ConsoleOptions {
    /// Options for `plant_dir` with defaults: reference program, 1x, production,
    /// journal in [`journal::data_dir_from_env`].
    pub fn new(plant_dir: &Path) -> Self {
        Self {
            plant_dir: plant_dir.to_path_buf(),
            scenario: None,
            speed: 1.0,
            mode: Mode::Production,
            level: None,
            run_until_ms: None,
            paused: false,
            data_dir: Some(journal::data_dir_from_env()),
            start: false,
            variant: None,
            link: None,
            program: None,
            lang: Lang::from_env(),
            open_files: false,
        }
    }
}

/// The file name a free run (no scenario file) stands at, in the plant folder.
const FREE_RUN: &str = "console.ron";

/// The scenario the console runs.
#[derive(Clone, Debug)]
pub(crate) struct Source {
    pub(crate) scenario: Scenario,
    pub(crate) path: PathBuf,
    /// The plant-fault exercise this run is (its fault is among the scenario's).
    pub(crate) plant_exercise: Option<String>,
}

impl Source {
    /// The run's title in the language shown: the reference program or a training
    /// variant by their console names, a scenario file by the plant folder's
    /// `scenario-<file stem>` when it has one, else the file's own name.
    pub(crate) fn title(&self, i18n: &I18n) -> String {
        words::title(i18n, &self.title_fields(), false)
    }

    /// What [`Source::title`] is built from, as a record's fields: `scenario` (the
    /// file's own name), `scenario_key` (the message or plant text that titles it) and
    /// `id` (a training variant).
    pub(crate) fn title_fields(&self) -> BTreeMap<String, String> {
        let free = self.path.file_name() == Some(std::ffi::OsStr::new(FREE_RUN));
        let mut f = BTreeMap::new();
        f.insert("scenario".to_string(), self.scenario.name.clone());
        let key = match (&self.scenario.program, free) {
            (ProgramChoice::Reference, true) if self.plant_exercise.is_some() => {
                f.insert(
                    "id".to_string(),
                    self.plant_exercise.clone().unwrap_or_default(),
                );
                "scenario-training".to_string()
            }
            (ProgramChoice::Reference, true) => "scenario-reference".to_string(),
            (ProgramChoice::Error(id), true) => {
                f.insert("id".to_string(), id.clone());
                "scenario-training".to_string()
            }
            _ => self.path.file_stem().map_or(String::new(), |s| {
                format!("scenario-{}", s.to_string_lossy())
            }),
        };
        f.insert("scenario_key".to_string(), key);
        f
    }

    fn free_run(plant_dir: &Path, program: ProgramChoice, name: &str) -> Self {
        let actions = match program {
            ProgramChoice::Error(_) => vec![vigie_core::sim::TimedAction {
                at_ms: 0,
                action: OperatorAction::Start,
            }],
            _ => Vec::new(),
        };
        Self {
            scenario: Scenario {
                name: name.to_string(),
                description: String::new(),
                plant: ".".into(),
                program,
                seed: 1,
                arrivals: None,
                faults: Vec::new(),
                actions,
                duration_ms: 120_000,
                filter: vigie_core::engine::FilterMode::Enforce,
                cycle_ms: 10,
                projection_ms: 10_000,
                diagnosers: plant_dir.join("diagnosers.ron").exists(),
                plausibility: true,
            },
            path: plant_dir.join(FREE_RUN),
            plant_exercise: None,
        }
    }

    /// The free run of the plant-fault exercise `e`: the reference program from Start,
    /// the exercise's fault hidden among the scenario's.
    fn plant_exercise(plant_dir: &Path, e: &PlantExercise) -> Self {
        let mut s = Self::free_run(
            plant_dir,
            ProgramChoice::Reference,
            &format!("Training: {}", e.id),
        );
        s.scenario.actions.push(vigie_core::sim::TimedAction {
            at_ms: 0,
            action: OperatorAction::Start,
        });
        s.scenario.faults.push(e.fault.clone());
        s.plant_exercise = Some(e.id.clone());
        s
    }

    fn build(&self) -> Result<Simulation, String> {
        Simulation::from_scenario(&self.scenario, &self.path, Options::default())
            .map_err(|p| vigie_core::diag::render(&p))
    }
}

/// A running incident-report capture (one screenshot per level).
#[derive(Clone, Debug)]
pub(crate) struct ReportJob {
    pub(crate) dir: PathBuf,
    pub(crate) level: usize,
    pub(crate) frames: u32,
    pub(crate) waiting: bool,
    pub(crate) shot: std::sync::Arc<std::sync::Mutex<Option<std::sync::Arc<egui::ColorImage>>>>,
    /// The level shown and whether the plant ran before the capture: given back after.
    pub(crate) restore: (Option<usize>, bool),
}

/// The console application.
pub struct Console {
    /// The closed loop.
    pub sim: Simulation,
    pub(crate) source: Source,
    pub(crate) plant_dir: PathBuf,
    /// The options the console opened with (the plant picker opens another plant
    /// folder with them).
    pub(crate) opened_with: ConsoleOptions,
    /// The plant folders beside this one (`plant.ron` in a sibling folder): folder and
    /// the plant's name, for the plant picker.
    pub(crate) plants: Vec<(PathBuf, String)>,
    /// Open a printed document in the desktop's browser.
    pub(crate) open_files: bool,
    /// Palette.
    pub palette: Palette,
    /// The journal.
    pub journal: Journal,
    /// Running (else paused).
    pub running: bool,
    /// Speed factor.
    pub speed: f64,
    budget_ms: f64,
    last_time: Option<f64>,
    /// Mode.
    pub mode: Mode,
    /// Explanation level shown on the synoptic.
    pub level: Option<usize>,
    wanted_level: Option<usize>,
    /// Replay time (`None`: live).
    pub replay: Option<u64>,
    /// Synoptic zoom/pan.
    pub view: synoptic::View,
    /// Status line (last refusal or result).
    pub status: String,
    pub(crate) notes: BTreeMap<u64, String>,
    pub(crate) csv_path: String,
    pub(crate) report_dir: String,
    pub(crate) report_job: Option<ReportJob>,
    pub(crate) synoptic_rect: Option<egui::Rect>,
    /// Where the chronogram was drawn last (for the incident report's picture).
    pub(crate) chrono_rect: Option<egui::Rect>,
    pub(crate) draft: Option<Draft>,
    pub(crate) compiled_edit: Option<CompiledProgram>,
    /// The last fix check: what it ran and found.
    pub last_fix: Option<FixCheck>,
    /// How the program is shown in maintenance.
    pub program_view: ProgramView,
    /// The program element the hypothesis link asked to show.
    pub program_focus: Option<String>,
    /// The program view scrolls to the focused element at the next frame (once).
    pub(crate) program_scroll: bool,
    pub(crate) problems: String,
    pub(crate) variants: Vec<(String, String, String)>,
    /// Per exercise: its correct fix (the reference program's texts).
    pub(crate) answers: BTreeMap<String, Vec<FixLine>>,
    /// The trainees' finished exercises (`training.csv` of the data folder).
    pub history: History,
    /// The training library: the fault library (`faults.ron`), the plant-fault
    /// exercises (`exercises.ron`) and the problems that kept a file out.
    pub library: Library,
    pub(crate) chrono_signals: BTreeSet<String>,
    /// The chronogram's time window, ms (2 s to 1 h).
    pub chrono_window_ms: u64,
    pub(crate) score: Score,
    pub(crate) wall_s: f64,
    pub(crate) alarm_filter_shelved: bool,
    /// The alarm list's page (pages of [`ALARMS_PER_PAGE`]).
    pub(crate) alarm_page: usize,
    /// The alarm history's search and filters.
    pub history_filter: vigie_core::alarms::HistoryFilter,
    /// The trends view (the historian's process history).
    pub trends: trends::TrendView,
    /// The save dialog open, if any.
    pub save: save::SaveDialog,
    /// The alarms of earlier runs last read from the historian: the second read, the
    /// rows or the error.
    past_alarms: Option<(u64, Result<Vec<crate::historian::AlarmRow>, String>)>,
    /// The texts, in the language shown.
    pub i18n: I18n,
    /// Where the journal and the exports go (`None`: the journal in memory only, the
    /// exports under the temporary folder).
    pub data_dir: Option<PathBuf>,
    /// The shelving form open on one alarm.
    pub(crate) shelve_form: Option<ShelveForm>,
    /// The re-initialisation's confirmation is open (it asks for a check of the plant).
    pub(crate) reinit_confirm: bool,
    /// The confirmation of entering manual mode is open.
    pub(crate) manual_confirm: bool,
    /// The last manual request refused, in operator terms (cleared by the next one
    /// taken).
    pub manual_refusal: Option<String>,
    /// The outputs jogged (ON while their Jog button is held).
    pub(crate) jogging: BTreeSet<String>,
    pub(crate) verification: verification::Verification,
    visuals_set: bool,
    /// Commands emitted by the last frame's views, applied at the next `logic`.
    pending: Vec<Command>,
    /// The live link followed instead of the emulator (`link.rs`).
    pub link: Option<link::LinkSession>,
    /// The accounts of the data folder.
    pub(crate) users: users::Users,
    /// Who is logged in (`None`: nobody, the operator role).
    pub user: Option<String>,
    /// The role in force.
    pub role: Role,
    /// The login dialog, open: the name and password typed.
    pub(crate) login: Option<(String, String)>,
    /// The bypass form: constraint, reason, minutes.
    pub(crate) bypass_form: (String, String, u64),
    /// The component picked in the plant-fault exercise's diagnosis form.
    pub(crate) diagnosis_pick: String,
    /// Failed logins in a row, and since when logins are locked after too many.
    failed_logins: (u32, Option<std::time::Instant>),
}

/// Failed logins in a row before logins are locked for [`LOGIN_LOCK`].
pub const MAX_FAILED_LOGINS: u32 = 5;

/// How long logins stay locked after [`MAX_FAILED_LOGINS`] failures.
pub const LOGIN_LOCK: std::time::Duration = std::time::Duration::from_secs(60);

/// Alarms on one page of the list.
pub const ALARMS_PER_PAGE: usize = 8;

/// The shelving form: the reason and the duration the operator chooses.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ShelveForm {
    pub(crate) id: u64,
    pub(crate) reason: String,
    pub(crate) minutes: u64,
}

/// The plant folder's training library, as data a trainer edits.
#[derive(Clone, Debug, Default)]
pub struct Library {
    /// The fault library (`faults.ron`): name and fault.
    pub faults: Vec<NamedFault>,
    /// The plant-fault exercises (`exercises.ron`).
    pub exercises: Vec<PlantExercise>,
    /// What kept a file of the library out (rendered problems, file:line:column), shown
    /// in the training view: a broken file is never skipped silently.
    pub problems: Vec<String>,
}

/// The control-error library's exercises and the training library, with the problems
/// of both and the ids they share.
fn training_library(plant_dir: &Path, sim: &Simulation) -> (Exercises, Library) {
    let (variants, broken) = sim_variants(plant_dir, sim);
    let mut library = load_library(plant_dir, sim);
    library.problems.extend(broken);
    for e in &library.exercises {
        if variants.0.iter().any(|(v, _, _)| *v == e.id) {
            library.problems.push(format!(
                "exercises.ron: exercise `{}` has the id of a control-error variant of \
                 programs/errors.ron: `--variant {}` and the history cannot tell them apart; \
                 the variant is loaded",
                e.id, e.id
            ));
        }
    }
    (variants, library)
}

fn load_library(plant_dir: &Path, sim: &Simulation) -> Library {
    use vigie_core::emulator::{load_exercises, load_faults};
    let plant = &sim.bundle.plant;
    let mut lib = Library::default();
    let emulator = Some(&sim.emulator);
    match load_faults(&plant_dir.join("faults.ron"), plant, emulator) {
        Ok(f) => lib.faults = f,
        Err(p) => lib.problems.push(vigie_core::diag::render(&p)),
    }
    match load_exercises(&plant_dir.join("exercises.ron"), plant, emulator) {
        Ok(e) => lib.exercises = e,
        Err(p) => lib.problems.push(vigie_core::diag::render(&p)),
    }
    lib
}

/// The users file of the data folder (none without one; a broken one is logged and
/// read as none).
fn load_users(opts: &ConsoleOptions) -> users::Users {
    match opts.data_dir.as_deref().map(users::Users::load) {
        None => users::Users::default(),
        Some(Ok(u)) => u,
        Some(Err(e)) => {
            tracing::warn!("{e}");
            users::Users::default()
        }
    }
}

impl Console {
    /// Opens the console; fails with the rendered problems when the plant or scenario
    /// cannot be loaded.
    pub fn new(opts: &ConsoleOptions) -> Result<Self, String> {
        let linked = link::options(opts)?;
        let opts = linked.as_ref().unwrap_or(opts);
        let (source, mut sim, plant_dir) = Self::open_simulation(opts)?;
        let ((variants, answers), library) = training_library(&plant_dir, &sim);
        let trends = trends::TrendView::new(&sim.bundle.symbols);
        let i18n = I18n::new(opts.lang, Some(&plant_dir)).map_err(|e| e.to_string())?;
        let view = synoptic_view(&i18n, &sim);
        let journal = Self::open_journal(opts, &sim, &source, &i18n);
        if opts.start {
            let _ = sim.act(&OperatorAction::Start);
        }
        if let Some(end) = opts.run_until_ms {
            sim.run_until(Millis(end));
        }
        let chrono_signals = plant_signals(&sim);
        let plant_exercise = source.plant_exercise.is_some();
        let plants = sibling_plants(&plant_dir);
        let mut c = Self {
            opened_with: opts.clone(),
            plants,
            library,
            sim,
            source,
            plant_dir,
            palette: Palette::default(),
            journal,
            running: !opts.paused,
            speed: opts.speed.clamp(0.1, 100.0),
            budget_ms: 0.0,
            last_time: None,
            mode: opts.mode,
            level: None,
            wanted_level: opts.level,
            replay: None,
            view,
            status: String::new(),
            notes: BTreeMap::new(),
            csv_path: "vigie-journal.csv".into(),
            report_dir: "incident-report".into(),
            report_job: None,
            synoptic_rect: None,
            chrono_rect: None,
            draft: None,
            compiled_edit: None,
            last_fix: None,
            program_view: ProgramView::default(),
            program_focus: None,
            program_scroll: false,
            problems: String::new(),
            variants,
            answers,
            history: History::load(opts.data_dir.as_deref()),
            chrono_signals,
            chrono_window_ms: 30_000,
            score: Score {
                variant: opts.variant.clone(),
                plant: plant_exercise,
                ..Score::default()
            },
            wall_s: 0.0,
            alarm_filter_shelved: false,
            alarm_page: 0,
            history_filter: vigie_core::alarms::HistoryFilter::default(),
            trends,
            save: save::SaveDialog::default(),
            past_alarms: None,
            i18n,
            data_dir: opts.data_dir.clone(),
            shelve_form: None,
            reinit_confirm: false,
            manual_confirm: false,
            manual_refusal: None,
            jogging: BTreeSet::new(),
            verification: verification::Verification::default(),
            visuals_set: false,
            pending: Vec::new(),
            link: None,
            users: load_users(opts),
            user: None,
            role: Role::Operator,
            login: None,
            bypass_form: (String::new(), String::new(), 15),
            diagnosis_pick: String::new(),
            failed_logins: (0, None),
            open_files: opts.open_files,
        };
        c.attach_link(opts)?;
        c.drain_journal();
        c.follow_trip();
        if c.mode == Mode::Maintenance {
            if c.may(Permission::EditProgram) {
                c.enter_maintenance();
            } else {
                c.mode = Mode::Production;
                c.refuse(Permission::EditProgram);
            }
        }
        Ok(c)
    }

    /// Loads the scenario (or the free run, or the training variant) and builds its
    /// simulation; returns the source, the simulation and the plant folder.
    fn open_simulation(opts: &ConsoleOptions) -> Result<(Source, Simulation, PathBuf), String> {
        let mut source = match &opts.scenario {
            Some(path) => Source {
                scenario: Scenario::load(path).map_err(|p| vigie_core::diag::render(&p))?,
                path: path.clone(),
                plant_exercise: None,
            },
            None => Source::free_run(
                &opts.plant_dir,
                ProgramChoice::Reference,
                "Reference program",
            ),
        };
        if let Some(config) = &opts.link {
            // The mirror of a live run replays the run's own engine cycle by cycle: with
            // the diagnosers and their constraint rewrite exactly when the run has them.
            source.scenario.diagnosers = link::runs_diagnosers(config)?;
            source.scenario.plausibility = link::runs_plausibility(config)?;
        }
        let plant_dir = source
            .path
            .parent()
            .unwrap_or(Path::new("."))
            .join(&source.scenario.plant);
        let (source, sim) = match &opts.variant {
            Some(id) => {
                // A plant-fault exercise's id, else a control-error variant's (a broken
                // `exercises.ron` is shown in the training view once the console opens).
                let exercises = vigie_core::plant::Plant::load(&plant_dir.join("plant.ron"))
                    .ok()
                    .and_then(|plant| {
                        let path = plant_dir.join("exercises.ron");
                        vigie_core::emulator::load_exercises(&path, &plant, None).ok()
                    })
                    .unwrap_or_default();
                let s = match exercises.iter().find(|e| &e.id == id) {
                    Some(e) => Source::plant_exercise(&plant_dir, e),
                    None => Source::free_run(
                        &plant_dir,
                        ProgramChoice::Error(id.clone()),
                        &format!("Training: {id}"),
                    ),
                };
                let sim = s.build()?;
                (s, sim)
            }
            None => {
                let sim = source.build()?;
                (source, sim)
            }
        };
        Ok((source, sim, plant_dir))
    }

    /// Opens the journal and writes the session's first entry.
    fn open_journal(
        opts: &ConsoleOptions,
        sim: &Simulation,
        source: &Source,
        i18n: &I18n,
    ) -> Journal {
        let mut journal = Journal::open(
            opts.data_dir.as_deref(),
            &sim.bundle.dir.display().to_string(),
            &sim.bundle.symbols,
        );
        {
            let mut fields = source.title_fields();
            let title = words::title(i18n, &fields, true);
            let text = i18n.ta_en("say-session", &[("scenario", (&title).into())]);
            fields.insert("scenario".into(), title);
            journal.push_coded(0, "session", &text, "say-session", fields);
        }
        journal
    }

    /// The maintenance draft (text of receptivities, actions, equations), if any; it
    /// changes through [`Command::EditDraft`].
    pub fn draft(&self) -> Option<&Draft> {
        self.draft.as_ref()
    }

    /// The training score.
    pub fn score(&self) -> &Score {
        &self.score
    }

    /// Installs fonts and visuals on a new context (call from the app's creator, before
    /// the first frame; `logic` does it otherwise, effective from the next frame).
    pub fn setup(&mut self, ctx: &egui::Context) {
        crate::theme::setup_context(ctx, &self.palette);
        self.visuals_set = true;
    }

    /// The latest explained trip, if any.
    pub fn latest_trip(&self) -> Option<usize> {
        self.sim.explanations.keys().next_back().copied()
    }

    fn drain_journal(&mut self) {
        let entries: Vec<_> = self.sim.take_journal().to_vec();
        for e in entries {
            let trip = e.kind == "trip";
            self.journal
                .push_coded(e.time_ms, &e.kind, &e.text, &e.code, e.fields);
            if trip && self.score.trip_wall_s.is_none() {
                self.score.trip_wall_s = Some(self.wall_s);
            }
        }
    }

    fn follow_trip(&mut self) {
        if self.latest_trip().is_some() && self.wanted_level.is_some() && self.level.is_none() {
            self.level = self.wanted_level;
            if let Some(l) = self.level {
                self.score.levels.insert(l);
            }
        }
    }

    /// Runs `n` PLC cycles.
    pub fn cycles(&mut self, n: u32) {
        for _ in 0..n {
            self.sim.cycle();
            if let Some(rec) = self.sim.engine.history.last() {
                self.journal.record_cycle(rec);
            }
        }
        self.drain_journal();
        self.follow_trip();
        self.journal.sync_alarms(&self.sim.alarms);
        self.journal.commit();
    }

    /// Advances by `dt_s` seconds of real time (× speed), in whole cycles, at most
    /// 5000 cycles per call.
    pub fn advance(&mut self, dt_s: f64) {
        if self.link.is_some() {
            self.pump_link();
            return;
        }
        if !self.running {
            self.budget_ms = 0.0;
            return;
        }
        let cycle = self.sim.cycle_period().0.max(1);
        self.budget_ms += dt_s.clamp(0.0, 0.25) * 1000.0 * self.speed;
        #[allow(clippy::cast_precision_loss)]
        let n = (self.budget_ms / cycle as f64).floor().clamp(0.0, 5000.0);
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let whole = n as u32;
        #[allow(clippy::cast_precision_loss)]
        {
            self.budget_ms =
                (self.budget_ms - f64::from(whole) * cycle as f64).min(cycle as f64 * 2.0);
        }
        self.cycles(whole);
    }

    /// Tells the operator `id` (with `args`) on the status line in the language shown;
    /// with a `kind`, also journals it at `sim_ms`: the English text as the record, the
    /// message id and its fields to show it in any language.
    fn say(&mut self, kind: Option<(&str, u64)>, id: &str, args: &[(&str, String)]) {
        let a: Vec<(&str, crate::i18n::Arg<'_>)> =
            args.iter().map(|(k, v)| (*k, v.into())).collect();
        self.status = self.i18n.ta(id, &a);
        if let Some((kind, sim_ms)) = kind {
            let text = self.i18n.ta_en(id, &a);
            let fields = args
                .iter()
                .map(|(k, v)| ((*k).to_string(), v.clone()))
                .collect();
            self.journal.push_coded(sim_ms, kind, &text, id, fields);
        }
    }

    fn now(&self) -> Millis {
        self.sim.now()
    }

    /// A training exercise: an error-library variant on the emulator, which never drives
    /// a plant; editing it is the exercise, open to every role.
    pub fn is_exercise(&self) -> bool {
        self.link.is_none() && matches!(self.source.scenario.program, ProgramChoice::Error(_))
    }

    /// Opens the program in maintenance on `element`: the GRAFCET for a step or a
    /// transition, the ladder for an equation's target.
    fn show_in_program(&mut self, element: String) {
        self.mode = Mode::Maintenance;
        self.enter_maintenance();
        let is_equation = self
            .sim
            .program
            .program()
            .program
            .equations
            .iter()
            .any(|(t, _)| *t == element);
        self.program_view = if is_equation {
            ProgramView::Ladder
        } else {
            ProgramView::Grafcet
        };
        self.program_focus = Some(element);
        self.program_scroll = true;
    }

    /// The exercise running: the control-error variant's id (`E01`).
    pub fn exercise_id(&self) -> Option<&str> {
        if self.link.is_some() {
            return None;
        }
        match &self.source.scenario.program {
            ProgramChoice::Error(id) => Some(id),
            _ => self.source.plant_exercise.as_deref(),
        }
    }

    /// The run's title in the language shown (the status line's).
    pub fn source_title(&self) -> String {
        self.source.title(&self.i18n)
    }

    /// The plant-fault exercise running, if any.
    pub fn plant_exercise(&self) -> Option<&PlantExercise> {
        let id = self
            .source
            .plant_exercise
            .as_deref()
            .filter(|_| self.link.is_none())?;
        self.library.exercises.iter().find(|e| e.id == id)
    }

    /// True when the role in force may do `p` (editing an exercise is everyone's).
    pub fn may(&self, p: Permission) -> bool {
        self.role.may(p) || (p == Permission::EditProgram && self.is_exercise())
    }

    /// The refusal of `p` for the role in force.
    /// Refuses `p` to the current role: said and journaled.
    fn refuse(&mut self, p: Permission) {
        let or = format!(" {} ", self.i18n.t("word-or"));
        let role = |r: &str| self.i18n.t(&format!("role-{r}"));
        let roles: Vec<String> = p.roles().into_iter().map(role).collect();
        let args = [
            ("what", self.i18n.t(&format!("perm-{p:?}"))),
            ("roles", roles.join(&or)),
            ("role", role(self.role.name())),
        ];
        let now = self.now().0;
        self.say(Some(("refused", now)), "say-refused", &args);
    }

    /// A login: the role of the account when the password is right. Guessing is
    /// slowed: after [`MAX_FAILED_LOGINS`] failures in a row, logins wait
    /// [`LOGIN_LOCK`] (wall-clock time: a person at the console).
    fn log_in(&mut self, name: &str, password: &str, now: u64) {
        if let Some(since) = self.failed_logins.1 {
            if since.elapsed() < LOGIN_LOCK {
                let left = LOGIN_LOCK.saturating_sub(since.elapsed()).as_secs().max(1);
                self.say(
                    None,
                    "say-login-locked",
                    &[
                        ("s", left.to_string()),
                        ("n", MAX_FAILED_LOGINS.to_string()),
                    ],
                );
                return;
            }
            self.failed_logins = (0, None);
        }
        let name = name.trim();
        match self.users.verify(name, password) {
            Ok(role) => {
                self.failed_logins = (0, None);
                self.role = role;
                self.user = Some(name.to_string());
                self.login = None;
                self.say(
                    Some(("login", now)),
                    "say-login",
                    &[
                        ("user", name.to_string()),
                        ("role", role.name().to_string()),
                    ],
                );
            }
            Err(e) => {
                // One message for both causes, in the console's language.
                let error = match &e {
                    users::UsersError::Refused => self.i18n.t("login-wrong"),
                    other => other.to_string(),
                };
                self.say(None, "say-login-refused", &[("error", error)]);
                self.journal.push(
                    now,
                    "login_refused",
                    &format!("login refused for `{name}`: {e}"),
                );
                self.failed_logins.0 += 1;
                if self.failed_logins.0 >= MAX_FAILED_LOGINS {
                    self.failed_logins.1 = Some(std::time::Instant::now());
                    self.journal.push(
                        now,
                        "login_locked",
                        &format!(
                            "{MAX_FAILED_LOGINS} failed logins in a row: logins locked for {} s",
                            LOGIN_LOCK.as_secs()
                        ),
                    );
                }
            }
        }
    }

    /// Checks `p`; a refusal is shown and journaled.
    fn require(&mut self, p: Permission) -> bool {
        if self.may(p) {
            return true;
        }
        self.refuse(p);
        false
    }

    /// Where an export goes: an absolute path as given, a relative one under the data
    /// folder (the journal's), never the current folder.
    pub fn export_path(&self, path: &Path) -> PathBuf {
        if path.is_absolute() {
            return path.to_path_buf();
        }
        self.data_dir
            .clone()
            .unwrap_or_else(|| std::env::temp_dir().join("vigie"))
            .join(path)
    }

    fn enter_maintenance(&mut self) {
        if self.draft.is_none() {
            self.draft = Some(Draft::of(&self.sim.program.program().program));
        }
    }

    /// Applies one command: the only place where the UI changes the simulation. What
    /// it journals is committed before it returns.
    pub fn apply(&mut self, cmd: Command) {
        self.apply_command(cmd);
        self.journal.sync_alarms(&self.sim.alarms);
        self.journal.commit();
    }

    fn apply_command(&mut self, cmd: Command) {
        if self.link_command(&cmd) {
            return;
        }
        let now = self.now().0;
        if !self.permitted(&cmd) {
            return;
        }
        match cmd {
            Command::Login { name, password } => self.log_in(&name, &password, now),
            Command::Logout => self.log_out(now),
            Command::Run => self.running = true,
            Command::Pause => self.running = false,
            Command::Step => {
                self.running = false;
                self.cycles(1);
            }
            Command::SetSpeed(s) => {
                self.speed = if s.is_finite() {
                    s.clamp(0.1, 100.0)
                } else {
                    1.0
                }
            }
            Command::Plant(action) => self.plant_command(action),
            Command::SetMode(m) => {
                self.mode = m;
                if m == Mode::Maintenance {
                    self.enter_maintenance();
                }
                self.say(
                    Some(("operator", now)),
                    "say-mode",
                    &[("mode", format!("{m:?}"))],
                );
            }
            Command::ShowLevel(l) => {
                self.level = l.filter(|l| *l < 5);
                if let Some(l) = self.level {
                    self.score.levels.insert(l);
                }
            }
            Command::Acknowledge { id, note } => self.acknowledge(id, note, now),
            Command::AcknowledgeAll { ids, note } => self.acknowledge_all(ids, note, now),
            Command::Shelve { id, ms, reason } => self.shelve(id, ms, &reason, now),
            Command::CloseShelveForm => self.shelve_form = None,
            Command::Unshelve(id) => match self.sim.alarms.unshelve(Millis(now), id) {
                Ok(()) => self.say(
                    Some(("unshelve", now)),
                    "say-unshelve",
                    &[("id", id.to_string())],
                ),
                Err(e) => self.say(None, "say-unshelve-refused", &[("error", e.to_string())]),
            },
            Command::Scrub(t) => self.replay = t,
            Command::ExportAlarms(path) => self.export_alarms(&path, now),
            Command::PrintAlarms(path) => self.print_alarms(&path, now),
            Command::ExportTrend(path) => self.export_trend(&path),
            Command::SetLanguage(lang) => self.set_language(lang, now),
            Command::SaveAs(what) => self.save_as(what),
            Command::ExportCsv(path) => self.export_csv(&path, now),
            Command::ExportReport(dir) => self.start_report(self.export_path(&dir)),
            Command::ExportProgram(path) => self.export_program(&path, now),
            Command::Recompile => self.recompile(),
            Command::RestartWithEdit => {
                if let Some(p) = self.compile_on_screen() {
                    self.restart(Some(p));
                }
            }
            Command::EditDraft(edit) => self.edit_draft(edit),
            Command::ShowProgramView(v) => self.program_view = v,
            Command::ProgramScrolled => self.program_scroll = false,
            Command::ChronoWindow(ms) => self.chrono_window_ms = ms.clamp(2_000, 3_600_000),
            Command::ShowInProgram(element) => self.show_in_program(element),
            Command::DiscardEdits => {
                self.draft = Some(Draft::of(&self.sim.program.program().program));
                self.compiled_edit = None;
                self.problems.clear();
            }
            Command::Restart => self.restart(None),
            Command::LoadVariant(id) => self.load_variant(id),
            Command::LoadPlantExercise(id) => self.load_plant_exercise(&id),
            Command::SubmitDiagnosis(component) => self.submit_diagnosis(&component),
            Command::ShowAnswer => self.finish_exercise(false),
            Command::InjectFault(i) => self.inject_fault(i, now),
            Command::OpenPlant(dir) => self.open_plant(dir),
            Command::VerifyFix => self.verify(),
            Command::VerifyConstraints => verification::start(self),
            Command::ReplayCounterexample => verification::replay(self),
        }
    }

    /// Opens the save dialog of `what` in the exports' folder.
    fn save_as(&mut self, what: save::Export) {
        let dir = self.export_path(Path::new(""));
        if !self.save.ask(what, &dir) {
            self.status = "a save dialog is already open".into();
        }
    }

    /// Writes the journal as CSV to `path` (under the data folder when relative).
    fn export_csv(&mut self, path: &Path, now: u64) {
        let path = self.export_path(path);
        self.status = match self.journal.export_csv(&path) {
            Ok(()) => format!("journal exported to {}", path.display()),
            Err(e) => format!("export failed: {e}"),
        };
        self.journal.push(now, "operator", &self.status.clone());
    }

    /// Whether the role may give `cmd`: the permission it needs, if any, checked.
    fn permitted(&mut self, cmd: &Command) -> bool {
        let needs = match cmd {
            Command::SetMode(Mode::Maintenance)
            | Command::ShowInProgram(_)
            | Command::Recompile
            | Command::RestartWithEdit
            | Command::ExportProgram(_)
            | Command::EditDraft(_) => Some(Permission::EditProgram),
            Command::Plant(OperatorAction::Filter(_)) => Some(Permission::ChangeFilterMode),
            Command::Plant(OperatorAction::Bypass { .. }) => Some(Permission::BypassConstraint),
            Command::InjectFault(_) => Some(Permission::Train),
            _ => None,
        };
        match needs {
            Some(p) => self.require(p),
            None => true,
        }
    }

    /// Logs the user out, back to the operator role (leaving maintenance if it needs a role).
    fn log_out(&mut self, now: u64) {
        if let Some(u) = self.user.take() {
            self.say(Some(("logout", now)), "say-logout", &[("user", u)]);
        }
        self.role = Role::Operator;
        if self.mode == Mode::Maintenance && !self.may(Permission::EditProgram) {
            self.mode = Mode::Production;
        }
        self.say(None, "say-logged-out", &[]);
    }

    /// Applies an operator action to the plant: status line, manual refusal, journal.
    fn plant_command(&mut self, action: OperatorAction) {
        let result = self.sim.act(&action);
        let result = match (result, &action) {
            (Err(e), OperatorAction::ManualSet(id, on)) => {
                // The request is not taken: checking it again gives the same
                // constraints, for the text in the language shown.
                let refused = self
                    .sim
                    .check_manual(id, *on)
                    .map(|(_, refused)| refused)
                    .unwrap_or_default();
                Err(words::refused_request(
                    &self.i18n,
                    &self.sim.bundle,
                    id,
                    *on,
                    &refused,
                    &e,
                ))
            }
            (r, _) => r,
        };
        match (&result, &action) {
            (Err(e), OperatorAction::ManualSet(..)) => {
                self.manual_refusal = Some(e.clone());
            }
            (Ok(()), OperatorAction::ManualSet(..) | OperatorAction::Manual(_)) => {
                self.manual_refusal = None;
            }
            _ => {}
        }
        self.status = match (result, &action) {
            (Ok(()), OperatorAction::Reinitialise { emptied: true }) => {
                self.i18n.t("status-reinit-emptied")
            }
            (Ok(()), OperatorAction::Reinitialise { emptied: false }) => {
                self.i18n.t("status-reinit-in-place")
            }
            (Ok(()), OperatorAction::Manual(true)) => self.i18n.t("status-manual-on"),
            (Ok(()), OperatorAction::Manual(false)) => self.i18n.t("status-manual-off"),
            (Ok(()), OperatorAction::ManualSet(id, on)) => self.i18n.ta(
                if *on {
                    "status-by-hand-on"
                } else {
                    "status-by-hand-off"
                },
                &[("id", id.into())],
            ),
            (
                Ok(()),
                OperatorAction::Bypass {
                    constraint,
                    minutes,
                    ..
                },
            ) => {
                self.bypass_form.1.clear();
                self.i18n.ta(
                    "status-bypassed",
                    &[
                        ("constraint", constraint.into()),
                        ("minutes", (*minutes).into()),
                    ],
                )
            }
            (Ok(()), OperatorAction::EndBypass(id)) => {
                self.i18n.ta("status-enforced-again", &[("id", id.into())])
            }
            (Ok(()), OperatorAction::Start) => self.i18n.t("status-start-pressed"),
            (Ok(()), OperatorAction::Stop) => self.i18n.t("status-stop-pressed"),
            (Ok(()), OperatorAction::Reset) => self.i18n.t("status-reset-done"),
            (Ok(()), OperatorAction::ResetDiagnosers) => self.i18n.t("status-diagnosers-reset"),
            (Ok(()), OperatorAction::Press(b)) => format!("{b} pressed"),
            (Ok(()), _) => format!("{action:?}: done"),
            (Err(e), OperatorAction::ManualSet(..)) => e.clone(),
            (Err(e), OperatorAction::Reset) => {
                let reason = match self.sim.engine.reset_check() {
                    Err(r) => words::reset_refused(&self.i18n, &r),
                    Ok(()) => e.clone(),
                };
                self.i18n
                    .ta("status-reset-refused", &[("reason", (&reason).into())])
            }
            (Err(e), _) => format!("{action:?}: {e}"),
        };
        self.drain_journal();
    }

    /// Acknowledges alarm `id` with a note.
    fn acknowledge(&mut self, id: u64, note: String, now: u64) {
        match self.sim.alarms.acknowledge(Millis(now), id, &note) {
            Ok(()) => {
                self.say(
                    Some(("ack", now)),
                    "say-ack",
                    &[("id", id.to_string()), ("note", note.clone())],
                );
                self.notes.remove(&id);
            }
            Err(e) => self.say(None, "say-ack-refused", &[("error", e.to_string())]),
        }
    }

    /// Acknowledges several alarms (all unacknowledged ones for `None`) with one note.
    fn acknowledge_all(&mut self, ids: Option<Vec<u64>>, note: String, now: u64) {
        let done = self
            .sim
            .alarms
            .acknowledge_all(Millis(now), ids.as_deref(), &note);
        for id in &done {
            self.notes.remove(id);
        }
        let list: Vec<String> = done.iter().map(|id| format!("#{id}")).collect();
        if !done.is_empty() {
            self.say(
                Some(("ack", now)),
                "say-ack-together",
                &[("list", list.join(", ")), ("note", note.clone())],
            );
        }
        self.say(None, "say-ack-all", &[("n", done.len().to_string())]);
    }

    /// Shelves alarm `id` for `ms` with a reason.
    fn shelve(&mut self, id: u64, ms: u64, reason: &str, now: u64) {
        match self.sim.alarms.shelve(Millis(now), id, Millis(ms), reason) {
            Ok(()) => {
                self.shelve_form = None;
                self.say(
                    Some(("shelve", now)),
                    "say-shelve",
                    &[
                        ("id", id.to_string()),
                        ("minutes", (ms / 60_000).to_string()),
                        ("reason", reason.trim().to_string()),
                    ],
                );
            }
            Err(e) => self.say(
                Some(("shelve_refused", now)),
                "say-shelve-refused",
                &[("error", e.to_string())],
            ),
        }
    }

    /// Exports the filtered alarm history to CSV.
    fn export_alarms(&mut self, path: &Path, now: u64) {
        let path = self.export_path(path);
        let list = self.sim.alarms.history(&self.history_filter);
        let csv = vigie_core::alarms::AlarmList::history_csv(&list);
        let n = list.len();
        let written = journal::write_export(&path, &csv);
        let shown = path.display().to_string();
        match written {
            Ok(()) => self.say(
                Some(("operator", now)),
                "say-alarms-exported",
                &[("n", n.to_string()), ("path", shown)],
            ),
            Err(e) => self.say(
                Some(("operator", now)),
                "say-alarms-export-failed",
                &[("path", shown), ("error", e.to_string())],
            ),
        }
    }

    /// Writes the filtered alarm history as HTML for print and opens it.
    fn print_alarms(&mut self, path: &Path, now: u64) {
        let path = self.export_path(path);
        let list = self.sim.alarms.history(&self.history_filter);
        let html = report::alarms_html(self, &list);
        let n = list.len();
        let shown = path.display().to_string();
        match journal::write_export(&path, &html) {
            Ok(()) => {
                self.say(
                    Some(("operator", now)),
                    "say-alarms-printed",
                    &[("n", n.to_string()), ("path", shown.clone())],
                );
                if self.open_files
                    && let Err(e) = open::that_detached(&path)
                {
                    self.say(
                        None,
                        "say-print-open-failed",
                        &[("path", shown), ("error", e.to_string())],
                    );
                }
            }
            Err(e) => self.say(
                Some(("operator", now)),
                "say-alarms-export-failed",
                &[("path", shown), ("error", e.to_string())],
            ),
        }
    }

    /// Exports the changes of the trends' signals over their range to CSV.
    fn export_trend(&mut self, path: &Path) {
        let path = self.export_path(path);
        let now = self.journal.wall_of(self.now().0);
        let csv = self.journal.store().map_or_else(
            || Err("the console runs without a data folder: no history".to_string()),
            |s| {
                trends::changes_csv(s, &self.trends.signals, now, self.trends.range_ms)
                    .map_err(|e| e.to_string())
            },
        );
        let written = csv.and_then(|(csv, n)| {
            journal::write_export(&path, &csv)
                .map(|()| n)
                .map_err(|e| e.to_string())
        });
        let shown = path.display().to_string();
        let at = self.now().0;
        match written {
            Ok(n) => self.say(
                Some(("operator", at)),
                "say-trend-exported",
                &[("n", n.to_string()), ("path", shown)],
            ),
            Err(e) => self.say(
                Some(("operator", at)),
                "say-trend-export-failed",
                &[("path", shown), ("error", e)],
            ),
        }
    }

    /// Switches the console's language (descriptions and synoptic words too), keeping the status.
    fn set_language(&mut self, lang: Lang, now: u64) {
        self.i18n.set_lang(lang);
        let view = synoptic_view(&self.i18n, &self.sim);
        self.view.descriptions = view.descriptions;
        self.view.words = view.words;
        self.view.elements = view.elements;
        self.view.parts = view.parts;
        self.view.dangers = view.dangers;
        self.view.items = view.items;
        let status = std::mem::take(&mut self.status);
        self.say(
            Some(("operator", now)),
            "say-language",
            &[("lang", lang.code().to_string())],
        );
        self.status = status;
    }

    /// Restarts on the training variant `id` with a new score.
    fn load_variant(&mut self, id: String) {
        self.source = Source::free_run(
            &self.plant_dir,
            ProgramChoice::Error(id.clone()),
            &format!("Training: {id}"),
        );
        self.score = Score::default();
        self.score.variant = Some(id);
        self.draft = None;
        self.compiled_edit = None;
        self.restart(None);
        if self.mode == Mode::Maintenance {
            self.enter_maintenance();
        }
    }

    /// Restarts on the plant-fault exercise `id` with a new score.
    fn load_plant_exercise(&mut self, id: &str) {
        let Some(e) = self.library.exercises.iter().find(|e| e.id == id).cloned() else {
            self.say(None, "say-no-such-exercise", &[("id", id.to_string())]);
            return;
        };
        self.source = Source::plant_exercise(&self.plant_dir, &e);
        self.diagnosis_pick.clear();
        self.score = Score {
            variant: Some(e.id),
            plant: true,
            ..Score::default()
        };
        self.draft = None;
        self.compiled_edit = None;
        self.last_fix = None;
        self.restart(None);
    }

    /// The trainee names `component` as the faulty one: right ends the exercise (the
    /// debrief), wrong counts an attempt.
    fn submit_diagnosis(&mut self, component: &str) {
        let Some(e) = self.plant_exercise().cloned() else {
            self.say(None, "say-no-plant-exercise", &[]);
            return;
        };
        if self.score.revealed {
            return;
        }
        let right = e.is_answer(component);
        self.score.attempts += 1;
        self.score.diagnoses.push((component.to_string(), right));
        let now = self.now().0;
        if right {
            self.score.fixed = true;
            // From the stop; a component named before any stop has no such time.
            self.score.located_after_s = self.score.trip_wall_s.map(|t| self.wall_s - t);
            self.finish_exercise(true);
            self.say(
                Some(("training", now)),
                "say-diagnosis-right",
                &[("component", component.to_string())],
            );
        } else {
            self.say(
                Some(("training", now)),
                "say-diagnosis-wrong",
                &[("component", component.to_string())],
            );
        }
    }

    /// Injects the training fault `i`, its time taken from now.
    fn inject_fault(&mut self, i: usize, now: u64) {
        if let Some((name, spec)) = self.library.faults.get(i).cloned() {
            let mut spec = spec;
            if let vigie_core::emulator::Trigger::At(t) = &mut spec.trigger {
                *t += now;
            }
            let what = words::fault(&self.i18n, &self.view.descriptions, &name, &spec);
            match self.sim.inject(spec) {
                Ok(()) => self.say(None, "say-fault-injected", &[("what", what)]),
                Err(e) => self.say(
                    None,
                    "say-fault-refused",
                    &[("what", what), ("error", e.message)],
                ),
            }
            self.drain_journal();
        }
    }

    fn restart(&mut self, program: Option<CompiledProgram>) {
        match self.source.build() {
            Ok(mut sim) => {
                if let Some(p) = program {
                    sim.replace_program(p);
                }
                self.sim = sim;
                self.journal.restart_run();
                self.level = None;
                self.replay = None;
                self.budget_ms = 0.0;
                self.running = true;
                self.score.trip_wall_s = None;
                let mut fields = self.source.title_fields();
                let title = words::title(&self.i18n, &fields, true);
                let text = self
                    .i18n
                    .ta_en("say-restart", &[("scenario", (&title).into())]);
                fields.insert("scenario".into(), title);
                self.journal
                    .push_coded(0, "operator", &text, "say-restart", fields);
                self.status = self.source.title(&self.i18n);
                self.drain_journal();
                self.say(None, "say-restarted", &[]);
            }
            Err(e) => self.say(None, "say-restart-failed", &[("error", e)]),
        }
    }

    fn start_report(&mut self, dir: PathBuf) {
        let Some(trip) = self.latest_trip() else {
            self.say(None, "say-no-trip", &[]);
            return;
        };
        let meta = self.report_meta();
        match report::write_markdown(&self.sim, &self.i18n, &meta, trip, &dir) {
            Ok(path) => {
                self.say(
                    Some(("report", self.now().0)),
                    "say-report",
                    &[("path", dir.display().to_string())],
                );
                self.say(
                    None,
                    "say-report-written",
                    &[("path", path.display().to_string())],
                );
                self.report_job = Some(ReportJob {
                    dir,
                    level: 0,
                    frames: 0,
                    waiting: false,
                    shot: std::sync::Arc::default(),
                    restore: (self.level, self.running),
                });
                self.running = false;
            }
            Err(e) => self.say(None, "say-report-failed", &[("error", e.to_string())]),
        }
    }

    /// The incident report's header: now, who, the plant, the program and its version.
    fn report_meta(&self) -> report::Meta {
        let program = &self.sim.program.program().program;
        report::Meta {
            wall_ms: crate::historian::wall_ms(),
            user: (self.user.clone(), format!("{:?}", self.role)),
            plant: (
                tidy(&self.plant_dir).display().to_string(),
                self.sim.bundle.plant.name.clone(),
            ),
            program: (
                program.name.clone(),
                program.version(),
                self.exercise_id().map(str::to_string),
            ),
            scenario: self.source.title(&self.i18n),
            filter: format!("{:?}", self.sim.engine.mode()),
        }
    }

    /// The report capture state machine (called from `logic`).
    fn report_step(&mut self, ctx: &egui::Context) {
        let Some(job) = &mut self.report_job else {
            return;
        };
        let shot = job.shot.lock().ok().and_then(|mut s| s.take());
        if let (Some(image), true) = (shot, job.waiting) {
            let ppp = ctx.pixels_per_point();
            let path = job.dir.join(format!("level-{}.png", job.level));
            let mut saved = report::save_png(&image, self.synoptic_rect, ppp, &path);
            if job.level == 0 {
                let chrono = job.dir.join("chronogram.png");
                saved = saved.and(report::save_png(&image, self.chrono_rect, ppp, &chrono));
            }
            if let Err(e) = saved {
                self.status = self
                    .i18n
                    .ta("say-png-failed", &[("error", (&e.to_string()).into())]);
            }
            job.level += 1;
            job.waiting = false;
            job.frames = 0;
        }
        if job.level >= 5 {
            self.status = self.i18n.ta(
                "say-report-complete",
                &[("path", (&job.dir.display().to_string()).into())],
            );
            // The view as it was: the export changes nothing the user sees.
            (self.level, self.running) = job.restore;
            self.report_job = None;
            return;
        }
        self.level = Some(job.level);
        job.frames += 1;
        if !job.waiting && job.frames >= 3 {
            let slot = job.shot.clone();
            let repaint = ctx.clone();
            ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(
                egui::ScreenshotCallback::new(move |image| {
                    if let Ok(mut s) = slot.lock() {
                        *s = Some(image);
                    }
                    repaint.request_repaint();
                }),
            ));
            job.waiting = true;
            job.frames = 0;
        } else if job.waiting && job.frames > 120 {
            self.status = self.i18n.ta(
                "say-report-no-png",
                &[("path", (&job.dir.display().to_string()).into())],
            );
            (self.level, self.running) = job.restore;
            self.report_job = None;
            return;
        }
        ctx.request_repaint();
    }

    /// The work of `App::logic`: advance by real time, run the report capture.
    pub fn logic(&mut self, ctx: &egui::Context) {
        if !self.visuals_set {
            crate::theme::setup_context(ctx, &self.palette);
            self.visuals_set = true;
        }
        for c in std::mem::take(&mut self.pending) {
            self.apply(c);
        }
        let t = ctx.input(|i| i.time);
        let dt = self.last_time.map_or(0.0, |l| (t - l).max(0.0));
        self.last_time = Some(t);
        self.wall_s += dt;
        if self.report_job.is_none() {
            self.advance(dt);
        }
        self.report_step(ctx);
        verification::poll(self, ctx);
        link::close_on_signal(self, ctx);
        match self.save.poll() {
            Some(Ok(cmd)) => self.apply(cmd),
            Some(Err(())) => {
                self.status = self.i18n.t("status-export-cancelled");
            }
            None => {}
        }
        self.journal.sync_alarms(&self.sim.alarms);
        self.journal.commit();
        if self.running {
            ctx.request_repaint();
        }
    }

    /// The work of `App::ui`: renders only; the commands the views emit are queued
    /// and applied at the next `logic`.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let mut commands = Vec::new();
        views::root_ui(self, ui, &mut commands);
        if !commands.is_empty() {
            ui.ctx().request_repaint();
        }
        self.pending.extend(commands);
    }
}

/// The synoptic's tags in the language shown.
/// The synoptic's texts in the language shown: the signals' descriptions, its tags and
/// the plant's element names (the schematic strip's blocks); zoom and pan at rest.
/// The plant folders beside `dir` (its parent's folders that hold a `plant.ron`),
/// `dir` included, sorted, each with its plant's name (the folder's when the plant
/// does not load).
fn sibling_plants(dir: &Path) -> Vec<(PathBuf, String)> {
    let parent = tidy(dir)
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let mut out: Vec<(PathBuf, String)> = std::fs::read_dir(&parent)
        .into_iter()
        .flatten()
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.join("plant.ron").exists())
        .map(|p| {
            let name = vigie_core::plant::Plant::load(&p.join("plant.ron")).map_or_else(
                |_| {
                    p.file_name()
                        .unwrap_or_default()
                        .to_string_lossy()
                        .into_owned()
                },
                |plant| plant.name,
            );
            (p, name)
        })
        .collect();
    out.sort();
    out
}

impl Console {
    /// The plant picker: the console reopened on `dir` with its reference program, in
    /// the language shown; a plant that does not open leaves this one as it is and
    /// says why.
    fn open_plant(&mut self, dir: PathBuf) {
        let mut o = self.opened_with.clone();
        o.plant_dir = dir;
        o.scenario = None;
        o.variant = None;
        o.run_until_ms = None;
        o.start = false;
        o.lang = self.i18n.lang();
        match Console::new(&o) {
            Ok(mut c) => {
                c.visuals_set = self.visuals_set;
                c.opened_with = self.opened_with.clone();
                *self = c;
            }
            Err(e) => self.status = format!("{}: {e}", o.plant_dir.display()),
        }
    }
}

fn synoptic_view(i18n: &I18n, sim: &vigie_core::sim::Simulation) -> synoptic::View {
    let plant = &sim.bundle.plant;
    // A plant of components names its components by id (`part-<id>` in the plant
    // folder's texts, else the name `components.ron` gives).
    let scene = sim.emulator.scene();
    let areas = scene
        .as_ref()
        .and_then(|s| synoptic::scene::shown_areas(s, plant));
    let components = scene.map(|s| s.elements).unwrap_or_default();
    synoptic::View {
        areas,
        descriptions: i18n.signal_descriptions(plant),
        words: synoptic_words(i18n),
        elements: plant
            .inputs
            .iter()
            .chain(&plant.outputs)
            .filter(|s| !s.element.is_empty())
            .map(|s| (s.element.clone(), words::element(i18n, &s.element)))
            .collect(),
        parts: components
            .into_iter()
            .map(|e| {
                let name = i18n.plant(&format!("part-{}", e.id)).unwrap_or(e.name);
                (e.id, name)
            })
            .collect(),
        dangers: sim
            .emulator
            .as_components()
            .map(|c| c.dangers())
            .unwrap_or_default()
            .into_iter()
            .map(|(id, text)| {
                let t = i18n.plant(&format!("danger-{id}")).unwrap_or(text);
                (id, t)
            })
            .collect(),
        items: sim
            .emulator
            .as_components()
            .map(|c| c.item_classes())
            .unwrap_or_default()
            .into_iter()
            .filter_map(|class| {
                let t = i18n.plant(&format!("item-{class}"))?;
                Some((class, t))
            })
            .collect(),
        ..synoptic::View::default()
    }
}

fn synoptic_words(i18n: &I18n) -> BTreeMap<&'static str, String> {
    synoptic::TAGS
        .iter()
        .map(|(k, _)| (*k, i18n.t(&format!("syn-{k}"))))
        .collect()
}

/// The control-error library's exercises (id, description, expected constraint) and
/// their correct fixes.
type Exercises = (
    Vec<(String, String, String)>,
    BTreeMap<String, Vec<FixLine>>,
);

/// `a/b/../c` as `a/c`: a path as a person writes it (lexically, no file system).
fn tidy(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// The chronogram's rows at start: every input and output of the plant, and the
/// observers.
fn plant_signals(sim: &Simulation) -> BTreeSet<String> {
    let plant = &sim.bundle.plant;
    plant
        .inputs
        .iter()
        .chain(plant.outputs.iter())
        .map(|s| s.id.clone())
        .chain(
            sim.engine
                .symbols
                .names(vigie_core::symbols::Space::Observer)
                .iter()
                .cloned(),
        )
        .collect()
}

/// The control-error library's exercises, and the rendered problems of a library that
/// cannot be loaded (shown in the training view, not skipped).
fn sim_variants(plant_dir: &Path, sim: &Simulation) -> (Exercises, Option<String>) {
    let path = plant_dir.join("programs/errors.ron");
    if !path.exists() {
        return ((Vec::new(), BTreeMap::new()), None);
    }
    match ErrorLibrary::load(&path, &sim.bundle.plant) {
        Ok(lib) => (
            (
                lib.variants
                    .iter()
                    .map(|v| {
                        (
                            v.def.id.clone(),
                            v.def.description.clone(),
                            v.def.expected_constraint.clone(),
                        )
                    })
                    .collect(),
                lib.variants
                    .iter()
                    .map(|v| (v.def.id.clone(), correct_fix(&lib.reference, &v.program)))
                    .collect(),
            ),
            None,
        ),
        Err(p) => (
            (Vec::new(), BTreeMap::new()),
            Some(vigie_core::diag::render(&p)),
        ),
    }
}

impl eframe::App for Console {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        Console::logic(self, ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        Console::ui(self, ui);
    }
}
