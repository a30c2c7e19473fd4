//! Physical (data-sheet) parameters of a toothed-belt axis, thesis 2.1,
//! the belt-segment geometry and stiffnesses (2.10), the replacement
//! stiffness (2.26) and damping (2.27), and the linearization to the
//! two-mass parameters of (2.33).
//!
//! Geometry (thesis 1.1, Figure 2.1): the driving pulley (motor side) and the
//! end pulley are `l_3` apart (centre to centre). The cart centre is `l_xi + xi`
//! from the driving pulley centre; the belt ends are clamped at the cart,
//! `cart_belt_span_m / 2` either side of its centre. Hence
//!
//! ```text
//! l_1(xi) = l_xi + xi - span/2            (driving pulley -> cart)
//! l_2(xi) = l_3 - l_xi - xi - span/2      (cart -> end pulley)
//! l_3                                     (return strand, end pulley -> driving pulley)
//! ```
//!
//! Segment stiffness (2.10) `c_i = c_b / (l_i + l_e)` and damping
//! `d_i = d_b / (l_i + l_e)`, where `c_b = E A` (N) is the data sheet's specific
//! stiffness and `l_e` the equivalent free-belt length of the compliance at the
//! segment's ends (tooth engagement at the pulley, clamp at the cart); the
//! thesis' (2.10) is the special case `l_e = 0`.
//!
//! Conventions (docs/thesis-map.md): viscous coefficients are translational
//! equivalents in N s/m (motor torque `i_t^2 d_m omega_m`), `i_t = r / i_g`.

use crate::error::{require_finite, require_non_negative, require_positive};
use crate::model::TwoMassParams;
use crate::{Error, Result};

/// Standard gravity, m/s^2.
pub const GRAVITY_M_S2: f64 = 9.80665;

