//! The incident report: a Markdown file (trip, constraint, the five levels' items, the
//! trace window) and one PNG of the synoptic per level.

use crate::i18n::I18n;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use vigie_core::explain::overbar_notation;
use vigie_core::sim::Simulation;

/// Writes `dir/report.md` for trip `trip`; returns its path.
/// The report is in the language `i18n` shows (the items of the levels as the console
/// shows them).
pub fn write_markdown(
    sim: &Simulation,
    i18n: &I18n,
    trip: usize,
    dir: &Path,
) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n", i18n.t("report-title"));
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
        // Trace window: the last 30 cycles before the trip, changes only.
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
            .filter(|r| r.time.0 <= ex.time_ms)
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
    let path = dir.join("report.md");
    std::fs::write(&path, md)?;
    Ok(path)
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
