#!/usr/bin/env python3
"""Generates layouts/production-line/{plant,components,io-map}.ron and the signal /
element / part / item / off keys of i18n/fr.ftl from one table, so that the 65+ signals
stay consistent across the files. The program, constraints, errors, tasks, scenarios
and the rest of fr.ftl are written by hand in the folder (this script leaves them).

Run: python3 scripts/gen-production-line.py   (from the repository root)
"""
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "layouts" / "production-line"

# ---------------------------------------------------------------------------------------
# Signals: (id, element, English description, French description) for sensors;
# actuators add (off text EN, off text FR).
S = []  # sensors
A = []  # actuators


def sensor(sid, element, en, fr):
    S.append((sid, element, en, fr))


def actuator(sid, element, en, fr, off_en, off_fr):
    A.append((sid, element, en, fr, off_en, off_fr))


# Panel
sensor("LINE_START", "Panel", "Line start push button (one press: the line runs)", "Bouton de marche de la ligne (un appui : la ligne produit)")
sensor("LINE_STOP", "Panel", "Line stop push button (end of production: the workpieces under way are finished)", "Bouton d'arrêt de la ligne (fin de production : les pièces en cours sont terminées)")

# Distributing station
sensor("DS_EJ_RET", "Distributing", "Magazine ejector retracted", "Éjecteur du magasin rentré")
sensor("DS_EJ_EXT", "Distributing", "Magazine ejector extended: the bottom workpiece pushed out onto the transfer belt", "Éjecteur du magasin sorti : la pièce du bas poussée sur le convoyeur de transfert")
sensor("DS_EJ_MOV", "Distributing", "Magazine ejector moving (motion sensor)", "Éjecteur du magasin en mouvement (détecteur de mouvement)")
sensor("DS_IN", "Distributing", "Workpiece at the transfer belt's entry (under the magazine)", "Pièce à l'entrée du convoyeur de transfert (sous le magasin)")
sensor("DS_OUT", "Distributing", "Workpiece at the transfer belt's end (before the testing belt)", "Pièce en bout du convoyeur de transfert (avant le convoyeur de test)")
sensor("DS_MOV", "Distributing", "Transfer belt moving (motion sensor)", "Convoyeur de transfert en mouvement (détecteur de mouvement)")
actuator("DS_EJ_FWD", "Distributing", "Magazine ejector: extend (push the bottom workpiece out)", "Éjecteur du magasin : sortir (pousser la pièce du bas)", "the ejector stops where it is", "l'éjecteur s'arrête où il est")
actuator("DS_EJ_BWD", "Distributing", "Magazine ejector: retract", "Éjecteur du magasin : rentrer", "the ejector stops where it is", "l'éjecteur s'arrête où il est")
actuator("DS_CONV", "Distributing", "Transfer belt motor", "Moteur du convoyeur de transfert", "the transfer belt stops; the workpiece stays where it is", "le convoyeur de transfert s'arrête ; la pièce reste où elle est")

# Testing station
sensor("TS_IN", "Testing", "Workpiece at the testing belt's entry", "Pièce à l'entrée du convoyeur de test")
sensor("TS_PRE", "Testing", "Workpiece approaching the test place (slow-down beam)", "Pièce à l'approche du poste de test (cellule de ralentissement)")
sensor("TS_POS", "Testing", "Workpiece at the test place, under the sensors", "Pièce au poste de test, sous les capteurs")
sensor("TS_TALL", "Testing", "Height sensor: a tall workpiece at the test place", "Capteur de hauteur : pièce haute au poste de test")
sensor("TS_METAL", "Testing", "Inductive sensor: a metal workpiece at the test place", "Capteur inductif : pièce métallique au poste de test")
sensor("TS_BRIGHT", "Testing", "Optical sensor: a bright (red or metal) workpiece at the test place", "Capteur optique : pièce claire (rouge ou métal) au poste de test")
sensor("TS_END", "Testing", "Workpiece at the testing belt's end, ready for the gantry", "Pièce en bout du convoyeur de test, prête pour le portique")
sensor("TS_MOV", "Testing", "Testing belt moving (motion sensor)", "Convoyeur de test en mouvement (détecteur de mouvement)")
sensor("TS_CL_OPEN", "Testing", "Test clamp open", "Bride de test ouverte")
sensor("TS_CL_CLOSED", "Testing", "Test clamp closed on the workpiece", "Bride de test fermée sur la pièce")
sensor("TS_CL_MOV", "Testing", "Test clamp moving (motion sensor)", "Bride de test en mouvement (détecteur de mouvement)")
actuator("TS_FAST", "Testing", "Testing belt, fast", "Convoyeur de test, grande vitesse", "the testing belt stops", "le convoyeur de test s'arrête")
actuator("TS_SLOW", "Testing", "Testing belt, slow (approach to the test place)", "Convoyeur de test, petite vitesse (approche du poste de test)", "the testing belt stops", "le convoyeur de test s'arrête")
actuator("TS_CL_FWD", "Testing", "Test clamp: close", "Bride de test : fermer", "the clamp stops where it is", "la bride s'arrête où elle est")
actuator("TS_CL_BWD", "Testing", "Test clamp: open", "Bride de test : ouvrir", "the clamp stops where it is", "la bride s'arrête où elle est")

