// EMRD episode viewer: reads DATA (episode) and FRAMES (base64 JPEGs), draws step t.
"use strict";
(function () {
  const NS = "http://www.w3.org/2000/svg";
  const steps = DATA.steps;
  const slider = document.getElementById("slider");
  const $ = (id) => document.getElementById(id);
  const fmt = (v) => (v === null || v === undefined ? "n/a" : Number(v).toFixed(3));

  function el(tag, attrs, parent, text) {
    const node = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
    if (text !== undefined) node.textContent = text;
    if (parent) parent.appendChild(node);
    return node;
  }

  // plan: DATA.plan_frame (the office's, north up, when known), z up (SVG y = -z)
  const xs = [], zs = [];
  DATA.rooms.forEach((r) => r.polygon.forEach(([x, z]) => { xs.push(x); zs.push(z); }));
  DATA.objects.forEach((o) => { xs.push(o[3]); zs.push(o[4]); });
  const pad = 0.8;
  const x0 = Math.min(...xs) - pad, x1 = Math.max(...xs) + pad;
  const z0 = Math.min(...zs) - pad, z1 = Math.max(...zs) + pad;
  const plan = $("plan");
  plan.setAttribute("viewBox", `${x0} ${-z1} ${x1 - x0} ${z1 - z0}`);
  const s = (x1 - x0) / 60; // a "pixel" in metres for strokes and glyphs
  const base = el("g", {}, plan);
  DATA.rooms.forEach((r) => {
    el("polygon", { points: r.polygon.map(([x, z]) => `${x},${-z}`).join(" "), fill: "#f2f2f2",
      stroke: "#555", "stroke-width": s * 0.25 }, base);
    const cx = r.polygon.reduce((a, p) => a + p[0], 0) / r.polygon.length;
    const cz = r.polygon.reduce((a, p) => a + p[1], 0) / r.polygon.length;
    el("text", { x: cx, y: -cz, "font-size": s * 1.6, fill: "#aaa", "text-anchor": "middle" },
      base, r.name);
  });
  const truth = {};
  const objs = el("g", {}, plan);
  DATA.objects.forEach((o) => {
    truth[o[0]] = o;
    const c = el("circle", { cx: o[3], cy: -o[4], r: s * 0.45, fill: "#888" }, objs);
    el("title", {}, c, `${o[0]} (${o[2]})`);
  });
  const path = el("polyline", { fill: "none", stroke: "#1f5fbf", "stroke-width": s * 0.25,
    "stroke-opacity": 0.6 }, plan);
  const links = el("g", {}, plan);
  const marks = el("g", {}, plan);
  const agent = el("g", {}, plan);

  // metrics over time
  const chart = $("chart");
  const W = 600, H = 150, L = 34, B = 18;
  chart.setAttribute("viewBox", `0 0 ${W} ${H}`);
  const T = Math.max(steps.length, 2);
  const X = (t) => L + ((t - 1) / (T - 1)) * (W - L - 8);
  const Y = (v) => 6 + (1 - v) * (H - B - 6);
  [0, 0.5, 1].forEach((v) => {
    el("line", { x1: L, x2: W - 8, y1: Y(v), y2: Y(v), stroke: "#ddd" }, chart);
    el("text", { x: L - 4, y: Y(v) + 4, "font-size": 10, "text-anchor": "end" }, chart, v);
  });
  el("text", { x: W - 8, y: H - 4, "font-size": 10, "text-anchor": "end" }, chart, "step t");
  // widest first, so coinciding curves all stay visible
  const SERIES = [["coverage", "#1f5fbf", "", 5, 0.45], ["pa", "#d62728", "6 3", 2.5, 1],
    ["tbs", "#2ca02c", "2 2", 1.5, 1]];
  SERIES.forEach(([key, colour, dash, width, opacity]) => {
    const pts = steps.filter((st) => st[key] !== null).map((st) => `${X(st.t)},${Y(st[key])}`);
    el("polyline", { points: pts.join(" "), fill: "none", stroke: colour, "stroke-width": width,
      "stroke-opacity": opacity, "stroke-dasharray": dash }, chart);
  });
  const cursor = el("line", { y1: 4, y2: H - B, stroke: "#333", "stroke-dasharray": "3 3" }, chart);

  function draw(i) {
    const st = steps[i];
    $("stepno").textContent = `step ${st.t} / ${steps.length}`;
    slider.value = i;
    // frame
    const img = $("frame"), flag = $("frameflag");
    if (st.frame === null) {
      img.removeAttribute("src");
      flag.className = "warn";
      flag.textContent = "no frame: not re-rendered (see the notes above)";
    } else {
      img.src = "data:image/jpeg;base64," + FRAMES[st.frame];
      if (st.frame_ok === true) { flag.className = "ok"; flag.textContent = "✓ frame matches the recorded digest"; }
      else if (st.frame_ok === false) { flag.className = "warn"; flag.textContent = "⚠ re-rendered frame differs from the recorded digest: not what the model saw"; }
      else { flag.className = "warn"; flag.textContent = "⚠ frame not checked against a recorded digest"; }
    }
    // request: this step's text and the frames of the history window
    $("prompt").textContent = st.prompt || "not rebuilt (see the notes above)";
    const thumbs = $("window");
    thumbs.replaceChildren();
    st.window.forEach((j) => {
      const past = steps[j], box = document.createElement("figure");
      const im = document.createElement("img");
      if (past.frame !== null) im.src = "data:image/jpeg;base64," + FRAMES[past.frame];
      im.alt = `frame of step ${past.t}`;
      const cap = document.createElement("figcaption");
      cap.textContent = past.t === st.t ? `t=${past.t} (now)` : `t=${past.t}`;
      if (past.t === st.t) box.className = "now";
      box.append(im, cap);
      thumbs.appendChild(box);
    });
    $("windowcap").textContent = st.window.length
      ? `frames in the request's history window: steps ${steps[st.window[0]].t}–${st.t}`
      : "no frame in the request";
    // reply and action
    $("action").textContent = st.action || "(none)";
    $("tokens").textContent = `${st.tokens[0].toLocaleString()} prompt + ` +
      `${st.tokens[1].toLocaleString()} completion`;
    $("latency").textContent = st.latency !== null ? `${st.latency.toFixed(2)} s`
      : st.recorded_latency != null ? `${st.recorded_latency.toFixed(2)} s (when recorded)`
      : "not recorded (a cassette answered this request)";
    // result: the engine's feedback on the action, after it
    $("outcome").textContent = st.success ? "executed" : "not executed";
    $("outcome").className = st.success ? "ok" : "warn";
    $("feedback").textContent = st.feedback;
    $("after").textContent = st.after;
    $("observation").textContent = st.observation || "";
    $("dedup").textContent = st.dedup || "";
    $("reasoning").textContent = st.reasoning || "";
    $("parse").textContent = st.parse_error || "none";
    $("pose").textContent = `x=${st.pose[0]} z=${st.pose[1]} heading=${st.pose[2]}° in ${st.room}`;
    $("visible").textContent = st.visible.join(", ") || "nothing";
    $("raw").textContent = st.raw;
    $("scores").textContent = `coverage ${fmt(st.coverage)} · PA ${fmt(st.pa)} · TBS ${fmt(st.tbs)} · ` +
      `${st.map.length} entries, aligned by ${st.rotation}° (RMSE ${st.rmse === null ? "n/a" : st.rmse + " m"})`;
    // plan, after this step: the path and the agent end at the pose after the action (the next
    // step's pose; the last step's own when there is none)
    path.setAttribute("points", steps.slice(0, i + 2).map((p) => `${p.at[0]},${-p.at[1]}`).join(" "));
    links.replaceChildren(); marks.replaceChildren(); agent.replaceChildren();
    st.visible.forEach((id) => {
      const o = truth[id];
      if (o) el("circle", { cx: o[3], cy: -o[4], r: s * 1.3, fill: "none", stroke: "#f0a800",
        "stroke-width": s * 0.35 }, links);
    });
    st.map.forEach(([label, x, z, id]) => {
      if (id && truth[id]) {
        el("line", { x1: x, y1: -z, x2: truth[id][3], y2: -truth[id][4], stroke: "#d62728",
          "stroke-width": s * 0.15, "stroke-opacity": 0.7 }, links);
      }
      const colour = id ? "#d62728" : "#ff9900", d = s * 0.5;
      const g = el("g", { stroke: colour, "stroke-width": s * 0.25 }, marks);
      el("line", { x1: x - d, y1: -z - d, x2: x + d, y2: -z + d }, g);
      el("line", { x1: x - d, y1: -z + d, x2: x + d, y2: -z - d }, g);
      el("title", {}, g, `${label} → ${id || "unmatched"}`);
    });
    const [ax, az, h] = (steps[i + 1] || st).at, rad = (h * Math.PI) / 180, r = s * 7;
    const left = rad - Math.PI / 4, right = rad + Math.PI / 4;
    el("path", { d: `M${ax},${-az} L${ax + r * Math.sin(left)},${-(az + r * Math.cos(left))} ` +
      `L${ax + r * Math.sin(right)},${-(az + r * Math.cos(right))} Z`, fill: "#1f5fbf",
      "fill-opacity": 0.25, stroke: "#1f5fbf", "stroke-width": s * 0.1 }, agent);
    el("circle", { cx: ax, cy: -az, r: s * 0.8, fill: "#1f5fbf" }, agent);
    cursor.setAttribute("x1", X(st.t)); cursor.setAttribute("x2", X(st.t));
    if (location.hash !== `#step=${st.t}`) history.replaceState(null, "", `#step=${st.t}`);
  }

  slider.max = steps.length - 1;
  const go = (i) => draw(Math.max(0, Math.min(steps.length - 1, i)));
  slider.addEventListener("input", () => go(Number(slider.value)));
  $("prev").addEventListener("click", () => go(Number(slider.value) - 1));
  $("next").addEventListener("click", () => go(Number(slider.value) + 1));
  document.addEventListener("keydown", (e) => {
    const i = Number(slider.value);
    const to = { ArrowLeft: i - 1, ArrowRight: i + 1, Home: 0, End: steps.length - 1 }[e.key];
    if (to !== undefined && e.target !== slider) { e.preventDefault(); go(to); }
  });
  const fromHash = () => {
    const m = /step=(\d+)/.exec(location.hash);
    return m ? Number(m[1]) - 1 : 0;
  };
  window.addEventListener("hashchange", () => go(fromHash()));
  if (steps.length) go(fromHash());
  else document.querySelector(".grid").textContent = "This episode has no steps.";
})();
