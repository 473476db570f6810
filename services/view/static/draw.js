// passive-fusion live view: canvas primitives of the plan views, waterfall and TMA
// panels (docs/view.md): grid and scale bar, ellipses, polylines, truth crosses, labels
// kept inside their canvas, and the check that lets a canvas keep its pixels when its
// inputs did not change. Every same-style shape of a layer goes into one path (one
// stroke per shape was the frame's main cost at 10^3-10^4 tracks). Uses view.js' state.
"use strict";

function nice(v) {  // 1, 2 or 5 x 10^k nearest above v
  const p = Math.pow(10, Math.floor(Math.log10(v))), m = v / p;
  return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * p;
}

function grid(ctx, canvas, xf) {
  const u = UNITS[unit], step = nice(canvas.width / xf.s / u / 10) * u;
  if (!fin(step) || step <= 0) return;
  ctx.strokeStyle = "#1b2834"; ctx.fillStyle = "#4b6075"; ctx.lineWidth = 1; ctx.font = "10px sans-serif";
  const txt = (v) => `${+(v / u).toPrecision(6)} ${unit}`;
  canvas.graticule = null;
  const x0 = Math.ceil(xf.wx(0) / step) * step, y0 = Math.ceil(xf.wy(canvas.height) / step) * step;
  const lines = new Path2D(), texts = [];  // the lines in one path, then their labels
  for (let i = 0, v = x0; i < MAX_GRID && v < xf.wx(canvas.width); i++, v = x0 + i * step) {
    lines.moveTo(xf.x(v), 0); lines.lineTo(xf.x(v), canvas.height);
    texts.push([txt(v), xf.x(v) + 2, canvas.height - 4]);
  }
  for (let i = 0, v = y0; i < MAX_GRID && v < xf.wy(0); i++, v = y0 + i * step) {
    lines.moveTo(0, xf.y(v)); lines.lineTo(canvas.width, xf.y(v));
    texts.push([txt(v), 2, xf.y(v) - 2]);
  }
  ctx.stroke(lines);
  texts.forEach(([t, x, y]) => label(ctx, canvas, t, x, y));
}

function scaleBar(ctx, canvas, xf) {
  const u = UNITS[unit], len = nice(canvas.width / 5 / xf.s / u), px = len * u * xf.s;
  const text = `${+len.toPrecision(6)} ${unit}`, x = 12, y = canvas.height - 22;
  ctx.strokeStyle = "#e0e0e0"; ctx.fillStyle = "#e0e0e0"; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(x, y - 5); ctx.lineTo(x, y); ctx.lineTo(x + px, y); ctx.lineTo(x + px, y - 5); ctx.stroke();
  ctx.font = "11px sans-serif"; ctx.fillText(text, x + 4, y - 6);
  canvas.dataset.scale = text;
}

// Adds to the current path the ellipse e = [a, b, angle counter-clockwise from East]
// around (x, y) (canvas y points down: rotated by -angle). One whose major semi-axis
// exceeds the canvas' diagonal is off scale: its centre goes to `off` instead (drawn as a
// dashed ring of OFF_SCALE_PX; its outline would lie mostly outside the canvas, and a
// path thousands of pixels long per track is what froze the page).
function ellipsePath(ctx, xf, x, y, e, off) {
  if (!e || !fin(x) || !fin(y) || !e.every(fin)) return;
  const c = ctx.canvas, px = xf.x(x), py = xf.y(y), a = Math.max(e[0] * xf.s, 0.5), r = -e[2];
  if (a > Math.hypot(c.width, c.height)) { off.push([px, py]); return; }
  if (px + a < 0 || px - a > c.width || py + a < 0 || py - a > c.height) return;  // all outside
  ctx.moveTo(px + a * Math.cos(r), py + a * Math.sin(r));
  ctx.ellipse(px, py, a, Math.max(e[1] * xf.s, 0.5), r, 0, 2 * Math.PI);
}

function ellipses(ctx, xf, items) {  // items: [x, y, ell] in the current stroke style
  const off = [];
  ctx.beginPath(); items.forEach((i) => ellipsePath(ctx, xf, i[0], i[1], i[2], off)); ctx.stroke();
  if (!off.length) return;
  ctx.setLineDash([2, 3]); ctx.beginPath();
  off.forEach(([px, py]) => { ctx.moveTo(px + OFF_SCALE_PX, py); ctx.arc(px, py, OFF_SCALE_PX, 0, 2 * Math.PI); });
  ctx.stroke(); ctx.setLineDash([]);
}

// Adds the polyline of pts, broken at non-finite points; a point within a pixel of the
// last one drawn is skipped unless it ends the line (a trail or an arc at the plan's
// scale is mostly such points: the path, and its rasterising, stays short).
function linePath(ctx, xf, pts) {
  let on = false, lx = 0, ly = 0;
  for (let i = 0; i < pts.length; i++) {
    const p = pts[i];
    if (!fin(p[0]) || !fin(p[1])) { on = false; continue; }
    const x = xf.x(p[0]), y = xf.y(p[1]);
    if (!on) { ctx.moveTo(x, y); on = true; lx = x; ly = y; continue; }
    const end = i === pts.length - 1 || !fin(pts[i + 1][0]) || !fin(pts[i + 1][1]);
    if (!end && Math.abs(x - lx) < 1 && Math.abs(y - ly) < 1) continue;
    ctx.lineTo(x, y); lx = x; ly = y;
  }
}

function polyline(ctx, xf, pts) { ctx.beginPath(); linePath(ctx, xf, pts); ctx.stroke(); }

// True when a canvas (or table) may keep what it shows: the frame allows it (`reuse`, see
// render) and it was last drawn from the same inputs, compared by identity (a topic's
// state is a new object whenever it changes). Records the inputs.
function unchanged(el, inputs) {
  const was = el.inputs;
  el.inputs = inputs;
  return reuse && !!was && was.length === inputs.length && was.every((v, i) => v === inputs[i]);
}

function crosses(ctx, xf, truth, r) {  // truth {x: [], y: []} as crosses, one path
  const W = ctx.canvas.width, H = ctx.canvas.height;
  ctx.beginPath();
  truth.x.forEach((x, i) => {
    const px = xf.x(x), py = xf.y(truth.y[i]);
    if (!fin(px) || !fin(py) || px < -r || px > W + r || py < -r || py > H + r) return;
    ctx.moveTo(px - r, py - r); ctx.lineTo(px + r, py + r);
    ctx.moveTo(px - r, py + r); ctx.lineTo(px + r, py - r);
  });
  ctx.stroke();
}

// A label kept inside its canvas (shifted left or down when it would be cut at an edge);
// every label drawn this frame is listed in canvas.labels ([text, x, y, width]).
const widths = new Map();  // font and text -> measured width (px): 10^3 labels a frame
function label(ctx, canvas, text, x, y) {
  const key = ctx.font + "|" + text, h = 11;
  let w = widths.get(key);
  if (w === undefined) {
    if (widths.size > 50000) widths.clear();
    widths.set(key, (w = ctx.measureText(text).width));
  }
  const lx = Math.min(Math.max(x, 2), canvas.width - w - 2), ly = Math.min(Math.max(y, h + 1), canvas.height - 3);
  ctx.fillText(text, lx, ly);
  (canvas.labels = canvas.labels || []).push([text, lx, ly, w]);
}
