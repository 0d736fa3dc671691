#!/usr/bin/env node
// Headless check of a `jawtrack report` page in Chromium: it loads with no console error,
// page error or failed request, every section named is present and not empty, every figure
// holds an SVG that Chromium laid out at a non-zero size, and a full-page screenshot is written.
//
//   node viewer/tests/report.mjs --file report.html --sections a,b,c --screenshot out.png \
//        [--chromium /usr/bin/chromium]
//
// Exit 0 and a one-line JSON summary on stdout on success; exit 1 with the reasons on stderr.

import { chromium } from 'playwright-core';
import { pathToFileURL } from 'node:url';
import path from 'node:path';

const USAGE =
  'usage: node viewer/tests/report.mjs --file report.html --sections a,b,c --screenshot out.png [--chromium PATH]';

function parseArgs(argv) {
  const out = { chromium: process.env.CHROMIUM || '/usr/bin/chromium' };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const next = () => {
      if (i + 1 >= argv.length) throw new Error(`${a} needs a value`);
      return argv[++i];
    };
    if (a === '--file') out.file = next();
    else if (a === '--sections') out.sections = next().split(',').filter(Boolean);
    else if (a === '--screenshot') out.screenshot = next();
    else if (a === '--chromium') out.chromium = next();
    else if (a === '--help' || a === '-h') {
      console.log(USAGE);
      process.exit(0);
    } else throw new Error(`unknown argument ${a}`);
  }
  if (!out.file || !out.sections || !out.screenshot) throw new Error('--file, --sections and --screenshot are required');
  return out;
}

let opts;
try {
  opts = parseArgs(process.argv.slice(2));
} catch (e) {
  console.error(`report check: ${e.message}\n${USAGE}`);
  process.exit(2);
}

const problems = [];
const browser = await chromium.launch({ executablePath: opts.chromium, args: ['--no-sandbox'] });
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 1400 } });
  page.on('console', (m) => {
    if (m.type() === 'error' || m.type() === 'warning') problems.push(`console ${m.type()}: ${m.text()}`);
  });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  page.on('requestfailed', (r) => problems.push(`request failed: ${r.url()}`));
  // A self-contained page asks for nothing but itself.
  page.on('request', (r) => {
    if (!r.url().startsWith('file://')) problems.push(`the page loads ${r.url()}`);
  });
  await page.goto(pathToFileURL(path.resolve(opts.file)).href, { waitUntil: 'load', timeout: 30000 });
  const found = await page.evaluate((ids) => {
    return ids.map((id) => {
      const s = document.getElementById(id);
      return { id, present: !!s, text: s ? s.innerText.trim().length : 0, tag: s ? s.tagName : null };
    });
  }, opts.sections);
  for (const s of found) {
    if (!s.present) problems.push(`section ${s.id} missing`);
    else if (s.tag !== 'SECTION' || s.text < 20) problems.push(`section ${s.id} is empty or not a section`);
  }
  const figures = await page.evaluate(() =>
    [...document.querySelectorAll('figure')].map((f) => {
      const svg = f.querySelector('svg');
      const r = svg ? svg.getBoundingClientRect() : { width: 0, height: 0 };
      return { svg: !!svg, width: r.width, height: r.height, caption: !!f.querySelector('figcaption') };
    }),
  );
  figures.forEach((f, i) => {
    if (!f.svg || !(f.width > 100 && f.height > 60) || !f.caption) problems.push(`figure ${i} has no laid-out SVG or caption`);
  });
  await page.screenshot({ path: opts.screenshot, fullPage: true });
  if (problems.length) {
    console.error(`report check: FAILED:\n  ${problems.join('\n  ')}`);
    process.exitCode = 1;
  } else {
    console.log(JSON.stringify({ ok: true, sections: found.length, figures: figures.length, screenshot: opts.screenshot }));
  }
} finally {
  await browser.close();
}
