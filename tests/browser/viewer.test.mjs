// The viewer in a real browser: Debian's chromium, headless, driven over the DevTools protocol by
// puppeteer-core, against a real naneyed replaying the bundled capture, then against one running a
// textured scene (sim://sphere, a hand-held camera; [recon] mode both). Run by ctest (viewer_browser):
//   node tests/browser/viewer.test.mjs --naneyed build/daemon/naneyed [--screenshots DIR]
// Prints one line per check and "N passed, N failed" at the end; exits non-zero on any failure.
import { spawn } from "node:child_process";
import { mkdtempSync, writeFileSync, mkdirSync } from "node:fs";
import { createServer } from "node:net";
import { tmpdir } from "node:os";
import { join, resolve, dirname } from "node:path";
import { fileURLToPath } from "node:url";
import puppeteer from "puppeteer-core";

const here = dirname(fileURLToPath(import.meta.url));
const root = resolve(here, "../..");
const arg = (name, fallback) => {
  const i = process.argv.indexOf(name);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const naneyed = resolve(arg("--naneyed", join(root, "build/daemon/naneyed")));
const capture = resolve(arg("--capture", join(root, "tests/data/sim-d3-mono/capture.raw")));
const chromium = arg("--chromium", "/usr/bin/chromium");
const screenshots = arg("--screenshots", null);

let passed = 0, failed = 0;
function check(name, ok, detail = "") {
  if (ok) ++passed; else ++failed;
  console.log(`${ok ? "PASS" : "FAIL"} ${name}${detail ? ": " + detail : ""}`);
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
async function until(what, fn, timeoutMs) {
  const end = Date.now() + timeoutMs;
  for (;;) {
    const v = await fn();
    if (v) return v;
    if (Date.now() > end) return null;
    await sleep(100);
  }
}

function freePort() {
  return new Promise((res, rej) => {
    const s = createServer();
    s.listen(0, "127.0.0.1", () => { const p = s.address().port; s.close(() => res(p)); });
    s.on("error", rej);
  });
}

const dir = mkdtempSync(join(tmpdir(), "naneye-viewer-"));
const port = await freePort();
const origin = `http://127.0.0.1:${port}`;
const config = join(dir, "naneyed.toml");
writeFileSync(config, `[source]\nuri = "file://${capture}?speed=realtime&loop=1"\n` +
  `[calibration]\npath = "${join(root, "config/calib/paper-d3.yaml")}"\n` +
  `[http]\nhost = "127.0.0.1"\nport = ${port}\n`);

let daemon = null;
// `probe` answers 200 once the daemon serves: /v1/status, or /healthz behind a token.
function startDaemon(cfg = config, at = origin, probe = "/v1/status") {
  daemon = spawn(naneyed, ["--config", cfg], { stdio: ["ignore", "ignore", "pipe"] });
  daemon.stderr.on("data", () => {});
  return until("daemon up", async () => {
    try { return (await fetch(`${at}${probe}`)).ok; } catch { return false; }
  }, 15000);
}
async function stopDaemon() {
  const exited = new Promise((r) => daemon.once("exit", r));
  daemon.kill("SIGTERM");
  await exited;
}
const status = async () => (await fetch(`${origin}/v1/status`)).json();

let browser = null;
try {
  check("naneyed serves on the bundled capture", await startDaemon());
  const index = await fetch(`${origin}/`);
  const html = await index.text();
  check("GET / is the viewer page", index.ok && index.headers.get("content-type").startsWith("text/html") && html.includes("viewer.js"));
  let bytes = html.length;
  for (const f of ["viewer.js", "cloud.js", "plot.js", "colormap.js", "viewer.css"]) bytes += (await (await fetch(`${origin}/web/${f}`)).text()).length;
  check("the page and its assets weigh under 300 kB", bytes < 300_000, `${bytes} bytes`);

  browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
      "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage"],
  });
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 1000 });
  const errors = [], foreign = [];
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", (e) => errors.push(String(e)));
  page.on("request", (r) => {
    const u = r.url();
    if (!u.startsWith(origin + "/") && !u.startsWith("blob:") && !u.startsWith("data:")) foreign.push(u);
  });
  await page.goto(`${origin}/`, { waitUntil: "domcontentloaded" });

  const pair = () => page.$eval("#pair", (e) => e.textContent);
  const p0 = await until("pair shown", async () => { const p = await pair(); return /^\d+$/.test(p) ? p : null; }, 10000);
  check("the pair number appears", p0 !== null, `pair ${p0}`);
  const p1 = await until("pair changes", async () => { const p = await pair(); return p !== p0 ? p : null; }, 5000);
  check("the pair number changes over time", p1 !== null, `${p0} -> ${p1}`);

  const framePair = () => page.evaluate(() => window.naneyeViewer.view.framesPair);
  const f0 = await until("frames", async () => (await framePair()) ?? null, 5000);
  const f1 = await until("frames change", async () => { const f = await framePair(); return f !== f0 ? f : null; }, 5000);
  const imgOk = await page.$eval("#img-left", (e) => e.complete && e.naturalWidth === 250);
  check("both frames load and change", f0 !== null && f1 !== null && imgOk, `frames of pair ${f0} then ${f1}`);

  const drawn = await until("cloud", async () => { const n = await page.evaluate(() => window.naneyeViewer.cloud.drawn); return n > 0 ? n : null; }, 15000);
  check("the 3D view draws points", drawn !== null, `${drawn} points`);

  // The health panel against /v1/status: fps within 1 (both are estimates over the same clock, read a
  // poll apart); each counter, which only grows, between the values read just before and just after
  // the panel was read (on a loaded machine a live replay drops pairs while the test looks). The page
  // polls once a second, so after 1.5 s its panel comes from a poll later than `before`.
  const before = await status();
  await sleep(1500);
  const panelFps = await page.$eval("#h-fps", (e) => e.textContent.split("/").map(Number));
  const panelCounters = await page.$$eval("#counters td[id]", (tds) => Object.fromEntries(tds.map((td) => [td.id.slice(2), Number(td.textContent)])));
  const s = await status();
  // The panel's fps comes from a poll between `before` and `s`: within the range those two reads span
  // (an estimate moves while a loaded machine drops pairs), with 1 fps for the estimate's own jitter.
  const within = (v, a, b) => v >= Math.min(a, b) - 1 && v <= Math.max(a, b) + 1;
  check("the health panel shows the status fps",
    within(panelFps[0], before.fps.left, s.fps.left) && within(panelFps[1], before.fps.right, s.fps.right),
    `panel ${panelFps.join(" / ")}, status ${before.fps.left.toFixed(1)}..${s.fps.left.toFixed(1)} / ` +
    `${before.fps.right.toFixed(1)}..${s.fps.right.toFixed(1)}`);
  const names = Object.keys(s.counters);
  const off = names.filter((k) => !(panelCounters[k] >= before.counters[k] && panelCounters[k] <= s.counters[k]));
  check("the health panel shows every driver counter", names.length === Object.keys(panelCounters).length && off.length === 0,
    `${names.length} counters` + (off.length ? `; off: ${off.map((k) => `${k} panel ${panelCounters[k]} status ${before.counters[k]}..${s.counters[k]}`).join(", ")}` : ""));
  const source = await page.$eval("#h-source", (e) => e.textContent);
  check("the health panel shows the source", source.includes(s.source.kind) && source.includes("capture.raw"), source);
  const folded = await page.evaluate(() => { const c = document.getElementById("ov-left"); const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data; let n = 0; for (let i = 3; i < d.length; i += 4) n += d[i] > 0; return n / (d.length / 4); });
  check("pixels beyond the left camera's fold are shaded", folded > 0.05 && folded < 0.5, `${(100 * folded).toFixed(1)} % of the overlay`);

  if (screenshots) {
    mkdirSync(screenshots, { recursive: true });
    await page.screenshot({ path: join(screenshots, "viewer-board.png"), fullPage: true });
  }
  check("no console errors while streaming", errors.length === 0, errors.join(" | "));
  check("no request leaves the daemon", foreign.length === 0, foreign.join(" "));

  await stopDaemon();
  const down = await until("stopped shown", async () => (await page.$eval("#state", (e) => e.dataset.state)) === "unreachable", 6000);
  const bannerText = await page.$eval("#banner", (e) => (e.hidden ? "" : e.textContent));
  check("a stopped daemon is said on the page", down && bannerText.includes("not answering"), bannerText);

  check("naneyed restarts on the same port", await startDaemon());
  const back = await until("recovered", async () => (await page.$eval("#state", (e) => e.dataset.state)) === "streaming", 15000);
  const p2 = await pair();
  const p3 = await until("pairs again", async () => { const p = await pair(); return p !== p2 ? p : null; }, 8000);
  check("the page recovers by itself", back && p3 !== null, `state streaming, pair ${p2} -> ${p3}`);
  await stopDaemon();

  // ---- a textured scene: the dense depth panel, the depth under the pointer, scene points in 3D ----
  // The simulator renders the scene live at 10 fps (its renderer's pace, docs/simulator.md); no
  // capture is bundled for it.
  const scenePort = await freePort();
  const sceneOrigin = `http://127.0.0.1:${scenePort}`;
  const sceneConfig = join(dir, "scene.toml");
  writeFileSync(sceneConfig, `[source]\nuri = "sim://sphere?fps=10&seed=4"\n` +
    `[calibration]\npath = "${join(root, "config/calib/paper-d3.yaml")}"\n` +
    `[http]\nhost = "127.0.0.1"\nport = ${scenePort}\n[recon]\nmode = "both"\n`);
  check("naneyed serves a textured scene (sim://sphere)", await startDaemon(sceneConfig, sceneOrigin));
  const scenePage = await browser.newPage();
  await scenePage.setViewport({ width: 1280, height: 1000 });
  const sceneErrors = [], sceneForeign = [];
  scenePage.on("console", (m) => { if (m.type() === "error") sceneErrors.push(m.text()); });
  scenePage.on("pageerror", (e) => sceneErrors.push(String(e)));
  scenePage.on("request", (r) => {
    const u = r.url();
    if (!u.startsWith(sceneOrigin + "/") && !u.startsWith("blob:") && !u.startsWith("data:")) sceneForeign.push(u);
  });
  await scenePage.goto(`${sceneOrigin}/`, { waitUntil: "domcontentloaded" });
  const latestScene = () => scenePage.evaluate(() => {
    const r = window.naneyeViewer.view.latest;
    return r && r.scene ? { pair: r.pair, valid: r.scene.valid_points, depth: r.scene.depth } : null;
  });
  const sc = await until("scene result", async () => { const r = await latestScene(); return r && r.depth ? r : null; }, 30000);
  check("the page receives scene results with a dense map", sc !== null, sc ? `pair ${sc.pair}: ${sc.valid} valid points, ${(100 * sc.depth.valid_share).toFixed(1)} % dense` : "");
  const depthShown = await until("depth image", () => scenePage.$eval("#img-depth", (e) => !e.hidden && e.complete && e.naturalWidth === 250 && e.naturalHeight === 286), 15000);
  const note = await scenePage.$eval("#depth-note", (e) => e.textContent);
  check("the depth panel shows the colour-mapped map with its scale in mm", depthShown && / scale [\d.]+-[\d.]+ mm/.test(note), note);
  // The match sigmas instead: a scale of hundredths of a mm (the sphere at 12-20 mm), not depths; the
  // calibration's sigma is not offered (the paper's calibration has no covariance).
  const calibOffered = await scenePage.$eval('#depth-layer option[value="calib_sigma"]', (e) => !e.hidden);
  await scenePage.select("#depth-layer", "sigma");
  const sigmaNote = await until("sigma layer", async () => {
    const t = await scenePage.$eval("#depth-note", (e) => e.textContent);
    return /match sigma/.test(t) ? t : null;
  }, 10000);
  const sigmaHi = sigmaNote ? Number((/ scale [\d.]+-([\d.]+) mm/.exec(sigmaNote) || [])[1]) : NaN;
  check("the depth panel shows the match sigmas on their own scale", sigmaNote !== null && sigmaHi > 0 && sigmaHi < 1 && !calibOffered,
        `${sigmaNote}; calibration sigma offered: ${calibOffered}`);
  await scenePage.select("#depth-layer", "depth");
  const sceneDrawn = await until("scene cloud", async () => { const n = await scenePage.evaluate(() => window.naneyeViewer.cloud.drawn); return n >= 300 ? n : null; }, 10000);
  check("the 3D view draws the scene points", sceneDrawn !== null, `${sceneDrawn} points`);
  // A pixel the dense map has a depth at (asked outside the page first, so the page's own request
  // is a 200, not an expected 422 that would be logged as a console error).
  let target = null;
  for (const [u, v] of [[125, 125], [110, 120], [140, 130], [120, 100], [130, 150]]) {
    const j = await (await fetch(`${sceneOrigin}/v1/depth/at?u=${u}&v=${v}`)).json();
    if (j.source === "dense") { target = [u, v]; break; }
  }
  check("the dense map answers /v1/depth/at", target !== null, target ? `at (${target.join(", ")})` : "no dense depth near the centre");
  if (target) {
    const box = await (await scenePage.$("#ov-depth")).boundingBox();
    await scenePage.mouse.move(box.x + ((target[0] + 0.5) / 250) * box.width, box.y + ((target[1] + 0.5) / 250) * box.height);
    const under = await until("depth under pointer", async () => {
      const t = await scenePage.$eval("#depth-at", (e) => e.textContent);
      return /mm ± [\d.]+ mm \(dense map, pair \d+\)/.test(t) ? t : null;
    }, 5000);
    check("the depth and sigma under the pointer come from the dense map", under !== null, under || "");
  }
  if (screenshots) {
    // A few pairs in, so that the health panel has rates to show.
    await until("rates", () => scenePage.evaluate(() => (window.naneyeViewer.view.status?.fps.left ?? 0) > 0), 20000);
    await sleep(1500);
    await scenePage.screenshot({ path: join(screenshots, "viewer-scene.png"), fullPage: true });
  }
  check("no console errors on the scene", sceneErrors.length === 0, sceneErrors.join(" | "));
  check("no request leaves the daemon on the scene", sceneForeign.length === 0, sceneForeign.join(" "));
  await stopDaemon();

  // ---- with a token: the login form, a wrong token refused, the right one opens the viewer ----
  // (docs/viewer.md, "With a token"). A fresh browser context: no cookie from the pages above.
  const tokenPort = await freePort();
  const tokenOrigin = `http://127.0.0.1:${tokenPort}`;
  const token = "naneye-browser-test-" + Math.random().toString(16).slice(2).padEnd(16, "0");
  const tokenFile = join(dir, "token");
  writeFileSync(tokenFile, token + "\n", { mode: 0o600 });
  const tokenConfig = join(dir, "token.toml");
  writeFileSync(tokenConfig, `[source]\nuri = "file://${capture}?speed=realtime&loop=1"\n` +
    `[calibration]\npath = "${join(root, "config/calib/paper-d3.yaml")}"\n` +
    `[http]\nhost = "127.0.0.1"\nport = ${tokenPort}\ntoken_file = "${tokenFile}"\n`);
  check("naneyed serves with a token file", await startDaemon(tokenConfig, tokenOrigin, "/healthz"));
  const bare = await fetch(`${tokenOrigin}/v1/status`);
  check("a request without the token is refused", bare.status === 401, `status ${bare.status}`);
  const context = await browser.createBrowserContext();
  const loginPage = await context.newPage();
  const loginErrors = [];
  loginPage.on("pageerror", (e) => loginErrors.push(String(e)));
  const first = await loginPage.goto(`${tokenOrigin}/`, { waitUntil: "domcontentloaded" });
  const form = await loginPage.$("form[action='/v1/session'] input[name=token][type=password]");
  check("GET / without a session shows the token form", first.status() === 401 && form !== null, `status ${first.status()}`);
  await loginPage.type("input[name=token]", "a-wrong-token-of-sixteen-chars");
  const wrong = await Promise.all([loginPage.waitForNavigation({ waitUntil: "domcontentloaded" }), loginPage.click("button[type=submit]")]);
  const noCookie = (await loginPage.cookies(tokenOrigin)).length === 0;
  check("a wrong token gets no session", wrong[0].status() === 401 && noCookie, `status ${wrong[0].status()}`);
  await loginPage.goto(`${tokenOrigin}/`, { waitUntil: "domcontentloaded" });
  await loginPage.type("input[name=token]", token);
  await Promise.all([loginPage.waitForNavigation({ waitUntil: "domcontentloaded" }), loginPage.click("button[type=submit]")]);
  const cookies = await loginPage.cookies(tokenOrigin);
  const session = cookies.find((c) => c.name === "naneye_session");
  check("the right token sets an HttpOnly, SameSite=Strict session cookie and returns to the viewer",
    session !== undefined && session.httpOnly && session.sameSite === "Strict" && new URL(loginPage.url()).pathname === "/",
    session ? `cookie ${session.name}, httpOnly ${session.httpOnly}, sameSite ${session.sameSite}, at ${loginPage.url()}` : "no cookie");
  const scriptSees = await loginPage.evaluate(() => document.cookie);
  check("no script on the page can read the session", !scriptSees.includes("naneye_session"), JSON.stringify(scriptSees));
  const lp = () => loginPage.$eval("#pair", (e) => e.textContent).catch(() => "");
  const lp0 = await until("pair behind the token", async () => { const p = await lp(); return /^\d+$/.test(p) ? p : null; }, 10000);
  const lp1 = await until("pair changes behind the token", async () => { const p = await lp(); return p !== lp0 ? p : null; }, 5000);
  const lImg = await until("frame behind the token", () => loginPage.$eval("#img-left", (e) => e.complete && e.naturalWidth === 250), 5000);
  check("behind the token the viewer streams (events, frames)", lp0 !== null && lp1 !== null && lImg !== null, `pair ${lp0} -> ${lp1}`);
  check("no script error behind the token", loginErrors.length === 0, loginErrors.join(" | "));
  await context.close();
} catch (e) {
  check("the browser test ran to its end", false, e.stack || String(e));
} finally {
  if (browser) await browser.close();
  if (daemon && daemon.exitCode === null) daemon.kill("SIGKILL");
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
