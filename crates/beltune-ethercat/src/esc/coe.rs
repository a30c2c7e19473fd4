//! The CoE (CANopen over EtherCAT) SDO server of the mailbox (ETG.1000.6
//! 5.6.2, CiA 301 7.2.4.3): expedited, normal (size in the initiate frame)
//! and segmented upload and download, abort transfer. A value longer than
//! one mailbox goes in segments: the initiate upload response carries only
//! the complete size, then each "upload segment" request (command 0x60 with
//! the toggle bit) is answered with up to `capacity - 9` bytes; a download
//! brings what fits into its initiate request and the rest in "download
//! segment" requests. The segment command byte is `t` (bit 4, toggling from
//! 0), `n` (bits 1-3, unused bytes of a 7-byte segment) and `c` (bit 0, the
//! last segment). A mailbox frame is a 6-byte mailbox header
//! (length, address, channel/priority, type 3 = CoE | counter << 4), a 2-byte
//! CoE header (number, service: 1 emergency, 2 SDO request, 3 SDO response,
//! 8 SDO information) and the SDO: command specifier, index, sub-index, 4
//! data bytes, then more data.
//!
//! - An abort transfer goes as an SDO *request* (service 2, ETG.1000.6
//!   5.6.2.7): a master tells it from a response by the service (SOEM read a
//!   service-3 abort of a read as a too-short answer and of a write as
//!   success).
//! - Complete access (command bit 4): the whole object from sub-index 0 or 1,
//!   sub-index 0 as UNSIGNED8 padded to 16 bits, the entries packed by their
//!   bit lengths; always a normal or segmented transfer.
//! - A request of another protocol (EoE, FoE, SoE, VoE), a CoE service this
//!   server does not offer or a malformed header gets a mailbox error reply
//!   (type 0, ETG.1000.4 table 29) instead of silence.
//! - SDO information (service 8): [`super::sdo_info`].

use super::sdo_info::{self, EntryInfo, ObjectInfo};
use super::AlState;

/// SDO abort codes (CiA 301 table 22) used by the emulator.
pub mod abort {
    /// Toggle bit not alternated.
    pub const TOGGLE: u32 = 0x0503_0000;
    /// Client/server command specifier not valid or unknown.
    pub const COMMAND_UNKNOWN: u32 = 0x0504_0001;
    /// Unsupported access to an object (complete access to a variable).
    pub const UNSUPPORTED_ACCESS: u32 = 0x0601_0000;
    /// Attempt to read a write only object.
    pub const WRITE_ONLY: u32 = 0x0601_0001;
    /// Out of memory (a download longer than the server accepts).
    pub const OUT_OF_MEMORY: u32 = 0x0504_0005;
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
    /// Data type does not match, length of service parameter too high.
    pub const LENGTH_TOO_HIGH: u32 = 0x0607_0012;
    /// Data type does not match, length of service parameter too low.
    pub const LENGTH_TOO_LOW: u32 = 0x0607_0013;
    /// Sub-index does not exist.
    pub const NO_SUB_INDEX: u32 = 0x0609_0011;
    /// Value range of parameter exceeded.
    pub const VALUE_RANGE: u32 = 0x0609_0030;
    /// Value of parameter written too high.
    pub const VALUE_TOO_HIGH: u32 = 0x0609_0031;
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
    /// The indices of an SDO information list (1 all objects, 2 RxPDO
    /// mappable, 3 TxPDO mappable, 4 stored for a device replacement, 5
    /// startup parameters).
    fn list(&self, _list_type: u16) -> Vec<u16> {
        Vec::new()
    }
    /// An object's description (SDO information, complete access).
    fn object_info(&self, _index: u16) -> Option<ObjectInfo> {
        None
    }
    /// An entry's description, or the abort code why there is none.
    fn entry_info(&self, _index: u16, _sub_index: u8) -> Result<EntryInfo, u32> {
        Err(abort::NO_OBJECT)
    }
}

/// Mailbox types (ETG.1000.4 table 30).
pub mod mailbox_type {
    /// Mailbox error reply.
    pub const ERROR: u8 = 0;
    /// CANopen over EtherCAT.
    pub const COE: u8 = 3;
}

