//! The library's top-level modules import one another in one direction only: no module reaches,
//! directly or through others, back to itself, and none imports one above it in
//! ARCHITECTURE.md's layer table. Read from the source: every `crate::MODULE` path outside
//! comments, in each top-level module's files.
//!
//! Within each folder of `src/` too, no file reaches back to itself through its siblings. A
//! folder's files are its `.rs` files and its subfolders (each one node, whatever it holds),
//! and its face (`mod.rs`, or `NAME.rs` beside the folder `NAME/`). What a file names through
//! `super::`, `self::` or `crate::…` (and a face through its children's own names) is taken to
//! the file that defines it: a `pub use` is a signpost followed to its target, not an import,
//! unless the file's own code uses the name too. Items of a face itself make the face a node like
//! any file, above the files its code uses and below the files that use its items. A test module
//! imports like its file; its `super::*` is its own file.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::support::rust_files;

/// A graph of names: each node → the nodes it imports.
type Graph = BTreeMap<String, BTreeSet<String>>;

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
fn import_graph(src: &Path) -> Graph {
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
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        node: &str,
        graph: &Graph,
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
    let graph: Graph = [
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

/// `text` with comments removed and string and character literals emptied, so that neither a
/// path in a doc nor a brace in a string is read as code.
fn code_of(text: &str) -> String {
    let b = text.as_bytes();
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let (mut out, mut i) = (String::new(), 0);
    while i < b.len() {
        let rest = &b[i..];
        if rest.starts_with(b"//") {
            i += rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
        } else if rest.starts_with(b"/*") {
            let mut depth = 0;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    (depth, i) = (depth + 1, i + 2);
                } else if b[i..].starts_with(b"*/") {
                    (depth, i) = (depth - 1, i + 2);
                } else {
                    i += 1;
                }
                if depth == 0 {
                    break;
                }
            }
            out.push(' ');
        } else if (i == 0 || !ident(b[i - 1]))
            && (rest.starts_with(b"r#") || rest.starts_with(b"r\"") || rest.starts_with(b"br"))
        {
            // A raw string: r"…", r#"…"#, br"…".
            let start = if rest[0] == b'b' { 2 } else { 1 };
            let hashes = rest[start..].iter().take_while(|&&c| c == b'#').count();
            if rest.get(start + hashes) != Some(&b'"') {
                out.push(rest[0] as char);
                i += 1;
                continue;
            }
            let close: Vec<u8> = std::iter::once(b'"')
                .chain(std::iter::repeat_n(b'#', hashes))
                .collect();
            let body = start + hashes + 1;
            let end = rest[body..]
                .windows(close.len())
                .position(|w| w == close.as_slice())
                .map_or(rest.len(), |p| body + p + close.len());
            out.push_str("\"\"");
            i += end;
        } else if rest[0] == b'"' {
            let mut j = 1;
            while j < rest.len() && rest[j] != b'"' {
                j += if rest[j] == b'\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            i += j + 1;
        } else if rest[0] == b'\'' {
            // A character literal ('x', '\n', '\u{…}', 'é'), or else a lifetime.
            let len = if rest.get(1) == Some(&b'\\') {
                rest[3.min(rest.len())..]
                    .iter()
                    .position(|&c| c == b'\'')
                    .map(|p| p + 4)
            } else {
                let width = text[i + 1..].chars().next().map_or(1, char::len_utf8);
                (rest.get(1 + width) == Some(&b'\'')).then_some(width + 2)
            };
            match len {
                Some(len) => {
                    out.push_str("' '");
                    i += len;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            let len = text[i..].chars().next().map_or(1, char::len_utf8);
            out.push_str(&text[i..i + len]);
            i += len;
        }
    }
    out
}

/// An identifier at `code[i..]`, if one starts there.
fn ident_at(code: &str, i: usize) -> Option<&str> {
    let len = code[i..]
        .bytes()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == b'_')
        .count();
    (len > 0 && !code.as_bytes()[i].is_ascii_digit()).then(|| &code[i..i + len])
}

/// The paths of the path or use tree at `code[i..]` (`a::b`, `a::{b, c::d as e, self}`), each
/// after `prefix` and with the name it binds (its `as`, else its last segment), and where the
/// tree ends. `self` and `*` segments are dropped: they name the module before them.
fn use_tree(code: &str, mut i: usize, prefix: &[String]) -> (Vec<(Vec<String>, String)>, usize) {
    let skip = |i: usize, also: &[u8]| {
        i + code[i..]
            .bytes()
            .take_while(|c| c.is_ascii_whitespace() || also.contains(c))
            .count()
    };
    let mut segments = prefix.to_vec();
    let mut bound = String::new();
    loop {
        i = skip(i, b"");
        if code[i..].starts_with('{') {
            let mut paths = Vec::new();
            i += 1;
            loop {
                i = skip(i, b",");
                if i >= code.len() || code[i..].starts_with('}') {
                    return (paths, (i + 1).min(code.len()));
                }
                let (inner, end) = use_tree(code, i, &segments);
                paths.extend(inner);
                i = end.max(i + 1);
            }
        }
        if code[i..].starts_with('*') {
            return (vec![(segments, "*".to_string())], i + 1);
        }
        let Some(name) = ident_at(code, i) else {
            return (vec![(segments, bound)], i);
        };
        i += name.len();
        if name == "self" {
            bound = segments.last().cloned().unwrap_or_default();
        } else {
            segments.push(name.to_string());
            bound = name.to_string();
        }
        let after = skip(i, b"");
        if code[after..].starts_with("::") {
            i = after + 2;
            continue;
        }
        if code[after..].starts_with("as") {
            let alias = skip(after + 2, b"");
            if alias > after + 2 {
                if let Some(alias_name) = ident_at(code, alias) {
                    return (
                        vec![(segments, alias_name.to_string())],
                        alias + alias_name.len(),
                    );
                }
            }
        }
        return (vec![(segments, bound)], i);
    }
}

/// What a file names: a module path from the crate root (its item, if any, last) and how.
#[derive(Debug)]
struct Named {
    path: Vec<String>,
    /// The name a `use` binds it to.
    bound: String,
    /// Named by a `pub use` (or `pub(crate) use`): a signpost.
    signpost: bool,
}

/// The module path of a file at `file` (relative to `src/`, `/`-separated).
fn module_path(file: &str) -> Vec<String> {
    let mut path: Vec<String> = file
        .trim_end_matches(".rs")
        .split('/')
        .map(String::from)
        .collect();
    if path.last().is_some_and(|last| last == "mod") {
        path.pop();
    }
    path
}

/// Every path `code` (a file's, see [`code_of`]) names through `crate::`, `super::`, `self::`,
/// or one of `children` (a face's own modules), from the crate root. `super` is taken from the
/// module each path is in: the file's `module`, or a `mod NAME { … }` inside it.
fn named_paths(code: &str, module: &[String], children: &[String]) -> Vec<Named> {
    let bytes = code.as_bytes();
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut found = Vec::new();
    // Inline modules open at a brace depth; `opening` names the one whose brace comes next.
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0;
    let mut opening: Option<String> = None;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'{' => {
                depth += 1;
                if let Some(name) = opening.take() {
                    inline.push((name, depth));
                }
            }
            b'}' => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            b';' => opening = None,
            _ => {}
        }
        let starts_word = i == 0 || !(ident(bytes[i - 1]) || bytes[i - 1] == b':');
        let Some(word) = ident_at(code, i).filter(|_| starts_word) else {
            i += 1;
            continue;
        };
        if word == "mod" {
            let rest = code[i + 3..].trim_start();
            if let Some(name) = ident_at(rest, 0) {
                if rest[name.len()..].trim_start().starts_with('{') {
                    opening = Some(name.to_string());
                }
            }
        }
        let is_head =
            ["crate", "super", "self"].contains(&word) || children.iter().any(|c| c == word);
        if !(is_head && code[i + word.len()..].starts_with("::")) {
            i += word.len();
            continue;
        }
        // The statement this path is in: a `use`, perhaps a `pub use`.
        let start = code[..i].rfind([';', '{', '}']).map_or(0, |s| s + 1);
        let words: Vec<&str> = code[start..i].split_whitespace().collect();
        let signpost = words
            .iter()
            .position(|w| *w == "use")
            .is_some_and(|u| u > 0 && words[u - 1].starts_with("pub"));
        let (paths, end) = use_tree(code, i, &[]);
        let here: Vec<String> = module
            .iter()
            .cloned()
            .chain(inline.iter().map(|(name, _)| name.clone()))
            .collect();
        for (segments, bound) in paths.into_iter().filter(|(s, _)| !s.is_empty()) {
            let mut path = match segments[0].as_str() {
                "crate" => Vec::new(),
                _ => here.clone(),
            };
            let mut rest = &segments[..];
            if rest[0] == "crate" {
                rest = &rest[1..];
            }
            while rest.first().is_some_and(|f| f == "super") {
                path.pop();
                rest = &rest[1..];
            }
            path.extend(rest.iter().cloned());
            found.push(Named {
                path,
                bound,
                signpost,
            });
        }
        i = end.max(i + word.len());
    }
    found
}

