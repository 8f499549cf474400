//! Region operators (seed 000, Defs. 2.3.6–2.3.11) and the synthesis of the monitoring
//! region `E*` (Theorem 4.3.1).
//!
//! - Forward: `E(l)`, the valuations reachable in each location from the initial
//!   location with every clock at 0 (the algorithm of §4.3.2 B.2, with an exact
//!   inclusion test against the union already stored).
//! - Backward, per component `c`: `B_c(l)`, the valuations from which `c`'s desired
//!   space (the guard of a goal edge) can still be reached while `c` stays in progress.
//!   This is the backward analysis of the direct automaton with `Pre_t` and `Pre_d`
//!   (equivalently the forward analysis of the reversed automaton, whose initial state
//!   the thesis states too tersely to implement, notes §5.5).
//! - `E*(l) = E(l) ∩ ⋂ B_c(l)` over the components in progress in `l`: a conjunction,
//!   as the thesis's tables are (every task in progress must remain able to finish
//!   acceptably; the text's union is a slip, notes §5.4).
//!
//! Reachability of stopwatch automata is undecidable; every fixed point is bounded by
//! [`Limits::iterations`] and reports [`SynthError::Limit`] rather than looping.

use super::automaton::Swa;
use super::poly::{HalfSpace, Poly, Q};
use std::collections::{BTreeSet, VecDeque};

/// A union of convex polyhedra.
pub type Union = Vec<Poly>;

/// Bounds of a synthesis.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Polyhedra processed by one fixed point.
    pub iterations: usize,
    /// Polyhedra kept per location; beyond, the location's union is replaced by its
    /// template hull (an over-approximation: detection may come later, never falsely;
    /// the thesis's PHAVer bounds its polyhedra the same way, §4.3).
    pub members: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            iterations: 20_000,
            members: 4,
        }
    }
}

/// The template hull of a union: every direction any member bounds, bounded by its
/// supremum over the union. It contains the union (it is an over-approximation).
pub fn template_hull(list: &[Poly], dim: usize) -> Poly {
    let mut dirs: Vec<Vec<Q>> = Vec::new();
    for p in list {
        for h in p.half_spaces() {
            if !dirs.contains(&h.a) {
                dirs.push(h.a);
            }
        }
    }
    let mut out = Poly::universe(dim);
    for d in dirs {
        let mut bound: Option<(Q, bool)> = None;
        let mut unbounded = false;
        for p in list {
            match p.sup(&d) {
                None => {}
                Some(None) => unbounded = true,
                Some(Some((v, attained))) => {
                    let looser = bound
                        .as_ref()
                        .is_none_or(|(b, a)| v > *b || (v == *b && attained && !*a));
                    if looser {
                        bound = Some((v, attained));
                    }
                }
            }
        }
        if let (false, Some((v, attained))) = (unbounded, bound) {
            out.add(HalfSpace {
                a: d,
                b: v,
                strict: !attained,
            });
        }
    }
    out
}

/// Why a synthesis stopped.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SynthError {
    /// A fixed point did not converge.
    #[error("the {analysis} analysis did not converge within {limit} steps")]
    Limit {
        /// `forward` or `backward (component)`.
        analysis: String,
        /// The limit.
        limit: usize,
    },
}

/// `Succ_t(l, E)`: `E` (inside the invariant) let flow with the rates of `l`, within
/// its invariant (convex, so checking the end point suffices).
pub fn succ_t(swa: &Swa, l: usize, e: &Poly) -> Poly {
    let loc = &swa.locations[l];
    let e = e.intersect(&loc.invariant);
    e.elapse(&loc.rates, true).intersect(&loc.invariant)
}

/// `Pre_t(l, E)`: the valuations of `l` from which `E` is reached by letting time flow
/// within the invariant.
pub fn pre_t(swa: &Swa, l: usize, e: &Poly) -> Poly {
    let loc = &swa.locations[l];
    let e = e.intersect(&loc.invariant);
    e.elapse(&loc.rates, false).intersect(&loc.invariant)
}

