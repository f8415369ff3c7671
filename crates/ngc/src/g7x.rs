//! The lathe roughing and finishing cycles G70, G71 (.1 .2) and G72 (.1 .2) of LinuxCNC
//! 2.9: the geometry of `interp_g7x.cc`, ported step by step (rs274 is the reference the
//! conformance test holds it to).
//!
//! A profile is a chain of lines and arcs in the ZX plane, held as complex numbers
//! `z + i·x` (program units, X as a radius). The cycle normalises it (rotates it by 90° for
//! G72 or when it is not monotonic, mirrors it so that Z and X decrease along it), offsets
//! it by the finishing allowance D, and then:
//!
//! - G70: cuts the offset profile P times, from distance D down to E (`(n-1)(D-E)/P + E`
//!   for n = P .. 1), each pass a rapid to the start, a rapid to the first point, then the
//!   profile.
//! - G71/G72: roughs the stock away in layers I deep: each layer feeds along Z until it
//!   meets the profile, escapes by R (at 45°), rapids back and steps down; pockets (where
//!   the profile climbs again) are cut after the profile (G71.1: no pockets, G71.2: only the
//!   pockets).
//!
//! The moves come out through [`Out`] in the normalised frame and are mapped back
//! (`flip_state`: bit 1 mirrors Z, bit 2 mirrors X, bit 4 rotates) before they are emitted.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A complex number `re + i·im`: `re` is Z, `im` is X.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct C {
    pub re: f64,
    pub im: f64,
}

const fn c(re: f64, im: f64) -> C {
    C { re, im }
}

const I: C = c(0.0, 1.0);

