//! The views: each `*_ui` function renders one part of the console from its state and
//! pushes [`Command`]s; none of them changes the simulation.

use super::synoptic::{self, Geometry, Picture};
use super::{ALARMS_PER_PAGE, Command, Console, LEVEL_NAMES, Mode, ShelveForm};
use egui::{Align2, Color32, FontId, RichText, Sense, Stroke, pos2, vec2};
use std::collections::{BTreeMap, BTreeSet};
use vigie_core::access::Permission;
use vigie_core::alarms::{AlarmKind, AlarmPriority, AlarmState};
use vigie_core::sim::{OperatorAction, PlantState};
use vigie_core::time::Millis;

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
                    Mode::Training => {
                        training_ui(c, ui, out);
                        ui.separator();
                        explanation_ui(c, ui, out);
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
            ui.horizontal(|ui| {
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
            });
            if c.trends.shown {
                super::trends::trends_ui(c, ui, out);
            } else {
                synoptic_panel_ui(c, ui);
            }
        });
}

/// The text of the red banner shown while no safety constraint protects the plant.
pub(crate) const UNPROTECTED_BANNER: &str =
    "UNPROTECTED: no safety constraint, the filter lets every command through";

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
                RichText::new(UNPROTECTED_BANNER)
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
        ui.label(format!("t = {}", fmt_ms(c.sim.now().0)));
        ui.separator();
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
                .button("Leave manual")
                .on_hover_text("Back to the program, restarted from its initial steps")
                .clicked()
            {
                out.push(Command::Plant(OperatorAction::Manual(false)));
            }
        } else if ui
            .add_enabled(
                c.link.is_none() && !c.sim.engine.is_tripped(),
                egui::Button::new("Manual…"),
            )
            .on_hover_text("Drive the actuators by hand, every command through the filter")
            .on_disabled_hover_text("Not while the filter holds the plant, nor on a live link")
            .clicked()
        {
            c.manual_confirm = true;
        }
        let tripped = c.sim.engine.is_tripped();
        let reset = egui::Button::new(RichText::new("Reset").color(if tripped {
            Color32::WHITE
        } else {
            c.palette.text
        }))
        .fill(if tripped {
            c.palette.trip
        } else {
            c.palette.equipment.gamma_multiply(0.5)
        });
        if ui
            .add(reset)
            .on_hover_text("Operator reset of the safety filter")
            .clicked()
        {
            out.push(Command::Plant(OperatorAction::Reset));
        }
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
            egui::Button::new(RichText::new("Re-initialise…").color(Color32::BLACK))
                .fill(c.palette.alarm)
        } else {
            egui::Button::new("Re-initialise…")
        };
        if ui
            .add_enabled(tripped && c.link.is_none(), reinit)
            .on_hover_text(
                "When the reset is refused because the program or an observer still \
                 believes what a transient made it believe: after a check of the plant \
                 (emptied, or every item where a sensor shows it), the program back to \
                 its initial steps, the sensors taken as read",
            )
            .on_disabled_hover_text(
                "Only after a trip, on the emulator (on a live link the PLC's program is \
                 re-initialised on the PLC)",
            )
            .clicked()
        {
            c.reinit_confirm = true;
        }
        ui.separator();
        state_ui(c, ui);
        ui.separator();
        match &c.user {
            Some(u) => {
                ui.label(format!("{u} · {}", c.role.name()));
                if ui.button("Log out").clicked() {
                    out.push(Command::Logout);
                }
            }
            None => {
                if ui
                    .button("Log in…")
                    .on_hover_text(
                        "Operator role until a maintenance, trainer or administrator login",
                    )
                    .clicked()
                {
                    c.login = Some((String::new(), String::new()));
                }
            }
        }
    });
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
        ui.heading("Log in to the console");
        if no_accounts {
            ui.label(
                "No account in the data folder yet: an administrator creates them with \
                 `vigie user add NAME --role maintenance` (the password on standard input).",
            );
        }
        egui::Grid::new("login_grid").show(ui, |ui| {
            let l = ui.label("User");
            ui.add(egui::TextEdit::singleline(name).min_size(vec2(180.0, 0.0)))
                .labelled_by(l.id);
            ui.end_row();
            let l = ui.label("Password");
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
            if ui.button("Log in").clicked() || enter {
                out.push(Command::Login {
                    name: name.clone(),
                    password: std::mem::take(password),
                });
            }
            if ui.button("Cancel").clicked() {
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
                        .map(|k| k.description.clone())
                        .filter(|d| !d.is_empty())
                        .map_or(String::new(), |d| format!(" ({d})"));
                    let left_s = b.until.0.saturating_sub(now.0) / 1000;
                    ui.label(
                        RichText::new(format!(
                            "BYPASS: {id}{what} is not enforced until {} ({} min {} s left), by {}: {}",
                            fmt_ms(b.until.0),
                            left_s / 60,
                            left_s % 60,
                            b.by,
                            b.reason
                        ))
                        .strong()
                        .color(Color32::BLACK),
                    );
                    if ui.button(format!("End bypass of {id}")).clicked() {
                        out.push(Command::Plant(OperatorAction::EndBypass(id.clone())));
                    }
                });
            }
        });
}

