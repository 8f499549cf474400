//! The console driven as a user would, through accessibility queries (egui_kittest):
//! start the plant, reach the paper's CSs10 trip, open each explanation level, read its
//! items, acknowledge the alarm, reset; plus image snapshots (wgpu, lavapipe on CI).

use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT as _, Queryable as _};
use std::path::PathBuf;
use vigie_app::{Command, Console, ConsoleOptions, Mode};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn options(data_dir: Option<PathBuf>) -> ConsoleOptions {
    let mut o = ConsoleOptions::new(&root().join("layouts/sorting-station"));
    o.scenario = Some(root().join("layouts/sorting-station/scenarios/cs10-paper.ron"));
    o.data_dir = data_dir;
    o
}

/// The console in English whatever the machine's locale (the language switch has its
/// own test).
fn harness(opts: ConsoleOptions) -> Harness<'static, Console> {
    harness_sized(opts, egui::vec2(1600.0, 1000.0))
}

/// [`harness`] in a window of `size`.
fn harness_sized(mut opts: ConsoleOptions, size: egui::Vec2) -> Harness<'static, Console> {
    opts.lang = vigie_app::i18n::Lang::En;
    Harness::builder()
        .with_size(size)
        .with_step_dt(1.0 / 60.0)
        .build_eframe(move |cc| {
            let mut c = Console::new(&opts).expect("console opens");
            c.setup(&cc.egui_ctx);
            c
        })
}

