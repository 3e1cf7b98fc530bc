//! Test fixtures of the update: a layout on the mock flash, real tables, the steps that send
//! one, and a boot.

use std::vec::Vec;

use super::boot::Accept;
use super::layout::Layout;
use super::mock::MockFlash;
use super::session::{Accepted, Step, Updater};
use super::{live_table, Refusal};
use crate::table::budget::BudgetData;
use crate::table::{quat_to_matrix, JointData, ProbeData, Release, TableData, MAX_TABLE_LEN};

/// Bytes of the mock flash that [`layout`] divides.
pub const FLASH_LEN: usize = 9 * 1024;

/// Two 3 KiB slots (the largest table without a parameter block, 2,448 bytes with eight
/// probes, fits one) and two 1 KiB copies of the state record, in 1 KiB erase units.
pub fn layout() -> Layout {
    Layout::Regions {
        slots: [0..3072, 3072..6144],
        state: [6144..7168, 7168..8192],
    }
}

/// The same slots with the state record in their trailers (the last 28 bytes of each).
pub fn trailer_layout() -> Layout {
    Layout::Trailers {
        slots: [0..3072, 3072..6144],
    }
}

/// Both layouts, the four-region one first.
pub fn layouts() -> [Layout; 2] {
    [layout(), trailer_layout()]
}

/// A valid table of a nominal six-joint arm whose links are `link` mm long.
pub fn table(link: f64) -> Vec<u8> {
    encoded(link, None)
}

/// [`table`] with an uncertainty budget (80 bytes more), as `armcal calibrate` writes it.
pub fn table_with_budget(link: f64) -> Vec<u8> {
    encoded(link, Some(&budget()))
}

/// The fixtures' budget: one count on each joint, 2 µm of probing, 1 µm of model, 0.2 °C.
fn budget() -> BudgetData {
    BudgetData {
        encoder_counts: [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0],
        probing_mm: 0.002,
        model_mm: 0.001,
        temperature_c: 0.2,
    }
}

/// [`table_with_budget`] with the blocks a board profile decides on (issue 32): an axis
/// wobble on joint 2 (one first-order term of 20 µrad) and a parameter block of three
/// parameters (joint 1's turn, joint 3's first cosine harmonic, a shift of joint 5). A hub
/// whose `quatarm` has the features `wobble` and `parameters` (the Pico's profile) takes it;
/// one without either (qemu-m0's minimal profile) refuses it by its flags.
pub fn table_with_blocks(link: f64) -> Vec<u8> {
    use crate::table::parameters::{Column, Kind, ParameterData};
    use crate::table::wobble::{WobbleData, WobbleTerm};
    let mut data = arm(link, 1 << 14, Release::default());
    data.wobble[1] = WobbleData {
        f1: [1.0, 0.0, 0.0],
        f2: [0.0, 1.0, 0.0],
        count: 1,
        terms: [
            WobbleTerm {
                order: 1,
                alpha: [2e-5, 0.0],
                beta: [0.0, -1e-5],
            },
            WobbleTerm::default(),
            WobbleTerm::default(),
            WobbleTerm::default(),
        ],
    };
    let columns = [
        Column::new(Kind::Turn, 0),
        Column {
            order: 1,
            ..Column::new(Kind::TurnCos, 2)
        },
        Column {
            vector: [0.0, 0.0, 1.0],
            w0: 1.0,
            ..Column::new(Kind::Shift, 4)
        },
    ];
    // L: 10 µrad, 2 µrad and 1 µm standard deviations, the first two correlated.
    let factor = [1e-5, 3e-6, 2e-6, 0.0, 0.0, 1e-3];
    let block = ParameterData {
        columns: &columns,
        factor: &factor,
        pose: None,
    };
    let mut bytes = [0u8; MAX_TABLE_LEN];
    let len = data
        .encode_full(Some(&budget()), Some(&block), &mut bytes)
        .expect("fixture table encodes");
    bytes[..len].to_vec()
}

/// [`table`] for encoders of `counts` per revolution (the others have 2^14).
pub fn table_for_encoders(link: f64, counts: u32) -> Vec<u8> {
    encoded_with(link, None, counts)
}

/// [`table`] of calibration number `number` (dated 2026-12-04).
pub fn numbered(link: f64, number: u32) -> Vec<u8> {
    encoded_release(
        link,
        None,
        1 << 14,
        Release {
            number,
            date: 20261204,
        },
    )
}

fn encoded(link: f64, budget: Option<&BudgetData>) -> Vec<u8> {
    encoded_with(link, budget, 1 << 14)
}

