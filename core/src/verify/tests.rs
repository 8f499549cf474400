use super::*;
use crate::diag::Problem;
use crate::test_support::Scratch;
use std::path::Path;

fn station() -> (PlantBundle, Layout) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    let (b, _) = PlantBundle::load(&dir).expect("bundle");
    let l = crate::test_support::station_layout();
    (b, l)
}

/// A copy of the station folder in a temporary directory with textual patches applied
/// (`(file, from, to)`), loaded; the folder is removed when the guard drops.
fn patched(tag: &str, patches: &[(&str, &str, &str)]) -> (Scratch, PlantBundle, Layout) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    let dir = std::env::temp_dir().join(format!("vigie-verify-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    for f in [
        "plant.ron",
        "observers.ron",
        "constraints.txt",
        "invariants.txt",
        "components.ron",
    ] {
        let mut text = std::fs::read_to_string(src.join(f)).expect("read station file");
        for (file, from, to) in patches {
            if *file == f {
                assert!(text.contains(from), "patch target `{from}` not in {f}");
                text = text.replace(from, to);
            }
        }
        std::fs::write(dir.join(f), text).expect("write patched file");
    }
    let (b, problems) = PlantBundle::load(&dir).expect("patched bundle");
    assert!(!problems.iter().any(Problem::is_error), "{problems:?}");
    let l = crate::machine::Description::load(&dir)
        .expect("patched components")
        .layout()
        .expect("a turntable cell");
    (Scratch(dir), b, l)
}

fn kinds(e: &Exploration) -> Vec<&str> {
    let mut k: Vec<&str> = e.hazard_kinds.iter().map(|(k, _)| k.as_str()).collect();
    k.sort_unstable();
    k
}

/// The paper's 17 constraints, one box and two boxes at once: safe, a delivery reachable
/// at both exits, every invariant holds.
#[test]
fn station_paper_set_is_safe_and_permissive() {
    let (b, l) = station();
    for max_boxes in [1, 2] {
        let r = verify(
            &b,
            &l,
            &Options {
                max_boxes,
                necessity_boxes: None,
            },
        )
        .expect("verify");
        assert!(r.safe, "{max_boxes} boxes: {:?}", kinds(&r.full));
        assert!(
            r.permissive,
            "{max_boxes} boxes: deliveries {:?}",
            r.full
                .delivered
                .iter()
                .map(Option::is_some)
                .collect::<Vec<_>>()
        );
        for i in &r.invariants {
            assert!(i.proved, "{max_boxes} boxes: {} refuted", i.id);
        }
    }
}

/// Without CSs13 (no rotation of an empty table) a hazard is reachable; its shortest
/// trace replays as that hazard in the emulator, and the console scenario generated from
/// it reaches the hazard with the weakened filter enforcing.
#[test]
fn counterexample_of_a_weakened_set_is_real() {
    let (_guard, b, l) = patched(
        "no-css13",
        &[(
            "constraints.txt",
            "CSs13 = C4 . /C6 . A4",
            "# CSs13 dropped",
        )],
    );
    let r = verify(
        &b,
        &l,
        &Options {
            max_boxes: 1,
            necessity_boxes: None,
        },
    )
    .expect("verify");
    let (kind, trace) = r
        .full
        .hazard
        .as_ref()
        .expect("without CSs13 a hazard is reachable");
    let rp = replay(&l, &b, trace, r.geometry.step_us, 10).expect("replay");
    assert!(
        rp.hazards
            .iter()
            .any(|h| hazard_name(h.kind) == kind.as_str()),
        "the emulator does not reproduce {kind}: {:?}",
        rp.hazards
    );
    let out = _guard.join("cex");
    let path = scenario::write(
        &out,
        trace,
        &b.plant,
        &_guard.to_string_lossy(),
        r.geometry.step_us,
    )
    .expect("write scenario");
    let sc = crate::sim::Scenario::load(&path).expect("scenario loads");
    let mut sim = crate::sim::Simulation::from_scenario(&sc, &path, crate::sim::Options::default())
        .expect("scenario builds");
    sim.run_until(crate::time::Millis(sc.duration_ms));
    let report = sim.report(1);
    assert!(
        report
            .hazards
            .iter()
            .any(|h| hazard_name(h.kind) == kind.as_str()),
        "the counterexample scenario does not reach {kind}: hazards {:?}, trips {:?}",
        report.hazards,
        report
            .trips
            .iter()
            .map(|t| (t.time_ms, t.constraints.clone()))
            .collect::<Vec<_>>()
    );
}