/// Physical parameters of a belt axis: everything a data sheet, a drive
/// configuration and a friction measurement give. Plain data (serde, TOML).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhysicalParams {
    // ---- drive train (2.8) ----
    /// `Theta_m`: motor rotor inertia, kg m^2.
    pub theta_motor_kg_m2: f64,
    /// Coupling (connection kit) inertia, kg m^2; counts on the motor side.
    pub theta_coupling_kg_m2: f64,
    /// `Theta_g`: gearbox inertia (0 without gearbox), kg m^2.
    pub theta_gearbox_kg_m2: f64,
    /// `Theta_r`: inertia of the driving pulley, kg m^2.
    pub theta_driving_pulley_kg_m2: f64,
    /// Inertia of the end-side (driven) pulley, kg m^2 (the thesis assumes the same pulley).
    pub theta_end_pulley_kg_m2: f64,
    /// `r`: effective pulley radius, m.
    pub r_m: f64,
    /// `i_g = omega_m / omega_g`: gear ratio (1 without gearbox), dimensionless (2.1).
    pub i_g: f64,

    // ---- belt ----
    /// `c_b = E A`: specific belt stiffness, N (a free segment of length `l` has `c_b / l` N/m) (2.10).
    pub c_b_n: f64,
    /// Specific belt damping, N s (a free segment of length `l` has `d_b / l` N s/m).
    pub d_b_n_s: f64,
    /// `l_e`: equivalent free-belt length of the end compliance of every segment
    /// (tooth engagement, clamp), m; 0 reproduces (2.10) exactly.
    pub end_compliance_length_m: f64,

    // ---- geometry ----
    /// `l_3`: distance between the pulley centres, m.
    pub pulley_distance_m: f64,
    /// `l_xi`: distance driving pulley centre -> cart centre at `xi = 0`, m.
    pub l_xi_m: f64,
    /// Distance between the two belt clamping points on the cart, m.
    pub cart_belt_span_m: f64,
    /// Usable stroke, m: the cart position `xi` ranges over `[0, stroke_m]`.
    pub stroke_m: f64,

    // ---- masses ----
    /// Moving mass of the empty cart (slide, mounting parts), kg.
    pub m_cart_kg: f64,
    /// Payload mounted on the cart, kg.
    pub payload_kg: f64,

    // ---- friction (2.21), (2.23) ----
    /// `d_m`: motor-side viscous friction, translational equivalent, N s/m
    /// (torque `i_t^2 d_m omega_m`).
    pub d_m_n_s_per_m: f64,
    /// `tau_c`: motor-side Coulomb friction torque, N m (2.21).
    pub tau_c_motor_nm: f64,
    /// `d_c`: cart viscous friction, N s/m (2.23).
    pub d_c_n_s_per_m: f64,
    /// `f_c`: cart Coulomb friction force, N (2.23).
    pub f_c_cart_n: f64,
    /// End-pulley viscous friction, translational equivalent at the belt, N s/m
    /// (torque `r^2 d omega_2`).
    pub d_end_pulley_n_s_per_m: f64,
    /// End-pulley Coulomb friction torque, N m.
    pub tau_c_end_pulley_nm: f64,

    // ---- installation and drive ----
    /// `alpha`: tilt of the axis against the horizontal, rad; positive lifts the
    /// cart when `xi` increases (gravity force (2.22) `-m_c g sin(alpha)`).
    #[serde(default)]
    pub tilt_rad: f64,
    /// Current-loop dead time, s (3.30).
    pub dead_time_s: f64,
    /// Torque limit of the drive (saturation of the current setpoint), N m.
    #[serde(alias = "torque_limit_nm")]
    pub torque_max_nm: f64,
    /// Motor encoder resolution, rad per count.
    pub motor_rad_per_count: f64,
    /// Sampling time of the drive, s.
    #[serde(alias = "sample_time_s")]
    pub ts_s: f64,

    // ---- simulation ----
    /// Measurement noise of the simulated drive (`[noise]` table, optional).
    #[serde(default)]
    pub noise: MeasurementNoise,

    // ---- ageing ----
    /// What has aged (`[wear]` table, optional; [`super::wear`]): belt
    /// stiffness, friction, a slack span, a worn guide. The default is a
    /// new axis and is left out of a written plant.
    #[serde(default, skip_serializing_if = "super::wear::Wear::is_new")]
    pub wear: super::wear::Wear,

    // ---- unmodeled dynamics ----
    /// The dynamics real axes have beyond (2.30) (`[unmodeled]` table,
    /// optional; [`super::unmodeled`]): all off by default and left out of a
    /// written plant.
    #[serde(default, skip_serializing_if = "super::unmodeled::Unmodeled::is_off")]
    pub unmodeled: super::unmodeled::Unmodeled,
}

/// Measurement noise of a simulated drive, part of the plant (the `[noise]`
/// table of a plant file): seeded Gaussian noise on the measured actual
/// torque and on the motor encoder before quantization. The simulator's
/// seed picks the realization; all zero gives noise-free measurements (the
/// encoder then only quantizes).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeasurementNoise {
    /// Standard deviation of the noise on the measured actual torque, N m.
    pub torque_nm: f64,
    /// Standard deviation of the motor encoder's position noise before
    /// quantization, counts (interpolation noise of a sin/cos encoder; 0 for
    /// an ideal incremental encoder).
    pub encoder_counts: f64,
}

/// Largest measurement-noise standard deviations accepted: torque, N m.
pub const NOISE_TORQUE_MAX_NM: f64 = 10.0;
/// Largest encoder noise accepted, counts.
pub const NOISE_ENCODER_MAX_COUNTS: f64 = 1e3;

impl Default for MeasurementNoise {
    /// The built-in drives: 2 mN m of torque noise, an ideal encoder.
    fn default() -> Self {
        MeasurementNoise {
            torque_nm: 2e-3,
            encoder_counts: 0.0,
        }
    }
}

impl MeasurementNoise {
    /// No noise at all.
    pub const NONE: MeasurementNoise = MeasurementNoise {
        torque_nm: 0.0,
        encoder_counts: 0.0,
    };