# Handling station
sensor("HS_X_PICK", "Handling", "Gantry X over the testing belt's end (pick place)", "Portique X au-dessus du bout du convoyeur de test (prise)")
sensor("HS_X_MID", "Handling", "Gantry X half way", "Portique X à mi-course")
sensor("HS_X_PLACE", "Handling", "Gantry X over the processing belt's entry (place)", "Portique X au-dessus de l'entrée du convoyeur d'usinage (dépose)")
sensor("HS_X_MOV", "Handling", "Gantry X moving (motion sensor)", "Portique X en mouvement (détecteur de mouvement)")
sensor("HS_Z_TOP", "Handling", "Gantry Z up (clear of the belts)", "Portique Z en haut (dégagé des convoyeurs)")
sensor("HS_Z_LOW", "Handling", "Gantry Z down at the belt", "Portique Z en bas, au niveau du convoyeur")
sensor("HS_Z_MOV", "Handling", "Gantry Z moving (motion sensor)", "Portique Z en mouvement (détecteur de mouvement)")
sensor("HS_GR_OPENED", "Handling", "Gripper open", "Pince ouverte")
sensor("HS_GR_CLOSED", "Handling", "Gripper closed", "Pince fermée")
actuator("HS_X_R", "Handling", "Gantry X towards the processing station", "Portique X vers le poste d'usinage", "the gantry stops where it is", "le portique s'arrête où il est")
actuator("HS_X_L", "Handling", "Gantry X towards the testing station", "Portique X vers le poste de test", "the gantry stops where it is", "le portique s'arrête où il est")
actuator("HS_Z_DN", "Handling", "Gantry Z down", "Portique Z : descendre", "the Z axis stops where it is", "l'axe Z s'arrête où il est")
actuator("HS_Z_UP", "Handling", "Gantry Z up", "Portique Z : monter", "the Z axis stops where it is", "l'axe Z s'arrête où il est")
actuator("HS_GR_CLOSE", "Handling", "Gripper: close", "Pince : fermer", "the gripper stays as it is", "la pince reste comme elle est")
actuator("HS_GR_OPEN", "Handling", "Gripper: open", "Pince : ouvrir", "the gripper stays as it is", "la pince reste comme elle est")

