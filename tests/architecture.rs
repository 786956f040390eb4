//! The module floors of the crate (README, Architecture): the top-level modules of
//! `src/` import each other without a circle, and every module imports only modules
//! on the floors below its own (`// Floor k` groups in `src/lib.rs`). Imports are read
//! as text (`crate::<module>`), test modules (after `#[cfg(test)]`) excluded.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The top-level module a file belongs to (`navier` for `src/navier/system.rs`).
fn module_of(file: &Path) -> String {
    let rel = file.strip_prefix(src()).unwrap();
    let first = rel.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
    first.trim_end_matches(".rs").to_string()
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

/// `module -> modules it names as crate::<module>` (non-test code only).
fn imports() -> BTreeMap<String, Vec<String>> {
    let mut all = Vec::new();
    files(&src(), &mut all);
    let mut graph: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for f in all {
        let m = module_of(&f);
        if m == "lib" || m == "main" || f.file_name().is_some_and(|n| n == "tests.rs" || n.to_string_lossy().ends_with("_tests.rs")) {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        let deps = graph.entry(m.clone()).or_default();
        for (i, _) in code.match_indices("crate::") {
            let name: String = code[i + 7..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if !name.is_empty() && name != m && !deps.contains(&name) {
                deps.push(name);
            }
        }
    }
    graph
}

/// The floor of every module: the `// Floor k` group `src/lib.rs` declares it in.
fn floors() -> BTreeMap<String, usize> {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let mut floor = 0;
    let mut out = BTreeMap::new();
    for line in lib.lines() {
        if let Some(k) = line.strip_prefix("// Floor ") {
            floor = k.trim().parse().expect("// Floor <number>");
        } else if let Some(m) = line.strip_prefix("pub mod ") {
            assert!(floor > 0, "pub mod {m} before the first // Floor line");
            out.insert(m.trim_end_matches(';').to_string(), floor);
        }
    }
    out
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
