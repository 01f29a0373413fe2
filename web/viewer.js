// The zoetic run viewer: plays the run's glTF (written by zoetic.viz.gltf) with three.js.
// The page holds <script id="zoetic-data" type="application/json"> with the .glb in base64
// and the run's figures (centre-of-mass paths, activations, numbers, plots). esbuild bundles
// this file, kinds.js (what each kind of run draws beside the bodies) and panels.js (the plots
// beside the view) with three.js into src/zoetic/web/static/viewer.js (see web/package.json).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { addGaze, addLabels, addSplash, setLayer, tagLayers } from "./kinds.js";
import { el, makeActivations, makeHistory, makeMind } from "./panels.js";

const SKY = 0x9ec2e6;
const BACKGROUNDS = { ground: SKY, sea: SKY, water: 0x1f4f74, vacuum: 0x14151f };

function decodeBase64(text) {
  const bin = atob(text);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

function parseGlb(buffer) {
  return new Promise((resolve, reject) => new GLTFLoader().parse(buffer, "", resolve, reject));
}

function fmt(v) {
  if (typeof v !== "number" || Number.isInteger(v)) return String(v);
  return Math.abs(v) >= 100 ? v.toFixed(1) : v.toPrecision(4);
}

// ---- time plots of the record's per-period scalars: one strip chart per chosen quantity of
// the chosen animal, with a cursor at the time shown (data.plots, from zoetic.viz.viewer)
const CHART_H = 58; // css px per strip chart
const MAX_CHARTS = 4; // charts shown at once, so the box stays clear of the panel

function lastAtOrBefore(times, t) { // index of the last period that began by t (0 if none)
  let lo = 0, hi = times.length - 1;
  while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (times[mid] <= t + 1e-9) lo = mid; else hi = mid - 1; }
  return lo;
}

