// rvlio report: draws the model embedded in #rvlio-data (docs/report.md).
// 2D plots are drawn on canvases here; the map uses three.js and its
// OrbitControls (libjs-three, inlined above).
"use strict";

var RvlioReport = (function () {
  var COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
                "#e377c2", "#17becf", "#bcbd22", "#7f7f7f", "#393b79", "#637939"];

  // base64 of little-endian float32 -> Float32Array.
  function decode(b64) {
    if (!b64) return new Float32Array(0);
    var bin = atob(b64);
    var bytes = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    var view = new DataView(bytes.buffer);
    var out = new Float32Array(bytes.length / 4);
    for (var k = 0; k < out.length; k++) out[k] = view.getFloat32(4 * k, true);
    return out;
  }

  // About n round tick values covering [lo, hi].
  function niceTicks(lo, hi, n) {
    if (!(hi > lo)) { hi = lo + 1; lo = lo - 1; }
    var raw = (hi - lo) / Math.max(1, n);
    var mag = Math.pow(10, Math.floor(Math.log10(raw)));
    var steps = [1, 2, 2.5, 5, 10];
    var step = mag;
    for (var i = 0; i < steps.length; i++) if (steps[i] * mag >= raw) { step = steps[i] * mag; break; }
    var ticks = [];
    for (var v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step)
      ticks.push(Math.abs(v) < 1e-12 * step ? 0 : v);
    return ticks;
  }

  function fmtTick(v) {
    var a = Math.abs(v);
    if (a === 0) return "0";
    if (a >= 1e4 || a < 1e-3) return v.toExponential(1);
    return String(parseFloat(v.toPrecision(4)));
  }

  function finiteRange(arrays) {
    var lo = Infinity, hi = -Infinity;
    arrays.forEach(function (a) {
      for (var i = 0; i < a.length; i++) if (isFinite(a[i])) { lo = Math.min(lo, a[i]); hi = Math.max(hi, a[i]); }
    });
    if (!isFinite(lo)) { lo = 0; hi = 1; }
    if (hi === lo) { lo -= 0.5; hi += 0.5; }
    return [lo, hi];
  }

  // series: [{x: Float32Array, y: Float32Array, color, width, dash, step}]
  // opts: {xlabel, ylabel}
  function linePlot(canvas, series, opts) {
    var ctx = canvas.getContext("2d");
    var W = canvas.width, H = canvas.height, L = 58, R = 12, T = 12, B = 36;
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, W, H);
    var xr = finiteRange(series.map(function (s) { return s.x; }));
    var yr = finiteRange(series.map(function (s) { return s.y; }));
    var pad = function (r) { var d = 0.04 * (r[1] - r[0]); return [r[0] - d, r[1] + d]; };
    xr = pad(xr); yr = pad(yr);
    var pw = W - L - R, ph = H - T - B;
    var X = function (v) { return L + (v - xr[0]) / (xr[1] - xr[0]) * pw; };
    var Y = function (v) { return T + ph - (v - yr[0]) / (yr[1] - yr[0]) * ph; };
    ctx.font = "11px sans-serif"; ctx.strokeStyle = "#e4e4e4"; ctx.fillStyle = "#444"; ctx.lineWidth = 1;
    niceTicks(xr[0], xr[1], 7).forEach(function (v) {
      ctx.beginPath(); ctx.moveTo(X(v), T); ctx.lineTo(X(v), T + ph); ctx.stroke();
      ctx.textAlign = "center"; ctx.fillText(fmtTick(v), X(v), T + ph + 14);
    });
    niceTicks(yr[0], yr[1], 5).forEach(function (v) {
      ctx.beginPath(); ctx.moveTo(L, Y(v)); ctx.lineTo(L + pw, Y(v)); ctx.stroke();
      ctx.textAlign = "right"; ctx.fillText(fmtTick(v), L - 4, Y(v) + 4);
    });
    ctx.strokeStyle = "#888"; ctx.strokeRect(L, T, pw, ph);
    ctx.textAlign = "center";
    if (opts.xlabel) ctx.fillText(opts.xlabel, L + pw / 2, H - 6);
    if (opts.ylabel) {
      ctx.save(); ctx.translate(12, T + ph / 2); ctx.rotate(-Math.PI / 2); ctx.fillText(opts.ylabel, 0, 0); ctx.restore();
    }
    ctx.save(); ctx.beginPath(); ctx.rect(L, T, pw, ph); ctx.clip();
    series.forEach(function (s) {
      if (s.markers) {  // points: a square (control) or a ring (check) each, with its label
        for (var m = 0; m < s.x.length; m++) {
          var mx = X(s.x[m]), my = Y(s.y[m]);
          ctx.strokeStyle = s.color; ctx.fillStyle = s.color; ctx.lineWidth = 1.5; ctx.setLineDash([]);
          if (s.hollow && s.hollow[m]) { ctx.beginPath(); ctx.arc(mx, my, 4.5, 0, 2 * Math.PI); ctx.stroke(); }
          else ctx.fillRect(mx - 4, my - 4, 8, 8);
          if (s.labels) { ctx.textAlign = "left"; ctx.fillText(s.labels[m], mx + 6, my - 6); }
        }
        return;
      }
      ctx.strokeStyle = s.color; ctx.lineWidth = s.width || 1.5; ctx.setLineDash(s.dash || []);
      ctx.beginPath();
      var pen = false, lastY = 0;
      for (var i = 0; i < s.x.length; i++) {
        if (!isFinite(s.x[i]) || !isFinite(s.y[i])) { pen = false; continue; }
        if (!pen) { ctx.moveTo(X(s.x[i]), Y(s.y[i])); pen = true; }
        else {
          if (s.step) ctx.lineTo(X(s.x[i]), Y(lastY));
          ctx.lineTo(X(s.x[i]), Y(s.y[i]));
        }
        lastY = s.y[i];
      }
      ctx.stroke();
    });
    ctx.restore(); ctx.setLineDash([]);
  }

  function el(tag, attrs, text) {
    var e = document.createElement(tag);
    for (var k in attrs || {}) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }

  function fmtValue(v) {
    if (v === null || v === undefined) return "";
    if (typeof v === "boolean") return v ? "yes" : "no";
    if (typeof v !== "number") return String(v);
    if (Number.isInteger(v)) return String(v);
    var a = Math.abs(v);
    if (a !== 0 && (a < 1e-3 || a >= 1e6)) return v.toExponential(3);
    return v.toFixed(a >= 100 ? 1 : 4);
  }

  function valueCell(v, column) {
    var td = el("td", {"data-column": column}, fmtValue(v));
    if (typeof v === "number") td.setAttribute("data-value", String(v));
    else td.className = "text";
    return td;
  }

  // One row per variant or cell; a single row (a run folder) is shown
  // transposed, one line per column.
  function drawTable(table) {
    var t = document.getElementById("metrics");
    if (table.rows.length === 1) {
      table.columns.forEach(function (c, i) {
        var tr = el("tr");
        tr.appendChild(el("th", {}, c));
        tr.appendChild(valueCell(table.rows[0][i], c));
        t.appendChild(tr);
      });
      return;
    }
    var head = el("tr");
    table.columns.forEach(function (c) { head.appendChild(el("th", {}, c)); });
    t.appendChild(head);
    var status = table.columns.indexOf("status");
    table.rows.forEach(function (row) {
      var tr = el("tr", status >= 0 ? {"class": String(row[status])} : {});
      row.forEach(function (v, i) { tr.appendChild(valueCell(v, table.columns[i])); });
      t.appendChild(tr);
    });
  }

  function drawTrajectories(model) {
    var top = [], axis = [], legend = document.getElementById("run-legend");
    if (model.gt) {
      var g = decode(model.gt.xyz);
      top.push({x: g.filter(function (_, i) { return i % 3 === 0; }),
                y: g.filter(function (_, i) { return i % 3 === 1; }), color: "#000", width: 2.5, dash: [6, 4]});
      var sp = el("span"); sp.appendChild(el("i", {style: "background:#000"})); sp.appendChild(document.createTextNode("ground truth"));
      legend.appendChild(sp);
    }
    model.runs.forEach(function (r, k) {
      if (!r.trajectory) return;
      var color = COLORS[k % COLORS.length];
      var p = decode(r.trajectory.xyz);
      top.push({x: p.filter(function (_, i) { return i % 3 === 0; }), y: p.filter(function (_, i) { return i % 3 === 1; }), color: color});
      if (r.axis_error) axis.push({x: decode(r.axis_error.t), y: decode(r.axis_error.err), color: color});
      var sp = el("span"); sp.appendChild(el("i", {style: "background:" + color}));
      sp.appendChild(document.createTextNode(r.label + (r.status !== "ok" && r.status !== "done" ? " (" + r.status + ")" : "")));
      legend.appendChild(sp);
    });
    document.getElementById("trajectory-caption").textContent = model.gt
      ? "Estimates aligned to the ground truth (" + model.gt.file + ") as rvlio eval aligns them. The top view scales its axes separately, so sideways error shows in a long tunnel."
      : "No ground truth: estimates in their own world frame; no along-axis error.";
    if (model.control && model.control.marks) {
      var xy = decode(model.control.marks.xy);
      top.push({markers: true, color: "#c0392b", labels: model.control.marks.names,
                hollow: model.control.marks.roles.map(function (r) { return r === "check"; }),
                x: xy.filter(function (_, i) { return i % 2 === 0; }), y: xy.filter(function (_, i) { return i % 2 === 1; })});
      var sc = el("span"); sc.appendChild(el("i", {style: "background:#c0392b"}));
      sc.appendChild(document.createTextNode("control points (filled), check points (rings)"));
      legend.appendChild(sc);
    }
    linePlot(document.getElementById("topview"), top, {xlabel: "x [m]", ylabel: "y [m]"});
    linePlot(document.getElementById("axiserror"), axis, {xlabel: "t [s]", ylabel: "along-axis error [m]"});
  }

  // control.csv of a refine --control: one row per control or check point.
  function drawControl(model) {
    var section = document.getElementById("control-section");
    if (!model.control) { section.style.display = "none"; return; }
    document.getElementById("control-caption").textContent = model.control.caption;
    var t = document.getElementById("control"), head = el("tr");
    model.control.columns.forEach(function (c) { head.appendChild(el("th", {}, c)); });
    t.appendChild(head);
    var role = model.control.columns.indexOf("role");
    model.control.rows.forEach(function (row) {
      var tr = el("tr", {"class": String(row[role])});
      row.forEach(function (v, i) { tr.appendChild(valueCell(v, model.control.columns[i])); });
      t.appendChild(tr);
    });
  }

  function drawScans(model) {
    var select = document.getElementById("scan-run");
    var runs = model.runs.filter(function (r) { return r.scans; });
    if (runs.length === 0) { document.getElementById("scans-section").style.display = "none"; return; }
    runs.forEach(function (r, i) { select.appendChild(el("option", {value: String(i)}, r.label)); });
    var preferred = runs.findIndex(function (r) { return /rv_on/.test(r.name); });
    select.value = String(Math.max(0, preferred));
    var show = function () {
      var r = runs[Number(select.value)], box = document.getElementById("scan-panels");
      box.innerHTML = "";
      var t = decode(r.scans.t);
      r.scans.columns.forEach(function (column) {
        var name = column.name;
        var fig = el("figure"), c = el("canvas", {width: "420", height: "180", "data-column": name});
        fig.appendChild(c); fig.appendChild(el("figcaption", {}, name)); box.appendChild(fig);
        var step = name === "rv_active" || name === "diverged" || name === "localized";
        linePlot(c, [{x: t, y: decode(column.values), color: "#1f77b4", step: step}], {xlabel: "t [s]"});
      });
      document.getElementById("scan-caption").textContent = r.scans.n + " scans (columns of its scans.csv)";
    };
    select.addEventListener("change", show);
    show();
  }

  // Blue-white-red for a signed deviation ("diverging"), grey for intensity
  // ("grey", as survey software shows it), a viridis-like ramp for height.
  function colormap(u, diverging) {
    u = Math.min(1, Math.max(0, u));
    if (diverging === "grey") return [0.08 + 0.92 * u, 0.08 + 0.92 * u, 0.08 + 0.92 * u];
    if (diverging) {
      return u < 0.5 ? [2 * u, 2 * u, 1] : [1, 2 * (1 - u), 2 * (1 - u)];
    }
    var stops = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]];
    var x = u * (stops.length - 1), i = Math.min(stops.length - 2, Math.floor(x)), f = x - i;
    return [0, 1, 2].map(function (k) { return stops[i][k] * (1 - f) + stops[i + 1][k] * f; });
  }

  function percentile(values, q) {
    var a = Array.prototype.filter.call(values, isFinite).sort(function (x, y) { return x - y; });
    return a.length ? a[Math.min(a.length - 1, Math.floor(q * a.length))] : 0;
  }

  function drawColorbar(lo, hi, field, diverging) {
    var c = document.getElementById("colorbar"), ctx = c.getContext("2d");
    for (var x = 0; x < c.width; x++) {
      var rgb = colormap(x / (c.width - 1), diverging);
      ctx.fillStyle = "rgb(" + rgb.map(function (v) { return Math.round(255 * v); }).join(",") + ")";
      ctx.fillRect(x, 0, 1, c.height);
    }
    var unit = field === "intensity" ? "" : " m";
    document.getElementById("colorbar-label").textContent =
      (field === "z" ? "height z" : field) + ": " + fmtTick(lo) + unit + " to " + fmtTick(hi) + unit;
  }

  var FIELD_TEXT = {z: "height", deviation_m: "deviation_m (distance to the reference map)",
                    intensity: "intensity (the sensor's, its reflectivity where it gives one)"};

  // The colourings the map offers: its first field, height, then the others
  // (intensity where the map has it), each as {field, value}.
  function cloudColourings(cloud, xyz) {
    var out = [{field: cloud.field, value: decode(cloud.value)}];
    if (cloud.field !== "z") {
      var z = new Float32Array(xyz.length / 3);
      for (var i = 0; i < z.length; i++) z[i] = xyz[3 * i + 2];
      out.push({field: "z", value: z});
    }
    Object.keys(cloud.other_fields || {}).forEach(function (name) {
      out.push({field: name, value: decode(cloud.other_fields[name])});
    });
    return out;
  }

  // Colours of the points for one colouring (2nd to 98th percentile; a
  // deviation symmetric around 0); grey where a value is missing.
  function colourPoints(c, colors) {
    var value = c.value, kind = c.field === "z" ? false : c.field === "intensity" ? "grey" : true;
    var lo = percentile(value, 0.02), hi = percentile(value, 0.98);
    if (kind === true) { var m = Math.max(Math.abs(lo), Math.abs(hi)) || 1; lo = -m; hi = m; }
    if (!(hi > lo)) hi = lo + 1;
    for (var i = 0; i < value.length; i++) {
      var rgb = isFinite(value[i]) ? colormap((value[i] - lo) / (hi - lo), kind) : [0.5, 0.5, 0.5];
      colors[3 * i] = rgb[0]; colors[3 * i + 1] = rgb[1]; colors[3 * i + 2] = rgb[2];
    }
    drawColorbar(lo, hi, c.field, kind);
  }

  function drawCloud(model) {
    var box = document.getElementById("cloud"), cloud = model.cloud;
    var caption = document.getElementById("map-caption");
    if (!cloud) {
      caption.textContent = "No map.pcd to show.";
      box.style.display = "none"; document.querySelector(".colorbar").style.display = "none";
      return;
    }
    var captionText = function (field) {
      return "map.pcd of " + cloud.run + ": " + cloud.shown + " of " + cloud.total + " points shown" +
        (cloud.stride > 1 ? " (thinned: every " + cloud.stride + "th point, to keep the file small)" : " (all points)") +
        ", coloured by " + (FIELD_TEXT[field] || field) + ". Drag to turn, right-drag to pan, wheel to zoom.";
    };
    caption.textContent = captionText(cloud.field);
    var canvas = document.createElement("canvas");
    var gl = canvas.getContext("webgl", {preserveDrawingBuffer: true}) || canvas.getContext("experimental-webgl");
    if (typeof THREE === "undefined" || !gl) {
      box.appendChild(el("div", {"class": "msg"}, "This browser offers no WebGL: the map cannot be drawn."));
      return;
    }
    var xyz = decode(cloud.xyz);
    var colourings = cloudColourings(cloud, xyz);
    var colors = new Float32Array(xyz.length);
    colourPoints(colourings[0], colors);
    var select = document.getElementById("cloud-field");
    colourings.forEach(function (c, i) { select.appendChild(el("option", {value: String(i)}, FIELD_TEXT[c.field] || c.field)); });
    var min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
    for (var j = 0; j < xyz.length; j++) { min[j % 3] = Math.min(min[j % 3], xyz[j]); max[j % 3] = Math.max(max[j % 3], xyz[j]); }
    var center = new THREE.Vector3((min[0] + max[0]) / 2, (min[1] + max[1]) / 2, (min[2] + max[2]) / 2);
    var extent = Math.max(max[0] - min[0], max[1] - min[1], max[2] - min[2], 1);
    var geometry = new THREE.BufferGeometry();
    var setAttr = (geometry.setAttribute || geometry.addAttribute).bind(geometry);
    setAttr("position", new THREE.BufferAttribute(xyz, 3));
    var colorAttribute = new THREE.BufferAttribute(colors, 3);
    setAttr("color", colorAttribute);
    var material = new THREE.PointsMaterial({size: 2, sizeAttenuation: false,
      vertexColors: THREE.VertexColors !== undefined ? THREE.VertexColors : true});
    var scene = new THREE.Scene();
    scene.background = new THREE.Color(0x111111);
    scene.add(new THREE.Points(geometry, material));
    var renderer = new THREE.WebGLRenderer({canvas: canvas, context: gl, antialias: false});
    box.appendChild(canvas);
    var w = box.clientWidth || 1000, h = box.clientHeight || 560;
    renderer.setSize(w, h);
    var camera = new THREE.PerspectiveCamera(50, w / h, extent * 1e-4, extent * 20);
    var render = function () { renderer.render(scene, camera); };
    // three.js's OrbitControls (libjs-three): drag turns, right-drag pans, wheel zooms; z is up.
    camera.up.set(0, 0, 1);
    camera.position.set(center.x - 0.5 * extent, center.y - 0.5 * extent, center.z + 0.45 * extent);
    var controls = new THREE.OrbitControls(camera, canvas);
    controls.target.copy(center);
    controls.screenSpacePanning = true;
    controls.addEventListener("change", render);
    controls.update();
    select.addEventListener("change", function () {
      var c = colourings[Number(select.value)];
      colourPoints(c, colors);
      colorAttribute.needsUpdate = true;
      caption.textContent = captionText(c.field);
      render();
    });
    window.addEventListener("resize", function () {
      var W = box.clientWidth, H = box.clientHeight;
      renderer.setSize(W, H); camera.aspect = W / H; camera.updateProjectionMatrix(); render();
    });
    render();
    var rect = canvas.getBoundingClientRect();  // page pixels of the map (read by the browser test)
    box.setAttribute("data-rect", [rect.left + window.scrollX, rect.top + window.scrollY, rect.width, rect.height]
      .map(Math.round).join(","));
  }

  function main() {
    var model = JSON.parse(document.getElementById("rvlio-data").textContent);
    document.getElementById("title").textContent = model.title;
    document.getElementById("subtitle").textContent = "Written by rvlio " + model.version + " (rvlio report), folder kind: " + model.kind + ".";
    var notes = document.getElementById("notes");
    (model.notes || []).forEach(function (n) { notes.appendChild(el("li", {}, n)); });
    drawTable(model.table);
    drawTrajectories(model);
    drawControl(model);
    drawScans(model);
    drawCloud(model);
    document.body.setAttribute("data-rvlio-ready", "1");
  }

  return {decode: decode, niceTicks: niceTicks, colormap: colormap, main: main};
})();

if (typeof document !== "undefined") RvlioReport.main();
if (typeof module !== "undefined") module.exports = RvlioReport;
