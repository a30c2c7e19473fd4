//! The drive's own position and velocity loops: the `beltune-rt` cascade
//! (Figure 4.1: P position loop, PI velocity loop with the velocity filter
//! (6.1), prefilter, anti-windup (6.26), feedforward (4.16) with the
//! dead-time preview) as firmware of the virtual drive in cyclic synchronous
//! position mode (CSP, mode 8), parameterised through manufacturer objects.
//!
//! One table ([`PARAMETERS`]) says where each quantity of a
//! [`CascadeConfig`] lives in the drive's object dictionary (REAL32, as
//! drives keep their gains, and as `ethercrab` writes them: expedited, 4
//! bytes); the dictionary's entries and the drive's controller are built
//! from it. The master knows a drive's objects from its drive profile
//! ([`crate::profile`]); the virtual drive's shipped profile is tested
//! against this table. The drive runs the cascade in
//! `f32`, as motor firmware does (the crate's README gives its per-sample
//! cost).
//!
//! | object | entries |
//! | --- | --- |
//! | 0x2000 position loop | K_PP [1/s], K_v [1] |
//! | 0x2001 velocity loop | K_P [N m s/rad], K_I [N m/rad], velocity filter b0, b1 [1/s], a1 [1] |
//! | 0x2002 prefilter | two second-order sections b0, b1, b2, a1, a2 |
//! | 0x2003 feedforward | inertia [kg m^2], viscous [N m s/rad], Coulomb [N m], deadband [rad/s], breakaway [rad], terms (bits: inertia, viscous, Coulomb) |
//! | 0x2004 options | torque limit [N m], torque offset [N m], options (bits: filtered desired velocity, feedforward preview, conditional integration), preview [cycles] |

use beltune_rt::control::{AntiWindup, CascadeConfig};

/// Position loop object.
pub const POSITION_LOOP: u16 = 0x2000;
/// Velocity loop object.
pub const VELOCITY_LOOP: u16 = 0x2001;
/// Prefilter object.
pub const PREFILTER: u16 = 0x2002;
/// Feedforward object.
pub const FEEDFORWARD: u16 = 0x2003;
/// Options object.
pub const OPTIONS: u16 = 0x2004;
/// Longest feedforward preview the drive buffers, cycles.
pub const MAX_PREVIEW: usize = 64;

/// A REAL32 parameter: object, sub-index, name (with its unit), and how
/// it is read from and written into a cascade configuration.
pub struct Parameter {
    /// beltune's name of the quantity (the key of a drive profile,
    /// [`crate::profile`]).
    pub quantity: &'static str,
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Name with unit.
    pub name: &'static str,
    /// The value in a configuration.
    pub get: fn(&CascadeConfig<f64>) -> f64,
    /// Set it in a configuration.
    pub set: fn(&mut CascadeConfig<f64>, f64),
}

macro_rules! p {
    ($q:expr, $i:expr, $s:expr, $n:expr, |$c:ident| $e:expr) => {
        Parameter {
            quantity: $q,
            index: $i,
            sub: $s,
            name: $n,
            get: |$c| $e,
            set: |$c, v| $e = v,
        }
    };
}

/// Every REAL32 parameter of the drive's loops.
pub const PARAMETERS: [Parameter; 24] = [
    p!("k_pp_per_s", POSITION_LOOP, 1, "K_PP [1/s]", |c| c
        .gains
        .k_pp_per_s),
    p!("k_v", POSITION_LOOP, 2, "K_v [1]", |c| c.gains.k_v),
    p!(
        "k_p_nm_s_per_rad",
        VELOCITY_LOOP,
        1,
        "K_P [N m s/rad]",
        |c| c.gains.k_p_nm_s_per_rad
    ),
    p!("k_i_nm_per_rad", VELOCITY_LOOP, 2, "K_I [N m/rad]", |c| c
        .gains
        .k_i_nm_per_rad),
    p!(
        "velocity_filter_b0",
        VELOCITY_LOOP,
        3,
        "Velocity filter b0 [1/s]",
        |c| c.velocity_filter.b0
    ),
    p!(
        "velocity_filter_b1",
        VELOCITY_LOOP,
        4,
        "Velocity filter b1 [1/s]",
        |c| c.velocity_filter.b1
    ),
    p!(
        "velocity_filter_a1",
        VELOCITY_LOOP,
        5,
        "Velocity filter a1 [1]",
        |c| c.velocity_filter.a1
    ),
    p!("prefilter_1_b0", PREFILTER, 1, "Section 1 b0", |c| c
        .prefilter[0]
        .b0),
    p!("prefilter_1_b1", PREFILTER, 2, "Section 1 b1", |c| c
        .prefilter[0]
        .b1),
    p!("prefilter_1_b2", PREFILTER, 3, "Section 1 b2", |c| c
        .prefilter[0]
        .b2),
    p!("prefilter_1_a1", PREFILTER, 4, "Section 1 a1", |c| c
        .prefilter[0]
        .a1),
    p!("prefilter_1_a2", PREFILTER, 5, "Section 1 a2", |c| c
        .prefilter[0]
        .a2),
    p!("prefilter_2_b0", PREFILTER, 6, "Section 2 b0", |c| c
        .prefilter[1]
        .b0),
    p!("prefilter_2_b1", PREFILTER, 7, "Section 2 b1", |c| c
        .prefilter[1]
        .b1),
    p!("prefilter_2_b2", PREFILTER, 8, "Section 2 b2", |c| c
        .prefilter[1]
        .b2),
    p!("prefilter_2_a1", PREFILTER, 9, "Section 2 a1", |c| c
        .prefilter[1]
        .a1),
    p!("prefilter_2_a2", PREFILTER, 10, "Section 2 a2", |c| c
        .prefilter[1]
        .a2),
    p!(
        "feedforward_inertia_kg_m2",
        FEEDFORWARD,
        1,
        "Inertia [kg m^2]",
        |c| c.feedforward.params.inertia_kg_m2
    ),
    p!(
        "feedforward_viscous_nm_s_per_rad",
        FEEDFORWARD,
        2,
        "Viscous [N m s/rad]",
        |c| c.feedforward.params.viscous_nm_s_per_rad
    ),
    p!(
        "feedforward_coulomb_nm",
        FEEDFORWARD,
        3,
        "Coulomb [N m]",
        |c| c.feedforward.params.coulomb_nm
    ),
    p!(
        "feedforward_coulomb_deadband_rad_s",
        FEEDFORWARD,
        4,
        "Coulomb deadband [rad/s]",
        |c| c.feedforward.params.coulomb_deadband_rad_s
    ),
    p!(
        "feedforward_coulomb_breakaway_rad",
        FEEDFORWARD,
        5,
        "Coulomb breakaway [rad]",
        |c| c.feedforward.params.coulomb_breakaway_rad
    ),
    p!("torque_max_nm", OPTIONS, 1, "Torque limit [N m]", |c| c
        .torque_max_nm),
    p!("torque_offset_nm", OPTIONS, 2, "Torque offset [N m]", |c| c
        .torque_offset_nm),
];