function makePlots(plots, root, duration) {
  const who = Object.keys(plots.animals || {});
  if (!who.length) return null;
  const box = el("div", { id: "plots" }, root);
  const head = el("div", { className: "head" }, box);
  el("span", { className: "name", textContent: "time plots" }, head);
  const pick = el("select", { id: "plot-who" }, head);
  for (const w of who) el("option", { value: w, textContent: w }, pick);
  const chips = el("div", { className: "chips" }, box);
  const holder = el("div", {}, box);
  const chosen = new Set();
  let charts = [];
  const unitOf = (what) => plots.units[what] ?? plots.units[what.replace(/ \d+$/, "")] ?? "";
  const build = () => {
    holder.replaceChildren();
    const series = plots.animals[pick.value];
    charts = [...chosen].filter((q) => q in series).map((what) => {
      const values = series[what];
      const finite = values.filter((v) => v !== null);
      let lo = Math.min(...finite), hi = Math.max(...finite);
      if (!finite.length) { lo = 0; hi = 1; }
      if (hi - lo < 1e-9) { lo -= 0.5; hi += 0.5; }
      const canvas = el("canvas", { className: "chart" }, holder);
      const dpr = window.devicePixelRatio || 1;
      const w = holder.clientWidth || 280;
      canvas.style.width = `${w}px`; canvas.style.height = `${CHART_H}px`;
      canvas.width = Math.round(w * dpr); canvas.height = Math.round(CHART_H * dpr);
      const trace = document.createElement("canvas"); // the series, drawn once
      trace.width = canvas.width; trace.height = canvas.height;
      const g = trace.getContext("2d");
      g.scale(dpr, dpr);
      const top = 14, bottom = CHART_H - 3;
      const xOf = (t) => (w * t) / Math.max(duration, 1e-9);
      const yOf = (v) => bottom - ((v - lo) / (hi - lo)) * (bottom - top);
      g.fillStyle = "rgba(255,255,255,0.06)"; g.fillRect(0, top, w, bottom - top);
      g.strokeStyle = "#6cc4ff"; g.lineWidth = 1.2; g.beginPath();
      let pen = false;
      values.forEach((v, k) => {
        if (v === null) { pen = false; return; }
        const x = xOf(plots.times[k]), y = yOf(v);
        if (pen) g.lineTo(x, y); else g.moveTo(x, y);
        pen = true;
      });
      g.stroke();
      g.fillStyle = "#9ab"; g.font = "10px system-ui, sans-serif"; g.textAlign = "right";
      g.fillText(`${short(lo)} … ${short(hi)}`, w - 2, 10);
      return { what, values, canvas, trace, w, xOf, unit: unitOf(what), points: finite.length, lo, hi };
    });
  };
  const toggle = (what, on) => {
    if (on) chosen.add(what); else chosen.delete(what);
    build();
  };
  const makeChips = () => {
    chips.replaceChildren();
    const names = Object.keys(plots.animals[pick.value]);
    for (const q of [...chosen]) if (!names.includes(q)) chosen.delete(q);
    if (!chosen.size) names.slice(0, 2).forEach((q) => chosen.add(q));
    for (const q of names) {
      const label = el("label", { className: "chip" }, chips);
      const box2 = el("input", { type: "checkbox", checked: chosen.has(q), value: q }, label);
      label.append(q);
      box2.onchange = () => {
        if (box2.checked && chosen.size >= MAX_CHARTS) { box2.checked = false; return; }
        toggle(q, box2.checked);
      };
    }
    build();
  };
  pick.onchange = makeChips;
  makeChips();
  const draw = (t) => {
    for (const c of charts) {
      const g = c.canvas.getContext("2d");
      const dpr = c.canvas.width / c.w;
      g.setTransform(1, 0, 0, 1, 0, 0);
      g.clearRect(0, 0, c.canvas.width, c.canvas.height);
      g.drawImage(c.trace, 0, 0);
      g.scale(dpr, dpr);
      const x = c.xOf(t);
      g.strokeStyle = "#ffd040"; g.lineWidth = 1; g.beginPath();
      g.moveTo(x, 12); g.lineTo(x, CHART_H); g.stroke();
      const v = c.values[lastAtOrBefore(plots.times, t)];
      g.fillStyle = "#eee"; g.font = "11px system-ui, sans-serif"; g.textAlign = "left";
      g.fillText(`${c.what}${c.unit ? ` (${c.unit})` : ""}: ${v === null ? "–" : String(Number(v.toPrecision(4)))}`, 2, 10);
    }
  };
  const info = () => ({ who: pick.value, charts: charts.map((c) =>
    ({ what: c.what, unit: c.unit, points: c.points, min: c.lo, max: c.hi })) });
  return { draw, info };
}

function short(v) { // three significant digits, no trailing zeros: an axis range
  return String(Number(v.toPrecision(3)));
}

// ---- display skins: an animal's surface is a fixed linear map of its nodes (zoetic.render.skin),
// written in the glTF as a skinned mesh with more than four joints per vertex (JOINTS_1, ...).
// three.js skins with four, so such a mesh is drawn here instead: each frame every vertex is the
// weighted sum of its joints' positions (the nodes, keyframed by the animation), then smoothly
// shaded with its own colour.
function skinSets(geometry) { // [[joints, weights], ...] attribute pairs, four influences each
  const sets = [[geometry.attributes.skinIndex, geometry.attributes.skinWeight]];
  for (let s = 1; geometry.attributes[`joints_${s}`]; s++) {
    sets.push([geometry.attributes[`joints_${s}`], geometry.attributes[`weights_${s}`]]);
  }
  return sets;
}

