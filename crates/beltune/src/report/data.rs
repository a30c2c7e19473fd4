//! What the report shows, as plain data (filled by the commissioning procedure).

use serde::Serialize;

/// One curve of a Bode diagram.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BodeCurve {
    /// Legend label.
    pub label: String,
    /// Frequencies, Hz (ascending, > 0).
    pub freq_hz: Vec<f64>,
    /// Magnitude, dB.
    pub magnitude_db: Vec<f64>,
    /// Phase, degrees (unwrapped).
    pub phase_deg: Vec<f64>,
}

/// A vertical marker in a Bode diagram (crossover, resonance, ...).
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrequencyMarker {
    /// Label shown next to the marker.
    pub label: String,
    /// Frequency, Hz.
    pub freq_hz: f64,
}

/// A Bode diagram (magnitude over phase).
#[derive(Clone, Debug, Default, Serialize)]
pub struct BodePlot {
    /// Title.
    pub title: String,
    /// Curves.
    pub curves: Vec<BodeCurve>,
    /// Vertical markers.
    pub markers: Vec<FrequencyMarker>,
}

/// The measured FRF with its coherence and the fitted model.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrfPlot {
    /// Measured FRF (all lines; unusable lines are drawn grey).
    pub measured: BodeCurve,
    /// `true` where the line was used by the fit.
    pub usable: Vec<bool>,
    /// Magnitude-squared coherence per measured line, 0..1.
    pub coherence: Vec<f64>,
    /// The fitted model (with dead time), evaluated on a log grid.
    pub model: BodeCurve,
    /// Resonance / antiresonance markers.
    pub markers: Vec<FrequencyMarker>,
}

/// Friction measurements and the fitted curve.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrictionPlot {
    /// Motor velocity of each constant-velocity run, rad/s.
    pub velocity_rad_s: Vec<f64>,
    /// Mean torque of each run, N m.
    pub torque_nm: Vec<f64>,
    /// Fitted viscous coefficient, N m s/rad.
    pub viscous_nm_s_per_rad: f64,
    /// Fitted Coulomb torque, N m.
    pub coulomb_nm: f64,
}

/// One validation move.
#[derive(Clone, Debug, Default, Serialize)]
pub struct MovePlot {
    /// Label (e.g. "nonlinear feedforward").
    pub label: String,
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Desired cart position, m.
    pub desired_m: Vec<f64>,
    /// Cart tracking error `xi_d - xi`, m (simulation truth; empty for a real axis without cart encoder).
    pub cart_error_m: Vec<f64>,
    /// Motor-side tracking error `xi_d - i_t phi_m`, m.
    pub motor_error_m: Vec<f64>,
    /// Torque command, N m.
    pub torque_nm: Vec<f64>,
}

/// One row of the parameter table.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ParameterRow {
    /// Quantity, with symbol.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Value before commissioning (data sheet / default), if any.
    pub before: Option<String>,
    /// Value after commissioning.
    pub after: String,
    /// True value of a simulated plant, if known.
    pub truth: Option<String>,
}

/// Everything the report page shows.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Report {
    /// Page title.
    pub title: String,
    /// One-paragraph summary (plain text).
    pub summary: String,
    /// Log of the commissioning stages (one line each).
    pub log: Vec<String>,
    /// Measured FRF and fitted model.
    pub frf: Option<FrfPlot>,
    /// Controller frequency response (prefilter and PI).
    pub controller: Option<BodePlot>,
    /// Open loops of the velocity and position loops with margins marked.
    pub open_loops: Vec<BodePlot>,
    /// Friction curve.
    pub friction: Option<FrictionPlot>,
    /// Validation moves (no / linear / nonlinear feedforward).
    pub moves: Vec<MovePlot>,
    /// Parameter table, before / after.
    pub parameters: Vec<ParameterRow>,
    /// Validation summary table rows: (variant, max error, static error, settling time) as text.
    pub validation_rows: Vec<[String; 4]>,
}
