//! Provisioning of the Python environment that runs the JSBSim bridge.
//!
//! On first use flightid creates a virtual environment in its cache directory and installs the pinned
//! packages into it, printing what it does. `FLIGHTID_PYTHON` points at a user's own Python instead (it must be
//! able to `import jsbsim`). The cache directory is `FLIGHTID_CACHE_DIR`, else `$XDG_CACHE_HOME/flightid`, else
//! `$HOME/.cache/flightid`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;

/// Packages the bridge environment holds: JSBSim for the simulator, pymavlink for telemetry fixtures, numpy,
/// scipy and python-control for the reference (oracle) scripts under `scripts/`.
pub const REQUIREMENTS: &[&str] = &[
    "jsbsim==1.3.3",
    "numpy==2.4.6",
    "scipy==1.17.1",
    "control==0.10.2",
    "pymavlink==2.4.50",
];

/// The bridge program, embedded so the binary works from any directory.
pub const BRIDGE_SOURCE: &str = include_str!("../../scripts/jsbsim_bridge.py");

/// Why the Python environment could not be provided.
#[derive(Debug, thiserror::Error)]
pub enum EnvError {
    /// No base Python interpreter to build the environment with.
    #[error("no Python 3 interpreter found ('{tried}' could not be run: {source}); install Python 3.9+ or set FLIGHTID_PYTHON to a Python that has jsbsim installed")]
    NoPython {
        tried: String,
        source: std::io::Error,
    },
    /// `FLIGHTID_PYTHON` names something that does not run.
    #[error("FLIGHTID_PYTHON={path} cannot be run: {reason}")]
    BadUserPython { path: String, reason: String },
    /// Creating the venv or installing packages failed.
    #[error("could not provision the JSBSim Python environment in {dir}: {step} failed: {detail}")]
    Provision {
        dir: PathBuf,
        step: String,
        detail: String,
    },
    /// Cache directory problems.
    #[error("cache directory {dir}: {source}")]
    Io {
        dir: PathBuf,
        source: std::io::Error,
    },
}

impl EnvError {
    /// For `map_err`: a file-system failure in the cache directory `dir`.
    fn io(dir: &Path) -> impl FnOnce(std::io::Error) -> EnvError + '_ {
        move |source| EnvError::Io {
            dir: dir.to_path_buf(),
            source,
        }
    }
}

static PROVISION_LOCK: Mutex<()> = Mutex::new(());

/// `FLIGHTID_PYTHON` interpreters this process has already seen import jsbsim.
static USER_PYTHON_OK: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The cache directory flightid keeps its Python environment and bridge program in.
pub fn cache_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("FLIGHTID_CACHE_DIR") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(d).join("flightid");
    }
    let home = std::env::var_os("HOME")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    home.join(".cache").join("flightid")
}

/// A short stable hash (FNV-1a 64) used to version cache entries by their content.
fn fnv1a(text: &str) -> String {
    let mut h: u64 = 0xcbf29ce484222325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x100000001b3);
    }
    format!("{h:016x}")
}

