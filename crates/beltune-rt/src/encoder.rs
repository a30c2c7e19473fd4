//! Quadrature encoder decoding with the debouncing state machine of thesis
//! Figure 6.3 (Section 6.1).
//!
//! The two channel levels `(A, B)` form a Gray code; with `A` leading `B` the
//! levels run `00 -> 10 -> 11 -> 01 -> 00` (positive direction). Each of the four
//! level combinations ("phase" 0..=3) exists as two states: reached while
//! moving positively (`S1`-`S4` for phases 0..=3) or negatively (`S8`-`S5` for
//! phases 0..=3, so that `S5 -> S6 -> S7 -> S8` is the negative cycle).
//!
//! Debouncing (thesis Section 6.1): a transition against the direction of the
//! current state produces **no** increment; the state becomes the
//! opposite-direction state of the new levels (e.g. `S3 -> S7` after `S2`).
//! If the next transition continues in the new direction (`S7 -> S8`), the
//! velocity has changed sign and an increment in the new direction is
//! produced: a reversal costs one transition. If it returns (`S7 -> S3`), it
//! was bouncing and the old direction is restored without an increment, so a
//! channel chattering between two adjacent states never counts.
//!
//! A transition that changes both channels at once (a skipped state, i.e. the
//! input was sampled too slowly) produces no increment, is counted in
//! [`QuadratureDecoder::invalid_transitions`] and keeps the direction.
//!
//! Time stamps are ticks of a fast free-running timer with tick period
//! `Delta t_min` (e.g. 10 ns on the thesis' FPGA), extended by the caller to a
//! monotonic `u64`. The decoder does not need the tick period; the velocity
//! estimators ([`crate::velocity`]) do.

/// Direction of an increment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Channel A leads channel B.
    Positive,
    /// Channel B leads channel A.
    Negative,
}

impl Direction {
    /// `+1` or `-1`.
    #[inline]
    pub fn sign(self) -> i32 {
        match self {
            Direction::Positive => 1,
            Direction::Negative => -1,
        }
    }

    /// The other direction.
    #[inline]
    pub fn reversed(self) -> Self {
        match self {
            Direction::Positive => Direction::Negative,
            Direction::Negative => Direction::Positive,
        }
    }
}

/// One counted encoder increment (one proper state transition).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Increment {
    /// Direction of motion.
    pub direction: Direction,
    /// Time stamp of the edge, timer ticks.
    pub ticks: u64,
}

/// The last run of increments of one direction inside one control sample:
/// what the event counter (6.4) needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeRun {
    /// Direction of every increment of the run.
    pub direction: Direction,
    /// Number of increments `n_inc >= 1` of the run.
    pub n_inc: u32,
    /// Time stamp of the first increment of the run, ticks.
    pub first_ticks: u64,
    /// Time stamp of the last increment of the run, ticks.
    pub last_ticks: u64,
}

/// Summary of one control sample, returned by [`QuadratureDecoder::take_window`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeWindow {
    /// Signed sum of all increments in the sample, counts.
    pub net_counts: i32,
    /// The last same-direction run of increments in the sample (`None`: no
    /// increment in this sample). A reversal inside the sample starts a new run.
    pub run: Option<EdgeRun>,
    /// The most recent increment, possibly from an earlier sample
    /// (`None` before the first increment).
    pub last_increment: Option<Increment>,
    /// Time between the two most recent increments, ticks, if both have the
    /// same direction (`T_inc` of the gate measurement (6.14)); possibly
    /// spanning several samples.
    pub gate_interval_ticks: Option<u64>,
    /// Position after the sample, counts since construction.
    pub position_counts: i64,
}

/// Channel levels `(A, B)` of Gray-code phase `position_counts mod 4`
/// (`00, 10, 11, 01`): what an ideal encoder outputs at that position.
/// Useful to drive the decoder from a simulated position.
#[inline]
pub fn quadrature_levels(position_counts: i64) -> (bool, bool) {
    match position_counts.rem_euclid(4) {
        0 => (false, false),
        1 => (true, false),
        2 => (true, true),
        _ => (false, true),
    }
}

#[inline]
fn phase_of(a: bool, b: bool) -> u8 {
    match (a, b) {
        (false, false) => 0,
        (true, false) => 1,
        (true, true) => 2,
        (false, true) => 3,
    }
}

