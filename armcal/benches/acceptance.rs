//! Which acceptance test sees which hidden effect: prints the table of
//! `docs/results/acceptance.md`.
//!
//! `cargo bench -p armcal --bench acceptance`. For each hidden effect, a virtual arm (random
//! geometric errors plus the effect) is calibrated with the geometric model from 600 `point`
//! readings (5 µm instrument noise, 16–28 °C), then the ISO 10360-12 test set of
//! `armcal simulate --test iso10360-12` is recorded on it (5 µm probing noise, the same
//! temperatures) and every statistic computed twice: with the true model (what the noise and
//! quantisation alone give) and with the calibrated geometric one (what the effect adds).

use armcal::acceptance::{self, statistics::Test};
use armcal::data::Kind;
use armcal::fit::calib::calibrate;
use armcal::fit::options::Options;
use armcal::rng::rng;
use armcal::sim::{self, perturb, protocol};
use quatarm_ref::arm::{Arm, Harmonic};

/// Adds one hidden effect to a truth arm.
type AddEffect = Box<dyn Fn(&mut Arm)>;

fn effects() -> Vec<(&'static str, AddEffect)> {
    vec![
        ("none", Box::new(|_: &mut Arm| {})),
        (
            "harmonic j2 order 1, 20 µrad",
            Box::new(|a: &mut Arm| {
                a.joints[1].harmonics = vec![Harmonic {
                    order: 1,
                    sin: 2e-5,
                    cos: 0.0,
                }]
            }),
        ),
        (
            "harmonic j2 order 3, 20 µrad",
            Box::new(|a: &mut Arm| {
                a.joints[1].harmonics = vec![Harmonic {
                    order: 3,
                    sin: 2e-5,
                    cos: 0.0,
                }]
            }),
        ),
        (
            "gravity j2, 1.3e-6 rad/mm",
            Box::new(|a: &mut Arm| a.joints[1].gravity = 1.3e-6),
        ),
        (
            "thermal link 2, 23e-6 /°C",
            Box::new(|a: &mut Arm| a.joints[1].thermal = 23e-6),
        ),
    ]
}

fn main() {
    let nominal = Arm::default6();
    println!("| hidden effect | model | P_Size | P_Form | L_Dia | E_Uni | SPAT_max | SPAT_2s |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, add) in effects() {
        let mut truth = perturb(&nominal, 3e-4, 0.3, &mut rng(21));
        add(&mut truth);
        let mut o = sim::Options::new(Kind::Point, 600);
        o.temp = Some((16.0, 28.0));
        let points = sim::simulate(&truth, &o, &mut rng(22))
            .expect("points")
            .data;
        let fit = calibrate(&nominal, &points, &Options::default()).expect("calibration");
        let tests = protocol::iso_10360_12(&truth, &o, &mut rng(23))
            .expect("test set")
            .data;
        for (model, arm) in [("true", &truth), ("calibrated geometric", &fit.arm)] {
            let c = acceptance::check(arm, &tests, None, None, false).expect("check");
            let cells: Vec<String> = Test::ALL
                .iter()
                .map(|t| format!("{:.1}", c.results[t.key()]))
                .collect();
            println!("| {name} | {model} | {} |", cells.join(" | "));
        }
    }
    println!("(µm; the worst group of each test)");
}
