//! Where the items are on the floor: the top view of a plant whose conveyors and
//! turntables are placed (`at` in `components.ron`), for the synoptic and for the
//! pictures an explanation keeps.

use super::description::{Components, Placement};
use super::items::{Body, Items};
use super::kinds::KindDef;
use crate::emulator::{BoxSize, BoxState, BoxView};
use std::collections::BTreeMap;

/// The placements and the item classes' widths.
#[derive(Clone, Debug)]
pub(crate) struct TopView {
    /// Per component, its placement.
    at: Vec<Option<Placement>>,
    /// Per component, the cosine and sine of its heading (a turntable's are of its
    /// angle, computed when it is drawn).
    axis: Vec<(f64, f64)>,
    /// Per class: its width (mm) and its size for the drawing (the first class of a
    /// source or feeder is `Small`, any other `Large`).
    classes: BTreeMap<String, (i64, BoxSize)>,
}

#[allow(clippy::cast_possible_truncation)]
fn round(v: f64) -> i64 {
    v.round() as i64
}

impl TopView {
    /// The top view of `desc`, or `None` when none of its surfaces is placed.
    pub(crate) fn new(desc: &Components) -> Option<Self> {
        let placed = desc.components.iter().any(|c| {
            c.at.is_some() && matches!(c.kind, KindDef::Conveyor(_) | KindDef::Turntable(_))
        });
        if !placed {
            return None;
        }
        let mut classes = BTreeMap::new();
        for c in &desc.components {
            let KindDef::Conveyor(v) = &c.kind else {
                continue;
            };
            let lists = v
                .source
                .iter()
                .map(|s| &s.items)
                .chain(v.feed.iter().map(|f| &f.items));
            for list in lists {
                for (i, k) in list.iter().enumerate() {
                    let size = if i == 0 {
                        BoxSize::Small
                    } else {
                        BoxSize::Large
                    };
                    classes
                        .entry(k.class.clone())
                        .or_insert((round(k.width.unwrap_or(k.length)), size));
                }
            }
        }
        Some(Self {
            axis: desc
                .components
                .iter()
                .map(|c| {
                    c.at.map_or((1.0, 0.0), |a| {
                        let h = a.heading.to_radians();
                        (h.cos(), h.sin())
                    })
                })
                .collect(),
            at: desc.components.iter().map(|c| c.at).collect(),
            classes,
        })
    }

    /// The items on placed surfaces, and those lying where they fell; `angle(k)` is
    /// component `k`'s position (a turntable's angle, degrees).
    /// Appended to `out` (what a snapshot of every cycle keeps, without allocating).
    pub(crate) fn boxes_into(
        &self,
        items: &Items,
        angle: impl Fn(usize) -> f64,
        out: &mut Vec<BoxView>,
    ) {
        let from = out.len();
        let lying = items.lying.iter().map(|b| (b, BoxState::Fallen));
        out.extend(
            items
                .bodies
                .iter()
                .map(|b| (b, BoxState::Transit))
                .chain(lying)
                .filter_map(|(b, state)| self.view(items, b, state, &angle)),
        );
        out[from..].sort_by_key(|b| b.id);
    }

    /// The turntable angle of the first placed turntable, millidegrees from +x.
    #[allow(clippy::cast_possible_truncation)]
    pub(crate) fn table_angle_mdeg(&self, items: &Items, angle: impl Fn(usize) -> f64) -> i32 {
        items
            .surfaces
            .iter()
            .filter(|s| s.rotation.is_some())
            .find_map(|s| Some((self.at[s.component]?, s.component)))
            .map_or(0, |(at, k)| {
                ((at.heading + angle(k)) * 1000.0).round() as i32
            })
    }

    #[allow(clippy::cast_possible_truncation, clippy::cast_precision_loss)]
    fn view(
        &self,
        items: &Items,
        b: &Body,
        state: BoxState,
        angle: &impl Fn(usize) -> f64,
    ) -> Option<BoxView> {
        let surface = &items.surfaces[b.surface];
        let at = self.at[surface.component]?;
        let c = b.c as f64 / 1e6;
        let (heading, along, (cos, sin)) = if surface.rotation.is_some() {
            let len = surface.len as f64 / 1e6;
            let heading = at.heading + angle(surface.component);
            let h = heading.to_radians();
            (heading, c - len / 2.0, (h.cos(), h.sin()))
        } else {
            (at.heading, c, self.axis[surface.component])
        };
        let (width, size) = self
            .classes
            .get(&b.class)
            .copied()
            .unwrap_or((2 * b.half / 1_000_000, BoxSize::Small));
        Some(BoxView {
            id: b.id,
            size,
            length_mm: round(2.0 * b.half as f64 / 1e6),
            width_mm: width,
            x_mm: (at.x + along * cos) as f32,
            y_mm: (at.y + along * sin) as f32,
            angle_mdeg: (heading * 1000.0).round() as i32,
            damaged: b.damaged,
            state,
        })
    }
}
