//! The incident report: a Markdown file (trip, constraint, the five levels' items, the
//! trace window), one PNG of the synoptic per level, the chronogram of the trip window
//! with every signal (SVG) and as it was on screen (PNG).

use crate::i18n::I18n;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use vigie_core::explain::overbar_notation;
use vigie_core::sim::Simulation;

/// Who wrote the report, when, and what ran: the report's header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Meta {
    /// Wall-clock time of the export, ms since the Unix epoch.
    pub wall_ms: u64,
    /// The logged-in user (`None`: nobody logged in) and the role in force.
    pub user: (Option<String>, String),
    /// The plant folder and the plant's name.
    pub plant: (String, String),
    /// The control program's name, its version ([`vigie_core::control::Program::version`])
    /// and the training exercise, if one runs.
    pub program: (String, String, Option<String>),
    /// The run's title (the scenario, the exercise or the live link).
    pub scenario: String,
    /// The filter's mode.
    pub filter: String,
}

/// Writes `dir/report.md` for trip `trip`; returns its path.
/// The report is in the language `i18n` shows (the items of the levels as the console
/// shows them).
pub fn write_markdown(
    sim: &Simulation,
    i18n: &I18n,
    meta: &Meta,
    trip: usize,
    dir: &Path,
) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n", i18n.t("report-title"));
    write_meta(&mut md, i18n, meta);
    if let Some(t) = sim.engine.trips.get(trip) {
        let _ = writeln!(
            md,
            "- {}",
            i18n.ta(
                "report-trip",
                &[("time_ms", t.time_ms.into()), ("cycle", t.cycle.into())]
            )
        );
        for c in &t.constraints {
            let _ = writeln!(
                md,
                "- {}",
                i18n.ta(
                    "report-constraint",
                    &[
                        ("id", (&c.id).into()),
                        ("source", (&c.notation).into()),
                        ("notation", (&overbar_notation(&c.notation)).into()),
                    ]
                )
            );
        }
        let fb: Vec<String> = t
            .fallback
            .iter()
            .map(|(o, v)| format!("{o}={}", u8::from(*v)))
            .collect();
        let _ = writeln!(
            md,
            "- {}\n",
            i18n.ta("report-fallback", &[("outputs", (&fb.join(" ")).into())])
        );
    }
    if let Some(ex) = sim.explanations.get(&trip) {
        for (i, level) in ex.levels().into_iter().enumerate() {
            let name = i18n.t(&format!("level-{i}"));
            let title = i18n.ta("expl-level", &[("level", (&name).into())]);
            let _ = writeln!(md, "## {title}\n\n![level {i}](level-{i}.png)\n");
            for item in &level.items {
                let _ = writeln!(md, "- `{}` {}", item.code, i18n.explain(item));
            }
            md.push('\n');
        }
        let constraints: Vec<String> = sim
            .engine
            .trips
            .get(trip)
            .map(|t| t.constraints.iter().map(|c| c.id.clone()).collect())
            .unwrap_or_default();
        std::fs::write(
            dir.join("chronogram.svg"),
            chronogram_svg(
                sim,
                ex.time_ms,
                &constraints,
                &i18n.t("report-chronogram-legend"),
            ),
        )?;
        let _ = writeln!(
            md,
            "## {}\n\n![chronogram](chronogram.svg)\n\n{}\n\n![chronogram](chronogram.png)\n",
            i18n.t("report-chronogram"),
            i18n.t("report-chronogram-screen")
        );
        write_trace(&mut md, sim, i18n, ex.time_ms);
    }
    let path = dir.join("report.md");
    std::fs::write(&path, md)?;
    Ok(path)
}

/// The trace window: the last 300 cycles before the trip, changes only.
fn write_trace(md: &mut String, sim: &Simulation, i18n: &I18n, trip_ms: u64) {
    let _ = writeln!(
        md,
        "## {}\n\n| {} | {} |\n|---|---|",
        i18n.t("report-trace"),
        i18n.t("report-time-ms"),
        i18n.t("report-changes")
    );
    let names: Vec<&String> = sim
        .bundle
        .plant
        .inputs
        .iter()
        .chain(&sim.bundle.plant.outputs)
        .map(|s| &s.id)
        .collect();
    let n_in = sim.bundle.plant.inputs.len();
    let recs: Vec<_> = sim
        .engine
        .history
        .iter()
        .filter(|r| r.time.0 <= trip_ms)
        .collect();
    let start = recs.len().saturating_sub(300);
    for w in recs[start..].windows(2) {
        let mut ch = Vec::new();
        for (i, name) in names.iter().enumerate() {
            let (a, b) = if i < n_in {
                (w[0].inputs.get(i), w[1].inputs.get(i))
            } else {
                (w[0].applied.get(i - n_in), w[1].applied.get(i - n_in))
            };
            if a != b {
                ch.push(format!("{name} {}→{}", u8::from(a), u8::from(b)));
            }
        }
        if !ch.is_empty() {
            let _ = writeln!(md, "| {} | {} |", w[1].time.0, ch.join(", "));
        }
    }
}

