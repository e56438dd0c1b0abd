//! The structure verdict beside the diagnosis. On a multisine record in the record format
//! (`level,realization,period,u,y`, [`crate::structure::Record`]) the BLAs of its levels give a
//! verdict (`linear`, `single-branch`, `parallel`, `feedback`; [`crate::structure::analyze`]).
//! A Hammerstein model (one branch, a static nonlinearity before the linear block) expresses
//! `linear` and `single-branch`; poles that move with the level (`feedback`) or zeros that move
//! (`parallel`) lie outside its class, and [`beyond_class`] says so as an [`Unexplained`] entry:
//! which class would express it, and the movement that shows it.
//!
//! Which samples the diagnosis fits on such a record: [`fit_rows`], the highest level's blocks
//! in file order (its transient periods included) — the widest amplitude range of the record,
//! so that the training and the validation parts come from the same level and the validation
//! part is not an extrapolation in amplitude.

use super::ids::TestId;
use super::outcome::Unexplained;
use super::residual_tests::structure_evidence::StructureEvidence;
use crate::structure::parametric::Root;
use crate::structure::{Record, Structure, Verdict};

/// The name the verdict's entry carries in `unexplained` (where a residual test's name stands).
pub const STRUCTURE_TEST: &str = "structure-verdict";

/// The input and output of the record's highest level, its blocks in file order (each block
/// whole: the transient period and the steady ones); `None` when the record has no output.
pub fn fit_rows(record: &Record) -> Option<(Vec<f64>, Vec<f64>)> {
    let top = record.levels().checked_sub(1)?;
    let (mut u, mut y) = (Vec::new(), Vec::new());
    for b in record.blocks().iter().filter(|b| b.level == top) {
        u.extend_from_slice(&b.u);
        y.extend_from_slice(b.y.as_ref()?);
    }
    Some((u, y))
}

/// The verdict and its strongest evidence in one line, e.g. "feedback: pole at 7.32 Hz moved to
/// 7.26 Hz, 32.8 s.e." (frequencies in the analysis' unit).
pub fn verdict_line(s: &Structure) -> String {
    let kind = match s.verdict {
        Verdict::Feedback => "pole",
        Verdict::Parallel => "zero",
        _ => "",
    };
    let named = s
        .moved
        .iter()
        .find(|m| m.kind == kind)
        .map(|m| {
            (
                m.from.clone(),
                m.to.clone(),
                m.freq_shift_se.abs().max(m.damping_shift_se.abs()),
            )
        })
        .or_else(|| nearest_resonance(s, kind));
    match named {
        Some((from, to, se)) => format!(
            "{}: {kind} at {} {u} moved to {} {u}, {se:.1} s.e.",
            s.verdict,
            short(from.freq),
            short(to.freq),
            u = s.freq_unit
        ),
        None => match s.verdict {
            Verdict::Feedback | Verdict::Parallel => format!(
                "{}: the {} move with the level (F test p = {:.1e})",
                s.verdict,
                if s.verdict == Verdict::Feedback {
                    "poles"
                } else {
                    "zeros"
                },
                rejected_p(s)
            ),
            _ => s.verdict.to_string(),
        },
    }
}

/// A movement too large for the evidence's matching (which pairs roots within 15 %): the
/// lowest level's resonance (complex, stable) and the highest level's nearest one, with the
/// frequency shift in standard errors.
fn nearest_resonance(s: &Structure, kind: &str) -> Option<(Root, Root, f64)> {
    let roots = |l: &crate::structure::verdict::LevelStructure| -> Vec<Root> {
        let r = if kind == "pole" { &l.poles } else { &l.zeros };
        r.iter()
            .filter(|r| !r.real && r.damping > 0.0 && r.damping < 1.0 && r.freq_se < 0.5 * r.freq)
            .cloned()
            .collect()
    };
    let (a, b) = (roots(s.levels.first()?), roots(s.levels.last()?));
    let mut best: Option<(Root, Root, f64)> = None;
    for x in &a {
        for y in &b {
            let d = ((y.freq - x.freq) / x.freq).abs();
            if best
                .as_ref()
                .is_none_or(|(p, q, _)| d < ((q.freq - p.freq) / p.freq).abs())
            {
                best = Some((x.clone(), y.clone(), 0.0));
            }
        }
    }
    best.map(|(x, y, _)| {
        let se =
            (y.freq - x.freq).abs() / (x.freq_se.powi(2) + y.freq_se.powi(2)).sqrt().max(1e-300);
        (x, y, se)
    })
}

/// Four significant digits, without trailing exponent noise.
fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}

/// The p-value of the test behind the verdict (poles move for feedback, zeros move for
/// parallel); 1 when none was rejected.
fn rejected_p(s: &Structure) -> f64 {
    let q = match s.verdict {
        Verdict::Feedback => "poles move",
        Verdict::Parallel => "zeros move",
        _ => return 1.0,
    };
    s.tests
        .iter()
        .find(|t| t.question == q)
        .map_or(1.0, |t| t.p_value)
}

