//! What the data can fix before any fit: the unknowns a calibration has ([`unknowns`]), the
//! equations the data give ([`equations`]), the structural identifiability at the arm's
//! nominal skeleton ([`structural`]), the comparison with a well-spread design of the same
//! kinds (a degenerate pose set against a limit of the data's kinds), and what a ridge or an
//! unknown's own prior shares out instead of holding. The fit starts from what this leaves
//! (`Structure`), or refuses with a [`CalibError`] that says what to record.

use crate::data::{Dataset, Layout};
use crate::effects::FAMILIES;
use crate::fit::design::design_like;
use crate::fit::error::CalibError;
use crate::fit::ident::{self, Fixed, Identifiability, Why};
use crate::fit::options::Options;
use crate::fit::problem::{start_frame, Problem, State};
use crate::kinds;
use crate::params::{frame_params, Param, ParamExt, Terms};
use crate::progress::Observer;
use nalgebra::{DMatrix, Vector3};
use quatarm_ref::arm::Arm;
use std::f64::consts::FRAC_PI_2;

/// Equations the data give once the fixed points are eliminated: 3 per `point` row, 3 (n − 1)
/// per `spat` group and per bar end, 1 per bar, and n − 3 per sphere position (one radial
/// equation per row, less the centre's three).
pub fn equations(layout: &Layout) -> usize {
    3 * layout.points.len()
        + layout
            .spat
            .iter()
            .map(|g| 3 * (g.rows.len() - 1))
            .sum::<usize>()
        + layout
            .length
            .iter()
            .map(|g| 3 * (g.a.len() - 1) + 3 * (g.b.len() - 1) + 1)
            .sum::<usize>()
        + layout
            .sphere
            .iter()
            .map(|g| g.rows.len().saturating_sub(3))
            .sum::<usize>()
}

fn equations_detail(layout: &Layout) -> String {
    let mut parts = Vec::new();
    if !layout.points.is_empty() {
        parts.push(format!("{} point rows × 3", layout.points.len()));
    }
    if !layout.spat.is_empty() {
        parts.push(format!(
            "{} spat groups: 3 per row beyond the first",
            layout.spat.len()
        ));
    }
    if !layout.length.is_empty() {
        parts.push(format!(
            "{} bar positions: 3 per row beyond the first of each ball, 1 per bar",
            layout.length.len()
        ));
    }
    if !layout.sphere.is_empty() {
        parts.push(format!(
            "{} sphere positions: 1 per row beyond the third",
            layout.sphere.len()
        ));
    }
    parts.join("; ")
}

/// The arm's nominal skeleton: every error key zeroed, tilts within 1e-3 rad of a multiple of
/// π/2 snapped onto it. Structural dependencies are exact there, so they show as singular
/// values at rounding level, not at the level of the errors.
pub fn skeleton(arm: &Arm) -> Arm {
    let mut a = arm.clone();
    for j in &mut a.joints {
        j.zero_offset = 0.0;
        j.link_error = [0.0; 3];
        for t in &mut j.tilt {
            let q = (*t / FRAC_PI_2).round() * FRAC_PI_2;
            if (*t - q).abs() < 1e-3 {
                *t = q;
            }
        }
    }
    a.probe.error = [0.0; 3];
    for p in &mut a.more_probes {
        p.error = [0.0; 3];
    }
    for f in FAMILIES {
        f.clear(&mut a);
    }
    a
}

/// The start arm with an entry for every harmonic term to fit, so that the file written
/// lists it.
fn with_entries(start: &Arm, params: &[Param]) -> Arm {
    let mut a = start.clone();
    for p in params {
        if let Some((e, _)) = p.effect() {
            e.with(|t| t.add_entry(&mut a));
        }
    }
    a
}

/// The unknowns a calibration of `data` with `terms` has: the arm's (with the geometric model,
/// the error of every other probe of `arm`'s that some row was taken with, beside the first's),
/// then the instrument frame's six when there are `point` rows. Without them, the frame's
/// three rotations stand for the rotation of the whole arm that `spat` and `length` data
/// cannot see: identifiability names what they absorb, and they are never fitted.
pub fn unknowns(arm: &Arm, terms: &Terms, data: &Dataset) -> Vec<Param> {
    let mut all = terms.params(data.dof);
    if terms.geometric {
        for k in crate::fit::probes::used(arm, data)
            .into_iter()
            .filter(|&k| k > 0)
        {
            all.extend(crate::params::probe_params(k));
        }
    }
    if has_points(data) {
        all.extend(frame_params());
    } else {
        all.extend((0..3).map(Param::FrameRotation));
    }
    all
}

