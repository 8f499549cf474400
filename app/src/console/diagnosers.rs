//! The diagnoser view: a banner while a sensor is estimated (degraded mode) or the
//! system is stopped by an actuator partition, and a collapsible table of every
//! component's state estimate, partition decisions and fault flags. Shown only when the
//! simulation runs the diagnosers (a scenario with `diagnosers: true`, or a live link
//! whose run steps them: the mirror's diagnosers follow the run's cycles). Renders, and
//! offers the operator's reset of the flags after a repair (a typed command).

use super::{Command, Console};
use egui::RichText;
use vigie_core::live::config::Mode;
use vigie_core::pop::Certainty;
use vigie_core::sim::OperatorAction;
use vigie_core::sim::diagnosis::hat;

/// The text of the degraded-mode banner, one line per flagged partition (on a monitor
/// link the filter only reports and the PLC reads its own sensors: the lines say so).
pub(crate) fn banner_lines(c: &Console) -> Vec<(String, bool)> {
    let Some(d) = c.sim.diagnosers.as_ref() else {
        return Vec::new();
    };
    let monitor = c.link.as_ref().is_some_and(|l| l.mode == Mode::Monitor);
    let i18n = &c.i18n;
    // A stop on the safe side (the component in doubt between a dead drive and a
    // sensor it cannot estimate) says so, with its candidates: no fault is certain.
    let doubt = |p: &str| {
        d.diagnoses
            .iter()
            .rev()
            .find(|x| x.partition == p)
            .filter(|x| x.certainty == Certainty::Ambiguous)
            .map(|x| (x.component.clone(), x.fault.replace('|', ", ")))
    };
    d.flagged()
        .into_iter()
        .map(|(p, stop, sensor)| match (stop, sensor, monitor) {
            (true, _, _) if let Some((comp, faults)) = doubt(&p) => (
                i18n.ta(
                    if monitor {
                        "diag-doubt-monitor"
                    } else {
                        "diag-doubt-stop"
                    },
                    &[
                        ("comp", (&comp).into()),
                        ("faults", (&faults).into()),
                        ("p", (&p).into()),
                    ],
                ),
                true,
            ),
            (false, Some(s), _) if !vigie_core::sim::diagnosis::has_estimate(d, &s) => {
                (i18n.ta("diag-no-estimate", &[("s", (&s).into())]), false)
            }
            (true, _, false) => (i18n.ta("diag-actuator-stop", &[("p", (&p).into())]), true),
            (true, _, true) => (
                i18n.ta("diag-actuator-monitor", &[("p", (&p).into())]),
                true,
            ),
            (false, Some(s), false) => (
                i18n.ta(
                    "diag-estimated",
                    &[("s", (&s).into()), ("hat", (&hat(&s)).into())],
                ),
                false,
            ),
            (false, Some(s), true) => (
                i18n.ta(
                    "diag-sensor-monitor",
                    &[("s", (&s).into()), ("hat", (&hat(&s)).into())],
                ),
                false,
            ),
            (false, None, _) => (i18n.ta("diag-partition", &[("p", (&p).into())]), false),
        })
        .collect()
}

/// The diagnoser panel (top of the window).
pub(crate) fn panel_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let Some(d) = c.sim.diagnosers.as_ref() else {
        return;
    };
    egui::Panel::top("diagnosers").show(ui, |ui| {
        let lines = banner_lines(c);
        for (line, stop) in &lines {
            let color = if *stop {
                c.palette.trip
            } else {
                c.palette.alarm
            };
            ui.label(RichText::new(line).strong().color(color));
        }
        // Seed 004, section 7: the operator's eyes lift the doubt.
        doubt_questions_ui(c, ui, out);
        for conclusion in c.sim.doubt_answers().values() {
            ui.label(
                RichText::new(
                    c.i18n
                        .ta("diag-answer", &[("conclusion", conclusion.into())]),
                )
                .strong(),
            );
        }
        if !lines.is_empty()
            && ui
                .button(c.i18n.t("diag-reset"))
                .on_hover_text(c.i18n.t("diag-reset-hover"))
                .clicked()
        {
            out.push(Command::Plant(OperatorAction::ResetDiagnosers));
        }
        let doubts = d
            .diagnoses
            .iter()
            .filter(|x| x.certainty == Certainty::Ambiguous)
            .count();
        egui::CollapsingHeader::new(if doubts == 0 {
            c.i18n.ta("diag-table", &[("n", d.diagnoses.len().into())])
        } else {
            c.i18n.ta(
                "diag-table-doubts",
                &[
                    ("n", (d.diagnoses.len() - doubts).into()),
                    ("doubts", doubts.into()),
                ],
            )
        })
        .id_salt("diagnosers-table")
        .show(ui, |ui| {
            diagnosers_grid_ui(c, ui, d);
        });
    });
}

/// The doubts the operator's eyes can lift: each question with its two answers.
fn doubt_questions_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    for q in c.sim.doubt_questions() {
        egui::Frame::group(ui.style())
            .stroke(egui::Stroke::new(2.0, c.palette.highlight))
            .show(ui, |ui| {
                ui.horizontal_wrapped(|ui| {
                    ui.label(
                        RichText::new(
                            c.i18n
                                .ta("diag-question", &[("question", (&q.question).into())]),
                        )
                        .strong(),
                    );
                    for (item, id) in [(true, "diag-item-there"), (false, "diag-no-item")] {
                        if ui
                            .button(c.i18n.ta(id, &[("sensor", (&q.sensor).into())]))
                            .clicked()
                        {
                            out.push(Command::Plant(OperatorAction::AnswerDoubt {
                                component: q.component.clone(),
                                sensor: q.sensor.clone(),
                                item,
                            }));
                        }
                    }
                });
            });
    }
}

/// The diagnosers' table: each component with its estimate and its decisions.
fn diagnosers_grid_ui(c: &Console, ui: &mut egui::Ui, d: &vigie_core::pop::Diagnosers) {
    egui::Grid::new("diagnosers-grid")
        .striped(true)
        .show(ui, |ui| {
            ui.strong(c.i18n.t("diag-component"));
            ui.strong(c.i18n.t("diag-estimate"));
            ui.strong(c.i18n.t("diag-decisions"));

            ui.end_row();
            let decisions = d.decisions();
            for comp in &d.compiled.components {
                ui.label(&comp.id);
                let est = d.estimate(&comp.id);
                let shown: Vec<&str> = est.iter().take(4).map(String::as_str).collect();
                let more = est.len().saturating_sub(shown.len());
                ui.label(if more > 0 {
                    format!("{} (+{more})", shown.join(", "))
                } else {
                    shown.join(", ")
                });
                ui.horizontal(|ui| {
                    for (_, p, dec) in decisions.iter().filter(|(cid, _, _)| *cid == comp.id) {
                        let (text, color) = match dec.certainty {
                            Certainty::Normal => (format!("{p}: N"), None),
                            Certainty::Ambiguous => (
                                format!("{p}: {{N, {}}}", dec.faults.join(", ")),
                                Some(c.palette.alarm),
                            ),
                            Certainty::Certain => (
                                format!("{p}: {} def_{p}", dec.faults.join("|")),
                                Some(c.palette.trip),
                            ),
                        };
                        let mut t = RichText::new(text);
                        if let Some(col) = color {
                            t = t.color(col).strong();
                        }
                        ui.label(t);
                    }
                });
                ui.end_row();
            }
        });
}
