//! A small, well-spread, noise-free design of the same kinds as the data ([`design_like`]):
//! what identifiability reaches with good poses, which the structure check compares the data
//! with to tell a degenerate pose set from a limit of the data's kinds.
//!
//! Its generators are the virtual arm's: poses and the numeric inverse ([`poses`]), `spat`
//! and bar groups ([`groups`]), `sphere` groups ([`sphere`]). They live here, below the
//! simulation (`crate::sim`), which builds on them adding noise, encoders and an instrument,
//! so that the fit needs nothing above its own layer.

pub mod groups;
pub mod poses;
pub mod sphere;

use crate::data::{Dataset, Kind, Row};
use crate::rng::{rng, SimRng};
use groups::{length_group, spat_group, Turns};
use poses::{limits, quantise, random_pose};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

/// A small, well-spread, noise-free data set of the same kinds (and temperatures) as `like`,
/// made with `arm`: what identifiability can reach with good poses, to tell a degenerate pose
/// set from a structural limit of the data's kinds.
pub fn design_like(arm: &Arm, like: &Dataset, seed: u64) -> Dataset {
    let mut rng = rng(seed);
    let temps: Vec<f64> = like.rows.iter().map(|r| r.temp_c).collect();
    let lim = limits(arm);
    let mut k = 0usize;
    let mut next_temp = |_: &mut SimRng| {
        k += 1;
        temps[(k * 7919) % temps.len()]
    };
    let turns = Turns::like(arm, like);
    let mut rows = Vec::new();
    if like.rows.iter().any(|r| r.kind == Kind::Point) {
        for i in 0..150 {
            let (probe, mounted) = turns.at(i);
            let th = random_pose(&lim, &mut rng);
            let tc = next_temp(&mut rng);
            let p = forward::forward(mounted, &th, tc).p;
            rows.push(Row::point(0, th, [p.x, p.y, p.z], tc, probe));
        }
    }
    if like.rows.iter().any(|r| r.kind == Kind::Spat) {
        for g in 0..6 {
            if let Some(made) = spat_group(&turns, &lim, 6, 0.0, 1000 + g, &mut next_temp, &mut rng)
            {
                rows.extend(made);
            }
        }
    }
    let bars: Vec<f64> = like.layout().length.iter().map(|g| g.length_mm).collect();
    for (g, bar) in bars
        .iter()
        .cycle()
        .take(if bars.is_empty() { 0 } else { 6 })
        .enumerate()
    {
        if let Some(made) = length_group(
            &turns,
            &lim,
            6,
            *bar,
            0.0,
            2000 + g as i64,
            &mut next_temp,
            &mut rng,
        ) {
            rows.extend(made);
        }
    }
    let spheres: Vec<f64> = like.layout().sphere.iter().map(|g| g.diameter_mm).collect();
    for (g, d) in spheres
        .iter()
        .cycle()
        .take(if spheres.is_empty() { 0 } else { 6 })
        .enumerate()
    {
        let test = sphere::Test {
            points: 25,
            diameter_mm: *d,
            articulations: None,
            noise_mm: 0.0,
        };
        if let Some(made) = sphere::group(
            turns.at(g),
            &lim,
            &test,
            3000 + g as i64,
            &mut next_temp,
            &mut rng,
        ) {
            rows.extend(made);
        }
    }
    // Spat, length and sphere rows are read by the encoders, as `simulate` records them (point rows
    // of the design keep their continuous angles).
    for r in rows.iter_mut().filter(|r| r.kind != Kind::Point) {
        r.theta = quantise(arm, &r.theta);
    }
    Dataset {
        rows,
        dof: arm.dof(),
        has_temperature: like.has_temperature,
        warnings: Vec::new(),
        source: "(design)".into(),
    }
}
