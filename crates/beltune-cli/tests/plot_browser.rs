//! The interactive plots (uPlot, vendored) of the tuning page and of the
//! report in headless Chromium, driven by a real pointer through WebDriver:
//!
//! - dragging across a plot zooms its x range to the dragged span, a
//!   double-click zooms out again;
//! - hovering a plot shows the values under the cursor with their units, and
//!   on the page they are the numbers the design library computes;
//! - the frequency axis is logarithmic: equal distances are equal frequency
//!   ratios (the definition of a log axis, not uPlot's code), its labels are
//!   1, 2, 5 times powers of ten;
//! - printed (CSS print media), the report shows its static SVG plots and
//!   hides the interactive charts; on screen it is the other way round.
//!
//! The page runs on the built-in axis (egc70); the report is
//! `beltune commission`'s on egc70 with its defaults. Missing Chromium or
//! ChromeDriver fails the test (install: `apt-get install -y chromium
//! chromium-driver fonts-dejavu-core`).

mod common;

use beltune_cli::serve::{self, library::LibraryTuner, tuner::Tuner, AppState};
use fantoccini::Client;
use serde_json::Value;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// How long a page may take to show a result (2 shared cores).
const WAIT: Duration = Duration::from_secs(90);
/// The page's open-loop magnitude plot.
const PAGE_BODE: &str = "plot-bode-mag";
/// The report's velocity open loop, its magnitude panel.
const REPORT_BODE: &str = "open-loop-0-chart-0";
/// Where a drag starts and ends, fractions of the plot width.
const DRAG: (f64, f64) = (0.3, 0.7);
/// Pointer positions land on whole CSS px, and the browser may round the
/// element's centre: a drag end or cursor is within this many px of the
/// requested fraction.
const PX_TOL: f64 = 2.0;

fn temp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-plot-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `beltune commission` on egc70 (defaults), once per test binary: its report.
fn report() -> PathBuf {
    static DIR: OnceLock<Mutex<Option<PathBuf>>> = OnceLock::new();
    let mut dir = DIR.get_or_init(|| Mutex::new(None)).lock().unwrap();
    if let Some(d) = dir.as_ref() {
        return d.join("report.html");
    }
    let d = temp("report");
    let out = Command::new(env!("CARGO_BIN_EXE_beltune"))
        .args(["commission", "--quiet", "--out"])
        .arg(&d)
        .output()
        .expect("running beltune commission");
    assert!(
        out.status.success(),
        "beltune commission: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    *dir = Some(d.clone());
    d.join("report.html")
}

async fn start_page(tag: &str) -> SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let state = AppState {
        tuner: Arc::new(LibraryTuner::builtin().unwrap()),
        save_dir: temp(tag),
        loopback_only: true,
    };
    tokio::spawn(serve::serve(listener, state));
    addr
}

async fn js(c: &Client, expr: &str) -> Value {
    c.execute(&format!("return {expr};"), vec![]).await.unwrap()
}

