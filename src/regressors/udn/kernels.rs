//! The UDN's evaluation kernels: every column's value at a sample as one branch-free row, and
//! v = φ·g formed block by block, column after column, with each sample's products summed in the
//! columns' order (the same sums as the regressor matrix times g, so the results are
//! bit-identical to it).

use super::{Col, Point, Udn, ind};
use crate::real::Real;
use crate::regressors::direction::DirectionTracker;

/// Every regressor column's value at one sample (input `uk`, direction `s`, zones `pt`),
/// indexed by `Col as usize`: one branch-free row the layout picks its columns from, so that
/// `regressors` and `eval` do not match the column kind per sample.
#[inline(always)]
pub(super) fn row_values<T: Real>(
    uk: T,
    s: T,
    pt: &Point<T>,
    play: bool,
    fold: bool,
    b: T,
) -> [T; 8] {
    let base = if play { pt.x } else { uk };
    let base = if fold { base - b * pt.sx } else { base };
    let l = ind::<T>(pt.l);
    [
        base * l,
        -s * l,
        -(s + pt.sx) * l,
        -pt.sx * l,
        ind(pt.h1),
        ind(pt.h2),
        ind(pt.p1),
        ind(pt.p2),
    ]
}

/// v = φ·g sample by sample for a layout of `R` columns (`idx`: each column's place in
/// [`row_values`]), the products summed in the columns' order from zero: the same sums as the
/// regressor matrix times g, with the column count known to the compiler.
pub(super) fn eval_layout<T: Real, const R: usize>(
    udn: &Udn<T>,
    u: &[T],
    idx: [usize; R],
    g: [T; R],
) -> Vec<T> {
    let (fold, b, play) = (udn.fold_b(), udn.b_eff(), udn.play());
    let sum = |row: [T; 8]| {
        let mut acc = T::zero();
        for j in 0..R {
            acc += row[idx[j]] * g[j];
        }
        acc
    };
    if play {
        let mut v = Vec::with_capacity(u.len());
        udn.for_each(u, |_, uk, s, pt, _| {
            v.push(sum(row_values(uk, s, &pt, play, fold, b)))
        });
        return v;
    }
    // Shift form: block by block, column after column (each sample's products still added
    // in the columns' order, from zero), so that the sums run over contiguous samples
    let mut v = Vec::with_capacity(u.len());
    shift_blocks(udn, u, |k0, cols| {
        // the first column's products added to zero as they are pushed (no zeroed buffer)
        v.extend(cols[idx[0]].iter().map(|&c| T::zero() + c * g[0]));
        let out = &mut v[k0..];
        for j in 1..R {
            let gj = g[j];
            for (o, &c) in out.iter_mut().zip(cols[idx[j]]) {
                *o += c * gj;
            }
        }
    });
    v
}

/// Samples per block of the Shift form's column kernels (`shift_blocks`).
pub(super) const BLOCK: usize = 64;

/// The eight column values ([`row_values`]) of the Shift-form samples (inputs `u`, directions
/// `s`, at most `BLOCK`) into `cols[c][i]`.
#[inline(always)]
pub(super) fn shift_block<T: Real>(udn: &Udn<T>, (u, s): (&[T], &[T]), cols: &mut [[T; BLOCK]; 8]) {
    let (a, fold, b) = (udn.a_eff(), udn.fold_b(), udn.b_eff());
    for (i, (&uk, &sk)) in u.iter().zip(s).enumerate() {
        let row = row_values(uk, sk, &udn.point(uk - a * sk), false, fold, b);
        for (col, &r) in cols.iter_mut().zip(&row) {
            col[i] = r;
        }
    }
}

/// The Shift form's column values block by block: `f(k0, cols)` with the block's first sample
/// `k0` and its eight columns, each as long as the block.
pub(super) fn shift_blocks<T: Real>(udn: &Udn<T>, u: &[T], mut f: impl FnMut(usize, [&[T]; 8])) {
    // the directions from the record's cache, or tracked block by block (a record too long
    // for the cache gets no copy of its length)
    let cached = udn.input.get(u, udn.s0);
    let mut dir = DirectionTracker::<T>::with_initial(udn.s0);
    let mut s_block = [T::zero(); BLOCK];
    let mut cols = [[T::zero(); BLOCK]; 8];
    for (blk, ub) in u.chunks(BLOCK).enumerate() {
        let (k0, len) = (blk * BLOCK, ub.len());
        let sb: &[T] = match &cached {
            Some(st) => &st.s[k0..k0 + len],
            None => {
                for (o, &x) in s_block.iter_mut().zip(ub) {
                    *o = dir.next(x);
                }
                &s_block[..len]
            }
        };
        shift_block(udn, (ub, sb), &mut cols);
        f(k0, std::array::from_fn(|c| &cols[c][..len]));
    }
}

