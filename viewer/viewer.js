// JawTrack live jaw-motion viewer (browser side).
//
// Served by `jawtrack receive --serve` (live mode, WebSocket /ws) and
// `jawtrack view session.jsonl` (replay mode, /api/recording). Units are mm.
// The scene frame is the maxilla frame (OpenCV-like axes: x right, y down,
// z away from the tracking camera); the mandible is placed with the
// row-major 4x4 `maxilla_from_mandible` pose.
//
// Server contract (matrices are 16 numbers, row-major 4x4; JSON null where unknown):
//   GET /api/scene -> {"mode": "live"|"replay", "maxilla": MESH, "mandible": MESH,
//                      "maxilla_from_mandible_rest": [16] | null}
//     where a scan's MESH may carry "marker_from_mesh": [16] (row-major), its place in
//     its marker's frame from the registration
//     MESH = {"format": "stl"|"ply"|"obj", "url": "/api/mesh/..."}
//          | {"format": "mesh", "positions": [x,y,z,...], "indices": [i,j,k,...]}
//   GET /api/recording (replay) -> {"frames": [{"t", "seq", "maxilla_from_mandible",
//                      "incisor": [x,y,z], "opening_mm", "lateral_mm", "protrusive_mm"}, ...],
//                      "header": {...} | null}
//   WS /ws (live), server -> client:
//     {"type":"pose","seq","t","maxilla_from_mandible","incisor","opening_mm","lateral_mm",
//      "protrusive_mm","tags":{"maxilla":n,"mandible":n}}
//     {"type":"status","link":"up"|"waiting"|"stale","received","accepted","lost",
//      "reordered","duplicated","rejected","loss_percent","rate_hz"}
//     {"type":"calibrated","ok":bool,"message":"..."}
//   client -> server: {"type":"calibrate_intercuspation"}

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { STLLoader } from 'three/addons/loaders/STLLoader.js';
import { PLYLoader } from 'three/addons/loaders/PLYLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { mergeVertices } from 'three/addons/utils/BufferGeometryUtils.js';
import { grid, headMatrix, hingeAxis, markerGroup, viewDirections } from './anatomy.js';
import { PointPicker } from './pick.js';

const LIVE_TRACE_POINTS = 2000;
const RECONNECT_MS = 2000;
const TOAST_MS = 4000;
const COLOURS = {
  background: 0x14181f,
  maxilla: 0x8fb8e8,
  mandible: 0xf0c58a,
  trace: 0xff4fa3,
  tip: 0xffffff,
  condyleLeft: 0x4fa3ff,
  condyleRight: 0x7ee081,
};

const $ = (id) => document.getElementById(id);

// ---------------------------------------------------------------- test hook
const hook = {
  ready: false,
  posesApplied: 0,
  mode: null,
  lastStatus: null,
  frameCount: 0,
  mandibleMatrix: () => Array.from(mandibleRoot.matrix.elements),
  // A loaded mesh's placement in its marker's frame, row-major (null before it loads).
  meshMatrix: (name) => {
    const o = scene.getObjectByName(`${name}-mesh`);
    return o ? Array.from(o.matrix.clone().transpose().elements) : null;
  },
  seek: (i) => {
    if (replay) replay.seek(i);
  },
  // What the scene holds besides the meshes, for the headless check.
  tagLabels: () => {
    let n = 0;
    scene.traverse((o) => {
      if (o.name.startsWith('tag-')) n += 1;
    });
    return n;
  },
  hasGrid: () => !!scene.getObjectByName('grid'),
  hasHingeAxis: () => !!scene.getObjectByName('hinge-axis'),
  condylePoints: () => condyleTraces.map((t) => t.line.geometry.drawRange.count),
  // The camera's direction (centre to camera) after a view button, in the scene frame.
  cameraDirection: () => {
    const target = controls ? controls.target : new THREE.Vector3();
    return camera.position.clone().sub(target).normalize().toArray();
  },
  viewDirections: () => {
    const d = viewDirections(head);
    return Object.fromEntries(Object.entries(d).map(([k, v]) => [k, v.toCamera.toArray()]));
  },
  // Picks on the scans where the middle of triangle `k` (modulo their number) of scan `name`
  // shows, as a click there would; returns the hit in the scene and in the upper scan's frame.
  pickTriangle: (name, k) => {
    const o = scene.getObjectByName(`${name}-mesh`);
    if (!o || !picker) return null;
    let mesh = null;
    o.traverse((m) => {
      if (!mesh && m.isMesh) mesh = m;
    });
    if (!mesh) return null;
    scene.updateMatrixWorld(true);
    const g = mesh.geometry;
    const positions = g.getAttribute('position');
    const triangles = g.index ? g.index.count / 3 : positions.count / 3;
    const t = k % triangles;
    const corner = (i) => (g.index ? g.index.getX(3 * t + i) : 3 * t + i);
    const p = new THREE.Vector3();
    for (let i = 0; i < 3; i++) p.add(new THREE.Vector3().fromBufferAttribute(positions, corner(i)));
    const ndc = p.divideScalar(3).applyMatrix4(mesh.matrixWorld).project(camera);
    return picker.pickAt(ndc.x, ndc.y);
  },
  startPicking: () => picker && picker.start(),
  pickCommand: () => (picker ? picker.command() : null),
  coloured: (name) => {
    let found = false;
    const o = scene.getObjectByName(`${name}-mesh`);
    if (o) o.traverse((m) => {
      if (m.isMesh && m.geometry.getAttribute('color') && m.material.vertexColors) found = true;
    });
    return found;
  },
};
window.jawtrack = hook;

