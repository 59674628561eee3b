//! The crate's layering (docs/architecture.md §6): every module imports only from floors below
//! its own. Checked on the source text: each `crate::m` path outside comments and outside
//! `#[cfg(test)]` modules (which may build fixtures with anything) names a module `m` of a lower
//! floor, or the module itself.

mod common;

use std::path::{Path, PathBuf};

/// The floor of each top-level module of the library (the binary, crate `physid-cli` in cli/,
/// is the floor above them all and reaches the library through `physid::` only).
const FLOORS: [(&str, u8); 17] = [
    ("conic", 0),
    ("spatial", 1),
    ("options", 1),
    ("signal", 1),
    ("linalg", 1),
    ("trajectory", 1),
    ("model", 2),
    ("prepare", 2),
    ("io", 3),
    ("dynamics", 3),
    ("effect", 4),
    ("sim", 5),
    ("ident", 5),
    ("diagnose", 6),
    ("experiment", 7),
    ("bench", 8),
    ("api", 9),
];

fn floor(module: &str) -> Option<u8> {
    FLOORS.iter().find(|(m, _)| *m == module).map(|(_, f)| *f)
}

/// The floors' own crates (`crates/NAME`), in floor order: the ground floors (`core`, floors
/// 0 to 3), then crates whose root is one module of the floor of that name.
const CRATES: [&str; 8] = [
    "core",
    "io",
    "effect",
    "ident",
    "sim",
    "diagnose",
    "experiment",
    "bench",
];

/// The library's source folders: the `physid` crate's (the api facade) and its floors' crates.
/// Cargo refuses an import of a crate not depended on; the checks below hold every crate to
/// the rules Cargo cannot see (floors inside one crate, function length, printing, …).
fn library_roots() -> Vec<PathBuf> {
    let root = common::root();
    let mut roots = vec![root.join("src")];
    roots.extend(CRATES.iter().map(|c| root.join(format!("crates/{c}/src"))));
    let on_disk = std::fs::read_dir(root.join("crates")).unwrap().count();
    assert_eq!(
        on_disk,
        CRATES.len(),
        "a crate under crates/ not listed in CRATES"
    );
    roots
}

/// The module a crate's root is, for the floors' crates whose root is one module (all but
/// `core`); `None` for crates of several modules (the library's, the ground floors').
fn root_module(src: &Path) -> Option<&'static str> {
    CRATES[1..]
        .iter()
        .copied()
        .find(|m| src.ends_with(format!("crates/{m}/src")))
}

/// A library file's path as a module path below the library's root (`rel`: its path below its
/// source folder `src`): in a crate whose root is one module, `io/cache.rs`, `effect/mod.rs`
/// for its `lib.rs` (`prepare.rs` of the io crate is its own module).
fn logical(src: &Path, rel: &Path) -> PathBuf {
    match root_module(src) {
        Some("io") if rel == Path::new("prepare.rs") => rel.to_path_buf(),
        Some(m) if rel == Path::new("lib.rs") => Path::new(m).join("mod.rs"),
        Some(m) => Path::new(m).join(rel),
        None => rel.to_path_buf(),
    }
}

/// The floor module a library file belongs to: its logical path's first component.
fn module_of(src: &Path, rel: &Path) -> String {
    let logical = logical(src, rel);
    let first = logical.components().next().unwrap();
    first
        .as_os_str()
        .to_string_lossy()
        .trim_end_matches(".rs")
        .to_string()
}

/// The floor module `crate::name` names from a file under `src`: that of a file `name.rs` at
/// its root (in a crate whose root is one module, any name but the io crate's `prepare` is an
/// item of that module).
fn target_of(src: &Path, name: &str) -> String {
    module_of(src, Path::new(&format!("{name}.rs")))
}

