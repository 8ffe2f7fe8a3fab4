// Renders one model once and reports back through window.__glbView (see render.mjs).
// Query string: model=<url> (.glb/.gltf or .obj), w, h, view=x,y,z (towards the camera), up=x,y,z,
// weights=a,b,... (morph target weights), time=t (seconds into animation 0; overrides weights),
// nomap=1 (material.normalMap = null), fit=current|all, persp=1, flat=1 or normals=angle (OBJ), label=text, bg=#rrggbb.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { mergeVertices } from 'three/addons/utils/BufferGeometryUtils.js';

const q = new URLSearchParams(location.search);
const vec = (s, d) => {
  if (!s) return new THREE.Vector3(...d);
  const a = s.split(',').map(Number);
  if (a.length !== 3 || a.some((x) => !Number.isFinite(x))) throw new Error(`bad vector '${s}'`);
  return new THREE.Vector3(...a);
};
// Vertex normals weighted by the corner angles (as qs-bake's "original normals"); three.js's
// computeVertexNormals weights by face area.
function angleWeightedNormals(g) {
  const pos = g.attributes.position, idx = g.index.array, n = new Float32Array(pos.count * 3);
  const p = [new THREE.Vector3(), new THREE.Vector3(), new THREE.Vector3()];
  const e1 = new THREE.Vector3(), e2 = new THREE.Vector3(), fn = new THREE.Vector3();
  for (let f = 0; f < idx.length; f += 3) {
    for (let k = 0; k < 3; k++) p[k].fromBufferAttribute(pos, idx[f + k]);
    fn.subVectors(p[1], p[0]).cross(e1.subVectors(p[2], p[0])).normalize();
    for (let k = 0; k < 3; k++) {
      e1.subVectors(p[(k + 1) % 3], p[k]); e2.subVectors(p[(k + 2) % 3], p[k]);
      const ang = e1.angleTo(e2);
      if (!Number.isFinite(ang)) continue;
      for (let c = 0; c < 3; c++) n[3 * idx[f + k] + c] += ang * fn.getComponent(c);
    }
  }
  g.setAttribute('normal', new THREE.BufferAttribute(n, 3));
  g.normalizeNormals();
}
const finish = (r) => { window.__glbView = r; document.title = r.ok ? 'done' : 'error'; };