/// Quadrature decoder with increment debouncing (Figure 6.3).
///
/// Feed it every change of the channel levels with its time stamp
/// ([`update`](Self::update); calls with unchanged levels are no-ops), and
/// once per control sample collect the [`EdgeWindow`] with
/// [`take_window`](Self::take_window).
///
/// Cost: `update` is a few comparisons and, on an increment, about ten integer
/// operations; `take_window` copies about 64 bytes. No floating point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QuadratureDecoder {
    phase: u8,
    direction: Direction,
    /// The current state was reached by a transition against the previous
    /// direction and is not yet confirmed.
    tentative: bool,
    position_counts: i64,
    invalid_transitions: u32,
    net_counts: i32,
    run: Option<EdgeRun>,
    last_increment: Option<Increment>,
    gate_interval_ticks: Option<u64>,
}

impl QuadratureDecoder {
    /// A decoder at the current channel levels, in the positive-direction
    /// state of these levels, at position 0. (A first move in the negative
    /// direction therefore costs one transition, like any reversal.)
    pub fn new(a: bool, b: bool) -> Self {
        QuadratureDecoder {
            phase: phase_of(a, b),
            direction: Direction::Positive,
            tentative: false,
            position_counts: 0,
            invalid_transitions: 0,
            net_counts: 0,
            run: None,
            last_increment: None,
            gate_interval_ticks: None,
        }
    }

    /// Process the channel levels `a`, `b` observed at time stamp `ticks`.
    /// Returns the increment if this was a proper state transition.
    pub fn update(&mut self, a: bool, b: bool, ticks: u64) -> Option<Increment> {
        let q = phase_of(a, b);
        let step = q.wrapping_sub(self.phase) & 3;
        let moved = match step {
            0 => return None,
            1 => Direction::Positive,
            3 => Direction::Negative,
            _ => {
                // both channels changed: a state was skipped
                self.invalid_transitions = self.invalid_transitions.saturating_add(1);
                self.phase = q;
                self.tentative = false;
                return None;
            }
        };
        self.phase = q;
        if moved == self.direction {
            self.tentative = false;
            let inc = Increment {
                direction: moved,
                ticks,
            };
            self.record(inc);
            Some(inc)
        } else {
            // Against the current direction: bouncing or the start of a
            // reversal. No increment; a second opposite transition in a row
            // means we are back in the old direction (bounce ended).
            self.direction = moved;
            self.tentative = !self.tentative;
            None
        }
    }

    fn record(&mut self, inc: Increment) {
        let s = inc.direction.sign();
        self.position_counts += i64::from(s);
        self.net_counts = self.net_counts.saturating_add(s);
        self.run = match self.run {
            Some(r) if r.direction == inc.direction => Some(EdgeRun {
                n_inc: r.n_inc.saturating_add(1),
                last_ticks: inc.ticks,
                ..r
            }),
            _ => Some(EdgeRun {
                direction: inc.direction,
                n_inc: 1,
                first_ticks: inc.ticks,
                last_ticks: inc.ticks,
            }),
        };
        self.gate_interval_ticks = match self.last_increment {
            Some(prev) if prev.direction == inc.direction => {
                Some(inc.ticks.saturating_sub(prev.ticks))
            }
            _ => None,
        };
        self.last_increment = Some(inc);
    }

    /// The summary of the control sample that just ended; starts a new one.
    pub fn take_window(&mut self) -> EdgeWindow {
        let w = EdgeWindow {
            net_counts: self.net_counts,
            run: self.run,
            last_increment: self.last_increment,
            gate_interval_ticks: self.gate_interval_ticks,
            position_counts: self.position_counts,
        };
        self.net_counts = 0;
        self.run = None;
        w
    }

    /// Position, counts since construction (debounced).
    pub fn position_counts(&self) -> i64 {
        self.position_counts
    }

    /// Number of transitions that changed both channels at once.
    pub fn invalid_transitions(&self) -> u32 {
        self.invalid_transitions
    }

    /// Direction of the current state.
    pub fn direction(&self) -> Direction {
        self.direction
    }

