// beltune tuning page: plain JavaScript, no network beyond this server. The plots
// are drawn by uPlot (vendored, served by this server) through beltune-plot.js.
// Every knob change (debounced) posts the knobs to /api/design and redraws the
// numbers and the plots from the returned data.
'use strict';
(function () {
  const SLIDERS = ['dynamics', 'pm_velocity_deg', 'pm_position_deg',
    'resonance_suppression_db', 'filter_attenuation_db', 'payload_kg'];
  const DYNAMICS_SET = ['pm_velocity_deg', 'pm_position_deg', 'resonance_suppression_db'];
  // The design state: moving one of these sends all of them, as the design on the
  // screen has them, so that one knob moves only itself.
  const DESIGN_KNOBS = ['pm_velocity_deg', 'pm_position_deg', 'resonance_suppression_db',
    'filter_attenuation_db'];
  const DEBOUNCE_MS = 30;
  const $ = (id) => document.getElementById(id);

  let info = null;
  let explicit = {}; // the request's knobs; the rest take the server's design rule
  let shown = null; // the effective knobs of the design on the screen (exact values)
  let timer = null;
  let seq = 0;
  let inflight = null;
  let tInput = null; // performance.now() of the first change not yet drawn

  // ---------- formatting ----------
  function fmt(x, digits) {
    if (x === null || x === undefined || !isFinite(x)) return '-';
    return Number(x).toPrecision(digits || 4);
  }
  // Shows `value * scale`; keeps the unscaled SI value at full precision in data-value.
  function setNumber(id, value, scale) {
    const el = $(id);
    if (value === null || value === undefined || !isFinite(value)) {
      el.textContent = '-';
      el.dataset.value = '';
      return;
    }
    el.dataset.value = String(value);
    el.textContent = fmt(value * (scale || 1));
  }

  function showError(msg) {
    const el = $('error');
    el.textContent = msg;
    el.hidden = false;
    document.body.dataset.state = 'error';
  }
  function clearError() {
    const el = $('error');
    el.textContent = '';
    el.hidden = true;
    document.body.dataset.state = 'ok';
  }

  // ---------- plots (uPlot through BeltunePlot: zoom, read-out on hover, log axes) ----------
  // A redraw after a knob change keeps the x window the user zoomed into.
  function plot(el, opts) {
    if (el.uplot && !opts.empty) {
      const d = el.dataset;
      if (Number(d.xMin) > Number(d.xFullMin) || Number(d.xMax) < Number(d.xFullMax)) {
        opts.xwindow = [Number(d.xMin), Number(d.xMax)];
      }
    }
    window.BeltunePlot.draw(el, opts);
  }
  const FREQ = { xlog: true, xlabel: 'frequency / Hz', xunit: 'Hz', xname: 'frequency' };
  const TIME = { xlabel: 'time / s', xunit: 's', xname: 'time' };

  const TWO_PI = 2 * Math.PI;
  const hz = (w) => w / TWO_PI;

  // The measured FRF of the loaded commissioning and its fitted model (drawn once).
  function drawFrf() {
    const f = info && info.measured_frf;
    if (!f) {
      $('frf-figures').hidden = true;
      return;
    }
    $('frf-figures').hidden = false;
    const pick = (arr, used) => arr.map((v, i) => (f.used_by_fit[i] === used ? v : NaN));
    const markers = [
      { x: info.f_z_hz, name: 'antiresonance', cls: 'ref', label: `fz ${fmt(info.f_z_hz, 3)} Hz`, row: 0 },
      { x: info.f_r_hz, name: 'resonance', cls: 'ref', label: `fr ${fmt(info.f_r_hz, 3)} Hz`, row: 1 },
    ];
    for (const [id, key, mkey] of [['plot-frf-mag', 'magnitude_db', 'model_magnitude_db'],
      ['plot-frf-phase', 'phase_deg', 'model_phase_deg']]) {
      const mag = id === 'plot-frf-mag';
      plot($(id), Object.assign({}, FREQ, {
        ylabel: mag ? `magnitude / dB re 1 ${info.frf_unit || 'rad/(N m)'}` : 'phase / deg',
        yunit: mag ? 'dB' : 'deg',
        series: [
          { x: f.freq_hz, y: pick(f[key], false), cls: 'excluded', name: 'measured-excluded',
            label: 'measured, not used by the fit', dots: true, norange: true },
          { x: f.freq_hz, y: pick(f[key], true), cls: 's0', name: 'measured', label: 'measured', dots: true },
          { x: f.model_freq_hz, y: f[mkey], cls: 's1', name: 'model', label: 'fitted model' },
        ],
        vlines: mag ? markers : markers.map((m) => ({ x: m.x, name: m.name, cls: 'ref' })),
      }));
    }
  }

  function drawPlots(r) {
    const f = r.bode.freq_hz;
    const ol = r.bode.open_loop_velocity, op = r.bode.open_loop_position, cl = r.bode.closed_loop_position;
    const fr = info ? info.f_r_hz : NaN;
    const cv = r.velocity_loop, cp = r.position_loop;
    const cross = [
      { x: hz(cv.crossover_rad_s), name: 'crossover-velocity', label: `fc,v ${fmt(hz(cv.crossover_rad_s), 3)} Hz`, row: 0 },
      { x: hz(cp.crossover_rad_s), name: 'crossover-position', label: `fc,p ${fmt(hz(cp.crossover_rad_s), 3)} Hz`, row: 1 },
      { x: fr, name: 'resonance', cls: 'ref', label: `fr ${fmt(fr, 3)} Hz`, row: 2 },
    ];
    const pf = r.prefilter;
    const corner = pf.kind === 'butterworth' ? hz(pf.omega_bw_rad_s) : pf.kind === 'notch' ? fr : NaN;
    if (isFinite(corner) && pf.kind === 'butterworth') {
      cross.push({ x: corner, name: 'filter-corner', cls: 'filter', label: `fbw ${fmt(corner, 3)} Hz`, row: 3 });
    } else if (isFinite(corner)) {
      cross.push({ x: corner, name: 'filter-corner', cls: 'filter', label: `notch ${fmt(corner, 3)} Hz`, row: 3 });
    }
    plot($('plot-bode-mag'), Object.assign({}, FREQ, {
      ylabel: '|L| / dB re 1', yunit: 'dB', yspan: 160,
      series: [
        { x: f, y: ol.magnitude_db, cls: 's0', name: 'open-loop-velocity', label: 'velocity loop' },
        { x: f, y: op.magnitude_db, cls: 's1', name: 'open-loop-position', label: 'position loop', dashed: true },
      ],
      hlines: [{ y: 0 }, { y: r.knobs.resonance_suppression_db, cls: 'ref', name: 'a-sup',
        label: `A_sup ${fmt(r.knobs.resonance_suppression_db, 3)} dB` }],
      vlines: cross,
    }));
    plot($('plot-bode-phase'), Object.assign({}, FREQ, {
      ylabel: 'phase of L / deg', yunit: 'deg', yspan: 720,
      series: [
        { x: f, y: ol.phase_deg, cls: 's0', name: 'open-loop-velocity', label: 'velocity loop' },
        { x: f, y: op.phase_deg, cls: 's1', name: 'open-loop-position', label: 'position loop', dashed: true },
      ],
      hlines: [{ y: -180 }],
      vlines: [
        { x: hz(cv.crossover_rad_s), name: 'crossover-velocity', label: `PMv ${fmt(cv.phase_margin_deg, 3)}°`, row: 0 },
        { x: hz(cp.crossover_rad_s), name: 'crossover-position', label: `PMp ${fmt(cp.phase_margin_deg, 3)}°`, row: 1 },
      ],
    }));
    plot($('plot-closed-loop'), Object.assign({}, FREQ, {
      yspan: 120,
      series: [
        { x: f, y: cl.magnitude_db, cls: 's2', name: 'closed-loop-position', label: 'position loop' },
        { x: f, y: r.bode.closed_loop_velocity.magnitude_db, cls: 's0', name: 'closed-loop-velocity', label: 'velocity loop' },
      ],
      ylabel: 'magnitude / dB re 1', yunit: 'dB',
      hlines: [{ y: 0 }, { y: -3, cls: 'ref', name: 'minus-3-db', label: '-3 dB' }],
    }));
    plot($('plot-sensitivity'), Object.assign({}, FREQ, {
      yspan: 120,
      series: [
        { x: f, y: r.bode.sensitivity_velocity.magnitude_db, cls: 's0', name: 'sensitivity-velocity', label: 'velocity loop' },
        { x: f, y: r.bode.sensitivity_position.magnitude_db, cls: 's1', name: 'sensitivity-position', label: 'position loop', dashed: true },
      ],
      ylabel: '|S| / dB re 1', yunit: 'dB',
      hlines: [{ y: 0 }, { y: 6, cls: 'ref', name: 'six-db', label: '6 dB (|S| limit, 50 % gain change)' }],
    }));
    const m = r.validation_move;
    if (m) {
      const tEnd = m.settling_time_s;
      // scaled to the delivered controller's error, not to the limit: a 0.04 mm error
      // under a 1 mm limit is a curve, not a flat line
      const peakMm = Math.max(...m.error_m.map((e) => Math.abs(e) * 1e3));
      plot($('plot-error'), Object.assign({}, TIME, {
        ylabel: 'cart error / mm', yunit: 'mm',
        series: [{ x: m.t_s, y: m.error_m.map((e) => e * 1e3), cls: 's0', name: 'tracking-error', label: 'cart tracking error' }],
        hlines: [{ y: 0 }, { y: 1, cls: 'limit', norange: true, name: 'limit', label: 'limit 1 mm' },
          { y: -1, cls: 'limit', norange: true, name: 'limit' }],
      }));
      $('plot-error').dataset.peakMm = String(peakMm);
      plot($('plot-torque'), Object.assign({}, TIME, {
        ylabel: 'torque / N m', yunit: 'N m',
        series: [{ x: m.t_s, y: m.torque_nm, cls: 's2', name: 'torque', label: 'motor torque' }],
        hlines: [{ y: 0 }],
      }));
      $('move-note').textContent = `Move ${m.plant} with ${fmt(m.payload_kg, 3)} kg payload` +
        (tEnd === null ? ' (did not settle).' : '.') + ` Largest error ${fmt(peakMm, 3)} mm; ` +
        (peakMm < 0.5 ? 'the 1 mm limit lies outside this scale.' : 'dashed red: the 1 mm limit.');
    } else {
      const why = r.move_error || 'no simulated move';
      plot($('plot-error'), { empty: why });
      plot($('plot-torque'), { empty: why });
      $('move-note').textContent = why;
    }
  }

  // ---------- controls ----------
  function setSlider(name, value) {
    const s = $(name);
    if (value === null || value === undefined) return;
    s.value = String(value);
    $(name + '-value').textContent = fmt(Number(s.value), 3);
  }

  // The first design knob the user moves fixes the whole design state at the
  // design on the screen (prefilter, margins, suppression, attenuation, exact
  // values, not the sliders' rounded ones); later requests carry all of it.
  function pinDesignState() {
    if (!shown || $('use-dynamics').checked) return;
    for (const n of DESIGN_KNOBS) if (!(n in explicit)) explicit[n] = shown[n];
    if (!('prefilter' in explicit)) explicit.prefilter = shown.prefilter;
  }

  function render(r) {
    const k = r.knobs;
    shown = k;
    for (const name of SLIDERS) if (name !== 'dynamics' || k.dynamics !== null) setSlider(name, k[name]);
    $('prefilter').value = k.prefilter;
    setNumber('k_p', r.gains.k_p);
    setNumber('k_i', r.gains.k_i);
    setNumber('k_pp', r.gains.k_pp);
    const p = r.prefilter;
    if (p.kind === 'notch') {
      $('prefilter-param-name').textContent = 'notch damping dn';
      setNumber('prefilter-param', p.d_n);
      $('prefilter-param-unit').textContent = '';
    } else if (p.kind === 'none') {
      $('prefilter-param-name').textContent = 'no prefilter';
      setNumber('prefilter-param', null);
      $('prefilter-param-unit').textContent = '';
    } else {
      $('prefilter-param-name').textContent = 'Butterworth corner fbw';
      setNumber('prefilter-param', p.omega_bw_rad_s, 1 / TWO_PI);
      $('prefilter-param-unit').textContent = 'Hz';
    }
    setNumber('crossover_velocity', r.velocity_loop.crossover_rad_s, 1 / TWO_PI);
    setNumber('pm_velocity', r.velocity_loop.phase_margin_deg);
    setNumber('gm_velocity', r.velocity_loop.gain_margin_db);
    setNumber('gain_at_resonance', r.gain_at_resonance_db);
    setNumber('crossover_position', r.position_loop.crossover_rad_s, 1 / TWO_PI);
    setNumber('pm_position', r.position_loop.phase_margin_deg);
    const m = r.validation_move;
    setNumber('max_error', m ? m.max_error_m : null, 1e3);
    setNumber('static_error', m ? m.static_error_m : null, 1e6);
    setNumber('settling_time', m ? m.settling_time_s : null, 1e3);
    drawPlots(r);
  }

  // A refused design: the banner, and no earlier design left drawn or listed
  // under it (its numbers and curves would read as the current one's).
  const DESIGN_NUMBERS = ['k_p', 'k_i', 'k_pp', 'prefilter-param', 'crossover_velocity',
    'pm_velocity', 'gm_velocity', 'gain_at_resonance', 'crossover_position', 'pm_position',
    'max_error', 'static_error', 'settling_time'];
  const DESIGN_PLOTS = ['plot-bode-mag', 'plot-bode-phase', 'plot-closed-loop',
    'plot-sensitivity', 'plot-error', 'plot-torque'];
  function showFailure(msg) {
    showError(msg);
    for (const id of DESIGN_NUMBERS) setNumber(id, null);
    for (const id of DESIGN_PLOTS) plot($(id), { empty: `no design: ${msg}` });
    $('move-note').textContent = '';
  }

  function currentRequest() {
    const req = Object.assign({}, explicit);
    if ($('use-dynamics').checked) {
      req.dynamics = Number($('dynamics').value);
      for (const n of DYNAMICS_SET) delete req[n];
    } else {
      delete req.dynamics;
    }
    return req;
  }

  function schedule() {
    if (tInput === null) tInput = performance.now();
    document.body.classList.add('stale');
    clearTimeout(timer);
    timer = setTimeout(run, DEBOUNCE_MS);
  }

  function done(my, t0, serverMs) {
    // Stamp after the next frame, i.e. once the new DOM has been laid out and painted.
    requestAnimationFrame(() => {
      if (my !== seq) return;
      const end = performance.now();
      const total = end - (tInput === null ? t0 : tInput);
      tInput = null;
      document.body.classList.remove('stale');
      const b = document.body.dataset;
      b.requestMs = (end - t0).toFixed(1);
      b.totalMs = total.toFixed(1);
      b.serverMs = serverMs === null ? '' : serverMs.toFixed(1);
      b.renderSeq = String(my);
      $('timing').textContent = `last update: ${b.totalMs} ms from change to redraw (debounce ` +
        `${DEBOUNCE_MS} ms, request + draw ${b.requestMs} ms, server ${b.serverMs || '-'} ms)`;
    });
  }

  async function run() {
    const my = ++seq;
    if (inflight) inflight.abort();
    inflight = new AbortController();
    const t0 = performance.now();
    let resp, body;
    try {
      resp = await fetch('/api/design', {
        method: 'POST',
        headers: { 'Content-Type': 'application/json' },
        body: JSON.stringify(currentRequest()),
        signal: inflight.signal,
      });
      body = await resp.json();
    } catch (e) {
      if (e.name === 'AbortError') return;
      if (my === seq) { showError(`request failed: ${e}`); done(my, t0, null); }
      return;
    }
    if (my !== seq) return;
    if (!resp.ok) {
      showFailure(body.error || `HTTP ${resp.status}`);
      done(my, t0, null);
      return;
    }
    clearError();
    render(body);
    done(my, t0, body.compute_ms);
  }

  async function save() {
    const out = $('save-result');
    out.textContent = 'saving...';
    delete out.dataset.path;
    try {
      const resp = await fetch('/api/save', {
        method: 'POST',
        headers: { 'Content-Type': 'application/json' },
        body: JSON.stringify(currentRequest()),
      });
      const body = await resp.json();
      if (!resp.ok) {
        out.textContent = `not saved: ${body.error}`;
        out.dataset.state = 'error';
        return;
      }
      out.dataset.path = body.path;
      out.dataset.dir = body.dir;
      out.dataset.state = 'ok';
      out.textContent = `saved a new set in ${body.dir}: ${body.files.join(', ')} (controller ${body.path}, ${body.bytes} bytes)`;
    } catch (e) {
      out.textContent = `not saved: ${e}`;
      out.dataset.state = 'error';
    }
  }

  function applyDynamicsMode() {
    const on = $('use-dynamics').checked;
    $('dynamics').disabled = !on;
    for (const n of DYNAMICS_SET) $(n).disabled = on;
    if (on) {
      // the robust rule chooses prefilter and margins for the knob's guarantee
      for (const n of DESIGN_KNOBS) delete explicit[n];
      delete explicit.prefilter;
    } else {
      // keep the design the knob produced: its whole state becomes explicit
      pinDesignState();
    }
  }

  async function init() {
    try {
      const resp = await fetch('/api/info');
      info = await resp.json();
    } catch (e) {
      showError(`cannot load /api/info: ${e}`);
      return;
    }
    $('model-info').textContent = `${info.model_source}: fr ${fmt(info.f_r_hz, 4)} Hz, ` +
      `fz ${fmt(info.f_z_hz, 4)} Hz; simulated move with ${fmt(info.nominal_payload_kg, 3)} kg payload ` +
      `unless set below; Save writes a new folder in ${info.save_dir}`;
    setNumber('f_r', info.f_r_hz);
    setNumber('f_z', info.f_z_hz);
    const cm = info.commissioned;
    setNumber('commissioned_max_error', cm ? cm.max_error_m : null, 1e3);
    setNumber('commissioned_static_error', cm ? cm.static_error_m : null, 1e6);
    const verdict = info.commissioned_verdict || '';
    $('commissioned_verdict').textContent = verdict ? verdict.split(':')[0] : '-';
    $('commissioned_verdict').title = verdict;
    drawFrf();
    for (const r of info.ranges) {
      const s = $(r.name);
      s.min = String(r.min);
      s.max = String(r.max);
      s.step = String(r.step);
    }
    const d = info.defaults;
    for (const name of SLIDERS) setSlider(name, name === 'dynamics' ? 0.5 : d[name]);
    $('prefilter').value = d.prefilter;
    for (const name of SLIDERS) {
      $(name).addEventListener('input', () => {
        if (DESIGN_KNOBS.includes(name)) pinDesignState();
        if (name !== 'dynamics') explicit[name] = Number($(name).value);
        $(name + '-value').textContent = fmt(Number($(name).value), 3);
        schedule();
      });
    }
    $('prefilter').addEventListener('change', () => {
      pinDesignState();
      explicit.prefilter = $('prefilter').value;
      delete explicit.filter_attenuation_db; // each prefilter has its own default
      schedule();
    });
    $('use-dynamics').addEventListener('change', () => { applyDynamicsMode(); schedule(); });
    $('reset').addEventListener('click', () => {
      explicit = {};
      $('use-dynamics').checked = false;
      applyDynamicsMode();
      explicit = {};
      $('prefilter').value = info.defaults.prefilter;
      schedule();
    });
    $('save').addEventListener('click', save);
    document.body.dataset.ready = '1';
    schedule();
  }

  document.addEventListener('DOMContentLoaded', init);
}());
