//! The arm description: what a calibration file holds, in memory.
//!
//! Field names follow the calibration file's keys so that a reader of `spec/` finds each one.
//! Vectors are plain arrays here (the file's shape); evaluation converts them to `nalgebra`.

use std::f64::consts::PI;

/// A joint's nominal rotation axis, one of the coordinate axes of its own frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// The x axis.
    X,
    /// The y axis.
    Y,
    /// The z axis.
    Z,
}

impl Axis {
    /// Unit vector of the axis.
    pub fn unit(self) -> [f64; 3] {
        match self {
            Axis::X => [1.0, 0.0, 0.0],
            Axis::Y => [0.0, 1.0, 0.0],
            Axis::Z => [0.0, 0.0, 1.0],
        }
    }

    /// The two axes that carry the misalignment δα, δβ, in the spec's cyclic order
    /// (u = z: x then y; u = x: y then z; u = y: z then x).
    pub fn perpendicular(self) -> (Axis, Axis) {
        match self {
            Axis::Z => (Axis::X, Axis::Y),
            Axis::X => (Axis::Y, Axis::Z),
            Axis::Y => (Axis::Z, Axis::X),
        }
    }

    /// The file's spelling: `x`, `y` or `z`.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }

    /// Index 0, 1, 2 for x, y, z.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// One `encoder_harmonic` term: e += sin·sin(order·θ) + cos·cos(order·θ), θ the raw reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Harmonic {
    /// Order h ≥ 1 (1: disc eccentricity, 2: ellipticity).
    pub order: u32,
    /// Coefficient of sin(hθ) (rad).
    pub sin: f64,
    /// Coefficient of cos(hθ) (rad).
    pub cos: f64,
}

/// One `axis_wobble` term: the tilt motion of a joint's bearing,
/// δα += a·sin(hθ) + b·cos(hθ) and δβ += c·sin(hθ) + d·cos(hθ), with `alpha` = (a, b),
/// `beta` = (c, d), h the order and θ the raw reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wobble {
    /// Order h ≥ 1 (cycles per turn).
    pub order: u32,
    /// Coefficients of sin(hθ) and cos(hθ) in δα (rad).
    pub alpha: [f64; 2],
    /// Coefficients of sin(hθ) and cos(hθ) in δβ (rad).
    pub beta: [f64; 2],
}

/// One revolute joint with the link that follows it.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Nominal rotation axis u_i in the joint's own frame.
    pub axis: Axis,
    /// Nominal link vector v_i (mm), in the joint's frame after its rotation.
    pub link: [f64; 3],
    /// Zero offset Δθ_i (rad).
    pub zero_offset: f64,
    /// The fixed rotation before the joint, nominal and error together: [δα, δβ] (rad).
    pub tilt: [f64; 2],
    /// Link vector error Δv_i (mm).
    pub link_error: [f64; 3],
    /// Encoder harmonic terms.
    pub harmonics: Vec<Harmonic>,
    /// Axis wobble terms.
    pub wobble: Vec<Wobble>,
    /// Gravity compliance g_i (rad/mm).
    pub gravity: f64,
    /// Thermal expansion κ_i of this link (1/°C).
    pub thermal: f64,
    /// Encoder counts per revolution.
    pub encoder_counts: u32,
}

impl Joint {
    /// A joint with nominal geometry only and every parameter zero.
    pub fn nominal(axis: Axis, link: [f64; 3]) -> Joint {
        Joint {
            axis,
            link,
            zero_offset: 0.0,
            tilt: [0.0, 0.0],
            link_error: [0.0; 3],
            harmonics: Vec::new(),
            wobble: Vec::new(),
            gravity: 0.0,
            thermal: 0.0,
            encoder_counts: DEFAULT_COUNTS,
        }
    }

    /// The link vector with its error, v_i + Δv_i (before thermal scaling).
    pub fn actual_link(&self) -> [f64; 3] {
        add3(self.link, self.link_error)
    }

    /// The tilt [δα, δβ] at raw reading θ: the fixed tilt with the wobble's variation.
    pub fn tilt_at(&self, theta: f64) -> [f64; 2] {
        self.wobble.iter().fold(self.tilt, |[a, b], w| {
            let (s, c) = (f64::from(w.order) * theta).sin_cos();
            [
                a + w.alpha[0] * s + w.alpha[1] * c,
                b + w.beta[0] * s + w.beta[1] * c,
            ]
        })
    }

    /// Encoder reading in radians for a count: θ = 2π · count / counts-per-revolution.
    pub fn count_to_rad(&self, count: i64) -> f64 {
        2.0 * PI * count as f64 / self.encoder_counts as f64
    }
}

/// A probe: from the last joint's frame to the centre of the stylus ball.
///
/// An arm carries up to [`MAX_PROBES`] of them (ball styli of different lengths and
/// diameters, an extension), one mounted at a time; each has an `id` of its own, which the
/// measured data's `probe` column and the hub's probe selection name.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// The probe's id (0 to 255; 0 where the file gives none).
    pub id: u8,
    /// Nominal probe vector v_p (mm).
    pub vector: [f64; 3],
    /// Probe vector error Δv_p (mm).
    pub error: [f64; 3],
    /// Thermal expansion κ_p (1/°C).
    pub thermal: f64,
    /// Diameter of the stylus ball (mm; 0 where the file gives none). The chain gives the
    /// ball's centre and needs none of it; tests that touch a surface (a sphere's size) do.
    pub ball_diameter: f64,
}

