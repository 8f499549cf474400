//! The register image ↔ [`Bits`] mapping, both ways:
//! - client side: which requests read the map ([`ReadBlock`]) and which write the
//!   outputs ([`WriteOp`]), and how their answers decode into [`AgedBits`];
//! - server side ([`ServerImage`]): answering reads and applying writes from the
//!   plant's inputs and outputs, with the Modbus error for each illegal request.

use super::age::AgedBits;
use super::iomap::{Area, IoMap, Mapped};
use crate::bits::Bits;
use crate::time::Millis;
use std::collections::BTreeMap;

/// Largest quantity of bits in one read (Modbus application protocol, functions 01/02).
pub const MAX_READ_BITS: u16 = 2000;
/// Largest quantity of registers in one read (functions 03/04).
pub const MAX_READ_REGISTERS: u16 = 125;
/// Largest quantity of coils in one write (function 15).
pub const MAX_WRITE_COILS: u16 = 1968;
/// Largest quantity of registers in one write (function 16).
pub const MAX_WRITE_REGISTERS: u16 = 123;

/// Which image a signal belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Side {
    /// A plant input (sensor).
    Input,
    /// A plant output (actuator).
    Output,
}

/// A signal inside a [`ReadBlock`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Member {
    /// Input or output.
    pub side: Side,
    /// Index in that side.
    pub index: usize,
    /// Offset from the block's start.
    pub offset: u16,
    /// Register bit (0 in the bit areas).
    pub bit: u8,
}

/// One read request covering several signals.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadBlock {
    /// Unit id.
    pub unit: u8,
    /// Area.
    pub area: Area,
    /// First address.
    pub start: u16,
    /// Quantity of bits or registers.
    pub count: u16,
    /// Poll period (the fastest of its members).
    pub poll: Millis,
    /// The signals it carries.
    pub members: Vec<Member>,
}

/// An answer to a [`ReadBlock`].
#[derive(Clone, Copy, Debug)]
pub enum Raw<'a> {
    /// Bits (coils, discrete inputs).
    Bits(&'a [bool]),
    /// Registers.
    Words(&'a [u16]),
}

/// A reply that does not fit its request.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("short or mistyped reply to a read of {count} at {area} {start}: got {got}")]
pub struct ShortReply {
    /// Area read.
    pub area: Area,
    /// First address.
    pub start: u16,
    /// Quantity asked.
    pub count: u16,
    /// Quantity received.
    pub got: usize,
}

impl ReadBlock {
    /// Decodes an answer into `inputs` and `outputs`, each value stamped `now`.
    /// A short or mistyped answer changes nothing (the values age).
    pub fn decode(
        &self,
        raw: Raw<'_>,
        now: Millis,
        inputs: &mut AgedBits,
        outputs: &mut AgedBits,
    ) -> Result<(), ShortReply> {
        let (len, ok_kind) = match raw {
            Raw::Bits(b) => (b.len(), self.area.is_bit()),
            Raw::Words(w) => (w.len(), !self.area.is_bit()),
        };
        if !ok_kind || len < usize::from(self.count) {
            return Err(ShortReply {
                area: self.area,
                start: self.start,
                count: self.count,
                got: len,
            });
        }
        for m in &self.members {
            let at = usize::from(m.offset);
            let value = match raw {
                Raw::Bits(b) => b.get(at).copied().unwrap_or(false),
                Raw::Words(w) => w.get(at).is_some_and(|w| (w >> m.bit) & 1 == 1),
            };
            match m.side {
                Side::Input => inputs.set(m.index, value, now),
                Side::Output => outputs.set(m.index, value, now),
            }
        }
        Ok(())
    }
}

/// The read requests for a map: signals grouped by unit, area and poll period, merged
/// into blocks when the gap between addresses is at most `max_gap`. With
/// `with_outputs`, the outputs are read too (monitor mode).
pub fn plan_reads(map: &IoMap, with_outputs: bool, max_gap: u16) -> Vec<ReadBlock> {
    let mut groups: BTreeMap<(u8, Area, Millis), Vec<(u16, Member)>> = BTreeMap::new();
    let sides = [(Side::Input, &map.inputs), (Side::Output, &map.outputs)];
    for (side, signals) in sides {
        if side == Side::Output && !with_outputs {
            continue;
        }
        for (index, m) in signals.iter().enumerate() {
            groups
                .entry((m.point.unit, m.point.area, m.poll))
                .or_default()
                .push((
                    m.point.address,
                    Member {
                        side,
                        index,
                        offset: 0,
                        bit: m.point.bit,
                    },
                ));
        }
    }
    let mut blocks = Vec::new();
    for ((unit, area, poll), mut members) in groups {
        members.sort_by_key(|(a, m)| (*a, m.bit));
        let limit = if area.is_bit() {
            MAX_READ_BITS
        } else {
            MAX_READ_REGISTERS
        };
        let mut current: Option<ReadBlock> = None;
        for (address, member) in members {
            if let Some(b) = current.as_mut() {
                let end = b.start.saturating_add(b.count);
                let fits = address < end || (address - end <= max_gap && address - b.start < limit);
                if fits {
                    b.count = b.count.max(address - b.start + 1);
                    b.members.push(Member {
                        offset: address - b.start,
                        ..member
                    });
                    continue;
                }
                blocks.extend(current.take());
            }
            current = Some(ReadBlock {
                unit,
                area,
                start: address,
                count: 1,
                poll,
                members: vec![member],
            });
        }
        blocks.extend(current);
    }
    blocks
}

/// One write of outputs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum WriteOp {
    /// Write multiple coils (function 15).
    Coils {
        /// Unit id.
        unit: u8,
        /// First coil.
        start: u16,
        /// Values.
        values: Vec<bool>,
    },
    /// Mask write register (function 22): `(current & and) | (or & !and)`.
    MaskRegister {
        /// Unit id.
        unit: u8,
        /// Register.
        address: u16,
        /// Bits kept.
        and_mask: u16,
        /// Bits set.
        or_mask: u16,
    },
}