// ---------------------------------------------------------------- helpers
const isFiniteNumber = (v) => typeof v === 'number' && Number.isFinite(v);
const isMatrix16 = (m) => Array.isArray(m) && m.length === 16 && m.every(isFiniteNumber);
const isVec3 = (p) => Array.isArray(p) && p.length === 3 && p.every(isFiniteNumber);
const fmtMm = (v) => (isFiniteNumber(v) ? v.toFixed(2) : '—');

function showMessage(text, { banner = false } = {}) {
  if (!banner) {
    const badge = $('mode-badge');
    badge.textContent = 'error';
    badge.className = 'badge disconnected';
  }
  const el = $('message');
  el.textContent = text;
  el.classList.toggle('banner', banner);
  el.hidden = false;
  $('loading').hidden = true;
}

let toastTimer = null;
function showToast(text, kind = '') {
  const el = $('toast');
  el.textContent = text;
  el.className = kind;
  el.hidden = false;
  clearTimeout(toastTimer);
  toastTimer = setTimeout(() => {
    el.hidden = true;
  }, TOAST_MS);
}

async function fetchJson(url) {
  let res;
  try {
    res = await fetch(url, { cache: 'no-store' });
  } catch (e) {
    throw new Error(`Could not reach the JawTrack server for ${url} (${e.message}).`);
  }
  if (!res.ok) {
    let body = '';
    try {
      body = (await res.text()).trim().slice(0, 300);
    } catch {
      // ignore: the status line is enough
    }
    throw new Error(`${url} answered HTTP ${res.status} ${res.statusText}${body ? `: ${body}` : ''}`);
  }
  try {
    return await res.json();
  } catch (e) {
    throw new Error(`${url} did not return valid JSON (${e.message}).`);
  }
}

// ---------------------------------------------------------------- renderer & scene
let renderer;
try {
  renderer = new THREE.WebGLRenderer({
    canvas: $('view'),
    antialias: true,
    preserveDrawingBuffer: true,
  });
} catch (e) {
  renderer = null;
  showMessage(`WebGL is not available in this browser, so the 3D view cannot be shown.\n(${e.message})`);
}

const scene = new THREE.Scene();
scene.background = new THREE.Color(COLOURS.background);

const camera = new THREE.PerspectiveCamera(35, 1, 0.1, 10000);
camera.up.set(0, -1, 0); // OpenCV-like axes: y points down
scene.add(camera);

// Light: a sky/ground fill (sky is -y, i.e. "up") plus a headlight that
// follows the camera so the meshes stay lit from every orbit angle.
const hemi = new THREE.HemisphereLight(0xffffff, 0x30343c, 1.4);
hemi.position.set(0, -1, 0);
scene.add(hemi);
const headlight = new THREE.DirectionalLight(0xffffff, 2.2);
headlight.position.set(0.6, 1.0, 0.2); // camera space: upper right
headlight.target.position.set(0, 0, -1);
camera.add(headlight);
camera.add(headlight.target);

const maxillaRoot = new THREE.Group();
maxillaRoot.name = 'maxilla';
scene.add(maxillaRoot);

const mandibleRoot = new THREE.Group();
mandibleRoot.name = 'mandible';
mandibleRoot.matrixAutoUpdate = false;
scene.add(mandibleRoot);

let restMatrix = null; // row-major 16 or null (identity)
let controls = null;
let homeView = null;
let dirty = true;
let sceneReady = false;

function applyMatrix(m) {
  if (isMatrix16(m)) mandibleRoot.matrix.set(...m);
  else mandibleRoot.matrix.identity();
  mandibleRoot.matrixWorldNeedsUpdate = true;
  dirty = true;
}

function applyPose(m) {
  if (!isMatrix16(m)) return false;
  applyMatrix(m);
  hook.posesApplied += 1;
  return true;
}

