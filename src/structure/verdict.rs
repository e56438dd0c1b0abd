//! The structure verdict from the BLAs of several levels: `linear`, `single-branch`, `parallel`
//! or `feedback`, with the evidence.
//!
//! One order n for all levels, chosen by the Bayesian information criterion with unknown scale,
//! N·ln(V/N) + p·ln N, over the levels' free fits (orders 1..=`max_order`). Then the nested joint
//! fits of [`super::nested`] and three F tests at level `alpha`: poles shared (against free),
//! zeros shared with a gain per level (against poles shared), one model (against a gain per
//! level). Poles that move → `feedback`; else zeros that move → `parallel`; else a gain that
//! moves or distortion in the BLA → `single-branch`; else `linear` (Schoukens et al., Automatica
//! 53, 2015; Schoukens & Ljung, IEEE Control Systems 39(6), 2019).
//!
//! The evidence: the free fits' poles (or zeros) of the lowest level matched to each higher
//! level's by nearest natural frequency and damping (within 15 %), with delta-method standard
//! errors, and the shift in standard errors.

use super::bla::{Bla, LineBla};
use super::nested::{self, Hypothesis, JointFit, LevelData};
use super::parametric::{Axis, Root, roots_with_errors};
use super::record::Record;
use super::single_branch::{SingleBranchRanking, rank_single_branch};
use crate::error::{Error, Result};

/// What the BLAs say about the system's structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// No distortion, the same linear model at every level.
    Linear,
    /// Poles and zeros stay put, the gain (or only the distortion) changes: Hammerstein, Wiener,
    /// Wiener–Hammerstein.
    SingleBranch,
    /// Poles stay, zeros move: parallel branches.
    Parallel,
    /// Poles move: a nonlinearity inside a feedback loop.
    Feedback,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Verdict::Linear => "linear",
            Verdict::SingleBranch => "single-branch",
            Verdict::Parallel => "parallel",
            Verdict::Feedback => "feedback",
        })
    }
}

/// Options of the structure analysis.
#[derive(Debug, Clone)]
pub struct StructureOptions {
    /// Sampling time in seconds (frequencies in Hz); none gives fractions of the sampling
    /// frequency.
    pub ts: Option<f64>,
    /// A fixed order (none: chosen from the data).
    pub order: Option<usize>,
    /// Highest order tried.
    pub max_order: usize,
    /// Level of the F tests.
    pub alpha: f64,
    /// Half-width in lines of the moving average that smooths the BLA variances used as weights.
    pub smooth: usize,
    /// Fit only the lines in this band (Hz when `ts` is given, else fractions of the sampling
    /// frequency); none: all excited lines.
    pub band: Option<(f64, f64)>,
}

impl Default for StructureOptions {
    fn default() -> Self {
        Self {
            ts: None,
            order: None,
            max_order: 8,
            alpha: 1e-3,
            smooth: 3,
            band: None,
        }
    }
}

/// One F test between nested hypotheses.
#[derive(Debug, Clone, serde::Serialize)]
pub struct NestedTest {
    /// What the test asks ("poles move", "zeros move", "gain moves").
    pub question: String,
    /// The restricted hypothesis.
    pub restricted: Hypothesis,
    /// The fuller hypothesis.
    pub full: Hypothesis,
    /// Costs of both fits.
    pub costs: (f64, f64),
    /// Free parameters of both fits.
    pub params: (usize, usize),
    /// The F statistic.
    pub f: f64,
    /// Its p-value.
    pub p_value: f64,
    /// Whether the restricted hypothesis is rejected.
    pub rejected: bool,
}

/// One level's parametric model.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LevelStructure {
    /// RMS of the level's input.
    pub rms: f64,
    /// Poles of the level's own fit (upper half plane).
    pub poles: Vec<Root>,
    /// Zeros of the level's own fit.
    pub zeros: Vec<Root>,
    /// BLA distortion above noise, dB (none when the record cannot separate them).
    pub distortion_db: Option<f64>,
}

