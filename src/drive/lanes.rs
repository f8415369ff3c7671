//! The drives of many points of a study on one setpoint stream, shared per axis: each
//! distinct servo of an axis is stepped once and its outputs read by every point that has it.
//!
//! The axes of [`super::Drives`] are independent (one [`AxisServo`] per axis, no coupling):
//! an axis's actual positions are a function of its drive configuration, the interpolation
//! period and its own setpoint stream alone. Points on one setpoint stream whose drive on an
//! axis is the same (the same [`crate::input::drive::AxisDrive`], exact for f64) therefore
//! have the same positions on that axis, and one servo gives them: a study of X and Y
//! backlash steps one Z, B and C servo for all its points, and one X servo per X backlash.
//! The linear twins (the drives without dry friction and backlash, [`super::Drives::new`]
//! with `linear`) are shared the same way, per axis. Every servo is the very model a single
//! run steps, on the same setpoints in the same order: a point's figures are the single
//! run's, bit for bit.
//!
//! The setpoints come a block at a time ([`BLOCK`]); each lane group of servos (up to
//! [`WIDE_LANES`], 16, where the host has AVX-512, else [`NARROW_LANES`], 8, stepped side
//! by side in SIMD lanes: [`super::lane_servo`], [`super::lane_drive`]) or servo
//! stepped alone runs through the block before the next one starts (its state stays in
//! cache), writing its outputs to a buffer of one block, which the points then read.
//! Memory: one block per distinct servo.

use super::lane_drive::DriveLaneGroup;
use super::lane_servo::TwinLanes;
use super::servo::AxisServo;
pub use super::simd::{NARROW_LANES, WIDE_LANES};
use crate::error::Result;
use crate::input::machine::Machine;
use crate::{Axis, AxisVec};

pub use super::lane_step::BLOCK;
use super::lane_step::SLOT;

/// The distinct servos of one axis over the points, and their outputs over the last block.
#[derive(Clone, Debug)]
struct AxisLanes {
    axis: Axis,
    /// The distinct servos; None once one has failed (diverged).
    servos: Vec<Option<AxisServo>>,
    /// The linear twins with a period map and the nonlinear drives with a slope-0 map,
    /// [`WIDE_LANES`] to a lane group where the host has AVX-512, else [`NARROW_LANES`] (the
    /// other width's groups empty); the servos stepped one by one (those of no group).
    wide: Groups<WIDE_LANES>,
    narrow: Groups<NARROW_LANES>,
    alone: Vec<usize>,
    /// Which servo each point has.
    servo_of: Vec<usize>,
    /// Per servo `s`, [`BLOCK`] entries from `s · SLOT`: actual position (mm, deg) and
    /// following error after each setpoint of the last block (the following errors only
    /// for the nonlinear drives).
    actual: Vec<f64>,
    following_error: Vec<f64>,
    /// Per servo, the setpoints of the last block it completed (fewer than the block's when
    /// it failed in it; 0 once failed).
    completed: Vec<usize>,
    /// Lane periods the groups stepped so far, and those of them handed to the scalar servo.
    lane_periods: (u64, u64),
}

/// One width's lane groups of an axis: twins or drives (the other kind's list empty).
#[derive(Clone, Debug)]
struct Groups<const W: usize> {
    twins: Vec<TwinLanes<W>>,
    drives: Vec<DriveLaneGroup<W>>,
}

impl<const W: usize> Groups<W> {
    /// No groups (the width the host does not step).
    fn none() -> Groups<W> {
        Groups {
            twins: Vec::new(),
            drives: Vec::new(),
        }
    }

    /// The groups of `servos` (the linear twins with `linear`), `W` lanes to a group, and
    /// the servos that step alone.
    fn new(servos: &[Option<AxisServo>], linear: bool) -> (Groups<W>, Vec<usize>) {
        let none = Groups::none();
        if linear {
            let (twins, alone) = lane_groups::<W, _>(servos, TwinLanes::new);
            (Groups { twins, ..none }, alone)
        } else {
            let (drives, alone) = lane_groups::<W, _>(servos, DriveLaneGroup::new);
            (Groups { drives, ..none }, alone)
        }
    }

