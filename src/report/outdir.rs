//! Output directories (`--report`, `--model-out`): the one rule every command follows before it writes a
//! directory of files; and [`check_output_file`], the check before it writes a single file (`--json`, `--out`).
//!
//! A directory is replaced only when it does not exist, is empty, or is one flightid made itself and that holds
//! nothing but what flightid wrote there. flightid marks each directory it makes with [`MARKER`], a file listing
//! the names it wrote; a directory without the marker, or with any entry the marker does not list, is refused —
//! before any work starts ([`check_output_dir`]) and again just before the swap ([`replace_output_dir`]).
//! The new content is built in a sibling temporary directory and renamed into place, so a failure leaves the old
//! directory untouched and no half-written one.

use super::ReportError;
use std::path::{Path, PathBuf};

/// Name of the file that marks a directory as flightid's: one line per entry flightid wrote.
pub const MARKER: &str = ".flightid-output";

fn refused(path: &Path, reason: impl Into<String>) -> ReportError {
    ReportError::Refused {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Checks that `dir` may be (re)placed by flightid output; call it before any work so a refusal costs nothing.
/// Refused: a path naming no directory of its own (`.`, `..`, `/`), an existing file, and an existing non-empty
/// directory that lacks flightid's marker or holds an entry the marker does not list.
pub fn check_output_dir(dir: &Path) -> Result<(), ReportError> {
    if dir.file_name().is_none() {
        return Err(refused(
            dir,
            "names no directory of its own (the output directory is replaced whole); give a new directory name",
        ));
    }
    let meta = match std::fs::symlink_metadata(dir) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(ReportError::Io {
                path: dir.to_path_buf(),
                source,
            })
        }
    };
    if !meta.is_dir() {
        return Err(refused(
            dir,
            "exists and is not a directory; give a new directory name",
        ));
    }
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|source| ReportError::Io {
        path: dir.to_path_buf(),
        source,
    })? {
        let entry = entry.map_err(|source| ReportError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let is_file = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
        names.push((entry.file_name().to_string_lossy().to_string(), is_file));
    }
    if names.is_empty() {
        return Ok(());
    }
    let listed = match std::fs::read_to_string(dir.join(MARKER)) {
        Ok(text) => text,
        Err(_) => return Err(refused(
            dir,
            "exists, is not empty and was not made by flightid; choose a new or empty directory",
        )),
    };
    let listed: Vec<&str> = listed.lines().collect();
    for (name, is_file) in &names {
        if name == MARKER {
            continue;
        }
        if !is_file || !listed.contains(&name.as_str()) {
            return Err(refused(
                dir,
                format!(
                    "holds '{}', which flightid did not write; move it away or choose another directory",
                    crate::text::escape_control(name)
                ),
            ));
        }
    }
    Ok(())
}

/// Checks that a single output file may be written at `path`; call it before any work, for every output a
/// command writes, so a bad path costs nothing and leaves no other output behind. Refused: a path naming no file
/// of its own (`.`, `/`), an existing directory, and a path inside something that exists and is not a directory
/// (that thing is named). Missing parent directories are fine: they are made when the file is written.
pub fn check_output_file(path: &Path) -> Result<(), ReportError> {
    if path.file_name().is_none() {
        return Err(refused(path, "names no file; give a file name"));
    }
    if std::fs::metadata(path).is_ok_and(|m| m.is_dir()) {
        return Err(refused(path, "is a directory; give a file name"));
    }
    for ancestor in path.ancestors().skip(1) {
        let ancestor = if ancestor.as_os_str().is_empty() {
            Path::new(".")
        } else {
            ancestor
        };
        match std::fs::metadata(ancestor) {
            Ok(m) if m.is_dir() => return Ok(()),
            Ok(_) => {
                return Err(refused(
                    path,
                    format!(
                        "would go inside {}, which is not a directory",
                        crate::text::escape_control(&ancestor.display().to_string())
                    ),
                ))
            }
            // `a/b` where `a` is a file: the culprit is found further up
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
                ) =>
            {
                continue
            }
            Err(source) => {
                return Err(ReportError::Io {
                    path: path.to_path_buf(),
                    source,
                })
            }
        }
    }
    Ok(())
}