    /// Typed error for a negative, non-finite or absurd level.
    pub fn validate(&self) -> crate::Result<()> {
        crate::error::require_range("noise.torque_nm", self.torque_nm, 0.0, NOISE_TORQUE_MAX_NM)?;
        crate::error::require_range(
            "noise.encoder_counts",
            self.encoder_counts,
            0.0,
            NOISE_ENCODER_MAX_COUNTS,
        )?;
        Ok(())
    }

    /// Both levels times `factor` (the study's noise factor).
    pub fn scaled(&self, factor: f64) -> Self {
        MeasurementNoise {
            torque_nm: self.torque_nm * factor,
            encoder_counts: self.encoder_counts * factor,
        }
    }
}

/// Lengths of the three free belt segments at one cart position, m.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SegmentLengths {
    /// `l_1(xi)`: driving pulley -> cart.
    pub l_1_m: f64,
    /// `l_2(xi)`: cart -> end pulley.
    pub l_2_m: f64,
    /// `l_3`: return strand between the pulleys.
    pub l_3_m: f64,
}

/// Stiffness and damping of the three belt segments at one cart position.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BeltSegments {
    /// `c_1(xi)`, N/m.
    pub c_1_n_per_m: f64,
    /// `c_2(xi)`, N/m.
    pub c_2_n_per_m: f64,
    /// `c_3`, N/m.
    pub c_3_n_per_m: f64,
    /// `d_1(xi)`, N s/m.
    pub d_1_n_s_per_m: f64,
    /// `d_2(xi)`, N s/m.
    pub d_2_n_s_per_m: f64,
    /// `d_3`, N s/m.
    pub d_3_n_s_per_m: f64,
}

impl BeltSegments {
    /// Replacement stiffness `c = c_1 + c_2 c_3 / (c_2 + c_3)` (2.26), N/m.
    pub fn replacement_stiffness_n_per_m(&self) -> f64 {
        let (c1, c2, c3) = (self.c_1_n_per_m, self.c_2_n_per_m, self.c_3_n_per_m);
        c1 + c2 * c3 / (c2 + c3)
    }

    /// Replacement damping `d = d_1 + d_2 d_3 / (d_2 + d_3)` (2.27), N s/m.
    pub fn replacement_damping_n_s_per_m(&self) -> f64 {
        let (d1, d2, d3) = (self.d_1_n_s_per_m, self.d_2_n_s_per_m, self.d_3_n_s_per_m);
        if d2 + d3 > 0.0 {
            d1 + d2 * d3 / (d2 + d3)
        } else {
            d1
        }
    }
}

/// The total friction seen at the motor when the belt is rigid (3.35)/(3.36):
/// `tau_R(omega_m) = d_v~ omega_m + tau_c~ sign(omega_m)`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrictionTotals {
    /// `d_v~ = i_t^2 (d_m + d_c) (+ end pulley)`, N m s/rad (docs/thesis-map.md: `d_m` translational).
    pub viscous_nm_s_per_rad: f64,
    /// `tau_c~ = tau_c + i_t f_c (+ end pulley / i_g)`, N m.
    pub coulomb_nm: f64,
}

impl PhysicalParams {
    /// `i_t = r / i_g` (2.16), m/rad.
    pub fn i_t(&self) -> f64 {
        self.r_m / self.i_g
    }

    /// `Theta_e = Theta_m + (Theta_r + Theta_g) / i_g^2` (2.8), with the coupling
    /// on the motor shaft, kg m^2.
    pub fn theta_e(&self) -> f64 {
        self.theta_motor_kg_m2
            + self.theta_coupling_kg_m2
            + (self.theta_driving_pulley_kg_m2 + self.theta_gearbox_kg_m2) / (self.i_g * self.i_g)
    }

    /// `m_c`: total moving mass (cart + payload), kg.
    pub fn m_c(&self) -> f64 {
        self.m_cart_kg + self.payload_kg
    }

    /// Gravity force on the cart (2.22) `f_g = -m_c g sin(alpha)`, N.
    pub fn gravity_force_n(&self) -> f64 {
        -self.m_c() * GRAVITY_M_S2 * self.tilt_rad.sin()
    }

