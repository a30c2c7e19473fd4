//! Identification of the nonlinear two-mass model (2.30) from the open-loop
//! excitation: the Coulomb friction the excitation meets,
//! separated from the damping, and the cart's mass and the belt's
//! stiffness as the sliding cart has them.
//!
//! **Why.** The thesis fits the linear model (2.42) to the FRF of a small
//! open-loop PRBS at rest (3.5). Where the cart's Coulomb friction is not
//! small against the belt force the excitation produces, the cart sticks at
//! every reversal, and the FRF mixes a free cart (antiresonance at `w_z`)
//! with a clamped one (a spring to ground): the fitted antiresonance moves
//! down and the apparent mass up (issue 12's study: `f_z` up to 9 % low,
//! `m_c` up to 20 % heavy on heavy carts with high friction), and the
//! fitted `d_m`, `d_c` lump the friction into viscous damping, which the
//! design then relies on. The distortion repeats every period, so the
//! coherence does not show it.
//!
//! **Method: equation error with a cart observer** ([`observer`]). The
//! cart's equation (2.25b) with Coulomb friction (2.23) is simulated,
//! driven by the *measured* motor angle through the belt; the belt torque it
//! gives and the motor's equation (2.25a) leave the residual
//!
//! ```text
//! r(t) = tau(t - T_t) - Theta_e phi'' - i_t^2 d_m phi' - tau_c sign(phi') - tau_b(t; m_c, c, d, d_c, F_c)
//! ```
//!
//! compared per excited line `l` of the analysed periods as
//! `e_l = R(w_l) / |T(w_l)|` (relative to the command's spectrum). The cart
//! parameters `m_c, c, d, d_c, F_c` are found by Levenberg-Marquardt in
//! logarithmic coordinates (started from the linear fit and three shares of
//! the Coulomb friction measured beforehand); `d_m` and `tau_c` (and
//! `Theta_e` where the data sheet does not give it) enter linearly and are
//! solved, non-negative, for every cart (variable projection).
//!
//! Measured on the study's plants (`examples`-free: `beltune montecarlo`):
//! `f_z` within 2 % on 99 % of the plants (the linear fit: 78 %).

pub mod observer;

use super::fit::{ParamUncertainty, DAMPING_RANGE, MASS_STIFFNESS_RANGE};
use crate::error::{require_all_finite, require_finite, require_positive};
use crate::lti::C64;
use crate::model::TwoMassParams;
use crate::{Error, Result};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use observer::{belt_torque, motor_signals, CartParams};
use realfft::RealFftPlanner;
use std::sync::Arc;

/// Settings of [`fit_nonlinear`] (SI units; torque may read current, then
/// every N m reads A).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonlinearConfig {
    /// Motor-side inertia `Theta_e` from the data sheet, kg m^2; `None`:
    /// solved with the motor's friction.
    pub theta_e: Option<f64>,
    /// Transmission `i_t`, m/rad.
    pub i_t: f64,
    /// Sample time, s.
    pub ts_s: f64,
    /// Samples per excitation period.
    pub period_samples: usize,
    /// Leading periods not compared (the cart observer's start-up too).
    pub skip_periods: usize,
    /// Current-loop dead time `T_t`, s (rounded to samples).
    pub dead_time_s: f64,
    /// Band of the compared lines, Hz.
    pub band_hz: (f64, f64),
    /// Constant force on the cart along the axis (gravity), N: minus the
    /// holding torque over `i_t`.
    pub cart_force_n: f64,
    /// Coulomb friction measured before (motor side, all bodies), N m: the
    /// start values of the cart's share. 0 if unknown.
    pub coulomb_hint_nm: f64,
    /// Hold the start's `m_c` instead of fitting it: the belt stiffness at
    /// another cart position, where the mass is the one identified already.
    pub fixed_mass: bool,
}

