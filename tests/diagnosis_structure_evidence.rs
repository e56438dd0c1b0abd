//! The structure verdict as evidence of the `feedback-nonlinearity` candidate: on a Hammerstein
//! record (a saturation at the input) the input-side shapes explain the held-out residual at
//! least as well as the feedback shapes, and the candidate is not offered; given a `feedback`
//! verdict (poles that move with the level, which no input nonlinearity produces) the same
//! candidate is offered, its evidence cites the verdict and its p-value joins the verdict's; a
//! `single-branch` verdict is cited and changes nothing.

use hammerstein::diagnosis::{CandidateId, Diagnoser, DiagnosisOptions, StructureEvidence};
use hammerstein::fit::Hammerstein;
use hammerstein::structure::Verdict;
use hammerstein::{IoData, Order};
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// Random levels held 20 samples through a saturation at ±0.6 into a resonant second-order
/// block, with 1 % white output noise.
fn hammerstein_record(seed: u64, n: usize) -> IoData<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut u = Vec::with_capacity(n);
    let mut level = 0.0f64;
    for k in 0..n {
        if k % 20 == 0 {
            level = rng.random_range(-1.0..1.0);
        }
        u.push(level);
    }
    let (a1, a2, b1) = (1.5, -0.7, 0.2);
    let mut y = vec![0.0; n];
    for k in 2..n {
        let v = u[k - 1].clamp(-0.6, 0.6);
        y[k] = a1 * y[k - 1] + a2 * y[k - 2] + b1 * v;
    }
    let scale = (y.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    let y: Vec<f64> = y
        .iter()
        .map(|v| v + 0.01 * scale * rng.random_range(-1.7..1.7))
        .collect();
    IoData::siso(&u, &y).unwrap()
}

fn evidence(options: DiagnosisOptions) -> (String, f64, bool) {
    let data = hammerstein_record(5, 3000);
    let model = Hammerstein::<f64>::linear()
        .order(Order::Fixed(2))
        .fit(&data)
        .unwrap();
    let d = Diagnoser::<f64>::new().options(options);
    let a = d.analysis(&model, &data).unwrap();
    let c = d
        .candidates()
        .get(&CandidateId::FeedbackNonlinearity)
        .unwrap();
    let e = c.evidence(&a).expect("the feedback signature is computed");
    (e.sentence, e.p_adjusted, e.significant)
}

fn with_verdict(verdict: Verdict, line: &str, p_value: f64) -> DiagnosisOptions {
    let mut o = DiagnosisOptions::default();
    o.analysis.structure = Some(StructureEvidence {
        verdict,
        line: line.into(),
        p_value,
    });
    o
}

#[test]
fn a_feedback_verdict_offers_the_feedback_candidate_and_cites_the_moving_pole() {
    let (plain, p_plain, _) = evidence(DiagnosisOptions::default());
    // the precondition: on this Hammerstein record the residual alone does not offer it
    assert!(
        plain.ends_with("an input nonlinearity explains it as well"),
        "{plain}"
    );
    assert!(!plain.contains("best linear approximations"), "{plain}");

    let line = "feedback: pole at 0.0732 moved to 0.0701, 32.8 s.e.";
    let (moved, p_moved, significant) = evidence(with_verdict(Verdict::Feedback, line, 1e-9));
    assert!(moved.contains(line), "{moved}");
    assert!(
        moved.contains("which a loop produces and an input nonlinearity does not")
            && moved.contains(": a nonlinearity in feedback (--feedback-nonlinearity"),
        "{moved}"
    );
    // Bonferroni over the signature and the verdict: twice the smaller
    assert!(
        (p_moved - (2.0 * p_plain.min(1e-9)).min(1.0)).abs() <= 1e-12,
        "{p_moved} {p_plain}"
    );
    assert!(significant);

    let (single, p_single, _) = evidence(with_verdict(Verdict::SingleBranch, "single-branch", 1.0));
    assert!(
        single.contains("best linear approximations: single-branch"),
        "{single}"
    );
    assert!(
        single.ends_with("an input nonlinearity explains it as well"),
        "{single}"
    );
    assert_eq!(p_single, p_plain);
}
