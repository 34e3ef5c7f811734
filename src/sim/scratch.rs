//! Scratch directories of the JSBSim bridge processes, owned by flightid (not by the Python side).
//!
//! Each bridge process works in `<temp dir>/flightid-jsbsim-<flightid pid>-<n>/` (its private aircraft copies,
//! initial-condition files, JSBSim output path). The directory is made here before the process starts and is
//! removed on every way out:
//! * normally and on an error or panic, by [`ScratchDir`]'s `Drop` (after the bridge process is gone, so also
//!   after a bridge that was killed or crashed);
//! * on SIGINT, SIGTERM and SIGHUP, by a signal thread that kills the live bridge processes, removes every live
//!   scratch directory and exits with 128 + the signal number;
//! * after `kill -9` of flightid itself (no handler can run), by the next flightid start: a directory whose pid no
//!   longer names a running process (`/proc/<pid>`) is stale and removed ([`remove_stale`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicI32, AtomicU64, Ordering};
use std::sync::{Mutex, Once};

/// Name prefix of every scratch directory.
pub const PREFIX: &str = "flightid-jsbsim-";

/// Live scratch directories and the bridge process (if started) working in each.
static LIVE: Mutex<Vec<(PathBuf, Option<u32>)>> = Mutex::new(Vec::new());
static NEXT: AtomicU64 = AtomicU64::new(0);
static SETUP: Once = Once::new();
/// The termination signal being handled, 0 when none.
static SIGNALLED: AtomicI32 = AtomicI32::new(0);

/// Blocks for good while a termination signal is being handled. The handler ends the process with 128 + the
/// signal once the bridges are dead and the directories gone; meanwhile the command, whose bridge was just
/// killed, fails with "bridge process died", and must not end the process first with that message and exit 1.
pub fn wait_if_terminating() {
    if SIGNALLED.load(Ordering::SeqCst) != 0 {
        loop {
            std::thread::park();
        }
    }
}

/// A scratch directory removed when dropped.
#[derive(Debug)]
pub struct ScratchDir {
    path: PathBuf,
}

impl ScratchDir {
    /// Makes a fresh scratch directory (the first call also removes stale ones and installs the signal handler).
    pub fn create() -> std::io::Result<Self> {
        SETUP.call_once(|| {
            remove_stale(&std::env::temp_dir());
            install_signal_handler();
        });
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("{PREFIX}{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path); // a leftover of an earlier process with the same pid
        std::fs::create_dir(&path)?;
        live().push((path.clone(), None));
        Ok(ScratchDir { path })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records the process working in this directory, so a signal kills it before the directory is removed.
    pub fn set_process(&self, pid: u32) {
        for entry in live().iter_mut() {
            if entry.0 == self.path {
                entry.1 = Some(pid);
            }
        }
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
        live().retain(|(p, _)| p != &self.path);
    }
}

fn live() -> std::sync::MutexGuard<'static, Vec<(PathBuf, Option<u32>)>> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes the scratch directories in `dir` whose owning flightid process is no longer running. Returns how many.
pub fn remove_stale(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Some(rest) = name.strip_prefix(PREFIX) else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue; // not one of ours (older versions made random names): leave it
        };
        if pid != std::process::id()
            && !process_alive(pid)
            && std::fs::remove_dir_all(e.path()).is_ok()
        {
            removed += 1;
        }
    }
    removed
}

/// Whether a process with this pid exists (Linux `/proc`; elsewhere every process counts as alive, so nothing is
/// removed that might be in use).
fn process_alive(pid: u32) -> bool {
    if !Path::new("/proc/self").exists() {
        return true;
    }
    Path::new(&format!("/proc/{pid}")).exists()
}

fn install_signal_handler() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            SIGNALLED.store(sig, Ordering::SeqCst);
            let entries: Vec<_> = live().clone();
            for (_, pid) in &entries {
                if let Some(pid) = pid {
                    kill_and_reap(*pid);
                }
            }
            for (path, _) in &entries {
                let _ = std::fs::remove_dir_all(path);
            }
            std::process::exit(128 + sig);
        }
    });
}

/// Kills a bridge process and waits for it, so it cannot write into its directory after the removal.
fn kill_and_reap(pid: u32) {
    // SAFETY: plain syscalls on a pid flightid started itself; waitpid on our own child.
    unsafe {
        libc::kill(pid as libc::pid_t, libc::SIGKILL);
        libc::waitpid(pid as libc::pid_t, std::ptr::null_mut(), 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_directories_of_dead_processes_are_removed_and_live_ones_kept() {
        let tmp = tempfile::tempdir().unwrap();
        // pid 1 is alive on Linux; a pid above the kernel's maximum (2^22) never is
        let live = tmp.path().join(format!("{PREFIX}1-0"));
        let dead = tmp.path().join(format!("{PREFIX}4999999-3"));
        let foreign = tmp.path().join(format!("{PREFIX}abcdef"));
        for d in [&live, &dead, &foreign] {
            std::fs::create_dir(d).unwrap();
            std::fs::write(d.join("x.xml"), "x").unwrap();
        }
        assert_eq!(remove_stale(tmp.path()), 1);
        assert!(live.exists() && foreign.exists() && !dead.exists());
    }

    #[test]
    fn a_scratch_directory_is_gone_after_drop() {
        let d = ScratchDir::create().unwrap();
        let p = d.path().to_path_buf();
        std::fs::write(p.join("f"), "x").unwrap();
        drop(d);
        assert!(!p.exists());
    }
}
