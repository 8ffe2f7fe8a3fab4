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
      if (this.dirty) {
        this.dirty = false;
        this.renderer.render(this.scene, this.camera);
        if (this.beforeRender) this.beforeRender();
        this.labels.render(this.scene, this.camera);
        if (this.afterLabels) this.afterLabels();
      }
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
    if (!box) return;
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
// Views that follow each other: turning, zooming or panning one turns the others the same way
// (relative to each one's own bounding box, so meshes of different sizes stay framed).
function linkViews(getViews, isOn) {
  let busy = false;
  return (from) => {
    if (busy || !isOn() || !from.box || from.linkable === false) return;
    busy = true;
    const c = from.box.getCenter(new THREE.Vector3()), r = from.radius || 1;
    const off = from.camera.position.clone().sub(from.controls.target).divideScalar(r);
    const tgt = from.controls.target.clone().sub(c).divideScalar(r);
    for (const v of getViews()) {
      if (v === from || !v.box) continue;
      const c2 = v.box.getCenter(new THREE.Vector3()), r2 = v.radius || 1;
      v.controls.target.copy(c2).addScaledVector(tgt, r2);
      v.camera.position.copy(v.controls.target).addScaledVector(off, r2);
      v.camera.up.copy(from.camera.up);
      v.controls.update();
      v.redraw();
    }
    busy = false;
  };
}
const VIEW_DIRS = { front: [0, 0, 1], side: [1, 0, 0], top: [0, 1, 0.0001], bottom: [0, -1, 0.0001] };
function viewButtons(getTargets) {
  return Object.keys(VIEW_DIRS).map((k) => {
    const b = el('button', { className: 'view-btn', textContent: k, title: `look from the ${k}` });
    b.dataset.view = k;
    b.onclick = () => { for (const v of getTargets()) v.frame(v.box, new THREE.Vector3(...VIEW_DIRS[k])); };
    return b;
  });
}

// ---------------------------------------------------------------------------------------------
// Landmark editor: one panel per open mesh. A click on the surface places only the landmark
// chosen for placing (its "place" button, or a new feature's "add"); without one a click changes
// nothing. Every edit can be undone (Ctrl-Z) and redone (Ctrl-Shift-Z).
const editors = [];
let activeEditor = null;
let knownFeatures = new Set();
const linkEditors = linkViews(() => editors.filter((e) => e.mesh).map((e) => e.viewer), () => $('link-editors').checked);

