use super::*;

const MM: i64 = 1_000_000;

fn pallet() -> Class {
    Class {
        name: "pallet".into(),
        length: 200 * MM,
        tags: Vec::new(),
    }
}

/// A 2 m belt of 200 mm pallets at 500 mm/s (5 mm a cycle) with an entry beam `a`
/// (input 0) at `a_mm` and an end beam `b` (input 1) at 1700 mm, fed by a pusher.
fn belt(exit: Exit, a_mm: i64) -> Belt {
    let beams = vec![(0, a_mm * MM, None), (1, 1700 * MM, None)];
    let classes = vec![pallet()];
    Belt {
        unit: "mm".into(),
        length: 2000 * MM,
        movers: Vec::new(),
        variation_ppm: 0,
        read: vec![true; beams.len()],
        points: cuts(2000 * MM, &beams, &classes),
        beams,
        motion: None,
        feed: Some(Feed {
            dnf: Vec::new(),
            places: vec![0],
            load: None,
        }),
        take: None,
        exit,
        upstream: false,
        classes,
    }
}

fn at(b: &Belt, rear_mm: i64, ahead: bool) -> Items {
    Items {
        item: Some((0, b.points.zone_of(rear_mm * MM) as u16)),
        ahead,
        carried: 0,
    }
}

const V: i64 = MM / 2;
const FEED: Ends = Ends {
    feed_rise: true,
    take_rise: false,
    load_rise: false,
};
const TAKE: Ends = Ends {
    feed_rise: false,
    take_rise: true,
    load_rise: false,
};

fn collides(out: &[(Items, Option<SubHazard>)]) -> bool {
    out.iter().any(|o| o.1 == Some(SubHazard::Collision))
}

#[test]
fn a_new_item_hits_the_last_one_while_its_rear_is_within_the_new_ones_length() {
    let b = belt(Exit::Sink, 200);
    // Rear at 0, at 100, at 200 exactly: hit (the emulator places only past 200).
    for rear in [0, 100, 200] {
        assert!(collides(&b.next(&at(&b, rear, false), 0, FEED)), "{rear}");
    }
    // Past 200: the new item is placed, the old one is now ahead.
    let out = b.next(&at(&b, 201, false), 0, FEED);
    assert!(!collides(&out));
    assert_eq!(out, vec![(at(&b, 0, true), None)]);
    // An empty belt takes it.
    let empty = Items {
        item: None,
        ahead: false,
        carried: 0,
    };
    assert_eq!(b.next(&empty, 0, FEED), vec![(at(&b, 0, false), None)]);
    // Moving backwards onto the entry during the cycle: the end of the cycle counts.
    let back = b.next(&at(&b, 202, false), -V, FEED);
    assert!(collides(&back));
}

#[test]
fn the_entry_beam_sees_the_rear_positions_a_new_item_would_hit_only_at_the_items_length() {
    // `a` at 100 mm: a pallet whose rear is in (100, 200] is not seen and still hit.
    let short = belt(Exit::Sink, 100);
    let z = at(&short, 150, false);
    let (known, _) = short.sense(&z);
    assert_eq!(known[0], (0, false));
    assert!(collides(&short.next(&z, 0, FEED)));
    // `a` at 200 mm: every rear a new item would hit is seen.
    let b = belt(Exit::Sink, 200);
    for rear in [0, 50, 150, 200] {
        let (known, _) = b.sense(&at(&b, rear, false));
        assert_eq!(known[0], (0, true), "{rear}");
    }
}

#[test]
fn beams_past_the_last_items_front_read_anything_only_when_items_may_lie_ahead() {
    let b = belt(Exit::Sink, 200);
    let (known, free) = b.sense(&at(&b, 500, false));
    assert_eq!(known, vec![(0, false), (1, false)]);
    assert!(free.is_empty());
    let (known, free) = b.sense(&at(&b, 500, true));
    assert_eq!(known, vec![(0, false)]);
    assert_eq!(free, vec![1]);
    // A beam nothing reads stays 0.
    let mut quiet = belt(Exit::Sink, 200);
    quiet.read[1] = false;
    assert!(quiet.sense(&at(&quiet, 500, true)).1.is_empty());
}

