//! End-to-end test of the tuning page in headless Chromium driven by
//! `fantoccini`: the server runs in-process on 127.0.0.1:0, the test starts
//! `chromedriver` itself on a free port. Missing Chromium or ChromeDriver fails the
//! test (install: `apt-get install -y chromium chromium-driver`).
//!
//! It loads the page, moves the velocity phase-margin slider with the keyboard,
//! checks that the displayed gains and the plotted curves change and equal what
//! `beltune::design::design` computes and what the `beltune design` command
//! prints for the same knobs, selects an infeasible setting and checks the message, recovers,
//! and saves `controller.toml`. It prints the measured slider-to-redraw times
//! (reported in the README; not asserted: no wall-clock assertions in tests).

use beltune_cli::serve;

use beltune::design::robust::{design_identified, DesignRule};
use beltune::design::{self as bdesign, DesignInput, DesignKnobs};
use fantoccini::{Client, ClientBuilder, Locator};
use serde_json::{json, Value};
use serve::library::LibraryTuner;
use serve::AppState;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

const CHROMIUM: &str = "/usr/bin/chromium";
/// How long the page may take to show a result before the test gives up. Generous:
/// 2 cores shared with parallel builds.
const WAIT: Duration = Duration::from_secs(60);
/// JSON round-trips f64 exactly and the page keeps the full value in data-value.
const REL_TOL: f64 = 1e-12;
/// Key presses on the slider (step 0.5 deg): 5 deg below where it starts.
const LEFT_PRESSES: usize = 10;
/// How far the slider moves the velocity phase margin, deg (0.5 deg steps).
const PM_STEP_DEG: f64 = 5.0;
/// A setting the design library refuses for egc70 (checked below against the
/// library): the slider's lower end, 20 deg velocity phase margin.
const INFEASIBLE_PM_VELOCITY_DEG: f64 = 20.0;

fn find_program(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join(name))
            .find(|p| p.is_file())
    })
}

/// Kills the child (chromedriver) when the test ends, also on panic.
struct Reaper(Child);
impl Drop for Reaper {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn egc70_input() -> DesignInput {
    // The page's default model: what the commissioning of the built-in
    // axis with the defaults of `beltune commission` identifies.
    let (_, run) = serve::library::builtin_commissioning().unwrap();
    run.design.input
}

/// `input` as a `beltune design --model` TOML file (`{:?}` prints the shortest
/// representation that parses back to the same f64).
fn write_model_toml(input: &DesignInput, path: &Path) {
    let m = input.model;
    let f = input.friction.unwrap();
    let text = format!(
        "theta_e = {:?}\nm_c = {:?}\nc = {:?}\nd = {:?}\nd_m = {:?}\nd_c = {:?}\ni_t = {:?}\n\
         dead_time_s = {:?}\nt_r_s = {:?}\nviscous = {:?}\ncoulomb = {:?}\n",
        m.theta_e,
        m.m_c,
        m.c,
        m.d,
        m.d_m,
        m.d_c,
        m.i_t,
        input.dead_time_s,
        input.t_r_s,
        f.viscous_nm_s_per_rad,
        f.coulomb_nm
    );
    std::fs::write(path, text).unwrap();
}

/// Run `beltune design --model MODEL` with every design knob of `k` given as
/// its flag, `--json OUT`: its JSON (the summary keys at the top level), or the
/// one-line error on stderr.
fn beltune_design(model: &Path, k: &DesignKnobs, out: &Path) -> Result<Value, String> {
    let prefilter = match k.prefilter {
        bdesign::PrefilterKind::Butterworth => "butterworth",
        bdesign::PrefilterKind::Notch => "notch",
        bdesign::PrefilterKind::None => "none",
    };
    let o = Command::new(env!("CARGO_BIN_EXE_beltune"))
        .arg("design")
        .arg("--model")
        .arg(model)
        .arg(format!("--pm-velocity={:?}", k.pm_velocity_deg))
        .arg(format!("--pm-position={:?}", k.pm_position_deg))
        .arg(format!(
            "--resonance-suppression-db={:?}",
            k.resonance_suppression_db
        ))
        .arg(format!("--prefilter={prefilter}"))
        .arg(format!("--filter-attenuation-db={:?}", k.attenuation_db()))
        .arg("--json")
        .arg(out)
        .output()
        .expect("running beltune design");
    if !o.status.success() {
        return Err(String::from_utf8_lossy(&o.stderr).trim_end().to_string());
    }
    Ok(serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap())
}

async fn start_server(dir: &Path) -> SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let state = AppState {
        tuner: Arc::new(LibraryTuner::builtin().unwrap()),
        save_dir: dir.to_path_buf(),
        loopback_only: true,
    };
    tokio::spawn(serve::serve(listener, state));
    addr
}