/// Runs frames at 100x until the filter has tripped (at most 600 frames).
fn run_to_trip(h: &mut Harness<'static, Console>) {
    h.state_mut().apply(Command::SetSpeed(100.0));
    for _ in 0..600 {
        h.step();
        if h.state().latest_trip().is_some() {
            break;
        }
    }
    h.state_mut().apply(Command::Pause);
    h.run_steps(2);
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vigie-console-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The journal the console wrote into `data`, checked to hold every one of `needles`.
#[track_caller]
fn journal_with(data: &std::path::Path, needles: &[&str]) -> String {
    let journal = crate::historian_journal(data);
    for needle in needles {
        assert!(
            journal.contains(needle),
            "journal lacks {needle}:\n{journal}"
        );
    }
    journal
}

#[test]
fn cs10_trip_levels_acknowledge_and_reset() {
    let data = temp_dir("cs10");
    let mut h = harness(options(Some(data.clone())));
    h.run_steps(2);
    h.get_by_label("Start").click();
    h.run_steps(2);
    h.get_by_label("No trip: the plant runs within its safety constraints.");
    run_to_trip(&mut h);

    // The trip, its constraint in the paper's notation.
    h.get_by_label("Trip at 11.68 s");
    h.get_by_label("CSs10 = C7 · A\u{305}4\u{305}");
    h.get_by_label("TRIPPED");

    let expected = [
        (
            "0 Current state",
            "A4 is held ON by the filter: CSs10 (C7=1).",
        ),
        ("1 Projection", "would be sheared by the rotating turntable"),
        (
            "2 Before stop",
            "CSs10 = C7 · A\u{305}4\u{305} became true: C7=1, A4=0.",
        ),
        (
            "3 Advanced",
            "C7 changed 0→1 at 11680 ms (in the stopping cycle), element of the constraint.",
        ),
        (
            "4 Hypothesis",
            "Expected from the control: A4 should have been ON.",
        ),
    ];
    for (button, item) in expected {
        h.get_by_label(button).click();
        h.run_steps(2);
        h.get_by_label(&format!("Level {button}"));
        assert!(
            h.query_by_label_contains(item).is_some(),
            "level {button}: no item containing {item:?}"
        );
    }
    assert_eq!(h.state().level, Some(4));

    // The alarm: unacknowledged, first out; acknowledge with a note.
    h.get_by_label("UNACK");
    h.get_by_label("FIRST OUT");
    let id = h.state().sim.alarms.all()[0].id;
    h.get_by_label(&format!("Acknowledge #{id}")).click();
    h.run_steps(2);
    assert!(h.query_by_label(&format!("Acknowledge #{id}")).is_none());
    h.get_by_label("ACK");

    // Reset: refused while CSs10 is still violated (the box is still at C7 and the
    // erroneous program still releases A4), with the reason shown.
    h.get_by_label("Reset").click();
    h.run_steps(2);
    assert!(h.state().sim.engine.is_tripped());
    assert!(
        h.query_by_label_contains("Reset: reset refused: CSs10 still violated")
            .is_some()
    );

    // Everything reached the disk as it happened.
    journal_with(&data, &["\"trip\"", "\"ack\"", "\"reset_refused\""]);
    let _ = std::fs::remove_dir_all(&data);
}

#[test]
fn maintenance_fix_of_e01_passes_verification() {
    let mut h = harness(options(None));
    h.run_steps(2);
    h.get_by_label("Maintenance").click();
    h.run_steps(2);
    assert_eq!(h.state().mode, Mode::Maintenance);
    h.get_by_label("Chart table");
    h.get_by_label("Step X24");
    // A syntax error is reported, not a panic.
    edit_t24(&mut h, "FE(C7");
    h.get_by_label("Recompile").click();
    h.run_steps(2);
    assert!(h.state().status.contains("compilation failed"));
    // The correct receptivity.
    edit_t24(&mut h, "FE(C7)");
    h.get_by_label("Verify fix").click();
    h.run_steps(2);
    assert!(
        h.state().status.starts_with("correct fix"),
        "{}",
        h.state().status
    );
    assert!(h.state().score().fixed);
    assert_eq!(h.state().score().attempts, 1);
    assert!(h.state().score().summary().contains("Fixed"));
}

/// The corrected program goes back to the PLC's tool: the maintenance panel's "Export
/// PLCopen XML…" writes the program on screen (the fix of E01), which reads back with
/// the fixed receptivity; a program on screen that does not compile is not exported.
#[test]
fn maintenance_exports_the_fixed_program_as_plcopen() {
    let mut h = harness(options(None));
    h.run_steps(2);
    h.get_by_label("Maintenance").click();
    h.run_steps(2);
    edit_t24(&mut h, "FE(C7)");
    h.get_by_label("Save PLCopen XML as…");
    // The button writes it under the data folder, named after the program's version.
    h.get_by_label("Export PLCopen XML").click();
    h.run_steps(2);
    let status = h.state().status.clone();
    assert!(status.contains("exported as PLCopen XML to"), "{status}");
    let written = status
        .rsplit(" to ")
        .next()
        .expect("a path")
        .trim()
        .to_string();
    assert!(
        written.ends_with(".xml") && std::path::Path::new(&written).exists(),
        "{written}"
    );
    let _ = std::fs::remove_file(&written);
    let dir = std::env::temp_dir().join(format!("vigie-console-plcopen-{}", std::process::id()));
    let file = dir.join("fixed.xml");
    h.state_mut().apply(Command::ExportProgram(file.clone()));
    h.run_steps(2);
    assert!(
        h.state().status.contains("exported as PLCopen XML"),
        "{}",
        h.state().status
    );
    let xml = std::fs::read_to_string(&file).expect("written");
    let t24 = xml
        .lines()
        .find(|l| l.contains("<transition name=\"t24\">"))
        .expect("t24");
    assert!(t24.contains("(C7_PRE AND NOT C7)"), "{t24}");
    let plant = vigie_core::plant::Plant::load(
        &crate::live::repo().join("layouts/sorting-station/plant.ron"),
    )
    .expect("plant");
    let read = vigie_core::plcopen::import(&xml, &file, &plant).expect("reads back");
    let running = h.state().sim.program.program().program.clone();
    assert_eq!(read.name, running.name);
    // A program on screen that does not compile: nothing written.
    edit_t24(&mut h, "FE(C7");
    let broken = dir.join("broken.xml");
    h.state_mut().apply(Command::ExportProgram(broken.clone()));
    h.run_steps(2);
    assert!(!broken.exists());
    assert!(
        h.state().status.contains("does not compile"),
        "{}",
        h.state().status
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Replaces t24's receptivity as a technician does: click the field, select all, type.
fn edit_t24(h: &mut Harness<'_, Console>, text: &str) {
    reveal(h, "Receptivity t24");
    h.get_by_label("Receptivity t24").click();
    h.run_steps(1);
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.run_steps(1);
    h.get_by_label("Receptivity t24").type_text(text);
    h.run_steps(2);
    assert_eq!(
        h.state().draft().expect("draft").conditions["t24"],
        text,
        "the field edits the draft"
    );
}

/// Issue 20: every fix check runs the text on screen, not the last compiled one. The
/// sequence that certified a wrong edit: a right fix verified, then a wrong edit
/// verified with no Recompile between.
#[test]
fn verify_fix_runs_the_text_on_screen_every_time() {
    let mut h = harness(options(None));
    h.run_steps(2);
    h.get_by_label("Maintenance").click();
    h.run_steps(2);
    let running = h.state().sim.program.program().program.version();
    let verify = |h: &mut Harness<'_, Console>| {
        h.get_by_label("Verify fix").click();
        h.run_steps(2);
        h.state().last_fix.clone().expect("a fix check")
    };
    // Nothing edited: the variant itself re-runs and is not fixed.
    let check = verify(&mut h);
    assert_eq!(check.version, running);
    assert!(check.changes.is_empty(), "{check:?}");
    assert!(!check.outcome.is_fixed(), "{check:?}");
    // The right fix.
    edit_t24(&mut h, "FE(C7)");
    let right = verify(&mut h);
    assert!(right.outcome.is_fixed(), "{right:?}");
    assert_ne!(right.version, running);
    assert_eq!(right.changes, ["transition t24"]);
    // A wrong edit with no Recompile: refused, and the version says it is another text.
    edit_t24(&mut h, "FE(C6)");
    let wrong = verify(&mut h);
    assert!(
        !wrong.outcome.is_fixed(),
        "a wrong edit certified: {wrong:?}"
    );
    assert_ne!(wrong.version, right.version);
    // Back to the right one: accepted again, same version as before.
    edit_t24(&mut h, "FE(C7)");
    let again = verify(&mut h);
    assert!(again.outcome.is_fixed(), "{again:?}");
    assert_eq!(again.version, right.version);
    // The console shows what ran (not only the status line), and the score counts
    // four checks, the last one fixed.
    h.get_by_label("Last fix check");
    assert!(
        h.query_by_label_contains(&format!("version {}", right.version))
            .is_some()
    );
    assert_eq!(h.state().score().attempts, 4);
    assert!(h.state().score().fixed);
    // Restart with edit runs the text on screen too.
    edit_t24(&mut h, "FE(C6)");
    h.get_by_label("Restart with edit").click();
    h.run_steps(2);
    assert_eq!(
        h.state().sim.program.program().program.version(),
        wrong.version
    );
}

/// Training in French: the control-error library and the fault library from the
/// plant's French texts and the faults' kinds, an injected fault journaled in French,
/// and a fix's verdict in French (recorded in English).
#[test]
fn training_in_french() {
    let mut h = harness(options(None));
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    // The answer stays hidden while the exercise runs.
    assert!(h.query_by_label_contains("Rotation relâchée").is_none());
    assert!(h.query_by_label_contains("Rotation released").is_none());
    h.get_by_label("Exercice E01");
    // The operator may not inject a fault: refused in French.
    h.state_mut().apply(Command::InjectFault(0));
    assert!(
        h.state().status.starts_with(
            "Refusé : charger des exercices et injecter des défauts demande le rôle formateur ou administrateur (rôle actuel : opérateur)"
        ),
        "{}",
        h.state().status
    );
    h.state_mut().role = vigie_core::access::Role::Trainer;
    h.get_by_label("Bibliothèque de défauts").click();
    h.run_steps(2);
    h.get_by_label("C7 bloqué à 0 (Caisse à l'entrée du convoyeur de sortie droit)");
    h.get_by_label("A1 bloqué EN MARCHE (contacteur soudé) (Moteur du convoyeur intermédiaire)");
    h.state_mut().apply(Command::InjectFault(0));
    h.state_mut().apply(Command::SetMode(Mode::Production));
    h.run_steps(2);
    assert!(
        h.query_by_label_contains("défaut injecté : C7 bloqué à 0")
            .is_some(),
        "the journal tells the fault in French"
    );
    // The fix of E01 (the scenario's variant), checked: the verdict in French.
    h.state_mut().apply(Command::SetMode(Mode::Maintenance));
    h.state_mut().apply(Command::EditDraft(
        vigie_app::console::DraftEdit::Condition {
            transition: "t24".into(),
            text: "FE(C7)".into(),
        },
    ));
    h.state_mut().apply(Command::VerifyFix);
    h.run_steps(2);
    assert!(
        h.state()
            .status
            .starts_with("correction juste : aucun arrêt"),
        "{}",
        h.state().status
    );
    let e = h
        .state()
        .journal
        .entries()
        .iter()
        .rev()
        .find(|e| e.code == "fix-correct")
        .cloned()
        .expect("entry");
    assert_eq!(e.kind, "training");
    assert!(e.text.starts_with("correct fix: no trip"), "{}", e.text);
    // The fix ends the exercise: the debrief shows the mistake in French.
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    assert!(
        h.query_by_label_contains("Rotation relâchée sur le front montant de C7")
            .is_some(),
        "variant E01 in French, after the fix"
    );
    h.get_by_label("Débriefing : exercice E01");
}

/// Issue 20: from the hypothesis to the program: the link of level 4 opens the
/// maintenance view on the suspect transition, framed in the GRAFCET, the plant still
/// on screen beside it; the ladder view draws the equations as rungs with their state.
#[test]
fn the_hypothesis_link_highlights_the_suspect_in_the_grafcet() {
    let mut h = harness(options(None));
    h.run_steps(2);
    run_to_trip(&mut h);
    h.state_mut().apply(Command::ShowLevel(Some(4)));
    h.run_steps(2);
    // Not yet suspect: no trip explained in the program view before the link.
    press(&mut h, "→ t24 in the program");
    assert_eq!(h.state().mode, Mode::Maintenance, "{}", h.state().status);
    assert_eq!(h.state().program_focus.as_deref(), Some("t24"));
    h.get_by_label("Transition t24, suspect");
    h.get_by_label("Transition t23");
    h.get_by_label("Receptivity t24");
    // Its step and the active ones are drawn as such.
    assert!(h.query_by_label_contains("Step X25, active").is_some());
    // The synoptic stays beside the program.
    h.get_by_label("Synoptic");
    // The ladder view: one rung per equation, its coil state said.
    press(&mut h, "Ladder");
    let rungs = h.query_all_by_label_contains("Rung ").count();
    let equations = h.state().draft().expect("draft").equations.len();
    assert!(
        equations > 0 && rungs == equations,
        "{rungs} rungs, {equations} equations"
    );
    h.get_by_label("Equation A0");
}

/// Clicks a button as a person does: scrolled into view first.
fn press(h: &mut Harness<'static, Console>, label: &str) {
    reveal(h, label);
    h.get_by_label(label).click();
    h.run_steps(2);
}

/// Scrolls a widget into view as a person does, and waits for the scroll to settle.
fn reveal(h: &mut Harness<'_, Console>, label: &str) {
    h.get_by_label(label).scroll_to_me();
    // The scroll is animated: let it settle (a bounded number of frames, until the
    // button stays in place three frames running).
    let mut rect = h.get_by_label(label).rect();
    let mut still = 0;
    for _ in 0..120 {
        h.step();
        let now = h.get_by_label(label).rect();
        still = if now == rect { still + 1 } else { 0 };
        rect = now;
        if still == 3 {
            break;
        }
    }
}

/// Issue 20, training for a trainer: the answer is hidden until the trainee asks for
/// it or fixes the error; the debrief shows the mistake, the correct fix and the levels
/// used; the history keeps every finished exercise in the data folder, across a
/// restart of the console.
#[test]
fn training_hides_the_answer_until_the_debrief_and_keeps_a_history() {
    let data = temp_dir("training-history");
    let mut opts = options(Some(data.clone()));
    opts.scenario = None;
    let mut h = harness(opts.clone());
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    press(&mut h, "Load E05");
    h.get_by_label("Exercise E05");
    assert!(h.query_by_label_contains("/C4 instead of C5").is_none());
    assert!(
        h.query_by_label_contains("Right evacuation started")
            .is_none()
    );
    run_to_trip(&mut h);
    h.state_mut().apply(Command::ShowLevel(Some(4)));
    h.run_steps(2);
    // A wrong fix first: not fixed, the exercise goes on, the answer still hidden.
    h.state_mut().apply(Command::EditDraft(
        vigie_app::console::DraftEdit::Condition {
            transition: "t23".into(),
            text: "/C4 . C6".into(),
        },
    ));
    press(&mut h, "Verify fix");
    assert!(!h.state().score().revealed);
    assert!(
        h.query_by_label_contains("Right evacuation started")
            .is_none()
    );
    press(&mut h, "Show the answer");
    assert!(h.state().score().revealed);
    h.get_by_label("Debrief: exercise E05");
    assert!(
        h.query_all_by_label_contains("Right evacuation started as soon as the table leaves")
            .count()
            >= 1
    );
    h.get_by_label("t23: /C4  →  C5");
    h.get_by_label("Levels consulted: 4");
    h.get_by_label("Answer shown after 1 fix checks, without a correct fix.");
    // Shown once: a second request changes nothing.
    h.state_mut().apply(Command::ShowAnswer);
    assert_eq!(h.state().history.records.len(), 1);
    // A second exercise, fixed.
    press(&mut h, "Load E01");
    assert!(!h.state().score().revealed);
    h.state_mut().apply(Command::EditDraft(
        vigie_app::console::DraftEdit::Condition {
            transition: "t24".into(),
            text: "FE(C7)".into(),
        },
    ));
    h.state_mut().apply(Command::VerifyFix);
    h.run_steps(2);
    assert!(h.state().score().revealed);
    h.get_by_label_contains("Fixed after 1 fix checks");
    drop(h);
    // The history is on disk and read back by a new console.
    let csv = std::fs::read_to_string(data.join("training.csv")).expect("history file");
    assert!(csv.starts_with("wall_ms,user,exercise,fixed,attempts,levels,seconds\n"));
    let mut h = harness(opts);
    let records: Vec<(String, bool)> = h
        .state()
        .history
        .records
        .iter()
        .map(|r| (r.exercise.clone(), r.fixed))
        .collect();
    assert_eq!(records, [("E05".into(), false), ("E01".into(), true)]);
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    h.get_by_label("Training history (not logged in)").click();
    h.run_steps(2);
    h.get_by_label("given up");
    h.get_by_label("solved");
    let _ = std::fs::remove_dir_all(&data);
}

/// Issue 20: every plant-fault exercise of the station stops the plant (the trainee
/// meets a stopped plant, as the paper's protocol wants), with its fault in force and
/// the run titled by the exercise only.
#[test]
fn every_plant_fault_exercise_stops_the_plant() {
    let mut opts = options(None);
    opts.scenario = None;
    let mut h = harness(opts);
    h.state_mut().apply(Command::SetMode(Mode::Training));
    let ids: Vec<String> = h
        .state()
        .library
        .exercises
        .iter()
        .map(|e| e.id.clone())
        .collect();
    assert!(ids.len() >= 4, "{ids:?}");
    for id in ids {
        h.state_mut().apply(Command::LoadPlantExercise(id.clone()));
        assert_eq!(h.state().exercise_id(), Some(id.as_str()));
        assert_eq!(h.state().source_title(), format!("Training: {id}"));
        run_to_trip(&mut h);
        let c = h.state();
        assert!(
            c.latest_trip().is_some(),
            "{id}: the plant did not stop by {} ms",
            c.sim.now().0
        );
        assert_eq!(c.sim.emulator.faults_in_force(), 1, "{id}");
        assert!(
            c.sim.emulator.hazards().is_empty(),
            "{id}: {:?}",
            c.sim.emulator.hazards()
        );
    }
}

/// Picks `component` in the plant-fault exercise's form and submits it, as a trainee
/// does: open the list, click the component, press Submit diagnosis.
fn name_component(h: &mut Harness<'static, Console>, component: &str) {
    press(h, "Faulty component:");
    let option = format!("{component} — ");
    h.get_by_label_contains(&option).click();
    h.run_steps(2);
    press(h, "Submit diagnosis");
}

/// Issue 20: a plant-fault exercise, as a trainee meets it: the fault hidden, the plant
/// stopped, a wrong component refused, the right one found, the debrief, the repair,
/// and the history; the same exercise opened from the command line.
#[test]
fn a_plant_fault_exercise_hides_the_fault_until_the_trainee_names_it() {
    let data = temp_dir("plant-exercise");
    let mut opts = options(Some(data.clone()));
    opts.scenario = None;
    let mut h = harness(opts.clone());
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    press(&mut h, "Load P03");
    h.get_by_label("Exercise P03");
    h.get_by_label_contains("A component of the plant failed");
    for secret in ["believes it holds", "C6 stuck", "stuck at 1"] {
        assert!(h.query_by_label_contains(secret).is_none(), "{secret}");
    }
    assert!(h.query_by_label("Verify fix").is_none());
    run_to_trip(&mut h);
    assert!(h.state().latest_trip().is_some());
    h.state_mut().apply(Command::ShowLevel(Some(0)));
    h.state_mut().apply(Command::ShowLevel(Some(4)));
    h.run_steps(2);
    // A wrong component: counted, said, the exercise goes on.
    name_component(&mut h, "C3");
    assert!(!h.state().score().revealed);
    h.get_by_label("C3 is not the faulty component.");
    assert!(h.query_by_label_contains("believes it holds").is_none());
    // The right one: the debrief.
    name_component(&mut h, "C6");
    assert!(h.state().score().revealed, "{}", h.state().status);
    h.get_by_label("Debrief: exercise P03");
    h.get_by_label_contains("believes it holds a box");
    h.get_by_label_contains("C6 stuck at 1");
    h.get_by_label("The faulty component: C6");
    h.get_by_label("Your diagnoses: C3 ✘, C6 ✔");
    h.get_by_label("Levels consulted: 0, 4");
    h.get_by_label_contains("Found after 2 attempts");
    h.get_by_label_contains("The fault is still in force: Repair the plant");
    // Repaired, reset, started: the plant runs again.
    press(&mut h, "Repair the plant");
    assert_eq!(h.state().sim.emulator.faults_in_force(), 0);
    assert!(h.query_by_label_contains("still in force").is_none());
    // The stuck beam made the program believe in a box: the reset is refused, the
    // re-initialisation (plant emptied) ends the stop.
    press(&mut h, "Reset");
    assert!(h.state().sim.engine.is_tripped());
    press(&mut h, "Re-initialise…");
    press(&mut h, "Plant emptied: re-initialise");
    assert!(!h.state().sim.engine.is_tripped(), "{}", h.state().status);
    let r = h.state().history.records.last().expect("a record").clone();
    assert_eq!((r.exercise.as_str(), r.fixed, r.attempts), ("P03", true, 2));
    assert_eq!(r.levels, "0 4");
    // A guess before any stop (the fault not even started): found, with no time from a
    // stop that has not happened.
    press(&mut h, "Load P01");
    h.state_mut().apply(Command::SubmitDiagnosis("C3".into()));
    h.run_steps(2);
    assert!(h.state().latest_trip().is_none());
    h.get_by_label("Found after 1 attempts, before the plant stopped.");
    assert_eq!(h.state().history.records.last().unwrap().seconds, None);
    // Given up: the answer shown, recorded as not found.
    press(&mut h, "Load P05");
    assert!(!h.state().score().revealed);
    press(&mut h, "Show the answer");
    h.get_by_label("The faulty component: A2");
    h.get_by_label("Your diagnoses: none");
    h.get_by_label_contains("Answer shown after 0 attempts");
    assert!(!h.state().history.records.last().unwrap().fixed);
    drop(h);
    // From the command line (`--variant P02`): the same exercise, fault in force.
    opts.variant = Some("P02".into());
    let h = harness(opts);
    assert_eq!(h.state().exercise_id(), Some("P02"));
    assert!(h.state().plant_exercise().is_some());
    assert!(h.state().score().plant, "scored as a plant-fault exercise");
    let _ = std::fs::remove_dir_all(&data);
}

/// A plant-fault exercise in French, as a French trainee reads it: the device
/// monitoring's stop and the task alarm in French (they were the core's English text), the form and the
/// debrief in French.
#[test]
fn a_plant_fault_exercise_in_french() {
    // The exercise in French, run to its stop and 10 s beyond (a task alarm comes 7 s
    // after the stop); its stop's text in French, never the core's English.
    let french_exercise = |exercise: &str, french: &str| {
        let mut opts = options(None);
        opts.scenario = None;
        let mut x = harness(opts);
        x.state_mut()
            .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
        x.state_mut().apply(Command::SetMode(Mode::Training));
        x.state_mut()
            .apply(Command::LoadPlantExercise(exercise.into()));
        run_to_trip(&mut x);
        x.state_mut().cycles(1_000);
        x.run_steps(2);
        let n = x.query_all_by_label_contains(french).count();
        assert!(n >= 1, "{exercise}: {french}");
        for english in ["the diagnosers stop", "Box carried by", "Safety stop"] {
            assert!(
                x.query_by_label_contains(english).is_none(),
                "{exercise}: {english}"
            );
        }
        x
    };
    // The valve's spool monitoring contact reads it open after its order: the safety
    // valve YV0 cuts the table's air.
    let mut h = french_exercise(
        "P02",
        "Arrêt sécurité : A4 ne commute pas : couper YV0 (CSk10)",
    );
    // The table blocked at C5 (mechanical: no mirror contact shows it): the diagnosers'
    // stop; the rollers' contactor dead (P05): KM0 stops the intermediate belt under its
    // box, whose task alarm comes 7 s later.
    french_exercise(
        "P04",
        "les diagnostiqueurs arrêtent la machine : P en défaut (DSTOP_P)",
    );
    french_exercise(
        "P05",
        "Caisse portée par le convoyeur intermédiaire de C1 à son bout C3",
    );
    h.get_by_label_contains("Un composant de la machine est en défaut");
    h.state_mut().apply(Command::SubmitDiagnosis("A4".into()));
    h.run_steps(2);
    h.get_by_label("Débriefing : exercice P02");
    h.get_by_label_contains("Le distributeur de rotation A4 est bloqué fermé");
    h.get_by_label_contains("A4 bloqué À L'ARRÊT");
    h.get_by_label("Vos diagnostics : A4 ✔");
}

/// A trainer's broken library is shown in the training view with its file, line and
/// column, never skipped: an exercise whose fault the emulator refuses, one that takes a
/// control-error variant's id, and an `errors.ron` that does not parse. What loads
/// still works.
#[test]
fn a_broken_training_library_is_shown_not_skipped() {
    let dir = crate::bad_input::station_copy("training-library");
    std::fs::write(
        dir.join("exercises.ron"),
        r#"(exercises: [
    (id: "P01", description: "ok", answer: ["C3"], fault: (trigger: At(20000), fault: SensorStuckAt1("C3"))),
    (id: "P02", description: "an actuator as a sensor", answer: ["A1"], fault: (trigger: At(0), fault: SensorStuckAt0("A1"))),
])"#,
    )
    .unwrap();
    let mut opts = ConsoleOptions::new(&dir);
    opts.data_dir = None;
    let mut h = harness(opts.clone());
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    h.get_by_label_contains("exercises.ron:3:10: error[V0703]: exercise `P02`");
    assert!(h.state().library.exercises.is_empty());
    // A clash with a variant's id, and errors.ron broken.
    std::fs::write(
        dir.join("exercises.ron"),
        r#"(exercises: [(id: "E01", description: "", answer: ["C3"], fault: (trigger: At(20000), fault: SensorStuckAt1("C3")))])"#,
    )
    .unwrap();
    let mut h = harness(opts.clone());
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    h.get_by_label_contains("exercise `E01` has the id of a control-error variant");
    std::fs::write(dir.join("programs/errors.ron"), "ErrorsFile(reference: ").unwrap();
    let mut h = harness(opts);
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    h.get_by_label_contains("errors.ron:1:");
    assert_eq!(
        h.state().library.exercises.len(),
        1,
        "the exercises still load"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 20: an injected fault is removed by the repair action; the filter's Reset is
/// taken after it.
#[test]
fn a_repair_removes_an_injected_fault_and_the_reset_is_taken() {
    let mut opts = options(None);
    opts.scenario = None;
    let mut h = harness(opts);
    h.state_mut().role = vigie_core::access::Role::Trainer;
    h.state_mut().apply(Command::SetMode(Mode::Training));
    h.run_steps(2);
    assert_eq!(h.state().sim.emulator.faults_in_force(), 0);
    h.state_mut()
        .apply(Command::Plant(vigie_core::sim::OperatorAction::Start));
    let table = h
        .state()
        .library
        .faults
        .iter()
        .position(|(n, _)| n.starts_with("Table blocked"))
        .expect("the table fault in faults.ron");
    h.state_mut().apply(Command::InjectFault(table));
    assert_eq!(h.state().sim.emulator.faults_in_force(), 1);
    run_to_trip(&mut h);
    assert!(
        h.state().sim.engine.is_tripped(),
        "the blocked table stops the plant"
    );
    h.state_mut()
        .apply(Command::Plant(vigie_core::sim::OperatorAction::Reset));
    assert!(
        h.state().sim.engine.is_tripped(),
        "Reset refused while the table is blocked"
    );
    press(&mut h, "Repair the plant");
    assert_eq!(
        h.state().sim.emulator.faults_in_force(),
        0,
        "{}",
        h.state().status
    );
    assert!(
        h.state()
            .journal
            .entries()
            .iter()
            .any(|e| e.text == "repair on the simulator: 1 faults removed")
    );
    h.state_mut()
        .apply(Command::Plant(vigie_core::sim::OperatorAction::Reset));
    assert!(
        !h.state().sim.engine.is_tripped(),
        "Reset taken after the repair: {}",
        h.state().status
    );
}

#[test]
fn journal_exports_to_csv_and_report_to_markdown() {
    let out = temp_dir("export");
    let mut h = harness(options(None));
    h.run_steps(1);
    run_to_trip(&mut h);
    h.state_mut()
        .apply(Command::ExportCsv(out.join("journal.csv")));
    h.state_mut()
        .apply(Command::ExportReport(out.join("report")));
    let csv = std::fs::read_to_string(out.join("journal.csv")).expect("csv");
    assert!(csv.starts_with("wall_ms,sim_ms,kind,text\n") && csv.contains(",trip,"));
    let md = std::fs::read_to_string(out.join("report/report.md")).expect("report");
    assert!(
        md.contains("CSs10")
            && md.contains("## Level 4 Hypothesis")
            && md.contains("A4 should have been ON")
    );
    // Issue 20: who, when, what ran.
    let version = h.state().sim.program.program().program.version();
    assert!(!md.contains("/.."), "the plant folder tidied:\n{md}");
    for needle in [
        "- Exported: ",
        " UTC\n",
        "- User: nobody logged in (role Operator)",
        "- Plant: ",
        &format!("exercise E01 (a variant of « Sorting station: reference »), version `{version}`"),
        "(folder `",
        "- Filter mode: Enforce",
        "## Chronogram of the trip window",
    ] {
        assert!(md.contains(needle), "{needle:?} not in\n{md}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn snapshots_of_levels_and_modes() {
    let mut opts = options(None);
    opts.run_until_ms = Some(12_000);
    opts.paused = true;
    let mut h = harness(opts);
    h.run_steps(3);
    h.snapshot("console_trip");
    for (i, name) in [
        "0 Current state",
        "1 Projection",
        "2 Before stop",
        "3 Advanced",
        "4 Hypothesis",
    ]
    .iter()
    .enumerate()
    {
        h.get_by_label(name).click();
        h.run_steps(2);
        h.snapshot(format!("console_level_{i}"));
    }
    h.get_by_label("Maintenance").click();
    h.run_steps(2);
    h.snapshot("console_maintenance");
    h.get_by_label("Training").click();
    h.run_steps(2);
    h.snapshot("console_training");
}

/// Maintenance: verify the loaded constraint set from the console and read the verdicts.
#[test]
fn maintenance_verifies_the_constraint_set() {
    let mut h = harness(options(None));
    h.run_steps(2);
    h.state_mut().apply(Command::SetMode(Mode::Maintenance));
    h.run_steps(2);
    h.get_by_label("Not verified yet.");
    h.get_by_label("Verify constraints");
    h.state_mut().apply(Command::VerifyConstraints);
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(900);
    while h.query_by_label_contains("Safety:").is_none() {
        assert!(
            std::time::Instant::now() < deadline,
            "the verification did not finish in 15 minutes"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.step();
    }
    h.get_by_label("Safety: proved, no hazard reachable");
    h.get_by_label_contains("Permissiveness left: delivery in");
    h.get_by_label_contains("Permissiveness right: delivery in");
    assert!(h.query_by_label("Replay counterexample").is_none());
    assert!(
        h.state().status.starts_with("verification: SAFE"),
        "{}",
        h.state().status
    );
    // Nothing to replay on a safe set: the command says so and changes nothing.
    h.state_mut().apply(Command::ReplayCounterexample);
    assert_eq!(h.state().mode, Mode::Maintenance);
    assert!(
        h.state().status.starts_with("no counterexample"),
        "{}",
        h.state().status
    );
}

/// Runs frames until the verification's verdict is on screen (at most 15 minutes).
fn wait_for_verdict(h: &mut Harness<'static, Console>) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(900);
    while h.query_by_label_contains("Safety:").is_none() {
        assert!(
            std::time::Instant::now() < deadline,
            "the verification did not finish in 15 minutes: {}",
            h.state().status
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.step();
    }
    h.run_steps(2);
}

/// Logs in the maintenance account of [`data_with_accounts`].
fn log_in_as_maintenance(h: &mut Harness<'static, Console>) {
    h.state_mut().apply(Command::Login {
        name: "marie".into(),
        password: "correct horse".into(),
    });
    h.run_steps(2);
    assert!(!h.get_by_label("Maintenance").accesskit_node().is_disabled());
}

/// The console on the plant `dir`, a maintenance technician logged in (accounts in the
/// data folder `data`), who opens Maintenance, clicks "Verify constraints" and waits
/// for the verdict.
fn verified_in_maintenance(dir: &std::path::Path, data: &str) -> Harness<'static, Console> {
    let mut o = ConsoleOptions::new(dir);
    o.data_dir = Some(data_with_accounts(data));
    let mut h = harness(o);
    h.run_steps(2);
    log_in_as_maintenance(&mut h);
    h.state_mut().apply(Command::SetMode(Mode::Maintenance));
    h.run_steps(2);
    h.get_by_label("Not verified yet.");
    h.get_by_label("Verify constraints").click();
    wait_for_verdict(&mut h);
    h
}

/// Issue 16: Maintenance's "Verify constraints" on a plant of components that is not a
/// turntable cell (seed 000's workshop) searches it per component, as `vigie verify`
/// does, instead of refusing it; with a constraint taken out of a copy, the part it
/// guarded is shown violated, and there is no trace to replay on the synoptic.
#[test]
fn maintenance_verifies_a_plant_of_components_per_component() {
    let dir = root().join("layouts/workshop");
    let h = verified_in_maintenance(&dir, "verify-parts");
    h.get_by_label("Safety: proved for every modelled component");
    h.get_by_label_contains("2 components verified one at a time");
    assert_eq!(
        h.query_all_by_label("safe with the filter").count(),
        2,
        "the conveyor and the robot"
    );
    h.get_by_label("conveyor");
    h.get_by_label("robot");
    assert!(
        h.state()
            .status
            .starts_with("verification of 2 components: SAFE"),
        "{}",
        h.state().status
    );

    // The same plant without CSw2 (the robot driven both ways at once).
    let copy = temp_dir("verify-parts-weak").join("workshop");
    crate::paper::copy_dir(&dir, &copy);
    let constraints = std::fs::read_to_string(copy.join("constraints.txt")).unwrap();
    let weakened: String = constraints
        .lines()
        .filter(|l| !l.starts_with("CSw2 "))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(weakened.lines().count(), constraints.lines().count());
    std::fs::write(copy.join("constraints.txt"), weakened).unwrap();
    let mut h = verified_in_maintenance(&copy, "verify-parts-weak-data");
    h.get_by_label("Safety: VIOLATED on some component");
    h.get_by_label("VIOLATED with the filter: driven both ways at once");
    assert!(
        h.state()
            .status
            .starts_with("verification of 2 components: NOT SAFE"),
        "{}",
        h.state().status
    );
    h.state_mut().apply(Command::ReplayCounterexample);
    h.run_steps(2);
    assert_eq!(h.state().mode, Mode::Maintenance, "nothing replayed");
    assert!(
        h.state()
            .status
            .starts_with("this plant is verified per component"),
        "{}",
        h.state().status
    );
}

/// Issue 17: a dead intermediate belt under a pushed box (`scenarios/a1-dead-belt.ron`,
/// on the paper's station) leaves the feed in doubt between the dead belt and a dead beam; after 4 s it stops
/// the plant on the safe side. The operator reads that no fault is certain, the
/// candidates, and what to do; the diagnosers' header counts the stop apart from the
/// certain diagnoses.
#[test]
fn a_stop_on_the_safe_side_says_it_is_in_doubt_and_what_to_do() {
    // The paper's station: the shipped one's mirror contact shows the dead belt's
    // contactor open at the next cycle (CSk4), before any doubt.
    let tmp = crate::live::TempDir::new("doubt");
    let paper = crate::paper_station_in(&tmp.0);
    let mut o = ConsoleOptions::new(&paper);
    o.scenario = Some(paper.join("scenarios/a1-dead-belt.ron"));
    o.run_until_ms = Some(36_000);
    o.paused = true;
    let mut h = harness(o);
    h.run_steps(3);
    let banner = h.get_by_label_contains("Stopped on the safe side");
    let text = format!("{banner:?}");
    for part in [
        "feed in doubt between",
        "M1_blocked",
        "reset the diagnosers",
    ] {
        assert!(text.contains(part), "{part}: {text}");
    }
    assert!(
        h.query_by_label_contains("at fault: the whole system is stopped")
            .is_none()
    );
    h.get_by_label_contains("0 certain diagnoses, 1 stops on the safe side");
    // The question that lifts the doubt (issue 19, seed 004 section 7), answered as the
    // operator sees the machine: the box is held at C0 against the dead belt.
    h.get_by_label(
        "Question: Look at the Entry conveyor: is there an item at C0 (Box at the end of \
         the entry conveyor)? C0 reads 1.",
    );
    h.get_by_label("Yes, an item is there (C0)").click();
    h.run_steps(2);
    h.get_by_label(
        "Operator's answer: feed: the operator sees an item at C0, as C0 reads: C0 is \
         right, the cause is M1_blocked (check that drive), then reset the diagnosers",
    );
    assert!(h.query_by_label_contains("Question:").is_none());
    assert!(
        h.state()
            .sim
            .journal()
            .iter()
            .any(|j| j.kind == "operator_answer")
    );
}

/// Issue 17 (recovery) as an operator meets it: a C6 pulse while the table pulls a box
/// off C3 is taken for the box, the filter trips, and C6 stays held at 1 (a box leaves
/// the table only at C5), so the reset is refused and the status says what to do next.
/// "Re-initialise…" asks for a check of the plant first (emptied, or every item where a
/// sensor shows it); confirmed with the plant emptied, it ends the trip and production
/// comes back.
#[test]
fn a_refused_reset_after_a_phantom_box_is_cleared_by_the_reinitialisation() {
    let mut o = ConsoleOptions::new(&root().join("layouts/sorting-station"));
    o.scenario = Some(root().join("layouts/sorting-station/scenarios/c6-phantom.ron"));
    o.run_until_ms = Some(28_000);
    o.paused = true;
    let mut h = harness(o);
    h.run_steps(3);
    assert!(h.state().sim.engine.is_tripped());
    h.get_by_label("Reset").click();
    h.run_steps(2);
    assert!(h.state().sim.engine.is_tripped());
    h.get_by_label_contains("Check the plant, then Re-initialise");
    h.get_by_label("Re-initialise…").click();
    h.run_steps(2);
    h.get_by_label_contains("Empty the plant first");
    // Cancel first: nothing happens.
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert!(h.state().sim.engine.is_tripped());
    assert!(h.query_by_label("Plant emptied: re-initialise").is_none());
    h.get_by_label("Re-initialise…").click();
    h.run_steps(2);
    let boxes = h.state().sim.emulator.boxes().len();
    assert!(boxes > 0, "boxes on the plant before it is emptied");
    let before = h.state().sim.emulator.stats();
    h.get_by_label("Plant emptied: re-initialise").click();
    h.run_steps(2);
    assert!(!h.state().sim.engine.is_tripped());
    assert!(h.state().sim.emulator.stats().removed > 0);
    h.get_by_label_contains("Re-initialised: the plant emptied");
    h.get_by_label_contains("taken off");
    assert!(h.query_by_label("TRIPPED").is_none());
    let journal: Vec<_> = h
        .state()
        .journal
        .entries()
        .iter()
        .map(|e| e.kind.clone())
        .collect();
    assert!(journal.iter().any(|k| k == "reinitialise"), "{journal:?}");
    assert!(journal.iter().any(|k| k == "plant_emptied"), "{journal:?}");
    // Production comes back: the program runs the next boxes (every 8 s or so).
    let t = h.state().sim.now().0;
    h.state_mut()
        .sim
        .run_until(vigie_core::time::Millis(t + 60_000));
    let s = h.state().sim.emulator.stats();
    let delivered = |s: &vigie_core::emulator::BoxStats| s.delivered_total();
    assert!(
        delivered(&s) >= delivered(&before) + 5,
        "{before:?} then {s:?}"
    );
    assert!(h.state().sim.emulator.hazards().is_empty());
}

/// Focuses the field of `role` labelled `label` and types `text` into it, as a person
/// would (one frame between).
fn type_into(
    h: &mut Harness<'static, Console>,
    role: egui::accesskit::Role,
    label: &str,
    text: &str,
) {
    h.get_by_role_and_label(role, label).focus();
    h.run_steps(1);
    h.get_by_role_and_label(role, label).type_text(text);
}

/// The y of the first label `text` on screen.
fn label_y(h: &Harness<'static, Console>, text: &str) -> f32 {
    h.get_by_label(text).rect().min.y
}

/// Issue 19, ISA-18.2: the trip is the most urgent alarm, listed first, in the
/// operator's words (the formula one click away), first-out rather than the task alarm
/// raised before it; it cannot be shelved; a task alarm can, only with a reason, and
/// the shelving is journaled with it.
#[test]
// One operator's session, step by step: split, the steps would lose their order.
#[allow(clippy::too_many_lines)]
fn alarms_by_priority_a_trip_never_shelved_and_shelving_needs_a_reason() {
    let data = temp_dir("priorities");
    let mut h = harness(options(Some(data.clone())));
    h.run_steps(2);
    // A task alarm before the trip (a prediction: it stops nothing).
    let task = h.state_mut().sim.alarms.raise(
        vigie_core::time::Millis(100),
        "task:test",
        vigie_core::alarms::AlarmKind::Task,
        "Box carried by the intermediate conveyor: slower than normal",
    );
    h.get_by_label("Start").click();
    h.run_steps(2);
    run_to_trip(&mut h);
    let trip = h
        .state()
        .sim
        .alarms
        .all()
        .iter()
        .find(|a| a.kind == vigie_core::alarms::AlarmKind::FilterTrip)
        .map(|a| a.id)
        .expect("trip alarm");
    // Priority badges, the trip first although raised last.
    assert!(label_y(&h, "P1 URGENT") < label_y(&h, "P3 MEDIUM"));
    h.get_by_label(
        "Safety stop: box leaving to the right: hold the rotation (CSs10). Held ON: A4 \
         (Turntable). Stopped: A0 (Entry conveyor), A5 (Left exit conveyor), A6 (Right exit \
         conveyor)",
    );
    assert!(h.query_by_label_contains("Safety filter: CSs10").is_none());
    // First-out is the trip, not the earlier task alarm.
    let first: Vec<u64> = h
        .state()
        .sim
        .alarms
        .all()
        .iter()
        .filter(|a| a.first_out)
        .map(|a| a.id)
        .collect();
    assert_eq!(first, vec![trip]);
    assert_eq!(h.get_all_by_label("FIRST OUT").count(), 1);
    // The formula, one click away.
    assert!(
        h.query_by_label("CSs10 = C7 . /A4 (true at 11680 ms)")
            .is_none()
    );
    h.get_all_by_label("Detail").next().expect("detail").click();
    h.run_steps(2);
    h.get_by_label("CSs10 = C7 . /A4 (true at 11680 ms)");

    // The trip's Shelve button is disabled; even a command is refused by the core.
    let label = format!("Shelve #{trip}…");
    assert!(h.get_by_label(&label).accesskit_node().is_disabled());
    h.state_mut().apply(Command::Shelve {
        id: trip,
        ms: 60_000,
        reason: "nuisance".into(),
    });
    h.run_steps(2);
    assert!(
        h.state()
            .status
            .contains("is a safety alarm (safety filter trip): it cannot be shelved"),
        "{}",
        h.state().status
    );
    assert!(
        h.state()
            .sim
            .alarms
            .get(trip)
            .is_some_and(|a| a.shelving.is_none())
    );

    // The task alarm: no reason, refused; with one, shelved and journaled.
    h.get_by_label(&format!("Shelve #{task}…")).click();
    h.run_steps(2);
    h.get_by_label(&format!("Shelve #{task} now")).click();
    h.run_steps(2);
    assert_eq!(h.state().status, "Shelving needs a reason");
    assert!(
        h.state()
            .sim
            .alarms
            .get(task)
            .is_some_and(|a| a.shelving.is_none())
    );
    type_into(
        &mut h,
        egui::accesskit::Role::TextInput,
        "Reason",
        "sensor being cleaned",
    );
    h.run_steps(2);
    h.get_by_label(&format!("Shelve #{task} now")).click();
    h.run_steps(2);
    assert!(h.query_by_label("P3 MEDIUM").is_none(), "shelved: hidden");
    let shelving = h
        .state()
        .sim
        .alarms
        .get(task)
        .and_then(|a| a.shelving.clone())
        .expect("shelved");
    assert_eq!(shelving.reason, "sensor being cleaned");
    assert_eq!(shelving.until.0 - shelving.at.0, 15 * 60_000);
    let journal = crate::historian_journal(&data);
    assert!(
        journal.contains(&format!(
            "alarm {task} shelved for 15 min: sensor being cleaned"
        )),
        "{journal}"
    );
    assert!(journal.contains("shelve_refused"), "{journal}");
    let _ = std::fs::remove_dir_all(&data);
}

/// Raises `n` task alarms `task alarm 0`.. at `from_ms`, `from_ms + 1`…, as the task
/// monitors would (key `task:<k>`).
fn raise_task_alarms(h: &mut Harness<'static, Console>, n: u64, from_ms: u64) {
    for k in 0..n {
        h.state_mut().sim.alarms.raise(
            vigie_core::time::Millis(from_ms + k),
            &format!("task:{k}"),
            vigie_core::alarms::AlarmKind::Task,
            format!("task alarm {k}"),
        );
    }
}

/// Acknowledge all: every unacknowledged alarm at once, one journal line naming them.
#[test]
fn acknowledge_all_acknowledges_every_alarm_and_journals_them() {
    let data = temp_dir("ackall");
    let mut h = harness(options(Some(data.clone())));
    h.run_steps(2);
    raise_task_alarms(&mut h, 3, 0);
    h.run_steps(2);
    h.get_by_label("3 unacknowledged");
    h.get_by_label("Acknowledge all (3)").click();
    h.run_steps(2);
    assert_eq!(h.state().sim.alarms.unacknowledged(), 0);
    assert!(h.query_by_label_contains("unacknowledged").is_none());
    assert!(
        h.get_by_label("Acknowledge all (0)")
            .accesskit_node()
            .is_disabled()
    );
    let journal = crate::historian_journal(&data);
    assert!(
        journal.contains("alarms #1, #2, #3 acknowledged together"),
        "{journal}"
    );
    let _ = std::fs::remove_dir_all(&data);
}

/// More alarms than a page: the list pages, and "Acknowledge page" acknowledges only
/// the alarms shown.
#[test]
fn the_alarm_list_pages_and_acknowledges_a_page() {
    let mut h = harness(options(None));
    h.run_steps(2);
    raise_task_alarms(&mut h, 11, 0);
    h.run_steps(2);
    h.get_by_label("Page 1 of 2");
    // Newest first: 10 down to 3 on the first page.
    h.get_by_label("task alarm 10");
    assert!(h.query_by_label("task alarm 2").is_none());
    h.get_by_label("Acknowledge page").click();
    h.run_steps(2);
    assert_eq!(h.state().sim.alarms.unacknowledged(), 3);
    // The three left unacknowledged come first now; the acknowledged ones follow.
    h.get_by_label("task alarm 2");
    h.get_by_label("task alarm 0");
    h.get_by_label("Next ▶").click();
    h.run_steps(2);
    h.get_by_label("Page 2 of 2");
    h.get_by_label("task alarm 3");
    assert!(h.query_by_label("task alarm 0").is_none());
}

/// State at a glance and the next step after a trip: IDLE before Start, RUNNING after;
/// TRIPPED with a panel that says why, what to check and whether Reset is possible;
/// Start refused while tripped with the reason, and the plant stays held.
#[test]
fn the_state_and_the_next_step_after_a_trip_and_start_refused_while_tripped() {
    // The reference program with the layout's arrivals, not started.
    let mut h = harness(ConsoleOptions::new(&root().join("layouts/sorting-station")));
    h.run_steps(2);
    h.get_by_label("IDLE");
    h.get_by_label("Start").click();
    h.state_mut().apply(Command::Run);
    h.run_steps(5);
    h.get_by_label("RUNNING");
    // The paper's CSs10 case (started by its scenario).
    let mut h = harness(options(None));
    h.run_steps(2);
    run_to_trip(&mut h);
    h.get_by_label("TRIPPED");
    h.get_by_label("What to do now (stopped at 11.68 s)");
    h.get_by_label_contains("1. Why: Safety stop: box leaving to the right");
    h.get_by_label("2. Check on the machine: Right exit conveyor (C7); Turntable (A4).");
    h.get_by_label_contains("3. Reset is refused now (reset refused: CSs10 still violated");
    h.get_by_label("Start").click();
    h.run_steps(2);
    assert_eq!(
        h.state().status,
        "Start: refused: the safety filter has stopped the plant (CSs10); Reset first, \
         then Start"
    );
    assert!(h.state().sim.engine.is_tripped());
    h.get_by_label("TRIPPED");
}

/// Degraded mode is unmistakable: the state reads DEGRADED (not RUNNING) while C4 is
/// read from its estimate, and the synoptic marks C4 itself as estimated.
#[test]
fn degraded_mode_is_shown_as_such_and_the_estimated_sensor_is_marked() {
    let mut o = ConsoleOptions::new(&root().join("layouts/sorting-station"));
    o.scenario = Some(root().join("layouts/sorting-station/scenarios/c4-stuck-degraded.ron"));
    let mut h = harness(o);
    h.run_steps(2);
    h.state_mut().apply(Command::SetSpeed(100.0));
    h.state_mut().apply(Command::Run);
    for _ in 0..2000 {
        h.step();
        if !h.state().sim.degraded_sensors().is_empty() {
            break;
        }
    }
    h.state_mut().apply(Command::Pause);
    h.run_steps(2);
    assert_eq!(h.state().sim.degraded_sensors(), ["C4"]);
    h.get_by_label("DEGRADED");
    assert!(h.query_by_label("RUNNING").is_none());
    let marks: Vec<(String, vigie_core::explain::Mark)> = h
        .state()
        .sim
        .live_marks()
        .into_iter()
        .map(|m| (m.element, m.mark))
        .collect();
    assert!(
        marks.contains(&("C4".to_string(), vigie_core::explain::Mark::Estimated)),
        "{marks:?}"
    );
}

/// Manual mode from the console: entered deliberately (a confirmation), shown as
/// MANUAL; a refused command is explained in the operator's terms in the panel and the
/// status bar, journaled, and the plant's output does not change; an allowed one
/// reaches the plant; leaving restarts the program (IDLE).
#[test]
fn manual_mode_refuses_a_command_with_its_reason_and_the_plant_does_not_move() {
    let data = temp_dir("manual");
    let mut o = ConsoleOptions::new(&root().join("layouts/sorting-station"));
    o.data_dir = Some(data.clone());
    let mut h = harness(o);
    h.run_steps(2);
    h.get_by_label("IDLE");
    h.get_by_label("Manual…").click();
    h.run_steps(2);
    h.get_by_label("Enter manual mode").click();
    h.run_steps(2);
    h.get_by_label("MANUAL");
    h.get_by_label("Manual mode");
    let a4 = h
        .state()
        .sim
        .bundle
        .plant
        .outputs
        .iter()
        .position(|s| s.id == "A4")
        .expect("A4");
    h.get_by_label("A4 ON").click();
    h.run_steps(3);
    let refusal = "A4 ON refused: no rotation of an empty table (CSs13, with C4 = 1, C6 = 0)";
    assert_eq!(h.state().status, refusal);
    assert_eq!(h.state().manual_refusal.as_deref(), Some(refusal));
    assert!(h.get_all_by_label(refusal).count() >= 1);
    h.state_mut().apply(Command::Step);
    h.run_steps(2);
    assert!(
        !h.state()
            .sim
            .engine
            .frame()
            .now(vigie_core::symbols::Space::Output)
            .get(a4),
        "the refused command never reached the plant"
    );
    // Allowed: the intermediate conveyor on by hand.
    h.get_by_label("A1 ON").click();
    h.run_steps(2);
    h.state_mut().apply(Command::Step);
    h.run_steps(2);
    let a1 = h
        .state()
        .sim
        .bundle
        .plant
        .outputs
        .iter()
        .position(|s| s.id == "A1")
        .expect("A1");
    assert!(
        h.state()
            .sim
            .engine
            .frame()
            .now(vigie_core::symbols::Space::Output)
            .get(a1)
    );
    assert!(h.state().manual_refusal.is_none());
    h.get_by_label("Leave manual").click();
    h.run_steps(2);
    h.get_by_label("IDLE");
    journal_with(
        &data,
        &[
            "\"manual_refused\"",
            refusal,
            "A1 ON by hand",
            "automatic mode",
        ],
    );
    let _ = std::fs::remove_dir_all(&data);
}

/// The alarm history: searched, filtered and exported to CSV under the data folder
/// (never the current folder); the rate KPIs, and a flood shown as such.
#[test]
fn the_alarm_history_searches_filters_exports_and_the_rate_shows_a_flood() {
    let data = temp_dir("history");
    let mut h = harness(options(Some(data.clone())));
    h.run_steps(2);
    run_to_trip(&mut h);
    raise_task_alarms(&mut h, 11, 11_000);
    h.run_steps(2);
    h.get_by_label("Rate: 12 in the last 10 min (average 12.0, peak 12)");
    h.get_by_label("ALARM FLOOD");
    h.get_by_label("Alarm history (12)").click();
    h.run_steps(2);
    h.get_by_label("12 of 12");
    type_into(
        &mut h,
        egui::accesskit::Role::TextInput,
        "Search",
        "rotation",
    );
    h.run_steps(2);
    h.get_by_label("1 of 12");
    h.get_by_label("Export alarms CSV").click();
    h.run_steps(2);
    let path = data.join("vigie-alarms.csv");
    assert_eq!(
        h.state().status,
        format!("1 alarms exported to {}", path.display())
    );
    let csv = std::fs::read_to_string(&path).expect("alarm csv");
    assert_eq!(csv.lines().count(), 2, "{csv}");
    assert!(csv.contains("\"P1\",\"safety filter trip\""), "{csv}");
    // Print: the same filtered history laid out for paper, in the language shown,
    // written (the test console opens no browser) with the filter on top.
    h.get_by_label("Print…");
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.state_mut()
        .apply(Command::PrintAlarms("vigie-alarms.html".into()));
    let printed = std::fs::read_to_string(data.join("vigie-alarms.html")).expect("print");
    assert!(
        printed.contains("<h1>Vigie : historique des alarmes</h1>"),
        "{printed}"
    );
    assert!(printed.contains("Filtre : texte « rotation »"), "{printed}");
    assert_eq!(printed.matches("<tr class=").count(), 1, "{printed}");
    assert!(
        printed.contains("<td>P1</td><td>arrêt sécurité du filtre</td><td>NON ACQ.</td>")
            && printed.contains("Arrêt sécurité : caisse sortant à droite"),
        "{printed}"
    );
    assert!(printed.contains("window.print()"));
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::En));
    // By kind: the task alarms only.
    h.state_mut().history_filter.text.clear();
    h.state_mut().history_filter.kind = Some(vigie_core::alarms::AlarmKind::Task);
    h.run_steps(2);
    h.get_by_label("11 of 12");
    // A relative journal export lands under the data folder too.
    h.state_mut()
        .apply(Command::ExportCsv("journal-export.csv".into()));
    assert!(data.join("journal-export.csv").is_file());
    let _ = std::fs::remove_dir_all(&data);
}

/// A data folder with two accounts: marie (maintenance) and tom (operator).
fn data_with_accounts(name: &str) -> PathBuf {
    let data = temp_dir(name);
    let mut users = vigie_app::console::users::Users::default();
    users
        .set(
            "marie",
            vigie_core::access::Role::Maintenance,
            "correct horse",
        )
        .unwrap();
    users
        .set("tom", vigie_core::access::Role::Operator, "battery staple")
        .unwrap();
    users.save(&data).unwrap();
    data
}

/// The console on the reference program (not started) with the accounts of
/// [`data_with_accounts`] in its data folder.
fn console_with_accounts(name: &str) -> (PathBuf, Harness<'static, Console>) {
    let data = data_with_accounts(name);
    let mut o = ConsoleOptions::new(&root().join("layouts/sorting-station"));
    o.data_dir = Some(data.clone());
    (data, harness(o))
}

/// Roles: the operator cannot open Maintenance on the production program (button
/// disabled, the command refused and journaled); a wrong password is refused without
/// saying which part was wrong and without journaling it; maintenance logs in, opens
/// Maintenance, logs out and is back to the operator role.
#[test]
fn login_roles_and_a_refused_maintenance_action_for_the_operator() {
    let (data, mut h) = console_with_accounts("roles");
    h.run_steps(2);
    assert!(h.get_by_label("Maintenance").accesskit_node().is_disabled());
    h.state_mut().apply(Command::SetMode(Mode::Maintenance));
    h.run_steps(2);
    assert_eq!(h.state().mode, Mode::Production);
    assert_eq!(
        h.state().status,
        "Refused: editing the program needs the maintenance or administrator role \
         (operator now): log in"
    );
    // A wrong password.
    h.get_by_label("Log in…").click();
    h.run_steps(2);
    type_into(&mut h, egui::accesskit::Role::TextInput, "User", "marie");
    h.run_steps(1);
    type_into(
        &mut h,
        egui::accesskit::Role::PasswordInput,
        "Password",
        "wrong one",
    );
    h.run_steps(1);
    h.get_by_label("Log in").click();
    h.run_steps(2);
    assert_eq!(
        h.state().status,
        "Login refused: unknown user or wrong password"
    );
    assert_eq!(h.state().role, vigie_core::access::Role::Operator);
    // The right one (the dialog is still open, the password field emptied).
    type_into(
        &mut h,
        egui::accesskit::Role::PasswordInput,
        "Password",
        "correct horse",
    );
    h.run_steps(1);
    h.get_by_label("Log in").click();
    h.run_steps(2);
    assert_eq!(h.state().status, "marie logged in (maintenance)");
    h.get_by_label("marie · maintenance");
    h.get_by_label("Maintenance").click();
    h.run_steps(2);
    assert_eq!(h.state().mode, Mode::Maintenance);
    h.get_by_label("Log out").click();
    h.run_steps(2);
    assert_eq!(h.state().mode, Mode::Production);
    assert_eq!(h.state().role, vigie_core::access::Role::Operator);
    let journal = journal_with(
        &data,
        &[
            "\"refused\"",
            "\"login_refused\"",
            "login refused for `marie`",
            "\"login\"",
            "marie logged out",
        ],
    );
    assert!(!journal.contains("wrong one") && !journal.contains("correct horse"));
    let _ = std::fs::remove_dir_all(&data);
}

/// A bypass of one constraint: refused for the operator; for maintenance, with a
/// reason, shown on a banner on every screen while active, ended by hand, journaled at
/// each step.
#[test]
fn a_bypass_needs_maintenance_shows_a_banner_and_is_journaled() {
    let (data, mut h) = console_with_accounts("bypass");
    h.run_steps(2);
    let bypass = Command::Plant(vigie_core::sim::OperatorAction::Bypass {
        constraint: "CSs1".into(),
        minutes: 15,
        reason: "sensor C1 replaced".into(),
        by: "tom".into(),
    });
    h.state_mut().apply(bypass);
    assert!(h.state().sim.bypasses().is_empty());
    assert!(
        h.state()
            .status
            .starts_with("Refused: bypassing a safety constraint")
    );
    h.state_mut().apply(Command::Login {
        name: "marie".into(),
        password: "correct horse".into(),
    });
    h.get_by_label("Maintenance").click();
    h.run_steps(2);
    h.get_by_label("Bypass a constraint");
    type_into(
        &mut h,
        egui::accesskit::Role::TextInput,
        "Bypass reason",
        "sensor C1 replaced",
    );
    h.run_steps(1);
    h.get_by_label("Bypass now").click();
    h.run_steps(2);
    assert_eq!(
        h.state().sim.engine.bypassed().iter().collect::<Vec<_>>(),
        ["CSs1"]
    );
    // The banner, on the production screen too.
    h.get_by_label("Production").click();
    h.run_steps(2);
    h.get_by_label_contains(
        "BYPASS: CSs1 (two boxes between C0 and C1: stop the entry conveyor) is not \
         enforced until",
    );
    // The banner and the journal's line both say who and why.
    assert_eq!(
        h.get_all_by_label_contains("by marie: sensor C1 replaced")
            .count(),
        2
    );
    h.get_by_label("End bypass of CSs1").click();
    h.run_steps(2);
    assert!(h.state().sim.engine.bypassed().is_empty());
    assert!(h.query_by_label_contains("BYPASS:").is_none());
    journal_with(
        &data,
        &[
            "CSs1 bypassed for 15 min by marie: sensor C1 replaced",
            "\"bypass_end\"",
        ],
    );
    let _ = std::fs::remove_dir_all(&data);
}

/// Guessing a password is slowed: after five failures in a row, even the right password
/// is refused while logins are locked, and the lock is journaled.
#[test]
fn five_failed_logins_lock_the_login() {
    let (data, mut h) = console_with_accounts("lockout-fr");
    h.run_steps(1);
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.state_mut().apply(Command::Login {
        name: "nobody".into(),
        password: "whatever1".into(),
    });
    assert_eq!(
        h.state().status,
        "Connexion refusée : utilisateur inconnu ou mot de passe erroné"
    );
    let _ = std::fs::remove_dir_all(&data);
    let (data, mut h) = console_with_accounts("lockout");
    h.run_steps(1);
    let login = |password: &str| Command::Login {
        name: "marie".into(),
        password: password.into(),
    };
    for k in 0..vigie_app::console::MAX_FAILED_LOGINS {
        h.state_mut().apply(login(&format!("guess {k}")));
        assert_eq!(
            h.state().status,
            "Login refused: unknown user or wrong password"
        );
    }
    h.state_mut().apply(login("correct horse"));
    assert!(
        h.state().status.starts_with("Login locked for ")
            && h.state().status.ends_with(" s after 5 failed attempts"),
        "{}",
        h.state().status
    );
    assert_eq!(h.state().role, vigie_core::access::Role::Operator);
    // In French, both refusals are French (the reason was the English error text).
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.state_mut().apply(login("correct horse"));
    assert!(
        h.state().status.starts_with("Connexion bloquée pendant ")
            && h.state().status.ends_with(" s après 5 échecs"),
        "{}",
        h.state().status
    );
    journal_with(&data, &["\"login_locked\"", "logins locked for 60 s"]);
    let _ = std::fs::remove_dir_all(&data);
}

/// Trends: the process history of the run, read back from the historian, drawn and
/// exported; without a data folder the view says there is no history.
#[test]
fn trends_show_and_export_the_process_history() {
    let data = temp_dir("trends");
    let mut opts = options(Some(data.clone()));
    opts.scenario = Some(root().join("layouts/sorting-station/scenarios/reference-hour.ron"));
    let mut h = harness(opts);
    h.run_steps(1);
    h.get_by_label("Start").click();
    h.run_steps(1);
    // 40 s of production (the station's boxes cross C0 every few seconds).
    h.state_mut().cycles(4000);
    assert!(h.state_mut().journal.flush_history(), "history committed");
    h.get_by_label("Trends").click();
    h.run_steps(2);
    h.get_by_label("C0 ✕");
    h.get_by_label("1 min").click();
    h.run_steps(2);
    let store = h.state().journal.store().expect("historian");
    let now = h.state().journal.wall_of(h.state().sim.now().0);
    let c0 = store.changes("C0", now - 60_000, now + 1).expect("changes");
    assert!(
        c0.len() >= 4,
        "C0 toggled in production: {c0:?}, now {now}, sim {}, state {:?}, status {}",
        h.state().sim.now().0,
        h.state().sim.plant_state(),
        h.state().status
    );
    // Removing a signal, adding another through the list.
    h.get_by_label("C0 ✕").click();
    h.run_steps(2);
    assert!(h.query_by_label("C0 ✕").is_none());
    h.get_by_label("Add a signal…").click();
    h.run_steps(2);
    // The list is long: filter it down, as a user would.
    type_into(&mut h, egui::accesskit::Role::TextInput, "Filter", "a4");
    h.run_steps(2);
    assert!(h.query_by_label("C0").is_none(), "filtered out");
    h.get_by_label("A4.cmd");
    h.get_by_label("A4").click();
    h.run_steps(2);
    h.get_by_label("A4 ✕");
    // The export: A4's changes over the minute.
    h.state_mut()
        .apply(Command::ExportTrend("trend.csv".into()));
    let csv = std::fs::read_to_string(data.join("trend.csv"))
        .expect("trend written under the data folder");
    assert!(csv.starts_with("signal,t_ms,value\n"), "{csv}");
    assert!(
        csv.lines().filter(|l| l.starts_with("A4,")).count() >= 2,
        "{csv}"
    );
    drop(h);
    let _ = std::fs::remove_dir_all(&data);

    let mut h = harness(options(None));
    h.run_steps(1);
    h.get_by_label("Trends").click();
    h.run_steps(2);
    assert!(h.query_by_label_contains("No history").is_some());
}

/// French and English, switched at run time: the state, the toolbar and the trends
/// change language at once; the switch is journaled; English comes back.
#[test]
fn language_switch_french_and_english() {
    let data = temp_dir("lang");
    let mut opts = options(Some(data.clone()));
    opts.scenario = None;
    let mut h = harness(opts);
    h.run_steps(1);
    h.get_by_label("IDLE");
    h.get_by_label("FR").click();
    h.run_steps(2);
    assert_eq!(h.state().i18n.lang(), vigie_app::i18n::Lang::Fr);
    h.get_by_label("AU REPOS");
    h.get_by_label("Départ cycle").click();
    h.run_steps(2);
    h.get_by_label("EN PRODUCTION");
    h.get_by_label("Courbes").click();
    h.run_steps(2);
    h.get_by_label("Ajouter un signal…");
    assert!(
        h.query_by_label("Start").is_none(),
        "no English left on the toolbar"
    );
    h.get_by_label("EN").click();
    h.run_steps(2);
    h.get_by_label("RUNNING");
    h.get_by_label("Add a signal…");
    journal_with(&data, &["language fr", "language en"]);
    let _ = std::fs::remove_dir_all(&data);
}

/// A data folder whose historian is not a database: the console opens all the same,
/// journals in memory, says why, and leaves the file as it was.
#[test]
fn a_damaged_historian_leaves_the_console_running_and_the_file_alone() {
    let data = temp_dir("damaged-historian");
    std::fs::create_dir_all(&data).unwrap();
    let garbage = b"this is not a database ".repeat(64);
    std::fs::write(data.join("vigie.sqlite"), &garbage).unwrap();
    let mut h = harness(options(Some(data.clone())));
    h.run_steps(2);
    let error = h.state().journal.error.clone().expect("the error is shown");
    assert!(
        error.contains("in memory only") && error.contains("vigie.sqlite"),
        "{error}"
    );
    h.get_by_label("Start").click();
    h.run_steps(2);
    assert!(
        h.state()
            .journal
            .entries()
            .iter()
            .any(|e| e.text == "Start")
    );
    assert_eq!(std::fs::read(data.join("vigie.sqlite")).unwrap(), garbage);
    drop(h);
    let _ = std::fs::remove_dir_all(&data);
}

/// The synoptic's element names in the language the console opens in.
#[test]
fn the_synoptic_names_its_elements_in_the_language_it_opens_in() {
    // Opened in French: the schematic strip's block is "Sécurité" from the first frame
    // (it read "Safety" until the language was switched by hand).
    let mut opts = options(None);
    opts.lang = vigie_app::i18n::Lang::Fr;
    let mut h = Harness::builder()
        .with_size(egui::vec2(1280.0, 720.0))
        .build_eframe(move |cc| {
            let mut c = Console::new(&opts).expect("console opens");
            c.setup(&cc.egui_ctx);
            c
        });
    h.run_steps(2);
    assert_eq!(h.state().view.elements["Safety"], "Sécurité");
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::En));
    assert_eq!(h.state().view.elements["Safety"], "Safety");
}

/// The paper's CSs10 trip in French: the next step, the alarm and the explanation
/// levels from the plant's French texts and the items' codes; the records stay English.
#[test]
// One operator's session, step by step: split, the steps would lose their order.
#[allow(clippy::too_many_lines)]
fn the_cs10_trip_explained_in_french() {
    let mut opts = options(None);
    opts.lang = vigie_app::i18n::Lang::Fr;
    let mut h = harness(opts);
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.run_steps(1);
    h.get_by_label("Départ cycle").click();
    h.run_steps(2);
    run_to_trip(&mut h);
    h.run_steps(2);
    let why = "Arrêt sécurité : caisse sortant à droite : maintenir la rotation (CSs10). Maintenus EN MARCHE : A4 (Table tournante). Arrêtés : A0 (Convoyeur d'entrée), A5 (Convoyeur de sortie gauche), A6 (Convoyeur de sortie droit)";
    assert!(
        h.query_by_label(&format!("1. Pourquoi : {why}.")).is_some(),
        "next step in French"
    );
    // The alarm row, as the next step says it.
    h.get_by_label(why);
    h.get_by_label(
        "2. À vérifier sur la machine : Convoyeur de sortie droit (C7) ; Table tournante (A4).",
    );
    assert!(
        h.query_by_label_contains("réarmement refusé : CSs10 encore violée(s)")
            .is_some()
    );
    for (button, item) in [
        (
            "2 Avant l'arrêt",
            "Le filtre a maintenu EN MARCHE A4 (commandé À L'ARRÊT ; A4 À L'ARRÊT : la table tournante revient en position de chargement).",
        ),
        (
            "3 Avancé",
            "C7 est passé de 0 à 1 à 11680 ms (dans le cycle de l'arrêt), élément de la contrainte.",
        ),
        ("4 Hypothèse", "Attendu de la commande : A4=1."),
    ] {
        h.get_by_label(button).click();
        h.run_steps(2);
        assert!(h.query_by_label(item).is_some(), "level {button}: {item}");
    }
    // Where the box would be sheared, with the plant's French name of the part.
    h.get_by_label("1 Projection").click();
    h.run_steps(2);
    assert!(
        h.query_by_label_contains("serait cisaillée au niveau de : Table tournante (bord)")
            .is_some(),
        "level 1 names the place in French"
    );
    // The journal panel in French, from the entries' message ids; the status line
    // titles the run in French.
    for shown in [
        "console ouverte sur CSs10 : A4 relâchée pendant que la caisse sort à droite",
        "opérateur  Départ cycle",
        "opérateur  langue fr",
        "arrêt      arrêt sécurité sur CSs10",
    ] {
        assert!(
            h.query_all_by_label_contains(shown).next().is_some(),
            "journal shows {shown:?}"
        );
    }
    assert!(
        h.query_by_label_contains(
            "CSs10 : A4 relâchée pendant que la caisse sort à droite — caisses"
        )
        .is_some()
    );
    // The incident report, in the language shown.
    let out = temp_dir("report-fr");
    h.state_mut()
        .apply(Command::ExportReport(out.join("report")));
    let md = std::fs::read_to_string(out.join("report/report.md")).expect("report");
    assert!(md.starts_with("# Rapport d'incident"), "{md}");
    assert!(
        md.contains("## Niveau 4 Hypothèse") && md.contains("Attendu de la commande : A4=1."),
        "{md}"
    );
    let _ = std::fs::remove_dir_all(&out);
    // The records stay in English (the journal, the core's alarm text), with the
    // message id that shows them in any language.
    assert!(
        h.state()
            .journal
            .entries()
            .iter()
            .any(|e| e.text == "filter tripped on CSs10"
                && e.code == "journal-trip"
                && e.fields.get("constraints").map(String::as_str) == Some("CSs10"))
    );
    // Back in English, the journal shows the records.
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::En));
    h.run_steps(2);
    assert!(
        h.query_by_label_contains("trip       filter tripped on CSs10")
            .is_some()
    );
    assert!(
        h.query_by_label_contains(
            "console opened on CSs10: A4 released while the box leaves to the right"
        )
        .is_some()
    );
    assert!(
        h.state()
            .sim
            .alarms
            .all()
            .iter()
            .any(|a| a.message.starts_with("Safety stop: "))
    );
}

