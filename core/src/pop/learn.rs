//! Interval learning from normal-run traces (seed 003, annex B): each window interval
//! gets the observed min/max, the mean T and the population σ of the times from its
//! clock event to the expected evolution it frames, and the tolerance ΔT = α·σ; only
//! evolutions of normally completed cycles (the clock phase ended with every
//! observation explained by the normal model) are counted.

use super::build::Compiled;
use super::model::{Bound, DiagnoserFile, Learned};
use crate::frame::Frame;
use crate::symbols::Space;
use crate::trace::TraceRow;
use std::collections::BTreeMap;

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
