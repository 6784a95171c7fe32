// brdftab view: the analytic spec editor. A slider per numeric parameter of the model (from
// /api/models), a choice per enumerated one; every move re-evaluates the spec on the server
// (it is sent inline: the only SOURCE the page may send).
"use strict";

const FRESNEL = ['"none"', '{"conductor":"Au"}', '{"conductor":"Ag"}', '{"conductor":"Cu"}', '{"conductor":"Al"}', '{"eta":1.5}', '{"schlick":0.04}'];

// Parameters a model takes one way or the other (its catalogue `rule`): the spec's way gets
// sliders, and a choice switches ways, so no slider makes a spec the model refuses.
const WAYS = { ggx: [{ label: "isotropic", params: ["alpha"] }, { label: "anisotropic", params: ["alpha_x", "alpha_y"] }] };

function sliderRange(name, kind) {
  if (kind === "radians") return { min: 0, max: 1.5, log: false };
  if (name === "n") return { min: 0, max: 4, log: true };
  if (/^(m|alpha)/.test(name)) return { min: 0.005, max: 1, log: false };
  if (name === "eta") return { min: 1, max: 3, log: false };
  return { min: 0, max: 1, log: false };
}

// The spec `json` holds if it is a JSON object, else null: `null`, `1` or `"x"` is JSON but
// not a spec.
function parseSpec(json) {
  try {
    const s = JSON.parse(json);
    return s !== null && typeof s === "object" && !Array.isArray(s) ? s : null;
  } catch { return null; }
}

// Shows spec `json` in the editor; false (and nothing changed) if it is not a spec.
function loadSpec(json) {
  const spec = parseSpec(json);
  if (!spec) return false;
  state.spec = JSON.stringify(spec);
  $("spec-json").value = state.spec;
  $("model").value = spec.model;
  buildParams(spec);
  return true;
}

function buildParams(spec) {
  const box = $("params");
  box.innerHTML = "";
  const info = models.find((m) => m.name === spec.model);
  if (!info) return;
  const ways = WAYS[spec.model] || [];
  const way = Math.max(0, ways.findIndex((w) => w.params.some((n) => spec[n] !== undefined)));
  const hidden = ways.filter((_, k) => k !== way).flatMap((w) => w.params);
  if (ways.length) box.appendChild(wayChoice(spec, ways, way));
  for (const p of info.params) {
    if (hidden.includes(p.name)) continue;
    const label = document.createElement("label");
    label.textContent = p.name;
    if (["number", "radians", "value"].includes(p.kind)) {
      const r = sliderRange(p.name, p.kind);
      // A colour (an RGB triple) keeps its hue: the slider sets its largest component and
      // scales the others with it (it used to set the value to a grey of its first).
      const rgb = Array.isArray(spec[p.name]) && spec[p.name].every(Number.isFinite) ? spec[p.name] : null;
      const top = rgb ? Math.max(...rgb) : 0;
      let v = rgb ? top : spec[p.name];
      if (typeof v !== "number") v = p.default !== null && Number.isFinite(+p.default) ? +p.default : r.min;
      const input = Object.assign(document.createElement("input"), { type: "range", min: r.min, max: r.max, step: (r.max - r.min) / 400 });
      input.value = r.log ? Math.log10(Math.max(v, 1)) : v;
      const out = document.createElement("span");
      out.textContent = (+v).toPrecision(3);
      input.addEventListener("input", () => {
        const x = r.log ? Math.round(Math.pow(10, +input.value)) : +input.value;
        out.textContent = x.toPrecision(3);
        const value = rgb && top > 0 ? rgb.map((c) => (c * x) / top) : x;
        specChanged(Object.assign(JSON.parse(state.spec), { [p.name]: value }));
      });
      label.append(input, out);
    } else if (p.kind === "fresnel" || (p.kind && p.kind.choice)) {
      const sel = document.createElement("select");
      const options = p.kind === "fresnel" ? FRESNEL : p.kind.choice.map((c) => JSON.stringify(c));
      const cur = JSON.stringify(spec[p.name] === undefined ? JSON.parse(options[0]) : spec[p.name]);
      for (const o of options.includes(cur) ? options : [cur, ...options]) sel.add(new Option(o, o, false, o === cur));
      sel.addEventListener("change", () => specChanged(Object.assign(JSON.parse(state.spec), { [p.name]: JSON.parse(sel.value) })));
      label.append(sel);
    } else continue;
    box.appendChild(label);
  }
}

// The choice between a model's ways: switching carries the first value over to every
// parameter of the other way (alpha 0.2 becomes alpha_x = alpha_y = 0.2).
function wayChoice(spec, ways, way) {
  const label = document.createElement("label");
  label.textContent = "lobe";
  const sel = document.createElement("select");
  ways.forEach((w, k) => sel.add(new Option(`${w.label} (${w.params.join(", ")})`, k, false, k === way)));
  sel.addEventListener("change", () => {
    const next = JSON.parse(state.spec);
    const v = ways[way].params.map((n) => next[n]).find((x) => typeof x === "number") ?? 0.1;
    for (const w of ways) for (const n of w.params) delete next[n];
    for (const n of ways[+sel.value].params) next[n] = v;
    buildParams(next);
    specChanged(next);
  });
  label.append(sel);
  return label;
}

function specChanged(spec) {
  state.spec = JSON.stringify(spec);
  $("spec-json").value = state.spec;
  writeHash();
  if (!state.on) return;
  fastViews();
  sphereView(64);
  slowViews(300);
}

