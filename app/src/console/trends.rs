//! Trends: the process history of any signal over minutes to days, read from the
//! historian and drawn as a digital timing diagram (egui_plot), one row per signal.
//!
//! The view queries the historian at most once a second (or when the signals or the
//! range change), in at most one bucket per pixel column; a bucket in which a signal
//! went both ways is drawn as a bar.

use super::save::Export;
use super::{Command, Console};
use crate::historian::writer::signal_names;
use egui::RichText;
use egui_plot::{Line, Plot, PlotPoints};

/// The ranges offered: ms, and the message of the label.
pub(crate) const RANGES: [(u64, &str); 6] = [
    (60_000, "trends-1-min"),
    (600_000, "trends-10-min"),
    (3_600_000, "trends-1-h"),
    (8 * 3_600_000, "trends-8-h"),
    (24 * 3_600_000, "trends-1-day"),
    (7 * 24 * 3_600_000, "trends-7-days"),
];

/// Rows shown at most.
pub(crate) const MAX_SIGNALS: usize = 12;

/// What the trends view shows.
#[derive(Debug)]
pub struct TrendView {
    /// The central panel shows the trends rather than the synoptic.
    pub shown: bool,
    /// The signals plotted, top to bottom.
    pub signals: Vec<String>,
    /// The range, ms, ending now.
    pub range_ms: u64,
    /// The signal list's filter.
    pub filter: String,
    /// The last query: its key and its points per signal (x in s before now).
    cache: Option<(CacheKey, Vec<SignalPoints>)>,
    /// The last error of a query.
    pub error: Option<String>,
}

/// A signal and its points (x in s before now).
type SignalPoints = (String, Vec<[f64; 2]>);

#[derive(Clone, Debug, PartialEq, Eq)]
struct CacheKey {
    signals: Vec<String>,
    range_ms: u64,
    /// The query's second.
    second: u64,
    buckets: u32,
}

impl TrendView {
    /// The first few inputs of the plant (its sensors) by default.
    pub fn new(symbols: &vigie_core::symbols::Symbols) -> Self {
        Self {
            shown: false,
            signals: symbols
                .names(vigie_core::symbols::Space::Input)
                .iter()
                .take(6)
                .cloned()
                .collect(),
            range_ms: 600_000,
            filter: String::new(),
            cache: None,
            error: None,
        }
    }

    /// Queries the points to draw again when they are stale (other signals, range or
    /// width, or a second later).
    fn refresh(&mut self, store: &crate::historian::Store, now_ms: u64, buckets: u32) {
        let key = CacheKey {
            signals: self.signals.clone(),
            range_ms: self.range_ms,
            second: now_ms / 1000,
            buckets,
        };
        if self.cache.as_ref().is_none_or(|(k, _)| *k != key) {
            let from = now_ms.saturating_sub(self.range_ms);
            let mut rows = Vec::new();
            self.error = None;
            for s in &self.signals {
                match store.trend(s, from, now_ms + 1, buckets) {
                    Ok(t) => {
                        #[allow(clippy::cast_precision_loss)]
                        let pts = t
                            .steps(from, now_ms)
                            .into_iter()
                            .map(|(t, v)| [-((now_ms.saturating_sub(t)) as f64) / 1000.0, v as f64])
                            .collect();
                        rows.push((s.clone(), pts));
                    }
                    Err(e) => {
                        self.error = Some(e.to_string());
                        rows.push((s.clone(), Vec::new()));
                    }
                }
            }
            self.cache = Some((key, rows));
        }
    }

    /// The points to draw, per signal (x in s before now).
    fn rows(&self) -> &[(String, Vec<[f64; 2]>)] {
        self.cache.as_ref().map_or(&[], |(_, r)| r.as_slice())
    }
}

/// The changes of `signals` over the `range_ms` before `now_ms` as CSV
/// (`signal,t_ms,value`, the value before the range first), and how many rows.
pub(crate) fn changes_csv(
    store: &crate::historian::Store,
    signals: &[String],
    now_ms: u64,
    range_ms: u64,
) -> Result<(String, usize), crate::historian::HistorianError> {
    let from = now_ms.saturating_sub(range_ms);
    let mut csv = String::from("signal,t_ms,value\n");
    let mut n = 0;
    for s in signals {
        for (t, v) in store.changes(s, from, now_ms + 1)? {
            csv.push_str(&format!("{s},{t},{v}\n"));
            n += 1;
        }
    }
    Ok((csv, n))
}

/// "-2 h 05 min", "-45 s": a time before now.
fn fmt_before(s: f64, now: &str) -> String {
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let s = (-s).max(0.0).round() as u64;
    match s {
        0 => now.to_string(),
        s if s < 120 => format!("-{s} s"),
        s if s < 7200 => format!("-{} min {:02} s", s / 60, s % 60),
        s if s < 2 * 86_400 => format!("-{} h {:02} min", s / 3600, s / 60 % 60),
        s => format!("-{} d {:02} h", s / 86_400, s / 3600 % 24),
    }
}