/// The output writes for `outputs`: runs of consecutive coils as one write each, and one
/// mask write per holding register (its other bits untouched).
pub fn plan_writes(map: &IoMap, outputs: &Bits) -> Vec<WriteOp> {
    let mut coils: BTreeMap<(u8, u16), bool> = BTreeMap::new();
    let mut registers: BTreeMap<(u8, u16), (u16, u16)> = BTreeMap::new();
    for (k, m) in map.outputs.iter().enumerate() {
        let p = m.point;
        let v = outputs.get(k);
        match p.area {
            Area::Coil => {
                coils.insert((p.unit, p.address), v);
            }
            Area::HoldingRegister => {
                let entry = registers.entry((p.unit, p.address)).or_insert((0xFFFF, 0));
                let mask = 1u16 << (p.bit & 15);
                entry.0 &= !mask;
                if v {
                    entry.1 |= mask;
                }
            }
            Area::DiscreteInput | Area::InputRegister => {}
        }
    }
    let mut ops = Vec::new();
    let mut run: Option<(u8, u16, Vec<bool>)> = None;
    for ((unit, address), v) in coils {
        if let Some((u, start, values)) = run.as_mut() {
            let next = usize::from(*start) + values.len();
            if *u == unit
                && usize::from(address) == next
                && values.len() < usize::from(MAX_WRITE_COILS)
            {
                values.push(v);
                continue;
            }
        }
        if let Some((unit, start, values)) = run.take() {
            ops.push(WriteOp::Coils {
                unit,
                start,
                values,
            });
        }
        run = Some((unit, address, vec![v]));
    }
    if let Some((unit, start, values)) = run {
        ops.push(WriteOp::Coils {
            unit,
            start,
            values,
        });
    }
    for ((unit, address), (and_mask, or_mask)) in registers {
        ops.push(WriteOp::MaskRegister {
            unit,
            address,
            and_mask,
            or_mask,
        });
    }
    ops
}

/// Why a server refuses a request; each maps to one Modbus exception code.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// Exception 02: an address outside the image, or not writable.
    #[error("illegal data address: {area} {start} (+{count})")]
    IllegalAddress {
        /// Area.
        area: Area,
        /// First address asked.
        start: u16,
        /// Quantity asked.
        count: u16,
    },
    /// Exception 03: a quantity of 0 or above the protocol's limit.
    #[error("illegal quantity {count} for {area}")]
    IllegalQuantity {
        /// Area.
        area: Area,
        /// Quantity asked.
        count: u16,
    },
}

/// A bit of the served image.
type Slot = Option<(Side, usize)>;

/// The image a Modbus server exposes for one map: reads answer from the inputs and the
/// outputs; writes reach only the outputs (actuators on coils or holding registers).
/// Addresses up to the highest mapped one of each area exist (unmapped ones read 0 and
/// refuse writes); anything past it is an illegal address.
#[derive(Clone, Debug, Default)]
pub struct ServerImage {
    /// Per area, per address, per bit (one bit in the bit areas).
    areas: BTreeMap<Area, Vec<[Slot; 16]>>,
}