    /// Steps the groups' live servos of `all` through `setpoints` (at `times_s`), their
    /// outputs to `out`; the lane periods stepped and those handed to the scalar servo.
    #[inline(always)]
    fn step_block(
        &mut self,
        all: &mut [Option<AxisServo>],
        axis: Axis,
        (setpoints, times_s): (&[AxisVec], &[f64]),
        out: (&mut [f64], &mut [f64], &mut [usize]),
    ) -> (u64, u64) {
        let (actual, following_error, completed) = out;
        let mut counts = (0, 0);
        for group in &mut self.twins {
            let (stepped, handed_back) =
                group.step_block(all, axis, setpoints, times_s, actual, completed);
            counts = (counts.0 + stepped, counts.1 + handed_back);
        }
        for group in &mut self.drives {
            let (stepped, handed_back) = group.step_block(
                all,
                axis,
                setpoints,
                times_s,
                actual,
                following_error,
                completed,
            );
            counts = (counts.0 + stepped, counts.1 + handed_back);
        }
        counts
    }
}

impl AxisLanes {
    /// The servos of `axis` for `machines`, at rest at `position` (mm, deg); with `linear`,
    /// their linear twins; in lane groups of [`WIDE_LANES`] with `wide`.
    fn new(
        machines: &[&Machine],
        (axis, position): (Axis, f64),
        linear: bool,
        wide: bool,
    ) -> Result<AxisLanes> {
        let mut keys: Vec<String> = Vec::new();
        let mut servos = Vec::new();
        let mut servo_of = Vec::with_capacity(machines.len());
        for machine in machines {
            let drive = machine.drive(axis);
            let drive = if linear { drive.linear_twin() } else { drive };
            let period = machine.interpolation_period_s;
            // The debug form is exact for f64 (the shortest text that reads back the same).
            let key = format!("{period:?} {drive:?}");
            let index = match keys.iter().position(|k| *k == key) {
                Some(i) => i,
                None => {
                    keys.push(key);
                    servos.push(Some(AxisServo::new(&drive, period, position)?));
                    servos.len() - 1
                }
            };
            servo_of.push(index);
        }
        let n = servos.len();
        let (wide_groups, narrow, alone) = if wide {
            let (groups, alone) = Groups::new(&servos, linear);
            (groups, Groups::none(), alone)
        } else {
            let (groups, alone) = Groups::new(&servos, linear);
            (Groups::none(), groups, alone)
        };
        Ok(AxisLanes {
            axis,
            servos,
            wide: wide_groups,
            narrow,
            alone,
            servo_of,
            actual: vec![0.0; n * SLOT],
            following_error: if linear {
                Vec::new()
            } else {
                vec![0.0; n * SLOT]
            },
            completed: vec![0; n],
            lane_periods: (0, 0),
        })
    }

    /// Steps every live servo through `setpoints` (at most [`BLOCK`]), reached at `times_s`,
    /// servo after servo: the nonlinear drives with [`AxisServo::advance`], the twins with
    /// [`AxisServo::advance_twin`], as [`super::Drives`] steps them; the lane groups of
    /// `W` lanes (`W` the width the groups were made with).
    #[inline(always)]
    fn step_block_inline<const W: usize>(
        &mut self,
        setpoints: &[AxisVec],
        times_s: &[f64],
        linear: bool,
    ) {
        let a = self.axis;
        let block = (setpoints, times_s);
        let out = (
            &mut self.actual[..],
            &mut self.following_error[..],
            &mut self.completed[..],
        );
        let counts = match W {
            WIDE_LANES => self.wide.step_block(&mut self.servos, a, block, out),
            _ => self.narrow.step_block(&mut self.servos, a, block, out),
        };
        self.lane_periods = (
            self.lane_periods.0 + counts.0,
            self.lane_periods.1 + counts.1,
        );
        for &s in &self.alone {
            let slot = &mut self.servos[s];
            let Some(servo) = slot.as_mut() else {
                self.completed[s] = 0;
                continue;
            };
            let actual = &mut self.actual[s * SLOT..s * SLOT + BLOCK];
            let mut done = 0;
            for (j, (q, &t)) in setpoints.iter().zip(times_s).enumerate() {
                let stepped = if linear {
                    servo.advance_twin(q[a], t)
                } else {
                    servo.advance(q[a], t)
                };
                if stepped.is_err() {
                    break;
                }
                actual[j] = servo.actual();
                if !linear {
                    self.following_error[s * SLOT + j] = servo.following_error();
                }
                done = j + 1;
            }
            if done < setpoints.len() {
                *slot = None;
            }
            self.completed[s] = done;
        }
    }

    /// Setpoints of the last block point `i`'s servo completed.
    #[inline(always)]
    fn completed_by(&self, i: usize) -> usize {
        self.completed[self.servo_of[i]]
    }
}

