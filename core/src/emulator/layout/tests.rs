use super::*;

fn station_text() -> String {
    std::fs::read_to_string(crate::test_support::station_layout_file()).unwrap()
}

/// `line:col` just after the first occurrence of `needle` in `text`.
fn after(text: &str, needle: &str) -> String {
    let start = text.find(needle).unwrap() + needle.len();
    let line = text[..start].matches('\n').count() + 1;
    let from = text[..start].rfind('\n').map_or(0, |n| n + 1);
    format!("{line}:{}", text[from..start].chars().count() + 1)
}

fn problems(text: &str) -> Vec<String> {
    match Layout::from_ron(text, Path::new("layout.ron")) {
        Ok(_) => Vec::new(),
        Err(p) => p
            .iter()
            .map(|p| p.to_string().trim_start_matches("layout.ron:").to_string())
            .collect(),
    }
}

#[test]
fn the_station_layout_passes() {
    assert_eq!(problems(&station_text()), Vec::<String>::new());
}

#[test]
fn a_zero_or_absurd_period_or_step_is_reported_at_its_value() {
    let text = station_text()
        .replacen("period_ms: 8000", "period_ms: 0", 1)
        .replacen("jitter_ms: 1000", "jitter_ms: 99999999999", 1)
        .replacen("step_ms: 1,", "step_ms: 0,", 1);
    assert_eq!(
        problems(&text),
        [
            format!(
                "{}: error[V0701]: step_ms is 0 ms: the simulation step is from 1 to 1000 ms",
                after(&text, "step_ms: ")
            ),
            format!(
                "{}: error[V0701]: period_ms is 0 ms: an arrival period is from 1 ms to 604800000 ms",
                after(&text, "period_ms: ")
            ),
            format!(
                "{}: error[V0701]: jitter_ms is 99999999999 ms: at most 604800000 ms",
                after(&text, "jitter_ms: ")
            ),
        ]
    );
    let text = station_text().replacen("step_ms: 1,", "step_ms: 60000,", 1);
    assert_eq!(
        problems(&text),
        [format!(
            "{}: error[V0701]: step_ms is 60000 ms: the simulation step is from 1 to 1000 ms",
            after(&text, "step_ms: ")
        )]
    );
}

#[test]
fn bad_box_dimensions_are_reported_at_the_box() {
    let text = station_text();
    let large = text.find("large:").unwrap();
    let (head, tail) = text.split_at(large);
    let text = format!("{head}{}", tail.replacen("height_mm: ", "height_mm: -", 1));
    assert_eq!(
        problems(&text),
        [format!(
            "{}: error[V0701]: large box dimensions must be positive",
            after(&text, "large: ")
        )]
    );
}

#[test]
fn a_name_quoted_in_a_comment_is_not_where_the_file_declares_it() {
    let text = "// the bus `\"bus_d1\"` is slowed by a scenario\n(id: \"bus_d1\", s: \"a // b\")\n";
    let map = super::quoted_positions(text);
    assert_eq!(map.get("bus_d1"), Some(&(2, 7)));
    assert_eq!(map.get("a // b"), Some(&(2, 20)), "{map:?}");
}

/// The station's `components.ron`, placed on the floor, derives the very layout its
/// first emulator ran: every part, sensor, speed and angle (the sensors listed in the
/// components' order, and the high beam between the two classes' heights where the
/// layout gave it as 250 mm: both see the tall class only).
#[test]
fn the_station_components_derive_its_layout() {
    let fixture = Layout::load(&crate::test_support::station_layout_file()).unwrap();
    let mut derived = crate::test_support::station_layout();
    assert_eq!(derived.high_beam_mm, 260);
    assert!(
        (fixture.source.small.height_mm..fixture.source.large.height_mm)
            .contains(&derived.high_beam_mm)
    );
    derived.high_beam_mm = fixture.high_beam_mm;
    derived
        .sensors
        .sort_by_key(|s| fixture.sensors.iter().position(|f| f.id == s.id));
    derived.file.clone_from(&fixture.file);
    derived.positions.clone_from(&fixture.positions);
    assert_eq!(derived, fixture);
}

