"""Offline browser animation of a scene built by :func:`amble.viz.scene.frames`.

:func:`write_html` writes one self-contained HTML file: the scene data, the
viewer and the vendored three.js (with OrbitControls) are all inlined, so the
file opens from disk with no network. The page shows a 3D view with an orbit
camera and a control bar (play/pause, time slider, clock, speed, camera
follow, shadows).

The page can be driven from a script:

* ``window.amble`` has ``play()``, ``pause()``, ``seek(t)``, ``time()`` and
  ``ready`` (true once the first frame is drawn).
* ``document.body.dataset.ambleState`` is ``"loading"``, ``"ready"``,
  ``"no-webgl"`` or ``"error"``.
* The URL hash sets the initial state, e.g. ``page.html#t=1.5`` opens paused
  at t = 1.5 s. Keys: ``t`` (seconds), ``play`` (0/1), ``speed``, ``follow``
  (0/1), ``shadows`` (0/1), ``ui`` (0 hides the control bar and captions),
  ``view`` (``iso``, ``side`` or ``front``: the initial camera direction).

Keyboard: space plays/pauses, left/right arrows step one frame.
"""

from __future__ import annotations

import html as _html
import json
import re
from functools import lru_cache
from pathlib import Path
from typing import Any

from .scene import FORMAT

__all__ = ["render_html", "write_html"]

_VENDOR = Path(__file__).resolve().parent / "_vendor"


@lru_cache(maxsize=1)
def _three_js() -> str:
    """The vendored three.js bundle (defines the global ``THREE``)."""
    code = (_VENDOR / "three.min.js").read_text(encoding="utf-8")
    # A literal "</script" would end the inline element early; "<\/" means the
    # same inside JS strings and regular expressions.
    return re.sub(r"</(script)", r"<\\/\1", code, flags=re.IGNORECASE)


def _scene_json(scene: dict[str, Any]) -> str:
    text = json.dumps(scene, separators=(",", ":"), allow_nan=False)
    # "<", ">" and "&" only occur inside JSON strings, where \u escapes are
    # equivalent; escaping them keeps the data from closing its <script> element.
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def render_html(scene: dict[str, Any], title: str = "amble") -> str:
    """The self-contained viewer page for ``scene`` as a string.

    Args:
        scene: a scene from :func:`amble.viz.scene.frames`.
        title: page title, also shown in the top-left corner.

    Raises:
        ValueError: ``scene`` is not in the ``amble.scene/1`` format or holds
            non-finite numbers.
    """
    if not isinstance(scene, dict) or scene.get("format") != FORMAT:
        got = scene.get("format") if isinstance(scene, dict) else type(scene).__name__
        raise ValueError(f"write_html: expected a scene in format {FORMAT!r}, got {got!r}")
    for key in ("times", "points", "shapes"):
        if key not in scene:
            raise ValueError(f"write_html: scene has no {key!r}")
    safe_title = _html.escape(title)
    parts = [
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n',
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n',
        f"<title>{safe_title}</title>\n<style>{_CSS}</style>\n</head>\n",
        '<body data-amble-state="loading">\n',
        _BODY.replace("@TITLE@", safe_title),
        '<script type="application/json" id="amble-scene">',
        _scene_json(scene),
        "</script>\n<script>",
        _three_js(),
        "</script>\n<script>",
        _VIEWER_JS,
        "</script>\n</body>\n</html>\n",
    ]
    return "".join(parts)


def write_html(path: str | Path, scene: dict[str, Any], title: str = "amble") -> Path:
    """Write the animation of ``scene`` to one offline HTML file.

    Args:
        path: where to write; parent folders are created.
        scene: a scene from :func:`amble.viz.scene.frames`.
        title: page title, also shown in the top-left corner.

    Returns:
        The absolute path of the written file.

    Raises:
        ValueError: see :func:`render_html`.
    """
    page = render_html(scene, title)
    out = Path(path).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(page, encoding="utf-8")
    return out


