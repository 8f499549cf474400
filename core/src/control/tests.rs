use super::*;
use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::engine::{Control, Engine, FilterMode};
use crate::frame::Frame;
use crate::observers::{ObserverDef, Observers, Rule};
use crate::plant::Plant;
use crate::symbols::Space;
use crate::time::Millis;
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn station() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

fn plant() -> Plant {
    Plant::load(&station().join("plant.ron")).unwrap()
}

fn compile(text: &str) -> Result<CompiledProgram, Vec<crate::diag::Problem>> {
    let file = Path::new("test.ron");
    let program = Program::from_ron(text, file)?;
    CompiledProgram::new(&program, &plant(), &Origin::new(file, text))
}

fn runtime(text: &str) -> ProgramRuntime {
    ProgramRuntime::new(Arc::new(compile(text).unwrap()))
}

/// Open-loop driver: the program alone, inputs given by name.
struct Open {
    rt: ProgramRuntime,
    plant: Plant,
    frame: Frame,
    out: Bits,
    t: u64,
}

impl Open {
    fn new(text: &str) -> Self {
        let plant = plant();
        let sizes = [plant.inputs.len(), plant.outputs.len(), 0, 0];
        Self {
            rt: runtime(text),
            frame: Frame::new(sizes),
            out: Bits::zeros(plant.outputs.len()),
            plant,
            t: 0,
        }
    }

    fn scan(&mut self, inputs: &[&str]) -> Vec<String> {
        self.frame.shift();
        self.frame.now_mut(Space::Input).clear();
        for i in inputs {
            let k = self.plant.input(i).unwrap();
            self.frame.now_mut(Space::Input).set(k, true);
        }
        self.t += 10;
        self.rt.scan(Millis(self.t), &self.frame, &mut self.out);
        self.out
            .ones()
            .map(|k| self.plant.outputs[k].id.clone())
            .collect()
    }
}

const MINI: &str = r#"Program(
    name: "mini",
    panel: ["GO", "SW"],
    memories: ["M"],
    timers: [("T1", "S1", 50)],
    charts: [
        Chart(name: "g", steps: [
            Step(id: "S0", initial: true),
            Step(id: "S1", actions: [Action(qualifier: N, target: "A0"), Action(qualifier: P, target: "A1"), Action(qualifier: S, target: "M")]),
            Step(id: "S2", actions: [Action(qualifier: L(30), target: "A2"), Action(qualifier: D(30), target: "A3")]),
            Step(id: "S3", actions: [Action(qualifier: R, target: "M")]),
        ], transitions: [
            Transition(id: "a", from: ["S0"], to: ["S1"], condition: "GO"),
            Transition(id: "b", from: ["S1"], to: ["S2"], condition: "T1"),
            Transition(id: "c", from: ["S2"], to: ["S3"], condition: "C0"),
            Transition(id: "d", from: ["S3"], to: ["S0"], condition: "1"),
        ]),
    ],
    equations: [("A4", "M . SW"), ("A5", "A4 + C1*"), ("A6", "A6* + C2")],
)"#;

#[test]
fn control_parse_error_has_line_and_column() {
    let text = "Program(\n  name: \"x\",\n  charts: [\n    Chart(name: \"g\", stepz: [])\n  ],\n)";
    let err = compile(text).unwrap_err();
    let loc = err[0].location.clone().unwrap();
    assert_eq!(loc.line, 4, "{}", err[0]);
    assert!(loc.column > 1, "{}", err[0]);
}

#[test]
fn control_unknown_name_reports_element_and_column() {
    let text = "Program(\n  name: \"x\",\n  charts: [Chart(name: \"g\", steps: [Step(id: \"S0\", initial: true)],\n    transitions: [Transition(id: \"t0\", from: [\"S0\"], to: [\"S0\"], condition: \"C0 . C99\")])],\n)";
    let err = compile(text).unwrap_err();
    assert_eq!(err.len(), 1);
    let p = &err[0];
    assert!(p.message.contains("t0") && p.message.contains("C99"), "{p}");
    let loc = p.location.clone().unwrap();
    assert_eq!(loc.line, 4);
    let line = text.lines().nth(3).unwrap();
    let col = line.find("C99").unwrap() + 1;
    assert_eq!(loc.column, col, "{p}");

    let eq = "Program(name: \"x\", charts: [Chart(name: \"g\", steps: [Step(id: \"S0\", initial: true)], transitions: [])],\n equations: [(\"A0\", \"S0 . /NOPE\")])";
    let err = compile(eq).unwrap_err();
    let loc = err[0].location.clone().unwrap();
    assert_eq!(
        (loc.line, loc.column),
        (2, " equations: [(\"A0\", \"S0 . /".len() + 1),
        "{}",
        err[0]
    );
}

