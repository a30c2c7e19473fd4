//! Built-in plants: the thesis' test rig `egc70` (Festo EGC-70-600-TB axis with
//! EMMS-AS-70 motor, built from the data sheets of Appendix A) and the linear
//! simulation sets `sim-a`, `sim-b`, `sim-c` (Tables A.11-A.13), plus plants
//! loaded from TOML. [`Plant`] is what the simulator and the CLI accept.

use crate::axis::AxisInfo;
use crate::model::params::{FrictionTotals, PhysicalParams};
use crate::model::TwoMassParams;
use crate::{Error, Result};
use std::f64::consts::PI;
use std::path::Path;

/// Names of the built-in plants.
pub const BUILTIN_NAMES: &[&str] = &["egc70", "sim-a", "sim-b", "sim-c"];

/// Default payload of `egc70`, kg (the thesis' plant `G_A`, Table A.4).
pub const EGC70_DEFAULT_PAYLOAD_KG: f64 = 11.2;

/// Drive-side data shared by the built-ins (docs/thesis-map.md): `T_s = 100 us`,
/// dead time 1 ms (3.30).
const SAMPLE_TIME_S: f64 = 100e-6;
const DEAD_TIME_S: f64 = 1e-3;
/// Encoder: the data sheets give no resolution; the thesis' (6.15) works with
/// 2.5 um of belt travel per count (= 31,200 counts per revolution at 78 mm/rev).
/// Assumption, documented in [`egc70_params`].
const BELT_TRAVEL_PER_COUNT_M: f64 = 2.5e-6;
/// Feed constant of the EGC-70-TB, 78 mm/rev (Table A.2); `r = 78 mm / (2 pi)`
/// (docs/thesis-map.md: Table A.2 prints 12.42 mm).
const FEED_CONSTANT_M_PER_REV: f64 = 0.078;

/// A plant the simulator can run and the CLI can show.
// A plant is built once per run and never held in bulk: the size of the
// physical variant (with its `[unmodeled]` table) costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Plant {
    /// A physical axis: simulated with the nonlinear three-mass model (2.20).
    Physical(PhysicalParams),
    /// A linear two-mass set (2.33), without Coulomb friction.
    Linear(LinearPlant),
}

/// A linear two-mass plant (2.33) with the drive data a simulation needs.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearPlant {
    /// The two-mass parameters.
    pub two_mass: TwoMassParams,
    /// Current-loop dead time, s.
    pub dead_time_s: f64,
    /// Torque limit, N m.
    #[serde(alias = "torque_limit_nm")]
    pub torque_max_nm: f64,
    /// Motor encoder resolution, rad per count.
    pub motor_rad_per_count: f64,
    /// Sampling time, s.
    #[serde(alias = "sample_time_s")]
    pub ts_s: f64,
    /// Measurement noise of the simulated drive (`[noise]` table, optional).
    #[serde(default)]
    pub noise: super::params::MeasurementNoise,
}

impl LinearPlant {
    /// Typed error for non-physical values.
    pub fn validate(&self) -> Result<()> {
        self.two_mass.validate()?;
        self.noise.validate()?;
        crate::error::require_non_negative("dead_time_s", self.dead_time_s)?;
        crate::error::require_positive("torque_max_nm", self.torque_max_nm)?;
        crate::error::require_positive("motor_rad_per_count", self.motor_rad_per_count)?;
        crate::error::require_range(
            "torque_max_nm",
            self.torque_max_nm,
            0.0,
            super::params::bounds::TORQUE_MAX_NM,
        )?;
        crate::error::require_range("motor_rad_per_count", self.motor_rad_per_count, 1e-9, 1.0)?;
        super::params::check_sample_time(self.ts_s)?;
        if self.dead_time_s > 1.0 {
            return Err(Error::invalid("dead_time_s", self.dead_time_s, "above 1 s"));
        }
        Ok(())
    }
}

