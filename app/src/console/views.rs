//! The views: each `*_ui` function renders one part of the console from its state and
//! pushes [`Command`]s; none of them changes the simulation.

use super::synoptic::{self, Geometry, Picture};
use super::{ALARMS_PER_PAGE, Command, Console, Mode, ShelveForm};
use egui::{Align2, Color32, FontId, RichText, Sense, Stroke, pos2, vec2};
use std::collections::{BTreeMap, BTreeSet};
use vigie_core::access::Permission;
use vigie_core::alarms::{AlarmKind, AlarmPriority, AlarmState};
use vigie_core::sim::{OperatorAction, PlantState};
use vigie_core::time::Millis;

/// The messages of the explanation's levels (`LEVEL_NAMES`, in the language shown).
const LEVEL_IDS: [&str; 5] = ["level-0", "level-1", "level-2", "level-3", "level-4"];

/// The whole console.
pub(crate) fn root_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let bg = c.palette.background;
    egui::Panel::top("toolbar")
        .frame(egui::Frame::side_top_panel(ui.style()).fill(c.palette.panel))
        .show(ui, |ui| toolbar_ui(c, ui, out));
    unprotected_ui(c, ui);
    bypass_banner_ui(c, ui, out);
    login_ui(c, ui, out);
    reinit_confirm_ui(c, ui, out);
    manual_confirm_ui(c, ui, out);
    // Below the toolbar: the degraded-mode banner and the diagnosers' table.
    super::diagnosers::panel_ui(c, ui, out);
    egui::Panel::bottom("status").show(ui, |ui| status_ui(c, ui));
    egui::Panel::bottom("chronogram")
        .resizable(true)
        .default_size(210.0)
        .min_size(120.0)
        .show(ui, |ui| chronogram_ui(c, ui, out));
    egui::Panel::right("side")
        .resizable(true)
        .default_size(if c.mode == Mode::Maintenance {
            440.0
        } else {
            470.0
        })
        .min_size(320.0)
        .show(ui, |ui| {
            super::link::panel_ui(c, ui);
            egui::ScrollArea::vertical()
                .auto_shrink([false, false])
                .show(ui, |ui| match c.mode {
                    Mode::Production => {
                        manual_ui(c, ui, out);
                        explanation_ui(c, ui, out);
                        ui.separator();
                        alarms_ui(c, ui, out);
                        ui.separator();
                        journal_ui(c, ui, out);
                    }
                    Mode::Maintenance => {
                        bypass_form_ui(c, ui, out);
                        ui.separator();
                        explanation_ui(c, ui, out);
                        ui.separator();
                        alarms_ui(c, ui, out);
                        ui.separator();
                        super::verification::panel_ui(c, ui, out);
                    }
                    // The paper's protocol: the stopped plant and its explanation
                    // first, the exercise's tools below.
                    Mode::Training => {
                        explanation_ui(c, ui, out);
                        ui.separator();
                        training_ui(c, ui, out);
                        ui.separator();
                        alarms_ui(c, ui, out);
                    }
                });
        });
    egui::CentralPanel::default()
        .frame(egui::Frame::NONE.fill(bg))
        .show(ui, |ui| {
            if c.mode == Mode::Maintenance {
                maintenance_ui(c, ui, out);
                return;
            }
            // Wrapped: a plant's areas (in French, long names) may not fit in one row.
            ui.horizontal_wrapped(|ui| {
                ui.add_space(6.0);
                if ui
                    .add(egui::Button::selectable(
                        !c.trends.shown,
                        c.i18n.t("tab-synoptic"),
                    ))
                    .clicked()
                {
                    c.trends.shown = false;
                }
                if ui
                    .add(egui::Button::selectable(
                        c.trends.shown,
                        c.i18n.t("tab-trends"),
                    ))
                    .on_hover_text(c.i18n.t("tab-trends-hover"))
                    .clicked()
                {
                    c.trends.shown = true;
                }
                if !c.trends.shown {
                    areas_ui(c, ui);
                }
            });
            if c.trends.shown {
                super::trends::trends_ui(c, ui, out);
            } else {
                synoptic_panel_ui(c, ui);
            }
        });
}

/// The areas to flag: those of the trip's signals (its constraints' literals) while the
/// plant is stopped, and of the suspect or estimated sensors.
fn flagged_areas(c: &Console) -> BTreeSet<String> {
    let plant = &c.sim.bundle.plant;
    let mut marked: BTreeSet<String> = BTreeSet::new();
    if c.view.areas.is_none() {
        return marked;
    }
    if c.sim.engine.is_tripped()
        && let Some(t) = c.sim.engine.trips.last()
    {
        for k in &t.constraints {
            marked.extend(k.literals.iter().map(|l| l.name.clone()));
        }
    }
    marked.extend(c.sim.live_marks().into_iter().map(|h| h.element));
    plant
        .inputs
        .iter()
        .chain(&plant.outputs)
        .filter(|s| marked.contains(&s.id))
        .map(|s| s.element.clone())
        .collect()
}

/// A plant of many components in several areas: one button for the whole plant and
/// one per area (ISA-101's unit displays), the area of a marked signal (a trip's
/// constraint, a suspect sensor) flagged.
fn areas_ui(c: &mut Console, ui: &mut egui::Ui) {
    let Some(areas) = &c.view.areas else {
        return;
    };
    let flagged = flagged_areas(c);
    ui.separator();
    let mut chosen = None;
    if ui
        .add(egui::Button::selectable(
            c.view.area.is_none(),
            c.i18n.t("synoptic-whole-plant"),
        ))
        .on_hover_text(c.i18n.t("synoptic-area-hover"))
        .clicked()
    {
        chosen = Some(None);
    }
    for (area, _) in areas {
        let name = c.view.elements.get(area).unwrap_or(area);
        let text = if flagged.contains(area) {
            RichText::new(format!("⚠ {name}"))
                .color(c.palette.trip)
                .strong()
        } else {
            RichText::new(name.as_str())
        };
        if ui
            .add(egui::Button::selectable(
                c.view.area.as_ref() == Some(area),
                text,
            ))
            .on_hover_text(c.i18n.t("synoptic-area-hover"))
            .clicked()
        {
            chosen = Some(Some(area.clone()));
        }
    }
    if let Some(a) = chosen
        && a != c.view.area
    {
        c.view.area = a;
        c.view.zoom = 1.0;
        c.view.pan = egui::Vec2::ZERO;
    }
}

/// The red banner under the toolbar while no safety constraint protects the plant
/// (`V0110`: `constraints.txt` absent, empty or rejected); its hover text is the warning.
fn unprotected_ui(c: &Console, ui: &mut egui::Ui) {
    let Some(warning) = c.sim.bundle.unprotected() else {
        return;
    };
    egui::Panel::top("unprotected")
        .frame(egui::Frame::side_top_panel(ui.style()).fill(c.palette.trip))
        .show(ui, |ui| {
            ui.label(
                RichText::new(c.i18n.t("unprotected-banner"))
                    .strong()
                    .size(16.0)
                    .color(Color32::WHITE),
            )
            .on_hover_text(warning.to_string());
        });
}

/// FR | EN: the language of the console, switched at once.
pub(crate) fn lang_switch_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    for l in crate::i18n::Lang::ALL {
        let r = ui
            .add(egui::Button::selectable(c.i18n.lang() == l, l.label()).small())
            .on_hover_text(c.i18n.t("lang-switch-hover"));
        if r.clicked() && c.i18n.lang() != l {
            out.push(Command::SetLanguage(l));
        }
    }
}

fn toolbar_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    ui.horizontal_wrapped(|ui| {
        if super::link::toolbar_ui(c, ui, out) {
            return;
        }
        ui.label(RichText::new("VIGIE").strong().size(18.0));
        lang_switch_ui(c, ui, out);
        plant_picker_ui(c, ui, out);
        ui.separator();
        // First, so that it is never pushed off a narrow screen.
        state_ui(c, ui);
        ui.separator();
        for (m, id) in [
            (Mode::Production, "mode-production"),
            (Mode::Maintenance, "mode-maintenance"),
            (Mode::Training, "mode-training"),
        ] {
            let allowed = m != Mode::Maintenance || c.may(Permission::EditProgram);
            let r = ui.add_enabled(allowed, egui::Button::selectable(c.mode == m, c.i18n.t(id)));
            let r = r.on_disabled_hover_text(c.i18n.t("mode-maintenance-needs-role"));
            if r.clicked() && c.mode != m {
                out.push(Command::SetMode(m));
            }
        }
        ui.separator();
        sim_controls_ui(c, ui, out);
        ui.separator();
        plant_buttons_ui(c, ui, out);
        ui.separator();
        match &c.user {
            Some(u) => {
                ui.label(format!("{u} · {}", c.role.name()));
                if ui.button(c.i18n.t("logout")).clicked() {
                    out.push(Command::Logout);
                }
            }
            None => {
                if ui
                    .button(c.i18n.t("login"))
                    .on_hover_text(c.i18n.t("login-hover"))
                    .clicked()
                {
                    c.login = Some((String::new(), String::new()));
                }
            }
        }
    });
}

/// The plant picker: the plant folders beside this one (none to pick from alone).
fn plant_picker_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    if c.plants.len() < 2 {
        return;
    }
    let current = &c.sim.bundle.plant.name;
    let r = egui::ComboBox::from_id_salt("plant-picker")
        .selected_text(current)
        .show_ui(ui, |ui| {
            for (dir, name) in &c.plants {
                if ui.selectable_label(name == current, name).clicked() && name != current {
                    out.push(Command::OpenPlant(dir.clone()));
                }
            }
        })
        .response;
    // Named by the plant shown, as a person reads it.
    r.widget_info(|| egui::WidgetInfo::labeled(egui::Role::ComboBox, true, current));
    r.on_hover_text(c.i18n.t("plant-picker-hover"));
}

/// The toolbar's simulation controls: run or pause, step, speed and the time.
fn sim_controls_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    if c.running {
        if ui.button(c.i18n.t("sim-pause")).clicked() {
            out.push(Command::Pause);
        }
    } else if ui.button(c.i18n.t("sim-run")).clicked() {
        out.push(Command::Run);
    }
    if ui
        .button(c.i18n.t("sim-step"))
        .on_hover_text(c.i18n.t("sim-step-hover"))
        .clicked()
    {
        out.push(Command::Step);
    }
    let mut speed = c.speed;
    let r = ui.add(
        egui::Slider::new(&mut speed, 0.1..=100.0)
            .logarithmic(true)
            .suffix("x")
            .text(c.i18n.t("sim-speed")),
    );
    if r.changed() {
        out.push(Command::SetSpeed(speed));
    }
    ui.separator();
    ui.add(
        egui::Label::new(format!("t = {}", fmt_ms(c.sim.now().0)))
            .wrap_mode(egui::TextWrapMode::Extend),
    );
}

/// The toolbar's plant buttons: start, stop, manual mode, reset and re-initialisation.
fn plant_buttons_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    if ui
        .button(c.i18n.t("plant-start"))
        .on_hover_text(c.i18n.t("plant-start-hover"))
        .clicked()
    {
        out.push(Command::Plant(OperatorAction::Start));
    }
    if ui
        .button(c.i18n.t("plant-stop"))
        .on_hover_text(c.i18n.t("plant-stop-hover"))
        .clicked()
    {
        out.push(Command::Plant(OperatorAction::Stop));
    }
    if c.sim.manual_outputs().is_some() {
        if ui
            .button(c.i18n.t("manual-leave"))
            .on_hover_text(c.i18n.t("manual-leave-hover"))
            .clicked()
        {
            out.push(Command::Plant(OperatorAction::Manual(false)));
        }
    } else if ui
        .add_enabled(
            c.link.is_none() && !c.sim.engine.is_tripped(),
            egui::Button::new(c.i18n.t("manual-enter")),
        )
        .on_hover_text(c.i18n.t("manual-enter-hover"))
        .on_disabled_hover_text(c.i18n.t("manual-enter-disabled-hover"))
        .clicked()
    {
        c.manual_confirm = true;
    }
    let tripped = c.sim.engine.is_tripped();
    reset_button_ui(c, ui, "reset-hover", out);
    // The reset was refused since the trip: the re-initialisation is the next step,
    // shown in the alarm colour.
    let refused = tripped
        && c.sim
            .journal()
            .iter()
            .rev()
            .find(|e| matches!(e.kind.as_str(), "trip" | "reset" | "reset_refused"))
            .is_some_and(|e| e.kind == "reset_refused");
    let reinit = if refused {
        egui::Button::new(RichText::new(c.i18n.t("reinit")).color(Color32::BLACK))
            .fill(c.palette.alarm)
    } else {
        egui::Button::new(c.i18n.t("reinit"))
    };
    if ui
        .add_enabled(tripped && c.link.is_none(), reinit)
        .on_hover_text(c.i18n.t("reinit-hover"))
        .on_disabled_hover_text(c.i18n.t("reinit-disabled-hover"))
        .clicked()
    {
        c.reinit_confirm = true;
    }
}

