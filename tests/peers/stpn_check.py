"""Cross-check of Vigie's stochastic Petri net analyses (core/src/stpn) with an
independent exact Markov-chain computation in sympy (rationals over QQ).

Reads on stdin the JSON of `vigie stpn NET --json`: the state graph (states, arcs
<from, to, transition, theta, p>, the initial distribution), the steady state's time
shares Vigie found, the queries asked and Vigie's answers. Recomputes, with its own code
and sympy's exact linear algebra:
  - the embedded chain's stationary vector on the terminal component and the time
    shares pi_i = eta_i gamma_i / sum eta_k gamma_k;
  - every `Passage` query: the graph split on its events, the source events weighted by
    the stationary vector, the first-passage probability and mean time to the target
    events (the MTFF of the thesis);
  - every `Reach` query: the probability of reaching its markings and the mean time to
    the first one.
Prints one line per check; exits 1 on any mismatch.
"""
import json
import sys

from sympy import Rational
from sympy.polys.domains import QQ
from sympy.polys.matrices import DomainMatrix


def q(text):
    return QQ.convert(Rational(text))


def solve(rows, rhs):
    """Solves A x = b, A given as a list of {column: value} rows."""
    n = len(rhs)
    a = DomainMatrix({i: {c: v for c, v in row.items() if v != 0} for i, row in enumerate(rows)},
                     (n, n), QQ)
    b = DomainMatrix({i: {0: v} for i, v in enumerate(rhs) if v != 0}, (n, 1), QQ)
    x = a.lu_solve(b)
    x = x.to_dense()
    return [x[i, 0].element for i in range(n)]


