//! The one table of `cargo xtask bench-target` that puts the product's chains on qemu-m4f, the
//! C baselines and the counted floor side by side: instructions a point over the same
//! recorded readings, flash, and accuracy against the f64 reference on those readings.

use super::{accuracy, Accuracy, Outcome};
use anyhow::Result;
use quatarm::stream::Reading;
use quatarm::{Chain, MatrixChain, Point, Table, F32};
use quatarm_ref::arm::Arm;

/// The product's chains on one qemu-m4f build.
pub struct Product {
    /// Compiler of the image.
    pub compiler: String,
    /// Flash of the whole hub image.
    pub flash: u64,
    /// Instructions a point: the hub's chain, the quaternion chain, the 3×4 matrix chain.
    pub chains: (f64, f64, f64),
    /// Whether the hub's chain is the lean form.
    pub lean: bool,
    /// The hub's chain with an axis wobble on every joint (its calibration file; instructions
    /// a point; whether it ran the lean form), if measured.
    pub wobble: Option<(String, f64, bool)>,
    /// U95 as the hub streams it, a point.
    pub u95: Option<f64>,
}

/// The product's chains evaluated on the host (the same code; no fused multiply–add, so the
/// host's f32 results are the hub's) on `readings`, against the reference: the hub's chain,
/// the quaternion chain, the 3×4 matrix chain.
pub fn product_accuracy(arm: &Arm, readings: &[Reading]) -> Result<[Accuracy; 3]> {
    let bytes = quatarm_wire::tablebuild::build(arm)?;
    let table = Table::parse(&bytes)?;
    let chain = Chain::<F32>::new(&table)?;
    let matrix = MatrixChain::<F32>::new(&table)?;
    let six = |p: Result<Point<F32>, _>| {
        p.ok().map(|p: Point<F32>| {
            let (x, d) = (p.xyz_f64(), p.dir_f64());
            [x[0], x[1], x[2], d[0], d[1], d[2]]
        })
    };
    let of =
        |f: &dyn Fn(&Reading) -> Option<[f64; 6]>| accuracy(arm, readings, readings.iter().map(f));
    Ok([
        of(&|r| six(chain.eval(r.counts.as_slice(), r.temp_mc))),
        of(&|r| six(chain.eval_quaternion(r.counts.as_slice(), r.temp_mc))),
        of(&|r| six(matrix.eval(r.counts.as_slice(), r.temp_mc))),
    ])
}

fn acc(a: &Accuracy) -> String {
    let refused = if a.refused > 0 {
        format!(" ({} refused)", a.refused)
    } else {
        String::new()
    };
    format!("{:.3} / {:.3}{refused}", a.tip_max_um, a.tip_rms_um)
}

/// The table, as markdown, with its notes.
pub fn render(
    products: &[(Product, [Accuracy; 3], Option<Accuracy>)],
    c: &Outcome,
    gcc: &str,
    floor: (u32, u32),
    points: usize,
) -> String {
    let mut s = format!(
        "| chain (qemu-m4f, Cortex-M4F) | compiler | instructions / point | flash (bytes) | tip max / RMS µm over the {points} readings |\n|---|---|---|---|---|\n"
    );
    for (p, a, wa) in products {
        let (h, q, m) = p.chains;
        let form = if p.lean { "lean" } else { "quaternion" };
        let rows = [
            (format!("quatarm hub's chain ({form})"), h, &a[0]),
            ("quatarm f32 quaternion chain".to_string(), q, &a[1]),
            ("quatarm f32 3×4 matrix chain".to_string(), m, &a[2]),
        ];
        for (label, n, a) in rows {
            s.push_str(&format!(
                "| {label} | {} | {n:.0} | {} (hub image) | {} |\n",
                p.compiler,
                p.flash,
                acc(a)
            ));
        }
        if let Some((file, n, lean)) = &p.wobble {
            let a = wa.as_ref().map_or("–".into(), acc);
            let form = if *lean { "lean" } else { "quaternion" };
            // Issue 32 asks for the wobble chain within 1.4× of the hub's chain without it.
            s.push_str(&format!(
                "| quatarm hub's chain ({form}) with an axis wobble on every joint ({file}) | {} | {n:.0} ({:.2}× the hub's chain without it) | (same image) | {a} |\n",
                p.compiler,
                n / h
            ));
        }
        if let Some(u) = p.u95 {
            s.push_str(&format!(
                "| quatarm U95 as streamed (after the chain) | {} | {u:.0} | (same image) | – |\n",
                p.compiler
            ));
        }
    }
    match c {
        Outcome::Measured(rows) => {
            for r in rows {
                s.push_str(&format!(
                    "| {} | {gcc} | {:.0} | {} (chain_eval {} B) | {} |\n",
                    r.chain.label(),
                    r.instructions,
                    r.flash,
                    r.code,
                    acc(&r.accuracy)
                ));
            }
        }
        Outcome::Skipped(why) => s.push_str(&format!("| {why} | | | | |\n")),
    }
    s.push_str(&format!(
        "| counted floor of the C lean form (its floating-point operations, a multiply–add as one; with the fewest loads and integer work) | – | {} FP, ~{} in all | – | – |\n",
        floor.0, floor.1
    ));
    s
}
