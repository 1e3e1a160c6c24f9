//! The pure input delay: a history of the command on the simulation's uniform step grid,
//! read back at `t − τ` with cubic Lagrange interpolation (4th-order accurate, so the delay
//! does not spoil RK4's order on smooth commands).

/// Uniformly sampled history of a signal, `value(t_n)` for `t_n = n·h`, `n ≥ 0`.
/// Before the first sample the signal is `initial` (the rig starts at rest).
///
/// Stored in a power-of-two ring buffer so that a read is a mask and four loads: the delay
/// line is read four times per RK4 step, so it sits on the twin's hot path.
#[derive(Debug, Clone)]
pub struct DelayLine {
    h: f64,
    inv_h: f64,
    /// Number of samples pushed so far (the next sample has index `len`).
    len: u64,
    /// Ring buffer of the newest `mask + 1` samples.
    ring: Vec<f64>,
    mask: u64,
    initial: f64,
}

impl DelayLine {
    /// A history with step `h` [s] long enough for delays up to `max_delay` [s].
    pub fn new(h: f64, max_delay: f64, initial: f64) -> Self {
        let needed = (max_delay / h).ceil() as usize + 8;
        let size = needed.next_power_of_two();
        Self {
            h,
            inv_h: 1.0 / h,
            len: 0,
            ring: vec![initial; size],
            mask: size as u64 - 1,
            initial,
        }
    }

    /// Appends the value at the next grid time `t_n = len·h`.
    #[inline]
    pub fn push(&mut self, v: f64) {
        self.ring[(self.len & self.mask) as usize] = v;
        self.len += 1;
    }

    /// Time of the newest sample [s] (−h before any).
    #[inline]
    pub fn last_time(&self) -> f64 {
        self.len as f64 * self.h - self.h
    }

    /// Newest sample (or the initial value).
    #[inline]
    pub fn last_value(&self) -> f64 {
        if self.len == 0 {
            self.initial
        } else {
            self.ring[((self.len - 1) & self.mask) as usize]
        }
    }

    #[inline(always)]
    fn at_index(&self, n: i64) -> f64 {
        if n < 0 {
            return self.initial;
        }
        let newest = self.len as i64 - 1;
        let oldest = (self.len as i64 - self.ring.len() as i64).max(0);
        // Beyond the newest sample: hold it; older than the window: the oldest kept (clamped).
        let n = n.clamp(oldest, newest.max(0));
        if newest < 0 {
            return self.initial;
        }
        self.ring[(n as u64 & self.mask) as usize]
    }

    /// The signal at `t` ≤ [`Self::last_time`], cubic in the interior, linear at the newest edge.
    #[inline]
    pub fn value_at(&self, t: f64) -> f64 {
        let s = t * self.inv_h;
        if s < 0.0 {
            // Before t = 0 the rig was at rest.
            return self.initial;
        }
        // s ≥ 0: truncation is floor (and much cheaper than a libm call).
        let n = s as i64;
        let f = s - n as f64;
        let newest = self.len as i64 - 1;
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
