//! Drive profiles: the shipped profile of the virtual drive maps every
//! quantity of the drive's loops onto the object the drive keeps it in (its
//! own table and its object dictionary, with the data type), and a profile
//! file with a mistake is refused in one line before anything is written.

use beltune::model::rigs;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive, IDENTITY};
use beltune_ethercat::loops;
use beltune_ethercat::od::data_type;
use beltune_ethercat::profile::{DriveProfile, ObjectType};

#[test]
fn the_shipped_profile_maps_every_quantity_onto_the_virtual_drives_objects() {
    let p = DriveProfile::virtual_servo();
    assert!(p.matches(IDENTITY.vendor_id, IDENTITY.product_code));
    let plant = rigs::builtin("egc70", None).unwrap();
    let d = VirtualDrive::new(&plant, DriveConfig::default()).unwrap();
    let od = d.firmware.objects();
    // every REAL32 parameter of the drive, at its place, with its type
    for q in &loops::PARAMETERS {
        let e = p
            .parameters
            .iter()
            .find(|e| e.quantity == q.quantity)
            .unwrap_or_else(|| panic!("{} not in the profile", q.quantity));
        assert_eq!((e.index, e.sub), (q.index, q.sub), "{}", q.quantity);
        assert_eq!(e.ty, ObjectType::REAL32);
        assert_eq!(e.scale, 1.0);
        let def = od.entry_def(e.index, e.sub).unwrap();
        assert_eq!(def.data_type, data_type::REAL32, "{}", q.quantity);
    }
    // and the three bit sets, UNSIGNED8
    for (q, sub) in [
        (
            loops::TERMS_QUANTITY,
            (loops::FEEDFORWARD, loops::TERMS_SUB),
        ),
        (
            loops::OPTIONS_QUANTITY,
            (loops::OPTIONS, loops::OPTIONS_SUB),
        ),
        (
            loops::PREVIEW_QUANTITY,
            (loops::OPTIONS, loops::PREVIEW_SUB),
        ),
    ] {
        let e = p.parameters.iter().find(|e| e.quantity == q).unwrap();
        assert_eq!((e.index, e.sub), sub);
        assert_eq!(
            od.entry_def(e.index, e.sub).unwrap().data_type,
            data_type::UNSIGNED8
        );
    }
    assert_eq!(p.parameters.len(), loops::PARAMETERS.len() + 3);
}

#[test]
fn a_profile_with_a_mistake_is_refused_in_one_line() {
    let base = "name = \"x\"\nvendor_id = 1\nproduct_code = 2\nmode = 8\n";
    let entry = |q: &str, extra: &str| {
        format!("[[parameter]]\nquantity = \"{q}\"\nindex = 0x2000\nsub = 1\ntype = \"REAL32\"\n{extra}")
    };
    for (text, says) in [
        (
            format!("{base}{}", entry("k_pp", "")),
            "unknown quantity `k_pp`",
        ),
        (
            format!("{base}{}", entry("k_pp_per_s", "scale = 0.0\n")),
            "scale",
        ),
        (
            format!("{base}{}{}", entry("k_pp_per_s", ""), entry("k_v", "")),
            "listed twice",
        ),
        (
            format!(
                "{}{}",
                base.replace("mode = 8", "mode = 10"),
                entry("k_pp_per_s", "")
            ),
            "mode 10",
        ),
        (base.to_string(), "missing field `parameter`"),
        (
            format!("{base}{}", entry("k_pp_per_s", "colour = 1\n")),
            "colour",
        ),
    ] {
        let e = DriveProfile::parse(&text, "test.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains(says) && !e.contains('\n'), "{e}");
    }
}

#[test]
fn a_scaled_integer_object_gets_the_rounded_value_or_a_range_error() {
    let text = "name = \"x\"\nvendor_id = 1\nproduct_code = 2\nmode = 8\n\
        [[parameter]]\nquantity = \"k_pp_per_s\"\nindex = 0x3000\nsub = 1\ntype = \"UNSIGNED16\"\nscale = 100.0\n";
    let p = DriveProfile::parse(text, "t").unwrap();
    let mut c = beltune_rt::control::CascadeConfig::<f64>::new(
        beltune_rt::control::CascadeGains::new(15.344, 0.0758, 0.556),
        1e-3,
        2e-3,
        3.1,
    )
    .unwrap();
    // K_PP 15.344 1/s in 0.01/s: 1534
    assert_eq!(
        p.objects(&c, 0).unwrap(),
        vec![(0x3000, 1, 1534u16.to_le_bytes().to_vec())]
    );
    c.gains.k_pp_per_s = 1000.0;
    assert!(p
        .objects(&c, 0)
        .unwrap_err()
        .to_string()
        .contains("does not fit"));
}
