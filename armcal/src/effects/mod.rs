//! The extended effects of the model, each a unit of its own, and the one registry the rest of
//! the tool iterates over.
//!
//! An effect is a family of terms of `spec/arm-model.md` beyond the geometric model (an encoder
//! harmonic, a gravity compliance, a thermal expansion). Each lives in one module that
//! implements its contract, split by concern:
//! - [`Family`]: what holds for every term of the effect — its key, how `--terms` spells and
//!   parses it, the candidates a diagnosis tries, the firmware table's limits, how a skeleton
//!   arm clears it;
//! - [`Draw`]: the figure its residual pattern shows in, drawn from the [`figure::Patterns`]
//!   the diagnosis computes (default: none);
//! - [`Term`]: the model's maths of one term (joint 2's harmonic of order 1) — its unknowns
//!   with their keys, units, plausible sizes, values in an arm and Jacobian columns;
//! - [`Describe`]: the term in words and its magnitude in a report (defaults for a term of one
//!   unknown that is not periodic);
//! - [`Simulate`]: a typical size of the term, for the diagnosis's scenarios.
//!
//! Defaults are given only where one answer is right for most effects; every other question a
//! new effect must answer. The only exhaustive matches over [`Effect`] and the effect unknowns
//! of [`Param`] are in this file, so a new variant that is not registered here does not
//! compile. `docs/adding-an-effect.md` lists the steps.
//!
//! This is the model layer: the effects import the parameters, the data and the leaf modules
//! ([`crate::rng`]), never the fit, the diagnosis or the simulation.

pub mod figure;
pub mod gravity;
pub mod harmonic;
pub mod thermal;
pub mod wobble;

use crate::rng::SimRng;
use figure::{Figure, Patterns};
use nalgebra::{Matrix3, Vector3};
use quatarm_params::{Link, Param};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward::{tilt_axis, Chain};
use serde_json::Value;
use std::fmt;

/// An extended effect of the spec's vocabulary: one term, as `--terms` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Effect {
    /// An encoder harmonic of a joint (0-based) and order: two coefficients (sin, cos);
    /// [`harmonic`].
    Harmonic {
        /// Joint, 0-based.
        joint: usize,
        /// Order h ≥ 1.
        order: u32,
    },
    /// A gravity compliance of a joint (0-based); [`gravity`].
    Gravity(usize),
    /// A thermal expansion of a link or the probe; [`thermal`].
    Thermal(Link),
    /// An axis wobble of a joint (0-based) and order: four coefficients; [`wobble`].
    Wobble {
        /// Joint, 0-based.
        joint: usize,
        /// Order h ≥ 1.
        order: u32,
    },
}

/// Why a `--terms` item was refused, in words naming the item.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct TermsError(pub String);

/// What holds for every term of one effect: how `--terms` spells and parses it, which terms
/// there are, what the firmware's table holds of it. Implemented by a unit struct per effect
/// module and registered once in [`FAMILIES`]; how the diagnosis draws the effect is its
/// supertrait [`Draw`].
pub trait Family: Draw + Sync {
    /// The spec's key, as `--terms` and the diagnosis report spell it.
    fn key(&self) -> &'static str;
    /// The `--terms` form, for the list of known terms (e.g. `+KEY:J`).
    fn usage(&self) -> &'static str;
    /// The terms of `+KEY:ARGS…` (`args` split at `:`) for an arm of `dof` joints. `item` is the
    /// whole text, for messages.
    fn parse(&self, item: &str, args: &[&str], dof: usize) -> Result<Vec<Effect>, TermsError>;
    /// Every term a diagnosis tries for `dof` joints; `thermal`: the data have a temperature
    /// spread.
    fn vocabulary(&self, dof: usize, thermal: bool) -> Vec<Effect>;
    /// What of `arm` at joint `at` (or the probe) the firmware's binary table cannot hold, in
    /// words, from `quatarm::table`'s own limits.
    fn beyond_table(&self, arm: &Arm, at: Link) -> Vec<String>;
    /// Clears the effect's values in `arm` (the skeleton a structural analysis runs at).
    fn clear(&self, arm: &mut Arm);
}

