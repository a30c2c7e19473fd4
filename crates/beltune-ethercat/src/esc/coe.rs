//! The CoE (CANopen over EtherCAT) SDO server of the mailbox (ETG.1000.6
//! 5.6.2): expedited and normal (size in the initiate frame) upload and
//! download, abort transfer. A mailbox frame is a 6-byte mailbox header
//! (length, address, channel/priority, type 3 = CoE | counter << 4), a 2-byte
//! CoE header (number, service: 2 request, 3 response) and the SDO: command
//! specifier, index, sub-index, 4 data bytes, then more data.

use super::AlState;

/// SDO abort codes (CiA 301 table 22) used by the emulator.
pub mod abort {
    /// Client/server command specifier not valid or unknown.
    pub const COMMAND_UNKNOWN: u32 = 0x0504_0001;
    /// Attempt to write a read only object.
    pub const READ_ONLY: u32 = 0x0601_0002;
    /// Object does not exist in the object dictionary.
    pub const NO_OBJECT: u32 = 0x0602_0000;
    /// Object cannot be mapped to the PDO.
    pub const NOT_MAPPABLE: u32 = 0x0604_0041;
    /// The number and length of the objects to be mapped would exceed the PDO length.
    pub const PDO_TOO_LONG: u32 = 0x0604_0042;
    /// Data type does not match, length of service parameter does not match.
    pub const LENGTH_MISMATCH: u32 = 0x0607_0010;
    /// Sub-index does not exist.
    pub const NO_SUB_INDEX: u32 = 0x0609_0011;
    /// Value range of parameter exceeded.
    pub const VALUE_RANGE: u32 = 0x0609_0030;
    /// Data cannot be transferred because of the present device state.
    pub const DEVICE_STATE: u32 = 0x0800_0022;
    /// Data cannot be transferred (general).
    pub const GENERAL: u32 = 0x0800_0000;
}

/// The object dictionary behind the SDO server.
pub trait Objects {
    /// Read an object's value (little endian bytes) or an abort code.
    fn upload(&mut self, index: u16, sub_index: u8) -> Result<Vec<u8>, u32>;
    /// Write an object's value or refuse with an abort code.
    fn download(
        &mut self,
        index: u16,
        sub_index: u8,
        data: &[u8],
        state: AlState,
    ) -> Result<(), u32>;
}

const MAILBOX_HEADER: usize = 6;
const COE_HEADER: usize = 2;
const SDO_HEADER: usize = 4;

/// Handle one mailbox request; `None` for anything that is not a CoE SDO
/// request (the mailbox then answers nothing, as for an unsupported protocol).
pub fn handle(
    request: &[u8],
    objects: &mut dyn Objects,
    state: AlState,
    capacity: usize,
) -> Option<Vec<u8>> {
    if request.len() < MAILBOX_HEADER + COE_HEADER + SDO_HEADER + 4 {
        return None;
    }
    let length = usize::from(u16::from_le_bytes([request[0], request[1]]));
    let ty = request[5] & 0x0F;
    let counter = (request[5] >> 4) & 0x07;
    if ty != 3 || length + MAILBOX_HEADER > request.len() {
        return None;
    }
    let coe = u16::from_le_bytes([request[6], request[7]]);
    if coe >> 12 != 2 {
        return None;
    }
    let s = MAILBOX_HEADER + COE_HEADER;
    let cmd = request[s];
    let index = u16::from_le_bytes([request[s + 1], request[s + 2]]);
    let sub = request[s + 3];
    let body = &request[s + SDO_HEADER..MAILBOX_HEADER + length.max(COE_HEADER + SDO_HEADER + 4)];
    let reply = |sdo_cmd: u8, data: &[u8]| {
        let len = COE_HEADER + SDO_HEADER + data.len().max(4);
        let mut out = Vec::with_capacity(MAILBOX_HEADER + len);
        out.extend_from_slice(&(len as u16).to_le_bytes());
        out.extend_from_slice(&[0, 0, 0, 3 | (counter << 4)]);
        out.extend_from_slice(&(3u16 << 12).to_le_bytes());
        out.push(sdo_cmd);
        out.extend_from_slice(&index.to_le_bytes());
        out.push(sub);
        out.extend_from_slice(data);
        while out.len() < MAILBOX_HEADER + COE_HEADER + SDO_HEADER + 4 {
            out.push(0);
        }
        out
    };
    let abort_reply = |code: u32| reply(0x80, &code.to_le_bytes());
    if cmd & 0x10 != 0 {
        // complete access is not offered (SII general category says so)
        return Some(abort_reply(abort::COMMAND_UNKNOWN));
    }
    match cmd >> 5 {
        // initiate download
        1 => {
            let expedited = cmd & 0x02 != 0;
            let sized = cmd & 0x01 != 0;
            let data: &[u8] = if expedited {
                let n = if sized {
                    4 - usize::from((cmd >> 2) & 0x03)
                } else {
                    4
                };
                &body[..n]
            } else {
                if !sized || body.len() < 4 {
                    return Some(abort_reply(abort::COMMAND_UNKNOWN));
                }
                let n = u32::from_le_bytes(body[..4].try_into().expect("4 bytes")) as usize;
                match body.get(4..4 + n) {
                    Some(d) => d,
                    // a normal download longer than one mailbox would need segments
                    None => return Some(abort_reply(abort::COMMAND_UNKNOWN)),
                }
            };
            Some(match objects.download(index, sub, data, state) {
                Ok(()) => reply(0x60, &[0; 4]),
                Err(code) => abort_reply(code),
            })
        }
        // initiate upload
        2 => Some(match objects.upload(index, sub) {
            Ok(v) if v.len() <= 4 => {
                let mut d = [0u8; 4];
                d[..v.len()].copy_from_slice(&v);
                reply(0x43 | (((4 - v.len()) as u8) << 2), &d)
            }
            Ok(v) if MAILBOX_HEADER + COE_HEADER + SDO_HEADER + 4 + v.len() <= capacity => {
                let mut d = (v.len() as u32).to_le_bytes().to_vec();
                d.extend_from_slice(&v);
                reply(0x41, &d)
            }
            Ok(_) => abort_reply(abort::GENERAL),
            Err(code) => abort_reply(code),
        }),
        _ => Some(abort_reply(abort::COMMAND_UNKNOWN)),
    }
}
