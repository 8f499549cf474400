//! Following a live PLC with the program it should be running (`--program FILE`).
//!
//! The follower runs the given program beside the PLC on the inputs the link reads, and
//! compares its outputs with the outputs the PLC writes. The operator's buttons of the
//! program (its panel: START, STOP…) are not on the bus. The follower therefore keeps
//! every situation the program can be in under any use of them, as a diagnoser keeps
//! its estimates. A situation is kept while its outputs equal the PLC's, or differ for no
//! more than `tolerance` consecutive cycles: the PLC scans on its own clock and the link
//! reads it a few milliseconds late. When no situation is left, no run of the program
//! explains what the PLC does: the PLC is not running the program given. The divergence
//! names the first output (in plant order) on which the closest situation differs.
//!
//! The follower must start with the PLC's program in its initial situation (before the
//! machine's start, or with the PLC restarted): it does not guess a situation reached
//! before it was attached.

use crate::bits::Bits;
use crate::control::{CompiledProgram, ProgramRuntime};
use crate::engine::Control;
use crate::frame::Frame;
use crate::plant::Plant;
use crate::symbols::Space;
use crate::time::Millis;
use serde::Serialize;
use std::sync::Arc;

/// Consecutive cycles of difference a run is kept through: the link reads the PLC's
/// outputs up to two cycles late.
pub const TOLERANCE: u32 = 2;

/// Largest number of situations kept (the closest ones first).
pub const MAX_SITUATIONS: usize = 64;

/// The PLC's outputs left the program's possible runs.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Divergence {
    /// When it was found.
    pub time_ms: u64,
    /// The first output (in plant order) on which the closest run differs.
    pub output: String,
    /// The PLC's value of that output.
    pub plc: bool,
    /// The program's value in its closest run.
    pub program: bool,
    /// The program's name and version.
    pub program_name: String,
    /// See `program_name`.
    pub version: String,
}

impl Divergence {
    /// The alarm's text, with its code and fields for the console's languages.
    pub fn alarm_text(&self) -> crate::alarms::AlarmText {
        let on = |b: bool| if b { "ON" } else { "OFF" }.to_string();
        let fields = [
            ("name", self.program_name.clone()),
            ("version", self.version.clone()),
            ("output", self.output.clone()),
            ("plc", on(self.plc)),
            ("program", on(self.program)),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        crate::alarms::AlarmText::from(self.message().as_str()).with("program-divergence", fields)
    }

    /// The operator's message.
    pub fn message(&self) -> String {
        let on = |b: bool| if b { "ON" } else { "OFF" };
        format!(
            "the PLC is not running the program you gave ({}, version {}): {} is {} at the PLC, {} in the program",
            self.program_name,
            self.version,
            self.output,
            on(self.plc),
            on(self.program)
        )
    }
}

#[derive(Clone, Debug)]
struct Situation {
    rt: ProgramRuntime,
    /// Consecutive cycles its outputs differed from the PLC's.
    streak: u32,
    out: Bits,
    /// The buttons of its last scan, and how many times they changed: of two
    /// situations, the one fewer presses explain comes first.
    panel: u32,
    changes: u32,
    /// The situation of the cycle before it came from (an index into `previous`).
    parent: usize,
}

/// True when a condition or an equation reads a panel button's edge or previous value.
fn reads_panel_history(program: &CompiledProgram) -> bool {
    let p = &program.program;
    p.transitions()
        .map(|(_, t)| t.condition.as_str())
        .chain(p.equations.iter().map(|e| e.1.as_str()))
        .chain(p.counters.iter().map(|c| c.reset.as_str()))
        .filter_map(|text| crate::expr::parse_str(text).ok())
        .any(|e| {
            e.leaves().iter().any(|(name, kind, _)| {
                *kind != crate::expr::LeafKind::Now && p.panel.iter().any(|b| b == name)
            })
        })
}

/// The program followed beside a live PLC, in its closest situation before the last scan
/// and after it ([`Follower::program`]): what the explanations of a trip read.
#[derive(Clone, Copy, Debug)]
pub struct Followed<'a> {
    /// The program before its last scan.
    pub before: &'a ProgramRuntime,
    /// The program after it.
    pub after: &'a ProgramRuntime,
    /// The outputs it drives (indices in plant order); the others are not the program's.
    pub driven: &'a [usize],
}

/// The outputs (indices in plant order) `program` drives: an action's or an equation's
/// target. The others (a safety contactor the safety function holds) are not the
/// program's.
fn driven_outputs(program: &crate::control::Program, plant: &Plant) -> Vec<usize> {
    let targets: Vec<&str> = program
        .steps()
        .flat_map(|(_, s)| s.actions.iter().map(|a| a.target.as_str()))
        .chain(program.equations.iter().map(|e| e.0.as_str()))
        .collect();
    (0..plant.outputs.len())
        .filter(|&k| targets.contains(&plant.outputs[k].id.as_str()))
        .collect()
}

