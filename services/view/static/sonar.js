// passive-fusion live view: per sonar array, the bearing-time waterfall (time axis on the
// left in min:s of message time, newest at the top; bearing axis below) and the TMA
// plan with its legend; labels kept inside their canvas (view.js label). docs/view.md.
"use strict";

const CONSTRAINED = "#CC79A7";  // Okabe-Ito reddish purple: a constrained TMA solution
const AXIS_L = 50, AXIS_B = 26;  // waterfall margins (px): time axis, bearing axis

function arrayPanel(id) {
  let el = $(`array-${id}`);
  if (el) return el;
  const host = $("arrays");
  host.querySelectorAll(".quiet").forEach((q) => q.remove());
  el = document.createElement("div");
  el.className = "array"; el.id = `array-${id}`;
  el.innerHTML = `<h3>array ${id}</h3><div><div class="quiet">bearing-time waterfall (detections, bearing tracks) ` +
    `<span class="age" data-topic="waterfall/${id}"></span></div>` +
    `<canvas class="waterfall" width="560" height="340"></canvas></div>` +
    `<div><div class="quiet">TMA: own ship, solutions, 2-sigma ellipses, course and speed ` +
    `<span class="age" data-topic="tma/${id}"></span> <button class="fit">fit all</button></div>` +
    `<canvas class="tma" width="420" height="340"></canvas>` +
    `<div class="legend tma-legend"><span class="sw" style="color:#e0e0e0">&#x2500;</span>own ship ` +
    `<span class="sw" style="color:${COLOURS.confirmed}">&#x25cf;</span>TMA ` +
    `<span class="sw" style="color:${CONSTRAINED}">&#x25cf;</span>constrained TMA ` +
    `<span class="sw" style="color:${PALETTE.truth}">&times;</span>truth ` +
    `<span class="sw">&#x2504;</span>bearing (range unobservable); ellipse 2&sigma;, vector 10 min</div>` +
    `<div class="sols"></div></div>`;
  host.appendChild(el);
  el.querySelector(".fit").addEventListener("click", () => fitAll(el.querySelector(".tma")));
  return el;
}

function sonar() {
  Object.keys(topics).filter((n) => n.startsWith("waterfall/") || n.startsWith("tma/")).forEach((n) => {
    const id = n.split("/")[1], panel = arrayPanel(id);
    if (n.startsWith("waterfall/")) waterfall(panel.querySelector(".waterfall"), topics[n]);
    else tmaPlan(panel.querySelector(".tma"), topics[n], topics[`truth_sonar/${id}`]);
  });
}

// Time ticks of the waterfall: a round step (s) giving at most ~8 ticks over [t0, t1] s
const TIME_STEPS_S = [1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200];
function timeTicks(t0, t1) {
  const step = TIME_STEPS_S.find((s) => (t1 - t0) / s <= 8) || 3600 * Math.ceil((t1 - t0) / 8 / 3600), out = [];
  for (let t = Math.ceil(t0 / step) * step; t <= t1 && out.length < 40; t += step) out.push(t);
  return out;
}

const mss = (t) => `${Math.floor(t / 60)}:${String(Math.round(t % 60)).padStart(2, "0")}`;

// The detections of a waterfall as pixels (2 x 2 each, #cfd8dc) in one buffer, put on an
// offscreen canvas and blitted (24,000 fillRect calls a frame otherwise). Little-endian
// RGBA words, as every browser's.
const DOT = 0xffdcd8cf;
function dotLayer(canvas, w, X, Y, W, H) {
  const c = canvas.dots || (canvas.dots = { el: document.createElement("canvas"), img: null });
  if (c.el.width !== W || c.el.height !== H) { c.el.width = W; c.el.height = H; c.img = null; }
  c.img = c.img || new ImageData(W, H);
  const px = new Uint32Array(c.img.data.buffer);
  px.fill(0);
  for (const [t, brgs] of w.rows) {
    const y = Math.round(Y(t)) - 1;
    for (const b of brgs) {
      const x = Math.round(X(b) - AXIS_L) - 1;
      for (let dy = 0; dy < 2; dy++) {
        if (y + dy < 0 || y + dy >= H) continue;
        if (x >= 0 && x < W) px[(y + dy) * W + x] = DOT;
        if (x + 1 >= 0 && x + 1 < W) px[(y + dy) * W + x + 1] = DOT;
      }
    }
  }
  c.el.getContext("2d").putImageData(c.img, 0, 0);
  return c.el;
}