/// Maintenance: bypass one constraint for a limited time, with a reason.
fn bypass_form_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    ui.heading("Bypass a constraint");
    if !c.may(Permission::BypassConstraint) {
        ui.label(
            RichText::new("Bypassing a safety constraint needs the maintenance role: log in.")
                .color(c.palette.text_dim),
        );
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
        let l = ui.label("Bypass reason");
        ui.add(egui::TextEdit::singleline(&mut form.1).desired_width(160.0))
            .labelled_by(l.id);
        if ui
            .add_enabled(!form.0.is_empty(), egui::Button::new("Bypass now"))
            .on_hover_text("The filter stops enforcing this constraint until the time is up")
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
            RichText::new(format!("{} = {}: {}", k.id, k.source, k.description))
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
            ui.label(RichText::new(txt).strong().size(22.0).color(fg))
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
        ui.heading("Drive the plant by hand?");
        ui.label(
            "The control program stops being scanned and the outputs stay as they are. \
             You then switch each actuator on or off, or jog it while the button is held. \
             Every command is checked against the safety constraints first: one that \
             would break a constraint is refused with the reason and never reaches the \
             plant. Leaving manual mode restarts the program from its initial steps.",
        );
        ui.horizontal(|ui| {
            if ui.button("Enter manual mode").clicked() {
                out.push(Command::Plant(OperatorAction::Manual(true)));
                c.manual_confirm = false;
            }
            if ui.button("Cancel").clicked() {
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
    ui.heading("Manual mode");
    ui.label(
        RichText::new(
            "Every command is checked against the safety constraints; a refused one \
             never reaches the plant.",
        )
        .color(c.palette.text_dim),
    );
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
            ui.label(RichText::new(element).color(c.palette.text_dim));
            ui.label(if on { "ON" } else { "OFF" });
            if ui
                .add_enabled(!on, egui::Button::new(format!("{id} ON")))
                .clicked()
            {
                out.push(Command::Plant(OperatorAction::ManualSet(id.clone(), true)));
            }
            if ui
                .add_enabled(on, egui::Button::new(format!("{id} OFF")))
                .clicked()
            {
                out.push(Command::Plant(OperatorAction::ManualSet(id.clone(), false)));
            }
            let jog = ui
                .add(egui::Button::new(format!("Jog {id}")).sense(Sense::click_and_drag()))
                .on_hover_text("ON while held");
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
        ui.heading("Re-initialise after a check of the plant");
        ui.label(
            "The control program goes back to its initial steps, as at the start of a \
             shift, the sensors are taken as read and the trip ends. The filter checks \
             the next commands as any other, and the diagnosers decide nothing with \
             certainty until each model is back in its initial state.",
        );
        ui.label(
            "Empty the plant first: take every item off by hand, fallen ones included \
             (the initial steps expect no item half-way). Every observer then restarts \
             empty.",
        );
        ui.weak("On the emulator, the emulated items are taken off for you.");
        ui.label(
            "Or leave the items in place, each where a sensor shows it, none between \
             the sensors: an observer is then cleared only where the sensors leave no \
             room for its item, and the program may stop again on an item it does not \
             expect.",
        );
        ui.horizontal(|ui| {
            if ui.button("Plant emptied: re-initialise").clicked() {
                out.push(Command::Plant(OperatorAction::Reinitialise {
                    emptied: true,
                }));
                c.reinit_confirm = false;
            }
            if ui.button("Items left in place: re-initialise").clicked() {
                out.push(Command::Plant(OperatorAction::Reinitialise {
                    emptied: false,
                }));
                c.reinit_confirm = false;
            }
            if ui.button("Cancel").clicked() {
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
        let s = c.sim.emulator.stats();
        let removed = if s.removed > 0 {
            format!(", {} taken off", s.removed)
        } else {
            String::new()
        };
        ui.label(format!(
            "{} — boxes: {} created, {} left, {} right, {} damaged{removed}",
            c.source.scenario.name, s.created, s.delivered_left, s.delivered_right, s.damaged
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
    let mut boxes = sim.emulator.boxes();
    let mut angle = sim.emulator.table_angle_mdeg();
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
        }
        banner = Some((
            format!(
                "Level {} — trip {} at {}",
                LEVEL_NAMES[*l],
                ex.constraints
                    .iter()
                    .map(|k| k.split(" =").next().unwrap_or(k))
                    .collect::<Vec<_>>()
                    .join(", "),
                fmt_ms(ex.time_ms)
            ),
            c.palette.highlight,
        ));
    }
    if let Some(r) = &replay_rec {
        banner = Some((
            format!(
                "REPLAY at {} (live: {})",
                fmt_ms(r.time.0),
                fmt_ms(sim.now().0)
            ),
            c.palette.highlight,
        ));
    } else if banner.is_none() && sim.engine.is_tripped() {
        let ids: Vec<String> = sim
            .engine
            .trips
            .last()
            .map(|t| t.constraints.iter().map(|c| c.id.clone()).collect())
            .unwrap_or_default();
        banner = Some((
            format!(
                "TRIP {} — the safety filter holds the plant",
                ids.join(", ")
            ),
            c.palette.trip,
        ));
    }
    let geom = Geometry::new(&sim.layout, angle);
    let pic = Picture {
        boxes,
        values: &values,
        forced: &forced,
        time_ms,
        highlights,
        ghost,
        banner,
    };
    let resp = synoptic::synoptic_ui(ui, &mut c.view, &geom, angle, &pic, &c.palette, plant);
    c.synoptic_rect = Some(resp.rect);
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
    let text = vigie_core::alarms::texts::trip(&c.sim.bundle, trip);
    let look = vigie_core::alarms::texts::where_to_look(&c.sim.bundle, trip);
    egui::Frame::group(ui.style())
        .stroke(Stroke::new(2.0, c.palette.trip))
        .show(ui, |ui| {
            ui.label(
                RichText::new(format!(
                    "What to do now (stopped at {})",
                    fmt_ms(trip.time_ms)
                ))
                .strong()
                .color(c.palette.trip),
            );
            ui.label(format!("1. Why: {}.", text.message));
            if !look.is_empty() {
                ui.label(format!("2. Check on the machine: {}.", look.join("; ")));
            }
            let reset = match c.sim.engine.reset_check() {
                Ok(()) => "3. Reset is possible now: press Reset, then Start if the \
                           program was stopped."
                    .to_string(),
                Err(e) => format!(
                    "3. Reset is refused now ({e}). Once the cause is gone (the item \
                     has moved on, the sensor reads right), press Reset; if it stays \
                     refused, check the plant and Re-initialise…"
                ),
            };
            ui.label(reset);
        });
}

fn explanation_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    next_step_ui(c, ui);
    ui.heading("Explanation");
    let Some(trip) = c.latest_trip() else {
        ui.label(
            RichText::new("No trip: the plant runs within its safety constraints.")
                .color(c.palette.text_dim),
        );
        return;
    };
    let Some(ex) = c.sim.explanations.get(&trip) else {
        return;
    };
    ui.label(
        RichText::new(format!("Trip at {}", fmt_ms(ex.time_ms)))
            .strong()
            .color(c.palette.trip),
    );
    for k in &ex.constraints {
        synoptic::overbar_formula(ui, k, 20.0, c.palette.text);
    }
    if let Some(t) = c.sim.engine.trips.get(trip) {
        for fc in &t.constraints {
            ui.label(
                RichText::new(format!("as written: {} = {}", fc.id, fc.notation))
                    .color(c.palette.text_dim),
            );
        }
    }
    ui.horizontal_wrapped(|ui| {
        for (i, name) in LEVEL_NAMES.iter().enumerate() {
            if ui.selectable_label(c.level == Some(i), *name).clicked() {
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
        ui.label(RichText::new(format!("Level {}", LEVEL_NAMES[l])).strong());
        for item in &level.items {
            ui.horizontal_wrapped(|ui| {
                ui.label(
                    RichText::new(item.code)
                        .monospace()
                        .color(c.palette.text_dim),
                );
                if item.text.contains('\u{305}') {
                    synoptic::overbar_formula(ui, &item.text, 14.0, c.palette.text);
                } else {
                    ui.label(&item.text);
                }
            });
        }
        if level.items.is_empty() {
            ui.label("Nothing to report at this level.");
        }
    } else {
        ui.label(
            RichText::new("Choose a level to draw it on the synoptic.").color(c.palette.text_dim),
        );
    }
    ui.add_space(4.0);
    ui.horizontal(|ui| {
        let l = ui.label("Report folder");
        ui.add(egui::TextEdit::singleline(&mut c.report_dir).desired_width(170.0))
            .labelled_by(l.id);
        if ui.button("Export incident report").clicked() {
            out.push(Command::ExportReport(c.report_dir.clone().into()));
        }
    });
}

/// The badge of an alarm's priority: text and colours.
pub(crate) fn priority_badge(c: &Console, p: AlarmPriority) -> (String, Color32, Color32) {
    let (name, bg, fg) = match p {
        AlarmPriority::Urgent => ("URGENT", c.palette.trip, Color32::WHITE),
        AlarmPriority::High => ("HIGH", c.palette.alarm, Color32::BLACK),
        AlarmPriority::Medium => ("MEDIUM", c.palette.caution, Color32::BLACK),
    };
    (format!("P{} {name}", p.rank()), bg, fg)
}

/// Shelving durations offered, minutes.
const SHELVE_MINUTES: [u64; 4] = [15, 60, 240, 480];

fn alarms_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let now = c.sim.now();
    let unack = c.sim.alarms.unacknowledged();
    ui.horizontal_wrapped(|ui| {
        ui.heading("Alarms");
        ui.checkbox(&mut c.alarm_filter_shelved, "show shelved");
        if ui
            .add_enabled(
                unack > 0,
                egui::Button::new(format!("Acknowledge all ({unack})")),
            )
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
        ui.label(RichText::new("No active alarm.").color(c.palette.text_dim));
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
                .add_enabled(page > 0, egui::Button::new("◀ Previous"))
                .clicked()
            {
                c.alarm_page = page - 1;
            }
            ui.label(format!("Page {} of {pages}", page + 1));
            if ui
                .add_enabled(page + 1 < pages, egui::Button::new("Next ▶"))
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
                .add_enabled(!ids.is_empty(), egui::Button::new("Acknowledge page"))
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
            RichText::new(format!(
                "Rate: {} in the last 10 min (average {:.1}, peak {})",
                k.last_10_min, k.average_per_10_min, k.peak_per_10_min
            ))
            .color(c.palette.text_dim),
        );
        if k.flooding {
            ui.label(
                RichText::new("ALARM FLOOD")
                    .strong()
                    .color(Color32::BLACK)
                    .background_color(c.palette.alarm),
            );
        }
    });
    egui::CollapsingHeader::new("Alarm performance")
        .id_salt("alarm_kpis")
        .show(ui, |ui| {
            ui.label(format!(
                "{} alarms in {} intervals of 10 min; {} in flood (more than {} alarms)",
                k.total,
                k.intervals,
                k.flood_intervals,
                vigie_core::alarms::FLOOD_PER_10_MIN
            ));
            if !k.chattering.is_empty() {
                ui.label(format!(
                    "Chattering (3 or more within a minute): {}",
                    k.chattering.join(", ")
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
    egui::CollapsingHeader::new(format!("Alarm history ({total})"))
        .id_salt("alarm_history")
        .show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                let l = ui.label("Search");
                ui.add(egui::TextEdit::singleline(&mut c.history_filter.text).desired_width(120.0))
                    .labelled_by(l.id);
                egui::ComboBox::from_id_salt("history_kind")
                    .selected_text(c.history_filter.kind.map_or("every kind", AlarmKind::name))
                    .show_ui(ui, |ui| {
                        ui.selectable_value(&mut c.history_filter.kind, None, "every kind");
                        for k in AlarmKind::ALL {
                            ui.selectable_value(&mut c.history_filter.kind, Some(k), k.name());
                        }
                    });
                let prio = |p: Option<AlarmPriority>| {
                    p.map_or("every priority".to_string(), |p| format!("P{}", p.rank()))
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
                ui.label(format!("{} of {total}", list.len()));
                if ui.button("Export alarms CSV").clicked() {
                    out.push(Command::ExportAlarms("vigie-alarms.csv".into()));
                }
                if ui
                    .add_enabled(!c.save.is_open(), egui::Button::new("Save alarms as…"))
                    .clicked()
                {
                    out.push(Command::SaveAs(super::save::Export::Alarms));
                }
            });
            const SHOWN: usize = 100;
            for a in list.iter().take(SHOWN) {
                let cleared = a
                    .cleared
                    .map_or(String::new(), |t| format!(", cleared {}", fmt_ms(t.0)));
                let ack = a.acknowledged.as_ref().map_or(String::new(), |(t, n)| {
                    format!(
                        ", ack {}{}",
                        fmt_ms(t.0),
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
                        a.message
                    ))
                    .size(11.0),
                );
            }
            if list.len() > SHOWN {
                ui.weak(format!(
                    "… {} more: narrow the search or export",
                    list.len() - SHOWN
                ));
            }
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
    let (state_txt, col) = match a.state() {
        AlarmState::Unacknowledged => ("UNACK", c.palette.equipment_edge),
        AlarmState::Acknowledged => ("ACK", c.palette.equipment),
        AlarmState::ClearedUnacknowledged => ("CLEARED-UNACK", c.palette.equipment),
        AlarmState::Normal => ("NORMAL", c.palette.equipment),
    };
    let (prio, prio_bg, prio_fg) = priority_badge(c, a.priority());
    egui::Frame::group(ui.style()).show(ui, |ui| {
        ui.horizontal_wrapped(|ui| {
            ui.label(
                RichText::new(prio)
                    .strong()
                    .color(prio_fg)
                    .background_color(prio_bg),
            );
            if a.first_out {
                ui.label(
                    RichText::new("FIRST OUT")
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
                ui.label(format!(
                    "(shelved until {}: {})",
                    fmt_ms(s.until.0),
                    s.reason
                ));
            }
        });
        ui.label(&a.message);
        if !a.detail.is_empty() {
            egui::CollapsingHeader::new("Detail")
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
                RichText::new(format!("acknowledged at {}: {note}", fmt_ms(t.0)))
                    .color(c.palette.text_dim),
            );
        }
        ui.horizontal_wrapped(|ui| {
            if a.acknowledged.is_none() {
                let note = c.notes.entry(a.id).or_default();
                ui.add(
                    egui::TextEdit::singleline(note)
                        .hint_text("note")
                        .desired_width(120.0),
                );
                if ui.button(format!("Acknowledge #{}", a.id)).clicked() {
                    out.push(Command::Acknowledge {
                        id: a.id,
                        note: note.clone(),
                    });
                }
            }
            if a.is_shelved(now) {
                if ui.button(format!("Unshelve #{}", a.id)).clicked() {
                    out.push(Command::Unshelve(a.id));
                }
            } else if ui
                .add_enabled(
                    a.kind.shelvable(),
                    egui::Button::new(format!("Shelve #{}…", a.id)),
                )
                .on_disabled_hover_text(
                    "A safety alarm (trip, hazard, specification error, live link) is \
                     never shelved",
                )
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
            shelve_form_ui(form, ui, out, &mut c.status);
        }
    });
}

/// The shelving form: a reason (required) and a duration of at most one shift.
fn shelve_form_ui(
    form: &mut ShelveForm,
    ui: &mut egui::Ui,
    out: &mut Vec<Command>,
    status: &mut String,
) {
    ui.horizontal_wrapped(|ui| {
        let l = ui.label("Reason");
        ui.add(
            egui::TextEdit::singleline(&mut form.reason)
                .hint_text("why (required)")
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
        if ui.button(format!("Shelve #{} now", form.id)).clicked() {
            if form.reason.trim().is_empty() {
                *status = "Shelving needs a reason".to_string();
            } else {
                out.push(Command::Shelve {
                    id: form.id,
                    ms: form.minutes * 60_000,
                    reason: form.reason.clone(),
                });
            }
        }
        if ui.button("Cancel").clicked() {
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
    ui.heading("Journal");
    if let Some(p) = c.journal.path() {
        ui.label(
            RichText::new(format!("written to {}", p.display()))
                .small()
                .color(c.palette.text_dim),
        );
    }
    for e in c.journal.entries().iter().rev().take(12) {
        ui.label(
            RichText::new(format!(
                "{:>9}  {:<10} {}",
                fmt_ms(e.sim_ms),
                e.kind,
                e.text
            ))
            .monospace()
            .size(11.0),
        );
    }
    ui.horizontal(|ui| {
        let l = ui.label("CSV file");
        ui.add(egui::TextEdit::singleline(&mut c.csv_path).desired_width(200.0))
            .labelled_by(l.id);
        if ui
            .button("Export CSV")
            .on_hover_text("Written under the data folder")
            .clicked()
        {
            out.push(Command::ExportCsv(c.csv_path.clone().into()));
        }
        if ui
            .add_enabled(!c.save.is_open(), egui::Button::new("Save journal as…"))
            .clicked()
        {
            out.push(Command::SaveAs(super::save::Export::Journal));
        }
    });
    ui.weak(format!(
        "Exports go under {}",
        c.export_path(std::path::Path::new("")).display()
    ));
}

fn training_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    ui.heading("Training");
    ui.label(RichText::new(c.score.summary()).strong());
    if c.score.variant.is_some() {
        ui.horizontal(|ui| {
            if ui
                .button("Verify fix")
                .on_hover_text("Re-run the scenario with the edited program (Maintenance)")
                .clicked()
            {
                out.push(Command::VerifyFix);
            }
            if ui.button("Edit program").clicked() {
                out.push(Command::SetMode(Mode::Maintenance));
            }
        });
    }
    egui::CollapsingHeader::new("Control-error library")
        .default_open(true)
        .show(ui, |ui| {
            for (id, desc, _) in &c.variants {
                ui.horizontal_wrapped(|ui| {
                    let selected = c.score.variant.as_deref() == Some(id.as_str());
                    if ui
                        .selectable_label(selected, format!("Load {id}"))
                        .clicked()
                    {
                        out.push(Command::LoadVariant(id.clone()));
                    }
                    ui.label(RichText::new(desc).small());
                });
            }
        });
    egui::CollapsingHeader::new("Fault library")
        .default_open(false)
        .show(ui, |ui| {
            if c.faults.is_empty() {
                ui.label("No faults.ron in the plant folder.");
            }
            for (i, (name, _)) in c.faults.iter().enumerate() {
                ui.horizontal(|ui| {
                    if ui.button("Inject").clicked() {
                        out.push(Command::InjectFault(i));
                    }
                    ui.label(name);
                });
            }
        });
}

fn maintenance_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let active: BTreeSet<String> = c
        .sim
        .program
        .active_steps()
        .into_iter()
        .map(str::to_string)
        .collect();
    let program = c.sim.program.program().program.clone();
    let pal = c.palette.clone();
    egui::Frame::NONE
        .fill(pal.panel)
        .inner_margin(8.0)
        .show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.heading(format!("Control program: {}", program.name));
                if ui.button("Recompile").clicked() {
                    out.push(Command::Recompile);
                }
                if ui.button("Restart with edit").clicked() {
                    out.push(Command::RestartWithEdit);
                }
                if ui.button("Discard edits").clicked() {
                    out.push(Command::DiscardEdits);
                }
                if ui
                    .button("Verify fix")
                    .on_hover_text("Re-run the scenario headless with the edit")
                    .clicked()
                {
                    out.push(Command::VerifyFix);
                }
            });
            if !c.problems.is_empty() {
                let col = if c.compiled_edit.is_some() {
                    pal.text
                } else {
                    pal.trip
                };
                ui.label(RichText::new(&c.problems).monospace().color(col));
            }
            let Some(draft) = &mut c.draft else {
                return;
            };
            egui::ScrollArea::vertical()
                .auto_shrink([false, false])
                .show(ui, |ui| {
                    for chart in &program.charts {
                        ui.add_space(6.0);
                        ui.label(
                            RichText::new(format!("Chart {}", chart.name))
                                .strong()
                                .size(16.0),
                        );
                        egui::Grid::new(format!("steps-{}", chart.name))
                            .striped(true)
                            .num_columns(3)
                            .show(ui, |ui| {
                                for s in &chart.steps {
                                    let on = active.contains(&s.id);
                                    let txt = RichText::new(format!(
                                        "{}{}",
                                        if s.initial { "[init] " } else { "" },
                                        s.id
                                    ))
                                    .monospace();
                                    let l = ui.label(if on {
                                        txt.strong()
                                            .color(Color32::WHITE)
                                            .background_color(pal.running)
                                    } else {
                                        txt
                                    });
                                    ui.label(if on { "active" } else { "" });
                                    if let Some(a) = draft.actions.get_mut(&s.id) {
                                        ui.add(
                                            egui::TextEdit::singleline(a)
                                                .desired_width(260.0)
                                                .font(egui::TextStyle::Monospace),
                                        )
                                        .labelled_by(l.id);
                                    }
                                    ui.end_row();
                                    for t in
                                        chart.transitions.iter().filter(|t| t.from.contains(&s.id))
                                    {
                                        let l = ui.label(
                                            RichText::new(format!("   + {}", t.id)).monospace(),
                                        );
                                        ui.label(
                                            RichText::new(format!("→ {}", t.to.join(", ")))
                                                .monospace()
                                                .color(pal.text_dim),
                                        );
                                        if let Some(cond) = draft.conditions.get_mut(&t.id) {
                                            ui.add(
                                                egui::TextEdit::singleline(cond)
                                                    .desired_width(260.0)
                                                    .font(egui::TextStyle::Monospace),
                                            )
                                            .labelled_by(l.id);
                                        }
                                        ui.end_row();
                                    }
                                }
                            });
                    }
                    if !draft.equations.is_empty() {
                        ui.add_space(6.0);
                        ui.label(RichText::new("Equations").strong().size(16.0));
                        egui::Grid::new("equations").num_columns(2).show(ui, |ui| {
                            for (target, expr) in &mut draft.equations {
                                let l = ui.label(RichText::new(format!("{target} =")).monospace());
                                ui.add(
                                    egui::TextEdit::singleline(expr)
                                        .desired_width(300.0)
                                        .font(egui::TextStyle::Monospace),
                                )
                                .labelled_by(l.id);
                                ui.end_row();
                            }
                        });
                    }
                });
        });
}

fn chronogram_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let sim = &c.sim;
    let now = sim.now().0;
    ui.horizontal(|ui| {
        ui.label(RichText::new("Chronogram").strong());
        for w in [10u64, 30, 60, 300] {
            if ui
                .selectable_label(c.chrono_window_s == w, format!("{w} s"))
                .clicked()
            {
                c.chrono_window_s = w;
            }
        }
        ui.separator();
        let oldest = sim.engine.history.iter().next().map_or(0, |r| r.time.0);
        let mut t = c.replay.unwrap_or(now);
        let r = ui.add(
            egui::Slider::new(&mut t, oldest..=now.max(oldest))
                .text("Replay")
                .custom_formatter(|v, _| fmt_ms(v as u64)),
        );
        if r.changed() {
            out.push(Command::Scrub(Some(t)));
        }
        if c.replay.is_some() && ui.button("Live").clicked() {
            out.push(Command::Scrub(None));
        }
        ui.menu_button("Signals", |ui| {
            for s in sim
                .bundle
                .plant
                .inputs
                .iter()
                .chain(&sim.bundle.plant.outputs)
            {
                let mut on = c.chrono_signals.contains(&s.id);
                if ui
                    .checkbox(&mut on, format!("{} {}", s.id, s.description))
                    .changed()
                {
                    if on {
                        c.chrono_signals.insert(s.id.clone());
                    } else {
                        c.chrono_signals.remove(&s.id);
                    }
                }
            }
        });
    });
    let size = ui.available_size().max(vec2(100.0, 60.0));
    let (resp, painter) = ui.allocate_painter(size, Sense::click_and_drag());
    resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "Chronogram"));
    let rect = resp.rect;
    let pal = &c.palette;
    painter.rect_filled(rect, 0.0, pal.background);
    let plant = &sim.bundle.plant;
    let rows: Vec<(bool, usize, &str)> = plant
        .inputs
        .iter()
        .enumerate()
        .filter(|(_, s)| c.chrono_signals.contains(&s.id))
        .map(|(i, s)| (true, i, s.id.as_str()))
        .chain(
            plant
                .outputs
                .iter()
                .enumerate()
                .filter(|(_, s)| c.chrono_signals.contains(&s.id))
                .map(|(i, s)| (false, i, s.id.as_str())),
        )
        .collect();
    if rows.is_empty() {
        return;
    }
    let label_w = 40.0;
    #[allow(clippy::cast_precision_loss)]
    let row_h = (rect.height() / rows.len() as f32).min(22.0);
    let window = c.chrono_window_s * 1000;
    let t1 = now.max(window);
    let t0 = t1 - window;
    let plot_w = rect.width() - label_w;
    #[allow(clippy::cast_precision_loss)]
    let x_of =
        |t: u64| rect.left() + label_w + (t.saturating_sub(t0)) as f32 / window as f32 * plot_w;
    let recs: Vec<&vigie_core::history::CycleRecord> = {
        let mut v: Vec<_> = sim
            .engine
            .history
            .iter()
            .rev()
            .take_while(|r| r.time.0 >= t0)
            .collect();
        v.reverse();
        v
    };
    for (k, (input, i, name)) in rows.iter().enumerate() {
        #[allow(clippy::cast_precision_loss)]
        let y = rect.top() + k as f32 * row_h;
        painter.text(
            pos2(rect.left() + 4.0, y + row_h / 2.0),
            Align2::LEFT_CENTER,
            *name,
            FontId::monospace(11.0),
            pal.text,
        );
        painter.line_segment(
            [
                pos2(rect.left() + label_w, y + row_h),
                pos2(rect.right(), y + row_h),
            ],
            Stroke::new(0.5, pal.equipment),
        );
        let get = |r: &vigie_core::history::CycleRecord| {
            if *input {
                r.inputs.get(*i)
            } else {
                r.applied.get(*i)
            }
        };
        let mut start: Option<u64> = None;
        let col = if *input {
            pal.running
        } else {
            pal.equipment_edge
        };
        let flush = |s: u64, e: u64| {
            let r = egui::Rect::from_min_max(
                pos2(x_of(s), y + 3.0),
                pos2(x_of(e).max(x_of(s) + 1.0), y + row_h - 3.0),
            );
            painter.rect_filled(r, 0.0, col);
        };
        for r in &recs {
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
    for t in &sim.engine.trips {
        if t.time_ms >= t0 {
            let x = x_of(t.time_ms);
            painter.line_segment(
                [pos2(x, rect.top()), pos2(x, rect.bottom())],
                Stroke::new(2.0, pal.trip),
            );
            let ids: Vec<&str> = t.constraints.iter().map(|c| c.id.as_str()).collect();
            painter.text(
                pos2(x + 3.0, rect.top() + 2.0),
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
    if let Some(p) = resp.interact_pointer_pos()
        && p.x > rect.left() + label_w
    {
        #[allow(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            clippy::cast_precision_loss
        )]
        let t =
            t0 + (((p.x - rect.left() - label_w) / plot_w).clamp(0.0, 1.0) * window as f32) as u64;
        out.push(Command::Scrub(Some(t.min(now))));
    }
}

/// `12.34 s`.
pub(crate) fn fmt_ms(ms: u64) -> String {
    format!("{}.{:02} s", ms / 1000, (ms % 1000) / 10)
}
