//! Process data: the objects the axis exchanges every cycle, their PDO mapping
//! entries (`index << 16 | sub << 8 | bits`, CiA 301) and the codec that packs
//! the outputs and unpacks the inputs of one cycle (little endian, byte
//! aligned, in mapping order) for any mapping built from these objects.

use crate::cia402::{
    CONTROLWORD, ERROR_CODE, MODES_OF_OPERATION, MODES_OF_OPERATION_DISPLAY, STATUSWORD,
};
use crate::Error;

/// Target torque, per mille of the rated torque (i16).
pub const TARGET_TORQUE: u16 = 0x6071;
/// Position actual value, increments (i32, wraps).
pub const POSITION_ACTUAL: u16 = 0x6064;
/// Velocity actual value, increments per second (i32).
pub const VELOCITY_ACTUAL: u16 = 0x606C;
/// Torque actual value, per mille of the rated torque (i16).
pub const TORQUE_ACTUAL: u16 = 0x6077;
/// Additional position actual value (array; sub-index 1: the load-side
/// encoder on the cart), load increments (i32, wraps).
pub const ADDITIONAL_POSITION_ACTUAL: u16 = 0x60E4;

/// RxPDO (master to drive) mapping object used by the axis.
pub const RX_PDO: u16 = 0x1600;
/// TxPDO (drive to master) mapping object used by the axis.
pub const TX_PDO: u16 = 0x1A00;
/// Sync manager 2 PDO assignment (outputs).
pub const SM2_ASSIGN: u16 = 0x1C12;
/// Sync manager 3 PDO assignment (inputs).
pub const SM3_ASSIGN: u16 = 0x1C13;

/// One mapped object: index, sub-index and length in bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MappingEntry {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub_index: u8,
    /// Length, bits (a multiple of 8 here: byte-aligned mapping).
    pub bits: u8,
}

impl MappingEntry {
    /// An entry.
    pub const fn new(index: u16, sub_index: u8, bits: u8) -> Self {
        MappingEntry {
            index,
            sub_index,
            bits,
        }
    }

    /// The 32-bit value written to a mapping sub-index (CiA 301).
    pub fn to_u32(self) -> u32 {
        (u32::from(self.index) << 16) | (u32::from(self.sub_index) << 8) | u32::from(self.bits)
    }

    /// Decode a mapping sub-index value.
    pub fn from_u32(v: u32) -> Self {
        MappingEntry {
            index: (v >> 16) as u16,
            sub_index: (v >> 8) as u8,
            bits: v as u8,
        }
    }
}

/// The outputs the axis maps (RxPDO): controlword, mode, target torque.
pub const OUTPUTS: [MappingEntry; 3] = [
    MappingEntry::new(CONTROLWORD, 0, 16),
    MappingEntry::new(MODES_OF_OPERATION, 0, 8),
    MappingEntry::new(TARGET_TORQUE, 0, 16),
];

/// The inputs the axis maps (TxPDO) without a load-side encoder.
pub const INPUTS: [MappingEntry; 6] = [
    MappingEntry::new(STATUSWORD, 0, 16),
    MappingEntry::new(MODES_OF_OPERATION_DISPLAY, 0, 8),
    MappingEntry::new(POSITION_ACTUAL, 0, 32),
    MappingEntry::new(VELOCITY_ACTUAL, 0, 32),
    MappingEntry::new(TORQUE_ACTUAL, 0, 16),
    MappingEntry::new(ERROR_CODE, 0, 16),
];

/// The outputs appended to [`OUTPUTS`] for cyclic synchronous position
/// (CSP): target position 0x607A and velocity offset 0x60B1.
pub const CSP_OUTPUTS: [MappingEntry; 2] = [
    MappingEntry::new(0x607A, 0, 32),
    MappingEntry::new(0x60B1, 0, 32),
];

/// The load-side position entry appended to [`INPUTS`] when the drive has it.
pub const LOAD_POSITION: MappingEntry = MappingEntry::new(ADDITIONAL_POSITION_ACTUAL, 1, 32);

/// Byte layout of a mapping: the offset of every entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    entries: Vec<(MappingEntry, usize)>,
    len: usize,
}

