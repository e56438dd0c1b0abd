//! Input direction of motion s(k) ∈ {+1, −1}, the only memory of the UDN.
//!
//! Rule (NOTES.md, correcting the paper's α = h[Δu]): s(k) = +1 if u(k) > u(k−1), −1 if
//! u(k) < u(k−1), and the previous direction when u(k) = u(k−1); s(0) is the initial direction.

use crate::real::Real;

/// Streaming direction tracker: feed samples one by one, no allocation.
#[derive(Debug, Clone, Copy)]
pub struct DirectionTracker<T: Real> {
    prev: Option<T>,
    s: T,
}

impl<T: Real> DirectionTracker<T> {
    /// A tracker starting with direction +1.
    pub fn new() -> Self {
        Self::with_initial(T::one())
    }
    /// A tracker starting with the given initial direction (its sign; 0 counts as +1).
    pub fn with_initial(s0: T) -> Self {
        let s = if s0 < T::zero() { -T::one() } else { T::one() };
        DirectionTracker { prev: None, s }
    }
    /// Direction of the next sample u(k).
    pub fn next(&mut self, u: T) -> T {
        if let Some(p) = self.prev {
            if u > p {
                self.s = T::one();
            } else if u < p {
                self.s = -T::one();
            }
        }
        self.prev = Some(u);
        self.s
    }
}

impl<T: Real> Default for DirectionTracker<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// Directions s(k) of an input record, initial direction +1.
pub fn directions<T: Real>(u: &[T]) -> Vec<T> {
    directions_from(u, T::one())
}

/// Directions s(k) of an input record starting with the initial direction `s0` (±1).
pub fn directions_from<T: Real>(u: &[T], s0: T) -> Vec<T> {
    let mut tr = DirectionTracker::with_initial(s0);
    u.iter().map(|&x| tr.next(x)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_input_keeps_direction() {
        let u = [0.0, 1.0, 1.0, 0.5, 0.5, 0.5, 2.0];
        assert_eq!(directions(&u), vec![1.0, 1.0, 1.0, -1.0, -1.0, -1.0, 1.0]);
        assert_eq!(
            directions_from(&[3.0, 3.0, 4.0], -1.0),
            vec![-1.0, -1.0, 1.0]
        );
    }
}
