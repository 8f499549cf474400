use super::*;
use crate::test_support::station_dir;

fn station_text() -> String {
    std::fs::read_to_string(station_dir().join("diagnosers.ron")).unwrap()
}

/// Measures of `samples` for each interval id.
fn measures(samples: &[(&str, &[u64])]) -> BTreeMap<String, Estimator> {
    samples
        .iter()
        .map(|(id, taus)| {
            let mut e = Estimator::default();
            for &t in *taus {
                e.push(t);
            }
            ((*id).to_string(), e)
        })
        .collect()
}

/// The committed file, the bounds learned from `samples`, and the file rewritten.
fn learn(text: &str, samples: &[(&str, &[u64])]) -> (DiagnoserFile, String) {
    let path = Path::new("diagnosers.ron");
    let mut file = DiagnoserFile::from_ron(text, path).unwrap();
    apply(&mut file, &measures(samples));
    let out = rewrite(text, path, &file).unwrap_or_else(|p| panic!("{p}"));
    (file, out)
}

fn bounds(file: &DiagnoserFile, id: &str) -> (Bound, Bound) {
    let iv = file
        .components
        .iter()
        .flat_map(|c| &c.intervals)
        .find(|iv| iv.id == id)
        .unwrap();
    (iv.lo.clone(), iv.hi.clone())
}

#[test]
fn only_the_learned_bounds_change_in_the_committed_file() {
    let text = station_text();
    let (file, out) = learn(
        &text,
        &[
            ("I2", &[120, 125, 130, 126]),
            ("I4", &[2920, 2940, 2931]),
            ("I7", &[80, 80, 80]),
            // Intervals defined from others keep their bounds (only statistics).
            ("I1", &[10, 12]),
            ("I5", &[4000]),
        ],
    );
    // What the learning gave, written as the file writes bounds.
    let ms = |b: &Bound| match b {
        Bound::Ms(v) => *v,
        other => panic!("{other:?}"),
    };
    let (i2, i4, i7) = (
        bounds(&file, "I2"),
        bounds(&file, "I4"),
        bounds(&file, "I7"),
    );
    assert_ne!(i2, (Bound::Ms(50), Bound::Ms(250)));
    assert_eq!(
        bounds(&file, "I1"),
        (Bound::Ms(0), Bound::LoOf("I2".into()))
    );
    let expected = text
        .replacen(
            "(id: \"I2\", after: \"RE(A4)\", lo: Ms(50), hi: Ms(250),",
            &format!(
                "(id: \"I2\", after: \"RE(A4)\", lo: Ms({}), hi: Ms({}),",
                ms(&i2.0),
                ms(&i2.1)
            ),
            1,
        )
        .replacen(
            "(id: \"I4\", after: \"RE(A4)\", lo: Ms(2800), hi: Ms(3100),",
            &format!(
                "(id: \"I4\", after: \"RE(A4)\", lo: Ms({}), hi: Ms({}),",
                ms(&i4.0),
                ms(&i4.1)
            ),
            1,
        )
        .replacen(
            "(id: \"I7\", after: \"FE(A4)\", lo: Ms(20), hi: Ms(250),",
            &format!(
                "(id: \"I7\", after: \"FE(A4)\", lo: Ms({}), hi: Ms({}),",
                ms(&i7.0),
                ms(&i7.1)
            ),
            1,
        );
    assert_ne!(expected, text);
    assert_eq!(out, expected);
    // Comments and line structure are the file's.
    assert_eq!(out.lines().count(), text.lines().count());
    let comments = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| l.trim_start().starts_with("//"))
            .map(str::to_string)
            .collect()
    };
    assert!(!comments(&text).is_empty());
    assert_eq!(comments(&out), comments(&text));
    // Reading the rewritten file gives the learned bounds, and nothing else moved.
    let got = DiagnoserFile::from_ron(&out, Path::new("diagnosers.ron")).unwrap();
    let mut want = DiagnoserFile::from_ron(&text, Path::new("diagnosers.ron")).unwrap();
    for (w, f) in want
        .components
        .iter_mut()
        .flat_map(|c| &mut c.intervals)
        .zip(file.components.iter().flat_map(|c| &c.intervals))
    {
        w.lo.clone_from(&f.lo);
        w.hi.clone_from(&f.hi);
    }
    assert_eq!(got, want);
}

#[test]
fn nothing_learned_leaves_the_file_as_it_is() {
    let text = station_text();
    assert_eq!(learn(&text, &[]).1, text);
}

#[test]
fn awkward_layouts_are_rewritten_in_place() {
    // Fields out of order and over several lines, decoys in comments and strings, a
    // raw string, a block comment between a name and its value.
    let text = r####"#![enable(implicit_some)]
/* Diagnosers( components: [ ( intervals: [ (id: "I2", lo: Ms(1), hi: Ms(2)) ] ) ] ) */
Diagnosers(
    components: [
        (
            id: "t",
            signals: ["A4", "C4"],
            initial: "x0",
            initial_values: "/A4 . C4",
            states: [(id: "x0"), (id: "x1", description: "lo: Ms(7), hi: Ms(8)")],
            expected: [
                (from: "x0", event: "RE(A4)", to: "x1"),
                (from: "x1", event: "FE(C4)", within: "I2", to: "x0"),
            ],
            intervals: [
                (
                    hi: /* old: Ms(400) */ Ms(250), // hi: Ms(1)
                    description: r#"lo: Ms(9), "quoted""#,
                    after: "RE(A4)",
                    id: "I2",
                    lo:
                        Ms(50),
                ),
                (id: "I1", after: "RE(A4)", lo: Ms(0), hi: LoOf("I2")),
            ],
            faults: [],
            partitions: [],
        ),
    ],
)
"####;
    let (file, out) = learn(text, &[("I2", &[100, 110])]);
    let (lo, hi) = bounds(&file, "I2");
    let (Bound::Ms(lo), Bound::Ms(hi)) = (lo, hi) else {
        panic!("window bounds");
    };
    let expected = text
        .replacen("*/ Ms(250),", &format!("*/ Ms({hi}),"), 1)
        .replacen("        Ms(50),", &format!("        Ms({lo}),"), 1);
    assert_ne!(expected, text);
    assert_eq!(out, expected);
}

#[test]
fn a_text_that_does_not_match_the_file_is_refused() {
    let text = station_text();
    let path = Path::new("diagnosers.ron");
    let mut file = DiagnoserFile::from_ron(&text, path).unwrap();
    file.components[0].intervals.pop();
    let err = rewrite(&text, path, &file).unwrap_err();
    assert_eq!(err.code, "V0514");
    // Another file's intervals (renamed) are not written over these.
    let mut file = DiagnoserFile::from_ron(&text, path).unwrap();
    file.components[0].intervals[1].id = "I99".into();
    file.components[0].intervals[1].lo = Bound::Ms(1);
    assert_eq!(rewrite(&text, path, &file).unwrap_err().code, "V0514");
    // A text that is not a diagnoser file is its parse error.
    assert_eq!(
        rewrite("Diagnosers(", path, &file).unwrap_err().code,
        "V0001"
    );
}
