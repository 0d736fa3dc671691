// What the viewer draws besides the meshes and the incisor path: the markers with their tags,
// the grid in the occlusal plane, the hinge axis, and the camera directions of the view
// buttons. All in mm; the scene frame is the maxilla marker's. The head frame (X the patient's
// left, Y down, Z posterior; its XZ plane the occlusal plane) comes from the server as
// `maxilla_from_head`, row-major.

import * as THREE from 'three';

export const GRID_MM = 100;
export const GRID_CELL_MM = 10;

const isFiniteNumber = (v) => typeof v === 'number' && Number.isFinite(v);
const isVec3 = (p) => Array.isArray(p) && p.length === 3 && p.every(isFiniteNumber);

// The head frame as a Matrix4 (maxilla from head), or null.
export function headMatrix(rowMajor) {
  if (!Array.isArray(rowMajor) || rowMajor.length !== 16 || !rowMajor.every(isFiniteNumber)) return null;
  return new THREE.Matrix4().set(...rowMajor);
}

// A text label that always faces the camera, `height` mm tall.
function label(text, height, colour = '#ffffff') {
  const canvas = document.createElement('canvas');
  const px = 64;
  const ctx = canvas.getContext('2d');
  ctx.font = `bold ${px}px sans-serif`;
  canvas.width = Math.ceil(ctx.measureText(text).width) + 16;
  canvas.height = px + 16;
  ctx.font = `bold ${px}px sans-serif`;
  ctx.fillStyle = colour;
  ctx.strokeStyle = 'rgba(0,0,0,0.8)';
  ctx.lineWidth = 8;
  ctx.textBaseline = 'middle';
  ctx.strokeText(text, 8, canvas.height / 2);
  ctx.fillText(text, 8, canvas.height / 2);
  const texture = new THREE.CanvasTexture(canvas);
  texture.colorSpace = THREE.SRGBColorSpace;
  // Hidden behind the solid like the faces they name; the grid's and the axis's labels too.
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: texture, transparent: true }));
  sprite.scale.set((height * canvas.width) / canvas.height, height, 1);
  sprite.renderOrder = 12;
  return sprite;
}

// A marker: its solid (see-through when a scan is shown), each tag's square and id.
export function markerGroup(solid, tags, colour, { seeThrough }) {
  const group = new THREE.Group();
  group.name = 'marker';
  if (solid && Array.isArray(solid.positions)) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(solid.positions, 3));
    if (Array.isArray(solid.indices)) g.setIndex(solid.indices);
    g.computeVertexNormals();
    const m = new THREE.MeshStandardMaterial({
      color: colour,
      flatShading: true,
      transparent: seeThrough,
      opacity: seeThrough ? 0.35 : 1,
      side: THREE.DoubleSide,
    });
    group.add(new THREE.Mesh(g, m));
  }
  let labelled = 0;
  for (const t of Array.isArray(tags) ? tags : []) {
    if (!Array.isArray(t.corners) || t.corners.length !== 4 || !t.corners.every(isVec3)) continue;
    const lift = isVec3(t.normal) ? new THREE.Vector3(...t.normal).multiplyScalar(0.05) : new THREE.Vector3();
    const pts = t.corners.map((c) => new THREE.Vector3(...c).add(lift));
    const square = new THREE.LineLoop(
      new THREE.BufferGeometry().setFromPoints(pts),
      new THREE.LineBasicMaterial({ color: 0x111111 }),
    );
    group.add(square);
    if (isVec3(t.centre)) {
      const side = pts[0].distanceTo(pts[1]);
      const l = label(String(t.id), Math.max(side * 0.45, 1.5));
      const out = isVec3(t.normal) ? new THREE.Vector3(...t.normal).multiplyScalar(1.5) : new THREE.Vector3();
      l.position.copy(new THREE.Vector3(...t.centre).add(out));
      l.name = `tag-${t.id}`;
      group.add(l);
      labelled += 1;
    }
  }
  group.userData.tags = labelled;
  return group;
}

// The grid: GRID_MM across, GRID_CELL_MM cells, in the head frame's occlusal (XZ) plane
// through its origin, with a "10 mm" note at one corner.
export function grid(maxillaFromHead) {
  const group = new THREE.Group();
  group.name = 'grid';
  const helper = new THREE.GridHelper(GRID_MM, GRID_MM / GRID_CELL_MM, 0x6b7a8f, 0x3a4350);
  helper.material.transparent = true;
  helper.material.opacity = 0.6;
  group.add(helper); // GridHelper lies in its XZ plane, as the occlusal plane does in the head frame
  const note = label(`grid ${GRID_CELL_MM} mm`, 3, '#b8c4d6');
  note.position.set(GRID_MM / 2, 0, GRID_MM / 2);
  group.add(note);
  group.matrixAutoUpdate = false;
  group.matrix.copy(maxillaFromHead);
  return group;
}

// The hinge axis: a line 140 mm long through its point, labelled.
export function hingeAxis(spec) {
  if (!spec || !isVec3(spec.point) || !isVec3(spec.direction)) return null;
  const p = new THREE.Vector3(...spec.point);
  const d = new THREE.Vector3(...spec.direction).normalize();
  const group = new THREE.Group();
  group.name = 'hinge-axis';
  const line = new THREE.Line(
    new THREE.BufferGeometry().setFromPoints([p.clone().addScaledVector(d, -70), p.clone().addScaledVector(d, 70)]),
    new THREE.LineBasicMaterial({ color: 0xffd23f, depthTest: false, transparent: true }),
  );
  line.renderOrder = 10;
  group.add(line);
  const l = label('hinge axis', 3, '#ffd23f');
  l.position.copy(p.clone().addScaledVector(d, 72));
  group.add(l);
  return group;
}

// The view buttons' camera directions in the scene frame: from the centre toward the camera,
// and the camera's up. Front: facing the patient (camera anterior); side: from the patient's
// right; occlusal: from below, looking up at the upper arch, anterior up on the screen.
export function viewDirections(maxillaFromHead) {
  const m = maxillaFromHead || new THREE.Matrix4();
  const axis = (x, y, z) => new THREE.Vector3(x, y, z).transformDirection(m);
  const up = axis(0, -1, 0); // head −Y: up
  return {
    front: { toCamera: axis(0, 0, -1), up },
    side: { toCamera: axis(-1, 0, 0), up },
    occlusal: { toCamera: axis(0, 1, 0), up: axis(0, 0, -1) },
  };
}
