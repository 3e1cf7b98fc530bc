//! The joint leverage ℓJ on the hub (issue 27; the table's [`crate::table::joint_leverage`],
//! the contract `quatarm_ref::uncertainty::JointLeverage`): how far a reading's joint
//! configuration is from the calibration's, for the factor max(1, ℓ, ℓJ) on the pose part
//! ([`super::pose`]).
//!
//! ℓJ = dᵀ W d, d_i = θ_i − μ_i taken to [−π, π) (the contract's wrap: a joint angle and the
//! same angle a turn on are one configuration, so a data file's (−π, π] and the counts'
//! [0, 2π) give the same ℓJ), θ_i = 2π · count_i / N_i (N_i the joint's counts per
//! revolution: the host's `Arm::counts_to_rad`). μ is taken to [0, 2π) at boot, so one
//! correction a joint wraps d. Cost: k subtractions, two compares a joint and k(k+1)/2
//! multiply-adds (21 for 6 joints), with the six- and seven-joint arms' loops unrolled
//! (a run-time joint count cost ~400 instructions a point on qemu-m4f, mostly the loops').

use crate::table::joint_leverage::{weight_len, JointLeverage};
use crate::table::{Table, MAX_JOINTS};

/// W's upper triangle for the most joints.
const TRIANGLE: usize = weight_len(MAX_JOINTS);

/// The joint leverage of a table that has it, built at boot (2π/N and W's doubled
/// off-diagonal formed once).
#[derive(Clone, Copy, Debug)]
pub struct JointPart {
    /// k, the table's joints.
    count: usize,
    /// 2π/N_i (rad per count).
    radians_per_count: [f32; MAX_JOINTS],
    /// μ_i (rad).
    mean: [f32; MAX_JOINTS],
    /// W's upper triangle row by row, its off-diagonal entries doubled (exact in f32), so
    /// that ℓJ = Σ_i d_i Σ_(j ≥ i) w_ij d_j.
    weight: [f32; TRIANGLE],
}

impl JointPart {
    /// The part of a validated table's joint leverage (k the table's joints, every number
    /// finite and within its limits there).
    pub fn new(table: &Table<'_>, joints: &JointLeverage<'_>) -> JointPart {
        let count = joints.count().min(MAX_JOINTS);
        let mut part = JointPart {
            count,
            radians_per_count: [0.0; MAX_JOINTS],
            mean: [0.0; MAX_JOINTS],
            weight: [0.0; TRIANGLE],
        };
        for i in 0..count {
            // N ≥ 1 in a validated table; a 0 would give θ = 0 (at the joint's origin), not
            // a division by zero.
            let n = table.joint(i).map_or(0, |j| j.counts);
            part.radians_per_count[i] = if n == 0 {
                0.0
            } else {
                (core::f64::consts::TAU / f64::from(n)) as f32
            };
            part.mean[i] = turn(f64::from(joints.mean(i).unwrap_or(0.0))) as f32;
        }
        let mut at = 0;
        for i in 0..count {
            for j in i..count {
                let w = joints.weight(i, j).unwrap_or(0.0);
                part.weight[at] = if i == j { w } else { 2.0 * w };
                at += 1;
            }
        }
        part
    }

    /// ℓJ of a reading's `counts` (≥ 0; counts beyond the table's joints are ignored, missing
    /// ones count as at the mean, as the host's `JointLeverage::ratio`).
    pub fn ratio(&self, counts: &[u32]) -> f32 {
        match self.count {
            6 if counts.len() >= 6 => self.unrolled::<6>(counts),
            7 if counts.len() >= 7 => self.unrolled::<7>(counts),
            _ => self.looped(counts),
        }
    }

    /// d_i = θ_i − μ_i in [−π, π) (θ in [0, 2π) from the count, μ there since boot).
    #[inline(always)]
    fn deviation(&self, i: usize, count: u32) -> f32 {
        let d = count as f32 * self.radians_per_count[i] - self.mean[i];
        if d >= core::f32::consts::PI {
            d - core::f32::consts::TAU
        } else if d < -core::f32::consts::PI {
            d + core::f32::consts::TAU
        } else {
            d
        }
    }

    /// [`Self::ratio`] for `K` joints known at compile time (the loops unrolled), `counts` at
    /// least `K` long: the same sums in the same order as [`Self::looped`].
    #[inline(always)]
    fn unrolled<const K: usize>(&self, counts: &[u32]) -> f32 {
        let mut d = [0.0f32; K];
        for (i, x) in d.iter_mut().enumerate() {
            *x = self.deviation(i, counts[i]);
        }
        let mut at = 0;
        let mut q = 0.0f32;
        for i in 0..K {
            let mut row = 0.0f32;
            for dj in &d[i..] {
                row += self.weight[at] * dj;
                at += 1;
            }
            q += d[i] * row;
        }
        q.max(0.0)
    }

