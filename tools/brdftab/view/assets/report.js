// brdftab view: the plausibility and error table of the shown materials (positive,
// reciprocal, energy; against a table's source, the error figures).
"use strict";

// The newest report asked for: an older one that answers later (its figures took seconds to
// compute) is dropped, or it would show materials no longer selected.
let reportGen = 0;

async function report() {
  const g = ++reportGen;
  const list = entries().filter((e) => e.sourceOf === undefined);
  const rows = await Promise.all(list.map(async (e) => {
    const p = await getJSON(`/api/plausibility?${e.q}`).catch(() => null);
    const m = e.id !== undefined && materials[e.id].has_source ? await getJSON(`/api/compare?m=${e.id}`).catch(() => null) : null;
    return { e, p, m };
  }));
  if (g !== reportGen) return;
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
