//! The ESI file (EtherCAT SubDevice Information, ETG.2000) of the virtual
//! drive: the XML a configuration tool (TwinCAT, the EtherCAT configurators
//! of other masters) reads to know a device without the device: identity,
//! sync managers, FMMUs, the default PDOs, the mailbox protocols, the
//! distributed-clock modes, the object dictionary with data types, access
//! and PDO mappability, and the EEPROM size.
//!
//! Generated from the same [`Dictionary`] and [`SiiContent`] the drive
//! serves (one source, [`crate::objects`]); `beltune virtual-drive --esi
//! FILE` writes it. Element order follows the ETG.2000 schema
//! (`EtherCATInfo.xsd` v1.6: Device = Type, Name, GroupType, Profile, Fmmu,
//! Sm, RxPdo, TxPdo, Mailbox, Dc, Eeprom).

use crate::esc::sdo_info::{OBJECT_CODE_ARRAY, OBJECT_CODE_VAR};
use crate::esc::sii::SiiContent;
use crate::od::{data_type, Access, Dictionary, Pdo};
use std::fmt::Write as _;

/// Vendor name written into the ESI.
pub const VENDOR_NAME: &str = "beltune (unregistered vendor ID 0)";
/// The drive's group in the ESI.
pub const GROUP: &str = "ServoDrives";

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn hex(v: u32, digits: usize) -> String {
    format!("#x{v:0digits$X}")
}

