// cbr report: sortable tables, synchronised zoom/pan viewers, slider and hold-to-flip, keys,
// pixel readout. No network, no libraries. `#selftest` runs scripted checks and writes their
// result as JSON into <pre id="selftest"> (the test suite reads it through headless Chromium).
"use strict";
const errors = [];
window.addEventListener("error", (e) => errors.push(String(e.message)));
const origError = console.error;
console.error = (...a) => { errors.push(a.map(String).join(" ")); origError.apply(console, a); };

// ---- images: each stored once in IMAGES (data URIs or relative paths) --------------------------
/* global IMAGES */
document.querySelectorAll("[data-im]").forEach((el) => {
  const src = IMAGES[el.dataset.im];
  if (el.tagName === "IMG") el.src = src;
  else el.style.backgroundImage = `url("${src}")`;
});

// ---- sortable tables -------------------------------------------------------------------------
function sortTable(th) {
  const table = th.closest("table");
  const idx = Array.from(th.parentNode.children).indexOf(th);
  const asc = !th.classList.contains("asc");
  table.querySelectorAll("th").forEach((h) => h.classList.remove("asc", "desc"));
  th.classList.add(asc ? "asc" : "desc");
  const body = table.tBodies[0];
  const rows = Array.from(body.rows);
  const key = (r) => {
    const c = r.cells[idx];
    const v = c.dataset.v !== undefined ? c.dataset.v : c.textContent;
    const n = parseFloat(v);
    return Number.isNaN(n) ? v : n;
  };
  rows.sort((a, b) => {
    const x = key(a), y = key(b);
    const xn = typeof x === "number", yn = typeof y === "number";
    let d;
    if (xn && yn) d = x - y; else if (xn) d = -1; else if (yn) d = 1; else d = String(x).localeCompare(String(y));
    return asc ? d : -d;
  });
  rows.forEach((r) => body.appendChild(r));
}
document.querySelectorAll("table.sortable th").forEach((th) => th.addEventListener("click", () => sortTable(th)));

// ---- viewers ---------------------------------------------------------------------------------
const viewers = [];
let activeViewer = null;

function Viewer(root) {
  this.root = root;
  this.w = +root.dataset.w;
  this.h = +root.dataset.h;
  this.panels = Array.from(root.querySelectorAll(".vp"));
  this.layers = Array.from(root.querySelectorAll(".vp .layer"));
  this.compare = root.querySelector(".compare");
  this.slider = root.querySelector("input.slider");
  this.readout = root.querySelector(".readout");
  this.techs = JSON.parse(root.dataset.techs);
  this.tech = 0;
  this.flip = false;
  this.canvases = new Map();
  this.reset();
  const self = this;
  this.panels.forEach((vp) => {
    vp.style.height = Math.round(vp.clientWidth * this.h / this.w) + "px";
    vp.addEventListener("wheel", (e) => { e.preventDefault(); self.zoomAt(vp, e.offsetX, e.offsetY, e.deltaY < 0 ? 1.25 : 0.8); }, { passive: false });
    vp.addEventListener("mousedown", (e) => { self.drag = { x: e.clientX, y: e.clientY }; activeViewer = self; });
    vp.addEventListener("mousemove", (e) => { activeViewer = self; self.readPixel(vp, e.offsetX, e.offsetY); });
  });
  window.addEventListener("mousemove", (e) => {
    if (!self.drag) return;
    self.tx += (e.clientX - self.drag.x) / self.scale0;
    self.ty += (e.clientY - self.drag.y) / self.scale0;
    self.drag = { x: e.clientX, y: e.clientY };
    self.apply();
  });
  window.addEventListener("mouseup", () => { self.drag = null; });
  if (this.slider) this.slider.addEventListener("input", () => self.applyCompare());
  this.applyCompare();
}
// View state in image pixels: the image point at a panel's top-left is (-tx, -ty); zoom z.
Viewer.prototype.reset = function () { this.z = 1; this.tx = 0; this.ty = 0; this.apply(); };
Viewer.prototype.zoomAt = function (vp, px, py, f) {
  const s = vp.clientWidth / this.w * this.z;
  const ix = px / s - this.tx, iy = py / s - this.ty;
  this.z = Math.min(64, Math.max(1, this.z * f));
  const s2 = vp.clientWidth / this.w * this.z;
  this.tx = px / s2 - ix;
  this.ty = py / s2 - iy;
  this.apply();
};
Viewer.prototype.apply = function () {
  this.scale0 = (this.panels[0] ? this.panels[0].clientWidth / this.w : 1) * this.z;
  this.layers.forEach((l) => {
    const s = l.parentNode.clientWidth / this.w * this.z;
    l.style.transform = `scale(${s}) translate(${this.tx}px, ${this.ty}px)`;
  });
};
Viewer.prototype.applyCompare = function () {
  if (!this.compare) return;
  const t = this.techs[this.tech];
  const top = this.compare.querySelector(".top");
  const img = top.querySelector("img");
  if (img.dataset.im !== t.im) { img.dataset.im = t.im; img.src = IMAGES[t.im]; }
  top.style.display = this.flip ? "none" : "";
  top.style.width = (this.slider ? this.slider.value : 50) + "%";
  this.compare.querySelector(".cmpname").textContent = (this.flip ? "reference (held)" : t.name) + " | reference";
};
Viewer.prototype.selectTech = function (i) {
  if (i >= 0 && i < this.techs.length) { this.tech = i; this.applyCompare(); }
};
Viewer.prototype.pixel = function (img, x, y) {
  const key = img.dataset.im;
  let c = this.canvases.get(key);
  try {
    if (!c) {
      c = document.createElement("canvas");
      c.width = img.naturalWidth; c.height = img.naturalHeight;
      c.getContext("2d").drawImage(img, 0, 0);
      this.canvases.set(key, c);
    }
    const d = c.getContext("2d").getImageData(x, y, 1, 1).data;
    return `${d[0]},${d[1]},${d[2]}`;
  } catch (e) {
    return "n/a (file:// assets)";
  }
};
Viewer.prototype.readPixel = function (vp, px, py) {
  const s = vp.clientWidth / this.w * this.z;
  const x = Math.floor(px / s - this.tx), y = Math.floor(py / s - this.ty);
  if (x < 0 || y < 0 || x >= this.w || y >= this.h) return;
  const lines = [`pixel (${x}, ${y})  display sRGB 8-bit`];
  this.root.querySelectorAll(".panel").forEach((p) => {
    const img = p.querySelector("img");
    if (img && img.complete && img.naturalWidth) lines.push(`${p.dataset.name.padEnd(44)} ${this.pixel(img, x, y)}`);
  });
  this.readout.textContent = lines.join("\n");
};

