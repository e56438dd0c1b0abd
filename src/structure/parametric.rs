//! A rational model of a BLA and its poles and zeros with standard errors.
//!
//! The frequency axis is the bilinear (Tustin) variable w = (z − 1)/(z + 1), scaled so that the
//! band's top line sits at |w| = 1: on the unit circle w = j tan(πf)/tan(πf_max). A discrete-time
//! transfer function of order n is exactly rational of order n in w (the map is Möbius), and the
//! scaled variable keeps the polynomial bases well conditioned over the band (the frequency scaling
//! of Pintelon & Schoukens 2012, §9.3.2). The model is G(w) = c·B(w)/A(w), A monic of degree n,
//! B of degree ≤ n, c a gain (1 unless a joint fit shares B over levels).
//!
//! Poles and zeros are the roots of A and B (eigenvalues of the companion matrix); their
//! covariance by the delta method, ∂p/∂a_i = −p^i / A'(p), from the parameters' covariance
//! (Gauss–Newton: s²(JᵀJ)⁻¹). A root is reported as a continuous-time root s = ln z / Ts:
//! natural frequency |s|/2π (Hz when the sampling time is known, else cycles per sample) and
//! damping −Re s/|s|, each with its standard error (numerical derivative of the map).

use super::bla::C64;
use crate::error::{Error, Result};
use faer::Mat;

/// The scaled bilinear frequency axis of a band.
#[derive(Debug, Clone, Copy)]
pub struct Axis {
    /// tan(π f_max), f_max the top line's frequency as a fraction of the sampling frequency.
    pub scale: f64,
    /// Sampling time (1 when unknown: frequencies are then fractions of the sampling frequency).
    pub ts: f64,
    /// Roots are in w (bilinear); false: roots are z itself.
    pub bilinear: bool,
}

impl Axis {
    /// The axis of a band whose top line is at `f_max` (fraction of the sampling frequency).
    pub fn new(f_max: f64, ts: f64) -> Self {
        Self {
            scale: (std::f64::consts::PI * f_max.clamp(1e-9, 0.499)).tan(),
            ts,
            bilinear: true,
        }
    }

    /// The identity axis: roots are z (a model in z⁻¹).
    pub fn z_domain(ts: f64) -> Self {
        Self {
            scale: 1.0,
            ts,
            bilinear: false,
        }
    }

    /// w at frequency `f` (fraction of the sampling frequency).
    pub fn w(&self, f: f64) -> C64 {
        C64::new(0.0, (std::f64::consts::PI * f).tan() / self.scale)
    }

    /// The continuous-time root s = ln z / Ts of a root w.
    pub fn s(&self, w: C64) -> C64 {
        if !self.bilinear {
            return w.ln() / self.ts;
        }
        let cw = w * self.scale;
        let z = (C64::new(1.0, 0.0) + cw) / (C64::new(1.0, 0.0) - cw);
        z.ln() / self.ts
    }
}

/// Evaluates Σ c_i w^i (Horner).
pub fn polyval(c: &[f64], w: C64) -> C64 {
    c.iter()
        .rev()
        .fold(C64::new(0.0, 0.0), |acc, &ci| acc * w + ci)
}

/// Evaluates the monic w^n + Σ_{i<n} a_i w^i.
pub fn monic(a: &[f64], w: C64) -> C64 {
    a.iter()
        .rev()
        .fold(C64::new(1.0, 0.0), |acc, &ai| acc * w + ai)
}

