// qs-studio in a real browser: headless Chromium (software WebGL) driven by puppeteer-core, as
// scripts/glb-view does. Registered with CTest (tests/CMakeLists.txt: studio_browser).
//  1. Landmarks: uploads examples/spot_2k.obj (and a file that is not a mesh, refused) into an
//     empty folder through the page, places seed0..seed3 and a feature by clicks, drags the feature, renames and deletes another, saves, and checks that
//     qs-dissect reads the saved <stem>.landmarks.json (exact face/bary references) unchanged.
//  2. Runs: on a copy of the examples triple (with their landmark files) plus a mesh with a hole,
//     checks the list's findings, runs dissect/remesh/bake/morph from the page, waits for the
//     progress to end, shows every result view (patches, remesh, normal map on/off, morph sliders,
//     path animation), fetches a download link; then a run that fails (seeds on one mesh only)
//     shows qs-dissect's own message and leaves the folder as it was.
// With --shots DIR, saves a PNG of each view (README pictures: docs/images/studio_*.png).
//   usage: node studio-test.mjs --studio build/tools/qs-studio --examples examples [--shots DIR]
//          [--chromium PATH]
// Exit codes: 0 passed, 1 failed, 77 skipped (no Chromium or no puppeteer-core / three.js).
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const webDir = path.resolve(here, '..');
const args = process.argv.slice(2);
const opt = { chromium: process.env.CHROMIUM || '/usr/bin/chromium' };
for (let i = 0; i < args.length; i++) {
  const k = args[i].replace(/^--/, '');
  opt[k] = args[++i];
}
const skip = (why) => { console.log(`studio-test: SKIPPED: ${why}`); process.exit(77); };
if (!opt.studio || !opt.examples) { console.error('usage: studio-test.mjs --studio QS_STUDIO --examples DIR [--shots DIR]'); process.exit(1); }
if (!fs.existsSync(opt.chromium)) skip(`no Chromium at ${opt.chromium} (Debian: apt-get install chromium; scripts/setup.sh installs it)`);
if (!fs.existsSync(path.join(webDir, 'node_modules/three/build/three.module.js'))) skip(`three.js is not installed in ${webDir}/node_modules (run scripts/setup.sh)`);
let puppeteer;
try { puppeteer = (await import(path.join(webDir, 'node_modules/puppeteer-core/lib/esm/puppeteer/puppeteer-core.js'))).default; } catch (e) {
  skip(`puppeteer-core is not installed in ${webDir}/node_modules (run scripts/setup.sh): ${e.message}`);
}
const toolsDir = path.dirname(path.resolve(opt.studio));

let failures = 0;
const T0 = Date.now();
const check = (ok, what) => {
  console.log(`${ok ? "ok  " : "FAIL"} ${what} [${((Date.now() - T0) / 1000).toFixed(1)} s]`);
  if (!ok) failures++;
  return ok;
};
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'qs-studio-test-'));
const servers = [];
let browser;

function startStudio(folder) {
  return new Promise((resolve, reject) => {
    const p = spawn(opt.studio, [folder, '--port', '0', '--web', webDir], { stdio: ['ignore', 'pipe', 'pipe'] });
    servers.push(p);
    let out = '';
    const t = setTimeout(() => reject(new Error(`qs-studio printed no address: ${out}`)), 20000);
    p.stdout.on('data', (d) => {
      out += d;
      const m = /open (http:\/\/127\.0\.0\.1:\d+\/)/.exec(out);
      if (m) { clearTimeout(t); resolve(m[1]); }
    });
    p.stderr.on('data', (d) => { out += d; });
    p.on('exit', (code) => { clearTimeout(t); reject(new Error(`qs-studio exited with ${code}: ${out}`)); });
  });
}