/// `Succ_d` through edge `a`: `∃R.(E ∧ δ) ∧ R = 0 ∧ I(l')`.
pub fn succ_d(swa: &Swa, a: usize, e: &Poly) -> Poly {
    let edge = &swa.edges[a];
    e.intersect(&edge.guard)
        .reset(&edge.resets)
        .intersect(&swa.locations[edge.to].invariant)
}

/// `Pre_d` through edge `a`: `δ ∧ I(l) ∧ ∃R.(E ∧ R = 0)`.
pub fn pre_d(swa: &Swa, a: usize, e: &Poly) -> Poly {
    let edge = &swa.edges[a];
    let n = swa.clocks.len();
    let mut at_zero = e.clone();
    for &r in &edge.resets {
        let mut c = vec![Q::zero(); n];
        c[r] = Q::one();
        at_zero.add_eq(c, Q::zero());
    }
    at_zero
        .exists_all(&edge.resets)
        .intersect(&edge.guard)
        .intersect(&swa.locations[edge.from].invariant)
}

/// `q \ p` as a union of disjoint convex pieces.
pub fn subtract(q: &Poly, p: &Poly) -> Union {
    if p.trivially_empty() {
        return vec![q.clone()];
    }
    let mut out = Vec::new();
    let mut rest = q.clone();
    for h in p.half_spaces() {
        let mut piece = rest.clone();
        piece.add(h.negation());
        if !piece.is_empty() {
            out.push(piece);
        }
        rest.add(h);
        if rest.is_empty() {
            break;
        }
    }
    out
}

/// True when `q ⊆ ⋃ list` (exact).
pub fn covered(q: &Poly, list: &[Poly]) -> bool {
    if q.is_empty() {
        return true;
    }
    if list.iter().any(|p| q.is_subset(p)) {
        return true;
    }
    let Some((p, rest)) = list.split_first() else {
        return false;
    };
    if rest.is_empty() {
        return false; // q ⊄ p, checked above
    }
    subtract(q, p).iter().all(|piece| covered(piece, rest))
}

/// True when the two unions are the same set.
pub fn same_union(a: &[Poly], b: &[Poly]) -> bool {
    a.iter().all(|p| covered(p, b)) && b.iter().all(|p| covered(p, a))
}

/// The union `p ∪ q` when it is convex, found by its envelope (the bounds of each that
/// the other satisfies; Bemporad et al.): `None` when the union is not convex.
pub fn convex_union(p: &Poly, q: &Poly) -> Option<Poly> {
    let mut env = Poly::universe(p.dim());
    for h in p.half_spaces() {
        if q.is_subset(&single(&h, p.dim())) {
            env.add(h);
        }
    }
    for h in q.half_spaces() {
        if p.is_subset(&single(&h, p.dim())) {
            env.add(h);
        }
    }
    subtract(&env, p)
        .iter()
        .all(|piece| piece.is_subset(q))
        .then_some(env)
}

fn single(h: &HalfSpace, dim: usize) -> Poly {
    let mut p = Poly::universe(dim);
    p.add(h.clone());
    p
}

/// True when one member of `list` contains `q`: the fixed points' test. It is weaker
/// than [`covered`] (a `q` split across members is processed again, once: it is then a
/// member) and avoids the subtraction, exponential in the union's size.
fn in_one(q: &Poly, list: &[Poly]) -> bool {
    q.is_empty() || list.iter().any(|p| q.is_subset(p))
}

/// Adds `p` to `list` unless covered; drops the members `p` covers and merges it with
/// those whose union with it is convex. Returns what was added (the merged polyhedron,
/// which the caller propagates), or `None` when `p` was already covered.
fn absorb(list: &mut Union, p: Poly, max: usize, hulled: &mut bool) -> Option<Poly> {
    if in_one(&p, list) {
        return None;
    }
    list.retain(|q| !q.is_subset(&p));
    let mut p = p;
    let mut i = 0;
    while i < list.len() {
        if let Some(merged) = convex_union(&p, &list[i]) {
            p = merged.minimize();
            list.swap_remove(i);
            i = 0;
        } else {
            i += 1;
        }
    }
    list.push(p.clone());
    if list.len() > max {
        let hull = template_hull(list, p.dim()).minimize();
        list.clear();
        list.push(hull.clone());
        *hulled = true;
        return Some(hull);
    }
    Some(p)
}

