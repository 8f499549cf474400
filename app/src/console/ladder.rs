//! The program's output equations as ladder rungs (IEC 61131-3 LD): an `AND` in series,
//! an `OR` in parallel branches, a name as a normally open contact, a negated name as a
//! normally closed one, `RE(x)` and `FE(x)` as rising and falling edge contacts, the
//! target as a coil. Contacts are drawn with their live state (closed: lit), the coil
//! with the program's command; the equation the hypothesis names is framed. The
//! equation's text is edited beside its rung (a [`Command::EditDraft`]).

use super::{Command, DraftEdit};
use crate::theme::Palette;
use egui::{Pos2, Stroke, Vec2, pos2, vec2};
use vigie_core::expr::{Expr, LeafKind};

/// One contact's cell.
const CELL: Vec2 = vec2(74.0, 46.0);

/// A rung's network: contacts in series and parallel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Net {
    /// A contact: the name, its kind, normally closed.
    Contact(String, LeafKind, bool),
    /// A constant (`1` always closed, `0` always open).
    Const(bool),
    /// In series.
    Series(Vec<Net>),
    /// In parallel.
    Parallel(Vec<Net>),
}

impl Net {
    /// The network of an expression; a negation of more than a name is pushed down to
    /// the names (De Morgan), as an electrician would wire it.
    pub(crate) fn of(e: &Expr) -> Self {
        Self::build(e, false)
    }

    fn build(e: &Expr, negated: bool) -> Self {
        match e {
            Expr::Const(v) => Self::Const(*v != negated),
            Expr::Leaf { name, kind, .. } => Self::Contact(name.clone(), *kind, negated),
            Expr::Not(inner) => Self::build(inner, !negated),
            Expr::And(xs) | Expr::Or(xs) => {
                let parts = xs.iter().map(|x| Self::build(x, negated)).collect();
                if matches!(e, Expr::And(_)) != negated {
                    Self::Series(parts)
                } else {
                    Self::Parallel(parts)
                }
            }
        }
    }

    /// Size in cells (columns, rows).
    pub(crate) fn size(&self) -> (usize, usize) {
        match self {
            Self::Contact(..) | Self::Const(_) => (1, 1),
            Self::Series(xs) => xs.iter().fold((0, 1), |(w, h), x| {
                let (a, b) = x.size();
                (w + a, h.max(b))
            }),
            Self::Parallel(xs) => xs.iter().fold((1, 0), |(w, h), x| {
                let (a, b) = x.size();
                (w.max(a), h + b)
            }),
        }
    }

    /// Whether power flows through, given the contacts' states.
    pub(crate) fn conducts(&self, state: &dyn Fn(&str, LeafKind) -> Option<bool>) -> bool {
        match self {
            Self::Const(v) => *v,
            Self::Contact(n, k, nc) => state(n, *k).is_some_and(|v| v != *nc),
            Self::Series(xs) => xs.iter().all(|x| x.conducts(state)),
            Self::Parallel(xs) => xs.iter().any(|x| x.conducts(state)),
        }
    }
}