    /// The state of Figure 6.3, 1..=8: `S1`-`S4` are phases 0..=3 reached in the
    /// positive direction, `S5`-`S8` phases 3..=0 reached in the negative
    /// direction.
    pub fn state(&self) -> u8 {
        match self.direction {
            Direction::Positive => self.phase + 1,
            Direction::Negative => 8 - self.phase,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// Drive the decoder through `n` transitions in direction `sign` from
    /// position `pos`, one tick apart; returns the new position and the number
    /// of increments produced (signed).
    fn walk(d: &mut QuadratureDecoder, pos: &mut i64, sign: i64, n: u32, t: &mut u64) -> i64 {
        let mut counted = 0;
        for _ in 0..n {
            *pos += sign;
            *t += 1;
            let (a, b) = quadrature_levels(*pos);
            if let Some(inc) = d.update(a, b, *t) {
                counted += i64::from(inc.direction.sign());
            }
        }
        counted
    }

    #[test]
    fn thesis_example_states_s2_s3_s7() {
        // phases 1 -> 2 positive are S2 -> S3; going back to phase 1 is S7.
        let (a, b) = quadrature_levels(1);
        let mut d = QuadratureDecoder::new(a, b);
        assert_eq!(d.state(), 2);
        let (a, b) = quadrature_levels(2);
        assert!(d.update(a, b, 1).is_some());
        assert_eq!(d.state(), 3);
        let (a, b) = quadrature_levels(1);
        assert!(d.update(a, b, 2).is_none(), "S3 -> S7 gives no increment");
        assert_eq!(d.state(), 7);
        let (a, b) = quadrature_levels(2);
        assert!(d.update(a, b, 3).is_none(), "S7 -> S3 is a bounce");
        assert_eq!(d.state(), 3);
        let (a, b) = quadrature_levels(1);
        assert!(d.update(a, b, 4).is_none());
        assert_eq!(d.state(), 7);
        let (a, b) = quadrature_levels(0);
        let inc = d.update(a, b, 5).expect("S7 -> S8 is a reversal");
        assert_eq!(inc.direction, Direction::Negative);
        assert_eq!(d.state(), 8);
    }

    #[test]
    fn bouncing_between_adjacent_states_produces_no_increments() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        for start_dir in [1i64, -1] {
            let mut d = QuadratureDecoder::new(false, false);
            let mut pos = 0i64;
            let mut t = 0u64;
            walk(&mut d, &mut pos, start_dir, 7, &mut t);
            let before = d.position_counts();
            // a channel chatters: back and forth one state, random number of times
            for _ in 0..200 {
                let n = rng.random_range(1..20u32);
                for _ in 0..n {
                    assert_eq!(walk(&mut d, &mut pos, -start_dir, 1, &mut t), 0);
                    assert_eq!(walk(&mut d, &mut pos, start_dir, 1, &mut t), 0);
                }
                assert_eq!(d.position_counts(), before);
            }
            // and then the motion continues in the old direction with full counts
            assert_eq!(walk(&mut d, &mut pos, start_dir, 5, &mut t), 5 * start_dir);
            assert_eq!(d.invalid_transitions(), 0);
        }
    }

    #[test]
    fn a_reversal_costs_exactly_one_transition() {
        let mut d = QuadratureDecoder::new(false, false);
        let mut pos = 0i64;
        let mut t = 0u64;
        assert_eq!(walk(&mut d, &mut pos, 1, 10, &mut t), 10);
        assert_eq!(walk(&mut d, &mut pos, -1, 1, &mut t), 0);
        assert_eq!(walk(&mut d, &mut pos, -1, 9, &mut t), -9);
        assert_eq!(d.direction(), Direction::Negative);
        // back again: again one transition lost, so the count returns to
        // the true position while moving positively
        assert_eq!(walk(&mut d, &mut pos, 1, 4, &mut t), 3);
        assert_eq!(d.position_counts(), pos);
        // an initial negative move also costs one transition (start state S_i positive)
        let mut d = QuadratureDecoder::new(false, false);
        let mut pos = 0i64;
        assert_eq!(walk(&mut d, &mut pos, -1, 6, &mut t), -5);
    }

    #[test]
    fn constant_speed_stream_gives_the_right_count_and_windows() {
        // 10 kHz control, 10 ns timer, edges every `period` ns with random phase.
        const TICKS_PER_SAMPLE: u64 = 10_000;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        for _ in 0..20 {
            let period_ticks: f64 = rng.random_range(300.0..60_000.0);
            let offset: f64 = rng.random_range(0.0..period_ticks);
            let mut d = QuadratureDecoder::new(false, false);
            let mut edge = 0i64;
            let mut total = 0i64;
            let samples = 500u64;
            let x = TICKS_PER_SAMPLE as f64 / period_ticks;
            for k in 1..=samples {
                let end = k * TICKS_PER_SAMPLE;
                loop {
                    let te = offset + (edge as f64) * period_ticks;
                    let ticks = libm::floor(te) as u64;
                    if ticks >= end {
                        break;
                    }
                    edge += 1;
                    let (a, b) = quadrature_levels(edge);
                    assert!(d.update(a, b, ticks).is_some());
                }
                let w = d.take_window();
                total += i64::from(w.net_counts);
                let n = w.run.map_or(0, |r| r.n_inc) as f64;
                assert!(n >= libm::floor(x) && n <= libm::ceil(x), "{n} vs {x}");
                assert_eq!(w.net_counts as f64, n);
                if let Some(g) = w.gate_interval_ticks {
                    assert!((g as f64 - period_ticks).abs() < 1.0 + 1e-9);
                }
            }
            assert_eq!(total, edge);
            assert_eq!(d.position_counts(), edge);
        }
    }

    /// Every edge of a constant-speed stream chatters (new, old, new levels
    /// within a few ticks, random number of bounces): the count and the
    /// increment time stamps are those of the clean stream.
    #[test]
    fn chattering_edges_count_once_with_the_first_edge_time() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(63);
        for sign in [1i64, -1] {
            let mut d = QuadratureDecoder::new(false, false);
            let mut pos = 0i64;
            let mut t = 0u64;
            // settle the direction first (a reversal from the start state costs one)
            walk(&mut d, &mut pos, sign, 1, &mut t);
            let start = d.position_counts();
            for j in 0..2000 {
                t += 1000;
                let edge_t = t;
                let old = quadrature_levels(pos);
                pos += sign;
                let new = quadrature_levels(pos);
                let inc = d.update(new.0, new.1, edge_t).expect("first edge counts");
                assert_eq!((i64::from(inc.direction.sign()), inc.ticks), (sign, edge_t));
                for _ in 0..rng.random_range(0..4u32) {
                    t += 1;
                    assert!(d.update(old.0, old.1, t).is_none(), "bounce back, edge {j}");
                    t += 1;
                    assert!(
                        d.update(new.0, new.1, t).is_none(),
                        "bounce forth, edge {j}"
                    );
                }
            }
            assert_eq!(d.position_counts() - start, 2000 * sign);
            let w = d.take_window();
            assert_eq!(w.gate_interval_ticks.map(|g| g >= 1000), Some(true));
        }
    }

