// umbra explore: draws what the engine did on one scanline (see docs/explore.md).
// Served by `umbra explore` (data from its JSON API) or exported with `--export` (data
// precomputed in data.js and lines/<stage>.js, read from disk).
"use strict";

const $ = (id) => document.getElementById(id);
const STATIC = window.UMBRA_STATIC || null;

const state = {
  scene: null, stage: "", paper: false, width: 0, height: 0, light: null,
  line: 0, x: null, frame: null, trace: null, playing: null, token: 0, scale: 1, lightKey: null,
};
const staticLines = {};

// --- data -----------------------------------------------------------------------------------

function params(extra) {
  const p = new URLSearchParams({ shadows: state.stage, width: state.width, height: state.height });
  if (state.light) p.set("light", state.light.map((v) => v.toFixed(4)).join(","));
  if (state.paper && state.scene.paper_stages.includes(state.stage)) p.set("paper", "1");
  for (const [k, v] of Object.entries(extra || {})) p.set(k, v);
  return p.toString();
}

async function api(path, extra) {
  const response = await fetch(`api/${path}?${params(extra)}`);
  const body = await response.json();
  if (!response.ok) throw new Error(body.error || `${response.status}`);
  return body;
}

function loadScript(src) {
  return new Promise((resolve, reject) => {
    const s = document.createElement("script");
    s.src = src;
    s.onload = resolve;
    s.onerror = () => reject(new Error(`cannot read ${src}`));
    document.head.appendChild(s);
  });
}

// Called by the exported lines/watkins.js (a line's visibility, the same for every stage)
// and lines/<stage>.js (the stage's decisions on a line).
window.umbraLine = (t) => { (staticLines.watkins ||= [])[t.line] = t; };
window.umbraDecisions = (stage, line, decisions) => { (staticLines[stage] ||= [])[line] = decisions; };

async function getFrame() {
  if (!STATIC) return [await api("frame"), `api/image?${params()}`];
  const f = STATIC.frames[state.stage];
  if (!f) throw new Error(`the stage ${state.stage} was not exported (not applicable to this scene)`);
  return [f, `frames/${state.stage}.png`];
}

async function getTrace() {
  if (!STATIC) return api("trace", { line: state.line });
  if (!staticLines.watkins) await loadScript("lines/watkins.js");
  if (!staticLines[state.stage]) await loadScript(`lines/${state.stage}.js`);
  const t = staticLines.watkins[state.line];
  return { ...t, shadows: state.stage, decisions: staticLines[state.stage][state.line] };
}

// --- control --------------------------------------------------------------------------------

function showError(e) {
  $("error").hidden = !e;
  $("error").textContent = e ? `umbra: ${e.message || e}` : "";
}

function busy(what) {
  document.body.dataset.state = what ? "busy" : "ready";
  $("status").textContent = what || "ready";
}

async function loadFrame() {
  const token = ++state.token;
  busy("rendering");
  try {
    const [frame, src] = await getFrame();
    if (token !== state.token) return;
    state.frame = frame;
    await new Promise((resolve, reject) => {
      const img = $("frame");
      img.onload = resolve;
      img.onerror = () => reject(new Error("the image did not load"));
      img.src = src;
    });
    if (token !== state.token) return;
    sizeCanvases();
    drawFrameSummary();
    showError(null);
  } catch (e) {
    if (token === state.token) { showError(e); busy(null); }
    return;
  }
  await loadTrace();
}

async function loadTrace() {
  const token = ++state.token;
  busy(`tracing line ${state.line}`);
  try {
    const trace = await getTrace();
    if (token !== state.token) return;
    state.trace = trace;
    drawTrace();
    showError(null);
  } catch (e) {
    if (token === state.token) showError(e);
  }
  if (token === state.token) busy(null);
}

function setLine(line, x) {
  line = Math.max(0, Math.min(state.height - 1, line | 0));
  if (x !== undefined) state.x = Math.max(0, Math.min(state.width - 1, x | 0));
  const moved = line !== state.line;
  state.line = line;
  $("line").value = line;
  drawOverlay();
  if (moved || !state.trace) loadTrace(); else drawTrace();
}

