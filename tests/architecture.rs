//! The module floors of the crate (docs/maintainers/architecture.md): the top-level
//! modules of `src/` import each other without a circle, every module imports only
//! modules on the floors below its own (`// Floor k` groups in `src/lib.rs`), no two
//! files import each other in a loop, and the architecture page matches `lib.rs`.
//! Imports are read as text (`crate::`, `super::`, `self::` paths), test modules
//! (after `#[cfg(test)]`) excluded. Also the layout of the tests themselves: every file
//! of `tests/` is in the quick suite (`cargo fast`) or named as a long study (`cargo
//! studies`), and the docs pages the tests cite exist.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The concern a file belongs to: its top-level module (`linalg` for
/// `src/linalg/amg.rs`), or `folder::part` inside a folder of concerns
/// (`models::navier` for `src/models/navier/system.rs`). `None` for a folder's own
/// `mod.rs`, which only declares its parts.
fn module_of(file: &Path, groups: &[String]) -> Option<String> {
    let rel = file.strip_prefix(src()).unwrap();
    let parts: Vec<String> = rel.components().map(|c| c.as_os_str().to_string_lossy().trim_end_matches(".rs").to_string()).collect();
    if groups.contains(&parts[0]) {
        (parts.len() > 1 && parts[1] != "mod").then(|| format!("{}::{}", parts[0], parts[1]))
    } else {
        Some(parts[0].clone())
    }
}

