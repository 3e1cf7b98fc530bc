//! The statistics of `spec/acceptance-tests.md`, each computed exactly as the spec writes it,
//! from the ball centres the calibrated model gives for the rows (mm inside, µm in reports).

use crate::data::{Dataset, Layout, Row};
use crate::geometry::sphere::{self as fit, FitError};
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// The tests, by their standard names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub enum Test {
    /// ISO 10360-12 `PSize.Sph.1×25::Tact.AArm`: size error of a sphere.
    #[serde(rename = "P_Size")]
    PSize,
    /// ISO 10360-12 `PForm.Sph.1×25`: form error of a sphere.
    #[serde(rename = "P_Form")]
    PForm,
    /// ISO 10360-12 `LDia.5×5:Art`: articulated location error.
    #[serde(rename = "L_Dia")]
    LDia,
    /// Length measurement error (ball bar).
    #[serde(rename = "E_Uni")]
    EUni,
    /// ASME B89.4.22 single-point articulation: the largest deviation from the mean.
    #[serde(rename = "SPAT_max")]
    SpatMax,
    /// ASME B89.4.22 single-point articulation: twice the deviations' RMS (n − 1).
    #[serde(rename = "SPAT_2s")]
    Spat2s,
}

impl Test {
    /// Every test, in report order.
    pub const ALL: [Test; 6] = [
        Test::PSize,
        Test::PForm,
        Test::LDia,
        Test::EUni,
        Test::SpatMax,
        Test::Spat2s,
    ];

    /// The spec's key (also the MPE file's).
    pub fn key(self) -> &'static str {
        match self {
            Test::PSize => "P_Size",
            Test::PForm => "P_Form",
            Test::LDia => "L_Dia",
            Test::EUni => "E_Uni",
            Test::SpatMax => "SPAT_max",
            Test::Spat2s => "SPAT_2s",
        }
    }

    /// Whether the test's result keeps its sign (a size or length error) or is a magnitude.
    pub fn signed(self) -> bool {
        matches!(self, Test::PSize | Test::EUni)
    }
}

/// One group's value of one test.
#[derive(Clone, Debug, PartialEq)]
pub struct Value {
    /// The test.
    pub test: Test,
    /// The data's group.
    pub group: i64,
    /// The value (mm).
    pub value_mm: f64,
    /// The length the value belongs to (E_Uni: the bar, mm), for a length-dependent MPE.
    pub length_mm: Option<f64>,
}

/// Why a test could not be computed from its group.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StatError {
    /// A sphere group without articulations needs 25 points.
    #[error("sphere group {group}: {have} points; P_Size and P_Form need 25 or more")]
    SphereTooFew {
        /// The group's number in the data.
        group: i64,
        /// Its points.
        have: usize,
    },
    /// L_Dia needs five articulations of five points.
    #[error("sphere group {group}: L_Dia needs 5 articulations of 5 points or more, {found}")]
    Articulations {
        /// The group's number in the data.
        group: i64,
        /// What the group has, in words.
        found: String,
    },
    /// The fit failed.
    #[error("sphere group {group}: {source}")]
    Fit {
        /// The group's number in the data.
        group: i64,
        /// Why the sphere fit failed.
        #[source]
        source: FitError,
    },
}

impl StatError {
    /// The group the test could not be computed from.
    pub fn group(&self) -> i64 {
        match self {
            StatError::SphereTooFew { group, .. }
            | StatError::Articulations { group, .. }
            | StatError::Fit { group, .. } => *group,
        }
    }
}

