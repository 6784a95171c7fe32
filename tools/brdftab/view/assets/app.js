// brdftab view: the page. State lives in the URL hash; every view is fetched from the local
// server as JSON arrays and drawn as SVG by plots.js.
"use strict";

const $ = (id) => document.getElementById(id);
const state = { sel: [], ti: 30, scale: "linear", cos: false, src: false, lt: 40, lp: 135, ev: 0, spec: "", on: false, yaw: -0.7, pitch: 1.05 };
let materials = [], models = [];
const gen = {}; // newest request per view: older answers are dropped
const data = { polar: [], lobe: [] };

async function getJSON(path) {
  const r = await fetch(path);
  const v = await r.json();
  if (!r.ok) throw new Error(v.error || r.statusText);
  return v;
}

// ---- the URL hash ----
function readHash() {
  const h = new URLSearchParams(location.hash.slice(1));
  if (h.get("m")) state.sel = h.get("m").split(",").map(Number).filter((i) => i >= 0 && i < materials.length).slice(0, 4);
  for (const k of ["ti", "lt", "lp", "ev", "yaw", "pitch"]) if (h.has(k) && Number.isFinite(+h.get(k))) state[k] = +h.get(k);
  if (h.has("scale")) state.scale = h.get("scale") === "log" ? "log" : "linear";
  state.cos = h.get("cos") === "1";
  state.src = h.get("src") === "1";
  if (h.has("spec")) state.spec = h.get("spec");
  state.on = h.get("on") === "1" && state.spec !== "";
  if (state.on) state.sel = state.sel.slice(0, 3);
}

function writeHash() {
  const h = [`m=${state.sel.join(",")}`];
  for (const k of ["ti", "scale", "lt", "lp", "ev"]) h.push(`${k}=${state[k]}`);
  h.push(`yaw=${state.yaw.toFixed(2)}`, `pitch=${state.pitch.toFixed(2)}`);
  if (state.cos) h.push("cos=1");
  if (state.src) h.push("src=1");
  if (state.spec) h.push("spec=" + encodeURIComponent(state.spec));
  if (state.on) h.push("on=1");
  history.replaceState(null, "", "#" + h.join("&"));
}

// ---- what is drawn: the selected materials, their sources, the spec ----
function entries() {
  const out = [];
  state.sel.forEach((id, k) => {
    const m = materials[id];
    out.push({ q: `m=${id}`, label: m.name, color: COLORS[k], id });
    if (state.src && m.has_source) out.push({ q: `m=${id}&of=source`, label: `${m.name} (source)`, color: COLORS[k], dash: "5 3", sourceOf: id });
  });
  if (state.on && state.spec) out.push({ q: "spec=" + encodeURIComponent(state.spec), label: "spec", color: "#7f3fbf", spec: true });
  return out;
}

async function view(name, params, draw) {
  const g = (gen[name] = (gen[name] || 0) + 1);
  const list = entries();
  try {
    const got = await Promise.all(list.map((e) => getJSON(`/api/${name}?${e.q}&${params}`)));
    if (g !== gen[name]) return false;
    draw(list, got);
    $("spec-error").textContent = "";
    return true;
  } catch (err) {
    if (g === gen[name]) $("spec-error").textContent = String(err.message || err);
    return false;
  }
}

// ---- the views ----
function polarSeries() {
  const series = [];
  data.polar.forEach(({ e, v }) => {
    const y = v.y.map((f, k) => (state.cos ? f * Math.cos((v.theta_o[k] * Math.PI) / 180) : f));
    series.push({ x: v.theta_o, y, color: e.color, dash: e.dash });
  });
  // The difference of each table and its source, thin.
  for (const a of data.polar) {
    if (a.e.id === undefined || a.e.sourceOf !== undefined) continue;
    const b = data.polar.find((o) => o.e.sourceOf === a.e.id);
    if (!b) continue;
    const y = a.v.y.map((f, k) => Math.abs(f - b.v.y[k]) * (state.cos ? Math.cos((a.v.theta_o[k] * Math.PI) / 180) : 1));
    series.push({ x: a.v.theta_o, y, color: a.e.color, dash: "1 2", width: 1 });
  }
  return series;
}

function drawPolar() {
  polarPlot($("polar"), polarSeries(), { log: state.scale === "log", thetaI: state.ti, label: state.cos ? "f_r cos θo" : "f_r (1/sr)" });
}