impl Plant {
    /// Typed error for non-physical values.
    pub fn validate(&self) -> Result<()> {
        match self {
            Plant::Physical(p) => p.validate(),
            Plant::Linear(l) => l.validate(),
        }
    }

    /// Linear two-mass parameters at cart position `xi_m` (a linear set is
    /// position independent).
    pub fn linearize(&self, xi_m: f64) -> Result<TwoMassParams> {
        match self {
            Plant::Physical(p) => p.linearize(xi_m),
            Plant::Linear(l) => {
                l.validate()?;
                Ok(l.two_mass)
            }
        }
    }

    /// The two-mass parameters of the simulator's own physics at cart
    /// position `xi_m`: for a physical plant the equivalent of the
    /// three-mass model with its end pulley
    /// ([`super::equivalent::equivalent_two_mass`]), which [`Self::linearize`]
    /// (thesis 2.1.4) neglects; a linear set as it is.
    pub fn true_two_mass(&self, xi_m: f64) -> Result<TwoMassParams> {
        match self {
            Plant::Physical(p) => super::equivalent::equivalent_two_mass(p, xi_m),
            Plant::Linear(_) => self.linearize(xi_m),
        }
    }

    /// The worst-case (lowest-resonance) cart position, m (0 for a linear set).
    pub fn worst_case_position_m(&self) -> f64 {
        match self {
            Plant::Physical(p) => p.worst_case_position_m(),
            Plant::Linear(_) => 0.0,
        }
    }

    /// Linearization at the worst-case position: the model the design uses.
    pub fn worst_case_two_mass(&self) -> Result<TwoMassParams> {
        self.linearize(self.worst_case_position_m())
    }

    /// Friction totals seen at the motor (3.36); a linear set has viscous
    /// friction only, `i_t^2 (d_m + d_c)`.
    pub fn friction_totals(&self) -> FrictionTotals {
        match self {
            Plant::Physical(p) => p.friction_totals(),
            Plant::Linear(l) => FrictionTotals {
                viscous_nm_s_per_rad: l.two_mass.rigid_damping(),
                coulomb_nm: 0.0,
            },
        }
    }

    /// Current-loop dead time, s.
    pub fn dead_time_s(&self) -> f64 {
        match self {
            Plant::Physical(p) => p.dead_time_s,
            Plant::Linear(l) => l.dead_time_s,
        }
    }

    /// What the drive knows about the axis.
    pub fn info(&self) -> AxisInfo {
        match self {
            Plant::Physical(p) => AxisInfo {
                ts_s: p.ts_s,
                motor_rad_per_count: p.motor_rad_per_count,
                torque_max_nm: p.torque_max_nm,
            },
            Plant::Linear(l) => AxisInfo {
                ts_s: l.ts_s,
                motor_rad_per_count: l.motor_rad_per_count,
                torque_max_nm: l.torque_max_nm,
            },
        }
    }

    /// Measurement noise of the simulated drive.
    pub fn noise(&self) -> super::params::MeasurementNoise {
        match self {
            Plant::Physical(p) => p.noise,
            Plant::Linear(l) => l.noise,
        }
    }

    /// Usable stroke, m, if the plant has one (a linear set has none).
    pub fn stroke_m(&self) -> Option<f64> {
        match self {
            Plant::Physical(p) => Some(p.stroke_m),
            Plant::Linear(_) => None,
        }
    }
}