impl ServerImage {
    /// The image of `map` for one unit (entries of other units are left out).
    pub fn new(map: &IoMap, unit: u8) -> Self {
        let mut areas: BTreeMap<Area, Vec<[Slot; 16]>> = BTreeMap::new();
        let sides = [(Side::Input, &map.inputs), (Side::Output, &map.outputs)];
        for (side, signals) in sides {
            for (index, m) in signals.iter().enumerate() {
                let Mapped { point, .. } = *m;
                if point.unit != unit {
                    continue;
                }
                let table = areas.entry(point.area).or_default();
                let at = usize::from(point.address);
                if table.len() <= at {
                    table.resize(at + 1, [None; 16]);
                }
                if let Some(slot) = table
                    .get_mut(at)
                    .and_then(|s| s.get_mut(usize::from(point.bit & 15)))
                {
                    *slot = Some((side, index));
                }
            }
        }
        Self { areas }
    }

    /// Number of addresses served in `area`.
    pub fn extent(&self, area: Area) -> usize {
        self.areas.get(&area).map_or(0, Vec::len)
    }

    fn range(
        &self,
        area: Area,
        start: u16,
        count: u16,
        limit: u16,
    ) -> Result<&[[Slot; 16]], ImageError> {
        if count == 0 || count > limit {
            return Err(ImageError::IllegalQuantity { area, count });
        }
        let table = self.areas.get(&area).map_or(&[][..], Vec::as_slice);
        let from = usize::from(start);
        table
            .get(from..from + usize::from(count))
            .ok_or(ImageError::IllegalAddress { area, start, count })
    }

    fn value(slot: Slot, inputs: &Bits, outputs: &Bits) -> bool {
        match slot {
            Some((Side::Input, i)) => inputs.get(i),
            Some((Side::Output, k)) => outputs.get(k),
            None => false,
        }
    }

    /// Reads `count` bits of a bit area.
    pub fn read_bits(
        &self,
        area: Area,
        start: u16,
        count: u16,
        inputs: &Bits,
        outputs: &Bits,
    ) -> Result<Vec<bool>, ImageError> {
        let slots = self.range(area, start, count, MAX_READ_BITS)?;
        Ok(slots
            .iter()
            .map(|s| Self::value(s[0], inputs, outputs))
            .collect())
    }

    /// Reads `count` registers of a register area.
    pub fn read_registers(
        &self,
        area: Area,
        start: u16,
        count: u16,
        inputs: &Bits,
        outputs: &Bits,
    ) -> Result<Vec<u16>, ImageError> {
        let slots = self.range(area, start, count, MAX_READ_REGISTERS)?;
        Ok(slots
            .iter()
            .map(|bits| {
                bits.iter().enumerate().fold(0u16, |w, (b, &s)| {
                    if Self::value(s, inputs, outputs) {
                        w | (1 << b)
                    } else {
                        w
                    }
                })
            })
            .collect())
    }

    /// Writes coils into `outputs`. All or nothing: every coil must be an actuator.
    pub fn write_coils(
        &self,
        start: u16,
        values: &[bool],
        outputs: &mut Bits,
    ) -> Result<(), ImageError> {
        let count = u16::try_from(values.len()).unwrap_or(u16::MAX);
        let slots = self.range(Area::Coil, start, count, MAX_WRITE_COILS)?;
        let mut targets = Vec::with_capacity(slots.len());
        for s in slots {
            match s[0] {
                Some((Side::Output, k)) => targets.push(k),
                _ => {
                    return Err(ImageError::IllegalAddress {
                        area: Area::Coil,
                        start,
                        count,
                    });
                }
            }
        }
        for (k, &v) in targets.into_iter().zip(values) {
            outputs.set(k, v);
        }
        Ok(())
    }

    /// Writes holding registers into `outputs`: each mapped actuator bit takes the
    /// register's bit `(word & !and_mask) | …` as given by `and_mask`/`or_mask` for a
    /// mask write, or the plain word for functions 06/16 (pass `and_mask = 0`,
    /// `or_mask = word`). Registers with no actuator are illegal addresses; bits of a
    /// register not mapped to an actuator are ignored.
    pub fn write_registers(
        &self,
        start: u16,
        words: &[(u16, u16)],
        outputs: &mut Bits,
    ) -> Result<(), ImageError> {
        let count = u16::try_from(words.len()).unwrap_or(u16::MAX);
        let slots = self.range(Area::HoldingRegister, start, count, MAX_WRITE_REGISTERS)?;
        let illegal = ImageError::IllegalAddress {
            area: Area::HoldingRegister,
            start,
            count,
        };
        if slots
            .iter()
            .any(|bits| !bits.iter().any(|s| matches!(s, Some((Side::Output, _)))))
        {
            return Err(illegal);
        }
        for (bits, &(and_mask, or_mask)) in slots.iter().zip(words) {
            for (b, s) in bits.iter().enumerate() {
                if let Some((Side::Output, k)) = *s {
                    let mask = 1u16 << b;
                    let current = if outputs.get(k) { mask } else { 0 };
                    let new = (current & and_mask) | (or_mask & !and_mask);
                    outputs.set(k, new & mask != 0);
                }
            }
        }
        Ok(())
    }
}
