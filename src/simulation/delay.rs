//! The pure input delay: a history of the command on the simulation's uniform step grid,
//! read back at `t − τ` with cubic Lagrange interpolation (4th-order accurate, so the delay
//! does not spoil RK4's order on smooth commands).

/// A saved state that does not fit what it is restored into: a delay line, a controller or a
/// simulation (each one's `restore`). Defined with the delay line, the lowest of the three
/// (a controller and a simulation hold delay lines), so both take it from below.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RestoreError {
    /// A part's size differs from the one rebuilt from the parameters.
    #[error("the saved {what} is {found}, this simulation's is {expected}")]
    Mismatch {
        /// Which part.
        what: &'static str,
        /// This simulation's.
        expected: usize,
        /// The saved state's.
        found: usize,
    },
}

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
    /// A history with step `h` \[s\] long enough for delays up to `max_delay` \[s\].
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

    /// Time of the newest sample \[s\] (−h before any).
    #[inline]
    pub fn last_time(&self) -> f64 {
        self.len as f64 * self.h - self.h
    }

    /// The line, leaving in its place an empty one of the same step (whose reads would panic)
    /// until it is put back: a stepping loop holds it as a local of its own.
    pub(crate) fn take(&mut self) -> DelayLine {
        let empty = DelayLine {
            h: self.h,
            inv_h: self.inv_h,
            len: 0,
            ring: Vec::new(),
            mask: 0,
            initial: self.initial,
        };
        std::mem::replace(self, empty)
    }

    /// Samples pushed so far.
    #[inline]
    pub(crate) fn pushed(&self) -> u64 {
        self.len
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
        self.interpolate(n, f, &lagrange_weights(f))
    }

    /// A fixed read `delay` \[s\] behind the grid, for [`Self::value_at_tap`].
    pub fn tap(&self, delay: f64) -> Tap {
        let d = delay * self.inv_h;
        let back = d.ceil();
        let f = back - d;
        Tap {
            back: back as i64,
            f,
            w: lagrange_weights(f),
        }
    }

    /// The signal at `n·h − delay` for the grid index `n` and a [`Tap`] made for `delay`:
    /// [`Self::value_at`] without the division, the floor and the weights, which a fixed delay
    /// on the simulation's grid makes constant.
    #[inline(always)]
    pub fn value_at_tap(&self, n: u64, tap: &Tap) -> f64 {
        self.interpolate(n as i64 - tap.back, tap.f, &tap.w)
    }

    /// The first grid index from which a read through `tap` is inside the window for a line
    /// that holds the samples up to the one before the read (`len` equal to the read's index,
    /// as in a loop that pushes one sample per step and reads the step's end before pushing):
    /// from there on [`Self::value_at_interior_tap`] reads what [`Self::value_at_tap`] reads.
    /// `None` for a tap that never reads inside (one not settled, or longer than the ring).
    pub(crate) fn interior_from(&self, tap: &Tap) -> Option<u64> {
        (tap.is_settled() && (tap.back as usize) < self.ring.len()).then_some(tap.back as u64 + 1)
    }

    /// [`Self::value_at_tap`] at grid index `n` for a read inside the window (`n` at least
    /// [`Self::interior_from`], and `len == n`): the four masked loads and the weighted sum
    /// only, without the edge cases.
    #[inline(always)]
    pub(crate) fn value_at_interior_tap(&self, n: u64, tap: &Tap) -> f64 {
        debug_assert!(self.len == n && n > tap.back as u64);
        let base = n - tap.back as u64;
        let at = |i: u64| self.ring[(i & self.mask) as usize];
        let w = &tap.w;
        w[0] * at(base - 1) + w[1] * at(base) + w[2] * at(base + 1) + w[3] * at(base + 2)
    }

    /// The newest samples of the line in a ring of `R` samples held by a stepping loop
    /// ([`LocalRing`]), for a line no longer than `R` (`None` for a longer one). `R` is a power
    /// of two, so that the ring's index is a mask by a constant and its reads and writes need
    /// no bounds check.
    pub(crate) fn local_ring<const R: usize>(&self) -> Option<LocalRing<R>> {
        const { assert!(R.is_power_of_two()) };
        if self.ring.len() > R {
            return None;
        }
        let mut buf = [self.initial; R];
        for i in self.len.saturating_sub(self.ring.len() as u64)..self.len {
            buf[i as usize & (R - 1)] = self.ring[(i & self.mask) as usize];
        }
        Some(LocalRing { buf, len: self.len })
    }

    /// Takes back the samples that `local` (from [`Self::local_ring`] of this line) was pushed
    /// from grid index `from` on: the line is then as the same pushes would have left it.
    pub(crate) fn put_back<const R: usize>(&mut self, local: &LocalRing<R>, from: u64) {
        let first = from.max(local.len.saturating_sub(self.ring.len() as u64));
        for i in first..local.len {
            self.ring[(i & self.mask) as usize] = local.buf[i as usize & (R - 1)];
        }
        self.len = local.len;
    }

    /// Value at `base + f` (grid units, `0 ≤ f < 1`) with the cubic weights `w` of `f`.
    #[inline(always)]
    fn interpolate(&self, base: i64, f: f64, w: &[f64; 4]) -> f64 {
        if base < 0 {
            return self.initial;
        }
        let newest = self.len as i64 - 1;
        let oldest = self.len as i64 - self.ring.len() as i64;
        if base >= 1 && base > oldest && base + 2 <= newest {
            // Interior: all four samples (base − 1 ..= base + 2) in the window.
            let at = |i: i64| self.ring[(i as u64 & self.mask) as usize];
            w[0] * at(base - 1) + w[1] * at(base) + w[2] * at(base + 1) + w[3] * at(base + 2)
        } else if base + 2 <= newest {
            // At the start (the rest value before it) or older than the window (clamped).
            w[0] * self.at_index(base - 1)
                + w[1] * self.at_index(base)
                + w[2] * self.at_index(base + 1)
                + w[3] * self.at_index(base + 2)
        } else {
            let (b, c) = (self.at_index(base), self.at_index(base + 1));
            b + f * (c - b)
        }
    }
}

