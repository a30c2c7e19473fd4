//! Unit labels of a result in torque (SI) or current units.
//!
//! A record whose input was a motor current in A (torque constant unknown,
//! `--current-units`) is identified and designed with the same numbers, every
//! N m reading A: an inertia is then in A s^2/rad, a gain `K_P` in A s/rad, a
//! mass (force per acceleration, force = torque / `i_t`) in A s^2/m^2. Files keep
//! the key names of the SI record and say `units = "current"`; the output files
//! (`commissioning.json`, `controller.toml`) rename the unit suffixes of their
//! keys ([`relabel_keys`]) so that no key claims N m for a value in A, and
//! [`ControllerFile`](crate::record::controller::ControllerFile) maps
//! them back when reading.

use crate::ident::ModelUnits;

/// Human unit labels for one unit system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnitLabels {
    /// Torque (N m or A).
    pub torque: &'static str,
    /// Inertia `Theta_e`, `m_e` (kg m^2 or A s^2/rad).
    pub inertia: &'static str,
    /// Mass `m_c` (kg or A s^2/m^2).
    pub mass: &'static str,
    /// Stiffness `c` (N/m or A/m^2).
    pub stiffness: &'static str,
    /// Translational damping `d_m`, `d_c` (N s/m or A s/m^2).
    pub damping: &'static str,
    /// `K_P` and viscous friction (N m s/rad or A s/rad).
    pub torque_per_velocity: &'static str,
    /// `K_I` (N m/rad or A/rad).
    pub torque_per_angle: &'static str,
}

/// SI labels.
pub const TORQUE_LABELS: UnitLabels = UnitLabels {
    torque: "N m",
    inertia: "kg m^2",
    mass: "kg",
    stiffness: "N/m",
    damping: "N s/m",
    torque_per_velocity: "N m s/rad",
    torque_per_angle: "N m/rad",
};

/// Current-unit labels (every N m reads A).
pub const CURRENT_LABELS: UnitLabels = UnitLabels {
    torque: "A",
    inertia: "A s^2/rad",
    mass: "A s^2/m^2",
    stiffness: "A/m^2",
    damping: "A s/m^2",
    torque_per_velocity: "A s/rad",
    torque_per_angle: "A/rad",
};

/// The labels of `units`.
pub fn labels(units: ModelUnits) -> UnitLabels {
    match units {
        ModelUnits::Torque => TORQUE_LABELS,
        ModelUnits::Current => CURRENT_LABELS,
    }
}

/// Key suffixes of torque units and their current-unit spelling, longest first.
const SUFFIXES: [(&str, &str); 7] = [
    ("_nm_s_per_rad", "_a_s_per_rad"),
    ("_nm_per_rad", "_a_per_rad"),
    ("_kg_m2", "_a_s2_per_rad"),
    ("_n_s_per_m", "_a_s_per_m2"),
    ("_n_per_m", "_a_per_m2"),
    ("_nm", "_a"),
    ("_kg", "_a_s2_per_m2"),
];

/// `key` with a torque-unit suffix replaced by its current-unit spelling
/// (`torque_max_nm` -> `torque_max_a`), or `None` if it has none.
pub fn current_key(key: &str) -> Option<String> {
    SUFFIXES
        .iter()
        .find_map(|(t, c)| key.strip_suffix(t).map(|stem| format!("{stem}{c}")))
}

/// The inverse of [`current_key`].
pub fn torque_key(key: &str) -> Option<String> {
    SUFFIXES
        .iter()
        .find_map(|(t, c)| key.strip_suffix(c).map(|stem| format!("{stem}{t}")))
}

/// Rename the unit suffixes of every key in a JSON tree (objects nested in
/// objects and arrays) with `rename`.
pub fn relabel_keys(v: &mut serde_json::Value, rename: &dyn Fn(&str) -> Option<String>) {
    match v {
        serde_json::Value::Object(map) => {
            let old = std::mem::take(map);
            for (k, mut x) in old {
                relabel_keys(&mut x, rename);
                map.insert(rename(&k).unwrap_or(k), x);
            }
        }
        serde_json::Value::Array(xs) => xs.iter_mut().for_each(|x| relabel_keys(x, rename)),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suffixes_map_both_ways() {
        for k in [
            "torque_max_nm",
            "k_p_nm_s_per_rad",
            "k_i_nm_per_rad",
            "inertia_kg_m2",
            "coulomb_nm",
            "m_c_kg",
            "c_n_per_m",
            "d_c_n_s_per_m",
        ] {
            let c = current_key(k).unwrap();
            assert!(!c.contains("_nm") && !c.contains("kg"), "{c}");
            assert_eq!(torque_key(&c).as_deref(), Some(k));
        }
        assert_eq!(current_key("ts_s"), None);
        assert_eq!(current_key("k_pp_per_s"), None);
        let mut v = serde_json::json!({"a_nm": 1, "b": [{"viscous_nm_s_per_rad": 2}]});
        relabel_keys(&mut v, &current_key);
        assert_eq!(
            v,
            serde_json::json!({"a_a": 1, "b": [{"viscous_a_s_per_rad": 2}]})
        );
    }
}
