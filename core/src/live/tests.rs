use super::age::{AgedBits, Backoff, Transition, Watchdog, is_stale};
use super::config::{GatewayConfig, Mode};
use super::image::{ImageError, Raw, ServerImage, WriteOp, plan_reads, plan_writes};
use super::iomap::{Area, IoMap};
use super::stale::{StaleGuard, quantify};
use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::frame::Frame;
use crate::plant::Plant;
use crate::symbols::Space;
use crate::time::Millis;
use std::path::{Path, PathBuf};

fn station() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

fn plant() -> Plant {
    Plant::load(&station().join("plant.ron")).unwrap()
}

/// The paper's station (11 sensors at inputs 0-10, 7 actuators at coils 0-6), for the
/// tests of block planning and the served image, which count its addresses.
fn paper() -> (Plant, IoMap) {
    static PAPER: std::sync::OnceLock<(Plant, IoMap)> = std::sync::OnceLock::new();
    PAPER
        .get_or_init(|| {
            let dir = crate::test_support::paper_station("live-paper");
            let plant = Plant::load(&dir.join("plant.ron")).unwrap();
            let (map, _) = IoMap::load(&dir.join("io-map.ron"), &plant).unwrap();
            (plant, map)
        })
        .clone()
}

fn station_map() -> IoMap {
    let (map, warnings) = IoMap::load(&station().join("io-map.ron"), &plant()).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    map
}

#[test]
fn station_map_matches_the_plant_addresses() {
    let map = station_map();
    assert_eq!(map.inputs.len(), 20);
    assert_eq!(map.outputs.len(), 9);
    let from_plant = IoMap::from_plant(&plant(), 1, 10).unwrap();
    let points = |m: &IoMap| {
        m.inputs
            .iter()
            .chain(&m.outputs)
            .map(|s| s.point)
            .collect::<Vec<_>>()
    };
    assert_eq!(points(&map), points(&from_plant));
    assert_eq!(map.inputs[7].max_age, Millis(30));
    assert_eq!(
        from_plant.inputs[0].max_age,
        Millis(30),
        "default bound: three polls"
    );
}

#[track_caller]
fn check_map_error(text: &str, code: &str, line: usize) {
    let err = IoMap::from_ron(text, Path::new("m.ron"), &plant()).unwrap_err();
    let p = err
        .iter()
        .find(|p| p.code == code)
        .unwrap_or_else(|| panic!("{err:?}"));
    assert_eq!(p.location.as_ref().map(|l| l.line), Some(line), "{p}");
}

fn station_text_with(replace: &str, by: &str) -> String {
    let text = std::fs::read_to_string(station().join("io-map.ron")).unwrap();
    assert!(text.contains(replace));
    text.replacen(replace, by, 1)
}

#[test]
fn map_errors_say_where() {
    // Actuator on a read-only area.
    check_map_error(
        &station_text_with(
            "\"A4\", address: Coil(4)",
            "\"A4\", address: DiscreteInput(40)",
        ),
        "V0607",
        25,
    );
    // Two signals on one bit.
    check_map_error(
        &station_text_with(
            "\"C10\", address: DiscreteInput(10)",
            "\"C10\", address: DiscreteInput(9)",
        ),
        "V0606",
        20,
    );
    // Unknown signal.
    check_map_error(&station_text_with("\"C10\"", "\"C11\""), "V0608", 20);
    // Missing signal.
    check_map_error(
        &station_text_with("(signal: \"C10\", address: DiscreteInput(10)),", ""),
        "V0610",
        1,
    );
    // Bad RON.
    check_map_error(&station_text_with("unit: 1,", "unit: one,"), "V0001", 6);
}

#[test]
fn stale_bound_below_the_poll_is_a_warning() {
    let text = station_text_with(
        "(signal: \"C7\", address: DiscreteInput(7))",
        "(signal: \"C7\", address: DiscreteInput(7), poll_ms: Some(50))",
    );
    let (_, warnings) = IoMap::from_ron(&text, Path::new("m.ron"), &plant()).unwrap();
    assert_eq!(warnings.len(), 1);
    assert_eq!(warnings[0].code, "V0605");
}

