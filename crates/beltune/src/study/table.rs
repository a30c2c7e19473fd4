//! The issue-12 table over the outcomes of a study.

use super::{Class, Outcome, OutcomeKind};
use serde::Serialize;

/// One row: what is measured, the value, the target.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableRow {
    /// What is measured.
    pub measured: String,
    /// The value over the study.
    pub value: String,
    /// The target.
    pub target: String,
}

/// The table and the counts behind it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table {
    /// Plants commissioned.
    pub plants: usize,
    /// Plants feasible by physics (computed).
    pub feasible: usize,
    /// Plants able to do the Table A.8 move (computed).
    pub table_a8_feasible: usize,
    /// Successes (a controller that met its limits).
    pub successes: usize,
    /// Correct refusals of infeasible or marginal plants.
    pub correct_refusals: usize,
    /// Defects.
    pub defects: usize,
    /// Plants whose true cart left the travel window.
    pub travel_violations: usize,
    /// The rows.
    pub rows: Vec<TableRow>,
}

/// The `q`-quantile (0..1) of `v` (sorted copy, nearest rank); NaN for none.
pub fn quantile(v: &[f64], q: f64) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let i = ((q * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

fn share(count: usize, of: usize) -> String {
    if of == 0 {
        "n/a".into()
    } else {
        format!(
            "{count} of {of} ({:.1} %)",
            100.0 * count as f64 / of as f64
        )
    }
}

impl Table {
    /// The table over `outcomes`.
    pub fn new(outcomes: &[Outcome]) -> Self {
        let n = outcomes.len();
        let count = |f: &dyn Fn(&Outcome) -> bool| outcomes.iter().filter(|o| f(o)).count();
        let feasible = count(&|o| o.feasibility.feasible);
        let a8 = count(&|o| o.feasibility.table_a8_feasible);
        let with_ctrl: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.kind != OutcomeKind::Failed)
            .collect();
        let ok: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.kind == OutcomeKind::Success)
            .collect();
        let feasible_ok = count(&|o| o.feasibility.feasible && o.kind == OutcomeKind::Success);
        let a8_fail = count(&|o| o.feasibility.table_a8_feasible && o.kind != OutcomeKind::Success);
        let pm: Vec<f64> = with_ctrl
            .iter()
            .filter_map(|o| o.true_velocity_phase_margin_deg)
            .map(|x| if x.is_finite() { x } else { -180.0 })
            .collect();
        let unstable = pm.iter().filter(|&&x| x <= 0.0).count();
        let pm_ge45 = pm.iter().filter(|&&x| x >= 45.0).count();
        let vals = |f: &dyn Fn(&Outcome) -> Option<f64>| -> Vec<f64> {
            ok.iter().filter_map(|o| f(o)).collect()
        };
        let static_um: Vec<f64> = vals(&|o| o.static_error_m.map(|x| x * 1e6));
        let cart_mm: Vec<f64> = vals(&|o| o.max_cart_error_m.map(|x| x * 1e3));
        let coulomb: Vec<f64> = vals(&|o| o.coulomb_error.map(|x| x * 100.0));
        let f_z: Vec<f64> = vals(&|o| o.f_z_error.map(|x| x * 100.0));
        let m_c: Vec<f64> = vals(&|o| o.m_c_error.map(|x| x * 100.0));
        let below = |v: &[f64], lim: f64| v.iter().filter(|&&x| x < lim).count();
        let rows = vec![
            TableRow {
                measured: format!("commissionings that end with a controller meeting its limits ({n} plants)"),
                value: format!(
                    "{}; feasible plants: {}",
                    share(ok.len(), n),
                    share(feasible_ok, feasible)
                ),
                target: "every physically feasible plant".into(),
            },
            TableRow {
                measured: "plants able to do the Table A.8 move that still fail or miss their limits".into(),
                value: format!("{a8_fail} of {a8}"),
                target: "0".into(),
            },
            TableRow {
                measured: "velocity-loop phase margin on the true linearized plant (controllers delivered)".into(),
                value: format!(
                    "median {:.1} deg, p10 {:.1} deg, p1 {:.1} deg, min {:.1} deg; >= 45 deg: {}",
                    quantile(&pm, 0.5),
                    quantile(&pm, 0.1),
                    quantile(&pm, 0.01),
                    quantile(&pm, 0.0),
                    share(pm_ge45, pm.len())
                ),
                target: ">= 45 deg on 99 %, never below 30 deg".into(),
            },
            TableRow {
                measured: "delivered controllers unstable on the true linear plant".into(),
                value: format!("{unstable} of {}", pm.len()),
                target: "0".into(),
            },
            TableRow {
                measured: "static error, nonlinear feedforward (successes)".into(),
                value: format!(
                    "median {:.0} um, p90 {:.0} um, p99 {:.0} um; < 100 um: {}",
                    quantile(&static_um, 0.5),
                    quantile(&static_um, 0.9),
                    quantile(&static_um, 0.99),
                    share(below(&static_um, 100.0), static_um.len())
                ),
                target: "< 100 um on 99 %".into(),
            },
            TableRow {
                measured: "max cart error, nonlinear feedforward (successes)".into(),
                value: format!(
                    "median {:.2} mm, p90 {:.2} mm; < 1 mm: {}",
                    quantile(&cart_mm, 0.5),
                    quantile(&cart_mm, 0.9),
                    share(below(&cart_mm, 1.0), cart_mm.len())
                ),
                target: "< 1 mm on 99 % of feasible plants".into(),
            },
            TableRow {
                measured: "Coulomb friction identification error".into(),
                value: format!(
                    "median {:.1} %, p90 {:.1} %; < 10 %: {}",
                    quantile(&coulomb, 0.5),
                    quantile(&coulomb, 0.9),
                    share(below(&coulomb, 10.0), coulomb.len())
                ),
                target: "< 10 % on 95 %".into(),
            },
            TableRow {
                measured: "f_z / m_c identification error".into(),
                value: format!(
                    "p90 {:.1} % / {:.1} %; < 2 % / < 5 %: {} / {}",
                    quantile(&f_z, 0.9),
                    quantile(&m_c, 0.9),
                    share(below(&f_z, 2.0), f_z.len()),
                    share(below(&m_c, 5.0), m_c.len())
                ),
                target: "< 2 % / < 5 % on 95 %".into(),
            },
        ];
        Table {
            plants: n,
            feasible,
            table_a8_feasible: a8,
            successes: ok.len(),
            correct_refusals: count(&|o| o.class == Class::CorrectRefusal),
            defects: count(&|o| o.class == Class::Defect),
            travel_violations: count(&|o| o.travel_violation),
            rows,
        }
    }

    /// The table as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::from("| measured | value | target |\n| --- | --- | --- |\n");
        for r in &self.rows {
            s.push_str(&format!(
                "| {} | {} | {} |\n",
                r.measured, r.value, r.target
            ));
        }
        s.push_str(&format!(
            "\n{} plants: {} feasible by physics ({} can do the Table A.8 move), {} successes, {} correct refusals, {} defects, {} travel-window violations.\n",
            self.plants,
            self.feasible,
            self.table_a8_feasible,
            self.successes,
            self.correct_refusals,
            self.defects,
            self.travel_violations
        ));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::quantile;

    #[test]
    fn quantiles_are_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(quantile(&v, 0.5), 50.0);
        assert_eq!(quantile(&v, 0.9), 90.0);
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
