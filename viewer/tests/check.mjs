#!/usr/bin/env node
// Headless check of the JawTrack viewer page, run in CI against a running
// `jawtrack receive --serve` (live) or `jawtrack view` (replay) server.
//
//   node viewer/tests/check.mjs --url http://127.0.0.1:PORT/ --mode live|replay \
//        --screenshot out.png [--chromium /usr/bin/chromium] [--timeout 30] \
//        [--expect-hinge-axis] [--expect-coloured]
//
// Besides the poses: both markers show their 24 tag ids, the grid is there, a replay draws
// both condyles' paths, the view buttons turn the camera to their head-frame directions, and
// a hinge axis or contact colours are there exactly when expected.
//
// Exit 0 and a one-line JSON summary on stdout on success; exit 1 with the
// reasons on stderr on any failed check, console error, page error or
// failed request.

import { chromium } from 'playwright-core';

const USAGE =
  'usage: node viewer/tests/check.mjs --url http://127.0.0.1:PORT/ --mode live|replay ' +
  '--screenshot out.png [--chromium /usr/bin/chromium] [--timeout 30]';

const MIN_DISTINCT_COLOURS = 50;
const MIN_FOREGROUND_FRACTION = 0.0025;

function parseArgs(argv) {
  const out = { chromium: process.env.CHROMIUM || '/usr/bin/chromium', timeout: 30 };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const next = () => {
      if (i + 1 >= argv.length) throw new Error(`${a} needs a value`);
      return argv[++i];
    };
    if (a === '--url') out.url = next();
    else if (a === '--mode') out.mode = next();
    else if (a === '--screenshot') out.screenshot = next();
    else if (a === '--chromium') out.chromium = next();
    else if (a === '--timeout') out.timeout = Number(next());
    else if (a === '--expect-hinge-axis') out.expectHingeAxis = true;
    else if (a === '--expect-coloured') out.expectColoured = true;
    else if (a === '--help' || a === '-h') {
      console.log(USAGE);
      process.exit(0);
    } else throw new Error(`unknown argument ${a}`);
  }
  if (!out.url) throw new Error('--url is required');
  if (out.mode !== 'live' && out.mode !== 'replay') throw new Error('--mode must be live or replay');
  if (!out.screenshot) throw new Error('--screenshot is required');
  if (!(out.timeout > 0)) throw new Error('--timeout must be a positive number of seconds');
  return out;
}

let opts;
try {
  opts = parseArgs(process.argv.slice(2));
} catch (e) {
  console.error(`check: ${e.message}\n${USAGE}`);
  process.exit(2);
}

const timeoutMs = opts.timeout * 1000;
// Last resort against a hung browser: never outlive ~4 timeouts.
setTimeout(() => {
  console.error(`check: FAILED: gave up after ${(4 * timeoutMs + 15000) / 1000} s (global watchdog)`);
  process.exit(1);
}, 4 * timeoutMs + 15000).unref();

const consoleErrors = [];
const consoleWarnings = [];
const pageErrors = [];
const failedRequests = [];
let listening = true;

class CheckFailure extends Error {}
const fail = (msg) => {
  throw new CheckFailure(msg);
};

const maxAbsDiff = (a, b) => {
  if (!Array.isArray(a) || !Array.isArray(b) || a.length !== 16 || b.length !== 16) return NaN;
  return Math.max(...a.map((v, i) => Math.abs(v - b[i])));
};

async function visibleMessage(page) {
  try {
    return await page.evaluate(() => {
      const el = document.getElementById('message');
      return el && !el.hidden ? el.textContent : '';
    });
  } catch {
    return '';
  }
}

async function waitFor(page, what, fn, arg) {
  try {
    await page.waitForFunction(fn, arg, { timeout: timeoutMs, polling: 50 });
  } catch (e) {
    if (e instanceof Error && e.name === 'TimeoutError') {
      const shown = await visibleMessage(page);
      fail(`timed out after ${opts.timeout} s waiting for ${what}${shown ? `; the page shows: ${shown}` : ''}`);
    }
    throw e;
  }
}

