//! `controller.toml` (schema [`SCHEMA_VERSION`], docs/schema.md): everything a
//! drive needs to run the commissioned controller with `beltune_rt`, and the
//! loader that builds the [`CascadeConfig`] from it.
//!
//! Filters are written twice: as the design parameters (cut-off, notch centre
//! and width, `T_R`) and as the discrete coefficients the controller runs
//! (`[b0, b1, b2, a1, a2]` of `H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)`,
//! `[b0, b1, a1]` of `(b0 + b1 z^-1) / (1 + a1 z^-1)`). The loader uses the
//! coefficients. In current units (`units = "current"`) the unit suffixes of the
//! keys are the current spelling (`torque_max_a`, `k_p_a_s_per_rad`, see
//! [`crate::units`]).

use super::SCHEMA_VERSION;
use crate::commission::stiffness::TargetStiffness;
use crate::design::{ControllerDesign, DriveForm, Prefilter};
use crate::ident::ModelUnits;
use crate::record::model::FrictionResult;
use crate::record::provenance::Provenance;
use crate::units::{current_key, relabel_keys, torque_key};
use crate::{Error, Result};
use beltune_rt::control::{
    AntiWindup, BeltStretch, CascadeConfig, CascadeGains, Feedforward, FeedforwardParams,
    FeedforwardTerms, SetpointConversion,
};
use beltune_rt::filter::{FirstOrderCoeffs, SosCoeffs};
use serde::{Deserialize, Serialize};

/// Largest gain or coefficient a plausible `controller.toml` holds (in SI or
/// current units): far beyond any axis, small enough that every product of
/// two stays finite.
pub const MAX_GAIN: f64 = 1e9;
/// Largest magnitude of a filter coefficient or a compliance term.
pub const MAX_COEFF: f64 = 1e9;

/// `controller.toml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerFile {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// `torque` (N m) or `current` (A): the unit of every torque below.
    pub units: ModelUnits,
    /// Sampling time `T_s`, s.
    pub ts_s: f64,
    /// Torque limit `tau_m,max` (symmetric), N m.
    pub torque_max_nm: f64,
    /// Constant torque offset (holding torque), N m.
    pub torque_offset_nm: f64,
    /// `"conditional_integration"` (6.26) or `"off"` (6.25).
    pub anti_windup: AntiWindupKind,
    /// Who wrote the file.
    pub provenance: Provenance,
    /// Continuous gains (Figure 4.1).
    pub gains: GainsSection,
    /// Prefilter `G_pre` in the velocity loop (Figure 6.9).
    pub prefilter: PrefilterSection,
    /// Velocity filter `G_R = s / (T_R s + 1)` (6.1), Tustin.
    pub velocity_filter: VelocityFilterSection,
    /// Torque feedforward (4.16) and the refinements of the cascade.
    pub feedforward: FeedforwardSection,
    /// Cart trajectory -> motor setpoint (transmission, belt stretch).
    pub setpoint: SetpointSection,
    /// The same controller in drive-menu form (information; not read back).
    pub drive_form: DriveForm,
}

/// Anti-windup of the velocity integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AntiWindupKind {
    /// Conditional integration (6.26).
    ConditionalIntegration,
    /// Plain integration (6.25).
    Off,
}

/// Cascade gains.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GainsSection {
    /// `K_PP`, 1/s.
    pub k_pp_per_s: f64,
    /// `K_P`, N m s/rad.
    pub k_p_nm_s_per_rad: f64,
    /// `K_I`, N m/rad.
    pub k_i_nm_per_rad: f64,
    /// `K_v` (4.17), dimensionless.
    pub k_v: f64,
}

/// Prefilter parameters and its two discrete sections (the second is the identity
/// for a single filter).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrefilterSection {
    /// "butterworth", "notch" or "none".
    pub kind: String,
    /// Butterworth cut-off `w_bw`, rad/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega_bw_rad_s: Option<f64>,
    /// Notch centre `w_r`, rad/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega_r_rad_s: Option<f64>,
    /// Notch width `d_n` (4.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d_n: Option<f64>,
    /// `[[b0, b1, b2, a1, a2], [b0, b1, b2, a1, a2]]`, run in series.
    pub sections: [[f64; 5]; 2],
}

/// Velocity filter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityFilterSection {
    /// `T_R`, s.
    pub t_r_s: f64,
    /// `[b0, b1, a1]`.
    pub coeffs: [f64; 3],
}

/// Feedforward (4.16) and the refinements (a), (b) of the cascade.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedforwardSection {
    /// Term `m_e alpha_d` on.
    pub inertia: bool,
    /// Term `d_v omega_d` on.
    pub viscous: bool,
    /// Term `tau_c sign(omega_d)` on.
    pub coulomb: bool,
    /// `m_e~ = Theta_e + i_t^2 m_c` (4.15), kg m^2.
    pub inertia_kg_m2: f64,
    /// `d_v~`, N m s/rad.
    pub viscous_nm_s_per_rad: f64,
    /// `tau_c~`, N m.
    pub coulomb_nm: f64,
    /// Dead band of `sign(omega_d)`, rad/s.
    pub coulomb_deadband_rad_s: f64,
    /// Breakaway threshold of the Coulomb hold, rad (0: off; absent in files
    /// written before issue 12's breakaway, which then behave as before).
    #[serde(default)]
    pub coulomb_breakaway_rad: f64,
    /// Viscous-only coefficient of the "linear" feedforward (information), N m s/rad.
    pub linear_viscous_nm_s_per_rad: f64,
    /// Refinement (b): the feedforward uses the trajectory `preview_samples` ahead.
    pub preview: bool,
    /// Dead-time preview `n_T = round(t_T / T_s)`, samples.
    pub preview_samples: usize,
    /// Current-loop dead time `t_T` the preview stands for, s.
    pub dead_time_s: f64,
    /// Refinement (a): the desired velocity passes the low-pass part of `G_R`.
    pub filter_desired_velocity: bool,
}

