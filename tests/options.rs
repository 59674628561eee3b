//! Library entry points check their own options: each `Options::validate()` rejects, naming
//! the option, what the command line rejects (the CLI only shows the option as its flag).

/// Each library `Options` rejects, by name, what the command line rejects.
#[test]
fn library_options_reject_what_the_cli_rejects() {
    use physid::bench::blind::{BlindError, BlindOptions};
    use physid::diagnose;
    use physid::ident::{self, ConstraintSet, IdentError};

    let named = |e: &diagnose::DiagnoseError| match e {
        diagnose::DiagnoseError::InvalidOption { option, value, .. } => (*option, *value),
        other => panic!("not an option error: {other}"),
    };
    let mut d = diagnose::Options {
        description_uncertainty: Some(-0.1),
        ..Default::default()
    };
    assert_eq!(
        named(&d.validate().unwrap_err()),
        ("description_uncertainty", -0.1)
    );
    d.description_uncertainty = Some(0.1);
    d.processing_cutoff = 0.0;
    assert_eq!(
        named(&d.validate().unwrap_err()),
        ("processing_cutoff", 0.0)
    );
    d.processing_cutoff = 20.0;
    assert!(d.validate().is_ok());

    let mut o = ident::Options::new(ConstraintSet::Consistent);
    o.prior_weight = -1.0;
    assert!(matches!(
        o.validate(),
        Err(IdentError::InvalidOption {
            option: "prior_weight",
            ..
        })
    ));
    o.prior_weight = 1e-6;
    o.eps = f64::NAN;
    assert!(matches!(
        o.validate(),
        Err(IdentError::InvalidOption { option: "eps", .. })
    ));

    let mut b = BlindOptions {
        cases: 0,
        seed: 1,
        description_error: 0.1,
        description_uncertainty: None,
    };
    assert!(matches!(
        b.validate(),
        Err(BlindError::InvalidOption {
            option: "cases",
            ..
        })
    ));
    b.cases = 3;
    b.description_error = -1.0;
    assert!(matches!(
        b.validate(),
        Err(BlindError::InvalidOption {
            option: "description_error",
            ..
        })
    ));
    b.description_error = 0.1;
    b.description_uncertainty = Some(-0.5);
    assert!(matches!(
        b.validate(),
        Err(BlindError::InvalidOption {
            option: "description_uncertainty",
            ..
        })
    ));
    b.description_uncertainty = Some(0.0);
    assert!(b.validate().is_ok());
    assert_eq!(b.diagnose_options().description_uncertainty, None);
}
