//! The ESI file (ETG.2000) of the virtual drive against the two other
//! descriptions of the same drive: the SII EEPROM image the drive serves
//! (decoded here from its bytes by the category layout of ETG.2010, not by
//! the code that built it) and the object dictionary its SDO server answers
//! from. The ETG.2000 schema (`EtherCATInfo.xsd`) is distributed by the
//! EtherCAT Technology Group to members and is not available here, so the
//! structure is checked by hand: the element order of a `Device`, every
//! type an object names defined under `DataTypes`, hex numbers as `#x..`.

use beltune::model::rigs;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive, IDENTITY, NAME};
use beltune_ethercat::od::{data_type, Access, Pdo};
use roxmltree::{Document, Node};

fn drive() -> VirtualDrive {
    let plant = rigs::builtin("egc70", None).unwrap();
    VirtualDrive::new(&plant, DriveConfig::default()).unwrap()
}

fn child<'a>(n: Node<'a, 'a>, name: &str) -> Node<'a, 'a> {
    n.children()
        .find(|c| c.has_tag_name(name))
        .unwrap_or_else(|| panic!("<{}> has no <{name}>", n.tag_name().name()))
}

fn text<'a>(n: Node<'a, 'a>, name: &str) -> &'a str {
    child(n, name).text().unwrap_or("")
}

/// `#x1A00` or decimal.
fn num(s: &str) -> u64 {
    match s.strip_prefix("#x") {
        Some(h) => u64::from_str_radix(h, 16).unwrap_or_else(|_| panic!("hex `{s}`")),
        None => s.parse().unwrap_or_else(|_| panic!("number `{s}`")),
    }
}

/// The categories of an SII image (ETG.2010 table 2: from word 0x40 on,
/// type and length in words, until type 0xFFFF).
fn categories(sii: &[u8]) -> Vec<(u16, Vec<u8>)> {
    let word = |w: usize| u16::from_le_bytes([sii[2 * w], sii[2 * w + 1]]);
    let mut out = Vec::new();
    let mut w = 0x40;
    while word(w) != 0xFFFF {
        let (ty, len) = (word(w), usize::from(word(w + 1)));
        out.push((ty, sii[2 * (w + 2)..2 * (w + 2 + len)].to_vec()));
        w += 2 + len;
    }
    out
}

