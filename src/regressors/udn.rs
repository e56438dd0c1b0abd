//! The Unified Discontinuous Nonlinearity (UDN) with effects switchable one by one.
//!
//! Definition (corrected form of the paper's eq. (5), see `/work/shared/paper/NOTES.md`):
//!
//! ```text
//! x = u − a·s                     hysteresis (Shift form; the Play form uses a play operator)
//! w = sign(x)·max(|x| − b, 0)     dead-zone
//! v = clamp(p·w, p·z2, p·z1) + e1·[x > b] + e2·[x < −b]
//! ```
//!
//! For fixed thresholds v = φ·g with g = [p, p·a, p·b, p·z1, p·z2, e1, e2] restricted to the
//! active effects and φ = [u·L, −s·L, −sign(x)·L, H1, H2, P1, P2] (L: sloped part, H1/H2:
//! saturated high/low, P1 = [x > b], P2 = [x < −b]).
//!
//! Identifiability decisions (NOTES.md, "Identifiability"):
//! - dead-zone AND preload (untied): φ3 − φ4 + φ5 + φ6 − φ7 = 0, so the φ3 column is dropped, its
//!   term −b·sign(x)·L is folded into the sloped column ((u − b·sign x)·L) and b is a searched
//!   parameter ([`searched_params`](StaticNonlinearity::searched_params)).
//! - preload without dead-zone: P1 + P2 = 1 almost everywhere (b = 0), so the basis spans the
//!   constant; it is identifiable only if the loop adds no separate constant input column
//!   ([`StaticNonlinearity::spans_constant`] reports it).
//! - tied (DN1/DN2, a = b) with preload: the tied column −(s + sign x)·L is not in the span of the
//!   others, so a stays a ratio of g.
//! - One-sided saturation ([`SaturationSides`]): v = min(p·w, p·z1) (upper limit only) or
//!   max(p·w, p·z2) (lower only). The absent limit is ±∞ and no parameter: its column H2 (H1)
//!   is 0 on every sample, so the layout drops it and g, θ and the model file do not hold it.
//! - Play form: x is a play operator (backlash) of u with half-width a; v is not linear in a, so a
//!   is searched (and folded into the sloped column x·L). The play operator is the one of
//!   Krasnosel'skii & Pokrovskii (Systems with Hysteresis, 1989; Visintin, Differential Models of
//!   Hysteresis, 1994, ch. III), discretised as x(k) = max(u(k) − a, min(u(k) + a, x(k−1))).

// `!(x > y)` is deliberate throughout: a NaN must fail every admissibility test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod jumps;
mod kernels;
mod kinks;
mod sides;

pub use sides::SaturationSides;

use kernels::{eval_any, eval_fixed, eval_shift_direct, row_values, shift_blocks};

use super::direction::DirectionTracker;
use super::udn_input::{Branches, InputCache, InputStats};
use super::zone::{
    MAX_WIDTH_FRACTION, ZONE_FRACTION, finite, quantile_index, select_quantile, spread,
};
use super::{Effect, EffectSet, NonlinearitySpec, StaticNonlinearity};
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::columns::columns_mut;
use faer::Mat;
use serde::{Deserialize, Serialize};

/// How hysteresis enters the UDN.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HysteresisForm {
    /// The paper's form: the branch is shifted by ±a with the direction, x = u − a·s.
    #[default]
    Shift,
    /// True backlash (play operator): x(k) = max(u − a, min(u + a, x(k−1))), held inside the band.
    Play,
}

impl HysteresisForm {
    /// Name as spelled in specs ("shift" or "play").
    pub fn name(self) -> &'static str {
        match self {
            HysteresisForm::Shift => "shift",
            HysteresisForm::Play => "play",
        }
    }
}

/// An input record and the UDN's cached stats of it (`None`: not cached, computed directly).
struct Record<'u, T: Real> {
    u: &'u [T],
    stats: Option<std::sync::Arc<InputStats<T>>>,
}

/// One regressor column of the UDN.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Col {
    /// (u − folded)·L (Shift) or (x − folded)·L (Play); gain p.
    Slope,
    /// −s·L; gain p·a.
    Hyst,
    /// −(s + sign x)·L (a = b tied); gain p·a.
    Tied,
    /// −sign(x)·L; gain p·b.
    Dead,
    /// H1; gain p·z1.
    High,
    /// H2; gain p·z2.
    Low,
    /// P1 = [x > b]; gain e1.
    Pre1,
    /// P2 = [x < −b]; gain e2.
    Pre2,
}

impl Col {
    fn name(self, form: HysteresisForm) -> &'static str {
        match (self, form) {
            (Col::Slope, HysteresisForm::Shift) => "u_sloped",
            (Col::Slope, HysteresisForm::Play) => "x_sloped",
            (Col::Hyst, _) => "-s_sloped",
            (Col::Tied, _) => "-(s+sign)_sloped",
            (Col::Dead, _) => "-sign_sloped",
            (Col::High, _) => "sat_high",
            (Col::Low, _) => "sat_low",
            (Col::Pre1, _) => "preload_pos",
            (Col::Pre2, _) => "preload_neg",
        }
    }
}

/// Zone membership of one sample.
#[derive(Debug, Clone, Copy)]
struct Point<T> {
    /// Branch variable x (after hysteresis).
    x: T,
    /// sign(x) (0 at x = 0).
    sx: T,
    /// Dead-zone output w.
    w: T,
    /// On the sloped part.
    l: bool,
    /// Saturated high.
    h1: bool,
    /// Saturated low.
    h2: bool,
    /// x > b.
    p1: bool,
    /// x < −b.
    p2: bool,
}