/// Degraded mode (C4 stuck at 0, estimated): the plant goes on, so no alarm is a
/// first-out (the finding: FIRST OUT on a suspect-sensor alarm while nothing stopped).
#[test]
fn degraded_mode_has_no_first_out() {
    let mut opts = options(None);
    opts.scenario = Some(root().join("layouts/sorting-station/scenarios/c4-stuck-degraded.ron"));
    let mut h = harness(opts);
    h.run_steps(1);
    h.state_mut().cycles(6000);
    h.run_steps(2);
    h.get_by_label("DEGRADED");
    let alarms = h.state().sim.alarms.all();
    assert!(
        alarms
            .iter()
            .any(|a| a.kind == vigie_core::alarms::AlarmKind::Diagnosis),
        "the diagnosis alarm"
    );
    assert!(alarms.iter().all(|a| !a.first_out), "no first-out");
    assert!(h.query_by_label("FIRST OUT").is_none());
}

/// A manual request refused in French: the refusal in the operator's language, from
/// the plant's French texts, and no output changed.
#[test]
fn a_manual_refusal_in_french() {
    let mut opts = options(None);
    opts.scenario = None;
    let mut h = harness(opts);
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.run_steps(1);
    h.state_mut()
        .apply(Command::Plant(vigie_core::sim::OperatorAction::Manual(
            true,
        )));
    h.run_steps(1);
    // The table at C4, empty: turning it is refused (CSs13).
    h.state_mut()
        .apply(Command::Plant(vigie_core::sim::OperatorAction::ManualSet(
            "A4".into(),
            true,
        )));
    h.run_steps(2);
    let refusal = h.state().manual_refusal.clone().expect("refused");
    assert_eq!(
        refusal,
        "A4 EN MARCHE refusé : pas de rotation d'une table vide (CSs13, avec C4 = 1, C6 = 0)"
    );
    assert!(h.get_all_by_label(&refusal).count() >= 1, "shown");
    assert!(!h.state().sim.manual_outputs().expect("manual").get(4));
    // The journal keeps the core's record, and shows the refusal in French.
    assert!(h.state().journal.entries().iter().any(|e| {
        e.kind == "manual_refused"
            && e.text
                .starts_with("A4 ON refused: no rotation of an empty table")
            && e.code == "journal-manual-refused"
    }));
    assert!(
        h.query_by_label_contains(&format!("man. refusé {refusal}"))
            .is_some(),
        "the journal panel in French"
    );
}

