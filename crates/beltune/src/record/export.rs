//! Firmware export of a `controller.toml`: a Rust module of `const`s that builds
//! the `beltune_rt` [`CascadeConfig`](beltune_rt::control::CascadeConfig), and a C
//! header with the same values for the C ABI of `beltune-rt-ffi`
//! (`BtCascadeConfig`, `BtSetpointConfig`; in single precision
//! `BtCascadeConfigF32`, `BtSetpointConfigF32` with `float` literals).
//!
//! Both list the same named scalars first (`pub const TS_S: f64 = ...;` and
//! `#define BELTUNE_TS_S ...`), printed as the shortest text that reads back
//! to the same `f64` (Rust's `{:?}`), and build the structs from those names,
//! so the two exports agree to the last digit. In current units the names
//! carry the current spelling of the unit (`TORQUE_MAX_A`, see [`crate::units`]).

use crate::ident::ModelUnits;
use crate::record::controller::{AntiWindupKind, ControllerFile};
use std::fmt::Write as _;

/// Target language of [`export`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lang {
    /// A Rust module (`const`s of `beltune_rt` types).
    Rust,
    /// A C header for `beltune_rt.h`.
    C,
}

/// Float type of the exported constants and structs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Precision {
    /// `f64` / `double` (the default): the values exactly as in the file.
    #[default]
    F64,
    /// `f32` / `float`, for MCUs with a single-precision FPU (Cortex-M4F):
    /// each value rounded to the nearest `f32`, printed as the shortest text
    /// that reads back to that `f32` (in C with the suffix `f`, a `float`
    /// constant), for `CascadeConfig<f32>` in Rust and the single-precision
    /// ABI of beltune-rt-ffi (`BtCascadeConfigF32`) in C.
    F32,
}

impl Precision {
    fn rust_type(self) -> &'static str {
        match self {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        }
    }

    /// The C names of the two configuration structs of beltune_rt.h.
    fn c_structs(self) -> (&'static str, &'static str) {
        match self {
            Precision::F64 => ("BtCascadeConfig", "BtSetpointConfig"),
            Precision::F32 => ("BtCascadeConfigF32", "BtSetpointConfigF32"),
        }
    }
}

/// One named value of the export.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// A real number.
    Real(f64),
    /// A sample count.
    Count(usize),
    /// A switch.
    Flag(bool),
}

