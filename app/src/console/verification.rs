//! Maintenance: verification of the loaded constraint set (`vigie verify` in the
//! console). The exploration runs on a worker thread. For a turntable cell the panel
//! shows safety, permissiveness, the invariants and which constraints are necessary,
//! and replays the shortest counterexample on the synoptic (filter enforcing); for any
//! other plant of components it shows each sub-plant's verdict, as `vigie verify` does.

use super::{Command, Console, Mode, Source};
use egui::RichText;
use std::thread::JoinHandle;
use vigie_core::verify::components::{ComponentsReport, SubHazard, SubReport};
use vigie_core::verify::{self, Options, Subject, VerifyReport};

/// What a verification found, after the plant's kind of model.
pub(crate) enum Verdict {
    /// The turntable cell's whole model.
    Cell(Box<VerifyReport>),
    /// Each sub-plant of a plant of components.
    Parts(ComponentsReport),
}

/// Verification state of the console.
#[derive(Default)]
pub(crate) struct Verification {
    job: Option<JoinHandle<Result<Verdict, String>>>,
    started_s: f64,
    /// Last result and its wall-clock duration.
    pub(crate) result: Option<(Result<Verdict, String>, f64)>,
    /// A result has just arrived: the side panel scrolls to it once, since the
    /// alarms above may have pushed it out of view while the search ran.
    reveal: bool,
}

impl Verification {
    /// A verification is running.
    pub(crate) fn running(&self) -> bool {
        self.job.is_some()
    }
}

/// Starts the verification of the loaded plant's constraint set on a worker thread.
pub(crate) fn start(c: &mut Console) {
    if c.verification.running() {
        return;
    }
    // The plant folder's own constraint set, as `vigie verify` reads it: the running
    // bundle may carry the diagnosers' rewriting (estimates, stops, their observers),
    // which is not the set the designer wrote and would not give the command's figures.
    let plant_dir = c.plant_dir.clone();
    c.verification.started_s = c.wall_s;
    let spawned = std::thread::Builder::new()
        .name("vigie-verify".into())
        .spawn(move || {
            let render = |p: vigie_core::diag::Problem| vigie_core::diag::render(&[p]);
            let (bundle, _) = vigie_core::bundle::PlantBundle::load(&plant_dir)
                .map_err(|p| vigie_core::diag::render(&p))?;
            match verify::subject_of(&plant_dir).map_err(|p| vigie_core::diag::render(&p))? {
                Subject::Cell(layout) => verify::verify(
                    &bundle,
                    &layout,
                    &Options {
                        max_boxes: 2,
                        necessity_boxes: None,
                    },
                )
                .map(|r| Verdict::Cell(Box::new(r)))
                .map_err(render),
                Subject::Parts(desc) => verify::components::verify_components(&bundle, &desc)
                    .map(Verdict::Parts)
                    .map_err(render),
            }
        });
    match spawned {
        Ok(job) => {
            c.verification.job = Some(job);
            c.say(None, "say-verifying", &[]);
        }
        Err(e) => c.say(None, "say-verify-cannot-start", &[("error", e.to_string())]),
    }
}

/// Collects a finished verification (called every frame).
pub(crate) fn poll(c: &mut Console, ctx: &egui::Context) {
    let finished = c
        .verification
        .job
        .as_ref()
        .is_some_and(JoinHandle::is_finished);
    if !finished {
        if c.verification.running() {
            ctx.request_repaint_after(std::time::Duration::from_millis(100));
        }
        return;
    }
    let Some(job) = c.verification.job.take() else {
        return;
    };
    let result = job
        .join()
        .unwrap_or_else(|_| Err("the verification worker panicked".into()));
    let secs = c.wall_s - c.verification.started_s;
    let at = Some(("maintenance", c.now().0));
    match &result {
        Ok(Verdict::Cell(r)) => c.say(
            at,
            "say-verified",
            &[
                ("safe", r.safe.to_string()),
                ("states", r.full.states.to_string()),
                ("permissive", r.permissive.to_string()),
            ],
        ),
        Ok(Verdict::Parts(r)) => {
            let (safe, unproved) = parts_verdict(r);
            c.say(
                at,
                "say-verified-parts",
                &[
                    ("verdict", parts_verdict_word(safe, unproved).to_string()),
                    ("parts", r.parts.len().to_string()),
                ],
            );
        }
        Err(e) => c.say(at, "say-verify-failed", &[("error", e.clone())]),
    }
    c.verification.result = Some((result, secs));
    c.verification.reveal = true;
}