/// Every `.rs` file of the library, with the source folder it is under.
fn library_files() -> Vec<(PathBuf, PathBuf)> {
    let mut out = vec![];
    for src in library_roots() {
        let mut files = vec![];
        rust_files(&src, &mut files);
        assert!(
            files.len() >= 4,
            "{}: the file walk found nothing",
            src.display()
        );
        out.extend(files.into_iter().map(|f| (src.clone(), f)));
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The source without comments and without `#[cfg(test)]` items (everything after the first
/// `#[cfg(test)]`, where physid keeps its unit tests).
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The top-level modules a file's code names as `crate::m` (a `crate::__name` is a
/// `#[macro_export]` macro, which Rust places at the crate's root whatever module defines it:
/// not a module).
fn imports(code: &str) -> Vec<String> {
    code.match_indices("crate::")
        .map(|(i, _)| {
            code[i + 7..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect::<String>()
        })
        .filter(|name| !name.starts_with("__"))
        .collect()
}

#[test]
fn every_module_imports_only_from_lower_floors() {
    let mut violations = vec![];
    let mut checked = 0;
    for (src, file) in &library_files() {
        let rel = file.strip_prefix(src).unwrap();
        let module = module_of(src, rel);
        if module == "lib" {
            continue;
        }
        let own =
            floor(&module).unwrap_or_else(|| panic!("{}: module without a floor", rel.display()));
        let text = std::fs::read_to_string(file).unwrap();
        for target in imports(&code(&text)) {
            let target = target_of(src, &target);
            checked += 1;
            let target_floor = floor(&target)
                .unwrap_or_else(|| panic!("{}: crate::{target} has no floor", rel.display()));
            if target != module && target_floor >= own {
                violations.push(format!(
                    "{} (floor {own}) imports crate::{target} (floor {target_floor})",
                    rel.display()
                ));
            }
        }
    }
    violations.sort();
    violations.dedup();
    assert!(
        checked > 100,
        "only {checked} imports found: the scan is broken"
    );
    assert!(
        violations.is_empty(),
        "imports from the same or a higher floor:\n{}",
        violations.join("\n")
    );
}

/// The names that follow each `prefix` in `code`: `prefix{a, b::c}` names `a` and `b`.
fn names_after(code: &str, prefix: &str) -> Vec<String> {
    let mut out = vec![];
    for (i, _) in code.match_indices(prefix) {
        let rest = &code[i + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let group = &group[..group.find('}').unwrap_or(group.len())];
            out.extend(
                group
                    .split(',')
                    .map(|s| s.trim().split("::").next().unwrap_or("").to_string()),
            );
        } else {
            out.push(
                rest.chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect(),
            );
        }
    }
    out
}

/// The child modules of `dir` as (module name, path): its `.rs` files other than `mod.rs`, and
/// its folders with a `mod.rs` (that file's path).
fn child_files(dir: &Path) -> Vec<(String, PathBuf)> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter_map(|p| {
            let name = p.file_stem().unwrap().to_string_lossy().to_string();
            if p.is_dir() {
                let m = p.join("mod.rs");
                m.is_file().then_some((name, m))
            } else {
                p.extension()
                    .is_some_and(|e| e == "rs")
                    .then_some((name, p))
            }
        })
        .filter(|(stem, _)| stem != "mod" && stem != "lib")
        .collect()
}

/// The code a child module of a folder reaches its siblings with: a file's code, or for a
/// folder module its `mod.rs` plus the `crate::` paths of its other files (their `super::` is
/// the folder module itself, not a sibling).
fn module_code(path: &Path) -> String {
    let mut text = code(&std::fs::read_to_string(path).unwrap());
    if path.file_name().is_some_and(|n| n == "mod.rs") {
        for (_, nested) in child_files(path.parent().unwrap()) {
            let inner = code(&std::fs::read_to_string(&nested).unwrap());
            for (i, _) in inner.match_indices("crate::") {
                let end = inner[i..].find([';', '\n']).map_or(inner.len(), |e| i + e);
                text.push('\n');
                text.push_str(&inner[i..end]);
            }
        }
    }
    text
}

/// The sibling files a file of `folder` (its path under `src/`, e.g. `diagnose`) names: as
/// `super::name` or `crate::folder::name`, for `name` among `siblings` (mod.rs is not one).
fn sibling_imports(code: &str, folder: &str, siblings: &[String]) -> Vec<String> {
    // A crate's root folder (the io crate's, `folder` empty) names its files `crate::x`.
    let crate_path = match folder {
        "" => "crate::".to_string(),
        _ => format!("crate::{}::", folder.replace('/', "::")),
    };
    let mut out: Vec<String> = ["super::", crate_path.as_str()]
        .into_iter()
        .flat_map(|prefix| names_after(code, prefix))
        .filter(|n| siblings.contains(n))
        .collect();
    out.sort();
    out.dedup();
    out
}

/// A cycle in `edges` (file → the siblings it imports), as its files in order, if any.
fn find_cycle(edges: &std::collections::BTreeMap<String, Vec<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        edges: &std::collections::BTreeMap<String, Vec<String>>,
        path: &mut Vec<String>,
        done: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == node) {
            return Some(path[at..].to_vec());
        }
        if done.iter().any(|d| d == node) {
            return None;
        }
        path.push(node.to_string());
        for next in edges.get(node).into_iter().flatten() {
            if let Some(c) = visit(next, edges, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.push(node.to_string());
        None
    }
    let mut done = vec![];
    edges
        .keys()
        .find_map(|k| visit(k, edges, &mut vec![], &mut done))
}

#[test]
fn no_import_circle_among_the_files_of_a_folder() {
    let mut folders = vec![];
    let mut stack: Vec<(PathBuf, PathBuf)> = library_roots()
        .into_iter()
        .map(|r| (r.clone(), r))
        .collect();
    while let Some((src, dir)) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push((src.clone(), path.clone()));
                folders.push((src.clone(), path));
            }
        }
    }
    // The single-module crates' roots are their modules' folders.
    for m in &CRATES[1..] {
        let root = common::root().join(format!("crates/{m}/src"));
        folders.push((root.clone(), root));
    }
    let mut circles = vec![];
    let mut edges_seen = 0;
    for (src, dir) in &folders {
        let folder = dir.strip_prefix(src).unwrap().to_string_lossy().to_string();
        let files = child_files(dir);
        let siblings: Vec<String> = files.iter().map(|(stem, _)| stem.clone()).collect();
        let mut edges = std::collections::BTreeMap::new();
        for (stem, f) in &files {
            let code = module_code(f);
            let to: Vec<String> = sibling_imports(&code, &folder, &siblings)
                .into_iter()
                .filter(|t| t != stem)
                .collect();
            edges_seen += to.len();
            edges.insert(stem.clone(), to);
        }
        if let Some(c) = find_cycle(&edges) {
            circles.push(format!("src/{folder}: {} -> {}", c.join(" -> "), c[0]));
        }
    }
    assert!(
        edges_seen > 20,
        "only {edges_seen} imports between sibling files: the scan is broken"
    );
    assert!(
        circles.is_empty(),
        "import circles:\n{}",
        circles.join("\n")
    );
}

