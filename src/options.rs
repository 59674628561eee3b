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
            let flag = match option {
                "processing_cutoff" => "cutoff".to_string(),
                other => other.replace('_', "-"),
            };
            format!("--{flag} must be {expected}, got {value}")
        })
    }
}

/// Implements [`OptionError`] for an error enum with an `InvalidOption { option, expected,
/// value }` variant.
macro_rules! option_error {
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
pub(crate) use option_error;