impl Layout {
    /// The layout of `entries` in order. Error for a length that is not a whole
    /// number of bytes (this codec maps byte-aligned objects only).
    pub fn new(entries: &[MappingEntry]) -> Result<Self, Error> {
        let mut offset = 0;
        let mut out = Vec::with_capacity(entries.len());
        for e in entries {
            if e.bits == 0 || e.bits % 8 != 0 || e.bits > 64 {
                return Err(Error::Mapping {
                    index: e.index,
                    sub_index: e.sub_index,
                    reason: format!("{} bits is not a whole number of bytes up to 8", e.bits),
                });
            }
            out.push((*e, offset));
            offset += usize::from(e.bits / 8);
        }
        Ok(Layout {
            entries: out,
            len: offset,
        })
    }

    /// Length, bytes.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is mapped.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The mapped entries.
    pub fn entries(&self) -> impl Iterator<Item = MappingEntry> + '_ {
        self.entries.iter().map(|(e, _)| *e)
    }

    /// Byte offset and length of an object, if mapped.
    pub fn find(&self, index: u16, sub_index: u8) -> Option<(usize, usize)> {
        self.entries
            .iter()
            .find(|(e, _)| e.index == index && e.sub_index == sub_index)
            .map(|(e, o)| (*o, usize::from(e.bits / 8)))
    }

    /// Read an object as a raw little-endian value (zero-extended to u64).
    pub fn get(&self, buf: &[u8], index: u16, sub_index: u8) -> Option<u64> {
        let (o, n) = self.find(index, sub_index)?;
        let bytes = buf.get(o..o + n)?;
        let mut v = 0u64;
        for (i, b) in bytes.iter().enumerate() {
            v |= u64::from(*b) << (8 * i);
        }
        Some(v)
    }

    /// Write an object (the low bytes of `value`); false if not mapped or `buf` too short.
    pub fn set(&self, buf: &mut [u8], index: u16, sub_index: u8, value: u64) -> bool {
        let Some((o, n)) = self.find(index, sub_index) else {
            return false;
        };
        let Some(bytes) = buf.get_mut(o..o + n) else {
            return false;
        };
        for (i, b) in bytes.iter_mut().enumerate() {
            *b = (value >> (8 * i)) as u8;
        }
        true
    }
}

/// The outputs of one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// Controlword 0x6040.
    pub controlword: u16,
    /// Modes of operation 0x6060.
    pub mode: i8,
    /// Target torque 0x6071, per mille of the rated torque.
    pub target_torque_permille: i16,
    /// Target position 0x607A (CSP), increments, when mapped.
    pub target_position_inc: i32,
    /// Velocity offset 0x60B1 (CSP), increments/s, when mapped.
    pub velocity_offset_inc_s: i32,
}

/// The inputs of one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    /// Statusword 0x6041.
    pub statusword: u16,
    /// Modes of operation display 0x6061.
    pub mode_display: i8,
    /// Position actual 0x6064, increments (wrapping).
    pub position_inc: i32,
    /// Velocity actual 0x606C, increments/s.
    pub velocity_inc_s: i32,
    /// Torque actual 0x6077, per mille of the rated torque.
    pub torque_permille: i16,
    /// Error code 0x603F.
    pub error_code: u16,
    /// Load-side position 0x60E4:01, load increments (wrapping), when mapped.
    pub load_position_inc: Option<i32>,
}

/// Pack and unpack the axis' process data for a pair of layouts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Codec {
    /// Output (RxPDO) layout.
    pub outputs: Layout,
    /// Input (TxPDO) layout.
    pub inputs: Layout,
}

impl Codec {
    /// A codec; error if a layout lacks an object the axis needs.
    pub fn new(outputs: Layout, inputs: Layout) -> Result<Self, Error> {
        for e in OUTPUTS {
            if outputs.find(e.index, e.sub_index).is_none() {
                return Err(Error::Mapping {
                    index: e.index,
                    sub_index: e.sub_index,
                    reason: "not in the output mapping".into(),
                });
            }
        }
        for e in INPUTS {
            if inputs.find(e.index, e.sub_index).is_none() {
                return Err(Error::Mapping {
                    index: e.index,
                    sub_index: e.sub_index,
                    reason: "not in the input mapping".into(),
                });
            }
        }
        Ok(Codec { outputs, inputs })
    }

    /// The codec of the axis' mapping with the CSP outputs ([`CSP_OUTPUTS`])
    /// after [`OUTPUTS`].
    pub fn with_csp(load_position: bool) -> Self {
        let mut c = Self::standard(load_position);
        let mut out = OUTPUTS.to_vec();
        out.extend_from_slice(&CSP_OUTPUTS);
        c.outputs = Layout::new(&out).expect("byte-aligned mapping");
        c
    }