/// The identifiers of `code` outside its `use` statements and `mod` names: what its own code
/// uses.
fn used_names(code: &str) -> BTreeSet<&str> {
    let mut names = BTreeSet::new();
    let (mut in_use, mut module_name) = (false, false);
    for word in code.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ';')) {
        for (k, part) in word.split(';').enumerate() {
            if k > 0 {
                in_use = false;
            }
            if part.is_empty() {
                continue;
            }
            match part {
                "use" => in_use = true,
                "mod" => module_name = true,
                _ if module_name => module_name = false,
                _ if !in_use => {
                    names.insert(part);
                }
                _ => {}
            }
        }
    }
    names
}

/// A folder under `src/`: its face and its children's names.
struct Folder {
    /// Relative to `src/`, `/`-separated.
    dir: String,
    /// `DIR/mod.rs`, or `DIR.rs` beside it.
    face: String,
    /// Its `.rs` files (but `mod.rs`) and subfolders, by module name.
    children: BTreeSet<String>,
}

/// The folders of a tree of `files` (paths relative to `src/`), and the faces' children.
fn folders(files: &BTreeMap<String, String>) -> Vec<Folder> {
    let mut dirs: BTreeSet<String> = BTreeSet::new();
    for file in files.keys() {
        let parts: Vec<&str> = file.split('/').collect();
        for k in 1..parts.len() {
            dirs.insert(parts[..k].join("/"));
        }
    }
    dirs.into_iter()
        .map(|dir| {
            let in_dir = format!("{dir}/");
            let children = files
                .keys()
                .filter_map(|f| f.strip_prefix(&in_dir))
                .filter_map(|rest| match rest.split_once('/') {
                    Some((sub, _)) => Some(sub.to_string()),
                    None => (rest != "mod.rs").then(|| rest.trim_end_matches(".rs").to_string()),
                })
                .collect();
            let face = if files.contains_key(&format!("{dir}/mod.rs")) {
                format!("{dir}/mod.rs")
            } else {
                format!("{dir}.rs")
            };
            Folder {
                dir,
                face,
                children,
            }
        })
        .collect()
}