/// The login dialog: name and password (hidden), checked against the accounts of the
/// data folder (`vigie user add`).
fn login_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let no_accounts = c.users.accounts.is_empty();
    let Some((name, password)) = c.login.as_mut() else {
        return;
    };
    let mut close = false;
    let mut enter = false;
    let modal = egui::Modal::new(egui::Id::unique("login")).show(ui.ctx(), |ui| {
        ui.set_min_width(360.0);
        ui.set_max_width(380.0);
        ui.heading(c.i18n.t("login-title"));
        if no_accounts {
            ui.label(c.i18n.t("login-no-accounts"));
        }
        egui::Grid::new("login_grid").show(ui, |ui| {
            let l = ui.label(c.i18n.t("login-user"));
            ui.add(egui::TextEdit::singleline(name).min_size(vec2(180.0, 0.0)))
                .labelled_by(l.id);
            ui.end_row();
            let l = ui.label(c.i18n.t("login-password"));
            let r = ui
                .add(
                    egui::TextEdit::singleline(password)
                        .password(true)
                        .min_size(vec2(180.0, 0.0)),
                )
                .labelled_by(l.id);
            // Enter in the password field logs in.
            enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            ui.end_row();
        });
        ui.horizontal(|ui| {
            if ui.button(c.i18n.t("login-submit")).clicked() || enter {
                out.push(Command::Login {
                    name: name.clone(),
                    password: std::mem::take(password),
                });
            }
            if ui.button(c.i18n.t("cancel")).clicked() {
                close = true;
            }
        });
    });
    if close || modal.should_close() {
        c.login = None;
    }
}

/// While a constraint is bypassed: a banner on every screen, what is not enforced, until
/// when, why and by whom, with its end at hand.
fn bypass_banner_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let bypasses = c.sim.bypasses();
    if bypasses.is_empty() {
        return;
    }
    let now = c.sim.now();
    egui::Panel::top("bypass_banner")
        .frame(egui::Frame::side_top_panel(ui.style()).fill(c.palette.alarm))
        .show(ui, |ui| {
            for (id, b) in bypasses {
                ui.horizontal_wrapped(|ui| {
                    let what = c
                        .sim
                        .bundle
                        .constraints
                        .get(id)
                        .map(|k| {
                            c.i18n
                                .plant(&format!("constraint-{}", k.id))
                                .unwrap_or_else(|| k.description.clone())
                        })
                        .filter(|d| !d.is_empty())
                        .map_or(String::new(), |d| format!(" ({d})"));
                    let left_s = b.until.0.saturating_sub(now.0) / 1000;
                    let until = fmt_ms(b.until.0);
                    ui.label(
                        RichText::new(c.i18n.ta(
                            "bypass-banner",
                            &[
                                ("id", id.into()),
                                ("what", (&what).into()),
                                ("until", (&until).into()),
                                ("min", (left_s / 60).into()),
                                ("s", (left_s % 60).into()),
                                ("by", (&b.by).into()),
                                ("reason", (&b.reason).into()),
                            ],
                        ))
                        .strong()
                        .color(Color32::BLACK),
                    );
                    if ui
                        .button(c.i18n.ta("bypass-end", &[("id", id.into())]))
                        .clicked()
                    {
                        out.push(Command::Plant(OperatorAction::EndBypass(id.clone())));
                    }
                });
            }
        });
}

/// Maintenance: bypass one constraint for a limited time, with a reason.
fn bypass_form_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    ui.heading(c.i18n.t("bypass-title"));
    if !c.may(Permission::BypassConstraint) {
        ui.label(RichText::new(c.i18n.t("bypass-needs-role")).color(c.palette.text_dim));
        return;
    }
    let ids: Vec<String> = c
        .sim
        .bundle
        .constraints
        .constraints
        .iter()
        .map(|k| k.id.clone())
        .filter(|id| !id.starts_with("DSTOP_") && !c.sim.bypasses().contains_key(id))
        .collect();
    let form = &mut c.bypass_form;
    if !ids.contains(&form.0) {
        form.0 = ids.first().cloned().unwrap_or_default();
    }
    ui.horizontal_wrapped(|ui| {
        egui::ComboBox::from_id_salt("bypass_constraint")
            .selected_text(form.0.clone())
            .show_ui(ui, |ui| {
                for id in &ids {
                    ui.selectable_value(&mut form.0, id.clone(), id);
                }
            });
        egui::ComboBox::from_id_salt("bypass_minutes")
            .selected_text(format!("{} min", form.2))
            .show_ui(ui, |ui| {
                for m in [15, 30, 60, 240, 480] {
                    ui.selectable_value(&mut form.2, m, format!("{m} min"));
                }
            });
        let l = ui.label(c.i18n.t("bypass-reason"));
        ui.add(egui::TextEdit::singleline(&mut form.1).desired_width(160.0))
            .labelled_by(l.id);
        if ui
            .add_enabled(
                !form.0.is_empty(),
                egui::Button::new(c.i18n.t("bypass-now")),
            )
            .on_hover_text(c.i18n.t("bypass-now-hover"))
            .clicked()
        {
            out.push(Command::Plant(OperatorAction::Bypass {
                constraint: form.0.clone(),
                minutes: form.2,
                reason: form.1.clone(),
                by: c.user.clone().unwrap_or_else(|| c.role.name().to_string()),
            }));
        }
    });
    if let Some(k) = c.sim.bundle.constraints.get(&c.bypass_form.0) {
        ui.label(
            RichText::new(format!(
                "{} = {}: {}",
                k.id,
                k.source,
                c.i18n
                    .plant(&format!("constraint-{}", k.id))
                    .unwrap_or_else(|| k.description.clone())
            ))
            .color(c.palette.text_dim),
        );
    }
}

/// The plant's state, unmistakable from across the room (large, coloured only when
/// abnormal or running), the simulation's pause, and the unacknowledged alarms.
fn state_ui(c: &Console, ui: &mut egui::Ui) {
    let (id, bg, fg) = match c.sim.plant_state() {
        PlantState::Tripped => ("state-tripped", c.palette.trip, Color32::WHITE),
        PlantState::Stopped => ("state-stopped", c.palette.alarm, Color32::BLACK),
        PlantState::Manual => ("state-manual", c.palette.highlight, Color32::WHITE),
        PlantState::Degraded => ("state-degraded", c.palette.caution, Color32::BLACK),
        PlantState::Idle => ("state-idle", c.palette.equipment, Color32::BLACK),
        PlantState::Running => ("state-running", c.palette.normal, Color32::WHITE),
    };
    let txt = c.i18n.t(id);
    egui::Frame::new()
        .fill(bg)
        .inner_margin(egui::Margin::symmetric(10, 2))
        .corner_radius(3.0)
        .show(ui, |ui| {
            // Never wrapped: on a crowded toolbar the badge moves to the next row whole.
            ui.add(
                egui::Label::new(RichText::new(txt).strong().size(22.0).color(fg))
                    .wrap_mode(egui::TextWrapMode::Extend),
            )
        })
        .inner
        .on_hover_text(c.i18n.t(&format!("{id}-hover")));
    if !c.running {
        ui.label(
            RichText::new(c.i18n.t("state-paused"))
                .strong()
                .color(Color32::WHITE)
                .background_color(c.palette.highlight),
        );
    }
    let unack = c.sim.alarms.unacknowledged();
    if unack > 0 {
        ui.add(
            egui::Label::new(
                RichText::new(c.i18n.ta("state-unacknowledged", &[("n", unack.into())]))
                    .strong()
                    .color(Color32::BLACK)
                    .background_color(c.palette.alarm),
            )
            .wrap_mode(egui::TextWrapMode::Extend),
        );
    }
}

/// Entering manual mode is deliberate: what it does, confirmed.
fn manual_confirm_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    if !c.manual_confirm {
        return;
    }
    let modal = egui::Modal::new(egui::Id::unique("manual_confirm")).show(ui.ctx(), |ui| {
        ui.set_max_width(460.0);
        ui.heading(c.i18n.t("manual-confirm-title"));
        ui.label(c.i18n.t("manual-confirm-text"));
        ui.horizontal(|ui| {
            if ui.button(c.i18n.t("manual-confirm-enter")).clicked() {
                out.push(Command::Plant(OperatorAction::Manual(true)));
                c.manual_confirm = false;
            }
            if ui.button(c.i18n.t("cancel")).clicked() {
                c.manual_confirm = false;
            }
        });
    });
    if modal.should_close() {
        c.manual_confirm = false;
    }
}

/// Manual mode: each actuator with its state, ON / OFF and Jog (ON while held); the
/// last refusal in operator terms.
fn manual_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let Some(requested) = c.sim.manual_outputs().cloned() else {
        c.jogging.clear();
        return;
    };
    ui.heading(c.i18n.t("manual-title"));
    ui.label(RichText::new(c.i18n.t("manual-note")).color(c.palette.text_dim));
    let outputs: Vec<(usize, String, String)> = c
        .sim
        .bundle
        .plant
        .outputs
        .iter()
        .enumerate()
        .map(|(k, s)| (k, s.id.clone(), s.element.clone()))
        .collect();
    egui::Grid::new("manual_grid").striped(true).show(ui, |ui| {
        for (k, id, element) in outputs {
            let on = requested.get(k);
            ui.label(RichText::new(&id).strong());
            ui.label(
                RichText::new(super::words::element(&c.i18n, &element)).color(c.palette.text_dim),
            );
            ui.label(c.i18n.t(if on { "manual-on" } else { "manual-off" }));
            if ui
                .add_enabled(
                    !on,
                    egui::Button::new(c.i18n.ta("manual-set-on", &[("id", (&id).into())])),
                )
                .clicked()
            {
                out.push(Command::Plant(OperatorAction::ManualSet(id.clone(), true)));
            }
            if ui
                .add_enabled(
                    on,
                    egui::Button::new(c.i18n.ta("manual-set-off", &[("id", (&id).into())])),
                )
                .clicked()
            {
                out.push(Command::Plant(OperatorAction::ManualSet(id.clone(), false)));
            }
            let jog = ui
                .add(
                    egui::Button::new(c.i18n.ta("manual-jog", &[("id", (&id).into())]))
                        .sense(Sense::click_and_drag()),
                )
                .on_hover_text(c.i18n.t("manual-jog-hover"));
            let held = jog.is_pointer_button_down_on();
            if held && !c.jogging.contains(&id) && !on {
                c.jogging.insert(id.clone());
                out.push(Command::Plant(OperatorAction::ManualSet(id.clone(), true)));
            } else if !held && c.jogging.remove(&id) {
                out.push(Command::Plant(OperatorAction::ManualSet(id.clone(), false)));
            }
            ui.end_row();
        }
    });
    // Below the buttons, so that they do not move under the operator's pointer.
    if let Some(r) = &c.manual_refusal {
        egui::Frame::group(ui.style())
            .stroke(Stroke::new(2.0, c.palette.trip))
            .show(ui, |ui| {
                ui.label(RichText::new(r).color(c.palette.trip));
            });
    }
}