async function main() {
  const W = +q.get('w') || 512, Hpage = +q.get('h') || W;
  // A caption gets its own band under the picture, so it never covers the model.
  const H = q.get('label') ? Math.max(16, Hpage - 26) : Hpage;
  document.body.style.background = q.get('bg') || '#ffffff';
  const viewDir = vec(q.get('view'), [0.3, 0.4, 1]).normalize();
  let up = vec(q.get('up'), [0, 1, 0]);
  const model = q.get('model');
  document.getElementById('label').textContent = q.get('label') || '';
  const info = { warnings: [] };

  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(W, H);
  renderer.setClearColor(new THREE.Color(q.get('bg') || '#ffffff'), 1);
  document.body.appendChild(renderer.domElement);
  const gl = renderer.getContext();
  const dbg = gl.getExtension('WEBGL_debug_renderer_info');
  info.gl = dbg ? gl.getParameter(dbg.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);

  const scene = new THREE.Scene();
  let root, gltf = null;
  if (/\.obj$/i.test(model)) {
    root = await new OBJLoader().loadAsync(model);
    const mat = new THREE.MeshStandardMaterial({ metalness: 0, roughness: 0.6 });
    mat.color.setRGB(0.8, 0.8, 0.8, THREE.LinearSRGBColorSpace); // as qs-bake's GLB material
    root.traverse((o) => {
      if (!o.isMesh) return;
      let g = o.geometry;
      g.deleteAttribute('normal'); g.deleteAttribute('uv');
      if (q.get('flat') === '1') g.computeVertexNormals();
      else { g = mergeVertices(g); if (q.get('normals') === 'angle') angleWeightedNormals(g); else g.computeVertexNormals(); }
      o.geometry = g;
      o.material = mat;
    });
  } else {
    gltf = await new GLTFLoader().loadAsync(model);
    root = gltf.scene;
  }
  scene.add(root);
  root.updateMatrixWorld(true);

  const meshes = [];
  root.traverse((o) => { if (o.isMesh) meshes.push(o); });
  if (!meshes.length) throw new Error('no mesh in the model');

  // Morph weights or animation time.
  const weights = q.get('weights') ? q.get('weights').split(',').map(Number) : null;
  if (weights && weights.some((x) => !Number.isFinite(x))) throw new Error(`bad weights '${q.get('weights')}'`);
  const time = q.get('time') !== null && q.get('time') !== '' ? Number(q.get('time')) : null;
  if (time !== null) {
    if (!gltf || !gltf.animations.length) throw new Error('--time given but the model has no animation');
    const mixer = new THREE.AnimationMixer(root);
    mixer.clipAction(gltf.animations[0]).play();
    mixer.setTime(time);
    info.animation = { name: gltf.animations[0].name, duration: gltf.animations[0].duration, time };
  } else if (weights) {
    for (const m of meshes) {
      if (!m.morphTargetInfluences) { info.warnings.push(`mesh '${m.name}' has no morph targets; weights ignored`); continue; }
      if (weights.length !== m.morphTargetInfluences.length)
        throw new Error(`${weights.length} weights given, mesh '${m.name}' has ${m.morphTargetInfluences.length} morph targets`);
      weights.forEach((w, i) => { m.morphTargetInfluences[i] = w; });
    }
  }

  if (q.get('nomap') === '1')
    for (const m of meshes) { m.material.normalMap = null; m.material.needsUpdate = true; }

  // Report what the viewer sees, per mesh.
  info.meshes = meshes.map((m) => {
    const g = m.geometry, mat = m.material;
    const r = {
      name: m.name, vertices: g.attributes.position.count,
      triangles: g.index ? g.index.count / 3 : g.attributes.position.count / 3,
      attributes: Object.keys(g.attributes),
      morphTargets: g.morphAttributes.position ? g.morphAttributes.position.length : 0,
      morphTargetsRelative: g.morphTargetsRelative,
      influences: m.morphTargetInfluences ? Array.from(m.morphTargetInfluences) : null,
      material: mat.type, side: mat.side, color: mat.color.toArray(),
      metalness: mat.metalness, roughness: mat.roughness,
      normalMap: mat.normalMap ? {
        size: [mat.normalMap.image.width, mat.normalMap.image.height],
        flipY: mat.normalMap.flipY, colorSpace: mat.normalMap.colorSpace,
        normalScale: mat.normalScale.toArray(),
      } : null,
      worldDeterminant: m.matrixWorld.determinant(),
    };
    if (m.matrixWorld.determinant() < 0) info.warnings.push(`mesh '${m.name}' has a mirroring transform`);
    return r;
  });

  // Camera basis: back = view direction, right = up x back.
  if (Math.abs(up.clone().normalize().dot(viewDir)) > 0.999) up = new THREE.Vector3(0, 0, 1);
  const right = new THREE.Vector3().crossVectors(up, viewDir).normalize();
  const camUp = new THREE.Vector3().crossVectors(viewDir, right).normalize();

  // Extent of the (morphed) vertices projected onto the camera axes.
  const fitAll = q.get('fit') === 'all';
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  const p = new THREE.Vector3();
  for (const m of meshes) {
    const pos = m.geometry.attributes.position;
    const targets = m.geometry.morphAttributes.position || [];
    const rel = m.geometry.morphTargetsRelative;
    const inf = m.morphTargetInfluences || [];
    // Shapes to fit: the current blend, plus (fit=all) the base and every target at weight 1.
    const shapes = [inf.slice()];
    if (fitAll) { shapes.push(inf.map(() => 0)); targets.forEach((_, t) => shapes.push(inf.map((_, i) => (i === t ? 1 : 0)))); }
    for (const w of shapes) {
      for (let v = 0; v < pos.count; v++) {
        p.fromBufferAttribute(pos, v);
        let base = 1;
        for (let t = 0; t < targets.length; t++) {
          if (!w[t]) continue;
          const a = targets[t];
          p.x += w[t] * a.getX(v); p.y += w[t] * a.getY(v); p.z += w[t] * a.getZ(v);
          base -= w[t];
        }
        if (!rel && targets.length) { // absolute targets: p = (1 - sum w) base + sum w target
          const b = new THREE.Vector3().fromBufferAttribute(pos, v);
          p.addScaledVector(b, base - 1);
        }
        p.applyMatrix4(m.matrixWorld);
        const c = [p.dot(right), p.dot(camUp), p.dot(viewDir)];
        for (let k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], c[k]); hi[k] = Math.max(hi[k], c[k]); }
      }
    }
  }
  const cx = (lo[0] + hi[0]) / 2, cy = (lo[1] + hi[1]) / 2;
  const margin = 1.08;
  let halfW = (hi[0] - lo[0]) / 2 * margin, halfH = (hi[1] - lo[1]) / 2 * margin;
  const aspect = W / H;
  if (halfW / halfH > aspect) halfH = halfW / aspect; else halfW = halfH * aspect;
  const depth = hi[2] - lo[2];
  const center = new THREE.Vector3().addScaledVector(right, cx).addScaledVector(camUp, cy)
    .addScaledVector(viewDir, (lo[2] + hi[2]) / 2);

  let camera;
  if (q.get('persp') === '1') {
    const fov = 30;
    const dist = Math.max(halfH / Math.tan(THREE.MathUtils.degToRad(fov / 2)), halfW / aspect / Math.tan(THREE.MathUtils.degToRad(fov / 2))) + depth / 2;
    camera = new THREE.PerspectiveCamera(fov, aspect, dist * 0.01, dist + depth * 2);
    camera.position.copy(center).addScaledVector(viewDir, dist);
  } else {
    camera = new THREE.OrthographicCamera(-halfW, halfW, halfH, -halfH, 0.01 * depth, 3 * depth + 1e-6);
    camera.position.copy(center).addScaledVector(viewDir, depth * 1.5);
  }
  camera.up.copy(camUp);
  camera.lookAt(center);
  scene.add(camera);

  // Lights: a key light from the viewer's upper left, a weak fill from the right, some ambient.
  const key = new THREE.DirectionalLight(0xffffff, 2.6);
  key.position.copy(viewDir).addScaledVector(camUp, 0.8).addScaledVector(right, -0.6);
  key.position.add(center);
  key.target.position.copy(center);
  scene.add(key, key.target);
  const fill = new THREE.DirectionalLight(0xffffff, 0.5);
  fill.position.copy(viewDir).addScaledVector(right, 1).addScaledVector(camUp, -0.3).add(center);
  fill.target.position.copy(center);
  scene.add(fill, fill.target);
  scene.add(new THREE.AmbientLight(0xffffff, 0.45));

  renderer.render(scene, camera);
  renderer.render(scene, camera);
  info.ok = true;
  info.bbox = { lo, hi };
  finish(info);
}

main().catch((e) => finish({ ok: false, error: String(e && e.stack || e) }));