// Statistics of the WebGL canvas, read in the page (needs preserveDrawingBuffer).
function canvasStats() {
  const src = document.querySelector('canvas#view') || document.querySelector('canvas');
  if (!src) return { error: 'no canvas on the page' };
  const w = src.width;
  const h = src.height;
  if (w === 0 || h === 0) return { error: `canvas is ${w}x${h}` };
  const c = document.createElement('canvas');
  c.width = w;
  c.height = h;
  const ctx = c.getContext('2d', { willReadFrequently: true });
  ctx.drawImage(src, 0, 0);
  const d = ctx.getImageData(0, 0, w, h).data;
  // Background: the most common colour of the four corners' pixels.
  const corner = (x, y) => {
    const o = 4 * (y * w + x);
    return [d[o], d[o + 1], d[o + 2]];
  };
  const corners = [corner(0, 0), corner(w - 1, 0), corner(0, h - 1), corner(w - 1, h - 1)];
  const key = (p) => p.join(',');
  const votes = new Map();
  for (const p of corners) votes.set(key(p), (votes.get(key(p)) || 0) + 1);
  const bgKey = [...votes.entries()].sort((a, b) => b[1] - a[1])[0][0];
  const bg = bgKey.split(',').map(Number);
  const colours = new Set();
  let foreground = 0;
  for (let o = 0; o < d.length; o += 4) {
    const r = d[o];
    const g = d[o + 1];
    const b = d[o + 2];
    colours.add((r << 16) | (g << 8) | b);
    if (Math.max(Math.abs(r - bg[0]), Math.abs(g - bg[1]), Math.abs(b - bg[2])) > 12) foreground++;
  }
  return { width: w, height: h, distinct: colours.size, foreground: foreground / (w * h), background: bg };
}

const launchArgs = [
  '--headless',
  '--no-sandbox',
  '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  '--no-first-run',
];