    #[test]
    fn skipped_states_are_counted_as_invalid_and_produce_no_increment() {
        let mut d = QuadratureDecoder::new(false, false);
        assert!(d.update(true, true, 1).is_none());
        assert_eq!(d.invalid_transitions(), 1);
        assert_eq!(d.position_counts(), 0);
        // continuing from the new levels counts normally
        let (a, b) = quadrature_levels(3);
        assert!(d.update(a, b, 2).is_some());
        assert_eq!(d.position_counts(), 1);
    }

    #[test]
    fn window_run_restarts_at_a_reversal_and_gate_interval_needs_same_direction() {
        let mut d = QuadratureDecoder::new(false, false);
        let mut pos = 0i64;
        let mut t = 0u64;
        walk(&mut d, &mut pos, 1, 5, &mut t);
        walk(&mut d, &mut pos, -1, 3, &mut t); // 1 lost, 2 counted
        let w = d.take_window();
        assert_eq!(w.net_counts, 3);
        let r = w.run.unwrap();
        assert_eq!((r.direction, r.n_inc), (Direction::Negative, 2));
        assert_eq!((r.first_ticks, r.last_ticks), (7, 8));
        assert_eq!(w.gate_interval_ticks, Some(1));
        let w2 = d.take_window();
        assert_eq!(w2.net_counts, 0);
        assert!(w2.run.is_none());
        assert_eq!(w2.last_increment, w.last_increment);
        // first increment after a reversal has no gate interval
        walk(&mut d, &mut pos, 1, 2, &mut t);
        assert_eq!(d.take_window().gate_interval_ticks, None);
    }
}
