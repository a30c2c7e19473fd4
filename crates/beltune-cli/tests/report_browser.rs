//! The report and the tuning page in headless Chromium.
//!
//! - `beltune commission` (egc70, its defaults) writes the report; the tuning
//!   page on the built-in axis (which commissions the same axis at start-up)
//!   must show the same numbers: the test reads them off both (the report's
//!   `data-value` attributes, the page's) and compares them.
//! - The FRF phase axis of egc70's report stays within [-720, 360] deg (the
//!   phase of excluded noisy lines once ran to -2000..+7000 deg).
//! - No two text labels of any plot overlap (bounding boxes from the browser),
//!   in the report (its static SVG as printed and its interactive charts on
//!   screen), the page and a comparison report.
//! - `beltune compare` on egc70 at 0 and 11.2 kg shows the resonance shift.
//! - The same folder loaded into the page (`serve --commissioning`) simulates
//!   its move on the plant the commissioning ran on: the report's number again.
//!
//! Missing Chromium or ChromeDriver fails the test (install:
//! `apt-get install -y chromium chromium-driver fonts-dejavu-core`).

mod common;

use beltune_cli::serve::{self, library::LibraryTuner, AppState};
use fantoccini::Client;
use serde_json::Value;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long the page may take to show a result (2 shared cores).
const WAIT: Duration = Duration::from_secs(90);
/// The report's data-value and the page's data-value are the same f64 printed
/// shortest-round-trip; unit scalings (Hz, mm, um) cost at most a few ulps.
const REL_TOL: f64 = 1e-12;
/// Overlap of two text boxes that counts, px (anti-aliasing slack).
const OVERLAP_SLACK_PX: f64 = 0.5;
/// The page's simulated move and the commissioning's validation move run the
/// same plant, controller and trajectory through the same library function;
/// they differ only in the noise realization and in the state the earlier
/// stages leave the simulated axis in (measured: 0.6405 vs 0.6398 mm before the
/// design rule and the Coulomb hold of main a9fc2f4; 0.5528 vs 0.5258 mm, 5.1 %,
/// after them: the part of that left to the axis state is not yet explained).
const SAME_MOVE_REL_TOL: f64 = 0.06;
/// ... or this much absolute, m: the report's move starts where the
/// commissioning's creep to the start left the cart at rest (within its static
/// error band, up to tens of um), the page's from exact rest; with max errors
/// near 0.2 mm (since the design rule, the Coulomb hold and the aligned record)
/// that start alone moves the max error by a few tens of um.
const SAME_MOVE_ABS_TOL_M: f64 = 50e-6;
/// The phase axis of the FRF plot must lie within this interval, deg.
const PHASE_AXIS_DEG: (f64, f64) = (-720.0, 360.0);

