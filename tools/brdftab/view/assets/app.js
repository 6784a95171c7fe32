// brdftab view: the page. State lives in the URL hash; every view is fetched from the local
// server as JSON arrays and drawn as SVG by plots.js.
"use strict";

const $ = (id) => document.getElementById(id);
// What a hash that does not name a setting means.
const DEFAULTS = { ti: 30, pi: 0, scale: "linear", ch: "y", cos: false, src: false, lt: 40, lp: 135, ev: 0, yaw: -0.7, pitch: 1.05 };
// The channels a view can show: the luminance, or a linear sRGB component (a spectrum's
// projection).
const CHANNELS = { y: "luminance Y", r: "R", g: "G", b: "B" };
const state = Object.assign({ sel: [], spec: "", on: false }, DEFAULTS);
// The settings with a slider: a hash value is clamped to its range and step.
const SLIDERS = { ti: "theta-i", pi: "phi-i", lt: "light-theta", lp: "light-phi", ev: "exposure" };
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
function clampTo(id, x) {
  const e = $(id), lo = +e.min, hi = +e.max, step = +e.step || 1;
  return Math.min(hi, Math.max(lo, lo + Math.round((x - lo) / step) * step));
}

function readHash() {
  const h = new URLSearchParams(location.hash.slice(1));
  Object.assign(state, DEFAULTS);
  const num = (k) => (h.has(k) && h.get(k).trim() !== "" && Number.isFinite(+h.get(k)) ? +h.get(k) : null);
  if (h.has("m")) {
    // Material indices only (no 0.5, no -1), each once.
    const ids = h.get("m").split(",").filter((x) => /^\d+$/.test(x)).map(Number).filter((i) => i < materials.length);
    state.sel = [...new Set(ids)].slice(0, 4);
  }
  for (const [k, id] of Object.entries(SLIDERS)) if (num(k) !== null) state[k] = clampTo(id, num(k));
  if (num("yaw") !== null) state.yaw = num("yaw");
  if (num("pitch") !== null) state.pitch = Math.min(Math.PI, Math.max(0, num("pitch")));
  if (h.has("scale")) state.scale = h.get("scale") === "log" ? "log" : "linear";
  if (h.has("ch") && Object.hasOwn(CHANNELS, h.get("ch"))) state.ch = h.get("ch");
  state.cos = h.get("cos") === "1";
  state.src = h.get("src") === "1";
  if (h.has("spec")) state.spec = h.get("spec");
  state.on = h.get("on") === "1" && state.spec !== "";
  if (state.on) state.sel = state.sel.slice(0, 3);
}

