use super::*;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn no_two_entries_share_a_code() {
    let mut seen = BTreeSet::new();
    for c in ALL {
        assert!(seen.insert(c.id), "{} is in the registry twice", c.id);
        let (family, digits) = c.id.split_at(1);
        let width = if family == "V" { 4 } else { 3 };
        assert!(
            matches!(family, "V" | "X" | "T")
                && digits.len() == width
                && digits.bytes().all(|b| b.is_ascii_digit()),
            "{} is not a code",
            c.id
        );
        assert!(!c.meaning.is_empty(), "{} has no meaning", c.id);
    }
}

#[test]
fn every_code_has_its_page_and_every_page_a_code() {
    // The pages are compiled in: each starts with `# CODE: meaning`.
    for c in ALL {
        let title = c.page.lines().next().unwrap_or("");
        assert_eq!(
            title,
            format!("# {}: {}", c.id, c.meaning),
            "docs/codes/{}.md",
            c.id
        );
        assert!(
            c.page.lines().count() > 3,
            "docs/codes/{}.md is empty",
            c.id
        );
    }
    // No page without a code.
    let dir = repo().join("docs/codes");
    let mut pages = BTreeSet::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        let id = name.strip_suffix(".md").unwrap_or(&name).to_string();
        assert!(
            ALL.iter().any(|c| c.id == id),
            "docs/codes/{name} names no code of the registry"
        );
        pages.insert(id);
    }
    assert_eq!(pages.len(), ALL.len());
}

#[test]
fn the_registry_knows_every_explanation_item_and_task_alarm() {
    let catalogue = std::fs::read_to_string(repo().join("core/src/explain/codes.md")).unwrap();
    let items: BTreeSet<&str> = catalogue
        .lines()
        .filter_map(|l| l.strip_prefix("| X"))
        .map(|l| &l[..3])
        .collect();
    assert!(items.len() >= 20, "{items:?}");
    for n in items {
        assert!(lookup(&format!("X{n}")).is_some(), "X{n}");
    }
    use crate::tasks::explain::AlarmCode::*;
    for a in [T001, T002, T003, T004, T005, T006, T007, T008, T009] {
        assert!(lookup(a.as_str()).is_some(), "{}", a.as_str());
        assert_eq!(a.as_str(), format!("{a:?}"));
    }
    let x = ALL.iter().filter(|c| c.id.starts_with('X')).count();
    let t = ALL.iter().filter(|c| c.id.starts_with('T')).count();
    assert_eq!((x, t), (36, 9));
}

/// The code literals (`"V0301"`, `"X201"`, `"T003"`) of a Rust source, with their
/// line numbers.
fn v_literals(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let b = line.as_bytes();
        for i in 0..b.len() {
            let width = match b.get(i + 1) {
                Some(b'V') => 4,
                Some(b'X' | b'T') => 3,
                _ => continue,
            };
            if b[i] == b'"'
                && b.len() > i + 2 + width
                && b[i + 2..i + 2 + width].iter().all(u8::is_ascii_digit)
                && b[i + 2 + width] == b'"'
            {
                out.push((n + 1, line[i + 1..i + 2 + width].to_string()));
            }
        }
    }
    out
}

/// The source without its test module (`#[cfg(test)]` then `mod …`, to the end).
fn non_test(text: &str) -> &str {
    let mut at = 0;
    let mut previous: Option<&str> = None;
    for line in text.split_inclusive('\n') {
        let t = line.trim();
        if previous == Some("#[cfg(test)]") && t.starts_with("mod ") {
            return &text[..at];
        }
        if !t.is_empty() {
            previous = Some(t);
        }
        at += line.len();
    }
    text
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "tests") {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs")
            && path.file_name().is_some_and(|n| n != "tests.rs")
        {
            out.push(path);
        }
    }
}

#[test]
fn no_source_spells_a_code_but_the_registry() {
    let registry = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src/diag/codes.rs")
        .canonicalize()
        .unwrap();
    let mut files = Vec::new();
    rust_files(&repo().join("core/src"), &mut files);
    rust_files(&repo().join("app/src"), &mut files);
    assert!(files.len() > 50, "{files:?}");
    let mut stray = Vec::new();
    for f in files
        .iter()
        .filter(|f| f.canonicalize().ok().as_ref() != Some(&registry))
    {
        let text = std::fs::read_to_string(f).unwrap();
        for (line, code) in v_literals(non_test(&text)) {
            stray.push(format!("{}:{line}: \"{code}\"", f.display()));
        }
    }
    assert!(
        stray.is_empty(),
        "use the constants of diag::codes:\n{}",
        stray.join("\n")
    );
    // The scan does see literals.
    assert_eq!(
        v_literals(r#"x("V0301", "V12", "V0302", "X201", "X20", "T003", "T0031")"#).len(),
        4
    );
    let registry = std::fs::read_to_string(&registry).unwrap();
    assert!(v_literals(&registry).len() > 130);
}

#[test]
fn explain_returns_the_page() {
    let trace = explain("V0301").unwrap();
    assert!(trace.starts_with("# V0301: empty trace\n"), "{trace}");
    assert!(trace.contains("error[V0301]"));
    assert!(explain("X001").unwrap().starts_with("# X001: "));
    assert!(explain(" t003 ").unwrap().starts_with("# T003: "));
    assert_eq!(explain("V0701"), Some(LAYOUT_INVALID.page));
    for unknown in ["V9999", "X999", "T000", "", "V030", "V03011"] {
        assert_eq!(explain(unknown), None, "{unknown}");
    }
}
