//! Design tests against the thesis conditions and independent evaluations.

use super::*;

/// Requested-vs-achieved tolerance of the issue: 0.01 deg / 0.01 dB.
const SPEC_TOL: f64 = 0.01;

#[test]
fn table_a4_designs_meet_the_conditions() {
    let input = DesignInput::new(TwoMassParams::thesis_table_a4(), 1e-3);
    for kind in [PrefilterKind::Butterworth, PrefilterKind::Notch] {
        let knobs = DesignKnobs {
            prefilter: kind,
            ..DesignKnobs::default()
        };
        let d = design(&input, &knobs).unwrap();
        assert!((d.velocity_margins.phase_margin_deg - 60.0).abs() < SPEC_TOL);
        assert!((d.gain_at_resonance_db + 10.0).abs() < SPEC_TOL);
        assert!((d.position_margins.phase_margin_deg - 80.0).abs() < SPEC_TOL);
        assert!(d.discrete_stability.velocity_max_pole_magnitude < 1.0);
        assert!(d.discrete_stability.position_max_pole_magnitude < 1.0);
    }
}