function togglePlay() {
  if (state.playing) {
    clearInterval(state.playing);
    state.playing = null;
    $("play").textContent = "Play";
    drawOverlay();
    return;
  }
  $("play").textContent = "Pause";
  if (state.line >= state.height - 1) setLine(0);
  state.playing = setInterval(() => {
    if (document.body.dataset.state !== "ready") return;
    if (state.line >= state.height - 1) return togglePlay();
    setLine(state.line + 1);
  }, 40);
}

// --- drawing --------------------------------------------------------------------------------

function colour(poly, alpha) {
  const h = (poly * 137.508) % 360;
  return `hsla(${h}, 62%, 48%, ${alpha === undefined ? 1 : alpha})`;
}

function cell(tag, text, attrs) {
  const e = document.createElement(tag);
  e.textContent = text;
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  return e;
}

function fillTable(table, head, rows) {
  table.replaceChildren();
  const tr = document.createElement("tr");
  head.forEach((h) => tr.appendChild(cell("th", h)));
  table.appendChild(tr);
  for (const r of rows) {
    const row = document.createElement("tr");
    r.cells.forEach((c) => row.appendChild(cell("td", c)));
    if (r.picked) row.className = "picked";
    table.appendChild(row);
  }
}

const f3 = (v) => Number(v).toFixed(3);

function sizeCanvases() {
  const w = state.frame.width, h = state.frame.height;
  state.scale = Math.max(1, Math.min(4, Math.floor(680 / Math.max(w, h * 4 / 3))));
  const img = $("frame"), ov = $("overlay");
  img.style.width = `${w * state.scale}px`;
  img.style.height = `${h * state.scale}px`;
  ov.width = w * state.scale;
  ov.height = h * state.scale;
  drawOverlay();
}

function drawOverlay() {
  const ov = $("overlay"), g = ov.getContext("2d"), s = state.scale, f = state.frame;
  g.clearRect(0, 0, ov.width, ov.height);
  if (!f) return;
  if (state.playing) {
    g.fillStyle = "rgba(20, 24, 34, 0.92)";
    g.fillRect(0, (state.line + 1) * s, ov.width, ov.height);
  }
  if ($("show-outlines").checked) {
    g.strokeStyle = "rgba(255, 214, 10, 0.55)";
    g.lineWidth = 1;
    for (const ring of f.outlines) {
      g.beginPath();
      ring.forEach(([x, y], i) => (i ? g.lineTo(x * s, y * s) : g.moveTo(x * s, y * s)));
      g.closePath();
      g.stroke();
    }
  }
  if ($("show-penumbra").checked && f.penumbra) {
    g.fillStyle = "rgba(86, 180, 233, 0.75)";
    for (const [x, y] of f.penumbra.pixels) g.fillRect(x * s, y * s, s, s);
  }
  if ($("show-differs").checked) {
    g.fillStyle = "rgba(255, 140, 0, 0.9)";
    for (const [x, y] of f.differs.ties) g.fillRect(x * s, y * s, s, s);
    g.fillStyle = "rgba(230, 0, 60, 0.95)";
    for (const [x, y] of f.differs.wrong) g.fillRect(x * s, y * s, s, s);
  }
  const y = (state.line + 0.5) * s;
  g.strokeStyle = "rgba(0, 229, 255, 0.95)";
  g.lineWidth = 1;
  g.beginPath(); g.moveTo(0, y); g.lineTo(ov.width, y); g.stroke();
  const t = state.trace;
  if (t && t.line === state.line) {
    for (const r of t.runs) {
      g.fillStyle = colour(r.poly, 0.9);
      g.fillRect(r.x0 * s, y + 2, (r.x1 - r.x0) * s, 3);
    }
    g.fillStyle = "white";
    for (const [x] of t.active) g.fillRect(x * s - 0.5, y - 5, 1, 4);
  }
  if (state.x !== null) {
    g.strokeStyle = "white";
    g.strokeRect(state.x * s - 1.5, state.line * s - 1.5, s + 3, s + 3);
  }
}