/// Derived quantities of a plant at its worst-case position, for display
/// (`beltune plant show`). Field names carry their units.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PlantSummary {
    /// `physical` or `linear`.
    pub kind: String,
    /// Resonance `f_r` (2.44) at the worst-case position, Hz.
    pub f_r_hz: f64,
    /// Antiresonance `f_z` (2.45) at the worst-case position, Hz.
    pub f_z_hz: f64,
    /// `Theta_e`, kg m^2.
    pub theta_e_kg_m2: f64,
    /// `m_c`, kg.
    pub m_c_kg: f64,
    /// Replacement stiffness `c` (2.26) at the worst-case position, N/m.
    pub c_n_per_m: f64,
    /// Replacement belt damping `d` (2.27), N s/m.
    pub d_n_s_per_m: f64,
    /// Motor viscous damping (translational equivalent), N s/m.
    pub d_m_n_s_per_m: f64,
    /// Cart viscous damping, N s/m.
    pub d_c_n_s_per_m: f64,
    /// `i_t = r / i_g`, m/rad.
    pub i_t_m: f64,
    /// Inertia ratio `kappa` (2.46).
    pub kappa: f64,
    /// Resonance ratio `R = f_r / f_z` (2.47).
    pub resonance_ratio: f64,
    /// Rigid-body inertia `Theta_e + i_t^2 m_c`, kg m^2.
    pub rigid_inertia_kg_m2: f64,
    /// Worst-case cart position, m.
    pub worst_case_position_m: f64,
    /// Friction totals (3.36) seen at the motor.
    pub friction: FrictionTotals,
    /// Current-loop dead time, s.
    pub dead_time_s: f64,
    /// Torque limit, N m.
    pub torque_max_nm: f64,
    /// Encoder resolution, rad per count.
    pub motor_rad_per_count: f64,
    /// Belt travel per encoder count, m.
    pub belt_travel_per_count_m: f64,
    /// Sampling time, s.
    pub ts_s: f64,
    /// Usable stroke, m (physical plants).
    pub stroke_m: Option<f64>,
    /// `f_r`, `f_z` and `c` over the stroke (physical plants; thesis Figure 2.9).
    pub position_sweep: Vec<PositionPoint>,
    /// The physical parameters (physical plants).
    pub physical: Option<PhysicalParams>,
}

/// The linearized model at one cart position.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PositionPoint {
    /// Cart position `xi`, m.
    pub xi_m: f64,
    /// Resonance, Hz.
    pub f_r_hz: f64,
    /// Antiresonance, Hz.
    pub f_z_hz: f64,
    /// Replacement stiffness (2.26), N/m.
    pub c_n_per_m: f64,
}

impl Plant {
    /// The derived quantities (worst case, friction, drive data, position sweep).
    pub fn summary(&self) -> Result<PlantSummary> {
        let wc = self.worst_case_two_mass()?;
        let info = self.info();
        let (kind, position_sweep, physical) = match self {
            Plant::Physical(p) => {
                let sweep = (0..=6)
                    .map(|k| {
                        let xi = p.stroke_m * k as f64 / 6.0;
                        p.linearize(xi).map(|t| PositionPoint {
                            xi_m: xi,
                            f_r_hz: t.f_r_hz(),
                            f_z_hz: t.f_z_hz(),
                            c_n_per_m: t.c,
                        })
                    })
                    .collect::<Result<Vec<_>>>()?;
                ("physical", sweep, Some(p.clone()))
            }
            Plant::Linear(_) => ("linear", Vec::new(), None),
        };
        Ok(PlantSummary {
            kind: kind.to_string(),
            f_r_hz: wc.f_r_hz(),
            f_z_hz: wc.f_z_hz(),
            theta_e_kg_m2: wc.theta_e,
            m_c_kg: wc.m_c,
            c_n_per_m: wc.c,
            d_n_s_per_m: wc.d,
            d_m_n_s_per_m: wc.d_m,
            d_c_n_s_per_m: wc.d_c,
            i_t_m: wc.i_t,
            kappa: wc.inertia_ratio(),
            resonance_ratio: wc.resonance_ratio(),
            rigid_inertia_kg_m2: wc.rigid_inertia(),
            worst_case_position_m: self.worst_case_position_m(),
            friction: self.friction_totals(),
            dead_time_s: self.dead_time_s(),
            torque_max_nm: info.torque_max_nm,
            motor_rad_per_count: info.motor_rad_per_count,
            belt_travel_per_count_m: info.motor_rad_per_count * wc.i_t,
            ts_s: info.ts_s,
            stroke_m: self.stroke_m(),
            position_sweep,
            physical,
        })
    }

