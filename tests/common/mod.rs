//! Helpers shared by the integration tests (each test file that needs them says `mod common;`).

#![allow(dead_code)] // each test crate uses its own subset

use std::path::Path;
use std::process::{Command, Output};

/// Runs `cmd` to completion and asserts that it exited 0, with its stderr in the failure message.
pub fn run_ok(cmd: &mut Command) -> Output {
    let out = cmd.output().expect("the command could not be started");
    assert!(
        out.status.success(),
        "{:?} failed ({}): {}",
        cmd,
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Parses the JSON file at `path`.
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{} is not JSON: {e}", path.display()))
}

/// Opens `dir/index.html` in headless Chromium through `scripts/report_screenshot.py` (file:// URL, background
/// networking off) and requires exactly `figures` rendered `<svg>` elements of non-zero size, every text of
/// `texts` visible on the rendered page, and a page screenshot.
///
/// Without a Chromium the check cannot run: it prints `SKIPPED browser check` (visible with `--nocapture`, and
/// in the failure output of any other assertion) and returns, except under `CI=true` or
/// `FLIGHTID_REQUIRE_BROWSER` (`.ci/run` installs Debian's chromium and sets it), where it fails.
pub fn browser_check(dir: &Path, figures: usize, texts: &[&str]) {
    let have_browser = ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .any(|b| Command::new(b).arg("--version").output().is_ok())
        || std::env::var_os("CHROMIUM").is_some();
    if !have_browser {
        let required = std::env::var_os("FLIGHTID_REQUIRE_BROWSER").is_some()
            || std::env::var("CI").is_ok_and(|v| v == "true");
        assert!(
            !required,
            "the browser check is required here (CI=true or FLIGHTID_REQUIRE_BROWSER) but no chromium is \
             installed (apt-get install -y chromium)"
        );
        eprintln!(
            "SKIPPED browser check of {}: no chromium (apt-get install -y chromium)",
            dir.display()
        );
        return;
    }
    let shots = dir.with_file_name(format!(
        "{}-shots",
        dir.file_name().unwrap().to_string_lossy()
    ));
    let mut cmd = Command::new("python3");
    cmd.arg(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scripts/report_screenshot.py"
    ))
    .arg(dir)
    .arg("--out")
    .arg(&shots)
    .args(["--expect", &figures.to_string()]);
    for t in texts {
        cmd.args(["--expect-text", t]);
    }
    let out = cmd.output().unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "browser check failed: {said}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        said.contains(&format!("{figures}/{figures} figures rendered")),
        "{said}"
    );
    let png = shots.join(format!(
        "{}.png",
        dir.file_name().unwrap().to_string_lossy()
    ));
    assert!(
        std::fs::metadata(&png)
            .map(|m| m.len() > 10_000)
            .unwrap_or(false),
        "screenshot {png:?}"
    );
}

/// Lines of `text` longer than `width` characters, with their line numbers.
pub fn lines_wider_than(text: &str, width: usize) -> Vec<String> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.chars().count() > width)
        .map(|(i, l)| format!("line {} ({} chars): {l}", i + 1, l.chars().count()))
        .collect()
}
