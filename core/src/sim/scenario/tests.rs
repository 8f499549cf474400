use super::*;
use crate::test_support::station_dir;

/// `line:col` just after the `nth` (from 0) occurrence of `needle` in `text`: where the
/// value that follows it starts.
fn after(text: &str, needle: &str, nth: usize) -> String {
    let (k, _) = text.match_indices(needle).nth(nth).unwrap();
    let start = k + needle.len();
    let line = text[..start].matches('\n').count() + 1;
    let from = text[..start].rfind('\n').map_or(0, |n| n + 1);
    format!("{line}:{}", text[from..start].chars().count() + 1)
}

/// The problems of a scenario text, rendered without the file name.
fn problems(text: &str) -> Vec<String> {
    let s: Scenario = match ron::from_str(text) {
        Ok(s) => s,
        Err(e) => {
            let p = crate::diag::ron_problem(Path::new("s.ron"), &e).to_string();
            return vec![p.trim_start_matches("s.ron:").to_string()];
        }
    };
    check(&s, text, Path::new("s.ron"))
        .iter()
        .map(|p| p.to_string().trim_start_matches("s.ron:").to_string())
        .collect()
}

#[test]
fn the_committed_scenarios_pass() {
    let dir = station_dir().join("scenarios");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        if let Err(p) = Scenario::load(&path) {
            panic!("{}", crate::diag::render(&p));
        }
        n += 1;
    }
    assert!(n >= 6);
}

#[test]
fn every_bad_duration_period_and_time_is_reported_at_its_value() {
    let text = r#"// A scenario with everything wrong in its times.
Scenario(
    name: "bad", // duration_ms: 1 in a comment does not count
    program: Reference,
    seed: 1,
    arrivals: Some(Periodic(period_ms: 0, jitter_ms: 18446744073709551615, mix: Alternate)),
    faults: [
        (trigger: At(5000), fault: SpuriousRise(sensor: "C3", pulse_ms: 0)),
        (trigger: When("C3"), fault: SensorStuckAt0("C4"), duration_ms: Some(0)),
        (duration_ms: Some(10), fault: SpuriousFall(pulse_ms: 5, sensor: "C3"), trigger: At(0)),
    ],
    actions: [(at_ms: 0, action: Start), (at_ms: 4000, action: Stop)],
    duration_ms: 4000,
    cycle_ms: 0,
    projection_ms: 86400000,
)
"#;
    let at = |needle: &str, nth: usize| after(text, needle, nth);
    assert_eq!(
        problems(text),
        [
            format!(
                "{}: error[V0401]: cycle_ms is 0 ms: a PLC cycle must be from 1 to 1000 ms",
                at("cycle_ms: ", 0)
            ),
            format!(
                "{}: error[V0403]: projection_ms is 86400000 ms: the projection horizon is at most 3600000 ms (1 h)",
                at("projection_ms: ", 0)
            ),
            format!(
                "{}: error[V0404]: action Stop at 4000 ms is not before the end of the run (duration_ms 4000): it would never happen",
                at("at_ms: ", 1)
            ),
            format!(
                "{}: error[V0405]: period_ms is 0 ms: an arrival period is from 1 ms to 604800000 ms",
                at("period_ms: ", 0)
            ),
            format!(
                "{}: error[V0405]: jitter_ms is 18446744073709551615 ms: at most 604800000 ms",
                at("jitter_ms: ", 0)
            ),
            format!(
                "{}: error[V0404]: fault SpuriousRise {{ sensor: \"C3\", pulse_ms: 0 }} at 5000 ms is not before the end of the run (duration_ms 4000): it would never happen",
                at("trigger: ", 0)
            ),
            format!(
                "{}: error[V0406]: pulse_ms is 0 ms: a spurious pulse lasts from 1 ms to 604800000 ms",
                at("pulse_ms: ", 0)
            ),
            format!(
                "{}: error[V0406]: fault SensorStuckAt0(\"C4\") lasts 0 ms: a fault lasts from 1 ms to 604800000 ms (leave duration_ms out for ever)",
                at("duration_ms: ", 1)
            ),
        ]
    );
}

#[test]
fn durations_zero_absurd_or_negative() {
    let scenario =
        |fields: &str| format!("Scenario(name: \"x\", program: Reference, seed: 1,\n    {fields})");
    assert_eq!(
        problems(&scenario("duration_ms: 0")),
        ["2:18: error[V0403]: duration_ms is 0 ms: a run lasts from 1 ms to 604800000 ms (7 days)"]
    );
    assert_eq!(
        problems(&scenario(
            "duration_ms: 18446744073709551615, cycle_ms: 100000"
        )),
        [
            "2:50: error[V0401]: cycle_ms is 100000 ms: a PLC cycle must be from 1 to 1000 ms",
            "2:18: error[V0403]: duration_ms is 18446744073709551615 ms: a run lasts from 1 ms to 604800000 ms (7 days)",
        ]
    );
    // A negative duration is not a number of milliseconds: the parser says where.
    assert_eq!(
        problems(&scenario("duration_ms: -5")),
        ["2:19: error[V0001]: invalid RON: Integer is out of bounds"]
    );
    // The longest run, cycle and horizon are accepted.
    assert!(
        problems(&scenario(
            "duration_ms: 604800000, cycle_ms: 1000, projection_ms: 3600000"
        ))
        .is_empty()
    );
    // Boxes listed after the end never arrive.
    assert_eq!(
        problems(&scenario(
            "duration_ms: 1000, arrivals: Some(List([(0, Small), (1000, Large)]))"
        )),
        [
            "2:34: error[V0404]: box arrival at 1000 ms is not before the end of the run (duration_ms 1000): it would never happen"
        ]
    );
}

#[test]
fn load_reports_the_file_and_the_position() {
    let dir = std::env::temp_dir().join(format!("vigie-scenario-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.ron");
    std::fs::write(
        &path,
        "Scenario(\n    name: \"x\",\n    program: Reference,\n    seed: 1,\n    duration_ms: 1000,\n    cycle_ms: 0,\n)\n",
    )
    .unwrap();
    let err = Scenario::load(&path).unwrap_err();
    assert_eq!(
        crate::diag::render(&err),
        format!(
            "{}:6:15: error[V0401]: cycle_ms is 0 ms: a PLC cycle must be from 1 to 1000 ms",
            path.display()
        )
    );
    let _ = std::fs::remove_dir_all(&dir);
}