#[test]
fn control_validation_errors() {
    let text = r#"Program(name: "x", memories: ["C0"], charts: [
        Chart(name: "g", steps: [Step(id: "S0"), Step(id: "S0")], transitions: [
            Transition(id: "t", from: ["S9"], to: ["S0"], condition: "1"),
            Transition(id: "t", from: ["S0"], to: ["S0"], condition: "1"),
        ]),
        Chart(name: "h", steps: [Step(id: "H0", initial: true, actions: [Action(qualifier: N, target: "C1")])], transitions: []),
    ], equations: [("A0", "1"), ("A0", "0"), ("P36", "1")])"#;
    let err = compile(text).unwrap_err();
    let msgs: Vec<String> = err.iter().map(ToString::to_string).collect();
    let has = |s: &str| msgs.iter().any(|m| m.contains(s));
    assert!(has("no initial step"), "{msgs:#?}");
    assert!(has("step `S0` has the name of another"), "{msgs:#?}");
    assert!(
        has("memory `C0` has the name of a plant signal"),
        "{msgs:#?}"
    );
    assert!(has("unknown upstream step `S9`"), "{msgs:#?}");
    assert!(has("transition `t`: the id is used twice"), "{msgs:#?}");
    assert!(has("action target `C1`"), "{msgs:#?}");
    assert!(has("`A0` has two equations"), "{msgs:#?}");
    assert!(has("equation `P36`"), "{msgs:#?}");
}

/// The console's Start and Stop press the buttons the program names (no button name
/// in the code): a name that is neither one of the panel's nor a plant input (a
/// machine's push button) is an error at its place; an output is no button.
#[test]
fn start_and_stop_name_panel_buttons() {
    let text = "Program(name: \"x\", panel: [\"GO\"],\n  start: Some(\"GO\"),\n  stop: Some(\"HALT\"),\n  charts: [Chart(name: \"g\", steps: [Step(id: \"S0\", initial: true)], transitions: [])])";
    let msgs: Vec<String> = compile(text)
        .unwrap_err()
        .iter()
        .map(ToString::to_string)
        .collect();
    assert_eq!(msgs.len(), 1, "{msgs:#?}");
    assert!(
        msgs[0].contains(":3:")
            && msgs[0].contains("V0915")
            && msgs[0].contains("`stop`: `HALT` is neither a panel button nor a plant input"),
        "{msgs:#?}"
    );
    let wired = text.replace("Some(\"HALT\")", "Some(\"C0\")");
    assert!(compile(&wired).is_ok(), "a plant input is a button");
    let output = text.replace("Some(\"HALT\")", "Some(\"A0\")");
    let msgs = compile(&output).unwrap_err();
    assert!(msgs[0].to_string().contains("`A0` is neither"), "{msgs:#?}");
}

