// What each kind of run draws beside the bodies and objects of its glTF: a predator's gaze
// rays (pursuit), a stunt's spray (drops thrown where the body crossed the surface) and the
// animals' named states (an aquarium fish's intention) as labels over them. Each adder
// returns { update(t, i) } or null: t the time shown (s), i its frame. Every object added is
// tagged with userData.layer so tests and tools can hide one kind of thing at a time.
import * as THREE from "three";

const GAZE_COLOR = 0xffff78; // as the chase videos' rays

// a pursuit's gaze: per animal with eyes, both eyes' rays from the eye to where it looks
export function addGaze(scene, gaze) {
  if (!gaze || !gaze.length) return null;
  const lines = gaze.map((g) => {
    const geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.Float32BufferAttribute(new Float32Array(12), 3));
    const line = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ color: GAZE_COLOR }));
    line.frustumCulled = false;
    line.userData.layer = "gaze";
    scene.add(line);
    return { line, rays: g.rays, frames: g.rays.length / 12 };
  });
  const update = (t, i) => {
    for (const l of lines) {
      const k = Math.min(i, l.frames - 1), pos = l.line.geometry.attributes.position;
      const ray = l.rays.slice(12 * k, 12 * k + 12);
      const ok = ray.every((v) => v !== null);
      l.line.visible = ok && l.line.userData.shown !== false;
      if (ok) { pos.array.set(ray); pos.needsUpdate = true; }
    }
  };
  return { update };
}

// a stunt's spray: drops launched at t0 from p0 with velocity v0 fly ballistically until they
// fall back below the water level (zoetic.viz.spray, as in the stunt videos)
export function addSplash(scene, splash) {
  if (!splash || !splash.t0 || !splash.t0.length) return null;
  const n = splash.t0.length;
  const geo = new THREE.BufferGeometry();
  geo.setAttribute("position", new THREE.Float32BufferAttribute(new Float32Array(3 * n), 3));
  geo.setDrawRange(0, 0);
  const dot = document.createElement("canvas"); // a round drop, not a square
  dot.width = dot.height = 32;
  const g = dot.getContext("2d");
  g.fillStyle = "#fff"; g.beginPath(); g.arc(16, 16, 14, 0, 2 * Math.PI); g.fill();
  const mat = new THREE.PointsMaterial({ color: 0xeef6ff, size: 0.07, sizeAttenuation: true,
    map: new THREE.CanvasTexture(dot), alphaTest: 0.5 });
  const drops = new THREE.Points(geo, mat);
  drops.frustumCulled = false;
  drops.userData.layer = "spray";
  scene.add(drops);
  const { t0, p0, v0, gravity, level } = splash;
  let shown = 0;
  const update = (t) => {
    const pos = geo.attributes.position.array;
    shown = 0;
    for (let d = 0; d < n; d++) {
      const dt = t - t0[d];
      if (dt < 0) continue;
      const y = p0[3 * d + 1] + v0[3 * d + 1] * dt - 0.5 * gravity * dt * dt;
      if (y < level) continue;
      pos[3 * shown] = p0[3 * d] + v0[3 * d] * dt;
      pos[3 * shown + 1] = y;
      pos[3 * shown + 2] = p0[3 * d + 2] + v0[3 * d + 2] * dt;
      shown++;
    }
    geo.setDrawRange(0, shown);
    geo.attributes.position.needsUpdate = true;
  };
  return { update, drops: () => shown };
}

// each animal's named states at the frame shown, in a label over its centre of mass; place()
// moves the labels where the camera sees the animals (after the camera moved)
export function addLabels(root, camera, states, animals, lift) {
  const who = Object.keys(states || {});
  if (!who.length) return null;
  const labels = who.map((name) => {
    const k = animals.findIndex((a) => a.name === name);
    const div = document.createElement("div");
    div.className = "label";
    root.appendChild(div);
    return { name, com: k >= 0 ? animals[k].com : null, q: Object.values(states[name]), div };
  });
  const v = new THREE.Vector3();
  let frame = 0;
  const place = () => { // over each animal as the camera sees it now
    camera.updateMatrixWorld();
    const w = root.clientWidth, h = root.clientHeight, i = frame;
    for (const l of labels) {
      if (!l.com) { l.div.style.display = "none"; continue; }
      v.set(l.com[3 * i], l.com[3 * i + 1] + lift, l.com[3 * i + 2]).project(camera);
      const on = v.z < 1 && Math.abs(v.x) < 1 && Math.abs(v.y) < 1;
      l.div.style.display = on ? "" : "none";
      l.div.style.left = `${((v.x + 1) / 2) * w}px`;
      l.div.style.top = `${((1 - v.y) / 2) * h}px`;
    }
  };
  const update = (t, i) => {
    frame = i;
    for (const l of labels) l.div.textContent = l.q.map((s) => s[i]).join(", ");
    place();
  };
  return { update, place, texts: () => labels.map((l) => l.div.textContent) };
}

// tag the glTF's nodes by what they are: the environment (ground, sea floor, surface), the
// run's objects (named kind-index-name by zoetic.viz.gltf); every other mesh is an animal
export function tagLayers(root, objects) {
  const clean = THREE.PropertyBinding.sanitizeNodeName; // as GLTFLoader names its nodes
  const env = new Set(["ground", "sea floor", "sea surface"].map(clean));
  const things = new Set((objects || []).map((o, i) => clean(`${o.kind}-${i + 1}-${o.name}`)));
  root.traverse((o) => {
    if (env.has(o.name)) o.userData.layer = "environment";
    else if (things.has(o.name)) o.userData.layer = "objects";
  });
}

// show or hide one layer: gaze, spray, paths, environment, objects, or animals (every mesh,
// line or point cloud without a layer of its own)
export function setLayer(scene, layer, visible) {
  const hit = [];
  scene.traverse((o) => {
    let tagged = o.userData.layer;
    for (let p = o.parent; !tagged && p; p = p.parent) tagged = p.userData.layer;
    const mine = tagged ? tagged === layer : layer === "animals" && (o.isMesh || o.isLine || o.isPoints);
    if (mine && (o.isMesh || o.isLine || o.isPoints)) hit.push(o);
  });
  for (const o of hit) { o.visible = visible; o.userData.shown = visible; }
  return hit.length;
}
