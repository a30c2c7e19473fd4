//! P-PI <-> PID gain conversion (Appendix B).
//!
//! With the ideal velocity filter `G_R = s` (B.3), the cascaded P-PI controller
//!
//! ```text
//! omega_ref = K_PP e_phi + K_v omega_d,  tau = (K_P + K_I/s)(omega_ref - omega) + K_a alpha_d
//! ```
//!
//! and the PID controller
//!
//! ```text
//! tau = (K_P + K_I/s + K_D s) e_phi + K_v omega_d + K_a alpha_d
//! ```
//!
//! have the same complementary sensitivity, (B.4) equal to (B.5), if (B.6) holds:
//!
//! ```text
//! K_D^PID = K_P^PPI                       (B.6e)
//! K_P^PID = K_I^PPI + K_P^PPI K_PP^PPI    (B.6c), (B.6f)
//! K_I^PID = K_I^PPI K_PP^PPI              (B.6d), (B.6g)
//! K_v^PID = 0                             (B.8)
//! K_a^PID = K_a^PPI                       (B.6a), unchanged, not part of these structs
//! ```
//!
//! which is possible only for `K_v^PPI = 1` (B.7).
//!
//! The inverse is not unique: `K_I^PPI` and `K_P^PPI K_PP^PPI` are the two roots
//! of `x^2 - K_P^PID x + K_D^PID K_I^PID = 0`, so a [`PositionGainRoot`] selects
//! which of the two is the position-loop term. Real roots need
//! `(K_P^PID)^2 >= 4 K_D^PID K_I^PID`; otherwise the PID has no cascade equivalent.

use super::cascade::CascadeGains;
use crate::error::Error;

/// PID gains on the position error `e_phi = phi_d - phi_m` (rad), torque in N m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidGains {
    /// `K_P^PID` in N m/rad.
    pub k_p_nm_per_rad: f64,
    /// `K_I^PID` in N m/(rad s).
    pub k_i_nm_per_rad_s: f64,
    /// `K_D^PID` in N m s/rad.
    pub k_d_nm_s_per_rad: f64,
    /// Velocity feedforward `K_v^PID` in N m s/rad (0 by (B.8)).
    pub k_v_nm_s_per_rad: f64,
}

/// Which root of the inverse conversion carries the position loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PositionGainRoot {
    /// `K_P^PPI K_PP^PPI <= K_I^PPI`: the smaller `K_PP` (position loop slower
    /// than the PI corner `K_I/K_P`; the thesis designs, Tables A.6/A.7, are of
    /// this kind).
    Slow,
    /// `K_P^PPI K_PP^PPI >= K_I^PPI`: the larger `K_PP`.
    Fast,
}

/// Relative tolerance for `K_v^PPI = 1` and `K_v^PID = 0` (rounding only).
pub const K_V_TOLERANCE: f64 = 1e-9;

fn check(name: &'static str, v: f64) -> Result<f64, Error> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(Error::InvalidParameter {
            name,
            reason: "must be finite and >= 0",
        })
    }
}

/// P-PI -> PID by (B.6). Requires `K_v^PPI = 1` (B.7) and non-negative finite gains.
pub fn ppi_to_pid(ppi: &CascadeGains<f64>) -> Result<PidGains, Error> {
    ppi.validate()?;
    if (ppi.k_v - 1.0).abs() > K_V_TOLERANCE {
        return Err(Error::InvalidParameter {
            name: "k_v",
            reason: "a PID equivalent exists only for K_v = 1 (B.7)",
        });
    }
    Ok(PidGains {
        k_p_nm_per_rad: ppi.k_i_nm_per_rad + ppi.k_p_nm_s_per_rad * ppi.k_pp_per_s,
        k_i_nm_per_rad_s: ppi.k_i_nm_per_rad * ppi.k_pp_per_s,
        k_d_nm_s_per_rad: ppi.k_p_nm_s_per_rad,
        k_v_nm_s_per_rad: 0.0,
    })
}

