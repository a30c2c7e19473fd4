//! The interface between the commissioning procedure and an axis: one cyclic
//! exchange per cycle (bus cycle or control interrupt), one torque command in,
//! one measurement out, which can fail. A simulated axis and a real drive (a
//! fieldbus master talking to a servo drive) implement the same trait, so the
//! procedure cannot tell them apart.

/// Static facts about an axis that a drive knows (from its configuration and data sheets).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AxisInfo {
    /// Cycle time of the exchange (the drive's control loop or the bus cycle),
    /// s (thesis: 100 us; a PC fieldbus master typically 250 us to 1 ms). Every
    /// sample count of the procedure is derived from it.
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

/// Why one cyclic exchange with the axis failed. Small and `Copy`, so that a
/// real-time loop can pass it on without allocating.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum AxisError {
    /// No valid answer for `cycles` consecutive cycles (lost frames, a
    /// timeout), more than the axis tolerates.
    #[error("no answer from the axis for {cycles} cycles (lost frames or timeout)")]
    Timeout {
        /// Consecutive cycles without an answer.
        cycles: u32,
    },
    /// The process data came back with a wrong working counter: a device did
    /// not read or write its data.
    #[error("working counter {received} instead of {expected}: a device did not exchange its process data")]
    WorkingCounter {
        /// Expected working counter.
        expected: u16,
        /// Received working counter.
        received: u16,
    },
    /// The drive reports a fault (CiA 402 state Fault), with its error code
    /// (object 0x603F).
    #[error("the drive reports fault 0x{error_code:04X}")]
    DriveFault {
        /// CiA 402 error code (0x603F).
        error_code: u16,
    },
    /// The drive is not (or no longer) in its operational state (CiA 402
    /// "Operation enabled", bus state OP).
    #[error("the drive is not operational")]
    NotOperational,
    /// The operator stopped the run (Ctrl-C, SIGTERM): the axis is
    /// quick-stopped like after a failure.
    #[error("stopped by the operator (SIGINT or SIGTERM)")]
    Interrupted,
}

/// An axis driven by one cyclic exchange per cycle: simulated or real.
pub trait Axis {
    /// Static facts about the axis (the cycle time among them).
    fn info(&self) -> AxisInfo;

    /// One cycle: apply `torque_command_nm` (the current-loop setpoint, N m)
    /// for one cycle and return what the drive measures at the end of it, or
    /// why the exchange failed. After an error the caller stops using the
    /// axis except for [`Axis::quick_stop`].
    fn exchange(&mut self, torque_command_nm: f64) -> Result<Measurement, AxisError>;

    /// Bring the axis to rest by the drive's own means (CiA 402 quick stop),
    /// without the host's controller: the reaction to a failed exchange. An
    /// axis without such a function removes the torque.
    fn quick_stop(&mut self) -> Result<(), AxisError>;

    /// Whether the axis' time runs in real time (a drive on a bus: the next
    /// cycle is due whether or not the host is ready), so that the procedure
    /// must keep exchanging, under a hold controller, while it computes. A
    /// simulated axis whose time only advances with [`Axis::exchange`] waits
    /// for the computation instead (the default).
    fn runs_in_real_time(&self) -> bool {
        false
    }
}
