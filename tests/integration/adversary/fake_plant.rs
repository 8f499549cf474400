//! A misbehaving plant: a Modbus TCP device written by hand (one thread per
//! connection, MBAP frames parsed here), unit-agnostic, serving the 11 sensors of the
//! sorting station as discrete inputs 0..10 (FC 2) and its 7 actuators as coils 0..6
//! (FC 1 read, FC 5 and FC 15 write). Its behaviour ([`Mode`]) is switched at run time;
//! whatever the mode, a write it receives is executed and recorded ([`Write`]), as a
//! real plant executes a write even when its read answers are broken, and every
//! connection is recorded with its first request ([`Conn`]).

use super::SplitMix64;
use std::collections::VecDeque;
use std::io::{ErrorKind, Read as _, Write as _};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

pub(crate) const SENSORS: usize = 11;
pub(crate) const COILS: usize = 7;
/// How late a slow plant answers reads.
pub(crate) const SLOW: Duration = Duration::from_millis(500);
/// Writes kept (the oldest go first): a gateway writes about 100 a second.
const KEEP: usize = 100_000;

/// How the plant behaves. The read-side modes (garbage, wrong length, wrong
/// transaction id, exception, slow) spoil the answers to reads only and answer writes
/// correctly; the silent, partial-frame and closing modes answer nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Mode {
    Good,
    /// Reads are answered with 1 to 16 random bytes.
    GarbageToReads,
    /// Answers to reads carry a wrong MBAP length field.
    WrongLength,
    /// Answers to reads carry another transaction id.
    WrongTransactionId,
    /// The first request of a connection gets half its answer, then nothing more.
    PartialFrameThenSilence,
    /// Requests are read, never answered.
    Silent,
    /// Reads are answered correctly, after this long (writes at once).
    Slow(Duration),
    /// Reads get exception 04 (server device failure).
    ExceptionToReads,
    /// Connections are closed as soon as they are accepted (an open one at its next
    /// request, unread): the plant receives nothing.
    CloseOnAccept,
    /// Each connection is closed after its first request, unanswered.
    CloseAfterRequest,
}

impl Mode {
    /// Every way of misbehaving.
    pub(crate) const BAD: [Self; 9] = [
        Self::GarbageToReads,
        Self::WrongLength,
        Self::WrongTransactionId,
        Self::PartialFrameThenSilence,
        Self::Silent,
        Self::Slow(SLOW),
        Self::ExceptionToReads,
        Self::CloseOnAccept,
        Self::CloseAfterRequest,
    ];

    /// Writes get their correct answer in this mode.
    pub(crate) fn answers_writes(self) -> bool {
        !matches!(
            self,
            Self::PartialFrameThenSilence
                | Self::Silent
                | Self::CloseOnAccept
                | Self::CloseAfterRequest
        )
    }
}

/// A write request the plant received and executed.
#[derive(Clone, Debug)]
pub(crate) struct Write {
    /// When it was received.
    pub(crate) at: Instant,
    /// The 7 coils after it ("0101000": coil 0 first).
    pub(crate) coils: String,
    /// Whether the plant sent its correct answer.
    pub(crate) answered: bool,
}

/// A connection the plant accepted.
#[derive(Clone, Debug)]
pub(crate) struct Conn {
    pub(crate) accepted: Instant,
    /// Its first request: the function code and, for an executed write, the coils after
    /// it; `None` while it sent none (or was closed at once).
    pub(crate) first: Option<(u8, Option<String>)>,
}

struct Device {
    sensors: [bool; SENSORS],
    coils: [bool; COILS],
    writes: VecDeque<Write>,
    conns: Vec<Conn>,
    rng: SplitMix64,
}