/// Mailbox error codes (ETG.1000.4 table 29).
pub mod mailbox_error {
    /// Syntax of the 6-byte mailbox header wrong.
    pub const SYNTAX: u16 = 0x0001;
    /// The mailbox protocol is not supported.
    pub const UNSUPPORTED_PROTOCOL: u16 = 0x0002;
    /// The service in the protocol's header is not supported.
    pub const SERVICE_NOT_SUPPORTED: u16 = 0x0004;
    /// The length in the mailbox header is too short for the protocol.
    pub const SIZE_TOO_SHORT: u16 = 0x0006;
    /// The length in the mailbox header does not fit the sync manager.
    pub const INVALID_SIZE: u16 = 0x0008;
}

/// A mailbox error reply: header (length 4, type 0), command 0x0001, detail.
pub fn mailbox_error_reply(counter: u8, detail: u16) -> Vec<u8> {
    let mut out = 4u16.to_le_bytes().to_vec();
    out.extend_from_slice(&[0, 0, 0, mailbox_type::ERROR | (counter << 4)]);
    out.extend_from_slice(&1u16.to_le_bytes());
    out.extend_from_slice(&detail.to_le_bytes());
    out
}

/// A CoE emergency (service 1, CiA 301 7.2.7): error code, error register
/// (0x1001), 5 bytes of manufacturer data.
pub fn emergency(counter: u8, error_code: u16, error_register: u8, data: [u8; 5]) -> Vec<u8> {
    let mut out = 10u16.to_le_bytes().to_vec();
    out.extend_from_slice(&[0, 0, 0, mailbox_type::COE | (counter << 4)]);
    out.extend_from_slice(&(1u16 << 12).to_le_bytes());
    out.extend_from_slice(&error_code.to_le_bytes());
    out.push(error_register);
    out.extend_from_slice(&data);
    out
}

const MAILBOX_HEADER: usize = 6;
const COE_HEADER: usize = 2;
const SDO_HEADER: usize = 4;
/// Smallest SDO frame after the mailbox header: CoE header, command, index,
/// sub-index, 4 data bytes.
const MIN_SDO: usize = COE_HEADER + SDO_HEADER + 4;
/// Longest value a segmented download may bring, bytes.
pub const MAX_DOWNLOAD: usize = 4096;

#[derive(Clone, Debug)]
enum Transfer {
    Upload {
        index: u16,
        sub: u8,
        data: Vec<u8>,
        sent: usize,
        toggle: bool,
    },
    Download {
        index: u16,
        sub: u8,
        size: usize,
        data: Vec<u8>,
        toggle: bool,
        complete: bool,
    },
}

/// The SDO server: the state of a segmented transfer between requests, and
/// the further fragments of an SDO information answer.
#[derive(Clone, Debug, Default)]
pub struct SdoServer {
    transfer: Option<Transfer>,
    follow_ups: std::collections::VecDeque<Vec<u8>>,
}

/// Counter and CoE header of a request, for building the answer.
pub(crate) struct Frame {
    pub(crate) counter: u8,
}

impl Frame {
    /// A CoE message of `service` with `body` after the CoE header.
    pub(crate) fn coe(&self, service: u16, body: &[u8]) -> Vec<u8> {
        let len = COE_HEADER + body.len();
        let mut out = Vec::with_capacity(MAILBOX_HEADER + len);
        out.extend_from_slice(&(len as u16).to_le_bytes());
        out.extend_from_slice(&[0, 0, 0, mailbox_type::COE | (self.counter << 4)]);
        out.extend_from_slice(&(service << 12).to_le_bytes());
        out.extend_from_slice(body);
        out
    }

    fn mailbox(&self, sdo: &[u8]) -> Vec<u8> {
        self.coe(3, sdo)
    }

    /// An initiate-style answer: command, index, sub-index, data (at least 4 bytes).
    fn reply(&self, cmd: u8, index: u16, sub: u8, data: &[u8]) -> Vec<u8> {
        let mut sdo = vec![cmd];
        sdo.extend_from_slice(&index.to_le_bytes());
        sdo.push(sub);
        sdo.extend_from_slice(data);
        sdo.resize(sdo.len().max(SDO_HEADER + 4), 0);
        self.mailbox(&sdo)
    }