/// The names a file reaches through `super::` or `crate::` that are not sibling modules: items
/// of its folder's `mod.rs` or crate's `lib.rs` (a back arrow to the parent that calls it).
fn back_arrows(code: &str, siblings: &[String]) -> Vec<String> {
    // In a crate whose root is the folder, `crate::name` reaches the root (lib.rs) too.
    let mut out: Vec<String> = ["super::", "crate::"]
        .into_iter()
        .flat_map(|prefix| names_after(code, prefix))
        .filter(|n| !n.is_empty() && n != "self" && !siblings.contains(n))
        .collect();
    out.sort();
    out.dedup();
    out
}

/// Folders whose `mod.rs` (or a crate's `lib.rs`) only declares and re-exports: a pipeline of
/// steps (its files import each other, never the parent that runs them). Other folders keep
/// the floor's shared types in `mod.rs` (`io::IoError`, `dynamics::Data`, `model::Model`),
/// which their files build on.
const PIPELINE_FOLDERS: [&str; 1] = ["crates/diagnose/src"];

#[test]
fn no_back_arrow_to_mod_rs_inside_a_pipeline_folder() {
    let root = common::root();
    let mut arrows = vec![];
    let mut files_seen = 0;
    for folder in PIPELINE_FOLDERS {
        let files = child_files(&root.join(folder));
        let siblings: Vec<String> = files.iter().map(|(stem, _)| stem.clone()).collect();
        for (stem, f) in &files {
            files_seen += 1;
            let code = module_code(f);
            for name in back_arrows(&code, &siblings) {
                arrows.push(format!("{folder}/{stem}.rs: super::{name}"));
            }
        }
    }
    assert!(files_seen > 15, "only {files_seen} files scanned");
    assert!(
        arrows.is_empty(),
        "imports of mod.rs items inside a pipeline folder:\n{}",
        arrows.join("\n")
    );
    let stage = code("use super::{stage::Stage, residual};\nuse super::Stage;\n");
    assert_eq!(
        back_arrows(&stage, &["stage".into(), "residual".into()]),
        vec!["Stage".to_string()]
    );
}

