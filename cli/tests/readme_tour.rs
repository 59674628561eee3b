//! The README's tour, run as written: every command between `<!-- tour:begin -->` and
//! `<!-- tour:end -->` (`scripts/physid` standing for this test's binary), in a scratch folder
//! that sees the repository's `data/` and `scenarios/`; each line of the `text` block after a
//! command must appear in what that command printed (`…` standing for any text within the line).

#[path = "../../tests/common/mod.rs"]
mod common;

use std::path::Path;

/// A command of the tour and the lines it must print.
struct Step {
    words: Vec<String>,
    shows: Vec<String>,
}

/// The tour's steps, from the README's fenced `sh` and `text` blocks between the markers.
fn tour(readme: &str) -> Vec<Step> {
    let begin = readme
        .find("<!-- tour:begin -->")
        .expect("tour:begin marker");
    let end = readme.find("<!-- tour:end -->").expect("tour:end marker");
    let (mut steps, mut block, mut kind): (Vec<Step>, Vec<String>, Option<String>) =
        (vec![], vec![], None);
    for line in readme[begin..end].lines() {
        match (line.strip_prefix("```"), &kind) {
            (Some(lang), None) => kind = Some(lang.to_string()),
            (Some(_), Some(k)) => {
                let lines = std::mem::take(&mut block);
                if k == "sh" {
                    steps.extend(lines.iter().map(|l| Step {
                        words: l.split_whitespace().map(String::from).collect(),
                        shows: vec![],
                    }));
                } else if let Some(last) = steps.last_mut() {
                    last.shows = lines;
                }
                kind = None;
            }
            (None, Some(_)) => block.push(line.to_string()),
            (None, None) => {}
        }
    }
    steps
}

/// Whether `line`'s pieces between `…` appear, in order, within one line of `printed`.
fn shows(printed: &str, line: &str) -> bool {
    printed.lines().any(|out| {
        let mut at = 0;
        line.split('…')
            .all(|piece| match out[at..].find(piece.trim()) {
                Some(i) => {
                    at += i + piece.trim().len();
                    true
                }
                None => false,
            })
    })
}

fn run(step: &Step, dir: &Path) -> String {
    let (program, args) = step.words.split_first().expect("a command");
    if program == "mkdir" {
        let folder = args.last().expect("mkdir's folder");
        std::fs::create_dir_all(dir.join(folder)).unwrap();
        return String::new();
    }
    assert_eq!(program, "scripts/physid", "the tour runs physid only");
    let out = std::process::Command::new(common::exe())
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    let printed = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{}:\n{printed}", step.words.join(" "));
    printed
}

#[test]
fn the_readme_tour_runs_as_written_and_prints_what_it_shows() {
    let root = common::root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let steps = tour(&readme);
    assert!(
        steps.iter().filter(|s| !s.shows.is_empty()).count() >= 3,
        "the tour shows what simulate, identify and diagnose print"
    );
    let dir = tempfile::tempdir().unwrap();
    for shared in ["data", "scenarios"] {
        std::os::unix::fs::symlink(root.join(shared), dir.path().join(shared)).unwrap();
    }
    for step in &steps {
        let printed = run(step, dir.path());
        for line in &step.shows {
            assert!(
                shows(&printed, line),
                "{}: the README shows\n  {line}\nbut it printed:\n{printed}",
                step.words.join(" ")
            );
        }
    }
    assert!(dir.path().join("tour/diagnosis/report.md").is_file());
}

#[test]
fn a_shown_line_must_be_printed_piece_by_piece_in_order() {
    let printed = "overall RMS: train 0.2362 N m, validation 0.3950 N m\nother";
    assert!(shows(
        printed,
        "overall RMS: train 0.2362 N m, validation 0.3950 N m"
    ));
    assert!(shows(printed, "overall RMS: … validation 0.3950"));
    assert!(!shows(printed, "validation 0.3950 … overall RMS"));
    assert!(!shows(printed, "overall RMS: train 0.2363"));
}
