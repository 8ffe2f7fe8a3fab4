// qs-studio's page: mesh list, landmark editor, runs and results. Talks to tools/qs-studio's
// JSON API (libqs/qs/studio/studio.h lists the routes). window.__studio exposes a few hooks for
// the browser tests (web/studio/test/studio-test.mjs).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { CSS2DRenderer, CSS2DObject } from 'three/addons/renderers/CSS2DRenderer.js';
import { Line2 } from 'three/addons/lines/Line2.js';
import { LineGeometry } from 'three/addons/lines/LineGeometry.js';
import { LineMaterial } from 'three/addons/lines/LineMaterial.js';

const $ = (id) => document.getElementById(id);
const el = (tag, props = {}, ...kids) => {
  const e = Object.assign(document.createElement(tag), props);
  for (const k of kids) e.append(k);
  return e;
};
const SEEDS = ['seed0', 'seed1', 'seed2', 'seed3'];
const SEED_COLOURS = ['#e6194b', '#3cb44b', '#4363d8', '#f0b400'];

async function api(path, opts = {}) {
  const r = await fetch(path, opts);
  let body = null;
  try { body = await r.json(); } catch { body = null; }
  if (!r.ok) throw new Error((body && body.error) || `HTTP ${r.status} on ${path}`);
  return body;
}
const postJSON = (path, obj) => api(path, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(obj) });

// ---------------------------------------------------------------------------------------------
// A 3D view: renderer, orbit camera, lights, labels; renders when something changed.
class Viewer {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(1);
    this.renderer.setClearColor(0xffffff);
    container.append(this.renderer.domElement);
    this.labels = new CSS2DRenderer();
    Object.assign(this.labels.domElement.style, { position: 'absolute', top: '0', left: '0', pointerEvents: 'none' });
    container.append(this.labels.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.001, 1000);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x666666, 1.6));
    const key = new THREE.DirectionalLight(0xffffff, 1.8);
    key.position.set(1, 2, 3);
    this.camera.add(key);
    this.scene.add(this.camera);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.redraw());
    this.last = performance.now();
    this.mixer = null;
    this.dirty = true;
    this.resize();
    new ResizeObserver(() => this.resize()).observe(container);
    const loop = () => {
      if (this.disposed) return;
      requestAnimationFrame(loop);
      const now = performance.now(), dt = (now - this.last) / 1000;
      this.last = now;
      if (this.mixer && this.playing) { this.mixer.update(dt); this.dirty = true; if (this.onTick) this.onTick(); }
      if (this.dirty) { this.dirty = false; this.renderer.render(this.scene, this.camera); this.labels.render(this.scene, this.camera); }
    };
    loop();
  }
  redraw() { this.dirty = true; }
  resize() {
    const w = Math.max(50, this.container.clientWidth), h = Math.max(50, this.container.clientHeight);
    this.renderer.setSize(w, h);
    this.labels.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.scene.traverse((o) => { if (o.material && o.material.isLineMaterial) o.material.resolution.set(w, h); });
    this.redraw();
  }
  // Frames a bounding box from a direction (default: front, slightly above).
  frame(box, dir = new THREE.Vector3(0.8, 0.35, 1)) {
    const c = box.getCenter(new THREE.Vector3()), r = box.getSize(new THREE.Vector3()).length() / 2 || 1;
    this.radius = r;
    const halfV = THREE.MathUtils.degToRad(this.camera.fov / 2), halfH = Math.atan(Math.tan(halfV) * this.camera.aspect);
    const d = (r / Math.sin(Math.min(halfV, halfH))) * 0.85;  // the bounding sphere, a little tighter
    this.camera.position.copy(c).addScaledVector(dir.clone().normalize(), d);
    this.camera.near = d / 100; this.camera.far = d * 10;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(c);
    this.controls.update();
    this.redraw();
  }
  dispose() {
    this.disposed = true;
    this.controls.dispose();
    this.renderer.dispose();
    this.renderer.forceContextLoss();
    this.container.remove();
  }
}

