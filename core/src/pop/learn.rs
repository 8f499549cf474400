//! Interval learning from normal-run traces (seed 003, annex B): each window interval
//! gets the observed min/max, the mean T and the population σ of the times from its
//! clock event to the expected evolution it frames, and the tolerance ΔT = α·σ; only
//! evolutions of normally completed cycles (the clock phase ended with every
//! observation explained by the normal model) are counted.
//!
//! [`rewrite`] writes the learned bounds into the file's text in place: comments,
//! layout and every other value are kept byte for byte.

use super::build::Compiled;
use super::model::{Bound, DiagnoserFile, Learned};
use crate::diag::codes;
use crate::diag::{Location, Problem, RonField};
use crate::frame::Frame;
use crate::symbols::Space;
use crate::trace::TraceRow;
use std::collections::BTreeMap;
use std::path::Path;

/// Running estimator of annex B: mean and variance updated after each measure.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimator {
    /// Number of measures.
    pub n: u64,
    /// Mean.
    pub mean: f64,
    /// Mean of the squares (β_j).
    pub beta: f64,
    /// Smallest measure.
    pub min: u64,
    /// Largest measure.
    pub max: u64,
}

impl Estimator {
    /// Adds one measure with the recursion (B.3)/(B.4): P_j = 1/j.
    pub fn push(&mut self, tau: u64) {
        let x = tau as f64;
        if self.n == 0 {
            *self = Self {
                n: 1,
                mean: x,
                beta: x * x,
                min: tau,
                max: tau,
            };
            return;
        }
        let p = 1.0 / self.n as f64;
        self.mean = (self.mean + p * x) / (1.0 + p);
        self.beta = self.beta / (1.0 + p) + p / (1.0 + p) * x * x;
        self.n += 1;
        self.min = self.min.min(tau);
        self.max = self.max.max(tau);
    }

    /// Population standard deviation.
    pub fn sigma(&self) -> f64 {
        (self.beta - self.mean * self.mean).max(0.0).sqrt()
    }
}

/// Measures the window intervals on `rows` (each trace replayed from its start).
pub fn measure(
    compiled: &Compiled,
    sizes: [usize; 4],
    traces: &[Vec<TraceRow>],
) -> BTreeMap<String, Estimator> {
    let mut out: BTreeMap<String, Estimator> = BTreeMap::new();
    for c in &compiled.components {
        // Window intervals and the evolutions they frame (normal states only).
        for rows in traces {
            let mut frame = Frame::new(sizes);
            let mut state: Option<usize> = None;
            let mut clock: Option<(usize, u64)> = None;
            let mut pending: Vec<(usize, u64)> = Vec::new();
            let mut ok = true;
            for (n, row) in rows.iter().enumerate() {
                if n > 0 {
                    frame.shift();
                }
                frame.now_mut(Space::Input).copy_from(&row.inputs);
                frame.now_mut(Space::Output).copy_from(&row.outputs);
                let val = c.signals.iter().enumerate().fold(0u64, |a, (i, s)| {
                    a | (u64::from(frame.now(s.var.space).get(s.var.index as usize)) << i)
                });
                let Some(x) = state else {
                    state = c.values.iter().position(|&v| v == val);
                    continue;
                };
                for space in c.edge_order() {
                    for (i, s) in c
                        .signals
                        .iter()
                        .enumerate()
                        .filter(|(_, s)| s.var.space == space)
                    {
                        let v = frame.now(space).get(s.var.index as usize);
                        if v == frame.prev(space).get(s.var.index as usize) {
                            continue;
                        }
                        let cur = state.unwrap_or(x);
                        let next = c.g[cur].obs.iter().find(|&&(sym, _, _)| {
                            let sy = &c.symbols[sym];
                            sy.edge == Some((i, v))
                                && sy
                                    .guard
                                    .as_ref()
                                    .is_none_or(|g| crate::expr::eval_dnf(g, &frame))
                        });
                        match next {
                            Some(&(_, to, w)) => {
                                if let (Some(k), Some((ck, ct))) = (w, clock)
                                    && c.intervals[k].clock == ck
                                {
                                    pending.push((k, row.time.0.saturating_sub(ct)));
                                }
                                state = Some(to);
                            }
                            None => {
                                ok = false;
                                state = c.values.iter().position(|&v2| v2 == val);
                            }
                        }
                        if let Some(k) = c.clocks.iter().position(|&e| e == (i, v)) {
                            if ok {
                                for (iv, tau) in pending.drain(..) {
                                    out.entry(c.intervals[iv].id.clone()).or_default().push(tau);
                                }
                            }
                            pending.clear();
                            ok = true;
                            clock = Some((k, row.time.0));
                        }
                    }
                }
            }
        }
    }
    out
}