function writeHash() {
  const h = [`m=${state.sel.join(",")}`];
  for (const k of ["ti", "pi", "scale", "lt", "lp", "ev"]) h.push(`${k}=${state[k]}`);
  h.push(`yaw=${state.yaw.toFixed(2)}`, `pitch=${state.pitch.toFixed(2)}`);
  if (state.ch !== "y") h.push(`ch=${state.ch}`);
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

// Fetches one view of every entry and draws those that answered; the panel keeps the others'
// errors until its next answer (another view's success does not clear them).
async function view(name, params, draw) {
  const g = (gen[name] = (gen[name] || 0) + 1);
  const list = entries();
  const got = await Promise.all(list.map((e) => getJSON(`/api/${name}?${e.q}&${params}`)
    .then((v) => ({ e, v }), (err) => ({ e, err: `${e.label}: ${err.message || err}` }))));
  if (g !== gen[name]) return false;
  const ok = got.filter((x) => !x.err), errors = got.filter((x) => x.err).map((x) => x.err);
  document.querySelector(`.panel[data-plot="${name}"] .error`).textContent = errors.join("; ");
  draw(ok.map((x) => x.e), ok.map((x) => x.v));
  return errors.length === 0;
}

// Each shown table with its shown source, as [table, source] of a view's {e, v} items.
function withSource(items) {
  return items.filter((a) => a.e.id !== undefined && a.e.sourceOf === undefined)
    .map((a) => [a, items.find((o) => o.e.sourceOf === a.e.id)]).filter(([, b]) => b);
}

// ---- the views ----
function polarSeries() {
  const series = [];
  data.polar.forEach(({ e, v }) => {
    const y = v.y.map((f, k) => (state.cos ? f * Math.cos((v.theta_o[k] * Math.PI) / 180) : f));
    series.push({ x: v.theta_o, y, color: e.color, dash: e.dash });
  });
  // The difference of each table and its source, thin.
  for (const [a, b] of withSource(data.polar)) {
    const y = a.v.y.map((f, k) => Math.abs(f - b.v.y[k]) * (state.cos ? Math.cos((a.v.theta_o[k] * Math.PI) / 180) : 1));
    series.push({ x: a.v.theta_o, y, color: a.e.color, dash: "1 2", width: 1 });
  }
  return series;
}

// What the plots of f_r show: the chosen channel of each material's colour (RGB, or a
// spectrum projected).
const quantity = (cos) => (cos ? "f_r cos θo" : "f_r") + `, ${CHANNELS[state.ch]} (1/sr)`;

// Whether every material shown is isotropic (set from the polar answers, with the slider).
// Then φi changes nothing, and the plots are drawn at φi = 0 whatever the URL's `pi` says, as
// the disabled slider promises: the same surface, not turned.
let isotropicOnly = true;

// The φi the shown answers were computed at (the slider's until one answers), as drawn.
const answeredPhi = (items) => (isotropicOnly ? 0 : items.length ? items[0].v.phi_i : state.pi);

function drawPolar() {
  polarPlot($("polar"), polarSeries(), { log: state.scale === "log", thetaI: state.ti, phiI: answeredPhi(data.polar), label: quantity(state.cos) });
}

function drawLobe() {
  const weigh = (v, y) => y.map((f, k) => (state.cos ? f * Math.cos((v.theta_o[Math.floor(k / v.np)] * Math.PI) / 180) : f));
  const phi = (v) => (isotropicOnly ? 0 : v.phi_i);
  const lobes = data.lobe.map(({ e, v }) => ({ nt: v.nt, np: v.np, theta: v.theta_o, phi: phi(v), color: e.color, dash: e.dash, r: weigh(v, v.y) }));
  // The difference of each table and its source, thin.
  for (const [a, b] of withSource(data.lobe)) {
    const d = a.v.y.map((f, k) => Math.abs(f - b.v.y[k]));
    lobes.push({ nt: a.v.nt, np: a.v.np, theta: a.v.theta_o, phi: phi(a.v), color: a.e.color, dash: "1 2", width: 0.4, r: weigh(a.v, d) });
  }
  lobePlot($("lobe"), lobes, { yaw: state.yaw, pitch: state.pitch, log: state.scale === "log", thetaI: state.ti, phiI: answeredPhi(data.lobe), label: quantity(state.cos) });
}

// What φi is, and why it is off when every material shown is isotropic (they look the same
// from every azimuth).
const PHI_HELP = "φi: the azimuth of the plane of incidence from the material's x axis (the tangent of α_x): " +
  "the light comes from φi + 180° and reflects towards φi. It sets the polar plot's plane, the lobe's light " +
  "and the albedo curve's light; the lit sphere has its own light φ.";
function phiControl(isotropic) {
  isotropicOnly = isotropic;
  $("phi-i").disabled = isotropic;
  $("phi-i-label").title = isotropic ? "every material shown is isotropic: φi changes nothing" : PHI_HELP;
}

async function fastViews() {
  const t0 = performance.now();
  const p = view("polar", `theta_i=${state.ti}&phi_i=${state.pi}&n=180&ch=${state.ch}`, (list, got) => {
    data.polar = list.map((e, k) => ({ e, v: got[k] }));
    if (got.length) {
      const was = isotropicOnly;
      phiControl(got.every((v) => v.isotropic));
      // A lobe that answered first was drawn for the other state.
      if (was !== isotropicOnly && data.lobe.length) drawLobe();
    }
    // A mirror or refraction lobe is a delta: f_r has none of it, the albedo has it all.
    const delta = list.filter((e, k) => got[k].delta).map((e) => e.label);
    document.querySelector('.panel[data-plot="polar"] .note').textContent = delta.length
      ? `${delta.join(", ")}: the delta (mirror/refraction) lobe is not drawn; the albedo counts it` : "";
    drawPolar();
  });
  const l = view("lobe", `theta_i=${state.ti}&phi_i=${state.pi}&nt=19&np=36&ch=${state.ch}`, (list, got) => {
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
    // Each material, then its source and their difference when shown: one group each.
    const groups = [];
    list.forEach((e, k) => {
      if (e.sourceOf !== undefined) return;
      const group = [{ ...got[k], color: e.color, label: e.label }];
      groups.push(group);
      const s = e.id === undefined ? -1 : list.findIndex((o) => o.sourceOf === e.id);
      if (s < 0) return;
      group.push({ ...got[s], color: e.color, label: list[s].label });
      const diff = got[k].rgb.map((x, i) => Math.min(255, 4 * Math.abs(x - got[s].rgb[i])));
      group.push({ size, rgb: diff, color: e.color, label: "|table − source| ×4" });
    });
    spherePanel($("sphere"), groups);
  });
}

// The slice of the first selected material (a map cannot overlay); with "table vs its source",
// its relative difference to its source.
function sliceView() {
  return view("slice", `n=64&ch=${state.ch}`, (list, got) => {
    const log = state.scale === "log";
    if (!got.length || list[0].sourceOf !== undefined) return clear($("slice"));
    const a = list[0], s = a.id === undefined ? -1 : list.findIndex((o) => o.sourceOf === a.id);
    const v = got[0];
    if (s > 0) {
      // Relative to the source (floored at 1e-5 /sr): absolute differences would show only the
      // grazing row, where analytic lobes reach 1e5.
      const src = got[s].y;
      const d = v.y.map((f, k) => (f - src[k]) / Math.max(Math.abs(src[k]), 1e-5));
      heatmap($("slice"), v.n, d, { signed: true, theta: v.theta, label: `${a.label}: (table − source) / source` });
    } else heatmap($("slice"), v.n, v.y, { log, theta: v.theta, label: `${a.label}: ${quantity(false)}` });
  });
}

function albedoView() {
  return view("albedo", `phi_i=${state.pi}&ch=${state.ch}`, (list, got) => {
    const items = list.map((e, k) => ({ e, v: got[k] }));
    const series = items.map(({ e, v }) => ({ x: v.theta, y: v.y, color: e.color, dash: e.dash }));
    // The difference of each table and its source, thin.
    for (const [a, b] of withSource(items)) {
      series.push({ x: a.v.theta, y: a.v.y.map((f, k) => Math.abs(f - b.v.y[k])), color: a.e.color, dash: "1 2", width: 1 });
    }
    // An isotropic material's curve is the one of every φi (the server computes it at 0).
    const turned = items.filter((x) => !x.v.isotropic);
    const phi = turned.length ? turned[0].v.phi_i : 0;
    linePlot($("albedo"), series, { x0: 0, x1: 90, dx: 15, xlabel: `θ′ at φi = ${phi}° (${state.ch === "y" ? "luminance" : CHANNELS[state.ch]})` });
  });
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
// The controls showing `state` (at start and when the hash changes).
function syncControls() {
  for (const [k, id] of Object.entries(SLIDERS)) $(id).value = state[k];
  $("theta-i-val").textContent = `${state.ti}°`;
  $("phi-i-val").textContent = `${state.pi}°`;
  $("scale").value = state.scale;
  $("channel").value = state.ch;
  $("cosine").checked = state.cos;
  $("vs-source").checked = state.src;
  $("spec-on").checked = state.on;
}

function bind() {
  syncControls();
  phiControl(true);
  const range = (id, key, fast) => {
    $(id).addEventListener("input", () => { state[key] = +$(id).value; writeHash(); fast(true); });
    $(id).addEventListener("change", () => fast(false));
  };
  range("theta-i", "ti", () => { $("theta-i-val").textContent = `${state.ti}°`; fastViews(); });
  // φi: the polar plot and the lobe as it moves, the albedo curve (slow) once it rests.
  let albedoTimer = null;
  range("phi-i", "pi", () => {
    $("phi-i-val").textContent = `${state.pi}°`;
    fastViews();
    clearTimeout(albedoTimer);
    albedoTimer = setTimeout(albedoView, 300);
  });
  range("light-theta", "lt", (drag) => sphereView(drag ? 48 : 128));
  range("light-phi", "lp", (drag) => sphereView(drag ? 48 : 128));
  range("exposure", "ev", (drag) => sphereView(drag ? 48 : 128));
  $("scale").addEventListener("change", () => { state.scale = $("scale").value; writeHash(); drawPolar(); drawLobe(); sliceView(); });
  $("channel").addEventListener("change", () => { state.ch = $("channel").value; writeHash(); fastViews(); sliceView(); albedoView(); });
  $("cosine").addEventListener("change", () => { state.cos = $("cosine").checked; writeHash(); drawPolar(); drawLobe(); });
  $("vs-source").addEventListener("change", () => { state.src = $("vs-source").checked; redrawAll(); });
  $("spec-on").addEventListener("change", () => {
    // Four curves at most: with four materials selected the spec waits for a free place
    // rather than dropping one of them unasked.
    if ($("spec-on").checked && state.sel.length >= 4) {
      $("spec-on").checked = false;
      $("spec-error").textContent = "four curves at most: deselect a material to show the spec";
      return;
    }
    state.on = $("spec-on").checked && state.spec !== "";
    redrawAll();
  });
  $("model").addEventListener("change", () => {
    const m = models.find((x) => x.name === $("model").value);
    loadSpec(m.example);
    $("spec-error").textContent = "";
    specChanged(JSON.parse(state.spec));
  });
  $("spec-json").addEventListener("input", () => {
    const s = parseSpec($("spec-json").value);
    if (!s) {
      let json = true;
      try { JSON.parse($("spec-json").value); } catch { json = false; }
      $("spec-error").textContent = json ? 'a spec is a JSON object: {"model": ...}' : "not JSON yet";
      return;
    }
    $("spec-error").textContent = "";
    state.spec = JSON.stringify(s);
    buildParams(s);
    specChanged(s);
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
    panel.appendChild(Object.assign(document.createElement("p"), { className: "error" }));
    panel.appendChild(Object.assign(document.createElement("p"), { className: "note" }));
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
  // A URL's spec that is not one (`spec=null`, which the editor used to write) is dropped:
  // it stopped the page before it drew anything.
  if (!loadSpec(state.spec)) {
    state.on = false;
    loadSpec(models.find((m) => m.name === "cook_torrance").example);
  }
  bind();
  redrawAll();
  window.addEventListener("hashchange", () => {
    readHash();
    syncControls();
    if (state.spec && state.spec !== $("spec-json").value) loadSpec(state.spec);
    redrawAll();
  });
}

main();