/// Fewest servos a lane group steps: a group costs its whole vectors whatever its lanes,
/// so one or two servos step faster on their own.
const MIN_LANES: usize = 3;

/// The servos of `servos` that `group` takes, in lane groups of `W` (the last one
/// ragged, of at least [`MIN_LANES`]), and the others.
fn lane_groups<const W: usize, G>(
    servos: &[Option<AxisServo>],
    group: impl Fn(&[Option<AxisServo>], &[usize]) -> Option<G>,
) -> (Vec<G>, Vec<usize>) {
    let (taken, mut alone): (Vec<usize>, Vec<usize>) =
        (0..servos.len()).partition(|&s| group(servos, &[s]).is_some());
    let mut groups = Vec::new();
    for lanes in taken.chunks(W) {
        if lanes.len() < MIN_LANES {
            alone.extend_from_slice(lanes);
        } else {
            groups.push(group(servos, lanes).expect("every lane was taken alone"));
        }
    }
    (groups, alone)
}

/// The drives and linear twins of several points, shared per axis.
#[derive(Clone, Debug)]
pub struct DriveLanes {
    points: usize,
    /// Lane groups of [`WIDE_LANES`] (stepped by the AVX-512 code), else [`NARROW_LANES`].
    wide: bool,
    /// Per machine axis, the points' drives and their twins.
    drives: Vec<AxisLanes>,
    twins: Vec<AxisLanes>,
    /// Per point, one entry per machine axis: where its outputs are in that axis's buffers.
    slots: Vec<Slot>,
}

/// Where one point's outputs on one axis are: the axis, and the first entries of its
/// drive's and its twin's outputs in their buffers.
#[derive(Clone, Copy, Debug)]
struct Slot {
    axis: Axis,
    drive: usize,
    twin: usize,
}

impl DriveLanes {
    /// The drives of `machines` (one per point, all with the same axes) at rest at `q`.
    /// In lane groups of [`WIDE_LANES`] where the host has AVX-512, else [`NARROW_LANES`].
    pub fn new(machines: &[&Machine], q: &AxisVec) -> Result<DriveLanes> {
        DriveLanes::with_width(machines, q, wide_host())
    }

    /// The same in lane groups of [`NARROW_LANES`] whatever the host (the width and code of
    /// a host without AVX-512; for tests of both widths on one host).
    pub fn narrow(machines: &[&Machine], q: &AxisVec) -> Result<DriveLanes> {
        DriveLanes::with_width(machines, q, false)
    }

    fn with_width(machines: &[&Machine], q: &AxisVec, wide: bool) -> Result<DriveLanes> {
        let axes = machines.first().map_or(&[][..], |m| m.axes());
        let lanes = |linear| {
            axes.iter()
                .map(|&a| AxisLanes::new(machines, (a, q[a]), linear, wide))
                .collect::<Result<Vec<_>>>()
        };
        let (drives, twins) = (lanes(false)?, lanes(true)?);
        let slots = (0..machines.len())
            .flat_map(|i| {
                drives.iter().zip(&twins).map(move |(d, t)| Slot {
                    axis: d.axis,
                    drive: d.servo_of[i] * SLOT,
                    twin: t.servo_of[i] * SLOT,
                })
            })
            .collect();
        Ok(DriveLanes {
            points: machines.len(),
            wide,
            drives,
            twins,
            slots,
        })
    }

