//! The one-knob setting `--dynamics` orders the delivered designs from slow
//! to fast on every axis: the velocity-loop and the position-loop crossover
//! never fall from conservative (0) over standard (0.5) to dynamic (1), and
//! the default is standard.
//!
//! The axes come from one function, [`axes`]: the built-in plants
//! (`beltune plant list`) and the seeded Monte Carlo sample's plants (the
//! generator of `beltune montecarlo`). An axis zoo extends that list.

use beltune::design::robust::{design_identified, DesignRule, RobustDesign};
use beltune::design::{DesignInput, DesignKnobs, Dynamics};
use beltune::model::stroke::StrokeVariation;
use beltune::model::{builtin, Plant, BUILTIN_NAMES};
use beltune::study::{generate, Ranges};
use rayon::prelude::*;

/// Seed of the Monte Carlo CI sample (tests/montecarlo.rs).
const MONTE_CARLO_SEED: u64 = 12;
/// Plants of the sample checked here (every one at five settings of the knob).
const MONTE_CARLO_PLANTS: u64 = 16;
/// The settings checked, slow to fast.
const SETTINGS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];
/// Relative tolerance of "never falls": the crossovers are found by bisection
/// to 1e-13 and verified on the 500-points-per-decade grid, so two designs
/// that are the same candidate agree to far better than this.
const REL_TOL: f64 = 1e-9;

/// Every axis the knob is checked on: (name, plant).
fn axes() -> Vec<(String, Plant)> {
    let mut out: Vec<(String, Plant)> = BUILTIN_NAMES
        .iter()
        .map(|n| (n.to_string(), builtin(n, None).expect("a built-in plant")))
        .collect();
    for i in 0..MONTE_CARLO_PLANTS {
        let g = generate(MONTE_CARLO_SEED, i, &Ranges::default()).expect("a generated plant");
        out.push((
            format!("montecarlo seed {MONTE_CARLO_SEED} #{i}"),
            Plant::Physical(g.params),
        ));
    }
    out
}

/// The commissioning's design rule for `plant` (its two-mass linearization at
/// the worst-case position, its true viscous friction, 5 % uncertainties) at
/// `dynamics`, checked along its stroke.
fn design_at(plant: &Plant, dynamics: Dynamics) -> beltune::Result<RobustDesign> {
    let model = plant.worst_case_two_mass()?;
    let input = DesignInput::new(model, plant.dead_time_s());
    let knobs = dynamics.knobs(&DesignKnobs::default());
    let stroke = StrokeVariation::of(plant, plant.worst_case_position_m());
    design_identified(
        &input,
        Some(plant.friction_totals().viscous_nm_s_per_rad),
        f64::NAN,
        f64::NAN,
        stroke.as_ref(),
        &knobs,
        DesignRule::Robust,
    )
}

/// The velocity and position crossovers of a design, rad/s (`None`: no design).
type Crossovers = Option<(f64, f64)>;

#[test]
fn dynamics_orders_the_designs_from_slow_to_fast_on_every_axis() {
    let axes = axes();
    let rows: Vec<(String, Vec<Crossovers>)> = axes
        .par_iter()
        .map(|(name, plant)| {
            let row = SETTINGS
                .iter()
                .map(|&x| {
                    design_at(plant, Dynamics::new(x).unwrap()).ok().map(|r| {
                        (
                            r.design.velocity_margins.crossover_rad_s,
                            r.design.position_margins.crossover_rad_s,
                        )
                    })
                })
                .collect();
            (name.clone(), row)
        })
        .collect();
    let mut faster = 0;
    for (name, row) in &rows {
        eprintln!("{name}: {row:?}");
        for pair in row.windows(2) {
            match (pair[0], pair[1]) {
                (Some((v0, p0)), Some((v1, p1))) => {
                    assert!(
                        v1 >= v0 * (1.0 - REL_TOL) && p1 >= p0 * (1.0 - REL_TOL),
                        "{name}: a faster setting gave a slower loop: {row:?}"
                    );
                }
                // a faster setting admits more designs, never fewer
                (Some(_), None) => panic!("{name}: a faster setting found no design: {row:?}"),
                _ => {}
            }
        }
        if let (Some(Some((v0, p0))), Some(Some((v1, p1)))) =
            (row.first().copied(), row.last().copied())
        {
            if v1 > v0 * 1.05 && p1 > p0 * 1.05 {
                faster += 1;
            }
        }
    }
    // The knob must do something: dynamic is clearly faster (> 5 % in both
    // loops) than conservative on most axes.
    assert!(
        2 * faster > rows.len(),
        "dynamic is clearly faster on only {faster} of {} axes",
        rows.len()
    );
}

/// Without `--dynamics` every command designs as with `--dynamics standard`.
#[test]
fn the_default_dynamics_is_standard() {
    assert_eq!(DesignKnobs::default().dynamics, Dynamics::STANDARD);
    assert_eq!(Dynamics::default(), Dynamics::STANDARD);
    assert_eq!(
        Dynamics::STANDARD.knobs(&DesignKnobs::default()),
        DesignKnobs::default()
    );
    let plant = builtin("egc70", None).unwrap();
    let standard = design_at(&plant, Dynamics::STANDARD).unwrap();
    let model = plant.worst_case_two_mass().unwrap();
    let default = design_identified(
        &DesignInput::new(model, plant.dead_time_s()),
        Some(plant.friction_totals().viscous_nm_s_per_rad),
        f64::NAN,
        f64::NAN,
        StrokeVariation::of(&plant, plant.worst_case_position_m()).as_ref(),
        &DesignKnobs::default(),
        DesignRule::default(),
    )
    .unwrap();
    assert_eq!(standard.design, default.design);
}