function drawLobe() {
  lobePlot($("lobe"), data.lobe.map(({ e, v }) => ({
    nt: v.nt, np: v.np, color: e.color, dash: e.dash,
    r: v.y.map((f, k) => {
      const t = (Math.PI / 2) * Math.floor(k / v.np) / (v.nt - 1);
      return state.cos ? f * Math.cos(t) : f;
    }),
  })), { yaw: state.yaw, pitch: state.pitch, log: state.scale === "log" });
}

async function fastViews() {
  const t0 = performance.now();
  const p = view("polar", `theta_i=${state.ti}&n=181`, (list, got) => {
    data.polar = list.map((e, k) => ({ e, v: got[k] }));
    drawPolar();
  });
  const l = view("lobe", `theta_i=${state.ti}&nt=19&np=36`, (list, got) => {
    data.lobe = list.map((e, k) => ({ e, v: got[k] }));
    drawLobe();
  });
  const [ok] = await Promise.all([p, l]);
  if (ok) {
    const ms = performance.now() - t0;
    window.brdftabRedrawMs = ms;
    $("timing").textContent = `redraw ${ms.toFixed(0)} ms`;
  }
}

function sphereView(size) {
  const q = `lt=${state.lt}&lp=${state.lp}&size=${size}&exposure=${Math.pow(2, state.ev)}`;
  return view("sphere", q, (list, got) => {
    // Each material, then its source and their difference when shown.
    const images = [];
    list.forEach((e, k) => {
      if (e.sourceOf !== undefined) return;
      images.push({ ...got[k], color: e.color, label: e.label });
      const s = e.id === undefined ? -1 : list.findIndex((o) => o.sourceOf === e.id);
      if (s < 0) return;
      images.push({ ...got[s], color: e.color, label: list[s].label });
      const diff = got[k].rgb.map((x, i) => Math.min(255, 4 * Math.abs(x - got[s].rgb[i])));
      images.push({ size, rgb: diff, color: e.color, label: "|table − source| ×4" });
    });
    spherePanel($("sphere"), images.slice(0, 6));
  });
}

function sliceView() {
  return view("slice", "n=64", (list, got) => {
    const log = state.scale === "log";
    if (!got.length) return clear($("slice"));
    const a = list[0], s = a.id === undefined ? -1 : list.findIndex((o) => o.sourceOf === a.id);
    if (s > 0) {
      // Relative to the source (floored at 1e-5 /sr): absolute differences would show only the
      // grazing row, where analytic lobes reach 1e5.
      const src = got[s].y;
      const d = got[0].y.map((v, k) => (v - src[k]) / Math.max(Math.abs(src[k]), 1e-5));
      heatmap($("slice"), got[0].n, d, { signed: true, label: `${a.label}: (table − source) / source` });
    } else heatmap($("slice"), got[0].n, got[0].y, { log, label: a.label });
  });
}

function albedoView() {
  return view("albedo", "", (list, got) => {
    const series = got.map((v, k) => ({ x: v.theta, y: v.y, color: list[k].color, dash: list[k].dash }));
    linePlot($("albedo"), series, { x0: 0, x1: 90, dx: 15, xlabel: "θ′ (luminance)" });
  });
}

async function report() {
  const list = entries().filter((e) => e.sourceOf === undefined);
  const rows = await Promise.all(list.map(async (e) => {
    const p = await getJSON(`/api/plausibility?${e.q}`).catch(() => null);
    const m = e.id !== undefined && materials[e.id].has_source ? await getJSON(`/api/compare?m=${e.id}`).catch(() => null) : null;
    return { e, p, m };
  }));
  // Built as DOM nodes, not HTML text: the page's CSP allows no inline style attributes.
  const table = document.createElement("table");
  const row = (cells, head) => {
    const tr = table.insertRow();
    for (const c of cells) {
      const td = document.createElement(head ? "th" : "td");
      if (typeof c === "string") td.textContent = c;
      else { td.textContent = c.text; if (c.cls) td.className = c.cls; if (c.color) td.style.color = c.color; }
      tr.appendChild(td);
    }
  };
  const yn = (b, x) => ({ text: (b ? "yes" : "no") + (x ? ` (${x})` : ""), cls: b ? "ok" : "bad" });
  row(["", "positive", "reciprocal", "energy (max a)", "cos-weighted err", "albedo err"], true);
  for (const { e, p, m } of rows) {
    const cells = [{ text: e.label, color: e.color }];
    if (p) cells.push(yn(p.positive), yn(p.reciprocal, p.max_reciprocity_error.toExponential(1)), yn(p.energy_conserving, p.max_albedo.toFixed(3)));
    else cells.push("…", "…", "…");
    if (m && !m.error) cells.push(`${(100 * m.rel_rmse).toFixed(3)} %`, `${(100 * m.albedo_err).toFixed(3)} %`);
    else cells.push("–", "–");
    row(cells);
  }
  $("report").replaceChildren(table);
}