/// The header: date, user, plant, program and version, run, filter, Vigie's version.
fn write_meta(md: &mut String, i18n: &I18n, meta: &Meta) {
    let none = i18n.t("report-nobody");
    let user = meta.user.0.as_deref().unwrap_or(&none);
    let program = match &meta.program.2 {
        Some(id) => i18n.ta(
            "report-program-exercise",
            &[
                ("name", (&meta.program.0).into()),
                ("version", (&meta.program.1).into()),
                ("id", id.into()),
            ],
        ),
        None => i18n.ta(
            "report-program",
            &[
                ("name", (&meta.program.0).into()),
                ("version", (&meta.program.1).into()),
            ],
        ),
    };
    let lines = [
        i18n.ta(
            "report-date",
            &[("date", (&super::past::fmt_wall(meta.wall_ms)).into())],
        ),
        i18n.ta(
            "report-user",
            &[("user", user.into()), ("role", (&meta.user.1).into())],
        ),
        i18n.ta(
            "report-plant",
            &[
                ("name", (&meta.plant.1).into()),
                ("folder", (&meta.plant.0).into()),
            ],
        ),
        program,
        i18n.ta("report-run", &[("title", (&meta.scenario).into())]),
        i18n.ta("report-filter", &[("mode", (&meta.filter).into())]),
        i18n.ta(
            "report-vigie",
            &[("version", env!("CARGO_PKG_VERSION").into())],
        ),
    ];
    for l in lines {
        let _ = writeln!(md, "- {l}");
    }
    md.push('\n');
}

/// Saves the part of a screenshot under `rect` (points) as PNG.
pub fn save_png(
    image: &egui::ColorImage,
    rect: Option<egui::Rect>,
    ppp: f32,
    path: &Path,
) -> Result<(), String> {
    let [w, h] = image.size;
    let (x0, y0, x1, y1) = match rect {
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        Some(r) => (
            ((r.min.x * ppp) as usize).min(w),
            ((r.min.y * ppp) as usize).min(h),
            ((r.max.x * ppp) as usize).min(w),
            ((r.max.y * ppp) as usize).min(h),
        ),
        None => (0, 0, w, h),
    };
    if x1 <= x0 || y1 <= y0 {
        return Err("empty capture".into());
    }
    let mut buf = image::RgbaImage::new(
        u32::try_from(x1 - x0).unwrap_or(1),
        u32::try_from(y1 - y0).unwrap_or(1),
    );
    for y in y0..y1 {
        for x in x0..x1 {
            let c = image.pixels[y * w + x];
            #[allow(clippy::cast_possible_truncation)]
            buf.put_pixel((x - x0) as u32, (y - y0) as u32, image::Rgba(c.to_array()));
        }
    }
    buf.save(path).map_err(|e| e.to_string())
}