    /// Segment lengths at cart position `xi_m` (see the module docs).
    pub fn segment_lengths(&self, xi_m: f64) -> SegmentLengths {
        let half = 0.5 * self.cart_belt_span_m;
        SegmentLengths {
            l_1_m: self.l_xi_m + xi_m - half,
            l_2_m: self.pulley_distance_m - self.l_xi_m - xi_m - half,
            l_3_m: self.pulley_distance_m,
        }
    }

    /// The specific belt stiffness the belt has now, N: `c_b` less the
    /// [`super::wear::Wear::belt_stiffness_loss`] (`c_b` on a new axis).
    pub fn c_b_effective_n(&self) -> f64 {
        self.c_b_n * self.wear.stiffness_factor()
    }

    /// The plant as the simulator runs it: the belt stiffness loss and the
    /// friction growth of [`Self::wear`] folded into `c_b` and the friction
    /// coefficients (and cleared from the wear); the slack span and the
    /// worn guide stay in the wear (they act on the state). A new axis is
    /// returned unchanged.
    pub fn aged(&self) -> PhysicalParams {
        if self.wear.belt_stiffness_loss == 0.0 && self.wear.friction_growth == 0.0 {
            return self.clone();
        }
        let k = self.wear.friction_factor();
        PhysicalParams {
            c_b_n: self.c_b_effective_n(),
            d_m_n_s_per_m: k * self.d_m_n_s_per_m,
            tau_c_motor_nm: k * self.tau_c_motor_nm,
            d_c_n_s_per_m: k * self.d_c_n_s_per_m,
            f_c_cart_n: k * self.f_c_cart_n,
            d_end_pulley_n_s_per_m: k * self.d_end_pulley_n_s_per_m,
            tau_c_end_pulley_nm: k * self.tau_c_end_pulley_nm,
            wear: super::wear::Wear {
                belt_stiffness_loss: 0.0,
                friction_growth: 0.0,
                ..self.wear
            },
            ..self.clone()
        }
    }

    /// Segment stiffness and damping at `xi_m` (2.10): `c_i = c_b / (l_i + l_e)`
    /// (`c_b` as aged, [`Self::c_b_effective_n`]).
    /// Positions outside the stroke are clamped to it (a real axis has end stops there).
    pub fn belt_segments(&self, xi_m: f64) -> BeltSegments {
        let l = self.segment_lengths(xi_m.clamp(0.0, self.stroke_m));
        let le = self.end_compliance_length_m;
        let (e1, e2, e3) = (l.l_1_m + le, l.l_2_m + le, l.l_3_m + le);
        let c_b = self.c_b_effective_n();
        BeltSegments {
            c_1_n_per_m: c_b / e1,
            c_2_n_per_m: c_b / e2,
            c_3_n_per_m: c_b / e3,
            d_1_n_s_per_m: self.d_b_n_s / e1,
            d_2_n_s_per_m: self.d_b_n_s / e2,
            d_3_n_s_per_m: self.d_b_n_s / e3,
        }
    }

    /// Replacement stiffness `c(xi)` (2.26), N/m.
    pub fn replacement_stiffness_n_per_m(&self, xi_m: f64) -> f64 {
        self.belt_segments(xi_m).replacement_stiffness_n_per_m()
    }

    /// The worst-case cart position (thesis 2.2): the lowest replacement
    /// stiffness (2.26), hence the lowest resonance and antiresonance, is at the
    /// end of the stroke farthest from the motor, where `l_1` is longest.
    /// `c(xi)` decreases monotonically in `xi` for `l_1 < l_2 + l_3`, so this is
    /// `xi = stroke`.
    pub fn worst_case_position_m(&self) -> f64 {
        self.stroke_m
    }