/// One step of a fixed point: `p` joins location `l`'s union; what was added (the merged
/// polyhedron, or the hull) waits to be propagated, and a hull marks `l` approximate.
fn grow(
    sets: &mut [Union],
    l: usize,
    p: Poly,
    limits: Limits,
    approx: &mut BTreeSet<usize>,
    waiting: &mut VecDeque<(usize, Poly)>,
) {
    let mut hulled = false;
    if let Some(added) = absorb(&mut sets[l], p, limits.members, &mut hulled) {
        waiting.push_back((l, added));
    }
    if hulled {
        approx.insert(l);
    }
}

/// Sets per location, and the locations whose union was replaced by its hull.
pub type Reached = (Vec<Union>, BTreeSet<usize>);

/// The result of a synthesis.
#[derive(Clone, Debug)]
pub struct Synthesis {
    /// `E(l)`: forward reachable valuations per location.
    pub forward: Vec<Union>,
    /// `B_c(l)` per component (empty unions outside its progress locations).
    pub backward: Vec<Vec<Union>>,
    /// `E*(l)` per location, minimised.
    pub regions: Vec<Union>,
    /// Locations where a set was over-approximated by its hull ([`Limits::members`]):
    /// their `E*` may detect later than the exact one, never falsely.
    pub approximate: BTreeSet<usize>,
}

impl Synthesis {
    /// Per component in progress in `l` and with a goal: `E(l) ∩ B_c(l)`.
    pub fn finishing(&self, swa: &Swa, l: usize) -> Vec<(usize, Union)> {
        swa.in_progress(l)
            .into_iter()
            .filter(|&c| swa.edges.iter().any(|e| e.goals.contains(&c)))
            .map(|c| (c, self.backward[c][l].clone()))
            .collect()
    }

    /// The regions the monitor runs.
    pub fn monitor_regions(&self, swa: &Swa) -> Vec<super::regions::Region> {
        (0..self.regions.len())
            .map(|l| super::regions::Region {
                all: self.regions[l].clone(),
                finish: self.finishing(swa, l),
            })
            .collect()
    }

    /// Locations with an empty `E*`: unreachable under acceptable behaviour.
    pub fn unreachable(&self) -> Vec<usize> {
        (0..self.regions.len())
            .filter(|&l| self.regions[l].is_empty())
            .collect()
    }
}

/// Forward reachability from the initial location with every clock at 0.
pub fn forward(swa: &Swa, limits: Limits) -> Result<Reached, SynthError> {
    let mut approx = BTreeSet::new();
    let mut reach: Vec<Union> = vec![Vec::new(); swa.locations.len()];
    let start = succ_t(swa, 0, &swa.origin());
    let mut waiting = VecDeque::new();
    if !start.is_empty() {
        reach[0].push(start.clone());
        waiting.push_back((0usize, start));
    }
    let out_edges = outgoing(swa);
    let mut steps = 0;
    while let Some((l, e)) = waiting.pop_front() {
        steps += 1;

        if steps > limits.iterations {
            return Err(SynthError::Limit {
                analysis: "forward".into(),
                limit: limits.iterations,
            });
        }
        for &a in &out_edges[l] {
            let next = succ_d(swa, a, &e);
            if next.is_empty() {
                continue;
            }
            let to = swa.edges[a].to;
            if in_one(&next, &reach[to]) {
                continue;
            }
            let grown = succ_t(swa, to, &next).minimize();
            grow(&mut reach, to, grown, limits, &mut approx, &mut waiting);
        }
    }
    Ok((reach, approx))
}