function drawFrameSummary() {
  const f = state.frame, st = f.stats, d = f.differs;
  const diff = f.shadows === "ray-cast" ? "this is the reference" :
    `${d.wrong_total} pixel(s) differ from ray-cast (red), ${d.ties_total} more only at ties (orange)`;
  $("frame-summary").textContent =
    `${st.width}×${st.height}, ${st.polygons} polygons, ${st.light_samples} light sample(s); ` +
    `${f.shadows}: ${st.time_ms.total.toFixed(1)} ms; ${diff}.` +
    (f.outlines_total > f.outlines.length ? ` Drawn: ${f.outlines.length} of ${f.outlines_total} stage polygons.` : "") +
    (f.penumbra && f.penumbra.light !== null
      ? ` Area light ${f.penumbra.light}: ${f.penumbra.umbra_total} pixel(s) in its umbra, ${f.penumbra.penumbra_total} in its penumbra (blue, with the box ticked).`
      : "");
  const rows = [];
  for (const [k, v] of Object.entries(st.time_ms)) rows.push({ cells: ["time", k, `${v.toFixed(2)} ms`] });
  for (const [k, v] of Object.entries(st.visibility_counters)) rows.push({ cells: ["visibility", k, `${v}`] });
  for (const [k, v] of Object.entries(st.shadow_counters)) rows.push({ cells: ["shadow", k, `${v}`] });
  fillTable($("counters"), ["", "counter", "value"], rows);
}

function edgeRows(list) {
  return list.map((e) => ({
    cells: [`${e.polygon}`, `${e.face}`, `${e.first_line}..${e.end_line}`, `(${f3(e.top[0])}, ${f3(e.top[1])})`, f3(e.dxdy)],
  }));
}

function drawTrace() {
  const t = state.trace;
  if (!t) return;
  const inRun = (a, b) => state.x !== null && a <= state.x && state.x < b;
  $("aet").dataset.line = t.line;
  fillTable($("entering"), ["polygon", "face", "lines", "top", "dx/dy"], edgeRows(t.entering));
  fillTable($("leaving"), ["polygon", "face", "lines", "top", "dx/dy"], edgeRows(t.leaving));
  fillTable($("aet"), ["x", "polygon", "face"],
    t.active.map(([x, p]) => ({ cells: [f3(x), `${p}`, `${faceOf(p)}`] })));
  fillTable($("spans"), ["pixels", "covering (face: 1/z at the ends)", "verdict"],
    t.spans.map((s) => ({
      cells: [
        `${"  ".repeat(s.depth)}${s.x0}..${s.x1}`,
        s.covering.map((c) => `${c[1]}: ${c[2].toFixed(4)}..${c[3].toFixed(4)}`).join(", "),
        s.split_at !== null ? `split at ${s.split_at}` : `polygon ${s.nearest[0]} wins`,
      ],
      picked: inRun(s.x0, s.x1),
    })));
  const runs = $("runs");
  runs.replaceChildren();
  for (const r of t.runs) {
    const li = cell("li", "");
    const sw = cell("span", "", { class: "swatch" });
    sw.style.background = colour(r.poly);
    li.append(sw, `${r.x0}..${r.x1}: polygon ${r.poly}`);
    if (inRun(r.x0, r.x1)) li.className = "picked";
    runs.appendChild(li);
  }
  drawCut(t);
  drawStage(t);
  drawPixel(t);
  drawOverlay();
}

function faceOf(poly) {
  const t = state.trace;
  for (const s of t.spans) for (const c of s.covering) if (c[0] === poly) return c[1];
  for (const e of t.entering.concat(t.leaving)) if (e.polygon === poly) return e.face;
  return "";
}

function fitCanvas(canvas) {
  const w = Math.max(300, canvas.clientWidth || 600);
  canvas.width = w;
  return canvas.getContext("2d");
}