/// Replays the shortest hazard trace on the synoptic.
pub(crate) fn replay(c: &mut Console) {
    let report = match &c.verification.result {
        Some((Ok(Verdict::Cell(report)), _)) => report,
        Some((Ok(Verdict::Parts(_)), _)) => {
            c.say(None, "say-no-replay-of-parts", &[]);
            return;
        }
        _ => {
            c.say(None, "say-no-verification", &[]);
            return;
        }
    };
    let Some((kind, trace)) = &report.full.hazard else {
        c.say(None, "say-no-counterexample", &[]);
        return;
    };
    let dir = std::env::temp_dir().join(format!("vigie-counterexample-{}", std::process::id()));
    let plant = std::fs::canonicalize(&c.plant_dir).unwrap_or_else(|_| c.plant_dir.clone());
    let written = verify::scenario::write(
        &dir,
        trace,
        &c.sim.bundle.plant,
        &plant.to_string_lossy(),
        report.geometry.step_us,
    );
    let kind = kind.clone();
    let path = match written {
        Ok(p) => p,
        Err(e) => {
            c.say(
                None,
                "say-counterexample-unwritable",
                &[("error", e.to_string())],
            );
            return;
        }
    };
    match vigie_core::sim::Scenario::load(&path) {
        Ok(scenario) => {
            c.source = Source {
                scenario,
                path,
                plant_exercise: None,
            };
            c.mode = Mode::Production;
            c.draft = None;
            c.compiled_edit = None;
            c.restart(None);
            c.speed = c.speed.min(0.5);
            c.say(None, "say-replaying", &[("kind", kind.to_string())]);
        }
        Err(p) => c.say(
            None,
            "say-counterexample-unreadable",
            &[("error", vigie_core::diag::render(&p))],
        ),
    }
}

/// The verification section of the maintenance side panel.
pub(crate) fn panel_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let pal = c.palette.clone();
    let heading = ui.heading(c.i18n.t("verif-title"));
    if std::mem::take(&mut c.verification.reveal) {
        heading.scroll_to_me(Some(egui::Align::Min));
    }
    ui.horizontal(|ui| {
        let running = c.verification.running();
        if ui
            .add_enabled(!running, egui::Button::new(c.i18n.t("verif-run")))
            .on_hover_text(c.i18n.t("verif-run-hover"))
            .clicked()
        {
            out.push(Command::VerifyConstraints);
        }
        if running {
            ui.spinner();
            let s = format!("{:.0}", c.wall_s - c.verification.started_s);
            ui.label(c.i18n.ta("verif-exploring", &[("s", (&s).into())]));
        }
    });
    let Some((result, secs)) = &c.verification.result else {
        ui.label(c.i18n.t("verif-not-yet"));
        return;
    };
    let r = match result {
        Ok(Verdict::Cell(r)) => r,
        Ok(Verdict::Parts(r)) => {
            parts_ui(&c.i18n, ui, r, *secs, &pal);
            return;
        }
        Err(e) => {
            ui.label(RichText::new(e).color(pal.trip));
            return;
        }
    };
    let i18n = &c.i18n;
    ui.label(i18n.ta(
        "verif-states",
        &[
            ("states", r.full.states.into()),
            ("transitions", r.full.transitions.into()),
            ("s", (&format!("{secs:.1}")).into()),
        ],
    ));
    hazard_ui(i18n, ui, r, &pal, out);
    if r.full.no_fallback.is_some() {
        ui.label(RichText::new(i18n.t("verif-no-fallback")).color(pal.trip));
    }
    deliveries_ui(i18n, ui, r);
    egui::CollapsingHeader::new(i18n.t("verif-invariants"))
        .default_open(false)
        .show(ui, |ui| {
            for i in &r.invariants {
                ui.label(format!(
                    "{} {}: {}",
                    i.id,
                    i.source,
                    i18n.t(if i.proved {
                        "verif-proved"
                    } else {
                        "verif-refuted"
                    })
                ));
            }
        });
    if r.constraints.is_empty() {
        ui.label(i18n.t("verif-necessity-hint"));
        return;
    }
    egui::CollapsingHeader::new(i18n.t("verif-necessity"))
        .default_open(true)
        .show(ui, |ui| {
            egui::Grid::new("necessity").striped(true).show(ui, |ui| {
                for role in &r.constraints {
                    ui.label(RichText::new(&role.id).monospace());
                    if role.necessary {
                        ui.label(i18n.ta(
                            "verif-necessary",
                            &[("hazard", role.hazard.as_deref().unwrap_or("?").into())],
                        ));
                    } else {
                        ui.label(i18n.t("verif-redundant"));
                    }
                    ui.end_row();
                }
            });
        });
}

