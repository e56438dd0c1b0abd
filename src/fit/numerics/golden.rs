//! Golden-section search's bracket (Kiefer 1953) and a guess of its next step's direction from
//! the parabola through the best point and its neighbours (Brent 1973, ch. 5), which lets the
//! loop's 1-D search (`search.rs`) evaluate the next step's point ahead, beside the current one.

/// Golden section's bracket [l, h] with its interior points x1 < x2.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bracket {
    /// Lower end.
    pub l: f64,
    /// Upper end.
    pub h: f64,
    /// The lower interior point.
    pub x1: f64,
    /// The upper interior point.
    pub x2: f64,
}

/// The golden ratio's conjugate (√5 − 1)/2.
fn golden_ratio() -> f64 {
    (5f64.sqrt() - 1.0) / 2.0
}

impl Bracket {
    /// The bracket [l, h] with its golden-section interior points.
    pub fn new(l: f64, h: f64) -> Self {
        let gr = golden_ratio();
        Self {
            l,
            h,
            x1: h - gr * (h - l),
            x2: l + gr * (h - l),
        }
    }

    /// One golden-section step: to the left when f(x1) ≤ f(x2) ([l, x2], a new x1), else to the
    /// right ([x1, h], a new x2); the new bracket and its new point.
    pub fn step(self, left: bool) -> (Self, f64) {
        let gr = golden_ratio();
        let Bracket { l, h, x1, x2 } = self;
        if left {
            let x = x2 - gr * (x2 - l);
            (
                Bracket {
                    l,
                    h: x2,
                    x1: x,
                    x2: x1,
                },
                x,
            )
        } else {
            let x = x1 + gr * (h - x1);
            (
                Bracket {
                    l: x1,
                    h,
                    x1: x2,
                    x2: x,
                },
                x,
            )
        }
    }

    /// A guess of the direction of the step after the one that evaluates `x` (this bracket's
    /// new point; the step was to the left when `went_left`), beside the interior point `kept`
    /// (x, f) it compares with: the next step goes left when the new point is the better of the
    /// two after a left step, the worse after a right one. The guess: the new point is better
    /// when it is nearer than `kept` to the vertex of the parabola through `kept` and the
    /// nearest points tried on either side of it (Brent 1973's parabolic step; worse when that
    /// parabola is not convex or a side has no point).
    pub fn guess_left(
        &self,
        went_left: bool,
        kept: (f64, f64),
        x: f64,
        tried: &[(f64, f64)],
    ) -> bool {
        let better =
            parabola_vertex(kept, tried).is_some_and(|v| (x - v).abs() < (kept.0 - v).abs());
        better == went_left
    }
}

/// The vertex of the parabola through `b` and the nearest points of `tried` left and right of
/// it, when it is convex (all values finite); `None` otherwise.
fn parabola_vertex((xb, fb): (f64, f64), tried: &[(f64, f64)]) -> Option<f64> {
    let nearest = |left: bool| {
        tried
            .iter()
            .filter(|(x, f)| f.is_finite() && if left { *x < xb } else { *x > xb })
            .min_by(|p, q| (p.0 - xb).abs().total_cmp(&(q.0 - xb).abs()))
            .copied()
    };
    let ((xa, fa), (xc, fc)) = (nearest(true)?, nearest(false)?);
    let (sa, sc) = ((fb - fa) / (xb - xa), (fc - fb) / (xc - xb));
    if !(fb.is_finite() && sc - sa > 0.0) {
        return None;
    }
    // the vertex of the interpolating parabola: the midpoint of the two secants' midpoints
    // shifted by their slopes (f' is linear in x)
    let (ma, mc) = (0.5 * (xa + xb), 0.5 * (xb + xc));
    Some(ma - sa * (mc - ma) / (sc - sa))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_the_classic_golden_section_updates() {
        let gr = golden_ratio();
        let b = Bracket::new(0.0, 1.0);
        assert!((b.x1 - (1.0 - gr)).abs() < 1e-15 && (b.x2 - gr).abs() < 1e-15);
        // left: [l, x2] with the old x1 as its upper interior point
        let (left, x) = b.step(true);
        assert_eq!((left.l, left.h, left.x2), (b.l, b.x2, b.x1));
        assert_eq!(x, left.x1);
        assert!((left.x1 - (b.x2 - gr * (b.x2 - b.l))).abs() == 0.0);
        // right: [x1, h] with the old x2 as its lower interior point
        let (right, x) = b.step(false);
        assert_eq!((right.l, right.h, right.x1), (b.x1, b.h, b.x2));
        assert_eq!(x, right.x2);
    }

    #[test]
    fn the_guess_follows_a_convex_parabola() {
        // f = (x − 0.3)²: the vertex from three samples, and the guesses it gives
        let f = |x: f64| (x - 0.3) * (x - 0.3);
        let tried: Vec<(f64, f64)> = [0.0, 0.5, 1.0].iter().map(|&x| (x, f(x))).collect();
        let v = parabola_vertex((0.5, f(0.5)), &tried).unwrap();
        assert!((v - 0.3).abs() < 1e-12, "{v}");
        // no point on one side, or concave: no vertex
        assert!(parabola_vertex((1.0, f(1.0)), &tried).is_none());
        let concave: Vec<(f64, f64)> = tried.iter().map(|&(x, y)| (x, -y)).collect();
        assert!(parabola_vertex((0.5, -f(0.5)), &concave).is_none());
        // after a left step, a new point nearer the vertex than the kept one is better: left
        let b = Bracket::new(0.0, 1.0);
        assert!(b.guess_left(true, (0.5, f(0.5)), 0.35, &tried));
        assert!(!b.guess_left(false, (0.5, f(0.5)), 0.35, &tried));
        assert!(!b.guess_left(true, (0.5, f(0.5)), 0.9, &tried));
    }
}