# Processing station
sensor("PS_IN", "Processing", "Workpiece at the processing belt's entry (placed by the gantry)", "Pièce à l'entrée du convoyeur d'usinage (déposée par le portique)")
sensor("PS_DRILL_POS", "Processing", "Workpiece at the drilling place", "Pièce au poste de perçage")
sensor("PS_TEST_POS", "Processing", "Workpiece at the hole-testing place", "Pièce au poste de contrôle du perçage")
sensor("PS_END", "Processing", "Workpiece at the processing belt's end (before the sorting belt)", "Pièce en bout du convoyeur d'usinage (avant le tri)")
sensor("PS_MOV", "Processing", "Processing belt moving (motion sensor)", "Convoyeur d'usinage en mouvement (détecteur de mouvement)")
sensor("PS_CL_OPEN", "Processing", "Drilling clamp open", "Bride de perçage ouverte")
sensor("PS_CL_CLOSED", "Processing", "Drilling clamp closed on the workpiece", "Bride de perçage fermée sur la pièce")
sensor("PS_CL_MOV", "Processing", "Drilling clamp moving (motion sensor)", "Bride de perçage en mouvement (détecteur de mouvement)")
sensor("PS_DR_TOP", "Processing", "Drill up (rest)", "Perceuse en haut (repos)")
sensor("PS_DR_APPROACH", "Processing", "Drill just above the workpiece: end of the fast approach", "Perceuse juste au-dessus de la pièce : fin de l'approche rapide")
sensor("PS_DR_LOW", "Processing", "Drill at full depth", "Perceuse à pleine profondeur")
sensor("PS_DR_MOV", "Processing", "Drill slide moving (motion sensor)", "Coulisse de la perceuse en mouvement (détecteur de mouvement)")
sensor("PS_TE_TOP", "Processing", "Hole tester up", "Palpeur de perçage en haut")
sensor("PS_TE_LOW", "Processing", "Hole tester down in the hole", "Palpeur de perçage en bas, dans le trou")
sensor("PS_TE_MOV", "Processing", "Hole tester moving (motion sensor)", "Palpeur de perçage en mouvement (détecteur de mouvement)")
sensor("PS_SP_STOP", "Processing", "Spindle stopped (speed monitor: below 100 rpm)", "Broche arrêtée (contrôleur de vitesse : moins de 100 tr/min)")
sensor("PS_SP_RUN", "Processing", "Spindle at speed (speed monitor: 2900 rpm or more)", "Broche à vitesse (contrôleur de vitesse : 2900 tr/min ou plus)")
actuator("PS_CONV", "Processing", "Processing belt motor", "Moteur du convoyeur d'usinage", "the processing belt stops", "le convoyeur d'usinage s'arrête")
actuator("PS_CL_FWD", "Processing", "Drilling clamp: close", "Bride de perçage : fermer", "the clamp stops where it is", "la bride s'arrête où elle est")
actuator("PS_CL_BWD", "Processing", "Drilling clamp: open", "Bride de perçage : ouvrir", "the clamp stops where it is", "la bride s'arrête où elle est")
actuator("PS_DR_FAST", "Processing", "Drill slide: fast approach down", "Coulisse de perceuse : approche rapide en descente", "the drill stops where it is", "la perceuse s'arrête où elle est")
actuator("PS_DR_FEED", "Processing", "Drill slide: drilling feed down", "Coulisse de perceuse : avance de perçage", "the drill stops where it is", "la perceuse s'arrête où elle est")
actuator("PS_DR_UP", "Processing", "Drill slide: up", "Coulisse de perceuse : monter", "the drill stops where it is", "la perceuse s'arrête où elle est")
actuator("PS_SPINDLE", "Processing", "Drill spindle motor", "Moteur de broche", "the spindle runs down and stops", "la broche ralentit et s'arrête")
actuator("PS_TE_DN", "Processing", "Hole tester: down", "Palpeur : descendre", "the tester stops where it is", "le palpeur s'arrête où il est")
actuator("PS_TE_UP", "Processing", "Hole tester: up", "Palpeur : monter", "the tester stops where it is", "le palpeur s'arrête où il est")

