use super::*;
use std::path::Path;

fn station() -> (PlantBundle, Layout) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    let (b, _) = PlantBundle::load(&dir).expect("bundle");
    let l = Layout::load(&dir.join("layout.ron")).expect("layout");
    (b, l)
}

#[test]
fn station_full_set() {
    let (b, l) = station();
    let r = verify(&b, &l, &Options { max_boxes: 1, necessity: false }).expect("verify");
    eprintln!("{}", serde_json::to_string_pretty(&r.full.hazard).unwrap_or_default());
    eprintln!("states {} trans {} kinds {:?} deliv {:?} always {:?}", r.full.states, r.full.transitions, r.full.hazard_kinds, r.full.delivered.iter().map(|d| d.as_ref().map(|t| t.steps.len())).collect::<Vec<_>>(), r.full.always_deliverable);
    if let Some(t) = &r.full.stuck[0] { for s in t.steps.iter().rev().take(5) { eprintln!("{s:?}"); } }
    for i in &r.invariants { eprintln!("{} {}", i.id, i.proved); }
}

/// Runs SPIN on a generated model; panics loudly when spin or gcc is missing.
fn run_spin(text: &str, tag: &str) -> promela::SpinVerdict {
    use std::process::Command;
    let dir = std::env::temp_dir().join(format!("vigie-spin-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("model.pml"), text).expect("write model");
    let ok = |c: &mut Command, what: &str| {
        let o = c.current_dir(&dir).output().unwrap_or_else(|e| {
            panic!("SPIN CROSS-CHECK CANNOT RUN: `{what}` failed to start ({e}); install the Debian package `spin` (scripts/test.sh does)")
        });
        assert!(o.status.success() || what == "pan", "{what} failed: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    ok(Command::new("spin").args(["-a", "model.pml"]), "spin");
    ok(Command::new("gcc").args(["-O1", "-w", "-DMEMLIM=2048", "-o", "pan", "pan.c"]), "gcc");
    let out = ok(Command::new("./pan").args(["-m3000000", "-c0", "-n"]), "pan");
    let _ = std::fs::remove_dir_all(&dir);
    promela::parse_pan(&out)
}

fn rust_verdict(e: &Exploration) -> (Vec<String>, [bool; 2], bool) {
    let mut h: Vec<String> = e.hazard_kinds.iter().map(|(k, _)| k.clone()).collect();
    h.sort();
    (h, [e.delivered[0].is_some(), e.delivered[1].is_some()], e.no_fallback.is_some())
}

/// SPIN and the explorer agree on the station and on every weakened set (one box).
#[test]
fn spin_agrees_on_station_and_weakened_sets() {
    let (b, l) = station();
    let m = Model::new(&b, &l, 1).expect("model");
    let n_out = b.plant.outputs.len();
    let mut sets = vec![("full".to_string(), b.constraints.clone())];
    for (i, c) in b.constraints.constraints.iter().enumerate() {
        sets.push((format!("without-{}", c.id), without(&b.constraints, i)));
    }
    for (name, set) in &sets {
        let e = explore(&m, &Filter::new(set, n_out));
        let s = run_spin(&promela::generate(&m, set, &b.symbols), name);
        assert!(s.complete, "{name}: SPIN search incomplete");
        let r = rust_verdict(&e);
        assert_eq!((s.hazards.clone(), s.delivered, s.no_fallback), r, "{name}: SPIN vs explorer");
    }
}

#[test]
fn promela_dump() {
    let (b, l) = station();
    let m = Model::new(&b, &l, 1).expect("model");
    let text = promela::generate(&m, &b.constraints, &b.symbols);
    std::fs::write(std::env::temp_dir().join("vigie_model.pml"), text).expect("write");
}
