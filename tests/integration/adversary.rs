//! Adversarial tests of the gateway's live link: a fake plant written here
//! (`fake_plant.rs`: a hand-parsed Modbus TCP device whose misbehaviour is switched at
//! run time, recording every write it receives) and raw clients that send what no
//! well-behaved PLC would. Every test asserts on what the plant received and when, not
//! only on the gateway's events.
//!
//! The guarantees under test:
//! 1. after the plant misbehaves or reconnects, the safe outputs are written first and
//!    a failed read never prevents the next write: whenever a `safe_outputs` event says
//!    X, the plant receives a write of X within [`BOUND`] of it (every bad mode but
//!    the one where the plant receives no bytes at all);
//! 2. the PLC is the configured endpoint, its liveness its own writes; nobody else's
//!    write, and no write to another unit, reaches the plant;
//! 3. a connection flood or descriptor exhaustion does not stop the PLC's session, and
//!    the server recovers; idle connections are closed;
//! 4. a gateway whose stdout and stderr nobody reads keeps filtering;
//! 5. a trip latched before a `kill -9` is restored and enforced after the restart.
//!
//! Waits poll a condition with a deadline; the pauses of the series (a pseudo-random
//! moment, from a seeded SplitMix64; `VIGIE_ADVERSARY_SEED=0x…` replays another seed)
//! choose when something happens, they synchronise nothing.

#![allow(clippy::unwrap_used)] // a failure is a test failure

mod fake_plant;
mod rig;

use crate::live::wait_until;
use fake_plant::{FakePlant, Mode};
use rig::{Cfg, RawClient, Rig, Spawn, WAIT, from_ip, write_coil_on, write_coils};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Link timeout (10 cycles of 10 ms) + request timeout (50 ms) + a margin: how soon a
/// safe output must reach the plant once a `safe_outputs` event announced it.
const BOUND: Duration = Duration::from_millis(300);
/// How soon the plant must receive the (filtered) outputs of a new PLC command.
const FOLLOW: Duration = Duration::from_secs(1);
/// The link timeout of the configuration (10 cycles of 10 ms).
const LINK_TIMEOUT: Duration = Duration::from_millis(100);

/// The PLC's command in most tests: A0 A1 (allowed while C0 = 0) and A5 A6 (in no
/// constraint), so that it differs from any safe fallback.
const COMMAND: &str = "1100011";
/// With C0 = 1, CSc1 = C0 . A0 . /A1 trips on this command; the filter clears A0.
const FORBIDDEN: &str = "1000000";
/// With C0 = 1, allowed (A1 takes the box).
const ALLOWED: &str = "1100000";
/// The sensor at the end of the entry conveyor.
const C0: usize = 0;

/// A tiny seeded generator (SplitMix64).
pub(crate) struct SplitMix64(pub(crate) u64);

