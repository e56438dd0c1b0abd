//! Random two-input Hammerstein records for the several-input tests: each input with its own
//! random block (order 1–3), random UDN effects and parameters, its own input kind and amplitude;
//! the branches' outputs summed, an output offset, white noise at a random SNR. Everything
//! follows from one seed.
#![allow(dead_code)]

use super::random_system::{Excitation, PoleKind, noisy, random_block, random_udn};
use super::{Udn, input};
use hammerstein::StateSpace;
use hammerstein::regressors::{Effect, EffectSet};
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// One branch of a random record: its truth and input.
#[derive(Debug, Clone)]
pub struct RandomBranch {
    pub order: usize,
    pub poles: PoleKind,
    pub effects: EffectSet,
    pub truth: Udn,
    pub excitation: Excitation,
    pub block: StateSpace<f64>,
    pub u: Vec<f64>,
}

/// A random two-input record with its truth.
#[derive(Debug, Clone)]
pub struct RandomMiso {
    pub seed: u64,
    pub branches: Vec<RandomBranch>,
    pub snr_db: f64,
    pub n: usize,
    pub y: Vec<f64>,
    pub noise_var: f64,
}

const EFFECTS: [Effect; 4] = [
    Effect::Hysteresis,
    Effect::DeadZone,
    Effect::Saturation,
    Effect::Preload,
];

fn branch(
    rng: &mut StdRng,
    n: usize,
    seed: u64,
    effects: EffectSet,
    kinds: &[Excitation],
) -> RandomBranch {
    let order = rng.random_range(1..=3usize);
    let poles = [
        PoleKind::LightlyDamped,
        PoleKind::Slow,
        PoleKind::Fast,
        PoleKind::Anywhere,
    ][rng.random_range(0..4usize)];
    let block = random_block(rng, order, poles, false);
    let amp = 10f64.powf(rng.random_range(-0.5..0.7));
    let truth = random_udn(rng, effects, amp);
    let excitation = kinds[rng.random_range(0..kinds.len())];
    let Excitation::Base(kind) = excitation else {
        unreachable!("the first three excitations are base kinds")
    };
    let u = input(kind, n, amp, seed);
    RandomBranch {
        order,
        poles,
        effects,
        truth,
        excitation,
        block,
        u,
    }
}

/// Draws one record from `seed` (each branch's block of order 1–3, poles of any kind, an input
/// amplitude over 0.3–5, N 2000–4000): the first input with a random subset of effects (each with
/// probability ½), the second with exactly one effect drawn at random.
pub fn random_miso(seed: u64, snr_db: (f64, f64)) -> RandomMiso {
    let mut rng = StdRng::seed_from_u64(seed.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ 0x5eed);
    let n = rng.random_range(2000..=4000usize);
    let mut first = EffectSet::empty();
    for e in EFFECTS {
        if rng.random_range(0.0..1.0) < 0.5 {
            first = first.with(e);
        }
    }
    let second = EffectSet::empty().with(EFFECTS[rng.random_range(0..4usize)]);
    // uniform, smooth or multisine, each branch its own and independent of the other's; not
    // two multisines: the test's multisines all sit on the same frequency lines, where two
    // inputs' responses cannot be told apart from one output (a several-input experiment puts
    // its inputs' multisines on different lines)
    let base = &Excitation::ALL[..3];
    let b1 = branch(&mut rng, n, seed ^ 0x11, first, base);
    let rest: Vec<Excitation> = base
        .iter()
        .copied()
        .filter(|&k| k != b1.excitation || k != base[2])
        .collect();
    let b2 = branch(&mut rng, n, seed ^ 0x22, second, &rest);
    let branches = vec![b1, b2];
    let mut y0 = vec![0.0; n];
    for b in &branches {
        let yi = b.block.simulate_siso(&b.truth.eval(&b.u), None).unwrap();
        for (a, c) in y0.iter_mut().zip(yi) {
            *a += c;
        }
    }
    let snr = rng.random_range(snr_db.0..snr_db.1);
    let offset = rng.random_range(-2.0..2.0);
    let (y, noise_var) = noisy(&y0, snr, offset, &mut rng);
    RandomMiso {
        seed,
        branches,
        snr_db: snr,
        n,
        y,
        noise_var,
    }
}

/// The record as `IoData` with inputs named `u1`, `u2` and output `y`.
pub fn io_data(r: &RandomMiso) -> hammerstein::IoData<f64> {
    let n = r.n;
    let u = hammerstein::faer::Mat::from_fn(n, r.branches.len(), |k, j| r.branches[j].u[k]);
    let y = hammerstein::faer::Mat::from_fn(n, 1, |k, _| r.y[k]);
    hammerstein::IoData::with_names(
        u,
        y,
        (1..=r.branches.len()).map(|i| format!("u{i}")).collect(),
        vec!["y".into()],
    )
    .unwrap()
}
