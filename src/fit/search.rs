//! One pass of the loop's steps 1–6 from the current θ (`Problem::pass`), with the bounded 1-D
//! search of the parameters the gains cannot determine (`searched_params`: a grid, then golden
//! section on an adaptive bracket kept in `SearchWidths`), and the exact-fit check at the searched
//! parameters' lower ends.

use super::linear_ls::fit_gains_given_block;
use super::problem::{Iterate, Problem, Workspace, normalise_iterate};
use crate::error::Result;
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use faer::MatRef;

/// Grid points of the 1-D search of a searched parameter before golden-section refinement.
pub(crate) const SEARCH_GRID: usize = 9;
/// Golden-section steps after the grid.
pub(crate) const SEARCH_GOLDEN: usize = 6;
/// Golden-section steps of the local search of later iterations (the first iteration searches the
/// whole range).
pub(crate) const SEARCH_GOLDEN_LOCAL: usize = 4;
/// Iterations with the searched parameters fixed at their lower ends tried after an exact fit.
pub(crate) const LOWER_END_ITERATIONS: usize = 4;
/// Factor by which the local bracket shrinks after a search whose best point was inside it (it
/// doubles when the best point was at its edge).
pub(crate) const SEARCH_SHRINK: f64 = 0.25;

/// Half-width of the next local search bracket per searched parameter (NaN: not set yet).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct SearchWidths(pub Vec<f64>);

impl SearchWidths {
    /// The stored half-width of parameter `j` (NaN when not set).
    pub fn get(&self, j: usize) -> f64 {
        self.0.get(j).copied().unwrap_or(f64::NAN)
    }
    /// Stores the half-width of parameter `j`.
    pub fn set(&mut self, j: usize, w: f64) {
        if self.0.len() <= j {
            self.0.resize(j + 1, f64::NAN);
        }
        self.0[j] = w;
    }
}