/// Roots of the monic polynomial w^n + Σ a_i w^i (companion-matrix eigenvalues).
pub fn monic_roots(a: &[f64]) -> Result<Vec<C64>> {
    let n = a.len();
    if n == 0 {
        return Ok(vec![]);
    }
    let m = Mat::from_fn(n, n, |i, j| {
        if i == 0 {
            -a[n - 1 - j]
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let ev = m
        .eigenvalues()
        .map_err(|e| Error::LinAlg(format!("polynomial roots: {e:?}")))?;
    Ok(ev.iter().map(|z| C64::new(z.re, z.im)).collect())
}

/// A pole or zero, as a continuous-time root, with standard errors.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Root {
    /// Natural frequency |s|/2π (Hz when the sampling time is known, else cycles per sample).
    pub freq: f64,
    /// Its standard error.
    pub freq_se: f64,
    /// Damping ratio −Re s/|s| (1 for a real stable root).
    pub damping: f64,
    /// Its standard error.
    pub damping_se: f64,
    /// Whether the root is real (a complex pair is listed once, its upper half).
    pub real: bool,
}

/// Roots of a polynomial with their delta-method standard errors, upper half plane only.
/// `coef` are the coefficients (ascending; `monic_top` says whether a leading 1 is implied),
/// `cov` their covariance.
pub fn roots_with_errors(
    coef: &[f64],
    monic_top: bool,
    cov: &Mat<f64>,
    axis: &Axis,
) -> Result<Vec<Root>> {
    let full: Vec<f64> = if monic_top {
        coef.iter().copied().chain(std::iter::once(1.0)).collect()
    } else {
        coef.to_vec()
    };
    // strip negligible leading coefficients (a numerator of lower degree)
    let scale = full.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let mut deg = full.len() - 1;
    while deg > 0 && full[deg].abs() <= 1e-9 * scale {
        deg -= 1;
    }
    if deg == 0 {
        return Ok(vec![]);
    }
    let lead = full[deg];
    let a: Vec<f64> = full[..deg].iter().map(|c| c / lead).collect();
    let roots = monic_roots(&a)?;
    let mut out = Vec::new();
    for p in roots {
        if p.im < -1e-12 * p.norm().max(1e-300) {
            continue;
        }
        // dp/dc_i = −p^i / P'(p) for the polynomial P = Σ c_i w^i (any normalisation)
        let dfull: Vec<f64> = (1..=deg).map(|i| i as f64 * full[i]).collect();
        let dp = polyval(&dfull, p);
        let nc = coef.len();
        let g: Vec<C64> = (0..nc).map(|i| -p.powu(i as u32) / dp).collect();
        let gr = Mat::from_fn(2, nc, |r, i| if r == 0 { g[i].re } else { g[i].im });
        let cp = &gr * cov * gr.transpose();
        let s = axis.s(p);
        let (freq, damping) = fd(s);
        // numerical derivative of (freq, damping) with respect to (Re p, Im p)
        let h = 1e-7 * p.norm().max(1e-3);
        let mut jac = Mat::<f64>::zeros(2, 2);
        for (c, dpv) in [C64::new(h, 0.0), C64::new(0.0, h)].iter().enumerate() {
            let (f1, d1) = fd(axis.s(p + dpv));
            let (f0, d0) = fd(axis.s(p - dpv));
            jac[(0, c)] = (f1 - f0) / (2.0 * h);
            jac[(1, c)] = (d1 - d0) / (2.0 * h);
        }
        let cf = &jac * &cp * jac.transpose();
        // a variance the conditioning spoils (not finite) is reported as unknown (infinite)
        let se = |v: f64| {
            if v.is_finite() {
                v.max(0.0).sqrt()
            } else {
                f64::INFINITY
            }
        };
        out.push(Root {
            freq,
            freq_se: se(cf[(0, 0)]),
            damping,
            damping_se: se(cf[(1, 1)]),
            real: p.im.abs() <= 1e-9 * p.norm().max(1e-300),
        });
    }
    out.sort_by(|a, b| a.freq.total_cmp(&b.freq));
    Ok(out)
}

fn fd(s: C64) -> (f64, f64) {
    let r = s.norm();
    (
        r / std::f64::consts::TAU,
        if r > 0.0 { -s.re / r } else { 1.0 },
    )
}
