//! The docs state what is true now: the README stays short and links every other doc, every
//! relative link resolves, ARCHITECTURE.md names every source file (and every file it names
//! exists), module docs fit on a screen, and docs/SOLVERS.md's figures are the bench's own.

use std::path::{Path, PathBuf};

use crate::support::rust_files;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The Markdown files of the project's docs.
fn doc_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["README.md", "ARCHITECTURE.md", "CHANGELOG.md"]
        .iter()
        .map(|f| root().join(f))
        .collect();
    for dir in ["docs", "docs/decisions"] {
        let mut more: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .collect();
        more.sort();
        files.extend(more);
    }
    files
}

/// The targets of the Markdown links `[text](target)` in `text`.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("](") {
        rest = &rest[at + 2..];
        if let Some(end) = rest.find(')') {
            targets.push(rest[..end].to_string());
        }
    }
    targets
}

/// The README is what a newcomer reads in three minutes: at most this many lines, the
/// measurements in docs/RESULTS.md.
const README_MAX_LINES: usize = 80;

#[test]
fn the_readme_is_short_starts_with_the_two_commands_and_links_every_doc() {
    let readme = read(&root().join("README.md"));
    let lines = readme.lines().count();
    assert!(
        lines <= README_MAX_LINES,
        "README.md has {lines} lines, over {README_MAX_LINES}: move detail to docs/GUIDE.md or docs/RESULTS.md"
    );
    let top: String = readme.lines().take(8).collect::<Vec<_>>().join("\n");
    assert!(top.contains("cargo run --release"), "{top}");
    assert!(top.contains("cargo test --release"), "{top}");
    let links = link_targets(&readme);
    // Every other Markdown file at the root and in docs/, and the decisions' index.
    let mut docs = vec!["docs/decisions/README.md".to_string()];
    for dir in [".", "docs"] {
        for entry in std::fs::read_dir(root().join(dir)).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if path.extension().is_some_and(|e| e == "md") && name != "README.md" {
                docs.push(if dir == "." {
                    name
                } else {
                    format!("{dir}/{name}")
                });
            }
        }
    }
    for doc in &docs {
        assert!(
            links.iter().any(|l| l == doc),
            "README.md does not link {doc}"
        );
    }
}

/// The anchors of a Markdown file's headings, as GitHub makes them: lower case, punctuation
/// other than `-` and `_` dropped, spaces as `-`.
fn anchors(markdown: &str) -> Vec<String> {
    markdown
        .lines()
        .filter(|l| l.starts_with('#'))
        .map(|l| {
            l.trim_start_matches('#')
                .trim()
                .to_lowercase()
                .chars()
                .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
                .map(|c| if c == ' ' { '-' } else { c })
                .collect()
        })
        .collect()
}

#[test]
fn every_relative_link_in_the_docs_resolves() {
    for file in doc_files() {
        let dir = file.parent().unwrap();
        let text = read(&file);
        for target in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, anchor) = target.split_once('#').unwrap_or((&target, ""));
            let linked = if path.is_empty() {
                file.clone()
            } else {
                dir.join(path)
            };
            assert!(
                linked.exists(),
                "{}: the link {target} leads nowhere",
                file.display()
            );
            if !anchor.is_empty() && linked.extension().is_some_and(|e| e == "md") {
                assert!(
                    anchors(&read(&linked)).iter().any(|a| a == anchor),
                    "{}: the link {target} names no heading",
                    file.display()
                );
            }
        }
    }
}