function drawCut(t) {
  const c = $("cut"), g = fitCanvas(c), W = c.width, H = c.height, pad = 14;
  g.clearRect(0, 0, W, H);
  const zs = [];
  for (const s of t.spans) for (const cv of s.covering) zs.push(1 / cv[2], 1 / cv[3]);
  const finite = zs.filter((z) => Number.isFinite(z));
  if (!finite.length) {
    g.fillStyle = "#4a5160";
    g.fillText("nothing crosses this line", pad, H / 2);
    return;
  }
  let lo = Math.min(...finite), hi = Math.max(...finite);
  if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
  const X = (x) => (x / state.width) * W;
  const Z = (z) => pad + ((z - lo) / (hi - lo)) * (H - 2 * pad);
  const winner = (x) => (t.runs.find((r) => r.x0 <= x && x < r.x1) || {}).poly;
  for (const s of t.spans) {
    g.strokeStyle = s.split_at !== null ? "rgba(220, 30, 30, 0.8)" : "rgba(0, 0, 0, 0.12)";
    g.beginPath(); g.moveTo(X(s.x0), 0); g.lineTo(X(s.x0), H); g.stroke();
    for (const [poly, , iz0, iz1] of s.covering) {
      const wins = s.split_at === null && winner(s.x0) === poly;
      g.strokeStyle = colour(poly, wins ? 1 : 0.45);
      g.lineWidth = wins ? 4 : 1.5;
      g.beginPath();
      g.moveTo(X(s.x0 + 0.5), Z(1 / iz0));
      g.lineTo(X(s.x1 - 0.5), Z(1 / iz1));
      g.stroke();
    }
  }
  g.lineWidth = 1;
  g.fillStyle = "#4a5160";
  g.fillText(`near z = ${lo.toPrecision(4)}`, 4, 10);
  g.fillText(`far z = ${hi.toPrecision(4)}`, 4, H - 3);
  if (state.x !== null) {
    g.strokeStyle = "rgba(0, 150, 200, 0.9)";
    g.beginPath(); g.moveTo(X(state.x + 0.5), 0); g.lineTo(X(state.x + 0.5), H); g.stroke();
  }
}

// The decision shown in the stage canvas: the picked pixel's run, or the first the stage was asked.
function pickedDecision(t) {
  const asked = t.decisions.filter((d) => d.asked_stage);
  if (state.x !== null) {
    const d = t.decisions.find((d) => d.x0 <= state.x && state.x < d.x1 && d.asked_stage) ||
      t.decisions.find((d) => d.x0 <= state.x && state.x < d.x1);
    if (d) return d;
  }
  return asked.find((d) => d.decision.detail.kind !== "none" && hasDetail(d.decision.detail)) || asked[0] || t.decisions[0];
}

function hasDetail(d) {
  return (d.covers && d.covers.length) || (d.adds && d.adds.length) || (d.segments && d.segments.length > 1);
}

