//! API tests of `beltune serve` (issue 7): the server runs in-process on
//! 127.0.0.1:0 and is spoken to with plain HTTP/1.1 over a tokio `TcpStream`.
//!
//! The request-validation tests use a counting test double behind the `Tuner`
//! seam, so they can prove that a refused request never reaches the design; the
//! design tests use the real library backend.

#[allow(dead_code)]
#[path = "../src/serve/mod.rs"]
mod serve;

use serve::api::{
    DefaultAttenuation, DesignResponse, EffectiveKnobs, ErrorBody, Knobs, PrefilterKind,
    MAX_BODY_BYTES,
};
use serve::tuner::{ModelSummary, TuneError, Tuner};
use serve::AppState;
use std::io::{Read, Write};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// Test double: counts calls; refuses `pm_velocity_deg > 85` as infeasible.
struct CountingTuner {
    calls: AtomicUsize,
}

const DOUBLE_INFEASIBLE_ABOVE_DEG: f64 = 85.0;

impl Tuner for CountingTuner {
    fn model(&self) -> ModelSummary {
        ModelSummary {
            source: "test double".into(),
            f_r_hz: 107.0,
            f_z_hz: 19.6,
            nominal_payload_kg: 11.2,
        }
    }
    fn defaults(&self) -> EffectiveKnobs {
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
    fn default_attenuation(&self) -> DefaultAttenuation {
        DefaultAttenuation {
            butterworth: -3.0,
            notch: -6.0,
        }
    }
    fn tune(&self, knobs: &Knobs) -> Result<DesignResponse, TuneError> {
        self.calls.fetch_add(1, Ordering::SeqCst);
        if knobs.pm_velocity_deg.unwrap_or(60.0) > DOUBLE_INFEASIBLE_ABOVE_DEG {
            return Err(TuneError::Infeasible("phase margin too large".into()));
        }
        Err(TuneError::Internal(
            "the test double designs nothing".into(),
        ))
    }
    fn controller_toml(&self, knobs: &Knobs) -> Result<String, TuneError> {
        self.calls.fetch_add(1, Ordering::SeqCst);
        Ok(format!(
            "# test double\npm_velocity_deg = {:?}\n",
            knobs.pm_velocity_deg
        ))
    }
}

struct Server {
    addr: SocketAddr,
    dir: PathBuf,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Start the server on its own runtime in a background thread (it lives until
/// the test process ends) and return its address.
fn start(tuner: Arc<dyn Tuner>, tag: &str) -> Server {
    let dir = std::env::temp_dir().join(format!("beltune-serve-api-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let state = AppState {
        tuner,
        save_dir: dir.clone(),
    };
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .unwrap();
        rt.block_on(async move {
            let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
            tx.send(listener.local_addr().unwrap()).unwrap();
            serve::serve(listener, state).await.unwrap();
        });
    });
    let addr = rx.recv().unwrap();
    Server { addr, dir }
}

/// One HTTP/1.1 request with `Connection: close`; returns (status, body).
fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    content_type: Option<&str>,
    body: &[u8],
) -> (u16, String) {
    let mut stream = std::net::TcpStream::connect(addr).unwrap();
    let mut head = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Length: {}\r\n",
        body.len()
    );
    if let Some(ct) = content_type {
        head.push_str(&format!("Content-Type: {ct}\r\n"));
    }
    head.push_str("\r\n");
    stream.write_all(head.as_bytes()).unwrap();
    // The server may answer (413) and stop reading before the whole body is sent.
    let _ = stream.write_all(body);
    let mut raw = Vec::new();
    let _ = stream.read_to_end(&mut raw);
    let text = String::from_utf8_lossy(&raw).into_owned();
    let (head, body) = text
        .split_once("\r\n\r\n")
        .unwrap_or_else(|| panic!("no HTTP response: {text:?}"));
    let status: u16 = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("bad status line: {head}"));
    (status, body.to_string())
}

fn post_json(addr: SocketAddr, path: &str, body: &str) -> (u16, String) {
    http(
        addr,
        "POST",
        path,
        Some("application/json"),
        body.as_bytes(),
    )
}

fn error_message(status: u16, body: &str) -> String {
    let e: ErrorBody = serde_json::from_str(body).unwrap_or_else(|err| {
        panic!("status {status}: body is not {{\"error\"}} JSON ({err}): {body}")
    });
    assert!(!e.error.is_empty(), "empty error message");
    e.error
}

fn counting() -> Arc<CountingTuner> {
    Arc::new(CountingTuner {
        calls: AtomicUsize::new(0),
    })
}

#[test]
fn malformed_json_wrong_types_and_unknown_fields_are_400_with_a_message() {
    let tuner = counting();
    let s = start(tuner.clone(), "malformed");
    for (body, expect) in [
        ("{\"pm_velocity_deg\": 60", "EOF"),
        ("not json", "expected"),
        ("{\"pm_velocity_deg\": \"sixty\"}", "invalid type"),
        ("{\"pm_velocity_deg\": true}", "invalid type"),
        ("{\"prefilter\": \"chebyshev\"}", "unknown variant"),
        ("{\"prefilter\": 3}", "expected value"),
        ("{\"pm_velocity\": 60}", "unknown field"),
        ("[60, 80]", "invalid type"),
        ("{\"pm_velocity_deg\": 1e999}", "number out of range"),
    ] {
        let (status, resp) = post_json(s.addr, "/api/design", body);
        assert_eq!(status, 400, "{body} -> {resp}");
        let msg = error_message(status, &resp);
        assert!(
            msg.contains(expect),
            "{body}: message `{msg}` lacks `{expect}`"
        );
    }
    assert_eq!(
        tuner.calls.load(Ordering::SeqCst),
        0,
        "a bad request reached the design"
    );
}