impl SplitMix64 {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform enough in `0..n`.
    pub(crate) fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// The seed of a series: `VIGIE_ADVERSARY_SEED` (hexadecimal) or `default`.
fn seed(default: u64) -> u64 {
    std::env::var("VIGIE_ADVERSARY_SEED")
        .ok()
        .and_then(|s| u64::from_str_radix(s.trim_start_matches("0x"), 16).ok())
        .unwrap_or(default)
}

fn alarm(key: &'static str) -> impl Fn(&serde_json::Value) -> bool {
    move |e| e["event"] == "alarm" && e["key"] == key
}

fn kind(kind: &'static str) -> impl Fn(&serde_json::Value) -> bool {
    move |e| e["event"] == kind
}

/// A `trip` (or `trip_restored`) event whose record names constraint `id`.
fn record_names(kind: &'static str, id: &'static str) -> impl Fn(&serde_json::Value) -> bool {
    move |e| {
        e["event"] == kind
            && e["record"]["constraints"]
                .as_array()
                .is_some_and(|c| c.iter().any(|c| c["id"] == id))
    }
}

// ---------------------------------------------------------------------------------
// The fake plant itself.

#[test]
fn the_fake_plant_misbehaves_as_each_mode_says() {
    let plant = FakePlant::start(7);
    plant.set_sensor(0, true);
    plant.set_sensor(10, true);
    // Answers that must come get 2 s (a loaded machine); answers that must not, 300 ms.
    let connect = |within: Duration| {
        RawClient::connect(plant.addr(), from_ip([127, 0, 0, 1]))
            .unwrap()
            .answer_within(within)
    };
    let (must, must_not) = (Duration::from_secs(2), Duration::from_millis(300));
    let sensors = vec![2, 2, 0b0000_0001, 0b0000_0100];
    let ack = vec![15, 0, 0, 0, 7];
    let t = Instant::now();
    let mut c = connect(must);
    assert_eq!(c.request(1, &rig::READ_SENSORS).unwrap(), sensors);
    assert_eq!(c.request(1, &write_coils("0100011")).unwrap(), ack);
    assert_eq!(c.request(1, &write_coil_on(0)).unwrap(), write_coil_on(0));
    let coils: Vec<(String, bool)> = plant
        .writes_since(t)
        .into_iter()
        .map(|w| (w.coils, w.answered))
        .collect();
    assert_eq!(
        coils,
        [("0100011".to_string(), true), ("1100011".to_string(), true)]
    );
    for mode in Mode::BAD {
        plant.set_mode(mode);
        let since = Instant::now();
        // A read on one connection, a write of 0000001 on another.
        let answered = mode.answers_writes();
        let read = match mode {
            Mode::ExceptionToReads => connect(must),
            _ => connect(must_not),
        }
        .request(1, &rig::READ_SENSORS);
        let write =
            connect(if answered { must } else { must_not }).request(1, &write_coils("0000001"));
        match mode {
            Mode::Slow(_) => assert!(read.is_err(), "{mode:?}: answered in 300 ms: {read:?}"),
            Mode::ExceptionToReads => assert_eq!(read.unwrap(), [0x82, 0x04]),
            _ => assert!(
                read.as_ref().is_err() || read.as_ref().unwrap() != &sensors,
                "{mode:?}: the read was answered correctly"
            ),
        }
        if mode == Mode::CloseOnAccept {
            let writes = plant.writes_since(since);
            assert!(
                write.is_err() && writes.is_empty(),
                "{mode:?}: {write:?} {writes:?}"
            );
            continue;
        }
        wait_until("the plant to record the write", || {
            !plant.writes_since(since).is_empty()
        });
        let writes = plant.writes_since(since);
        assert_eq!(write.is_ok(), answered, "{mode:?}: the write got {write:?}");
        assert!(
            writes.len() == 1 && writes[0].coils == "0000001" && writes[0].answered == answered,
            "{mode:?}: the plant recorded {writes:?}"
        );
    }
    // A slow plant does answer its reads, late.
    plant.set_mode(Mode::Slow(fake_plant::SLOW));
    let asked = Instant::now();
    let mut c = connect(must);
    assert_eq!(c.request(1, &rig::READ_SENSORS).unwrap(), sensors);
    assert!(asked.elapsed() >= fake_plant::SLOW);
    // Every connection was recorded with its first request.
    let conns = plant.conns_since(t);
    assert!(conns.len() > 2 * Mode::BAD.len(), "{conns:?}");
    assert_eq!(conns[0].first, Some((2, None)));
}

// ---------------------------------------------------------------------------------
// 1. A misbehaving plant still receives the safe outputs.

/// A plant following the PLC's [`COMMAND`].
fn misbehaviour_rig(seed: u64) -> Rig {
    Rig::start(Cfg {
        command: Some(COMMAND),
        seed,
        ..Cfg::default()
    })
}

/// The outputs of the `safe_outputs` events received since `since`, with when.
fn safe_outputs_since(rig: &mut Rig, since: Instant) -> Vec<(Instant, String)> {
    rig.gw
        .events_of("safe_outputs", since)
        .into_iter()
        .map(|(t, e)| (t, e["outputs"].as_str().unwrap_or("?").to_string()))
        .collect()
}

fn safe_values(rig: &mut Rig, since: Instant) -> Vec<String> {
    safe_outputs_since(rig, since)
        .into_iter()
        .map(|(_, x)| x)
        .collect()
}

/// Guarantee 1: each `safe_outputs` event received since `since` was followed by a
/// write of its outputs within [`BOUND`].
fn safe_outputs_reached_the_plant(rig: &mut Rig, since: Instant) {
    for (at, x) in safe_outputs_since(rig, since) {
        let what = format!(
            "{x} (announced by the safe_outputs event received at +{} ms, within {BOUND:?})",
            rig.ms(at)
        );
        rig.expect_write(&what, since, at + BOUND, |w| w.coils == x);
    }
}

/// Every connection accepted in `[from, to]` (the plant lost, the safe outputs in
/// force) started with a write of the safe outputs announced since `since`, before any
/// read.
fn reconnections_wrote_the_safe_outputs_first(
    rig: &mut Rig,
    since: Instant,
    from: Instant,
    to: Instant,
) {
    let safe = safe_values(rig, since);
    let conns = rig.plant.conns_since(from);
    for c in conns.iter().filter(|c| c.accepted <= to) {
        let Some((fc, coils)) = &c.first else {
            continue;
        };
        let write_of_safe =
            matches!(fc, 5 | 15) && coils.as_ref().is_some_and(|c| safe.contains(c));
        if !write_of_safe {
            let at = rig.ms(c.accepted);
            rig.fail(&format!(
                "the first request on the connection accepted at +{at} ms (the plant lost) \
                 to be a write of the safe outputs {safe:?}, not function {fc} (coils after it: {coils:?})"
            ));
        }
    }
}

/// Switches the plant to `mode` and checks guarantee 1, the `plant_write` reports and
/// the write-first rule; switches it back and waits until it follows the PLC again.
fn misbehave(rig: &mut Rig, mode: Mode) {
    let since = Instant::now();
    rig.plant.set_mode(mode);
    let what = format!("alarm link:plant once the plant is {mode:?}");
    let (lost, _) = rig.event(&what, since, WAIT, alarm("link:plant"));
    rig.event("a safe_outputs event", since, WAIT, kind("safe_outputs"));
    if mode != Mode::CloseOnAccept {
        safe_outputs_reached_the_plant(rig, since);
        // What the gateway says the plant acknowledged is what the plant did.
        let acked = mode.answers_writes();
        let safe = safe_values(rig, since);
        let what = format!("plant_write of the safe outputs {safe:?} with acknowledged: {acked}");
        rig.event(&what, since, WAIT, move |e| {
            e["event"] == "plant_write"
                && e["acknowledged"] == acked
                && safe.iter().any(|s| e["outputs"] == s.as_str())
        });
    }
    let back = Instant::now();
    rig.plant.set_mode(Mode::Good);
    let what = "safe_outputs_released once the plant is good again";
    let (released, _) = rig.event(what, back, WAIT, kind("safe_outputs_released"));
    if mode != Mode::CloseOnAccept {
        safe_outputs_reached_the_plant(rig, since);
    }
    // The safe outputs are surely handed to the plant's side one cycle after the
    // alarm, or once the test saw their event.
    let from = back.min(lost + Duration::from_millis(20));
    reconnections_wrote_the_safe_outputs_first(rig, since, from, released);
    if mode == Mode::CloseOnAccept {
        // The plant received nothing while it closed every connection: the first
        // connection it keeps (checked above) must exist.
        let first = rig
            .plant
            .conns_since(back)
            .into_iter()
            .find(|c| c.first.is_some());
        if first.is_none() {
            rig.fail("a connection with a request once the plant accepts connections again");
        }
    }
    rig.expect_write(
        "the PLC's command again",
        back,
        Instant::now() + WAIT,
        |w| w.coils == COMMAND,
    );
}

#[test]
fn plant_answering_garbage_to_reads_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(11), Mode::GarbageToReads);
}

