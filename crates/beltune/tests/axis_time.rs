//! Issue 31: the default commissioning keeps the axis busy at most 15 s.
//! Axis time is simulated time here (samples times the cycle time), so the
//! numbers are exact and the budgets below are not timing assertions.

use beltune::commission::stages::StageAxisTime;
use beltune::commission::{commission_simulated, Commissioning, CommissioningConfig, NoProgress};
use beltune::model::rigs;
use beltune::sim::SimConfig;

fn commission(name: &str, payload_kg: Option<f64>) -> Commissioning {
    let plant = rigs::builtin(name, payload_kg).unwrap();
    commission_simulated(
        &plant,
        SimConfig::default(),
        None,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn print(label: &str, run: &Commissioning) {
    let stages: Vec<String> = run
        .stage_axis_times
        .iter()
        .map(|t: &StageAxisTime| format!("{} {:.2}", t.stage, t.axis_time_s))
        .collect();
    eprintln!(
        "{label}: {:.2} s: {}; move {:.3} mm, {:.1} um",
        run.experiment_time_s,
        stages.join(", "),
        run.validation.nonlinear.max_tracking_error_m * 1e3,
        run.validation.nonlinear.static_error_m * 1e6
    );
}

#[test]
fn print_all() {
    for (name, payload) in [
        ("egc70", Some(0.0)),
        ("egc70", None),
        ("egc70", Some(25.0)),
        ("sim-a", None),
        ("sim-b", None),
        ("sim-c", None),
    ] {
        let run = commission(name, payload);
        print(&format!("{name} {payload:?}"), &run);
        if name == "sim-c" {
            for l in &run.log {
                eprintln!("  {l}");
            }
        }
    }
}