/// A pole or zero of the lowest level matched at a higher level, and its shift.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Movement {
    /// "pole" or "zero".
    pub kind: String,
    /// The level it moved from (the lowest).
    pub from_level: usize,
    /// The level it moved to.
    pub to_level: usize,
    /// At the lowest level.
    pub from: Root,
    /// At the highest level.
    pub to: Root,
    /// Natural-frequency shift in standard errors (signed).
    pub freq_shift_se: f64,
    /// Damping shift in standard errors (signed).
    pub damping_shift_se: f64,
}

/// The structure analysis.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Structure {
    /// The verdict.
    pub verdict: Verdict,
    /// The order of every level's model.
    pub order: usize,
    /// Unit of the frequencies ("Hz" or "cycles/sample").
    pub freq_unit: String,
    /// Per level, lowest first.
    pub levels: Vec<LevelStructure>,
    /// The nested tests.
    pub tests: Vec<NestedTest>,
    /// The lowest level's poles (feedback) or zeros (parallel) matched at each higher level,
    /// largest shift first: those beyond 3 standard errors when any are, else all; poles and
    /// zeros both when the verdict is single-branch or linear.
    pub moved: Vec<Movement>,
    /// The model families consistent with the verdict; for `single-branch` ranked by
    /// [`Structure::rank_single_branch`] once it has run (first the preferred), else in a fixed
    /// order.
    pub candidates: Vec<String>,
    /// The single-branch candidates' fits and validation MSEs, once ranked.
    pub ranking: Option<SingleBranchRanking>,
    /// What the analysis could not tell.
    pub notes: Vec<String>,
}

fn level_data(lines: &[LineBla], axis: &Axis, smooth: usize) -> LevelData {
    let var: Vec<f64> = lines.iter().map(|l| l.var_total).collect();
    let pos: Vec<f64> = var
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let floor = if pos.is_empty() {
        1.0
    } else {
        let mut s = pos.clone();
        s.sort_by(f64::total_cmp);
        1e-6 * s[s.len() / 2]
    };
    let k = var.len();
    let weight = (0..k)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(smooth), (i + smooth).min(k - 1));
            let vals: Vec<f64> = var[lo..=hi]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            let m = if vals.is_empty() {
                floor
            } else {
                vals.iter().sum::<f64>() / vals.len() as f64
            };
            1.0 / m.max(floor).sqrt()
        })
        .collect();
    LevelData {
        w: lines.iter().map(|l| axis.w(l.freq)).collect(),
        g: lines.iter().map(|l| l.value()).collect(),
        weight,
    }
}

fn best(a: Result<JointFit>, b: Result<JointFit>) -> Result<JointFit> {
    match (a, b) {
        (Ok(x), Ok(y)) => Ok(if y.cost < x.cost { y } else { x }),
        (Ok(x), Err(_)) | (Err(_), Ok(x)) => Ok(x),
        (Err(e), Err(_)) => Err(e),
    }
}

/// The four nested fits of order n, each started from the more restricted one's solution too
/// (so that the costs are nested), shared denominators also from each level's own (several
/// starts against local minima).
pub fn nested_fits(data: &[LevelData], n: usize) -> Result<[JointFit; 4]> {
    let levels = data.len();
    let free0 = nested::fit(data, Hypothesis::Free, n, None);
    let lin = nested::fit(data, Hypothesis::Linear, n, None)?;
    let mut shared = best(
        nested::fit(data, Hypothesis::SharedAll, n, None),
        nested::fit(data, Hypothesis::SharedAll, n, Some(&lin)),
    )?;
    if let Ok(f) = &free0 {
        for l in 0..levels {
            shared = best(
                Ok(shared),
                nested::fit_from(data, Hypothesis::SharedAll, n, Some(f), Some(l)),
            )?;
        }
    }
    let mut poles = best(
        nested::fit(data, Hypothesis::SharedPoles, n, None),
        nested::fit(data, Hypothesis::SharedPoles, n, Some(&shared)),
    )?;
    if let Ok(f) = &free0 {
        for l in 0..levels {
            poles = best(
                Ok(poles),
                nested::fit_from(data, Hypothesis::SharedPoles, n, Some(f), Some(l)),
            )?;
        }
    }
    let free = best(free0, nested::fit(data, Hypothesis::Free, n, Some(&poles)))?;
    Ok([lin, shared, poles, free])
}