/// Paints `net` from `at` (its top-left cell) over `width` cells; returns nothing, the
/// painter keeps it. The rails between cells are drawn lit when the element conducts.
fn paint(
    painter: &egui::Painter,
    net: &Net,
    at: Pos2,
    width: usize,
    state: &dyn Fn(&str, LeafKind) -> Option<bool>,
    pal: &Palette,
) {
    let mid = |p: Pos2| p.y + CELL.y / 2.0;
    let wire = |on: bool| Stroke::new(2.0, if on { pal.running } else { pal.text_dim });
    match net {
        Net::Const(v) => {
            let y = mid(at);
            painter.line_segment(
                [pos2(at.x, y), pos2(at.x + width as f32 * CELL.x, y)],
                wire(*v),
            );
        }
        Net::Contact(name, kind, nc) => {
            let y = mid(at);
            let closed = state(name, *kind).is_some_and(|v| v != *nc);
            let x0 = at.x;
            let x1 = at.x + width as f32 * CELL.x;
            let c = at.x + CELL.x / 2.0;
            painter.line_segment([pos2(x0, y), pos2(c - 8.0, y)], wire(closed));
            painter.line_segment([pos2(c + 8.0, y), pos2(x1, y)], wire(closed));
            let col = if closed { pal.running } else { pal.text };
            let s = Stroke::new(2.5, col);
            painter.line_segment([pos2(c - 8.0, y - 10.0), pos2(c - 8.0, y + 10.0)], s);
            painter.line_segment([pos2(c + 8.0, y - 10.0), pos2(c + 8.0, y + 10.0)], s);
            match (nc, kind) {
                (true, _) => {
                    painter.line_segment([pos2(c - 9.0, y + 10.0), pos2(c + 9.0, y - 10.0)], s);
                }
                (false, LeafKind::Rise) => {
                    painter.text(
                        pos2(c, y),
                        egui::Align2::CENTER_CENTER,
                        "P",
                        egui::FontId::monospace(11.0),
                        col,
                    );
                }
                (false, LeafKind::Fall) => {
                    painter.text(
                        pos2(c, y),
                        egui::Align2::CENTER_CENTER,
                        "N",
                        egui::FontId::monospace(11.0),
                        col,
                    );
                }
                _ => {}
            }
            let label = match kind {
                LeafKind::Prev => format!("{name}*"),
                LeafKind::Estimate => format!("EST({name})"),
                _ => name.clone(),
            };
            painter.text(
                pos2(c, y - 13.0),
                egui::Align2::CENTER_BOTTOM,
                label,
                egui::FontId::monospace(12.0),
                pal.text,
            );
        }
        Net::Series(xs) => {
            let mut x = at.x;
            let (total, _) = net.size();
            let n = xs.len();
            for (i, part) in xs.iter().enumerate() {
                let (w, _) = part.size();
                // The last element stretches to the width given.
                let w = if i + 1 == n { w + width - total } else { w };
                paint(painter, part, pos2(x, at.y), w, state, pal);
                x += w as f32 * CELL.x;
            }
        }
        Net::Parallel(xs) => {
            let mut y = at.y;
            let x1 = at.x + width as f32 * CELL.x;
            let top = mid(at);
            let mut bottom = top;
            for part in xs {
                paint(painter, part, pos2(at.x, y), width, state, pal);
                bottom = mid(pos2(at.x, y));
                y += part.size().1 as f32 * CELL.y;
            }
            let on = net.conducts(state);
            painter.line_segment([pos2(at.x, top), pos2(at.x, bottom)], wire(on));
            painter.line_segment([pos2(x1, top), pos2(x1, bottom)], wire(on));
        }
    }
}