/// How the diagnosis draws an effect: the figure its residual pattern shows in.
pub trait Draw {
    /// The figure of the diagnosis in which the effect's residual pattern shows, drawn from
    /// the patterns the diagnosis computed (`None`, the default: the effect has no figure, or
    /// none for these data).
    fn figure(&self, _at: &Patterns) -> Option<Figure> {
        None
    }
}

/// The model's maths of one term of an effect: its unknowns, numbered 0..[`Term::coefficients`],
/// their values in an arm and their Jacobian columns. How the term is told in words is its
/// supertrait [`Describe`], how a simulation sets it [`Simulate`].
pub trait Term: Describe + Simulate {
    /// Its family.
    fn family(&self) -> &'static dyn Family;
    /// How many unknowns it adds.
    fn coefficients(&self) -> usize;
    /// Its unknown `c`.
    fn param(&self, c: usize) -> Param;
    /// Unit of its unknowns' values.
    fn unit(&self) -> &'static str;
    /// A size beyond which a value is not physically plausible.
    fn plausible(&self) -> f64;
    /// Which unknown to keep when the data cannot separate two: lower keeps first (the
    /// geometric model's are 1–4, the frame's 0).
    fn priority(&self) -> u32;
    /// Unknown `c`'s current value in `arm`.
    fn value(&self, arm: &Arm, c: usize) -> f64;
    /// Adds `dx` to unknown `c` in `arm`.
    fn add_to(&self, arm: &mut Arm, c: usize, dx: f64);
    /// Gives `arm` the entry the term needs in a calibration file (a harmonic's order), with
    /// value 0, if it has none.
    fn add_entry(&self, arm: &mut Arm);
    /// ∂p/∂(unknown `c`) at one point of the chain.
    fn column(&self, c: usize, at: &TipPoint) -> Vector3<f64>;
}

/// How one term is told in reports: its spelling, its words, its size.
pub trait Describe {
    /// The `--terms` spelling, e.g. `+KEY:4` (joint 1-based).
    fn spec(&self) -> String;
    /// In words, joints 1-based.
    fn describe(&self) -> String;
    /// Its physical cause in a few words, with a leading space and in parentheses (or empty).
    fn physical(&self) -> &'static str;
    /// Where it acts, for the report: the 1-based joint, or `"probe"`.
    fn location(&self) -> Value;
    /// The order of a periodic term (`None`, the default: not periodic).
    fn order(&self) -> Option<u32> {
        None
    }
    /// Unknown `c` in words.
    fn describe_param(&self, c: usize) -> String;
    /// Its magnitude and standard uncertainty from its unknowns' (value, uncertainty) and, for
    /// two unknowns, their correlation `rho`. The default is for a term of one unknown: that
    /// unknown's value and uncertainty.
    fn magnitude(&self, values: &[(f64, f64)], _rho: f64) -> (f64, f64) {
        values[0]
    }
    /// The (sin, cos) coefficients of a single sinusoid, for the report (`None`, the default:
    /// not one).
    fn phasor(&self, _values: &[f64]) -> Option<(f64, f64)> {
        None
    }
    /// Why it cannot change any residual, when the structural analysis says so and the effect
    /// knows a specific reason (`None`, the default: the generic one).
    fn no_effect_reason(&self, _arm: &Arm, _thermal: bool) -> Option<String> {
        None
    }
}

/// How a simulation sets one term: the diagnosis's scenarios draw arms with it.
pub trait Simulate {
    /// Sets it in `arm` to a random size of the kind a hub-class arm shows.
    fn set_typical(&self, arm: &mut Arm, rng: &mut SimRng);
}

/// Every effect, in report order (figures, candidates, table limits follow it).
pub static FAMILIES: [&dyn Family; 4] = [
    &harmonic::FAMILY,
    &gravity::FAMILY,
    &thermal::FAMILY,
    &wobble::FAMILY,
];