function makeDisplaySkins(root, scene) {
  const skins = [];
  root.traverse((o) => {
    if (!o.isSkinnedMesh || !o.geometry.attributes.joints_1) return;
    const sets = skinSets(o.geometry);
    const n = o.geometry.attributes.position.count, k = 4 * sets.length;
    const index = new Uint16Array(n * k), weight = new Float32Array(n * k);
    sets.forEach(([j, w], s) => {
      for (let v = 0; v < n; v++) {
        for (let c = 0; c < 4; c++) {
          index[v * k + 4 * s + c] = j.getComponent(v, c);
          weight[v * k + 4 * s + c] = w.getComponent(v, c);
        }
      }
    });
    // GLTFLoader rescales the first four weights to sum to 1; all of them did, so set 0's
    // share is 1 minus the other sets'
    for (let v = 0; v < n; v++) {
      let first = 0, others = 0;
      for (let c = 0; c < k; c++) (c < 4 ? (first += weight[v * k + c]) : (others += weight[v * k + c]));
      if (first > 0) for (let c = 0; c < 4; c++) weight[v * k + c] *= (1 - others) / first;
    }
    const geo = new THREE.BufferGeometry();
    geo.setIndex(o.geometry.index);
    geo.setAttribute("position", o.geometry.attributes.position.clone());
    if (o.geometry.attributes.color) geo.setAttribute("color", o.geometry.attributes.color);
    const material = o.material.clone();
    material.vertexColors = Boolean(o.geometry.attributes.color);
    material.side = THREE.DoubleSide;
    const mesh = new THREE.Mesh(geo, material);
    mesh.name = `${o.name} (display skin)`;
    mesh.frustumCulled = false;
    o.visible = false;
    scene.add(mesh);
    skins.push({ bones: o.skeleton.bones, index, weight, k, n, geo });
  });
  const p = new THREE.Vector3();
  const update = () => {
    if (!skins.length) return;
    root.updateMatrixWorld(true);
    for (const s of skins) {
      const joints = new Float32Array(3 * s.bones.length);
      s.bones.forEach((b, j) => { p.setFromMatrixPosition(b.matrixWorld); p.toArray(joints, 3 * j); });
      const out = s.geo.attributes.position.array;
      for (let v = 0; v < s.n; v++) {
        let x = 0, y = 0, z = 0;
        for (let c = v * s.k; c < (v + 1) * s.k; c++) {
          const w = s.weight[c];
          if (w === 0) continue;
          const j = 3 * s.index[c];
          x += w * joints[j]; y += w * joints[j + 1]; z += w * joints[j + 2];
        }
        out[3 * v] = x; out[3 * v + 1] = y; out[3 * v + 2] = z;
      }
      s.geo.attributes.position.needsUpdate = true;
      s.geo.computeVertexNormals();
    }
  };
  return { count: skins.length, update };
}

