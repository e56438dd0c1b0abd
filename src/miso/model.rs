//! The fitted several-input model: one fitted Hammerstein branch per input, summed.

use super::partial::partial_record;
use super::report::MisoReport;
use super::settings::MisoHammerstein;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::HammersteinModel;
use crate::real::Real;
use crate::statespace::StateSpace;
use faer::{Mat, MatRef};

/// Gauss–Seidel passes over the branches that estimate their initial states on a record.
const X0_PASSES: usize = 8;
/// Relative MSE fall of a pass below which the initial-state passes stop.
const X0_TOLERANCE: f64 = 1e-9;

/// A fitted several-input Hammerstein model y = Σᵢ Gᵢ(Nᵢ(uᵢ(k − nkᵢ))) + c.
#[derive(Debug, Clone)]
pub struct MisoModel<T: Real> {
    pub(crate) branches: Vec<HammersteinModel<T>>,
    pub(crate) input_names: Vec<String>,
    pub(crate) output_name: String,
    pub(crate) settings: MisoHammerstein<T>,
    pub(crate) report: MisoReport,
}

/// A simulation of a several-input model on a measured record.
#[derive(Debug, Clone)]
pub struct MisoSimulation<T: Real> {
    /// Simulated output (offset included).
    pub y_hat: Vec<T>,
    /// Each branch's simulated output (the first includes the offset), in input order.
    pub contributions: Vec<Vec<T>>,
    /// Each branch's initial state, estimated on the record.
    pub x0: Vec<Vec<T>>,
}

impl<T: Real> MisoModel<T> {
    /// Assembles a model from fitted branches (one per input, named), e.g. loaded ones.
    pub fn from_branches(
        branches: Vec<HammersteinModel<T>>,
        input_names: Vec<String>,
        output_name: String,
        report: MisoReport,
    ) -> Result<Self> {
        if branches.is_empty() || branches.len() != input_names.len() {
            return Err(Error::Dimension(format!(
                "{} branches for {} input names (one branch per input, at least one)",
                branches.len(),
                input_names.len()
            )));
        }
        // two branches of one input would be fed the same column (a hand-edited file)
        if let Some((_, name)) = input_names
            .iter()
            .enumerate()
            .find(|(k, n)| input_names[..*k].contains(n))
        {
            return Err(Error::RepeatedChannel {
                name: name.clone(),
                roles: "two inputs",
            });
        }
        if branches.iter().any(|b| b.output_map().is_some()) {
            return Err(Error::InvalidParameter(
                "a branch of a several-input model has no output map".into(),
            ));
        }
        let settings =
            MisoHammerstein::new(branches.iter().map(|b| b.settings().clone()).collect());
        Ok(Self {
            branches,
            input_names,
            output_name,
            settings,
            report,
        })
    }

    /// The fitted branches, in input order.
    pub fn branches(&self) -> &[HammersteinModel<T>] {
        &self.branches
    }

    /// The branch of the input named `name`.
    pub fn branch(&self, name: &str) -> Option<&HammersteinModel<T>> {
        let i = self.input_names.iter().position(|n| n == name)?;
        self.branches.get(i)
    }

    /// Names of the inputs, in branch order.
    pub fn input_names(&self) -> &[String] {
        &self.input_names
    }

    /// Name of the output.
    pub fn output_name(&self) -> &str {
        &self.output_name
    }

    /// The settings the model was fitted with (the branches' settings as fitted).
    pub fn settings(&self) -> &MisoHammerstein<T> {
        &self.settings
    }

    /// The backfitting's report.
    pub fn report(&self) -> &MisoReport {
        &self.report
    }

    /// Output offset c (carried by the first branch).
    pub fn output_offset(&self) -> f64 {
        self.branches.iter().map(|b| b.output_offset()).sum()
    }

    /// Total order Σ nᵢ of the linear part.
    pub fn order(&self) -> usize {
        self.branches.iter().map(|b| b.linear().order()).sum()
    }

    /// Every branch's parameters as (input, name, value, standard error).
    pub fn parameters_with_errors(&self) -> Vec<(String, String, f64, Option<f64>)> {
        self.input_names
            .iter()
            .zip(&self.branches)
            .flat_map(|(input, b)| {
                b.parameters_with_errors()
                    .into_iter()
                    .map(move |(n, v, se)| (input.clone(), n, v, se))
            })
            .collect()
    }

