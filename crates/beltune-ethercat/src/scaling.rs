//! Units of a CiA 402 drive and SI: torque in per mille of the rated torque
//! (0x6076, mN m), the torque limit 0x6072 (per mille), encoder increments per
//! motor revolution (0x608F), a load encoder's resolution, and the wrapping
//! 32-bit positions (0x6064, 0x60E4) unwrapped into 64-bit counts.

use crate::Error;
use std::f64::consts::PI;

/// Motor rated torque, mN m (u32).
pub const RATED_TORQUE: u16 = 0x6076;
/// Max torque, per mille of the rated torque (u16).
pub const MAX_TORQUE: u16 = 0x6072;
/// Position encoder resolution: sub 1 encoder increments, sub 2 motor revolutions (u32 each).
pub const ENCODER_RESOLUTION: u16 = 0x608F;
/// Interpolation time period: sub 1 value (u8), sub 2 index (i8, power of ten seconds).
pub const INTERPOLATION_TIME: u16 = 0x60C2;
/// Manufacturer object of the virtual drive: resolution of the load-side
/// (cart) encoder behind 0x60E4:01, nm per increment (u32).
pub const LOAD_ENCODER_RESOLUTION: u16 = 0x2110;

/// Scaling of one drive, read from its objects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaling {
    /// Rated torque (0x6076), N m.
    pub rated_torque_nm: f64,
    /// Torque limit (0x6072), per mille of the rated torque.
    pub max_torque_permille: u16,
    /// Encoder increments per `motor_revolutions` (0x608F:01).
    pub encoder_increments: u32,
    /// Motor revolutions for `encoder_increments` (0x608F:02).
    pub motor_revolutions: u32,
    /// Load-side encoder resolution, m per increment (when the drive has one).
    pub load_m_per_inc: Option<f64>,
}

impl Scaling {
    /// From the raw object values; typed errors for zero or absurd values.
    pub fn from_objects(
        rated_torque_mnm: u32,
        max_torque_permille: u16,
        encoder_increments: u32,
        motor_revolutions: u32,
        load_nm_per_inc: Option<u32>,
    ) -> Result<Self, Error> {
        let bad = |object: &'static str, value: u64, reason: &'static str| {
            Err(Error::BadObject {
                object,
                value,
                reason,
            })
        };
        if rated_torque_mnm == 0 {
            return bad("rated torque 0x6076 [mN m]", 0, "must be positive");
        }
        if max_torque_permille == 0 || max_torque_permille > i16::MAX as u16 {
            return bad(
                "max torque 0x6072 [per mille]",
                u64::from(max_torque_permille),
                "must be in 1..=32767",
            );
        }
        if encoder_increments == 0 || motor_revolutions == 0 {
            return bad(
                "encoder resolution 0x608F",
                u64::from(encoder_increments.min(motor_revolutions)),
                "increments and revolutions must be positive",
            );
        }
        if load_nm_per_inc == Some(0) {
            return bad(
                "load encoder resolution 0x2110 [nm/inc]",
                0,
                "must be positive",
            );
        }
        Ok(Scaling {
            rated_torque_nm: f64::from(rated_torque_mnm) * 1e-3,
            max_torque_permille,
            encoder_increments,
            motor_revolutions,
            load_m_per_inc: load_nm_per_inc.map(|n| f64::from(n) * 1e-9),
        })
    }

    /// Torque limit, N m.
    pub fn torque_limit_nm(&self) -> f64 {
        self.permille_to_nm(self.max_torque_permille as i16)
    }

    /// Motor angle per increment, rad.
    pub fn motor_rad_per_inc(&self) -> f64 {
        2.0 * PI * f64::from(self.motor_revolutions) / f64::from(self.encoder_increments)
    }

    /// A torque in N m as the target-torque value: rounded to the nearest per
    /// mille and saturated at the torque limit. Non-finite torque gives 0 (the
    /// drive must never see a garbage command; the caller reports it).
    pub fn nm_to_permille(&self, torque_nm: f64) -> i16 {
        if !torque_nm.is_finite() {
            return 0;
        }
        let lim = f64::from(self.max_torque_permille);
        (torque_nm / self.rated_torque_nm * 1e3)
            .round()
            .clamp(-lim, lim) as i16
    }

    /// A per-mille torque value in N m.
    pub fn permille_to_nm(&self, permille: i16) -> f64 {
        f64::from(permille) * 1e-3 * self.rated_torque_nm
    }
}