#[test]
fn control_qualifiers_timers_and_buttons() {
    let mut o = Open::new(MINI);
    assert!(o.scan(&[]).is_empty());
    assert_eq!(o.rt.active_steps(), vec!["S0"]);
    o.rt.press("GO").unwrap();
    assert!(o.rt.press("NOPE").is_err());
    // Activation scan: N and P on, S stored.
    assert_eq!(o.scan(&[]), vec!["A0", "A1"]);
    assert_eq!(o.rt.value("M"), Some(true));
    assert_eq!(o.rt.value("GO"), Some(true));
    // The pulse lasts one scan, the button too.
    assert_eq!(o.scan(&[]), vec!["A0"]);
    assert_eq!(o.rt.value("GO"), Some(false));
    // Timer T1 after 50 ms: S1 active at t=20, true at t=70 → S2 at that scan.
    o.scan(&[]);
    o.scan(&[]);
    o.scan(&[]);
    assert!(o.rt.is_active("S1"));
    assert_eq!(o.scan(&[]), vec!["A2"]); // t = 70: b fires, S2 active, L on
    assert_eq!(o.rt.fired_last_scan(), vec!["b"]);
    assert_eq!(o.scan(&[]), vec!["A2"]); // 10 ms
    assert_eq!(o.scan(&[]), vec!["A2"]); // 20 ms
    assert_eq!(o.scan(&[]), vec!["A3"]); // 30 ms: L over, D on
    // Switch and equations top-down (A5 reads A4 of this scan).
    o.rt.set_switch("SW", true).unwrap();
    assert_eq!(o.scan(&[]), vec!["A3", "A4", "A5"]);
    let d = o.rt.drivers("A5").unwrap();
    assert!(matches!(&d[..], [Driver::Equation { .. }]), "{d:?}");
    let d = o.rt.drivers("A4").unwrap();
    assert_eq!(d.len(), 1);
    let d = o.rt.drivers("M").unwrap();
    assert!(
        matches!(&d[..], [Driver::Stored { set_by }] if set_by == &vec!["S1".to_string()]),
        "{d:?}"
    );
    // C0 → S3 resets M (one evolution per scan: d fires only at the next scan).
    assert_eq!(o.scan(&["C0"]), Vec::<String>::new());
    assert!(o.rt.is_active("S3"));
    assert_eq!(o.rt.value("M"), Some(false));
    o.scan(&[]);
    assert!(o.rt.is_active("S0"));
    // A6 = A6* + C2 latches.
    assert!(o.scan(&["C2"]).contains(&"A6".to_string()));
    assert!(o.scan(&[]).contains(&"A6".to_string()));
    let ev = o.rt.evolutions();
    let fired: Vec<&str> = ev
        .iter()
        .flat_map(|e| e.fired.iter().map(String::as_str))
        .collect();
    assert_eq!(fired, vec!["a", "b", "c", "d"]);
}

#[test]
fn control_simultaneous_firing_and_one_evolution_per_scan() {
    let text = r#"Program(name: "p", charts: [
        Chart(name: "g", steps: [
            Step(id: "S0", initial: true), Step(id: "S1", initial: true),
            Step(id: "S2"), Step(id: "S3"), Step(id: "S4"),
        ], transitions: [
            // Both enabled and true in the same scan: both fire (rule 4).
            Transition(id: "a", from: ["S0"], to: ["S2"], condition: "C0"),
            Transition(id: "b", from: ["S1"], to: ["S3", "S1"], condition: "C0"),
            // Enabled by S2 only after the evolution: fires one scan later.
            Transition(id: "c", from: ["S2", "S3"], to: ["S4"], condition: "C0"),
        ]),
    ], equations: [("A0", "S1")])"#;
    let mut o = Open::new(text);
    o.scan(&[]);
    let t_s1 = o.rt.step_time("S1").unwrap();
    o.scan(&["C0"]);
    assert_eq!(o.rt.active_steps(), vec!["S1", "S2", "S3"]);
    assert_eq!(o.rt.fired_last_scan(), vec!["a", "b"]);
    // S1 was deactivated and activated in the same scan: it stayed active.
    assert_eq!(o.rt.step_time("S1").unwrap(), Millis(t_s1.0 + 10));
    o.scan(&["C0"]);
    assert_eq!(o.rt.fired_last_scan(), vec!["b", "c"]);
    assert_eq!(o.rt.active_steps(), vec!["S1", "S3", "S4"]);
}

