// rtlab view: frames from the server's WebSocket onto an <img>, the mouse and keys back as
// moves (tracer/viewer/server.py describes the messages). Nothing here loads from elsewhere.
"use strict";

const $ = (id) => document.getElementById(id);
const img = $("frame");
// What the tests (tests/tracer/test_viewer_browser.py) read: frames drawn, the last header,
// a hash of the last image's bytes, the error shown.
const state = { frames: 0, header: null, hash: null, error: null, stats: null, compare: null,
                sizes: [], open: false };
window.rtlab = state;

const socket = new WebSocket(`ws://${location.host}/ws`);
socket.binaryType = "arraybuffer";
const send = (message) => { if (socket.readyState === 1) socket.send(JSON.stringify(message)); };

function fnv1a(bytes) {  // FNV-1a, 32 bits: enough to tell two frames apart
  let h = 0x811c9dc5;
  for (let i = 0; i < bytes.length; i++) { h ^= bytes[i]; h = Math.imul(h, 0x01000193) >>> 0; }
  return h.toString(16);
}

const ms = (x) => `${x.toFixed(1)} ms`;

function showFrame(buffer) {
  const view = new DataView(buffer);
  const length = view.getUint32(0);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  const bytes = new Uint8Array(buffer, 4 + length);
  const url = URL.createObjectURL(new Blob([bytes], { type: `image/${header.format}` }));
  const old = img.src;
  img.onload = () => {
    if (old.startsWith("blob:")) URL.revokeObjectURL(old);
    state.frames += 1;
    state.header = header;
    state.hash = fnv1a(bytes);
    send({ type: "ack", frame: header.frame });
    $("s-frame").textContent = `${header.frame} (pass ${header.pass + 1}/${header.passes})`;
    $("s-render").textContent = ms(header.render_ms);
    $("s-encode").textContent = `${ms(header.encode_ms)}, ${(header.bytes / 1024).toFixed(0)} KiB ${header.format}`;
    $("s-rays").textContent = `${(header.rays_per_s / 1e6).toFixed(2)} M (${header.threads} threads)`;
    $("s-spp").textContent = `${header.spp}${header.converged ? " (done)" : ""}`;
    $("s-size").textContent = `${header.width}x${header.height}${header.interacting ? " (dragging: half size)" : ""}`;
    $("s-integrator").textContent = `${header.mode} (${header.integrator})`;
  };
  img.src = url;
}

function showError(e) {
  state.error = e;
  const box = $("error");
  if (!e) { box.hidden = true; box.textContent = ""; return; }
  box.hidden = false;
  const where = e.file ? `${e.file}${e.key ? ": " + e.key : ""}` : e.where;
  box.textContent = `${e.where === "scene file" ? "The scene file has an error; showing the last good image.\n" : ""}` +
    `${where}: ${e.message}`;
}

function fillSelect(id, values, label) {
  const s = $(id);
  s.innerHTML = "";
  for (const v of values) {
    const o = document.createElement("option");
    o.value = JSON.stringify(v);
    o.textContent = label ? label(v) : v;
    s.appendChild(o);
  }
}

function syncSelects(st) {
  $("mode").value = JSON.stringify(st.mode);
  $("stereo").value = JSON.stringify(st.stereo);
  $("format").value = JSON.stringify(st.format);
  $("size").value = JSON.stringify(st.size);
}

function showCompare(m) {
  state.compare = m;
  const out = $("compare-out");
  $("compare").disabled = m.status === "running";
  if (m.status !== "done") { out.textContent = m.message || `comparison ${m.status}...`; return; }
  out.innerHTML = "";
  const table = document.createElement("table");
  table.innerHTML = "<tr><th>renderer</th><th>RMSE</th><th>PSNR</th><th>FLIP</th><th>agrees</th></tr>";
  for (const r of m.rows) {
    const tr = document.createElement("tr");
    const f = (x, d) => (typeof x === "number" ? x.toPrecision(d) : (x ?? ""));
    const agrees = r.agrees === true ? "yes" : r.agrees === false ? "NO" : "-";
    for (const cell of [r.renderer, f(r.rmse, 3), f(r.psnr, 4), f(r.flip, 3), agrees]) {
      const td = document.createElement("td"); td.textContent = cell; tr.appendChild(td);
    }
    tr.title = r.verdict || "";
    table.appendChild(tr);
  }
  out.appendChild(table);
  for (const r of m.rows) {
    if (!r.heat_map) continue;
    const p = document.createElement("p");
    p.className = "small";
    p.textContent = `${r.renderer} against rtlab (${m.size[0]}x${m.size[1]}): ${r.verdict}`;
    const heat = document.createElement("img");
    heat.src = r.heat_map; heat.alt = `heat map of |${r.renderer} - rtlab|`;
    out.appendChild(p); out.appendChild(heat);
  }
}