/// The re-initialisation's confirmation: what to check on the plant first, and what it
/// does.
fn reinit_confirm_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    if !c.reinit_confirm {
        return;
    }
    if !c.sim.engine.is_tripped() {
        c.reinit_confirm = false;
        return;
    }
    let modal = egui::Modal::new(egui::Id::unique("reinit_confirm")).show(ui.ctx(), |ui| {
        ui.set_max_width(460.0);
        ui.heading(c.i18n.t("reinit-title"));
        ui.label(c.i18n.t("reinit-text"));
        ui.label(c.i18n.t("reinit-empty-first"));
        ui.weak(c.i18n.t("reinit-emulator"));
        ui.label(c.i18n.t("reinit-leave-in-place"));
        ui.horizontal(|ui| {
            if ui.button(c.i18n.t("reinit-emptied")).clicked() {
                out.push(Command::Plant(OperatorAction::Reinitialise {
                    emptied: true,
                }));
                c.reinit_confirm = false;
            }
            if ui.button(c.i18n.t("reinit-items-left")).clicked() {
                out.push(Command::Plant(OperatorAction::Reinitialise {
                    emptied: false,
                }));
                c.reinit_confirm = false;
            }
            if ui.button(c.i18n.t("cancel")).clicked() {
                c.reinit_confirm = false;
            }
        });
    });
    if modal.should_close() {
        c.reinit_confirm = false;
    }
}

fn status_ui(c: &Console, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        if super::link::status_ui(c, ui) {
            return;
        }
        if c.sim.layout.is_none() {
            // A plant of components: its elementary actions, not boxes.
            let events = c.sim.action_events();
            let faults = events.iter().filter(|e| e.is_fault()).count();
            ui.label(c.i18n.ta(
                "status-actions",
                &[
                    ("scenario", (&c.source.title(&c.i18n)).into()),
                    ("done", (events.len() - faults).into()),
                    ("faults", faults.into()),
                ],
            ));
            if let Some(p) = c.sim.emulator.as_components().filter(|p| p.carries_items()) {
                ui.separator();
                ui.label(c.i18n.ta(
                    "status-items",
                    &[
                        ("placed", p.items_in().into()),
                        ("out", p.items_out().into()),
                    ],
                ));
            }
            ui.separator();
            if !c.status.is_empty() {
                ui.label(RichText::new(&c.status).strong());
            }
            return;
        }
        let s = c.sim.emulator.stats();
        let removed = if s.removed > 0 {
            c.i18n.ta("status-removed", &[("n", s.removed.into())])
        } else {
            String::new()
        };
        ui.label(c.i18n.ta(
            "status-boxes",
            &[
                ("scenario", (&c.source.title(&c.i18n)).into()),
                ("created", s.created.into()),
                ("delivered", s.delivered_total().into()),
                ("damaged", s.damaged.into()),
                ("removed", (&removed).into()),
            ],
        ));

        ui.separator();
        if !c.status.is_empty() {
            ui.label(RichText::new(&c.status).strong());
        }
        if let Some(e) = &c.journal.error {
            ui.label(RichText::new(e).color(c.palette.trip));
        }
    });
}

/// Builds the values, boxes and marks to draw, then paints the synoptic.
fn synoptic_panel_ui(c: &mut Console, ui: &mut egui::Ui) {
    let sim = &c.sim;
    let plant = &sim.bundle.plant;
    let mut values: BTreeMap<String, bool> = BTreeMap::new();
    let mut forced = BTreeSet::new();
    let live_boxes = sim.emulator.boxes();
    let mut boxes: &[vigie_core::emulator::BoxView] = &live_boxes;
    let mut angle = sim.emulator.table_angle_mdeg();
    let mut live_scene = sim.emulator.scene();
    let mut time_ms = sim.now().0;
    let mut banner = None;
    let replay_rec = c.replay.and_then(|t| sim.engine.history.at(Millis(t)));
    let level = c
        .level
        .zip(c.latest_trip())
        .and_then(|(l, t)| sim.explanations.get(&t).map(|ex| (l, t, ex)));
    // The picture's time: replay, the trip (levels 2-4) or now.
    let picture_time = match (&replay_rec, &level) {
        (Some(r), _) => Some(r.time.0),
        (None, Some((l, _, ex))) if *l >= 2 => Some(ex.time_ms),
        _ => None,
    };
    let record = picture_time
        .and_then(|t| sim.engine.history.at(Millis(t)))
        .or_else(|| sim.engine.history.last());
    if let Some(r) = record {
        for (i, s) in plant.inputs.iter().enumerate() {
            values.insert(s.id.clone(), r.inputs.get(i));
        }
        for (i, s) in plant.outputs.iter().enumerate() {
            values.insert(s.id.clone(), r.applied.get(i));
            if r.tripped && r.applied.get(i) != r.commanded.get(i) {
                forced.insert(s.id.clone());
            }
        }
    }
    if let Some(t) = picture_time {
        let snaps = sim.snapshots();
        let i = snaps
            .partition_point(|s| s.time.0 < t)
            .min(snaps.len().saturating_sub(1));
        if let Some(s) = snaps.get(i) {
            boxes = &s.boxes;
            angle = s.table_angle_mdeg;
            if let Some(c) = sim.emulator.as_components() {
                live_scene = Some(c.scene_at(&s.positions));
            }
            time_ms = s.time.0;
        }
    }
    // No level shown, live: the estimated and suspect sensors are marked.
    let live_marks = if level.is_none() && replay_rec.is_none() {
        sim.live_marks()
    } else {
        Vec::new()
    };
    let mut highlights: &[vigie_core::explain::Highlight] = &live_marks;
    let mut ghost = None;
    let mut ghost_scene = None;
    if let Some((l, t, ex)) = &level {
        let lv = ex.levels()[*l];
        for (k, v) in &lv.state {
            values.insert(k.clone(), *v);
        }
        highlights = &lv.highlights;
        if *l == 1
            && let Some(p) = sim.projections.get(t)
        {
            ghost = Some((p.boxes.as_slice(), p.table_angle_mdeg, p.hazards.as_slice()));
            ghost_scene = p.scene.as_ref();
        }
        banner = Some(level_banner(c, *l, ex));
    }
    if let Some(r) = &replay_rec {
        banner = Some((
            c.i18n.ta(
                "banner-replay",
                &[
                    ("time", (&fmt_ms(r.time.0)).into()),
                    ("now", (&fmt_ms(sim.now().0)).into()),
                ],
            ),
            c.palette.highlight,
        ));
    } else if banner.is_none() && sim.engine.is_tripped() {
        banner = Some(trip_banner(c));
    }
    let geom = geometry(c, live_scene.as_ref(), angle);
    let flagged = flagged_areas(c);
    let pic = Picture {
        flagged: &flagged,
        boxes,
        values: &values,
        forced: &forced,
        time_ms,
        highlights,
        ghost,
        banner,
        ghost_scene,
    };
    let resp = synoptic::synoptic_ui(ui, &mut c.view, &geom, angle, &pic, &c.palette, plant);
    c.synoptic_rect = Some(resp.rect);
    open_clicked_area(c, &resp);
}

/// The overview: a click on an area's block opens it.
fn open_clicked_area(c: &mut Console, resp: &egui::Response) {
    if resp.clicked()
        && let Some(p) = resp.interact_pointer_pos()
        && let Some((area, _)) = c.view.placed.frames.iter().find(|(_, r)| r.contains(p))
        && !area.is_empty()
    {
        c.view.area = Some(area.clone());
        c.view.zoom = 1.0;
        c.view.pan = egui::Vec2::ZERO;
    }
}

/// The synoptic's geometry: the station's layout, or the components of the area shown
/// (the whole plant when none).
fn geometry(c: &Console, scene: Option<&vigie_core::machine::Scene>, angle: i32) -> Geometry {
    let plant = &c.sim.bundle.plant;
    match (&c.sim.layout, scene) {
        (Some(layout), _) => Geometry::new(layout, plant, angle),
        (None, Some(scene)) => {
            let Some(areas) = &c.view.areas else {
                return Geometry::from_scene(scene, plant);
            };
            match c
                .view
                .area
                .as_ref()
                .and_then(|a| areas.iter().find(|x| &x.0 == a))
            {
                Some((area, ids)) => {
                    let (scene, part) = synoptic::scene::area_view(scene, plant, area, ids);
                    Geometry::from_scene(&scene, &part)
                }
                None => Geometry::overview(scene, plant, areas),
            }
        }
        (None, None) => Geometry::from_scene(&vigie_core::machine::Scene::default(), plant),
    }
}

/// The banner of an explanation level: the level, the constraints and the time.
fn level_banner(c: &Console, l: usize, ex: &vigie_core::explain::Explanation) -> (String, Color32) {
    let ids = ex
        .constraints
        .iter()
        .map(|k| k.split(" =").next().unwrap_or(k))
        .collect::<Vec<_>>()
        .join(", ");
    (
        c.i18n.ta(
            "banner-level",
            &[
                ("level", (&c.i18n.t(LEVEL_IDS[l])).into()),
                ("ids", (&ids).into()),
                ("time", (&fmt_ms(ex.time_ms)).into()),
            ],
        ),
        c.palette.highlight,
    )
}

/// The banner of a trip: the constraints that tripped.
fn trip_banner(c: &Console) -> (String, Color32) {
    let sim = &c.sim;
    let ids: Vec<String> = sim
        .engine
        .trips
        .last()
        .map(|t| t.constraints.iter().map(|c| c.id.clone()).collect())
        .unwrap_or_default();
    (
        c.i18n
            .ta("banner-trip", &[("ids", (&ids.join(", ")).into())]),
        c.palette.trip,
    )
}

/// After a trip, while the plant is held: what was stopped and why, what to check on
/// the machine, and whether Reset is possible now (the engine's own check).
fn next_step_ui(c: &Console, ui: &mut egui::Ui) {
    if !c.sim.engine.is_tripped() {
        return;
    }
    let Some(trip) = c.sim.engine.trips.last() else {
        return;
    };
    let message = super::words::trip_message(&c.i18n, &c.sim.bundle, trip);
    let look = super::words::where_to_look(&c.i18n, &c.sim.bundle, trip);
    egui::Frame::group(ui.style())
        .stroke(Stroke::new(2.0, c.palette.trip))
        .show(ui, |ui| {
            ui.label(
                RichText::new(
                    c.i18n
                        .ta("next-title", &[("time", (&fmt_ms(trip.time_ms)).into())]),
                )
                .strong()
                .color(c.palette.trip),
            );
            ui.label(c.i18n.ta("next-why", &[("text", (&message).into())]));
            if !look.is_empty() {
                ui.label(c.i18n.ta(
                    "next-check",
                    &[("where", (&look.join(&c.i18n.t("words-list-sep"))).into())],
                ));
            }
            let reset = match c.sim.engine.reset_check() {
                Ok(()) => c.i18n.t("next-reset-possible"),
                Err(e) => c.i18n.ta(
                    "next-reset-refused",
                    &[("reason", (&super::words::reset_refused(&c.i18n, &e)).into())],
                ),
            };
            ui.label(reset);
        });
}

/// The items of level `l`, each with its code; at level 4 a link to the program
/// element an item names.
fn level_items_ui(
    c: &Console,
    ui: &mut egui::Ui,
    l: usize,
    items: &[vigie_core::explain::Item],
    out: &mut Vec<Command>,
) {
    for item in items {
        ui.horizontal_wrapped(|ui| {
            ui.label(
                RichText::new(item.code)
                    .monospace()
                    .color(c.palette.text_dim),
            );
            let text = c.i18n.explain(item);
            if text.contains('\u{305}') {
                synoptic::overbar_formula(ui, &text, 14.0, c.palette.text);
            } else {
                ui.label(text);
            }
        });
        // Level 4: a link to the element in the program, on its own line (not on a
        // live link, whose program Vigie does not have).
        if l == 4
            && c.link.is_none()
            && let Some(element) = program_element(item)
        {
            ui.horizontal(|ui| {
                ui.add_space(36.0);
                if ui
                    .link(
                        c.i18n
                            .ta("expl-show-in-program", &[("element", (&element).into())]),
                    )
                    .clicked()
                {
                    out.push(Command::ShowInProgram(element));
                }
            });
        }
    }
}