/// The observers of the station, with P67 set only when the box leaves to the right
/// (see the note in `reference_closed_loop_scripted`).
fn station_bundle() -> PlantBundle {
    let (mut bundle, problems) = PlantBundle::load(&station()).unwrap();
    // Property (6) is reported on the paper's set for purely logical A4 pairs.
    assert!(
        problems.iter().all(|p| !p.is_error() || p.code == "V0106"),
        "{problems:?}"
    );
    let mut defs = bundle.observers.defs.clone();
    for d in &mut defs {
        if d.id == "P67" {
            d.rule = Rule::Memory {
                set: "FE(C6) . A3*".into(),
                reset: "RE(C7)".into(),
            };
        }
    }
    let _: &ObserverDef = &defs[0];
    let mut symbols = bundle.plant.symbols();
    let (obs, p) = Observers::from_defs(defs, Path::new("observers.ron"), &mut symbols);
    assert!(p.is_empty(), "{p:?}");
    bundle.observers = obs;
    bundle
}

struct Closed {
    engine: Engine,
    rt: ProgramRuntime,
    plant: Plant,
    t: u64,
}

impl Closed {
    fn new(rt: ProgramRuntime) -> Self {
        let bundle = station_bundle();
        Self {
            // Scripted boxes appear and move faster than the physics: every edge taken.
            engine: {
                let mut e = Engine::new(&bundle, FilterMode::ReportOnly, 16);
                e.set_plausibility(false);
                e
            },
            plant: bundle.plant.clone(),
            rt,
            t: 0,
        }
    }

    /// One scan with these sensors on; every mirror contact reads its contactor as
    /// applied in the previous cycle (healthy contactors). Returns the commanded
    /// outputs, less the safety contactors the safety function holds ON.
    fn scan(&mut self, inputs: &[&str]) -> String {
        let mut bits = Bits::zeros(self.plant.inputs.len());
        for i in inputs {
            bits.set(self.plant.input(i).unwrap(), true);
        }
        for (i, o) in self.plant.mirrors() {
            bits.set(i, self.engine.applied().get(o));
        }
        self.t += 10;
        self.engine.cycle(Millis(self.t), &bits, &mut self.rt);
        let out: Vec<String> = self
            .engine
            .commanded()
            .ones()
            .filter(|&k| !self.plant.outputs[k].held_on)
            .map(|k| self.plant.outputs[k].id.clone())
            .collect();
        out.join(" ")
    }

    fn violations(&self) -> Vec<String> {
        self.engine
            .trips
            .iter()
            .flat_map(|t| {
                t.constraints
                    .iter()
                    .map(move |c| format!("{} at {} ms", c.id, t.time_ms))
            })
            .collect()
    }
}

fn reference() -> ProgramRuntime {
    let compiled =
        CompiledProgram::load(&station().join("programs/reference.ron"), &plant()).unwrap();
    ProgramRuntime::new(Arc::new(compiled))
}

/// One box through the station, scripted sensor by sensor. Returns the exit taken.
fn one_box(c: &mut Closed, large: bool) -> &'static str {
    let size: &[&str] = if large { &["C2"] } else { &[] };
    let with = |base: &[&'static str], extra: &[&'static str]| -> Vec<&'static str> {
        base.iter().chain(extra).copied().collect()
    };
    c.scan(&["C4"]);
    assert_eq!(c.scan(&["C0", "C4"]), "A0 A1 A5 A6", "push from C0");
    c.scan(&with(&["C0", "C1", "C4"], size));
    assert_eq!(
        c.scan(&with(&["C1", "C4"], size)),
        "A0 A1 A5 A6",
        "box on A1, next box fed"
    );
    c.scan(&["C4"]);
    let s = c.scan(&["C3", "C4"]);
    assert_eq!(
        s, "A0 A1 A2 A5 A6",
        "table takes the box in the scan C3 rises"
    );
    let right = c.rt.is_active("X21");
    assert_eq!(
        c.scan(&["C4"]),
        "A0 A2 A5 A6",
        "box left A1: A1 off, rollers on"
    );
    assert_eq!(
        c.scan(&["C4", "C6"]),
        "A0 A4 A5 A6",
        "C6 rises: A2 off, A4 on in the same scan"
    );
    c.scan(&["C6"]);
    let (act, exit, far) = if right {
        ("A3", "C7", "C9")
    } else {
        ("A2", "C8", "C10")
    };
    let s = c.scan(&["C5", "C6"]);
    assert_eq!(
        s,
        format!("A0 {} A4 A5 A6", act).replace("A0 A4 A3", "A0 A3 A4"),
        "evacuation at C5"
    );
    if right {
        assert!(c.scan(&["C5"]).contains("A4"), "A4 held while P67");
    } else {
        // C6-C8 is shorter than a box: C8 rises before C6 falls.
        assert!(c.scan(&["C5", "C6", exit]).contains("A4"));
    }
    assert!(c.scan(&["C5", exit]).contains("A4"), "A4 held while {exit}");
    assert!(c.scan(&["C5", exit]).contains("A4"));
    assert_eq!(
        c.scan(&["C5", far]),
        "A0 A5 A6",
        "released on FE({exit}) at C5"
    );
    c.scan(&[]);
    c.scan(&[]);
    c.scan(&["C4"]);
    assert!(c.rt.is_active("X20"));
    if right { "right" } else { "left" }
}