/// The identified nonlinear two-mass model (2.30).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NonlinearFit {
    /// The linear part: `Theta_e`, `m_c`, `c`, belt damping `d`, viscous
    /// `d_m` (translational equivalent), `d_c`, `i_t` (SI).
    pub params: TwoMassParams,
    /// Coulomb friction on the motor side (motor and everything turning
    /// with it), N m.
    pub tau_c_motor_nm: f64,
    /// Coulomb friction of the cart, N.
    pub f_c_cart_n: f64,
    /// One-sigma uncertainties of `m_c`, `c`, `d`, `d_c` (0 for the
    /// linearly solved `d_m`, `Theta_e`).
    pub uncertainty: Option<ParamUncertainty>,
    /// RMS over the compared lines of the motor equation's error relative
    /// to the command, `sqrt(mean |e_l|^2)`.
    pub residual: f64,
    /// The same for the start model (the linear fit, no friction).
    pub linear_residual: f64,
    /// Resonance (2.44) of the linear part, Hz.
    pub f_r_hz: f64,
    /// Antiresonance (2.45), Hz.
    pub f_z_hz: f64,
    /// Number of lines compared.
    pub n_lines: usize,
    /// Cart simulations run.
    pub evaluations: usize,
}

impl NonlinearFit {
    /// Whether the nonlinear model explains the record better than the
    /// linear fit it started from.
    pub fn improves_on_linear(&self) -> bool {
        self.residual < self.linear_residual
    }

    /// The cart's Coulomb friction at the motor, `i_t F_c`, N m.
    pub fn cart_coulomb_nm(&self) -> f64 {
        self.params.i_t * self.f_c_cart_n
    }
}

/// Lines whose command amplitude is below this fraction of the strongest
/// line's are not compared (-40 dB, the ETFE's excitation floor).
const EXCITATION_FLOOR: f64 = 0.01;
/// Shares of the Coulomb hint started at the cart.
const START_SHARES: [f64; 3] = [0.2, 0.5, 0.8];
/// Forward-difference step of the Jacobian in the logarithmic coordinates:
/// 0.1 % of each parameter. Smaller steps resolve single stick events of
/// the observer (a non-smooth residual); larger ones the curvature.
const JACOBIAN_STEP: f64 = 1e-3;

/// Fit the nonlinear two-mass model to a periodic open-loop excitation:
/// `torque` the command (N m), `angle_rad` the motor angle, sample by
/// sample; `start` the linear fit (its `m_c`, `c` start the search, its
/// damping is the model the result is compared with).
///
/// Errors: mismatched or non-finite records, too few periods or lines,
/// invalid settings, a search that fails everywhere ([`Error::FitFailed`]).
pub fn fit_nonlinear(
    torque: &[f64],
    angle_rad: &[f64],
    start: &TwoMassParams,
    cfg: &NonlinearConfig,
) -> Result<NonlinearFit> {
    let problem = Problem::new(torque, angle_rad, start, cfg)?;
    let linear_residual = problem.linear_residual(start);
    let mut best: Option<(Problem, f64)> = None;
    let mut evaluations = 0;
    for share in START_SHARES {
        let mut p = problem.clone();
        p.restart(start, share * cfg.coulomb_hint_nm.max(0.0));
        let (solved, report) = LevenbergMarquardt::new().with_patience(20).minimize(p);
        evaluations += solved.evaluations.get();
        if !report.termination.was_successful() || !report.objective_function.is_finite() {
            continue;
        }
        if best
            .as_ref()
            .is_none_or(|(_, cost)| report.objective_function < *cost)
        {
            best = Some((solved, report.objective_function));
        }
    }
    let (solved, _) = best.ok_or_else(|| Error::FitFailed {
        reason: "the friction-aware fit did not converge from any start".into(),
    })?;
    if let Some(k) = solved.at_bound() {
        return Err(Error::FitFailed {
            reason: format!(
                "the friction-aware fit ran to the edge of its range in `{}`",
                ["m_c", "c", "d", "d_c", "F_c"][k]
            ),
        });
    }
    let eval = solved.evaluate(&solved.q).ok_or_else(|| Error::FitFailed {
        reason: "the friction-aware fit is not finite at its optimum".into(),
    })?;
    let cart = solved.cart(&solved.q);
    let params = TwoMassParams {
        theta_e: eval.theta_e,
        m_c: cart.m_c,
        c: cart.c,
        d: cart.d,
        d_m: eval.d_m,
        d_c: cart.d_c,
        i_t: cfg.i_t,
    };
    params.validate().map_err(|e| Error::FitFailed {
        reason: format!("the friction-aware fit is not physical ({e})"),
    })?;
    let n = eval.residual.len();
    let uncertainty = solved.jacobian_mat().and_then(|j| {
        let n_free = solved.n_free();
        let s2 = eval.residual.norm_squared() / (n.saturating_sub(n_free)).max(1) as f64;
        let jtj = j.transpose() * &j;
        let scale = jtj.diagonal().max();
        let cov = jtj.pseudo_inverse(1e-12 * scale).ok()? * s2;
        let sig = |k: usize| match solved.q_index(k) {
            Some(i) => cov[(i, i)].max(0.0).sqrt() * solved.dlnp_dq(k),
            None => 0.0,
        };
        Some(ParamUncertainty {
            theta_e: 0.0,
            m_c: cart.m_c * sig(0),
            c: cart.c * sig(1),
            d: cart.d * sig(2),
            d_c: cart.d_c * sig(3),
            d_m: 0.0,
        })
    });
    Ok(NonlinearFit {
        f_r_hz: params.f_r_hz(),
        f_z_hz: params.f_z_hz(),
        params,
        tau_c_motor_nm: eval.tau_c,
        f_c_cart_n: cart.f_c,
        uncertainty,
        residual: (eval.residual.norm_squared() / (n / 2).max(1) as f64).sqrt(),
        linear_residual,
        n_lines: solved.spectra.lines.len(),
        evaluations,
    })
}

