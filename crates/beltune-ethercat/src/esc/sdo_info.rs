//! The SDO information service of CoE (ETG.1000.6 5.6.3, CoE service 8): a
//! master browses the object dictionary without knowing it beforehand.
//!
//! Every message after the CoE header starts with a 4-byte SDO information
//! header: opcode (bits 0-6) and "incomplete" (bit 7: more fragments
//! follow), a reserved byte, and the number of fragments still to come
//! (UNSIGNED16). The opcodes:
//!
//! | request | response | data of the response |
//! | --- | --- | --- |
//! | 1 get OD list (list type) | 2 | list type, then the indices (UNSIGNED16 each); list type 0: the lengths of lists 1-5 |
//! | 3 get object description (index) | 4 | index, data type, max sub-index, object code, name |
//! | 5 get entry description (index, sub-index, value info) | 6 | index, sub-index, value info, data type, bit length, object access, name |
//! | - | 7 SDO info error | abort code (UNSIGNED32) |
//!
//! An answer longer than the mailbox goes in fragments; the master reads the
//! further fragments without another request (SOEM `ecx_readODlist`). The
//! entry description answers without the optional values (value info 0).

use super::coe::{abort, Frame, Objects};

/// CoE service number of SDO information.
pub const SERVICE: u16 = 8;
/// Object code of a variable (one value, sub-index 0).
pub const OBJECT_CODE_VAR: u8 = 7;
/// Object code of an array (entries of one type).
pub const OBJECT_CODE_ARRAY: u8 = 8;
/// Object code of a record (entries of different types).
pub const OBJECT_CODE_RECORD: u8 = 9;

/// Object access bits of an entry description (ETG.1000.6 table 51).
pub mod access {
    /// Readable in PRE-OP.
    pub const READ_PREOP: u16 = 0x0001;
    /// Readable in SAFE-OP.
    pub const READ_SAFEOP: u16 = 0x0002;
    /// Readable in OP.
    pub const READ_OP: u16 = 0x0004;
    /// Writable in PRE-OP.
    pub const WRITE_PREOP: u16 = 0x0008;
    /// Writable in SAFE-OP.
    pub const WRITE_SAFEOP: u16 = 0x0010;
    /// Writable in OP.
    pub const WRITE_OP: u16 = 0x0020;
    /// Mappable into an RxPDO (outputs).
    pub const RXPDO: u16 = 0x0040;
    /// Mappable into a TxPDO (inputs).
    pub const TXPDO: u16 = 0x0080;
    /// Readable in every state.
    pub const READ_ALL: u16 = READ_PREOP | READ_SAFEOP | READ_OP;
    /// Writable in every state.
    pub const WRITE_ALL: u16 = WRITE_PREOP | WRITE_SAFEOP | WRITE_OP;
}

/// Writable in some state.
pub const ACCESS_WRITE_ANY: u16 = access::WRITE_ALL;

/// What SDO information tells about an object.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjectInfo {
    /// CoE data type index (ETG.1000.6 table 63: 0x0007 UNSIGNED32, ...);
    /// for arrays the type of the entries.
    pub data_type: u16,
    /// Highest sub-index.
    pub max_sub: u8,
    /// [`OBJECT_CODE_VAR`], [`OBJECT_CODE_ARRAY`] or [`OBJECT_CODE_RECORD`].
    pub object_code: u8,
    /// Name.
    pub name: String,
}

/// What SDO information tells about one entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EntryInfo {
    /// CoE data type index.
    pub data_type: u16,
    /// Length, bits.
    pub bits: u16,
    /// Access bits ([`access`]).
    pub access: u16,
    /// Name.
    pub name: String,
}

const INFO_HEADER: usize = 4;
const MAILBOX_AND_COE: usize = 8;

fn message(f: &Frame, opcode: u8, more: bool, fragments_left: u16, data: &[u8]) -> Vec<u8> {
    let mut body = vec![opcode | if more { 0x80 } else { 0 }, 0];
    body.extend_from_slice(&fragments_left.to_le_bytes());
    body.extend_from_slice(data);
    f.coe(SERVICE, &body)
}

fn error(f: &Frame, code: u32) -> Vec<Vec<u8>> {
    vec![message(f, 7, false, 0, &code.to_le_bytes())]
}

/// Room for data in one message of a mailbox of `capacity` bytes.
fn room(capacity: usize) -> usize {
    capacity.saturating_sub(MAILBOX_AND_COE + INFO_HEADER)
}

/// Answer one SDO information request (`body`: after the CoE header); the
/// first message goes at once, the others follow as further fragments.
pub(crate) fn handle(
    f: &Frame,
    body: &[u8],
    objects: &dyn Objects,
    capacity: usize,
) -> Vec<Vec<u8>> {
    if body.len() < INFO_HEADER {
        return error(f, abort::COMMAND_UNKNOWN);
    }
    let data = &body[INFO_HEADER..];
    let u16_at = |i: usize| data.get(i..i + 2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    match body[0] & 0x7F {
        1 => {
            let Some(list_type) = u16_at(0) else {
                return error(f, abort::LENGTH_MISMATCH);
            };
            let indices: Vec<u16> = if list_type == 0 {
                (1..=5).map(|t| objects.list(t).len() as u16).collect()
            } else if (1..=5).contains(&list_type) {
                objects.list(list_type)
            } else {
                return error(f, abort::VALUE_RANGE);
            };
            let mut payload = list_type.to_le_bytes().to_vec();
            for i in indices {
                payload.extend_from_slice(&i.to_le_bytes());
            }
            // fragments of whole indices
            let per = room(capacity) & !1;
            if per == 0 {
                return error(f, abort::GENERAL);
            }
            let chunks: Vec<&[u8]> = payload.chunks(per).collect();
            let n = chunks.len();
            chunks
                .iter()
                .enumerate()
                .map(|(k, c)| message(f, 2, k + 1 < n, (n - 1 - k) as u16, c))
                .collect()
        }
        3 => {
            let Some(index) = u16_at(0) else {
                return error(f, abort::LENGTH_MISMATCH);
            };
            let Some(o) = objects.object_info(index) else {
                return error(f, abort::NO_OBJECT);
            };
            let mut d = index.to_le_bytes().to_vec();
            d.extend_from_slice(&o.data_type.to_le_bytes());
            d.extend_from_slice(&[o.max_sub, o.object_code]);
            let name = o.name.as_bytes();
            let n = name.len().min(room(capacity).saturating_sub(d.len()));
            d.extend_from_slice(&name[..n]);
            vec![message(f, 4, false, 0, &d)]
        }
        5 => {
            let (Some(index), Some(&sub)) = (u16_at(0), data.get(2)) else {
                return error(f, abort::LENGTH_MISMATCH);
            };
            let e = match objects.entry_info(index, sub) {
                Ok(e) => e,
                Err(code) => return error(f, code),
            };
            let mut d = index.to_le_bytes().to_vec();
            d.extend_from_slice(&[sub, 0]);
            d.extend_from_slice(&e.data_type.to_le_bytes());
            d.extend_from_slice(&e.bits.to_le_bytes());
            d.extend_from_slice(&e.access.to_le_bytes());
            let name = e.name.as_bytes();
            let n = name.len().min(room(capacity).saturating_sub(d.len()));
            d.extend_from_slice(&name[..n]);
            vec![message(f, 6, false, 0, &d)]
        }
        _ => error(f, abort::COMMAND_UNKNOWN),
    }
}
