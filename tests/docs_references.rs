//! The repository carries its own documentation: no source, test, script, aircraft file, README or `--help`
//! text points at a design file that is not in the repository or at an issue number; contracts live in `docs/`,
//! and the module table of `docs/architecture.md` lists exactly the modules in `src/`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The name of the design file that lived outside the repository (spelt in two pieces so that this file does
/// not match itself).
fn outside_design_file() -> String {
    ["DESIGN", ".md"].concat()
}

/// Text files under `dir` (recursively), skipping build output.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            if !p.ends_with("target") && !p.ends_with("__pycache__") {
                files(&p, out);
            }
        } else if std::fs::read_to_string(&p).is_ok() {
            out.push(p);
        }
    }
}

/// `issue 7`, `Issue 3 acceptance`, `issue #12`: a citation of a tracker the reader cannot see.
fn cites_issue_number(line: &str) -> bool {
    let lower = line.to_ascii_lowercase();
    lower.match_indices("issue").any(|(i, _)| {
        let rest = lower[i + "issue".len()..].trim_start_matches(['s', ' ', '#']);
        rest.starts_with(|c: char| c.is_ascii_digit())
    })
}

#[test]
fn no_file_cites_an_outside_design_file_or_an_issue_number() {
    let mut all = Vec::new();
    for dir in [
        "src",
        "tests",
        "scripts",
        "aircraft",
        "benches",
        "campaigns",
        "docs",
        ".ci",
    ] {
        files(&root().join(dir), &mut all);
    }
    all.push(root().join("README.md"));
    let me = root().join("tests/docs_references.rs");
    let design = outside_design_file();
    let mut found = Vec::new();
    for f in all.iter().filter(|f| **f != me) {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, line) in text.lines().enumerate() {
            if line.contains(&design) || cites_issue_number(line) {
                found.push(format!("{}:{}: {}", f.display(), i + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "point to docs/ instead:\n{}",
        found.join("\n")
    );
}

#[test]
fn no_help_text_cites_an_outside_design_file() {
    let bin = env!("CARGO_BIN_EXE_flightid");
    let top = Command::new(bin).arg("--help").output().unwrap();
    let top = String::from_utf8_lossy(&top.stdout).to_string();
    // the command names from the top-level help's "Commands:" list
    let commands: Vec<String> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect();
    assert!(commands.len() >= 10, "commands found: {commands:?}");
    let mut texts = vec![("flightid --help".to_string(), top)];
    for c in &commands {
        let out = Command::new(bin).args([c, "--help"]).output().unwrap();
        texts.push((
            format!("flightid {c} --help"),
            String::from_utf8_lossy(&out.stdout).to_string(),
        ));
        if c == "campaign" {
            for sub in ["run", "report"] {
                let out = Command::new(bin).args([c, sub, "--help"]).output().unwrap();
                texts.push((
                    format!("flightid {c} {sub} --help"),
                    String::from_utf8_lossy(&out.stdout).to_string(),
                ));
            }
        }
    }
    let design = outside_design_file();
    for (what, text) in &texts {
        assert!(!text.contains(&design), "{what} cites {design}");
        assert!(
            !text.lines().any(cites_issue_number),
            "{what} cites an issue number"
        );
    }
}

#[test]
fn architecture_module_table_matches_the_source_tree() {
    let doc = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let listed: std::collections::BTreeSet<String> = doc
        .lines()
        .filter(|l| l.starts_with("| `src/"))
        .filter_map(|l| l.split('`').nth(1))
        .map(|m| {
            m.trim_start_matches("src/")
                .trim_end_matches('/')
                .to_string()
        })
        .collect();
    let mut in_tree = std::collections::BTreeSet::new();
    for e in std::fs::read_dir(root().join("src")).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let module_file = name != "lib.rs" && name != "main.rs" && name.ends_with(".rs");
        if e.path().is_dir() || module_file {
            in_tree.insert(name);
        }
    }
    assert_eq!(
        listed, in_tree,
        "docs/architecture.md's module table (left) against src/ (right)"
    );
}

#[test]
fn no_two_source_files_import_each_other() {
    let out = Command::new("python3")
        .arg(root().join("scripts/import_cycles.py"))
        .current_dir(root())
        .output()
        .expect("python3 runs scripts/import_cycles.py");
    assert!(
        out.status.success(),
        "files that import each other:\n{}",
        String::from_utf8_lossy(&out.stdout)
    );
}
