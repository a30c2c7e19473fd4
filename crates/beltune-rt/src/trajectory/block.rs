//! Selection of the time-optimal profile among the valid extremal profiles
//! of step 1 (for one degree of freedom only the minimum duration matters,
//! but the consistency rules of the reference are kept so that the planner
//! succeeds exactly when the reference does).
//!
//! Ported from Ruckig's `Block::calculate_block` (via rsruckig 3.0.1).
//! Copyright (c) 2021 Lars Berscheid (Ruckig), Petri Koskinen (rsruckig);
//! MIT License, full notice in `trajectory/mod.rs`.

use super::profile::Profile;

/// The fastest valid profile and its duration (s, including the brake pre-phase).
#[derive(Clone, Copy, Default, Debug)]
pub(crate) struct Block {
    pub p_min: Profile,
    pub t_min: f64,
}

fn remove_profile(valid_profiles: &mut [Profile; 6], count: &mut usize, index: usize) {
    for i in index..(*count - 1) {
        valid_profiles[i] = valid_profiles[i + 1];
    }
    *count -= 1;
}

impl Block {
    #[inline]
    fn set_min_profile(&mut self, profile: &Profile) {
        self.p_min = *profile;
        self.t_min = self.p_min.total_duration();
    }

    /// Pick the fastest of the `count` valid profiles; `false` when the set of
    /// profiles is inconsistent (an even count that cannot be explained by
    /// duplicates), as in the reference.
    #[allow(clippy::if_same_then_else)]
    pub(crate) fn calculate_block(
        block: &mut Block,
        valid_profiles: &mut [Profile; 6],
        count: &mut usize,
        _numerical_robust: Option<bool>,
    ) -> bool {
        if *count == 1 {
            block.set_min_profile(&valid_profiles[0]);
            return true;
        } else if *count == 2 {
            if (valid_profiles[0].t_sum[6] - valid_profiles[1].t_sum[6]).abs() < 8.0 * f64::EPSILON
            {
                block.set_min_profile(&valid_profiles[0]);
                return true;
            }
            let idx_min = if valid_profiles[0].t_sum[6] < valid_profiles[1].t_sum[6] {
                0
            } else {
                1
            };
            block.set_min_profile(&valid_profiles[idx_min]);
            return true;
        } else if *count == 4 {
            // Identical profiles found by two families.
            if (valid_profiles[0].t_sum[6] - valid_profiles[1].t_sum[6]).abs() < 32.0 * f64::EPSILON
                && valid_profiles[0].direction != valid_profiles[1].direction
            {
                remove_profile(valid_profiles, count, 1);
            } else if (valid_profiles[2].t_sum[6] - valid_profiles[3].t_sum[6]).abs()
                < 256.0 * f64::EPSILON
                && valid_profiles[2].direction != valid_profiles[3].direction
            {
                remove_profile(valid_profiles, count, 3);
            } else if (valid_profiles[0].t_sum[6] - valid_profiles[3].t_sum[6]).abs()
                < 256.0 * f64::EPSILON
            {
                remove_profile(valid_profiles, count, 3);
            } else {
                let mut removed = false;
                'outer: for i in 0..4 {
                    for j in (i + 1)..4 {
                        let ti = valid_profiles[i].t_sum[6];
                        let tj = valid_profiles[j].t_sum[6];
                        if (ti - tj).abs() < 1e-12 * (1.0 + ti.abs()) {
                            remove_profile(valid_profiles, count, j);
                            removed = true;
                            break 'outer;
                        }
                    }
                }
                if !removed {
                    return false;
                }
            }
        } else if *count % 2 == 0 {
            return false;
        }

        // Fastest of the remaining (odd number of) profiles.
        let mut idx_min = 0;
        for i in 1..*count {
            if valid_profiles[i].t_sum[6] < valid_profiles[idx_min].t_sum[6] {
                idx_min = i;
            }
        }
        block.set_min_profile(&valid_profiles[idx_min]);
        *count == 3 || *count == 5
    }
}