/// Cart trajectory -> motor setpoint ([`SetpointConversion`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetpointSection {
    /// `i_t = r / i_g`, m/rad.
    pub i_t_m_per_rad: f64,
    /// Belt-stretch compensation `phi_d = (xi_d + m_c xi_d'' / c) / i_t` on.
    pub belt_stretch: bool,
    /// Moving mass `m_c`, kg.
    pub m_c_kg: f64,
    /// Belt stiffness `c`, N/m: the one measured where the validation move
    /// ended (commissioning stage 5b, `target_stiffness` in
    /// `commissioning.json`), else the model's.
    pub c_n_per_m: f64,
    /// Static belt stretch under the holding torque at
    /// [`Self::stiffness_position_m`], `tau_hold / (i_t c)`, m: what the
    /// conversion's static force gives there (information: the conversion
    /// applies it, a consumer does not add it again).
    pub static_stretch_m: f64,
    /// Cart position where [`Self::c_n_per_m`] holds, m (in the coordinates
    /// of the trajectory samples; the validation target). 0 in older files,
    /// whose stiffness is one for the whole stroke.
    #[serde(default)]
    pub stiffness_position_m: f64,
    /// Slope of the belt's compliance `1 / c` along the stroke at
    /// [`Self::stiffness_position_m`], 1/N (stages 5b/5c; 0: one stiffness).
    #[serde(default)]
    pub compliance_slope_per_n: f64,
    /// Half the compliance's second derivative, 1/(N m) (0: at most linear).
    #[serde(default)]
    pub compliance_curvature_per_n_m: f64,
    /// Force the belt carries at rest, `tau_hold / i_t`, N: the conversion
    /// leads the motor by its stretch `F / c(xi)` wherever the cart is
    /// (absent in older files: `static_stretch_m c_n_per_m`).
    #[serde(default)]
    pub static_force_n: Option<f64>,
    /// The cart's viscous friction `d_c`, N s/m: the motor leads by the
    /// stretch `d_c xi' / c(xi)` too (0: not compensated, older files).
    #[serde(default)]
    pub cart_viscous_n_s_per_m: f64,
    /// The cart's Coulomb friction `F_c`, N: the motor leads by
    /// `F_c sign(xi') / c(xi)` while the cart moves (0: not compensated).
    #[serde(default)]
    pub cart_coulomb_n: f64,
    /// Cart speed over which the Coulomb lead ramps in and out, m/s.
    #[serde(default = "default_coulomb_velocity")]
    pub coulomb_velocity_m_s: f64,
    /// Distance of the validated move's final approach, m (0: none;
    /// [`crate::commission::validation::final_approach`]): the last part of a move,
    /// crept at [`Self::final_approach_speed_m_s`] with the cart's Coulomb
    /// lead held in the move's direction (`beltune_rt::trajectory::Approach`,
    /// `SetpointConversion::motor_sample_held`). It is `2 F_c / c + 1 mm`
    /// at the stiffness `c` of [`Self::stiffness_position_m`].
    #[serde(default)]
    pub final_approach_distance_m: f64,
    /// Speed of the final approach, m/s.
    #[serde(default = "default_final_approach_speed")]
    pub final_approach_speed_m_s: f64,
}

fn default_coulomb_velocity() -> f64 {
    crate::commission::stiffness::CART_COULOMB_VELOCITY_M_S
}

fn default_final_approach_speed() -> f64 {
    crate::commission::validation::FINAL_APPROACH_SPEED_M_S
}

impl SetpointSection {
    /// The belt model of the conversion: the compliance along the stroke
    /// about [`Self::stiffness_position_m`] with the static force
    /// (`Off` when `belt_stretch` is off; a non-positive `c_n_per_m` is
    /// left for [`SetpointConversion::new`] to refuse).
    pub fn belt_stretch(&self) -> BeltStretch<f64> {
        if !self.belt_stretch {
            return BeltStretch::Off;
        }
        BeltStretch::Profile(beltune_rt::control::BeltProfile {
            m_c_kg: self.m_c_kg,
            reference_m: self.stiffness_position_m,
            compliance_m_per_n: 1.0 / self.c_n_per_m,
            compliance_slope_per_n: self.compliance_slope_per_n,
            compliance_curvature_per_n_m: self.compliance_curvature_per_n_m,
            static_force_n: self
                .static_force_n
                .unwrap_or(self.static_stretch_m * self.c_n_per_m),
            cart_viscous_n_s_per_m: self.cart_viscous_n_s_per_m,
            cart_coulomb_n: self.cart_coulomb_n,
            coulomb_velocity_m_s: self.coulomb_velocity_m_s,
        })
    }
}