fn explanation_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    next_step_ui(c, ui);
    ui.heading(c.i18n.t("expl-title"));
    let Some(trip) = c.latest_trip() else {
        if let Some(why) = c.sim.action_stop() {
            // Stopped by the elementary-action monitor (seed 003), not by a constraint.
            ui.label(
                RichText::new(c.i18n.ta("expl-action-stop", &[("why", why.into())]))
                    .color(c.palette.trip),
            );
            return;
        }
        ui.label(RichText::new(c.i18n.t("expl-no-trip")).color(c.palette.text_dim));
        return;
    };
    let Some(ex) = c.sim.explanations.get(&trip) else {
        return;
    };
    // In monitor mode the filter did not stop the plant: a violation, not a trip.
    let enforced = c.sim.engine.trips.get(trip).is_none_or(|t| t.enforced);
    let heading = if enforced {
        "expl-trip-at"
    } else {
        "expl-violation-at"
    };
    ui.label(
        RichText::new(
            c.i18n
                .ta(heading, &[("time", (&fmt_ms(ex.time_ms)).into())]),
        )
        .strong()
        .color(c.palette.trip),
    );
    for k in &ex.constraints {
        synoptic::overbar_formula(ui, k, 20.0, c.palette.text);
    }
    if let Some(t) = c.sim.engine.trips.get(trip) {
        for fc in &t.constraints {
            ui.label(
                RichText::new(c.i18n.ta(
                    "expl-as-written",
                    &[("id", (&fc.id).into()), ("notation", (&fc.notation).into())],
                ))
                .color(c.palette.text_dim),
            );
        }
    }
    ui.horizontal_wrapped(|ui| {
        for (i, id) in LEVEL_IDS.iter().enumerate() {
            if ui
                .selectable_label(c.level == Some(i), c.i18n.t(id))
                .clicked()
            {
                out.push(Command::ShowLevel(if c.level == Some(i) {
                    None
                } else {
                    Some(i)
                }));
            }
        }
    });
    if let Some(l) = c.level {
        let level = ex.levels()[l];
        ui.label(
            RichText::new(
                c.i18n
                    .ta("expl-level", &[("level", (&c.i18n.t(LEVEL_IDS[l])).into())]),
            )
            .strong(),
        );
        level_items_ui(c, ui, l, &level.items, out);
        if level.items.is_empty() {
            ui.label(c.i18n.t("expl-nothing"));
        }
    } else {
        ui.label(RichText::new(c.i18n.t("expl-choose-level")).color(c.palette.text_dim));
    }
    ui.add_space(4.0);
    let folder = c.i18n.t("expl-report-folder");
    let export = c.i18n.t("expl-export-report");
    ui.horizontal(|ui| {
        let l = ui.label(folder);
        ui.add(egui::TextEdit::singleline(&mut c.report_dir).desired_width(170.0))
            .labelled_by(l.id);
        if ui.button(export).clicked() {
            out.push(Command::ExportReport(c.report_dir.clone().into()));
        }
        if ui
            .add_enabled(
                !c.save.is_open(),
                egui::Button::new(c.i18n.t("expl-save-report-as")),
            )
            .clicked()
        {
            out.push(Command::SaveAs(super::save::Export::Report));
        }
    });
}

/// The badge of an alarm's priority: text and colours.
pub(crate) fn priority_badge(c: &Console, p: AlarmPriority) -> (String, Color32, Color32) {
    let (id, bg, fg) = match p {
        AlarmPriority::Urgent => ("prio-urgent", c.palette.trip, Color32::WHITE),
        AlarmPriority::High => ("prio-high", c.palette.alarm, Color32::BLACK),
        AlarmPriority::Medium => ("prio-medium", c.palette.caution, Color32::BLACK),
    };
    (format!("P{} {}", p.rank(), c.i18n.t(id)), bg, fg)
}

/// Shelving durations offered, minutes.
const SHELVE_MINUTES: [u64; 4] = [15, 60, 240, 480];

fn alarms_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let now = c.sim.now();
    let unack = c.sim.alarms.unacknowledged();
    let title = c.i18n.t("alarms-title");
    let show_shelved = c.i18n.t("alarms-show-shelved");
    let ack_all = c.i18n.ta("alarms-ack-all", &[("n", unack.into())]);
    ui.horizontal_wrapped(|ui| {
        ui.heading(title);
        ui.checkbox(&mut c.alarm_filter_shelved, show_shelved);
        if ui
            .add_enabled(unack > 0, egui::Button::new(ack_all))
            .clicked()
        {
            out.push(Command::AcknowledgeAll {
                ids: None,
                note: String::new(),
            });
        }
    });
    kpi_ui(c, ui, now);
    history_ui(c, ui, out);
    let mut list: Vec<vigie_core::alarms::Alarm> =
        c.sim.alarms.visible(now).into_iter().cloned().collect();
    if c.alarm_filter_shelved {
        list.extend(c.sim.alarms.shelved(now).into_iter().cloned());
    }
    if list.is_empty() {
        ui.label(RichText::new(c.i18n.t("alarms-none")).color(c.palette.text_dim));
        return;
    }
    let pages = list.len().div_ceil(ALARMS_PER_PAGE);
    let page = c.alarm_page.min(pages - 1);
    let shown: Vec<vigie_core::alarms::Alarm> = list
        .into_iter()
        .skip(page * ALARMS_PER_PAGE)
        .take(ALARMS_PER_PAGE)
        .collect();
    if pages > 1 {
        ui.horizontal(|ui| {
            if ui
                .add_enabled(page > 0, egui::Button::new(c.i18n.t("alarms-previous")))
                .clicked()
            {
                c.alarm_page = page - 1;
            }
            ui.label(c.i18n.ta(
                "alarms-page",
                &[("page", (page + 1).into()), ("pages", pages.into())],
            ));
            if ui
                .add_enabled(page + 1 < pages, egui::Button::new(c.i18n.t("alarms-next")))
                .clicked()
            {
                c.alarm_page = page + 1;
            }
            let ids: Vec<u64> = shown
                .iter()
                .filter(|a| a.acknowledged.is_none())
                .map(|a| a.id)
                .collect();
            if ui
                .add_enabled(
                    !ids.is_empty(),
                    egui::Button::new(c.i18n.t("alarms-ack-page")),
                )
                .clicked()
            {
                out.push(Command::AcknowledgeAll {
                    ids: Some(ids),
                    note: String::new(),
                });
            }
        });
    }
    for a in shown {
        alarm_row_ui(c, ui, &a, now, out);
    }
}

/// The alarm rate (ISA-18.2: alarms per 10 minutes, floods above 10), with the
/// performance figures one click away.
fn kpi_ui(c: &Console, ui: &mut egui::Ui, now: Millis) {
    let k = c.sim.alarms.kpis(now);
    ui.horizontal_wrapped(|ui| {
        ui.label(
            RichText::new(c.i18n.ta(
                "kpi-rate",
                &[
                    ("last", k.last_10_min.into()),
                    ("average", (&format!("{:.1}", k.average_per_10_min)).into()),
                    ("peak", k.peak_per_10_min.into()),
                ],
            ))
            .color(c.palette.text_dim),
        );
        if k.flooding {
            ui.label(
                RichText::new(c.i18n.t("kpi-flood"))
                    .strong()
                    .color(Color32::BLACK)
                    .background_color(c.palette.alarm),
            );
        }
    });
    egui::CollapsingHeader::new(c.i18n.t("kpi-title"))
        .id_salt("alarm_kpis")
        .show(ui, |ui| {
            ui.label(c.i18n.ta(
                "kpi-summary",
                &[
                    ("total", k.total.into()),
                    ("intervals", k.intervals.into()),
                    ("floods", k.flood_intervals.into()),
                    ("limit", vigie_core::alarms::FLOOD_PER_10_MIN.into()),
                ],
            ));
            if !k.chattering.is_empty() {
                ui.label(c.i18n.ta(
                    "kpi-chattering",
                    &[("sources", (&k.chattering.join(", ")).into())],
                ));
            }
            for (source, n) in &k.most_frequent {
                ui.label(format!("{n} × {source}"));
            }
        });
}

/// The alarm history: every alarm raised, searched and filtered, exported to CSV.
fn history_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let total = c.sim.alarms.all().len();
    let title = c.i18n.ta("history-title", &[("n", total.into())]);
    let search = c.i18n.t("history-search");
    let every_kind = c.i18n.t("history-every-kind");
    let every_priority = c.i18n.t("history-every-priority");
    let export = c.i18n.t("history-export");
    let save_as = c.i18n.t("history-save-as");
    let print = c.i18n.t("history-print");
    egui::CollapsingHeader::new(title)
        .id_salt("alarm_history")
        .show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                let l = ui.label(search);
                ui.add(egui::TextEdit::singleline(&mut c.history_filter.text).desired_width(120.0))
                    .labelled_by(l.id);
                egui::ComboBox::from_id_salt("history_kind")
                    .selected_text(c.history_filter.kind.map_or(every_kind.clone(), |k| {
                        c.i18n.t(&format!("kind-{}", k.name().replace(' ', "-")))
                    }))
                    .show_ui(ui, |ui| {
                        ui.selectable_value(&mut c.history_filter.kind, None, &every_kind);
                        for k in AlarmKind::ALL {
                            let name = c.i18n.t(&format!("kind-{}", k.name().replace(' ', "-")));
                            ui.selectable_value(&mut c.history_filter.kind, Some(k), name);
                        }
                    });
                let prio = |p: Option<AlarmPriority>| {
                    p.map_or(every_priority.clone(), |p| format!("P{}", p.rank()))
                };
                egui::ComboBox::from_id_salt("history_priority")
                    .selected_text(prio(c.history_filter.priority))
                    .show_ui(ui, |ui| {
                        for p in [
                            None,
                            Some(AlarmPriority::Urgent),
                            Some(AlarmPriority::High),
                            Some(AlarmPriority::Medium),
                        ] {
                            ui.selectable_value(&mut c.history_filter.priority, p, prio(p));
                        }
                    });
            });
            let list = c.sim.alarms.history(&c.history_filter);
            ui.horizontal(|ui| {
                ui.label(c.i18n.ta(
                    "history-count",
                    &[("n", list.len().into()), ("total", total.into())],
                ));
                if ui.button(export).clicked() {
                    out.push(Command::ExportAlarms("vigie-alarms.csv".into()));
                }
                if ui
                    .add_enabled(!c.save.is_open(), egui::Button::new(save_as))
                    .clicked()
                {
                    out.push(Command::SaveAs(super::save::Export::Alarms));
                }
                if ui
                    .add_enabled(!c.save.is_open(), egui::Button::new(&print))
                    .on_hover_text(c.i18n.t("history-print-hover"))
                    .clicked()
                {
                    out.push(Command::SaveAs(super::save::Export::AlarmsPrint));
                }
            });
            const SHOWN: usize = 100;
            for a in list.iter().take(SHOWN) {
                let cleared = a.cleared.map_or(String::new(), |t| {
                    c.i18n
                        .ta("history-cleared", &[("time", (&fmt_ms(t.0)).into())])
                });
                let ack = a.acknowledged.as_ref().map_or(String::new(), |(t, n)| {
                    format!(
                        "{}{}",
                        c.i18n.ta("history-ack", &[("time", (&fmt_ms(t.0)).into())]),
                        if n.is_empty() {
                            String::new()
                        } else {
                            format!(" ({n})")
                        }
                    )
                });
                ui.label(
                    RichText::new(format!(
                        "{:>9} P{} {}{cleared}{ack}",
                        fmt_ms(a.raised.0),
                        a.priority().rank(),
                        super::words::alarm_message(&c.i18n, &c.sim.bundle, a)
                    ))
                    .size(11.0),
                );
            }
            if list.len() > SHOWN {
                ui.weak(
                    c.i18n
                        .ta("history-more", &[("n", (list.len() - SHOWN).into())]),
                );
            }
            // Earlier runs, from the historian (every session of the data folder).
            super::past::past_alarms_ui(c, ui);
        });
}