#[test]
fn read_plan_and_decode_round_trip() {
    let (_, map) = paper();
    let inputs_only = plan_reads(&map, false, 8);
    assert_eq!(inputs_only.len(), 1);
    assert_eq!(
        (
            inputs_only[0].area,
            inputs_only[0].start,
            inputs_only[0].count
        ),
        (Area::DiscreteInput, 0, 11)
    );
    let both = plan_reads(&map, true, 8);
    assert_eq!(both.len(), 2);
    assert_eq!((both[0].area, both[0].count), (Area::DiscreteInput, 11));
    assert_eq!((both[1].area, both[1].count), (Area::Coil, 7));

    let mut inputs = AgedBits::new(11);
    let mut outputs = AgedBits::new(7);
    let di: Vec<bool> = (0..11).map(|i| i % 3 == 0).collect();
    both[0]
        .decode(Raw::Bits(&di), Millis(5), &mut inputs, &mut outputs)
        .unwrap();
    assert_eq!(inputs.values().to_bools(), di);
    assert_eq!(inputs.read_at(10), Some(Millis(5)));
    assert_eq!(outputs.read_at(0), None);
    // A short reply changes nothing.
    assert!(
        both[1]
            .decode(Raw::Bits(&[true; 3]), Millis(6), &mut inputs, &mut outputs)
            .is_err()
    );
    assert!(
        both[1]
            .decode(Raw::Words(&[0; 7]), Millis(6), &mut inputs, &mut outputs)
            .is_err()
    );
    assert_eq!(outputs.read_at(0), None);
}

#[test]
fn gaps_split_blocks_and_register_bits_decode() {
    let text = r#"IoMap(signals: [
        (signal: "C0", address: InputRegisterBit(3, 0)), (signal: "C1", address: InputRegisterBit(3, 15)),
        (signal: "C2", address: DiscreteInput(0)), (signal: "C3", address: DiscreteInput(100)),
        (signal: "C4", address: DiscreteInput(1)), (signal: "C5", address: DiscreteInput(2)),
        (signal: "C6", address: DiscreteInput(3)), (signal: "C7", address: DiscreteInput(4)),
        (signal: "C8", address: DiscreteInput(5)), (signal: "C9", address: DiscreteInput(6)),
        (signal: "C10", address: DiscreteInput(7), unit: Some(2)),
        (signal: "A0", address: HoldingRegisterBit(0, 0)), (signal: "A1", address: HoldingRegisterBit(0, 2)),
        (signal: "A2", address: Coil(0)), (signal: "A3", address: Coil(1)), (signal: "A4", address: Coil(3)),
        (signal: "A5", address: Coil(4)), (signal: "A6", address: Coil(5)),
    ])"#;
    let (map, _) = IoMap::from_ron(text, Path::new("m.ron"), &paper().0).unwrap();
    let blocks = plan_reads(&map, false, 8);
    let shape: Vec<_> = blocks
        .iter()
        .map(|b| (b.unit, b.area, b.start, b.count))
        .collect();
    assert_eq!(
        shape,
        vec![
            (1, Area::DiscreteInput, 0, 7),
            (1, Area::DiscreteInput, 100, 1),
            (1, Area::InputRegister, 3, 1),
            (2, Area::DiscreteInput, 7, 1),
        ]
    );
    let mut inputs = AgedBits::new(11);
    let mut outputs = AgedBits::new(7);
    blocks[2]
        .decode(Raw::Words(&[0x8000]), Millis(1), &mut inputs, &mut outputs)
        .unwrap();
    assert!(!inputs.values().get(0) && inputs.values().get(1));

    let writes = plan_writes(
        &map,
        &Bits::from_bools(&[true, false, true, true, false, true, true]),
    );
    assert_eq!(
        writes,
        vec![
            WriteOp::Coils {
                unit: 1,
                start: 0,
                values: vec![true, true]
            },
            WriteOp::Coils {
                unit: 1,
                start: 3,
                values: vec![false, true, true]
            },
            WriteOp::MaskRegister {
                unit: 1,
                address: 0,
                and_mask: !0b101,
                or_mask: 0b001
            },
        ]
    );
    // The same map served: register bits read and mask-write.
    let image = ServerImage::new(&map, 1);
    let mut out = Bits::zeros(7);
    image.write_registers(0, &[(0, 0b100)], &mut out).unwrap();
    assert!(!out.get(0) && out.get(1));
    image
        .write_registers(0, &[(!0b001, 0b001)], &mut out)
        .unwrap();
    assert!(out.get(0) && out.get(1), "mask write keeps the other bit");
    let words = image
        .read_registers(Area::HoldingRegister, 0, 1, &Bits::zeros(11), &out)
        .unwrap();
    assert_eq!(words, vec![0b101]);
    assert!(matches!(
        image.write_registers(1, &[(0, 1)], &mut out),
        Err(ImageError::IllegalAddress { .. })
    ));
}