impl ControllerFile {
    /// The controller commissioning validated: the design's gains and filters,
    /// conditional integration, nonlinear feedforward (4.16) with dead-time
    /// preview, filtered desired velocity, belt-stretch compensation, and the
    /// static belt stretch under the holding torque, both with the stiffness
    /// at the validation target (`target_stiffness`; `None`: the model's `c`).
    pub fn from_design(
        des: &ControllerDesign,
        friction: &FrictionResult,
        target_stiffness: Option<&TargetStiffness>,
        torque_max_nm: f64,
        units: ModelUnits,
        provenance: Provenance,
    ) -> Result<Self> {
        let cfg = des.cascade_config(torque_max_nm)?;
        let (kind, omega_bw, omega_r, d_n) = match des.prefilter {
            Prefilter::Butterworth { omega_bw_rad_s } => {
                ("butterworth", Some(omega_bw_rad_s), None, None)
            }
            Prefilter::Notch { omega_r_rad_s, d_n } => {
                ("notch", None, Some(omega_r_rad_s), Some(d_n))
            }
            Prefilter::None => ("none", None, None, None),
        };
        let sos = |s: &SosCoeffs<f64>| [s.b0, s.b1, s.b2, s.a1, s.a2];
        let v = cfg.velocity_filter;
        let model = des.input.model;
        // the stiffness where the validated move decelerated and rests, and
        // how it changes along the stroke
        let belt = target_stiffness
            .copied()
            .unwrap_or_else(|| TargetStiffness::constant(0.0, model.c, model.f_z_hz(), false));
        let c_setpoint = belt.c_n_per_m;
        let static_force_n = friction.holding_torque_nm / model.i_t;
        let file = ControllerFile {
            schema_version: SCHEMA_VERSION,
            units,
            ts_s: des.input.ts_s,
            torque_max_nm,
            torque_offset_nm: friction.holding_torque_nm,
            anti_windup: AntiWindupKind::ConditionalIntegration,
            provenance,
            gains: GainsSection {
                k_pp_per_s: des.k_pp,
                k_p_nm_s_per_rad: des.k_p,
                k_i_nm_per_rad: des.k_i,
                k_v: cfg.gains.k_v,
            },
            prefilter: PrefilterSection {
                kind: kind.into(),
                omega_bw_rad_s: omega_bw,
                omega_r_rad_s: omega_r,
                d_n,
                sections: [sos(&cfg.prefilter[0]), sos(&cfg.prefilter[1])],
            },
            velocity_filter: VelocityFilterSection {
                t_r_s: des.input.t_r_s,
                coeffs: [v.b0, v.b1, v.a1],
            },
            feedforward: FeedforwardSection {
                inertia: true,
                viscous: true,
                coulomb: true,
                // what the validation moved with (the friction-aware fit's
                // rigid inertia, else the friction runs' momentum balance)
                inertia_kg_m2: des.feedforward.inertia_kg_m2,
                viscous_nm_s_per_rad: friction.viscous_nm_s_per_rad,
                coulomb_nm: friction.coulomb_nm,
                coulomb_deadband_rad_s: beltune_rt::control::DEFAULT_COULOMB_DEADBAND_RAD_S,
                coulomb_breakaway_rad: crate::commission::validation::coulomb_breakaway_rad(
                    model.i_t,
                    friction,
                    belt.c_n_per_m,
                ),
                linear_viscous_nm_s_per_rad: friction.linear_viscous_nm_s_per_rad,
                preview: true,
                preview_samples: (des.input.dead_time_s / des.input.ts_s).round() as usize,
                dead_time_s: des.input.dead_time_s,
                filter_desired_velocity: true,
            },
            setpoint: SetpointSection {
                i_t_m_per_rad: model.i_t,
                belt_stretch: true,
                m_c_kg: model.m_c,
                c_n_per_m: c_setpoint,
                static_stretch_m: static_force_n / c_setpoint,
                stiffness_position_m: belt.position_m,
                compliance_slope_per_n: belt.compliance_slope_per_n,
                compliance_curvature_per_n_m: belt.compliance_curvature_per_n_m,
                static_force_n: Some(static_force_n),
                cart_viscous_n_s_per_m: friction.cart_viscous_n_s_per_m,
                cart_coulomb_n: friction.cart_coulomb_n,
                coulomb_velocity_m_s: crate::commission::stiffness::CART_COULOMB_VELOCITY_M_S,
                final_approach_distance_m: crate::commission::validation::final_approach_for_band(
                    friction.cart_coulomb_n / c_setpoint,
                )
                .map_or(0.0, |a| a.distance_m),
                final_approach_speed_m_s: crate::commission::validation::FINAL_APPROACH_SPEED_M_S,
            },
            drive_form: DriveForm::of(des),
        };
        file.cascade_config()?;
        Ok(file)
    }

