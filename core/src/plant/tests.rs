use super::*;

fn station_text() -> String {
    std::fs::read_to_string(crate::test_support::station_dir().join("plant.ron")).unwrap()
}

/// The problems of a plant text, rendered.
fn problems(text: &str) -> Vec<String> {
    match Plant::from_ron(text, Path::new("plant.ron")) {
        Ok(p) => panic!("expected problems, loaded {} signals", p.inputs.len()),
        Err(problems) => problems.iter().map(ToString::to_string).collect(),
    }
}

#[test]
fn the_station_loads() {
    let p = Plant::from_ron(&station_text(), Path::new("plant.ron")).unwrap();
    // The paper's 11 sensors and 7 actuators, and the device monitoring: nine mirror
    // contacts, KM0 and YV0.
    assert_eq!((p.inputs.len(), p.outputs.len()), (20, 9));
}

#[test]
fn a_duplicate_id_is_reported_where_the_duplicate_is_written() {
    // The last signal of the station copied after it, behind a comment that quotes it.
    let text = station_text();
    let (n, a6) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.contains("id: \"A6\""))
        .unwrap();
    let column = a6.find("\"A6\"").unwrap() + 1;
    let text = text.replacen(
        &format!("{a6}\n"),
        &format!("{a6}\n        // A6 again: {a6}\n{a6}\n"),
        1,
    );
    assert_eq!(
        problems(&text),
        [format!(
            "plant.ron:{}:{column}: error[V0011]: signal `A6` is declared twice (first on line {})",
            n + 3,
            n + 1
        )]
    );
}

#[test]
fn duplicates_behind_comments_strings_and_line_breaks() {
    // Fake `id:` in a comment and in a description must not shift the count; the
    // third `C1` is reported at its own place too, each against the first.
    let text = r#"Plant(
    name: "p",
    signals: [
        (id: "C0", kind: Sensor, description: "id: \"C1\""),
        // (id: "C1", kind: Sensor, description: "commented out"),
        (id: "C1", kind: Sensor, description: "first"),
        /* (id: "C0", kind: Sensor), */
        (
            kind: Sensor,
            description: "second",
            id:
                "C1",
        ),
        (description: "third", kind: Actuator, id: "C1"),
        (id: "C 2", kind: Sensor, description: "bad name"),
    ],
)
"#;
    assert_eq!(
        problems(text),
        [
            "plant.ron:12:17: error[V0011]: signal `C1` is declared twice (first on line 6)",
            "plant.ron:14:52: error[V0011]: signal `C1` is declared twice (first on line 6)",
            "plant.ron:15:14: error[V0010]: signal id `C 2` must be letters, digits and `_`",
        ]
    );
}

#[test]
fn a_sensor_and_an_actuator_with_one_id_are_a_duplicate() {
    let text = "Plant(name: \"p\", signals: [(id: \"X\", kind: Sensor, description: \"\"), (id: \"X\", kind: Actuator, description: \"\")])";
    assert_eq!(
        problems(text),
        ["plant.ron:1:75: error[V0011]: signal `X` is declared twice (first on line 1)"]
    );
}

/// Safety devices wired to the wrong kind of signal, or to nothing: V0014 at the
/// signal's line, every one.
#[test]
fn safety_devices_wired_wrong_are_reported_where_they_are_written() {
    let text = r#"Plant(name: "p", signals: [
    (id: "S1", kind: Sensor, description: "", supplies: ["M1"]),
    (id: "S2", kind: Sensor, description: "", feedback_of: Some("S1")),
    (id: "M1", kind: Actuator, description: "", feedback_of: Some("M1")),
    (id: "K1", kind: Actuator, description: "", supplies: ["M1", "K1", "X9"], held_on: true),
    (id: "M1_fb", kind: Sensor, description: "", feedback_of: Some("M1")),
    (id: "S3", kind: Sensor, description: "", feedback_ms: 30),
    (id: "M2_fb", kind: Sensor, description: "", feedback_of: Some("M1"), feedback_ms: 60000),
])"#;
    let p = problems(text);
    let expect = [
        "plant.ron:2:10: error[V0014]: `supplies` and `held_on` are for actuators; `S1` is a sensor",
        "plant.ron:3:10: error[V0014]: `S2` mirrors `S1`, which is not an actuator of the plant",
        "plant.ron:4:10: error[V0014]: `feedback_of` is for sensors (a contactor's mirror contact); `M1` is an actuator",
        "plant.ron:5:10: error[V0014]: `K1` supplies `K1`, which is not another actuator of the plant",
        "plant.ron:5:10: error[V0014]: `K1` supplies `X9`, which is not another actuator of the plant",
        "plant.ron:7:10: error[V0014]: `S3` has `feedback_ms` but mirrors nothing (`feedback_of`)",
        "plant.ron:8:10: error[V0014]: `M2_fb`: `feedback_ms` 60000 is longer than 10 s; a contact that slow cannot watch a contactor",
    ];
    assert_eq!(p, expect);
    // Wired right: the supplies and the mirrors by index.
    let ok = Plant::from_ron(
        r#"Plant(name: "p", signals: [
    (id: "M1_fb", kind: Sensor, description: "", feedback_of: Some("M1")),
    (id: "M1", kind: Actuator, description: ""),
    (id: "K1", kind: Actuator, description: "", supplies: ["M1"], held_on: true),
])"#,
        Path::new("plant.ron"),
    )
    .unwrap();
    assert_eq!(ok.supplies(), [(1, vec![0])]);
    assert_eq!(ok.mirrors(), [(0, 0)]);
}
