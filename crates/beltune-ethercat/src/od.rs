//! The object dictionary of the virtual drive: values as little-endian bytes
//! with their access rights, CoE data types, names and PDO mappability (what
//! SDO information and the ESI file tell a master), the PDO mapping and
//! assignment objects with the checks of CiA 301 (mapping changed only in
//! PRE-OP and only while sub-index 0 is 0; only mappable objects of the right
//! direction).

use crate::esc::coe::{abort, Objects};
use crate::esc::sdo_info::{
    access as acc, EntryInfo, ObjectInfo, OBJECT_CODE_ARRAY, OBJECT_CODE_RECORD, OBJECT_CODE_VAR,
};
use crate::esc::AlState;
use crate::pdo::{MappingEntry, RX_PDO, SM2_ASSIGN, SM3_ASSIGN, TX_PDO};
use std::collections::BTreeMap;

/// CoE data types (ETG.1000.6 table 63) and their ESI names.
pub mod data_type {
    /// BOOL.
    pub const BOOLEAN: u16 = 0x0001;
    /// SINT.
    pub const INTEGER8: u16 = 0x0002;
    /// INT.
    pub const INTEGER16: u16 = 0x0003;
    /// DINT.
    pub const INTEGER32: u16 = 0x0004;
    /// USINT.
    pub const UNSIGNED8: u16 = 0x0005;
    /// UINT.
    pub const UNSIGNED16: u16 = 0x0006;
    /// UDINT.
    pub const UNSIGNED32: u16 = 0x0007;
    /// REAL.
    pub const REAL32: u16 = 0x0008;
    /// STRING(n).
    pub const VISIBLE_STRING: u16 = 0x0009;
    /// LREAL.
    pub const REAL64: u16 = 0x0011;

    /// The ESI (ETG.2000) name of a basic type, `STRING(n)` for strings of `bytes`.
    pub fn esi_name(t: u16, bytes: usize) -> String {
        match t {
            BOOLEAN => "BOOL".into(),
            INTEGER8 => "SINT".into(),
            INTEGER16 => "INT".into(),
            INTEGER32 => "DINT".into(),
            UNSIGNED8 => "USINT".into(),
            UNSIGNED16 => "UINT".into(),
            UNSIGNED32 => "UDINT".into(),
            REAL32 => "REAL".into(),
            REAL64 => "LREAL".into(),
            VISIBLE_STRING => format!("STRING({bytes})"),
            _ => format!("DT{t:04X}"),
        }
    }
}

/// Whether an entry may be mapped into process data, and which way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pdo {
    /// Not mappable.
    No,
    /// Into an RxPDO (outputs, master to drive).
    Rx,
    /// Into a TxPDO (inputs, drive to master).
    Tx,
}

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

/// One entry (sub-index) of an object.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Value, little endian (its length is the entry's size).
    pub data: Vec<u8>,
    /// Who may write it.
    pub access: Access,
    /// CoE data type ([`data_type`]).
    pub data_type: u16,
    /// Name.
    pub name: String,
    /// PDO mappability.
    pub pdo: Pdo,
}

impl Entry {
    /// Length, bits.
    pub fn bits(&self) -> u16 {
        (self.data.len() * 8) as u16
    }
}

/// An object: its name and object code.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Object {
    /// Name.
    pub name: String,
    /// Object code: VAR 7, ARRAY 8, RECORD 9.
    pub code: u8,
}

/// The dictionary.
#[derive(Clone, Debug, Default)]
pub struct Dictionary {
    objects: BTreeMap<u16, Object>,
    entries: BTreeMap<(u16, u8), Entry>,
    /// Largest number of entries per PDO.
    pub max_entries: u8,
}

impl Dictionary {
    /// An empty dictionary.
    pub fn new() -> Self {
        Dictionary {
            objects: BTreeMap::new(),
            entries: BTreeMap::new(),
            max_entries: 8,
        }
    }

    /// Declare an object (VAR, ARRAY or RECORD) with its name.
    pub fn object(&mut self, index: u16, name: &str, code: u8) {
        self.objects.insert(
            index,
            Object {
                name: name.into(),
                code,
            },
        );
    }

    /// Add or replace an entry of a declared object.
    #[allow(clippy::too_many_arguments)]
    pub fn entry(
        &mut self,
        index: u16,
        sub: u8,
        name: &str,
        data_type: u16,
        access: Access,
        pdo: Pdo,
        data: Vec<u8>,
    ) {
        self.entries.insert(
            (index, sub),
            Entry {
                data,
                access,
                data_type,
                name: name.into(),
                pdo,
            },
        );
    }

    /// A VAR object with its one entry (sub-index 0).
    pub fn var(
        &mut self,
        index: u16,
        name: &str,
        data_type: u16,
        access: Access,
        pdo: Pdo,
        data: Vec<u8>,
    ) {
        self.object(index, name, OBJECT_CODE_VAR);
        self.entry(index, 0, name, data_type, access, pdo, data);
    }