// ---------------------------------------------------------------- incisor trace
class Trace {
  constructor(capacity) {
    this.capacity = Math.max(1, capacity);
    this.count = 0;
    this.positions = new Float32Array(this.capacity * 3);
    this.attr = new THREE.BufferAttribute(this.positions, 3);
    this.attr.setUsage(THREE.DynamicDrawUsage);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', this.attr);
    geometry.setDrawRange(0, 0);
    this.line = new THREE.Line(
      geometry,
      new THREE.LineBasicMaterial({ color: COLOURS.trace, depthTest: false, transparent: true }),
    );
    this.line.frustumCulled = false; // the bounding sphere is never recomputed
    this.line.renderOrder = 10;
  }

  push(p) {
    if (this.count === this.capacity) {
      this.positions.copyWithin(0, 3);
      this.count -= 1;
    }
    this.positions.set(p, this.count * 3);
    this.count += 1;
    this.attr.needsUpdate = true;
    this.line.geometry.setDrawRange(0, this.count);
  }

  setVisibleCount(n) {
    this.line.geometry.setDrawRange(0, Math.min(n, this.count));
  }

  clear() {
    this.count = 0;
    this.line.geometry.setDrawRange(0, 0);
  }
}

let trace = new Trace(LIVE_TRACE_POINTS);
scene.add(trace.line);

// Picking the anatomical points on the scans (null without scans).
let picker = null;

// The condyles' paths (replay), left and right.
let condyleTraces = [];
// The head frame (maxilla from head), from the scene; null until it is known.
let head = null;

const tip = new THREE.Mesh(
  new THREE.SphereGeometry(1, 16, 12),
  new THREE.MeshBasicMaterial({ color: COLOURS.tip, depthTest: false, transparent: true }),
);
tip.renderOrder = 11;
tip.visible = false;
scene.add(tip);

function setTip(p) {
  if (isVec3(p)) {
    tip.position.set(p[0], p[1], p[2]);
    tip.visible = true;
  } else {
    tip.visible = false;
  }
  dirty = true;
}

// ---------------------------------------------------------------- readouts
let pendingReadout = null; // flushed once per animation frame
let autoFitWanted = false;

function setPoseState(state, text) {
  const el = $('pose-state');
  el.className = `pose-state ${state}`;
  el.textContent = text;
}

function flushReadout() {
  const r = pendingReadout;
  if (!r) return;
  pendingReadout = null;
  $('opening').textContent = fmtMm(r.opening_mm);
  $('lateral').textContent = fmtMm(r.lateral_mm);
  $('protrusive').textContent = fmtMm(r.protrusive_mm);
  if (r.hasPose) setPoseState('tracking', r.poseText);
  else setPoseState('nopose', r.poseText);
  if (r.tags !== undefined) {
    const tags = r.tags && typeof r.tags === 'object' ? r.tags : {};
    $('tags-maxilla').textContent = isFiniteNumber(tags.maxilla) ? String(tags.maxilla) : '—';
    $('tags-mandible').textContent = isFiniteNumber(tags.mandible) ? String(tags.mandible) : '—';
  }
}

// ---------------------------------------------------------------- meshes
function meshMaterial(colour, flat) {
  return new THREE.MeshStandardMaterial({
    color: colour,
    roughness: 0.55,
    metalness: 0.05,
    side: THREE.DoubleSide,
    flatShading: flat,
  });
}

// Keep only positions, weld duplicated vertices (STL/OBJ are triangle soups)
// so that computed vertex normals shade smoothly.
function prepareGeometry(source, keepColours = false) {
  let g = new THREE.BufferGeometry();
  g.setAttribute('position', source.getAttribute('position'));
  // A contact map's colours are per vertex: kept, and the mesh drawn in them.
  if (keepColours && source.getAttribute('color')) g.setAttribute('color', source.getAttribute('color'));
  if (source.index) g.setIndex(source.index);
  else g = mergeVertices(g);
  g.computeVertexNormals();
  g.computeBoundingSphere();
  return g;
}

async function loadObject(spec, name, colour) {
  if (!spec || typeof spec !== 'object') throw new Error(`the scene has no ${name} mesh`);
  switch (String(spec.format).toLowerCase()) {
    case 'mesh': {
      const { positions, indices } = spec;
      if (!Array.isArray(positions) || positions.length < 9 || positions.length % 3 !== 0) {
        throw new Error(`${name}: inline mesh needs "positions" as a flat array of x,y,z`);
      }
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
      if (Array.isArray(indices) && indices.length > 0) g.setIndex(indices);
      return new THREE.Mesh(prepareGeometry(g), meshMaterial(colour, true));
    }
    case 'stl': {
      const g = await new STLLoader().loadAsync(spec.url);
      return new THREE.Mesh(prepareGeometry(g), meshMaterial(colour, false));
    }
    case 'ply': {
      const g = await new PLYLoader().loadAsync(spec.url);
      if (!g.index) {
        // A PLY without faces is a point cloud.
        const size = 0.004 * (g.computeBoundingSphere(), g.boundingSphere.radius || 100);
        const pg = new THREE.BufferGeometry();
        pg.setAttribute('position', g.getAttribute('position'));
        return new THREE.Points(pg, new THREE.PointsMaterial({ color: colour, size }));
      }
      if (spec.coloured && g.getAttribute('color')) {
        const m = meshMaterial(0xffffff, false);
        m.vertexColors = true;
        return new THREE.Mesh(prepareGeometry(g, true), m);
      }
      return new THREE.Mesh(prepareGeometry(g), meshMaterial(colour, false));
    }
    case 'obj': {
      const group = await new OBJLoader().loadAsync(spec.url);
      group.traverse((o) => {
        if (o.isMesh) {
          o.geometry = prepareGeometry(o.geometry);
          o.material = meshMaterial(colour, false);
        } else if (o.isLine || o.isPoints) {
          o.material = o.isLine
            ? new THREE.LineBasicMaterial({ color: colour })
            : new THREE.PointsMaterial({ color: colour, size: 0.5 });
        }
      });
      return group;
    }
    default:
      throw new Error(`${name}: unknown mesh format ${JSON.stringify(spec.format)}`);
  }
}

