//! Several probes (issue 14): data that say which probe each row used, a calibration that
//! fits every probe's error beside the arm's geometry, and the refusals of data that name a
//! probe the arm lacks.

mod common;

use armcal::data::Kind;
use armcal::fit::calib::calibrate;
use armcal::fit::design::poses::{limits, random_pose};
use armcal::fit::options::Options;
use armcal::rng::rng;
use armcal::sim::{self, perturb, simulate};
use common::{armcal, armcal_ok, workdir, write_truth};
use nalgebra::Vector3;
use quatarm_ref::arm::{Arm, Probe};
use quatarm_ref::forward;

/// `default-6` with three probes: the 120 mm stylus (id 0), a 250 mm extension (id 3) and a
/// bent stylus (id 7), each with a small ball.
fn nominal() -> Arm {
    let mut a = Arm::default6();
    a.probe.ball_diameter = 6.0;
    let probe = |id, vector, ball_diameter| Probe {
        id,
        vector,
        error: [0.0; 3],
        thermal: 0.0,
        ball_diameter,
    };
    a.more_probes = vec![
        probe(3, [0.0, 0.0, 250.0], 3.0),
        probe(7, [60.0, 0.0, 100.0], 2.0),
    ];
    a
}

/// The nominal arm with random geometric errors and each probe off by a few tenths of a mm.
fn truth(seed: u64) -> Arm {
    let mut t = perturb(&nominal(), 3e-4, 0.3, &mut rng(seed));
    let offsets = [[0.21, -0.14, 0.33], [-0.4, 0.25, -0.18], [0.12, 0.31, 0.27]];
    for (k, e) in offsets.iter().enumerate() {
        t.probe_at_mut(k).unwrap().error = *e;
    }
    t
}

/// Each probe's ball centre, fitted against true, over fresh poses: RMS (µm) per probe, after
/// the best rigid alignment of the first probe's (the data's frame is the fit's own).
fn fresh_rms_um(fit: &Arm, truth: &Arm) -> Vec<f64> {
    let lim = limits(truth);
    let mut r = rng(99);
    let poses: Vec<Vec<f64>> = (0..2000).map(|_| random_pose(&lim, &mut r)).collect();
    let tips = |a: &Arm, k: usize| -> Vec<Vector3<f64>> {
        let m = a.for_probe(k).unwrap();
        poses
            .iter()
            .map(|th| forward::forward(&m, th, 20.0).p)
            .collect()
    };
    let frame = armcal::fit::residuals::best_rigid(&tips(fit, 0), &tips(truth, 0));
    (0..truth.probe_count())
        .map(|k| {
            let (f, t) = (tips(fit, k), tips(truth, k));
            let ss: f64 = f
                .iter()
                .zip(&t)
                .map(|(a, b)| (frame.apply(a) - b).norm_squared())
                .sum();
            (ss / f.len() as f64).sqrt() * 1e3
        })
        .collect()
}

/// Point rows taken with the three probes in turn: the calibration fits every probe's error
/// with the geometry, and each probe's ball is right on fresh poses.
#[test]
fn point_data_of_three_probes_calibrate_each_probe() {
    let truth = truth(5);
    let mut o = sim::Options::new(Kind::Point, 450);
    o.probes = vec![0, 3, 7];
    let data = simulate(&truth, &o, &mut rng(6)).unwrap().data;
    assert_eq!(
        data.rows.iter().filter(|r| r.probe == Some(7)).count(),
        150,
        "the rows take the probes in turn"
    );
    let fit = calibrate(&nominal(), &data, &Options::default()).unwrap();
    let fitted: Vec<String> = fit.params.iter().map(|p| p.to_string()).collect();
    for key in ["probe.error[0]", "probe[2].error[1]", "probe[3].error[2]"] {
        assert!(fitted.iter().any(|k| k == key), "{key} in {fitted:?}");
    }
    let before = fresh_rms_um(&nominal(), &truth);
    let after = fresh_rms_um(&fit.arm, &truth);
    println!("fresh poses, RMS µm per probe: before {before:.1?}, after {after:.2?}");
    for (k, rms) in after.iter().enumerate() {
        assert!(*rms < 5.0, "probe index {k}: {rms} µm");
    }
    // A probe's own vector trades with the last link's (a shift of both along it moves no
    // ball) and with the last frame's turn (joint 6's tilt and zero offset turn every probe
    // alike), but the distance between two probes' balls is the data's.
    let apart = |a: &Arm, k: usize| {
        (Vector3::from(a.probe_at(k).unwrap().actual()) - Vector3::from(a.probe.actual())).norm()
    };
    for k in 1..3 {
        let err_um = (apart(&fit.arm, k) - apart(&truth, k)).abs() * 1e3;
        println!("ball {k} from the first's: off by {err_um:.2} µm");
        assert!(err_um < 5.0, "{err_um}");
    }
}

