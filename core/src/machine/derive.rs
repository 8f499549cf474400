//! Elementary actions derived from the components (seed 003, part II, II.3): what a
//! monitor of the plant can check without anyone writing the actions by hand.
//!
//! For an axis, every sensor window is a controlled state and every drive a command.
//! From a window, a drive moves the axis to the next window in its direction: that is
//! one elementary action (rule R1: every change of the sensors other than the
//! disappearance of the initial state is a final state, so a descent from `b1` under
//! `DPV` ends at `b2`, not `b3`). Its mean time T and tolerance ΔT follow from the
//! geometry: the axis rests anywhere in its initial window, each move's speed varies
//! by `variation_ppm`, and the axis's `tolerance_ms` is added (the sensors' response).
//! A drive that leads to no window (towards a travel end) gives no action.

/// An axis as the derivation sees it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AxisGeometry {
    /// Component id.
    pub component: String,
    /// Drives: command expression and speed, units/s.
    pub drives: Vec<(String, f64)>,
    /// Sensor windows: signal, from, to.
    pub windows: Vec<(String, f64, f64)>,
    /// Each move's speed varies within this many millionths.
    pub variation_ppm: u32,
    /// Added to every ΔT, ms.
    pub tolerance_ms: u64,
}

/// One derived action, before it gets the paper's form.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DerivedAction {
    /// `component.initial.command.final`.
    pub id: String,
    /// Component id.
    pub component: String,
    /// Initial state (a sensor).
    pub initial: String,
    /// Command (the drive's expression).
    pub command: String,
    /// Final state (a sensor).
    pub final_state: String,
    /// Mean time, ms.
    pub t_ms: u64,
    /// Tolerance, ms.
    pub dt_ms: u64,
}

/// The actions of one axis, sorted by id.
pub(crate) fn axis_actions(axis: &AxisGeometry) -> Vec<DerivedAction> {
    let var = f64::from(axis.variation_ppm) / 1e6;
    let tolerance_ms = axis.tolerance_ms;
    let mut out = Vec::new();
    for (initial, i_from, i_to) in &axis.windows {
        for (command, speed) in &axis.drives {
            let up = *speed > 0.0;
            // The nearest window beyond this one in the drive's direction.
            let next = axis
                .windows
                .iter()
                .filter(|(s, from, to)| {
                    s != initial && if up { *from > *i_to } else { *to < *i_from }
                })
                .min_by(|a, b| {
                    let key = |w: &(String, f64, f64)| if up { w.1 } else { -w.2 };
                    key(a).total_cmp(&key(b))
                });
            let Some((final_state, f_from, f_to)) = next else {
                continue;
            };
            // Distances from the farthest and the nearest rest point of the initial
            // window to the edge of the final one.
            let (near, far) = if up {
                (f_from - i_to, f_from - i_from)
            } else {
                (i_from - f_to, i_to - f_to)
            };
            let v = speed.abs() / 1000.0;
            let fastest = near / (v * (1.0 + var));
            let slowest = far / (v * (1.0 - var));
            let t = (fastest + slowest) / 2.0;
            let dt = (slowest - fastest) / 2.0;
            out.push(DerivedAction {
                id: action_id(&[&axis.component, initial, command, final_state]),
                component: axis.component.clone(),
                initial: initial.clone(),
                command: command.clone(),
                final_state: final_state.clone(),
                t_ms: t.round() as u64,
                dt_ms: dt.ceil() as u64 + tolerance_ms,
            });
        }
    }
    out.sort_by(|a, b| a.id.cmp(&b.id));
    out
}

/// A derived action's id: its parts joined by `_`, every other character than a letter
/// or a digit made `_` and runs of them one (an id is letters, digits and `_`: V1101).
fn action_id(parts: &[&str]) -> String {
    let mut id = String::new();
    for c in parts.join("_").chars() {
        let c = if c.is_alphanumeric() { c } else { '_' };
        if !(c == '_' && id.ends_with('_')) {
            id.push(c);
        }
    }
    id.trim_matches('_').to_string()
}

#[cfg(test)]
mod tests {

    #[test]
    fn a_derived_actions_id_is_letters_digits_and_underscores() {
        assert_eq!(
            action_id(&["tank1", "b1", "M1 . V1", "h1"]),
            "tank1_b1_M1_V1_h1"
        );
        assert_eq!(action_id(&["head", "h", "/Y1", "b1"]), "head_h_Y1_b1");
        assert!(
            crate::plant::is_valid_name(&action_id(&["a.b", "x", "A + /B*", "y"])),
            "{}",
            action_id(&["a.b", "x", "A + /B*", "y"])
        );
    }
    use super::*;

    fn head(variation_ppm: u32, tolerance_ms: u64) -> AxisGeometry {
        AxisGeometry {
            variation_ppm,
            tolerance_ms,
            component: "head".into(),
            drives: vec![
                ("DGV".into(), 100.0),
                ("DPV".into(), 10.0),
                ("MGV".into(), -100.0),
            ],
            windows: vec![
                ("h".into(), 0.0, 2.0),
                ("b1".into(), 98.0, 102.0),
                ("b2".into(), 148.0, 152.0),
                ("b3".into(), 198.0, 202.0),
            ],
        }
    }

    fn find<'a>(a: &'a [DerivedAction], i: &str, c: &str) -> &'a DerivedAction {
        a.iter()
            .find(|x| x.initial == i && x.command == c)
            .unwrap_or_else(|| panic!("no action from {i} under {c}: {a:?}"))
    }

    #[test]
    fn the_drilling_heads_actions_follow_rule_r1() {
        let a = axis_actions(&head(0, 0));
        // The paper's six (Fig. II.6), with their final states.
        for (i, c, f) in [
            ("h", "DGV", "b1"),
            ("b1", "DPV", "b2"),
            ("b2", "MGV", "b1"),
            ("b2", "DPV", "b3"),
            ("b3", "MGV", "b2"),
            ("b1", "MGV", "h"),
        ] {
            assert_eq!(find(&a, i, c).final_state, f);
        }
        // No action leads past the travel's last window.
        assert!(a.iter().all(|x| !(x.initial == "b3" && x.command != "MGV")));
        assert!(a.iter().all(|x| !(x.initial == "h" && x.command == "MGV")));
        // h -> b1 at 100 mm/s: 96 to 98 mm, 960 to 980 ms.
        let n1 = find(&a, "h", "DGV");
        assert_eq!((n1.t_ms, n1.dt_ms), (970, 10));
        // b1 -> b2 at 10 mm/s: 46 to 50 mm.
        let n2 = find(&a, "b1", "DPV");
        assert_eq!((n2.t_ms, n2.dt_ms), (4800, 200));
    }

    #[test]
    fn speed_variation_and_tolerance_widen_the_window() {
        let a = axis_actions(&head(10_000, 20));
        let n1 = find(&a, "h", "DGV");
        // 96 / (0.1 * 1.01) = 950.5 ms, 98 / (0.1 * 0.99) = 989.9 ms.
        assert_eq!(n1.t_ms, 970);
        assert_eq!(n1.dt_ms, 20 + 20);
    }
}