/// Degraded mode in French: the diagnosis and the suspect sensor's alarms from their
/// codes and fields, with the plant's French descriptions.
#[test]
fn degraded_mode_alarms_in_french() {
    let mut opts = options(None);
    opts.scenario = Some(root().join("layouts/sorting-station/scenarios/c4-stuck-degraded.ron"));
    let mut h = harness(opts);
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.run_steps(1);
    h.state_mut().cycles(6000);
    h.run_steps(2);
    h.get_by_label("DÉGRADÉ");
    h.get_by_label(
        "Diagnostic : défaut F1 du capteur C4 (Table tournante en position de chargement) (certain) : C4 est estimé à partir des intervalles de temps (la temporisation de table) ; la production continue en mode dégradé",
    );
    // The alarm row and its journal entry, both in French.
    assert_eq!(
        h.query_all_by_label_contains(
            "C4 (Table tournante en position de chargement) suspect : retombée invraisemblable"
        )
        .count(),
        2
    );
    assert!(
        h.query_by_label_contains(
            "plausibilité C4 (Table tournante en position de chargement) suspect"
        )
        .is_some(),
        "the journal entry in French"
    );
}

/// The alarms of earlier runs come back from the historian: the console's own last run
/// and a gateway's session in the same data folder, newest first.
#[test]
fn alarms_of_earlier_runs_from_the_historian() {
    let data = temp_dir("past-alarms");
    {
        let mut h = harness(options(Some(data.clone())));
        h.run_steps(1);
        h.get_by_label("Start").click();
        h.run_steps(1);
        run_to_trip(&mut h);
        h.run_steps(2);
        assert!(h.state_mut().journal.flush_history());
    }
    // A gateway's session in the same folder (as `vigie gateway` writes it).
    {
        let mut store = vigie_app::historian::Store::open_in(&data).expect("historian");
        let s = store
            .begin_session("gateway", "station", vigie_app::historian::wall_ms())
            .unwrap();
        store
            .upsert_alarms(
                s,
                &[vigie_app::historian::AlarmRow {
                    alarm: 1,
                    key: "link:peer".into(),
                    kind: "link".into(),
                    priority: "high".into(),
                    message: "peer lost (never heard)".into(),
                    detail: String::new(),
                    raised_ms: vigie_app::historian::wall_ms(),
                    acked: None,
                    cleared_ms: None,
                    shelved: None,
                    first_out: false,
                    ..Default::default()
                }],
            )
            .unwrap();
    }
    let mut h = harness(options(Some(data.clone())));
    h.run_steps(1);
    h.get_by_label("Alarm history (0)").click();
    h.run_steps(2);
    h.get_by_label("Alarms of earlier runs (historian)").click();
    h.run_steps(2);
    assert!(
        h.query_by_label_contains("URGENT · UNACK  Safety stop: box leaving to the right")
            .is_some()
    );
    assert!(
        h.query_by_label_contains("HIGH · UNACK  peer lost (never heard)")
            .is_some()
    );
    // In French: the earlier trip told from its code and fields with the plant's
    // French texts; the gateway's alarm, which has none, as recorded.
    h.state_mut()
        .apply(Command::SetLanguage(vigie_app::i18n::Lang::Fr));
    h.run_steps(2);
    assert!(
        h.query_by_label_contains(
            "URGENTE · NON ACQ.  Arrêt sécurité : caisse sortant à droite : maintenir la rotation (CSs10)"
        )
        .is_some()
    );
    assert!(
        h.query_by_label_contains("HAUTE · NON ACQ.  peer lost (never heard)")
            .is_some()
    );
    drop(h);
    let _ = std::fs::remove_dir_all(&data);
}