function drawStage(t) {
  const panel = $("stage-panel");
  panel.dataset.stage = state.stage;
  $("stage-title").textContent = `Shadow stage: ${t.shadows}`;
  $("stage-intro").textContent = state.scene.descriptions[state.stage] || "";
  const d = pickedDecision(t);
  $("stage-map-box").hidden = true;
  const c = $("stage-canvas");
  c.height = 30 + 18 * (d ? rowsOf(d.decision.detail) : 1);
  const g = fitCanvas(c);
  g.clearRect(0, 0, c.width, c.height);
  fillTable($("decisions"), ["run", "polygon", "light.sample", "lit pixels", "the stage's account"],
    t.decisions.map((e) => ({
      cells: [`${e.x0}..${e.x1}`, `${e.polygon}`, `${e.light}.${e.sample}`,
        e.lit.map(([a, b, v]) => `${a}..${b}: ${+v.toFixed(3)}`).join(", "), e.decision.note],
      picked: e === d,
    })));
  if (!d) {
    $("stage-pick").textContent = "No visible run on this line.";
    return;
  }
  $("stage-pick").textContent =
    `Run ${d.x0}..${d.x1} on polygon ${d.polygon}, light ${d.light} sample ${d.sample}: ${d.decision.note}`;
  $("stage-extra").textContent = extra(d);
  const W = c.width, left = 40, X = (x) => left + ((x - d.x0) / Math.max(1, d.x1 - d.x0)) * (W - left - 8);
  const bar = (a, b, row, fill, label) => {
    g.fillStyle = fill;
    g.fillRect(X(a), 6 + row * 18, Math.max(1, X(b) - X(a)), 14);
    if (label) { g.fillStyle = "#1d2330"; g.fillText(label, X(a) + 2, 17 + row * 18); }
  };
  const name = (row, text) => { g.fillStyle = "#4a5160"; g.fillText(text, 2, 17 + row * 18); };
  let row = 0;
  name(row, "lit");
  for (const [a, b, v] of d.lit) bar(a, b, row, v > 0 ? `rgba(250, 200, 40, ${0.3 + 0.7 * v})` : "#243a73", null);
  row++;
  const detail = d.decision.detail;
  if (detail.kind === "segments") {
    for (const cv of detail.covers) { name(row, `#${cv.polygon}`); bar(cv.start, cv.end, row++, "rgba(36, 58, 115, 0.35)", "shadow polygon"); }
    const fill = { "lit": "rgba(250, 200, 40, 0.9)", "shadow": "#243a73", "split": "rgba(160, 160, 160, 0.5)" };
    for (const s of detail.segments) {
      name(row + s.depth, `d${s.depth}`);
      bar(s.start, s.end, row + s.depth, fill[s.outcome], s.outcome === "split" ? "split" : null);
    }
  } else if (detail.kind === "counts") {
    for (const a of detail.adds) {
      name(row, a.far_caps ? "far" : `#${a.polygon}`);
      bar(a.start, a.end, row++, a.add > 0 ? "rgba(200, 60, 60, 0.6)" : "rgba(60, 120, 200, 0.6)",
        `${a.add > 0 ? "+" : ""}${a.add}${a.near_cap ? " (eye)" : ""}${a.far_caps ? " (far caps)" : ""}`);
    }
    name(row, "count");
    for (const [a, b, n] of detail.counts) bar(a, b, row, n === 0 ? "rgba(250, 200, 40, 0.9)" : "#243a73", `${n}`);
    row++;
  } else if (detail.kind === "texels") {
    drawTexels(g, detail, d, X, row, c.height);
    showMap(detail, d);
  } else if (detail.kind === "covers") {
    for (const cv of detail.covers) { name(row, `#${cv.polygon}`); bar(cv.start, cv.end, row++, "rgba(250, 200, 40, 0.7)", "lit detail polygon"); }
  }
  g.fillStyle = "#4a5160";
  g.fillText(`${d.x0}`, left, c.height - 4);
  g.fillText(`${d.x1}`, W - 30, c.height - 4);
}

// What the stage found before the walk, in words.
function extra(d) {
  const detail = d.decision.detail;
  if (detail.kind === "segments" && !detail.pairs && STATIC) {
    return "Steps 1-3 (the pairs the prefilter kept for this receiver) are shown by the live page only.";
  }
  if (detail.kind === "segments" && detail.pairs) {
    const p = detail.pairs;
    const from = p.shadow_polygons.map(([tag, caster]) => `#${tag} from polygon ${caster}`);
    return `Steps 1-3 for polygon ${d.polygon}: the sphere prefilter kept ${p.kept.length} caster(s) ` +
      `[${p.kept.join(", ")}]; ${p.behind.length} lie wholly behind it as the light sees it` +
      `${p.behind.length ? ` [${p.behind.join(", ")}]` : ""}; the others project to ` +
      `${from.length} shadow polygon(s) on it: ${from.join(", ") || "none"}.`;
  }
  if (detail.kind === "texels") {
    const inside = detail.texels.filter((t) => t.map !== null);
    return `A ${detail.size}² map, ${detail.kernel === 1 ? "one texel" : `${detail.kernel}×${detail.kernel} texels`} compared per pixel. ` +
      `Below: the nearness the map holds at each pixel's texel (dots) and the pixel's own, with the ` +
      `bias (line); where the map holds more, the texel hides the point. ${inside.length} of ` +
      `${detail.texels.length} pixels fall on drawn texels. Right: their path across the map.`;
  }
  return "";
}

