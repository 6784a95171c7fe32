// Plot drawing for brdftab view: every plot is an SVG built here, so it downloads as SVG as
// it is and as PNG through a canvas. No library, no network.
"use strict";

const SVGNS = "http://www.w3.org/2000/svg";
const COLORS = ["#d62728", "#2ca02c", "#1f77b4", "#ff7f0e"];

function el(name, attrs, parent) {
  const e = document.createElementNS(SVGNS, name);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

function text(parent, x, y, s, attrs) {
  const t = el("text", Object.assign({ x, y, "font-size": 10, fill: "#444" }, attrs || {}), parent);
  t.textContent = s;
  return t;
}

function clear(svg) {
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  el("rect", { x: 0, y: 0, width: "100%", height: "100%", fill: "#fff" }, svg);
}

// A value mapped to [0, 1] on the plot's scale: linear against max, or log over 4 decades;
// values above the scale are clipped at 1.
function scaler(max, log) {
  if (log) return (v) => (v > 0 ? Math.min(1, Math.max(0, 1 + Math.log10(v / max) / 4)) : 0);
  return (v) => Math.min(1, Math.max(0, v / max));
}

// Plots are scaled by their samples within SCALE_DEG of the normal (or up to θi when the light
// is lower): measured data rise like 1/cos θ towards the horizon, where they are extrapolated
// (the error figures leave that band out too), and a few grazing samples would make the rest of
// the plot invisible. Samples beyond the scale are clipped, and the plot says how many.
const SCALE_DEG = 80;

// The scale of `series` ({x: angle, y: value}) counting the samples `keep(x)` accepts: {max,
// top: the largest of all, clipped: how many exceed max}.
function robustScale(series, keep) {
  let max = 0, top = 0, clipped = 0;
  for (const s of series) s.y.forEach((v, k) => {
    if (!Number.isFinite(v)) return;
    top = Math.max(top, Math.abs(v));
    if (keep(s.x[k])) max = Math.max(max, Math.abs(v));
  });
  if (!(max > 0)) max = top > 0 ? top : 1;
  for (const s of series) for (const v of s.y) if (Math.abs(v) > max) clipped++;
  return { max, top, clipped };
}

function scaleNote(sc, what, sign) {
  const note = `scale ${sign || ""}${sc.max.toPrecision(3)}`;
  return sc.clipped ? `${note}; ${sc.clipped} ${what} clipped, up to ${sc.top.toPrecision(3)}` : note;
}

function seriesMax(series) {
  let m = 0;
  for (const s of series) for (const v of s.y) if (Number.isFinite(v)) m = Math.max(m, Math.abs(v));
  return m > 0 ? m : 1;
}

// The in-plane polar plot: θo from −90° to 90° around the normal (up), radius = value.
function polarPlot(svg, series, opts) {
  clear(svg);
  const cx = 210, cy = 220, R = 195;
  const keep = (t) => Math.abs(t) <= Math.max(SCALE_DEG, opts.thetaI);
  const sc = robustScale(series, keep), s = scaler(sc.max, opts.log);
  // Each ring says its value: a quarter of the scale apart, or a decade apart on the log scale.
  for (const f of [0.25, 0.5, 0.75, 1]) {
    el("path", { d: `M${cx - R * f},${cy} A${R * f},${R * f} 0 0 1 ${cx + R * f},${cy}`, fill: "none", stroke: "#ddd" }, svg);
    const v = opts.log ? sc.max * Math.pow(10, 4 * (f - 1)) : sc.max * f;
    text(svg, cx + R * f - 10, cy + 12, v >= 0.01 && v < 1e4 ? v.toPrecision(2) : v.toExponential(1), { "font-size": 8, class: "ring" });
  }
  for (let a = -90; a <= 90; a += 30) {
    const r = (a * Math.PI) / 180;
    el("line", { x1: cx, y1: cy, x2: cx + R * Math.sin(r), y2: cy - R * Math.cos(r), stroke: "#eee" }, svg);
    text(svg, cx + (R + 8) * Math.sin(r) - 8, cy - (R + 4) * Math.cos(r), `${a}°`);
  }
  const ti = (opts.thetaI * Math.PI) / 180;
  el("line", { x1: cx, y1: cy, x2: cx - R * Math.sin(ti), y2: cy - R * Math.cos(ti), stroke: "#999", "stroke-dasharray": "4 3" }, svg);
  text(svg, 4, 12, (opts.log ? "log, " : "") + scaleNote(sc, "grazing samples"));
  text(svg, 4, 24, opts.label);
  // Which plane this is: the plane of incidence at φi, the light on the left.
  if (opts.phiI !== undefined) {
    const light = opts.phiI + 180 > 180 ? opts.phiI - 180 : opts.phiI + 180;
    text(svg, 4, 236, `plane φi = ${opts.phiI}° (light from ${light}°)`, { class: "plane" });
  }
  for (const ser of series) {
    const pts = ser.x.map((t, k) => {
      const r = (t * Math.PI) / 180, v = R * s(ser.y[k]);
      return `${(cx + v * Math.sin(r)).toFixed(1)},${(cy - v * Math.cos(r)).toFixed(1)}`;
    });
    el("polyline", { points: pts.join(" "), fill: "none", stroke: ser.color, "stroke-width": ser.width || 1.5, "stroke-dasharray": ser.dash || "" }, svg);
    // Clipped samples: a ring on the rim.
    ser.x.forEach((t, k) => {
      if (!(Math.abs(ser.y[k]) > sc.max)) return;
      const r = (t * Math.PI) / 180;
      el("circle", { cx: cx + R * Math.sin(r), cy: cy - R * Math.cos(r), r: 2.5, fill: "none", stroke: ser.color }, svg);
    });
  }
}

// A curve plot over x (albedo against θ′).
function linePlot(svg, series, opts) {
  clear(svg);
  const L = 40, T = 10, W = 370, H = 200;
  const ymax = opts.ymax || seriesMax(series) * 1.05;
  el("rect", { x: L, y: T, width: W, height: H, fill: "none", stroke: "#999" }, svg);
  const X = (x) => L + (W * (x - opts.x0)) / (opts.x1 - opts.x0);
  const Y = (y) => T + H - (H * y) / ymax;
  for (let k = 0; k <= 4; k++) {
    const y = (ymax * k) / 4;
    el("line", { x1: L, x2: L + W, y1: Y(y), y2: Y(y), stroke: "#eee" }, svg);
    text(svg, 2, Y(y) + 3, y.toPrecision(2));
  }
  for (let x = opts.x0; x <= opts.x1; x += opts.dx) text(svg, X(x) - 6, T + H + 12, `${x}°`);
  text(svg, L + W, T + H + 26, opts.xlabel, { "text-anchor": "end" });
  for (const ser of series) {
    const pts = ser.x.map((x, k) => `${X(x).toFixed(1)},${Y(ser.y[k]).toFixed(1)}`);
    el("polyline", { points: pts.join(" "), fill: "none", stroke: ser.color, "stroke-width": ser.width || 1.5, "stroke-dasharray": ser.dash || "" }, svg);
  }
}

// Viridis-like colour ramp for t in [0, 1].
function ramp(t) {
  const stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  t = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(t)), f = t - i;
  const c = stops[i].map((a, k) => Math.round(a + f * (stops[i + 1][k] - a)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

// An n × n map (row = θd, column = θh) as rectangles; signed data uses a red/blue ramp.
function heatmap(svg, n, y, opts) {
  clear(svg);
  const S = 200, L = 34, T = 6, cell = S / n;
  // The cells that set the scale: both directions within SCALE_DEG of the normal (at φd = 90°
  // both make cos θ = cos θh cos θd with it). Signed maps (differences) scale by the 99th
  // percentile of those, so a few cells where the source is tiny do not wash the rest out;
  // others by their maximum.
  const c = (t) => Math.cos((t * Math.PI) / 180), cut = c(SCALE_DEG);
  const mags = y.filter((v, k) => Number.isFinite(v) && v !== 0 && c(opts.theta[k % n]) * c(opts.theta[Math.floor(k / n)]) >= cut)
    .map(Math.abs).sort((a, b) => a - b);
  const max = (opts.signed ? mags[Math.floor(0.99 * (mags.length - 1))] : mags[mags.length - 1]) || 1;
  const s = scaler(max, opts.log);
  const all = y.filter(Number.isFinite).map(Math.abs);
  const sc = { max, top: all.reduce((a, b) => Math.max(a, b), 0), clipped: all.filter((v) => v > max).length };
  const g = el("g", { "shape-rendering": "crispEdges" }, svg);
  for (let d = 0; d < n; d++) {
    for (let h = 0; h < n; h++) {
      const v = y[d * n + h];
      let fill;
      if (opts.signed) {
        const a = Math.round(255 * (1 - Math.min(1, Math.abs(v) / max)));
        fill = v >= 0 ? `rgb(255,${a},${a})` : `rgb(${a},${a},255)`;
      } else fill = ramp(s(v));
      el("rect", { x: (L + h * cell).toFixed(2), y: (T + S - (d + 1) * cell).toFixed(2), width: (cell + 0.3).toFixed(2), height: (cell + 0.3).toFixed(2), fill }, g);
    }
  }
  text(svg, L + S / 2 - 10, T + S + 12, "θh →");
  text(svg, 2, T + S / 2, "θd ↑");
  // Both axes run over [0°, 90°] (the cells' edges; `opts.theta` are their centres).
  for (const [x, y, s] of [[L - 2, T + S + 12, "0°"], [L + S - 14, T + S + 12, "90°"], [12, T + S, "0°"], [8, T + 8, "90°"]]) {
    text(svg, x, y, s, { class: "tick" });
  }
  text(svg, L, T + S + 26, opts.label);
  const [scale, clip] = scaleNote(sc, "cells", opts.signed ? "±" : "").split("; ");
  text(svg, L, T + S + 39, (opts.log ? "log, " : "") + (opts.signed ? "red +, blue −, " : "") + scale);
  if (clip) text(svg, L, T + S + 52, clip);
}

// The 3D lobe: r(θo, φo) along each outgoing direction, rotated by yaw/pitch, projected. A
// lobe's columns start at its φi (`l.phi`, degrees from x): the light is at φi + 180°, dashed.
function lobePlot(svg, lobes, view) {
  clear(svg);
  const cx = 160, cy = 150, R = 120;
  const keep = (t) => t <= Math.max(SCALE_DEG, view.thetaI);
  const sc = robustScale(lobes.map((l) => ({ x: l.r.map((_, k) => l.theta[Math.floor(k / l.np)]), y: l.r })), keep);
  const s = scaler(sc.max, view.log);
  const cy_ = Math.cos(view.yaw), sy = Math.sin(view.yaw), cp = Math.cos(view.pitch), sp = Math.sin(view.pitch);
  const project = (x, y, z) => {
    const x1 = cy_ * x - sy * y, y1 = sy * x + cy_ * y;
    const y2 = cp * y1 - sp * z, z2 = sp * y1 + cp * z;
    return [cx + R * x1, cy - R * z2, y2];
  };
  const axis = (x, y, z, name) => {
    const [a, b] = project(0, 0, 0), [c, d] = project(x, y, z);
    el("line", { x1: a, y1: b, x2: c, y2: d, stroke: "#bbb" }, svg);
    text(svg, c, d, name);
  };
  axis(1, 0, 0, "x"); axis(0, 1, 0, "y"); axis(0, 0, 1, "n");
  if (view.phiI !== undefined) {
    const t = (view.thetaI * Math.PI) / 180, p = ((view.phiI + 180) * Math.PI) / 180;
    const [a, b] = project(0, 0, 0), [c, d] = project(Math.sin(t) * Math.cos(p), Math.sin(t) * Math.sin(p), Math.cos(t));
    el("line", { x1: a, y1: b, x2: c, y2: d, stroke: "#999", "stroke-dasharray": "4 3" }, svg);
    text(svg, c, d, "light");
  }
  text(svg, 4, 12, (view.log ? "log, " : "") + scaleNote(sc, "grazing samples"));
  if (view.label) text(svg, 4, 24, view.label);
  for (const l of lobes) {
    const pt = (i, j) => {
      const t = (l.theta[i] * Math.PI) / 180, p = ((l.phi || 0) * Math.PI) / 180 + (2 * Math.PI * j) / l.np, r = s(l.r[i * l.np + j]);
      return project(r * Math.sin(t) * Math.cos(p), r * Math.sin(t) * Math.sin(p), r * Math.cos(t));
    };
    const lines = [];
    for (let i = 0; i < l.nt; i++) {
      const row = [];
      for (let j = 0; j <= l.np; j++) row.push(pt(i, j % l.np));
      lines.push(row);
    }
    for (let j = 0; j < l.np; j += 2) {
      const col = [];
      for (let i = 0; i < l.nt; i++) col.push(pt(i, j));
      lines.push(col);
    }
    const d = lines.map((ps) => "M" + ps.map((p) => `${p[0].toFixed(1)},${p[1].toFixed(1)}`).join("L")).join("");
    el("path", { d, fill: "none", stroke: l.color, "stroke-width": l.width || 0.7, "stroke-opacity": 0.85, "stroke-dasharray": l.dash || "" }, svg);
  }
}

// Lit spheres: RGB bytes from the server, one image per entry, with a label. `groups` holds
// each material's images (itself, or itself, its source and their difference): three a row
// when every group is one image, else a row per group. The panel grows to its rows (four
// materials against their sources are twelve images; it used to show the first six).
function spherePanel(svg, groups) {
  clear(svg);
  const single = groups.every((g) => g.length === 1);
  const rows = single ? [] : groups;
  if (single) for (let k = 0; k < groups.length; k += 3) rows.push(groups.slice(k, k + 3).flat());
  svg.setAttribute("viewBox", `0 0 440 ${Math.max(2, rows.length) * 118 + 4}`);
  rows.forEach((row, r) => row.forEach((im, c) => {
    const cv = document.createElement("canvas");
    cv.width = cv.height = im.size;
    const data = new ImageData(im.size, im.size);
    for (let p = 0; p < im.size * im.size; p++) {
      data.data.set([im.rgb[3 * p], im.rgb[3 * p + 1], im.rgb[3 * p + 2], 255], 4 * p);
    }
    cv.getContext("2d").putImageData(data, 0, 0);
    const x = 4 + c * 145, y = 4 + r * 118;
    el("image", { x, y, width: 100, height: 100, href: cv.toDataURL() }, svg);
    el("rect", { x, y: y + 102, width: 100, height: 3, fill: im.color }, svg);
    text(svg, x, y + 114, im.label.slice(0, 24));
  }));
}

// Download buttons (SVG, PNG) on each plot's panel.
function addDownloads(panel, svg, name) {
  const box = document.createElement("span");
  box.className = "dl";
  for (const kind of ["SVG", "PNG"]) {
    const b = document.createElement("button");
    b.textContent = kind;
    b.addEventListener("click", () => download(svg, name, kind));
    box.appendChild(b);
  }
  panel.appendChild(box);
}

function save(url, file) {
  const a = document.createElement("a");
  a.href = url;
  a.download = file;
  a.click();
}

function download(svg, name, kind) {
  const clone = svg.cloneNode(true);
  clone.setAttribute("xmlns", SVGNS);
  const vb = svg.viewBox.baseVal;
  clone.setAttribute("width", vb.width);
  clone.setAttribute("height", vb.height);
  const blob = new Blob([new XMLSerializer().serializeToString(clone)], { type: "image/svg+xml" });
  const url = URL.createObjectURL(blob);
  if (kind === "SVG") return save(url, `${name}.svg`);
  const img = new Image();
  img.onload = () => {
    const c = document.createElement("canvas");
    c.width = vb.width * 2;
    c.height = vb.height * 2;
    const g = c.getContext("2d");
    g.scale(2, 2);
    g.drawImage(img, 0, 0);
    save(c.toDataURL("image/png"), `${name}.png`);
    URL.revokeObjectURL(url);
  };
  img.src = url;
}