    /// A physical plant with another payload; an error for a linear set.
    pub fn with_payload(&self, payload_kg: f64) -> Result<Plant> {
        match self {
            Plant::Physical(p) => {
                let q = PhysicalParams {
                    payload_kg,
                    ..p.clone()
                };
                q.validate()?;
                Ok(Plant::Physical(q))
            }
            Plant::Linear(_) => Err(Error::invalid(
                "payload_kg",
                payload_kg,
                "a linear simulation set has a fixed moving mass; a payload applies to physical plants only",
            )),
        }
    }
}

/// The built-in plant `name` (one of [`BUILTIN_NAMES`]). `payload_kg` applies
/// to `egc70` only (`None`: 11.2 kg); the linear sets are fixed and reject it.
pub fn builtin(name: &str, payload_kg: Option<f64>) -> Result<Plant> {
    let fixed = |two_mass: TwoMassParams| -> Result<Plant> {
        if let Some(p) = payload_kg {
            return Err(Error::invalid(
                "payload_kg",
                p,
                format!("`{name}` is a fixed linear simulation set; a payload applies to physical plants only"),
            ));
        }
        Ok(Plant::Linear(linear_set(two_mass)))
    };
    match name {
        "egc70" => {
            let payload = payload_kg.unwrap_or(EGC70_DEFAULT_PAYLOAD_KG);
            let p = egc70_params(payload);
            p.validate()?;
            Ok(Plant::Physical(p))
        }
        "sim-a" => fixed(sim_a()),
        "sim-b" => fixed(sim_b()),
        "sim-c" => fixed(sim_c()),
        _ => Err(Error::UnknownPlant {
            name: name.to_string(),
            known: BUILTIN_NAMES.join(", "),
        }),
    }
}

/// Load a plant from a TOML file: `kind = "physical"` with the fields of
/// [`PhysicalParams`], or `kind = "linear"` with those of [`LinearPlant`]
/// (`[two_mass]` table). Errors name the file and the field.
pub fn load_toml(path: &Path) -> Result<Plant> {
    let file = path.display().to_string();
    // `Error::Parse` rather than `Error::Io`: the CLI prints the cause chain,
    // and `Io` would repeat its source.
    let text = crate::io::read_to_string_capped(path, crate::io::MAX_TEXT_BYTES)?;
    let plant: Plant = toml::from_str(&text).map_err(|e| Error::Parse {
        path: file.clone(),
        message: e.message().to_string()
            + &e.span()
                .map(|s| {
                    let line = text[..s.start.min(text.len())].matches('\n').count() + 1;
                    format!(" (line {line})")
                })
                .unwrap_or_default(),
    })?;
    plant.validate().map_err(|e| Error::Parse {
        path: file,
        message: e.to_string(),
    })?;
    Ok(plant)
}