#[test]
fn server_image_answers_and_refuses() {
    let (_, map) = paper();
    let image = ServerImage::new(&map, 1);
    let inputs = Bits::from_bools(&[
        true, false, false, false, false, false, false, true, false, false, true,
    ]);
    let mut outputs = Bits::zeros(7);
    assert_eq!(image.extent(Area::DiscreteInput), 11);
    assert_eq!(
        image
            .read_bits(Area::DiscreteInput, 7, 4, &inputs, &outputs)
            .unwrap(),
        vec![true, false, false, true]
    );
    assert!(matches!(
        image.read_bits(Area::DiscreteInput, 8, 4, &inputs, &outputs),
        Err(ImageError::IllegalAddress { .. })
    ));
    assert!(matches!(
        image.read_bits(Area::DiscreteInput, 0, 0, &inputs, &outputs),
        Err(ImageError::IllegalQuantity { .. })
    ));
    assert!(matches!(
        image.read_bits(Area::DiscreteInput, 0, 2001, &inputs, &outputs),
        Err(ImageError::IllegalQuantity { .. })
    ));
    assert!(matches!(
        image.read_registers(Area::HoldingRegister, 0, 1, &inputs, &outputs),
        Err(ImageError::IllegalAddress { .. })
    ));
    image
        .write_coils(4, &[true, false, true], &mut outputs)
        .unwrap();
    assert_eq!(
        outputs.to_bools(),
        vec![false, false, false, false, true, false, true]
    );
    assert_eq!(
        image
            .read_bits(Area::Coil, 0, 7, &inputs, &outputs)
            .unwrap(),
        outputs.to_bools()
    );
    // Past the last actuator: nothing written.
    assert!(image.write_coils(6, &[false, true], &mut outputs).is_err());
    assert!(outputs.get(6));
}

#[test]
fn data_age_is_stale_past_the_bound_only() {
    assert!(is_stale(None, Millis(0), Millis(100)));
    assert!(!is_stale(Some(Millis(10)), Millis(40), Millis(30)));
    assert!(is_stale(Some(Millis(10)), Millis(41), Millis(30)));
    assert!(
        !is_stale(Some(Millis(50)), Millis(40), Millis(0)),
        "a read after now is fresh"
    );
    let mut v = AgedBits::new(3);
    v.set(0, true, Millis(10));
    v.set(2, true, Millis(40));
    assert_eq!(
        v.stale(Millis(45), &[Millis(30), Millis(30), Millis(3)])
            .to_bools(),
        vec![true, true, true]
    );
    assert_eq!(
        v.stale(Millis(40), &[Millis(30), Millis(30), Millis(3)])
            .to_bools(),
        vec![false, true, false]
    );
    assert_eq!(v.age(0, Millis(45)), Some(Millis(35)));
    v.invalidate();
    assert!(v.values().get(0), "values are held");
    assert_eq!(v.read_at(0), None);
}

#[test]
fn watchdog_and_backoff() {
    let mut w = Watchdog::new(Millis(20), Millis(100));
    assert_eq!(w.check(Millis(120)), None);
    assert_eq!(
        w.check(Millis(121)),
        Some(Transition::Lost { last_heard: None })
    );
    assert_eq!(w.check(Millis(200)), None, "reported once");
    assert_eq!(w.heard(Millis(210)), Some(Transition::Restored));
    assert_eq!(w.heard(Millis(220)), None);
    assert_eq!(
        w.check(Millis(241)),
        Some(Transition::Lost {
            last_heard: Some(Millis(220))
        })
    );
    assert!(w.is_lost());

    let mut b = Backoff::new(Millis(100), Millis(500));
    let delays: Vec<u64> = (0..5).map(|_| b.failed().0).collect();
    assert_eq!(delays, vec![100, 200, 400, 500, 500]);
    b.reset();
    assert_eq!(b.failed(), Millis(100));
}