    /// [`Self::ratio`] for any joint count.
    fn looped(&self, counts: &[u32]) -> f32 {
        let k = self.count.min(MAX_JOINTS);
        let mut d = [0.0f32; MAX_JOINTS];
        for (i, (x, &c)) in d.iter_mut().zip(counts).take(k).enumerate() {
            *x = self.deviation(i, c);
        }
        // W's rows one after the other: row i's k − i entries pair with d_i … d_(k−1).
        let mut w = self.weight.iter();
        let mut q = 0.0f32;
        for i in 0..k {
            let mut row = 0.0f32;
            // d first: when the row's d runs out, zip takes no entry of W past the row.
            for (dj, wij) in d[i..k].iter().zip(&mut w) {
                row += wij * dj;
            }
            q += d[i] * row;
        }
        q.max(0.0)
    }
}

/// `x` (rad) taken to [0, 2π), in f64 at boot (no `floor` in `core`: the whole turns by a
/// truncating cast, |x| ≤ the table's mean limit).
fn turn(x: f64) -> f64 {
    let tau = core::f64::consts::TAU;
    let t = x - (x / tau) as i64 as f64 * tau;
    if t < 0.0 {
        t + tau
    } else {
        t
    }
}

#[cfg(all(test, feature = "parameters", not(feature = "fixed-u95")))]
mod tests {
    use super::*;
    use crate::table::Table;

    /// ℓJ against the f64 formula (θ = 2π c/N, (θ − μ)ᵀ W (θ − μ)) on the sample table with a
    /// joint leverage: within f32's rounding, 0 at the mean, a missing count at the mean.
    #[test]
    fn the_ratio_is_the_quadratic_form_of_the_angles() {
        let (buf, n) = crate::table::pose::tests::encoded_with_joints();
        let t = Table::parse(&buf[..n]).unwrap();
        let joints = t.parameters().unwrap().pose().unwrap().joints().unwrap();
        let part = JointPart::new(&t, &joints);
        let k = t.joint_count();
        let per_rev: std::vec::Vec<f64> = (0..k)
            .map(|i| f64::from(t.joint(i).unwrap().counts))
            .collect();
        let mean: std::vec::Vec<f64> = (0..k).map(|i| f64::from(joints.mean(i).unwrap())).collect();
        let w = |i, j| f64::from(joints.weight(i, j).unwrap());
        let exact = |counts: &[u32]| {
            let d: std::vec::Vec<f64> = (0..k)
                .map(|i| {
                    counts.get(i).map_or(0.0, |&c| {
                        let d = core::f64::consts::TAU * f64::from(c) / per_rev[i] - mean[i];
                        d - (d / core::f64::consts::TAU).round() * core::f64::consts::TAU
                    })
                })
                .collect();
            (0..k)
                .map(|i| d[i] * (0..k).map(|j| w(i, j) * d[j]).sum::<f64>())
                .sum::<f64>()
        };
        let at_mean: std::vec::Vec<u32> = (0..k)
            .map(|i| (mean[i] / core::f64::consts::TAU * per_rev[i]).round() as u32)
            .collect();
        let mut seen_large = false;
        for (s, counts) in [
            at_mean.clone(),
            at_mean.iter().map(|c| c + 3000).collect(),
            at_mean
                .iter()
                .enumerate()
                .map(|(i, c)| c + 40_000 * i as u32)
                .collect(),
            std::vec![0; k],
            std::vec![100_000; k],
            at_mean[..3].to_vec(),
        ]
        .into_iter()
        .enumerate()
        {
            let (got, want) = (f64::from(part.ratio(&counts)), exact(&counts));
            assert!(
                (got - want).abs() <= 1e-5 * want.abs() + 1e-4,
                "case {s}: {got} against {want}"
            );
            seen_large |= want > 10.0;
        }
        assert!(seen_large, "a case far from the mean");
        assert!(f64::from(part.ratio(&at_mean)) < 1e-2);
        // The looped form (any joint count) gives the unrolled form's bits.
        for counts in [at_mean.clone(), std::vec![100_000; k]] {
            assert_eq!(
                part.ratio(&counts).to_bits(),
                part.looped(&counts).to_bits()
            );
        }
    }

    /// The wrap: a mean of −0.1 rad and a reading at 2π − 0.1 rad are one configuration
    /// (ℓJ ≈ 0), as are means a whole turn apart; half a turn away is the largest ℓJ.
    #[test]
    fn a_turn_apart_is_the_same_configuration() {
        let (buf, n) = crate::table::pose::tests::encoded_with_joints();
        let t = Table::parse(&buf[..n]).unwrap();
        let joints = t.parameters().unwrap().pose().unwrap().joints().unwrap();
        let mut part = JointPart::new(&t, &joints);
        let k = t.joint_count();
        let per_rev = f64::from(t.joint(0).unwrap().counts);
        let at = |rad: f64| (rad / core::f64::consts::TAU * per_rev).round() as u32;
        for i in 0..k {
            part.mean[i] = turn(-0.1) as f32;
        }
        let near = std::vec![at(core::f64::consts::TAU - 0.1); k];
        assert!(part.ratio(&near) < 1e-6, "{}", part.ratio(&near));
        let far = std::vec![at(core::f64::consts::PI - 0.1 - 1e-3); k];
        assert!(part.ratio(&far) > 1.0, "{}", part.ratio(&far));
        assert!((turn(-0.1) - (core::f64::consts::TAU - 0.1)).abs() < 1e-12);
        assert!((turn(3.0 * core::f64::consts::TAU + 0.5) - 0.5).abs() < 1e-12);
    }
}