// Williams: the map's nearness at each pixel's texel against the point's threshold, and the
// pixels' path across the map.
function drawTexels(g, detail, d, X, row, height) {
  const ts = detail.texels, top = 6 + row * 18, bottom = height - 16;
  const values = ts.flatMap((t) => [t.map, t.threshold]).filter((v) => v !== null && Number.isFinite(v));
  if (!values.length) return;
  let lo = Math.min(...values), hi = Math.max(...values);
  if (hi - lo < 1e-12) { lo -= 1e-6; hi += 1e-6; }
  const Y = (v) => bottom - ((v - lo) / (hi - lo)) * (bottom - top);
  const width = g.canvas.width, plotRight = width - 130;
  const Xp = (x) => X(x) * (plotRight / width);
  g.strokeStyle = "rgba(200, 150, 0, 0.95)";
  g.beginPath();
  ts.forEach((t, i) => Number.isFinite(t.threshold) &&
    (i ? g.lineTo(Xp(t.x + 0.5), Y(t.threshold)) : g.moveTo(Xp(t.x + 0.5), Y(t.threshold))));
  g.stroke();
  for (const t of ts) {
    if (t.map === null) continue;
    g.fillStyle = t.map > t.threshold ? "#243a73" : "rgba(36, 58, 115, 0.35)";
    g.fillRect(Xp(t.x + 0.5) - 1.5, Y(t.map) - 1.5, 3, 3);
  }
  g.fillStyle = "#4a5160";
  g.fillText("nearness", 2, top + 10);
  // The path across the map, in a square at the right.
  const side = Math.min(110, bottom - top), x0 = width - side - 8, y0 = top;
  g.strokeStyle = "#bbb";
  g.strokeRect(x0, y0, side, side);
  g.fillStyle = "rgba(36, 58, 115, 0.8)";
  for (const t of ts) {
    if (!Number.isFinite(t.u) || !Number.isFinite(t.v)) continue;
    g.fillRect(x0 + (t.u / detail.size) * side - 1, y0 + (t.v / detail.size) * side - 1, 2, 2);
  }
  g.fillStyle = "#4a5160";
  g.fillText("map", x0, y0 + side + 11);
}

// Williams: the shadow map the run looked up (the face most of its pixels fall in), with the
// path of its lookups drawn over it.
function showMap(detail, d) {
  const pictures = (state.frame && state.frame.pictures) || [];
  const faces = detail.texels.map((t) => t.face);
  const face = faces.sort((a, b) => faces.filter((f) => f === b).length - faces.filter((f) => f === a).length)[0] || 0;
  const index = pictures.findIndex((p) => p.light === d.light && p.sample === d.sample && p.face === face);
  if (index < 0) return;
  const src = STATIC ? `pictures/${state.stage}-${index}.png` : `api/picture?${params({ index })}`;
  const img = $("stage-map");
  if (img.getAttribute("src") !== src) img.src = src;
  const c = $("stage-map-path"), g = c.getContext("2d"), size = pictures[index].size;
  c.width = c.height = 256;
  g.clearRect(0, 0, 256, 256);
  g.fillStyle = "rgba(255, 60, 40, 0.9)";
  for (const t of detail.texels) {
    if (t.face !== face || !Number.isFinite(t.u) || !Number.isFinite(t.v)) continue;
    g.fillRect((t.u / size) * 256 - 1, (t.v / size) * 256 - 1, 2, 2);
  }
  $("stage-map-caption").textContent =
    `Light ${d.light} sample ${d.sample}${pictures.length > 1 ? `, cube face ${face}` : ""}: the ${size}² depth map ` +
    "(nearer is brighter, black where nothing was drawn); red: the texels this run looked up.";
  $("stage-map-box").hidden = false;
}

// Rows of the stage canvas: the lit row and the detail's own.
function rowsOf(detail) {
  switch (detail.kind) {
    case "segments": return 2 + detail.covers.length + Math.max(0, ...detail.segments.map((s) => s.depth));
    case "counts": return 2 + detail.adds.length;
    case "covers": return 1 + detail.covers.length;
    case "texels": return 9;
    default: return 1;
  }
}

function drawPixel(t) {
  if (state.x === null) { $("pixel").textContent = "No pixel picked."; return; }
  const r = t.runs.find((r) => r.x0 <= state.x && state.x < r.x1);
  const lit = t.decisions.filter((d) => d.x0 <= state.x && state.x < d.x1)
    .map((d) => `light ${d.light}.${d.sample}: ${(d.lit.find(([a, b]) => a <= state.x && state.x < b) || [0, 0, 0])[2]}`);
  $("pixel").textContent = `Pixel (${state.x}, ${t.line}): ` +
    (r ? `polygon ${r.poly} (face ${faceOf(r.poly)}); ${lit.join(", ")}` : "background");
  loadLightView();
}

