//! One internal step of the emulator: faults, table rotation, box motion, hazards,
//! arrivals and sensors. No allocation in the steady state.

use super::model::{Body, END, Link, START, TablePos};
use super::{BoxState, Emulator, Hazard, HazardKind, Place};
use crate::symbols::Space;

/// Velocity factor from the axis of a part, across its end `e`, into the axis of the
/// part joined at `q_end`: +1 when the axes continue, -1 when they face each other.
#[inline]
fn factor(e: u8, q_end: u8) -> i64 {
    if e == q_end { -1 } else { 1 }
}

/// Length of a box beyond end `e` of a part of length `len` (negative when inside).
#[inline]
fn overhang(b: &Body, e: u8, len: i64) -> i64 {
    if e == END {
        b.c + b.half - len
    } else {
        b.half - b.c
    }
}

impl Emulator {
    /// Advances one internal step. Sensors are computed only when `sense` is set: the
    /// caller asks for them on the last step of a PLC period, or on every step when a
    /// fault waits for a condition over the sensors.
    pub(super) fn tick(&mut self, sense: bool) {
        self.now += self.step_ms;
        if !self.faults.is_empty() {
            self.update_faults();
        }
        let act = self.acting();
        self.rotate(act);
        self.drive(act);
        self.move_boxes();
        self.transfer();
        self.check_hazards();
        self.arrivals();
        if sense || self.has_conditions {
            self.compute_sensors();
        }
    }

    /// How many internal steps (at most `max`) can be taken at once: none of them can do
    /// anything but move every box straight on its part. That holds while no fault is
    /// active, no box waits at the source and no arrival is due, the turntable rests at
    /// the position its command drives it to, and every box lies inside its part with
    /// room to spare (so it can neither reach an end, a joint or the table edge, nor
    /// touch a box on another part; boxes on one part move together). Returns 1 when
    /// that is not the case.
    pub(super) fn quiet_steps(&mut self, max: u64) -> u64 {
        if max < 2 || !self.faults.is_empty() || !self.pending.is_empty() || self.no_skip {
            return 1;
        }
        let act = self.acting();
        let t = &self.layout.table;
        let target = if act >> (self.table + 2) & 1 == 1 {
            i64::from(t.unloading_mdeg) * 1000
        } else {
            i64::from(t.loading_mdeg) * 1000
        };
        if self.angle != target && self.unpowered() >> (self.table + 2) & 1 == 0 {
            return 1;
        }
        self.drive(act);
        let mut k = max;
        if let Some((at, _)) = self.next_arrival {
            // The arrival is taken in the step whose time reaches `at`.
            let steps_before = at.saturating_sub(self.now) / self.step_ms.max(1);
            k = k.min(steps_before.saturating_sub(1));
        }
        for b in &self.bodies {
            let p = b.part as usize;
            let room = (b.c - b.half).min(self.parts[p].len - b.c - b.half);
            if room <= 0 {
                return 1;
            }
            let v = self.vel[p].abs();
            if v > 0 {
                k = k.min(u64::try_from((room - 1) / v).unwrap_or(0));
            }
            if k < 2 {
                return 1;
            }
        }
        k
    }

    /// Takes `k` quiet steps at once (see [`Self::quiet_steps`]): the same positions as
    /// `k` single steps.
    pub(super) fn take_quiet_steps(&mut self, k: u64) {
        self.now += k * self.step_ms;
        let k = i64::try_from(k).unwrap_or(0);
        for b in &mut self.bodies {
            b.c += self.vel[b.part as usize] * k;
            b.slip = 0;
        }
        self.moving = false;
        self.rot_dir = 0;
    }

    fn update_faults(&mut self) {
        if self.has_conditions {
            let frame = &mut self.frame;
            for (k, &i) in self.sensor_plant.iter().enumerate() {
                frame
                    .now_mut(Space::Input)
                    .set(i, self.sensor_mask >> k & 1 == 1);
            }
            for (r, &o) in self.role_plant.iter().enumerate() {
                frame.now_mut(Space::Output).set(o, self.cmd >> r & 1 == 1);
            }
        }
        let mut changed = false;
        for f in &mut self.faults {
            changed |= f.update(self.now, &self.frame);
        }
        if self.has_conditions {
            self.frame.shift();
        }
        if changed {
            self.refresh_overrides();
        }
    }

    /// Recomputes the combined effect of the active faults.
    pub(super) fn refresh_overrides(&mut self) {
        self.driven = None;
        self.overrides = Default::default();
        self.slow.iter_mut().for_each(|s| *s = 100);
        for f in &self.faults {
            f.apply(&mut self.overrides, &mut self.slow);
        }
        self.sensor_mask =
            (self.sensor_raw & !self.overrides.sensor_off) | self.overrides.sensor_on;
    }