/// One alarm: priority, first-out, state, time and the operator's text; the detail one
/// click away; acknowledge with a note; shelve with a reason (never a safety alarm).
fn alarm_row_ui(
    c: &mut Console,
    ui: &mut egui::Ui,
    a: &vigie_core::alarms::Alarm,
    now: Millis,
    out: &mut Vec<Command>,
) {
    let id = a.id.to_string();
    egui::Frame::group(ui.style()).show(ui, |ui| {
        alarm_header_ui(c, ui, a, now);
        ui.label(super::words::alarm_message(&c.i18n, &c.sim.bundle, a));
        if !a.detail.is_empty() {
            egui::CollapsingHeader::new(c.i18n.t("alarm-detail"))
                .id_salt(("alarm_detail", a.id))
                .show(ui, |ui| {
                    ui.label(
                        RichText::new(&a.detail)
                            .monospace()
                            .color(c.palette.text_dim),
                    );
                });
        }
        if let Some((t, note)) = &a.acknowledged {
            ui.label(
                RichText::new(c.i18n.ta(
                    "alarm-acknowledged-at",
                    &[("time", (&fmt_ms(t.0)).into()), ("note", note.into())],
                ))
                .color(c.palette.text_dim),
            );
        }
        ui.horizontal_wrapped(|ui| {
            if a.acknowledged.is_none() {
                let hint = c.i18n.t("alarm-note-hint");
                let label = c.i18n.ta("alarm-acknowledge", &[("id", (&id).into())]);
                let note = c.notes.entry(a.id).or_default();
                ui.add(
                    egui::TextEdit::singleline(note)
                        .hint_text(hint)
                        .desired_width(120.0),
                );
                if ui.button(label).clicked() {
                    out.push(Command::Acknowledge {
                        id: a.id,
                        note: note.clone(),
                    });
                }
            }
            if a.is_shelved(now) {
                if ui
                    .button(c.i18n.ta("alarm-unshelve", &[("id", (&id).into())]))
                    .clicked()
                {
                    out.push(Command::Unshelve(a.id));
                }
            } else if ui
                .add_enabled(
                    a.kind.shelvable(),
                    egui::Button::new(c.i18n.ta("alarm-shelve", &[("id", (&id).into())])),
                )
                .on_disabled_hover_text(c.i18n.t("alarm-shelve-safety"))
                .clicked()
            {
                c.shelve_form = Some(ShelveForm {
                    id: a.id,
                    reason: String::new(),
                    minutes: SHELVE_MINUTES[0],
                });
            }
        });
        if let Some(form) = c.shelve_form.as_mut().filter(|f| f.id == a.id) {
            shelve_form_ui(form, ui, out, &mut c.status, &c.i18n);
        }
    });
}

/// One alarm's header line: priority, first-out, state, time raised and shelving.
fn alarm_header_ui(c: &Console, ui: &mut egui::Ui, a: &vigie_core::alarms::Alarm, now: Millis) {
    let (state_id, col) = match a.state() {
        AlarmState::Unacknowledged => ("alarm-unack", c.palette.equipment_edge),
        AlarmState::Acknowledged => ("alarm-ack", c.palette.equipment),
        AlarmState::ClearedUnacknowledged => ("alarm-cleared-unack", c.palette.equipment),
        AlarmState::Normal => ("alarm-normal", c.palette.equipment),
    };
    let state_txt = c.i18n.t(state_id);
    let (prio, prio_bg, prio_fg) = priority_badge(c, a.priority());
    ui.horizontal_wrapped(|ui| {
        ui.label(
            RichText::new(prio)
                .strong()
                .color(prio_fg)
                .background_color(prio_bg),
        );
        if a.first_out {
            ui.label(
                RichText::new(c.i18n.t("alarm-first-out"))
                    .strong()
                    .color(Color32::WHITE)
                    .background_color(c.palette.equipment_edge),
            );
        }
        ui.label(
            RichText::new(state_txt)
                .strong()
                .color(Color32::WHITE)
                .background_color(col),
        );
        ui.label(fmt_ms(a.raised.0));
        if let Some(s) = a.shelving.as_ref().filter(|_| a.is_shelved(now)) {
            ui.label(c.i18n.ta(
                "alarm-shelved-until",
                &[
                    ("until", (&fmt_ms(s.until.0)).into()),
                    ("reason", (&s.reason).into()),
                ],
            ));
        }
    });
}

/// The shelving form: a reason (required) and a duration of at most one shift.
fn shelve_form_ui(
    form: &mut ShelveForm,
    ui: &mut egui::Ui,
    out: &mut Vec<Command>,
    status: &mut String,
    i18n: &crate::i18n::I18n,
) {
    ui.horizontal_wrapped(|ui| {
        let l = ui.label(i18n.t("shelve-reason"));
        ui.add(
            egui::TextEdit::singleline(&mut form.reason)
                .hint_text(i18n.t("shelve-reason-hint"))
                .desired_width(150.0),
        )
        .labelled_by(l.id);
        egui::ComboBox::from_id_salt(("shelve_minutes", form.id))
            .selected_text(fmt_minutes(form.minutes))
            .show_ui(ui, |ui| {
                for m in SHELVE_MINUTES {
                    ui.selectable_value(&mut form.minutes, m, fmt_minutes(m));
                }
            });
        if ui
            .button(i18n.ta("shelve-now", &[("id", (&form.id.to_string()).into())]))
            .clicked()
        {
            if form.reason.trim().is_empty() {
                *status = i18n.t("shelve-needs-reason");
            } else {
                out.push(Command::Shelve {
                    id: form.id,
                    ms: form.minutes * 60_000,
                    reason: form.reason.clone(),
                });
            }
        }
        if ui.button(i18n.t("cancel")).clicked() {
            out.push(Command::CloseShelveForm);
        }
    });
}

fn fmt_minutes(m: u64) -> String {
    if m >= 60 {
        format!("{} h", m / 60)
    } else {
        format!("{m} min")
    }
}

fn journal_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    ui.heading(c.i18n.t("journal-title"));
    if let Some(p) = c.journal.path() {
        ui.label(
            RichText::new(c.i18n.ta(
                "journal-written-to",
                &[("path", (&p.display().to_string()).into())],
            ))
            .small()
            .color(c.palette.text_dim),
        );
    }
    for e in c.journal.entries().iter().rev().take(12) {
        ui.label(
            RichText::new(format!(
                "{:>9}  {:<10} {}",
                fmt_ms(e.sim_ms),
                super::words::journal_kind(&c.i18n, &e.kind),
                super::words::journal_text(&c.i18n, &c.sim.bundle, e)
            ))
            .monospace()
            .size(11.0),
        );
    }
    ui.horizontal(|ui| {
        let l = ui.label(c.i18n.t("journal-csv-file"));
        ui.add(egui::TextEdit::singleline(&mut c.csv_path).desired_width(200.0))
            .labelled_by(l.id);
        if ui
            .button(c.i18n.t("journal-export-csv"))
            .on_hover_text(c.i18n.t("journal-export-csv-hover"))
            .clicked()
        {
            out.push(Command::ExportCsv(c.csv_path.clone().into()));
        }
        if ui
            .add_enabled(
                !c.save.is_open(),
                egui::Button::new(c.i18n.t("journal-save-as")),
            )
            .clicked()
        {
            out.push(Command::SaveAs(super::save::Export::Journal));
        }
    });
    let under = c
        .export_path(std::path::Path::new(""))
        .display()
        .to_string();
    ui.weak(
        c.i18n
            .ta("journal-exports-under", &[("path", (&under).into())]),
    );
}

fn training_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    ui.heading(c.i18n.t("training-title"));
    for p in &c.library.problems {
        ui.colored_label(c.palette.alarm, RichText::new(p).monospace().small());
    }
    let exercise = c.exercise_id().map(str::to_string);
    let plant = c.plant_exercise().is_some();
    if let Some(id) = &exercise {
        ui.label(RichText::new(c.i18n.ta("training-exercise", &[("id", id.into())])).strong());
        if !c.score.revealed {
            ui.label(c.i18n.t(if plant {
                "training-plant-exercise-how"
            } else {
                "training-exercise-how"
            }));
        }
    }
    ui.label(RichText::new(c.score.summary_in(&c.i18n)).strong());
    if plant {
        diagnosis_ui(c, ui, out);
    } else if c.score.variant.is_some() || exercise.is_some() {
        fix_buttons_ui(c, ui, out, exercise.is_some());
    }
    if let Some(check) = c.last_fix.as_ref().filter(|_| !plant) {
        fix_check_ui(&c.i18n, &c.palette, ui, check);
    }
    if let Some(id) = exercise.as_ref().filter(|_| c.score.revealed) {
        if plant {
            plant_debrief_ui(c, ui, id);
        } else {
            debrief_ui(c, ui, id);
        }
    }
    faults_ui(c, ui, out);
    plant_exercises_ui(c, ui, out, exercise.as_deref());
    egui::CollapsingHeader::new(c.i18n.t("training-errors"))
        .default_open(exercise.is_none())
        .show(ui, |ui| {
            for (id, desc, _) in &c.variants {
                ui.horizontal_wrapped(|ui| {
                    let selected = exercise.as_deref() == Some(id.as_str());
                    if ui
                        .selectable_label(
                            selected,
                            c.i18n.ta("training-load", &[("id", id.into())]),
                        )
                        .clicked()
                    {
                        out.push(Command::LoadVariant(id.clone()));
                    }
                    // The answer stays hidden until the exercise is over.
                    if selected && c.score.revealed {
                        let desc = c
                            .i18n
                            .plant(&format!("variant-{id}"))
                            .unwrap_or_else(|| desc.clone());
                        ui.label(RichText::new(desc).small());
                    }
                });
            }
        });
    training_history_ui(c, ui);
}

/// Verify fix, Edit the program and Show the answer (a control-error exercise).
fn fix_buttons_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>, exercise: bool) {
    ui.horizontal_wrapped(|ui| {
        if ui
            .button(c.i18n.t("training-verify-fix"))
            .on_hover_text(c.i18n.t("training-verify-fix-hover"))
            .clicked()
        {
            out.push(Command::VerifyFix);
        }
        if ui.button(c.i18n.t("training-edit-program")).clicked() {
            out.push(Command::SetMode(Mode::Maintenance));
        }
        if exercise && !c.score.revealed {
            show_answer_button(c, ui, out);
        }
    });
}

fn show_answer_button(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    if ui
        .button(c.i18n.t("training-show-answer"))
        .on_hover_text(c.i18n.t("training-show-answer-hover"))
        .clicked()
    {
        out.push(Command::ShowAnswer);
    }
}

