//! The tuning page's server against careless and hostile clients on loopback: concurrent saves
//! never expose a partial `controller.toml`, slow or abusive clients are cut
//! off, the `Host` check is strict, and every error answer is JSON.

mod common;

use beltune_cli::serve;
use beltune_cli::serve::api::{DefaultAttenuation, DesignResponse, EffectiveKnobs, Knobs};
use beltune_cli::serve::tuner::{ModelSummary, TuneError, Tuner};
use common::http::{self, error_message as json_error, exchange, request, Server};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Test double: a controller.toml of some size whose every line names the
/// request, so that a mixed or truncated file fails to parse or to agree.
struct TextTuner;

impl Tuner for TextTuner {
    fn model(&self) -> ModelSummary {
        http::double_model()
    }
    fn defaults(&self) -> EffectiveKnobs {
        http::double_defaults()
    }
    fn default_attenuation(&self) -> DefaultAttenuation {
        http::double_attenuation()
    }
    fn tune(&self, _: &Knobs) -> Result<DesignResponse, TuneError> {
        Err(TuneError::Internal(
            "the test double designs nothing".into(),
        ))
    }
    fn controller_toml(&self, knobs: &Knobs) -> Result<String, TuneError> {
        let pm = knobs.pm_velocity_deg.unwrap_or(60.0);
        let mut s = format!("pm_velocity_deg = {pm:?}\n");
        for k in 0..200 {
            s.push_str(&format!("line_{k} = {pm:?}\n"));
        }
        Ok(s)
    }
}

fn start(tag: &str) -> Server {
    http::start(Arc::new(TextTuner), &format!("limits-{tag}"), 2)
}

#[test]
fn concurrent_saves_never_expose_a_partial_file() {
    // Every save makes its own folder `tuned-<time>[-n]` in the save
    // folder (renamed into place whole); a reader must never see a folder
    // without its complete controller.toml, and no save may replace another.
    let s = start("saves");
    let dir = s.dir.clone();
    let stop = Arc::new(AtomicBool::new(false));
    let looks = Arc::new(AtomicUsize::new(0));
    // A reader parses every visible set as fast as it can, the whole time.
    let reader = {
        let (dir, stop, looks) = (dir.clone(), stop.clone(), looks.clone());
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                for e in std::fs::read_dir(&dir).unwrap().flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if !name.starts_with("tuned-") {
                        continue;
                    }
                    let text = std::fs::read_to_string(e.path().join(serve::CONTROLLER_FILE))
                        .unwrap_or_else(|err| panic!("{name} without its controller.toml: {err}"));
                    let v: toml::Value = toml::from_str(&text)
                        .unwrap_or_else(|e| panic!("invalid TOML ({e}): {text:?}"));
                    let pm = v["pm_velocity_deg"].as_float().unwrap();
                    assert_eq!(v["line_199"].as_float(), Some(pm), "mixed file");
                    looks.fetch_add(1, Ordering::Relaxed);
                }
            }
        })
    };
    // 600 saves, 40 in parallel.
    let next = Arc::new(AtomicUsize::new(0));
    let answers = Arc::new(std::sync::Mutex::new(Vec::new()));
    let clients: Vec<_> = (0..40)
        .map(|_| {
            let (next, answers) = (next.clone(), answers.clone());
            let addr = s.addr;
            std::thread::spawn(move || loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= 600 {
                    break;
                }
                let pm = 20.0 + (k % 69) as f64;
                let body = format!("{{\"pm_velocity_deg\": {pm}}}");
                let (status, answer) = request(
                    addr,
                    "POST",
                    "/api/save",
                    "Host: 127.0.0.1\r\nContent-Type: application/json\r\n",
                    &body,
                );
                assert_eq!(status, 200, "save {k}: {answer}");
                let saved: serve::api::SaveResponse = serde_json::from_str(&answer).unwrap();
                answers.lock().unwrap().push((saved.path, pm));
            })
        })
        .collect();
    for c in clients {
        c.join().unwrap();
    }
    stop.store(true, Ordering::Relaxed);
    reader.join().unwrap();
    assert!(looks.load(Ordering::Relaxed) > 0);
    // One folder per save, each holding what its save answered; no temporaries left.
    let answers = answers.lock().unwrap();
    let mut paths: Vec<&String> = answers.iter().map(|a| &a.0).collect();
    paths.sort();
    paths.dedup();
    assert_eq!(paths.len(), 600, "two saves shared a folder");
    for (path, pm) in answers.iter() {
        let v: toml::Value = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        assert_eq!(
            v["pm_velocity_deg"].as_float(),
            Some(*pm),
            "{path} was overwritten"
        );
    }
    let names: Vec<String> = std::fs::read_dir(&s.dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 600);
    assert!(
        names.iter().all(|n| n.starts_with("tuned-")),
        "temporaries left"
    );
}