fn outgoing(swa: &Swa) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); swa.locations.len()];
    for (i, e) in swa.edges.iter().enumerate() {
        out[e.from].push(i);
    }
    out
}

/// `B_c`: the valuations of the forward reachable set `fwd` from which component `c`'s
/// desired space is reached while `c` stays in progress. Each backward step is cut to
/// `fwd` (the thesis's `E*_n = E_n ∩ Pre_t(S)`): a path from a reachable state only
/// visits reachable states, and the cut keeps the other components' clocks bounded.
pub fn backward(swa: &Swa, c: usize, fwd: &[Union], limits: Limits) -> Result<Reached, SynthError> {
    let mut approx = BTreeSet::new();
    let n = swa.locations.len();
    let progress: Vec<bool> = (0..n)
        .map(|l| swa.components[c].in_progress(swa.locations[l].parts[c]))
        .collect();
    let mut back: Vec<Union> = vec![Vec::new(); n];
    let mut waiting = VecDeque::new();
    for e in &swa.edges {
        if progress[e.from] && e.goals.contains(&c) {
            let seed = e
                .guard
                .intersect(&swa.locations[e.from].invariant)
                .intersect(&swa.locations[e.to].invariant.exists_all(&e.resets));
            let seed = pre_t(swa, e.from, &seed);
            for piece in cut(&seed, &fwd[e.from]) {
                grow(&mut back, e.from, piece, limits, &mut approx, &mut waiting);
            }
        }
    }
    let mut incoming = vec![Vec::new(); n];
    for (i, e) in swa.edges.iter().enumerate() {
        if progress[e.from] && progress[e.to] && !e.goals.contains(&c) {
            incoming[e.to].push(i);
        }
    }
    let mut steps = 0;
    while let Some((l, s)) = waiting.pop_front() {
        steps += 1;
        if steps > limits.iterations {
            return Err(SynthError::Limit {
                analysis: format!("backward ({})", swa.components[c].def.name),
                limit: limits.iterations,
            });
        }
        for &a in &incoming[l] {
            let from = swa.edges[a].from;
            let prev = pre_d(swa, a, &s);
            if prev.is_empty() || in_one(&prev, &back[from]) {
                continue;
            }
            let grown = pre_t(swa, from, &prev);
            for piece in cut(&grown, &fwd[from]) {
                grow(&mut back, from, piece, limits, &mut approx, &mut waiting);
            }
        }
    }
    Ok((back, approx))
}

/// `p ∩ ⋃ fwd`, minimised pieces.
fn cut(p: &Poly, fwd: &[Poly]) -> Vec<Poly> {
    fwd.iter()
        .map(|f| p.intersect(f))
        .filter(|q| !q.is_empty())
        .map(|q| q.minimize())
        .collect()
}

/// `E*` of every location.
///
/// Components that share no event (directly or through others) form independent groups;
/// each group is synthesised alone and the location's region is the conjunction of its
/// groups' regions. Time still passes for all groups at once in the product, so the
/// product's own forward set can be smaller (a group's invariant can lock time): the
/// decomposition over-approximates it, and every location is then reported in
/// [`Synthesis::approximate`] when there is more than one group.
pub fn synthesize(swa: &Swa, limits: Limits) -> Result<Synthesis, SynthError> {
    let groups = independent_groups(swa);
    if groups.len() > 1 {
        return synthesize_groups(swa, &groups, limits);
    }
    synthesize_product(swa, limits)
}