#[test]
fn a_late_runtime_does_not_blame_the_peer_but_a_silent_peer_is_lost() {
    // Heard at 100, timeout 20, grace 50 (the request timeout), hard bound 400.
    let fresh = || {
        let mut w = Watchdog::new(Millis(20), Millis(0));
        w.heard(Millis(100));
        w
    };
    // The runtime last ran at 105: whatever the cycle's clock says (up to the hard
    // bound), the silence it saw is 5 ms.
    let mut w = fresh();
    assert_eq!(
        w.check_seen(Millis(300), Millis(105), false, Millis(50), Millis(400)),
        None
    );
    assert_eq!(
        w.check_seen(Millis(300), Millis(105), true, Millis(50), Millis(400)),
        None
    );
    // A request in flight that has not failed: timeout + grace.
    let mut w = fresh();
    assert_eq!(
        w.check_seen(Millis(170), Millis(170), false, Millis(50), Millis(400)),
        None
    );
    assert!(
        w.check_seen(Millis(171), Millis(171), false, Millis(50), Millis(400))
            .is_some()
    );
    // A failed request: the timeout alone.
    let mut w = fresh();
    assert_eq!(
        w.check_seen(Millis(120), Millis(120), true, Millis(50), Millis(400)),
        None
    );
    assert_eq!(
        w.check_seen(Millis(121), Millis(121), true, Millis(50), Millis(400)),
        Some(Transition::Lost {
            last_heard: Some(Millis(100))
        })
    );
    assert_eq!(
        w.check_seen(Millis(130), Millis(130), true, Millis(50), Millis(400)),
        None,
        "once"
    );
    // A runtime starved beyond the hard bound: lost on the cycle's clock.
    let mut w = fresh();
    assert!(
        w.check_seen(Millis(501), Millis(105), false, Millis(50), Millis(400))
            .is_some()
    );
    // Exhaustive over a small grid: never lost before the timeout seen by the runtime,
    // always lost past the hard bound.
    for seen in 100..=200 {
        for now in seen..=560 {
            for failed in [false, true] {
                let mut w = fresh();
                let lost = w
                    .check_seen(Millis(now), Millis(seen), failed, Millis(50), Millis(400))
                    .is_some();
                if now - 100 > 400 {
                    assert!(lost, "now {now} seen {seen}");
                } else if seen - 100 <= 20 {
                    assert!(!lost, "now {now} seen {seen}");
                }
            }
        }
    }
}

#[test]
fn plc_endpoint_is_an_address_or_an_address_and_source_port() {
    use super::config::PlcEndpoint;
    let any = PlcEndpoint::try_from("127.0.0.2".to_string()).unwrap();
    assert!(any.matches("127.0.0.2:40000".parse().unwrap()));
    assert!(!any.matches("127.0.0.1:40000".parse().unwrap()));
    let pinned = PlcEndpoint::try_from("127.0.0.2:5020".to_string()).unwrap();
    assert!(pinned.matches("127.0.0.2:5020".parse().unwrap()));
    assert!(!pinned.matches("127.0.0.2:5021".parse().unwrap()));
    assert_eq!(pinned.to_string(), "127.0.0.2:5020");
    let err = PlcEndpoint::try_from("plc.local".to_string()).unwrap_err();
    assert!(err.contains("not a PLC endpoint"), "{err}");
}

#[test]
fn server_units_connection_caps_and_idle_timeouts_are_validated() {
    let path = std::path::Path::new("gw.ron");
    for (body, code) in [
        ("unit: 0", "V0626"),
        ("unit: 255", "V0626"),
        ("max_connections: 0", "V0627"),
        ("idle_timeout_ms: 20", "V0628"),
    ] {
        let text = format!(
            "Gateway(mode: Emulator, plant: \".\", cycle_ms: 10, link_timeout_cycles: 2,\n server: Modbus(plc: \"127.0.0.1\", {body}))"
        );
        let problems = GatewayConfig::from_ron(&text, path).unwrap_err();
        assert!(
            problems
                .iter()
                .any(|p| p.code == code && p.location.as_ref().is_some_and(|l| l.line == 2)),
            "{body}: {problems:?}"
        );
    }
    let ok = "Gateway(mode: Emulator, plant: \".\", server: Modbus(plc: \"127.0.0.2:5020\", allow: [\"127.0.0.2\"], unit: 247))";
    let c = GatewayConfig::from_ron(ok, path).unwrap();
    assert_eq!(c.modbus_server().unwrap().plc.unwrap().port, Some(5020));
}

