// sdrs view: plays back a simulation or an optimization result (the data is
// the JSON in <script id="sdrs-data">, written by `sdrs view`; see
// cli/src/view/page.rs for its layout). World frame: z up, metres.
// URL hash options: #frame=K (start paused at frame K), #iter=K (design at
// iteration K), #planes=0, #trails=1.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const t0 = performance.now();
const DATA = JSON.parse(document.getElementById('sdrs-data').textContent);
const hash = new URLSearchParams(location.hash.slice(1));

function b64(s, Type) {
  const bin = atob(s);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}

const view = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setClearColor(0xf4f5f7, 1);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.8);
sun.position.set(3, -5, 10);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
camera.up.set(0, 0, 1);
const controls = new OrbitControls(camera, renderer.domElement);

function hullGeometry(h) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(b64(h.p, Float32Array), 3));
  g.setIndex(new THREE.BufferAttribute(b64(h.i, Uint32Array), 1));
  return g;
}

// One group per scene (shifted by its offset), one group per link.
const box = new THREE.Box3();
const scenes = DATA.scenes.map((s) => {
  const root = new THREE.Group();
  root.position.fromArray(s.offset);
  scene.add(root);
  const poses = b64(s.poses, Float32Array);
  const times = b64(s.times, Float32Array);
  const nl = s.links.length;
  const links = s.links.map((l) => {
    const g = new THREE.Group();
    const color = new THREE.Color().setRGB(l.color[0], l.color[1], l.color[2], THREE.SRGBColorSpace);
    const mat = new THREE.MeshStandardMaterial({ color, flatShading: true, roughness: 0.75, metalness: 0.0 });
    const edges = new THREE.LineBasicMaterial({ color: 0x333333, transparent: true, opacity: 0.35 });
    for (const h of l.hulls) {
      const geo = hullGeometry(h);
      g.add(new THREE.Mesh(geo, mat));
      g.add(new THREE.LineSegments(new THREE.EdgesGeometry(geo, 20), edges));
    }
    root.add(g);
    return { group: g, mat, env: l.env };
  });
  let planes = null;
  if (s.contacts) {
    planes = { start: b64(s.contacts.start, Uint32Array), data: b64(s.contacts.planes, Float32Array), pool: [] };
  }
  const trail = new THREE.Group();
  root.add(trail);
  return { s, root, poses, times, nl, links, planes, trail, steps: s.steps };
});

const planeGeo = new THREE.PlaneGeometry(1, 1);
const planeMat = new THREE.MeshBasicMaterial({ color: 0xd02020, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false });
const normalMat = new THREE.LineBasicMaterial({ color: 0xb00000 });
const zAxis = new THREE.Vector3(0, 0, 1);
const opts = { planes: hash.get('planes') !== '0', trails: hash.get('trails') === '1' };

function setFrame(sc, f) {
  f = Math.min(f, sc.steps - 1);
  const p = sc.poses;
  for (let i = 0; i < sc.nl; i++) {
    const o = 7 * (f * sc.nl + i);
    sc.links[i].group.position.set(p[o], p[o + 1], p[o + 2]);
    sc.links[i].group.quaternion.set(p[o + 3], p[o + 4], p[o + 5], p[o + 6]);
  }
  if (sc.planes) {
    const { start, data, pool } = sc.planes;
    const a = opts.planes ? start[f] : 0, b = opts.planes ? start[f + 1] : 0;
    while (pool.length < b - a) {
      const m = new THREE.Mesh(planeGeo, planeMat);
      const n = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3(0, 0, 1)]), normalMat);
      m.add(n);
      sc.root.add(m);
      pool.push(m);
    }
    pool.forEach((m, k) => {
      m.visible = k < b - a;
      if (!m.visible) return;
      const o = 7 * (a + k);
      m.position.set(data[o], data[o + 1], data[o + 2]);
      m.quaternion.setFromUnitVectors(zAxis, new THREE.Vector3(data[o + 3], data[o + 4], data[o + 5]));
      m.scale.setScalar(data[o + 6]);
    });
  }
  sc.trail.clear();
  if (opts.trails) {
    const from = Math.max(0, f - 200);
    for (let i = 0; i < sc.nl; i++) {
      if (sc.links[i].env || f - from < 1) continue;
      const pts = [];
      for (let k = from; k <= f; k++) {
        const o = 7 * (k * sc.nl + i);
        pts.push(new THREE.Vector3(p[o], p[o + 1], p[o + 2]));
      }
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color: sc.links[i].mat.color }));
      sc.trail.add(line);
    }
  }
}

// Design at any iteration (optimize results): swaps the designed links'
// hulls of the scene `DATA.iteration_scene`.
function setIteration(k) {
  const it = DATA.iterations[k];
  const sc = scenes[DATA.iteration_scene];
  it.poses.forEach((q, i) => {
    sc.poses.set(q, 7 * i);
  });
  setFrame(sc, 0);
  for (const [li, hulls] of Object.entries(it.links)) {
    const g = sc.links[+li].group;
    const mat = sc.links[+li].mat;
    g.children.slice().forEach((c) => { g.remove(c); c.geometry.dispose(); });
    const edges = new THREE.LineBasicMaterial({ color: 0x333333, transparent: true, opacity: 0.35 });
    for (const h of hulls) {
      const geo = hullGeometry(h);
      g.add(new THREE.Mesh(geo, mat));
      g.add(new THREE.LineSegments(new THREE.EdgesGeometry(geo, 20), edges));
    }
  }
  document.getElementById('iterLabel').textContent = `iteration ${it.iteration} (loss ${it.loss.toPrecision(4)})`;
  document.body.dataset.iteration = it.iteration;
}