#[test]
fn plant_answering_with_a_wrong_mbap_length_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(12), Mode::WrongLength);
}

#[test]
fn plant_answering_with_wrong_transaction_ids_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(13), Mode::WrongTransactionId);
}

#[test]
fn plant_sending_half_a_frame_then_silence_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(14), Mode::PartialFrameThenSilence);
}

#[test]
fn silent_plant_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(15), Mode::Silent);
}

#[test]
fn plant_answering_reads_500_ms_late_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(16), Mode::Slow(fake_plant::SLOW));
}

#[test]
fn plant_answering_exceptions_to_reads_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(17), Mode::ExceptionToReads);
}

#[test]
fn plant_closing_connections_at_accept_gets_the_safe_outputs_first_when_it_returns() {
    misbehave(&mut misbehaviour_rig(18), Mode::CloseOnAccept);
}

#[test]
fn plant_closing_after_each_request_still_receives_the_safe_outputs() {
    misbehave(&mut misbehaviour_rig(19), Mode::CloseAfterRequest);
}

#[test]
fn plant_misbehaving_at_random_moments_always_receives_the_safe_outputs() {
    let seed = seed(0x5EED_0001);
    let mut rng = SplitMix64(seed);
    let mut rig = misbehaviour_rig(seed);
    // Every mode once in a shuffled order, then pseudo-random ones.
    let mut order = Mode::BAD.to_vec();
    for i in (1..order.len()).rev() {
        order.swap(i, rng.below(i as u64 + 1) as usize);
    }
    for run in 0..20 {
        let mode = order
            .get(run)
            .copied()
            .unwrap_or_else(|| Mode::BAD[rng.below(Mode::BAD.len() as u64) as usize]);
        // The moment: anywhere in the gateway's cycle and the PLC's scan.
        let pause = Duration::from_millis(rng.below(50));
        rig.note = format!("run {run} of seed {seed:#x} ({mode:?} after {pause:?})");
        std::thread::sleep(pause);
        misbehave(&mut rig, mode);
    }
}