socket.onopen = () => { state.open = true; };
socket.onclose = () => {
  state.open = false;
  showError({ where: "connection", message: "the viewer's server is gone (stopped?); reload when it runs again" });
};
socket.onmessage = (event) => {
  if (event.data instanceof ArrayBuffer) { showFrame(event.data); return; }
  const m = JSON.parse(event.data);
  if (m.type === "hello") {
    $("scene").textContent = m.scene;
    state.sizes = m.sizes;
    fillSelect("mode", m.modes, (v) => ({ depth: "aov: depth", object_id: "aov: object id", normal: "aov: normal" }[v] || v));
    fillSelect("size", m.sizes, (v) => `${v[0]}x${v[1]}${v === m.sizes[0] ? " (the file's)" : ""}`);
    fillSelect("stereo", m.stereo, (v) => v.replaceAll("_", " "));
    fillSelect("format", m.formats, (v) => v.toUpperCase());
    syncSelects(m.state);
  } else if (m.type === "stats") {
    state.stats = m;
    $("s-e2e").textContent = ms(m.e2e_ms);
    $("s-fps").textContent = m.fps.toFixed(1);
  } else if (m.type === "error") {
    showError(m);
  } else if (m.type === "scene") {
    showError(null);
    syncSelects(m.state);
  } else if (m.type === "settings") {
    syncSelects(m.state);
  } else if (m.type === "compare") {
    showCompare(m);
  }
};

for (const id of ["mode", "stereo", "format", "size"]) {
  $(id).addEventListener("change", () => {
    send({ type: "settings", [id]: JSON.parse($(id).value) });
    img.focus();
  });
}
$("reset").addEventListener("click", () => send({ type: "reset" }));
$("compare").addEventListener("click", () => send({ type: "compare" }));

// The mouse: moves are summed and sent at most once per animation frame; the server merges
// whatever arrives while a frame renders.
img.tabIndex = 0;
let drag = null;
let pending = { yaw: 0, pitch: 0, dx: 0, dy: 0 };
let scheduled = false;
function flush() {
  scheduled = false;
  if (pending.yaw || pending.pitch) send({ type: "orbit", yaw: pending.yaw, pitch: pending.pitch });
  if (pending.dx || pending.dy) send({ type: "pan", dx: pending.dx, dy: pending.dy });
  pending = { yaw: 0, pitch: 0, dx: 0, dy: 0 };
}
function schedule() { if (!scheduled) { scheduled = true; requestAnimationFrame(flush); } }

img.addEventListener("contextmenu", (e) => e.preventDefault());
img.addEventListener("mousedown", (e) => {
  e.preventDefault();
  img.focus();
  drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
  send({ type: "interact", active: true });
});
window.addEventListener("mousemove", (e) => {
  if (!drag) return;
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag.x = e.clientX; drag.y = e.clientY;
  const w = img.clientWidth || 1, h = img.clientHeight || 1;
  if (drag.pan) {
    // In pixels of the full-size image (the server's pan keeps the point under the mouse).
    const full = JSON.parse($("size").value || "[0,0]")[1] || h;
    pending.dx += dx * full / h; pending.dy += dy * full / h;
  } else {
    // A drag across the whole image turns the eye half way round.
    pending.yaw -= Math.PI * dx / w; pending.pitch += Math.PI * dy / h;
  }
  schedule();
});
window.addEventListener("mouseup", () => {
  if (!drag) return;
  drag = null;
  flush();
  send({ type: "interact", active: false });
});
img.addEventListener("wheel", (e) => {
  e.preventDefault();
  send({ type: "zoom", factor: Math.exp(Math.max(-5, Math.min(5, e.deltaY * 0.002))) });
}, { passive: false });

const KEYS = {  // steps in shares of the distance to the look-at point
  w: { forward: 0.05 }, ArrowUp: { forward: 0.05 }, s: { forward: -0.05 }, ArrowDown: { forward: -0.05 },
  a: { right: -0.05 }, ArrowLeft: { right: -0.05 }, d: { right: 0.05 }, ArrowRight: { right: 0.05 },
  q: { lift: -0.05 }, e: { lift: 0.05 },
};
document.addEventListener("keydown", (e) => {
  if (e.target instanceof HTMLSelectElement || e.ctrlKey || e.metaKey || e.altKey) return;
  const key = e.key.length === 1 ? e.key.toLowerCase() : e.key;
  if (key === "r") { send({ type: "reset" }); return; }
  const step = KEYS[key];
  if (!step) return;
  e.preventDefault();
  send({ type: "walk", forward: 0, right: 0, lift: 0, ...step });
});
