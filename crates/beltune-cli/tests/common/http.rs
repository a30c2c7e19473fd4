//! A plain HTTP/1.1 client for the `serve` tests, the in-process server
//! they talk to, and the parts of the test doubles behind the `Tuner` seam
//! that every double answers the same.

use beltune_cli::serve::api::{DefaultAttenuation, EffectiveKnobs, ErrorBody, PrefilterKind};
use beltune_cli::serve::tuner::{ModelSummary, Tuner};
use beltune_cli::serve::{self, AppState};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// A server on loopback with its save folder (removed when dropped).
pub struct Server {
    /// Where it listens.
    pub addr: SocketAddr,
    /// Its save folder.
    pub dir: PathBuf,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Start `tuner` behind the server on 127.0.0.1:0 (see [`start_in`]), saving
/// into a fresh folder named after `tag`.
pub fn start(tuner: Arc<dyn Tuner>, tag: &str, workers: usize) -> Server {
    let dir = std::env::temp_dir().join(format!("beltune-serve-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Server {
        addr: start_in(tuner, &dir, workers),
        dir,
    }
}

/// Start `tuner` behind the server on 127.0.0.1:0, saving into `save_dir`, on
/// its own runtime with `workers` threads in a background thread (it lives
/// until the test process ends); returns its address.
pub fn start_in(tuner: Arc<dyn Tuner>, save_dir: &std::path::Path, workers: usize) -> SocketAddr {
    let state = AppState {
        tuner,
        save_dir: save_dir.to_path_buf(),
        loopback_only: true,
    };
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(workers)
            .enable_all()
            .build()
            .unwrap();
        rt.block_on(async move {
            let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
            tx.send(listener.local_addr().unwrap()).unwrap();
            serve::serve(listener, state).await.unwrap();
        });
    });
    rx.recv().unwrap()
}

/// Send `raw` bytes, read the answer to the end: (status, body). A write
/// error is ignored: the server may answer (413) and stop reading first.
pub fn exchange(addr: SocketAddr, raw: &[u8]) -> (u16, String) {
    let mut stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let _ = stream.write_all(raw);
    let mut out = Vec::new();
    let _ = stream.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out).into_owned();
    let (head, body) = text
        .split_once("\r\n\r\n")
        .unwrap_or_else(|| panic!("no HTTP answer: {text:?}"));
    let status = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("bad status line: {head}"));
    (status, body.to_string())
}

/// One request with `Connection: close` and `Content-Length`; `headers` are
/// whole lines (`"Host: x\r\n"`).
pub fn request(
    addr: SocketAddr,
    method: &str,
    path: &str,
    headers: &str,
    body: impl AsRef<[u8]>,
) -> (u16, String) {
    let body = body.as_ref();
    let mut raw = format!(
        "{method} {path} HTTP/1.1\r\n{headers}Connection: close\r\nContent-Length: {}\r\n\r\n",
        body.len()
    )
    .into_bytes();
    raw.extend_from_slice(body);
    exchange(addr, &raw)
}

/// The message of a JSON error answer (`{"error": "..."}`); panics if the
/// body is not one.
pub fn error_message(status: u16, body: &str) -> String {
    let e: ErrorBody = serde_json::from_str(body).unwrap_or_else(|err| {
        panic!("status {status}: body is not {{\"error\"}} JSON ({err}): {body:?}")
    });
    assert!(!e.error.is_empty(), "empty error message");
    e.error
}

/// The model a test double reports.
pub fn double_model() -> ModelSummary {
    ModelSummary {
        source: "test double".into(),
        f_r_hz: 107.0,
        f_z_hz: 19.6,
        nominal_payload_kg: 11.2,
        measured_frf: None,
        commissioned: None,
        commissioned_verdict: None,
    }
}

/// The knob defaults a test double reports.
pub fn double_defaults() -> EffectiveKnobs {
    EffectiveKnobs {
        prefilter: PrefilterKind::Butterworth,
        pm_velocity_deg: 60.0,
        pm_position_deg: 80.0,
        resonance_suppression_db: -10.0,
        filter_attenuation_db: -3.0,
        dynamics: None,
        payload_kg: 11.2,
    }
}

/// The default attenuations a test double reports.
pub fn double_attenuation() -> DefaultAttenuation {
    DefaultAttenuation {
        butterworth: -3.0,
        notch: -6.0,
    }
}