async function loadInto(root, spec, name, colour) {
  try {
    const obj = await loadObject(spec, name, colour);
    obj.name = `${name}-mesh`;
    // A scan with a registration is drawn in its marker's frame (row-major 4x4).
    if (spec && isMatrix16(spec.marker_from_mesh)) {
      obj.matrixAutoUpdate = false;
      obj.matrix.set(...spec.marker_from_mesh);
    }
    root.add(obj);
    return null;
  } catch (e) {
    const where = spec && spec.url ? ` from ${spec.url}` : '';
    return `Could not load the ${name} mesh${where}: ${e.message}`;
  }
}

// ---------------------------------------------------------------- camera framing
let mandibleLocalBox = new THREE.Box3(); // mandible mesh bounds in the mandible frame

function boxCorners(b) {
  const out = [];
  for (let i = 0; i < 8; i++) {
    out.push(new THREE.Vector3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z));
  }
  return out;
}

// Bounding box of the maxilla, the mandible at its current pose (and, in
// replay, at every recorded pose) and the visible incisor trace.
function contentBox() {
  scene.updateMatrixWorld(true);
  const box = new THREE.Box3().expandByObject(maxillaRoot);
  if (!mandibleLocalBox.isEmpty()) {
    const corners = boxCorners(mandibleLocalBox);
    const m = new THREE.Matrix4();
    const addAt = (matrix) => {
      for (const c of corners) box.expandByPoint(c.clone().applyMatrix4(matrix));
    };
    addAt(mandibleRoot.matrix);
    if (replay && replay.n > 0) {
      const stride = Math.max(1, Math.ceil(replay.n / 2000));
      for (let i = 0; i < replay.n; i += stride) {
        const f = replay.frames[i];
        if (f && isMatrix16(f.maxilla_from_mandible)) addAt(m.set(...f.maxilla_from_mandible));
      }
    }
  }
  const n = replay ? trace.count : trace.line.geometry.drawRange.count;
  const p = new THREE.Vector3();
  for (let i = 0; i < Math.min(n, trace.count); i++) box.expandByPoint(p.fromArray(trace.positions, 3 * i));
  return box;
}

// Screen area hidden by the overlays, so the content is centred in (and
// fitted to) the part of the canvas that is actually visible.
function viewInsets() {
  const canvas = renderer.domElement;
  const w = Math.max(canvas.clientWidth, 1);
  const h = Math.max(canvas.clientHeight, 1);
  const panel = $('panel').getBoundingClientRect();
  const left = w > 2.2 * panel.right ? panel.right : 0;
  const top = $('bar').getBoundingClientRect().bottom;
  const timeline = $('timeline');
  const bottom = timeline.hidden ? 0 : Math.max(0, h - timeline.getBoundingClientRect().top);
  return { w, h, left, top, bottom: Math.min(bottom, h - top - 1) };
}

// Live mode keeps the content in view by itself (growing the view as the
// incisor path grows) until the user moves the camera; "Fit view" resumes it.
let fittedBox = null;
let userMovedCamera = false;
let lastAutoFit = 0;
const probe = new THREE.Vector3();

function contentOutsideView() {
  if (!fittedBox || userMovedCamera) return false;
  if (trace.count > 0 && !fittedBox.containsPoint(probe.fromArray(trace.positions, 3 * (trace.count - 1)))) return true;
  if (mandibleLocalBox.isEmpty()) return false;
  for (const c of boxCorners(mandibleLocalBox)) {
    if (!fittedBox.containsPoint(c.applyMatrix4(mandibleRoot.matrix))) return true;
  }
  return false;
}

// The oblique view the page opens with: from the tracking camera's side (-z), a little to the
// right and above (-y), so that both the opening (y) and the hinge arc (z) are visible.
const OBLIQUE = { toCamera: new THREE.Vector3(1.0, -0.45, -1.0).normalize(), up: new THREE.Vector3(0, -1, 0) };
let currentView = OBLIQUE;

