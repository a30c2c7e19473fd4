//! Helpers shared by the CLI integration tests: a headless Chromium session
//! (this file), the HTTP client of the `serve` tests ([`http`]) and the bench
//! recording ([`bench`]).
#![allow(dead_code)]

pub mod bench;
pub mod drive;
pub mod http;

use fantoccini::{Client, ClientBuilder};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The two-mass model of thesis Table A.4 as the keys of a model TOML file
/// (`theta_e`, `m_c`, `c`, `d_m`, `d_c`, `i_t`; no dead time, no friction),
/// from the library's one definition ([`beltune::model::TwoMassParams::thesis_table_a4`]).
pub fn table_a4_model_toml() -> String {
    let p = beltune::model::TwoMassParams::thesis_table_a4();
    format!(
        "theta_e = {:?}\nm_c = {:?}\nc = {:?}\nd_m = {:?}\nd_c = {:?}\ni_t = {:?}\n",
        p.theta_e, p.m_c, p.c, p.d_m, p.d_c, p.i_t
    )
}

/// Debian's Chromium (`apt-get install chromium chromium-driver`; `.ci/run` installs it).
pub const CHROMIUM: &str = "/usr/bin/chromium";

/// A program on `PATH`.
pub fn find_program(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join(name))
            .find(|p| p.is_file())
    })
}

/// Kills the child (chromedriver) when the test ends, also on panic.
pub struct Reaper(pub Child);
impl Drop for Reaper {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A free TCP port on loopback.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Start chromedriver and connect a headless Chromium session with a fresh
/// profile. Panics (fails the test) with an install hint if either is missing.
pub async fn headless_chromium(profile_dir: &std::path::Path) -> (Client, Reaper) {
    let driver = find_program("chromedriver").unwrap_or_else(|| {
        panic!("chromedriver not found: install Debian's chromium and chromium-driver (apt-get install -y chromium chromium-driver)")
    });
    assert!(
        std::path::Path::new(CHROMIUM).is_file(),
        "{CHROMIUM} not found: install Debian's chromium (apt-get install -y chromium chromium-driver)"
    );
    let port = free_port();
    let child = Command::new(driver)
        .arg(format!("--port={port}"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromedriver");
    let reaper = Reaper(child);
    let mut caps = serde_json::Map::new();
    caps.insert(
        "goog:chromeOptions".into(),
        serde_json::json!({
            "binary": CHROMIUM,
            "args": [
                "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--no-first-run",
                format!("--user-data-dir={}", profile_dir.display()),
            ],
        }),
    );
    let url = format!("http://127.0.0.1:{port}");
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        match ClientBuilder::native()
            .capabilities(caps.clone())
            .connect(&url)
            .await
        {
            Ok(c) => return (c, reaper),
            Err(e) if Instant::now() > deadline => panic!("cannot connect to chromedriver: {e}"),
            Err(_) => tokio::time::sleep(Duration::from_millis(200)).await,
        }
    }
}
