//! `physid keywords` (hidden): every command's flags with their help, default and allowed
//! values, as JSON. The one place the Python package's keyword documentation is generated from
//! (scripts/python_keywords.py writes python/keywords/; the tests check it is current).

use clap::CommandFactory;
use serde_json::{json, Map, Value};

/// Print every command's flags with their help, default and allowed values (JSON), for the
/// Python package's documentation.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// One flag as the Python documentation needs it.
fn flag(a: &clap::Arg) -> Value {
    let text = |s: Option<&clap::builder::StyledStr>| s.map(|h| h.to_string());
    json!({
        "flag": a.get_long(),
        "help": text(a.get_long_help()).or_else(|| text(a.get_help())),
        "values": a.get_possible_values().iter().filter(|v| !v.is_hide_set()).map(|v| v.get_name().to_string()).collect::<Vec<_>>(),
        "default": a.get_default_values().iter().map(|v| v.to_string_lossy().into_owned()).collect::<Vec<_>>(),
    })
}

/// Prints the flags of every command.
pub fn run(_: Args) -> anyhow::Result<()> {
    let cli = crate::Cli::command();
    let mut out = Map::new();
    for command in cli.get_subcommands() {
        let flags: Vec<Value> = command
            .get_arguments()
            .filter(|a| a.get_long().is_some() && !a.is_hide_set())
            .map(flag)
            .collect();
        out.insert(command.get_name().to_string(), Value::Array(flags));
    }
    println!("{}", serde_json::to_string_pretty(&Value::Object(out))?);
    Ok(())
}