    /// Friction totals seen at the motor (3.36), with the end-pulley friction
    /// reflected through `i_g`, as aged ([`Self::aged`]; a worn guide counts
    /// where it covers the whole stroke: a worn section is position
    /// dependent and not in the totals).
    pub fn friction_totals(&self) -> FrictionTotals {
        if !self.wear.is_new() {
            let a = self.aged();
            let guide = if a.wear.guide_wear_section_m.is_none() {
                a.wear.guide_wear_n
            } else {
                0.0
            };
            let mut t = PhysicalParams {
                wear: super::wear::Wear::default(),
                ..a
            }
            .friction_totals();
            t.coulomb_nm += self.i_t() * guide;
            return t;
        }
        let it = self.i_t();
        FrictionTotals {
            viscous_nm_s_per_rad: it
                * it
                * (self.d_m_n_s_per_m + self.d_c_n_s_per_m + self.d_end_pulley_n_s_per_m),
            coulomb_nm: self.tau_c_motor_nm
                + it * self.f_c_cart_n
                + self.tau_c_end_pulley_nm / self.i_g,
        }
    }

    /// Linear two-mass parameters (2.33) at cart position `xi_m`: `c` from
    /// (2.26), `d` from (2.27), the viscous coefficients unchanged; the
    /// end-pulley inertia is neglected as in thesis 2.1.4, its viscous friction
    /// is added to the motor side (rigid belt between the pulleys).
    pub fn linearize(&self, xi_m: f64) -> Result<TwoMassParams> {
        self.validate()?;
        require_finite("xi [m]", xi_m)?;
        let aged = self.aged();
        let seg = aged.belt_segments(xi_m);
        let p = TwoMassParams {
            theta_e: self.theta_e(),
            m_c: self.m_c(),
            c: seg.replacement_stiffness_n_per_m(),
            d: seg.replacement_damping_n_s_per_m(),
            d_m: aged.d_m_n_s_per_m + aged.d_end_pulley_n_s_per_m,
            d_c: aged.d_c_n_s_per_m,
            i_t: self.i_t(),
        };
        p.validate()?;
        Ok(p)
    }

    /// Number of whole samples of the dead time, `round(T_d / T_s)`.
    pub fn dead_time_samples(&self) -> usize {
        (self.dead_time_s / self.ts_s).round() as usize
    }

