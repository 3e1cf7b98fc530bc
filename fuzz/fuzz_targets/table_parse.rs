//! The binary table parser (`quatarm::table`): any bytes in flash are refused with an error or
//! accepted as a table whose every value is inside the table's limits, which re-encodes to the
//! same values (to the same bytes in the current format; the parameter block's pose part
//! and its joint leverage with it), and from which both chains build or refuse cleanly. Never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quatarm::table::joint_leverage::JointLeverageData;
use quatarm::table::parameters::{Column, ParameterData};
use quatarm::table::pose::PoseData;
use quatarm::uncertainty::Uncertainty;
use quatarm::{Chain, ChainError, Fixed, MatrixChain, Table, F32};

fuzz_target!(|bytes: &[u8]| {
    let Ok(table) = Table::parse(bytes) else {
        return;
    };
    // An accepted table reads back and re-encodes to the same bytes, its budget and
    // parameter block with it.
    let data = table.data();
    let budget = table.budget().map(|b| b.data());
    let block = table.parameters().map(|p| {
        let columns: Vec<Column> = (0..p.count())
            .map(|i| p.column(i).expect("an accepted block's records read back"))
            .collect();
        let factor: Vec<f32> = (0..p.count())
            .flat_map(|i| p.factor_row(i).chunks_exact(4))
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        // The budget's pose part (issue 27), where the block has one.
        let pose = p.pose().map(|pose| {
            let d: Vec<f32> = pose
                .factor()
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            // Its joint leverage (μ, W's upper triangle), where it has one.
            let joints = pose.joints().map(|j| {
                let k = j.count();
                let mean: Vec<f32> = (0..k)
                    .map(|i| j.mean(i).expect("an accepted part's means read back"))
                    .collect();
                let weight: Vec<f32> = (0..k)
                    .flat_map(|a| (a..k).map(move |b| (a, b)))
                    .map(|(a, b)| j.weight(a, b).expect("an accepted part's W reads back"))
                    .collect();
                (mean, weight)
            });
            (d, pose.count(), pose.shrink(), pose.leverage_mean(), joints)
        });
        (columns, factor, pose)
    });
    let parameters = block.as_ref().map(|(columns, factor, pose)| ParameterData {
        columns,
        factor,
        pose: pose
            .as_ref()
            .map(|(d, count, shrink, leverage_mean, joints)| PoseData {
                factor: d,
                count: *count,
                shrink: *shrink,
                leverage_mean: *leverage_mean,
                joints: joints
                    .as_ref()
                    .map(|(mean, weight)| JointLeverageData { mean, weight }),
            }),
    });
    let mut out = vec![0u8; quatarm::table::MAX_TABLE_LEN];
    let n = data
        .encode_full(budget.as_ref(), parameters.as_ref(), &mut out)
        .expect("an accepted table re-encodes");
    // A table of the current format re-encodes to its own bytes; an older one (format 3,
    // read as calibration number 0 with no date) re-encodes in the current format, whose
    // values are the same.
    if table.version() == quatarm::table::VERSION {
        assert_eq!(
            &out[..n],
            &bytes[..n],
            "re-encoding an accepted table changed it"
        );
    }
    assert_eq!(Table::parse(&out[..n]).map(|t| t.data()), Ok(data));
    if let Ok(mut chain) = Chain::<F32>::new(&table) {
        mounts_each(&table, "an f32", |k| chain.mount(&table, k));
    }
    if let Ok(mut chain) = Chain::<Fixed>::new(&table) {
        mounts_each(&table, "a fixed", |k| chain.mount(&table, k));
    }
    if let Ok(mut chain) = MatrixChain::<F32>::new(&table) {
        mounts_each(&table, "a matrix", |k| chain.mount(&table, k));
    }
    let _ = MatrixChain::<Fixed>::new(&table);
    // And its uncertainty builds or refuses cleanly, and never panics on a reading.
    if let (Ok(Some(u)), Ok(chain)) = (Uncertainty::<F32>::new(&table), Chain::<F32>::new(&table)) {
        let counts: Vec<u32> = (0..table.joint_count())
            .map(|i| table.joint(i).map_or(0, |j| j.counts / 3))
            .collect();
        if chain.eval(&counts, 21_000).is_ok() {
            let _ = u.covariance(&counts, 21_000);
        }
    }
});

/// A chain built from `table` mounts each of its probes (the reach was checked with the
/// longest) and none past them.
fn mounts_each(
    table: &Table<'_>,
    chain: &str,
    mut mount: impl FnMut(usize) -> Result<(), ChainError>,
) {
    for k in 0..table.probe_count() {
        if let Err(e) = mount(k) {
            panic!("{chain} chain does not mount its table's probe {k}: {e:?}");
        }
    }
    assert!(
        mount(table.probe_count()).is_err(),
        "{chain} chain mounts a probe past its table's"
    );
}