/// The trends view (central panel).
pub(crate) fn trends_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    trends_toolbar_ui(c, ui, out);
    let now = c.journal.wall_of(c.sim.now().0);
    let Some(store) = c.journal.store() else {
        ui.label(RichText::new(c.i18n.t("trends-no-history")).color(c.palette.caution));
        return;
    };
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let buckets = ui.available_width().clamp(100.0, 4000.0) as u32;
    c.trends.refresh(store, now, buckets);
    let rows = c.trends.rows();
    if let Some(e) = &c.trends.error {
        ui.label(RichText::new(e).color(c.palette.alarm));
    }
    if rows.is_empty() {
        ui.label(c.i18n.t("trends-empty"));
        return;
    }
    ui.label(
        RichText::new(c.i18n.t("trends-legend"))
            .small()
            .color(c.palette.text_dim),
    );
    let n = rows.len();
    let now_label = c.i18n.t("trends-now");
    let labels: Vec<String> = rows.iter().map(|(s, _)| s.clone()).collect();
    #[allow(clippy::cast_precision_loss)]
    let range_s = c.trends.range_ms as f64 / 1000.0;
    Plot::new("trends")
        .allow_scroll(false)
        .include_x(-range_s)
        .include_x(0.0)
        .include_y(-0.3)
        .include_y(n as f64 * 1.5)
        .x_axis_formatter(move |m, _| fmt_before(m.value, &now_label))
        .y_axis_formatter(move |m, _| {
            let v = m.value;
            let row = (v / 1.5).floor();
            if (v - row * 1.5).abs() < 1e-6 && row >= 0.0 {
                #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                let i = row as usize;
                labels
                    .get(n.saturating_sub(1 + i))
                    .cloned()
                    .unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_grid_spacer(|_| {
            (0..n)
                .map(|i| egui_plot::GridMark {
                    value: i as f64 * 1.5,
                    step_size: 1.5,
                })
                .collect()
        })
        .show(ui, |p| {
            for (i, (name, pts)) in rows.iter().enumerate() {
                #[allow(clippy::cast_precision_loss)]
                let y0 = (n - 1 - i) as f64 * 1.5;
                let pts: Vec<[f64; 2]> = pts.iter().map(|[x, y]| [*x, y0 + y]).collect();
                p.line(
                    Line::new(name.as_str(), PlotPoints::from(pts))
                        .width(1.5)
                        .allow_band(false),
                );
            }
        });
}

/// The trends' toolbar: range, signals added (with a filter) and removed, export.
fn trends_toolbar_ui(c: &mut Console, ui: &mut egui::Ui, out: &mut Vec<Command>) {
    let names = signal_names(&c.sim.bundle.symbols);
    ui.horizontal_wrapped(|ui| {
        ui.label(c.i18n.t("trends-range"));
        for (ms, id) in RANGES {
            if ui
                .add(egui::Button::selectable(
                    c.trends.range_ms == ms,
                    c.i18n.t(id),
                ))
                .clicked()
            {
                c.trends.range_ms = ms;
            }
        }
        ui.separator();
        let full = c.trends.signals.len() >= MAX_SIGNALS;
        let add = if full {
            c.i18n.ta("trends-full", &[("n", MAX_SIGNALS.into())])
        } else {
            c.i18n.t("trends-add")
        };
        ui.add_enabled_ui(!full, |ui| {
            ui.menu_button(add, |ui| {
                let l = ui.label(c.i18n.t("trends-filter"));
                ui.add(egui::TextEdit::singleline(&mut c.trends.filter).desired_width(100.0))
                    .labelled_by(l.id);
                let f = c.trends.filter.to_lowercase();
                egui::ScrollArea::vertical()
                    .max_height(300.0)
                    .show(ui, |ui| {
                        for n in names.iter().filter(|n| n.to_lowercase().contains(&f)) {
                            let on = c.trends.signals.contains(n);
                            if ui
                                .add_enabled(!on, egui::Button::selectable(on, n.as_str()))
                                .clicked()
                            {
                                c.trends.signals.push(n.clone());
                                ui.close();
                            }
                        }
                    });
            });
        });
        let mut remove = None;
        for (i, s) in c.trends.signals.iter().enumerate() {
            if ui
                .small_button(format!("{s} ✕"))
                .on_hover_text(c.i18n.ta("trends-remove-hover", &[("signal", s.into())]))
                .clicked()
            {
                remove = Some(i);
            }
        }
        if let Some(i) = remove {
            c.trends.signals.remove(i);
        }
        ui.separator();
        if ui
            .add_enabled(
                !c.save.is_open(),
                egui::Button::new(c.i18n.t("trends-export")),
            )
            .on_hover_text(c.i18n.t("trends-export-hover"))
            .clicked()
        {
            out.push(Command::SaveAs(Export::Trend));
        }
    });
}
