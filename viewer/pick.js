// Picking the anatomical points on the scans, for `jawtrack points`: the incisal point and the
// left and right first molars' mesiobuccal cusp tips on the upper scan, then the lower incisal
// point with the jaw closed. Each is read in the upper scan's frame (the frame the points file
// holds), whichever scan was clicked, and the panel shows the command that writes the file.

import * as THREE from 'three';

export const STEPS = [
  'the incisal point, between the upper central incisors',
  "the left first molar's mesiobuccal cusp tip",
  "the right first molar's mesiobuccal cusp tip",
  'the lower incisal point, with the jaw closed',
];

const fmt = (v) => v.toArray().map((c) => Number(c.toFixed(3))).join(',');

export class PointPicker {
  // camera: the view's camera; targets(): the scans that can be clicked; upper(): the upper
  // scan's object (its local frame is the upper scan's); onChange(picker): redraw the panel.
  constructor({ camera, targets, upper, onChange }) {
    this.camera = camera;
    this.targets = targets;
    this.upper = upper;
    this.onChange = onChange;
    this.raycaster = new THREE.Raycaster();
    this.active = false;
    this.points = [];
  }

  start() {
    this.active = true;
    this.points = [];
    this.onChange(this);
  }

  stop() {
    this.active = false;
    this.onChange(this);
  }

  // What to click next, or null when all are picked.
  next() {
    return this.points.length < STEPS.length ? STEPS[this.points.length] : null;
  }

  // Picks at normalised device coordinates (x, y in −1..1, y up): the nearest scan surface
  // under them. Returns {world, scan} (arrays) or null when nothing is hit.
  pickAt(x, y) {
    const upper = this.upper();
    if (!this.active || !upper || this.next() === null) return null;
    this.raycaster.setFromCamera(new THREE.Vector2(x, y), this.camera);
    const hit = this.raycaster.intersectObjects(this.targets(), true)[0];
    if (!hit || !Number.isFinite(hit.point.x + hit.point.y + hit.point.z)) return null;
    upper.updateMatrixWorld(true);
    const scan = upper.worldToLocal(hit.point.clone());
    this.points.push(scan);
    if (this.next() === null) this.active = false;
    this.onChange(this);
    return { world: hit.point.toArray(), scan: scan.toArray() };
  }

  // The `jawtrack points` command of the points picked, once all are.
  command() {
    if (this.points.length < STEPS.length) return null;
    const [incisal, left, right, lower] = this.points;
    return (
      `jawtrack points --occlusal ${fmt(incisal)},${fmt(left)},${fmt(right)} ` +
      `--lower-incisal ${fmt(lower)} --out points.json`
    );
  }
}
