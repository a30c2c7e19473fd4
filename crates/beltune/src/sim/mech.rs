//! A lumped mechanical system with `N` generalized coordinates and `S` belt
//! segments, `M q'' = B u + f_g - V q' - sum_k g_k (c_k g_k.q + d_k g_k.q') - coulomb`,
//! integrated with RK4 for the smooth part and a velocity-level (Moreau)
//! stick-slip step for Coulomb friction.
//!
//! Each belt segment `k` stretches by `g_k . q` (e.g. `i_t phi_m - xi` for `l_1`),
//! its potential `c_k (g_k.q)^2 / 2` gives the forces of (2.20)/(2.30).
//!
//! Stick-slip: after the smooth RK4 step gives the "free" velocity `v_f` of a
//! body with Coulomb force `F_c` and mass `m`, the friction impulse over the
//! step `h` is at most `h F_c`. If `|v_f| <= h F_c / m` the friction can stop the
//! body within the step and it sticks (`v = 0`); else it slides with
//! `v = v_f - sign(v_f) h F_c / m`, and the position is corrected by the
//! trapezoidal integral of the velocity change, `h (v - v_f) / 2`. A sticking
//! body's position is `q_0 + h v_0 / 2` (exactly `q_0` when it was at rest). A body held
//! by a net force below its breakaway force stays exactly at rest (no
//! chattering, no creep), and a sliding body decelerates by exactly `F_c / m`.

// Index loops over several equally sized fixed arrays read like the equations
// and compile to straight-line code for N <= 3.
#![allow(clippy::needless_range_loop)]

/// The system; `q` and `v` are the generalized positions and velocities.
#[derive(Clone, Debug)]
pub(crate) struct Mech<const N: usize, const S: usize> {
    pub q: [f64; N],
    pub v: [f64; N],
    pub inv_mass: [f64; N],
    /// Diagonal viscous friction (generalized), e.g. `i_t^2 d_m` for the motor.
    pub viscous: [f64; N],
    /// Coulomb friction magnitude (generalized force/torque) per coordinate.
    pub coulomb: [f64; N],
    /// Input distribution `B` (torque on the motor coordinate).
    pub input: [f64; N],
    /// Constant generalized forces (gravity).
    pub constant: [f64; N],
    /// Segment geometry vectors `g_k`.
    pub g: [[f64; N]; S],
    /// Segment stiffness `c_k` (N/m), updated with the cart position.
    pub c: [f64; S],
    /// Segment damping `d_k` (N s/m).
    pub d: [f64; S],
}

#[inline(always)]
fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut s = 0.0;
    for i in 0..N {
        s += a[i] * b[i];
    }
    s
}

impl<const N: usize, const S: usize> Mech<N, S> {
    /// Smooth accelerations (everything but Coulomb friction).
    #[inline(always)]
    pub fn accel(&self, q: &[f64; N], v: &[f64; N], u: f64) -> [f64; N] {
        let mut f = [0.0; N];
        for i in 0..N {
            f[i] = self.input[i] * u + self.constant[i] - self.viscous[i] * v[i];
        }
        for k in 0..S {
            let t = self.c[k] * dot(&self.g[k], q) + self.d[k] * dot(&self.g[k], v);
            for i in 0..N {
                f[i] -= self.g[k][i] * t;
            }
        }
        for i in 0..N {
            f[i] *= self.inv_mass[i];
        }
        f
    }

    /// One step of length `h` with constant input `u`.
    #[inline]
    pub fn step(&mut self, u: f64, h: f64) {
        let (q0, v0) = (self.q, self.v);
        let a1 = self.accel(&q0, &v0, u);
        let mut q = [0.0; N];
        let mut v = [0.0; N];
        for i in 0..N {
            q[i] = q0[i] + 0.5 * h * v0[i];
            v[i] = v0[i] + 0.5 * h * a1[i];
        }
        let v2 = v;
        let a2 = self.accel(&q, &v2, u);
        for i in 0..N {
            q[i] = q0[i] + 0.5 * h * v2[i];
            v[i] = v0[i] + 0.5 * h * a2[i];
        }
        let v3 = v;
        let a3 = self.accel(&q, &v3, u);
        for i in 0..N {
            q[i] = q0[i] + h * v3[i];
            v[i] = v0[i] + h * a3[i];
        }
        let v4 = v;
        let a4 = self.accel(&q, &v4, u);
        for i in 0..N {
            self.q[i] = q0[i] + h / 6.0 * (v0[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            self.v[i] = v0[i] + h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i]);
        }
        // Coulomb friction: velocity-level stick-slip (module docs).
        for i in 0..N {
            let dv_max = h * self.coulomb[i] * self.inv_mass[i];
            if dv_max <= 0.0 {
                continue;
            }
            let vf = self.v[i];
            if vf.abs() <= dv_max {
                // stick: the body stops within the step; its position follows
                // the trapezoid of its velocity (exactly unchanged when it was at rest)
                self.q[i] = q0[i] + 0.5 * h * v0[i];
                self.v[i] = 0.0;
            } else {
                let vn = vf - dv_max.copysign(vf);
                self.q[i] += 0.5 * h * (vn - vf);
                self.v[i] = vn;
            }
        }
    }

    /// Upper bound of the undamped natural frequencies, rad/s (Gershgorin on
    /// `M^-1/2 K M^-1/2`), and of the damping rates, 1/s (same on `D`).
    pub fn rate_bounds(&self) -> (f64, f64) {
        let mut kmax: f64 = 0.0;
        let mut dmax: f64 = 0.0;
        for i in 0..N {
            let mut ks = 0.0;
            let mut ds = self.viscous[i] * self.inv_mass[i];
            for j in 0..N {
                let scale = (self.inv_mass[i] * self.inv_mass[j]).sqrt();
                let mut kij = 0.0;
                let mut dij = 0.0;
                for k in 0..S {
                    kij += self.c[k] * self.g[k][i] * self.g[k][j];
                    dij += self.d[k] * self.g[k][i] * self.g[k][j];
                }
                ks += kij.abs() * scale;
                ds += dij.abs() * scale;
            }
            kmax = kmax.max(ks);
            dmax = dmax.max(ds);
        }
        (kmax.sqrt(), dmax)
    }
}
