// passive-fusion live view: merges the server's topics (docs/view.md) and draws them.
// Frame: East-North metres; angles on the wire in degrees, clockwise from North.
// Whatever the data (null for NaN or infinite values, 1e12 m covariances, 1e4 tracks, a
// track at 1e7 m) a frame stays bounded: plan extents come from robust statistics,
// grid lines are capped, ellipses clipped, the track list truncated.
"use strict";

const BASE_COLOURS = ["#4fc3f7", "#ffb74d", "#ba68c8", "#81c784", "#f06292", "#fff176"];
const LEAD_S = 60;         // radar velocity vector: 60 s of motion
const TMA_LEAD_S = 600;    // TMA course and speed vector: 10 min of motion
const LIMIT_M = 1e8;       // a coordinate beyond this never counts for an extent
const OUTLIER_K = 10;      // farther than K x the median distance from the median: an outlier
const FLOOR_M = { plan: 3e5, tma: 1e5 };  // ... but never nearer than this
const MAX_GRID = 40;       // grid lines per direction, at most
const MAX_ROWS = 500;      // rows of the track list, at most
const OFF_SCALE_PX = 18;   // ring drawn for an ellipse larger than the canvas
const SPAN_M = [50, 1e8];  // zoom limits: the canvas width spans between these
const MIN_AUTO_M = 5e3;    // the automatic extent spans at least this (one own-ship point)
const UNITS = { km: 1000, NM: 1852 };
const DATA = /^(gtracks|etracks\/|truth_radar|waterfall\/|tma\/|truth_sonar\/)/;
const topics = {};
const got = {};            // topic -> page time (s) the view received its latest state
let limits = { stale_s: 5, router_s: 5 };
let wsOpen = false;
let selected = null;
let planXf = null;
let unit = "km";
const navs = new Map();    // canvas -> {auto, box (auto, grows), cx, cy, s (manual), follow}
const $ = (id) => document.getElementById(id);
const fin = Number.isFinite;  // false for null (NaN and Infinity on the wire), NaN, Infinity
const num = (v, d) => (fin(v) ? v.toFixed(d) : "-");
const dist = (m, d = 2) => (fin(m) ? (m / UNITS[unit]).toFixed(d) : "-");
const speed = (vx, vy) => (fin(vx) && fin(vy) ? Math.hypot(vx, vy) : NaN);
const layer = (name) => $("layer-" + name).checked;
const nowS = () => performance.now() / 1000;

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws`);
  ws.onopen = () => { wsOpen = true; tick(); };
  ws.onclose = () => { wsOpen = false; tick(); setTimeout(connect, 1000); };
  ws.onmessage = (ev) => {
    const t0 = performance.now();
    try {
      const m = JSON.parse(ev.data), now = nowS();
      timeline.take(m.topics);  // timeline.js: recorded, and shown unless paused
      Object.entries(m.ages || {}).forEach(([n, a]) => { got[n] = now - a; });
      if (m.limits) limits = m.limits;
      render(true);
    } finally {
      ws.send("ack");  // the server sends the next message only after this one is drawn
      timeline.frameDone(performance.now() - t0);
    }
  };
}

// ---- freshness: badge, data age per panel, UTC clock (every 0.5 s, messages or not) ----
function age(name) { return got[name] === undefined ? Infinity : nowS() - got[name]; }

function ageText(a) {
  if (!fin(a)) return "no data";
  return a < 60 ? `${a.toFixed(1)} s` : a < 3600 ? `${(a / 60).toFixed(1)} min` : `${(a / 3600).toFixed(1)} h`;
}

function badgeState() {
  const link = topics.link;
  if (!wsOpen || (link && !link.router && age("link") >= limits.router_s)) return "disconnected";
  const newest = Math.min(...Object.keys(got).filter((n) => DATA.test(n)).map(age));
  return newest >= limits.stale_s ? "stale" : "live";
}

function tick() {
  const b = $("conn"), state = badgeState();
  b.textContent = state; b.className = `conn ${state}`; b.dataset.state = state;
  document.querySelectorAll(".age").forEach((el) => {
    const a = age(el.dataset.topic);
    el.textContent = `age ${ageText(a)}`; el.dataset.age = fin(a) ? a.toFixed(2) : "";
  });
  $("clock").textContent = new Date().toISOString().slice(11, 19) + " UTC";
  document.querySelectorAll("#service-rows td.up").forEach((td) => {
    const up = +td.dataset.up;
    td.textContent = td.dataset.up === "" ? "-" : uptime(up + age("services"));
  });
}
setInterval(tick, 500);

// Draws every panel. render(true), for a message or a navigation step, lets a panel whose
// inputs did not change keep its pixels (draw.js unchanged); render() redraws them all.
let reuse = false;
function render(keep = false) {
  reuse = keep;
  const geo = topics.geometry || { bases: [], root: "-" };
  $("root").textContent = geo.root;
  const g = topics.gtracks || { t: null, tracks: [] };
  $("t-radar").textContent = g.t === null ? "-" : g.t.toFixed(1);
  $("n-confirmed").textContent = g.tracks.filter((k) => k.status === "confirmed").length;
  drawPlan(geo, g);
  trackTable(g.tracks);
  details(g.tracks.find((k) => k.id === selected));
  sonar();
  sonarTable();
  services();
  tick();
}

let pending = false;
function schedule() {  // a redraw for navigation, at most one per animation frame
  if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; render(true); }); }
}

// ---- plan views: robust extents, navigation (grid, scale bar and shapes: draw.js) ----
function grow(box, x, y) {
  box[0] = Math.min(box[0], x); box[1] = Math.max(box[1], x);
  box[2] = Math.min(box[2], y); box[3] = Math.max(box[3], y);
}

function median(v) { const s = Float64Array.from(v).sort(); return s[s.length >> 1]; }

// The box of `anchors` (always kept: sensors, own ship) and of the points of `pts` that are
// not outliers; non-finite and |v| >= LIMIT_M points are ignored. null when nothing is left.
function robustBox(anchors, pts, floor) {
  const ok = (p) => fin(p[0]) && fin(p[1]) && Math.abs(p[0]) < LIMIT_M && Math.abs(p[1]) < LIMIT_M;
  const a = anchors.filter(ok), b = pts.filter(ok), all = a.concat(b);
  if (!all.length) return null;
  const cx = median(all.map((p) => p[0])), cy = median(all.map((p) => p[1]));
  const keep = Math.max(OUTLIER_K * median(all.map((p) => Math.hypot(p[0] - cx, p[1] - cy))), floor);
  const box = [Infinity, -Infinity, Infinity, -Infinity];
  a.forEach((p) => grow(box, p[0], p[1]));
  b.forEach((p) => { if (Math.hypot(p[0] - cx, p[1] - cy) <= keep) grow(box, p[0], p[1]); });
  return box;
}

function nav(canvas) {
  let n = navs.get(canvas);
  if (!n) { n = { auto: true, box: null, follow: null }; navs.set(canvas, n); listen(canvas, n); }
  return n;
}

function xfOf(canvas, cx, cy, s) {
  const W = canvas.width, H = canvas.height;
  return { s, cx, cy, x: (x) => W / 2 + (x - cx) * s, y: (y) => H / 2 - (y - cy) * s,
    wx: (px) => cx + (px - W / 2) / s, wy: (py) => cy - (py - H / 2) / s };
}

function clampS(canvas, s) { return Math.min(Math.max(s, canvas.width / SPAN_M[1]), canvas.width / SPAN_M[0]); }

// The transform of a plan canvas: in auto mode it fits `box`; after a zoom or a pan, the
// operator's centre and scale (centred on the followed point when there is one).
function transform(canvas, box, follow) {
  const n = nav(canvas);
  if (n.auto) {
    const pad = 30, w = canvas.width - 2 * pad, h = canvas.height - 2 * pad;
    const s = Math.min(w / Math.max(box[1] - box[0], MIN_AUTO_M), h / Math.max(box[3] - box[2], MIN_AUTO_M));
    Object.assign(n, { cx: (box[0] + box[1]) / 2, cy: (box[2] + box[3]) / 2, s: clampS(canvas, s) });
  }
  if (follow) { n.cx = follow[0]; n.cy = follow[1]; }
  return (canvas.xf = xfOf(canvas, n.cx, n.cy, n.s));
}

function listen(canvas, n) {
  const at = (ev) => {
    const r = canvas.getBoundingClientRect(), k = canvas.width / r.width;
    return [(ev.clientX - r.left) * k, (ev.clientY - r.top) * k];
  };
  canvas.addEventListener("wheel", (ev) => {
    ev.preventDefault();
    const xf = canvas.xf;
    if (!xf) return;
    const [px, py] = at(ev), wx = xf.wx(px), wy = xf.wy(py);
    const s = clampS(canvas, xf.s * (ev.deltaY < 0 ? 1.25 : 1 / 1.25));
    Object.assign(n, { auto: false, s, cx: wx - (px - canvas.width / 2) / s, cy: wy + (py - canvas.height / 2) / s });
    schedule();
  }, { passive: false });
  let drag = null;
  canvas.addEventListener("mousedown", (ev) => { drag = { p: at(ev), moved: false }; });
  window.addEventListener("mouseup", () => { if (drag) setTimeout(() => { drag = null; }, 0); });
  canvas.addEventListener("mousemove", (ev) => {
    if (!drag || !(ev.buttons & 1) || !canvas.xf) return;
    const p = at(ev), dx = p[0] - drag.p[0], dy = p[1] - drag.p[1];
    if (!drag.moved && Math.hypot(dx, dy) < 3) return;
    drag.moved = true; drag.p = p;
    Object.assign(n, { auto: false, follow: null, cx: n.cx - dx / n.s, cy: n.cy + dy / n.s });
    schedule();
  });
  canvas.dragged = () => drag !== null && drag.moved;
}

function fitAll(canvas) { Object.assign(nav(canvas), { auto: true, box: null, follow: null }); render(); }

// ---- radar plan view ----
function followed(canvas, tracks) {
  const n = nav(canvas);
  if (n.follow === null) return null;
  const k = tracks.find((t) => t.id === n.follow);
  if (k && fin(k.x[0]) && fin(k.x[2])) return [k.x[0], k.x[2]];
  $("follow-note").textContent = `track ${n.follow} is gone: follow ended`;
  n.follow = null;
  return null;
}

function drawPlan(geo, g) {
  const canvas = $("plan"), ctx = canvas.getContext("2d"), n = nav(canvas);
  const arcs = geo.bases.map((b) => topics[`etracks/${b.id}`]);
  if (unchanged(canvas, [geo, g, topics.truth_radar, ...arcs, ...["trails", "ellipses", "arcs", "truth"].map(layer),
    selected, unit, n.auto, n.cx, n.cy, n.s, n.follow])) return;
  const anchors = geo.bases.flatMap((b) => [b.tx, b.rx]);
  const now = robustBox(anchors, g.tracks.map((k) => [k.x[0], k.x[2]]), FLOOR_M.plan);
  const box = n.box ? n.box.slice() : [Infinity, -Infinity, Infinity, -Infinity];
  if (now) { grow(box, now[0], now[2]); grow(box, now[1], now[3]); }  // grows: the picture stays still
  if (!fin(box[0])) { grow(box, -5e4, -5e4); grow(box, 5e4, 5e4); }
  n.box = box;
  const xf = planXf = transform(canvas, box, followed(canvas, g.tracks));
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  canvas.labels = [];
  (geo.origin ? graticule : grid)(ctx, canvas, xf, geo.origin);
  geo.bases.forEach((b, i) => {
    const c = BASE_COLOURS[i % BASE_COLOURS.length];
    ctx.strokeStyle = c; ctx.setLineDash([4, 4]); ctx.lineWidth = 1;
    ctx.beginPath(); ctx.moveTo(xf.x(b.rx[0]), xf.y(b.rx[1])); ctx.lineTo(xf.x(b.tx[0]), xf.y(b.tx[1])); ctx.stroke();
    ctx.setLineDash([]);
    ctx.fillStyle = c; ctx.fillRect(xf.x(b.tx[0]) - 5, xf.y(b.tx[1]) - 5, 10, 10);
    ctx.font = "11px sans-serif"; ctx.fillText(`Tx ${b.id}`, xf.x(b.tx[0]) + 8, xf.y(b.tx[1]) + 4);
    const arcs = topics[`etracks/${b.id}`];
    if (layer("arcs") && arcs) {
      ctx.globalAlpha = 0.6; ctx.lineWidth = 2;
      ctx.beginPath(); arcs.arcs.forEach((a) => linePath(ctx, xf, a.pts)); ctx.stroke();
      ctx.globalAlpha = 1;
    }
  });
  const rxs = new Set(geo.bases.map((b) => b.rx.join(",")));
  rxs.forEach((r) => {
    const [x, y] = r.split(",").map(Number);
    ctx.fillStyle = "#e0e0e0"; ctx.beginPath();
    ctx.moveTo(xf.x(x), xf.y(y) - 7); ctx.lineTo(xf.x(x) - 6, xf.y(y) + 5); ctx.lineTo(xf.x(x) + 6, xf.y(y) + 5);
    ctx.fill(); ctx.fillText("Rx", xf.x(x) + 8, xf.y(y) + 4);
  });
  const truth = topics.truth_radar;
  if (layer("truth") && truth) {
    ctx.strokeStyle = PALETTE.truth; ctx.lineWidth = 1.5;
    crosses(ctx, xf, truth, 5);
  }
  drawTracks(ctx, xf, g.tracks);
  scaleBar(ctx, canvas, xf);
  $("plan-scale").textContent = canvas.dataset.scale;
}

// Tracks drawn in one path per status colour and layer (10^4 tracks: one stroke each
// cost ~100 ms a frame); the few rings (ambiguous, selected) one by one.
function drawTracks(ctx, xf, tracks) {
  const groups = new Map();
  tracks.forEach((k) => {
    if (!fin(k.x[0]) || !fin(k.x[2])) return;  // no position: listed, not drawn
    if (!groups.has(k.status)) groups.set(k.status, []);
    groups.get(k.status).push(k);
  });
  ctx.lineWidth = 1.5; ctx.font = "bold 12px sans-serif";
  groups.forEach((ks, status) => {
    const c = COLOURS[status] || "#fff";
    ctx.strokeStyle = c; ctx.fillStyle = c;
    if (layer("trails")) {
      ctx.globalAlpha = 0.55; ctx.beginPath(); ks.forEach((k) => linePath(ctx, xf, k.trail)); ctx.stroke();
      ctx.globalAlpha = 1;
    }
    if (layer("ellipses")) ellipses(ctx, xf, ks.map((k) => [k.x[0], k.x[2], k.ell]));
    marks(ctx, xf, ks, status);
    ctx.beginPath();
    ks.forEach((k) => {
      if (!fin(k.x[1]) || !fin(k.x[3])) return;
      ctx.moveTo(xf.x(k.x[0]), xf.y(k.x[2]));
      ctx.lineTo(xf.x(k.x[0] + k.x[1] * LEAD_S), xf.y(k.x[2] + k.x[3] * LEAD_S));
    });
    ctx.stroke();
    const W = ctx.canvas.width, H = ctx.canvas.height;
    ks.forEach((k) => {  // labels of the tracks on the canvas, kept inside it
      const px = xf.x(k.x[0]), py = xf.y(k.x[2]);
      if (px >= 0 && px <= W && py >= 0 && py <= H) label(ctx, ctx.canvas, `${k.id}${k.amb ? "?" : ""}`, px + 7, py - 7);
    });
  });
  groups.forEach((ks) => ks.forEach((k) => {
    const px = xf.x(k.x[0]), py = xf.y(k.x[2]);
    if (k.amb) {
      ctx.strokeStyle = AMBIGUOUS; ctx.setLineDash([3, 3]);
      ctx.beginPath(); ctx.arc(px, py, 10, 0, 2 * Math.PI); ctx.stroke(); ctx.setLineDash([]);
    }
    if (k.id === selected) {
      ctx.strokeStyle = "#ffffff"; ctx.beginPath(); ctx.arc(px, py, 14, 0, 2 * Math.PI); ctx.stroke();
    }
  }));
}

function marks(ctx, xf, ks, status) {  // the status' shape cue (palette.js SHAPES)
  ctx.beginPath();
  ks.forEach((k) => {
    const px = xf.x(k.x[0]), py = xf.y(k.x[2]);
    if (status === "coasting") ctx.rect(px - 4, py - 4, 8, 8);
    else { ctx.moveTo(px + 4, py); ctx.arc(px, py, 4, 0, 2 * Math.PI); }
  });
  status === "tentative" ? ctx.stroke() : ctx.fill();
}

$("plan").addEventListener("click", (ev) => {
  const g = topics.gtracks, canvas = ev.target;
  if (!g || !planXf || canvas.dragged()) return;
  const r = canvas.getBoundingClientRect(), sx = canvas.width / r.width;
  const cx = (ev.clientX - r.left) * sx, cy = (ev.clientY - r.top) * sx;
  let best = null, bestD = 15;
  g.tracks.forEach((k) => {
    const d = Math.hypot(planXf.x(k.x[0]) - cx, planXf.y(k.x[2]) - cy);
    if (d < bestD) { best = k.id; bestD = d; }
  });
  select(best);
});
["trails", "ellipses", "arcs", "truth"].forEach((n) => $("layer-" + n).addEventListener("change", render));
$("fit-plan").addEventListener("click", () => fitAll($("plan")));
$("follow").addEventListener("click", () => {
  if (selected === null) return;
  const n = nav($("plan"));
  if (n.auto) n.auto = false;  // keeps the present scale, centred on the track
  n.follow = selected; $("follow-note").textContent = `following track ${selected}`;
  render();
});
$("units").addEventListener("change", (ev) => { unit = ev.target.value; render(); });

function select(id) { selected = id; selectedSonar = null; render(); }

function course(vx, vy) { return fin(vx) && fin(vy) ? ((Math.atan2(vx, vy) * 180 / Math.PI) + 360) % 360 : NaN; }

// ---- services: the table of pfusion status; red when a token goes without a normal end ----
function uptime(s) {
  if (!fin(s)) return "-";
  const h = Math.floor(s / 3600), m = Math.floor(s / 60) % 60, sec = Math.floor(s % 60);
  return h ? `${h}h${String(m).padStart(2, "0")}m` : m ? `${m}m${String(sec).padStart(2, "0")}s` : `${sec}s`;
}

function services() {
  const rows = (topics.services || { rows: [] }).rows;
  $("service-rows").replaceChildren(...rows.map((r) => {
    const tr = document.createElement("tr");
    const state = r.state || (r.alive ? "alive" : "gone");
    tr.dataset.service = r.service; tr.dataset.instance = r.instance; tr.dataset.state = state;
    tr.className = { alive: "alive", finished: "finished", gone: "dead" }[state];
    const has = r.in !== undefined;
    [r.service, r.instance, { alive: "yes", finished: "finished", gone: "GONE" }[state], "", r.restarts ?? 0, ...(has
      ? [r.in, r.out, r.rejected, r.missed, num(r.p50, 2), num(r.p99, 2), r.queue, num(r.t, 1)]
      : Array(8).fill("-"))].forEach((c) => { const td = document.createElement("td"); td.textContent = c; tr.appendChild(td); });
    const up = tr.children[3];
    up.className = "up"; up.dataset.up = fin(r.up) ? r.up : "";
    if (has && r.rejected) tr.title = Object.entries(r.reasons).map(([k, v]) => `${k}=${v}`).join(", ");
    return tr;
  }));
}

connect();