fn has_points(data: &Dataset) -> bool {
    data.rows.iter().any(|r| r.kind == crate::data::Kind::Point)
}

/// Structural identifiability of `params` for `data` at the skeleton of `arm`.
pub fn structural(
    arm: &Arm,
    data: &Dataset,
    params: &[Param],
    tol: f64,
) -> (Identifiability, DMatrix<f64>) {
    let layout = data.layout();
    let skel = skeleton(&with_entries(arm, params));
    let all: Vec<usize> = (0..params.len()).collect();
    let problem = Problem::new(data, &layout, &skel, params, &all);
    let state = State {
        x: vec![0.0; params.len()],
        frame: start_frame(&skel, data, &layout),
    };
    let r = problem.r_factor(&state);
    let mut id = ident::analyse(&r, params, tol);
    if !has_points(data) {
        // No instrument: the frame's rotations are the data's symmetry, not unknowns.
        let sym: Vec<usize> = id
            .kept
            .iter()
            .copied()
            .filter(|&i| params[i].is_frame())
            .collect();
        id.kept.retain(|&i| !params[i].is_frame());
        id.fixed.retain(|f| !params[f.index].is_frame());
        id.symmetries = sym;
        ident::refresh(&r, &mut id);
    }
    (id, r)
}

/// What the structural check leaves for the fit.
pub(crate) struct Structure {
    pub(crate) layout: Layout,
    /// Every unknown considered.
    pub(crate) all: Vec<Param>,
    /// The start arm with an entry for each term to fit.
    pub(crate) base: Arm,
    /// Equations the data give.
    pub(crate) eqs: usize,
    /// What the data can fix.
    pub(crate) id: Identifiability,
    /// The R factor of the structural analysis.
    pub(crate) r_skel: DMatrix<f64>,
    /// Unknowns a ridge shares out instead of holding.
    pub(crate) shared: Vec<usize>,
    /// What the structural analysis said of each shared unknown (what absorbs it when held).
    pub(crate) shared_fixed: Vec<Fixed>,
}

/// What can be fitted before any fit: the data's kinds, the structural identifiability at the
/// skeleton, the comparison with a well-spread design, and what a ridge shares out.
pub(crate) fn check_structure(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    observer: &mut dyn Observer,
) -> Result<Structure, CalibError> {
    if data.dof != start.dof() {
        return Err(CalibError::Mismatch(format!(
            "the data have {} joints, the arm {}",
            data.dof,
            start.dof()
        )));
    }
    crate::fit::probes::check(start, data).map_err(|e| CalibError::Mismatch(e.to_string()))?;
    let layout = data.layout();
    let all = unknowns(start, &opts.terms, data);
    let base = with_entries(start, &all);
    let eqs = equations(&layout);
    if opts.terms.params(data.dof).is_empty() {
        return Err(CalibError::Mismatch(format!(
            "nothing to fit: no terms requested (`only` needs an effect, e.g. `only,+{}:*`)",
            crate::effects::gravity::KEY
        )));
    }
    check_sphere_groups(&base, data, &layout)?;
    // 0. What the data's kinds cannot fix, before anything is computed on them.
    let requested: Vec<usize> = (0..all.len())
        .filter(|&i| !all[i].is_frame() && !opts.hold.contains(&all[i]))
        .collect();
    if let Some(r) = kinds::check(&layout, &base, &all, &requested) {
        return Err(CalibError::Unfixable {
            what: r.what,
            why: r.why,
        });
    }
    // 1. Structural identifiability, and the design it is compared with.
    observer.stage(&format!(
        "identifiability of {} unknowns on {} rows",
        all.len(),
        data.rows.len()
    ));
    let (mut id, r_skel) = structural(&base, data, &all, opts.structural_tol);
    hold_requested(&mut id, &all, &opts.hold);
    compare_design(&base, data, &layout, &all, &id, opts, observer)?;
    if !id.kept.iter().any(|&i| !all[i].is_frame()) {
        return Err(CalibError::Mismatch(
            "nothing to fit: these data determine none of the unknowns requested".into(),
        ));
    }
    // Under a ridge, or an unknown's own prior, what the data cannot separate is shared out by
    // the penalty instead of held (the frame's rotations without an instrument are a symmetry,
    // never unknowns).
    let penalised = |i: usize| {
        opts.ridge
            .is_some_and(|r| r.weight(all[i], data.rows.len()) > 0.0)
            || opts.prior.as_ref().is_some_and(|p| p.own(all[i]).is_some())
    };
    let shared: Vec<usize> = id
        .fixed
        .iter()
        .filter(|f| matches!(f.why, Why::Inseparable | Why::NoEffect))
        .map(|f| f.index)
        .filter(|&i| penalised(i))
        .collect();
    let shared_fixed: Vec<Fixed> = id
        .fixed
        .iter()
        .filter(|f| shared.contains(&f.index))
        .cloned()
        .collect();
    id.fixed.retain(|f| !shared.contains(&f.index));
    id.kept.extend(&shared);
    id.kept.sort_unstable();
    Ok(Structure {
        layout,
        all,
        base,
        eqs,
        id,
        r_skel,
        shared,
        shared_fixed,
    })
}

