//! Stopwatch automata as data (seed 000, Def. 2.3.1) and their synchronous product
//! (Def. 2.3.3).
//!
//! A component has its own clocks, locations (the clocks that run there, rate 1, the
//! others stopped, rate 0; an invariant) and edges (an event, a guard, the clocks reset,
//! and whether the guard is the component's *desired space*: the edge that ends a task
//! acceptably). The locations listed in `progress` are those in which the component's
//! goal must stay reachable (a task running or interrupted, a window open). Written in
//! RON:
//!
//! ```ron
//! (
//!     components: [(
//!         name: "conveyor", clocks: ["x", "y"], initial: "idle", progress: ["run", "int"],
//!         locations: [
//!             (name: "idle"),
//!             (name: "run", running: ["x", "y"], invariant: "x <= 12 && y <= 10"),
//!             (name: "int", running: ["x"], invariant: "x <= 12 && y <= 10"),
//!         ],
//!         edges: [
//!             (from: "idle", to: "run", event: "d", reset: ["x", "y"]),
//!             (from: "run", to: "int", event: "s", guard: "x < 12"),
//!             (from: "int", to: "run", event: "r", guard: "x < 12"),
//!             (from: "run", to: "idle", event: "b", guard: "10 <= x < 12 && 10 <= y <= 10", goal: true),
//!         ],
//!     )],
//! )
//! ```
//!
//! Clocks are qualified by their component in the product (`conveyor.x`). Components
//! sharing an event move together on it; a component without the event stays.

use super::linear;
use super::poly::{HalfSpace, Poly, Q};
use crate::diag::codes;
use crate::diag::{Location as At, Problem};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::Path;

/// A location as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocationDef {
    /// Its name, unique in the component.
    pub name: String,
    /// What the component does there (shown to the operator).
    #[serde(default)]
    pub label: String,
    /// The clocks that run (rate 1); the others are stopped.
    #[serde(default)]
    pub running: Vec<String>,
    /// The invariant (`true` when absent).
    #[serde(default = "truth")]
    pub invariant: String,
}

/// An edge as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeDef {
    /// Source location.
    pub from: String,
    /// Target location.
    pub to: String,
    /// The observed event.
    pub event: String,
    /// The guard (`true` when absent).
    #[serde(default = "truth")]
    pub guard: String,
    /// Clocks reset to 0.
    #[serde(default)]
    pub reset: Vec<String>,
    /// The guard is the component's desired space (the acceptable end).
    #[serde(default)]
    pub goal: bool,
}

fn truth() -> String {
    "true".into()
}

/// A component automaton as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentDef {
    /// Its name (a task or a window).
    pub name: String,
    /// Its clocks.
    pub clocks: Vec<String>,
    /// The initial location.
    pub initial: String,
    /// The locations in which its goal must stay reachable.
    #[serde(default)]
    pub progress: Vec<String>,
    /// Its locations.
    pub locations: Vec<LocationDef>,
    /// Its edges.
    pub edges: Vec<EdgeDef>,
}

/// A set of component automata (`*.swa.ron`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SwaFile {
    /// The components, composed in this order.
    pub components: Vec<ComponentDef>,
}

/// A location of the product.
#[derive(Clone, Debug)]
pub struct Location {
    /// `conveyor:run robot:idle`.
    pub name: String,
    /// The location of each component.
    pub parts: Vec<usize>,
    /// Rate of each clock (0 or 1).
    pub rates: Vec<Q>,
    /// Conjunction of the components' invariants.
    pub invariant: Poly,
}

/// An edge of the product.
#[derive(Clone, Debug)]
pub struct Edge {
    /// Source location.
    pub from: usize,
    /// Target location.
    pub to: usize,
    /// The event.
    pub event: String,
    /// Conjunction of the moving components' guards.
    pub guard: Poly,
    /// Clocks reset.
    pub resets: Vec<usize>,
    /// Components whose goal edge this is.
    pub goals: Vec<usize>,
    /// The component edges taken: `(component, its edge)`.
    pub moves: Vec<(usize, usize)>,
}