/// sign(x) (+0 at x = 0 and for NaN), without branches: the difference of two indicators.
#[inline(always)]
fn sgn<T: Real>(x: T) -> T {
    ind::<T>(x > T::zero()) - ind::<T>(x < T::zero())
}

/// 1 or 0, converted from the integer (no branch).
#[inline(always)]
fn ind<T: Real>(b: bool) -> T {
    T::lit(f64::from(u8::from(b)))
}

/// The UDN: gain p, hysteresis a, dead-zone b, saturation z1/z2, preload e1/e2, each effect
/// switchable via an [`EffectSet`].
#[derive(Debug, Clone, PartialEq)]
pub struct Udn<T: Real> {
    effects: EffectSet,
    form: HysteresisForm,
    tied: bool,
    /// The saturation's limits (both, or one with the other at ±∞ and not a parameter).
    sides: SaturationSides,
    p: T,
    a: T,
    b: T,
    z1: T,
    z2: T,
    e1: T,
    e2: T,
    /// The direction of motion before the record's first sample (+1 rising, −1 falling): the
    /// hysteresis' initial memory, a nuisance parameter the fit estimates like x0.
    s0: T,
    /// The last input record's directions, spread and sorted branches (`udn_input.rs`).
    input: InputCache<T>,
}

impl<T: Real> Udn<T> {
    /// A UDN with the given effects and neutral parameters (p = 1, a = b = 0, z1 = 1, z2 = −1,
    /// e1 = e2 = 0); call [`initialize`](StaticNonlinearity::initialize) or
    /// [`set_params`](StaticNonlinearity::set_params) before use.
    pub fn new(effects: EffectSet) -> Self {
        // the Prandtl–Ishlinskii basis is added around the UDN (`PrandtlIshlinskii`), not inside
        let effects = effects.udn_part();
        let sat = effects.contains(Effect::Saturation);
        Udn {
            effects,
            form: HysteresisForm::Shift,
            tied: false,
            sides: SaturationSides::Both,
            p: T::one(),
            a: T::zero(),
            b: T::zero(),
            z1: if sat { T::one() } else { T::infinity() },
            z2: if sat { -T::one() } else { T::neg_infinity() },
            e1: T::zero(),
            e2: T::zero(),
            s0: T::one(),
            input: InputCache::default(),
        }
    }

    /// A UDN with the given effects and active parameters (in the order of `param_names`).
    pub fn with_params(effects: EffectSet, theta: &[T]) -> Result<Self> {
        let mut u = Self::new(effects);
        u.set_params(theta)?;
        Ok(u)
    }

    /// The full UDN (all four effects).
    pub fn full() -> Self {
        Self::new(EffectSet::all())
    }