    /// The real-time controller configuration (validated).
    pub fn cascade_config(&self) -> Result<CascadeConfig<f64>> {
        let s = |c: &[f64; 5]| SosCoeffs {
            b0: c[0],
            b1: c[1],
            b2: c[2],
            a1: c[3],
            a2: c[4],
        };
        let g = &self.gains;
        let f = &self.feedforward;
        let [b0, b1, a1] = self.velocity_filter.coeffs;
        let cfg = CascadeConfig {
            ts_s: self.ts_s,
            gains: CascadeGains {
                k_pp_per_s: g.k_pp_per_s,
                k_p_nm_s_per_rad: g.k_p_nm_s_per_rad,
                k_i_nm_per_rad: g.k_i_nm_per_rad,
                k_v: g.k_v,
            },
            velocity_filter: FirstOrderCoeffs { b0, b1, a1 },
            prefilter: [
                s(&self.prefilter.sections[0]),
                s(&self.prefilter.sections[1]),
            ],
            torque_max_nm: self.torque_max_nm,
            anti_windup: match self.anti_windup {
                AntiWindupKind::ConditionalIntegration => AntiWindup::ConditionalIntegration,
                AntiWindupKind::Off => AntiWindup::Off,
            },
            feedforward: Feedforward {
                params: FeedforwardParams {
                    inertia_kg_m2: f.inertia_kg_m2,
                    viscous_nm_s_per_rad: f.viscous_nm_s_per_rad,
                    coulomb_nm: f.coulomb_nm,
                    coulomb_deadband_rad_s: f.coulomb_deadband_rad_s,
                    coulomb_breakaway_rad: f.coulomb_breakaway_rad,
                },
                terms: FeedforwardTerms {
                    inertia: f.inertia,
                    viscous: f.viscous,
                    coulomb: f.coulomb,
                },
            },
            torque_offset_nm: self.torque_offset_nm,
            filter_desired_velocity: f.filter_desired_velocity,
            feedforward_preview: f.preview,
        };
        cfg.validate()?;
        Ok(cfg)
    }

    /// The setpoint conversion for cart trajectories (validated).
    pub fn setpoint_conversion(&self) -> Result<SetpointConversion<f64>> {
        let s = &self.setpoint;
        Ok(SetpointConversion::new(s.i_t_m_per_rad, s.belt_stretch())?)
    }

    /// The TOML text (keys relabelled in current units).
    pub fn to_toml(&self) -> Result<String> {
        let err = |e: String| Error::Report {
            reason: format!("controller.toml: {e}"),
        };
        let mut v = serde_json::to_value(self).map_err(|e| err(e.to_string()))?;
        if self.units == ModelUnits::Current {
            relabel_keys(&mut v, &current_key);
        }
        strip_nulls(&mut v);
        let body = toml::to_string_pretty(&v).map_err(|e| err(e.to_string()))?;
        let l = crate::units::labels(self.units);
        Ok(format!(
            "# beltune controller.toml, schema {SCHEMA_VERSION} (docs/schema.md).\n\
             # Torques in {}, K_P in {}, K_I in {}; angles in rad, times in s.\n\n{body}",
            l.torque, l.torque_per_velocity, l.torque_per_angle
        ))
    }