/// The components grouped by shared events (connected components), in order.
pub fn independent_groups(swa: &Swa) -> Vec<Vec<usize>> {
    let n = swa.components.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while parent[r] != r {
            r = parent[r];
        }
        parent[x] = r;
        r
    }
    for a in 0..n {
        for b in a + 1..n {
            let shared = swa.components[a]
                .def
                .edges
                .iter()
                .any(|e| swa.components[b].knows(&e.event));
            if shared {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut index: Vec<Option<usize>> = vec![None; n];
    for c in 0..n {
        let r = find(&mut parent, c);
        match index[r] {
            Some(g) => groups[g].push(c),
            None => {
                index[r] = Some(groups.len());
                groups.push(vec![c]);
            }
        }
    }
    groups
}

fn synthesize_groups(
    swa: &Swa,
    groups: &[Vec<usize>],
    limits: Limits,
) -> Result<Synthesis, SynthError> {
    let dim = swa.clocks.len();
    let n = swa.locations.len();
    let mut forward_sets: Vec<Union> = vec![vec![Poly::universe(dim)]; n];
    let mut backward_sets: Vec<Vec<Union>> = vec![vec![Vec::new(); n]; swa.components.len()];
    let mut regions: Vec<Union> = vec![vec![Poly::universe(dim)]; n];
    for group in groups {
        let file = super::automaton::SwaFile {
            components: group
                .iter()
                .map(|&c| swa.components[c].def.clone())
                .collect(),
        };
        // The group's components were compiled once already: this cannot fail.
        let Ok(sub) = file.compile(std::path::Path::new("<group>"), "") else {
            continue;
        };
        let map: Vec<usize> = sub
            .clocks
            .iter()
            .map(|k| swa.clocks.iter().position(|x| x == k).unwrap_or_default())
            .collect();
        let s = synthesize_product(&sub, limits)?;
        let index: std::collections::BTreeMap<Vec<usize>, usize> = sub
            .locations
            .iter()
            .enumerate()
            .map(|(i, l)| (l.parts.clone(), i))
            .collect();
        for l in 0..n {
            let parts: Vec<usize> = group.iter().map(|&c| swa.locations[l].parts[c]).collect();
            let Some(&gl) = index.get(&parts) else {
                // Not reachable in the group: not reachable in the product.
                forward_sets[l].clear();
                regions[l].clear();
                continue;
            };
            let lift = |u: &Union| -> Union { u.iter().map(|p| p.embed(&map, dim)).collect() };
            forward_sets[l] = intersect_unions(&forward_sets[l], &lift(&s.forward[gl]));
            regions[l] = intersect_unions(&regions[l], &lift(&s.regions[gl]));
            for (gi, &c) in group.iter().enumerate() {
                backward_sets[c][l] = lift(&s.backward[gi][gl]);
            }
        }
    }
    Ok(Synthesis {
        forward: forward_sets,
        backward: backward_sets,
        regions,
        approximate: (0..n).collect(),
    })
}

fn synthesize_product(swa: &Swa, limits: Limits) -> Result<Synthesis, SynthError> {
    let (fwd, mut approximate) = forward(swa, limits)?;
    let mut backward_sets = Vec::new();
    for c in 0..swa.components.len() {
        let has_goal = swa.edges.iter().any(|e| e.goals.contains(&c));
        backward_sets.push(if has_goal {
            let (b, approx) = backward(swa, c, &fwd, limits)?;
            approximate.extend(approx);
            b
        } else {
            vec![Vec::new(); swa.locations.len()]
        });
    }
    let mut regions = Vec::new();
    for (l, reach) in fwd.iter().enumerate() {
        let mut acc: Union = reach.clone();
        for c in swa.in_progress(l) {
            if !swa.edges.iter().any(|e| e.goals.contains(&c)) {
                continue;
            }
            acc = intersect_unions(&acc, &backward_sets[c][l]);
        }
        let mut minimal: Union = Vec::new();
        for p in acc {
            absorb(&mut minimal, p.minimize(), usize::MAX, &mut false);
        }
        regions.push(minimal);
    }
    Ok(Synthesis {
        forward: fwd,
        backward: backward_sets,
        regions,
        approximate,
    })
}

/// `(⋃ a) ∩ (⋃ b)`.
pub fn intersect_unions(a: &[Poly], b: &[Poly]) -> Union {
    let mut out = Vec::new();
    for p in a {
        for q in b {
            let r = p.intersect(q);
            if !r.is_empty() {
                out.push(r);
            }
        }
    }
    out
}
