//! PLCopen import and export: every plant's programs written and read back, the
//! station's runs from the PLCopen file identical to its runs from RON, and the IEC
//! 61131-3 semantics of the SFC and the action qualifiers on worked examples.

use super::*;
use crate::control::{CompiledProgram, ErrorLibrary, Origin, Program};
use crate::diag::{Problem, render};
use crate::engine::FilterMode;
use crate::plant::Plant;
use crate::sim::{Options, ProgramChoice, Scenario, Simulation};
use crate::time::Millis;
use std::path::{Path, PathBuf};

mod conformance;
mod fixtures;

/// A program alone on a plant, one scan every 10 ms, inputs given by name.
pub(super) struct Open {
    rt: crate::control::ProgramRuntime,
    plant: Plant,
    frame: crate::frame::Frame,
    out: crate::bits::Bits,
    t: u64,
}

impl Open {
    /// `program` read from PLCopen `xml` (`file` in messages) and compiled for `plant`.
    pub(super) fn new(xml: &str, file: &Path, plant: Plant) -> Self {
        let program = import(xml, file, &plant).unwrap_or_else(|p| panic!("{}\n{xml}", shown(&p)));
        let compiled = CompiledProgram::new(&program, &plant, &Origin::default())
            .unwrap_or_else(|p| panic!("{}\n{program:#?}", shown(&p)));
        Self {
            rt: crate::control::ProgramRuntime::new(std::sync::Arc::new(compiled)),
            frame: crate::frame::Frame::new([plant.inputs.len(), plant.outputs.len(), 0, 0]),
            out: crate::bits::Bits::zeros(plant.outputs.len()),
            plant,
            t: 0,
        }
    }

    /// One scan with these inputs on.
    pub(super) fn scan(&mut self, inputs: &[&str]) -> &mut Self {
        use crate::engine::Control as _;
        use crate::symbols::Space;
        self.frame.shift();
        self.frame.now_mut(Space::Input).clear();
        for i in inputs {
            let k = self.plant.input(i).expect("an input of the plant");
            self.frame.now_mut(Space::Input).set(k, true);
        }
        self.t += 10;
        self.rt.scan(Millis(self.t), &self.frame, &mut self.out);
        self
    }

    /// A name's value after the last scan.
    pub(super) fn v(&self, name: &str) -> bool {
        self.rt.value(name).unwrap_or_else(|| panic!("no `{name}`"))
    }

    /// The active steps.
    pub(super) fn active(&self) -> Vec<&str> {
        self.rt.active_steps()
    }

    /// The outputs on after the last scan.
    pub(super) fn outputs(&self) -> Vec<String> {
        self.out
            .ones()
            .map(|k| self.plant.outputs[k].id.clone())
            .collect()
    }
}

fn layouts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts")
}

fn plant_dirs() -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(layouts())
        .expect("layouts")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.join("programs/reference.ron").exists())
        .collect();
    dirs.sort();
    assert!(dirs.len() >= 7, "{dirs:?}");
    dirs
}

fn shown(p: &[Problem]) -> String {
    render(p)
}

fn write(program: &Program, plant: &Plant) -> String {
    export(program, plant, Path::new("program.ron"))
        .unwrap_or_else(|p| panic!("{}: {}", program.name, shown(&p)))
}

fn read(xml: &str, plant: &Plant) -> Program {
    import(xml, Path::new("program.xml"), plant).unwrap_or_else(|p| panic!("{}\n{xml}", shown(&p)))
}

/// Every program of every plant: the reference and each variant of its error library.
fn every_program() -> Vec<(String, Plant, Program)> {
    let mut out = Vec::new();
    for dir in plant_dirs() {
        let plant = Plant::load(&dir.join("plant.ron")).expect("plant");
        let lib = ErrorLibrary::load(&dir.join("programs/errors.ron"), &plant).expect("library");
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        out.push((
            format!("{name}/reference"),
            plant.clone(),
            lib.reference.clone(),
        ));
        for v in lib.variants {
            out.push((format!("{name}/{}", v.def.id), plant.clone(), v.program));
        }
    }
    assert!(out.len() > 40, "{}", out.len());
    out
}