#[test]
fn at_the_exit_an_item_waits_leaves_into_a_sink_or_falls() {
    // End stop: the rear stops at 1800 mm (front at the end).
    let b = belt(Exit::Stop, 200);
    let end = at(&b, 1800, false);
    assert_eq!(b.next(&end, V, Ends::default()), vec![(end.clone(), None)]);
    // Sink: gone once its middle passes the end (rear past 1900 mm).
    let s = belt(Exit::Sink, 200);
    let out = s.next(&at(&s, 1900, true), V, Ends::default());
    assert!(out.iter().any(|o| o.0.item.is_none() && !o.0.ahead));
    assert!(out.iter().all(|o| o.1.is_none()));
    // Drop: the same move is a fall; and an item ahead may fall whenever it runs.
    let d = belt(Exit::Drop, 200);
    let out = d.next(&at(&d, 1900, false), V, Ends::default());
    assert!(out.iter().any(|o| o.1 == Some(SubHazard::Dropped)));
    let out = d.next(&at(&d, 100, true), V, Ends::default());
    assert!(out.iter().any(|o| o.1 == Some(SubHazard::Dropped)));
    assert!(
        d.next(&at(&d, 100, true), 0, Ends::default())[0]
            .1
            .is_none()
    );
    // A following belt may take it at the end, or not yet.
    let t = belt(Exit::To("next".into()), 200);
    let out = t.next(&at(&t, 1800, false), 0, Ends::default());
    assert_eq!(out.len(), 2);
    assert!(out.iter().any(|o| o.0.item.is_none()));
}

#[test]
fn the_taker_removes_the_last_item_only_within_its_reach() {
    let mut b = belt(Exit::Stop, 200);
    b.take = Some(Vec::new());
    // Front within half a length of the end: rear at 1700 mm or more.
    let out = b.next(&at(&b, 1700, false), 0, TAKE);
    assert_eq!(
        out,
        vec![(
            Items {
                item: None,
                ahead: false,
                carried: 0
            },
            None
        )]
    );
    let out = b.next(&at(&b, 1699, false), 0, TAKE);
    assert_eq!(out, vec![(at(&b, 1699, false), None)]);
    // With items ahead, the frontmost may be one of them.
    let out = b.next(&at(&b, 1700, true), 0, TAKE);
    assert_eq!(out.len(), 2);
}

#[test]
fn an_item_from_the_belt_upstream_arrives_only_when_the_entry_is_free() {
    let mut b = belt(Exit::Sink, 200);
    b.feed = None;
    b.upstream = true;
    let out = b.next(&at(&b, 150, false), 0, Ends::default());
    assert_eq!(out, vec![(at(&b, 150, false), None)]);
    let out = b.next(&at(&b, 250, false), 0, Ends::default());
    assert!(out.contains(&(at(&b, 0, true), None)));
}

#[test]
fn classes_a_belt_cannot_tell_apart_are_one() {
    let k = |class: &str, length: f64, tags: &[&str]| ItemClass {
        class: class.into(),
        length,
        tags: tags.iter().map(|t| t.to_string()).collect(),
        width: None,
        height: None,
    };
    let all = [
        k("metal", 40.0, &["metal", "tall"]),
        k("red", 40.0, &["red", "tall"]),
        k("black_low", 40.0, &[]),
        k("pallet", 200.0, &[]),
    ];
    // No beam discriminates: two lengths.
    let none = merge(all.iter(), &BTreeSet::new());
    assert_eq!(none.len(), 2);
    assert_eq!(none[0].name, "metal/red/black_low");
    // A beam that sees `tall`: the low workpiece is its own class.
    let tall = merge(all.iter(), &BTreeSet::from(["tall"]));
    assert_eq!(tall.len(), 3);
    assert_eq!(class_of(&tall, &all[2], &BTreeSet::from(["tall"])), 1);
}

#[test]
fn a_carrier_places_only_what_it_picked() {
    let mut b = belt(Exit::Sink, 200);
    b.feed.as_mut().unwrap().load = Some(Vec::new());
    let empty = Items {
        item: None,
        ahead: false,
        carried: 0,
    };
    // Holding nothing: a rise of the feeder places nothing.
    assert_eq!(b.next(&empty, 0, FEED), vec![(empty.clone(), None)]);
    // A pick loads one (or none: the other belt's end may be empty).
    let load = Ends {
        load_rise: true,
        ..Ends::default()
    };
    let out = b.next(&empty, 0, load);
    let one = Items {
        carried: 1,
        ..empty.clone()
    };
    assert_eq!(out, vec![(empty.clone(), None), (one.clone(), None)]);
    // Holding one, a second pick takes nothing more.
    assert_eq!(b.next(&one, 0, load), vec![(one.clone(), None)]);
    // Holding one: it is placed, and then it holds nothing.
    let out = b.next(&one, 0, FEED);
    assert_eq!(out, vec![(at(&b, 0, false), None)]);
    // Placed onto the one it just placed: only if it picked another in between.
    let placed = at(&b, 0, false);
    assert_eq!(b.next(&placed, 0, FEED), vec![(placed.clone(), None)]);
    let again = Items {
        carried: 1,
        ..placed
    };
    assert!(collides(&b.next(&again, 0, FEED)));
}