/// Every test value the data supports, group by group; `ball_diameter` gives the stylus ball
/// (mm) a row was taken with (a sphere group is touched with one probe: the data reader's rule).
pub fn values(
    data: &Dataset,
    centres: &[Vector3<f64>],
    ball_diameter: &dyn Fn(&Row) -> f64,
) -> Result<Vec<Value>, StatError> {
    let layout = data.layout();
    let mut out = Vec::new();
    sphere_values(data, &layout, centres, ball_diameter, &mut out)?;
    for g in &layout.length {
        let e =
            (super::mean_of(&g.a, centres) - super::mean_of(&g.b, centres)).norm() - g.length_mm;
        out.push(Value {
            test: Test::EUni,
            group: g.group,
            value_mm: e,
            length_mm: Some(g.length_mm),
        });
    }
    for g in &layout.spat {
        let p: Vec<Vector3<f64>> = g.rows.iter().map(|&i| centres[i]).collect();
        let (max, two_s) = spat(&p);
        out.push(value(Test::SpatMax, g.group, max));
        out.push(value(Test::Spat2s, g.group, two_s));
    }
    Ok(out)
}

fn value(test: Test, group: i64, value_mm: f64) -> Value {
    Value {
        test,
        group,
        value_mm,
        length_mm: None,
    }
}

/// SPAT of one group: (δ_max, 2s) about the mean.
pub fn spat(p: &[Vector3<f64>]) -> (f64, f64) {
    let n = p.len();
    let mean = p.iter().sum::<Vector3<f64>>() / n as f64;
    let d: Vec<f64> = p.iter().map(|q| (q - mean).norm()).collect();
    let max = d.iter().fold(0.0f64, |m, x| m.max(*x));
    let two_s = 2.0 * (d.iter().map(|x| x * x).sum::<f64>() / (n as f64 - 1.0)).sqrt();
    (max, two_s)
}

fn sphere_values(
    data: &Dataset,
    layout: &Layout,
    centres: &[Vector3<f64>],
    ball_diameter: &dyn Fn(&Row) -> f64,
    out: &mut Vec<Value>,
) -> Result<(), StatError> {
    for g in &layout.sphere {
        let ball_diameter = ball_diameter(&data.rows[g.rows[0]]);
        let p: Vec<Vector3<f64>> = g.rows.iter().map(|&i| centres[i]).collect();
        let fit_err = |source| StatError::Fit {
            group: g.group,
            source,
        };
        let articulated = data.rows[g.rows[0]]
            .sphere
            .and_then(|t| t.articulation)
            .is_some();
        if !articulated {
            if p.len() < 25 {
                return Err(StatError::SphereTooFew {
                    group: g.group,
                    have: p.len(),
                });
            }
            let s = fit::free(&p).map_err(fit_err)?;
            let d = fit::distances(&p, &s.centre);
            let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
                (lo.min(*x), hi.max(*x))
            });
            out.push(value(
                Test::PSize,
                g.group,
                (2.0 * s.radius - ball_diameter) - g.diameter_mm,
            ));
            out.push(value(Test::PForm, g.group, hi - lo));
            continue;
        }
        let c: Vec<Vector3<f64>> = articulation_centres(data, g, centres, ball_diameter)?
            .into_iter()
            .map(|(_, c)| c)
            .collect();
        let mut l = 0.0f64;
        for a in &c {
            for b in &c {
                l = l.max((a - b).norm());
            }
        }
        out.push(value(Test::LDia, g.group, l));
    }
    Ok(())
}

/// L_Dia's centres: each articulation's least-squares centre of a sphere group, the radius
/// fixed at (D + d)/2, by articulation number (the report plots them too).
pub fn articulation_centres(
    data: &Dataset,
    g: &crate::data::SphereGroup,
    centres: &[Vector3<f64>],
    ball_diameter: f64,
) -> Result<Vec<(i64, Vector3<f64>)>, StatError> {
    let p: Vec<Vector3<f64>> = g.rows.iter().map(|&i| centres[i]).collect();
    let fit_err = |source| StatError::Fit {
        group: g.group,
        source,
    };
    let mut sets: BTreeMap<i64, Vec<Vector3<f64>>> = BTreeMap::new();
    for &i in &g.rows {
        let a = data.rows[i]
            .sphere
            .and_then(|t| t.articulation)
            .unwrap_or(0);
        sets.entry(a).or_default().push(centres[i]);
    }
    if sets.len() != 5 || sets.values().any(|s| s.len() < 5) {
        let found = sets
            .iter()
            .map(|(a, s)| format!("articulation {a}: {} points", s.len()))
            .collect::<Vec<_>>()
            .join(", ");
        return Err(StatError::Articulations {
            group: g.group,
            found: format!("found {}", found),
        });
    }
    // Every set's centre from the whole group's free centre: the right side of each cap.
    let start = fit::free(&p).map_err(fit_err)?.centre;
    let radius = (g.diameter_mm + ball_diameter) / 2.0;
    sets.iter()
        .map(|(&a, s)| Ok((a, fit::with_radius(s, radius, start).map_err(fit_err)?)))
        .collect()
}