async fn start_browser(profile: &Path) -> (Reaper, Client) {
    let driver = find_program("chromedriver");
    if !Path::new(CHROMIUM).is_file() || driver.is_none() {
        panic!(
            "the browser test needs Debian's Chromium ({CHROMIUM}) and ChromeDriver on PATH: \
             apt-get update && apt-get install -y chromium chromium-driver"
        );
    }
    let port = free_port();
    let child = Command::new(driver.unwrap())
        .arg(format!("--port={port}"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("starting chromedriver");
    let reaper = Reaper(child);
    let url = format!("http://127.0.0.1:{port}");
    let mut caps = serde_json::Map::new();
    caps.insert(
        "goog:chromeOptions".into(),
        json!({
            "binary": CHROMIUM,
            "args": [
                "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--no-first-run", "--window-size=1400,1000",
                format!("--user-data-dir={}", profile.display()),
            ],
        }),
    );
    let started = Instant::now();
    loop {
        match ClientBuilder::native()
            .capabilities(caps.clone())
            .connect(&url)
            .await
        {
            Ok(c) => return (reaper, c),
            Err(_) if started.elapsed() < WAIT => {
                tokio::time::sleep(Duration::from_millis(200)).await;
            }
            Err(e) => panic!("cannot start a Chromium session through chromedriver: {e}"),
        }
    }
}

/// Poll `script` (a JS expression) until it is truthy; return its value.
async fn wait_js(c: &Client, script: &str, what: &str) -> Value {
    let started = Instant::now();
    loop {
        let v = c
            .execute(&format!("return {script};"), vec![])
            .await
            .unwrap();
        let truthy = match &v {
            Value::Null => false,
            Value::Bool(b) => *b,
            Value::String(s) => !s.is_empty(),
            Value::Number(n) => n.as_f64() != Some(0.0),
            _ => true,
        };
        if truthy {
            return v;
        }
        assert!(started.elapsed() < WAIT, "timed out waiting for {what}");
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
}

async fn js(c: &Client, script: &str) -> Value {
    c.execute(&format!("return {script};"), vec![])
        .await
        .unwrap()
}

async fn render_seq(c: &Client) -> u64 {
    js(c, "Number(document.body.dataset.renderSeq || 0)")
        .await
        .as_u64()
        .unwrap()
}

/// Wait until a render newer than `after` has finished and no change is pending.
async fn wait_render(c: &Client, after: u64) -> u64 {
    wait_js(
        c,
        &format!(
            "Number(document.body.dataset.renderSeq || 0) > {after} && \
             !document.body.classList.contains('stale')"
        ),
        "the page to redraw",
    )
    .await;
    render_seq(c).await
}

async fn number(c: &Client, id: &str) -> f64 {
    let v = js(c, &format!("document.getElementById('{id}').dataset.value")).await;
    v.as_str()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("#{id} shows no number: {v}"))
}

async fn attr(c: &Client, selector: &str, name: &str) -> String {
    c.find(Locator::Css(selector))
        .await
        .unwrap_or_else(|e| panic!("{selector}: {e}"))
        .attr(name)
        .await
        .unwrap()
        .unwrap_or_else(|| panic!("{selector} has no {name}"))
}

fn assert_close(what: &str, got: f64, want: f64) {
    assert!(
        (got - want).abs() <= REL_TOL * want.abs().max(1e-300),
        "{what}: page {got} vs library {want}"
    );
}

/// Displayed numbers and plot markers against a library design.
async fn check_against(c: &Client, d: &bdesign::ControllerDesign) {
    assert_close("K_P", number(c, "k_p").await, d.k_p);
    assert_close("K_I", number(c, "k_i").await, d.k_i);
    assert_close("K_PP", number(c, "k_pp").await, d.k_pp);
    assert_close(
        "velocity crossover",
        number(c, "crossover_velocity").await,
        d.velocity_margins.crossover_rad_s,
    );
    assert_close(
        "velocity phase margin",
        number(c, "pm_velocity").await,
        d.velocity_margins.phase_margin_deg,
    );
    assert_close(
        "position phase margin",
        number(c, "pm_position").await,
        d.position_margins.phase_margin_deg,
    );
    // the crossover markers of the Bode plot sit at the library's crossovers
    for (name, w) in [
        ("crossover-velocity", d.velocity_margins.crossover_rad_s),
        ("crossover-position", d.position_margins.crossover_rad_s),
    ] {
        let x: f64 = attr(
            c,
            &format!("#plot-bode-mag .bp-vline[data-name={name}]"),
            "data-x",
        )
        .await
        .parse()
        .unwrap();
        // the page's frequency axis is in Hz
        assert_close(name, x, w / (2.0 * std::f64::consts::PI));
    }
    // K_P is shown rounded to 4 significant digits
    let text = js(c, "document.getElementById('k_p').textContent").await;
    assert_eq!(text.as_str().unwrap(), sig4(d.k_p));
}

/// The number of points the plot `plot` draws of its series `name` (uPlot's data).
async fn series_points(c: &Client, plot: &str, name: &str) -> usize {
    let v = js(
        c,
        &format!("BeltunePlot.series(document.getElementById('{plot}'), '{name}').points"),
    )
    .await;
    v.as_u64()
        .unwrap_or_else(|| panic!("#{plot} has no series {name}: {v}")) as usize
}

/// The (x, y) points the plot `plot` draws of its series `name`, as JSON text.
async fn series_values(c: &Client, plot: &str, name: &str) -> String {
    js(
        c,
        &format!(
            "JSON.stringify(BeltunePlot.series(document.getElementById('{plot}'), '{name}').xy)"
        ),
    )
    .await
    .as_str()
    .unwrap()
    .to_string()
}

/// `Number.prototype.toPrecision(4)` for the magnitudes that occur here (1e-3..1e5).
fn sig4(x: f64) -> String {
    let digits = 3 - x.abs().log10().floor() as i32;
    if digits >= 0 {
        format!("{:.*}", digits as usize, x)
    } else {
        format!("{x:.0}")
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tuning_page_end_to_end_in_headless_chromium() {
    let root = std::env::temp_dir().join(format!("beltune-serve-browser-{}", std::process::id()));
    let save_dir = root.join("save");
    let profile = root.join("chromium-profile");
    std::fs::create_dir_all(&save_dir).unwrap();
    std::fs::create_dir_all(&profile).unwrap();
    let addr = start_server(&save_dir).await;
    let (_driver, c) = start_browser(&profile).await;

    let client = c.clone();
    let root_dir = root.clone();
    let body = tokio::spawn(async move {
        let c = client;
        c.goto(&format!("http://{addr}/")).await.unwrap();
        let seq0 = wait_render(&c, 0).await;
        let input = egc70_input();
        // the page's defaults: the commissioning's design rule on the identified model
        let d0 = {
            let (_, run) = serve::library::builtin_commissioning().unwrap();
            design_identified(
                &DesignInput {
                    model: run.fit.params,
                    ..run.design.input
                },
                run.design.input.friction.map(|f| f.viscous_nm_s_per_rad),
                run.identified.m_c_sigma,
                run.identified.c_sigma,
                run.identified.stroke_variation.as_ref(),
                &DesignKnobs::default(),
                DesignRule::Robust,
            )
            .unwrap()
            .design
        };
        check_against(&c, &d0).await;
        // plots that show the result: the 6 dB line is labelled, the filter's
        // corner is marked, the frequency axis has more labels than the decades,
        // and the error panel is scaled to the delivered controller's error
        let six = js(&c, "[...document.querySelectorAll('#plot-sensitivity .hline-label')].map(t => t.textContent).join('|')").await;
        assert!(six.as_str().unwrap().contains("6 dB"), "{six}");
        let corner = js(&c, "document.querySelectorAll('#plot-bode-mag .bp-vline[data-name=filter-corner]').length").await;
        assert_eq!(corner.as_u64(), Some(1), "the prefilter's corner is not marked");
        let ticks = js(&c, "document.getElementById('plot-bode-mag').dataset.xTicks.split('|').filter(Boolean).length").await;
        assert!(ticks.as_u64().unwrap() >= 6, "{ticks} frequency labels");
        let peak_mm: f64 = js(&c, "document.getElementById('plot-error').dataset.peakMm")
            .await
            .as_str()
            .unwrap()
            .parse()
            .unwrap();
        let top = js(&c, "Math.max(...document.getElementById('plot-error').dataset.yTicks.split('|').map(Number).filter(isFinite))").await;
        let top = top.as_f64().unwrap();
        assert!(
            top < 3.0 * peak_mm.max(0.01),
            "the error panel reaches {top} mm for a largest error of {peak_mm} mm"
        );
        let path0 = series_values(&c, "plot-bode-mag", "open-loop-velocity").await;
        let points = series_points(&c, "plot-bode-mag", "open-loop-velocity").await;
        assert_eq!(points, serve::library::PLOT_POINTS, "curve lost points");

        // Move the velocity phase-margin slider with the keyboard: 60 -> 55 deg.
        let slider = c.find(Locator::Id("pm_velocity_deg")).await.unwrap();
        let mut times = Vec::new();
        let mut seq = seq0;
        for _ in 0..LEFT_PRESSES {
            slider.send_keys("\u{E012}").await.unwrap(); // ArrowLeft
            seq = wait_render(&c, seq).await;
            let total = js(&c, "Number(document.body.dataset.totalMs)").await;
            let request = js(&c, "Number(document.body.dataset.requestMs)").await;
            let server = js(&c, "Number(document.body.dataset.serverMs)").await;
            times.push([total, request, server].map(|v| v.as_f64().unwrap_or(f64::NAN)));
        }
        let value: f64 = js(&c, "document.getElementById('pm_velocity_deg').value")
            .await
            .as_str()
            .unwrap()
            .parse()
            .unwrap();
        // the slider starts at the knobs the design rule chose
        let pm_after_deg = d0.knobs.pm_velocity_deg - PM_STEP_DEG;
        assert_eq!(value, pm_after_deg);
        // one knob moves only itself: the rest of the design state stays as the
        // design rule chose it (prefilter, attenuation, position margin, A_sup)
        let knobs1 = DesignKnobs {
            pm_velocity_deg: pm_after_deg,
            filter_attenuation_db: Some(d0.knobs.attenuation_db()),
            ..d0.knobs
        };
        let d1 = bdesign::design(&input, &knobs1).unwrap();
        assert!(d1.k_p != d0.k_p, "the design did not change");
        check_against(&c, &d1).await;
        assert_close(
            "the position phase margin after moving the velocity margin",
            number(&c, "pm_position").await,
            d0.position_margins.phase_margin_deg,
        );
        let prefilter = js(&c, "document.getElementById('prefilter').value").await;
        assert_eq!(
            prefilter,
            serde_json::to_value(d0.knobs.prefilter).unwrap(),
            "the prefilter moved with the velocity margin"
        );
        // ... and what `beltune design` prints for the same knobs
        let model_toml = root_dir.join("egc70-model.toml");
        write_model_toml(&input, &model_toml);
        let cli = beltune_design(&model_toml, &knobs1, &root_dir.join("design.json"))
            .expect("beltune design failed");
        for (id, key) in [
            ("k_p", "k_p"),
            ("k_i", "k_i"),
            ("k_pp", "k_pp"),
            ("crossover_velocity", "omega_c_velocity"),
            ("pm_velocity", "phase_margin_velocity_deg"),
            ("crossover_position", "omega_c_position"),
            ("pm_position", "phase_margin_position_deg"),
            ("gain_at_resonance", "gain_at_resonance_db"),
        ] {
            assert_close(
                &format!("{id} vs beltune design {key}"),
                number(&c, id).await,
                cli[key]
                    .as_f64()
                    .unwrap_or_else(|| panic!("beltune design JSON lacks {key}")),
            );
        }
        // The move numbers and traces are the server's (deterministic, seeded simulation).
        let knobs = serve::api::DesignRequest {
            prefilter: Some(serde_json::from_value(serde_json::to_value(d0.knobs.prefilter).unwrap()).unwrap()),
            pm_velocity_deg: Some(pm_after_deg),
            pm_position_deg: Some(d0.knobs.pm_position_deg),
            resonance_suppression_db: Some(d0.knobs.resonance_suppression_db),
            filter_attenuation_db: Some(d0.knobs.attenuation_db()),
            ..Default::default()
        }
        .validate()
        .unwrap();
        let tuned = serve::tuner::Tuner::tune(&LibraryTuner::builtin().unwrap(), &knobs).unwrap();
        let m = tuned.validation_move.expect("no simulated move");
        assert_close("max error", number(&c, "max_error").await, m.max_error_m);
        assert_close("static error", number(&c, "static_error").await, m.static_error_m);
        for (plot, name) in [("plot-error", "tracking-error"), ("plot-torque", "torque")] {
            let n = series_points(&c, plot, name).await;
            assert_eq!(n, m.t_s.len(), "{plot} lost points");
        }
        let path1 = series_values(&c, "plot-bode-mag", "open-loop-velocity").await;
        assert_ne!(path0, path1, "the open-loop curve was not redrawn");
        let stats = |k: usize| {
            let mut v: Vec<f64> = times.iter().map(|t| t[k]).collect();
            v.sort_by(f64::total_cmp);
            (v[v.len() / 2], v[v.len() - 1])
        };
        let ((tm, tx), (rm, rx), (sm, sx)) = (stats(0), stats(1), stats(2));
        eprintln!(
            "{LEFT_PRESSES} slider steps, median / max ms: change -> redrawn page (incl. 30 ms debounce) \
             {tm:.1} / {tx:.1}; request + draw {rm:.1} / {rx:.1}; server design + move {sm:.1} / {sx:.1}"
        );

        // Infeasible: the velocity phase margin at the slider's lower end (Home key).
        let infeasible = DesignKnobs {
            pm_velocity_deg: INFEASIBLE_PM_VELOCITY_DEG,
            ..knobs1
        };
        let lib = bdesign::design(&input, &infeasible);
        let reason = lib.expect_err("the infeasible setting is feasible for the library").to_string();
        slider.send_keys("\u{E011}").await.unwrap(); // Home
        seq = wait_render(&c, seq).await;
        let shown = js(&c, "document.getElementById('error').hidden ? '' : document.getElementById('error').textContent").await;
        assert_eq!(shown.as_str().unwrap(), reason, "the page does not show the library's reason");
        let cli = beltune_design(&model_toml, &infeasible, &root_dir.join("x.json"));
        assert_eq!(cli.unwrap_err(), format!("error: {reason}"), "beltune design says otherwise");
        // no earlier design stays drawn or listed under the banner: the numbers
        // are blank and every design plot says why, in full
        for id in ["k_p", "k_i", "k_pp", "pm_velocity", "pm_position"] {
            let v = js(&c, &format!("document.getElementById('{id}').dataset.value")).await;
            assert_eq!(v.as_str(), Some(""), "#{id} still shows the refused design's predecessor");
        }
        for plot in ["plot-bode-mag", "plot-bode-phase", "plot-error", "plot-torque"] {
            let why = js(&c, &format!("document.getElementById('{plot}').dataset.empty || ''")).await;
            assert!(
                why.as_str().unwrap().contains(&reason),
                "#{plot} does not say why it is empty: {why}"
            );
            // the message is wrapped inside the plot, not clipped at its edges
            let fits = js(
                &c,
                &format!(
                    "(() => {{ const s = document.getElementById('{plot}').getBoundingClientRect(); \
                     const n = document.getElementById('{plot}').querySelector('.plot-empty'); \
                     const b = n.getBoundingClientRect(); \
                     return n.scrollWidth <= n.clientWidth && b.left >= s.left && b.right <= s.right; }})()"
                ),
            )
            .await;
            assert_eq!(fits, Value::Bool(true), "#{plot}: the message is clipped");
        }

        // Back to a feasible setting: the error goes away and the page keeps working.
        c.execute("document.getElementById('reset').click(); return 0;", vec![]).await.unwrap();
        wait_render(&c, seq).await;
        assert_eq!(js(&c, "document.getElementById('error').hidden").await, Value::Bool(true));
        check_against(&c, &d0).await;

        // Save: a new folder in the save folder with the displayed gains.
        c.find(Locator::Id("save")).await.unwrap().click().await.unwrap();
        let path = wait_js(&c, "document.getElementById('save-result').dataset.path", "the save").await;
        let path = PathBuf::from(path.as_str().unwrap());
        assert_eq!(path.file_name().unwrap(), serve::CONTROLLER_FILE);
        assert_eq!(path.parent().unwrap().parent().unwrap(), save_dir, "a new folder per save");
        let saved: toml::Value = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let gains = &saved["gains"];
        assert_close("saved K_P", gains["k_p_nm_s_per_rad"].as_float().unwrap(), d0.k_p);
        assert_close("saved K_I", gains["k_i_nm_per_rad"].as_float().unwrap(), d0.k_i);
        assert_close("saved K_PP", gains["k_pp_per_s"].as_float().unwrap(), d0.k_pp);
        let shown = js(&c, "document.getElementById('save-result').textContent").await;
        assert!(shown.as_str().unwrap().contains(&path.display().to_string()));
    })
    .await;
    let _ = c.close().await;
    let _ = std::fs::remove_dir_all(&root);
    if let Err(e) = body {
        std::panic::resume_unwind(e.into_panic());
    }
}