// margin: fraction of the content's size added on every side.
function fitView(margin = 0.02) {
  const box = contentBox();
  if (box.isEmpty()) box.setFromCenterAndSize(new THREE.Vector3(0, 20, 0), new THREE.Vector3(100, 100, 100));
  box.expandByScalar(margin * box.getSize(new THREE.Vector3()).length());
  fittedBox = box.clone();
  const center = box.getCenter(new THREE.Vector3());
  const size = box.getSize(new THREE.Vector3()).length();

  const { w, h, left, top, bottom } = viewInsets();
  const tanHalf = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2);
  const tanV = tanHalf * ((h - top - bottom) / h);
  const tanH = tanHalf * camera.aspect * ((w - left) / w);
  camera.up.copy(currentView.up);
  const dir = currentView.toCamera.clone(); // centre -> camera
  const forward = dir.clone().negate();
  const right = new THREE.Vector3().crossVectors(forward, camera.up).normalize();
  const up = new THREE.Vector3().crossVectors(right, forward);
  // Smallest distance at which every corner of the box is inside the frustum.
  let dist = 0;
  for (const c of boxCorners(box)) {
    const r = c.sub(center);
    const depth = r.dot(dir); // towards the camera
    dist = Math.max(dist, depth + Math.abs(r.dot(right)) / tanH, depth + Math.abs(r.dot(up)) / tanV);
  }
  dist = Math.max(dist, 1);
  homeView = {
    position: center.clone().addScaledVector(dir, dist),
    target: center,
  };
  camera.near = Math.max(dist / 100, 0.01);
  camera.far = dist + size * 50;
  camera.updateProjectionMatrix();
  tip.scale.setScalar(Math.max(size * 0.01, 0.2));
  resetView();
}

function resetView() {
  if (!homeView) return;
  camera.position.copy(homeView.position);
  if (controls) {
    controls.target.copy(homeView.target);
    controls.update();
  } else {
    camera.lookAt(homeView.target);
  }
  dirty = true;
}

function resize() {
  if (!renderer) return;
  const canvas = renderer.domElement;
  const w = Math.max(canvas.clientWidth, 1);
  const h = Math.max(canvas.clientHeight, 1);
  const pr = Math.min(window.devicePixelRatio || 1, 2);
  if (renderer.getPixelRatio() !== pr) renderer.setPixelRatio(pr);
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  const ins = viewInsets();
  camera.setViewOffset(w, h, -ins.left / 2, (ins.bottom - ins.top) / 2, w, h);
  camera.updateProjectionMatrix();
  dirty = true;
}

// ---------------------------------------------------------------- live mode
let ws = null;
let wsOpen = false;

function setLinkBadge(state, text) {
  const el = $('link-badge');
  el.hidden = false;
  el.className = `badge ${state}`;
  el.textContent = text;
}

function connectLive() {
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const socket = new WebSocket(`${proto}//${location.host}/ws`);
  ws = socket;
  setLinkBadge('connecting', 'connecting');
  $('calibrate').disabled = true;

  socket.addEventListener('open', () => {
    wsOpen = true;
    $('calibrate').disabled = false;
    setLinkBadge('waiting', 'connected');
  });
  socket.addEventListener('message', (ev) => {
    if (typeof ev.data !== 'string') return;
    let msg;
    try {
      msg = JSON.parse(ev.data);
    } catch {
      return; // not ours to judge; ignore malformed frames
    }
    handleLiveMessage(msg);
  });
  socket.addEventListener('close', () => {
    wsOpen = false;
    ws = null;
    $('calibrate').disabled = true;
    setLinkBadge('disconnected', 'disconnected');
    pendingReadout = null;
    setPoseState('nopose', 'disconnected — showing the last pose');
    $('rate').hidden = true;
    $('loss').hidden = true;
    setTimeout(connectLive, RECONNECT_MS);
  });
  // 'error' is always followed by 'close', which handles the retry.
}

function handleLiveMessage(msg) {
  if (!msg || typeof msg !== 'object') return;
  switch (msg.type) {
    case 'pose': {
      const ok = applyPose(msg.maxilla_from_mandible);
      if (isVec3(msg.incisor)) {
        trace.push(msg.incisor);
        setTip(msg.incisor);
      }
      if (contentOutsideView()) autoFitWanted = true;
      pendingReadout = {
        opening_mm: msg.opening_mm,
        lateral_mm: msg.lateral_mm,
        protrusive_mm: msg.protrusive_mm,
        hasPose: ok,
        poseText: `${ok ? 'tracking' : 'no pose'}${isFiniteNumber(msg.seq) ? ` · seq ${msg.seq}` : ''}`,
        tags: msg.tags ?? null,
      };
      dirty = true;
      break;
    }
    case 'status':
      hook.lastStatus = msg;
      showStatus(msg);
      break;
    case 'calibrated':
      showToast(
        String(msg.message ?? (msg.ok ? 'Calibrated.' : 'Calibration failed.')),
        msg.ok ? 'ok' : 'bad',
      );
      break;
    default:
      break;
  }
}

