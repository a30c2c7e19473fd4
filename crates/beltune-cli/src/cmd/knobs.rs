//! The design knobs on the command line, shared by `design` and `commission`.
//!
//! Without an expert flag the robust rule designs (prefilter and nominal
//! margins chosen for the margins `--dynamics` guarantees, standard by
//! default). With one the thesis' conditions hold exactly: defaults
//! (Butterworth, 60 deg / 80 deg, -10 dB), then `--dynamics`, then the
//! explicit expert flags.

use beltune::design::robust::DesignRule;
use beltune::design::{DesignKnobs, Dynamics, PrefilterKind};

/// Design knobs (thesis 4.2-4.3) and the one-knob mode.
#[derive(clap::Args, Clone, Debug)]
pub struct KnobArgs {
    /// Prefilter in the velocity loop: butterworth, notch or none (default: chosen by the
    /// robust design rule among Butterworth and notch filters). Giving it, or any of the
    /// margin flags below, designs with exactly these values (the thesis' conditions).
    #[arg(long)]
    pub prefilter: Option<String>,
    /// Velocity-loop phase margin in degrees (default: chosen by the robust design rule,
    /// typically 50-60; 60 with any other expert flag).
    #[arg(long, allow_negative_numbers = true)]
    pub pm_velocity: Option<f64>,
    /// Position-loop phase margin in degrees (default: chosen by the robust design rule,
    /// typically 65-80; 80 with any other expert flag).
    #[arg(long, allow_negative_numbers = true)]
    pub pm_position: Option<f64>,
    /// Open-loop gain at the resonance A_sup in dB (default -10).
    #[arg(long, allow_negative_numbers = true)]
    pub resonance_suppression_db: Option<f64>,
    /// Prefilter gain at the antiresonance in dB (default -3 Butterworth, -6 notch).
    #[arg(long, allow_negative_numbers = true)]
    pub filter_attenuation_db: Option<f64>,
    /// One knob from slow to fast: conservative, standard (the default), dynamic, or a number
    /// in [0, 1]. It sets the phase margins the design keeps over the identification's
    /// uncertainty: velocity/position 55/70 deg conservative, 45/60 standard, 35/50 dynamic.
    #[arg(long, allow_hyphen_values = true)]
    pub dynamics: Option<String>,
    /// Design with the thesis' rule on the fit as identified (friction lumped into damping)
    /// instead of the robust rule, for comparison.
    #[arg(long)]
    pub thesis_design: bool,
}

impl KnobArgs {
    /// The knobs, or one line saying which flag is wrong. The ranges are
    /// checked here, before a commissioning moves the axis (the design checks
    /// them again, with the library's names).
    pub fn knobs(&self) -> anyhow::Result<DesignKnobs> {
        let kind: PrefilterKind = self.prefilter.as_deref().unwrap_or("butterworth").parse()?;
        let mut knobs = DesignKnobs {
            prefilter: kind,
            ..DesignKnobs::default()
        };
        if let Some(d) = &self.dynamics {
            let d = d
                .parse::<Dynamics>()
                .map_err(|e| super::util::in_flag_words(e.into(), &super::util::KNOB_FLAGS))?;
            knobs = d.knobs(&knobs);
        }
        let bad = |flag: &str, v: f64, why: &str| {
            anyhow::Error::new(crate::exit::Failure::new(
                crate::exit::ExitStatus::BadInput,
                format!("{flag} {}: {why}", beltune::error::short_number(v)),
            ))
        };
        for (flag, v, what) in [
            (
                "--pm-velocity",
                self.pm_velocity,
                "the velocity phase margin",
            ),
            (
                "--pm-position",
                self.pm_position,
                "the position phase margin",
            ),
        ] {
            if let Some(v) = v.filter(|v| !(*v > 0.0 && *v < 180.0)) {
                return Err(bad(flag, v, &format!("{what} must lie in (0, 180) deg")));
            }
        }
        if let Some(v) = self
            .resonance_suppression_db
            .filter(|v| !(v.is_finite() && (-100.0..0.0).contains(v)))
        {
            return Err(bad(
                "--resonance-suppression-db",
                v,
                "the open-loop gain at the resonance A_sup must lie in [-100, 0) dB",
            ));
        }
        if let Some(v) = self
            .filter_attenuation_db
            .filter(|v| !(-60.0..0.0).contains(v))
        {
            return Err(bad(
                "--filter-attenuation-db",
                v,
                "the prefilter gain at the antiresonance must lie in [-60, 0) dB",
            ));
        }
        if let Some(v) = self.pm_velocity {
            knobs.pm_velocity_deg = v;
        }
        if let Some(v) = self.pm_position {
            knobs.pm_position_deg = v;
        }
        if let Some(v) = self.resonance_suppression_db {
            knobs.resonance_suppression_db = v;
        }
        knobs.filter_attenuation_db = self.filter_attenuation_db;
        Ok(knobs)
    }

    /// The design rule: the thesis' with `--thesis-design`, exactly the knobs
    /// when any expert knob flag is given, else the robust rule
    /// ([`beltune::design::robust::DesignRule`]) at `--dynamics`.
    pub fn rule(&self) -> DesignRule {
        let explicit = self.prefilter.is_some()
            || self.pm_velocity.is_some()
            || self.pm_position.is_some()
            || self.resonance_suppression_db.is_some()
            || self.filter_attenuation_db.is_some();
        if self.thesis_design {
            DesignRule::Thesis
        } else if explicit {
            DesignRule::Knobs
        } else {
            DesignRule::Robust
        }
    }
}