    /// Parse and check a `controller.toml`; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let perr = |message: String| Error::Parse {
            path: origin.to_string(),
            message,
        };
        let t: toml::Value =
            toml::from_str(text).map_err(|e| perr(e.to_string().replace('\n', " ")))?;
        if let Some((key, x)) = non_finite(&t, "") {
            return Err(perr(format!(
                "`{key}` = {x}: every number of a controller must be finite"
            )));
        }
        let mut v = serde_json::to_value(t).map_err(|e| perr(e.to_string()))?;
        match v.get("schema_version").and_then(|s| s.as_u64()) {
            Some(s) if s == u64::from(SCHEMA_VERSION) => {}
            Some(s) => {
                return Err(perr(format!(
                    "schema_version {s} is not the one this beltune reads ({SCHEMA_VERSION})"
                )))
            }
            None => {
                return Err(perr(
                    "no schema_version: a controller.toml from before schema 1 cannot drive beltune_rt (it lacks i_t, anti-windup and the second filter section); commission again".into(),
                ))
            }
        }
        let current = v.get("units").and_then(|u| u.as_str()) == Some("current");
        if current {
            relabel_keys(&mut v, &torque_key);
        }
        let file: ControllerFile = serde_json::from_value(v).map_err(|e| perr(e.to_string()))?;
        // the key as the file spells it (current units: `torque_max_a`)
        let spelled = |key: &str| match current {
            true => crate::units::current_key(key).unwrap_or_else(|| key.to_string()),
            false => key.to_string(),
        };
        file.check_plausible().map_err(|e| match e {
            Error::InvalidParameter {
                name,
                value,
                reason,
            } => perr(format!(
                "`{}` = {}: {reason}",
                spelled(&name),
                crate::error::short_number(value)
            )),
            e => perr(e.to_string()),
        })?;
        file.cascade_config()
            .map_err(|e| perr(format!("not a valid controller: {e}")))?;
        file.setpoint_conversion()
            .map_err(|e| perr(format!("not a valid setpoint conversion: {e}")))?;
        Ok(file)
    }

    /// The plausibility checks a design's inputs pass
    /// ([`crate::design::DesignInput::validate`], [`crate::model::TwoMassParams::validate`]),
    /// on what a file gives the drive: a hand-edited or foreign
    /// `controller.toml` is refused before `export` or a drive uses it.
    /// Errors name the key (`gains.k_v`).
    pub fn check_plausible(&self) -> Result<()> {
        use crate::error::require_range;
        use crate::model::params::bounds;
        crate::model::params::check_sample_time(self.ts_s)?;
        crate::model::params::check_torque_limit("torque_max_nm", self.torque_max_nm)?;
        let t = self.torque_max_nm;
        require_range("torque_offset_nm", self.torque_offset_nm, -t, t).map_err(|_| {
            Error::invalid(
                "torque_offset_nm",
                self.torque_offset_nm,
                "must lie within the torque limit",
            )
        })?;
        let g = &self.gains;
        require_range("gains.k_pp_per_s", g.k_pp_per_s, 0.0, MAX_GAIN)?;
        require_range("gains.k_p_nm_s_per_rad", g.k_p_nm_s_per_rad, 0.0, MAX_GAIN)?;
        require_range("gains.k_i_nm_per_rad", g.k_i_nm_per_rad, 0.0, MAX_GAIN)?;
        require_range("gains.k_v", g.k_v, 0.0, 1.0)?;
        for (i, sec) in self.prefilter.sections.iter().enumerate() {
            for c in sec {
                require_range(
                    &format!("prefilter.sections[{i}]"),
                    *c,
                    -MAX_COEFF,
                    MAX_COEFF,
                )?;
            }
        }
        require_range(
            "velocity_filter.t_r_s",
            self.velocity_filter.t_r_s,
            1e-6,
            1.0,
        )?;
        let f = &self.feedforward;
        require_range("feedforward.inertia_kg_m2", f.inertia_kg_m2, 0.0, MAX_GAIN)?;
        require_range(
            "feedforward.viscous_nm_s_per_rad",
            f.viscous_nm_s_per_rad,
            0.0,
            MAX_GAIN,
        )?;
        require_range(
            "feedforward.linear_viscous_nm_s_per_rad",
            f.linear_viscous_nm_s_per_rad,
            0.0,
            MAX_GAIN,
        )?;
        require_range("feedforward.coulomb_nm", f.coulomb_nm, 0.0, t)?;
        require_range(
            "feedforward.coulomb_deadband_rad_s",
            f.coulomb_deadband_rad_s,
            0.0,
            MAX_GAIN,
        )?;
        require_range(
            "feedforward.coulomb_breakaway_rad",
            f.coulomb_breakaway_rad,
            0.0,
            MAX_GAIN,
        )?;
        require_range(
            "feedforward.dead_time_s",
            f.dead_time_s,
            0.0,
            crate::design::MAX_DEAD_TIME_S,
        )?;
        let samples = f.dead_time_s / self.ts_s;
        if (f.preview_samples as f64 - samples).abs() > 1.0 {
            return Err(Error::invalid(
                "feedforward.preview_samples",
                f.preview_samples as f64,
                format!(
                    "must be the dead time in samples, dead_time_s / ts_s = {}",
                    crate::error::short_number(samples)
                ),
            ));
        }
        let p = &self.setpoint;
        require_range("setpoint.i_t_m_per_rad", p.i_t_m_per_rad, 1e-6, 1e3)?;
        require_range("setpoint.m_c_kg", p.m_c_kg, 0.0, 1e6)?;
        require_range("setpoint.c_n_per_m", p.c_n_per_m, 1e-6, 1e12)?;
        require_range(
            "setpoint.static_stretch_m",
            p.static_stretch_m,
            -bounds::LENGTH_MAX_M,
            bounds::LENGTH_MAX_M,
        )?;
        require_range(
            "setpoint.stiffness_position_m",
            p.stiffness_position_m,
            -bounds::LENGTH_MAX_M,
            bounds::LENGTH_MAX_M,
        )?;
        require_range(
            "setpoint.compliance_slope_per_n",
            p.compliance_slope_per_n,
            -MAX_COEFF,
            MAX_COEFF,
        )?;
        require_range(
            "setpoint.compliance_curvature_per_n_m",
            p.compliance_curvature_per_n_m,
            -MAX_COEFF,
            MAX_COEFF,
        )?;
        if let Some(force) = p.static_force_n {
            require_range(
                "setpoint.static_force_n",
                force,
                -bounds::FORCE_MAX_N,
                bounds::FORCE_MAX_N,
            )?;
        }
        require_range(
            "setpoint.cart_viscous_n_s_per_m",
            p.cart_viscous_n_s_per_m,
            0.0,
            bounds::DAMPING_MAX_N_S_PER_M,
        )?;
        require_range(
            "setpoint.cart_coulomb_n",
            p.cart_coulomb_n,
            0.0,
            bounds::FORCE_MAX_N,
        )?;
        require_range(
            "setpoint.coulomb_velocity_m_s",
            p.coulomb_velocity_m_s,
            1e-9,
            10.0,
        )?;
        require_range(
            "setpoint.final_approach_distance_m",
            p.final_approach_distance_m,
            0.0,
            1.0,
        )?;
        require_range(
            "setpoint.final_approach_speed_m_s",
            p.final_approach_speed_m_s,
            1e-9,
            1.0,
        )?;
        Ok(())
    }

    /// Read and parse a file.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = crate::io::read_to_string_capped(path, crate::io::MAX_TEXT_BYTES)?;
        ControllerFile::parse(&text, &path.display().to_string())
    }
}