/// Path of a Python that can run the bridge: `FLIGHTID_PYTHON`, or the provisioned venv (created on first use).
pub fn python() -> Result<PathBuf, EnvError> {
    if let Some(p) = std::env::var_os("FLIGHTID_PYTHON") {
        let path = PathBuf::from(&p);
        // checked once per process and path: every bridge start (campaign workers, reloads) asks again,
        // and `import jsbsim` costs ~0.1 s
        let mut checked = USER_PYTHON_OK.lock().unwrap_or_else(|e| e.into_inner());
        if checked.contains(&path) {
            return Ok(path);
        }
        let out = Command::new(&path)
            .arg("-c")
            .arg("import jsbsim")
            .stdin(Stdio::null())
            .output();
        return match out {
            Ok(o) if o.status.success() => {
                checked.push(path.clone());
                Ok(path)
            }
            Ok(o) => Err(EnvError::BadUserPython {
                path: path.display().to_string(),
                reason: format!(
                    "'import jsbsim' failed: {}",
                    last_line(&String::from_utf8_lossy(&o.stderr))
                ),
            }),
            Err(e) => Err(EnvError::BadUserPython {
                path: path.display().to_string(),
                reason: e.to_string(),
            }),
        };
    }
    let dir = cache_dir();
    let venv = dir.join(format!("venv-{}", fnv1a(&REQUIREMENTS.join(" "))));
    let py = venv.join("bin").join("python");
    if py.exists() {
        return Ok(py);
    }
    let _guard = PROVISION_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    std::fs::create_dir_all(&dir).map_err(EnvError::io(&dir))?;
    // Serialise provisioning across processes too (tests and campaigns start many at once).
    let lock_path = dir.join(".provision.lock");
    let lock = std::fs::File::create(&lock_path).map_err(EnvError::io(&dir))?;
    lock.lock().map_err(EnvError::io(&dir))?;
    if py.exists() {
        return Ok(py);
    }
    provision(&dir, &venv)?;
    Ok(py)
}

fn last_line(text: &str) -> String {
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .trim()
        .to_string()
}

/// Builds the venv in a temporary sibling directory and renames it into place, so that concurrent processes
/// never see a half-installed environment (the loser of a race discards its copy).
fn provision(dir: &Path, venv: &Path) -> Result<(), EnvError> {
    std::fs::create_dir_all(dir).map_err(EnvError::io(dir))?;
    let base = std::env::var("FLIGHTID_BASE_PYTHON").unwrap_or_else(|_| "python3".to_string());
    let tmp = dir.join(format!(".venv-building-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    eprintln!(
        "flightid: first use: creating the JSBSim Python environment in {} ({}); this takes about a minute",
        venv.display(),
        REQUIREMENTS.join(", ")
    );
    let status = Command::new(&base)
        .args(["-m", "venv"])
        .arg(&tmp)
        .stdin(Stdio::null())
        .output()
        .map_err(|source| EnvError::NoPython {
            tried: base.clone(),
            source,
        })?;
    if !status.status.success() {
        return Err(EnvError::Provision {
            dir: venv.to_path_buf(),
            step: format!("{base} -m venv"),
            detail: last_line(&String::from_utf8_lossy(&status.stderr)),
        });
    }
    let pip = Command::new(tmp.join("bin").join("python"))
        .args([
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            "--quiet",
        ])
        .args(REQUIREMENTS)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| EnvError::Provision {
            dir: venv.to_path_buf(),
            step: "pip".into(),
            detail: e.to_string(),
        })?;
    if !pip.status.success() {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(EnvError::Provision {
            dir: venv.to_path_buf(),
            step: "pip install".into(),
            detail: last_line(&String::from_utf8_lossy(&pip.stderr)),
        });
    }
    if std::fs::rename(&tmp, venv).is_err() {
        // Another process finished first; theirs is complete, ours is redundant.
        let _ = std::fs::remove_dir_all(&tmp);
    }
    eprintln!("flightid: JSBSim Python environment ready");
    Ok(())
}

/// Writes the embedded bridge program into the cache (content-addressed) and returns its path.
pub fn bridge_script() -> Result<PathBuf, EnvError> {
    let dir = cache_dir();
    std::fs::create_dir_all(&dir).map_err(EnvError::io(&dir))?;
    let path = dir.join(format!("jsbsim_bridge-{}.py", fnv1a(BRIDGE_SOURCE)));
    if !path.exists() {
        // Unique per process *and* call: threads of one process (parallel tests, campaign workers) may
        // write the script at the same time; the last rename wins and every content is identical.
        static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = dir.join(format!(".bridge-{}-{n}.py", std::process::id()));
        std::fs::write(&tmp, BRIDGE_SOURCE).map_err(EnvError::io(&dir))?;
        if let Err(source) = std::fs::rename(&tmp, &path) {
            let _ = std::fs::remove_file(&tmp);
            if !path.exists() {
                return Err(EnvError::Io { dir, source });
            }
        }
    }
    Ok(path)
}