    /// Saturation with hysteresis (SH = DN4).
    pub fn sh() -> Self {
        Self::new(EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]))
    }

    /// A pure linear gain v = p·u.
    pub fn linear() -> Self {
        Self::new(EffectSet::empty())
    }

    /// A backlash alone: hysteresis in the Play form, parameters p and a.
    pub fn backlash() -> Self {
        Self::new(EffectSet::of(&[Effect::Hysteresis])).with_form(HysteresisForm::Play)
    }

    /// The paper's Table 1 case DN1..DN8 (DN1/DN2 have tied widths a = b).
    pub fn dn(k: u8) -> Result<Self> {
        use Effect::*;
        let (set, tied): (&[Effect], bool) = match k {
            1 => (&[Hysteresis, DeadZone, Saturation, Preload], true),
            2 => (&[Hysteresis, DeadZone, Saturation], true),
            3 => (&[Hysteresis, DeadZone, Saturation], false),
            4 => (&[Hysteresis, Saturation], false),
            5 => (&[DeadZone, Saturation, Preload], false),
            6 => (&[Saturation, Preload], false),
            7 => (&[DeadZone, Saturation], false),
            8 => (&[Saturation], false),
            _ => {
                return Err(Error::InvalidParameter(format!(
                    "DN{k} does not exist (the paper's Table 1 has DN1..DN8)"
                )));
            }
        };
        Self::new(EffectSet::of(set)).with_tied(tied)
    }

    /// A UDN by name: "udn", "sh", "linear", "backlash", "dn1".."dn8", or an effect list
    /// ("saturation,dead-zone"); a "-play" suffix selects the play form of hysteresis, an
    /// "-upper-only" ("-lower-only") suffix a saturation with its upper (lower) limit only
    /// ([`SaturationSides`]). The suffixes are stripped from the end, in any order, each once.
    pub fn by_name(name: &str) -> Result<Self> {
        let n = name.trim().to_ascii_lowercase();
        if n.is_empty() {
            return Err(Error::InvalidParameter(
                "empty nonlinearity name (udn, sh, linear, backlash, dn1..dn8, or effects \
                 separated by commas)"
                    .into(),
            ));
        }
        let (mut base, mut play, mut sides) = (n, false, SaturationSides::Both);
        loop {
            if !play && let Some(b) = base.strip_suffix("-play") {
                (base, play) = (b.to_string(), true);
                continue;
            }
            let one = [SaturationSides::Upper, SaturationSides::Lower]
                .into_iter()
                .find_map(|s| base.strip_suffix(s.suffix()).map(|b| (b.to_string(), s)));
            match one {
                Some((b, s)) if sides == SaturationSides::Both => (base, sides) = (b, s),
                _ => break,
            }
        }
        let udn = match base.as_str() {
            "udn" => Self::full(),
            "sh" => Self::sh(),
            "backlash" => Self::backlash(),
            b if b.len() == 3 && b.starts_with("dn") => {
                Self::dn(b[2..].parse().map_err(|_| {
                    Error::InvalidParameter(format!("unknown nonlinearity '{name}'"))
                })?)?
            }
            b => Self::new(EffectSet::parse(b).map_err(|_| {
                Error::InvalidParameter(format!(
                    "unknown nonlinearity '{name}' (udn, sh, linear, backlash, dn1..dn8, or \
                     effects hysteresis, dead-zone, saturation, preload separated by commas)"
                ))
            })?),
        };
        let udn = udn.with_saturation_sides(sides)?;
        Ok(if play && udn.has(Effect::Hysteresis) {
            udn.with_form(HysteresisForm::Play)
        } else {
            udn
        })
    }

    /// The same UDN with the saturation's limits `sides`: both, or one of them only (the other
    /// at ±∞, not a parameter). The kept limit's value is kept. A one-sided saturation needs the
    /// saturation effect.
    pub fn with_saturation_sides(mut self, sides: SaturationSides) -> Result<Self> {
        if sides != SaturationSides::Both && !self.has(Effect::Saturation) {
            return Err(Error::InvalidParameter(format!(
                "a saturation with the {} limit only needs the saturation effect, got {{{}}}",
                sides.name(),
                self.effects
            )));
        }
        self.sides = sides;
        if self.has(Effect::Saturation) {
            // the limits the sides drop at ±∞; one they restore at the neutral ±1 beyond the
            // other (the admissible order z1 > z2 kept)
            self.z1 = match (sides.upper(), self.z1.is_finite()) {
                (false, _) => T::infinity(),
                (true, true) => self.z1,
                (true, false) => self.z2.max(T::zero()) + T::one(),
            };
            self.z2 = match (sides.lower(), self.z2.is_finite()) {
                (false, _) => T::neg_infinity(),
                (true, true) => self.z2,
                (true, false) => self.z1.min(T::zero()) - T::one(),
            };
        }
        Ok(self)
    }

    /// The saturation's limits ([`SaturationSides::Both`] without a saturation).
    pub fn saturation_sides(&self) -> SaturationSides {
        self.sides
    }

    /// The same UDN with another hysteresis form (parameters kept).
    pub fn with_form(mut self, form: HysteresisForm) -> Self {
        self.form = form;
        self
    }

    /// The same UDN with hysteresis and dead-zone widths tied (a = b, one parameter) or untied;
    /// tying needs both effects.
    pub fn with_tied(mut self, tied: bool) -> Result<Self> {
        if tied
            && !(self.effects.contains(Effect::Hysteresis)
                && self.effects.contains(Effect::DeadZone))
        {
            return Err(Error::InvalidParameter(format!(
                "tied widths (a = b) need both hysteresis and dead-zone, got {{{}}}",
                self.effects
            )));
        }
        self.tied = tied;
        if tied {
            self.b = self.a;
        }
        Ok(self)
    }

    /// The effect set.
    pub fn effect_set(&self) -> EffectSet {
        self.effects
    }

    /// The hysteresis form.
    pub fn form(&self) -> HysteresisForm {
        self.form
    }

    /// True when a = b is one parameter (DN1/DN2).
    pub fn is_tied(&self) -> bool {
        self.tied
    }

    fn has(&self, e: Effect) -> bool {
        self.effects.contains(e)
    }

    /// Hysteresis half-width in force (0 when hysteresis is off).
    fn a_eff(&self) -> T {
        if self.has(Effect::Hysteresis) {
            self.a
        } else {
            T::zero()
        }
    }

    /// Dead-zone half-width in force (a when tied, 0 when the dead-zone is off).
    fn b_eff(&self) -> T {
        if !self.has(Effect::DeadZone) {
            T::zero()
        } else if self.tied {
            self.a
        } else {
            self.b
        }
    }

    fn play(&self) -> bool {
        self.form == HysteresisForm::Play && self.has(Effect::Hysteresis)
    }

    /// True when the dead-zone term −b·sign(x)·L is folded into the sloped column (b not in g).
    fn fold_b(&self) -> bool {
        self.has(Effect::DeadZone)
            && ((self.tied && self.play()) || (!self.tied && self.has(Effect::Preload)))
    }

    /// The regressor columns, in the order of g.
    fn layout(&self) -> Vec<Col> {
        let mut c = vec![Col::Slope];
        if self.has(Effect::Hysteresis) && !self.play() {
            c.push(if self.tied { Col::Tied } else { Col::Hyst });
        }
        if self.has(Effect::DeadZone) && !self.tied && !self.has(Effect::Preload) {
            c.push(Col::Dead);
        }
        if self.has(Effect::Saturation) {
            if self.sides.upper() {
                c.push(Col::High);
            }
            if self.sides.lower() {
                c.push(Col::Low);
            }
        }
        if self.has(Effect::Preload) {
            c.push(Col::Pre1);
            c.push(Col::Pre2);
        }
        c
    }

    /// Which of the 7 UDN parameters [p, a, b, z1, z2, e1, e2] are active, in order.
    fn active(&self) -> Vec<usize> {
        let mut v = vec![0];
        if self.has(Effect::Hysteresis) {
            v.push(1);
        }
        if self.has(Effect::DeadZone) && !self.tied {
            v.push(2);
        }
        if self.has(Effect::Saturation) {
            if self.sides.upper() {
                v.push(3);
            }
            if self.sides.lower() {
                v.push(4);
            }
        }
        if self.has(Effect::Preload) {
            v.extend([5, 6]);
        }
        v
    }

    fn all7(&self) -> [T; 7] {
        [self.p, self.a, self.b, self.z1, self.z2, self.e1, self.e2]
    }

    /// Zones of one sample with branch variable x.
    #[inline(always)]
    fn point(&self, x: T) -> Point<T> {
        let b = self.b_eff();
        let ax = x.abs();
        let sx = sgn(x);
        // sign(x)·max(|x| − b, 0), +0 inside the band (`+ 0` turns a −0 into +0), branch-free
        let w = sx * (ax - b).max(T::zero()) + T::zero();
        // `&`, not `&&`: comparisons combined without branches
        let h1 = w > self.z1;
        let h2 = !h1 & (w < self.z2);
        Point {
            x,
            sx,
            w,
            l: (ax > b) & !h1 & !h2,
            h1,
            h2,
            p1: x > b,
            p2: x < -b,
        }
    }

    /// Calls `f(k, u, s, point, dx/da)` for every sample (no allocation).
    fn for_each(&self, u: &[T], mut f: impl FnMut(usize, T, T, Point<T>, T)) {
        let a = self.a_eff();
        let mut dir = DirectionTracker::<T>::with_initial(self.s0);
        if self.play() {
            // Play operator started on the branch of the initial direction s0:
            // x(−1) = u(0) − a·s0.
            let mut xp = u.first().map_or(T::zero(), |&u0| u0 - a * self.s0);
            let mut dp = -self.s0;
            for (k, &uk) in u.iter().enumerate() {
                let s = dir.next(uk);
                let (lo, hi) = (uk - a, uk + a);
                let (x, d) = if xp < lo {
                    (lo, -T::one())
                } else if xp > hi {
                    (hi, T::one())
                } else {
                    (xp, dp)
                };
                xp = x;
                dp = d;
                f(k, uk, s, self.point(x), d);
            }
        } else {
            for (k, &uk) in u.iter().enumerate() {
                let s = dir.next(uk);
                f(k, uk, s, self.point(uk - a * s), -s);
            }
        }
    }

    fn check(&self, v: [T; 7]) -> Result<()> {
        let names = ["p", "a", "b", "z1", "z2", "e1", "e2"];
        for i in self.active() {
            if !v[i].is_finite() {
                return Err(Error::InvalidParameter(format!(
                    "UDN parameter {} = {} is not finite",
                    names[i], v[i]
                )));
            }
        }
        if !(v[0] > T::zero()) {
            return Err(Error::InvalidParameter(format!(
                "UDN gain p = {} must be positive (normalise the sign of g so that p > 0)",
                v[0]
            )));
        }
        if v[1] < T::zero() || v[2] < T::zero() {
            return Err(Error::InvalidParameter(format!(
                "UDN widths must be non-negative (a = {}, b = {})",
                v[1], v[2]
            )));
        }
        if self.has(Effect::Saturation) && !(v[3] > v[4]) {
            return Err(Error::InvalidParameter(format!(
                "UDN saturation limits need z1 > z2 (z1 = {}, z2 = {})",
                v[3], v[4]
            )));
        }
        Ok(())
    }

    fn store(&mut self, v: [T; 7]) {
        self.p = v[0];
        self.a = if self.has(Effect::Hysteresis) {
            v[1]
        } else {
            T::zero()
        };
        self.b = if !self.has(Effect::DeadZone) {
            T::zero()
        } else if self.tied {
            self.a
        } else {
            v[2]
        };
        let sat = self.has(Effect::Saturation);
        self.z1 = if sat && self.sides.upper() {
            v[3]
        } else {
            T::infinity()
        };
        self.z2 = if sat && self.sides.lower() {
            v[4]
        } else {
            T::neg_infinity()
        };
        let pre = self.has(Effect::Preload);
        self.e1 = if pre { v[5] } else { T::zero() };
        self.e2 = if pre { v[6] } else { T::zero() };
    }

    /// Largest dead-zone half-width that leaves ≥ ZONE_FRACTION of the samples of each branch
    /// (rising, falling) on each side of the band (x > b and x < −b), for the branch variables of
    /// the current a, and at most MAX_WIDTH_FRACTION of the input spread.
    fn b_max(&self, rec: &Record<'_, T>) -> T {
        if let Some((st, a)) = self.shift_stats(rec) {
            return b_max_sorted(st, a);
        }
        let u = rec.u;
        let mut rise = Vec::with_capacity(u.len());
        let mut fall = Vec::with_capacity(u.len());
        self.for_each(u, |_, _, s, p, _| {
            if s > T::zero() {
                rise.push(p.x)
            } else {
                fall.push(p.x)
            }
        });
        let mut m = T::lit(MAX_WIDTH_FRACTION) * spread(u);
        // without hysteresis both branches coincide; a tiny branch (< ZONE_FRACTION) is ignored
        let min_len = (ZONE_FRACTION * u.len() as f64).ceil() as usize;
        for branch in [rise, fall] {
            if branch.len() < min_len.max(1) {
                continue;
            }
            let mut vals = finite(branch.into_iter());
            let hi = select_quantile(&mut vals, 1.0 - ZONE_FRACTION);
            let lo = select_quantile(&mut vals, ZONE_FRACTION);
            let side = hi.min(-lo);
            m = m.min(side);
        }
        m.max(T::zero())
    }

    /// The record `u` with its cached stats (looked up once for the zone guard's steps).
    fn record<'u>(&self, u: &'u [T]) -> Record<'u, T> {
        Record {
            u,
            stats: self.input.get(u, self.s0),
        }
    }

    /// The record's cached stats and the hysteresis width in force, for the Shift form with a
    /// finite width (`None`: the direct computation).
    fn shift_stats<'r>(&self, rec: &'r Record<'_, T>) -> Option<(&'r InputStats<T>, T)> {
        let a = self.a_eff();
        if self.play() || !a.is_finite() {
            return None;
        }
        rec.stats.as_deref().map(|st| (st, a))
    }

    /// Tied widths: the largest a ≤ current a with a ≤ b_max(a) (bisection, 30 steps).
    fn tied_a_max(&self, rec: &Record<'_, T>) -> T {
        if self.a <= self.b_max(rec) {
            return self.a;
        }
        let mut probe = self.clone();
        let (mut lo, mut hi) = (T::zero(), self.a);
        for _ in 0..30 {
            let mid = (lo + hi) * T::lit(0.5);
            probe.a = mid;
            probe.b = mid;
            if mid <= probe.b_max(rec) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// Zone guard: moves every threshold back inside the data so that every zone an effect claims
    /// keeps at least ZONE_FRACTION of the samples (NOTES.md: otherwise a zero column makes the
    /// next linear step singular).
    fn zone_guard(&mut self, u: &[T]) {
        let rec = self.record(u);
        let spr = rec.stats.as_ref().map_or_else(|| spread(u), |st| st.spread);
        if !(spr > T::zero()) {
            return;
        }
        let a_max = T::lit(MAX_WIDTH_FRACTION) * spr;
        if self.has(Effect::Hysteresis) {
            self.a = self.a.max(T::zero()).min(a_max);
        }
        if self.has(Effect::DeadZone) {
            if self.tied {
                self.a = self.tied_a_max(&rec);
                self.b = self.a;
            } else {
                let bm = self.b_max(&rec);
                self.b = self.b.max(T::zero()).min(bm);
            }
        }
        if self.has(Effect::Saturation) {
            self.saturation_guard(&rec);
        }
    }

    /// The zone guard's saturation part: z1, z2 inside the 3 %/97 % quantiles of the dead-zone
    /// output w, reset to its 10 %/90 % quantiles when the sloped zone keeps too few samples;
    /// an absent limit of a one-sided saturation stays at ±∞.
    /// With the record's stats cached (Shift form) the quantiles and the count are binary
    /// searches over the sorted branches (w is non-decreasing in x, `udn_input.rs`).
    fn saturation_guard(&mut self, rec: &Record<'_, T>) {
        let (z1, z2) = match self.shift_stats(rec) {
            Some((st, a)) => saturation_limits(
                (self.z1, self.z2),
                self.sides,
                &mut SortedW {
                    udn: self,
                    br: &st.branches,
                    a,
                },
            ),
            None => {
                let mut w = vec![T::zero(); rec.u.len()];
                self.for_each(rec.u, |k, _, _, p, _| w[k] = p.w);
                saturation_limits(
                    (self.z1, self.z2),
                    self.sides,
                    &mut UnsortedW(finite(w.into_iter())),
                )
            }
        };
        self.z1 = z1;
        self.z2 = z2;
    }
}

/// The dead-zone outputs w of a record, as the saturation guard reads them.
trait WValues<T: Real> {
    /// The number of finite values.
    fn len(&self) -> usize;
    /// The q-quantile (`select_quantile`'s).
    fn quantile(&mut self, q: f64) -> T;
    /// How many are non-zero and within [z2, z1] (z2 < z1).
    fn sloped(&self, z1: T, z2: T) -> usize;
}

/// The values themselves, unordered.
struct UnsortedW<T: Real>(Vec<T>);

impl<T: Real> WValues<T> for UnsortedW<T> {
    fn len(&self) -> usize {
        self.0.len()
    }
    fn quantile(&mut self, q: f64) -> T {
        select_quantile(&mut self.0, q)
    }
    fn sloped(&self, z1: T, z2: T) -> usize {
        self.0
            .iter()
            .filter(|&&x| x != T::zero() && x >= z2 && x <= z1)
            .count()
    }
}

/// The values as w(x) of the record's sorted branches (Shift form, width `a`): w is
/// non-decreasing in x, so its quantiles are w of x's and its counts are counts of x.
struct SortedW<'s, T: Real> {
    udn: &'s Udn<T>,
    br: &'s Branches<T>,
    a: T,
}

