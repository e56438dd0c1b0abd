//! One pass of the loop's steps 1–6 from the current θ (`Problem::pass`), with the bounded 1-D
//! search of the parameters the gains cannot determine (`searched_params`: a grid, then golden
//! section on an adaptive bracket kept in `SearchWidths`), and the exact-fit check at the searched
//! parameters' lower ends.

use super::problem::{Iterate, Problem, Workspace, normalise_iterate};
use crate::error::Result;
use crate::fit::numerics::golden::Bracket;
use crate::fit::numerics::linear_ls::fit_gains_given_block;
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
                cand: Candidates {
                    problem: self,
                    nl: &*nl,
                    j,
                    r,
                    a,
                    c,
                    base: &base,
                },
                ws: &mut *ws,
                best: None,
                tried: Vec::new(),
                ahead: None,
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

/// Records up to this length evaluate the search's independent candidates two at a time
/// (`rayon::join`: the grid, the local start's points, golden section's first pair); longer ones
/// in turn, holding one candidate's regressors and least squares at a time.
const PARALLEL_SEARCH_ROWS: usize = 65_536;

/// What the candidates of the 1-D search of parameter `j` given (A, C) share (read only, so
/// that two candidates can be evaluated side by side).
struct Candidates<'p, 'a, T: Real> {
    problem: &'p Problem<'a, T>,
    nl: &'p dyn StaticNonlinearity<T>,
    j: usize,
    /// Regressor count of the nonlinearity when the search began.
    r: usize,
    a: MatRef<'p, T>,
    c: MatRef<'p, T>,
    /// The single-input block the candidates' gain steps hold fixed.
    base: &'p Iterate<T>,
}

/// The 1-D search of one parameter given (A, C): the candidates tried so far, the best kept.
struct LineSearch<'p, 'a, T: Real> {
    cand: Candidates<'p, 'a, T>,
    ws: &'p mut Workspace<T>,
    /// (MSE floored at the exact level, value, iterate) of the best candidate so far.
    best: Option<(f64, f64, Iterate<T>)>,
    /// (value, floored MSE) of every candidate so far (for golden section's guesses).
    tried: Vec<(f64, f64)>,
    /// A candidate evaluated ahead on a guess (value, iterate), until the next evaluation.
    ahead: Option<(f64, Option<Iterate<T>>)>,
}

impl<T: Real> LineSearch<'_, '_, T> {
    /// The MSEs of the candidates `xs` (floored at the exact-fit level, +∞ when inadmissible),
    /// recorded in `xs`'s order, so that the best kept is the one of trying them in turn. MSEs
    /// at the exact-fit level count as equal: the first such candidate (the range's lower end,
    /// "no effect", is tried first) is kept. The candidates are independent and, on records of
    /// at most `PARALLEL_SEARCH_ROWS` samples, evaluated half on each of two threads, the second
    /// half with the workspace's `side` buffers.
    fn consider_all(&mut self, xs: &[f64], guess: Option<f64>) -> Vec<f64> {
        // a point evaluated ahead (a guess) is not evaluated again
        let ahead = self.ahead.take();
        let hit = ahead
            .as_ref()
            .and_then(|(xa, _)| xs.iter().position(|x| x.to_bits() == xa.to_bits()));
        let todo: Vec<f64> = (0..xs.len())
            .filter(|&i| Some(i) != hit)
            .map(|i| xs[i])
            .collect();
        let mut values = self.values_of(&todo, guess).into_iter();
        let mut ahead = ahead.map(|(_, it)| it);
        let all: Vec<Option<Iterate<T>>> = (0..xs.len())
            .map(|i| {
                if Some(i) == hit {
                    ahead.take().flatten()
                } else {
                    values.next().flatten()
                }
            })
            .collect();
        xs.iter()
            .zip(all)
            .map(|(&x, it)| self.record(x, it))
            .collect()
    }

    /// The candidates `xs` evaluated (in turn, or half on each of two threads on records of at
    /// most `PARALLEL_SEARCH_ROWS` samples, the second half with the workspace's `side`
    /// buffers), and `guess` kept ahead when the second thread has time for it (it took the
    /// smaller half, or a lone candidate was left to the first).
    fn values_of(&mut self, xs: &[f64], guess: Option<f64>) -> Vec<Option<Iterate<T>>> {
        let parallel = self.cand.problem.y.len() <= PARALLEL_SEARCH_ROWS;
        if !parallel || xs.is_empty() || (xs.len() == 1 && guess.is_none()) {
            return self.cand.values(self.ws, xs);
        }
        let (first, second) = xs.split_at(xs.len().div_ceil(2));
        let guess = guess.filter(|_| second.len() < first.len());
        let mut side = Workspace {
            ls: std::mem::take(&mut self.ws.side),
            side: Default::default(),
        };
        let (cand, ws) = (&self.cand, &mut *self.ws);
        let (mut va, (vb, spec)) = rayon::join_context(
            |_| cand.values(ws, first),
            |ctx| {
                let vb = cand.values(&mut side, second);
                // a guess only when this half runs beside the first, not after it
                let spec = guess
                    .filter(|_| ctx.migrated())
                    .map(|g| (g, cand.value(&mut side, T::lit(g))));
                (vb, spec)
            },
        );
        self.ws.side = side.ls;
        if spec.is_some() {
            self.ahead = spec;
        }
        va.extend(vb);
        va
    }
    /// Keeps the candidate `x` (iterate `it`, `None` when inadmissible) when best; its MSE
    /// floored at the exact-fit level (+∞ when inadmissible).
    fn record(&mut self, x: f64, it: Option<Iterate<T>>) -> f64 {
        let m = self.keep(x, it);
        self.tried.push((x, m));
        m
    }

