  // series.js: the time-series panel. data.series: name -> one value per frame; data.series_groups:
  // the panels, each {title, unit, series: [names], units: [unit per series]} (default: one per
  // series). Each panel has a y axis with tick values and its unit, all share a time axis in
  // data.time_unit. The axes and curves are drawn once to an offscreen canvas; drawSeries(time)
  // copies it, draws the playhead and writes the values at `time` into each panel's legend.
  // The panel's dataset exposes what is drawn (series, groups, tick labels, values) to scripts.
  const series = data.series || {};
  const seriesNames = Object.keys(series);
  const groups = (data.series_groups || seriesNames.map((n) => ({ title: n, unit: '', series: [n] })))
    .map((g) => Object.assign({}, g, { series: g.series.filter((n) => series[n]) }))
    .filter((g) => g.series.length);
  const timeUnit = data.time_unit === undefined ? 's' : data.time_unit;
  const panel = $('series');
  const COLORS = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b', '#e377c2', '#17becf'];
  const PANEL_H = 84, AXIS_H = 22, LEFT = 48, RIGHT = 10, TITLE_H = 15;
  let seriesImage = null;
  let layout = [];                       // per group: {top, bottom, lo, hi, step}

  // "Nice" ticks (1, 2, 5 times a power of ten) in [lo, hi], about `count` of them, at least two.
  function ticks(lo, hi, count) {
    const raw = (hi - lo) / Math.max(1, count);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    let step = [1, 2, 5, 10].map((k) => k * mag)
      .reduce((a, b) => (Math.abs(Math.log(b / raw)) < Math.abs(Math.log(a / raw)) ? b : a));
    const within = (st) => {
      const out = [];
      for (let k = Math.ceil(lo / st - 1e-9); k * st <= hi + 1e-9 * st; k++) out.push(k * st);
      return out;
    };
    let values = within(step);
    while (values.length < 2) {          // the next smaller of 1, 2, 5 times a power of ten
      const m = Math.pow(10, Math.floor(Math.log10(step) + 1e-9)), lead = Math.round(step / m);
      step = lead === 5 ? 2 * m : lead === 2 ? m : m / 2;
      values = within(step);
    }
    return { step, values };
  }
  function tickText(v, step) {
    const digits = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    const s = (Math.abs(v) < step * 1e-6 ? 0 : v).toFixed(Math.min(digits, 8));
    return s === '-0' ? '0' : s;
  }
  // A value at the playhead: one digit finer than its panel's ticks.
  function valueText(v, step) {
    if (v === null || !isFinite(v)) return '–';
    const a = Math.abs(v);
    if (a >= 1e6 || (a !== 0 && a < 1e-4 && step < 1e-4)) return v.toExponential(3);
    return tickText(v, step / 10);
  }
  function range(names) {
    let lo = Infinity, hi = -Infinity;
    for (const n of names) for (const x of series[n]) if (x !== null) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    if (!(hi >= lo)) { lo = -1; hi = 1; }
    if (!(hi > lo)) { const d = Math.abs(lo) > 0 ? Math.abs(lo) * 0.1 : 1; lo -= d; hi += d; }
    const pad = 0.06 * (hi - lo);
    return [lo - pad, hi + pad];
  }
  const xOf = (t, w) => LEFT + (duration > 0 ? (t - t0) / duration : 0) * (w - LEFT - RIGHT);

  function buildSeries() {
    if (!groups.length || !panel) return;
    panel.hidden = false;
    const maxH = Math.max(AXIS_H + 60, Math.floor(0.5 * (window.innerHeight || 600)));
    panel.style.height = Math.min(groups.length * PANEL_H + AXIS_H, maxH) + 'px';
    const w = panel.width = panel.clientWidth || 420, h = panel.height = panel.clientHeight || 140;
    const gh = (h - AXIS_H) / groups.length;
    const off = document.createElement('canvas');
    off.width = w; off.height = h;
    const g = off.getContext('2d');
    g.fillStyle = 'rgba(255,255,255,0.9)'; g.fillRect(0, 0, w, h);
    g.font = '10px sans-serif'; g.textBaseline = 'middle';
    layout = [];
    const yTicks = [];
    groups.forEach((grp, k) => {
      const top = k * gh + TITLE_H, bottom = (k + 1) * gh - 4;
      const [lo, hi] = range(grp.series);
      const tk = ticks(lo, hi, Math.max(3, Math.floor((bottom - top) / 14)));
      const yOf = (v) => bottom - (v - lo) / (hi - lo) * (bottom - top);
      layout.push({ top, bottom, step: tk.step, yOf });
      // frame, grid and y tick labels
      g.strokeStyle = '#cfd6de'; g.lineWidth = 1;
      g.strokeRect(LEFT + 0.5, top + 0.5, w - LEFT - RIGHT - 1, bottom - top);
      g.textAlign = 'right'; g.fillStyle = '#3e4c59';
      const labels = [];
      for (const v of tk.values) {
        const y = Math.round(yOf(v)) + 0.5;
        g.strokeStyle = '#eef1f4'; g.beginPath(); g.moveTo(LEFT + 1, y); g.lineTo(w - RIGHT - 1, y); g.stroke();
        g.strokeStyle = '#7b8794'; g.beginPath(); g.moveTo(LEFT - 3, y); g.lineTo(LEFT, y); g.stroke();
        const text = tickText(v, tk.step);
        g.fillText(text, LEFT - 5, y);
        labels.push(text);
      }
      yTicks.push(labels.join(' '));
      // curves
      g.save(); g.beginPath(); g.rect(LEFT, top, w - LEFT - RIGHT, bottom - top); g.clip();
      grp.series.forEach((name, c) => {
        const v = series[name];
        g.strokeStyle = COLORS[c % COLORS.length]; g.lineWidth = 1.3; g.beginPath();
        let pen = false;
        for (let i = 0; i < F; i++) {
          if (v[i] === null) { pen = false; continue; }
          const x = xOf(T[i], w), y = yOf(v[i]);
          if (pen) g.lineTo(x, y); else g.moveTo(x, y);
          pen = true;
        }
        g.stroke();
      });
      g.restore();
    });
    // the time axis, under the last panel
    const tk = ticks(t0, duration > 0 ? t1 : t0 + 1, Math.max(2, Math.floor((w - LEFT - RIGHT) / 60)));
    const base = h - AXIS_H + 2, tLabels = [];
    g.textAlign = 'center'; g.textBaseline = 'top'; g.fillStyle = '#3e4c59'; g.strokeStyle = '#7b8794';
    for (const t of tk.values) {
      if (t > t1 + 1e-9) continue;
      const x = Math.round(xOf(t, w)) + 0.5;
      g.beginPath(); g.moveTo(x, base - 6); g.lineTo(x, base - 2); g.stroke();
      const text = tickText(t, tk.step);
      g.fillText(text, x, base + 1);
      tLabels.push(text);
    }
    g.textAlign = 'left';
    g.fillText(timeUnit ? `t [${timeUnit}]` : 't', 4, base + 1);
    seriesImage = off;
    panel.dataset.series = groups.map((grp) => grp.series.join(',')).join(',');
    panel.dataset.groups = groups.map((grp) => grp.title + (grp.unit ? ` [${grp.unit}]` : '')).join('|');
    panel.dataset.yticks = yTicks.join('|');
    panel.dataset.tticks = tLabels.join(' ');
  }

  function valueAt(name, l) {
    const v = series[name], a = v[l.i], b = v[l.j];
    if (a === null) return null;
    return b === null ? a : a + l.w * (b - a);
  }

  // The title and legend line of each panel, with the values at the playhead.
  function drawLegend(g, grp, L, w, l, values) {
    const top = L.top;
    g.textBaseline = 'middle'; g.textAlign = 'left'; g.font = 'bold 10px sans-serif'; g.fillStyle = '#1f2933';
    const y = top - TITLE_H / 2;
    const title = grp.title + (grp.unit ? ` [${grp.unit}]` : '');
    let x = LEFT + 2 + g.measureText(title).width + 10;
    g.fillText(title, LEFT + 2, y);
    g.font = '10px sans-serif';
    grp.series.forEach((name, c) => {
      const v = valueAt(name, l), unit = !grp.unit && grp.units && grp.units[c] ? ' ' + grp.units[c] : '';
      values.push(`${name}=${valueText(v, L.step)}`);
      if (x < 0) return;                     // no room left: the legend stops at "…"
      const text = `${name} ${valueText(v, L.step)}${unit}`, tw = g.measureText(text).width;
      if (x + 12 + tw > w - RIGHT) { g.fillStyle = '#616e7c'; g.fillText('…', x, y); x = -1; return; }
      g.fillStyle = COLORS[c % COLORS.length]; g.fillRect(x, y - 3, 8, 6);
      g.fillStyle = '#1f2933'; g.fillText(text, x + 11, y);
      x += 11 + tw + 10;
    });
  }

  function drawSeries(time) {
    if (!seriesImage) return;
    const g = panel.getContext('2d'), w = panel.width;
    g.drawImage(seriesImage, 0, 0);
    const l = locate(time), x = Math.round(xOf(Math.min(Math.max(time, t0), t1), w)) + 0.5;
    const values = [];
    groups.forEach((grp, k) => {
      const L = layout[k];
      g.strokeStyle = '#1f2933'; g.lineWidth = 1; g.beginPath();
      g.moveTo(x, L.top); g.lineTo(x, L.bottom); g.stroke();
      grp.series.forEach((name, c) => {
        const v = valueAt(name, l);
        if (v === null) return;
        g.fillStyle = COLORS[c % COLORS.length]; g.beginPath();
        g.arc(x, Math.min(Math.max(L.yOf(v), L.top), L.bottom), 2.5, 0, 2 * Math.PI); g.fill();
      });
      drawLegend(g, grp, L, w, l, values);
    });
    panel.dataset.playhead = time.toFixed(3);
    panel.dataset.values = values.join(';');
  }