struct Shared {
    mode: Mutex<Mode>,
    device: Mutex<Device>,
    stop: AtomicBool,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn bits_text(bits: &[bool]) -> String {
    bits.iter().map(|&b| if b { '1' } else { '0' }).collect()
}

/// The fake plant; stopped when dropped.
pub(crate) struct FakePlant {
    addr: SocketAddr,
    shared: Arc<Shared>,
    accept: Option<std::thread::JoinHandle<()>>,
}

impl FakePlant {
    /// Listens on 127.0.0.1 (an OS-chosen port); `seed` drives the garbage it sends.
    pub(crate) fn start(seed: u64) -> Self {
        let listener = TcpListener::bind("127.0.0.1:0").expect("fake plant: bind");
        let addr = listener.local_addr().expect("fake plant: address");
        let shared = Arc::new(Shared {
            mode: Mutex::new(Mode::Good),
            device: Mutex::new(Device {
                sensors: [false; SENSORS],
                coils: [false; COILS],
                writes: VecDeque::new(),
                conns: Vec::new(),
                rng: SplitMix64(seed),
            }),
            stop: AtomicBool::new(false),
        });
        let s = Arc::clone(&shared);
        let accept = std::thread::Builder::new()
            .name("fake-plant-accept".into())
            .spawn(move || accept_loop(&listener, &s))
            .expect("fake plant: thread");
        Self {
            addr,
            shared,
            accept: Some(accept),
        }
    }

    pub(crate) fn addr(&self) -> SocketAddr {
        self.addr
    }

    pub(crate) fn set_mode(&self, mode: Mode) {
        *lock(&self.shared.mode) = mode;
    }

    pub(crate) fn set_sensor(&self, index: usize, on: bool) {
        lock(&self.shared.device).sensors[index] = on;
    }

    /// The writes received at or after `t`, oldest first.
    pub(crate) fn writes_since(&self, t: Instant) -> Vec<Write> {
        let d = lock(&self.shared.device);
        d.writes.iter().filter(|w| w.at >= t).cloned().collect()
    }

    /// The connections accepted at or after `t`.
    pub(crate) fn conns_since(&self, t: Instant) -> Vec<Conn> {
        let d = lock(&self.shared.device);
        d.conns
            .iter()
            .filter(|c| c.accepted >= t)
            .cloned()
            .collect()
    }
}

impl Drop for FakePlant {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        // Wakes the accept loop, which then sees the stop.
        let _ = TcpStream::connect_timeout(&self.addr, Duration::from_secs(1));
        if let Some(t) = self.accept.take() {
            let _ = t.join();
        }
    }
}

fn accept_loop(listener: &TcpListener, shared: &Arc<Shared>) {
    for stream in listener.incoming() {
        if shared.stop.load(Ordering::Acquire) {
            return;
        }
        let Ok(stream) = stream else {
            // Out of descriptors in the test process: let the others close.
            std::thread::sleep(Duration::from_millis(1));
            continue;
        };
        let id = {
            let mut d = lock(&shared.device);
            d.conns.push(Conn {
                accepted: Instant::now(),
                first: None,
            });
            d.conns.len() - 1
        };
        if *lock(&shared.mode) == Mode::CloseOnAccept {
            continue; // dropped: closed at once
        }
        let s = Arc::clone(shared);
        let _ = std::thread::Builder::new()
            .name("fake-plant-conn".into())
            .spawn(move || serve(stream, id, &s));
    }
}

/// One request as received.
struct Frame {
    tid: u16,
    unit: u8,
    pdu: Vec<u8>,
}

/// Takes one complete frame off `buf`; `Err` when the header cannot be a Modbus one.
fn take_frame(buf: &mut Vec<u8>) -> Result<Option<Frame>, ()> {
    if buf.len() < 7 {
        return Ok(None);
    }
    let len = usize::from(u16::from_be_bytes([buf[4], buf[5]]));
    if buf[2..4] != [0, 0] || !(2..=254).contains(&len) {
        return Err(());
    }
    if buf.len() < 6 + len {
        return Ok(None);
    }
    let bytes: Vec<u8> = buf.drain(..6 + len).collect();
    Ok(Some(Frame {
        tid: u16::from_be_bytes([bytes[0], bytes[1]]),
        unit: bytes[6],
        pdu: bytes[7..].to_vec(),
    }))
}