/// A program followed beside a live PLC (see the module documentation).
#[derive(Clone, Debug)]
pub struct Follower {
    situations: Vec<Situation>,
    /// The situations of the cycle before (the program before its last scan).
    previous: Vec<Situation>,
    panel: Vec<String>,
    outputs: Vec<String>,
    frame: Frame,
    /// The outputs the program drives (an action's or an equation's target): the
    /// others (a safety contactor the safety function holds) are not compared.
    driven: Vec<usize>,
    /// The panel's state bits, left out when two situations are compared: the
    /// follower sets every button anew each cycle, so they weigh on the future only
    /// through an edge or a previous value of a button, which then keeps them.
    ignore: Vec<(usize, u64)>,
    tolerance: u32,
    divergence: Option<Divergence>,
    name: String,
    version: String,
}

impl Follower {
    /// A follower of `program` on `plant`'s signals, tolerating `tolerance` consecutive
    /// cycles of difference per run.
    pub fn new(program: Arc<CompiledProgram>, plant: &Plant, tolerance: u32) -> Self {
        let panel = program.program.panel.clone();
        let name = program.program.name.clone();
        let version = program.program.version();
        let n_out = plant.outputs.len();
        let driven = driven_outputs(&program.program, plant);
        let rt = ProgramRuntime::new(Arc::clone(&program));
        let ignore = if reads_panel_history(&program) {
            Vec::new()
        } else {
            rt.panel_bits()
        };
        Self {
            situations: vec![Situation {
                rt,
                streak: 0,
                out: Bits::zeros(n_out),
                panel: 0,
                changes: 0,
                parent: 0,
            }],
            previous: Vec::new(),
            panel,
            outputs: plant.outputs.iter().map(|s| s.id.clone()).collect(),
            frame: Frame::new([plant.inputs.len(), n_out, 0, 0]),
            driven,
            ignore,
            tolerance,
            divergence: None,
            name,
            version,
        }
    }

    /// The divergence found, if any (it stays: the follower stops there).
    pub fn divergence(&self) -> Option<&Divergence> {
        self.divergence.as_ref()
    }

    /// True once a cycle has been followed.
    pub fn started(&self) -> bool {
        !self.previous.is_empty() || self.divergence.is_some()
    }

    /// Number of situations the program may be in.
    pub fn situations(&self) -> usize {
        self.situations.len()
    }

    /// One cycle: the inputs as read and the outputs the PLC wrote. Returns the
    /// divergence the cycle finds (once).
    pub fn step(&mut self, now: Millis, inputs: &Bits, plc: &Bits) -> Option<Divergence> {
        if self.divergence.is_some() {
            return None;
        }
        self.frame.shift();
        let ins = self.frame.now_mut(Space::Input);
        if ins.len() == inputs.len() {
            ins.copy_from(inputs);
        }
        let combos = 1u32 << self.panel.len().min(8);
        let mut next: Vec<Situation> = Vec::new();
        for (parent, s) in self.situations.iter().enumerate() {
            for mask in 0..combos {
                let mut rt = s.rt.clone();
                for (i, b) in self.panel.iter().enumerate() {
                    let _ = rt.set_switch(b, mask >> i & 1 == 1);
                }
                let mut out = s.out.clone();
                rt.scan(now, &self.frame, &mut out);
                let same = self.driven.iter().all(|&k| out.get(k) == plc.get(k));
                let streak = if same { 0 } else { s.streak + 1 };
                if streak > self.tolerance {
                    continue;
                }
                let changes = s.changes + (mask ^ s.panel).count_ones();
                match next
                    .iter_mut()
                    .find(|n| n.rt.same_situation(&rt, &self.ignore))
                {
                    Some(n) if (streak, changes) < (n.streak, n.changes) => {
                        (n.streak, n.changes, n.panel, n.parent) = (streak, changes, mask, parent);
                    }
                    Some(_) => {}
                    None => next.push(Situation {
                        rt,
                        streak,
                        out,
                        panel: mask,
                        changes,
                        parent,
                    }),
                }
            }
        }
        if next.is_empty() {
            let d = self.diverged(now, plc);
            self.divergence = Some(d.clone());
            return Some(d);
        }
        next.sort_by_key(|s| (s.streak, s.changes));
        next.truncate(MAX_SITUATIONS);
        self.previous = std::mem::replace(&mut self.situations, next);
        None
    }

