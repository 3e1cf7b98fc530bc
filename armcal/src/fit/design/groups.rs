//! Groups of rows around one fixed point, as an arm records them: a `spat` cone probed from
//! several poses, a ball bar's two ends, each row taken with the probes in turn (`Turns`).
//! With no noise they are the design's groups; with noise, the simulation's.

use super::poses::{probe_point, random_pose, Limits};
use crate::data::{Dataset, End, Kind, Row};
use crate::rng::{normal, SimRng};
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

/// The probes a simulation takes rows with, in turn, and the arm as each measures.
pub(crate) struct Turns<'a> {
    turns: Vec<(Option<u8>, std::borrow::Cow<'a, Arm>)>,
}

impl<'a> Turns<'a> {
    /// The probes `ids` of `truth` (the first alone, with no id, for none).
    /// The probes `ids` of `truth` (the first alone, with no id, for none); `Err` names an id
    /// the arm does not carry.
    pub(crate) fn new(truth: &'a Arm, ids: &[u8]) -> Result<Turns<'a>, u8> {
        if ids.is_empty() {
            return Ok(Turns {
                turns: vec![(None, std::borrow::Cow::Borrowed(truth))],
            });
        }
        let turns = ids
            .iter()
            .map(|&id| {
                truth
                    .probe_index(id)
                    .and_then(|k| truth.for_probe(k))
                    .map(|a| (Some(id), a))
                    .ok_or(id)
            })
            .collect::<Result<_, _>>()?;
        Ok(Turns { turns })
    }

    /// The probes of the rows of `like` (the design of a calibration: identifiability must
    /// see every probe the data has, the first too where rows leave the probe cell empty),
    /// in ascending order of id; the first alone, with no id, where the data use no other.
    pub(crate) fn like(arm: &'a Arm, like: &Dataset) -> Turns<'a> {
        let used = crate::fit::probes::used(arm, like);
        if used == [0] {
            return Turns {
                turns: vec![(None, std::borrow::Cow::Borrowed(arm))],
            };
        }
        let mut turns: Vec<_> = used
            .into_iter()
            .filter_map(|k| Some((Some(arm.probe_at(k)?.id), arm.for_probe(k)?)))
            .collect();
        turns.sort_unstable_by_key(|t| t.0);
        Turns { turns }
    }

    /// The `i`-th turn's id and arm.
    pub(crate) fn at(&self, i: usize) -> (Option<u8>, &Arm) {
        let (id, arm) = &self.turns[i % self.turns.len()];
        (*id, arm)
    }
}

/// A cone probed `size` times, the rows taking the probes in turn (how the probes' vectors
/// are told apart: each puts its ball in the same cone).
pub(crate) fn spat_group(
    turns: &Turns,
    lim: &Limits,
    size: usize,
    noise_mm: f64,
    group: i64,
    temp: &mut dyn FnMut(&mut SimRng) -> f64,
    rng: &mut SimRng,
) -> Option<Vec<Row>> {
    let truth = turns.at(0).1;
    'placement: for _ in 0..20 {
        let centre = forward::forward(truth, &random_pose(lim, rng), forward::REFERENCE_TEMP_C).p;
        let mut rows = Vec::with_capacity(size);
        for i in 0..size {
            let (probe, mounted) = turns.at(i);
            let tc = temp(rng);
            let Some(th) = probe_point(mounted, lim, &centre, noise_mm, tc, rng) else {
                continue 'placement;
            };
            let mut r = row(Kind::Spat, group, &th, None, tc);
            r.probe = probe;
            rows.push(r);
        }
        return Some(rows);
    }
    None
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn length_group(
    turns: &Turns,
    lim: &Limits,
    size: usize,
    bar: f64,
    noise_mm: f64,
    group: i64,
    temp: &mut dyn FnMut(&mut SimRng) -> f64,
    rng: &mut SimRng,
) -> Option<Vec<Row>> {
    let na = size.div_ceil(2);
    let truth = turns.at(0).1;
    'placement: for _ in 0..40 {
        let a = forward::forward(truth, &random_pose(lim, rng), forward::REFERENCE_TEMP_C).p;
        let dir = Vector3::new(normal(rng), normal(rng), normal(rng)).normalize();
        let b = a + dir * bar;
        let mut rows = Vec::with_capacity(size);
        for i in 0..size {
            let (end, centre) = if i < na { (End::A, &a) } else { (End::B, &b) };
            let (probe, mounted) = turns.at(i);
            let tc = temp(rng);
            let Some(th) = probe_point(mounted, lim, centre, noise_mm, tc, rng) else {
                continue 'placement;
            };
            let mut r = row(Kind::Length, group, &th, Some(end), tc);
            r.length_mm = Some(bar);
            r.probe = probe;
            rows.push(r);
        }
        return Some(rows);
    }
    None
}

/// A row at the continuous true angles: the caller reads them through the encoders.
pub(crate) fn row(kind: Kind, group: i64, th: &[f64], end: Option<End>, tc: f64) -> Row {
    Row {
        kind,
        group,
        theta: th.to_vec(),
        xyz: None,
        end,
        length_mm: None,
        sphere: None,
        temp_c: tc,
        probe: None,
        line: 0,
        file: None,
    }
}