class Editor {
  constructor(name, inspectOnly = false) {
    this.name = name;
    this.inspectOnly = inspectOnly;  // a rejected mesh: its problems drawn, no landmarks
    this.landmarks = new Map();  // name -> {face, bary:[a,b,c], pos: Vector3}
    this.markers = new Map();
    this.loopLines = [];
    this.history = [];
    this.future = [];
    this.placing = null;
    this.saved = '[]';
    const bar = el('div', { className: 'bar' });
    this.title = el('b', { textContent: name });
    this.unsavedMark = el('span', { className: 'unsaved-mark hidden', textContent: '● unsaved', title: 'edits not saved yet' });
    this.shading = el('select', { className: 'shading' }, el('option', { value: 'smooth', textContent: 'smooth' }), el('option', { value: 'flat', textContent: 'flat' }));
    this.wire = el('input', { type: 'checkbox', className: 'wire' });
    this.saveBtn = el('button', { className: 'save', textContent: 'Save landmarks' });
    this.undoBtn = el('button', { className: 'undo', textContent: '↶', title: 'undo (Ctrl-Z)', disabled: true });
    this.redoBtn = el('button', { className: 'redo', textContent: '↷', title: 'redo (Ctrl-Shift-Z)', disabled: true });
    const close = el('button', { className: 'close', textContent: '×', title: 'close' });
    bar.append(this.title, this.unsavedMark, ...viewButtons(() => [this.viewer]), this.shading, el('label', {}, this.wire, ' wireframe'));
    if (!inspectOnly) bar.append(this.undoBtn, this.redoBtn, this.saveBtn);
    bar.append(close);
    const view = el('div', { className: 'view' });
    this.placeInfo = el('div', { className: 'place-info' });
    this.status = el('div', { className: 'status' });
    this.loopStatus = el('div', { className: 'status loop-status' });
    this.list = el('ul', { className: 'lmlist' });
    this.newName = el('input', { className: 'new-name', placeholder: 'feature name', title: 'a feature to add: type its name, press add, click on the surface' });
    this.newName.setAttribute('list', 'feature-names');
    const add = el('button', { className: 'add', textContent: 'add' });
    add.onclick = () => this.startPlacing(this.newName.value.trim());
    this.newName.onkeydown = (ev) => { if (ev.key === 'Enter') add.onclick(); };
    const adder = el('div', { className: 'adder' }, 'new feature ', this.newName, add);
    this.panel = el('div', { className: 'panel editor' }, bar, view);
    if (inspectOnly) this.panel.append(this.status);
    else this.panel.append(this.placeInfo, this.status, this.loopStatus, this.list, adder);
    this.panel.dataset.mesh = name;
    $('editors').append(this.panel);
    this.viewer = new Viewer(view);
    this.viewer.linkable = false;  // its own framing while it opens is not passed on
    this.viewer.controls.addEventListener('change', () => linkEditors(this.viewer));
    this.viewer.beforeRender = () => this.hideCoveredLabels();
    this.viewer.afterLabels = () => this.spreadLabels();
    this.viewer.controls.addEventListener('start', () => { this.turning = true; });
    this.viewer.controls.addEventListener('end', () => { this.turning = false; this.viewer.redraw(); });
    this.shading.onchange = () => { this.material.flatShading = this.shading.value === 'flat'; this.material.needsUpdate = true; this.viewer.redraw(); };
    this.wire.onchange = () => { this.wireLines.visible = this.wire.checked; this.viewer.redraw(); };
    this.saveBtn.onclick = () => this.save();
    this.undoBtn.onclick = () => this.undo();
    this.redoBtn.onclick = () => this.redo();
    close.onclick = () => closeEditor(this);
    this.panel.addEventListener('pointerdown', () => { activeEditor = this; }, true);
    if (!inspectOnly) this.installPointer();
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
    this.viewer.box = this.geometry.boundingBox;
    this.viewer.frame(this.geometry.boundingBox);
    this.markerRadius = this.viewer.radius * 0.018;
    if (this.inspectOnly) return this.drawProblems(data);
    try {
      const lm = await api(`/api/landmarks?name=${encodeURIComponent(this.name)}`);
      lm.seeds.forEach((s, i) => this.set(SEEDS[i], s.face, s.bary));
      for (const f of lm.features) this.set(f.name, f.face, f.bary);
      this.say(lm.file ? `loaded ${lm.file}: ${lm.seeds.length} seeds, ${lm.features.length} features` : 'no landmark file yet');
    } catch (e) {
      this.say(`the landmark file beside ${this.name} was not loaded: ${e.message}`, true);
    }
    this.saved = this.serialize();
    // A mesh without seeds starts with seed0 chosen for placing; one with all four with nothing.
    this.placing = SEEDS.every((s) => !this.landmarks.has(s)) ? 'seed0' : null;
    this.changed();
    // Looked at from the side its seeds face most (the examples' seeds sit on the feet).
    this.lookAtSeeds();
  }
  // Edges used by one face (holes) and by more than two (non-manifold), drawn over a rejected mesh.
  drawProblems(data) {
    const F = data.faces, P = data.positions, uses = new Map();
    for (let f = 0; f < F.length / 3; f++)
      for (let k = 0; k < 3; k++) {
        const a = F[3 * f + k], b = F[3 * f + (k + 1) % 3], key = a < b ? `${a},${b}` : `${b},${a}`;
        uses.set(key, (uses.get(key) || 0) + 1);
      }
    const open = [], nonManifold = [];
    for (const [key, n] of uses) {
      if (n === 2) continue;
      const [a, b] = key.split(',').map(Number);
      (n === 1 ? open : nonManifold).push(P[3 * a], P[3 * a + 1], P[3 * a + 2], P[3 * b], P[3 * b + 1], P[3 * b + 2]);
    }
    const size = this.viewer.renderer.getSize(new THREE.Vector2());
    const draw = (pts, colour) => {
      for (let i = 0; i < pts.length; i += 6) {
        const g = new LineGeometry();
        g.setPositions(pts.slice(i, i + 6));
        const mat = new LineMaterial({ color: colour, linewidth: 4, depthTest: false });
        mat.resolution.copy(size);
        const line = new Line2(g, mat);
        line.renderOrder = 2;
        this.viewer.scene.add(line);
      }
    };
    draw(open, '#e6194b');
    draw(nonManifold, '#b000d0');
    this.problemEdges = { open: open.length / 6, nonManifold: nonManifold.length / 6 };
    const parts = [];
    if (open.length) parts.push(`${open.length / 6} edges on holes (red)`);
    if (nonManifold.length) parts.push(`${nonManifold.length / 6} edges shared by more than two faces (purple)`);
    this.say(parts.length ? `drawn through the surface: ${parts.join(', ')}` : 'no open or non-manifold edges: the finding is elsewhere (see the list)', !!parts.length);
    this.viewer.redraw();
  }
  lookAtSeeds() {
    const pts = SEEDS.filter((s) => this.landmarks.has(s)).map((s) => this.landmarks.get(s).pos);
    if (pts.length < 2) return;
    const c = this.geometry.boundingBox.getCenter(new THREE.Vector3()), d = new THREE.Vector3();
    for (const p of pts) d.add(p.clone().sub(c));
    if (d.length() < 1e-9 * this.viewer.radius) return;
    d.normalize();
    // from that side, a little from the front
    this.viewer.frame(this.geometry.boundingBox, d.clone().multiplyScalar(0.8).add(new THREE.Vector3(0.3, 0, 1).multiplyScalar(0.6)));
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
  // The landmarks as text, in a fixed order: what "unsaved" compares and what undo restores.
  serialize() {
    return JSON.stringify([...this.landmarks.entries()].map(([n, l]) => [n, l.face, l.bary]).sort((a, b) => (a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : 0)));
  }
  restore(text) {
    this.landmarks.clear();
    for (const [n, f, b] of JSON.parse(text)) this.set(n, f, b);
  }
  get unsaved() { return this.serialize() !== this.saved; }
  // One edit: remembered for undo, then drawn.
  edit(fn, msg) {
    const before = this.serialize();
    fn();
    if (this.serialize() === before) return;
    this.history.push(before);
    this.future = [];
    this.say(msg);
    this.changed();
  }
  undo() {
    if (!this.history.length) { this.say('nothing to undo'); return; }
    this.future.push(this.serialize());
    this.restore(this.history.pop());
    this.say('undone');
    this.changed();
  }
  redo() {
    if (!this.future.length) { this.say('nothing to redo'); return; }
    this.history.push(this.serialize());
    this.restore(this.future.pop());
    this.say('redone');
    this.changed();
  }
  startPlacing(name) {
    if (!name) { this.say('type the new feature\'s name first', true); return; }
    if (/^seed[4-9]|^seed\d\d/.test(name)) { this.say('there are four seeds, seed0 to seed3; give a feature another name', true); return; }
    this.placing = name;
    activeEditor = this;
    this.showPlacing();
  }
  showPlacing() {
    this.placeInfo.textContent = this.placing
      ? `click on the surface to ${this.landmarks.has(this.placing) ? 'move' : 'place'} ${this.placing} (Esc: stop)`
      : 'clicks change nothing: press a landmark\'s "place" button, or add a feature, then click on the surface; drag a marker to move it';
    this.placeInfo.classList.toggle('placing', !!this.placing);
    this.panel.dataset.placing = this.placing || '';
    for (const li of this.list.children) li.classList.toggle('selected', li.dataset.name === this.placing);
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
        // a marker under the pointer: it moves only once the pointer does (a click moves nothing)
        drag = { name: m.object.userData.name, before: this.serialize(), moved: false };
        this.viewer.controls.enabled = false;
        canvas.setPointerCapture(ev.pointerId);
      }
    });
    canvas.addEventListener('pointermove', (ev) => {
      if (!drag || !down) return;
      if (!drag.moved && Math.hypot(ev.clientX - down.x, ev.clientY - down.y) <= 4) return;
      const hit = this.pick(ev, [this.mesh]);
      if (!hit) return;
      drag.moved = true;
      const ref = this.hitToRef(hit);
      this.set(drag.name, ref.face, ref.bary);
      this.changed(false);
    });
    canvas.addEventListener('pointerup', (ev) => {
      const wasDrag = drag;
      drag = null;
      this.viewer.controls.enabled = true;
      if (wasDrag && wasDrag.moved) {
        if (this.serialize() !== wasDrag.before) { this.history.push(wasDrag.before); this.future = []; }
        this.say(`moved ${wasDrag.name}`);
        this.changed();
        down = null;
        return;
      }
      if (!down || Math.hypot(ev.clientX - down.x, ev.clientY - down.y) > 4) { down = null; return; }  // an orbit
      down = null;
      this.click(ev);
    });
  }
  click(ev) {
    const hit = this.pick(ev, [this.mesh]);
    if (!hit) { this.say('the click missed the surface: nothing placed', true); return; }
    const name = this.placing;
    if (!name) {
      this.say('nothing changed: choose a landmark to place first (its "place" button, or add a feature)');
      return;
    }
    const ref = this.hitToRef(hit);
    const moved = this.landmarks.has(name);
    this.edit(() => this.set(name, ref.face, ref.bary), `${moved ? 'moved' : 'placed'} ${name} on face ${ref.face}`);
    // Seeds go on to the next missing one; a feature, or the last seed, ends placing.
    this.placing = SEEDS.includes(name) ? SEEDS.find((s) => !this.landmarks.has(s)) || null : null;
    this.showPlacing();
  }
  // Labels of markers the surface hides (seen through the mesh) are hidden too.
  hideCoveredLabels() {
    // Ray casts cost a pass over every triangle per marker: while the view turns they wait (the
    // labels keep their state) and run once it stops.
    if (!this.mesh || this.turning) return;
    const cam = this.viewer.camera.position, ray = new THREE.Raycaster();
    for (const m of this.markers.values()) {
      const to = m.position.clone().sub(cam), d = to.length();
      ray.set(cam, to.normalize());
      ray.far = d;
      const hit = ray.intersectObject(this.mesh, false)[0];
      const covered = !!hit && hit.distance < d - 1.5 * this.markerRadius;
      m.userData.label.classList.toggle('covered', covered);
    }
  }
  // Labels that would overlap on the screen are moved down, one under the other.
  spreadLabels() {
    const shown = [...this.markers.values()].map((m) => m.userData.label)
      .filter((t) => !t.classList.contains('covered') && t.style.display !== 'none');
    for (const t of shown) t.style.marginTop = '0px';
    const boxes = shown.map((t) => ({ t, r: t.getBoundingClientRect() })).sort((a, b) => a.r.top - b.r.top || a.r.left - b.r.left);
    const placed = [];
    for (const b of boxes) {
      let top = b.r.top;
      for (const p of placed)
        if (b.r.left < p.right && p.left < b.r.right && top < p.bottom && p.top < top + b.r.height) top = p.bottom + 1;
      if (top !== b.r.top) b.t.style.marginTop = `${top - b.r.top}px`;
      placed.push({ left: b.r.left, right: b.r.right, top, bottom: top + b.r.height });
    }
  }
  // Redraws markers and the list; with `loop`, asks the server for the seed loop preview.
  changed(loop = true) {
    for (const m of this.markers.values()) { this.viewer.scene.remove(m); m.clear(); }
    this.markers.clear();
    this.list.replaceChildren();
    const names = [...new Set([...SEEDS, ...this.landmarks.keys()])].sort((a, b) => (SEEDS.includes(a) ? SEEDS.indexOf(a) - 10 : 0) - (SEEDS.includes(b) ? SEEDS.indexOf(b) - 10 : 0) || a.localeCompare(b));
    for (const name of names) {
      const l = this.landmarks.get(name);
      const colour = SEEDS.includes(name) ? SEED_COLOURS[SEEDS.indexOf(name)] : '#ff7f0e';
      if (l) {
        const m = new THREE.Mesh(new THREE.SphereGeometry(this.markerRadius, 16, 12), new THREE.MeshBasicMaterial({ color: colour }));
        m.position.copy(l.pos);
        m.userData.name = name;
        const tag = el('span', { className: 'label3d', textContent: name });
        const label = new CSS2DObject(tag);
        label.position.set(0, this.markerRadius * 1.8, 0);
        m.add(label);
        m.userData.label = tag;
        this.viewer.scene.add(m);
        this.markers.set(name, m);
      }
      const place = el('button', { textContent: l ? 'move' : 'place', className: 'place', title: `the next click on the surface ${l ? 'moves' : 'places'} ${name}` });
      place.onclick = () => this.startPlacing(name);
      const li = el('li', {}, el('span', { className: 'swatch', style: `background:${colour}` }));
      if (l) {
        const rename = el('input', { value: name, title: 'rename' });
        rename.onchange = () => this.rename(name, rename.value.trim());
        if (SEEDS.includes(name)) rename.disabled = true;
        const del = el('button', { textContent: 'delete', className: 'delete' });
        del.onclick = () => this.edit(() => this.landmarks.delete(name), `deleted ${name}`);
        li.append(rename, place, el('span', { className: 'hint', textContent: `face ${l.face}` }), del);
      } else {
        li.classList.add('missing');
        li.append(el('span', { className: 'lm-name', textContent: name }), place, el('span', { className: 'hint', textContent: 'not placed' }));
      }
      li.dataset.name = name;
      this.list.append(li);
    }
    refreshFeatureNames();
    this.showPlacing();
    this.undoBtn.disabled = !this.history.length;
    this.redoBtn.disabled = !this.future.length;
    const unsaved = this.unsaved;
    this.unsavedMark.classList.toggle('hidden', !unsaved);
    this.panel.classList.toggle('unsaved', unsaved);
    markUnsavedInList();
    this.viewer.redraw();
    if (loop) this.previewLoop();
  }
  rename(from, to) {
    if (!to || to === from) return this.changed(false);
    if (this.landmarks.has(to)) { this.say(`there is already a landmark named ${to}`, true); return this.changed(false); }
    if (SEEDS.includes(to)) { this.say('seed0..seed3 are the seeds: give the feature another name', true); return this.changed(false); }
    this.edit(() => { const l = this.landmarks.get(from); this.landmarks.delete(from); this.set(to, l.face, l.bary); }, `renamed ${from} to ${to}`);
  }
  toJSON() {
    const seeds = SEEDS.filter((s) => this.landmarks.has(s));
    const out = {};
    // No "seeds" key without all four: the tools then choose them automatically.
    if (seeds.length === 4) out.seeds = SEEDS.map((s) => ({ face: this.landmarks.get(s).face, bary: this.landmarks.get(s).bary }));
    out.features = {};
    for (const [name, l] of this.landmarks) if (!SEEDS.includes(name)) out.features[name] = { face: l.face, bary: l.bary };
    return { body: out, seedCount: seeds.length };
  }
  async previewLoop() {
    for (const l of this.loopLines) this.viewer.scene.remove(l);
    this.loopLines = [];
    const { body, seedCount } = this.toJSON();
    if (seedCount !== 4) {
      this.loopOk = undefined;
      this.loopStatus.textContent = seedCount ? `seed loop: ${4 - seedCount} seed${seedCount === 3 ? '' : 's'} still to place` : 'no seeds: a run chooses them automatically (for shapes in similar poses)';
      this.loopStatus.className = 'status loop-status';
      this.viewer.redraw();
      return;
    }
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
      this.loopStatus.textContent = `seed loop: length ${r.length.toPrecision(4)} (drawn as qs-dissect routes it)`;
      this.loopStatus.className = 'status loop-status ok';
    } catch (e) {
      if (ticket !== this.loopTicket) return;
      this.loopOk = false;
      this.loopStatus.textContent = e.message;
      this.loopStatus.className = 'status loop-status error';
    }
    this.viewer.redraw();
  }
  async save() {
    const { body, seedCount } = this.toJSON();
    if (seedCount !== 0 && seedCount !== 4) {
      const missing = SEEDS.filter((s) => !this.landmarks.has(s));
      this.say(`not saved: place all four seeds or none (${seedCount} placed). Press "place" beside ${missing.join(', ')} and click on the surface, `
        + 'or delete the placed seeds to let qs choose them automatically', true);
      return false;
    }
    let r;
    this.say('saving…');
    try {
      r = await postJSON(`/api/landmarks?name=${encodeURIComponent(this.name)}`, body);
    } catch (e) {
      this.say(`not saved: ${e.message}`, true);
      return false;
    }
    this.saved = this.serialize();
    this.changed(false);
    // The mesh list shows the saved file before the editor says "saved"; a list that cannot be
    // reloaded does not undo the save.
    let listed = '';
    try {
      await loadMeshes();
    } catch (e) {
      listed = ` (the mesh list was not reloaded: ${e.message})`;
    }
    this.say(`saved ${r.file}: ${r.seeds} seeds${r.seeds ? '' : ' (chosen automatically in a run)'}, ${r.features} feature${r.features === 1 ? '' : 's'}${listed}`, !!listed);
    return true;
  }
}