/// The named values of `file`, in order; names are lower case with unit
/// suffixes (current spelling in current units).
pub fn values(file: &ControllerFile) -> Vec<(String, Value)> {
    use Value::*;
    let g = &file.gains;
    let f = &file.feedforward;
    let s = &file.setpoint;
    let v = file.velocity_filter.coeffs;
    let p = &file.prefilter.sections;
    let d = &file.drive_form;
    let mut out: Vec<(String, Value)> = vec![
        ("ts_s".into(), Real(file.ts_s)),
        ("torque_max_nm".into(), Real(file.torque_max_nm)),
        ("torque_offset_nm".into(), Real(file.torque_offset_nm)),
        ("k_pp_per_s".into(), Real(g.k_pp_per_s)),
        ("k_p_nm_s_per_rad".into(), Real(g.k_p_nm_s_per_rad)),
        ("k_i_nm_per_rad".into(), Real(g.k_i_nm_per_rad)),
        ("k_v".into(), Real(g.k_v)),
        ("velocity_filter_b0".into(), Real(v[0])),
        ("velocity_filter_b1".into(), Real(v[1])),
        ("velocity_filter_a1".into(), Real(v[2])),
    ];
    for (i, sec) in p.iter().enumerate() {
        for (n, c) in ["b0", "b1", "b2", "a1", "a2"].iter().zip(sec) {
            out.push((format!("prefilter{}_{n}", i + 1), Real(*c)));
        }
    }
    out.extend([
        ("ff_inertia".into(), Flag(f.inertia)),
        ("ff_viscous".into(), Flag(f.viscous)),
        ("ff_coulomb".into(), Flag(f.coulomb)),
        ("ff_inertia_kg_m2".into(), Real(f.inertia_kg_m2)),
        (
            "ff_viscous_nm_s_per_rad".into(),
            Real(f.viscous_nm_s_per_rad),
        ),
        ("ff_coulomb_nm".into(), Real(f.coulomb_nm)),
        (
            "ff_coulomb_deadband_rad_s".into(),
            Real(f.coulomb_deadband_rad_s),
        ),
        (
            "ff_coulomb_breakaway_rad".into(),
            Real(f.coulomb_breakaway_rad),
        ),
        (
            "filter_desired_velocity".into(),
            Flag(f.filter_desired_velocity),
        ),
        ("feedforward_preview".into(), Flag(f.preview)),
        ("preview_samples".into(), Count(f.preview_samples)),
        ("dead_time_s".into(), Real(f.dead_time_s)),
        (
            "anti_windup_conditional".into(),
            Flag(file.anti_windup == AntiWindupKind::ConditionalIntegration),
        ),
        ("i_t_m_per_rad".into(), Real(s.i_t_m_per_rad)),
        ("belt_stretch_on".into(), Flag(s.belt_stretch)),
        ("m_c_kg".into(), Real(s.m_c_kg)),
        ("c_n_per_m".into(), Real(s.c_n_per_m)),
        ("static_stretch_m".into(), Real(s.static_stretch_m)),
        ("stiffness_position_m".into(), Real(s.stiffness_position_m)),
        (
            "compliance_slope_per_n".into(),
            Real(s.compliance_slope_per_n),
        ),
        (
            "compliance_curvature_per_n_m".into(),
            Real(s.compliance_curvature_per_n_m),
        ),
        (
            "static_force_n".into(),
            Real(s.static_force_n.unwrap_or(s.static_stretch_m * s.c_n_per_m)),
        ),
        (
            "cart_viscous_n_s_per_m".into(),
            Real(s.cart_viscous_n_s_per_m),
        ),
        ("cart_coulomb_n".into(), Real(s.cart_coulomb_n)),
        ("coulomb_velocity_m_s".into(), Real(s.coulomb_velocity_m_s)),
        (
            "final_approach_distance_m".into(),
            Real(s.final_approach_distance_m),
        ),
        (
            "final_approach_speed_m_s".into(),
            Real(s.final_approach_speed_m_s),
        ),
        ("t_r_s".into(), Real(file.velocity_filter.t_r_s)),
        // drive-menu form (information)
        (
            "drive_velocity_gain_nm_s_per_rad".into(),
            Real(d.velocity_gain_nm_s_per_rad),
        ),
        (
            "drive_position_gain_per_s".into(),
            Real(d.position_gain_per_s),
        ),
        (
            "drive_velocity_filter_time_ms".into(),
            Real(d.velocity_filter_time_ms),
        ),
    ]);
    if let Some(tn) = d.integral_time_ms {
        out.push(("drive_integral_time_ms".into(), Real(tn)));
    }
    if let Some(x) = d.filter_frequency_hz {
        out.push(("drive_filter_frequency_hz".into(), Real(x)));
    }
    if let Some(x) = d.filter_damping {
        out.push(("drive_filter_damping".into(), Real(x)));
    }
    if file.units == ModelUnits::Current {
        for (n, _) in out.iter_mut() {
            if let Some(c) = crate::units::current_key(n) {
                *n = c;
            }
        }
    }
    out
}

/// `x` as the shortest literal that reads back to the same `f64` in Rust and
/// C, or (`F32`) to the `f32` nearest to `x` (in Rust; C adds the suffix `f`).
fn real(x: f64, precision: Precision) -> String {
    match precision {
        Precision::F64 => format!("{x:?}"),
        Precision::F32 => format!("{:?}", x as f32),
    }
}