function waterfall(canvas, w) {
  if (unchanged(canvas, [w])) return;
  const ctx = canvas.getContext("2d"), W = canvas.width - AXIS_L, H = canvas.height - AXIS_B;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  canvas.labels = [];
  if (!w.rows.length) return;
  const t1 = w.rows[w.rows.length - 1][0], t0 = Math.min(w.rows[0][0], t1 - 1);
  const X = (b) => AXIS_L + b / 360 * W, Y = (t) => (t1 - t) / (t1 - t0) * H;  // newest at the top
  canvas.axis = { t0, t1, top: t1, bottom: t0 };
  ctx.fillStyle = "#4b6075"; ctx.strokeStyle = "#1b2834"; ctx.font = "10px sans-serif";
  for (let b = 0; b <= 360; b += 45) { ctx.fillRect(X(b), 0, 1, H); label(ctx, canvas, `${b}`, X(b) - 6, H + 11); }
  label(ctx, canvas, "true bearing (deg)", AXIS_L + W / 2 - 40, H + 23);
  timeTicks(t0, t1).forEach((t) => {
    ctx.fillRect(AXIS_L - 4, Y(t), W + 4, 1);
    label(ctx, canvas, mss(t), AXIS_L - 6 - ctx.measureText(mss(t)).width, Y(t) + 4);
  });
  ctx.save(); ctx.translate(10, H / 2 + 60); ctx.rotate(-Math.PI / 2); ctx.fillText("time (min:s), newest at top", 0, 0); ctx.restore();
  ctx.drawImage(dotLayer(canvas, w, X, Y, W, H), AXIS_L, 0);
  bearingTracks(ctx, canvas, w, X, Y, t1);
}

// Confirmed stretches as lines (broken at gaps of 3 scans and through North) in one path,
// tentative estimates as small marks in another, then the ids of the confirmed tracks.
function bearingTracks(ctx, canvas, w, X, Y, t1) {
  const dt = w.rows.length > 1 ? (t1 - w.rows[0][0]) / (w.rows.length - 1) : 1, marks = new Path2D(), ends = [];
  ctx.strokeStyle = COLOURS.confirmed; ctx.lineWidth = 1.5;
  ctx.beginPath();
  Object.entries(w.tracks).forEach(([id, pts]) => {
    pts.forEach((p, j) => {
      const q = pts[j - 1];
      if (!p[2]) { marks.rect(X(p[1]) - 1.5, Y(p[0]) - 0.5, 3, 1); return; }
      const join = q && q[2] && p[0] - q[0] <= 3 * dt && Math.abs(p[1] - q[1]) <= 180;
      join ? ctx.lineTo(X(p[1]), Y(p[0])) : ctx.moveTo(X(p[1]), Y(p[0]));
    });
    const last = pts[pts.length - 1];
    if (last[2]) ends.push([id, last]);
  });
  ctx.stroke();
  ctx.fillStyle = COLOURS.tentative; ctx.fill(marks);
  ctx.fillStyle = COLOURS.confirmed;
  ends.forEach(([id, last]) => label(ctx, canvas, id, X(last[1]) + 3, Y(last[0]) + 10));
}

