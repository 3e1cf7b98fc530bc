//! What the fuzz targets share: valid calibration tables built from the shipped calibration
//! files, the way `armcal table build` builds them, so that the chain and hub targets start
//! from tables a real hub would boot with.

use std::sync::OnceLock;

use quatarm::{Chain, Fixed, Table, F32};

/// Calibration files the tables are built from: the default arm with and without its full
/// set of terms (6 joints), and two MUKCa arms (7 joints; the Panda with its calibration).
const CALIBRATIONS: [&str; 4] = [
    include_str!("../../data/default-6-full.toml"),
    include_str!("../../data/default-6.toml"),
    include_str!("../../data/mukca/mukca-panda-panda_3-repo-calibrated.toml"),
    include_str!("../../data/mukca/mukca-iiwa14-kuka_14.toml"),
];

/// The binary tables of [`CALIBRATIONS`], built once per process.
pub fn tables() -> &'static [Vec<u8>] {
    static TABLES: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    TABLES.get_or_init(|| {
        CALIBRATIONS
            .iter()
            .map(|text| {
                let arm = quatarm_ref::calfile::parse(text)
                    .expect("a shipped calibration file reads")
                    .arm;
                armcal::tablebuild::build(&arm).expect("a shipped calibration builds a table")
            })
            .collect()
    })
}

/// The f32 and fixed-point chains of each of [`tables`], built once per process (building a
/// chain costs more than decoding a few frames).
pub fn chains() -> &'static [(Chain<F32>, Chain<Fixed>)] {
    static CHAINS: OnceLock<Vec<(Chain<F32>, Chain<Fixed>)>> = OnceLock::new();
    CHAINS.get_or_init(|| {
        tables()
            .iter()
            .map(|t| {
                let t = Table::parse(t).expect("a built table parses");
                (
                    Chain::new(&t).expect("a built table makes an f32 chain"),
                    Chain::new(&t).expect("a built table makes a fixed chain"),
                )
            })
            .collect()
    })
}

/// The table of the shipped calibration with three probes (`data/default-6-probes.toml`: ids
/// 1, 2, 5), built once per process.
pub fn probes_table() -> &'static [u8] {
    static TABLE: OnceLock<Vec<u8>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let arm = quatarm_ref::calfile::parse(include_str!("../../data/default-6-probes.toml"))
            .expect("the three-probe calibration reads")
            .arm;
        armcal::tablebuild::build(&arm).expect("the three-probe calibration builds a table")
    })
}