fn encoded_with(link: f64, budget: Option<&BudgetData>, counts: u32) -> Vec<u8> {
    encoded_release(link, budget, counts, Release::default())
}

fn encoded_release(
    link: f64,
    budget: Option<&BudgetData>,
    counts: u32,
    release: Release,
) -> Vec<u8> {
    let data = arm(link, counts, release);
    let mut bytes = [0u8; MAX_TABLE_LEN];
    let len = data
        .encode_with(budget, &mut bytes)
        .expect("fixture table encodes");
    bytes[..len].to_vec()
}

/// The fixture arm: six joints about z, links of `link` mm along x, the probe 50 mm along z.
fn arm(link: f64, counts: u32, release: Release) -> TableData {
    let mut data = TableData {
        joint_count: 6,
        release,
        ..TableData::default()
    };
    data.serial[..4].copy_from_slice(b"SN-9");
    let identity = [1.0, 0.0, 0.0, 0.0];
    for joint in &mut data.joints[..6] {
        *joint = JointData {
            axis: 2,
            counts,
            rotation: identity,
            matrix: quat_to_matrix(&identity),
            link: [link, 0.0, 0.0],
            ..JointData::default()
        };
    }
    data.probe = ProbeData {
        vector: [0.0, 0.0, 50.0],
        direction: [0.0, 0.0, 1.0],
        ..ProbeData::default()
    };
    data.flags = data.content_flags();
    data
}

/// The CRC a table carries in its last four bytes.
pub fn crc_of(t: &[u8]) -> u32 {
    u32::from_le_bytes([
        t[t.len() - 4],
        t[t.len() - 3],
        t[t.len() - 2],
        t[t.len() - 1],
    ])
}

/// The steps that send `t`.
pub fn steps(t: &[u8]) -> Vec<Step> {
    Step::sequence(t).collect()
}

/// Sends `t` whole through an updater of [`layout`]; the last answer.
pub fn update(flash: &mut MockFlash, t: &[u8]) -> Result<Accepted, Refusal> {
    update_in(&layout(), flash, t)
}

/// [`update`] on `layout`.
pub fn update_in(layout: &Layout, flash: &mut MockFlash, t: &[u8]) -> Result<Accepted, Refusal> {
    update_with(layout, &Accept::joints(6), flash, t)
}

/// [`update_in`] by a hub that requires `accept` (its keys).
pub fn update_with(
    layout: &Layout,
    accept: &Accept,
    flash: &mut MockFlash,
    t: &[u8],
) -> Result<Accepted, Refusal> {
    let mut up = Updater::new(layout.clone(), *accept);
    let mut scratch = [0u8; MAX_TABLE_LEN];
    let mut last = Accepted::Aborted;
    for s in steps(t) {
        last = up.step(flash, &mut scratch, &s)?;
    }
    Ok(last)
}

/// The table the flash boots on, as bytes (`None`: no table).
pub fn boot(flash: &mut MockFlash) -> Option<Vec<u8>> {
    boot_in(&layout(), flash)
}

/// [`boot`] on `layout`.
pub fn boot_in(layout: &Layout, flash: &mut MockFlash) -> Option<Vec<u8>> {
    boot_with(layout, &Accept::joints(6), flash)
}

/// [`boot_in`] by a hub that requires `accept` (its keys).
pub fn boot_with(layout: &Layout, accept: &Accept, flash: &mut MockFlash) -> Option<Vec<u8>> {
    let mut buf = [0u8; MAX_TABLE_LEN];
    live_table(flash, layout, accept, &mut buf)
        .ok()
        .map(|l| l.table.bytes().to_vec())
}

/// The flash a board leaves the factory with: `t` in slot 0 by a probe, no state record.
pub fn factory(t: &[u8]) -> MockFlash {
    let mut f = MockFlash::new(FLASH_LEN);
    f.mem[..t.len()].copy_from_slice(t);
    f
}

/// The public key of the test signing key made from `seed` (never a maker's key).
pub fn public_key(seed: u8) -> [u8; crate::signature::KEY_LEN] {
    ed25519_dalek::SigningKey::from_bytes(&[seed; 32])
        .verifying_key()
        .to_bytes()
}

/// `t` followed by its signature under the test key made from `seed`: a signed image.
pub fn signed(t: &[u8], seed: u8) -> Vec<u8> {
    use ed25519_dalek::Signer;
    let sig = ed25519_dalek::SigningKey::from_bytes(&[seed; 32]).sign(t);
    let mut out = t.to_vec();
    out.extend_from_slice(&sig.to_bytes());
    out
}