#[test]
fn the_circle_check_sees_a_circle_when_there_is_one() {
    let siblings = vec![
        "kinds".to_string(),
        "library".to_string(),
        "context".to_string(),
    ];
    let code = code(
        "use super::library::{Context, Kind};\nuse super::{context, residual};\n// super::kinds\n",
    );
    assert_eq!(
        sibling_imports(&code, "diagnose", &siblings),
        vec!["context".to_string(), "library".to_string()]
    );
    let mut edges = std::collections::BTreeMap::new();
    edges.insert("a".to_string(), vec!["b".to_string()]);
    edges.insert("b".to_string(), vec!["c".to_string()]);
    edges.insert("c".to_string(), vec![]);
    assert_eq!(find_cycle(&edges), None);
    edges.insert("c".to_string(), vec!["a".to_string()]);
    assert_eq!(
        find_cycle(&edges),
        Some(vec!["a".to_string(), "b".to_string(), "c".to_string()])
    );
}

/// Whether a (trimmed) line starts a function with a body on the lines below: any
/// visibility (`pub`, `pub(crate)`, `pub(in path)`), then any of `const`, `async`, `unsafe`,
/// `extern "ABI"`, then `fn`; not a declaration without a body (`;`) or a one-line function.
fn opens_a_function_body(t: &str) -> bool {
    let mut rest = t;
    if let Some(r) = rest.strip_prefix("pub") {
        rest = match r.strip_prefix('(') {
            Some(inner) => match inner.find(')') {
                Some(close) => inner[close + 1..].trim_start(),
                None => return false,
            },
            None if r.starts_with(' ') => r.trim_start(),
            None => return false,
        };
    }
    loop {
        let before = rest;
        for q in ["const ", "async ", "unsafe "] {
            rest = rest.strip_prefix(q).unwrap_or(rest);
        }
        if let Some(r) = rest.strip_prefix("extern ") {
            let r = r.trim_start();
            rest = match r.strip_prefix('"') {
                Some(abi) => abi
                    .split_once('"')
                    .map_or(r, |(_, after)| after.trim_start()),
                None => r,
            };
        }
        if rest == before {
            break;
        }
    }
    let line = t.trim_end();
    rest.starts_with("fn ") && !line.ends_with(';') && !(line.contains('{') && line.ends_with('}'))
}

#[test]
fn a_function_opens_with_any_visibility_and_qualifiers() {
    for yes in [
        "fn f() {",
        "pub fn f(",
        "pub(crate) fn f<T>(x: T) -> T {",
        "pub(in crate::io) fn f() {",
        "pub(super) const fn f() -> u8 {",
        "const fn f() {",
        "pub unsafe extern \"C\" fn f() {",
        "async fn f() {",
    ] {
        assert!(opens_a_function_body(yes), "{yes}");
    }
    for no in [
        "fn f(&self) -> u8;",
        "pub const fn f() -> u8 { 1 }",
        "let fn_name = 3;",
        "pub struct F {",
        "// fn in a comment",
        "pubfn f() {",
    ] {
        assert!(!opens_a_function_body(no), "{no}");
    }
}

