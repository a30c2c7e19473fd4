//! Test helper: synthetic quadrature edge streams through the decoder.

use super::EncoderResolution;
use crate::encoder::{quadrature_levels, EdgeWindow, QuadratureDecoder};

/// Edges at constant speed `speed` (u/s), the first at `offset_ticks`
/// (real-valued, ticks), optionally no edges at or after `stop_ticks`.
/// Edge time stamps are quantized down to whole ticks, like a free-running
/// timer latching the edge.
pub struct ConstantSpeedStream {
    pub decoder: QuadratureDecoder,
    ticks_per_edge: f64,
    offset_ticks: f64,
    stop_ticks: f64,
    sign: i64,
    pos: i64,
    edges: u64,
    ticks_per_sample: u64,
    sample: u64,
}

impl ConstantSpeedStream {
    pub fn new(r: &EncoderResolution, speed: f64, offset_ticks: f64, stop_ticks: f64) -> Self {
        let (a, b) = quadrature_levels(0);
        ConstantSpeedStream {
            decoder: QuadratureDecoder::new(a, b),
            ticks_per_edge: r.increment / speed.abs() / r.tick_s,
            offset_ticks,
            stop_ticks,
            sign: if speed >= 0.0 { 1 } else { -1 },
            pos: 0,
            edges: 0,
            ticks_per_sample: r.ticks_per_sample(),
            sample: 0,
        }
    }

    /// Advance one control sample: returns its window and its end time stamp.
    pub fn next_sample(&mut self) -> (EdgeWindow, u64) {
        self.sample += 1;
        let end = self.sample * self.ticks_per_sample;
        loop {
            let t = self.offset_ticks + self.edges as f64 * self.ticks_per_edge;
            if t >= self.stop_ticks || libm::floor(t) as u64 >= end {
                break;
            }
            self.edges += 1;
            self.pos += self.sign;
            let (a, b) = quadrature_levels(self.pos);
            self.decoder.update(a, b, libm::floor(t) as u64);
        }
        (self.decoder.take_window(), end)
    }
}