impl Probe {
    /// v_p + Δv_p (before thermal scaling).
    pub fn actual(&self) -> [f64; 3] {
        add3(self.vector, self.error)
    }
}

/// The rigid transform of a reference instrument: x_ref = R_T p + t_T.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Unit quaternion (w, x, y, z) of R_T.
    pub rotation: [f64; 4],
    /// t_T (mm).
    pub translation: [f64; 3],
}

/// A whole arm: nominal geometry, identified parameters and, optionally, the instrument frame
/// of the data it was fitted on.
#[derive(Clone, Debug, PartialEq)]
pub struct Arm {
    /// Free text name (`name`).
    pub name: Option<String>,
    /// The arm's serial number (`serial`).
    pub serial: Option<String>,
    /// Joints, base first.
    pub joints: Vec<Joint>,
    /// The arm's first probe: the one readings and rows without a probe id are taken with.
    pub probe: Probe,
    /// The arm's other probes, in file order (none for most arms): at most
    /// [`MAX_PROBES`] − 1, ids distinct from each other and from `probe`'s.
    pub more_probes: Vec<Probe>,
    /// `[reference_frame]`, where present.
    pub reference_frame: Option<Frame>,
}

/// Counts per revolution where the file gives none: 2^20.
pub const DEFAULT_COUNTS: u32 = 1 << 20;

/// The joint counts the model takes.
pub const JOINT_COUNTS: std::ops::RangeInclusive<usize> = 6..=7;

/// Most probes an arm carries (`[[probe]]` entries of a calibration file).
pub const MAX_PROBES: usize = 8;

impl Arm {
    /// A whole reading (one count per joint) in radians, joint by joint as
    /// [`Joint::count_to_rad`] (extra counts beyond the arm's joints are ignored).
    pub fn counts_to_rad(&self, counts: &[u32]) -> Vec<f64> {
        counts
            .iter()
            .zip(&self.joints)
            .map(|(&c, j)| j.count_to_rad(i64::from(c)))
            .collect()
    }

    /// The spec's `default-6`: a 2.6 m class arm, straight up at θ = 0.
    pub fn default6() -> Arm {
        let j = |axis, z| Joint::nominal(axis, [0.0, 0.0, z]);
        Arm {
            name: Some("default-6".into()),
            serial: None,
            joints: vec![
                j(Axis::Z, 200.0),
                j(Axis::X, 300.0),
                j(Axis::Z, 300.0),
                j(Axis::X, 250.0),
                j(Axis::Z, 250.0),
                j(Axis::X, 80.0),
            ],
            probe: Probe {
                id: 0,
                vector: [0.0, 0.0, 120.0],
                error: [0.0; 3],
                thermal: 0.0,
                ball_diameter: 0.0,
            },
            more_probes: Vec::new(),
            reference_frame: None,
        }
    }

    /// Every probe, the first (`probe`) then the others: position k in this order is the
    /// probe's index, which a calibration's unknowns use.
    pub fn probes(&self) -> impl Iterator<Item = &Probe> {
        std::iter::once(&self.probe).chain(&self.more_probes)
    }

    /// How many probes the arm carries (at least one).
    pub fn probe_count(&self) -> usize {
        1 + self.more_probes.len()
    }

    /// The index (in [`Arm::probes`] order) of the probe with id `id`.
    pub fn probe_index(&self, id: u8) -> Option<usize> {
        self.probes().position(|p| p.id == id)
    }

    /// The probe at index `k` ([`Arm::probes`] order); `None` past the last.
    pub fn probe_at(&self, k: usize) -> Option<&Probe> {
        self.probes().nth(k)
    }

    /// The probe at index `k`, to change; `None` past the last.
    pub fn probe_at_mut(&mut self, k: usize) -> Option<&mut Probe> {
        if k == 0 {
            Some(&mut self.probe)
        } else {
            self.more_probes.get_mut(k - 1)
        }
    }

    /// The arm as it measures with its probe at index `k`: the same joints, that probe as
    /// `probe` and no others. Every evaluation of the model (the reference's forward pass,
    /// the firmware's chain) is of one mounted probe; this is how a reading taken with
    /// another than the first is evaluated. Borrowed for the first probe (no copy); `None`
    /// past the last.
    pub fn for_probe(&self, k: usize) -> Option<std::borrow::Cow<'_, Arm>> {
        if k == 0 {
            return Some(std::borrow::Cow::Borrowed(self));
        }
        let probe = self.more_probes.get(k - 1)?.clone();
        Some(std::borrow::Cow::Owned(Arm {
            name: self.name.clone(),
            serial: self.serial.clone(),
            joints: self.joints.clone(),
            probe,
            more_probes: Vec::new(),
            reference_frame: self.reference_frame.clone(),
        }))
    }

    /// Number of joints N.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Whether joint `joint` (0-based) is a hinge: its axis lies across its link rather than
    /// along it. On `default-6` hinges travel ±170° and swivels are unlimited.
    pub fn is_hinge(&self, joint: usize) -> bool {
        let j = &self.joints[joint];
        let l = j.link;
        let a = j.axis.index();
        let along = l[a].abs();
        let across = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2] - l[a] * l[a]).sqrt();
        across > along
    }
}

fn add3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
