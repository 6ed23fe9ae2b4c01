// Checks a report page with the GlassFusion viewer in headless Chromium (software WebGL).
// Usage: node viewer_test.mjs REPORT.html [--min-fill-pixels N] [--max-load-ms MS] [--plyloader]
// (--plyloader: parse the maps with three's PLYLoader instead of the direct reader, to compare)
// Checks: (a) every pane draws something; (b) in "source" colour mode the stereo fill colour
// #1b7837 shows in the "with fill" pane and not in the "without fill" pane; (c) unchecking
// the sensor source changes the picture; (d) load time (dataset.pageMs: from opening the page,
// its data script read, to both maps drawn) with --max-load-ms;
// (e) clicking a keyframe shows its fill overlay; (f) dragging one pane moves the other's view.
// Prints one line per check and "N passed, N failed"; exits 0 only if all pass. Saves
// screenshots next to the report as viewer_test_{before,source,after,overlay}.png.
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';
import { countPixels, diffPixels, installPixelReader, rememberPixels } from './pixels.mjs';

const CHROMIUM = '/usr/bin/chromium';
const STEREO_FILL = [0x1b, 0x78, 0x37]; // #1b7837, the stereo fill colour in "source" mode

function parseArgs(argv) {
  const opts = { report: null, minFillPixels: 50, maxLoadMs: null, plyLoader: false };
  for (let i = 0; i < argv.length; i++) {
    if (argv[i] === '--min-fill-pixels') opts.minFillPixels = Number(argv[++i]);
    else if (argv[i] === '--max-load-ms') opts.maxLoadMs = Number(argv[++i]);
    else if (argv[i] === '--plyloader') opts.plyLoader = true;
    else if (!opts.report) opts.report = path.resolve(argv[i]);
    else throw new Error(`unexpected argument ${argv[i]}`);
  }
  if (!opts.report) {
    console.error('usage: node viewer_test.mjs REPORT.html [--min-fill-pixels N] [--max-load-ms MS] [--plyloader]');
    process.exit(2);
  }
  return opts;
}

// Collects check results and prints each as it is made.
function makeChecks() {
  const results = [];
  return {
    check(name, ok, detail) {
      results.push(ok);
      console.log(`${ok ? 'PASS' : 'FAIL'} ${name}: ${detail}`);
    },
    summary() {
      const passed = results.filter(Boolean).length;
      console.log(`${passed} passed, ${results.length - passed} failed`);
      return passed === results.length;
    },
  };
}

// Waits until the viewer has redrawn after a control change (two animation frames).
const settle = (page) => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

async function openReport(browser, report, plyLoader) {
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  page.on('pageerror', (err) => console.log(`page error: ${err.message}`));
  page.on('console', (msg) => { if (msg.type() === 'error') console.log(`console error: ${msg.text()}`); });
  await page.goto(pathToFileURL(report).href + (plyLoader ? '#gf-parser=plyloader' : ''));
  await page.waitForFunction(() => ['ready', 'error'].includes(document.documentElement.dataset.view),
    null, { timeout: 60000, polling: 100 });
  return page;
}

// The panes: [{ index, name, surfels }] from the pane boxes' data attributes.
const listPanes = (page) => page.$$eval('[data-pane]', (boxes) => boxes.map((b) => ({
  index: Number(b.dataset.pane), name: b.dataset.mapName || '', maxPointPx: b.dataset.maxPointPx,
  surfels: Number(b.dataset.surfels), message: b.querySelector('.gf-msg')?.textContent || '' })));

async function runChecks(page, opts, checks, shot) {
  const state = await page.evaluate(() => ({ ...document.documentElement.dataset }));
  checks.check('ready', state.view === 'ready', `data-view=${state.view}`);
  if (state.view !== 'ready') return;
  await installPixelReader(page);
  const panes = await listPanes(page);
  console.log(`pageMs: ${state.pageMs}, viewMs: ${state.viewMs} (${state.viewSteps || ''}; max point size ${panes.map((p) => p.maxPointPx).join(', ')} px)`);
  await shot('before');
  await checkNotBlank(page, panes, checks);
  const withFill = panes.find((p) => /with fill/i.test(p.name) && !/without/i.test(p.name));
  await checkStereoFill(page, panes, withFill, opts, checks);
  await shot('source');
  await checkSourceToggle(page, withFill || panes[0], checks);
  await shot('after');
  await checkKeyframeClick(page, checks);
  await shot('overlay');
  await checkSharedCamera(page, panes, checks);
  if (opts.maxLoadMs != null) {
    checks.check('(d) load time', Number(state.pageMs) <= opts.maxLoadMs,
      `pageMs ${state.pageMs} from opening the page to both maps drawn (max ${opts.maxLoadMs})`);
  }
}