_CSS = """
:root { --fg: #1f2933; --muted: #616e7c; --accent: #2f6fde; --bar: rgba(255,255,255,0.92); }
* { box-sizing: border-box; }
html, body { margin: 0; height: 100%; overflow: hidden; background: #f3f5f8;
  font: 13px/1.3 system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif;
  color: var(--fg); }
#view { position: absolute; inset: 0; }
#view canvas { display: block; width: 100%; height: 100%; outline: none; }
#title { position: absolute; left: 14px; top: 10px; font-weight: 600; font-size: 14px;
  pointer-events: none; }
#title small { display: block; font-weight: 400; color: var(--muted); font-size: 12px; }
#hint { position: absolute; right: 14px; top: 12px; color: var(--muted); font-size: 11px;
  pointer-events: none; }
#bar { position: absolute; left: 50%; bottom: 12px; transform: translateX(-50%);
  width: min(760px, calc(100% - 24px)); display: flex; align-items: center; gap: 10px;
  padding: 6px 12px; background: var(--bar); border: 1px solid #dde2e8; border-radius: 10px;
  box-shadow: 0 2px 10px rgba(31,41,51,0.10); }
#bar button { width: 30px; height: 30px; border: 0; border-radius: 50%; background: var(--accent);
  color: #fff; cursor: pointer; display: grid; place-items: center; flex: none; padding: 0; }
#bar button:hover { filter: brightness(1.1); }
#bar button svg { width: 14px; height: 14px; fill: currentColor; }
#slider { flex: 1; min-width: 80px; accent-color: var(--accent); }
#clock { font-variant-numeric: tabular-nums; white-space: nowrap; min-width: 92px; }
#labels { font-variant-numeric: tabular-nums; white-space: nowrap; color: var(--muted); }
#labels:empty { display: none; }
#bar select { font: inherit; border: 1px solid #cfd6de; border-radius: 6px; background: #fff;
  padding: 2px 4px; }
#bar label { white-space: nowrap; color: var(--muted); cursor: pointer; user-select: none; }
#bar label input { vertical-align: -2px; accent-color: var(--accent); }
#message { position: absolute; inset: 0; display: grid; place-items: center; padding: 24px; }
#message[hidden] { display: none; }
#message div { max-width: 520px; background: #fff; border: 1px solid #e3b4b4;
  border-left: 4px solid #c53030; border-radius: 8px; padding: 16px 18px;
  box-shadow: 0 2px 10px rgba(0,0,0,0.08); }
#message b { display: block; margin-bottom: 6px; font-size: 15px; }
"""

_BODY = """<div id="view"></div>
<div id="title">@TITLE@<small id="subtitle"></small></div>
<div id="hint">drag: orbit &middot; right-drag: pan &middot; wheel: zoom &middot;
  space: play/pause</div>
<div id="bar">
  <button id="play" type="button" title="Play / pause (space)" aria-label="Play or pause"></button>
  <span id="clock">0.00 s</span>
  <input id="slider" type="range" min="0" max="1" step="any" value="0" aria-label="Time">
  <span id="labels"></span>
  <select id="speed" title="Playback speed" aria-label="Playback speed">
    <option value="0.25">0.25&times;</option><option value="0.5">0.5&times;</option>
    <option value="1" selected>1&times;</option><option value="2">2&times;</option>
    <option value="4">4&times;</option>
  </select>
  <label title="Camera tracks the robot"><input id="follow" type="checkbox" checked>
    follow robot</label>
  <label title="Cast shadows"><input id="shadows" type="checkbox" checked> shadows</label>
</div>
<div id="message" hidden><div><b id="message-title"></b><span id="message-text"></span></div></div>
"""

