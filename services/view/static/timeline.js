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
  const ARC_KEPT = 5;                // points kept of an elementary-track arc
  const KEPT = /^(gtracks|etracks\/|truth_radar|waterfall\/|tma\/|truth_sonar\/)/;
  const TIMES = 4096;                // frame times kept for the readout
  const names = [];                  // status and base names <-> small codes
  const frames = [];                 // {t: page time s, parts: {topic: part}}, oldest first
  const live = {};                   // the latest state of every data topic
  const scans = new Map();           // array -> {rows: [[t, Float32Array]], series: Map, last}
  const cache = new Map();           // topic -> [part, unpacked] of the last seek
  const drawn = [];                  // recent frame times (ms)
  const pending = [];                // [topic, part] not packed yet, oldest first
  const IDLE_MS = 1000;
  let bytes = 0, paused = false, at = null, lastMs = NaN, pruned = 0;
  const clock = () => (performance.timeOrigin + performance.now()) / 1000;
  const code = (s) => { let i = names.indexOf(s); if (i < 0) i = names.push(s) - 1; return i; };
  const f32 = (a) => Float32Array.from(a, (v) => (v === null ? NaN : v));
  const size = (p) => Object.values(p).reduce((b, v) => b + (ArrayBuffer.isView(v) ? v.byteLength : 8), 64);

  // ---- packing: one part per topic version ----
  function put(dst, i, src, n) {  // src[0..n) (null: NaN) into dst from i; NaN when src is null
    for (let j = 0; j < n; j++) dst[i + j] = src && src[j] !== null ? src[j] : NaN;
  }

  function packTracks(g) {
    const ks = g.tracks, n = ks.length, off = new Int32Array(n + 1), eb = [], ei = [];
    const p = { t: g.t, id: new Int32Array(n), st: new Uint8Array(n), amb: new Uint8Array(n),
      x: new Float32Array(6 * n), sig: new Float32Array(6 * n), ell: new Float32Array(3 * n),
      score: new Float32Array(n), seen: new Int32Array(n), off };
    for (let i = 0; i < n; i++) {
      const k = ks[i];
      p.id[i] = k.id; p.st[i] = code(k.status); p.amb[i] = k.amb ? 1 : 0;
      put(p.x, 6 * i, k.x, 6); put(p.sig, 6 * i, k.sig, 6); put(p.ell, 3 * i, k.ell, 3);
      p.score[i] = k.score; p.seen[i] = k.n;
      for (const [b, e] of k.et) { eb.push(code(b)); ei.push(e); }
      off[i + 1] = eb.length;
    }
    Object.assign(p, { eb: Uint16Array.from(eb), ei: Int32Array.from(ei) });
    p.bytes = size(p);
    return p;
  }

  // An arc keeps ARC_KEPT of its points, evenly spaced, first and last included (its
  // shape at the plan's scales; the history's largest part otherwise).
  function packArcs(e) {
    const n = e.arcs.length, off = new Int32Array(n + 1);
    e.arcs.forEach((a, i) => { off[i + 1] = off[i] + Math.min(a.pts.length, ARC_KEPT); });
    const pts = new Float32Array(2 * off[n]);
    e.arcs.forEach((a, i) => {
      const m = off[i + 1] - off[i], step = m > 1 ? (a.pts.length - 1) / (m - 1) : 0;
      for (let j = 0; j < m; j++) put(pts, 2 * (off[i] + j), a.pts[Math.round(j * step)], 2);
    });
    const p = { t: e.t, id: Int32Array.from(e.arcs, (a) => a.id), st: Uint8Array.from(e.arcs, (a) => code(a.status)),
      amb: Uint8Array.from(e.arcs, (a) => (a.amb ? 1 : 0)), off, pts };
    p.bytes = size(p);
    return p;
  }

  function packTruth(s) {
    const p = { t: s.t, id: Int32Array.from(s.id), x: new Float32Array(s.x.length), y: new Float32Array(s.y.length) };
    put(p.x, 0, s.x, s.x.length); put(p.y, 0, s.y, s.y.length);
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
      id, status: names[p.st[i]], amb: p.amb[i] === 1, x: p.x.subarray(6 * i, 6 * i + 6),
      sig: p.sig.subarray(6 * i, 6 * i + 6), ell: p.ell.subarray(3 * i, 3 * i + 3), score: p.score[i], n: p.seen[i], trail: tr[i],
      et: Array.from(p.eb.subarray(p.off[i], p.off[i + 1]), (b, j) => [names[b], p.ei[p.off[i] + j]]) })) };
  }

  function unpackArcs(p) {
    return { t: p.t, arcs: Array.from(p.id, (id, i) => ({ id, status: names[p.st[i]], amb: p.amb[i] === 1,
      pts: Array.from({ length: p.off[i + 1] - p.off[i] }, (_, j) => p.pts.subarray(2 * (p.off[i] + j), 2 * (p.off[i] + j) + 2)) })) };
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
      Object.entries(old.parts).forEach(([n, p]) => { if (next[n] !== p) { bytes -= p.bytes; p.gone = true; } });
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
  // the others (geometry, services, link) always shown. Packing waits for the page to be
  // idle (at most IDLE_MS), after the frame is drawn: a part is packed in place, so every
  // frame that shares it sees the packed form.
  function take(msgTopics, now = clock()) {
    const changed = {};
    Object.entries(msgTopics).forEach(([n, s]) => {
      if (!KEPT.test(n)) { topics[n] = s; return; }
      live[n] = s; changed[n] = { raw: s, bytes: 0 }; pending.push([n, changed[n]]);
      if (!paused) topics[n] = s;
    });
    if (Object.keys(changed).length) {
      const prev = frames.length ? frames[frames.length - 1].parts : {};
      frames.push({ t: Math.max(now, frames.length ? frames[frames.length - 1].t : now), parts: { ...prev, ...changed } });
      evict(now);
      if (pending.length === Object.keys(changed).length) requestIdleCallback(packPending, { timeout: IDLE_MS });
    }
    bar();
  }

  function packPending() {
    pending.splice(0).forEach(([n, part]) => {
      const raw = part.raw;
      delete part.raw;
      if (part.gone && !n.startsWith("waterfall/")) return;  // evicted before it was packed
      Object.assign(part, pack(n, raw));
      if (!part.gone) bytes += part.bytes;
    });
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
    packPending();
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
  let wanted = null;  // a drag's input events: one seek per animation frame, to the latest
  $t("tl-scrub").addEventListener("input", (ev) => {
    if (wanted === null) requestAnimationFrame(() => { const t = wanted; wanted = null; seek(t); });
    wanted = +ev.target.value;
  });

  return { take, pause, seek, goLive, frameDone, settle: packPending,
    get paused() { return paused; }, get lastMs() { return lastMs; }, get bytes() { return bytes + scanBytes(); },
    times: () => frames.map((f) => f.t), live: () => live, drawTimes: () => drawn.splice(0, drawn.length) };
})();