/// PID -> P-PI by inverting (B.6), with `K_v^PPI = 1`. Requires `K_v^PID = 0`
/// (B.8), `K_D^PID > 0` and real roots (`(K_P^PID)^2 >= 4 K_D^PID K_I^PID`).
pub fn pid_to_ppi(pid: &PidGains, root: PositionGainRoot) -> Result<CascadeGains<f64>, Error> {
    let kp = check("k_p_nm_per_rad", pid.k_p_nm_per_rad)?;
    let ki = check("k_i_nm_per_rad_s", pid.k_i_nm_per_rad_s)?;
    let kd = check("k_d_nm_s_per_rad", pid.k_d_nm_s_per_rad)?;
    if !(pid.k_v_nm_s_per_rad.is_finite()
        && pid.k_v_nm_s_per_rad.abs() <= K_V_TOLERANCE * kd.max(1.0))
    {
        return Err(Error::InvalidParameter {
            name: "k_v_nm_s_per_rad",
            reason: "a P-PI equivalent exists only for K_v^PID = 0 (B.8)",
        });
    }
    if kd <= 0.0 {
        return Err(Error::InvalidParameter {
            name: "k_d_nm_s_per_rad",
            reason: "must be > 0: K_P^PPI = K_D^PID (B.6e)",
        });
    }
    let disc = kp * kp - 4.0 * kd * ki;
    if disc < -1e-12 * kp * kp {
        return Err(Error::Infeasible {
            reason: "K_P^2 < 4 K_D K_I: the PID has no real cascaded P-PI equivalent",
        });
    }
    let sq = libm::sqrt(disc.max(0.0));
    // Roots x1 <= x2 of x^2 - kp x + kd ki = 0, computed without cancellation.
    let x2 = 0.5 * (kp + sq);
    let x1 = if x2 > 0.0 { kd * ki / x2 } else { 0.0 };
    // x_pos = K_P^PPI K_PP^PPI, the other root is K_I^PPI.
    let (x_pos, k_i) = match root {
        PositionGainRoot::Slow => (x1, x2),
        PositionGainRoot::Fast => (x2, x1),
    };
    Ok(CascadeGains {
        k_pp_per_s: x_pos / kd,
        k_p_nm_s_per_rad: kd,
        k_i_nm_per_rad: k_i,
        k_v: 1.0,
    })
}