#[test]
fn control_reference_right_then_left_scan_by_scan() {
    // Note: with observers.ron as shipped, P67 is set by FE(C6) whichever side the box
    // leaves, and never reset after a left evacuation (no RE(C7)), so releasing A4
    // after a left box would violate CSs11. The test uses `FE(C6) . A3*` as set rule.
    let mut c = Closed::new(reference());
    assert_eq!(c.scan(&["C4"]), "A5 A6", "stopped");
    c.rt.press("START").unwrap();
    assert_eq!(
        c.scan(&["C4"]),
        "A0 A5 A6",
        "running: A0 brings a box to C0"
    );
    assert!(c.rt.is_active("X1"));
    assert_eq!(one_box(&mut c, false), "right");
    assert_eq!(c.rt.value("LAST_R"), Some(true));
    assert_eq!(one_box(&mut c, true), "left");
    assert_eq!(c.rt.value("LAST_R"), Some(false));
    assert!(c.violations().is_empty(), "{:?}", c.violations());
    // A box waits at C3 while the table is away: A1 stops in the scan C3 rises.
    c.scan(&["C0", "C4"]);
    c.scan(&["C1", "C4"]);
    c.scan(&["C4"]);
    c.rt.press("STOP").unwrap();
    // STOP: the feed stops (A0 off) but the box in transit completes.
    assert_eq!(c.scan(&["C4"]), "A1 A5 A6");
    assert_eq!(
        c.scan(&["C3"]),
        "A5 A6",
        "table not at C4: A1 stops as C3 rises"
    );
    assert_eq!(
        c.scan(&["C3", "C4"]),
        "A1 A2 A5 A6",
        "table back: taken in one scan"
    );
    assert!(c.violations().is_empty(), "{:?}", c.violations());
    let ev = c.rt.evolutions();
    assert!(
        ev.last().unwrap().fired.contains(&"t20R".to_string()),
        "{ev:?}"
    );
}

#[test]
fn control_reference_by_size() {
    let mut c = Closed::new(reference());
    c.rt.set_switch("BY_SIZE", true).unwrap();
    c.rt.press("START").unwrap();
    c.scan(&["C4"]);
    assert_eq!(one_box(&mut c, false), "left");
    assert_eq!(one_box(&mut c, false), "left");
    assert_eq!(one_box(&mut c, true), "right");
    assert_eq!(one_box(&mut c, true), "right");
    assert!(c.violations().is_empty(), "{:?}", c.violations());
}

#[test]
fn control_paper_error_trips_cs10_on_scripted_box() {
    let lib = ErrorLibrary::load(&station().join("programs/errors.ron"), &plant()).unwrap();
    let v = lib.variants.iter().find(|v| v.def.id == "E01").unwrap();
    let mut c = Closed::new(ProgramRuntime::new(Arc::new(v.compiled.clone())));
    c.rt.press("START").unwrap();
    c.scan(&["C4"]);
    for s in [
        &["C0", "C4"][..],
        &["C0", "C1", "C4"],
        &["C1", "C4"],
        &["C4"],
        &["C3", "C4"],
        &["C4"],
        &["C4", "C6"],
        &["C6"],
        &["C5", "C6"],
        &["C5"],
        &["C5", "C7"],
    ] {
        c.scan(s);
    }
    let v = c.violations();
    assert_eq!(
        v.first().map(|s| s.split(' ').next().unwrap()),
        Some("CSs10"),
        "{v:?}"
    );
}

