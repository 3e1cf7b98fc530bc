//! Maximum permissible errors (the MPE file of `spec/acceptance-tests.md`) and the ISO 14253-1
//! decision: conformance proven when |value| + U ≤ MPE, non-conformance when |value| − U > MPE,
//! otherwise no decision.

use super::statistics::{Test, Value};
use std::collections::BTreeMap;
use std::path::Path;

/// An MPE: a constant, or for E_Uni a + L/1000 · per_m (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limit {
    /// A constant (mm).
    Constant(f64),
    /// a + L / 1000 mm · per_m.
    Linear {
        /// The constant part (mm).
        a: f64,
        /// The part per metre of length (mm).
        per_m: f64,
    },
}

/// What a limit may be, as its error says.
const LIMIT_FORMS: &str = "a limit is a number (mm) or { a = …, per_m = … } (mm, mm per metre)";

/// Read by hand rather than as an untagged enum: serde's untagged error ("did not match any
/// variant of untagged enum Limit") names no key, and an untagged struct variant ignores a key
/// it does not know (`per_km = 5` was silently dropped: issue 29, F8). toml adds the line and
/// the key this is under.
impl<'de> serde::Deserialize<'de> for Limit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Limit, D::Error> {
        use serde::de::Error;
        let number = |v: &toml::Value| match v {
            toml::Value::Float(x) => Some(*x),
            toml::Value::Integer(i) => Some(*i as f64),
            _ => None,
        };
        let value = toml::Value::deserialize(d)?;
        if let Some(x) = number(&value) {
            return Ok(Limit::Constant(x));
        }
        let toml::Value::Table(t) = &value else {
            return Err(D::Error::custom(format!(
                "`{value}` is not a limit: {LIMIT_FORMS}"
            )));
        };
        if let Some(k) = t.keys().find(|k| !matches!(k.as_str(), "a" | "per_m")) {
            return Err(D::Error::custom(format!(
                "unknown key `{}` in a limit: {LIMIT_FORMS}",
                crate::limits::shown(k)
            )));
        }
        let part = |k: &str| match t.get(k) {
            None => Err(D::Error::custom(format!(
                "missing key `{k}`: {LIMIT_FORMS}"
            ))),
            Some(v) => number(v).ok_or_else(|| {
                D::Error::custom(format!("`{k} = {v}` is not a number: {LIMIT_FORMS}"))
            }),
        };
        Ok(Limit::Linear {
            a: part("a")?,
            per_m: part("per_m")?,
        })
    }
}

impl Limit {
    /// The MPE at a length (mm); a constant ignores it.
    pub fn at(self, length_mm: Option<f64>) -> f64 {
        match self {
            Limit::Constant(c) => c,
            Limit::Linear { a, per_m } => a + length_mm.unwrap_or(0.0) / 1000.0 * per_m,
        }
    }
}

/// The MPE file.
#[derive(Clone, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mpe {
    #[serde(rename = "P_Size")]
    p_size: Option<f64>,
    #[serde(rename = "P_Form")]
    p_form: Option<f64>,
    #[serde(rename = "L_Dia")]
    l_dia: Option<f64>,
    #[serde(rename = "E_Uni")]
    e_uni: Option<Limit>,
    #[serde(rename = "SPAT_max")]
    spat_max: Option<f64>,
    #[serde(rename = "SPAT_2s")]
    spat_2s: Option<f64>,
    /// U (k = 2) of each test value (mm), by test key.
    #[serde(default)]
    test_uncertainty: BTreeMap<String, f64>,
    /// The file's name as given (the verdict and the report name it).
    #[serde(skip)]
    path: String,
}

/// Why an MPE file was refused.
#[derive(Debug, thiserror::Error)]
pub enum MpeError {
    /// Unreadable.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: String,
        #[source]
        /// Why it could not be read.
        source: std::io::Error,
    },
    /// Not TOML of the MPE file's keys (toml's message names the line, column and key).
    #[error("{path}: {message}")]
    Syntax {
        /// The file.
        path: String,
        /// toml's message.
        message: String,
    },
    /// A value that is no limit.
    #[error("{path}: key {key}: {value} is not a limit (a finite number ≥ 0, mm)")]
    Value {
        /// The file.
        path: String,
        /// The key, as the file spells it.
        key: String,
        /// Its value.
        value: f64,
    },
}

/// The outcome of ISO 14253-1's rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Decision {
    /// |value| + U ≤ MPE.
    Pass,
    /// |value| − U > MPE.
    Fail,
    /// Neither.
    #[serde(rename = "cannot decide")]
    CannotDecide,
}

impl Decision {
    /// ISO 14253-1 for a value, its expanded uncertainty and the MPE.
    pub fn of(value: f64, u: f64, mpe: f64) -> Decision {
        if value.abs() + u <= mpe {
            Decision::Pass
        } else if value.abs() - u > mpe {
            Decision::Fail
        } else {
            Decision::CannotDecide
        }
    }