/// Issue 20: the synoptic's sensor names and the explanation tags of every level stand
/// beside their own element (the nearest symbol to a tag is its element's), on no
/// symbol, no name and no other tag, at 1280x720 and at 1920x1080.
#[test]
fn tags_and_names_sit_at_their_element_without_overlap() {
    for size in [egui::vec2(1280.0, 720.0), egui::vec2(1920.0, 1080.0)] {
        let mut opts = options(None);
        opts.lang = vigie_app::i18n::Lang::En;
        let mut h = Harness::builder()
            .with_size(size)
            .with_step_dt(1.0 / 60.0)
            .build_eframe(move |cc| {
                let mut c = Console::new(&opts).expect("console opens");
                c.setup(&cc.egui_ctx);
                c
            });
        h.run_steps(2);
        run_to_trip(&mut h);
        for level in 0..5 {
            h.state_mut().apply(Command::ShowLevel(Some(level)));
            h.run_steps(3);
            let placed = h.state().view.placed.clone();
            assert!(!placed.symbols.is_empty());
            let overlap =
                |a: &egui::Rect, b: &egui::Rect| a.intersect(*b).area() > 0.5 && a.intersects(*b);
            for (i, (a, ra)) in placed.names.iter().enumerate() {
                for (b, rb) in placed.names.iter().skip(i + 1) {
                    assert!(!overlap(ra, rb), "{size:?}: names {a} and {b} overlap");
                }
                for (b, rb) in &placed.symbols {
                    assert!(!overlap(ra, rb), "{size:?}: name {a} on the symbol of {b}");
                }
            }
            for (i, (a, ra)) in placed.tags.iter().enumerate() {
                for (b, rb) in placed.tags.iter().skip(i + 1) {
                    assert!(
                        !overlap(ra, rb),
                        "{size:?} level {level}: tags of {a} and {b} overlap"
                    );
                }
                for (b, rb) in placed.symbols.iter().chain(&placed.names) {
                    assert!(
                        !overlap(ra, rb),
                        "{size:?} level {level}: tag of {a} on {b}"
                    );
                }
                let own = placed
                    .symbols
                    .iter()
                    .find(|(s, _)| s == a)
                    .map(|(_, r)| ra.distance_to_pos(r.center()))
                    .expect("the tag's element is drawn");
                for (b, rb) in &placed.symbols {
                    let d = ra.distance_to_pos(rb.center());
                    assert!(
                        own <= d + 0.5,
                        "{size:?} level {level}: the tag of {a} is nearer {b} ({d:.0} px) than {a} ({own:.0} px)"
                    );
                }
            }
            if level >= 2 {
                assert!(!placed.tags.is_empty(), "level {level} has tags");
            }
        }
    }
}