impl<T: Real> SortedW<'_, T> {
    fn count(&self, pred: impl Fn(T) -> bool) -> usize {
        self.br.count_x(self.a, |x| pred(self.udn.point(x).w))
    }
}

impl<T: Real> WValues<T> for SortedW<'_, T> {
    fn len(&self) -> usize {
        self.br.len()
    }
    fn quantile(&mut self, q: f64) -> T {
        quantile_index(self.br.len(), q)
            .map_or(T::zero(), |k| self.udn.point(self.br.kth_x(self.a, k)).w)
    }
    fn sloped(&self, z1: T, z2: T) -> usize {
        let within = self.count(|w| w <= z1) - self.count(|w| w < z2);
        let zero = T::zero();
        if z2 <= zero && zero <= z1 {
            within - (self.count(|w| w <= zero) - self.count(|w| w < zero))
        } else {
            within
        }
    }
}

/// The saturation limits the zone guard keeps from `(z1, z2)` given the record's w values:
/// each limit `sides` has is clamped inside the ZONE_FRACTION / 1 − ZONE_FRACTION quantiles of w
/// (so that each saturated zone keeps ZONE_FRACTION of the samples), both are reset to the
/// 10 %/90 % quantiles when the sloped zone between them keeps fewer; an absent limit is ±∞.
fn saturation_limits<T: Real>(
    (z1, z2): (T, T),
    sides: SaturationSides,
    vals: &mut dyn WValues<T>,
) -> (T, T) {
    let hi = vals.quantile(1.0 - ZONE_FRACTION);
    let lo = vals.quantile(ZONE_FRACTION);
    let upper = |z: T| if sides.upper() { z } else { T::infinity() };
    let lower = |z: T| if sides.lower() { z } else { T::neg_infinity() };
    let (z1, z2) = (upper(z1.min(hi)), lower(z2.max(lo)));
    let need = (ZONE_FRACTION * vals.len() as f64).ceil() as usize;
    if z1 > z2 && vals.sloped(z1, z2) >= need {
        return (z1, z2);
    }
    // Reset to the initial quantiles (10 % / 90 %) of w.
    let (r1, r2) = (upper(vals.quantile(0.9)), lower(vals.quantile(0.1)));
    if r1 > r2 {
        (r1, r2)
    } else {
        (upper(hi), lower(lo))
    }
}

