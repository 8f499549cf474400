//! The control program as a GRAFCET (IEC 60848): steps (double frame for an initial
//! step), transitions as bars with their receptivity, actions in boxes beside their
//! step, selection divergences as a single line, simultaneous ones as a double line,
//! jumps back up as an arrow with the target step's name. Active steps are lit and
//! carry a token; the suspects of the hypothesis are framed. Receptivities and actions
//! are edited in place: every edit goes out as a [`Command::EditDraft`].
//!
//! The geometry is computed first ([`layout`], pure and tested), then painted.

use super::{Command, Draft, DraftEdit};
use crate::theme::Palette;
use egui::{Color32, Pos2, Rect, RichText, Stroke, Vec2, pos2, vec2};
use std::collections::{BTreeMap, BTreeSet};
use vigie_core::control::program::Chart;

/// Width of one column of the chart (a step, its actions and its receptivities).
pub(crate) const COLUMN_W: f32 = 430.0;
/// A step's square.
pub(crate) const STEP: f32 = 38.0;
/// The action box's left edge, from the step's left edge.
const ACTION_X: f32 = STEP + 24.0;
/// The action box's width.
const ACTION_W: f32 = 230.0;
/// The receptivity's left edge, from the step's left edge.
const RECEPTIVITY_X: f32 = STEP / 2.0 + 26.0;
/// The receptivity field's width.
pub(crate) const RECEPTIVITY_W: f32 = 330.0;
/// Height of a transition's zone below a step.
const TRANSITION_H: f32 = 56.0;
/// Margin around the chart (the left one holds the transitions' names).
const MARGIN: f32 = 12.0;
/// Left margin: the transitions' names stand left of their bar.
const MARGIN_LEFT: f32 = 56.0;
/// Width of one character of the monospace font the texts are edited in.
const CHAR_W: f32 = 8.4;

/// Where a chart's elements go.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ChartLayout {
    /// Step id → its square.
    pub steps: BTreeMap<String, Rect>,
    /// Transition id → its bar's centre, and the column it stands in.
    pub transitions: BTreeMap<String, (Pos2, usize)>,
    /// Transition id → its receptivity's rectangle.
    pub receptivities: BTreeMap<String, Rect>,
    /// Step id → its action box.
    pub actions: BTreeMap<String, Rect>,
    /// Transition id → the targets reached by a jump (drawn as an arrow and a name),
    /// not by a line.
    pub jumps: BTreeMap<String, Vec<String>>,
    /// The chart's size.
    pub size: Vec2,
}

impl ChartLayout {
    /// Every rectangle that must not overlap another: steps, actions, receptivities.
    #[cfg(test)]
    pub(crate) fn boxes(&self) -> Vec<(String, Rect)> {
        let steps = self.steps.iter().map(|(k, r)| (format!("step {k}"), *r));
        let actions = self
            .actions
            .iter()
            .map(|(k, r)| (format!("actions {k}"), *r));
        let rec = self
            .receptivities
            .iter()
            .map(|(k, r)| (format!("receptivity {k}"), *r));
        steps.chain(actions).chain(rec).collect()
    }
}

/// Places `chart`'s steps in columns and rows: the steps in the order they are reached
/// from the initial ones, the first target of a transition below its step, every other
/// branch (a selection or a simultaneous divergence) in a new column to the right, a
/// step already placed reached by a jump.
pub(crate) fn layout(chart: &Chart, texts: &Draft) -> ChartLayout {
    let cells = place(chart);
    geometry(chart, texts, &cells)
}

/// The cells (column, row) of the steps and of the transitions, and the jumps.
struct Cells {
    steps: BTreeMap<String, (usize, usize)>,
    transitions: BTreeMap<String, (usize, usize)>,
    jumps: BTreeMap<String, Vec<String>>,
}

