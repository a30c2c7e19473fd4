//! The CiA 402 (IEC 61800-7-201) power drive system state machine: the
//! statusword 0x6041 decoded into its state, the controlword 0x6040 commands,
//! the drive-side transitions (what a drive does with a controlword; the
//! virtual drive runs them) and the master-side sequence that brings a drive
//! from any state to "operation enabled".
//!
//! Statusword bits: 0 ready to switch on, 1 switched on, 2 operation enabled,
//! 3 fault, 4 voltage enabled, 5 quick stop (active low), 6 switch on disabled,
//! 7 warning, 9 remote, 12-13 mode specific. Controlword bits: 0 switch on,
//! 1 enable voltage, 2 quick stop (active low), 3 enable operation, 7 fault reset.

/// Object index of the controlword.
pub const CONTROLWORD: u16 = 0x6040;
/// Object index of the statusword.
pub const STATUSWORD: u16 = 0x6041;
/// Object index of the modes of operation.
pub const MODES_OF_OPERATION: u16 = 0x6060;
/// Object index of the modes of operation display.
pub const MODES_OF_OPERATION_DISPLAY: u16 = 0x6061;
/// Object index of the error code (CiA 402 / CiA 301 emergency codes).
pub const ERROR_CODE: u16 = 0x603F;
/// Object index of the supported drive modes (bit 9: CST).
pub const SUPPORTED_DRIVE_MODES: u16 = 0x6502;

/// Mode of operation: cyclic synchronous torque (CST).
pub const MODE_CST: i8 = 10;
/// Mode of operation: cyclic synchronous position (CSP): the drive closes
/// its position and velocity loops.
pub const MODE_CSP: i8 = 8;

/// Statusword bit: remote (the drive accepts the controlword from the bus).
pub const SW_REMOTE: u16 = 1 << 9;
/// Statusword bit: warning.
pub const SW_WARNING: u16 = 1 << 7;
/// Statusword bit: voltage enabled.
pub const SW_VOLTAGE_ENABLED: u16 = 1 << 4;
/// Statusword bit (CSx modes): the drive follows the target value.
pub const SW_FOLLOWS_TARGET: u16 = 1 << 12;

/// States of the power drive system (CiA 402 figure "state machine").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    /// Initialising; no command is accepted.
    NotReadyToSwitchOn,
    /// Power stage off; waits for "shutdown".
    SwitchOnDisabled,
    /// High voltage may be applied; power stage off.
    ReadyToSwitchOn,
    /// Power stage on, no torque.
    SwitchedOn,
    /// Torque follows the command.
    OperationEnabled,
    /// The quick stop function runs (the drive brakes the axis).
    QuickStopActive,
    /// A fault was detected; the drive reacts (removes torque).
    FaultReactionActive,
    /// Fault; waits for a fault reset.
    Fault,
}

impl State {
    /// Decode a statusword (the masks of CiA 402 table "state coding").
    pub fn from_statusword(sw: u16) -> State {
        match (sw & 0x004F, sw & 0x006F) {
            (0x0000, _) => State::NotReadyToSwitchOn,
            (0x0040, _) => State::SwitchOnDisabled,
            (0x000F, _) => State::FaultReactionActive,
            (0x0008, _) => State::Fault,
            (_, 0x0021) => State::ReadyToSwitchOn,
            (_, 0x0023) => State::SwitchedOn,
            (_, 0x0027) => State::OperationEnabled,
            (_, 0x0007) => State::QuickStopActive,
            // Bit combinations outside the table: treat as not ready.
            _ => State::NotReadyToSwitchOn,
        }
    }

    /// The state bits of the statusword (bits 0-3, 5, 6) for this state.
    pub fn statusword_bits(self) -> u16 {
        match self {
            State::NotReadyToSwitchOn => 0x0000,
            State::SwitchOnDisabled => 0x0040,
            State::ReadyToSwitchOn => 0x0021,
            State::SwitchedOn => 0x0023,
            State::OperationEnabled => 0x0027,
            State::QuickStopActive => 0x0007,
            State::FaultReactionActive => 0x000F,
            State::Fault => 0x0008,
        }
    }

