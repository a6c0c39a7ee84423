// The browser test of `umbra explore` (run by .ci/run):
//
//   node tests/browser/explore.test.mjs [UMBRA_BINARY]
//
// Starts the server on a free loopback port, drives Debian's headless Chromium through the page
// with playwright-core, and checks that the page loads with no console error, that the active
// edge table and runs it shows for a line are what `umbra trace --json` prints, that switching
// the stage changes the panels, that moving the light re-renders, that bad requests get a JSON
// error the page shows, that many requests at once are all answered, and that the exported
// static page works from files. With SCREENSHOTS=DIR it saves the screenshots of docs/explore.md.

import { chromium } from "playwright-core";
import { spawn, execFileSync } from "node:child_process";
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join, resolve } from "node:path";
import assert from "node:assert/strict";

const umbra = resolve(process.argv[2] || "target/debug/umbra");
const scene = resolve("scenes/cornell.toml");
const shots = process.env.SCREENSHOTS;
const LINE = 261;

function startServer(file = scene) {
  const server = spawn(umbra, ["explore", file, "--port", "0"], { stdio: ["ignore", "ignore", "pipe"] });
  return new Promise((resolvePromise, reject) => {
    let err = "";
    const timer = setTimeout(() => reject(new Error(`no address from umbra explore: ${err}`)), 30000);
    server.stderr.on("data", (chunk) => {
      err += chunk;
      const m = err.match(/http:\/\/127\.0\.0\.1:\d+\//);
      if (m) { clearTimeout(timer); resolvePromise([server, m[0]]); }
    });
    server.on("exit", (code) => reject(new Error(`umbra explore exited (${code}): ${err}`)));
  });
}

function trace(line, stage) {
  const out = execFileSync(umbra, ["trace", scene, "--line", `${line}`, "--shadows", stage, "--json"]);
  return JSON.parse(out.toString());
}

async function ready(page, line) {
  if (line !== undefined) await page.waitForSelector(`#aet[data-line="${line}"]`, { timeout: 60000 });
  await page.waitForSelector("body[data-state=ready]", { timeout: 60000 });
}

async function tableRows(page, id) {
  return page.$$eval(`#${id} tr`, (rows) => rows.slice(1).map((r) => [...r.cells].map((c) => c.textContent)));
}

async function newPage(browser, errors) {
  const page = await browser.newPage({ viewport: { width: 1500, height: 1100 } });
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", (e) => errors.push(String(e)));
  return page;
}

async function checkLive(browser, url) {
  const errors = [];
  const page = await newPage(browser, errors);
  await page.goto(url);
  await ready(page);
  assert.deepEqual(errors, [], "console errors on load");

  // The scene's own size, so that `umbra trace` (which renders at that size) is comparable.
  await page.selectOption("#size", "640x480");
  await ready(page);
  await page.fill("#line", `${LINE}`);
  await page.press("#line", "Enter");
  await ready(page, LINE);
  const want = trace(LINE, "bouknight-kelley");
  const aet = await tableRows(page, "aet");
  assert.deepEqual(aet.map((r) => [r[0], r[1]]), want.active.map(([x, p]) => [x.toFixed(3), `${p}`]), "active edge table");
  const runs = await page.$$eval("#runs li", (li) => li.map((l) => l.textContent));
  assert.deepEqual(runs, want.runs.map((r) => `${r.x0}..${r.x1}: polygon ${r.poly}`), "runs");
  const decisions = await tableRows(page, "decisions");
  assert.deepEqual(decisions.map((r) => r[4]), want.decisions.map((d) => d.decision.note), "stage decisions");

  // The arrow keys and a click move the scanline.
  await page.$eval("#line", (i) => i.blur());
  await page.keyboard.press("ArrowDown");
  await ready(page, LINE + 1);
  const box = await page.locator("#overlay").boundingBox();
  const scale = box.width / 640;
  await page.mouse.click(box.x + 210.5 * scale, box.y + 440.5 * scale);
  await ready(page, 440);
  assert.match(await page.textContent("#pixel"), /^Pixel \(210, 440\)/);
  const atClick = trace(440, "bouknight-kelley");
  assert.equal((await tableRows(page, "aet")).length, atClick.active.length, "active edges after a click");
  assert.match(await page.textContent("#stage-extra"), /the sphere prefilter kept \d+ caster\(s\)/);
  if (shots) await page.screenshot({ path: join(shots, "explore-bouknight-kelley.png"), fullPage: true });

  // Switching the stage changes the panels.
  const before = await page.textContent("#stage-panel");
  await page.selectOption("#stage", "crow");
  await page.waitForSelector('#stage-panel[data-stage="crow"]', { timeout: 60000 });
  await ready(page);
  const after = await page.textContent("#stage-panel");
  assert.notEqual(after, before, "the stage panel changed");
  assert.match(await page.textContent("#stage-title"), /crow/);
  const crow = trace(440, "crow");
  assert.deepEqual((await tableRows(page, "decisions")).map((r) => r[4]), crow.decisions.map((d) => d.decision.note));
  await page.locator("#overlay").click({ position: { x: 305.5 * scale, y: 300.5 * scale } });
  await ready(page, 300);
  await page.locator("#overlay").click({ position: { x: 305.5 * scale, y: 440.5 * scale } });
  await page.waitForFunction(() => /^Pixel \(305, 440\)/.test(document.getElementById("pixel").textContent));
  if (shots) await page.screenshot({ path: join(shots, "explore-crow.png"), fullPage: true });
  // The "as published" box runs the paper path (Crow 1977) and says so in the title.
  await page.check("#paper");
  await page.waitForFunction(() => /crow \(paper\)/.test(document.getElementById("stage-title").textContent), null, { timeout: 60000 });
  assert.match(await page.getAttribute("#frame", "src"), /paper=1/);
  await page.uncheck("#paper");
  await page.waitForFunction(() => !/paper/.test(document.getElementById("stage-title").textContent), null, { timeout: 60000 });
  await page.selectOption("#stage", "williams");
  assert.ok(await page.isDisabled("#paper"), "williams has no paper path");
  await page.waitForSelector('#stage-panel[data-stage="williams"]', { timeout: 60000 });
  await ready(page);
  assert.match(await page.textContent("#stage-extra"), /A 2048² map, one texel compared per pixel/);
  await page.waitForFunction(() => { const i = document.getElementById("stage-map"); return i.complete && i.naturalWidth > 0; }, null, { timeout: 60000 });
  assert.match(await page.textContent("#stage-map-caption"), /depth map/);
  if (shots) await page.screenshot({ path: join(shots, "explore-williams.png"), fullPage: true });

  // Moving the light renders again.
  const src = await page.getAttribute("#frame", "src");
  const summary = await page.textContent("#frame-summary");
  await page.$eval("#light-x", (i) => { i.value = Number(i.min) + 0.1 * (Number(i.max) - Number(i.min)); i.dispatchEvent(new Event("change")); });
  await page.waitForFunction((old) => document.getElementById("frame").getAttribute("src") !== old, src, { timeout: 60000 });
  await ready(page);
  assert.match(await page.getAttribute("#frame", "src"), /light=/);
  assert.ok(await page.$eval("#frame", (i) => i.complete && i.naturalWidth > 0), "the new frame loaded");
  assert.notEqual(await page.textContent("#frame-summary"), summary, "the frame's figures changed");

  // A bad request: a JSON error, shown on the page.
  const bad = await page.evaluate(async () => {
    const answers = [];
    for (const q of ["trace?line=99999", "trace?line=3&shadows=bogus", "frame?width=0", "frame?width=100000", "frame?light=1,nan,2", "frame?colour=red"]) {
      const r = await fetch(`api/${q}`);
      answers.push([r.status, (await r.json()).error]);
    }
    return answers;
  });
  for (const [status, error] of bad) {
    assert.equal(status, 400);
    assert.ok(typeof error === "string" && error.length > 10, `a clear error: ${error}`);
  }
  await page.$eval("#stage", (s) => { s.appendChild(new Option("bogus", "bogus")); s.value = "bogus"; s.dispatchEvent(new Event("change")); });
  await page.waitForSelector("#error:not([hidden])", { timeout: 60000 });
  assert.match(await page.textContent("#error"), /unknown shadow method 'bogus'/);

  // Many requests at once, every one answered.
  const statuses = await page.evaluate(async () => {
    const asks = [];
    for (let i = 0; i < 24; i++) {
      const stage = ["bouknight-kelley", "crow", "ray-cast", "williams"][i % 4];
      for (const u of [`api/trace?line=${10 * i}&shadows=${stage}&width=320&height=240`, `api/frame?shadows=${stage}&width=${100 + i}&height=80`]) {
        asks.push(fetch(u, { signal: AbortSignal.timeout(30000) }).then((r) => r.status, (e) => `${u}: ${e.name}`));
      }
    }
    return Promise.all(asks);
  });
  assert.deepEqual(statuses, statuses.map(() => 200), "every concurrent request answered");
  assert.deepEqual(errors.filter((e) => !/status of 400/.test(e)), [], "console errors other than the bad requests");
  await page.close();
}

async function checkExported(browser) {
  const dir = mkdtempSync(join(tmpdir(), "umbra-explore-"));
  try {
    execFileSync(umbra, ["explore", scene, "--export", dir, "--size", "160x120", "--force"], { stdio: "pipe" });
    const errors = [];
    const page = await newPage(browser, errors);
    await page.goto(`file://${dir}/index.html`);
    await ready(page);
    await page.fill("#line", "70");
    await page.press("#line", "Enter");
    await ready(page, 70);
    assert.ok((await tableRows(page, "aet")).length > 0, "the exported page shows the active edges");
    await page.selectOption("#stage", "atherton-weiler-greenberg");
    await page.waitForSelector('#stage-panel[data-stage="atherton-weiler-greenberg"]', { timeout: 60000 });
    await ready(page);
    assert.ok((await tableRows(page, "decisions")).length > 0, "the exported page shows the stage's decisions");
    if (shots) await page.screenshot({ path: join(shots, "explore-exported-awg.png"), fullPage: true });
    assert.deepEqual(errors, [], "console errors in the exported page");
    await page.close();
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

// The scene with an area light: a picked pixel in its penumbra shows what its point sees of
// the light (the visible part, the occluders' shadows), with a fraction strictly between 0
// and 1 that is the reference's.
async function checkLightView(browser) {
  const [lights, at] = await startServer(resolve("scenes/lights.toml"));
  try {
    const errors = [];
    const page = await newPage(browser, errors);
    await page.goto(at);
    await ready(page);
    await page.check("#show-penumbra");
    const frame = await page.evaluate(() => fetch(`api/frame?shadows=bouknight-kelley&width=${state.width}&height=${state.height}`).then((r) => r.json()));
    const pixels = frame.penumbra.pixels;
    assert.ok(pixels.length > 0, "the lights scene has a penumbra");
    const [x, y] = pixels[Math.floor(pixels.length / 2)];
    const scale = await page.evaluate(() => state.scale);
    await page.locator("#overlay").click({ position: { x: (x + 0.5) * scale, y: (y + 0.5) * scale } });
    await ready(page, y);
    await page.waitForSelector("#light-view:not([hidden])", { timeout: 60000 });
    const caption = await page.textContent("#light-caption");
    const fraction = Number(caption.match(/Exact fraction ([0-9.]+)/)[1]);
    assert.ok(fraction > 0 && fraction < 1, `a penumbra pixel's fraction: ${caption}`);
    const want = await page.evaluate(([x, y]) => fetch(`api/light?shadows=bouknight-kelley&width=${state.width}&height=${state.height}&x=${x}&line=${y}`).then((r) => r.json()), [x, y]);
    assert.equal(fraction.toFixed(4), want.fraction.toFixed(4), "the caption's fraction is the reference's");
    assert.ok(want.hidden.length > 0 && want.visible.length > 0, "occluders and a visible part");
    if (shots) await page.screenshot({ path: join(shots, "explore-light-view.png"), fullPage: false });
    assert.deepEqual(errors, [], "console errors on the lights scene");
    await page.close();
  } finally {
    lights.kill();
  }
}

// A hung request fails the test instead of hanging CI.
setTimeout(() => { console.error("explore browser test: timed out"); process.exit(1); }, 300000).unref();
const [server, url] = await startServer();
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync"],
});
try {
  await checkLive(browser, url);
  await checkLightView(browser);
  await checkExported(browser);
  console.log("explore browser test: ok");
} finally {
  await browser.close();
  server.kill();
}
