//! The SII EEPROM image (ETG.2010): the fixed area (identity, mailbox
//! configuration, size) and the categories (strings, general, FMMU, sync
//! managers, RxPDO/TxPDO description), as words in little endian.

/// Identity (SII words 0x08-0x0F, CoE 0x1018).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Identity {
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision number.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
}

/// A sync manager as the SII describes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SiiSyncManager {
    /// Physical start address.
    pub start: u16,
    /// Default length, bytes (0: set by the mapping).
    pub len: u16,
    /// Control byte.
    pub control: u8,
    /// Type: 1 mailbox out, 2 mailbox in, 3 outputs, 4 inputs.
    pub ty: u8,
}

/// One PDO for the RxPDO/TxPDO categories.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SiiPdo {
    /// PDO index (0x1600, 0x1A00).
    pub index: u16,
    /// Sync manager it belongs to.
    pub sync_manager: u8,
    /// Entries: index, sub-index, CoE data type, bits.
    pub entries: Vec<(u16, u8, u8, u8)>,
}

/// Everything the image contains.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SiiContent {
    /// Identity.
    pub identity: Identity,
    /// Device name (general category, string 1).
    pub name: String,
    /// Mailbox SM0 (receive) start and size, SM1 (send) start and size.
    pub mailbox: (u16, u16, u16, u16),
    /// Sync managers in order.
    pub sync_managers: Vec<SiiSyncManager>,
    /// FMMU usage: 1 outputs, 2 inputs, 3 SM status.
    pub fmmus: Vec<u8>,
    /// Output PDOs.
    pub rx_pdos: Vec<SiiPdo>,
    /// Input PDOs.
    pub tx_pdos: Vec<SiiPdo>,
}

fn crc8(data: &[u8]) -> u8 {
    // ETG.2010: CRC-8, polynomial x^8 + x^2 + x + 1, initial 0xFF
    let mut crc = 0xFFu8;
    for b in data {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    crc
}

fn category(out: &mut Vec<u8>, ty: u16, mut data: Vec<u8>) {
    if data.len() % 2 == 1 {
        data.push(0);
    }
    out.extend_from_slice(&ty.to_le_bytes());
    out.extend_from_slice(&((data.len() / 2) as u16).to_le_bytes());
    out.extend_from_slice(&data);
}

/// The EEPROM image, bytes (2 KiB, 0xFF after the end marker).
pub fn build(c: &SiiContent) -> Vec<u8> {
    let mut w = vec![0u8; 0x80];
    // 0x00: PDI control etc. stay 0; 0x07: checksum over words 0-6
    let crc = crc8(&w[..14]);
    w[14] = crc;
    let put32 = |w: &mut Vec<u8>, word: usize, v: u32| {
        w[2 * word..2 * word + 4].copy_from_slice(&v.to_le_bytes())
    };
    let put16 = |w: &mut Vec<u8>, word: usize, v: u16| {
        w[2 * word..2 * word + 2].copy_from_slice(&v.to_le_bytes())
    };
    put32(&mut w, 0x08, c.identity.vendor_id);
    put32(&mut w, 0x0A, c.identity.product_code);
    put32(&mut w, 0x0C, c.identity.revision);
    put32(&mut w, 0x0E, c.identity.serial);
    let (rx, rxn, tx, txn) = c.mailbox;
    put16(&mut w, 0x14, rx);
    put16(&mut w, 0x15, rxn);
    put16(&mut w, 0x16, tx);
    put16(&mut w, 0x17, txn);
    put16(&mut w, 0x18, rx);
    put16(&mut w, 0x19, rxn);
    put16(&mut w, 0x1A, tx);
    put16(&mut w, 0x1B, txn);
    put16(&mut w, 0x1C, 0x0004); // mailbox protocols: CoE
    put16(&mut w, 0x3E, 15); // EEPROM size: 16 kbit - 1
    put16(&mut w, 0x3F, 1); // version
                            // strings: 1 = name, 2 = "CiA402"
    let mut strings = vec![2u8];
    for s in [c.name.as_str(), "CiA402"] {
        strings.push(s.len() as u8);
        strings.extend_from_slice(s.as_bytes());
    }
    category(&mut w, 10, strings);
    // general: group 2, image 0, order 1, name 1
    let mut general = vec![0u8; 32];
    general[0] = 2;
    general[2] = 1;
    general[3] = 1;
    // CoE details (ETG.2010): SDO 0x01, SDO information 0x02, PDO assign
    // 0x04, PDO configuration 0x08, complete access 0x20
    general[5] = 0x01 | 0x02 | 0x04 | 0x08 | 0x20;
    general[9] = 1; // one DS402 channel
    general[11] = 0x01; // safe-op enabled
    category(&mut w, 30, general);
    category(&mut w, 40, c.fmmus.clone());
    let mut sms = Vec::new();
    for s in &c.sync_managers {
        sms.extend_from_slice(&s.start.to_le_bytes());
        sms.extend_from_slice(&s.len.to_le_bytes());
        sms.extend_from_slice(&[s.control, 0, 1, s.ty]);
    }
    category(&mut w, 41, sms);
    for (ty, pdos) in [(50u16, &c.tx_pdos), (51u16, &c.rx_pdos)] {
        for p in pdos {
            let mut d = p.index.to_le_bytes().to_vec();
            d.extend_from_slice(&[p.entries.len() as u8, p.sync_manager, 0, 0, 0, 0]);
            for (index, sub, dtype, bits) in &p.entries {
                d.extend_from_slice(&index.to_le_bytes());
                d.extend_from_slice(&[*sub, 0, *dtype, *bits, 0, 0]);
            }
            category(&mut w, ty, d);
        }
    }
    w.extend_from_slice(&0xFFFFu16.to_le_bytes());
    w.resize(2048, 0xFF);
    w
}