// ---------------------------------------------------------------------------------
// 2. Only the PLC writes, and only its writes keep it alive.

/// A program on the PLC's own address (as every local program is when the PLC is
/// 127.0.0.1) polls the gateway while the PLC dies: its reads are no liveness.
#[test]
fn a_client_that_only_reads_does_not_keep_a_dead_plc_alive() {
    let mut rig = misbehaviour_rig(21);
    let reads = Arc::new(AtomicU64::new(0));
    let stop = Arc::new(AtomicBool::new(false));
    let mut reader = RawClient::connect(rig.server, from_ip([127, 0, 0, 2])).unwrap();
    let (r, s) = (Arc::clone(&reads), Arc::clone(&stop));
    let poller = std::thread::Builder::new()
        .name("reader-127.0.0.2".into())
        .spawn(move || {
            for _ in 0..20_000 {
                if s.load(Ordering::Acquire) {
                    return Ok(());
                }
                let answer = reader.request(1, &rig::READ_SENSORS)?;
                if answer.first() != Some(&2) {
                    return Err(std::io::Error::other(format!("{answer:02x?}")));
                }
                r.fetch_add(1, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(5));
            }
            Ok(())
        })
        .unwrap();
    rig.wait("the reader to be served", WAIT, |_| {
        reads.load(Ordering::Relaxed) >= 5
    });
    let killed = Instant::now();
    rig.plc = None;
    let (lost, _) = rig.event("alarm link:plc", killed, WAIT, alarm("link:plc"));
    if lost > killed + LINK_TIMEOUT + Duration::from_millis(500) {
        rig.fail(&format!(
            "the link:plc alarm within {:?} of the kill, not at +{} ms (killed at +{} ms)",
            LINK_TIMEOUT + Duration::from_millis(500),
            rig.ms(lost),
            rig.ms(killed)
        ));
    }
    let (_, safe) = rig.event("safe_outputs", killed, WAIT, kind("safe_outputs"));
    if safe["outputs"] == COMMAND {
        rig.fail("safe outputs other than the dead PLC's command");
    }
    safe_outputs_reached_the_plant(&mut rig, killed);
    // The reader polled all along.
    let at_alarm = reads.load(Ordering::Relaxed);
    rig.wait("the reader to be served after the alarm", WAIT, |_| {
        reads.load(Ordering::Relaxed) >= at_alarm + 5
    });
    stop.store(true, Ordering::Release);
    poller.join().unwrap().unwrap();
    if let Some(w) = rig
        .plant
        .writes_since(lost + BOUND)
        .iter()
        .find(|w| w.coils == COMMAND)
    {
        let at = rig.ms(w.at);
        rig.fail(&format!(
            "no write of the dead PLC's {COMMAND} after the alarm (one at +{at} ms)"
        ));
    }
}

