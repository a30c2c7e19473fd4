//! Drive profiles: a TOML file that maps beltune's form of the controller
//! (the quantities of [`crate::loops`], SI units) onto a drive's objects,
//! so that a user adds a real drive's mapping without code. The master
//! writes each listed quantity by SDO (scaled into the object's unit and
//! type), reads it back, and switches the drive to the profile's mode.
//! The virtual drive's profile ships as
//! `crates/beltune-ethercat/profiles/beltune-virtual-servo.toml`
//! ([`DriveProfile::virtual_servo`]).
//!
//! ```toml
//! name = "beltune virtual servo"
//! vendor_id = 0x00000000
//! product_code = 0x00420402
//! mode = 8                      # CSP
//!
//! [[parameter]]
//! quantity = "k_pp_per_s"       # beltune's name, unit in it
//! index = 0x2000
//! sub = 1
//! type = "REAL32"               # REAL32 INTEGER32 UNSIGNED32 INTEGER16 UNSIGNED16 UNSIGNED8
//! scale = 1.0                   # object value = quantity * scale (default 1)
//! ```

use crate::cia402::MODE_CSP;
use crate::Error;
use beltune_rt::control::CascadeConfig;
use serde::Deserialize;

/// The shipped profile of the virtual drive.
pub const VIRTUAL_SERVO_TOML: &str = include_str!("../profiles/beltune-virtual-servo.toml");
/// Largest profile file read, bytes.
pub const MAX_PROFILE_BYTES: u64 = 1 << 20;

/// CoE data types a profile may name (one expedited SDO transfer each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[allow(clippy::upper_case_acronyms)]
pub enum ObjectType {
    /// 32-bit float.
    REAL32,
    /// 32-bit signed.
    INTEGER32,
    /// 32-bit unsigned.
    UNSIGNED32,
    /// 16-bit signed.
    INTEGER16,
    /// 16-bit unsigned.
    UNSIGNED16,
    /// 8-bit unsigned.
    UNSIGNED8,
}

/// One quantity of the controller in a drive object.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileParameter {
    /// beltune's name of the quantity ([`crate::loops::quantity`]).
    pub quantity: String,
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// The object's data type.
    #[serde(rename = "type")]
    pub ty: ObjectType,
    /// Object value = quantity * scale.
    #[serde(default = "one")]
    pub scale: f64,
}

fn one() -> f64 {
    1.0
}

/// A drive profile.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveProfile {
    /// The drive's name (for messages).
    pub name: String,
    /// Vendor ID the profile is for (0x1018:01).
    pub vendor_id: u32,
    /// Product code the profile is for (0x1018:02).
    pub product_code: u32,
    /// Mode of operation in which the drive runs its loops (8: CSP).
    pub mode: i8,
    /// Where each quantity goes.
    #[serde(rename = "parameter")]
    pub parameters: Vec<ProfileParameter>,
}

impl DriveProfile {
    /// Parse and check a profile (`what` names it in errors).
    pub fn parse(text: &str, what: &str) -> Result<Self, Error> {
        let bad = |reason: String| Error::Config {
            name: "drive profile",
            reason: format!("{what}: {reason}"),
        };
        let p: DriveProfile = toml::from_str(text).map_err(|e| bad(e.message().to_string()))?;
        if p.mode != MODE_CSP {
            return Err(bad(format!(
                "mode {} is not supported (the drive's loops run in CSP, mode 8)",
                p.mode
            )));
        }
        let probe = CascadeConfig::<f64>::new(
            beltune_rt::control::CascadeGains::new(1.0, 1.0, 1.0),
            1e-3,
            2e-3,
            1.0,
        )
        .map_err(|e| bad(e.to_string()))?;
        for q in &p.parameters {
            if crate::loops::quantity(&q.quantity, &probe, 0).is_none() {
                return Err(bad(format!("unknown quantity `{}`", q.quantity)));
            }
            if !(q.scale.is_finite() && q.scale != 0.0) {
                return Err(bad(format!(
                    "`{}`: scale {} is not a finite non-zero number",
                    q.quantity, q.scale
                )));
            }
        }
        for (k, a) in p.parameters.iter().enumerate() {
            if p.parameters[..k]
                .iter()
                .any(|b| b.quantity == a.quantity || (b.index, b.sub) == (a.index, a.sub))
            {
                return Err(bad(format!(
                    "`{}` at {:#06x}:{:02x} is listed twice",
                    a.quantity, a.index, a.sub
                )));
            }
        }
        Ok(p)
    }

    /// Read a profile file (at most [`MAX_PROFILE_BYTES`]).
    pub fn read(path: &std::path::Path) -> Result<Self, Error> {
        let text = beltune::io::read_to_string_capped(path, MAX_PROFILE_BYTES)?;
        Self::parse(&text, &path.display().to_string())
    }

    /// The shipped profile of the virtual drive.
    pub fn virtual_servo() -> Self {
        Self::parse(VIRTUAL_SERVO_TOML, "profiles/beltune-virtual-servo.toml")
            .expect("the shipped profile parses (tested)")
    }

    /// Whether the profile is for the drive with this identity.
    pub fn matches(&self, vendor_id: u32, product_code: u32) -> bool {
        (self.vendor_id, self.product_code) == (vendor_id, product_code)
    }

    /// The objects to write for the cascade `c` with a preview of `preview`
    /// cycles: `(index, sub-index, little-endian bytes)`; an error for a
    /// value the object's type cannot hold.
    pub fn objects(
        &self,
        c: &CascadeConfig<f64>,
        preview: u8,
    ) -> Result<Vec<(u16, u8, Vec<u8>)>, Error> {
        self.parameters
            .iter()
            .map(|q| {
                let v =
                    crate::loops::quantity(&q.quantity, c, preview).unwrap_or(f64::NAN) * q.scale;
                let out_of_range = || Error::Config {
                    name: "drive profile",
                    reason: format!(
                        "{}: {} = {v} does not fit {:?} at {:#06x}:{:02x}",
                        self.name, q.quantity, q.ty, q.index, q.sub
                    ),
                };
                if !v.is_finite() {
                    return Err(out_of_range());
                }
                let int = |lo: f64, hi: f64| {
                    let r = v.round();
                    if (lo..=hi).contains(&r) {
                        Ok(r)
                    } else {
                        Err(out_of_range())
                    }
                };
                let bytes = match q.ty {
                    ObjectType::REAL32 => {
                        if v.abs() > f64::from(f32::MAX) {
                            return Err(out_of_range());
                        }
                        (v as f32).to_le_bytes().to_vec()
                    }
                    ObjectType::INTEGER32 => (int(i32::MIN.into(), i32::MAX.into())? as i32)
                        .to_le_bytes()
                        .to_vec(),
                    ObjectType::UNSIGNED32 => {
                        (int(0.0, u32::MAX.into())? as u32).to_le_bytes().to_vec()
                    }
                    ObjectType::INTEGER16 => (int(i16::MIN.into(), i16::MAX.into())? as i16)
                        .to_le_bytes()
                        .to_vec(),
                    ObjectType::UNSIGNED16 => {
                        (int(0.0, u16::MAX.into())? as u16).to_le_bytes().to_vec()
                    }
                    ObjectType::UNSIGNED8 => vec![int(0.0, 255.0)? as u8],
                };
                Ok((q.index, q.sub, bytes))
            })
            .collect()
    }
}
