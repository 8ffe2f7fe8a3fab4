// Driver of scripts/glb-view.sh: serves this folder and the model over a local HTTP port, opens
// index.html in headless Chromium (software WebGL: SwiftShader through ANGLE) with puppeteer-core,
// waits until the page has rendered (window.__glbView), and screenshots the page to a PNG.
// Exit codes: 0 ok, 1 usage, 2 the page failed (bad model, bad weights, no WebGL), 3 missing deps.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const usage = `usage: glb-view.sh MODEL.glb|MODEL.obj -o OUT.png [options]
  --size W|WxH         image size in pixels (default 512)
  --view x,y,z         direction from the object towards the camera (default 0.3,0.4,1, as qs-render)
  --up x,y,z           up direction in the image (default 0,1,0)
  --weights a,b,...    morph target weights (one per target)
  --time T             pose at T seconds of the model's first animation (instead of --weights)
  --no-map             render without the normal map (material.normalMap = null)
  --fit current|all    frame the current blend (default) or the base and every morph target,
                       so frames of one morph share one framing
  --persp              perspective camera (default orthographic, like qs-render)
  --flat               OBJ input: flat shading (default smooth, vertices merged by position)
  --angle-normals      OBJ input: smooth normals weighted by corner angle (as qs-bake's original
                       normals) instead of three.js's area weighting
  --label TEXT         caption drawn at the bottom of the image
  --bg '#rrggbb'       background (default #ffffff)
  --chromium PATH      browser (default $CHROMIUM, else /usr/bin/chromium)
  --timeout S          seconds to wait for the page (default 120)
  -q, --quiet          print nothing but errors (default prints what the viewer loaded)`;

function die(code, msg) { console.error(`glb-view: ${msg}`); process.exit(code); }

const a = process.argv.slice(2);
const opt = { size: '512', fit: 'current', bg: '#ffffff', timeout: 120, quiet: false,
  chromium: process.env.CHROMIUM || '/usr/bin/chromium' };
let model = null;
for (let i = 0; i < a.length; i++) {
  const k = a[i];
  const val = () => { if (i + 1 >= a.length) die(1, `${k} needs a value\n${usage}`); return a[++i]; };
  switch (k) {
    case '-h': case '--help': console.log(usage); process.exit(0);
    case '-o': case '--output': opt.out = val(); break;
    case '--size': opt.size = val(); break;
    case '--view': opt.view = val(); break;
    case '--up': opt.up = val(); break;
    case '--weights': opt.weights = val(); break;
    case '--time': opt.time = val(); break;
    case '--no-map': opt.nomap = true; break;
    case '--fit': opt.fit = val(); break;
    case '--persp': opt.persp = true; break;
    case '--flat': opt.flat = true; break;
    case '--angle-normals': opt.angle = true; break;
    case '--label': opt.label = val(); break;
    case '--bg': opt.bg = val(); break;
    case '--chromium': opt.chromium = val(); break;
    case '--timeout': opt.timeout = Number(val()); break;
    case '-q': case '--quiet': opt.quiet = true; break;
    default:
      if (k.startsWith('-') && !/^-[\d.]/.test(k)) die(1, `unknown option ${k}\n${usage}`);
      if (model) die(1, `more than one model given\n${usage}`);
      model = k;
  }
}
if (!model || !opt.out) die(1, `a model and -o OUT.png are required\n${usage}`);
if (!fs.existsSync(model)) die(1, `no such file: ${model}`);
const ext = path.extname(model).toLowerCase();
if (!['.glb', '.gltf', '.obj'].includes(ext)) die(1, `model must be .glb, .gltf or .obj: ${model}`);
const m = /^(\d+)(?:x(\d+))?$/.exec(opt.size);
if (!m) die(1, `bad --size '${opt.size}' (W or WxH)`);
const W = +m[1], H = +(m[2] || m[1]);
if (W < 16 || H < 16 || W > 8192 || H > 8192) die(1, `--size out of range: ${opt.size}`);
for (const k of ['view', 'up']) if (opt[k] !== undefined) {
  const v = opt[k].split(',').map(Number);
  if (v.length !== 3 || v.some((x) => !Number.isFinite(x)) || v.every((x) => x === 0)) die(1, `bad --${k} '${opt[k]}' (x,y,z)`);
}
if (opt.weights !== undefined && opt.weights.split(',').some((x) => x === '' || !Number.isFinite(Number(x))))
  die(1, `bad --weights '${opt.weights}' (comma list of numbers)`);
if (opt.time !== undefined && !Number.isFinite(Number(opt.time))) die(1, `bad --time '${opt.time}'`);
if (opt.weights !== undefined && opt.time !== undefined) die(1, '--weights and --time exclude each other');
if (!['current', 'all'].includes(opt.fit)) die(1, `bad --fit '${opt.fit}' (current or all)`);
if (!fs.existsSync(opt.chromium)) die(3, `no Chromium at ${opt.chromium}: install it with 'apt-get install chromium' (Debian) or pass --chromium PATH`);

let puppeteer;
try { puppeteer = (await import('puppeteer-core')).default; } catch {
  die(3, `puppeteer-core is not installed: run 'npm ci' in ${here}`);
}

// Local server: this folder (page, three.js from node_modules) and the model at /model<ext>.
const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
  '.glb': 'model/gltf-binary', '.gltf': 'model/gltf+json', '.obj': 'text/plain', '.png': 'image/png', '.bin': 'application/octet-stream' };
const modelAbs = path.resolve(model), modelDir = path.dirname(modelAbs);
const server = http.createServer((req, res) => {
  const u = decodeURIComponent(new URL(req.url, 'http://x').pathname);
  let file;
  if (u === '/favicon.ico') { res.writeHead(204); res.end(); return; }
  if (u === '/model' + ext) file = modelAbs;
  else if (u.startsWith('/model-files/')) file = path.join(modelDir, u.slice('/model-files/'.length)); // .gltf buffers/images
  else file = path.join(here, u === '/' ? 'index.html' : u);
  const inside = file === modelAbs || file.startsWith(here + path.sep) || file.startsWith(modelDir + path.sep);
  if (!inside || !fs.existsSync(file) || !fs.statSync(file).isFile()) { res.writeHead(404); res.end(); return; }
  res.writeHead(200, { 'Content-Type': types[path.extname(file).toLowerCase()] || 'application/octet-stream' });
  fs.createReadStream(file).pipe(res);
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const port = server.address().port;

const qs = new URLSearchParams({ model: (ext === '.gltf' ? '/model-files/' + path.basename(modelAbs) : '/model' + ext), w: W, h: H, fit: opt.fit, bg: opt.bg });
for (const k of ['view', 'up', 'weights', 'time', 'label']) if (opt[k] !== undefined) qs.set(k, opt[k]);
if (opt.nomap) qs.set('nomap', '1');
if (opt.persp) qs.set('persp', '1');
if (opt.flat) qs.set('flat', '1');
if (opt.angle) qs.set('normals', 'angle');

let browser, code = 0;
const logs = [];
try {
  browser = await puppeteer.launch({
    executablePath: opt.chromium,
    headless: true,
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--use-gl=angle', '--use-angle=swiftshader',
      '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--hide-scrollbars', '--mute-audio',
      '--no-first-run', '--disable-extensions', '--force-color-profile=srgb'],
    defaultViewport: { width: W, height: H, deviceScaleFactor: 1 },
  });
  const page = await browser.newPage();
  page.on('console', (msg) => logs.push(`[console.${msg.type()}] ${msg.text()}`));
  page.on('pageerror', (e) => logs.push(`[pageerror] ${e.message}`));
  await page.goto(`http://127.0.0.1:${port}/?${qs}`, { waitUntil: 'load', timeout: opt.timeout * 1000 });
  await page.waitForFunction('window.__glbView !== undefined', { timeout: opt.timeout * 1000, polling: 100 });
  const info = await page.evaluate(() => window.__glbView);
  if (!info.ok) {
    code = 2;
    console.error(`glb-view: the page failed on ${model}: ${info.error}`);
    for (const l of logs) console.error(l);
  } else {
    fs.mkdirSync(path.dirname(path.resolve(opt.out)), { recursive: true });
    await page.screenshot({ path: opt.out, type: 'png', clip: { x: 0, y: 0, width: W, height: H } });
    if (!opt.quiet) {
      console.log(`glb-view: ${model} -> ${opt.out} (${W}x${H}, ${info.gl})`);
      for (const mm of info.meshes) console.log(`  mesh ${JSON.stringify(mm)}`);
      console.log(`  extent along the camera axes (right, up, view): ${JSON.stringify(info.bbox)}`);
      if (info.animation) console.log(`  animation ${JSON.stringify(info.animation)}`);
      for (const l of logs) console.log(`  ${l}`);
    }
    for (const w of info.warnings) console.error(`glb-view: warning: ${w}`);
  }
} catch (e) {
  code = 2;
  console.error(`glb-view: ${e.message}`);
  for (const l of logs) console.error(l);
} finally {
  if (browser) await browser.close();
  server.close();
}
process.exit(code);