#[test]
fn out_of_range_and_contradictory_knobs_are_400_naming_the_knob() {
    let tuner = counting();
    let s = start(tuner.clone(), "range");
    for (body, knob) in [
        ("{\"pm_velocity_deg\": 95}", "pm_velocity_deg"),
        ("{\"pm_velocity_deg\": -60}", "pm_velocity_deg"),
        ("{\"pm_position_deg\": 5}", "pm_position_deg"),
        (
            "{\"resonance_suppression_db\": 3}",
            "resonance_suppression_db",
        ),
        ("{\"filter_attenuation_db\": -60}", "filter_attenuation_db"),
        ("{\"dynamics\": 1.5}", "dynamics"),
        ("{\"payload_kg\": -1}", "payload_kg"),
        ("{\"payload_kg\": 1000}", "payload_kg"),
        (
            "{\"dynamics\": 0.5, \"pm_velocity_deg\": 60}",
            "pm_velocity_deg",
        ),
    ] {
        for path in ["/api/design", "/api/save"] {
            let (status, resp) = post_json(s.addr, path, body);
            assert_eq!(status, 400, "{path} {body} -> {resp}");
            let msg = error_message(status, &resp);
            assert!(
                msg.contains(knob),
                "{body}: message `{msg}` does not name `{knob}`"
            );
        }
    }
    assert_eq!(tuner.calls.load(Ordering::SeqCst), 0);
    assert!(
        !s.dir.join(serve::CONTROLLER_FILE).exists(),
        "a refused save wrote a file"
    );
}

#[test]
fn oversized_body_is_413_and_wrong_content_type_is_415() {
    let tuner = counting();
    let s = start(tuner.clone(), "size");
    // Valid JSON (padding in a string would be an unknown field anyway) but too big.
    let big = format!(
        "{{\"pm_velocity_deg\": 60{}}}",
        " ".repeat(MAX_BODY_BYTES + 1)
    );
    let (status, resp) = post_json(s.addr, "/api/design", &big);
    assert_eq!(status, 413, "{resp}");
    assert!(error_message(status, &resp).contains("too large"));
    // At the limit it is accepted (and reaches the double, which refuses to design).
    let fits = format!(
        "{{\"pm_velocity_deg\": 60{}}}",
        " ".repeat(MAX_BODY_BYTES - 24)
    );
    assert!(fits.len() <= MAX_BODY_BYTES);
    let (status, resp) = post_json(s.addr, "/api/design", &fits);
    assert_eq!(status, 500, "{resp}");
    assert!(error_message(status, &resp).contains("test double"));

    for ct in [
        None,
        Some("text/plain"),
        Some("application/x-www-form-urlencoded"),
    ] {
        let (status, resp) = http(s.addr, "POST", "/api/save", ct, b"{}");
        assert_eq!(status, 415, "{ct:?}: {resp}");
        assert!(error_message(status, &resp).contains("application/json"));
    }
    assert_eq!(tuner.calls.load(Ordering::SeqCst), 1);
    assert!(!s.dir.join(serve::CONTROLLER_FILE).exists());
}

#[test]
fn infeasible_is_422_with_the_reason_and_unknown_routes_are_404_json() {
    let tuner = counting();
    let s = start(tuner.clone(), "infeasible");
    let (status, resp) = post_json(s.addr, "/api/design", "{\"pm_velocity_deg\": 88}");
    assert_eq!(status, 422, "{resp}");
    assert_eq!(error_message(status, &resp), "phase margin too large");
    let (status, resp) = http(s.addr, "GET", "/api/nothing", None, b"");
    assert_eq!(status, 404);
    error_message(status, &resp);
    let (status, _) = http(s.addr, "GET", "/api/design", None, b"");
    assert_eq!(status, 405);
}

#[test]
fn page_and_assets_are_embedded_and_self_contained() {
    let s = start(counting(), "assets");
    let (status, html) = http(s.addr, "GET", "/", None, b"");
    assert_eq!(status, 200);
    for id in [
        "pm_velocity_deg",
        "pm_position_deg",
        "resonance_suppression_db",
        "prefilter",
        "filter_attenuation_db",
        "dynamics",
        "payload_kg",
        "save",
    ] {
        assert!(html.contains(&format!("id=\"{id}\"")), "page lacks #{id}");
    }
    for path in ["/", "/app.js", "/style.css"] {
        let (status, text) = http(s.addr, "GET", path, None, b"");
        assert_eq!(status, 200, "{path}");
        // No CDN, no network: the only absolute URL anywhere is the SVG namespace.
        let urls = text.matches("http").count();
        let ns = text.matches("http://www.w3.org/2000/svg").count();
        assert_eq!(urls, ns, "{path} references a network URL");
    }
    let (status, info) = http(s.addr, "GET", "/api/info", None, b"");
    assert_eq!(status, 200);
    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(
        info["ranges"].as_array().unwrap().len(),
        serve::api::RANGES.len()
    );
    assert_eq!(info["defaults"]["pm_velocity_deg"], 60.0);
}
