//! docs/ci.md's recipe: the commands between its markers run as written (the binary under
//! test for `physid`, a temporary directory for `target/physid-ci`) and pass against the
//! committed baseline; the GitHub Actions and GitLab CI recipes carry each of them.

#[path = "../../tests/common/mod.rs"]
mod common;

#[test]
fn the_ci_recipe_runs_and_passes_against_the_committed_baseline() {
    let root = &common::root();
    let doc = std::fs::read_to_string(root.join("docs/ci.md")).unwrap();
    let begin = doc.find("# physid-ci-begin").expect("begin marker");
    let end = doc.find("# physid-ci-end").expect("end marker");
    let commands: Vec<&str> = doc[begin..end]
        .lines()
        .skip(1)
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    assert_eq!(commands.len(), 3, "{commands:?}");
    // Both recipes run exactly these lines.
    for c in &commands {
        assert!(
            doc.contains(&format!("- run: {c}")),
            "GitHub recipe lacks: {c}"
        );
        assert!(
            doc.contains(&format!("    - {c}")),
            "GitLab recipe lacks: {c}"
        );
    }
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("physid-ci");
    std::fs::create_dir_all(&work).unwrap();
    for c in &commands {
        let line = c.replace("target/physid-ci", work.to_str().unwrap());
        let line = line.strip_prefix("physid ").expect("a physid command");
        // The recipe's quoting is the shell's: split on spaces outside double quotes.
        let mut args: Vec<String> = vec![];
        let mut quoted = false;
        let mut cur = String::new();
        for ch in line.chars() {
            match ch {
                '"' => quoted = !quoted,
                ' ' if !quoted => {
                    if !cur.is_empty() {
                        args.push(std::mem::take(&mut cur));
                    }
                }
                _ => cur.push(ch),
            }
        }
        args.push(cur);
        let o = common::command()
            .args(&args)
            .current_dir(root)
            .env_remove("GITHUB_STEP_SUMMARY")
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{c}: exit {:?}\n{}{}",
            o.status.code(),
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let md = std::fs::read_to_string(work.join("compare.md")).unwrap();
    assert!(md.contains("**PASS**: 0 of 16 groups regressed"), "{md}");
    let xml = std::fs::read_to_string(work.join("variants.xml")).unwrap();
    assert!(xml.contains("tests=\"3\" failures=\"0\""), "{xml}");
}
