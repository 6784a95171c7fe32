// brdftab view: the analytic spec editor. A slider per numeric parameter of the model (from
// /api/models), a choice per enumerated one; every move re-evaluates the spec on the server
// (it is sent inline: the only SOURCE the page may send).
"use strict";

const FRESNEL = ['"none"', '{"conductor":"Au"}', '{"conductor":"Ag"}', '{"conductor":"Cu"}', '{"conductor":"Al"}', '{"eta":1.5}', '{"schlick":0.04}'];

function sliderRange(name, kind) {
  if (kind === "radians") return { min: 0, max: 1.5, log: false };
  if (name === "n") return { min: 0, max: 4, log: true };
  if (/^(m|alpha)/.test(name)) return { min: 0.005, max: 1, log: false };
  if (name === "eta") return { min: 1, max: 3, log: false };
  return { min: 0, max: 1, log: false };
}

function loadSpec(json) {
  let spec;
  try { spec = JSON.parse(json); } catch { return; }
  state.spec = JSON.stringify(spec);
  $("spec-json").value = state.spec;
  $("model").value = spec.model;
  buildParams(spec);
}

function buildParams(spec) {
  const box = $("params");
  box.innerHTML = "";
  const info = models.find((m) => m.name === spec.model);
  if (!info) return;
  for (const p of info.params) {
    const label = document.createElement("label");
    label.textContent = p.name;
    if (["number", "radians", "value"].includes(p.kind)) {
      const r = sliderRange(p.name, p.kind);
      let v = spec[p.name];
      if (Array.isArray(v)) v = v[0];
      if (typeof v !== "number") v = p.default !== null && Number.isFinite(+p.default) ? +p.default : r.min;
      const input = Object.assign(document.createElement("input"), { type: "range", min: r.min, max: r.max, step: (r.max - r.min) / 400 });
      input.value = r.log ? Math.log10(Math.max(v, 1)) : v;
      const out = document.createElement("span");
      out.textContent = (+v).toPrecision(3);
      input.addEventListener("input", () => {
        const x = r.log ? Math.round(Math.pow(10, +input.value)) : +input.value;
        out.textContent = x.toPrecision(3);
        specChanged(Object.assign(JSON.parse(state.spec), { [p.name]: x }));
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

function specChanged(spec) {
  state.spec = JSON.stringify(spec);
  $("spec-json").value = state.spec;
  writeHash();
  if (!state.on) return;
  fastViews();
  sphereView(64);
  slowViews(300);
}