/// The chronogram of the trip window as SVG (`chronogram.svg` of the report): every
/// input, every output (applied as a bar, an amber line over it where the filter
/// applied another value than the command) and every observer, from [`CHRONO_BEFORE_MS`] before
/// the trip to the last record, with a time axis and the trip's line. The console's
/// chronogram shows the rows the user chose and fits its panel; the report keeps them
/// all.
pub fn chronogram_svg(
    sim: &Simulation,
    trip_ms: u64,
    constraints: &[String],
    legend: &str,
) -> String {
    let start = trip_ms.saturating_sub(CHRONO_BEFORE_MS);
    let recs: Vec<_> = sim
        .engine
        .history
        .iter()
        .filter(|r| r.time.0 >= start)
        .collect();
    let plant = &sim.bundle.plant;
    let observers = sim
        .bundle
        .symbols
        .names(vigie_core::symbols::Space::Observer);
    let rows: Vec<(&str, Row, usize)> = plant
        .inputs
        .iter()
        .enumerate()
        .map(|(i, s)| (s.id.as_str(), Row::Input, i))
        .chain(
            plant
                .outputs
                .iter()
                .enumerate()
                .map(|(i, s)| (s.id.as_str(), Row::Output, i)),
        )
        .chain(
            observers
                .iter()
                .enumerate()
                .map(|(i, s)| (s.as_str(), Row::Observer, i)),
        )
        .collect();
    let end = recs.last().map_or(trip_ms, |r| r.time.0).max(start + 1);
    let g = Svg::new(start, end, rows.len());
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" \
         font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>",
        g.width(),
        g.height
    );
    g.axis(&mut s);
    for (n, &(name, kind, i)) in rows.iter().enumerate() {
        g.row(&mut s, n, name, kind, |value| {
            runs(&recs, |r| value(r, i), end)
        });
    }
    let tx = g.x(trip_ms);
    let _ = writeln!(
        s,
        "<line x1=\"{tx:.1}\" y1=\"{:.1}\" x2=\"{tx:.1}\" y2=\"{:.1}\" stroke=\"#c00\" stroke-width=\"1.5\"/>\n\
         <text x=\"{:.1}\" y=\"{:.1}\" fill=\"#c00\">{}</text>\n\
         <text x=\"4\" y=\"{:.1}\" fill=\"#555\">{}</text>\n</svg>",
        g.top - 4.0,
        g.height,
        tx + 3.0,
        g.top + 8.0,
        html_escape(&constraints.join(", ")),
        g.height - 6.0,
        html_escape(legend)
    );
    s
}

/// What a chronogram row shows.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Row {
    Input,
    Output,
    Observer,
}

/// A value of a record: what the bar shows, or (outputs) where the filter applied
/// another value than the command.
type Probe = fn(&vigie_core::history::CycleRecord, usize) -> bool;

/// The chronogram's geometry: a label column, the plot, one row per signal.
struct Svg {
    start: u64,
    end: u64,
    top: f64,
    row_h: f64,
    label_w: f64,
    plot_w: f64,
    height: f64,
}

impl Svg {
    fn new(start: u64, end: u64, rows: usize) -> Self {
        let (top, row_h) = (28.0, 18.0);
        #[allow(clippy::cast_precision_loss)]
        let height = top + rows as f64 * row_h + 28.0;
        Self {
            start,
            end,
            top,
            row_h,
            label_w: 70.0,
            plot_w: 1100.0,
            height,
        }
    }

    fn width(&self) -> f64 {
        self.label_w + self.plot_w + 20.0
    }

    #[allow(clippy::cast_precision_loss)]
    fn x(&self, t: u64) -> f64 {
        self.label_w
            + t.saturating_sub(self.start) as f64 / (self.end - self.start) as f64 * self.plot_w
    }

    /// The time axis: a tick per second, a label every 5 s (every second under 10 s).
    fn axis(&self, s: &mut String) {
        let every = if (self.end - self.start).div_ceil(1000) <= 10 {
            1
        } else {
            5
        };
        for k in self.start.div_ceil(1000)..=self.end / 1000 {
            let tx = self.x(k * 1000);
            let _ = writeln!(
                s,
                "<line x1=\"{tx:.1}\" y1=\"{:.1}\" x2=\"{tx:.1}\" y2=\"{:.1}\" stroke=\"#eee\"/>",
                self.top - 4.0,
                self.height
            );
            if k % every == 0 {
                let _ = writeln!(
                    s,
                    "<text x=\"{tx:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{k} s</text>",
                    self.top - 8.0
                );
            }
        }
    }

