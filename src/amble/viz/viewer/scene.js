  // scene.js: the three.js renderer, lights and shapes built from the scene JSON, and the initial camera.
  // One part of the viewer: html.py joins data.js, scene.js and player.js, in that
  // order, into the body of one function, so they share its local names.

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
    group.rotation.y = g.slope;             // local x runs downhill: z = height - x tan(slope)
    group.position.z = g.height || 0;       // a floor under a robot that is no walker
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
  // The robot's extent over the whole run (a robot that falls or swings its arms up needs
  // more room than its first pose shows); older scenes without it: the first frame's.
  const robotSize = Math.max(0.5, data.size || hi0.clone().sub(lo0).length());
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
  // Close enough to see the robot, or the whole walk when the camera stays put (the view's
  // height at distance d is 0.69 d: 2.4 sizes leave a margin around a robot standing still).
  const walk = new THREE.Vector3().fromArray(data.bounds.max)
    .sub(new THREE.Vector3().fromArray(data.bounds.min)).length();
  const dist = followOn ? 3.2 * robotSize : Math.max(2.4 * robotSize, 1.1 * walk);
  controls.target.copy(center);
  // A side view from -y (x runs left to right), slightly raised and from ahead.
  // '#view=side|front|iso' picks another initial direction (figures, front view of 3D sway).
  const views = { iso: [0.3, -1, 0.3], side: [0, -1, 0.12], front: [1, 0, 0.2] };
  const dir = views[hash.get('view')] || views.iso;
  camera.position.copy(center).add(new THREE.Vector3(...dir).normalize()
    .multiplyScalar(dist));
  controls.update();
