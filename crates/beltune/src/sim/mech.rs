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
    /// Segment geometry vectors `g_k` (fixed after [`Self::prepared`]).
    pub g: [[f64; N]; S],
    /// `g_k[i] g_k[j]`, computed once from `g` by [`Self::prepared`].
    pub gg: [[[f64; N]; N]; S],
    /// Segment stiffness `c_k` (N/m), updated with the cart position.
    pub c: [f64; S],
    /// Segment damping `d_k` (N s/m).
    pub d: [f64; S],
    /// Slack spans ([`Slack`]), `None`: every segment is a linear spring.
    pub slack: Option<Slack<S>>,
}

/// Spans that cannot push ([`crate::model::wear`]): segment `k` carries the
/// tension `T_k = P + sign_k (c_k g_k.q + d_k g_k.q')` (`sign_k g_k.q` its
/// elongation, the pretension `P` cancelling around the closed belt); where
/// `T_k` would fall below zero the span is slack and carries nothing, which
/// adds `sign_k g_k min(T_k, 0)` to the generalized force of the linear
/// springs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slack<const S: usize> {
    /// The pretension `P`, N.
    pub pretension_n: f64,
    /// `sign_k`: +1 where `g_k.q` is the elongation of segment `k`, -1 where
    /// it is the shortening.
    pub sign: [f64; S],
}

/// The velocity-level (Moreau) Coulomb step of one body (module docs):
/// from `(q0, v0)` at the start of a step of `h` s, the smooth step's end
/// `(q, v_f)` and the largest velocity change friction can make in it,
/// `dv_max = h F_c / m`, the position and velocity after friction. Sticks
/// (`v = 0`, position on the trapezoid of the velocity: exactly `q0` when it
/// was at rest) when `|v_f| <= dv_max`, else slides with `v_f - sign(v_f)
/// dv_max`; `dv_max <= 0` (no friction) leaves the smooth step as it is.
/// Shared by the simulator and the friction-aware fit's cart observer.
#[inline]
pub(crate) fn coulomb_step(q0: f64, v0: f64, q: f64, v_f: f64, dv_max: f64, h: f64) -> (f64, f64) {
    if dv_max <= 0.0 {
        (q, v_f)
    } else if v_f.abs() <= dv_max {
        (q0 + 0.5 * h * v0, 0.0)
    } else {
        let vn = v_f - dv_max.copysign(v_f);
        (q + 0.5 * h * (vn - v_f), vn)
    }
}

/// `a . b`, summed in index order from the first product (`N >= 1`). Equal
/// (`==`) to [`dot_reference`], which adds the products to 0: `0 + x` is
/// `x` but for the sign of a zero `x`, and a zero's sign never changes a
/// sum with a nonzero term, a comparison, `abs` or `floor` (the simulator
/// uses nothing else of it); one dependent addition less per dot product.
#[inline(always)]
fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut s = a[0] * b[0];
    for i in 1..N {
        s += a[i] * b[i];
    }
    s
}

/// [`dot`] as it was written before: the products added to 0.
#[inline(always)]
fn dot_reference<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut s = 0.0;
    for i in 0..N {
        s += a[i] * b[i];
    }
    s
}

impl<const N: usize, const S: usize> Mech<N, S> {
    /// The system with the products `g_k[i] g_k[j]` of its geometry
    /// computed ([`Self::gg`]); call once after setting `g`.
    pub fn prepared(mut self) -> Self {
        for s in 0..S {
            for i in 0..N {
                for j in 0..N {
                    self.gg[s][i][j] = self.g[s][i] * self.g[s][j];
                }
            }
        }
        self
    }

    /// Smooth accelerations (everything but Coulomb friction), from the
    /// segment springs directly (reference form; the integrator uses the
    /// assembled matrices of [`Self::assemble`], which are equal).
    #[cfg(test)]
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

