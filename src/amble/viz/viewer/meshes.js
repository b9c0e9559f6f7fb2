  // meshes.js: triangle meshes (data.meshes) carried by link frames (data.poses), e.g. a URDF's
  // visual meshes. One part of the viewer: html.py joins the parts into one function body, so
  // this part uses scene.js's scene, material() and updaters.

  // base64 -> a typed array over a fresh (aligned) buffer; the data are little-endian
  function unpack(text, Type) {
    const bin = atob(text), bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  const geometries = {};
  function meshGeometry(key) {
    if (geometries[key]) return geometries[key];
    const m = data.meshes[key];
    const k = unpack(m.positions, Uint16Array), pos = new Float32Array(k.length);
    for (let i = 0; i < k.length; i += 3) {   // vertex = lo + k * step, per axis
      pos[i] = m.lo[0] + k[i] * m.step[0];
      pos[i + 1] = m.lo[1] + k[i + 1] * m.step[1];
      pos[i + 2] = m.lo[2] + k[i + 2] * m.step[2];
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setIndex(new THREE.BufferAttribute(unpack(m.indices, m.wide ? Uint32Array : Uint16Array), 1));
    geo.computeVertexNormals();
    geometries[key] = geo;
    return geo;
  }

  // One group per link frame, moved every frame: positions interpolated linearly, rotations by
  // slerp between the stored quaternions (x, y, z, w).
  const poses = {}, linkGroups = {};
  const qa = new THREE.Quaternion(), qb = new THREE.Quaternion();
  for (const name in (data.poses || {})) poses[name] = Float64Array.from(data.poses[name]);
  function linkGroup(name) {
    if (linkGroups[name]) return linkGroups[name];
    const g = new THREE.Group(), a = poses[name];
    updaters.push((l) => {
      const i = 7 * l.i, j = 7 * l.j, w = l.w;
      g.position.set(a[i] + w * (a[j] - a[i]), a[i + 1] + w * (a[j + 1] - a[i + 1]),
                     a[i + 2] + w * (a[j + 2] - a[i + 2]));
      qa.set(a[i + 3], a[i + 4], a[i + 5], a[i + 6]);
      qb.set(a[j + 3], a[j + 4], a[j + 5], a[j + 6]);
      g.quaternion.slerpQuaternions(qa, qb, w);
    });
    scene.add(g);
    linkGroups[name] = g;
    return g;
  }

  for (const s of data.shapes) {
    if (s.type !== 'mesh' || !poses[s.frame] || !(data.meshes || {})[s.mesh]) continue;
    // CAD meshes: flat shading shows their facets after decimation, and both sides are lit
    // because exported triangles do not always wind the same way.
    const mesh = new THREE.Mesh(meshGeometry(s.mesh),
      material(s, { flatShading: true, side: THREE.DoubleSide, roughness: 0.6 }));
    mesh.castShadow = true;
    mesh.receiveShadow = true;
    linkGroup(s.frame).add(mesh);
  }
