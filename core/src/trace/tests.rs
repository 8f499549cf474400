use super::*;
use crate::test_support::station;

fn plant() -> Plant {
    station().plant
}

/// A header and rows of 0s for the station, with `edit` applied to the text.
fn trace_text(rows: usize) -> String {
    let p = plant();
    let mut text = header(&p);
    text.push('\n');
    for i in 0..rows {
        write_row(
            &mut text,
            Millis(10 * (i as u64 + 1)),
            &Bits::zeros(p.inputs.len()),
            &Bits::zeros(p.outputs.len()),
        );
    }
    text
}

#[track_caller]
fn check_error(text: &str, expected: &str) {
    match parse(text, Path::new("t.csv"), &plant()) {
        Ok(rows) => panic!("expected {expected}, parsed {} rows", rows.len()),
        Err(p) => assert_eq!(p.to_string(), expected),
    }
}

#[test]
fn header_lists_time_then_sensors_then_actuators() {
    assert_eq!(
        header(&plant()),
        "time_ms,C0,C1,C2,C3,C4,C5,C6,C7,C8,C9,C10,A0_fb,A1_fb,A2_fb,A3_fb,A4_fb,A5_fb,A6_fb,KM0_fb,YV0_fb,A0,A1,A2,A3,A4,A5,A6,KM0,YV0"
    );
}

#[test]
fn round_trip() {
    let p = plant();
    let mut text = header(&p);
    text.push('\n');
    let mut rows = Vec::new();
    let mut rng = crate::synthetic::SplitMix64::new(4);
    for i in 0..50u64 {
        let inputs = Bits::from_bools(
            &(0..p.inputs.len())
                .map(|_| rng.chance(1, 2))
                .collect::<Vec<_>>(),
        );
        let outputs = Bits::from_bools(
            &(0..p.outputs.len())
                .map(|_| rng.chance(1, 2))
                .collect::<Vec<_>>(),
        );
        write_row(&mut text, Millis(i * 7), &inputs, &outputs);
        rows.push(TraceRow {
            time: Millis(i * 7),
            inputs,
            outputs,
        });
    }
    assert_eq!(parse(&text, Path::new("t.csv"), &p).unwrap(), rows);
    // Columns in another order, spaces and blank lines are accepted.
    let text = "YV0,KM0,A6, A5,A4,A3,A2,A1,A0,YV0_fb,KM0_fb,A6_fb,A5_fb,A4_fb,A3_fb,A2_fb,A1_fb,A0_fb,C10,C9,C8,C7,C6,C5,C4,C3,C2,C1,C0,time_ms\n\n0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0, 1 ,5\n";
    let rows = parse(text, Path::new("t.csv"), &p).unwrap();
    assert_eq!(rows.len(), 1);
    assert_eq!(
        (
            rows[0].time,
            rows[0].inputs.to_string(),
            rows[0].outputs.to_string()
        ),
        (Millis(5), "10000000000000000000".into(), "000000100".into())
    );
}

#[test]
fn errors_have_line_and_column() {
    let good = trace_text(2);
    // Bad value: row 3 (line 3), column of the 5th cell (C3).
    let bad = good.replacen("20,0,0,0,0", "20,0,0,0,x", 1);
    check_error(&bad, "t.csv:3:10: error[V0307]: `x` is not 0 or 1");
    check_error(
        &good.replacen("20,", "2O,", 1),
        "t.csv:3:1: error[V0306]: `2O` is not a time in milliseconds",
    );
    check_error(
        &good.replacen("20,0,", "20,", 1),
        "t.csv:3:1: error[V0305]: expected 30 values, found 29",
    );
    check_error(
        &good.replacen("\n10,", "\n\n10,0,", 1),
        "t.csv:3:1: error[V0305]: expected 30 values, found 31",
    );
    // Header problems.
    check_error(
        &good.replacen(",C3,", ",X3,", 1),
        "t.csv:1:18: error[V0302]: unknown signal `X3` in trace header",
    );
    // Columns count the spaces around names.
    check_error(
        "time_ms, C0,  X\n",
        "t.csv:1:13: error[V0302]: unknown signal `X` in trace header",
    );
    check_error(
        &good.replacen(",C1,", ",", 1),
        "t.csv:1:1: error[V0304]: trace has no column for signal `C1`",
    );
    check_error(
        &good.replacen("time_ms", "time", 1),
        "t.csv:1:1: error[V0302]: unknown signal `time` in trace header",
    );
    check_error(
        "C0,C1\n",
        "t.csv:1:1: error[V0303]: trace header has no `time_ms` column",
    );
    check_error(
        "\n  \n",
        "t.csv:1:1: error[V0301]: empty trace: expected a header `time_ms,<signals>`",
    );
}