/// The plant-fault exercise's form: the trainee picks the faulty component among the
/// plant's sensors and actuators and submits it.
fn diagnosis_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    if c.score.revealed {
        return;
    }
    let plant = &c.sim.bundle.plant;
    let signals: Vec<&str> = plant
        .inputs
        .iter()
        .chain(&plant.outputs)
        .map(|s| s.id.as_str())
        .collect();
    // The description in the language shown, else the plant file's.
    let name = |id: &str| {
        let own = plant
            .inputs
            .iter()
            .chain(&plant.outputs)
            .find(|s| s.id == id);
        match c.view.descriptions.get(id).or(own.map(|s| &s.description)) {
            Some(d) if !d.is_empty() => format!("{id} — {d}"),
            _ => id.to_string(),
        }
    };
    // The id only once picked: the form keeps its width, Submit stays in place.
    let shown = if c.diagnosis_pick.is_empty() {
        c.i18n.t("training-pick-component")
    } else {
        c.diagnosis_pick.clone()
    };
    let mut pick = c.diagnosis_pick.clone();
    ui.horizontal_wrapped(|ui| {
        let label = ui.label(c.i18n.t("training-faulty-component"));
        egui::ComboBox::from_id_salt("diagnosis-pick")
            .selected_text(shown)
            .width(260.0)
            .show_ui(ui, |ui| {
                for id in &signals {
                    ui.selectable_value(&mut pick, (*id).to_string(), name(id));
                }
            })
            .response
            .labelled_by(label.id);
        if ui
            .add_enabled(
                !pick.is_empty(),
                egui::Button::new(c.i18n.t("training-submit-diagnosis")),
            )
            .on_hover_text(c.i18n.t("training-submit-diagnosis-hover"))
            .clicked()
        {
            out.push(Command::SubmitDiagnosis(pick.clone()));
        }
        show_answer_button(c, ui, out);
    });
    for (component, right) in c.score.diagnoses.iter().filter(|(_, r)| !r) {
        debug_assert!(!right);
        ui.weak(c.i18n.ta(
            "training-diagnosis-wrong",
            &[("component", component.into())],
        ));
    }
    c.diagnosis_pick = pick;
}

/// The plant-fault exercises: Load buttons that do not give the fault away.
fn plant_exercises_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>, now: Option<&str>) {
    if c.library.exercises.is_empty() {
        return;
    }
    egui::CollapsingHeader::new(c.i18n.t("training-plant-exercises"))
        .default_open(now.is_none())
        .show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                for e in &c.library.exercises {
                    let selected = now == Some(e.id.as_str());
                    if ui
                        .selectable_label(
                            selected,
                            c.i18n.ta("training-load", &[("id", (&e.id).into())]),
                        )
                        .clicked()
                    {
                        out.push(Command::LoadPlantExercise(e.id.clone()));
                    }
                }
            });
        });
}

/// The end of a plant-fault exercise: what failed, the answers given, the levels used.
fn plant_debrief_ui(c: &Console, ui: &mut egui::Ui, id: &str) {
    let Some(e) = c.plant_exercise() else {
        return;
    };
    debrief_frame(c, ui, id, |ui| {
        let desc = c
            .i18n
            .plant(&format!("exercise-{id}"))
            .unwrap_or_else(|| e.description.clone());
        ui.label(c.i18n.ta("debrief-fault", &[("text", (&desc).into())]));
        let fault = super::words::fault_told(&c.i18n, &c.view.descriptions, &e.fault);
        ui.label(RichText::new(fault).monospace());
        let answer = e.answer.join(", ");
        ui.label(c.i18n.ta("debrief-answer", &[("answer", (&answer).into())]));
        let given: Vec<String> = c
            .score
            .diagnoses
            .iter()
            .map(|(d, right)| format!("{d} {}", if *right { "✔" } else { "✘" }))
            .collect();
        let given = if given.is_empty() {
            c.i18n.t("score-none")
        } else {
            given.join(", ")
        };
        ui.label(c.i18n.ta("debrief-named", &[("named", (&given).into())]));
        debrief_levels_ui(c, ui);
        let verdict = match (c.score.fixed, c.score.located_after_s) {
            (true, Some(s)) => c.i18n.ta(
                "debrief-found",
                &[
                    ("attempts", c.score.attempts.into()),
                    ("s", (&format!("{s:.0}")).into()),
                ],
            ),
            (true, None) => c.i18n.ta(
                "debrief-found-before-stop",
                &[("attempts", c.score.attempts.into())],
            ),
            (false, _) => c.i18n.ta(
                "debrief-not-found",
                &[("attempts", c.score.attempts.into())],
            ),
        };
        ui.label(verdict);
        if c.sim.emulator.faults_in_force() > 0 {
            ui.label(RichText::new(c.i18n.t("debrief-repair")).strong());
        }
    });
}

fn debrief_levels_ui(c: &Console, ui: &mut egui::Ui) {
    let levels = c.score.levels_in(&c.i18n);
    ui.label(c.i18n.ta("debrief-levels", &[("levels", (&levels).into())]));
}

/// The debrief's frame and title, around `body`.
fn debrief_frame(c: &Console, ui: &mut egui::Ui, id: &str, body: impl FnOnce(&mut egui::Ui)) {
    egui::Frame::NONE
        .stroke(egui::Stroke::new(1.5, c.palette.text_dim))
        .inner_margin(6.0)
        .show(ui, |ui| {
            ui.label(
                RichText::new(c.i18n.ta("debrief-title", &[("id", id.into())]))
                    .strong()
                    .size(16.0),
            );
            body(ui);
        });
}

/// The end of an exercise: the mistake, the correct fix, and how the trainee got there.
fn debrief_ui(c: &Console, ui: &mut egui::Ui, id: &str) {
    debrief_frame(c, ui, id, |ui| {
        let desc = c
            .variants
            .iter()
            .find(|(v, _, _)| v == id)
            .map(|(_, d, _)| {
                c.i18n
                    .plant(&format!("variant-{id}"))
                    .unwrap_or_else(|| d.clone())
            })
            .unwrap_or_default();
        ui.label(c.i18n.ta("debrief-mistake", &[("text", (&desc).into())]));
        ui.label(RichText::new(c.i18n.t("debrief-fix")).strong());
        for line in c.answers.get(id).into_iter().flatten() {
            ui.label(
                RichText::new(format!(
                    "{}: {}  →  {}",
                    line.element, line.wrong, line.right
                ))
                .monospace(),
            );
        }
        debrief_levels_ui(c, ui);
        let verdict = match (c.score.fixed, c.score.located_after_s) {
            (true, Some(s)) => c.i18n.ta(
                "debrief-fixed",
                &[
                    ("attempts", c.score.attempts.into()),
                    ("s", (&format!("{s:.0}")).into()),
                ],
            ),
            _ => c
                .i18n
                .ta("debrief-given-up", &[("attempts", c.score.attempts.into())]),
        };
        ui.label(verdict);
    });
}

/// The fault library (inject: trainer) and the repair of the simulated plant.
fn faults_ui(c: &Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let in_force = c.sim.emulator.faults_in_force();
    ui.horizontal_wrapped(|ui| {
        ui.label(
            c.i18n
                .ta("training-faults-in-force", &[("n", in_force.into())]),
        );
        if ui
            .add_enabled(in_force > 0, egui::Button::new(c.i18n.t("training-repair")))
            .on_hover_text(c.i18n.t("training-repair-hover"))
            .clicked()
        {
            out.push(Command::Plant(OperatorAction::Repair));
        }
    });
    egui::CollapsingHeader::new(c.i18n.t("training-faults"))
        .default_open(false)
        .show(ui, |ui| {
            if c.library.faults.is_empty() {
                ui.label(c.i18n.t("training-no-faults"));
            }
            for (i, (name, spec)) in c.library.faults.iter().enumerate() {
                ui.horizontal(|ui| {
                    if ui.button(c.i18n.t("training-inject")).clicked() {
                        out.push(Command::InjectFault(i));
                    }
                    ui.label(super::words::fault(
                        &c.i18n,
                        &c.view.descriptions,
                        name,
                        spec,
                    ));
                });
            }
        });
}

/// The trainee's finished exercises, newest first.
fn training_history_ui(c: &Console, ui: &mut egui::Ui) {
    let user = c.user.clone().unwrap_or_else(|| "-".to_string());
    let title = match &c.user {
        Some(u) => c.i18n.ta("history-training-title", &[("user", u.into())]),
        None => c.i18n.t("history-training-anonymous"),
    };
    egui::CollapsingHeader::new(title)
        .default_open(false)
        .show(ui, |ui| {
            let mut any = false;
            egui::Grid::new("training-history")
                .striped(true)
                .show(ui, |ui| {
                    for r in c.history.of(&user).take(20) {
                        any = true;
                        ui.label(super::past::fmt_wall(r.wall_ms));
                        ui.label(&r.exercise);
                        ui.label(if r.fixed {
                            c.i18n.t("history-training-fixed")
                        } else {
                            c.i18n.t("history-training-given-up")
                        });
                        ui.label(
                            c.i18n
                                .ta("history-training-attempts", &[("n", r.attempts.into())]),
                        );
                        ui.label(
                            c.i18n
                                .ta("history-training-levels", &[("levels", (&r.levels).into())]),
                        );
                        ui.label(r.seconds.map_or(String::new(), |s| format!("{s:.0} s")));
                        ui.end_row();
                    }
                });
            if !any {
                ui.label(c.i18n.t("history-training-none"));
            }
            for line in &c.history.unreadable {
                ui.label(
                    RichText::new(
                        c.i18n
                            .ta("history-training-unreadable", &[("line", line.into())]),
                    )
                    .color(c.palette.trip),
                );
            }
        });
}

fn maintenance_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let program = c.sim.program.program().program.clone();
    let pal = c.palette.clone();
    let exercise = c.exercise_id().map(str::to_string);
    egui::Frame::NONE
        .fill(pal.panel)
        .inner_margin(8.0)
        .show(ui, |ui| {
            let title = match &exercise {
                Some(id) => c.i18n.ta(
                    "maint-program-exercise",
                    &[
                        ("name", (&program.name).into()),
                        ("id", id.into()),
                        ("version", (&program.version()).into()),
                    ],
                ),
                None => c.i18n.ta(
                    "maint-program",
                    &[
                        ("name", (&program.name).into()),
                        ("version", (&program.version()).into()),
                    ],
                ),
            };
            ui.set_min_width(ui.available_width());
            maintenance_header_ui(&c.i18n, ui, &title, out);
            if !c.problems.is_empty() {
                let col = if c.compiled_edit.is_some() {
                    pal.text
                } else {
                    pal.trip
                };
                ui.label(RichText::new(&c.problems).monospace().color(col));
            }
            if let Some(check) = &c.last_fix {
                fix_check_ui(&c.i18n, &pal, ui, check);
            }
            ui.horizontal(|ui| {
                for (v, id) in [
                    (super::ProgramView::Grafcet, "maint-view-grafcet"),
                    (super::ProgramView::Ladder, "maint-view-ladder"),
                    (super::ProgramView::Text, "maint-view-text"),
                ] {
                    if ui
                        .add(egui::Button::selectable(c.program_view == v, c.i18n.t(id)))
                        .clicked()
                    {
                        out.push(Command::ShowProgramView(v));
                    }
                }
            });
        });
    // The program and, beside it, the plant: the technician follows both.
    let avail = ui.available_rect_before_wrap();
    let program_w = (avail.width() * 0.6).max(480.0).min(avail.width());
    let left = egui::Rect::from_min_size(avail.min, vec2(program_w, avail.height()));
    let right = egui::Rect::from_min_max(egui::pos2(left.right() + 4.0, avail.top()), avail.max);
    ui.scope_builder(egui::UiBuilder::new().max_rect(left), |ui| {
        program_body_ui(c, ui, &program, out);
    });
    if right.width() > 240.0 {
        ui.scope_builder(egui::UiBuilder::new().max_rect(right), |ui| {
            synoptic_panel_ui(c, ui);
        });
    }
}