fn mbap(tid: u16, length: u16, unit: u8, pdu: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(7 + pdu.len());
    out.extend_from_slice(&tid.to_be_bytes());
    out.extend_from_slice(&[0, 0]);
    out.extend_from_slice(&length.to_be_bytes());
    out.push(unit);
    out.extend_from_slice(pdu);
    out
}

fn pdu_length(pdu: &[u8]) -> u16 {
    u16::try_from(pdu.len() + 1).unwrap_or(u16::MAX)
}

fn serve(mut stream: TcpStream, id: usize, shared: &Shared) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(20)));
    let _ = stream.set_nodelay(true);
    let mut buf = Vec::new();
    let mut chunk = [0u8; 512];
    let mut silenced = false;
    while !shared.stop.load(Ordering::Acquire) {
        match stream.read(&mut chunk) {
            Ok(0) => return,
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(_) => return,
        }
        loop {
            match take_frame(&mut buf) {
                Ok(Some(frame)) => {
                    if !answer(&mut stream, id, &frame, &mut silenced, shared) {
                        return;
                    }
                }
                Ok(None) => break,
                Err(()) => return,
            }
        }
    }
}

/// Executes one request and answers it as the mode says; false closes the connection.
fn answer(
    stream: &mut TcpStream,
    id: usize,
    frame: &Frame,
    silenced: &mut bool,
    shared: &Shared,
) -> bool {
    let received = Instant::now();
    let mode = *lock(&shared.mode);
    if mode == Mode::CloseOnAccept {
        return false;
    }
    let fc = frame.pdu.first().copied().unwrap_or(0);
    let is_read = (1..=4).contains(&fc);
    let (reply, written, noise) = {
        let mut d = lock(&shared.device);
        let (reply, written) = execute(&mut d, &frame.pdu);
        if let Some(c) = d.conns.get_mut(id)
            && c.first.is_none()
        {
            c.first = Some((fc, written.clone()));
        }
        (reply, written, d.rng.next())
    };
    let correct = mbap(frame.tid, pdu_length(&reply), frame.unit, &reply);
    let (bytes, keep_open) = match mode {
        Mode::GarbageToReads if is_read => {
            let mut rng = SplitMix64(noise);
            let n = 1 + rng.below(16);
            ((0..n).map(|_| rng.next().to_le_bytes()[0]).collect(), true)
        }
        Mode::WrongLength if is_read => {
            let right = pdu_length(&reply);
            let wrong = [right - 1, right + 1, right + 3, right + 200][(noise % 4) as usize];
            (mbap(frame.tid, wrong, frame.unit, &reply), true)
        }
        Mode::WrongTransactionId if is_read => {
            let tid = frame.tid.wrapping_add(1 + (noise % 100) as u16);
            (mbap(tid, pdu_length(&reply), frame.unit, &reply), true)
        }
        Mode::ExceptionToReads if is_read => {
            let pdu = [fc | 0x80, 0x04];
            (mbap(frame.tid, 3, frame.unit, &pdu), true)
        }
        Mode::Slow(delay) if is_read => {
            std::thread::sleep(delay);
            (correct, true)
        }
        Mode::PartialFrameThenSilence if !*silenced => {
            *silenced = true;
            (correct[..correct.len() / 2].to_vec(), true)
        }
        Mode::PartialFrameThenSilence | Mode::Silent => (Vec::new(), true),
        Mode::CloseAfterRequest => (Vec::new(), false),
        _ => (correct, true),
    };
    // Recorded before the answer goes (whoever gets the answer finds the record),
    // corrected if it cannot be sent.
    let answering = !bytes.is_empty() && mode.answers_writes();
    if let Some(coils) = written.clone() {
        let mut d = lock(&shared.device);
        if d.writes.len() >= KEEP {
            d.writes.pop_front();
        }
        d.writes.push_back(Write {
            at: received,
            coils,
            answered: answering,
        });
    }
    let sent = !bytes.is_empty() && stream.write_all(&bytes).is_ok();
    if answering && !sent && written.is_some() {
        let mut d = lock(&shared.device);
        if let Some(w) = d.writes.iter_mut().rev().find(|w| w.at == received) {
            w.answered = false;
        }
    }
    keep_open
}