async fn wait_js(c: &Client, expr: &str, what: &str) -> Value {
    let started = Instant::now();
    loop {
        let v = js(c, expr).await;
        let truthy = match &v {
            Value::Null => false,
            Value::Bool(b) => *b,
            Value::String(s) => !s.is_empty(),
            _ => true,
        };
        if truthy {
            return v;
        }
        assert!(started.elapsed() < WAIT, "timed out waiting for {what}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// The page at `addr`, its first design drawn.
async fn open_page(c: &Client, addr: SocketAddr) {
    c.goto(&format!("http://{addr}/")).await.unwrap();
    wait_js(
        c,
        "Number(document.body.dataset.renderSeq || 0) > 0 && \
         !document.body.classList.contains('stale') && \
         !!document.getElementById('plot-bode-mag').uplot",
        "the page to draw its plots",
    )
    .await;
}

/// The report, its interactive charts drawn.
async fn open_report(c: &Client, report: &Path) {
    c.goto(&format!("file://{}", report.display()))
        .await
        .unwrap();
    wait_js(
        c,
        &format!("!!document.getElementById('{REPORT_BODE}') && !!document.getElementById('{REPORT_BODE}').uplot"),
        "the report's charts",
    )
    .await;
}

/// The x range plot `#id` shows: [min, max].
async fn x_range(c: &Client, id: &str) -> (f64, f64) {
    let v = js(
        c,
        &format!("(() => {{ const u = document.getElementById('{id}').uplot; return [u.scales.x.min, u.scales.x.max]; }})()"),
    )
    .await;
    (v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

/// The legend rows of plot `#id` (uPlot's live read-out): (label, value text).
async fn readout(c: &Client, id: &str) -> Vec<(String, String)> {
    let v = js(
        c,
        &format!(
            "[...document.querySelectorAll('#{id} .u-legend .u-series')].map((tr) => \
             [tr.querySelector('.u-label').textContent, tr.querySelector('.u-value').textContent])"
        ),
    )
    .await;
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r[0].as_str().unwrap().to_string(),
                r[1].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

/// Hover at the fraction `fx` of the plot's width; the read-out once it shows a value.
async fn hover_readout(c: &Client, id: &str, fx: f64) -> Vec<(String, String)> {
    common::hover_plot(c, id, fx, 0.5).await;
    let started = Instant::now();
    loop {
        let rows = readout(c, id).await;
        if rows
            .first()
            .is_some_and(|r| r.1.chars().any(|ch| ch.is_ascii_digit()))
        {
            return rows;
        }
        assert!(
            started.elapsed() < WAIT,
            "#{id}: no read-out on hover: {rows:?}"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// The number and unit of a read-out text such as "12.34 Hz".
fn value_unit(text: &str) -> (f64, String) {
    let (v, u) = text
        .split_once(' ')
        .unwrap_or_else(|| panic!("read-out `{text}` has no unit"));
    (
        v.parse()
            .unwrap_or_else(|_| panic!("read-out `{text}`: not a number")),
        u.to_string(),
    )
}

/// `x` rounded to 4 significant digits, as the read-out shows it.
fn sig4(x: f64) -> f64 {
    format!("{x:.3e}").parse().unwrap()
}

/// The frequency at the fraction `p` of a log axis from `x0` to `x1`.
fn log_axis(x0: f64, x1: f64, p: f64) -> f64 {
    x0 * (x1 / x0).powf(p)
}

/// The plot-area width of `#id`, CSS px.
async fn plot_width(c: &Client, id: &str) -> f64 {
    js(
        c,
        &format!("document.querySelector('#{id} .u-over').getBoundingClientRect().width"),
    )
    .await
    .as_f64()
    .unwrap()
}

/// Run `body` with a headless Chromium session, closed afterwards (also on panic).
async fn with_browser<F, Fut>(tag: &str, body: F)
where
    F: FnOnce(Client) -> Fut + Send + 'static,
    Fut: std::future::Future<Output = ()> + Send + 'static,
{
    let profile = temp(&format!("{tag}-profile"));
    let (c, _driver) = common::headless_chromium(&profile).await;
    c.set_window_size(1400, 1000).await.unwrap();
    let result = tokio::spawn(body(c.clone())).await;
    let _ = c.close().await;
    let _ = std::fs::remove_dir_all(&profile);
    if let Err(e) = result {
        std::panic::resume_unwind(e.into_panic());
    }
}

/// Drag across `#id` from 30 % to 70 % of its width: the x range becomes the
/// dragged span (on the log axis: the frequencies at those fractions); a
/// double-click returns to the full range.
async fn check_zoom(c: &Client, id: &str) {
    let (x0, x1) = x_range(c, id).await;
    let width = plot_width(c, id).await;
    common::drag_plot(c, id, DRAG.0, DRAG.1).await;
    let (z0, z1) = x_range(c, id).await;
    assert!(
        z0 > x0 && z1 < x1 && z0 < z1,
        "#{id}: a drag did not zoom: {x0}..{x1} -> {z0}..{z1}"
    );
    // PX_TOL px of the plot width, as a frequency ratio
    let ratio_tol = (x1 / x0).powf(PX_TOL / width);
    for (got, want, end) in [
        (z0, log_axis(x0, x1, DRAG.0), "start"),
        (z1, log_axis(x0, x1, DRAG.1), "end"),
    ] {
        assert!(
            got / want <= ratio_tol && want / got <= ratio_tol,
            "#{id}: zoomed {end} at {got} Hz, the drag's {end} is at {want} Hz (full range {x0}..{x1} Hz)"
        );
    }
    common::double_click_plot(c, id).await;
    let started = Instant::now();
    while x_range(c, id).await != (x0, x1) {
        assert!(
            started.elapsed() < WAIT,
            "#{id}: a double-click did not zoom out: {:?}",
            x_range(c, id).await
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dragging_across_a_plot_zooms_its_x_range() {
    let addr = start_page("zoom").await;
    let report = report();
    with_browser("zoom", move |c| async move {
        open_page(&c, addr).await;
        check_zoom(&c, PAGE_BODE).await;
        // the time plots zoom too (a linear axis: the span is linear in time)
        let (t0, t1) = x_range(&c, "plot-error").await;
        common::drag_plot(&c, "plot-error", DRAG.0, DRAG.1).await;
        let (z0, z1) = x_range(&c, "plot-error").await;
        let width = plot_width(&c, "plot-error").await;
        let tol_s = PX_TOL / width * (t1 - t0);
        assert!(
            (z0 - (t0 + DRAG.0 * (t1 - t0))).abs() <= tol_s
                && (z1 - (t0 + DRAG.1 * (t1 - t0))).abs() <= tol_s,
            "time plot zoomed to {z0}..{z1} s from {t0}..{t1} s"
        );
        // a knob change redraws the plots and keeps the zoom
        let seq = js(&c, "Number(document.body.dataset.renderSeq)").await;
        common::drag_plot(&c, PAGE_BODE, DRAG.0, DRAG.1).await;
        let zoomed = x_range(&c, PAGE_BODE).await;
        c.execute(
            "const s = document.getElementById('pm_position_deg'); s.value = String(Number(s.value) - 5); \
             s.dispatchEvent(new Event('input')); return 0;",
            vec![],
        )
        .await
        .unwrap();
        wait_js(
            &c,
            &format!(
                "Number(document.body.dataset.renderSeq) > {seq} && !document.body.classList.contains('stale')"
            ),
            "the redraw after a knob change",
        )
        .await;
        assert_eq!(
            x_range(&c, PAGE_BODE).await,
            zoomed,
            "a knob change lost the zoom"
        );

        open_report(&c, &report).await;
        check_zoom(&c, REPORT_BODE).await;
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hovering_a_plot_shows_the_values_with_their_units() {
    let addr = start_page("hover").await;
    let report = report();
    // the numbers the page plots: the design library through the page's tuner
    let tuned = LibraryTuner::builtin()
        .unwrap()
        .tune(&serve::api::DesignRequest::default().validate().unwrap())
        .unwrap();
    with_browser("hover", move |c| async move {
        open_page(&c, addr).await;
        let rows = hover_readout(&c, PAGE_BODE, 0.5).await;
        // frequency in Hz, both loops in dB
        let (f, unit) = value_unit(&rows[0].1);
        assert_eq!(unit, "Hz", "{rows:?}");
        let b = &tuned.bode;
        let i = (0..b.freq_hz.len())
            .min_by(|&a, &k| {
                (b.freq_hz[a] / f)
                    .ln()
                    .abs()
                    .total_cmp(&(b.freq_hz[k] / f).ln().abs())
            })
            .unwrap();
        assert_eq!(
            f,
            sig4(b.freq_hz[i]),
            "the read-out's frequency is not a plotted one"
        );
        for (row, curve, label) in [
            (1, &b.open_loop_velocity, "velocity loop"),
            (2, &b.open_loop_position, "position loop"),
        ] {
            assert_eq!(rows[row].0, label, "{rows:?}");
            let (v, unit) = value_unit(&rows[row].1);
            assert_eq!(unit, "dB", "{rows:?}");
            assert_eq!(
                v,
                sig4(curve.magnitude_db[i]),
                "{label} at {} Hz: read-out {v} dB",
                b.freq_hz[i]
            );
        }
        // the time plots read seconds and millimetres / newton metres
        for (id, want) in [("plot-error", "mm"), ("plot-torque", "N m")] {
            let rows = hover_readout(&c, id, 0.5).await;
            assert_eq!(value_unit(&rows[0].1).1, "s", "{id}: {rows:?}");
            assert_eq!(value_unit(&rows[1].1).1, want, "{id}: {rows:?}");
        }

        open_report(&c, &report).await;
        let rows = hover_readout(&c, REPORT_BODE, 0.5).await;
        assert_eq!(value_unit(&rows[0].1).1, "Hz", "{rows:?}");
        assert!(rows.len() >= 2, "{rows:?}");
        for r in &rows[1..] {
            assert_eq!(value_unit(&r.1).1, "dB", "{rows:?}");
        }
        let rows = hover_readout(&c, "moves-chart-1", 0.5).await;
        assert_eq!(value_unit(&rows[0].1).1, "s", "{rows:?}");
        assert_eq!(value_unit(&rows[1].1).1, "mm", "{rows:?}");
    })
    .await;
}

/// Hovering at 25, 50 and 75 % of the width reads the frequencies a log axis
/// has there, within half the widest step between plotted points (the cursor
/// snaps to the nearest) and [`PX_TOL`]; a linear axis would read far off.
async fn check_log_axis(c: &Client, id: &str) {
    let (x0, x1) = x_range(c, id).await;
    assert!(x1 / x0 > 100.0, "#{id}: {x0}..{x1} Hz is not two decades");
    let width = plot_width(c, id).await;
    // the widest step between neighbouring plotted frequencies, as a ratio
    let step = js(
        c,
        &format!(
            "(() => {{ const x = document.getElementById('{id}').uplot.data[0]; let r = 1; \
             for (let i = 1; i < x.length; i++) r = Math.max(r, x[i] / x[i - 1]); return r; }})()"
        ),
    )
    .await
    .as_f64()
    .unwrap();
    let tol = step.sqrt() * (x1 / x0).powf(PX_TOL / width);
    for p in [0.25, 0.5, 0.75] {
        let rows = hover_readout(c, id, p).await;
        let (f, _) = value_unit(&rows[0].1);
        let want = log_axis(x0, x1, p);
        assert!(
            f / want <= tol * 1.001 && want / f <= tol * 1.001,
            "#{id}: at {p} of the width the read-out is {f} Hz, a log axis has {want} Hz there"
        );
        let linear = x0 + p * (x1 - x0);
        assert!(
            (f / linear).ln().abs() > 5.0 * tol.ln(),
            "#{id}: {f} Hz is where a linear axis would be"
        );
    }
    // the labels: 1, 2, 5 (or every integer) times powers of ten, over two decades at least
    let ticks = js(
        c,
        &format!("document.getElementById('{id}').dataset.xTicks"),
    )
    .await;
    let ticks: Vec<f64> = ticks
        .as_str()
        .unwrap()
        .split('|')
        .map(|t| t.parse().unwrap())
        .collect();
    assert!(ticks.len() >= 6, "#{id}: frequency labels {ticks:?}");
    for t in &ticks {
        let lead = t / 10f64.powf(t.log10().floor());
        assert!(
            (lead - lead.round()).abs() < 1e-9,
            "#{id}: label {t} is not a multiple of a power of ten"
        );
    }
    assert!(
        ticks.last().unwrap() / ticks.first().unwrap() >= 100.0,
        "{ticks:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_frequency_axis_is_logarithmic() {
    let addr = start_page("log").await;
    let report = report();
    with_browser("log", move |c| async move {
        open_page(&c, addr).await;
        for id in [PAGE_BODE, "plot-sensitivity", "plot-frf-mag"] {
            check_log_axis(&c, id).await;
        }
        open_report(&c, &report).await;
        for id in [REPORT_BODE, "frf-chart-0"] {
            check_log_axis(&c, id).await;
        }
    })
    .await;
}

/// For every figure of the report with an interactive chart: (static SVG's
/// rendered width and height, interactive part's width and height, canvases
/// drawn in it).
const FIGURE_SIZES_JS: &str = r#"
return [...document.querySelectorAll('figure')].filter((f) => f.querySelector('.interactive')).map((f) => {
  const s = f.querySelector('.static svg').getBoundingClientRect();
  const i = f.querySelector('.interactive').getBoundingClientRect();
  return [f.id, s.width, s.height, i.width, i.height, f.querySelectorAll('.interactive canvas').length];
});
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn printing_the_report_shows_the_static_svg() {
    let report = report();
    with_browser("print", move |c| async move {
        open_report(&c, &report).await;
        let figures = |v: Value| -> Vec<(String, [f64; 5])> {
            v.as_array()
                .unwrap()
                .iter()
                .map(|f| {
                    (
                        f[0].as_str().unwrap().to_string(),
                        [1, 2, 3, 4, 5].map(|k| f[k].as_f64().unwrap()),
                    )
                })
                .collect()
        };
        // on screen: the interactive charts, the SVG hidden
        let screen = figures(c.execute(FIGURE_SIZES_JS, vec![]).await.unwrap());
        for want in ["frf", "controller", "open-loop-0", "moves"] {
            assert!(
                screen.iter().any(|(id, _)| id == want),
                "#{want} has no interactive chart: {screen:?}"
            );
        }
        for (id, [sw, sh, iw, ih, canvases]) in &screen {
            assert!(
                *sw == 0.0 && *sh == 0.0,
                "#{id}: the SVG shows on screen ({sw} x {sh})"
            );
            assert!(
                *iw > 300.0 && *ih > 150.0 && *canvases >= 1.0,
                "#{id}: no chart on screen ({iw} x {ih}, {canvases} canvases)"
            );
        }
        // printed: the SVG, the interactive charts hidden
        common::emulate_media(&c, "print").await;
        let print = figures(c.execute(FIGURE_SIZES_JS, vec![]).await.unwrap());
        assert_eq!(print.len(), screen.len());
        for (id, [sw, sh, iw, ih, _]) in &print {
            assert!(
                *sw > 300.0 && *sh > 150.0,
                "#{id}: the SVG does not print ({sw} x {sh})"
            );
            assert!(
                *iw == 0.0 && *ih == 0.0,
                "#{id}: the interactive chart prints ({iw} x {ih})"
            );
        }
        // the report needs nothing beside it: no element loads anything
        let loads = js(&c, "document.querySelectorAll('[src], link[href]').length").await;
        assert_eq!(loads.as_u64(), Some(0), "the report loads a file");
    })
    .await;
}