#[test]
fn time_that_goes_backwards_or_repeats_is_an_error_at_its_cell() {
    // Rows at 10, 20, 30 ms on lines 2, 3, 4.
    let good = trace_text(3);
    assert_eq!(parse(&good, Path::new("t.csv"), &plant()).unwrap().len(), 3);
    check_error(
        &good.replacen("\n30,", "\n5,", 1),
        "t.csv:4:1: error[V0331]: time 5 ms goes backwards from 20 ms on line 3: the time of a trace must increase",
    );
    check_error(
        &good.replacen("\n30,", "\n20,", 1),
        "t.csv:4:1: error[V0331]: time 20 ms repeats 20 ms on line 3: the time of a trace must increase",
    );
    // Blank lines do not count as rows, but lines are the file's.
    check_error(
        &good.replacen("\n20,", "\n\n\n10,", 1),
        "t.csv:5:1: error[V0331]: time 10 ms repeats 10 ms on line 2: the time of a trace must increase",
    );
    // The time column anywhere: its own column is reported.
    let p = plant();
    let names: Vec<&str> = p
        .inputs
        .iter()
        .chain(&p.outputs)
        .map(|s| s.id.as_str())
        .collect();
    let zeros = vec!["0"; names.len()].join(",");
    let text = format!("{},time_ms\n{zeros},7\n{zeros},3\n", names.join(","));
    check_error(
        &text,
        &format!(
            "t.csv:3:{}: error[V0331]: time 3 ms goes backwards from 7 ms on line 2: the time of a trace must increase",
            zeros.len() + 2
        ),
    );
}

#[test]
fn a_repeated_column_is_an_error_at_its_header_cell() {
    let good = trace_text(1);
    // `C3` twice: the second one is at column 21 (where `C4` was).
    check_error(
        &good.replacen(",C4,", ",C3,", 1),
        "t.csv:1:21: error[V0330]: column `C3` appears twice in the trace header (first at column 18)",
    );
    // A second time column, and a name repeated with spaces around it.
    check_error(
        &good.replacen(",YV0\n", ",time_ms\n", 1),
        "t.csv:1:124: error[V0330]: column `time_ms` appears twice in the trace header (first at column 1)",
    );
    check_error(
        &good.replacen(",A0,", ", A1 ,", 1),
        "t.csv:1:104: error[V0330]: column `A1` appears twice in the trace header (first at column 99)",
    );
}

#[test]
fn header_problems_are_reported_on_the_header_line() {
    // Blank lines and a byte-order mark before the header: the line is the header's.
    let good = trace_text(1);
    check_error(
        &format!("\n \n{}", good.replacen(",C3,", ",X3,", 1)),
        "t.csv:3:18: error[V0302]: unknown signal `X3` in trace header",
    );
    check_error(
        &format!("\n\n{}", good.replacen(",C1,", ",", 1)),
        "t.csv:3:1: error[V0304]: trace has no column for signal `C1`",
    );
    check_error(
        "\n\u{feff}C0,C1\n",
        "t.csv:2:1: error[V0302]: unknown signal `\u{feff}C0` in trace header",
    );
    let bom = format!("\u{feff}{good}");
    assert_eq!(parse(&bom, Path::new("t.csv"), &plant()).unwrap().len(), 1);
}