impl C {
    fn conj(self) -> C {
        c(self.re, -self.im)
    }
    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
    pub(crate) fn norm(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
}

impl Add for C {
    type Output = C;
    fn add(self, o: C) -> C {
        c(self.re + o.re, self.im + o.im)
    }
}
impl Sub for C {
    type Output = C;
    fn sub(self, o: C) -> C {
        c(self.re - o.re, self.im - o.im)
    }
}
impl Neg for C {
    type Output = C;
    fn neg(self) -> C {
        c(-self.re, -self.im)
    }
}
impl Mul for C {
    type Output = C;
    fn mul(self, o: C) -> C {
        c(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}
impl Mul<C> for f64 {
    type Output = C;
    fn mul(self, o: C) -> C {
        c(self * o.re, self * o.im)
    }
}
impl Div for C {
    type Output = C;
    fn div(self, o: C) -> C {
        let d = o.norm();
        c(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}
impl Div<f64> for C {
    type Output = C;
    fn div(self, o: f64) -> C {
        c(self.re / o, self.im / o)
    }
}

/// One move of a cycle, in program units (`z + i·x`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Out {
    Feed(C),
    Rapid(C),
    Arc { ccw: bool, center: C, end: C },
}

/// A profile element: a line or an arc (`ccw`: G3). `corner` marks the fillet (an arc,
/// profile word A) or chamfer (a line, C) LinuxCNC inserts at a corner: it starts with
/// zero length and `finish` its size, and is fitted between its neighbours by
/// [`Profile::do_finish`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Seg {
    Line {
        s: C,
        e: C,
        finish: f64,
        corner: bool,
    },
    Arc {
        ccw: bool,
        s: C,
        c: C,
        e: C,
        finish: f64,
        corner: bool,
    },
}

type R<T> = Result<T, String>;

/// LinuxCNC's `tolerance` in interp_g7x.cc.
const TOL: f64 = 1e-6;

impl Seg {
    pub fn line(s: C, e: C) -> Seg {
        Seg::Line {
            s,
            e,
            finish: 0.0,
            corner: false,
        }
    }
    pub fn arc(ccw: bool, s: C, c: C, e: C) -> Seg {
        Seg::Arc {
            ccw,
            s,
            c,
            e,
            finish: 0.0,
            corner: false,
        }
    }
    /// A fillet of radius `d` at the corner `l`.
    pub fn fillet(d: f64, l: C) -> Seg {
        Seg::Arc {
            ccw: false,
            s: l,
            c: l,
            e: l,
            finish: d,
            corner: true,
        }
    }
    /// A chamfer of size `d` at the corner `l`.
    pub fn chamfer(d: f64, l: C) -> Seg {
        Seg::Line {
            s: l,
            e: l,
            finish: d,
            corner: true,
        }
    }
    fn sp(&mut self) -> &mut C {
        match self {
            Seg::Line { s, .. } | Seg::Arc { s, .. } => s,
        }
    }
    fn ep(&mut self) -> &mut C {
        match self {
            Seg::Line { e, .. } | Seg::Arc { e, .. } => e,
        }
    }
    pub(crate) fn start(&self) -> C {
        match *self {
            Seg::Line { s, .. } | Seg::Arc { s, .. } => s,
        }
    }
    pub(crate) fn end(&self) -> C {
        match *self {
            Seg::Line { e, .. } | Seg::Arc { e, .. } => e,
        }
    }

    fn radius(&self) -> f64 {
        match *self {
            Seg::Line { s, e, .. } => (s - e).abs(),
            Seg::Arc { s, c, e, .. } => (s - e).abs().min((s - c).abs()),
        }
    }

    fn monotonic(&self) -> bool {
        match *self {
            Seg::Line { s, e, .. } => (e - s).re <= 1e-3,
            Seg::Arc {
                ccw,
                s,
                c,
                e,
                finish,
                ..
            } => {
                if finish != 0.0 {
                    return true;
                }
                let (entry, exit, dz) = ((s - c).im, (e - c).im, (e - s).re);
                if ccw {
                    entry >= -1e-3 && exit >= -1e-3 && dz <= -1e-3
                } else {
                    entry <= 1e-3 && exit <= 1e-3 && dz <= -1e-3
                }
            }
        }
    }

    fn map(&mut self, f: impl Fn(C) -> C, flips: bool) {
        match self {
            Seg::Line { s, e, .. } => {
                *s = f(*s);
                *e = f(*e);
            }
            Seg::Arc { ccw, s, c, e, .. } => {
                *s = f(*s);
                *e = f(*e);
                *c = f(*c);
                if flips {
                    *ccw = !*ccw;
                }
            }
        }
    }
    fn flip_imag(&mut self) {
        self.map(C::conj, true);
    }
    fn flip_real(&mut self) {
        self.map(|p| -p.conj(), true);
    }
    fn rotate(&mut self) {
        self.map(|p| -(p * I), false);
    }
    fn shift(&mut self, d: C) {
        self.map(|p| p + d, false);
    }

    fn offset(&mut self, distance: f64) {
        match self {
            Seg::Line { s, e, .. } => {
                let d = I * (distance * (*s - *e) / (*s - *e).abs());
                *s = *s + d;
                *e = *e + d;
            }
            Seg::Arc { ccw, s, c, e, .. } => {
                let r = (*s - *c).abs();
                let factor = (r + if *ccw { 1.0 } else { -1.0 } * distance) / r;
                *s = factor * (*s - *c) + *c;
                *e = factor * (*e - *c) + *c;
            }
        }
    }

    fn on_arc(ccw: bool, s: C, c: C, e: C, p: C) -> bool {
        let a = ((s - c).conj() * (p - c)).im;
        let b = ((e - c).conj() * (p - c)).im;
        if ccw {
            a >= -TOL && b <= TOL
        } else {
            a <= TOL && b >= -TOL
        }
    }

    /// The Z of the points of the element at X = `x`, in LinuxCNC's order.
    fn intersection_z(&self, x: f64, is: &mut Vec<f64>) {
        match *self {
            Seg::Line { s, e, .. } => {
                if s.im.min(e.im) > x + TOL || s.im.max(e.im) < x - TOL {
                    return;
                }
                if (s - e).im.abs() < TOL {
                    is.push(s.re);
                    is.push(e.re);
                } else {
                    is.push((x - s.im) / (e.im - s.im) * (e.re - s.re) + s.re);
                }
            }
            Seg::Arc { ccw, s, c, e, .. } => {
                let r = (s - c).abs();
                let mut q = -(x - r - c.im) * (x + r - c.im);
                if q < -TOL {
                    return;
                }
                if q < 0.0 {
                    q = 0.0;
                }
                let q = q.sqrt();
                let p1 = C {
                    re: c.re + q,
                    im: x,
                };
                if Seg::on_arc(ccw, s, c, e, p1) {
                    is.push(p1.re);
                }
                let p2 = C {
                    re: c.re - q,
                    im: x,
                };
                if Seg::on_arc(ccw, s, c, e, p2) {
                    is.push(p2.re);
                }
            }
        }
    }

    fn intersections(&self, x: f64) -> Vec<f64> {
        let mut is = Vec::new();
        self.intersection_z(x, &mut is);
        is
    }

    fn draw(&self, out: &mut Vec<Out>) {
        match *self {
            Seg::Line { e, .. } => out.push(Out::Feed(e)),
            Seg::Arc { ccw, c, e, .. } => out.push(Out::Arc {
                ccw,
                center: c,
                end: e,
            }),
        }
    }

    /// Top of an arc climbing counter-clockwise past its centre.
    fn arc_top(ccw_end: C, s: C, c: C) -> C {
        if ccw_end.re < c.re {
            C {
                re: c.re,
                im: c.im + (s - c).abs(),
            }
        } else {
            ccw_end
        }
    }

    fn climb(&self, loc: &mut C, out: &mut Vec<Out>) -> R<bool> {
        match *self {
            Seg::Line { s, e, .. } => {
                if e.im + TOL < s.im {
                    return Ok(true);
                }
                if (*loc - s).abs() > TOL {
                    return Err("How did we get here?".into());
                }
                out.push(Out::Feed(e));
                *loc = e;
                Ok(false)
            }
            Seg::Arc { ccw, s, c, e, .. } => {
                if !ccw {
                    if loc.re > c.re {
                        return Ok(true);
                    }
                    if (*loc - e).abs() > 1e-3 {
                        out.push(Out::Arc {
                            ccw,
                            center: c,
                            end: e,
                        });
                    }
                    *loc = e;
                    Ok(false)
                } else {
                    if loc.re < c.re {
                        return Ok(true);
                    }
                    let ep = Seg::arc_top(e, s, c);
                    if (*loc - ep).abs() > 1e-3 {
                        out.push(Out::Arc {
                            ccw,
                            center: c,
                            end: ep,
                        });
                    }
                    *loc = ep;
                    Ok(true)
                }
            }
        }
    }

    fn climb_only(&self, loc: &mut C, out: &mut Vec<Out>) {
        match *self {
            Seg::Line { s, e, .. } => {
                if e.im < s.im {
                    return;
                }
                let is = self.intersections(loc.im);
                let Some(&front) = is.first() else { return };
                loc.re = front;
                out.push(Out::Feed(*loc));
                out.push(Out::Feed(e));
                *loc = e;
            }
            Seg::Arc { ccw, s, c, e, .. } => {
                let is = self.intersections(loc.im);
                if is.is_empty() {
                    return;
                }
                if !ccw {
                    let back = *is.last().expect("not empty");
                    if back > c.re {
                        return;
                    }
                    loc.re = back;
                    out.push(Out::Feed(*loc));
                    if (*loc - e).abs() > 1e-3 {
                        out.push(Out::Arc {
                            ccw,
                            center: c,
                            end: e,
                        });
                    }
                    *loc = e;
                } else {
                    if is[0] < c.re {
                        return;
                    }
                    loc.re = is[0];
                    out.push(Out::Feed(*loc));
                    let ep = Seg::arc_top(e, s, c);
                    if (*loc - ep).abs() > 1e-3 {
                        out.push(Out::Arc {
                            ccw,
                            center: c,
                            end: ep,
                        });
                    }
                    *loc = ep;
                }
            }
        }
    }

    fn dive(&self, loc: &mut C, x: f64, out: &mut Vec<Out>, fast: bool) -> R<bool> {
        match *self {
            Seg::Line { s, e, .. } => {
                if s.im <= e.im + TOL {
                    return Ok(true);
                }
                let mv = |p: C| if fast { Out::Rapid(p) } else { Out::Feed(p) };
                if x < e.im {
                    out.push(mv(e));
                    *loc = e;
                    return Ok(false);
                }
                let is = self.intersections(x);
                let Some(&front) = is.first() else {
                    return Err("x too large in straight dive".into());
                };
                let ep = C { re: front, im: x };
                out.push(mv(ep));
                *loc = ep;
                Ok(false)
            }
            Seg::Arc { ccw, c, e, .. } => {
                if (*loc - e).abs() < TOL || (*loc - e).re <= TOL {
                    *loc = e;
                    return Ok(false);
                }
                let mut is = self.intersections(x);
                if is.is_empty() {
                    self.intersection_z(x - TOL, &mut is);
                }
                let arc = |end: C| Out::Arc {
                    ccw,
                    center: c,
                    end,
                };
                if ccw {
                    if loc.re - TOL > c.re {
                        return Ok(true);
                    }
                    match is.last() {
                        Some(&back) if back <= c.re => {
                            let ep = C { re: back, im: x };
                            out.push(arc(ep));
                            *loc = ep;
                        }
                        _ => {
                            out.push(arc(e));
                            *loc = e;
                        }
                    }
                } else {
                    if loc.re <= c.re {
                        return Ok(true);
                    }
                    match is.first() {
                        None => {
                            out.push(arc(e));
                            *loc = e;
                        }
                        // Hit on the back side only: the pocket steps down.
                        Some(&front) if front < c.re => {}
                        Some(&front) => {
                            let ep = C { re: front, im: x };
                            out.push(arc(ep));
                            *loc = ep;
                        }
                    }
                }
                Ok(false)
            }
        }
    }
}

/// Makes `p`'s end and `n`'s start meet after an offset (LinuxCNC `intersect_end`).
fn join(p: &mut Seg, n: &mut Seg) -> R<()> {
    let closer = |start: C, s1: C, s2: C| {
        if (start - s1).abs() < (start - s2).abs() {
            s1
        } else {
            s2
        }
    };
    // The two points of the circle (centre pc, through pe) on the real axis, in the frame
    // rotated by `rot` about `base`.
    let on_line = |pc: C, pe: C, rot: C, base: C| {
        let mut b = (pc - pe).norm() - pc.im * pc.im;
        b = if b < 0.0 { 0.0 } else { b.sqrt() };
        (
            c(pc.re + b, 0.0) / rot + base,
            c(pc.re - b, 0.0) / rot + base,
        )
    };
    match (*p, &mut *n) {
        (Seg::Line { s: ps0, e: pe0, .. }, Seg::Line { s, e, .. }) => {
            let rot = (*s - *e).conj() / (*s - *e).abs();
            let ps = (ps0 - *e) * rot;
            let pe = (pe0 - *e) * rot;
            if (ps - pe).im == 0.0 {
                return Err("Cannot intersect parallel lines".into());
            }
            let f = ps.im / (ps - pe).im;
            let is = (ps + f * (pe - ps)) / rot + *e;
            *s = is;
            *p.ep() = is;
        }
        (Seg::Arc { c: pc0, e: pe0, .. }, Seg::Line { s, e, .. }) => {
            if (*s - pe0).abs() < TOL {
                return Ok(());
            }
            let rot = (*s - *e).conj() / (*s - *e).abs();
            let (s1, s2) = on_line((pc0 - *e) * rot, (pe0 - *e) * rot, rot, *e);
            let is = closer(*s, s1, s2);
            *s = is;
            *p.ep() = is;
        }
        (
            Seg::Line { s: ps0, e: pe0, .. },
            Seg::Arc {
                s, c: nc, e: ne, ..
            },
        ) => {
            if (*s - pe0).abs() < TOL {
                return Ok(());
            }
            let rot = (ps0 - pe0).conj() / (ps0 - pe0).abs();
            let (s1, s2) = on_line((*nc - pe0) * rot, (*ne - pe0) * rot, rot, pe0);
            let is = closer(*s, s1, s2);
            *s = is;
            *p.ep() = is;
        }
        (Seg::Arc { s: ps0, c: pc0, .. }, Seg::Arc { s, c: nc, .. }) => {
            let a = (*s - *nc).abs();
            let b = (ps0 - pc0).abs();
            let cc = (*nc - pc0).abs();
            let cos_b = (cc * cc + a * a - b * b) / 2.0 / a / cc;
            let cos_b2 = (cos_b * cos_b).min(1.0);
            let rot = c(cos_b, (1.0 - cos_b2).sqrt());
            let is = a * (rot * (pc0 - *nc) / cc) + *nc;
            *s = is;
            *p.ep() = is;
        }
    }
    Ok(())
}

/// Fits the corner element `seg` (fillet or chamfer of size `finish`) between `prev` and
/// `next` (LinuxCNC `corner_finish`): both neighbours offset by the size meet at the
/// fillet's centre; their tangent points become the corner element's ends.
fn corner_finish(seg: &mut Seg, prev: &mut Seg, next: &mut Seg) -> R<C> {
    let mut finish = match *seg {
        Seg::Line { finish, .. } | Seg::Arc { finish, .. } => finish,
    };
    let (mut p, mut n) = (*prev, *next);
    p.offset(finish);
    n.offset(finish);
    if (p.end() - n.start()).re > 1e-2 {
        finish = -finish;
        p = *prev;
        n = *next;
        p.offset(finish);
        n.offset(finish);
    }
    if (p.end() - n.start()).re > 1e-2 {
        let at = prev.end();
        return Err(format!("Corner finish failed at ({},{})", at.re, at.im));
    }
    join(&mut p, &mut n)?;
    let center = (p.end() + n.start()) / 2.0;
    p.offset(-finish);
    n.offset(-finish);
    *seg.sp() = p.end();
    *prev.ep() = p.end();
    *seg.ep() = n.start();
    *next.sp() = n.start();
    match seg {
        Seg::Line { finish: f, .. } | Seg::Arc { finish: f, .. } => *f = finish,
    }
    Ok(center)
}

/// The most steps an offset or a roughing cycle (layers) may take before it is refused.
const MAX_STEPS: usize = 100_000;

/// The most finishing passes (G70 P).
pub(crate) const MAX_PASSES: f64 = 10_000.0;

/// A profile and the cycle's frame (`flip_state`, layer depth, escape).
#[derive(Clone, Debug)]
pub(crate) struct Profile {
    pub segs: Vec<Seg>,
    delta: f64,
    escape: C,
    flip_state: u8,
    pocket_starts: Vec<C>,
}

impl Profile {
    pub fn new(segs: Vec<Seg>) -> Profile {
        Profile {
            segs,
            delta: 0.5,
            escape: c(0.3, 0.3),
            flip_state: 0,
            pocket_starts: Vec::new(),
        }
    }

    fn rotate(&mut self) {
        self.segs.iter_mut().for_each(Seg::rotate);
        self.flip_state ^= 4;
    }

    /// Mirrors the profile so that X and Z decrease from its first to its last point.
    fn swap(&mut self) {
        let first = self.segs[0].end();
        let last = self.segs[self.segs.len() - 1].end();
        let (dir_x, dir_z) = ((first - last).im, (first - last).re);
        if dir_x > 0.0 {
            self.segs.iter_mut().for_each(Seg::flip_imag);
            self.flip_state ^= 2;
        }
        if dir_z < 0.0 {
            self.segs.iter_mut().for_each(Seg::flip_real);
            self.flip_state ^= 1;
        }
    }

    /// Maps a move of the normalised frame back to the program's.
    fn unswap(flip_state: u8, o: Out) -> Out {
        let f = |p: C| match flip_state {
            0 => p,
            1 => -p.conj(),
            2 => p.conj(),
            3 => -p,
            4 => I * p,
            5 => (I * p).conj(),
            6 => -(I * p).conj(),
            _ => -(I * p),
        };
        match o {
            Out::Feed(p) => Out::Feed(f(p)),
            Out::Rapid(p) => Out::Rapid(f(p)),
            Out::Arc { ccw, center, end } => Out::Arc {
                ccw: if matches!(flip_state, 1 | 2 | 5 | 6) {
                    !ccw
                } else {
                    ccw
                },
                center: f(center),
                end: f(end),
            },
        }
    }

    fn monotonic(&mut self) -> R<()> {
        let (s, e) = (self.segs[0].start(), self.segs[0].end());
        if (e - s).re > 0.0 {
            self.segs[0].sp().re = e.re;
        }
        if self.segs.iter().any(|s| !s.monotonic()) {
            return Err("Not monotonic".into());
        }
        Ok(())
    }

    /// Fits the fillets and chamfers, then drops elements of no length.
    fn do_finish(&mut self) -> R<()> {
        let n = self.segs.len();
        for h in 1..n.saturating_sub(1) {
            let corner = matches!(
                self.segs[h],
                Seg::Line { corner: true, .. } | Seg::Arc { corner: true, .. }
            );
            if !corner {
                continue;
            }
            let (before, rest) = self.segs.split_at_mut(h);
            let (mid, after) = rest.split_at_mut(1);
            let (prev, seg, next) = (&mut before[h - 1], &mut mid[0], &mut after[0]);
            let center = corner_finish(seg, prev, next)?;
            if let Seg::Arc {
                ccw,
                s,
                c: cc,
                e,
                finish,
                ..
            } = seg
            {
                *cc = center;
                *ccw = (*s - center).im > 0.0 || (*e - center).im > 0.0;
                *finish = 0.0;
            }
        }
        self.segs.retain(|s| !(s.radius() < 1e-3));
        if self.segs.is_empty() {
            return Err("the profile has no moves of any length".into());
        }
        Ok(())
    }

    /// Offsets the profile (all but its first, approach element) by `distance`.
    fn add_distance(&mut self, mut distance: f64) -> R<()> {
        if self.segs.len() < 2 {
            return Err("the profile needs at least two moves".into());
        }
        let v1 = self.segs[0].end() - self.segs[0].start();
        let v2 = self.segs[self.segs.len() - 1].start() - self.segs[0].start();
        if (v1 / v2).im < 0.0 {
            distance = -distance;
        }
        let mut of = self.segs.remove(0);
        let segs = &mut self.segs;
        let mut current = 0.0;
        let mut steps = 0;
        while current != distance {
            steps += 1;
            if steps > MAX_STEPS || segs.is_empty() {
                return Err("offsetting the profile does not converge".into());
            }
            let mut max_d = segs.iter().fold(1e9f64, |m, s| m.min(s.radius() / 2.0));
            max_d = max_d.min((distance - current).abs());
            if distance < 0.0 {
                max_d = -max_d;
            }
            let mut k = 0;
            while k < segs.len() {
                segs[k].offset(max_d);
                if segs[k].radius() < 1e-3 {
                    segs.remove(k);
                } else {
                    k += 1;
                }
            }
            let mut k = 0;
            while k + 1 < segs.len() {
                if (segs[k].end() - segs[k + 1].start()).re > 1e-2 {
                    let (mut s, mut e) = (segs[k], segs[k + 1]);
                    s.offset(-max_d);
                    e.offset(-max_d);
                    let center = (s.end() + e.start()) / 2.0;
                    let arc = Seg::arc(distance > 0.0, segs[k].end(), center, segs[k + 1].start());
                    segs.insert(k + 1, arc);
                    k += 1;
                }
                k += 1;
            }
            let mut k = 0;
            while k + 1 < segs.len() {
                if !segs[k].monotonic() {
                    // LinuxCNC drops the smaller of this element and the one before.
                    if k == 0 || segs[k].radius() < segs[k - 1].radius() {
                        segs.remove(k);
                    } else {
                        segs.remove(k - 1);
                    }
                    k = 0;
                    if segs.len() < 2 {
                        break;
                    }
                }
                if segs[k].radius() < 1e-3 {
                    segs.remove(k);
                    k = 0;
                    if segs.len() < 2 {
                        break;
                    }
                } else {
                    let (a, b) = segs.split_at_mut(k + 1);
                    join(&mut a[k], &mut b[0])?;
                }
                k += 1;
            }
            current += max_d;
        }
        if segs.is_empty() {
            return Err("the offset profile vanished".into());
        }
        for k in 0..segs.len() - 1 {
            let mid = (segs[k].end() + segs[k + 1].start()) / 2.0;
            *segs[k].ep() = mid;
            *segs[k + 1].sp() = mid;
        }
        *of.ep() = segs[0].start();
        segs.insert(0, of);
        Ok(())
    }

    /// G70 from `start` (`z + i·x`): P passes from distance D to E, each a rapid to `start`,
    /// a rapid to the offset profile's start, then the offset profile. rs274 2.9 (the
    /// version measured) sends every one of them through cutter compensation when it is on.
    pub fn g70(mut self, start: C, d: f64, e: f64, p: f64) -> R<Vec<Out>> {
        *self.segs[0].sp() = start;
        let mut path = self.clone();
        path.segs.remove(0);
        if path.segs.is_empty() {
            return Err("the profile needs at least two moves".into());
        }
        path.swap();
        if path.segs.iter().any(|s| !s.monotonic()) {
            path.rotate();
            path.swap();
        }
        path.monotonic()?;
        if path.flip_state & 4 != 0 {
            self.rotate();
        }
        self.swap();
        self.do_finish()?;
        self.monotonic()?;
        let fs = self.flip_state;
        let mut out = Vec::new();
        if !(p <= MAX_PASSES) {
            return Err(format!("P{p} passes: expected at most {MAX_PASSES}"));
        }
        let passes = p as i64;
        for pass in (1..=passes).rev() {
            let distance = (pass - 1) as f64 * (d - e) / p + e;
            let mut path = self.clone();
            path.add_distance(distance)?;
            out.push(Out::Rapid(path.segs[0].start()));
            out.push(Out::Rapid(path.segs[0].end()));
            let mut drawn = Vec::new();
            for s in &path.segs[1..] {
                s.draw(&mut drawn);
            }
            out.extend(drawn);
        }
        Ok(out.into_iter().map(|o| Profile::unswap(fs, o)).collect())
    }

    /// G71 (`rotate` false) or G72 (true): `cycle` 0 all, 1 no pockets (.1), 2 only the
    /// pockets (.2); from `start`, allowance D, layers I, escape R, shift `w + i·u`.
    #[allow(clippy::too_many_arguments)]
    pub fn g71(
        mut self,
        rotate: bool,
        cycle: u32,
        start: C,
        shift: C,
        d: f64,
        i: f64,
        r: f64,
    ) -> R<Vec<Out>> {
        *self.segs[0].sp() = start;
        if rotate {
            self.rotate();
        }
        self.swap();
        self.do_finish()?;
        self.monotonic()?;
        self.add_distance(d)?;
        if self.segs.len() < 2 {
            return Err("the offset profile vanished".into());
        }
        self.segs.iter_mut().for_each(|s| s.shift(shift));
        let fs = self.flip_state;
        self.delta = i.max(2.0 * TOL);
        self.escape = r * c(1.0, 1.0);
        let mut out = vec![Out::Rapid(self.segs[0].start())];
        let last = self.segs[self.segs.len() - 1].end();
        let first = self.segs[0].start();
        if last.im < first.im {
            self.segs.push(Seg::line(
                last,
                C {
                    re: last.re,
                    im: first.im,
                },
            ));
        }
        self.pocket_starts.push(first);
        let mut steps = 0;
        self.pocket(cycle, first, 0, &mut out, &mut steps)?;
        Ok(out.into_iter().map(|o| Profile::unswap(fs, o)).collect())
    }

    fn pocket(
        &mut self,
        mut cycle: u32,
        mut loc: C,
        mut p: usize,
        out: &mut Vec<Out>,
        steps: &mut usize,
    ) -> R<()> {
        let mut x = self.pocket_starts.last().expect("pushed by g71").im;
        let n = self.segs.len();
        if cycle == 2 {
            while p < n {
                if self.segs[p].dive(&mut loc, -1e9, out, p == 0)? {
                    break;
                }
                p += 1;
            }
            cycle = 3;
        }
        while p < n {
            *steps += 1;
            if *steps > MAX_STEPS {
                return Err(format!(
                    "more than {MAX_STEPS} roughing layers: expected a larger I"
                ));
            }
            if !((x - TOL - loc.im) / self.delta < MAX_STEPS as f64) {
                return Err("too many roughing layers: expected a larger I".into());
            }
            while x - TOL > loc.im {
                x -= self.delta;
            }
            if self.segs[p].dive(&mut loc, x, out, p == 0)? {
                if cycle == 1 {
                    while p < n {
                        self.segs[p].climb_only(&mut loc, out);
                        p += 1;
                    }
                } else {
                    while p < n {
                        if self.segs[p].climb(&mut loc, out)? {
                            if cycle == 3 {
                                let back = *self.pocket_starts.last().expect("not empty");
                                if loc.im > back.im && self.pocket_starts.len() > 1 {
                                    self.pocket_starts.pop();
                                }
                                if self.pocket_starts.len() == 1 {
                                    self.pocket_starts.push(loc);
                                }
                            }
                            return self.pocket(cycle, loc, p, out, steps);
                        }
                        p += 1;
                    }
                }
                return Ok(());
            }
            if (loc.im - x).abs() > TOL {
                p += 1;
                continue;
            }
            for ip in p..n {
                let is = self.segs[ip].intersections(loc.im);
                if is.is_empty() {
                    continue;
                }
                let dest_z = if ip != p {
                    is[0]
                } else {
                    *is.last().expect("not empty")
                };
                let distance = (dest_z - loc.re).abs();
                if dest_z - TOL > loc.re {
                    continue;
                }
                if distance < TOL {
                    if p == ip {
                        continue;
                    } else if (loc - self.segs[ip].start()).abs() < TOL {
                        p = ip;
                        break;
                    } else {
                        x -= self.delta;
                        break;
                    }
                }
                let mut dest = loc;
                dest.re = dest_z;
                out.push(Out::Feed(dest));
                let scale = (distance / 2.0 / self.escape.re).min(1.0);
                dest = dest + scale * self.escape;
                out.push(Out::Rapid(dest));
                dest = loc - (scale * self.escape).conj();
                out.push(Out::Rapid(dest));
                out.push(if p == 0 {
                    Out::Rapid(loc)
                } else {
                    Out::Feed(loc)
                });
                x -= self.delta;
                break;
            }
        }
        Ok(())
    }
}