/// The per-line mean spectrum over the analysed periods.
#[derive(Clone)]
struct Spectra {
    fft: Arc<dyn realfft::RealToComplex<f64>>,
    period: usize,
    skip: usize,
    n_periods: usize,
    lines: Vec<usize>,
}

impl Spectra {
    fn of(&self, x: &[f64]) -> Vec<C64> {
        let mut buf = self.fft.make_input_vec();
        let mut spec = self.fft.make_output_vec();
        let mut acc = vec![C64::new(0.0, 0.0); self.lines.len()];
        let scale = 1.0 / self.n_periods as f64;
        for p in 0..self.n_periods {
            let start = (self.skip + p) * self.period;
            buf.copy_from_slice(&x[start..start + self.period]);
            // the lengths match by construction: the FFT cannot fail
            if self.fft.process(&mut buf, &mut spec).is_err() {
                return vec![C64::new(f64::NAN, 0.0); self.lines.len()];
            }
            for (a, &k) in acc.iter_mut().zip(&self.lines) {
                *a += spec[k] * scale;
            }
        }
        acc
    }
}

/// The result of one evaluation: the residual vector and the linearly
/// solved parameters.
struct Evaluation {
    residual: DVector<f64>,
    theta_e: f64,
    d_m: f64,
    tau_c: f64,
}

/// Number of nonlinear parameters: `m_c, c, d, d_c, F_c`.
const N_Q: usize = 5;

#[derive(Clone)]
struct Problem {
    angle: Arc<Vec<f64>>,
    ts: f64,
    i_t: f64,
    cart_force: f64,
    spectra: Spectra,
    /// `1 / |T_l|` of the command per line.
    inv_command: Vec<f64>,
    /// Spectrum of `tau(t - T_t) - Theta_e phi''` (data-sheet `Theta_e`).
    known: Vec<C64>,
    /// Regressors solved linearly: `d_m`, `tau_c`, and `Theta_e` if free.
    regressors: Vec<Vec<C64>>,
    theta_e: Option<f64>,
    /// Start values and log half-widths of `m_c, c, d, d_c, F_c`.
    p0: [f64; N_Q],
    half_width: [f64; N_Q],
    /// The first of `m_c, c, d, d_c, F_c` that is fitted (1: `m_c` held at
    /// its start value); `q` holds it and the ones after it, in order.
    first_free: usize,
    q: DVector<f64>,
    residual: Option<DVector<f64>>,
    evaluations: std::cell::Cell<usize>,
}