/// The hazard found (with the kinds and the replay of its counterexample), or safe.
fn hazard_ui(
    i18n: &crate::i18n::I18n,
    ui: &mut egui::Ui,
    r: &VerifyReport,
    pal: &crate::theme::Palette,
    out: &mut Vec<Command>,
) {
    match &r.full.hazard {
        None => {
            ui.label(RichText::new(i18n.t("verif-safe")).strong());
        }
        Some((kind, trace)) => {
            ui.label(
                RichText::new(i18n.ta(
                    "verif-violated",
                    &[
                        ("kind", (&kind.to_string()).into()),
                        ("n", trace.steps.len().into()),
                    ],
                ))
                .strong()
                .color(pal.trip),
            );
            let kinds: Vec<String> = r
                .full
                .hazard_kinds
                .iter()
                .map(|(k, n)| {
                    i18n.ta(
                        "verif-hazard-kind",
                        &[("kind", (&k.to_string()).into()), ("n", (*n).into())],
                    )
                })
                .collect();
            ui.label(i18n.ta("verif-hazards", &[("kinds", (&kinds.join(", ")).into())]));
            if ui
                .button(i18n.t("verif-replay"))
                .on_hover_text(i18n.t("verif-replay-hover"))
                .clicked()
            {
                out.push(Command::ReplayCounterexample);
            }
        }
    }
}

/// Whether each side can be delivered to (always or in some runs), with the steps.
fn deliveries_ui(i18n: &crate::i18n::I18n, ui: &mut egui::Ui, r: &VerifyReport) {
    for (side, id) in ["verif-left", "verif-right"].iter().enumerate() {
        let name = i18n.t(id);
        let text = match (&r.full.delivered[side], r.full.always_deliverable[side]) {
            (None, _) => i18n.ta("verif-no-delivery", &[("side", (&name).into())]),
            (Some(t), always) => i18n.ta(
                if always {
                    "verif-delivery-always"
                } else {
                    "verif-delivery-some"
                },
                &[("side", (&name).into()), ("n", t.steps.len().into())],
            ),
        };
        ui.label(text);
    }
}

/// Whether no modelled sub-plant reaches a hazard with the filter (the environment's
/// own hazards aside), and whether some sub-plant was not verified or not to the end.
fn parts_verdict(r: &ComponentsReport) -> (bool, bool) {
    (r.unsafe_parts().is_empty(), r.unproved())
}

/// The word `say-verified-parts` selects on.
fn parts_verdict_word(safe: bool, unproved: bool) -> &'static str {
    match (safe, unproved) {
        (false, _) => "violated",
        (true, true) => "unproved",
        (true, false) => "safe",
    }
}

