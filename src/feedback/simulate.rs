//! The feedback model's simulation and its exact output sensitivities.
//!
//! The sensitivities ∂y(k)/∂p come from the forward sensitivity recursion (the model's
//! recursion differentiated: Pintelon & Schoukens, *System Identification: A Frequency Domain
//! Approach*, 2nd ed., 2012, §10.5 for state-space models; the loop adds f′(z) ∂z/∂p):
//!
//! S(k+1) = A S(k) + E f′(z) ∂z/∂p + ∂A/∂p x + ∂B/∂p (u + u₀) + B ∂u₀/∂p + ∂E/∂p w + E ∂f/∂θ,
//!
//! with S(k) = ∂x(k)/∂p, ∂z/∂p = C S(k) (− ∂[C x(k−1)]/∂p for velocity) + ∂C/∂p x(k), or
//! F S(k) + ∂F/∂p x(k) for `state` feedback z = F x, and
//! ∂y/∂p = C S + ∂C/∂p x + ∂D/∂p u + ∂y₀/∂p. With an input nonlinearity v = N(u; θ_N) the
//! block's input is v (in place of u above) and θ_N adds B ∂v/∂θ_N to S(k+1) and D ∂v/∂θ_N
//! to ∂y/∂θ_N. With an output map y = g(ℓ) + y₀, ℓ = C x + D v the linear output, every
//! column above is ℓ's and is multiplied by g′(ℓ); y₀'s stays 1 and the map's parameters θ_g
//! add ∂g/∂θ_g ([`super::output_side`]). One pass gives all columns of the Jacobian, which
//! are exact for a differentiable f (f′ by a central difference of the basis at z).

use super::FeedbackOn;
use super::model::FeedbackModel;
use crate::error::{Error, Result};
use faer::Mat;

/// A state or output beyond this magnitude (normalised units: the record's RMS is 1) is a
/// blown-up simulation.
pub const DIVERGED: f64 = 1e6;

/// Which parameters the sensitivities are taken for: the whole model and the initial state
/// (training), or the initial state only (a validation record's x0).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub n: usize,
    pub q: usize,
    pub with_d: bool,
    pub velocity: bool,
    /// `state` feedback: F (n values) among the parameters.
    pub state: bool,
    /// The input nonlinearity's parameter count (0 without one).
    pub qn: usize,
    /// The output map's parameter count (0 without one).
    pub qg: usize,
    pub model_free: bool,
}

impl Layout {
    pub fn of(m: &FeedbackModel, model_free: bool) -> Self {
        Self {
            n: m.order(),
            q: m.f.params().len() + usize::from(m.on == FeedbackOn::Velocity),
            with_d: m.with_d,
            velocity: m.on == FeedbackOn::Velocity,
            state: m.on == FeedbackOn::State,
            qn: m.input.as_ref().map_or(0, |nl| nl.params().len()),
            qg: m.output.as_ref().map_or(0, |g| g.params().len()),
            model_free,
        }
    }
    fn ns(&self) -> usize {
        self.n + usize::from(self.velocity)
    }
    /// Offsets of the groups: A, B, C, D, E, θ, u₀, y₀, x0, F, θ_N (F, for `state`, the input
    /// nonlinearity's θ_N and the output map's θ_g, at [`theta_g`](Self::theta_g), lie between
    /// y₀ and x0).
    pub(crate) fn offsets(&self) -> [usize; 11] {
        let n = self.n;
        if !self.model_free {
            return [0; 11];
        }
        let a = 0;
        let b = a + n * n;
        let c = b + n;
        let d = c + n;
        let e = d + usize::from(self.with_d);
        let th = e + n;
        let u0 = th + self.q;
        let y0 = u0 + 1;
        let fz = y0 + 1;
        let thn = fz + if self.state { n } else { 0 };
        let x0 = thn + self.qn + self.qg;
        [a, b, c, d, e, th, u0, y0, x0, fz, thn]
    }
    /// The offset of the output map's parameters θ_g (after θ_N).
    pub(crate) fn theta_g(&self) -> usize {
        self.offsets()[10] + self.qn
    }
    pub fn len(&self) -> usize {
        self.offsets()[8] + self.ns()
    }