/// `Udn::b_max` from the record's sorted branches (Shift form, hysteresis width `a`): each
/// branch's 3 %/97 % quantiles of x are its sorted inputs at those ranks shifted by −a·s.
fn b_max_sorted<T: Real>(st: &InputStats<T>, a: T) -> T {
    let br = &st.branches;
    let mut m = T::lit(MAX_WIDTH_FRACTION) * st.spread;
    // without hysteresis both branches coincide; a tiny branch (< ZONE_FRACTION) is ignored
    let min_len = (ZONE_FRACTION * st.s.len() as f64).ceil() as usize;
    for (rising, len) in [(true, br.rise.len()), (false, br.fall.len())] {
        if len < min_len.max(1) {
            continue;
        }
        let hi = br.quantile(rising, a, 1.0 - ZONE_FRACTION);
        let lo = br.quantile(rising, a, ZONE_FRACTION);
        m = m.min(hi.min(-lo));
    }
    m.max(T::zero())
}

impl<T: Real> StaticNonlinearity<T> for Udn<T> {
    fn name(&self) -> String {
        use Effect::*;
        let e = self.effects;
        let base = if e.is_empty() {
            "linear".to_string()
        } else if e == EffectSet::of(&[Hysteresis]) && self.play() {
            return "backlash".into();
        } else if e == EffectSet::all() && !self.tied {
            "udn".into()
        } else if e == EffectSet::of(&[Hysteresis, Saturation]) {
            "sh".into()
        } else if e == EffectSet::of(&[Hysteresis, DeadZone, Saturation]) {
            if self.tied { "dn2" } else { "dn3" }.into()
        } else if e == EffectSet::all() {
            "dn1".into()
        } else if let Some(k) = e.dn_type().filter(|_| !e.contains(Hysteresis)) {
            format!("dn{k}")
        } else {
            let short: Vec<&str> = e
                .effects()
                .iter()
                .map(|x| match x {
                    Hysteresis => "h",
                    DeadZone => "dz",
                    Saturation => "s",
                    Preload => "pl",
                    PrandtlIshlinskii => "pi",
                })
                .collect();
            format!("udn-{}", short.join("-"))
        };
        let base = format!("{base}{}", self.sides.suffix());
        if self.play() {
            format!("{base}-play")
        } else {
            base
        }
    }

