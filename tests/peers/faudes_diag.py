"""libFAUDES side of the diagnoser cross-check and benchmark.

    faudes_diag.py check GEN FTM SEQS.json   -> JSON: for each sequence, the failure
        labels of the libFAUDES event diagnoser's state after each event
    faudes_diag.py bench GEN FTM NAME [K..]  -> construction time of the centralized
        diagnoser (EventDiagnoser on the parallel composition of K copies of component
        NAME, each copy's events renamed), for each K (default 3 4 5)
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


def label_table(diag):
    """State token -> sorted failure labels of its estimate ("N" for normal), parsed
    from the diagnoser's token text:
    <States> 1 <StateEstimates> 1 <DiagLabels> N </DiagLabels> ... </StateEstimates> ..."""
    toks = diag.ToString().replace("<", " <").replace(">", "> ").split()
    i = toks.index("<States>") + 1
    table = {}
    cur = None
    inside = False
    while toks[i] != "</States>":
        t = toks[i]
        if t == "<DiagLabels>":
            inside = True
        elif t == "</DiagLabels>":
            inside = False
        elif inside:
            table[cur].add(t.strip('"'))
        elif toks[i + 1] == "<StateEstimates>":
            cur = t.strip('"')
            table[cur] = set()
        i += 1
    return {k: sorted(v) for k, v in table.items()}


def labels(diag, table, state):
    name = diag.StateName(state) or str(state)
    return table.get(name, [])


def check(gen, ftm, seqs_path):
    g, fm = load(gen, ftm)
    d = faudes.Diagnoser()
    faudes.EventDiagnoser(g, fm, d)
    if d.Size() == 0:
        # libFAUDES built no diagnoser (seen on the one-sensor conveyor models).
        json.dump({"empty": True}, sys.stdout)
        return
    table = label_table(d)
    seqs = json.load(open(seqs_path))
    result = []
    for seq in seqs:
        s = d.InitState()
        row = []
        for e in seq:
            if not d.ExistsEvent(e):
                row.append(None)
                break
            nxt = list(d.SuccessorStates(s, d.EventIndex(e)))
            if len(nxt) == 0:
                row.append(None)
                break
            s = nxt[0]
            row.append(labels(d, table, s))
        result.append(row)
    json.dump(result, sys.stdout)


def bench(gen, ftm, what, ks):
    g, fm = load(gen, ftm)
    for k in ks:
        copies = []
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
        print(f"libFAUDES parallel composition, {k} x {what}: "
              f"{(time.perf_counter() - start)*1e3:.1f} ms (plant {prod.Size()} states, "
              f"{prod.TransRelSize()} transitions)", flush=True)
        ft = faudes.FailureTypeMap()
        # One failure type per fault label and copy.
        for name in [prod.EventName(e) if not isinstance(e, str) else e for e in list(prod.Alphabet())]:
            if name.startswith("f_"):
                es = faudes.EventSet()
                es.Insert(name)
                ft.AddFailureTypeMapping(name[2:], es)
        d = faudes.Diagnoser()
        faudes.EventDiagnoser(prod, ft, d)
        el = time.perf_counter() - start
        print(f"libFAUDES centralized EventDiagnoser, {k} x {what}: {el*1e3:.1f} ms "
              f"(plant {prod.Size()} states, diagnoser {d.Size()} states)", flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "check":
        check(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        bench(sys.argv[2], sys.argv[3], sys.argv[4], [int(k) for k in sys.argv[5:]] or [3, 4, 5])