    /// Typed error for anything non-physical: non-finite values, non-positive
    /// inertias/masses/lengths/stiffness, negative friction, an impossible
    /// geometry (a belt segment of zero or negative length anywhere on the
    /// stroke), a tilt beyond +-90 deg, a dead time that is not a
    /// non-negative number of samples below one second.
    pub fn validate(&self) -> Result<()> {
        use crate::error::require_range;
        use bounds::*;
        self.noise.validate()?;
        self.wear.validate(self.stroke_m)?;
        self.unmodeled.validate(self.ts_s)?;
        // Positivity first (the messages say "must be > 0"), then the
        // plausibility bounds: every quantity has an upper bound, so that no
        // derived frequency overflows and the simulator's sub-steps stay few.
        require_positive("theta_motor_kg_m2", self.theta_motor_kg_m2)?;
        require_non_negative("theta_coupling_kg_m2", self.theta_coupling_kg_m2)?;
        require_non_negative("theta_gearbox_kg_m2", self.theta_gearbox_kg_m2)?;
        require_positive(
            "theta_driving_pulley_kg_m2",
            self.theta_driving_pulley_kg_m2,
        )?;
        require_positive("theta_end_pulley_kg_m2", self.theta_end_pulley_kg_m2)?;
        require_positive("r_m", self.r_m)?;
        require_positive("i_g", self.i_g)?;
        require_positive("c_b_n", self.c_b_n)?;
        require_non_negative("d_b_n_s", self.d_b_n_s)?;
        require_non_negative("end_compliance_length_m", self.end_compliance_length_m)?;
        require_positive("pulley_distance_m", self.pulley_distance_m)?;
        require_positive("l_xi_m", self.l_xi_m)?;
        require_non_negative("cart_belt_span_m", self.cart_belt_span_m)?;
        require_positive("stroke_m", self.stroke_m)?;
        require_positive("m_cart_kg", self.m_cart_kg)?;
        require_non_negative("payload_kg", self.payload_kg)?;
        require_non_negative("d_m_n_s_per_m", self.d_m_n_s_per_m)?;
        require_non_negative("tau_c_motor_nm", self.tau_c_motor_nm)?;
        require_non_negative("d_c_n_s_per_m", self.d_c_n_s_per_m)?;
        require_non_negative("f_c_cart_n", self.f_c_cart_n)?;
        require_non_negative("d_end_pulley_n_s_per_m", self.d_end_pulley_n_s_per_m)?;
        require_non_negative("tau_c_end_pulley_nm", self.tau_c_end_pulley_nm)?;
        require_finite("tilt_rad", self.tilt_rad)?;
        for (name, x) in [
            ("theta_motor_kg_m2", self.theta_motor_kg_m2),
            (
                "theta_driving_pulley_kg_m2",
                self.theta_driving_pulley_kg_m2,
            ),
            ("theta_end_pulley_kg_m2", self.theta_end_pulley_kg_m2),
        ] {
            require_range(name, x, INERTIA_MIN_KG_M2, INERTIA_MAX_KG_M2)?;
        }
        for (name, x) in [
            ("theta_coupling_kg_m2", self.theta_coupling_kg_m2),
            ("theta_gearbox_kg_m2", self.theta_gearbox_kg_m2),
        ] {
            require_range(name, x, 0.0, INERTIA_MAX_KG_M2)?;
        }
        require_range("r_m", self.r_m, 1e-4, 1.0)?;
        require_range("i_g", self.i_g, 1e-2, 1e3)?;
        require_range("c_b_n", self.c_b_n, 1.0, 1e9)?;
        require_range("d_b_n_s", self.d_b_n_s, 0.0, 1e6)?;
        for (name, x) in [
            ("end_compliance_length_m", self.end_compliance_length_m),
            ("pulley_distance_m", self.pulley_distance_m),
            ("l_xi_m", self.l_xi_m),
            ("cart_belt_span_m", self.cart_belt_span_m),
            ("stroke_m", self.stroke_m),
        ] {
            require_range(name, x, 0.0, LENGTH_MAX_M)?;
        }
        require_range("m_cart_kg", self.m_cart_kg, MASS_MIN_KG, MASS_MAX_KG)?;
        require_range("payload_kg", self.payload_kg, 0.0, MASS_MAX_KG)?;
        for (name, x) in [
            ("d_m_n_s_per_m", self.d_m_n_s_per_m),
            ("d_c_n_s_per_m", self.d_c_n_s_per_m),
            ("d_end_pulley_n_s_per_m", self.d_end_pulley_n_s_per_m),
        ] {
            require_range(name, x, 0.0, DAMPING_MAX_N_S_PER_M)?;
        }
        for (name, x) in [
            ("tau_c_motor_nm", self.tau_c_motor_nm),
            ("tau_c_end_pulley_nm", self.tau_c_end_pulley_nm),
        ] {
            require_range(name, x, 0.0, TORQUE_MAX_NM)?;
        }
        require_range("f_c_cart_n", self.f_c_cart_n, 0.0, FORCE_MAX_N)?;
        if self.tilt_rad.abs() > std::f64::consts::FRAC_PI_2 {
            return Err(Error::invalid(
                "tilt_rad",
                self.tilt_rad,
                "tilt must be within +-pi/2 (+-90 deg)",
            ));
        }
        require_non_negative("dead_time_s", self.dead_time_s)?;
        require_positive("torque_max_nm", self.torque_max_nm)?;
        require_range("torque_max_nm", self.torque_max_nm, 0.0, TORQUE_MAX_NM)?;
        require_positive("motor_rad_per_count", self.motor_rad_per_count)?;
        require_range("motor_rad_per_count", self.motor_rad_per_count, 1e-9, 1.0)?;
        check_sample_time(self.ts_s)?;
        if self.dead_time_s > 1.0 {
            return Err(Error::invalid(
                "dead_time_s",
                self.dead_time_s,
                "a current-loop dead time above 1 s is not physical",
            ));
        }
        // the design's limit, known now: refused before anything simulates
        crate::lti::discrete::check_delay_samples(self.ts_s, self.dead_time_s)?;
        // Geometry: every belt segment must have positive length over the whole stroke.
        let start = self.segment_lengths(0.0);
        if start.l_1_m <= 0.0 {
            return Err(Error::invalid(
                "l_xi_m",
                self.l_xi_m,
                format!(
                    "at xi = 0 the cart's belt clamp would be {:.4} m behind the driving pulley centre \
                     (l_1 = l_xi - cart_belt_span/2 must be > 0)",
                    -start.l_1_m
                ),
            ));
        }
        let end = self.segment_lengths(self.stroke_m);
        if end.l_2_m <= 0.0 {
            return Err(Error::invalid(
                "stroke_m",
                self.stroke_m,
                format!(
                    "the stroke does not fit between the pulleys: l_2 at the end of the stroke would be {:.4} m \
                     (needs pulley_distance > l_xi + stroke + cart_belt_span/2)",
                    end.l_2_m
                ),
            ));
        }
        Ok(())
    }
}

