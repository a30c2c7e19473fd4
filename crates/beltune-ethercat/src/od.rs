//! The object dictionary of the virtual drive: values as little-endian bytes
//! with their access rights, the PDO mapping and assignment objects with the
//! checks of CiA 301 (mapping changed only in PRE-OP and only while sub-index
//! 0 is 0; only mappable objects of the right direction and length).

use crate::esc::coe::{abort, Objects};
use crate::esc::AlState;
use crate::pdo::{MappingEntry, RX_PDO, SM2_ASSIGN, SM3_ASSIGN, TX_PDO};
use std::collections::BTreeMap;

/// Who may write an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Read only.
    Ro,
    /// Read and write in any state.
    Rw,
    /// Writable in PRE-OP only (communication and mapping parameters).
    RwPreOp,
}

#[derive(Clone, Debug)]
struct Entry {
    data: Vec<u8>,
    access: Access,
}

/// The dictionary.
#[derive(Clone, Debug, Default)]
pub struct Dictionary {
    entries: BTreeMap<(u16, u8), Entry>,
    rx_mappable: Vec<MappingEntry>,
    tx_mappable: Vec<MappingEntry>,
    /// Largest number of entries per PDO.
    pub max_entries: u8,
}

impl Dictionary {
    /// An empty dictionary whose PDOs may map `rx_mappable` (outputs) and
    /// `tx_mappable` (inputs).
    pub fn new(rx_mappable: Vec<MappingEntry>, tx_mappable: Vec<MappingEntry>) -> Self {
        Dictionary {
            entries: BTreeMap::new(),
            rx_mappable,
            tx_mappable,
            max_entries: 8,
        }
    }

    /// Add or replace an object.
    pub fn insert(&mut self, index: u16, sub: u8, data: Vec<u8>, access: Access) {
        self.entries.insert((index, sub), Entry { data, access });
    }

    /// Set a value without access checks (the drive's own update).
    pub fn set(&mut self, index: u16, sub: u8, data: &[u8]) {
        if let Some(e) = self.entries.get_mut(&(index, sub)) {
            e.data.clear();
            e.data.extend_from_slice(data);
        }
    }

    /// Raw value.
    pub fn get(&self, index: u16, sub: u8) -> Option<&[u8]> {
        self.entries.get(&(index, sub)).map(|e| e.data.as_slice())
    }

    /// A value as an unsigned integer (zero-extended).
    pub fn get_uint(&self, index: u16, sub: u8) -> Option<u64> {
        let d = self.get(index, sub)?;
        Some(
            d.iter()
                .take(8)
                .enumerate()
                .fold(0u64, |v, (i, b)| v | (u64::from(*b) << (8 * i))),
        )
    }

    /// The mapping currently assigned to a sync manager (`SM2_ASSIGN` or `SM3_ASSIGN`).
    pub fn assigned_mapping(&self, assign: u16) -> Vec<MappingEntry> {
        let mut out = Vec::new();
        let n = self.get_uint(assign, 0).unwrap_or(0) as u8;
        for i in 1..=n {
            let pdo = self.get_uint(assign, i).unwrap_or(0) as u16;
            let m = self.get_uint(pdo, 0).unwrap_or(0) as u8;
            for j in 1..=m {
                out.push(MappingEntry::from_u32(
                    self.get_uint(pdo, j).unwrap_or(0) as u32
                ));
            }
        }
        out
    }

    fn check_mapping_write(&self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let value = data
            .iter()
            .take(4)
            .enumerate()
            .fold(0u32, |v, (i, b)| v | (u32::from(*b) << (8 * i)));
        let (mappable, pdo) = if index == RX_PDO || index == SM2_ASSIGN {
            (&self.rx_mappable, RX_PDO)
        } else {
            (&self.tx_mappable, TX_PDO)
        };
        let assign = index == SM2_ASSIGN || index == SM3_ASSIGN;
        if sub == 0 {
            if data.len() != 1 {
                return Err(abort::LENGTH_MISMATCH);
            }
            let n = data[0];
            if assign {
                if n > 1 {
                    return Err(abort::VALUE_RANGE);
                }
                if n == 1 && self.get_uint(index, 1) != Some(u64::from(pdo)) {
                    return Err(abort::VALUE_RANGE);
                }
                return Ok(());
            }
            if n > self.max_entries {
                return Err(abort::PDO_TOO_LONG);
            }
            let mut bits = 0u32;
            for i in 1..=n {
                let e = MappingEntry::from_u32(self.get_uint(index, i).unwrap_or(0) as u32);
                if !mappable.contains(&e) {
                    return Err(abort::NOT_MAPPABLE);
                }
                bits += u32::from(e.bits);
            }
            if bits > 8 * 64 {
                return Err(abort::PDO_TOO_LONG);
            }
            return Ok(());
        }
        // sub-index n > 0: only while sub 0 is 0
        if self.get_uint(index, 0).unwrap_or(0) != 0 {
            return Err(abort::DEVICE_STATE);
        }
        if data.len() != if assign { 2 } else { 4 } {
            return Err(abort::LENGTH_MISMATCH);
        }
        if assign {
            if sub != 1 || value != u32::from(pdo) {
                return Err(abort::VALUE_RANGE);
            }
        } else if sub > self.max_entries {
            return Err(abort::NO_SUB_INDEX);
        } else if !mappable.contains(&MappingEntry::from_u32(value)) {
            return Err(abort::NOT_MAPPABLE);
        }
        Ok(())
    }
}

impl Objects for Dictionary {
    fn upload(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
        match self.entries.get(&(index, sub)) {
            Some(e) => Ok(e.data.clone()),
            None if self.entries.keys().any(|(i, _)| *i == index) => Err(abort::NO_SUB_INDEX),
            None => Err(abort::NO_OBJECT),
        }
    }

    fn download(&mut self, index: u16, sub: u8, data: &[u8], state: AlState) -> Result<(), u32> {
        let is_mapping = matches!(index, RX_PDO | TX_PDO | SM2_ASSIGN | SM3_ASSIGN);
        if is_mapping
            && sub > 0
            && !self.entries.contains_key(&(index, sub))
            && sub <= self.max_entries
        {
            // mapping sub-indices exist up to the maximum
            self.insert(
                index,
                sub,
                vec![0; if index >= SM2_ASSIGN { 2 } else { 4 }],
                Access::RwPreOp,
            );
        }
        let Some(e) = self.entries.get(&(index, sub)) else {
            return Err(if self.entries.keys().any(|(i, _)| *i == index) {
                abort::NO_SUB_INDEX
            } else {
                abort::NO_OBJECT
            });
        };
        match e.access {
            Access::Ro => return Err(abort::READ_ONLY),
            Access::RwPreOp if state != AlState::PreOp => return Err(abort::DEVICE_STATE),
            _ => {}
        }
        if is_mapping {
            self.check_mapping_write(index, sub, data)?;
        } else if data.len() != e.data.len() {
            return Err(abort::LENGTH_MISMATCH);
        }
        self.set(index, sub, data);
        Ok(())
    }
}