// --- the picked point's view of an area light -------------------------------------------------

// What the picked pixel's point sees of the scene's first area light (the served page only:
// any pixel can be asked; the export holds no such answers).
async function loadLightView() {
  const area = !STATIC && state.x !== null && state.scene.lights.some((l) => l.kind === "area");
  if (!area) { $("light-view").hidden = true; state.lightKey = null; return; }
  const key = `${params()}|${state.x}|${state.line}`;
  if (state.lightKey === key) return;
  state.lightKey = key;
  try {
    const v = await api("light", { x: state.x, line: state.line });
    if (state.lightKey === key) drawLightView(v);
  } catch (e) {
    if (state.lightKey === key) showError(e);
  }
}

// `ring` clipped to the box [lo, hi]² (Sutherland-Hodgman): shadows can reach far beyond the
// light, and a canvas draws huge coordinates badly.
function clipToBox(ring, lo, hi) {
  let out = ring;
  const sides = [[0, lo, 1], [0, hi, -1], [1, lo, 1], [1, hi, -1]];
  for (const [axis, at, sign] of sides) {
    const input = out;
    out = [];
    for (let i = 0; i < input.length; i++) {
      const p = input[i], q = input[(i + 1) % input.length];
      const dp = sign * (p[axis] - at), dq = sign * (q[axis] - at);
      if (dp >= 0) out.push(p);
      if ((dp >= 0) !== (dq >= 0)) {
        const t = dp / (dp - dq);
        out.push([p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t]);
      }
    }
  }
  return out;
}

function drawLightView(v) {
  const c = $("light-canvas"), g = c.getContext("2d");
  $("light-view").hidden = false;
  const S = c.width, m = 36, side = S - 2 * m;
  const X = (a) => m + a * side, Y = (b) => S - m - b * side;
  const trace = (ring) => {
    const r = clipToBox(ring, -0.15, 1.15);
    r.forEach(([a, b], i) => (i ? g.lineTo(X(a), Y(b)) : g.moveTo(X(a), Y(b))));
    g.closePath();
  };
  g.clearRect(0, 0, S, S);
  if (!v.seen) {
    $("light-caption").textContent = `No polygon is seen at pixel (${state.x}, ${state.line}).`;
    return;
  }
  // The light: dark where hidden, yellow where the point sees it.
  g.fillStyle = "#3a3a3a";
  g.fillRect(X(0), Y(1), side, side);
  g.fillStyle = "#ffd84a";
  g.beginPath();
  v.visible.forEach(trace);
  g.fill("evenodd");
  // Each occluder's shadow from the point, outlined; the part behind the polygon's plane dashed.
  g.lineWidth = 1.5;
  g.strokeStyle = "#3b8eea";
  for (const h of v.hidden) { g.beginPath(); trace(h.ring); g.stroke(); }
  if (v.cut.length) {
    g.strokeStyle = "#d33"; g.setLineDash([5, 3]);
    g.beginPath(); trace(v.cut); g.stroke();
    g.setLineDash([]);
  }
  g.strokeStyle = "#000"; g.lineWidth = 1;
  g.strokeRect(X(0), Y(1), side, side);
  g.fillStyle = "#000"; g.font = "11px sans-serif";
  g.fillText("a →", X(1) - 22, Y(0) + 16);
  g.fillText("b ↑", X(0) - 30, Y(1) + 10);
  const inPenumbra = v.fraction > 0 && v.fraction < 1;
  $("light-caption").textContent =
    `What the point at pixel (${v.x}, ${v.line}) sees of area light ${v.light}, drawn as the square of ` +
    `its coordinates (a, b): yellow where it sees the light, dark where not; blue: the shadows of ` +
    `${v.hidden.length} occluder(s) from the point` + (v.cut.length ? "; dashed red: the part behind its polygon's plane" : "") +
    `. Exact fraction ${v.fraction.toFixed(4)}` + (inPenumbra ? " (penumbra)." : v.fraction === 0 ? " (umbra)." : " (lit).");
}

// --- set-up ---------------------------------------------------------------------------------