# Sorting station
sensor("SS_IN1", "Sorting", "Workpiece at the sorting belt 1's entry", "Pièce à l'entrée du convoyeur de tri 1")
sensor("SS_METAL", "Sorting", "Inductive sensor at pusher 1: a metal workpiece", "Capteur inductif au poussoir 1 : pièce métallique")
sensor("SS_RED1", "Sorting", "Colour sensor at pusher 1: a red workpiece", "Capteur de couleur au poussoir 1 : pièce rouge")
sensor("SS_TALL", "Sorting", "Height sensor at pusher 1: a tall workpiece", "Capteur de hauteur au poussoir 1 : pièce haute")
sensor("SS_AT1", "Sorting", "Workpiece in front of pusher 1 (belt 1's end)", "Pièce devant le poussoir 1 (bout du convoyeur 1)")
sensor("SS_MOV1", "Sorting", "Sorting belt 1 moving (motion sensor)", "Convoyeur de tri 1 en mouvement (détecteur de mouvement)")
sensor("SS_P1_RET", "Sorting", "Pusher 1 retracted", "Poussoir 1 rentré")
sensor("SS_P1_EXT", "Sorting", "Pusher 1 extended: the workpiece pushed into the metal slide", "Poussoir 1 sorti : la pièce poussée dans la goulotte métal")
sensor("SS_P1_MOV", "Sorting", "Pusher 1 moving (motion sensor)", "Poussoir 1 en mouvement (détecteur de mouvement)")
sensor("SS_IN2", "Sorting", "Workpiece at the sorting belt 2's entry", "Pièce à l'entrée du convoyeur de tri 2")
sensor("SS_RED2", "Sorting", "Colour sensor at pusher 2: a red workpiece", "Capteur de couleur au poussoir 2 : pièce rouge")
sensor("SS_METAL2", "Sorting", "Inductive sensor at pusher 2: a metal workpiece (one that pusher 1 missed)", "Capteur inductif au poussoir 2 : pièce métallique (manquée par le poussoir 1)")
sensor("SS_AT2", "Sorting", "Workpiece in front of pusher 2 (belt 2's end)", "Pièce devant le poussoir 2 (bout du convoyeur 2)")
sensor("SS_MOV2", "Sorting", "Sorting belt 2 moving (motion sensor)", "Convoyeur de tri 2 en mouvement (détecteur de mouvement)")
sensor("SS_P2_RET", "Sorting", "Pusher 2 retracted", "Poussoir 2 rentré")
sensor("SS_P2_EXT", "Sorting", "Pusher 2 extended: the workpiece pushed into the red slide", "Poussoir 2 sorti : la pièce poussée dans la goulotte rouge")
sensor("SS_P2_MOV", "Sorting", "Pusher 2 moving (motion sensor)", "Poussoir 2 en mouvement (détecteur de mouvement)")
sensor("SS_OUT_IN", "Sorting", "Workpiece at the black outfeed's entry", "Pièce à l'entrée de la sortie noire")
sensor("SS_OUT_RED", "Sorting", "Colour sensor on the black outfeed: a red workpiece (missorted)", "Capteur de couleur sur la sortie noire : pièce rouge (mal triée)")
sensor("SS_OUT_END", "Sorting", "Workpiece at the black outfeed's end, falling into the bin", "Pièce en bout de la sortie noire, tombant dans le bac")
sensor("SS_OUT_MOV", "Sorting", "Black outfeed moving (motion sensor)", "Sortie noire en mouvement (détecteur de mouvement)")
actuator("SS_CONV1", "Sorting", "Sorting belt 1 motor", "Moteur du convoyeur de tri 1", "sorting belt 1 stops", "le convoyeur de tri 1 s'arrête")
actuator("SS_P1_FWD", "Sorting", "Pusher 1: extend", "Poussoir 1 : sortir", "pusher 1 stops where it is", "le poussoir 1 s'arrête où il est")
actuator("SS_P1_BWD", "Sorting", "Pusher 1: retract", "Poussoir 1 : rentrer", "pusher 1 stops where it is", "le poussoir 1 s'arrête où il est")
actuator("SS_CONV2", "Sorting", "Sorting belt 2 motor", "Moteur du convoyeur de tri 2", "sorting belt 2 stops", "le convoyeur de tri 2 s'arrête")
actuator("SS_P2_FWD", "Sorting", "Pusher 2: extend", "Poussoir 2 : sortir", "pusher 2 stops where it is", "le poussoir 2 s'arrête où il est")
actuator("SS_P2_BWD", "Sorting", "Pusher 2: retract", "Poussoir 2 : rentrer", "pusher 2 stops where it is", "le poussoir 2 s'arrête où il est")
actuator("SS_CONV_OUT", "Sorting", "Black outfeed motor", "Moteur de la sortie noire", "the outfeed stops", "la sortie noire s'arrête")

ELEMENTS_FR = {
    "Panel": "Pupitre",
    "Distributing": "Poste de distribution",
    "Testing": "Poste de test",
    "Handling": "Poste de manipulation",
    "Processing": "Poste d'usinage",
    "Sorting": "Poste de tri",
}

# The classes, in the order the magazine holds them.
CLASSES = [
    ("metal", ["metal", "bright", "tall"], "pièce métallique"),
    ("red", ["red", "bright", "tall"], "pièce rouge"),
    ("black", ["tall"], "pièce noire"),
    ("red", ["red", "bright", "tall"], None),
    ("black_low", [], "pièce noire basse"),
    ("metal", ["metal", "bright", "tall"], None),
]
ITEM_LEN = 40.0


def items():
    return "[" + ", ".join(
        f'(class: "{c}", length: {ITEM_LEN}, tags: [{", ".join(chr(34) + t + chr(34) for t in tags)}])'
        for c, tags, _ in CLASSES) + "]"


PARTS = [
    # id, name, French name
    ("start_button", "Line start", "bouton de marche de la ligne"),
    ("stop_button", "Line stop", "bouton d'arrêt de la ligne"),
    ("ds_ejector", "Magazine ejector", "éjecteur du magasin"),
    ("ds_belt", "Transfer belt", "convoyeur de transfert"),
    ("ts_belt", "Testing belt", "convoyeur de test"),
    ("ts_clamp", "Test clamp", "bride de test"),
    ("hs_x", "Gantry X", "portique X"),
    ("hs_z", "Gantry Z", "portique Z"),
    ("hs_grip", "Gripper", "pince"),
    ("ps_belt", "Processing belt", "convoyeur d'usinage"),
    ("ps_clamp", "Drilling clamp", "bride de perçage"),
    ("ps_drill", "Drill slide", "coulisse de perceuse"),
    ("ps_spindle", "Spindle", "broche"),
    ("ps_tester", "Hole tester", "palpeur de perçage"),
    ("ss_belt1", "Sorting belt 1", "convoyeur de tri 1"),
    ("ss_pusher1", "Pusher 1 (metal)", "poussoir 1 (métal)"),
    ("ss_belt2", "Sorting belt 2", "convoyeur de tri 2"),
    ("ss_pusher2", "Pusher 2 (red)", "poussoir 2 (rouge)"),
    ("ss_out", "Black outfeed", "sortie noire"),
]


