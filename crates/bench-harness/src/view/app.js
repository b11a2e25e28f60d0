// The `surftrack view` page: panels of runs drawn by three.js with one shared orbit
// camera. Frames are decoded from their base64 elements only when first shown.
// `window.surftrackView` reports state for tests and scripts (ready, timings in ms,
// step).
import * as THREE from 'three';
import { OrbitControls } from 'three-orbit-controls';

const started = performance.now();
const state = (window.surftrackView = { ready: false, error: null, timings: {}, renders: 0 });
const meta = JSON.parse(document.getElementById('surftrack-meta').textContent);
state.timings.parsed = performance.now() - started;

const $ = (id) => document.getElementById(id);
const pairKey = (lo, hi) => lo + '-' + hi;
const pairIndex = new Map(meta.pairs.map(([lo, hi], i) => [pairKey(lo, hi), i]));
const materialOn = new Map(meta.materials.map(([m]) => [m, true]));
const pairOn = new Map(meta.pairs.map(([lo, hi]) => [pairKey(lo, hi), true]));
const view = { shading: 'flat', wireframe: false, cut: false, axis: 2, pos: 0.5, flip: false };

function bytesOf(id) {
  const text = document.getElementById(id).textContent.trim();
  if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text);
  const raw = atob(text);
  const bytes = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  return bytes;
}

// The box around every frame of every run: frames the camera and the cut plane.
const box = new THREE.Box3();
for (const run of meta.runs) {
  for (const f of run.frames) {
    if (f.vertices > 0) {
      box.expandByPoint(new THREE.Vector3(...f.bounds[0]));
      box.expandByPoint(new THREE.Vector3(...f.bounds[1]));
    }
  }
}
if (box.isEmpty()) box.set(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1));
const centre = box.getCenter(new THREE.Vector3());
const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-9);

// Every step any run has a frame for; each panel shows its latest frame at or before it.
const steps = [...new Set(meta.runs.flatMap((r) => r.frames.map((f) => f.step)))].sort((a, b) => a - b);

const camera = new THREE.PerspectiveCamera(35, 1, radius / 100, radius * 100);
// The report pictures look from the same direction (report::picture::VIEW_DIRECTION).
camera.position.copy(centre).add(new THREE.Vector3(1.0, 0.8, 1.6).normalize().multiplyScalar(radius * 3.4));
camera.lookAt(centre);
const cutPlane = new THREE.Plane(new THREE.Vector3(0, 0, -1), 0);
const panels = [];
const controls = [];

function makeMaterials() {
  return meta.pairs.map(([, , colour]) => new THREE.MeshLambertMaterial({
    color: new THREE.Color(colour), side: THREE.DoubleSide, flatShading: true,
    polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
  }));
}
function makeWires() {
  return meta.pairs.map(() => new THREE.MeshBasicMaterial({
    color: 0x000000, wireframe: true, transparent: true, opacity: 0.35,
  }));
}

function makePanel(run, r) {
  const div = document.createElement('div');
  div.className = 'panel';
  const h2 = document.createElement('h2');
  h2.textContent = run.title;
  h2.title = run.title;
  const canvas = document.createElement('canvas');
  canvas.dataset.run = r;
  const record = document.createElement('div');
  record.className = 'record';
  const plots = document.createElement('div');
  plots.className = 'plots';
  for (const p of run.plots) {
    const img = document.createElement('img');
    img.src = p.src;
    img.alt = p.name;
    img.title = p.name;
    plots.appendChild(img);
  }
  div.append(h2, canvas, record, plots);
  $('panels').appendChild(div);
  // preserveDrawingBuffer: the picture stays readable (screenshots, tests) after a frame.
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.localClippingEnabled = true;
  renderer.setClearColor(0xffffff, 1);
  const scene = new THREE.Scene();
  scene.add(new THREE.AmbientLight(0xffffff, 0.45));
  const light = new THREE.DirectionalLight(0xffffff, 2.2);
  scene.add(light, light.target);
  const panel = {
    run, r, canvas, record, renderer, scene, light,
    materials: makeMaterials(), wires: makeWires(),
    cache: new Map(), shown: -1, mesh: null, wire: null,
  };
  const c = new OrbitControls(camera, canvas);
  // One target for every panel's controls: dragging in any panel turns them all.
  if (controls.length > 0) c.target = controls[0].target;
  else c.target.copy(centre);
  c.addEventListener('change', renderAll);
  controls.push(c);
  return panel;
}

