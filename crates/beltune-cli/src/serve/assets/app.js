// beltune tuning page: plain JavaScript, no libraries, no network beyond this server.
// Every knob change (debounced) posts the knobs to /api/design and redraws the
// numbers and the inline-SVG plots from the returned data.
'use strict';
(function () {
  const NS = 'http://www.w3.org/2000/svg';
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

  // ---------- SVG plots ----------
  function el(tag, attrs, text) {
    const e = document.createElementNS(NS, tag);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }
  function niceTicks(a, b, n) {
    const step0 = (b - a) / n;
    const mag = Math.pow(10, Math.floor(Math.log10(step0)));
    const f = step0 / mag;
    const step = (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
    const out = [];
    for (let v = Math.ceil(a / step) * step; v <= b + 1e-9 * step; v += step) {
      out.push(Math.abs(v) < 1e-9 * step ? 0 : v);
    }
    return out;
  }
  function tickLabel(v) {
    const a = Math.abs(v);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(0);
    return String(Number(v.toPrecision(6)));
  }

  // opts: { xlog, series: [{x, y, cls, name}], vlines: [{x, cls, label}],
  //         hlines: [{y, cls, label}], yspan (max visible span), empty (message) }
  function plot(svg, opts) {
    const W = 460, H = 200, L = 48, R = 12, T = 10, B = 24;
    svg.setAttribute('viewBox', `0 0 ${W} ${H}`);
    svg.replaceChildren();
    if (opts.empty) {
      // wrapped into lines of at most ~70 characters, centred: never clipped at the edges
      const words = String(opts.empty).split(/\s+/);
      const lines = [''];
      for (const w of words) {
        const cur = lines[lines.length - 1];
        if (cur && (cur + ' ' + w).length > 70) lines.push(w);
        else lines[lines.length - 1] = cur ? cur + ' ' + w : w;
      }
      const t = el('text', { x: W / 2, y: H / 2 - 6 * (lines.length - 1), 'text-anchor': 'middle', class: 'empty-note' });
      lines.forEach((line, i) => {
        const span = el('tspan', { x: W / 2, dy: i === 0 ? 0 : 12 }, line);
        t.appendChild(span);
      });
      svg.appendChild(t);
      svg.dataset.empty = String(opts.empty);
      return;
    }
    delete svg.dataset.empty;
    const ok = (x, y) => isFinite(x) && isFinite(y) && (!opts.xlog || x > 0);
    let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    for (const s of opts.series) {
      if (s.norange) continue;
      for (let i = 0; i < s.x.length; i++) {
        if (!ok(s.x[i], s.y[i])) continue;
        x0 = Math.min(x0, s.x[i]); x1 = Math.max(x1, s.x[i]);
        y0 = Math.min(y0, s.y[i]); y1 = Math.max(y1, s.y[i]);
      }
    }
    for (const h of opts.hlines || []) {
      if (h.norange) continue;
      y0 = Math.min(y0, h.y); y1 = Math.max(y1, h.y);
    }
    if (!isFinite(x0)) { plot(svg, { empty: 'no data' }); return; }
    if (opts.yspan && y1 - y0 > opts.yspan) y0 = y1 - opts.yspan;
    if (y1 - y0 < 1e-12) { y0 -= 1; y1 += 1; }
    const pad = 0.05 * (y1 - y0);
    y0 -= pad; y1 += pad;
    const tx = opts.xlog ? Math.log10 : (v) => v;
    const a0 = tx(x0), a1 = tx(x1) === a0 ? a0 + 1 : tx(x1);
    const px = (x) => L + (tx(x) - a0) / (a1 - a0) * (W - L - R);
    const py = (y) => T + (y1 - Math.min(Math.max(y, y0), y1)) / (y1 - y0) * (H - T - B);

    // grid and ticks
    const xt = [];
    if (opts.xlog) {
      // 1, 2, 5 per decade labelled (a decade or less: every integer multiple)
      const few = a1 - a0 <= 1.2;
      for (let k = Math.floor(a0) - 1; k <= Math.ceil(a1); k++) {
        for (const m of few ? [1, 2, 3, 4, 5, 6, 7, 8, 9] : [1, 2, 5]) {
          const v = m * Math.pow(10, k);
          if (tx(v) >= a0 - 1e-9 && tx(v) <= a1 + 1e-9) xt.push(v);
        }
      }
    } else {
      xt.push(...niceTicks(x0, x1, 6));
    }
    for (const v of xt) {
      const X = px(v).toFixed(1);
      svg.appendChild(el('line', { x1: X, x2: X, y1: T, y2: H - B, class: 'grid' }));
      // the axis' unit sits at the right end: a tick label there would cover it
      if (opts.xlabel && W - R - px(v) < 30) continue;
      svg.appendChild(el('text', { x: X, y: H - B + 12, 'text-anchor': 'middle', class: 'tick x-tick' }, tickLabel(v)));
    }
    for (const v of niceTicks(y0, y1, 5)) {
      const Y = py(v).toFixed(1);
      svg.appendChild(el('line', { x1: L, x2: W - R, y1: Y, y2: Y, class: 'grid' }));
      svg.appendChild(el('text', { x: L - 4, y: Number(Y) + 3, 'text-anchor': 'end', class: 'tick' }, tickLabel(v)));
    }
    svg.appendChild(el('rect', { x: L, y: T, width: W - L - R, height: H - T - B, class: 'axis' }));
    if (opts.xlabel) {
      svg.appendChild(el('text', { x: W - R, y: H - 2, 'text-anchor': 'end', class: 'tick' }, opts.xlabel));
    }
    if (opts.ylabel) {
      svg.appendChild(el('text', { x: L + 3, y: T + H - T - B - 4, class: 'tick y-label' }, opts.ylabel));
    }
    for (const h of opts.hlines || []) {
      if (h.y < y0 || h.y > y1) continue; // a line off the scale (e.g. a far limit) is not drawn
      const Y = py(h.y).toFixed(1);
      svg.appendChild(el('line', { x1: L, x2: W - R, y1: Y, y2: Y, class: h.cls || 'ref', 'data-name': h.name || '' }));
      if (h.label) {
        svg.appendChild(el('text', { x: W - R - 3, y: Number(Y) - 3, 'text-anchor': 'end', class: 'hline-label' }, h.label));
      }
    }
    for (const s of opts.series) {
      if (s.dots) {
        const g = el('g', { class: `series ${s.cls}`, 'data-name': s.name, 'data-points': 0 });
        let n = 0;
        for (let i = 0; i < s.x.length; i++) {
          if (!ok(s.x[i], s.y[i]) || s.y[i] < y0 || s.y[i] > y1) continue;
          g.appendChild(el('circle', { cx: px(s.x[i]).toFixed(2), cy: py(s.y[i]).toFixed(2), r: 2.6 }));
          n++;
        }
        g.setAttribute('data-points', n);
        svg.appendChild(g);
        continue;
      }
      let d = '';
      let pen = 'M';
      let n = 0;
      for (let i = 0; i < s.x.length; i++) {
        if (!ok(s.x[i], s.y[i])) { pen = 'M'; continue; }
        d += `${pen}${px(s.x[i]).toFixed(2)},${py(s.y[i]).toFixed(2)}`;
        pen = 'L';
        n++;
      }
      svg.appendChild(el('path', { d, class: `series ${s.cls}`, 'data-name': s.name, 'data-points': n }));
    }
    for (const v of opts.vlines || []) {
      if (!ok(v.x, 0) || v.x < x0 || v.x > x1) continue;
      const X = px(v.x).toFixed(1);
      svg.appendChild(el('line', {
        x1: X, x2: X, y1: T, y2: H - B, class: v.cls || 'marker', 'data-x': String(v.x), 'data-name': v.name || '',
      }));
      if (v.label) {
        // rows one text box (10 px font, 1.3 em) apart, so that labels of close lines never overlap
        svg.appendChild(el('text', { x: Number(X) + 3, y: T + 10 + 13 * (v.row || 0), class: 'marker-label' }, v.label));
      }
    }
  }

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
      plot($(id), {
        xlog: true, xlabel: 'Hz',
        ylabel: id === 'plot-frf-mag' ? `dB re 1 ${info.frf_unit || 'rad/(N m)'}` : 'deg',
        series: [
          { x: f.freq_hz, y: pick(f[key], false), cls: 'excluded', name: 'measured-excluded', dots: true, norange: true },
          { x: f.freq_hz, y: pick(f[key], true), cls: 's0', name: 'measured', dots: true },
          { x: f.model_freq_hz, y: f[mkey], cls: 's1', name: 'model' },
        ],
        vlines: id === 'plot-frf-mag' ? markers : markers.map((m) => ({ x: m.x, name: m.name, cls: 'ref' })),
      });
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
    plot($('plot-bode-mag'), {
      xlog: true, xlabel: 'Hz', ylabel: 'dB re 1 (|L|)', yspan: 160,
      series: [
        { x: f, y: ol.magnitude_db, cls: 's0', name: 'open-loop-velocity' },
        { x: f, y: op.magnitude_db, cls: 's1', name: 'open-loop-position' },
      ],
      hlines: [{ y: 0 }, { y: r.knobs.resonance_suppression_db, cls: 'ref', name: 'a-sup',
        label: `A_sup ${fmt(r.knobs.resonance_suppression_db, 3)} dB` }],
      vlines: cross,
    });
    plot($('plot-bode-phase'), {
      xlog: true, xlabel: 'Hz', yspan: 720,
      series: [
        { x: f, y: ol.phase_deg, cls: 's0', name: 'open-loop-velocity' },
        { x: f, y: op.phase_deg, cls: 's1', name: 'open-loop-position' },
      ],
      hlines: [{ y: -180 }],
      vlines: [
        { x: hz(cv.crossover_rad_s), name: 'crossover-velocity', label: `PMv ${fmt(cv.phase_margin_deg, 3)}°`, row: 0 },
        { x: hz(cp.crossover_rad_s), name: 'crossover-position', label: `PMp ${fmt(cp.phase_margin_deg, 3)}°`, row: 1 },
      ],
    });
    plot($('plot-closed-loop'), {
      xlog: true, xlabel: 'Hz', yspan: 120,
      series: [
        { x: f, y: cl.magnitude_db, cls: 's2', name: 'closed-loop-position' },
        { x: f, y: r.bode.closed_loop_velocity.magnitude_db, cls: 's0', name: 'closed-loop-velocity' },
      ],
      ylabel: 'dB re 1',
      hlines: [{ y: 0 }, { y: -3, cls: 'ref', name: 'minus-3-db', label: '-3 dB' }],
    });
    plot($('plot-sensitivity'), {
      xlog: true, xlabel: 'Hz', yspan: 120,
      series: [
        { x: f, y: r.bode.sensitivity_velocity.magnitude_db, cls: 's0', name: 'sensitivity-velocity' },
        { x: f, y: r.bode.sensitivity_position.magnitude_db, cls: 's1', name: 'sensitivity-position' },
      ],
      ylabel: 'dB re 1',
      hlines: [{ y: 0 }, { y: 6, cls: 'ref', name: 'six-db', label: '6 dB (|S| limit, 50 % gain change)' }],
    });
    const m = r.validation_move;
    if (m) {
      const tEnd = m.settling_time_s;
      // scaled to the delivered controller's error, not to the limit: a 0.04 mm error
      // under a 1 mm limit is a curve, not a flat line
      const peakMm = Math.max(...m.error_m.map((e) => Math.abs(e) * 1e3));
      plot($('plot-error'), {
        xlabel: 's', ylabel: 'mm',
        series: [{ x: m.t_s, y: m.error_m.map((e) => e * 1e3), cls: 's0', name: 'tracking-error' }],
        hlines: [{ y: 0 }, { y: 1, cls: 'limit', norange: true, name: 'limit', label: 'limit 1 mm' },
          { y: -1, cls: 'limit', norange: true, name: 'limit' }],
      });
      $('plot-error').dataset.peakMm = String(peakMm);
      plot($('plot-torque'), {
        xlabel: 's',
        series: [{ x: m.t_s, y: m.torque_nm, cls: 's2', name: 'torque' }],
        hlines: [{ y: 0 }],
      });
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