    /// Whether the power stage produces torque in this state.
    pub fn torque_enabled(self) -> bool {
        matches!(self, State::OperationEnabled | State::QuickStopActive)
    }

    /// A short name for messages.
    pub fn name(self) -> &'static str {
        match self {
            State::NotReadyToSwitchOn => "not ready to switch on",
            State::SwitchOnDisabled => "switch on disabled",
            State::ReadyToSwitchOn => "ready to switch on",
            State::SwitchedOn => "switched on",
            State::OperationEnabled => "operation enabled",
            State::QuickStopActive => "quick stop active",
            State::FaultReactionActive => "fault reaction active",
            State::Fault => "fault",
        }
    }
}

impl core::fmt::Display for State {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Device-control commands (CiA 402 table "command coding").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// Transitions 2, 6, 8: to "ready to switch on".
    Shutdown,
    /// Transition 3: to "switched on".
    SwitchOn,
    /// Transitions 4, 16 (and 3 + 4 at once): to "operation enabled".
    EnableOperation,
    /// Transition 5: back to "switched on".
    DisableOperation,
    /// Transitions 7, 9, 10, 12: power stage off.
    DisableVoltage,
    /// Transitions 7, 10, 11: quick stop.
    QuickStop,
    /// Transition 15 (rising edge of bit 7): leave "fault".
    FaultReset,
}

impl Command {
    /// The controlword for this command (bits 0-3 and 7).
    pub fn controlword(self) -> u16 {
        match self {
            Command::Shutdown => 0x0006,
            Command::SwitchOn => 0x0007,
            Command::EnableOperation => 0x000F,
            Command::DisableOperation => 0x0007,
            Command::DisableVoltage => 0x0000,
            Command::QuickStop => 0x0002,
            Command::FaultReset => 0x0080,
        }
    }

    /// Decode a controlword as a drive does. Bit 7 is a fault reset only on its
    /// rising edge (`previous` is the controlword of the cycle before).
    /// "Switch on" and "disable operation" share a code; the drive's current
    /// state tells them apart ([`drive_transition`]).
    pub fn from_controlword(cw: u16, previous: u16) -> Command {
        if cw & 0x0080 != 0 && previous & 0x0080 == 0 {
            return Command::FaultReset;
        }
        if cw & 0x0002 == 0 {
            Command::DisableVoltage
        } else if cw & 0x0004 == 0 {
            Command::QuickStop
        } else if cw & 0x0001 == 0 {
            Command::Shutdown
        } else if cw & 0x0008 == 0 {
            Command::SwitchOn
        } else {
            Command::EnableOperation
        }
    }
}

/// What a drive does with a command in a state (CiA 402 transitions 2-12, 15,
/// 16). Automatic transitions (0, 1, 13, 14 and the end of a quick stop) are the
/// drive's own business and not in this table. `SwitchOn` from "operation
/// enabled" is "disable operation" (transition 5).
pub fn drive_transition(state: State, command: Command) -> State {
    use Command as C;
    use State as S;
    match (state, command) {
        (S::SwitchOnDisabled, C::Shutdown) => S::ReadyToSwitchOn, // 2
        (S::ReadyToSwitchOn, C::SwitchOn) => S::SwitchedOn,       // 3
        // 3 + 4: "enable operation" from "ready to switch on" passes "switched on"
        (S::ReadyToSwitchOn, C::EnableOperation) => S::OperationEnabled,
        (S::SwitchedOn, C::EnableOperation) => S::OperationEnabled, // 4
        (S::OperationEnabled, C::SwitchOn | C::DisableOperation) => S::SwitchedOn, // 5
        (S::SwitchedOn, C::Shutdown) => S::ReadyToSwitchOn,         // 6
        (S::ReadyToSwitchOn, C::QuickStop | C::DisableVoltage) => S::SwitchOnDisabled, // 7
        (S::OperationEnabled, C::Shutdown) => S::ReadyToSwitchOn,   // 8
        (S::OperationEnabled, C::DisableVoltage) => S::SwitchOnDisabled, // 9
        (S::SwitchedOn, C::DisableVoltage | C::QuickStop) => S::SwitchOnDisabled, // 10
        (S::OperationEnabled, C::QuickStop) => S::QuickStopActive,  // 11
        (S::QuickStopActive, C::DisableVoltage) => S::SwitchOnDisabled, // 12
        (S::QuickStopActive, C::EnableOperation) => S::OperationEnabled, // 16
        (S::Fault, C::FaultReset) => S::SwitchOnDisabled,           // 15
        (s, _) => s,
    }
}