/// The program generated from a trace commands exactly the trace's output vectors.
#[test]
fn counterexample_program_follows_the_trace() {
    let (b, l) = station();
    let m = Model::new(&b, &l, 1).expect("model");
    let e = explore(&m, &Filter::new(&b.constraints, b.plant.outputs.len()));
    let trace = e.delivered[0].as_ref().expect("a delivery witness");
    let prog = scenario::program(trace, &b.plant, m.geo.step_us);
    let compiled =
        crate::control::CompiledProgram::new(&prog, &b.plant, &crate::control::Origin::default())
            .expect("generated program compiles");
    assert!(compiled.step_count() >= 2);
    // Durations add up to the trace length.
    let total: u64 = prog.timers.iter().map(|t| t.2).sum();
    let expected = (trace.steps.len() as i64 * m.geo.step_us + 500) / 1000;
    assert_eq!(total as i64, expected);
}

/// Runs SPIN on a generated model (`pan -cN`: stop after N errors, 0 = never); panics
/// loudly when spin or gcc is missing.
fn run_spin(text: &str, errors: u32, ignore_end_states: bool) -> promela::SpinVerdict {
    promela::run_spin(text, errors, ignore_end_states)
        .unwrap_or_else(|p| panic!("SPIN CROSS-CHECK CANNOT RUN: {}", p.message))
}

fn rust_verdict(e: &Exploration) -> (Vec<String>, [bool; 2], bool) {
    let mut h: Vec<String> = e.hazard_kinds.iter().map(|(k, _)| k.clone()).collect();
    h.sort();
    (
        h,
        [e.delivered[0].is_some(), e.delivered[1].is_some()],
        e.no_fallback.is_some(),
    )
}

/// The one-box model of `b`, and SPIN's verdict on it checked complete and equal to
/// the explorer's.
fn spin_agrees(b: &PlantBundle, l: &Layout) -> (Model, promela::SpinVerdict) {
    let m = Model::new(b, l, 1).expect("model");
    let e = explore(&m, &Filter::new(&b.constraints, b.plant.outputs.len()));
    let s = run_spin(&promela::generate(&m, &b.constraints, &b.symbols), 0, false);
    assert!(s.complete, "SPIN search incomplete");
    assert_eq!(
        (s.hazards.clone(), s.delivered, s.no_fallback),
        rust_verdict(&e),
        "SPIN vs explorer"
    );
    (m, s)
}

/// SPIN and the explorer agree on the station (one box): hazard kinds, deliveries at
/// both exits, fallback everywhere; the full state space.
#[test]
fn spin_agrees_on_the_station() {
    let (b, l) = station();
    let (_, s) = spin_agrees(&b, &l);
    assert!(s.hazards.is_empty() && s.delivered == [true, true] && !s.no_fallback);
}

/// Drop each constraint in turn: SPIN and the explorer give the same safety verdict
/// (a hazard reachable or not; SPIN stops at its first hazard).
#[test]
fn spin_agrees_on_weakened_sets() {
    let (b, l) = station();
    let m = Model::new(&b, &l, 1).expect("model");
    let n_out = b.plant.outputs.len();
    let mut unsafe_sets = 0;
    for (i, c) in b.constraints.constraints.iter().enumerate() {
        let set = without(&b.constraints, i);
        let e = explore(&m, &Filter::new(&set, n_out));
        let s = run_spin(&promela::generate_safety(&m, &set, &b.symbols), 1, true);
        let spin_unsafe = !s.hazards.is_empty();
        // pan -c1 stops at its first hazard: only a safe verdict must be complete.
        assert!(
            spin_unsafe || s.complete,
            "without {}: SPIN search incomplete",
            c.id
        );
        assert_eq!(
            spin_unsafe,
            e.hazard.is_some(),
            "without {}: SPIN {:?} vs explorer {:?}",
            c.id,
            s.hazards,
            e.hazard_kinds
        );
        if let Some(h) = s.hazards.first() {
            assert!(
                e.hazard_kinds.iter().any(|(k, _)| k == h),
                "without {}: SPIN found {h}, the explorer {:?}",
                c.id,
                e.hazard_kinds
            );
        }
        unsafe_sets += usize::from(spin_unsafe);
    }
    assert!(
        unsafe_sets > 0,
        "no weakened set is unsafe: the check proves nothing"
    );
}