/// A compiled component.
#[derive(Clone, Debug)]
pub struct Component {
    /// As written.
    pub def: ComponentDef,
    /// Index of its first clock in the product.
    pub offset: usize,
    /// Invariant per location (product dimension).
    invariants: Vec<Poly>,
    /// Guard per edge (product dimension).
    guards: Vec<Poly>,
    /// `(from, to)` per edge.
    ends: Vec<(usize, usize)>,
    /// The product clocks each location runs.
    running: Vec<BTreeSet<usize>>,
    /// Reset product clocks per edge.
    resets: Vec<Vec<usize>>,
    initial: usize,
    progress: BTreeSet<usize>,
}

impl Component {
    /// True when location `l` (of this component) is in progress.
    pub fn in_progress(&self, l: usize) -> bool {
        self.progress.contains(&l)
    }

    /// Location `l` as written.
    pub fn location(&self, l: usize) -> &LocationDef {
        &self.def.locations[l]
    }

    /// The guard of edge `e` (product dimension).
    pub fn guard(&self, e: usize) -> &Poly {
        &self.guards[e]
    }

    /// True when the component has an edge on `event`.
    pub fn knows(&self, event: &str) -> bool {
        self.def.edges.iter().any(|e| e.event == event)
    }

    /// True when the component can take `event` from its location `l`.
    pub fn accepts(&self, l: usize, event: &str) -> bool {
        self.def
            .edges
            .iter()
            .zip(&self.ends)
            .any(|(e, &(from, _))| e.event == event && from == l)
    }
}

/// The synchronous product of the components.
#[derive(Clone, Debug)]
pub struct Swa {
    /// Qualified clock names (`conveyor.x`).
    pub clocks: Vec<String>,
    /// The components.
    pub components: Vec<Component>,
    /// Reachable product locations (by the discrete structure), the initial first.
    pub locations: Vec<Location>,
    /// Edges of the product.
    pub edges: Vec<Edge>,
}

/// Largest product the composition builds.
pub const MAX_LOCATIONS: usize = 100_000;

/// Where a file's text comes from, to place a problem at the string it is about.
#[derive(Clone, Copy)]
pub(crate) struct Src<'a> {
    pub(crate) file: &'a Path,
    pub(crate) text: &'a str,
}

fn problem(src: Src<'_>, needle: &str, msg: String) -> Problem {
    let at = if src.text.is_empty() {
        At::new(src.file, 1, 1)
    } else {
        At::of_nth(src.file, src.text, &format!("\"{needle}\""), 0)
    };
    Problem::error(codes::SWA_INVALID.id, msg, Some(at))
}

fn lift(p: &Poly, offset: usize, dim: usize) -> Poly {
    let map: Vec<usize> = (offset..offset + p.dim()).collect();
    p.embed(&map, dim)
}

impl SwaFile {
    /// Reads a `*.swa.ron` file and builds its product.
    pub fn load(path: &Path) -> Result<Swa, Problem> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            Problem::error(
                codes::SWA_INVALID.id,
                format!("cannot read: {e}"),
                Some(At::new(path, 1, 1)),
            )
        })?;
        let file: SwaFile = ron::from_str(&text).map_err(|e| crate::diag::ron_problem(path, &e))?;
        file.compile(path, &text)
    }

    /// Checks every name and constraint and builds the product. `file` and its `text`
    /// (empty for generated automata) place the problems.
    pub fn compile(&self, file: &Path, text: &str) -> Result<Swa, Problem> {
        let file = Src { file, text };
        let mut clocks = Vec::new();
        let mut names = BTreeSet::new();
        for c in &self.components {
            if !names.insert(c.name.clone()) {
                return Err(problem(
                    file,
                    &c.name,
                    format!("two components named `{}`", c.name),
                ));
            }
            let mut seen = BTreeSet::new();
            for k in &c.clocks {
                if !seen.insert(k) {
                    return Err(problem(
                        file,
                        k,
                        format!("component `{}`: clock `{k}` declared twice", c.name),
                    ));
                }
                clocks.push(format!("{}.{k}", c.name));
            }
        }
        let dim = clocks.len();
        let mut components = Vec::new();
        let mut offset = 0;
        for c in &self.components {
            components.push(compile_component(c, offset, dim, file)?);
            offset += c.clocks.len();
        }
        let (locations, edges) = compose(&components, dim, file)?;
        Ok(Swa {
            clocks,
            components,
            locations,
            edges,
        })
    }
}