#[test]
fn host_header_must_be_exactly_one_loopback_name() {
    let s = start("host");
    let save = |headers: &str| {
        request(
            s.addr,
            "POST",
            "/api/save",
            &format!("{headers}Content-Type: application/json\r\n"),
            "{}",
        )
    };
    let (status, body) = save("");
    assert_eq!(status, 400, "{body}");
    assert!(json_error(status, &body).contains("exactly one Host"));
    let (status, body) = save("Host: 127.0.0.1\r\nHost: 127.0.0.1\r\n");
    assert_eq!(status, 400, "{body}");
    for host in [
        "[::1]evil.com",
        "localhost:evil.com",
        "localhost.",
        "127.0.0.1:",
        "127.0.0.1:99999",
        "[::1",
        "localhost:80:80",
        "[::ffff:127.0.0.1]:80",
    ] {
        let (status, body) = save(&format!("Host: {host}\r\n"));
        assert_eq!(status, 403, "{host}: {body}");
        assert!(json_error(status, &body).contains("loopback"));
    }
    assert!(!s.dir.join(serve::CONTROLLER_FILE).exists());
    for host in [
        "localhost",
        "LOCALHOST:8080",
        "127.0.0.1:1",
        "[::1]:8080",
        "[::1]",
    ] {
        assert!(serve::is_loopback_host(host), "{host}");
    }
}

#[test]
fn every_error_answer_is_json() {
    let s = start("json");
    let host = "Host: 127.0.0.1\r\n";
    let (status, body) = request(s.addr, "DELETE", "/api/save", host, "");
    assert_eq!(status, 405, "{body}");
    json_error(status, &body);
    let (status, body) = request(s.addr, "GET", "/api/design", host, "");
    assert_eq!(status, 405, "{body}");
    json_error(status, &body);
    let long = format!("/{}", "a".repeat(serve::MAX_URI_BYTES + 10));
    let (status, body) = request(s.addr, "GET", &long, host, "");
    assert_eq!(status, 414, "{body}");
    json_error(status, &body);
    let big = format!(
        "{host}X-Big: {}\r\n",
        "b".repeat(serve::MAX_HEADER_BYTES + 10)
    );
    let (status, body) = request(s.addr, "GET", "/api/info", &big, "");
    assert_eq!(status, 431, "{body}");
    json_error(status, &body);
    let (status, body) = request(s.addr, "GET", "/nowhere", host, "");
    assert_eq!(status, 404, "{body}");
    json_error(status, &body);
}