fn place(chart: &Chart) -> Cells {
    let mut cell: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    let mut t_cell: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    let mut jumps: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut next_col = 0usize;
    let mut queue = std::collections::VecDeque::new();
    let initial: Vec<&str> = chart
        .steps
        .iter()
        .filter(|s| s.initial)
        .map(|s| s.id.as_str())
        .collect();
    let roots: Vec<&str> = if initial.is_empty() {
        chart
            .steps
            .first()
            .map(|s| s.id.as_str())
            .into_iter()
            .collect()
    } else {
        initial
    };

    // Every step is placed: the unreached ones start new columns at the top.
    let mut pending: Vec<&str> = roots.clone();
    pending.extend(
        chart
            .steps
            .iter()
            .map(|s| s.id.as_str())
            .filter(|id| !roots.contains(id)),
    );
    for root in pending {
        if cell.contains_key(root) {
            continue;
        }
        cell.insert(root.to_string(), (next_col, 0));
        queue.push_back(root.to_string());
        next_col += 1;
        while let Some(step) = queue.pop_front() {
            let (col, row) = cell[&step];
            let outgoing: Vec<_> = chart
                .transitions
                .iter()
                .filter(|t| t.from.first() == Some(&step))
                .collect();
            for (k, t) in outgoing.into_iter().enumerate() {
                let t_col = if k == 0 {
                    col
                } else {
                    next_col += 1;
                    next_col - 1
                };
                t_cell.insert(t.id.clone(), (t_col, row));
                for (j, target) in t.to.iter().enumerate() {
                    if cell.contains_key(target) {
                        jumps.entry(t.id.clone()).or_default().push(target.clone());
                        continue;
                    }
                    let c = if j == 0 {
                        t_col
                    } else {
                        next_col += 1;
                        next_col - 1
                    };
                    cell.insert(target.clone(), (c, row + 1));
                    queue.push_back(target.clone());
                }
            }
        }
    }
    // Transitions whose first upstream step is not in the chart (none are, once the
    // program compiled; kept safe): under their first placed upstream step.
    for t in &chart.transitions {
        if !t_cell.contains_key(&t.id)
            && let Some(&(c, r)) = t.from.iter().find_map(|s| cell.get(s))
        {
            t_cell.insert(t.id.clone(), (c, r));
            for target in &t.to {
                jumps.entry(t.id.clone()).or_default().push(target.clone());
            }
        }
    }
    Cells {
        steps: cell,
        transitions: t_cell,
        jumps,
    }
}

/// Pixels from cells: columns as wide as the longest text, rows of one step and one
/// transition.
fn geometry(chart: &Chart, texts: &Draft, cells: &Cells) -> ChartLayout {
    let (cell, t_cell) = (&cells.steps, &cells.transitions);
    let jumps = cells.jumps.clone();
    let rows = cell.values().map(|(_, r)| r + 1).max().unwrap_or(1);
    let cols = cell
        .values()
        .map(|(c, _)| c + 1)
        .chain(t_cell.values().map(|(c, _)| c + 1))
        .max()
        .unwrap_or(1);
    let row_h = STEP + TRANSITION_H;
    // Receptivities are never cut: the columns widen to the longest one (monospace).
    let longest = chart
        .transitions
        .iter()
        .map(|t| {
            texts
                .conditions
                .get(&t.id)
                .unwrap_or(&t.condition)
                .chars()
                .count()
        })
        .max()
        .unwrap_or(0);
    let receptivity_w = RECEPTIVITY_W.max(longest as f32 * CHAR_W + 24.0);
    let longest_action = chart
        .steps
        .iter()
        .filter_map(|s| texts.actions.get(&s.id))
        .map(|a| a.chars().count())
        .max()
        .unwrap_or(0);
    let action_w = ACTION_W.max(longest_action as f32 * CHAR_W + 16.0);
    let column_w = COLUMN_W
        .max(RECEPTIVITY_X + receptivity_w + 40.0)
        .max(ACTION_X + action_w + 40.0);
    let origin = |col: usize, row: usize| {
        pos2(
            MARGIN_LEFT + col as f32 * column_w,
            MARGIN + row as f32 * row_h,
        )
    };
    let mut out = ChartLayout {
        jumps,
        size: vec2(
            MARGIN_LEFT + MARGIN + cols as f32 * column_w,
            2.0 * MARGIN + rows as f32 * row_h + 8.0,
        ),
        ..ChartLayout::default()
    };
    for s in &chart.steps {
        let Some(&(c, r)) = cell.get(&s.id) else {
            continue;
        };
        let o = origin(c, r);
        out.steps
            .insert(s.id.clone(), Rect::from_min_size(o, Vec2::splat(STEP)));
        if !s.actions.is_empty() {
            out.actions.insert(
                s.id.clone(),
                Rect::from_min_size(o + vec2(ACTION_X, 4.0), vec2(action_w, STEP - 8.0)),
            );
        }
    }
    for t in &chart.transitions {
        let Some(&(c, r)) = t_cell.get(&t.id) else {
            continue;
        };
        let o = origin(c, r);
        let bar = o + vec2(STEP / 2.0, STEP + TRANSITION_H / 2.0);
        out.transitions.insert(t.id.clone(), (bar, c));
        out.receptivities.insert(
            t.id.clone(),
            Rect::from_min_size(
                pos2(o.x + RECEPTIVITY_X, bar.y - 12.0),
                vec2(receptivity_w, 24.0),
            ),
        );
    }
    out
}