fn compile_component(
    c: &ComponentDef,
    offset: usize,
    dim: usize,
    file: Src<'_>,
) -> Result<Component, Problem> {
    let local = &c.clocks;
    let loc_index = |n: &str, what: &str| -> Result<usize, Problem> {
        c.locations.iter().position(|l| l.name == n).ok_or_else(|| {
            problem(
                file,
                n,
                format!("component `{}`: {what} `{n}` is not a location", c.name),
            )
        })
    };
    let clock_index = |n: &str| -> Result<usize, Problem> {
        local
            .iter()
            .position(|k| k == n)
            .map(|k| offset + k)
            .ok_or_else(|| {
                problem(
                    file,
                    n,
                    format!("component `{}`: unknown clock `{n}`", c.name),
                )
            })
    };
    let constraint = |text: &str, what: String| -> Result<Poly, Problem> {
        linear::parse(text, local)
            .map(|p| lift(&p, offset, dim))
            .map_err(|e| {
                problem(
                    file,
                    text,
                    format!(
                        "component `{}`, {what}: `{text}`: {} (at character {})",
                        c.name,
                        e.message,
                        e.offset + 1
                    ),
                )
            })
    };
    let mut seen = BTreeSet::new();
    let mut invariants = Vec::new();
    let mut running = Vec::new();
    for l in &c.locations {
        if !seen.insert(&l.name) {
            return Err(problem(
                file,
                &l.name,
                format!("component `{}`: location `{}` twice", c.name, l.name),
            ));
        }
        invariants.push(constraint(
            &l.invariant,
            format!("invariant of `{}`", l.name),
        )?);
        running.push(
            l.running
                .iter()
                .map(|k| clock_index(k))
                .collect::<Result<BTreeSet<_>, _>>()?,
        );
    }
    let mut guards = Vec::new();
    let mut ends = Vec::new();
    let mut resets = Vec::new();
    for (i, e) in c.edges.iter().enumerate() {
        ends.push((
            loc_index(&e.from, "edge source")?,
            loc_index(&e.to, "edge target")?,
        ));
        guards.push(constraint(
            &e.guard,
            format!("guard of edge {} ({})", i + 1, e.event),
        )?);
        resets.push(
            e.reset
                .iter()
                .map(|k| clock_index(k))
                .collect::<Result<Vec<_>, _>>()?,
        );
    }
    let progress = c
        .progress
        .iter()
        .map(|n| loc_index(n, "progress location"))
        .collect::<Result<BTreeSet<_>, _>>()?;
    Ok(Component {
        def: c.clone(),
        offset,
        invariants,
        guards,
        ends,
        running,
        resets,
        initial: loc_index(&c.initial, "initial location")?,
        progress,
    })
}

fn product_location(components: &[Component], parts: &[usize], dim: usize) -> Location {
    let mut rates = vec![Q::zero(); dim];
    // Stopwatches are non-negative (Def. 2.3.1).
    let mut invariant = Poly::universe(dim);
    for k in 0..dim {
        let mut a = vec![Q::zero(); dim];
        a[k] = -Q::one();
        invariant.add(HalfSpace::le(a, Q::zero()));
    }
    let mut name = Vec::new();
    for (c, &l) in components.iter().zip(parts) {
        for &k in &c.running[l] {
            rates[k] = Q::one();
        }
        invariant = invariant.intersect(&c.invariants[l]);
        name.push(format!("{}:{}", c.def.name, c.def.locations[l].name));
    }
    Location {
        name: name.join(" "),
        parts: parts.to_vec(),
        rates,
        invariant,
    }
}

type Composed = (Vec<Location>, Vec<Edge>);