/// The next controlword on the way from `state` to "operation enabled", one
/// transition per cycle (2, 3, 4 or 15). `previous` is the controlword sent in
/// the cycle before: a fault reset needs a rising edge of bit 7, so after a
/// reset the master first sends "disable voltage" again. Returns `None` in the
/// states where the master can only wait (not ready, fault reaction, quick stop).
pub fn next_command_towards_enabled(state: State, previous: u16) -> Option<u16> {
    match state {
        State::Fault => Some(if previous & 0x0080 != 0 {
            Command::DisableVoltage.controlword()
        } else {
            Command::FaultReset.controlword()
        }),
        State::SwitchOnDisabled => Some(Command::Shutdown.controlword()),
        State::ReadyToSwitchOn => Some(Command::SwitchOn.controlword()),
        State::SwitchedOn | State::OperationEnabled => Some(Command::EnableOperation.controlword()),
        State::NotReadyToSwitchOn | State::FaultReactionActive | State::QuickStopActive => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [State; 8] = [
        State::NotReadyToSwitchOn,
        State::SwitchOnDisabled,
        State::ReadyToSwitchOn,
        State::SwitchedOn,
        State::OperationEnabled,
        State::QuickStopActive,
        State::FaultReactionActive,
        State::Fault,
    ];

    #[test]
    fn statusword_codes_of_the_standard_decode_to_their_states() {
        // CiA 402 table "state coding", with unrelated bits set (voltage
        // enabled, remote, warning, mode-specific) that must not matter.
        let table = [
            (0x0000, State::NotReadyToSwitchOn),
            (0x0040, State::SwitchOnDisabled),
            (0x0021, State::ReadyToSwitchOn),
            (0x0023, State::SwitchedOn),
            (0x0027, State::OperationEnabled),
            (0x0007, State::QuickStopActive),
            (0x000F, State::FaultReactionActive),
            (0x0008, State::Fault),
        ];
        for (sw, st) in table {
            for extra in [
                0,
                SW_REMOTE,
                SW_VOLTAGE_ENABLED | SW_REMOTE,
                SW_WARNING | SW_FOLLOWS_TARGET,
            ] {
                assert_eq!(
                    State::from_statusword(sw | extra),
                    st,
                    "{sw:#06x} | {extra:#06x}"
                );
            }
            // A fault state keeps its meaning whatever bit 5 says.
            if matches!(
                st,
                State::Fault | State::FaultReactionActive | State::SwitchOnDisabled
            ) {
                assert_eq!(State::from_statusword(sw | 0x0020), st);
            }
        }
        for st in ALL {
            assert_eq!(State::from_statusword(st.statusword_bits()), st);
        }
    }

    #[test]
    fn controlword_codes_decode_to_their_commands() {
        for (cw, cmd) in [
            (0x0006, Command::Shutdown),
            (0x0007, Command::SwitchOn),
            (0x000F, Command::EnableOperation),
            (0x0000, Command::DisableVoltage),
            (0x0001, Command::DisableVoltage),
            (0x0008, Command::DisableVoltage),
            (0x0002, Command::QuickStop),
            (0x000B, Command::QuickStop),
        ] {
            assert_eq!(Command::from_controlword(cw, 0), cmd, "{cw:#06x}");
        }
        // fault reset only on the rising edge of bit 7
        assert_eq!(
            Command::from_controlword(0x0080, 0x0000),
            Command::FaultReset
        );
        assert_eq!(
            Command::from_controlword(0x0080, 0x0080),
            Command::DisableVoltage
        );
        for cmd in [
            Command::Shutdown,
            Command::SwitchOn,
            Command::EnableOperation,
            Command::DisableVoltage,
            Command::QuickStop,
        ] {
            assert_eq!(Command::from_controlword(cmd.controlword(), 0), cmd);
        }
    }

    #[test]
    fn the_master_sequence_reaches_operation_enabled_from_every_state_the_master_can_leave() {
        for start in [
            State::Fault,
            State::SwitchOnDisabled,
            State::ReadyToSwitchOn,
            State::SwitchedOn,
        ] {
            let mut st = start;
            let mut prev = 0u16;
            let mut steps = 0;
            while st != State::OperationEnabled {
                let cw = next_command_towards_enabled(st, prev).expect("the master can act");
                st = drive_transition(st, Command::from_controlword(cw, prev));
                prev = cw;
                steps += 1;
                assert!(steps < 8, "no progress from {start}");
            }
            // fault: reset (15), shutdown (2), switch on (3), enable (4)
            let expected = match start {
                State::Fault => 4,
                State::SwitchOnDisabled => 3,
                State::ReadyToSwitchOn => 2,
                _ => 1,
            };
            assert_eq!(steps, expected, "from {start}");
        }
        for st in [
            State::NotReadyToSwitchOn,
            State::FaultReactionActive,
            State::QuickStopActive,
        ] {
            assert_eq!(next_command_towards_enabled(st, 0), None);
        }
    }

    #[test]
    fn a_repeated_fault_reset_bit_needs_a_new_edge() {
        // The master held bit 7 from the cycle before: it must drop it first.
        let cw = next_command_towards_enabled(State::Fault, 0x0080).unwrap();
        assert_eq!(cw & 0x0080, 0);
        assert_eq!(
            drive_transition(State::Fault, Command::from_controlword(0x0080, 0x0080)),
            State::Fault
        );
    }

    #[test]
    fn quick_stop_and_disable_transitions() {
        use Command as C;
        use State as S;
        assert_eq!(
            drive_transition(S::OperationEnabled, C::QuickStop),
            S::QuickStopActive
        ); // 11
        assert_eq!(
            drive_transition(S::QuickStopActive, C::DisableVoltage),
            S::SwitchOnDisabled
        ); // 12
        assert_eq!(
            drive_transition(S::QuickStopActive, C::EnableOperation),
            S::OperationEnabled
        ); // 16
        assert_eq!(
            drive_transition(S::QuickStopActive, C::Shutdown),
            S::QuickStopActive
        );
        assert_eq!(
            drive_transition(S::OperationEnabled, C::Shutdown),
            S::ReadyToSwitchOn
        ); // 8
        assert_eq!(
            drive_transition(S::OperationEnabled, C::DisableVoltage),
            S::SwitchOnDisabled
        ); // 9
        assert_eq!(
            drive_transition(S::OperationEnabled, C::SwitchOn),
            S::SwitchedOn
        ); // 5
        assert_eq!(
            drive_transition(S::SwitchedOn, C::QuickStop),
            S::SwitchOnDisabled
        ); // 10
        assert_eq!(
            drive_transition(S::ReadyToSwitchOn, C::QuickStop),
            S::SwitchOnDisabled
        ); // 7
           // A fault is left only by a reset, whatever else is commanded.
        for c in [
            C::Shutdown,
            C::SwitchOn,
            C::EnableOperation,
            C::QuickStop,
            C::DisableVoltage,
        ] {
            assert_eq!(drive_transition(S::Fault, c), S::Fault);
        }
        // A fault reset does nothing outside "fault".
        assert_eq!(
            drive_transition(S::OperationEnabled, C::FaultReset),
            S::OperationEnabled
        );
        // Torque only where the standard allows it.
        let with_torque: Vec<_> = ALL.iter().filter(|s| s.torque_enabled()).collect();
        assert_eq!(with_torque, [&S::OperationEnabled, &S::QuickStopActive]);
    }
}
