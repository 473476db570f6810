// passive-fusion live view: merges the server's topics (docs/view.md) and draws them.
// Frame: East-North metres; angles on the wire in degrees, clockwise from North.
"use strict";

const COLOURS = { confirmed: "#66bb6a", tentative: "#b0bec5", coasting: "#ffa726" };
const AMBIGUOUS = "#e040fb";
const BASE_COLOURS = ["#4fc3f7", "#ffb74d", "#ba68c8", "#81c784", "#f06292", "#fff176"];
const LEAD_S = 60;       // radar velocity vector: 60 s of motion
const TMA_LEAD_S = 600;  // TMA course and speed vector: 10 min of motion
const topics = {};
let selected = null;
let extent = null;       // radar plan: world box, only grows so the picture stays still
let planXf = null;
const $ = (id) => document.getElementById(id);
const km = (m) => (m / 1000).toFixed(2);
const layer = (name) => $("layer-" + name).checked;

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws`);
  ws.onopen = () => { $("conn").textContent = "live"; $("conn").className = "conn up"; };
  ws.onclose = () => {
    $("conn").textContent = "disconnected"; $("conn").className = "conn down";
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => {
    try {
      Object.assign(topics, JSON.parse(ev.data).topics);
      render();
    } finally {
      ws.send("ack");  // the server sends the next message only after this one is drawn
    }
  };
}

function render() {
  const geo = topics.geometry || { bases: [], root: "-" };
  $("root").textContent = geo.root;
  const g = topics.gtracks || { t: null, tracks: [] };
  $("t-radar").textContent = g.t === null ? "-" : g.t.toFixed(1);
  $("n-confirmed").textContent = g.tracks.filter((k) => k.status === "confirmed").length;
  drawPlan(geo, g);
  trackTable(g.tracks);
  details(g.tracks.find((k) => k.id === selected));
  sonar();
  services();
}

// ---- radar plan view ----
function grow(box, x, y) {
  box[0] = Math.min(box[0], x); box[1] = Math.max(box[1], x);
  box[2] = Math.min(box[2], y); box[3] = Math.max(box[3], y);
}

function transform(canvas, box) {
  const pad = 30, w = canvas.width - 2 * pad, h = canvas.height - 2 * pad;
  const s = Math.min(w / Math.max(box[1] - box[0], 1), h / Math.max(box[3] - box[2], 1));
  const cx = (box[0] + box[1]) / 2, cy = (box[2] + box[3]) / 2;
  return { s, x: (x) => canvas.width / 2 + (x - cx) * s, y: (y) => canvas.height / 2 - (y - cy) * s };
}

function grid(ctx, canvas, xf) {
  const span = canvas.width / xf.s;
  const step = [1e3, 2e3, 5e3, 1e4, 2e4, 5e4, 1e5].find((v) => span / v < 12) || 2e5;
  ctx.strokeStyle = "#1b2834"; ctx.fillStyle = "#4b6075"; ctx.lineWidth = 1; ctx.font = "10px sans-serif";
  const inv = (px) => (px - xf.x(0)) / xf.s, invy = (py) => -(py - xf.y(0)) / xf.s;
  for (let v = Math.ceil(inv(0) / step) * step; v < inv(canvas.width); v += step) {
    ctx.beginPath(); ctx.moveTo(xf.x(v), 0); ctx.lineTo(xf.x(v), canvas.height); ctx.stroke();
    ctx.fillText(`${v / 1000} km`, xf.x(v) + 2, canvas.height - 4);
  }
  for (let v = Math.ceil(invy(canvas.height) / step) * step; v < invy(0); v += step) {
    ctx.beginPath(); ctx.moveTo(0, xf.y(v)); ctx.lineTo(canvas.width, xf.y(v)); ctx.stroke();
    ctx.fillText(`${v / 1000} km`, 2, xf.y(v) - 2);
  }
}

function ellipse(ctx, xf, x, y, e) {
  // e = [a, b, angle counter-clockwise from East]; canvas y points down: rotate by -angle
  ctx.beginPath();
  ctx.ellipse(xf.x(x), xf.y(y), Math.max(e[0] * xf.s, 0.5), Math.max(e[1] * xf.s, 0.5), -e[2], 0, 2 * Math.PI);
  ctx.stroke();
}

function drawPlan(geo, g) {
  const canvas = $("plan"), ctx = canvas.getContext("2d");
  const box = extent ? extent.slice() : [Infinity, -Infinity, Infinity, -Infinity];
  geo.bases.forEach((b) => { grow(box, b.tx[0], b.tx[1]); grow(box, b.rx[0], b.rx[1]); });
  g.tracks.forEach((k) => grow(box, k.x[0], k.x[2]));
  if (!isFinite(box[0])) { grow(box, -5e4, -5e4); grow(box, 5e4, 5e4); }
  extent = box;
  const xf = planXf = transform(canvas, box);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  grid(ctx, canvas, xf);
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
      arcs.arcs.forEach((a) => {
        ctx.beginPath();
        a.pts.forEach((p, j) => (j ? ctx.lineTo(xf.x(p[0]), xf.y(p[1])) : ctx.moveTo(xf.x(p[0]), xf.y(p[1]))));
        ctx.stroke();
      });
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
    ctx.strokeStyle = "#5c6bc0"; ctx.lineWidth = 1.5;
    truth.x.forEach((x, i) => {
      const px = xf.x(x), py = xf.y(truth.y[i]);
      ctx.beginPath(); ctx.moveTo(px - 5, py - 5); ctx.lineTo(px + 5, py + 5);
      ctx.moveTo(px - 5, py + 5); ctx.lineTo(px + 5, py - 5); ctx.stroke();
    });
  }
  g.tracks.forEach((k) => drawTrack(ctx, xf, k));
}

function drawTrack(ctx, xf, k) {
  const c = COLOURS[k.status] || "#fff", x = k.x[0], y = k.x[2], px = xf.x(x), py = xf.y(y);
  ctx.strokeStyle = c; ctx.fillStyle = c; ctx.lineWidth = 1.5;
  if (layer("trails") && k.trail.length > 1) {
    ctx.globalAlpha = 0.55; ctx.beginPath();
    k.trail.forEach((p, j) => (j ? ctx.lineTo(xf.x(p[0]), xf.y(p[1])) : ctx.moveTo(xf.x(p[0]), xf.y(p[1]))));
    ctx.stroke(); ctx.globalAlpha = 1;
  }
  if (layer("ellipses")) ellipse(ctx, xf, x, y, k.ell);
  ctx.beginPath(); ctx.arc(px, py, 4, 0, 2 * Math.PI); ctx.fill();
  ctx.beginPath(); ctx.moveTo(px, py); ctx.lineTo(xf.x(x + k.x[1] * LEAD_S), xf.y(y + k.x[3] * LEAD_S)); ctx.stroke();
  if (k.amb) {
    ctx.strokeStyle = AMBIGUOUS; ctx.setLineDash([3, 3]);
    ctx.beginPath(); ctx.arc(px, py, 10, 0, 2 * Math.PI); ctx.stroke(); ctx.setLineDash([]);
  }
  if (k.id === selected) {
    ctx.strokeStyle = "#ffffff"; ctx.beginPath(); ctx.arc(px, py, 14, 0, 2 * Math.PI); ctx.stroke();
  }
  ctx.fillStyle = c; ctx.font = "bold 12px sans-serif";
  ctx.fillText(`${k.id}${k.amb ? "?" : ""}`, px + 7, py - 7);
}

$("plan").addEventListener("click", (ev) => {
  const g = topics.gtracks;
  if (!g || !planXf) return;
  const r = ev.target.getBoundingClientRect(), sx = ev.target.width / r.width;
  const cx = (ev.clientX - r.left) * sx, cy = (ev.clientY - r.top) * sx;
  let best = null, bestD = 15;
  g.tracks.forEach((k) => {
    const d = Math.hypot(planXf.x(k.x[0]) - cx, planXf.y(k.x[2]) - cy);
    if (d < bestD) { best = k.id; bestD = d; }
  });
  select(best);
});
["trails", "ellipses", "arcs", "truth"].forEach((n) => $("layer-" + n).addEventListener("change", render));

function select(id) { selected = id; render(); }

function course(vx, vy) { return ((Math.atan2(vx, vy) * 180 / Math.PI) + 360) % 360; }

function trackTable(tracks) {
  const body = $("tracks");
  body.replaceChildren(...tracks.map((k) => {
    const tr = document.createElement("tr");
    tr.dataset.id = k.id; tr.dataset.status = k.status; tr.dataset.x = k.x[0]; tr.dataset.y = k.x[2];
    tr.className = `status-${k.status}${k.amb ? " ambiguous" : ""}${k.id === selected ? " selected" : ""}`;
    const v = Math.hypot(k.x[1], k.x[3]);
    [k.id, k.status, km(k.x[0]), km(k.x[2]), km(k.x[4]), v.toFixed(0), course(k.x[1], k.x[3]).toFixed(0)]
      .forEach((c) => { const td = document.createElement("td"); td.textContent = c; tr.appendChild(td); });
    tr.addEventListener("click", () => select(k.id));
    return tr;
  }));
}

function details(k) {
  const el = $("details");
  el.dataset.id = k ? k.id : "";
  if (!k) { el.textContent = selected === null ? "none: click a track on the plan or in the list" : `track ${selected} is gone`; return; }
  const s = k.sig, x = k.x;
  el.textContent = [
    `track ${k.id}  ${k.status}${k.amb ? "  AMBIGUOUS" : ""}`,
    `position  x ${km(x[0])} km  y ${km(x[2])} km  z ${km(x[4])} km`,
    `velocity  vx ${x[1].toFixed(1)}  vy ${x[3].toFixed(1)}  vz ${x[5].toFixed(1)} m/s`,
    `          ${Math.hypot(x[1], x[3]).toFixed(1)} m/s, course ${course(x[1], x[3]).toFixed(1)} deg`,
    `sigmas    x ${s[0].toFixed(0)}  y ${s[2].toFixed(0)}  z ${s[4].toFixed(0)} m`,
    `          vx ${s[1].toFixed(1)}  vy ${s[3].toFixed(1)}  vz ${s[5].toFixed(1)} m/s`,
    `2-sigma   ${k.ell[0].toFixed(0)} x ${k.ell[1].toFixed(0)} m`,
    `etracks   ${k.et.map((e) => `${e[0]}:${e[1]}`).join(" ") || "none"}`,
    `score     ${k.score}`,
    `history   ${k.n} updates drawn, trail ${k.trail.length} points`,
  ].join("\n");
}

// ---- sonar: waterfall and TMA plan per array ----
function arrayPanel(id) {
  let el = $(`array-${id}`);
  if (el) return el;
  const host = $("arrays");
  host.querySelectorAll(".quiet").forEach((q) => q.remove());
  el = document.createElement("div");
  el.className = "array"; el.id = `array-${id}`;
  el.innerHTML = `<h3>array ${id}</h3><div><div class="quiet">bearing-time waterfall (detections, bearing tracks)</div>` +
    `<canvas class="waterfall" width="560" height="320"></canvas></div>` +
    `<div><div class="quiet">TMA: own ship, solutions, 2-sigma ellipses, course and speed</div>` +
    `<canvas class="tma" width="420" height="320"></canvas></div>`;
  host.appendChild(el);
  return el;
}

function sonar() {
  Object.keys(topics).filter((n) => n.startsWith("waterfall/") || n.startsWith("tma/")).forEach((n) => {
    const id = n.split("/")[1], panel = arrayPanel(id);
    if (n.startsWith("waterfall/")) waterfall(panel.querySelector(".waterfall"), topics[n]);
    else tmaPlan(panel.querySelector(".tma"), topics[n], topics[`truth_sonar/${id}`]);
  });
}

function waterfall(canvas, w) {
  const ctx = canvas.getContext("2d"), W = canvas.width, H = canvas.height - 14;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  if (!w.rows.length) return;
  const t1 = w.rows[w.rows.length - 1][0], t0 = Math.min(w.rows[0][0], t1 - 1);
  const X = (b) => b / 360 * W, Y = (t) => (t1 - t) / (t1 - t0) * H;  // newest at the top
  ctx.fillStyle = "#4b6075"; ctx.font = "10px sans-serif";
  for (let b = 0; b <= 360; b += 45) { ctx.fillRect(X(b), 0, 1, H); ctx.fillText(`${b}`, Math.min(X(b) + 2, W - 18), H + 11); }
  ctx.fillStyle = "#cfd8dc";
  w.rows.forEach(([t, brgs]) => brgs.forEach((b) => ctx.fillRect(X(b) - 1, Y(t) - 1, 2, 2)));
  const dt = w.rows.length > 1 ? (t1 - w.rows[0][0]) / (w.rows.length - 1) : 1;
  Object.entries(w.tracks).forEach(([id, pts]) => {
    // confirmed stretches as lines (broken at gaps of 3 scans and through North),
    // tentative estimates as small marks
    ctx.strokeStyle = COLOURS.confirmed; ctx.fillStyle = COLOURS.tentative; ctx.lineWidth = 1.5;
    ctx.beginPath();
    pts.forEach((p, j) => {
      const q = pts[j - 1];
      if (!p[2]) { ctx.fillRect(X(p[1]) - 1.5, Y(p[0]) - 0.5, 3, 1); return; }
      const join = q && q[2] && p[0] - q[0] <= 3 * dt && Math.abs(p[1] - q[1]) <= 180;
      join ? ctx.lineTo(X(p[1]), Y(p[0])) : ctx.moveTo(X(p[1]), Y(p[0]));
    });
    ctx.stroke();
    const last = pts[pts.length - 1];
    if (last[2]) { ctx.fillStyle = COLOURS.confirmed; ctx.fillText(id, X(last[1]) + 3, Y(last[0]) + 10); }
  });
}

function tmaPlan(canvas, tma, truth) {
  const ctx = canvas.getContext("2d");
  const box = [Infinity, -Infinity, Infinity, -Infinity];
  tma.own.forEach((p) => grow(box, p[0], p[1]));
  tma.sols.forEach((s) => { grow(box, s.x - s.ell[0], s.y - s.ell[0]); grow(box, s.x + s.ell[0], s.y + s.ell[0]); });
  if (truth) truth.x.forEach((x, i) => grow(box, x, truth.y[i]));
  if (!isFinite(box[0])) return;
  const xf = transform(canvas, box);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  grid(ctx, canvas, xf);
  ctx.strokeStyle = "#e0e0e0"; ctx.lineWidth = 1.5; ctx.beginPath();
  tma.own.forEach((p, j) => (j ? ctx.lineTo(xf.x(p[0]), xf.y(p[1])) : ctx.moveTo(xf.x(p[0]), xf.y(p[1]))));
  ctx.stroke();
  if (truth) {
    ctx.strokeStyle = "#5c6bc0";
    truth.x.forEach((x, i) => { const px = xf.x(x), py = xf.y(truth.y[i]);
      ctx.beginPath(); ctx.moveTo(px - 4, py - 4); ctx.lineTo(px + 4, py + 4); ctx.moveTo(px - 4, py + 4); ctx.lineTo(px + 4, py - 4); ctx.stroke(); });
  }
  tma.sols.forEach((s) => {
    const c = s.constrained ? "#4fc3f7" : COLOURS.confirmed;
    ctx.strokeStyle = c; ctx.fillStyle = c;
    ellipse(ctx, xf, s.x, s.y, s.ell);
    ctx.beginPath(); ctx.arc(xf.x(s.x), xf.y(s.y), 3.5, 0, 2 * Math.PI); ctx.fill();
    ctx.beginPath(); ctx.moveTo(xf.x(s.x), xf.y(s.y));
    ctx.lineTo(xf.x(s.x + s.vx * TMA_LEAD_S), xf.y(s.y + s.vy * TMA_LEAD_S)); ctx.stroke();
    ctx.font = "11px sans-serif";
    ctx.fillText(`${s.track}: ${km(s.range)} km ${s.course.toFixed(0)}\u00b0 ${(s.speed * 1.9438).toFixed(1)} kn`,
      xf.x(s.x) + 6, xf.y(s.y) - 6);
  });
}

// ---- services: the table of pfusion status, red when a liveliness token is gone ----
function services() {
  const rows = (topics.services || { rows: [] }).rows;
  $("service-rows").replaceChildren(...rows.map((r) => {
    const tr = document.createElement("tr");
    tr.dataset.service = r.service; tr.dataset.instance = r.instance;
    tr.className = r.alive ? "alive" : "dead";
    const has = r.in !== undefined;
    [r.service, r.instance, r.alive ? "yes" : "GONE", ...(has
      ? [r.in, r.out, r.rejected, r.missed, r.p50.toFixed(2), r.p99.toFixed(2), r.queue, r.t.toFixed(1)]
      : Array(8).fill("-"))].forEach((c) => { const td = document.createElement("td"); td.textContent = c; tr.appendChild(td); });
    if (has && r.rejected) tr.title = Object.entries(r.reasons).map(([k, v]) => `${k}=${v}`).join(", ");
    return tr;
  }));
}

connect();
