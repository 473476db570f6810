// passive-fusion live view: the track tables (global radar tracks, sonar bearing
// tracks), sorted by a click on a header (again: reversed), filtered by a text box
// (rows whose text contains it), and the selected track's fields, the bases (or the
// array) that hold it and its recent history (docs/view.md). Uses view.js' helpers.
"use strict";

const HIST = 12;             // updates remembered per track for its history
const SPEEDS = { "m/s": 1, kn: 3600 / 1852 };
let vunit = "m/s";
const sorts = { g: { key: "id", dir: 1, filter: "" }, s: { key: "id", dir: 1, filter: "" } };
const hist = new Map();      // global track id -> [[t, x, y, z, speed, course, status]], newest last
let histT = -Infinity;       // message time of the last gtracks remembered
let selectedSonar = null;    // "array/id" of the selected sonar track

const spd = (v, d = 0) => (fin(v) ? (v * SPEEDS[vunit]).toFixed(d) : "-");

function remember(g) {       // once per new gtracks message (not on redraws)
  if (g.t === null || !(g.t > histT)) return;
  histT = g.t;
  const live = new Set();
  g.tracks.forEach((k) => {
    live.add(k.id);
    let h = hist.get(k.id);
    if (!h) hist.set(k.id, (h = []));
    h.push([g.t, k.x[0], k.x[2], k.x[4], speed(k.x[1], k.x[3]), course(k.x[1], k.x[3]), k.status]);
    if (h.length > HIST) h.shift();
  });
  [...hist.keys()].forEach((id) => { if (!live.has(id)) hist.delete(id); });
}

// Rows [{key, cells: () => texts, sortv: {col: value}, ...}] sorted and filtered by
// sorts[which]; cells are formatted only for the rows filtered or shown (10^4 tracks)
function arrange(which, rows) {
  const s = sorts[which], f = s.filter.trim().toLowerCase();
  const kept = f ? rows.filter((r) => r.cells().join(" ").toLowerCase().includes(f)) : rows.slice();
  const v = (r) => r.sortv[s.key];
  kept.sort((a, b) => {
    const x = v(a), y = v(b);
    if (x === y) return 0;
    if (!fin(x) && typeof x !== "string") return 1;  // no value: last either way
    if (!fin(y) && typeof y !== "string") return -1;
    return (x < y ? -1 : 1) * s.dir;
  });
  return kept;
}

// Rows updated in place: a row element per place, kept from frame to frame; a cell's
// text, a row's class and data attributes written only when they changed (500 rows
// rebuilt every message cost a frame 25-34 ms).
function fillTable(which, body, rows, more, onClick) {
  const n = Math.min(rows.length, MAX_ROWS);
  while (body.rows.length > n) body.lastElementChild.remove();
  for (let i = 0; i < n; i++) {
    const r = rows[i];
    let tr = body.rows[i];
    if (!tr) { tr = body.insertRow(); tr.addEventListener("click", () => onClick(tr.key)); }
    tr.key = r.key;
    for (const [k, v] of Object.entries(r.data)) if (tr.dataset[k] !== String(v)) tr.dataset[k] = v;
    if (tr.className !== r.cls) tr.className = r.cls;
    r.cells().forEach((c, j) => {
      const td = tr.cells[j] || tr.insertCell(), t = String(c);
      if (td.text !== t) { td.textContent = t; td.text = t; }
    });
  }
  more.textContent = rows.length > MAX_ROWS ? `first ${MAX_ROWS} of ${rows.length} tracks` : "";
  document.querySelectorAll(`th[data-table='${which}']`).forEach((th) => {
    th.dataset.sorted = th.dataset.key === sorts[which].key ? (sorts[which].dir > 0 ? "asc" : "desc") : "";
  });
}

const sortBy = (which) => [sorts[which].key, sorts[which].dir, sorts[which].filter, unit, vunit];

function trackTable(tracks) {
  remember(topics.gtracks || { t: null, tracks: [] });
  if (unchanged($("tracks"), [tracks, selected, ...sortBy("g")])) return;
  const rows = tracks.map((k) => {
    const sp = speed(k.x[1], k.x[3]), co = course(k.x[1], k.x[3]), bases = k.et.map((t) => t[0]);
    return {
      key: k.id,
      data: { id: k.id, status: k.status, x: k.x[0], y: k.x[2] },
      cls: `status-${k.status}${k.amb ? " ambiguous" : ""}${k.id === selected ? " selected" : ""}`,
      cells: () => [k.id, k.status, dist(k.x[0]), dist(k.x[2]), dist(k.x[4]), spd(sp), num(co, 0), bases.join(" ")],
      sortv: { id: k.id, status: k.status, x: k.x[0], y: k.x[2], z: k.x[4], speed: sp, course: co, bases: bases.join(" ") },
    };
  });
  fillTable("g", $("tracks"), arrange("g", rows), $("tracks-more"), select);
  $("unit-head").textContent = unit;
  $("speed-head").textContent = vunit;
}