fn bundle() -> PlantBundle {
    let (b, problems) = PlantBundle::load(&station()).unwrap();
    assert!(
        !problems.iter().any(crate::diag::Problem::is_error),
        "{problems:?}"
    );
    b
}

#[test]
fn stale_c7_holds_the_rotation() {
    // CSs10 = C7 . /A4: with C7 stale (held at 0), releasing A4 is potentially unsafe.
    let b = bundle();
    let mut guard = StaleGuard::new(&b);
    let c7 = b.plant.input("C7").unwrap();
    let a4 = b.plant.output("A4").unwrap();
    let mut frame = Frame::new(b.symbols.sizes());
    // Table in unloading position, loaded: C5 C6.
    frame
        .now_mut(Space::Input)
        .set(b.plant.input("C5").unwrap(), true);
    frame
        .now_mut(Space::Input)
        .set(b.plant.input("C6").unwrap(), true);
    frame.now_mut(Space::Output).set(a4, true);
    frame.prev[Space::Output as usize].set(a4, true); // rotated: no rising edge
    let mut stale = Bits::zeros(11);
    stale.set(c7, true);
    let v = guard.check(&frame, &stale);
    assert!(v.potentially_violated.is_empty(), "{v:?}");
    frame.now_mut(Space::Output).set(a4, false);
    let v = guard.check(&frame, &stale);
    assert!(
        v.potentially_violated.contains(&"CSs10".to_string()),
        "{v:?}"
    );
    let fallback = v.fallback.unwrap().unwrap();
    assert!(fallback.get(a4));
    // Nothing stale: the guard says nothing (the engine's filter is exact).
    assert!(
        guard
            .check(&frame, &Bits::zeros(11))
            .potentially_violated
            .is_empty()
    );
}

#[test]
fn stale_observers_follow_their_inputs() {
    let b = bundle();
    let guard = StaleGuard::new(&b);
    let deps = super::stale::observer_inputs(&b.observers, &b.symbols);
    assert_eq!(deps.len(), b.observers.defs.len());
    for (o, d) in deps.iter().enumerate() {
        assert!(
            d.count_ones() > 0,
            "observer {} reads no input",
            b.observers.defs[o].id
        );
    }
    let s = guard.stale(&Bits::zeros(11));
    assert!(s.is_empty());
    let s = guard.stale(&Bits::from_bools(&[true; 11]));
    assert_eq!(s.observers.count_ones(), deps.len());
}