/// Every `sphere` group must fix a sphere at the start arm (four or more points, not in one
/// plane), or its centre, which the fit eliminates, is not defined.
fn check_sphere_groups(start: &Arm, data: &Dataset, layout: &Layout) -> Result<(), CalibError> {
    let mounted = crate::fit::probes::Mounted::new(start);
    for g in &layout.sphere {
        let qs: Vec<Vector3<f64>> = g.rows.iter().map(|&i| mounted.tip(&data.rows[i])).collect();
        let radius = crate::fit::probes::sphere_radius(start, data, g);
        if let Err(e) = crate::geometry::sphere::centre_of(&qs, radius) {
            let first = g.rows.first().map(|&i| &data.rows[i]);
            let line = first.map_or(0, |r| r.line);
            let file = first.map_or(data.source.as_str(), |r| data.file_of(r));
            return Err(CalibError::Mismatch(format!(
                "{file}: sphere group {} (line {line}): {e}",
                g.group
            )));
        }
    }
    Ok(())
}

/// Holds the unknowns `--hold` names.
fn hold_requested(id: &mut Identifiability, all: &[Param], hold: &[Param]) {
    for p in hold {
        if let Some(i) = all.iter().position(|q| q == p) {
            if id.is_kept(i) {
                id.kept.retain(|&k| k != i);
                id.fixed.push(Fixed {
                    index: i,
                    why: Why::Requested,
                    absorbed_by: Vec::new(),
                    unexplained: 1.0,
                });
            }
        }
    }
}

/// Refuses data with too few equations, or (with the design check) data that fix less than a
/// well-spread design of the same size would.
fn compare_design(
    base: &Arm,
    data: &Dataset,
    layout: &Layout,
    all: &[Param],
    id: &Identifiability,
    opts: &Options,
    observer: &mut dyn Observer,
) -> Result<(), CalibError> {
    let eqs = equations(layout);
    if !opts.design_check {
        if eqs <= id.kept.len() {
            return Err(CalibError::TooFewRows {
                equations: eqs,
                parameters: id.kept.len(),
                detail: equations_detail(layout),
            });
        }
        return Ok(());
    }
    observer.stage("comparing with a well-spread design");
    let design = design_like(&skeleton(base), data, 0x5eed);
    let (id_design, _) = structural(base, &design, all, opts.structural_tol);
    let need = id_design.kept.len();
    if eqs <= need {
        return Err(CalibError::TooFewRows {
            equations: eqs,
            parameters: need,
            detail: equations_detail(layout),
        });
    }
    if id.kept.len() < need && !opts.allow_degenerate {
        let lost = id_design.kept.iter().filter(|i| !id.is_kept(**i));
        return Err(CalibError::Degenerate {
            lost: lost.map(|&i| all[i].describe(base)).collect(),
            hint: degenerate_hint(data),
        });
    }
    Ok(())
}

/// Which joints hardly move in the data, to say what a degenerate pose set lacks.
fn degenerate_hint(data: &Dataset) -> String {
    let still: Vec<String> = (0..data.dof)
        .filter(|&k| {
            let (lo, hi) = data
                .rows
                .iter()
                .map(|r| r.theta[k])
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t), b.max(t))
                });
            hi - lo < 0.1
        })
        .map(|k| format!("joint {}", k + 1))
        .collect();
    if still.is_empty() {
        "spread the poses over more of each joint's travel (or pass --allow-degenerate to hold \
         what they cannot determine)"
            .into()
    } else {
        format!(
            "{} hardly move{} (less than 0.1 rad over the data); record poses that turn {}, or \
             pass --allow-degenerate to hold what they cannot determine",
            still.join(", "),
            if still.len() == 1 { "s" } else { "" },
            if still.len() == 1 { "it" } else { "them" }
        )
    }
}
