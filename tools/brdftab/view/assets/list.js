// brdftab view: the material list (thumbnails, what each material is) and the selection.
"use strict";

function renderList() {
  const ul = $("materials");
  if (!ul.children.length) {
    materials.forEach((m) => {
      const li = document.createElement("li");
      li.dataset.id = m.id;
      const c = document.createElement("canvas");
      c.width = c.height = 48;
      const meta = document.createElement("div");
      meta.className = "meta";
      const kb = m.bytes !== undefined ? `${(m.bytes / 1024).toFixed(1)} KiB, ${m.ratio.toFixed(1)}× vs f32, ${m.codec.quant}` : "";
      meta.innerHTML = `<div class="name">${escapeHtml(m.name)}</div>${m.kind} · ${m.channels.join(" ")}` +
        (m.grid ? `<br>${escapeHtml(m.grid)}<br>${kb}` : "") + (m.has_source ? "<br>source: opens" : "") +
        (m.source_note ? `<br>source: not paired, ${escapeHtml(m.source_note)}` : "") +
        (m.delta ? "<br>delta lobe: not in the plots, in the albedo" : "");
      li.append(c, meta);
      li.addEventListener("click", () => toggle(m.id));
      ul.appendChild(li);
    });
    thumbnails();
  }
  for (const li of ul.children) {
    const k = state.sel.indexOf(+li.dataset.id);
    li.classList.toggle("selected", k >= 0);
    li.style.borderLeftColor = k >= 0 ? COLORS[k] : "transparent";
  }
}

async function thumbnails() {
  for (const m of materials) {
    const v = await getJSON(`/api/sphere?m=${m.id}&size=48&lt=40&lp=135`).catch(() => null);
    if (!v) continue;
    const c = document.querySelector(`#materials li[data-id="${m.id}"] canvas`);
    const img = new ImageData(v.size, v.size);
    for (let p = 0; p < v.size * v.size; p++) img.data.set([v.rgb[3 * p], v.rgb[3 * p + 1], v.rgb[3 * p + 2], 255], 4 * p);
    c.getContext("2d").putImageData(img, 0, 0);
  }
}

function toggle(id) {
  const k = state.sel.indexOf(id);
  if (k >= 0) state.sel.splice(k, 1);
  else if (state.sel.length + (state.on ? 1 : 0) < 4) state.sel.push(id);
  const m = materials[id];
  if (k < 0 && m.spec) loadSpec(JSON.stringify(m.spec));
  redrawAll();
}

function escapeHtml(s) {
  return s.replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}