/// A sub-plant's hazard in the console's language.
fn sub_hazard_text(i18n: &crate::i18n::I18n, h: &SubHazard) -> String {
    match h {
        SubHazard::EndStop(end) => i18n.ta("verif-sub-end-stop", &[("end", end.into())]),
        SubHazard::OpposedDrives => i18n.t("syn-hazard-opposeddrives"),
        SubHazard::Overflow => i18n.t("syn-hazard-overflow"),
        SubHazard::DryRun => i18n.t("syn-hazard-dryrun"),
        SubHazard::Declared(id) => i18n.ta("verif-sub-declared", &[("id", id.into())]),
        SubHazard::Collision => i18n.t("verif-sub-collision"),
        SubHazard::Dropped => i18n.t("verif-sub-dropped"),
    }
}

/// One sub-plant's verdict with the filter, and whether it is a failure.
fn part_verdict(i18n: &crate::i18n::I18n, p: &SubReport) -> (String, bool) {
    let hazards = |v: &mut dyn Iterator<Item = &SubHazard>| -> String {
        v.map(|h| sub_hazard_text(i18n, h))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(why) = &p.skipped {
        return (i18n.ta("verif-part-skipped", &[("why", why.into())]), true);
    }
    let violated = hazards(&mut p.violated().map(|r| &r.hazard));
    let mut text = if !violated.is_empty() {
        i18n.ta("verif-part-violated", &[("hazards", (&violated).into())])
    } else if p.truncated {
        i18n.t("verif-part-truncated")
    } else {
        i18n.t("verif-part-safe")
    };
    if !p.uncontrollable.is_empty() {
        let env = hazards(&mut p.uncontrollable.iter());
        text.push_str("; ");
        text.push_str(&i18n.ta("verif-part-environment", &[("hazards", (&env).into())]));
    }
    (text, !violated.is_empty() || p.truncated)
}

/// The verdicts of a plant of components, one row per sub-plant.
fn parts_ui(
    i18n: &crate::i18n::I18n,
    ui: &mut egui::Ui,
    r: &ComponentsReport,
    secs: f64,
    pal: &crate::theme::Palette,
) {
    let (safe, unproved) = parts_verdict(r);
    ui.label(i18n.ta(
        "verif-parts",
        &[
            ("parts", r.parts.len().into()),
            ("s", (&format!("{secs:.1}")).into()),
        ],
    ));
    let verdict = RichText::new(i18n.ta(
        "verif-parts-verdict",
        &[("verdict", parts_verdict_word(safe, unproved).into())],
    ))
    .strong();
    ui.label(if safe && !unproved {
        verdict
    } else {
        verdict.color(pal.trip)
    });
    // One line per sub-plant, wrapped to the panel: a long reason must not widen it.
    for p in &r.parts {
        let name = if p.with.is_empty() {
            p.component.clone()
        } else {
            format!("{} (+ {})", p.component, p.with.join(", "))
        };
        let (text, bad) = part_verdict(i18n, p);
        let guarded = if p.constraints.is_empty() {
            i18n.t("verif-part-unguarded")
        } else {
            p.constraints.join(" ")
        };
        ui.horizontal_wrapped(|ui| {
            ui.label(RichText::new(name).monospace());
            let row = ui.label(if bad {
                RichText::new(text).color(pal.trip)
            } else {
                RichText::new(text)
            });
            row.on_hover_text(i18n.ta("verif-part-guarded", &[("by", (&guarded).into())]));
        });
    }
    if !r.not_modelled.is_empty() {
        ui.label(i18n.ta(
            "verif-not-modelled",
            &[("names", (&r.not_modelled.join(", ")).into())],
        ));
    }
    egui::CollapsingHeader::new(i18n.t("verif-assumptions"))
        .default_open(false)
        .show(ui, |ui| {
            for a in &r.assumptions {
                ui.label(format!("• {a}"));
            }
        });
}