def plant():
    lines = []
    lines.append("""// A five-station production line of the modular kind used in teaching labs (Festo MPS
// style): distributing (stack magazine + ejector + transfer belt), testing (belt with a
// clamp and height / inductive / optical sensors), handling (pick-and-place gantry X, Z
// and gripper), processing (belt with a clamp, a two-speed drill and its spindle, a
// hole tester) and sorting (two belts with a pusher each, and a powered outfeed into
// the black bin). Issue 16: a plant with more than 64 sensors and 24 actuators.
//
// Signals are prefixed by station: DS_, TS_, HS_, PS_, SS_; the panel has LINE_START
// and LINE_STOP. Generated by scripts/gen-production-line.py (with components.ron,
// io-map.ron and the signal keys of i18n/fr.ftl).
//
// Safe values: every output Zero. Every cylinder is double-acting (two valves, one per
// direction) and every motor stops when its output drops: with all outputs off nothing
// moves, so the fallback's all-zero vector satisfies every constraint in every context.
// The spindle runs down when PS_SPINDLE drops (the drill does not move by itself).
Plant(
    name: "Production line",
    description: "Five stations of a teaching line: distributing, testing, handling, processing (drilling) and sorting of workpieces of three colours/materials.",
    signals: [""")
    for k, (sid, el, en, _fr) in enumerate(S):
        lines.append(f'        (id: "{sid}", kind: Sensor, description: "{en}", element: "{el}", address: Some(DiscreteInput({k}))),')
    for k, (sid, el, en, _fr, off_en, _off_fr) in enumerate(A):
        lines.append(f'        (id: "{sid}", kind: Actuator, description: "{en}", element: "{el}", address: Some(Coil({k})), safe: Zero, off: Some("{off_en}")),')
    lines.append("    ],\n)\n")
    return "\n".join(lines)


def io_map():
    lines = ["// The line's Modbus map: sensors as discrete inputs, outputs as coils, in the order",
             "// of plant.ron (generated by scripts/gen-production-line.py).",
             "IoMap(", "    unit: 1,", "    poll_ms: 10,", "    max_age_ms: 30,", "    signals: ["]
    for k, s in enumerate(S):
        lines.append(f'        (signal: "{s[0]}", address: DiscreteInput({k})),')
    for k, a in enumerate(A):
        lines.append(f'        (signal: "{a[0]}", address: Coil({k})),')
    lines += ["    ],", ")", ""]
    return "\n".join(lines)


def fr_signals():
    out = ["# --- generated by scripts/gen-production-line.py (signals, elements, parts, items, off) ---"]
    for s in S:
        out.append(f"signal-{s[0]} = {s[3]}")
    for a in A:
        out.append(f"signal-{a[0]} = {a[3]}")
    out.append("")
    for el, fr in ELEMENTS_FR.items():
        out.append(f"element-{el.lower().replace(' ', '-')} = {fr}")
    out.append("")
    for pid, _n, fr in PARTS:
        out.append(f"part-{pid} = {fr}")
    seen = set()
    for c, _t, fr in CLASSES:
        if fr and c not in seen:
            seen.add(c)
            out.append(f"item-{c} = {fr}")
    out.append("")
    for a in A:
        out.append(f"off-{a[0]} = {a[5]}")
    out.append("# --- end of generated part ---")
    return "\n".join(out) + "\n"