impl<T: Real> Problem<'_, T> {
    /// Bounded 1-D search over each searched parameter; θ is set to the best candidate found (or
    /// left unchanged) and, with one searched parameter, its iterate is returned. `global` (first
    /// iteration): a grid over the whole range, then golden-section refinement around the best
    /// grid point; otherwise the lower range end, the current value and golden section on the
    /// adaptive bracket kept in `widths` (see `docs/algorithm.md`).
    fn search(
        &self,
        ws: &mut Workspace<T>,
        widths: &mut SearchWidths,
        nl: &mut dyn StaticNonlinearity<T>,
        a: MatRef<'_, T>,
        c: MatRef<'_, T>,
        global: bool,
    ) -> Result<Option<Iterate<T>>> {
        let r = nl.n_regressors();
        let mut chosen = None;
        // the single-input block the candidates' gain steps hold fixed
        let base = self.evaluate(ws, nl, a, c)?;
        for j in nl.searched_params() {
            let (lo, hi) = nl.search_range(j, &self.u);
            let (lo, hi) = (lo.as_f64(), hi.as_f64());
            if !(lo.is_finite() && hi.is_finite() && hi >= lo) {
                continue;
            }
            let current = nl.params()[j].as_f64();
            let mut line = LineSearch {
                problem: self,
                ws: &mut *ws,
                nl: &*nl,
                j,
                r,
                a,
                c,
                base: &base,
                best: None,
            };
            let (width, golden_steps) = line.start(lo, hi, current, widths.get(j), global);
            let Some(x_best) = line.best.as_ref().map(|b| b.1) else {
                continue;
            };
            line.golden(x_best, width, (lo, hi), golden_steps);
            let x_final = line.best.as_ref().map_or(x_best, |b| b.1);
            let best = line.best;
            widths.set(j, next_width(x_best, x_final, width, (lo, hi)));
            if let Some((_, _, it)) = best {
                nl.set_params(&it.theta)?;
                chosen = Some(it);
            }
        }
        // the chosen candidate's iterate is the step's evaluation when one parameter was searched
        Ok(if nl.searched_params().len() == 1 {
            chosen
        } else {
            None
        })
    }

    /// When the searched parameters are above their lower ends: up to `LOWER_END_ITERATIONS`
    /// iterations with them fixed at the lower ends (steps 1–6, no search); the iterate when it
    /// fits exactly (MSE at the floor).
    pub fn exact_at_lower_end(
        &self,
        ws: &mut Workspace<T>,
        nl: &dyn StaticNonlinearity<T>,
        order: Option<usize>,
        offset_hint: Option<T>,
    ) -> Option<Iterate<T>> {
        let searched = nl.searched_params();
        let mut trial = nl.clone_box();
        let mut theta = trial.params();
        let mut moved = false;
        for &j in &searched {
            let lo = nl.search_range(j, &self.u).0;
            if theta[j] != lo {
                theta[j] = lo;
                moved = true;
            }
        }
        if !moved {
            return None;
        }
        trial.set_params(&theta).ok()?;
        for _ in 0..LOWER_END_ITERATIONS {
            let phi = trial.regressors(&self.u);
            let mode = self.offset_mode(trial.as_ref());
            let (a, c, _, _) = self
                .identify_ac(phi.as_ref(), order, offset_hint, mode)
                .ok()?;
            self.update_gains(ws, trial.as_mut(), phi.as_ref(), a.as_ref(), c.as_ref())
                .ok()?;
            let mut th = trial.params();
            for &j in &searched {
                th[j] = theta[j];
            }
            trial.set_params(&th).ok()?;
            let mut it = self
                .evaluate(ws, trial.as_ref(), a.as_ref(), c.as_ref())
                .ok()?;
            normalise_iterate(self, trial.as_mut(), &mut it);
            if it.mse <= self.floor {
                return Some(it);
            }
        }
        None
    }

    /// One complete pass of steps 1–6 from the current θ. Returns the iterate, the order and
    /// the singular values of the subspace step.
    pub fn pass(
        &self,
        ws: &mut Workspace<T>,
        widths: &mut SearchWidths,
        nl: &mut dyn StaticNonlinearity<T>,
        order: Option<usize>,
        offset_hint: Option<T>,
    ) -> Result<(Iterate<T>, usize, Vec<f64>)> {
        let phi = nl.regressors(&self.u);
        self.pass_from(ws, widths, nl, phi.as_ref(), order, offset_hint)
    }

    /// `pass` with the regressors of the current θ already computed.
    pub fn pass_from(
        &self,
        ws: &mut Workspace<T>,
        widths: &mut SearchWidths,
        nl: &mut dyn StaticNonlinearity<T>,
        phi: MatRef<'_, T>,
        order: Option<usize>,
        offset_hint: Option<T>,
    ) -> Result<(Iterate<T>, usize, Vec<f64>)> {
        let mode = self.offset_mode(nl);
        let (a, c, sv, n) = self.identify_ac(phi, order, offset_hint, mode)?;
        self.update_gains(ws, nl, phi, a.as_ref(), c.as_ref())?;
        let searched = if nl.searched_params().is_empty() {
            None
        } else {
            self.search(ws, widths, nl, a.as_ref(), c.as_ref(), order.is_none())?
        };
        let mut it = match searched {
            Some(it) => it,
            None => self.evaluate(ws, nl, a.as_ref(), c.as_ref())?,
        };
        normalise_iterate(self, nl, &mut it);
        Ok((it, n, sv))
    }
}

/// The 1-D search of one parameter `j` given (A, C): the candidates tried so far, the best kept.
struct LineSearch<'p, 'a, T: Real> {
    problem: &'p Problem<'a, T>,
    ws: &'p mut Workspace<T>,
    nl: &'p dyn StaticNonlinearity<T>,
    j: usize,
    /// Regressor count of the nonlinearity when the search began.
    r: usize,
    a: MatRef<'p, T>,
    c: MatRef<'p, T>,
    /// The single-input block the candidates' gain steps hold fixed.
    base: &'p Iterate<T>,
    /// (MSE floored at the exact level, value, iterate) of the best candidate so far.
    best: Option<(f64, f64, Iterate<T>)>,
}

impl<T: Real> LineSearch<'_, '_, T> {
    /// The candidate `x`'s MSE (floored at the exact-fit level, +∞ when inadmissible), kept when
    /// best. MSEs at the exact-fit level count as equal: the first such candidate (the range's
    /// lower end, "no effect", is tried first) is kept.
    fn consider(&mut self, x: f64) -> f64 {
        match self.value(T::lit(x)) {
            Some(it) => {
                let m = it.mse.max(self.problem.floor);
                if self.best.as_ref().is_none_or(|b| m < b.0) {
                    self.best = Some((m, x, it));
                }
                m
            }
            None => f64::INFINITY,
        }
    }