    fn effects(&self) -> Vec<String> {
        self.effects
            .effects()
            .iter()
            .map(|e| e.name().to_string())
            .collect()
    }

    fn param_names(&self) -> Vec<String> {
        let names = ["p", "a", "b", "z1", "z2", "e1", "e2"];
        self.active()
            .into_iter()
            .map(|i| names[i].to_string())
            .collect()
    }

    fn params(&self) -> Vec<T> {
        let v = self.all7();
        self.active().into_iter().map(|i| v[i]).collect()
    }

    fn set_params(&mut self, theta: &[T]) -> Result<()> {
        let act = self.active();
        if theta.len() != act.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "{} has {} parameters ({}), got {}",
                    StaticNonlinearity::<T>::name(self),
                    act.len(),
                    StaticNonlinearity::<T>::param_names(self).join(", "),
                    theta.len()
                ),
            });
        }
        let mut v = self.all7();
        for (&i, &t) in act.iter().zip(theta) {
            v[i] = t;
        }
        if self.tied {
            v[2] = v[1];
        }
        self.check(v)?;
        self.store(v);
        Ok(())
    }

    fn regressor_names(&self) -> Vec<String> {
        self.layout()
            .iter()
            .map(|c| c.name(self.form).to_string())
            .collect()
    }

    fn n_regressors(&self) -> usize {
        self.layout().len()
    }

    fn regressors(&self, u: &[T]) -> Mat<T> {
        let cols = self.layout();
        let mut phi = Mat::<T>::zeros(u.len(), cols.len());
        let (fold, b, play) = (self.fold_b(), self.b_eff(), self.play());
        let idx: Vec<usize> = cols.iter().map(|&c| c as usize).collect();
        let mut out = columns_mut(&mut phi);
        if play {
            self.for_each(u, |k, uk, s, pt, _| {
                let row = row_values(uk, s, &pt, play, fold, b);
                for (col, &i) in out.iter_mut().zip(&idx) {
                    col[k] = row[i];
                }
            });
        } else {
            shift_blocks(self, u, |k0, block| {
                for (col, &i) in out.iter_mut().zip(&idx) {
                    col[k0..k0 + block[i].len()].copy_from_slice(block[i]);
                }
            });
        }
        drop(out);
        phi
    }

    /// v = φ(u)·g (the same sums, in the same order, as the regressor matrix times g, without
    /// building the matrix).
    fn eval(&self, u: &[T]) -> Vec<T> {
        let cols = self.layout();
        let g = StaticNonlinearity::<T>::gains(self);
        if !self.play()
            && let Some(v) = eval_shift_direct(self, u, &cols, &g)
        {
            return v;
        }
        match cols.len() {
            1 => eval_fixed::<T, 1>(self, u, &cols, &g),
            2 => eval_fixed::<T, 2>(self, u, &cols, &g),
            3 => eval_fixed::<T, 3>(self, u, &cols, &g),
            4 => eval_fixed::<T, 4>(self, u, &cols, &g),
            5 => eval_fixed::<T, 5>(self, u, &cols, &g),
            6 => eval_fixed::<T, 6>(self, u, &cols, &g),
            _ => eval_any(self, u, &cols, &g),
        }
    }

    fn gains(&self) -> Vec<T> {
        let p = self.p;
        self.layout()
            .iter()
            .map(|c| match c {
                Col::Slope => p,
                Col::Hyst | Col::Tied => p * self.a,
                Col::Dead => p * self.b,
                Col::High => p * self.z1,
                Col::Low => p * self.z2,
                Col::Pre1 => self.e1,
                Col::Pre2 => self.e2,
            })
            .collect()
    }

    fn update_from_gains(&mut self, g: &[T], u: &[T]) -> Result<()> {
        let cols = self.layout();
        if g.len() != cols.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "gain vector has {} entries, {} has {} regressors",
                    g.len(),
                    StaticNonlinearity::<T>::name(self),
                    cols.len()
                ),
            });
        }
        if let Some(i) = g.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                what: "UDN gain vector g".into(),
                index: i,
            });
        }
        let scale = g.iter().fold(T::zero(), |m, &x| m.max(x.abs()));
        let p = g[0];
        if !(p > T::lit(1e3) * T::epsilon() * scale.max(T::min_positive_value())) {
            return Err(Error::InvalidParameter(format!(
                "gain p = g1 = {p} is not positive and away from zero (max |g| = {scale}): \
                 thresholds cannot be recovered from the ratios"
            )));
        }
        let mut v = self.all7();
        v[0] = p;
        for (c, &gi) in cols.iter().zip(g) {
            match c {
                Col::Slope => {}
                Col::Hyst | Col::Tied => v[1] = gi / p,
                Col::Dead => v[2] = gi / p,
                Col::High => v[3] = gi / p,
                Col::Low => v[4] = gi / p,
                Col::Pre1 => v[5] = gi,
                Col::Pre2 => v[6] = gi,
            }
        }
        v[1] = v[1].max(T::zero());
        v[2] = v[2].max(T::zero());
        if self.tied {
            v[2] = v[1];
        }
        if self.has(Effect::Saturation) && !(v[3] > v[4]) {
            // Inadmissible order: the guard below resets the limits to data quantiles.
            v[3] = T::infinity();
            v[4] = T::neg_infinity();
        }
        // store without check: the guard brings the thresholds back inside the data.
        self.store(v);
        self.zone_guard(u);
        self.check(self.all7())
    }

    fn searched_params(&self) -> Vec<usize> {
        let mut s = Vec::new();
        if self.play() {
            s.push(1);
        }
        if self.has(Effect::DeadZone) && !self.tied && self.has(Effect::Preload) {
            s.push(if self.has(Effect::Hysteresis) { 2 } else { 1 });
        }
        s
    }

    fn search_range(&self, index: usize, u: &[T]) -> (T, T) {
        let names = StaticNonlinearity::<T>::param_names(self);
        let max = T::lit(MAX_WIDTH_FRACTION) * spread(u);
        match names.get(index).map(String::as_str) {
            Some("b") => (T::zero(), self.b_max(&self.record(u))),
            Some("a") if self.tied && self.has(Effect::DeadZone) => {
                let mut probe = self.clone();
                probe.a = max;
                probe.b = max;
                (T::zero(), probe.tied_a_max(&probe.record(u)))
            }
            Some("a") => (T::zero(), max),
            _ => (T::zero(), max),
        }
    }

    fn initialize(&mut self, u: &[T]) {
        let spr = spread(u);
        let w0 = T::lit(0.05) * spr;
        let mut v = [
            T::one(),
            w0,
            w0,
            T::infinity(),
            T::neg_infinity(),
            T::zero(),
            T::zero(),
        ];
        if self.tied {
            v[2] = v[1];
        }
        self.store(v);
        if self.has(Effect::Saturation) {
            let mut w = vec![T::zero(); u.len()];
            self.for_each(u, |k, _, _, p, _| w[k] = p.w);
            let mut vals = finite(w.into_iter());
            let (mut z1, mut z2) = (
                select_quantile(&mut vals, 0.9),
                select_quantile(&mut vals, 0.1),
            );
            if !(z1 > z2) {
                let c = z1;
                z1 = c + T::one();
                z2 = c - T::one();
            }
            self.z1 = if self.sides.upper() {
                z1
            } else {
                T::infinity()
            };
            self.z2 = if self.sides.lower() {
                z2
            } else {
                T::neg_infinity()
            };
        }
    }

    fn param_jacobian(&self, u: &[T]) -> Mat<T> {
        let act = self.active();
        let mut jac = Mat::<T>::zeros(u.len(), act.len());
        let p = self.p;
        let tied = self.tied && self.has(Effect::DeadZone);
        self.for_each(u, |k, _, _, pt, dxda| {
            let l = ind::<T>(pt.l);
            for (j, &i) in act.iter().enumerate() {
                jac[(k, j)] = match i {
                    0 => pt.w.max(self.z2).min(self.z1),
                    1 => {
                        let dw = if tied { dxda - pt.sx } else { dxda };
                        p * dw * l
                    }
                    2 => -p * pt.sx * l,
                    3 => p * ind::<T>(pt.h1),
                    4 => p * ind::<T>(pt.h2),
                    5 => ind(pt.p1),
                    _ => ind(pt.p2),
                };
            }
        });
        jac
    }

    fn spans_constant(&self) -> bool {
        self.has(Effect::Preload) && !self.has(Effect::DeadZone)
    }

    fn constant_pair(&self) -> Option<(usize, usize)> {
        // P1 and P2 are the layout's last two columns
        let r = self.layout().len();
        StaticNonlinearity::<T>::spans_constant(self).then(|| (r - 2, r - 1))
    }

    fn set_initial_falling(&mut self, falling: bool) -> bool {
        if !self.has(Effect::Hysteresis) {
            return false;
        }
        self.s0 = if falling { -T::one() } else { T::one() };
        true
    }

    fn initial_falling(&self) -> bool {
        self.s0 < T::zero()
    }

    fn memoryless(&self) -> bool {
        // the direction s enters only the hysteresis columns and the play
        !self.has(Effect::Hysteresis)
    }

    fn rescaled(&self, input: T, output: T) -> Option<Box<dyn StaticNonlinearity<T>>> {
        // thresholds in input units, p in output per input units, preloads in output units
        let mut out = self.clone();
        out.p = self.p * output / input;
        out.a = self.a * input;
        out.b = self.b * input;
        out.z1 = self.z1 * input;
        out.z2 = self.z2 * input;
        out.e1 = self.e1 * output;
        out.e2 = self.e2 * output;
        Some(Box::new(out))
    }

    fn input_shifted(&self, shift: T) -> Option<(Box<dyn StaticNonlinearity<T>>, T)> {
        // the hysteresis (shift or play) and the saturation's thresholds move with the input;
        // a dead-zone and the preloads sit at x = 0 and do not
        if self.has(Effect::DeadZone) || self.has(Effect::Preload) {
            return None;
        }
        let mut out = self.clone();
        if self.has(Effect::Saturation) {
            out.z1 = self.z1 - shift;
            out.z2 = self.z2 - shift;
        }
        // N(u + m) = p·(x + m) on the slope, p·z on a limit: N'(u) + p·m everywhere
        Some((Box::new(out), self.p * shift))
    }

    fn jump_params(&self) -> Vec<usize> {
        // the preload steps sit at x = ±b with x = u − a·s: a and b move them
        if !self.has(Effect::Preload) {
            return Vec::new();
        }
        let names = StaticNonlinearity::<T>::param_names(self);
        names
            .iter()
            .enumerate()
            .filter(|(_, n)| *n == "a" || *n == "b")
            .map(|(i, _)| i)
            .collect()
    }

    fn jump_positions(&self, index: usize, u: &[T]) -> Vec<T> {
        jumps::positions(self, index, u)
    }

    fn jump_step(&self, index: usize) -> Option<T> {
        Some(jumps::step(self, index))
    }

    fn kink_params(&self) -> Vec<usize> {
        kinks::params(self)
    }

    fn kink_positions(&self, index: usize, u: &[T]) -> Vec<T> {
        kinks::positions(self, index, u)
    }

    fn spec(&self) -> NonlinearitySpec {
        let kind = if StaticNonlinearity::<T>::name(self) == "backlash" {
            "backlash"
        } else {
            "udn"
        };
        let mut config = serde_json::json!({
            "effects": self.effects.effects().iter().map(|e| e.name()).collect::<Vec<_>>(),
            "hysteresis_form": self.form.name(),
            "tied": self.tied,
        });
        // the fitted initial direction, recorded only when it is not the default (rising)
        if self.s0 < T::zero() {
            config["initial_direction"] = "falling".into();
        }
        // a one-sided saturation, recorded only when it is one (the absent limit is no parameter
        // and no number in the file)
        if self.sides != SaturationSides::Both {
            config["saturation_sides"] = self.sides.name().into();
        }
        NonlinearitySpec {
            kind: kind.into(),
            config,
            param_names: StaticNonlinearity::<T>::param_names(self),
            params: self.params().iter().map(|x| x.as_f64()).collect(),
        }
    }

    fn clone_box(&self) -> Box<dyn StaticNonlinearity<T>> {
        Box::new(self.clone())
    }
}

