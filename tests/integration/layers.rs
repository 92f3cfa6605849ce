//! The library's top-level modules import one another in one direction only: no module reaches,
//! directly or through others, back to itself, and none imports one above it in
//! ARCHITECTURE.md's layer table. Read from the source: every `crate::MODULE` path outside
//! comments, in each top-level module's files.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::support::rust_files;

/// Top-level modules of the library, from `pub mod NAME;` / `mod NAME;` lines in `src/lib.rs`.
fn top_level_modules(src: &Path) -> Vec<String> {
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    lib.lines()
        .filter_map(|line| {
            let line = line.trim();
            let rest = line
                .strip_prefix("pub mod ")
                .or_else(|| line.strip_prefix("mod "))?;
            Some(rest.trim_end_matches(';').trim().to_string())
        })
        .collect()
}

/// The `.rs` files of module `name`: `src/NAME.rs` or everything under `src/NAME/`.
fn module_files(src: &Path, name: &str) -> Vec<PathBuf> {
    let single = src.join(format!("{name}.rs"));
    if single.exists() {
        return vec![single];
    }
    rust_files(&src.join(name))
}

/// Modules named by `crate::NAME` or `crate::{NAME::…, …}` in `text`, comments skipped.
fn imports(text: &str, modules: &[String]) -> BTreeSet<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let code: String = text
        .lines()
        .map(|line| line.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let mut found = BTreeSet::new();
    let mut rest = code.as_str();
    while let Some(at) = rest.find("crate::") {
        rest = &rest[at + "crate::".len()..];
        let mut names = Vec::new();
        if let Some(group) = rest.strip_prefix('{') {
            // Split the group at its top-level commas: each item starts with a module's name.
            let (mut depth, mut start) = (0, 0);
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        names.push(ident(&group[start..i]));
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        names.push(ident(&group[start..i]));
                        start = i + 1;
                    }
                    _ => {}
                }
            }
        } else {
            names.push(ident(rest));
        }
        found.extend(names.into_iter().filter(|n| modules.contains(n)));
    }
    found
}

/// The import graph: module → the other modules it names.
fn import_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let modules = top_level_modules(src);
    modules
        .iter()
        .map(|m| {
            let mut named = BTreeSet::new();
            for file in module_files(src, m) {
                named.extend(imports(&std::fs::read_to_string(file).unwrap(), &modules));
            }
            named.remove(m);
            (m.clone(), named)
        })
        .collect()
}

/// A cycle in `graph`, as the modules along it, if there is one.
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        marks: &mut BTreeMap<String, Mark>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match marks.get(node) {
            Some(Mark::Done) => return None,
            Some(Mark::Open) => {
                let start = path.iter().position(|n| n == node).unwrap();
                let mut cycle = path[start..].to_vec();
                cycle.push(node.to_string());
                return Some(cycle);
            }
            None => {}
        }
        marks.insert(node.to_string(), Mark::Open);
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(cycle) = visit(next, graph, marks, path) {
                return Some(cycle);
            }
        }
        path.pop();
        marks.insert(node.to_string(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for node in graph.keys() {
        if let Some(cycle) = visit(node, graph, &mut marks, &mut Vec::new()) {
            return Some(cycle);
        }
    }
    None
}

#[test]
fn no_top_level_module_imports_one_that_imports_it_back() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = import_graph(&src);
    assert!(graph.len() >= 10, "modules found: {:?}", graph.keys());
    if let Some(cycle) = find_cycle(&graph) {
        panic!("import cycle: {}", cycle.join(" → "));
    }
}

/// The layers of ARCHITECTURE.md's table, top first: a row per layer, `→` splitting a row into
/// layers one above the other, `,` listing modules side by side. Module → its depth (0 at the
/// top).
fn documented_layers() -> BTreeMap<String, usize> {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md"))
            .unwrap();
    let table = text
        .split("## Layers")
        .nth(1)
        .expect("ARCHITECTURE.md has a Layers section");
    let mut depth = BTreeMap::new();
    let mut level = 0;
    for row in table.lines().skip_while(|l| !l.starts_with("|---")).skip(1) {
        if !row.starts_with('|') {
            break;
        }
        let modules_cell = row.trim_matches('|').split('|').nth(1).unwrap_or("");
        for part in modules_cell.split('→') {
            for name in part.split(',') {
                depth.insert(name.trim().trim_matches('`').to_string(), level);
            }
            level += 1;
        }
    }
    depth
}

#[test]
fn every_module_imports_only_modules_at_or_below_its_documented_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = import_graph(&src);
    let depth = documented_layers();
    for (module, named) in &graph {
        let d = *depth
            .get(module)
            .unwrap_or_else(|| panic!("ARCHITECTURE.md's layers do not list {module}"));
        for other in named {
            assert!(
                depth[other] >= d,
                "{module} imports {other}, a layer above it in ARCHITECTURE.md"
            );
        }
    }
}

#[test]
fn the_cycle_check_finds_a_cycle_when_there_is_one() {
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("base", vec![]),
        ("leg", vec!["base", "knit"]),
        ("knit", vec!["base", "sim"]),
        ("sim", vec!["leg"]),
    ]
    .into_iter()
    .map(|(m, to)| (m.to_string(), to.into_iter().map(String::from).collect()))
    .collect();
    let cycle = find_cycle(&graph).expect("leg → knit → sim → leg");
    assert_eq!(cycle.first(), cycle.last());
    assert_eq!(cycle.len(), 4, "{cycle:?}");
    assert_eq!(
        imports(
            "use crate::leg::X; // crate::sim",
            &["leg".into(), "sim".into()]
        )
        .len(),
        1
    );
}

#[test]
fn the_base_module_imports_no_stage() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = import_graph(&src);
    let allowed: BTreeSet<String> = ["error".to_string()].into();
    assert!(
        graph["base"].is_subset(&allowed),
        "base imports {:?}",
        graph["base"]
    );
}