    /// Row `n`: its name, its bars (`spans` of a probe), and for an output the amber
    /// line where the filter applied another value than the command.
    fn row(
        &self,
        s: &mut String,
        n: usize,
        name: &str,
        kind: Row,
        spans: impl Fn(Probe) -> Vec<(u64, u64)>,
    ) {
        #[allow(clippy::cast_precision_loss)]
        let y = self.top + n as f64 * self.row_h;
        let _ = writeln!(
            s,
            "<text x=\"4\" y=\"{:.1}\">{}</text>\n<line x1=\"{}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"#ccc\"/>",
            y + self.row_h - 5.0,
            html_escape(name),
            self.label_w,
            y + self.row_h - 2.0,
            self.label_w + self.plot_w,
            y + self.row_h - 2.0
        );
        let (probe, fill): (Probe, &str) = match kind {
            Row::Input => (|r, i| r.inputs.get(i), "#333"),
            Row::Output => (|r, i| r.applied.get(i), "#1f5fbf"),
            Row::Observer => (|r, i| r.observers.get(i), "#6a3d9a"),
        };
        let bar = |s: &mut String, (from, to): (u64, u64), dy: f64, h: f64, fill: &str| {
            let _ = writeln!(
                s,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{h:.1}\" fill=\"{fill}\"/>",
                self.x(from),
                y + dy,
                (self.x(to) - self.x(from)).max(1.0),
            );
        };
        for span in spans(probe) {
            bar(s, span, 4.0, self.row_h - 8.0, fill);
        }
        if kind == Row::Output {
            for span in spans(|r, i| r.commanded.get(i) != r.applied.get(i)) {
                bar(s, span, 1.0, 3.0, "#e08a00");
            }
        }
    }
}

/// How far back the report's chronogram goes before the trip, ms.
pub const CHRONO_BEFORE_MS: u64 = 30_000;

