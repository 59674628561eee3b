//! `physid schema`: the JSON Schema of a JSON output, generated from its Rust type.

use clap::ValueEnum;
use serde_json::{json, Value};

/// Print the JSON Schema (draft 2020-12) of a JSON output, generated from the type that writes
/// it. The committed copies live in docs/schemas/ (tests check they are current).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The output.
    #[arg(value_enum)]
    output: Output,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum Output {
    /// `identify --json`.
    Identify,
    /// `diagnose --json` and `report.json`.
    Diagnose,
    /// `blind`'s `scores.json`.
    BlindScores,
    /// `blind --real`'s `scores.json`.
    BlindRealScores,
    /// `generalize`'s `scores.json`.
    GeneralizeScores,
    /// `experiment`'s `provenance.json`.
    Provenance,
    /// `simulate --json`.
    Simulate,
    /// `model --json`.
    Model,
    /// `excite --json`.
    Excite,
}

/// Every `"type": "number"` also admits null: serde_json writes a non-finite number (NaN, an
/// infinite standard error) as null.
fn nullable_numbers(v: &mut Value) {
    match v {
        Value::Object(map) => {
            if map.get("type") == Some(&json!("number")) {
                map.insert("type".into(), json!(["number", "null"]));
            }
            map.values_mut().for_each(nullable_numbers);
        }
        Value::Array(items) => items.iter_mut().for_each(nullable_numbers),
        _ => {}
    }
}

/// The schema of `output`, with the two fields every physid JSON carries.
pub fn schema(output: &str) -> anyhow::Result<Value> {
    let s = match output {
        "identify" => schemars::schema_for!(physid::api::identify::IdentifyJson),
        "diagnose" => schemars::schema_for!(physid::diagnose::Diagnosis),
        "blind_scores" => schemars::schema_for!(physid::bench::blind::Scores),
        "blind_real_scores" => schemars::schema_for!(physid::bench::semireal::RealScores),
        "generalize_scores" => schemars::schema_for!(physid::bench::generalize::Scores),
        "provenance" => schemars::schema_for!(physid::api::provenance::Provenance),
        "simulate" => schemars::schema_for!(physid::api::simulate::SimulateJson),
        "model" => schemars::schema_for!(physid::api::model::ModelJson),
        "excite" => schemars::schema_for!(physid::api::excite::ExciteJson),
        other => anyhow::bail!("no schema for '{other}'"),
    };
    let mut v = serde_json::to_value(s)?;
    nullable_numbers(&mut v);
    v["$id"] = json!(format!("physid.{output}/1"));
    v["properties"]["physid_version"] =
        json!({"type": "string", "description": "The physid version that wrote it."});
    v["properties"]["schema"] = json!({"const": format!("physid.{output}/1")});
    if let Some(req) = v["required"].as_array_mut() {
        req.push(json!("physid_version"));
        req.push(json!("schema"));
    }
    Ok(v)
}

/// `physid schema`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let name = match a.output {
        Output::Identify => "identify",
        Output::Diagnose => "diagnose",
        Output::BlindScores => "blind_scores",
        Output::BlindRealScores => "blind_real_scores",
        Output::GeneralizeScores => "generalize_scores",
        Output::Provenance => "provenance",
        Output::Simulate => "simulate",
        Output::Model => "model",
        Output::Excite => "excite",
    };
    println!("{}", serde_json::to_string_pretty(&schema(name)?)?);
    Ok(())
}
