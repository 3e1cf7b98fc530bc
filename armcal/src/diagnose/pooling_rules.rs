//! Rules that name a pooled effect for an arm, side by side (issue 30, round 5).
//!
//! The product names by one rule, the one [`super::fleet_pooled`] applies: the design's mean
//! passes, then each arm whose pooled interval (t on [`super::pooling::interval_df`]) excludes
//! zero; since stop 40 on the pool with the fleet's error scale ([`Rule::FleetScale`],
//! `ErrorScale::Fleet`), before on the arms' own errors ([`Rule::OwnErrors`], `ErrorScale::Own`,
//! still `armcal diagnose --fleet --error-scale own`). Rules that would name more are kept here
//! so that `examples/pooling_power.rs` can count, on the same pooled fleets, what each names
//! where the effect is (power) and where it is not (false causes: null fleets, and mixed fleets
//! whose design mean passes while some arms have nothing). A rule is adopted by the product only
//! when its false causes on both stay at α (docs/results/claims.md §7.6); until then these are
//! comparisons, not diagnoses.
//!
//! Every rule reads only what the pooled stage reports for an arm ([`Arm`]) and its design
//! ([`Design`], whose `named` is the gate after Holm over the candidates), so the counts are of
//! the same estimates the product names from.

use super::pooling::{interval_df, satterthwaite_df, shrinkage_df, Arm, Design};
use crate::stats::{t_critical, t_tail};

/// A rule that names an arm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// Gate, then the arm's pooled interval on min(ν, k − 1) df excludes 0, each arm pooled
    /// with its own jackknife error (the product's until stop 40; `ErrorScale::Own`).
    OwnErrors,
    /// Round 3's: the pooled interval on k − 1 df (covers 0.88–0.92 with 8 arms of 4 sessions).
    RoundThree,
    /// The pooled interval on [`satterthwaite_df`] (covers 0.87–0.95).
    Satterthwaite,
    /// The pooled interval on [`shrinkage_df`]: df growing from the arm's own ν to k − 1 with
    /// its shrinkage B.
    ShrinkageDf,
    /// Gate, then the pooled value on the design mean's side, one-sided at α on the product's
    /// df: the design's two-sided test has fixed the direction, so the arm's claim is then
    /// one-sided.
    OneSided,
    /// Gate, then the design's predictive distribution N(μ̂, τ̂² + se(μ̂)²) excludes 0 at α on
    /// k − 2 df (Higgins, Thompson & Spiegelhalter 2009): a new arm of the design has the
    /// effect, so every arm of the fleet is named, or none.
    Predictive,
    /// The arm's own estimate alone, two-sided on its own ν (no pooling, no gate): the
    /// single-arm test.
    OwnAlone,
    /// The product's (since stop 40; `ErrorScale::Fleet`): [`Rule::OwnErrors`]'s gate and
    /// interval on a different pool: the arms' errors s̃ = √φ̂·v from
    /// their model-based errors and the fleet's pooled dispersion φ̂ (on Σν df), where the
    /// ratios pass their homogeneity test ([`super::pooling::pool_fleet_scale`]); the arms'
    /// own jackknife errors where it fails. Its [`Rule::names`] must be given that pool's
    /// design and arms ([`Rule::fleet_scaled`]), its design's `named` the gate on that pool's
    /// mean (Holm over the candidates).
    FleetScale,
}

/// Every rule, in the order the power example prints them.
pub const RULES: [Rule; 8] = [
    Rule::OwnErrors,
    Rule::RoundThree,
    Rule::Satterthwaite,
    Rule::ShrinkageDf,
    Rule::OneSided,
    Rule::Predictive,
    Rule::OwnAlone,
    Rule::FleetScale,
];

