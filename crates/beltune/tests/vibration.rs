//! The vibration benchmark on commissioned axes (issue 32).

use beltune::commission::{commission_simulated, CommissioningConfig, NoProgress};
use beltune::model::rigs::builtin;
use beltune::model::Plant;
use beltune::record::commissioning::{AxisRecord, Origin};
use beltune::record::provenance::Provenance;
use beltune::report::folder::ResultSet;
use beltune::sim::SimConfig;
use beltune::vibration::bench::{self, BenchSetup, VibrationBenchmark};

fn commissioned(
    name: &str,
    plant: &Plant,
    payload_range: Option<(f64, f64)>,
) -> VibrationBenchmark {
    let sim = SimConfig {
        seed: 1,
        ..SimConfig::default()
    };
    let run = commission_simulated(
        plant,
        sim,
        None,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap();
    let origin = Origin {
        name: name.into(),
        axis: AxisRecord::simulated(name, plant, 0.05, 1),
        truth: None,
        provenance: Provenance::of_this_process(Some(1)),
    };
    let set = ResultSet::of_run(&run, &origin).unwrap();
    let setup = BenchSetup::from_result(&set.record, &set.controller, payload_range).unwrap();
    let t = std::time::Instant::now();
    let b = bench::run(&setup).unwrap();
    eprintln!("{name}: bench {:.1} s", t.elapsed().as_secs_f64());
    b
}

fn show(name: &str, b: &VibrationBenchmark) {
    eprintln!(
        "{name}: f_z,min {:.1} Hz window {:.3} s, klipper {:?}, limits {:?}",
        b.f_z_min_hz, b.window_s, b.klipper, b.limits_v_a_j
    );
    for c in &b.contestants {
        eprintln!(
            "  {:8} worst {:8.1} um median {:8.1} um settle {:?} ({} settled) T {:.3} s",
            c.name,
            c.worst_residual_um,
            c.median_residual_um,
            c.worst_settling_s,
            c.settled_moves,
            c.move_time_s
        );
        for m in &c.moves {
            eprintln!(
                "     end {:.3} p {:5.1} fz {:5.1} res {:8.1} settle {:?} {}",
                m.end_m, m.payload_kg, m.f_z_model_hz, m.residual_um, m.settling_s, m.shaper
            );
        }
    }
}

#[test]
fn egc70_benchmark() {
    let plant = builtin("egc70", None).unwrap();
    let b = commissioned("egc70", &plant, Some((0.0, 25.0)));
    show("egc70", &b);
}