impl Problem {
    fn new(
        torque: &[f64],
        angle_rad: &[f64],
        start: &TwoMassParams,
        cfg: &NonlinearConfig,
    ) -> Result<Problem> {
        require_positive("i_t [m/rad]", cfg.i_t)?;
        require_positive("sample time [s]", cfg.ts_s)?;
        require_finite("cart force [N]", cfg.cart_force_n)?;
        require_finite("Coulomb friction hint [N m]", cfg.coulomb_hint_nm)?;
        if let Some(t) = cfg.theta_e {
            require_positive("theta_e [kg m^2]", t)?;
        }
        if !(cfg.dead_time_s.is_finite() && cfg.dead_time_s >= 0.0) {
            return Err(Error::invalid(
                "dead time [s]",
                cfg.dead_time_s,
                "must be finite and not negative",
            ));
        }
        start.validate()?;
        if torque.len() != angle_rad.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "torque has {} samples, angle has {}",
                    torque.len(),
                    angle_rad.len()
                ),
            });
        }
        require_all_finite("torque", torque)?;
        require_all_finite("angle", angle_rad)?;
        let period = cfg.period_samples;
        if period < 4 {
            return Err(Error::invalid(
                "period_samples",
                period as f64,
                "a period needs at least 4 samples",
            ));
        }
        let needed = cfg
            .skip_periods
            .checked_add(1)
            .and_then(|p| p.checked_mul(period))
            .unwrap_or(usize::MAX);
        if torque.len() < needed {
            return Err(Error::TooShort {
                what: format!(
                    "{} skipped + 1 compared period of {period} samples",
                    cfg.skip_periods
                ),
                needed,
                got: torque.len(),
            });
        }
        let n_periods = torque.len() / period - cfg.skip_periods;
        let df = 1.0 / (period as f64 * cfg.ts_s);
        let (lo, hi) = cfg.band_hz;
        let mut planner = RealFftPlanner::<f64>::new();
        let mut spectra = Spectra {
            fft: planner.plan_fft_forward(period),
            period,
            skip: cfg.skip_periods,
            n_periods,
            lines: (1..period / 2)
                .filter(|&k| {
                    let f = k as f64 * df;
                    f >= lo && f <= hi
                })
                .collect(),
        };
        // Lines the command does not excite (a PRBS has zeros at multiples
        // of its clock frequency) are not compared: relative to the command
        // their error is noise over nothing.
        let command = spectra.of(torque);
        let peak = command.iter().map(|t| t.norm()).fold(0.0, f64::max);
        // a line of a constant command holds only the FFT's rounding,
        // about 1e-16 of the samples' sum
        let scale: f64 = torque.iter().map(|t| t.abs()).sum::<f64>() / n_periods.max(1) as f64;
        if peak.is_nan() || peak <= 1e-12 * scale {
            return Err(Error::NoExcitation {
                what: "the torque command has no power in the compared band".into(),
            });
        }
        let floor = peak * EXCITATION_FLOOR;
        let (lines, command): (Vec<usize>, Vec<C64>) = spectra
            .lines
            .iter()
            .zip(&command)
            .filter(|(_, t)| t.norm() >= floor)
            .map(|(&k, &t)| (k, t))
            .unzip();
        spectra.lines = lines;
        if spectra.lines.len() < 2 * N_Q {
            return Err(Error::FitFailed {
                reason: format!(
                    "{} excited lines in the band {lo:.1}-{hi:.1} Hz for {N_Q} parameters",
                    spectra.lines.len()
                ),
            });
        }
        let dead = (cfg.dead_time_s / cfg.ts_s).round().min(u32::MAX as f64) as usize;
        let motor = motor_signals(torque, angle_rad, cfg.ts_s, cfg.i_t, dead, cfg.theta_e);
        let inv_command = command.iter().map(|t| 1.0 / t.norm()).collect();
        let mut regressors = vec![spectra.of(&motor.viscous), spectra.of(&motor.coulomb)];
        if cfg.theta_e.is_none() {
            regressors.push(spectra.of(&motor.acceleration));
        }
        let mut p = Problem {
            angle: Arc::new(angle_rad.to_vec()),
            ts: cfg.ts_s,
            i_t: cfg.i_t,
            cart_force: cfg.cart_force_n,
            known: spectra.of(&motor.known_nm),
            spectra,
            inv_command,
            regressors,
            theta_e: cfg.theta_e,
            p0: [1.0; N_Q],
            half_width: [1.0; N_Q],
            first_free: usize::from(cfg.fixed_mass),
            q: DVector::zeros(N_Q),
            residual: None,
            evaluations: std::cell::Cell::new(0),
        };
        p.restart(start, 0.5 * cfg.coulomb_hint_nm.max(0.0));
        Ok(p)
    }

    /// Start at `start`'s cart and belt with the cart's Coulomb friction
    /// `cart_coulomb_nm` (at the motor).
    fn restart(&mut self, start: &TwoMassParams, cart_coulomb_nm: f64) {
        // The resonance damping (2.38g) of the linear fit, as belt damping
        // `d`, is the largest the belt can have (the fit lumps friction in).
        let it2 = self.i_t * self.i_t;
        let d_max = start.resonance_damping() / (it2 * start.m_c + start.theta_e);
        // A tenth of the largest force scale: the fit ranges over 1e4 both ways.
        let force_scale = start.c * 1e-5 + start.m_c;
        self.p0 = [
            start.m_c,
            start.c,
            (0.3 * d_max).max(1e-6 * force_scale),
            (0.1 * start.d_c).max(1e-6 * force_scale),
            (cart_coulomb_nm / self.i_t).max(1e-3 * force_scale),
        ];
        self.half_width = [
            MASS_STIFFNESS_RANGE.ln(),
            MASS_STIFFNESS_RANGE.ln(),
            DAMPING_RANGE.ln(),
            DAMPING_RANGE.ln(),
            DAMPING_RANGE.ln(),
        ];
        self.q = DVector::zeros(self.n_free());
        self.evaluations.set(0);
        self.residual = self.evaluate(&self.q).map(|e| e.residual);
    }

    /// How many parameters are fitted.
    fn n_free(&self) -> usize {
        N_Q - self.first_free
    }

    /// The index in `q` of parameter `k`, if it is fitted.
    fn q_index(&self, k: usize) -> Option<usize> {
        k.checked_sub(self.first_free)
    }

    /// The coordinate of parameter `k` in `q`, if it is fitted.
    fn q_of(&self, q: &DVector<f64>, k: usize) -> Option<f64> {
        self.q_index(k).map(|i| q[i])
    }

    fn value(&self, q: &DVector<f64>, k: usize) -> f64 {
        let h = self.half_width[k];
        match self.q_of(q, k) {
            Some(x) => self.p0[k] * (h * (x / h).tanh()).exp(),
            None => self.p0[k],
        }
    }

    fn dlnp_dq(&self, k: usize) -> f64 {
        let t = (self.q_of(&self.q, k).unwrap_or(0.0) / self.half_width[k]).tanh();
        1.0 - t * t
    }

    /// The first fitted mass/stiffness parameter within 1 % (in ln p) of its range.
    fn at_bound(&self) -> Option<usize> {
        (0..2).find(|&k| {
            self.q_of(&self.q, k)
                .is_some_and(|x| (x / self.half_width[k]).tanh().abs() > 0.99)
        })
    }

    fn cart(&self, q: &DVector<f64>) -> CartParams {
        CartParams {
            m_c: self.value(q, 0),
            c: self.value(q, 1),
            d: self.value(q, 2),
            d_c: self.value(q, 3),
            f_c: self.value(q, 4),
        }
    }

    /// The residual of the start model as fitted (no friction, its own
    /// motor damping and `Theta_e`), relative rms.
    fn linear_residual(&self, start: &TwoMassParams) -> f64 {
        let cart = CartParams {
            m_c: start.m_c,
            c: start.c,
            d: start.d,
            d_c: start.d_c,
            f_c: 0.0,
        };
        let tb = self.spectra.of(&belt_torque(
            &self.angle,
            self.ts,
            self.i_t,
            self.cart_force,
            &cart,
        ));
        let mut x = vec![start.d_m, 0.0];
        if self.theta_e.is_none() {
            x.push(start.theta_e);
        }
        let mut sum = 0.0;
        for l in 0..tb.len() {
            let mut e = self.known[l] - tb[l];
            for (j, r) in self.regressors.iter().enumerate() {
                e -= r[l] * x[j];
            }
            sum += (e * self.inv_command[l]).norm_sqr();
        }
        (sum / tb.len() as f64).sqrt()
    }

    fn evaluate(&self, q: &DVector<f64>) -> Option<Evaluation> {
        self.evaluations.set(self.evaluations.get() + 1);
        let cart = self.cart(q);
        let tb = self.spectra.of(&belt_torque(
            &self.angle,
            self.ts,
            self.i_t,
            self.cart_force,
            &cart,
        ));
        let z: Vec<C64> = (0..tb.len())
            .map(|l| (self.known[l] - tb[l]) * self.inv_command[l])
            .collect();
        let regs: Vec<Vec<C64>> = self
            .regressors
            .iter()
            .map(|r| {
                r.iter()
                    .zip(&self.inv_command)
                    .map(|(x, w)| x * *w)
                    .collect()
            })
            .collect();
        let x = nonnegative_least_squares(&regs, &z)?;
        let mut residual = DVector::zeros(2 * z.len());
        for l in 0..z.len() {
            let mut e = z[l];
            for (j, r) in regs.iter().enumerate() {
                e -= r[l] * x[j];
            }
            residual[2 * l] = e.re;
            residual[2 * l + 1] = e.im;
        }
        residual
            .iter()
            .all(|v| v.is_finite())
            .then_some(Evaluation {
                residual,
                d_m: x[0],
                tau_c: x[1],
                theta_e: self
                    .theta_e
                    .unwrap_or_else(|| x.get(2).copied().unwrap_or(0.0)),
            })
    }

    fn jacobian_mat(&self) -> Option<DMatrix<f64>> {
        let base = match &self.residual {
            Some(r) => r.clone(),
            None => self.evaluate(&self.q)?.residual,
        };
        let mut j = DMatrix::zeros(base.len(), self.n_free());
        for k in 0..self.n_free() {
            let mut qp = self.q.clone();
            qp[k] += JACOBIAN_STEP;
            let col = (self.evaluate(&qp)?.residual - &base) / JACOBIAN_STEP;
            j.set_column(k, &col);
        }
        Some(j)
    }
}