/// What the chart view shows live.
pub(crate) struct Live<'a> {
    /// Active steps.
    pub active: &'a BTreeSet<String>,
    /// Program elements named by the hypothesis (steps, transitions).
    pub suspects: &'a BTreeSet<String>,
    /// The element the hypothesis link asked to show (framed).
    pub focus: Option<&'a str>,
    /// Scroll it into view this frame (once, after the link: the technician then
    /// scrolls freely).
    pub scroll: bool,
}

/// Paints one chart and its in-place editors; edits go to `out`.
pub(crate) fn chart_ui(
    ui: &mut egui::Ui,
    chart: &Chart,
    draft: &Draft,
    live: &Live<'_>,
    (i18n, pal): (&crate::i18n::I18n, &Palette),
    out: &mut Vec<Command>,
) {
    let geometry = layout(chart, draft);
    let (resp, painter) = ui.allocate_painter(geometry.size, egui::Sense::hover());
    let o = resp.rect.min.to_vec2();
    let focus = live.focus;
    let p = Paint {
        painter: &painter,
        o,
        geometry: &geometry,
        live,
        i18n,
        pal,
    };
    // Links: step → its transitions → their targets.
    for t in &chart.transitions {
        transition_ui(ui, &p, t);
    }
    // Steps and their actions.
    for s in &chart.steps {
        step_ui(ui, &p, s, draft, out);
    }
    // Receptivities, edited in place.
    for t in &chart.transitions {
        let (Some(rect), Some(text)) = (
            geometry.receptivities.get(&t.id),
            draft.conditions.get(&t.id),
        ) else {
            continue;
        };
        let marked = live.suspects.contains(&t.id) || focus == Some(t.id.as_str());
        let name = i18n.ta("maint-edit-condition", &[("id", (&t.id).into())]);
        let mut c = text.clone();
        if edit_in_place(
            ui,
            rect.translate(o),
            &mut c,
            &name,
            marked.then_some(pal.trip),
        ) {
            out.push(Command::EditDraft(DraftEdit::Condition {
                transition: t.id.clone(),
                text: c,
            }));
        }
    }
    // The focused element into view, its step and bar at the left of the view.
    if live.scroll
        && let Some(f) = focus
    {
        let at = geometry
            .transitions
            .get(f)
            .map(|(bar, _)| *bar)
            .or_else(|| geometry.steps.get(f).map(|r| r.center()));
        if let Some(at) = at {
            let view = Rect::from_min_max(pos2(0.0, at.y - 90.0), pos2(at.x + 260.0, at.y + 90.0))
                .translate(o);
            ui.scroll_to_rect(view, Some(egui::Align::Center));
        }
    }
}