    /// The first candidates: the grid over [lo, hi] (and the current value) when global or no
    /// bracket is stored, otherwise the lower end, the current value and the upper end when it
    /// lies inside the stored bracket. Returns the bracket's half-width (one grid step after the
    /// grid, the stored width otherwise) and the golden-section steps to run.
    fn start(&mut self, lo: f64, hi: f64, current: f64, stored: f64, global: bool) -> (f64, usize) {
        let step = (hi - lo) / (SEARCH_GRID - 1) as f64;
        let in_range = current.is_finite() && current >= lo && current <= hi;
        let local = !global && in_range && stored.is_finite() && stored > 0.0;
        let width = if local { stored.min(hi - lo) } else { step };
        if !local {
            let mut grid: Vec<f64> = (0..SEARCH_GRID).map(|i| lo + step * i as f64).collect();
            if in_range {
                grid.push(current);
            }
            for &x in &grid {
                self.consider(x);
            }
            (width, SEARCH_GOLDEN)
        } else {
            // the lower end (b = 0: no dead-zone) is always tried exactly, and first; the
            // upper end when it lies inside the bracket
            if lo != current {
                self.consider(lo);
            }
            self.consider(current);
            if (hi - current).abs() <= width && hi != current {
                self.consider(hi);
            }
            (width, SEARCH_GOLDEN_LOCAL)
        }
    }

    /// Golden section on [x_best − width, x_best + width] ∩ [lo, hi], `steps` steps.
    fn golden(&mut self, x_best: f64, width: f64, (lo, hi): (f64, f64), steps: usize) {
        let (mut l, mut h) = ((x_best - width).max(lo), (x_best + width).min(hi));
        let gr = (5f64.sqrt() - 1.0) / 2.0;
        let mut x1 = h - gr * (h - l);
        let mut x2 = l + gr * (h - l);
        let mut f1 = self.consider(x1);
        let mut f2 = self.consider(x2);
        for _ in 0..steps {
            if f1 <= f2 {
                h = x2;
                x2 = x1;
                f2 = f1;
                x1 = h - gr * (h - l);
                f1 = self.consider(x1);
            } else {
                l = x1;
                x1 = x2;
                f1 = f2;
                x2 = l + gr * (h - l);
                f2 = self.consider(x2);
            }
        }
    }

    /// The iterate after fixing parameter `j` at `t`, given (A, C); `None` when the value is
    /// inadmissible. The gains come from the gain step of alternating least squares — the
    /// current single-input block `base` (A, b, C, d) fixed, g, x0 and the offset free (m + n + 1
    /// unknowns, against the m·n + n + 1 of the loop's relaxed step 3, which made every candidate
    /// 2× dearer and, in the paper's loop, biased b, e1, e2 more: Table 2's b RMSE 0.068 against
    /// 0.046 now); then θ from g and step 6 (the block refitted for v = N(u; θ)).
    fn value(&mut self, t: T) -> Option<Iterate<T>> {
        let (p, j) = (self.problem, self.j);
        let phi_cols = self.r;
        let mut trial = self.nl.clone_box();
        let mut theta = trial.params();
        theta[j] = t;
        trial.set_params(&theta).ok()?;
        let phi = trial.regressors(&p.u);
        if phi.ncols() != phi_cols {
            return None;
        }
        let fit = fit_gains_given_block(
            p.la,
            self.a,
            &self.base.b,
            self.c,
            self.base.d,
            phi.as_ref(),
            &p.y,
            p.terms(trial.as_ref()),
            &mut self.ws.ls,
        )
        .ok()?;
        let g: Vec<T> = (0..phi_cols).map(|q| fit.b[(0, q)]).collect();
        trial.update_from_gains(&g, &p.u).ok()?;
        let mut theta = trial.params();
        if theta[j] != t {
            theta[j] = t;
            trial.set_params(&theta).ok()?;
        }
        p.evaluate(self.ws, trial.as_ref(), self.a, self.c).ok()
    }
}

/// The next bracket's half-width: shrunk around an interior optimum, widened when the optimum
/// hit the bracket's edge (golden section never evaluates the bracket ends: "at the edge" = in
/// its outer 20 %).
fn next_width(x_best: f64, x_final: f64, width: f64, (lo, hi): (f64, f64)) -> f64 {
    let at_edge = (x_final - (x_best - width)).abs() < 0.2 * width
        || (x_final - (x_best + width)).abs() < 0.2 * width;
    if at_edge {
        (2.0 * width).min(hi - lo)
    } else {
        (SEARCH_SHRINK * width).max(f64::EPSILON * (hi - lo).max(f64::MIN_POSITIVE))
    }
}