    /// Servos a lane group steps side by side: [`WIDE_LANES`] or [`NARROW_LANES`].
    pub fn lane_width(&self) -> usize {
        if self.wide {
            WIDE_LANES
        } else {
            NARROW_LANES
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.points == 0
    }

    /// Distinct servos stepped per axis, drives and twins: `(axis, drives, twins)`.
    pub fn distinct(&self) -> Vec<(Axis, usize, usize)> {
        self.drives
            .iter()
            .zip(&self.twins)
            .map(|(d, t)| (d.axis, d.servos.len(), t.servos.len()))
            .collect()
    }

    /// Periods the lane groups stepped so far, `[drives, twins]`, each with how many of
    /// them were handed to the scalar servo (a lane that left the shared map for that period).
    pub fn lane_periods(&self) -> [(u64, u64); 2] {
        let sum = |lanes: &[AxisLanes]| {
            lanes.iter().fold((0, 0), |(a, b), l| {
                (a + l.lane_periods.0, b + l.lane_periods.1)
            })
        };
        [sum(&self.drives), sum(&self.twins)]
    }

    /// Periods the drives' lane groups stepped by substeps in their lanes so far (of the
    /// drives' periods [`DriveLanes::lane_periods`] counts, none of those handed to the
    /// scalar servo).
    pub fn lane_substep_periods(&self) -> u64 {
        let wide = self.drives.iter().flat_map(|l| &l.wide.drives);
        let narrow = self.drives.iter().flat_map(|l| &l.narrow.drives);
        wide.map(DriveLaneGroup::substep_periods).sum::<u64>()
            + narrow.map(DriveLaneGroup::substep_periods).sum::<u64>()
    }

    /// Steps every distinct drive and twin through `setpoints` (at most [`BLOCK`]), the
    /// `j`-th reached at `times_s[j]`; read each point's outputs with
    /// [`DriveLanes::outputs`]. A servo that fails stops there, and with it every point
    /// that has it.
    pub fn step_block(&mut self, setpoints: &[AxisVec], times_s: &[f64]) {
        assert!(setpoints.len() <= BLOCK && times_s.len() == setpoints.len());
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: the groups are wide only where the CPU has AVX-512F (`wide_host`).
            return unsafe { self.step_block_avx512(setpoints, times_s) };
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX, checked at run time just above.
            return unsafe { self.step_block_avx(setpoints, times_s) };
        }
        self.step_block_inline(setpoints, times_s)
    }

    /// [`DriveLanes::step_block`] compiled for AVX-512: a lane group's vectors of
    /// [`WIDE_LANES`] f64 in two registers (Rust never fuses a multiplication and an
    /// addition, so the arithmetic is still the same whatever the vector width).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn step_block_avx512(&mut self, setpoints: &[AxisVec], times_s: &[f64]) {
        self.step_groups::<WIDE_LANES>(setpoints, times_s)
    }

    /// [`DriveLanes::step_block`] compiled for AVX, as [`super::Drives::step_into`] is (no
    /// FMA: the arithmetic is the same whatever the vector width), [`NARROW_LANES`] lanes.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn step_block_avx(&mut self, setpoints: &[AxisVec], times_s: &[f64]) {
        self.step_groups::<NARROW_LANES>(setpoints, times_s)
    }

    /// [`DriveLanes::step_block`] without AVX, [`NARROW_LANES`] lanes.
    fn step_block_inline(&mut self, setpoints: &[AxisVec], times_s: &[f64]) {
        self.step_groups::<NARROW_LANES>(setpoints, times_s)
    }

    /// Every axis's drives, then twins, through the block, by their groups of `W` lanes.
    #[inline(always)]
    fn step_groups<const W: usize>(&mut self, setpoints: &[AxisVec], times_s: &[f64]) {
        for lanes in &mut self.drives {
            lanes.step_block_inline::<W>(setpoints, times_s, false);
        }
        for lanes in &mut self.twins {
            lanes.step_block_inline::<W>(setpoints, times_s, true);
        }
    }

    /// Setpoints of the last block for which point `i` has outputs: all of them, or fewer
    /// when one of its drives or twins failed in the block (0 once failed).
    pub fn completed(&self, i: usize) -> usize {
        self.drives
            .iter()
            .chain(&self.twins)
            .map(|lanes| lanes.completed_by(i))
            .min()
            .unwrap_or(usize::MAX)
    }

    /// Point `i`'s outputs over the last block, one entry per driven axis: the axis, then
    /// the actual positions and following errors of its drive (mm, deg) and the actual
    /// positions of its twin, one per setpoint (read the first [`DriveLanes::completed`]).
    pub fn outputs(&self, i: usize) -> impl Iterator<Item = (Axis, &[f64], &[f64], &[f64])> {
        let n = self.drives.len();
        let slots = &self.slots[i * n..(i + 1) * n];
        slots
            .iter()
            .zip(&self.drives)
            .zip(&self.twins)
            .map(|((slot, drive), twin)| {
                (
                    slot.axis,
                    &drive.actual[slot.drive..slot.drive + BLOCK],
                    &drive.following_error[slot.drive..slot.drive + BLOCK],
                    &twin.actual[slot.twin..slot.twin + BLOCK],
                )
            })
    }
}

/// Whether this host steps lane groups of [`WIDE_LANES`]: it has AVX-512F. With AVX alone,
/// 16 lanes (four registers a vector) ran 8-9 % slower than 8 (docs/performance.md,
/// session 29).
fn wide_host() -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        return true;
    }
    false
}