#[test]
fn control_error_library_loads_and_each_variant_differs_once() {
    let plant = plant();
    let lib = ErrorLibrary::load(&station().join("programs/errors.ron"), &plant).unwrap();
    assert!(lib.variants.len() >= 12);
    let bundle = station_bundle();
    let mut expected = std::collections::BTreeSet::new();
    for v in &lib.variants {
        let d = differences(&lib.reference, &v.program);
        assert_eq!(d.len(), 1, "{}: {d:?}", v.def.id);
        assert!(
            bundle.constraints.get(&v.def.expected_constraint).is_some(),
            "{}",
            v.def.id
        );
        expected.insert(v.def.expected_constraint.clone());
    }
    assert!(expected.len() >= 10, "{expected:?}");
    // A broken patch is reported with the variant id.
    let dir = std::env::temp_dir().join(format!("vigie-control-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        station().join("programs/reference.ron"),
        dir.join("reference.ron"),
    )
    .unwrap();
    std::fs::write(
        dir.join("errors.ron"),
        "ErrorsFile(reference: \"reference.ron\", variants: [(id: \"B1\", description: \"\", expected_constraint: \"CSs1\", patch: Condition(transition: \"t99\", condition: \"1\")), (id: \"B2\", description: \"\", expected_constraint: \"CSs1\", patch: Condition(transition: \"t24\", condition: \"C77\"))])",
    )
    .unwrap();
    let err = ErrorLibrary::load(&dir.join("errors.ron"), &plant).unwrap_err();
    let msgs: Vec<String> = err.iter().map(ToString::to_string).collect();
    assert!(
        msgs.iter().any(|m| m.contains("B1") && m.contains("t99")),
        "{msgs:?}"
    );
    assert!(
        msgs.iter().any(|m| m.contains("B2") && m.contains("C77")),
        "{msgs:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every mutation edits one place (a moved action: its step and the one it goes to) and
/// compiles.
#[test]
fn control_mutations_are_single_place_and_compile() {
    let plant = plant();
    let text = std::fs::read_to_string(station().join("programs/reference.ron")).unwrap();
    let reference = Program::from_ron(&text, Path::new("reference.ron")).unwrap();
    let ms = mutations(&reference, &plant);
    assert!(ms.len() > 200, "{}", ms.len());
    let ops: std::collections::BTreeSet<_> = ms.iter().map(|m| m.operator).collect();
    assert_eq!(ops.len(), 6);
    for m in &ms {
        let p = m.patch.apply(&reference).unwrap();
        let places = differences(&reference, &p);
        if let Patch::MoveAction { from, to, .. } = &m.patch {
            // A moved action edits its step and the one it goes to, in the same chart.
            let mut places = places;
            places.sort();
            let mut expected = vec![format!("step {from}"), format!("step {to}")];
            expected.sort();
            assert_eq!(places, expected, "{}", m.description);
            assert!(
                matches!(&m.place, mutation::Place::Action { step, .. } if step == to),
                "{}",
                m.description
            );
        } else {
            assert_eq!(places.len(), 1, "{}", m.description);
        }
        CompiledProgram::new(&p, &plant, &Origin::default())
            .unwrap_or_else(|e| panic!("{}: {e:?}", m.description));
    }
    // The paper's error is among them.
    assert!(ms.iter().any(|m| m.patch
        == Patch::Condition {
            transition: "t24".into(),
            condition: "RE(C7)".into()
        }));
    assert!(ms.iter().any(
        |m| m.description.contains("equation A1") && m.operator == mutation::Operator::DropTerm
    ));
    // The rotation A4 written one step early, in X22 (the finding of issue 20).
    assert!(ms.iter().any(|m| m.patch
        == Patch::MoveAction {
            from: "X23".into(),
            to: "X22".into(),
            target: "A4".into()
        }));
    let moved = ms
        .iter()
        .filter(|m| m.operator == mutation::Operator::MoveAction)
        .count();
    assert_eq!(moved, 86);
}

#[test]
fn control_runtime_clone_runs_forward_independently() {
    let mut c = Closed::new(reference());
    c.rt.press("START").unwrap();
    c.scan(&["C4"]);
    let fork = c.rt.clone();
    c.scan(&["C0", "C4"]);
    assert!(c.rt.is_active("X11"));
    assert!(fork.is_active("X10"));
}

/// Sensor script of one box (no assertion), with a 2 s rotation.
fn script(right: bool) -> Vec<Vec<&'static str>> {
    let (exit, far) = if right { ("C7", "C9") } else { ("C8", "C10") };
    let mut s: Vec<Vec<&'static str>> = vec![
        vec!["C4"],
        vec!["C0", "C4"],
        vec!["C0", "C1", "C4"],
        vec!["C1", "C4"],
        vec!["C4"],
        vec!["C3", "C4"],
        vec!["C4"],
        vec!["C4"],
        vec!["C4", "C6"],
        vec!["C4", "C6"],
    ];
    s.extend(std::iter::repeat_n(vec!["C6"], 200));
    s.push(vec!["C5", "C6"]);
    if right {
        s.push(vec!["C5"]);
    } else {
        s.push(vec!["C5", "C6", exit]);
    }
    s.extend([vec!["C5", exit], vec!["C5", exit], vec!["C5", far]]);
    s.extend(std::iter::repeat_n(vec![], 200));
    s.push(vec!["C4"]);
    s
}

#[test]
fn control_variants_trip_their_constraint_on_scripted_boxes() {
    let lib = ErrorLibrary::load(&station().join("programs/errors.ron"), &plant()).unwrap();
    // E13 and E14 need the plant's reaction (the next box's timing), not a script.
    let mut checked = 0;
    for v in lib
        .variants
        .iter()
        .filter(|v| !["E13", "E14"].contains(&v.def.id.as_str()))
    {
        let mut c = Closed::new(ProgramRuntime::new(Arc::new(v.compiled.clone())));
        c.rt.press("START").unwrap();
        for s in script(true).iter().chain(&script(false)) {
            c.scan(s);
        }
        let first = c.engine.trips.first().map(|t| {
            t.constraints
                .iter()
                .map(|k| k.id.clone())
                .collect::<Vec<_>>()
        });
        let first = first.unwrap_or_default();
        assert!(
            first.contains(&v.def.expected_constraint),
            "{}: expected {}, first violation {first:?}",
            v.def.id,
            v.def.expected_constraint
        );
        checked += 1;
    }
    assert!(checked >= 12);
    // And the reference on the same script: nothing.
    let mut c = Closed::new(reference());
    c.rt.press("START").unwrap();
    for s in script(true).iter().chain(&script(false)) {
        c.scan(s);
    }
    assert!(c.violations().is_empty(), "{:?}", c.violations());
}

#[test]
fn control_shipped_observers_let_the_reference_evacuate_both_ways() {
    // With the paper's `set: "FE(C6)"`, a box leaving to the LEFT would set P67 and
    // nothing would reset it, so releasing A4 would violate CSs11. The shipped rule
    // `FE(C6) . /C8` (C8 is on when C6 falls on the left side) fixes it.
    let (bundle, _) = PlantBundle::load(&station()).unwrap();
    let mut engine = Engine::new(&bundle, FilterMode::ReportOnly, 4);
    engine.set_plausibility(false); // scripted boxes
    let mut rt = reference();
    rt.press("START").unwrap();
    let p = plant();
    let mut t = 0;
    for s in script(true).iter().chain(&script(false)) {
        let mut bits = Bits::zeros(p.inputs.len());
        for i in s {
            bits.set(p.input(i).unwrap(), true);
        }
        for (i, o) in p.mirrors() {
            bits.set(i, engine.applied().get(o));
        }
        t += 10;
        engine.cycle(Millis(t), &bits, &mut rt);
    }
    let ids: Vec<&str> = engine
        .trips
        .iter()
        .flat_map(|t| t.constraints.iter().map(|c| c.id.as_str()))
        .collect();
    assert!(ids.is_empty(), "{ids:?}");
}

/// Skipping quiescent scans never changes what the program commands: a runtime that
/// evaluates every scan and one that skips stable ones give the same outputs on random
/// input sequences (inputs often held for many scans, as on a real plant).
#[test]
fn quiescent_scans_are_skipped_without_changing_the_outputs() {
    let p = plant();
    let mut fast = reference();
    let mut full = reference();
    full.always_evaluate();
    let mut rng = crate::synthetic::SplitMix64::new(11);
    let mut frame = Frame::new([p.inputs.len(), p.outputs.len(), 0, 0]);
    let (mut a, mut b) = (Bits::zeros(p.outputs.len()), Bits::zeros(p.outputs.len()));
    for k in 0..20_000u64 {
        if k == 3 || rng.chance(1, 50) {
            let _ = fast.press("START");
            let _ = full.press("START");
        }
        frame.shift();
        if rng.chance(1, 8) {
            let i = rng.below(p.inputs.len() as u64) as usize;
            let v = frame.now(Space::Input).get(i);
            frame.now_mut(Space::Input).set(i, !v);
        }
        fast.scan(Millis(k * 10), &frame, &mut a);
        full.scan(Millis(k * 10), &frame, &mut b);
        assert_eq!(a, b, "scan {k}");
        assert_eq!(fast.active_steps(), full.active_steps(), "scan {k}");
    }
}

#[test]
fn a_program_version_changes_with_any_edit_and_only_then() {
    let path = station().join("programs/reference.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let p = Program::from_ron(&text, &path).unwrap();
    let v = p.version();
    assert_eq!(v.len(), 12);
    assert!(v.bytes().all(|b| b.is_ascii_hexdigit()), "{v}");
    // The same program read again (or cloned) has the same version.
    assert_eq!(Program::from_ron(&text, &path).unwrap().version(), v);
    // Any receptivity, action or equation edit changes it; undoing it restores it.
    let mut edited = p.clone();
    let t = &mut edited.charts[0].transitions[0];
    let before = t.condition.clone();
    t.condition = format!("({before}) . 1");
    assert_ne!(edited.version(), v);
    edited.charts[0].transitions[0].condition = before;
    assert_eq!(edited.version(), v);
    let mut edited = p.clone();
    let step = edited
        .charts
        .iter_mut()
        .flat_map(|c| c.steps.iter_mut())
        .find(|s| !s.actions.is_empty())
        .unwrap();
    step.actions.pop();
    assert_ne!(edited.version(), v, "an action removed");
}

/// A counter in Vigie's own format: its equation is the count input, `reset` beside it;
/// A0 reads Q after the third box at C0 (rising edges), until C1 resets it. A reset
/// that reads an unknown name, or a counter without its equation, is a problem placed
/// in the file.
#[test]
fn a_ron_counter_counts_edges_of_its_equation_and_its_reset_clears_it() {
    let text = r#"(
        name: "count", charts: [],
        counters: [(id: "n3", kind: Up, preset: 3, reset: "C1")],
        equations: [("n3", "C0"), ("A0", "n3")],
    )"#;
    let mut o = Open::new(text);
    let on: Vec<bool> = [
        &["C0"][..],
        &[],
        &["C0"],
        &["C0"],
        &[],
        &["C0"],
        &[],
        &["C1", "C0"],
        &["C0"],
    ]
    .iter()
    .map(|i| o.scan(i).contains(&"A0".to_string()))
    .collect();
    assert_eq!(
        on,
        [false, false, false, false, false, true, true, false, false]
    );
    let unknown = compile(&text.replace("reset: \"C1\"", "reset: \"C1 . Z9\"")).expect_err("Z9");
    assert!(unknown[0].message.contains("Z9"), "{}", unknown[0]);
    let at = unknown[0].location.as_ref().expect("placed");
    assert_eq!(at.line, 3, "{}", unknown[0]);
    let missing = compile(&text.replace("(\"n3\", \"C0\"), ", "")).expect_err("no input");
    assert!(
        missing
            .iter()
            .any(|p| p.message.contains("counter `n3` has no equation")),
        "{missing:?}"
    );
}