let browser = null;
let exitCode = 0;
let summary = null;
try {
  try {
    browser = await chromium.launch({
      executablePath: opts.chromium,
      headless: true,
      args: launchArgs,
      timeout: timeoutMs,
    });
  } catch (e) {
    fail(`could not launch chromium at ${opts.chromium}: ${e.message.split('\n')[0]}`);
  }
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, deviceScaleFactor: 1 });
  const page = await context.newPage();
  page.on('console', (m) => {
    if (!listening) return;
    const loc = m.location();
    const where = loc && loc.url ? ` (${loc.url}:${loc.lineNumber})` : '';
    if (m.type() === 'error') consoleErrors.push(`${m.text()}${where}`);
    else if (m.type() === 'warning') consoleWarnings.push(`${m.text()}${where}`);
  });
  page.on('pageerror', (e) => {
    if (listening) pageErrors.push(e.stack || e.message);
  });
  page.on('requestfailed', (r) => {
    if (listening) failedRequests.push(`${r.method()} ${r.url()}: ${r.failure()?.errorText ?? 'failed'}`);
  });
  page.on('response', (r) => {
    if (listening && r.status() >= 400) failedRequests.push(`${r.request().method()} ${r.url()}: HTTP ${r.status()}`);
  });

  let checkError = null;
  let posesApplied = 0;
  let stats = null;
  try {
    try {
      await page.goto(opts.url, { waitUntil: 'load', timeout: timeoutMs });
    } catch (e) {
      fail(`could not open ${opts.url}: ${e.message.split('\n')[0]}`);
    }
    await waitFor(page, 'window.jawtrack.ready', () => window.jawtrack && window.jawtrack.ready === true);

    const pageMode = await page.evaluate(() => window.jawtrack.mode);
    if (pageMode !== opts.mode) fail(`page is in mode ${JSON.stringify(pageMode)}, expected ${opts.mode}`);

    if (opts.mode === 'live') {
      const m0 = await page.evaluate(() => window.jawtrack.mandibleMatrix());
      await waitFor(
        page,
        'at least 5 poses and a moving mandible',
        (m0) => {
          const j = window.jawtrack;
          if (j.posesApplied < 5) return false;
          const m = j.mandibleMatrix();
          return m.some((v, i) => Math.abs(v - m0[i]) > 1e-6);
        },
        m0,
      );
    } else {
      const n = await page.evaluate(() => window.jawtrack.frameCount);
      if (!(n >= 2)) fail(`the recording has ${n} frame(s); need at least 2 to check seeking`);
      const a = await page.evaluate(() => {
        window.jawtrack.seek(0);
        return window.jawtrack.mandibleMatrix();
      });
      // The jaw may come back to where it started (a cyclic motion), so try several frames.
      const targets = [...new Set([n - 1, Math.floor(n / 2), Math.floor(n / 3), Math.floor(n / 4), 1])];
      const diffs = await page.evaluate(
        ({ targets, a }) =>
          targets.map((k) => {
            window.jawtrack.seek(k);
            const m = window.jawtrack.mandibleMatrix();
            return Math.max(...m.map((v, i) => Math.abs(v - a[i])));
          }),
        { targets, a },
      );
      const diff = Math.max(...diffs);
      if (!(diff > 1e-6)) fail(`seeking to frames ${targets.join(', ')} never moves the mandible from frame 0 (max diff ${diff})`);
      // The timeline numbers frames as the recording and the CLI do, from 0.
      const labels = await page.evaluate(async (targets) => {
        const frames = (await (await fetch('/api/recording')).json()).frames;
        return [0, ...targets].map((k) => {
          window.jawtrack.seek(k);
          const want = Number.isFinite(frames[k].frame) ? frames[k].frame : k;
          return { want, shown: document.getElementById('time').textContent };
        });
      }, targets);
      for (const { want, shown } of labels) {
        if (!shown.includes(`frame ${want} `)) fail(`the timeline should name frame ${want}: it shows "${shown}"`);
      }
    }
    // Each scan the server placed by a registration is drawn where it says.
    const placement = await page.evaluate(async () => {
      const spec = await (await fetch('/api/scene')).json();
      return ['maxilla', 'mandible'].map((name) => ({
        name,
        want: spec[name] && spec[name].marker_from_mesh,
        got: window.jawtrack.meshMatrix(name),
      }));
    });
    for (const { name, want, got } of placement) {
      if (!Array.isArray(want)) continue;
      if (!Array.isArray(got)) fail(`the ${name} scan is not in the scene`);
      const off = Math.max(...want.map((v, i) => Math.abs(v - got[i])));
      if (!(off < 1e-9)) fail(`the ${name} scan is not drawn where its registration places it (off by ${off})`);
    }
    // The markers with their tags, the grid, and (replayed) both condyles' paths.
    const tagLabels = await page.evaluate(() => window.jawtrack.tagLabels());
    if (tagLabels !== 24) fail(`the markers show ${tagLabels} tag ids, not 24 (12 per marker)`);
    if (!(await page.evaluate(() => window.jawtrack.hasGrid()))) fail('no grid in the scene');
    if (opts.mode === 'replay') {
      const points = await page.evaluate(() => {
        window.jawtrack.seek(window.jawtrack.frameCount - 1);
        return window.jawtrack.condylePoints();
      });
      if (!(points.length === 2 && points.every((n) => n >= 2))) fail(`the condyle paths have ${points} points`);
    }
    const axis = await page.evaluate(() => window.jawtrack.hasHingeAxis());
    if (axis !== !!opts.expectHingeAxis) fail(`hinge axis drawn: ${axis}, expected ${!!opts.expectHingeAxis}`);
    if (opts.expectColoured) {
      for (const name of ['maxilla', 'mandible']) {
        if (!(await page.evaluate((n) => window.jawtrack.coloured(n), name))) fail(`the ${name} is not drawn in its contact colours`);
      }
    }
    // Each view button turns the camera to its direction in the head frame.
    const want = await page.evaluate(() => window.jawtrack.viewDirections());
    for (const name of ['front', 'side', 'occlusal']) {
      await page.click(`#view-${name}`);
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => r()))));
      const got = await page.evaluate(() => window.jawtrack.cameraDirection());
      const dot = got.reduce((acc, v, i) => acc + v * want[name][i], 0);
      if (!(dot > 0.99)) fail(`the ${name} view looks from ${got.map((v) => v.toFixed(2))}, not ${want[name].map((v) => v.toFixed(2))}`);
    }
    await page.click('#fit-view');
    // With scans: the four points of `jawtrack points` picked where scan triangles show, each
    // read back in the upper scan's frame (the registration's placement maps it to the hit).
    const scanSpec = await page.evaluate(async () => (await (await fetch('/api/scene')).json()).maxilla);
    if (scanSpec && scanSpec.format !== 'mesh' && Array.isArray(scanSpec.marker_from_mesh)) {
      const picks = await page.evaluate(() => {
        window.jawtrack.startPicking();
        return [0, 40, 80, 120].map((k, i) => window.jawtrack.pickTriangle(i < 3 ? 'maxilla' : 'mandible', k));
      });
      const m = scanSpec.marker_from_mesh;
      picks.forEach((p, i) => {
        if (!p) fail(`pick ${i + 1} hit no scan`);
        const w = [0, 1, 2].map((r) => m[4 * r] * p.scan[0] + m[4 * r + 1] * p.scan[1] + m[4 * r + 2] * p.scan[2] + m[4 * r + 3]);
        const off = Math.max(...w.map((v, k) => Math.abs(v - p.world[k])));
        if (!(off < 1e-3)) fail(`pick ${i + 1} is not in the upper scan's frame (off by ${off} mm): ${JSON.stringify(p)}`);
      });
      const command = await page.evaluate(() => window.jawtrack.pickCommand());
      const numbers = (command || '').match(/-?\d+(\.\d+)?/g) || [];
      if (!command || !command.startsWith('jawtrack points --occlusal ') || numbers.length !== 12) {
        fail(`the picked points give no command: ${command}`);
      }
    }
    posesApplied = await page.evaluate(() => window.jawtrack.posesApplied);

    // Let at least two frames render after the last pose/seek.
    await page.evaluate(
      () => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => r()))),
    );
    stats = await page.evaluate(canvasStats);
    if (stats.error) fail(`cannot read the WebGL canvas: ${stats.error}`);
    if (stats.distinct < MIN_DISTINCT_COLOURS) {
      fail(`the 3D view looks blank: ${stats.distinct} distinct colours (< ${MIN_DISTINCT_COLOURS})`);
    }
    if (stats.foreground < MIN_FOREGROUND_FRACTION) {
      fail(
        `the 3D view looks empty: ${(100 * stats.foreground).toFixed(2)} % of pixels differ from the background ` +
          `(< ${100 * MIN_FOREGROUND_FRACTION} %)`,
      );
    }
  } catch (e) {
    checkError = e;
  }

  // Screenshot in every case: it is the first thing to look at when CI fails.
  try {
    await page.screenshot({ path: opts.screenshot, timeout: timeoutMs });
  } catch (e) {
    if (!checkError) checkError = new CheckFailure(`could not take the screenshot: ${e.message.split('\n')[0]}`);
  }
  listening = false;
  if (checkError) throw checkError;

  summary = {
    mode: opts.mode,
    poses_applied: posesApplied,
    distinct_colours: stats.distinct,
    foreground_percent: Number((100 * stats.foreground).toFixed(2)),
    canvas: `${stats.width}x${stats.height}`,
    console_errors: consoleErrors.length,
    console_warnings: consoleWarnings.length,
    screenshot: opts.screenshot,
  };
} catch (e) {
  exitCode = 1;
  console.error(`check: FAILED: ${e instanceof CheckFailure ? e.message : e.stack || e}`);
} finally {
  listening = false;
  if (browser) await browser.close().catch(() => {});
}

const problems = [
  ...consoleErrors.map((m) => `console error: ${m}`),
  ...pageErrors.map((m) => `page error: ${m}`),
  ...failedRequests.map((m) => `failed request: ${m}`),
];
if (problems.length > 0) {
  exitCode = 1;
  for (const p of problems) console.error(`check: FAILED: ${p}`);
}
for (const w of consoleWarnings) console.error(`check: note: console warning: ${w}`);

if (exitCode === 0) console.log(JSON.stringify(summary));
process.exit(exitCode);
