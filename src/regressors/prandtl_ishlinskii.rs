//! Dynamic hysteresis: the Prandtl–Ishlinskii (PI) operator, a weighted sum of play (backlash)
//! operators on a fixed threshold grid, added to a base nonlinearity (a UDN):
//! v(k) = N_base(u)(k) + Σ_j w_j·F_{r_j}\[u\](k).
//!
//! Play operator (Brokate & Sprekels 1996, *Hysteresis and Phase Transitions*, §2.3; Kuhnen 2003,
//! "Modeling, identification and compensation of complex hysteretic nonlinearities: a modified
//! Prandtl–Ishlinskii approach", European Journal of Control 9(4)):
//! F_r\[u\](k) = max(u(k) − r, min(u(k) + r, F_r\[u\](k − 1))), started from the grid's centre c:
//! F_r\[u\](−1) = c, i.e. F_r\[u\](0) = clamp(c, u(0) − r, u(0) + r).
//!
//! The loop width of the sum grows with the amplitude of the input's reversals (a play of
//! threshold r only opens a loop for reversals wider than 2r), unlike the UDN's constant-width
//! hysteresis. The operator is linear in its weights w, so the loop's linear-in-parameters step
//! estimates them with the base's gains; with the UDN's gain p the identity (r = 0) term of the
//! classic PI operator is already in the base.
//!
//! Grid: K thresholds r_j = (j/(K + 1))^1.5·R, j = 1..K, with R half the input's range and c
//! its mid-range (denser at small thresholds, where PI weight densities concentrate), fixed by [`initialize`](StaticNonlinearity::initialize) on the (normalised)
//! training input and kept afterwards (as configuration, not parameters): the model evaluates
//! other records on the same grid.
//!
//! Subset of the grid: [`PrandtlIshlinskii::on_subset`] keeps only some of the K plays (the
//! others' weights fixed at 0), so that a fit can constrain the weights to one sign by an outer
//! active set (Lawson & Hanson 1974, *Solving Least Squares Problems*, ch. 23: the variables
//! whose estimates leave the feasible side are removed and the rest refitted). The kept plays
//! keep their grid positions in their names (w2, w5, … of the K-grid).

use super::{NonlinearitySpec, StaticNonlinearity, from_spec};
use crate::error::{Error, Result};
use crate::real::Real;
use faer::Mat;

/// Default number of play operators K.
pub const DEFAULT_PLAYS: usize = 6;
/// Half-range R of the grid before it is fixed from data (inputs normalised by their RMS).
const DEFAULT_RANGE: f64 = 2.0;

/// The play (backlash) operator F_r\[u\] started from `start` (F_r\[u\](−1) = start). The
/// threshold `r` is a half-width: 0 or more (infinite: the output stays at `start`); a NaN or
/// negative `r`, or a non-finite `start`, is [`Error::InvalidParameter`].
pub fn play<T: Real>(u: &[T], r: T, start: T) -> Result<Vec<T>> {
    if r.is_nan() || r < T::zero() {
        return Err(Error::InvalidParameter(format!(
            "play operator: threshold {} (a half-width ≥ 0 is needed)",
            r.as_f64()
        )));
    }
    if !start.is_finite() {
        return Err(Error::InvalidParameter(format!(
            "play operator: start value {} (a finite value is needed)",
            start.as_f64()
        )));
    }
    Ok(play_checked(u, r, start))
}

/// [`play`] of a threshold and start already checked (the grid's: `check_grid`).
pub(crate) fn play_checked<T: Real>(u: &[T], r: T, start: T) -> Vec<T> {
    let mut y = start;
    u.iter()
        .map(|&x| {
            y = (x - r).max((x + r).min(y));
            y
        })
        .collect()
}

/// The thresholds r_j = (j/(K + 1))^1.5·R, j = 1..K, and centre c of the grid for input `u`
/// (R half its range, c its mid-range); `None` for a constant or non-finite input.
pub fn grid<T: Real>(u: &[T], k: usize) -> Option<(Vec<T>, T)> {
    let lo = u.iter().fold(T::infinity(), |m, &x| m.min(x));
    let hi = u.iter().fold(T::neg_infinity(), |m, &x| m.max(x));
    let half = (hi - lo) / T::lit(2.0);
    if !(half.is_finite() && half > T::zero()) {
        return None;
    }
    let r = (1..=k)
        .map(|j| half * (T::from_usize(j) / T::from_usize(k + 1)).powf(T::lit(1.5)))
        .collect();
    Some((r, (hi + lo) / T::lit(2.0)))
}