/// Plausibility bounds of plant parameters, SI units. Generous (a factor of
/// 100 or more beyond any belt axis), but finite: with them every derived
/// quantity (frequencies, inertia ratio) is finite.
pub mod bounds {
    /// Smallest motor-side or pulley inertia, kg m^2.
    pub const INERTIA_MIN_KG_M2: f64 = 1e-12;
    /// Largest inertia, kg m^2.
    pub const INERTIA_MAX_KG_M2: f64 = 10.0;
    /// Smallest cart mass, kg.
    pub const MASS_MIN_KG: f64 = 1e-3;
    /// Largest cart mass or payload, kg.
    pub const MASS_MAX_KG: f64 = 1e4;
    /// Largest length (stroke, pulley distance), m.
    pub const LENGTH_MAX_M: f64 = 100.0;
    /// Largest viscous damping, N s/m.
    pub const DAMPING_MAX_N_S_PER_M: f64 = 1e6;
    /// Largest torque (friction, torque limit), N m.
    pub const TORQUE_MAX_NM: f64 = 1e4;
    /// Smallest torque limit of a drive, N m (a micro drive has about 1e-3).
    pub const TORQUE_LIMIT_MIN_NM: f64 = 1e-6;
    /// Largest force (cart friction), N.
    pub const FORCE_MAX_N: f64 = 1e6;
    /// Shortest sampling time, s.
    pub const SAMPLE_TIME_MIN_S: f64 = 1e-6;
    /// Longest sampling time, s.
    pub const SAMPLE_TIME_MAX_S: f64 = 0.1;
}

/// A drive's torque limit within [`bounds::TORQUE_LIMIT_MIN_NM`,
/// `bounds::TORQUE_MAX_NM`] (in the unit of the record: N m, or A for a
/// current record); `name` is how the caller's input spells it.
pub fn check_torque_limit(name: &str, torque_max: f64) -> Result<()> {
    crate::error::require_range(
        name,
        torque_max,
        bounds::TORQUE_LIMIT_MIN_NM,
        bounds::TORQUE_MAX_NM,
    )
    .map(|_| ())
}

