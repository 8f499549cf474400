//! The plant as components (`components.ron`): what each component is, which outputs
//! drive it, which sensors read it, and the dangerous states its expert declares.
//!
//! The file is authored by the plant's engineer, so it is loaded like every authored
//! RON file of a plant folder: unknown fields are refused, and every problem carries
//! the file, line and column of what it names.
//!
//! ```ron
//! Components(
//!     name: "Drilling station",
//!     components: [
//!         (id: "head", name: "Drill head", kind: Axis((
//!             min: 0.0, max: 210.0, start: 0.0, unit: "mm",
//!             drives: [(when: "DGV", speed: 100.0), (when: "MGV", speed: -100.0)],
//!             sensors: [(signal: "h", from: 0.0, to: 2.0)],
//!         ))),
//!     ],
//! )
//! ```

use super::kinds::KindDef;
use crate::diag::{Location, Problem, codes, ron_problem};
use crate::expr::parse_str;
use crate::plant::Plant;
use crate::symbols::Space;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest internal step of the component emulator, ms.
const MAX_STEP_MS: u64 = 100;

/// A plant described as components.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Components {
    /// Display name.
    pub name: String,
    /// Internal step of the emulator, ms (1 by default).
    #[serde(default = "one_ms")]
    pub step_ms: u64,
    /// The components, in drawing order.
    pub components: Vec<ComponentDef>,
    /// States the plant's expert declares dangerous (seed 004, section 2, "états
    /// dangereux"), beyond the hazards every kind knows.
    #[serde(default)]
    pub dangers: Vec<DangerDef>,
    /// The constants of the items' physics on conveyors and turntables.
    #[serde(default)]
    pub items: super::items::ItemsDef,
    /// The file it was loaded from, for messages.
    #[serde(skip)]
    pub file: PathBuf,
    /// First position of each quoted string in the source, for messages.
    #[serde(skip)]
    positions: BTreeMap<String, (usize, usize)>,
}

fn one_ms() -> u64 {
    1
}

/// One component: an id the other files of the plant name it by, a display name, and
/// its kind with the kind's own parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentDef {
    /// Id (`head`), unique in the plant.
    pub id: String,
    /// Display name (`Drill head`).
    pub name: String,
    /// What it is.
    pub kind: KindDef,
    /// Where it stands on the floor (a top view), when the engineer gives it: the
    /// synoptic then draws the plant to scale, and a plant whose conveyors and
    /// turntable are all placed gets the console's top view.
    #[serde(default)]
    pub at: Option<Placement>,
}

/// A component's place on the floor, world millimetres, top view (x to the right, y
/// upwards): a conveyor's entry end (its belt runs along `heading`), a turntable's
/// centre (its rollers' axis points along `heading` at angle 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    /// Abscissa, mm.
    pub x: f64,
    /// Ordinate, mm.
    pub y: f64,
    /// Direction of its axis, degrees counter-clockwise from +x.
    #[serde(default)]
    pub heading: f64,
    /// Width across its axis, mm.
    pub width: f64,
}

impl Placement {
    /// What is wrong with it, if anything.
    pub(crate) fn check(&self) -> Option<String> {
        let finite = [self.x, self.y, self.heading, self.width]
            .iter()
            .all(|v| v.is_finite() && v.abs() <= 1e9);
        if !finite {
            return Some("its placement must be finite numbers within 1e9 mm".to_string());
        }
        (self.width <= 0.0).then(|| format!("its placed width {} must be positive", self.width))
    }
}

/// A dangerous state: while `when` (over the plant's signals, outputs as applied)
/// holds and the component `component` is within `[from, to]` of its travel, the
/// plant is damaged.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DangerDef {
    /// Id (`fast_into_part`).
    pub id: String,
    /// What happens, for the operator (`the bit enters the part at full speed`).
    pub text: String,
    /// The component whose position matters.
    pub component: String,
    /// The zone of its travel, in the component's unit.
    pub from: f64,
    /// End of the zone.
    pub to: f64,
    /// The signals' condition, in the logic notation; `1` for always.
    #[serde(default = "always")]
    pub when: String,
}

fn always() -> String {
    "1".to_string()
}