    fn rotate(&mut self, act: u64) {
        let t = &self.layout.table;
        let load = i64::from(t.loading_mdeg) * 1000;
        let unload = i64::from(t.unloading_mdeg) * 1000;
        let a4 = act >> (self.table + 2) & 1 == 1;
        let target = if a4 { unload } else { load };
        let dir = (target - self.angle).signum();
        let ov = self.overrides.table;
        // Without its supply (a safety valve released) the table stays where it is,
        // whatever its valve says: it does not return on its own.
        let blocked = ov & 4 != 0
            || self.unpowered() >> (self.table + 2) & 1 == 1
            || (ov & 1 != 0 && self.angle == load)
            || (ov & 2 != 0 && self.angle == unload);
        let old = self.angle;
        if dir == 0 {
            self.rot_dir = 0;
        } else if !blocked {
            if dir != self.rot_dir {
                let base = if dir > 0 {
                    t.out_speed_udeg_ms
                } else {
                    t.back_speed_udeg_ms
                };
                let v = t.speed_variation_ppm.max(0);
                let r = self.rng_table.below(2 * v as u64 + 1) as i64 - v;
                self.rot_speed = (base * (1_000_000 + r) / 1_000_000).max(1);
                self.rot_dir = dir;
            }
            let d = self.rot_speed * self.step_ms as i64;
            self.angle = if dir > 0 {
                (self.angle + d).min(target)
            } else {
                (self.angle - d).max(target)
            };
        }
        self.moving = self.angle != old;
        self.update_links(false);
    }

    /// Recomputes which ends are joined, after the table position class changed.
    pub(super) fn update_links(&mut self, force: bool) {
        let t = &self.layout.table;
        let tol = i64::from(t.dock_tolerance_mdeg.max(0)) * 1000;
        let pos = if (self.angle - i64::from(t.loading_mdeg) * 1000).abs() <= tol {
            TablePos::Load
        } else if (self.angle - i64::from(t.unloading_mdeg) * 1000).abs() <= tol {
            TablePos::Unload
        } else {
            TablePos::Other
        };
        if pos == self.pos && !force {
            return;
        }
        self.pos = pos;
        for (p, part) in self.parts.iter().enumerate() {
            self.near[p] = 1 << p;
            for e in 0..2 {
                let k = &part.ends[e];
                self.links[p][e] = k.fixed.or(match pos {
                    TablePos::Load => k.at_load,
                    TablePos::Unload => k.at_unload,
                    TablePos::Other => None,
                });
                if let Some(q) = self.links[p][e] {
                    self.near[p] |= 1 << q.part;
                }
            }
        }
    }

    /// Surface velocity of each part along its axis, µm per step.
    fn drive(&mut self, act: u64) {
        // Velocities depend on the command and the slow-down faults only.
        if self.faults.is_empty() && self.driven == Some(act) {
            return;
        }
        self.driven = Some(act);
        let n = self.table;
        let step = self.step_ms as i64;
        for (i, p) in self.parts.iter().enumerate() {
            self.vel[i] = if i == n {
                let plus = (act >> n & 1) as i64 * i64::from(self.slow[n]);
                let minus = (act >> (n + 1) & 1) as i64 * i64::from(self.slow[n + 1]);
                (plus - minus) * p.speed * step / 100
            } else {
                (act >> i & 1) as i64 * p.speed * step * i64::from(self.slow[i]) / 100
            };
        }
    }

    /// Centre of a box on `part_j` at `cj`, in the axis of part `p`, with the velocity factor.
    #[inline]
    fn map_into(&self, part_j: u8, cj: i64, p: u8) -> Option<(i64, i64)> {
        if part_j == p {
            return Some((cj, 1));
        }
        for e in [START, END] {
            if let Some(q) = self.links[p as usize][e as usize]
                && q.part == part_j
            {
                let len_j = self.parts[part_j as usize].len;
                let dj = if q.end == START { cj } else { len_j - cj };
                let c = if e == END {
                    self.parts[p as usize].len + dj
                } else {
                    -dj
                };
                return Some((c, factor(e, q.end)));
            }
        }
        None
    }