    /// The parameter vector of a model and initial state.
    pub fn pack(&self, m: &FeedbackModel, x0: &[f64]) -> Vec<f64> {
        let mut p = Vec::with_capacity(self.len());
        if self.model_free {
            let n = self.n;
            for i in 0..n {
                for j in 0..n {
                    p.push(m.a[(i, j)]);
                }
            }
            p.extend_from_slice(&m.b);
            p.extend_from_slice(&m.c);
            if self.with_d {
                p.push(m.d);
            }
            p.extend_from_slice(&m.e);
            p.extend(m.f.params());
            if self.velocity {
                p.push(m.viscous);
            }
            p.push(m.u_offset);
            p.push(m.y_offset);
            if self.state {
                p.extend_from_slice(&m.fz);
            }
            if let Some(nl) = &m.input {
                p.extend(nl.params());
            }
            if let Some(g) = &m.output {
                p.extend(g.params());
            }
        }
        p.extend_from_slice(x0);
        p
    }

    /// Writes a parameter vector into a model; returns the initial state.
    pub fn unpack(&self, p: &[f64], m: &mut FeedbackModel) -> Result<Vec<f64>> {
        let o = self.offsets();
        if self.model_free {
            let n = self.n;
            for i in 0..n {
                for j in 0..n {
                    m.a[(i, j)] = p[o[0] + i * n + j];
                }
            }
            m.b.copy_from_slice(&p[o[1]..o[1] + n]);
            m.c.copy_from_slice(&p[o[2]..o[2] + n]);
            if self.with_d {
                m.d = p[o[3]];
            }
            m.e.copy_from_slice(&p[o[4]..o[4] + n]);
            let nf = self.q - usize::from(self.velocity);
            m.f.set_params(&p[o[5]..o[5] + nf])?;
            if self.velocity {
                m.viscous = p[o[5] + nf];
            }
            m.u_offset = p[o[6]];
            m.y_offset = p[o[7]];
            if self.state {
                m.fz.copy_from_slice(&p[o[9]..o[9] + n]);
            }
            if let Some(nl) = m.input.as_mut() {
                nl.set_params(&p[o[10]..o[10] + self.qn])?;
            }
            if let Some(g) = m.output.as_mut() {
                let og = self.theta_g();
                g.set_params(&p[og..og + self.qg])?;
            }
        }
        Ok(p[o[8]..o[8] + self.ns()].to_vec())
    }
}

/// The step of the central difference for f′(z), relative to the spread of z.
const SLOPE_STEP: f64 = 1e-6;

/// Simulates the model on the normalised input `u` from the full initial state `x0`; with
/// `jac`, also fills the Jacobian ∂y/∂p (N × layout length) of the layout's parameters.
pub(crate) fn run(
    m: &FeedbackModel,
    u: &[f64],
    x0: &[f64],
    jac: Option<(&Layout, &mut Mat<f64>)>,
) -> Result<Vec<f64>> {
    run_z(m, u, x0, jac, None)
}