function showStatus(s) {
  const link = s.link;
  if (link === 'up') setLinkBadge('up', 'link up');
  else if (link === 'waiting') setLinkBadge('waiting', 'waiting for sender');
  else if (link === 'stale') setLinkBadge('stale', 'stale');
  else setLinkBadge('connecting', String(link ?? 'unknown'));

  const rate = $('rate');
  rate.hidden = false;
  rate.textContent = isFiniteNumber(s.rate_hz) ? `${s.rate_hz.toFixed(1)} Hz` : '— Hz';
  const loss = $('loss');
  loss.hidden = false;
  loss.textContent = isFiniteNumber(s.loss_percent) ? `${s.loss_percent.toFixed(2)} % lost` : '— % lost';

  const n = (k) => (isFiniteNumber(s[k]) ? String(s[k]) : '—');
  $('counters').textContent =
    `received ${n('received')} · accepted ${n('accepted')}\n` +
    `lost ${n('lost')} · reordered ${n('reordered')} · duplicated ${n('duplicated')} · rejected ${n('rejected')}`;
  $('counters').style.whiteSpace = 'pre-line';
}

function setupLive() {
  $('tags-section').hidden = false;
  $('link-section').hidden = false;
  $('calibrate').hidden = false;
  $('clear-trace').hidden = false;
  $('calibrate').addEventListener('click', () => {
    if (ws && wsOpen) {
      ws.send(JSON.stringify({ type: 'calibrate_intercuspation' }));
      showToast('Calibration requested — hold the teeth in maximal intercuspation…');
    } else {
      showToast('Not connected to the server.', 'bad');
    }
  });
  $('clear-trace').addEventListener('click', () => {
    trace.clear();
    dirty = true;
  });
  connectLive();
}

// ---------------------------------------------------------------- replay mode
let replay = null;

// Frame `i` of `n` numbered as the CLI and the recording number frames, from 0: by its own
// `frame` when the server sends it (a received recording need not start at 0), else by place.
function frameLabel(f, i, n) {
  return `frame ${isFiniteNumber(f.frame) ? f.frame : i} (${i + 1} of ${n})`;
}

class Replay {
  constructor(frames) {
    this.frames = frames;
    const n = frames.length;
    this.n = n;
    this.times = new Float64Array(n);
    this.lastPose = new Int32Array(n);
    this.lastIncisor = new Int32Array(n);
    this.traceCount = new Int32Array(n);

    let incisors = 0;
    for (const f of frames) if (f && isVec3(f.incisor)) incisors += 1;
    scene.remove(trace.line);
    trace = new Trace(incisors);
    scene.add(trace.line);
    for (const t of condyleTraces) scene.remove(t.line);
    condyleTraces = [COLOURS.condyleLeft, COLOURS.condyleRight].map((colour) => {
      const t = new Trace(incisors);
      t.line.material.color.setHex(colour);
      scene.add(t.line);
      return t;
    });
    this.condyleCount = new Int32Array(n);

    const t0 = frames.map((f) => f && f.t).find(isFiniteNumber) ?? 0;
    let lp = -1;
    let li = -1;
    let prevT = 0;
    for (let i = 0; i < n; i++) {
      const f = frames[i] || {};
      const t = isFiniteNumber(f.t) ? f.t - t0 : prevT + 1 / 60;
      this.times[i] = t;
      prevT = t;
      if (isMatrix16(f.maxilla_from_mandible)) lp = i;
      if (isVec3(f.incisor)) {
        trace.push(f.incisor);
        li = i;
      }
      if (Array.isArray(f.condyles) && f.condyles.length === 2 && f.condyles.every(isVec3)) {
        condyleTraces.forEach((t, k) => t.push(f.condyles[k]));
      }
      this.condyleCount[i] = condyleTraces[0].count;
      this.lastPose[i] = lp;
      this.lastIncisor[i] = li;
      this.traceCount[i] = trace.count;
    }
    this.duration = n > 0 ? this.times[n - 1] : 0;
    this.current = 0;
    this.playing = false;
    this.playT = 0;
    this.lastTick = null;
    this.speed = 1;
  }