fn bic(f: &JointFit) -> f64 {
    let n = f.residuals as f64;
    n * (f.cost / n).max(1e-300).ln() + f.params as f64 * n.ln()
}

/// The structure verdict from the BLAs of two or more levels.
pub fn analyze(bla: &Bla, options: &StructureOptions) -> Result<Structure> {
    let levels = bla.levels.len();
    if levels < 2 {
        let what = match bla.levels.first().and_then(|l| l.nonlinearity.as_ref()) {
            Some(nl) if nl.detected => format!(
                "the record is nonlinear (distortion {:.1} dB above the noise, {} of {} lines significant)",
                nl.db_above_noise, nl.lines, nl.of
            ),
            Some(nl) => format!(
                "no distortion above the noise ({} of {} lines significant at 1 %)",
                nl.lines, nl.of
            ),
            None => {
                "this record cannot separate distortion from noise (one realization of a full grid)"
                    .into()
            }
        };
        return Err(Error::InvalidParameter(format!(
            "structure needs BLAs at two or more levels (RMS values) and this record has one level: \
             whether poles or zeros move with the level is not testable. What one level tells: {what} \
             (see `hammerstein bla`). Measure the same experiment at two or more RMS levels."
        )));
    }
    let ts = options.ts.unwrap_or(1.0);
    let in_band = |f: f64| {
        options
            .band
            .is_none_or(|(lo, hi)| f / ts >= lo && f / ts <= hi)
    };
    let kept: Vec<Vec<LineBla>> = bla
        .levels
        .iter()
        .map(|l| {
            l.lines
                .iter()
                .filter(|x| in_band(x.freq))
                .cloned()
                .collect()
        })
        .collect();
    let lines = kept[0].len();
    if lines < 4 {
        return Err(Error::InvalidParameter(format!(
            "the band {:?} holds {lines} excited line(s); at least 4 are needed",
            options.band.unwrap_or((0.0, 0.0))
        )));
    }
    let f_lo = kept[0][0].freq;
    let fmax = kept[0][lines - 1].freq;
    let axis = Axis::new(fmax, ts);
    let data: Vec<LevelData> = kept
        .iter()
        .map(|l| level_data(l, &axis, options.smooth))
        .collect();
    // the order: the lowest BIC of any hypothesis, over the orders (stopping two orders past
    // the best); the verdict's tests then run at that order
    let (order, [lin, shared, poles, free]) = match options.order {
        Some(n) => (n, nested_fits(&data, n)?),
        None => {
            let mut chosen: Option<(f64, usize, [JointFit; 4])> = None;
            for n in 1..=options.max_order.max(1) {
                if 2 * (levels * (2 * n + 1)) >= 2 * lines * levels {
                    break;
                }
                if chosen.as_ref().is_some_and(|c| n >= c.1 + 3) {
                    break;
                }
                let Ok(fits) = nested_fits(&data, n) else {
                    continue;
                };
                let b = fits.iter().map(bic).fold(f64::INFINITY, f64::min);
                if chosen.as_ref().is_none_or(|c| b < c.0) {
                    chosen = Some((b, n, fits));
                }
            }
            let (_, n, fits) = chosen.ok_or_else(|| {
                Error::Identification("no rational model of the BLAs could be fitted".into())
            })?;
            (n, fits)
        }
    };
    let test = |q: &str, r: &JointFit, f: &JointFit| {
        let (fs, p) = nested::f_test(r, f);
        NestedTest {
            question: q.into(),
            restricted: r.hypothesis,
            full: f.hypothesis,
            costs: (r.cost, f.cost),
            params: (r.params, f.params),
            f: fs,
            p_value: p,
            rejected: p < options.alpha,
        }
    };
    let tests = vec![
        test("poles move", &poles, &free),
        test("zeros move", &shared, &poles),
        test("gain moves", &lin, &shared),
    ];
    let distorted = bla
        .levels
        .iter()
        .any(|l| l.nonlinearity.as_ref().is_some_and(|n| n.detected));
    let verdict = if tests[0].rejected {
        Verdict::Feedback
    } else if tests[1].rejected {
        Verdict::Parallel
    } else if tests[2].rejected || distorted {
        Verdict::SingleBranch
    } else {
        Verdict::Linear
    };
    let mut level_out = Vec::with_capacity(levels);
    for (l, lb) in bla.levels.iter().enumerate() {
        let (a, b, cov) = free.level_model(l);
        let n = a.len();
        let ca = faer::Mat::from_fn(n, n, |i, j| cov[(i, j)]);
        let cb = faer::Mat::from_fn(n + 1, n + 1, |i, j| cov[(n + i, n + j)]);
        level_out.push(LevelStructure {
            rms: lb.rms,
            poles: roots_with_errors(&a, true, &ca, &axis)?,
            zeros: roots_with_errors(&b, false, &cb, &axis)?,
            distortion_db: lb.nonlinearity.as_ref().map(|n| n.db_above_noise),
        });
    }
    let mut moved = Vec::new();
    let kinds: &[&str] = match verdict {
        Verdict::Feedback => &["pole"],
        Verdict::Parallel => &["zero"],
        _ => &["pole", "zero"],
    };
    // roots near the band whose frequency is determined and that are stable (spare roots far
    // outside the band or with a frequency the data do not fix carry no evidence)
    let (blo, bhi) = (0.5 * f_lo / ts, 1.5 * fmax / ts);
    let evident =
        |r: &&Root| r.freq >= blo && r.freq <= bhi && r.damping > 0.0 && r.freq_se < 0.5 * r.freq;
    for to_level in 1..levels {
        for &kind in kinds {
            let (a, b) = if kind == "pole" {
                (&level_out[0].poles, &level_out[to_level].poles)
            } else {
                (&level_out[0].zeros, &level_out[to_level].zeros)
            };
            let a: Vec<Root> = a.iter().filter(evident).cloned().collect();
            let b: Vec<Root> = b.iter().filter(evident).cloned().collect();
            for (x, y) in match_roots(&a, &b) {
                let fs =
                    (y.freq - x.freq) / (x.freq_se.powi(2) + y.freq_se.powi(2)).sqrt().max(1e-300);
                let ds = (y.damping - x.damping)
                    / (x.damping_se.powi(2) + y.damping_se.powi(2))
                        .sqrt()
                        .max(1e-300);
                moved.push(Movement {
                    kind: kind.into(),
                    from_level: 0,
                    to_level,
                    from: x.clone(),
                    to: y.clone(),
                    freq_shift_se: fs,
                    damping_shift_se: ds,
                });
            }
        }
    }
    let size = |m: &Movement| m.freq_shift_se.abs().max(m.damping_shift_se.abs());
    moved.sort_by(|a, b| size(b).total_cmp(&size(a)));
    if matches!(verdict, Verdict::Feedback | Verdict::Parallel)
        && moved.iter().any(|m| size(m) > 3.0)
    {
        moved.retain(|m| size(m) > 3.0);
    }
    let candidates: Vec<String> = match verdict {
        Verdict::Linear => vec!["linear".into()],
        Verdict::SingleBranch => vec![
            "hammerstein".into(),
            "wiener".into(),
            "wiener-hammerstein".into(),
        ],
        Verdict::Parallel => vec!["parallel wiener-hammerstein branches".into()],
        Verdict::Feedback => vec!["static nonlinearity in feedback (lur'e / nonlinear lfr)".into()],
    };
    let mut notes = Vec::new();
    if verdict == Verdict::SingleBranch {
        notes.push(NOT_RANKED.into());
    }
    if options.order.is_none() && order == options.max_order {
        notes.push(format!(
            "the order reached --max-order {order}: a higher one may fit the BLAs better"
        ));
    }
    if bla.levels.iter().any(|l| l.realizations < 2) {
        notes.push(
            "one realization per level: the BLA variances hold the noise only (or the detection \
             lines' distortion), so the distortion of that realization acts as a bias the tests \
             do not see as noise"
                .into(),
        );
    }
    Ok(Structure {
        verdict,
        order,
        freq_unit: if options.ts.is_some() {
            "Hz".into()
        } else {
            "cycles/sample".into()
        },
        levels: level_out,
        tests,
        moved,
        candidates,
        ranking: None,
        notes,
    })
}