/// The program in the chosen view, with the suspects of the latest hypothesis framed.
fn program_body_ui(
    c: &Console,
    ui: &mut egui::Ui,
    program: &vigie_core::control::Program,
    out: &mut Vec<Command>,
) {
    let Some(draft) = &c.draft else {
        return;
    };
    let active: BTreeSet<String> = c
        .sim
        .program
        .active_steps()
        .into_iter()
        .map(str::to_string)
        .collect();
    let suspects = program_suspects(c);
    let pal = &c.palette;
    egui::ScrollArea::both()
        .id_salt(("program", c.program_view))
        .auto_shrink([false, false])
        .show(ui, |ui| match c.program_view {
            super::ProgramView::Grafcet => {
                let live = super::grafcet::Live {
                    active: &active,
                    suspects: &suspects,
                    focus: c.program_focus.as_deref(),
                    scroll: c.program_scroll,
                };
                if c.program_scroll {
                    out.push(Command::ProgramScrolled);
                }
                for chart in &program.charts {
                    ui.add_space(10.0);
                    ui.label(
                        RichText::new(c.i18n.ta("maint-chart", &[("name", (&chart.name).into())]))
                            .strong()
                            .size(16.0),
                    );
                    super::grafcet::chart_ui(ui, chart, draft, &live, (&c.i18n, pal), out);
                }
            }
            super::ProgramView::Ladder => {
                if draft.equations.is_empty() {
                    ui.label(c.i18n.t("maint-no-equations"));
                }
                let rt = &c.sim.program;
                let state = |name: &str, kind| super::ladder::contact_state(rt, name, kind);
                super::ladder::ladder_ui(
                    ui,
                    &draft.equations,
                    &state,
                    &suspects,
                    (&c.i18n, pal),
                    out,
                );
            }
            super::ProgramView::Text => program_text_ui(c, ui, program, draft, &active, out),
        });
}

/// The program elements the latest trip's hypothesis names (transitions, steps,
/// equations).
fn program_suspects(c: &Console) -> BTreeSet<String> {
    let Some(ex) = c.latest_trip().and_then(|t| c.sim.explanations.get(&t)) else {
        return BTreeSet::new();
    };
    ex.hypothesis
        .items
        .iter()
        .filter_map(program_element)
        .collect()
}

/// The program element an explanation item names: its transition, else its step, else
/// its equation.
pub(super) fn program_element(item: &vigie_core::explain::Item) -> Option<String> {
    ["transition", "step", "equation"]
        .iter()
        .find_map(|k| item.fields.get(*k))
        .filter(|v| !v.is_empty())
        .cloned()
}

/// Every element's text in a list: steps with their actions, transitions with their
/// receptivities, then the equations.
fn program_text_ui(
    c: &Console,
    ui: &mut egui::Ui,
    program: &vigie_core::control::Program,
    draft: &super::Draft,
    active: &BTreeSet<String>,
    out: &mut Vec<Command>,
) {
    let pal = &c.palette;
    let active_label = c.i18n.t("maint-active");
    for chart in &program.charts {
        ui.add_space(6.0);
        ui.label(
            RichText::new(c.i18n.ta("maint-chart", &[("name", (&chart.name).into())]))
                .strong()
                .size(16.0),
        );
        egui::Grid::new(format!("steps-{}", chart.name))
            .striped(true)
            .num_columns(3)
            .show(ui, |ui| {
                let labels = (active_label.as_str(), &c.i18n);
                chart_steps_ui(ui, chart, draft, active, labels, pal, out);
            });
    }
    if !draft.equations.is_empty() {
        ui.add_space(6.0);
        ui.label(
            RichText::new(c.i18n.t("maint-equations"))
                .strong()
                .size(16.0),
        );
        egui::Grid::new("equations").num_columns(2).show(ui, |ui| {
            for (target, expr) in &draft.equations {
                ui.label(RichText::new(format!("{target} =")).monospace());
                let mut text = expr.clone();
                let name = c.i18n.ta("maint-edit-equation", &[("id", target.into())]);
                if text_field(ui, &mut text, &name) {
                    out.push(Command::EditDraft(super::DraftEdit::Equation {
                        target: target.clone(),
                        text,
                    }));
                }
                ui.end_row();
            }
        });
    }
}

/// A one-line monospace editor whose accessible name is `name`; true when edited.
fn text_field(ui: &mut egui::Ui, text: &mut String, name: &str) -> bool {
    let r = ui.add(
        egui::TextEdit::singleline(text)
            .desired_width(260.0)
            .font(egui::TextStyle::Monospace),
    );
    ui.ctx()
        .accesskit_node_builder(r.id, |node| node.set_label(name.to_string()));
    r.changed()
}

/// The last fix check: the program version it ran, the scenario, what changed and the
/// verdict with its trips and hazards.
pub(super) fn fix_check_ui(
    i18n: &crate::i18n::I18n,
    pal: &crate::theme::Palette,
    ui: &mut egui::Ui,
    check: &super::FixCheck,
) {
    let ok = check.outcome.is_fixed();
    egui::Frame::NONE
        .stroke(egui::Stroke::new(
            1.5,
            if ok { pal.running } else { pal.trip },
        ))
        .inner_margin(6.0)
        .show(ui, |ui| {
            ui.label(RichText::new(i18n.t("fix-check-title")).strong());
            let version = if check.version.is_empty() {
                i18n.t("fix-check-not-compiled")
            } else {
                check.version.clone()
            };
            ui.label(i18n.ta(
                "fix-check-ran",
                &[
                    ("name", (&check.program).into()),
                    ("version", (&version).into()),
                    ("scenario", (&check.scenario).into()),
                ],
            ));
            let changes = if check.changes.is_empty() {
                i18n.t("fix-check-no-change")
            } else {
                check.changes.join(", ")
            };
            ui.label(i18n.ta("fix-check-changes", &[("changes", (&changes).into())]));
            let (id, mut args) = check.outcome.message();
            args.push(("version", check.version.clone()));
            let a: Vec<(&str, crate::i18n::Arg<'_>)> =
                args.iter().map(|(k, v)| (*k, v.into())).collect();
            ui.label(RichText::new(i18n.ta(id, &a)).strong().color(if ok {
                pal.running
            } else {
                pal.trip
            }));
        });
}

/// The maintenance panel's heading with its buttons: recompile, restart, discard, verify.
fn maintenance_header_ui(
    i18n: &crate::i18n::I18n,
    ui: &mut egui::Ui,
    title: &str,
    out: &mut Vec<Command>,
) {
    ui.horizontal_wrapped(|ui| {
        ui.heading(title);
        if ui.button(i18n.t("maint-recompile")).clicked() {
            out.push(Command::Recompile);
        }
        if ui.button(i18n.t("maint-restart")).clicked() {
            out.push(Command::RestartWithEdit);
        }
        if ui.button(i18n.t("maint-discard")).clicked() {
            out.push(Command::DiscardEdits);
        }
        if ui
            .button(i18n.t("training-verify-fix"))
            .on_hover_text(i18n.t("maint-verify-fix-hover"))
            .clicked()
        {
            out.push(Command::VerifyFix);
        }
        if ui
            .button(i18n.t("maint-export-plcopen"))
            .on_hover_text(i18n.t("maint-export-plcopen-hover"))
            .clicked()
        {
            out.push(Command::ExportProgram(std::path::PathBuf::new()));
        }
        if ui
            .button(i18n.t("maint-export-plcopen-as"))
            .on_hover_text(i18n.t("maint-export-plcopen-hover"))
            .clicked()
        {
            out.push(Command::SaveAs(super::save::Export::Program));
        }
    });
}

/// One chart's grid: each step (lit when active) with its editable action, then the
/// transitions leaving it with their editable conditions; edits go out as commands.
fn chart_steps_ui(
    ui: &mut egui::Ui,
    chart: &vigie_core::control::program::Chart,
    draft: &super::Draft,
    active: &BTreeSet<String>,
    (active_label, i18n): (&str, &crate::i18n::I18n),
    pal: &crate::theme::Palette,
    out: &mut Vec<Command>,
) {
    for s in &chart.steps {
        let on = active.contains(&s.id);
        let txt = RichText::new(format!(
            "{}{}",
            if s.initial { "[init] " } else { "" },
            s.id
        ))
        .monospace();
        ui.label(if on {
            txt.strong()
                .color(Color32::WHITE)
                .background_color(pal.running)
        } else {
            txt
        });
        ui.label(if on { active_label } else { "" });
        if let Some(a) = draft.actions.get(&s.id) {
            let mut text = a.clone();
            let name = i18n.ta("maint-edit-actions", &[("id", (&s.id).into())]);
            if text_field(ui, &mut text, &name) {
                out.push(Command::EditDraft(super::DraftEdit::Actions {
                    step: s.id.clone(),
                    text,
                }));
            }
        }
        ui.end_row();
        for t in chart.transitions.iter().filter(|t| t.from.contains(&s.id)) {
            ui.label(RichText::new(format!("   + {}", t.id)).monospace());
            ui.label(
                RichText::new(format!("→ {}", t.to.join(", ")))
                    .monospace()
                    .color(pal.text_dim),
            );
            if let Some(cond) = draft.conditions.get(&t.id) {
                let mut text = cond.clone();
                let name = i18n.ta("maint-edit-condition", &[("id", (&t.id).into())]);
                if text_field(ui, &mut text, &name) {
                    out.push(Command::EditDraft(super::DraftEdit::Condition {
                        transition: t.id.clone(),
                        text,
                    }));
                }
            }
            ui.end_row();
        }
    }
}

/// One row of the chronogram: which record bits it shows.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Row {
    /// A sensor.
    Input(usize),
    /// An actuator: applied (filled) and commanded (the line on top).
    Output(usize),
    /// An observer.
    Observer(usize),
    /// An auxiliary (diagnosers' flags, intervals, estimates, plausibility).
    Aux(usize),
}

/// The chronogram's rows: the signals chosen, in the plant's order, then the
/// observers and auxiliaries chosen.
fn chronogram_rows(c: &Console) -> Vec<(Row, String)> {
    use vigie_core::symbols::Space;
    let symbols = &c.sim.engine.symbols;
    let mut rows = Vec::new();
    for (space, make) in [
        (Space::Input, Row::Input as fn(usize) -> Row),
        (Space::Output, Row::Output),
        (Space::Observer, Row::Observer),
        (Space::Aux, Row::Aux),
    ] {
        for (i, name) in symbols.names(space).iter().enumerate() {
            if c.chrono_signals.contains(name) {
                rows.push((make(i), name.clone()));
            }
        }
    }
    rows
}

/// Height of one chronogram row.
const CHRONO_ROW_H: f32 = 18.0;
/// Height of the time axis.
const CHRONO_AXIS_H: f32 = 18.0;

fn chronogram_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let title = c.i18n.t("chrono-title");
    chronogram_controls_ui(c, ui, &title, out);
    let rows = chronogram_rows(c);
    if rows.is_empty() {
        return;
    }
    let now = c.sim.now().0;
    let window = c.chrono_window_ms;
    let t1 = now.max(window);
    let t0 = t1 - window;
    egui::ScrollArea::vertical()
        .auto_shrink([false, false])
        .show(ui, |ui| {
            #[allow(clippy::cast_precision_loss)]
            let height = rows.len() as f32 * CHRONO_ROW_H + CHRONO_AXIS_H;
            let size = vec2(ui.available_width().max(100.0), height);
            let (resp, painter) = ui.allocate_painter(size, Sense::click_and_drag());
            resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, &title));
            let rect = resp.rect;
            c.chrono_rect = Some(ui.clip_rect().intersect(rect));
            let pal = &c.palette;
            painter.rect_filled(rect, 0.0, pal.background);
            let label_w = 56.0;
            let plot_w = rect.width() - label_w;
            #[allow(clippy::cast_precision_loss)]
            let x_of = |t: u64| {
                rect.left() + label_w + (t.saturating_sub(t0)) as f32 / window as f32 * plot_w
            };
            let recs: Vec<&vigie_core::history::CycleRecord> = {
                let mut v: Vec<_> = c
                    .sim
                    .engine
                    .history
                    .iter()
                    .rev()
                    .take_while(|r| r.time.0 >= t0)
                    .collect();
                v.reverse();
                v
            };
            for (k, (row, name)) in rows.iter().enumerate() {
                #[allow(clippy::cast_precision_loss)]
                let y = rect.top() + CHRONO_AXIS_H + k as f32 * CHRONO_ROW_H;
                chronogram_row(
                    &painter,
                    (rect, label_w),
                    (*row, name),
                    &recs,
                    (y, &x_of, now),
                    pal,
                );
            }
            chronogram_axis(&painter, rect, label_w, (t0, window), &x_of, pal);
            paint_chronogram_marks(c, &painter, rect, t0, &x_of);
            // Ctrl + wheel zooms the time window around the pointer's time.
            if resp.hovered() {
                let (zoom, ctrl) = ui.input(|i| (i.zoom_delta(), i.modifiers.command));
                if (zoom - 1.0).abs() > 1e-3 || ctrl {
                    #[allow(
                        clippy::cast_possible_truncation,
                        clippy::cast_sign_loss,
                        clippy::cast_precision_loss
                    )]
                    let w = ((window as f32 / zoom) as u64).clamp(2_000, 3_600_000);
                    if w != window {
                        out.push(Command::ChronoWindow(w));
                    }
                }
            }
            if let Some(p) = resp.interact_pointer_pos()
                && p.x > rect.left() + label_w
            {
                #[allow(
                    clippy::cast_possible_truncation,
                    clippy::cast_sign_loss,
                    clippy::cast_precision_loss
                )]
                let t = t0
                    + (((p.x - rect.left() - label_w) / plot_w).clamp(0.0, 1.0) * window as f32)
                        as u64;
                out.push(Command::Scrub(Some(t.min(now))));
            }
        });
}