/// The folders of concerns: the `folder` of every `folder::part` on a floor.
fn groups() -> Vec<String> {
    let mut g: Vec<String> = floors().keys().filter_map(|u| u.split_once("::").map(|(f, _)| f.to_string())).collect();
    g.dedup();
    g
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// `concern -> concerns it names as crate::<module>` or `crate::<folder>::<part>`
/// (non-test code only).
fn imports() -> BTreeMap<String, Vec<String>> {
    let groups = groups();
    let mut all = Vec::new();
    files(&src(), &mut all);
    let mut graph: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    for f in all {
        let name = f.file_name().unwrap().to_string_lossy();
        if name == "lib.rs" || name == "main.rs" || name == "tests.rs" || name.ends_with("_tests.rs") {
            continue;
        }
        let Some(m) = module_of(&f, &groups) else { continue };
        let text = std::fs::read_to_string(&f).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        let deps = graph.entry(m.clone()).or_default();
        for (i, _) in code.match_indices("crate::") {
            let rest = &code[i + 7..];
            let mut name = ident(rest);
            if groups.contains(&name) {
                let part = rest[name.len()..].strip_prefix("::").map(ident).unwrap_or_default();
                if part.is_empty() {
                    continue;
                }
                name = format!("{name}::{part}");
            }
            if !name.is_empty() && name != m && !deps.contains(&name) {
                deps.push(name);
            }
        }
    }
    graph
}

/// The floor of every concern: the `// Floor k: a b folder::part` lines of
/// `src/lib.rs`.
fn floors() -> BTreeMap<String, usize> {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let mut out = BTreeMap::new();
    for line in lib.lines() {
        if let Some(rest) = line.strip_prefix("// Floor ") {
            let (k, units) = rest.split_once(':').expect("// Floor <number>: <modules>");
            let floor: usize = k.trim().parse().expect("// Floor <number>");
            for u in units.split_whitespace() {
                assert!(out.insert(u.to_string(), floor).is_none(), "{u} on two floors");
            }
        }
    }
    out
}

/// Every concern on a floor is a module of the crate, and every module of the crate
/// (top-level, or a part of a folder of concerns) is on a floor.
#[test]
fn every_module_is_on_exactly_one_floor() {
    let floor = floors();
    let groups = groups();
    let mut all = Vec::new();
    files(&src(), &mut all);
    let mut found: std::collections::BTreeSet<String> = all
        .iter()
        .filter(|f| !f.file_name().is_some_and(|n| n == "lib.rs" || n == "main.rs"))
        .filter_map(|f| module_of(f, &groups))
        .collect();
    for g in &groups {
        found.remove(g);
    }
    let declared: std::collections::BTreeSet<String> = floor.keys().cloned().collect();
    assert_eq!(found, declared, "modules of src/ against the floors of src/lib.rs");
}

#[test]
fn modules_import_only_modules_below_them() {
    let floor = floors();
    let graph = imports();
    let mut wrong = Vec::new();
    for (m, deps) in &graph {
        let own = *floor.get(m).unwrap_or_else(|| panic!("module {m} is not declared in lib.rs"));
        for d in deps {
            let other = *floor.get(d).unwrap_or_else(|| panic!("{m} names unknown module {d}"));
            if other >= own {
                wrong.push(format!("{m} (floor {own}) imports {d} (floor {other})"));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    // Floors imply no circle; check it directly too, so the message names the circle.
    fn visit(m: &str, graph: &BTreeMap<String, Vec<String>>, path: &mut Vec<String>) {
        if let Some(k) = path.iter().position(|p| p == m) {
            panic!("import circle: {} -> {m}", path[k..].join(" -> "));
        }
        path.push(m.to_string());
        for d in graph.get(m).into_iter().flatten() {
            visit(d, graph, path);
        }
        path.pop();
    }
    for m in graph.keys() {
        visit(m, &graph, &mut Vec::new());
    }
}

/// The page a maintainer reads first, `docs/maintainers/architecture.md`.
fn architecture_page() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/maintainers/architecture.md");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The floors table of the architecture page lists exactly the modules of `lib.rs`,
/// each on the floor `lib.rs` declares it on (rows `| k | `module` | ... |`).
#[test]
fn architecture_page_lists_the_modules_of_lib_rs_on_their_floors() {
    let mut page = BTreeMap::new();
    for line in architecture_page().lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() >= 4 && cells[2].starts_with('`') {
            if let Ok(floor) = cells[1].parse::<usize>() {
                page.insert(cells[2].trim_matches('`').to_string(), floor);
            }
        }
    }
    assert_eq!(page, floors(), "docs/maintainers/architecture.md's floors table against src/lib.rs");
}

/// Every `src/...` path the architecture page names exists.
#[test]
fn architecture_page_names_only_files_that_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let page = architecture_page();
    let mut missing = Vec::new();
    for (i, _) in page.match_indices("src/") {
        let path: String = page[i..].chars().take_while(|c| c.is_alphanumeric() || "_/.".contains(*c)).collect();
        let path = path.trim_end_matches('.');
        if path.ends_with(".rs") && !root.join(path).exists() {
            missing.push(path.to_string());
        }
    }
    assert!(missing.is_empty(), "named on docs/maintainers/architecture.md but missing: {missing:?}");
}

/// The module path of a source file: `["linalg", "amg"]` for `src/linalg/amg.rs`,
/// `["navier", "sector"]` for `src/models/navier/sector/mod.rs`.
fn module_path(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src()).unwrap().with_extension("");
    let mut parts: Vec<String> = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    if parts.last().is_some_and(|p| p == "mod" || p == "lib" || p == "main") {
        parts.pop();
    }
    parts
}

/// The file of module `path`, if it is one (`src/a/b.rs` or `src/a/b/mod.rs`).
fn file_of(path: &[String]) -> Option<PathBuf> {
    if path.is_empty() {
        return None;
    }
    let base = src().join(path.join("/"));
    [base.with_extension("rs"), base.join("mod.rs")].into_iter().find(|p| p.exists())
}

/// The files a source file names through `crate::`, `super::` or `self::` paths
/// (grouped imports `super::{a, b}` included), each resolved to the deepest module
/// that is a file.
fn file_imports(file: &Path, code: &str) -> Vec<PathBuf> {
    let own = module_path(file);
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    let mut out = Vec::new();
    let mut resolve = |mut base: Vec<String>, rest: &str| {
        let mut target = None;
        for seg in rest.split("::") {
            let seg = ident(seg.trim());
            if seg.is_empty() {
                break;
            }
            base.push(seg);
            match file_of(&base) {
                Some(f) => target = Some(f),
                None => break,
            }
        }
        if let Some(t) = target.or_else(|| file_of(&base[..base.len().saturating_sub(1)])) {
            if t != file {
                out.push(t);
            }
        }
    };
    for start in ["crate::", "super::", "self::"] {
        for (i, _) in code.match_indices(start) {
            let before = code[..i].chars().last();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            let mut base = if start == "crate::" { Vec::new() } else { own.clone() };
            let mut rest = &code[i + start.len()..];
            if start == "super::" {
                // `super` of `a/b.rs` is `a`; of `a/b/mod.rs` (module `a::b`) also `a`.
                base.pop();
                while let Some(r) = rest.strip_prefix("super::") {
                    base.pop();
                    rest = r;
                }
            }
            if let Some(group) = rest.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                for item in group[..end].split(',') {
                    resolve(base.clone(), item);
                }
            } else {
                resolve(base, rest);
            }
        }
    }
    out
}