/// Without the `probe` column the rows of the other probes would be taken as the first's:
/// the same data fitted that way miss by millimetres, which is what the column is for.
#[test]
fn ignoring_which_probe_was_used_fails_by_millimetres() {
    let truth = truth(8);
    let mut o = sim::Options::new(Kind::Spat, 240);
    o.probes = vec![0, 3, 7];
    let mut data = simulate(&truth, &o, &mut rng(9)).unwrap().data;
    let mut l = sim::Options::new(Kind::Length, 60);
    l.probes = vec![0];
    let bars = simulate(&truth, &l, &mut rng(10)).unwrap().data;
    let first = data.rows.iter().map(|r| r.group).max().unwrap();
    data.rows.extend(bars.rows.into_iter().map(|mut r| {
        r.group += first;
        r
    }));
    let with = calibrate(&nominal(), &data, &Options::default()).unwrap();
    let after = fresh_rms_um(&with.arm, &truth);
    println!("spat + bar, each probe's ball on fresh poses (µm): {after:.2?}");
    for rms in &after {
        assert!(*rms < 20.0, "{after:?}");
    }
    for r in &mut data.rows {
        r.probe = None;
    }
    let blind = calibrate(&nominal(), &data, &Options::default());
    let sigma_um = blind.map_or(f64::INFINITY, |f| f.sigma_mm * 1e3);
    println!("the same rows as one probe: sigma {sigma_um:.0} µm");
    assert!(sigma_um > 1000.0, "{sigma_um}");
}

/// The command line: `simulate --probes`, `calibrate` writing `[[probe]]`, `eval` with a
/// `probe` column; data naming a probe the arm lacks is refused with its line and column.
#[test]
fn the_cli_carries_the_probe_from_data_to_file_to_eval() {
    let dir = workdir("calib_probes");
    write_truth(&dir, &truth(11));
    std::fs::write(
        dir.join("nominal.toml"),
        quatarm_ref::calfile::write(&nominal(), &[]),
    )
    .unwrap();
    common::simulate(
        &dir,
        "point",
        "300",
        "3",
        &["--probes", "0,3,7"],
        "data.csv",
    );
    let text = std::fs::read_to_string(dir.join("data.csv")).unwrap();
    assert!(
        text.lines().any(|l| l.ends_with(",probe")),
        "a probe column"
    );
    armcal_ok(
        &[
            "calibrate",
            "data.csv",
            "--arm",
            "nominal.toml",
            "-o",
            "cal.toml",
        ],
        &dir,
    );
    let cal = quatarm_ref::calfile::read(&dir.join("cal.toml"))
        .unwrap()
        .arm;
    assert_eq!(cal.probes().map(|p| p.id).collect::<Vec<_>>(), [0, 3, 7]);
    // Eval with each probe against the truth.
    let input = "j1,j2,j3,j4,j5,j6,probe\n0.1,0.5,0.2,-0.7,0.3,0.4,3\n0.1,0.5,0.2,-0.7,0.3,0.4,\n";
    std::fs::write(dir.join("in.csv"), input).unwrap();
    let out = armcal_ok(&["eval", "--calib", "cal.toml", "in.csv"], &dir);
    let rows: Vec<Vec<f64>> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let extension = (Vector3::new(rows[0][0], rows[0][1], rows[0][2])
        - Vector3::new(rows[1][0], rows[1][1], rows[1][2]))
    .norm();
    assert!((extension - 130.0).abs() < 1.5, "{extension}");
    // A probe the arm lacks: refused, naming line and column.
    let bad = text.replacen(",3\n", ",9\n", 1);
    std::fs::write(dir.join("bad.csv"), &bad).unwrap();
    let o = armcal(
        &[
            "calibrate",
            "bad.csv",
            "--arm",
            "nominal.toml",
            "-o",
            "x.toml",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("column probe") && err.contains("probe 9") && err.contains("0, 3, 7"),
        "{err}"
    );
    assert!(!dir.join("x.toml").exists(), "no partial output");
    let o = armcal(&["eval", "--calib", "cal.toml", "bad.csv"], &dir);
    assert!(!o.status.success());
}

/// A sphere is touched with one stylus ball: a group touched with two probes is refused by
/// the data reader, naming the line.
#[test]
fn a_sphere_group_touched_with_two_probes_is_refused() {
    let text = "kind,group,j1,j2,j3,j4,j5,j6,diameter_mm,probe\n\
                sphere,1,0,0,0,0,0,0,25,3\n\
                sphere,1,0,0.1,0,0,0,0,25,3\n\
                sphere,1,0,0.2,0,0,0,0,25,7\n";
    let e = armcal::data::parse(text, "s.csv", 6).unwrap_err();
    assert_eq!((e.line, e.column.as_str()), (4, "probe"), "{e}");
    assert!(e.message.contains("two probes"), "{e}");
    let e = armcal::data::parse(&text.replace(",7\n", ",300\n"), "s.csv", 6).unwrap_err();
    assert_eq!((e.line, e.column.as_str()), (4, "probe"), "{e}");
}