  seek(index, { fromPlayback = false } = {}) {
    if (this.n === 0) return;
    const i = Math.min(this.n - 1, Math.max(0, Math.round(Number(index) || 0)));
    this.current = i;
    if (!fromPlayback) this.playT = this.times[i];
    const f = this.frames[i] || {};
    const p = this.lastPose[i];
    if (p >= 0) applyPose(this.frames[p].maxilla_from_mandible);
    else applyMatrix(restMatrix);
    trace.setVisibleCount(this.traceCount[i]);
    for (const t of condyleTraces) t.setVisibleCount(this.condyleCount[i]);
    const li = this.lastIncisor[i];
    setTip(li >= 0 ? this.frames[li].incisor : null);
    const hasPose = isMatrix16(f.maxilla_from_mandible);
    pendingReadout = {
      opening_mm: f.opening_mm,
      lateral_mm: f.lateral_mm,
      protrusive_mm: f.protrusive_mm,
      hasPose,
      poseText: hasPose ? 'pose' : 'no pose',
    };
    $('scrub').value = String(i);
    const seq = isFiniteNumber(f.seq) ? ` · seq ${f.seq}` : '';
    $('time').textContent =
      `${this.times[i].toFixed(3)} s / ${this.duration.toFixed(3)} s · ${frameLabel(f, i, this.n)}${seq}`;
    dirty = true;
  }

  setPlaying(on) {
    if (on && this.current >= this.n - 1) this.seek(0);
    this.playing = on && this.n > 1;
    this.lastTick = null;
    const btn = $('play');
    btn.textContent = this.playing ? '❚❚ Pause' : '▶ Play';
    btn.setAttribute('aria-label', this.playing ? 'Pause' : 'Play');
  }

  tick(now) {
    if (!this.playing) return;
    if (this.lastTick === null) {
      this.lastTick = now;
      return;
    }
    const dt = Math.min((now - this.lastTick) / 1000, 0.25);
    this.lastTick = now;
    this.playT += dt * this.speed;
    let i = this.current;
    while (i + 1 < this.n && this.times[i + 1] <= this.playT) i += 1;
    if (i !== this.current) this.seek(i, { fromPlayback: true });
    if (this.current >= this.n - 1) this.setPlaying(false);
  }
}

async function setupReplay() {
  const rec = await fetchJson('/api/recording');
  const frames = rec && Array.isArray(rec.frames) ? rec.frames : null;
  if (!frames) throw new Error('/api/recording has no "frames" array.');
  replay = new Replay(frames);
  hook.frameCount = frames.length;

  if (rec.header != null) {
    $('header-details').hidden = false;
    $('header-json').textContent = JSON.stringify(rec.header, null, 2);
  }
  const scrub = $('scrub');
  scrub.max = String(Math.max(frames.length - 1, 0));
  $('timeline').hidden = false;
  if (frames.length === 0) {
    scrub.disabled = true;
    $('play').disabled = true;
    $('time').textContent = 'empty recording';
    setPoseState('nopose', 'the recording has no frames');
    return;
  }
  scrub.addEventListener('input', () => replay.seek(Number(scrub.value)));
  $('play').addEventListener('click', () => replay.setPlaying(!replay.playing));
  $('speed').addEventListener('change', (e) => {
    replay.speed = Number(e.target.value) || 1;
  });
  window.addEventListener('keydown', (e) => {
    const tag = e.target && e.target.tagName;
    if (tag === 'BUTTON' || tag === 'INPUT' || tag === 'SELECT') return;
    if (e.code === 'Space') {
      replay.setPlaying(!replay.playing);
      e.preventDefault();
    } else if (e.code === 'ArrowRight') {
      replay.seek(replay.current + 1);
    } else if (e.code === 'ArrowLeft') {
      replay.seek(replay.current - 1);
    }
  });
  replay.seek(0);
}

// ---------------------------------------------------------------- main loop
function animate(now) {
  requestAnimationFrame(animate);
  if (replay) replay.tick(now);
  if (autoFitWanted && now - lastAutoFit > 500) {
    autoFitWanted = false;
    lastAutoFit = now;
    fitView(0.06);
  }
  if (controls && controls.update()) dirty = true;
  flushReadout();
  if (!dirty || !sceneReady) return;
  dirty = false;
  renderer.render(scene, camera);
  if (!hook.ready) {
    hook.ready = true;
    $('loading').hidden = true;
  }
}

// Orbit controls about the current view's up: made again when a view button changes it, since
// the controls take the camera's up when made.
function makeControls() {
  if (controls) controls.dispose();
  camera.up.copy(currentView.up);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = true;
  controls.dampingFactor = 0.12;
  controls.addEventListener('change', () => {
    dirty = true;
  });
  controls.addEventListener('start', () => {
    userMovedCamera = true; // stop auto-framing once the user takes the camera
  });
}