fn compose(components: &[Component], dim: usize, file: Src<'_>) -> Result<Composed, Problem> {
    // Alphabet of each component.
    let alphabets: Vec<BTreeSet<&str>> = components
        .iter()
        .map(|c| c.def.edges.iter().map(|e| e.event.as_str()).collect())
        .collect();
    let events: BTreeSet<&str> = alphabets.iter().flatten().copied().collect();
    let initial: Vec<usize> = components.iter().map(|c| c.initial).collect();
    let mut index: BTreeMap<Vec<usize>, usize> = BTreeMap::new();
    let mut locations = vec![product_location(components, &initial, dim)];
    index.insert(initial, 0);
    let mut edges = Vec::new();
    let mut queue = VecDeque::from([0usize]);
    while let Some(l) = queue.pop_front() {
        let parts = locations[l].parts.clone();
        for ev in &events {
            // Per participating component: the edges it can take on `ev`.
            let mut choices: Vec<(usize, Vec<usize>)> = Vec::new();
            let mut blocked = false;
            for (ci, c) in components.iter().enumerate() {
                if !alphabets[ci].contains(ev) {
                    continue;
                }
                let mine: Vec<usize> = (0..c.def.edges.len())
                    .filter(|&e| c.def.edges[e].event == *ev && c.ends[e].0 == parts[ci])
                    .collect();
                if mine.is_empty() {
                    blocked = true;
                    break;
                }
                choices.push((ci, mine));
            }
            if blocked {
                continue;
            }
            for combo in cartesian(&choices) {
                let mut to = parts.clone();
                let mut guard = Poly::universe(dim);
                let mut resets = BTreeSet::new();
                let mut goals = Vec::new();
                let mut moves = Vec::new();
                for &(ci, e) in &combo {
                    let c = &components[ci];
                    to[ci] = c.ends[e].1;
                    guard = guard.intersect(&c.guards[e]);
                    resets.extend(c.resets[e].iter().copied());
                    if c.def.edges[e].goal {
                        goals.push(ci);
                    }
                    moves.push((ci, e));
                }
                let target = match index.get(&to) {
                    Some(&t) => t,
                    None => {
                        if locations.len() >= MAX_LOCATIONS {
                            return Err(problem(
                                file,
                                "components",
                                format!("the product has more than {MAX_LOCATIONS} locations"),
                            ));
                        }
                        let t = locations.len();
                        locations.push(product_location(components, &to, dim));
                        index.insert(to, t);
                        queue.push_back(t);
                        t
                    }
                };
                edges.push(Edge {
                    from: l,
                    to: target,
                    event: (*ev).to_string(),
                    guard,
                    resets: resets.into_iter().collect(),
                    goals,
                    moves,
                });
            }
        }
    }
    Ok((locations, edges))
}

fn cartesian(choices: &[(usize, Vec<usize>)]) -> Vec<Vec<(usize, usize)>> {
    let mut out: Vec<Vec<(usize, usize)>> = vec![Vec::new()];
    for (ci, edges) in choices {
        let mut next = Vec::new();
        for prefix in &out {
            for &e in edges {
                let mut p = prefix.clone();
                p.push((*ci, e));
                next.push(p);
            }
        }
        out = next;
    }
    out
}

impl Swa {
    /// The index of a product location by its name.
    pub fn location(&self, name: &str) -> Option<usize> {
        self.locations.iter().position(|l| l.name == name)
    }

    /// The components in progress in product location `l`.
    pub fn in_progress(&self, l: usize) -> Vec<usize> {
        self.components
            .iter()
            .enumerate()
            .filter(|(ci, c)| c.in_progress(self.locations[l].parts[*ci]))
            .map(|(ci, _)| ci)
            .collect()
    }

    /// The component owning product clock `k`.
    pub fn owner(&self, k: usize) -> usize {
        self.components
            .iter()
            .rposition(|c| c.offset <= k)
            .unwrap_or_default()
    }

    /// Events of the product.
    pub fn events(&self) -> BTreeSet<&str> {
        self.edges.iter().map(|e| e.event.as_str()).collect()
    }

    /// The valuation with every clock at 0.
    pub fn zero(&self) -> Vec<Q> {
        vec![Q::zero(); self.clocks.len()]
    }

    /// The component whose name is `name`.
    pub fn component(&self, name: &str) -> Option<usize> {
        self.components.iter().position(|c| c.def.name == name)
    }

    /// The point `{all clocks = 0}` as a polyhedron.
    pub fn origin(&self) -> Poly {
        let n = self.clocks.len();
        let mut p = Poly::universe(n);
        for k in 0..n {
            let mut a = vec![Q::zero(); n];
            a[k] = Q::one();
            p.add_eq(a, Q::zero());
        }
        p
    }
}