/// The raw PLC's keep-alive: a write of [`ALLOWED`] to unit 1, which must be acknowledged.
fn keep_alive(rig: &mut Rig, plc: &mut RawClient) {
    let answer = plc.request(1, &write_coils(ALLOWED));
    if !matches!(&answer, Ok(a) if a[..] == [15, 0, 0, 0, 7]) {
        rig.fail(&format!(
            "the PLC's write of {ALLOWED} to be acknowledged, not {answer:?}"
        ));
    }
}

/// The raw PLC makes the plant follow [`ALLOWED`]; each of `attacks` (unit, request
/// writing A5 or A6), sent by `attacker` (the PLC itself when `None`) between two
/// writes of the PLC a cycle apart, is refused with an exception (`code` when given);
/// none of them reaches the plant while the PLC stays heard. Then the PLC's own A5 A6
/// do.
fn refused_writes_never_reach_the_plant(
    rig: &mut Rig,
    plc: &mut RawClient,
    mut attacker: Option<&mut RawClient>,
    attacks: &[(u8, Vec<u8>)],
    code: Option<u8>,
) {
    let start = Instant::now();
    rig.wait("the plant to follow the raw PLC's 1100000", WAIT, |r| {
        keep_alive(r, plc);
        r.plant
            .writes_since(start)
            .iter()
            .any(|w| w.coils == ALLOWED)
    });
    let attacked = Instant::now();
    for (unit, pdu) in attacks {
        keep_alive(rig, plc);
        let client = match attacker.as_deref_mut() {
            Some(a) => a,
            None => &mut *plc,
        };
        let answer = client.request(*unit, pdu);
        let refused = matches!(&answer, Ok(a) if a.len() == 2 && a[0] == pdu[0] | 0x80
            && code.is_none_or(|c| a[1] == c));
        if !refused {
            let code = code.map_or_else(String::new, |c| format!(" {c:02x}"));
            rig.fail(&format!(
                "exception{code} to the write {pdu:02x?} to unit {unit}, not {answer:?}"
            ));
        }
        // A full cycle before the PLC writes again: a write that got through would
        // reach the plant.
        let after = Instant::now();
        rig.wait("2 writes to the plant after a refused one", WAIT, |r| {
            r.plant.writes_since(after).len() >= 2
        });
    }
    let leaked = rig
        .plant
        .writes_since(attacked)
        .into_iter()
        .find(|w| &w.coils[5..] != "00");
    if let Some(w) = leaked {
        let at = rig.ms(w.at);
        rig.fail(&format!(
            "no refused write to reach the plant ({} at +{at} ms)",
            w.coils
        ));
    }
    let t = Instant::now();
    rig.wait(
        "the PLC's own 0000011 (unit 1) to reach the plant",
        WAIT,
        |r| {
            let _ = plc.request(1, &write_coils("0000011"));
            r.plant.writes_since(t).iter().any(|w| w.coils == "0000011")
        },
    );
}

/// A5 and A6 on, by FC 15 and by FC 5.
fn a5_a6_writes(units: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut v = Vec::new();
    for &u in units {
        v.push((u, write_coils("0000011")));
        v.push((u, write_coil_on(5)));
        v.push((u, write_coil_on(6)));
    }
    v
}

fn raw_plc_rig(plc: &str) -> Rig {
    Rig::start(Cfg {
        plc: plc.into(),
        command: None,
        ..Cfg::default()
    })
}

#[test]
fn writes_from_a_client_that_is_not_the_plc_get_exception_01_and_never_reach_the_plant() {
    let mut rig = raw_plc_rig("127.0.0.2");
    let mut plc = RawClient::connect(rig.server, from_ip([127, 0, 0, 2])).unwrap();
    let mut intruder = RawClient::connect(rig.server, from_ip([127, 0, 0, 1])).unwrap();
    let attacks = a5_a6_writes(&[1; 5]);
    refused_writes_never_reach_the_plant(
        &mut rig,
        &mut plc,
        Some(&mut intruder),
        &attacks,
        Some(0x01),
    );
}

