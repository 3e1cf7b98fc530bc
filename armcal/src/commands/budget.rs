//! The uncertainty budget options of `calibrate` and `diagnose -o`, and the budget they write.

use armcal::data::Dataset;
use armcal::fit::finish::Fit;
use armcal::fit::holdout::Holdout;
use armcal::uncertainty::estimate::{self, Settings};
use armcal::uncertainty::extrapolation::Support;
use armcal::uncertainty::report::BudgetReport;
use armcal::uncertainty::QUANTISATION_COUNTS;
use quatarm_ref::calfile::Uncertainty;

/// What the data cannot tell: set here, stated in the report as set or assumed.
#[derive(clap::Args, Clone, Debug)]
pub struct BudgetArgs {
    /// Standard uncertainty of one joint reading (counts): 1/√12 is quantisation alone; an
    /// encoder with noise σ counts before quantisation has √(σ² + 1/12).
    #[arg(long, default_value_t = QUANTISATION_COUNTS, value_parser = super::args::budget_counts)]
    encoder_counts: f64,
    /// Standard uncertainty of the probing per axis (mm); default: from the spat scatter when
    /// the data have spat rows, else 0.
    #[arg(long, value_parser = super::args::budget_mm)]
    probing_mm: Option<f64>,
    /// What the model leaves unexplained per axis (mm); default: estimated from the held-out
    /// residuals (the least isotropic term that covers 95 % of them, split-conformal).
    #[arg(long, value_parser = super::args::budget_mm)]
    model_mm: Option<f64>,
    /// The reference instrument's noise per axis (mm) in `point` data: in a held-out row's
    /// residual but not in a reading's error, so not counted in the model term; default 0
    /// (every held-out misfit counted: the safe side).
    #[arg(long, default_value_t = 0.0, value_parser = super::args::budget_mm)]
    instrument_mm: f64,
    /// Standard uncertainty of the temperature reading (°C).
    #[arg(long, default_value_t = 0.0, value_parser = super::args::budget_temperature_c)]
    temperature_c: f64,
    /// Scale κ of the pose-dependent model term when the data are held out by group and have
    /// only two groups, so the data cannot set it: default measured with two training
    /// sessions on the MUKCa fleet (0.968; 0.760 with `--joint-leverage`;
    /// docs/spec-reading.md); give your own fleet's.
    #[arg(long, value_parser = super::args::positive)]
    fleet_kappa: Option<f64>,
    /// Also widen the pose-dependent term where a reading's joint angles are far from the
    /// calibration's (the factor max(1, ℓ, ℓJ), the file's `pose_joint_*` keys). Off by
    /// default: measured, it covers held-out sessions less on simulated arms and gains
    /// nothing on MUKCa's (docs/results/uncertainty.md, round 6).
    #[arg(long)]
    joint_leverage: bool,
}

impl BudgetArgs {
    fn settings(&self) -> Settings {
        Settings {
            encoder_counts: self.encoder_counts,
            probing_mm: self.probing_mm,
            model_mm: self.model_mm,
            instrument_mm: self.instrument_mm,
            temperature_c: self.temperature_c,
            two_group_scale: self
                .fleet_kappa
                .unwrap_or_else(|| armcal::uncertainty::pose::two_group_scale(self.joint_leverage)),
            joint_leverage: self.joint_leverage,
            ..Settings::default()
        }
    }

    /// The budget of `fit` as the file holds it, and its report; `in_sample_rms_um` is the
    /// fit's own RMS residual that the held-out one is compared with.
    pub fn budget(
        &self,
        fit: &Fit,
        data: &Dataset,
        holdout: Option<&Holdout>,
        in_sample_rms_um: f64,
    ) -> anyhow::Result<(Uncertainty, BudgetReport)> {
        let est = estimate::from_fit(fit, data, holdout, in_sample_rms_um, &self.settings())
            .map_err(|e| anyhow::anyhow!("no uncertainty budget: {e}"))?;
        let file = est
            .budget
            .to_file(&fit.arm)
            .map_err(|e| anyhow::anyhow!("no uncertainty budget: {e}"))?;
        let mut report = BudgetReport::build(&est, &fit.arm);
        report.extrapolation = Support::of(&fit.arm, data).map(|s| s.report());
        Ok((file, report))
    }
}

/// The budget for the file, or none and a warning that says why: a fit without a covariance
/// is still written (`calibrate`, `diagnose -o`), without an `[uncertainty]` section. The
/// budget's own warnings (held-out groups it misses as a whole) join the report's.
pub fn or_warning(
    made: anyhow::Result<(Uncertainty, BudgetReport)>,
    report: &mut Option<BudgetReport>,
    warnings: &mut Vec<String>,
) -> Option<Uncertainty> {
    match made {
        Ok((budget, budget_report)) => {
            warnings.extend(budget_report.warnings());
            *report = Some(budget_report);
            Some(budget)
        }
        Err(e) => {
            warnings.push(format!("{e}; the file has no [uncertainty] section"));
            None
        }
    }
}