// Decodes frame `f` of a panel into a geometry (kept in a small cache).
function geometry(panel, f) {
  const hit = panel.cache.get(f);
  if (hit) return hit;
  const frame = panel.run.frames[f];
  const p = bytesOf('r' + panel.r + 'f' + f + 'p');
  const t = bytesOf('r' + panel.r + 'f' + f + 't');
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(p.buffer, 0, p.length / 4), 3));
  g.setIndex(new THREE.BufferAttribute(new Uint32Array(t.buffer, 0, t.length / 4), 1));
  for (const pr of frame.pairs) {
    g.addGroup(pr.first * 3, pr.count * 3, pairIndex.get(pairKey(pr.lo, pr.hi)));
  }
  g.computeBoundingSphere();
  if (panel.cache.size >= 6) {
    const [oldest, old] = panel.cache.entries().next().value;
    if (oldest !== panel.shown) {
      old.dispose();
      panel.cache.delete(oldest);
    }
  }
  panel.cache.set(f, g);
  return g;
}

function frameAt(run, step) {
  let best = 0;
  run.frames.forEach((f, i) => { if (f.step <= step) best = i; });
  return best;
}

function fmt(x) { return typeof x === 'number' ? (Number.isInteger(x) ? String(x) : x.toFixed(4)) : String(x); }

function recordText(panel, f) {
  const frame = panel.run.frames[f];
  const lines = [`step ${frame.step}: ${frame.triangles} triangles, ${frame.vertices} vertices (${frame.file.split('/').pop()})`];
  const rec = panel.run.record;
  if (rec) {
    const s = (rec.per_step || []).find((x) => x.step === frame.step);
    if (s) {
      const e = s.events;
      lines.push(`t ${fmt(s.t)}  dt ${fmt(s.dt)}  ${fmt(s.seconds)} s  substeps ${s.substeps}  valid ${s.valid}`);
      lines.push(`events: merges ${e.merges}, splits ${e.splits}, T1 ${e.t1}, T2 ${e.t2}, remeshing ${e.remeshing_edits}`);
      lines.push('stages: ' + s.stages.map((x) => `${x.stage} ${x.seconds.toFixed(4)}`).join(', '));
    } else if (frame.step === 0 && rec.initial) {
      lines.push(`initial mesh: ${rec.initial.triangles} triangles, valid ${rec.initial.valid}`);
    }
    const outcome = rec.success ? 'succeeded' : `FAILED (${rec.failure ? rec.failure.reason + ': ' + rec.failure.message.split('\n')[0] : '?'})`;
    lines.push(`run: ${rec.steps_completed}/${rec.steps} steps, ${outcome}`);
  }
  return lines.join('\n');
}

function applyMaterials(panel) {
  meta.pairs.forEach(([lo, hi], i) => {
    const visible = pairOn.get(pairKey(lo, hi)) && materialOn.get(lo) && materialOn.get(hi);
    const m = panel.materials[i];
    m.visible = visible;
    if (m.flatShading !== (view.shading === 'flat')) {
      m.flatShading = view.shading === 'flat';
      m.needsUpdate = true;
    }
    const planes = view.cut ? [cutPlane] : [];
    if (m.clippingPlanes === null || m.clippingPlanes.length !== planes.length) {
      m.clippingPlanes = planes;
      panel.wires[i].clippingPlanes = planes;
      m.needsUpdate = true;
      panel.wires[i].needsUpdate = true;
    }
    panel.wires[i].visible = visible && view.wireframe;
  });
}

function show(panel, step) {
  const f = frameAt(panel.run, step);
  if (f !== panel.shown) {
    const g = geometry(panel, f);
    if (view.shading === 'smooth' && !g.getAttribute('normal')) g.computeVertexNormals();
    if (!panel.mesh) {
      panel.mesh = new THREE.Mesh(g, panel.materials);
      panel.wire = new THREE.Mesh(g, panel.wires);
      panel.scene.add(panel.mesh, panel.wire);
    } else {
      panel.mesh.geometry = g;
      panel.wire.geometry = g;
    }
    panel.shown = f;
    panel.record.textContent = recordText(panel, f);
  }
}

