//! Random oversampled records (and controls that are not oversampled) of the decimation battery
//! (`tests/decimation_default_battery.rs`) and of the tests that reproduce one of its records
//! (`tests/from_rest.rs`): a second-order block drawn at random, four input kinds, five static
//! nonlinearities, SNR 10–40 dB, 20 000–40 000 samples; every draw from its seed.

use hammerstein::StateSpace;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

/// Static nonlinearities of the draw.
#[derive(Debug, Clone, Copy)]
pub enum Map {
    Linear,
    Saturation,
    DeadZone,
    Cubic,
    Tanh,
}

impl Map {
    pub const ALL: [Map; 5] = [
        Map::Linear,
        Map::Saturation,
        Map::DeadZone,
        Map::Cubic,
        Map::Tanh,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Map::Linear => "linear",
            Map::Saturation => "saturation",
            Map::DeadZone => "dead-zone",
            Map::Cubic => "cubic",
            Map::Tanh => "tanh",
        }
    }
    pub fn eval(self, u: f64) -> f64 {
        match self {
            Map::Linear => u,
            Map::Saturation => u.clamp(-0.7, 0.9),
            Map::DeadZone => u.signum() * (u.abs() - 0.3).max(0.0),
            Map::Cubic => u + 0.5 * u * u * u,
            Map::Tanh => (1.5 * u).tanh(),
        }
    }
    /// The options a user who knows the map's kind gives (`None`: the default, linear).
    pub fn fit_options(self) -> &'static [&'static str] {
        match self {
            Map::Linear | Map::Tanh => &[],
            Map::Saturation => &["--effects", "saturation"],
            Map::DeadZone => &["--effects", "dead-zone"],
            Map::Cubic => &["--nonlinearity", "poly3"],
        }
    }
}

/// Input kinds of the draw.
#[derive(Debug, Clone, Copy)]
pub enum Input {
    /// Random levels in [−1, 1] held for `hold` samples.
    Steps,
    /// Two levels ±1 held for `hold` samples (a PRBS at the slow rate).
    Prbs,
    /// White noise through a first-order low-pass of the block's bandwidth.
    Smooth,
    /// 12 sines of random phase spread over the block's band.
    Multisine,
}

impl Input {
    pub const ALL: [Input; 4] = [Input::Steps, Input::Prbs, Input::Smooth, Input::Multisine];
    pub fn name(self) -> &'static str {
        match self {
            Input::Steps => "steps",
            Input::Prbs => "prbs",
            Input::Smooth => "smooth",
            Input::Multisine => "multisine",
        }
    }
}

/// One record's draw.
pub struct Draw {
    pub oversampled: bool,
    /// Natural frequency of the block, radians per sample.
    pub wn: f64,
    pub zeta: f64,
    pub input: Input,
    pub hold: usize,
    pub map: Map,
    pub known: bool,
    pub snr: f64,
    pub n: usize,
}

pub fn draw(seed: u64) -> Draw {
    let mut rng = StdRng::seed_from_u64(seed ^ 0xdec1_3a7e);
    let oversampled = seed % 5 != 4;
    let wn = if oversampled {
        10f64.powf(rng.random_range(-2.5..-1.5))
    } else {
        rng.random_range(0.4..1.2)
    };
    let input = Input::ALL[rng.random_range(0..Input::ALL.len())];
    // steps held for about a tenth to a half of the block's period; 1–2 samples for a control
    let hold = if oversampled {
        ((rng.random_range(0.1..0.5) * std::f64::consts::TAU / wn) as usize).max(2)
    } else {
        rng.random_range(1..3)
    };
    Draw {
        oversampled,
        wn,
        zeta: rng.random_range(0.2..1.2),
        input,
        hold,
        map: Map::ALL[rng.random_range(0..Map::ALL.len())],
        known: rng.random_bool(0.5),
        snr: rng.random_range(10.0..40.0),
        n: rng.random_range(20_000..40_000),
    }
}

