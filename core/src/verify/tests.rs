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
