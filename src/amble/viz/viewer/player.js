  // player.js: time, drawing, the control bar, keyboard, window.amble and the animation loop.
  // One part of the viewer: html.py joins data.js, scene.js and player.js, in that
  // order, into the body of one function, so they share its local names.

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
    drawSeries(time);
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
  buildSeries();
  window.addEventListener('resize', () => { resize(); buildSeries(); draw(); });

  // ---- subtitle -------------------------------------------------------------------
  const sub = [];
  // a level floor (under a robot that is no walker) has no slope to tell
  if (ground && ground.slope) sub.push('slope ' + (ground.slope * 180 / Math.PI).toFixed(2) + '°');
  sub.push(F + ' frames');
  $('subtitle').textContent = sub.join(' · ');

  // ---- public API, initial state and loop -------------------------------------------
  api.play = () => setPlaying(true);
  api.pause = () => setPlaying(false);
  api.seek = seek;
  api.time = () => t;
  api.playing = () => playing;
  api.duration = duration;

  if (!hashBool('ui', true)) {          // bare canvas, e.g. for figures: no overlay hides the robot
    for (const id of ['bar', 'title', 'hint', 'series']) $(id).style.display = 'none';
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
