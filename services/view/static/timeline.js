// passive-fusion view, time: pause the picture and scrub back over its last HISTORY_S
// seconds (docs/view.md "Time"). The page records every message's data topics as a
// frame; a frame holds compact typed arrays (one array per field for all tracks, not one
// object per track per frame) and shares the parts that did not change with the frame
// before it. The history is bounded twice: by age (HISTORY_S of page time) and by size
// (BUDGET_B bytes of parts, the oldest frames go first). While paused the data panels
// show the chosen frame and messages keep being recorded; "live" goes back. A frame's
// trails are rebuilt from the frames before it (view_model.py's rule: one point per
// TRAIL_DT s of message time, TRAIL points), its waterfall from the recorded scans.
"use strict";

const timeline = (() => {
  const HISTORY_S = 600;
  const BUDGET_B = 300e6;
  const TRAIL = 30, TRAIL_DT = 1.0;  // view_model.py TRAIL, TRAIL_DT
  const ROWS = 240;                  // view_model.py ROWS: waterfall scans shown
  const KEPT = /^(gtracks|etracks\/|truth_radar|waterfall\/|tma\/|truth_sonar\/)/;
  const TIMES = 4096;                // frame times kept for the readout
  const names = [];                  // status and base names <-> small codes
  const frames = [];                 // {t: page time s, parts: {topic: part}}, oldest first
  const live = {};                   // the latest state of every data topic
  const scans = new Map();           // array -> {rows: [[t, Float32Array]], series: Map, last}
  const cache = new Map();           // topic -> [part, unpacked] of the last seek
  const drawn = [];                  // recent frame times (ms)
  let bytes = 0, paused = false, at = null, lastMs = NaN, pruned = 0;
  const clock = () => (performance.timeOrigin + performance.now()) / 1000;
  const code = (s) => { let i = names.indexOf(s); if (i < 0) i = names.push(s) - 1; return i; };
  const f32 = (a) => Float32Array.from(a, (v) => (v === null ? NaN : v));
  const arr = (a, i, n) => Array.from(a.subarray(i, i + n));
  const size = (p) => Object.values(p).reduce((b, v) => b + (ArrayBuffer.isView(v) ? v.byteLength : 8), 64);

  // ---- packing: one part per topic version ----
  function packTracks(g) {
    const ks = g.tracks, n = ks.length, off = new Int32Array(n + 1), eb = [], ei = [];
    const p = { t: g.t, id: new Int32Array(n), st: new Uint8Array(n), amb: new Uint8Array(n),
      x: new Float32Array(6 * n), sig: new Float32Array(6 * n), ell: new Float32Array(3 * n).fill(NaN),
      score: new Float32Array(n), seen: new Int32Array(n), off };
    ks.forEach((k, i) => {
      p.id[i] = k.id; p.st[i] = code(k.status); p.amb[i] = k.amb ? 1 : 0;
      p.x.set(f32(k.x), 6 * i); p.sig.set(f32(k.sig), 6 * i);
      if (k.ell) p.ell.set(f32(k.ell), 3 * i);
      p.score[i] = k.score; p.seen[i] = k.n;
      k.et.forEach(([b, e]) => { eb.push(code(b)); ei.push(e); });
      off[i + 1] = eb.length;
    });
    Object.assign(p, { eb: Uint16Array.from(eb), ei: Int32Array.from(ei) });
    p.bytes = size(p);
    return p;
  }

  function packArcs(e) {
    const n = e.arcs.length, off = new Int32Array(n + 1);
    e.arcs.forEach((a, i) => { off[i + 1] = off[i] + a.pts.length; });
    const pts = new Float32Array(2 * off[n]);
    e.arcs.forEach((a, i) => a.pts.forEach((q, j) => pts.set(f32(q), 2 * (off[i] + j))));
    const p = { t: e.t, id: Int32Array.from(e.arcs, (a) => a.id), st: Uint8Array.from(e.arcs, (a) => code(a.status)),
      amb: Uint8Array.from(e.arcs, (a) => (a.amb ? 1 : 0)), off, pts };
    p.bytes = size(p);
    return p;
  }

  function packTruth(s) {
    const p = { t: s.t, id: Int32Array.from(s.id), x: f32(s.x), y: f32(s.y) };
    p.bytes = size(p);
    return p;
  }

  // A waterfall version adds its new scans and bearing-track points to the array's
  // record; the part only says up to which scan time it showed.
  function packScans(name, w) {
    const newest = w.rows.length ? w.rows[w.rows.length - 1][0] : -Infinity;
    let h = scans.get(name);
    if (!h || newest < h.last) { h = { rows: [], series: new Map(), last: -Infinity }; scans.set(name, h); }
    w.rows.forEach(([t, b]) => { if (t > h.last) h.rows.push([t, f32(b)]); });
    Object.entries(w.tracks).forEach(([id, pts]) => {
      let s = h.series.get(id);
      if (!s) { s = []; h.series.set(id, s); }
      const from = s.length ? s[s.length - 3] : -Infinity;
      let j = pts.length;
      while (j > 0 && pts[j - 1][0] > from) j--;
      for (; j < pts.length; j++) s.push(pts[j][0], pts[j][1], pts[j][2]);
    });
    h.last = Math.max(h.last, newest);
    return { t: newest, h, bytes: 0 };
  }

  function pack(name, state) {
    if (name === "gtracks") return packTracks(state);
    if (name === "truth_radar") return packTruth(state);
    if (name.startsWith("etracks/")) return packArcs(state);
    if (name.startsWith("waterfall/")) return packScans(name, state);
    // TMA and sonar truth: a few objects per version, kept as received
    const n = name.startsWith("tma/") ? 2 * state.own.length + 16 * state.sols.length : 3 * state.id.length;
    return { obj: state, bytes: 16 * n + 64 };
  }

  // ---- unpacking: the topic's state as the view model sent it ----
  function trails(p, k) {  // the trail of each track of part p, from frames up to index k
    const row = new Map(), out = Array.from(p.id, () => []), last = new Float64Array(p.id.length).fill(-Infinity);
    p.id.forEach((id, i) => row.set(id, i));
    const win = [];
    for (let j = k, prev = null; j >= 0; j--) {
      const q = frames[j].parts.gtracks;
      if (!q || q === prev) continue;
      if (q.t < p.t - (TRAIL + 1) * TRAIL_DT) break;
      if (q.t <= p.t) win.push(q);
      prev = q;
    }
    win.reverse().forEach((q) => q.id.forEach((id, j) => {
      const i = row.get(id), x = q.x[6 * j], y = q.x[6 * j + 2];
      if (i === undefined || q.t < last[i] + TRAIL_DT || !Number.isFinite(x) || !Number.isFinite(y)) return;
      out[i].push([Math.round(x), Math.round(y)]); last[i] = q.t;
    }));
    return out.map((tr) => tr.slice(-TRAIL));
  }

  function unpackTracks(p, k) {
    const tr = trails(p, k);
    return { t: p.t, tracks: Array.from(p.id, (id, i) => ({
      id, status: names[p.st[i]], amb: p.amb[i] === 1, x: arr(p.x, 6 * i, 6), sig: arr(p.sig, 6 * i, 6),
      ell: arr(p.ell, 3 * i, 3), score: p.score[i], n: p.seen[i], trail: tr[i],
      et: Array.from(p.eb.subarray(p.off[i], p.off[i + 1]), (b, j) => [names[b], p.ei[p.off[i] + j]]) })) };
  }

  function unpackArcs(p) {
    return { t: p.t, arcs: Array.from(p.id, (id, i) => ({ id, status: names[p.st[i]], amb: p.amb[i] === 1,
      pts: Array.from({ length: p.off[i + 1] - p.off[i] }, (_, j) => arr(p.pts, 2 * (p.off[i] + j), 2)) })) };
  }

  function unpackScans(p) {
    const rows = p.h.rows;
    let hi = rows.length;  // first scan after p.t
    for (let lo = 0; lo < hi;) { const m = (lo + hi) >> 1; if (rows[m][0] <= p.t) lo = m + 1; else hi = m; }
    const shown = rows.slice(Math.max(0, hi - ROWS), hi), since = shown.length ? shown[0][0] : p.t;
    const tracks = {};
    p.h.series.forEach((s, id) => {
      const pts = [];
      for (let j = 0; j < s.length; j += 3) if (s[j] >= since && s[j] <= p.t) pts.push([s[j], s[j + 1], s[j + 2]]);
      if (pts.length) tracks[id] = pts;
    });
    return { rows: shown.map(([t, b]) => [t, Array.from(b)]), tracks };
  }

  function unpack(name, p, k) {
    if (p.obj) return p.obj;
    if (name === "gtracks") return unpackTracks(p, k);
    if (name === "truth_radar") return { t: p.t, id: Array.from(p.id), x: Array.from(p.x), y: Array.from(p.y) };
    return name.startsWith("etracks/") ? unpackArcs(p) : unpackScans(p);
  }

  // ---- the record: bounded by age and by bytes ----
  function evict(now) {
    while (frames.length > 1 && (frames[0].t < now - HISTORY_S || bytes > BUDGET_B)) {
      const [old] = frames.splice(0, 1), next = frames[0].parts;
      Object.entries(old.parts).forEach(([n, p]) => { if (next[n] !== p) bytes -= p.bytes; });
    }
    if (now - pruned < 1.0) return;
    pruned = now;
    scans.forEach((h, name) => {  // keep the scans the oldest frame can show
      const ref = frames[0].parts[name], t0 = ref && ref.h === h ? ref.t : h.last;
      const i = h.rows.findIndex((r) => r[0] >= t0);
      if (i > ROWS) h.rows.splice(0, i - ROWS);
      const since = h.rows.length ? h.rows[0][0] : h.last;
      h.series.forEach((s, id) => {
        let j = 0;
        while (j < s.length && s[j] < since) j += 3;
        if (j >= s.length) h.series.delete(id); else if (j) s.splice(0, j);
      });
    });
  }

  function scanBytes() {
    let b = 0;
    scans.forEach((h) => {
      h.rows.forEach((r) => { b += r[1].byteLength + 48; });
      h.series.forEach((s) => { b += 8 * s.length + 48; });
    });
    return b;
  }

  // A message's topics: the data ones are recorded (a new frame) and shown unless paused,
  // the others (geometry, services, link) always shown.
  function take(msgTopics, now = clock()) {
    const changed = {};
    Object.entries(msgTopics).forEach(([n, s]) => {
      if (!KEPT.test(n)) { topics[n] = s; return; }
      live[n] = s; changed[n] = pack(n, s); bytes += changed[n].bytes;
      if (!paused) topics[n] = s;
    });
    if (Object.keys(changed).length) {
      const prev = frames.length ? frames[frames.length - 1].parts : {};
      frames.push({ t: Math.max(now, frames.length ? frames[frames.length - 1].t : now), parts: { ...prev, ...changed } });
      evict(now);
    }
    bar();
  }

  // ---- what the operator does ----
  function indexAt(t) {  // the last frame at or before t (the first if none)
    let lo = 0, hi = frames.length;
    while (lo < hi) { const m = (lo + hi) >> 1; if (frames[m].t <= t) lo = m + 1; else hi = m; }
    return Math.max(lo - 1, 0);
  }

  function show() {
    const t0 = performance.now();
    render();
    lastMs = performance.now() - t0;
    bar();
  }

  function seek(t) {  // pause on the frame shown at page time t; returns the ms it took
    if (!frames.length) return NaN;
    const t0 = performance.now(), k = indexAt(t), f = frames[k];
    paused = true; at = f.t;
    Object.keys(topics).filter((n) => KEPT.test(n) && !(n in f.parts)).forEach((n) => delete topics[n]);
    Object.entries(f.parts).forEach(([n, p]) => {
      const c = cache.get(n);
      if (!c || c[0] !== p) cache.set(n, [p, unpack(n, p, k)]);
      topics[n] = cache.get(n)[1];
    });
    show();
    lastMs = performance.now() - t0;
    return lastMs;
  }

  function pause() { if (!paused && frames.length) { paused = true; at = frames[frames.length - 1].t; bar(); } }

  function goLive() {
    paused = false; at = null; cache.clear();
    Object.keys(topics).filter((n) => KEPT.test(n)).forEach((n) => delete topics[n]);
    Object.assign(topics, live);
    show();
  }

  function frameDone(ms) { if (drawn.push(ms) > TIMES) drawn.splice(0, drawn.length - TIMES); }

  // ---- the bar in the header ----
  const ui = document.createElement("span");
  ui.className = "timeline";
  ui.innerHTML = `<button id="tl-pause">pause</button> <button id="tl-live">live</button> ` +
    `<input type="range" id="tl-scrub" min="0" max="0" step="1" value="0" title="scrub back over the last 10 minutes"> ` +
    `<b id="tl-at" data-state="live">live</b> <span id="tl-info" class="quiet"></span>`;
  document.querySelector("header").appendChild(ui);
  const $t = (id) => document.getElementById(id);
  const hms = (t) => new Date(t * 1000).toISOString().slice(11, 19);

  function bar() {
    const s = $t("tl-scrub"), el = $t("tl-at");
    if (!frames.length) return;
    const t0 = frames[0].t, t1 = frames[frames.length - 1].t;
    s.min = t0; s.max = t1;
    s.value = paused ? at : t1;
    el.dataset.state = paused ? "paused" : "live";
    el.dataset.t = paused ? at : "";
    el.textContent = paused ? `paused at ${hms(at)} UTC (${(at - t1).toFixed(0)} s)` : "live";
    const sorted = drawn.slice(-200).sort((a, b) => a - b);
    const p99 = sorted.length ? sorted[Math.floor(0.99 * (sorted.length - 1))] : NaN;
    $t("tl-info").textContent = `history ${((t1 - t0) / 60).toFixed(1)} min, ${frames.length} frames, ` +
      `${((bytes + scanBytes()) / 1e6).toFixed(0)} MB; frame p99 ${Number.isFinite(p99) ? p99.toFixed(0) : "-"} ms`;
  }

  $t("tl-pause").addEventListener("click", pause);
  $t("tl-live").addEventListener("click", goLive);
  $t("tl-scrub").addEventListener("input", (ev) => seek(+ev.target.value));

  return { take, pause, seek, goLive, frameDone,
    get paused() { return paused; }, get lastMs() { return lastMs; }, get bytes() { return bytes + scanBytes(); },
    times: () => frames.map((f) => f.t), live: () => live, drawTimes: () => drawn.splice(0, drawn.length) };
})();