    /// The codec of the axis' own mapping ([`OUTPUTS`], [`INPUTS`], the load
    /// position when `load_position`).
    pub fn standard(load_position: bool) -> Self {
        let mut inputs = INPUTS.to_vec();
        if load_position {
            inputs.push(LOAD_POSITION);
        }
        Codec {
            outputs: Layout::new(&OUTPUTS).expect("byte-aligned mapping"),
            inputs: Layout::new(&inputs).expect("byte-aligned mapping"),
        }
    }

    /// Pack outputs into `buf` (at least `outputs.len()` bytes).
    pub fn pack_outputs(&self, o: &Outputs, buf: &mut [u8]) -> Result<(), Error> {
        self.check_len("outputs", buf.len(), self.outputs.len())?;
        let l = &self.outputs;
        l.set(buf, CONTROLWORD, 0, u64::from(o.controlword));
        l.set(buf, MODES_OF_OPERATION, 0, o.mode as u8 as u64);
        l.set(
            buf,
            TARGET_TORQUE,
            0,
            o.target_torque_permille as u16 as u64,
        );
        let [p, v] = CSP_OUTPUTS;
        l.set(buf, p.index, 0, o.target_position_inc as u32 as u64);
        l.set(buf, v.index, 0, o.velocity_offset_inc_s as u32 as u64);
        Ok(())
    }

    /// Unpack outputs (the drive's side).
    pub fn unpack_outputs(&self, buf: &[u8]) -> Result<Outputs, Error> {
        self.check_len("outputs", buf.len(), self.outputs.len())?;
        let l = &self.outputs;
        Ok(Outputs {
            controlword: l.get(buf, CONTROLWORD, 0).unwrap_or(0) as u16,
            mode: l.get(buf, MODES_OF_OPERATION, 0).unwrap_or(0) as u8 as i8,
            target_torque_permille: l.get(buf, TARGET_TORQUE, 0).unwrap_or(0) as u16 as i16,
            target_position_inc: l.get(buf, CSP_OUTPUTS[0].index, 0).unwrap_or(0) as u32 as i32,
            velocity_offset_inc_s: l.get(buf, CSP_OUTPUTS[1].index, 0).unwrap_or(0) as u32 as i32,
        })
    }

    /// Pack inputs (the drive's side).
    pub fn pack_inputs(&self, i: &Inputs, buf: &mut [u8]) -> Result<(), Error> {
        self.check_len("inputs", buf.len(), self.inputs.len())?;
        let l = &self.inputs;
        l.set(buf, STATUSWORD, 0, u64::from(i.statusword));
        l.set(
            buf,
            MODES_OF_OPERATION_DISPLAY,
            0,
            i.mode_display as u8 as u64,
        );
        l.set(buf, POSITION_ACTUAL, 0, i.position_inc as u32 as u64);
        l.set(buf, VELOCITY_ACTUAL, 0, i.velocity_inc_s as u32 as u64);
        l.set(buf, TORQUE_ACTUAL, 0, i.torque_permille as u16 as u64);
        l.set(buf, ERROR_CODE, 0, u64::from(i.error_code));
        if let Some(p) = i.load_position_inc {
            l.set(
                buf,
                LOAD_POSITION.index,
                LOAD_POSITION.sub_index,
                p as u32 as u64,
            );
        }
        Ok(())
    }

    /// Unpack inputs (the master's side).
    pub fn unpack_inputs(&self, buf: &[u8]) -> Result<Inputs, Error> {
        self.check_len("inputs", buf.len(), self.inputs.len())?;
        let l = &self.inputs;
        Ok(Inputs {
            statusword: l.get(buf, STATUSWORD, 0).unwrap_or(0) as u16,
            mode_display: l.get(buf, MODES_OF_OPERATION_DISPLAY, 0).unwrap_or(0) as u8 as i8,
            position_inc: l.get(buf, POSITION_ACTUAL, 0).unwrap_or(0) as u32 as i32,
            velocity_inc_s: l.get(buf, VELOCITY_ACTUAL, 0).unwrap_or(0) as u32 as i32,
            torque_permille: l.get(buf, TORQUE_ACTUAL, 0).unwrap_or(0) as u16 as i16,
            error_code: l.get(buf, ERROR_CODE, 0).unwrap_or(0) as u16,
            load_position_inc: l
                .get(buf, LOAD_POSITION.index, LOAD_POSITION.sub_index)
                .map(|v| v as u32 as i32),
        })
    }

