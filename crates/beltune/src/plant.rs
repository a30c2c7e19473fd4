//! The interface between the commissioning procedure and an axis: one torque
//! command in, one measurement out, per sample. A simulated axis and a real
//! drive implement the same trait, so the procedure cannot tell them apart.

/// Static facts about an axis that a drive knows (from its configuration and data sheets).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AxisInfo {
    /// Sampling time of the drive's control loop, s (thesis: 100 us).
    pub ts_s: f64,
    /// Motor angle per encoder count, rad/count.
    pub motor_rad_per_count: f64,
    /// Largest torque command the drive accepts, N m (commands beyond are saturated).
    pub torque_max_nm: f64,
}

/// What the drive measures in one sample.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Measurement {
    /// Motor encoder position, counts (incremental, zero at power-up).
    pub motor_counts: i64,
    /// Actual motor torque, N m (measured current times torque constant, with
    /// the current-loop dead time and noise). Used for the dead-time estimate (3.27).
    pub torque_actual_nm: f64,
    /// Cart position from a linear encoder, m, when the axis has one. Simulated
    /// axes provide it for evaluation only; the commissioning never feeds it back.
    pub cart_position_m: Option<f64>,
}

/// An axis driven sample by sample: simulated or real.
pub trait Axis {
    /// Static facts about the axis.
    fn info(&self) -> AxisInfo;

    /// Apply `torque_command_nm` (the current-loop setpoint, N m) for one
    /// sample period and return what the drive measures at the end of it.
    fn step(&mut self, torque_command_nm: f64) -> Measurement;
}