/// The Festo EGC-70-600-TB-KF-0H-GK axis with EMMS-AS-70-S-LS-RMB motor and
/// EAMM-A-L38-70A coupling (thesis 1.1, Appendix A) with `payload_kg` on the cart.
///
/// Sources of every number:
/// - `Theta_m = 0.45 kg cm^2` (Table A.1, printed "kg/cm^2"; docs/thesis-map.md).
/// - pulley inertia `23.63 kg mm^2` (Table A.2, printed "kg/mm^2"), the same for
///   both pulleys (thesis 2.1).
/// - coupling `3.10 kg mm^2`: Table A.3 lost its numbers; docs/thesis-map.md: the
///   identified `Theta_e = 71.73 kg mm^2` (Table A.4) minus 45 and 23.63.
/// - `r = 78 mm / (2 pi)` from the feed constant (Table A.2; docs/thesis-map.md), `i_g = 1`.
/// - `c_b = 106,250 N` (Table A.2, a specific stiffness, docs/thesis-map.md).
/// - belt damping `d_b = c_b * 1e-4 s`: no data sheet value; Tables A.11-A.13 use
///   `d = 20 N s/m` at `c = 200 kN/m`, i.e. `d / c = 1e-4 s`.
/// - stroke 0.6 m (Table A.2).
/// - geometry (pulley distance 0.84 m, `l_xi = 0.12 m`, belt clamps 0.15 m apart):
///   **assumed**; the thesis gives no drawing. Chosen so that the cart travels
///   the 0.6 m stroke with 0.045 m of free belt left at either end.
/// - end compliance `l_e = 0.20 m`: **calibrated**. (2.26) with the data-sheet
///   `c_b` and the geometry above gives 285 kN/m at the worst case, 28-40 %
///   above the identified 204-222 kN/m (Tables A.4/A.5): the data-sheet value
///   ignores the tooth engagement at the pulleys and the clamps. An equivalent
///   0.2 m of free belt per segment end brings the worst case to 208 kN/m.
/// - empty cart `0.96 kg`: the identified moving mass without payload (Table A.5);
///   the data sheet's "moving load 0.37 kg" (Table A.2) is the bare slide, the
///   rig carries mounting parts on it. With 11.2 kg this gives 12.16 kg
///   (Table A.4 identified 13.44 kg).
/// - friction: Table A.10 gives only the totals seen at the motor,
///   `d_v~ = 2.230 / 2.530 mN m s/rad` and `tau_c~ = 0.115 / 0.125 N m` for
///   0 / 11.2 kg. Split (assumption): of the no-load totals, 40 % on the motor
///   (bearings, shaft seal), 10 % on the end pulley, 50 % on the cart (guide);
///   the payload-dependent part (the difference G_A - G_B, linear in the payload)
///   on the cart. The totals at 0 and 11.2 kg reproduce Table A.10 exactly.
/// - dead time 1 ms (3.30), `T_s = 100 us` (docs/thesis-map.md).
/// - encoder: not in the data sheets; 2.5 um of belt travel per count, the
///   thesis' (6.15) value (31,200 counts/rev). Assumption.
/// - torque limit 3.1 N m: the motor's maximum torque (Table A.1) is what the
///   drive enforces. The axis' "max. driving torque 1.24 N m" (Table A.2, the
///   100 N feed force rating) is a mechanical rating, not a drive limit: the
///   thesis' own 0 -> 500 mm move with 11.2 kg (Table A.8, chapter 5) needs about
///   1.7 N m peak, so the rig ran above it.
pub fn egc70_params(payload_kg: f64) -> PhysicalParams {
    let r = FEED_CONSTANT_M_PER_REV / (2.0 * PI);
    let it2 = r * r; // i_g = 1
                     // Table A.10 totals: G_B (0 kg) and G_A (11.2 kg).
    let (dv0, dv_a) = (2.230e-3, 2.530e-3); // N m s/rad
    let (tc0, tc_a) = (0.115, 0.125); // N m
    let dv_per_kg = (dv_a - dv0) / EGC70_DEFAULT_PAYLOAD_KG;
    let tc_per_kg = (tc_a - tc0) / EGC70_DEFAULT_PAYLOAD_KG;
    let (motor_share, end_share, cart_share) = (0.4, 0.1, 0.5);
    let c_b = 106_250.0;
    PhysicalParams {
        theta_motor_kg_m2: 45e-6,
        theta_coupling_kg_m2: 3.10e-6,
        theta_gearbox_kg_m2: 0.0,
        theta_driving_pulley_kg_m2: 23.63e-6,
        theta_end_pulley_kg_m2: 23.63e-6,
        r_m: r,
        i_g: 1.0,
        c_b_n: c_b,
        d_b_n_s: c_b * 1e-4,
        end_compliance_length_m: 0.20,
        pulley_distance_m: 0.84,
        l_xi_m: 0.12,
        cart_belt_span_m: 0.15,
        stroke_m: 0.6,
        m_cart_kg: 0.96,
        payload_kg,
        d_m_n_s_per_m: motor_share * dv0 / it2,
        tau_c_motor_nm: motor_share * tc0,
        d_c_n_s_per_m: (cart_share * dv0 + dv_per_kg * payload_kg) / it2,
        f_c_cart_n: (cart_share * tc0 + tc_per_kg * payload_kg) / r,
        d_end_pulley_n_s_per_m: end_share * dv0 / it2,
        tau_c_end_pulley_nm: end_share * tc0,
        tilt_rad: 0.0,
        dead_time_s: DEAD_TIME_S,
        torque_max_nm: 3.1,
        motor_rad_per_count: BELT_TRAVEL_PER_COUNT_M / r,
        ts_s: SAMPLE_TIME_S,
        noise: super::params::MeasurementNoise::default(),
        wear: super::wear::Wear::default(),
        unmodeled: super::unmodeled::Unmodeled::default(),
    }
}