/// Import, export, import gives the same program, and writing it again the same
/// file, for every program of every plant.
#[test]
fn every_program_of_every_plant_reads_back_the_same_after_export_and_import() {
    for (name, plant, p0) in every_program() {
        let xml1 = write(&p0, &plant);
        let p1 = read(&xml1, &plant);
        CompiledProgram::new(&p1, &plant, &Origin::default())
            .unwrap_or_else(|p| panic!("{name}: {}\n{xml1}", shown(&p)));
        let xml2 = write(&p1, &plant);
        let p2 = read(&xml2, &plant);
        // The places are those of each file; the elements placed are the same.
        assert_eq!(
            p1.places.keys().collect::<Vec<_>>(),
            p2.places.keys().collect::<Vec<_>>(),
            "{name}: places"
        );
        let unplaced = |p: &Program| Program {
            places: std::collections::BTreeMap::new(),
            ..p.clone()
        };
        assert_eq!(
            unplaced(&p1),
            unplaced(&p2),
            "{name}: import, export, import differs\n{xml2}"
        );
        assert_eq!(
            xml2,
            write(&p2, &plant),
            "{name}: the second export differs"
        );
        // What the original says survives: steps, transitions, actions, buttons.
        assert_eq!(p1.panel, p0.panel, "{name}");
        assert_eq!(
            (p1.start.clone(), p1.stop.clone()),
            (p0.start.clone(), p0.stop.clone()),
            "{name}"
        );
        let ids = |p: &Program| {
            let mut v: Vec<String> = p.transitions().map(|(_, t)| t.id.clone()).collect();
            v.sort();
            v
        };
        assert_eq!(ids(&p1), ids(&p0), "{name}");
        let charts = |p: &Program| p.charts.iter().map(|c| c.name.clone()).collect::<Vec<_>>();
        assert_eq!(charts(&p1), charts(&p0), "{name}");
    }
}