function details(k) {
  const el = $("details");
  el.dataset.id = k ? k.id : "";
  el.dataset.sonar = "";
  if (selectedSonar !== null && selected === null) { sonarDetails(el); return; }
  if (!k) { el.textContent = selected === null ? "none: click a track on the plan or in a list" : `track ${selected} is gone`; return; }
  const s = k.sig, x = k.x, e = k.ell || [null, null];
  const h = (hist.get(k.id) || []).slice().reverse();
  el.textContent = [
    `track ${k.id}  ${k.status}${k.amb ? "  AMBIGUOUS" : ""}`,
    `position  x ${dist(x[0])} ${unit}  y ${dist(x[2])} ${unit}  z ${dist(x[4])} ${unit}`,
    `velocity  vx ${num(x[1], 1)}  vy ${num(x[3], 1)}  vz ${num(x[5], 1)} m/s`,
    `          ${spd(speed(x[1], x[3]), 1)} ${vunit}, course ${num(course(x[1], x[3]), 1)} deg`,
    `sigmas    x ${num(s[0], 0)}  y ${num(s[2], 0)}  z ${num(s[4], 0)} m`,
    `          vx ${num(s[1], 1)}  vy ${num(s[3], 1)}  vz ${num(s[5], 1)} m/s`,
    `2-sigma   ${num(e[0], 0)} x ${num(e[1], 0)} m`,
    `bases     ${k.et.map((t) => `${t[0]} (etrack ${t[1]})`).join(", ") || "none"}`,
    `etracks   ${k.et.map((t) => `${t[0]}:${t[1]}`).join(" ") || "none"}`,
    `score     ${k.score}`,
    `history   ${k.n} updates drawn, trail ${k.trail.length} points; last updates, newest first:`,
    `      t s        x ${unit}      y ${unit}      z ${unit}  ${vunit.padStart(6)}  course  status`,
    ...h.map((r) => `${num(r[0], 1).padStart(8)} ${dist(r[1]).padStart(9)} ${dist(r[2]).padStart(9)} ` +
      `${dist(r[3]).padStart(9)} ${spd(r[4]).padStart(7)} ${num(r[5], 0).padStart(7)}  ${r[6]}`),
  ].join("\n");
}

// ---- sonar tracks: one row per bearing track of every array, with its TMA solution ----
function sonarRows() {
  const rows = [];
  Object.keys(topics).filter((n) => n.startsWith("waterfall/")).forEach((n) => {
    const a = n.split("/")[1], sols = (topics[`tma/${a}`] || { sols: [] }).sols;
    Object.entries(topics[n].tracks).forEach(([id, pts]) => {
      const last = pts[pts.length - 1], sol = sols.find((s) => String(s.track) === id);
      const status = last[2] ? "confirmed" : "tentative", key = `${a}/${id}`;
      const range = sol && sol.range_obs !== false ? sol.range : NaN;
      rows.push({
        key, data: { key, array: a, id, status },
        cls: `status-${status}${key === selectedSonar ? " selected" : ""}`,
        cells: () => [`${a}/${id}`, status, num(last[1], 1), num(last[0], 1), dist(range),
          sol ? num(sol.course, 0) : "-", sol ? spd(sol.speed, 1) : "-"],
        sortv: { id: key, status, brg: last[1], t: last[0], range, course: sol ? sol.course : NaN,
          speed: sol ? sol.speed : NaN },
      });
    });
  });
  return rows;
}

function sonarTable() {
  const from = Object.keys(topics).filter((n) => n.startsWith("waterfall/") || n.startsWith("tma/")).sort();
  if (unchanged($("sonar-tracks"), [...from, ...from.map((n) => topics[n]), selectedSonar, ...sortBy("s")])) return;
  fillTable("s", $("sonar-tracks"), arrange("s", sonarRows()), $("sonar-more"), selectSonar);
  $("sonar-unit-head").textContent = unit;
  $("sonar-speed-head").textContent = vunit;
}

function selectSonar(key) { selectedSonar = key; selected = null; render(); }

function sonarDetails(el) {
  const [a, id] = selectedSonar.split("/"), w = topics[`waterfall/${a}`];
  const pts = w && w.tracks[id];
  el.dataset.sonar = selectedSonar;
  if (!pts) { el.textContent = `sonar track ${selectedSonar} is gone`; return; }
  const sol = ((topics[`tma/${a}`] || { sols: [] }).sols).find((s) => String(s.track) === id);
  const last = pts[pts.length - 1];
  el.textContent = [
    `sonar track ${id} of array ${a}  ${last[2] ? "confirmed" : "tentative"}`,
    `bearing   ${num(last[1], 2)} deg at t ${num(last[0], 1)} s`,
    sol ? `TMA       ${sol.range_obs === false ? "range unobservable" : `${dist(sol.range)} ${unit}`}, ` +
      `course ${num(sol.course, 1)} deg, ${spd(sol.speed, 1)} ${vunit}${sol.constrained ? ", constrained" : ""}` : "TMA       none",
    `history   ${pts.length} bearings; newest first:`,
    ...pts.slice(-HIST).reverse().map((p) => `${num(p[0], 1).padStart(8)} s ${num(p[1], 2).padStart(8)} deg  ${p[2] ? "confirmed" : "tentative"}`),
  ].join("\n");
}

document.querySelectorAll("th[data-key]").forEach((th) => th.addEventListener("click", () => {
  const s = sorts[th.dataset.table];
  s.dir = s.key === th.dataset.key ? -s.dir : 1;
  s.key = th.dataset.key;
  render();
}));
["g", "s"].forEach((w) => $(`filter-${w}`).addEventListener("input", (ev) => { sorts[w].filter = ev.target.value; render(); }));
$("speed-units").addEventListener("change", (ev) => { vunit = ev.target.value; render(); });