/// What the painters of one chart share.
struct Paint<'a> {
    painter: &'a egui::Painter,
    o: Vec2,
    geometry: &'a ChartLayout,
    live: &'a Live<'a>,
    i18n: &'a crate::i18n::I18n,
    pal: &'a Palette,
}

/// One transition: the links from its step and to its targets, its bar and its name.
fn transition_ui(ui: &mut egui::Ui, p: &Paint<'_>, t: &vigie_core::control::program::Transition) {
    let (painter, o, geometry, live, i18n, pal) =
        (p.painter, p.o, p.geometry, p.live, p.i18n, p.pal);
    let line = Stroke::new(1.6, pal.text);
    let focus = live.focus;
    let Some(&(bar, col)) = geometry.transitions.get(&t.id) else {
        return;
    };
    let bar = bar + o;
    if let Some(from) = t.from.first().and_then(|s| geometry.steps.get(s)) {
        let from = from.translate(o);
        let top = pos2(from.center().x, from.bottom());
        if (bar.x - top.x).abs() < 0.5 {
            painter.line_segment([top, bar], line);
        } else {
            // A selection divergence: a single horizontal line under the step.
            let y = top.y + 8.0;
            painter.line_segment([top, pos2(top.x, y)], line);
            painter.line_segment([pos2(top.x, y), pos2(bar.x, y)], line);
            painter.line_segment([pos2(bar.x, y), bar], line);
        }
    }
    // Other upstream steps (a convergence): named above the bar.
    if t.from.len() > 1 {
        painter.text(
            bar + vec2(-6.0, -18.0),
            egui::Align2::RIGHT_BOTTOM,
            format!("{} ·", t.from[1..].join(" · ")),
            egui::FontId::proportional(12.0),
            pal.text_dim,
        );
    }
    let placed: Vec<&String> =
        t.to.iter()
            .filter(|s| !geometry.jumps.get(&t.id).is_some_and(|j| j.contains(s)))
            .collect();
    let below = bar.y + TRANSITION_H / 2.0;
    if placed.len() > 1 {
        // A simultaneous divergence: a double line, then each branch.
        let xs: Vec<f32> = placed
            .iter()
            .filter_map(|s| geometry.steps.get(*s))
            .map(|r| r.translate(o).center().x)
            .collect();
        let (lo, hi) = xs
            .iter()
            .fold((bar.x, bar.x), |(a, b), x| (a.min(*x), b.max(*x)));
        let y = below - 8.0;
        painter.line_segment([bar, pos2(bar.x, y - 2.0)], line);
        painter.line_segment([pos2(lo, y - 2.0), pos2(hi, y - 2.0)], line);
        painter.line_segment([pos2(lo, y + 2.0), pos2(hi, y + 2.0)], line);
        for x in xs {
            painter.line_segment([pos2(x, y + 2.0), pos2(x, below)], line);
        }
    } else if let Some(target) = placed.first().and_then(|s| geometry.steps.get(*s)) {
        let target = target.translate(o);
        painter.line_segment([bar, pos2(bar.x, below)], line);
        if (target.center().x - bar.x).abs() > 0.5 {
            painter.line_segment([pos2(bar.x, below), pos2(target.center().x, below)], line);
        }
    }
    // Jumps: an arrow down and the step's name.
    if let Some(targets) = geometry.jumps.get(&t.id) {
        let end = pos2(bar.x, bar.y + 20.0);
        painter.arrow(bar, end - bar, line);
        painter.text(
            end + vec2(6.0, 0.0),
            egui::Align2::LEFT_CENTER,
            targets.join(", "),
            egui::FontId::monospace(13.0),
            pal.text,
        );
    }
    // The bar, framed when suspect.
    let marked = live.suspects.contains(&t.id) || focus == Some(t.id.as_str());
    painter.line_segment(
        [bar - vec2(14.0, 0.0), bar + vec2(14.0, 0.0)],
        Stroke::new(4.0, if marked { pal.trip } else { pal.text }),
    );
    painter.text(
        bar - vec2(18.0, 0.0),
        egui::Align2::RIGHT_CENTER,
        &t.id,
        egui::FontId::monospace(12.0),
        pal.text_dim,
    );
    let label = format!(
        "{} {}{}",
        i18n.t("grafcet-transition"),
        t.id,
        if marked {
            format!(", {}", i18n.t("grafcet-suspect"))
        } else {
            String::new()
        }
    );
    let hit = Rect::from_center_size(bar, vec2(32.0, 10.0));
    ui.interact(
        hit,
        ui.scope_id().with(("transition", &t.id, col)),
        egui::Sense::hover(),
    )
    .widget_info(|| egui::WidgetInfo::labeled(egui::Role::Label, true, &label));
}