// UI.
const nSteps = Math.max(...scenes.map((s) => s.steps));
const times = scenes.reduce((a, s) => (s.steps === nSteps ? s.times : a), scenes[0].times);
const slider = document.getElementById('time');
slider.max = nSteps - 1;
const label = document.getElementById('tlabel');
let frame = 0;
function show(f) {
  frame = f;
  scenes.forEach((sc) => setFrame(sc, f));
  label.textContent = `t = ${(times[f] - times[0]).toFixed(3)} s  (step ${f} of ${nSteps - 1})`;
  document.body.dataset.frame = f;
  render();
}
slider.addEventListener('input', () => show(+slider.value));
const playBtn = document.getElementById('play');
let playing = !hash.has('frame') && nSteps > 1;
let simTime = 0, last = null;
playBtn.textContent = playing ? 'pause' : 'play';
playBtn.addEventListener('click', () => { playing = !playing; playBtn.textContent = playing ? 'pause' : 'play'; last = null; });
const speed = document.getElementById('speed');
for (const id of ['planes', 'trails']) {
  const c = document.getElementById(id);
  c.checked = opts[id];
  c.addEventListener('change', () => { opts[id] = c.checked; show(frame); });
}
if (DATA.iterations.length) {
  const it = document.getElementById('iter');
  document.getElementById('iterBox').hidden = false;
  it.max = DATA.iterations.length - 1;
  it.value = hash.has('iter') ? Math.min(+hash.get('iter'), DATA.iterations.length - 1) : DATA.iterations.length - 1;
  it.addEventListener('input', () => { setIteration(+it.value); render(); });
  setIteration(+it.value);
}

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
function render() { renderer.render(scene, camera); }
window.addEventListener('resize', () => { resize(); render(); });
controls.addEventListener('change', render);

// Frame the robots (not the environment) over the whole run: their hulls
// at up to 60 sampled frames.
for (const sc of scenes) {
  const every = Math.max(1, Math.floor(sc.steps / 60));
  for (let f = 0; f < sc.steps; f += every) {
    setFrame(sc, f);
    sc.root.updateMatrixWorld(true);
    sc.links.forEach((l) => { if (!l.env) box.expandByObject(l.group); });
  }
  setFrame(sc, 0);
}
scene.updateMatrixWorld(true);
if (box.isEmpty()) box.setFromObject(scene);
const c = box.getCenter(new THREE.Vector3());
const r = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.1);
// Far enough for the bounding sphere to fit the narrower field of view.
const halfFov = Math.min(camera.fov / 2, (Math.atan(Math.tan((camera.fov * Math.PI) / 360) * view.clientWidth / Math.max(view.clientHeight, 1)) * 180) / Math.PI);
const dist = (0.8 * r) / Math.sin((halfFov * Math.PI) / 180);
const dir = new THREE.Vector3(0.45, -0.85, 0.35).normalize();
camera.position.copy(c).addScaledVector(dir, dist);
camera.near = r / 100;
camera.far = r * 200;
controls.target.copy(c);
controls.update();
if (!scenes.some((sc) => sc.links.some((l) => l.env))) {
  const grid = new THREE.GridHelper(4 * r, 20, 0xaaaaaa, 0xdddddd);
  grid.rotation.x = Math.PI / 2;
  grid.position.set(c.x, c.y, box.min.z - 0.5 * r);
  scene.add(grid);
}
resize();

// Self-check for tests: pixels each scene covers when drawn alone.
function drawnPixels() {
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(4 * w * h);
  const counts = [];
  for (const sc of scenes) {
    scenes.forEach((o) => { o.root.visible = o === sc; });
    render();
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let n = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - 0xf4) + Math.abs(px[i + 1] - 0xf5) + Math.abs(px[i + 2] - 0xf7) > 24) n++;
    }
    counts.push(`${sc.s.label}:${n}`);
  }
  scenes.forEach((o) => { o.root.visible = true; });
  return counts.join(',');
}
const start = hash.has('frame') ? Math.min(+hash.get('frame'), nSteps - 1) : 0;
slider.value = start;
slider.dispatchEvent(new Event('input'));
document.body.dataset.meshes = scenes.map((sc) => `${sc.s.label}:${sc.links.reduce((a, l) => a + l.group.children.filter((c) => c.isMesh).length, 0)}`).join(',');
if (hash.get('check') === '1') {
  document.body.dataset.drawn = drawnPixels();
  render();
}
// Milliseconds from navigation start (HTML parsed, three.js compiled, data
// decoded, first frame drawn) and of this module alone.
document.body.dataset.readyMs = performance.now().toFixed(0);
document.body.dataset.moduleMs = (performance.now() - t0).toFixed(0);
document.body.dataset.ready = '1';

function tick(now) {
  if (playing && last !== null) {
    simTime += ((now - last) / 1000) * +speed.value;
    const dur = times[nSteps - 1] - times[0];
    if (dur > 0) {
      simTime %= dur;
      const f = Math.min(nSteps - 1, Math.round((simTime / dur) * (nSteps - 1)));
      if (f !== frame) { slider.value = f; show(f); }
    }
  }
  last = now;
  requestAnimationFrame(tick);
}
requestAnimationFrame(tick);
