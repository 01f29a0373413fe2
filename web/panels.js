// The run's plots beside the 3D view, drawn on canvases from the data the page carries
// (zoetic.viz.viewer): muscle activations over time, the animals' minds (drives and
// intentions), a search's E history. Each panel returns { draw(t), info() }: draw puts the
// cursor at time t (s); info tells tests and tools what it shows.

export function el(tag, attrs = {}, parent = null) {
  const e = document.createElement(tag);
  Object.assign(e, attrs);
  if (parent) parent.appendChild(e);
  return e;
}

const short = (v) => String(Number(v.toPrecision(3))); // an axis label

// A panel: a titled box in the side bar, with a picker when there are several animals
export function section(side, id, title, names = []) {
  const box = el("div", { id, className: "section" }, side);
  const head = el("div", { className: "head" }, box);
  el("span", { className: "name", textContent: title }, head);
  let pick = null;
  if (names.length > 1) {
    pick = el("select", { id: `${id}-who` }, head);
    for (const n of names) el("option", { value: n, textContent: n }, pick);
  }
  return { box, pick, who: () => (pick ? pick.value : names[0]) };
}

// A canvas of css height h spanning its parent, with its drawing context in css pixels, and
// an offscreen copy (the base, drawn once) that draw(t) repaints under the time cursor
function chart(parent, h) {
  const canvas = el("canvas", { className: "chart" }, parent);
  const dpr = window.devicePixelRatio || 1;
  const w = parent.clientWidth || 300;
  canvas.style.width = `${w}px`; canvas.style.height = `${h}px`;
  canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
  const base = document.createElement("canvas");
  base.width = canvas.width; base.height = canvas.height;
  const g = base.getContext("2d");
  g.scale(dpr, dpr);
  g.font = "10px system-ui, sans-serif";
  const cursor = (x, y0, y1, text) => {
    const c = canvas.getContext("2d");
    c.setTransform(1, 0, 0, 1, 0, 0);
    c.clearRect(0, 0, canvas.width, canvas.height);
    c.drawImage(base, 0, 0);
    c.scale(dpr, dpr);
    if (x !== null) {
      c.strokeStyle = "#ffd040"; c.lineWidth = 1; c.beginPath();
      c.moveTo(x, y0); c.lineTo(x, y1); c.stroke();
    }
    if (text) {
      c.fillStyle = "#eee"; c.font = "11px system-ui, sans-serif"; c.textAlign = "left";
      c.fillText(text, 2, 10);
    }
  };
  return { canvas, g, w, h, cursor };
}

// ---- muscle activations: one row per actuator, time across, brighter = more active
function heat(v) { // activation 0..1 -> dark blue .. orange .. pale yellow
  const a = Math.min(Math.max(v, 0), 1);
  const r = Math.round(30 + 225 * Math.min(1, a * 1.4));
  const g = Math.round(35 + 200 * a * a);
  const b = Math.round(70 + 60 * (1 - a) - 40 * a);
  return `rgb(${r},${g},${b})`;
}

export function makeActivations(side, animals, fps, duration) {
  const movers = animals.filter((a) => a.activations && a.actuators.length);
  if (!movers.length) return null;
  const sec = section(side, "activations", "activations", movers.map((a) => a.name));
  const holder = el("div", {}, sec.box);
  let c = null, mover = null;
  const rowH = 11, label = 74, top = 14;
  const build = () => {
    holder.replaceChildren();
    mover = movers.find((a) => a.name === sec.who());
    const n = mover.actuators.length, frames = mover.activations.length / n;
    c = chart(holder, top + n * rowH + 2);
    const g = c.g, x0 = label, span = c.w - label;
    const cw = span / Math.max(frames, 1);
    for (let i = 0; i < frames; i++) {
      for (let j = 0; j < n; j++) {
        g.fillStyle = heat(mover.activations[i * n + j]);
        g.fillRect(x0 + i * cw, top + j * rowH, Math.ceil(cw + 0.5), rowH - 1);
      }
    }
    g.fillStyle = "#bcd"; g.textAlign = "right"; g.font = "9px system-ui, sans-serif";
    mover.actuators.forEach((name, j) => g.fillText(name.slice(0, 14), label - 3, top + j * rowH + 8));
    c.xOf = (t) => x0 + (span * t) / Math.max(duration, 1e-9);
    c.frames = frames; c.n = n;
  };
  if (sec.pick) sec.pick.onchange = () => { build(); };
  build();
  const draw = (t) => {
    const i = Math.min(Math.round(t * fps), c.frames - 1);
    let mean = 0;
    for (let j = 0; j < c.n; j++) mean += mover.activations[i * c.n + j] / c.n;
    c.cursor(c.xOf(t), top - 2, c.h, `${mover.name}: mean activation ${mean.toFixed(2)}`);
  };
  const info = () => ({ who: mover.name, actuators: c.n, frames: c.frames });
  return { draw, info };
}

// ---- the mind: a fish's intention as a coloured band, its drives as lines (0..1)
const STATE_COLORS = ["#e05a4f", "#c77dff", "#4fb0e0", "#f0a030", "#ff7eb6", "#b23a3a",
  "#7fcf6a", "#9aa4b0"];
const DRIVE_COLORS = { hunger: "#f0a030", libido: "#ff7eb6", fear: "#c77dff" };