/// Builds the content of `dir` with `fill` in a fresh sibling temporary directory, marks it as flightid's and
/// renames it into place (after [`check_output_dir`] once more). On any failure the temporary directory is
/// removed and `dir` is left as it was. `fill` receives the directory to write into.
pub fn replace_output_dir<T, E>(
    dir: &Path,
    fill: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E>
where
    E: From<ReportError>,
{
    check_output_dir(dir)?;
    let parent = dir
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ReportError::Io { path, source }
    };
    std::fs::create_dir_all(parent).map_err(io(parent))?;
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = parent.join(format!(".{name}.tmp-{}", std::process::id()));
    let old = parent.join(format!(".{name}.old-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp); // a leftover of an earlier process with the same id
    let _ = std::fs::remove_dir_all(&old);
    std::fs::create_dir(&tmp).map_err(io(&tmp))?;
    let guard = RemoveOnDrop(tmp.clone());
    let value = fill(&tmp)?;
    write_marker(&tmp)?;
    check_output_dir(dir)?; // the user may have put something there while we worked
    if dir.exists() {
        std::fs::rename(dir, &old).map_err(io(dir))?;
    }
    if let Err(e) = std::fs::rename(&tmp, dir) {
        let _ = std::fs::rename(&old, dir);
        return Err(io(dir)(e).into());
    }
    std::mem::forget(guard);
    let _ = std::fs::remove_dir_all(&old);
    Ok(value)
}

/// Writes [`MARKER`] into `dir`, listing every entry `dir` holds.
fn write_marker(dir: &Path) -> Result<(), ReportError> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map_err(|source| ReportError::Io {
            path: dir.to_path_buf(),
            source,
        })?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n != MARKER)
        .collect();
    names.sort();
    let mut text = names.join("\n");
    text.push('\n');
    super::write_atomic(&dir.join(MARKER), text.as_bytes())
}

/// Removes a directory when dropped (the temporary directory of a replacement that did not complete).
struct RemoveOnDrop(PathBuf);

impl Drop for RemoveOnDrop {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fill_with(names: &'static [&'static str]) -> impl FnOnce(&Path) -> Result<(), ReportError> {
        move |d: &Path| {
            for n in names {
                std::fs::write(d.join(n), n).unwrap();
            }
            Ok(())
        }
    }

    #[test]
    fn flightid_directory_is_replaced_and_anything_foreign_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        replace_output_dir(&dir, fill_with(&["a.svg", "report.json"])).unwrap();
        replace_output_dir(&dir, fill_with(&["b.svg"])).unwrap();
        assert!(dir.join("b.svg").exists() && !dir.join("a.svg").exists());
        // a user file dropped into a flightid directory makes it foreign
        std::fs::write(dir.join("notes.txt"), "keep").unwrap();
        let e = replace_output_dir(&dir, fill_with(&["c.svg"])).unwrap_err();
        assert!(e.to_string().contains("notes.txt"), "{e}");
        assert!(dir.join("notes.txt").exists() && dir.join("b.svg").exists());
        // a directory holding report.json but no marker (made by hand) is refused
        let hand = tmp.path().join("hand");
        std::fs::create_dir(&hand).unwrap();
        std::fs::write(hand.join("report.json"), "{}").unwrap();
        assert!(check_output_dir(&hand).is_err());
        // `.` names no directory of its own
        assert!(check_output_dir(Path::new(".")).is_err());
        assert!(check_output_dir(Path::new("/")).is_err());
        // an existing empty directory is fine; nothing temporary is left beside the outputs
        let empty = tmp.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        replace_output_dir(&empty, fill_with(&["x"])).unwrap();
        let mut names: Vec<String> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        names.sort();
        assert_eq!(names, ["empty", "hand", "out"]);
    }

    #[test]
    fn an_output_file_inside_a_file_or_on_a_directory_is_refused_naming_the_culprit() {
        let tmp = tempfile::tempdir().unwrap();
        let afile = tmp.path().join("afile");
        std::fs::write(&afile, "x").unwrap();
        let e = check_output_file(&afile.join("deeper/x.json")).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("{}, which is not a directory", afile.display())),
            "{e}"
        );
        let e = check_output_file(tmp.path()).unwrap_err();
        assert!(e.to_string().contains("is a directory"), "{e}");
        assert!(check_output_file(&tmp.path().join("new/dir/x.json")).is_ok());
        assert!(check_output_file(&afile).is_ok()); // an existing file is replaced
        assert!(check_output_file(Path::new("x.json")).is_ok());
    }

    #[test]
    fn a_failing_fill_leaves_the_old_directory_and_no_temporary() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        replace_output_dir(&dir, fill_with(&["a.svg"])).unwrap();
        let r: Result<(), ReportError> = replace_output_dir(&dir, |d| {
            std::fs::write(d.join("half"), "x").unwrap();
            Err(refused(d, "simulated failure"))
        });
        assert!(r.is_err());
        assert!(dir.join("a.svg").exists() && !dir.join("half").exists());
        assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
    }
}