/// How one language spells the values of the table ([`values`]): the two
/// exports differ only in this and in the struct literal built from the names.
struct Syntax {
    /// Prefix of every constant's name (`BELTUNE_` in C).
    prefix: &'static str,
    /// The declaration of one named value (the name already upper case).
    declare: fn(&str, &Value, Precision) -> String,
}

const RUST: Syntax = Syntax {
    prefix: "",
    declare: |name, v, precision| {
        let (ty, lit) = match v {
            Value::Real(x) => (precision.rust_type(), real(*x, precision)),
            Value::Count(c) => ("usize", c.to_string()),
            Value::Flag(b) => ("bool", b.to_string()),
        };
        format!("pub const {name}: {ty} = {lit};")
    },
};

const C: Syntax = Syntax {
    prefix: "BELTUNE_",
    declare: |name, v, precision| {
        let lit = match v {
            Value::Real(x) => match precision {
                Precision::F64 => real(*x, precision),
                Precision::F32 => real(*x, precision) + "f",
            },
            Value::Count(c) => format!("{c}u"),
            Value::Flag(b) => b.to_string(),
        };
        format!("#define BELTUNE_{name} {lit}")
    },
};

impl Syntax {
    /// The constant's name of the table entry `n` (lower case, torque
    /// spelling) in `file`'s units.
    fn name(&self, file: &ControllerFile, n: &str) -> String {
        let n = match file.units {
            ModelUnits::Current => crate::units::current_key(n).unwrap_or_else(|| n.to_string()),
            ModelUnits::Torque => n.to_string(),
        };
        format!("{}{}", self.prefix, n.to_ascii_uppercase())
    }

    /// One declaration per value of the table, one line each.
    fn declarations(&self, file: &ControllerFile, precision: Precision) -> String {
        values(file)
            .iter()
            .map(|(n, v)| (self.declare)(&n.to_ascii_uppercase(), v, precision) + "\n")
            .collect()
    }

    /// The names of the coefficients `b0, b1, b2, a1, a2` of prefilter section `i`.
    fn section(&self, file: &ControllerFile, i: usize) -> [String; 5] {
        ["b0", "b1", "b2", "a1", "a2"].map(|c| self.name(file, &format!("prefilter{i}_{c}")))
    }
}