fn temp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-report-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn beltune(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_beltune"))
        .args(args)
        .output()
        .expect("running beltune");
    assert!(
        out.status.success(),
        "beltune {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn commission(dir: &Path, extra: &[&str]) {
    let mut args = vec!["commission", "--quiet", "--out", dir.to_str().unwrap()];
    args.extend_from_slice(extra);
    beltune(&args);
}

async fn js(c: &Client, script: &str) -> Value {
    c.execute(script, vec![]).await.unwrap()
}

async fn wait_js(c: &Client, expr: &str, what: &str) -> Value {
    let started = Instant::now();
    loop {
        let v = js(c, &format!("return {expr};")).await;
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

/// Every pair of non-empty labels of one plot whose browser bounding boxes
/// overlap: `<text>` elements of an `<svg>` (the report's static plots) and
/// the labels over an interactive plot (`.plot-label` in a `.plot`):
/// `{overlaps: [[figure, text a, text b, box a, box b]], shown: labels with a size}`.
const OVERLAPS_JS: &str = r#"
const slack = arguments[0];
const out = [];
let shown = 0;
document.querySelectorAll('svg, .plot').forEach((host) => {
  const fig = (host.closest('figure') && host.closest('figure').id) || host.id || '?';
  const boxes = [...host.querySelectorAll(host.tagName.toLowerCase() === 'svg' ? 'text' : '.plot-label')]
    .filter((t) => t.textContent.trim() !== '')
    .map((t) => { const r = t.getBoundingClientRect();
      return { t: t.textContent.trim(), x0: r.left, y0: r.top, x1: r.right, y1: r.bottom, w: r.width }; })
    .filter((b) => b.w > 0);
  shown += boxes.length;
  for (let i = 0; i < boxes.length; i++) {
    for (let j = i + 1; j < boxes.length; j++) {
      const a = boxes[i], b = boxes[j];
      const ox = Math.min(a.x1, b.x1) - Math.max(a.x0, b.x0);
      const oy = Math.min(a.y1, b.y1) - Math.max(a.y0, b.y0);
      if (ox > slack && oy > slack) out.push([fig, a.t, b.t, [a.x0, a.y0, a.x1, a.y1], [b.x0, b.y0, b.x1, b.y1]]);
    }
  }
});
return {overlaps: out, shown: shown};
"#;

/// No two labels of a plot overlap, and at least `min_shown` labels are laid
/// out (the check saw the plots).
async fn assert_no_overlapping_labels(c: &Client, what: &str, min_shown: u64) {
    let r = c
        .execute(OVERLAPS_JS, vec![Value::from(OVERLAP_SLACK_PX)])
        .await
        .unwrap();
    let list = r["overlaps"].as_array().unwrap();
    assert!(list.is_empty(), "{what}: overlapping labels: {list:?}");
    let n = r["shown"].as_u64().unwrap();
    assert!(
        n >= min_shown,
        "{what}: {n} labels laid out, expected {min_shown} or more"
    );
}

/// The report's parameter table: name -> data-value.
async fn report_parameters(c: &Client) -> HashMap<String, f64> {
    let v = js(
        c,
        r#"return [...document.querySelectorAll('#parameters tr')].slice(1).map((tr) =>
            [tr.cells[0].textContent, tr.querySelector('td.after').dataset.value]);"#,
    )
    .await;
    v.as_array()
        .unwrap()
        .iter()
        .filter_map(|r| {
            let name = r[0].as_str()?.to_string();
            let value = r[1].as_str()?.parse().ok()?;
            Some((name, value))
        })
        .collect()
}

async fn page_number(c: &Client, id: &str) -> f64 {
    let v = js(
        c,
        &format!("return document.getElementById('{id}').dataset.value;"),
    )
    .await;
    v.as_str()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("#{id} shows no number: {v}"))
}

fn assert_same(what: &str, report: f64, page: f64) {
    assert!(
        (report - page).abs() <= REL_TOL * report.abs().max(1e-300),
        "{what}: report {report} vs page {page}"
    );
}

/// The numeric tick labels of the phase panel of the FRF figure: each y tick
/// (right-aligned number left of the plot) belongs to the panel whose rotated
/// axis description ("phase / deg") is vertically nearest.
const PHASE_TICKS_JS_BODY: &str = r#"
const svg = document.querySelector('#frf svg');
const texts = [...svg.querySelectorAll('text')];
const center = (t) => { const r = t.getBoundingClientRect(); return (r.top + r.bottom) / 2; };
const descs = texts.filter((t) => ['magnitude / dB', 'phase / deg', 'coherence'].includes(t.textContent.trim()));
const ticks = texts.filter((t) => t.getAttribute('text-anchor') === 'end' && /^-?[0-9.]+$/.test(t.textContent.trim()));
const phase = [];
for (const t of ticks) {
  let best = null, dist = Infinity;
  for (const d of descs) { const e = Math.abs(center(d) - center(t)); if (e < dist) { dist = e; best = d; } }
  if (best && best.textContent.trim().trim() === 'phase / deg') phase.push(Number(t.textContent.trim()));
}
return phase;
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn report_and_page_show_the_same_numbers_and_readable_plots() {
    let root = temp("same");
    let out = root.join("egc70");
    commission(&out, &[]);
    // the data files are beside the report
    for f in ["report.html", "frf.csv", "loops.csv", "moves.csv"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.len() < 1_500_000,
        "report too large: {} bytes",
        html.len()
    );

    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let state = AppState {
        tuner: Arc::new(LibraryTuner::builtin().unwrap()),
        save_dir: root.join("save"),
        loopback_only: true,
    };
    tokio::spawn(serve::serve(listener, state));

    // the same folder loaded into the page (`serve --commissioning DIR`)
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let loaded_addr = listener.local_addr().unwrap();
    let loaded = serve::library::load_commissioning(&out).unwrap();
    let state = AppState {
        tuner: Arc::new(LibraryTuner::new(loaded).unwrap()),
        save_dir: root.join("save-loaded"),
        loopback_only: true,
    };
    tokio::spawn(serve::serve(listener, state));

    let profile = root.join("profile");
    std::fs::create_dir_all(&profile).unwrap();
    let (c, _driver) = common::headless_chromium(&profile).await;
    let client = c.clone();
    let body = tokio::spawn(async move {
        let c = client;
        // ---- the report ----
        c.goto(&format!("file://{}", out.join("report.html").display()))
            .await
            .unwrap();
        let verdict = js(&c, "return document.getElementById('verdict-result').textContent;").await;
        assert_eq!(verdict.as_str().unwrap(), "PASS", "egc70 meets the thesis limits");
        let next = js(&c, "return document.getElementById('next-step').textContent;").await;
        assert!(next.as_str().unwrap().contains("controller.toml"), "{next}");
        let params = report_parameters(&c).await;
        let checks = js(
            &c,
            "return [...document.querySelectorAll('#verdict-checks td.value')].map((t) => Number(t.dataset.value));",
        )
        .await;
        let checks: Vec<f64> = checks
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(
            checks.len(),
            5,
            "tracking, static, settling, saturation, guaranteed margin"
        );
        // the checks' values are SI (m); the page's numbers too
        let max_mm = checks[0] * 1e3;
        // the static plots as printed (on screen the interactive charts replace them)
        common::emulate_media(&c, "print").await;
        let phase = js(&c, PHASE_TICKS_JS_BODY).await;
        let phase: Vec<f64> = phase
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert!(phase.len() >= 3, "phase ticks not found: {phase:?}");
        let (lo, hi) = phase
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        assert!(
            lo >= PHASE_AXIS_DEG.0 && hi <= PHASE_AXIS_DEG.1,
            "FRF phase axis {lo}..{hi} deg outside {PHASE_AXIS_DEG:?}"
        );
        assert_no_overlapping_labels(&c, "report (print)", 20).await;
        // on screen: the interactive charts' labels
        common::emulate_media(&c, "").await;
        assert_no_overlapping_labels(&c, "report (screen)", 8).await;

        // ---- the page (built-in axis, default knobs) ----
        c.goto(&format!("http://{addr}/")).await.unwrap();
        wait_js(
            &c,
            "Number(document.body.dataset.renderSeq || 0) > 0 && !document.body.classList.contains('stale')",
            "the page to render",
        )
        .await;
        let two_pi = 2.0 * std::f64::consts::PI;
        let p = |name: &str| {
            *params
                .get(name)
                .unwrap_or_else(|| panic!("report has no row `{name}`: {params:?}"))
        };
        assert_same("K_P", p("K_P"), page_number(&c, "k_p").await);
        assert_same("K_I", p("K_I"), page_number(&c, "k_i").await);
        assert_same("K_PP", p("K_PP"), page_number(&c, "k_pp").await);
        assert_same(
            "velocity crossover, Hz",
            p("velocity crossover f_c"),
            page_number(&c, "crossover_velocity").await / two_pi,
        );
        assert_same(
            "position crossover, Hz",
            p("position crossover f_c"),
            page_number(&c, "crossover_position").await / two_pi,
        );
        assert_same(
            "velocity phase margin",
            p("velocity phase margin"),
            page_number(&c, "pm_velocity").await,
        );
        assert_same(
            "position phase margin",
            p("position phase margin"),
            page_number(&c, "pm_position").await,
        );
        assert_same(
            "gain at resonance",
            p("gain at resonance"),
            page_number(&c, "gain_at_resonance").await,
        );
        // the model: f_r, f_z of the fit (the page derives them from the
        // identified parameters: the same formula (2.44), (2.45) on the same numbers)
        for (row, id) in [("resonance f_r", "f_r"), ("antiresonance f_z", "f_z")] {
            let (a, b) = (p(row), page_number(&c, id).await);
            assert!((a - b).abs() <= 1e-9 * a, "{row}: report {a} vs page {b}");
        }
        // the commissioning's own validation: the verdict numbers of the report
        assert_same(
            "max tracking error, mm",
            max_mm,
            page_number(&c, "commissioned_max_error").await * 1e3,
        );
        assert_same(
            "static error, um",
            checks[1] * 1e6,
            page_number(&c, "commissioned_static_error").await * 1e6,
        );
        // the page's own simulated move (default knobs, 11.2 kg, egc70) is the
        // commissioning's validation move again
        let sim_mm = page_number(&c, "max_error").await * 1e3;
        assert!(
            (sim_mm - max_mm).abs() <= (SAME_MOVE_REL_TOL * max_mm).max(SAME_MOVE_ABS_TOL_M * 1e3),
            "page's simulated move {sim_mm} mm vs the report's {max_mm} mm"
        );
        // the measured FRF is overlaid and the axes are in Hz
        let frf_points = js(
            &c,
            "return BeltunePlot.series(document.getElementById('plot-frf-mag'), 'measured').points;",
        )
        .await;
        assert!(frf_points.as_f64().unwrap() > 20.0, "no measured FRF on the page");
        // labels, legends and axis descriptions (the axes are drawn on a canvas:
        // their descriptions are kept in data-xlabel / data-ylabel)
        let rad = js(
            &c,
            "return [...document.querySelectorAll('.plot')].some((p) => \
             (p.textContent + p.dataset.xlabel + p.dataset.ylabel).includes('rad/s'));",
        )
        .await;
        assert_eq!(rad, Value::Bool(false), "the page still shows rad/s");
        assert_no_overlapping_labels(&c, "tuning page", 8).await;

        // ---- the page on the loaded folder ----
        // `commissioning.json` records the plant the commissioning ran on, so
        // the page simulates on egc70 with 11.2 kg as the report did, not on
        // the identified linear model (0.139 mm against the measured 0.640 mm).
        c.goto(&format!("http://{loaded_addr}/")).await.unwrap();
        wait_js(
            &c,
            "Number(document.body.dataset.renderSeq || 0) > 0 && !document.body.classList.contains('stale')",
            "the loaded page to render",
        )
        .await;
        assert_same("K_P (loaded)", p("K_P"), page_number(&c, "k_p").await);
        let sim_mm = page_number(&c, "max_error").await * 1e3;
        assert!(
            (sim_mm - max_mm).abs() <= (SAME_MOVE_REL_TOL * max_mm).max(SAME_MOVE_ABS_TOL_M * 1e3),
            "loaded page's simulated move {sim_mm} mm vs the report's {max_mm} mm"
        );
        assert_same(
            "max tracking error (loaded), mm",
            max_mm,
            page_number(&c, "commissioned_max_error").await * 1e3,
        );
    })
    .await;
    let _ = c.close().await;
    let _ = std::fs::remove_dir_all(&root);
    if let Err(e) = body {
        std::panic::resume_unwind(e.into_panic());
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn compare_shows_the_resonance_shift_with_the_payload() {
    let root = temp("compare");
    let (a, b) = (root.join("empty"), root.join("loaded"));
    commission(&a, &["--payload", "0"]);
    commission(&b, &["--payload", "11.2"]);
    let report = root.join("compare.html");
    let stdout = beltune(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(stdout.contains("resonance moved"), "{stdout}");
    let f_r = |dir: &Path| -> f64 {
        let j: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("commissioning.json")).unwrap())
                .unwrap();
        j["identified"]["f_r_hz"].as_f64().unwrap()
    };
    let (fa, fb) = (f_r(&a), f_r(&b));
    // (2.44): more mass, lower resonance; 11.2 kg on a ~1 kg cart is a large shift
    assert!(fb < 0.9 * fa, "f_r {fa} Hz (0 kg) vs {fb} Hz (11.2 kg)");

    let profile = root.join("profile");
    std::fs::create_dir_all(&profile).unwrap();
    let (c, _driver) = common::headless_chromium(&profile).await;
    let client = c.clone();
    let url = format!("file://{}", report.display());
    let body = tokio::spawn(async move {
        let c = client;
        c.goto(&url).await.unwrap();
        // the static plots as printed
        common::emulate_media(&c, "print").await;
        let row = js(
            &c,
            r#"return [...document.querySelectorAll('table.extra tr')].map((tr) =>
                [...tr.cells].map((td) => td.textContent)).find((r) => r[0] === 'resonance f_r');"#,
        )
        .await;
        let row: Vec<String> = row
            .as_array()
            .expect("no resonance row in the comparison")
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        let shown_a: f64 = row[2].parse().unwrap();
        let shown_b: f64 = row[3].parse().unwrap();
        let change: f64 = row[4].trim_end_matches(" %").parse().unwrap();
        // 4 decimals shown
        assert!((shown_a - fa).abs() < 1e-4 && (shown_b - fb).abs() < 1e-4, "{row:?}");
        assert!(
            (change - (fb - fa) / fa * 100.0).abs() < 0.01,
            "{row:?}: change vs {}",
            (fb - fa) / fa * 100.0
        );
        // both resonances are marked on the FRF overlay, both fits drawn
        let labels = js(
            &c,
            "return [...document.querySelectorAll('#overlay-0 svg text')].map((t) => t.textContent.trim());",
        )
        .await;
        let labels: Vec<String> = labels
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        for want in ["f_r A", "f_r B", "A fitted model", "B fitted model"] {
            assert!(labels.iter().any(|l| l.starts_with(want)), "{want} not in {labels:?}");
        }
        assert_no_overlapping_labels(&c, "comparison (print)", 20).await;
        common::emulate_media(&c, "").await;
        assert_no_overlapping_labels(&c, "comparison (screen)", 4).await;
    })
    .await;
    let _ = c.close().await;
    let _ = std::fs::remove_dir_all(&root);
    if let Err(e) = body {
        std::panic::resume_unwind(e.into_panic());
    }
}
