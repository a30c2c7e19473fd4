//! The dynamics real axes have and the two-mass model (2.30) does not: the
//! plant file's optional `[unmodeled]` table. Every key is off at 0 (the
//! default, a plant as before); `beltune plant template` documents each with
//! a physical value to start from. The simulator applies them in
//! `sim/unmodeled.rs`.
//!
//! - the current loop as a second-order low-pass of bandwidth
//!   `current_loop_bandwidth_hz` and damping `current_loop_damping`, behind
//!   the transport delay `dead_time_s` (instead of the pure dead time);
//! - a second mechanical mode: a compliant frame (motor flange or machine
//!   base) of `frame_inertia_ratio` times the motor-side inertia, tuned to
//!   `frame_mode_hz`, rotating the stator against which the encoder
//!   measures;
//! - cogging (a torque periodic in the motor angle, independent of the load)
//!   and torque ripple (a fraction of the torque, periodic in the motor angle);
//! - encoder line errors once and twice per revolution;
//! - the belt's tooth-mesh excitation, a force periodic in belt travel with
//!   the tooth pitch.

use crate::{Error, Result};

/// The `[unmodeled]` table (units in the names; `Default`: all off).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Unmodeled {
    /// Bandwidth (natural frequency) of the closed current loop, Hz; 0: ideal
    /// (the dead time alone). Servo drives: 1-4 kHz.
    pub current_loop_bandwidth_hz: f64,
    /// Damping ratio of the current loop; 0: 1/sqrt(2).
    pub current_loop_damping: f64,
    /// Natural frequency of the frame mode, Hz; 0: a rigid frame. Seen at
    /// 2-6 times the belt resonance on real axes.
    pub frame_mode_hz: f64,
    /// Damping ratio of the frame mode; 0: 0.02 (steel structures, 1-3 %).
    pub frame_mode_damping: f64,
    /// Frame inertia about the motor axis as a multiple of the motor-side
    /// inertia `Theta_e` (dimensionless; needed when `frame_mode_hz > 0`).
    pub frame_inertia_ratio: f64,
    /// Cogging torque amplitude, N m (0: none). Typically 0.5-2 % of the
    /// rated torque.
    pub cogging_torque_nm: f64,
    /// Cogging periods per motor revolution (the lowest common multiple of
    /// slots and poles); 0: 24.
    pub cogging_per_rev: f64,
    /// Torque ripple amplitude as a fraction of the torque (0: none);
    /// typically 0.5-3 %.
    pub torque_ripple: f64,
    /// Ripple periods per motor revolution (6 per electrical period times the
    /// pole pairs); 0: 24.
    pub torque_ripple_per_rev: f64,
    /// Encoder line error once per revolution, amplitude, rad (0: none);
    /// eccentricity of the code disc, typically 1e-5 to 5e-4 rad.
    pub encoder_error_once_rad: f64,
    /// Encoder line error twice per revolution, amplitude, rad (0: none).
    pub encoder_error_twice_rad: f64,
    /// Tooth-mesh force amplitude on the belt, N (0: none); a few newtons on
    /// a loaded toothed belt.
    pub tooth_mesh_force_n: f64,
    /// Tooth pitch of the belt, m; 0: 5 mm (HTD 5M, the egc70's belt class).
    pub tooth_pitch_m: f64,
}

/// Default current-loop damping ratio (Butterworth).
pub const DEFAULT_CURRENT_LOOP_DAMPING: f64 = std::f64::consts::FRAC_1_SQRT_2;
/// Default frame-mode damping ratio.
pub const DEFAULT_FRAME_DAMPING: f64 = 0.02;
/// Default cogging and ripple periods per revolution.
pub const DEFAULT_PER_REV: f64 = 24.0;
/// Default tooth pitch, m.
pub const DEFAULT_TOOTH_PITCH_M: f64 = 5e-3;

impl Unmodeled {
    /// Whether every effect is off (the plant file leaves the table out).
    pub fn is_off(&self) -> bool {
        *self == Unmodeled::default()
    }

    /// The current-loop damping ratio in use.
    pub fn current_loop_zeta(&self) -> f64 {
        if self.current_loop_damping > 0.0 {
            self.current_loop_damping
        } else {
            DEFAULT_CURRENT_LOOP_DAMPING
        }
    }

    /// The frame-mode damping ratio in use.
    pub fn frame_zeta(&self) -> f64 {
        if self.frame_mode_damping > 0.0 {
            self.frame_mode_damping
        } else {
            DEFAULT_FRAME_DAMPING
        }
    }

