use super::*;
use proptest::prelude::*;

/// A fresh empty directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vigie-diag-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `(name, path, value text, line, column)` of every field.
fn fields(text: &str) -> Vec<(String, String, String, usize, usize)> {
    ron_fields(text)
        .into_iter()
        .map(|f| {
            (
                f.name.clone(),
                f.path.join("."),
                text[f.value.clone()].to_string(),
                f.line,
                f.column,
            )
        })
        .collect()
}

#[test]
fn ron_fields_name_paths_values_and_positions() {
    let text = r##"// id: "not a field", in a comment
Plant(
    name: "p: q", /* kind: Sensor, /* nested */ still a comment */
    signals: [
        (id: "C0", kind: Sensor, description: "a \"quoted\" id: x"),
        (id : r#"C1"#, kind: Actuator, address: Some(Coil(3)),),
        (
            id: "Ç2", // é
            kind: Sensor,
            description: 'x', delay: 1e+3,
        ),
    ],
)
"##;
    let got = fields(text);
    let want: Vec<(&str, &str, &str, usize, usize)> = vec![
        ("name", "", "\"p: q\"", 3, 11),
        (
            "signals",
            "",
            "[\n        (id: \"C0\", kind: Sensor, description: \"a \\\"quoted\\\" id: x\"),\n        (id : r#\"C1\"#, kind: Actuator, address: Some(Coil(3)),),\n        (\n            id: \"Ç2\", // é\n            kind: Sensor,\n            description: 'x', delay: 1e+3,\n        ),\n    ]",
            4,
            14,
        ),
        ("id", "signals", "\"C0\"", 5, 14),
        ("kind", "signals", "Sensor", 5, 26),
        (
            "description",
            "signals",
            "\"a \\\"quoted\\\" id: x\"",
            5,
            47,
        ),
        ("id", "signals", "r#\"C1\"#", 6, 15),
        ("kind", "signals", "Actuator", 6, 30),
        ("address", "signals", "Some(Coil(3))", 6, 49),
        ("id", "signals", "\"Ç2\"", 8, 17),
        ("kind", "signals", "Sensor", 9, 19),
        ("description", "signals", "'x'", 10, 26),
        ("delay", "signals", "1e+3", 10, 38),
    ];
    let got: Vec<_> = got
        .iter()
        .map(|(a, b, c, d, e)| (a.as_str(), b.as_str(), c.as_str(), *d, *e))
        .collect();
    assert_eq!(got, want);
    let all = ron_fields(text);
    let second = ron_field(&all, &["signals"], "id", 1).unwrap();
    assert_eq!(
        second.location(Path::new("plant.ron")).to_string(),
        "plant.ron:6:15"
    );
    // The fields of one struct share their container, the next struct has another.
    assert_eq!(all[2].container, all[4].container);
    assert_ne!(all[2].container, all[5].container);
    assert!(ron_field(&all, &["signals"], "id", 3).is_none());
    assert!(ron_field(&all, &[], "id", 0).is_none());
}

#[test]
fn ron_fields_nested_paths() {
    let text = "Scenario(arrivals: Some(Periodic(period_ms: 0)), faults: [(fault: SpuriousRise(sensor: \"C3\", pulse_ms: 0), duration_ms: Some(0))], duration_ms: 5)";
    let got: Vec<(String, String)> = fields(text)
        .into_iter()
        .map(|(n, p, v, _, _)| (format!("{p}/{n}"), v))
        .collect();
    let want = [
        ("/arrivals", "Some(Periodic(period_ms: 0))"),
        ("arrivals/period_ms", "0"),
        (
            "/faults",
            "[(fault: SpuriousRise(sensor: \"C3\", pulse_ms: 0), duration_ms: Some(0))]",
        ),
        ("faults/fault", "SpuriousRise(sensor: \"C3\", pulse_ms: 0)"),
        ("faults.fault/sensor", "\"C3\""),
        ("faults.fault/pulse_ms", "0"),
        ("faults/duration_ms", "Some(0)"),
        ("/duration_ms", "5"),
    ];
    let want: Vec<(String, String)> = want
        .iter()
        .map(|(a, b)| ((*a).to_string(), (*b).to_string()))
        .collect();
    assert_eq!(got, want);
}

proptest! {
    /// Whatever the text (cut RON, unbalanced brackets and quotes, any character), the
    /// scan ends, and every value range lies on character boundaries of the text.
    #[test]
    fn ron_fields_never_panics(
        text in prop::collection::vec(
            prop_oneof![
                prop::sample::select(vec![
                    "(", ")", "[", "]", "{", "}", ",", ":", "::", "\"", "\\", "'", "r#\"", "\"#",
                    "//", "/*", "*/", "\n", " ", "id", "a:", "1e-", "é", "·", "#", "r",
                ]).prop_map(str::to_string),
                any::<char>().prop_map(|c| c.to_string()),
            ],
            0..60,
        ).prop_map(|v| v.concat())
    ) {
        for f in ron_fields(&text) {
            prop_assert!(f.value.start <= f.value.end && f.value.end <= text.len());
            prop_assert!(text.get(f.value.clone()).is_some());
            prop_assert!(f.line >= 1 && f.column >= 1);
        }
    }
}

#[test]
fn a_50_mib_file_is_refused_before_it_is_read() {
    let dir = temp_dir("large");
    let path = dir.join("plant.ron");
    let f = std::fs::File::create(&path).unwrap();
    f.set_len(50 * 1024 * 1024).unwrap(); // sparse: no disk, no memory
    // (How fast: `tests/integration/bad_input.rs` times it; the core has no clock.)
    let err = read_text(&path).unwrap_err();
    assert_eq!(err.code, "V0003");
    assert_eq!(
        err.message,
        format!(
            "{} is 52428800 bytes (50.0 MiB), more than the limit of 8388608 bytes (8 MiB): not read",
            path.display()
        )
    );
    assert_eq!(check_size(&path).unwrap_err(), err);
    assert_eq!(read_text_optional(&path).unwrap_err(), err);
    // Exactly at the limit is read.
    f.set_len(MAX_FILE_BYTES).unwrap();
    assert_eq!(read_text(&path).unwrap().len() as u64, MAX_FILE_BYTES);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_device_is_not_read() {
    // `/dev/zero` says it has 0 bytes and never ends; a pipe would block the open.
    let zero = Path::new("/dev/zero");
    if !zero.exists() {
        return;
    }
    let err = read_text(zero).unwrap_err();
    assert_eq!(
        err.to_string(),
        "error[V0002]: cannot read /dev/zero: not a regular file (a device, a pipe or a socket)"
    );
    assert_eq!(check_size(zero).unwrap_err(), err);
}

#[test]
fn unreadable_files_are_v0002_problems_naming_the_file() {
    let dir = temp_dir("unreadable");
    let bad = dir.join("observers.ron");
    std::fs::write(&bad, b"Observers(\xff)").unwrap();
    let err = read_text(&bad).unwrap_err();
    assert_eq!(err.code, "V0002");
    assert!(
        err.message
            .starts_with(&format!("cannot read {}: invalid utf-8", bad.display())),
        "{}",
        err.message
    );
    let missing = dir.join("missing.ron");
    assert_eq!(read_text_optional(&missing), Ok(None));
    assert_eq!(read_text(&missing).unwrap_err().code, "V0002");
    // A directory is not a file.
    assert_eq!(read_text(&dir).unwrap_err().code, "V0002");
    let _ = std::fs::remove_dir_all(&dir);
}

/// RON's whitespace is wider than ASCII's: a vertical tab, a form feed or a line
/// separator between a field's name and its colon still leaves the field found where
/// RON reads it (`vigie diagnose learn` rewrites bounds by these positions).
#[test]
fn ron_fields_skip_every_whitespace_ron_skips() {
    #[derive(serde::Deserialize)]
    struct I {
        lo: u32,
        hi: u32,
    }
    for ws in [
        "\u{b}",
        "\u{c}",
        "\u{85}",
        "\u{200e}",
        "\u{2028}",
        " \u{2029}\t",
    ] {
        let text = format!("(lo{ws}: 1,{ws}hi{ws}:{ws}22)");
        let parsed: I = ron::from_str(&text).unwrap_or_else(|e| panic!("{ws:?}: {e}"));
        assert_eq!((parsed.lo, parsed.hi), (1, 22));
        let fields = ron_fields(&text);
        let hi = ron_field(&fields, &[], "hi", 0).unwrap_or_else(|| panic!("{ws:?}: {fields:?}"));
        assert_eq!(&text[hi.value.clone()], "22", "{ws:?}");
    }
}