/// Issue 20: the chronogram's window zooms between 2 s and one hour.
#[test]
fn the_chronogram_window_zooms_within_bounds() {
    let mut h = harness(options(None));
    h.run_steps(2);
    h.state_mut().apply(Command::ChronoWindow(1));
    assert_eq!(h.state().chrono_window_ms, 2_000);
    h.state_mut().apply(Command::ChronoWindow(u64::MAX));
    assert_eq!(h.state().chrono_window_ms, 3_600_000);
    h.get_by_label("60 s").click();
    h.run_steps(2);
    assert_eq!(h.state().chrono_window_ms, 60_000);
}

/// Issue 20: exporting the report captures every level and gives the view back as it
/// was (the level shown, paused or running).
#[test]
fn exporting_the_report_does_not_change_the_view() {
    let out = temp_dir("report-view");
    let mut h = harness(options(None));
    h.run_steps(1);
    run_to_trip(&mut h);
    h.state_mut().apply(Command::ShowLevel(Some(3)));
    h.run_steps(2);
    let running = h.state().running;
    h.state_mut()
        .apply(Command::ExportReport(out.join("report")));
    // The capture runs over frames; bounded.
    for _ in 0..2_000 {
        h.step();
        if h.state().status.contains("incident report complete")
            || h.state().status.contains("PNG capture unavailable")
        {
            break;
        }
    }
    assert!(
        h.state().status.contains("incident report complete"),
        "{}",
        h.state().status
    );
    assert_eq!(h.state().level, Some(3), "the level shown is kept");
    assert_eq!(h.state().running, running);
    for f in [
        "level-0.png",
        "level-4.png",
        "chronogram.png",
        "chronogram.svg",
        "report.md",
    ] {
        assert!(out.join("report").join(f).exists(), "{f}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// Issue 20, hardware before program: with the turntable's valve stuck ON, the console's
/// level 4 starts with the hardware (its spool monitoring contact against its output,
/// X419, and A4 to check), and lists no program suspect to link to.
#[test]
fn an_actuator_stuck_on_is_told_as_hardware_first_on_the_console() {
    let mut opts = options(None);
    opts.scenario = Some(root().join("layouts/sorting-station/scenarios/a4-stuck-on.ron"));
    let mut h = harness(opts);
    h.run_steps(2);
    run_to_trip(&mut h);
    h.state_mut().apply(Command::ShowLevel(Some(4)));
    h.run_steps(3);
    let items = &h
        .state()
        .sim
        .explanations
        .values()
        .next_back()
        .expect("explained")
        .hypothesis
        .items;
    assert_eq!(items[0].code, "X419", "{:?}", items[0].text);
    assert!(items[0].fields["check"].split(", ").any(|e| e == "A4"));
    // What the technician reads first, on screen: the valve's spool monitoring contact
    // still reads it switched after its release.
    h.get_by_label_contains("Hardware first: A4 was released and its mirror contact A4_fb");
    h.get_by_label_contains("Check A4's contactor on the machine");
    assert!(h.query_by_label_contains("in the program").is_none());
}

/// Issue 16: the console opens on a plant described as components (no `layout.ron`):
/// the synoptic draws the drill head from its scene, the status line counts elementary
/// actions, the console's Start presses the machine's DY button, and a stuck sensor
/// stops the plant with the action monitor's words in the explanation panel.
#[test]
fn the_console_runs_a_plant_of_components() {
    let dir = root().join("layouts/drilling-station");
    let mut o = ConsoleOptions::new(&dir);
    o.scenario = Some(dir.join("scenarios/reference.ron"));
    o.data_dir = Some(temp_dir("drilling"));
    let mut h = harness(o);
    h.run_steps(2);
    assert!(h.state().sim.layout.is_none());
    assert!(h.query_all_by_label("Synoptic").count() >= 1);
    h.query_by_label_contains("elementary actions: 0 completed, 0 faults")
        .expect("the status line counts actions, not boxes");
    h.state_mut().apply(Command::SetSpeed(100.0));
    for _ in 0..300 {
        h.step();
        if h.state().sim.now().0 > 4000 {
            break;
        }
    }
    h.state_mut().apply(Command::Pause);
    h.run_steps(2);
    let done = h.state().sim.action_events();
    assert_eq!(
        done.iter().map(|e| e.action.as_str()).collect::<Vec<_>>(),
        ["N1"],
        "the scenario's Start pressed DY and the head reached b1"
    );
    h.query_by_label_contains("elementary actions: 1 completed, 0 faults")
        .expect("status line");

    let mut o = ConsoleOptions::new(&dir);
    o.scenario = Some(dir.join("scenarios/b2-stuck-on.ron"));
    o.data_dir = Some(temp_dir("drilling-stuck"));
    let mut h = harness(o);
    h.state_mut().apply(Command::SetSpeed(100.0));
    for _ in 0..120 {
        h.step();
        if h.state().sim.now().0 > 1000 {
            break;
        }
    }
    h.state_mut().apply(Command::Pause);
    h.run_steps(2);
    h.get_by_label("STOPPED");
    h.query_by_label_contains("Stopped by the elementary-action monitor")
        .expect("the explanation says who stopped the plant");
    assert!(
        h.query_all_by_label_contains("Action N2 (b1 -> b2 under DPV): unexpected final state")
            .count()
            >= 1,
        "the alarm names the action"
    );
}

/// Issue 16: the plant picker lists the plant folders beside the one opened and
/// reopens the console on the one picked, its reference program running, in the
/// language shown.
#[test]
fn the_plant_picker_opens_another_plant_folder() {
    let mut h = harness(options(Some(temp_dir("picker"))));
    h.run_steps(2);
    assert!(h.state().sim.layout.is_some());
    let station = h.state().sim.bundle.plant.name.clone();
    h.get_by_label(station.as_str()).click();
    h.run_steps(2);
    h.get_by_label("Drilling station").click();
    h.run_steps(3);
    assert_eq!(h.state().sim.bundle.plant.name, "Drilling station");
    assert!(h.state().sim.layout.is_none(), "a plant of components");
    h.query_by_label_contains("elementary actions: 0 completed")
        .expect("the drilling station's status line");
    // And back.
    h.get_by_label("Drilling station").click();
    h.run_steps(2);
    h.get_by_label(station.as_str()).click();
    h.run_steps(3);
    assert!(h.state().sim.layout.is_some());
}

/// A plant with conveyors (seed 000's workshop) opens on its own folder: the synoptic
/// draws the belt and the robot, the status line counts the items, and the thesis's
/// scenario 1 raises the conveyor task's alarm in the console too.
#[test]
fn the_console_runs_a_plant_with_conveyors() {
    let dir = root().join("layouts/workshop");
    let mut o = ConsoleOptions::new(&dir);
    o.scenario = Some(dir.join("scenarios/thesis-scenario-1.ron"));
    o.data_dir = Some(temp_dir("workshop"));
    let mut h = harness(o);
    h.run_steps(2);
    h.state_mut().apply(Command::SetSpeed(100.0));
    for _ in 0..600 {
        h.step();
        if h.state().sim.now().0 > 6_500 {
            break;
        }
    }
    h.state_mut().apply(Command::Pause);
    h.run_steps(2);
    assert!(h.state().sim.now().0 > 6_500, "{:?}", h.state().sim.now());
    h.query_by_label_contains("items: 2 placed, 1 out")
        .expect("the status line counts the pallets");
    let alarms = h.state().sim.alarms.all();
    assert!(
        alarms
            .iter()
            .any(|a| a.kind == vigie_core::alarms::AlarmKind::Task
                && a.message.contains("conveyor and pusher: stopped too long")
                && (6_000..=6_020).contains(&a.raised.0)),
        "{alarms:?}"
    );
}

/// A click of the primary button at `at`, as a pointer gives it.
fn click_at(h: &mut Harness<'_, Console>, at: egui::Pos2) {
    h.event(egui::Event::PointerMoved(at));
    for pressed in [true, false] {
        h.event(egui::Event::PointerButton {
            pos: at,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::default(),
        });
        h.run_steps(1);
    }
    h.run_steps(2);
}

/// The whole plant of many areas is an overview: every signal's symbol, no name (the
/// tooltip gives it), the areas framed apart from each other, each symbol in its own
/// area's frame, no two symbols on each other. Returns what it placed.
fn overview_is_readable(h: &Harness<'_, Console>) -> vigie_app::console::synoptic::Placed {
    // The whole plant is an overview: every signal's symbol, no name (the tooltip
    // gives it), the areas framed apart from each other, each symbol in its own
    // area's frame, no two symbols on each other.
    let placed = h.state().view.placed.clone();
    assert!(placed.names.is_empty(), "{:?}", placed.names);
    let symbols: Vec<&str> = placed.symbols.iter().map(|(id, _)| id.as_str()).collect();
    assert!(
        symbols.contains(&"TS_POS") && symbols.contains(&"PS_DR_LOW"),
        "{symbols:?}"
    );
    let frames: Vec<&str> = placed.frames.iter().map(|(a, _)| a.as_str()).collect();
    for area in [
        "Distributing",
        "Testing",
        "Handling",
        "Processing",
        "Sorting",
    ] {
        assert!(frames.contains(&area), "{frames:?}");
    }
    for (i, (a, r)) in placed.frames.iter().enumerate() {
        for (b, q) in &placed.frames[i + 1..] {
            assert!(!r.intersects(*q), "frames {a} and {b} overlap");
        }
    }
    let element = |id: &str| {
        let plant = &h.state().sim.bundle.plant;
        plant
            .inputs
            .iter()
            .chain(&plant.outputs)
            .find(|s| s.id == id)
            .map(|s| s.element.clone())
    };
    for (i, (id, r)) in placed.symbols.iter().enumerate() {
        let inside: Vec<&str> = placed
            .frames
            .iter()
            .filter(|(_, f)| f.contains_rect(*r))
            .map(|(a, _)| a.as_str())
            .collect();
        assert_eq!(inside.len(), 1, "{id} in {inside:?}");
        if let Some(e) = element(id).filter(|e| frames.contains(&e.as_str())) {
            assert_eq!(inside[0], e, "{id}");
        }
        for (j, q) in placed.symbols[i + 1..].iter() {
            assert!(
                r.intersect(*q).area() < 1.0,
                "symbols {id} and {j} on each other"
            );
        }
    }
    placed
}

/// A plant of many components in several stations (the production line): the synoptic
/// offers one view per area besides the whole plant, flags the area of a trip, and an
/// area's view draws its own signals only.
#[test]
fn a_large_plant_is_shown_area_by_area_and_the_trips_area_is_flagged() {
    let dir = root().join("layouts/production-line");
    let mut o = ConsoleOptions::new(&dir);
    o.scenario = Some(dir.join("scenarios/e03-drill-fast-into-part.ron"));
    o.data_dir = Some(temp_dir("production-line"));
    let mut h = harness(o);
    h.run_steps(2);
    h.state_mut().apply(Command::SetSpeed(100.0));
    for _ in 0..2_000 {
        h.step();
        if h.state().sim.engine.is_tripped() {
            break;
        }
    }
    h.state_mut().apply(Command::Pause);
    h.run_steps(2);
    assert!(
        h.state().sim.engine.is_tripped(),
        "{:?}",
        h.state().sim.now()
    );
    let names = |h: &Harness<'_, Console>| -> Vec<String> {
        h.state()
            .view
            .placed
            .names
            .iter()
            .map(|(id, _)| id.clone())
            .collect()
    };
    let placed = overview_is_readable(&h);
    // CSp22 is the drill's: its area is flagged, the others are not; a click in its
    // block of the overview opens it.
    assert!(h.query_by_label("⚠ Processing").is_some());
    assert!(h.query_by_label("⚠ Testing").is_none());
    let block = placed
        .frames
        .iter()
        .find(|(a, _)| a == "Processing")
        .map(|(_, r)| *r)
        .expect("the Processing block");
    click_at(&mut h, block.left_top() + egui::vec2(6.0, 6.0));
    assert_eq!(h.state().view.area.as_deref(), Some("Processing"));
    let area = names(&h);
    assert!(area.iter().any(|n| n == "PS_DR_LOW"), "{area:?}");
    assert!(!area.iter().any(|n| n == "TS_POS"), "{area:?}");
    h.get_by_label("Testing").click();
    h.run_steps(3);
    let area = names(&h);
    assert!(area.iter().any(|n| n == "TS_POS"), "{area:?}");
    assert!(!area.iter().any(|n| n == "PS_DR_LOW"), "{area:?}");
    h.get_by_label("Whole plant").click();
    h.run_steps(3);
    assert_eq!(h.state().view.area, None);
}

/// An area drawn too small for its names (the production line's sorting station beside
/// the program in Maintenance, at 1280x720) keeps its symbols, none on another, and
/// drops the names, which the tooltip gives: they were drawn over each other. The same
/// area in Production keeps its names.
#[test]
fn an_area_too_small_for_its_names_is_drawn_with_its_symbols_only() {
    let dir = root().join("layouts/production-line");
    let mut o = ConsoleOptions::new(&dir);
    o.scenario = Some(dir.join("scenarios/e03-drill-fast-into-part.ron"));
    o.data_dir = None;
    let mut h = harness_sized(o, egui::vec2(1280.0, 720.0));
    h.run_steps(2);
    h.get_by_label("Sorting").click();
    h.run_steps(3);
    assert_eq!(h.state().view.area.as_deref(), Some("Sorting"));
    let names = |h: &Harness<'_, Console>| -> Vec<String> {
        let placed = &h.state().view.placed;
        placed.names.iter().map(|(id, _)| id.clone()).collect()
    };
    assert!(
        names(&h).iter().any(|n| n == "SS_P1_RET"),
        "{:?}",
        names(&h)
    );
    h.state_mut().apply(Command::SetMode(Mode::Maintenance));
    h.run_steps(3);
    assert_eq!(
        h.state().mode,
        Mode::Maintenance,
        "an exercise: anyone edits it"
    );
    let placed = h.state().view.placed.clone();
    assert!(placed.names.is_empty(), "{:?}", placed.names);
    assert!(
        placed.symbols.iter().any(|(id, _)| id == "SS_P1_RET"),
        "{:?}",
        placed.symbols
    );
    for (i, (a, r)) in placed.symbols.iter().enumerate() {
        for (b, q) in &placed.symbols[i + 1..] {
            // Touching edges are allowed (stacked beams), covering is not.
            let both = r.intersect(*q);
            assert!(
                both.width() <= 0.0 || both.height() <= 0.0,
                "symbols {a} {r:?} and {b} {q:?} overlap"
            );
        }
    }
    h.state_mut().apply(Command::SetMode(Mode::Production));
    h.run_steps(3);
    assert!(names(&h).iter().any(|n| n == "SS_P1_RET"));
}