// (a) every pane drew something besides the background (a pane whose map has no surfels
// must say so instead).
async function checkNotBlank(page, panes, checks) {
  for (const p of panes) {
    if (p.surfels === 0) {
      checks.check(`(a) pane ${p.index} "${p.name}" has no surfels and says so`, /no surfels/.test(p.message), `message "${p.message}"`);
      continue;
    }
    const { differing, total } = await countPixels(page, p.index, null);
    const share = differing / total;
    checks.check(`(a) pane ${p.index} "${p.name}" not blank`, share > 0.01,
      `${differing} of ${total} pixels (${(100 * share).toFixed(1)}%) differ from the background`);
  }
}

// (b) in "source" colour mode, the stereo fill colour is in the with-fill pane and (almost)
// absent from the without-fill pane.
async function checkStereoFill(page, panes, withFill, opts, checks) {
  await page.selectOption('#gf-color-mode', 'source');
  await settle(page);
  const name = '(b) stereo fill #1b7837 in the with-fill pane';
  if (!withFill) {
    checks.check(name, false, 'no pane whose map name contains "with fill"');
    return;
  }
  const fillCount = (await countPixels(page, withFill.index, STEREO_FILL)).matching;
  checks.check(name, fillCount >= opts.minFillPixels, `${fillCount} pixels (need >= ${opts.minFillPixels})`);
  const withoutFill = panes.find((p) => /without fill/i.test(p.name));
  if (!withoutFill) {
    console.log('(b) no "without fill" pane: its check does not apply');
    return;
  }
  const n = (await countPixels(page, withoutFill.index, STEREO_FILL)).matching;
  checks.check('(b) no stereo fill in the without-fill pane', n < 0.05 * fillCount,
    `${n} pixels (need < 5% of ${fillCount})`);
}

// (c) hiding the sensor surfels changes the with-fill pane's picture.
async function checkSourceToggle(page, pane, checks) {
  await rememberPixels(page, pane.index);
  await page.uncheck('#gf-source-1');
  await settle(page);
  const { differing, total } = await diffPixels(page, pane.index);
  checks.check(`(c) unchecking gf-source-1 changes pane ${pane.index}`, differing > 0.01 * total,
    `${differing} of ${total} pixels changed (${(100 * differing / total).toFixed(1)}%)`);
}

// (e) clicking the first keyframe that has an overlay shows that overlay image, loaded.
async function checkKeyframeClick(page, checks) {
  const keyframes = await page.evaluate(() => (window.GF_VIEW && window.GF_VIEW.keyframes) || []);
  const index = keyframes.findIndex((k) => k.overlay);
  if (index < 0) {
    console.log('(e) no keyframe with an overlay: the click check does not apply');
    return;
  }
  const point = await page.evaluate((i) => document.getElementById('gf-view').gfView.keyframeClientPoint(i, 0), index);
  await page.mouse.click(point.x, point.y);
  const img = await page.waitForFunction(() => {
    const im = document.querySelector('.gf-overlay img');
    return im && im.complete && im.naturalWidth > 0 ? im.getAttribute('src') : null;
  }, null, { timeout: 5000 }).then((h) => h.jsonValue()).catch(() => null);
  checks.check(`(e) clicking keyframe ${keyframes[index].label} shows its overlay`, img === keyframes[index].overlay,
    img ? `shows ${img}` : 'no overlay image loaded');
}

// (f) dragging in the last pane turns the shared camera: the first pane's picture changes.
async function checkSharedCamera(page, panes, checks) {
  const last = panes[panes.length - 1];
  const box = await page.locator(`[data-pane="${last.index}"]`).boundingBox();
  await rememberPixels(page, panes[0].index);
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 30, { steps: 8 });
  await page.mouse.up();
  await settle(page);
  const { differing, total } = await diffPixels(page, panes[0].index);
  checks.check(`(f) dragging pane ${last.index} moves the view of pane ${panes[0].index}`, differing > 0.01 * total,
    `${differing} of ${total} pixels changed`);
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  if (!fs.existsSync(CHROMIUM)) {
    console.log(`SKIPPED: ${CHROMIUM} is missing`);
    return;
  }
  if (!fs.existsSync(opts.report)) throw new Error(`no such report: ${opts.report}`);
  const checks = makeChecks();
  const browser = await chromium.launch({ executablePath: CHROMIUM, headless: true,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'] });
  try {
    const page = await openReport(browser, opts.report, opts.plyLoader);
    const shot = (tag) => page.screenshot({ path: path.join(path.dirname(opts.report), `viewer_test_${tag}.png`), fullPage: true });
    await runChecks(page, opts, checks, shot);
  } catch (err) {
    checks.check('run', false, err.message.split('\n')[0]);
  } finally {
    await browser.close();
  }
  process.exitCode = checks.summary() ? 0 : 1;
}

main().catch((err) => { console.error(err); process.exitCode = 1; });