/// A plant that is not a turntable cell derives none: the drilling station (an axis),
/// the station with a third table position or without placements.
#[test]
fn only_a_placed_turntable_cell_derives_a_layout() {
    use crate::machine::Components;
    let dir = crate::test_support::station_dir();
    let text = std::fs::read_to_string(dir.join("components.ron")).unwrap();
    let load = |t: &str| Components::from_ron(t, Path::new("components.ron")).unwrap();
    assert!(Layout::from_components(&load(&text)).is_some());
    let unplaced = text.replacen("at: Some((x: 1200.0, y: 0.0, width: 450.0)), ", "", 1);
    assert_ne!(unplaced, text);
    assert!(Layout::from_components(&load(&unplaced)).is_none());
    let third = text.replacen(
        "(at: 90.0, when: \"A4\"",
        "(at: 180.0, when: \"A4*A5\", joins: []),\n(at: 90.0, when: \"A4\"",
        1,
    );
    assert_ne!(third, text);
    assert!(Layout::from_components(&load(&third)).is_none());
    let drilling = Components::load(&dir.join("../drilling-station/components.ron")).unwrap();
    assert!(Layout::from_components(&drilling).is_none());
    // Each says why.
    let why = |c: &Components| Layout::cell_of(c).err().unwrap_or_default();
    assert_eq!(
        why(&load(&unplaced)),
        "conveyor `intermediate` is not placed (`at`)"
    );
    assert!(why(&load(&third)).starts_with("turntable `table` is not a cell's: two positions"));
    assert!(
        why(&drilling).contains("is not part of a turntable cell"),
        "{}",
        why(&drilling)
    );
    let one_class = text.replacen(
        "(class: \"large\", length: 380.0, width: Some(380.0), height: Some(320.0), tags: [\"tall\"]),",
        "",
        1,
    );
    assert_ne!(one_class, text);
    assert!(why(&load(&one_class)).starts_with("the source must place two classes"));
}

/// A legacy layout read as components (`Layout::to_components`) derives the layout
/// back, field by field (the same two asides as above), and passes every check of a
/// components file.
#[test]
fn a_layout_read_as_components_derives_itself_back() {
    let fixture = Layout::load(&crate::test_support::station_layout_file()).unwrap();
    let converted = fixture
        .to_components()
        .expect("the station's layout converts");
    let mut back = Layout::from_components(&converted).expect("a turntable cell");
    assert!(
        (fixture.source.small.height_mm..fixture.source.large.height_mm)
            .contains(&back.high_beam_mm)
    );
    back.high_beam_mm = fixture.high_beam_mm;
    back.sensors
        .sort_by_key(|s| fixture.sensors.iter().position(|f| f.id == s.id));
    back.positions.clone_from(&fixture.positions);
    assert_eq!(back, fixture);
    // Its messages point into the layout file, where the layout's own do.
    assert_eq!(
        converted.location_of("C3"),
        fixture.location_of("C3").expect("located")
    );
}

/// What the layout said by geometry: a conveyor whose end meets nothing drops its
/// items; an explicit arrival list has no place in a description and is refused with
/// where it is written.
#[test]
fn a_layout_read_as_components_keeps_its_geometry_and_refuses_an_arrival_list() {
    use crate::machine::kinds::KindDef;
    use crate::machine::kinds::conveyor::Exit;
    let text = station_text();
    // The entry conveyor moved 100 mm up: its end meets nothing any more.
    let moved = text.replacen(
        "start: (x: 0, y: 0), end: (x: 1200, y: 0)",
        "start: (x: 0, y: 100), end: (x: 1200, y: 100)",
        1,
    );
    assert_ne!(moved, text, "the fixture's entry conveyor");
    let layout = Layout::from_ron(&moved, Path::new("layout.ron")).expect("loads");
    let c = layout.to_components().expect("converts");
    let exit = |id: &str| {
        c.components
            .iter()
            .find(|k| k.id == id)
            .and_then(|k| match &k.kind {
                KindDef::Conveyor(v) => Some(v.exit.clone()),
                _ => None,
            })
    };
    assert_eq!(exit("entry"), Some(Exit::Drop));
    assert_eq!(exit("intermediate"), Some(Exit::To("table".into())));
    assert_eq!(exit("left_exit"), Some(Exit::Sink));
    let mut layout = Layout::from_ron(&text, Path::new("layout.ron")).expect("loads");
    layout.source.arrivals = ArrivalPlan::List(vec![(0, BoxSize::Small)]);
    let p = layout.to_components().expect_err("a list is refused");
    assert!(
        p[0].to_string().contains("move it to the scenarios"),
        "{}",
        p[0]
    );
}
