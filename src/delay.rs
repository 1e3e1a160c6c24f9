//! The pure input delay: a history of the command on the simulation's uniform step grid,
//! read back at `t − τ` with cubic Lagrange interpolation (4th-order accurate, so the delay
//! does not spoil RK4's order on smooth commands).

use std::collections::VecDeque;

/// Uniformly sampled history of a signal, `value(t_n)` for `t_n = n·h`, `n ≥ 0`.
/// Before the first sample the signal is `initial` (the rig starts at rest).
#[derive(Debug, Clone)]
pub struct DelayLine {
    h: f64,
    capacity: usize,
    first_index: u64,
    values: VecDeque<f64>,
    initial: f64,
}

impl DelayLine {
    /// A history with step `h` [s] long enough for delays up to `max_delay` [s].
    pub fn new(h: f64, max_delay: f64, initial: f64) -> Self {
        let capacity = (max_delay / h).ceil() as usize + 8;
        Self {
            h,
            capacity,
            first_index: 0,
            values: VecDeque::with_capacity(capacity + 1),
            initial,
        }
    }

    /// Appends the value at the next grid time `t_n = len·h`.
    #[inline]
    pub fn push(&mut self, v: f64) {
        self.values.push_back(v);
        if self.values.len() > self.capacity {
            self.values.pop_front();
            self.first_index += 1;
        }
    }

    /// Time of the newest sample [s] (−h before any).
    #[inline]
    pub fn last_time(&self) -> f64 {
        (self.first_index + self.values.len() as u64) as f64 * self.h - self.h
    }

    /// Newest sample (or the initial value).
    #[inline]
    pub fn last_value(&self) -> f64 {
        self.values.back().copied().unwrap_or(self.initial)
    }

    #[inline(always)]
    fn at_index(&self, n: i64) -> f64 {
        if n < self.first_index as i64 {
            // Before the stored window: either before t = 0 (rest) or forgotten (clamped).
            if n < 0 {
                self.initial
            } else {
                self.values.front().copied().unwrap_or(self.initial)
            }
        } else {
            let i = (n - self.first_index as i64) as usize;
            self.values
                .get(i)
                .copied()
                .unwrap_or_else(|| self.last_value())
        }
    }

    /// The signal at `t` ≤ [`Self::last_time`], cubic in the interior, linear at the newest edge.
    #[inline]
    pub fn value_at(&self, t: f64) -> f64 {
        let s = t / self.h;
        let n = s.floor();
        let f = s - n;
        let n = n as i64;
        let newest = (self.first_index + self.values.len() as u64) as i64 - 1;
        if n + 2 <= newest {
            let (a, b, c, d) = (
                self.at_index(n - 1),
                self.at_index(n),
                self.at_index(n + 1),
                self.at_index(n + 2),
            );
            // Cubic Lagrange through (−1, a), (0, b), (1, c), (2, d).
            b + f * (-a / 3.0 - b / 2.0 + c - d / 6.0)
                + f * f * ((a + c) / 2.0 - b)
                + f * f * f * ((d - a) / 6.0 + (b - c) / 2.0)
        } else {
            let (b, c) = (self.at_index(n), self.at_index(n + 1));
            b + f * (c - b)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_is_exact_for_cubics_and_rest_before_zero() {
        let h = 0.01;
        let mut d = DelayLine::new(h, 0.5, 0.0);
        let g = |t: f64| 1.0 + 2.0 * t - 3.0 * t * t + 0.5 * t * t * t;
        for n in 0..40 {
            d.push(g(n as f64 * h));
        }
        for t in [0.0137, 0.2, 0.3333] {
            assert!((d.value_at(t) - g(t)).abs() < 1e-12);
        }
        assert_eq!(d.value_at(-0.05), 0.0);
    }

    #[test]
    fn old_samples_are_forgotten_but_window_is_kept() {
        let mut d = DelayLine::new(1.0, 3.0, 0.0);
        for n in 0..100 {
            d.push(n as f64);
        }
        assert_eq!(d.last_time(), 99.0);
        assert!((d.value_at(97.5) - 97.5).abs() < 1e-12);
    }
}