function pointer(e) {
  const rect = $("overlay").getBoundingClientRect();
  const x = Math.floor((e.clientX - rect.left) / state.scale), y = Math.floor((e.clientY - rect.top) / state.scale);
  setLine(y, x);
}

function setUpControls() {
  const sc = state.scene;
  const stage = $("stage");
  const stages = STATIC ? sc.stages.filter((s) => STATIC.frames[s]) : sc.stages;
  for (const s of stages) stage.appendChild(cell("option", s, { value: s }));
  state.stage = stages.includes(sc.default_stage) ? sc.default_stage : stages[0];
  stage.value = state.stage;
  // The paper path: live only, for the stages that have one.
  const paper = $("paper");
  const paperFits = () => { paper.disabled = !sc.paper_stages.includes(state.stage); };
  state.paper = paper.checked = !STATIC && sc.paper;
  paperFits();
  paper.onchange = () => { state.paper = paper.checked; loadFrame(); };
  stage.onchange = () => { state.stage = stage.value; paperFits(); loadFrame(); };

  const size = $("size");
  const aspect = sc.height / sc.width;
  const widths = [...new Set([160, 240, 320, 480, 640, 960, sc.width])].filter((w) => w <= sc.max_side).sort((a, b) => a - b);
  for (const w of widths) {
    const h = Math.max(1, Math.round(w * aspect));
    size.appendChild(cell("option", `${w}×${h}`, { value: `${w}x${h}` }));
  }
  const start = widths.filter((w) => w <= 320).pop() || widths[0];
  state.width = start;
  state.height = Math.max(1, Math.round(start * aspect));
  size.value = `${state.width}x${state.height}`;
  if (STATIC) { state.width = sc.width; state.height = sc.height; }
  size.onchange = () => {
    [state.width, state.height] = size.value.split("x").map(Number);
    state.line = Math.min(state.line, state.height - 1);
    state.x = null;
    loadFrame();
  };

  const light = sc.lights[0];
  if (!light || STATIC) {
    $("light-controls").hidden = true;
  } else {
    const [lo, hi] = sc.bounds, span = Math.max(...hi.map((v, i) => v - lo[i]), 1);
    const at = light.kind === "directional"
      ? hi.map((v, i) => (v + lo[i]) / 2 - light.at[i] * span) : light.at;
    ["x", "y", "z"].forEach((axis, i) => {
      const input = $(`light-${axis}`);
      input.min = Math.min(lo[i] - span, at[i]);
      input.max = Math.max(hi[i] + span, at[i]);
      input.value = at[i];
      input.onchange = () => {
        state.light = ["x", "y", "z"].map((a) => Number($(`light-${a}`).value));
        loadFrame();
      };
    });
  }

  $("line").max = state.height - 1;
  $("line").onchange = () => setLine(Number($("line").value));
  $("play").onclick = togglePlay;
  $("show-outlines").onchange = drawOverlay;
  $("show-differs").onchange = drawOverlay;
  $("show-penumbra").onchange = drawOverlay;
  const ov = $("overlay");
  ov.onpointerdown = (e) => { ov.setPointerCapture(e.pointerId); pointer(e); };
  ov.onpointermove = (e) => { if (e.buttons) pointer(e); };
  document.addEventListener("keydown", (e) => {
    if (e.target.tagName === "INPUT" || e.target.tagName === "SELECT") return;
    const step = { ArrowUp: [-1, 0], ArrowDown: [1, 0], ArrowLeft: [0, -1], ArrowRight: [0, 1] }[e.key];
    if (!step) return;
    e.preventDefault();
    setLine(state.line + step[0], (state.x === null ? 0 : state.x + step[1]));
  });
  window.addEventListener("resize", () => state.trace && drawTrace());
}

async function start() {
  try {
    if (STATIC) document.body.classList.add("static");
    state.scene = STATIC ? STATIC.scene : await fetch("api/scene").then((r) => r.json());
    $("scene-name").textContent = state.scene.name;
    setUpControls();
    state.line = Math.floor(state.height / 2);
    $("line").value = state.line;
    await loadFrame();
  } catch (e) {
    showError(e);
    busy(null);
  }
}

start();