// Geometry from /api/mesh's JSON; faces keep their file ids (face f = triangle f).
function geometryOf(data, perFaceColour) {
  const g = new THREE.BufferGeometry();
  if (!perFaceColour) {
    g.setAttribute('position', new THREE.Float32BufferAttribute(data.positions, 3));
    g.setIndex(data.faces);
    g.computeVertexNormals();
  } else {  // one colour per face: unshared corners
    const P = data.positions, F = data.faces, pos = new Float32Array(F.length * 3), col = new Float32Array(F.length * 3);
    const c = new THREE.Color();
    for (let f = 0; f < F.length / 3; f++) {
      perFaceColour(f, c);
      for (let k = 0; k < 3; k++) {
        const v = F[3 * f + k];
        pos.set([P[3 * v], P[3 * v + 1], P[3 * v + 2]], 9 * f + 3 * k);
        col.set([c.r, c.g, c.b], 9 * f + 3 * k);
      }
    }
    g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    g.setAttribute('color', new THREE.BufferAttribute(col, 3));
    g.computeVertexNormals();
  }
  g.computeBoundingBox();
  return g;
}

// The colour of patch p: the same golden-ratio hue walk on every mesh (patch indices are common).
function patchColour(p, c) { return c.setHSL((p * 0.618033988749895) % 1, 0.62, 0.58); }

// ---------------------------------------------------------------------------------------------
// Landmark editor: one panel per open mesh.
const editors = [];
let knownFeatures = new Set();