    /// The objects in index order.
    pub fn objects(&self) -> impl Iterator<Item = (u16, &Object)> {
        self.objects.iter().map(|(i, o)| (*i, o))
    }

    /// The entries of an object in sub-index order.
    pub fn entries_of(&self, index: u16) -> impl Iterator<Item = (u8, &Entry)> {
        self.entries
            .range((index, 0)..=(index, u8::MAX))
            .map(|((_, s), e)| (*s, e))
    }

    /// One entry.
    pub fn entry_def(&self, index: u16, sub: u8) -> Option<&Entry> {
        self.entries.get(&(index, sub))
    }

    /// The entries mappable in `dir`, as mapping entries.
    pub fn mappable(&self, dir: Pdo) -> Vec<MappingEntry> {
        self.entries
            .iter()
            .filter(|(_, e)| e.pdo == dir && dir != Pdo::No)
            .map(|((i, s), e)| MappingEntry::new(*i, *s, e.bits() as u8))
            .collect()
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
            (&self.mappable(Pdo::Rx), RX_PDO)
        } else {
            (&self.mappable(Pdo::Tx), TX_PDO)
        };
        let assign = index == SM2_ASSIGN || index == SM3_ASSIGN;
        if sub == 0 {
            if data.len() != 1 {
                return Err(abort::LENGTH_MISMATCH);
            }
            let n = data[0];
            if assign {
                if n > 1 {
                    return Err(abort::VALUE_TOO_HIGH);
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
    fn list(&self, list_type: u16) -> Vec<u16> {
        let with = |dir: Pdo| {
            self.objects
                .keys()
                .copied()
                .filter(|i| self.entries_of(*i).any(|(_, e)| e.pdo == dir))
                .collect()
        };
        match list_type {
            1 => self.objects.keys().copied().collect(),
            2 => with(Pdo::Rx),
            3 => with(Pdo::Tx),
            _ => Vec::new(),
        }
    }

    fn object_info(&self, index: u16) -> Option<ObjectInfo> {
        let o = self.objects.get(&index)?;
        let max_sub = self.entries_of(index).map(|(s, _)| s).max().unwrap_or(0);
        let max_sub = if o.code == OBJECT_CODE_VAR {
            0
        } else if matches!(index, RX_PDO | TX_PDO) {
            // mapping sub-indices exist up to the maximum
            max_sub.max(self.max_entries)
        } else {
            max_sub
        };
        let data_type = match o.code {
            OBJECT_CODE_VAR => self.entries.get(&(index, 0)).map_or(0, |e| e.data_type),
            OBJECT_CODE_ARRAY => self.entries.get(&(index, 1)).map_or(0, |e| e.data_type),
            _ => 0,
        };
        debug_assert!(matches!(
            o.code,
            OBJECT_CODE_VAR | OBJECT_CODE_ARRAY | OBJECT_CODE_RECORD
        ));
        Some(ObjectInfo {
            data_type,
            max_sub,
            object_code: o.code,
            name: o.name.clone(),
        })
    }

    fn entry_info(&self, index: u16, sub: u8) -> Result<EntryInfo, u32> {
        let Some(e) = self.entries.get(&(index, sub)) else {
            if matches!(index, RX_PDO | TX_PDO) && sub > 0 && sub <= self.max_entries {
                return Ok(EntryInfo {
                    data_type: data_type::UNSIGNED32,
                    bits: 32,
                    access: acc::READ_ALL | acc::WRITE_PREOP,
                    name: format!("SubIndex {sub:03}"),
                });
            }
            return Err(if self.objects.contains_key(&index) {
                abort::NO_SUB_INDEX
            } else {
                abort::NO_OBJECT
            });
        };
        let access = acc::READ_ALL
            | match e.access {
                Access::Ro => 0,
                Access::Rw => acc::WRITE_ALL,
                Access::RwPreOp => acc::WRITE_PREOP,
            }
            | match e.pdo {
                Pdo::No => 0,
                Pdo::Rx => acc::RXPDO,
                Pdo::Tx => acc::TXPDO,
            };
        Ok(EntryInfo {
            data_type: e.data_type,
            bits: e.bits(),
            access,
            name: e.name.clone(),
        })
    }

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
            let (ty, n) = if index >= SM2_ASSIGN {
                (data_type::UNSIGNED16, 2)
            } else {
                (data_type::UNSIGNED32, 4)
            };
            self.entry(
                index,
                sub,
                &format!("SubIndex {sub:03}"),
                ty,
                Access::RwPreOp,
                Pdo::No,
                vec![0; n],
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
        } else if data.len() > e.data.len() && e.data_type != data_type::VISIBLE_STRING {
            return Err(abort::LENGTH_TOO_HIGH);
        } else if data.len() < e.data.len() && e.data_type != data_type::VISIBLE_STRING {
            return Err(abort::LENGTH_TOO_LOW);
        }
        self.set(index, sub, data);
        Ok(())
    }
}