export function makeMind(side, mind, times, duration) {
  const who = Object.keys(mind.animals || {});
  if (!who.length) return null;
  const sec = section(side, "mind", "mind", who);
  const holder = el("div", {}, sec.box);
  const legend = el("div", { className: "legend" }, sec.box);
  mind.labels.forEach((name, k) => {
    const s = el("span", { textContent: name }, legend);
    s.style.borderLeft = `8px solid ${STATE_COLORS[k % STATE_COLORS.length]}`;
  });
  for (const [d, col] of Object.entries(DRIVE_COLORS)) {
    const s = el("span", { textContent: d }, legend);
    s.style.borderBottom = `2px solid ${col}`;
  }
  let c = null, m = null;
  const top = 14, band = 12, plotTop = top + band + 4, H = 86;
  const xOf = (t) => (c.w * t) / Math.max(duration, 1e-9);
  const build = () => {
    holder.replaceChildren();
    m = mind.animals[sec.who()];
    c = chart(holder, H);
    const g = c.g;
    m.intention.forEach((code, k) => { // the band: each period's intention until the next
      if (code < 0) return;
      const x = xOf(times[k]), x1 = k + 1 < times.length ? xOf(times[k + 1]) : c.w;
      g.fillStyle = STATE_COLORS[code % STATE_COLORS.length];
      g.fillRect(x, top, Math.max(x1 - x, 1), band);
    });
    g.fillStyle = "rgba(255,255,255,0.06)"; g.fillRect(0, plotTop, c.w, H - plotTop - 2);
    const yOf = (v) => H - 3 - v * (H - plotTop - 4);
    for (const [d, values] of Object.entries(m.drives)) {
      g.strokeStyle = DRIVE_COLORS[d] || "#ddd"; g.lineWidth = 1.3; g.beginPath();
      let pen = false;
      values.forEach((v, k) => {
        if (v === null) { pen = false; return; }
        if (pen) g.lineTo(xOf(times[k]), yOf(v)); else g.moveTo(xOf(times[k]), yOf(v));
        pen = true;
      });
      g.stroke();
    }
  };
  if (sec.pick) sec.pick.onchange = build;
  build();
  const at = (t) => { // index of the last period that began by t
    let k = 0;
    while (k + 1 < times.length && times[k + 1] <= t + 1e-9) k++;
    return k;
  };
  const draw = (t) => {
    const k = at(t), code = m.intention[k];
    const drives = Object.entries(m.drives).map(([d, v]) => `${d[0]} ${v[k] === null ? "–" : v[k].toFixed(2)}`);
    c.cursor(xOf(t), top, H, `${sec.who()}: ${code >= 0 ? mind.labels[code] : "–"}  ${drives.join(" ")}`);
  };
  const info = () => ({ who: sec.who(), periods: m.intention.length, drives: Object.keys(m.drives),
    intentions: [...new Set(m.intention)].filter((k) => k >= 0).map((k) => mind.labels[k]) });
  return { draw, info };
}

// ---- a search's progress: E of each candidate (dots) and the best E so far (line)
export function makeHistory(side, history) {
  const series = history.series || {};
  const best = series.best_E, all = series.E;
  if (!best || !best.length) return null;
  const sec = section(side, "history", "E history (per evaluation)");
  const c = chart(sec.box, 90);
  const xs = history.evaluations;
  const finite = [...(all || []), ...best].filter((v) => v !== null);
  // the range of the best E and the candidates near it: one blown-up candidate's E would
  // squash the rest, so the view spans the best E's range plus as much again above it
  const bestFinite = best.filter((v) => v !== null);
  let lo = Math.min(...bestFinite), hi = Math.max(...bestFinite);
  const spread = Math.max(hi - lo, 1e-6);
  hi = Math.min(Math.max(...finite), hi + spread);
  lo -= 0.05 * spread;
  const top = 14, bottom = c.h - 12, n = xs[xs.length - 1];
  const xOf = (k) => 2 + ((c.w - 4) * (k - 1)) / Math.max(n - 1, 1);
  const yOf = (v) => bottom - ((Math.min(v, hi) - lo) / Math.max(hi - lo, 1e-9)) * (bottom - top);
  const g = c.g;
  g.fillStyle = "rgba(255,255,255,0.06)"; g.fillRect(0, top, c.w, bottom - top);
  if (all) {
    g.fillStyle = "rgba(170,190,210,0.7)";
    all.forEach((v, k) => { if (v !== null) g.fillRect(xOf(xs[k]) - 1, yOf(v) - 1, 2, 2); });
  }
  g.strokeStyle = "#7fdc6a"; g.lineWidth = 1.6; g.beginPath();
  let pen = false;
  best.forEach((v, k) => {
    if (v === null) { pen = false; return; }
    if (pen) g.lineTo(xOf(xs[k]), yOf(v)); else g.moveTo(xOf(xs[k]), yOf(v));
    pen = true;
  });
  g.stroke();
  g.fillStyle = "#9ab"; g.textAlign = "right";
  g.fillText(`E ${short(lo)} … ${short(hi)}`, c.w - 2, 10);
  g.textAlign = "left"; g.fillText("1", 2, c.h - 2);
  g.textAlign = "right"; g.fillText(`${n} evaluations`, c.w - 2, c.h - 2);
  const last = bestFinite[bestFinite.length - 1];
  const draw = () => c.cursor(null, 0, 0, `best E ${short(last)}`);
  const info = () => ({ evaluations: n, points: best.length, best: last });
  return { draw, info };
}
