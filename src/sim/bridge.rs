//! The JSBSim bridge process: a long-lived Python subprocess (`scripts/jsbsim_bridge.py`) spoken to with a
//! batch protocol — one JSON line per request, whole float64 arrays as raw little-endian bytes. The messages are
//! typed in [`super::protocol`]; this module frames them and runs the process.

use super::env;
use super::protocol::{ReplyStatus, Request};
use super::scratch::ScratchDir;
use super::SimError;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};

const STDERR_LINES_KEPT: usize = 40;

/// One running bridge process.
pub struct Bridge {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    stderr_tail: Arc<Mutex<VecDeque<String>>>,
    /// The process's working directory; dropped (removed) after the process is gone (see `Drop`).
    scratch: ScratchDir,
}

/// A successful response: the command's reply (a struct of [`super::protocol`]) and the float64 payload (empty
/// when there is none).
pub struct Response<R> {
    /// The reply line, `ok` true.
    pub reply: R,
    /// Raw float64 array sent after the reply line.
    pub payload: Vec<f64>,
}

/// A request as framed on the wire: its fields and, when a payload follows, its length.
#[derive(Serialize)]
struct Framed<'a> {
    #[serde(flatten)]
    request: &'a Request,
    #[serde(skip_serializing_if = "Option::is_none")]
    payload_f64: Option<usize>,
}

impl Bridge {
    /// Starts a bridge process with the provisioned (or user's) Python.
    pub fn spawn() -> Result<Self, SimError> {
        let python = env::python()?;
        let script = env::bridge_script()?;
        let scratch = ScratchDir::create().map_err(|source| SimError::Spawn {
            python: format!(
                "{} (making its scratch directory in {})",
                python.display(),
                std::env::temp_dir().display()
            ),
            source,
        })?;
        let mut child = Command::new(&python)
            .arg("-u")
            .arg(&script)
            // jsbsim imports numpy, whose BLAS would start a thread per core at import: the bridge does no linear
            // algebra, and those threads cost ~0.05 s CPU per process start (measured, 2 cores)
            .env("OPENBLAS_NUM_THREADS", "1")
            .env("OMP_NUM_THREADS", "1")
            .env("MKL_NUM_THREADS", "1")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| SimError::Spawn {
                python: python.display().to_string(),
                source,
            })?;
        scratch.set_process(child.id());
        let stdin = child.stdin.take().expect("stdin is piped");
        let stdout =
            BufReader::with_capacity(1 << 20, child.stdout.take().expect("stdout is piped"));
        let stderr = child.stderr.take().expect("stderr is piped");
        let stderr_tail = Arc::new(Mutex::new(VecDeque::new()));
        let tail = Arc::clone(&stderr_tail);
        // Drain stderr continuously (JSBSim prints there); keep the last lines for error messages.
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let mut t = tail.lock().unwrap_or_else(|e| e.into_inner());
                if t.len() == STDERR_LINES_KEPT {
                    t.pop_front();
                }
                t.push_back(line);
            }
        });
        Ok(Bridge {
            child,
            stdin,
            stdout,
            stderr_tail,
            scratch,
        })
    }

    /// The process's scratch directory (passed with `load`; removed by flightid when the bridge is dropped).
    pub fn scratch_dir(&self) -> &std::path::Path {
        self.scratch.path()
    }

    /// Operating-system process id of the Python process.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Sends one request (with an optional float64 payload) and waits for its response; `R` is the command's
    /// reply struct. A failed reply is the error it names (see [`ReplyStatus::into_error`]).
    pub fn request<R: DeserializeOwned>(
        &mut self,
        req: &Request,
        payload: &[f64],
    ) -> Result<Response<R>, SimError> {
        let cmd = req.command();
        let framed = Framed {
            request: req,
            payload_f64: (!payload.is_empty()).then_some(payload.len()),
        };
        let mut buf = serde_json::to_vec(&framed).map_err(|e| SimError::Protocol(e.to_string()))?;
        buf.push(b'\n');
        buf.reserve(payload.len() * 8);
        for x in payload {
            buf.extend_from_slice(&x.to_le_bytes());
        }
        if self
            .stdin
            .write_all(&buf)
            .and_then(|_| self.stdin.flush())
            .is_err()
        {
            return Err(self.crashed(cmd));
        }
        let mut line = String::new();
        match self.stdout.read_line(&mut line) {
            Ok(0) | Err(_) => return Err(self.crashed(cmd)),
            Ok(_) => {}
        }
        let bad_response = |e: serde_json::Error| {
            SimError::Protocol(format!("bad response to '{cmd}': {e}: {}", line.trim()))
        };
        let status: ReplyStatus = serde_json::from_str(&line).map_err(bad_response)?;
        let mut payload_out = Vec::new();
        if status.payload_f64 > 0 {
            let mut bytes = vec![0u8; status.payload_f64 * 8];
            if self.stdout.read_exact(&mut bytes).is_err() {
                return Err(self.crashed(cmd));
            }
            payload_out = bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect();
        }
        if !status.ok {
            return Err(status.into_error());
        }
        Ok(Response {
            reply: serde_json::from_str(&line).map_err(bad_response)?,
            payload: payload_out,
        })
    }

    /// The error for a bridge that stopped answering: exit status and its last stderr lines.
    fn crashed(&mut self, during: &str) -> SimError {
        // Give the process a moment to be reaped so the status is known.
        let mut status = None;
        for _ in 0..50 {
            if let Ok(Some(s)) = self.child.try_wait() {
                status = Some(s);
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let status = match status {
            Some(s) => describe_status(s),
            None => "still running but not answering".to_string(),
        };
        std::thread::sleep(std::time::Duration::from_millis(20));
        let tail = self.stderr_tail.lock().unwrap_or_else(|e| e.into_inner());
        let last = tail
            .iter()
            .rev()
            .find(|l| !l.trim().is_empty())
            .cloned()
            .unwrap_or_default();
        SimError::Crashed {
            during: during.to_string(),
            status,
            last_output: last,
        }
    }
}

fn describe_status(s: std::process::ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = s.signal() {
            return format!("killed by signal {sig}");
        }
    }
    match s.code() {
        Some(c) => format!("exit code {c}"),
        None => "unknown exit status".to_string(),
    }
}

impl Drop for Bridge {
    /// Asks the process to quit, kills it if it does not, and waits for it; the scratch directory field is
    /// dropped (removed) after this, so the process can no longer write into it.
    fn drop(&mut self) {
        if let Ok(mut line) = serde_json::to_vec(&Request::Quit) {
            line.push(b'\n');
            let _ = self.stdin.write_all(&line);
        }
        let _ = self.stdin.flush();
        // Give it a short while to clean up its private directory, then make sure it is gone.
        for _ in 0..100 {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A request is framed as its own keys plus `payload_f64` when float64 follow; `quit` (sent on drop) is the
    /// bare command.
    #[test]
    fn framing_adds_the_payload_length_only_when_a_payload_follows() {
        let req = Request::Rate { dt_s: 0.5 };
        let framed = |payload_f64| {
            serde_json::to_value(Framed {
                request: &req,
                payload_f64,
            })
            .unwrap()
        };
        assert_eq!(framed(None), json!({"cmd": "rate", "dt_s": 0.5}));
        assert_eq!(
            framed(Some(3)),
            json!({"cmd": "rate", "dt_s": 0.5, "payload_f64": 3})
        );
        assert_eq!(
            serde_json::to_string(&Request::Quit).unwrap(),
            r#"{"cmd":"quit"}"#
        );
    }
}
