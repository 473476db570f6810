// passive-fusion live view: latitude/longitude graticule and axes of a plan view when the
// deployment has a WGS-84 origin ([radar.origin], the geometry topic's origin). The page
// converts itself: geodetic -> ECEF -> ENU in closed form, ENU -> ECEF -> geodetic by
// fixed-point iteration on the latitude (converged to < 1 mm after 5 steps near the
// surface). The plan is the ENU frame's East-North plane (up dropped), as for the
// tracks. Parallels and meridians as polylines, labels on the left and bottom edges.
// No antimeridian or pole handling (a plan view spans at most a few hundred km there).
"use strict";

const WGS84_A = 6378137.0, WGS84_F = 1 / 298.257223563, WGS84_E2 = WGS84_F * (2 - WGS84_F);
const RAD = Math.PI / 180;
const GRAT_STEPS = [10, 5, 2, 1, 30 / 60, 20 / 60, 10 / 60, 5 / 60, 2 / 60, 1 / 60, 0.5 / 60, 0.2 / 60, 0.1 / 60];
const GRAT_LINES = 8;      // about this many lines across the larger span
const GRAT_POINTS = 24;    // segments per graticule line

function ecef(lat, lon, h) {
  const sl = Math.sin(lat * RAD), n = WGS84_A / Math.sqrt(1 - WGS84_E2 * sl * sl);
  return [(n + h) * Math.cos(lat * RAD) * Math.cos(lon * RAD), (n + h) * Math.cos(lat * RAD) * Math.sin(lon * RAD),
    (n * (1 - WGS84_E2) + h) * sl];
}

function geoToEnu(lat, lon, h, o) {  // o: origin [lat0, lon0, h0]
  const p = ecef(lat, lon, h), q = ecef(o[0], o[1], o[2]), d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
  const sf = Math.sin(o[0] * RAD), cf = Math.cos(o[0] * RAD), sl = Math.sin(o[1] * RAD), cl = Math.cos(o[1] * RAD);
  return [-sl * d[0] + cl * d[1], -sf * cl * d[0] - sf * sl * d[1] + cf * d[2],
    cf * cl * d[0] + cf * sl * d[1] + sf * d[2]];
}

function enuToGeo(e, n, u, o) {  // -> [lat deg, lon deg, h m]
  const sf = Math.sin(o[0] * RAD), cf = Math.cos(o[0] * RAD), sl = Math.sin(o[1] * RAD), cl = Math.cos(o[1] * RAD);
  const q = ecef(o[0], o[1], o[2]);
  const x = q[0] - sl * e - sf * cl * n + cf * cl * u, y = q[1] + cl * e - sf * sl * n + cf * sl * u,
    z = q[2] + cf * n + sf * u;
  const p = Math.hypot(x, y);
  let lat = Math.atan2(z, p * (1 - WGS84_E2)), h = 0;
  for (let i = 0; i < 5; i++) {
    const s = Math.sin(lat), nn = WGS84_A / Math.sqrt(1 - WGS84_E2 * s * s);
    h = p / Math.cos(lat) - nn;
    lat = Math.atan2(z, p * (1 - WGS84_E2 * nn / (nn + h)));
  }
  return [lat / RAD, Math.atan2(y, x) / RAD, h];
}

function dms(v, pos, neg, step) {  // 47.5 -> 47°30'N; decimal minutes under a 1' step
  const a = Math.abs(v), d = Math.floor(a + 1e-9), m = (a - d) * 60;
  const mm = step < 1 / 60 - 1e-12 ? m.toFixed(1) : String(Math.round(m));
  const [dd, mt] = mm === "60" ? [d + 1, "0"] : [d, mm];
  return `${dd}\u00b0${mt === "0" ? "" : `${mt}'`}${v >= 0 ? pos : neg}`;
}

// Draws the graticule of the visible area in place of the metric grid (view.js grid)
function graticule(ctx, canvas, xf, o) {
  const W = canvas.width, H = canvas.height, pts = [];
  for (const px of [0, W / 2, W]) for (const py of [0, H / 2, H]) pts.push(enuToGeo(xf.wx(px), xf.wy(py), 0, o));
  const lat = [Math.min(...pts.map((p) => p[0])), Math.max(...pts.map((p) => p[0]))];
  const lon = [Math.min(...pts.map((p) => p[1])), Math.max(...pts.map((p) => p[1]))];
  if (![...lat, ...lon].every(fin)) return;
  const span = Math.max(lat[1] - lat[0], lon[1] - lon[0]);
  const step = GRAT_STEPS.find((s) => span / s >= GRAT_LINES) || GRAT_STEPS[GRAT_STEPS.length - 1];
  const values = (r) => {
    const out = [];
    for (let v = Math.ceil(r[0] / step) * step; v <= r[1] && out.length < MAX_GRID; v += step) out.push(v);
    return out;
  };
  const px = (la, lo) => { const p = geoToEnu(la, lo, o[2], o); return [xf.x(p[0]), xf.y(p[1])]; };
  const line = (f) => {  // f(i / GRAT_POINTS) -> [lat, lon]
    ctx.beginPath();
    for (let i = 0; i <= GRAT_POINTS; i++) { const p = px(...f(i / GRAT_POINTS)); i ? ctx.lineTo(...p) : ctx.moveTo(...p); }
    ctx.stroke();
  };
  ctx.strokeStyle = "#1b2834"; ctx.fillStyle = "#6f8296"; ctx.lineWidth = 1; ctx.font = "10px sans-serif";
  const lats = values(lat), lons = values(lon);
  lats.forEach((la) => line((k) => [la, lon[0] + k * (lon[1] - lon[0])]));
  lons.forEach((lo) => line((k) => [lat[0] + k * (lat[1] - lat[0]), lo]));
  const left = enuToGeo(xf.wx(0), xf.wy(H / 2), 0, o)[1], bottom = enuToGeo(xf.wx(W / 2), xf.wy(H), 0, o)[0];
  lats.forEach((la) => { const p = px(la, left); if (p[1] >= 0 && p[1] <= H) label(ctx, canvas, dms(la, "N", "S", step), 2, p[1] - 2); });
  lons.forEach((lo) => { const p = px(bottom, lo); if (p[0] >= 0 && p[0] <= W) label(ctx, canvas, dms(lo, "E", "W", step), p[0] + 2, H - 4); });
  canvas.graticule = { step, lats, lons };
}