/// The ladder view: one rung per equation, its text editable beside it.
pub(crate) fn ladder_ui(
    ui: &mut egui::Ui,
    equations: &[(String, String)],
    state: &dyn Fn(&str, LeafKind) -> Option<bool>,
    suspects: &std::collections::BTreeSet<String>,
    (i18n, pal): (&crate::i18n::I18n, &Palette),
    out: &mut Vec<Command>,
) {
    for (target, text) in equations {
        let marked = suspects.contains(target);
        ui.horizontal(|ui| {
            ui.label(
                egui::RichText::new(format!("{target} ="))
                    .monospace()
                    .strong(),
            );
            let mut t = text.clone();
            let name = i18n.ta("maint-edit-equation", &[("id", target.into())]);
            let r = ui.add(
                egui::TextEdit::singleline(&mut t)
                    .font(egui::TextStyle::Monospace)
                    .desired_width(420.0),
            );
            ui.ctx()
                .accesskit_node_builder(r.id, |node| node.set_label(name.clone()));
            if r.changed() {
                out.push(Command::EditDraft(DraftEdit::Equation {
                    target: target.clone(),
                    text: t,
                }));
            }
            if marked {
                ui.label(
                    egui::RichText::new(i18n.t("grafcet-suspect"))
                        .color(pal.trip)
                        .strong(),
                );
            }
        });
        let net = match vigie_core::expr::parse_str(text) {
            Ok(e) => Net::of(&e),
            Err(e) => {
                ui.label(egui::RichText::new(e.to_string()).color(pal.trip));
                continue;
            }
        };
        let (w, h) = net.size();
        let size = vec2((w + 2) as f32 * CELL.x, h as f32 * CELL.y + 8.0);
        let (resp, painter) = ui.allocate_painter(size, egui::Sense::hover());
        let r = resp.rect;
        let energized = state(target, LeafKind::Now).unwrap_or(false);
        let label = i18n.ta(
            "ladder-rung",
            &[
                ("target", target.into()),
                (
                    "state",
                    (&i18n.t(if energized { "ladder-on" } else { "ladder-off" })).into(),
                ),
            ],
        );
        resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Label, true, &label));
        // Left and right rails.
        let rail = Stroke::new(3.0, pal.text);
        painter.line_segment(
            [
                r.left_top() + vec2(4.0, 0.0),
                r.left_bottom() + vec2(4.0, 0.0),
            ],
            rail,
        );
        painter.line_segment(
            [
                r.right_top() - vec2(4.0, 0.0),
                r.right_bottom() - vec2(4.0, 0.0),
            ],
            rail,
        );
        let at = r.left_top() + vec2(4.0 + CELL.x * 0.5, 4.0);
        paint(&painter, &net, at, w, state, pal);
        // The coil.
        let y = at.y + CELL.y / 2.0;
        let cx = at.x + w as f32 * CELL.x + CELL.x * 0.5;
        let flows = net.conducts(state);
        let wire = Stroke::new(2.0, if flows { pal.running } else { pal.text_dim });
        painter.line_segment([pos2(at.x - CELL.x * 0.5 + 0.0, y), pos2(at.x, y)], wire);
        painter.line_segment(
            [pos2(at.x + w as f32 * CELL.x, y), pos2(cx - 12.0, y)],
            wire,
        );
        painter.line_segment([pos2(cx + 12.0, y), pos2(r.right() - 4.0, y)], wire);
        let coil = if energized { pal.running } else { pal.text };
        painter.circle_stroke(pos2(cx, y), 12.0, Stroke::new(2.5, coil));
        if energized {
            painter.circle_filled(pos2(cx, y), 6.0, pal.running);
        }
        painter.text(
            pos2(cx, y - 15.0),
            egui::Align2::CENTER_BOTTOM,
            target,
            egui::FontId::monospace(12.0),
            pal.text,
        );
        if marked {
            painter.rect_stroke(r, 3.0, Stroke::new(2.5, pal.trip), egui::StrokeKind::Inside);
        }
        ui.add_space(6.0);
    }
}

/// The value of a contact in the program's state after its last scan.
pub(crate) fn contact_state(
    rt: &vigie_core::control::ProgramRuntime,
    name: &str,
    kind: LeafKind,
) -> Option<bool> {
    let now = rt.value(name)?;
    let prev = rt.previous_value(name)?;
    Some(match kind {
        LeafKind::Now | LeafKind::Estimate => now,
        LeafKind::Prev => prev,
        LeafKind::Rise => now && !prev,
        LeafKind::Fall => !now && prev,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn net(text: &str) -> Net {
        Net::of(&vigie_core::expr::parse_str(text).unwrap())
    }

    #[test]
    fn a_sum_of_products_is_parallel_branches_of_series_contacts() {
        let n = net("X11 + X1 . /C0");
        assert_eq!(
            n,
            Net::Parallel(vec![
                Net::Contact("X11".into(), LeafKind::Now, false),
                Net::Series(vec![
                    Net::Contact("X1".into(), LeafKind::Now, false),
                    Net::Contact("C0".into(), LeafKind::Now, true),
                ]),
            ])
        );
        assert_eq!(n.size(), (2, 2));
        // Power flows through the second branch only when X1 is on and C0 off.
        let state = |x1: bool, c0: bool| {
            move |name: &str, _: LeafKind| match name {
                "X11" => Some(false),
                "X1" => Some(x1),
                "C0" => Some(c0),
                _ => None,
            }
        };
        assert!(n.conducts(&state(true, false)));
        assert!(!n.conducts(&state(true, true)));
        assert!(!n.conducts(&state(false, false)));
    }

    #[test]
    fn a_negated_group_is_wired_by_de_morgan_and_edges_keep_their_kind() {
        assert_eq!(
            net("/(A . RE(B))"),
            Net::Parallel(vec![
                Net::Contact("A".into(), LeafKind::Now, true),
                Net::Contact("B".into(), LeafKind::Rise, true),
            ])
        );
        assert_eq!(net("1"), Net::Const(true));
        assert_eq!(net("/1"), Net::Const(false));
        // Every size is at least one cell, a series of parallels as wide as its parts.
        assert_eq!(net("(A + B) . (C + D + E)").size(), (2, 3));
    }
}
