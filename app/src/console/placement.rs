//! Placement of the synoptic's labels and explanation tags: each beside its own
//! element, on none of the plant's symbols and on no other label, inside the picture.
//! The candidates go round the element (right, left, above, below, then the corners)
//! at a growing distance; a label moved away from its element gets a leader line.

use egui::{Pos2, Rect, Vec2, pos2, vec2};

/// The rectangles of labels of `size` for `anchor` points: the first candidate around
/// each anchor that lies in `bounds`, meets no obstacle and no label placed before, and
/// is nearer its own anchor than any of `elements` (every symbol's centre), so that it
/// reads as its element's; else the first free one; else the first in bounds.
pub(crate) fn place(
    labels: &[(Pos2, Vec2)],
    elements: &[Pos2],
    obstacles: &[Rect],
    bounds: Rect,
    gap: f32,
) -> Vec<Rect> {
    let mut placed: Vec<Rect> = Vec::with_capacity(labels.len());
    for &(p, size) in labels {
        let mut fallback = None;
        let mut free_but_ambiguous = None;
        let mut chosen = None;
        let own = |r: &Rect| {
            let d = r.distance_to_pos(p);
            elements
                .iter()
                .filter(|e| e.distance(p) > 0.5)
                .all(|e| r.distance_to_pos(*e) > d)
        };
        'rings: for k in 1..=6 {
            let d = gap * k as f32;
            let (w, h) = (size.x, size.y);
            let candidates = [
                pos2(p.x + d, p.y - h / 2.0),
                pos2(p.x - d - w, p.y - h / 2.0),
                pos2(p.x - w / 2.0, p.y - d - h),
                pos2(p.x - w / 2.0, p.y + d),
                pos2(p.x + d, p.y - d - h),
                pos2(p.x + d, p.y + d),
                pos2(p.x - d - w, p.y - d - h),
                pos2(p.x - d - w, p.y + d),
            ];
            for at in candidates {
                let r = Rect::from_min_size(at, size);
                if !bounds.contains_rect(r) {
                    continue;
                }
                fallback.get_or_insert(r);
                let free = obstacles.iter().all(|o| !o.intersects(r))
                    && placed.iter().all(|o| !o.expand(1.0).intersects(r));
                if free && own(&r) {
                    chosen = Some(r);
                    break 'rings;
                }
                if free {
                    free_but_ambiguous.get_or_insert(r);
                }
            }
        }
        placed.push(
            chosen
                .or(free_but_ambiguous)
                .or(fallback)
                .unwrap_or_else(|| Rect::from_min_size(p + vec2(gap, -size.y / 2.0), size)),
        );
    }
    placed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_close_elements_do_not_overlap_and_stay_near_their_element() {
        // Three symbols stacked closely (as A2, A4, A3 beside the table).
        let anchors = [pos2(100.0, 100.0), pos2(100.0, 118.0), pos2(100.0, 136.0)];
        let obstacles: Vec<Rect> = anchors
            .iter()
            .map(|p| Rect::from_center_size(*p, Vec2::splat(16.0)))
            .collect();
        let labels: Vec<(Pos2, Vec2)> = anchors.iter().map(|p| (*p, vec2(80.0, 16.0))).collect();
        let bounds = Rect::from_min_size(Pos2::ZERO, vec2(400.0, 300.0));
        let rects = place(&labels, &anchors, &obstacles, bounds, 12.0);
        for (i, r) in rects.iter().enumerate() {
            assert!(bounds.contains_rect(*r));
            for o in &obstacles {
                assert!(!o.intersects(*r), "label {i} on a symbol");
            }
            for (j, q) in rects.iter().enumerate().skip(i + 1) {
                assert!(!r.intersects(*q), "labels {i} and {j} overlap");
            }
            // Nearer its own element than any other.
            let d = r.distance_to_pos(anchors[i]);
            for (j, a) in anchors.iter().enumerate().filter(|(j, _)| *j != i) {
                assert!(r.distance_to_pos(*a) > d, "label {i} nearer element {j}");
            }
        }
        // The first one sits right of its element, at the first distance.
        assert_eq!(rects[0].min, pos2(112.0, 92.0));
    }

    #[test]
    fn a_label_against_the_edge_goes_to_the_other_side() {
        let bounds = Rect::from_min_size(Pos2::ZERO, vec2(200.0, 200.0));
        let r = place(
            &[(pos2(190.0, 100.0), vec2(60.0, 14.0))],
            &[],
            &[],
            bounds,
            10.0,
        );
        assert!(r[0].max.x <= 180.0 + 0.01, "{:?}", r[0]);
        assert!(bounds.contains_rect(r[0]));
    }
}