    /// The program in the closest situation (the PLC's outputs the longest, the fewest
    /// presses), before its last scan and after it: what the explanations of a trip in
    /// the cycle just followed read. `None` before the first cycle followed and once the
    /// PLC diverged (it is not running this program).
    pub fn program(&self) -> Option<Followed<'_>> {
        if self.divergence.is_some() {
            return None;
        }
        let closest = self.situations.first()?;
        let before = self.previous.get(closest.parent)?;
        Some(Followed {
            before: &before.rt,
            after: &closest.rt,
            driven: &self.driven,
        })
    }

    /// The divergence from the closest situation (lowest streak) of the last cycle.
    fn diverged(&self, now: Millis, plc: &Bits) -> Divergence {
        let closest = self.situations.iter().min_by_key(|s| s.streak);
        let (k, program) = closest
            .and_then(|s| {
                self.driven
                    .iter()
                    .copied()
                    .find(|&k| s.out.get(k) != plc.get(k))
                    .map(|k| (k, s.out.get(k)))
            })
            .unwrap_or((0, !plc.get(0)));
        Divergence {
            time_ms: now.0,
            output: self.outputs.get(k).cloned().unwrap_or_default(),
            plc: plc.get(k),
            program,
            program_name: self.name.clone(),
            version: self.version.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::FilterMode;
    use crate::sim::{Options, ProgramChoice, Scenario, Simulation};
    use std::path::{Path, PathBuf};

    fn station() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
    }

    fn reference(plant: &Plant) -> Arc<CompiledProgram> {
        Arc::new(
            CompiledProgram::load(&station().join("programs/reference.ron"), plant)
                .expect("the reference compiles"),
        )
    }

    /// The inputs each cycle's program read and the outputs it commanded, over `ms` of
    /// `scenario` run with `program` and the filter off (the PLC's own outputs).
    fn plc_run(
        scenario: &str,
        program: ProgramChoice,
        ms: u64,
    ) -> (Plant, Vec<(Millis, Bits, Bits)>) {
        let path = station().join("scenarios").join(scenario);
        let mut s = Scenario::load(&path).expect("scenario");
        s.program = program;
        s.filter = FilterMode::Off;
        let mut sim = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
        let mut out = Vec::new();
        while sim.now() < Millis(ms) {
            sim.cycle();
            out.push((
                sim.now(),
                sim.engine.frame().now(Space::Input).clone(),
                sim.engine.commanded().clone(),
            ));
        }
        (sim.bundle.plant.clone(), out)
    }

    /// The station's reference program, started by the console's Start (a panel button
    /// the bus does not carry), followed for five minutes of production: never a
    /// divergence.
    #[test]
    fn the_program_the_plc_runs_is_followed_without_divergence() {
        let (plant, run) = plc_run("reference-hour.ron", ProgramChoice::Reference, 300_000);
        let mut f = Follower::new(reference(&plant), &plant, 0);
        for (now, ins, outs) in &run {
            assert_eq!(f.step(*now, ins, outs), None, "at {} ms", now.0);
            assert!(f.situations() <= MAX_SITUATIONS);
        }
    }

    /// The paper's error E01 (the rotation released on the rising edge of C7) runs in
    /// the PLC; the follower of the reference finds it when A4 falls early.
    #[test]
    fn a_plc_running_another_program_diverges_on_the_first_output_that_differs() {
        let (plant, run) = plc_run("cs10-paper.ron", ProgramChoice::Error("E01".into()), 40_000);
        let mut f = Follower::new(reference(&plant), &plant, 2);
        let found = run
            .iter()
            .find_map(|(now, ins, outs)| f.step(*now, ins, outs));
        let d = found.expect("a divergence");
        // X24 left at the rise of C7 instead of its fall: the evacuation rollers A3 and
        // the rotation A4 stop early; A3 comes first in the plant's order.
        assert_eq!(
            (d.output.as_str(), d.plc, d.program),
            ("A3", false, true),
            "{d:?}"
        );
        assert!(
            d.message().contains("not running the program you gave"),
            "{}",
            d.message()
        );
        // Latched: reported once.
        let (now, ins, outs) = run.last().expect("cycles");
        assert_eq!(f.step(*now, ins, outs), None);
        assert_eq!(f.divergence(), Some(&d));
    }

    /// The link reads the PLC's outputs one cycle late: with a tolerance of two cycles
    /// the reference is followed without a false divergence; with none it is not.
    #[test]
    fn outputs_read_a_cycle_late_are_tolerated_within_the_tolerance() {
        let (plant, run) = plc_run("reference-hour.ron", ProgramChoice::Reference, 300_000);
        let late: Vec<(Millis, Bits, Bits)> = run
            .windows(2)
            .map(|w| (w[1].0, w[1].1.clone(), w[0].2.clone()))
            .collect();
        let mut tolerant = Follower::new(reference(&plant), &plant, 2);
        for (now, ins, outs) in &late {
            assert_eq!(tolerant.step(*now, ins, outs), None, "at {} ms", now.0);
        }
        let mut strict = Follower::new(reference(&plant), &plant, 0);
        assert!(
            late.iter()
                .any(|(now, ins, outs)| strict.step(*now, ins, outs).is_some())
        );
    }
}