function refreshFeatureNames() {
  let dl = $('feature-names');
  if (!dl) { dl = el('datalist', { id: 'feature-names' }); document.body.append(dl); }
  dl.replaceChildren(...[...knownFeatures].sort().map((n) => el('option', { value: n })));
}
function markUnsavedInList() {
  for (const li of $('meshes').children) {
    const ed = editors.find((e) => e.name === li.dataset.mesh && !e.inspectOnly);
    const unsaved = !!ed && ed.unsaved;
    li.classList.toggle('unsaved', unsaved);
    const mark = li.querySelector('.unsaved-mark');
    if (mark) mark.classList.toggle('hidden', !unsaved);
  }
  updateRunReadiness();
}

async function openEditor(name, inspectOnly = false) {
  showTab('edit');
  if (editors.find((e) => e.name === name)) return;
  $('edit-empty').classList.add('hidden');
  const ed = new Editor(name, inspectOnly);
  editors.push(ed);
  activeEditor = ed;
  await ed.load().catch((e) => ed.say(`cannot open ${name}: ${e.message}`, true));
  ed.viewer.linkable = true;
  ed.ready = true;
  saveSettings();
}
function closeEditor(ed, ask = true) {
  if (ask && !ed.inspectOnly && ed.unsaved && !window.confirm(`${ed.name} has landmark edits that are not saved. Close it and lose them?`)) return false;
  editors.splice(editors.indexOf(ed), 1);
  if (activeEditor === ed) activeEditor = editors[editors.length - 1] || null;
  ed.viewer.dispose();
  ed.panel.remove();
  if (!editors.length) $('edit-empty').classList.remove('hidden');
  markUnsavedInList();
  saveSettings();
  return true;
}
document.addEventListener('keydown', (ev) => {
  const typing = ev.target instanceof HTMLInputElement || ev.target instanceof HTMLTextAreaElement || ev.target instanceof HTMLSelectElement;
  const ed = activeEditor && editors.includes(activeEditor) && !activeEditor.inspectOnly ? activeEditor : null;
  if (!ed || typing || $('edit').classList.contains('hidden')) return;
  const key = ev.key.toLowerCase();
  if ((ev.ctrlKey || ev.metaKey) && key === 'z') { ev.preventDefault(); ev.shiftKey ? ed.redo() : ed.undo(); }
  else if ((ev.ctrlKey || ev.metaKey) && key === 'y') { ev.preventDefault(); ed.redo(); }
  else if (key === 'escape' && ed.placing) { ed.placing = null; ed.showPlacing(); }
});
// Unsaved landmark edits: the browser asks before a reload or closing the tab.
window.addEventListener('beforeunload', (ev) => {
  if (editors.some((e) => !e.inspectOnly && e.unsaved)) { ev.preventDefault(); ev.returnValue = ''; }
});

