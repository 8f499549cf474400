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
    if std::env::var_os("VIGIE_CAMPAIGN_DUMP").is_some() {
        for o in report.outcomes.iter().filter(|o| o.trip_ms.is_some()) {
            let f = o
                .first
                .as_ref()
                .map(|i| format!("{} {}", i.code, i.text))
                .unwrap_or_default();
            eprintln!(
                "{} {} @{:?} [{}] {} :: {}",
                if o.localised { "OK  " } else { "MISS" },
                o.id,
                o.trip_ms,
                o.constraints.join(","),
                o.description,
                f
            );
        }
    }
    for o in report.misses() {
        eprintln!(
            "MISS {} {} [{}] {}",
            o.id,
            o.description,
            o.constraints.join(","),
            o.why
        );
    }
    let m = &report.misplaced;
    eprintln!(
        "mutants {} tripped {} localised {} rate {:.1}% mean names {:.2}; misplaced actions {} tripped {} blamed {} ({:.1}%), driven {} blamed {}",
        report.mutants,
        report.tripped,
        report.localised,
        report.rate_percent(),
        report.mean_first_names,
        m.mutants,
        m.tripped,
        m.localised,
        m.rate_percent,
        m.driven,
        m.driven_localised
    );
    // Measured: 490 mutants (14 library variants + 390 single mutations + 86 actions
    // moved to another step of their chart), 182 trip, 173 are localised (95.1 %). Every
    // library variant but E14 trips (E14 needs two boxes closer than C0-C1 on the entry
    // conveyor). The misses are feed-chart receptivities (t11, t12) that keep X11
    // active: the first suspect is then the A0/A1 equation that reads X11, not the
    // transition that should have left it.
    assert_eq!(report.mutants, 490);
    assert!(report.tripped >= 170, "{} tripped", report.tripped);
    let library: Vec<&str> = report
        .outcomes
        .iter()
        .filter(|o| o.id.starts_with('E') && o.trip_ms.is_some())
        .map(|o| o.id.as_str())
        .collect();
    eprintln!("library variants that trip: {library:?}");
    let rate = report.rate_percent();
    assert!(
        rate >= 93.0,
        "localisation rate {rate:.1}% below the floor of 93%"
    );
    assert_eq!(library.len(), 13, "{library:?}");
    // Misplaced actions, measured: 41 of the 86 trip; the first suspect blames the step
    // the action was moved to (X417) for 22 (53.7 %; before X417, 5: the X409 of an
    // initial step). The 27 trips that the moved action drove give 22 of them: the misses
    // are A3 moved to X21/X22 (nothing in the program says that C4 excludes C5) and A2
    // moved to X25 (active for a while: its exits stay the first suspect, X412). The 14
    // others trip on the action's absence from its own step (A2 missing in X21/X31, A4
    // in X24/X34) before the step it was moved to is ever active: the first suspect then
    // names the step it was taken from.
    assert_eq!(m.mutants, 86);
    assert!(m.tripped >= 35, "{} misplaced actions tripped", m.tripped);
    assert!(
        m.rate_percent >= 53.0,
        "misplaced actions: the first suspect blames the step for {:.1}%, below the floor of 53%",
        m.rate_percent
    );
    assert!(
        m.driven_localised * 100 >= m.driven * 80,
        "misplaced actions that drove the trip: {} of {} blamed on their step, below 80%",
        m.driven_localised,
        m.driven
    );
    // The paper's case is localised on t24 and its receptivity.
    let e01 = report.outcomes.iter().find(|o| o.id == "E01").expect("E01");
    let first = e01.first.as_ref().expect("hypothesis");
    assert_eq!(
        (first.code, first.fields["transition"].as_str()),
        ("X407", "t24")
    );
}

/// The reference program itself never trips in the campaign's run.
#[test]
fn the_reference_program_does_not_trip() {
    let bundle = station();
    let lib = ErrorLibrary::load(&bundle.dir.join("programs/errors.ron"), &bundle.plant)
        .expect("library");
    let reference = Mutant {
        id: "REF".into(),
        description: "reference".into(),
        place: String::new(),
        names: BTreeSet::new(),
        element: String::new(),
        operator: None,
        program: lib.reference,
    };
    let o = run_one(&bundle, &reference, &Config::default());
    assert_eq!(o.trip_ms, None, "{o:?}");
    assert_eq!(o.why, "no trip");
}

#[test]
fn a_suspect_names_its_elements_not_the_actuator() {
    let item = Item::new(
        crate::diag::codes::X_TRANSITION_DEACTIVATED_STEP,
        String::new(),
        &[
            ("output", "A4".into()),
            ("transition", "t24".into()),
            ("signals", "C7".into()),
            ("activated", "X25".into()),
        ],
    );
    let names: Vec<String> = suspect_names(&item).into_iter().collect();
    assert_eq!(names, vec!["C7", "X25", "t24"]);
}

#[test]
fn library_patches_name_their_place() {
    let (place, names) = patch_names(&Patch::Condition {
        transition: "t24".into(),
        condition: "RE(C7)".into(),
    });
    assert_eq!(place, "transition t24");
    assert_eq!(names.into_iter().collect::<Vec<_>>(), vec!["C7", "t24"]);
    let (place, names) = patch_names(&Patch::RemoveAction {
        step: "X24".into(),
        target: "A4".into(),
    });
    assert_eq!(place, "step X24");
    assert_eq!(names.into_iter().collect::<Vec<_>>(), vec!["X24"]);
    // A moved action: its place is the step it goes to; either step localises it, the
    // step it goes to is what a suspect must blame.
    let moved = Patch::MoveAction {
        from: "X23".into(),
        to: "X22".into(),
        target: "A4".into(),
    };
    let (place, names) = patch_names(&moved);
    assert_eq!(place, "step X22");
    assert_eq!(names.into_iter().collect::<Vec<_>>(), vec!["X22", "X23"]);
    assert_eq!(patch_element(&moved), "X22");
}