const NOT_RANKED: &str = "within single-branch, Hammerstein, Wiener and Wiener–Hammerstein are \
                          not ranked: fit each on the record and compare validation errors";

impl Structure {
    /// For a `single-branch` verdict: fits the three classes on the record and ranks them by
    /// validation MSE ([`super::single_branch`]), reorders [`Structure::candidates`], fills
    /// [`Structure::ranking`] and says in the notes how decisive the ranking is. Other verdicts
    /// are left as they are. A ranking that cannot run (no second block to validate on, every
    /// fit failed) leaves the candidates unranked with the reason in the notes.
    pub fn rank_single_branch(&mut self, record: &Record) {
        if self.verdict != Verdict::SingleBranch {
            return;
        }
        self.notes.retain(|n| n != NOT_RANKED);
        match rank_single_branch(record, self.order) {
            Ok(r) => {
                self.candidates = r.candidates.iter().map(|c| c.name.clone()).collect();
                let within: Vec<&str> = r.candidates[1..]
                    .iter()
                    .filter(|c| c.within_noise)
                    .map(|c| c.name.as_str())
                    .collect();
                self.notes.push(if r.decisive {
                    format!(
                        "single-branch ranking (validation MSE on {}, level {}): {} is preferred \
                         beyond noise{}",
                        r.validation,
                        r.fit_level,
                        r.candidates[0].name,
                        if within.is_empty() {
                            String::new()
                        } else {
                            format!(
                                " ({} within one standard error but with more maps: not needed)",
                                within.join(", ")
                            )
                        }
                    )
                } else {
                    format!(
                        "single-branch ranking not decisive: {} within one standard error of the \
                         best validation MSE (on {}, level {})",
                        within.join(", "),
                        r.validation,
                        r.fit_level
                    )
                });
                self.ranking = Some(r);
            }
            Err(e) => self.notes.push(format!(
                "within single-branch, Hammerstein, Wiener and Wiener–Hammerstein are not ranked: {e}"
            )),
        }
    }
}

/// Greedy matching of two root lists by relative distance of (frequency, damping).
pub(crate) fn match_roots<'a>(a: &'a [Root], b: &'a [Root]) -> Vec<(&'a Root, &'a Root)> {
    let mut pairs = Vec::new();
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            let d = ((x.freq - y.freq) / x.freq.max(y.freq).max(1e-300)).abs()
                + (x.damping - y.damping).abs();
            pairs.push((d, i, j));
        }
    }
    pairs.sort_by(|p, q| p.0.total_cmp(&q.0));
    let (mut ua, mut ub) = (vec![false; a.len()], vec![false; b.len()]);
    let mut out = Vec::new();
    for (d, i, j) in pairs {
        // farther than 15 % in frequency (or damping): not the same root
        if d > 0.15 {
            break;
        }
        if !ua[i] && !ub[j] {
            ua[i] = true;
            ub[j] = true;
            out.push((&a[i], &b[j]));
        }
    }
    out
}
