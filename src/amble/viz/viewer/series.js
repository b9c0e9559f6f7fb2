  // series.js: the time-series panel (data.series: name -> one value per frame), drawn once to an
  // offscreen canvas; drawSeries(time) copies it and draws the playhead at `time`.
  const series = data.series || {};
  const seriesNames = Object.keys(series);
  const panel = $('series');
  const COLORS = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b', '#e377c2', '#17becf'];
  let seriesImage = null;
  function buildSeries() {
    if (!seriesNames.length || !panel) return;
    panel.hidden = false;
    const w = panel.width = panel.clientWidth || 360, h = panel.height = panel.clientHeight || 140;
    const off = document.createElement('canvas');
    off.width = w; off.height = h;
    const g = off.getContext('2d');
    g.fillStyle = 'rgba(255,255,255,0.85)'; g.fillRect(0, 0, w, h);
    const band = (h - 6) / seriesNames.length;
    g.font = '11px sans-serif';
    seriesNames.forEach((name, k) => {
      const v = series[name];
      let lo = Infinity, hi = -Infinity;
      for (const x of v) if (x !== null) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
      if (!(hi > lo)) { hi = lo + 1; lo -= 1; }
      const y0 = 3 + band * (k + 1) - 2, sc = (band - 4) / (hi - lo);
      g.strokeStyle = COLORS[k % COLORS.length]; g.lineWidth = 1.2; g.beginPath();
      let pen = false;
      for (let i = 0; i < F; i++) {
        if (v[i] === null) { pen = false; continue; }
        const x = duration > 0 ? (T[i] - t0) / duration * (w - 1) : 0, y = y0 - (v[i] - lo) * sc;
        if (pen) g.lineTo(x, y); else g.moveTo(x, y);
        pen = true;
      }
      g.stroke();
      g.fillStyle = COLORS[k % COLORS.length];
      g.fillText(name, 4, 3 + band * k + 11);
    });
    seriesImage = off;
    panel.dataset.series = seriesNames.join(',');
  }
  function drawSeries(time) {
    if (!seriesImage) return;
    const g = panel.getContext('2d');
    g.drawImage(seriesImage, 0, 0);
    const x = duration > 0 ? (time - t0) / duration * (panel.width - 1) : 0;
    g.strokeStyle = '#1f2933'; g.lineWidth = 1; g.beginPath();
    g.moveTo(x + 0.5, 0); g.lineTo(x + 0.5, panel.height); g.stroke();
    panel.dataset.playhead = time.toFixed(3);
  }