impl Effect {
    /// The term's unit, to ask it anything.
    pub fn with<R>(self, f: impl FnOnce(&dyn Term) -> R) -> R {
        match self {
            Effect::Harmonic { joint, order } => f(&harmonic::Harmonic { joint, order }),
            Effect::Gravity(joint) => f(&gravity::Gravity { joint }),
            Effect::Thermal(link) => f(&thermal::Thermal { link }),
            Effect::Wobble { joint, order } => f(&wobble::Wobble { joint, order }),
        }
    }

    /// The unknowns the effect adds.
    pub fn params(self) -> Vec<Param> {
        self.with(|t| (0..t.coefficients()).map(|c| t.param(c)).collect())
    }

    /// The `--terms` spelling, e.g. `+KEY:4` (joint 1-based).
    pub fn spec(self) -> String {
        self.with(|t| t.spec())
    }

    /// The effect in words, joints 1-based.
    pub fn describe(self) -> String {
        self.with(|t| t.describe())
    }

    /// The spec's key of its family.
    pub fn key(self) -> &'static str {
        self.with(|t| t.family().key())
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.spec())
    }
}

/// The effect an unknown belongs to and its number within it (`None`: a geometric or frame
/// unknown).
pub fn effect_of(p: Param) -> Option<(Effect, usize)> {
    match p {
        Param::Harmonic { joint, order, cos } => {
            Some((Effect::Harmonic { joint, order }, usize::from(cos)))
        }
        Param::Gravity(j) => Some((Effect::Gravity(j), 0)),
        Param::Thermal(l) => Some((Effect::Thermal(l), 0)),
        Param::Wobble { joint, order, coef } => {
            Some((Effect::Wobble { joint, order }, usize::from(coef)))
        }
        Param::ZeroOffset(_)
        | Param::Tilt(..)
        | Param::LinkError(..)
        | Param::ProbeError(..)
        | Param::FrameRotation(_)
        | Param::FrameTranslation(_) => None,
    }
}

/// The family whose key is `key`.
pub fn family(key: &str) -> Option<&'static dyn Family> {
    FAMILIES.iter().copied().find(|f| f.key() == key)
}

/// Every effect's `--terms` form, comma-separated, for messages.
pub fn usages() -> String {
    FAMILIES
        .iter()
        .map(|f| f.usage())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Every term a diagnosis tries for `dof` joints, family by family.
pub fn vocabulary(dof: usize, thermal: bool) -> Vec<Effect> {
    FAMILIES
        .iter()
        .flat_map(|f| f.vocabulary(dof, thermal))
        .collect()
}

/// One point of the chain, for the Jacobian columns: the arm, its evaluated chain and the
/// reading.
pub struct TipPoint<'a> {
    /// The arm as it measured the reading: its probe mounted (`Arm::for_probe`).
    pub arm: &'a Arm,
    /// The index of that probe among the whole arm's (`crate::fit::probes`): a term of another
    /// probe does not move this ball.
    pub probe: usize,
    /// Its chain at the reading.
    pub chain: &'a Chain,
    /// Joint readings (rad).
    pub theta: &'a [f64],
    /// Temperature (°C).
    pub temp_c: f64,
}

impl TipPoint<'_> {
    /// t_j = a_j × (p − o_j): the ball's motion per radian turned at joint j.
    pub fn turn(&self, j: usize) -> Vector3<f64> {
        self.chain.axes[j].cross(&(self.chain.p - self.chain.origins[j]))
    }

    /// w_c × (p − o_j): the ball's motion per radian of joint j's tilt component `c` (0: δα,
    /// 1: δβ), with w_c the tilt's axis ([`tilt_axis`]) at the joint's tilt at this reading
    /// (the fixed tilt varied by its wobble), in base coordinates.
    pub fn tilt_turn(&self, j: usize, c: usize) -> Vector3<f64> {
        let joint = &self.arm.joints[j];
        let before = if j == 0 {
            Matrix3::identity()
        } else {
            self.chain.rotations[j - 1]
        };
        let w = before * tilt_axis(joint.axis, joint.tilt_at(self.theta[j]), c);
        w.cross(&(self.chain.p - self.chain.origins[j]))
    }

    /// The rotation from the base to the frame after joint j.
    pub fn after(&self, j: usize) -> Matrix3<f64> {
        self.chain.rotations[j]
    }
}