/// `DefaultData` of ETG.2000: the value's bytes in hex, in memory (little
/// endian) order.
fn default_data(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

fn access_flags(access: Access, pdo: Pdo) -> String {
    let access = match access {
        Access::Ro => "<Access>ro</Access>".to_string(),
        Access::Rw => "<Access>rw</Access>".to_string(),
        Access::RwPreOp => "<Access WriteRestrictions=\"PreOP\">rw</Access>".to_string(),
    };
    let pdo = match pdo {
        Pdo::No => "",
        Pdo::Rx => "<PdoMapping>R</PdoMapping>",
        Pdo::Tx => "<PdoMapping>T</PdoMapping>",
    };
    format!("<Flags>{access}{pdo}</Flags>")
}

/// Name of an entry's type in the ESI.
fn type_name(od: &Dictionary, index: u16, sub: u8) -> String {
    od.entry_def(index, sub).map_or("USINT".into(), |e| {
        data_type::esi_name(e.data_type, e.data.len())
    })
}

/// Name of the structured type of an ARRAY or RECORD object.
fn struct_type(index: u16) -> String {
    format!("DT{index:04X}")
}

/// The ESI document of the drive with dictionary `od` and EEPROM content
/// `sii` (its sync managers, FMMUs, PDOs and identity), for a drive cycle
/// of `cycle_ns`.
pub fn esi(od: &Dictionary, sii: &SiiContent, cycle_ns: u32) -> String {
    let mut x = String::new();
    let id = &sii.identity;
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<EtherCATInfo xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="EtherCATInfo.xsd" Version="1.6">"#
    );
    let _ = writeln!(
        x,
        "  <Vendor>\n    <Id>{}</Id>\n    <Name>{}</Name>\n  </Vendor>",
        hex(id.vendor_id, 8),
        esc(VENDOR_NAME)
    );
    let _ = writeln!(x, "  <Descriptions>");
    let _ = writeln!(
        x,
        "    <Groups>\n      <Group>\n        <Type>{GROUP}</Type>\n        <Name>Servo drives</Name>\n      </Group>\n    </Groups>"
    );
    let _ = writeln!(x, "    <Devices>");
    let _ = writeln!(x, r#"      <Device Physics="YY">"#);
    let _ = writeln!(
        x,
        r#"        <Type ProductCode="{}" RevisionNo="{}">{}</Type>"#,
        hex(id.product_code, 8),
        hex(id.revision, 8),
        esc(&sii.name)
    );
    let _ = writeln!(x, "        <Name>{}</Name>", esc(&sii.name));
    let _ = writeln!(x, "        <GroupType>{GROUP}</GroupType>");
    // ---- profile and dictionary ----
    let _ = writeln!(
        x,
        "        <Profile>\n          <ProfileNo>402</ProfileNo>\n          <AddInfo>2</AddInfo>\n          <Dictionary>\n            <DataTypes>"
    );
    let mut basic: Vec<String> = Vec::new();
    for (index, _) in od.objects() {
        for (sub, e) in od.entries_of(index) {
            let n = data_type::esi_name(e.data_type, e.data.len());
            if !basic.contains(&n) {
                basic.push(n);
            }
            let _ = sub;
        }
    }
    for n in &basic {
        let bits = od
            .objects()
            .flat_map(|(i, _)| od.entries_of(i).map(|(_, e)| e.clone()).collect::<Vec<_>>())
            .find(|e| &data_type::esi_name(e.data_type, e.data.len()) == n)
            .map_or(8, |e| e.bits());
        let _ = writeln!(
            x,
            "              <DataType><Name>{}</Name><BitSize>{bits}</BitSize></DataType>",
            esc(n)
        );
    }
    for (index, o) in od.objects() {
        if o.code == OBJECT_CODE_VAR {
            continue;
        }
        let entries: Vec<_> = od.entries_of(index).collect();
        let mut offs = 0u32;
        let mut sub_items = String::new();
        let mut total = 0u32;
        for (sub, e) in &entries {
            // sub-index 0 is padded to 16 bits (as in a complete access)
            let bits = u32::from(e.bits());
            let _ = write!(
                sub_items,
                "<SubItem><SubIdx>{sub}</SubIdx><Name>{}</Name><Type>{}</Type><BitSize>{bits}</BitSize><BitOffs>{offs}</BitOffs>{}</SubItem>",
                esc(&e.name),
                esc(&data_type::esi_name(e.data_type, e.data.len())),
                access_flags(e.access, e.pdo)
            );
            offs += if *sub == 0 { 16 } else { bits };
            total = offs;
        }
        let array = if o.code == OBJECT_CODE_ARRAY {
            let n = entries.iter().filter(|(s, _)| *s > 0).count();
            format!(
                "<BaseType>{}</BaseType><ArrayInfo><LBound>1</LBound><Elements>{n}</Elements></ArrayInfo>",
                esc(&type_name(od, index, 1))
            )
        } else {
            String::new()
        };
        let _ = writeln!(
            x,
            "              <DataType><Name>{}</Name><BitSize>{total}</BitSize>{array}{sub_items}</DataType>",
            struct_type(index)
        );
    }
    let _ = writeln!(x, "            </DataTypes>\n            <Objects>");
    for (index, o) in od.objects() {
        let entries: Vec<_> = od.entries_of(index).collect();
        if o.code == OBJECT_CODE_VAR {
            let Some((_, e)) = entries.first() else {
                continue;
            };
            let _ = writeln!(
                x,
                "              <Object><Index>{}</Index><Name>{}</Name><Type>{}</Type><BitSize>{}</BitSize><Info><DefaultData>{}</DefaultData></Info>{}</Object>",
                hex(u32::from(index), 4),
                esc(&o.name),
                esc(&data_type::esi_name(e.data_type, e.data.len())),
                e.bits(),
                default_data(&e.data),
                access_flags(e.access, e.pdo)
            );
        } else {
            let mut info = String::new();
            let mut total = 0u32;
            for (sub, e) in &entries {
                let _ = write!(
                    info,
                    "<SubItem><Name>{}</Name><Info><DefaultData>{}</DefaultData></Info></SubItem>",
                    esc(&e.name),
                    default_data(&e.data)
                );
                total += if *sub == 0 { 16 } else { u32::from(e.bits()) };
            }
            let _ = writeln!(
                x,
                "              <Object><Index>{}</Index><Name>{}</Name><Type>{}</Type><BitSize>{total}</BitSize><Info>{info}</Info><Flags><Access>ro</Access></Flags></Object>",
                hex(u32::from(index), 4),
                esc(&o.name),
                struct_type(index)
            );
        }
    }
    let _ = writeln!(
        x,
        "            </Objects>\n          </Dictionary>\n        </Profile>"
    );
    // ---- FMMUs, sync managers, PDOs ----
    for f in &sii.fmmus {
        let name = match f {
            1 => "Outputs",
            2 => "Inputs",
            3 => "MBoxState",
            _ => continue,
        };
        let _ = writeln!(x, "        <Fmmu>{name}</Fmmu>");
    }
    for s in &sii.sync_managers {
        let name = match s.ty {
            1 => "MBoxOut",
            2 => "MBoxIn",
            3 => "Outputs",
            _ => "Inputs",
        };
        let size = if s.ty <= 2 {
            format!(
                r#" MinSize="{}" MaxSize="{}" DefaultSize="{}""#,
                crate::drive::MAILBOX_MIN,
                crate::drive::MAILBOX_LEN,
                s.len
            )
        } else {
            String::new()
        };
        let _ = writeln!(
            x,
            r#"        <Sm{size} StartAddress="{}" ControlByte="{}" Enable="1">{name}</Sm>"#,
            hex(u32::from(s.start), 4),
            hex(u32::from(s.control), 2)
        );
    }
    for (tag, pdos) in [("RxPdo", &sii.rx_pdos), ("TxPdo", &sii.tx_pdos)] {
        for p in pdos {
            let name = od
                .objects()
                .find(|(i, _)| *i == p.index)
                .map_or(String::new(), |(_, o)| o.name.clone());
            let _ = writeln!(
                x,
                r#"        <{tag} Fixed="0" Mandatory="1" Sm="{}"><Index>{}</Index><Name>{}</Name>"#,
                p.sync_manager,
                hex(u32::from(p.index), 4),
                esc(&name)
            );
            for (index, sub, _, bits) in &p.entries {
                let e = od.entry_def(*index, *sub);
                let _ = writeln!(
                    x,
                    "          <Entry><Index>{}</Index><SubIndex>{sub}</SubIndex><BitLen>{bits}</BitLen><Name>{}</Name><DataType>{}</DataType></Entry>",
                    hex(u32::from(*index), 4),
                    esc(&e.map_or(String::new(), |e| e.name.clone())),
                    esc(&type_name(od, *index, *sub))
                );
            }
            let _ = writeln!(x, "        </{tag}>");
        }
    }
    let _ = writeln!(
        x,
        r#"        <Mailbox DataLinkLayer="1">
          <CoE SdoInfo="1" PdoAssign="1" PdoConfig="1" CompleteAccess="1" SegmentedSdo="1"/>
        </Mailbox>
        <Dc>
          <OpMode><Name>DC</Name><Desc>DC-synchronous (SYNC0 = drive cycle {cycle_ns} ns)</Desc><AssignActivate>#x0300</AssignActivate><CycleTimeSync0 Factor="1">{cycle_ns}</CycleTimeSync0><ShiftTimeSync0>0</ShiftTimeSync0></OpMode>
          <OpMode><Name>SM</Name><Desc>SM-synchronous</Desc><AssignActivate>#x0000</AssignActivate></OpMode>
        </Dc>
        <Eeprom><ByteSize>2048</ByteSize><ConfigData>0000000000000000</ConfigData></Eeprom>
      </Device>
    </Devices>
  </Descriptions>
</EtherCATInfo>"#
    );
    x
}