/// Writes the measures into the file: each measured interval gets its statistics and
/// the window `[floor(min(min, T−ΔT)), ceil(max(max, T+ΔT)) + 1[`; intervals defined
/// from others follow. Returns the ids updated.
pub fn apply(file: &mut DiagnoserFile, measures: &BTreeMap<String, Estimator>) -> Vec<String> {
    let alpha = file.alpha;
    let mut done = Vec::new();
    for c in &mut file.components {
        for iv in &mut c.intervals {
            let Some(m) = measures.get(&iv.id) else {
                continue;
            };
            if m.n == 0 {
                continue;
            }
            let sigma = m.sigma();
            let delta = alpha * sigma;
            let lo = (m.mean - delta).floor().max(0.0).min(m.min as f64) as u64;
            let hi = (m.mean + delta).ceil().max(m.max as f64) as u64 + 1;
            // Only the window intervals (both bounds in ms) move; an interval defined
            // from others or without end (`I5`: waiting for the release, as long as
            // the operator wants) keeps its bounds and only gets the statistics.
            if matches!((&iv.lo, &iv.hi), (Bound::Ms(_), Bound::Ms(_))) {
                iv.lo = Bound::Ms(lo);
                iv.hi = Bound::Ms(hi);
            }
            iv.learned = Some(Learned {
                samples: m.n,
                min_ms: m.min,
                max_ms: m.max,
                mean_ms: (m.mean * 100.0).round() / 100.0,
                sigma_ms: (sigma * 100.0).round() / 100.0,
                alpha,
                delta_ms: (delta * 100.0).round() / 100.0,
            });
            done.push(iv.id.clone());
        }
    }
    done
}

/// The text of the diagnoser file `text` (read from `path`) with the interval bounds of
/// `learned` (the file after [`apply`]): only the value of each `lo` or `hi` that
/// changed is replaced, so comments, layout, order and every other value stay byte for
/// byte (the learned statistics and α are printed by `vigie diagnose learn`, not written). The
/// result is parsed again and must give the bounds asked for; anything unexpected is a
/// `V0514` problem and nothing is written.
pub fn rewrite(text: &str, path: &Path, learned: &DiagnoserFile) -> Result<String, Problem> {
    let fail = |message: String, at: Option<&RonField>| {
        Problem::error(
            codes::LEARN_WRITE_IN_PLACE.id,
            format!("cannot write the learned bounds in place: {message}"),
            Some(at.map_or_else(|| Location::new(path, 1, 1), |f| f.location(path))),
        )
    };
    let before = DiagnoserFile::from_ron(text, path)?;
    let fields = crate::diag::ron_fields(text);
    let at = ["components", "intervals"];
    let ids: Vec<&RonField> = fields
        .iter()
        .filter(|f| f.name == "id" && f.is_at(&at))
        .collect();
    let old: Vec<_> = before
        .components
        .iter()
        .flat_map(|c| &c.intervals)
        .collect();
    let new: Vec<_> = learned
        .components
        .iter()
        .flat_map(|c| &c.intervals)
        .collect();
    if ids.len() != old.len() || new.len() != old.len() {
        return Err(fail(
            format!(
                "{} intervals written, {} parsed, {} learned",
                ids.len(),
                old.len(),
                new.len()
            ),
            None,
        ));
    }
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    let mut expected = before.clone();
    for (((id, o), n), e) in ids.iter().zip(&old).zip(&new).zip(
        expected
            .components
            .iter_mut()
            .flat_map(|c| &mut c.intervals),
    ) {
        let written: Option<String> = text
            .get(id.value.clone())
            .and_then(|v| ron::from_str(v).ok());
        if written.as_deref() != Some(o.id.as_str()) || n.id != o.id {
            return Err(fail(
                format!("interval `{}` is not where expected", n.id),
                Some(id),
            ));
        }
        for (name, old_bound, new_bound, slot) in [
            ("lo", &o.lo, &n.lo, &mut e.lo),
            ("hi", &o.hi, &n.hi, &mut e.hi),
        ] {
            if old_bound == new_bound {
                continue;
            }
            let field = fields
                .iter()
                .find(|f| f.container == id.container && f.name == name && f.is_at(&at));
            let (Some(field), Ok(value)) = (field, ron::to_string(new_bound)) else {
                return Err(fail(
                    format!("no `{name}` found for interval `{}`", n.id),
                    Some(id),
                ));
            };
            edits.push((field.value.clone(), value));
            slot.clone_from(new_bound);
        }
    }
    edits.sort_by_key(|(r, _)| r.start);
    let mut out = String::with_capacity(text.len());
    let mut done = 0;
    for (range, value) in &edits {
        let Some(kept) = text.get(done..range.start) else {
            return Err(fail("overlapping values".into(), None));
        };
        out.push_str(kept);
        out.push_str(value);
        done = range.end;
    }
    out.push_str(text.get(done..).unwrap_or_default());
    match DiagnoserFile::from_ron(&out, path) {
        Ok(got) if got == expected => Ok(out),
        Ok(_) => Err(fail("the rewritten file reads differently".into(), None)),
        Err(p) => Err(fail(
            format!("the rewritten file does not parse ({})", p.message),
            None,
        )),
    }
}

#[cfg(test)]
mod tests;