fn word(pdu: &[u8], at: usize) -> Option<usize> {
    Some(usize::from(u16::from_be_bytes([
        *pdu.get(at)?,
        *pdu.get(at + 1)?,
    ])))
}

fn exception(fc: u8, code: u8) -> Vec<u8> {
    vec![fc | 0x80, code]
}

/// The correct answer to `pdu` and, for an executed write, the coils after it.
fn execute(d: &mut Device, pdu: &[u8]) -> (Vec<u8>, Option<String>) {
    let fc = pdu.first().copied().unwrap_or(0);
    let (Some(addr), Some(n)) = (word(pdu, 1), word(pdu, 3)) else {
        return (exception(fc, 0x03), None);
    };
    match fc {
        1 | 2 => {
            let bits: &[bool] = if fc == 1 { &d.coils } else { &d.sensors };
            if n == 0 || addr + n > bits.len() {
                return (exception(fc, 0x02), None);
            }
            let mut out = vec![fc, u8::try_from(n.div_ceil(8)).unwrap_or(0)];
            for chunk in bits[addr..addr + n].chunks(8) {
                out.push(
                    chunk
                        .iter()
                        .enumerate()
                        .fold(0u8, |b, (k, &v)| b | (u8::from(v) << k)),
                );
            }
            (out, None)
        }
        5 => {
            if addr >= COILS || !(n == 0xFF00 || n == 0) {
                return (exception(fc, 0x02), None);
            }
            d.coils[addr] = n == 0xFF00;
            (pdu[..5].to_vec(), Some(bits_text(&d.coils)))
        }
        15 => {
            let data = pdu.get(6..).unwrap_or_default();
            let count = usize::from(pdu.get(5).copied().unwrap_or(0));
            if n == 0 || addr + n > COILS || count != n.div_ceil(8) || data.len() < count {
                return (exception(fc, 0x02), None);
            }
            for k in 0..n {
                d.coils[addr + k] = data[k / 8] >> (k % 8) & 1 == 1;
            }
            (pdu[..5].to_vec(), Some(bits_text(&d.coils)))
        }
        _ => (exception(fc, 0x01), None),
    }
}

/// The writes as runs of equal values, times relative to `origin`, for messages.
pub(crate) fn summary(writes: &[Write], origin: Instant) -> String {
    let ms = |t: Instant| t.saturating_duration_since(origin).as_millis();
    let mut runs: Vec<(Instant, Instant, &str, bool, usize)> = Vec::new();
    for w in writes {
        match runs.last_mut() {
            Some(r) if r.2 == w.coils && r.3 == w.answered => {
                r.1 = w.at;
                r.4 += 1;
            }
            _ => runs.push((w.at, w.at, &w.coils, w.answered, 1)),
        }
    }
    if runs.is_empty() {
        return "  (no write at all)".into();
    }
    let skip = runs.len().saturating_sub(40);
    let mut out = if skip > 0 {
        format!("  ({skip} earlier runs left out)\n")
    } else {
        String::new()
    };
    for (from, to, coils, answered, n) in &runs[skip..] {
        let ack = if *answered { "answered" } else { "unanswered" };
        out.push_str(&format!(
            "  +{}..+{} ms: {n} x {coils} ({ack})\n",
            ms(*from),
            ms(*to)
        ));
    }
    out
}
