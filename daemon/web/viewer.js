// naneye's live viewer. Everything comes from this daemon (same origin); the page only reads the public
// API, as any HTTP client does, so the pipeline never waits for it (docs/viewer.md).
import { CloudView } from "./cloud.js";
import { LatencyPlot } from "./plot.js";

const $ = (id) => document.getElementById(id);
const FRAME_INTERVAL_MS = 200;   // frames: 5 per second is enough to judge focus and placement
const STATUS_INTERVAL_MS = 1000; // health panel and latency plot
const STALE_MS = 2000;           // a result older than this is called stale on the page
const HISTORY = 256;             // results kept by pair (4 s at 62 fps: frames lag results by < 1 s)

const view = {
  latest: null,        // the latest /v1/depth object (from /v1/events)
  latestAt: 0,         // performance.now() when it arrived
  status: null,
  connected: false,
  framesPair: null,    // pair of the frames shown
  depthPair: null,     // pair of the depth map shown
  byPair: new Map(),   // the last results by pair number, so that an overlay matches its frame
  cloudFrom: null,     // the result the 3D view shows: the latest one with valid points
  sensor: { w: 250, h: 250 },
};
const cloud = new CloudView($("cloud"));
const plot = new LatencyPlot($("latency"), 120);
window.naneyeViewer = { view, cloud, plot };  // read by the browser tests

function banner(text, level = "error") {
  const b = $("banner");
  b.hidden = !text;
  b.textContent = text || "";
  b.dataset.level = level;
}

function setState(state) {
  const s = $("state");
  s.textContent = state.replaceAll("_", " ");
  s.dataset.state = state;
}

// ---- events: one result per processed pair; drawn at most once per animation frame -----------------
let dirty = false;
function connectEvents() {
  const es = new EventSource("/v1/events");
  es.addEventListener("result", (e) => {
    view.latest = JSON.parse(e.data);
    view.latestAt = performance.now();
    view.byPair.set(view.latest.pair, view.latest);
    if (view.byPair.size > HISTORY) view.byPair.delete(view.byPair.keys().next().value);
    view.connected = true;
    if (!dirty) {
      dirty = true;
      requestAnimationFrame(drawResult);
    }
  });
  es.addEventListener("dropped", () => {}); // the browser reconnects with Last-Event-ID
  es.onerror = () => {
    view.connected = false;
    // EventSource retries by itself; a 503 (too many clients) closes it for good: retry by hand.
    if (es.readyState === EventSource.CLOSED) setTimeout(connectEvents, 2000);
    updateBanner();
  };
}

function scenePoints(r) {
  const pts = [];
  for (const p of r.points || []) if (p.valid && p.xyz_mm) pts.push({ xyz: p.xyz_mm, sigma: p.depth_sigma_mm, scene: false });
  for (const p of (r.scene && r.scene.points) || []) if (p.valid && p.xyz_mm) pts.push({ xyz: p.xyz_mm, sigma: p.depth_sigma_mm, scene: true });
  return pts;
}

function drawResult() {
  dirty = false;
  const r = view.latest;
  if (!r) return;
  $("pair").textContent = r.pair;
  // The 3D view keeps the latest result that has points, and says which pair it is: a board lost
  // for a few pairs should not blank the view.
  const pts = scenePoints(r);
  if (pts.length || !view.cloudFrom) {
    view.cloudFrom = { pair: r.pair, at: performance.now() };
    cloud.set(pts, boardOutline(r));
  }
  const ago = (performance.now() - view.cloudFrom.at) / 1000;
  $("cloud-legend").textContent = `Pair ${view.cloudFrom.pair}` + (ago > 0.5 ? ` (${ago.toFixed(1)} s ago: no points since)` : "") + ".";
  drawOverlays();
}

// The board's outline in the left camera's frame: the rectangle of its inner corners plus one square
// around them, from the corners on the fitted plane (xyz_board_mm, camera frame) at the four extreme
// (row, col) positions. None when one of those four is missing.
function boardOutline(r) {
  if (!r.board || !r.points) return null;
  const on = r.points.filter((p) => p.xyz_board_mm);
  if (on.length < 4) return null;
  const rows = Math.max(...on.map((p) => p.row)), cols = Math.max(...on.map((p) => p.col));
  if (rows < 1 || cols < 1) return null;
  const at = (row, col) => on.find((p) => p.row === row && p.col === col);
  const a = at(0, 0), b = at(0, cols), c = at(rows, cols), d = at(rows, 0);
  if (!a || !b || !c || !d) return null;
  const A = a.xyz_board_mm, B = b.xyz_board_mm, C = c.xyz_board_mm, D = d.xyz_board_mm;
  const stepCol = [0, 1, 2].map((k) => (B[k] - A[k]) / cols), stepRow = [0, 1, 2].map((k) => (D[k] - A[k]) / rows);
  const move = (P, sc, sr) => [0, 1, 2].map((k) => P[k] + sc * stepCol[k] + sr * stepRow[k]);
  return [move(A, -1, -1), move(B, 1, -1), move(C, 1, 1), move(D, -1, 1)];
}