/// One row: its name, its grid line and its spans; an actuator's commanded value is
/// the line along the top of its row, amber where the filter applied another value.
fn chronogram_row(
    painter: &egui::Painter,
    (rect, label_w): (egui::Rect, f32),
    (row, name): (Row, &str),
    recs: &[&vigie_core::history::CycleRecord],
    (y, x_of, now): (f32, &impl Fn(u64) -> f32, u64),
    pal: &crate::theme::Palette,
) {
    let h = CHRONO_ROW_H;
    painter.text(
        pos2(rect.left() + 4.0, y + h / 2.0),
        Align2::LEFT_CENTER,
        name,
        FontId::monospace(11.0),
        match row {
            Row::Observer(_) | Row::Aux(_) => pal.text_dim,
            _ => pal.text,
        },
    );
    painter.line_segment(
        [
            pos2(rect.left() + label_w, y + h),
            pos2(rect.right(), y + h),
        ],
        Stroke::new(0.5, pal.equipment),
    );
    match row {
        Row::Input(i) => paint_spans(
            painter,
            recs,
            |r| r.inputs.get(i),
            (y + 2.0, h - 4.0),
            pal.running,
            x_of,
            now,
        ),
        Row::Observer(i) => paint_spans(
            painter,
            recs,
            |r| r.observers.get(i),
            (y + 2.0, h - 4.0),
            pal.highlight,
            x_of,
            now,
        ),
        Row::Aux(i) => paint_spans(
            painter,
            recs,
            |r| r.aux.get(i),
            (y + 2.0, h - 4.0),
            pal.caution,
            x_of,
            now,
        ),
        Row::Output(i) => {
            paint_spans(
                painter,
                recs,
                |r| r.applied.get(i),
                (y + 5.0, h - 7.0),
                pal.equipment_edge,
                x_of,
                now,
            );
            // Commanded: a thin bar at the top; amber where it differs from applied.
            paint_spans(
                painter,
                recs,
                |r| r.commanded.get(i),
                (y + 1.0, 5.0),
                pal.text,
                x_of,
                now,
            );
            paint_spans(
                painter,
                recs,
                |r| r.commanded.get(i) != r.applied.get(i),
                (y + 1.0, h - 2.0),
                pal.forced.gamma_multiply(0.55),
                x_of,
                now,
            );
        }
    }
}

/// The time axis above the rows (always in view): ticks at a round step, labelled in
/// seconds.
fn chronogram_axis(
    painter: &egui::Painter,
    rect: egui::Rect,
    label_w: f32,
    (t0, window): (u64, u64),
    x_of: &impl Fn(u64) -> f32,
    pal: &crate::theme::Palette,
) {
    let y = rect.top() + CHRONO_AXIS_H - 1.0;
    painter.line_segment(
        [pos2(rect.left() + label_w, y), pos2(rect.right(), y)],
        Stroke::new(1.0, pal.text_dim),
    );
    let step = axis_step_ms(window);
    let first = t0.div_ceil(step) * step;
    let mut t = first;
    while t <= t0 + window {
        let x = x_of(t);
        painter.line_segment(
            [pos2(x, y - 4.0), pos2(x, y)],
            Stroke::new(1.0, pal.text_dim),
        );
        painter.text(
            pos2(x, y - 4.0),
            Align2::CENTER_BOTTOM,
            fmt_tick(t, step),
            FontId::proportional(11.0),
            pal.text_dim,
        );
        t += step;
    }
}

/// A checkbox adding or removing a chronogram row.
fn chrono_toggle(shown: &mut BTreeSet<String>, ui: &mut egui::Ui, id: &str, text: &str) {
    let mut on = shown.contains(id);
    if ui.checkbox(&mut on, text).changed() {
        if on {
            shown.insert(id.to_string());
        } else {
            shown.remove(id);
        }
    }
}

/// A tick's label: whole seconds when the step is, else tenths.
fn fmt_tick(ms: u64, step: u64) -> String {
    if step.is_multiple_of(1000) {
        format!("{} s", ms / 1000)
    } else {
        format!("{}.{} s", ms / 1000, (ms % 1000) / 100)
    }
}

/// A round tick step (1, 2 or 5 × 10^k ms) giving about eight ticks over `window`.
fn axis_step_ms(window: u64) -> u64 {
    let raw = (window / 8).max(1);
    let mut p = 1u64;
    while p * 10 <= raw {
        p *= 10;
    }
    [1, 2, 5, 10]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10 * p)
}

/// The chronogram's controls: window length, replay slider, back to live, signals shown.
fn chronogram_controls_ui(c: &mut Console, ui: &mut egui::Ui, title: &str, out: &mut Vec<Command>) {
    let sim = &c.sim;
    let now = sim.now().0;
    let replay = c.i18n.t("chrono-replay");
    let live = c.i18n.t("chrono-live");
    let signals = c.i18n.t("chrono-signals");
    ui.horizontal(|ui| {
        ui.label(RichText::new(title).strong());
        for w in [10u64, 30, 60, 300] {
            if ui
                .selectable_label(c.chrono_window_ms == w * 1000, format!("{w} s"))
                .on_hover_text(c.i18n.t("chrono-zoom-hover"))
                .clicked()
            {
                out.push(Command::ChronoWindow(w * 1000));
            }
        }
        ui.separator();
        let oldest = sim.engine.history.iter().next().map_or(0, |r| r.time.0);
        let mut t = c.replay.unwrap_or(now);
        let r = ui.add(
            egui::Slider::new(&mut t, oldest..=now.max(oldest))
                .text(replay)
                .custom_formatter(|v, _| fmt_ms(v as u64)),
        );
        if r.changed() {
            out.push(Command::Scrub(Some(t)));
        }
        if c.replay.is_some() && ui.button(live).clicked() {
            out.push(Command::Scrub(None));
        }
        ui.menu_button(signals, |ui| {
            egui::ScrollArea::vertical()
                .max_height(420.0)
                .show(ui, |ui| {
                    for s in sim
                        .bundle
                        .plant
                        .inputs
                        .iter()
                        .chain(&sim.bundle.plant.outputs)
                    {
                        let text = format!(
                            "{} {}",
                            s.id,
                            c.view.descriptions.get(&s.id).unwrap_or(&s.description)
                        );
                        chrono_toggle(&mut c.chrono_signals, ui, &s.id, &text);
                    }
                    ui.separator();
                    ui.label(RichText::new(c.i18n.t("chrono-observers")).strong());
                    let symbols = &sim.engine.symbols;
                    for name in symbols.names(vigie_core::symbols::Space::Observer) {
                        chrono_toggle(&mut c.chrono_signals, ui, name, name);
                    }
                    ui.label(RichText::new(c.i18n.t("chrono-aux")).strong());
                    for name in symbols.names(vigie_core::symbols::Space::Aux) {
                        chrono_toggle(&mut c.chrono_signals, ui, name, name);
                    }
                });
        });
    });
}

/// Paints one chronogram row's spans where the signal (`get`) is on, in `col`.
fn paint_spans(
    painter: &egui::Painter,
    recs: &[&vigie_core::history::CycleRecord],
    get: impl Fn(&vigie_core::history::CycleRecord) -> bool,
    (y, row_h): (f32, f32),
    col: Color32,
    x_of: &impl Fn(u64) -> f32,
    now: u64,
) {
    let mut start: Option<u64> = None;
    let flush = |s: u64, e: u64| {
        let r = egui::Rect::from_min_max(
            pos2(x_of(s), y + 3.0),
            pos2(x_of(e).max(x_of(s) + 1.0), y + row_h - 3.0),
        );
        painter.rect_filled(r, 0.0, col);
    };
    for r in recs {
        let v = get(r);
        match (v, start) {
            (true, None) => start = Some(r.time.0),
            (false, Some(s)) => {
                flush(s, r.time.0);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        flush(s, now);
    }
}

/// Marks the chronogram's trips (with their constraints), hazards and replay time.
fn paint_chronogram_marks(
    c: &Console,
    painter: &egui::Painter,
    rect: egui::Rect,
    t0: u64,
    x_of: &impl Fn(u64) -> f32,
) {
    let (sim, pal) = (&c.sim, &c.palette);
    for t in &sim.engine.trips {
        if t.time_ms >= t0 {
            let x = x_of(t.time_ms);
            painter.line_segment(
                [pos2(x, rect.top()), pos2(x, rect.bottom())],
                Stroke::new(2.0, pal.trip),
            );
            let ids: Vec<&str> = t.constraints.iter().map(|c| c.id.as_str()).collect();
            painter.text(
                pos2(x + 3.0, rect.top() + CHRONO_AXIS_H + 2.0),
                Align2::LEFT_TOP,
                ids.join(","),
                FontId::proportional(11.0),
                pal.trip,
            );
        }
    }
    for h in sim.emulator.hazards() {
        if h.time_ms >= t0 {
            let x = x_of(h.time_ms);
            painter.line_segment(
                [pos2(x, rect.top()), pos2(x, rect.bottom())],
                Stroke::new(2.0, pal.alarm),
            );
        }
    }
    if let Some(t) = c.replay {
        let x = x_of(t);
        painter.line_segment(
            [pos2(x, rect.top()), pos2(x, rect.bottom())],
            Stroke::new(2.0, pal.highlight),
        );
    }
}

/// `12.34 s`.
pub(crate) fn fmt_ms(ms: u64) -> String {
    format!("{}.{:02} s", ms / 1000, (ms % 1000) / 10)
}

/// The Reset button: red while the filter is tripped; `hover` is the id of its tooltip.
pub(crate) fn reset_button_ui(c: &Console, ui: &mut egui::Ui, hover: &str, out: &mut Vec<Command>) {
    let tripped = c.sim.engine.is_tripped();
    let reset = egui::Button::new(RichText::new(c.i18n.t("reset")).color(if tripped {
        Color32::WHITE
    } else {
        c.palette.text
    }))
    .fill(if tripped {
        c.palette.trip
    } else {
        c.palette.equipment.gamma_multiply(0.5)
    });
    if ui.add(reset).on_hover_text(c.i18n.t(hover)).clicked() {
        out.push(Command::Plant(OperatorAction::Reset));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_axis_ticks_at_round_steps() {
        assert_eq!(axis_step_ms(10_000), 2_000);
        assert_eq!(axis_step_ms(30_000), 5_000);
        assert_eq!(axis_step_ms(2_000), 250.max(axis_step_ms(2_000)));
        assert_eq!(axis_step_ms(3_600_000), 500_000);
        for w in [2_000u64, 7_777, 30_000, 300_000, 3_600_000] {
            let step = axis_step_ms(w);
            let ticks = w / step;
            assert!(
                (4..=10).contains(&ticks),
                "{w} ms: {ticks} ticks of {step} ms"
            );
        }
        assert_eq!(fmt_tick(12_000, 2_000), "12 s");
        assert_eq!(fmt_tick(12_500, 500), "12.5 s");
    }
}
