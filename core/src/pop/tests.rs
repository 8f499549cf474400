use super::*;
use crate::test_support::station_dir;

fn station() -> DiagBundle {
    match load(&station_dir()) {
        Ok((d, _)) => d,
        Err(p) => panic!("{}", crate::diag::render(&p)),
    }
}

#[test]
fn station_models_compile_and_prune_by_the_filter() {
    let d = station();
    let table = d.compiled.components.iter().find(|c| c.id == "table").unwrap();
    assert_eq!(table.states.len(), 6);
    let pruned: Vec<_> = table.unexpected.iter().filter(|u| u.pruned_by.is_some()).map(|u| (u.state.as_str(), u.event.as_str(), u.pruned_by.as_deref().unwrap())).collect();
    assert!(pruned.contains(&("x4", "RE(A4)", "CSs14")), "{pruned:?}");
    assert!(pruned.contains(&("x2", "FE(A4)", "CSs15")), "{pruned:?}");
    assert!(d.rewritten.contains("def_C4"), "{}", d.rewritten);
}

#[test]
fn fault_free_run_has_no_certain_diagnosis() {
    let (out, _) = closed_loop(&station_dir(), 7, 600_000, None).unwrap();
    assert!(out.diagnoses.is_empty(), "{:#?}", out.diagnoses);
    assert!(out.delivered > 30, "{out:?}");
}

#[test]
fn c4_stuck_at_0_is_never_misdiagnosed() {
    let (out, sim) = closed_loop(&station_dir(), 3, 300_000, Some((crate::emulator::FaultKind::SensorStuckAt0("C4".into()), 100_000))).unwrap();
    // C4 stuck at 0 on the return looks like the table blocked between C5 and C4 (F12):
    // no certain diagnosis of the wrong partition, and no hazard.
    assert!(out.diagnoses.iter().all(|d| d.partition != "C5"), "{:#?}", out.diagnoses);
    assert_eq!(out.hazards, 0);
    let _ = sim;
}


#[test]
fn c4_stuck_at_1_is_diagnosed_on_its_partition() {
    let (out, _) = closed_loop(&station_dir(), 5, 200_000, Some((crate::emulator::FaultKind::SensorStuckAt1("C4".into()), 100_000))).unwrap();
    assert!(out.diagnoses.iter().any(|d| d.partition == "C4"), "{:#?}", out.diagnoses);
    assert!(out.diagnoses.iter().all(|d| d.partition == "C4"), "{:#?}", out.diagnoses);
}

#[test]
fn annex_b_recursion_matches_the_batch_figures() {
    let mut e = learn::Estimator::default();
    for t in [2000, 2200, 1900, 2100, 2300, 1800, 2000, 2200, 2100, 1900] {
        e.push(t);
    }
    assert!((e.mean - 2050.0).abs() < 1e-6 && (e.sigma() - 150.0).abs() < 1e-6, "{e:?}");
}

#[test]
fn untimed_replay_and_report() {
    let d = station();
    let table = d.compiled.components.iter().find(|c| c.id == "table").unwrap();
    let r = runtime::replay_untimed(table, &["RE(A4)", "tmo(I2)", "RE(C5)"]).unwrap();
    assert_eq!(r[2], [Some("F2".to_string())].into_iter().collect());
    let rep = report(&d.compiled);
    let f5 = rep.faults.iter().find(|f| f.fault == "F5").unwrap();
    assert!(f5.diagnosable, "{f5:?}");
    let (text, map) = faudes_export(table);
    assert!(text.contains("\"f_F1\" +o+") && map.contains("F12"));
}