    /// `M^-1 K`, `M^-1 (D + V)` and `M^-1 (B u + f_const)` for the current
    /// segment coefficients: the accelerations become two small mat-vecs.
    ///
    /// `K_ij = sum_k c_k g_k[i] g_k[j]` (and `D` alike) is summed over the
    /// segments in order, as [`Self::assemble_reference`] does, but from the
    /// products `gg` computed once, for `j >= i` only (`K` is symmetric: the
    /// same products in the same order) and without the terms whose product
    /// is zero (a zero `c_k 0` added to the sum leaves it unchanged, bit for
    /// bit, for finite `c_k`): the three-mass belt has 10 such terms of 27
    /// per entry set. The result is bit-identical to the reference form
    /// (test `assembled_equals_reference_bit_for_bit`).
    #[inline(always)]
    fn assemble(&self, u: f64) -> Assembled<N> {
        let mut kq = [[0.0; N]; N];
        let mut kv = [[0.0; N]; N];
        for i in 0..N {
            for j in i..N {
                let mut k = 0.0;
                let mut d = 0.0;
                for s in 0..S {
                    let gg = self.gg[s][i][j];
                    if gg != 0.0 {
                        k += self.c[s] * gg;
                        d += self.d[s] * gg;
                    }
                }
                kq[i][j] = k * self.inv_mass[i];
                kv[i][j] = d * self.inv_mass[i];
                kq[j][i] = k * self.inv_mass[j];
                kv[j][i] = d * self.inv_mass[j];
            }
            kv[i][i] += self.viscous[i] * self.inv_mass[i];
        }
        let mut f = [0.0; N];
        for i in 0..N {
            f[i] = (self.input[i] * u + self.constant[i]) * self.inv_mass[i];
        }
        Assembled { kq, kv, f }
    }