class Editor {
  constructor(name) {
    this.name = name;
    this.landmarks = new Map();  // name -> {face, bary:[a,b,c], pos: Vector3}
    this.markers = new Map();
    this.loopLines = [];
    const bar = el('div', { className: 'bar' });
    this.nameInput = el('input', { className: 'place-name', value: 'seed0', title: 'the landmark a click places' });
    this.nameInput.setAttribute('list', 'feature-names');
    this.shading = el('select', { className: 'shading' }, el('option', { value: 'smooth', textContent: 'smooth' }), el('option', { value: 'flat', textContent: 'flat' }));
    this.wire = el('input', { type: 'checkbox', className: 'wire' });
    this.saveBtn = el('button', { className: 'save', textContent: 'Save landmarks' });
    const close = el('button', { className: 'close', textContent: '×', title: 'close' });
    bar.append(el('b', { textContent: name }), el('label', {}, 'click places ', this.nameInput),
      this.shading, el('label', {}, this.wire, ' wireframe'), this.saveBtn, close);
    const view = el('div', { className: 'view' });
    this.status = el('div', { className: 'status' });
    this.list = el('ul', { className: 'lmlist' });
    this.panel = el('div', { className: 'panel editor' }, bar, view, this.status, this.list);
    this.panel.dataset.mesh = name;
    $('editors').append(this.panel);
    this.viewer = new Viewer(view);
    this.shading.onchange = () => { this.material.flatShading = this.shading.value === 'flat'; this.material.needsUpdate = true; this.viewer.redraw(); };
    this.wire.onchange = () => { this.wireLines.visible = this.wire.checked; this.viewer.redraw(); };
    this.saveBtn.onclick = () => this.save();
    close.onclick = () => closeEditor(this);
    this.installPointer();
  }
  async load() {
    const data = await api(`/api/mesh?path=${encodeURIComponent(this.name)}`);
    this.geometry = geometryOf(data);
    // pushed back in depth so that the seed loop, drawn on the surface's edges, stays in sight
    this.material = new THREE.MeshStandardMaterial({ color: 0xc8c8c8, roughness: 0.8, metalness: 0, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
    this.mesh = new THREE.Mesh(this.geometry, this.material);
    this.wireLines = new THREE.LineSegments(new THREE.WireframeGeometry(this.geometry), new THREE.LineBasicMaterial({ color: 0x333333, transparent: true, opacity: 0.35 }));
    this.wireLines.visible = false;
    this.viewer.scene.add(this.mesh, this.wireLines);
    this.viewer.frame(this.geometry.boundingBox);
    this.markerRadius = this.viewer.radius * 0.018;
    try {
      const lm = await api(`/api/landmarks?name=${encodeURIComponent(this.name)}`);
      lm.seeds.forEach((s, i) => this.set(SEEDS[i], s.face, s.bary));
      for (const f of lm.features) this.set(f.name, f.face, f.bary);
      this.say(lm.file ? `loaded ${lm.file}: ${lm.seeds.length} seeds, ${lm.features.length} features` : 'no landmark file yet: click on the surface to place seed0');
    } catch (e) {
      this.say(`the landmark file beside ${this.name} was not loaded: ${e.message}`, true);
    }
    this.advance();
    this.changed();
  }
  say(msg, bad = false) { this.status.textContent = msg; this.status.className = 'status' + (bad ? ' error' : ' ok'); }
  positionOf(face, bary) {
    const pos = this.geometry.attributes.position, idx = this.geometry.index.array, p = new THREE.Vector3(), q = new THREE.Vector3();
    for (let k = 0; k < 3; k++) p.addScaledVector(q.fromBufferAttribute(pos, idx[3 * face + k]), bary[k]);
    return p;
  }
  set(name, face, bary) {
    this.landmarks.set(name, { face, bary, pos: this.positionOf(face, bary) });
    if (!SEEDS.includes(name)) knownFeatures.add(name);
  }
  // The next seed still missing, else the name field is left alone.
  advance() {
    const missing = SEEDS.find((s) => !this.landmarks.has(s));
    if (missing && SEEDS.includes(this.nameInput.value) && this.landmarks.has(this.nameInput.value)) this.nameInput.value = missing;
  }
  // A surface point under the pointer: exact face (file id) and barycentric coordinates.
  pick(ev, objects) {
    const r = this.viewer.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.viewer.camera);
    const hits = ray.intersectObjects(objects, false);
    return hits.length ? hits[0] : null;
  }
  hitToRef(hit) {
    const idx = this.geometry.index.array, pos = this.geometry.attributes.position, f = hit.faceIndex;
    const a = new THREE.Vector3().fromBufferAttribute(pos, idx[3 * f]), b = new THREE.Vector3().fromBufferAttribute(pos, idx[3 * f + 1]),
      c = new THREE.Vector3().fromBufferAttribute(pos, idx[3 * f + 2]);
    const t = new THREE.Vector3();
    THREE.Triangle.getBarycoord(hit.point, a, b, c, t);
    let w = [t.x, t.y, t.z].map((x) => Math.max(0, x));
    const s = w[0] + w[1] + w[2];
    w = s > 0 ? w.map((x) => x / s) : [1, 0, 0];
    return { face: f, bary: w };
  }
  installPointer() {
    const canvas = this.viewer.renderer.domElement;
    let down = null, drag = null;
    canvas.addEventListener('pointerdown', (ev) => {
      if (ev.button !== 0 || !this.mesh) return;
      down = { x: ev.clientX, y: ev.clientY };
      const m = this.pick(ev, [...this.markers.values()]);
      if (m) {
        drag = m.object.userData.name;
        this.viewer.controls.enabled = false;
        canvas.setPointerCapture(ev.pointerId);
      }
    });
    canvas.addEventListener('pointermove', (ev) => {
      if (!drag) return;
      const hit = this.pick(ev, [this.mesh]);
      if (!hit) return;
      const ref = this.hitToRef(hit);
      this.set(drag, ref.face, ref.bary);
      this.changed(false);
    });
    canvas.addEventListener('pointerup', (ev) => {
      if (drag) {
        this.unsaved = true;
        this.say(`moved ${drag}`);
        drag = null;
        this.viewer.controls.enabled = true;
        this.changed();
        return;
      }
      if (!down || Math.hypot(ev.clientX - down.x, ev.clientY - down.y) > 4) { down = null; return; }  // an orbit
      down = null;
      const name = this.nameInput.value.trim();
      if (!name) { this.say('type a name in "click places" first', true); return; }
      const hit = this.pick(ev, [this.mesh]);
      if (!hit) return;
      const ref = this.hitToRef(hit);
      this.set(name, ref.face, ref.bary);
      this.unsaved = true;
      this.say(`placed ${name} on face ${ref.face}`);
      this.advance();
      this.changed();
    });
  }
  // Redraws markers and the list; with `loop`, asks the server for the seed loop preview.
  changed(loop = true) {
    for (const m of this.markers.values()) { this.viewer.scene.remove(m); m.clear(); }
    this.markers.clear();
    this.list.replaceChildren();
    const names = [...this.landmarks.keys()].sort((a, b) => (SEEDS.includes(a) ? SEEDS.indexOf(a) - 10 : 0) - (SEEDS.includes(b) ? SEEDS.indexOf(b) - 10 : 0) || a.localeCompare(b));
    for (const name of names) {
      const l = this.landmarks.get(name);
      const colour = SEEDS.includes(name) ? SEED_COLOURS[SEEDS.indexOf(name)] : '#ff7f0e';
      const m = new THREE.Mesh(new THREE.SphereGeometry(this.markerRadius, 16, 12), new THREE.MeshBasicMaterial({ color: colour }));
      m.position.copy(l.pos);
      m.userData.name = name;
      const label = new CSS2DObject(el('span', { className: 'label3d', textContent: name }));
      label.position.set(0, this.markerRadius * 1.8, 0);
      m.add(label);
      this.viewer.scene.add(m);
      this.markers.set(name, m);
      const rename = el('input', { value: name, title: 'rename' });
      rename.onchange = () => this.rename(name, rename.value.trim());
      const del = el('button', { textContent: 'delete', className: 'delete' });
      del.onclick = () => { this.landmarks.delete(name); this.unsaved = true; this.say(`deleted ${name}`); this.changed(); };
      const li = el('li', {}, el('span', { className: 'swatch', style: `background:${colour}` }), rename,
        el('span', { className: 'hint', textContent: `face ${l.face} (${l.bary.map((x) => x.toFixed(3)).join(', ')})` }), del);
      li.dataset.name = name;
      this.list.append(li);
    }
    refreshFeatureNames();
    this.viewer.redraw();
    if (loop) this.previewLoop();
  }
  rename(from, to) {
    if (!to || to === from) return this.changed(false);
    if (this.landmarks.has(to)) { this.say(`there is already a landmark named ${to}`, true); return this.changed(false); }
    const l = this.landmarks.get(from);
    this.landmarks.delete(from);
    this.set(to, l.face, l.bary);
    this.unsaved = true;
    this.say(`renamed ${from} to ${to}`);
    this.changed();
  }
  toJSON() {
    const seeds = SEEDS.filter((s) => this.landmarks.has(s));
    const out = { seeds: [], features: {} };
    if (seeds.length === 4) out.seeds = SEEDS.map((s) => ({ face: this.landmarks.get(s).face, bary: this.landmarks.get(s).bary }));
    for (const [name, l] of this.landmarks) if (!SEEDS.includes(name)) out.features[name] = { face: l.face, bary: l.bary };
    return { body: out, seedCount: seeds.length };
  }
  async previewLoop() {
    for (const l of this.loopLines) this.viewer.scene.remove(l);
    this.loopLines = [];
    const { body, seedCount } = this.toJSON();
    if (seedCount !== 4) { this.viewer.redraw(); return; }
    const ticket = (this.loopTicket = (this.loopTicket || 0) + 1);
    try {
      const r = await postJSON(`/api/seed-loop?name=${encodeURIComponent(this.name)}`, body);
      if (ticket !== this.loopTicket) return;
      const size = this.viewer.renderer.getSize(new THREE.Vector2());
      r.paths.forEach((p, i) => {
        const g = new LineGeometry();
        g.setPositions(p);
        const mat = new LineMaterial({ color: SEED_COLOURS[i], linewidth: 3 });
        mat.resolution.copy(size);
        const line = new Line2(g, mat);
        line.computeLineDistances();
        line.renderOrder = 1;
        this.loopLines.push(line);
        this.viewer.scene.add(line);
      });
      this.loopOk = true;
      this.say(`seed loop: length ${r.length.toPrecision(4)} (drawn as qs-dissect routes it)`);
    } catch (e) {
      if (ticket !== this.loopTicket) return;
      this.loopOk = false;
      this.say(e.message, true);
    }
    this.viewer.redraw();
  }
  async save() {
    const { body, seedCount } = this.toJSON();
    if (seedCount !== 0 && seedCount !== 4) { this.say(`place all four seeds or none (${seedCount} placed)`, true); return; }
    try {
      const r = await postJSON(`/api/landmarks?name=${encodeURIComponent(this.name)}`, body);
      this.unsaved = false;
      this.say(`saved ${r.file}: ${r.seeds} seeds, ${r.features} features`);
      this.saved = r.file;
      loadMeshes();
    } catch (e) {
      this.say(`not saved: ${e.message}`, true);
    }
  }
}

function refreshFeatureNames() {
  let dl = $('feature-names');
  if (!dl) { dl = el('datalist', { id: 'feature-names' }); document.body.append(dl); }
  dl.replaceChildren(...[...SEEDS, ...[...knownFeatures].sort()].map((n) => el('option', { value: n })));
}

async function openEditor(name) {
  showTab('edit');
  if (editors.find((e) => e.name === name)) return;
  $('edit-empty').classList.add('hidden');
  const ed = new Editor(name);
  editors.push(ed);
  await ed.load().catch((e) => ed.say(`cannot open ${name}: ${e.message}`, true));
  ed.ready = true;
}
function closeEditor(ed) {
  editors.splice(editors.indexOf(ed), 1);
  ed.viewer.dispose();
  ed.panel.remove();
  if (!editors.length) $('edit-empty').classList.remove('hidden');
}

// ---------------------------------------------------------------------------------------------
// Mesh list and upload.
let ticked = [];
async function loadMeshes() {
  const r = await api('/api/meshes');
  $('folder').textContent = r.folder;
  const ul = $('meshes');
  ul.replaceChildren();
  ticked = ticked.filter((n) => r.meshes.some((m) => m.name === n && m.accepted));
  for (const m of r.meshes) {
    const tick = el('input', { type: 'checkbox', checked: ticked.includes(m.name), disabled: !m.accepted, className: 'tick' });
    tick.onchange = () => { ticked = tick.checked ? [...ticked, m.name] : ticked.filter((n) => n !== m.name); showTicked(); };
    const open = el('button', { textContent: 'open', className: 'open', disabled: !m.accepted });
    open.onclick = () => openEditor(m.name);
    const li = el('li', {}, tick, ' ', el('span', { className: 'name', textContent: m.name }), ' ',
      el('span', { className: 'badge ' + (m.accepted ? 'ok' : 'bad'), textContent: m.accepted ? 'ready' : 'rejected' }), ' ', open,
      el('div', { className: 'summary', textContent: m.summary }));
    li.dataset.mesh = m.name;
    if (m.landmarks) {
      li.append(el('div', {
        className: 'hint lm', textContent: m.landmarks.error ? `landmarks ${m.landmarks.file}: ${m.landmarks.error}`
          : `landmarks: ${m.landmarks.file}` + (m.landmarks.seeds !== undefined ? ` (${m.landmarks.seeds} seeds, ${m.landmarks.features} features)` : ''),
      }));
    } else if (m.accepted) li.append(el('div', { className: 'hint lm', textContent: 'no landmarks (seeds chosen automatically)' }));
    if (m.problems.length) {
      li.append(el('ul', { className: 'problems' }, ...m.problems.map((p) => el('li', { className: p.severity, textContent: p.plain },
        el('span', { className: 'tech', textContent: p.message })))));
    }
    ul.append(li);
  }
  showTicked();
  return r;
}
function showTicked() {
  $('run-meshes').textContent = ticked.length ? `run on: ${ticked.join(', ')}` : 'no mesh ticked';
}
$('upload').onchange = async (ev) => {
  const f = ev.target.files[0];
  if (!f) return;
  const st = $('upload-status');
  try {
    await api(`/api/upload?name=${encodeURIComponent(f.name)}`, { method: 'POST', body: f });
    st.textContent = `added ${f.name}`; st.className = 'status ok';
    await loadMeshes();
  } catch (e) {
    st.textContent = `${f.name} not added: ${e.message}`; st.className = 'status error';
  }
  ev.target.value = '';
};

// ---------------------------------------------------------------------------------------------
// Runs.
let polling = null;
$('run-btn').onclick = async () => {
  $('run-error').textContent = '';
  if (!ticked.length) { $('run-error').textContent = 'tick the meshes to run first'; return; }
  // The tools read the landmark files: edits still only in the page would be silently left out.
  const unsaved = editors.filter((e) => ticked.includes(e.name) && e.unsaved).map((e) => e.name);
  if (unsaved.length) { $('run-error').textContent = `save the landmarks of ${unsaved.join(', ')} first (the run reads the saved files)`; return; }
  try {
    await postJSON('/api/run', { meshes: ticked, level: +$('level').value, bake_size: +$('bake-size').value, max_area: +$('max-area').value || 0 });
    pollRun();
  } catch (e) {
    $('run-error').textContent = e.message;
  }
};
async function pollRun() {
  clearTimeout(polling);
  const s = await api('/api/run');
  const ol = $('stages');
  ol.replaceChildren(...s.stages.map((st) => el('li', { className: st.status, textContent: `${st.name}: ${st.status}`
    + (st.status === 'running' && st.fraction > 0 ? ` ${Math.round(100 * st.fraction)}%` : '') + (st.exit_code > 0 ? ` (exit ${st.exit_code})` : '') })));
  // done stages count 1, the running one its reported fraction
  const done = s.stages.reduce((a, st) => a + (st.status === 'done' ? 1 : st.status === 'running' ? st.fraction : 0), 0);
  $('progress').value = s.stages.length ? done / s.stages.length : 0;
  $('log').textContent = s.log;
  $('log').scrollTop = 1e9;
  $('run-error').textContent = s.error;
  $('run-btn').disabled = s.status === 'running';
  if (s.status === 'running') { document.body.dataset.run = s.status; polling = setTimeout(pollRun, 400); return; }
  if (s.status === 'done') { await loadRuns(s.name); showTab('results'); }
  // published last, so that whoever waits for "done" finds the results tab already shown
  document.body.dataset.run = s.status;
}

let runList = [];
async function loadRuns(select) {
  runList = (await api('/api/runs')).runs;
  const sel = $('runs');
  sel.replaceChildren(...runList.map((r) => el('option', { value: r.name, textContent: `${r.name}: ${(r.run && r.run.meshes || []).join(', ')}` })));
  if (runList.length) sel.value = select || runList[runList.length - 1].name;
  showRun();
}
$('runs').onchange = () => showRun();
document.querySelectorAll('input[name=rmode]').forEach((r) => { r.onchange = () => showRun(); });

let resultViewers = [];
function currentRun() { return runList.find((r) => r.name === $('runs').value); }
async function showRun() {
  for (const v of resultViewers) v.dispose();
  resultViewers = [];
  $('result-controls').replaceChildren();
  const run = currentRun();
  $('result-empty').classList.toggle('hidden', !!run);
  $('downloads').replaceChildren();
  document.body.dataset.resultsReady = '0';
  if (!run) return;
  for (const f of run.files) {
    $('downloads').append(el('li', {}, el('a', { href: `/files/${f.path}?download=1`, textContent: f.path.split('/').slice(2).join('/') || f.path, download: '' }),
      el('span', { className: 'hint', textContent: ` ${(f.bytes / 1024).toFixed(0)} KiB` })));
  }
  const mode = document.querySelector('input[name=rmode]:checked').value;
  const files = run.files.map((f) => f.path);
  const stems = (run.run ? run.run.meshes : []).map((m) => m.replace(/\.[^.]+$/, ''));
  const addView = (title) => {
    const view = el('div', { className: 'view' });
    const panel = el('div', { className: 'panel result' }, el('div', { className: 'bar' }, el('b', { textContent: title })), view);
    $('result-views').append(panel);
    const v = new Viewer(view);
    v.panel = panel;
    const d = v.dispose.bind(v);
    v.dispose = () => { d(); panel.remove(); };
    resultViewers.push(v);
    return v;
  };
  try {
    if (mode === 'patches' || mode === 'remesh') {
      const dir = mode === 'patches' ? 'dissection/' : `remesh-L${run.run.level}/`;
      const ext = mode === 'patches' ? '.chart.ply' : '.obj';
      const wire = mode === 'remesh' ? el('input', { type: 'checkbox', checked: true, id: 'result-wire' }) : null;
      if (wire) $('result-controls').append(el('label', {}, wire, ' wireframe'));
      await Promise.all(stems.map(async (stem) => {
        const path = files.find((f) => f.endsWith(dir + stem + ext));
        if (!path) return;
        const v = addView(`${stem}: ${mode === 'patches' ? 'common patches' : `level-${run.run.level} remesh`}`);
        const data = await api(`/api/mesh?path=${encodeURIComponent(path)}`);
        const g = mode === 'patches' ? geometryOf(data, (f, c) => patchColour(data.patch[f], c)) : geometryOf(data);
        const mat = new THREE.MeshStandardMaterial({ color: mode === 'patches' ? 0xffffff : 0xd0d0d0, vertexColors: mode === 'patches', roughness: 0.85, flatShading: mode === 'patches', polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
        v.scene.add(new THREE.Mesh(g, mat));
        if (mode === 'patches') v.panel.querySelector('.bar').append(el('span', { className: 'hint', textContent: `${data.patches} patches, ${data.faces.length / 3} faces` }));
        else {
          const lines = new THREE.LineSegments(new THREE.WireframeGeometry(g), new THREE.LineBasicMaterial({ color: 0x1a3d6b }));
          v.scene.add(lines);
          wire.addEventListener('change', () => { lines.visible = wire.checked; v.redraw(); });
          v.panel.querySelector('.bar').append(el('span', { className: 'hint', textContent: `${data.positions.length / 3} vertices, ${data.faces.length / 3} faces (one face list for all)` }));
        }
        v.frame(g.boundingBox);
      }));
    } else if (mode === 'bake') {
      const mapBox = el('input', { type: 'checkbox', checked: true, id: 'result-map' });
      $('result-controls').append(el('label', {}, mapBox, ' normal map'));
      await Promise.all(stems.map(async (stem) => {
        const path = files.find((f) => f.endsWith('bake/' + stem + '.glb'));
        if (!path) return;
        const v = addView(`${stem}: coarse remesh with its baked normal map`);
        const gltf = await new GLTFLoader().loadAsync(`/files/${path}`);
        const maps = [];
        gltf.scene.traverse((o) => { if (o.isMesh && o.material.normalMap) maps.push([o.material, o.material.normalMap]); });
        mapBox.addEventListener('change', () => { for (const [m, t] of maps) { m.normalMap = mapBox.checked ? t : null; m.needsUpdate = true; } v.redraw(); });
        v.scene.add(gltf.scene);
        v.frame(new THREE.Box3().setFromObject(gltf.scene));
      }));
    } else if (mode === 'morph') {
      const path = files.find((f) => f.endsWith('/morph.glb'));
      if (!path) { $('result-controls').append(el('span', { className: 'hint', textContent: 'no morph in this run (it needs two meshes or more)' })); }
      else {
        const v = addView('morph: one target per shape, the path animation');
        const gltf = await new GLTFLoader().loadAsync(`/files/${path}`);
        let mesh = null;
        gltf.scene.traverse((o) => { if (o.isMesh && o.morphTargetInfluences && !mesh) mesh = o; });
        v.scene.add(gltf.scene);
        // framed on the base shape's own positions, with room for the targets (placed on it by a similarity)
        gltf.scene.updateMatrixWorld(true);
        const box = new THREE.Box3().setFromBufferAttribute(mesh.geometry.attributes.position).applyMatrix4(mesh.matrixWorld);
        v.frame(box.expandByScalar(box.getSize(new THREE.Vector3()).length() * 0.12));
        const names = (mesh.geometry.userData.targetNames || mesh.userData.targetNames || (gltf.parser.json.meshes[0].extras || {}).targetNames || []);
        const sliders = mesh.morphTargetInfluences.map((_, i) => {
          const s = el('input', { type: 'range', min: 0, max: 1, step: 0.01, value: 0, className: 'morph-slider' });
          s.oninput = () => { play.checked = false; v.playing = false; mesh.morphTargetInfluences[i] = +s.value; v.redraw(); };
          $('result-controls').append(el('label', { className: 'slider' }, names[i] || `target ${i}`, s));
          return s;
        });
        const play = el('input', { type: 'checkbox', id: 'result-play' });
        $('result-controls').append(el('label', {}, play, ' play the path'));
        if (gltf.animations.length) {
          v.mixer = new THREE.AnimationMixer(gltf.scene);
          v.mixer.clipAction(gltf.animations[0]).play();
          v.onTick = () => sliders.forEach((s, i) => { s.value = mesh.morphTargetInfluences[i]; });
          play.onchange = () => { v.playing = play.checked; v.redraw(); };
        } else play.disabled = true;
      }
    }
    document.body.dataset.resultsReady = '1';
  } catch (e) {
    $('result-controls').append(el('span', { className: 'status error', textContent: `cannot show ${mode}: ${e.message}` }));
    document.body.dataset.resultsReady = 'error';
  }
}

function showTab(which) {
  $('edit').classList.toggle('hidden', which !== 'edit');
  $('results').classList.toggle('hidden', which !== 'results');
  $('tab-edit').classList.toggle('on', which === 'edit');
  $('tab-results').classList.toggle('on', which === 'results');
  for (const v of [...resultViewers, ...editors.map((e) => e.viewer)]) v.resize();
}
$('tab-edit').onclick = () => showTab('edit');
$('tab-results').onclick = () => showTab('results');

// Hooks for the browser tests: where a vertex of an open mesh is on the screen, after turning the
// camera to look at it along its normal (so it is in sight).
window.__studio = {
  editors, openEditor, loadMeshes, showTab,
  lookAtVertex(mesh, v) {
    const ed = editors.find((e) => e.name === mesh);
    const pos = ed.geometry.attributes.position, nrm = ed.geometry.attributes.normal;
    const p = new THREE.Vector3().fromBufferAttribute(pos, v), n = new THREE.Vector3().fromBufferAttribute(nrm, v).normalize();
    const vw = ed.viewer;
    vw.controls.target.copy(p);
    vw.camera.position.copy(p).addScaledVector(n, vw.radius * 2.5);
    vw.controls.update();
    vw.renderer.render(vw.scene, vw.camera);
    const s = p.clone().project(vw.camera), r = vw.renderer.domElement.getBoundingClientRect();
    return { x: r.left + (s.x + 1) / 2 * r.width, y: r.top + (1 - s.y) / 2 * r.height };
  },
  frameFront(mesh, dir) {
    const ed = editors.find((e) => e.name === mesh);
    ed.viewer.frame(ed.geometry.boundingBox, new THREE.Vector3(...dir));
  },
};

Promise.all([loadMeshes(), loadRuns()]).then(async () => {
  const s = await api('/api/run');
  if (s.status === 'running') pollRun();
  document.body.dataset.ready = '1';
}).catch((e) => { document.body.append(el('pre', { className: 'error', textContent: e.message })); });