/// Unwraps a wrapping 32-bit position into a 64-bit count relative to the
/// first value seen: consecutive values may differ by less than 2^31
/// increments (at 1 kHz and 2^20 increments per revolution that is 2 million
/// revolutions per second).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unwrap32 {
    last: Option<i32>,
    count: i64,
}

impl Unwrap32 {
    /// An unwrapper that counts from the first value it is given.
    pub fn new() -> Self {
        Self::default()
    }

    /// The next raw value; returns the unwrapped count (0 for the first).
    pub fn update(&mut self, raw: i32) -> i64 {
        if let Some(last) = self.last {
            self.count += i64::from(raw.wrapping_sub(last));
        }
        self.last = Some(raw);
        self.count
    }

    /// The last unwrapped count.
    pub fn count(&self) -> i64 {
        self.count
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn scaling() -> Scaling {
        // 1.55 N m rated, 200 % limit, 31200 increments per revolution (EGC-70: 78 mm / 2.5 um)
        Scaling::from_objects(1550, 2000, 31_200, 1, Some(1000)).unwrap()
    }

    #[test]
    fn torque_units_are_per_mille_of_the_rated_torque() {
        let s = scaling();
        assert_eq!(s.nm_to_permille(1.55), 1000);
        assert_eq!(s.nm_to_permille(-0.00155), -1);
        assert_eq!(s.nm_to_permille(0.000_774), 0); // below half a per mille
        assert_eq!(s.nm_to_permille(0.000_776), 1);
        assert!((s.permille_to_nm(-250) + 0.3875).abs() < 1e-12);
        assert!((s.torque_limit_nm() - 3.1).abs() < 1e-12);
        // saturation at the limit, never an overflow
        assert_eq!(s.nm_to_permille(100.0), 2000);
        assert_eq!(s.nm_to_permille(-1e300), -2000);
        assert_eq!(s.nm_to_permille(f64::NAN), 0);
        assert_eq!(s.nm_to_permille(f64::INFINITY), 0);
    }

    #[test]
    fn encoder_resolution_gives_the_motor_angle() {
        let s = scaling();
        assert!((s.motor_rad_per_inc() * 31_200.0 - 2.0 * PI).abs() < 1e-12);
        // 4096 increments per 2 revolutions (a gearbox-side encoder)
        let g = Scaling::from_objects(1000, 1000, 4096, 2, None).unwrap();
        assert!((g.motor_rad_per_inc() - 4.0 * PI / 4096.0).abs() < 1e-15);
        assert_eq!(g.load_m_per_inc, None);
        assert!((s.load_m_per_inc.unwrap() - 1e-6).abs() < 1e-18);
    }

    #[test]
    fn absurd_objects_are_typed_errors() {
        assert!(Scaling::from_objects(0, 1000, 1, 1, None).is_err());
        assert!(Scaling::from_objects(1, 0, 1, 1, None).is_err());
        assert!(Scaling::from_objects(1, 40_000, 1, 1, None).is_err());
        assert!(Scaling::from_objects(1, 1000, 0, 1, None).is_err());
        assert!(Scaling::from_objects(1, 1000, 1, 0, None).is_err());
        assert!(Scaling::from_objects(1, 1000, 1, 1, Some(0)).is_err());
    }

    #[test]
    fn the_position_unwraps_across_the_32_bit_wrap_in_both_directions() {
        let mut u = Unwrap32::new();
        assert_eq!(u.update(i32::MAX - 1), 0);
        assert_eq!(u.update(i32::MAX), 1);
        assert_eq!(u.update(i32::MIN), 2); // wrapped forwards
        assert_eq!(u.update(i32::MIN + 5), 7);
        assert_eq!(u.update(i32::MAX - 3), -2); // and back across the wrap
        let mut d = Unwrap32::new();
        d.update(i32::MIN + 2);
        assert_eq!(d.update(i32::MAX), -3);
    }

    proptest! {
        #[test]
        fn unwrapping_recovers_any_64_bit_walk(start in any::<i64>(), steps in proptest::collection::vec(-1_000_000i64..1_000_000, 1..200)) {
            let start = start / 4; // stay far from the i64 ends
            let mut u = Unwrap32::new();
            let mut pos = start;
            u.update(pos as i32);
            for s in steps {
                pos += s;
                prop_assert_eq!(u.update(pos as i32), pos - start);
            }
        }
    }
}