/// [`run`], also writing the feedback variable z(k) along the record into `zs` when given.
pub(crate) fn run_z(
    m: &FeedbackModel,
    u: &[f64],
    x0: &[f64],
    mut jac: Option<(&Layout, &mut Mat<f64>)>,
    mut zs: Option<&mut Vec<f64>>,
) -> Result<Vec<f64>> {
    let n = m.order();
    let velocity = m.on == FeedbackOn::Velocity;
    let state = m.on == FeedbackOn::State;
    if state && m.fz.len() != n {
        return Err(Error::LengthMismatch {
            what: format!("state feedback: F has {} values for {n} states", m.fz.len()),
        });
    }
    // A by columns (acol[l * n + i] = A[i, l]): the products A·s below add column by column,
    // each element's terms in the order l = 0, 1, …, so the sums are those of the row-wise
    // loop while the n elements of a column update independently
    let acol: Vec<f64> = (0..n)
        .flat_map(|l| (0..n).map(move |i| (i, l)))
        .map(|(i, l)| m.a[(i, l)])
        .collect();
    let mut x = x0[..n].to_vec();
    let mut q = if velocity { x0[n] } else { 0.0 };
    let mut xn = vec![0.0; n];
    let mut y = Vec::with_capacity(u.len());
    let h = SLOPE_STEP * (m.z_range.1 - m.z_range.0).abs().max(1e-12);
    // sensitivities: S (n × P) and Sq (P)
    let (lay, off, p_len) = match &jac {
        Some((l, _)) => (Some(**l), l.offsets(), l.len()),
        None => (None, [0; 11], 0),
    };
    let mut s = vec![0.0; n * p_len]; // column-major: s[j * n + i]
    let mut sn = vec![0.0; n * p_len];
    let mut sq = vec![0.0; p_len];
    // ∂f(z)/∂θ_f at the current sample (model-free layouts)
    let mut dth = vec![0.0; if jac.is_some() { m.f.params().len() } else { 0 }];
    let mut dz = vec![0.0; p_len];
    if let Some(l) = lay {
        for i in 0..n {
            s[(off[8] + i) * n + i] = 1.0;
        }
        if l.velocity {
            sq[off[8] + n] = 1.0;
        }
    }
    let cdot = |v: &[f64]| (0..n).map(|i| m.c[i] * v[i]).sum::<f64>();
    let fdot = |v: &[f64]| (0..n).map(|i| m.fz[i] * v[i]).sum::<f64>();
    if let Some(z) = zs.as_mut() {
        z.clear();
    }
    // the block's input v = N(u) (u itself without an input nonlinearity), and ∂v/∂θ_N
    let v: std::borrow::Cow<[f64]> = match &m.input {
        Some(nl) => std::borrow::Cow::Owned(nl.eval(u)),
        None => std::borrow::Cow::Borrowed(u),
    };
    let dv = match (&m.input, lay) {
        (Some(nl), Some(l)) if l.model_free && l.qn > 0 => Some(nl.param_jacobian(u)),
        _ => None,
    };
    for (k, &uk) in v.iter().enumerate() {
        let cx = cdot(&x);
        let z = if state {
            fdot(&x)
        } else if velocity {
            cx - q
        } else {
            cx
        };
        if let Some(zv) = zs.as_mut() {
            zv.push(z);
        }
        let (f0, fp, fm) = (m.f.eval_one(z), m.f.eval_one(z + h), m.f.eval_one(z - h));
        // the viscous term c_v z of velocity feedback beside f
        let cv = if velocity { m.viscous } else { 0.0 };
        let w = f0 + cv * z;
        let slope = (fp - fm) / (h + h) + cv;
        // the linear output ℓ through the output map (if any): y = g(ℓ) + y₀
        let lin = cx + m.d * uk;
        let (gk, gslope) = super::output_side::apply(m, lin);
        let yk = gk + m.y_offset;
        if !yk.is_finite() || yk.abs() > DIVERGED || !w.is_finite() {
            return Err(Error::Diverged {
                index: k,
                value: yk,
            });
        }
        y.push(yk);
        let ue = uk + m.u_offset;
        if let (Some(l), Some((_, jm))) = (lay, jac.as_mut()) {
            if l.model_free {
                m.f.param_jacobian_one(z, &mut dth);
            }
            // ∂z, ∂y
            for j in 0..p_len {
                let sj = &s[j * n..(j + 1) * n];
                let csj = cdot(sj);
                dz[j] = if state {
                    fdot(sj)
                } else {
                    csj - if velocity { sq[j] } else { 0.0 }
                };
                jm[(k, j)] = csj;
            }
            if l.model_free {
                for i in 0..n {
                    if state {
                        dz[off[9] + i] += x[i];
                    } else {
                        dz[off[2] + i] += x[i];
                    }
                    jm[(k, off[2] + i)] += x[i];
                }
                if l.with_d {
                    jm[(k, off[3])] += uk;
                }
                jm[(k, off[7])] += 1.0;
                if let Some(dv) = &dv {
                    for i in 0..l.qn {
                        jm[(k, off[10] + i)] += m.d * dv[(k, i)];
                    }
                }
            }
            super::output_side::chain(m, &l, lin, gslope, jm, k);
            // S(k+1)
            for j in 0..p_len {
                let mut dw = slope * dz[j];
                if l.model_free && j >= off[5] && j < off[5] + l.q {
                    let i = j - off[5];
                    dw += if i < dth.len() { dth[i] } else { z };
                }
                let sj = &s[j * n..(j + 1) * n];
                let out = &mut sn[j * n..(j + 1) * n];
                a_times(&acol, sj, &m.e, dw, out);
            }
            if l.model_free {
                for i in 0..n {
                    for l2 in 0..n {
                        sn[(off[0] + i * n + l2) * n + i] += x[l2];
                    }
                    sn[(off[1] + i) * n + i] += ue;
                    sn[(off[4] + i) * n + i] += w;
                    sn[off[6] * n + i] += m.b[i];
                }
                if let Some(dv) = &dv {
                    for j in 0..l.qn {
                        for i in 0..n {
                            sn[(off[10] + j) * n + i] += m.b[i] * dv[(k, j)];
                        }
                    }
                }
            }
            if velocity {
                for j in 0..p_len {
                    sq[j] = cdot(&s[j * n..(j + 1) * n]);
                }
                if l.model_free {
                    for i in 0..n {
                        sq[off[2] + i] += x[i];
                    }
                }
            }
            std::mem::swap(&mut s, &mut sn);
        }
        for ((o, &b), &e) in xn.iter_mut().zip(&m.b).zip(&m.e) {
            *o = b * ue + e * w;
        }
        add_a_times(&acol, &x, &mut xn);
        q = cx;
        std::mem::swap(&mut x, &mut xn);
    }
    Ok(y)
}