/// Which root a P-PI design corresponds to (for a round trip).
pub fn position_gain_root(ppi: &CascadeGains<f64>) -> PositionGainRoot {
    if ppi.k_p_nm_s_per_rad * ppi.k_pp_per_s <= ppi.k_i_nm_per_rad {
        PositionGainRoot::Slow
    } else {
        PositionGainRoot::Fast
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64 as C;
    use rand::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// (B.5): complementary sensitivity of the P-PI cascade with feedforward, as printed.
    fn t_ppi_b5(g: &CascadeGains<f64>, k_a: f64, plant: C, s: C) -> C {
        let (kpp, kp, ki, kv) = (g.k_pp_per_s, g.k_p_nm_s_per_rad, g.k_i_nm_per_rad, g.k_v);
        let num = k_a * s * s * s + kv * kp * s * s + (kv * ki + kp * kpp) * s + ki * kpp;
        let den = kp * s * s + (ki + kp * kpp + 1.0 / plant) * s + ki * kpp;
        num / den
    }

    /// (B.4): complementary sensitivity of the PID with feedforward, as printed.
    fn t_pid_b4(p: &PidGains, k_a: f64, plant: C, s: C) -> C {
        let num = k_a * s * s * s
            + (p.k_v_nm_s_per_rad + p.k_d_nm_s_per_rad) * s * s
            + p.k_p_nm_per_rad * s
            + p.k_i_nm_per_rad_s;
        let den =
            p.k_d_nm_s_per_rad * s * s + (1.0 / plant + p.k_p_nm_per_rad) * s + p.k_i_nm_per_rad_s;
        num / den
    }

    /// Independent of (B.5): solve the block diagram of Figure B.1(b) at `s`:
    /// phi = G tau, tau = (K_P + K_I/s)(K_PP (phi_d - phi) + K_v s phi_d - s phi) + K_a s^2 phi_d.
    /// Linear in phi with phi_d = 1: phi (1 + G C (K_PP + s)) = G (C (K_PP + K_v s) + K_a s^2).
    fn t_ppi_block(g: &CascadeGains<f64>, k_a: f64, plant: C, s: C) -> C {
        let c = g.k_p_nm_s_per_rad + g.k_i_nm_per_rad / s;
        plant * (c * (g.k_pp_per_s + g.k_v * s) + k_a * s * s)
            / (1.0 + plant * c * (g.k_pp_per_s + s))
    }

    fn random_ppi(rng: &mut Xoshiro256PlusPlus) -> CascadeGains<f64> {
        // log-uniform over the range a belt drive spans (Tables A.6/A.7 lie inside)
        let lu = |rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64| {
            libm::exp(libm::log(lo) + rng.random::<f64>() * (libm::log(hi) - libm::log(lo)))
        };
        CascadeGains::new(lu(rng, 0.1, 1e3), lu(rng, 1e-3, 10.0), lu(rng, 1e-2, 1e3))
    }

    /// Relative tolerance of the round trip: a few ulps amplified by the
    /// quadratic's conditioning `(x1 + x2)/|x1 - x2|`, which the sweep keeps below 1e4.
    const ROUND_TRIP_REL_TOL: f64 = 1e-8;

    #[test]
    fn ppi_to_pid_to_ppi_is_the_identity() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0xB6);
        let mut n = 0;
        while n < 10_000 {
            let g = random_ppi(&mut rng);
            let (x_pos, x_i) = (g.k_p_nm_s_per_rad * g.k_pp_per_s, g.k_i_nm_per_rad);
            if (x_pos + x_i) / (x_pos - x_i).abs() > 1e4 {
                continue; // nearly double root: the inverse is ill-conditioned by nature
            }
            n += 1;
            let pid = ppi_to_pid(&g).unwrap();
            let back = pid_to_ppi(&pid, position_gain_root(&g)).unwrap();
            for (a, b) in [
                (g.k_pp_per_s, back.k_pp_per_s),
                (g.k_p_nm_s_per_rad, back.k_p_nm_s_per_rad),
                (g.k_i_nm_per_rad, back.k_i_nm_per_rad),
                (g.k_v, back.k_v),
            ] {
                assert!(
                    (a - b).abs() <= ROUND_TRIP_REL_TOL * a.abs(),
                    "{g:?} -> {back:?}"
                );
            }
        }
    }

    #[test]
    fn conversion_matches_b4_equals_b5_and_the_block_diagram() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
        // rigid plant of Table A.4 size: G = 1/(m_e s^2), m_e = 2.14e-3 kg m^2, plus a dead time
        let m_e = 2.14e-3;
        for _ in 0..200 {
            let g = random_ppi(&mut rng);
            let k_a = m_e * rng.random::<f64>();
            let pid = ppi_to_pid(&g).unwrap();
            for s in [
                C::new(0.0, 3.0),
                C::new(-5.0, 40.0),
                C::new(2.0, 700.0),
                C::new(0.0, 5000.0),
            ] {
                let plant = (-s * 1e-3).exp() / (m_e * s * s);
                let a = t_ppi_b5(&g, k_a, plant, s);
                let b = t_pid_b4(&pid, k_a, plant, s);
                let c = t_ppi_block(&g, k_a, plant, s);
                const REL_TOL: f64 = 1e-9;
                assert!(
                    (a - b).norm() <= REL_TOL * a.norm().max(1e-12),
                    "{a} vs {b}"
                );
                assert!(
                    (a - c).norm() <= REL_TOL * a.norm().max(1e-12),
                    "{a} vs {c}"
                );
            }
            // both inverse roots describe the same PID, hence the same loop
            if let (Ok(slow), Ok(fast)) = (
                pid_to_ppi(&pid, PositionGainRoot::Slow),
                pid_to_ppi(&pid, PositionGainRoot::Fast),
            ) {
                let s = C::new(-1.0, 123.0);
                let plant = 1.0 / (m_e * s * s);
                let a = t_ppi_block(&slow, k_a, plant, s);
                let b = t_ppi_block(&fast, k_a, plant, s);
                assert!((a - b).norm() <= 1e-6 * a.norm());
            }
        }
    }

    #[test]
    fn thesis_table_a6_gains_convert() {
        // Table A.6: K_I 1.69, K_P 0.08, K_PP 10.91 (K_P K_PP = 0.87 < K_I: slow root)
        let g = CascadeGains::new(10.91, 0.08, 1.69);
        let pid = ppi_to_pid(&g).unwrap();
        assert!((pid.k_p_nm_per_rad - (1.69 + 0.08 * 10.91)).abs() < 1e-12);
        assert!((pid.k_i_nm_per_rad_s - 1.69 * 10.91).abs() < 1e-12);
        assert_eq!(pid.k_d_nm_s_per_rad, 0.08);
        assert_eq!(position_gain_root(&g), PositionGainRoot::Slow);
    }

    #[test]
    fn conditions_b7_b8_and_complex_roots_are_errors() {
        let mut g = CascadeGains::new(10.0, 0.1, 1.0);
        g.k_v = 0.5;
        assert!(ppi_to_pid(&g).is_err());
        let pid = PidGains {
            k_p_nm_per_rad: 1.0,
            k_i_nm_per_rad_s: 10.0,
            k_d_nm_s_per_rad: 0.1,
            k_v_nm_s_per_rad: 0.0,
        };
        assert!(matches!(
            pid_to_ppi(&pid, PositionGainRoot::Slow),
            Err(Error::Infeasible { .. })
        ));
        let pid = PidGains {
            k_v_nm_s_per_rad: 0.2,
            k_p_nm_per_rad: 10.0,
            ..pid
        };
        assert!(pid_to_ppi(&pid, PositionGainRoot::Slow).is_err());
    }
}