/// The newest samples of a [`DelayLine`] in a ring of `R` (a power of two) held by a stepping
/// loop ([`DelayLine::local_ring`], given back by [`DelayLine::put_back`]): its reads of a
/// settled tap are [`DelayLine::value_at_interior_tap`]'s, with the ring's index masked by a
/// constant instead of the line's mask (measured: about a dozen instructions fewer a step in
/// the linear model's loop, the bounds checks of the five accesses).
#[derive(Debug, Clone)]
pub(crate) struct LocalRing<const R: usize> {
    buf: [f64; R],
    /// Samples pushed so far (the next sample has index `len`).
    len: u64,
}

impl<const R: usize> LocalRing<R> {
    /// [`DelayLine::push`].
    #[inline(always)]
    pub(crate) fn push(&mut self, v: f64) {
        self.buf[self.len as usize & (R - 1)] = v;
        self.len += 1;
    }

    /// The newest sample (the ring's initial value before any push).
    pub(crate) fn newest(&self) -> f64 {
        self.buf[(self.len as usize).wrapping_sub(1) & (R - 1)]
    }

    /// [`DelayLine::value_at_interior_tap`], under the same conditions (`n` at least
    /// [`DelayLine::interior_from`] of the line this came from, and `len == n`), the same
    /// operations in the same order.
    #[inline(always)]
    pub(crate) fn value_at_interior_tap(&self, n: u64, tap: &Tap) -> f64 {
        debug_assert!(self.len == n && n > tap.back as u64);
        let base = (n - tap.back as u64) as usize;
        let at = |i: usize| self.buf[i & (R - 1)];
        let w = &tap.w;
        w[0] * at(base.wrapping_sub(1))
            + w[1] * at(base)
            + w[2] * at(base + 1)
            + w[3] * at(base + 2)
    }
}