/// A base nonlinearity plus a Prandtl–Ishlinskii sum of K weighted play operators.
///
/// Parameters: the base's θ followed by the weights w1..wK (so the base's searched and jump
/// parameter indices stay valid).
#[derive(Debug, Clone)]
pub struct PrandtlIshlinskii<T: Real> {
    base: Box<dyn StaticNonlinearity<T>>,
    thresholds: Vec<T>,
    centre: T,
    weights: Vec<T>,
    grid_from_data: bool,
    /// Size K of the grid the thresholds are drawn from.
    grid_size: usize,
    /// Positions (1-based, increasing) of the kept plays on the K-grid.
    kept: Vec<usize>,
}

impl<T: Real> PrandtlIshlinskii<T> {
    /// `base` plus `k` play operators whose grid is fixed from the input by `initialize`;
    /// weights start at 0. Errors for k = 0.
    pub fn new(base: Box<dyn StaticNonlinearity<T>>, k: usize) -> Result<Self> {
        if k == 0 {
            return Err(Error::InvalidParameter(
                "a Prandtl–Ishlinskii basis needs at least one play operator".into(),
            ));
        }
        let r = (1..=k)
            .map(|j| T::lit(DEFAULT_RANGE) * T::from_usize(j) / T::from_usize(k + 1))
            .collect();
        Ok(Self {
            base,
            thresholds: r,
            centre: T::zero(),
            weights: vec![T::zero(); k],
            grid_from_data: true,
            grid_size: k,
            kept: (1..=k).collect(),
        })
    }

    /// `base` plus the plays at positions `kept` (1-based, increasing, at most `k`) of the
    /// `k`-play grid fixed from the input by `initialize`; the other plays' weights are 0.
    /// Errors for an empty, unordered or out-of-range `kept`.
    pub fn on_subset(
        base: Box<dyn StaticNonlinearity<T>>,
        k: usize,
        kept: &[usize],
    ) -> Result<Self> {
        check_kept(kept, k)?;
        let mut out = Self::new(base, k)?;
        out.thresholds = kept.iter().map(|&j| out.thresholds[j - 1]).collect();
        out.weights = vec![T::zero(); kept.len()];
        out.kept = kept.to_vec();
        Ok(out)
    }

    /// `base` plus play operators on a given grid (thresholds positive, finite, increasing;
    /// centre finite), kept by `initialize`; weights start at 0.
    pub fn with_grid(
        base: Box<dyn StaticNonlinearity<T>>,
        thresholds: Vec<T>,
        centre: T,
    ) -> Result<Self> {
        check_grid(&thresholds, centre)?;
        let k = thresholds.len();
        Ok(Self {
            base,
            thresholds,
            centre,
            weights: vec![T::zero(); k],
            grid_from_data: false,
            grid_size: k,
            kept: (1..=k).collect(),
        })
    }

    /// The base nonlinearity.
    pub fn base(&self) -> &dyn StaticNonlinearity<T> {
        self.base.as_ref()
    }
    /// Thresholds r1..rK (input units).
    pub fn thresholds(&self) -> &[T] {
        &self.thresholds
    }
    /// Start value c of every play operator (input units).
    pub fn centre(&self) -> T {
        self.centre
    }
    /// Weights of the kept plays (w1..wK on the whole grid).
    pub fn weights(&self) -> &[T] {
        &self.weights
    }
    /// Positions (1-based) of the kept plays on the grid of [`grid_size`](Self::grid_size).
    pub fn kept(&self) -> &[usize] {
        &self.kept
    }
    /// Size K of the grid the kept plays are drawn from.
    pub fn grid_size(&self) -> usize {
        self.grid_size
    }
    /// True when some plays of the grid are left out ([`on_subset`](Self::on_subset)).
    fn is_subset(&self) -> bool {
        self.kept.len() != self.grid_size
    }
    /// The play operators' outputs, N×K.
    pub fn plays(&self, u: &[T]) -> Vec<Vec<T>> {
        self.thresholds
            .iter()
            .map(|&r| play_checked(u, r, self.centre))
            .collect()
    }

