//! The axis zoo: belt-axis designs built from public data sheets, one TOML
//! plant file each under `data/axes/` (each file cites its sources and
//! names its assumptions), spanning hobby GT2 axes to 4 m gantries, and the
//! physical definition of an axis that can do a modest move
//! ([`modest_move`]): the commissioning must succeed on every such axis
//! and refuse the others with their physical reason (`tests/zoo.rs`,
//! docs/zoo.md).

use crate::model::Plant;
use crate::{Error, Result};

/// The zoo's plant files, `(name, TOML text)`.
pub const ZOO_FILES: &[(&str, &str)] = &[
    (
        "gt2-hobby-300",
        include_str!("../../../../data/axes/gt2-hobby-300.toml"),
    ),
    (
        "gt2-hobby-500-1khz",
        include_str!("../../../../data/axes/gt2-hobby-500-1khz.toml"),
    ),
    (
        "gt2-gantry-2900",
        include_str!("../../../../data/axes/gt2-gantry-2900.toml"),
    ),
    (
        "gt2-z-planetary-vertical",
        include_str!("../../../../data/axes/gt2-z-planetary-vertical.toml"),
    ),
    (
        "egc70-empty-1khz",
        include_str!("../../../../data/axes/egc70-empty-1khz.toml"),
    ),
    (
        "egc70-payload-8khz-20bit",
        include_str!("../../../../data/axes/egc70-payload-8khz-20bit.toml"),
    ),
    (
        "egc70-vertical-g10",
        include_str!("../../../../data/axes/egc70-vertical-g10.toml"),
    ),
    (
        "egc80-2000-g3",
        include_str!("../../../../data/axes/egc80-2000-g3.toml"),
    ),
    (
        "egc120-1500-20kg",
        include_str!("../../../../data/axes/egc120-1500-20kg.toml"),
    ),
    (
        "egc185-4000-60kg-g3",
        include_str!("../../../../data/axes/egc185-4000-60kg-g3.toml"),
    ),
    (
        "t5-steel-3000-19kg",
        include_str!("../../../../data/axes/t5-steel-3000-19kg.toml"),
    ),
    (
        "preloaded-rail-1.5kg-45N",
        include_str!("../../../../data/axes/preloaded-rail-1.5kg-45N.toml"),
    ),
    (
        "stiff-short-300",
        include_str!("../../../../data/axes/stiff-short-300.toml"),
    ),
    (
        "line8-1500-4khz",
        include_str!("../../../../data/axes/line8-1500-4khz.toml"),
    ),
    (
        "heavy-motor-light-cart",
        include_str!("../../../../data/axes/heavy-motor-light-cart.toml"),
    ),
    (
        "egc50-300-hobby-servo",
        include_str!("../../../../data/axes/egc50-300-hobby-servo.toml"),
    ),
    (
        "underpowered-gantry",
        include_str!("../../../../data/axes/underpowered-gantry.toml"),
    ),
];

/// The zoo's plants by name, in [`ZOO_FILES`]' order.
pub fn zoo() -> Result<Vec<(&'static str, Plant)>> {
    ZOO_FILES
        .iter()
        .map(|(name, text)| {
            let plant: Plant = toml::from_str(text).map_err(|e| Error::Parse {
                path: format!("data/axes/{name}.toml"),
                message: e.message().to_string(),
            })?;
            plant.validate()?;
            Ok((*name, plant))
        })
        .collect()
}

/// The zoo's plant `name`.
pub fn zoo_plant(name: &str) -> Result<Plant> {
    zoo()?
        .into_iter()
        .find(|(n, _)| *n == name)
        .map(|(_, p)| p)
        .ok_or_else(|| Error::invalid("zoo axis", f64::NAN, format!("no axis named {name}")))
}

/// Length of a modest move, m.
pub const MODEST_MOVE_M: f64 = 0.1;
/// Room the commissioning needs beyond a move at either end of the stroke,
/// m (the window's clearances, the identification's excursion).
pub const STROKE_CLEARANCE_M: f64 = 0.05;
/// Acceleration of a modest move, m/s^2.
pub const MODEST_ACCELERATION_M_S2: f64 = 0.5;
/// Torque reserve a modest move keeps on top of what it needs (the
/// friction and the inertia are known to the data sheet's accuracy).
pub const MODEST_TORQUE_RESERVE: f64 = 1.25;
/// Encoder counts a modest move spans at least.
pub const MODEST_MOVE_COUNTS: f64 = 1000.0;

