//! Every command of the README runs as written. The `sh` blocks are run in order from a temporary directory that
//! holds copies of the repository files the commands name (`campaigns/`, `aircraft/`, `models/`, `scripts/`,
//! `tests/fixtures/`), with `cargo run --release --` replaced by the already-built binary (no rebuild). Each
//! command must exit 0, and every file or directory it was asked to write (`--out`, `--report`, `--json FILE`,
//! `--model-out`) must exist afterwards. Commands in `text` blocks (the test suite itself) are listed as not run;
//! the browser screenshot line needs chromium and says SKIPPED without it (a failure under `CI=true`).

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The commands of the README: (fence language, command with continuations joined).
fn readme_commands() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let mut out = Vec::new();
    let mut fence: Option<String> = None;
    let mut pending = String::new();
    for line in text.lines() {
        if let Some(lang) = line.strip_prefix("```") {
            fence = match fence {
                None => Some(lang.trim().to_string()),
                Some(_) => None,
            };
            continue;
        }
        let Some(lang) = &fence else { continue };
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(head) = line.strip_suffix('\\') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(line);
        out.push((lang.clone(), std::mem::take(&mut pending)));
    }
    out
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(e.file_name());
        if e.path().is_dir() {
            if e.file_name() != "__pycache__" {
                copy_dir(&e.path(), &target);
            }
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

/// Paths a command was asked to write.
fn outputs(args: &[&str]) -> Vec<PathBuf> {
    args.windows(2)
        .filter(|w| {
            ["--out", "--report", "--json", "--model-out"].contains(&w[0])
                && !w[1].starts_with("--")
        })
        .map(|w| PathBuf::from(w[1]))
        .collect()
}

fn have_chromium() -> bool {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .any(|b| Command::new(b).arg("--version").output().is_ok())
}

#[test]
fn every_readme_command_runs_as_written() {
    let commands = readme_commands();
    assert!(commands.len() >= 20, "README commands found: {commands:?}");
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    for dir in [
        "campaigns",
        "aircraft",
        "models",
        "scripts",
        "tests/fixtures",
    ] {
        copy_dir(&repo().join(dir), &cwd.join(dir));
    }
    let mut report = Vec::new();
    for (lang, line) in &commands {
        assert!(
            !line.contains('"') && !line.contains('\''),
            "README command with quotes (this test splits at spaces): {line}"
        );
        let words: Vec<&str> = line.split_whitespace().collect();
        if lang != "sh" {
            report.push(format!(
                "NOT RUN ({lang} block: the build and test commands themselves): {line}"
            ));
            continue;
        }
        let mut cmd = match words.as_slice() {
            ["cargo", "run", "--release", "--", args @ ..] => {
                let mut c = Command::new(env!("CARGO_BIN_EXE_flightid"));
                c.args(args);
                c
            }
            ["python3", "scripts/report_screenshot.py", args @ ..] => {
                if !have_chromium() {
                    assert!(
                        std::env::var("CI").map_or(true, |v| v != "true"),
                        "CI=true and no chromium for: {line}"
                    );
                    report.push(format!("SKIPPED (no chromium): {line}"));
                    continue;
                }
                let mut c = Command::new("python3");
                c.arg("scripts/report_screenshot.py").args(args);
                c
            }
            _ => panic!("the README holds a command this test does not know how to run: {line}"),
        };
        let started = std::time::Instant::now();
        let out = cmd.current_dir(cwd).output().unwrap();
        assert!(
            out.status.success(),
            "README command failed ({}): {line}\nstdout:\n{}\nstderr:\n{}",
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            !out.stdout.is_empty() || !out.stderr.is_empty() || !outputs(&words).is_empty(),
            "silent and wrote nothing: {line}"
        );
        for path in outputs(&words) {
            assert!(
                cwd.join(&path).exists(),
                "{line}: did not write {}",
                path.display()
            );
        }
        report.push(format!(
            "ok ({:.1} s): {line}",
            started.elapsed().as_secs_f64()
        ));
    }
    eprintln!("{}", report.join("\n"));
    assert!(
        report
            .iter()
            .any(|r| r.contains("ingest --tlog tests/fixtures/flight.tlog")),
        "the ingest line runs on the committed fixture"
    );
}
