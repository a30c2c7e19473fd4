//! The polynomial equations of the families against direct integration.
//! (The solver as a whole is tested against rsruckig and a discretized linear
//! program in `tests/`.)

use super::*;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Relative agreement of the polynomial and the direct position (rounding of
/// a degree-6 evaluation against seven integrated phases).
const POSITION_REL_TOL: f64 = 1e-9;

fn random_problem(rng: &mut Xoshiro256PlusPlus) -> Problem {
    let mut r = |lo: f64, hi: f64| rng.random_range(lo..hi);
    Problem {
        p0: r(-1.0, 1.0),
        v0: r(-0.5, 0.5),
        a0: r(-2.0, 2.0),
        pf: r(-3.0, 3.0),
        vf: r(-0.5, 0.5),
        af: r(-2.0, 2.0),
        v_max: r(0.6, 3.0),
        v_min: r(-3.0, -0.6),
        a_max: r(2.5, 10.0),
        a_min: r(-10.0, -2.5),
        j_max: r(5.0, 100.0),
        j_min: r(-100.0, -5.0),
        v_scale: 3.0,
    }
}

fn assert_close(poly: f64, direct: f64, what: &str) {
    let scale = 1.0 + poly.abs().max(direct.abs());
    assert!(
        (poly - direct).abs() <= POSITION_REL_TOL * scale,
        "{what}: polynomial {poly} vs integrated {direct}"
    );
}

#[test]
fn polynomial_end_positions_equal_the_integrated_phases() {
    // Truncation in `Poly` (capacity 7) or an algebra slip would show here:
    // the family's position polynomial, evaluated at x (and y = +-sqrt(q)),
    // must equal integrating the shape at that x phase by phase.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(31);
    for _ in 0..500 {
        let pb = random_problem(&mut rng);
        let x = rng.random_range(-5.0..5.0);

        let fam = neither_held(&pb);
        let p = fam.shape.end_position(&pb);
        let q = fam.shape.a_low.q.eval(x);
        if q >= 0.0 {
            for y in [q.sqrt(), -q.sqrt()] {
                let direct = fam.shape.at(x, y).end_position(&pb);
                assert_close(p.at(x, y), direct, "neither held");
            }
            // The eliminated polynomial vanishes exactly where one sign does.
            let f = p.eliminate_y().eval(x);
            let product = p.at(x, q.sqrt()) * p.at(x, -q.sqrt());
            assert_close(f, product, "a^2 - q b^2");
        }

        let t2 = rng.random_range(0.0..2.0);
        for (name, fam, x) in [
            ("a_max held", a_max_held(&pb), x),
            ("a_min held", a_min_held(&pb), x),
            ("both held", both_held(&pb), t2),
        ] {
            let poly = fam.shape.end_position(&pb);
            assert_close(poly.eval(x), fam.shape.at(x, 0.0).end_position(&pb), name);
        }
    }
}

#[test]
fn velocity_condition_holds_on_every_family() {
    // The holds and `y` come from the summed velocity condition; a shape at
    // any x must end at the target velocity and acceleration.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(32);
    for _ in 0..500 {
        let pb = random_problem(&mut rng);
        let x = rng.random_range(-5.0..5.0);
        let end_velocity = |s: &Shape<f64>| {
            let (mut v, mut a) = (pb.v0, pb.a0);
            for (t, j) in s.durations(&pb).into_iter().zip(up_jerks(&pb)) {
                v += t * (a + t * j / 2.0);
                a += t * j;
            }
            (v, a)
        };
        let q = neither_held(&pb).shape.a_low.q.eval(x);
        let mut shapes = [
            a_max_held(&pb).shape.at(x, 0.0),
            a_min_held(&pb).shape.at(x, 0.0),
            both_held(&pb).shape.at(x.abs(), 0.0),
            neither_held(&pb).shape.at(x, q.abs().sqrt()),
        ];
        if q < 0.0 {
            shapes[3] = shapes[0];
        }
        for s in shapes {
            let (v, a) = end_velocity(&s);
            assert!((v - pb.vf).abs() < 1e-9 * (1.0 + v.abs()), "{s:?}: v {v}");
            assert!((a - pb.af).abs() < 1e-12 * (1.0 + a.abs()), "{s:?}: a {a}");
        }
    }
}