#[test]
fn no_function_is_longer_than_60_lines() {
    // The library's, the binary's and the Python extension's.
    let mut files: Vec<PathBuf> = library_files().into_iter().map(|(_, f)| f).collect();
    for glue in ["cli/src", "python/src"] {
        let before = files.len();
        rust_files(&common::root().join(glue), &mut files);
        assert!(files.len() > before, "{glue}: the file walk found nothing");
    }
    let mut long = vec![];
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let t = line.trim_start();
            if !opens_a_function_body(t) {
                continue;
            }
            let indent = line.len() - t.len();
            // The function ends at the first line that closes its brace at its own indentation.
            let end = lines[i..]
                .iter()
                .position(|l| {
                    l.starts_with(&" ".repeat(indent))
                        && l.trim_end() == format!("{}}}", " ".repeat(indent))
                })
                .map(|k| i + k);
            if let Some(end) = end {
                if end - i + 1 > 60 {
                    long.push(format!(
                        "{}:{} {} lines",
                        file.strip_prefix(common::root()).unwrap().display(),
                        i + 1,
                        end - i + 1
                    ));
                }
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over 60 lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn the_scan_sees_a_violation_when_there_is_one() {
    // The checker itself: a floor-3 file naming a floor-5 module is caught, comments are not.
    let code = code("use crate::sim::simulate;\n// crate::experiment in a comment\nfn f() {}\n");
    assert_eq!(imports(&code), vec!["sim".to_string()]);
    assert!(floor("sim").unwrap() > floor("io").unwrap());
}

#[test]
fn the_entry_modules_stay_short() {
    // The diagnosis is a sequence of named steps and the CLI a dispatcher over one file per
    // command (argument parsing and printing): their sizes stay under those docs/architecture.md
    // §6 states.
    let root = common::root();
    let mut files = vec![("crates/diagnose/src/lib.rs".to_string(), 400)];
    let mut cli = vec![];
    rust_files(&root.join("cli/src"), &mut cli);
    assert!(cli.len() > 10, "the CLI's files not found");
    for f in cli {
        let rel = f.strip_prefix(&root).unwrap().display().to_string();
        let limit = if rel.ends_with("main.rs") { 160 } else { 520 };
        files.push((rel, limit));
    }
    for (file, limit) in files {
        let lines = std::fs::read_to_string(root.join(&file))
            .unwrap()
            .lines()
            .count();
        assert!(lines < limit, "{file} has {lines} lines (limit {limit})");
    }
}

/// The files of `crates/effect/src/` that are not a kind's: the table, the checks and trait of the
/// simulator's form, the per-data state, the columns over a data set, the dead zone's dynamics,
/// the encoder-shifted inverse dynamics.
const EFFECT_SHARED: [&str; 7] = [
    "mod",
    "lib",
    "physics",
    "context",
    "library",
    "dead_zone",
    "shifted",
];

/// Lines of library code outside the kinds' own files that name a particular kind, as
/// `Kind::X` (the diagnosis's table) or `EffectSpec::X` (the simulator's form).
fn kind_branches(rel: &Path, text: &str) -> Vec<String> {
    let mut out = vec![];
    for (i, line) in text.lines().enumerate() {
        let named = |prefix: &str| {
            line.match_indices(prefix).any(|(at, _)| {
                let before = &line[..at];
                let after = &line[at + prefix.len()..];
                !before.ends_with("Shape")
                    && !after.starts_with("ALL")
                    && after.starts_with(|c: char| c.is_ascii_uppercase() || c == '*')
            })
        };
        if named("Kind::") || named("EffectSpec::") {
            out.push(format!("{}:{}: {}", rel.display(), i + 1, line.trim()));
        }
    }
    out
}

#[test]
fn effect_kinds_are_matched_only_in_their_files() {
    // A new effect kind is one file of `crates/effect/src/` (its row of the table and its simulator
    // form): no other library file names a particular kind, neither its `Kind` nor its
    // `EffectSpec` variant (tests and the CLI's flag names aside). The table's `mod.rs` lists
    // them, and the semi-real benchmark's order of injected kinds is kept there.
    let mut branching = vec![];
    for (src, file) in &library_files() {
        let rel = &logical(src, file.strip_prefix(src).unwrap());
        let stem = rel.file_stem().unwrap().to_str().unwrap();
        let kind_file = rel.starts_with("effect") && !EFFECT_SHARED.contains(&stem);
        if kind_file || rel == Path::new("effect/mod.rs") {
            continue;
        }
        let text = code(&std::fs::read_to_string(file).unwrap());
        branching.extend(kind_branches(rel, &text));
    }
    assert!(
        branching.is_empty(),
        "kind-specific branches outside the kinds' files:\n{}",
        branching.join("\n")
    );
    // The check sees both spellings.
    let seen = kind_branches(
        Path::new("x.rs"),
        "let a = Kind::Spring;\nlet b = EffectSpec::Tilt(t);\nlet c = Kind::ALL;\n",
    );
    assert_eq!(seen.len(), 2, "{seen:?}");
}

#[test]
fn anyhow_and_printing_stay_in_the_binary() {
    // The library returns typed errors and never prints; anyhow and the one error print live
    // in the binary (cli/).
    let mut found = vec![];
    for (src, file) in &library_files() {
        let rel = file.strip_prefix(src).unwrap();
        let text = code(&std::fs::read_to_string(file).unwrap());
        for (i, line) in text.lines().enumerate() {
            if ["anyhow", "println!", "eprintln!"]
                .iter()
                .any(|w| line.contains(w))
            {
                found.push(format!("{}:{}: {}", rel.display(), i + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "in the library:\n{}", found.join("\n"));
}

/// A workspace manifest (`path` below the repository's root), parsed.
fn manifest(path: &str) -> toml::Table {
    toml::from_str(&std::fs::read_to_string(common::root().join(path)).unwrap()).unwrap()
}

#[test]
fn the_library_crate_has_no_command_line_dependencies() {
    // The workspace's split: argument parsing, anyhow, progress bars and signals belong to the
    // binary's crate (cli/Cargo.toml), not to the library a Python package or another tool
    // links.
    let deps = |m: &toml::Table| -> Vec<String> {
        m["dependencies"]
            .as_table()
            .unwrap()
            .keys()
            .cloned()
            .collect()
    };
    let library = deps(&manifest("Cargo.toml"));
    let binary = deps(&manifest("cli/Cargo.toml"));
    assert!(library.iter().any(|d| d == "clarabel"), "{library:?}");
    // The floors' own crates are the library too.
    let floors: Vec<(String, Vec<String>)> = CRATES
        .iter()
        .map(|c| format!("crates/{c}/Cargo.toml"))
        .map(|p| (p.clone(), deps(&manifest(&p))))
        .collect();
    for cli_only in ["clap", "anyhow", "indicatif", "libc"] {
        assert!(
            !library.iter().any(|d| d == cli_only),
            "the library depends on {cli_only}"
        );
        for (path, floor) in &floors {
            assert!(
                !floor.iter().any(|d| d == cli_only),
                "{path} depends on {cli_only}"
            );
        }
        assert!(
            binary.iter().any(|d| d == cli_only),
            "cli/ lacks {cli_only}"
        );
    }
    let cli = manifest("cli/Cargo.toml");
    let bin = &cli["bin"].as_array().unwrap()[0];
    assert_eq!(bin["name"].as_str(), Some("physid"));
}

#[test]
fn the_api_floor_returns_named_types_not_tuples() {
    // The entry points the binary and the Python package stand on return and hold named
    // types (a field per value, documented), never an anonymous tuple or a String error.
    let api = common::root().join("src/api");
    let mut files = vec![];
    rust_files(&api, &mut files);
    let mut found = vec![];
    for file in &files {
        let text = code(&std::fs::read_to_string(file).unwrap());
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let first = line.trim_start();
            // A signature over several lines is read whole, up to its body or `;`.
            let t = if first.starts_with("pub fn ") {
                let mut sig = String::new();
                for l in &lines[i..] {
                    sig.push_str(l.trim());
                    if l.contains('{') || l.trim_end().ends_with(';') {
                        break;
                    }
                }
                sig
            } else {
                first.to_string()
            };
            let t = t.as_str();
            let public = t.starts_with("pub fn ") || (t.starts_with("pub ") && t.contains(": "));
            let tuple = (t.contains("-> (") && !t.contains("-> ()"))
                || (t.contains("Result<(") && !t.contains("Result<()"))
                || t.contains(", String>")
                || (t.starts_with("pub ") && !t.starts_with("pub fn") && t.contains(": ("));
            if public && tuple {
                found.push(format!(
                    "{}:{}: {t}",
                    file.strip_prefix(&api).unwrap().display(),
                    i + 1
                ));
            }
        }
    }
    assert!(files.len() >= 8, "src/api not found");
    assert!(found.is_empty(), "in the api floor:\n{}", found.join("\n"));
}

#[test]
fn the_model_is_immutable_its_fields_private() {
    // pinocchio's Model: read through accessors, changed only by building another
    // (`with_parameters`, `with_bodies_edited`, ...), so that no edit leaves its layout stale.
    let text =
        std::fs::read_to_string(common::root().join("crates/core/src/model/mod.rs")).unwrap();
    let start = text
        .find("pub struct Model {")
        .expect("Model in crates/core/src/model/mod.rs");
    let body = &text[start..start + text[start..].find("\n}").unwrap()];
    let public: Vec<&str> = body
        .lines()
        .skip(1)
        .map(str::trim)
        .filter(|l| l.starts_with("pub"))
        .collect();
    assert!(
        body.lines().count() > 5,
        "the scan did not find Model's fields"
    );
    assert!(public.is_empty(), "public fields of Model: {public:?}");
}

/// The entries of the `effect_kinds!` list in `crates/effect/src/lib.rs`: per entry its module, its
/// `Kind` variant and its `EffectSpec` variant (each when given).
fn effect_entries(table: &str) -> Vec<(String, Option<String>, Option<String>)> {
    let head = "\neffect_kinds! {\n";
    let list = &table[table.find(head).expect("the effect_kinds! list") + head.len() - 1..];
    let list = &list[..list.find("\n}").unwrap()];
    let mut entries = vec![];
    let mut keyword = None;
    for line in list.lines().map(str::trim) {
        if let Some(module) = line.strip_suffix(" {") {
            entries.push((module.to_string(), None, None));
        } else if line == "kind" || line == "effect" {
            keyword = Some(line.to_string());
        } else if let Some(name) = line.strip_suffix(',') {
            let entry = entries.last_mut().expect("an entry");
            let slot = match keyword.take().as_deref() {
                Some("kind") => &mut entry.1,
                Some("effect") => &mut entry.2,
                _ => panic!("{name}: neither a kind nor an effect"),
            };
            *slot = Some(name.to_string());
        }
    }
    entries
}

#[test]
fn every_effect_kind_has_its_own_file_and_one_entry_in_the_list() {
    // The kinds are the entries of `effect_kinds!` (the macro makes `Kind`, `KIND_TABLE`,
    // `EffectSpec` and its `physics()` arms from them, and checks at compile time that each
    // table row is its own kind's); each entry's module is `crates/effect/src/<module>.rs`, named
    // after its variants, holding the kind's row (`SPEC`, naming that variant) and, for the
    // simulator's form, its struct and `impl Physics`; every file of the folder is an entry's
    // or one of the shared ones.
    let dir = common::root().join("crates/effect/src");
    let table = std::fs::read_to_string(dir.join("lib.rs")).unwrap();
    let entries = effect_entries(&table);
    let kinds = entries.iter().filter(|e| e.1.is_some()).count();
    let specs = entries.iter().filter(|e| e.2.is_some()).count();
    assert!(kinds >= 13 && specs >= 13, "{entries:?}");
    let snake = |v: &str| {
        let mut out = String::new();
        for (i, c) in v.chars().enumerate() {
            if c.is_ascii_uppercase() && i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        }
        out
    };
    let mut missing = vec![];
    for (module, kind, spec) in &entries {
        let Ok(text) = std::fs::read_to_string(dir.join(format!("{module}.rs"))) else {
            missing.push(format!("{module}: no file crates/effect/src/{module}.rs"));
            continue;
        };
        for name in kind.iter().chain(spec) {
            if snake(name) != *module {
                missing.push(format!("{name}: in the entry of {module}"));
            }
        }
        if let Some(v) = kind {
            if !(text.contains("pub(super) const SPEC: KindSpec")
                && text.contains(&format!("Kind::{v},")))
            {
                missing.push(format!("{v}: {module}.rs holds no SPEC row of Kind::{v}"));
            }
        }
        if let Some(v) = spec {
            if !(text.contains(&format!("pub struct {v} {{"))
                && text.contains(&format!("impl Physics for {v} {{")))
            {
                missing.push(format!(
                    "{v}: {module}.rs holds no struct {v} with its Physics"
                ));
            }
        }
    }
    for (file, _) in child_files(&dir) {
        let owned = EFFECT_SHARED.contains(&file.as_str()) || entries.iter().any(|e| e.0 == file);
        if !owned {
            missing.push(format!(
                "crates/effect/src/{file}.rs is neither an entry's nor a shared file"
            ));
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
    // The list's reader sees both kinds of entry.
    let sample = "x\neffect_kinds! {\n    a_b {\n        kind\n            /// d\n            AB,\n    }\n    c {\n        effect\n            C,\n    }\n}\n";
    assert_eq!(
        effect_entries(sample),
        vec![
            ("a_b".to_string(), Some("AB".to_string()), None),
            ("c".to_string(), None, Some("C".to_string()))
        ]
    );
}

/// The crates' floors (docs/architecture.md §6): core → io → ident | effect → sim → diagnose →
/// experiment → bench → physid (the api) → cli | python. Cargo refuses a circle between crates
/// but not an edge up the floors (io depending on sim, say, while sim does not depend on io).
const CRATE_FLOORS: [(&str, u8); 11] = [
    ("physid-core", 0),
    ("physid-io", 1),
    ("physid-effect", 2),
    ("physid-ident", 2),
    ("physid-sim", 3),
    ("physid-diagnose", 4),
    ("physid-experiment", 5),
    ("physid-bench", 6),
    ("physid", 7),
    ("physid-cli", 8),
    ("physid-python", 8),
];

/// Each workspace crate's manifest and the workspace crates it depends on (path dependencies,
/// normal and build; a crate's tests may use any crate below or above).
fn crate_edges() -> Vec<(String, Vec<String>)> {
    let mut manifests: Vec<String> = ["Cargo.toml", "cli/Cargo.toml", "python/Cargo.toml"]
        .map(String::from)
        .to_vec();
    manifests.extend(CRATES.iter().map(|c| format!("crates/{c}/Cargo.toml")));
    manifests
        .iter()
        .map(|path| {
            let m = manifest(path);
            let name = m["package"]["name"].as_str().unwrap().to_string();
            let deps = ["dependencies", "build-dependencies"]
                .iter()
                .filter_map(|k| m.get(*k).and_then(|d| d.as_table()))
                .flat_map(|t| t.iter())
                .filter(|(_, v)| v.get("path").is_some())
                .map(|(k, v)| {
                    v.get("package")
                        .and_then(|p| p.as_str())
                        .unwrap_or(k)
                        .to_string()
                })
                .collect();
            (name, deps)
        })
        .collect()
}

#[test]
fn no_crate_depends_on_one_of_its_own_floor_or_above() {
    let floor_of = |name: &str| {
        CRATE_FLOORS
            .iter()
            .find(|(c, _)| *c == name)
            .map(|(_, f)| *f)
            .unwrap_or_else(|| panic!("crate {name} has no floor in CRATE_FLOORS"))
    };
    let edges = crate_edges();
    assert_eq!(edges.len(), CRATE_FLOORS.len());
    let mut up = vec![];
    for (name, deps) in &edges {
        for dep in deps {
            if floor_of(dep) >= floor_of(name) {
                up.push(format!(
                    "{name} (floor {}) -> {dep} (floor {})",
                    floor_of(name),
                    floor_of(dep)
                ));
            }
        }
    }
    assert!(
        up.is_empty(),
        "edges that do not run down the floors:\n{}",
        up.join("\n")
    );
    let io = &edges.iter().find(|(n, _)| n == "physid-io").unwrap().1;
    assert_eq!(
        io,
        &["physid-core".to_string()],
        "the scan reads the io crate's manifest"
    );
}

/// The names a Python binding file takes from the library that are not the `api` floor's
/// (`physid::io::…`, `physid::sim::…`), as `file: name`.
fn below_the_api(path: &Path, text: &str) -> Vec<String> {
    let mut out = vec![];
    for (k, _) in text.match_indices("physid::") {
        let rest = &text[k + "physid::".len()..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let preceded_by_name = text[..k]
            .chars()
            .last()
            .is_some_and(|c| c.is_alphanumeric() || c == '_');
        if name != "api" && !preceded_by_name {
            out.push(format!("{}: physid::{name}", path.display()));
        }
    }
    out
}

#[test]
fn the_python_package_stands_on_the_api_floor_alone() {
    // Like the binary, the Python extension is a caller of the library's entry points: what it
    // needs from a lower floor, the api floor names (re-exports or an entry point).
    let mut files = vec![];
    rust_files(&common::root().join("python/src"), &mut files);
    assert!(files.len() >= 10, "{files:?}");
    let below: Vec<String> = files
        .iter()
        .flat_map(|f| below_the_api(f, &std::fs::read_to_string(f).unwrap()))
        .collect();
    assert!(below.is_empty(), "below the api floor: {below:?}");
    // The scan sees a name below the floor when there is one.
    let sample = "use physid::api;\nlet x = physid::io::versioned(a, b);\nmy_physid::io::x();";
    assert_eq!(
        below_the_api(Path::new("x.rs"), sample),
        ["x.rs: physid::io"]
    );
}