// Picking the points of `jawtrack points` on the scans: a click (not a drag) picks.
function setupPicking(spec) {
  const isScan = (name) => spec[name] && spec[name].format !== 'mesh';
  if (!isScan('maxilla')) return;
  const scans = () => ['maxilla', 'mandible'].map((n) => scene.getObjectByName(`${n}-mesh`)).filter(Boolean);
  picker = new PointPicker({
    camera,
    targets: scans,
    upper: () => scene.getObjectByName('maxilla-mesh'),
    onChange: showPicking,
  });
  $('pick-section').hidden = false;
  $('pick').addEventListener('click', () => (picker.active ? picker.stop() : picker.start()));
  const canvas = renderer.domElement;
  let down = null;
  canvas.addEventListener('pointerdown', (e) => {
    down = [e.clientX, e.clientY];
  });
  canvas.addEventListener('pointerup', (e) => {
    if (!picker.active || !down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
    const r = canvas.getBoundingClientRect();
    const x = ((e.clientX - r.left) / r.width) * 2 - 1;
    const y = -((e.clientY - r.top) / r.height) * 2 + 1;
    if (!picker.pickAt(x, y)) showToast('Nothing there: click on a scan.', 'warn');
  });
  showPicking(picker);
}

function showPicking(p) {
  $('pick').textContent = p.active ? 'Stop picking' : 'Pick points on the scans';
  const next = p.next();
  $('pick-step').textContent = p.active && next ? `Click ${next}.` : '';
  $('pick-list').replaceChildren(
    ...p.points.map((q) => {
      const li = document.createElement('li');
      li.textContent = q.toArray().map((c) => c.toFixed(2)).join(', ');
      return li;
    }),
  );
  const command = p.command();
  $('pick-command').hidden = !command;
  $('pick-command').textContent = command || '';
}

// The markers with their tags on both jaws, the grid in the occlusal plane, the hinge axis.
function addAnatomy(spec) {
  const tags = spec.tags || {};
  for (const [root, name] of [
    [maxillaRoot, 'maxilla'],
    [mandibleRoot, 'mandible'],
  ]) {
    // With a scan, the marker is drawn see-through beside it; without, the mesh is the marker.
    const scan = spec[name] && spec[name].format !== 'mesh';
    const solid = scan ? spec.marker_solid : null;
    root.add(markerGroup(solid, tags[name], COLOURS[name], { seeThrough: scan }));
  }
  scene.add(grid(head || new THREE.Matrix4()));
  const axis = hingeAxis(spec.hinge_axis);
  if (axis) scene.add(axis);
  $('legend-axis').hidden = !axis;
}

async function main() {
  if (!renderer) return;
  let sceneSpec;
  try {
    sceneSpec = await fetchJson('/api/scene');
  } catch (e) {
    showMessage(`Could not load the scene.\n${e.message}`);
    console.error(e);
    return;
  }
  const mode = sceneSpec && sceneSpec.mode;
  if (mode !== 'live' && mode !== 'replay') {
    showMessage(`The server sent an unknown viewer mode: ${JSON.stringify(mode)}.`);
    console.error('unknown mode', mode);
    return;
  }
  hook.mode = mode;
  const badge = $('mode-badge');
  badge.textContent = mode;
  badge.className = `badge ${mode}`;

  restMatrix = isMatrix16(sceneSpec.maxilla_from_mandible_rest) ? sceneSpec.maxilla_from_mandible_rest : null;

  const problems = (
    await Promise.all([
      loadInto(maxillaRoot, sceneSpec.maxilla, 'maxilla', COLOURS.maxilla),
      loadInto(mandibleRoot, sceneSpec.mandible, 'mandible', COLOURS.mandible),
    ])
  ).filter(Boolean);
  if (problems.length > 0) {
    showMessage(problems.join('\n'), { banner: true });
    for (const p of problems) console.error(p);
  }
  applyMatrix(null);
  scene.updateMatrixWorld(true);
  mandibleLocalBox = new THREE.Box3().expandByObject(mandibleRoot);
  applyMatrix(restMatrix);

  head = headMatrix(sceneSpec.maxilla_from_head);
  addAnatomy(sceneSpec);
  setupPicking(sceneSpec);
  makeControls();
  $('fit-view').addEventListener('click', () => {
    userMovedCamera = false;
    currentView = OBLIQUE;
    makeControls();
    fitView();
  });
  const dirs = viewDirections(head);
  for (const name of ['front', 'side', 'occlusal']) {
    $(`view-${name}`).addEventListener('click', () => {
      userMovedCamera = true; // a chosen view stays until the user asks to fit again
      currentView = dirs[name];
      makeControls();
      fitView();
    });
  }

  if (mode === 'replay') {
    try {
      await setupReplay();
    } catch (e) {
      showMessage(`Could not load the recording.\n${e.message}`);
      console.error(e);
      return;
    }
  } else {
    setupLive();
  }

  resize();
  // Live: the trace is still empty, so leave some room for the jaw to open.
  fitView(mode === 'live' ? 0.1 : 0.02);
  new ResizeObserver(resize).observe(renderer.domElement);

  sceneReady = true;
  dirty = true;
  requestAnimationFrame(animate);
}

main();