function updateCutPlane() {
  const n = new THREE.Vector3();
  n.setComponent(view.axis, view.flip ? 1 : -1);
  const lo = box.min.getComponent(view.axis);
  const hi = box.max.getComponent(view.axis);
  const at = lo + view.pos * (hi - lo);
  // Keeps the side where n·x + constant ≥ 0: below `at` unless flipped.
  cutPlane.set(n, view.flip ? -at : at);
}

function resize(panel) {
  const w = panel.canvas.clientWidth || 400;
  const h = panel.canvas.clientHeight || 400;
  panel.renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}

function renderAll() {
  const step = steps[Number($('frame').value)] ?? 0;
  $('step-label').textContent = `step ${step} (${Number($('frame').value) + 1}/${steps.length})`;
  state.step = step;
  for (const panel of panels) {
    show(panel, step);
    applyMaterials(panel);
    panel.light.position.copy(camera.position).add(new THREE.Vector3(0, radius, 0));
    panel.light.target.position.copy(controls[0].target);
    panel.renderer.render(panel.scene, camera);
  }
  state.renders += 1;
}

function legend() {
  const div = $('legend');
  const label = (html) => { const l = document.createElement('label'); l.innerHTML = html; return l; };
  const title = document.createElement('b');
  title.textContent = 'materials';
  div.appendChild(title);
  for (const [m, colour] of meta.materials) {
    const l = label(`<input type="checkbox" class="material" data-material="${m}" checked><span class="swatch" style="background:${colour}"></span>${m === 0 ? '0 (outside)' : m}`);
    l.querySelector('input').addEventListener('change', (e) => { materialOn.set(m, e.target.checked); renderAll(); });
    div.appendChild(l);
  }
  const title2 = document.createElement('b');
  title2.textContent = 'pairs';
  div.appendChild(title2);
  for (const [lo, hi, colour] of meta.pairs) {
    const key = pairKey(lo, hi);
    const l = label(`<input type="checkbox" class="pair" data-pair="${key}" checked><span class="swatch" style="background:${colour}"></span>${lo}|${hi}`);
    l.querySelector('input').addEventListener('change', (e) => { pairOn.set(key, e.target.checked); renderAll(); });
    div.appendChild(l);
  }
}

let timer = null;
function play() {
  const slider = $('frame');
  if (timer) {
    clearInterval(timer);
    timer = null;
    $('play').textContent = 'play';
    return;
  }
  if (Number(slider.value) >= steps.length - 1) slider.value = 0;
  $('play').textContent = 'pause';
  timer = setInterval(() => {
    const next = Number(slider.value) + 1;
    if (next >= steps.length) { play(); return; }
    slider.value = next;
    renderAll();
  }, 350);
  renderAll();
}

try {
  legend();
  meta.runs.forEach((run, r) => panels.push(makePanel(run, r)));
  const slider = $('frame');
  slider.max = Math.max(steps.length - 1, 0);
  slider.addEventListener('input', renderAll);
  $('play').addEventListener('click', play);
  $('shading').addEventListener('change', (e) => {
    view.shading = e.target.value;
    for (const p of panels) {
      if (view.shading === 'smooth') for (const g of p.cache.values()) if (!g.getAttribute('normal')) g.computeVertexNormals();
    }
    renderAll();
  });
  $('wireframe').addEventListener('change', (e) => { view.wireframe = e.target.checked; renderAll(); });
  $('cut').addEventListener('change', (e) => { view.cut = e.target.checked; renderAll(); });
  $('cut-axis').addEventListener('change', (e) => { view.axis = Number(e.target.value); updateCutPlane(); renderAll(); });
  $('cut-pos').addEventListener('input', (e) => { view.pos = Number(e.target.value) / 1000; updateCutPlane(); renderAll(); });
  $('cut-flip').addEventListener('change', (e) => { view.flip = e.target.checked; updateCutPlane(); renderAll(); });
  window.addEventListener('resize', () => { panels.forEach(resize); renderAll(); });
  updateCutPlane();
  panels.forEach(resize);
  renderAll();
  state.timings.firstRender = performance.now() - started;
  // From navigation start: reading the file, parsing the page, three.js, first picture.
  state.timings.readySinceNavigation = performance.now();
  state.ready = true;
} catch (e) {
  state.error = String(e && e.message ? e.message : e);
  $('message').textContent = 'cannot show the meshes: ' + state.error;
  console.error('surftrack view:', e);
}