/// Whether the axis can physically do a modest move ([`MODEST_MOVE_M`] at
/// [`MODEST_ACCELERATION_M_S2`]): its stroke holds the move and the
/// commissioning's clearances, its torque limit covers gravity, Coulomb
/// friction and the acceleration of its rigid inertia with
/// [`MODEST_TORQUE_RESERVE`], and its encoder resolves the move into
/// [`MODEST_MOVE_COUNTS`]. `Err` names the first reason it cannot, in one
/// line.
pub fn modest_move(plant: &Plant) -> std::result::Result<(), String> {
    let stroke = plant.stroke_m().unwrap_or(0.6);
    if stroke < MODEST_MOVE_M + 2.0 * STROKE_CLEARANCE_M {
        return Err(format!(
            "the stroke {:.0} mm cannot hold a {:.0} mm move and {:.0} mm of clearance at either end",
            stroke * 1e3,
            MODEST_MOVE_M * 1e3,
            STROKE_CLEARANCE_M * 1e3
        ));
    }
    let model = plant.worst_case_two_mass().map_err(|e| e.to_string())?;
    let info = plant.info();
    let it = model.i_t;
    let gravity = match plant {
        Plant::Physical(p) => (p.gravity_force_n() * it).abs(),
        Plant::Linear(_) => 0.0,
    };
    let coulomb = plant.friction_totals().coulomb_nm;
    let accel = model.rigid_inertia() * MODEST_ACCELERATION_M_S2 / it;
    let need = MODEST_TORQUE_RESERVE * (gravity + coulomb + accel);
    if info.torque_max_nm < need {
        return Err(format!(
            "the torque limit {:.3} N m does not cover gravity {:.3} N m, Coulomb friction {:.3} N m and {:.1} m/s^2 of acceleration ({:.3} N m) with {:.0} % to spare",
            info.torque_max_nm,
            gravity,
            coulomb,
            MODEST_ACCELERATION_M_S2,
            accel,
            (MODEST_TORQUE_RESERVE - 1.0) * 100.0
        ));
    }
    let per_count = info.motor_rad_per_count * it;
    if MODEST_MOVE_M / per_count < MODEST_MOVE_COUNTS {
        return Err(format!(
            "the encoder resolves {:.0} um of belt travel per count: a {:.0} mm move spans fewer than {:.0} counts",
            per_count * 1e6,
            MODEST_MOVE_M * 1e3,
            MODEST_MOVE_COUNTS
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs::egc70_params;

    /// Every zoo file reads as a valid plant and cites its sources: a
    /// public address, or the thesis' appendix (the specification).
    #[test]
    fn the_zoo_reads() {
        let zoo = zoo().unwrap();
        assert!(zoo.len() >= 15);
        for (name, text) in ZOO_FILES {
            assert!(text.contains("# Sources"), "{name}");
            assert!(
                text.contains("http") || text.contains("thesis Appendix A"),
                "{name} cites no source"
            );
        }
    }

    /// The definition of "can": each criterion decides on its own side of
    /// its threshold (egc70 with the torque limit, stroke or encoder just
    /// above and just below what a modest move needs).
    #[test]
    fn the_modest_move_definition_holds_at_its_thresholds() {
        let base = egc70_params(0.0);
        let plant = Plant::Physical(base.clone());
        assert_eq!(modest_move(&plant), Ok(()));
        let model = plant.worst_case_two_mass().unwrap();
        let need = MODEST_TORQUE_RESERVE
            * (plant.friction_totals().coulomb_nm
                + model.rigid_inertia() * MODEST_ACCELERATION_M_S2 / model.i_t);
        let with_torque = |t: f64| {
            Plant::Physical(crate::model::PhysicalParams {
                torque_max_nm: t,
                ..base.clone()
            })
        };
        assert!(modest_move(&with_torque(need * 1.01)).is_ok());
        let e = modest_move(&with_torque(need * 0.99)).unwrap_err();
        assert!(e.contains("torque limit") && !e.contains('\n'), "{e}");
        // gravity counts: the same axis standing upright needs more
        let upright = Plant::Physical(crate::model::PhysicalParams {
            tilt_rad: std::f64::consts::FRAC_PI_2,
            payload_kg: 20.0,
            torque_max_nm: need * 1.01,
            ..base.clone()
        });
        assert!(modest_move(&upright).unwrap_err().contains("gravity"));
        let short = |s: f64| {
            Plant::Physical(crate::model::PhysicalParams {
                stroke_m: s,
                pulley_distance_m: s + 0.24,
                ..base.clone()
            })
        };
        assert!(modest_move(&short(0.21)).is_ok());
        assert!(modest_move(&short(0.19)).unwrap_err().contains("stroke"));
        let coarse = |counts: f64| {
            Plant::Physical(crate::model::PhysicalParams {
                motor_rad_per_count: 2.0 * std::f64::consts::PI / counts,
                ..base.clone()
            })
        };
        // 78 mm per revolution: 1000 counts in 100 mm need 780 per revolution
        assert!(modest_move(&coarse(800.0)).is_ok());
        assert!(modest_move(&coarse(760.0)).unwrap_err().contains("encoder"));
    }
}