# The viewer. Plain ES2020 in a classic script: it uses the global THREE that
# the inlined bundle defines, so no module loading is involved.
_VIEWER_JS = r"""
(function () {
  'use strict';
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

  // ---- renderer, scene, camera ----------------------------------------------
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    fail('no-webgl', 'WebGL is not available.', 'Creating a WebGL 2 context failed: ' + e.message);
    return;
  }
  const view = $('view');
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = THREE.PCFSoftShadowMap;
  view.appendChild(renderer.domElement);

  const BG = 0xf3f5f8;
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(BG);
  scene.fog = new THREE.Fog(BG, 10, 40);

  const camera = new THREE.PerspectiveCamera(38, 1, 0.01, 1000);
  camera.up.set(0, 0, 1);            // z is up in amble's world frame
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.enableDamping = true;
  controls.dampingFactor = 0.12;

  scene.add(new THREE.HemisphereLight(0xffffff, 0xb9c0c8, 1.9));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.castShadow = true;
  sun.shadow.mapSize.set(2048, 2048);
  sun.shadow.bias = -0.0005;
  sun.shadow.normalBias = 0.01;
  scene.add(sun, sun.target);

  const srgb = (c) => new THREE.Color().setRGB(c[0], c[1], c[2], THREE.SRGBColorSpace);
  function material(s, extra) {
    const m = new THREE.MeshStandardMaterial(Object.assign({
      color: srgb(s.color), roughness: 0.5, metalness: 0.05,
      transparent: s.opacity < 1, opacity: s.opacity, depthWrite: s.opacity >= 1,
    }, extra || {}));
    return m;
  }

  // ---- shapes -----------------------------------------------------------------
  const sphereGeo = new THREE.SphereGeometry(1, 40, 24);
  const cylGeo = new THREE.CylinderGeometry(1, 1, 1, 28, 1);
  const UP = new THREE.Vector3(0, 1, 0);   // CylinderGeometry's axis
  const va = new THREE.Vector3(), vb = new THREE.Vector3(), vd = new THREE.Vector3();
  const updaters = [];

  function addGround(g) {
    const group = new THREE.Group();
    group.rotation.y = g.slope;             // local x runs downhill: z = -x tan(slope)
    const s0 = g.extent[0], s1 = g.extent[1], w = g.width, step = g.grid;
    const plane = new THREE.Mesh(new THREE.PlaneGeometry(s1 - s0, w),
      material(g, { roughness: 0.95, metalness: 0, polygonOffset: true,
                    polygonOffsetFactor: 1, polygonOffsetUnits: 1 }));
    plane.position.set((s0 + s1) / 2, 0, 0);
    plane.receiveShadow = true;
    group.add(plane);
    // Grid lines on the surface: minor every `grid`, major every 10 grid steps.
    const minor = [], major = [], z = 0.0005;
    const k0 = Math.ceil(s0 / step), k1 = Math.floor(s1 / step);
    for (let k = k0; k <= k1; k++) {
      (k % 10 === 0 ? major : minor).push(k * step, -w / 2, z, k * step, w / 2, z);
    }
    const m = Math.floor(w / 2 / step + 1e-9);
    for (let k = -m; k <= m; k++) {
      (k % 10 === 0 ? major : minor).push(s0, k * step, z, s1, k * step, z);
    }
    const lines = (arr, color, opacity) => {
      const geo = new THREE.BufferGeometry();
      geo.setAttribute('position', new THREE.Float32BufferAttribute(arr, 3));
      return new THREE.LineSegments(geo, new THREE.LineBasicMaterial(
        { color, transparent: true, opacity }));
    };
    group.add(lines(minor, 0x8a96a3, 0.45), lines(major, 0x4f5b67, 0.7));
    scene.add(group);
  }

  for (const s of data.shapes) {
    if (s.type === 'ground') { addGround(s); continue; }
    let mesh;
    if (s.type === 'sphere') {
      mesh = new THREE.Mesh(sphereGeo, material(s));
      mesh.scale.setScalar(s.radius);
      updaters.push((l) => pointAt(s.at, l, mesh.position));
    } else if (s.type === 'cylinder') {
      mesh = new THREE.Mesh(cylGeo, material(s));
      const [a, b] = s.between;
      updaters.push((l) => {
        pointAt(a, l, va); pointAt(b, l, vb);
        vd.subVectors(vb, va);
        const len = vd.length();
        mesh.visible = len > 1e-9;
        if (!mesh.visible) return;
        mesh.position.addVectors(va, vb).multiplyScalar(0.5);
        mesh.quaternion.setFromUnitVectors(UP, vd.divideScalar(len));
        mesh.scale.set(s.radius, len, s.radius);
      });
    } else if (s.type === 'box') {
      mesh = new THREE.Mesh(new THREE.BoxGeometry(s.size[0], s.size[1], s.size[2]), material(s));
      mesh.rotation.set(s.rotation[0], s.rotation[1], s.rotation[2], 'XYZ');
      if (typeof s.center === 'string') updaters.push((l) => pointAt(s.center, l, mesh.position));
      else mesh.position.set(s.center[0], s.center[1], s.center[2]);
    } else {
      continue;                            // unknown types from newer formats are skipped
    }
    mesh.castShadow = true;
    mesh.receiveShadow = true;
    scene.add(mesh);
  }

  // ---- framing ------------------------------------------------------------------
  // Robot size from the first frame (not the whole walk) sets the camera distance.
  const names = Object.keys(P);
  const lo0 = new THREE.Vector3(Infinity, Infinity, Infinity);
  const hi0 = new THREE.Vector3(-Infinity, -Infinity, -Infinity);
  const first = locate(t0);
  for (const n of names) { pointAt(n, first, va); lo0.min(va); hi0.max(va); }
  if (!names.length) { lo0.set(-0.5, -0.5, 0); hi0.set(0.5, 0.5, 1); }
  const robotSize = Math.max(0.5, hi0.clone().sub(lo0).length());
  const center = new THREE.Vector3();
  const followHeight = follow
    ? pointAt(follow, first, va).z + va.x * tanSlope : 0;   // height above the ground

  // Where the camera looks: below the follow point, at a fixed fraction of its
  // initial height above the ground (so the view glides instead of bobbing with
  // every step and the whole robot is in view), else the centroid of all points.
  function robotCenter(l, out) {
    if (follow) {
      pointAt(follow, l, out);
      if (ground) out.z = -out.x * tanSlope + 0.5 * followHeight;
      return out;
    }
    out.set(0, 0, 0);
    if (!names.length) return out;
    for (const n of names) out.add(pointAt(n, l, vb));
    return out.divideScalar(names.length);
  }

  const shadowBox = Math.max(1.5, 2 * robotSize);
  Object.assign(sun.shadow.camera, { left: -shadowBox, right: shadowBox,
    top: shadowBox, bottom: -shadowBox, near: 0.1, far: 20 * shadowBox });
  sun.shadow.camera.updateProjectionMatrix();
  const sunOffset = new THREE.Vector3(-0.35, -0.55, 1).normalize().multiplyScalar(8 * shadowBox);

  let followOn = hashBool('follow', !!follow);
  robotCenter(first, center);
  if (!followOn) {
    const b = data.bounds;
    center.set((b.min[0] + b.max[0]) / 2, (b.min[1] + b.max[1]) / 2, (b.min[2] + b.max[2]) / 2);
  }
  // Close enough to see the robot, or the whole walk when the camera stays put.
  const walk = new THREE.Vector3().fromArray(data.bounds.max)
    .sub(new THREE.Vector3().fromArray(data.bounds.min)).length();
  const dist = followOn ? 3.2 * robotSize : Math.max(3.2 * robotSize, 1.1 * walk);
  controls.target.copy(center);
  // A side view from -y (x runs left to right), slightly raised and from ahead.
  // '#view=side|front|iso' picks another initial direction (figures, front view of 3D sway).
  const views = { iso: [0.3, -1, 0.3], side: [0, -1, 0.12], front: [1, 0, 0.2] };
  const dir = views[hash.get('view')] || views.iso;
  camera.position.copy(center).add(new THREE.Vector3(...dir).normalize()
    .multiplyScalar(dist));
  controls.update();

  // ---- state and drawing ----------------------------------------------------------
  let t = t0, playing = false, speed = 1;
  const lastTarget = center.clone();
  const slider = $('slider'), clock = $('clock'), labelBox = $('labels');
  slider.min = String(t0); slider.max = String(t1 > t0 ? t1 : t0 + 1);
  const digits = duration >= 100 ? 1 : 2;
  let dragging = false;

  function fmtLabel(v) {
    if (typeof v === 'number' && !Number.isInteger(v)) return v.toFixed(3);
    return v === null ? '–' : String(v);
  }

  function apply(time) {
    const l = locate(time);
    for (const u of updaters) u(l);
    robotCenter(l, vd);
    if (followOn) {
      // Carry the camera along with the target so user orbit/zoom is kept.
      camera.position.add(va.subVectors(vd, lastTarget));
      controls.target.add(va);
      lastTarget.copy(vd);
    }
    sun.target.position.copy(vd);
    sun.position.copy(vd).add(sunOffset);
    // UI
    clock.textContent = time.toFixed(digits) + ' / ' + t1.toFixed(digits) + ' s';
    if (!dragging) slider.value = String(time);
    const k = l.w > 0.5 ? l.j : l.i;
    const parts = [];
    for (const key in labels) parts.push(key + ' ' + fmtLabel(labels[key][k]));
    labelBox.textContent = parts.join('  ·  ');
  }

  function resize() {
    const w = view.clientWidth || window.innerWidth, h = view.clientHeight || window.innerHeight;
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
  }

  function render() {
    // Fog scaled to the viewing distance fades the far ground into the background.
    const d = camera.position.distanceTo(controls.target);
    scene.fog.near = 2.5 * d; scene.fog.far = 7 * d;
    renderer.render(scene, camera);
  }

  function draw() {
    apply(t);
    controls.update();
    render();
  }

  const ICON_PLAY = '<svg viewBox="0 0 16 16"><path d="M4 2.5v11l9.5-5.5z"/></svg>';
  const ICON_PAUSE =
    '<svg viewBox="0 0 16 16"><path d="M3.5 2.5h3.2v11H3.5zM9.3 2.5h3.2v11H9.3z"/></svg>';
  function setPlaying(p) {
    playing = p && duration > 0;
    $('play').innerHTML = playing ? ICON_PAUSE : ICON_PLAY;
  }
  function seek(time) {
    const x = Number(time);
    t = Math.min(t1, Math.max(t0, isFinite(x) ? x : t0));
    draw();
  }
  function stepFrame(dir) {
    setPlaying(false);
    const l = locate(t);
    const i = dir > 0 ? (l.w > 0 ? l.j : Math.min(F - 1, l.i + 1))
                      : (l.w > 0 ? l.i : Math.max(0, l.i - 1));
    seek(T[i]);
  }

  // ---- controls -------------------------------------------------------------------
  $('play').addEventListener('click', () => setPlaying(!playing));
  slider.addEventListener('pointerdown', () => { dragging = true; });
  window.addEventListener('pointerup', () => { dragging = false; });
  slider.addEventListener('input', () => seek(parseFloat(slider.value)));
  const speedSel = $('speed');
  speedSel.addEventListener('change', () => { speed = parseFloat(speedSel.value) || 1; });
  const followBox = $('follow');
  followBox.checked = followOn;
  followBox.disabled = !follow;
  if (!follow) followBox.parentElement.title = 'This scene names no point to follow';
  followBox.addEventListener('change', () => {
    followOn = followBox.checked && !!follow;
    robotCenter(locate(t), lastTarget);
    if (followOn) {            // jump to the robot, keeping the current view direction
      camera.position.add(va.subVectors(lastTarget, controls.target));
      controls.target.copy(lastTarget);
    }
    draw();
  });
  const shadowBox2 = $('shadows');
  const setShadows = (on) => { sun.castShadow = on; shadowBox2.checked = on; };
  shadowBox2.addEventListener('change', () => { setShadows(shadowBox2.checked); draw(); });
  window.addEventListener('keydown', (e) => {
    if (e.target && /^(INPUT|SELECT|TEXTAREA)$/.test(e.target.tagName) && e.target.type !== 'range'
        && e.target.type !== 'checkbox') return;
    if (e.code === 'Space') { e.preventDefault(); setPlaying(!playing); }
    else if (e.code === 'ArrowRight') { e.preventDefault(); stepFrame(1); }
    else if (e.code === 'ArrowLeft') { e.preventDefault(); stepFrame(-1); }
  });
  window.addEventListener('resize', () => { resize(); draw(); });

  // ---- subtitle -------------------------------------------------------------------
  const sub = [];
  if (ground) sub.push('slope ' + (ground.slope * 180 / Math.PI).toFixed(2) + '°');
  sub.push(F + ' frames');
  $('subtitle').textContent = sub.join(' · ');

  // ---- public API, initial state and loop -------------------------------------------
  api.play = () => setPlaying(true);
  api.pause = () => setPlaying(false);
  api.seek = seek;
  api.time = () => t;
  api.playing = () => playing;
  api.duration = duration;

  if (!hashBool('ui', true)) {          // bare canvas, e.g. for figures
    for (const id of ['bar', 'title', 'hint']) $(id).style.display = 'none';
  }
  speed = hashNum('speed', 1);
  const listed = [...speedSel.options].find((o) => parseFloat(o.value) === speed);
  if (listed) speedSel.value = listed.value;
  setShadows(hashBool('shadows', true));
  resize();
  // A requested time opens paused there (reproducible screenshots); otherwise play.
  seek(hashNum('t', t0));
  setPlaying(hashBool('play', !hash.has('t')));

  // Draw only when something changed: a paused view costs nothing, which matters
  // for laptops and for software-rendered (headless) browsers.
  let last = null;
  function tick(now) {
    requestAnimationFrame(tick);
    const dt = last === null ? 0 : Math.min(0.1, (now - last) / 1000);
    last = now;
    if (playing) {
      t += dt * speed;
      if (t > t1) t = t0 + ((t - t0) % duration);   // loop
      draw();
    } else if (controls.update()) {
      render();
    }
  }
  api.ready = true;
  body.dataset.ambleState = 'ready';
  requestAnimationFrame(tick);
})();
"""
