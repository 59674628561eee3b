"""Real physid JSON outputs validated against the committed JSON Schemas in docs/schemas/
(generated from the Rust types by `physid schema`): identify --json (the KUKA runs with effect
terms and a validation run, and a physid log with ground truth), diagnose --json (KUKA), and
the blind benchmark's committed scores. Run by scripts/test.sh;
`python scripts/check_schemas.py [--physid PATH]`."""
import json
import os
import sys
import tempfile

import jsonschema

from physid_common import KUKA_URDF, ROOT, arguments, physid_bin, run


def main():
    binary = physid_bin(arguments(__doc__).physid)
    passed = failed = 0

    def check(name, doc, schema_name):
        nonlocal passed, failed
        with open(os.path.join(ROOT, "docs", "schemas", f"{schema_name}.schema.json")) as f:
            schema = json.load(f)
        try:
            jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)
            ok = doc.get("schema") == f"physid.{schema_name}/1"
            detail = "" if ok else f"schema field {doc.get('schema')!r}"
        except jsonschema.ValidationError as e:
            ok, detail = False, f"{'/'.join(map(str, e.absolute_path))}: {e.message[:300]}"
        print(f"{'ok  ' if ok else 'FAIL'} {name}{': ' + detail if detail else ''}")
        passed += ok
        failed += not ok

    k = os.path.join(ROOT, "data", "kuka_lwr4")
    m = [os.path.join(k, f"measurements_{i}.csv") for i in (1, 2, 3)]
    ident = json.loads(run(binary, "identify", "--data", m[0], m[1], "--validate-data", m[2], "--robot", KUKA_URDF,
                           "--constraints", "consistent", "--effects-from",
                           os.path.join(ROOT, "results", "kuka_diagnosis", "report.json"), "--json"))
    check("identify --json (KUKA, effects, validation runs)", ident, "identify")
    with tempfile.TemporaryDirectory() as d:
        log = os.path.join(d, "shell.mcap")
        run(binary, "simulate", os.path.join(ROOT, "scenarios", "cheetah3_shell.toml"), "--out", log, "--duration", "3")
        sim = json.loads(run(binary, "simulate", os.path.join(ROOT, "scenarios", "cheetah3_shell.toml"), "--out",
                             os.path.join(d, "again.mcap"), "--duration", "1", "--json"))
        check("simulate --json", sim, "simulate")
        truth = json.loads(run(binary, "identify", "--data", log, "--json"))
        check("identify --json (physid log with ground truth)", truth, "identify")
        if not truth.get("truth_errors"):
            print("FAIL the log's identify output carries truth_errors"); failed += 1
    check("model --json (KUKA URDF)", json.loads(run(binary, "model", "--robot", KUKA_URDF, "--json")), "model")
    check("model --json (Cheetah leg)", json.loads(run(binary, "model", "--json")), "model")
    check("excite --json (KUKA URDF)", json.loads(run(binary, "excite", "--robot", KUKA_URDF, "--iterations", "20",
                                                       "--duration", "10", "--json")), "excite")
    with open(os.path.join(ROOT, "results", "excitation", "provenance.json")) as f:
        check("results/excitation/provenance.json", json.load(f), "provenance")
    diag = json.loads(run(binary, "diagnose", "--robot", KUKA_URDF, "--constraints", "consistent", "--data", m[0], m[1],
                          "--validate", m[2], "--json"))
    check("diagnose --json (KUKA)", diag, "diagnose")
    with open(os.path.join(ROOT, "results", "kuka_diagnosis", "report.json")) as f:
        check("results/kuka_diagnosis/report.json", json.load(f), "diagnose")
    with open(os.path.join(ROOT, "results", "blind", "scores.json")) as f:
        check("results/blind/scores.json", json.load(f), "blind_scores")
    with open(os.path.join(ROOT, "results", "sample_size", "provenance.json")) as f:
        check("results/sample_size/provenance.json", json.load(f), "provenance")
    print(f"{passed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
