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

/// One Chrome DevTools Protocol command through ChromeDriver's extension
/// endpoint `POST /session/{id}/goog/cdp/execute`.
#[derive(Debug)]
struct Cdp {
    cmd: &'static str,
    params: serde_json::Value,
}

impl fantoccini::wd::WebDriverCompatibleCommand for Cdp {
    fn endpoint(
        &self,
        base_url: &url::Url,
        session_id: Option<&str>,
    ) -> Result<url::Url, url::ParseError> {
        base_url.join(&format!(
            "session/{}/goog/cdp/execute",
            session_id.unwrap_or_default()
        ))
    }

    fn method_and_body(&self, _: &url::Url) -> (axum::http::Method, Option<String>) {
        let body = serde_json::json!({ "cmd": self.cmd, "params": self.params });
        (axum::http::Method::POST, Some(body.to_string()))
    }
}

/// Lay the page out for the CSS media type `media`: "print" shows what the
/// browser prints (`@media print` rules apply), "" returns to the screen
/// (DevTools' `Emulation.setEmulatedMedia`).
pub async fn emulate_media(c: &Client, media: &str) {
    c.issue_cmd(Cdp {
        cmd: "Emulation.setEmulatedMedia",
        params: serde_json::json!({ "media": media }),
    })
    .await
    .unwrap_or_else(|e| panic!("cannot emulate media `{media}`: {e}"));
}

/// The plot area (uPlot's `.u-over`) of the plot `#id`, scrolled into the
/// middle of the window, and its width and height in CSS px.
pub async fn plot_area(c: &Client, id: &str) -> (fantoccini::elements::Element, f64, f64) {
    let sel = format!("#{id} .u-over");
    let wh = c
        .execute(
            &format!(
                "const o = document.querySelector('{sel}'); o.scrollIntoView({{block: 'center'}}); \
                 const r = o.getBoundingClientRect(); return [r.width, r.height];"
            ),
            vec![],
        )
        .await
        .unwrap();
    let el = c
        .find(fantoccini::Locator::Css(&sel))
        .await
        .unwrap_or_else(|e| panic!("{sel}: {e}"));
    (
        el,
        wh[0].as_f64().expect("plot width"),
        wh[1].as_f64().expect("plot height"),
    )
}

/// Offset of the fraction `(fx, fy)` of a `w` x `h` box from its centre (the
/// origin of WebDriver's element-relative pointer moves), whole px.
fn from_centre(w: f64, h: f64, fx: f64, fy: f64) -> (f64, f64) {
    (((fx - 0.5) * w).round(), ((fy - 0.5) * h).round())
}

/// Move the mouse (a real pointer through WebDriver) to the fraction `(fx, fy)`
/// of the plot area of `#id`.
pub async fn hover_plot(c: &Client, id: &str, fx: f64, fy: f64) {
    use fantoccini::actions::{InputSource, MouseActions, PointerAction};
    let (el, w, h) = plot_area(c, id).await;
    let (x, y) = from_centre(w, h, fx, fy);
    let mouse = MouseActions::new("mouse".into()).then(PointerAction::MoveToElement {
        element: el,
        duration: None,
        x,
        y,
    });
    c.perform_actions(mouse).await.unwrap();
}

/// Drag with the left button across the plot area of `#id` from the fraction
/// `fx0` to `fx1` of its width (at mid height).
pub async fn drag_plot(c: &Client, id: &str, fx0: f64, fx1: f64) {
    use fantoccini::actions::{InputSource, MouseActions, PointerAction, MOUSE_BUTTON_LEFT};
    let (el, w, h) = plot_area(c, id).await;
    let (x0, y) = from_centre(w, h, fx0, 0.5);
    let (x1, _) = from_centre(w, h, fx1, 0.5);
    let step = Some(Duration::from_millis(50));
    let mouse = MouseActions::new("mouse".into())
        .then(PointerAction::MoveToElement {
            element: el.clone(),
            duration: None,
            x: x0,
            y,
        })
        .then(PointerAction::Down {
            button: MOUSE_BUTTON_LEFT,
        })
        .then(PointerAction::MoveToElement {
            element: el.clone(),
            duration: step,
            x: (x0 + x1) / 2.0,
            y,
        })
        .then(PointerAction::MoveToElement {
            element: el,
            duration: step,
            x: x1,
            y,
        })
        .then(PointerAction::Up {
            button: MOUSE_BUTTON_LEFT,
        });
    c.perform_actions(mouse).await.unwrap();
    c.release_actions().await.unwrap();
}

/// Double-click the middle of the plot area of `#id`.
pub async fn double_click_plot(c: &Client, id: &str) {
    use fantoccini::actions::{InputSource, MouseActions, PointerAction, MOUSE_BUTTON_LEFT};
    let (el, _, _) = plot_area(c, id).await;
    let mut mouse = MouseActions::new("mouse".into()).then(PointerAction::MoveToElement {
        element: el,
        duration: None,
        x: 0.0,
        y: 0.0,
    });
    for _ in 0..2 {
        mouse = mouse
            .then(PointerAction::Down {
                button: MOUSE_BUTTON_LEFT,
            })
            .then(PointerAction::Up {
                button: MOUSE_BUTTON_LEFT,
            });
    }
    c.perform_actions(mouse).await.unwrap();
    c.release_actions().await.unwrap();
}