// ---- frames, fold shading, overlays -----------------------------------------------------------------
const foldMask = { left: null, right: null };  // ImageData of the shading beyond the fold

async function loadFoldMasks() {
  for (const eye of ["left", "right"]) {
    try {
      const res = await fetch(`/v1/domain/${eye}.png`);
      if (!res.ok) continue;
      const bmp = await createImageBitmap(await res.blob());
      const c = new OffscreenCanvas(bmp.width, bmp.height);
      const g = c.getContext("2d");
      g.drawImage(bmp, 0, 0);
      const src = g.getImageData(0, 0, bmp.width, bmp.height);
      const out = new ImageData(bmp.width, bmp.height);
      for (let i = 0; i < src.data.length; i += 4) {
        const outside = src.data[i] < 128;
        out.data[i] = 180; out.data[i + 1] = 30; out.data[i + 2] = 30;
        out.data[i + 3] = outside ? 110 : 0;
      }
      foldMask[eye] = out;
      view.sensor = { w: bmp.width, h: bmp.height };
    } catch (e) {
      console.warn("fold mask", eye, e);
    }
  }
  drawOverlays();
}

function drawOverlays() {
  // The result of the pair whose frames are shown (frames are copied at most every
  // pipeline.frame_snapshot_interval_ms, results come with every pair).
  const r = view.byPair.get(view.framesPair) || null;
  for (const eye of ["left", "right"]) {
    const canvas = $(`ov-${eye}`);
    const g = canvas.getContext("2d");
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clearRect(0, 0, canvas.width, canvas.height);
    const scale = canvas.width / view.sensor.w;
    if ($("fold").checked && foldMask[eye]) {
      const tmp = new OffscreenCanvas(foldMask[eye].width, foldMask[eye].height);
      tmp.getContext("2d").putImageData(foldMask[eye], 0, 0);
      g.imageSmoothingEnabled = false;
      g.drawImage(tmp, 0, 0, canvas.width, canvas.height);
    }
    if (!$("overlay").checked || !r) continue;
    // Pixel centres at integer coordinates: pixel (u, v) covers [u - 0.5, u + 0.5].
    const at = (px) => [(px[0] + 0.5) * scale, (px[1] + 0.5) * scale];
    const key = `${eye}_px`;
    g.font = "9px system-ui, sans-serif";
    for (const p of r.points || []) {
      if (!p[key]) continue;
      const [x, y] = at(p[key]);
      g.strokeStyle = p.id === 0 ? "#ff3030" : p.valid ? "#3fb950" : "#d29922";
      g.lineWidth = p.id === 0 ? 2 : 1;
      g.beginPath();
      g.arc(x, y, p.id === 0 ? 6 : 4, 0, 2 * Math.PI);
      g.stroke();
      g.fillStyle = "#ffffff";
      g.fillText(String(p.id), x + 5, y - 5);
    }
    for (const p of (r.scene && r.scene.points) || []) {
      if (!p[key]) continue;
      const [x, y] = at(p[key]);
      g.strokeStyle = p.valid ? "#58a6ff" : "#8a939c";
      g.strokeRect(x - 2, y - 2, 4, 4);
    }
  }
  // The valid scene features over the depth map of the same pair (the map and its features agree).
  const d = $("ov-depth").getContext("2d");
  d.clearRect(0, 0, 250, 250);
  const rd = view.byPair.get(view.depthPair);
  if ($("overlay").checked && rd && rd.scene) {
    d.strokeStyle = "rgba(255,255,255,0.8)";
    for (const p of rd.scene.points) if (p.valid) d.strokeRect(p.left_px[0] - 1, p.left_px[1] - 1, 3, 3);
  }
}

async function refreshFrame(eye) {
  const res = await fetch(`/v1/frames/${eye}.png`, { cache: "no-store" });
  if (!res.ok) return null;
  const url = URL.createObjectURL(await res.blob());
  const img = $(`img-${eye}`);
  const old = img.src;
  img.src = url;
  if (old.startsWith("blob:")) URL.revokeObjectURL(old);
  return res.headers.get("X-Naneye-Pair");
}