#[test]
fn writes_to_unit_ids_other_than_1_are_refused_and_never_reach_the_plant() {
    let mut rig = raw_plc_rig("127.0.0.2");
    let mut plc = RawClient::connect(rig.server, from_ip([127, 0, 0, 2])).unwrap();
    let attacks = a5_a6_writes(&[0, 255, 2, 247, 0, 255]);
    refused_writes_never_reach_the_plant(&mut rig, &mut plc, None, &attacks, None);
}

#[test]
fn only_the_pinned_source_port_of_the_plc_may_write() {
    // A free port on 127.0.0.2, chosen by the OS, for the PLC's source.
    let port = std::net::TcpListener::bind("127.0.0.2:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut rig = raw_plc_rig(&format!("127.0.0.2:{port}"));
    let source = std::net::SocketAddr::from(([127, 0, 0, 2], port));
    let mut plc = RawClient::connect(rig.server, source).unwrap();
    let mut impostor = RawClient::connect(rig.server, from_ip([127, 0, 0, 2])).unwrap();
    let attacks = a5_a6_writes(&[1; 5]);
    refused_writes_never_reach_the_plant(
        &mut rig,
        &mut plc,
        Some(&mut impostor),
        &attacks,
        Some(0x01),
    );
}

// ---------------------------------------------------------------------------------
// 3. Floods, descriptor exhaustion, idle connections.

/// `n` connections from 127.0.0.1, held open; every other one sends half an MBAP
/// header and stops. Gives up after 5 connections in a row fail; `each` runs after
/// every attempt.
fn flood(
    server: std::net::SocketAddr,
    n: usize,
    mut each: impl FnMut(),
) -> Vec<std::net::TcpStream> {
    let mut held = Vec::new();
    let mut failures = 0;
    for i in 0..n {
        match std::net::TcpStream::connect_timeout(&server, Duration::from_millis(200)) {
            Ok(mut s) => {
                if i % 2 == 1 {
                    let _ = std::io::Write::write_all(&mut s, &[0, 1, 0]);
                }
                held.push(s);
                failures = 0;
            }
            Err(_) if failures >= 5 => break,
            Err(_) => failures += 1,
        }
        each();
    }
    held
}

/// True when a new client from 127.0.0.1 connects and reads the sensors.
fn a_new_client_is_served(server: std::net::SocketAddr) -> bool {
    RawClient::connect(server, from_ip([127, 0, 0, 1]))
        .and_then(|mut c| c.request(1, &rig::READ_SENSORS))
        .is_ok_and(|a| a.first() == Some(&2))
}

#[test]
fn a_connection_flood_does_not_stop_the_plc_session() {
    let mut rig = misbehaviour_rig(31);
    let (scans, errors, _) = rig.plc().status();
    let held = flood(rig.server, 200, || {});
    rig.note = format!("{} flood connections held", held.len());
    rig.wait(
        "the PLC to scan 50 more times during the flood",
        WAIT,
        |r| r.plc().status().0 >= scans + 50,
    );
    let t = Instant::now();
    rig.plc().command("0000011");
    rig.expect_write("the PLC's 0000011 during the flood", t, t + FOLLOW, |w| {
        w.coils == "0000011"
    });
    let (_, now_errors, last) = rig.plc().status();
    if now_errors != errors {
        rig.fail(&format!(
            "no error in the PLC's session during the flood ({} new, the last {last})",
            now_errors - errors
        ));
    }
    drop(held);
    let server = rig.server;
    rig.wait(
        "a new client to be served once the flood is gone",
        WAIT,
        |_| a_new_client_is_served(server),
    );
}

#[test]
fn the_gateway_serves_a_new_plc_after_descriptor_exhaustion() {
    let mut rig = Rig::start(Cfg {
        command: Some(COMMAND),
        // No cap below the descriptor limit: the flood exhausts the descriptors.
        max_connections: 1000,
        spawn: Spawn::FdLimit(64),
        ..Cfg::default()
    });
    let fds = format!("/proc/{}/fd", rig.gw.pid());
    let mut peak = 0;
    let held = flood(rig.server, 200, || {
        peak = peak.max(std::fs::read_dir(&fds).map_or(0, Iterator::count));
    });
    rig.note = format!(
        "{} flood connections held, at most {peak} descriptors open in the gateway",
        held.len()
    );
    drop(held);
    rig.plc = None;
    let mut plc = crate::live::Plc::start(rig.server, Some("127.0.0.2"));
    let t = Instant::now();
    plc.command("0000011");
    rig.plc = Some(plc);
    rig.expect_write("the new PLC's 0000011", t, t + WAIT, |w| {
        w.coils == "0000011"
    });
    if !rig.gw.is_running() {
        rig.fail("the gateway to be running");
    }
    let server = rig.server;
    rig.wait("a new client to be served", WAIT, |_| {
        a_new_client_is_served(server)
    });
    // The flood did exhaust the descriptors (the test proves what it says).
    if peak < 60 {
        rig.fail("the flood to take 60 of the gateway's 64 descriptors");
    }
}

#[test]
fn idle_connections_are_closed_after_the_idle_timeout() {
    let idle = Duration::from_millis(500);
    let mut rig = Rig::start(Cfg {
        idle_timeout_ms: 500,
        command: None,
        ..Cfg::default()
    });
    let connected = Instant::now();
    let watch = |name: &str, prefix: &'static [u8]| {
        let mut c = RawClient::connect(rig.server, from_ip([127, 0, 0, 1])).unwrap();
        c.send_raw(prefix).unwrap();
        std::thread::Builder::new()
            .name(name.into())
            .spawn(move || c.closed_within(idle * 5).then(|| connected.elapsed()))
            .unwrap()
    };
    let silent = watch("silent-client", b"");
    let partial = watch("partial-client", &[0, 1, 0]);
    // A client that asks every 100 ms for 1.2 s is served all along.
    let mut active = RawClient::connect(rig.server, from_ip([127, 0, 0, 1])).unwrap();
    for i in 0..12 {
        let answer = active.request(1, &rig::READ_SENSORS);
        if !answer.as_ref().is_ok_and(|a| a.first() == Some(&2)) {
            rig.fail(&format!(
                "request {i} of an active client answered, not {answer:?}"
            ));
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    for (name, t) in [("silent", silent), ("half a header then", partial)] {
        match t.join().unwrap() {
            Some(after) if after >= idle - Duration::from_millis(50) => {}
            other => rig.fail(&format!(
                "a {name} client closed after the idle timeout ({idle:?}), not {other:?}"
            )),
        }
    }
    // The gateway wrote to the plant all along.
    let writes = rig.plant.writes_since(connected).len();
    if writes < 50 {
        rig.fail(&format!("50 writes to the plant in 1.2 s, not {writes}"));
    }
}

// ---------------------------------------------------------------------------------
// 4. Nobody reads the gateway's output.

/// The PLC commands `command` (C0 = 1); the plant must receive the filter's output
/// for it (A0 = 0 for [`FORBIDDEN`], the command itself otherwise) within `within`.
/// Returns how long that took.
fn follow(rig: &mut Rig, command: &'static str, within: Duration) -> Duration {
    let t = Instant::now();
    rig.plc().command(command);
    let what = format!("the filter's output for {command}");
    let w = rig.expect_write(&what, t, t + within, |w| match command {
        FORBIDDEN => w.coils.starts_with('0'),
        _ => w.coils == command,
    });
    w.at - t
}

#[test]
fn a_gateway_whose_stdout_and_stderr_nobody_reads_keeps_filtering_through_300_trips() {
    let mut rig = Rig::start(Cfg {
        auto_reset: true,
        sensors: vec![C0],
        command: Some(ALLOWED),
        // Debug logs: stderr fills its pipe too.
        spawn: Spawn::Unread("debug"),
        ..Cfg::default()
    });
    // Each command is followed (a gateway blocked on a full pipe never follows
    // again); the slowest is said in messages.
    let mut slowest = Duration::ZERO;
    let trips = |r: &Rig| {
        r.journal()
            .iter()
            .filter(|e| e["journal_kind"] == "trip")
            .count()
    };
    // A forbidden command meets the stale guard rather than the filter when the PLC's
    // link is lost at that moment (a peer starved for 100 ms on a loaded machine): the
    // safe outputs follow it with no trip. More commands then, bounded, until 300 trips.
    let mut commands = 0;
    while commands < 300 || (trips(&rig) < 300 && commands < 450) {
        rig.note = format!("command {commands} (the slowest follow so far {slowest:?})");
        slowest = slowest.max(follow(&mut rig, FORBIDDEN, WAIT));
        slowest = slowest.max(follow(&mut rig, ALLOWED, WAIT));
        commands += 1;
    }
    rig.note = format!("after {commands} forbidden commands (the slowest follow {slowest:?})");
    // The last command, within the bound.
    follow(&mut rig, FORBIDDEN, FOLLOW);
    if !rig.gw.is_running() {
        rig.fail("the gateway to be running");
    }
    // The journal has every trip, and more than two pipes' worth of events: stdout
    // was full for most of the run.
    rig.wait("300 trips in the journal", WAIT, |r| {
        r.journal()
            .iter()
            .filter(|e| e["journal_kind"] == "trip")
            .count()
            >= 300
    });
    let bytes: usize = rig.journal().iter().map(|e| e.to_string().len()).sum();
    if bytes < 2 * 65_536 {
        rig.fail(&format!(
            "more than 128 KiB of events (a full pipe), not {bytes} bytes"
        ));
    }
}

// ---------------------------------------------------------------------------------
// 5. kill -9.

/// True while the alarm `key` raised since `since` is not cleared.
fn alarm_active(rig: &mut Rig, key: &str, since: Instant) -> bool {
    let mut last = None;
    for kind in ["alarm", "alarm_cleared"] {
        for (t, e) in rig.gw.events_of(kind, since) {
            if e["key"] == key && last.is_none_or(|(l, _)| t >= l) {
                last = Some((t, kind));
            }
        }
    }
    last.is_some_and(|(_, k)| k == "alarm")
}

#[test]
fn a_trip_latched_before_a_kill_9_is_restored_and_enforced_after_restart() {
    let seed = seed(0x5EED_0005);
    let mut rng = SplitMix64(seed);
    for run in 0..20 {
        let mut rig = Rig::start(Cfg {
            sensors: vec![C0],
            seed: seed.wrapping_add(run),
            ..Cfg::default()
        });
        let delay = Duration::from_millis(rng.below(51));
        rig.note = format!("run {run} of seed {seed:#x} (kill -9 {delay:?} after the trip)");
        let t = Instant::now();
        rig.plc().command(FORBIDDEN);
        let (tripped, _) = rig.event("a trip on CSc1", t, WAIT, record_names("trip", "CSc1"));
        std::thread::sleep((tripped + delay).saturating_duration_since(Instant::now()));
        rig.cfg.command = Some(FORBIDDEN);
        let restarted = rig.kill9_and_restart();
        let what = "trip_restored naming CSc1";
        rig.event(what, restarted, WAIT, record_names("trip_restored", "CSc1"));
        // The new PLC is heard commanding 1000000, both links are up.
        let (scans, _, _) = rig.plc().status();
        rig.wait("the PLC to be heard and both links up", WAIT, |r| {
            r.plc().status().0 >= scans + 5
                && !alarm_active(r, "link:plc", restarted)
                && !alarm_active(r, "link:plant", restarted)
        });
        let heard = Instant::now();
        rig.expect_write("A0 = 0 (the latched trip)", heard, heard + BOUND, |w| {
            w.coils.starts_with('0')
        });
        let leak = rig
            .plant
            .writes_since(restarted)
            .into_iter()
            .find(|w| w.coils.starts_with('1'));
        if let Some(w) = leak {
            let at = rig.ms(w.at);
            rig.fail(&format!(
                "A0 = 0 in every write after the restart ({} at +{at} ms)",
                w.coils
            ));
        }
        if !rig.journal().iter().any(|e| e["journal_kind"] == "trip") {
            rig.fail("a trip entry in the journal (vigie.sqlite)");
        }
    }
}