/// out = e·dw + A·s, A given by columns (`acol`, n × n): each element starts at e_i·dw and
/// adds A[i, l]·s_l for l = 0, 1, … in turn (the row-wise loop's sums, column by column).
fn a_times(acol: &[f64], s: &[f64], e: &[f64], dw: f64, out: &mut [f64]) {
    for (o, &ei) in out.iter_mut().zip(e) {
        *o = ei * dw;
    }
    add_a_times(acol, s, out);
}

/// out += A·s, A given by columns (`acol`, n × n with n = `s.len()`), column by column: each
/// element adds A[i, l]·s_l for l = 0, 1, … in turn.
fn add_a_times(acol: &[f64], s: &[f64], out: &mut [f64]) {
    let n = s.len();
    for (col, &sl) in acol.chunks_exact(n.max(1)).zip(s) {
        for (o, &a) in out.iter_mut().zip(col) {
            *o += a * sl;
        }
    }
}

/// The largest relative difference |fd − J| / (1 + |fd|) between the exact sensitivities of
/// [`run`] (every parameter of [`Layout::of`]`(m, true)`, x₀ included) and central differences
/// with step 1e-6, over the simulation of `u` from `m.x0` (the unit tests' check of the
/// sensitivities).
#[cfg(test)]
pub(crate) fn worst_sensitivity_error(m: &FeedbackModel, u: &[f64]) -> f64 {
    let lay = Layout::of(m, true);
    let np = lay.len();
    let mut jac = Mat::<f64>::zeros(u.len(), np);
    run(m, u, &m.x0, Some((&lay, &mut jac))).unwrap();
    let p = lay.pack(m, &m.x0);
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for j in 0..np {
        let sim = |delta: f64| {
            let mut q = p.clone();
            q[j] += delta;
            let mut mm = m.clone();
            let x0 = lay.unpack(&q, &mut mm).unwrap();
            run(&mm, u, &x0, None).unwrap()
        };
        let (yp, ym) = (sim(h), sim(-h));
        for k in 0..u.len() {
            let fd = (yp[k] - ym[k]) / (2.0 * h);
            worst = worst.max((fd - jac[(k, j)]).abs() / (1.0 + fd.abs()));
        }
    }
    worst
}