COMPONENTS = """// The production line's machine as components (generated by
// scripts/gen-production-line.py; edit the script, not this file).
//
// The workpieces are items of 40 mm along the belts, in classes whose tags the beams may
// see: metal (metal, bright, tall), red (red, bright, tall), black (tall), black_low (no
// tag: a black workpiece too low). The magazine holds them in the order
// metal, red, black, red, black_low, metal, then again.
//
// Timings are the emulator's (1 ms step, 10 ms PLC scan), measured with
// `vigie run --headless` on scenarios/reference.ron; see each station.
//
// Where the kinds stop (said here rather than pretended):
// - The stack magazine itself is not modelled: its ejector's extension places the next
//   workpiece of an endless list at the transfer belt's entry (the conveyor's `feed`).
//   There is no magazine-empty sensor (no kind counts a stack).
// - The gantry carries the workpiece: its pick is the testing belt's `take` (the
//   gripper closing low at the pick place) and its place is the processing belt's
//   `feed` with `from: "ts_belt"` (the gripper opening low at the place): the very
//   workpiece, class and number kept, is put down. The gripper's jaws do not know it
//   (their axis closes the same with or without a workpiece).
// - The pushers' slides are not conveyors: a pusher's extension is the sorting belt's
//   `take` (the item at the belt's end leaves, counted as delivered); a slide would
//   be a conveyor fed `from` that belt.
// - Pusher, clamp and gripper axes always reach their end windows: an axis does not
//   know the item (a clamp with no workpiece closes like one with a workpiece; the
//   gripper's closed window cannot tell a part from no part).
// - The processing "rotary indexing table" of the MPS is a straight belt here (a
//   conveyor is straight and an axis carries no item): drilling place at 300 mm, hole
//   test at 600 mm.
Components(
    name: "Production line",
    components: [
        (id: "start_button", name: "Line start", kind: Button((signal: "LINE_START", pulse_ms: 300))),
        (id: "stop_button", name: "Line stop", kind: Button((signal: "LINE_STOP", pulse_ms: 300))),

        // --- Distributing -------------------------------------------------------------
        // The magazine's ejector: 60 mm at 120 mm/s (0.5 s each way). Its extension
        // places the bottom workpiece at the transfer belt's entry.
        (id: "ds_ejector", name: "Magazine ejector", kind: Axis((
            min: 0.0, max: 60.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "DS_EJ_FWD", speed: 120.0), (when: "DS_EJ_BWD", speed: -120.0)],
            sensors: [(signal: "DS_EJ_RET", from: 0.0, to: 2.0), (signal: "DS_EJ_EXT", from: 58.0, to: 60.0)],
            motion: Some("DS_EJ_MOV"),
        ))),
        // Transfer belt: 400 mm at 200 mm/s; a workpiece reaches the end 1.8 s after it
        // is placed and passes to the testing belt's entry (when free).
        (id: "ds_belt", name: "Transfer belt", kind: Conveyor((
            length: 400.0,
            drives: [(when: "DS_CONV", speed: 200.0)],
            sensors: [(signal: "DS_IN", at: 20.0), (signal: "DS_OUT", at: 385.0)],
            motion: Some("DS_MOV"),
            feed: Some((when: "DS_EJ_EXT", items: ITEMS)),
            exit: To("ts_belt"),
        ))),

        // --- Testing ------------------------------------------------------------------
        // Testing belt: 600 mm, fast 200 mm/s, slow 50 mm/s from the slow-down beam
        // (250 mm) to the test place (300 mm: 1 s); the height, inductive and optical
        // sensors look at the workpiece held there (at 290 mm: covered whenever TS_POS
        // is). The gantry takes the workpiece at the end (its front at 585 mm or more).
        (id: "ts_belt", name: "Testing belt", kind: Conveyor((
            length: 600.0,
            drives: [(when: "TS_FAST", speed: 200.0), (when: "TS_SLOW", speed: 50.0)],
            sensors: [
                (signal: "TS_IN", at: 20.0),
                (signal: "TS_PRE", at: 250.0),
                (signal: "TS_POS", at: 300.0),
                (signal: "TS_TALL", at: 290.0, sees: Some("tall")),
                (signal: "TS_METAL", at: 290.0, sees: Some("metal")),
                (signal: "TS_BRIGHT", at: 290.0, sees: Some("bright")),
                (signal: "TS_END", at: 585.0),
            ],
            motion: Some("TS_MOV"),
            take: Some("HS_GR_CLOSED . HS_X_PICK . HS_Z_LOW"),
            exit: Stop,
        ))),
        // Test clamp: 15 mm at 50 mm/s (0.3 s).
        (id: "ts_clamp", name: "Test clamp", kind: Axis((
            min: 0.0, max: 15.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "TS_CL_FWD", speed: 50.0), (when: "TS_CL_BWD", speed: -50.0)],
            sensors: [(signal: "TS_CL_OPEN", from: 0.0, to: 1.0), (signal: "TS_CL_CLOSED", from: 14.0, to: 15.0)],
            motion: Some("TS_CL_MOV"),
        ))),

        // --- Handling -----------------------------------------------------------------
        // Gantry X: 600 mm at 400 mm/s (1.5 s pick to place, through the half-way window).
        (id: "hs_x", name: "Gantry X", kind: Axis((
            min: 0.0, max: 600.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "HS_X_R", speed: 400.0), (when: "HS_X_L", speed: -400.0)],
            sensors: [
                (signal: "HS_X_PICK", from: 0.0, to: 2.0),
                (signal: "HS_X_MID", from: 298.0, to: 302.0),
                (signal: "HS_X_PLACE", from: 598.0, to: 600.0),
            ],
            motion: Some("HS_X_MOV"),
        ))),
        // Gantry Z: 120 mm at 200 mm/s (0.6 s), down positive.
        (id: "hs_z", name: "Gantry Z", kind: Axis((
            min: 0.0, max: 120.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "HS_Z_DN", speed: 200.0), (when: "HS_Z_UP", speed: -200.0)],
            sensors: [(signal: "HS_Z_TOP", from: 0.0, to: 2.0), (signal: "HS_Z_LOW", from: 118.0, to: 120.0)],
            motion: Some("HS_Z_MOV"),
        ))),
        // Gripper fingers: 10 mm at 50 mm/s (0.2 s), closing positive.
        (id: "hs_grip", name: "Gripper", kind: Axis((
            min: 0.0, max: 10.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "HS_GR_CLOSE", speed: 50.0), (when: "HS_GR_OPEN", speed: -50.0)],
            sensors: [(signal: "HS_GR_OPENED", from: 0.0, to: 0.5), (signal: "HS_GR_CLOSED", from: 9.5, to: 10.0)],
        ))),

        // --- Processing ---------------------------------------------------------------
        // Processing belt: 900 mm at 200 mm/s; the gantry places a workpiece at its entry
        // (the gripper opening low over it); drilling place at 300 mm, hole test at
        // 600 mm; it passes to the sorting belt 1 at its end (when free).
        (id: "ps_belt", name: "Processing belt", kind: Conveyor((
            length: 900.0,
            drives: [(when: "PS_CONV", speed: 200.0)],
            sensors: [
                (signal: "PS_IN", at: 20.0),
                (signal: "PS_DRILL_POS", at: 300.0),
                (signal: "PS_TEST_POS", at: 600.0),
                (signal: "PS_END", at: 885.0),
            ],
            motion: Some("PS_MOV"),
            feed: Some((when: "HS_GR_OPENED . HS_X_PLACE . HS_Z_LOW", from: Some("ts_belt"))),
            exit: To("ss_belt1"),
        ))),
        (id: "ps_clamp", name: "Drilling clamp", kind: Axis((
            min: 0.0, max: 15.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "PS_CL_FWD", speed: 50.0), (when: "PS_CL_BWD", speed: -50.0)],
            sensors: [(signal: "PS_CL_OPEN", from: 0.0, to: 1.0), (signal: "PS_CL_CLOSED", from: 14.0, to: 15.0)],
            motion: Some("PS_CL_MOV"),
        ))),
        // Drill slide, down positive: fast approach 60 mm/s from the top (0-1 mm) to
        // just above the workpiece (29-31 mm, about 0.5 s), drilling feed 15 mm/s to full
        // depth (58-60 mm, about 1.8 s), up 100 mm/s (about 0.6 s). The fixture is at
        // 64 mm: a drill driven into it breaks (Crash), 0.27 s of feed past full depth.
        (id: "ps_drill", name: "Drill slide", kind: Axis((
            min: 0.0, max: 64.0, start: 0.0,
            end_stops: (max: Crash),
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "PS_DR_FAST", speed: 60.0), (when: "PS_DR_FEED", speed: 15.0), (when: "PS_DR_UP", speed: -100.0)],
            sensors: [
                (signal: "PS_DR_TOP", from: 0.0, to: 1.0),
                (signal: "PS_DR_APPROACH", from: 29.0, to: 31.0),
                (signal: "PS_DR_LOW", from: 58.0, to: 60.0),
            ],
            motion: Some("PS_DR_MOV"),
        ))),
        // The spindle: its one degree of freedom is its speed (unit rpm), read by a speed
        // monitor with two windows. Switched on, it runs up at 10000 rpm/s (at speed,
        // 2900 rpm, in 0.29 s); switched off, it runs down at 6000 rpm/s (below 100 rpm
        // 0.48 s later). The run-down is the one drive of the line active with its output
        // off (`/PS_SPINDLE`): the safe state lets the spindle stop, which is harmless.
        (id: "ps_spindle", name: "Spindle", kind: Axis((
            unit: "rpm",
            min: 0.0, max: 3000.0, start: 0.0,
            tolerance_ms: 40,
            drives: [(when: "PS_SPINDLE", speed: 10000.0), (when: "/PS_SPINDLE", speed: -6000.0)],
            sensors: [(signal: "PS_SP_STOP", from: 0.0, to: 100.0), (signal: "PS_SP_RUN", from: 2900.0, to: 3000.0)],
        ))),
        // Hole tester: 20 mm at 50 mm/s (0.4 s). It reaches its low window whether or not
        // the hole was drilled (an axis does not know the item).
        (id: "ps_tester", name: "Hole tester", kind: Axis((
            min: 0.0, max: 20.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "PS_TE_DN", speed: 50.0), (when: "PS_TE_UP", speed: -50.0)],
            sensors: [(signal: "PS_TE_TOP", from: 0.0, to: 1.0), (signal: "PS_TE_LOW", from: 19.0, to: 20.0)],
            motion: Some("PS_TE_MOV"),
        ))),

        // --- Sorting ------------------------------------------------------------------
        // Sorting belt 1: 400 mm at 200 mm/s. A workpiece stops in front of pusher 1 when
        // its front reaches 388 mm (SS_AT1), where the inductive, colour and height
        // sensors (380 mm) see it; pusher 1's extension takes it (into the metal slide);
        // else the belt runs on and it passes to belt 2.
        (id: "ss_belt1", name: "Sorting belt 1", kind: Conveyor((
            length: 400.0,
            drives: [(when: "SS_CONV1", speed: 200.0)],
            sensors: [
                (signal: "SS_IN1", at: 20.0),
                (signal: "SS_METAL", at: 380.0, sees: Some("metal")),
                (signal: "SS_RED1", at: 380.0, sees: Some("red")),
                (signal: "SS_TALL", at: 380.0, sees: Some("tall")),
                (signal: "SS_AT1", at: 388.0),
            ],
            motion: Some("SS_MOV1"),
            take: Some("SS_P1_EXT"),
            exit: To("ss_belt2"),
        ))),
        // Pushers: 50 mm at 150 mm/s (about 0.33 s).
        (id: "ss_pusher1", name: "Pusher 1 (metal)", kind: Axis((
            min: 0.0, max: 50.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "SS_P1_FWD", speed: 150.0), (when: "SS_P1_BWD", speed: -150.0)],
            sensors: [(signal: "SS_P1_RET", from: 0.0, to: 2.0), (signal: "SS_P1_EXT", from: 48.0, to: 50.0)],
            motion: Some("SS_P1_MOV"),
        ))),
        (id: "ss_belt2", name: "Sorting belt 2", kind: Conveyor((
            length: 400.0,
            drives: [(when: "SS_CONV2", speed: 200.0)],
            sensors: [
                (signal: "SS_IN2", at: 20.0),
                (signal: "SS_RED2", at: 380.0, sees: Some("red")),
                (signal: "SS_METAL2", at: 380.0, sees: Some("metal")),
                (signal: "SS_AT2", at: 388.0),
            ],
            motion: Some("SS_MOV2"),
            take: Some("SS_P2_EXT"),
            exit: To("ss_out"),
        ))),
        (id: "ss_pusher2", name: "Pusher 2 (red)", kind: Axis((
            min: 0.0, max: 50.0, start: 0.0,
            variation_ppm: 10000, tolerance_ms: 40,
            drives: [(when: "SS_P2_FWD", speed: 150.0), (when: "SS_P2_BWD", speed: -150.0)],
            sensors: [(signal: "SS_P2_RET", from: 0.0, to: 2.0), (signal: "SS_P2_EXT", from: 48.0, to: 50.0)],
            motion: Some("SS_P2_MOV"),
        ))),
        // The black outfeed: 300 mm at 200 mm/s into the black bin (a sink: delivered).
        (id: "ss_out", name: "Black outfeed", kind: Conveyor((
            length: 300.0,
            drives: [(when: "SS_CONV_OUT", speed: 200.0)],
            sensors: [
                (signal: "SS_OUT_IN", at: 20.0),
                (signal: "SS_OUT_RED", at: 150.0, sees: Some("red")),
                (signal: "SS_OUT_END", at: 290.0),
            ],
            motion: Some("SS_OUT_MOV"),
            exit: Sink,
        ))),
    ],
    dangers: [
        (id: "drill_fast_into_part", text: "the drill enters the workpiece at the approach speed",
         component: "ps_drill", from: 32.0, to: 64.0, when: "PS_DR_FAST"),
    ],
)
"""


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "plant.ron").write_text(plant())
    (OUT / "io-map.ron").write_text(io_map())
    (OUT / "components.ron").write_text(COMPONENTS.replace("ITEMS", items()))
    fr = OUT / "i18n" / "fr.ftl"
    fr.parent.mkdir(exist_ok=True)
    head = ""
    if fr.exists():
        text = fr.read_text()
        head = text.split("# --- generated by")[0]
    fr.write_text(head + fr_signals())
    print(f"{len(S)} sensors, {len(A)} actuators -> {OUT}")


if __name__ == "__main__":
    main()