def terminal_components(n, succ):
    """Tarjan, iterative; the components no arc leaves."""
    index, low, on, stack, comps = {}, {}, set(), [], []
    counter = [0]
    for root in range(n):
        if root in index:
            continue
        work = [(root, iter(succ[root]))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            nxt = next(it, None)
            if nxt is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    comps.append(sorted(comp))
            elif nxt not in index:
                index[nxt] = low[nxt] = counter[0]
                counter[0] += 1
                stack.append(nxt)
                on.add(nxt)
                work.append((nxt, iter(succ[nxt])))
            elif nxt in on:
                low[v] = min(low[v], index[nxt])
    return [c for c in comps if all(t in c for s in c for t in succ[s])]


class Chain:
    def __init__(self, n, arcs, initial):
        self.n, self.arcs, self.initial = n, arcs, initial
        self.out = [[] for _ in range(n)]
        for a in arcs:
            self.out[a["from"]].append(a)

    def stationary(self, comp):
        pos = {s: i for i, s in enumerate(comp)}
        m = len(comp)
        rows = [dict() for _ in range(m)]
        for a in self.arcs:
            if a["from"] in pos and a["to"] in pos:
                j, i = pos[a["to"]], pos[a["from"]]
                rows[j][i] = rows[j].get(i, QQ(0)) + a["p"]
        for i in range(m):
            rows[i][i] = rows[i].get(i, QQ(0)) - QQ(1)
        rows[m - 1] = {i: QQ(1) for i in range(m)}
        rhs = [QQ(0)] * m
        rhs[m - 1] = QQ(1)
        return dict(zip(comp, solve(rows, rhs)))

    def weights(self):
        succ = [[a["to"] for a in self.out[s]] for s in range(self.n)]
        cyclic = [c for c in terminal_components(self.n, succ) if self.out[c[0]]]
        assert len(cyclic) == 1, "one cyclic terminal component"
        g = self.stationary(cyclic[0])
        return [g.get(s, QQ(0)) for s in range(self.n)]

    def passage(self, reached):
        """h (probability) and g (time-weighted) of the first passage to `reached`."""
        n = self.n
        into = [[] for _ in range(n)]
        for a in self.arcs:
            into[a["to"]].append(a["from"])
        can = [reached(s) for s in range(n)]
        todo = [s for s in range(n) if can[s]]
        while todo:
            v = todo.pop()
            for u in into[v]:
                if not can[u]:
                    can[u] = True
                    todo.append(u)
        free = [s for s in range(n) if can[s] and not reached(s)]
        pos = {s: i for i, s in enumerate(free)}
        rows = [{i: QQ(1)} for i in range(len(free))]
        bh = [QQ(0)] * len(free)
        for s in free:
            for a in self.out[s]:
                if reached(a["to"]):
                    bh[pos[s]] += a["p"]
                elif a["to"] in pos:
                    r = rows[pos[s]]
                    r[pos[a["to"]]] = r.get(pos[a["to"]], QQ(0)) - a["p"]
        hv = solve(rows, bh) if free else []
        h = [QQ(1) if reached(s) else (hv[pos[s]] if s in pos else QQ(0)) for s in range(n)]
        bg = [QQ(0)] * len(free)
        for s in free:
            for a in self.out[s]:
                bg[pos[s]] += a["p"] * a["theta"] * h[a["to"]]
        gv = solve(rows, bg) if free else []
        g = [gv[pos[s]] if s in pos else QQ(0) for s in range(n)]
        return h, g


def split(n, arcs, events):
    """A node per (event, state) reached by one of `events`; returns the new arcs and
    the event of each node."""
    node, event, origin = {}, [None] * n, list(range(n))
    for a in arcs:
        if a["transition"] in events and (a["transition"], a["to"]) not in node:
            node[(a["transition"], a["to"])] = len(origin)
            origin.append(a["to"])
            event.append(a["transition"])
    out = [[] for _ in range(n)]
    for a in arcs:
        out[a["from"]].append(a)
    new = []
    for k, s in enumerate(origin):
        for a in out[s]:
            to = node[(a["transition"], a["to"])] if a["transition"] in events else a["to"]
            new.append({"from": k, "to": to, "transition": a["transition"],
                        "theta": a["theta"], "p": a["p"]})
    return len(origin), new, event


def main():
    data = json.load(sys.stdin)
    names = data["transitions"]
    tick = QQ(data["ticks_per_unit"])
    graph = data["graph"]
    n = len(graph["states"])
    arcs = [dict(a, p=q(a["p"]), theta=QQ(a["theta"])) for a in graph["arcs"]]
    initial = [(s, q(p)) for s, p in graph["initial"]]
    chain = Chain(n, arcs, initial)
    bad = checks = 0

    def check(what, mine, theirs):
        nonlocal bad, checks
        checks += 1
        ok = mine == theirs
        bad += not ok
        print(f"{'ok' if ok else 'MISMATCH'}: {what}: sympy {mine}, vigie {theirs}")

    if data["steady"] is not None:
        w = chain.weights()
        eta = [sum((a["p"] * a["theta"] for a in chain.out[s]), QQ(0)) for s in range(n)]
        total = sum((eta[s] * w[s] for s in range(n)), QQ(0))
        vigie = {s: q(p) for s, p in data["steady"]}
        for s in range(n):
            if w[s] != 0 or s in vigie:
                check(f"time share of state {s}", eta[s] * w[s] / total, vigie.get(s, QQ(0)))
        check("stationary vector sums to 1", sum(w, QQ(0)), QQ(1))

    answers = {}
    for o in data["queries"]:
        kind, body = next(iter(o.items()))
        answers[body["name"]] = (kind, body)
    for asked in data["asked"]:
        kind, body = next(iter(asked.items()))
        name = body["name"]
        _, theirs = answers[name]
        if kind == "Passage":
            frm = {names.index(e) for e in body["from"] if e in names}
            to = {names.index(e) for e in body["to"] if e in names}
            m, sarcs, event = split(n, arcs, frm | to)
            sc = Chain(m, sarcs, initial)
            h, g = sc.passage(lambda s: event[s] in to)
            if frm:
                w = sc.weights()
                src = [s for s in range(m) if event[s] in frm]
                tot = sum((w[s] for s in src), QQ(0))
                f = sum((w[s] * a["p"] * h[a["to"]] for s in src for a in sc.out[s]), QQ(0))
                gg = sum((w[s] * a["p"] * (a["theta"] * h[a["to"]] + g[a["to"]])
                          for s in src for a in sc.out[s]), QQ(0))
            else:
                tot = sum((p for _, p in initial), QQ(0))
                f = sum((p * h[s] for s, p in initial), QQ(0))
                gg = sum((p * g[s] for s, p in initial), QQ(0))
            check(f"{name}: probability", f / tot, q(theirs["p"]))
            mean = gg / f / tick if f != 0 else None
            check(f"{name}: mean time", mean,
                  q(theirs["mean"]) if theirs["mean"] is not None else None)
        elif kind == "Reach":
            places = data["places"]
            marked = [places.index(x) for x in body["marked"]]
            empty = [places.index(x) for x in body["empty"]]
            states = graph["states"]

            def inside(s):
                m = states[s]["marking"]
                return all(m[k] > 0 for k in marked) and all(m[k] == 0 for k in empty)

            h, g = chain.passage(inside)
            f = sum((p * h[s] for s, p in initial), QQ(0))
            check(f"{name}: probability", f, q(theirs["p"]))
            first = sum((p * g[s] for s, p in initial), QQ(0)) / f / tick if f != 0 else None
            check(f"{name}: first time", first,
                  q(theirs["first"]) if theirs["first"] is not None else None)
    print(f"{checks} checks, {bad} mismatches")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