// ---------------------------------------------------------------------------------------------
// Settings kept across reloads (per folder): ticked meshes, run options, open meshes, result view.
let folderName = '';
const settingsKey = () => `qs-studio:${folderName}`;
function saveSettings() {
  if (!folderName || !settingsLoaded) return;
  const s = { ticked, level: $('level').value, bakeSize: $('bake-size').value, maxArea: $('max-area').value,
    rmode: document.querySelector('input[name=rmode]:checked').value, run: $('runs').value, open: editors.map((e) => [e.name, e.inspectOnly]) };
  try { localStorage.setItem(settingsKey(), JSON.stringify(s)); } catch { /* storage full or off: settings are not kept */ }
}
let settingsLoaded = false;
function loadSettings() {
  let s = null;
  try { s = JSON.parse(localStorage.getItem(settingsKey()) || 'null'); } catch { s = null; }
  settingsLoaded = true;
  if (!s || typeof s !== 'object') return null;
  const pick = (sel, v) => { if (v !== undefined && [...$(sel).options].some((o) => o.value === String(v))) $(sel).value = String(v); };
  pick('level', s.level);
  pick('bake-size', s.bakeSize);
  if (s.maxArea !== undefined && isFinite(+s.maxArea)) $('max-area').value = s.maxArea;
  if (s.rmode) { const r = document.querySelector(`input[name=rmode][value="${CSS.escape(String(s.rmode))}"]`); if (r) r.checked = true; }
  if (Array.isArray(s.ticked)) ticked = s.ticked.filter((n) => typeof n === 'string');
  return s;
}
for (const id of ['level', 'bake-size', 'max-area']) $(id).addEventListener('change', saveSettings);