    /// Abort transfer: command 0x80 in an SDO *request* (service 2).
    fn abort(&self, index: u16, sub: u8, code: u32) -> Vec<u8> {
        let mut sdo = vec![0x80];
        sdo.extend_from_slice(&index.to_le_bytes());
        sdo.push(sub);
        sdo.extend_from_slice(&code.to_le_bytes());
        self.coe(2, &sdo)
    }
}

impl SdoServer {
    /// A server with no transfer under way.
    pub fn new() -> Self {
        SdoServer::default()
    }

    /// Whether a segmented transfer is under way.
    pub fn in_transfer(&self) -> bool {
        self.transfer.is_some()
    }

    /// The next fragment of a multi-fragment answer (SDO information),
    /// which the master reads without a further request.
    pub fn follow_up(&mut self) -> Option<Vec<u8>> {
        self.follow_ups.pop_front()
    }

    /// Handle one mailbox request (the SM0 buffer). `None` only for an abort
    /// from the master (no answer) or a request too short to carry a
    /// mailbox header; anything else this server does not offer gets a
    /// mailbox error reply. `capacity` is the length of the answer mailbox
    /// (SM1), bytes.
    pub fn handle(
        &mut self,
        request: &[u8],
        objects: &mut dyn Objects,
        state: AlState,
        capacity: usize,
    ) -> Option<Vec<u8>> {
        if request.len() < MAILBOX_HEADER || capacity < MAILBOX_HEADER + MIN_SDO {
            return None;
        }
        let length = usize::from(u16::from_le_bytes([request[0], request[1]]));
        let ty = request[5] & 0x0F;
        let counter = (request[5] >> 4) & 0x07;
        if length + MAILBOX_HEADER > request.len() {
            return Some(mailbox_error_reply(counter, mailbox_error::INVALID_SIZE));
        }
        if ty != mailbox_type::COE {
            return Some(mailbox_error_reply(
                counter,
                mailbox_error::UNSUPPORTED_PROTOCOL,
            ));
        }
        if length < COE_HEADER {
            return Some(mailbox_error_reply(counter, mailbox_error::SIZE_TOO_SHORT));
        }
        let coe = u16::from_le_bytes([request[6], request[7]]);
        let f = Frame { counter };
        match coe >> 12 {
            2 => {}
            8 => {
                let body = &request[MAILBOX_HEADER + COE_HEADER..MAILBOX_HEADER + length];
                let mut answers = sdo_info::handle(&f, body, objects, capacity);
                let first = if answers.is_empty() {
                    None
                } else {
                    Some(answers.remove(0))
                };
                self.follow_ups = answers.into();
                return first;
            }
            _ => {
                return Some(mailbox_error_reply(
                    counter,
                    mailbox_error::SERVICE_NOT_SUPPORTED,
                ))
            }
        }
        if length < COE_HEADER + 1 || request.len() < MAILBOX_HEADER + MIN_SDO {
            return Some(mailbox_error_reply(counter, mailbox_error::SIZE_TOO_SHORT));
        }
        let s = MAILBOX_HEADER + COE_HEADER;
        let cmd = request[s];
        // the SDO after the CoE header, as long as the mailbox header says
        let sdo = &request[s..MAILBOX_HEADER + length.max(MIN_SDO)];
        let index = u16::from_le_bytes([sdo[1], sdo[2]]);
        let sub = sdo[3];
        match cmd >> 5 {
            // download segment
            0 => Some(self.download_segment(&f, sdo, length - COE_HEADER, objects, state)),
            // upload segment
            3 => Some(self.upload_segment(&f, cmd, capacity)),
            // abort from the client: end the transfer, no answer
            4 => {
                self.transfer = None;
                None
            }
            1 => {
                self.transfer = None;
                Some(self.initiate_download(&f, cmd, index, sub, sdo, length, objects, state))
            }
            2 => {
                self.transfer = None;
                let complete = cmd & 0x10 != 0;
                Some(self.initiate_upload(&f, index, sub, complete, objects, capacity))
            }
            _ => {
                self.transfer = None;
                Some(f.abort(index, sub, abort::COMMAND_UNKNOWN))
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn initiate_download(
        &mut self,
        f: &Frame,
        cmd: u8,
        index: u16,
        sub: u8,
        sdo: &[u8],
        length: usize,
        objects: &mut dyn Objects,
        state: AlState,
    ) -> Vec<u8> {
        let expedited = cmd & 0x02 != 0;
        let sized = cmd & 0x01 != 0;
        let complete = cmd & 0x10 != 0;
        let body = &sdo[SDO_HEADER..];
        if complete && (expedited || sub > 1) {
            // complete access goes normal or segmented, from sub-index 0 or 1
            return f.abort(index, sub, abort::UNSUPPORTED_ACCESS);
        }
        if expedited {
            let n = if sized {
                4 - usize::from((cmd >> 2) & 0x03)
            } else {
                4
            };
            return match objects.download(index, sub, &body[..n], state) {
                Ok(()) => f.reply(0x60, index, sub, &[0; 4]),
                Err(code) => f.abort(index, sub, code),
            };
        }
        if !sized {
            return f.abort(index, sub, abort::COMMAND_UNKNOWN);
        }
        let size = u32::from_le_bytes(body[..4].try_into().expect("4 bytes")) as usize;
        // data present in this frame: the mailbox length after CoE header, SDO header and size
        let present = length.saturating_sub(MIN_SDO).min(body.len() - 4);
        if size <= present {
            let r = if complete {
                download_complete(objects, index, sub, &body[4..4 + size], state)
            } else {
                objects.download(index, sub, &body[4..4 + size], state)
            };
            return match r {
                Ok(()) => f.reply(0x60, index, sub, &[0; 4]),
                Err(code) => f.abort(index, sub, code),
            };
        }
        if size > MAX_DOWNLOAD {
            return f.abort(index, sub, abort::OUT_OF_MEMORY);
        }
        // segmented: the rest follows in download segments
        self.transfer = Some(Transfer::Download {
            index,
            sub,
            size,
            data: body[4..4 + present].to_vec(),
            toggle: false,
            complete,
        });
        f.reply(0x60, index, sub, &[0; 4])
    }

    fn download_segment(
        &mut self,
        f: &Frame,
        sdo: &[u8],
        sdo_len: usize,
        objects: &mut dyn Objects,
        state: AlState,
    ) -> Vec<u8> {
        let cmd = sdo[0];
        let Some(Transfer::Download {
            index,
            sub,
            size,
            mut data,
            toggle,
            complete,
        }) = self.transfer.take()
        else {
            return f.abort(0, 0, abort::COMMAND_UNKNOWN);
        };
        let t = cmd & 0x10 != 0;
        if t != toggle {
            return f.abort(index, sub, abort::TOGGLE);
        }
        // segment data: the SDO after its command byte; a 7-byte segment
        // says in n how many of its bytes are unused
        let mut n = sdo_len.saturating_sub(1).min(sdo.len() - 1);
        if n == 7 {
            n -= usize::from((cmd >> 1) & 0x07);
        }
        data.extend_from_slice(&sdo[1..1 + n]);
        let last = cmd & 0x01 != 0;
        if data.len() > size || (last && data.len() != size) {
            return f.abort(index, sub, abort::LENGTH_MISMATCH);
        }
        let answer = f.mailbox(&[0x20 | (u8::from(t) << 4), 0, 0, 0, 0, 0, 0, 0]);
        if last {
            let r = if complete {
                download_complete(objects, index, sub, &data, state)
            } else {
                objects.download(index, sub, &data, state)
            };
            return match r {
                Ok(()) => answer,
                Err(code) => f.abort(index, sub, code),
            };
        }
        self.transfer = Some(Transfer::Download {
            index,
            sub,
            size,
            data,
            toggle: !toggle,
            complete,
        });
        answer
    }

    fn initiate_upload(
        &mut self,
        f: &Frame,
        index: u16,
        sub: u8,
        complete: bool,
        objects: &mut dyn Objects,
        capacity: usize,
    ) -> Vec<u8> {
        let value = if complete {
            upload_complete(objects, index, sub)
        } else {
            objects.upload(index, sub)
        };
        match value {
            Ok(v) if v.len() <= 4 && !complete => {
                let mut d = [0u8; 4];
                d[..v.len()].copy_from_slice(&v);
                f.reply(0x43 | (((4 - v.len()) as u8) << 2), index, sub, &d)
            }
            Ok(v) => {
                let mut d = (v.len() as u32).to_le_bytes().to_vec();
                if MAILBOX_HEADER + MIN_SDO + v.len() <= capacity {
                    // normal: all of it in the answer
                    d.extend_from_slice(&v);
                } else {
                    // segmented: the size now, the data in upload segments
                    self.transfer = Some(Transfer::Upload {
                        index,
                        sub,
                        data: v,
                        sent: 0,
                        toggle: false,
                    });
                }
                f.reply(0x41, index, sub, &d)
            }
            Err(code) => f.abort(index, sub, code),
        }
    }

    fn upload_segment(&mut self, f: &Frame, cmd: u8, capacity: usize) -> Vec<u8> {
        let Some(Transfer::Upload {
            index,
            sub,
            data,
            sent,
            toggle,
        }) = self.transfer.take()
        else {
            return f.abort(0, 0, abort::COMMAND_UNKNOWN);
        };
        let t = cmd & 0x10 != 0;
        if t != toggle {
            return f.abort(index, sub, abort::TOGGLE);
        }
        let room = capacity - MAILBOX_HEADER - COE_HEADER - 1;
        let n = (data.len() - sent).min(room);
        let last = sent + n == data.len();
        let unused = 7usize.saturating_sub(n) as u8;
        let mut sdo = vec![(u8::from(t) << 4) | (unused << 1) | u8::from(last)];
        sdo.extend_from_slice(&data[sent..sent + n]);
        sdo.resize(sdo.len().max(8), 0);
        if !last {
            self.transfer = Some(Transfer::Upload {
                index,
                sub,
                data,
                sent: sent + n,
                toggle: !toggle,
            });
        }
        f.mailbox(&sdo)
    }
}

/// Bytes of sub-index 0 in a complete access (UNSIGNED8 padded to 16 bits).
const CA_SUB0_BYTES: usize = 2;

/// The whole object for a complete-access upload from `first` (0 or 1).
fn upload_complete(objects: &mut dyn Objects, index: u16, first: u8) -> Result<Vec<u8>, u32> {
    if first > 1 {
        return Err(abort::UNSUPPORTED_ACCESS);
    }
    let info = objects.object_info(index).ok_or(abort::NO_OBJECT)?;
    if info.object_code == sdo_info::OBJECT_CODE_VAR {
        return Err(abort::UNSUPPORTED_ACCESS);
    }
    let n = objects.upload(index, 0)?.first().copied().unwrap_or(0);
    let mut out = Vec::new();
    if first == 0 {
        out.extend_from_slice(&[n, 0]);
    }
    for sub in 1..=n {
        let e = objects.entry_info(index, sub)?;
        let v = objects.upload(index, sub)?;
        let bytes = usize::from(e.bits).div_ceil(8);
        let mut v = v;
        v.resize(bytes, 0);
        out.extend_from_slice(&v);
        if out.len() > MAX_DOWNLOAD {
            return Err(abort::OUT_OF_MEMORY);
        }
    }
    Ok(out)
}

/// A complete-access download from `first` (0 or 1): the entries in order,
/// each as long as its description says; with sub-index 0 (writable, e.g. a
/// PDO mapping) it is set to 0 first, then the entries, then its value, as
/// CiA 301 asks for mapping and assignment objects.
fn download_complete(
    objects: &mut dyn Objects,
    index: u16,
    first: u8,
    data: &[u8],
    state: AlState,
) -> Result<(), u32> {
    let info = objects.object_info(index).ok_or(abort::NO_OBJECT)?;
    if info.object_code == sdo_info::OBJECT_CODE_VAR {
        return Err(abort::UNSUPPORTED_ACCESS);
    }
    let (n, mut at) = if first == 0 {
        if data.len() < CA_SUB0_BYTES {
            return Err(abort::LENGTH_MISMATCH);
        }
        (data[0], CA_SUB0_BYTES)
    } else {
        (info.max_sub, 0)
    };
    if n > info.max_sub {
        return Err(abort::VALUE_RANGE);
    }
    let sub0_writable = first == 0
        && objects
            .entry_info(index, 0)
            .is_ok_and(|e| e.access & sdo_info::ACCESS_WRITE_ANY != 0);
    if sub0_writable {
        objects.download(index, 0, &[0], state)?;
    } else if first == 0 && objects.upload(index, 0)?.first() != Some(&n) {
        return Err(abort::VALUE_RANGE);
    }
    for sub in 1..=n {
        let e = objects.entry_info(index, sub)?;
        let bytes = usize::from(e.bits).div_ceil(8);
        let Some(v) = data.get(at..at + bytes) else {
            return Err(abort::LENGTH_MISMATCH);
        };
        objects.download(index, sub, v, state)?;
        at += bytes;
    }
    if at != data.len() {
        return Err(abort::LENGTH_MISMATCH);
    }
    if sub0_writable {
        objects.download(index, 0, &[n], state)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A dictionary of byte strings, writable in any state.
    #[derive(Default)]
    struct Bytes(BTreeMap<(u16, u8), Vec<u8>>);

    impl Objects for Bytes {
        fn upload(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
            self.0.get(&(index, sub)).cloned().ok_or(abort::NO_OBJECT)
        }
        fn download(&mut self, index: u16, sub: u8, data: &[u8], _: AlState) -> Result<(), u32> {
            match self.0.get_mut(&(index, sub)) {
                Some(v) => {
                    *v = data.to_vec();
                    Ok(())
                }
                None => Err(abort::NO_OBJECT),
            }
        }
    }

    /// A CoE request as a master sends it: mailbox header (length, address
    /// 0, priority 0, type 3 with counter), CoE header (service 2), `sdo`,
    /// padded to a 128-byte SM0 buffer.
    fn request(counter: u8, sdo: &[u8]) -> Vec<u8> {
        let mut r = ((COE_HEADER + sdo.len()) as u16).to_le_bytes().to_vec();
        r.extend_from_slice(&[0, 0, 0, 3 | (counter << 4), 0x00, 0x20]);
        r.extend_from_slice(sdo);
        r.resize(128, 0);
        r
    }

    /// The SDO part of an answer (after the mailbox and CoE headers), as
    /// long as its mailbox length says.
    fn sdo_of(answer: &[u8]) -> &[u8] {
        let len = usize::from(u16::from_le_bytes([answer[0], answer[1]]));
        assert_eq!(answer[5] & 0x0F, 3, "CoE");
        let service = u16::from_le_bytes([answer[6], answer[7]]) >> 12;
        // ETG.1000.6 5.6.2.7.1: the abort transfer is an SDO request
        let expected = if answer[8] == 0x80 { 2 } else { 3 };
        assert_eq!(service, expected, "SDO response, or request for an abort");
        &answer[8..MAILBOX_HEADER + len]
    }

    const NAME: &[u8] = b"beltune virtual servo"; // 21 bytes

    fn server_with_name() -> (SdoServer, Bytes) {
        let mut od = Bytes::default();
        od.0.insert((0x1008, 0), NAME.to_vec());
        od.0.insert((0x6040, 0), vec![0, 0]);
        (SdoServer::new(), od)
    }

    #[test]
    fn a_value_longer_than_the_mailbox_is_uploaded_in_segments() {
        // 32-byte mailbox: 32 - 6 - 2 - 1 = 23 data bytes per segment
        let (mut srv, mut od) = server_with_name();
        let cap = 32;
        // initiate upload request: ccs 2 (0x40), index 0x1008, sub 0
        let a = srv
            .handle(
                &request(1, &[0x40, 0x08, 0x10, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::PreOp,
                cap,
            )
            .unwrap();
        // 21 bytes would need 6 + 10 + 21 = 37 > 32: segmented, size only
        // (scs 2, s = 1, e = 0: 0x41; complete size 21)
        assert_eq!(sdo_of(&a), &[0x41, 0x08, 0x10, 0, 21, 0, 0, 0]);
        assert_eq!(a[5] >> 4, 1, "the counter of the request");
        assert!(srv.in_transfer());
        // upload segment request: ccs 3 (0x60), toggle 0
        let a = srv
            .handle(
                &request(2, &[0x60, 0, 0, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::PreOp,
                cap,
            )
            .unwrap();
        let seg = sdo_of(&a);
        // scs 0, t 0, n 0 (more than 7 bytes), c 1: all 21 bytes fit in 23
        assert_eq!(seg[0], 0x01);
        assert_eq!(&seg[1..], NAME);
        assert!(!srv.in_transfer());
    }

    #[test]
    fn segments_toggle_and_a_short_last_segment_says_its_unused_bytes() {
        let mut od = Bytes::default();
        let value: Vec<u8> = (0..30u8).collect();
        od.0.insert((0x2000, 1), value.clone());
        let mut srv = SdoServer::new();
        // 24-byte mailbox: 15 data bytes per segment -> 15 + 15
        let cap = 24;
        let a = srv
            .handle(
                &request(1, &[0x40, 0x00, 0x20, 1, 0, 0, 0, 0]),
                &mut od,
                AlState::Op,
                cap,
            )
            .unwrap();
        assert_eq!(sdo_of(&a), &[0x41, 0x00, 0x20, 1, 30, 0, 0, 0]);
        let a = srv
            .handle(
                &request(2, &[0x60, 0, 0, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::Op,
                cap,
            )
            .unwrap();
        assert_eq!(sdo_of(&a)[0], 0x00, "t 0, more follows");
        assert_eq!(&sdo_of(&a)[1..], &value[..15]);
        // the same toggle again is refused (CiA 301: toggle bit not alternated)
        let mut again = srv.clone();
        let a = again
            .handle(
                &request(3, &[0x60, 0, 0, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::Op,
                cap,
            )
            .unwrap();
        assert_eq!(sdo_of(&a)[0], 0x80);
        assert_eq!(&sdo_of(&a)[4..8], &abort::TOGGLE.to_le_bytes());
        let a = srv
            .handle(
                &request(3, &[0x70, 0, 0, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::Op,
                cap,
            )
            .unwrap();
        assert_eq!(sdo_of(&a)[0], 0x11, "t 1, last");
        assert_eq!(&sdo_of(&a)[1..], &value[15..]);
        // a value of 3 bytes in a last segment: n = 4 unused of 7
        od.0.insert((0x2000, 2), (0..18u8).collect());
        srv.handle(
            &request(4, &[0x40, 0x00, 0x20, 2, 0, 0, 0, 0]),
            &mut od,
            AlState::Op,
            cap,
        )
        .unwrap();
        srv.handle(
            &request(5, &[0x60, 0, 0, 0, 0, 0, 0, 0]),
            &mut od,
            AlState::Op,
            cap,
        )
        .unwrap();
        let a = srv
            .handle(
                &request(6, &[0x70, 0, 0, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::Op,
                cap,
            )
            .unwrap();
        let seg = sdo_of(&a);
        assert_eq!(seg.len(), 8, "command and 7 segment bytes");
        assert_eq!(seg[0], 0x10 | (4 << 1) | 1);
        assert_eq!(&seg[1..4], &[15, 16, 17]);
    }

    #[test]
    fn a_segmented_download_collects_the_segments_and_writes_once() {
        let mut od = Bytes::default();
        od.0.insert((0x2000, 1), vec![0; 20]);
        let mut srv = SdoServer::new();
        let value: Vec<u8> = (100..120u8).collect();
        // initiate download, normal, sized (0x21), complete size 20, the first 6 bytes
        let mut init = vec![0x21, 0x00, 0x20, 1, 20, 0, 0, 0];
        init.extend_from_slice(&value[..6]);
        let a = srv
            .handle(&request(1, &init), &mut od, AlState::PreOp, 128)
            .unwrap();
        assert_eq!(sdo_of(&a), &[0x60, 0x00, 0x20, 1, 0, 0, 0, 0]);
        assert_eq!(od.0[&(0x2000, 1)], vec![0; 20], "nothing written yet");
        // download segment, t 0, more follows: 10 bytes
        let mut seg = vec![0x00];
        seg.extend_from_slice(&value[6..16]);
        let a = srv
            .handle(&request(2, &seg), &mut od, AlState::PreOp, 128)
            .unwrap();
        assert_eq!(sdo_of(&a), &[0x20, 0, 0, 0, 0, 0, 0, 0], "scs 1, t 0");
        // the last 4 bytes in a 7-byte segment: t 1, n 3, c 1
        let mut seg = vec![0x10 | (3 << 1) | 1];
        seg.extend_from_slice(&value[16..]);
        seg.extend_from_slice(&[0xEE; 3]);
        let a = srv
            .handle(&request(3, &seg), &mut od, AlState::PreOp, 128)
            .unwrap();
        assert_eq!(sdo_of(&a), &[0x30, 0, 0, 0, 0, 0, 0, 0], "scs 1, t 1");
        assert_eq!(od.0[&(0x2000, 1)], value);
        assert!(!srv.in_transfer());
    }

    #[test]
    fn a_segment_without_a_transfer_or_with_the_wrong_length_is_aborted() {
        let (mut srv, mut od) = server_with_name();
        let a = srv
            .handle(
                &request(1, &[0x60, 0, 0, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::PreOp,
                128,
            )
            .unwrap();
        assert_eq!(sdo_of(&a)[0], 0x80);
        assert_eq!(&sdo_of(&a)[4..8], &abort::COMMAND_UNKNOWN.to_le_bytes());
        od.0.insert((0x2000, 1), vec![0; 12]);
        // announces 12 bytes, brings 2 + 3 and says "last"
        let init = [0x21, 0x00, 0x20, 1, 12, 0, 0, 0, 1, 2];
        srv.handle(&request(2, &init), &mut od, AlState::PreOp, 128)
            .unwrap();
        let a = srv
            .handle(
                &request(3, &[0x01 | (4 << 1), 3, 4, 5, 0, 0, 0, 0]),
                &mut od,
                AlState::PreOp,
                128,
            )
            .unwrap();
        assert_eq!(&sdo_of(&a)[4..8], &abort::LENGTH_MISMATCH.to_le_bytes());
        assert_eq!(od.0[&(0x2000, 1)], vec![0; 12]);
    }

    #[test]
    fn other_protocols_and_services_get_a_mailbox_error_reply_not_silence() {
        let (mut srv, mut od) = server_with_name();
        // FoE (type 4) read request: ETG.1000.4 mailbox error, detail 0x0002
        let mut foe = request(5, &[1, 0, 0, 0, 0, 0, 0, 0]);
        foe[5] = 0x04 | (5 << 4);
        let a = srv.handle(&foe, &mut od, AlState::PreOp, 128).unwrap();
        assert_eq!(a[5] & 0x0F, 0, "type 0: mailbox error");
        assert_eq!(a[5] >> 4, 5, "the request's counter");
        assert_eq!(
            &a[6..10],
            &[0x01, 0x00, 0x02, 0x00],
            "command 1, unsupported protocol"
        );
        // a CoE service other than SDO request or information (5: RxPDO remote)
        let mut coe = request(6, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
        coe[7] = 0x50;
        let a = srv.handle(&coe, &mut od, AlState::PreOp, 128).unwrap();
        assert_eq!(
            &a[6..10],
            &[0x01, 0x00, 0x04, 0x00],
            "service not supported"
        );
        // a length beyond the mailbox
        let mut long = request(7, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
        long[0] = 200;
        let a = srv.handle(&long, &mut od, AlState::PreOp, 128).unwrap();
        assert_eq!(&a[6..10], &[0x01, 0x00, 0x08, 0x00], "invalid size");
        // an abort from the master ends a transfer without an answer
        assert!(srv
            .handle(
                &request(8, &[0x80, 0, 0, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::PreOp,
                128
            )
            .is_none());
    }

    #[test]
    fn short_values_stay_expedited_and_mid_sized_ones_normal() {
        let (mut srv, mut od) = server_with_name();
        // 2-byte object: expedited, size indicated, 2 unused (0x4B)
        let a = srv
            .handle(
                &request(1, &[0x40, 0x40, 0x60, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::Op,
                128,
            )
            .unwrap();
        assert_eq!(sdo_of(&a), &[0x4B, 0x40, 0x60, 0, 0, 0, 0, 0]);
        // 21 bytes in a 128-byte mailbox: normal, size then data
        let a = srv
            .handle(
                &request(2, &[0x40, 0x08, 0x10, 0, 0, 0, 0, 0]),
                &mut od,
                AlState::Op,
                128,
            )
            .unwrap();
        let s = sdo_of(&a);
        assert_eq!(&s[..8], &[0x41, 0x08, 0x10, 0, 21, 0, 0, 0]);
        assert_eq!(&s[8..], NAME);
        assert!(!srv.in_transfer());
    }
}
