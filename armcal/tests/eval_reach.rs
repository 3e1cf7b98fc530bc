//! Issue 15, D4: an arm that reaches 2.3 m (`c-reach-2p3m.toml`, copied from the session's
//! reproducers). The f32 evaluator used to print 2147.483647 mm, the end of the stream's i32
//! nanometre range, for its 2300 mm straight up; now the firmware paths refuse the arm with an
//! error naming the file and the limit, and print nothing, while f64 evaluates it.

// The suites' shared helpers; this one needs only the runners.
#[allow(dead_code)]
mod common;
use common::{armcal, armcal_ok, workdir};
use std::path::Path;

fn data(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
        .display()
        .to_string()
}

#[test]
fn an_arm_beyond_the_streams_range_is_refused_not_clipped() {
    let dir = workdir("reach");
    let (calib, up) = (data("c-reach-2p3m.toml"), data("e-up.csv"));
    for precision in ["f32", "fixed"] {
        let o = armcal(
            &["eval", "--calib", &calib, "--precision", precision, &up],
            &dir,
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{precision}: {err}");
        assert!(o.stdout.is_empty(), "{precision}: partial output");
        assert!(err.contains("c-reach-2p3m.toml"), "{precision}: {err}");
        assert!(err.contains("2300.0 mm"), "{precision}: {err}");
        assert!(err.contains("2064 mm"), "{precision}: {err}");
    }
    let o = armcal_ok(
        &["eval", "--calib", &calib, "--precision", "f64", &up],
        &dir,
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.lines().nth(1).unwrap().contains(",2300.000000000,"),
        "{out}"
    );
}
