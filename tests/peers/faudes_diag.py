"""libFAUDES side of the diagnoser cross-check and benchmark.

    faudes_diag.py check GEN FTM SEQS.json   -> JSON: for each sequence, the failure
        labels of the libFAUDES event diagnoser's state after each event
    faudes_diag.py bench GEN FTM             -> construction time of the centralized
        diagnoser (EventDiagnoser on the parallel composition) for 3, 4, 5 copies
"""
import json
import sys
import time

import faudes


def load(gen, ftm):
    g = faudes.System()
    g.Read(gen)
    fm = faudes.FailureTypeMap()
    fm.Read(ftm)
    return g, fm


def labels(diag, state):
    # Diagnoser state text: "<StateEstimates> q <DiagLabels> L.. </DiagLabels> ... </StateEstimates>"
    text = diag.StateAttribute(state).ToString()
    out = set()
    toks = text.replace("<", " <").replace(">", "> ").split()
    inside = False
    for t in toks:
        if t == "<DiagLabels>":
            inside = True
        elif t == "</DiagLabels>":
            inside = False
        elif inside:
            out.add(t.strip('"'))
    return sorted(out)


def check(gen, ftm, seqs_path):
    g, fm = load(gen, ftm)
    d = faudes.Diagnoser()
    faudes.EventDiagnoser(g, fm, d)
    seqs = json.load(open(seqs_path))
    result = []
    for seq in seqs:
        s = d.InitState()
        row = []
        for e in seq:
            nxt = d.SuccessorStates(s, e)
            if nxt.Size() == 0:
                row.append(None)
                break
            s = list(nxt)[0] if hasattr(nxt, "__iter__") else nxt.Begin()
            row.append(labels(d, s))
        result.append(row)
    json.dump(result, sys.stdout)


def bench(gen, ftm):
    g, fm = load(gen, ftm)
    for k in (3, 4, 5):
        copies = []
        fmk = faudes.FailureTypeMap()
        for i in range(k):
            c = faudes.System(g)
            for ev in list(g.Alphabet()):
                name = g.EventName(ev) if not isinstance(ev, str) else ev
                c.EventRename(name, f"{name}_{i}")
            copies.append(c)
        start = time.perf_counter()
        prod = copies[0]
        for c in copies[1:]:
            p = faudes.System()
            faudes.Parallel(prod, c, p)
            prod = p
        for i in range(k):
            for f in fm.ToString().split("<FailureEvents>")[1:]:
                pass
        ft = faudes.FailureTypeMap()
        for i in range(k):
            for ev in list(prod.UnobservableEvents()) if hasattr(prod, "UnobservableEvents") else []:
                pass
        # One failure type per fault label and copy.
        for name in [prod.EventName(e) if not isinstance(e, str) else e for e in list(prod.Alphabet())]:
            if name.startswith("f_"):
                es = faudes.EventSet()
                es.Insert(name)
                ft.AddFailureTypeMapping(name[2:], es)
        d = faudes.Diagnoser()
        faudes.EventDiagnoser(prod, ft, d)
        el = time.perf_counter() - start
        print(f"libFAUDES centralized EventDiagnoser, {k} turntables: {el*1e3:.1f} ms "
              f"(plant {prod.Size()} states, diagnoser {d.Size()} states)")


if __name__ == "__main__":
    if sys.argv[1] == "check":
        check(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        bench(sys.argv[2], sys.argv[3])
