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

/// The benchmark on egc70 (11.2 kg commissioned, payloads 5-20 kg): three
/// contestants of 21 moves each (7 ends x 3 payloads), all of the same
/// duration, the residual window 5 / f_z,min of the lowest model mode over
/// the moves (recomputed here from the identified model's formula
/// `sqrt(c / m_c) / 2 pi`), finite figures, and Klipper's choice reducing its
/// recorded spectra below its own 5 % goal. The targets (best
/// contestant at most half of `klipper`'s and a third of `fixed`'s worst
/// residual) are NOT met yet and not asserted: docs/vibration.md.
#[test]
fn egc70_benchmark_figures() {
    let plant = builtin("egc70", None).unwrap();
    let b = commissioned("egc70", &plant, Some((5.0, 20.0)));
    show("egc70", &b);
    assert_eq!(b.contestants.len(), 3);
    let t = b.contestants[0].move_time_s;
    for c in &b.contestants {
        assert_eq!(c.moves.len(), 21, "{}", c.name);
        assert!((c.move_time_s - t).abs() < 1e-12, "{}", c.name);
        assert!(c.worst_residual_um.is_finite() && c.median_residual_um <= c.worst_residual_um);
    }
    let f_min = b.contestants[0]
        .moves
        .iter()
        .map(|m| m.f_z_model_hz)
        .fold(f64::MAX, f64::min);
    assert!((b.f_z_min_hz - f_min).abs() < 1e-9);
    assert!((b.window_s - 5.0 / f_min).abs() < 1e-12);
    assert!(b.klipper.vibration < 0.05, "{:?}", b.klipper);
}
