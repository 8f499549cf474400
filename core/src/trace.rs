//! The per-cycle trace: CSV with a `time_ms` column and one 0/1 column per signal, the
//! outputs being the values commanded by the control program.
//!
//! ```text
//! time_ms,C0,C1,…,C10,A0,…,A6
//! 10,0,0,…,0,1,…,1
//! ```

use crate::bits::Bits;
use crate::diag::{Location, Problem};
use crate::plant::Plant;
use crate::time::Millis;
use std::fmt::Write as _;
use std::path::Path;

/// One row of a trace.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TraceRow {
    /// Time of the cycle.
    pub time: Millis,
    /// Sensor values, by input number.
    pub inputs: Bits,
    /// Commanded actuator values, by output number.
    pub outputs: Bits,
}

/// Parses a trace for `plant`. Every plant signal must have a column.
pub fn parse(text: &str, file: &Path, plant: &Plant) -> Result<Vec<TraceRow>, Problem> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(Problem::error(
            "V0301",
            "empty trace: expected a header `time_ms,<signals>`",
            Some(Location::new(file, 1, 1)),
        ));
    };
    // column → (is_output, index); None for time.
    let mut columns: Vec<Option<(bool, usize)>> = Vec::new();
    let mut has_time = false;
    let mut col = 1;
    for name in header.split(',') {
        let name = name.trim();
        if name == "time_ms" {
            has_time = true;
            columns.push(None);
        } else if let Some(i) = plant.input(name) {
            columns.push(Some((false, i)));
        } else if let Some(k) = plant.output(name) {
            columns.push(Some((true, k)));
        } else {
            return Err(Problem::error(
                "V0302",
                format!("unknown signal `{name}` in trace header"),
                Some(Location::new(file, 1, col)),
            ));
        }
        col += name.chars().count() + 1;
    }
    if !has_time {
        return Err(Problem::error(
            "V0303",
            "trace header has no `time_ms` column",
            Some(Location::new(file, 1, 1)),
        ));
    }
    for s in plant.inputs.iter().chain(&plant.outputs) {
        let present = columns.iter().flatten().any(|&(out, i)| {
            if out {
                plant.outputs[i].id == s.id
            } else {
                plant.inputs[i].id == s.id
            }
        });
        if !present {
            return Err(Problem::error(
                "V0304",
                format!("trace has no column for signal `{}`", s.id),
                Some(Location::new(file, 1, 1)),
            ));
        }
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let line_no = i + 1;
        let mut row = TraceRow {
            time: Millis::ZERO,
            inputs: Bits::zeros(plant.inputs.len()),
            outputs: Bits::zeros(plant.outputs.len()),
        };
        let mut col = 1;
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != columns.len() {
            return Err(Problem::error(
                "V0305",
                format!("expected {} values, found {}", columns.len(), cells.len()),
                Some(Location::new(file, line_no, 1)),
            ));
        }
        for (cell, column) in cells.iter().zip(&columns) {
            let v = cell.trim();
            match column {
                None => {
                    row.time = Millis(v.parse().map_err(|_| {
                        Problem::error(
                            "V0306",
                            format!("`{v}` is not a time in milliseconds"),
                            Some(Location::new(file, line_no, col)),
                        )
                    })?);
                }
                Some((out, idx)) => {
                    let b = match v {
                        "0" => false,
                        "1" => true,
                        _ => {
                            return Err(Problem::error(
                                "V0307",
                                format!("`{v}` is not 0 or 1"),
                                Some(Location::new(file, line_no, col)),
                            ));
                        }
                    };
                    if *out {
                        row.outputs.set(*idx, b);
                    } else {
                        row.inputs.set(*idx, b);
                    }
                }
            }
            col += cell.chars().count() + 1;
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The header line for `plant` (no newline).
pub fn header(plant: &Plant) -> String {
    let mut s = String::from("time_ms");
    for sig in plant.inputs.iter().chain(&plant.outputs) {
        s.push(',');
        s.push_str(&sig.id);
    }
    s
}

/// Appends one row (with newline) to `out`.
pub fn write_row(out: &mut String, time: Millis, inputs: &Bits, outputs: &Bits) {
    let _ = write!(out, "{}", time.0);
    for i in 0..inputs.len() {
        out.push_str(if inputs.get(i) { ",1" } else { ",0" });
    }
    for k in 0..outputs.len() {
        out.push_str(if outputs.get(k) { ",1" } else { ",0" });
    }
    out.push('\n');
}
