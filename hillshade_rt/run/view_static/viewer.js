// hillshade-rt view: the page. The map is in the DEM's pixel coordinates (Leaflet's CRS.Simple:
// lng = column, lat = -row); every change asks the server for the visible window at screen size
// (/api/render) and swaps the picture in when it arrives (older answers are dropped).
"use strict";
(function () {
  const $ = (id) => document.getElementById(id);
  const st = { mode: "time", az: 203.7, el: 30, date: null, minutes: 600, algorithm: "auto",
               soft: false, sunhours: false, path: null, brush: false };
  const viewer = { renders: 0, last: null, state: st, edits: 0 };
  window.viewer = viewer;
  let info = null, map = null, overlay = null, seq = 0, timer = null;

  function pad(n) { return String(n).padStart(2, "0"); }
  function clock(m) { return pad(Math.floor(m / 60)) + ":" + pad(m % 60); }

  function sunQuery() {
    if (st.mode === "time" && info.has_time)
      return "time=" + encodeURIComponent(st.date + "T" + clock(st.minutes));
    return "az=" + st.az.toFixed(3) + "&el=" + st.el.toFixed(3);
  }
  function query() {
    let q = sunQuery() + "&algorithm=" + encodeURIComponent(st.algorithm) +
            "&soft=" + (st.soft ? 1 : 0);
    if (st.sunhours && info.has_time) q += "&sunhours=" + st.date;
    return q;
  }

  function schedule() { clearTimeout(timer); timer = setTimeout(refresh, 30); }

  async function refresh() {
    const b = map.getBounds(), size = map.getSize();
    if (size.x < 1 || size.y < 1) return;
    const x0 = b.getWest(), x1 = b.getEast(), y0 = -b.getNorth(), y1 = -b.getSouth();
    const bbox = [x0, y0, x1, y1].map((v) => Number(v.toFixed(4)));   // as sent
    const url = "/api/render?" + query() + "&bbox=" + bbox.join(",") +
                "&w=" + size.x + "&h=" + size.y;
    const mine = ++seq;
    $("status").textContent = "shading ...";
    const t0 = performance.now();
    let resp;
    try { resp = await fetch(url); } catch (e) { $("status").textContent = String(e); return; }
    if (!resp.ok) { $("status").textContent = await resp.text(); return; }
    const blob = await resp.blob();
    if (mine !== seq) return;              // a newer view was asked for meanwhile
    const h = (k) => resp.headers.get(k);
    const src = URL.createObjectURL(blob);
    const fresh = L.imageOverlay(src, [[-y1, x0], [-y0, x1]], { interactive: false });
    fresh.once("load", () => {
      if (mine !== seq) { map.removeLayer(fresh); return; }
      if (overlay) { map.removeLayer(overlay); URL.revokeObjectURL(overlay._url); }
      overlay = fresh;
      const az = parseFloat(h("X-Sun-Azimuth")), el = parseFloat(h("X-Sun-Elevation"));
      if (st.mode === "time") { st.az = az; st.el = el; drawCompass(); }
      viewer.renders += 1;
      viewer.last = { seq: mine, url: url, bbox: bbox, w: size.x, h: size.y, azimuth: az,
                      elevation: el, level: parseInt(h("X-Level")), algorithm: h("X-Algorithm"),
                      time: h("X-Time"), ms: performance.now() - t0 };
      document.body.dataset.renders = String(viewer.renders);
      $("status").textContent = (viewer.last.level === 1 ? "full resolution" :
        "overview: every " + viewer.last.level + "th cell") + ", " + viewer.last.algorithm +
        ", " + Math.round(viewer.last.ms) + " ms" +
        (h("X-Sun-Hours-Max") ? ", sun hours 0.." + h("X-Sun-Hours-Max") : "");
      sunLabel();
    });
    fresh.addTo(map);
  }

  // the picture on screen as a PNG data URL (tests read its pixels)
  viewer.pixels = function () {
    if (!overlay) return null;
    const img = overlay.getElement(), c = document.createElement("canvas");
    c.width = img.naturalWidth; c.height = img.naturalHeight;
    c.getContext("2d").drawImage(img, 0, 0);
    return c.toDataURL("image/png");
  };

  function sunLabel() {
    $("sunlabel").textContent = "sun: azimuth " + st.az.toFixed(1) + "°, elevation " +
      st.el.toFixed(1) + "°" + (st.mode === "time" && info.has_time ? "" : " (set by hand)");
    $("clock").textContent = clock(st.minutes);
  }

  // -- the compass: grid north up, elevation 90 at the centre, 0 on the rim -------------------
  const R = 80;
  function toXY(az, el) {
    const r = R * (1 - Math.max(el, 0) / 90), a = az * Math.PI / 180;
    return [90 + r * Math.sin(a), 90 - r * Math.cos(a)];
  }
  function drawCompass() {
    const c = $("compass").getContext("2d");
    c.clearRect(0, 0, 180, 180);
    c.fillStyle = "#e8eef4"; c.beginPath(); c.arc(90, 90, R, 0, 2 * Math.PI); c.fill();
    c.strokeStyle = "#9aa"; c.lineWidth = 1;
    for (const e of [0, 30, 60]) { c.beginPath(); c.arc(90, 90, R * (1 - e / 90), 0, 2 * Math.PI); c.stroke(); }
    c.fillStyle = "#345"; c.font = "11px sans-serif"; c.textAlign = "center"; c.textBaseline = "middle";
    [["N", 0], ["E", 90], ["S", 180], ["W", 270]].forEach(([t, a]) => {
      const r = R + 6, b = a * Math.PI / 180;
      c.fillText(t, 90 + r * Math.sin(b), 90 - r * Math.cos(b));
    });
    if (st.path && info.has_time) {
      c.strokeStyle = "#e0a020"; c.lineWidth = 2; c.beginPath();
      let up = false;
      for (const p of st.path.points) {
        if (p.elevation <= 0) { up = false; continue; }
        const [x, y] = toXY(p.azimuth, p.elevation);
        if (up) c.lineTo(x, y); else c.moveTo(x, y);
        up = true;
      }
      c.stroke();
      c.fillStyle = "#b07010";
      for (const p of st.path.points) {
        if (p.elevation > 0 && p.minutes % 180 === 0) {
          const [x, y] = toXY(p.azimuth, p.elevation);
          c.fillRect(x - 1.5, y - 1.5, 3, 3);
        }
      }
    }
    const [x, y] = toXY(st.az, st.el);
    c.fillStyle = st.el > 0 ? "#ffcc00" : "#667"; c.strokeStyle = "#a07000";
    c.beginPath(); c.arc(x, y, 7, 0, 2 * Math.PI); c.fill(); c.stroke();
  }
  function dragSun(ev) {
    const r = $("compass").getBoundingClientRect();
    const dx = ev.clientX - r.left - 90, dy = ev.clientY - r.top - 90;
    st.az = (Math.atan2(dx, -dy) * 180 / Math.PI + 360) % 360;
    st.el = Math.max(0.5, Math.min(90, 90 * (1 - Math.hypot(dx, dy) / R)));
    st.mode = "manual";
    drawCompass(); sunLabel(); schedule();
  }

  async function loadPath() {
    if (!info.has_time) return;
    const r = await fetch("/api/sunpath?date=" + st.date);
    if (r.ok) {
      st.path = await r.json(); drawCompass();
      if (st.path.zone_label) $("zone").textContent = "times in " + st.path.zone_label;
    }
  }

  let marker = null;
  async function showPoint(e) {
    const x = e.latlng.lng, y = -e.latlng.lat;
    if (marker) map.removeLayer(marker);
    marker = L.circleMarker(e.latlng, { radius: 5, color: "#c00", weight: 2 }).addTo(map);
    const r = await fetch("/api/point?x=" + x + "&y=" + y + "&" + sunQuery() +
                          "&algorithm=" + encodeURIComponent(st.algorithm));
    if (!r.ok) { $("point").textContent = await r.text(); $("profile").style.display = "none"; return; }
    const p = await r.json();
    let rows = [["cell", "row " + p.row + ", col " + p.col]];
    if (p.lat !== undefined) rows.push(["lat, lon", p.lat.toFixed(5) + ", " + p.lon.toFixed(5)]);
    rows.push(["height", p.height === null ? "nodata" : p.height.toFixed(1) + " m"]);
    if (p.lit !== null) rows.push(["sun", p.lit ? "lit" : "in shadow"]);
    if (p.horizon) rows.push(["horizon toward the sun", p.horizon.toward_sun.toFixed(2) + "°"]);
    $("point").innerHTML = "<table>" + rows.map(([k, v]) => "<tr><td>" + k + "</td><td>" + v +
                           "</td></tr>").join("") + "</table>";
    const cv = $("profile");
    if (!p.horizon) { cv.style.display = "none"; return; }
    cv.style.display = "block";
    const c = cv.getContext("2d"), W = cv.width, H = cv.height;
    const hi = Math.max(10, ...p.horizon.angles, st.el) + 3, lo = -5;
    const yy = (a) => H - (a - lo) / (hi - lo) * H;
    c.fillStyle = "#cfe3f5"; c.fillRect(0, 0, W, H);
    c.fillStyle = "#8a7a5c"; c.beginPath(); c.moveTo(0, H);
    p.horizon.azimuths.forEach((a, i) => c.lineTo(a / 360 * W, yy(Math.max(p.horizon.angles[i], lo))));
    c.lineTo(W, yy(Math.max(p.horizon.angles[0], lo))); c.lineTo(W, H); c.fill();
    c.strokeStyle = "#888"; c.beginPath(); c.moveTo(0, yy(0)); c.lineTo(W, yy(0)); c.stroke();
    c.fillStyle = "#ffcc00"; c.beginPath(); c.arc(p.sun.azimuth / 360 * W, yy(p.sun.elevation), 4, 0, 2 * Math.PI); c.fill();
    c.fillStyle = "#333"; c.font = "10px sans-serif";
    ["N", "E", "S", "W"].forEach((t, i) => c.fillText(t, i * W / 4 + 2, 10));
  }

  // -- the terrain brush: a click raises or lowers the terrain (the server's heights, in memory)
  function showEdits(r) {
    viewer.edits = r.edits;
    document.body.dataset.edits = String(r.edits);
    $("edits").textContent = r.edits === 0 ? "no edits" :
      r.edits + " edit(s), in memory (the DEM's file is unchanged; the download is of the " +
      "edited terrain)";
  }
  async function post(path, body) {
    const r = await fetch(path, { method: "POST", headers: { "Content-Type": "application/json" },
                                  body: body === undefined ? "" : JSON.stringify(body) });
    if (!r.ok) { $("status").textContent = await r.text(); return; }
    showEdits(await r.json());
    schedule();
  }
  function applyBrush(e) {
    return post("/api/edit", { x: e.latlng.lng, y: -e.latlng.lat,
                               radius: parseFloat($("radius").value),
                               delta: parseFloat($("delta").value), shape: $("shape").value });
  }
  function toggleBrush() {
    st.brush = !st.brush;
    $("brush").textContent = "brush: " + (st.brush ? "on (click the map)" : "off");
    $("brush").setAttribute("aria-pressed", String(st.brush));
    $("map").style.cursor = st.brush ? "crosshair" : "";
  }

  async function start() {
    info = await (await fetch("/api/info")).json();
    $("dem").textContent = info.name + " (" + info.cols + " x " + info.rows + ")";
    st.algorithm = info.algorithm;
    for (const a of info.algorithms) {
      const o = document.createElement("option"); o.value = o.textContent = a;
      if (a === st.algorithm) o.selected = true;
      $("algorithm").appendChild(o);
    }
    if (info.has_time) {
      st.date = info.date; st.minutes = info.minutes;
      $("date").value = st.date; $("time").value = String(st.minutes);
      $("zone").textContent = "times in " + (info.zone_label || info.zone);
    } else {
      st.mode = "manual";
      $("timebox").style.display = "none"; $("hoursbox").style.display = "none";
    }
    map = L.map("map", { crs: L.CRS.Simple, minZoom: -8, maxZoom: 6, zoomSnap: 0.25,
                         attributionControl: false });
    viewer.map = map;
    map.fitBounds([[-info.rows, 0], [0, info.cols]]);
    map.on("moveend zoomend resize", schedule);
    map.on("click", (e) => (st.brush ? applyBrush(e) : showPoint(e)));
    $("brush").addEventListener("click", toggleBrush);
    $("undo").addEventListener("click", () => post("/api/undo"));
    $("reset").addEventListener("click", () => post("/api/reset"));
    $("date").addEventListener("change", () => {
      st.date = $("date").value; st.mode = "time"; loadPath(); schedule();
    });
    $("time").addEventListener("input", () => {
      st.minutes = parseInt($("time").value); st.mode = "time"; sunLabel(); schedule();
    });
    $("algorithm").addEventListener("change", () => { st.algorithm = $("algorithm").value; schedule(); });
    $("soft").addEventListener("change", () => { st.soft = $("soft").checked; schedule(); });
    $("sunhours").addEventListener("change", () => { st.sunhours = $("sunhours").checked; schedule(); });
    $("download").addEventListener("click", () => { window.location = "/api/download?" + query(); });
    const cp = $("compass");
    let dragging = false;
    cp.addEventListener("pointerdown", (e) => { dragging = true; cp.setPointerCapture(e.pointerId); dragSun(e); });
    cp.addEventListener("pointermove", (e) => { if (dragging) dragSun(e); });
    cp.addEventListener("pointerup", () => { dragging = false; });
    sunLabel(); drawCompass(); loadPath(); refresh();
  }
  start();
})();