/// The contents of a [`DelayLine`] ([`DelayLine::snapshot`]): everything but its step and
/// size, which the line is rebuilt with.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DelayLineState {
    /// Samples pushed so far.
    pub len: u64,
    /// The ring buffer as stored (its length is the line's size).
    pub ring: Vec<f64>,
}

impl DelayLine {
    /// The line's contents.
    pub fn snapshot(&self) -> DelayLineState {
        DelayLineState {
            len: self.len,
            ring: self.ring.clone(),
        }
    }

    /// Takes the contents of a line of the same step and size; refused for another size.
    pub fn restore(&mut self, state: &DelayLineState) -> Result<(), RestoreError> {
        if state.ring.len() != self.ring.len() {
            return Err(RestoreError::Mismatch {
                what: "delay line size",
                expected: self.ring.len(),
                found: state.ring.len(),
            });
        }
        self.len = state.len;
        self.ring.copy_from_slice(&state.ring);
        Ok(())
    }
}

/// A read of a [`DelayLine`] a fixed delay behind its grid: `value(n·h − delay)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tap {
    /// Grid steps from the read time back to the sample at or before it.
    back: i64,
    /// Fraction of a step from that sample [-], `0 ≤ f < 1`.
    f: f64,
    /// Cubic Lagrange weights of the samples at −1, 0, 1, 2 for `f`.
    w: [f64; 4],
}

impl Tap {
    /// Whether a read through this tap for the grid index `n + 1`, made while sample `n` is
    /// the newest, equals the same read after sample `n + 1` is pushed (bit for bit): true
    /// when the delay spans at least two steps, so that all four samples it reads are stored.
    pub fn is_settled(&self) -> bool {
        self.back >= 3
    }
}

/// Weights of the cubic Lagrange interpolant through the nodes −1, 0, 1, 2 at `f`.
#[inline(always)]
fn lagrange_weights(f: f64) -> [f64; 4] {
    let (fm1, fm2, fp1) = (f - 1.0, f - 2.0, f + 1.0);
    [
        -f * fm1 * fm2 / 6.0,
        fp1 * fm1 * fm2 / 2.0,
        -fp1 * f * fm2 / 2.0,
        fp1 * f * fm1 / 6.0,
    ]
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

    #[test]
    fn a_tap_reads_what_value_at_reads() {
        let h = 1e-3;
        let mut d = DelayLine::new(h, 0.05, 0.0);
        let g = |t: f64| (37.0 * t).sin() + 0.3 * t;
        for delay in [0.0, 5e-4, 1e-3, 2.3e-3, 1.75e-2, 0.049] {
            let tap = d.tap(delay);
            let mut d = d.clone();
            for n in 0..400u64 {
                d.push(g(n as f64 * h));
                for m in [n, n + 1] {
                    let t = m as f64 * h - delay;
                    let (a, b) = (d.value_at_tap(m, &tap), d.value_at(t));
                    assert!(
                        (a - b).abs() < 1e-12,
                        "delay {delay} n {n} m {m}: {a} vs {b}"
                    );
                }
            }
        }
        d.push(1.0);
        assert_eq!(d.value_at_tap(0, &d.tap(2e-3)), 0.0);
        // A settled tap reads the same before and after the next push; an unsettled one with
        // a fractional delay does not (the newest-edge read is linear).
        for (delay, settled) in [
            (1.2e-3, false),
            (1.5e-3, false),
            (2.1e-3, true),
            (1.75e-2, true),
        ] {
            let tap = d.tap(delay);
            assert_eq!(tap.is_settled(), settled, "delay {delay}");
            let mut d = DelayLine::new(h, 0.05, 0.0);
            let mut same = true;
            for n in 0..100u64 {
                d.push(g(n as f64 * h));
                let before = d.value_at_tap(n + 1, &tap);
                let mut e = d.clone();
                e.push(g((n + 1) as f64 * h));
                same &= before.to_bits() == e.value_at_tap(n + 1, &tap).to_bits();
            }
            assert_eq!(same, settled, "delay {delay}");
        }
    }
}