impl Rule {
    /// A short name for tables.
    pub fn label(self) -> &'static str {
        match self {
            Rule::OwnErrors => "own errors (own df)",
            Rule::RoundThree => "round 3 (k − 1 df)",
            Rule::Satterthwaite => "Satterthwaite df",
            Rule::ShrinkageDf => "shrinkage df",
            Rule::OneSided => "one-sided, own df",
            Rule::Predictive => "predictive N(μ̂, τ̂²)",
            Rule::OwnAlone => "own estimate alone",
            Rule::FleetScale => "fleet's error scale (product)",
        }
    }

    /// Whether the rule reads the pool of [`super::pooling::pool_fleet_scale`] instead of
    /// [`super::pooling::pool`]'s: one implementation of the pooling, two inputs.
    pub fn fleet_scaled(self) -> bool {
        self == Rule::FleetScale
    }

    /// Whether the rule names the effect for arm `a` of the design `d` at `alpha`.
    pub fn names(self, d: &Design, a: &Arm, alpha: f64) -> bool {
        let k = d.arms;
        let z = a.pooled / a.pooled_se;
        let two_sided = |df: f64| 2.0 * t_tail(z.abs(), df) < alpha;
        match self {
            Rule::OwnAlone => 2.0 * t_tail((a.estimate / a.se).abs(), a.se_df) < alpha,
            _ if !d.named => false,
            Rule::OwnErrors | Rule::FleetScale => two_sided(interval_df(a.se_df, k)),
            Rule::RoundThree => two_sided(k.saturating_sub(1).max(1) as f64),
            Rule::Satterthwaite => {
                let own = (1.0 - a.shrinkage) * a.se * a.se;
                let design = a.pooled_se * a.pooled_se - own;
                two_sided(satterthwaite_df(own, a.shrinkage, a.se_df, design, k))
            }
            Rule::ShrinkageDf => two_sided(shrinkage_df(a.shrinkage, a.se_df, k)),
            Rule::OneSided => {
                a.pooled * d.mean > 0.0 && t_tail(z.abs(), interval_df(a.se_df, k)) < alpha
            }
            Rule::Predictive => {
                let sd = (d.spread * d.spread + d.mean_se * d.mean_se).sqrt();
                let df = k.saturating_sub(2).max(1) as f64;
                sd > 0.0 && d.mean.abs() > t_critical(alpha, df) * sd
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::pooling::pool;

    /// Eight arms of 4-session errors whose values agree about 1 (no spread seen).
    fn agreeing() -> (Design, Vec<Arm>) {
        let y = [0.5, 1.4, 0.9, 1.2, 0.6, 1.5, 0.8, 1.1];
        pool(&y, &[0.3; 8], &[3.0; 8], 0.01).unwrap()
    }

    #[test]
    fn the_product_rule_is_the_pooled_stages_own() {
        for (y, se) in [
            ([0.5, 1.4, 0.9, 1.2, 0.6, 1.5, 0.8, 1.1], [0.3; 8]),
            ([0.5, 1.4, 0.9, 1.2, 0.6, 1.5, 0.0, -0.1], [0.2; 8]),
            ([3.0, 0.1, -0.2, 0.3, 0.0, 0.2, -0.1, 0.1], [0.5; 8]),
        ] {
            let (d, arms) = pool(&y, &se, &[3.0; 8], 0.01).unwrap();
            for a in &arms {
                assert_eq!(Rule::OwnErrors.names(&d, a, 0.01), a.named_pooled, "{a:?}");
            }
        }
    }

    #[test]
    fn no_pooled_rule_names_without_the_gate() {
        let (mut d, arms) = agreeing();
        assert!(d.named);
        d.named = false;
        for r in RULES.iter().filter(|r| **r != Rule::OwnAlone) {
            assert!(arms.iter().all(|a| !r.names(&d, a, 0.01)), "{r:?}");
        }
        // The arm's own test does not look at the design.
        let own = arms
            .iter()
            .filter(|a| Rule::OwnAlone.names(&d, a, 0.01))
            .count();
        assert_eq!(own, arms.iter().filter(|a| a.named_alone).count());
    }

    #[test]
    fn rules_that_need_less_evidence_name_at_least_as_many() {
        // The one-sided test and the longer df name every arm the product names (same error,
        // a smaller critical value); the predictive rule names all arms or none.
        let (d, arms) = agreeing();
        let count = |r: Rule| arms.iter().filter(|a| r.names(&d, a, 0.01)).count();
        for a in &arms {
            if Rule::OwnErrors.names(&d, a, 0.01) {
                for r in [Rule::OneSided, Rule::RoundThree, Rule::ShrinkageDf] {
                    assert!(r.names(&d, a, 0.01), "{r:?} {a:?}");
                }
            }
        }
        assert!(count(Rule::RoundThree) >= count(Rule::ShrinkageDf));
        assert!(count(Rule::ShrinkageDf) >= count(Rule::OwnErrors));
        assert!([0, 8].contains(&count(Rule::Predictive)));
    }

    #[test]
    fn the_fleet_scale_rule_names_nothing_when_its_gate_does_not_pass() {
        // Arms scattered about 0 with errors whose ratios to the model's agree: the scale is
        // pooled, the design's mean does not pass, and nothing is named, though two arms' own
        // estimates are many of their (fleet-scale) errors from 0.
        let y = [2.0, -2.1, 0.3, -0.2, 0.1, -0.4, 0.2, 0.0];
        let v = [0.1; 8];
        let se = [0.15, 0.2, 0.18, 0.22, 0.2, 0.17, 0.25, 0.2];
        let (_, scaled, d, arms) =
            crate::diagnose::pooling::pool_fleet_scale(&y, &se, &[3.0; 8], &v, 0.01).unwrap();
        assert!(scaled && !d.named, "{d:?}");
        assert!(arms.iter().any(|a| a.named_alone));
        assert!(arms.iter().all(|a| !Rule::FleetScale.names(&d, a, 0.01)));
        // The same arms behind a passed gate: those two are named.
        let open = Design { named: true, ..d };
        let named = arms
            .iter()
            .filter(|a| Rule::FleetScale.names(&open, a, 0.01))
            .count();
        assert!(named >= 2, "{arms:?}");
    }

    #[test]
    fn the_one_sided_rule_names_only_on_the_means_side() {
        // A fleet whose mean is positive and one precise arm clearly negative: the product
        // names it (two-sided), the one-sided rule does not.
        let mut y = vec![5.0, 5.2, 4.8, 5.1, 4.9, 5.0, 5.3, 4.7];
        y.extend_from_within(..);
        y[15] = -1.0;
        let mut se = vec![0.2; 16];
        se[15] = 0.05;
        let (d, arms) = pool(&y, &se, &[9.0; 16], 0.01).unwrap();
        assert!(d.named && d.mean > 0.0, "{d:?}");
        let last = &arms[15];
        assert!(
            last.pooled < 0.0 && Rule::OwnErrors.names(&d, last, 0.01),
            "{last:?}"
        );
        assert!(!Rule::OneSided.names(&d, last, 0.01));
    }

    #[test]
    fn the_predictive_rule_wants_the_spread_small_against_the_mean() {
        // The same mean, a spread of the mean's size: the design's distribution reaches 0.
        let (d, arms) = agreeing();
        assert!(Rule::Predictive.names(&d, &arms[0], 0.01), "{d:?}");
        let wide = Design {
            spread: d.mean,
            ..d
        };
        assert!(!Rule::Predictive.names(&wide, &arms[0], 0.01));
    }

    #[test]
    fn shrinkage_df_runs_from_the_arms_own_to_the_designs() {
        assert_eq!(shrinkage_df(0.0, 3.0, 8), 3.0);
        assert_eq!(shrinkage_df(1.0, 3.0, 8), 7.0);
        assert!((shrinkage_df(0.25, 3.0, 8) - 4.0).abs() < 1e-12);
        // Never fewer than the product's df, never more than k − 1 where ν is more.
        assert_eq!(shrinkage_df(0.5, 20.0, 8), 7.0);
        assert_eq!(shrinkage_df(f64::NAN, 3.0, 4), 3.0);
        assert_eq!(shrinkage_df(2.0, 2.0, 5), 4.0);
    }
}