/// One step: its square (lit when active, framed when suspect) and its actions' editor.
fn step_ui(
    ui: &mut egui::Ui,
    p: &Paint<'_>,
    s: &vigie_core::control::program::Step,
    draft: &Draft,
    out: &mut Vec<Command>,
) {
    let (painter, o, geometry, live, i18n, pal) =
        (p.painter, p.o, p.geometry, p.live, p.i18n, p.pal);
    let line = Stroke::new(1.6, pal.text);
    let suspect = Stroke::new(3.0, pal.trip);
    let focus = live.focus;
    let Some(r) = geometry.steps.get(&s.id) else {
        return;
    };
    let r = r.translate(o);
    let on = live.active.contains(&s.id);
    let marked = live.suspects.contains(&s.id) || focus == Some(s.id.as_str());
    painter.rect_filled(r, 2.0, if on { pal.running } else { pal.panel });
    painter.rect_stroke(r, 2.0, line, egui::StrokeKind::Inside);
    if s.initial {
        painter.rect_stroke(r.shrink(4.0), 1.0, line, egui::StrokeKind::Inside);
    }
    if marked {
        painter.rect_stroke(r.expand(4.0), 3.0, suspect, egui::StrokeKind::Outside);
    }
    painter.text(
        r.center(),
        egui::Align2::CENTER_CENTER,
        &s.id,
        egui::FontId::monospace(13.0),
        if on { Color32::WHITE } else { pal.text },
    );
    if on {
        painter.circle_filled(r.left_top() + vec2(7.0, 7.0), 3.5, Color32::WHITE);
    }
    let label = format!(
        "{} {}{}{}",
        i18n.t("grafcet-step"),
        s.id,
        if on {
            format!(", {}", i18n.t("maint-active"))
        } else {
            String::new()
        },
        if marked {
            format!(", {}", i18n.t("grafcet-suspect"))
        } else {
            String::new()
        }
    );
    let id = ui.scope_id().with(("step", &s.id));
    let step_resp = ui.interact(r, id, egui::Sense::hover());
    step_resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Label, true, &label));
    if let (Some(a), Some(text)) = (geometry.actions.get(&s.id), draft.actions.get(&s.id)) {
        let a = a.translate(o);
        painter.line_segment(
            [pos2(r.right(), r.center().y), pos2(a.left(), r.center().y)],
            line,
        );
        let name = i18n.ta("maint-edit-actions", &[("id", (&s.id).into())]);
        let mut t = text.clone();
        if edit_in_place(ui, a, &mut t, &name, marked.then_some(pal.trip)) {
            out.push(Command::EditDraft(DraftEdit::Actions {
                step: s.id.clone(),
                text: t,
            }));
        }
    }
}

/// A one-line editor at `rect` whose accessible name is `name`, framed in `mark` when
/// the hypothesis names it; true when edited.
fn edit_in_place(
    ui: &mut egui::Ui,
    rect: Rect,
    text: &mut String,
    name: &str,
    mark: Option<Color32>,
) -> bool {
    let r = ui.put(
        rect,
        egui::TextEdit::singleline(text)
            .font(egui::TextStyle::Monospace)
            .desired_width(rect.width()),
    );
    if let Some(c) = mark {
        ui.painter().rect_stroke(
            r.rect.expand(2.0),
            2.0,
            Stroke::new(2.5, c),
            egui::StrokeKind::Outside,
        );
    }
    let full = text.clone();
    r.clone().on_hover_text(RichText::new(full).monospace());
    ui.ctx()
        .accesskit_node_builder(r.id, |node| node.set_label(name.to_string()));
    r.changed()
}