impl<T: Real> Udn<T> {
    /// Rebuilds a UDN from a spec of kind "udn" or "backlash".
    pub fn from_spec(spec: &NonlinearitySpec) -> Result<Self> {
        let cfg = &spec.config;
        let bad = |m: String| Error::ModelFormat(format!("{} spec: {m}", spec.kind));
        let effects = match cfg.get("effects") {
            None if spec.kind == "backlash" => EffectSet::of(&[Effect::Hysteresis]),
            None => return Err(bad("missing \"effects\"".into())),
            Some(e) => {
                let list = e
                    .as_array()
                    .ok_or_else(|| bad("\"effects\" must be a list of names".into()))?;
                let mut set = EffectSet::empty();
                for x in list {
                    let name = x
                        .as_str()
                        .ok_or_else(|| bad("effect names must be strings".into()))?;
                    set = set.with(name.parse()?);
                }
                set
            }
        };
        let form = match cfg.get("hysteresis_form").and_then(|x| x.as_str()) {
            None if spec.kind == "backlash" => HysteresisForm::Play,
            None | Some("shift") => HysteresisForm::Shift,
            Some("play") => HysteresisForm::Play,
            Some(o) => return Err(bad(format!("unknown hysteresis_form '{o}' (shift, play)"))),
        };
        let tied = cfg.get("tied").and_then(|x| x.as_bool()).unwrap_or(false);
        let sides = match cfg.get("saturation_sides") {
            None => SaturationSides::Both,
            Some(x) => x.as_str().and_then(SaturationSides::parse).ok_or_else(|| {
                bad(format!(
                    "unknown saturation_sides {x} (\"both\", \"upper\", \"lower\")"
                ))
            })?,
        };
        let mut udn = Self::new(effects)
            .with_form(form)
            .with_tied(tied)?
            .with_saturation_sides(sides)
            .map_err(|e| bad(e.to_string()))?;
        match cfg.get("initial_direction").and_then(|x| x.as_str()) {
            None | Some("rising") => {}
            Some("falling") => {
                StaticNonlinearity::<T>::set_initial_falling(&mut udn, true);
            }
            Some(o) => {
                return Err(bad(format!(
                    "unknown initial_direction '{o}' (rising, falling)"
                )));
            }
        }
        if !spec.params.is_empty() {
            let theta: Vec<T> = spec.params.iter().map(|&x| T::lit(x)).collect();
            udn.set_params(&theta)?;
        }
        Ok(udn)
    }
}