impl Components {
    /// Loads `components.ron`.
    pub fn load(path: &Path) -> Result<Self, Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
        Self::from_ron(&text, path)
    }

    /// Parses a components file and checks what needs no plant; `file` is for messages.
    pub fn from_ron(text: &str, file: &Path) -> Result<Self, Vec<Problem>> {
        let mut c: Components = ron::from_str(text).map_err(|e| vec![ron_problem(file, &e)])?;
        c.file = file.to_path_buf();
        c.positions = crate::emulator::quoted_positions(text);
        let problems = c.check();
        if problems.is_empty() {
            Ok(c)
        } else {
            Err(problems)
        }
    }

    /// A description built in memory (a legacy layout read as components), checked as
    /// a file would be; `file` and `positions` (first line and column of each quoted
    /// string) locate its messages.
    pub(crate) fn assembled(
        name: String,
        step_ms: u64,
        components: Vec<ComponentDef>,
        items: super::items::ItemsDef,
        file: &Path,
        positions: BTreeMap<String, (usize, usize)>,
    ) -> Result<Self, Vec<Problem>> {
        let c = Components {
            name,
            step_ms,
            components,
            dangers: Vec::new(),
            items,
            file: file.to_path_buf(),
            positions,
        };
        let problems = c.check();
        if problems.is_empty() {
            Ok(c)
        } else {
            Err(problems)
        }
    }

    /// The arrivals of the first conveyor with a source, if any.
    pub fn first_source(&self) -> Option<&super::items::ArrivalsDef> {
        self.components.iter().find_map(|c| match &c.kind {
            KindDef::Conveyor(v) => v.source.as_ref().map(|s| &s.arrivals),
            _ => None,
        })
    }

    /// Where `quoted` first appears in the file (the start of the file when it does
    /// not), for messages.
    pub fn location_of(&self, quoted: &str) -> Location {
        let (line, col) = self.positions.get(quoted).copied().unwrap_or((1, 1));
        Location::new(&self.file, line, col)
    }

    /// An error of `code` located at the first occurrence of `quoted`.
    pub(crate) fn error(&self, code: &'static str, quoted: &str, message: String) -> Problem {
        Problem::error(code, message, Some(self.location_of(quoted)))
    }

    /// Where the conveyors' exits and the turntables' positions lead: to conveyors
    /// (an exit to a turntable, one whose positions join that exit).
    fn check_links(&self) -> Vec<Problem> {
        let mut out = Vec::new();
        for c in &self.components {
            let super::kinds::KindDef::Conveyor(v) = &c.kind else {
                continue;
            };
            let Some(to) = v.target() else { continue };
            let next = self.components.iter().find(|o| o.id == to);
            let joins_it = |t: &super::kinds::turntable::TurntableDef| {
                t.positions
                    .iter()
                    .flat_map(|p| &p.joins)
                    .any(|j| j.to == c.id && j.at == super::kinds::turntable::End::End)
            };
            let fits = match next.map(|n| &n.kind) {
                Some(super::kinds::KindDef::Conveyor(_)) => true,
                Some(super::kinds::KindDef::Turntable(t)) => joins_it(t),
                _ => false,
            };
            if !fits || to == c.id {
                out.push(self.error(
                    codes::COMPONENTS_INVALID.id,
                    to,
                    format!(
                        "component `{}`: its exit leads to `{to}`, which is not another \
                         conveyor nor a turntable with a position joining this exit",
                        c.id
                    ),
                ));
            }
        }
        for c in &self.components {
            let super::kinds::KindDef::Turntable(t) = &c.kind else {
                continue;
            };
            for to in t.joined() {
                let ok = self
                    .components
                    .iter()
                    .any(|o| o.id == to && matches!(o.kind, super::kinds::KindDef::Conveyor(_)));
                if !ok {
                    out.push(self.error(
                        codes::COMPONENTS_INVALID.id,
                        to,
                        format!(
                            "component `{}`: a position joins `{to}`, which is not a conveyor",
                            c.id
                        ),
                    ));
                }
            }
        }
        out
    }

    /// The checks that need no plant: unique ids, the step, each kind's own values.
    pub fn check(&self) -> Vec<Problem> {
        let mut out = Vec::new();
        if !(1..=MAX_STEP_MS).contains(&self.step_ms) {
            out.push(Problem::error(
                codes::COMPONENTS_INVALID.id,
                format!(
                    "step_ms is {} ms: the emulator's step is from 1 to {MAX_STEP_MS} ms",
                    self.step_ms
                ),
                Some(Location::new(&self.file, 1, 1)),
            ));
        }
        let mut seen = BTreeSet::new();
        for c in &self.components {
            if !seen.insert(c.id.as_str()) {
                out.push(self.error(
                    codes::COMPONENTS_DUPLICATE.id,
                    &c.id,
                    format!("component `{}` is declared twice", c.id),
                ));
            }
            for message in c
                .kind
                .check()
                .into_iter()
                .chain(c.at.and_then(|a| a.check()))
            {
                out.push(self.error(
                    codes::COMPONENTS_INVALID.id,
                    &c.id,
                    format!("component `{}`: {message}", c.id),
                ));
            }
        }
        out.extend(self.check_links());
        for message in self.items.check() {
            out.push(self.error(codes::COMPONENTS_INVALID.id, "items", message));
        }
        for c in &self.components {
            let super::kinds::KindDef::Conveyor(v) = &c.kind else {
                continue;
            };
            let Some(from) = v.carries_from() else {
                continue;
            };
            let src = self.components.iter().find(|o| o.id == from);
            let takes = matches!(
                src.map(|n| &n.kind),
                Some(super::kinds::KindDef::Conveyor(s)) if s.take.is_some()
            );
            if !takes || from == c.id {
                out.push(self.error(
                    codes::COMPONENTS_INVALID.id,
                    from,
                    format!(
                        "component `{}`: its feeder carries from `{from}`, which is not another conveyor with a `take`",
                        c.id
                    ),
                ));
            }
        }
        for d in &self.dangers {
            if !seen.contains(d.component.as_str()) {
                out.push(self.error(
                    codes::COMPONENTS_INVALID.id,
                    &d.component,
                    format!(
                        "danger `{}` names component `{}`, which is not declared",
                        d.id, d.component
                    ),
                ));
            }
            if d.from.is_nan() || d.to.is_nan() || d.from > d.to {
                out.push(self.error(
                    codes::COMPONENTS_INVALID.id,
                    &d.id,
                    format!(
                        "danger `{}`: its zone [{}, {}] is empty",
                        d.id, d.from, d.to
                    ),
                ));
            }
        }
        out
    }

    /// The warnings about what the machine lets its constraints see: a conveyor whose
    /// feeder can place an item onto one its entry beams do not see (V0748), so that no
    /// constraint over those beams forbids that collision.
    pub fn warnings(&self) -> Vec<Problem> {
        // Every length an item may have anywhere: items pass from belt to belt.
        let lengths: Vec<f64> = self
            .components
            .iter()
            .filter_map(|c| match &c.kind {
                KindDef::Conveyor(v) => v.feed.as_ref(),
                _ => None,
            })
            .flat_map(|f| f.items.iter().map(|i| i.length))
            .collect();
        let mut out = Vec::new();
        for c in &self.components {
            let KindDef::Conveyor(v) = &c.kind else {
                continue;
            };
            if let Some((from, to, e, n)) = v.unseen_entry(&lengths) {
                out.push(Problem::warning(
                    codes::ENTRY_UNSEEN.id,
                    format!(
                        "conveyor `{}`: an item of {e} {u} whose rear is between {from} and {to} {u} still occupies the entry where the feeder places the next one ({n} {u}), and no entry beam sees it: no constraint over the beams can forbid that collision; put a beam at {n} {u} from the entry",
                        c.id,
                        u = v.unit
                    ),
                    Some(self.location_of(&c.id)),
                ));
            }
        }
        out
    }

    /// The checks against the plant: every signal named exists and is of the right
    /// kind (drives read outputs, sensors write inputs), every expression parses and
    /// names the plant's signals only, and no input is written by two components.
    pub fn check_signals(&self, plant: &Plant) -> Vec<Problem> {
        let symbols = plant.symbols();
        let mut out = Vec::new();
        let mut written: BTreeMap<&str, &str> = BTreeMap::new();
        for c in &self.components {
            for (signal, space) in c.kind.signals() {
                match symbols.lookup(signal) {
                    Some((s, _)) if s == space => {}
                    found => {
                        let want = if space == Space::Input {
                            "sensor"
                        } else {
                            "actuator"
                        };
                        let why = match found {
                            Some((Space::Input, _)) => "which the plant declares as a sensor",
                            Some((Space::Output, _)) => "which the plant declares as an actuator",
                            Some(_) => "which is not a plant signal",
                            None => "which the plant does not declare",
                        };
                        out.push(self.error(
                            codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                            signal,
                            format!("component `{}` names {want} `{signal}`, {why}", c.id),
                        ));
                    }
                }
                if space == Space::Input
                    && let Some(other) = written.insert(signal, &c.id)
                {
                    out.push(self.error(
                        codes::COMPONENTS_DUPLICATE.id,
                        signal,
                        format!(
                            "sensor `{signal}` is read from both `{other}` and `{}`",
                            c.id
                        ),
                    ));
                }
            }
            for text in c.kind.expressions() {
                out.extend(self.check_expression(text, &c.id, plant));
            }
        }
        for d in &self.dangers {
            out.extend(self.check_expression(&d.when, &d.id, plant));
        }
        out
    }

    fn check_expression(&self, text: &str, owner: &str, plant: &Plant) -> Option<Problem> {
        let symbols = plant.symbols();
        let err = parse_str(text)
            .and_then(|e| e.to_dnf(&symbols).map(|_| ()))
            .err()?;
        let (line, col) = self.positions.get(text).copied().unwrap_or((1, 1));
        Some(Problem::error(
            codes::COMPONENTS_EXPRESSION.id,
            format!("`{owner}`: expression `{text}`: {}", err.message),
            Some(Location::new(
                &self.file,
                line + err.span.line - 1,
                if err.span.line == 1 {
                    col + err.span.column - 1
                } else {
                    err.span.column
                },
            )),
        ))
    }

    /// The component `id`.
    pub fn component(&self, id: &str) -> Option<&ComponentDef> {
        self.components.iter().find(|c| c.id == id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::{Signal, SignalKind};

    fn plant() -> Plant {
        Plant {
            name: "t".into(),
            description: String::new(),
            inputs: vec![
                Signal::new("lo", SignalKind::Sensor, "low end"),
                Signal::new("hi", SignalKind::Sensor, "high end"),
            ],
            outputs: vec![Signal::new("Y", SignalKind::Actuator, "extend")],
        }
    }

    const CYLINDER: &str = r#"Components(
    name: "t",
    components: [
        (id: "cyl", name: "Cylinder", kind: Axis((
            min: 0.0, max: 100.0, start: 0.0,
            drives: [(when: "Y", speed: 200.0), (when: "/Y", speed: -200.0)],
            sensors: [(signal: "lo", from: 0.0, to: 2.0), (signal: "hi", from: 98.0, to: 100.0)],
        ))),
    ],
)"#;

    /// A belt with a feeder placing `items` (lengths) and beams (`at`, `sees`).
    fn belt(items: &[f64], beams: &[(f64, Option<&str>)]) -> Components {
        let items: Vec<String> = items
            .iter()
            .enumerate()
            .map(|(k, l)| format!("(class: \"c{k}\", length: {l:?})"))
            .collect();
        let beams: Vec<String> = beams
            .iter()
            .enumerate()
            .map(|(k, (at, sees))| {
                let sees = sees.map_or("None".to_string(), |t| format!("Some(\"{t}\")"));
                format!("(signal: \"b{k}\", at: {at:?}, sees: {sees})")
            })
            .collect();
        let text = format!(
            r#"Components(name: "t", components: [
    (id: "belt", name: "Belt", kind: Conveyor((
        length: 1000.0,
        drives: [(when: "Y", speed: 100.0)],
        sensors: [{}],
        feed: Some((when: "Y", items: [{}])),
    ))),
])"#,
            beams.join(", "),
            items.join(", ")
        );
        Components::from_ron(&text, Path::new("c.ron")).unwrap()
    }

    /// The rear positions of the first unseen entry, or `None`.
    fn unseen(c: &Components) -> Option<(f64, f64)> {
        let w = c.warnings();
        assert!(w.len() <= 1, "{w:?}");
        w.first().map(|p| {
            assert_eq!(p.code, codes::ENTRY_UNSEEN.id);
            assert!(!p.is_error());
            let at = p.location.as_ref().unwrap();
            assert_eq!((at.line, at.column), (2, 11), "{p:?}");
            let m = &p.message;
            let inner = &m[m.find("is between ").unwrap() + 11..];
            let (a, b) = inner.split_once(" and ").unwrap();
            let b = &b[..b.find(' ').unwrap()];
            (a.parse().unwrap(), b.parse().unwrap())
        })
    }

    #[test]
    fn an_entry_beam_short_of_the_items_length_leaves_an_unseen_entry() {
        // The workshop's first beam: at 100 mm for pallets of 200 mm.
        assert_eq!(
            unseen(&belt(&[200.0], &[(100.0, None)])),
            Some((100.0, 200.0))
        );
        // At the pallet's length it sees every pallet a new one would hit.
        assert_eq!(unseen(&belt(&[200.0], &[(200.0, None)])), None);
        // Past it, a pallet just placed is not seen until it reaches the beam.
        assert_eq!(unseen(&belt(&[200.0], &[(250.0, None)])), Some((0.0, 50.0)));
        // Two beams whose windows join: [-100, 100] and [100, 300].
        let two = belt(&[200.0], &[(100.0, None), (300.0, None)]);
        assert_eq!(unseen(&two), None);
        // A beam for tall items only sees nothing of the others.
        assert_eq!(
            unseen(&belt(&[200.0], &[(200.0, Some("tall"))])),
            Some((0.0, 200.0))
        );
        // Mixed lengths: a beam at 60 sees a 40 mm item only from rear 20.
        assert_eq!(
            unseen(&belt(&[40.0, 60.0], &[(60.0, None)])),
            Some((0.0, 20.0))
        );
        assert_eq!(
            unseen(&belt(&[40.0, 60.0], &[(40.0, None), (60.0, None)])),
            None
        );
        // No beam at all.
        assert_eq!(unseen(&belt(&[200.0], &[])), Some((0.0, 200.0)));
    }

    #[test]
    fn a_monostable_cylinder_loads_and_names_the_plants_signals() {
        let c = Components::from_ron(CYLINDER, Path::new("c.ron")).unwrap();
        assert!(c.check_signals(&plant()).is_empty());
    }

    #[test]
    fn an_unknown_sensor_is_located_at_its_name() {
        let text = CYLINDER.replace("\"hi\"", "\"top\"");
        let c = Components::from_ron(&text, Path::new("c.ron")).unwrap();
        let p = c.check_signals(&plant());
        assert_eq!(p.len(), 1, "{p:?}");
        assert_eq!(p[0].code, codes::COMPONENTS_UNKNOWN_SIGNAL.id);
        let at = p[0].location.as_ref().unwrap();
        assert_eq!((at.line, at.column), (7, 69), "{}", p[0]);
    }

    #[test]
    fn a_drive_on_a_sensor_and_a_bad_expression_are_refused() {
        let text = CYLINDER.replace("when: \"/Y\"", "when: \"/Y . \"");
        let c = Components::from_ron(&text, Path::new("c.ron")).unwrap();
        let p = c.check_signals(&plant());
        assert!(
            p.iter().any(|p| p.code == codes::COMPONENTS_EXPRESSION.id
                && p.location.as_ref().is_some_and(|l| l.line == 6)),
            "{p:?}"
        );
    }

    #[test]
    fn duplicate_ids_a_bad_step_and_unknown_fields_are_refused() {
        let twice = CYLINDER.replace(
            "    ],\n)",
            "        (id: \"cyl\", name: \"Again\", kind: Axis((min: 0.0, max: 1.0, start: 0.0, drives: [], sensors: []))),\n    ],\n)",
        );
        let p = Components::from_ron(&twice, Path::new("c.ron")).unwrap_err();
        assert!(
            p.iter().any(|p| p.code == codes::COMPONENTS_DUPLICATE.id),
            "{p:?}"
        );
        let step = CYLINDER.replace("name: \"t\",", "name: \"t\", step_ms: 0,");
        let p = Components::from_ron(&step, Path::new("c.ron")).unwrap_err();
        assert!(p[0].message.contains("step_ms"), "{p:?}");
        let unknown = CYLINDER.replace("start: 0.0,", "start: 0.0, colour: 3,");
        let p = Components::from_ron(&unknown, Path::new("c.ron")).unwrap_err();
        assert!(p[0].message.contains("colour"), "{p:?}");
    }
}
