//! The binary's help: the product's description first (the same as the library's manifest
//! says, whichever crate clap reads it from), and every command documented.

#[path = "../../tests/common/mod.rs"]
mod common;

#[test]
fn the_help_leads_with_the_products_description_and_lists_every_command() {
    let manifest: toml::Table =
        toml::from_str(&std::fs::read_to_string(common::root().join("Cargo.toml")).unwrap())
            .unwrap();
    let description = manifest["package"]["description"].as_str().unwrap();
    let (code, help, _) = common::physid(&["--help"]);
    assert_eq!(code, 0);
    assert_eq!(help.lines().next(), Some(description), "{help}");
    let commands = [
        "diagnose",
        "blind",
        "generalize",
        "model",
        "dynamics",
        "simulate",
        "identify",
        "experiment",
        "sweep",
        "excite",
        "export",
        "compare",
        "schema",
    ];
    for c in commands {
        let line = help
            .lines()
            .find(|l| l.starts_with(&format!("  {c} ")))
            .unwrap_or_else(|| panic!("{c} missing from:\n{help}"));
        assert!(
            line[2 + c.len()..].trim().len() > 20,
            "{c} has no description in:\n{help}"
        );
        let (code, text, err) = common::physid(&[c, "--help"]);
        assert_eq!(code, 0, "{c}: {err}");
        assert!(text.contains(&format!("Usage: physid {c}")), "{text}");
    }
}

#[test]
fn identify_s_help_lists_every_effect_kind_with_its_grid() {
    let (code, help, _) = common::physid(&["identify", "--help"]);
    assert_eq!(code, 0);
    // Every kind of the table (the help is built from it; backlash was once missing).
    for kind in physid::diagnose::library::Kind::ALL {
        assert!(
            help.contains(kind.name()),
            "{} missing:\n{help}",
            kind.name()
        );
    }
    let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat.contains("backlash[:<width of the secant, rad: 0.01, 0.02 or 0.04; 0: the tangent>]"),
        "{flat}"
    );
}