/// `eval_layout` for any column count (the same sums, the count not known to the compiler).
pub(super) fn eval_any<T: Real>(udn: &Udn<T>, u: &[T], cols: &[Col], g: &[T]) -> Vec<T> {
    let (fold, b, play) = (udn.fold_b(), udn.b_eff(), udn.play());
    let mut v = Vec::with_capacity(u.len());
    udn.for_each(u, |_, uk, s, pt, _| {
        let row = row_values(uk, s, &pt, play, fold, b);
        let mut acc = T::zero();
        for (&c, &gj) in cols.iter().zip(g) {
            acc += row[c as usize] * gj;
        }
        v.push(acc);
    });
    v
}

/// `eval_layout` for a layout of `R` columns (`cols`, with gains `g`).
pub(super) fn eval_fixed<T: Real, const R: usize>(
    udn: &Udn<T>,
    u: &[T],
    cols: &[Col],
    g: &[T],
) -> Vec<T> {
    let idx: [usize; R] = std::array::from_fn(|j| cols[j] as usize);
    let gs: [T; R] = std::array::from_fn(|j| g[j]);
    eval_layout(udn, u, idx, gs)
}

/// The gains of the Shift form's columns by kind, 0 for a column not in the layout (its product
/// is then ±0, which leaves the sum unchanged), for [`eval_shift_direct`].
struct ShiftGains<T> {
    slope: T,
    /// Of −s·L (untied) or −(s + sign x)·L (tied), with `tied` telling which.
    hyst: T,
    tied: bool,
    dead: T,
    high: T,
    low: T,
    pre1: T,
    pre2: T,
}

/// One sample of [`eval_shift_direct`]: input `uk`, direction `s`.
#[inline(always)]
fn shift_value<T: Real>(
    udn: &Udn<T>,
    k: &ShiftGains<T>,
    (a, fold, b): (T, bool, T),
    uk: T,
    s: T,
) -> T {
    let pt = udn.point(uk - a * s);
    let zero = T::zero();
    let zone = if pt.l {
        let base = if fold { uk - b * pt.sx } else { uk };
        let hyst = if k.tied { -(s + pt.sx) } else { -s };
        zero + base * k.slope + hyst * k.hyst + -pt.sx * k.dead
    } else if pt.h1 {
        zero + k.high
    } else if pt.h2 {
        zero + k.low
    } else {
        zero
    };
    let p1 = if pt.p1 { k.pre1 } else { zero };
    let p2 = if pt.p2 { k.pre2 } else { zero };
    zone + p1 + p2
}

/// `eval_layout` of the Shift form summing only the zone's products: per sample the sloped
/// part's terms or one limit's gain, then the preloads', in the layout's order, from +0. The
/// bits are those of `eval_layout`: a column whose indicator is 0 (or that the layout lacks,
/// gain 0 here) gives a product ±0 (the gains finite), and adding ±0 to a sum started at +0
/// leaves it unchanged, because such a sum is never −0 (x + y = −0 needs x = y = −0). `None`
/// when a gain or an input is not finite or the layout is not in [`Col`]'s order (the caller
/// then takes `eval_layout`).
pub(super) fn eval_shift_direct<T: Real>(
    udn: &Udn<T>,
    u: &[T],
    cols: &[Col],
    g: &[T],
) -> Option<Vec<T>> {
    if cols.len() != g.len()
        || !g.iter().all(|x| x.is_finite())
        || !cols.windows(2).all(|w| (w[0] as usize) < (w[1] as usize))
    {
        return None;
    }
    let zero = T::zero();
    let mut k = ShiftGains {
        slope: zero,
        hyst: zero,
        tied: false,
        dead: zero,
        high: zero,
        low: zero,
        pre1: zero,
        pre2: zero,
    };
    for (&c, &gj) in cols.iter().zip(g) {
        match c {
            Col::Slope => k.slope = gj,
            Col::Hyst => k.hyst = gj,
            Col::Tied => (k.hyst, k.tied) = (gj, true),
            Col::Dead => k.dead = gj,
            Col::High => k.high = gj,
            Col::Low => k.low = gj,
            Col::Pre1 => k.pre1 = gj,
            Col::Pre2 => k.pre2 = gj,
        }
    }
    let shape = (udn.a_eff(), udn.fold_b(), udn.b_eff());
    let mut v = Vec::with_capacity(u.len());
    match udn.input.get(u, udn.s0) {
        Some(st) => v.extend(
            u.iter()
                .zip(&st.s[..u.len()])
                .map(|(&uk, &s)| shift_value(udn, &k, shape, uk, s)),
        ),
        None => {
            // a record the cache refused for its values: `eval_layout`'s NaNs are kept
            if !u.iter().all(|x| x.is_finite()) {
                return None;
            }
            let mut dir = DirectionTracker::<T>::with_initial(udn.s0);
            v.extend(
                u.iter()
                    .map(|&uk| shift_value(udn, &k, shape, uk, dir.next(uk))),
            );
        }
    }
    Some(v)
}