/// Quantity name of the feedforward terms (bits: inertia, viscous, Coulomb).
pub const TERMS_QUANTITY: &str = "feedforward_terms";
/// Quantity name of the option bits.
pub const OPTIONS_QUANTITY: &str = "options";
/// Quantity name of the feedforward preview, cycles.
pub const PREVIEW_QUANTITY: &str = "preview_cycles";

/// The value of quantity `name` of `c` with a preview of `preview` cycles
/// (the bit sets as numbers); `None` for a name beltune does not know.
pub fn quantity(name: &str, c: &CascadeConfig<f64>, preview: u8) -> Option<f64> {
    match name {
        TERMS_QUANTITY => Some(f64::from(terms_bits(c))),
        OPTIONS_QUANTITY => Some(f64::from(option_bits(c))),
        PREVIEW_QUANTITY => Some(f64::from(preview)),
        _ => PARAMETERS
            .iter()
            .find(|p| p.quantity == name)
            .map(|p| (p.get)(c)),
    }
}

/// Sub-index of the feedforward terms (UNSIGNED8) in [`FEEDFORWARD`].
pub const TERMS_SUB: u8 = 6;
/// Sub-index of the option bits (UNSIGNED8) in [`OPTIONS`].
pub const OPTIONS_SUB: u8 = 3;
/// Sub-index of the preview in cycles (UNSIGNED8) in [`OPTIONS`].
pub const PREVIEW_SUB: u8 = 4;

/// The feedforward terms as bits (0 inertia, 1 viscous, 2 Coulomb).
pub fn terms_bits(c: &CascadeConfig<f64>) -> u8 {
    let t = c.feedforward.terms;
    u8::from(t.inertia) | (u8::from(t.viscous) << 1) | (u8::from(t.coulomb) << 2)
}

/// The options as bits (0 filtered desired velocity, 1 feedforward preview,
/// 2 conditional integration).
pub fn option_bits(c: &CascadeConfig<f64>) -> u8 {
    u8::from(c.filter_desired_velocity)
        | (u8::from(c.feedforward_preview) << 1)
        | (u8::from(c.anti_windup == AntiWindup::ConditionalIntegration) << 2)
}

/// The configuration the objects describe (`ts_s` is the drive's cycle),
/// and the preview in cycles; `value(index, sub)` reads an object.
pub fn config_from(
    ts_s: f64,
    value: impl Fn(u16, u8) -> Option<Vec<u8>>,
) -> Option<(CascadeConfig<f64>, usize)> {
    let f = |i: u16, s: u8| -> Option<f64> {
        let v = value(i, s)?;
        Some(f64::from(f32::from_le_bytes(v.get(..4)?.try_into().ok()?)))
    };
    let byte = |i: u16, s: u8| value(i, s).and_then(|v| v.first().copied());
    let mut c = CascadeConfig::<f64>::new(
        beltune_rt::control::CascadeGains::new(0.0, 0.0, 0.0),
        ts_s,
        1e-3,
        1.0,
    )
    .ok()?;
    for p in &PARAMETERS {
        (p.set)(&mut c, f(p.index, p.sub)?);
    }
    let terms = byte(FEEDFORWARD, TERMS_SUB)?;
    c.feedforward.terms.inertia = terms & 1 != 0;
    c.feedforward.terms.viscous = terms & 2 != 0;
    c.feedforward.terms.coulomb = terms & 4 != 0;
    let options = byte(OPTIONS, OPTIONS_SUB)?;
    c.filter_desired_velocity = options & 1 != 0;
    c.feedforward_preview = options & 2 != 0;
    c.anti_windup = if options & 4 != 0 {
        AntiWindup::ConditionalIntegration
    } else {
        AntiWindup::Off
    };
    let preview = usize::from(byte(OPTIONS, PREVIEW_SUB)?).min(MAX_PREVIEW);
    Some((c, preview))
}
