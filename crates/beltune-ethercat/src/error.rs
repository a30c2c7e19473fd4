//! The one error type of `beltune-ethercat`.

/// Everything this crate reports instead of panicking.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An object cannot be mapped as asked.
    #[error("PDO mapping of {index:#06x}:{sub_index:02x}: {reason}")]
    Mapping {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub_index: u8,
        /// Why not.
        reason: String,
    },
    /// A process-data buffer is shorter than its mapping.
    #[error("process data {what}: {got} bytes, the mapping needs {needed}")]
    ProcessDataLength {
        /// Inputs or outputs.
        what: &'static str,
        /// Bytes available.
        got: usize,
        /// Bytes needed.
        needed: usize,
    },
    /// A drive object has a value this axis cannot use.
    #[error("drive object {object} = {value}: {reason}")]
    BadObject {
        /// Which object (with its index and unit).
        object: &'static str,
        /// The value read.
        value: u64,
        /// Why it is not usable.
        reason: &'static str,
    },
    /// The EtherCAT master (ethercrab) reported an error.
    #[error("EtherCAT: {what}: {message}")]
    Bus {
        /// What was being done.
        what: String,
        /// ethercrab's message.
        message: String,
    },
    /// No SubDevice at the requested position.
    #[error("EtherCAT: no SubDevice {index} on the bus ({found} found)")]
    NoSubDevice {
        /// Requested position (0-based).
        index: usize,
        /// SubDevices found.
        found: usize,
    },
    /// The drive does not offer what the commissioning needs.
    #[error("drive {name}: {reason}")]
    Unsupported {
        /// The drive's name.
        name: String,
        /// What is missing.
        reason: String,
    },
    /// A raw socket could not be opened.
    #[error("cannot open a raw EtherCAT socket on `{interface}`: {message}{hint}")]
    Socket {
        /// The interface.
        interface: String,
        /// The OS error.
        message: String,
        /// A hint (root / CAP_NET_RAW) when the error is a permission error.
        hint: &'static str,
    },
    /// Bad configuration of the virtual drive or the axis.
    #[error("invalid {name}: {reason}")]
    Config {
        /// The setting.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// The simulator behind the virtual drive.
    #[error(transparent)]
    Sim(#[from] beltune::Error),
}

impl Error {
    pub(crate) fn bus(what: impl Into<String>, e: impl core::fmt::Display) -> Self {
        Error::Bus {
            what: what.into(),
            message: e.to_string(),
        }
    }
}