#[test]
fn slow_clients_are_cut_off_and_connections_are_limited() {
    let s = start("slow");
    // A partial head (slowloris): the server closes the connection after
    // the header timeout instead of holding it.
    let mut slow = TcpStream::connect(s.addr).unwrap();
    slow.write_all(b"GET /api/info HTTP/1.1\r\nHost: 127.0.0.1\r\n")
        .unwrap();
    slow.set_read_timeout(Some(serve::HEADER_READ_TIMEOUT * 3))
        .unwrap();
    let t0 = Instant::now();
    let mut buf = Vec::new();
    let r = slow.read_to_end(&mut buf);
    let waited = t0.elapsed();
    assert!(r.is_ok(), "connection still open after {waited:?}: {r:?}");
    assert!(waited < serve::HEADER_READ_TIMEOUT * 2, "{waited:?}");
    // A body that never completes: 408 with a JSON body.
    let raw = "POST /api/save HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n\
               Connection: close\r\nContent-Length: 100\r\n\r\n{\"pm";
    let (status, body) = exchange(s.addr, raw.as_bytes());
    assert_eq!(status, 408, "{body}");
    json_error(status, &body);
    // Connections beyond the limit get 503 at once.
    let held: Vec<TcpStream> = (0..serve::MAX_CONNECTIONS)
        .map(|_| {
            let mut c = TcpStream::connect(s.addr).unwrap();
            c.write_all(b"GET / HTTP/1.1\r\n").unwrap();
            c
        })
        .collect();
    // Let the server accept them all.
    std::thread::sleep(Duration::from_millis(500));
    let (status, body) = request(s.addr, "GET", "/api/info", "Host: 127.0.0.1\r\n", "");
    assert_eq!(status, 503, "{body}");
    assert!(json_error(status, &body).contains("busy"));
    drop(held);
    // Freed connections are served again.
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (status, _) = request(s.addr, "GET", "/api/info", "Host: 127.0.0.1\r\n", "");
        if status == 200 {
            break;
        }
        assert!(Instant::now() < deadline, "still {status}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn malformed_request_heads_get_json_answers() {
    let s = start("heads");
    let host = "Host: 127.0.0.1\r\n";
    // a garbage request line (a TLS hello sent to plain HTTP)
    let (status, body) = exchange(
        s.addr,
        b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03\r\n\r\n",
    );
    assert_eq!(status, 400, "{body}");
    json_error(status, &body);
    // more headers than allowed
    let many: String = (0..101).map(|k| format!("X-H{k}: v\r\n")).collect();
    let (status, body) = request(s.addr, "GET", "/api/info", &format!("{host}{many}"), "");
    assert_eq!(status, 431, "{body}");
    assert!(json_error(status, &body).contains("headers"));
    // a 70 KB target, longer than anything read before hyper
    let long = format!("/{}", "a".repeat(70 * 1024));
    let (status, body) = request(s.addr, "GET", &long, host, "");
    assert_eq!(status, 414, "{body}");
    json_error(status, &body);
    // request smuggling: two lengths, or a length and a transfer encoding
    let raw = "POST /api/design HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n\
               Content-Length: 2\r\nContent-Length: 3\r\nConnection: close\r\n\r\n{}";
    let (status, body) = exchange(s.addr, raw.as_bytes());
    assert_eq!(status, 400, "{body}");
    assert!(json_error(status, &body).contains("Content-Length"));
    let raw = "POST /api/design HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n\
               Content-Length: 2\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n\r\n{}";
    let (status, body) = exchange(s.addr, raw.as_bytes());
    assert_eq!(status, 400, "{body}");
    json_error(status, &body);
    // and a plain request still works
    let (status, body) = request(s.addr, "GET", "/api/info", host, "");
    assert_eq!(status, 200, "{body}");
}

#[test]
fn clients_that_pipeline_and_never_read_do_not_hold_the_server() {
    // Every connection slot taken by a client that pipelines requests and
    // reads nothing: each gets one answer and is closed, so the page is
    // served again at once (it used to answer 503 for the 5-minute life of
    // those connections).
    let s = start("pipeline");
    let one = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
    let held: Vec<TcpStream> = (0..serve::MAX_CONNECTIONS)
        .map(|_| {
            let mut c = TcpStream::connect(s.addr).unwrap();
            let _ = c.write_all(one.repeat(40).as_bytes());
            c
        })
        .collect();
    let deadline = Instant::now() + serve::conn::WRITE_TIMEOUT + Duration::from_secs(5);
    loop {
        let (status, _) = request(s.addr, "GET", "/api/info", "Host: 127.0.0.1\r\n", "");
        if status == 200 {
            break;
        }
        assert_eq!(status, 503);
        assert!(
            Instant::now() < deadline,
            "still busy while the pipelining clients hold their connections"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    drop(held);
}

#[test]
fn the_page_cannot_be_framed_or_posted_to_from_another_site() {
    let s = start("framing");
    let host = "Host: 127.0.0.1\r\n";
    let raw = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
    let mut c = TcpStream::connect(s.addr).unwrap();
    c.write_all(raw.as_bytes()).unwrap();
    let mut answer = String::new();
    c.read_to_string(&mut answer).unwrap();
    let head = answer
        .split("\r\n\r\n")
        .next()
        .unwrap()
        .to_ascii_lowercase();
    assert!(head.contains("x-frame-options: deny"), "{head}");
    assert!(head.contains("frame-ancestors 'none'"), "{head}");
    let body = "{}";
    let json = "Content-Type: application/json\r\n";
    for extra in [
        "Origin: http://evil.example\r\n",
        "Origin: null\r\n",
        "Origin: http://127.0.0.1:1\r\n",
        "Sec-Fetch-Site: cross-site\r\n",
        "Sec-Fetch-Site: same-site\r\n",
    ] {
        let (status, answer) = request(
            s.addr,
            "POST",
            "/api/save",
            &format!("{host}{json}{extra}"),
            body,
        );
        assert_eq!(status, 403, "{extra}: {answer}");
        json_error(status, &answer);
    }
    assert!(
        std::fs::read_dir(&s.dir).map_or(true, |mut d| d.next().is_none()),
        "a refused save wrote a file"
    );
    // the page's own requests pass the check (the test double answers 500
    // for a design: it designs nothing)
    let own = "Origin: http://127.0.0.1\r\nSec-Fetch-Site: same-origin\r\n";
    let (status, answer) = request(
        s.addr,
        "POST",
        "/api/design",
        &format!("{host}{json}{own}"),
        body,
    );
    assert_ne!(status, 403, "{answer}");
}