/// A scratch folder removed at the end of the test.
struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("vigie-plcopen-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `scenario` and the same with its program read from `xml`; the commanded
/// outputs and the sensors must be equal at every cycle.
fn same_runs(name: &str, scenario: &Scenario, path: &Path, xml_file: &Path, until: u64) {
    let options = Options {
        history_cycles: 10,
        explain: false,
    };
    let mut a = Simulation::from_scenario(scenario, path, options.clone()).expect("starts");
    let mut s = scenario.clone();
    s.program = ProgramChoice::File(xml_file.to_string_lossy().into_owned());
    let mut b = Simulation::from_scenario(&s, path, options)
        .unwrap_or_else(|p| panic!("{name}: {}", shown(&p)));
    let mut cycles = 0u64;
    while a.now() < Millis(until) {
        a.cycle();
        b.cycle();
        cycles += 1;
        assert_eq!(
            a.engine.commanded(),
            b.engine.commanded(),
            "{name}: the PLCopen program commands differently at {} ms (cycle {cycles})",
            a.now().0
        );
        assert_eq!(
            a.emulator.sensors(),
            b.emulator.sensors(),
            "{name}: sensors at {} ms",
            a.now().0
        );
    }
    assert!(cycles > 100, "{name}: {cycles} cycles");
    assert_eq!(a.emulator.hazards(), b.emulator.hazards(), "{name}");
}

/// The station's reference program and every variant of its error library, written as
/// PLCopen XML and loaded from that file, run every scenario of the station (the
/// reference) and a busy minute with and without the filter (each variant) exactly as
/// the RON programs do, cycle by cycle.
#[test]
fn the_station_runs_the_same_from_its_plcopen_export() {
    let station = layouts().join("sorting-station");
    let plant = Plant::load(&station.join("plant.ron")).expect("plant");
    let lib = ErrorLibrary::load(&station.join("programs/errors.ron"), &plant).expect("library");
    let scratch = Scratch::new("station");
    let reference = scratch.0.join("reference.xml");
    std::fs::write(&reference, write(&lib.reference, &plant)).expect("writes");
    let mut names: Vec<PathBuf> = std::fs::read_dir(station.join("scenarios"))
        .expect("scenarios")
        .map(|e| e.expect("entry").path())
        .collect();
    names.sort();
    for path in names {
        let scenario = Scenario::load(&path).expect("scenario");
        if scenario.program != ProgramChoice::Reference {
            continue;
        }
        let until = scenario.duration_ms.min(600_000);
        same_runs(
            &path.display().to_string(),
            &scenario,
            &path,
            &reference,
            until,
        );
    }
    let base = Scenario::load(&station.join("scenarios/cs10-paper.ron")).expect("scenario");
    for v in &lib.variants {
        let file = scratch.0.join(format!("{}.xml", v.def.id));
        std::fs::write(&file, write(&v.program, &plant)).expect("writes");
        for filter in [FilterMode::Off, FilterMode::Enforce] {
            let mut s = base.clone();
            s.program = ProgramChoice::Error(v.def.id.clone());
            s.filter = filter;
            let path = station.join("scenarios/cs10-paper.ron");
            same_runs(
                &format!("{} {filter:?}", v.def.id),
                &s,
                &path,
                &file,
                60_000,
            );
        }
    }
}

/// The text of `xml` from 1-based `line` and `column` on.
fn at(xml: &str, line: usize, column: usize) -> String {
    xml.lines()
        .nth(line - 1)
        .map(|l| l.chars().skip(column - 1).collect())
        .unwrap_or_default()
}

/// Every variant of the station's error library, run from its PLCopen export with the
/// filter: each trip's hypothesis is the one the RON program gives, with after each
/// program suspect the places (X420) of the steps, transitions and equations it names,
/// and each place is where that element is written in the file.
#[test]
fn the_hypothesis_places_the_suspected_elements_in_the_plcopen_file() {
    let station = layouts().join("sorting-station");
    let plant = Plant::load(&station.join("plant.ron")).expect("plant");
    let lib = ErrorLibrary::load(&station.join("programs/errors.ron"), &plant).expect("library");
    let scratch = Scratch::new("places");
    let path = station.join("scenarios/cs10-paper.ron");
    let base = Scenario::load(&path).expect("scenario");
    let (mut placed, mut kinds) = (0, std::collections::BTreeSet::new());
    for v in &lib.variants {
        let file = scratch.0.join(format!("{}.xml", v.def.id));
        let xml = write(&v.program, &plant);
        std::fs::write(&file, &xml).expect("writes");
        let mut s = base.clone();
        s.program = ProgramChoice::Error(v.def.id.clone());
        s.filter = FilterMode::Enforce;
        let steps: Vec<&str> = v.program.steps().map(|(_, st)| st.id.as_str()).collect();
        let reads_step = v.program.equations.iter().any(|(_, e)| {
            crate::expr::parse_str(e)
                .is_ok_and(|e| e.leaves().iter().any(|(n, _, _)| steps.contains(n)))
        });
        let mut a = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
        s.program = ProgramChoice::File(file.to_string_lossy().into_owned());
        let mut b = Simulation::from_scenario(&s, &path, Options::default()).expect("starts");
        a.run_until(Millis(60_000));
        b.run_until(Millis(60_000));
        assert_eq!(a.explanations.len(), b.explanations.len(), "{}", v.def.id);
        for (ea, eb) in a.explanations.values().zip(b.explanations.values()) {
            let (places, rest): (Vec<_>, Vec<_>) =
                eb.hypothesis.items.iter().partition(|i| i.code == "X420");
            // The same suspects (a receptivity reads as its IEC form: `C7 . /C7_PRE`
            // for `RE(C7)`).
            let shape = |i: &crate::explain::Item| {
                let mut f = i.fields.clone();
                for k in ["receptivity", "signals", "expression", "condition"] {
                    f.remove(k);
                }
                (i.code, f)
            };
            // An equation that reads a step is exported reading an `S_X` memory its
            // step drives (IEC steps are local to their POU): the import sees a memory,
            // so the suspects that go from the equation to the step (X413) differ.
            if !reads_step {
                assert_eq!(
                    rest.iter().map(|i| shape(i)).collect::<Vec<_>>(),
                    ea.hypothesis.items.iter().map(shape).collect::<Vec<_>>(),
                    "{}: the same suspects",
                    v.def.id
                );
            }
            for p in places {
                let f = |k: &str| p.fields.get(k).cloned().unwrap_or_default();
                let (line, column) = (
                    f("line").parse().expect("line"),
                    f("column").parse().expect("column"),
                );
                let text = at(&xml, line, column);
                let element = f("element");
                let ok = match f("kind").as_str() {
                    "step" => {
                        text.starts_with("<step localId=")
                            && text.contains(&format!("name=\"{element}\""))
                    }
                    "transition" => text.starts_with("<transition"),
                    _ => text
                        .to_ascii_lowercase()
                        .starts_with(&element.to_ascii_lowercase()),
                };
                assert!(
                    ok,
                    "{}: {} placed at {line}:{column}: `{text}`",
                    v.def.id, p.text
                );
                assert_eq!(f("file"), format!("{}.xml", v.def.id));
                kinds.insert(f("kind"));
                placed += 1;
            }
        }
    }
    assert!(placed > 10, "{placed} places");
    assert!(kinds.len() >= 2, "{kinds:?}");
}

/// Every other plant's reference program runs its scenarios the same from PLCopen.
#[test]
fn every_plants_reference_runs_the_same_from_its_plcopen_export() {
    let scratch = Scratch::new("plants");
    for dir in plant_dirs() {
        let plant = Plant::load(&dir.join("plant.ron")).expect("plant");
        let program = Program::from_ron(
            &std::fs::read_to_string(dir.join("programs/reference.ron")).expect("reads"),
            Path::new("reference.ron"),
        )
        .expect("parses");
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let file = scratch.0.join(format!("{name}.xml"));
        std::fs::write(&file, write(&program, &plant)).expect("writes");
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir.join("scenarios"))
            .map(|rd| rd.map(|e| e.expect("entry").path()).collect())
            .unwrap_or_default();
        paths.sort();
        let mut ran = 0;
        for path in paths
            .iter()
            .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        {
            let Ok(scenario) = Scenario::load(path) else {
                continue;
            };
            if scenario.program != ProgramChoice::Reference {
                continue;
            }
            same_runs(
                &path.display().to_string(),
                &scenario,
                path,
                &file,
                scenario.duration_ms.min(300_000),
            );
            ran += 1;
        }
        assert!(
            ran > 0 || name == "production-line",
            "{name}: no scenario on the reference"
        );
    }
}

/// An equation reading a step timer has no PLCopen form: the export says so once, with
/// the timer's name.
#[test]
fn an_equation_reading_a_step_timer_is_refused_once() {
    let plant = Plant::load(&layouts().join("single-conveyor/plant.ron")).expect("plant");
    let program = Program::from_ron(
        r#"Program(name: "t", timers: [("T1", "S0", 100)],
            charts: [Chart(name: "g", steps: [Step(id: "S0", initial: true)], transitions: [])],
            equations: [("CV", "T1")])"#,
        Path::new("t.ron"),
    )
    .expect("parses");
    let err = export(&program, &plant, Path::new("t.ron")).expect_err("refused");
    assert_eq!(err.len(), 1, "{}", shown(&err));
    assert!(err[0].message.contains("T1"), "{}", err[0]);
}