// ---------------------------------------------------------------------------------------------
// Mesh list, upload and delete.
let ticked = [];
let meshList = [];
async function loadMeshes() {
  const r = await api('/api/meshes');
  folderName = r.folder;
  $('folder').textContent = r.folder;
  meshList = r.meshes;
  const ul = $('meshes');
  ul.replaceChildren();
  ticked = ticked.filter((n) => r.meshes.some((m) => m.name === n && m.accepted));
  for (const m of r.meshes) {
    const tick = el('input', { type: 'checkbox', checked: ticked.includes(m.name), disabled: !m.accepted, className: 'tick' });
    tick.onchange = () => { ticked = tick.checked ? [...ticked, m.name] : ticked.filter((n) => n !== m.name); showTicked(); saveSettings(); };
    const open = el('button', { textContent: m.accepted ? 'open' : 'show', className: 'open', disabled: !m.read,
      title: m.accepted ? 'place landmarks' : 'see where the problem is' });
    open.onclick = () => openEditor(m.name, !m.accepted);
    const del = el('button', { textContent: 'delete', className: 'delete-mesh', title: `remove ${m.name} from the folder` });
    del.onclick = () => deleteMesh(m.name);
    const li = el('li', {}, tick, ' ', el('span', { className: 'name', textContent: m.name }), ' ',
      el('span', { className: 'badge ' + (m.accepted ? 'ok' : 'bad'), textContent: m.accepted ? 'ready' : 'rejected' }), ' ',
      el('span', { className: 'badge unsaved-mark hidden', textContent: 'unsaved edits' }), ' ', open, ' ', del,
      el('div', { className: 'summary', textContent: m.summary }));
    li.dataset.mesh = m.name;
    if (m.landmarks) {
      li.append(el('div', {
        className: 'hint lm', textContent: m.landmarks.error ? `landmarks ${m.landmarks.file}: ${m.landmarks.error}`
          : `landmarks: ${m.landmarks.file}` + (m.landmarks.seeds !== undefined ? ` (${m.landmarks.seeds} seeds${m.landmarks.seeds ? '' : ': automatic'}, ${m.landmarks.features} features)` : ''),
      }));
    } else if (m.accepted) li.append(el('div', { className: 'hint lm', textContent: 'no landmarks (seeds chosen automatically)' }));
    if (m.problems.length) {
      li.append(el('ul', { className: 'problems' }, ...m.problems.map((p) => el('li', { className: p.severity, textContent: p.plain },
        el('span', { className: 'tech', textContent: p.message })))));
    }
    ul.append(li);
  }
  markUnsavedInList();
  showTicked();
  return r;
}
async function deleteMesh(name) {
  const ed = editors.find((e) => e.name === name);
  if (!window.confirm(`Remove ${name} from the folder? (Its landmark file stays.)`)) return;
  if (ed && !closeEditor(ed)) return;
  const st = $('upload-status');
  try {
    await api(`/api/meshes?name=${encodeURIComponent(name)}`, { method: 'DELETE' });
    st.textContent = `removed ${name}`; st.className = 'status ok';
  } catch (e) {
    st.textContent = `${name} not removed: ${e.message}`; st.className = 'status error';
  }
  await loadMeshes();
}
function showTicked() {
  $('run-meshes').textContent = ticked.length ? `run on: ${ticked.join(', ')}` : 'no mesh ticked';
  updateRunReadiness();
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
// The landmark template of the ticked set: every name once, what each mesh lacks; the reasons a
// run cannot start yet (shown beside the disabled button).
let runGoing = false;
function runBlockers() {
  const why = [];
  if (runGoing) return ['a run is going (cancel it or wait)'];
  if (!ticked.length) return ['tick the meshes to run'];
  const meshes = ticked.map((n) => meshList.find((m) => m.name === n)).filter(Boolean);
  const unsaved = editors.filter((e) => ticked.includes(e.name) && !e.inspectOnly && e.unsaved).map((e) => e.name);
  if (unsaved.length) why.push(`save the landmarks of ${unsaved.join(', ')} first (a run reads the saved files)`);
  for (const m of meshes) if (m.landmarks && m.landmarks.error) why.push(`${m.name}: its landmark file cannot be used (${m.landmarks.error})`);
  const seeds = (m) => (m.landmarks && !m.landmarks.error ? m.landmarks.seeds || 0 : 0);
  const feats = (m) => (m.landmarks && !m.landmarks.error ? m.landmarks.feature_names || [] : []);
  if (meshes.length > 1) {
    const withSeeds = meshes.filter((m) => seeds(m) === 4), without = meshes.filter((m) => seeds(m) !== 4);
    if (withSeeds.length && without.length)
      why.push(`seeds correspond by order, so every mesh needs them or none: ${without.map((m) => m.name).join(', ')} ${without.length > 1 ? 'have' : 'has'} none `
        + `(place them, or delete the seeds of ${withSeeds.map((m) => m.name).join(', ')})`);
    const all = [...new Set(meshes.flatMap(feats))].sort();
    for (const m of meshes) {
      const lacks = all.filter((f) => !feats(m).includes(f));
      if (lacks.length) why.push(`${m.name} lacks the feature${lacks.length > 1 ? 's' : ''} ${lacks.join(', ')} (features correspond by name)`);
    }
  }
  return why;
}
function updateRunReadiness() {
  const why = runBlockers();
  $('run-btn').disabled = why.length > 0;
  $('run-btn').title = why.join('; ');
  $('run-why').textContent = why.length && ticked.length && !runGoing ? `Run is disabled: ${why.join('; ')}` : '';
  document.body.dataset.runBlocked = why.length ? '1' : '0';
  // the template: rows = landmark names, columns = ticked meshes
  const meshes = ticked.map((n) => meshList.find((m) => m.name === n)).filter(Boolean);
  const t = $('template');
  t.replaceChildren();
  if (meshes.length < 1) return;
  const seeds = (m) => (m.landmarks && !m.landmarks.error ? m.landmarks.seeds || 0 : 0);
  const feats = (m) => (m.landmarks && !m.landmarks.error ? m.landmarks.feature_names || [] : []);
  const names = [...(meshes.some((m) => seeds(m) === 4) ? SEEDS : []), ...[...new Set(meshes.flatMap(feats))].sort()];
  if (!names.length) { t.append(el('tr', {}, el('td', { className: 'hint', textContent: 'no landmarks: seeds chosen automatically on each mesh' }))); return; }
  t.append(el('tr', {}, el('th', { textContent: 'landmark' }), ...meshes.map((m) => el('th', { textContent: m.name.replace(/\.[^.]+$/, '') }))));
  for (const n of names) {
    t.append(el('tr', {}, el('td', { textContent: n }), ...meshes.map((m) => {
      const has = SEEDS.includes(n) ? seeds(m) === 4 : feats(m).includes(n);
      return el('td', { className: has ? 'has' : 'lacks', textContent: has ? '✓' : 'missing' });
    })));
  }
}

// ---------------------------------------------------------------------------------------------
// Runs.
let polling = null;
let shownProgress = { run: '', value: 0 };
const progressSeen = [];  // every overall progress value the server sent during runs (for the tests)
function clearRunPanel() {
  $('stages').replaceChildren();
  $('progress').value = 0;
  $('phase').textContent = '';
  $('log').textContent = '';
  $('verdict').textContent = '';
  $('verdict').className = '';
  $('warnings').replaceChildren();
}
$('run-btn').onclick = async () => {
  const why = runBlockers();
  clearRunPanel();
  if (why.length) { $('run-error').textContent = why.join('\n'); return; }
  $('run-error').textContent = '';
  try {
    await postJSON('/api/run', { meshes: ticked, level: +$('level').value, bake_size: +$('bake-size').value, max_area: +$('max-area').value || 0 });
    pollRun();
  } catch (e) {
    // a refused run: no stage of an earlier run stays beside its error
    $('run-error').textContent = e.message;
    document.body.dataset.run = 'refused';
  }
};
$('cancel-btn').onclick = async () => {
  $('cancel-btn').disabled = true;
  try { await api('/api/run/cancel', { method: 'POST' }); } catch (e) { $('run-error').textContent = e.message; }
  pollRun();
};
const seconds = (s) => (s < 60 ? `${Math.round(s)} s` : `${Math.floor(s / 60)} min ${Math.round(s % 60)} s`);
async function pollRun() {
  clearTimeout(polling);
  const s = await api('/api/run');
  const ol = $('stages');
  ol.replaceChildren(...s.stages.map((st) => el('li', { className: st.status, textContent: `${st.name}: ${st.status}` + (st.exit_code > 0 ? ` (exit ${st.exit_code})` : '') })));
  if (s.status === 'running') progressSeen.push(s.progress);
  // one bar for the whole run, never moving back
  if (shownProgress.run !== s.name) shownProgress = { run: s.name, value: 0 };
  shownProgress.value = Math.max(shownProgress.value, s.progress);
  $('progress').value = shownProgress.value;
  $('phase').textContent = s.status === 'running'
    ? `${s.phase || 'starting'}: ${Math.floor(100 * shownProgress.value)}%, ${seconds(s.elapsed_s)} so far` + (s.eta_s >= 0 ? `, about ${seconds(s.eta_s)} left` : '')
    : s.status === 'idle' ? '' : `${s.status} after ${seconds(s.elapsed_s)}`;
  $('log').textContent = s.log;
  $('log').scrollTop = 1e9;
  $('run-error').textContent = s.error;
  runGoing = s.status === 'running';
  $('cancel-btn').classList.toggle('hidden', !runGoing);
  $('cancel-btn').disabled = !runGoing;
  updateRunReadiness();
  showVerdict(s.status === 'done' ? s.verdict : s.status, s.warnings || [], $('verdict'), $('warnings'));
  if (runGoing) { document.body.dataset.run = s.status; polling = setTimeout(pollRun, 300); return; }
  if (s.status === 'done') { await loadRuns(s.name); showTab('results'); }
  // published last, so that whoever waits for "done" finds the results tab already shown
  document.body.dataset.run = s.status;
  document.body.dataset.verdict = s.status === 'done' ? s.verdict : s.status;
}
function showVerdict(verdict, warnings, box, list) {
  const words = { 'done': 'done', 'done with warnings': 'done with warnings', failed: 'failed', cancelled: 'cancelled' };
  box.textContent = words[verdict] || '';
  box.className = 'verdict ' + (verdict === 'done' ? 'ok' : verdict === 'done with warnings' ? 'warn' : verdict ? 'bad' : '');
  list.replaceChildren(...warnings.map((w) => el('li', { textContent: w })));
}

let runList = [];
async function loadRuns(select) {
  runList = (await api('/api/runs')).runs;
  const sel = $('runs');
  sel.replaceChildren(...runList.map((r) => el('option', { value: r.name, textContent: `${r.name}: ${(r.run && r.run.meshes || []).join(', ')}`
    + (r.run && r.run.verdict === 'done with warnings' ? ' (warnings)' : '') })));
  if (runList.length) sel.value = select && runList.some((r) => r.name === select) ? select : runList[runList.length - 1].name;
  $('delete-run').disabled = !runList.length;
  showRun();
}
$('runs').onchange = () => { saveSettings(); showRun(); };
document.querySelectorAll('input[name=rmode]').forEach((r) => { r.onchange = () => { saveSettings(); showRun(); }; });
$('delete-run').onclick = async () => {
  const name = $('runs').value;
  if (!name || !window.confirm(`Delete ${name} and all its files?`)) return;
  try {
    await api(`/api/runs?name=${encodeURIComponent(name)}`, { method: 'DELETE' });
  } catch (e) {
    $('result-status').textContent = `${name} not deleted: ${e.message}`;
    return;
  }
  $('result-status').textContent = `deleted ${name}`;
  await loadRuns();
};

let resultViewers = [];
let colourByStretch = false;
const linkResults = linkViews(() => resultViewers, () => $('link-results').checked);
function currentRun() { return runList.find((r) => r.name === $('runs').value); }
async function showRun() {
  for (const v of resultViewers) v.dispose();
  resultViewers = [];
  $('result-controls').replaceChildren();
  const run = currentRun();
  $('result-empty').classList.toggle('hidden', !!run);
  $('downloads').replaceChildren();
  $('archive').classList.toggle('hidden', !run);
  showVerdict(run && run.run ? run.run.verdict || '' : '', run && run.run ? run.run.warnings || [] : [], $('result-verdict'), $('result-warnings'));
  document.body.dataset.resultsReady = '0';
  if (!run) return;
  $('archive').href = `/api/run-archive?name=${encodeURIComponent(run.name)}`;
  $('archive').textContent = `all files of ${run.name} (.tar)`;
  for (const f of run.files) {
    $('downloads').append(el('li', {}, el('a', { href: `/files/${f.path}?download=1`, textContent: f.path.split('/').slice(2).join('/') || f.path, download: '' }),
      el('span', { className: 'hint', textContent: ` ${(f.bytes / 1024).toFixed(0)} KiB` })));
  }
  const mode = document.querySelector('input[name=rmode]:checked').value;
  const files = run.files.map((f) => f.path);
  const stems = (run.run ? run.run.meshes : []).map((m) => m.replace(/\.[^.]+$/, ''));
  const addView = (title, wide = false) => {
    const view = el('div', { className: 'view' });
    const panel = el('div', { className: 'panel result' + (wide ? ' wide' : '') }, el('div', { className: 'bar' }, el('b', { textContent: title })), view);
    $('result-views').append(panel);
    const v = new Viewer(view);
    v.panel = panel;
    const d = v.dispose.bind(v);
    v.dispose = () => { d(); panel.remove(); };
    v.linkable = false;  // its own first framing is not passed on
    v.controls.addEventListener('change', () => linkResults(v));
    resultViewers.push(v);
    return v;
  };
  // Seen in profile: across the longer horizontal side of the box (a quadruped from its side).
  const frame = (v, box) => {
    const size = box.getSize(new THREE.Vector3());
    v.box = box;
    v.frame(box, size.x >= size.z ? new THREE.Vector3(0.3, 0.3, 1) : new THREE.Vector3(1, 0.3, 0.3));
    v.linkable = true;
  };
  $('result-controls').append(...viewButtons(() => resultViewers));
  try {
    if (mode === 'patches' || mode === 'remesh') {
      const dir = mode === 'patches' ? 'dissection/' : `remesh-L${run.run.level}/`;
      const ext = mode === 'patches' ? '.chart.ply' : '.obj';
      const wire = mode === 'remesh' ? el('input', { type: 'checkbox', checked: true, id: 'result-wire' }) : null;
      if (wire) $('result-controls').append(el('label', {}, wire, ' wireframe'));
      // patches: coloured by patch or by each patch's stretch (dissection.json); hovering names one
      let report = null;
      const byStretch = mode === 'patches' ? el('input', { type: 'checkbox', id: 'result-stretch', checked: colourByStretch }) : null;
      if (byStretch) {
        const dj = files.find((f) => f.endsWith('/dissection/dissection.json'));
        if (dj) report = await api(`/files/${dj}`);
        const tau = report && report.options ? report.options.tau : 3;
        $('result-controls').append(el('label', { title: 'each patch coloured by its L2 stretch (1: no distortion)' }, byStretch, ' colour by stretch'),
          el('span', { className: 'hint stretch-legend', textContent: ` green 1 · yellow tau ${tau} · red ${3 * tau} and over` }));
        byStretch.onchange = () => { colourByStretch = byStretch.checked; showRun(); };
      }
      const views = stems.map((stem) => {
        const path = files.find((f) => f.endsWith(dir + stem + ext));
        return path ? [stem, path, addView(`${stem}: ${mode === 'patches' ? 'common patches' : `level-${run.run.level} remesh`}`)] : null;
      }).filter(Boolean);
      await Promise.all(views.map(async ([, path, v]) => {
        const data = await api(`/api/mesh?path=${encodeURIComponent(path)}`);
        const info = report && (report.meshes || []).find((m) => path.endsWith('/' + m.chart));
        const tau = report && report.options ? report.options.tau : 3;
        const stretchColour = (st, c) => {  // 1 -> green, tau -> yellow, 3 tau and over -> red (log scale)
          const t = Math.min(1, Math.max(0, Math.log(Math.max(st, 1)) / Math.log(3 * tau)));
          return c.setHSL((1 - t) * 0.33, 0.8, 0.5);
        };
        const colour = mode !== 'patches' ? null : colourByStretch && info
          ? (f, c) => stretchColour(info.patches[data.patch[f]].stretch, c) : (f, c) => patchColour(data.patch[f], c);
        const g = colour ? geometryOf(data, colour) : geometryOf(data);
        const mat = new THREE.MeshStandardMaterial({ color: mode === 'patches' ? 0xffffff : 0xd0d0d0, vertexColors: mode === 'patches', roughness: 0.85, flatShading: mode === 'patches', polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
        const surface = new THREE.Mesh(g, mat);
        v.scene.add(surface);
        if (mode === 'patches') {
          v.panel.querySelector('.bar').append(el('span', { className: 'hint', textContent: `${data.patches} patches, ${data.faces.length / 3} faces` }));
          const hover = el('span', { className: 'hover-patch' });
          v.panel.querySelector('.bar').append(hover);
          const canvas = v.renderer.domElement, ray = new THREE.Raycaster();
          canvas.addEventListener('pointermove', (ev) => {
            const r = canvas.getBoundingClientRect();
            ray.setFromCamera(new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1), v.camera);
            const hit = ray.intersectObject(surface, false)[0];
            const p = hit ? data.patch[hit.faceIndex] : -1;
            const pi = info && p >= 0 ? info.patches[p] : null;
            hover.textContent = p < 0 ? '' : `patch ${pi ? pi.name : p}` + (pi ? `: stretch ${pi.stretch.toFixed(2)}, ${pi.faces} faces${pi.stop_reason ? `, left over tau (${pi.stop_reason})` : ''}` : '');
          });
        }
        else {
          const lines = new THREE.LineSegments(new THREE.WireframeGeometry(g), new THREE.LineBasicMaterial({ color: 0x1a3d6b }));
          v.scene.add(lines);
          wire.addEventListener('change', () => { lines.visible = wire.checked; v.redraw(); });
          v.panel.querySelector('.bar').append(el('span', { className: 'hint', textContent: `${data.positions.length / 3} vertices, ${data.faces.length / 3} faces (one face list for all)` }));
        }
        frame(v, g.boundingBox);
      }));
    } else if (mode === 'bake') {
      const mapBox = el('input', { type: 'checkbox', checked: true, id: 'result-map' });
      $('result-controls').append(el('label', {}, mapBox, ' normal map'));
      const views = stems.map((stem) => {
        const path = files.find((f) => f.endsWith('bake/' + stem + '.glb'));
        return path ? [path, addView(`${stem}: the remesh with its baked normal map`)] : null;
      }).filter(Boolean);
      await Promise.all(views.map(async ([path, v]) => {
        const gltf = await new GLTFLoader().loadAsync(`/files/${path}`);
        const maps = [];
        let faces = 0;
        gltf.scene.traverse((o) => { if (o.isMesh) { faces += o.geometry.index ? o.geometry.index.count / 3 : 0; if (o.material.normalMap) maps.push([o.material, o.material.normalMap]); } });
        v.panel.querySelector('.bar').append(el('span', { className: 'hint', textContent: `${faces} faces` }));
        mapBox.addEventListener('change', () => { for (const [m, t] of maps) { m.normalMap = mapBox.checked ? t : null; m.needsUpdate = true; } v.redraw(); });
        v.scene.add(gltf.scene);
        frame(v, new THREE.Box3().setFromObject(gltf.scene));
      }));
    } else if (mode === 'morph') {
      const path = files.find((f) => f.endsWith('/morph.glb'));
      if (!path) { $('result-controls').append(el('span', { className: 'hint', textContent: 'no morph in this run (it needs two meshes or more)' })); }
      else {
        const v = addView('morph: one target per shape, the path animation', true);
        const gltf = await new GLTFLoader().loadAsync(`/files/${path}`);
        let mesh = null;
        gltf.scene.traverse((o) => { if (o.isMesh && o.morphTargetInfluences && !mesh) mesh = o; });
        v.scene.add(gltf.scene);
        // framed on the base shape's own positions, with room for the targets (placed on it by a similarity)
        gltf.scene.updateMatrixWorld(true);
        const box = new THREE.Box3().setFromBufferAttribute(mesh.geometry.attributes.position).applyMatrix4(mesh.matrixWorld);
        frame(v, box.expandByScalar(box.getSize(new THREE.Vector3()).length() * 0.04));
        const names = (mesh.geometry.userData.targetNames || mesh.userData.targetNames || (gltf.parser.json.meshes[0].extras || {}).targetNames || []);
        const sliders = mesh.morphTargetInfluences.map((_, i) => {
          const s = el('input', { type: 'range', min: 0, max: 1, step: 0.01, value: 0, className: 'morph-slider' });
          s.oninput = () => { play.checked = false; v.playing = false; mesh.morphTargetInfluences[i] = +s.value; v.redraw(); };
          $('result-controls').append(el('label', { className: 'slider' }, el('span', { className: 'slider-name', textContent: names[i] || `target ${i}` }), s));
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
  editors, openEditor, loadMeshes, showTab, progressSeen, runBlockers, pollRun,
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
  // Whether landmark `name`'s label is shown when the camera looks at vertex v along its normal
  // (sign 1: from outside) or against it (sign -1: from the other side of the shape).
  labelShown(mesh, name, v, sign) {
    const ed = editors.find((e) => e.name === mesh);
    const p = new THREE.Vector3().fromBufferAttribute(ed.geometry.attributes.position, v);
    const n = new THREE.Vector3().fromBufferAttribute(ed.geometry.attributes.normal, v).normalize();
    const vw = ed.viewer;
    vw.controls.target.copy(p);
    vw.camera.position.copy(p).addScaledVector(n, sign * vw.radius * 2.5);
    vw.controls.update();
    vw.dirty = false;
    vw.renderer.render(vw.scene, vw.camera);
    ed.hideCoveredLabels();
    vw.labels.render(vw.scene, vw.camera);
    const tag = ed.markers.get(name).userData.label;
    return !tag.classList.contains('covered') && getComputedStyle(tag).visibility !== 'hidden';
  },
  frameFront(mesh, dir) {
    const ed = editors.find((e) => e.name === mesh);
    ed.viewer.frame(ed.geometry.boundingBox, new THREE.Vector3(...dir));
  },
  // Draws editor i at once (as the next frame would), labels included.
  renderNow(i) {
    const ed = editors[i], vw = ed.viewer;
    vw.dirty = false;
    vw.renderer.render(vw.scene, vw.camera);
    ed.hideCoveredLabels();
    vw.labels.render(vw.scene, vw.camera);
    ed.spreadLabels();
  },
  resultCameras() { return resultViewers.map((v) => v.camera.position.clone().sub(v.controls.target).normalize().toArray()); },
  turnResult(i, dir) {
    const v = resultViewers[i], d = v.camera.position.distanceTo(v.controls.target);
    v.camera.position.copy(v.controls.target).addScaledVector(new THREE.Vector3(...dir).normalize(), d);
    v.controls.update();
  },
  cameraOf(i) { const v = editors[i].viewer; return v.camera.position.clone().sub(v.controls.target).normalize().toArray(); },
};

Promise.all([loadMeshes(), loadRuns()]).then(async () => {
  const saved = loadSettings();
  await loadMeshes();
  if (saved && saved.run && runList.some((r) => r.name === saved.run)) { $('runs').value = saved.run; await showRun(); }
  if (saved && Array.isArray(saved.open))
    for (const [n, inspect] of saved.open) if (meshList.some((m) => m.name === n && m.read)) await openEditor(n, !!inspect);
  const s = await api('/api/run');
  if (s.status === 'running') pollRun();
  document.body.dataset.ready = '1';
}).catch((e) => { document.body.append(el('pre', { className: 'error', textContent: e.message })); });
