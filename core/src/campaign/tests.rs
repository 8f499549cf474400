use super::*;

fn station() -> PlantBundle {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    let (bundle, problems) = PlantBundle::load(&dir).expect("plant loads");
    assert!(problems.iter().all(|p| !p.is_error()), "{problems:?}");
    bundle
}

/// The whole campaign: every library variant and every single mutation of the
/// reference program. The localisation rate must not fall below the measured floor.
#[test]
fn mutation_campaign_localises_the_errors() {
    let bundle = station();
    let all = mutants(&bundle).expect("mutants");
    let report = run_mutants(&bundle, &all, &Config::default());
    for o in report.misses() {
        eprintln!("MISS {} {} [{}] {}", o.id, o.description, o.constraints.join(","), o.why);
    }
    eprintln!(
        "mutants {} tripped {} localised {} rate {:.1}% mean names {:.2}",
        report.mutants,
        report.tripped,
        report.localised,
        report.rate_percent(),
        report.mean_first_names
    );
}
