// beltune's plots on uPlot (vendored: assets/uplot/README.md), shared by the
// tuning page (`beltune serve`) and the reports. One function draws one panel
// from a plain description:
//
//   BeltunePlot.draw(container, {
//     xlog, xlabel, xunit, ylabel, yunit, yspan,
//     series: [{ name, label, x, y, cls | color, dots, dashed, norange }],
//     vlines: [{ x, name, label, cls, row }],   // markers (crossover, resonance, ...)
//     hlines: [{ y, name, label, cls, norange }], // reference lines (0 dB, 6 dB, limits)
//     points: [{ x, y, label }],                 // labelled points (margins)
//     empty,                                     // a message instead of a plot
//     xwindow: [min, max],                       // start zoomed into this x range
//     onZoom(min, max),                          // called when the x range changes
//   })
//
// x values in `xunit` (Hz or s), y values in `yunit`. Drag across a plot to
// zoom its x range, double-click to zoom out; the legend under the plot reads
// the values under the cursor with their units. Markers and reference lines
// are DOM elements over the plot (data-name, data-x), so that they stay
// readable and testable; the numbers drawn on the axes are recorded in
// data-x-ticks / data-y-ticks of the container.
'use strict';
(function (global) {
  const COLORS = {
    s0: '#1f77b4', s1: '#d62728', s2: '#2ca02c', s3: '#ff7f0e', s4: '#9467bd', s5: '#17becf',
    excluded: '#aaaaaa', black: '#222222',
  };
  const PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#17becf'];
  /** Height of a panel's plot area and axes, CSS px (the legend comes below). */
  const HEIGHT_PX = 230;
  /** Width used while the container has no layout yet, CSS px. */
  const FALLBACK_WIDTH_PX = 460;
  /** Smallest distance between two x tick labels, CSS px. */
  const X_LABEL_GAP_PX = 34;
  /** Rows of labels (10 px font) are this far apart, CSS px. */
  const LABEL_ROW_PX = 13;

  function color(s, i) {
    if (s.color) return s.color;
    if (s.cls && COLORS[s.cls]) return COLORS[s.cls];
    return PALETTE[i % PALETTE.length];
  }

  function tickLabel(v) {
    const a = Math.abs(v);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(0);
    return String(Number(v.toPrecision(6)));
  }

  function readout(v, unit) {
    if (v === null || v === undefined || !isFinite(v)) return '-';
    const s = String(Number(Number(v).toPrecision(4)));
    return unit ? `${s} ${unit}` : s;
  }

  // 1..9 times every power of ten inside [min, max]: the grid of a log axis.
  function logSplits(min, max) {
    const out = [];
    if (!(min > 0) || !(max > min)) return out;
    for (let k = Math.floor(Math.log10(min)); k <= Math.ceil(Math.log10(max)); k++) {
      for (let m = 1; m <= 9; m++) {
        const v = Number((m * Math.pow(10, k)).toPrecision(12));
        if (v >= min * (1 - 1e-9) && v <= max * (1 + 1e-9)) out.push(v);
      }
    }
    return out;
  }

  // Which of the log grid lines get a label: all if they fit, else 1, 2, 5 per
  // decade, else the decades.
  function logLabels(splits, widthPx) {
    const lead = (v) => Math.round(v / Math.pow(10, Math.floor(Math.log10(v)) ) );
    for (const keep of [[1, 2, 3, 4, 5, 6, 7, 8, 9], [1, 2, 5], [1]]) {
      const n = splits.filter((v) => keep.includes(lead(v))).length;
      if (n <= 1 || widthPx / n >= X_LABEL_GAP_PX || keep.length === 1) {
        return splits.map((v) => (keep.includes(lead(v)) ? tickLabel(v) : ''));
      }
    }
    return splits.map(tickLabel);
  }

  // The y range: the data inside the x window (uPlot scans the series that
  // set the range: [dmin, dmax], null without data) with the reference lines
  // and points that set it, at most `yspan` below the top, 5 % pad.
  function yRange(spec, dmin, dmax) {
    let y0 = Number.isFinite(dmin) ? dmin : Infinity;
    let y1 = Number.isFinite(dmax) ? dmax : -Infinity;
    for (const h of spec.hlines || []) {
      if (h.norange || !Number.isFinite(h.y)) continue;
      y0 = Math.min(y0, h.y); y1 = Math.max(y1, h.y);
    }
    for (const p of spec.points || []) {
      if (!Number.isFinite(p.y)) continue;
      y0 = Math.min(y0, p.y); y1 = Math.max(y1, p.y);
    }
    if (!Number.isFinite(y0) || !Number.isFinite(y1)) return [-1, 1];
    if (spec.yspan && y1 - y0 > spec.yspan) y0 = y1 - spec.yspan;
    if (y1 - y0 < 1e-12) { y0 -= 1; y1 += 1; }
    const pad = 0.05 * (y1 - y0);
    return [y0 - pad, y1 + pad];
  }

  // The series aligned on one x column (uPlot's data layout): series that share
  // an x array share its values, others are joined (undefined where a series
  // has no point: the line runs on; null where its value is not finite: a gap).
  function alignedData(spec) {
    const okX = (x) => Number.isFinite(x) && (!spec.xlog || x > 0);
    const tables = [];
    const byX = new Map();
    const where = [];
    spec.series.forEach((s) => {
      let t = byX.get(s.x);
      if (!t) {
        const keep = [];
        for (let i = 0; i < s.x.length; i++) if (okX(s.x[i])) keep.push(i);
        t = { keep, table: [keep.map((i) => s.x[i])] };
        byX.set(s.x, t);
        tables.push(t);
      }
      t.table.push(t.keep.map((i) => {
        const y = s.y[i];
        return Number.isFinite(y) ? y : null;
      }));
      where.push([tables.indexOf(t), t.table.length - 1]);
    });
    const joined = tables.length === 1 ? tables[0].table : global.uPlot.join(tables.map((t) => t.table));
    // uPlot.join appends the series table by table: map them back to spec order
    const offsets = [];
    let off = 1;
    for (const t of tables) { offsets.push(off); off += t.table.length - 1; }
    const data = [joined[0]];
    for (const [ti, si] of where) data.push(joined[offsets[ti] + si - 1]);
    return data;
  }

  function emptyPlot(el, msg) {
    destroy(el);
    const note = document.createElement('div');
    note.className = 'plot-empty';
    note.textContent = String(msg);
    el.replaceChildren(note);
    el.dataset.empty = String(msg);
  }

  function destroy(el) {
    if (el.uplot) { el.uplot.destroy(); el.uplot = null; }
    if (el.bpResize) { global.removeEventListener('resize', el.bpResize); el.bpResize = null; }
  }

  // Places label boxes so that no two overlap: a label moves down (then up) by
  // whole rows until it is free, inside the plot area.
  function Placer(widthPx, heightPx) {
    const boxes = [];
    const free = (b) => boxes.every((o) => b.x1 <= o.x0 || o.x1 <= b.x0 || b.y1 <= o.y0 || o.y1 <= b.y0);
    return function place(node, x, y, alignRight) {
      const w = node.offsetWidth, h = node.offsetHeight;
      let left = alignRight ? x - w : x;
      if (left + w > widthPx) left = Math.max(0, x - w - 6);
      left = Math.max(0, left);
      let best = null;
      for (let k = 0; k < 24; k++) {
        const dy = k % 2 === 0 ? (k / 2) * LABEL_ROW_PX : -((k + 1) / 2) * LABEL_ROW_PX;
        const top = y + dy;
        if (top < 0 || top + h > heightPx) continue;
        const b = { x0: left - 1, y0: top, x1: left + w + 1, y1: top + h };
        if (free(b)) { best = b; break; }
        if (best === null) best = b;
      }
      if (best === null) best = { x0: left - 1, y0: Math.max(0, Math.min(y, heightPx - h)), x1: left + w + 1, y1: 0 };
      best.y1 = best.y0 + h;
      boxes.push(best);
      node.style.left = `${best.x0 + 1}px`;
      node.style.top = `${best.y0}px`;
    };
  }

  // Markers, reference lines and labelled points over the plot area.
  function drawOverlay(u, spec) {
    let layer = u.over.querySelector('.bp-layer');
    if (!layer) {
      layer = document.createElement('div');
      layer.className = 'bp-layer';
      u.over.appendChild(layer);
    }
    layer.replaceChildren();
    const W = u.over.clientWidth, H = u.over.clientHeight;
    const [x0, x1] = [u.scales.x.min, u.scales.x.max];
    const [y0, y1] = [u.scales.y.min, u.scales.y.max];
    const place = Placer(W, H);
    const add = (cls, attrs, text) => {
      const d = document.createElement('div');
      d.className = cls;
      for (const k in attrs) d.setAttribute(k, attrs[k]);
      if (text !== undefined) d.textContent = text;
      layer.appendChild(d);
      return d;
    };
    for (const h of spec.hlines || []) {
      if (!Number.isFinite(h.y) || h.y < y0 || h.y > y1) continue; // off the scale: not drawn
      const top = u.valToPos(h.y, 'y');
      const line = add(`bp-hline ${h.cls || 'ref'}`, { 'data-name': h.name || '', 'data-y': String(h.y) });
      line.style.top = `${top}px`;
      if (h.label) place(add('plot-label hline-label', {}, h.label), W - 3, top - LABEL_ROW_PX, true);
    }
    const vlines = (spec.vlines || []).slice().sort((a, b) => (a.row || 0) - (b.row || 0));
    for (const v of vlines) {
      if (!Number.isFinite(v.x) || (spec.xlog && v.x <= 0) || v.x < x0 || v.x > x1) continue;
      const left = u.valToPos(v.x, 'x');
      const line = add(`bp-vline ${v.cls || 'marker'}`, { 'data-name': v.name || '', 'data-x': String(v.x) });
      line.style.left = `${left}px`;
      if (v.label) {
        place(add(`plot-label marker-label ${v.cls || 'marker'}`, { 'data-name': v.name || '' }, v.label),
          left + 3, 2 + LABEL_ROW_PX * (v.row || 0), false);
      }
    }
    for (const p of spec.points || []) {
      if (!Number.isFinite(p.x) || !Number.isFinite(p.y) || p.x < x0 || p.x > x1 || p.y < y0 || p.y > y1) continue;
      const left = u.valToPos(p.x, 'x'), top = u.valToPos(p.y, 'y');
      const dot = add('bp-point', { 'data-x': String(p.x), 'data-y': String(p.y) });
      dot.style.left = `${left}px`;
      dot.style.top = `${top}px`;
      if (p.label) place(add('plot-label point-label', {}, p.label), left + 6, top + 4, false);
    }
  }

  function draw(el, spec) {
    destroy(el);
    el.replaceChildren();
    if (spec.empty) { emptyPlot(el, spec.empty); return null; }
    if (!global.uPlot) { emptyPlot(el, 'the plotting library (uPlot) did not load'); return null; }
    delete el.dataset.empty;
    const data = alignedData(spec);
    if (data[0].length === 0) { emptyPlot(el, 'no data'); return null; }
    const xs = data[0];
    const full = [xs[0], xs[xs.length - 1]];
    const width = () => Math.max(200, el.clientWidth || FALLBACK_WIDTH_PX);
    const xunit = spec.xunit || '';
    const yunit = spec.yunit || '';
    el.dataset.xlabel = spec.xlabel || '';
    el.dataset.ylabel = spec.ylabel || '';
    const series = [{ label: spec.xname || (spec.xlog ? 'frequency' : 'x'), value: (u, v) => readout(v, xunit) }];
    spec.series.forEach((s, i) => {
      const c = color(s, i);
      const o = {
        label: s.label || s.name || `series ${i + 1}`,
        stroke: c,
        width: 1.6,
        value: (u, v) => readout(v, yunit),
        spanGaps: false,
        auto: !s.norange, // a series that does not set the y range is not scanned for it
      };
      if (s.dashed) o.dash = [5, 3];
      if (s.dots) {
        o.paths = () => null;
        o.points = { show: true, size: 5, width: 0, fill: c, stroke: c };
      } else {
        o.points = { show: false };
      }
      series.push(o);
    });
    const yAxisValues = (u, splits) => {
      const labels = splits.map(tickLabel);
      el.dataset.yTicks = labels.join('|');
      return labels;
    };
    const xAxis = {
      label: spec.xlabel || '',
      labelSize: 18,
      size: 34,
      font: '11px system-ui, sans-serif',
      labelFont: '11px system-ui, sans-serif',
      grid: { stroke: '#e4e4e4', width: 1 },
      ticks: { stroke: '#bbb', width: 1, size: 4 },
    };
    if (spec.xlog) {
      xAxis.splits = (u, ai, min, max) => logSplits(min, max);
      xAxis.values = (u, splits) => {
        const labels = logLabels(splits, u.over.clientWidth || width());
        el.dataset.xTicks = labels.filter((t) => t !== '').join('|');
        return labels;
      };
      xAxis.filter = (u, splits) => splits;
    } else {
      xAxis.values = (u, splits) => {
        const labels = splits.map(tickLabel);
        el.dataset.xTicks = labels.join('|');
        return labels;
      };
    }
    const opts = {
      width: width(),
      height: HEIGHT_PX,
      series,
      scales: {
        x: spec.xlog
          ? { time: false, distr: 3, log: 10, auto: true, range: (u, min, max) => [min, max] }
          : { time: false, auto: true, range: (u, min, max) => [min, max] },
        // auto: re-ranged to the data in the x window after every zoom
        y: { auto: true, range: (u, dmin, dmax) => yRange(spec, dmin, dmax) },
      },
      axes: [xAxis, {
        label: spec.ylabel || '',
        labelSize: 18,
        size: 52,
        font: '11px system-ui, sans-serif',
        labelFont: '11px system-ui, sans-serif',
        grid: { stroke: '#e4e4e4', width: 1 },
        ticks: { stroke: '#bbb', width: 1, size: 4 },
        values: yAxisValues,
      }],
      cursor: { drag: { x: true, y: false, setScale: true }, points: { size: 6 } },
      legend: { live: true },
      hooks: {
        setScale: [(u, key) => {
          if (key !== 'x') return;
          el.dataset.xMin = String(u.scales.x.min);
          el.dataset.xMax = String(u.scales.x.max);
          // only a change after construction (a zoom) is passed on
          if (spec.onZoom && u.bpReady) spec.onZoom(u.scales.x.min, u.scales.x.max);
        }],
        draw: [(u) => drawOverlay(u, spec)],
        // uPlot commits its first scales in a microtask, then says it is ready
        ready: [(u) => { u.bpReady = true; }],
      },
    };
    el.dataset.xMin = String(full[0]);
    el.dataset.xMax = String(full[1]);
    el.dataset.xFullMin = String(full[0]);
    el.dataset.xFullMax = String(full[1]);
    const u = new global.uPlot(opts, data, el);
    u.bpSpec = spec;
    u.bpNames = spec.series.map((s) => s.name || '');
    el.uplot = u;
    // a window to start in (the page keeps the user's zoom over a redraw)
    if (spec.xwindow) {
      const lo = Math.max(spec.xwindow[0], full[0]), hi = Math.min(spec.xwindow[1], full[1]);
      if (lo < hi) u.setScale('x', { min: lo, max: hi });
    }
    el.bpResize = () => { if (el.uplot === u) u.setSize({ width: width(), height: HEIGHT_PX }); };
    global.addEventListener('resize', el.bpResize);
    return u;
  }

  // What a panel shows of its series `name`: its label, the number of points
  // drawn and their values (for tests and tools).
  function seriesOf(el, name) {
    const u = el && el.uplot;
    if (!u) return null;
    const k = u.bpNames.indexOf(name);
    if (k < 0) return null;
    const y = u.data[k + 1];
    const x = u.data[0];
    const pts = [];
    for (let i = 0; i < y.length; i++) if (y[i] !== null && y[i] !== undefined) pts.push([x[i], y[i]]);
    return { label: u.series[k + 1].label, points: pts.length, xy: pts };
  }

  global.BeltunePlot = { draw, series: seriesOf, destroy };
}(window));