async function frameLoop() {
  // Frames exist once a pair has been processed: asking before would only collect 503s (a slow
  // source, e.g. the simulator rendering a textured scene, takes seconds for its first pair).
  if (!view.latest) return setTimeout(frameLoop, FRAME_INTERVAL_MS);
  try {
    const [pl] = await Promise.all([refreshFrame("left"), refreshFrame("right"), refreshDepth()]);
    if (pl !== null) view.framesPair = Number(pl);
    drawOverlays();
  } catch (e) {
    // the daemon is away: the banner says so, the loop goes on
  }
  setTimeout(frameLoop, FRAME_INTERVAL_MS);
}

// ---- depth map and the depth under the pointer ----------------------------------------------------
// Only asked for while the latest result carries a dense map (scene reconstruction on): no request the
// daemon must refuse.
async function refreshDepth() {
  const r = view.latest;
  const dense = r && r.scene && r.scene.depth;
  const img = $("img-depth");
  $("dl-depth").hidden = !dense;
  if (!dense) {
    $("depth-note").textContent = r && r.scene
      ? "No dense depth map in the latest result: the depth under the pointer comes from the board plane."
      : "No dense depth map in the latest result (scene reconstruction off): the depth under the pointer comes from the board plane.";
    img.hidden = true;
    view.depthPair = null;
    return;
  }
  // The calibration's sigma exists only when the calibration carries its covariance (null median
  // otherwise): the choice is offered only then, and falls back to the depth when it goes away.
  const select = $("depth-layer");
  const calibOption = select.querySelector('option[value="calib_sigma"]');
  calibOption.hidden = dense.calib_sigma_median_mm === null || dense.calib_sigma_median_mm === undefined;
  if (calibOption.hidden && select.value === "calib_sigma") select.value = "depth";
  const layer = select.value;
  const res = await fetch(`/v1/depth/colour.png?layer=${layer}`, { cache: "no-store" });
  if (!res.ok) return;  // 503 while a newer map replaced this one: the next round fetches it
  // The image is the layer on the left raw grid with its scale bar (mm) below; the scale's ends are
  // also given as headers (the 1st and 99th percentiles of this pair's values).
  const lo = res.headers.get("X-Naneye-Scale-Min-Mm"), hi = res.headers.get("X-Naneye-Scale-Max-Mm");
  view.depthPair = Number(res.headers.get("X-Naneye-Pair"));
  const share = (100 * dense.valid_share).toFixed(1);
  const median = dense.median_mm === null ? "-" : `${dense.median_mm.toFixed(2)} mm`;
  const what = { depth: "depth", sigma: "each depth's match sigma", calib_sigma: "each depth's calibration sigma" }[layer];
  $("depth-note").textContent = `Pair ${view.depthPair}: ${what} on the left raw pixel grid, scale ${lo}-${hi} mm; ` +
    `black: no depth. Depth at ${share} % of the pixels both eyes see, median ${median}.`;
  $("dl-depth").href = `/v1/depth.png?layer=${layer}`;
  $("dl-depth").download = `${layer}.png`;
  img.hidden = false;
  const url = URL.createObjectURL(await res.blob());
  const old = img.src;
  img.src = url;
  if (old.startsWith("blob:")) URL.revokeObjectURL(old);
}

let depthAtPending = false;
function pointerDepth(e, el) {
  const rect = el.getBoundingClientRect();
  const u = ((e.clientX - rect.left) / rect.width) * view.sensor.w - 0.5;
  const v = ((e.clientY - rect.top) / rect.height) * view.sensor.h - 0.5;
  if (depthAtPending) return;
  depthAtPending = true;
  fetch(`/v1/depth/at?u=${u.toFixed(2)}&v=${v.toFixed(2)}`)
    .then((res) => res.json())
    .then((j) => {
      const where = `(${u.toFixed(1)}, ${v.toFixed(1)})`;
      const from = { dense: "dense map", board_plane: "board plane" }[j.source] || j.source;
      $("depth-at").textContent = j.error
        ? `${where}: ${j.error.replaceAll("_", " ")}`
        : `${where}: ${j.depth_mm.toFixed(2)} mm ± ${j.depth_sigma_mm.toFixed(3)} mm (${from}, pair ${j.pair})`;
      $("depth-at").dataset.source = j.source || "";
    })
    .catch(() => {})
    .finally(() => { depthAtPending = false; });
}
for (const id of ["ov-left", "ov-depth"]) $(id).addEventListener("pointermove", (e) => pointerDepth(e, $(id)));

// ---- health -------------------------------------------------------------------------------------------
const fmt = (x, d = 2) => (x === null || x === undefined ? "-" : typeof x === "number" ? x.toFixed(d) : String(x));