function escapeHtml(s) {
  return s.replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}

let slowTimer = null;
function slowViews(delay) {
  clearTimeout(slowTimer);
  slowTimer = setTimeout(() => { sliceView(); albedoView(); report(); }, delay || 0);
}

function redrawAll() {
  writeHash();
  renderList();
  fastViews();
  sphereView(128);
  slowViews(0);
}

// ---- controls ----
function bind() {
  const range = (id, key, fast) => {
    $(id).value = state[key];
    $(id).addEventListener("input", () => { state[key] = +$(id).value; writeHash(); fast(true); });
    $(id).addEventListener("change", () => fast(false));
  };
  range("theta-i", "ti", () => { $("theta-i-val").textContent = `${state.ti}°`; fastViews(); });
  range("light-theta", "lt", (drag) => sphereView(drag ? 48 : 128));
  range("light-phi", "lp", (drag) => sphereView(drag ? 48 : 128));
  range("exposure", "ev", (drag) => sphereView(drag ? 48 : 128));
  $("theta-i-val").textContent = `${state.ti}°`;
  $("scale").value = state.scale;
  $("scale").addEventListener("change", () => { state.scale = $("scale").value; writeHash(); drawPolar(); drawLobe(); sliceView(); });
  $("cosine").checked = state.cos;
  $("cosine").addEventListener("change", () => { state.cos = $("cosine").checked; writeHash(); drawPolar(); drawLobe(); });
  $("vs-source").checked = state.src;
  $("vs-source").addEventListener("change", () => { state.src = $("vs-source").checked; redrawAll(); });
  $("spec-on").checked = state.on;
  $("spec-on").addEventListener("change", () => {
    state.on = $("spec-on").checked && state.spec !== "";
    if (state.on) state.sel = state.sel.slice(0, 3); // four curves at most
    redrawAll();
  });
  $("model").addEventListener("change", () => {
    const m = models.find((x) => x.name === $("model").value);
    loadSpec(m.example);
    specChanged(JSON.parse(state.spec));
  });
  $("spec-json").addEventListener("input", () => {
    try { const s = JSON.parse($("spec-json").value); state.spec = JSON.stringify(s); buildParams(s); specChanged(s); }
    catch { $("spec-error").textContent = "not JSON yet"; }
  });
  // Drag on the lobe rotates it; drag on the sphere moves the light.
  drag($("lobe"), (dx, dy) => { state.yaw += dx * 0.01; state.pitch = Math.min(Math.PI, Math.max(0, state.pitch + dy * 0.01)); drawLobe(); }, writeHash);
  drag($("sphere"), (dx, dy) => {
    state.lp = Math.round(((state.lp + dx + 540) % 360) - 180);
    state.lt = Math.min(90, Math.max(0, state.lt + dy * 0.5));
    $("light-theta").value = state.lt; $("light-phi").value = state.lp;
    sphereView(48);
  }, () => { writeHash(); sphereView(128); });
  for (const panel of document.querySelectorAll(".panel[data-plot]")) {
    addDownloads(panel, panel.querySelector("svg"), "brdftab-" + panel.dataset.plot);
  }
}

function drag(target, move, end) {
  let last = null;
  target.addEventListener("pointerdown", (e) => { last = [e.clientX, e.clientY]; target.setPointerCapture(e.pointerId); });
  target.addEventListener("pointermove", (e) => {
    if (!last) return;
    move(e.clientX - last[0], e.clientY - last[1]);
    last = [e.clientX, e.clientY];
  });
  target.addEventListener("pointerup", () => { last = null; end(); });
}

async function main() {
  [materials, models] = await Promise.all([getJSON("/api/materials"), getJSON("/api/models")]);
  for (const m of models) $("model").add(new Option(m.name, m.name));
  readHash();
  if (!location.hash) state.sel = [0];
  loadSpec(state.spec || models.find((m) => m.name === "cook_torrance").example);
  bind();
  redrawAll();
  window.addEventListener("hashchange", () => { readHash(); redrawAll(); });
}

main();