    /// As the report writes it.
    pub fn name(self) -> &'static str {
        match self {
            Decision::Pass => "pass",
            Decision::Fail => "fail",
            Decision::CannotDecide => "cannot decide",
        }
    }
}

impl Mpe {
    /// Reads and checks an MPE file.
    pub fn read(path: &Path) -> Result<Mpe, MpeError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| MpeError::Io {
            path: name.clone(),
            source,
        })?;
        Mpe::parse(&text, &name)
    }

    /// Parses an MPE file's text; `path` names it in errors.
    pub fn parse(text: &str, path: &str) -> Result<Mpe, MpeError> {
        let mut m: Mpe = toml::from_str(text).map_err(|e| MpeError::Syntax {
            path: path.to_string(),
            message: e.to_string().trim_end().to_string(),
        })?;
        m.path = path.to_string();
        let bad = |key: &str, value: f64| MpeError::Value {
            path: path.to_string(),
            key: key.to_string(),
            value,
        };
        for t in Test::ALL {
            let check = |v: f64| {
                if v.is_finite() && v >= 0.0 {
                    Ok(())
                } else {
                    Err(bad(t.key(), v))
                }
            };
            match m.limit(t) {
                Some(Limit::Constant(c)) => check(c)?,
                Some(Limit::Linear { a, per_m }) => {
                    check(a)?;
                    check(per_m)?;
                }
                None => {}
            }
        }
        for (k, &u) in &m.test_uncertainty {
            if !Test::ALL.iter().any(|t| t.key() == k) {
                return Err(MpeError::Syntax {
                    path: path.to_string(),
                    message: format!("test_uncertainty.{k}: not a test: {}", keys()),
                });
            }
            if !(u.is_finite() && u >= 0.0) {
                return Err(bad(&format!("test_uncertainty.{k}"), u));
            }
        }
        Ok(m)
    }

    /// The file's name, as given to [`Mpe::read`] or [`Mpe::parse`].
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The MPE of a test, where the file gives one.
    pub fn limit(&self, t: Test) -> Option<Limit> {
        match t {
            Test::PSize => self.p_size.map(Limit::Constant),
            Test::PForm => self.p_form.map(Limit::Constant),
            Test::LDia => self.l_dia.map(Limit::Constant),
            Test::EUni => self.e_uni,
            Test::SpatMax => self.spat_max.map(Limit::Constant),
            Test::Spat2s => self.spat_2s.map(Limit::Constant),
        }
    }

    /// The MPE of one value (E_Uni at its bar's length).
    pub fn of(&self, v: &Value) -> Option<f64> {
        self.limit(v.test).map(|l| l.at(v.length_mm))
    }

    /// The file's `test_uncertainty` of a test (mm).
    pub fn test_uncertainty(&self, t: Test) -> Option<f64> {
        self.test_uncertainty.get(t.key()).copied()
    }
}

fn keys() -> String {
    Test::ALL.map(Test::key).join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decides_as_iso_14253_1() {
        assert_eq!(Decision::of(0.010, 0.002, 0.012), Decision::Pass);
        assert_eq!(Decision::of(-0.010, 0.002, 0.012), Decision::Pass);
        assert_eq!(Decision::of(0.011, 0.002, 0.012), Decision::CannotDecide);
        assert_eq!(Decision::of(0.014, 0.002, 0.012), Decision::CannotDecide);
        assert_eq!(Decision::of(0.0141, 0.002, 0.012), Decision::Fail);
    }

    #[test]
    fn reads_the_spec_example() {
        let m = Mpe::parse(
            "P_Size = 0.016\nP_Form = 0.020\nL_Dia = 0.030\nE_Uni = { a = 0.010, per_m = 0.010 }\n\
             SPAT_max = 0.025\nSPAT_2s = 0.020\ntest_uncertainty = { P_Size = 0.002, E_Uni = 0.003 }\n",
            "m.toml",
        )
        .unwrap();
        assert_eq!(m.limit(Test::PSize), Some(Limit::Constant(0.016)));
        let e = m.limit(Test::EUni).unwrap();
        assert!((e.at(Some(1500.0)) - 0.025).abs() < 1e-15);
        assert_eq!(m.test_uncertainty(Test::EUni), Some(0.003));
        assert_eq!(m.test_uncertainty(Test::LDia), None);
        let c = Mpe::parse("E_Uni = 0.030\n", "m.toml").unwrap();
        assert_eq!(c.limit(Test::EUni).unwrap().at(Some(2000.0)), 0.030);
    }

    #[test]
    fn refuses_bad_files_with_the_key() {
        let e = Mpe::parse("P_Sise = 0.016\n", "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.toml") && e.contains("P_Sise"), "{e}");
        let e = Mpe::parse("P_Form = -1.0\n", "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("P_Form"), "{e}");
        let e = Mpe::parse("test_uncertainty = { Q = 0.1 }\n", "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("test_uncertainty.Q"), "{e}");
    }
}