#[test]
fn the_esi_the_sii_and_the_object_dictionary_describe_the_same_drive() {
    let d = drive();
    let xml = d.esi();
    let doc = Document::parse(&xml).expect("well-formed XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "EtherCATInfo");
    let vendor = child(root, "Vendor");
    assert_eq!(num(text(vendor, "Id")), u64::from(IDENTITY.vendor_id));
    let device = child(child(child(root, "Descriptions"), "Devices"), "Device");

    // ETG.2000 element order of a Device (the ones used here)
    let order = [
        "Type",
        "Name",
        "GroupType",
        "Profile",
        "Fmmu",
        "Sm",
        "RxPdo",
        "TxPdo",
        "Mailbox",
        "Dc",
        "Eeprom",
    ];
    let rank: Vec<usize> = device
        .children()
        .filter(|c| c.is_element())
        .map(|c| {
            order
                .iter()
                .position(|o| c.has_tag_name(*o))
                .unwrap_or_else(|| panic!("unexpected <{}>", c.tag_name().name()))
        })
        .collect();
    assert!(
        rank.windows(2).all(|w| w[0] <= w[1]),
        "element order {rank:?}"
    );

    // identity: ESI = SII words 0x08-0x0F = object 0x1018
    let ty = child(device, "Type");
    assert_eq!(ty.text(), Some(NAME));
    let sii = d.esc.sii();
    let w32 = |w: usize| u32::from_le_bytes(sii[2 * w..2 * w + 4].try_into().unwrap());
    assert_eq!(
        num(ty.attribute("ProductCode").unwrap()),
        u64::from(w32(0x0A))
    );
    assert_eq!(
        num(ty.attribute("RevisionNo").unwrap()),
        u64::from(w32(0x0C))
    );
    assert_eq!(w32(0x08), IDENTITY.vendor_id);
    let od = d.firmware.objects();
    assert_eq!(
        od.get_uint(0x1018, 2),
        Some(u64::from(IDENTITY.product_code))
    );

    let cats = categories(sii);
    let cat = |t: u16| -> Vec<&Vec<u8>> {
        cats.iter()
            .filter(|(ty, _)| *ty == t)
            .map(|(_, d)| d)
            .collect()
    };

    // sync managers: ESI <Sm> = SII category 41 (8 bytes each: start, length, control, ..)
    let sms: Vec<Node> = device.children().filter(|c| c.has_tag_name("Sm")).collect();
    let sii_sms = cat(41)[0];
    assert_eq!(sms.len(), sii_sms.len() / 8);
    for (k, sm) in sms.iter().enumerate() {
        let b = &sii_sms[8 * k..8 * k + 8];
        let start = u16::from_le_bytes([b[0], b[1]]);
        assert_eq!(num(sm.attribute("StartAddress").unwrap()), u64::from(start));
        assert_eq!(num(sm.attribute("ControlByte").unwrap()), u64::from(b[4]));
        if let Some(size) = sm.attribute("DefaultSize") {
            assert_eq!(num(size), u64::from(u16::from_le_bytes([b[2], b[3]])));
        }
    }
    // FMMUs: ESI <Fmmu> = SII category 40 (1 outputs, 2 inputs, 3 mailbox state)
    let fmmus: Vec<&str> = device
        .children()
        .filter(|c| c.has_tag_name("Fmmu"))
        .map(|c| c.text().unwrap_or(""))
        .collect();
    let sii_fmmus: Vec<&str> = cat(40)[0]
        .iter()
        .filter_map(|u| match u {
            1 => Some("Outputs"),
            2 => Some("Inputs"),
            3 => Some("MBoxState"),
            _ => None,
        })
        .collect();
    assert_eq!(fmmus, sii_fmmus);

    // PDOs: ESI <RxPdo>/<TxPdo> = SII categories 51/50 = the dictionary's
    // 0x1600/0x1A00 at power-up (entries: index, sub-index, bits)
    for (tag, cat_ty, pdo_index) in [("RxPdo", 51u16, 0x1600u16), ("TxPdo", 50, 0x1A00)] {
        let p = device.children().find(|c| c.has_tag_name(tag)).unwrap();
        assert_eq!(num(text(p, "Index")), u64::from(pdo_index));
        let esi: Vec<(u64, u64, u64)> = p
            .children()
            .filter(|c| c.has_tag_name("Entry"))
            .map(|e| {
                (
                    num(text(e, "Index")),
                    num(text(e, "SubIndex")),
                    num(text(e, "BitLen")),
                )
            })
            .collect();
        let c = cat(cat_ty)[0];
        let n = usize::from(c[2]);
        let sii_entries: Vec<(u64, u64, u64)> = (0..n)
            .map(|k| {
                let e = &c[8 + 8 * k..16 + 8 * k];
                (
                    u64::from(u16::from_le_bytes([e[0], e[1]])),
                    u64::from(e[2]),
                    u64::from(e[5]),
                )
            })
            .collect();
        let od_entries: Vec<(u64, u64, u64)> = (1..=od.get_uint(pdo_index, 0).unwrap() as u8)
            .map(|s| {
                let v = od.get_uint(pdo_index, s).unwrap();
                (v >> 16, (v >> 8) & 0xFF, v & 0xFF)
            })
            .collect();
        assert_eq!(esi, sii_entries, "{tag}: ESI and SII");
        assert_eq!(esi, od_entries, "{tag}: ESI and the dictionary");
        // each entry's data type is the dictionary's
        for e in p.children().filter(|c| c.has_tag_name("Entry")) {
            let (i, s) = (num(text(e, "Index")) as u16, num(text(e, "SubIndex")) as u8);
            let def = od.entry_def(i, s).unwrap();
            assert_eq!(
                text(e, "DataType"),
                data_type::esi_name(def.data_type, def.data.len())
            );
        }
    }

    // mailbox: ESI <CoE> attributes = SII general category CoE details byte
    // (ETG.2010: 0x01 SDO, 0x02 SDO information, 0x04 PDO assign, 0x08 PDO
    // configuration, 0x20 complete access)
    let coe = child(child(device, "Mailbox"), "CoE");
    let details = cat(30)[0][5];
    for (attr, bit) in [
        ("SdoInfo", 0x02),
        ("PdoAssign", 0x04),
        ("PdoConfig", 0x08),
        ("CompleteAccess", 0x20),
    ] {
        assert_eq!(
            coe.attribute(attr) == Some("1"),
            details & bit != 0,
            "{attr}"
        );
    }

    // the dictionary: the same objects with the same names, types, sizes,
    // access, mappability and power-up values
    let dict = child(child(device, "Profile"), "Dictionary");
    let types: Vec<&str> = child(dict, "DataTypes")
        .children()
        .filter(|c| c.has_tag_name("DataType"))
        .map(|t| text(t, "Name"))
        .collect();
    let objects: Vec<Node> = child(dict, "Objects")
        .children()
        .filter(|c| c.has_tag_name("Object"))
        .collect();
    let esi_index: Vec<(u64, &str)> = objects
        .iter()
        .map(|o| (num(text(*o, "Index")), text(*o, "Name")))
        .collect();
    let od_index: Vec<(u64, &str)> = od
        .objects()
        .map(|(i, o)| (u64::from(i), o.name.as_str()))
        .collect();
    assert_eq!(esi_index, od_index);
    for o in &objects {
        let index = num(text(*o, "Index")) as u16;
        let ty = text(*o, "Type");
        assert!(types.contains(&ty), "{index:#06x}: type {ty} not defined");
        let info = child(*o, "Info");
        if info.children().all(|c| !c.has_tag_name("SubItem")) {
            // a variable: value, type, size, access, mapping
            let e = od.entry_def(index, 0).unwrap();
            assert_eq!(ty, data_type::esi_name(e.data_type, e.data.len()));
            assert_eq!(num(text(*o, "BitSize")), u64::from(e.bits()));
            let want: String = e.data.iter().map(|b| format!("{b:02X}")).collect();
            assert_eq!(text(info, "DefaultData"), want, "{index:#06x}");
            let flags = child(*o, "Flags");
            let access = child(flags, "Access");
            let rw = access.text() == Some("rw");
            assert_eq!(rw, e.access != Access::Ro, "{index:#06x}");
            assert_eq!(
                access.attribute("WriteRestrictions") == Some("PreOP"),
                e.access == Access::RwPreOp
            );
            let mapping = flags
                .children()
                .find(|c| c.has_tag_name("PdoMapping"))
                .and_then(|m| m.text());
            let want = match e.pdo {
                Pdo::No => None,
                Pdo::Rx => Some("R"),
                Pdo::Tx => Some("T"),
            };
            assert_eq!(mapping, want, "{index:#06x}");
        } else {
            // an array or a record: one SubItem per entry with its value
            let subs: Vec<Node> = info
                .children()
                .filter(|c| c.has_tag_name("SubItem"))
                .collect();
            let entries: Vec<_> = od.entries_of(index).collect();
            assert_eq!(subs.len(), entries.len(), "{index:#06x}");
            for (s, (_, e)) in subs.iter().zip(&entries) {
                assert_eq!(text(*s, "Name"), e.name);
                let want: String = e.data.iter().map(|b| format!("{b:02X}")).collect();
                assert_eq!(text(child(*s, "Info"), "DefaultData"), want);
            }
        }
    }
    // the DC mode's SYNC0 cycle is the drive's (0x1C32:02)
    let dc = child(device, "Dc");
    let sync0 = dc
        .descendants()
        .find(|c| c.has_tag_name("CycleTimeSync0"))
        .unwrap();
    assert_eq!(num(sync0.text().unwrap()), od.get_uint(0x1C32, 2).unwrap());
    // a value changed by SDO does not change the ESI (power-up values):
    // 0x6060 = 10 by an expedited download (ccs 1, e, s, n = 3)
    let mut d2 = drive();
    let mut req = 10u16.to_le_bytes().to_vec();
    req.extend_from_slice(&[0, 0, 0, 0x13, 0x00, 0x20, 0x2F, 0x60, 0x60, 0, 10, 0, 0, 0]);
    req.resize(128, 0);
    use beltune_ethercat::esc::{AlState, Application};
    let answer = d2.firmware.mailbox(&req, AlState::PreOp).unwrap();
    assert_eq!(answer[8], 0x60, "download response");
    assert_eq!(d2.firmware.objects().get_uint(0x6060, 0), Some(10));
    assert_eq!(d2.esi(), xml);
}