document.querySelectorAll(".viewer").forEach((v) => viewers.push(new Viewer(v)));
activeViewer = viewers[0] || null;
window.addEventListener("keydown", (e) => {
  const v = activeViewer;
  if (!v) return;
  if (e.key >= "1" && e.key <= "9") v.selectTech(+e.key - 1);
  else if (e.key === "r" || e.key === "R") v.reset();
  else if ((e.key === "f" || e.key === "F") && !v.flip) { v.flip = true; v.applyCompare(); }
});
window.addEventListener("keyup", (e) => {
  const v = activeViewer;
  if (v && (e.key === "f" || e.key === "F")) { v.flip = false; v.applyCompare(); }
});

// ---- self-test (headless Chromium) -------------------------------------------------------------
function selftest() {
  const r = { errors, checks: {} };
  const imgs = Array.from(document.images);
  r.checks.images = imgs.length;
  r.checks.images_broken = imgs.filter((i) => !i.complete || i.naturalWidth === 0).map((i) => i.alt || i.dataset.im);
  const table = document.querySelector("table.sortable");
  if (table) {
    const ths = Array.from(table.querySelectorAll("th"));
    const th = ths.find((h) => h.dataset.key === "flip_mean");
    const col = ths.indexOf(th);
    const vals = () => Array.from(table.tBodies[0].rows).map((row) => parseFloat(row.cells[col].dataset.v)).filter((x) => !Number.isNaN(x));
    th.click();
    const a = vals();
    th.click();
    const d = vals();
    r.checks.sort_ascending = a.every((x, i) => i === 0 || a[i - 1] <= x);
    r.checks.sort_descending = d.every((x, i) => i === 0 || d[i - 1] >= x);
    r.checks.sorted_rows = a.length;
  }
  const v = viewers[0];
  if (v) {
    const before = v.layers.map((l) => l.style.transform);
    const rect = v.panels[0].getBoundingClientRect();
    v.panels[0].dispatchEvent(new WheelEvent("wheel", { deltaY: -100, clientX: rect.left + 20, clientY: rect.top + 20, bubbles: true, cancelable: true }));
    const after = v.layers.map((l) => l.style.transform);
    r.checks.zoom_changed = after.every((t, i) => t !== before[i]);
    r.checks.zoom_synchronised = new Set(after.map((t) => t.replace(/scale\([^)]*\)/, ""))).size === 1;
    const top = v.compare.querySelector(".top");
    v.slider.value = 20; v.slider.dispatchEvent(new Event("input"));
    const w20 = top.style.width;
    v.slider.value = 80; v.slider.dispatchEvent(new Event("input"));
    r.checks.slider_moves = w20 === "20%" && top.style.width === "80%";
    activeViewer = v;
    window.dispatchEvent(new KeyboardEvent("keydown", { key: "2" }));
    r.checks.key_selects = v.tech === Math.min(1, v.techs.length - 1);
    window.dispatchEvent(new KeyboardEvent("keydown", { key: "f" }));
    const held = top.style.display === "none";
    window.dispatchEvent(new KeyboardEvent("keyup", { key: "f" }));
    r.checks.hold_to_flip = held && top.style.display === "";
    v.readPixel(v.panels[0], 5, 5);
    r.checks.readout = v.readout.textContent.split("\n").length > 1;
    r.checks.readout_values = /\d+,\d+,\d+/.test(v.readout.textContent);
    if (location.hash === "#selftest-zoomed") return r; // leave the zoomed view for a screenshot
    window.dispatchEvent(new KeyboardEvent("keydown", { key: "r" }));
    r.checks.reset = v.z === 1 && v.tx === 0;
  }
  return r;
}
window.addEventListener("load", () => {
  if (!location.hash.startsWith("#selftest")) return;
  const pre = document.createElement("pre");
  pre.id = "selftest";
  let result;
  try { result = selftest(); } catch (e) { result = { errors: errors.concat([String(e)]) }; }
  pre.textContent = JSON.stringify(result);
  document.body.appendChild(pre);
});
