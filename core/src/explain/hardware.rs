//! Level 4, hardware before program: when the diagnosers hold a component faulty at the
//! stop (a certain fault, or a stop on the safe side between faults), the hypothesis
//! says so first, names the component and what to check on the machine, and only then
//! lists the program's suspects, which assume the plant obeyed its commands.
//!
//! The evidence is what a technician could see on the console: the diagnosers' flagged
//! partitions with their decision, never the fault a test or a trainer injected.

use super::{Explanation, Highlight, Item, Mark};
use crate::diag::codes;

/// One flagged partition of the diagnosers at the stop.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HardwareFault {
    /// When it was decided, ms.
    pub time_ms: u64,
    /// The component model (`table`).
    pub component: String,
    /// The partition (`P`, `C4`).
    pub partition: String,
    /// The fault labels with their descriptions from `diagnosers.ron` (one when
    /// certain, several when ambiguous).
    pub faults: Vec<(String, String)>,
    /// Certain (one fault), else a stop on the safe side between several.
    pub certain: bool,
    /// What to check on the machine: the partition's sensor, or its actuators.
    pub check: Vec<String>,
}

/// Puts the hardware items first in the hypothesis level (replacing earlier ones, so
/// that it can be called again when a diagnosis arrives after the stop).
pub fn add_hardware_hypothesis(ex: &mut Explanation, faults: &[HardwareFault]) {
    let level = &mut ex.hypothesis;
    let hardware =
        |code: &str| code == codes::X_HARDWARE_CERTAIN.id || code == codes::X_HARDWARE_AMBIGUOUS.id;
    level.items.retain(|i| !hardware(i.code));
    let mut items = Vec::with_capacity(faults.len() + level.items.len());
    for f in faults {
        let labels: Vec<&str> = f.faults.iter().map(|(l, _)| l.as_str()).collect();
        let described: Vec<String> = f
            .faults
            .iter()
            .map(|(l, d)| {
                if d.is_empty() {
                    l.clone()
                } else {
                    format!("{l}: {d}")
                }
            })
            .collect();
        let check = f.check.join(", ");
        let (code, text) = if f.certain {
            (
                codes::X_HARDWARE_CERTAIN,
                format!(
                    "Hardware first: the {} diagnoser found a fault with certainty at {} ms ({}). Check {check} on the machine before the program: the program suspects below assume the plant did what it was commanded.",
                    f.component,
                    f.time_ms,
                    described.join("; ")
                ),
            )
        } else {
            (
                codes::X_HARDWARE_AMBIGUOUS,
                format!(
                    "Hardware first: the {} diagnoser holds the component faulty at {} ms and cannot tell between {}. Check {check} on the machine before the program: the program suspects below assume the plant did what it was commanded.",
                    f.component,
                    f.time_ms,
                    described.join("; ")
                ),
            )
        };
        items.push(Item::new(
            code,
            text,
            &[
                ("category", "hardware".into()),
                ("component", f.component.clone()),
                ("partition", f.partition.clone()),
                ("faults", labels.join(",")),
                ("descriptions", described.join("; ")),
                ("check", check.clone()),
                ("time_ms", f.time_ms.to_string()),
            ],
        ));
        for element in &f.check {
            let h = Highlight {
                element: element.clone(),
                mark: Mark::Suspect,
            };
            if !level.highlights.contains(&h) {
                level.highlights.insert(0, h);
            }
        }
    }
    items.append(&mut level.items);
    level.items = items;
}

/// Drops the items identical to an earlier one (same code and text): a trip on several
/// terms of one constraint lists each conclusion once.
pub fn merge_identical(items: &mut Vec<Item>) {
    let mut seen = std::collections::BTreeSet::new();
    items.retain(|i| seen.insert((i.code, i.text.clone())));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(code: crate::diag::codes::Code, text: &str) -> Item {
        Item::new(code, text.into(), &[])
    }

    #[test]
    fn identical_items_are_merged_and_the_order_kept() {
        let mut items: Vec<Item> = (0..8)
            .map(|_| {
                item(
                    codes::X_EXPECTED_ACTION,
                    "Expected from the control: A4 ON.",
                )
            })
            .collect();
        items.insert(1, item(codes::X_LAST_CHANGE, "C7 rose."));
        items.push(item(
            codes::X_EXPECTED_ACTION,
            "Expected from the control: A2 OFF.",
        ));
        merge_identical(&mut items);
        let texts: Vec<&str> = items.iter().map(|i| i.text.as_str()).collect();
        assert_eq!(
            texts,
            [
                "Expected from the control: A4 ON.",
                "C7 rose.",
                "Expected from the control: A2 OFF."
            ]
        );
    }

    #[test]
    fn hardware_items_come_first_and_replace_earlier_ones() {
        let mut ex = Explanation::default();
        ex.hypothesis
            .items
            .push(item(codes::X_EXPECTED_ACTION, "A0 OFF."));
        let fault = HardwareFault {
            time_ms: 100,
            component: "table".into(),
            partition: "P".into(),
            faults: vec![("F6".into(), "table blocked".into())],
            certain: true,
            check: vec!["A4".into()],
        };
        add_hardware_hypothesis(&mut ex, std::slice::from_ref(&fault));
        add_hardware_hypothesis(
            &mut ex,
            &[
                fault.clone(),
                HardwareFault {
                    certain: false,
                    faults: vec![("M1".into(), String::new()), ("C0".into(), "beam".into())],
                    check: vec!["C0".into()],
                    ..fault
                },
            ],
        );
        let codes: Vec<&str> = ex.hypothesis.items.iter().map(|i| i.code).collect();
        assert_eq!(codes, ["X415", "X416", "X403"]);
        assert_eq!(
            ex.hypothesis.items[1].fields["descriptions"],
            "M1; C0: beam"
        );
        assert!(
            ex.hypothesis.items[0]
                .text
                .contains("Check A4 on the machine")
        );
        assert_eq!(ex.hypothesis.highlights.len(), 2);
    }
}