    /// Rebuilds from a spec of kind "prandtl-ishlinskii" (the base must be a built-in kind).
    pub fn from_spec(spec: &NonlinearitySpec) -> Result<Self> {
        let bad = |m: &str| Error::ModelFormat(format!("prandtl-ishlinskii spec: {m}"));
        let base_spec: NonlinearitySpec = spec
            .config
            .get("base")
            .cloned()
            .ok_or_else(|| bad("missing \"base\""))
            .and_then(|v| serde_json::from_value(v).map_err(|e| bad(&e.to_string())))?;
        let base = from_spec::<T>(&base_spec)?;
        let thresholds: Vec<T> = spec
            .config
            .get("thresholds")
            .and_then(|v| v.as_array())
            .ok_or_else(|| bad("missing \"thresholds\""))?
            .iter()
            .map(|x| {
                x.as_f64()
                    .map(T::lit)
                    .ok_or_else(|| bad("non-numeric threshold"))
            })
            .collect::<Result<_>>()?;
        let centre = spec
            .config
            .get("centre")
            .and_then(|v| v.as_f64())
            .ok_or_else(|| bad("missing \"centre\""))?;
        let mut out =
            Self::with_grid(base, thresholds, T::lit(centre)).map_err(|e| bad(&e.to_string()))?;
        if let Some(kept) = spec.config.get("kept") {
            let kept: Vec<usize> =
                serde_json::from_value(kept.clone()).map_err(|e| bad(&e.to_string()))?;
            let k = spec
                .config
                .get("grid_size")
                .and_then(|v| v.as_u64())
                .ok_or_else(|| bad("missing \"grid_size\""))? as usize;
            if kept.len() != out.thresholds.len() {
                return Err(bad("\"kept\" and \"thresholds\" differ in length"));
            }
            check_kept(&kept, k).map_err(|e| bad(&e.to_string()))?;
            out.kept = kept;
            out.grid_size = k;
        }
        let th: Vec<T> = spec.params.iter().map(|&x| T::lit(x)).collect();
        if !th.is_empty() {
            out.set_params(&th)?;
        }
        Ok(out)
    }
}

fn check_grid<T: Real>(thresholds: &[T], centre: T) -> Result<()> {
    if thresholds.is_empty() {
        return Err(Error::InvalidParameter(
            "a Prandtl–Ishlinskii basis needs at least one threshold".into(),
        ));
    }
    let increasing = thresholds.windows(2).all(|w| w[0] < w[1]);
    if !(thresholds.iter().all(|r| r.is_finite() && *r > T::zero()) && increasing) {
        return Err(Error::InvalidParameter(
            "play thresholds must be positive, finite and increasing".into(),
        ));
    }
    if !centre.is_finite() {
        return Err(Error::InvalidParameter(
            "the play operators' start value must be finite".into(),
        ));
    }
    Ok(())
}

fn check_kept(kept: &[usize], k: usize) -> Result<()> {
    let increasing = kept.windows(2).all(|w| w[0] < w[1]);
    if kept.is_empty() || !increasing || kept[0] == 0 || kept[kept.len() - 1] > k {
        return Err(Error::InvalidParameter(format!(
            "the kept plays must be increasing positions 1..={k} of the grid, got {kept:?}"
        )));
    }
    Ok(())
}

fn check_finite<T: Real>(g: &[T], what: &str) -> Result<()> {
    match g.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(Error::NonFinite {
            what: what.into(),
            index: i,
        }),
        None => Ok(()),
    }
}