async function main() {
  const data = JSON.parse(document.getElementById("zoetic-data").textContent);
  const api = { ready: false, error: null, frames: data.frames, duration: data.duration };
  window.zoetic = api;
  const root = document.getElementById("zoetic");
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  root.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  const medium = data.medium;
  scene.background = new THREE.Color(BACKGROUNDS[medium] ?? SKY);
  if (medium === "water") scene.fog = new THREE.Fog(scene.background, 2, 14);
  else if (medium !== "vacuum") scene.fog = new THREE.Fog(scene.background, 20, 60);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x445566, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 2.2);
  sun.position.set(-2, 10, 7);
  scene.add(sun);
  const camera = new THREE.PerspectiveCamera(45, 1, 0.02, 500);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;

  const gltf = await parseGlb(decodeBase64(data.glb));
  scene.add(gltf.scene);
  tagLayers(gltf.scene, data.objects);
  gltf.scene.traverse((o) => {
    if (o.isSkinnedMesh || o.isMesh) o.frustumCulled = false; // skinned bounds are the rest pose
  });
  const mixer = new THREE.AnimationMixer(gltf.scene);
  if (gltf.animations.length) mixer.clipAction(gltf.animations[0]).play();
  const clipEnd = gltf.animations.length ? gltf.animations[0].duration * (1 - 1e-6) : 0;
  const displaySkins = makeDisplaySkins(gltf.scene, scene);

  // centre-of-mass paths, in glTF axes, flat [x, y, z, ...] per frame
  const coms = data.animals.map((a) => a.com);
  for (const com of coms) {
    const geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.Float32BufferAttribute(com, 3));
    const line = new THREE.Line(geo, new THREE.LineBasicMaterial({ color: 0xffd040 }));
    line.frustumCulled = false;
    line.userData.layer = "paths";
    scene.add(line);
  }
  const comAt = (k, i) => new THREE.Vector3(coms[k][3 * i], coms[k][3 * i + 1], coms[k][3 * i + 2]);

  // the camera starts behind and to the right of the animal, as in the videos
  const az = THREE.MathUtils.degToRad(data.azimuth), elev = THREE.MathUtils.degToRad(data.elevation);
  const dist = (2.0 * data.extent) / Math.tan(THREE.MathUtils.degToRad(22.5));
  const dir = new THREE.Vector3(-Math.cos(elev) * Math.cos(az), Math.sin(elev),
    Math.cos(elev) * Math.sin(az));
  controls.target.copy(comAt(0, 0));
  camera.position.copy(controls.target).addScaledVector(dir, dist);
  controls.update();

  // ---- the panel and the controls
  const panel = el("div", { id: "panel" }, root);
  el("div", { className: "title", textContent: data.title }, panel);
  const timeText = el("div", { className: "time" }, panel);
  const rows = el("table", {}, panel);
  const dynamic = {};
  const addRow = (key, value) => {
    const tr = el("tr", {}, rows);
    el("td", { textContent: key }, tr);
    return el("td", { textContent: value }, tr);
  };
  dynamic.distance = addRow("distance (m)", "");
  // the run's figures: a long list folds away so that it does not hide the animal
  const figures = Object.entries(data.numbers);
  let figureRows = rows;
  if (figures.length > 4) {
    const fold = el("details", { id: "figures" }, panel);
    el("summary", { textContent: `figures (${figures.length})` }, fold);
    figureRows = el("table", {}, fold);
  }
  for (const [key, value] of figures) {
    const tr = el("tr", {}, figureRows);
    el("td", { textContent: key.replaceAll("_", " ") }, tr);
    el("td", { textContent: fmt(value) }, tr);
  }
  // each animal's named states (an aquarium fish's intention) at the frame shown
  const states = Object.entries(data.states || {});
  const stateBox = states.length ? el("div", { className: "sub states" }, panel) : null;
  // the last few events (eat, catch, mate, ...) up to the time shown
  const events = data.events || [];
  const eventBox = events.length ? el("div", { className: "sub events" }, panel) : null;
  const bar = el("div", { id: "controls" }, root);
  const play = el("button", { id: "play", textContent: "pause" }, bar);
  const slider = el("input", { id: "timeline", type: "range", min: 0, max: data.duration,
    step: 1 / data.fps, value: 0 }, bar);
  const speed = el("select", { id: "speed" }, bar);
  for (const s of [0.25, 0.5, 1, 2, 4]) el("option", { value: s, textContent: `${s}x`, selected: s === 1 }, speed);
  // the plots beside the view, and what this kind of run draws beside the bodies
  const side = el("div", { id: "side" }, document.body);
  const plots = makePlots(data.plots || {}, side, data.duration);
  const panels = {
    activations: makeActivations(side, data.animals, data.fps, data.duration),
    mind: makeMind(side, data.mind || {}, (data.plots || {}).times || [], data.duration),
    history: makeHistory(side, data.history || {}),
  };
  if (!side.childElementCount) side.remove();
  else document.body.classList.add("with-side");
  const extras = {
    gaze: addGaze(scene, data.gaze),
    spray: addSplash(scene, data.splash),
    labels: addLabels(root, camera, data.states, data.animals, 0.6 * data.extent),
  };
  const followLabel = el("label", { textContent: " follow" }, bar);
  const follow = el("input", { id: "follow", type: "checkbox", checked: true });
  followLabel.prepend(follow);

  let t = 0, playing = true, last = performance.now();
  const setTime = (time) => {
    t = Math.min(Math.max(time, 0), data.duration);
    mixer.setTime(Math.min(t, clipEnd)); // a repeating clip wraps to its start at its end
    displaySkins.update();
    const i = Math.min(Math.round(t * data.fps), data.frames - 1);
    if (follow.checked) {
      const delta = comAt(0, i).sub(controls.target);
      controls.target.add(delta);
      camera.position.add(delta);
    }
    const start = comAt(0, 0), now = comAt(0, i);
    dynamic.distance.textContent = Math.hypot(now.x - start.x, now.z - start.z).toFixed(3);
    timeText.textContent = `t = ${t.toFixed(2)} s / ${data.duration.toFixed(2)} s`;
    slider.value = t;
    if (stateBox) {
      stateBox.textContent = states.map(([who, q]) =>
        `${who}: ${Object.values(q).map((v) => v[i]).join(", ")}`).join("\n");
    }
    if (eventBox) {
      let n = 0;
      while (n < events.length && events[n][0] <= t + 1e-9) n++;
      eventBox.textContent = events.slice(Math.max(0, n - 5), n)
        .map((e) => `${e[0].toFixed(1)} s ${e[1]} ${e[2]} ${e[3]}`).join("\n");
    }
    if (plots) plots.draw(t);
    for (const p of Object.values(panels)) if (p) p.draw(t);
    for (const x of Object.values(extras)) if (x) x.update(t, i);
  };
  play.onclick = () => { playing = !playing; play.textContent = playing ? "pause" : "play"; };
  slider.oninput = () => setTime(parseFloat(slider.value));
  window.addEventListener("keydown", (e) => { // space: play/pause; arrows: one frame
    if (e.target.tagName === "SELECT" || e.target.tagName === "INPUT" && e.target !== slider) return;
    if (e.key === " ") { play.onclick(); e.preventDefault(); }
    if (e.key === "ArrowRight" || e.key === "ArrowLeft") {
      if (playing) play.onclick();
      setTime(t + (e.key === "ArrowRight" ? 1 : -1) / data.fps);
      e.preventDefault();
    }
  });
  const resize = () => {
    const w = root.clientWidth, h = root.clientHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  };
  window.addEventListener("resize", resize);
  resize();
  const render = () => {
    controls.update();
    if (extras.labels) extras.labels.place();
    renderer.render(scene, camera);
  };
  renderer.setAnimationLoop((now) => {
    const step = (now - last) / 1000;
    last = now;
    if (playing && data.duration > 0) setTime((t + step * parseFloat(speed.value)) % data.duration);
    render();
  });

  Object.assign(api, {
    scene, camera, controls,
    displaySkins: () => displaySkins.count,
    time: () => t,
    setTime: (time) => { setTime(time); render(); },
    pause: () => { playing = false; play.textContent = "play"; },
    // for tests and tools: the animal and the quantities plotted, with their sample counts
    plots: () => (plots ? plots.info() : null),
    // for tests and tools: what the side bar's panels show, and what each kind's extras hold
    panels: () => Object.fromEntries(Object.entries(panels).filter(([, p]) => p)
      .map(([k, p]) => [k, p.info()])),
    extras: () => ({ gaze: !!extras.gaze, drops: extras.spray ? extras.spray.drops() : 0,
      labels: extras.labels ? extras.labels.texts() : [] }),
    // for tests and tools: show or hide one kind of thing (animals, objects, environment,
    // paths, gaze, spray; returns how many there are), and where animal k's centre is drawn
    setLayer: (layer, visible) => { const n = setLayer(scene, layer, visible); render(); return n; },
    project: (k) => {
      const i = Math.min(Math.round(t * data.fps), data.frames - 1);
      const v = comAt(k, i).project(camera), c = renderer.domElement;
      return { x: ((v.x + 1) / 2) * c.clientWidth, y: ((1 - v.y) / 2) * c.clientHeight };
    },
    // for tests and tools: parse any .glb (base64) with three.js's GLTFLoader and count its parts
    inspectGlb: async (b64) => {
      const g = await parseGlb(decodeBase64(b64));
      let meshes = 0, skinned = 0;
      g.scene.traverse((o) => { if (o.isMesh) meshes++; if (o.isSkinnedMesh) skinned++; });
      return { meshes, skinned, animations: g.animations.length,
        tracks: g.animations.reduce((s, a) => s + a.tracks.length, 0),
        duration: g.animations.length ? g.animations[0].duration : 0 };
    },
  });
  setTime(0);
  render();
  api.ready = true;
}

main().catch((err) => {
  window.zoetic = Object.assign(window.zoetic || {}, { ready: false, error: String(err) });
  document.body.appendChild(el("pre", { id: "error", textContent: String(err && err.stack || err) }));
});
