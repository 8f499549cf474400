"""Cross-check of Vigie's polyhedra (core/src/swa/poly.rs) against the Parma
Polyhedra Library (pplpy, NNC polyhedra: strict inequalities included).

Reads JSON cases on stdin: {"dim", "input": [[coefs, b, strict], ...], "op", ...,
"result": [[coefs, b, strict], ...] or null for empty}; coefficients and bounds are
[numerator, denominator] pairs. Applies the operation with PPL and checks that PPL's
polyhedron equals Vigie's. Prints one line per case; exits 1 on any mismatch.
"""
import json
import sys
from fractions import Fraction
from math import lcm

import ppl


def frac(p):
    return Fraction(p[0], p[1])


def poly(dim, rows):
    p = ppl.NNC_Polyhedron(dim, "universe")
    for coefs, b, strict in rows:
        cs = [frac(c) for c in coefs]
        bb = frac(b)
        m = lcm(*[x.denominator for x in cs + [bb]])
        e = ppl.Linear_Expression(0)
        for k, c in enumerate(cs):
            e += int(c * m) * ppl.Variable(k)
        rhs = int(bb * m)
        p.add_constraint(e < rhs if strict else e <= rhs)
    return p


def main():
    cases = json.load(sys.stdin)
    bad = 0
    for i, case in enumerate(cases):
        dim = case["dim"]
        p = poly(dim, case["input"])
        op = case["op"]
        if op == "elapse":
            # P + cone(r): the ray joins P's generators (the time elapse).
            e = ppl.Linear_Expression(0)
            for k, r in enumerate(case["rates"]):
                e += int(r) * ppl.Variable(k)
            if any(case["rates"]) and not p.is_empty():
                p.add_generator(ppl.ray(e))
        elif op == "exists":
            p.unconstrain(ppl.Variable(case["var"]))
        elif op == "intersect":
            p.intersection_assign(poly(dim, case["other"]))
        elif op == "minimize":
            pass
        else:
            raise SystemExit(f"unknown op {op}")
        if case["result"] is None:
            ok = p.is_empty()
        else:
            q = poly(dim, case["result"])
            ok = p.contains(q) and q.contains(p)
        if not ok:
            bad += 1
            print(f"case {i} ({op}): MISMATCH: ppl {p.constraints()} vigie {case['result']}")
    print(f"{len(cases)} cases, {bad} mismatches")
    sys.exit(1 if bad else 0)


main()