/// A second-order block of natural frequency `wn` (rad/sample) and damping `zeta`: its
/// discrete poles e^{s·1} of the continuous ones, unit DC gain, companion form.
pub fn block(wn: f64, zeta: f64) -> StateSpace<f64> {
    let (a1, a2) = if zeta < 1.0 {
        let r = (-zeta * wn).exp();
        let th = wn * (1.0 - zeta * zeta).sqrt();
        (2.0 * r * th.cos(), -r * r)
    } else {
        let d = (zeta * zeta - 1.0).sqrt();
        let (p1, p2) = ((-wn * (zeta - d)).exp(), (-wn * (zeta + d)).exp());
        (p1 + p2, -p1 * p2)
    };
    let gain = 1.0 - a1 - a2;
    StateSpace::from_rows(
        &[&[a1, 1.0], &[a2, 0.0]],
        &[&[gain], &[0.0]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap()
}

pub fn input(d: &Draw, n: usize, rng: &mut StdRng) -> Vec<f64> {
    match d.input {
        Input::Steps | Input::Prbs => {
            let mut u = Vec::with_capacity(n);
            while u.len() < n {
                let level = match d.input {
                    Input::Steps => rng.random_range(-1.0..1.0),
                    _ => {
                        if rng.random_bool(0.5) {
                            1.0
                        } else {
                            -1.0
                        }
                    }
                };
                u.extend(std::iter::repeat_n(level, d.hold.min(n - u.len())));
            }
            u
        }
        Input::Smooth => {
            let a = (-2.0 * d.wn).exp();
            let mut x = 0.0;
            let raw: Vec<f64> = (0..n + 2000)
                .map(|_| {
                    x = a * x + (1.0 - a) * rng.random_range(-1.0..1.0);
                    x
                })
                .skip(2000)
                .collect();
            let m = raw.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            raw.iter().map(|v| v / m).collect()
        }
        Input::Multisine => {
            let ws: Vec<(f64, f64)> = (0..12)
                .map(|_| {
                    (
                        d.wn * rng.random_range(0.05..2.0),
                        rng.random_range(0.0..std::f64::consts::TAU),
                    )
                })
                .collect();
            let raw: Vec<f64> = (0..n)
                .map(|k| ws.iter().map(|(w, p)| (w * k as f64 + p).sin()).sum())
                .collect();
            let m = raw.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            raw.iter().map(|v| v / m).collect()
        }
    }
}

/// One record of the draw: the training record (input, noisy output, noise-free output) and a
/// held-out record of half its length (another input of the same kind) with its noisy and
/// noise-free outputs.
pub struct Record {
    pub draw: Draw,
    pub u: Vec<f64>,
    pub y: Vec<f64>,
    pub y0: Vec<f64>,
    pub uv: Vec<f64>,
    pub yv: Vec<f64>,
    pub yv0: Vec<f64>,
}

/// The record of `seed` (every draw from it: the same seed, the same record).
pub fn record(seed: u64) -> Record {
    let d = draw(seed);
    let g = block(d.wn, d.zeta);
    let mut rng = StdRng::seed_from_u64(seed);
    let record = |n: usize, rng: &mut StdRng| {
        let u = input(&d, n, rng);
        let v: Vec<f64> = u.iter().map(|&x| d.map.eval(x)).collect();
        let y0 = g.simulate_siso(&v, None).unwrap();
        (u, y0)
    };
    let (u, y0) = record(d.n, &mut rng);
    let (uv, yv0) = record(d.n / 2, &mut rng);
    let var = {
        let m = y0.iter().sum::<f64>() / y0.len() as f64;
        y0.iter().map(|y| (y - m).powi(2)).sum::<f64>() / y0.len() as f64
    };
    let noise = Normal::new(0.0, (var / 10f64.powf(d.snr / 10.0)).sqrt()).unwrap();
    let y: Vec<f64> = y0.iter().map(|v| v + noise.sample(&mut rng)).collect();
    let yv: Vec<f64> = yv0.iter().map(|v| v + noise.sample(&mut rng)).collect();
    Record {
        draw: d,
        u,
        y,
        y0,
        uv,
        yv,
        yv0,
    }
}