/// The quantified set is exact: for every stale subset of a few inputs and every context,
/// "potentially violated" ⇔ some completion of the stale inputs violates the original set,
/// and the fallback is safe for every completion.
#[test]
fn quantification_is_exact_over_completions() {
    let b = bundle();
    let filter = crate::filter::Filter::new(&b.constraints, 7);
    let names = ["C4", "C5", "C6", "C7", "C8"];
    let idx: Vec<usize> = names.iter().map(|n| b.plant.input(n).unwrap()).collect();
    let a4 = b.plant.output("A4").unwrap();
    let a2 = b.plant.output("A2").unwrap();
    let guard = StaleGuard::new(&b);
    for stale_mask in 0u32..(1 << names.len()) {
        let mut stale = Bits::zeros(11);
        for (j, &i) in idx.iter().enumerate() {
            stale.set(i, stale_mask >> j & 1 == 1);
        }
        // Observers are quantified only when their inputs are stale; keep them out of
        // this check by zeroing them and using inputs they do not read where possible.
        let q = quantify(&b.constraints, &guard.stale(&stale));
        let qf = crate::filter::Filter::new(&q, 7);
        for ctx in 0u32..(1 << names.len()) {
            for outs in 0u32..4 {
                let mut frame = Frame::new(b.symbols.sizes());
                for (j, &i) in idx.iter().enumerate() {
                    frame.now_mut(Space::Input).set(i, ctx >> j & 1 == 1);
                }
                frame.now_mut(Space::Output).set(a4, outs & 1 == 1);
                frame.now_mut(Space::Output).set(a2, outs & 2 == 2);
                let potential = !qf.violations(&frame).is_empty();
                let mut some = false;
                let stale_idx: Vec<usize> = idx.iter().copied().filter(|&i| stale.get(i)).collect();
                for comp in 0u32..(1 << stale_idx.len()) {
                    let mut f = frame.clone();
                    for (j, &i) in stale_idx.iter().enumerate() {
                        f.now_mut(Space::Input).set(i, comp >> j & 1 == 1);
                    }
                    some |= !filter.violations(&f).is_empty();
                }
                // Observers are all 0 here and quantified when stale, so the quantified set
                // may only be more conservative than the completions of the inputs.
                assert!(
                    potential >= some,
                    "mask {stale_mask:b} ctx {ctx:b} outs {outs:b}"
                );
                if guard.stale(&stale).observers.count_ones() == 0 {
                    assert_eq!(
                        potential, some,
                        "mask {stale_mask:b} ctx {ctx:b} outs {outs:b}"
                    );
                }
                if let Ok(fb) = qf.fallback(&frame) {
                    for comp in 0u32..(1 << stale_idx.len()) {
                        let mut f = frame.clone();
                        for (j, &i) in stale_idx.iter().enumerate() {
                            f.now_mut(Space::Input).set(i, comp >> j & 1 == 1);
                        }
                        f.now_mut(Space::Output).copy_from(&fb);
                        assert!(
                            filter.violations(&f).is_empty(),
                            "fallback unsafe: mask {stale_mask:b} ctx {ctx:b}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn example_configs_load() {
    for (name, mode) in [
        ("gateway-monitor.ron", Mode::Monitor),
        ("gateway-enforce.ron", Mode::Gateway),
        ("gateway-emulator.ron", Mode::Emulator),
    ] {
        let c =
            GatewayConfig::load(&station().join(name)).unwrap_or_else(|p| panic!("{name}: {p:?}"));
        assert_eq!(c.mode, mode);
        assert_eq!(c.link_timeout(), Millis(20));
        assert!(c.io_map_path().ends_with("io-map.ron"));
        if let Some(s) = &c.server {
            assert!(s.bind().ip().is_loopback());
        }
    }
}

#[test]
fn config_errors_say_where() {
    let p = GatewayConfig::from_ron(
        "Gateway(mode: Gateway, plant: \".\",\n client: Some(Modbus(address: \"127.0.0.1:1\")))",
        Path::new("g.ron"),
    )
    .unwrap_err();
    assert_eq!(p[0].code, "V0623");
    let p = GatewayConfig::from_ron(
        "Gateway(mode: Emulator, plant: \".\",\n server: Some(Modbus(allow: [\"127.0.0.1\"], plc: Some(\"127.0.0.2\"))))",
        Path::new("g.ron"),
    )
    .unwrap_err();
    assert_eq!(
        (p[0].code, p[0].location.as_ref().unwrap().line),
        ("V0624", 2)
    );
    let p = GatewayConfig::from_ron(
        "Gateway(mode: Emulator, plant: \".\",\n cycle_priority: 0, server: Some(Modbus()))",
        Path::new("g.ron"),
    )
    .unwrap_err();
    assert_eq!(
        (p[0].code, p[0].location.as_ref().unwrap().line),
        ("V0625", 2)
    );
    // Defaults: loopback bind.
    let c = GatewayConfig::from_ron(
        "Gateway(mode: Emulator, plant: \".\", server: Some(Modbus()))",
        Path::new("g.ron"),
    )
    .unwrap();
    assert_eq!(c.server.unwrap().bind().to_string(), "127.0.0.1:1502");
}

/// The substation's feeders read each other's fault state (`def1_D2`, `def2_D1`) over
/// its FIP bus (`bus.ron`): such an input is stale once older than what the deadline
/// leaves after the bus's worst case, when that is sooner than the map's own bound. A
/// bus that leaves no room, or that delivers an unknown input, stops the link at load.
#[test]
fn a_fieldbus_bounds_the_staleness_of_the_inputs_it_delivers() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/substation");
    let plant = Plant::load(&dir.join("plant.ron")).unwrap();
    let (map, warnings) = IoMap::load(&dir.join("io-map.ron"), &plant).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let bound = |map: &IoMap, s: &str| map.inputs[plant.input(s).unwrap()].max_age;
    // Table 3.2's bus leaves 100 − 50.077 ms: 49 ms, later than the map's 30 ms.
    assert_eq!(bound(&map, "def1_D2"), Millis(30));
    let scratch = std::env::temp_dir().join(format!("vigie-bus-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).unwrap();
    let bus = |name: &str, period: u64, deadline: u64, signal: &str| {
        let path = scratch.join(name);
        std::fs::write(
            &path,
            format!(
                "Bus(bit_rate: 1000000, turnaround_us: 20, variables: [\n  (name: \"DefDep_D1\", period_us: {period}, bytes: 2, deadline_us: {deadline}, signals: [\"{signal}\"]),\n])"
            ),
        )
        .unwrap();
        path
    };
    // DefDep every 100 ms with a 120 ms deadline leaves 19 ms: the bus bounds def1_D2,
    // and a value read 20 ms ago is stale, where it was fresh on the map's bound alone.
    // (100 ms is also above Δ/r = 60 ms: warned.)
    let mut slow = map.clone();
    let w = slow
        .follow_bus(&bus("slow.ron", 100_000, 120_000, "def1_D2"), &plant)
        .unwrap();
    let codes: Vec<&str> = w.iter().map(|p| p.code).collect();
    assert_eq!(codes, [crate::diag::codes::BUS_PERIOD_DEADLINE.id], "{w:?}");
    assert_eq!(bound(&slow, "def1_D2"), Millis(19));
    assert_eq!(bound(&slow, "def2_D1"), Millis(30), "not on this bus");
    let k = plant.input("def1_D2").unwrap();
    let mut v = AgedBits::new(plant.inputs.len());
    v.set(k, true, Millis(100));
    assert!(!v.stale(Millis(120), &map.input_bounds()).get(k));
    assert!(v.stale(Millis(120), &slow.input_bounds()).get(k));
    // A bus that leaves less than 1 ms, or delivers a signal the plant does not have.
    let mut m = map.clone();
    let err = m
        .follow_bus(&bus("tight.ron", 100_000, 100_500, "def1_D2"), &plant)
        .unwrap_err();
    assert_eq!(
        err[0].code,
        crate::diag::codes::BUS_DEADLINE.id,
        "{}",
        err[0]
    );
    assert_eq!(err[0].location.as_ref().map(|l| l.line), Some(2));
    let err = m
        .follow_bus(&bus("unknown.ron", 50_000, 100_000, "defX"), &plant)
        .unwrap_err();
    assert!(err[0].message.contains("`defX`"), "{}", err[0]);
    let _ = std::fs::remove_dir_all(&scratch);
}

#[test]
fn example_opcua_configs_and_node_map_load() {
    use super::config::{ClientLink, ServerLink};
    for (name, mode) in [
        ("gateway-opcua-monitor.ron", Mode::Monitor),
        ("gateway-opcua-enforce.ron", Mode::Gateway),
        ("gateway-opcua-emulator.ron", Mode::Emulator),
    ] {
        let c =
            GatewayConfig::load(&station().join(name)).unwrap_or_else(|p| panic!("{name}: {p:?}"));
        assert_eq!(c.mode, mode);
        assert!(c.warnings.is_empty(), "{name}: {:?}", c.warnings);
        if let Some(ServerLink::OpcUa(s)) = &c.server {
            assert!(s.bind.ip().is_loopback(), "{name}");
        }
        if let Some(ClientLink::OpcUa(_)) = &c.client {
            let path = c.node_map_path().unwrap();
            let plant = crate::plant::Plant::load(&station().join("plant.ron")).unwrap();
            let (map, warnings) = super::nodemap::NodeMap::load(&path, &plant)
                .unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)));
            assert!(warnings.is_empty(), "{warnings:?}");
            assert_eq!(map.inputs.len(), plant.inputs.len());
            assert!(map.inputs.iter().all(|m| m.at.is_some()));
        }
    }
}
