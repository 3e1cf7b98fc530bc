//! Value parsers shared by the subcommands' arguments: a bad number is refused by clap, with
//! the argument named, before any file is read or any fit is run.

/// Why an argument's value was refused (clap prints it after the argument's name).
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum ArgError {
    #[error("`{0}` is not a finite number ≥ 0")]
    NotNonNegative(String),
    #[error("`{0}` is not a finite number > 0")]
    NotPositive(String),
    #[error("`{0}` is not a number strictly between 0 and 1")]
    NotProbability(String),
    #[error("{value} mm is beyond {max} mm, the longest length data may hold")]
    TooLong { value: f64, max: f64 },
    #[error("`{given}` is not {what}: {choices}")]
    NotOneOf {
        given: String,
        what: &'static str,
        choices: &'static str,
    },
    #[error("`{0}` is not a range: e.g. 16..28")]
    NotRange(String),
    #[error("`{given}` is outside {lo}..{hi} °C, the temperatures the firmware (and the data reader) accept")]
    TemperatureOutside { given: String, lo: f64, hi: f64 },
    #[error("`{given}` is beyond {max} {unit}, the largest such standard uncertainty a calibration file (and the hub's table) holds")]
    BeyondBudgetLimit {
        given: String,
        max: f64,
        unit: &'static str,
    },
}

/// A finite number ≥ 0.
pub fn non_negative(s: &str) -> Result<f64, ArgError> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(ArgError::NotNonNegative(s.to_string())),
    }
}

/// A standard uncertainty in [0, `max`] `unit`: the budget limits a calibration file is read
/// with (`armcal::limits::CALFILE`), so `calibrate` never writes a budget no command reads.
fn budget_term(s: &str, max: f64, unit: &'static str) -> Result<f64, ArgError> {
    let x = non_negative(s)?;
    if x > max {
        return Err(ArgError::BeyondBudgetLimit {
            given: s.to_string(),
            max,
            unit,
        });
    }
    Ok(x)
}

/// A budget's standard uncertainty of a length (probing, model), mm.
pub fn budget_mm(s: &str) -> Result<f64, ArgError> {
    budget_term(s, armcal::limits::CALFILE.budget_mm, "mm")
}

/// A budget's standard uncertainty of a joint reading, counts.
pub fn budget_counts(s: &str) -> Result<f64, ArgError> {
    budget_term(s, armcal::limits::CALFILE.budget_counts, "counts")
}

/// A budget's standard uncertainty of the temperature reading, °C.
pub fn budget_temperature_c(s: &str) -> Result<f64, ArgError> {
    budget_term(s, armcal::limits::CALFILE.budget_temperature_c, "°C")
}

/// A finite number > 0.
pub fn positive(s: &str) -> Result<f64, ArgError> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(ArgError::NotPositive(s.to_string())),
    }
}

/// A probability strictly between 0 and 1.
pub fn probability(s: &str) -> Result<f64, ArgError> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x < 1.0 => Ok(x),
        _ => Err(ArgError::NotProbability(s.to_string())),
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_nan_inf_and_signs() {
        for bad in ["nan", "NaN", "inf", "-1", "x", ""] {
            assert!(non_negative(bad).is_err(), "{bad}");
            assert!(positive(bad).is_err(), "{bad}");
        }
        assert_eq!(non_negative("0"), Ok(0.0));
        assert!(positive("0").is_err());
        assert!(probability("1").is_err() && probability("0").is_err());
        assert_eq!(probability("0.001"), Ok(0.001));
    }

    #[test]
    fn budget_terms_stop_at_the_calibration_files_limits() {
        // issue 27, F2: `calibrate --probing-mm 1e200` wrote a budget whose U95 was 0.
        assert!(matches!(
            budget_mm("1e200"),
            Err(ArgError::BeyondBudgetLimit { .. })
        ));
        assert!(budget_counts("1e300").is_err() && budget_temperature_c("1e3").is_err());
        assert!(budget_mm("-0.001").is_err() && budget_mm("nan").is_err());
        assert_eq!(budget_mm("0.002"), Ok(0.002));
        assert_eq!(budget_counts("0.29"), Ok(0.29));
    }
}