/// Each folder's import graph between its files (see the module docs), by folder, from `files`
/// (path relative to `src/` → text; files in `src/` itself are the top-level check's).
fn file_graphs(files: &BTreeMap<String, String>) -> BTreeMap<String, Graph> {
    let files: BTreeMap<String, String> = files
        .iter()
        .filter(|(path, _)| path.contains('/'))
        .map(|(path, text)| (path.clone(), code_of(text)))
        .collect();
    let folders = folders(&files);
    let children_of = |file: &str| -> Vec<String> {
        folders
            .iter()
            .find(|f| f.face == file)
            .map(|f| f.children.iter().cloned().collect())
            .unwrap_or_default()
    };
    // What each file names, its signposts, and the module each file is.
    let mut named: BTreeMap<&str, Vec<Named>> = BTreeMap::new();
    let mut signposts: BTreeMap<Vec<String>, Vec<String>> = BTreeMap::new();
    let modules: BTreeSet<Vec<String>> = files.keys().map(|f| module_path(f)).collect();
    for (file, code) in &files {
        let module = module_path(file);
        let paths = named_paths(code, &module, &children_of(file));
        for n in paths.iter().filter(|n| n.signpost) {
            let at: Vec<String> = module.iter().chain([&n.bound]).cloned().collect();
            signposts.insert(at, n.path.clone());
        }
        named.insert(file, paths);
    }
    // The module that defines what `path` names: signposts followed, then its longest module.
    let definer = |path: &[String]| -> Option<Vec<String>> {
        let mut path = path.to_vec();
        for _ in 0..16 {
            let hop = (1..=path.len()).find_map(|k| signposts.get(&path[..k]).map(|to| (k, to)));
            let Some((k, to)) = hop else { break };
            path = to.iter().chain(&path[k..]).cloned().collect();
        }
        (0..=path.len())
            .rev()
            .map(|k| path[..k].to_vec())
            .find(|m| modules.contains(m))
    };
    let mut graphs = BTreeMap::new();
    for folder in &folders {
        let base = module_path(&format!("{}.rs", folder.dir));
        let label = |child: &str| {
            let file = format!("{}/{child}.rs", folder.dir);
            if files.contains_key(&file) {
                file
            } else {
                format!("{}/{child}/", folder.dir)
            }
        };
        // The node a module of this folder is: the face, or the child it is in.
        let node = |module: &[String]| -> Option<String> {
            let rest = module.strip_prefix(base.as_slice())?;
            Some(match rest.first() {
                None => folder.face.clone(),
                Some(child) => label(child),
            })
        };
        let mut graph: Graph = folder
            .children
            .iter()
            .map(|c| (label(c), BTreeSet::new()))
            .collect();
        graph.insert(folder.face.clone(), BTreeSet::new());
        for (file, paths) in &named {
            let Some(from) = node(&module_path(file)) else {
                continue;
            };
            let used = used_names(&files[*file]);
            for n in paths {
                if n.signpost && !used.contains(n.bound.as_str()) {
                    continue;
                }
                let Some(to) = definer(&n.path).and_then(|m| node(&m)) else {
                    continue;
                };
                if to != from {
                    graph.get_mut(&from).unwrap().insert(to);
                }
            }
        }
        graphs.insert(folder.dir.clone(), graph);
    }
    graphs
}