#[test]
fn promela_dump() {
    let (b, l) = station();
    let m = Model::new(&b, &l, 1).expect("model");
    let text = promela::generate(&m, &b.constraints, &b.symbols);
    std::fs::write(std::env::temp_dir().join("vigie_model.pml"), text).expect("write");
    let i = b
        .constraints
        .constraints
        .iter()
        .position(|c| c.id == "CSs13")
        .expect("CSs13");
    let w = without(&b.constraints, i);
    std::fs::write(
        std::env::temp_dir().join("vigie_model_w13.pml"),
        promela::generate(&m, &w, &b.symbols),
    )
    .expect("write");
}

/// The verifier's budget counts the previous-cycle values its state keeps, not the
/// plant's signals: the station with 40 more sensors that nothing reads (60 inputs, 69
/// signals in all) explores the same states as the station. Before, past 29 signals in
/// all, it was refused ("too many signals for the verifier").
#[test]
fn extra_signals_that_nothing_reads_cost_the_verifier_nothing() {
    let spare: String = (0..40)
        .map(|k| format!("        (id: \"X{k}\", kind: Sensor, description: \"spare\"),\n"))
        .collect();
    let anchor = "        (id: \"A0\", kind: Actuator";
    let with_spare = format!("{spare}{anchor}");
    let (_guard, b, l) = patched("spare", &[("plant.ron", anchor, &with_spare)]);
    assert_eq!(b.plant.inputs.len(), 60);
    let o = Options {
        max_boxes: 1,
        necessity_boxes: None,
    };
    let big = verify(&b, &l, &o).expect("verify with 40 spare sensors");
    let (sb, sl) = station();
    let small = verify(&sb, &sl, &o).expect("verify the station");
    assert!(big.safe && big.permissive);
    assert_eq!(big.full.states, small.full.states);
    assert_eq!(big.full.transitions, small.full.transitions);
}

/// More previous-cycle values read than the state keeps: refused with the count, not
/// explored wrong.
#[test]
fn too_many_previous_values_read_are_refused_with_the_count() {
    let spare: String = (0..30)
        .map(|k| format!("        (id: \"X{k}\", kind: Sensor, description: \"spare\"),\n"))
        .collect();
    let anchor = "        (id: \"A0\", kind: Actuator";
    let with_spare = format!("{spare}{anchor}");
    let reads: Vec<String> = (0..30).map(|k| format!("X{k}*")).collect();
    let line = format!("CSs1  = 2P . A0\nCSx = {} . A0\n", reads.join(" . "));
    let (_guard, b, l) = patched(
        "prev-reads",
        &[
            ("plant.ron", anchor, &with_spare),
            ("constraints.txt", "CSs1  = 2P . A0", line.trim_end()),
        ],
    );
    let Err(err) = Model::new(&b, &l, 1) else {
        panic!("30 previous-cycle reads accepted");
    };
    assert!(
        err.message.contains("at most 29 previous-cycle values") && err.message.contains("read 3"),
        "{}",
        err.message
    );
}