function fillTable(tbody, rows) {
  tbody.replaceChildren(...rows.map(([k, v, id]) => {
    const tr = document.createElement("tr");
    const a = document.createElement("td");
    const b = document.createElement("td");
    a.textContent = k;
    b.textContent = v;
    if (id) b.id = id;
    tr.append(a, b);
    return tr;
  }));
}

function renderStatus(s) {
  const r = view.latest;
  const m = r && r.metrics;
  fillTable($("health").tBodies[0], [
    ["state", s.state, "h-state"],
    ["source", `${s.source.kind ?? "-"}: ${s.source.uri}`, "h-source"],
    ["source state", s.source.state + (s.source.error ? ` (${s.source.error})` : "")],
    ["fallback", s.source.fallback ? `yes: ${s.source.reason}` : "no", "h-fallback"],
    ["fps left / right", `${fmt(s.fps.left, 1)} / ${fmt(s.fps.right, 1)}`, "h-fps"],
    ["left/right offset", `${fmt(s.offset_ms, 3)} ms`],
    ["pairs processed / dropped", `${s.pairs.processed} / ${s.pairs.dropped}`, "h-pairs"],
    ["recon p50 / p99", `${fmt(s.recon_ms.p50, 3)} / ${fmt(s.recon_ms.p99, 3)} ms`],
    ["capture to publish p50 / p99", `${fmt(s.capture_to_publish_ms.p50, 3)} / ${fmt(s.capture_to_publish_ms.p99, 3)} ms`],
    ["board", r ? (r.board_found ? `found at ${fmt(r.board.distance_mm)} mm` : "not found") : "-"],
    ["P planarity", m ? `${fmt(m.planarity_mm, 4)} mm` : "-", "h-P"],
    ["D distance error", m ? `${fmt(m.distance_error_mm, 4)} mm` : "-", "h-D"],
    ["R reprojection", m ? `${fmt(m.reprojection_px, 4)} px` : "-", "h-R"],
    ["processor", s.processor],
    ["calibration", `${s.calibration.files.join(", ")} (baseline ${fmt(s.calibration.baseline_mm, 3)} mm, ${s.calibration.reloads} reloads)`],
    ["event clients", `${s.events.clients}`],
  ]);
  fillTable($("counters").tBodies[0], Object.entries(s.counters).map(([k, v]) => [k.replaceAll("_", " "), String(v), `c-${k}`]));
  plot.add(performance.now() / 1000, [s.recon_ms.p99, s.capture_to_publish_ms.p99, s.recon_ms.p50]);
}

let calibrationReloads = -1;
async function statusLoop() {
  try {
    const res = await fetch("/v1/status", { cache: "no-store" });
    const s = await res.json();
    view.status = s;
    view.statusOk = true;
    renderStatus(s);
    if (s.calibration.reloads !== calibrationReloads) {
      calibrationReloads = s.calibration.reloads;
      loadFoldMasks();
    }
  } catch (e) {
    view.statusOk = false;
  }
  updateBanner();
  setTimeout(statusLoop, STATUS_INTERVAL_MS);
}

function updateBanner() {
  const s = view.status;
  const age = view.latest ? performance.now() - view.latestAt : null;
  $("age").textContent = age === null ? "-" : `${(age / 1000).toFixed(1)} s`;
  if (!view.statusOk) {
    setState("unreachable");
    return banner("The daemon is not answering (stopped?). This page reconnects by itself when it is back.");
  }
  setState(s.state);
  if (s.state === "stopped") return banner("The stream has stopped (the replay ended or the service is stopping).");
  if (s.state === "waiting_for_device") return banner(`Waiting for the device: ${s.source.error || s.source.reason || "not attached"}`, "warn");
  if (s.state === "stalled") return banner("The stream is stalled: no pair has arrived for a while.");
  if (s.state === "starting") return banner("Starting: no result yet.", "warn");
  if (age !== null && age > STALE_MS) {
    setState("stale");
    return banner(`Stale: the latest result is ${(age / 1000).toFixed(1)} s old.`, "warn");
  }
  banner(null);
}

$("overlay").addEventListener("change", drawOverlays);
$("fold").addEventListener("change", drawOverlays);
$("colour-by").addEventListener("change", (e) => { cloud.colourBy = e.target.value; cloud.draw(); });
$("depth-layer").addEventListener("change", () => { refreshDepth(); });
$("reset-view").addEventListener("click", () => cloud.reset());
setInterval(updateBanner, 500);

connectEvents();
statusLoop();
frameLoop();