    /// [`Self::assemble`] as it was written before it was made faster: every
    /// entry and every segment, the products `g_k[i] g_k[j]` formed each time.
    #[cfg_attr(not(test), allow(dead_code))]
    #[inline(always)]
    fn assemble_reference(&self, u: f64) -> Assembled<N> {
        let mut kq = [[0.0; N]; N];
        let mut kv = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                let mut k = 0.0;
                let mut d = 0.0;
                for s in 0..S {
                    let gg = self.g[s][i] * self.g[s][j];
                    k += self.c[s] * gg;
                    d += self.d[s] * gg;
                }
                kq[i][j] = k * self.inv_mass[i];
                kv[i][j] = d * self.inv_mass[i];
            }
            kv[i][i] += self.viscous[i] * self.inv_mass[i];
        }
        let mut f = [0.0; N];
        for i in 0..N {
            f[i] = (self.input[i] * u + self.constant[i]) * self.inv_mass[i];
        }
        Assembled { kq, kv, f }
    }

    /// The accelerations of the assembled linear part, with the slack spans'
    /// correction where there are any ([`Slack`]).
    #[inline(always)]
    fn accel_of<const REFERENCE: bool>(
        &self,
        asm: &Assembled<N>,
        q: &[f64; N],
        v: &[f64; N],
    ) -> [f64; N] {
        let mut a = if REFERENCE {
            asm.accel_reference(q, v)
        } else {
            asm.accel(q, v)
        };
        if let Some(slack) = &self.slack {
            for k in 0..S {
                let sign = slack.sign[k];
                let t = slack.pretension_n
                    + sign * (self.c[k] * dot(&self.g[k], q) + self.d[k] * dot(&self.g[k], v));
                if t < 0.0 {
                    for i in 0..N {
                        a[i] += self.inv_mass[i] * sign * self.g[k][i] * t;
                    }
                }
            }
        }
        a
    }

    /// One step of length `h` with constant input `u`.
    #[inline]
    pub fn step(&mut self, u: f64, h: f64) {
        self.step_as::<false>(u, h);
    }

    /// [`Self::step`] as it was written before it was made faster
    /// ([`Self::assemble_reference`], [`dot_reference`]), for the test that
    /// both give the same states.
    #[cfg(test)]
    pub fn step_reference(&mut self, u: f64, h: f64) {
        self.step_as::<true>(u, h);
    }

    #[inline(always)]
    fn step_as<const REFERENCE: bool>(&mut self, u: f64, h: f64) {
        let asm = if REFERENCE {
            self.assemble_reference(u)
        } else {
            self.assemble(u)
        };
        let (q0, v0) = (self.q, self.v);
        let a1 = self.accel_of::<REFERENCE>(&asm, &q0, &v0);
        let mut q = [0.0; N];
        let mut v = [0.0; N];
        for i in 0..N {
            q[i] = q0[i] + 0.5 * h * v0[i];
            v[i] = v0[i] + 0.5 * h * a1[i];
        }
        let v2 = v;
        let a2 = self.accel_of::<REFERENCE>(&asm, &q, &v2);
        for i in 0..N {
            q[i] = q0[i] + 0.5 * h * v2[i];
            v[i] = v0[i] + 0.5 * h * a2[i];
        }
        let v3 = v;
        let a3 = self.accel_of::<REFERENCE>(&asm, &q, &v3);
        for i in 0..N {
            q[i] = q0[i] + h * v3[i];
            v[i] = v0[i] + h * a3[i];
        }
        let v4 = v;
        let a4 = self.accel_of::<REFERENCE>(&asm, &q, &v4);
        for i in 0..N {
            self.q[i] = q0[i] + h / 6.0 * (v0[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            self.v[i] = v0[i] + h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i]);
        }
        // Coulomb friction: velocity-level stick-slip (module docs).
        for i in 0..N {
            let dv_max = h * self.coulomb[i] * self.inv_mass[i];
            (self.q[i], self.v[i]) = coulomb_step(q0[i], v0[i], self.q[i], self.v[i], dv_max, h);
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

/// The assembled linear part of one step.
struct Assembled<const N: usize> {
    kq: [[f64; N]; N],
    kv: [[f64; N]; N],
    f: [f64; N],
}

impl<const N: usize> Assembled<N> {
    #[inline(always)]
    fn accel(&self, q: &[f64; N], v: &[f64; N]) -> [f64; N] {
        let mut a = self.f;
        for i in 0..N {
            a[i] -= dot(&self.kq[i], q) + dot(&self.kv[i], v);
        }
        a
    }

    /// [`Self::accel`] with [`dot_reference`].
    #[cfg_attr(not(test), allow(dead_code))]
    #[inline(always)]
    fn accel_reference(&self, q: &[f64; N], v: &[f64; N]) -> [f64; N] {
        let mut a = self.f;
        for i in 0..N {
            a[i] -= dot_reference(&self.kq[i], q) + dot_reference(&self.kv[i], v);
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The assembled matrices give the accelerations of the spring form.
    #[test]
    fn assembled_equals_spring_form() {
        let m = Mech::<3, 3> {
            q: [0.0; 3],
            v: [0.0; 3],
            inv_mass: [1.0 / 7e-5, 1.0 / 2e-5, 1.0 / 12.0],
            viscous: [1e-3, 2e-4, 20.0],
            coulomb: [0.0; 3],
            input: [1.0, 0.0, 0.0],
            constant: [0.0, 0.0, -3.0],
            g: [
                [0.0124, 0.0, -1.0],
                [0.0, 0.0124, -1.0],
                [0.0124, -0.0124, 0.0],
            ],
            gg: [[[0.0; 3]; 3]; 3],
            c: [3e5, 4e5, 1e5],
            d: [30.0, 40.0, 10.0],
            slack: None,
        }
        .prepared();
        let (q, v, u) = ([40.0, 41.0, 0.5], [3.0, -2.0, 0.04], 0.7);
        let a = m.accel(&q, &v, u);
        let b = m.assemble(u).accel(&q, &v);
        for i in 0..3 {
            assert!(
                (a[i] - b[i]).abs() <= 1e-9 * a[i].abs().max(1.0),
                "{a:?} {b:?}"
            );
        }
    }

    /// The fast assembly (products once, symmetric half, zero products
    /// skipped) gives the reference assembly's matrices bit for bit, on the
    /// three-mass geometry (with zeros of both signs among the products) and
    /// on a dense random one, with zero damping on a segment.
    #[test]
    fn assembled_equals_reference_bit_for_bit() {
        let mut m = Mech::<3, 3> {
            q: [0.0; 3],
            v: [0.0; 3],
            inv_mass: [1.0 / 7e-5, 1.0 / 2e-5, 1.0 / 12.0],
            viscous: [1e-3, 2e-4, 20.0],
            coulomb: [0.0; 3],
            input: [1.0, 0.0, 0.0],
            constant: [0.0, 0.0, -3.0],
            g: [
                [0.0124, 0.0, -1.0],
                [0.0, 0.0124, -1.0],
                [0.0124, -0.0124, 0.0],
            ],
            gg: [[[0.0; 3]; 3]; 3],
            c: [3e5, 4e5, 1e5],
            d: [30.0, 0.0, 10.0],
            slack: None,
        }
        .prepared();
        let mut state = 0x5EED_u64;
        let mut draw = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let same = |a: &Assembled<3>, b: &Assembled<3>| {
            let bits = |x: &Assembled<3>| {
                let mut v: Vec<u64> = x.kq.iter().flatten().map(|y| y.to_bits()).collect();
                v.extend(x.kv.iter().flatten().map(|y| y.to_bits()));
                v.extend(x.f.iter().map(|y| y.to_bits()));
                v
            };
            assert_eq!(bits(a), bits(b));
        };
        for round in 0..200 {
            m.c = [draw() * 1e6, draw() * 1e6, draw() * 1e6];
            m.d = [draw() * 50.0, 0.0, draw() * 50.0];
            if round >= 100 {
                for s in 0..3 {
                    for i in 0..3 {
                        m.g[s][i] = draw() - 0.5;
                    }
                }
                m = m.prepared();
            }
            let u = draw() - 0.5;
            same(&m.assemble(u), &m.assemble_reference(u));
        }
    }
}
