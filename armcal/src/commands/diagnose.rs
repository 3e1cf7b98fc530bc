//! `armcal diagnose`: show what the arm's model gets wrong, name the physical cause, extend
//! the model with it and measure the gain on data it did not fit.

use anyhow::{bail, Context};
use armcal::data::Dataset;
use armcal::diagnose::report::Report;
use armcal::diagnose::same_arm::{self, Grouping};
use armcal::diagnose::Diagnosis;
use armcal::diagnose::{self, patterns, plots, report, FoldChoice};
use armcal::effects::figure::Figure;
use armcal::html::header::Provenance;
use armcal::output::Staged;
use quatarm_ref::arm::Arm;
use std::path::{Path, PathBuf};

/// Arguments of `armcal diagnose`.
#[derive(clap::Args)]
pub struct Args {
    /// Measured data (CSV of `spec/measured-data.md`): any mix of point, spat and length rows,
    /// in one file or several (each file's groups kept apart), joint readings in radians
    /// (`j1..jN`) or encoder counts (`c1..cN`).
    #[arg(required_unless_present = "fleet", num_args = 1..)]
    data: Vec<PathBuf>,
    /// Diagnose several units of one design instead, one file per recording (its `group`s
    /// are its sessions): which causes the design has (random-effects pooling of every unit's
    /// held-out gain) and which single units have. A recording is named by its file stem
    /// less the prefix all stems share up to a `-`; recordings of one physical arm are one
    /// unit (see `--same-arm-alpha`, `--same-arm`, `--each-file-an-arm`).
    #[arg(long, num_args = 2.., value_name = "CSV",
          conflicts_with_all = ["data", "plots", "output", "by_group"])]
    fleet: Vec<PathBuf>,
    /// With `--fleet`: family-wise level of each step's design-level test (Holm over the
    /// candidates).
    #[arg(long, default_value_t = diagnose::fleet::ALPHA,
          value_parser = super::args::probability)]
    fleet_alpha: f64,
    /// With `--fleet`: the error each arm's pooled estimate is weighed by. `fleet` (default):
    /// its jackknife error's scale pooled over the arms (√φ̂ times its fit's in-sample error,
    /// where Bartlett's test at the fleet's α does not reject one φ for the design; else its
    /// own); `own`: its own jackknife error on its sessions − 1 df (the earlier default).
    #[arg(long, value_enum, default_value_t = diagnose::fleet::ErrorScale::Fleet)]
    error_scale: diagnose::fleet::ErrorScale,
    /// With `--fleet`: the model each pooled candidate is estimated in. `full` (default): every
    /// candidate the recordings share in one fit, each conditional on all the others (a joint
    /// sharing another's gravity lever is not named for it; where a recording's full fit cannot
    /// be made, each alone, said); `alone`: each with the geometric model alone.
    #[arg(long, value_enum, default_value_t = diagnose::fleet::PooledModel::Full)]
    pooled_model: diagnose::fleet::PooledModel,
    /// With `--fleet`: an arm with no recording of 3 sessions or more but one of 2 joins the
    /// pooled stage, its value from one fit on all its sessions weighed by √φ̂ times that fit's
    /// in-sample error (only on the fleet's error scale; its φ is assumed the other arms',
    /// which nothing can test), with no held-out gain. Off by default: left out, said.
    #[arg(long, requires = "fleet")]
    join_short: bool,
    /// With `--fleet`: these recordings (unit names as the fleet gives them, e.g.
    /// `--same-arm panda_3=panda_3,panda_3_bis,panda_right`) are one physical arm, one unit of
    /// the fleet test named ARM, their sessions' evidence pooled. Repeat for more arms. Given, it sets
    /// the grouping wholly: every recording not listed is an arm of its own and nothing is
    /// detected (the pairwise statistics are still reported).
    #[arg(long = "same-arm", value_name = "ARM=REC,REC,…", requires = "fleet",
          conflicts_with = "each_file_an_arm",
          value_parser = diagnose::same_arm::parse_same_arm)]
    same_arm: Vec<(String, Vec<String>)>,
    /// With `--fleet`: every file is an arm of its own (no same-arm detection, no
    /// statistics).
    #[arg(long, requires = "fleet")]
    each_file_an_arm: bool,
    /// With `--fleet` and neither option above: two recordings are one arm when their
    /// identified geometric errors (probe excluded) agree, P(F(k, D) > F) ≥ this, with
    /// F = dᵀ(C_A + C_B)⁻¹d / (k φ̂) (d their difference, C their covariances, k the unknowns
    /// both identify alike, φ̂ the same statistic's χ²/k between alternate-session halves of
    /// every recording, pooled over D degrees of freedom), closed transitively.
    #[arg(long, default_value_t = diagnose::same_arm::ALPHA,
          value_parser = super::args::probability)]
    same_arm_alpha: f64,
    /// The arm's nominal model (or an earlier calibration); default the spec's `default-6`.
    #[arg(long)]
    arm: Option<PathBuf>,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Show progress on stderr even when it is not a terminal (`--fleet`: each recording's
    /// fits and tests counted, with the time left).
    #[arg(long)]
    progress: bool,
    /// Write the figures (PNG) into this folder: residuals against each joint's reading,
    /// each joint's gravity lever, and temperature.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Write the extended calibration file here; its binary table goes beside it (`.bin`).
    #[arg(short, long, value_name = "EXTENDED.toml")]
    output: Option<PathBuf>,
    /// Write the diagnosis report here: one self-contained HTML page (header with the arm's
    /// serial, the data file and its SHA-256, the verdict, held-out residuals before and
    /// after, residual vectors against position, each cause with its evidence).
    #[arg(long, value_name = "FILE.html", conflicts_with = "fleet")]
    report: Option<PathBuf>,
    /// Folds of held-out validation (units: a point row, a spat or length group whole).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=1000))]
    folds: u32,
    /// Hold out one group at a time (whole sessions, artefact positions) instead of k folds.
    #[arg(long)]
    by_group: bool,
    /// Family-wise level of the in-sample test at each selection step (Bonferroni over the
    /// candidates).
    #[arg(long, default_value_t = 1e-3, value_parser = super::args::probability)]
    alpha: f64,
    /// The held-out rule: a cause is kept only if its gain in held-out squared error, paired
    /// over the held-out units (a `point` row, a `spat` or `length` group), passes a one-sided
    /// paired t-test with (units − 1) degrees of freedom at p < Φ(−z), the normal tail of z
    /// (z = 2: p < 0.0228). Fewer than 3 units test nothing ("cannot test").
    #[arg(long, default_value_t = 2.0, value_parser = super::args::non_negative)]
    z: f64,
    /// Highest order of a periodic cause tried, on every joint: encoder harmonics up to this,
    /// axis wobbles up to the smaller of this and 3. The data may resolve less, and then set
    /// the limit: joint k is tried up to min(this, ⌊π / g⌋ − 1, n / 8), with g the widest gap
    /// (rad) between its consecutive distinct readings and n their number (one reading per
    /// half period, eight per order); higher orders are listed as not testable. The search
    /// for unexplained structure uses the data's limit alone.
    #[arg(long, default_value_t = diagnose::candidates::MAX_ORDER,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    max_order: u32,
    /// Family-wise level of the search for unexplained structure in what the named causes
    /// leave (Holm's step-down over every test of every variable).
    #[arg(long, default_value_t = diagnose::unexplained::ALPHA,
          value_parser = super::args::probability)]
    unexplained_alpha: f64,
    /// Iterations before a fit is declared not converging.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    max_iter: u32,
    #[command(flatten)]
    budget: super::budget::BudgetArgs,
    #[command(flatten)]
    accept: super::accept::AcceptArgs,
}