/// No two files import each other in a loop (the floors rule it out between
/// top-level modules; this is the same rule between the files inside them).
#[test]
fn no_files_import_each_other_in_a_circle() {
    let mut all = Vec::new();
    files(&src(), &mut all);
    let mut graph: BTreeMap<PathBuf, Vec<PathBuf>> = BTreeMap::new();
    for f in &all {
        let name = f.file_name().unwrap().to_string_lossy();
        if name == "tests.rs" || name.ends_with("_tests.rs") {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        let code: String = code.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n");
        let mut deps = file_imports(f, &code);
        deps.sort();
        deps.dedup();
        graph.insert(f.clone(), deps);
    }
    let mut done = std::collections::BTreeSet::new();
    fn visit(f: &PathBuf, graph: &BTreeMap<PathBuf, Vec<PathBuf>>, path: &mut Vec<PathBuf>, done: &mut std::collections::BTreeSet<PathBuf>) {
        if let Some(k) = path.iter().position(|p| p == f) {
            let names: Vec<String> = path[k..].iter().map(|p| p.strip_prefix(src()).unwrap().display().to_string()).collect();
            panic!("files import each other in a circle: {} -> {}", names.join(" -> "), names[0]);
        }
        if !done.insert(f.clone()) {
            return;
        }
        path.push(f.clone());
        for d in graph.get(f).into_iter().flatten() {
            visit(d, graph, path, done);
        }
        path.pop();
    }
    for f in graph.keys() {
        visit(f, &graph, &mut Vec::new(), &mut done);
    }
}

/// The files of `tests/` by name (`cli` for `tests/cli.rs`), sorted.
fn test_files() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The aliases of `.cargo/config.toml`, `fast` (the unit tests and the quick files of
/// `tests/`) and `studies` (the long verification studies), name every file of `tests/`
/// once between them, and nothing else: a new test file goes into one list or the
/// other, and cannot fall out of both (docs/maintainers/README.md, "Build and test").
#[test]
fn the_fast_and_studies_aliases_name_every_test_file_once() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(".cargo/config.toml");
    let config: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
    let args = |alias: &str| -> Vec<String> {
        let list = config["alias"][alias].as_array().unwrap_or_else(|| panic!("{}: no alias {alias}", path.display()));
        list.iter().map(|v| v.as_str().unwrap().to_string()).collect()
    };
    let named = |alias: &str| -> Vec<String> { args(alias).windows(2).filter(|w| w[0] == "--test").map(|w| w[1].clone()).collect() };
    let (fast, studies) = (named("fast"), named("studies"));
    assert_eq!(args("fast")[..4], ["test", "--release", "--lib", "--bins"], "fast runs the unit tests too");
    let files = test_files();
    let mut listed: Vec<String> = fast.iter().chain(&studies).cloned().collect();
    listed.sort();
    let missing: Vec<&String> = files.iter().filter(|f| !listed.contains(f)).collect();
    assert!(
        missing.is_empty(),
        "tests/{{{}}}.rs: in neither `fast` nor `studies` of .cargo/config.toml",
        missing.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(",")
    );
    assert_eq!(listed, files, "each file of tests/ once in `fast` ({fast:?}) or `studies` ({studies:?})");
}

/// Every page under `docs/` that a comment in `tests/` cites exists (the README's
/// sections moved to docs/ in issue 50).
#[test]
fn the_docs_pages_tests_cite_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut missing = Vec::new();
    for name in test_files() {
        let text = std::fs::read_to_string(root.join("tests").join(format!("{name}.rs"))).unwrap();
        for (i, _) in text.match_indices("docs/") {
            let path: String = text[i..].chars().take_while(|c| c.is_alphanumeric() || "_/.-".contains(*c)).collect();
            let path = path.trim_end_matches('.');
            if path.ends_with(".md") && !root.join(path).exists() {
                missing.push(format!("tests/{name}.rs: {path}"));
            }
        }
    }
    assert!(missing.is_empty(), "cited but missing: {missing:?}");
}
