//! The per-cycle trace: CSV with a `time_ms` column and one 0/1 column per signal, the
//! outputs being the values commanded by the control program.
//!
//! ```text
//! time_ms,C0,C1,…,C10,A0,…,A6
//! 10,0,0,…,0,1,…,1
//! ```

use crate::bits::Bits;
use crate::diag::codes;
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

/// Parses a trace for `plant`. Every plant signal must have exactly one column, and
/// the time must increase from row to row (a cycle is recorded once, in order).
pub fn parse(text: &str, file: &Path, plant: &Plant) -> Result<Vec<TraceRow>, Problem> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((header_index, header)) = lines.next() else {
        return Err(Problem::error(
            codes::TRACE_EMPTY.id,
            "empty trace: expected a header `time_ms,<signals>`",
            Some(Location::new(file, 1, 1)),
        ));
    };
    let header_line = header_index + 1;
    let columns = parse_header(header, header_line, file, plant)?;
    let mut rows: Vec<TraceRow> = Vec::new();
    // The line of the previous row, for the time check.
    let mut previous_line = 0;
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
                codes::TRACE_ROW_WIDTH.id,
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
                            codes::TRACE_TIME_INVALID.id,
                            format!("`{v}` is not a time in milliseconds"),
                            Some(Location::new(file, line_no, col)),
                        )
                    })?);
                    if let Some(prev) = rows.last()
                        && row.time <= prev.time
                    {
                        let how = if row.time == prev.time {
                            "repeats"
                        } else {
                            "goes backwards from"
                        };
                        return Err(Problem::error(
                            codes::TRACE_TIME_BACKWARDS.id,
                            format!(
                                "time {} ms {how} {} ms on line {previous_line}: the time of a trace must increase",
                                row.time.0, prev.time.0
                            ),
                            Some(Location::new(file, line_no, col)),
                        ));
                    }
                }
                Some((out, idx)) => {
                    let b = match v {
                        "0" => false,
                        "1" => true,
                        _ => {
                            return Err(Problem::error(
                                codes::TRACE_VALUE_INVALID.id,
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
        previous_line = line_no;
    }
    Ok(rows)
}

/// The columns of the trace header: `(is_output, index)` of each signal, None for the
/// time; every plant signal must have exactly one.
fn parse_header(
    header: &str,
    header_line: usize,
    file: &Path,
    plant: &Plant,
) -> Result<Vec<Option<(bool, usize)>>, Problem> {
    // column → (is_output, index); None for time.
    let mut columns: Vec<Option<(bool, usize)>> = Vec::new();
    // Name → column number (1-based character position of its cell).
    let mut names: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
    let mut has_time = false;
    let mut col = 1;
    for cell in header.split(',') {
        let name = cell.trim();
        if let Some(first) = names.insert(name, col) {
            return Err(Problem::error(
                codes::TRACE_DUPLICATE_COLUMN.id,
                format!(
                    "column `{name}` appears twice in the trace header (first at column {first})"
                ),
                Some(Location::new(file, header_line, col)),
            ));
        }
        if name == "time_ms" {
            has_time = true;
            columns.push(None);
        } else if let Some(i) = plant.input(name) {
            columns.push(Some((false, i)));
        } else if let Some(k) = plant.output(name) {
            columns.push(Some((true, k)));
        } else {
            return Err(Problem::error(
                codes::TRACE_UNKNOWN_SIGNAL.id,
                format!("unknown signal `{name}` in trace header"),
                Some(Location::new(file, header_line, col)),
            ));
        }
        col += cell.chars().count() + 1;
    }
    if !has_time {
        return Err(Problem::error(
            codes::TRACE_NO_TIME_COLUMN.id,
            "trace header has no `time_ms` column",
            Some(Location::new(file, header_line, 1)),
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
                codes::TRACE_MISSING_SIGNAL.id,
                format!("trace has no column for signal `{}`", s.id),
                Some(Location::new(file, header_line, 1)),
            ));
        }
    }
    Ok(columns)
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

#[cfg(test)]
mod tests;