impl<T: Real> StaticNonlinearity<T> for PrandtlIshlinskii<T> {
    fn name(&self) -> String {
        if self.is_subset() {
            format!(
                "{}+pi{}of{}",
                self.base.name(),
                self.thresholds.len(),
                self.grid_size
            )
        } else {
            format!("{}+pi{}", self.base.name(), self.thresholds.len())
        }
    }
    fn effects(&self) -> Vec<String> {
        let mut e = self.base.effects();
        e.push("prandtl-ishlinskii".into());
        e
    }
    fn param_names(&self) -> Vec<String> {
        let mut n = self.base.param_names();
        n.extend(self.kept.iter().map(|j| format!("w{j}")));
        n
    }
    fn params(&self) -> Vec<T> {
        let mut p = self.base.params();
        p.extend_from_slice(&self.weights);
        p
    }
    fn set_params(&mut self, theta: &[T]) -> Result<()> {
        let nb = self.base.params().len();
        let k = self.weights.len();
        if theta.len() != nb + k {
            return Err(Error::LengthMismatch {
                what: format!(
                    "'{}' has {} parameters, got {}",
                    self.name(),
                    nb + k,
                    theta.len()
                ),
            });
        }
        check_finite(&theta[nb..], "play-operator weights")?;
        self.base.set_params(&theta[..nb])?;
        self.weights.copy_from_slice(&theta[nb..]);
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        let mut n = self.base.regressor_names();
        n.extend(self.kept.iter().map(|j| format!("play{j}")));
        n
    }
    fn n_regressors(&self) -> usize {
        self.base.n_regressors() + self.thresholds.len()
    }
    fn regressors(&self, u: &[T]) -> Mat<T> {
        let phi_b = self.base.regressors(u);
        let rb = phi_b.ncols();
        let mut phi = Mat::zeros(u.len(), rb + self.thresholds.len());
        phi.as_mut().subcols_mut(0, rb).copy_from(phi_b.as_ref());
        for (j, col) in self.plays(u).into_iter().enumerate() {
            for (k, x) in col.into_iter().enumerate() {
                phi[(k, rb + j)] = x;
            }
        }
        phi
    }
    fn gains(&self) -> Vec<T> {
        let mut g = self.base.gains();
        g.extend_from_slice(&self.weights);
        g
    }
    fn update_from_gains(&mut self, g: &[T], u: &[T]) -> Result<()> {
        let rb = self.base.n_regressors();
        if g.len() != rb + self.weights.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "'{}' has {} gains, got {}",
                    self.name(),
                    rb + self.weights.len(),
                    g.len()
                ),
            });
        }
        check_finite(&g[rb..], "play-operator weights")?;
        self.base.update_from_gains(&g[..rb], u)?;
        self.weights.copy_from_slice(&g[rb..]);
        Ok(())
    }
    fn searched_params(&self) -> Vec<usize> {
        self.base.searched_params()
    }
    fn search_range(&self, index: usize, u: &[T]) -> (T, T) {
        self.base.search_range(index, u)
    }
    /// The base's own initialisation, the grid from the input (unless given), weights 0.
    fn initialize(&mut self, u: &[T]) {
        self.base.initialize(u);
        if self.grid_from_data
            && let Some((r, c)) = grid(u, self.grid_size)
        {
            self.thresholds = self.kept.iter().map(|&j| r[j - 1]).collect();
            self.centre = c;
        }
        self.weights.iter_mut().for_each(|w| *w = T::zero());
    }
    /// The grid of a fitted operator of the same grid size whose plays include this one's: its
    /// centre and its thresholds at this operator's positions (the base's configuration
    /// carried too). Any other operator leaves the grid as it is.
    fn carry_configuration(&mut self, fitted: &NonlinearitySpec) {
        if fitted.kind != "prandtl-ishlinskii" {
            return;
        }
        let Ok(other) = Self::from_spec(fitted) else {
            return;
        };
        self.base.carry_configuration(&other.base.spec());
        if other.grid_size != self.grid_size {
            return;
        }
        let at = |j: &usize| other.kept.iter().position(|k| k == j);
        let Some(thresholds) = self
            .kept
            .iter()
            .map(|j| at(j).map(|i| other.thresholds[i]))
            .collect::<Option<Vec<T>>>()
        else {
            return;
        };
        self.thresholds = thresholds;
        self.centre = other.centre;
    }
    fn param_jacobian(&self, u: &[T]) -> Mat<T> {
        let jb = self.base.param_jacobian(u);
        let nb = jb.ncols();
        let mut jac = Mat::zeros(u.len(), nb + self.thresholds.len());
        jac.as_mut().subcols_mut(0, nb).copy_from(jb.as_ref());
        for (j, col) in self.plays(u).into_iter().enumerate() {
            for (k, x) in col.into_iter().enumerate() {
                jac[(k, nb + j)] = x;
            }
        }
        jac
    }
    fn jump_params(&self) -> Vec<usize> {
        self.base.jump_params()
    }
    /// F_{r·s}\[s·u\] = s·F_r\[u\]: thresholds and centre scale with the input, weights by
    /// output/input.
    fn rescaled(&self, input: T, output: T) -> Option<Box<dyn StaticNonlinearity<T>>> {
        let base = self.base.rescaled(input, output)?;
        Some(Box::new(Self {
            base,
            thresholds: self.thresholds.iter().map(|&r| r * input).collect(),
            centre: self.centre * input,
            weights: self.weights.iter().map(|&w| w * output / input).collect(),
            grid_from_data: self.grid_from_data,
            grid_size: self.grid_size,
            kept: self.kept.clone(),
        }))
    }
    fn spans_constant(&self) -> bool {
        self.base.spans_constant()
    }
    fn constant_pair(&self) -> Option<(usize, usize)> {
        // the base's columns come first
        self.base.constant_pair()
    }
    /// The plays' states after one reversal before the record: the input came from far below
    /// (above) up (down) to an extreme u0 ± 2r_j and back to u0, j = 1..K. Plays with r ≤ r_j
    /// then sit at u0 ± r, the others at u0 ± (2r_j − r): the states a Preisach memory curve
    /// with one corner gives (Brokate & Sprekels 1996, §2.3), the corner at each threshold.
    /// The truth's memory at a record's start (a later part of one experiment, e.g. a
    /// validation part) is unknown; these 2K histories let the simulation estimate it.
    fn memory_histories(&self, u0: T) -> Vec<Vec<T>> {
        let Some(&widest) = self.thresholds.last() else {
            return Vec::new();
        };
        // far enough that the first sample pushes every play to its band's edge
        let far = (u0 - self.centre).abs() + T::lit(3.0) * widest + T::one();
        let mut out = Vec::with_capacity(2 * self.thresholds.len());
        for &r in &self.thresholds {
            let turn = T::lit(2.0) * r;
            out.push(vec![u0 - far, u0 + turn]);
            out.push(vec![u0 + far, u0 - turn]);
        }
        out
    }
    /// The grid, and for a subset the kept positions and the grid's size (a whole grid's file
    /// is the same as before subsets existed).
    fn spec(&self) -> NonlinearitySpec {
        let mut config = serde_json::json!({
            "base": self.base.spec(),
            "thresholds": self.thresholds.iter().map(|r| r.as_f64()).collect::<Vec<_>>(),
            "centre": self.centre.as_f64(),
        });
        if self.is_subset() {
            config["kept"] = serde_json::json!(self.kept);
            config["grid_size"] = serde_json::json!(self.grid_size);
        }
        NonlinearitySpec {
            kind: "prandtl-ishlinskii".into(),
            config,
            param_names: self.param_names(),
            params: self.params().iter().map(|x| x.as_f64()).collect(),
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<T>> {
        Box::new(self.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regressors::Udn;

    #[test]
    fn play_follows_the_recursion_and_its_start() {
        let u = [0.0, 1.0, 2.0, 1.5, 0.5, -1.0, 0.0];
        let y = play(&u, 0.5, 0.0).unwrap();
        // rises with u − r, holds inside the band, falls with u + r
        assert_eq!(y, vec![0.0, 0.5, 1.5, 1.5, 1.0, -0.5, -0.5]);
        // a start outside the first band is clamped into it
        assert_eq!(play(&[3.0], 0.5, 0.0).unwrap()[0], 2.5);
    }

    #[test]
    fn rescaling_commutes_with_evaluation() {
        let mut pi = PrandtlIshlinskii::<f64>::new(Box::new(Udn::linear()), 4).unwrap();
        let u: Vec<f64> = (0..200)
            .map(|k| (k as f64 * 0.13).sin() * (1.0 + k as f64 / 100.0))
            .collect();
        pi.initialize(&u);
        pi.set_params(&[1.5, 0.3, -0.2, 0.4, 0.1]).unwrap();
        let (si, so) = (7.0, 0.25);
        let us: Vec<f64> = u.iter().map(|x| x * si).collect();
        let scaled = pi.rescaled(si, so).unwrap();
        let (v, vs) = (pi.eval(&u), scaled.eval(&us));
        for k in 0..u.len() {
            assert!(
                (vs[k] - so * v[k]).abs() < 1e-12,
                "{k}: {} {}",
                vs[k],
                so * v[k]
            );
        }
        assert!(PrandtlIshlinskii::<f64>::new(Box::new(Udn::linear()), 0).is_err());
        assert!(pi.set_params(&[1.0, f64::NAN, 0.0, 0.0, 0.0]).is_err());
    }

    #[test]
    fn a_subset_keeps_its_grid_positions() {
        let u: Vec<f64> = (0..300)
            .map(|k| (k as f64 * 0.07).sin() * (1.0 + k as f64 / 150.0))
            .collect();
        let mut whole = PrandtlIshlinskii::<f64>::new(Box::new(Udn::linear()), 6).unwrap();
        let mut part =
            PrandtlIshlinskii::<f64>::on_subset(Box::new(Udn::linear()), 6, &[2, 5]).unwrap();
        whole.initialize(&u);
        part.initialize(&u);
        // the kept plays sit where they sit on the whole grid, named by their positions
        assert_eq!(
            part.thresholds(),
            &[whole.thresholds()[1], whole.thresholds()[4]]
        );
        assert_eq!(part.centre(), whole.centre());
        assert_eq!(part.param_names(), vec!["p", "w2", "w5"]);
        assert_eq!(part.name(), "linear+pi2of6");
        // the same map as the whole grid with the other weights at 0
        part.set_params(&[1.2, 0.3, 0.5]).unwrap();
        whole
            .set_params(&[1.2, 0.0, 0.3, 0.0, 0.0, 0.5, 0.0])
            .unwrap();
        assert_eq!(part.eval(&u), whole.eval(&u));
        // its file keeps the positions; a whole grid's file has none
        let back = PrandtlIshlinskii::<f64>::from_spec(&part.spec()).unwrap();
        assert_eq!(back.param_names(), part.param_names());
        assert_eq!(back.eval(&u), part.eval(&u));
        assert!(whole.spec().config.get("kept").is_none());
        for bad in [&[][..], &[3, 2], &[0, 1], &[7]] {
            assert!(PrandtlIshlinskii::<f64>::on_subset(Box::new(Udn::linear()), 6, bad).is_err());
        }
    }

    #[test]
    fn a_fitted_grid_is_carried_to_a_subset_of_its_plays() {
        let u: Vec<f64> = (0..300)
            .map(|k| (k as f64 * 0.07).sin() * (1.0 + k as f64 / 150.0))
            .collect();
        // a grid fixed on the first part of the input (a screening window)
        let mut fitted =
            PrandtlIshlinskii::<f64>::on_subset(Box::new(Udn::linear()), 6, &[1, 2, 4]).unwrap();
        fitted.initialize(&u[..100]);
        let spec = fitted.spec();
        let mut part =
            PrandtlIshlinskii::<f64>::on_subset(Box::new(Udn::linear()), 6, &[1, 4]).unwrap();
        part.initialize(&u);
        assert_ne!(part.thresholds()[0], fitted.thresholds()[0]);
        part.carry_configuration(&spec);
        assert_eq!(
            part.thresholds(),
            &[fitted.thresholds()[0], fitted.thresholds()[2]]
        );
        assert_eq!(part.centre(), fitted.centre());
        // a play the fitted operator does not have, another grid size or another kind: the
        // grid stays the one from the input
        for (kept, k) in [(&[1, 3][..], 6), (&[1, 4][..], 5)] {
            let mut other =
                PrandtlIshlinskii::<f64>::on_subset(Box::new(Udn::linear()), k, kept).unwrap();
            other.initialize(&u);
            let before = other.thresholds().to_vec();
            other.carry_configuration(&spec);
            assert_eq!(other.thresholds(), &before[..]);
        }
        let before = part.thresholds().to_vec();
        part.initialize(&u);
        let from_input = part.thresholds().to_vec();
        part.carry_configuration(&Udn::<f64>::linear().spec());
        assert_eq!(part.thresholds(), &from_input[..]);
        assert_ne!(before, from_input);
    }
}
