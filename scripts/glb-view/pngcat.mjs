// Puts PNG images side by side (left to right, tops aligned) into one RGB PNG; no dependencies.
//   usage: node scripts/glb-view/pngcat.mjs -o OUT.png [--gap PX] [--bg '#rrggbb'] A.png B.png ...
// Reads 8-bit non-interlaced PNGs (grey, grey+alpha, RGB, RGBA, palette); alpha is composited
// over the background.
import fs from 'node:fs';
import zlib from 'node:zlib';

function die(msg) { console.error(`pngcat: ${msg}`); process.exit(1); }

function crc32(buf) {
  let c, crc = 0xffffffff;
  for (let n = 0; n < buf.length; n++) {
    c = (crc ^ buf[n]) & 0xff;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    crc = (crc >>> 8) ^ c;
  }
  return (crc ^ 0xffffffff) >>> 0;
}

function readPng(file, bg) {
  const b = fs.readFileSync(file);
  if (b.readUInt32BE(0) !== 0x89504e47) die(`${file}: not a PNG`);
  let w, h, depth, type, interlace, palette = null, trns = null;
  const idat = [];
  for (let i = 8; i < b.length;) {
    const n = b.readUInt32BE(i), t = b.toString('latin1', i + 4, i + 8), d = b.subarray(i + 8, i + 8 + n);
    if (t === 'IHDR') { w = d.readUInt32BE(0); h = d.readUInt32BE(4); depth = d[8]; type = d[9]; interlace = d[12]; }
    else if (t === 'PLTE') palette = d;
    else if (t === 'tRNS') trns = d;
    else if (t === 'IDAT') idat.push(d);
    i += 12 + n;
  }
  if (depth !== 8 || interlace !== 0) die(`${file}: only 8-bit non-interlaced PNGs are supported`);
  const ch = { 0: 1, 2: 3, 3: 1, 4: 2, 6: 4 }[type];
  if (!ch) die(`${file}: unsupported colour type ${type}`);
  const raw = zlib.inflateSync(Buffer.concat(idat)), stride = w * ch;
  const px = Buffer.alloc(h * stride);
  let prev = Buffer.alloc(stride);
  for (let y = 0; y < h; y++) {
    const f = raw[y * (stride + 1)], line = Buffer.from(raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1)));
    for (let x = 0; x < stride; x++) {
      const a = x >= ch ? line[x - ch] : 0, up = prev[x], c = x >= ch ? prev[x - ch] : 0;
      let p = 0;
      if (f === 1) p = a; else if (f === 2) p = up; else if (f === 3) p = (a + up) >> 1;
      else if (f === 4) { const pa = Math.abs(up - c), pb = Math.abs(a - c), pc = Math.abs(a + up - 2 * c); p = pa <= pb && pa <= pc ? a : pb <= pc ? up : c; }
      line[x] = (line[x] + p) & 255;
    }
    line.copy(px, y * stride);
    prev = line;
  }
  const rgb = Buffer.alloc(w * h * 3);
  for (let i = 0; i < w * h; i++) {
    let r, g, bl, al = 255;
    const o = i * ch;
    if (type === 0) r = g = bl = px[o];
    else if (type === 4) { r = g = bl = px[o]; al = px[o + 1]; }
    else if (type === 2) { r = px[o]; g = px[o + 1]; bl = px[o + 2]; }
    else if (type === 6) { r = px[o]; g = px[o + 1]; bl = px[o + 2]; al = px[o + 3]; }
    else { const k = px[o]; r = palette[3 * k]; g = palette[3 * k + 1]; bl = palette[3 * k + 2]; if (trns && k < trns.length) al = trns[k]; }
    rgb[3 * i] = Math.round((r * al + bg[0] * (255 - al)) / 255);
    rgb[3 * i + 1] = Math.round((g * al + bg[1] * (255 - al)) / 255);
    rgb[3 * i + 2] = Math.round((bl * al + bg[2] * (255 - al)) / 255);
  }
  return { w, h, rgb };
}

function writePng(file, w, h, rgb) {
  const stride = w * 3, raw = Buffer.alloc(h * (stride + 1));
  for (let y = 0; y < h; y++) { // filter 1 (sub) on every row: small files for flat backgrounds
    raw[y * (stride + 1)] = 1;
    for (let x = 0; x < stride; x++) {
      const v = rgb[y * stride + x], a = x >= 3 ? rgb[y * stride + x - 3] : 0;
      raw[y * (stride + 1) + 1 + x] = (v - a) & 255;
    }
  }
  const chunk = (t, d) => {
    const len = Buffer.alloc(4); len.writeUInt32BE(d.length);
    const td = Buffer.concat([Buffer.from(t, 'latin1'), d]);
    const crc = Buffer.alloc(4); crc.writeUInt32BE(crc32(td));
    return Buffer.concat([len, td, crc]);
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0); ihdr.writeUInt32BE(h, 4); ihdr[8] = 8; ihdr[9] = 2;
  fs.writeFileSync(file, Buffer.concat([Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk('IHDR', ihdr), chunk('IDAT', zlib.deflateSync(raw, { level: 9 })), chunk('IEND', Buffer.alloc(0))]));
}

const a = process.argv.slice(2);
let out = null, gap = 0, bgHex = '#ffffff';
const inputs = [];
for (let i = 0; i < a.length; i++) {
  if (a[i] === '-o') out = a[++i];
  else if (a[i] === '--gap') gap = Number(a[++i]);
  else if (a[i] === '--bg') bgHex = a[++i];
  else if (a[i] === '-h' || a[i] === '--help') { console.log('usage: node pngcat.mjs -o OUT.png [--gap PX] [--bg #rrggbb] A.png B.png ...'); process.exit(0); }
  else inputs.push(a[i]);
}
if (!out || !inputs.length) die('usage: node pngcat.mjs -o OUT.png [--gap PX] [--bg #rrggbb] A.png B.png ...');
if (!/^#[0-9a-f]{6}$/i.test(bgHex) || !(gap >= 0)) die('bad --bg or --gap');
const bg = [1, 3, 5].map((k) => parseInt(bgHex.slice(k, k + 2), 16));
const imgs = inputs.map((f) => readPng(f, bg));
const W = imgs.reduce((s, im) => s + im.w, 0) + gap * (imgs.length - 1), H = Math.max(...imgs.map((im) => im.h));
const rgb = Buffer.alloc(W * H * 3);
for (let i = 0; i < W * H; i++) { rgb[3 * i] = bg[0]; rgb[3 * i + 1] = bg[1]; rgb[3 * i + 2] = bg[2]; }
let x0 = 0;
for (const im of imgs) {
  for (let y = 0; y < im.h; y++) im.rgb.copy(rgb, (y * W + x0) * 3, y * im.w * 3, (y + 1) * im.w * 3);
  x0 += im.w + gap;
}
writePng(out, W, H, rgb);
console.log(`pngcat: ${inputs.length} images -> ${out} (${W}x${H})`);