/// The test's result over its groups: the group of largest |value| (sign kept for P_Size and
/// E_Uni; the others are magnitudes already).
pub fn result(values: &[Value], test: Test) -> Option<&Value> {
    values
        .iter()
        .filter(|v| v.test == test)
        .fold(None, |best: Option<&Value>, v| match best {
            Some(b) if b.value_mm.abs() >= v.value_mm.abs() => Some(b),
            _ => Some(v),
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{End, Kind, Row, Touch};

    fn row(kind: Kind, group: i64) -> Row {
        Row {
            kind,
            group,
            theta: vec![0.0; 6],
            xyz: None,
            end: None,
            length_mm: None,
            sphere: None,
            temp_c: 20.0,
            probe: None,
            line: 0,
            file: None,
        }
    }

    fn sphere_rows(group: i64, d: f64, articulations: &[Option<i64>]) -> Vec<Row> {
        articulations
            .iter()
            .map(|&articulation| Row {
                sphere: Some(Touch {
                    diameter_mm: d,
                    articulation,
                }),
                ..row(Kind::Sphere, group)
            })
            .collect()
    }

    fn data(rows: Vec<Row>) -> Dataset {
        Dataset::from_rows(rows, 6, false, "test").unwrap()
    }

    fn on_sphere(c: Vector3<f64>, r: f64, n: usize) -> Vec<Vector3<f64>> {
        crate::sim::sphere_directions(n)
            .into_iter()
            .map(|u| c + u * r)
            .collect()
    }

    #[test]
    fn spat_by_hand() {
        let d = data(vec![row(Kind::Spat, 1), row(Kind::Spat, 1)]);
        let c = [Vector3::zeros(), Vector3::new(2.0, 0.0, 0.0)];
        let v = values(&d, &c, &|_| 0.0).unwrap();
        assert_eq!(v[0].test, Test::SpatMax);
        assert!((v[0].value_mm - 1.0).abs() < 1e-15);
        // 2 √((1² + 1²) / (2 − 1)) = 2√2.
        assert!((v[1].value_mm - 2.0 * 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn length_error_by_hand() {
        let mut rows = Vec::new();
        for (end, _) in [(End::A, 0), (End::A, 1), (End::B, 2)] {
            rows.push(Row {
                end: Some(end),
                length_mm: Some(100.0),
                ..row(Kind::Length, 3)
            });
        }
        let c = [
            Vector3::new(0.0, 0.0, -0.001),
            Vector3::new(0.0, 0.0, 0.001),
            Vector3::new(100.01, 0.0, 0.0),
        ];
        let v = values(&data(rows), &c, &|_| 0.0).unwrap();
        assert_eq!(v.len(), 1);
        assert_eq!((v[0].test, v[0].group), (Test::EUni, 3));
        assert!((v[0].value_mm - 0.01).abs() < 1e-9, "{}", v[0].value_mm);
        assert_eq!(v[0].length_mm, Some(100.0));
    }

    #[test]
    fn sphere_size_and_form_by_hand() {
        // D = 25, d = 2: centres at (D + d)/2 = 13.5 give P_Size 0; at 13.502 exactly +4 µm.
        let c = Vector3::new(10.0, 20.0, 30.0);
        let d = data(sphere_rows(1, 25.0, &[None; 25]));
        let exact = values(&d, &on_sphere(c, 13.5, 25), &|_| 2.0).unwrap();
        assert!(exact[0].value_mm.abs() < 1e-9 && exact[1].value_mm < 1e-9);
        let big = values(&d, &on_sphere(c, 13.502, 25), &|_| 2.0).unwrap();
        assert_eq!((big[0].test, big[1].test), (Test::PSize, Test::PForm));
        assert!(
            (big[0].value_mm - 0.004).abs() < 1e-9,
            "{}",
            big[0].value_mm
        );
        // One point 3 µm out and one 2 µm in: the fitted sphere moves a little towards them,
        // so the form is a little under 5 µm and the size a little off 4 µm.
        let mut p = on_sphere(c, 13.502, 25);
        p[3] = c + (p[3] - c).normalize() * 13.505;
        p[7] = c + (p[7] - c).normalize() * 13.500;
        let v = values(&d, &p, &|_| 2.0).unwrap();
        assert!((v[0].value_mm - 0.004).abs() < 5e-4, "{}", v[0].value_mm);
        assert!(
            v[1].value_mm > 0.004 && v[1].value_mm <= 0.005 + 1e-9,
            "{}",
            v[1].value_mm
        );
    }

    #[test]
    fn articulated_location_by_hand() {
        // Five sets on one sphere; set 3 displaced by 10 µm along x: L_Dia = 10 µm.
        let c = Vector3::new(0.0, 0.0, 500.0);
        let mut arts = Vec::new();
        let mut p = Vec::new();
        for a in 1..=5 {
            let shift = if a == 3 {
                Vector3::new(0.01, 0.0, 0.0)
            } else {
                Vector3::zeros()
            };
            for q in on_sphere(c + shift, 12.5, 5) {
                arts.push(Some(a));
                p.push(q);
            }
        }
        let v = values(&data(sphere_rows(2, 25.0, &arts)), &p, &|_| 0.0).unwrap();
        assert_eq!((v[0].test, v[0].group), (Test::LDia, 2));
        assert!((v[0].value_mm - 0.01).abs() < 1e-9, "{}", v[0].value_mm);
    }

    #[test]
    fn degenerate_groups_are_clear_errors() {
        let c = Vector3::new(0.0, 0.0, 500.0);
        let few = values(
            &data(sphere_rows(1, 25.0, &[None; 24])),
            &on_sphere(c, 12.5, 24),
            &|_| 0.0,
        );
        assert_eq!(
            few.unwrap_err(),
            StatError::SphereTooFew { group: 1, have: 24 }
        );
        let flat: Vec<Vector3<f64>> = (0..25)
            .map(|i| Vector3::new((i as f64).cos(), (i as f64).sin(), 0.0) * 12.5)
            .collect();
        let e = values(&data(sphere_rows(4, 25.0, &[None; 25])), &flat, &|_| 0.0).unwrap_err();
        assert_eq!(
            e,
            StatError::Fit {
                group: 4,
                source: FitError::Coplanar
            }
        );
        assert!(e.to_string().contains("group 4") && e.to_string().contains("coplanar"));
        // Four articulations where L_Dia needs five.
        let arts: Vec<Option<i64>> = (0..20).map(|i| Some(i / 5 + 1)).collect();
        let e = values(
            &data(sphere_rows(5, 25.0, &arts)),
            &on_sphere(c, 12.5, 20),
            &|_| 0.0,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("group 5") && e.contains("5 articulations"),
            "{e}"
        );
    }

    #[test]
    fn the_result_is_the_worst_group_with_its_sign() {
        let v = |group, value_mm| Value {
            test: Test::PSize,
            group,
            value_mm,
            length_mm: None,
        };
        let all = [v(1, 0.002), v(2, -0.005), v(3, 0.004)];
        let r = result(&all, Test::PSize).unwrap();
        assert_eq!((r.group, r.value_mm), (2, -0.005));
        assert!(result(&all, Test::LDia).is_none());
    }
}
