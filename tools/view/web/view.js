// The page of `sweepmap view`: draws what the server sends on /ws (tools/view/view_model.hpp
// for the frames) with three.js from Debian's libjs-three, served under /three/.
import * as THREE from '/three/build/three.module.js';
import { OrbitControls } from '/three/examples/jsm/controls/OrbitControls.js';

const $ = (id) => document.getElementById(id);

// ---- Scene ------------------------------------------------------------------------------
const renderer = new THREE.WebGLRenderer({ canvas: $('scene'), antialias: false,
  preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.localClippingEnabled = true;
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x111111);
const camera = new THREE.PerspectiveCamera(60, 1, 0.05, 500);
camera.up.set(0, 0, 1);
camera.position.set(-8, -8, 6);
const controls = new OrbitControls(camera, renderer.domElement);
controls.screenSpacePanning = true;
scene.add(new THREE.AmbientLight(0xffffff, 0.6));
const sun = new THREE.DirectionalLight(0xffffff, 0.6);
sun.position.set(3, 2, 10);
scene.add(sun);
scene.add(new THREE.AxesHelper(0.5));

const clipPlanes = [new THREE.Plane(new THREE.Vector3(0, 0, 1), 10),
  new THREE.Plane(new THREE.Vector3(0, 0, -1), 10)];
const pointMaterial = new THREE.PointsMaterial({ size: 2, sizeAttenuation: false,
  vertexColors: THREE.VertexColors, clippingPlanes: clipPlanes });

// ---- State --------------------------------------------------------------------------------
const state = {
  mode: null, connected: false, sweeps: new Map(), colour: 'height',
  zRange: [Infinity, -Infinity], voxelRes: 0.05, voxelCount: 0, lastCheck: null,
  voxelSource: 'points',  // 'mapper' once MAP_UPDATE arrives
  iRange: [Infinity, -Infinity], hasIntensity: false,
  status: null, frames: 0, fps: 0, latencies: [], pendingLatency: [], time: null,
  messages: 0, dragging: false, statusSeq: 0,
};

// Colours: a blue-green-yellow-red ramp for t in [0, 1].
function ramp(t, out, i) {
  t = Math.min(1, Math.max(0, t));
  const c = new THREE.Color().setHSL(0.66 * (1 - t), 0.9, 0.5);
  out[i] = c.r; out[i + 1] = c.g; out[i + 2] = c.b;
}
// Intensity: the lidar's device units, linear between the smallest and largest seen so far;
// grey where a sweep has none (a lidar that measures no intensity).
function colourPoints(sweep, from, to) {
  const p = sweep.positions, c = sweep.colours, inten = sweep.intensities;
  const [z0, z1] = state.zRange, [i0, i1] = state.iRange;
  const hue = new THREE.Color().setHSL((sweep.id * 0.618034) % 1, 0.8, 0.55);
  for (let k = from; k < to; k++) {
    const i = 3 * k;
    if (state.colour === 'height') {
      ramp((p[i + 2] - z0) / Math.max(1e-6, z1 - z0), c, i);
    } else if (state.colour === 'sweep') {
      c[i] = hue.r; c[i + 1] = hue.g; c[i + 2] = hue.b;
    } else if (state.colour === 'intensity') {
      if (sweep.hasIntensity) ramp((inten[k] - i0) / Math.max(1e-6, i1 - i0), c, i);
      else c[i] = c[i + 1] = c[i + 2] = 0.5;
    } else {
      const o = sweep.origin;
      ramp(Math.hypot(p[i] - o[0], p[i + 1] - o[1], p[i + 2] - o[2]) / 10, c, i);
    }
  }
}
function recolourAll() {
  for (const s of state.sweeps.values()) {
    colourPoints(s, 0, s.count);
    s.geometry.attributes.color.needsUpdate = true;
  }
}

// One view sweep: its points in growing arrays, and the chunks they came in (for thinning).
function makeSweep(id) {
  const s = { id, count: 0, capacity: 0, chunks: [], origin: [0, 0, 0], positions: null,
    colours: null, intensities: null, hasIntensity: false, geometry: null, points: null };
  reallocate(s, 4096);
  state.sweeps.set(id, s);
  return s;
}
function reallocate(s, capacity) {
  const positions = new Float32Array(3 * capacity), colours = new Float32Array(3 * capacity);
  const intensities = new Float32Array(capacity);
  if (s.positions) {
    positions.set(s.positions.subarray(0, 3 * s.count));
    colours.set(s.colours.subarray(0, 3 * s.count));
    intensities.set(s.intensities.subarray(0, s.count));
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
  geometry.setDrawRange(0, s.count);
  if (s.points) {
    s.geometry.dispose();
    s.points.geometry = geometry;
  } else {
    s.points = new THREE.Points(geometry, pointMaterial);
    s.points.frustumCulled = false;
    s.points.userData.sweep = s;
    scene.add(s.points);
  }
  Object.assign(s, { positions, colours, intensities, geometry, capacity });
}
function updateGeometry(s) {
  s.geometry.setDrawRange(0, s.count);
  s.geometry.attributes.position.needsUpdate = true;
  s.geometry.attributes.color.needsUpdate = true;
  s.geometry.boundingSphere = null;
}

function addCloud(view) {
  const n = view.getUint32(4, true);
  const id = Number(view.getBigInt64(8, true));
  const received = Number(view.getBigInt64(24, true));
  const xyz = new Float32Array(view.buffer, view.byteOffset + 48, 3 * n);
  // Flags bit 0: n intensities follow the points (tools/view/view_model.hpp).
  const inten = (view.getUint32(44, true) & 1) ?
    new Float32Array(view.buffer, view.byteOffset + 48 + 12 * n, n) : null;
  const s = state.sweeps.get(id) || makeSweep(id);
  s.origin = [view.getFloat32(32, true), view.getFloat32(36, true), view.getFloat32(40, true)];
  if (s.count + n > s.capacity) reallocate(s, Math.max(2 * s.capacity, s.count + n));
  s.positions.set(xyz, 3 * s.count);
  let rangeGrew = false;
  for (let k = 2; k < xyz.length; k += 3) {
    if (xyz[k] < state.zRange[0]) { state.zRange[0] = xyz[k]; rangeGrew = true; }
    if (xyz[k] > state.zRange[1]) { state.zRange[1] = xyz[k]; rangeGrew = true; }
  }
  const intensityGrew = inten ? takeIntensities(s, inten) : false;
  s.chunks.push({ start: s.count, count: n });
  colourPoints(s, s.count, s.count + n);
  s.count += n;
  updateGeometry(s);
  if ((rangeGrew && state.colour === 'height') ||
    (intensityGrew && state.colour === 'intensity')) recolourAll();
  if (state.mode === 'live') state.pendingLatency.push(received);
}

// A chunk's intensities into its sweep (after its points' place); whether the range grew.
function takeIntensities(s, inten) {
  s.intensities.set(inten, s.count);
  s.hasIntensity = true;
  if (!state.hasIntensity) {
    state.hasIntensity = true;
    $('colour-intensity').disabled = false;
    $('colour-intensity').title = 'the lidar\'s intensity (device units)';
  }
  let grew = false;
  for (const v of inten) {
    if (v < state.iRange[0]) { state.iRange[0] = v; grew = true; }
    if (v > state.iRange[1]) { state.iRange[1] = v; grew = true; }
  }
  return grew;
}

// Every second point of each chunk dropped (the server's arithmetic: ceil(m / 2) kept).
function thinSweep(id) {
  const s = state.sweeps.get(id);
  if (!s) return;
  let w = 0;
  const chunks = [];
  for (const c of s.chunks) {
    const start = w;
    for (let k = 0; k < c.count; k += 2) {
      const r = 3 * (c.start + k);
      s.positions.copyWithin(3 * w, r, r + 3);
      s.colours.copyWithin(3 * w, r, r + 3);
      s.intensities[w] = s.intensities[c.start + k];
      w++;
    }
    chunks.push({ start, count: w - start });
  }
  s.chunks = chunks;
  s.count = w;
  updateGeometry(s);
}
function removeSweep(id) {
  const s = state.sweeps.get(id);
  if (!s) return;
  scene.remove(s.points);
  s.geometry.dispose();
  state.sweeps.delete(id);
}
function pointsDrawn() {
  let n = 0;
  for (const s of state.sweeps.values()) n += s.count;
  return n;
}

// ---- Voxels ------------------------------------------------------------------------------
// Each occupied voxel as a square of the voxel's size at its centre (one vertex per voxel: a
// software renderer draws hundreds of thousands of them, where it would not draw as many boxes).
const voxelMaterial = new THREE.PointsMaterial({ color: 0xff9933, size: 0.05,
  sizeAttenuation: true, transparent: true, opacity: 0.35, depthWrite: false,
  clippingPlanes: clipPlanes });
let voxelXyz = new Float32Array(3 * 16384);
const voxelGeometry = new THREE.BufferGeometry();
voxelGeometry.setAttribute('position', new THREE.BufferAttribute(voxelXyz, 3));
const voxelPoints = new THREE.Points(voxelGeometry, voxelMaterial);
voxelPoints.frustumCulled = false;
scene.add(voxelPoints);
// The voxels drawn, by key ("i,j,k") -> their slot in voxelXyz; a removed voxel's slot takes
// the last one's, so the first voxelCount slots are the drawn voxels.
const voxelSlots = new Map();
const voxelKeys = [];
function clearVoxels() {
  state.voxelCount = 0;
  voxelSlots.clear();
  voxelKeys.length = 0;
  voxelGeometry.setDrawRange(0, 0);
}
function removeVoxel(key) {
  const slot = voxelSlots.get(key);
  if (slot === undefined) return;
  const last = --state.voxelCount;
  voxelXyz.copyWithin(3 * slot, 3 * last, 3 * last + 3);
  voxelKeys[slot] = voxelKeys[last];
  voxelSlots.set(voxelKeys[slot], slot);
  voxelKeys.length = last;
  voxelSlots.delete(key);
}
// Frame type 2 (tools/view/view_model.hpp): n voxel keys added, or removed when flags has 1.
function addVoxels(view) {
  const n = view.getUint32(4, true);
  const res = view.getFloat32(8, true);
  const removed = (view.getUint32(12, true) & 1) !== 0;
  state.voxelRes = res;
  voxelMaterial.size = res;
  if (3 * (state.voxelCount + n) > voxelXyz.length) {
    const grown = new Float32Array(Math.max(2 * voxelXyz.length, 3 * (state.voxelCount + n)));
    grown.set(voxelXyz.subarray(0, 3 * state.voxelCount));
    voxelXyz = grown;
    voxelGeometry.setAttribute('position', new THREE.BufferAttribute(voxelXyz, 3));
  }
  for (let k = 0; k < n; k++) {
    const o = 16 + 12 * k;
    const x = view.getInt32(o, true), y = view.getInt32(o + 4, true), z = view.getInt32(o + 8, true);
    const key = `${x},${y},${z}`;
    if (removed) {
      removeVoxel(key);
      continue;
    }
    if (voxelSlots.has(key)) continue;
    const slot = state.voxelCount++, i = 3 * slot;
    voxelSlots.set(key, slot);
    voxelKeys[slot] = key;
    voxelXyz[i] = (x + 0.5) * res;
    voxelXyz[i + 1] = (y + 0.5) * res;
    voxelXyz[i + 2] = (z + 0.5) * res;
  }
  voxelGeometry.setDrawRange(0, state.voxelCount);
  voxelGeometry.attributes.position.needsUpdate = true;
}

// ---- Pose, path, scan --------------------------------------------------------------------
const pathGeometry = new THREE.BufferGeometry();
let pathXyz = new Float32Array(3 * 1024);
let pathCount = 0;
pathGeometry.setAttribute('position', new THREE.BufferAttribute(pathXyz, 3));
const pathLine = new THREE.Line(pathGeometry, new THREE.LineBasicMaterial({ color: 0x33ddff }));
pathLine.frustumCulled = false;
scene.add(pathLine);
const poseArrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 0.6,
  0xff33cc, 0.2, 0.12);
poseArrow.visible = false;
scene.add(poseArrow);
function addPath(xy) {
  for (let k = 0; k + 1 < xy.length; k += 2) {
    if (pathCount >= pathXyz.length / 3) {
      const grown = new Float32Array(pathXyz.length * 2);
      grown.set(pathXyz);
      pathXyz = grown;
      pathGeometry.setAttribute('position', new THREE.BufferAttribute(pathXyz, 3));
    }
    pathXyz.set([xy[k], xy[k + 1], 0.02], 3 * pathCount++);
  }
  pathGeometry.setDrawRange(0, pathCount);
  pathGeometry.attributes.position.needsUpdate = true;
}
function setPose(p) {
  poseArrow.visible = true;
  poseArrow.position.set(p.x, p.y, 0.05);
  poseArrow.setDirection(new THREE.Vector3(Math.cos(p.theta), Math.sin(p.theta), 0));
}
function drawScan(view) {
  const n = view.getUint32(4, true);
  const yz = new Float32Array(view.buffer, view.byteOffset + 16, 2 * n);
  const cv = $('scan'), g = cv.getContext('2d');
  g.fillStyle = '#000';
  g.fillRect(0, 0, cv.width, cv.height);
  let rmax = 0.5;
  for (let k = 0; k < yz.length; k++) rmax = Math.max(rmax, Math.abs(yz[k]));
  const scale = (cv.width / 2 - 4) / rmax;
  g.fillStyle = '#7f7';
  for (let k = 0; k + 1 < yz.length; k += 2) {
    g.fillRect(cv.width / 2 + yz[k] * scale, cv.height / 2 - yz[k + 1] * scale, 1.5, 1.5);
  }
  g.fillStyle = '#888';
  g.fillText(`${n} points, ${rmax.toFixed(1)} m`, 4, 12);
}

// ---- Status ------------------------------------------------------------------------------
function text(s) { return String(s).replace(/[&<>"]/g, (c) => `&#${c.charCodeAt(0)};`); }
function showStatus(msg) {
  state.status = msg;
  state.statusSeq++;
  state.lastCheck = { server: msg.you.points, drawn: pointsDrawn() };
  const rows = [];
  const procs = (msg.board && msg.board.processes) || {};
  for (const [name, p] of Object.entries(procs)) {
    const cls = p.status === 'OK' ? 'ok' : p.status === 'DEGRADED' ? 'warn' : 'bad';
    rows.push(`<tr><td>${text(name)}</td><td class="${cls}">${text(p.status)}</td>` +
      `<td>${p.age_s.toFixed(1)} s</td><td>${text(p.detail)}</td></tr>`);
  }
  $('processes').innerHTML = rows.join('') || '<tr><td>no STATUS_* seen yet</td></tr>';
  const m = msg.board && msg.board.mapper;
  $('mapper').textContent = m ? `mapper: ${m.sweeps} sweeps, ${m.occupied_voxels} occupied voxels`
    : '';
  const y = msg.you;
  $('view-status').innerHTML = `sent ${y.frames_sent} frames (${(y.bytes_sent / 1e6).toFixed(1)} MB)` +
    `<br><span class="${y.frames_dropped ? 'warn' : ''}">dropped ${y.frames_dropped} frames ` +
    `(${y.points_dropped} points), replaced ${y.replaced}</span>` +
    `<br>queued ${(y.queued_bytes / 1e6).toFixed(1)} MB · ${msg.view.connections} connections` +
    `<br>${state.fps.toFixed(0)} frames/s`;
}
function showCounts() {
  $('counts').textContent = `${state.sweeps.size} sweeps, ${pointsDrawn()} points, ` +
    `${state.voxelCount} voxels (${state.voxelRes.toFixed(3)} m, ` +
    (state.voxelSource === 'mapper' ? "the mapper's OctoMap)"
      : 'from the cloud points: no MAP_UPDATE yet)');
}

// ---- Connection --------------------------------------------------------------------------
function resetAll() {
  for (const id of [...state.sweeps.keys()]) removeSweep(id);
  clearVoxels();
  state.voxelSource = 'points';
  pathCount = 0;
  pathGeometry.setDrawRange(0, 0);
  poseArrow.visible = false;
  state.zRange = [Infinity, -Infinity];
  state.iRange = [Infinity, -Infinity];
}
function onText(msg) {
  switch (msg.type) {
    case 'hello':
      state.mode = msg.mode;
      state.voxelRes = msg.voxel_m;
      $('log-controls').hidden = msg.mode !== 'log';
      break;
    case 'status': showStatus(msg); break;
    case 'thin': thinSweep(msg.sweep); break;
    case 'remove': removeSweep(msg.sweep); break;
    case 'reset': resetAll(); break;
    case 'voxels':  // the mapper's voxels (MAP_UPDATE) replace the cloud-derived ones
      clearVoxels();
      state.voxelSource = msg.source;
      state.voxelRes = msg.voxel_m;
      break;
    case 'pose': setPose(msg); break;
    case 'path': addPath(msg.xy); break;
    case 'time': showTime(msg); break;
    default: break;
  }
}
function onBinary(buffer) {
  const view = new DataView(buffer);
  switch (view.getUint8(0)) {
    case 1: addCloud(view); break;
    case 2: addVoxels(view); break;
    case 3: drawScan(view); break;
    default: break;
  }
}
let socket = null;
function connect() {
  socket = new WebSocket(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`);
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => {
    state.connected = true;
    resetAll();
    $('connection').textContent = `connected to ${location.host}`;
    $('connection').className = 'ok';
  };
  socket.onmessage = (e) => {
    state.messages++;
    if (typeof e.data === 'string') onText(JSON.parse(e.data)); else onBinary(e.data);
  };
  socket.onclose = () => {
    state.connected = false;
    $('connection').textContent = 'disconnected: retrying';
    $('connection').className = 'bad';
    setTimeout(connect, 1000);
  };
}
function send(obj) { if (socket && socket.readyState === 1) socket.send(JSON.stringify(obj)); }

// ---- Log playback ------------------------------------------------------------------------
function showTime(t) {
  state.time = t;
  const span = Math.max(1, t.end - t.start);
  if (!state.dragging) $('time').value = Math.round(1000 * (t.utime - t.start) / span);
  $('time-out').textContent = `${((t.utime - t.start) / 1e6).toFixed(1)} / ` +
    `${(span / 1e6).toFixed(1)} s`;
  $('play').textContent = t.playing ? 'pause' : 'play';
}
$('time').addEventListener('input', () => { state.dragging = true; });
$('time').addEventListener('change', () => {
  state.dragging = false;
  const t = state.time;
  if (t) send({ type: 'seek', utime: Math.round(t.start + (t.end - t.start) * $('time').value / 1000) });
});
$('play').addEventListener('click', () => send({ type: state.time && state.time.playing ? 'pause' : 'play' }));
$('speed').addEventListener('change', () => send({ type: 'speed', value: Number($('speed').value) }));

// ---- Controls ----------------------------------------------------------------------------
// The drawn points only: a sweep's buffers hold zeros (or thinned points) past its count.
function bounds() {
  const box = new THREE.Box3();
  const p = new THREE.Vector3();
  for (const s of state.sweeps.values()) {
    for (let k = 0; k < s.count; k++) box.expandByPoint(p.fromArray(s.positions, 3 * k));
  }
  return box;
}
function view(direction, up) {
  const box = bounds();
  const centre = box.isEmpty() ? new THREE.Vector3() : box.getCenter(new THREE.Vector3());
  const size = box.isEmpty() ? 10 : box.getSize(new THREE.Vector3()).length();
  camera.up.copy(up);
  camera.position.copy(centre).addScaledVector(direction, size);
  controls.target.copy(centre);
  controls.update();
}
$('cam-top').onclick = () => { view(new THREE.Vector3(0, 0, 1), new THREE.Vector3(0, 1, 0));
  controls.enableRotate = false; };
$('cam-side').onclick = () => { view(new THREE.Vector3(0, -1, 0), new THREE.Vector3(0, 0, 1));
  controls.enableRotate = false; };
$('cam-free').onclick = () => { controls.enableRotate = true; camera.up.set(0, 0, 1); };
$('cam-fit').onclick = () => view(new THREE.Vector3(-0.6, -0.6, 0.5).normalize(),
  new THREE.Vector3(0, 0, 1));
$('colour').onchange = () => { state.colour = $('colour').value; recolourAll(); };
$('point-size').oninput = () => { pointMaterial.size = Number($('point-size').value); };
$('voxels').onchange = () => { voxelPoints.visible = $('voxels').checked; };
function setClip() {
  clipPlanes[0].constant = -Number($('clip-min').value);
  clipPlanes[1].constant = Number($('clip-max').value);
}
$('clip-min').oninput = setClip;
$('clip-max').oninput = setClip;
setClip();

// Measuring: the nearest drawn point under each of two clicks, and the distance between them.
const raycaster = new THREE.Raycaster();
const measured = [];
const measureLine = new THREE.Line(new THREE.BufferGeometry().setFromPoints(
  [new THREE.Vector3(), new THREE.Vector3()]), new THREE.LineBasicMaterial({ color: 0xffffff }));
measureLine.visible = false;
scene.add(measureLine);
function pick(clientX, clientY) {
  const r = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1,
    -((clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  raycaster.params.Points.threshold = Math.max(0.02, 0.01 * camera.position.distanceTo(controls.target));
  const hits = raycaster.intersectObjects([...state.sweeps.values()].map((s) => s.points));
  return hits.length ? hits[0].point.clone() : null;
}
function measure(clientX, clientY) {
  const p = pick(clientX, clientY);
  if (!p) return null;
  if (measured.length === 2) measured.length = 0;
  measured.push(p);
  if (measured.length === 2) {
    measureLine.geometry.setFromPoints(measured);
    measureLine.visible = true;
    const d = measured[0].distanceTo(measured[1]);
    $('measure-out').textContent = `distance ${d.toFixed(3)} m`;
    return d;
  }
  $('measure-out').textContent = 'first point set: click the second';
  return null;
}
let down = null;
renderer.domElement.addEventListener('pointerdown', (e) => { down = [e.clientX, e.clientY]; });
renderer.domElement.addEventListener('pointerup', (e) => {
  if ($('measure').checked && down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 4) {
    measure(e.clientX, e.clientY);
  }
});

// ---- Drawing -----------------------------------------------------------------------------
let fpsFrames = 0;
let fpsSince = performance.now();
function resize() {
  const w = window.innerWidth, h = window.innerHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(1, h);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();
let countsShown = 0;
function frame(now) {
  requestAnimationFrame(frame);
  controls.update();
  renderer.render(scene, camera);
  state.frames++;
  fpsFrames++;
  if (state.pendingLatency.length) {
    const drawn = (performance.timeOrigin + performance.now()) * 1000;
    for (const r of state.pendingLatency) state.latencies.push((drawn - r) / 1000);
    if (state.latencies.length > 10000) state.latencies.splice(0, 5000);
    state.pendingLatency.length = 0;
  }
  if (now - fpsSince > 1000) {
    state.fps = (1000 * fpsFrames) / (now - fpsSince);
    fpsFrames = 0;
    fpsSince = now;
  }
  if (now - countsShown > 250) { showCounts(); countsShown = now; }
}
requestAnimationFrame(frame);
connect();

// What tests and benchmarks read (tests/js/view_*.js).
function quantile(values, q) {
  const v = Float32Array.from(values).sort();
  return v.length ? v[Math.min(v.length - 1, Math.floor(q * v.length))] : NaN;
}
window.sweepmapView = {
  get connected() { return state.connected; },
  get mode() { return state.mode; },
  get lastCheck() { return state.lastCheck; },
  get status() { return state.status; },
  get statusSeq() { return state.statusSeq; },
  get fps() { return state.fps; },
  get frames() { return state.frames; },
  get time() { return state.time; },
  get latenciesMs() { return state.latencies.slice(); },
  pointsDrawn,
  sweeps: () => state.sweeps.size,
  voxels: () => state.voxelCount,
  voxelSource: () => state.voxelSource,
  // Per axis, the q and 1-q quantiles of the drawn points' coordinates.
  extent(q) {
    const axes = [[], [], []];
    for (const s of state.sweeps.values()) {
      for (let k = 0; k < 3 * s.count; k++) axes[k % 3].push(s.positions[k]);
    }
    return axes.map((a) => [quantile(a, q), quantile(a, 1 - q)]);
  },
  measure,
  seek: (utime) => send({ type: 'seek', utime }),
  play: () => send({ type: 'play' }),
  pause: () => send({ type: 'pause' }),
  setCamera: (which) => $(`cam-${which}`).click(),
  get colour() { return state.colour; },
  get intensityAvailable() { return state.hasIntensity; },
  // Picks a colour mode as a person does (the selector, then its change event); false when
  // that option is disabled (intensity before any chunk carried it).
  setColour(mode) {
    const option = [...$('colour').options].find((o) => o.value === mode);
    if (!option || option.disabled) return false;
    $('colour').value = mode;
    $('colour').dispatchEvent(new Event('change'));
    return true;
  },
  // Up to n points spread over the sweeps: z, intensity (null without) and the drawn hue.
  colourSample(n) {
    const out = [], hsl = {};
    for (const s of state.sweeps.values()) {
      const step = Math.max(1, Math.floor(s.count / n));
      for (let k = 0; k < s.count && out.length < n * state.sweeps.size; k += step) {
        new THREE.Color(s.colours[3 * k], s.colours[3 * k + 1], s.colours[3 * k + 2]).getHSL(hsl);
        out.push({ z: s.positions[3 * k + 2], intensity: s.hasIntensity ? s.intensities[k] : null,
          hue: hsl.h, saturation: hsl.s });
      }
    }
    return out;
  },
};