/// `text` made safe for a `//` line comment of generated C or Rust source:
/// the one place where text from a file (the provenance of a
/// `controller.toml`, which a user may edit, holding a command line with any
/// characters) reaches generated source. Printable ASCII stays as it is but
/// for `\\` (a C line comment ending in a backslash continues onto the next
/// line), `?` (the trigraph `??/` is a backslash) and `%`; every other byte
/// (line breaks, NUL, control characters, non-ASCII) is written `%XX`, its
/// UTF-8 bytes in hex, like a URL. The result is one line that cannot end a
/// comment or continue it.
pub fn comment_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for b in text.bytes() {
        if (0x20..0x7f).contains(&b) && !matches!(b, b'\\' | b'?' | b'%') {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

fn header_lines(file: &ControllerFile, comment: &str) -> String {
    let p = &file.provenance;
    let l = crate::units::labels(file.units);
    format!(
        "{comment} beltune controller export (schema {}), generated by `beltune export`: do not edit.\n\
         {comment} From a controller.toml written by beltune {} at {}: {}\n\
         {comment} Torques in {}, gains K_P in {}, K_I in {}; angles in rad, times in s.\n",
        file.schema_version,
        comment_text(&p.beltune_version),
        comment_text(&p.created_utc),
        comment_text(&p.command_line_text()),
        l.torque,
        l.torque_per_velocity,
        l.torque_per_angle
    )
}

/// The export of `file` in `lang` (double precision).
pub fn export(file: &ControllerFile, lang: Lang) -> String {
    match lang {
        Lang::Rust => rust_module(file),
        Lang::C => c_header(file),
    }
}

/// The export of `file` in `lang` and `precision`. Errors for a value whose
/// magnitude an `f32` cannot hold (it would round to infinity) in `F32`.
pub fn export_as(
    file: &ControllerFile,
    lang: Lang,
    precision: Precision,
) -> crate::error::Result<String> {
    if precision == Precision::F32 {
        for (name, v) in values(file) {
            if let Value::Real(x) = v {
                if !(x as f32).is_finite() {
                    return Err(crate::Error::invalid(
                        name,
                        x,
                        "does not fit an f32 (export with --precision f64)",
                    ));
                }
            }
        }
    }
    Ok(match lang {
        Lang::Rust => rust_module_as(file, precision),
        Lang::C => c_header_as(file, precision),
    })
}

/// The Rust module: named `const`s, `CASCADE` (`CascadeConfig<f64>`) and
/// `BELT_STRETCH` (`BeltStretch<f64>`: the belt's compliance along the
/// stroke and the static force, [`beltune_rt::control::BeltProfile`]) for
/// `SetpointConversion::new(I_T_M_PER_RAD, BELT_STRETCH)`.
pub fn rust_module(file: &ControllerFile) -> String {
    rust_module_as(file, Precision::F64)
}

/// [`rust_module`] in `precision`: `CascadeConfig<f32>` and
/// `BeltStretch<f32>` with `f32` constants for [`Precision::F32`] (no check
/// that the values fit an `f32`: [`export_as`] does that).
pub fn rust_module_as(file: &ControllerFile, precision: Precision) -> String {
    let ty = precision.rust_type();
    let name = |n: &str| RUST.name(file, n);
    let mut s = header_lines(file, "//");
    s.push_str(
        "\nuse beltune_rt::control::{\n    AntiWindup, BeltProfile, BeltStretch, CascadeConfig, CascadeGains, Feedforward,\n    FeedforwardParams, FeedforwardTerms,\n};\nuse beltune_rt::filter::{FirstOrderCoeffs, SosCoeffs};\n\n",
    );
    s.push_str(&RUST.declarations(file, precision));
    let sos = |i: usize| {
        let [b0, b1, b2, a1, a2] = RUST.section(file, i);
        format!(
            "SosCoeffs {{\n            b0: {b0},\n            b1: {b1},\n            b2: {b2},\n            a1: {a1},\n            a2: {a2},\n        }}"
        )
    };
    let aw = match file.anti_windup {
        AntiWindupKind::ConditionalIntegration => "AntiWindup::ConditionalIntegration",
        AntiWindupKind::Off => "AntiWindup::Off",
    };
    let _ = write!(
        s,
        "\n/// The commissioned controller.\npub const CASCADE: CascadeConfig<{ty}> = CascadeConfig {{\n    ts_s: TS_S,\n    gains: CascadeGains {{\n        k_pp_per_s: K_PP_PER_S,\n        k_p_nm_s_per_rad: {kp},\n        k_i_nm_per_rad: {ki},\n        k_v: K_V,\n    }},\n    velocity_filter: FirstOrderCoeffs {{\n        b0: VELOCITY_FILTER_B0,\n        b1: VELOCITY_FILTER_B1,\n        a1: VELOCITY_FILTER_A1,\n    }},\n    prefilter: [\n        {s1},\n        {s2},\n    ],\n    torque_max_nm: {tmax},\n    anti_windup: {aw},\n    feedforward: Feedforward {{\n        params: FeedforwardParams {{\n            inertia_kg_m2: {ffi},\n            viscous_nm_s_per_rad: {ffv},\n            coulomb_nm: {ffc},\n            coulomb_deadband_rad_s: FF_COULOMB_DEADBAND_RAD_S,\n            coulomb_breakaway_rad: FF_COULOMB_BREAKAWAY_RAD,\n        }},\n        terms: FeedforwardTerms {{\n            inertia: FF_INERTIA,\n            viscous: FF_VISCOUS,\n            coulomb: FF_COULOMB,\n        }},\n    }},\n    torque_offset_nm: {toff},\n    filter_desired_velocity: FILTER_DESIRED_VELOCITY,\n    feedforward_preview: FEEDFORWARD_PREVIEW,\n}};\n",
        kp = name("k_p_nm_s_per_rad"),
        ki = name("k_i_nm_per_rad"),
        s1 = sos(1),
        s2 = sos(2),
        tmax = name("torque_max_nm"),
        ffi = name("ff_inertia_kg_m2"),
        ffv = name("ff_viscous_nm_s_per_rad"),
        ffc = name("ff_coulomb_nm"),
        toff = name("torque_offset_nm"),
    );
    let belt = if file.setpoint.belt_stretch {
        format!(
            "BeltStretch::Profile(BeltProfile {{\n    m_c_kg: {},\n    reference_m: {},\n    compliance_m_per_n: 1.0 / {},\n    compliance_slope_per_n: {},\n    compliance_curvature_per_n_m: {},\n    static_force_n: {},\n    cart_viscous_n_s_per_m: {},\n    cart_coulomb_n: {},\n    coulomb_velocity_m_s: {},\n}})",
            name("m_c_kg"),
            name("stiffness_position_m"),
            name("c_n_per_m"),
            name("compliance_slope_per_n"),
            name("compliance_curvature_per_n_m"),
            name("static_force_n"),
            name("cart_viscous_n_s_per_m"),
            name("cart_coulomb_n"),
            name("coulomb_velocity_m_s"),
        )
    } else {
        "BeltStretch::Off".to_string()
    };
    let _ = write!(
        s,
        "\n/// Belt-stretch compensation of the setpoint conversion.\npub const BELT_STRETCH: BeltStretch<{ty}> = {belt};\n"
    );
    s
}

/// The C header: `#define BELTUNE_...` values, `BELTUNE_CASCADE`
/// (`BtCascadeConfig`) and `BELTUNE_SETPOINT` (`BtSetpointConfig`) of `beltune_rt.h`.
pub fn c_header(file: &ControllerFile) -> String {
    c_header_as(file, Precision::F64)
}

/// [`c_header`] in `precision`: for [`Precision::F32`] `float` constants
/// (`0.1f`) and the single-precision structs `BtCascadeConfigF32` and
/// `BtSetpointConfigF32` for `bt_cascade_f32_init` and `bt_setpoint_f32_init`
/// (no check that the values fit a `float`: [`export_as`] does that).
pub fn c_header_as(file: &ControllerFile, precision: Precision) -> String {
    let name = |n: &str| C.name(file, n);
    let (cascade_struct, setpoint_struct) = precision.c_structs();
    let mut s = header_lines(file, "//");
    s.push_str("#ifndef BELTUNE_CONTROLLER_H\n#define BELTUNE_CONTROLLER_H\n\n#include \"beltune_rt.h\"\n\n");
    s.push_str(&C.declarations(file, precision));
    let sec = |i: usize| format!("{{{}}}", C.section(file, i).join(", "));
    let aw = match file.anti_windup {
        AntiWindupKind::ConditionalIntegration => "BT_ANTI_WINDUP_CONDITIONAL",
        AntiWindupKind::Off => "BT_ANTI_WINDUP_OFF",
    };
    let _ = write!(
        s,
        "\n/* The commissioned controller. */\nstatic const {cascade_struct} BELTUNE_CASCADE = {{\n    .ts_s = BELTUNE_TS_S,\n    .k_pp_per_s = BELTUNE_K_PP_PER_S,\n    .k_p_nm_s_per_rad = {kp},\n    .k_i_nm_per_rad = {ki},\n    .k_v = BELTUNE_K_V,\n    .velocity_filter = {{BELTUNE_VELOCITY_FILTER_B0, BELTUNE_VELOCITY_FILTER_B1, BELTUNE_VELOCITY_FILTER_A1}},\n    .prefilter = {{\n        {s1},\n        {s2},\n    }},\n    .torque_max_nm = {tmax},\n    .anti_windup = {aw},\n    .ff_inertia = BELTUNE_FF_INERTIA,\n    .ff_viscous = BELTUNE_FF_VISCOUS,\n    .ff_coulomb = BELTUNE_FF_COULOMB,\n    .inertia_kg_m2 = {ffi},\n    .viscous_nm_s_per_rad = {ffv},\n    .coulomb_nm = {ffc},\n    .coulomb_deadband_rad_s = BELTUNE_FF_COULOMB_DEADBAND_RAD_S,\n    .coulomb_breakaway_rad = BELTUNE_FF_COULOMB_BREAKAWAY_RAD,\n    .torque_offset_nm = {toff},\n    .filter_desired_velocity = BELTUNE_FILTER_DESIRED_VELOCITY,\n    .feedforward_preview = BELTUNE_FEEDFORWARD_PREVIEW,\n}};\n\n/* The cart -> motor setpoint conversion. */\nstatic const {setpoint_struct} BELTUNE_SETPOINT = {{\n    .i_t_m_per_rad = BELTUNE_I_T_M_PER_RAD,\n    .belt_stretch = BELTUNE_BELT_STRETCH_ON,\n    .m_c_kg = {mc},\n    .c_n_per_m = {c},\n    .stiffness_position_m = {sp},\n    .compliance_slope_per_n = {cs},\n    .compliance_curvature_per_n_m = {cc},\n    .static_force_n = {sf},\n    .cart_viscous_n_s_per_m = {cv},\n    .cart_coulomb_n = {cf},\n    .coulomb_velocity_m_s = {vc},\n}};\n\n#endif /* BELTUNE_CONTROLLER_H */\n",
        kp = name("k_p_nm_s_per_rad"),
        ki = name("k_i_nm_per_rad"),
        s1 = sec(1),
        s2 = sec(2),
        tmax = name("torque_max_nm"),
        ffi = name("ff_inertia_kg_m2"),
        ffv = name("ff_viscous_nm_s_per_rad"),
        ffc = name("ff_coulomb_nm"),
        toff = name("torque_offset_nm"),
        mc = name("m_c_kg"),
        c = name("c_n_per_m"),
        sp = name("stiffness_position_m"),
        cs = name("compliance_slope_per_n"),
        cc = name("compliance_curvature_per_n_m"),
        sf = name("static_force_n"),
        cv = name("cart_viscous_n_s_per_m"),
        cf = name("cart_coulomb_n"),
        vc = name("coulomb_velocity_m_s"),
    );
    s
}

/// The named values of an export (`pub const NAME: T = LIT;` or
/// `#define BELTUNE_NAME LIT`), as `(name in lower case, literal)`.
pub fn parse_values(text: &str) -> Vec<(String, String)> {
    text.lines()
        .filter_map(|l| {
            if let Some(rest) = l.strip_prefix("pub const ") {
                let (name, rest) = rest.split_once(':')?;
                let (ty, lit) = rest.split_once('=')?;
                if ty.trim().contains('<') {
                    return None;
                }
                let lit = lit.trim().strip_suffix(';')?;
                return Some((name.trim().to_ascii_lowercase(), lit.to_string()));
            }
            let rest = l.strip_prefix("#define BELTUNE_")?;
            let (name, lit) = rest.split_once(' ')?;
            let lit = lit.trim();
            let lit = lit.strip_suffix('u').unwrap_or(lit);
            // a `float` constant (`0.1f`) of a single-precision header
            let lit = match lit.strip_suffix('f') {
                Some(x) if x.parse::<f64>().is_ok() => x,
                _ => lit,
            };
            Some((name.to_ascii_lowercase(), lit.to_string()))
        })
        .filter(|(n, _)| n != "controller_h")
        .collect()
}