    fn move_boxes(&mut self) {
        let margin = self.layout.straddle_margin_mm * 1000;
        self.scratch.clear();
        for b in &self.bodies {
            let len = self.parts[b.part as usize].len;
            let mut v = self.vel[b.part as usize];
            if v == 0 {
                for e in [START, END] {
                    if overhang(b, e, len) > margin
                        && let Some(q) = self.links[b.part as usize][e as usize]
                    {
                        v = self.vel[q.part as usize] * factor(e, q.end);
                        if v != 0 {
                            break;
                        }
                    }
                }
            }
            self.scratch.push((v, b.c + v, -1));
        }
        let n = self.bodies.len();
        for _ in 0..4 {
            let mut changed = false;
            for i in 0..n {
                let (v, ci, _) = self.scratch[i];
                if v == 0 {
                    continue;
                }
                let bi = self.bodies[i];
                let near = self.near[bi.part as usize];
                for j in 0..n {
                    let bj = &self.bodies[j];
                    if i == j || near >> bj.part & 1 == 0 {
                        continue;
                    }
                    let Some((cj, _)) = self.map_into(bj.part, self.scratch[j].1, bi.part) else {
                        continue;
                    };
                    let reach = bi.half + bj.half;
                    let d = cj - self.scratch[i].1;
                    if d.signum() == v.signum() && d.abs() < reach {
                        let mut target = cj - v.signum() * reach;
                        if (target - bi.c) * v.signum() < 0 {
                            target = bi.c;
                        }
                        if target != ci {
                            changed = true;
                        }
                        self.scratch[i].1 = target;
                        self.scratch[i].2 = j as i64;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        for i in 0..n {
            let (v, ci, blk) = self.scratch[i];
            if blk >= 0 && ci - self.bodies[i].c != v {
                let j = blk as usize;
                let bj = self.bodies[j];
                let f = self
                    .map_into(bj.part, bj.c, self.bodies[i].part)
                    .map_or(0, |m| m.1);
                let dj = (self.scratch[j].1 - bj.c) * f;
                if dj * v.signum() < v.abs() && self.first(i, HazardKind::Collision) {
                    let (pi, pj) = (self.bodies[i].part as usize, bj.part as usize);
                    let place = format!("{} (against box {})", self.parts[pi].name, bj.id);
                    let mut el = self.parts[pi].actuators.clone();
                    if pj != pi {
                        el.extend(self.parts[pj].actuators.iter().cloned());
                    }
                    let at = Place::Against {
                        part: self.parts[pi].id.clone(),
                        item: bj.id,
                    };
                    self.report(i, HazardKind::Collision, (place, at), el);
                }
            }
        }
        for (b, s) in self.bodies.iter_mut().zip(&self.scratch) {
            b.c = s.1;
        }
    }

    /// Moves boxes whose centre left their part: to the joined part, an elevator, or the floor.
    fn transfer(&mut self) {
        let mut i = 0;
        while i < self.bodies.len() {
            let b = self.bodies[i];
            let len = self.parts[b.part as usize].len;
            let (e, over) = if b.c > len {
                (END, b.c - len)
            } else if b.c < 0 {
                (START, -b.c)
            } else {
                i += 1;
                continue;
            };
            let end = &self.parts[b.part as usize].ends[e as usize];
            if let Some(q) = self.links[b.part as usize][e as usize] {
                let lq = self.parts[q.part as usize].len;
                let body = &mut self.bodies[i];
                body.part = q.part;
                body.c = if q.end == START { over } else { lq - over };
                i += 1;
            } else if let Some(side) = end.sink {
                let exit = &self.parts[b.part as usize].id;
                match self.stats.delivered.get_mut(exit) {
                    Some(n) => *n += 1,
                    None => {
                        self.stats.delivered.insert(exit.clone(), 1);
                    }
                }
                let v = self.view(&b, BoxState::Delivered(side));
                self.done.push((v, self.now));
                self.bodies.remove(i);
            } else {
                if self.first(i, HazardKind::Dropped) {
                    let p = &self.parts[b.part as usize];
                    let place = format!(
                        "{} of the {}",
                        if e == END { "end" } else { "start" },
                        p.name
                    );
                    let mut el = p.actuators.clone();
                    if b.part as usize == self.table {
                        el.push(self.layout.table.rotate_actuator.clone());
                    }
                    let at = Place::Off {
                        part: p.id.clone(),
                        end: e == END,
                    };
                    self.report(i, HazardKind::Dropped, (place, at), el);
                }
                let v = self.view(&self.bodies[i], BoxState::Fallen);
                self.done.push((v, self.now));
                self.bodies.remove(i);
            }
        }
    }

    fn check_hazards(&mut self) {
        let margin = self.layout.straddle_margin_mm * 1000;
        let shear = self.layout.shear_margin_mm * 1000;
        // Within the docking tolerance the guides accept the misalignment: the table is
        // joined to the conveyors and a straddling box is not sheared.
        let rotating = self.pos == TablePos::Other;
        let tolerance = self.layout.push_tolerance_mm.max(0) * 1000;
        for i in 0..self.bodies.len() {
            let b = self.bodies[i];
            let p = b.part as usize;
            let mut pushing = 0;
            for e in [START, END] {
                let over = overhang(&b, e, self.parts[p].len);
                if over <= 0 {
                    continue;
                }
                if rotating
                    && over > shear
                    && self.parts[p].ends[e as usize].table_side
                    && self.first(i, HazardKind::Sheared)
                {
                    let place = format!("edge of the {}", self.layout.table.name);
                    let mut el = vec![self.layout.table.rotate_actuator.clone()];
                    el.extend(self.parts[p].actuators.iter().cloned());
                    let at = Place::Edge {
                        part: self.layout.table.id.clone(),
                    };
                    self.report(i, HazardKind::Sheared, (place, at), el);
                }
                let Some(q) = self.links[p][e as usize] else {
                    continue;
                };
                if over <= margin || 2 * b.half - over <= margin {
                    continue;
                }
                let out = if e == END { 1 } else { -1 };
                let vp = self.vel[p] * out;
                let vq = self.vel[q.part as usize] * if q.end == START { 1 } else { -1 };
                if (vp > 0 && vq <= 0) || (vq < 0 && vp >= 0) {
                    // The driving surface slides under the box held by the other one:
                    // damage once it has slid `push_tolerance_mm` without a break.
                    pushing = pushing.max((vp - vq).abs());
                    if self.bodies[i].slip + pushing > tolerance
                        && self.first(i, HazardKind::PushedAgainstStopped)
                    {
                        self.report_pushed(i, q);
                    }
                }
            }
            let b = &mut self.bodies[i];
            b.slip = if pushing > 0 { b.slip + pushing } else { 0 };
        }
    }

    fn report_pushed(&mut self, i: usize, q: Link) {
        let p = self.bodies[i].part as usize;
        let (a, b) = (&self.parts[p], &self.parts[q.part as usize]);
        let place = format!("between the {} and the {}", a.name, b.name);
        let mut el = a.actuators.clone();
        el.extend(b.actuators.iter().cloned());
        let at = Place::Between {
            part: a.id.clone(),
            other: b.id.clone(),
        };
        self.report(i, HazardKind::PushedAgainstStopped, (place, at), el);
    }

    /// True when box `i` has not yet reported `kind`.
    #[inline]
    fn first(&self, i: usize, kind: HazardKind) -> bool {
        self.bodies[i].reported & (1 << kind as u8) == 0
    }

    fn report(
        &mut self,
        i: usize,
        kind: HazardKind,
        (place, at): (String, Place),
        elements: Vec<String>,
    ) {
        let b = &mut self.bodies[i];
        b.reported |= 1 << kind as u8;
        if !b.damaged {
            b.damaged = true;
            self.stats.damaged += 1;
        }
        self.hazards.push(Hazard {
            time_ms: self.now,
            kind,
            place,
            at,
            elements,
            box_id: b.id,
        });
    }

    fn arrivals(&mut self) {
        while let Some((t, size)) = self.next_arrival {
            if t > self.now {
                break;
            }
            if self.pending.len() < 64 {
                self.pending.push_back(size);
            }
            self.arrival_k += 1;
            self.plan_next();
        }
        let Some(&size) = self.pending.front() else {
            return;
        };
        let Some(src) = self.source_part else { return };
        let len = self.layout.dims(size).length_mm * 1000;
        let free = self
            .bodies
            .iter()
            .all(|b| b.part as usize != src || b.c - b.half >= len + 10_000);
        if free {
            self.pending.pop_front();
            self.spawn(src, len / 2, size);
        }
    }

    /// Sensor values from box positions and table angle, then faults.
    pub(super) fn compute_sensors(&mut self) {
        let mut m = 0u64;
        for &(k, lo, hi) in &self.angles {
            if (lo..=hi).contains(&self.angle) {
                m |= 1 << k;
            }
        }
        for b in &self.bodies {
            let p = b.part as usize;
            m |= self.probe(p, b.c, b);
            for e in [START, END] {
                if overhang(b, e, self.parts[p].len) <= 0 {
                    continue;
                }
                if let Some(q) = self.links[p][e as usize] {
                    let dist = if e == END {
                        self.parts[p].len - b.c
                    } else {
                        b.c
                    };
                    let cq = if q.end == START {
                        -dist
                    } else {
                        self.parts[q.part as usize].len + dist
                    };
                    m |= self.probe(q.part as usize, cq, b);
                }
            }
        }
        self.sensor_raw = m;
        self.sensor_mask = (m & !self.overrides.sensor_off) | self.overrides.sensor_on;
    }

    #[inline]
    fn probe(&self, part: usize, c: i64, b: &Body) -> u64 {
        let mut m = 0;
        for pr in &self.probes[part] {
            if (c - pr.at).abs() <= b.half && b.height_mm >= pr.min_height {
                m |= 1 << pr.sensor;
            }
        }
        m
    }
}