/// The intervals `[from, to)` where `value` holds, over records in time order (the last
/// one lasting to `end`).
fn runs(
    recs: &[&vigie_core::history::CycleRecord],
    value: impl Fn(&vigie_core::history::CycleRecord) -> bool,
    end: u64,
) -> Vec<(u64, u64)> {
    let mut out = Vec::new();
    let mut open: Option<u64> = None;
    for r in recs {
        match (value(r), open) {
            (true, None) => open = Some(r.time.0),
            (false, Some(from)) => {
                out.push((from, r.time.0));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(from) = open {
        out.push((from, end));
    }
    out
}

/// `text` with `&`, `<`, `>` and `"` escaped for HTML.
fn html_escape(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            c => s.push(c),
        }
    }
    s
}

/// The alarm history `list` (as filtered) as a document laid out for paper, in the
/// language shown: the plant, the run, the filter and the time printed on top, one row
/// per alarm (time, priority, kind, state, the operator's text, cleared, acknowledged
/// with its note, shelving with its reason). It asks the browser to print once loaded.
pub(crate) fn alarms_html(c: &super::Console, list: &[&vigie_core::alarms::Alarm]) -> String {
    use super::past::fmt_wall;
    use super::views::fmt_ms;
    use vigie_core::alarms::AlarmState;
    let i = &c.i18n;
    let e = |s: &str| html_escape(s);
    let f = &c.history_filter;
    let kind_name =
        |k: vigie_core::alarms::AlarmKind| i.t(&format!("kind-{}", k.name().replace(' ', "-")));
    let filter = format!(
        "{} · {} · {}",
        if f.text.trim().is_empty() {
            i.t("print-no-search")
        } else {
            i.ta("print-search", &[("text", f.text.trim().into())])
        },
        f.kind.map_or_else(|| i.t("history-every-kind"), kind_name),
        f.priority.map_or_else(
            || i.t("history-every-priority"),
            |p| format!("P{}", p.rank())
        ),
    );
    let now = crate::historian::wall_ms();
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"{lang}\"><head><meta charset=\"utf-8\">\
         <title>{title}</title>\n<style>\
         @page {{ size: A4 landscape; margin: 12mm; }}\
         body {{ font-family: sans-serif; font-size: 10pt; }}\
         table {{ border-collapse: collapse; width: 100%; }}\
         th, td {{ border: 1px solid #888; padding: 2pt 4pt; vertical-align: top; text-align: left; }}\
         th {{ background: #ddd; }} thead {{ display: table-header-group; }}\
         tr {{ page-break-inside: avoid; }} .p1 {{ font-weight: bold; }}\
         </style></head>\n<body onload=\"window.print()\">\n<h1>{title}</h1>\n\
         <p>{plant}<br>{run}<br>{printed}<br>{filter}<br>{count}</p>\n<table>\n<thead><tr>",
        lang = i.lang().code(),
        title = e(&i.t("print-title")),
        plant = e(&i.ta(
            "print-plant",
            &[("name", (&c.sim.bundle.plant.name).into())]
        )),
        run = e(&i.ta("print-run", &[("title", (&c.source.title(i)).into())])),
        printed = e(&i.ta("print-printed", &[("time", (&fmt_wall(now)).into())])),
        filter = e(&i.ta("print-filter", &[("filter", (&filter).into())])),
        count = e(&i.ta(
            "history-count",
            &[
                ("n", list.len().into()),
                ("total", c.sim.alarms.all().len().into())
            ]
        )),
    );
    for col in [
        "print-col-raised",
        "print-col-priority",
        "print-col-kind",
        "print-col-state",
        "print-col-message",
        "print-col-cleared",
        "print-col-ack",
        "print-col-shelved",
    ] {
        let _ = write!(h, "<th>{}</th>", e(&i.t(col)));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for a in list {
        let state = match a.state() {
            AlarmState::Unacknowledged => "alarm-unack",
            AlarmState::Acknowledged => "alarm-ack",
            AlarmState::ClearedUnacknowledged => "alarm-cleared-unack",
            AlarmState::Normal => "alarm-normal",
        };
        let at = |ms: u64| format!("{} ({})", fmt_ms(ms), fmt_wall(c.journal.wall_of(ms)));
        let ack = a.acknowledged.as_ref().map_or(String::new(), |(t, n)| {
            if n.is_empty() {
                at(t.0)
            } else {
                format!("{}: {n}", at(t.0))
            }
        });
        let shelved = a.shelving.as_ref().map_or(String::new(), |s| {
            format!("{}: {}", fmt_ms(s.until.0), s.reason)
        });
        let _ = writeln!(
            h,
            "<tr class=\"p{rank}\"><td>{raised}</td><td>P{rank}</td><td>{kind}</td><td>{state}</td>\
             <td>{message}</td><td>{cleared}</td><td>{ack}</td><td>{shelved}</td></tr>",
            rank = a.priority().rank(),
            raised = e(&at(a.raised.0)),
            kind = e(&kind_name(a.kind)),
            state = e(&i.t(state)),
            message = e(&super::words::alarm_message(i, &c.sim.bundle, a)),
            cleared = e(&a.cleared.map_or(String::new(), |t| at(t.0))),
            ack = e(&ack),
            shelved = e(&shelved),
        );
    }
    h.push_str("</tbody>\n</table>\n</body></html>\n");
    h
}

#[cfg(test)]
mod tests {
    /// The report's chronogram keeps every row whatever the console showed: every input,
    /// every output, every observer, the trip's line and a time axis.
    #[test]
    fn the_reports_chronogram_has_every_signal_and_the_trip() {
        use vigie_core::sim::{Options, Scenario, Simulation};
        use vigie_core::time::Millis;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../layouts/sorting-station/scenarios/cs10-paper.ron");
        let scenario = Scenario::load(&path).unwrap();
        let mut sim = Simulation::from_scenario(&scenario, &path, Options::default()).unwrap();
        sim.run_until(Millis(14_000));
        let trip = sim
            .engine
            .trips
            .first()
            .expect("the paper's CSs10 trip")
            .clone();
        let svg = super::chronogram_svg(&sim, trip.time_ms, &["CSs10".to_string()], "legend");
        assert!(svg.starts_with("<svg ") && svg.ends_with("</svg>\n"));
        let plant = &sim.bundle.plant;
        for id in plant
            .inputs
            .iter()
            .chain(&plant.outputs)
            .map(|s| s.id.as_str())
            .chain(["P36", "P67", "2P"])
        {
            assert!(svg.contains(&format!(">{id}</text>")), "row {id}");
        }
        assert!(
            svg.contains("fill=\"#c00\">CSs10</text>"),
            "the trip's line"
        );
        assert!(svg.contains(">10 s</text>"), "the time axis");
        // Bars for the outputs that ran; amber where the filter applied another value
        // (A0, A5, A6 stopped against the command, A4 held ON).
        assert!(svg.matches("fill=\"#1f5fbf\"").count() >= 3);
        assert!(svg.matches("fill=\"#e08a00\"").count() >= 4);
        assert!(svg.contains(">legend</text>"));
        // Before any record, only the axis and the rows.
        let empty = super::chronogram_svg(&sim, 0, &[], "");
        assert!(empty.contains(">C0</text>"));
    }

    /// What an operator typed (a note, a search) cannot break the printed page.
    #[test]
    fn html_escape_neutralises_markup() {
        assert_eq!(
            super::html_escape(r#"<script>alert("x")</script> & co"#),
            "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; &amp; co"
        );
    }
}