/// `i_t` of the simulation sets, m/rad. Tables A.11-A.13 do not print it. With
/// the EGC-70's `78 mm / (2 pi) = 12.4141 mm` (2.44) gives f_r = 133.771 /
/// 149.847 / 423.022 Hz, below the printed (truncated) 133.78 / 149.85 / 423.05;
/// `i_t = 12.415 mm` reproduces all three to the printed precision, so the
/// tables were computed with this rounded radius.
fn sim_i_t() -> f64 {
    12.415e-3
}

fn linear_set(two_mass: TwoMassParams) -> LinearPlant {
    LinearPlant {
        two_mass,
        dead_time_s: DEAD_TIME_S,
        torque_max_nm: 3.1,
        motor_rad_per_count: BELT_TRAVEL_PER_COUNT_M / two_mass.i_t,
        ts_s: SAMPLE_TIME_S,
        noise: super::params::MeasurementNoise::default(),
    }
}

/// Simulation set `S_A` (Table A.11; its caption was lost, docs/thesis-map.md).
pub fn sim_a() -> TwoMassParams {
    TwoMassParams {
        theta_e: 44.90e-6,
        m_c: 10.0,
        c: 200e3,
        d: 20.0,
        d_m: 100.0,
        d_c: 100.0,
        i_t: sim_i_t(),
    }
}

/// Simulation set `S_B` (Table A.12): `S_A` with a tenth of the mass.
pub fn sim_b() -> TwoMassParams {
    TwoMassParams {
        m_c: 1.0,
        ..sim_a()
    }
}