/// The first key (dotted path) whose value is a non-finite float (TOML has
/// `nan` and `inf`, JSON has not: converted, they would read as absent).
fn non_finite(v: &toml::Value, at: &str) -> Option<(String, f64)> {
    match v {
        toml::Value::Float(x) if !x.is_finite() => Some((at.to_string(), *x)),
        toml::Value::Table(t) => t.iter().find_map(|(k, x)| {
            let key = if at.is_empty() {
                k.clone()
            } else {
                format!("{at}.{k}")
            };
            non_finite(x, &key)
        }),
        toml::Value::Array(a) => a
            .iter()
            .enumerate()
            .find_map(|(i, x)| non_finite(x, &format!("{at}[{i}]"))),
        _ => None,
    }
}

/// TOML has no null: an absent key is `None`.
fn strip_nulls(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|_, x| !x.is_null());
            m.values_mut().for_each(strip_nulls);
        }
        serde_json::Value::Array(xs) => xs.iter_mut().for_each(strip_nulls),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{design, DesignInput, DesignKnobs, FrictionParams, PrefilterKind};
    use crate::model::TwoMassParams;
    use beltune_rt::control::{CascadeController, MotionSample, Setpoint};

    fn table_a4() -> TwoMassParams {
        TwoMassParams::thesis_table_a4()
    }

    fn friction() -> FrictionResult {
        FrictionResult {
            viscous_nm_s_per_rad: 2.53e-3,
            coulomb_nm: 0.125,
            linear_viscous_nm_s_per_rad: 4.1e-3,
            relative_residual: 0.02,
            holding_torque_nm: 0.31,
            cart_coulomb_n: 6.4,
            cart_viscous_n_s_per_m: 9.2,
        }
    }

    fn designed(kind: PrefilterKind) -> ControllerDesign {
        let mut inp = DesignInput::new(table_a4(), 1e-3);
        inp.friction = Some(FrictionParams {
            viscous_nm_s_per_rad: 2.53e-3,
            coulomb_nm: 0.125,
        });
        design(
            &inp,
            &DesignKnobs {
                prefilter: kind,
                ..DesignKnobs::default()
            },
        )
        .unwrap()
    }

    /// The configuration commissioning validates, built the way
    /// `procedure::commission` builds it (independently of this module).
    fn reference(des: &ControllerDesign, f: &FrictionResult, tmax: f64) -> CascadeConfig<f64> {
        let mut c = crate::commission::cascade_from_design(des, tmax, f.holding_torque_nm).unwrap();
        c.feedforward = Feedforward::nonlinear(
            des.input.model.rigid_inertia(),
            f.viscous_nm_s_per_rad,
            f.coulomb_nm,
        );
        // the breakaway of the validation: 20 um at the cart beyond the
        // stretch of the cart's Coulomb friction (the model's stiffness)
        let m = des.input.model;
        c.feedforward.params.coulomb_breakaway_rad = (20e-6 + f.cart_coulomb_n / m.c) / m.i_t;
        c.filter_desired_velocity = true;
        c.feedforward_preview = true;
        c
    }

    /// Torques of `cfg` over 4000 samples of a moving setpoint against a
    /// measured angle that lags and rings (saturating now and then).
    fn torques(cfg: CascadeConfig<f64>) -> Vec<f64> {
        let mut c = CascadeController::new(cfg).unwrap();
        (0..4000)
            .map(|k| {
                let t = k as f64 * 1e-4;
                let s = |t: f64| MotionSample {
                    angle_rad: 20.0 * (1.0 - (3.0 * t).cos()),
                    velocity_rad_s: 60.0 * (3.0 * t).sin(),
                    acceleration_rad_s2: 180.0 * (3.0 * t).cos(),
                };
                let measured = s(t - 0.05).angle_rad + 0.01 * (700.0 * t).sin();
                c.step(&Setpoint::with_preview(s(t), s(t + 1e-3)), measured)
                    .torque_nm
            })
            .collect()
    }

    #[test]
    fn toml_gives_the_same_controller_sample_by_sample() {
        for kind in [PrefilterKind::Butterworth, PrefilterKind::Notch] {
            let des = designed(kind);
            let f = friction();
            let file = ControllerFile::from_design(
                &des,
                &f,
                None,
                3.1,
                ModelUnits::Torque,
                Provenance::now(vec!["beltune".into()], Some(1)),
            )
            .unwrap();
            let text = file.to_toml().unwrap();
            let back = ControllerFile::parse(&text, "controller.toml").unwrap();
            assert_eq!(back, file);
            let loaded = back.cascade_config().unwrap();
            let want = reference(&des, &f, 3.1);
            assert_eq!(loaded, want, "{kind:?}");
            let (a, b) = (torques(loaded), torques(want));
            assert_eq!(a, b);
            assert!(a.iter().any(|t| t.abs() == 3.1), "the test saturates");
            assert_eq!(back.feedforward.preview_samples, 10);
            let sc = back.setpoint_conversion().unwrap();
            // the model's stiffness everywhere, the holding torque's force
            let want_sc = SetpointConversion::new(
                table_a4().i_t,
                BeltStretch::Profile(beltune_rt::control::BeltProfile {
                    m_c_kg: 13.44,
                    reference_m: 0.0,
                    compliance_m_per_n: 1.0 / 203.74e3,
                    compliance_slope_per_n: 0.0,
                    compliance_curvature_per_n_m: 0.0,
                    static_force_n: f.holding_torque_nm / table_a4().i_t,
                    // the cart's friction the friction-aware model found
                    cart_viscous_n_s_per_m: 9.2,
                    cart_coulomb_n: 6.4,
                    coulomb_velocity_m_s: crate::commission::stiffness::CART_COULOMB_VELOCITY_M_S,
                }),
            )
            .unwrap();
            assert_eq!(sc, want_sc);
        }
    }

    /// The file's setpoint leads by the static stretch of the
    /// stiffness measured where the validation move ended, not of the
    /// worst-case position's (the cart rested short by the difference).
    #[test]
    fn static_stretch_uses_the_stiffness_at_the_validation_target() {
        let des = designed(PrefilterKind::Butterworth);
        let f = friction();
        let file = |t: Option<&TargetStiffness>| {
            ControllerFile::from_design(
                &des,
                &f,
                t,
                3.1,
                ModelUnits::Torque,
                Provenance::now(vec![], None),
            )
            .unwrap()
        };
        // 0.31 N m / table_a4().i_t m/rad = 24.97 N: 122.6 um on the model's
        // 203.74 kN/m, 99.9 um on 250 kN/m
        let tol = 1e-9;
        let model = file(None).setpoint;
        assert!((model.static_stretch_m - 0.31 / (table_a4().i_t * 203.74e3)).abs() < tol);
        let target = TargetStiffness::constant(0.5, 250e3, 22.0, true);
        let at_target = file(Some(&target)).setpoint;
        assert!((at_target.static_stretch_m - 0.31 / (table_a4().i_t * 250e3)).abs() < tol);
        // the dynamic stretch compensation m_c a / c uses it too, as the
        // validation move did
        assert_eq!(model.c_n_per_m, 203.74e3);
        assert_eq!(at_target.c_n_per_m, 250e3);
    }

    /// The file carries the belt's compliance along the stroke
    /// and the static force, and its setpoint conversion is the one the
    /// validation moved with: at the target it leads by the static stretch
    /// there, at another position by the stretch of that position's
    /// stiffness, `F K(xi)`; an older file (no profile keys) reads as one
    /// stiffness with the static force `static_stretch_m c`.
    #[test]
    fn the_setpoint_carries_the_belt_profile() {
        let des = designed(PrefilterKind::Butterworth);
        let f = friction();
        let profile = TargetStiffness {
            compliance_slope_per_n: 1.0e-5,
            compliance_curvature_per_n_m: -5.0e-6,
            ..TargetStiffness::constant(0.5, 250e3, 22.0, true)
        };
        let file = ControllerFile::from_design(
            &des,
            &f,
            Some(&profile),
            3.1,
            ModelUnits::Torque,
            Provenance::now(vec![], None),
        )
        .unwrap();
        let back = ControllerFile::parse(&file.to_toml().unwrap(), "c.toml").unwrap();
        assert_eq!(back.setpoint, file.setpoint);
        // the final approach at the target's stiffness (250 kN/m): 2 F_c / c + 1 mm
        let approach = 1e-3 + 2.0 * 6.4 / 250e3;
        assert!((back.setpoint.final_approach_distance_m - approach).abs() < 1e-15);
        assert_eq!(back.setpoint.final_approach_speed_m_s, 2e-3);
        let conv = back.setpoint_conversion().unwrap();
        let force = 0.31 / table_a4().i_t;
        let at_rest = |x: f64| {
            conv.motor_sample(&beltune_rt::control::CartSample {
                position_m: x,
                ..Default::default()
            })
            .angle_rad
                * table_a4().i_t
                - x
        };
        let tol = 1e-12;
        assert!(
            (at_rest(0.5) - force / 250e3).abs() < tol,
            "{}",
            at_rest(0.5)
        );
        assert!((at_rest(0.1) - force * profile.compliance_at(0.1)).abs() < tol);
        assert!(at_rest(0.1) < at_rest(0.5), "stiffer near the motor");
        // an older file: no profile keys
        let text = file.to_toml().unwrap();
        let old: String = text
            .lines()
            .filter(|l| {
                ![
                    "stiffness_position_m",
                    "compliance_slope",
                    "compliance_curvature",
                    "static_force_n",
                ]
                .iter()
                .any(|k| l.starts_with(k))
            })
            .map(|l| format!("{l}\n"))
            .collect();
        let old = ControllerFile::parse(&old, "old.toml").unwrap();
        let s = &old.setpoint;
        assert_eq!((s.compliance_slope_per_n, s.static_force_n), (0.0, None));
        let conv = old.setpoint_conversion().unwrap();
        let lead = conv
            .motor_sample(&beltune_rt::control::CartSample {
                position_m: 0.1,
                ..Default::default()
            })
            .angle_rad
            * table_a4().i_t
            - 0.1;
        assert!((lead - s.static_stretch_m).abs() < tol, "{lead}");
    }

    #[test]
    fn current_units_relabel_every_torque_key() {
        let des = designed(PrefilterKind::Butterworth);
        let file = ControllerFile::from_design(
            &des,
            &friction(),
            None,
            15.0,
            ModelUnits::Current,
            Provenance::now(vec![], None),
        )
        .unwrap();
        let text = file.to_toml().unwrap();
        for bad in ["_nm", "kg", "N m"] {
            assert!(!text.contains(bad), "`{bad}` in\n{text}");
        }
        assert!(text.contains("torque_max_a = 15.0"), "{text}");
        assert!(text.contains("k_p_a_s_per_rad"), "{text}");
        let back = ControllerFile::parse(&text, "c.toml").unwrap();
        assert_eq!(back, file);
    }

    #[test]
    fn old_or_broken_files_are_errors() {
        let des = designed(PrefilterKind::Butterworth);
        let file = ControllerFile::from_design(
            &des,
            &friction(),
            None,
            3.1,
            ModelUnits::Torque,
            Provenance::now(vec![], None),
        )
        .unwrap();
        let text = file.to_toml().unwrap();
        let old = text.replace("schema_version = 1\n", "");
        let e = ControllerFile::parse(&old, "c.toml").unwrap_err();
        assert!(e.to_string().contains("schema_version"), "{e}");
        let neg = text.replace("torque_max_nm = 3.1", "torque_max_nm = -3.1");
        assert!(ControllerFile::parse(&neg, "c.toml").is_err());
        let extra = text.replace("ts_s =", "bogus = 1\nts_s =");
        assert!(ControllerFile::parse(&extra, "c.toml").is_err());
        // A file from before the breakaway loads with it off.
        assert!(text.contains("coulomb_breakaway_rad = "), "{text}");
        let before: String = text
            .lines()
            .filter(|l| !l.starts_with("coulomb_breakaway_rad"))
            .map(|l| format!("{l}\n"))
            .collect();
        let old = ControllerFile::parse(&before, "c.toml").unwrap();
        assert_eq!(old.feedforward.coulomb_breakaway_rad, 0.0);
        let off = old.cascade_config().unwrap();
        assert_eq!(off.feedforward.params.coulomb_breakaway_rad, 0.0);
        let mut unstable = file.clone();
        unstable.prefilter.sections[0][4] = 1.5;
        let e = ControllerFile::parse(&unstable.to_toml().unwrap(), "c.toml").unwrap_err();
        assert!(e.to_string().contains("prefilter"), "{e}");
    }

    /// `export` and a drive read only plausible controllers: every absurd
    /// value a hostile or careless edit can put into a `controller.toml` is
    /// refused in one line naming its key, as a design's inputs are.
    #[test]
    fn an_implausible_controller_file_is_refused_naming_its_key() {
        let des = designed(PrefilterKind::Butterworth);
        let file = ControllerFile::from_design(
            &des,
            &friction(),
            None,
            3.1,
            ModelUnits::Torque,
            Provenance::now(vec![], None),
        )
        .unwrap();
        let text = file.to_toml().unwrap();
        ControllerFile::parse(&text, "c.toml").expect("the commissioned file is plausible");
        let set = |key: &str, value: &str| -> String {
            let mut done = false;
            let out: String = text
                .lines()
                .map(|l| {
                    if !done && l.split(" = ").next() == Some(key) {
                        done = true;
                        format!("{key} = {value}\n")
                    } else {
                        format!("{l}\n")
                    }
                })
                .collect();
            assert!(done, "no key {key}");
            out
        };
        for (key, value, named) in [
            ("ts_s", "5e-324", "ts_s"),
            ("ts_s", "1.0", "ts_s"),
            ("ts_s", "1e308", "ts_s"),
            ("torque_max_nm", "1e308", "torque_max_nm"),
            ("torque_max_nm", "1e-300", "torque_max_nm"),
            ("torque_offset_nm", "5.0", "torque_offset_nm"),
            ("k_p_nm_s_per_rad", "1e308", "gains.k_p_nm_s_per_rad"),
            ("k_v", "-1e308", "gains.k_v"),
            ("i_t_m_per_rad", "5e-324", "setpoint.i_t_m_per_rad"),
            ("c_n_per_m", "1e-300", "setpoint.c_n_per_m"),
            ("preview_samples", "9223372036854775807", "preview_samples"),
            ("dead_time_s", "-1.0", "feedforward.dead_time_s"),
            ("k_i_nm_per_rad", "nan", "k_i_nm_per_rad"),
            ("ts_s", "inf", "ts_s"),
            ("coulomb_breakaway_rad", "nan", "coulomb_breakaway_rad"),
        ] {
            let e = ControllerFile::parse(&set(key, value), "c.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains(named), "{key} = {value}: {e}");
            assert!(e.len() < 300 && !e.contains('\n'), "one short line: {e}");
        }
        let extra = text.replace("[provenance]\n", "[provenance]\ninjected = \"x\"\n");
        let e = ControllerFile::parse(&extra, "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("injected"), "{e}");
    }
}
