//! Does the plant's safe state hurt it? The filter's fallback and every stop hold the
//! outputs at their safe values (`safe` in `plant.ron`); on a machine whose actuators
//! move when their output is 0 (a monostable cylinder returns, a spring-return valve
//! closes, a lift whose "down" output off means "up"), that state is a motion, and a
//! motion can end in an end stop that crashes, a declared danger, a spilled tank.
//!
//! The check runs the plant's own emulator: every component that has a position (an
//! axis, a tank) is put at each of its sensor windows' edges and middles and at both
//! ends of its travel, then left for up to two simulated minutes with every output at
//! its safe value (each combination of the `Hold` outputs, which keep whatever they
//! had); any hazard is an error (V0747) naming the component, where it started and
//! what happened.

use super::description::Components;
use super::emulator::ComponentPlant;
use super::scene::Shape;
use crate::bits::Bits;
use crate::diag::{Problem, codes};
use crate::plant::{Plant, SafeValue};
use crate::time::Millis;

/// How long the safe state is watched from each start, ms.
const WATCH_MS: u64 = 120_000;
/// At most this many `Hold` outputs are tried both ways.
const MAX_HOLD: usize = 6;

/// The hazards the safe state leads to, one problem per component and start.
pub fn check(desc: &Components, plant: &Plant) -> Vec<Problem> {
    let Ok(base) = ComponentPlant::new(desc, plant, 0) else {
        return Vec::new();
    };
    let n_out = plant.outputs.len();
    let holds: Vec<usize> = (0..n_out)
        .filter(|&k| plant.outputs[k].safe == SafeValue::Hold)
        .take(MAX_HOLD)
        .collect();
    let mut vectors = Vec::new();
    for combo in 0..(1u32 << holds.len()) {
        let mut v = Bits::zeros(n_out);
        for (k, s) in plant.outputs.iter().enumerate() {
            v.set(k, s.safe == SafeValue::One);
        }
        for (b, &k) in holds.iter().enumerate() {
            v.set(k, combo >> b & 1 == 1);
        }
        vectors.push(v);
    }
    let mut out = Vec::new();
    for e in &base.scene().elements {
        for start in starts(&e.shape) {
            let found = vectors.iter().find_map(|v| {
                let mut p = base.clone();
                p.set_position(&e.id, start);
                let end = p.now().0 + WATCH_MS;
                while p.now().0 < end && p.hazards().is_empty() {
                    p.step(Millis(10), v);
                }
                p.hazards().first().cloned().map(|h| (h, v.clone()))
            });
            if let Some((h, v)) = found {
                let on: Vec<&str> = (0..n_out)
                    .filter(|&k| v.get(k))
                    .map(|k| plant.outputs[k].id.as_str())
                    .collect();
                out.push(desc.error(
                    codes::SAFE_STATE_HAZARD.id,
                    &e.id,
                    format!(
                        "the safe state (every output at its safe value{}) drives `{}` from {start} into a hazard: {}; give the outputs that move it another `safe` value in plant.ron, or a constraint that holds it",
                        if on.is_empty() {
                            String::from(": all off")
                        } else {
                            format!(": {} on", on.join(", "))
                        },
                        e.id,
                        h.summary()
                    ),
                ));
                break;
            }
        }
    }
    out
}

/// Where to start a component: both ends of its travel, and each sensor window's edges
/// and middle.
fn starts(shape: &Shape) -> Vec<f64> {
    let (lo, hi, windows) = match shape {
        Shape::Axis {
            min, max, sensors, ..
        } => (*min, *max, sensors),
        Shape::Tank {
            capacity, sensors, ..
        } => (0.0, *capacity, sensors),
        _ => return Vec::new(),
    };
    let mut v = vec![lo, hi];
    for w in windows {
        v.extend([w.from, w.to, (w.from + w.to) / 2.0]);
    }
    v.retain(|p| p.is_finite() && *p >= lo && *p <= hi);
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::{Signal, SignalKind};
    use std::path::Path;

    /// A monostable cylinder: Y1 extends it, released it returns to 0 where its end
    /// stop crashes (a clamp closing on the operator's hand).
    const CYLINDER: &str = r#"Components(
        name: "press",
        components: [
            (id: "clamp", name: "Clamp", kind: Axis((
                min: 0.0, max: 100.0, start: 100.0, end_stops: (min: Crash),
                drives: [(when: "Y1", speed: 200.0), (when: "/Y1", speed: -200.0)],
                sensors: [(signal: "open", from: 99.0, to: 100.0)],
            ))),
        ],
    )"#;

    fn plant(safe: SafeValue) -> Plant {
        let mut y = Signal::new("Y1", SignalKind::Actuator, "Y1");
        y.safe = safe;
        Plant {
            name: "press".into(),
            description: String::new(),
            inputs: vec![Signal::new("open", SignalKind::Sensor, "open")],
            outputs: vec![y],
        }
    }

    #[test]
    fn a_monostable_actuator_whose_rest_crashes_is_found() {
        let c = Components::from_ron(CYLINDER, Path::new("components.ron")).unwrap();
        let p = check(&c, &plant(SafeValue::Zero));
        assert_eq!(p.len(), 1, "{p:?}");
        assert_eq!(p[0].code, codes::SAFE_STATE_HAZARD.id);
        assert!(
            p[0].message.contains("`clamp`") && p[0].message.contains("EndStop"),
            "{p:?}"
        );
        assert!(p[0].location.as_ref().is_some_and(|l| l.line > 1), "{p:?}");
        // Held extended (safe One), the safe state rests it against its cushion.
        assert!(check(&c, &plant(SafeValue::One)).is_empty());
        // Hold: kept at 0 it returns and crashes: found among the combinations.
        assert_eq!(check(&c, &plant(SafeValue::Hold)).len(), 1);
    }
}
