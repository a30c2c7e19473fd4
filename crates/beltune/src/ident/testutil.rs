//! Test helpers: a maximal-length PRBS (3.2)-(3.4) and an exact (zero-order
//! hold) discretization of the linear two-mass model, independent of the
//! frequency-domain code under test.

use crate::model::TwoMassParams;
use nalgebra::{SMatrix, SVector};

/// Maximal-length PRBS of `order` (taps of x^n + x^m + 1), each value held
/// `clock` samples, values `+-amplitude/2` (3.4), repeated `periods` times.
pub fn prbs(order: u32, clock: usize, amplitude: f64, periods: usize) -> Vec<f64> {
    let tap = match order {
        7 => 6,
        9 => 5,
        10 => 7,
        11 => 9,
        _ => panic!("test PRBS order {order} not tabulated"),
    };
    let m = (1usize << order) - 1;
    let mut reg: u32 = 1;
    let mut one = Vec::with_capacity(m * clock);
    for _ in 0..m {
        let bit = ((reg >> (order - 1)) ^ (reg >> (tap - 1))) & 1;
        reg = ((reg << 1) | bit) & ((1 << order) - 1);
        let v = if bit == 1 { 0.5 } else { -0.5 } * amplitude;
        one.extend(std::iter::repeat_n(v, clock));
    }
    let mut out = Vec::with_capacity(one.len() * periods);
    for _ in 0..periods {
        out.extend_from_slice(&one);
    }
    out
}

/// `y_k = a y_{k-1} + b u_{k-1}`, zero initial state.
pub fn simulate_discrete(u: &[f64], a: f64, b: f64) -> Vec<f64> {
    let mut y = Vec::with_capacity(u.len());
    let mut prev_y = 0.0;
    let mut prev_u = 0.0;
    for &uk in u {
        let yk = a * prev_y + b * prev_u;
        y.push(yk);
        prev_y = yk;
        prev_u = uk;
    }
    y
}

/// Exact ZOH discretization of the two-mass model (2.33) with belt damping `d`:
/// states `[phi, omega, xi, xi']`, torque input held over each sample.
pub struct ZohTwoMass {
    ad: SMatrix<f64, 4, 4>,
    bd: SVector<f64, 4>,
    x: SVector<f64, 4>,
}

impl ZohTwoMass {
    /// At rest at the origin.
    pub fn new(p: &TwoMassParams, ts: f64) -> Self {
        let it = p.i_t;
        let j = p.theta_e;
        let m = p.m_c;
        let mut a = SMatrix::<f64, 5, 5>::zeros();
        // phi' = omega
        a[(0, 1)] = 1.0;
        // Theta_e omega' = tau - it^2 dm omega - it c (it phi - xi) - it d (it omega - v)
        a[(1, 0)] = -it * it * p.c / j;
        a[(1, 1)] = -(it * it * p.d_m + it * it * p.d) / j;
        a[(1, 2)] = it * p.c / j;
        a[(1, 3)] = it * p.d / j;
        a[(1, 4)] = 1.0 / j;
        // xi' = v
        a[(2, 3)] = 1.0;
        // m v' = -dc v + c (it phi - xi) + d (it omega - v)
        a[(3, 0)] = p.c * it / m;
        a[(3, 1)] = p.d * it / m;
        a[(3, 2)] = -p.c / m;
        a[(3, 3)] = -(p.d_c + p.d) / m;
        let e = (a * ts).exp();
        ZohTwoMass {
            ad: e.fixed_view::<4, 4>(0, 0).into_owned(),
            bd: e.fixed_view::<4, 1>(0, 4).into_owned(),
            x: SVector::zeros(),
        }
    }

    /// Motor angle now (rad).
    pub fn phi(&self) -> f64 {
        self.x[0]
    }

    /// Cart position now (m).
    pub fn xi(&self) -> f64 {
        self.x[2]
    }

    /// The exact discrete FRF torque -> motor angle of this ZOH model,
    /// `G(z) = e_phi^T (z I - A_d)^-1 b_d` at `z = e^{j w T_s}` (the angle
    /// sampled before the step, as [`ZohTwoMass::phi`]), by a complex
    /// linear solve: independent of any ETFE.
    pub fn freq_response(&self, w_rad_s: f64, ts: f64) -> crate::lti::C64 {
        use crate::lti::C64;
        let z = C64::from_polar(1.0, w_rad_s * ts);
        let m = SMatrix::<C64, 4, 4>::from_fn(|r, c| {
            let id = if r == c { z } else { C64::new(0.0, 0.0) };
            id - C64::new(self.ad[(r, c)], 0.0)
        });
        let b = SVector::<C64, 4>::from_fn(|r, _| C64::new(self.bd[r], 0.0));
        let x = m
            .lu()
            .solve(&b)
            .expect("z is not an eigenvalue on the unit circle");
        x[0]
    }

    /// Hold `tau` for one sample.
    pub fn step(&mut self, tau: f64) {
        self.x = self.ad * self.x + self.bd * tau;
    }
}

/// Open-loop response: the motor angle sampled at the start of each sample
/// (the response to `torque[k]` appears at `k + 1`), then the cart position.
pub fn simulate_two_mass(p: &TwoMassParams, torque: &[f64], ts: f64) -> (Vec<f64>, Vec<f64>) {
    let mut sys = ZohTwoMass::new(p, ts);
    let mut phi = Vec::with_capacity(torque.len());
    let mut xi = Vec::with_capacity(torque.len());
    for &tau in torque {
        phi.push(sys.phi());
        xi.push(sys.xi());
        sys.step(tau);
    }
    (phi, xi)
}

/// Delay a sequence by `n` samples (zeros in front).
pub fn delay(x: &[f64], n: usize) -> Vec<f64> {
    let mut out = vec![0.0; n.min(x.len())];
    out.extend_from_slice(&x[..x.len() - n.min(x.len())]);
    out
}
