//! The JSON Schemas committed in docs/schemas/ are the ones the types generate now
//! (`physid schema NAME`); scripts/check_schemas.py validates real outputs against them.

#[path = "../../tests/common/mod.rs"]
mod common;

#[test]
fn the_committed_json_schemas_are_current() {
    let root = common::root();
    for (name, arg) in [
        ("identify", "identify"),
        ("diagnose", "diagnose"),
        ("blind_scores", "blind-scores"),
        ("blind_real_scores", "blind-real-scores"),
        ("generalize_scores", "generalize-scores"),
        ("provenance", "provenance"),
        ("simulate", "simulate"),
        ("model", "model"),
        ("excite", "excite"),
    ] {
        let o = common::command().args(["schema", arg]).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let generated: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let path = root.join(format!("docs/schemas/{name}.schema.json"));
        let committed: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(
            generated,
            committed,
            "{} is stale: physid schema {arg} > {}",
            path.display(),
            path.display()
        );
        assert_eq!(generated["$id"], format!("physid.{name}/1"));
        let required = generated["required"].as_array().unwrap();
        assert!(required.contains(&"physid_version".into()) && required.contains(&"schema".into()));
    }
}