/// `min |z - sum_j x_j a_j|^2` over real `x >= 0` for complex columns
/// `a_j` (at most three): every subset of the columns, the best feasible.
fn nonnegative_least_squares(a: &[Vec<C64>], z: &[C64]) -> Option<Vec<f64>> {
    let m = a.len();
    let g = DMatrix::from_fn(m, m, |i, j| {
        a[i].iter()
            .zip(&a[j])
            .map(|(x, y)| (x * y.conj()).re)
            .sum::<f64>()
    });
    let b = DVector::from_fn(m, |i, _| {
        z.iter()
            .zip(&a[i])
            .map(|(x, y)| (x * y.conj()).re)
            .sum::<f64>()
    });
    let zz: f64 = z.iter().map(|x| x.norm_sqr()).sum();
    let mut best: Option<(f64, Vec<f64>)> = None;
    for mask in 0u32..(1 << m) {
        let idx: Vec<usize> = (0..m).filter(|&i| mask >> i & 1 == 1).collect();
        let mut x = vec![0.0; m];
        if !idx.is_empty() {
            let gs = DMatrix::from_fn(idx.len(), idx.len(), |i, j| g[(idx[i], idx[j])]);
            let bs = DVector::from_fn(idx.len(), |i, _| b[idx[i]]);
            let Some(sol) = gs.lu().solve(&bs) else {
                continue;
            };
            if sol.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                continue;
            }
            for (k, &i) in idx.iter().enumerate() {
                x[i] = sol[k];
            }
        }
        // |z - A x|^2 = z'z - 2 b'x + x'Gx
        let xv = DVector::from_vec(x.clone());
        let cost = zz - 2.0 * b.dot(&xv) + (xv.transpose() * &g * &xv)[(0, 0)];
        if best.as_ref().is_none_or(|(c, _)| cost < *c) {
            best = Some((cost, x));
        }
    }
    best.map(|(_, x)| x)
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.q.copy_from(x);
        self.residual = self.evaluate(&self.q).map(|e| e.residual);
    }

    fn params(&self) -> DVector<f64> {
        self.q.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.residual.clone()
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.jacobian_mat()
    }
}

#[cfg(test)]
mod tests;
