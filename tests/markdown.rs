//! Every Markdown report parses as CommonMark tables (pulldown-cmark) with each row as wide as
//! its header, the expected columns, and cells that carry `|` intact (`|qd| low`, `a|b`).

use physid::sim::scenario::EffectSpec;
use pulldown_cmark::{Event, Options, Parser, Tag, TagEnd};

/// The tables of `md`: per table, its rows of cell texts (header first).
fn tables(md: &str) -> Vec<Vec<Vec<String>>> {
    let mut out: Vec<Vec<Vec<String>>> = vec![];
    let (mut row, mut cell): (Vec<String>, Option<String>) = (vec![], None);
    for ev in Parser::new_ext(md, Options::ENABLE_TABLES) {
        match ev {
            Event::Start(Tag::Table(_)) => out.push(vec![]),
            Event::Start(Tag::TableHead) | Event::Start(Tag::TableRow) => row.clear(),
            Event::End(TagEnd::TableHead) | Event::End(TagEnd::TableRow) => {
                out.last_mut().unwrap().push(std::mem::take(&mut row))
            }
            Event::Start(Tag::TableCell) => cell = Some(String::new()),
            Event::End(TagEnd::TableCell) => row.push(cell.take().unwrap_or_default()),
            Event::Text(t) | Event::Code(t) => {
                if let Some(c) = cell.as_mut() {
                    c.push_str(&t)
                }
            }
            _ => {}
        }
    }
    out
}

/// Checks that every row of every table is as wide as its header; returns the tables.
fn well_formed(md: &str) -> Vec<Vec<Vec<String>>> {
    let t = tables(md);
    assert!(!t.is_empty(), "no table in:\n{md}");
    for table in &t {
        let width = table[0].len();
        for r in table {
            assert_eq!(r.len(), width, "row {r:?} vs header {:?}", table[0]);
        }
    }
    t
}

#[test]
fn the_diagnosis_report_parses_with_its_columns() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/blind.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(&path).unwrap();
    sc.simulation.duration = 12.0;
    sc.effects = vec![EffectSpec::TorqueOffset {
        offset: vec![0.0, 1.5, 0.0],
    }];
    let rec = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
    let d = &rec.processed;
    let diag = physid::diagnose::diagnose(
        &m,
        &d.slice(0..8000),
        &d.slice(8000..d.len()),
        &Default::default(),
    )
    .unwrap();
    let md = physid::diagnose::report::markdown(&diag);
    let t = well_formed(&md);
    let headers: Vec<&Vec<String>> = t.iter().map(|x| &x[0]).collect();
    let has = |cols: &[&str]| {
        headers
            .iter()
            .any(|h| h.iter().map(String::as_str).eq(cols.iter().copied()))
    };
    assert!(
        has(&["joint", "regime", "samples", "RMS", "share"]),
        "{headers:?}"
    );
    assert!(
        headers
            .iter()
            .any(|h| h.len() == 2 + 3 && h[0] == "step" && h[4] == "all"),
        "{headers:?}"
    );
    // The regime cells keep their |qd| (escaped pipes are not column breaks).
    let where_table = t.iter().find(|x| x[0][1] == "regime").unwrap();
    assert!(
        where_table.iter().any(|r| r[1].starts_with("|qd| low")),
        "{where_table:?}"
    );
}

#[test]
fn a_case_table_with_ambiguity_groups_parses() {
    use polars::prelude::*;
    let df = df!(
        "case" => [0u32, 1],
        "found" => ["torque_offset|asymmetric_coulomb", ""],
        "gap" => [0.5f64, 0.1],
    )
    .unwrap();
    let md = physid::experiment::tables::markdown(&df);
    let t = well_formed(&md);
    assert_eq!(t[0][0], vec!["case", "found", "gap"]);
    assert_eq!(t[0][1][1], "torque_offset|asymmetric_coulomb");
}