/// The library's source: path relative to `src/` → text.
fn library_source() -> BTreeMap<String, String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    rust_files(&src)
        .into_iter()
        .map(|file| {
            let name = file
                .strip_prefix(&src)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            (name, std::fs::read_to_string(&file).unwrap())
        })
        .collect()
}

#[test]
fn no_file_imports_a_sibling_that_imports_it_back() {
    let graphs = file_graphs(&library_source());
    for dir in ["knit", "post", "export/gltf", "run", "sim", "fit"] {
        assert!(
            graphs.contains_key(dir),
            "folders found: {:?}",
            graphs.keys()
        );
    }
    for (dir, graph) in &graphs {
        if let Some(cycle) = find_cycle(graph) {
            panic!("import cycle in src/{dir}/: {}", cycle.join(" → "));
        }
    }
}

#[test]
fn the_file_cycle_check_finds_a_cycle_when_there_is_one() {
    let tree = |files: &[(&str, &str)]| -> BTreeMap<String, String> {
        files
            .iter()
            .map(|(path, text)| (path.to_string(), text.to_string()))
            .collect()
    };
    let face = "pub mod fields;\npub mod loops;\npub mod transfer;\n\
                pub use fields::KnitFields;\npub use transfer::{carry_to_leg as carry, OpenEnd};\n";
    // The transfer takes the fields through the face's signpost; the fields take the transfer's
    // function by its other name there: a cycle of two files, the face in neither.
    let looped = tree(&[
        ("post/mod.rs", face),
        (
            "post/fields.rs",
            "//! Carried by [`super::transfer`].\n\
             use super::carry;\npub struct KnitFields;\n\
             #[cfg(test)]\nmod tests {\n    use super::*;\n}\n",
        ),
        (
            "post/transfer.rs",
            "use crate::post::KnitFields;\npub fn carry_to_leg() {}\npub struct OpenEnd;\n",
        ),
        (
            "post/loops.rs",
            "// crate::post::fields\nfn f() -> &'static str { let c = '{'; \"super::fields::\" }\n",
        ),
    ]);
    let graph = &file_graphs(&looped)["post"];
    assert!(graph["post/loops.rs"].is_empty(), "{graph:?}");
    assert!(graph["post/mod.rs"].is_empty(), "{graph:?}");
    let cycle = find_cycle(graph).expect("fields → transfer → fields");
    assert_eq!(
        cycle,
        ["post/fields.rs", "post/transfer.rs", "post/fields.rs"],
        "{graph:?}"
    );
    // A signpost to what the face's own code does, and a subfolder as one node: no cycle; the
    // face's code using the fields while the fields use the face's items: a cycle.
    let signposts = tree(&[
        (
            "post/mod.rs",
            "pub mod fields;\npub mod gltf;\npub fn both() {}\n",
        ),
        (
            "post/fields.rs",
            "pub use super::both;\npub fn f() { super::gltf::read::g(); }\n",
        ),
        ("post/gltf/mod.rs", "pub mod read;\n"),
        ("post/gltf/read.rs", "pub fn g() {}\n"),
    ]);
    let graph = &file_graphs(&signposts)["post"];
    assert_eq!(graph["post/fields.rs"], ["post/gltf/".to_string()].into());
    assert_eq!(find_cycle(graph), None);
    let face_in_the_loop = tree(&[
        (
            "run/bench.rs",
            "pub mod stocking;\nuse stocking::rows;\npub fn mib() {}\nfn run() { rows(); }\n",
        ),
        ("run/bench/stocking.rs", "pub fn rows() { super::mib(); }\n"),
    ]);
    let cycle = find_cycle(&file_graphs(&face_in_the_loop)["run/bench"]).expect("a cycle");
    assert_eq!(cycle.len(), 3, "{cycle:?}");
}