/// Simulation set `S_C` (Table A.13): `S_A` with ten times the stiffness.
pub fn sim_c() -> TwoMassParams {
    TwoMassParams {
        c: 2000e3,
        ..sim_a()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tables A.11-A.13 print f_r and f_z with two decimals, truncated rather
    /// than rounded (f_z = sqrt(200 kN/m / 1 kg) / 2 pi = 71.176 Hz is printed
    /// 71.17; 22.508 Hz is printed 22.50), so the check is
    /// `printed <= computed < printed + 0.01 Hz`.
    const PRINTED_PRECISION_HZ: f64 = 0.01;

    #[test]
    fn simulation_sets_match_tables_a11_a13() {
        for (name, f_r, f_z) in [
            ("sim-a", 133.78, 22.50),
            ("sim-b", 149.85, 71.17),
            ("sim-c", 423.05, 71.17),
        ] {
            let p = builtin(name, None).unwrap().worst_case_two_mass().unwrap();
            let truncated =
                |x: f64, printed: f64| x >= printed && x < printed + PRINTED_PRECISION_HZ;
            assert!(
                truncated(p.f_r_hz(), f_r),
                "{name}: f_r {} vs {f_r}",
                p.f_r_hz()
            );
            assert!(
                truncated(p.f_z_hz(), f_z),
                "{name}: f_z {} vs {f_z}",
                p.f_z_hz()
            );
        }
    }

    /// The data-sheet rig comes within 10 % of the identified Tables A.4 / A.5
    /// (the thesis' values were identified on hardware).
    const DATASHEET_VS_IDENTIFIED: f64 = 0.10;

    #[test]
    fn egc70_worst_case_near_tables_a4_a5() {
        for (payload, table) in [
            (Some(11.2), TwoMassParams::thesis_table_a4()),
            (Some(0.0), TwoMassParams::thesis_table_a5()),
            (None, TwoMassParams::thesis_table_a4()),
        ] {
            let p = builtin("egc70", payload)
                .unwrap()
                .worst_case_two_mass()
                .unwrap();
            let e_r = (p.f_r_hz() / table.f_r_hz() - 1.0).abs();
            let e_z = (p.f_z_hz() / table.f_z_hz() - 1.0).abs();
            assert!(
                e_r < DATASHEET_VS_IDENTIFIED,
                "{payload:?}: f_r {} vs {}",
                p.f_r_hz(),
                table.f_r_hz()
            );
            assert!(
                e_z < DATASHEET_VS_IDENTIFIED,
                "{payload:?}: f_z {} vs {}",
                p.f_z_hz(),
                table.f_z_hz()
            );
            // Theta_e is built to equal the identified 71.73 kg mm^2 (docs/thesis-map.md).
            assert!((p.theta_e - 71.73e-6).abs() < 1e-9);
        }
    }

    /// Table A.10 totals are reproduced at 0 kg (G_B) and 11.2 kg (G_A);
    /// the table prints four significant digits.
    #[test]
    fn egc70_friction_totals_match_table_a10() {
        for (payload, dv, tc) in [(11.2, 2.530e-3, 0.125), (0.0, 2.230e-3, 0.115)] {
            let t = builtin("egc70", Some(payload)).unwrap().friction_totals();
            assert!((t.viscous_nm_s_per_rad - dv).abs() < 0.5e-6, "{t:?}");
            assert!((t.coulomb_nm - tc).abs() < 0.5e-3, "{t:?}");
        }
    }

    #[test]
    fn unknown_names_and_bad_payloads_are_errors() {
        assert!(matches!(
            builtin("egc80", None),
            Err(Error::UnknownPlant { .. })
        ));
        assert!(builtin("sim-a", Some(1.0)).is_err());
        assert!(builtin("egc70", Some(-1.0)).is_err());
        assert!(builtin("egc70", Some(f64::NAN)).is_err());
        for name in BUILTIN_NAMES {
            assert!(builtin(name, None).is_ok());
        }
    }

    #[test]
    fn toml_round_trip_and_errors() {
        let dir = std::env::temp_dir().join(format!("beltune-rigs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in BUILTIN_NAMES {
            let plant = builtin(name, None).unwrap();
            let path = dir.join(format!("{name}.toml"));
            std::fs::write(&path, toml::to_string(&plant).unwrap()).unwrap();
            assert_eq!(load_toml(&path).unwrap(), plant);
        }
        // a negative mass names the file and the field
        let text = toml::to_string(&builtin("egc70", None).unwrap())
            .unwrap()
            .replace("m_cart_kg = 0.96", "m_cart_kg = -0.96");
        let path = dir.join("bad.toml");
        std::fs::write(&path, text).unwrap();
        let msg = load_toml(&path).unwrap_err().to_string();
        assert!(
            msg.contains("bad.toml") && msg.contains("m_cart_kg"),
            "{msg}"
        );
        // a missing field
        std::fs::write(&path, "kind = \"physical\"\nr_m = 0.01\n").unwrap();
        let msg = load_toml(&path).unwrap_err().to_string();
        assert!(
            msg.contains("bad.toml") && msg.contains("missing field"),
            "{msg}"
        );
        // a misspelled field
        let text = toml::to_string(&builtin("sim-a", None).unwrap())
            .unwrap()
            .replace("dead_time_s", "dead_tme_s");
        std::fs::write(&path, text).unwrap();
        let msg = load_toml(&path).unwrap_err().to_string();
        assert!(msg.contains("dead_tme_s"), "{msg}");
        assert!(load_toml(&dir.join("does-not-exist.toml")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