function tmaPlan(canvas, tma, truth) {
  const ctx = canvas.getContext("2d"), n = nav(canvas);
  if (unchanged(canvas, [tma, truth, unit, vunit, n.auto, n.cx, n.cy, n.s])) return;
  // an unobservable range leaves the solution's position out of the extent
  const pts = tma.sols.filter((s) => s.range_obs !== false).map((s) => [s.x, s.y]);
  if (truth) truth.x.forEach((x, i) => pts.push([x, truth.y[i]]));
  const box = robustBox(tma.own, pts, FLOOR_M.tma) || [-1e4, 1e4, -1e4, 1e4];
  const xf = transform(canvas, box, null);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  canvas.labels = [];
  grid(ctx, canvas, xf);
  ctx.strokeStyle = "#e0e0e0"; ctx.lineWidth = 1.5;
  polyline(ctx, xf, tma.own);
  if (truth) {
    ctx.strokeStyle = PALETTE.truth;
    crosses(ctx, xf, truth, 4);
  }
  const own = tma.own.length ? tma.own[tma.own.length - 1] : [0, 0], far = 2 * canvas.width / xf.s;
  ctx.font = "11px sans-serif";
  [false, true].forEach((constrained) => {  // one path per colour and shape
    const sols = tma.sols.filter((s) => !!s.constrained === constrained);
    if (sols.length) solutions(ctx, xf, sols, constrained ? CONSTRAINED : COLOURS.confirmed, own, far);
  });
  const lines = tma.sols.map((s) => {
    const range = s.range_obs === false ? "range unobservable" : `${dist(s.range)} ${unit}`;
    const text = `${s.track}: ${range} ${num(s.course, 0)}\u00b0 ${spd(s.speed, 1)} ${vunit}`;
    const px = xf.x(s.x), py = xf.y(s.y);
    ctx.fillStyle = s.constrained ? CONSTRAINED : COLOURS.confirmed;
    if (fin(px) && fin(py)) label(ctx, canvas, text, px + 6, py - 6);
    return text;
  });
  scaleBar(ctx, canvas, xf);
  // the same lines under the plan: a solution off the canvas is still read
  const list = canvas.parentElement.querySelector(".sols");
  if (list.dataset.text !== lines.join("\n")) {
    list.dataset.text = lines.join("\n");
    list.replaceChildren(...lines.map((t) => Object.assign(document.createElement("div"), { textContent: t })));
  }
}

// TMA solutions of one colour: where the range is unobservable the bearing, dashed from
// own ship; the 2-sigma ellipses; the positions; the 10 min course and speed vectors.
function solutions(ctx, xf, sols, colour, own, far) {
  ctx.strokeStyle = colour; ctx.fillStyle = colour;
  const blind = sols.filter((s) => s.range_obs === false && fin(s.x) && fin(s.y));
  if (blind.length) {
    ctx.setLineDash([6, 4]); ctx.beginPath();
    blind.forEach((s) => {
      const b = Math.atan2(s.x - own[0], s.y - own[1]);
      ctx.moveTo(xf.x(own[0]), xf.y(own[1]));
      ctx.lineTo(xf.x(own[0] + far * Math.sin(b)), xf.y(own[1] + far * Math.cos(b)));
    });
    ctx.stroke(); ctx.setLineDash([]);
  }
  ellipses(ctx, xf, sols.map((s) => [s.x, s.y, s.ell]));
  const dots = new Path2D(), vectors = new Path2D();
  sols.forEach((s) => {
    const px = xf.x(s.x), py = xf.y(s.y), qx = xf.x(s.x + s.vx * TMA_LEAD_S), qy = xf.y(s.y + s.vy * TMA_LEAD_S);
    if (!fin(px) || !fin(py)) return;
    dots.moveTo(px + 3.5, py); dots.arc(px, py, 3.5, 0, 2 * Math.PI);
    if (fin(qx) && fin(qy)) { vectors.moveTo(px, py); vectors.lineTo(qx, qy); }
  });
  ctx.fill(dots); ctx.stroke(vectors);
}
