  // data.js: status reporting, WebGL check, the scene JSON, the URL hash, frame lookup.
  // One part of the viewer: html.py joins data.js, scene.js and player.js, in that
  // order, into the body of one function, so they share its local names.

  const body = document.body;
  const $ = (id) => document.getElementById(id);
  const api = { ready: false, play() {}, pause() {}, seek() {}, time() { return 0; },
                playing() { return false; }, duration: 0 };
  window.amble = api;

  function fail(state, title, text) {
    body.dataset.ambleState = state;
    api.ready = false;
    $('message-title').textContent = title;
    $('message-text').textContent = text;
    $('message').hidden = false;
    $('bar').style.display = 'none';
  }
  window.addEventListener('error', (e) => {
    fail('error', 'The animation could not be shown.', String(e.message || e.error || e));
  });

  function webgl2Available() {
    try { return !!document.createElement('canvas').getContext('webgl2'); }
    catch (e) { return false; }
  }
  if (typeof THREE === 'undefined') {
    fail('error', 'The animation could not be shown.', 'three.js did not load.');
    return;
  }
  if (!webgl2Available()) {
    fail('no-webgl', 'WebGL is not available.',
      'This animation needs WebGL 2. Enable hardware acceleration (or WebGL) in the ' +
      'browser settings, or open the file in a recent Chrome, Firefox, Edge or Safari.');
    return;
  }

  const data = JSON.parse($('amble-scene').textContent);
  const T = Float64Array.from(data.times);
  const F = T.length;
  const t0 = T[0], t1 = T[F - 1], duration = t1 - t0;
  const P = {};
  for (const name in data.points) P[name] = Float64Array.from(data.points[name]);
  const labels = data.labels || {};
  const follow = data.follow && P[data.follow] ? data.follow : null;
  const ground = data.shapes.find((s) => s.type === 'ground') || null;
  const tanSlope = ground ? Math.tan(ground.slope) : 0;

  const hash = new URLSearchParams(location.hash.replace(/^#/, ''));
  const hashNum = (k, d) => {
    const v = hash.has(k) ? parseFloat(hash.get(k)) : NaN;
    return isFinite(v) ? v : d;
  };
  const hashBool = (k, d) => (hash.has(k) ? !/^(0|false|no|off)$/i.test(hash.get(k)) : d);

  // ---- frame lookup: linear interpolation between stored frames -------------
  const loc = { i: 0, j: 0, w: 0 };
  function locate(t) {
    if (t <= t0) { loc.i = loc.j = 0; loc.w = 0; return loc; }
    if (t >= t1) { loc.i = loc.j = F - 1; loc.w = 0; return loc; }
    let lo = 0, hi = F - 1;            // largest i with T[i] <= t
    while (hi - lo > 1) { const m = (lo + hi) >> 1; if (T[m] <= t) lo = m; else hi = m; }
    const dt = T[lo + 1] - T[lo];
    loc.i = lo; loc.j = lo + 1; loc.w = dt > 0 ? (t - T[lo]) / dt : 1;
    return loc;
  }
  function pointAt(name, l, out) {
    const a = P[name], i = 3 * l.i, j = 3 * l.j, w = l.w;
    return out.set(a[i] + w * (a[j] - a[i]), a[i + 1] + w * (a[j + 1] - a[i + 1]),
                   a[i + 2] + w * (a[j + 2] - a[i + 2]));
  }
