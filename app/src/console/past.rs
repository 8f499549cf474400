//! The alarms of earlier runs, read back from the historian: every session of the data
//! folder, the console's and the gateway's, newest first, searched with the history's
//! search text. They are the records as written (the core's English text).

use super::Console;
use egui::RichText;

/// How far back the view reads, ms.
const BACK_MS: u64 = 30 * 86_400_000;
/// Rows read at most.
const ROWS: usize = 500;
/// Rows shown at most.
const SHOWN: usize = 100;

/// `2026-12-04 01:37:08 UTC`: a wall-clock time (ms since the Unix epoch).
pub(crate) fn fmt_wall(ms: u64) -> String {
    let secs = ms / 1000;
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    #[allow(clippy::cast_possible_wrap)]
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

/// The collapsible list of the earlier runs' alarms.
pub(crate) fn past_alarms_ui(c: &mut Console, ui: &mut egui::Ui) {
    egui::CollapsingHeader::new(c.i18n.t("past-title"))
        .id_salt("past_alarms")
        .show(ui, |ui| {
            let Some(store) = c.journal.store() else {
                ui.label(c.i18n.t("trends-no-history"));
                return;
            };
            // Read again at most once a second, not every frame.
            let now = c.journal.wall_of(c.sim.now().0);
            if c.past_alarms
                .as_ref()
                .is_none_or(|(at, _)| *at != now / 1000)
            {
                let rows = store
                    .alarms(now.saturating_sub(BACK_MS), ROWS)
                    .map_err(|e| e.to_string());
                c.past_alarms = Some((now / 1000, rows));
            }
            let rows = match c.past_alarms.as_ref().map(|(_, r)| r) {
                Some(Ok(r)) => r,
                Some(Err(e)) => {
                    ui.label(RichText::new(e).color(c.palette.alarm));
                    return;
                }
                None => return,
            };
            let search = c.history_filter.text.to_lowercase();
            let shown: Vec<_> = rows
                .iter()
                .rev()
                .filter(|a| {
                    search.is_empty()
                        || a.message.to_lowercase().contains(&search)
                        || a.key.to_lowercase().contains(&search)
                })
                .collect();
            ui.label(
                RichText::new(c.i18n.ta(
                    "past-count",
                    &[
                        ("n", shown.len().into()),
                        ("days", (BACK_MS / 86_400_000).into()),
                    ],
                ))
                .small()
                .color(c.palette.text_dim),
            );
            for a in shown.iter().take(SHOWN) {
                let state = match (a.acked.is_some(), a.cleared_ms.is_some()) {
                    (true, true) => String::new(),
                    (true, false) => format!(" · {}", c.i18n.t("alarm-ack")),
                    (false, true) => format!(" · {}", c.i18n.t("alarm-cleared-unack")),
                    (false, false) => format!(" · {}", c.i18n.t("alarm-unack")),
                };
                let message = if a.code.is_empty() || c.i18n.lang() == crate::i18n::Lang::En {
                    a.message.clone()
                } else {
                    super::words::coded(
                        &c.i18n,
                        &c.sim.bundle,
                        &format!("alarm-{}", a.code),
                        &a.fields,
                    )
                    .unwrap_or_else(|| a.message.clone())
                };
                let priority = c.i18n.t(&format!("prio-{}", a.priority));
                ui.label(
                    RichText::new(format!(
                        "{}  {priority}{state}  {message}",
                        fmt_wall(a.raised_ms),
                    ))
                    .size(11.0),
                );
            }
        });
}

#[cfg(test)]
mod tests {
    use super::fmt_wall;

    #[test]
    fn wall_times_as_dates() {
        assert_eq!(fmt_wall(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(fmt_wall(951_782_400_000), "2000-02-29 00:00:00 UTC");
        assert_eq!(fmt_wall(1_796_347_028_000), "2026-12-04 01:17:08 UTC");
        assert_eq!(fmt_wall(4_107_542_399_000), "2100-02-28 23:59:59 UTC");
    }
}