#[test]
fn architecture_names_every_source_file_and_only_files_that_exist() {
    let architecture = read(&root().join("ARCHITECTURE.md"));
    for file in rust_files(&root().join("src")) {
        let name = file
            .strip_prefix(root())
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let is_list = ["mod.rs", "lib.rs"].iter().any(|m| name.ends_with(m));
        assert!(
            is_list || architecture.contains(&format!("`{name}`")),
            "ARCHITECTURE.md does not say where {name} fits"
        );
    }
    for doc in doc_files() {
        for word in read(&doc).split('`') {
            let word = word.trim();
            let is_path = ["src/", "tools/", "tests/"]
                .iter()
                .any(|d| word.starts_with(d));
            let is_file = [".rs", ".py", ".js", ".sh"]
                .iter()
                .any(|e| word.ends_with(e));
            if is_path && is_file && !word.contains(' ') {
                assert!(
                    root().join(word).exists(),
                    "{} names {word}, which does not exist",
                    doc.display()
                );
            }
        }
    }
    let lower = architecture.to_lowercase();
    assert!(!lower.contains("issue "), "ARCHITECTURE.md names an issue");
}

#[test]
fn the_readmes_library_example_is_the_one_the_doc_test_runs() {
    // Each line of the README's Rust block (less `mut` and comments) is a line of the fit
    // library's doc example, which `cargo test` compiles and runs.
    let code = |text: &str, opening: &str, prefix: &str| -> Vec<String> {
        let block = text.split(opening).nth(1).expect("a Rust block");
        block
            .lines()
            .map(|l| l.trim_start().trim_start_matches(prefix).trim())
            .take_while(|l| !l.starts_with("```"))
            .map(|l| l.split(" //").next().unwrap().replace("let mut ", "let "))
            .filter(|l| !l.is_empty())
            .collect()
    };
    let readme = code(&read(&root().join("README.md")), "```rust\n", "");
    let example = code(&read(&root().join("src/fit/mod.rs")), "//! ```\n", "//!");
    assert!(readme.len() >= 3, "{readme:?}");
    for line in &readme {
        assert!(
            example.contains(line),
            "README's {line:?} is not in src/fit/mod.rs's example"
        );
    }
}

#[test]
fn the_glossary_is_short_and_names_the_words_the_code_uses() {
    let architecture = read(&root().join("ARCHITECTURE.md"));
    let glossary = architecture
        .split("## Words the code uses")
        .nth(1)
        .and_then(|rest| rest.split("\n## ").next())
        .expect("ARCHITECTURE.md has a glossary");
    let lines = glossary.lines().filter(|l| !l.trim().is_empty()).count();
    assert!(lines <= 25, "the glossary has {lines} lines");
    for word in [
        "real count",
        "level",
        "settled",
        "stall",
        "polish",
        "pressed",
        "slack",
    ] {
        assert!(glossary.contains(word), "the glossary leaves out {word:?}");
    }
}

#[test]
fn every_module_doc_fits_on_a_screen() {
    for file in rust_files(&root().join("src")) {
        let text = read(&file);
        let lines = text.lines().take_while(|l| l.starts_with("//!")).count();
        assert!(lines > 0, "{} has no module doc", file.display());
        assert!(
            lines <= 50,
            "{}: module doc of {lines} lines",
            file.display()
        );
    }
}

#[test]
fn solvers_md_embeds_the_bench_tables_as_the_bench_wrote_them() {
    let solvers = read(&root().join("docs/SOLVERS.md"));
    for (file, begins, ends) in [
        ("bench.md", "<!-- bench.md begins", "<!-- bench.md ends -->"),
        (
            "bench-quick.md",
            "<!-- bench-quick.md begins",
            "<!-- bench-quick.md ends -->",
        ),
    ] {
        let start = solvers.find(begins).expect("the begin marker");
        let body_start = start + solvers[start..].find('\n').unwrap() + 1;
        let end = solvers.find(ends).expect("the end marker");
        assert_eq!(
            &solvers[body_start..end],
            read(&root().join("docs").join(file)),
            "docs/SOLVERS.md's copy of docs/{file} differs: run python3 tools/embed_bench.py"
        );
    }
}

/// The decision records' files, `NNNN-title.md`, sorted.
fn decision_records() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(root().join("docs/decisions"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".md") && n != "README.md")
        .collect();
    names.sort();
    names
}