    /// Cogging periods per revolution in use.
    pub fn cogging_periods(&self) -> f64 {
        if self.cogging_per_rev > 0.0 {
            self.cogging_per_rev
        } else {
            DEFAULT_PER_REV
        }
    }

    /// Ripple periods per revolution in use.
    pub fn ripple_periods(&self) -> f64 {
        if self.torque_ripple_per_rev > 0.0 {
            self.torque_ripple_per_rev
        } else {
            DEFAULT_PER_REV
        }
    }

    /// Tooth pitch in use, m.
    pub fn pitch_m(&self) -> f64 {
        if self.tooth_pitch_m > 0.0 {
            self.tooth_pitch_m
        } else {
            DEFAULT_TOOTH_PITCH_M
        }
    }

    /// Every key finite and non-negative; a frame mode needs its inertia;
    /// a current loop or frame mode below the sampling rate's reach is
    /// refused (the simulator discretizes exactly, but a mode above Nyquist
    /// cannot be seen and signals a unit error, e.g. rad/s for Hz).
    pub fn validate(&self, ts_s: f64) -> Result<()> {
        let keys = [
            ("current_loop_bandwidth_hz", self.current_loop_bandwidth_hz),
            ("current_loop_damping", self.current_loop_damping),
            ("frame_mode_hz", self.frame_mode_hz),
            ("frame_mode_damping", self.frame_mode_damping),
            ("frame_inertia_ratio", self.frame_inertia_ratio),
            ("cogging_torque_nm", self.cogging_torque_nm),
            ("cogging_per_rev", self.cogging_per_rev),
            ("torque_ripple", self.torque_ripple),
            ("torque_ripple_per_rev", self.torque_ripple_per_rev),
            ("encoder_error_once_rad", self.encoder_error_once_rad),
            ("encoder_error_twice_rad", self.encoder_error_twice_rad),
            ("tooth_mesh_force_n", self.tooth_mesh_force_n),
            ("tooth_pitch_m", self.tooth_pitch_m),
        ];
        for (name, v) in keys {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(
                    format!("unmodeled.{name}"),
                    v,
                    "must be finite and >= 0 (0: off)",
                ));
            }
        }
        let nyquist = 0.5 / ts_s;
        for (name, f) in [
            ("current_loop_bandwidth_hz", self.current_loop_bandwidth_hz),
            ("frame_mode_hz", self.frame_mode_hz),
        ] {
            if f >= nyquist {
                return Err(Error::invalid(
                    format!("unmodeled.{name}"),
                    f,
                    format!("at or above the Nyquist frequency {nyquist} Hz of the drive (Hz, not rad/s)"),
                ));
            }
        }
        if self.frame_mode_hz > 0.0 && self.frame_inertia_ratio <= 0.0 {
            return Err(Error::invalid(
                "unmodeled.frame_inertia_ratio",
                self.frame_inertia_ratio,
                "a frame mode needs the frame's inertia (> 0, a multiple of Theta_e)",
            ));
        }
        if self.current_loop_damping > 10.0 || self.frame_mode_damping > 10.0 {
            return Err(Error::invalid(
                "unmodeled damping",
                self.current_loop_damping.max(self.frame_mode_damping),
                "a damping ratio above 10 is not a mode",
            ));
        }
        if self.torque_ripple > 0.5 {
            return Err(Error::invalid(
                "unmodeled.torque_ripple",
                self.torque_ripple,
                "a ripple of more than 50 % of the torque is not a servo motor",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_off_and_valid() {
        let u = Unmodeled::default();
        assert!(u.is_off());
        u.validate(1e-4).unwrap();
        assert_eq!(u.current_loop_zeta(), DEFAULT_CURRENT_LOOP_DAMPING);
    }

    #[test]
    fn bad_keys_are_refused() {
        let bad = [
            Unmodeled {
                cogging_torque_nm: -1.0,
                ..Default::default()
            },
            Unmodeled {
                current_loop_bandwidth_hz: 6000.0,
                ..Default::default()
            },
            Unmodeled {
                frame_mode_hz: 300.0,
                ..Default::default()
            },
            Unmodeled {
                torque_ripple: f64::NAN,
                ..Default::default()
            },
        ];
        for u in bad {
            assert!(u.validate(1e-4).is_err(), "{u:?}");
        }
    }
}