/// Runs the subcommand. Arguments, the start arm, the outputs' names and the data are
/// checked before any fit; the files (calibration, table, figures) are written together at
/// the end, or none of them.
pub fn run(a: Args) -> anyhow::Result<()> {
    if !a.fleet.is_empty() {
        return run_fleet(&a);
    }
    let (start, inputs) = check_before_fit(&a)?;
    let data = super::data_in::read(&a.data, &start, a.accept.accept())?;
    let opts = options(&a);
    let d = spinning(
        !a.json,
        "diagnosing: fitting the geometric model, testing candidates…",
        || diagnose::diagnose(&start, &data, &opts),
    )
    .with_context(|| format!("cannot diagnose {}", super::data_in::names(&a.data)))?;
    let mut figures = patterns::figures(&d, &data);
    figures.extend(diagnose::unexplained::figure(&d.unexplained));
    let mut rep = report::build(&d, &data, &figures);
    nested(&a, &start, &data, &opts, &mut rep)?;
    test_level(&start, &data, &opts, &d, &mut rep);
    let mut files = Staged::guarding(&inputs);
    stage(&a, &d, &data, &figures, &mut rep, &mut files)?;
    files.commit()?;
    super::print_report(a.json, || rep.json(), || rep.text());
    Ok(())
}

