//! What the report shows, as plain data (filled by [`super::build`]).

use serde::Serialize;

/// One curve of a Bode diagram.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BodeCurve {
    /// Legend label.
    pub label: String,
    /// Frequencies, Hz (ascending, > 0).
    pub freq_hz: Vec<f64>,
    /// Magnitude, dB.
    pub magnitude_db: Vec<f64>,
    /// Phase, degrees (unwrapped).
    pub phase_deg: Vec<f64>,
    /// Drawn as dots (measured lines) instead of a connected line.
    #[serde(default)]
    pub dots: bool,
    /// Drawn dashed (a "before" or reference curve).
    #[serde(default)]
    pub dashed: bool,
    /// Colour: index into the report's palette (`None`: the curve's position in
    /// its plot), so that one run keeps one colour over several plots.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color_index: Option<usize>,
}

/// Which panel of a Bode diagram a point belongs to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Panel {
    /// Magnitude, dB.
    #[default]
    Magnitude,
    /// Phase, deg.
    Phase,
}

/// A labelled point (gain or phase margin) in a Bode diagram.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MarginPoint {
    /// Label, e.g. "PM 60.0 deg".
    pub label: String,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Value on the panel's axis (dB or deg).
    pub value: f64,
    /// The panel.
    pub panel: Panel,
}

/// A vertical marker in a Bode diagram (crossover, resonance, ...).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrequencyMarker {
    /// Label shown next to the marker.
    pub label: String,
    /// Frequency, Hz.
    pub freq_hz: f64,
}

/// A Bode diagram (magnitude over phase).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BodePlot {
    /// Title.
    pub title: String,
    /// Curves.
    pub curves: Vec<BodeCurve>,
    /// Vertical markers.
    pub markers: Vec<FrequencyMarker>,
    /// Horizontal reference lines in the magnitude panel (0 dB), dB.
    pub magnitude_lines_db: Vec<f64>,
    /// Horizontal reference lines in the phase panel (-180 deg), deg.
    pub phase_lines_deg: Vec<f64>,
    /// Margin points.
    pub points: Vec<MarginPoint>,
    /// Draw the magnitude panel only (closed loops, sensitivities).
    pub magnitude_only: bool,
}

/// The measured FRF with its coherence and the fitted model.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
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
    /// Unit of the input (the magnitude is in dB re 1 rad per this unit):
    /// "N m", or "A" for a current record; empty: "N m".
    pub input_unit: String,
}

/// Friction measurements and the fitted curve.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
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
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
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

/// The identification experiment: torque command and position over time
/// with the limits drawn.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ExcitationPlot {
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Torque command, N m.
    pub torque_nm: Vec<f64>,
    /// Time of the position samples, s.
    pub position_time_s: Vec<f64>,
    /// Motor-side position, m.
    pub position_m: Vec<f64>,
    /// Torque limit (drawn at +-), N m.
    pub torque_limit_nm: f64,
    /// Travel window, m.
    pub travel_min_m: f64,
    /// Travel window, m.
    pub travel_max_m: f64,
}

/// One row of the parameter table.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
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
    /// The "after" value at full precision, in `unit` (written as `data-value`
    /// so that tests and tools read the exact number).
    pub value: Option<f64>,
}

/// Everything the report page shows.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
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
    /// Pass/fail per limit, warnings and the next step (shown first).
    pub verdict: Option<crate::verdict::Verdict>,
    /// Version, date, command line and seed of the run.
    pub provenance: Option<crate::record::provenance::Provenance>,
    /// Closed loops and sensitivities (magnitude).
    pub closed_loops: Vec<BodePlot>,
    /// Before/after overlays (e.g. the bootstrap against the designed controller).
    pub overlays: Vec<BodePlot>,
    /// The identification experiment.
    pub excitation: Option<ExcitationPlot>,
    /// Data files beside the report (names), with what they hold.
    pub data_files: Vec<(String, String)>,
    /// Extra tables (title, header, rows), e.g. the parameter changes of a comparison.
    pub tables: Vec<Table>,
    /// Trends of quantities over an axis' runs (`beltune history --html`).
    pub trends: Vec<TrendPlot>,
}

/// A table of text cells.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Table {
    /// Heading above the table.
    pub title: String,
    /// Column headers.
    pub header: Vec<String>,
    /// Rows of cells.
    pub rows: Vec<Vec<String>>,
}

/// One quantity's trend over an axis' runs (`beltune history --html`):
/// values in the quantity's unit, the runs numbered oldest first.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TrendPlot {
    /// Title (the quantity in words and its unit).
    pub title: String,
    /// Unit of the values.
    pub unit: String,
    /// Run numbers of the commissionings.
    pub commissioning_run: Vec<f64>,
    /// Their values.
    pub commissioning_value: Vec<f64>,
    /// Run numbers of the health checks.
    pub health_run: Vec<f64>,
    /// Their values.
    pub health_value: Vec<f64>,
    /// Their one-sigma uncertainties (NaN: unknown).
    pub health_sigma: Vec<f64>,
    /// The baseline of the latest health check, if any.
    pub baseline: Option<f64>,
    /// Its limits as values (label, value), where there are.
    pub limits: Vec<(String, f64)>,
}