#[cfg(test)]
mod tests {
    use super::super::Draft;
    use super::*;
    use vigie_core::control::Program;

    fn reference() -> Program {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../layouts/sorting-station/programs/reference.ron");
        Program::from_ron(&std::fs::read_to_string(&path).unwrap(), &path).unwrap()
    }

    /// Every chart of the reference program: every step and transition placed, no two
    /// boxes overlap, a selection divergence puts its branches side by side, and a
    /// loop back to the initial step is a jump.
    #[test]
    fn the_reference_charts_are_laid_out_without_overlap() {
        for chart in &reference().charts {
            let g = layout(chart, &Draft::of(&reference()));
            assert_eq!(g.steps.len(), chart.steps.len(), "{}", chart.name);
            assert_eq!(
                g.transitions.len(),
                chart.transitions.len(),
                "{}",
                chart.name
            );
            let boxes = g.boxes();
            for (i, (a, ra)) in boxes.iter().enumerate() {
                assert!(
                    Rect::from_min_size(Pos2::ZERO, g.size).contains_rect(*ra),
                    "{}: {a} outside the chart",
                    chart.name
                );
                for (b, rb) in &boxes[i + 1..] {
                    assert!(!ra.intersects(*rb), "{}: {a} overlaps {b}", chart.name);
                }
            }
            // Every transition's bar is below its first upstream step.
            for t in &chart.transitions {
                let step = g.steps[&t.from[0]];
                let (bar, _) = g.transitions[&t.id];
                assert!(bar.y > step.bottom(), "{}", t.id);
            }
        }
        let table = reference()
            .charts
            .into_iter()
            .find(|c| c.transitions.iter().any(|t| t.id == "t20L"))
            .expect("the table chart");
        let g = layout(&table, &Draft::of(&reference()));
        // The two branches of the selection (right, left) side by side, in one row.
        let (r, l) = (g.steps["X21"], g.steps["X31"]);
        assert_eq!(r.top(), l.top());
        assert!(l.left() >= r.right() + COLUMN_W - STEP - 1.0);
        // No receptivity is cut: each field holds its whole text.
        let draft = Draft::of(&reference());
        for (t, rect) in &g.receptivities {
            let chars = draft.conditions[t].chars().count() as f32;
            assert!(
                rect.width() >= chars * CHAR_W,
                "{t}: {} px for {chars} chars",
                rect.width()
            );
        }
        // The loop back to X20 is a jump.
        assert!(
            g.jumps.values().flatten().any(|s| s == "X20"),
            "{:?}",
            g.jumps
        );
    }

    /// A simultaneous divergence puts each target in its own column, side by side.
    #[test]
    fn a_simultaneous_divergence_opens_two_columns() {
        let chart: Chart = ron::from_str(
            r#"(name: "and", steps: [(id: "S0", initial: true), (id: "S1"), (id: "S2"), (id: "S3")],
                transitions: [
                    (id: "a", from: ["S0"], to: ["S1", "S2"], condition: "C0"),
                    (id: "b", from: ["S1", "S2"], to: ["S3"], condition: "C1"),
                    (id: "c", from: ["S3"], to: ["S0"], condition: "C2"),
                ])"#,
        )
        .unwrap();
        let g = layout(&chart, &Draft::default());
        assert_eq!(g.steps["S1"].top(), g.steps["S2"].top());
        assert!(g.steps["S2"].left() > g.steps["S1"].right());
        assert!(g.steps["S3"].top() > g.steps["S1"].bottom());
        assert_eq!(g.jumps["c"], ["S0"]);
        let boxes = g.boxes();
        for (i, (a, ra)) in boxes.iter().enumerate() {
            for (b, rb) in &boxes[i + 1..] {
                assert!(!ra.intersects(*rb), "{a} overlaps {b}");
            }
        }
    }
}