    /// The linear part as one state-space model with m inputs: A = diag(Aᵢ), B = diag(bᵢ),
    /// C = [c₁ … c_m], D = [d₁ … d_m] (the intermediate signals vᵢ = Nᵢ(uᵢ) as its inputs).
    pub fn linear(&self) -> Result<StateSpace<T>> {
        let n = self.order();
        let m = self.branches.len();
        let (mut a, mut b) = (Mat::zeros(n, n), Mat::zeros(n, m));
        let (mut c, mut d) = (Mat::zeros(1, n), Mat::zeros(1, m));
        let mut at = 0;
        for (i, br) in self.branches.iter().enumerate() {
            let l = br.linear();
            let ni = l.order();
            for r in 0..ni {
                for q in 0..ni {
                    a[(at + r, at + q)] = l.a[(r, q)];
                }
                b[(at + r, i)] = l.b[(r, 0)];
                c[(0, at + r)] = l.c[(0, r)];
            }
            d[(0, i)] = l.d[(0, 0)];
            at += ni;
        }
        let mut ss = StateSpace::new(a, b, c, d)?;
        ss.ts = self.branches[0].linear().ts;
        Ok(ss)
    }

    /// Simulates from zero initial states; `u` is N×m, one column per input in branch order.
    pub fn simulate(&self, u: MatRef<'_, T>) -> Result<Vec<T>> {
        self.check_inputs(u.ncols())?;
        let mut y = vec![T::zero(); u.nrows()];
        for (i, br) in self.branches.iter().enumerate() {
            let ui: Vec<T> = (0..u.nrows()).map(|k| u[(k, i)]).collect();
            for (yk, vk) in y.iter_mut().zip(br.simulate(&ui)?) {
                *yk += vk;
            }
        }
        Ok(y)
    }

    /// Simulates on a measured record with every branch's initial state estimated on it: passes
    /// over the branches, each estimating its own initial state (and hysteresis direction,
    /// delay-line values) on its partial residual, until the total MSE settles — block
    /// coordinate descent on the joint least squares, whose minimum it reaches.
    pub fn simulate_on(&self, data: &IoData<T>) -> Result<MisoSimulation<T>> {
        self.check_inputs(data.n_inputs())?;
        if data.n_outputs() != 1 {
            return Err(Error::Dimension(format!(
                "a several-input model has one output; the record has {}",
                data.n_outputs()
            )));
        }
        let m = self.branches.len();
        let y = data.output_slice(0);
        let mut contributions = vec![Vec::new(); m];
        let mut x0 = vec![Vec::new(); m];
        let mut last = f64::INFINITY;
        for _ in 0..X0_PASSES {
            for i in 0..m {
                let rec = partial_record(data, i, &contributions)?;
                let sim = self.branches[i].simulate_on(&rec)?;
                contributions[i] = sim.y_hat;
                x0[i] = sim.x0;
            }
            let e = mse_of_sum(y, &contributions);
            if m == 1 || e.is_nan() || (last.is_finite() && last - e <= X0_TOLERANCE * last) {
                break;
            }
            last = e;
        }
        Ok(MisoSimulation {
            y_hat: sum_of(y.len(), &contributions),
            contributions,
            x0,
        })
    }

    fn check_inputs(&self, m: usize) -> Result<()> {
        if m != self.branches.len() {
            return Err(Error::Dimension(format!(
                "the model has {} inputs ({}), the record {m}",
                self.branches.len(),
                self.input_names.join(", ")
            )));
        }
        Ok(())
    }
}

/// Σᵢ contributions[i] (empty ones count as zero).
pub(crate) fn sum_of<T: Real>(nn: usize, contributions: &[Vec<T>]) -> Vec<T> {
    let mut s = vec![T::zero(); nn];
    for c in contributions {
        for (sk, ck) in s.iter_mut().zip(c) {
            *sk += *ck;
        }
    }
    s
}

/// MSE of `y` against the sum of the contributions.
pub(crate) fn mse_of_sum<T: Real>(y: &[T], contributions: &[Vec<T>]) -> f64 {
    crate::fit::order_selection::mse_between(y, &sum_of(y.len(), contributions))
}