/// A safety contactor on the drives' supply and a mirror contact (issue 17): the model's
/// mirror reads the output applied at t-1 and the contactor gates the drives it feeds,
/// so the station with them stays safe and permissive (unmodelled, the mirror would read
/// 0 and CSk2 would cut the supply whenever A1 runs: no delivery).
#[test]
fn a_safety_contactor_and_a_mirror_contact_are_modelled() {
    let (b, l) = with_contactor();
    let r = verify(
        &b,
        &l,
        &Options {
            max_boxes: 1,
            necessity_boxes: None,
        },
    )
    .expect("verify");
    assert!(r.safe, "{:?}", kinds(&r.full));
    assert!(
        r.permissive,
        "{:?}",
        r.full
            .delivered
            .iter()
            .map(Option::is_some)
            .collect::<Vec<_>>()
    );
    // The mirror reads A1 as applied at t-1; the released contactor unpowers its drives.
    let m = Model::new(&b, &l, 1).expect("model");
    let (a1, km0) = (
        b.plant.output("A1").unwrap(),
        b.plant.output("KM0").unwrap(),
    );
    let fb = b.plant.input("A1_fb").unwrap();
    let mut frame = Frame::new([m.n_in, m.n_out, m.n_obs, 0]);
    let mut obs = m.observers.clone();
    let mut s = m.initial();
    let (inputs, _, _) = m.frame(&s, &mut frame, &mut obs);
    assert_eq!(
        inputs >> fb & 1,
        0,
        "A1 released at t-1: the mirror reads open"
    );
    s.prev.1 |= 1 << a1;
    let (inputs, _, _) = m.frame(&s, &mut frame, &mut obs);
    assert_eq!(
        inputs >> fb & 1,
        1,
        "A1 applied at t-1: the mirror reads closed"
    );
    assert_eq!(m.powered(1 << a1 | 1 << km0).0, 1 << a1 | 1 << km0);
    assert_eq!(m.powered(1 << a1).0, 0, "no supply: A1 does not act");
}

/// The station: a safety contactor KM0 on the drives' supply, mirror contacts on every
/// drive and the monomials that watch them (`CSk*`), all in its data.
fn with_contactor() -> (PlantBundle, Layout) {
    station()
}

/// SPIN and the explorer agree on the station with a safety contactor and a mirror
/// contact (the Promela model reads the mirror as the output applied at t-1 and gates
/// the drives by the contactor, as the explorer does).
#[test]
fn spin_agrees_with_a_safety_contactor() {
    let (b, l) = with_contactor();
    let (m, _) = spin_agrees(&b, &l);
    // The model's text: the mirror reads A1 as applied at t-1, the drives act only with
    // the contactor applied.
    let text = promela::generate(&m, &b.constraints, &b.symbols);
    let (a1, km0) = (
        b.plant.output("A1").unwrap(),
        b.plant.output("KM0").unwrap(),
    );
    let fb = b.plant.input("A1_fb").unwrap();
    assert!(text.contains(&format!("ci[{fb}] = po[{a1}];")), "mirror");
    assert!(text.contains(&format!("(o[{a1}] && o[{km0}])")), "supply");
}

/// The station with external device monitoring (seven drive mirrors, two safety
/// devices, sixteen `CSk*` monomials): a monomial that reads a mirror and its output at
/// t-1 with opposite polarities is never true in the model (its contactors neither weld
/// nor die), so the state keeps no more previous outputs than the station's and the
/// exploration stays the station's size (before: every drive's previous output kept,
/// 2^9 times the states, 18 GB and no end). The station with it is safe and permissive,
/// and SPIN agrees (the table without its air stays where it is in both models).
#[test]
fn device_monitoring_costs_the_verifier_nothing() {
    let (b, l) = station();
    let dir = crate::test_support::paper_station("verify-paper");
    let (sb, _) = PlantBundle::load(&dir).unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
    let sl = crate::machine::Description::load(&dir)
        .expect("components")
        .layout()
        .expect("a turntable cell");
    assert_eq!(
        Model::new(&b, &l, 1).expect("model").prev_mask.1 & 0x7f,
        Model::new(&sb, &sl, 1).expect("model").prev_mask.1,
        "the previous outputs kept"
    );
    let o = Options {
        max_boxes: 1,
        necessity_boxes: None,
    };
    let edm = verify(&b, &l, &o).expect("verify the station with EDM");
    let plain = verify(&sb, &sl, &o).expect("verify the station");
    let last = |t: &Option<(String, Trace)>| {
        t.as_ref().map(|(k, t)| {
            (
                k.clone(),
                t.steps[t.steps.len().saturating_sub(3)..].to_vec(),
            )
        })
    };
    assert!(edm.safe && edm.permissive, "{:#?}", last(&edm.full.hazard));
    assert_eq!(edm.full.states, plain.full.states);
}