// A tree listing with sizes and contents' lengths: "nothing changed on disk".
function snapshot(dir) {
  const out = [];
  const walk = (d) => {
    for (const e of fs.readdirSync(d, { withFileTypes: true }).sort((a, b) => a.name.localeCompare(b.name))) {
      const p = path.join(d, e.name);
      if (e.isDirectory()) { out.push(`${path.relative(dir, p)}/`); walk(p); } else out.push(`${path.relative(dir, p)} ${fs.statSync(p).size} ${fs.statSync(p).mtimeMs}`);
    }
  };
  walk(dir);
  return out.join('\n');
}

async function shot(page, name, selector) {
  if (!opt.shots) return;
  fs.mkdirSync(opt.shots, { recursive: true });
  const file = path.join(opt.shots, name);
  if (selector) await (await page.$(selector)).screenshot({ path: file });
  else await page.screenshot({ path: file });
  console.log(`     wrote ${file}`);
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

try {
  browser = await puppeteer.launch({
    executablePath: opt.chromium,
    headless: true,
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--ignore-gpu-blocklist', '--hide-scrollbars', '--mute-audio', '--no-first-run', '--disable-extensions', '--force-color-profile=srgb',
      '--no-proxy-server'],
    defaultViewport: { width: 1280, height: 720, deviceScaleFactor: 1 },
  });
  const page = await browser.newPage();
  const logs = [];
  page.on('console', (m) => { if (m.type() === 'error' || m.type() === 'warning') logs.push(`[console.${m.type()}] ${m.text()}`); });
  page.on('pageerror', (e) => logs.push(`[pageerror] ${e.message}`));

  // ---- 1. landmarks by clicks ----------------------------------------------------------------
  const a = path.join(tmp, 'a');
  fs.mkdirSync(a);
  const ref = JSON.parse(fs.readFileSync(path.join(opt.examples, 'spot_2k.landmarks.json'), 'utf8'));
  const urlA = await startStudio(a);
  await page.goto(urlA, { waitUntil: 'load' });
  await page.waitForSelector('body[data-ready="1"]', { timeout: 30000 });
  // the meshes come in through the page: a file that is not a mesh is refused, the OBJ is added
  const junk = path.join(tmp, 'notes.obj');
  fs.writeFileSync(junk, 'these are my notes, not a mesh\n');
  await (await page.$('#upload')).uploadFile(junk);
  await page.waitForFunction(() => /not added/.test(document.getElementById('upload-status').textContent), { timeout: 10000 });
  check(!fs.existsSync(path.join(a, 'notes.obj')), `a non-mesh upload is refused: "${await page.$eval('#upload-status', (e) => e.textContent)}"`);
  await (await page.$('#upload')).uploadFile(path.join(opt.examples, 'spot_2k.obj'));
  await page.waitForSelector('#meshes li[data-mesh="spot_2k.obj"]', { timeout: 10000 });
  check(fs.readFileSync(path.join(a, 'spot_2k.obj')).equals(fs.readFileSync(path.join(opt.examples, 'spot_2k.obj'))), 'spot_2k.obj uploaded through the page');
  const item = await page.$eval('#meshes li[data-mesh="spot_2k.obj"]', (li) => li.textContent);
  check(/ready/.test(item) && /no landmarks/.test(item), `mesh list: spot_2k.obj is ready, without landmarks ("${item.slice(0, 80)}...")`);
  await page.click('#meshes li[data-mesh="spot_2k.obj"] button.open');
  await page.waitForFunction(() => window.__studio.editors[0] && window.__studio.editors[0].ready, { timeout: 30000 });

  const placeAt = async (name, vertex) => {
    await page.$eval('.editor .place-name', (i, n) => { i.value = n; }, name);
    const p = await page.evaluate((v) => window.__studio.lookAtVertex('spot_2k.obj', v), vertex);
    await page.mouse.click(p.x + 1, p.y + 1);
    await page.waitForSelector(`.editor .lmlist li[data-name="${name}"]`, { timeout: 5000 });
    return p;
  };
  for (let i = 0; i < 4; i++) await placeAt(`seed${i}`, ref.seeds[i]);
  await page.waitForFunction(() => window.__studio.editors[0].loopOk !== undefined, { timeout: 20000 });
  check(await page.evaluate(() => window.__studio.editors[0].loopOk === true && window.__studio.editors[0].loopLines.length === 4),
    `4 seeds placed by clicks; the seed loop preview has 4 paths (${await page.$eval('.editor .status', (s) => s.textContent)})`);
  const nosePos = await placeAt('nose', ref.features.nose);
  const before = await page.evaluate(() => JSON.stringify(window.__studio.editors[0].landmarks.get('nose').bary));
  // drag the nose a few pixels along the surface
  await page.mouse.move(nosePos.x + 1, nosePos.y + 1);
  await page.mouse.down();
  await page.mouse.move(nosePos.x + 5, nosePos.y + 4, { steps: 4 });
  await page.mouse.up();
  const after = await page.evaluate(() => JSON.stringify(window.__studio.editors[0].landmarks.get('nose')));
  check(before !== JSON.stringify(JSON.parse(after).bary), `the nose was dragged (now ${after.slice(0, 90)}...)`);
  await placeAt('tail', ref.features.tail);
  await page.$eval('.editor .lmlist li[data-name="tail"] input', (i) => { i.value = 'tail_tip'; i.dispatchEvent(new Event('change')); });
  check(await page.$('.editor .lmlist li[data-name="tail_tip"]') !== null, 'tail renamed to tail_tip');
  await page.click('.editor .lmlist li[data-name="tail_tip"] button.delete');
  check(await page.$('.editor .lmlist li[data-name="tail_tip"]') === null, 'tail_tip deleted');
  await page.evaluate(() => window.__studio.frameFront('spot_2k.obj', [0.55, -0.75, 0.6]));
  await page.waitForFunction(() => window.__studio.editors[0].loopLines.length === 4, { timeout: 20000 });
  await sleep(300);
  await shot(page, 'studio_landmarks.png');
  await page.click('.editor button.save');
  await page.waitForFunction(() => /saved|not saved/.test(document.querySelector('.editor .status').textContent), { timeout: 10000 });
  const saved = path.join(a, 'spot_2k.landmarks.json');
  if (check(fs.existsSync(saved), `saved ${saved}`)) {
    const j = JSON.parse(fs.readFileSync(saved, 'utf8'));
    check(j.seeds.length === 4 && j.seeds.every((s) => Number.isInteger(s.face) && s.bary.length === 3) && j.features.nose && Object.keys(j.features).length === 1,
      `the file holds 4 seeds and the nose as exact {"face","bary"} references: ${JSON.stringify(j.seeds[0])}`);
    const r = spawnSync(path.join(toolsDir, 'qs-dissect'), [path.join(a, 'spot_2k.obj'), '-o', path.join(tmp, 'a-dissection')], { encoding: 'utf8' });
    check(r.status === 0, `qs-dissect reads the saved file back (exit ${r.status}): ${(r.stdout + r.stderr).split('\n')[0]}`);
    if (r.status === 0) {
      const d = JSON.parse(fs.readFileSync(path.join(tmp, 'a-dissection/dissection.json'), 'utf8'));
      check(d.meshes[0].seed_source.endsWith('spot_2k.landmarks.json') && d.meshes[0].features.length === 1 && d.meshes[0].features[0].name === 'nose',
        `qs-dissect used the saved seeds (${d.meshes[0].seed_source}) and the nose`);
    }
  }

  // ---- 2. the run flow -------------------------------------------------------------------------
  const b = path.join(tmp, 'b');
  fs.mkdirSync(b);
  for (const f of ['spot_2k.obj', 'cat_16k.obj', 'koala_7k.obj', 'fish_blub_2k.obj', 'spot_2k.landmarks.json', 'cat_16k.landmarks.json', 'koala_7k.landmarks.json'])
    fs.copyFileSync(path.join(opt.examples, f), path.join(b, f));
  // a tetrahedron with a missing face: rejected, with a finding in plain words
  fs.writeFileSync(path.join(b, 'open_box.obj'), 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n');
  const urlB = await startStudio(b);
  await page.goto(urlB, { waitUntil: 'load' });
  await page.waitForSelector('body[data-ready="1"]', { timeout: 30000 });
  const open = await page.$eval('#meshes li[data-mesh="open_box.obj"]', (li) => li.textContent);
  check(/rejected/.test(open) && /holes/.test(open), `open_box.obj is rejected: "${open.slice(0, 100)}..."`);
  for (const m of ['spot_2k.obj', 'cat_16k.obj', 'koala_7k.obj']) await page.click(`#meshes li[data-mesh="${m}"] input.tick`);
  await page.select('#bake-size', '64');
  await shot(page, 'studio_meshes.png', 'aside');
  const t0 = Date.now();
  await page.click('#run-btn');
  await page.waitForFunction(() => document.body.dataset.run === 'running' || document.body.dataset.run === 'done', { timeout: 10000 });
  await page.waitForFunction(() => ['done', 'failed'].includes(document.body.dataset.run), { timeout: 180000, polling: 200 });
  const stages = await page.$$eval('#stages li', (l) => l.map((x) => x.textContent));
  check(await page.evaluate(() => document.body.dataset.run) === 'done' && stages.length === 4 && stages.every((s) => /done/.test(s)),
    `run from the page: ${stages.join(', ')} in ${((Date.now() - t0) / 1000).toFixed(1)} s; progress ${await page.$eval('#progress', (p) => p.value)}`);
  const views = async (mode) => {
    await page.click(`input[name=rmode][value=${mode}]`);
    await page.waitForFunction(() => document.body.dataset.resultsReady !== '0', { timeout: 60000 });
    await sleep(400);
    return page.evaluate(() => ({ ready: document.body.dataset.resultsReady, panels: document.querySelectorAll('#result-views .panel').length }));
  };
  let v = await views('patches');
  check(v.ready === '1' && v.panels === 3, `patches: ${v.panels} views (${await page.$$eval('#result-views .bar .hint', (h) => h.map((x) => x.textContent).join('; '))})`);
  await shot(page, 'studio_patches.png', 'main');
  v = await views('remesh');
  check(v.ready === '1' && v.panels === 3, `remesh wireframes: ${v.panels} views`);
  await shot(page, 'studio_remesh.png', 'main');
  v = await views('bake');
  check(v.ready === '1' && v.panels === 3, `normal-map views: ${v.panels}`);
  await shot(page, 'studio_bake.png', 'main');
  await page.click('#result-map');
  check(await page.$eval('#result-map', (c) => !c.checked), 'normal map switched off');
  await page.click('#result-map');
  v = await views('morph');
  const sliders = await page.$$('.morph-slider');
  check(v.ready === '1' && sliders.length === 2, `morph: ${sliders.length} sliders (${await page.$eval('#result-controls', (c) => c.textContent)})`);
  await page.$eval('.morph-slider', (s) => { s.value = '0.5'; s.dispatchEvent(new Event('input')); });
  await page.click('#result-play');
  await sleep(1300);
  const w1 = await page.$$eval('.morph-slider', (s) => s.map((x) => +x.value));
  await sleep(500);
  const w2 = await page.$$eval('.morph-slider', (s) => s.map((x) => +x.value));
  check(JSON.stringify(w1) !== JSON.stringify(w2), `the path animation plays (weights ${w1} -> ${w2})`);
  await page.click('#result-play');
  await page.$$eval('.morph-slider', (s) => { s[0].value = '0.5'; s[0].dispatchEvent(new Event('input')); s[1].value = '0.25'; s[1].dispatchEvent(new Event('input')); });
  await sleep(300);
  await shot(page, 'studio_morph.png', 'main');
  const links = await page.$$eval('#downloads a', (l) => l.map((x) => x.getAttribute('href')));
  const glbLink = links.find((l) => /morph\.glb/.test(l));
  check(links.length >= 15 && !!glbLink, `${links.length} download links, one for morph.glb`);
  if (glbLink) {
    const res = await fetch(new URL(glbLink, urlB));
    const buf = Buffer.from(await res.arrayBuffer());
    check(res.status === 200 && buf.subarray(0, 4).toString() === 'glTF' && /attachment/.test(res.headers.get('content-disposition') || ''),
      `download of morph.glb: HTTP ${res.status}, ${buf.length} bytes, ${res.headers.get('content-disposition')}`);
  }

  // a failing run: seeds on spot (landmarks) but none on fish -> qs-dissect refuses; nothing changes
  const beforeFail = snapshot(b);
  await page.click('#meshes li[data-mesh="cat_16k.obj"] input.tick');
  await page.click('#meshes li[data-mesh="koala_7k.obj"] input.tick');
  await page.click('#meshes li[data-mesh="fish_blub_2k.obj"] input.tick');
  await page.click('#run-btn');
  await page.waitForFunction(() => document.body.dataset.run === 'running' || document.body.dataset.run === 'failed', { timeout: 10000 });
  await page.waitForFunction(() => ['done', 'failed'].includes(document.body.dataset.run), { timeout: 60000, polling: 200 });
  const err = await page.$eval('#run-error', (e) => e.textContent);
  check(await page.evaluate(() => document.body.dataset.run) === 'failed' && /qs-dissect: invalid input error/.test(err),
    `a failing run shows the tool's message: "${err.replace(/\n/g, ' ').slice(0, 160)}..."`);
  check(snapshot(b) === beforeFail, 'the failed run left the folder as it was');
  await page.click('#tab-edit');
  await page.click('#meshes li[data-mesh="spot_2k.obj"] button.open');
  await page.click('#meshes li[data-mesh="cat_16k.obj"] button.open');
  await page.waitForFunction(() => window.__studio.editors.length === 2 && window.__studio.editors.every((e) => e.ready && e.loopOk !== undefined), { timeout: 30000 });
  const both = await page.evaluate(() => window.__studio.editors.map((e) => [...e.landmarks.keys()].sort().join(',')));
  check(both[0] === both[1] && /nose/.test(both[0]), `two meshes side by side with the same landmark names: ${both[0]}`);
  const options = await page.$$eval('#feature-names option', (o) => o.map((x) => x.value));
  check(['left_ear', 'nose', 'right_ear', 'tail'].every((n) => options.includes(n)), `feature names offered: ${options.join(', ')}`);
  await sleep(300);
  await shot(page, 'studio_side_by_side.png', 'main');
  // an edit not saved yet: the run refuses to start rather than run on the old file
  await placeAt('chin', 300);
  await page.click('#run-btn');
  const unsavedMsg = await page.$eval('#run-error', (e) => e.textContent);
  check(/save the landmarks of spot_2k\.obj first/.test(unsavedMsg) && snapshot(b) === beforeFail, `a run with unsaved landmark edits is refused: "${unsavedMsg}"`);
  for (const l of logs) console.log(`     ${l}`);
  check(!logs.some((l) => l.startsWith('[pageerror]')), 'no script errors in the page');
} catch (e) {
  check(false, `unexpected: ${e.stack || e.message}`);
} finally {
  if (browser) await browser.close();
  for (const s of servers) s.kill('SIGTERM');
  fs.rmSync(tmp, { recursive: true, force: true });
}
console.log(failures ? `studio-test: ${failures} check(s) failed` : 'studio-test: all checks passed');
process.exit(failures ? 1 : 0);
