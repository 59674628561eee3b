//! What every floor's `Options::validate()` shares: an option outside its range is reported as
//! `(option, expected, value)`, so that the binary names it as its flag in one place.

/// An error that may be an option outside its range.
pub trait OptionError {
    /// `(option field, what it must be, the value given)` when this is an invalid option.
    fn invalid_option(&self) -> Option<(&'static str, &'static str, f64)>;

    /// The error as the CLI and the Python package word it, the option named as its flag
    /// (`processing_cutoff` is `--cutoff`, other fields `--field-name`); `None` for any other
    /// error.
    fn flag_message(&self) -> Option<String> {
        self.invalid_option().map(|(option, expected, value)| {
            let flag = keyword(option).replace('_', "-");
            format!("--{flag} must be {expected}, got {}", readable(value))
        })
    }

    /// The error as a keyword-argument API words it (the Python package): the option named as
    /// its keyword (`processing_cutoff` is `cutoff`, other fields as they are); `None` for any
    /// other error.
    fn keyword_message(&self) -> Option<String> {
        self.invalid_option().map(|(option, expected, value)| {
            format!(
                "{} must be {expected}, got {}",
                keyword(option),
                readable(value)
            )
        })
    }
}

/// The name a user gives an option field as (the flag `--name-with-dashes`, the keyword
/// `name_with_underscores`).
fn keyword(option: &str) -> &str {
    match option {
        "processing_cutoff" => "cutoff",
        other => other,
    }
}

/// Implements [`OptionError`] for an error enum with an `InvalidOption { option, expected,
/// value }` variant (exported at the crate's root for the floors above; use it as
/// `options::option_error!`).
#[doc(hidden)]
#[macro_export]
macro_rules! __option_error {
    ($t:ty) => {
        impl $crate::options::OptionError for $t {
            fn invalid_option(&self) -> Option<(&'static str, &'static str, f64)> {
                match self {
                    Self::InvalidOption {
                        option,
                        expected,
                        value,
                    } => Some((option, expected, *value)),
                    _ => None,
                }
            }
        }
    };
}
pub use crate::__option_error as option_error;

/// `x` as written for a reader: plainly between 10⁻³ and 10⁶, and a whole number below 10¹⁵
/// (a count), else in scientific notation (`1e300`, not three hundred digits).
pub fn readable(x: f64) -> String {
    let whole = x.fract() == 0.0 && x.abs() < 1e15;
    if whole || !x.is_finite() || (1e-3..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn numbers_are_written_as_a_reader_reads_them() {
        let shown: Vec<String> = [0.0, -1.0, 0.25, 1e9, 1e300, 1e-300, 2.5e-5, f64::NAN]
            .into_iter()
            .map(super::readable)
            .collect();
        assert_eq!(
            shown,
            [
                "0",
                "-1",
                "0.25",
                "1000000000",
                "1e300",
                "1e-300",
                "2.5e-5",
                "NaN"
            ]
        );
    }
}