/// "joint J" with J 1-based, or the probe, as messages name a link.
pub fn joint_args(
    item: &str,
    key: &str,
    arg: Option<&&str>,
    dof: usize,
    probe_ok: bool,
) -> Result<Vec<Link>, TermsError> {
    match arg.copied() {
        None => Err(TermsError(format!(
            "`{item}`: which joint? e.g. `{key}:2` or `{key}:*`"
        ))),
        Some("*") => {
            let mut v: Vec<Link> = (0..dof).map(Link::Joint).collect();
            if probe_ok {
                v.push(Link::Probe);
            }
            Ok(v)
        }
        Some("probe") if probe_ok => Ok(vec![Link::Probe]),
        Some(j) => match j.parse::<usize>() {
            Ok(k) if (1..=dof).contains(&k) => Ok(vec![Link::Joint(k - 1)]),
            _ => Err(TermsError(format!(
                "`{item}`: `{j}` is not a joint of this arm (1..={dof}{})",
                if probe_ok { ", probe or *" } else { " or *" }
            ))),
        },
    }
}

/// The order H of a periodic term's `+KEY:J:H`: 1 to the highest a calibration file holds.
pub fn order_arg(item: &str, key: &str, arg: Option<&&str>) -> Result<u32, TermsError> {
    use quatarm_ref::calfile::MAX_HARMONIC_ORDER as MAX_ORDER;
    match arg.map(|s| s.parse::<u32>()) {
        Some(Ok(h)) if (1..=MAX_ORDER).contains(&h) => Ok(h),
        Some(Ok(h)) => Err(TermsError(format!(
            "`{item}`: order {h} is beyond {MAX_ORDER}, the highest a calibration file holds"
        ))),
        _ => Err(TermsError(format!(
            "`{item}`: give the order, e.g. `+{key}:2:1` (joint 2, order 1)"
        ))),
    }
}

/// The terms of a periodic effect's `+KEY:J:H` (joint through [`joint_args`], order through
/// [`order_arg`]), each made by `make(joint, order)`.
pub fn parse_periodic(
    item: &str,
    key: &str,
    args: &[&str],
    dof: usize,
    make: fn(usize, u32) -> Effect,
) -> Result<Vec<Effect>, TermsError> {
    let order = order_arg(item, key, args.get(1))?;
    let links = joint_args(item, key, args.first(), dof, false)?;
    Ok(joints_of(links).map(|joint| make(joint, order)).collect())
}

/// A periodic effect's vocabulary: every joint, orders 1 to `max_order`.
pub fn periodic_vocabulary(
    dof: usize,
    max_order: u32,
    make: fn(usize, u32) -> Effect,
) -> Vec<Effect> {
    (0..dof)
        .flat_map(|joint| (1..=max_order).map(move |order| make(joint, order)))
        .collect()
}

/// The entry of order `order` in a joint's list of periodic terms (`order_of` reads an
/// entry's), appended as `fresh` where the list has none: where a calibration adds to it.
pub fn periodic_entry<T>(
    list: &mut Vec<T>,
    order: u32,
    order_of: fn(&T) -> u32,
    fresh: impl FnOnce() -> T,
) -> &mut T {
    let i = match list.iter().position(|e| order_of(e) == order) {
        Some(i) => i,
        None => {
            list.push(fresh());
            list.len() - 1
        }
    };
    &mut list[i]
}

/// The joints of `+KEY:J` (links other than joints cannot occur: `probe_ok` was false).
pub fn joints_of(links: Vec<Link>) -> impl Iterator<Item = usize> {
    links.into_iter().map(|l| match l {
        Link::Joint(j) => j,
        Link::Probe => 0,
    })
}