    fn check_len(&self, what: &'static str, got: usize, needed: usize) -> Result<(), Error> {
        if got < needed {
            Err(Error::ProcessDataLength { what, got, needed })
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_standard_mapping_has_the_sizes_and_offsets_of_the_objects() {
        let c = Codec::standard(true);
        assert_eq!(c.outputs.len(), 2 + 1 + 2);
        assert_eq!(c.inputs.len(), 2 + 1 + 4 + 4 + 2 + 2 + 4);
        assert_eq!(c.outputs.find(TARGET_TORQUE, 0), Some((3, 2)));
        assert_eq!(c.inputs.find(POSITION_ACTUAL, 0), Some((3, 4)));
        assert_eq!(c.inputs.find(ADDITIONAL_POSITION_ACTUAL, 1), Some((15, 4)));
        assert_eq!(Codec::standard(false).inputs.len(), 15);
    }

    #[test]
    fn mapping_entries_encode_as_cia301_says() {
        // 0x6040:00, 16 bit -> 0x60400010 (CiA 301 PDO mapping parameter)
        assert_eq!(MappingEntry::new(0x6040, 0, 16).to_u32(), 0x6040_0010);
        assert_eq!(MappingEntry::new(0x60E4, 1, 32).to_u32(), 0x60E4_0120);
        assert_eq!(
            MappingEntry::from_u32(0x6071_0010),
            MappingEntry::new(0x6071, 0, 16)
        );
    }

    #[test]
    fn a_known_frame_decodes_byte_by_byte() {
        let c = Codec::standard(false);
        // statusword 0x1237, mode 10, position -2 (0xFFFFFFFE), velocity 1000,
        // torque -500 per mille (0xFE0C), error 0x7500
        let buf = [
            0x37, 0x12, 0x0A, 0xFE, 0xFF, 0xFF, 0xFF, 0xE8, 0x03, 0x00, 0x00, 0x0C, 0xFE, 0x00,
            0x75,
        ];
        let i = c.unpack_inputs(&buf).unwrap();
        assert_eq!(i.statusword, 0x1237);
        assert_eq!(i.mode_display, 10);
        assert_eq!(i.position_inc, -2);
        assert_eq!(i.velocity_inc_s, 1000);
        assert_eq!(i.torque_permille, -500);
        assert_eq!(i.error_code, 0x7500);
        assert_eq!(i.load_position_inc, None);
        let mut out = [0u8; 5];
        c.pack_outputs(
            &Outputs {
                controlword: 0x000F,
                mode: 10,
                target_torque_permille: -1,
                ..Outputs::default()
            },
            &mut out,
        )
        .unwrap();
        assert_eq!(out, [0x0F, 0x00, 0x0A, 0xFF, 0xFF]);
    }

    #[test]
    fn short_buffers_and_missing_objects_are_errors() {
        let c = Codec::standard(true);
        assert!(matches!(
            c.unpack_inputs(&[0; 10]),
            Err(Error::ProcessDataLength { .. })
        ));
        assert!(c.pack_outputs(&Outputs::default(), &mut [0; 4]).is_err());
        let no_torque = Layout::new(&OUTPUTS[..2]).unwrap();
        assert!(matches!(
            Codec::new(no_torque, Layout::new(&INPUTS).unwrap()),
            Err(Error::Mapping {
                index: TARGET_TORQUE,
                ..
            })
        ));
        assert!(Layout::new(&[MappingEntry::new(0x6040, 0, 12)]).is_err());
    }

    proptest! {
        #[test]
        fn inputs_and_outputs_round_trip(
            sw in any::<u16>(), mode in any::<i8>(), pos in any::<i32>(), vel in any::<i32>(),
            tq in any::<i16>(), err in any::<u16>(), load in proptest::option::of(any::<i32>()),
            cw in any::<u16>(), target in any::<i16>(),
        ) {
            let c = Codec::standard(load.is_some());
            let i = Inputs { statusword: sw, mode_display: mode, position_inc: pos, velocity_inc_s: vel,
                torque_permille: tq, error_code: err, load_position_inc: load };
            let mut buf = vec![0u8; c.inputs.len()];
            c.pack_inputs(&i, &mut buf).unwrap();
            prop_assert_eq!(c.unpack_inputs(&buf).unwrap(), i);
            let o = Outputs { controlword: cw, mode, target_torque_permille: target, ..Outputs::default() };
            let mut buf = vec![0u8; c.outputs.len()];
            c.pack_outputs(&o, &mut buf).unwrap();
            prop_assert_eq!(c.unpack_outputs(&buf).unwrap(), o);
        }
    }
}