/// A drive sampling time within [`bounds::SAMPLE_TIME_MIN_S`, `bounds::SAMPLE_TIME_MAX_S`].
pub fn check_sample_time(ts_s: f64) -> Result<()> {
    if ts_s.is_finite() && (bounds::SAMPLE_TIME_MIN_S..=bounds::SAMPLE_TIME_MAX_S).contains(&ts_s) {
        return Ok(());
    }
    Err(Error::invalid(
        "ts_s",
        ts_s,
        format!(
            "a drive sampling time must lie within [{} us, {} ms]",
            bounds::SAMPLE_TIME_MIN_S * 1e6,
            bounds::SAMPLE_TIME_MAX_S * 1e3
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs::egc70_params;

    /// (2.26) is the stiffness of `c_1` parallel to `c_2` in series with `c_3`;
    /// with `l_e = 0` and segments from (2.10) it is `c_b (1/l_1 + 1/(l_2 + l_3))`.
    #[test]
    fn replacement_stiffness_is_parallel_series_combination() {
        let p = PhysicalParams {
            end_compliance_length_m: 0.0,
            ..egc70_params(11.2)
        };
        for xi in [0.0, 0.2, 0.45, 0.6] {
            let l = p.segment_lengths(xi);
            let expected = p.c_b_n * (1.0 / l.l_1_m + 1.0 / (l.l_2_m + l.l_3_m));
            let got = p.replacement_stiffness_n_per_m(xi);
            assert!(
                (got - expected).abs() / expected < 1e-12,
                "{got} {expected}"
            );
        }
    }

    /// The cart centre moves with `xi`; `l_1 + l_2 + span = l_3` everywhere.
    #[test]
    fn segment_lengths_close_the_loop() {
        let p = egc70_params(0.0);
        for xi in [0.0, 0.1, 0.6] {
            let l = p.segment_lengths(xi);
            let sum = l.l_1_m + l.l_2_m + p.cart_belt_span_m;
            assert!((sum - l.l_3_m).abs() < 1e-12);
        }
    }

    /// (3.36) with the docs/thesis-map.md convention: `d_v~ = i_t^2 (d_m + d_c)`,
    /// `tau_c~ = tau_c + i_t f_c` (end pulley zero here).
    #[test]
    fn friction_totals_follow_3_36() {
        let p = PhysicalParams {
            d_m_n_s_per_m: 10.0,
            d_c_n_s_per_m: 30.0,
            tau_c_motor_nm: 0.05,
            f_c_cart_n: 4.0,
            d_end_pulley_n_s_per_m: 0.0,
            tau_c_end_pulley_nm: 0.0,
            ..egc70_params(0.0)
        };
        let it = p.i_t();
        let t = p.friction_totals();
        assert!((t.viscous_nm_s_per_rad - it * it * 40.0).abs() < 1e-15);
        assert!((t.coulomb_nm - (0.05 + it * 4.0)).abs() < 1e-15);
    }

    #[test]
    fn invalid_params_are_typed_errors() {
        let ok = egc70_params(11.2);
        assert!(ok.validate().is_ok());
        let cases: Vec<(&str, PhysicalParams)> = vec![
            (
                "m_cart_kg",
                PhysicalParams {
                    m_cart_kg: 0.0,
                    ..ok.clone()
                },
            ),
            (
                "payload_kg",
                PhysicalParams {
                    payload_kg: -1.0,
                    ..ok.clone()
                },
            ),
            (
                "c_b_n",
                PhysicalParams {
                    c_b_n: f64::NAN,
                    ..ok.clone()
                },
            ),
            (
                "r_m",
                PhysicalParams {
                    r_m: f64::INFINITY,
                    ..ok.clone()
                },
            ),
            (
                "tau_c_motor_nm",
                PhysicalParams {
                    tau_c_motor_nm: -0.1,
                    ..ok.clone()
                },
            ),
            (
                "stroke_m",
                PhysicalParams {
                    stroke_m: 2.0,
                    ..ok.clone()
                },
            ),
            (
                "l_xi_m",
                PhysicalParams {
                    l_xi_m: 0.01,
                    ..ok.clone()
                },
            ),
            (
                "tilt_rad",
                PhysicalParams {
                    tilt_rad: 2.0,
                    ..ok.clone()
                },
            ),
            (
                "ts_s",
                PhysicalParams {
                    ts_s: 0.0,
                    ..ok.clone()
                },
            ),
        ];
        for (field, bad) in cases {
            match bad.validate() {
                Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, field),
                other => panic!("{field}: expected InvalidParameter, got {other:?}"),
            }
            assert!(bad.linearize(0.3).is_err());
        }
        assert!(ok.linearize(f64::NAN).is_err());
    }
}