/// A record's status, as its `- Status:` line begins: `accepted`, `rejected` or `superseded`,
/// and whether it is an accepted record of findings.
fn record_status(name: &str) -> (String, bool) {
    let text = read(&root().join("docs/decisions").join(name));
    let status = text
        .lines()
        .find_map(|l| l.strip_prefix("- Status: "))
        .unwrap_or_else(|| panic!("docs/decisions/{name} has no `- Status:` line"));
    let word: String = status
        .chars()
        .take_while(|c| c.is_ascii_alphabetic())
        .collect();
    (word, status.starts_with("accepted (findings"))
}

#[test]
fn the_decisions_index_lists_every_record_once_and_counts_them_right() {
    let index = read(&root().join("docs/decisions/README.md"));
    let records = decision_records();
    // A record is listed by a list item that begins with its link: `- [0001](0001-….md) …`.
    let listed: Vec<String> = index
        .lines()
        .filter_map(|l| l.strip_prefix("- ["))
        .filter_map(|l| l.split_once("](").map(|(_, rest)| rest))
        .filter_map(|rest| rest.split_once(')').map(|(target, _)| target.to_string()))
        .collect();
    for record in &records {
        let times = listed.iter().filter(|l| *l == record).count();
        assert_eq!(
            times, 1,
            "docs/decisions/README.md lists {record} {times} times, not once"
        );
    }
    for item in &listed {
        assert!(
            records.contains(item),
            "docs/decisions/README.md lists {item}, which is no record"
        );
    }
    // The index's line of counts is the records' own statuses.
    let statuses: Vec<(String, bool)> = records.iter().map(|r| record_status(r)).collect();
    let count = |word: &str| statuses.iter().filter(|(w, _)| w == word).count();
    let findings = statuses.iter().filter(|(_, f)| *f).count();
    let counts = format!(
        "{} records: {} accepted ({findings} of them findings), {} rejected, {} superseded.",
        records.len(),
        count("accepted"),
        count("rejected"),
        count("superseded"),
    );
    assert_eq!(
        count("accepted") + count("rejected") + count("superseded"),
        records.len(),
        "a record's status is none of accepted, rejected, superseded: {statuses:?}"
    );
    assert!(
        index.contains(&counts),
        "docs/decisions/README.md should say \"{counts}\""
    );
    // The status the index gives a record is the record's own.
    for line in index.lines().filter(|l| l.starts_with("- [")) {
        let record = line[line.find("](").unwrap() + 2..line.find(')').unwrap()].to_string();
        let (word, findings) = record_status(&record);
        let said = if line.contains(") *rejected:*") {
            "rejected"
        } else if line.contains(") *superseded by ") {
            "superseded"
        } else {
            "accepted"
        };
        assert_eq!(said, word, "docs/decisions/README.md: {line}");
        assert_eq!(
            line.contains(") *findings:*"),
            findings,
            "docs/decisions/README.md: {line}"
        );
    }
}

#[test]
fn the_changelog_has_one_line_entries_and_one_section_per_kind() {
    let changelog = read(&root().join("CHANGELOG.md"));
    let kinds = [
        "Added",
        "Changed",
        "Deprecated",
        "Removed",
        "Fixed",
        "Security",
    ];
    let mut sections: Vec<&str> = Vec::new();
    let mut in_entry = false;
    for (n, line) in changelog.lines().enumerate() {
        let n = n + 1;
        if line.starts_with("## ") {
            sections.clear();
        } else if let Some(kind) = line.strip_prefix("### ") {
            assert!(
                kinds.contains(&kind),
                "CHANGELOG.md:{n}: `### {kind}` is not one of Keep a Changelog's {kinds:?}"
            );
            assert!(
                !sections.contains(&kind),
                "CHANGELOG.md:{n}: a second `### {kind}` in one release"
            );
            sections.push(kind);
        }
        // An entry is one line: the line after it starts another entry, or is blank.
        assert!(
            !(in_entry && line.starts_with(' ')),
            "CHANGELOG.md:{n}: an entry goes on over more than one line"
        );
        in_entry = line.starts_with("- ");
        assert!(
            !line.contains("(was "),
            "CHANGELOG.md:{n}: a figure from before (\"(was …)\") belongs in the decision record"
        );
    }
}
