//! EtherCAT frames (ETG.1000.4 clause 5): an Ethernet II frame of EtherType
//! 0x88A4, a 2-byte EtherCAT header (length 11 bits, type 4 bits: 1 = PDUs)
//! and datagrams, each `command, index, address (4), length/flags (2), IRQ (2),
//! data, working counter (2)`.

/// EtherType of EtherCAT.
pub const ETHERTYPE: u16 = 0x88A4;
/// Ethernet header length, bytes.
pub const ETH_HEADER: usize = 14;
/// Datagram header length, bytes.
pub const DATAGRAM_HEADER: usize = 10;

/// Datagram commands (ETG.1000.4 table 11).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cmd {
    /// No operation.
    Nop,
    /// Auto-increment physical read.
    Aprd,
    /// Auto-increment physical write.
    Apwr,
    /// Auto-increment physical read-write.
    Aprw,
    /// Configured-address physical read.
    Fprd,
    /// Configured-address physical write.
    Fpwr,
    /// Configured-address physical read-write.
    Fprw,
    /// Broadcast read.
    Brd,
    /// Broadcast write.
    Bwr,
    /// Broadcast read-write.
    Brw,
    /// Logical read.
    Lrd,
    /// Logical write.
    Lwr,
    /// Logical read-write.
    Lrw,
    /// Auto-increment read, multiple write.
    Armw,
    /// Configured-address read, multiple write.
    Frmw,
}

impl Cmd {
    /// Decode a command byte.
    pub fn from_u8(b: u8) -> Option<Cmd> {
        Some(match b {
            0 => Cmd::Nop,
            1 => Cmd::Aprd,
            2 => Cmd::Apwr,
            3 => Cmd::Aprw,
            4 => Cmd::Fprd,
            5 => Cmd::Fpwr,
            6 => Cmd::Fprw,
            7 => Cmd::Brd,
            8 => Cmd::Bwr,
            9 => Cmd::Brw,
            10 => Cmd::Lrd,
            11 => Cmd::Lwr,
            12 => Cmd::Lrw,
            13 => Cmd::Armw,
            14 => Cmd::Frmw,
            _ => return None,
        })
    }

    /// Whether the command reads from the addressed device.
    pub fn reads(self) -> bool {
        matches!(
            self,
            Cmd::Aprd
                | Cmd::Aprw
                | Cmd::Fprd
                | Cmd::Fprw
                | Cmd::Brd
                | Cmd::Brw
                | Cmd::Lrd
                | Cmd::Lrw
        )
    }

    /// Whether the command writes to the addressed device.
    pub fn writes(self) -> bool {
        matches!(
            self,
            Cmd::Apwr
                | Cmd::Aprw
                | Cmd::Fpwr
                | Cmd::Fprw
                | Cmd::Bwr
                | Cmd::Brw
                | Cmd::Lwr
                | Cmd::Lrw
        )
    }
}

/// One datagram inside a frame buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Datagram {
    /// The command, if known.
    pub cmd: Option<Cmd>,
    /// Offset of the datagram header in the frame.
    pub start: usize,
    /// Data length, bytes.
    pub len: usize,
}

impl Datagram {
    /// Offset of the data in the frame.
    pub fn data(&self) -> usize {
        self.start + DATAGRAM_HEADER
    }

    /// Offset of the working counter in the frame.
    pub fn wkc(&self) -> usize {
        self.data() + self.len
    }
}

/// The datagrams of an EtherCAT frame, or `None` if `frame` is not one (wrong
/// EtherType, wrong type, lengths that do not fit).
pub fn datagrams(frame: &[u8]) -> Option<Vec<Datagram>> {
    if frame.len() < ETH_HEADER + 2 {
        return None;
    }
    if u16::from_be_bytes([frame[12], frame[13]]) != ETHERTYPE {
        return None;
    }
    let h = u16::from_le_bytes([frame[14], frame[15]]);
    let payload_len = usize::from(h & 0x07FF);
    if h >> 12 != 1 || ETH_HEADER + 2 + payload_len > frame.len() {
        return None;
    }
    let end = ETH_HEADER + 2 + payload_len;
    let mut out = Vec::new();
    let mut at = ETH_HEADER + 2;
    loop {
        if at + DATAGRAM_HEADER + 2 > end {
            return None;
        }
        let lf = u16::from_le_bytes([frame[at + 6], frame[at + 7]]);
        let len = usize::from(lf & 0x07FF);
        let d = Datagram {
            cmd: Cmd::from_u8(frame[at]),
            start: at,
            len,
        };
        if d.wkc() + 2 > end {
            return None;
        }
        out.push(d);
        at = d.wkc() + 2;
        if lf & 0x8000 == 0 {
            break;
        }
    }
    Some(out)
}

/// Build a frame from datagrams `(command, address, data)` (a test helper and
/// what a minimal master sends): broadcast destination, `src` as source.
pub fn build(src: [u8; 6], datagrams: &[(Cmd, u32, &[u8])]) -> Vec<u8> {
    let mut f = vec![0xFF; 6];
    f.extend_from_slice(&src);
    f.extend_from_slice(&ETHERTYPE.to_be_bytes());
    let payload: usize = datagrams
        .iter()
        .map(|(_, _, d)| DATAGRAM_HEADER + d.len() + 2)
        .sum();
    f.extend_from_slice(&((payload as u16 & 0x07FF) | 0x1000).to_le_bytes());
    for (i, (cmd, addr, data)) in datagrams.iter().enumerate() {
        f.push(*cmd as u8);
        f.push(i as u8);
        f.extend_from_slice(&addr.to_le_bytes());
        let more = if i + 1 < datagrams.len() { 0x8000 } else { 0 };
        f.extend_from_slice(&((data.len() as u16 & 0x07FF) | more).to_le_bytes());
        f.extend_from_slice(&[0, 0]);
        f.extend_from_slice(data);
        f.extend_from_slice(&[0, 0]);
    }
    f
}