    /// [`Self::record`] without the history.
    fn keep(&mut self, x: f64, it: Option<Iterate<T>>) -> f64 {
        match it {
            Some(it) => {
                let m = it.mse.max(self.cand.problem.floor);
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
            self.consider_all(&grid, None);
            (width, SEARCH_GOLDEN)
        } else {
            // the lower end (b = 0: no dead-zone) is always tried exactly, and first; the
            // upper end when it lies inside the bracket
            let mut points = Vec::with_capacity(3);
            if lo != current {
                points.push(lo);
            }
            points.push(current);
            if (hi - current).abs() <= width && hi != current {
                points.push(hi);
            }
            // beside the odd third point: golden section's first point about the current value
            // (`golden`'s bracket when the current value stays the best, as it mostly does)
            let guess = Bracket::new((current - width).max(lo), (current + width).min(hi)).x1;
            self.consider_all(&points, Some(guess));
            (width, SEARCH_GOLDEN_LOCAL)
        }
    }

    /// Golden section on [x_best − width, x_best + width] ∩ [lo, hi], `steps` steps. On records
    /// of at most `PARALLEL_SEARCH_ROWS` samples each step's point is evaluated beside a guess of
    /// the next step's (`Bracket::guess_left`), when the pool's other thread is free to take it
    /// (`join_context`'s `migrated`: otherwise the guess is skipped, not run after); a right
    /// guess saves the next step's evaluation. The points and their order are those of the
    /// search in turn, so its result is the same.
    fn golden(&mut self, x_best: f64, width: f64, (lo, hi): (f64, f64), steps: usize) {
        let (l, h) = ((x_best - width).max(lo), (x_best + width).min(hi));
        let mut br = Bracket::new(l, h);
        let (mut f1, mut f2) = match self.consider_all(&[br.x1, br.x2], None)[..] {
            [f1, f2] => (f1, f2),
            _ => return,
        };
        let parallel = self.cand.problem.y.len() <= PARALLEL_SEARCH_ROWS;
        for s in 0..steps {
            let left = f1 <= f2;
            let (next, x) = br.step(left);
            let guess = (parallel && s + 1 < steps).then(|| {
                let kept = if left { (br.x1, f1) } else { (br.x2, f2) };
                next.step(next.guess_left(left, kept, x, &self.tried)).1
            });
            let it = match self.consider_all(&[x], guess)[..] {
                [f] => f,
                _ => f64::INFINITY,
            };
            (f1, f2) = if left { (it, f1) } else { (f2, it) };
            br = next;
        }
    }
}

impl<T: Real> Candidates<'_, '_, T> {
    /// [`Self::value`] of each point of `xs` in turn, with the workspace `ws`.
    fn values(&self, ws: &mut Workspace<T>, xs: &[f64]) -> Vec<Option<Iterate<T>>> {
        xs.iter().map(|&x| self.value(ws, T::lit(x))).collect()
    }

    /// The iterate after fixing parameter `j` at `t`, given (A, C); `None` when the value is
    /// inadmissible. The gains come from the gain step of alternating least squares — the
    /// current single-input block `base` (A, b, C, d) fixed, g, x0 and the offset free (m + n + 1
    /// unknowns, against the m·n + n + 1 of the loop's relaxed step 3, which made every candidate
    /// 2× dearer and, in the paper's loop, biased b, e1, e2 more: Table 2's b RMSE 0.068 against
    /// 0.046 now); then θ from g and step 6 (the block refitted for v = N(u; θ)).
    fn value(&self, ws: &mut Workspace<T>, t: T) -> Option<Iterate<T>> {
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
            &mut ws.ls,
        )
        .ok()?;
        let g: Vec<T> = (0..phi_cols).map(|q| fit.b[(0, q)]).collect();
        trial.update_from_gains(&g, &p.u).ok()?;
        let mut theta = trial.params();
        if theta[j] != t {
            theta[j] = t;
            trial.set_params(&theta).ok()?;
        }
        p.evaluate(ws, trial.as_ref(), self.a, self.c).ok()
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