/// What can be refused before any fit: the arguments, the start arm, the outputs' names
/// (none may overwrite an input) and a `--plots` folder that is a file. Returns the start arm
/// and the inputs the outputs are guarded against.
fn check_before_fit(a: &Args) -> anyhow::Result<(Arm, Vec<(&Path, &'static str)>)> {
    if a.data.is_empty() {
        bail!("no data file given");
    }
    if a.folds < 2 && !a.by_group {
        bail!("--folds must be 2 or more: a diagnosis needs held-out data");
    }
    let start = super::calibrate::start_arm(a.arm.as_deref(), a.accept.accept())?;
    let mut inputs = super::data_in::inputs(&a.data);
    if let Some(arm) = &a.arm {
        inputs.push((arm.as_path(), "start arm"));
    }
    let table = a.output.as_ref().map(|o| o.with_extension("bin"));
    let mut outputs = Vec::new();
    if let (Some(out), Some(table)) = (&a.output, &table) {
        outputs.push((out.as_path(), "extended calibration file"));
        outputs.push((table.as_path(), "binary table"));
    }
    if let Some(r) = &a.report {
        outputs.push((r.as_path(), "report"));
    }
    armcal::output::check(&outputs, &inputs)?;
    if let Some(dir) = &a.plots {
        if dir.is_file() {
            bail!(
                "{}: --plots names a folder, and this is a file",
                dir.display()
            );
        }
    }
    Ok((start, inputs))
}

/// The diagnosis' options from the arguments.
fn options(a: &Args) -> diagnose::Options {
    let mut opts = diagnose::Options {
        folds: if a.by_group {
            FoldChoice::ByGroup
        } else {
            FoldChoice::KFold {
                k: a.folds as usize,
                seed: 0x0f01d,
            }
        },
        ..diagnose::Options::default()
    };
    opts.calib.lm.max_iterations = a.max_iter as usize;
    opts.select.alpha = a.alpha;
    opts.select.z = a.z;
    opts.max_order = a.max_order;
    opts.unexplained_alpha = a.unexplained_alpha;
    opts
}

/// Runs `work` under a spinner on stderr saying `message` (`show` false: no spinner, the
/// output is JSON for a program), cleared when it ends.
fn spinning<T>(show: bool, message: &'static str, work: impl FnOnce() -> T) -> T {
    let pb = show.then(|| {
        let pb = indicatif::ProgressBar::new_spinner();
        pb.set_message(message);
        pb.enable_steady_tick(std::time::Duration::from_millis(200));
        pb
    });
    let done = work();
    if let Some(pb) = &pb {
        pb.finish_and_clear();
    }
    done
}

/// The headline test with sessions: the whole selection rerun without each one, whenever
/// the data have groups to hold out (`sessions::nested_plan` says when not, and why, in the
/// report).
fn nested(
    a: &Args,
    start: &Arm,
    data: &Dataset,
    opts: &diagnose::Options,
    rep: &mut Report,
) -> anyhow::Result<()> {
    if let Err(why) = diagnose::sessions::nested_plan(data, opts.folds) {
        rep.nested_not_run = Some(why);
        return Ok(());
    }
    let n = spinning(
        !a.json,
        "rerunning the diagnosis without each session…",
        || diagnose::nested::nested(start, data, opts),
    );
    rep.nested = Some(
        n.with_context(|| {
            format!(
                "cannot rerun the diagnosis of {}",
                super::data_in::names(&a.data)
            )
        })?
        .report(),
    );
    Ok(())
}

/// Stages the outputs asked for: the figures, the extended calibration file and its table,
/// the HTML report; the report says what was written.
fn stage(
    a: &Args,
    d: &Diagnosis,
    data: &Dataset,
    figures: &[Figure],
    rep: &mut Report,
    files: &mut Staged,
) -> anyhow::Result<()> {
    if let Some(dir) = &a.plots {
        let pictures = plots::write_all(figures, dir, files)?;
        rep.output.plots = pictures.iter().map(|p| p.display().to_string()).collect();
        if !d.candidates.thermal {
            rep.warnings
                .push("no figure against temperature: the data have no temperature spread".into());
        }
    }
    if let Some(out) = &a.output {
        stage_extended(a, out, d, data, rep, files)?;
    }
    if let Some(r) = &a.report {
        let prov = Provenance::of_fit(&d.extended.fit.arm, a.arm.as_deref(), &a.data, data);
        let page = armcal::html::diagnosis::page(rep, d, data, &prov);
        files.write(r, page.as_bytes())?;
    }
    Ok(())
}

/// `armcal diagnose --fleet`: every file is a unit of the arm `--arm` (default `default-6`).
fn run_fleet(a: &Args) -> anyhow::Result<()> {
    let start = super::calibrate::start_arm(a.arm.as_deref(), a.accept.accept())?;
    let paths: Vec<&Path> = a.fleet.iter().map(PathBuf::as_path).collect();
    let files = diagnose::fleet::read_units(&paths, start.dof())?;
    for u in &files {
        for w in &u.data.warnings {
            eprintln!("armcal: warning: {}: {w}", u.file);
        }
    }
    let mut opts = diagnose::fleet::Options {
        alpha: a.fleet_alpha,
        error_scale: a.error_scale,
        pooled_model: a.pooled_model,
        join_short: a.join_short,
        ..diagnose::fleet::Options::default()
    };
    opts.diagnose.calib.lm.max_iterations = a.max_iter as usize;
    opts.diagnose.select.alpha = a.alpha;
    opts.diagnose.select.z = a.z;
    opts.diagnose.max_order = a.max_order;
    opts.diagnose.unexplained_alpha = a.unexplained_alpha;
    let grouping = if a.each_file_an_arm {
        Grouping::EachFile
    } else if !a.same_arm.is_empty() {
        Grouping::ByHand(a.same_arm.clone())
    } else {
        Grouping::Detect {
            alpha: a.same_arm_alpha,
        }
    };
    // A count with the time left for each stage: on a terminal, or piped with --progress.
    let mut obs = armcal::progress::for_command(
        a.progress,
        &format!("diagnosing a fleet of {} recordings", files.len()),
    );
    let mut run = || -> anyhow::Result<_> {
        let arms = same_arm::group_observed(&start, &files, &opts, &grouping, obs.as_mut())?;
        if arms.groups.len() < 2 {
            return Err(anyhow::anyhow!(
                "the {} recordings are all one arm ({}): a fleet needs two arms or more to tell a \
                 design's causes from a unit's (one arm's fleet test has no spread: ± inf). Diagnose \
                 the arm with `armcal diagnose {}` (several files are read as one dataset), or say \
                 they are different arms with --each-file-an-arm or --same-arm",
                files.len(),
                arms.groups
                    .first()
                    .map_or_else(|| "none fitted".to_string(), |g| g.arm.clone()),
                a.fleet
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(" ")
            ));
        }

        let f = diagnose::fleet::diagnose_arms_observed(
            &start,
            &files,
            &arms.list(),
            &opts,
            obs.as_mut(),
        )
        .context("cannot diagnose the fleet")?;
        // Partial pooling of every one-unknown candidate over the arms.
        let pooled = diagnose::fleet_pooled::pool_fleet(&start, &files, &f, &opts)
            .context("cannot pool the fleet's arms")?;
        Ok((arms, f, pooled))
    };
    let done = run();
    drop(obs);
    let (arms, f, pooled) = done?;
    let names: Vec<String> = files.iter().map(|u| u.name.clone()).collect();
    let rep = diagnose::fleet_report::build(
        &f,
        "file stem less the prefix every stem shares up to its last `-`",
        &arms,
        &names,
        &pooled,
    );
    super::print_report(a.json, || rep.json(), || rep.text());
    Ok(())
}

/// Tests the assumption of the named gravity terms, a level base ([`diagnose::level`]),
/// where the data have the sessions for it; the report says the outcome or why not.
fn test_level(
    start: &Arm,
    data: &Dataset,
    opts: &diagnose::Options,
    d: &Diagnosis,
    rep: &mut Report,
) {
    let gravity: Vec<_> = d
        .extended
        .effects
        .iter()
        .copied()
        .filter(|e| matches!(e, armcal::params::Effect::Gravity(_)))
        .collect();
    if gravity.is_empty() {
        return;
    }
    let calib = armcal::fit::options::Options {
        design_check: false,
        allow_degenerate: true,
        ..opts.calib.clone()
    };
    let level = spinning(
        true,
        "fitting the base's tilt through the gravity terms…",
        || diagnose::level::test_level(start, data, &calib, &gravity),
    );
    match level {
        Ok(l) => rep.level = Some(l),
        Err(e) => rep.level_not_tested = Some(e.to_string()),
    }
}

/// Stages the extended calibration file `out` and its binary table beside it (or says in the
/// report why the firmware cannot hold the model, and removes a stale table at commit).
fn stage_extended(
    a: &Args,
    out: &Path,
    d: &Diagnosis,
    data: &Dataset,
    rep: &mut Report,
    files: &mut Staged,
) -> anyhow::Result<()> {
    let arm = &d.extended.fit.arm;
    let header = [
        format!(
            "extended calibration by armcal diagnose from {}",
            super::data_in::names(&a.data)
        ),
        format!("model {}; {}", rep.extended.model, rep.verdict),
    ];
    let refs: Vec<&str> = header.iter().map(String::as_str).collect();
    // The diagnosis' own held-out check compares models, not this fit's σ̂: no inflation
    // (an in-sample RMS of 0 asks for none), but its held-out residuals of the extended
    // model are what the budget's model term is estimated from.
    let fit = &d.extended.fit;
    let made = a.budget.budget(fit, data, Some(&d.extended.holdout), 0.0);
    let budget = super::budget::or_warning(made, &mut rep.uncertainty, &mut rep.warnings);
    let text = super::written::checked_text(arm, budget.as_ref(), &refs, data)?;
    let table = super::written::stage_with_table(files, out, &text, arm, budget.as_ref())?;
    rep.output.calibration = Some(out.display().to_string());
    match table {
        Ok(table) => rep.output.table = Some(table.display().to_string()),
        Err(e) => {
            let why = report::beyond_table(arm);
            rep.output.table_error = Some(format!(
                "{e}{}: the firmware could not apply {}; the calibration file is \
                 written and the host evaluates every term",
                if why.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", why.join("; "))
                },
                if why.len() == 1 {
                    "this term"
                } else {
                    "these terms"
                }
            ));
        }
    }
    Ok(())
}