/// The verdict as evidence for the residual analysis
/// ([`AnalysisOptions::structure`](crate::diagnosis::residual_tests::analysis::AnalysisOptions)):
/// the feedback-nonlinearity candidate cites it.
pub fn evidence(s: &Structure) -> StructureEvidence {
    StructureEvidence {
        verdict: s.verdict,
        line: verdict_line(s),
        p_value: rejected_p(s),
    }
}

/// The `unexplained` entry when the verdict lies outside the class of a Hammerstein model
/// (`feedback`: unless the model has a nonlinearity in feedback; `parallel`: always); `None`
/// for `linear` and `single-branch`.
pub fn beyond_class(s: &Structure, model_has_feedback: bool) -> Option<Unexplained> {
    let class = match s.verdict {
        Verdict::Feedback if !model_has_feedback => {
            "a static nonlinearity inside the feedback loop: a Hammerstein model cannot express \
             poles that move with the level; see --feedback-nonlinearity"
        }
        Verdict::Parallel => {
            "parallel branches (Wiener–Hammerstein branches summed): a single-branch model cannot \
             express zeros that move with the level"
        }
        _ => return None,
    };
    Some(Unexplained {
        test: TestId::User(STRUCTURE_TEST.into()),
        p_adjusted: rejected_p(s),
        model_classes: vec![format!(
            "the structure verdict is {}; {class}",
            verdict_line(s)
        )],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::{Block, MultisineDesign, MultisineKind, StructureOptions, analyze, bla};

    /// A record of two levels through y = G(u − c·y³) (feedback) or y = G(u + 0.3 u³)
    /// (Hammerstein), G a resonant second-order block.
    fn record(feedback: bool, c: f64) -> Record {
        let design = MultisineDesign {
            kind: MultisineKind::RandomOdd { group: 4 },
            samples: 256,
            band: (0.01, 0.2),
            levels: vec![0.2, 1.0],
            realizations: 4,
            periods: 2,
            seed: 3,
        }
        .generate()
        .unwrap();
        let (a1, a2, b1) = (-1.6, 0.8, 0.2);
        design
            .replayed(|b: &Block| {
                let mut y = vec![0.0f64; b.u.len()];
                let mut e = vec![0.0; b.u.len()];
                for t in 0..b.u.len() {
                    if t >= 2 {
                        y[t] = b1 * e[t - 1] - a1 * y[t - 1] - a2 * y[t - 2];
                    } else if t == 1 {
                        y[t] = b1 * e[0] - a1 * y[0];
                    }
                    e[t] = if feedback {
                        b.u[t] - c * y[t].powi(3)
                    } else {
                        b.u[t] + 0.3 * b.u[t].powi(3)
                    };
                }
                y
            })
            .unwrap()
    }

    #[test]
    fn feedback_is_beyond_a_hammerstein_model_and_single_branch_is_not() {
        let r = record(true, 0.1);
        let s = analyze(&bla(&r).unwrap(), &StructureOptions::default()).unwrap();
        assert_eq!(s.verdict, Verdict::Feedback, "{s:?}");
        let u = beyond_class(&s, false).expect("feedback lies outside a Hammerstein model");
        assert_eq!(u.test.as_str(), STRUCTURE_TEST);
        assert!(u.p_adjusted < 1e-3);
        let why = &u.model_classes[0];
        assert!(
            why.contains("feedback: pole at"),
            "{why} {:?} {:?}",
            s.moved,
            s.levels
        );
        assert!(why.contains("--feedback-nonlinearity"), "{why}");
        assert!(beyond_class(&s, true).is_none());
        // a pole that moves farther than the evidence's matching window is still named
        let strong = analyze(
            &bla(&record(true, 0.5)).unwrap(),
            &StructureOptions::default(),
        )
        .unwrap();
        assert_eq!(strong.verdict, Verdict::Feedback);
        assert!(strong.moved.is_empty(), "{:?}", strong.moved);
        let line = verdict_line(&strong);
        assert!(line.starts_with("feedback: pole at 0.07"), "{line}");
        let h = analyze(
            &bla(&record(false, 0.0)).unwrap(),
            &StructureOptions::default(),
        )
        .unwrap();
        assert_eq!(h.verdict, Verdict::SingleBranch, "{h:?}");
        assert!(beyond_class(&h, false).is_none());
        // the rows the diagnosis fits: the highest level, every block whole
        let (u, y) = fit_rows(&r).unwrap();
        let top: usize = r
            .blocks()
            .iter()
            .filter(|b| b.level == 1)
            .map(|b| b.u.len())
            .sum();
        assert_eq!((u.len(), y.len()), (top, top));
        assert!(fit_rows(&MultisineDesign::default().generate().unwrap()).is_none());
    }
}
